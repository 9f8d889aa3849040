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
//!     .record(|cmd| pipeline.dispatch(cmd, &[&scene.set, &set], push, groups));
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
//! Within one pass, a later step that depends on an earlier one (a dispatch
//! reading what the previous dispatch wrote) is ordered by `step`, a
//! declaration of the same kind: `step(ctx, cmd).read(..).write(..).emit()`.

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
    fn add(&mut self, resource: Resource<'a>, access: Access, discard: bool) {
        match resource {
            Resource::Image(image) => self.images.push(if discard {
                ImageAccess::discard(image, access)
            } else {
                ImageAccess::new(image, access)
            }),
            Resource::Buffer(buffer) => {
                assert!(!discard, "only an image's contents can be discarded");
                self.buffers.push(BufferAccess::new(buffer, access));
            }
        }
    }

    fn read(&mut self, resource: Resource<'a>, access: Access) {
        assert!(
            !access.is_write(),
            "read declared with the writing access {access:?}"
        );
        self.add(resource, access, false);
    }

    fn write(&mut self, resource: Resource<'a>, access: Access, discard: bool) {
        assert!(
            access.is_write(),
            "write declared with the read-only access {access:?}"
        );
        self.add(resource, access, discard);
    }

    fn emit(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        barrier(ctx, cmd, &self.images, &self.buffers);
    }
}

/// `read`, `write` and `overwrite`, shared by a pass (`Pass`) and a step
/// within one (`Sync`): both gather `Accesses` in a field `accesses`.
macro_rules! declarations {
    () => {
        /// Reads `resource` (for a pass: bound elsewhere, such as set 0, an
        /// attachment or an indirect argument buffer).
        pub fn read(mut self, resource: impl Into<Resource<'a>>, access: Access) -> Self {
            self.accesses.read(resource.into(), access);
            self
        }

        /// Writes `resource`, keeping what is not overwritten.
        pub fn write(mut self, resource: impl Into<Resource<'a>>, access: Access) -> Self {
            self.accesses.write(resource.into(), access, false);
            self
        }

        /// Overwrites every texel of `image`: its contents need not be kept.
        pub fn overwrite(mut self, image: &'a Image, access: Access) -> Self {
            self.accesses.write(Resource::Image(image), access, true);
            self
        }
    };
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
}

impl<'r, 'f, 'a> Pass<'r, 'f, 'a> {
    pub(super) fn new(rec: &'r mut FrameRecorder<'f>, name: &str) -> Self {
        Pass {
            rec,
            name: name.to_string(),
            accesses: Accesses::default(),
            bindings: Vec::new(),
        }
    }

    declarations!();

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
    /// barrier first, then `commands`.
    pub fn record(self, commands: impl FnOnce(vk::CommandBuffer)) {
        let Pass {
            rec,
            name,
            accesses,
            bindings,
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
        rec.record_pass(&name, |cmd| {
            accesses.emit(&ctx, cmd);
            commands(cmd);
        });
    }
}

/// Starts a mid-pass declaration: a step of a pass that depends on an
/// earlier step of it (`emit` records the barrier between them).
pub fn step<'c, 'a>(ctx: &'c Context, cmd: vk::CommandBuffer) -> Sync<'c, 'a> {
    Sync {
        ctx,
        cmd,
        accesses: Accesses::default(),
    }
}

/// A mid-pass declaration (`step`); `emit` records its barrier.
#[must_use = "a sync declaration takes effect only through `emit`"]
pub struct Sync<'c, 'a> {
    ctx: &'c Context,
    cmd: vk::CommandBuffer,
    accesses: Accesses<'a>,
}

impl<'a> Sync<'_, 'a> {
    declarations!();

    pub fn emit(self) {
        self.accesses.emit(self.ctx, self.cmd);
    }
}
