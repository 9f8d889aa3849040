//! Frame orchestration: technique selection, tonemapping, profiling and
//! output, over the scene and targets of `crate::frame`. `render`, `bench`
//! and the demo run frames through here, with `vk::Frames` keeping N frames
//! in flight: `submit_frame` does not wait for the GPU, `finish` waits for
//! every frame in flight, and whatever a replaced technique, scene or set
//! of targets held is released after the fences of the frames that used it.

use crate::frame::{FrameTargets, SceneGpu};
use crate::params::{Apply, Params};
use crate::passes::accumulate::Accumulate;
use crate::passes::tonemap::Tonemap;
use crate::scene::Scene;
use crate::techniques::{self, Technique};
use crate::vk::{
    Context, FrameOptions, FrameRecorder, FrameSync, FrameTiming, Frames, Image, PassTiming,
    VkError, VkResult,
};
use anyhow::Context as _;
use std::sync::Arc;

/// What `Renderer::new` was making when it failed, as the error's context
/// (`anyhow::Error::downcast_ref::<Stage>()`), so a caller can name the
/// argument behind it: a device limit met by the scene, the image size or
/// the technique's parameters (the command line does).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The scene's geometry, materials, lights and textures on the device.
    Scene,
    /// The frame targets and the display image.
    Targets { width: u32, height: u32 },
    /// The technique's own resources.
    Technique,
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stage::Scene => write!(f, "the scene on the device"),
            Stage::Targets { width, height } => write!(f, "the {width}x{height} frame targets"),
            Stage::Technique => write!(f, "the technique's resources"),
        }
    }
}

pub struct Renderer {
    /// First, so it drops first: `Frames::drop` waits for the frames in
    /// flight before the scene, targets and technique they use go.
    pub frames: Frames,
    pub ctx: Arc<Context>,
    pub scene: Scene,
    pub scene_gpu: SceneGpu,
    pub targets: FrameTargets,
    pub tonemap: Tonemap,
    technique: Box<dyn Technique>,
    params: Params,
    frame_index: u32,
    /// Completed frames whose timings nobody has taken yet.
    completed: Vec<FrameTiming>,
    /// Counts technique rebuilds: a frame recorded by an older technique
    /// completes after its replacement, whose `after_frame` must not read
    /// its own (unwritten) read-backs for that frame.
    technique_generation: u64,
    /// The generation that recorded each slot's latest frame.
    slot_generation: Vec<u64>,
    /// Still-view accumulation, when on (`set_accumulation`).
    accumulate: Option<Accumulate>,
    /// The view the accumulated frames show and how many there are; None
    /// after anything changed that the next frame must not be averaged
    /// across (every mutator calls `restart_accumulation`).
    still: Option<(StillView, u32)>,
}

/// What a frame shows that callers may change between frames through the
/// renderer's public fields: the camera, the components drawn and, in an
/// animated scene, the time. Everything else goes through a method.
#[derive(Clone, Copy, PartialEq)]
struct StillView {
    camera: crate::scene::Camera,
    components: u32,
    animated_time: Option<u32>,
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
        let scene_gpu = SceneGpu::new(ctx, &scene, time).context(Stage::Scene)?;
        let (targets, tonemap) = Self::targets(ctx, width, height)?;
        let technique =
            techniques::create_named(ctx, technique, params, &scene, &scene_gpu, width, height)
                .context(Stage::Technique)?;
        Ok(Self {
            ctx: ctx.clone(),
            scene,
            scene_gpu,
            frames: Frames::new(ctx, FrameOptions::default())?,
            targets,
            tonemap,
            technique,
            params: params.clone(),
            frame_index: 0,
            completed: Vec::new(),
            technique_generation: 0,
            slot_generation: Vec::new(),
            accumulate: None,
            still: None,
        })
    }

    /// Still-view accumulation on or off (off by default). On, each frame
    /// of a view that has not changed since the last one is averaged with
    /// the frames before it (passes/accumulate.rs), and its stochastic
    /// passes draw new samples (`SceneGpu::still_frames`); a changed camera,
    /// time (in an animated scene), component, parameter, light, scene or
    /// size starts over. The demo, `bench` and `render --frames N` turn it on.
    pub fn set_accumulation(&mut self, on: bool) -> VkResult<()> {
        self.restart_accumulation();
        if !on {
            if let Some(old) = self.accumulate.take() {
                self.frames.defer_release(old);
            }
        } else if self.accumulate.is_none() {
            self.accumulate = Some(Accumulate::new(&self.ctx, &self.targets.radiance)?);
        }
        Ok(())
    }

    /// The next frame starts a new accumulation.
    fn restart_accumulation(&mut self) {
        self.still = None;
    }

    /// Still frames accumulated before the next one at `time` (0: a new
    /// view), and the view it shows.
    fn still_frames(&mut self, time: f32) -> u32 {
        let view = StillView {
            camera: self.scene.camera,
            components: self.scene_gpu.components,
            animated_time: self.scene.is_animated().then(|| time.to_bits()),
        };
        let frames = match self.still {
            Some((still, n)) if still == view && self.accumulate.is_some() => n,
            _ => 0,
        };
        self.still = Some((view, frames.saturating_add(1)));
        frames
    }

    /// Frames in flight and timing mode (waits for the frames in flight first).
    pub fn set_frame_options(&mut self, options: FrameOptions) -> VkResult<()> {
        self.finish()?;
        self.frames = Frames::new(&self.ctx, options)?;
        Ok(())
    }

    /// Rebuilds the frame targets, the tonemap and the technique at a new
    /// size (the demo's window resize). All three are built before any is
    /// replaced, so on an error the renderer keeps the old size whole; the
    /// old ones are released after the frames in flight that use them.
    /// A zero width or height (a minimised window) is refused: the caller
    /// skips such frames (the demo does) and the renderer keeps its size.
    pub fn resize(&mut self, width: u32, height: u32) -> anyhow::Result<()> {
        if width == 0 || height == 0 {
            anyhow::bail!("cannot render at {width}x{height}: nothing to draw (minimised)");
        }
        let (targets, tonemap) = Self::targets(&self.ctx, width, height)?;
        let technique = techniques::create_named(
            &self.ctx,
            self.technique.name(),
            &self.params,
            &self.scene,
            &self.scene_gpu,
            width,
            height,
        )?;
        let accumulate = match self.accumulate {
            Some(_) => Some(Accumulate::new(&self.ctx, &targets.radiance)?),
            None => None,
        };
        if let Some(old) = std::mem::replace(&mut self.accumulate, accumulate) {
            self.frames.defer_release(old);
        }
        self.replace_technique(technique);
        let old_tonemap = std::mem::replace(&mut self.tonemap, tonemap);
        self.frames.defer_release(old_tonemap);
        let old_targets = std::mem::replace(&mut self.targets, targets);
        self.frames.defer_release(old_targets);
        Ok(())
    }

    /// The frame targets and the tonemap's display image at a size.
    fn targets(
        ctx: &Arc<Context>,
        width: u32,
        height: u32,
    ) -> anyhow::Result<(FrameTargets, Tonemap)> {
        let stage = Stage::Targets { width, height };
        let targets = FrameTargets::new(ctx, width, height).context(stage)?;
        let tonemap = Tonemap::new(ctx, &targets.radiance).context(stage)?;
        Ok((targets, tonemap))
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
        self.replace_technique(technique);
        self.params = params.clone();
        Ok(())
    }

    /// Puts `technique` in place; the old one is released after the frames
    /// in flight, which it recorded (and whose read-backs only it knows).
    fn replace_technique(&mut self, technique: Box<dyn Technique>) {
        let old = std::mem::replace(&mut self.technique, technique);
        self.frames.defer_release(old);
        self.technique_generation += 1;
        self.restart_accumulation();
    }

    /// Frames have completed: hands each one's read-backs to the technique
    /// that recorded it, if that is still the current one, and keeps their
    /// timings, all of them even when an `after_frame` fails (its first
    /// error is returned; the timings were read already and stay for
    /// `take_timings`). (Fields, not `&mut self`: a frame recorder may hold
    /// `frames`.)
    fn frames_done(
        technique: &mut dyn Technique,
        generation: u64,
        slot_generation: &[u64],
        completed: &mut Vec<FrameTiming>,
        done: Vec<FrameTiming>,
    ) -> VkResult<()> {
        let mut first_error = None;
        for done in done {
            if slot_generation.get(done.slot) == Some(&generation) {
                if let Err(e) = technique.after_frame(done.slot) {
                    first_error.get_or_insert(e);
                }
            }
            completed.push(done);
        }
        first_error.map_or(Ok(()), Err)
    }

    /// New parameter values for the current technique. When every changed
    /// parameter is live (`params::Apply::Live`) and the technique takes
    /// them in place (`TechniqueBuild::update_live`), nothing is rebuilt;
    /// otherwise the technique is rebuilt (keeping the current one on
    /// error; the old one is released after the frames in flight). Returns
    /// whether it was rebuilt. Live values are read at record time, so
    /// frames in flight keep theirs.
    pub fn set_params(&mut self, params: &Params) -> anyhow::Result<bool> {
        let live = self
            .params
            .changed(params)
            .iter()
            .all(|s| s.apply == Apply::Live);
        if live && (self.technique_info().update_live)(self.technique.as_mut(), params)? {
            self.params = params.clone();
            self.restart_accumulation();
            return Ok(false);
        }
        self.set_technique(self.technique.name(), params)?;
        Ok(true)
    }

    /// Replaces the scene (reload from disk, or a light moved): re-uploads it
    /// and rebuilds the technique, whose resources (shadow maps) depend on
    /// the lights. On error the old scene stays; the old one is released
    /// after the frames in flight.
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
        self.replace_technique(technique);
        let old = std::mem::replace(&mut self.scene_gpu, scene_gpu);
        self.frames.defer_release(old);
        self.scene = scene;
        Ok(())
    }

    /// `scene.lights` were edited in place (the demo moves a light): updates
    /// the GPU copy and the technique, rebuilding the technique only if it
    /// cannot take the change. Waits for the frames in flight (they read
    /// the lights buffer this rewrites); a user's edit, not every frame.
    pub fn lights_changed(&mut self, time: f32) -> anyhow::Result<()> {
        self.finish()?;
        self.restart_accumulation();
        if self.technique.set_lights(&self.scene.lights) {
            self.scene_gpu.update_lights(&self.scene)?;
            Ok(())
        } else {
            let scene = self.scene.clone();
            self.set_scene(scene, time)
        }
    }

    /// Turns the environment to `rotate_deg` degrees about +y (the demo's
    /// live rotation), with the result of loading the scene with that
    /// `rotate`: the scene (a sky's sun direction), the environment's
    /// constants on the GPU (what the camera sees, the reference's and
    /// pinhole's lookups, the sun found in an image), the lights (the sun's
    /// directional stand-in) and the technique: updated in place where it
    /// can (`Technique::environment_changed`: `direct`'s SH are projected
    /// again on the GPU next frame), else rebuilt for the new scene. Waits
    /// for the frames in flight, which read the constants. An error when
    /// the scene has no environment; when the rebuild fails, the old
    /// rotation is restored.
    pub fn set_environment_rotation(&mut self, rotate_deg: f32) -> anyhow::Result<()> {
        anyhow::ensure!(
            rotate_deg.is_finite(),
            "environment rotation must be finite, got {rotate_deg}"
        );
        let Some(old) = self.scene.environment.as_ref().map(|e| e.rotate_deg) else {
            anyhow::bail!("the scene has no environment to rotate");
        };
        self.finish()?;
        self.restart_accumulation();
        self.scene.set_environment_rotation(rotate_deg);
        self.scene_gpu.update_environment(&self.scene)?;
        if !self.technique.environment_changed() {
            let params = self.params.clone();
            if let Err(e) = self.set_technique(self.technique.name(), &params) {
                // The current technique stays, with the old rotation.
                self.scene.set_environment_rotation(old);
                self.scene_gpu.update_environment(&self.scene)?;
                return Err(e);
            }
        }
        Ok(())
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

    /// `scene.medium` was edited in place (same density kind): re-uploads
    /// it, after the frames in flight that read it. A medium with
    /// `multiple_scattering` rebuilds the technique too: its airlight pass
    /// placed its virtual lights with the old coefficients.
    pub fn medium_changed(&mut self) -> anyhow::Result<()> {
        self.finish()?;
        self.restart_accumulation();
        self.scene_gpu.update_medium(&self.scene)?;
        if self
            .scene
            .medium
            .as_ref()
            .is_some_and(|m| m.multiple_scattering)
        {
            let params = self.params.clone();
            self.set_technique(self.technique.name(), &params)?;
        }
        Ok(())
    }

    /// Records and submits one frame at animation time `time` without
    /// waiting for it. `present` records what follows the tonemap into the
    /// same command buffer (the demo's blit to the swapchain) and names the
    /// semaphores the submission waits on and signals. Timings of frames
    /// that completed meanwhile are kept for `take_timings`.
    pub fn submit_frame_with<E: From<VkError>>(
        &mut self,
        time: f32,
        present: impl FnOnce(&mut FrameRecorder, &Image) -> Result<FrameSync, E>,
    ) -> Result<(), E> {
        let still_frames = self.still_frames(time);
        self.scene_gpu.still_frames = still_frames;
        let (mut rec, done) = self.frames.begin_frame()?;
        let slot = rec.slot();
        // Their fences have signalled: their read-backs are current.
        Self::frames_done(
            &mut *self.technique,
            self.technique_generation,
            &self.slot_generation,
            &mut self.completed,
            done,
        )?;
        if self.slot_generation.len() <= slot {
            self.slot_generation.resize(slot + 1, u64::MAX);
        }
        self.slot_generation[slot] = self.technique_generation;
        if self.scene.is_animated() {
            self.scene_gpu.update_geometry(&mut rec, &self.scene, time);
        }
        let size = (self.targets.width, self.targets.height);
        self.scene_gpu
            .upload_frame(&mut rec, &self.scene, size, time, self.frame_index);
        self.frame_index = self.frame_index.wrapping_add(1);
        let recorded = self
            .technique
            .record(&mut rec, &self.scene_gpu, &self.targets)
            .map(|()| {
                if let Some(accumulate) = &self.accumulate {
                    accumulate.record(&mut rec, &self.targets.radiance, still_frames);
                }
                self.tonemap
                    .record(&mut rec, &self.targets.radiance, self.scene.output.exposure)
            });
        let sync = match recorded {
            Ok(()) => present(&mut rec, &self.tonemap.display),
            Err(e) => Err(E::from(e)),
        };
        // Submitted even after an error: the slot's fence must signal.
        let none = FrameSync::default();
        let submitted = rec.submit(sync.as_ref().unwrap_or(&none));
        sync?;
        Ok(submitted?)
    }

    /// `submit_frame_with` for headless frames.
    pub fn submit_frame(&mut self, time: f32) -> VkResult<()> {
        self.submit_frame_with(time, |_, _| Ok(FrameSync::default()))
    }

    /// Waits for every frame in flight; returns the timings of all frames
    /// completed since the last `take_timings`, oldest first.
    pub fn finish(&mut self) -> VkResult<Vec<FrameTiming>> {
        let done = self.frames.wait_all()?;
        Self::frames_done(
            &mut *self.technique,
            self.technique_generation,
            &self.slot_generation,
            &mut self.completed,
            done,
        )?;
        Ok(self.take_timings())
    }

    /// Timings of the frames completed so far and not yet taken, oldest first.
    pub fn take_timings(&mut self) -> Vec<FrameTiming> {
        std::mem::take(&mut self.completed)
    }

    /// Renders one frame at animation time `time` and waits for it (and any
    /// other frame in flight); returns each pass's time.
    pub fn render_frame(&mut self, time: f32) -> VkResult<Vec<PassTiming>> {
        self.submit_frame(time)?;
        Ok(self.finish()?.pop().map(|t| t.passes).unwrap_or_default())
    }

    /// The technique's counts of the last frame (`Technique::counters`).
    pub fn technique_counters(&self) -> Vec<(&'static str, u64)> {
        self.technique.counters()
    }

    /// The last frame's radiance, RGBA f32 per pixel, rows top to bottom
    /// (the copy is queued after the frames in flight and ordered after them).
    pub fn radiance(&self) -> VkResult<Vec<f32>> {
        self.targets.radiance.download_rgba32f()
    }

    /// The last frame tonemapped to 8-bit sRGB RGBA.
    pub fn display(&self) -> VkResult<Vec<u8>> {
        self.tonemap.display.download_bytes(4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A technique whose `after_frame` fails for one slot.
    struct FailsIn(usize, Vec<usize>);

    impl Technique for FailsIn {
        fn name(&self) -> &'static str {
            "fails_in"
        }
        fn record(
            &mut self,
            _: &mut FrameRecorder,
            _: &SceneGpu,
            _: &FrameTargets,
        ) -> VkResult<()> {
            Ok(())
        }
        fn after_frame(&mut self, slot: usize) -> VkResult<()> {
            self.1.push(slot);
            if slot == self.0 {
                return Err(VkError::DeviceLost);
            }
            Ok(())
        }
    }

    fn timing(slot: usize) -> FrameTiming {
        FrameTiming {
            slot,
            passes: vec![PassTiming {
                name: format!("pass {slot}"),
                ms: slot as f64,
            }],
            submit_to_done_ms: 1.0,
        }
    }

    /// Issue 18: an error from `after_frame` keeps every completed frame's
    /// timings (they were read already) and still hands the later frames to
    /// the technique; the first error is returned.
    #[test]
    fn after_frame_errors_keep_the_timings() {
        let mut technique = FailsIn(1, Vec::new());
        let mut completed = Vec::new();
        let done = (0..3).map(timing).collect();
        let result = Renderer::frames_done(&mut technique, 7, &[7, 7, 7], &mut completed, done);
        assert!(matches!(result, Err(VkError::DeviceLost)));
        assert_eq!(technique.1, vec![0, 1, 2]);
        let slots: Vec<usize> = completed.iter().map(|t| t.slot).collect();
        assert_eq!(slots, vec![0, 1, 2]);
    }
}
