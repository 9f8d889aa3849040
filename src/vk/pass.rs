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
use super::sync::{Accesses, Resource};
use super::{Access, Buffer, DescriptorSet, FrameRecorder, Image, Sampler};
use ash::vk;

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
