//! A compute pass over storage images only (the tonemap, the still-view
//! accumulation): its layout (set 0, what its shader uses), its pipeline
//! and one set.

use crate::vk::{ComputePipeline, Context, DescriptorSet, DescriptorSetLayout, VkResult};
use std::sync::Arc;

pub struct ImageCompute {
    pub pipeline: ComputePipeline,
    _layout: DescriptorSetLayout,
    pub set: DescriptorSet,
}

impl ImageCompute {
    pub fn new(ctx: &Arc<Context>, shader: &str, push_size: u32) -> VkResult<Self> {
        let layout = DescriptorSetLayout::of_shaders(ctx, 0, &[shader])?;
        let pipeline = ComputePipeline::new(ctx, shader, &[&layout], push_size)?;
        let set = DescriptorSet::new(ctx, &layout)?;
        Ok(Self {
            pipeline,
            _layout: layout,
            set,
        })
    }
}
