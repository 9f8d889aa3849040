//! Resize storm (issue 18): the demo's resize path headless
//! (`Renderer::resize`: new frame targets, tonemap and technique, the old
//! ones released after the frames in flight that use them), 100 times with
//! two frames in flight, through 1x1 and a refused 0x0 (a minimised window,
//! which the demo skips), under validation with synchronization
//! validation. Nothing may leak: gpu-allocator's live bytes and
//! allocations after the storm equal those before it (within 1%, measured
//! exactly equal), and the frame at the first size renders the same image.

use crate::common;

use caustics::params::Params;
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::techniques;
use caustics::vk::FrameOptions;
use std::path::Path;

#[test]
fn a_hundred_resizes_with_frames_in_flight_leak_nothing() {
    let ctx = common::validated_context();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ball_lens.toml");
    let scene = Scene::load(&path).expect("scene");
    let info = techniques::find("direct").expect("direct");
    let given = ["shadow_map_size=64".to_string()];
    let params = Params::resolve("direct", info.params(), &given).expect("params");
    let (w0, h0) = (48, 40);
    let mut r = Renderer::new(&ctx, scene, "direct", &params, w0, h0, 0.0).expect("renderer");
    r.set_frame_options(FrameOptions {
        frames_in_flight: 2,
        ..FrameOptions::default()
    })
    .expect("frames");
    // Warm up every frame slot (each grows its upload ring on first use),
    // then the frame to compare with.
    for i in 0..4 {
        r.submit_frame(i as f32).expect("frame");
    }
    r.render_frame(0.0).expect("frame");
    let image = r.radiance().expect("radiance");
    let before = ctx.memory_report();
    let heaps_before = ctx.memory.heaps();

    let mut sizes = Vec::new();
    for i in 0..100u32 {
        sizes.push(match i % 10 {
            3 => (1, 1),
            7 => (0, 0),
            8 => (64, 1),
            _ => (32 + (i * 7) % 33, 32 + (i * 13) % 33),
        });
    }
    let mut refused = 0;
    for (i, &(w, h)) in sizes.iter().enumerate() {
        let old = (r.targets.width, r.targets.height);
        match r.resize(w, h) {
            Ok(()) => assert_eq!((r.targets.width, r.targets.height), (w, h)),
            Err(e) => {
                assert_eq!((w, h), (0, 0), "resize to {w}x{h}: {e:#}");
                assert!(e.to_string().contains("0x0"), "{e}");
                assert_eq!((r.targets.width, r.targets.height), old, "size kept");
                refused += 1;
            }
        }
        // Frames stay in flight across the next resize.
        r.submit_frame(i as f32 / 60.0).expect("frame");
        r.submit_frame(i as f32 / 60.0 + 0.01).expect("frame");
        assert!(r.frames.pending() > 0);
    }
    assert_eq!(refused, 10);
    r.resize(w0, h0).expect("back to the first size");
    r.render_frame(0.0).expect("frame");
    r.finish().expect("finish");
    let after = ctx.memory_report();
    let again = r.radiance().expect("radiance");
    assert_eq!(
        common::max_difference(&image, &again),
        0.0,
        "the first size renders the same image after the storm"
    );
    println!("device memory before {before:?}, after {after:?}");
    let within = |a: u64, b: u64| (a as f64 - b as f64).abs() <= 0.01 * b as f64;
    assert!(
        within(after.allocated, before.allocated),
        "live bytes {} before, {} after",
        before.allocated,
        after.allocated
    );
    assert_eq!(after.allocations, before.allocations, "live allocations");
    assert_eq!(
        ctx.memory.heaps(),
        heaps_before,
        "the heap accounting returns"
    );
    drop(r);
    common::assert_validation_clean(&ctx);
}
