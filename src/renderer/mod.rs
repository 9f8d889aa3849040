//! Frame orchestration: scene upload, technique selection, tonemapping,
//! profiling and output. `render` and `bench` run frames through here.

mod scene_gpu;

pub use scene_gpu::{camera_matrices, GeometryStats, SceneGpu};

use crate::passes::tonemap::Tonemap;
use crate::scene::Scene;
use crate::techniques::{self, Params, Technique};
use crate::vk::{Context, Image, ImageDesc, PassTiming, Profiler, VkResult};
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

pub struct Renderer {
    pub ctx: Arc<Context>,
    pub scene: Scene,
    pub scene_gpu: SceneGpu,
    pub profiler: Profiler,
    pub targets: FrameTargets,
    pub tonemap: Tonemap,
    technique: Box<dyn Technique>,
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
            techniques::create(ctx, technique, params, &scene, &scene_gpu, width, height)?;
        Ok(Self {
            ctx: ctx.clone(),
            scene,
            scene_gpu,
            profiler: Profiler::new(ctx, 64)?,
            targets,
            tonemap,
            technique,
            frame_index: 0,
        })
    }

    pub fn technique_name(&self) -> &'static str {
        self.technique.name()
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
        self.profiler.frame(|rec| {
            technique.record(rec, scene_gpu, targets)?;
            tonemap.record(rec, &targets.radiance, exposure);
            Ok(())
        })
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
