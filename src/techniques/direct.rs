//! `direct`: direct light with shadow maps (`passes::direct_light`) alone,
//! the base frame every technique adds to; the ground truth's L D
//! component for diffuse surfaces seen directly.

use super::{CausticSources, Technique, TechniqueBuild};
use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::direct_light::DirectLight;
pub use crate::passes::direct_light::DirectParams;
use crate::radiometry::Component;
use crate::scene::Scene;
use crate::vk::{Context, FrameRecorder, VkResult};
use std::sync::Arc;

pub struct Direct {
    pub light: DirectLight,
}

impl TechniqueBuild for Direct {
    const NAME: &'static str = "direct";
    const DESCRIPTION: &'static str =
        "direct light with shadow maps (the base frame every technique adds to)";
    const COMPONENTS: &'static [Component] = &[Component::Direct, Component::Emitted];
    const CAUSTIC_SOURCES: CausticSources = CausticSources::None;
    type Params = DirectParams;

    fn build(
        ctx: &Arc<Context>,
        params: &DirectParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        Ok(Self {
            light: DirectLight::new(ctx, params, scene, scene_gpu, width, height)?,
        })
    }

    fn update_live(&mut self, params: &DirectParams) -> bool {
        self.light.set_live(params);
        true
    }
}

impl Technique for Direct {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) -> VkResult<()> {
        self.light.record(rec, scene, targets)
    }

    fn set_lights(&mut self, lights: &[crate::scene::Light]) -> bool {
        self.light.set_lights(lights)
    }

    /// Its shadow maps hold the scene's own lights; the sun and the sky
    /// come from the environment's constants and SH.
    fn environment_changed(&mut self) -> bool {
        self.light.environment_changed();
        true
    }
}
