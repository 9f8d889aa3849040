//! TEMPORARY: replaced by the direct technique (G-buffer, shadow maps, lighting).
use super::{ParamSpec, Params, Technique};
use crate::renderer::{FrameTargets, SceneGpu};
use crate::scene::Scene;
use crate::vk::{Context, FrameRecorder, VkResult};
use std::sync::Arc;
pub const PARAMS: &[ParamSpec] = &[];
pub struct Direct;
impl Direct {
    pub fn new(
        _: &Arc<Context>,
        _: &Params,
        _: &Scene,
        _: &SceneGpu,
        _: u32,
        _: u32,
    ) -> VkResult<Self> {
        Ok(Direct)
    }
}
impl Technique for Direct {
    fn name(&self) -> &'static str {
        "direct"
    }
    fn record(&mut self, _: &mut FrameRecorder, _: &SceneGpu, _: &FrameTargets) -> VkResult<()> {
        Ok(())
    }
}
