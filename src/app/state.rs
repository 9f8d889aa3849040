//! The open window's state and its frame: recreate the swapchain, render,
//! blit, overlay, present, and the once-a-second report.

use super::camera::OrbitCamera;
use super::overlay::{Action, MediumValues, Overlay, UiData};
use super::slots::{Frame, ImageSemaphores};
use super::FRAMES_IN_FLIGHT;
use crate::renderer::Renderer;
use crate::vk::{
    barrier, begin_rendering, end_rendering, Access, Acquired, Context, ImageAccess, PassTiming,
    Surface, Swapchain,
};
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
/// order: frame slots and semaphores, swapchain, renderer, surface, window
/// (the surface must go before the window it was made from).
pub(super) struct State {
    pub(super) frames: Vec<Frame>,
    pub(super) finished: ImageSemaphores,
    /// Made with the first swapchain (it needs the swapchain's format).
    pub(super) overlay: Option<Overlay>,
    pub(super) swapchain: Option<Swapchain>,
    pub(super) renderer: Renderer,
    pub(super) surface: Surface,
    pub(super) window: Window,
    pub(super) current: usize,
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
    pub(super) screenshots: u32,
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
            // The scene (lights) is re-uploaded: nothing may still read it.
            self.ctx().wait_idle();
            self.renderer.lights_changed(self.time)?;
        }
        if self.medium_changed {
            self.medium_changed = false;
            self.ctx().wait_idle();
            self.renderer
                .scene_gpu
                .update_medium(&self.renderer.scene)?;
        }
        self.renderer.scene.camera = self.camera.camera();

        let ctx = self.ctx().clone();
        let d = &ctx.device;
        let frame = &self.frames[self.current];
        // Wait until this slot's previous submission is done: its command
        // buffer and acquire semaphore may then be reused. The renderer's
        // host writes below (frame uniform buffer, animated geometry) do not
        // need this wait: `render_frame` waits for its own GPU work before
        // returning, and the presentation submissions only read the display
        // image, never those buffers. Were `render_frame` made asynchronous,
        // those buffers would have to become per frame slot.
        unsafe { d.wait_for_fences(&[frame.fence], true, u64::MAX) }?;

        if self.overlay.is_none() {
            let format = self.swapchain.as_ref().expect("swapchain").format;
            self.overlay = Some(Overlay::new(&ctx, &self.window, format, FRAMES_IN_FLIGHT)?);
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
            },
        )?;
        for action in actions {
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
                Action::Params(params) => {
                    ctx.wait_idle();
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
        let frame = &self.frames[self.current];

        let start = Instant::now();
        let timings = self.renderer.render_frame(self.time)?;

        let swapchain = self.swapchain.as_ref().expect("swapchain");
        let index = match swapchain.acquire(frame.acquired)? {
            Acquired::Image { index, suboptimal } => {
                self.stale |= suboptimal;
                index
            }
            Acquired::OutOfDate => {
                self.stale = true;
                return Ok(false);
            }
        };
        // Reset only once an image is acquired: an early return above leaves
        // the fence signalled, so the next wait on it cannot deadlock.
        unsafe {
            d.reset_fences(&[frame.fence])?;
            d.reset_command_pool(frame.pool, vk::CommandPoolResetFlags::empty())?;
            d.begin_command_buffer(
                frame.cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?;
        }
        let display = &self.renderer.tonemap.display;
        // The tonemap's compute writes -> transfer read. The next frame's
        // tonemap pass (a later submission) orders its write after this read
        // through the display image's tracked state (write-after-read).
        barrier(
            &ctx,
            frame.cmd,
            &[ImageAccess::new(display, Access::TransferRead)],
            &[],
        );
        let overlay = self.overlay.as_mut().expect("overlay");
        let draw_overlay = overlay.visible();
        swapchain.blit_to_image(
            frame.cmd,
            index,
            display.raw,
            display.extent(),
            draw_overlay,
        );
        if draw_overlay {
            let view = swapchain.views[index as usize];
            begin_rendering(&ctx, frame.cmd, swapchain.extent, &[(view, None)], None);
            let drawn = overlay.record(frame.cmd, swapchain.extent);
            end_rendering(&ctx, frame.cmd);
            swapchain.attachment_to_present(frame.cmd, index);
            drawn?;
        }
        unsafe { d.end_command_buffer(frame.cmd) }?;
        let finished = self.finished.raw[index as usize];
        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(frame.acquired)
            .stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(finished)
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(frame.cmd)];
        let submit = vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals);
        unsafe { d.queue_submit2(ctx.queue, &[submit], frame.fence) }?;
        self.stale |= swapchain.present(index, finished)?;
        self.current = (self.current + 1) % FRAMES_IN_FLIGHT;
        self.presented += 1;

        self.frame_ms.push(start.elapsed().as_secs_f64() * 1e3);
        self.last_timings.clone_from(&timings);
        self.timings.push(timings);
        if Instant::now() >= self.report_at {
            self.report();
        }
        Ok(true)
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
            "{} {}x{}: {:.2} ms/frame render+present, {:.2} ms frame interval, over {} frame(s) ({})",
            r.technique_name(),
            r.targets.width,
            r.targets.height,
            frame_ms,
            interval_ms,
            self.frame_ms.len(),
            r.profiler.source.describe()
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
