//! The pass builder: one declaration per pass of every image and buffer it
//! touches, from which both its barriers (`vk/sync.rs`) and its descriptor
//! writes come, so the two cannot drift apart:
//!
//! ```ignore
//! rec.pass("direct lighting")
//!     .storage_image(&set, BINDING_POSITION, &gbuffer.position, Access::ComputeRead)
//!     .sampled(&set, BINDING_SHADOW_MAP, &shadows.map, &sampler, Access::ComputeRead)
//!     .overwrite_storage_image(&set, BINDING_RADIANCE, &targets.radiance, Access::ComputeWrite)
//!     .read(&sh, Access::ComputeRead)
//!     .record(|c| c.dispatch(&pipeline, &[&scene.set, &set], push, groups));
//! ```
//!
//! A binding's layout is the layout its access puts the image in
//! (`Access::layout`), never spelled out by the caller. A binding is written
//! only when what it points at changes (the set remembers its contents by
//! resource id). Changing a binding that submitted frames may use first
//! waits for the other frames in flight (a set may not be updated while a
//! pending command buffer uses it); changing one after the set was bound
//! earlier in the same frame is a programming error and panics.
//!
//! The closure records through `Commands` (`vk/commands.rs`), which orders
//! a pass's later steps after its earlier ones from the same declaration.

use super::commands::Commands;
use super::descriptors::Bound;
use super::sync::{barrier, ImageAccess};
use super::{Access, Buffer, BufferAccess, Context, DescriptorSet, FrameRecorder, Image, Sampler};
use ash::vk;

/// An image or a buffer, as a pass declares it.
#[derive(Clone, Copy)]
pub enum Resource<'a> {
    Image(&'a Image),
    Buffer(&'a Buffer),
}

impl<'a> From<&'a Image> for Resource<'a> {
    fn from(image: &'a Image) -> Self {
        Resource::Image(image)
    }
}

impl<'a> From<&'a Buffer> for Resource<'a> {
    fn from(buffer: &'a Buffer) -> Self {
        Resource::Buffer(buffer)
    }
}

/// The accesses one step declares, turned into one barrier.
#[derive(Default)]
pub struct Accesses<'a> {
    images: Vec<ImageAccess<'a>>,
    buffers: Vec<BufferAccess<'a>>,
}

impl<'a> Accesses<'a> {
    /// Adds one access; the same access to the same resource again (one
    /// image bound through several views, as a mip chain's levels are)
    /// adds nothing, so the barrier, emitted again before each later
    /// command of the pass, holds each resource once.
    fn add(&mut self, resource: Resource<'a>, access: Access, discard: bool) {
        match resource {
            Resource::Image(image) => {
                let same = |a: &ImageAccess| {
                    a.image.raw == image.raw && a.next == access && a.discard == discard
                };
                if !self.images.iter().any(same) {
                    self.images.push(if discard {
                        ImageAccess::discard(image, access)
                    } else {
                        ImageAccess::new(image, access)
                    });
                }
            }
            Resource::Buffer(buffer) => {
                assert!(!discard, "only an image's contents can be discarded");
                let same = |a: &BufferAccess| a.buffer.raw == buffer.raw && a.next == access;
                if !self.buffers.iter().any(same) {
                    self.buffers.push(BufferAccess::new(buffer, access));
                }
            }
        }
    }

    pub(super) fn read(&mut self, resource: Resource<'a>, access: Access) {
        assert!(
            !access.is_write(),
            "read declared with the writing access {access:?}"
        );
        self.add(resource, access, false);
    }

    pub(super) fn write(&mut self, resource: Resource<'a>, access: Access, discard: bool) {
        assert!(
            access.is_write(),
            "write declared with the read-only access {access:?}"
        );
        self.add(resource, access, discard);
    }

    pub(super) fn emit(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        barrier(ctx, cmd, &self.images, &self.buffers);
    }

    /// The declaration again, keeping every image's contents, with `step`'s
    /// accesses in place of it for the resources `step` names.
    pub(super) fn emit_kept(&self, ctx: &Context, cmd: vk::CommandBuffer, step: Option<&Accesses>) {
        let step_images = step.map_or(&[][..], |s| &s.images[..]);
        let step_buffers = step.map_or(&[][..], |s| &s.buffers[..]);
        let images: Vec<ImageAccess> = self
            .images
            .iter()
            .filter(|a| step_images.iter().all(|s| s.image.raw != a.image.raw))
            .map(|a| ImageAccess::new(a.image, a.next))
            .chain(
                step_images
                    .iter()
                    .map(|s| ImageAccess::new(s.image, s.next)),
            )
            .collect();
        let buffers: Vec<BufferAccess> = self
            .buffers
            .iter()
            .filter(|a| step_buffers.iter().all(|s| s.buffer.raw != a.buffer.raw))
            .map(|a| BufferAccess::new(a.buffer, a.next))
            .chain(
                step_buffers
                    .iter()
                    .map(|s| BufferAccess::new(s.buffer, s.next)),
            )
            .collect();
        barrier(ctx, cmd, &images, &buffers);
    }
}

/// One binding a pass declares, written before its commands are recorded.
struct Binding<'a> {
    set: &'a DescriptorSet,
    binding: u32,
    bound: Bound,
    /// The buffer, for a buffer binding.
    buffer: Option<&'a Buffer>,
}

/// A pass being declared: `FrameRecorder::pass` starts it, `record` records it.
#[must_use = "a pass is recorded only by `record`"]
pub struct Pass<'r, 'f, 'a> {
    rec: &'r mut FrameRecorder<'f>,
    name: String,
    accesses: Accesses<'a>,
    bindings: Vec<Binding<'a>>,
    untimed: bool,
}

impl<'r, 'f, 'a> Pass<'r, 'f, 'a> {
    pub(super) fn new(rec: &'r mut FrameRecorder<'f>, name: &str) -> Self {
        Pass {
            rec,
            name: name.to_string(),
            accesses: Accesses::default(),
            bindings: Vec::new(),
            untimed: false,
        }
    }

    /// Reads `resource`, bound elsewhere (set 0, an attachment, an indirect
    /// argument buffer).
    pub fn read(mut self, resource: impl Into<Resource<'a>>, access: Access) -> Self {
        self.accesses.read(resource.into(), access);
        self
    }

    /// Writes `resource`, keeping what is not overwritten.
    pub fn write(mut self, resource: impl Into<Resource<'a>>, access: Access) -> Self {
        self.accesses.write(resource.into(), access, false);
        self
    }

    /// Overwrites every texel of `image` at the start of the pass: its
    /// contents need not be kept.
    pub fn overwrite(mut self, image: &'a Image, access: Access) -> Self {
        self.accesses.write(Resource::Image(image), access, true);
        self
    }

    /// Records the pass into the frame's command buffer untimed, even when
    /// every other pass is a submission of its own (`TimingSource::WallClock`):
    /// the demo's blit to the swapchain image, which must wait for the
    /// frame's acquire semaphore.
    pub fn untimed(mut self) -> Self {
        self.untimed = true;
        self
    }

    fn declare(&mut self, resource: Resource<'a>, access: Access) {
        if access.is_write() {
            self.accesses.write(resource, access, false);
        } else {
            self.accesses.read(resource, access);
        }
    }

    fn bind_image(&mut self, set: &'a DescriptorSet, binding: u32, bound: Bound) {
        self.bindings.push(Binding {
            set,
            binding,
            bound,
            buffer: None,
        });
    }

    /// `set`'s storage-image `binding` is `image` (all layers), accessed as `access`.
    pub fn storage_image(
        self,
        set: &'a DescriptorSet,
        binding: u32,
        image: &'a Image,
        access: Access,
    ) -> Self {
        self.storage_view(set, binding, image, image.view, access)
    }

    /// As `storage_image`, for a pass that overwrites every texel.
    pub fn overwrite_storage_image(
        mut self,
        set: &'a DescriptorSet,
        binding: u32,
        image: &'a Image,
        access: Access,
    ) -> Self {
        self.accesses.write(Resource::Image(image), access, true);
        self.bind_storage(set, binding, image, image.view, access);
        self
    }

    /// `set`'s storage-image `binding` is one view of `image` (a mip level,
    /// `Image::level_views`); the barrier covers the whole image.
    pub fn storage_view(
        mut self,
        set: &'a DescriptorSet,
        binding: u32,
        image: &'a Image,
        view: vk::ImageView,
        access: Access,
    ) -> Self {
        self.declare(Resource::Image(image), access);
        self.bind_storage(set, binding, image, view, access);
        self
    }

    fn bind_storage(
        &mut self,
        set: &'a DescriptorSet,
        binding: u32,
        image: &'a Image,
        view: vk::ImageView,
        access: Access,
    ) {
        let layout = access.layout_of(image);
        assert_eq!(
            layout,
            vk::ImageLayout::GENERAL,
            "storage images are accessed in GENERAL layout, not through {access:?}"
        );
        self.bind_image(
            set,
            binding,
            Bound::image(image, view, layout, vk::Sampler::null()),
        );
    }

    /// `set`'s combined-image-sampler `binding` is `image` with `sampler`,
    /// in the layout `access` puts it in.
    pub fn sampled(
        mut self,
        set: &'a DescriptorSet,
        binding: u32,
        image: &'a Image,
        sampler: &'a Sampler,
        access: Access,
    ) -> Self {
        self.accesses.read(Resource::Image(image), access);
        self.bind_image(
            set,
            binding,
            Bound::image(image, image.view, access.layout_of(image), sampler.raw),
        );
        self
    }

    /// `set`'s uniform or storage-buffer `binding` is `buffer`, accessed as `access`.
    pub fn buffer(
        mut self,
        set: &'a DescriptorSet,
        binding: u32,
        buffer: &'a Buffer,
        access: Access,
    ) -> Self {
        self.declare(Resource::Buffer(buffer), access);
        self.bindings.push(Binding {
            set,
            binding,
            bound: Bound::buffer(buffer),
            buffer: Some(buffer),
        });
        self
    }

    /// Writes the declared bindings that changed, then records the pass: its
    /// barrier first, then `commands` through the recorder. `None` when an
    /// earlier pass of the frame failed (the frame is not recorded further).
    pub fn record<R>(self, commands: impl FnOnce(&mut Commands) -> R) -> Option<R> {
        let Pass {
            rec,
            name,
            accesses,
            bindings,
            untimed,
        } = self;
        let serial = rec.serial();
        let mut waited = false;
        for b in &bindings {
            let current = b.set.bound(b.binding);
            if current == Some(b.bound) {
                continue;
            }
            // Updating a set already bound in this command buffer would
            // invalidate it: a set's image bindings are declared by the
            // first pass that binds it in a frame (or a pass has its own set).
            assert!(
                b.set.bound_in.get() != serial,
                "pass \"{name}\": binding {} changes after its set was bound earlier in this frame",
                b.binding
            );
            // A set that submitted frames may still use is rewritten only
            // when none is in flight.
            if current.is_some() && !waited {
                rec.wait_for_other_frames();
                waited = true;
            }
            match b.buffer {
                Some(buffer) => {
                    b.set.write_buffer(b.binding, buffer);
                }
                None => b.set.write_image(b.binding, b.bound),
            }
        }
        let ctx = rec.ctx().clone();
        rec.record_pass(&name, untimed, |cmd| {
            commands(&mut Commands::begin(&ctx, cmd, &accesses))
        })
    }
}
