//! The approximate multiple scattering of the volume techniques
//! (`[medium] multiple_scattering = true`, src/passes/scattered_lights.rs,
//! glsl/passes/airlight.comp) on `light_shaft`, 64², lavapipe, validation
//! on:
//! - against the reference (its full frame, and its `other` component: the
//!   multiple scattering and the surfaces lit by the haze): relative energy
//!   and FLIP mean of the tonemapped images, for `volume_lines` and `beams`;
//! - the switch: without it the technique's `other` is exactly 0, and with
//!   it the full frame is the frame without it plus its `other`.
//!
//! Measured values are in each bound's comment and in BENCHMARKS.md
//! ("Where users look").

use crate::common;

use caustics::params::Params;
use caustics::reference::Component;
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::techniques;
use common::*;

const SIZE: u32 = 64;
/// The reference's photons: noise 11.7% at 4 M, 128² (BENCHMARKS.md).
const PHOTONS: u64 = 2 << 20;

/// `technique`'s frames of `scene` for each of `components`, with
/// parameter `overrides`.
fn frames(
    ctx: &std::sync::Arc<caustics::vk::Context>,
    scene: &Scene,
    technique: &str,
    components: &[&str],
    overrides: &[String],
) -> Vec<Vec<f32>> {
    let info = techniques::find(technique).unwrap();
    let params = Params::resolve(technique, info.params(), overrides).unwrap();
    let mut r = Renderer::new(ctx, scene.clone(), technique, &params, SIZE, SIZE, 0.0).unwrap();
    components
        .iter()
        .map(|c| {
            r.scene_gpu.components = info.component_mask(c).unwrap();
            r.render_frame(0.0).unwrap();
            let img = r.radiance().unwrap();
            assert_finite(&img);
            img
        })
        .collect()
}

/// (relative energy, FLIP mean) of `ours` against `truth`.
fn score(ours: &[f32], truth: &[f32]) -> (f64, f32) {
    let (o, t) = (energy(ours), energy(truth));
    ((o - t) / t, flip(&tonemap(ours), &tonemap(truth), SIZE).0)
}

#[test]
fn light_shaft_matches_the_reference_with_multiple_scattering() {
    let ctx = validated_context();
    let scene = canonical_scene("light_shaft");
    assert!(scene.medium.as_ref().unwrap().multiple_scattering);
    let reference = traced_reference(&ctx, &scene, SIZE, PHOTONS);
    let truth_all = reference.whole(Component::All).to_vec();
    let truth_other = reference.whole(Component::Other).to_vec();
    let mut failures = Vec::new();
    // (technique, frame bounds, `other` bounds): |energy|, FLIP. Measured
    // (2026-12-07, reference noise 20.9%): volume_lines frame -0.0440 /
    // 0.0277, other -0.1376 / 0.0219; beams frame -0.0606 / 0.0305, other
    // the same. Bounds: |energy| + 0.02 and 1.25 x FLIP, the frame's energy
    // no looser than issue 28's 5% where it is met (volume_lines: 0.05);
    // beams' frame misses it (its volume caustics are -11%, BENCHMARKS.md),
    // and its bound records that. Without the option both frames are -22%.
    for (technique, frame_bound, other_bound) in [
        ("volume_lines", (0.05, 0.035), (0.16, 0.028)),
        ("beams", (0.081, 0.039), (0.16, 0.028)),
    ] {
        let ours = frames(&ctx, &scene, technique, &["all", "other"], &[]);
        let (frame_energy, frame_flip) = score(&ours[0], &truth_all);
        let (other_energy, other_flip) = score(&ours[1], &truth_other);
        println!(
            "{technique}: frame energy {frame_energy:+.4} FLIP {frame_flip:.4}; other energy {other_energy:+.4} FLIP {other_flip:.4} (reference noise {:.1}%)",
            reference.noise.unwrap_or(f64::NAN) * 100.0
        );
        if frame_energy.abs() >= frame_bound.0 || frame_flip >= frame_bound.1 {
            failures.push(format!(
                "{technique} frame: {frame_energy:+.4}, {frame_flip:.4}"
            ));
        }
        if other_energy.abs() >= other_bound.0 || other_flip >= other_bound.1 {
            failures.push(format!(
                "{technique} other: {other_energy:+.4}, {other_flip:.4}"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("; "));
    assert_validation_clean(&ctx);
}

#[test]
fn multiple_scattering_adds_only_the_other_component() {
    let ctx = validated_context();
    let on = canonical_scene("light_shaft");
    let mut off = on.clone();
    off.medium.as_mut().unwrap().multiple_scattering = false;
    // Midpoints and fixed shadow-ray offsets: each frame draws the same
    // samples (a jittered frame draws new ones).
    let fixed = ["airlight_jitter=0".to_string()];
    let with = frames(&ctx, &on, "volume_lines", &["all", "other"], &fixed);
    let without = frames(&ctx, &off, "volume_lines", &["all", "other"], &fixed);
    assert_eq!(energy(&without[1]), 0.0, "other without the option");
    let other = energy(&with[1]);
    assert!(
        other > 0.1 * energy(&with[0]),
        "other {other} of {}",
        energy(&with[0])
    );
    // RGB adds; alpha is the frame's own.
    let sum: Vec<f32> = without[0]
        .iter()
        .zip(&with[1])
        .enumerate()
        .map(|(i, (a, b))| if i % 4 == 3 { *a } else { a + b })
        .collect();
    println!(
        "the frame with the option against the frame without it plus its other: worst {:.2e}; other {:.1}% of the frame",
        max_difference(&sum, &with[0]),
        100.0 * other / energy(&with[0])
    );
    // Up to the order of the caustic map's splats (its photons are
    // appended by atomics).
    assert_equal_up_to_splat_order(&with[0], &sum, "all = all without + other");
    assert_validation_clean(&ctx);
}
