//! A medium inside water (docs/SCENES.md, "A medium inside a dielectric"),
//! as the ground truth renders it: sunlight refracted into flat, turbid
//! water and scattered once there is the `volume_caustics` component
//! (L S V E), which a closed form gives, seen from under the surface and
//! from above it through the surface.

use crate::common::*;
use caustics::radiometry::{fresnel_dielectric, Component};
use caustics::scene::Scene;
use glam::DVec3;

const SIZE: u32 = 48;
const IOR: f64 = 1.33;
const SURFACE: f64 = 3.0;
const HALF_EXTENT: f64 = 5.0;
const SIGMA_S: [f64; 3] = [0.2, 0.3, 0.4];
const SIGMA_A: [f64; 3] = [0.3, 0.1, 0.05];
const G: f64 = 0.5;
const IRRADIANCE: f64 = 1000.0;
/// Bounds on |reference / closed form - 1| over the whole image and over
/// each quarter of its rows: measured plus margin (BENCHMARKS.md,
/// "Underwater shafts").
const WHOLE_BOUND: f64 = 0.015;
const BAND_BOUND: f64 = 0.03;

/// Flat water 3 m deep over a black floor, 40 x 40 m, the sun 26.6° off
/// the zenith; the camera at `eye` looking at `target`.
fn flat_water(eye: [f64; 3], target: [f64; 3]) -> Scene {
    let text = format!(
        r#"
[camera]
eye = {eye:?}
target = {target:?}
fov_y = 40.0

[[light]]
kind = "directional"
direction = [0.5, -1.0, 0.0]
irradiance = {IRRADIANCE:.1}

[[material]]
name = "black"
kind = "diffuse"
albedo = 0.0

[[material]]
name = "water"
kind = "dielectric"
ior = {IOR}

[material.medium]
sigma_s = {SIGMA_S:?}
sigma_a = {SIGMA_A:?}
g = {G}

[[object]]
name = "floor"
shape = "plane"
size = [{side:.1}, {side:.1}]
material = "black"

[[object]]
name = "water"
shape = "water"
center = [0.0, 0.0]
size = [{side:.1}, {side:.1}]
resolution = [4, 4]
base_height = {SURFACE:.1}
material = "water"
"#,
        side = 2.0 * HALF_EXTENT
    );
    Scene::from_str(&text, std::path::Path::new("flat_water.toml")).unwrap()
}

/// The single-scattered radiance in the water along the ray o + t d, t in
/// [0, t_end] (o in the water): the refracted sun's beam, of irradiance
/// E (1 - F) cos(theta_i) / cos(theta_t) across it, attenuated along its
/// slant path from the surface, scattered by sigma_s p toward -d and
/// attenuated back to o; midpoint rule over 4000 steps. Points whose
/// beam entered outside the water's rectangle are unlit.
fn single_scattering(o: DVec3, d: DVec3, t_end: f64) -> [f64; 3] {
    let w_i = DVec3::new(0.5, -1.0, 0.0).normalize();
    let cos_i = -w_i.y;
    let w_t = refract(w_i, DVec3::Y, 1.0 / IOR).unwrap();
    let cos_t = -w_t.y;
    let transmitted = 1.0 - fresnel_dielectric(cos_i as f32, (1.0 / IOR) as f32) as f64;
    let across = IRRADIANCE * transmitted * cos_i / cos_t;
    let phase = hg_phase(w_t.dot(-d), G);
    let steps = 4000;
    let dt = t_end / steps as f64;
    let mut sum = [0.0; 3];
    for k in 0..steps {
        let t = (k as f64 + 0.5) * dt;
        let x = o + d * t;
        let slant = (SURFACE - x.y) / cos_t;
        let entry = x - w_t * slant;
        if entry.x.abs() > HALF_EXTENT || entry.z.abs() > HALF_EXTENT {
            continue;
        }
        for c in 0..3 {
            let sigma_t = SIGMA_S[c] + SIGMA_A[c];
            sum[c] += SIGMA_S[c] * phase * across * (-sigma_t * (slant + t)).exp() * dt;
        }
    }
    sum
}

/// The closed form per pixel centre: under the water directly; from above,
/// the refracted camera ray's, times (1 - F) / n^2 (the radiance a camera
/// in air sees through the surface).
fn expected(scene: &Scene) -> Vec<f32> {
    let mut img = vec![0.0f32; (SIZE * SIZE * 4) as usize];
    for py in 0..SIZE {
        for px in 0..SIZE {
            let (o, d) = pixel_ray(&scene.camera, SIZE, SIZE, px, py);
            let (mut o, mut d) = (o.as_dvec3(), d.as_dvec3());
            let mut factor = 1.0;
            if o.y > SURFACE {
                let t = (o.y - SURFACE) / -d.y;
                let cos = -d.y;
                factor =
                    (1.0 - fresnel_dielectric(cos as f32, (1.0 / IOR) as f32) as f64) / (IOR * IOR);
                o += d * t;
                d = refract(d, DVec3::Y, 1.0 / IOR).unwrap();
            }
            let value = single_scattering(o, d, o.y / -d.y);
            let i = ((py * SIZE + px) * 4) as usize;
            for c in 0..3 {
                img[i + c] = (value[c] * factor) as f32;
            }
        }
    }
    img
}

fn channel_sums(img: &[f32]) -> [f64; 3] {
    let mut s = [0.0; 3];
    for p in img.chunks(4) {
        for c in 0..3 {
            s[c] += p[c] as f64;
        }
    }
    s
}

/// Under the surface (the camera's eye inside the water: the light
/// tracer's connections give way to the volume gather there) and above it
/// (gathered along the refracted camera rays): the reference's
/// `volume_caustics` against the closed form, per channel and over the
/// image's upper and lower halves (near and far water); its `airlight`
/// (light scattered before any specular event: none) is black. The bound
/// is the measured difference plus a margin (BENCHMARKS.md, "Underwater
/// shafts").
#[test]
fn single_scattering_in_flat_water_matches_the_closed_form() {
    let ctx = validated_context();
    let mut worst: f64 = 0.0;
    let views = [
        ("under the surface", [0.0, 2.5, 0.0], [0.0, 0.5, 3.0]),
        ("above the surface", [0.0, 4.5, 0.0], [0.0, 1.0, 4.0]),
    ];
    for (name, eye, target) in views {
        let scene = flat_water(eye, target);
        let images = traced_reference(&ctx, &scene, SIZE, 1 << 22);
        let got = images.whole(Component::VolumeCaustics);
        assert_finite(got);
        let want = expected(&scene);
        let airlight = energy(images.whole(Component::Airlight));
        assert_eq!(airlight, 0.0, "{name}: airlight {airlight}");
        // The whole image, then four bands of rows from far water (top)
        // to near (bottom).
        let band = got.len() / 4;
        let parts = [("whole", 0..got.len())]
            .into_iter()
            .chain((0..4).map(|k| ("band", k * band..(k + 1) * band)));
        for (k, (part, range)) in parts.enumerate() {
            let (g, w) = (
                channel_sums(&got[range.clone()]),
                channel_sums(&want[range]),
            );
            for c in 0..3 {
                let rel = g[c] / w[c] - 1.0;
                println!(
                    "{name}, {part} {k}, channel {c}: reference {:.4e}, closed form {:.4e}, {:+.2}%",
                    g[c],
                    w[c],
                    rel * 100.0
                );
                let bound = if k == 0 { WHOLE_BOUND } else { BAND_BOUND };
                worst = worst.max(rel.abs() / bound);
            }
        }
    }
    assert!(worst < 1.0, "a difference is {:.2} times its bound", worst);
    assert_validation_clean(&ctx);
}
