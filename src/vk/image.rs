//! Images backed by gpu-allocator (2D, 2D arrays, mip chains, and the
//! swapchain's images wrapped for tracking). Each owns its allocation and
//! returns it (and destroys the Vulkan handle) on `Drop`; see the lifetime
//! note in `vk/mod.rs`.

use super::resources::{allocate, free, next_id};
use super::sync::ResourceState;
use super::{limits, Buffer, BufferUsage, Context, VkResult};
use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;
use std::cell::Cell;
use std::sync::Arc;

#[derive(Clone, Copy, Debug)]
pub struct ImageDesc {
    pub width: u32,
    pub height: u32,
    pub layers: u32,
    pub format: vk::Format,
    pub usage: vk::ImageUsageFlags,
}

impl ImageDesc {
    pub fn new_2d(width: u32, height: u32, format: vk::Format, usage: vk::ImageUsageFlags) -> Self {
        Self {
            width,
            height,
            layers: 1,
            format,
            usage,
        }
    }
}

/// A 2D image (or 2D array of `layers`), its full view and one view per layer
/// (for rendering into single layers). It tracks its current layout and last
/// access so `sync::barrier` can build the transition.
pub struct Image {
    ctx: Arc<Context>,
    pub raw: vk::Image,
    /// View of every layer (2D, or 2D array when layers > 1).
    pub view: vk::ImageView,
    /// One 2D view per layer.
    pub layer_views: Vec<vk::ImageView>,
    /// One 2D-array view (all layers) per mip level, for compute writes of
    /// single levels (`Image::mipmapped`); empty otherwise.
    pub level_views: Vec<vk::ImageView>,
    pub desc: ImageDesc,
    /// Mip levels (1 but for `Image::sampled_with_levels`).
    pub mip_levels: u32,
    pub(super) state: Cell<ResourceState>,
    /// As `Buffer::id`.
    pub(super) id: u64,
    /// A swapchain's image: the swapchain owns `raw` (only the view is ours).
    presentable: bool,
    allocation: Option<Allocation>,
}

impl Image {
    pub fn new(ctx: &Arc<Context>, name: &str, desc: ImageDesc) -> VkResult<Image> {
        Self::create(ctx, name, desc, false, 1)
    }

    /// As `new`, but the full view is a 2D array even with one layer (for
    /// shaders that declare `image2DArray` whatever the layer count).
    pub fn new_array(ctx: &Arc<Context>, name: &str, desc: ImageDesc) -> VkResult<Image> {
        Self::create(ctx, name, desc, true, 1)
    }

    /// A 2D array image with `levels` mip levels that shaders write level
    /// by level (`level_views`) and sample through `view` (all levels).
    pub fn mipmapped(
        ctx: &Arc<Context>,
        name: &str,
        desc: ImageDesc,
        levels: u32,
    ) -> VkResult<Image> {
        let mut image = Self::create(ctx, name, desc, true, levels)?;
        for level in 0..levels {
            let info = vk::ImageViewCreateInfo::default()
                .image(image.raw)
                .view_type(vk::ImageViewType::TYPE_2D_ARRAY)
                .format(desc.format)
                .subresource_range(vk::ImageSubresourceRange {
                    aspect_mask: aspect_of(desc.format),
                    base_mip_level: level,
                    level_count: 1,
                    base_array_layer: 0,
                    layer_count: desc.layers,
                });
            image
                .level_views
                .push(unsafe { ctx.device.create_image_view(&info, None) }?);
        }
        Ok(image)
    }

    /// A read-only sampled 2D array image with one mip level per entry of
    /// `levels` (level l: every layer's texels, layer after layer, tightly
    /// packed; level l is `max(1, width >> l)` wide). The data is copied in
    /// a blocking submission that ends in SHADER_READ_ONLY_OPTIMAL, made
    /// visible to every later shader read; the image never changes again,
    /// so its readers declare no access to it (and it must not be passed to
    /// `barrier`).
    pub fn sampled_with_levels(
        ctx: &Arc<Context>,
        name: &str,
        desc: ImageDesc,
        levels: &[&[u8]],
    ) -> VkResult<Image> {
        let desc = ImageDesc {
            usage: desc.usage | vk::ImageUsageFlags::SAMPLED,
            ..desc
        };
        let image = Self::create(ctx, name, desc, true, levels.len() as u32)?;
        let bytes: Vec<u8> = levels.concat();
        let staging = Buffer::new(
            ctx,
            "texture staging",
            bytes.len() as u64,
            BufferUsage::Upload,
        )?;
        staging.upload(&bytes)?;
        let range = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: image.mip_levels,
            base_array_layer: 0,
            layer_count: desc.layers,
        };
        ctx.submit_and_wait(|cmd| unsafe {
            let to_dst = vk::ImageMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::NONE)
                .dst_stage_mask(vk::PipelineStageFlags2::COPY)
                .dst_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .old_layout(vk::ImageLayout::UNDEFINED)
                .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .image(image.raw)
                .subresource_range(range);
            ctx.device.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().image_memory_barriers(&[to_dst]),
            );
            let mut offset = 0u64;
            let regions: Vec<vk::BufferImageCopy> = levels
                .iter()
                .enumerate()
                .map(|(l, data)| {
                    let region = vk::BufferImageCopy::default()
                        .buffer_offset(offset)
                        .image_subresource(vk::ImageSubresourceLayers {
                            aspect_mask: vk::ImageAspectFlags::COLOR,
                            mip_level: l as u32,
                            base_array_layer: 0,
                            layer_count: desc.layers,
                        })
                        .image_extent(vk::Extent3D {
                            width: (desc.width >> l).max(1),
                            height: (desc.height >> l).max(1),
                            depth: 1,
                        });
                    offset += data.len() as u64;
                    region
                })
                .collect();
            ctx.device.cmd_copy_buffer_to_image(
                cmd,
                staging.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &regions,
            );
            // A fence makes device writes visible to the host only: make the
            // copy visible to every later submission's shader reads.
            let to_read = vk::ImageMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COPY)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .dst_access_mask(vk::AccessFlags2::SHADER_SAMPLED_READ)
                .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .new_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
                .image(image.raw)
                .subresource_range(range);
            ctx.device.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().image_memory_barriers(&[to_read]),
            );
        })?;
        image.state.set(ResourceState {
            layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            ..Default::default()
        });
        Ok(image)
    }

    fn create(
        ctx: &Arc<Context>,
        name: &str,
        desc: ImageDesc,
        array: bool,
        mip_levels: u32,
    ) -> VkResult<Image> {
        limits::check_image(&ctx.limits, name, desc.width, desc.height, desc.layers)?;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D {
                width: desc.width,
                height: desc.height,
                depth: 1,
            })
            .mip_levels(mip_levels)
            .array_layers(desc.layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(
                desc.usage | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST,
            )
            .initial_layout(vk::ImageLayout::UNDEFINED);
        limits::check_image_format(ctx, name, &info)?;
        let raw = unsafe { ctx.device.create_image(&info, None) }?;
        let requirements = unsafe { ctx.device.get_image_memory_requirements(raw) };
        let allocation = match allocate(ctx, name, requirements, MemoryLocation::GpuOnly, false) {
            Ok(a) => a,
            Err(e) => {
                unsafe { ctx.device.destroy_image(raw, None) };
                return Err(e);
            }
        };
        unsafe {
            ctx.device
                .bind_image_memory(raw, allocation.memory(), allocation.offset())
        }?;
        ctx.set_name(raw, name);
        let aspect = aspect_of(desc.format);
        let make_view = |base: u32, count: u32, ty: vk::ImageViewType, levels: u32| {
            let info = vk::ImageViewCreateInfo::default()
                .image(raw)
                .view_type(ty)
                .format(desc.format)
                .subresource_range(vk::ImageSubresourceRange {
                    aspect_mask: aspect,
                    base_mip_level: 0,
                    level_count: levels,
                    base_array_layer: base,
                    layer_count: count,
                });
            unsafe { ctx.device.create_image_view(&info, None) }
        };
        let ty = if desc.layers > 1 || array {
            vk::ImageViewType::TYPE_2D_ARRAY
        } else {
            vk::ImageViewType::TYPE_2D
        };
        let mut image = Image {
            ctx: ctx.clone(),
            raw,
            view: vk::ImageView::null(),
            layer_views: Vec::new(),
            level_views: Vec::new(),
            desc,
            mip_levels,
            state: Cell::new(ResourceState::default()),
            id: next_id(),
            presentable: false,
            allocation: Some(allocation),
        };
        image.view = make_view(0, desc.layers, ty, mip_levels)?;
        for layer in 0..desc.layers {
            image
                .layer_views
                .push(make_view(layer, 1, vk::ImageViewType::TYPE_2D, 1)?);
        }
        Ok(image)
    }

    /// A swapchain's image `raw` (the swapchain owns and destroys it) with a
    /// colour view of its own, tracked like any image so that its layout
    /// transitions come from the same declarations (`vk/swapchain.rs`).
    pub(super) fn presentable(
        ctx: &Arc<Context>,
        raw: vk::Image,
        format: vk::Format,
        extent: vk::Extent2D,
    ) -> VkResult<Image> {
        let info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(vk::ImageSubresourceRange {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                base_mip_level: 0,
                level_count: 1,
                base_array_layer: 0,
                layer_count: 1,
            });
        let view = unsafe { ctx.device.create_image_view(&info, None) }?;
        Ok(Image {
            ctx: ctx.clone(),
            raw,
            view,
            layer_views: Vec::new(),
            level_views: Vec::new(),
            desc: ImageDesc::new_2d(
                extent.width,
                extent.height,
                format,
                vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::COLOR_ATTACHMENT,
            ),
            mip_levels: 1,
            state: Cell::new(ResourceState::default()),
            id: next_id(),
            presentable: true,
            allocation: None,
        })
    }

    /// A swapchain image was just acquired: its contents are undefined, and
    /// its first barrier must start at the stage the acquire semaphore is
    /// waited at (transfer: the blit), so that the layout transition waits
    /// for the presentation engine.
    pub(super) fn acquired(&self) {
        self.state.set(ResourceState {
            layout: vk::ImageLayout::UNDEFINED,
            last_write: super::Access::Undefined,
            current: super::Access::TransferRead,
        });
    }

    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D {
            width: self.desc.width,
            height: self.desc.height,
        }
    }

    /// Mip level 0 of `layer`, as a copy addresses it.
    pub(super) fn level0_layer(&self, layer: u32) -> vk::ImageSubresourceLayers {
        vk::ImageSubresourceLayers {
            aspect_mask: self.aspect(),
            mip_level: 0,
            base_array_layer: layer,
            layer_count: 1,
        }
    }

    /// Mip level 0's extent, as a copy addresses it.
    pub(super) fn extent_3d(&self) -> vk::Extent3D {
        vk::Extent3D {
            width: self.desc.width,
            height: self.desc.height,
            depth: 1,
        }
    }

    pub fn aspect(&self) -> vk::ImageAspectFlags {
        aspect_of(self.desc.format)
    }

    pub fn layout(&self) -> vk::ImageLayout {
        self.state.get().layout
    }

    /// Reads layer 0 back as 32-bit floats, four per pixel (the image must be
    /// RGBA32F; the caller has recorded the last write into an earlier submission).
    pub fn download_rgba32f(&self) -> VkResult<Vec<f32>> {
        assert_eq!(
            self.desc.format,
            vk::Format::R32G32B32A32_SFLOAT,
            "download_rgba32f needs an RGBA32F image"
        );
        let bytes = self.download_bytes(16)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Reads layer 0 back as raw texels of `texel_size` bytes.
    pub fn download_bytes(&self, texel_size: u64) -> VkResult<Vec<u8>> {
        self.download_layer_bytes(0, texel_size)
    }

    /// Reads layer `layer` back as 32-bit floats, four per pixel (RGBA32F).
    pub fn download_layer_rgba32f(&self, layer: u32) -> VkResult<Vec<f32>> {
        assert_eq!(
            self.desc.format,
            vk::Format::R32G32B32A32_SFLOAT,
            "download_layer_rgba32f needs an RGBA32F image"
        );
        let bytes = self.download_layer_bytes(layer, 16)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Reads layer `layer` back as raw texels of `texel_size` bytes.
    pub fn download_layer_bytes(&self, layer: u32, texel_size: u64) -> VkResult<Vec<u8>> {
        let size = self.desc.width as u64 * self.desc.height as u64 * texel_size;
        let readback = Buffer::new(&self.ctx, "image readback", size, BufferUsage::Readback)?;
        self.ctx.submit_and_wait(|cmd| {
            super::sync::barrier(
                &self.ctx,
                cmd,
                &[super::ImageAccess::new(self, super::Access::TransferRead)],
                &[],
            );
            let region = vk::BufferImageCopy::default()
                .image_subresource(self.level0_layer(layer))
                .image_extent(self.extent_3d());
            unsafe {
                self.ctx.device.cmd_copy_image_to_buffer(
                    cmd,
                    self.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    readback.raw,
                    &[region],
                );
            }
            readback.state.set(ResourceState {
                current: super::Access::TransferWrite,
                ..Default::default()
            });
            super::sync::barrier(
                &self.ctx,
                cmd,
                &[],
                &[super::BufferAccess::new(&readback, super::Access::HostRead)],
            );
        })?;
        readback.download()
    }
}

pub(super) fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D32_SFLOAT | vk::Format::D16_UNORM | vk::Format::X8_D24_UNORM_PACK32 => {
            vk::ImageAspectFlags::DEPTH
        }
        vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        unsafe {
            for v in self.layer_views.drain(..).chain(self.level_views.drain(..)) {
                self.ctx.device.destroy_image_view(v, None);
            }
            self.ctx.device.destroy_image_view(self.view, None);
        }
        if let Some(a) = self.allocation.take() {
            free(&self.ctx, a);
        }
        if !self.presentable {
            unsafe { self.ctx.device.destroy_image(self.raw, None) };
        }
    }
}
