//! Tonemap: the frame's linear radiance to 8-bit sRGB for PNG and display.

use super::image_compute::ImageCompute;
use crate::vk::{groups_8x8, Access, Context, FrameRecorder, Image, ImageDesc, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct Tonemap {
    pass: ImageCompute,
    pub display: Image,
}

impl Tonemap {
    pub fn new(ctx: &Arc<Context>, radiance: &Image) -> VkResult<Self> {
        let pass = ImageCompute::new(ctx, "passes/tonemap.comp", 4)?;
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
        Ok(Self { pass, display })
    }

    pub fn record(&self, rec: &mut FrameRecorder, radiance: &Image, exposure: f32) {
        let set = &self.pass.set;
        rec.pass("tonemap")
            .storage_image(set, 0, radiance, Access::ComputeRead)
            .overwrite_storage_image(set, 1, &self.display, Access::ComputeWrite)
            .record(|c| {
                let groups = groups_8x8(radiance.desc.width, radiance.desc.height);
                c.dispatch(
                    &self.pass.pipeline,
                    &[set],
                    bytemuck::bytes_of(&exposure),
                    groups,
                );
            });
    }
}
