//! Presentation: a `VkSurfaceKHR` and a `VkSwapchainKHR` over it. Generic: it
//! knows windows only through raw-window-handle and nothing of caustics.
//!
//! Swapchain images are owned by the swapchain; each is wrapped in an
//! `Image` (`Image::presentable`: its own view, tracked state) so that the
//! blit into it and its transition to presentation are declared like any
//! pass's accesses (`vk::step`). Recreation (resize) passes the old swapchain to the new one and
//! destroys the old one only after the caller has waited for the frames that
//! used it.

use super::sync::{barrier, ImageAccess};
use super::{Access, Commands, Context, Image, VkError, VkResult};
use ash::vk;
use std::sync::Arc;

/// Owns a surface. Dropped after every swapchain made from it.
pub struct Surface {
    ctx: Arc<Context>,
    pub loader: ash::khr::surface::Instance,
    pub raw: vk::SurfaceKHR,
}

impl Surface {
    /// Required instance extensions for windows of `display` (pass them to
    /// `Context::with_instance_extensions`).
    pub fn required_extensions(
        display: raw_window_handle::RawDisplayHandle,
    ) -> VkResult<&'static [*const std::ffi::c_char]> {
        Ok(ash_window::enumerate_required_extensions(display)?)
    }

    pub fn new(
        ctx: &Arc<Context>,
        display: raw_window_handle::RawDisplayHandle,
        window: raw_window_handle::RawWindowHandle,
    ) -> VkResult<Surface> {
        // SAFETY: the handles come from a live window, which the caller keeps
        // alive for as long as this surface (the app drops the surface first).
        let raw = unsafe {
            ash_window::create_surface(&ctx.entry, &ctx.instance, display, window, None)
        }?;
        let loader = ash::khr::surface::Instance::new(&ctx.entry, &ctx.instance);
        let supported = unsafe {
            loader.get_physical_device_surface_support(ctx.physical_device, ctx.queue_family, raw)
        }?;
        if !supported {
            unsafe { loader.destroy_surface(raw, None) };
            return Err(VkError::MissingFeatures {
                device: ctx.info.name.clone(),
                missing: "presentation to this window from the graphics queue".into(),
            });
        }
        Ok(Surface {
            ctx: ctx.clone(),
            loader,
            raw,
        })
    }

    /// The size the surface has now, when it fixes one (X11, Wayland do
    /// not always); `Some(0x0)` while the window is minimised, when no
    /// swapchain may be made.
    pub fn current_extent(&self) -> VkResult<Option<vk::Extent2D>> {
        let caps = unsafe {
            self.loader
                .get_physical_device_surface_capabilities(self.ctx.physical_device, self.raw)
        }?;
        Ok((caps.current_extent.width != u32::MAX).then_some(caps.current_extent))
    }

    pub fn present_modes(&self) -> VkResult<Vec<vk::PresentModeKHR>> {
        Ok(unsafe {
            self.loader
                .get_physical_device_surface_present_modes(self.ctx.physical_device, self.raw)
        }?)
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}

pub struct Swapchain {
    ctx: Arc<Context>,
    pub loader: ash::khr::swapchain::Device,
    pub raw: vk::SwapchainKHR,
    /// The swapchain's images, each with a colour view (for drawing on top
    /// of a blit: an overlay).
    pub images: Vec<Image>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub present_mode: vk::PresentModeKHR,
}

/// What `acquire` returned.
pub enum Acquired {
    /// Index of the image to render into; `suboptimal` asks for a recreation after presenting.
    Image { index: u32, suboptimal: bool },
    /// The surface changed (resize): recreate before rendering.
    OutOfDate,
}

impl Swapchain {
    /// A swapchain of `wanted` size (clamped to what the surface allows).
    /// Formats: B8G8R8A8_UNORM or R8G8B8A8_UNORM preferred, since callers
    /// copy already sRGB-encoded 8-bit values in; `present_mode` falls back to
    /// FIFO (always supported) when the surface lacks it.
    pub fn new(
        ctx: &Arc<Context>,
        surface: &Surface,
        wanted: vk::Extent2D,
        present_mode: vk::PresentModeKHR,
        old: Option<&Swapchain>,
    ) -> VkResult<Swapchain> {
        let pd = ctx.physical_device;
        let caps = unsafe {
            surface
                .loader
                .get_physical_device_surface_capabilities(pd, surface.raw)
        }?;
        let formats = unsafe {
            surface
                .loader
                .get_physical_device_surface_formats(pd, surface.raw)
        }?;
        let format = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM]
            .into_iter()
            .find_map(|f| formats.iter().find(|s| s.format == f).copied())
            .or_else(|| formats.first().copied())
            .ok_or(VkError::MissingFeatures {
                device: ctx.info.name.clone(),
                missing: "a surface format".into(),
            })?;
        let modes = surface.present_modes()?;
        let present_mode = if modes.contains(&present_mode) {
            present_mode
        } else {
            log::warn!("present mode {present_mode:?} not offered; using FIFO");
            vk::PresentModeKHR::FIFO
        };
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: wanted
                    .width
                    .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: wanted
                    .height
                    .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::COLOR_ATTACHMENT)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old.map(|o| o.raw).unwrap_or_default());
        let loader = ash::khr::swapchain::Device::new(&ctx.instance, &ctx.device);
        let raw = unsafe { loader.create_swapchain(&info, None) }?;
        let images = match unsafe { loader.get_swapchain_images(raw) } {
            Ok(i) => i,
            Err(e) => {
                unsafe { loader.destroy_swapchain(raw, None) };
                return Err(e.into());
            }
        };
        let mut swapchain = Swapchain {
            ctx: ctx.clone(),
            loader,
            raw,
            images: Vec::new(),
            format: format.format,
            extent,
            present_mode,
        };
        // From here `swapchain` owns what was made: an error drops it whole.
        for image in images {
            swapchain
                .images
                .push(Image::presentable(ctx, image, format.format, extent)?);
        }
        Ok(swapchain)
    }

    /// Acquires the next image; `signal` is signalled when it may be written.
    pub fn acquire(&self, signal: vk::Semaphore) -> VkResult<Acquired> {
        match unsafe {
            self.loader
                .acquire_next_image(self.raw, u64::MAX, signal, vk::Fence::null())
        } {
            Ok((index, suboptimal)) => Ok(Acquired::Image { index, suboptimal }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(e) => Err(e.into()),
        }
    }

    /// Queues image `index` for presentation after `wait`. Returns true when
    /// the swapchain should be recreated (out of date or suboptimal).
    pub fn present(&self, index: u32, wait: vk::Semaphore) -> VkResult<bool> {
        let waits = [wait];
        let swapchains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&swapchains)
            .image_indices(&indices);
        match unsafe { self.loader.queue_present(self.ctx.queue, &info) } {
            Ok(suboptimal) => Ok(suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(true),
            Err(e) => Err(e.into()),
        }
    }

    /// Records a blit of `src` (already declared as read by transfer) into
    /// swapchain image `index`, just acquired, leaving it ready to present,
    /// or, with `then_draw`, as a colour attachment for drawing on top (then
    /// `attachment_to_present`). The image's old contents are discarded,
    /// and its first barrier waits on the transfer stage, the stage the
    /// acquire semaphore is waited at (`Image::acquired`). A blit, not a
    /// copy, so RGBA sources reach BGRA swapchains with their channels in
    /// place and mismatched sizes are scaled.
    pub fn blit_to_image(&self, commands: &mut Commands, index: u32, src: &Image, then_draw: bool) {
        let cmd = commands.raw();
        let image = &self.images[index as usize];
        image.acquired();
        barrier(
            &self.ctx,
            cmd,
            &[ImageAccess::discard(image, Access::TransferWrite)],
            &[],
        );
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let corner = |e: vk::Extent2D| vk::Offset3D {
            x: e.width as i32,
            y: e.height as i32,
            z: 1,
        };
        let region = vk::ImageBlit::default()
            .src_subresource(layers)
            .src_offsets([vk::Offset3D::default(), corner(src.extent())])
            .dst_subresource(layers)
            .dst_offsets([vk::Offset3D::default(), corner(self.extent)]);
        unsafe {
            self.ctx.device.cmd_blit_image(
                cmd,
                src.raw,
                src.layout(),
                image.raw,
                image.layout(),
                &[region],
                vk::Filter::LINEAR,
            )
        };
        // Presentation needs no access mask: the render-finished semaphore
        // signalled at the end of the submission makes the writes visible.
        let next = if then_draw {
            Access::ColorAttachment
        } else {
            Access::Present
        };
        barrier(&self.ctx, cmd, &[ImageAccess::new(image, next)], &[]);
    }

    /// After drawing on top of a blit: swapchain image `index` to presentation.
    pub fn attachment_to_present(&self, commands: &mut Commands, index: u32) {
        let image = &self.images[index as usize];
        barrier(
            &self.ctx,
            commands.raw(),
            &[ImageAccess::new(image, Access::Present)],
            &[],
        );
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        // The images' views first, then the swapchain that owns the images.
        self.images.clear();
        unsafe { self.loader.destroy_swapchain(self.raw, None) };
    }
}
