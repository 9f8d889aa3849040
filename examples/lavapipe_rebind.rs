//! Reproduces, with no renderer code, why `water_photons` grew its host
//! memory by about 1.8 MB a frame on lavapipe (issue 18, BENCHMARKS.md
//! "Soak"): one compute shader (glsl/tests/uniform_branch.comp) whose loop
//! count and branch come from a uniform block, bound and dispatched
//! `--binds` times, one submission each, against the same shader with the
//! two values as specialisation constants. Lavapipe (Mesa 22.3) inlines the
//! uniform values into a new copy of the shader at every bind and compiles
//! it (a hit in Mesa's disk shader cache when the values repeat, a full
//! LLVM compile without it: `MESA_SHADER_CACHE_DISABLE=true`), keeping each
//! copy until the pipeline is destroyed. Prints the host RSS growth per bind
//! and the time per bind of each. No validation layer.
//!
//! ```sh
//! VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json \
//!   cargo run --example lavapipe_rebind -- [--binds 200]
//! ```

use caustics::shader_bindings as b;
use caustics::vk::{
    bytes, host_rss, Buffer, BufferUsage, ComputePipeline, Context, ContextOptions, DescriptorSet,
    SetResource, Specialization,
};
use std::sync::Arc;
use std::time::Instant;

/// Threads dispatched (one workgroup of uniform_branch.comp's 64).
const THREADS: usize = 64;

fn main() -> anyhow::Result<()> {
    let mut binds = 200u32;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match (a.as_str(), args.next()) {
            ("--binds", Some(v)) => binds = v.parse()?,
            _ => anyhow::bail!("usage: lavapipe_rebind [--binds N]"),
        }
    }
    let ctx = Context::new(&ContextOptions::default())?;
    println!("device: {} ({})", ctx.info.name, ctx.info.driver);
    for (label, from_constants) in [("uniform block", false), ("constants", true)] {
        let (growth, ms) = run(&ctx, from_constants, binds)?;
        println!(
            "{label:>14}: host RSS +{} over {binds} binds ({:.1} KiB a bind), {ms:.2} ms a bind",
            bytes(growth.max(0) as u64),
            growth as f64 / 1024.0 / binds as f64,
        );
    }
    Ok(())
}

/// Host RSS growth (bytes) over `binds` binds of one pipeline after a
/// warm-up of 10, and the mean milliseconds a bind and dispatch takes.
fn run(ctx: &Arc<Context>, from_constants: bool, binds: u32) -> anyhow::Result<(i64, f64)> {
    // Trip count 2 and branch 0 either way.
    let params = Buffer::with_data(ctx, "params", &[2u32, 0, 0, 0], BufferUsage::Uniform)?;
    let results = Buffer::with_data(ctx, "results", &[0.5f32; 4 * THREADS], BufferUsage::Storage)?;
    let (layout, set) = DescriptorSet::of_resources(
        ctx,
        &[
            (b::PROBE_BINDING_PARAMS, SetResource::Buffer(&params)),
            (b::PROBE_BINDING_RESULTS, SetResource::Buffer(&results)),
        ],
    )?;
    let pipeline = ComputePipeline::specialized(
        ctx,
        "tests/uniform_branch.comp",
        &Specialization::new()
            .bool(0, from_constants)
            .u32(1, 2)
            .u32(2, 0),
        &[&layout],
        0,
    )?;
    let dispatch =
        || ctx.submit_commands_and_wait(|c| c.dispatch(&pipeline, &[&set], &[], [1, 1, 1]));
    for _ in 0..10 {
        dispatch()?;
    }
    let rss = || host_rss().ok_or_else(|| anyhow::anyhow!("no VmRSS in /proc/self/status"));
    let before = rss()?;
    let start = Instant::now();
    for _ in 0..binds {
        dispatch()?;
    }
    let ms = start.elapsed().as_secs_f64() * 1e3 / binds as f64;
    Ok((rss()? as i64 - before as i64, ms))
}
