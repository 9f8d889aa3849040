//! `pinhole` (Wand & Straßer 2003): the reflector sample points, the
//! irradiance and flux a flat mirror reflects, the ring against the ground
//! truth, and the components adding up to the frame. Measurements (lavapipe,
//! Mesa 22.3.6; the inputs are deterministic: fixed seeds, one workgroup for
//! the selection):
//! - flat_mirror_reflects_r_times_the_sun (32², 4000 samples, 256² cube
//!   faces, one cluster, sun radius 3°, epsilon 0, filtering on): mean
//!   mirrored irradiance over the patch's centre 8.951 W/m² vs R E = 9
//!   (-0.55%), bound 2%; flux on the wall 6.369 W vs R E A cos 45° = 6.364 W
//!   (+0.08%), bound 5%.
//! - flat_dielectric_reflects_fresnel_times_the_sun (the same plate as
//!   glass, n = 1.5): 0.50118 W/m² vs F(45°) E = 0.50240 (-0.24%), bound 2%.
//! - ring_caustics_match_reference (64², default parameters: 1000 samples,
//!   neighbourhood removal, 8 clusters, filtering and visibility on;
//!   reference 4M photons with max_depth 2, i.e. the single specular bounce
//!   the paper renders: the L S+ D of the full reference also holds light
//!   that bounces between the ring's walls, 451 vs 311, mostly inside the
//!   ring): energy -11.3%, FLIP mean 0.110 (the reference's two halves:
//!   0.030); one cluster (the paper's single map, the light 4 m away):
//!   see BENCHMARKS.md. The test traces 2M since 2026-12-03 (issue 26):
//!   -11.4%, 0.110 (halves 0.039).
//! - flat_mirror_reflects_sky_sphere_and_rect_lights (the flat mirror, 32²,
//!   4000 samples, 256² faces, one cluster, epsilon 0; each emitter alone):
//!   mirrored irradiance over the patch's centre against the analytic value,
//!   constant sky -0.08%, sphere light 1 km away -0.36%, rect light 1 km
//!   away -0.49%; bound 2%.
//! - ring_sky_caustics_match_reference (64², default parameters, the
//!   environment's table and sun through the cube maps' environment slot;
//!   reference 4M photons, max_depth 2): energy -10.7%, FLIP mean 0.146
//!   (the reference's two halves: 0.133, its noise dominates); bounds
//!   0.15 and 0.18.
//! - cup_caustics_match_reference (64², 4000 samples, 16 clusters; the
//!   reference 4M photons, max_depth 2, without camera-side photon mapping:
//!   what the mixed cup's mirror part shows the camera is not pinhole's):
//!   energy -7.2%, FLIP mean 0.094 (reference halves 0.031); bounds 0.11
//!   and 0.12. With the defaults (1000 samples, 8 clusters): -24.3%, 0.171.
//!   The test traces 2M since 2026-12-03 (issue 26): -7.5%, 0.095 (halves
//!   0.043). ring_sky keeps 4M: its reference's noise is most of its FLIP.

use crate::common;

use caustics::frame::{FrameTargets, SceneGpu};
use caustics::params::ParamSet;
use caustics::scene::Scene;
use caustics::scene::{Material, MaterialKind};
use caustics::techniques::pinhole::{GpuSample, Pinhole, PinholeParams};
use caustics::techniques::Technique;
use caustics::vk::Context;
use common::*;
use glam::{Mat4, Vec3};
use std::sync::Arc;

/// One `pinhole` frame of `scene` at `size`², straight through the technique.
struct Frame {
    tech: Pinhole,
    _scene_gpu: SceneGpu,
    targets: FrameTargets,
}

fn render(
    ctx: &Arc<Context>,
    scene: &Scene,
    overrides: &[&str],
    size: u32,
    components: Option<u32>,
) -> Frame {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let params = PinholeParams::parse("pinhole", &overrides).unwrap();
    let mut scene_gpu = SceneGpu::new(ctx, scene, 0.0).unwrap();
    if let Some(c) = components {
        scene_gpu.components = c;
    }
    let targets = FrameTargets::new(ctx, size, size).unwrap();
    let mut tech = Pinhole::new(ctx, &params, scene, &scene_gpu, size, size).unwrap();
    scene_gpu.update_frame(scene, size, size, 0.0, 0).unwrap();
    let profiler = caustics::vk::Profiler::new(ctx, 64).unwrap();
    profiler
        .frame(|rec| tech.record(rec, &scene_gpu, &targets))
        .unwrap();
    Frame {
        tech,
        _scene_gpu: scene_gpu,
        targets,
    }
}

fn state(f: &Frame) -> (f32, u32, Vec<[f32; 4]>) {
    let s: Vec<f32> = f.tech.state.download_pod().unwrap();
    let centres = (0..16)
        .map(|k| [s[4 + 4 * k], s[5 + 4 * k], s[6 + 4 * k], s[7 + 4 * k]])
        .collect();
    (s[0], s[1].to_bits(), centres)
}

fn mirror(name: &str, reflectance: f32) -> Material {
    Material {
        name: name.into(),
        kind: MaterialKind::Mirror,
        color: Vec3::splat(reflectance),
        ior: 1.0,
        absorption: Vec3::ZERO,
        texture: None,
        emission: Vec3::ZERO,
        specular: Vec3::ZERO,
        scattering: None,
    }
}

const R: f32 = 0.9;
const SUN_E: f32 = 10.0;
const ALBEDO: f32 = 0.5;

/// A 1 m x 1 m mirror of reflectance R at the origin, tilted 45° about z
/// (normal (1, 1, 0)/sqrt 2), lit straight down by a directional light of
/// irradiance E: it reflects the sun along +x onto a wall at x = 2 facing
/// it; a camera at x = 1 looks at the wall squarely (fov 90°: each pixel
/// covers (2 / size)^2 m^2 of the wall).
fn flat_mirror_scene() -> Scene {
    let mut m = object("mirror", floor_mesh(0.5, 0.0, 0));
    m.transform = Mat4::from_rotation_z(-std::f32::consts::FRAC_PI_4);
    let mut wall = object("wall", floor_mesh(2.0, 0.0, 1));
    wall.transform = Mat4::from_translation(Vec3::new(2.0, 0.0, 0.0))
        * Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2);
    scene(
        camera(Vec3::new(1.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), 90.0),
        vec![directional_light(Vec3::NEG_Y, SUN_E)],
        vec![mirror("mirror", R), diffuse("wall", ALBEDO)],
        vec![m, wall],
    )
}

/// The mirrored irradiance at the centre of the reflected patch and the
/// flux over the wall (pixels' radiance x pi / albedo x pixel area) of the
/// flat reflector scene with `reflector` as material 0.
fn flat_reflector(ctx: &Arc<Context>, reflector: Material) -> (f64, f64, u32) {
    let size = 32u32;
    let mut scene = flat_mirror_scene();
    scene.materials[0] = reflector;
    let f = render(
        ctx,
        &scene,
        &[
            "samples=4000",
            "epsilon=0",
            "sun_radius=3",
            "cube_size=256",
            "clusters=1",
        ],
        size,
        Some(1 << caustics::shader_bindings::COMPONENT_SURFACE_CAUSTICS),
    );
    let img = f.targets.radiance.download_rgba32f().unwrap();
    assert_finite(&img);
    let (area, count, _) = state(&f);
    assert!((area - 1.0).abs() < 1e-4, "reflector area {area}");
    // The camera at distance 1 with a 90° field: every pixel covers
    // (2 / size)^2 m^2 of the wall; pixel (x, y) sees the wall at
    // (y, z) = (1 - (y + 1/2) 2 / size, (x + 1/2) 2 / size - 1).
    let px_area = (2.0 / size as f64).powi(2);
    let (mut flux, mut centre, mut n) = (0.0f64, 0.0f64, 0);
    for y in 0..size as usize {
        for x in 0..size as usize {
            let e = img[4 * (y * size as usize + x)] as f64 * std::f64::consts::PI / ALBEDO as f64;
            flux += e * px_area;
            let wy = 1.0 - (y as f64 + 0.5) * 2.0 / size as f64;
            let wz = (x as f64 + 0.5) * 2.0 / size as f64 - 1.0;
            // The patch is |y| < 0.354, |z| < 0.5, its penumbra 2 tan 3° = 0.1 m wide.
            if wy.abs() < 0.15 && wz.abs() < 0.25 {
                centre += e;
                n += 1;
            }
        }
    }
    (centre / n as f64, flux, count)
}

/// The flat mirror (ε = 0 so the equation is the plain area integral):
/// inside the mirrored patch the wall faces the reflected sun, whose disc
/// (L = E / (π sin² α)) it sees whole in the mirror, so E = R E_sun exactly;
/// over the wall the reflected flux is R times the flux the mirror
/// intercepts, E A cos 45°.
#[test]
fn flat_mirror_reflects_r_times_the_sun() {
    let ctx = validated_context();
    let (centre, flux, count) = flat_reflector(&ctx, mirror("mirror", R));
    assert!(count > 3500 && count <= 4000, "{count} sample points");
    let expected_e = (R * SUN_E) as f64;
    let expected_flux = expected_e * std::f64::consts::FRAC_1_SQRT_2;
    let rel_e = centre / expected_e - 1.0;
    let rel_flux = flux / expected_flux - 1.0;
    println!("mirrored irradiance {centre:.4} W/m² vs {expected_e} ({rel_e:+.4}); flux {flux:.4} W vs {expected_flux:.4} ({rel_flux:+.4})");
    assert!(rel_e.abs() < 0.02, "mirrored irradiance off by {rel_e:+.4}");
    assert!(
        rel_flux.abs() < 0.05,
        "reflected flux off by {rel_flux:+.4}"
    );
    assert_validation_clean(&ctx);
}

/// The same plate as glass (n = 1.5, one interface facing the light): the
/// reflected irradiance is the Fresnel reflectance at 45° (0.0503) times
/// E (Sect. 5's Fresnel modulation).
#[test]
fn flat_dielectric_reflects_fresnel_times_the_sun() {
    let ctx = validated_context();
    let f45 =
        caustics::radiometry::fresnel_dielectric(std::f32::consts::FRAC_1_SQRT_2, 1.0 / 1.5) as f64;
    let (centre, _, _) = flat_reflector(&ctx, dielectric("glass", 1.5));
    let expected = f45 * SUN_E as f64;
    let rel = centre / expected - 1.0;
    println!(
        "glass: reflected irradiance {centre:.5} W/m² vs F(45°) E = {expected:.5} ({rel:+.4})"
    );
    assert!(rel.abs() < 0.02, "glass reflection off by {rel:+.4}");
    assert_validation_clean(&ctx);
}

/// Irradiance at `x` (normal `n`) from a Lambertian polygon of unit
/// radiance wholly above x's horizon: Lambert's formula
/// E = 1/2 |sum_i Theta_i (n . gamma_i)| (Arvo 1995, Sect. 3).
fn polygon_irradiance(corners: &[glam::DVec3], x: glam::DVec3, n: glam::DVec3) -> f64 {
    let mut sum = 0.0;
    for i in 0..corners.len() {
        let a = (corners[i] - x).normalize();
        let b = (corners[(i + 1) % corners.len()] - x).normalize();
        let g = a.cross(b);
        sum += g.length().atan2(a.dot(b)) * g.normalize().dot(n);
    }
    0.5 * sum.abs()
}

/// The flat mirror of `flat_mirror_scene` (as a scene file) lit by each
/// extended emitter kind in turn, each through its own light cube-map
/// slot: a constant sky (L = 1, the environment's table), a sphere light
/// and a rect light 1 km up. In the mirror the wall sees each emitter's
/// image (reflected across the mirror plane: centre (-1000, 0, 0), the
/// rect's normal turned to +x), so at a wall point p well inside the
/// mirrored patch the caustic irradiance is R times
///   sky:    L x (Lambert's formula over the mirror quad),
///   sphere: pi L r² / |p - c'|² cos (a sphere seen whole),
///   rect:   L x (Lambert's formula over the image rect).
/// ε = 0, one cluster. The cube map holds each emitter as seen from the
/// cluster's centre, a distant light (Sect. 5): an emitter at distance D
/// from the mirror, whose image is D + 2 m from the wall, comes back
/// ((D + 2) / D)² too bright (+44% at D = 10 m; the clusters' reason), so
/// the lamps here are 1 km away (+0.4%).
#[test]
fn flat_mirror_reflects_sky_sphere_and_rect_lights() {
    use glam::DVec3;
    let ctx = validated_context();
    let (sphere_l, sphere_r, rect_l, rect_w) = (40.0, 30.0, 30.0, 50.0);
    let geometry = format!(
        "[camera]\neye = [1.0, 0.0, 0.0]\ntarget = [2.0, 0.0, 0.0]\nfov_y = 90\n\
         [[material]]\nname = \"mirror\"\nkind = \"mirror\"\nreflectance = {R}\n\
         [[material]]\nname = \"wall\"\nkind = \"diffuse\"\nalbedo = {ALBEDO}\n\
         [[object]]\nshape = \"plane\"\nnormal = [1.0, 1.0, 0.0]\nsize = [1.0, 1.0]\ntangent = [0.0, 0.0, 1.0]\nmaterial = \"mirror\"\n\
         [[object]]\nshape = \"plane\"\ncenter = [2.0, 0.0, 0.0]\nnormal = [-1.0, 0.0, 0.0]\nsize = [4.0, 4.0]\nmaterial = \"wall\"\n"
    );
    let r = R as f64;
    let s2 = std::f64::consts::FRAC_1_SQRT_2 * 0.5; // half the mirror's extent in x and y
    let mirror = [
        DVec3::new(s2, -s2, -0.5),
        DVec3::new(-s2, s2, -0.5),
        DVec3::new(-s2, s2, 0.5),
        DVec3::new(s2, -s2, 0.5),
    ];
    let h = 0.5 * rect_w;
    let rect = [
        DVec3::new(-1000.0, -h, -h),
        DVec3::new(-1000.0, h, -h),
        DVec3::new(-1000.0, h, h),
        DVec3::new(-1000.0, -h, h),
    ];
    let n = DVec3::NEG_X;
    type Expected<'a> = Box<dyn Fn(DVec3) -> f64 + 'a>;
    let cases: [(&str, String, Expected); 3] = [
        (
            "sky",
            "kind = \"environment\"\nsky = { sun_direction = [0.0, 1.0, 0.0], sun_radius = 1.0, sun_radiance = 0.0, zenith = 1.0, horizon = 1.0 }".into(),
            Box::new(|p| r * polygon_irradiance(&mirror, p, n)),
        ),
        (
            "sphere",
            format!("kind = \"sphere\"\ncenter = [0.0, 1000.0, 0.0]\nradius = {sphere_r}\nradiance = {sphere_l}"),
            Box::new(|p: DVec3| {
                let v = DVec3::new(-1000.0, 0.0, 0.0) - p;
                r * std::f64::consts::PI * sphere_l * sphere_r * sphere_r / v.length_squared()
                    * n.dot(v.normalize())
            }),
        ),
        (
            "rect",
            format!("kind = \"rect\"\ncenter = [0.0, 1000.0, 0.0]\nnormal = [0.0, -1.0, 0.0]\nsize = [{rect_w}, {rect_w}]\nradiance = {rect_l}"),
            Box::new(|p| r * rect_l * polygon_irradiance(&rect, p, n)),
        ),
    ];
    let size = 32u32;
    for (name, light, expected_at) in &cases {
        let text = format!("{geometry}[[light]]\n{light}\n");
        let scene = Scene::from_str(&text, std::path::Path::new("flat_mirror.toml")).unwrap();
        let f = render(
            &ctx,
            &scene,
            &["samples=4000", "epsilon=0", "cube_size=256", "clusters=1"],
            size,
            Some(1 << caustics::shader_bindings::COMPONENT_SURFACE_CAUSTICS),
        );
        let img = f.targets.radiance.download_rgba32f().unwrap();
        assert_finite(&img);
        let (mut actual, mut expected) = (0.0f64, 0.0f64);
        for y in 0..size as usize {
            for x in 0..size as usize {
                let wy = 1.0 - (y as f64 + 0.5) * 2.0 / size as f64;
                let wz = (x as f64 + 0.5) * 2.0 / size as f64 - 1.0;
                if wy.abs() >= 0.15 || wz.abs() >= 0.25 {
                    continue;
                }
                actual +=
                    img[4 * (y * size as usize + x)] as f64 * std::f64::consts::PI / ALBEDO as f64;
                expected += expected_at(DVec3::new(2.0, wy, wz));
            }
        }
        let rel = actual / expected - 1.0;
        println!("{name}: mirrored irradiance summed over the patch's centre {actual:.4} vs {expected:.4} ({rel:+.4})");
        assert!(
            rel.abs() < 0.02,
            "{name}: mirrored irradiance off by {rel:+.4}"
        );
    }
    assert_validation_clean(&ctx);
}

/// The same plate as a `mixed` material (albedo 0.3, mirror part 0.6): a
/// reflector through its mirror part, so the wall receives 0.6 E.
#[test]
fn flat_mixed_plate_reflects_its_mirror_part() {
    let ctx = validated_context();
    let plate = Material {
        color: Vec3::splat(0.3),
        specular: Vec3::splat(0.6),
        scattering: None,
        ..diffuse("plate", 0.3)
    };
    let (centre, _, _) = flat_reflector(&ctx, plate);
    let expected = 0.6 * SUN_E as f64;
    let rel = centre / expected - 1.0;
    println!("mixed plate: reflected irradiance {centre:.4} W/m² vs {expected} ({rel:+.4})");
    assert!(
        rel.abs() < 0.02,
        "mixed plate's mirror part off by {rel:+.4}"
    );
    assert_validation_clean(&ctx);
}

/// Each strategy of Sect. 3.2 on the flat mirror (A = 1 m²): at most N
/// points, all on the mirror (quantized ones within half a cell diagonal);
/// grid stratification keeps one point per cell, neighbourhood removal keeps
/// its points at least delta = 0.75 sqrt(A / N) apart; random keeps N.
/// The normal gradient of a plane is zero, of the ring's cylinder (R = 1)
/// |dn/du| = 1 / R along the principal direction and 0 along the axis.
#[test]
fn sample_points_follow_each_strategy() {
    let ctx = validated_context();
    let n = 400u32;
    let rot = Mat4::from_rotation_z(std::f32::consts::FRAC_PI_4);
    for strategy in 0..4 {
        let f = render(
            &ctx,
            &flat_mirror_scene(),
            &[&format!("samples={n}"), &format!("strategy={strategy}")],
            16,
            None,
        );
        let (area, count, _) = state(&f);
        let s: Vec<GpuSample> = f.tech.samples.download_pod().unwrap();
        let cell = (1.5 * area / n as f32).sqrt();
        let points: Vec<Vec3> = (0..count as usize)
            .map(|i| Vec3::from_slice(&s[i].position[..3]))
            .collect();
        let mut min_d = f32::MAX;
        for (i, a) in points.iter().enumerate() {
            // In the mirror's own frame: y = 0, |x|, |z| <= 0.5.
            let local = rot.transform_point3(*a);
            let slack = if strategy == 2 {
                0.5 * 3f32.sqrt() * cell
            } else {
                1e-4
            };
            assert!(
                local.y.abs() <= slack
                    && local.x.abs() <= 0.5 + slack
                    && local.z.abs() <= 0.5 + slack,
                "strategy {strategy}: point {a} off the mirror"
            );
            for b in &points[i + 1..] {
                min_d = min_d.min(a.distance(*b));
            }
            let grad = Vec3::from_slice(&s[i].dn_du[..3]).length()
                + Vec3::from_slice(&s[i].dn_dv[..3]).length();
            assert!(
                grad < 1e-3,
                "strategy {strategy}: a plane's normal gradient {grad}"
            );
        }
        let cells: std::collections::HashSet<[i32; 3]> = points
            .iter()
            .map(|p| (*p / cell).floor().as_ivec3().to_array())
            .collect();
        println!(
            "strategy {strategy}: {count} points, {} cells, closest pair {min_d:.4} m",
            cells.len()
        );
        assert!(count <= n);
        match strategy {
            0 => assert_eq!(count, n),
            1 => assert_eq!(cells.len(), count as usize, "grid: one point per cell"),
            2 => assert!(count > n / 2),
            _ => {
                let delta = 0.75 * (area / n as f32).sqrt();
                assert!(
                    min_d >= delta * 0.999,
                    "neighbourhood: closest pair {min_d} < {delta}"
                );
                assert_eq!(
                    count, n,
                    "neighbourhood removal reaches N before the mirror is full"
                );
            }
        }
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ring.toml");
    let f = render(
        &ctx,
        &Scene::load(&path).unwrap(),
        &["samples=400"],
        16,
        None,
    );
    let (_, count, _) = state(&f);
    let s: Vec<GpuSample> = f.tech.samples.download_pod().unwrap();
    let (mut k_max, mut k_min) = (Vec::new(), Vec::new());
    for p in &s[..count as usize] {
        let du = Vec3::from_slice(&p.dn_du[..3]).length();
        let dv = Vec3::from_slice(&p.dn_dv[..3]).length();
        k_max.push(du.max(dv));
        k_min.push(du.min(dv));
    }
    k_max.sort_by(f32::total_cmp);
    k_min.sort_by(f32::total_cmp);
    let (med_max, med_min) = (k_max[k_max.len() / 2], k_min[k_min.len() / 2]);
    println!("ring: median principal |dn/du| {med_max:.4}, |dn/dv| {med_min:.4}");
    assert!((med_max - 1.0).abs() < 0.05, "cylinder curvature {med_max}");
    assert!(med_min < 0.05, "cylinder axis curvature {med_min}");
    assert_validation_clean(&ctx);
}

/// The measurement of one scene against the reference's single-bounce
/// L S+ D (max_depth 2: the paper renders one specular bounce), masked to
/// the pixels whose camera ray meets a diffuse surface first, both
/// tonemapped at the scene's exposure. `seen_directly`: the reference
/// without its camera-side photon mapping, so that a `mixed` surface's
/// pixels hold only its diffuse part's light, not what its mirror part
/// shows the camera (which pinhole's frame does not render).
struct Accuracy {
    /// pinhole's relative caustic energy error.
    energy: f64,
    /// FLIP mean, pinhole against the reference.
    flip: f32,
    /// FLIP mean between the reference's two halves (its own noise).
    noise: f32,
}

fn caustics_vs_reference(
    ctx: &Arc<Context>,
    scene_file: &str,
    overrides: &[&str],
    size: u32,
    photons: u64,
    seen_directly: bool,
    name: &str,
) -> Accuracy {
    use caustics::reference::{Component, ReferenceSettings};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(scene_file);
    let scene = Scene::load(&path).unwrap();
    let exposure = scene.output.exposure;
    let ldr = |img: &[f32]| caustics::compare::metrics::tonemap(img, exposure);
    let mask = first_hit_mask(&scene, size, false, |k| k == MaterialKind::Diffuse);
    let settings = ReferenceSettings {
        max_depth: 2,
        photon_mapping: !seen_directly,
        ..ReferenceSettings::default()
    };
    let reference = reference_images(
        ctx,
        &ReferenceRequest::new(&scene, size, photons)
            .in_halves()
            .with_settings(settings),
    );
    let half_a = masked(reference.first_half(Component::SurfaceCaustics), &mask);
    let truth = masked(reference.whole(Component::SurfaceCaustics), &mask);
    let (noise, _) = flip(&ldr(&second_half(&truth, &half_a)), &ldr(&half_a), size);
    let t = energy(&truth);
    let truth_ldr = ldr(&truth);
    println!("{name}: reference single-bounce L S+ D energy {t:.2}; its halves' FLIP {noise:.4}");
    let f = render(
        ctx,
        &scene,
        overrides,
        size,
        Some(1 << caustics::shader_bindings::COMPONENT_SURFACE_CAUSTICS),
    );
    let img = masked(&f.targets.radiance.download_rgba32f().unwrap(), &mask);
    assert_finite(&img);
    let rel = (energy(&img) - t) / t;
    let img_ldr = ldr(&img);
    let (flip_mean, map) = flip(&img_ldr, &truth_ldr, size);
    println!("{name} {overrides:?}: energy {rel:+.4}, FLIP mean {flip_mean:.4}");
    write_comparison_pngs(name, size, &img_ldr, &truth_ldr, &map);
    Accuracy {
        energy: rel,
        flip: flip_mean,
        noise,
    }
}

/// `ring` (point light 4 m from a mirror ring of radius 1 m) against the
/// reference's single-bounce L S+ D. Bounds: the measurement in the header
/// plus a margin (energy |measured| + 0.04, FLIP 1.25 x measured).
#[test]
fn ring_caustics_match_reference() {
    let ctx = validated_context();
    let a = caustics_vs_reference(
        &ctx,
        "assets/scenes/ring.toml",
        &[],
        64,
        2_000_000,
        false,
        "pinhole_ring",
    );
    assert!(
        a.energy.abs() < 0.155 && a.flip < 0.14,
        "ring: relative energy {:+.4} (bound 0.155), FLIP {:.4} (bound 0.14)",
        a.energy,
        a.flip
    );
    assert_validation_clean(&ctx);
}

/// `ring_sky` (the ring under sky.hdr: a low 3° sun and the sky) against
/// the reference's single-bounce L S+ D: the environment's table and the
/// sun in it come from the light cube maps' environment slot. Bounds: the
/// measurement in the header plus a margin.
#[test]
fn ring_sky_caustics_match_reference() {
    let ctx = validated_context();
    let a = caustics_vs_reference(
        &ctx,
        "assets/scenes/ring_sky.toml",
        &[],
        64,
        4_000_000,
        false,
        "pinhole_ring_sky",
    );
    assert!(
        a.energy.abs() < 0.15 && a.flip < 0.18,
        "ring_sky: relative energy {:+.4} (bound 0.15), FLIP {:.4} (bound 0.18; reference noise {:.4})",
        a.energy,
        a.flip,
        a.noise
    );
    assert_validation_clean(&ctx);
}

/// `cup` (a mixed-material cup under a low sun: the caustic its mirror part
/// throws onto its own bottom and onto the floor) against the reference's
/// single-bounce L S+ D seen directly, with 4000 sample points in 16
/// clusters (the cup is small and near its receivers). Bounds: the
/// measurement in the header plus a margin.
#[test]
fn cup_caustics_match_reference() {
    let ctx = validated_context();
    let a = caustics_vs_reference(
        &ctx,
        "assets/scenes/cup.toml",
        &["samples=4000", "clusters=16"],
        64,
        2_000_000,
        true,
        "pinhole_cup",
    );
    assert!(
        a.energy.abs() < 0.11 && a.flip < 0.12,
        "cup: relative energy {:+.4} (bound 0.11), FLIP {:.4} (bound 0.12; reference noise {:.4})",
        a.energy,
        a.flip,
        a.noise
    );
    assert_validation_clean(&ctx);
}

/// The frame is direct + surface caustics: each component alone (the
/// component mask) adds up to the whole frame.
#[test]
fn components_add_up_to_the_frame() {
    use caustics::shader_bindings as sb;
    let ctx = validated_context();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ring.toml");
    let scene = Scene::load(&path).unwrap();
    let size = 32;
    let frame = |mask| {
        render(&ctx, &scene, &["samples=300"], size, Some(mask))
            .targets
            .radiance
            .download_rgba32f()
            .unwrap()
    };
    let all = frame((1 << sb::COMPONENT_DIRECT) | (1 << sb::COMPONENT_SURFACE_CAUSTICS));
    let direct = frame(1 << sb::COMPONENT_DIRECT);
    let caustic = frame(1 << sb::COMPONENT_SURFACE_CAUSTICS);
    assert!(energy(&caustic) > 0.0 && energy(&direct) > 0.0);
    // rgb only: alpha is coverage, 1 in each.
    let diff = (0..all.len())
        .filter(|i| i % 4 != 3)
        .map(|i| (all[i] - direct[i] - caustic[i]).abs())
        .fold(0.0f32, f32::max);
    println!("largest |all - (direct + caustics)| {diff:e}");
    assert!(
        diff < 1e-3 * all.iter().cloned().fold(0.0, f32::max),
        "components differ by {diff}"
    );
    assert_validation_clean(&ctx);
}

/// BENCHMARKS.md's accuracy tables (not part of the suite:
/// `cargo test --release --test pinhole ring_accuracy_table -- --ignored --nocapture`):
/// the ring at 64² against the reference's single-bounce L S+ D (4M
/// photons), FLIP mean and relative energy per sampling strategy at 2,000
/// points (the paper's Fig. 5, with and without filtering) and per cluster
/// count at 1,000 points (Sect. 5's clusters, the light 4 m away).
#[test]
#[ignore]
fn ring_accuracy_table() {
    use caustics::reference::{Component, ReferenceRenderer, ReferenceSettings};
    let ctx = validated_context();
    let size = 64u32;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ring.toml");
    let scene = Scene::load(&path).unwrap();
    let mask = first_hit_mask(&scene, size, false, |k| k == MaterialKind::Diffuse);
    let settings = ReferenceSettings {
        max_depth: 2,
        ..ReferenceSettings::default()
    };
    let mut reference =
        ReferenceRenderer::new(&ctx, scene.clone(), size, size, 0.0, settings).unwrap();
    reference.trace(4_000_000, |_, _| {}).unwrap();
    let truth = masked(
        &reference.resolve(Component::SurfaceCaustics).unwrap(),
        &mask,
    );
    drop(reference);
    let t = energy(&truth);
    let truth_ldr = tonemap(&truth);
    let mut configs: Vec<String> = Vec::new();
    for filter in [0, 1] {
        for strategy in 0..4 {
            configs.push(format!("samples=2000,strategy={strategy},filter={filter}"));
        }
    }
    for clusters in [1, 2, 4, 8, 16] {
        configs.push(format!("samples=1000,clusters={clusters}"));
    }
    // PINHOLE_CONFIGS="a=1,b=2;c=3" measures other parameter sets instead.
    if let Ok(list) = std::env::var("PINHOLE_CONFIGS") {
        configs = list.split(';').map(str::to_string).collect();
    }
    println!("| parameters | relative energy | FLIP mean |\n| --- | ---: | ---: |");
    for config in &configs {
        let overrides: Vec<&str> = config.split(',').collect();
        let f = render(
            &ctx,
            &scene,
            &overrides,
            size,
            Some(1 << caustics::shader_bindings::COMPONENT_SURFACE_CAUSTICS),
        );
        let img = masked(&f.targets.radiance.download_rgba32f().unwrap(), &mask);
        let rel = (energy(&img) - t) / t;
        let ldr = tonemap(&img);
        let (fl, map) = flip(&ldr, &truth_ldr, size);
        println!("| {} | {rel:+.3} | {fl:.4} |", config.replace(',', ", "));
        write_comparison_pngs(
            &format!("pinhole_ring_{}", config.replace(['=', ','], "_")),
            size,
            &ldr,
            &truth_ldr,
            &map,
        );
    }
    assert_validation_clean(&ctx);
}

/// Light maps too large for the device (layers) or for the 1 GiB budget are
/// refused with a message naming the parameters, not a failed allocation.
#[test]
fn oversized_light_maps_are_refused() {
    use caustics::techniques::TechniqueBuild;
    let ctx = validated_context();
    let mut scene = flat_mirror_scene();
    for x in [-1.0, 1.0] {
        scene.lights.push(point_light(Vec3::new(x, 3.0, 0.0), 10.0));
    }
    let scene_gpu = SceneGpu::new(&ctx, &scene, 0.0).unwrap();
    let overrides = ["clusters=16".to_string(), "cube_size=512".to_string()];
    let params = PinholeParams::parse("pinhole", &overrides).unwrap();
    let err = match Pinhole::build(&ctx, &params, &scene, &scene_gpu, 16, 16) {
        Ok(_) => panic!("16 clusters x 3 lights of 512² faces (1.6 GiB) were accepted"),
        Err(e) => e.to_string(),
    };
    println!("{err}");
    assert!(
        err.contains("clusters") && err.contains("cube_size"),
        "{err}"
    );
    drop(scene_gpu);
    assert_validation_clean(&ctx);
}
