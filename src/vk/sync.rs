//! Barriers from one function. A pass declares how it is about to use each
//! image and buffer (an `Access`); `barrier` looks up how the resource was
//! last used, and emits the synchronization2 barrier (stages, access masks,
//! layout transition) between the two. Every resource remembers its last
//! access, so passes never spell out source stages by hand.

use super::{Buffer, Context, Image};
use ash::vk;

/// How a pass uses a resource.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Access {
    /// Contents are not needed (first use, or about to be overwritten entirely).
    #[default]
    Undefined,
    /// Read by compute shaders (storage buffer / storage image / sampled).
    ComputeRead,
    /// Written (and possibly read) by compute shaders.
    ComputeWrite,
    /// Sampled or read as storage by fragment shaders.
    FragmentRead,
    /// Read as storage by vertex or geometry shaders (vertex pulling).
    VertexRead,
    /// Read as storage by every stage of a draw: vertex, geometry and
    /// fragment shaders (a buffer pulled per primitive and read again per
    /// fragment).
    GraphicsRead,
    /// Written as storage (e.g. atomics) by fragment shaders.
    FragmentWrite,
    /// Colour attachment written by rendering.
    ColorAttachment,
    /// Depth attachment tested and written by rendering.
    DepthAttachment,
    /// Read by vkCmdDraw*Indirect as arguments.
    IndirectRead,
    TransferRead,
    TransferWrite,
    /// Read by the host after the submission's fence.
    HostRead,
    /// Read by any command without a declaration of its own: a buffer the
    /// frame uploads and every pass may read through set 0 (frame
    /// constants, light views). `FrameRecorder::upload` leaves it so, and
    /// its next upload waits for all of those reads.
    AnyRead,
    /// Handed to the presentation engine.
    Present,
}

/// What a barrier needs to know of a resource's past: its last writer (whose
/// writes must be made visible) and its current use (which a following write
/// must wait for, the write-after-read hazard).
#[derive(Clone, Copy, Debug, Default)]
pub struct ResourceState {
    pub layout: vk::ImageLayout,
    pub last_write: Access,
    pub current: Access,
}

impl ResourceState {
    fn src_stage(&self) -> vk::PipelineStageFlags2 {
        self.last_write.stage() | self.current.stage()
    }
    fn src_access(&self) -> vk::AccessFlags2 {
        self.last_write.writes() | self.current.writes()
    }
    fn after(&self, next: Access, layout: vk::ImageLayout) -> ResourceState {
        let last_write = if next.writes().is_empty() {
            self.last_write
        } else {
            next
        };
        ResourceState {
            layout,
            last_write,
            current: next,
        }
    }
}

impl Access {
    fn stage(self) -> vk::PipelineStageFlags2 {
        use vk::PipelineStageFlags2 as S;
        match self {
            Access::Undefined => S::NONE,
            Access::ComputeRead | Access::ComputeWrite => S::COMPUTE_SHADER,
            Access::FragmentRead | Access::FragmentWrite => S::FRAGMENT_SHADER,
            Access::VertexRead => S::VERTEX_SHADER | S::GEOMETRY_SHADER,
            Access::GraphicsRead => S::VERTEX_SHADER | S::GEOMETRY_SHADER | S::FRAGMENT_SHADER,
            Access::ColorAttachment => S::COLOR_ATTACHMENT_OUTPUT,
            Access::DepthAttachment => S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
            Access::IndirectRead => S::DRAW_INDIRECT,
            Access::TransferRead | Access::TransferWrite => S::ALL_TRANSFER,
            Access::HostRead => S::HOST,
            Access::AnyRead => S::ALL_COMMANDS,
            Access::Present => S::NONE,
        }
    }

    fn access(self) -> vk::AccessFlags2 {
        use vk::AccessFlags2 as A;
        match self {
            Access::Undefined | Access::Present => A::NONE,
            Access::ComputeRead
            | Access::FragmentRead
            | Access::VertexRead
            | Access::GraphicsRead => A::SHADER_READ,
            Access::ComputeWrite | Access::FragmentWrite => A::SHADER_READ | A::SHADER_WRITE,
            Access::ColorAttachment => A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE,
            Access::DepthAttachment => {
                A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE
            }
            Access::IndirectRead => A::INDIRECT_COMMAND_READ,
            Access::TransferRead => A::TRANSFER_READ,
            Access::TransferWrite => A::TRANSFER_WRITE,
            Access::HostRead => A::HOST_READ,
            Access::AnyRead => A::MEMORY_READ,
        }
    }

    /// Whether the access writes (a pass declares it as a write).
    pub fn is_write(self) -> bool {
        !self.writes().is_empty()
    }

    /// The layout this access puts `image` in (what a descriptor of it must say).
    pub fn layout_of(self, image: &Image) -> vk::ImageLayout {
        self.layout(image.aspect().contains(vk::ImageAspectFlags::DEPTH))
    }

    /// Only the write part of the access: what a later barrier must make available.
    fn writes(self) -> vk::AccessFlags2 {
        use vk::AccessFlags2 as A;
        self.access()
            & (A::SHADER_WRITE
                | A::COLOR_ATTACHMENT_WRITE
                | A::DEPTH_STENCIL_ATTACHMENT_WRITE
                | A::TRANSFER_WRITE)
    }

    fn layout(self, format_is_depth: bool) -> vk::ImageLayout {
        use vk::ImageLayout as L;
        match self {
            Access::Undefined => L::UNDEFINED,
            Access::ComputeRead | Access::ComputeWrite | Access::FragmentWrite => L::GENERAL,
            Access::FragmentRead | Access::VertexRead | Access::GraphicsRead => {
                // The DEPTH_STENCIL_* layouts need no separateDepthStencilLayouts.
                if format_is_depth {
                    L::DEPTH_STENCIL_READ_ONLY_OPTIMAL
                } else {
                    L::SHADER_READ_ONLY_OPTIMAL
                }
            }
            Access::ColorAttachment => L::COLOR_ATTACHMENT_OPTIMAL,
            Access::DepthAttachment => L::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
            Access::IndirectRead | Access::HostRead | Access::AnyRead => L::GENERAL,
            Access::TransferRead => L::TRANSFER_SRC_OPTIMAL,
            Access::TransferWrite => L::TRANSFER_DST_OPTIMAL,
            Access::Present => L::PRESENT_SRC_KHR,
        }
    }
}

/// An image about to be used as `next`. `discard` drops its contents (layout UNDEFINED as source).
pub struct ImageAccess<'a> {
    pub image: &'a Image,
    pub next: Access,
    pub discard: bool,
}

impl<'a> ImageAccess<'a> {
    pub fn new(image: &'a Image, next: Access) -> Self {
        Self {
            image,
            next,
            discard: false,
        }
    }
    /// The pass overwrites the whole image: earlier contents need not be kept.
    pub fn discard(image: &'a Image, next: Access) -> Self {
        Self {
            image,
            next,
            discard: true,
        }
    }
}

pub struct BufferAccess<'a> {
    pub buffer: &'a Buffer,
    pub next: Access,
}

impl<'a> BufferAccess<'a> {
    pub fn new(buffer: &'a Buffer, next: Access) -> Self {
        Self { buffer, next }
    }
}

/// Emits one vkCmdPipelineBarrier2 that orders every listed resource's last
/// access before its next one, and records the new state. Read-after-read
/// with an unchanged layout needs no barrier and is skipped.
pub fn barrier(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    images: &[ImageAccess],
    buffers: &[BufferAccess],
) {
    let mut image_barriers = Vec::new();
    for ia in images {
        let prev = ia.image.state.get();
        let is_depth = ia.image.aspect().contains(vk::ImageAspectFlags::DEPTH);
        let new_layout = ia.next.layout(is_depth);
        let old_layout = if ia.discard {
            vk::ImageLayout::UNDEFINED
        } else {
            prev.layout
        };
        if old_layout == new_layout && prev.current == ia.next && ia.next.writes().is_empty() {
            continue;
        }
        image_barriers.push(
            vk::ImageMemoryBarrier2::default()
                .src_stage_mask(prev.src_stage())
                .src_access_mask(prev.src_access())
                .dst_stage_mask(ia.next.stage())
                .dst_access_mask(ia.next.access())
                .old_layout(old_layout)
                .new_layout(new_layout)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(ia.image.raw)
                .subresource_range(vk::ImageSubresourceRange {
                    aspect_mask: ia.image.aspect(),
                    base_mip_level: 0,
                    level_count: ia.image.mip_levels,
                    base_array_layer: 0,
                    layer_count: ia.image.desc.layers,
                }),
        );
        ia.image.state.set(prev.after(ia.next, new_layout));
    }
    let mut buffer_barriers = Vec::new();
    for ba in buffers {
        ba.buffer.bound.set(true);
        let prev = ba.buffer.state.get();
        if prev.current == ba.next && ba.next.writes().is_empty() {
            continue;
        }
        buffer_barriers.push(
            vk::BufferMemoryBarrier2::default()
                .src_stage_mask(prev.src_stage())
                .src_access_mask(prev.src_access())
                .dst_stage_mask(ba.next.stage())
                .dst_access_mask(ba.next.access())
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .buffer(ba.buffer.raw)
                .offset(0)
                .size(vk::WHOLE_SIZE),
        );
        ba.buffer
            .state
            .set(prev.after(ba.next, vk::ImageLayout::UNDEFINED));
    }
    if image_barriers.is_empty() && buffer_barriers.is_empty() {
        return;
    }
    let dep = vk::DependencyInfo::default()
        .image_memory_barriers(&image_barriers)
        .buffer_memory_barriers(&buffer_barriers);
    unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &dep) };
}

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
