//! The overlay's compare panel: a reference snapshot of the current view
//! (`ReferenceRenderer` for the demo's scene, time and camera at the
//! window's size), traced one pass per live frame and compared with the live
//! frame by the same driver as `caustics compare` (`compare::driver`:
//! `LiveReference`; the metrics are src/compare/metrics.rs: the CPU display
//! transform, LDR-FLIP and its magma error map).
//!
//! Synchronisation: a reference pass is its own submission on the demo's
//! queue (`Profiler::frame` submits and waits for that submission's fence),
//! into the snapshot's own scene buffers and images, which no live frame
//! touches; the live radiance is read back with `Renderer::radiance`, whose
//! copy is queued after the frames in flight. So the live frames in flight
//! need no extra wait, and the snapshot is dropped with all its work done.
//!
//! Any change of what the snapshot shows (camera, time, technique or its
//! parameters, drawn components, window size, scene edits) discards it.

use crate::compare::driver::{self, LiveReference};
use crate::compare::metrics;
use crate::renderer::Renderer;
use crate::scene::Camera;
use crate::vk::Context;
use std::sync::Arc;

/// What the window shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    Live,
    Reference,
    Flip,
}

impl View {
    pub const ALL: [View; 3] = [View::Live, View::Reference, View::Flip];

    pub fn name(self) -> &'static str {
        match self {
            View::Live => "live",
            View::Reference => "reference",
            View::Flip => "FLIP",
        }
    }
}

/// What the snapshot was taken of; any difference discards it.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct ViewKey {
    pub(super) camera: Camera,
    pub(super) time: f32,
    pub(super) technique: &'static str,
    pub(super) params: String,
    pub(super) components: u32,
    pub(super) size: (u32, u32),
    /// `State::scene_edits`: lights, medium, environment or a reload.
    pub(super) scene_edits: u64,
}

impl ViewKey {
    pub(super) fn of(renderer: &Renderer, time: f32, scene_edits: u64) -> Self {
        ViewKey {
            camera: renderer.scene.camera,
            time,
            technique: renderer.technique_name(),
            params: format!("{:?}", renderer.params()),
            components: renderer.scene_gpu.components,
            size: (renderer.targets.width, renderer.targets.height),
            scene_edits,
        }
    }

    /// What changed between the snapshot's view and `now`, for the log.
    fn change(&self, now: &ViewKey) -> &'static str {
        if self.camera != now.camera {
            "camera moved"
        } else if self.time != now.time {
            "time changed"
        } else if self.technique != now.technique || self.params != now.params {
            "technique changed"
        } else if self.components != now.components {
            "components changed"
        } else if self.size != now.size {
            "window resized"
        } else {
            "scene edited"
        }
    }
}

/// A snapshot in progress: the reference, the last comparison and the image
/// the chosen view shows.
pub(super) struct Snapshot {
    key: ViewKey,
    /// Resolves the component the live frame draws alone, else all.
    reference: LiveReference,
    pub(super) flip_mean: Option<f32>,
    /// RGBA8 of the reference (tonemapped) and of the FLIP map (magma).
    reference_rgba: Vec<u8>,
    flip_rgba: Vec<u8>,
    /// Counts the images' updates (the overlay re-uploads on a change).
    pub(super) generation: u64,
}

impl Snapshot {
    pub(super) fn passes(&self) -> u64 {
        self.reference.passes()
    }
}

/// The compare panel's state, owned by the window's `State`.
pub(super) struct Compare {
    pub(super) view: View,
    pub(super) snapshot: Option<Snapshot>,
}

/// What the overlay reads of the compare panel.
#[cfg_attr(not(feature = "overlay"), allow(dead_code))]
pub struct CompareStatus<'a> {
    pub view: View,
    /// None without a snapshot.
    pub passes: Option<u64>,
    pub photons: u64,
    pub flip_mean: Option<f32>,
    pub size: (u32, u32),
    /// The component the reference resolves (`Component::name`).
    pub component: &'static str,
    /// The image of `view` (RGBA8, `size`), None for the live view.
    pub image: Option<(&'a [u8], u64)>,
}

impl Compare {
    pub(super) fn new() -> Self {
        Compare {
            view: View::Live,
            snapshot: None,
        }
    }

    /// Starts a snapshot of the live renderer's current view.
    pub(super) fn start(
        &mut self,
        ctx: &Arc<Context>,
        renderer: &Renderer,
        key: ViewKey,
    ) -> anyhow::Result<()> {
        self.snapshot = None;
        let (width, height) = key.size;
        let component = driver::component_drawn(renderer.technique_info(), key.components);
        let view = driver::View {
            width,
            height,
            time: key.time,
            diffuse_bounces: 0,
        };
        let reference = LiveReference::new(ctx, &renderer.scene, view, component)?;
        println!(
            "compare: snapshot {width}x{height} at t = {:.2} s, {} ({})",
            key.time,
            key.technique,
            component.name()
        );
        self.snapshot = Some(Snapshot {
            key,
            reference,
            flip_mean: None,
            reference_rgba: Vec::new(),
            flip_rgba: Vec::new(),
            generation: 0,
        });
        Ok(())
    }

    pub(super) fn discard(&mut self, why: &str) {
        if self.snapshot.take().is_some() {
            println!("compare: snapshot discarded ({why})");
        }
    }

    /// Discards the snapshot if the view changed, else traces one more
    /// reference pass and compares the live frame with the reference.
    pub(super) fn step(&mut self, renderer: &Renderer, now: &ViewKey) -> anyhow::Result<()> {
        let Some(s) = self.snapshot.as_ref() else {
            return Ok(());
        };
        if s.key != *now {
            let why = s.key.change(now);
            self.discard(why);
            return Ok(());
        }
        let s = self.snapshot.as_mut().expect("snapshot");
        let live = renderer.radiance()?;
        let (w, h) = s.key.size;
        let exposure = renderer.scene.output.exposure;
        let judged = s.reference.refine(&live, exposure)?;
        s.reference_rgba = metrics::tonemap(&judged.reference, exposure);
        s.flip_rgba = metrics::rgba8(&judged.map.magma_rgb8());
        s.flip_mean = Some(judged.metrics.flip);
        s.generation += 1;
        println!(
            "compare: pass {}, {} photons, FLIP mean {:.4} (live vs reference, {w}x{h})",
            s.reference.passes(),
            s.reference.photons(),
            judged.metrics.flip
        );
        Ok(())
    }

    pub(super) fn set_view(&mut self, view: View) {
        if view != self.view {
            self.view = view;
            println!("compare: view {}", view.name());
        }
    }

    pub(super) fn status(&self) -> CompareStatus<'_> {
        let s = self.snapshot.as_ref();
        let image = s.and_then(|s| {
            let rgba = match self.view {
                View::Live => return None,
                View::Reference => &s.reference_rgba,
                View::Flip => &s.flip_rgba,
            };
            (!rgba.is_empty()).then_some((rgba.as_slice(), s.generation))
        });
        CompareStatus {
            view: self.view,
            passes: s.map(|s| s.reference.passes()),
            photons: s.map_or(0, |s| s.reference.photons()),
            flip_mean: s.and_then(|s| s.flip_mean),
            size: s.map_or((0, 0), |s| s.key.size),
            component: s.map_or("all", |s| s.reference.component().name()),
            image,
        }
    }
}
