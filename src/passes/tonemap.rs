//! Tonemap: the frame's linear radiance to 8-bit sRGB for PNG and display.

use crate::vk::{
    groups_8x8, Access, BindingKind, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    FrameRecorder, Image, ImageDesc, VkResult,
};
use ash::vk;
use std::sync::Arc;

pub struct Tonemap {
    pipeline: ComputePipeline,
    _layout: DescriptorSetLayout,
    set: DescriptorSet,
    pub display: Image,
}

impl Tonemap {
    pub fn new(ctx: &Arc<Context>, radiance: &Image) -> VkResult<Self> {
        let layout = DescriptorSetLayout::new(
            ctx,
            &[
                (0, BindingKind::StorageImage),
                (1, BindingKind::StorageImage),
            ],
        )?;
        let pipeline = ComputePipeline::new(ctx, "passes/tonemap.comp", &[&layout], 4)?;
        let display = Image::new(
            ctx,
            "display (sRGB 8-bit)",
            ImageDesc::new_2d(
                radiance.desc.width,
                radiance.desc.height,
                vk::Format::R8G8B8A8_UNORM,
                vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED,
            ),
        )?;
        let set = DescriptorSet::new(ctx, &layout)?;
        Ok(Self {
            pipeline,
            _layout: layout,
            set,
            display,
        })
    }

    pub fn record(&self, rec: &mut FrameRecorder, radiance: &Image, exposure: f32) {
        rec.pass("tonemap")
            .storage_image(&self.set, 0, radiance, Access::ComputeRead)
            .overwrite_storage_image(&self.set, 1, &self.display, Access::ComputeWrite)
            .record(|cmd| {
                let groups = groups_8x8(radiance.desc.width, radiance.desc.height);
                self.pipeline
                    .dispatch(cmd, &[&self.set], bytemuck::bytes_of(&exposure), groups);
            });
    }
}
