//! The `caustics` command line: render, reference, bench, demo, info.

use anyhow::Context as _;
use caustics::output;
use caustics::params::Params;
use caustics::reference::{Component, ReferenceRenderer, ReferenceSettings};
use caustics::renderer::Renderer;
use caustics::scene::{Scene, DEFAULT_SCENE};
use caustics::techniques;
use caustics::vk::{Context, ContextOptions, PassTiming};
use clap::{Args, Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

#[derive(Parser)]
#[command(
    name = "caustics",
    version,
    about = "Real-time caustics techniques on Vulkan, side by side against a GPU ground truth"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Args, Clone)]
struct DeviceArgs {
    /// Vulkan device by index or name substring (`caustics info` lists them).
    #[arg(long)]
    device: Option<String>,
    /// Turn on the Khronos validation layer (default in debug builds); any validation error makes the command fail.
    #[arg(long)]
    validate: bool,
    /// Also turn on the validation layer's synchronization validation (hazards between commands are errors); implies --validate; default in debug builds.
    #[arg(long)]
    validate_sync: bool,
}

#[derive(Args, Clone)]
struct SceneArgs {
    /// Scene file: TOML, or a glTF 2.0 file (.gltf/.glb) as a whole scene (docs/SCENES.md).
    #[arg(long, default_value = DEFAULT_SCENE)]
    scene: PathBuf,
    #[arg(long, default_value_t = 512)]
    width: u32,
    #[arg(long, default_value_t = 512)]
    height: u32,
    /// Animation time in seconds.
    #[arg(long, default_value_t = 0.0)]
    time: f32,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene with a real-time technique and write PNG (tonemapped) or EXR (linear radiance).
    Render {
        #[command(flatten)]
        scene: SceneArgs,
        /// Technique name, or `list` to print them with their parameters.
        #[arg(long, default_value = "direct")]
        technique: String,
        /// Technique parameter, NAME=VALUE (repeatable; `--technique list` shows them).
        #[arg(long = "param")]
        params: Vec<String>,
        /// Frames to render (time advances 1/60 s per frame); timings are averaged over them.
        #[arg(long, default_value_t = 1)]
        frames: u32,
        /// Path-type component to draw: one the technique renders (`--technique list`) or all.
        #[arg(long, default_value = "all")]
        component: String,
        /// Output image; .png or .exr (the other format is written beside it).
        #[arg(long, default_value = "out/render.png")]
        out: PathBuf,
        #[command(flatten)]
        device: DeviceArgs,
    },
    /// Render the ground truth with the GPU light tracer.
    Reference {
        #[command(flatten)]
        scene: SceneArgs,
        /// Photons to trace (rounded up to whole passes of 262,144).
        #[arg(long, default_value_t = 20_000_000, conflicts_with = "seconds")]
        photons: u64,
        /// Trace for this many seconds instead of a photon count (whole passes).
        #[arg(long)]
        seconds: Option<f64>,
        /// Seed of the random streams: different seeds give independent images.
        #[arg(long, default_value_t = 0)]
        seed: u32,
        /// First pass's photon-mapping radius in metres (default: 1.5 pixel
        /// footprints at the camera target's distance); it shrinks every pass.
        #[arg(long)]
        radius: Option<f32>,
        /// The light tracer and the camera chains' direct light only: what is
        /// seen through glass, water or mirrors lacks its caustics (for
        /// measuring what photon mapping costs).
        #[arg(long)]
        no_photon_mapping: bool,
        /// Share of the photons aimed at the mirrors and dielectrics (their
        /// bounding sphere), in [0, 1); the rest follow the light's own
        /// distribution. Unbiased for any share; more caustic photons.
        #[arg(long, default_value_t = 0.5)]
        aim_share: f32,
        /// Path-type component to write: direct, surface_caustics, airlight, volume_caustics, other, all.
        #[arg(long, default_value = "all")]
        component: String,
        /// Diffuse bounces photons continue through (0: direct light and caustics only).
        #[arg(long, default_value_t = 0)]
        diffuse_bounces: u32,
        /// Output image; .png or .exr (the other format is written beside it).
        #[arg(long, default_value = "out/reference.png")]
        out: PathBuf,
        #[command(flatten)]
        device: DeviceArgs,
    },
    /// Per-pass GPU timings averaged over frames after a warm-up.
    Bench {
        #[command(flatten)]
        scene: SceneArgs,
        #[arg(long, default_value = "direct")]
        technique: String,
        #[arg(long = "param")]
        params: Vec<String>,
        #[arg(long, default_value_t = 20)]
        frames: u32,
        /// Frames rendered before timing starts (pipeline compilation, caches).
        #[arg(long, default_value_t = 2)]
        warmup: u32,
        /// Also write the results as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
        #[command(flatten)]
        device: DeviceArgs,
    },
    /// Open a window and render interactively (keys and mouse: README.md).
    Demo {
        /// Scene file: TOML, or a glTF 2.0 file (.gltf/.glb) as a whole scene (docs/SCENES.md). R reloads it.
        #[arg(long, default_value = DEFAULT_SCENE)]
        scene: PathBuf,
        #[arg(long, default_value = "direct")]
        technique: String,
        #[arg(long = "param")]
        params: Vec<String>,
        /// Initial window width.
        #[arg(long, default_value_t = 512)]
        width: u32,
        /// Initial window height.
        #[arg(long, default_value_t = 512)]
        height: u32,
        /// fifo (default, vsync), mailbox or immediate; falls back to fifo when not offered.
        #[arg(long, default_value = "fifo")]
        present_mode: String,
        /// With --exit: frames to present before exiting.
        #[arg(long)]
        frames: Option<u32>,
        /// Exit after --frames N frames (tests, screenshots).
        #[arg(long, requires = "frames")]
        exit: bool,
        /// Resize the window every few frames while running (tests).
        #[arg(long)]
        resize_test: bool,
        #[command(flatten)]
        device: DeviceArgs,
    },
    /// List Vulkan devices and the features this renderer needs.
    Info,
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format_timestamp(None)
        .init();
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", describe(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line, like `{e:#}`, but without repeating a
/// cause that a message already quotes (`SceneError::Read` and `VkError`
/// variants put their source in their own message and also report it as the
/// source, which `{e:#}` printed twice).
fn describe(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let m = cause.to_string();
        if line.is_empty() {
            line = m;
        } else if !line.contains(&m) {
            line.push_str(": ");
            line.push_str(&m);
        }
    }
    line
}

fn context(args: &DeviceArgs) -> anyhow::Result<Arc<Context>> {
    let options = ContextOptions {
        validation: args.validate || args.validate_sync || cfg!(debug_assertions),
        sync_validation: args.validate_sync || cfg!(debug_assertions),
        device: args.device.clone(),
    };
    let ctx = Context::new(&options)?;
    eprintln!("device: {} ({})", ctx.info.name, ctx.info.driver.trim());
    Ok(ctx)
}

/// Fails the command if the validation layer reported errors, leaked objects
/// included: everything that used the device must be dropped before this.
fn check_validation(ctx: Arc<Context>) -> anyhow::Result<()> {
    let counts = Context::shutdown(ctx)?;
    if counts.errors > 0 {
        anyhow::bail!(
            "the Vulkan validation layer reported {} error(s) (see the log above)",
            counts.errors
        );
    }
    Ok(())
}

fn load_scene(path: &Path) -> anyhow::Result<Scene> {
    Ok(Scene::load(path)?)
}

fn check_size(args: &SceneArgs) -> anyhow::Result<()> {
    for (name, v) in [("--width", args.width), ("--height", args.height)] {
        if !(1..=16384).contains(&v) {
            anyhow::bail!("{name} {v}: must be between 1 and 16384");
        }
    }
    if !args.time.is_finite() {
        anyhow::bail!("--time must be a finite number of seconds");
    }
    Ok(())
}

/// What `render` and `bench` check before they touch the device: the
/// technique and its parameters, the image size, the frame count, the scene.
fn checked_technique_run(
    scene: &SceneArgs,
    technique: &str,
    overrides: &[String],
    frames: u32,
) -> anyhow::Result<(Scene, Params)> {
    let info = techniques::find(technique)?;
    let params = Params::resolve(technique, info.params(), overrides)?;
    check_size(scene)?;
    if frames == 0 {
        anyhow::bail!("--frames must be at least 1");
    }
    Ok((load_scene(&scene.scene)?, params))
}

fn print_timings(title: &str, timings: &[PassTiming], source: &str) {
    println!("{title} ({source}):");
    let mut total = 0.0;
    for t in timings {
        println!("  {:<28} {:>9.3} ms", t.name, t.ms);
        total += t.ms;
    }
    println!("  {:<28} {:>9.3} ms", "total", total);
}

/// Averages per-pass timings over frames (passes matched by position and name).
fn average(frames: &[Vec<PassTiming>]) -> Vec<PassTiming> {
    let Some(first) = frames.first() else {
        return Vec::new();
    };
    first
        .iter()
        .enumerate()
        .map(|(i, p)| PassTiming {
            name: p.name.clone(),
            ms: frames
                .iter()
                .filter_map(|f| f.get(i))
                .map(|t| t.ms)
                .sum::<f64>()
                / frames.len() as f64,
        })
        .collect()
}

/// Writes both images, or neither: when the PNG fails the EXR just written is removed.
fn write_outputs(
    (exr, png): &(PathBuf, PathBuf),
    width: u32,
    height: u32,
    radiance: &[f32],
    display: &[u8],
) -> anyhow::Result<()> {
    if radiance.iter().any(|v| !v.is_finite()) {
        anyhow::bail!("the rendered radiance contains NaN or Inf; no image written");
    }
    output::write_exr(exr, width, height, radiance)?;
    if let Err(e) = output::write_png(png, width, height, display) {
        let _ = std::fs::remove_file(exr);
        return Err(e);
    }
    println!(
        "wrote {} (linear radiance) and {} (tonemapped)",
        exr.display(),
        png.display()
    );
    Ok(())
}

fn list_techniques() {
    println!("techniques (caustics render --technique NAME):");
    for t in techniques::TECHNIQUES {
        println!("  {:<14} {}", t.name, t.description);
        let components: Vec<_> = t.components.iter().map(|c| c.name()).collect();
        println!("      --component {}|all", components.join("|"));
        for p in t.params() {
            println!(
                "      --param {}=VALUE  {} [{} .. {}], default {}{}",
                p.name,
                p.description,
                p.min,
                p.max,
                p.default,
                match p.apply {
                    caustics::params::Apply::Live => " (live)",
                    caustics::params::Apply::Rebuild => "",
                }
            );
        }
    }
    println!(
        "  {:<14} ground-truth light tracer: run `caustics reference`",
        "reference"
    );
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Demo {
            scene,
            technique,
            params,
            width,
            height,
            present_mode,
            frames,
            exit,
            resize_test,
            device,
        } => {
            let info = techniques::find(&technique)?;
            let params = Params::resolve(&technique, info.params(), &params)?;
            check_size(&SceneArgs {
                scene: scene.clone(),
                width,
                height,
                time: 0.0,
            })?;
            if frames == Some(0) {
                anyhow::bail!("--frames must be at least 1");
            }
            caustics::app::run(caustics::app::DemoOptions {
                scene,
                technique,
                params,
                width,
                height,
                present_mode: caustics::app::parse_present_mode(&present_mode)?,
                frames,
                exit,
                resize_test,
                validate: device.validate,
                validate_sync: device.validate_sync,
                device: device.device,
            })
        }
        Command::Info => {
            let devices = Context::list_devices()?;
            if devices.is_empty() {
                anyhow::bail!("no Vulkan device found; install Mesa's lavapipe: apt-get install mesa-vulkan-drivers");
            }
            for d in devices {
                println!(
                    "[{}] {} ({:?}), Vulkan {}.{}.{}, {}",
                    d.index,
                    d.name,
                    d.kind,
                    d.api_version.0,
                    d.api_version.1,
                    d.api_version.2,
                    d.driver.trim()
                );
                for (f, ok) in &d.features {
                    println!("    {} {}", if *ok { "yes" } else { "NO " }, f.name());
                }
            }
            Ok(())
        }
        Command::Render {
            scene,
            technique,
            params,
            frames,
            component,
            out,
            device,
        } => {
            if technique == "list" {
                list_techniques();
                return Ok(());
            }
            output::format_of(&out)?;
            let (loaded, params) = checked_technique_run(&scene, &technique, &params, frames)?;
            let components = techniques::find(&technique)?.component_mask(&component)?;
            let outputs = output::prepare(&out)?;
            let ctx = context(&device)?;
            let mut renderer = Renderer::new(
                &ctx,
                loaded,
                &technique,
                &params,
                scene.width,
                scene.height,
                scene.time,
            )?;
            renderer.scene_gpu.components = components;
            let mut all = Vec::new();
            for i in 0..frames {
                all.push(renderer.render_frame(scene.time + i as f32 / 60.0)?);
            }
            let title = format!(
                "{} at {}x{}, {} frame(s), mean per pass",
                technique, scene.width, scene.height, frames
            );
            print_timings(&title, &average(&all), renderer.profiler.source.describe());
            let stats = renderer.scene_gpu.stats;
            println!(
                "geometry: {} triangles, BVH {} nodes ({} leaves, depth {}) built in {:.1} ms",
                stats.triangles,
                stats.bvh_nodes,
                stats.bvh_leaves,
                stats.bvh_depth,
                stats.bvh_build_ms
            );
            let radiance = renderer.radiance()?;
            let display = renderer.display()?;
            drop(renderer);
            check_validation(ctx)?;
            write_outputs(&outputs, scene.width, scene.height, &radiance, &display)
        }
        Command::Reference {
            scene,
            photons,
            seconds,
            seed,
            radius,
            no_photon_mapping,
            aim_share,
            component,
            diffuse_bounces,
            out,
            device,
        } => {
            check_size(&scene)?;
            output::format_of(&out)?;
            let component = Component::parse(&component)?;
            if photons == 0 {
                anyhow::bail!("--photons must be at least 1");
            }
            if let Some(seconds) = seconds {
                if !(seconds.is_finite() && seconds > 0.0) {
                    anyhow::bail!("--seconds must be a positive number, got {seconds}");
                }
            }
            if let Some(r) = radius {
                if !(r.is_finite() && r > 0.0) {
                    anyhow::bail!("--radius must be a positive length in metres, got {r}");
                }
            }
            let loaded = load_scene(&scene.scene)?;
            let outputs = output::prepare(&out)?;
            let ctx = context(&device)?;
            let settings = ReferenceSettings {
                diffuse_bounces,
                seed,
                radius,
                photon_mapping: !no_photon_mapping,
                aim_share,
                ..Default::default()
            };
            let mut reference = ReferenceRenderer::new(
                &ctx,
                loaded,
                scene.width,
                scene.height,
                scene.time,
                settings,
            )?;
            trace_reference(&mut reference, photons, seconds)?;
            let radiance = reference.resolve(component)?;
            let display = reference.display()?;
            drop(reference);
            check_validation(ctx)?;
            write_outputs(&outputs, scene.width, scene.height, &radiance, &display)
        }
        Command::Bench {
            scene,
            technique,
            params,
            frames,
            warmup,
            json,
            device,
        } => {
            let (loaded, params) = checked_technique_run(&scene, &technique, &params, frames)?;
            let ctx = context(&device)?;
            let mut renderer = Renderer::new(
                &ctx,
                loaded,
                &technique,
                &params,
                scene.width,
                scene.height,
                scene.time,
            )?;
            for i in 0..warmup {
                renderer.render_frame(scene.time + i as f32 / 60.0)?;
            }
            let mut all = Vec::new();
            let mut frame_ms = Vec::new();
            for i in 0..frames {
                let start = std::time::Instant::now();
                all.push(renderer.render_frame(scene.time + (warmup + i) as f32 / 60.0)?);
                frame_ms.push(start.elapsed().as_secs_f64() * 1e3);
            }
            let (device_name, driver) = (ctx.info.name.clone(), ctx.info.driver.trim().to_string());
            let (source, stats) = (renderer.profiler.source, renderer.scene_gpu.stats);
            let counters: std::collections::BTreeMap<_, _> =
                renderer.technique_counters().into_iter().collect();
            drop(renderer);
            check_validation(ctx)?;
            let passes = average(&all);
            let frame_mean = frame_ms.iter().sum::<f64>() / frame_ms.len() as f64;
            let title = format!(
                "bench {} on {} at {}x{}, {} frames after {} warm-up",
                technique,
                scene.scene.display(),
                scene.width,
                scene.height,
                frames,
                warmup
            );
            print_timings(&title, &passes, source.describe());
            println!(
                "  {:<28} {:>9.3} ms (host wall clock, submit to fence)",
                "frame", frame_mean
            );
            if let Some(path) = json {
                let report = serde_json::json!({
                    "device": device_name,
                    "driver": driver,
                    "timing_source": source.describe(),
                    "scene": scene.scene.display().to_string(),
                    "technique": technique,
                    "params": params.iter().map(|(k, v)| (k.clone(), *v)).collect::<std::collections::BTreeMap<_, _>>(),
                    "width": scene.width,
                    "height": scene.height,
                    "frames": frames,
                    "warmup": warmup,
                    "passes_ms": passes,
                    "frame_ms": frame_mean,
                    "geometry": stats,
                    "counters": counters,
                });
                if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir)
                        .with_context(|| format!("cannot create folder {}", dir.display()))?;
                }
                std::fs::write(&path, serde_json::to_string_pretty(&report)?)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                println!("wrote {}", path.display());
            }
            Ok(())
        }
    }
}

/// Runs reference passes until `photons` are traced or `seconds` have
/// passed, with a progress bar that shows per pass the photons, the
/// photon-mapping radius and the remaining noise; then prints the totals.
fn trace_reference(
    reference: &mut ReferenceRenderer,
    photons: u64,
    seconds: Option<f64>,
) -> anyhow::Result<()> {
    let bar = match seconds {
        Some(s) => indicatif::ProgressBar::new((s * 1000.0) as u64).with_style(
            indicatif::ProgressStyle::with_template("{bar:40} {elapsed}/{msg}")
                .context("progress style")?,
        ),
        None => indicatif::ProgressBar::new(photons).with_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {percent:>3}% {human_pos}/{human_len} photons, eta {eta} {msg}",
            )
            .context("progress style")?,
        ),
    };
    let start = std::time::Instant::now();
    loop {
        let elapsed = start.elapsed().as_secs_f64();
        let done = match seconds {
            Some(s) => elapsed >= s,
            None => reference.reference.photons >= photons,
        };
        if done {
            break;
        }
        let report = reference.pass()?;
        let noise = reference.noise()?;
        let noise = noise.map_or("-".to_string(), |n| format!("{:.2}%", n * 100.0));
        let message = format!(
            "pass {} at {:.1} s, r {:.4} m, noise {}",
            reference.reference.passes,
            start.elapsed().as_secs_f64(),
            report.radius,
            noise
        );
        match seconds {
            Some(s) => {
                bar.set_position((start.elapsed().as_secs_f64() * 1000.0).min(s * 1000.0) as u64);
                bar.set_message(format!("{s:.0}s, {message}"));
            }
            None => {
                bar.set_position(reference.reference.photons.min(photons));
                bar.set_message(message.clone());
            }
        }
        if bar.is_hidden() {
            eprintln!("{} photons, {message}", reference.reference.photons);
        }
    }
    bar.finish_and_clear();
    let noise = reference.noise()?;
    println!(
        "traced {} photons in {} passes, {:.2} s: {:.3} M photons/s; last radius {:.4} m; remaining noise {}",
        reference.reference.photons,
        reference.reference.passes,
        reference.trace_seconds,
        reference.photons_per_second() / 1e6,
        reference.reference.radius(),
        noise.map_or("unknown (one pass)".to_string(), |n| format!("{:.2}%", n * 100.0)),
    );
    let passes = reference.reference.passes.max(1) as f64;
    let stages: Vec<String> = reference
        .pass_ms
        .iter()
        .map(|(name, ms)| format!("{name} {:.1} ms", ms / passes))
        .collect();
    println!("per pass: {}", stages.join(", "));
    if reference.volume_overflow > 0 {
        eprintln!(
            "warning: {} medium collisions did not fit the volume photon map ({} per pass); the volume gather saw fewer photons than the light tracer",
            reference.volume_overflow,
            reference.reference.volume_capacity()
        );
    }
    Ok(())
}
