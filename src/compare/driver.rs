//! The comparison against the ground truth, driven once for both front
//! ends: `caustics compare` (src/cli/compare.rs: progress, files, the
//! contact sheet) and the demo's compare panel (src/app/compare.rs: a
//! snapshot of the window's view). Here: the reference's budget and its
//! cache, a technique's components and timed frames, and the metrics of
//! each (`metrics`, the tests' code path).

use super::metrics::{self, FlipMap, Metrics};
use super::report::{
    pass_stats, ComponentResult, NotApplicable, ReferenceInfo, TechniqueResult, Timing,
};
use super::{cache_key, ReferenceKey};
use crate::output;
use crate::params::Params;
use crate::reference::{Component, ReferenceRenderer, ReferenceSettings};
use crate::renderer::Renderer;
use crate::scene::Scene;
use crate::techniques::{self, TechniqueInfo};
use crate::vk::{Context, FrameOptions};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// The photons a comparison traces by default: 2^23, 32 passes.
pub const DEFAULT_PHOTONS: u64 = 1 << 23;

/// What the reference traces: photons (whole passes), or seconds of passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    Photons(u64),
    Seconds(f64),
}

/// Runs reference passes until `photons` are traced or `seconds` have
/// passed (the front end's progress display); returns whether a signal cut
/// it short.
pub type TraceFn<'a> =
    dyn FnMut(&mut ReferenceRenderer, u64, Option<f64>) -> anyhow::Result<bool> + 'a;

/// A comparison's image size, animation time and reference photon paths.
#[derive(Clone, Copy, Debug)]
pub struct View {
    pub width: u32,
    pub height: u32,
    pub time: f32,
    /// Diffuse bounces the reference's photons continue through.
    pub diffuse_bounces: u32,
}

/// The reference's images: the full frame, each path-type component (none
/// from a file) and the first half-run's full frame (for its noise).
pub struct ReferenceImages {
    pub all: Vec<f32>,
    pub components: Vec<(Component, Vec<f32>)>,
    pub first_half: Option<Vec<f32>>,
    pub info: ReferenceInfo,
}

/// Components a reference run resolves (everything but `All`).
pub fn reference_components() -> Vec<Component> {
    Component::NAMED
        .iter()
        .map(|(_, c)| *c)
        .filter(|c| *c != Component::All)
        .collect()
}

/// The cache folder for references: `references` in
/// [`crate::cache_dir::cache_dir`]; None without one.
pub fn cache_root() -> Option<PathBuf> {
    Some(crate::cache_dir::cache_dir()?.join("references"))
}

impl ReferenceImages {
    /// A reference read from an EXR (`--reference`): the full frame only.
    pub fn from_file(all: Vec<f32>, path: &Path, diffuse_bounces: u32) -> Self {
        ReferenceImages {
            all,
            components: Vec::new(),
            first_half: None,
            info: ReferenceInfo {
                source: "file".into(),
                path: Some(path.display().to_string()),
                photons: 0,
                passes: 0,
                trace_seconds: 0.0,
                diffuse_bounces,
                noise: None,
            },
        }
    }

    /// The reference of `scene` from the cache under `cache` (None: no
    /// cache), else traced by `trace` in two equal half-runs (whose
    /// difference is its noise) and then cached. A half-run cut short by a
    /// signal is an error: a reference short of its budget would be cached
    /// under the full budget's key.
    pub fn cached_or_traced(
        ctx: &Arc<Context>,
        scene: &Scene,
        view: View,
        budget: Budget,
        cache: Option<&Path>,
        trace: &mut TraceFn,
    ) -> anyhow::Result<Self> {
        let (width, height) = (view.width, view.height);
        let settings = ReferenceSettings {
            diffuse_bounces: view.diffuse_bounces,
            ..Default::default()
        };
        let key = ReferenceKey {
            width,
            height,
            time: view.time,
            diffuse_bounces: view.diffuse_bounces,
            budget: match budget {
                Budget::Photons(n) => format!("photons {n}"),
                // What S seconds trace depends on the device.
                Budget::Seconds(s) => format!("seconds {s} on {}", ctx.info.name),
            },
            settings: format!("{settings:?}"),
        };
        let folder = cache.map(|root| root.join(cache_key(scene, &key)));
        if let Some(dir) = &folder {
            if let Some(images) = read_cached(dir, width, height)? {
                println!("reference from the cache: {}", dir.display());
                return Ok(images);
            }
        }
        let mut r = ReferenceRenderer::new(ctx, scene.clone(), width, height, view.time, settings)?;
        // Whole passes, so the second half stops at exactly twice the
        // first's photons.
        let interrupted = match budget {
            Budget::Seconds(s) => trace(&mut r, 0, Some(s / 2.0))?,
            Budget::Photons(n) => trace(&mut r, (n / 2).max(1), None)?,
        };
        let first_half = r.resolve(Component::All)?;
        let half_photons = r.photons();
        if interrupted || trace(&mut r, 2 * half_photons, None)? {
            anyhow::bail!("interrupted while tracing the reference; nothing written");
        }
        let all = r.resolve(Component::All)?;
        let mut components = Vec::new();
        for c in reference_components() {
            components.push((c, r.resolve(c)?));
        }
        let info = ReferenceInfo {
            source: "traced".into(),
            path: folder.as_ref().map(|d| d.display().to_string()),
            photons: r.photons(),
            passes: r.passes(),
            trace_seconds: r.trace_seconds,
            diffuse_bounces: view.diffuse_bounces,
            noise: None,
        };
        drop(r);
        let images = ReferenceImages {
            all,
            components,
            first_half: Some(first_half),
            info,
        };
        if let Some(dir) = &folder {
            if let Err(e) = write_cache(dir, &images, width, height) {
                eprintln!(
                    "warning: could not cache the reference in {}: {e:#}",
                    dir.display()
                );
            }
        }
        Ok(images)
    }

    /// The reference's own noise: its second half-run against its first
    /// (frees the first); None for a reference read from a file. Also
    /// recorded in `info.noise`.
    pub fn measure_noise(
        &mut self,
        width: u32,
        height: u32,
        exposure: f32,
    ) -> Option<(Metrics, FlipMap)> {
        let half = self.first_half.take()?;
        let second = metrics::second_half(&self.all, &half);
        let (m, map) = metrics::compare(&second, &half, width, height, exposure);
        self.info.noise = Some(m);
        Some((m, map))
    }

    fn component(&self, c: Component) -> Option<&[f32]> {
        self.components
            .iter()
            .find(|(rc, _)| *rc == c)
            .map(|(_, img)| img.as_slice())
    }
}

/// Reads a cached reference; None when the folder is absent or incomplete.
fn read_cached(dir: &Path, width: u32, height: u32) -> anyhow::Result<Option<ReferenceImages>> {
    let Ok(text) = std::fs::read_to_string(dir.join("info.json")) else {
        return Ok(None);
    };
    let mut info: ReferenceInfo = match serde_json::from_str(&text) {
        Ok(i) => i,
        Err(_) => return Ok(None),
    };
    let read = |name: &str| -> Option<Vec<f32>> {
        let (w, h, rgba) = output::read_exr(&dir.join(format!("{name}.exr"))).ok()?;
        ((w, h) == (width, height)).then_some(rgba)
    };
    let (Some(all), Some(first_half)) = (read("all"), read("first_half")) else {
        return Ok(None);
    };
    let mut components = Vec::new();
    for c in reference_components() {
        let Some(img) = read(c.name()) else {
            return Ok(None);
        };
        components.push((c, img));
    }
    info.source = "cache".into();
    Ok(Some(ReferenceImages {
        all,
        components,
        first_half: Some(first_half),
        info,
    }))
}

/// Writes a traced reference into the cache: the images first, info.json
/// last (a folder without it is incomplete and traced again).
fn write_cache(
    dir: &Path,
    images: &ReferenceImages,
    width: u32,
    height: u32,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)?;
    output::write_exr(&dir.join("all.exr"), width, height, &images.all)?;
    if let Some(half) = &images.first_half {
        output::write_exr(&dir.join("first_half.exr"), width, height, half)?;
    }
    for (c, img) in &images.components {
        output::write_exr(&dir.join(format!("{}.exr", c.name())), width, height, img)?;
    }
    std::fs::write(
        dir.join("info.json"),
        serde_json::to_string_pretty(&images.info)?,
    )?;
    Ok(())
}

/// Where a comparison puts the images it makes, as it makes them (the CLI
/// writes files; a caller that keeps nothing ignores them).
pub trait ImageSink {
    /// A radiance image (RGBA f32) named `stem`.
    fn radiance(&mut self, stem: &str, rgba: &[f32]) -> anyhow::Result<()>;
    /// A FLIP error map named `stem`.
    fn flip_map(&mut self, stem: &str, map: &FlipMap) -> anyhow::Result<()>;
}

/// One technique judged: its numbers, its full frame and that frame's FLIP map.
pub struct Judged {
    pub result: TechniqueResult,
    pub image: Vec<f32>,
    pub map: FlipMap,
    /// What timed its passes (`FrameTimer::describe`).
    pub timing_source: String,
}

/// Renders technique `name` with its default parameters: each of its
/// components (which also warm up every pass) against the reference's
/// matching component (a component the scene has more of than the
/// technique models is listed as not applicable instead), then `frames` timed full frames, the last against
/// the reference's full frame. Each image goes to `sink` as it is made.
/// `Ok(Err(reason))` when the technique does not take the scene (its
/// scene check refused it); an error of `Renderer::new` carries its
/// `renderer::Stage`.
pub fn judge_technique(
    ctx: &Arc<Context>,
    scene: &Scene,
    name: &str,
    view: View,
    frames: u32,
    reference: &ReferenceImages,
    sink: &mut dyn ImageSink,
) -> anyhow::Result<Result<Judged, String>> {
    let (width, height, time) = (view.width, view.height, view.time);
    let exposure = scene.output.exposure;
    let info = techniques::find(name)?;
    let params = Params::resolve(name, info.params(), &[])?;
    if let Err(e) = (info.check_scene)(scene) {
        return Ok(Err(format!("{e:#}")));
    }
    let mut r = Renderer::new(ctx, scene.clone(), name, &params, width, height, time)?;
    r.set_frame_options(FrameOptions::default())?;
    let timing_source = r.frames.source.describe().to_string();
    // Each component's frame first, all at the comparison's time. Together
    // they run every pass once (a technique skips in a component's frame
    // only the passes of the components it does not draw,
    // `SceneGpu::draws`), so they are the warm-up (pipeline compilation)
    // the timed frames need; a separate warm-up frame only without them.
    let mut components = Vec::new();
    let mut not_applicable = Vec::new();
    // The technique's own images of the components it is not scored on,
    // taken out of its frame for the `modelled` comparison.
    let mut unscored_images = Vec::new();
    for &c in info.components {
        r.scene_gpu.components = c.mask();
        r.render_frame(time)?;
        let img = r.radiance()?;
        sink.radiance(&format!("{name}_{}", c.name()), &img)?;
        let Some(truth) = reference.component(c) else {
            continue;
        };
        // `other` also holds diffuse interreflection, which no technique
        // draws, once the reference's photons bounce off diffuse surfaces.
        let interreflection = (c == Component::Other && view.diffuse_bounces > 0).then(|| {
            format!(
                "{name} draws no diffuse interreflection, which `other` holds with {} diffuse bounces",
                view.diffuse_bounces
            )
        });
        if let Some(reason) = info.not_modelled(scene, c).or(interreflection) {
            // Not a gap where the reference has (next to) no light either.
            if holds_light(truth, &reference.all) {
                not_applicable.push(NotApplicable {
                    component: c.name().into(),
                    reason,
                });
                unscored_images.push(img);
            }
            continue;
        }
        let (m, cmap) = metrics::compare(&img, truth, width, height, exposure);
        sink.flip_map(&format!("{name}_{}_flip", c.name()), &cmap)?;
        components.push(ComponentResult {
            component: c.name().into(),
            metrics: m,
        });
    }
    // Light of the reference in components the technique has no image of
    // (image_space's airlight in fog, every technique's `other`: multiple
    // scattering in media).
    for (c, truth) in &reference.components {
        if !info.components.contains(c) && holds_light(truth, &reference.all) {
            not_applicable.push(NotApplicable {
                component: c.name().into(),
                reason: format!("{name} does not render {}", c.name()),
            });
        }
    }
    r.scene_gpu.components = Component::All.mask();
    if info.components.is_empty() {
        r.render_frame(time)?;
    }
    // The timed frames; the last one is the image compared.
    let start = Instant::now();
    for _ in 0..frames {
        r.submit_frame(time)?;
    }
    let done = r.finish()?;
    let timing = Timing {
        frames,
        frame_ms: start.elapsed().as_secs_f64() * 1e3 / frames as f64,
        passes_ms: pass_stats(&done),
    };
    let image = r.radiance()?;
    drop(r);
    let (full, map) = metrics::compare(&image, &reference.all, width, height, exposure);
    // Both frames without the components not scored: what the technique
    // claims to render, against the reference's matching components.
    // The truth is the sum of the reference's scored components, not `all`
    // less the others: where those are black (`direct` under the water of
    // `pool_shafts`) the subtraction's rounding residue read "energy -100%".
    let modelled = (!not_applicable.is_empty()).then(|| {
        let unscored = |c: Component| not_applicable.iter().any(|n| n.component == c.name());
        // rgb summed, alpha as `all`'s.
        let mut truth: Vec<f32> = reference
            .all
            .iter()
            .enumerate()
            .map(|(i, &a)| if i % 4 == 3 { a } else { 0.0 })
            .collect();
        for (c, img) in reference.components.iter().filter(|(c, _)| !unscored(*c)) {
            debug_assert_ne!(*c, Component::All);
            for (i, (t, v)) in truth.iter_mut().zip(img).enumerate() {
                if i % 4 != 3 {
                    *t += v;
                }
            }
        }
        let ours = without(&image, unscored_images.iter().map(Vec::as_slice));
        metrics::compare(&ours, &truth, width, height, exposure).0
    });
    sink.radiance(name, &image)?;
    sink.flip_map(&format!("{name}_flip"), &map)?;
    let result = TechniqueResult {
        technique: name.into(),
        params: params
            .iter()
            .map(|(s, v)| (s.name.to_string(), v))
            .collect(),
        timing,
        full,
        modelled,
        components,
        not_applicable,
    };
    Ok(Ok(Judged {
        result,
        image,
        map,
        timing_source,
    }))
}

/// Whether a reference component holds more than 0.1% of the frame's
/// light (a scene without media has exactly none in airlight; the noise
/// of a few stray paths is not a component to claim).
fn holds_light(component: &[f32], all: &[f32]) -> bool {
    metrics::energy(component) > 1e-3 * metrics::energy(all)
}

/// `frame` less each of `parts` (RGBA, the rgb channels; alpha kept).
fn without<'a>(frame: &[f32], parts: impl Iterator<Item = &'a [f32]>) -> Vec<f32> {
    let mut out = frame.to_vec();
    for part in parts {
        for (i, (o, p)) in out.iter_mut().zip(part).enumerate() {
            if i % 4 != 3 {
                *o -= p;
            }
        }
    }
    out
}

/// The component a live frame shows when it draws the components `mask`:
/// the technique's component with that mask, else the full frame.
pub fn component_drawn(info: &TechniqueInfo, mask: u32) -> Component {
    info.components
        .iter()
        .copied()
        .find(|c| c.mask() == mask)
        .unwrap_or(Component::All)
}

/// A reference refined a pass at a time beside a live view (the demo's
/// compare panel): each `refine` traces one more pass and judges the live
/// frame against the reference so far.
pub struct LiveReference {
    renderer: ReferenceRenderer,
    component: Component,
}

/// One `LiveReference::refine`: the reference so far and the live frame
/// against it.
pub struct LiveJudgement {
    pub reference: Vec<f32>,
    pub metrics: Metrics,
    pub map: FlipMap,
}

impl LiveReference {
    /// Photons per pass: a quarter of `caustics reference`'s, so that one
    /// pass per live frame keeps a window responsive.
    pub const PHOTONS_PER_PASS: u32 = 1 << 16;

    /// The reference of `scene` as `view` shows it, resolving `component`.
    pub fn new(
        ctx: &Arc<Context>,
        scene: &Scene,
        view: View,
        component: Component,
    ) -> anyhow::Result<Self> {
        let settings = ReferenceSettings {
            batch: Self::PHOTONS_PER_PASS,
            diffuse_bounces: view.diffuse_bounces,
            ..ReferenceSettings::default()
        };
        let renderer = ReferenceRenderer::new(
            ctx,
            scene.clone(),
            view.width,
            view.height,
            view.time,
            settings,
        )?;
        Ok(LiveReference {
            renderer,
            component,
        })
    }

    /// Traces one more pass and compares `live` (RGBA radiance of the same
    /// view) with the reference so far.
    pub fn refine(&mut self, live: &[f32], exposure: f32) -> anyhow::Result<LiveJudgement> {
        self.renderer.pass()?;
        let reference = self.renderer.resolve(self.component)?;
        let (width, height) = (self.renderer.targets.width, self.renderer.targets.height);
        let (metrics, map) = metrics::compare(live, &reference, width, height, exposure);
        Ok(LiveJudgement {
            reference,
            metrics,
            map,
        })
    }

    pub fn component(&self) -> Component {
        self.component
    }

    pub fn passes(&self) -> u64 {
        self.renderer.passes()
    }

    pub fn photons(&self) -> u64 {
        self.renderer.photons()
    }
}
