//! Still-view accumulation (glsl/passes/accumulate.comp): the running mean
//! of the frames since the view last changed, kept in a history image the
//! size of the frame and written back into the frame's radiance. The
//! renderer decides when a view is still (`Renderer::set_accumulation`).

use crate::vk::{
    groups_8x8, Access, BindingKind, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    FrameRecorder, Image, ImageDesc, VkResult,
};
use ash::vk;
use std::sync::Arc;

pub struct Accumulate {
    pipeline: ComputePipeline,
    _layout: DescriptorSetLayout,
    set: DescriptorSet,
    history: Image,
}

impl Accumulate {
    /// A history for frames the size of `radiance`.
    pub fn new(ctx: &Arc<Context>, radiance: &Image) -> VkResult<Self> {
        let layout = DescriptorSetLayout::new(
            ctx,
            &[
                (0, BindingKind::StorageImage),
                (1, BindingKind::StorageImage),
            ],
        )?;
        let pipeline = ComputePipeline::new(ctx, "passes/accumulate.comp", &[&layout], 4)?;
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
        let set = DescriptorSet::new(ctx, &layout)?;
        Ok(Self {
            pipeline,
            _layout: layout,
            set,
            history,
        })
    }

    /// Folds this frame's `radiance` into the history, which holds `frames`
    /// earlier frames of the same view (0: restart from this frame), and
    /// writes the mean back into `radiance`.
    pub fn record(&self, rec: &mut FrameRecorder, radiance: &Image, frames: u32) {
        rec.pass("accumulate")
            .storage_image(&self.set, 0, radiance, Access::ComputeWrite)
            .storage_image(&self.set, 1, &self.history, Access::ComputeWrite)
            .record(|cmd| {
                let groups = groups_8x8(radiance.desc.width, radiance.desc.height);
                self.pipeline
                    .dispatch(cmd, &[&self.set], bytemuck::bytes_of(&frames), groups);
            });
    }
}
