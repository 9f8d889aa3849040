//! `caustics compare`: every applicable technique against the ground truth
//! in one command (docs/REPORTS.md). The reference is traced (two equal
//! half-runs, whose difference is its own noise), taken from the cache, or
//! read from `--reference`; each technique renders each of its components
//! (which warm it up) and then its full frame, timed over `--frames`; the
//! metrics are the tests' (`caustics::compare::metrics`). Each file is written as soon as it is
//! made, to a temporary renamed into place with all the others at the end
//! (`output::Batch`; removed on SIGINT/SIGTERM or an error), report.json
//! last, so a failed or interrupted run leaves none of its files. What
//! stays in memory is what the rest of the run needs: the reference and
//! its components (every technique is measured against them), the contact
//! sheet's thumbnails (`sheet::thumbnail`) and the numbers; a technique's
//! images are dropped once written and measured.

use super::reference::trace_reference;
use super::{check_size, check_validation, context, load_scene, CompareArgs};
use anyhow::Context as _;
use caustics::compare::metrics::{self, FlipMap};
use caustics::compare::report::{
    pass_stats, signed_percent, CompareReport, ComponentResult, ReferenceInfo, RunInfo, Skipped,
    TechniqueResult, Timing, SCHEMA,
};
use caustics::compare::sheet::{self, Tile};
use caustics::compare::{cache_key, ReferenceKey};
use caustics::output;
use caustics::output::{Batch, OutputFile};
use caustics::params::Params;
use caustics::reference::{Component, ReferenceRenderer, ReferenceSettings};
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::techniques::{self, TECHNIQUES};
use caustics::vk::{Context, FrameOptions};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// The photons a comparison traces by default: 2^23, 32 passes.
pub const DEFAULT_PHOTONS: u64 = 1 << 23;

/// The reference's images: the full frame, each path-type component
/// (none from a file) and the first half-run's full frame (for its noise).
struct ReferenceImages {
    all: Vec<f32>,
    components: Vec<(Component, Vec<f32>)>,
    first_half: Option<Vec<f32>>,
    info: ReferenceInfo,
}

/// Components a reference run resolves (everything but `All`).
fn reference_components() -> Vec<Component> {
    Component::NAMED
        .iter()
        .map(|(_, c)| *c)
        .filter(|c| *c != Component::All)
        .collect()
}

pub fn compare(args: CompareArgs) -> anyhow::Result<()> {
    check_size(&args.scene)?;
    let (width, height, time) = (args.scene.width, args.scene.height, args.scene.time);
    if args.frames == 0 {
        anyhow::bail!("--frames must be at least 1");
    }
    if let Some(photons) = args.photons {
        super::check_photons(photons)?;
    }
    if let Some(s) = args.reference_time {
        if !(s.is_finite() && s > 0.0) {
            anyhow::bail!("--reference-time must be a positive number of seconds, got {s}");
        }
    }
    let names = technique_names(&args.techniques)?;
    let from_file = match &args.reference {
        Some(path) => {
            let (w, h, rgba) = output::read_exr(path).context("--reference")?;
            if (w, h) != (width, height) {
                anyhow::bail!(
                    "--reference {}: the image is {w}x{h}, the comparison {width}x{height} (set --width and --height)",
                    path.display()
                );
            }
            Some(rgba)
        }
        None => None,
    };
    let scene = load_scene(&args.scene.file, time)?;
    let exposure = scene.output.exposure;
    if args.out.exists() && !args.out.is_dir() {
        anyhow::bail!("--out {}: not a folder", args.out.display());
    }
    output::check_writable(&args.out.join("report.json"), "--out")?;
    let mut staging = Outputs::new(&args.out);
    let ctx = context(&args.device)?;

    let mut reference = match from_file {
        Some(all) => ReferenceImages {
            all,
            components: Vec::new(),
            first_half: None,
            info: ReferenceInfo {
                source: "file".into(),
                path: args.reference.as_ref().map(|p| p.display().to_string()),
                photons: 0,
                passes: 0,
                trace_seconds: 0.0,
                diffuse_bounces: args.diffuse_bounces,
                noise: None,
            },
        },
        None => reference_images(&ctx, &scene, &args)?,
    };
    staging.write_pair("reference", width, height, &reference.all, exposure)?;
    for (c, img) in &reference.components {
        staging.write_pair(
            &format!("reference_{}", c.name()),
            width,
            height,
            img,
            exposure,
        )?;
    }
    let mut info = reference.info.clone();
    let mut tiles = vec![vec![Tile {
        rgb: thumbnail_of(&reference.all, width, height, exposure),
        lines: vec!["reference".into(), format!("{} photons", info.photons)],
    }]];
    // The first half-run is needed for the noise only.
    if let Some(half) = reference.first_half.take() {
        let second = metrics::second_half(&reference.all, &half);
        let (m, map) = metrics::compare(&second, &half, width, height, exposure);
        staging.write_map("reference_noise_flip", &map)?;
        tiles[0].push(Tile {
            rgb: sheet::thumbnail(map.magma_rgb8(), width, height),
            lines: vec!["its noise".into(), format!("FLIP {:.4}", m.flip)],
        });
        info.noise = Some(m);
    }

    let mut results = Vec::new();
    let mut skipped = Vec::new();
    let bar = indicatif::ProgressBar::new(names.len() as u64).with_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} techniques {msg}")
            .context("progress style")?,
    );
    let mut timing_source = None;
    for name in &names {
        bar.set_message(name.to_string());
        match run_technique(
            &ctx,
            &scene,
            name,
            &args,
            &reference,
            &mut staging,
            &mut timing_source,
        )? {
            Ok((result, [image, map])) => {
                let label = vec![
                    name.to_string(),
                    format!("FLIP {:.4}", result.full.flip),
                    format!("E {}", signed_percent(result.full.energy)),
                    format!("{:.1} ms", result.timing.frame_ms),
                ];
                tiles.push(vec![
                    Tile {
                        rgb: image,
                        lines: label,
                    },
                    Tile {
                        rgb: map,
                        lines: vec![format!("{name} error")],
                    },
                ]);
                results.push(result);
            }
            Err(reason) => skipped.push(Skipped {
                technique: name.to_string(),
                reason,
            }),
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let (tile_w, tile_h) = sheet::tile_size(width, height);
    let contact = sheet::compose(&tiles, tile_w, tile_h);
    staging.write_rgb("contact_sheet", contact.width, contact.height, contact.rgb)?;

    let report = CompareReport {
        run: RunInfo {
            schema: SCHEMA.into(),
            device: ctx.info.name.clone(),
            driver: ctx.info.driver.trim().to_string(),
            timing_source: timing_source.unwrap_or_else(|| "none (no technique ran)".into()),
            scene: args.scene.file.scene.display().to_string(),
            width,
            height,
            time,
        },
        exposure,
        reference: info,
        techniques: results,
        skipped,
    };
    staging.write_text("report.md", &report.markdown())?;
    staging.write_text("report.json", &serde_json::to_string_pretty(&report)?)?;
    check_validation(ctx)?;
    let moved = staging.commit()?;
    for t in &report.techniques {
        println!(
            "{:<16} FLIP {:.4}  energy {}  {:.2} ms/frame",
            t.technique,
            t.full.flip,
            signed_percent(t.full.energy),
            t.timing.frame_ms
        );
    }
    for s in &report.skipped {
        println!("{:<16} skipped: {}", s.technique, s.reason);
    }
    println!("wrote {moved} files to {}", args.out.display());
    Ok(())
}

/// `all` or a comma-separated list of registered technique names.
fn technique_names(list: &str) -> anyhow::Result<Vec<&'static str>> {
    if list == "all" {
        return Ok(TECHNIQUES.iter().map(|t| t.name).collect());
    }
    let mut names: Vec<&'static str> = Vec::new();
    for n in list.split(',') {
        let name = techniques::find(n.trim()).context("--techniques")?.name;
        if !names.contains(&name) {
            names.push(name);
        }
    }
    Ok(names)
}

/// The cache folder for references: `references` in
/// [`caustics::cache_dir::cache_dir`]; None without one.
fn cache_root() -> Option<PathBuf> {
    Some(caustics::cache_dir::cache_dir()?.join("references"))
}

/// The reference from the cache, or traced (and then cached).
fn reference_images(
    ctx: &Arc<Context>,
    scene: &Scene,
    args: &CompareArgs,
) -> anyhow::Result<ReferenceImages> {
    let (width, height) = (args.scene.width, args.scene.height);
    let budget = match args.reference_time {
        Some(s) => format!("seconds {s} on {}", ctx.info.name),
        None => format!("photons {}", args.photons.unwrap_or(DEFAULT_PHOTONS)),
    };
    let settings = ReferenceSettings {
        diffuse_bounces: args.diffuse_bounces,
        ..Default::default()
    };
    let key = ReferenceKey {
        width,
        height,
        time: args.scene.time,
        diffuse_bounces: args.diffuse_bounces,
        budget,
        settings: format!("{settings:?}"),
    };
    let folder = (!args.no_cache)
        .then(cache_root)
        .flatten()
        .map(|root| root.join(cache_key(scene, &key)));
    if let Some(dir) = &folder {
        if let Some(images) = read_cached(dir, width, height)? {
            println!("reference from the cache: {}", dir.display());
            return Ok(images);
        }
    }
    let mut r =
        ReferenceRenderer::new(ctx, scene.clone(), width, height, args.scene.time, settings)?;
    // Two equal half-runs: whole passes, so the second stops at exactly
    // twice the first's photons.
    // A signal ends the comparison: a reference short of its budget would
    // be cached under the full budget's key.
    let interrupted = match args.reference_time {
        Some(s) => trace_reference(&mut r, 0, Some(s / 2.0))?,
        None => trace_reference(
            &mut r,
            (args.photons.unwrap_or(DEFAULT_PHOTONS) / 2).max(1),
            None,
        )?,
    };
    let first_half = r.resolve(Component::All)?;
    let half_photons = r.photons();
    if interrupted || trace_reference(&mut r, 2 * half_photons, None)? {
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
        diffuse_bounces: args.diffuse_bounces,
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

/// The contact sheet's thumbnail of a radiance image.
fn thumbnail_of(rgba: &[f32], width: u32, height: u32, exposure: f32) -> Vec<u8> {
    sheet::thumbnail(
        metrics::rgb8(&metrics::tonemap(rgba, exposure)),
        width,
        height,
    )
}

/// One technique's metrics and the sheet's thumbnails of its full frame
/// and of its FLIP map, its images written to `staging` as they are made;
/// `Ok(Err(reason))` when it does not apply to the scene (its constructor
/// refused it).
#[allow(clippy::type_complexity)]
fn run_technique(
    ctx: &Arc<Context>,
    scene: &Scene,
    name: &str,
    args: &CompareArgs,
    reference: &ReferenceImages,
    staging: &mut Outputs,
    timing_source: &mut Option<String>,
) -> anyhow::Result<Result<(TechniqueResult, [Vec<u8>; 2]), String>> {
    let (width, height, time) = (args.scene.width, args.scene.height, args.scene.time);
    let exposure = scene.output.exposure;
    let info = techniques::find(name)?;
    let params = Params::resolve(name, info.params(), &[])?;
    // A technique that does not take the scene is skipped; any other
    // failure is the comparison's.
    if let Err(e) = (info.check_scene)(scene) {
        return Ok(Err(format!("{e:#}")));
    }
    let mut r = Renderer::new(ctx, scene.clone(), name, &params, width, height, time)
        .map_err(|e| super::name_arguments(e, &args.scene, name, &[]))?;
    r.set_frame_options(FrameOptions::default())?;
    *timing_source = Some(r.frames.source.describe().to_string());
    // Each component's frame first, all at the comparison's time. Together
    // they run every pass once (a technique skips in a component's frame
    // only the passes of the components it does not draw,
    // `SceneGpu::draws`), so they are the warm-up (pipeline compilation)
    // the timed frames need; a separate warm-up frame only without them.
    let mut components = Vec::new();
    for &c in info.components {
        r.scene_gpu.components = c.mask();
        r.render_frame(time)?;
        let img = r.radiance()?;
        staging.write_pair(
            &format!("{name}_{}", c.name()),
            width,
            height,
            &img,
            exposure,
        )?;
        let Some((_, truth)) = reference.components.iter().find(|(rc, _)| *rc == c) else {
            continue;
        };
        let (m, cmap) = metrics::compare(&img, truth, width, height, exposure);
        staging.write_map(&format!("{name}_{}_flip", c.name()), &cmap)?;
        components.push(ComponentResult {
            component: c.name().into(),
            metrics: m,
        });
    }
    r.scene_gpu.components = Component::All.mask();
    if info.components.is_empty() {
        r.render_frame(time)?;
    }
    // The timed frames; the last one is the image compared.
    let start = Instant::now();
    for _ in 0..args.frames {
        r.submit_frame(time)?;
    }
    let done = r.finish()?;
    let timing = Timing {
        frames: args.frames,
        frame_ms: start.elapsed().as_secs_f64() * 1e3 / args.frames as f64,
        passes_ms: pass_stats(&done),
    };
    let image = r.radiance()?;
    let (full, map) = metrics::compare(&image, &reference.all, width, height, exposure);
    staging.write_pair(name, width, height, &image, exposure)?;
    staging.write_map(&format!("{name}_flip"), &map)?;
    let thumbnails = [
        thumbnail_of(&image, width, height, exposure),
        sheet::thumbnail(map.magma_rgb8(), width, height),
    ];
    drop((image, map));
    drop(r);
    let result = TechniqueResult {
        technique: name.into(),
        params: params.iter().map(|(k, v)| (k.clone(), *v)).collect(),
        timing,
        full,
        components,
    };
    Ok(Ok((result, thumbnails)))
}

/// Every file of the comparison, each written to its temporary when it is
/// made and renamed into place with the others by `commit` (all of them or
/// none appear).
struct Outputs {
    out: PathBuf,
    batch: Batch,
}

impl Outputs {
    fn new(out: &Path) -> Outputs {
        Outputs {
            out: out.to_path_buf(),
            batch: Batch::default(),
        }
    }

    fn add(&mut self, name: String, write: output::WriteBytes) -> anyhow::Result<()> {
        let path = self.out.join(name);
        self.batch.write(OutputFile { path: &path, write })
    }

    /// `<stem>.exr` (linear radiance) and `<stem>.png` (display transform).
    fn write_pair(
        &mut self,
        stem: &str,
        w: u32,
        h: u32,
        rgba: &[f32],
        exposure: f32,
    ) -> anyhow::Result<()> {
        if rgba.iter().any(|v| !v.is_finite()) {
            anyhow::bail!("{stem}: the radiance contains NaN or Inf; nothing written");
        }
        let exr = self.out.join(format!("{stem}.exr"));
        self.batch.write(output::exr_file(&exr, w, h, rgba))?;
        let png = self.out.join(format!("{stem}.png"));
        let display = metrics::tonemap(rgba, exposure);
        self.batch.write(output::png_file(&png, w, h, &display))
    }

    /// A FLIP map through the magma colour map, `<stem>.png`.
    fn write_map(&mut self, stem: &str, map: &FlipMap) -> anyhow::Result<()> {
        self.write_rgb(stem, map.width, map.height, map.magma_rgb8())
    }

    fn write_rgb(&mut self, stem: &str, w: u32, h: u32, rgb: Vec<u8>) -> anyhow::Result<()> {
        self.add(
            format!("{stem}.png"),
            Box::new(move |out| {
                let image = image::RgbImage::from_raw(w, h, rgb)
                    .ok_or_else(|| anyhow::anyhow!("image buffer has the wrong size"))?;
                Ok(image.write_to(out, image::ImageFormat::Png)?)
            }),
        )
    }

    fn write_text(&mut self, name: &str, text: &str) -> anyhow::Result<()> {
        let text = text.to_owned();
        self.add(
            name.to_owned(),
            Box::new(move |out| Ok(out.write_all(text.as_bytes())?)),
        )
    }

    /// Renames every file into place, report.json (written last) last;
    /// returns how many.
    fn commit(self) -> anyhow::Result<usize> {
        let n = self.batch.len();
        self.batch.commit()?;
        Ok(n)
    }
}
