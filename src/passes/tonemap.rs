//! Tonemap: the frame's linear radiance to 8-bit sRGB for PNG and display.

use crate::vk::{
    barrier, Access, BindingKind, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    FrameRecorder, Image, ImageAccess, ImageDesc, VkResult,
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
        set.write_storage_image(0, radiance)
            .write_storage_image(1, &display);
        Ok(Self {
            pipeline,
            _layout: layout,
            set,
            display,
        })
    }

    pub fn record(&self, rec: &mut FrameRecorder, radiance: &Image, exposure: f32) {
        let ctx = rec.ctx().clone();
        rec.pass("tonemap", |cmd| {
            barrier(
                &ctx,
                cmd,
                &[
                    ImageAccess::new(radiance, Access::ComputeRead),
                    ImageAccess::discard(&self.display, Access::ComputeWrite),
                ],
                &[],
            );
            let groups = [
                radiance.desc.width.div_ceil(8),
                radiance.desc.height.div_ceil(8),
                1,
            ];
            self.pipeline
                .dispatch(cmd, &[&self.set], bytemuck::bytes_of(&exposure), groups);
        });
    }
}
