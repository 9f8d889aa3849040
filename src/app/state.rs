//! The open window's state and its frame: recreate the swapchain, render,
//! blit, overlay, present, and the once-a-second report.

use super::camera::OrbitCamera;
use super::compare::{Compare, View, ViewKey};
use super::overlay::{Action, MediumValues, Overlay, UiData};
use super::slots::ImageSemaphores;
use crate::renderer::Renderer;
use crate::vk::{Access, Acquired, Context, FrameSync, PassTiming, Surface, Swapchain};
use ash::vk;
use std::collections::{HashSet, VecDeque};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::keyboard::KeyCode;
use winit::window::Window;

#[derive(Default)]
pub(super) struct Input {
    pub(super) keys: HashSet<KeyCode>,
    pub(super) left: bool,
    pub(super) right: bool,
    pub(super) cursor: Option<(f64, f64)>,
}

/// Everything that lives while the window is open. Fields drop in this
/// order: semaphores, swapchain, renderer (with its frame slots), surface,
/// window (the surface must go before the window it was made from).
pub(super) struct State {
    pub(super) finished: ImageSemaphores,
    /// Made with the first swapchain (it needs the swapchain's format).
    pub(super) overlay: Option<Overlay>,
    pub(super) swapchain: Option<Swapchain>,
    pub(super) renderer: Renderer,
    pub(super) surface: Surface,
    pub(super) window: Window,
    pub(super) camera: OrbitCamera,
    pub(super) input: Input,
    pub(super) time: f32,
    pub(super) paused: bool,
    pub(super) last: Instant,
    pub(super) presented: u32,
    /// The swapchain no longer matches the window (resize, out of date).
    pub(super) stale: bool,
    /// A light moved or its intensity changed: the lights are re-uploaded
    /// before the next frame.
    pub(super) lights_changed: bool,
    /// The medium's coefficients changed: re-uploaded before the next frame.
    pub(super) medium_changed: bool,
    pub(super) timings: Vec<Vec<PassTiming>>,
    pub(super) frame_ms: Vec<f64>,
    /// The last frame's per-pass timings and recent frame intervals (overlay).
    pub(super) last_timings: Vec<PassTiming>,
    pub(super) history_ms: VecDeque<f32>,
    pub(super) report_at: Instant,
    /// When the frames being averaged for the next report began.
    pub(super) report_from: Instant,
    /// `Frames::host_wait` at `report_from`.
    pub(super) waited_from: Duration,
    /// Host time in vkAcquireNextImageKHR and vkQueuePresentKHR since
    /// `report_from` (a software presentation engine may wait there for
    /// the frame's rendering).
    pub(super) swapchain_wait: Duration,
    pub(super) screenshots: u32,
    /// The compare panel: reference snapshot and the view shown.
    pub(super) compare: Compare,
    /// Counts scene edits (lights, medium, environment, reload): a change
    /// discards the compare snapshot.
    pub(super) scene_edits: u64,
    /// `--compare-test N`: a scripted snapshot of N reference passes that
    /// switches the three views (tests); None for interactive runs.
    pub(super) compare_script: Option<u32>,
    /// `--allow-paths`, for reloads.
    pub(super) allowed: crate::scene::AllowedPaths,
}

impl State {
    pub(super) fn ctx(&self) -> &Arc<Context> {
        &self.renderer.ctx
    }

    /// Recreates the swapchain, the per-image semaphores and the renderer's
    /// frame targets at the window's size. A zero-size (minimised) window
    /// keeps no swapchain and renders nothing until it is restored.
    ///
    /// Waits for the device: the old swapchain's images, the old display
    /// image and the old semaphores may still be used by queued submissions
    /// and presents. This happens once per resize, not per frame.
    pub(super) fn recreate(&mut self, mode: vk::PresentModeKHR) -> anyhow::Result<()> {
        let size = self.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(());
        }
        if self
            .surface
            .current_extent()?
            .is_some_and(|e| e.width == 0 || e.height == 0)
        {
            // The window reports a size but the surface is already (or
            // still) zero-sized: stay stale and try again next frame.
            return Ok(());
        }
        self.ctx().wait_idle();
        let ctx = self.ctx().clone();
        let wanted = vk::Extent2D {
            width: size.width,
            height: size.height,
        };
        let new = Swapchain::new(&ctx, &self.surface, wanted, mode, self.swapchain.as_ref())?;
        // The old swapchain is retired by the new one's creation; drop it now.
        self.swapchain = None;
        self.finished = ImageSemaphores::new(&ctx, new.images.len())?;
        let extent = new.extent;
        println!(
            "swapchain: {}x{}, {} images, {:?}, {:?}",
            extent.width,
            extent.height,
            new.images.len(),
            new.format,
            new.present_mode
        );
        self.swapchain = Some(new);
        if extent.width > 0
            && extent.height > 0
            && (extent.width, extent.height)
                != (self.renderer.targets.width, self.renderer.targets.height)
        {
            self.renderer.resize(extent.width, extent.height)?;
        }
        self.stale = false;
        Ok(())
    }

    pub(super) fn minimised(&self) -> bool {
        let s = self.window.inner_size();
        s.width == 0 || s.height == 0
    }

    /// One frame; returns false when nothing was presented.
    pub(super) fn draw(&mut self, mode: vk::PresentModeKHR) -> anyhow::Result<bool> {
        if self.minimised() {
            return Ok(false);
        }
        if self.stale || self.swapchain.is_none() {
            self.recreate(mode)?;
            if self.stale || self.swapchain.is_none() {
                return Ok(false);
            }
        }
        let now = Instant::now();
        let dt = (now - self.last).as_secs_f32().min(0.25);
        self.last = now;
        if self.history_ms.len() >= 240 {
            self.history_ms.pop_front();
        }
        self.history_ms.push_back(dt * 1e3);
        if !self.paused {
            self.time += dt;
        }
        self.apply_fly(dt);
        if self.lights_changed {
            self.lights_changed = false;
            // Waits for the frames in flight, which read the lights.
            self.renderer.lights_changed(self.time)?;
            self.scene_edits += 1;
        }
        if self.medium_changed {
            self.medium_changed = false;
            self.renderer.medium_changed()?;
            self.scene_edits += 1;
        }
        self.renderer.scene.camera = self.camera.camera();
        // The last submitted frame showed this view if nothing changed
        // since the snapshot: trace a pass and compare.
        let key = ViewKey::of(&self.renderer, self.time, self.scene_edits);
        self.compare.step(&self.renderer, &key)?;
        let mut scripted = self.script_compare();

        let ctx = self.ctx().clone();
        if self.overlay.is_none() {
            let format = self.swapchain.as_ref().expect("swapchain").format;
            let n = self.renderer.frames.frames_in_flight();
            self.overlay = Some(Overlay::new(&ctx, &self.window, format, n)?);
        }
        let overlay = self.overlay.as_mut().expect("overlay");
        let history: Vec<f32> = self.history_ms.iter().copied().collect();
        let actions = overlay.prepare(
            &self.window,
            &UiData {
                technique: self.renderer.technique_name(),
                params: self.renderer.params(),
                timings: &self.last_timings,
                history_ms: &history,
                components: self.renderer.technique_info().components,
                component_mask: self.renderer.scene_gpu.components,
                medium: self.renderer.scene.medium.as_ref().map(|m| MediumValues {
                    sigma_s: m.sigma_s.to_array(),
                    sigma_a: m.sigma_a.to_array(),
                    g: m.g,
                }),
                light_intensities: self
                    .renderer
                    .scene
                    .lights
                    .iter()
                    .map(|l| l.intensity.to_array())
                    .collect(),
                environment_rotate: self
                    .renderer
                    .scene
                    .environment
                    .as_ref()
                    .map(|e| e.rotate_deg),
                compare: self.compare.status(),
            },
        )?;
        scripted.extend(actions);
        for action in scripted {
            match action {
                Action::Technique(name) => self.switch_technique_named(name)?,
                Action::Components(mask) => self.renderer.scene_gpu.components = mask,
                Action::Medium(values) => {
                    if let Some(m) = self.renderer.scene.medium.as_mut() {
                        m.sigma_s = values.sigma_s.into();
                        m.sigma_a = values.sigma_a.into();
                        m.g = values.g;
                        self.medium_changed = true;
                    }
                }
                Action::LightIntensity { light, rgb } => {
                    if let Some(l) = self.renderer.scene.lights.get_mut(light) {
                        l.intensity = rgb.into();
                        self.lights_changed = true;
                    }
                }
                Action::EnvironmentRotation(deg) => self.set_environment_rotation(deg),
                Action::CompareStart => {
                    // The snapshot holds one instant: stop the clock.
                    self.paused = true;
                    // The reference uploads its scene with `Buffer::upload`,
                    // which needs no frame in flight: wait for them once.
                    for done in self.renderer.finish()? {
                        self.timings.push(done.passes);
                    }
                    // A reference the device cannot make (too large an
                    // image) is reported; the demo goes on.
                    if let Err(e) = self.compare.start(&ctx, &self.renderer, key.clone()) {
                        eprintln!("compare: no snapshot: {e:#}");
                    }
                }
                Action::CompareDiscard => self.compare.discard("by the user"),
                Action::CompareView(view) => self.compare.set_view(view),
                Action::Params(params) => {
                    // No wait: a rebuilt technique's predecessor is released
                    // after the frames in flight that use it.
                    let start = Instant::now();
                    let how = match self.renderer.set_params(&params)? {
                        true => "rebuilt",
                        false => "live",
                    };
                    println!(
                        "parameters: {how} in {:.1} ms",
                        start.elapsed().as_secs_f64() * 1e3
                    );
                }
            }
        }

        let start = Instant::now();
        let swapchain = self.swapchain.as_ref().expect("swapchain");
        let overlay = self.overlay.as_mut().expect("overlay");
        let finished = &self.finished;
        let stale = &mut self.stale;
        let mut presented = None;
        let mut in_swapchain = Duration::ZERO;
        // One command buffer per frame: technique, tonemap, then the blit
        // (and overlay) to the acquired image. `submit_frame_with` first waits
        // for the fence of the frame that last used this slot, which frees
        // its command buffer, ring and acquire semaphore; it does not wait
        // for this frame.
        self.renderer.submit_frame_with(
            self.time,
            |rec, display| -> anyhow::Result<FrameSync> {
                let acquired = rec.acquire_semaphore();
                let acquiring = Instant::now();
                let result = swapchain.acquire(acquired)?;
                in_swapchain += acquiring.elapsed();
                let index = match result {
                    Acquired::Image { index, suboptimal } => {
                        *stale |= suboptimal;
                        index
                    }
                    Acquired::OutOfDate => {
                        // The frame is still submitted (its fence must
                        // signal), with nothing to present.
                        *stale = true;
                        return Ok(FrameSync::default());
                    }
                };
                // The tonemap's compute writes -> transfer read. The next frame's
                // tonemap pass orders its write after this read through the
                // display image's tracked state (write-after-read).
                let draw_overlay = overlay.visible();
                let extent = swapchain.extent;
                rec.pass("present")
                    .untimed()
                    .read(display, Access::TransferRead)
                    .record(|c| {
                        swapchain.blit_to_image(c, index, display, draw_overlay);
                        if !draw_overlay {
                            return Ok(());
                        }
                        let view = swapchain.images[index as usize].view;
                        let drawn =
                            c.render(extent, &[(view, None)], None, |r| overlay.record(r, extent));
                        swapchain.attachment_to_present(c, index);
                        drawn
                    })
                    .transpose()?;
                presented = Some(index);
                Ok(FrameSync {
                    waits: vec![(acquired, vk::PipelineStageFlags2::ALL_TRANSFER)],
                    signals: vec![(
                        finished.raw[index as usize],
                        vk::PipelineStageFlags2::ALL_COMMANDS,
                    )],
                })
            },
        )?;
        for done in self.renderer.take_timings() {
            self.last_timings.clone_from(&done.passes);
            self.timings.push(done.passes);
        }
        let Some(index) = presented else {
            return Ok(false);
        };
        let swapchain = self.swapchain.as_ref().expect("swapchain");
        let presenting = Instant::now();
        self.stale |= swapchain.present(index, self.finished.raw[index as usize])?;
        self.swapchain_wait += in_swapchain + presenting.elapsed();
        self.presented += 1;
        self.frame_ms.push(start.elapsed().as_secs_f64() * 1e3);
        if Instant::now() >= self.report_at {
            self.report();
        }
        Ok(true)
    }

    /// `--compare-test N`: starts a snapshot on the third frame, switches
    /// to the next view (live, reference, FLIP) after each reference pass
    /// and stops tracing after N passes.
    fn script_compare(&mut self) -> Vec<Action> {
        let Some(n) = self.compare_script else {
            return Vec::new();
        };
        match self.compare.snapshot.as_ref().map(|s| s.passes()) {
            None if self.presented == 2 => vec![Action::CompareStart],
            Some(p) if p >= n as u64 => {
                self.compare_script = None;
                vec![Action::CompareView(View::Live), Action::CompareDiscard]
            }
            Some(p) if p > 0 => vec![Action::CompareView(View::ALL[p as usize % 3])],
            _ => Vec::new(),
        }
    }

    /// Once a second: per-pass means on stdout (the same scope names as
    /// `caustics render`), frame time in the window title.
    pub(super) fn report(&mut self) {
        let now = Instant::now();
        self.report_at = now + Duration::from_secs(1);
        let n = self.frame_ms.len().max(1) as f64;
        let frame_ms = self.frame_ms.iter().sum::<f64>() / n;
        // Frame interval: everything, fence waits and event handling included.
        let interval_ms = (now - self.report_from).as_secs_f64() * 1e3 / n;
        self.report_from = now;
        // Host time blocked on fences (frame slots and waits for edits).
        let waited = self.renderer.frames.host_wait;
        let wait_ms = (waited - self.waited_from).as_secs_f64() * 1e3 / n;
        self.waited_from = waited;
        let swapchain_ms = self.swapchain_wait.as_secs_f64() * 1e3 / n;
        self.swapchain_wait = Duration::ZERO;
        let mut passes: Vec<(String, f64, usize)> = Vec::new();
        for t in self.timings.iter().flatten() {
            match passes.iter_mut().find(|p| p.0 == t.name) {
                Some(p) => {
                    p.1 += t.ms;
                    p.2 += 1;
                }
                None => passes.push((t.name.clone(), t.ms, 1)),
            }
        }
        let r = &self.renderer;
        println!(
            "{} {}x{}: {:.2} ms/frame render+present, {:.2} ms frame interval, {:.2} ms/frame host wait on fences, {:.2} ms/frame in acquire+present, over {} frame(s), {} in flight ({})",
            r.technique_name(),
            r.targets.width,
            r.targets.height,
            frame_ms,
            interval_ms,
            wait_ms,
            swapchain_ms,
            self.frame_ms.len(),
            r.frames.frames_in_flight(),
            r.frames.source.describe()
        );
        for (name, sum, count) in &passes {
            println!("  {:<28} {:>9.3} ms", name, sum / *count as f64);
        }
        self.window.set_title(&format!(
            "caustics - {} - {}x{} - {:.1} ms{}",
            r.technique_name(),
            r.targets.width,
            r.targets.height,
            frame_ms,
            if self.paused { " (paused)" } else { "" }
        ));
        self.frame_ms.clear();
        self.timings.clear();
    }
}
