//! Measures what a parameter change costs the demo: the time
//! `Renderer::set_params` takes plus the first frame after it (a pipeline's
//! first use may compile), for a live parameter (no rebuild) and a rebuild
//! parameter of each technique, with pipelines
//! - `none`: created anew and without the driver's cache,
//! - `cache`: created anew through the `VkPipelineCache` (empty on lavapipe),
//! - `reuse`: shared by the pipeline store (the default), plus the cache.
//!
//! Each change toggles between the default and the value below, `--repeat`
//! times; the median and minimum are printed (milliseconds). No validation.
//! `--apply-only` renders no frames (the frames dominate on lavapipe and
//! take minutes; `set_params` alone is what reuse changes).
//!
//! ```sh
//! VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json \
//!   cargo run --example param_change -- [--size 64] [--repeat 5] [--technique NAME] [--apply-only]
//! ```

use caustics::params::Params;
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::techniques;
use caustics::vk::{Context, ContextOptions};
use std::path::Path;
use std::time::Instant;

/// (technique, scene, a live change, a rebuild change that sizes resources
/// only, so no shader changes).
const CASES: &[(&str, &str, &str, &str)] = &[
    ("direct", "ball_lens", "pcf_radius=2", "shadow_map_size=512"),
    (
        "image_space",
        "ball_lens",
        "search_steps=48",
        "caustic_map_size=256",
    ),
    (
        "volume_lines",
        "volume_cone",
        "airlight_steps=32",
        "volume_buffer_size=256",
    ),
    (
        "water_photons",
        "water_pool",
        "search_steps=48",
        "ccm_size=256",
    ),
];

#[derive(Clone, Copy)]
enum Mode {
    None,
    Cache,
    Reuse,
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::None => "none",
            Mode::Cache => "cache",
            Mode::Reuse => "reuse",
        }
    }

    fn apply(self, ctx: &Context) {
        let store = ctx.pipelines();
        store.set_reuse(matches!(self, Mode::Reuse));
        store.set_driver_cache(!matches!(self, Mode::None));
    }
}

fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn resolve(technique: &str, overrides: &[&str]) -> anyhow::Result<Params> {
    let specs = techniques::find(technique)?.params();
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Params::resolve(technique, specs, &o)
}

/// (median, min) of `v`.
fn stats(v: &mut [f64]) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0])
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let size: u32 = arg(&args, "--size").map_or(Ok(64), |s| s.parse())?;
    let repeat: usize = arg(&args, "--repeat").map_or(Ok(5), |s| s.parse())?;
    let only = arg(&args, "--technique");
    let frames = !args.iter().any(|a| a == "--apply-only");
    let ctx = Context::new(&ContextOptions::default())?;
    println!("device: {} ({})", ctx.info.name, ctx.info.driver.trim());
    println!("size {size}x{size}, {repeat} changes each, ms as median (min)");
    println!(
        "{:<14} {:<24} {:<6} {:>8} {:>20} {:>20}",
        "technique", "change", "mode", "rebuilt", "set_params", "set_params+frame"
    );
    for &(technique, scene, live, rebuild) in CASES {
        if only.as_deref().is_some_and(|o| o != technique) {
            continue;
        }
        let path = format!("{}/assets/scenes/{scene}.toml", env!("CARGO_MANIFEST_DIR"));
        let scene = Scene::load(Path::new(&path))?;
        let defaults = resolve(technique, &[])?;
        for change in [live, rebuild] {
            let changed = resolve(technique, &[change])?;
            for mode in [Mode::None, Mode::Cache, Mode::Reuse] {
                mode.apply(&ctx);
                let created = ctx.pipelines().counts().created;
                let mut r =
                    Renderer::new(&ctx, scene.clone(), technique, &defaults, size, size, 0.0)?;
                if matches!(mode, Mode::None) && change == live {
                    println!(
                        "{technique}: {} pipelines per build (tonemap included)",
                        ctx.pipelines().counts().created - created
                    );
                }
                // Warm: the first frame pays first-use costs no change should.
                if frames {
                    r.render_frame(0.0)?;
                }
                let (mut apply, mut total) = (Vec::new(), Vec::new());
                let mut rebuilt = false;
                for i in 0..repeat {
                    let next = if i % 2 == 0 { &changed } else { &defaults };
                    let start = Instant::now();
                    rebuilt |= r.set_params(next)?;
                    let applied = start.elapsed().as_secs_f64() * 1e3;
                    if frames {
                        r.render_frame(0.0)?;
                    }
                    apply.push(applied);
                    total.push(start.elapsed().as_secs_f64() * 1e3);
                }
                let (am, an) = stats(&mut apply);
                let with_frame = if frames {
                    let (tm, tn) = stats(&mut total);
                    format!("{tm:>11.1} ({tn:>6.1})")
                } else {
                    "-".into()
                };
                println!(
                    "{technique:<14} {change:<24} {:<6} {rebuilt:>8} {am:>11.1} ({an:>6.1}) {with_frame:>20}",
                    mode.name(),
                );
            }
        }
    }
    let counts = ctx.pipelines().counts();
    println!(
        "pipelines created {}, reused {}",
        counts.created, counts.reused
    );
    Context::shutdown(ctx)?;
    Ok(())
}
