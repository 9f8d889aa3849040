//! Still-view accumulation (glsl/passes/accumulate.comp): the running mean
//! of the frames since the view last changed, kept in a history image the
//! size of the frame and written back into the frame's radiance. The
//! renderer decides when a view is still (`Renderer::set_accumulation`).

use super::image_compute::ImageCompute;
use crate::vk::{groups_8x8, Access, Context, FrameRecorder, Image, ImageDesc, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct Accumulate {
    pass: ImageCompute,
    history: Image,
}

impl Accumulate {
    /// A history for frames the size of `radiance`.
    pub fn new(ctx: &Arc<Context>, radiance: &Image) -> VkResult<Self> {
        let pass = ImageCompute::new(ctx, "passes/accumulate.comp", 4)?;
        let history = Image::new(
            ctx,
            "accumulated radiance",
            ImageDesc::new_2d(
                radiance.desc.width,
                radiance.desc.height,
                vk::Format::R32G32B32A32_SFLOAT,
                vk::ImageUsageFlags::STORAGE,
            ),
        )?;
        Ok(Self { pass, history })
    }

    /// Folds this frame's `radiance` into the history, which holds `frames`
    /// earlier frames of the same view (0: restart from this frame), and
    /// writes the mean back into `radiance`.
    pub fn record(&self, rec: &mut FrameRecorder, radiance: &Image, frames: u32) {
        let set = &self.pass.set;
        rec.pass("accumulate")
            .storage_image(set, 0, radiance, Access::ComputeWrite)
            .storage_image(set, 1, &self.history, Access::ComputeWrite)
            .record(|c| {
                let groups = groups_8x8(radiance.desc.width, radiance.desc.height);
                c.dispatch(
                    &self.pass.pipeline,
                    &[set],
                    bytemuck::bytes_of(&frames),
                    groups,
                );
            });
    }
}
