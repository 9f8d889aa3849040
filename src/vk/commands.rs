//! The transfer and draw commands passes record beside their dispatches
//! (`ComputePipeline::dispatch`) and rendering scopes (`begin_rendering`),
//! as safe calls: each takes the project's own `Buffer` or `Image`, alive
//! for the call, and the pass's command buffer (the one `Pass::record`
//! hands its closure), and records one command. Ordering against other
//! passes is the pass declaration's (`Pass::read`/`write`), as for every
//! command.

use super::{Buffer, Context, Image};
use ash::vk;

/// Fills every byte of `buffer` with the 32-bit `value`.
pub fn fill_buffer(ctx: &Context, cmd: vk::CommandBuffer, buffer: &Buffer, value: u32) {
    // SAFETY: `buffer` is alive; `cmd` is recording (a pass's closure).
    unsafe {
        ctx.device
            .cmd_fill_buffer(cmd, buffer.raw, 0, vk::WHOLE_SIZE, value)
    };
}

/// Writes `data` (at most 65536 bytes, a multiple of 4) into `buffer` at
/// `offset`, inline in the command buffer.
pub fn update_buffer(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    buffer: &Buffer,
    offset: u64,
    data: &[u8],
) {
    // SAFETY: as `fill_buffer`; the data is copied into the command buffer.
    unsafe { ctx.device.cmd_update_buffer(cmd, buffer.raw, offset, data) };
}

/// Copies the first `size` bytes of `src` to the start of `dst`.
pub fn copy_buffer(ctx: &Context, cmd: vk::CommandBuffer, src: &Buffer, dst: &Buffer, size: u64) {
    let region = vk::BufferCopy::default().size(size);
    // SAFETY: as `fill_buffer`, for both buffers.
    unsafe { ctx.device.cmd_copy_buffer(cmd, src.raw, dst.raw, &[region]) };
}

/// Clears every layer of mip level 0 of `image` (in the transfer
/// destination layout a `TransferWrite` declaration gives it) to `value`.
pub fn clear_color_image(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    image: &Image,
    value: vk::ClearColorValue,
) {
    let all_layers = vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: vk::REMAINING_ARRAY_LAYERS,
    };
    // SAFETY: as `fill_buffer`, for the image.
    unsafe {
        ctx.device.cmd_clear_color_image(
            cmd,
            image.raw,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &value,
            &[all_layers],
        )
    };
}

/// Draws `vertices` vertices of one instance with the bound graphics
/// pipeline (vertex pulling: no vertex buffers).
pub fn draw(ctx: &Context, cmd: vk::CommandBuffer, vertices: u32) {
    // SAFETY: `cmd` is recording inside a rendering scope with a pipeline bound.
    unsafe { ctx.device.cmd_draw(cmd, vertices, 1, 0, 0) };
}

/// One indirect draw whose `VkDrawIndirectCommand` lies at `offset` in `args`.
pub fn draw_indirect(ctx: &Context, cmd: vk::CommandBuffer, args: &Buffer, offset: u64) {
    // SAFETY: as `draw`; `args` is alive.
    unsafe { ctx.device.cmd_draw_indirect(cmd, args.raw, offset, 1, 0) };
}
