//! The ground-truth light tracer against analytic answers (GUIDE §3, issue: the
//! reference must agree with them before any technique is judged against it).

mod common;

use caustics::reference::{Component, ReferenceRenderer, ReferenceSettings};
use common::*;
use glam::Vec3;

/// Point light over a diffuse plane: L = albedo / pi * I cos(theta) / r^2.
#[test]
fn point_light_on_plane_matches_inverse_square_law() {
    let ctx = validated_context();
    let (w, h) = (64, 64);
    let cam = camera(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, 50.0);
    let light = Vec3::new(0.3, 2.0, 0.2);
    let intensity = 10.0;
    let albedo = 0.6;
    let s = scene(cam, vec![point_light(light, intensity)], vec![diffuse("floor", albedo)], vec![object("floor", floor_mesh(20.0, 0.0, 0))]);
    let mut r = ReferenceRenderer::new(&ctx, s, w, h, 0.0, ReferenceSettings::default()).unwrap();
    let start = std::time::Instant::now();
    r.trace(8_000_000, |_, _| {}).unwrap();
    eprintln!("8M photons in {:.2} s", start.elapsed().as_secs_f64());
    let img = r.resolve(Component::All).unwrap();
    assert_finite(&img);
    // Compare block sums of 16x16 pixels against the analytic radiance at the pixel centres.
    let mut worst: f32 = 0.0;
    for by in 0..h / 16 {
        for bx in 0..w / 16 {
            let (mut measured, mut expected) = (0.0f64, 0.0f64);
            for y in by * 16..(by + 1) * 16 {
                for x in bx * 16..(bx + 1) * 16 {
                    let (o, d) = pixel_ray(&cam, w, h, x, y);
                    let t = -o.y / d.y;
                    let p = o + d * t;
                    let to_light = light - p;
                    let r2 = to_light.length_squared();
                    let cos = to_light.normalize().y;
                    expected += (albedo / std::f32::consts::PI * intensity * cos / r2) as f64;
                    measured += red(&img, w, x, y) as f64;
                }
            }
            let rel = ((measured - expected) / expected).abs() as f32;
            worst = worst.max(rel);
        }
    }
    eprintln!("worst 16x16 block relative error: {worst:.4}");
    assert!(worst < 0.01, "worst block error {worst}");
    assert_validation_clean(&ctx);
}
