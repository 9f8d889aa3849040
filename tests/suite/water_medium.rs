//! A medium inside water (docs/SCENES.md, "A medium inside a dielectric"),
//! as the ground truth renders it: sunlight refracted into flat, turbid
//! water and scattered once there is the `volume_caustics` component
//! (L S V E), which a closed form gives, seen from under the surface and
//! from above it through the surface.

use crate::common::*;
use caustics::radiometry::{fresnel_dielectric, Component};
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::vk::Context;
use glam::DVec3;
use std::sync::Arc;

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
/// `water_photons`' shafts against the same closed form.
const SHAFTS_WHOLE_BOUND: f64 = 0.025;
const SHAFTS_BAND_BOUND: f64 = 0.03;
/// `water_photons` on `pool_shafts` against the reference: measured plus
/// margin (BENCHMARKS.md, "Underwater shafts").
const POOL_SHAFTS_SURFACE_ENERGY_BOUND: f64 = 0.03;
const POOL_SHAFTS_SURFACE_FLIP_BOUND: f32 = 0.13;
const POOL_SHAFTS_VOLUME_ENERGY_BOUND: f64 = 0.09;
const POOL_SHAFTS_VOLUME_HALF_BOUND: f64 = 0.12;
const POOL_SHAFTS_VOLUME_FLIP_BOUND: f32 = 0.06;

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

/// |got / want − 1| per channel over the whole image and over four bands
/// of its rows (far water at the top to near at the bottom), printed; the
/// largest as a multiple of its bound (`whole`, `band`).
fn worst_band_error(label: &str, got: &[f32], want: &[f32], whole: f64, band: f64) -> f64 {
    let rows = got.len() / 4;
    let parts = std::iter::once(0..got.len()).chain((0..4).map(|k| k * rows..(k + 1) * rows));
    let mut worst: f64 = 0.0;
    for (k, range) in parts.enumerate() {
        let (g, w) = (
            channel_sums(&got[range.clone()]),
            channel_sums(&want[range]),
        );
        let part = if k == 0 {
            "whole".to_string()
        } else {
            format!("band {k}")
        };
        for c in 0..3 {
            let rel = g[c] / w[c] - 1.0;
            println!(
                "{label}, {part}, channel {c}: {:.4e} against {:.4e}, {:+.2}%",
                g[c],
                w[c],
                rel * 100.0
            );
            worst = worst.max(rel.abs() / if k == 0 { whole } else { band });
        }
    }
    worst
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
        worst = worst.max(worst_band_error(name, got, &want, WHOLE_BOUND, BAND_BOUND));
    }
    assert!(worst < 1.0, "a difference is {:.2} times its bound", worst);
    assert_validation_clean(&ctx);
}

/// One `water_photons` frame of `s` at `size`², the component `c` only.
fn water_photons_frame(ctx: &Arc<Context>, s: Scene, size: u32, c: Component) -> Vec<f32> {
    use caustics::params::{ParamSet, Params};
    let params = Params::resolve(
        "water_photons",
        caustics::techniques::water_photons::WaterPhotonsParams::specs(),
        &[],
    )
    .unwrap();
    let mut r = Renderer::new(ctx, s, "water_photons", &params, size, size, 0.0).unwrap();
    r.scene_gpu.components = c.mask();
    r.render_frame(0.0).unwrap();
    r.radiance().unwrap()
}

/// `scene` with its water's medium scattering `scale` times as much
/// (absorption unchanged).
fn scaled_scattering(scene: &Scene, scale: f32) -> Scene {
    let mut s = scene.clone();
    for m in &mut s.materials {
        if let Some(inside) = m.scattering.as_mut() {
            inside.sigma_s *= scale;
        }
    }
    s
}

/// Mean FLIP over the pixels `mask` keeps.
fn masked_flip(test: &[f32], reference: &[f32], mask: &[bool], size: u32) -> f32 {
    let (_, map) = flip(&tonemap(test), &tonemap(reference), size);
    let kept: Vec<f32> = map
        .values()
        .iter()
        .zip(mask)
        .filter(|(_, &m)| m)
        .map(|(v, _)| *v)
        .collect();
    kept.iter().sum::<f32>() / kept.len() as f32
}

/// `pool_shafts` from under the surface, `water_photons` against the
/// reference (the bounds: measured plus margin, BENCHMARKS.md "Underwater
/// shafts"):
/// - surface caustics (L S+ D S* E) over the pixels that see the floor,
///   walls and columns directly (through the water, without crossing its
///   surface): both attenuate by the water's extinction σa + σs on the
///   light's way down (the trace's refracted flux) and on the view's (the
///   water view under the surface); in clear water the same frame is far
///   brighter, so neither attenuation can be lost unseen;
/// - volume caustics (the shafts: sunlight scattered in the water after its
///   refraction, L S V), over the whole frame and over the upper and lower
///   halves;
/// - the shafts vanish without scattering and grow linearly with a small
///   σs (0.01 and 0.02 times the scene's: twice the light within 2%).
#[test]
fn pool_shafts_from_below_match_the_reference() {
    use caustics::scene::MaterialKind;
    const SIZE: u32 = 64;
    let ctx = validated_context();
    let scene = canonical_scene("pool_shafts");
    let reference = traced_reference(&ctx, &scene, SIZE, 1 << 21);
    let mask = eroded(
        &first_hit_mask(&scene, SIZE, false, |k| k == MaterialKind::Diffuse),
        SIZE,
    );

    let truth = reference.whole(Component::SurfaceCaustics);
    let turbid = water_photons_frame(&ctx, scene.clone(), SIZE, Component::SurfaceCaustics);
    let mut clear_scene = scene.clone();
    for m in &mut clear_scene.materials {
        if m.holds_medium() {
            (m.absorption, m.scattering) = (glam::Vec3::ZERO, None);
        }
    }
    let clear = water_photons_frame(&ctx, clear_scene, SIZE, Component::SurfaceCaustics);
    let (e_truth, e_turbid, e_clear) = (
        energy(&masked(truth, &mask)),
        energy(&masked(&turbid, &mask)),
        energy(&masked(&clear, &mask)),
    );
    let rel = e_turbid / e_truth - 1.0;
    let surface_flip = masked_flip(&turbid, truth, &mask, SIZE);
    println!(
        "surface caustics, {} pixels: reference {e_truth:.4e}, water_photons {e_turbid:.4e} ({:+.2}%, FLIP {surface_flip:.3}), in clear water {e_clear:.4e} ({:.2}x)",
        mask.iter().filter(|&&m| m).count(),
        rel * 100.0,
        e_clear / e_turbid
    );
    assert!(e_clear > 1.5 * e_turbid, "the water's extinction is lost");
    assert!(
        rel.abs() < POOL_SHAFTS_SURFACE_ENERGY_BOUND,
        "surface caustics {:+.2}%",
        rel * 100.0
    );
    assert!(
        surface_flip < POOL_SHAFTS_SURFACE_FLIP_BOUND,
        "surface caustics FLIP {surface_flip:.3}"
    );

    let truth = reference.whole(Component::VolumeCaustics);
    let shafts = water_photons_frame(&ctx, scene.clone(), SIZE, Component::VolumeCaustics);
    assert_finite(&shafts);
    let everywhere = vec![true; (SIZE * SIZE) as usize];
    let half = (SIZE * SIZE * 2) as usize;
    for (part, range, bound) in [
        (
            "whole frame",
            0..shafts.len(),
            POOL_SHAFTS_VOLUME_ENERGY_BOUND,
        ),
        ("upper half", 0..half, POOL_SHAFTS_VOLUME_HALF_BOUND),
        (
            "lower half",
            half..shafts.len(),
            POOL_SHAFTS_VOLUME_HALF_BOUND,
        ),
    ] {
        let rel = energy(&shafts[range.clone()]) / energy(&truth[range]) - 1.0;
        println!("volume caustics, {part}: {:+.2}%", rel * 100.0);
        assert!(
            rel.abs() < bound,
            "volume caustics, {part}: {:+.2}%",
            rel * 100.0
        );
    }
    let volume_flip = masked_flip(&shafts, truth, &everywhere, SIZE);
    println!("volume caustics FLIP {volume_flip:.3}");
    assert!(
        volume_flip < POOL_SHAFTS_VOLUME_FLIP_BOUND,
        "volume caustics FLIP {volume_flip:.3}"
    );

    let volume = |scale: f32| {
        energy(&water_photons_frame(
            &ctx,
            scaled_scattering(&scene, scale),
            SIZE,
            Component::VolumeCaustics,
        ))
    };
    let (none, small, twice) = (volume(0.0), volume(0.01), volume(0.02));
    println!("volume caustics at 0, 0.01 and 0.02 times sigma_s: {none:.4e}, {small:.4e}, {twice:.4e} (ratio {:.4})", twice / small);
    assert_eq!(none, 0.0);
    assert!(
        small > 0.0 && (twice / small - 2.0).abs() < 0.04,
        "{}",
        twice / small
    );
    assert_validation_clean(&ctx);
}

/// The shafts of flat water, under the surface: `water_photons`' volume
/// caustics against the closed form of `single_scattering` (the tubes of a
/// flat surface are parallel prisms that tile the water), with one, two
/// and three cascades (s = 2): the outer cascades' texels are 2^c times
/// wider and their tubes carry 4^c times the flux, so the shafts are the
/// same across the seams; and with two cascades drawn as tubes of 2 x 2
/// texel blocks (`shaft_stride` 2, which tile flat water too); over the
/// whole image and each quarter of its rows.
#[test]
fn flat_water_shafts_match_the_closed_form_across_cascades() {
    use caustics::params::{ParamSet, Params};
    let ctx = validated_context();
    let scene = flat_water([0.0, 2.5, 0.0], [0.0, 0.5, 3.0]);
    let want = expected(&scene);
    let mut worst: f64 = 0.0;
    for (cascades, stride) in [(1, 1), (2, 1), (3, 1), (2, 2)] {
        let overrides = [
            format!("cascades={cascades}"),
            format!("shaft_stride={stride}"),
        ];
        let params = Params::resolve(
            "water_photons",
            caustics::techniques::water_photons::WaterPhotonsParams::specs(),
            &overrides,
        )
        .unwrap();
        let mut r = Renderer::new(
            &ctx,
            scene.clone(),
            "water_photons",
            &params,
            SIZE,
            SIZE,
            0.0,
        )
        .unwrap();
        r.scene_gpu.components = Component::VolumeCaustics.mask();
        r.render_frame(0.0).unwrap();
        let got = r.radiance().unwrap();
        let label = format!("N = {cascades}, shaft_stride {stride}");
        worst = worst.max(worst_band_error(
            &label,
            &got,
            &want,
            SHAFTS_WHOLE_BOUND,
            SHAFTS_BAND_BOUND,
        ));
    }
    assert!(worst < 1.0, "a difference is {worst:.2} times its bound");
    assert_validation_clean(&ctx);
}
