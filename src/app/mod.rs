//! The desktop demo (`caustics demo`): a winit window, a swapchain, and the
//! existing `Renderer` behind it. docs/ARCHITECTURE.md ("The demo frame
//! loop") describes the synchronisation; the short version:
//!
//! 1. wait for this frame slot's fence (its command buffer and acquire
//!    semaphore are free again; at most `FRAMES_IN_FLIGHT` presentation
//!    submissions are queued);
//! 2. `Renderer::render_frame` renders technique + tonemap into
//!    `tonemap.display` and waits for that work itself, so the host writes it
//!    makes (frame uniform buffer, animated geometry) never race the GPU;
//! 3. acquire a swapchain image, record the blit display -> swapchain image in
//!    the slot's command buffer, submit it waiting on the acquire semaphore
//!    and signalling the image's render-finished semaphore and the slot's fence;
//! 4. present, waiting on that semaphore.

mod camera;
mod overlay;

pub use camera::OrbitCamera;
use overlay::{Action, MediumValues, Overlay, UiData};

use crate::output;
use crate::reference::Component;
use crate::renderer::Renderer;
use crate::scene::Scene;
use crate::techniques::{self, Params};
use crate::vk::{
    barrier, begin_rendering, end_rendering, Access, Acquired, Context, ContextOptions,
    ImageAccess, PassTiming, Surface, Swapchain, VkResult,
};
use anyhow::Context as _;
use ash::vk;
use std::collections::{HashSet, VecDeque};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

/// Presentation submissions that may be queued at once.
pub const FRAMES_IN_FLIGHT: usize = 2;

#[derive(Clone, Debug)]
pub struct DemoOptions {
    pub scene: PathBuf,
    pub technique: String,
    pub params: Params,
    pub width: u32,
    pub height: u32,
    pub present_mode: vk::PresentModeKHR,
    /// Stop after this many presented frames when `exit` is set.
    pub frames: Option<u32>,
    pub exit: bool,
    pub resize_test: bool,
    pub validate: bool,
    pub device: Option<String>,
}

pub fn parse_present_mode(s: &str) -> anyhow::Result<vk::PresentModeKHR> {
    Ok(match s.to_ascii_lowercase().as_str() {
        "fifo" => vk::PresentModeKHR::FIFO,
        "mailbox" => vk::PresentModeKHR::MAILBOX,
        "immediate" => vk::PresentModeKHR::IMMEDIATE,
        other => anyhow::bail!("--present-mode {other}: expected fifo, mailbox or immediate"),
    })
}

/// Runs the demo until the window closes (or `--frames N --exit`). Fails on
/// any error, on validation errors and on leaked Vulkan objects.
pub fn run(options: DemoOptions) -> anyhow::Result<()> {
    let scene = Scene::load(&options.scene)?;
    let event_loop = EventLoop::new().context("cannot open a window (is DISPLAY set?)")?;
    let display = event_loop
        .display_handle()
        .context("no display handle")?
        .as_raw();
    let extensions = Surface::required_extensions(display)?;
    let ctx = Context::with_instance_extensions(
        &ContextOptions {
            validation: options.validate || cfg!(debug_assertions),
            device: options.device.clone(),
        },
        extensions,
    )?;
    eprintln!("device: {} ({})", ctx.info.name, ctx.info.driver.trim());
    let mut app = App {
        ctx: Some(ctx),
        options,
        scene: Some(scene),
        state: None,
        error: None,
    };
    event_loop.run_app(&mut app)?;
    // Everything that used the device is gone (`exiting` dropped the state)
    // before the context is shut down and checked for leaks.
    app.state = None;
    let ctx = app.ctx.take().expect("context");
    let counts = Context::shutdown(ctx)?;
    if let Some(e) = app.error {
        return Err(e);
    }
    if counts.errors > 0 {
        anyhow::bail!(
            "the Vulkan validation layer reported {} error(s) (see the log above)",
            counts.errors
        );
    }
    Ok(())
}

/// One frame slot. Per GUIDE §7 it owns its fence, command pool and acquire
/// semaphore (render-finished semaphores are per swapchain image, in `State`).
struct Frame {
    ctx: Arc<Context>,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    /// Signalled when this slot's presentation submission has finished.
    fence: vk::Fence,
    /// Signalled by vkAcquireNextImageKHR; waited by this slot's submission.
    acquired: vk::Semaphore,
}

impl Frame {
    fn new(ctx: &Arc<Context>) -> VkResult<Frame> {
        let d = &ctx.device;
        unsafe {
            let pool = d.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(ctx.queue_family)
                    .flags(vk::CommandPoolCreateFlags::TRANSIENT),
                None,
            )?;
            // Owned from here on, so an error below destroys what was made
            // (Drop skips null handles' destruction: destroying null is a no-op).
            let mut frame = Frame {
                ctx: ctx.clone(),
                pool,
                cmd: vk::CommandBuffer::null(),
                fence: vk::Fence::null(),
                acquired: vk::Semaphore::null(),
            };
            frame.cmd = d.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1),
            )?[0];
            // Signalled, so the first wait on a fresh slot returns at once.
            frame.fence = d.create_fence(
                &vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED),
                None,
            )?;
            frame.acquired = d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?;
            Ok(frame)
        }
    }
}

impl Drop for Frame {
    fn drop(&mut self) {
        let d = &self.ctx.device;
        unsafe {
            d.destroy_semaphore(self.acquired, None);
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
        }
    }
}

/// Binary semaphores, one per swapchain image: a present waits on it, and it
/// is signalled again only after that image is re-acquired, which implies
/// the earlier present has consumed it.
struct ImageSemaphores {
    ctx: Arc<Context>,
    raw: Vec<vk::Semaphore>,
}

impl ImageSemaphores {
    fn new(ctx: &Arc<Context>, count: usize) -> VkResult<Self> {
        let mut s = ImageSemaphores {
            ctx: ctx.clone(),
            raw: Vec::new(),
        };
        for _ in 0..count {
            s.raw.push(unsafe {
                ctx.device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
            }?);
        }
        Ok(s)
    }
}

impl Drop for ImageSemaphores {
    fn drop(&mut self) {
        for s in &self.raw {
            unsafe { self.ctx.device.destroy_semaphore(*s, None) };
        }
    }
}

#[derive(Default)]
struct Input {
    keys: HashSet<KeyCode>,
    left: bool,
    right: bool,
    cursor: Option<(f64, f64)>,
}

/// Everything that lives while the window is open. Fields drop in this
/// order: frame slots and semaphores, swapchain, renderer, surface, window
/// (the surface must go before the window it was made from).
struct State {
    frames: Vec<Frame>,
    finished: ImageSemaphores,
    /// Made with the first swapchain (it needs the swapchain's format).
    overlay: Option<Overlay>,
    swapchain: Option<Swapchain>,
    renderer: Renderer,
    surface: Surface,
    window: Window,
    current: usize,
    camera: OrbitCamera,
    input: Input,
    time: f32,
    paused: bool,
    last: Instant,
    presented: u32,
    /// The swapchain no longer matches the window (resize, out of date).
    stale: bool,
    /// A light moved or its intensity changed: the lights are re-uploaded
    /// before the next frame.
    lights_changed: bool,
    /// The medium's coefficients changed: re-uploaded before the next frame.
    medium_changed: bool,
    timings: Vec<Vec<PassTiming>>,
    frame_ms: Vec<f64>,
    /// The last frame's per-pass timings and recent frame intervals (overlay).
    last_timings: Vec<PassTiming>,
    history_ms: VecDeque<f32>,
    report_at: Instant,
    /// When the frames being averaged for the next report began.
    report_from: Instant,
    screenshots: u32,
}

struct App {
    ctx: Option<Arc<Context>>,
    options: DemoOptions,
    scene: Option<Scene>,
    state: Option<State>,
    error: Option<anyhow::Error>,
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        self.close(event_loop);
    }

    /// Waits for the device, then drops everything in order.
    fn close(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(ctx) = &self.ctx {
            ctx.wait_idle();
        }
        self.state = None;
        event_loop.exit();
    }

    fn start(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<State> {
        let ctx = self.ctx.clone().expect("context");
        let o = &self.options;
        let window = event_loop.create_window(
            Window::default_attributes()
                .with_title("caustics")
                .with_inner_size(PhysicalSize::new(o.width, o.height)),
        )?;
        let surface = Surface::new(
            &ctx,
            window.display_handle()?.as_raw(),
            window.window_handle()?.as_raw(),
        )?;
        let size = window.inner_size();
        let (w, h) = (size.width.max(1), size.height.max(1));
        let scene = self.scene.take().expect("scene");
        let camera = OrbitCamera::from_camera(&scene.camera);
        let renderer = Renderer::new(&ctx, scene, &o.technique, &o.params, w, h, 0.0)?;
        let frames = (0..FRAMES_IN_FLIGHT)
            .map(|_| Frame::new(&ctx))
            .collect::<VkResult<Vec<_>>>()?;
        let now = Instant::now();
        let mut state = State {
            frames,
            finished: ImageSemaphores::new(&ctx, 0)?,
            swapchain: None,
            renderer,
            surface,
            window,
            current: 0,
            camera,
            input: Input::default(),
            time: 0.0,
            paused: false,
            last: now,
            presented: 0,
            stale: true,
            lights_changed: false,
            medium_changed: false,
            timings: Vec::new(),
            frame_ms: Vec::new(),
            last_timings: Vec::new(),
            history_ms: VecDeque::new(),
            overlay: None,
            report_at: now + Duration::from_secs(1),
            report_from: now,
            screenshots: 0,
        };
        state.recreate(o.present_mode)?;
        println!(
            "demo: {} at {}x{}, present mode {:?}; keys: 1-9 technique, C components, F1 overlay, Space pause, R reload, P screenshot, Esc quit; \
             mouse: left orbit, right pan, wheel zoom, L+left move light; WASD fly",
            state.renderer.technique_name(),
            state.renderer.targets.width,
            state.renderer.targets.height,
            state.swapchain.as_ref().map(|s| s.present_mode).unwrap_or_default()
        );
        Ok(state)
    }
}

impl State {
    fn ctx(&self) -> &Arc<Context> {
        &self.renderer.ctx
    }

    /// Recreates the swapchain, the per-image semaphores and the renderer's
    /// frame targets at the window's size. A zero-size (minimised) window
    /// keeps no swapchain and renders nothing until it is restored.
    ///
    /// Waits for the device: the old swapchain's images, the old display
    /// image and the old semaphores may still be used by queued submissions
    /// and presents. This happens once per resize, not per frame.
    fn recreate(&mut self, mode: vk::PresentModeKHR) -> anyhow::Result<()> {
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

    fn minimised(&self) -> bool {
        let s = self.window.inner_size();
        s.width == 0 || s.height == 0
    }

    /// One frame; returns false when nothing was presented.
    fn draw(&mut self, mode: vk::PresentModeKHR) -> anyhow::Result<bool> {
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
                    let name = self.renderer.technique_name();
                    self.renderer.set_technique(name, &params)?;
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
    fn report(&mut self) {
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

    fn apply_fly(&mut self, dt: f32) {
        let k = &self.input.keys;
        let axis =
            |pos: KeyCode, neg: KeyCode| (k.contains(&pos) as i32 - k.contains(&neg) as i32) as f32;
        let forward = axis(KeyCode::KeyW, KeyCode::KeyS);
        let strafe = axis(KeyCode::KeyD, KeyCode::KeyA);
        if forward != 0.0 || strafe != 0.0 {
            self.camera.fly(forward, strafe, dt);
        }
    }

    fn mouse_moved(&mut self, x: f64, y: f64) {
        let Some((px, py)) = self.input.cursor.replace((x, y)) else {
            return;
        };
        let (dx, dy) = ((x - px) as f32, (y - py) as f32);
        if self.input.left && self.input.keys.contains(&KeyCode::KeyL) {
            self.move_light(dx, dy);
        } else if self.input.left {
            self.camera.orbit(dx, dy);
        } else if self.input.right {
            self.camera.pan(dx, dy);
        }
    }

    /// L + left drag: moves the first light across the ground plane, along
    /// the camera's right and (flattened) forward directions.
    fn move_light(&mut self, dx: f32, dy: f32) {
        let right = self.camera.right();
        let mut ahead = self.camera.forward();
        ahead.y = 0.0;
        let ahead = ahead.normalize_or(glam::Vec3::NEG_Z);
        let step = self.camera.distance * 0.003;
        if let Some(light) = self.renderer.scene.lights.first_mut() {
            light.position += (right * dx - ahead * dy) * step;
            self.lights_changed = true;
        }
    }

    fn screenshot(&mut self) -> anyhow::Result<()> {
        self.ctx().wait_idle();
        let (w, h) = (self.renderer.targets.width, self.renderer.targets.height);
        let radiance = self.renderer.radiance()?;
        let display = self.renderer.display()?;
        self.screenshots += 1;
        let stamp = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs())
            .unwrap_or(0);
        let base = PathBuf::from(format!("out/demo-{stamp}-{}", self.screenshots));
        let (exr, png) = output::prepare(&base.with_extension("png"))?;
        output::write_exr(&exr, w, h, &radiance)?;
        output::write_png(&png, w, h, &display)?;
        println!("wrote {} and {}", png.display(), exr.display());
        Ok(())
    }

    fn reload(&mut self) {
        let path = self.renderer.scene.source.clone();
        match Scene::load(&path) {
            Err(e) => eprintln!("reload: {e} (keeping the old scene)"),
            Ok(scene) => {
                self.ctx().wait_idle();
                let camera = OrbitCamera::from_camera(&scene.camera);
                match self.renderer.set_scene(scene, self.time) {
                    Ok(()) => {
                        self.camera = camera;
                        println!("reloaded {}", path.display());
                    }
                    Err(e) => eprintln!("reload: {e:#} (keeping the old scene)"),
                }
            }
        }
    }

    fn switch_technique(&mut self, n: usize) -> anyhow::Result<()> {
        let Some(info) = techniques::TECHNIQUES.get(n - 1) else {
            println!(
                "key {n}: no technique {n} (there are {}); ignored",
                techniques::TECHNIQUES.len()
            );
            return Ok(());
        };
        self.switch_technique_named(info.name)
    }

    fn switch_technique_named(&mut self, name: &str) -> anyhow::Result<()> {
        let info = techniques::find(name)?;
        if info.name == self.renderer.technique_name() {
            return Ok(());
        }
        let params = Params::resolve(info.name, info.params, &[])?;
        self.ctx().wait_idle();
        self.renderer.set_technique(info.name, &params)?;
        self.renderer.scene_gpu.components = Component::All.mask();
        println!("technique: {}", info.name);
        Ok(())
    }

    /// C: all components, then each one the technique renders alone, then
    /// all again.
    fn cycle_components(&mut self) {
        let all = Component::All.mask();
        let own = self.renderer.technique_info().components;
        let current = self.renderer.scene_gpu.components;
        let position = own.iter().position(|c| c.mask() == current);
        let next = match position {
            None if current == all => own.first(),
            Some(i) => own.get(i + 1),
            None => None,
        };
        self.renderer.scene_gpu.components = next.map_or(all, |c| c.mask());
        println!("components: {}", next.map_or("all", |c| c.name()));
    }
}

/// Window sizes `--resize-test` steps through, one every few frames.
const RESIZE_STEPS: [(u32, u32); 4] = [(320, 240), (640, 360), (200, 300), (480, 480)];

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() || self.error.is_some() {
            return;
        }
        match self.start(event_loop) {
            Ok(s) => {
                event_loop.set_control_flow(ControlFlow::Poll);
                self.state = Some(s);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let mode = self.options.present_mode;
        let Some(state) = self.state.as_mut() else {
            return;
        };
        if let WindowEvent::KeyboardInput { event: key, .. } = &event {
            if key.physical_key == PhysicalKey::Code(KeyCode::F1)
                && key.state == ElementState::Pressed
                && !key.repeat
            {
                if let Some(o) = state.overlay.as_mut() {
                    o.toggle();
                }
                return;
            }
        }
        if let Some(o) = state.overlay.as_mut() {
            if o.on_event(&state.window, &event) {
                // egui uses this input; still track the cursor and releases
                // so the demo's drags and held keys do not go stale.
                match &event {
                    WindowEvent::CursorMoved { position, .. } => {
                        state.input.cursor = Some((position.x, position.y));
                    }
                    WindowEvent::KeyboardInput { event: k, .. }
                        if k.state == ElementState::Released =>
                    {
                        if let PhysicalKey::Code(code) = k.physical_key {
                            state.input.keys.remove(&code);
                        }
                    }
                    WindowEvent::MouseInput {
                        state: ElementState::Released,
                        button,
                        ..
                    } => match button {
                        MouseButton::Left => state.input.left = false,
                        MouseButton::Right => state.input.right = false,
                        _ => {}
                    },
                    _ => {}
                }
                return;
            }
        }
        let result: anyhow::Result<()> = match event {
            WindowEvent::CloseRequested => {
                self.close(event_loop);
                return;
            }
            WindowEvent::Resized(_) => {
                state.stale = true;
                Ok(())
            }
            WindowEvent::RedrawRequested => match state.draw(mode) {
                Ok(_) => {
                    let done = self.options.exit
                        && self.options.frames.is_some_and(|n| state.presented >= n);
                    if done {
                        if !state.frame_ms.is_empty() {
                            state.report();
                        }
                        println!("demo: presented {} frames", state.presented);
                        self.close(event_loop);
                        return;
                    }
                    if self.options.resize_test && state.presented > 0 {
                        let p = state.presented;
                        if p % 5 == 0 {
                            let (w, h) = RESIZE_STEPS[(p as usize / 5) % RESIZE_STEPS.len()];
                            let _ = state.window.request_inner_size(PhysicalSize::new(w, h));
                        }
                    }
                    Ok(())
                }
                Err(e) => Err(e),
            },
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return;
                };
                if event.state == ElementState::Released {
                    state.input.keys.remove(&code);
                    return;
                }
                let first = state.input.keys.insert(code);
                if !first || event.repeat {
                    return;
                }
                let digit = match code {
                    KeyCode::Digit1 => Some(1),
                    KeyCode::Digit2 => Some(2),
                    KeyCode::Digit3 => Some(3),
                    KeyCode::Digit4 => Some(4),
                    KeyCode::Digit5 => Some(5),
                    KeyCode::Digit6 => Some(6),
                    KeyCode::Digit7 => Some(7),
                    KeyCode::Digit8 => Some(8),
                    KeyCode::Digit9 => Some(9),
                    _ => None,
                };
                match code {
                    KeyCode::Escape => {
                        self.close(event_loop);
                        return;
                    }
                    KeyCode::Space => {
                        state.paused = !state.paused;
                        println!(
                            "animation {}",
                            if state.paused { "paused" } else { "running" }
                        );
                        Ok(())
                    }
                    KeyCode::KeyR => {
                        state.reload();
                        Ok(())
                    }
                    KeyCode::KeyP => state.screenshot(),
                    KeyCode::KeyC => {
                        state.cycle_components();
                        Ok(())
                    }
                    _ => match digit {
                        Some(n) => state.switch_technique(n),
                        None => Ok(()),
                    },
                }
            }
            WindowEvent::MouseInput {
                state: s, button, ..
            } => {
                let down = s == ElementState::Pressed;
                match button {
                    MouseButton::Left => state.input.left = down,
                    MouseButton::Right => state.input.right = down,
                    _ => {}
                }
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                state.mouse_moved(position.x, position.y);
                Ok(())
            }
            WindowEvent::CursorLeft { .. } => {
                state.input.cursor = None;
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                state.camera.zoom(steps);
                Ok(())
            }
            WindowEvent::Focused(false) => {
                state.input = Input::default();
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(state) = &self.state {
            if state.minimised() {
                // Nothing to draw until the window is restored (a Resized
                // event wakes the loop).
                event_loop.set_control_flow(ControlFlow::Wait);
            } else {
                event_loop.set_control_flow(ControlFlow::Poll);
                state.window.request_redraw();
            }
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(ctx) = &self.ctx {
            ctx.wait_idle();
        }
        self.state = None;
    }
}
