//! `caustics reference`: the ground truth with the GPU light tracer.

use super::{check_size, check_validation, context, load_scene, write_outputs, ReferenceArgs};
use anyhow::Context as _;
use caustics::output;
use caustics::reference::{Component, ReferenceRenderer, ReferenceSettings};

pub fn reference(args: ReferenceArgs) -> anyhow::Result<()> {
    let ReferenceArgs {
        scene,
        photons,
        seconds,
        seed,
        radius,
        no_photon_mapping,
        aim_share,
        no_aim_guide,
        fresnel_splits,
        pass_photons,
        component,
        diffuse_bounces,
        out,
        device,
    } = args;
    check_size(&scene)?;
    output::format_of(&out)?;
    let component = Component::parse(&component)?;
    super::check_photons(photons)?;
    if let Some(seconds) = seconds {
        if !(seconds.is_finite() && seconds > 0.0) {
            anyhow::bail!("--seconds must be a positive number, got {seconds}");
        }
    }
    if !(64..=1 << 24).contains(&pass_photons) || pass_photons % 64 != 0 {
        anyhow::bail!(
            "--pass-photons must be a multiple of 64 from 64 to 16777216, got {pass_photons}"
        );
    }
    let most = caustics::shader_bindings::REFERENCE_MAX_FRESNEL_SPLITS;
    if fresnel_splits > most {
        anyhow::bail!("--fresnel-splits must lie in 0..={most}, got {fresnel_splits}");
    }
    if let Some(r) = radius {
        if !(r.is_finite() && r > 0.0) {
            anyhow::bail!("--radius must be a positive length in metres, got {r}");
        }
    }
    let loaded = load_scene(&scene.file, scene.time)?;
    let outputs = output::prepare(&out)?;
    let ctx = context(&device)?;
    super::check_device_limits(&ctx, &scene)?;
    let settings = ReferenceSettings {
        diffuse_bounces,
        seed,
        radius,
        photon_mapping: !no_photon_mapping,
        aim_share,
        aim_guide: !no_aim_guide,
        fresnel_splits,
        batch: pass_photons,
        ..Default::default()
    };
    // Whole passes: say so when --photons is not a multiple of one.
    let batch = settings.pass_photons();
    let rounded = settings.passes_for(photons) * batch;
    if seconds.is_none() && rounded != photons {
        println!("--photons {photons}: rounded up to {rounded}, whole passes of {batch}");
    }
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

/// Runs reference passes until `photons` are traced or `seconds` have
/// passed, with a progress bar that shows per pass the photons, the
/// photon-mapping radius and the remaining noise; then prints the totals.
/// Returns whether a signal cut it short (after the pass in flight).
pub(super) fn trace_reference(
    reference: &mut ReferenceRenderer,
    photons: u64,
    seconds: Option<f64>,
) -> anyhow::Result<bool> {
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
    // SIGINT/SIGTERM while tracing: finish the pass in flight, then write.
    let finish = super::interrupt::FinishOnSignal::new();
    let mut interrupted = false;
    loop {
        let elapsed = start.elapsed().as_secs_f64();
        let done = match seconds {
            Some(s) => elapsed >= s,
            None => reference.photons() >= photons,
        };
        if done {
            break;
        }
        let report = reference.pass()?;
        let noise = reference.noise()?;
        let noise = noise.map_or("-".to_string(), |n| format!("{:.2}%", n * 100.0));
        let message = format!(
            "pass {} at {:.1} s, r {:.4} m, noise {}",
            reference.passes(),
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
                bar.set_position(reference.photons().min(photons));
                bar.set_message(message.clone());
            }
        }
        if bar.is_hidden() {
            eprintln!("{} photons, {message}", reference.photons());
        }
        if finish.requested() {
            interrupted = true;
            break;
        }
    }
    drop(finish);
    bar.finish_and_clear();
    if interrupted {
        println!(
            "interrupted: writing the {} photons traced so far",
            reference.photons()
        );
    }
    let noise = reference.noise()?;
    println!(
        "traced {} photons in {} passes, {:.2} s: {:.3} M photons/s; last radius {:.4} m; remaining noise {}",
        reference.photons(),
        reference.passes(),
        reference.trace_seconds,
        reference.photons_per_second() / 1e6,
        reference.radius(),
        noise.map_or("unknown (one pass)".to_string(), |n| format!("{:.2}%", n * 100.0)),
    );
    let passes = reference.passes().max(1) as f64;
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
            reference.volume_capacity()
        );
    }
    if reference.gather_overflow > 0 {
        eprintln!(
            "warning: {} points on camera paths in the medium did not fit the gather buffer ({} per pass); the volume gather missed them",
            reference.gather_overflow,
            reference.gather_capacity()
        );
    }
    if reference.longest_walk >= caustics::shader_bindings::REFERENCE_GATHER_WALK_LIMIT {
        eprintln!(
            "warning: a volume gather walk reached {} photons in one grid cell and was cut short; pass fewer photons a pass (--pass-photons) or a smaller --radius",
            caustics::shader_bindings::REFERENCE_GATHER_WALK_LIMIT
        );
    }
    Ok(interrupted)
}
