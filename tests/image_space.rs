//! The `image_space` technique (Wyman 2005-06 caustic maps) against physics:
//! flux conservation through the splat, IOR 1 (the caustic map gives back
//! exactly the light the sphere's shadow removed), total transmitted flux
//! against the Fresnel integral, and the ball lens's paraxial focus.
//! Lavapipe, validation on. Measured values: see each test and the
//! `--nocapture` output.

mod common;

use caustics::passes::caustic_map::GpuPhoton;
use caustics::radiometry::fresnel_dielectric;
use caustics::renderer::{FrameTargets, SceneGpu};
use caustics::scene::Scene;
use caustics::shader_bindings as b;
use caustics::techniques::image_space::{ImageSpace, PARAMS};
use caustics::techniques::{Params, Technique};
use caustics::vk::{Context, Profiler};
use common::*;
use glam::Vec3;
use std::f64::consts::PI;
use std::sync::Arc;

const LIGHT: Vec3 = Vec3::new(0.0, 8.0, 0.0);
const INTENSITY: f32 = 60.0;
const CENTRE: Vec3 = Vec3::new(0.0, 1.6, 0.0);
const RADIUS: f32 = 1.0;
const ALBEDO: f32 = 0.8;
const SIZE: u32 = 128;

fn ball_scene(ior: Option<f32>, floor_y: f32) -> Scene {
    let mut objects = vec![object("floor", floor_mesh(5.0, floor_y, 0))];
    if ior.is_some() {
        objects.push(object("lens", sphere_mesh(CENTRE, RADIUS, 1, 64)));
    }
    scene(
        camera(Vec3::new(0.0, 5.0, 7.0), Vec3::new(0.0, 0.8, 0.0), 40.0),
        vec![point_light(LIGHT, INTENSITY)],
        vec![
            diffuse("floor", ALBEDO),
            dielectric("glass", ior.unwrap_or(1.5)),
        ],
        objects,
    )
}

struct Frame {
    tech: ImageSpace,
    scene_gpu: SceneGpu,
    targets: FrameTargets,
}

fn render(ctx: &Arc<Context>, scene: &Scene, overrides: &[&str]) -> Frame {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let params = Params::resolve("image_space", PARAMS, &overrides).unwrap();
    let scene_gpu = SceneGpu::new(ctx, scene, 0.0).unwrap();
    let targets = FrameTargets::new(ctx, SIZE, SIZE).unwrap();
    let mut tech = ImageSpace::new(ctx, &params, scene, &scene_gpu, SIZE, SIZE).unwrap();
    scene_gpu.update_frame(scene, SIZE, SIZE, 0.0, 0).unwrap();
    let profiler = Profiler::new(ctx, 64).unwrap();
    profiler
        .frame(|rec| tech.record(rec, &scene_gpu, &targets))
        .unwrap();
    Frame {
        tech,
        scene_gpu,
        targets,
    }
}

fn photons(f: &Frame) -> Vec<GpuPhoton> {
    f.tech.caustics.photons.download_pod::<GpuPhoton>().unwrap()
}

/// Every layer of light 0's caustic map, RGBA per texel.
fn map_layers(f: &Frame) -> Vec<Vec<f32>> {
    (0..b::SHADOW_LAYERS_PER_LIGHT)
        .map(|l| f.tech.caustics.map.download_layer_rgba32f(l).unwrap())
        .collect()
}

#[test]
fn splat_conserves_flux() {
    let ctx = validated_context();
    let s = ball_scene(Some(1.5), 0.0);
    let f = render(
        &ctx,
        &s,
        &[
            "photon_buffer_size=256",
            "caustic_map_size=256",
            "splat_size=7",
        ],
    );
    let photon_flux: f64 = photons(&f)
        .iter()
        .filter(|p| p.position[3] == 1.0)
        .map(|p| p.flux[0] as f64)
        .sum();
    let map_flux: f64 = map_layers(&f)
        .iter()
        .flat_map(|l| l.chunks(4).map(|t| t[0] as f64))
        .sum();
    let rel = (map_flux - photon_flux).abs() / photon_flux;
    println!("photon flux {photon_flux:.6} W, caustic map flux {map_flux:.6} W, relative difference {rel:.2e}");
    assert!(photon_flux > 0.1);
    assert!(rel < 1e-4, "splat lost or gained flux: {rel:.2e}");
    assert_validation_clean(&ctx);
}

/// Analytic flux through the sphere's first-order transmission (T T), in W:
/// integral over the cone the sphere subtends of I (1 - F(theta_i))^2 dOmega
/// (the exit angle equals the entry angle in a sphere), and the flux entering it.
fn transmitted_flux(ior: f64) -> (f64, f64) {
    let d = (LIGHT - CENTRE).length() as f64;
    let r = RADIUS as f64;
    let beta_max = (r / d).asin();
    let n = 200_000;
    let (mut through, mut entering) = (0.0, 0.0);
    for i in 0..n {
        let beta = (i as f64 + 0.5) / n as f64 * beta_max;
        let sin_i = (d * beta.sin() / r).min(1.0);
        let cos_i = (1.0 - sin_i * sin_i).sqrt();
        let f = fresnel_dielectric(cos_i as f32, (1.0 / ior) as f32) as f64;
        let d_omega = 2.0 * PI * beta.sin() * beta_max / n as f64;
        entering += INTENSITY as f64 * d_omega;
        through += INTENSITY as f64 * (1.0 - f) * (1.0 - f) * d_omega;
    }
    (through, entering)
}

#[test]
fn floor_flux_matches_fresnel_transmission() {
    let ctx = validated_context();
    let s = ball_scene(Some(1.5), 0.0);
    let f = render(
        &ctx,
        &s,
        &["photon_buffer_size=256", "caustic_map_size=256"],
    );
    let ph = photons(&f);
    let n2 = ph.len() / 2;
    let refracted: f64 = ph[..n2]
        .iter()
        .filter(|p| p.position[3] == 1.0 && p.position[1].abs() < 1e-3)
        .map(|p| p.flux[0] as f64)
        .sum();
    // Every photon that met the sphere, with its full emitted flux I * Omega.
    let entering_measured: f64 = ph[..n2]
        .iter()
        .filter(|p| p.position[3] == 1.0)
        .map(|p| INTENSITY as f64 * p.flux[3] as f64)
        .sum();
    let (expected, entering) = transmitted_flux(1.5);
    let rel_in = (entering_measured - entering).abs() / entering;
    println!("flux entering the sphere: photons {entering_measured:.4} W, analytic {entering:.4} W, relative error {rel_in:.2e}");
    assert!(rel_in < 0.01, "entering flux off by {rel_in}");
    let rel = (refracted - expected).abs() / expected;
    println!(
        "flux entering the sphere {entering:.4} W (analytic), refracted flux on the floor {refracted:.4} W, analytic (1-F)^2 integral {expected:.4} W, relative error {rel:.2e}"
    );
    assert!(rel < 0.05, "relative error {rel}");
    assert_validation_clean(&ctx);
}

/// Floor pixels of the test camera: (index, angle from the light's axis at
/// the light), skipping pixels whose ray meets the sphere (with a margin).
fn floor_pixels(s: &Scene) -> Vec<(usize, f32)> {
    let mut out = Vec::new();
    for py in 0..SIZE {
        for px in 0..SIZE {
            let (o, d) = pixel_ray(&s.camera, SIZE, SIZE, px, py);
            let oc = o - CENTRE;
            let bq = oc.dot(d);
            let disc = bq * bq - (oc.length_squared() - (RADIUS * 1.03).powi(2));
            if disc > 0.0 && -bq + disc.sqrt() > 0.0 {
                continue;
            }
            if d.y >= 0.0 {
                continue;
            }
            let x = o + d * (-o.y / d.y);
            if x.x.abs() > 4.9 || x.z.abs() > 4.9 {
                continue;
            }
            let rho = (x.x * x.x + x.z * x.z).sqrt();
            out.push(((py * SIZE + px) as usize, (rho / LIGHT.y).atan()));
        }
    }
    out
}

#[test]
fn ior_one_gives_back_the_shadowed_light() {
    let ctx = validated_context();
    let with = ball_scene(Some(1.0), 0.0);
    let without = ball_scene(None, 0.0);
    let a = render(&ctx, &with, &[]);
    let b_ = render(&ctx, &without, &[]);
    let ra = a.targets.radiance.download_rgba32f().unwrap();
    let rb = b_.targets.radiance.download_rgba32f().unwrap();
    assert_finite(&ra);
    // The shadow's rim: cone half-angle asin(R / D); the caustic splat blurs
    // it by (splat/2 + 1) caustic texels of 2 / 512 rad on the -y cube face,
    // the shadow's PCF by about a shadow texel: skip 0.02 rad either side.
    let alpha = (RADIUS / (LIGHT - CENTRE).length()).asin();
    let band = 0.02;
    let (mut worst_in, mut worst_out) = (0.0f32, 0.0f32);
    let (mut sum_a, mut sum_b, mut n_in) = (0.0f64, 0.0f64, 0);
    for (i, gamma) in floor_pixels(&with) {
        let (va, vb) = (ra[4 * i], rb[4 * i]);
        let rel = (va - vb).abs() / vb;
        if gamma < alpha - band {
            worst_in = worst_in.max(rel);
            sum_a += va as f64;
            sum_b += vb as f64;
            n_in += 1;
        } else if gamma > alpha + band {
            worst_out = worst_out.max(rel);
        }
    }
    let mean_rel = (sum_a - sum_b).abs() / sum_b;
    println!(
        "IOR 1: {n_in} pixels inside the shadow cone: worst relative error {worst_in:.4}, mean {mean_rel:.2e}; outside: worst {worst_out:.2e}"
    );
    assert!(n_in > 100);
    assert!(worst_out < 1e-4, "outside the shadow: {worst_out}");
    assert!(mean_rel < 0.02, "inside the shadow, mean: {mean_rel}");
    assert!(
        worst_in < 0.02,
        "inside the shadow, worst pixel: {worst_in}"
    );
    assert_validation_clean(&ctx);
}
