//! Still-view accumulation (issue 28, `Renderer::set_accumulation`): the
//! frames of an unchanged view average, each drawing new samples of the
//! stochastic passes (here `direct`'s sky visibility under `ring_sky`'s
//! environment, 16 rays a pixel), so that a still frame converges instead
//! of keeping its grain; any change starts over from a single frame.

use crate::common;

use caustics::params::Params;
use caustics::radiometry::Component;
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::techniques;
use common::*;

const SIZE: u32 = 48;

/// Still frames accumulated before two consecutive ones are compared.
const STILL_FRAMES: usize = 16;

/// The still views' size (both sides).
const STILL_SIZE: u32 = 48;

fn renderer(ctx: &std::sync::Arc<caustics::vk::Context>, accumulate: bool) -> Renderer {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ring_sky.toml");
    let scene = Scene::load(&path).unwrap();
    let info = techniques::find("direct").unwrap();
    let params = Params::resolve("direct", info.params(), &[]).unwrap();
    let mut r = Renderer::new(ctx, scene, "direct", &params, SIZE, SIZE, 0.0).unwrap();
    r.set_accumulation(accumulate).unwrap();
    r
}

fn frame(r: &mut Renderer) -> Vec<f32> {
    r.render_frame(0.0).unwrap();
    let img = r.radiance().unwrap();
    assert_finite(&img);
    img
}

/// RMS over pixels of the rgb difference, relative to the mean pixel.
fn relative_rms(a: &[f32], b: &[f32]) -> f64 {
    let n = a.len() as f64 / 4.0;
    let sq: f64 = a
        .chunks(4)
        .zip(b.chunks(4))
        .map(|(p, q)| (0..3).map(|c| ((p[c] - q[c]) as f64).powi(2)).sum::<f64>())
        .sum();
    (sq / n).sqrt() / (energy(b) / n)
}

/// The first frame is the frame itself (bit for bit what a renderer
/// without accumulation draws); 64 still frames take the sky visibility's
/// per-pixel noise to under half that of one frame against a 256-frame
/// mean (independent samples: 1/8 of it in theory); and after 64 frames
/// two consecutive still frames differ by FLIP <= 0.01 (issue 28's bound).
#[test]
fn still_frames_converge_and_consecutive_ones_agree() {
    let ctx = validated_context();
    let single = frame(&mut renderer(&ctx, false));
    let mut r = renderer(&ctx, true);
    let first = frame(&mut r);
    assert_eq!(
        first, single,
        "the first accumulated frame is the frame itself"
    );
    let mut mean = first.clone();
    for _ in 1..64 {
        mean = frame(&mut r);
    }
    let next = frame(&mut r);
    let (flip_mean, _) = flip(&tonemap(&mean), &tonemap(&next), SIZE);
    let mut converged = next.clone();
    for _ in 65..256 {
        converged = frame(&mut r);
    }
    let (one, many) = (
        relative_rms(&first, &converged),
        relative_rms(&mean, &converged),
    );
    println!(
        "ring_sky, direct, {SIZE}²: noise of 1 frame {:.4}, of 64 frames {:.4} (against 256); FLIP between frames 64 and 65: {flip_mean:.5}",
        one, many
    );
    assert!(one > 0.0, "the sky visibility is noisy in one frame");
    assert!(
        many < 0.5 * one,
        "64 frames: {many} against one frame's {one}"
    );
    assert!(
        flip_mean <= 0.01,
        "consecutive still frames: FLIP {flip_mean}"
    );
    assert_validation_clean(&ctx);
}

/// A change between frames starts over: after frames of one view, a frame
/// with another camera, or with other components drawn, is exactly the
/// single frame a fresh renderer draws of that view.
#[test]
fn a_changed_view_starts_over() {
    let ctx = validated_context();
    let mut r = renderer(&ctx, true);
    for _ in 0..4 {
        frame(&mut r);
    }
    r.scene.camera.eye += glam::Vec3::new(0.05, 0.0, 0.0);
    let moved = frame(&mut r);
    let mut fresh = renderer(&ctx, false);
    fresh.scene.camera = r.scene.camera;
    assert_eq!(moved, frame(&mut fresh), "a moved camera starts over");

    frame(&mut r);
    r.scene_gpu.components = Component::Direct.mask();
    fresh.scene_gpu.components = Component::Direct.mask();
    assert_eq!(
        frame(&mut r),
        frame(&mut fresh),
        "other components start over"
    );
    assert_validation_clean(&ctx);
}

/// Every technique, in a still view that exercises its stochastic passes
/// (the sky visibility under `ring_sky`'s environment, the airlight's
/// jitter in `light_shaft`'s haze, `pinhole`'s samples, the water's
/// photons): after accumulation two consecutive still frames differ by
/// FLIP <= 0.01 (issue 28's bound).
#[test]
fn every_techniques_still_frames_agree_after_accumulation() {
    let ctx = validated_context();
    for info in techniques::TECHNIQUES {
        let scene = match info.name {
            "water_photons" => "water_pool",
            "beams" | "volume_lines" => "light_shaft",
            _ => "ring_sky",
        };
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("assets/scenes/{scene}.toml"));
        let params = Params::resolve(info.name, info.params(), &[]).unwrap();
        let start = std::time::Instant::now();
        let mut r = Renderer::new(
            &ctx,
            Scene::load(&path).unwrap(),
            info.name,
            &params,
            STILL_SIZE,
            STILL_SIZE,
            0.0,
        )
        .unwrap();
        r.set_accumulation(true).unwrap();
        let first = frame(&mut r);
        let mut last = first.clone();
        for _ in 1..STILL_FRAMES {
            last = frame(&mut r);
        }
        let next = frame(&mut r);
        let (single, _) = flip(&tonemap(&first), &tonemap(&next), STILL_SIZE);
        let (still, _) = flip(&tonemap(&last), &tonemap(&next), STILL_SIZE);
        println!(
            "{}, {scene}, {STILL_SIZE}²: FLIP between frames {STILL_FRAMES} and {}: {still:.5} (frame 1 against {}: {single:.4}); {:.1} s",
            info.name,
            STILL_FRAMES + 1,
            STILL_FRAMES + 1,
            start.elapsed().as_secs_f64()
        );
        assert!(
            still <= 0.01,
            "{} on {scene}: consecutive still frames differ by FLIP {still}",
            info.name
        );
    }
    assert_validation_clean(&ctx);
}
