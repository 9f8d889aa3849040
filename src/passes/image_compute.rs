//! A compute pass over storage images only (the tonemap, the still-view
//! accumulation): its layout of `images` storage images at bindings
//! 0..images, its pipeline and one set.

use crate::vk::{
    BindingKind, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout, VkResult,
};
use std::sync::Arc;

pub struct ImageCompute {
    pub pipeline: ComputePipeline,
    _layout: DescriptorSetLayout,
    pub set: DescriptorSet,
}

impl ImageCompute {
    pub fn new(ctx: &Arc<Context>, shader: &str, images: u32, push_size: u32) -> VkResult<Self> {
        let bindings: Vec<_> = (0..images)
            .map(|b| (b, BindingKind::StorageImage))
            .collect();
        let layout = DescriptorSetLayout::new(ctx, &bindings)?;
        let pipeline = ComputePipeline::new(ctx, shader, &[&layout], push_size)?;
        let set = DescriptorSet::new(ctx, &layout)?;
        Ok(Self {
            pipeline,
            _layout: layout,
            set,
        })
    }
}
