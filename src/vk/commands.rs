//! The command recorder a pass's closure receives (`Pass::record`): safe
//! calls for everything passes record, each taking the project's own
//! `Buffer`, `Image` and pipelines, alive for the call. No code above
//! `src/vk` sees a command buffer or places a barrier:
//!
//! - the pass's declaration (`Pass::read`, `write`, the bindings) holds at
//!   the start of the pass and again before every later dispatch or
//!   rendering scope: when anything was recorded since its last barrier, the
//!   barrier is emitted again (without discarding), so the steps of a
//!   multi-step pass are ordered as they are written (a dispatch reading
//!   what the previous one wrote, a depth image shared by successive
//!   rendering scopes);
//! - transfer commands (fill, update, copies, clears, read-back) declare
//!   the access to their own resources;
//! - a step whose resources are used otherwise than the pass declares them
//!   (a buffer written as indirect arguments by one dispatch and read as
//!   such by the next) declares the difference with `step()`, and the
//!   declaration goes with the one command that follows.

use super::sync::Accesses;
use super::sync::{barrier, BufferAccess, ImageAccess};
use super::{Access, Buffer, ComputePipeline, Context, DescriptorSet, GraphicsPipeline, Image};
use ash::vk;

/// Records one pass's commands (`Pass::record` hands it to the closure).
pub struct Commands<'c, 'a> {
    ctx: &'c Context,
    cmd: vk::CommandBuffer,
    declared: &'c Accesses<'a>,
    /// A command was recorded after the declaration's last barrier.
    recorded_since_barrier: bool,
}

impl<'c, 'a> Commands<'c, 'a> {
    /// Emits the pass's declaration (discarding what it says to discard) and
    /// returns the recorder for the pass's commands.
    pub(super) fn begin(
        ctx: &'c Context,
        cmd: vk::CommandBuffer,
        declared: &'c Accesses<'a>,
    ) -> Self {
        declared.emit(ctx, cmd);
        Commands {
            ctx,
            cmd,
            declared,
            recorded_since_barrier: false,
        }
    }

    /// The command buffer, for the backend's own recorders (the swapchain).
    pub(super) fn raw(&self) -> vk::CommandBuffer {
        self.cmd
    }

    /// Before a dispatch or a rendering scope: the declaration again, with
    /// `step`'s declarations replacing it for the resources they name.
    fn order(&mut self, step: Option<&Accesses<'_>>) {
        if self.recorded_since_barrier || step.is_some() {
            self.declared.emit_kept(self.ctx, self.cmd, step);
        }
        self.recorded_since_barrier = true;
    }

    /// Binds `pipeline` and `sets`, pushes `push` and dispatches `groups`.
    pub fn dispatch(
        &mut self,
        pipeline: &ComputePipeline,
        sets: &[&DescriptorSet],
        push: &[u8],
        groups: [u32; 3],
    ) {
        self.order(None);
        pipeline.dispatch(self.cmd, sets, push, groups);
    }

    /// As `dispatch`, with the `VkDispatchIndirectCommand` at byte `offset`
    /// of `args` (declared by the pass as `IndirectRead`).
    pub fn dispatch_indirect(
        &mut self,
        pipeline: &ComputePipeline,
        sets: &[&DescriptorSet],
        push: &[u8],
        args: &Buffer,
        offset: u64,
    ) {
        self.order(None);
        pipeline.dispatch_indirect(self.cmd, sets, push, args, offset);
    }

    /// A transfer command's own barrier: `images` and `buffers` as given.
    fn transfer(&mut self, images: &[ImageAccess], buffers: &[BufferAccess]) {
        barrier(self.ctx, self.cmd, images, buffers);
        self.recorded_since_barrier = true;
    }

    /// Fills every byte of `buffer` with the 32-bit `value`.
    pub fn fill(&mut self, buffer: &Buffer, value: u32) {
        self.transfer(&[], &[BufferAccess::new(buffer, Access::TransferWrite)]);
        // SAFETY: `buffer` is alive; `cmd` is recording (a pass's closure).
        unsafe {
            self.ctx
                .device
                .cmd_fill_buffer(self.cmd, buffer.raw, 0, vk::WHOLE_SIZE, value)
        };
    }

    /// Writes `data` (at most 65536 bytes, a multiple of 4) into `buffer` at
    /// `offset`, inline in the command buffer.
    pub fn update(&mut self, buffer: &Buffer, offset: u64, data: &[u8]) {
        self.transfer(&[], &[BufferAccess::new(buffer, Access::TransferWrite)]);
        // SAFETY: as `fill`; the data is copied into the command buffer.
        unsafe {
            self.ctx
                .device
                .cmd_update_buffer(self.cmd, buffer.raw, offset, data)
        };
    }

    /// Copies the first `size` bytes of `src` to the start of `dst`.
    pub fn copy_buffer(&mut self, src: &Buffer, dst: &Buffer, size: u64) {
        self.transfer(
            &[],
            &[
                BufferAccess::new(src, Access::TransferRead),
                BufferAccess::new(dst, Access::TransferWrite),
            ],
        );
        let region = vk::BufferCopy::default().size(size);
        // SAFETY: as `fill`, for both buffers.
        unsafe {
            self.ctx
                .device
                .cmd_copy_buffer(self.cmd, src.raw, dst.raw, &[region])
        };
    }

    /// Copies the first `size` bytes of `src` into the host-visible `dst`,
    /// for the host to read after the frame's fence.
    pub fn read_back(&mut self, src: &Buffer, dst: &Buffer, size: u64) {
        self.copy_buffer(src, dst, size);
        self.transfer(&[], &[BufferAccess::new(dst, Access::HostRead)]);
    }

    /// Copies `src`'s first layer over all of `dst` (same extent and
    /// format); `dst`'s old contents are discarded.
    pub fn copy_image(&mut self, src: &Image, dst: &Image) {
        assert_eq!(
            (src.extent(), src.desc.format),
            (dst.extent(), dst.desc.format),
            "copy_image: images differ in extent or format"
        );
        self.transfer(
            &[
                ImageAccess::new(src, Access::TransferRead),
                ImageAccess::discard(dst, Access::TransferWrite),
            ],
            &[],
        );
        let region = vk::ImageCopy::default()
            .src_subresource(src.level0_layer(0))
            .dst_subresource(dst.level0_layer(0))
            .extent(src.extent_3d());
        // SAFETY: as `fill`, for both images, in the layouts just set.
        unsafe {
            self.ctx.device.cmd_copy_image(
                self.cmd,
                src.raw,
                src.layout(),
                dst.raw,
                dst.layout(),
                &[region],
            )
        };
    }

    /// Clears every layer of mip level 0 of `image` to `value`.
    pub fn clear_image(&mut self, image: &Image, value: vk::ClearColorValue) {
        self.transfer(&[ImageAccess::discard(image, Access::TransferWrite)], &[]);
        let all_layers = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: vk::REMAINING_ARRAY_LAYERS,
        };
        // SAFETY: as `fill`, for the image in the layout just set.
        unsafe {
            self.ctx.device.cmd_clear_color_image(
                self.cmd,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &value,
                &[all_layers],
            )
        };
    }

    /// One dynamic-rendering scope of `extent` into `colors` (each cleared
    /// to its value, or loaded) and an optional depth view `(view, clear)`
    /// (cleared to 1, or loaded to test against an earlier pass's depth);
    /// `draws` records the scope's draws.
    pub fn render<R>(
        &mut self,
        extent: vk::Extent2D,
        colors: &[(vk::ImageView, Option<[f32; 4]>)],
        depth: Option<(vk::ImageView, bool)>,
        draws: impl FnOnce(&mut Rendering) -> R,
    ) -> R {
        self.order(None);
        begin_rendering(self.ctx, self.cmd, extent, colors, depth);
        let result = draws(&mut Rendering {
            ctx: self.ctx,
            cmd: self.cmd,
            extent,
        });
        // SAFETY: the scope begun above.
        unsafe { self.ctx.device.cmd_end_rendering(self.cmd) };
        result
    }

    /// Copies the tightly packed texels of `src` into level 0, layer 0 of
    /// `image`, whose old contents are discarded.
    pub fn copy_buffer_to_image(&mut self, src: &Buffer, image: &Image) {
        self.transfer(
            &[ImageAccess::discard(image, Access::TransferWrite)],
            &[BufferAccess::new(src, Access::TransferRead)],
        );
        let region = vk::BufferImageCopy::default()
            .image_subresource(image.level0_layer(0))
            .image_extent(image.extent_3d());
        // SAFETY: as `fill`, for the buffer and the image in the layout just set.
        unsafe {
            self.ctx.device.cmd_copy_buffer_to_image(
                self.cmd,
                src.raw,
                image.raw,
                image.layout(),
                &[region],
            )
        };
    }

    /// The command buffer for a third-party recorder that records commands
    /// of its own, outside any declaration (a test that must record what
    /// the recorder would order: tests/suite/sync_validation.rs).
    pub fn third_party<R>(&mut self, commands: impl FnOnce(vk::CommandBuffer) -> R) -> R {
        self.recorded_since_barrier = true;
        commands(self.cmd)
    }

    /// Declares, for the one command that follows (`Step::dispatch`), the
    /// resources it uses otherwise than the pass declares them.
    pub fn step<'s>(&'s mut self) -> Step<'s, 'c, 'a> {
        Step {
            commands: self,
            accesses: Accesses::default(),
        }
    }
}

impl Context {
    /// Records `commands` into a one-time command buffer, outside any frame
    /// and with nothing declared (set-up work and tests: declare what a
    /// command needs with `Commands::step`), submits it and waits for it.
    pub fn submit_commands_and_wait<R>(
        &self,
        commands: impl FnOnce(&mut Commands) -> R,
    ) -> super::VkResult<R> {
        let nothing = Accesses::default();
        self.submit_and_wait(|cmd| commands(&mut Commands::begin(self, cmd, &nothing)))
    }
}

/// Resource uses that differ from the pass's declaration, for one command
/// (`Commands::step`).
#[must_use = "a step's declarations take effect with its command"]
pub struct Step<'s, 'c, 'a> {
    commands: &'s mut Commands<'c, 'a>,
    accesses: Accesses<'s>,
}

impl<'s> Step<'s, '_, '_> {
    /// Reads `resource` as `access` in the step's command.
    pub fn read(mut self, resource: impl Into<super::Resource<'s>>, access: Access) -> Self {
        self.accesses.read(resource.into(), access);
        self
    }

    /// Writes `resource` as `access` in the step's command, keeping what is
    /// not overwritten.
    pub fn write(mut self, resource: impl Into<super::Resource<'s>>, access: Access) -> Self {
        self.accesses.write(resource.into(), access, false);
        self
    }

    /// `Commands::dispatch`, after the step's barrier.
    pub fn dispatch(
        self,
        pipeline: &ComputePipeline,
        sets: &[&DescriptorSet],
        push: &[u8],
        groups: [u32; 3],
    ) {
        self.commands.order(Some(&self.accesses));
        pipeline.dispatch(self.commands.cmd, sets, push, groups);
    }
}

/// The draws of one rendering scope (`Commands::render`).
pub struct Rendering<'r> {
    ctx: &'r Context,
    cmd: vk::CommandBuffer,
    extent: vk::Extent2D,
}

impl Rendering<'_> {
    /// Binds `pipeline`, its `sets` and `push` constants, with a viewport
    /// and scissor covering the scope.
    pub fn bind(&mut self, pipeline: &GraphicsPipeline, sets: &[&DescriptorSet], push: &[u8]) {
        pipeline.bind(self.cmd, sets, push, self.extent);
    }

    /// Draws `vertices` vertices of one instance with the bound pipeline
    /// (vertex pulling: no vertex buffers).
    pub fn draw(&mut self, vertices: u32) {
        // SAFETY: `cmd` is recording inside a rendering scope.
        unsafe { self.ctx.device.cmd_draw(self.cmd, vertices, 1, 0, 0) };
    }

    /// One indirect draw whose `VkDrawIndirectCommand` lies at `offset` in
    /// `args` (declared by the pass as `IndirectRead`).
    pub fn draw_indirect(&mut self, args: &Buffer, offset: u64) {
        // SAFETY: as `draw`; `args` is alive.
        unsafe {
            self.ctx
                .device
                .cmd_draw_indirect(self.cmd, args.raw, offset, 1, 0)
        };
    }

    /// The scope's command buffer for a third-party renderer that records
    /// its own draws (the demo's egui overlay, whose renderer takes one);
    /// it must leave the scope as it found it.
    pub fn third_party<R>(&mut self, draws: impl FnOnce(vk::CommandBuffer) -> R) -> R {
        draws(self.cmd)
    }
}

fn begin_rendering(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    extent: vk::Extent2D,
    colors: &[(vk::ImageView, Option<[f32; 4]>)],
    depth: Option<(vk::ImageView, bool)>,
) {
    let load = |clear: bool| {
        if clear {
            vk::AttachmentLoadOp::CLEAR
        } else {
            vk::AttachmentLoadOp::LOAD
        }
    };
    let color_attachments: Vec<_> = colors
        .iter()
        .map(|&(view, clear)| {
            vk::RenderingAttachmentInfo::default()
                .image_view(view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(load(clear.is_some()))
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue {
                    color: vk::ClearColorValue {
                        float32: clear.unwrap_or_default(),
                    },
                })
        })
        .collect();
    let depth_attachment = depth.map(|(view, clear)| {
        vk::RenderingAttachmentInfo::default()
            .image_view(view)
            .image_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
            .load_op(load(clear))
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 1.0,
                    stencil: 0,
                },
            })
    });
    let mut info = vk::RenderingInfo::default()
        .render_area(vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent,
        })
        .layer_count(1)
        .color_attachments(&color_attachments);
    if let Some(d) = depth_attachment.as_ref() {
        info = info.depth_attachment(d);
    }
    // SAFETY: the views are alive (their images are declared by the pass).
    unsafe { ctx.device.cmd_begin_rendering(cmd, &info) };
}
