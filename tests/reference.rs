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
    let s = scene(
        cam,
        vec![point_light(light, intensity)],
        vec![diffuse("floor", albedo)],
        vec![object("floor", floor_mesh(20.0, 0.0, 0))],
    );
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

/// Single-scattered airlight in a homogeneous medium against a numerical
/// integral along each camera ray: L = int T(eye,x) sigma_s p(theta) I / |x-l|^2 T(x,l) dt.
#[test]
fn airlight_matches_numerical_single_scattering_integral() {
    use caustics::radiometry::henyey_greenstein;
    use caustics::scene::{Density, Medium};
    let ctx = validated_context();
    let (w, h) = (64, 64);
    // The light sits above the view so no camera ray passes near its 1/r^2 singularity.
    let cam = camera(Vec3::new(0.0, 1.0, 6.0), Vec3::new(0.0, 0.0, 0.0), 40.0);
    let light = Vec3::new(0.0, 3.0, 0.0);
    let intensity = 100.0;
    let (sigma_s, sigma_a, g) = (0.1f32, 0.05f32, 0.3f32);
    let (bmin, bmax) = (Vec3::new(-4.0, -1.0, -4.0), Vec3::new(4.0, 4.0, 4.0));
    let mut s = scene(
        cam,
        vec![point_light(light, intensity)],
        vec![diffuse("black", 0.0)],
        vec![object("floor", floor_mesh(20.0, -1.0, 0))],
    );
    s.medium = Some(Medium {
        sigma_s: Vec3::splat(sigma_s),
        sigma_a: Vec3::splat(sigma_a),
        g,
        bounds_min: bmin,
        bounds_max: bmax,
        density: Density::Constant(1.0),
    });
    let mut r = ReferenceRenderer::new(&ctx, s, w, h, 0.0, ReferenceSettings::default()).unwrap();
    r.trace(16_000_000, |_, _| {}).unwrap();
    let img = r.resolve(Component::Airlight).unwrap();
    assert_finite(&img);
    let sigma_t = sigma_s + sigma_a;
    let analytic = |o: Vec3, d: Vec3| -> f64 {
        // Entry and exit of the medium box, and the floor (y = -1) ends the ray.
        let inv = d.recip();
        let (a, b) = ((bmin - o) * inv, (bmax - o) * inv);
        let t0 = a.min(b).max_element().max(0.0);
        let mut t1 = a.max(b).min_element();
        if d.y < 0.0 {
            t1 = t1.min((-1.0 - o.y) / d.y);
        }
        if t1 <= t0 {
            return 0.0;
        }
        let n = 4000;
        let dt = (t1 - t0) / n as f32;
        (0..n)
            .map(|i| {
                let t = t0 + (i as f32 + 0.5) * dt;
                let x = o + d * t;
                let to_x = x - light;
                let r2 = to_x.length_squared();
                let cos = to_x.normalize().dot(-d);
                let tr = (-sigma_t * (t - t0)).exp() * (-sigma_t * r2.sqrt()).exp();
                (tr * sigma_s * henyey_greenstein(cos, g) * intensity / r2 * dt) as f64
            })
            .sum()
    };
    let mut worst: f32 = 0.0;
    for by in 0..h / 32 {
        for bx in 0..w / 32 {
            let (mut measured, mut expected) = (0.0f64, 0.0f64);
            for y in by * 32..(by + 1) * 32 {
                for x in bx * 32..(bx + 1) * 32 {
                    let (o, d) = pixel_ray(&cam, w, h, x, y);
                    expected += analytic(o, d);
                    measured += red(&img, w, x, y) as f64;
                }
            }
            worst = worst.max(((measured - expected) / expected).abs() as f32);
        }
    }
    eprintln!("airlight: worst 32x32 block relative error {worst:.4}");
    assert!(worst < 0.02, "worst block error {worst}");
    assert_validation_clean(&ctx);
}

/// A glass slab at normal incidence transmits (1 - F)^2 of the light, F = ((n-1)/(n+1))^2
/// (the internal reflections add F^2 (1-F)^2 + ..., 0.16% more at n = 1.5, inside the bound).
#[test]
fn glass_slab_transmits_one_minus_fresnel_squared() {
    let ctx = validated_context();
    let (w, h) = (64, 64);
    // The camera looks at the floor from below the slab.
    let cam = camera(Vec3::new(0.0, 0.6, 3.5), Vec3::new(0.0, 0.0, 0.0), 60.0);
    let (irradiance, albedo, n) = (2.0f32, 0.5f32, 1.5f32);
    let s = scene(
        cam,
        vec![directional_light(Vec3::NEG_Y, irradiance)],
        vec![diffuse("floor", albedo), dielectric("glass", n)],
        vec![
            object("floor", floor_mesh(4.0, 0.0, 0)),
            object(
                "slab",
                box_mesh(Vec3::new(-3.0, 1.0, -3.0), Vec3::new(3.0, 1.2, 3.0), 1),
            ),
        ],
    );
    let mut r = ReferenceRenderer::new(&ctx, s, w, h, 0.0, ReferenceSettings::default()).unwrap();
    r.trace(8_000_000, |_, _| {}).unwrap();
    let caustic = r.resolve(Component::SurfaceCaustics).unwrap();
    let direct = r.resolve(Component::Direct).unwrap();
    assert_finite(&caustic);
    let (mut measured, mut count, mut direct_sum) = (0.0f64, 0usize, 0.0f64);
    for y in 0..h {
        for x in 0..w {
            let (o, d) = pixel_ray(&cam, w, h, x, y);
            let p = o + d * (-o.y / d.y);
            if d.y < 0.0 && p.x.abs() < 2.0 && p.z.abs() < 2.0 {
                measured += red(&caustic, w, x, y) as f64;
                direct_sum += red(&direct, w, x, y) as f64;
                count += 1;
            }
        }
    }
    let f = ((n - 1.0) / (n + 1.0)).powi(2);
    let expected = (albedo / std::f32::consts::PI * irradiance * (1.0 - f).powi(2)) as f64;
    let mean = measured / count as f64;
    let rel = ((mean - expected) / expected).abs();
    eprintln!(
        "slab: {count} pixels, mean {mean:.5}, expected {expected:.5}, relative error {rel:.4}"
    );
    assert!(count > 500, "the test region must be visible");
    assert!(rel < 0.01, "transmitted radiance off by {rel}");
    assert!(
        direct_sum == 0.0,
        "no direct light reaches the floor under the slab"
    );
    assert_validation_clean(&ctx);
}

/// A glass ball focuses a narrow beam at f = n R / (2 (n - 1)) from its centre
/// (paraxial), shifted by the lens equation 1/v = 1/f - 1/s for a source at
/// distance s. The spot's RMS radius on floors at several heights is fitted
/// with a parabola; its minimum must lie within 5% of v.
#[test]
fn ball_lens_focuses_at_paraxial_focal_length() {
    let ctx = validated_context();
    let (radius, n, centre_y, source_distance) = (1.0f32, 1.5f32, 3.0f32, 50.0f32);
    let f = n * radius / (2.0 * (n - 1.0));
    let v = 1.0 / (1.0 / f - 1.0 / source_distance);
    // A spot light whose cone just covers the central 0.2 R of the ball (paraxial rays).
    let cone = (0.2 * radius / source_distance).atan().to_degrees();
    let light = caustics::scene::Light {
        kind: caustics::scene::LightKind::Spot,
        position: Vec3::new(0.0, centre_y + source_distance, 0.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(1000.0),
        cone_angle_deg: cone,
        cone_falloff_deg: 0.0,
    };
    let (w, h) = (96, 96);
    let mut samples = Vec::new();
    for k in [0.85f32, 0.925, 1.0, 1.075, 1.15] {
        let floor_y = centre_y - v * k;
        let cam = camera(
            Vec3::new(0.0, floor_y + 0.25, 1.2),
            Vec3::new(0.0, floor_y, 0.0),
            12.0,
        );
        let s = scene(
            cam,
            vec![light],
            vec![diffuse("floor", 0.8), dielectric("glass", n)],
            vec![
                object("floor", floor_mesh(3.0, floor_y, 0)),
                object(
                    "ball",
                    sphere_mesh(Vec3::new(0.0, centre_y, 0.0), radius, 1, 96),
                ),
            ],
        );
        let mut r =
            ReferenceRenderer::new(&ctx, s, w, h, 0.0, ReferenceSettings::default()).unwrap();
        r.trace(1_000_000, |_, _| {}).unwrap();
        let img = r.resolve(Component::SurfaceCaustics).unwrap();
        assert_finite(&img);
        // Radiance-weighted second moment of the floor positions of the spot.
        let (mut sw, mut sx, mut sz, mut sxx) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for y in 0..h {
            for x in 0..w {
                let value = red(&img, w, x, y) as f64;
                if value <= 0.0 {
                    continue;
                }
                let (o, d) = pixel_ray(&cam, w, h, x, y);
                let p = o + d * ((floor_y - o.y) / d.y);
                sw += value;
                sx += value * p.x as f64;
                sz += value * p.z as f64;
                sxx += value * (p.x as f64 * p.x as f64 + p.z as f64 * p.z as f64);
            }
        }
        assert!(sw > 0.0, "the caustic must be visible at k = {k}");
        let (cx, cz) = (sx / sw, sz / sw);
        let rms2 = sxx / sw - cx * cx - cz * cz;
        eprintln!("floor at {k:.3} v: RMS spot radius {:.4} m", rms2.sqrt());
        samples.push((k as f64, rms2));
    }
    let (a, b) = fit_parabola(&samples);
    let best = -b / (2.0 * a);
    eprintln!("best focus at {best:.4} v (v = {v:.4} m from the centre, f = {f})");
    assert!(a > 0.0, "the spot must shrink then grow");
    assert!((best - 1.0).abs() < 0.05, "focus at {best} v");
    assert_validation_clean(&ctx);
}

/// Least-squares parabola y = a x^2 + b x + c through the samples; returns (a, b)
/// (normal equations solved by Cramer's rule).
fn fit_parabola(samples: &[(f64, f64)]) -> (f64, f64) {
    let sum = |f: &dyn Fn(f64, f64) -> f64| samples.iter().map(|&(x, y)| f(x, y)).sum::<f64>();
    let (s0, s1, s2) = (samples.len() as f64, sum(&|x, _| x), sum(&|x, _| x * x));
    let (s3, s4) = (sum(&|x, _| x * x * x), sum(&|x, _| x * x * x * x));
    let (t0, t1, t2) = (sum(&|_, y| y), sum(&|x, y| x * y), sum(&|x, y| x * x * y));
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let m = [[s4, s3, s2], [s3, s2, s1], [s2, s1, s0]];
    let d = det3(m);
    let a = det3([[t2, s3, s2], [t1, s2, s1], [t0, s1, s0]]) / d;
    let b = det3([[s4, t2, s2], [s3, t1, s1], [s2, t0, s0]]) / d;
    (a, b)
}
