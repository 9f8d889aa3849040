//! Frames in flight (`vk::Frames`): animated frames rendered with two in
//! flight, under validation with synchronization validation, end on the
//! same image as with one in flight. A host write that skipped the upload
//! ring (a frame reading the next frame's constants or geometry), a
//! descriptor set rewritten under a pending frame or a resource freed early
//! shows up as a different image or a validation error.

use crate::common;

use caustics::params::Params;
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::techniques;
use caustics::vk::FrameOptions;
use std::path::Path;

struct Run {
    /// Radiance of the last frame.
    last: Vec<f32>,
    /// Radiance after the first frame alone.
    first: Vec<f32>,
    /// Most frames seen submitted and not complete at once.
    most_pending: usize,
}

fn run(technique: &str, scene: &str, size: u32, frames: u32, in_flight: usize) -> Run {
    let ctx = common::validated_context();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
    let scene = Scene::load(&path).expect("scene");
    assert!(scene.is_animated(), "{} should be animated", path.display());
    let info = techniques::find(technique).expect("technique");
    let params = Params::resolve(technique, info.params(), &[]).expect("params");
    let mut r = Renderer::new(&ctx, scene, technique, &params, size, size, 0.0).expect("renderer");
    r.set_frame_options(FrameOptions {
        frames_in_flight: in_flight,
        ..FrameOptions::default()
    })
    .expect("frames");
    let mut first = Vec::new();
    let mut most_pending = 0;
    for i in 0..frames {
        r.submit_frame(i as f32 / 60.0).expect("frame");
        most_pending = most_pending.max(r.frames.pending());
        if i == 0 {
            r.finish().expect("first frame");
            first = r.radiance().expect("radiance");
        }
    }
    let done = r.finish().expect("frames");
    assert_eq!(done.len() as u32, frames - 1, "every frame completes once");
    let last = r.radiance().expect("radiance");
    drop(r);
    common::assert_validation_clean(&ctx);
    common::assert_finite(&last);
    Run {
        last,
        first,
        most_pending,
    }
}

/// `direct` writes each pixel once, from the frame's constants and geometry:
/// the last image is bit-exact whatever the overlap.
#[test]
fn direct_100_animated_frames_two_in_flight_match_one() {
    let scene = "assets/scenes/gemstone.toml";
    let one = run("direct", scene, 64, 100, 1);
    let two = run("direct", scene, 64, 100, 2);
    assert_eq!(one.most_pending, 1);
    assert_eq!(
        two.most_pending, 2,
        "submit_frame must not wait for the frame"
    );
    assert!(
        one.first != one.last,
        "the spinning gem should change the image over 100 frames"
    );
    assert_eq!(one.first, two.first);
    let differing = one
        .last
        .iter()
        .zip(&two.last)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differing, 0,
        "{differing} channels differ between 1 and 2 in flight"
    );
}

/// `water_photons`' splat sums may come in another order whatever the
/// frames in flight (`common::assert_equal_up_to_splat_order`). Measured on
/// lavapipe (Mesa 22.3.6, 2 cores, idle): 0, the order came out the same.
#[test]
fn water_photons_10_animated_frames_two_in_flight_match_one() {
    let scene = "assets/scenes/water_pool.toml";
    let one = run("water_photons", scene, 32, 10, 1);
    let two = run("water_photons", scene, 32, 10, 2);
    assert_eq!(
        two.most_pending, 2,
        "submit_frame must not wait for the frame"
    );
    assert!(one.first != one.last, "the waves should change the image");
    common::assert_equal_up_to_splat_order(&one.last, &two.last, "1 vs 2 in flight");
}

/// A rebuild (`set_params`) while two frames of the old technique are in
/// flight: those frames complete under the new technique, which must not
/// take their read-backs for its own (its `after_frame` would read buffers
/// no frame of its has written), while every frame's timings still come
/// back. `water_photons` reads its photon counts back per frame; the new
/// ccm_size changes the count requested, so whose counts arrive shows.
#[test]
fn a_rebuild_with_frames_in_flight_keeps_read_backs_with_their_technique() {
    let ctx = common::validated_context();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/water_pool.toml");
    let scene = Scene::load(&path).expect("scene");
    let info = techniques::find("water_photons").expect("technique");
    let resolve = |o: &[&str]| {
        let o: Vec<String> = o.iter().map(|s| s.to_string()).collect();
        Params::resolve("water_photons", info.params(), &o).expect("params")
    };
    let (before, after) = (resolve(&["ccm_size=64"]), resolve(&["ccm_size=32"]));
    let mut r =
        Renderer::new(&ctx, scene, "water_photons", &before, 32, 32, 0.0).expect("renderer");
    r.set_frame_options(FrameOptions {
        frames_in_flight: 2,
        ..FrameOptions::default()
    })
    .expect("frames");
    let requested = |r: &Renderer| {
        r.technique_counters()
            .into_iter()
            .find(|(n, _)| *n == "photons_requested")
            .map(|(_, v)| v)
    };
    r.render_frame(0.0).expect("first frame");
    let old_requested = requested(&r).expect("counts of the first frame");
    r.submit_frame(0.0).expect("frame");
    r.submit_frame(0.0).expect("frame");
    assert_eq!(r.frames.pending(), 2);
    assert!(r.set_params(&after).expect("rebuild"), "ccm_size rebuilds");
    // Reusing the oldest slot completes an old frame: not the new one's.
    r.submit_frame(0.0).expect("frame");
    assert_eq!(
        requested(&r),
        None,
        "an old frame's read-back reached the new technique"
    );
    let done = r.finish().expect("frames");
    let new_requested = requested(&r).expect("counts of the new technique's frame");
    assert_ne!(old_requested, new_requested);
    // 1 (render_frame) + 3 submitted, every one's timings reported once.
    assert_eq!(done.len(), 3, "the three frames after the first");
    drop(r);
    common::assert_validation_clean(&ctx);
}

/// A host write that bypasses the frame's upload ring is refused while
/// frames are in flight: re-uploading the scene's lights straight into the
/// buffer every frame reads (as an animation would if it skipped
/// `FrameRecorder::upload`) panics naming the ring; once the frames are
/// complete the same write is allowed (the demo's light edits wait first).
#[test]
fn a_host_write_bypassing_the_ring_is_refused_while_frames_are_in_flight() {
    let ctx = common::validated_context();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ball_lens.toml");
    let scene = Scene::load(&path).expect("scene");
    let info = techniques::find("direct").expect("technique");
    let params = Params::resolve("direct", info.params(), &[]).expect("params");
    let mut r =
        Renderer::new(&ctx, scene.clone(), "direct", &params, 32, 32, 0.0).expect("renderer");
    r.set_frame_options(FrameOptions {
        frames_in_flight: 2,
        ..FrameOptions::default()
    })
    .expect("frames");
    r.submit_frame(0.0).expect("frame");
    assert_eq!(r.frames.pending(), 1);
    let bypass = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        r.scene_gpu.update_lights(&scene)
    }));
    let message = bypass
        .expect_err("a direct write under a frame in flight must be refused")
        .downcast::<String>()
        .map(|s| *s)
        .unwrap_or_default();
    assert!(
        message.contains("FrameRecorder::upload"),
        "the refusal names the ring: {message}"
    );
    r.finish().expect("frames");
    r.scene_gpu
        .update_lights(&scene)
        .expect("allowed with no frame in flight");
    drop(r);
    common::assert_validation_clean(&ctx);
}
