//! Surface light attenuated by the participating medium (Hu et al. 2010
//! Sect. 5.3, Fig. 2 C): `direct` multiplies each light's irradiance by the
//! transmittance tau(s, x) from the light to the surface point x and the
//! radiance by tau(x, v) toward the eye.
//!
//! - Analytic: a point light over a diffuse plane in a homogeneous medium,
//!   L = albedo / pi * I cos / r^2 * exp(-sigma_t l_light) * exp(-sigma_t l_eye),
//!   l the lengths of the two segments inside the medium's bounds (the
//!   whole segments, or clipped by a slab-shaped medium), per channel
//!   (sigma_t differs per channel). Bound 1e-3 relative.
//! - Against the reference's `direct` component (L D) on volume_cone and
//!   smoke with the lens removed (so every floor pixel is L D seen directly),
//!   128²: relative energy and FLIP mean; bounds from measurement + margin.
//! - A medium with zero coefficients renders bit-identical to no medium.
//! - Caustic photons carry tau along their air segments and the apply pass
//!   multiplies by tau(x, v): `image_space`'s caustic image (its frame minus
//!   `direct`'s) on volume_cone against the reference's L S+ D component,
//!   on the pixels whose camera ray meets a diffuse surface first.
//!
//! Measured (lavapipe, Mesa 22.3.6, 2 cores; `-- --nocapture`): see the
//! constants' comments.

use crate::common;

use caustics::params::{ParamSet, Params};
use caustics::reference::Component;
use caustics::renderer::Renderer;
use caustics::scene::{Density, Medium, Scene};
use caustics::techniques;
use common::*;
use glam::Vec3;
use std::path::Path;
use std::sync::Arc;

const SIZE: u32 = 128;
const ALBEDO: f32 = 0.5;
/// Reference photons per scene (two halves, to measure its own noise).
const PHOTONS: u64 = 8_000_000;

fn render_direct(ctx: &Arc<caustics::vk::Context>, scene: Scene, overrides: &[&str]) -> Vec<f32> {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let params = Params::resolve(
        "direct",
        techniques::direct::DirectParams::specs(),
        &overrides,
    )
    .unwrap();
    let mut renderer = Renderer::new(ctx, scene, "direct", &params, SIZE, SIZE, 0.0).unwrap();
    renderer.render_frame(0.0).unwrap();
    let radiance = renderer.radiance().unwrap();
    assert_finite(&radiance);
    radiance
}

fn homogeneous(sigma_s: Vec3, sigma_a: Vec3, min: Vec3, max: Vec3) -> Medium {
    Medium {
        sigma_s,
        sigma_a,
        g: 0.0,
        bounds_min: min,
        bounds_max: max,
        density: Density::Constant(1.0),
        multiple_scattering: false,
    }
}

fn plane_scene(medium: Option<Medium>) -> Scene {
    let mut s = scene(
        camera(Vec3::new(0.0, 4.0, 3.0), Vec3::ZERO, 60.0),
        vec![point_light(Vec3::new(0.5, 2.0, -0.5), 10.0)],
        vec![diffuse("floor", ALBEDO)],
        vec![object("floor", floor_mesh(4.0, 0.0, 0))],
    );
    s.medium = medium;
    s
}

/// Worst relative errors over the floor pixels of `plane_scene(medium)`:
/// of the radiance against the analytic L, and of the ratio to the same
/// frame without the medium against the analytic tau(s, x) tau(x, v).
fn check_plane(medium: Medium) -> (f64, f64) {
    let ctx = validated_context();
    let s = plane_scene(Some(medium.clone()));
    let radiance = render_direct(&ctx, s.clone(), &[]);
    let clear = render_direct(&ctx, plane_scene(None), &[]);
    let light = s.lights[0];
    let (lo, hi) = (medium.bounds_min.as_dvec3(), medium.bounds_max.as_dvec3());
    let sigma_t = (medium.sigma_s + medium.sigma_a).as_dvec3();
    let mut worst = 0.0f64;
    let mut worst_ratio = 0.0f64;
    let mut worst_at = (0, 0, 0);
    let mut checked = 0;
    for py in 0..SIZE {
        for px in 0..SIZE {
            let (o, d) = pixel_ray(&s.camera, SIZE, SIZE, px, py);
            let (o, d) = (o.as_dvec3(), d.as_dvec3());
            if d.y >= -1e-6 {
                continue;
            }
            let x = o + d * (-o.y / d.y);
            // Away from the plane's edge (pixel footprints straddling it).
            if x.x.abs() > 3.8 || x.z.abs() > 3.8 {
                continue;
            }
            let to_light = light.position.as_dvec3() - x;
            let r = to_light.length();
            let cos = to_light.y / r;
            let tau_light = (-sigma_t * length_in_box(x, light.position.as_dvec3(), lo, hi)).exp();
            let tau_eye = (-sigma_t * length_in_box(x, o, lo, hi)).exp();
            let expected = ALBEDO as f64 / std::f64::consts::PI * light.intensity.as_dvec3() * cos
                / (r * r)
                * tau_light
                * tau_eye;
            let i = ((py * SIZE + px) * 4) as usize;
            for c in 0..3 {
                let e = (radiance[i + c] as f64 - expected[c]).abs() / expected[c];
                if e > worst {
                    worst = e;
                    worst_at = (px, py, c);
                }
                let ratio = radiance[i + c] as f64 / clear[i + c] as f64;
                let tau = tau_light[c] * tau_eye[c];
                worst_ratio = worst_ratio.max((ratio - tau).abs() / tau);
            }
            checked += 1;
        }
    }
    assert!(checked > 5000, "only {checked} floor pixels");
    eprintln!("worst at (pixel x, pixel y, channel) {worst_at:?}");
    assert_validation_clean(&ctx);
    (worst, worst_ratio)
}

fn check(m: Medium, name: &str) {
    let (worst, worst_ratio) = check_plane(m);
    eprintln!("{name}: worst relative error {worst:.2e}, of the transmittance {worst_ratio:.2e}");
    assert!(
        worst < MAX_ANALYTIC,
        "worst relative error {worst:.2e} >= {MAX_ANALYTIC}"
    );
    assert!(
        worst_ratio < MAX_TRANSMITTANCE,
        "worst relative error of the transmittance {worst_ratio:.2e} >= {MAX_TRANSMITTANCE}"
    );
}

#[test]
fn homogeneous_medium_attenuates_direct_light_analytically() {
    // Channels with different sigma_t: 0.3, 0.15, 0.05 per metre.
    let m = homogeneous(
        Vec3::new(0.2, 0.1, 0.04),
        Vec3::new(0.1, 0.05, 0.01),
        Vec3::splat(-10.0),
        Vec3::splat(10.0),
    );
    check(m, "homogeneous medium everywhere");
}

#[test]
fn medium_slab_clips_the_attenuated_segments() {
    // A 1 m slab above the floor: the light (y = 2) and the eye (y = 4) are
    // outside it, so only the part of each segment below y = 1 attenuates.
    let m = homogeneous(
        Vec3::new(0.6, 0.3, 0.1),
        Vec3::new(0.2, 0.1, 0.05),
        Vec3::new(-10.0, 0.0, -10.0),
        Vec3::new(10.0, 1.0, 10.0),
    );
    check(m, "medium slab");
}

#[test]
fn zero_coefficients_render_bit_identical_to_no_medium() {
    let ctx = validated_context();
    let none = render_direct(&ctx, plane_scene(None), &[]);
    let zero = homogeneous(
        Vec3::ZERO,
        Vec3::ZERO,
        Vec3::splat(-10.0),
        Vec3::splat(10.0),
    );
    let with = render_direct(&ctx, plane_scene(Some(zero)), &[]);
    assert!(none.iter().any(|v| *v > 0.0));
    assert!(
        none.iter()
            .zip(&with)
            .all(|(a, b)| a.to_bits() == b.to_bits()),
        "a medium with sigma = 0 changed the image"
    );
    assert_validation_clean(&ctx);
}

fn without_lens(path: &str) -> Scene {
    let mut s = Scene::load(Path::new(path)).unwrap();
    s.objects.retain(|o| o.name != "lens");
    assert_eq!(s.objects.len(), 1, "{path}: expected floor and lens");
    s
}

fn sum_rgb(img: &[f32]) -> f64 {
    img.chunks(4)
        .map(|p| (p[0] + p[1] + p[2]) as f64)
        .sum::<f64>()
}

/// `direct` against the reference's L D component on `path` without its
/// lens: (relative energy error, FLIP mean, FLIP between the reference's halves).
fn compare_with_reference(path: &str, name: &str) -> (f64, f32, f32) {
    let ctx = validated_context();
    let actual = render_direct(&ctx, without_lens(path), &[]);
    let reference = reference_images(
        &ctx,
        // The spot light's direct light is the camera side's: PHOTONS'
        // passes with few photons each give the same images.
        &ReferenceRequest::new(&without_lens(path), SIZE, PHOTONS)
            .in_halves()
            .camera_side(),
    );
    let half_a = reference.first_half(Component::Direct);
    let truth = reference.whole(Component::Direct).to_vec();
    assert_finite(&truth);
    let half_b = second_half(&truth, half_a);
    let (noise_flip, _) = flip(&tonemap(&half_b), &tonemap(half_a), SIZE);
    let energy = (sum_rgb(&actual) - sum_rgb(&truth)).abs() / sum_rgb(&truth);
    let (flip_mean, flip_map) = flip(&tonemap(&actual), &tonemap(&truth), SIZE);
    eprintln!(
        "{name}: relative energy {energy:.5}, FLIP mean {flip_mean:.4}, reference halves FLIP {noise_flip:.4}"
    );
    let dir = write_comparison_pngs(
        &format!("medium_attenuation_{name}"),
        SIZE,
        &tonemap(&actual),
        &tonemap(&truth),
        &flip_map,
    );
    eprintln!("images in {dir}");
    assert_validation_clean(&ctx);
    (energy, flip_mean, noise_flip)
}

#[test]
fn direct_matches_reference_in_homogeneous_medium() {
    let (energy, flip_mean, _) =
        compare_with_reference("assets/scenes/volume_cone.toml", "volume_cone");
    assert!(
        energy < MAX_ENERGY,
        "relative energy {energy:.4} >= {MAX_ENERGY}"
    );
    assert!(
        flip_mean < MAX_FLIP,
        "FLIP mean {flip_mean:.4} >= {MAX_FLIP}"
    );
}

#[test]
fn direct_matches_reference_in_noise_medium() {
    let (energy, flip_mean, _) = compare_with_reference("assets/scenes/smoke.toml", "smoke");
    assert!(
        energy < MAX_ENERGY,
        "relative energy {energy:.4} >= {MAX_ENERGY}"
    );
    assert!(
        flip_mean < MAX_FLIP,
        "FLIP mean {flip_mean:.4} >= {MAX_FLIP}"
    );
}

/// `direct` (default parameters: `medium_steps` 16) vs the reference's L D
/// without the lens (128², 8 M photons): measured energy below 5e-5 on
/// volume_cone (constant density: exact transmittance) and 0.0010 on smoke
/// (below 5e-5 with `medium_steps=32`: the midpoint rule's bias); FLIP mean
/// 0.0018 and 0.0017, where the reference's two halves differ by 0.0016
/// and 0.0018. With the lights sampled from the camera (the same passes,
/// 2026-12-03): energy 0.00046 and 0.0029, FLIP 0.0014 and 0.0024 (halves
/// 0.0012 and 0.0035). Bounds: energy 0.5%, FLIP 0.005 (a missing tau on either
/// side is off by 25% or more).
const MAX_ENERGY: f64 = 0.005;
const MAX_FLIP: f32 = 0.005;

#[test]
fn image_space_caustics_are_attenuated_like_the_reference() {
    let ctx = validated_context();
    let path = Path::new("assets/scenes/volume_cone.toml");
    let load = || Scene::load(path).unwrap();
    let mask = first_hit_mask(&load(), SIZE, false, |k| {
        k == caustics::scene::MaterialKind::Diffuse
    });
    let masked = |img: Vec<f32>| masked(&img, &mask);
    let frame = |technique: &str| {
        let info = techniques::find(technique).unwrap();
        let params = Params::resolve(technique, info.params(), &[]).unwrap();
        let mut r = Renderer::new(&ctx, load(), technique, &params, SIZE, SIZE, 0.0).unwrap();
        r.render_frame(0.0).unwrap();
        masked(r.radiance().unwrap())
    };
    let full = frame("image_space");
    let direct = frame("direct");
    assert_finite(&full);
    let caustic: Vec<f32> = full.iter().zip(&direct).map(|(a, b)| a - b).collect();
    let reference = traced_reference(&ctx, &load(), SIZE, CAUSTIC_PHOTONS);
    let truth = masked(reference.whole(Component::SurfaceCaustics).to_vec());
    let energy = (sum_rgb(&caustic) - sum_rgb(&truth)) / sum_rgb(&truth);
    let (flip_mean, flip_map) = flip(&tonemap(&caustic), &tonemap(&truth), SIZE);
    eprintln!("volume_cone caustics: relative energy {energy:+.4}, FLIP mean {flip_mean:.4}");
    if energy.abs() >= MAX_CAUSTIC_ENERGY || flip_mean >= MAX_CAUSTIC_FLIP {
        let dir = write_comparison_pngs(
            "medium_attenuation_caustics",
            SIZE,
            &tonemap(&caustic),
            &tonemap(&truth),
            &flip_map,
        );
        panic!("relative energy {energy:+.4} (bound {MAX_CAUSTIC_ENERGY}), FLIP mean {flip_mean:.4} (bound {MAX_CAUSTIC_FLIP}); images in {dir}");
    }
    assert_validation_clean(&ctx);
}

const CAUSTIC_PHOTONS: u64 = 2_000_000;
/// Measured (128², 4 M photons): relative energy +0.0341, FLIP mean 0.0108;
/// at the 2 M traced since 2026-12-03 (issue 26): +0.0343, 0.0118.
/// The same comparison with the medium removed reads +0.0332 (FLIP 0.0155):
/// image_space's own difference on this scene, which the medium moves by
/// 0.1%. Without the attenuation the caustic would be about twice the
/// reference's (tau ~0.74 light side, ~0.64 eye side). Bounds: energy
/// |measured| + 0.02, FLIP about 2x measured.
const MAX_CAUSTIC_ENERGY: f64 = 0.055;
const MAX_CAUSTIC_FLIP: f32 = 0.02;

/// Against the analytic radiance: measured 8.9e-4 at the farthest, most
/// grazing floor pixels, where `direct` without any medium is off by the
/// same amount (the rasterised G-buffer position vs the exact ray hit).
const MAX_ANALYTIC: f64 = 1.5e-3;
/// The medium's own factor (frame / frame without medium vs the analytic
/// transmittance product): measured 4.2e-4 at the same far pixels (the
/// G-buffer position's error moves the segments' ends).
const MAX_TRANSMITTANCE: f64 = 1e-3;
