//! The demo's egui overlay (feature `overlay`; F1 toggles it): technique
//! picker, parameter sliders from each technique's `ParamSpec`s, the per-pass
//! timing table and a rolling frame-time graph. Without the feature the same
//! API is a no-op, so the frame loop has no `cfg`s.
//!
//! It draws straight onto the swapchain image after the blit (so screenshots,
//! which read the display image, never contain it), in the frame slot's
//! command buffer. egui-ash-renderer keeps one vertex/index buffer pair per
//! frame in flight and rotates them per `cmd_draw`, which the demo calls
//! once per submitted frame, so a buffer is rewritten only after the fence
//! of the frame that last read it has been waited for.

pub use super::compare::{CompareStatus, View};
use crate::params::Params;
use crate::radiometry::Component;
use crate::vk::{Context, PassTiming, Rendering};
use ash::vk;
use std::sync::Arc;
use winit::event::WindowEvent;
use winit::window::Window;

/// What the overlay shows, gathered by the frame loop.
#[cfg_attr(not(feature = "overlay"), allow(dead_code))]
pub struct UiData<'a> {
    pub technique: &'static str,
    pub params: &'a Params,
    pub timings: &'a [PassTiming],
    /// Recent frame intervals, oldest first.
    pub history_ms: &'a [f32],
    /// The technique's components and the mask of those drawn.
    pub components: &'static [Component],
    pub component_mask: u32,
    /// The scene's medium, if any (sigma_s, sigma_a in 1/m; g).
    pub medium: Option<MediumValues>,
    /// Each light's intensity (W/sr) or, for a directional light, irradiance (W/m^2).
    pub light_intensities: Vec<[f32; 3]>,
    /// The environment's `rotate` (degrees about +y), if there is one.
    pub environment_rotate: Option<f32>,
    /// The compare panel's snapshot and chosen view.
    pub compare: CompareStatus<'a>,
}

/// The medium coefficients the overlay edits.
#[cfg_attr(not(feature = "overlay"), allow(dead_code))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumValues {
    pub sigma_s: [f32; 3],
    pub sigma_a: [f32; 3],
    pub g: f32,
}

/// What the user asked for in the overlay.
#[cfg_attr(not(feature = "overlay"), allow(dead_code))]
pub enum Action {
    Technique(&'static str),
    Params(Params),
    /// The component mask to draw (`Component::mask` bits).
    Components(u32),
    Medium(MediumValues),
    LightIntensity {
        light: usize,
        rgb: [f32; 3],
    },
    /// The environment's new `rotate` (degrees about +y).
    EnvironmentRotation(f32),
    /// Take a reference snapshot of the current view.
    CompareStart,
    CompareDiscard,
    /// Show the live frame, the reference or the FLIP map.
    CompareView(View),
}

#[cfg(not(feature = "overlay"))]
pub struct Overlay;

#[cfg(not(feature = "overlay"))]
impl Overlay {
    pub fn new(
        _ctx: &Arc<Context>,
        _window: &Window,
        _format: vk::Format,
        _frames_in_flight: usize,
    ) -> anyhow::Result<Self> {
        Ok(Overlay)
    }
    pub fn toggle(&mut self) {
        println!("overlay: not built in (cargo build --features overlay)");
    }
    pub fn visible(&self) -> bool {
        false
    }
    pub fn on_event(&mut self, _window: &Window, _event: &WindowEvent) -> bool {
        false
    }
    pub fn prepare(&mut self, _window: &Window, _data: &UiData) -> anyhow::Result<Vec<Action>> {
        Ok(Vec::new())
    }
    pub fn record(&mut self, _draws: &mut Rendering, _extent: vk::Extent2D) -> anyhow::Result<()> {
        Ok(())
    }
}

#[cfg(feature = "overlay")]
pub use enabled::{panel_rect, Overlay};

#[cfg(feature = "overlay")]
mod enabled {
    use super::*;
    use crate::params::Apply;
    use crate::techniques::TECHNIQUES;
    use crate::vk::CommandPool;
    use egui_ash_renderer::{DynamicRendering, Options, RenderMode, Renderer};

    pub struct Overlay {
        ctx: Arc<Context>,
        egui: egui::Context,
        winit: egui_winit::State,
        renderer: Renderer<egui_ash_renderer::allocator::DefaultAllocator>,
        /// For egui-ash-renderer's blocking texture uploads.
        pool: CommandPool,
        visible: bool,
        primitives: Vec<egui::ClippedPrimitive>,
        pixels_per_point: f32,
        /// Textures egui released; freed once no queued frame can use them.
        to_free: Vec<egui::TextureId>,
        /// Slider edits not yet applied (applied when the mouse is released,
        /// since a technique rebuild compiles pipelines).
        pending: Option<Params>,
        /// The compare view's image and the snapshot generation it holds.
        compare_texture: Option<(egui::TextureHandle, u64)>,
    }

    impl Overlay {
        pub fn new(
            ctx: &Arc<Context>,
            window: &Window,
            format: vk::Format,
            frames_in_flight: usize,
        ) -> anyhow::Result<Self> {
            let pool = CommandPool::new(ctx)?;
            let renderer = Renderer::with_default_allocator(
                &ctx.instance,
                ctx.physical_device,
                ctx.device.clone(),
                RenderMode::DynamicRendering(DynamicRendering {
                    color_attachment_format: format,
                    depth_attachment_format: None,
                    stencil_attachment_format: None,
                }),
                Options {
                    in_flight_frames: frames_in_flight,
                    // The swapchain is UNORM holding sRGB-encoded values.
                    srgb_framebuffer: false,
                    ..Default::default()
                },
            );
            let renderer = renderer.map_err(|e| anyhow::anyhow!("egui renderer: {e}"))?;
            let egui = egui::Context::default();
            let winit = egui_winit::State::new(
                egui.clone(),
                egui::ViewportId::ROOT,
                window,
                Some(window.scale_factor() as f32),
                None,
                None,
            );
            Ok(Overlay {
                ctx: ctx.clone(),
                egui,
                winit,
                renderer,
                pool,
                visible: true,
                primitives: Vec::new(),
                pixels_per_point: 1.0,
                to_free: Vec::new(),
                pending: None,
                compare_texture: None,
            })
        }

        pub fn toggle(&mut self) {
            self.visible = !self.visible;
        }

        pub fn visible(&self) -> bool {
            self.visible
        }

        /// Feeds a window event to egui; true when egui used it (the demo
        /// then leaves it alone: dragging a slider must not orbit).
        pub fn on_event(&mut self, window: &Window, event: &WindowEvent) -> bool {
            if !self.visible {
                return false;
            }
            let r = self.winit.on_window_event(window, event);
            let wants = match event {
                WindowEvent::KeyboardInput { .. } => self.egui.egui_wants_keyboard_input(),
                WindowEvent::MouseInput { .. } | WindowEvent::MouseWheel { .. } => {
                    self.egui.egui_wants_pointer_input()
                }
                _ => false,
            };
            r.consumed || wants
        }

        /// Runs the UI for this frame and uploads changed textures. Called
        /// before the frame is recorded, while earlier frames may still be
        /// in flight and sampling the UI's textures: freeing or replacing
        /// one (below) waits for the device first.
        pub fn prepare(&mut self, window: &Window, data: &UiData) -> anyhow::Result<Vec<Action>> {
            self.primitives.clear();
            if !self.to_free.is_empty() {
                // Rare (egui frees textures seldom): wait rather than track
                // which queued frame last drew with them.
                self.ctx.wait_idle();
                for id in &self.to_free {
                    self.renderer.free_texture(*id)?;
                }
                self.to_free.clear();
            }
            if !self.visible {
                return Ok(Vec::new());
            }
            let mut actions = Vec::new();
            let raw = self.winit.take_egui_input(window);
            let pending = &mut self.pending;
            let texture = &mut self.compare_texture;
            let mut output = self.egui.run_ui(raw, |ui| {
                compare_view(ui.ctx(), &data.compare, texture);
                panel(ui.ctx(), data, &mut actions, pending);
            });
            if let Some(p) = self.pending.take() {
                if self.egui.input(|i| i.pointer.any_down()) {
                    self.pending = Some(p);
                } else {
                    actions.push(Action::Params(p));
                }
            }
            self.winit
                .handle_platform_output(window, output.platform_output);
            self.pixels_per_point = output.pixels_per_point;
            // A whole-texture delta (no position: the first upload, or a
            // font atlas rebuilt after a DPI change) makes the renderer
            // destroy the old image at once; rare enough to wait for.
            if output
                .textures_delta
                .set
                .values()
                .flatten()
                .any(|d| d.pos.is_none())
            {
                self.ctx.wait_idle();
            }
            for (id, deltas) in &output.textures_delta.set {
                for delta in deltas {
                    self.renderer
                        .set_texture(self.ctx.queue, self.pool.raw, *id, delta)?;
                }
            }
            self.to_free
                .extend(output.textures_delta.free.iter().copied());
            // Applied above; egui 0.36 panics on dropping unapplied deltas.
            output.textures_delta.clear();
            self.primitives = self.egui.tessellate(output.shapes, output.pixels_per_point);
            Ok(actions)
        }

        /// Draws the prepared UI in the caller's rendering scope over the
        /// target image (egui's renderer records its own draws).
        pub fn record(
            &mut self,
            draws: &mut Rendering,
            extent: vk::Extent2D,
        ) -> anyhow::Result<()> {
            draws.third_party(|cmd| {
                self.renderer
                    .cmd_draw(cmd, extent, self.pixels_per_point, &self.primitives)
            })?;
            Ok(())
        }
    }

    /// The panel window's egui id (`panel_rect` looks its area up).
    const PANEL_ID: &str = "caustics panel";

    fn panel(
        ctx: &egui::Context,
        data: &UiData,
        actions: &mut Vec<Action>,
        pending: &mut Option<Params>,
    ) {
        egui::Window::new("caustics")
            .id(egui::Id::new(PANEL_ID))
            .default_pos([8.0, 8.0])
            .default_width(260.0)
            // The height follows the content, up to the screen's (the
            // scroll area below); the width stays the user's. Without the
            // default height egui would cap the content at 420 points.
            .resizable([true, false])
            .default_height(ctx.content_rect().height())
            .show(ctx, |ui| {
                // With every section shown the panel is taller than a
                // 480-pixel window: what does not fit between here and the
                // screen's bottom (less the window's margin) scrolls; a
                // tall enough screen shows it all.
                let room = ui.ctx().content_rect().bottom() - ui.cursor().top() - 12.0;
                egui::ScrollArea::vertical()
                    .max_height(room.max(64.0))
                    .show(ui, |ui| panel_contents(ui, data, actions, pending));
            });
    }

    /// The panel's sections, top to bottom.
    fn panel_contents(
        ui: &mut egui::Ui,
        data: &UiData,
        actions: &mut Vec<Action>,
        pending: &mut Option<Params>,
    ) {
        let mut chosen = data.technique;
        egui::ComboBox::from_label("technique")
            .selected_text(chosen)
            .show_ui(ui, |ui| {
                for t in TECHNIQUES {
                    ui.selectable_value(&mut chosen, t.name, t.name)
                        .on_hover_text(t.description);
                }
            });
        if chosen != data.technique {
            actions.push(Action::Technique(chosen));
        }
        // The current technique's values, by position in its specs (a
        // pending edit of another technique's is dropped).
        let current = pending
            .clone()
            .filter(|p| p.specs() == data.params.specs())
            .unwrap_or_else(|| data.params.clone());
        // The sliders edit typed values in a copy (`Params::set`).
        let mut next = current.clone();
        let mut edited = false;
        for (index, (spec, value)) in current.iter().enumerate() {
            let mut v = value;
            let mut slider = egui::Slider::new(&mut v, spec.min..=spec.max).text(spec.name);
            if spec.apply == Apply::Live {
                slider = slider.suffix(" (live)");
            }
            if spec.integer {
                slider = slider.integer();
            }
            if ui.add(slider).on_hover_text(spec.description).changed() {
                edited |= next.set(index, v).is_ok();
            }
        }
        if edited {
            *pending = Some(next);
        }
        components(ui, data, actions);
        medium(ui, data, actions);
        light_intensities(ui, data, actions);
        environment_rotation(ui, data, actions);
        compare_panel(ui, &data.compare, actions);
        ui.separator();
        egui::Grid::new("timings").striped(true).show(ui, |ui| {
            let mut total = 0.0;
            for t in data.timings {
                ui.label(&t.name);
                ui.label(format!("{:8.3} ms", t.ms));
                ui.end_row();
                total += t.ms;
            }
            ui.strong("total");
            ui.strong(format!("{total:8.3} ms"));
            ui.end_row();
        });
        ui.separator();
        frame_graph(ui, data.history_ms);
    }

    /// The panel laid out alone on a `width` x `height` (points) screen
    /// with `data`, after enough passes for egui to size the window: its
    /// rectangle as [left, top, right, bottom]. For tests/suite/overlay_layout.rs.
    pub fn panel_rect(data: &UiData, width: f32, height: f32) -> [f32; 4] {
        let screen = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(width, height));
        let egui = egui::Context::default();
        let (mut actions, mut pending) = (Vec::new(), None);
        // egui sizes a window from the previous pass's content.
        for _ in 0..4 {
            let raw = egui::RawInput {
                screen_rect: Some(screen),
                ..Default::default()
            };
            let mut output =
                egui.run_ui(raw, |ui| panel(ui.ctx(), data, &mut actions, &mut pending));
            // Nothing is drawn; egui panics on dropping unapplied deltas.
            output.textures_delta.clear();
        }
        let r = egui
            .memory(|m| m.area_rect(egui::Id::new(PANEL_ID)))
            .expect("the panel was laid out");
        [r.left(), r.top(), r.right(), r.bottom()]
    }

    /// One checkbox per component the technique renders.
    fn components(ui: &mut egui::Ui, data: &UiData, actions: &mut Vec<Action>) {
        ui.separator();
        ui.horizontal_wrapped(|ui| {
            ui.label("components (C)");
            let mut mask = data.component_mask;
            for c in data.components {
                let mut on = mask & c.mask() != 0;
                if ui.checkbox(&mut on, c.name()).changed() {
                    mask ^= c.mask();
                }
            }
            if mask != data.component_mask {
                actions.push(Action::Components(mask));
            }
        });
    }

    /// Three drag values for an RGB quantity; true when one changed.
    fn rgb(ui: &mut egui::Ui, label: &str, v: &mut [f32; 3], speed: f64, hover: &str) -> bool {
        let mut changed = false;
        ui.horizontal(|ui| {
            for c in v.iter_mut() {
                changed |= ui
                    .add(egui::DragValue::new(c).speed(speed).range(0.0..=1.0e6))
                    .on_hover_text(hover)
                    .changed();
            }
            ui.label(label);
        });
        changed
    }

    fn medium(ui: &mut egui::Ui, data: &UiData, actions: &mut Vec<Action>) {
        let Some(old) = data.medium else {
            return;
        };
        ui.separator();
        let mut m = old;
        rgb(
            ui,
            "σs (1/m)",
            &mut m.sigma_s,
            0.005,
            "scattering coefficient per channel",
        );
        rgb(
            ui,
            "σa (1/m)",
            &mut m.sigma_a,
            0.005,
            "absorption coefficient per channel",
        );
        ui.add(egui::Slider::new(&mut m.g, -0.99..=0.99).text("g"))
            .on_hover_text("Henyey-Greenstein anisotropy");
        if m != old {
            actions.push(Action::Medium(m));
        }
    }

    fn light_intensities(ui: &mut egui::Ui, data: &UiData, actions: &mut Vec<Action>) {
        ui.separator();
        for (light, old) in data.light_intensities.iter().enumerate() {
            let mut rgb_value = *old;
            let label = format!("light {light}");
            let hover = "intensity (W/sr; directional: irradiance, W/m²) per channel";
            if rgb(ui, &label, &mut rgb_value, 0.1, hover) {
                actions.push(Action::LightIntensity {
                    light,
                    rgb: rgb_value,
                });
            }
        }
    }

    /// The environment's rotation about +y, applied while dragging.
    fn environment_rotation(ui: &mut egui::Ui, data: &UiData, actions: &mut Vec<Action>) {
        let Some(old) = data.environment_rotate else {
            return;
        };
        ui.separator();
        let mut deg = old;
        ui.add(egui::Slider::new(&mut deg, -180.0..=180.0).text("environment rotate ([ ])"))
            .on_hover_text("degrees about +y: background, irradiance, sun and reflections follow");
        if deg != old {
            actions.push(Action::EnvironmentRotation(deg));
        }
    }

    /// The compare panel: snapshot, its progress and FLIP mean, the view.
    fn compare_panel(ui: &mut egui::Ui, c: &CompareStatus, actions: &mut Vec<Action>) {
        ui.separator();
        ui.horizontal(|ui| {
            ui.strong("compare");
            if ui
                .button("snapshot")
                .on_hover_text(
                    "trace a reference of this view (scene, time, camera) at the window's size; \
                     pauses the animation",
                )
                .clicked()
            {
                actions.push(Action::CompareStart);
            }
            if c.passes.is_some() && ui.button("discard").clicked() {
                actions.push(Action::CompareDiscard);
            }
        });
        match c.passes {
            None => {
                ui.label("no snapshot");
            }
            Some(passes) => {
                ui.label(format!(
                    "reference {}x{} ({}): {passes} passes, {:.2} M photons",
                    c.size.0,
                    c.size.1,
                    c.component,
                    c.photons as f64 / 1e6
                ));
                ui.label(match c.flip_mean {
                    Some(f) => format!("FLIP mean (live vs reference): {f:.4}"),
                    None => "FLIP mean: after the first pass".to_owned(),
                });
            }
        }
        ui.horizontal(|ui| {
            let mut view = c.view;
            for v in View::ALL {
                ui.radio_value(&mut view, v, v.name());
            }
            if view != c.view {
                actions.push(Action::CompareView(view));
            }
        });
        ui.small(
            "One reference pass runs per live frame: on lavapipe (CPU Vulkan) the live \
             frame rate drops while it runs. Moving the camera, time, technique, \
             parameters, components, window size or scene discards the snapshot.",
        );
    }

    /// The reference or FLIP map over the whole window, under the panel
    /// (the live view draws nothing here). The texture is re-uploaded when
    /// the snapshot's images change.
    fn compare_view(
        ctx: &egui::Context,
        c: &CompareStatus,
        texture: &mut Option<(egui::TextureHandle, u64)>,
    ) {
        let Some((rgba, generation)) = c.image else {
            return;
        };
        let key = generation * 3 + c.view as u64;
        let image = || {
            let size = [c.size.0 as usize, c.size.1 as usize];
            egui::ColorImage::from_rgba_unmultiplied(size, rgba)
        };
        match texture {
            Some((_, shown)) if *shown == key => {}
            Some((handle, shown)) => {
                handle.set(image(), egui::TextureOptions::NEAREST);
                *shown = key;
            }
            None => {
                let handle = ctx.load_texture("compare", image(), egui::TextureOptions::NEAREST);
                *texture = Some((handle, key));
            }
        }
        let Some((handle, _)) = texture.as_ref() else {
            return;
        };
        let painter = ctx.layer_painter(egui::LayerId::background());
        painter.image(
            handle.id(),
            ctx.content_rect(),
            egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
            egui::Color32::WHITE,
        );
    }

    /// Frame intervals as a polyline, scaled to the largest recent one.
    fn frame_graph(ui: &mut egui::Ui, history: &[f32]) {
        let max = history.iter().copied().fold(1.0f32, f32::max);
        ui.label(format!(
            "frame time, last {} frames (max {:.1} ms)",
            history.len(),
            max
        ));
        let (rect, _) =
            ui.allocate_exact_size(egui::vec2(ui.available_width(), 60.0), egui::Sense::hover());
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 2.0, egui::Color32::from_black_alpha(96));
        if history.len() < 2 {
            return;
        }
        let n = (history.len() - 1) as f32;
        let points: Vec<egui::Pos2> = history
            .iter()
            .enumerate()
            .map(|(i, ms)| {
                egui::pos2(
                    rect.left() + rect.width() * i as f32 / n,
                    rect.bottom() - rect.height() * (ms / max),
                )
            })
            .collect();
        painter.add(egui::Shape::line(
            points,
            egui::Stroke::new(1.5, egui::Color32::LIGHT_GREEN),
        ));
    }
}
