//! The desktop demo (`caustics demo`): a winit window, a swapchain, and the
//! existing `Renderer` behind it. docs/ARCHITECTURE.md ("The demo frame
//! loop") describes the synchronisation; the short version, per frame:
//!
//! 1. `Renderer::submit_frame_with` takes the next of the renderer's frame
//!    slots (`vk::Frames`, `--frames-in-flight`, default 2) and waits for the
//!    fence of the frame that last used it, the loop's only wait: its
//!    command buffer, upload ring and acquire semaphore are free again;
//! 2. it records technique + tonemap into the slot's command buffer (host
//!    writes through the slot's upload ring), then the demo acquires a
//!    swapchain image and records the blit display -> swapchain image (and
//!    the overlay) into the same command buffer;
//! 3. one submission waits on the acquire semaphore and signals the image's
//!    render-finished semaphore and the slot's fence;
//! 4. present, waiting on that semaphore. The host goes on to the next frame
//!    while the GPU runs this one.

mod camera;
mod compare;
mod controls;
mod overlay;
mod slots;
mod state;

pub use camera::OrbitCamera;
// For tests/suite/overlay_layout.rs: the panel's layout without a window.
#[cfg(feature = "overlay")]
pub use overlay::{panel_rect, CompareStatus, MediumValues, UiData, View};
use slots::ImageSemaphores;
use state::{Input, State};

use crate::params::Params;
use crate::renderer::Renderer;
use crate::scene::{AllowedPaths, Scene};
use crate::vk::{Context, ContextOptions, FrameOptions, Surface};
use anyhow::Context as _;
use ash::vk;
use std::collections::VecDeque;
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

/// Degrees the environment turns about +y per press of `[` or `]`.
const ENVIRONMENT_STEP_DEG: f32 = 15.0;

#[derive(Clone, Debug)]
pub struct DemoOptions {
    pub scene: PathBuf,
    /// `--allow-paths`: folders the scene's files may be in besides its
    /// own tree (a reload reads with the same).
    pub allowed: AllowedPaths,
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
    /// Frames the renderer keeps in flight (`vk::Frames`).
    pub frames_in_flight: usize,
    /// Synchronization validation too (implies `validate`).
    pub validate_sync: bool,
    pub device: Option<String>,
    /// `--compare-test N`: a scripted compare snapshot of N reference
    /// passes that switches the three views (tests).
    pub compare_test: Option<u32>,
}

pub fn parse_present_mode(s: &str) -> anyhow::Result<vk::PresentModeKHR> {
    Ok(match s.to_ascii_lowercase().as_str() {
        "fifo" => vk::PresentModeKHR::FIFO,
        "mailbox" => vk::PresentModeKHR::MAILBOX,
        "immediate" => vk::PresentModeKHR::IMMEDIATE,
        other => anyhow::bail!("--present-mode {other}: expected fifo, mailbox or immediate"),
    })
}

/// Where the demo keeps the driver's pipeline cache between runs:
/// `pipelines.bin` in [`crate::cache_dir::cache_dir`]; none without one.
fn pipeline_cache_file() -> Option<PathBuf> {
    Some(crate::cache_dir::cache_dir()?.join("pipelines.bin"))
}

/// Runs the demo until the window closes (or `--frames N --exit`). Fails on
/// any error, on validation errors and on leaked Vulkan objects.
pub fn run(options: DemoOptions) -> anyhow::Result<()> {
    let scene = Scene::load_allowing(&options.scene, &options.allowed)?;
    // Screenshots never replace a file the scene was read from.
    crate::output::protect_inputs(&crate::scene::input::files_read());
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        anyhow::bail!(
            "demo needs a display: neither DISPLAY nor WAYLAND_DISPLAY is set (run it in a desktop session, or under `xvfb-run`)"
        );
    }
    // winit's message starts with its own source location: keep the reason.
    let event_loop = EventLoop::new().map_err(|e| {
        let m = e.to_string();
        let reason = match m.split_once(": ") {
            Some((at, reason)) if at.starts_with("os error at") => reason.to_owned(),
            _ => m,
        };
        anyhow::anyhow!("demo cannot open a window: {reason}")
    })?;
    let display = event_loop
        .display_handle()
        .context("no display handle")?
        .as_raw();
    let extensions = Surface::required_extensions(display)?;
    let ctx = Context::with_instance_extensions(
        &ContextOptions {
            validation: options.validate || options.validate_sync || cfg!(debug_assertions),
            sync_validation: options.validate_sync || cfg!(debug_assertions),
            device: options.device.clone(),
        },
        extensions,
    )?;
    eprintln!("device: {} ({})", ctx.info.name, ctx.info.driver.trim());
    let cache_file = pipeline_cache_file();
    if let Some(path) = &cache_file {
        // A bad or foreign file is ignored with a warning (vk::CacheLoad).
        log::info!(
            "pipeline cache {}: {:?}",
            path.display(),
            ctx.pipelines().load(path)
        );
    }
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
    if let Some(path) = &cache_file {
        // The next start compiles nothing this run compiled (real GPUs;
        // lavapipe's cache stays empty). Failing to save costs only time.
        if let Err(e) = ctx.pipelines().save(path) {
            log::warn!("cannot save the pipeline cache {}: {e}", path.display());
        }
    }
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
        let mut renderer = Renderer::new(&ctx, scene, &o.technique, &o.params, w, h, 0.0)?;
        renderer.set_frame_options(FrameOptions {
            frames_in_flight: o.frames_in_flight,
            ..FrameOptions::default()
        })?;
        // A still view converges; moving the camera starts over.
        renderer.set_accumulation(true)?;
        let now = Instant::now();
        let mut state = State {
            finished: ImageSemaphores::new(&ctx, 0)?,
            swapchain: None,
            renderer,
            surface,
            window,
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
            waited_from: Duration::ZERO,
            swapchain_wait: Duration::ZERO,
            screenshots: 0,
            compare: compare::Compare::new(),
            scene_edits: 0,
            compare_script: o.compare_test,
            allowed: o.allowed.clone(),
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
                    KeyCode::BracketLeft | KeyCode::BracketRight => {
                        let step = ENVIRONMENT_STEP_DEG;
                        state.rotate_environment(if code == KeyCode::BracketLeft {
                            -step
                        } else {
                            step
                        });
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
