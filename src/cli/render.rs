//! `caustics render` and `caustics bench`: frames of a real-time technique,
//! N in flight (`--frames-in-flight`), waited for once at the end.

use super::{
    check_validation, checked_technique_run, context, write_outputs, BenchArgs, DeviceArgs,
    RenderArgs, TechniqueArgs,
};
use anyhow::Context as _;
use caustics::compare::report::{
    extend_per_pass, median, per_pass, stats_per_pass, BenchReport, MemorySample, RunInfo, Timing,
    SCHEMA,
};
use caustics::output;
use caustics::params::Params;
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::techniques;
use caustics::vk::{
    bytes, host_rss, rust_heap, trim_host_heap, vulkan_host_memory, Context, FrameOptions,
    PassTiming,
};
use std::collections::BTreeMap;
use std::io::Write as _;
use std::sync::Arc;
use std::time::Instant;

pub fn render(args: RenderArgs) -> anyhow::Result<()> {
    let RenderArgs {
        mut run,
        frames,
        component,
        out,
        frame,
        device,
    } = args;
    if run.technique == "list" {
        super::info::list_techniques();
        return Ok(());
    }
    output::format_of(&out)?;
    let (loaded, params) = checked_technique_run(&mut run, frames)?;
    let components = techniques::find(&run.technique)?.component_mask(&component)?;
    let options = frame.options()?;
    let outputs = output::prepare(&out)?;
    let (ctx, mut renderer) = start(&run, loaded, &params, options, &device)?;
    let (scene, technique) = (&run.scene, &run.technique);
    renderer.scene_gpu.components = components;
    for i in 0..frames {
        renderer.submit_frame(scene.time + i as f32 / 60.0)?;
    }
    // The one wait of the run: every frame in flight.
    let done = renderer.finish()?;
    let title = format!(
        "{} at {}x{}, {} frame(s), {} in flight, mean per pass",
        technique,
        scene.width,
        scene.height,
        frames,
        renderer.frames.frames_in_flight()
    );
    let passes = per_pass(&done);
    let mean: Vec<PassTiming> = passes
        .iter()
        .map(|(name, ms)| PassTiming {
            name: name.clone(),
            ms: ms.iter().sum::<f64>() / ms.len() as f64,
        })
        .collect();
    println!("{title} ({}):", renderer.frames.source.describe());
    let mut total = 0.0;
    for t in &mean {
        println!("  {:<28} {:>9.3} ms", t.name, t.ms);
        total += t.ms;
    }
    println!("  {:<28} {:>9.3} ms", "total", total);
    let stats = renderer.scene_gpu.stats;
    println!(
        "geometry: {} triangles, BVH {} nodes ({} leaves, depth {}) built in {:.1} ms",
        stats.triangles, stats.bvh_nodes, stats.bvh_leaves, stats.bvh_depth, stats.bvh_build_ms
    );
    let radiance = renderer.radiance()?;
    let display = renderer.display()?;
    drop(renderer);
    check_validation(ctx)?;
    write_outputs(&outputs, scene.width, scene.height, &radiance, &display)
}

/// The device and a renderer for `run` with `options`' frames in flight.
fn start(
    run: &TechniqueArgs,
    scene: Scene,
    params: &Params,
    options: FrameOptions,
    device: &DeviceArgs,
) -> anyhow::Result<(Arc<Context>, Renderer)> {
    let ctx = context(device)?;
    let s = &run.scene;
    super::check_device_limits(&ctx, s)?;
    let mut renderer = Renderer::new(
        &ctx,
        scene,
        &run.technique,
        params,
        s.width,
        s.height,
        s.time,
    )
    .map_err(|e| super::name_arguments(e, s, &run.technique, &run.params))?;
    renderer.set_frame_options(options)?;
    // Frames of a still view accumulate (`render --frames N` writes their
    // mean; an animated scene's frames, at different times, do not).
    renderer.set_accumulation(true)?;
    Ok((ctx, renderer))
}

pub fn bench(args: BenchArgs) -> anyhow::Result<()> {
    let BenchArgs {
        mut run,
        frames,
        warmup,
        json,
        memory_samples,
        frame,
        device,
    } = args;
    let (loaded, params) = checked_technique_run(&mut run, frames)?;
    if memory_samples > frames {
        anyhow::bail!("--memory-samples {memory_samples}: at most --frames ({frames})");
    }
    let options = frame.options()?;
    if let Some(path) = &json {
        output::check_writable(path, "--json")?;
        output::check_replaceable(path).context("--json")?;
    }
    let (ctx, mut renderer) = start(&run, loaded, &params, options, &device)?;
    let (scene, technique) = (&run.scene, &run.technique);
    for i in 0..warmup {
        renderer.submit_frame(scene.time + i as f32 / 60.0)?;
    }
    renderer.finish()?;
    let waited_before = renderer.frames.host_wait;
    let submit_before = renderer.frames.host_submit;
    let start = Instant::now();
    // Timings are taken as numbers every so often, so a long run's host
    // memory does not grow with per-frame records. At each take every
    // pass's record is reserved for the whole run, as many values a frame
    // as the pass has run so far (beams records its refinement passes
    // several times a frame); the first take comes before the first memory
    // sample, so the Rust heap does not grow with the bench's bookkeeping
    // unless a pass first runs, or runs more often, later in the run.
    let all_frames = frames as usize;
    let (mut by_pass, mut submit_to_done) = (Vec::new(), Vec::with_capacity(all_frames));
    let mut frames_taken = 0;
    let mut take = |done: Vec<caustics::vk::FrameTiming>| {
        submit_to_done.extend(done.iter().map(|f| f.submit_to_done_ms));
        frames_taken += done.len();
        extend_per_pass(&mut by_pass, per_pass(&done));
        for (_, ms) in by_pass.iter_mut() {
            let whole_run = ms.len().div_ceil(frames_taken.max(1)) * all_frames;
            ms.reserve_exact(whole_run.saturating_sub(ms.len()));
        }
    };
    let mut memory = Vec::with_capacity(memory_samples as usize);
    // A SIGINT or SIGTERM ends the timed frames after the one in flight;
    // what was timed is printed and written (marked partial).
    let finish = super::interrupt::FinishOnSignal::new();
    eprintln!("timing {frames} frames (SIGINT or SIGTERM: stop after the frame in flight and report what was timed)");
    let asked = frames;
    let mut frames = frames;
    for i in 0..asked {
        if finish.requested() {
            frames = i;
            break;
        }
        renderer.submit_frame(scene.time + (warmup + i) as f32 / 60.0)?;
        if i % 64 == 63 {
            take(renderer.take_timings());
        }
        // After frames k * frames / samples, k = 1..=samples.
        let n = u64::from(memory_samples);
        if n > 0
            && (u64::from(i) + 1) * n / u64::from(frames) > u64::from(i) * n / u64::from(frames)
        {
            // Sampled with no frame in flight: the driver's per-frame
            // working memory (lavapipe's command execution, llvmpipe's
            // rasteriser bins) is freed again when the frame completes and
            // is not what a leak check counts.
            take(renderer.finish()?);
            let device = ctx.memory_report();
            let rss = || host_rss().context("--memory-samples: no VmRSS in /proc/self/status");
            // The untrimmed RSS moves by MiBs with the arenas' retained free
            // pages (BENCHMARKS.md "Soak"); after the trim it is memory in
            // use, which is what a leak makes grow.
            let host_rss_untrimmed = rss()?;
            let host_heap_trimmed = trim_host_heap();
            let (vulkan_host, rust_heap) = (vulkan_host_memory(), rust_heap());
            memory.push(MemorySample {
                frame: i + 1,
                host_rss: rss()?,
                host_rss_untrimmed,
                host_heap_trimmed,
                device_allocated: device.allocated,
                device_allocations: device.allocations,
                device_capacity: device.capacity,
                vulkan_host: vulkan_host.bytes,
                vulkan_host_allocations: vulkan_host.allocations,
                rust_heap: rust_heap.map(|h| h.bytes),
                rust_heap_allocations: rust_heap.map(|h| h.allocations),
            });
        }
    }
    take(renderer.finish()?);
    drop(finish);
    let partial = frames < asked;
    if frames == 0 {
        anyhow::bail!("interrupted before the first timed frame; nothing to report");
    }
    // Wall clock over the timed frames, the final wait included: what a
    // frame costs when frames overlap.
    let interval_ms = start.elapsed().as_secs_f64() * 1e3 / frames as f64;
    let wait_ms = (renderer.frames.host_wait - waited_before).as_secs_f64() * 1e3 / frames as f64;
    let submit_ms =
        (renderer.frames.host_submit - submit_before).as_secs_f64() * 1e3 / frames as f64;
    let (device_name, driver) = (ctx.info.name.clone(), ctx.info.driver.trim().to_string());
    let (source, stats) = (renderer.frames.source, renderer.scene_gpu.stats);
    let in_flight = renderer.frames.frames_in_flight();
    let counters: BTreeMap<_, _> = renderer.technique_counters().into_iter().collect();
    drop(renderer);
    check_validation(ctx)?;
    let passes = stats_per_pass(by_pass);
    println!(
        "bench {} on {} at {}x{}, {} frames{} after {} warm-up, {} in flight ({}):",
        technique,
        scene.file.scene.display(),
        scene.width,
        scene.height,
        frames,
        if partial {
            format!(" (interrupted: {asked} asked, partial)")
        } else {
            String::new()
        },
        warmup,
        in_flight,
        source.describe()
    );
    println!("  {:<28} {:>9} {:>9}", "pass", "min ms", "median ms");
    for p in &passes {
        println!("  {:<28} {:>9.3} {:>9.3}", p.name, p.min_ms, p.ms);
    }
    println!(
        "  {:<28} {:>9.3} ms (host wall clock over the frames / frames)",
        "frame interval", interval_ms
    );
    println!(
        "  {:<28} {:>9.3} ms (median; with more than one in flight it includes queueing)",
        "submit to done",
        median(&submit_to_done)
    );
    println!(
        "  {:<28} {:>9.3} ms per frame (host blocked on fences)",
        "host wait", wait_ms
    );
    println!(
        "  {:<28} {:>9.3} ms per frame (host inside vkQueueSubmit2)",
        "host submit", submit_ms
    );
    for m in &memory {
        println!(
            "  memory after frame {:>7}: host RSS {:>10} ({:>10} untrimmed), device {:>10} in {} allocations ({} in blocks)",
            m.frame,
            bytes(m.host_rss),
            bytes(m.host_rss_untrimmed),
            bytes(m.device_allocated),
            m.device_allocations,
            bytes(m.device_capacity)
        );
    }
    if let Some(path) = json {
        let report = BenchReport {
            run: RunInfo {
                schema: SCHEMA.into(),
                device: device_name,
                driver,
                timing_source: source.describe().into(),
                scene: scene.file.scene.display().to_string(),
                width: scene.width,
                height: scene.height,
                time: scene.time,
            },
            technique: technique.clone(),
            params: params
                .iter()
                .map(|(s, v)| (s.name.to_string(), v))
                .collect(),
            warmup,
            frames_in_flight: in_flight,
            timing: Timing {
                frames,
                frame_ms: interval_ms,
                passes_ms: passes,
            },
            submit_to_done_ms: median(&submit_to_done),
            host_wait_ms: wait_ms,
            host_submit_ms: submit_ms,
            geometry: stats,
            counters: counters
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
            memory,
            partial,
        };
        let text = serde_json::to_string_pretty(&report)?;
        output::write_files(vec![output::OutputFile {
            path: &path,
            write: Box::new(|w| Ok(w.write_all(text.as_bytes())?)),
        }])?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
