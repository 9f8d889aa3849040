//! Frame orchestration: technique selection, tonemapping, profiling and
//! output, over the scene and targets of `crate::frame`. `render` and `bench` run frames through here.

use crate::frame::{FrameTargets, SceneGpu};
use crate::params::{Apply, Params};
use crate::passes::tonemap::Tonemap;
use crate::scene::Scene;
use crate::techniques::{self, Technique};
use crate::vk::{Context, PassTiming, Profiler, VkResult};
use std::sync::Arc;

pub struct Renderer {
    pub ctx: Arc<Context>,
    pub scene: Scene,
    pub scene_gpu: SceneGpu,
    pub profiler: Profiler,
    pub targets: FrameTargets,
    pub tonemap: Tonemap,
    technique: Box<dyn Technique>,
    params: Params,
    frame_index: u32,
}

impl Renderer {
    pub fn new(
        ctx: &Arc<Context>,
        scene: Scene,
        technique: &str,
        params: &Params,
        width: u32,
        height: u32,
        time: f32,
    ) -> anyhow::Result<Self> {
        let scene_gpu = SceneGpu::new(ctx, &scene, time)?;
        let targets = FrameTargets::new(ctx, width, height)?;
        let tonemap = Tonemap::new(ctx, &targets.radiance)?;
        let technique =
            techniques::create_named(ctx, technique, params, &scene, &scene_gpu, width, height)?;
        Ok(Self {
            ctx: ctx.clone(),
            scene,
            scene_gpu,
            profiler: Profiler::new(ctx, 64)?,
            targets,
            tonemap,
            technique,
            params: params.clone(),
            frame_index: 0,
        })
    }

    /// Rebuilds the frame targets, the tonemap and the technique at a new
    /// size (the demo's window resize). The caller has waited for every frame
    /// that used the old ones.
    pub fn resize(&mut self, width: u32, height: u32) -> anyhow::Result<()> {
        let name = self.technique.name();
        // Drop the old technique and targets before making the new ones, so
        // peak memory holds one set.
        self.technique = Box::new(NoTechnique);
        let targets = FrameTargets::new(&self.ctx, width, height)?;
        let tonemap = Tonemap::new(&self.ctx, &targets.radiance)?;
        self.tonemap = tonemap;
        self.targets = targets;
        self.set_technique(name, &self.params.clone())
    }

    /// Switches to technique `name` with `params` (keeps the current one on error).
    pub fn set_technique(&mut self, name: &str, params: &Params) -> anyhow::Result<()> {
        let technique = techniques::create_named(
            &self.ctx,
            name,
            params,
            &self.scene,
            &self.scene_gpu,
            self.targets.width,
            self.targets.height,
        )?;
        self.technique = technique;
        self.params = params.clone();
        Ok(())
    }

    /// New parameter values for the current technique. When every changed
    /// parameter is live (`params::Apply::Live`) and the technique takes
    /// them in place (`Technique::update_live`), nothing is rebuilt;
    /// otherwise the technique is rebuilt (keeping the current one on
    /// error). Returns whether it was rebuilt. The caller has waited for
    /// every frame in flight.
    pub fn set_params(&mut self, params: &Params) -> anyhow::Result<bool> {
        let specs = self.technique_info().params();
        let live = self.params.changed(params).all(|name| {
            specs
                .iter()
                .any(|s| s.name == name && s.apply == Apply::Live)
        });
        if live && self.technique.update_live(params)? {
            self.params = params.clone();
            return Ok(false);
        }
        self.set_technique(self.technique.name(), params)?;
        Ok(true)
    }

    /// Replaces the scene (reload from disk, or a light moved): re-uploads it
    /// and rebuilds the technique, whose resources (shadow maps) depend on
    /// the lights. On error the old scene stays. The caller has waited for
    /// every frame that used the old scene.
    pub fn set_scene(&mut self, scene: Scene, time: f32) -> anyhow::Result<()> {
        let mut scene_gpu = SceneGpu::new(&self.ctx, &scene, time)?;
        scene_gpu.components = self.scene_gpu.components;
        let technique = techniques::create_named(
            &self.ctx,
            self.technique.name(),
            &self.params,
            &scene,
            &scene_gpu,
            self.targets.width,
            self.targets.height,
        )?;
        self.technique = technique;
        self.scene_gpu = scene_gpu;
        self.scene = scene;
        Ok(())
    }

    /// `scene.lights` were edited in place (the demo moves a light): updates
    /// the GPU copy and the technique, rebuilding the technique only if it
    /// cannot take the change. The caller has waited for every frame in flight.
    pub fn lights_changed(&mut self, time: f32) -> anyhow::Result<()> {
        if self.technique.set_lights(&self.scene.lights) {
            self.scene_gpu.update_lights(&self.scene)?;
            Ok(())
        } else {
            let scene = self.scene.clone();
            self.set_scene(scene, time)
        }
    }

    pub fn params(&self) -> &Params {
        &self.params
    }

    pub fn technique_name(&self) -> &'static str {
        self.technique.name()
    }

    pub fn technique_info(&self) -> &'static techniques::TechniqueInfo {
        techniques::find(self.technique.name()).expect("a built technique is listed")
    }

    /// Renders one frame at animation time `time` and waits for it; returns
    /// each pass's time.
    pub fn render_frame(&mut self, time: f32) -> VkResult<Vec<PassTiming>> {
        if self.scene.is_animated() {
            self.scene_gpu.update_geometry(&self.scene, time)?;
        }
        self.scene_gpu.update_frame(
            &self.scene,
            self.targets.width,
            self.targets.height,
            time,
            self.frame_index,
        )?;
        self.frame_index = self.frame_index.wrapping_add(1);
        let technique = &mut self.technique;
        let scene_gpu = &self.scene_gpu;
        let targets = &self.targets;
        let tonemap = &self.tonemap;
        let exposure = self.scene.output.exposure;
        let timings = self.profiler.frame(|rec| {
            technique.record(rec, scene_gpu, targets)?;
            tonemap.record(rec, &targets.radiance, exposure);
            Ok(())
        })?;
        // The frame has completed: the technique's read-backs are current.
        self.technique.after_frame()?;
        Ok(timings)
    }

    /// The technique's counts of the last frame (`Technique::counters`).
    pub fn technique_counters(&self) -> Vec<(&'static str, u64)> {
        self.technique.counters()
    }

    /// The last frame's radiance, RGBA f32 per pixel, rows top to bottom.
    pub fn radiance(&self) -> VkResult<Vec<f32>> {
        self.targets.radiance.download_rgba32f()
    }

    /// The last frame tonemapped to 8-bit sRGB RGBA.
    pub fn display(&self) -> VkResult<Vec<u8>> {
        self.tonemap.display.download_bytes(4)
    }
}

/// Stands in for a technique while `resize` rebuilds the real one.
struct NoTechnique;

impl Technique for NoTechnique {
    fn name(&self) -> &'static str {
        "none"
    }
    fn record(
        &mut self,
        _rec: &mut crate::vk::FrameRecorder,
        _scene: &SceneGpu,
        _targets: &FrameTargets,
    ) -> VkResult<()> {
        Ok(())
    }
}
