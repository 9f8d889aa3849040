//! `caustics compare`: every applicable technique against the ground truth
//! in one command (docs/REPORTS.md), a front end over
//! `caustics::compare::driver` (the reference's budget and cache, each
//! technique's components and timed frames, the metrics). Here: the
//! arguments, the progress display (`trace_reference`), the files and the
//! contact sheet. Each file is written as soon as it is made, to a
//! temporary renamed into place with all the others at the end
//! (`output::Batch`; removed on SIGINT/SIGTERM or an error), report.json
//! last, so a failed or interrupted run leaves none of its files. What
//! stays in memory is what the rest of the run needs: the reference and
//! its components (every technique is measured against them), the contact
//! sheet's thumbnails (`sheet::thumbnail`) and the numbers; a technique's
//! images are dropped once written and measured.

use super::reference::trace_reference;
use super::{check_size, check_validation, context, load_scene, CompareArgs};
use anyhow::Context as _;
use caustics::compare::driver::{self, Budget, ImageSink, Judged, ReferenceImages, View};
use caustics::compare::metrics::{self, FlipMap};
use caustics::compare::report::{signed_percent, CompareReport, RunInfo, Skipped, SCHEMA};
use caustics::compare::sheet::{self, Tile};
use caustics::output;
use caustics::output::{Batch, OutputFile};
use caustics::techniques::{self, TECHNIQUES};
use std::io::Write as _;
use std::path::{Path, PathBuf};

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
            Some(ReferenceImages::from_file(rgba, path, args.diffuse_bounces))
        }
        None => None,
    };
    let scene = load_scene(&args.scene.file, time)?;
    let exposure = scene.output.exposure;
    if args.out.exists() && !args.out.is_dir() {
        anyhow::bail!("--out {}: not a folder", args.out.display());
    }
    output::check_writable(&args.out.join("report.json"), "--out")?;
    let mut staging = Outputs::new(&args.out, (width, height), exposure);
    let ctx = context(&args.device)?;

    let view = View {
        width,
        height,
        time,
        diffuse_bounces: args.diffuse_bounces,
    };
    let mut reference = match from_file {
        Some(reference) => reference,
        None => {
            let budget = match args.reference_time {
                Some(s) => Budget::Seconds(s),
                None => Budget::Photons(args.photons.unwrap_or(driver::DEFAULT_PHOTONS)),
            };
            let cache = (!args.no_cache).then(driver::cache_root).flatten();
            ReferenceImages::cached_or_traced(
                &ctx,
                &scene,
                view,
                budget,
                cache.as_deref(),
                &mut |r, photons, seconds| trace_reference(r, photons, seconds),
            )?
        }
    };
    staging.radiance("reference", &reference.all)?;
    for (c, img) in &reference.components {
        staging.radiance(&format!("reference_{}", c.name()), img)?;
    }
    let mut tiles = vec![vec![Tile {
        rgb: thumbnail_of(&reference.all, width, height, exposure),
        lines: vec![
            "reference".into(),
            format!("{} photons", reference.info.photons),
        ],
    }]];
    if let Some((m, map)) = reference.measure_noise(width, height, exposure) {
        staging.flip_map("reference_noise_flip", &map)?;
        tiles[0].push(Tile {
            rgb: sheet::thumbnail(map.magma_rgb8(), width, height),
            lines: vec!["its noise".into(), format!("FLIP {:.4}", m.flip)],
        });
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
        let judged = driver::judge_technique(
            &ctx,
            &scene,
            name,
            view,
            args.frames,
            &reference,
            &mut staging,
        )
        .map_err(|e| super::name_arguments(e, &args.scene, name, &[]))?;
        match judged {
            Ok(Judged {
                result,
                image,
                map,
                timing_source: source,
            }) => {
                timing_source = Some(source);
                let label = vec![
                    name.to_string(),
                    format!("FLIP {:.4}", result.full.flip),
                    format!("E {}", signed_percent(result.full.energy)),
                    format!("{:.1} ms", result.timing.frame_ms),
                ];
                tiles.push(vec![
                    Tile {
                        rgb: thumbnail_of(&image, width, height, exposure),
                        lines: label,
                    },
                    Tile {
                        rgb: sheet::thumbnail(map.magma_rgb8(), width, height),
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
        reference: reference.info,
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
        for n in &t.not_applicable {
            println!("{:<16} {}: not applicable ({})", "", n.component, n.reason);
        }
        if let Some(m) = &t.modelled {
            println!(
                "{:<16} modelled components: FLIP {:.4}  energy {}",
                "",
                m.flip,
                signed_percent(m.energy)
            );
        }
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

/// The contact sheet's thumbnail of a radiance image.
fn thumbnail_of(rgba: &[f32], width: u32, height: u32, exposure: f32) -> Vec<u8> {
    sheet::thumbnail(
        metrics::rgb8(&metrics::tonemap(rgba, exposure)),
        width,
        height,
    )
}

/// Every file of the comparison, each written to its temporary when it is
/// made and renamed into place with the others by `commit` (all of them or
/// none appear).
struct Outputs {
    out: PathBuf,
    batch: Batch,
    exposure: f32,
    size: (u32, u32),
}

impl Outputs {
    fn new(out: &Path, size: (u32, u32), exposure: f32) -> Outputs {
        Outputs {
            out: out.to_path_buf(),
            batch: Batch::default(),
            exposure,
            size,
        }
    }

    fn add(&mut self, name: String, write: output::WriteBytes) -> anyhow::Result<()> {
        let path = self.out.join(name);
        self.batch.write(OutputFile { path: &path, write })
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

impl ImageSink for Outputs {
    /// `<stem>.exr` (linear radiance) and `<stem>.png` (display transform).
    fn radiance(&mut self, stem: &str, rgba: &[f32]) -> anyhow::Result<()> {
        if rgba.iter().any(|v| !v.is_finite()) {
            anyhow::bail!("{stem}: the radiance contains NaN or Inf; nothing written");
        }
        let (w, h) = self.size;
        let exr = self.out.join(format!("{stem}.exr"));
        self.batch.write(output::exr_file(&exr, w, h, rgba))?;
        let png = self.out.join(format!("{stem}.png"));
        let display = metrics::tonemap(rgba, self.exposure);
        self.batch.write(output::png_file(&png, w, h, &display))
    }

    /// A FLIP map through the magma colour map, `<stem>.png`.
    fn flip_map(&mut self, stem: &str, map: &FlipMap) -> anyhow::Result<()> {
        self.write_rgb(stem, map.width, map.height, map.magma_rgb8())
    }
}
