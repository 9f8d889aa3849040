//! The images a frame renders into.

use crate::vk::{Context, Image, ImageDesc, VkResult};
use ash::vk;
use std::sync::Arc;

/// The images a technique renders into.
pub struct FrameTargets {
    /// Linear radiance, W m^-2 sr^-1 per channel (RGBA32F: storage, sampled, colour attachment).
    pub radiance: Image,
    pub width: u32,
    pub height: u32,
}

impl FrameTargets {
    pub fn new(ctx: &Arc<Context>, width: u32, height: u32) -> VkResult<Self> {
        let radiance = Image::new(
            ctx,
            "radiance",
            ImageDesc::new_2d(
                width,
                height,
                vk::Format::R32G32B32A32_SFLOAT,
                vk::ImageUsageFlags::STORAGE
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::COLOR_ATTACHMENT,
            ),
        )?;
        Ok(Self {
            radiance,
            width,
            height,
        })
    }
}
