//! The ground truth with environment and area lights against analytic
//! answers: a constant environment over a diffuse plane (E = π L), a rect
//! light's form-factor irradiance, and what the camera sees of emitters
//! (the `emitted` component: L S* E).

use crate::common;

use caustics::reference::{Component, ReferenceRenderer, ReferenceSettings};
use caustics::scene::Scene;
use common::*;
use glam::Vec3;
use std::f32::consts::PI;
use std::path::Path;

fn load(text: &str) -> Scene {
    Scene::from_str(text, Path::new("test.toml")).expect("scene")
}

/// Irradiance at a point of the plane y = 0 from a downward-facing rect of
/// radiance `l` spanning [x0, x1] x [z0, z1] (relative to the point) at
/// height `h`: the differential-area-to-parallel-rectangle form factor,
/// E = π L F, by superposing the corner rectangles
/// f(a, b) = L/2 [a/√(a²+h²) atan(b/√(a²+h²)) + b/√(b²+h²) atan(a/√(b²+h²))]
/// (odd in a and in b, so signed extents add up).
fn rect_irradiance(l: f64, h: f64, x0: f64, x1: f64, z0: f64, z1: f64) -> f64 {
    let f = |a: f64, b: f64| {
        let (ra, rb) = ((a * a + h * h).sqrt(), (b * b + h * h).sqrt());
        0.5 * l * (a / ra * (b / ra).atan() + b / rb * (a / rb).atan())
    };
    f(x1, z1) - f(x0, z1) - f(x1, z0) + f(x0, z0)
}

/// A constant environment of radiance L (a sky with zenith = horizon and no
/// sun) over a diffuse plane filling the view: E = π L, so the plane's
/// radiance is albedo · L. Measured (4 M photons, 48²): mean +0.14%, worst
/// 12x12 block 1.1%.
#[test]
fn constant_environment_over_a_plane_gives_pi_l() {
    let ctx = validated_context();
    let (w, h) = (48u32, 48u32);
    let (l, albedo) = (2.0f32, 0.6f32);
    let s = load(&format!(
        "[camera]\neye = [0.0, 3.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nfov_y = 60\n\
         [[light]]\nkind = \"environment\"\nsky = {{ sun_direction = [0.0, 1.0, 0.0], sun_radius = 0.5, sun_radiance = 0.0, zenith = {l}, horizon = {l} }}\n\
         [[material]]\nname = \"floor\"\nkind = \"diffuse\"\nalbedo = {albedo}\n\
         [[object]]\nshape = \"plane\"\nsize = [4.0, 4.0]\nmaterial = \"floor\"\n"
    ));
    let mut r = ReferenceRenderer::new(&ctx, s, w, h, 0.0, ReferenceSettings::default()).unwrap();
    let start = std::time::Instant::now();
    r.trace(4_000_000, |_, _| {}).unwrap();
    eprintln!("4M photons in {:.2} s", start.elapsed().as_secs_f64());
    let img = r.resolve(Component::Direct).unwrap();
    assert_finite(&img);
    let expected = (albedo * l) as f64;
    let mean = (0..w * h).map(|i| img[i as usize * 4] as f64).sum::<f64>() / (w * h) as f64;
    let mut worst = 0.0f64;
    for by in 0..4 {
        for bx in 0..4 {
            let mut sum = 0.0;
            for y in by * 12..(by + 1) * 12 {
                for x in bx * 12..(bx + 1) * 12 {
                    sum += red(&img, w, x, y) as f64;
                }
            }
            worst = worst.max((sum / 144.0 / expected - 1.0).abs());
        }
    }
    eprintln!("mean {mean:.5} (expected {expected}), worst block {worst:.4}");
    assert!(
        (mean / expected - 1.0).abs() < 0.01,
        "mean {mean} vs {expected}"
    );
    assert!(worst < 0.04, "worst 12x12 block error {worst}");
    // Nothing else: no background in view, no caustics.
    let emitted = r.resolve(Component::Emitted).unwrap();
    assert!(energy(&emitted) == 0.0);
    assert_validation_clean(&ctx);
}

/// A 0.5 x 0.5 m rect light 1 m above a diffuse floor, seen from the side:
/// every floor pixel against albedo/π times the form-factor irradiance at
/// its centre. Measured (4 M photons, 48²): sum over the floor −0.01%, worst
/// 12x12 block 1.3%; sampled from the camera (its 16 passes, 2026-12-03):
/// +0.08%, worst block 1.8%.
#[test]
fn rect_light_over_a_plane_matches_the_form_factor() {
    let ctx = validated_context();
    let (w, h) = (48u32, 48u32);
    let (l, albedo, height, half) = (10.0f32, 0.5f32, 1.0f32, 0.25f32);
    let s = load(&format!(
        "[camera]\neye = [0.0, 2.5, 2.5]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 50\n\
         [[light]]\nkind = \"rect\"\ncenter = [0.0, {height}, 0.0]\nnormal = [0.0, -1.0, 0.0]\nsize = [{s}, {s}]\ntangent = [1.0, 0.0, 0.0]\nradiance = {l}\n\
         [[material]]\nname = \"floor\"\nkind = \"diffuse\"\nalbedo = {albedo}\n\
         [[object]]\nshape = \"plane\"\nsize = [6.0, 6.0]\nmaterial = \"floor\"\n",
        s = 2.0 * half
    ));
    let cam = s.camera;
    // A rect light's direct light is sampled from the camera (a point on the
    // light per pixel and pass): 4M photons' passes with few photons each.
    let (settings, photons) = camera_side(ReferenceSettings::default(), 4_000_000);
    let mut r = ReferenceRenderer::new(&ctx, s, w, h, 0.0, settings).unwrap();
    r.trace(photons, |_, _| {}).unwrap();
    let img = r.resolve(Component::Direct).unwrap();
    assert_finite(&img);
    let mut expected = vec![None; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let (o, d) = pixel_ray(&cam, w, h, x, y);
            let t_rect = (height - o.y) / d.y;
            let pr = o + d * t_rect;
            if t_rect > 0.0 && pr.x.abs() < half + 0.02 && pr.z.abs() < half + 0.02 {
                continue; // the light's back (and its edge pixels)
            }
            let p = o + d * (-o.y / d.y);
            if p.x.abs() > 2.9 || p.z.abs() > 2.9 {
                continue;
            }
            let (px, pz) = (p.x as f64, p.z as f64);
            let hf = half as f64;
            let e = rect_irradiance(
                l as f64,
                height as f64,
                -hf - px,
                hf - px,
                -hf - pz,
                hf - pz,
            );
            expected[(y * w + x) as usize] = Some(albedo as f64 / PI as f64 * e);
        }
    }
    let (mut total_m, mut total_e) = (0.0, 0.0);
    let mut worst = 0.0f64;
    for by in 0..4 {
        for bx in 0..4 {
            let (mut m, mut e) = (0.0, 0.0);
            for y in by * 12..(by + 1) * 12 {
                for x in bx * 12..(bx + 1) * 12 {
                    if let Some(v) = expected[(y * w + x) as usize] {
                        m += red(&img, w, x, y) as f64;
                        e += v;
                    }
                }
            }
            total_m += m;
            total_e += e;
            if e > 0.0 {
                worst = worst.max((m / e - 1.0).abs());
            }
        }
    }
    let rel = total_m / total_e - 1.0;
    eprintln!("floor energy {rel:+.4}, worst block {worst:.4}");
    assert!(rel.abs() < 0.01, "floor energy off by {rel}");
    assert!(worst < 0.05, "worst 12x12 block error {worst}");
    assert_validation_clean(&ctx);
}

/// The emitted component: a sphere light seen directly shows its radiance,
/// the sky behind it the environment's, and a mirror (reflectance 0.5)
/// shows both halved. Exact per pixel wherever a pixel is entirely one of
/// them (the reference averages jittered rays over the pixel).
#[test]
fn emitters_are_seen_directly_and_in_a_mirror() {
    let ctx = validated_context();
    let (w, h) = (48u32, 48u32);
    let s = load(
        "[camera]\neye = [0.0, 0.0, 4.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40\n\
         [[light]]\nkind = \"environment\"\nsky = { sun_direction = [0.0, 1.0, 0.0], sun_radius = 0.5, sun_radiance = 0.0, zenith = 0.25, horizon = 0.25 }\n\
         [[light]]\nkind = \"sphere\"\ncenter = [-0.6, 0.0, 0.0]\nradius = 0.4\nradiance = [8.0, 4.0, 2.0]\n\
         [[material]]\nname = \"mirror\"\nkind = \"mirror\"\nreflectance = 0.5\n\
         [[object]]\nshape = \"plane\"\ncenter = [0.5, 0.0, 0.0]\nnormal = [-1.0, 0.0, 1.0]\nsize = [2.0, 3.0]\ntangent = [1.0, 0.0, 1.0]\nmaterial = \"mirror\"\n",
    );
    let cam = s.camera;
    let settings = ReferenceSettings {
        batch: 1 << 12,
        ..ReferenceSettings::default()
    };
    let mut r = ReferenceRenderer::new(&ctx, s, w, h, 0.0, settings).unwrap();
    r.trace(64 << 12, |_, _| {}).unwrap();
    let img = r.resolve(Component::Emitted).unwrap();
    assert_finite(&img);
    // Classify each pixel by where its centre ray and rays at its corners go.
    let sphere = (Vec3::new(-0.6, 0.0, 0.0), 0.4f32);
    let mirror_n = Vec3::new(-1.0, 0.0, 1.0).normalize();
    let hits_sphere = |o: Vec3, d: Vec3| {
        let oc = o - sphere.0;
        let b = oc.dot(d);
        let disc = b * b - (oc.length_squared() - sphere.1 * sphere.1);
        disc > 0.0 && -b - disc.sqrt() > 0.0
    };
    // What a ray sees: 0 sky, 1 sphere, 2 mirror then sky, 3 mirror then sphere.
    let classify = |o: Vec3, d: Vec3| -> u32 {
        let t_m = (Vec3::new(0.5, 0.0, 0.0) - o).dot(mirror_n) / d.dot(mirror_n);
        let pm = o + d * t_m;
        let tangent = Vec3::new(1.0, 0.0, 1.0).normalize();
        let in_mirror = t_m > 0.0
            && pm.y.abs() < 1.5
            && (pm - Vec3::new(0.5, 0.0, 0.0)).dot(tangent).abs() < 1.0;
        let sphere_first =
            hits_sphere(o, d) && (!in_mirror || (o - sphere.0).length() - sphere.1 < t_m);
        if sphere_first {
            return 1;
        }
        if in_mirror && d.dot(mirror_n) < 0.0 {
            let r = d - 2.0 * d.dot(mirror_n) * mirror_n;
            return if hits_sphere(pm + r * 1e-3, r) { 3 } else { 2 };
        }
        0
    };
    let expected = [
        Vec3::splat(0.25),
        Vec3::new(8.0, 4.0, 2.0),
        Vec3::splat(0.125),
        Vec3::new(4.0, 2.0, 1.0),
    ];
    let mut counts = [0u32; 4];
    let mut worst = 0.0f32;
    let mut worst_class = [0.0f32; 4];
    for y in 0..h {
        for x in 0..w {
            let (o, c) = pixel_ray(&cam, w, h, x, y);
            let class = classify(o, c);
            // Skip pixels on an edge: a neighbour centre classifies otherwise.
            let edge = [(-1i32, 0i32), (1, 0), (0, -1), (0, 1)]
                .iter()
                .any(|&(dx, dy)| {
                    let (nx, ny) = (x as i32 + dx, y as i32 + dy);
                    nx < 0 || ny < 0 || nx >= w as i32 || ny >= h as i32 || {
                        let (o, d) = pixel_ray(&cam, w, h, nx as u32, ny as u32);
                        classify(o, d) != class
                    }
                });
            if edge {
                continue;
            }
            counts[class as usize] += 1;
            let i = ((y * w + x) * 4) as usize;
            let got = Vec3::new(img[i], img[i + 1], img[i + 2]);
            let e = expected[class as usize];
            let err = ((got - e) / e).abs().max_element();
            worst = worst.max(err);
            worst_class[class as usize] = worst_class[class as usize].max(err);
        }
    }
    eprintln!(
        "pixels per class {counts:?}, worst relative error {worst:.2e} per class {worst_class:?}"
    );
    assert!(counts.iter().all(|&c| c > 10), "{counts:?}");
    assert!(worst < 1e-3, "worst {worst}");
    assert_validation_clean(&ctx);
}
