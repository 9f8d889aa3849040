//! The command line's arguments and what its commands share: device and
//! validation, scene and size checks, image output. One file per command.

pub mod compare;
pub mod info;
pub mod interrupt;
pub mod reference;
pub mod render;

use caustics::output;
use caustics::params::Params;
use caustics::renderer::Stage;
use caustics::scene::{AllowedPaths, Scene, DEFAULT_SCENE};
use caustics::techniques;
use caustics::vk::{Context, ContextOptions, FrameOptions, MAX_FRAMES_IN_FLIGHT};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Parser)]
#[command(
    name = "caustics",
    version,
    about = "Real-time caustics techniques on Vulkan, side by side against a GPU ground truth"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Args, Clone)]
pub struct DeviceArgs {
    /// Vulkan device by index or name substring (`caustics info` lists them).
    #[arg(long)]
    pub device: Option<String>,
    /// Turn on the Khronos validation layer (default in debug builds); any validation error makes the command fail.
    #[arg(long)]
    pub validate: bool,
    /// Also turn on the validation layer's synchronization validation (hazards between commands are errors); implies --validate; default in debug builds.
    #[arg(long)]
    pub validate_sync: bool,
}

/// The scene every command that loads one reads, and where its files may be.
#[derive(Args, Clone)]
pub struct SceneFileArgs {
    /// Scene file: TOML, or a glTF 2.0 file (.gltf/.glb) as a whole scene (docs/SCENES.md; the demo's R reloads it).
    #[arg(long, default_value = DEFAULT_SCENE)]
    pub scene: PathBuf,
    /// Also read files the scene names from this folder's tree (repeatable); by default only files inside the scene file's folder tree are read (docs/SCENES.md, "Paths").
    #[arg(long = "allow-paths", value_name = "DIR")]
    pub allow_paths: Vec<PathBuf>,
}

impl SceneFileArgs {
    /// The `--allow-paths` folders, each checked to be one.
    pub fn allowed(&self) -> anyhow::Result<AllowedPaths> {
        AllowedPaths::new(&self.allow_paths).map_err(anyhow::Error::msg)
    }
}

#[derive(Args, Clone)]
pub struct SceneArgs {
    #[command(flatten)]
    pub file: SceneFileArgs,
    #[arg(long, allow_negative_numbers = true, default_value_t = 512)]
    pub width: u32,
    #[arg(long, allow_negative_numbers = true, default_value_t = 512)]
    pub height: u32,
    /// Animation time in seconds.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.0)]
    pub time: f32,
}

#[derive(Args, Clone)]
pub struct FrameArgs {
    /// Frames the GPU may still be running while the host records the next
    /// (1 to 4); the host waits only for the frame that last used a slot.
    #[arg(long, allow_negative_numbers = true, default_value_t = 2)]
    pub frames_in_flight: usize,
    /// Per-pass times on a CPU device (lavapipe), whose timestamps miss
    /// compute: one submission per pass, each waited for, so frames cannot
    /// overlap. Without it the frame is timed as a whole.
    #[arg(long)]
    pub pass_timing: bool,
}

impl FrameArgs {
    pub fn options(&self) -> anyhow::Result<FrameOptions> {
        if !(1..=MAX_FRAMES_IN_FLIGHT).contains(&self.frames_in_flight) {
            anyhow::bail!(
                "--frames-in-flight {}: must be between 1 and {MAX_FRAMES_IN_FLIGHT}",
                self.frames_in_flight
            );
        }
        Ok(FrameOptions {
            frames_in_flight: self.frames_in_flight,
            per_pass: self.pass_timing,
            ..FrameOptions::default()
        })
    }
}

#[derive(Subcommand)]
pub enum Command {
    /// Render a scene with a real-time technique and write PNG (tonemapped) or EXR (linear radiance).
    Render(RenderArgs),
    /// Render the ground truth with the GPU light tracer.
    Reference(ReferenceArgs),
    /// Per-pass GPU timings (min and median over frames) and the frame interval, after a warm-up.
    Bench(BenchArgs),
    /// Every technique against the ground truth: images, FLIP error maps, a contact sheet and report.md/report.json.
    Compare(CompareArgs),
    /// Open a window and render interactively (keys and mouse: README.md).
    Demo(DemoArgs),
    /// List Vulkan devices and the features this renderer needs.
    Info,
}

/// What `render` and `bench` run: a scene and a technique with its parameters.
#[derive(Args)]
pub struct TechniqueArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Technique name, `auto` (the default: the one that renders every
    /// component the scene has, printed; `volume_lines` with a medium,
    /// `water_photons` for sunlit water, else `image_space`), or `list`
    /// (with `render`) to print them with their parameters.
    #[arg(long, default_value = "auto")]
    pub technique: String,
    /// Technique parameter, NAME=VALUE (repeatable; `render --technique list` shows them).
    #[arg(long = "param")]
    pub params: Vec<String>,
}

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub run: TechniqueArgs,
    /// Frames to render (time advances 1/60 s per frame); timings are
    /// averaged over them. In a scene without animation the frames show one
    /// still view and accumulate: the image written is their mean.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1)]
    pub frames: u32,
    /// Path-type component to draw: one the technique renders (`--technique list`) or all.
    #[arg(long, default_value = "all")]
    pub component: String,
    /// Output image; .png or .exr (the other format is written beside it).
    #[arg(long, default_value = "out/render.png")]
    pub out: PathBuf,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[command(flatten)]
    pub device: DeviceArgs,
}

#[derive(Args)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Photons to trace (rounded up to whole passes of 262,144; at most 1e15).
    #[arg(
        long,
        allow_negative_numbers = true,
        default_value_t = 20_000_000,
        conflicts_with = "seconds"
    )]
    pub photons: u64,
    /// Trace for this many seconds instead of a photon count (whole passes).
    #[arg(long, allow_negative_numbers = true)]
    pub seconds: Option<f64>,
    /// Seed of the random streams: different seeds give independent images.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0)]
    pub seed: u32,
    /// First pass's photon-mapping radius in metres (default: 1.5 pixel
    /// footprints at the camera target's distance); it shrinks every pass.
    #[arg(long, allow_negative_numbers = true)]
    pub radius: Option<f32>,
    /// The light tracer and the camera chains' direct light only: what is
    /// seen through glass, water or mirrors lacks its caustics (for
    /// measuring what photon mapping costs).
    #[arg(long)]
    pub no_photon_mapping: bool,
    /// Share of the photons aimed at the mirrors and dielectrics (their
    /// bounding sphere), in [0, 1); the rest follow the light's own
    /// distribution. Unbiased for any share; more caustic photons.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.5)]
    pub aim_share: f32,
    /// Aim the photons uniformly over the specular objects' bounding sphere
    /// instead of by the aim guide (where earlier passes' aimed photons
    /// reached the image); for measuring what the guide gains.
    #[arg(long)]
    pub no_aim_guide: bool,
    /// Camera chains through glass and water follow both branches of their
    /// first N Fresnel choices (reflected and refracted, each weighted by
    /// its probability), from 0 (every choice random) to 2: less noise in
    /// what is seen through and in glass
    #[arg(long, default_value_t = caustics::shader_bindings::REFERENCE_MAX_FRESNEL_SPLITS)]
    pub fresnel_splits: u32,
    /// Photons per pass, a multiple of 64 from 64 to 16,777,216: a pass is
    /// the unit of progress (its camera samples, its photons, its radius).
    /// Smaller passes show a first image sooner.
    #[arg(long, default_value_t = 1 << 18)]
    pub pass_photons: u32,
    /// Path-type component to write: direct, surface_caustics, airlight, volume_caustics, other, all.
    #[arg(long, default_value = "all")]
    pub component: String,
    /// Diffuse bounces photons continue through (0: direct light and caustics only).
    #[arg(long, allow_negative_numbers = true, default_value_t = 0)]
    pub diffuse_bounces: u32,
    /// Output image; .png or .exr (the other format is written beside it).
    #[arg(long, default_value = "out/reference.png")]
    pub out: PathBuf,
    #[command(flatten)]
    pub device: DeviceArgs,
}

#[derive(Args)]
pub struct BenchArgs {
    #[command(flatten)]
    pub run: TechniqueArgs,
    #[arg(long, allow_negative_numbers = true, default_value_t = 20)]
    pub frames: u32,
    /// Frames rendered before timing starts (pipeline compilation, caches).
    #[arg(long, allow_negative_numbers = true, default_value_t = 2)]
    pub warmup: u32,
    /// Also write the results as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Sample host RSS and gpu-allocator's device memory this many times,
    /// evenly over the timed frames (printed, and in the JSON): a soak
    /// test's leak check (scripts/soak.sh). Each sample waits for the
    /// frames in flight and, with glibc, returns the malloc heap's free
    /// pages (malloc_trim) first, so the RSS is memory in use between
    /// frames; the JSON keeps the untrimmed RSS too. The waits cost the
    /// timings a little overlap (one drain per sample).
    #[arg(long, allow_negative_numbers = true, default_value_t = 0)]
    pub memory_samples: u32,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[command(flatten)]
    pub device: DeviceArgs,
}

#[derive(Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// `all` (every technique that applies to the scene) or a comma-separated list.
    #[arg(long, default_value = "all")]
    pub techniques: String,
    /// Photons the reference traces (default 2^23), in two equal half-runs.
    #[arg(long, conflicts_with_all = ["reference_time", "reference"])]
    pub photons: Option<u64>,
    /// Trace the reference for this many seconds instead (two equal half-runs).
    #[arg(long, conflicts_with = "reference")]
    pub reference_time: Option<f64>,
    /// A reference image (EXR, linear radiance, the comparison's size) instead of tracing one: full frames only, no components, no noise estimate.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Diffuse bounces in the reference (0: the single-bounce components the techniques render).
    #[arg(long, default_value_t = 0)]
    pub diffuse_bounces: u32,
    /// Full frames timed per technique, after its component frames (which warm it up).
    #[arg(long, default_value_t = 3)]
    pub frames: u32,
    /// Trace the reference even when the cache (`references` in $CAUSTICS_CACHE_DIR, else $XDG_CACHE_HOME/caustics) holds it, and do not store it.
    #[arg(long)]
    pub no_cache: bool,
    /// Output folder.
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
    #[command(flatten)]
    pub device: DeviceArgs,
}

#[derive(Args)]
pub struct DemoArgs {
    #[command(flatten)]
    pub scene: SceneFileArgs,
    /// Technique name, or `auto` (the default: as for `render`).
    #[arg(long, default_value = "auto")]
    pub technique: String,
    #[arg(long = "param")]
    pub params: Vec<String>,
    /// Initial window width.
    #[arg(long, allow_negative_numbers = true, default_value_t = 512)]
    pub width: u32,
    /// Initial window height.
    #[arg(long, allow_negative_numbers = true, default_value_t = 512)]
    pub height: u32,
    /// fifo (default, vsync), mailbox or immediate; falls back to fifo when not offered.
    #[arg(long, default_value = "fifo")]
    pub present_mode: String,
    /// With --exit: frames to present before exiting.
    #[arg(long, allow_negative_numbers = true)]
    pub frames: Option<u32>,
    /// Exit after --frames N frames (tests, screenshots).
    #[arg(long, requires = "frames")]
    pub exit: bool,
    /// Resize the window every few frames while running (tests).
    #[arg(long)]
    pub resize_test: bool,
    /// Take a compare snapshot on the third frame, trace N reference passes
    /// beside the live frames while switching live, reference and FLIP
    /// views, then discard it (tests).
    #[arg(long, value_name = "N")]
    pub compare_test: Option<u32>,
    /// Frames the GPU may still be running while the host records the next (1 to 4).
    #[arg(long, allow_negative_numbers = true, default_value_t = 2)]
    pub frames_in_flight: usize,
    #[command(flatten)]
    pub device: DeviceArgs,
}

pub fn context(args: &DeviceArgs) -> anyhow::Result<Arc<Context>> {
    let options = ContextOptions {
        validation: args.validate || args.validate_sync || cfg!(debug_assertions),
        sync_validation: args.validate_sync || cfg!(debug_assertions),
        device: args.device.clone(),
    };
    let ctx = Context::new(&options)?;
    // On stdout with the results: stderr holds only the one line of an error.
    println!("device: {} ({})", ctx.info.name, ctx.info.driver.trim());
    Ok(ctx)
}

/// Checks the image size against the device's limit before anything is
/// allocated (`maxImageDimension2D`: every frame target is a 2D image of
/// the output's size).
pub fn check_device_limits(ctx: &Context, args: &SceneArgs) -> anyhow::Result<()> {
    let max = ctx.limits.max_image_dimension2_d;
    for (name, v) in [("--width", args.width), ("--height", args.height)] {
        if v > max {
            anyhow::bail!(
                "{name} {v}: the device's largest 2D image is {max} pixels (maxImageDimension2D)"
            );
        }
    }
    Ok(())
}

/// Names the arguments behind a failure of `Renderer::new` (a device limit
/// met by the scene, the image size or the technique `technique` with the
/// `--param`s `params`).
pub fn name_arguments(
    e: anyhow::Error,
    scene: &SceneArgs,
    technique: &str,
    params: &[String],
) -> anyhow::Error {
    let what = match e.downcast_ref::<Stage>() {
        Some(Stage::Scene) => format!("--scene {}", scene.file.scene.display()),
        Some(Stage::Targets { .. }) => format!("--width {} --height {}", scene.width, scene.height),
        Some(Stage::Technique) => {
            let params: String = params.iter().map(|p| format!(" --param {p}")).collect();
            format!("--technique {technique}{params}")
        }
        None => return e,
    };
    e.context(what)
}

/// Fails the command if the validation layer reported errors, leaked objects
/// included: everything that used the device must be dropped before this.
pub fn check_validation(ctx: Arc<Context>) -> anyhow::Result<()> {
    let counts = Context::shutdown(ctx)?;
    if counts.errors > 0 {
        anyhow::bail!(
            "the Vulkan validation layer reported {} error(s) (see the log above)",
            counts.errors
        );
    }
    Ok(())
}

/// Loads the scene (its files confined to its tree and the
/// `--allow-paths` folders) and checks what it derives at `time`
/// (transforms, light power: `Scene::check_at`) before any device work.
/// Every file the scene read is then protected from the command's outputs.
pub fn load_scene(file: &SceneFileArgs, time: f32) -> anyhow::Result<Scene> {
    let scene = Scene::load_allowing(&file.scene, &file.allowed()?)?;
    scene.check_at(time).map_err(anyhow::Error::msg)?;
    caustics::output::protect_inputs(&caustics::scene::input::files_read());
    Ok(scene)
}

/// The most photons `reference` and `compare` trace: 10^15, years of
/// tracing on any device today (lavapipe: about 2.5 M photons/s), and far
/// from where counting them in whole passes would overflow.
pub const MAX_PHOTONS: u64 = 1_000_000_000_000_000;

/// Checks a photon count given as `--photons`.
pub fn check_photons(photons: u64) -> anyhow::Result<()> {
    if !(1..=MAX_PHOTONS).contains(&photons) {
        anyhow::bail!("--photons {photons}: must be between 1 and {MAX_PHOTONS:e}");
    }
    Ok(())
}

pub fn check_size(args: &SceneArgs) -> anyhow::Result<()> {
    for (name, v) in [("--width", args.width), ("--height", args.height)] {
        if !(1..=16384).contains(&v) {
            anyhow::bail!("{name} {v}: must be between 1 and 16384");
        }
    }
    if !(args.time.is_finite() && args.time.abs() as f64 <= caustics::scene::MAX_MAGNITUDE) {
        anyhow::bail!(
            "--time {:e}: must be a finite number of seconds within ±{:e}",
            args.time,
            caustics::scene::MAX_MAGNITUDE
        );
    }
    Ok(())
}

/// What `render` and `bench` check before they touch the device: the
/// technique and its parameters, the image size, the frame count, the scene.
/// `--technique auto` becomes the technique `techniques::auto` picks for the
/// scene (in `run.technique`).
pub fn checked_technique_run(
    run: &mut TechniqueArgs,
    frames: u32,
) -> anyhow::Result<(Scene, Params)> {
    if run.technique != "auto" {
        techniques::find(&run.technique)?;
    }
    check_size(&run.scene)?;
    if frames == 0 {
        anyhow::bail!("--frames must be at least 1");
    }
    let loaded = load_scene(&run.scene.file, run.scene.time)?;
    if run.technique == "auto" {
        // Printed with the timings (`render`'s and `bench`'s first line),
        // after every check, so a failing command prints nothing.
        run.technique = techniques::auto(&loaded).to_owned();
    }
    let info = techniques::find(&run.technique)?;
    let params = Params::resolve(&run.technique, info.params(), &run.params)?;
    (info.check_scene)(&loaded)?;
    Ok((loaded, params))
}

/// Writes both images, or neither: both are written to temporary names and
/// renamed together (an interrupt removes the temporaries).
pub fn write_outputs(
    (exr, png): &(PathBuf, PathBuf),
    width: u32,
    height: u32,
    radiance: &[f32],
    display: &[u8],
) -> anyhow::Result<()> {
    if radiance.iter().any(|v| !v.is_finite()) {
        anyhow::bail!("the rendered radiance contains NaN or Inf; no image written");
    }
    output::write_files(vec![
        output::exr_file(exr, width, height, radiance),
        output::png_file(png, width, height, display),
    ])?;
    println!(
        "wrote {} (linear radiance) and {} (tonemapped)",
        exr.display(),
        png.display()
    );
    Ok(())
}
