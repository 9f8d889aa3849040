//! The `beams` technique (Liktor & Dachsbacher 2011, adaptive caustic
//! beams) against physics and the ground truth. Lavapipe, validation on,
//! small frames; each component is drawn alone through the component mask,
//! so what is measured is what `render --component ...` writes.
//!
//! Measured (lavapipe, Mesa 22.3.6; `cargo test --test beams -- --nocapture`):
//! see each test's comment; BENCHMARKS.md has the comparisons with the
//! reference.

use crate::common;

use caustics::bvh::Bvh;
use caustics::frame::{camera_matrices, FrameTargets, SceneGpu};
use caustics::params::ParamSet;
use caustics::reference::{Component, ReferenceRenderer, ReferenceSettings};
use caustics::scene::{Material, MaterialKind, Scene};
use caustics::techniques::beams::{BeamCounts, Beams, BeamsParams, GpuBeam};
use caustics::techniques::{Technique, TechniqueBuild};
use caustics::vk::Context;
use common::*;
use glam::{DVec3, Vec3};
use std::sync::Arc;

struct Frame {
    tech: Beams,
    targets: FrameTargets,
    _scene_gpu: SceneGpu,
}

impl Frame {
    fn radiance(&self) -> Vec<f32> {
        let img = self.targets.radiance.download_rgba32f().unwrap();
        assert_finite(&img);
        img
    }

    fn beams(&self, counts: &BeamCounts) -> Vec<GpuBeam> {
        let mut all: Vec<GpuBeam> = self.tech.tracer.beams.download_pod().unwrap();
        all.truncate(counts.total_beams() as usize);
        all
    }

    fn counts(&self) -> BeamCounts {
        self.tech.tracer.counts(0).unwrap()
    }
}

/// One `beams` frame of `scene` at size², drawing only the components in
/// `mask`.
fn render(ctx: &Arc<Context>, scene: &Scene, overrides: &[&str], mask: u32, size: u32) -> Frame {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let params = BeamsParams::parse("beams", &overrides).unwrap();
    let mut scene_gpu = SceneGpu::new(ctx, scene, 0.0).unwrap();
    scene_gpu.components = mask;
    let targets = FrameTargets::new(ctx, size, size).unwrap();
    let mut tech = Beams::build(ctx, &params, scene, &scene_gpu, size, size).unwrap();
    scene_gpu.update_frame(scene, size, size, 0.0, 0).unwrap();
    let profiler = caustics::vk::Profiler::new(ctx, 64).unwrap();
    profiler
        .frame(|rec| tech.record(rec, &scene_gpu, &targets))
        .unwrap();
    Frame {
        tech,
        targets,
        _scene_gpu: scene_gpu,
    }
}

fn set_medium(scene: &mut Scene, sigma_s: f32, sigma_a: f32, g: f32) {
    let m = scene.medium.as_mut().expect("scene has a medium");
    m.sigma_s = Vec3::splat(sigma_s);
    m.sigma_a = Vec3::splat(sigma_a);
    m.g = g;
}

fn lens_ior(scene: &mut Scene, ior: f32) {
    for m in &mut scene.materials {
        if m.kind == MaterialKind::Dielectric {
            m.ior = ior;
        }
    }
}

/// Flux bookkeeping on ball_lens with n = 1 (no Fresnel reflection, no
/// bending): every kept base triangle's flux goes into its refracted beam,
/// and the lens's solid angle seen from the light, 2 pi (1 - sqrt(1 -
/// (r/d)^2)), lies between that of the kept triangles and that of the kept
/// plus the dropped ones (which straddle its outline), the gap shrinking
/// with refinement. Measured (32² frame): beams / entering 1.00000 (n = 1:
/// F = 0, T = 1); kept / lens 0.8524 -> 0.9684 and (kept + dropped) / lens
/// 1.0849 -> 1.0282 from 1 to 3 levels; dropped fraction 21.4% -> 5.8%.
#[test]
fn beams_carry_the_flux_entering_their_base_triangles() {
    let ctx = validated_context();
    let mut scene = canonical_scene("ball_lens");
    lens_ior(&mut scene, 1.0);
    let intensity = 60.0f32; // W/sr, white
    let lens_solid_angle = {
        let d = 6.4f64;
        2.0 * std::f64::consts::PI * (1.0 - (1.0 - 1.0 / (d * d)).sqrt())
    };
    let mut dropped = Vec::new();
    for levels in [1u32, 3] {
        let f = render(
            &ctx,
            &scene,
            &[&format!("levels={levels}")],
            Component::SurfaceCaustics.mask(),
            32,
        );
        let c = f.counts();
        let beams = f.beams(&c);
        // The counters (luminance W) against the beams read back.
        let carried: f64 = beams.iter().map(|b| b.flux[1] as f64).sum();
        assert!((carried / c.flux_out as f64 - 1.0).abs() < 1e-4);
        let ratio = c.flux_out as f64 / c.flux_in as f64;
        let kept = c.kept_measure as f64 / lens_solid_angle;
        let tiled = (c.kept_measure + c.dropped_measure) as f64 / lens_solid_angle;
        println!(
            "levels {levels}: {} beams, carried / entering {ratio:.5}, flux_in {:.4} W vs I x kept {:.4} W, kept / lens solid angle {kept:.4}, (kept + dropped) / lens {tiled:.4}, dropped {:.4}",
            beams.len(),
            c.flux_in,
            intensity * c.kept_measure,
            c.dropped_fraction()
        );
        assert_eq!(c.beam_overflow, 0);
        assert!(
            (ratio - 1.0).abs() < 0.01,
            "beams carry {ratio} of the entering flux"
        );
        assert!(((c.flux_in / (intensity * c.kept_measure)) - 1.0).abs() < 1e-3);
        // Kept triangles lie on the lens, dropped ones straddle its outline.
        assert!(
            kept < 1.0 && tiled > 1.0,
            "kept {kept}, kept + dropped {tiled}"
        );
        dropped.push(c.dropped_fraction());
    }
    assert!(
        dropped[1] < dropped[0],
        "refinement shrinks the dropped fraction: {dropped:?}"
    );
    assert_validation_clean(&ctx);
}

/// Ball lens (n = 1.5, r = 1 m) under a directional light tilted 20
/// degrees, the floor through the paraxial focus: a ball lens's effective
/// focal length from its centre is f = n r / (2 (n - 1)) = 1.5 m, so the
/// focus is the centre + f d. The brightest surface-caustic pixel must lie
/// on it. Measured (96²): 0.018 m from the focus, 0.62 pixel (bound 3 pixels).
#[test]
fn ball_lens_focuses_at_the_paraxial_focus() {
    let ctx = validated_context();
    let size = 96u32;
    let centre = Vec3::new(0.0, 1.6, 0.0);
    let alpha = 20f32.to_radians();
    let d = Vec3::new(alpha.sin(), -alpha.cos(), 0.0);
    let focus = centre + 1.5 * d;
    let s = scene(
        // From the side away from the lens, which must not hide the focus.
        camera(focus + Vec3::new(2.5, 3.0, 0.0), focus, 30.0),
        vec![directional_light(d, 1.0)],
        vec![dielectric("glass", 1.5), diffuse("floor", 0.8)],
        vec![
            object("lens", sphere_mesh(centre, 1.0, 0, 48)),
            object("floor", floor_mesh(4.0, focus.y, 1)),
        ],
    );
    let f = render(&ctx, &s, &[], Component::SurfaceCaustics.mask(), size);
    let img = f.radiance();
    let (mut best, mut at) = (0.0f64, 0usize);
    for i in 0..(size * size) as usize {
        let v = sum_rgb(&img, i);
        if v > best {
            best = v;
            at = i;
        }
    }
    let (o, dir) = pixel_ray(&s.camera, size, size, at as u32 % size, at as u32 / size);
    let hit = o + dir * ((focus.y - o.y) / dir.y);
    // One pixel's footprint on the floor (along the slant).
    let view = focus - s.camera.eye;
    let pixel =
        2.0 * view.length() * 15f32.to_radians().tan() / size as f32 / (view.normalize().y.abs());
    let miss = (hit - focus).length();
    println!(
        "brightest surface-caustic pixel at {hit:?}, paraxial focus {focus:?}: {miss:.4} m ({:.2} pixels)",
        miss / pixel
    );
    assert!(best > 0.0);
    assert!(miss < 3.0 * pixel, "{miss} m from the paraxial focus");
    assert_validation_clean(&ctx);
}

/// With n = 1 the lens neither bends nor reflects: direct light plus the
/// beams' surface caustics must equal the direct light of the scene
/// without it (the project's convention: a dielectric shadows the direct
/// term, its caustics return the light). Compared where the camera sees
/// the floor directly (through the glass the camera refraction adds its
/// own image-space error). Measured (64²): relative energy -0.34%, FLIP
/// mean 0.0030 (bounds 1%, 0.006).
#[test]
fn index_one_restores_the_floor_without_the_lens() {
    let ctx = validated_context();
    let size = 64u32;
    let mut with = canonical_scene("ball_lens");
    lens_ior(&mut with, 1.0);
    let mut without = with.clone();
    without.objects.retain(|o| o.name != "lens");
    let mask = first_hit_mask(&with, size, false, |k| k == MaterialKind::Diffuse);
    let lit = masked(
        &render(
            &ctx,
            &with,
            &[],
            Component::Direct.mask() | Component::SurfaceCaustics.mask(),
            size,
        )
        .radiance(),
        &mask,
    );
    let truth = masked(
        &render(&ctx, &without, &[], Component::Direct.mask(), size).radiance(),
        &mask,
    );
    let rel = energy(&lit) / energy(&truth) - 1.0;
    let (lit_ldr, truth_ldr) = (tonemap(&lit), tonemap(&truth));
    let (flip_mean, flip_map) = flip(&lit_ldr, &truth_ldr, size);
    println!("n = 1: direct + surface caustics vs direct without the lens: relative energy {rel:+.5}, FLIP mean {flip_mean:.4}");
    if rel.abs() > BOUND_IOR1_ENERGY || flip_mean > BOUND_IOR1_FLIP {
        let dir = write_comparison_pngs("beams_ior1", size, &lit_ldr, &truth_ldr, &flip_map);
        panic!("relative energy {rel:+.5}, FLIP {flip_mean:.4} (images in {dir})");
    }
    assert_validation_clean(&ctx);
}
// Measured -0.0034 and 0.0030, plus a margin.
const BOUND_IOR1_ENERGY: f64 = 0.01;
const BOUND_IOR1_FLIP: f32 = 0.006;

/// sigma_s = 0: the volume component is exactly zero while beams are drawn.
#[test]
fn no_scattering_no_volume_caustic() {
    let ctx = validated_context();
    let mut scene = canonical_scene("volume_cone");
    set_medium(&mut scene, 0.0, 0.005, 0.0);
    let f = render(&ctx, &scene, &[], Component::VolumeCaustics.mask(), 32);
    let c = f.counts();
    assert!(c.total_beams() > 100 && c.fragments > 1000, "{c:?}");
    let max = f
        .radiance()
        .chunks(4)
        .flat_map(|p| p[..3].to_vec())
        .fold(0.0f32, |a, v| a.max(v.abs()));
    assert_eq!(max, 0.0, "sigma_s = 0 must give exactly no volume caustic");
    assert_validation_clean(&ctx);
}

/// Optically thin (sigma_a = 0): doubling sigma_s doubles the volume
/// caustic, less the extra extinction along the paths. Measured (32²): ratio 1.9563
/// (exp(-0.002 x ~12 m) = 0.977 of 2; bound 5%).
#[test]
fn optically_thin_volume_caustic_is_linear_in_sigma_s() {
    let ctx = validated_context();
    let mut scene = canonical_scene("volume_cone");
    set_medium(&mut scene, 0.002, 0.0, 0.0);
    let one = energy(&render(&ctx, &scene, &[], Component::VolumeCaustics.mask(), 32).radiance());
    set_medium(&mut scene, 0.004, 0.0, 0.0);
    let two = energy(&render(&ctx, &scene, &[], Component::VolumeCaustics.mask(), 32).radiance());
    let ratio = two / one;
    println!("sigma_s 0.002 -> 0.004: volume caustic {one:.6} -> {two:.6}, ratio {ratio:.4}");
    assert!(one > 0.0);
    assert!((ratio / 2.0 - 1.0).abs() < 0.05, "ratio {ratio}");
    assert_validation_clean(&ctx);
}

/// Sum over the size² image of the radiance the beams scatter toward the
/// camera, by the physics the fragments stand for and independently of
/// the bounding volumes, the ray-beam intervals and the quadrature: the
/// beam's flux is uniform over each cross-section, so the slab of the beam
/// between heights y and y + dy around barycentric lam sends the intensity
///   sigma_s p(d . -w) Phi tau(base, x) tau(x, eye) |e(lam)| dy dlam / area(simplex)
/// toward the eye (E_perp dV = Phi |e| dy over the cross-section's
/// fraction), which spreads it over pixels of solid angle Omega_px:
///   sum_px L_px = sum_beams int int ... V(x) / (t^2 Omega_px(x)),
/// V = inside the frustum and not behind a surface (CPU BVH). Midpoint
/// rule: `ny` heights, `m`^2 sub-triangles of the base. Homogeneous medium.
fn beams_energy(
    scene: &Scene,
    beams: &[GpuBeam],
    g: f64,
    size: u32,
    ny: u32,
    m: u32,
) -> (f64, Vec<f64>) {
    let mut bins = vec![0.0f64; (size * size) as usize];
    let medium = scene.medium.as_ref().unwrap();
    let caustics::scene::Density::Constant(density) = medium.density else {
        panic!("homogeneous media only");
    };
    let (lo, hi) = (medium.bounds_min.as_dvec3(), medium.bounds_max.as_dvec3());
    let sigma_s = (medium.sigma_s.x * density) as f64;
    let sigma_t = ((medium.sigma_s.x + medium.sigma_a.x) * density) as f64;
    let tris = scene.triangles(0.0);
    let bvh = Bvh::build(&tris);
    let gpu = bvh.gpu_triangles(&tris);
    let cam = &scene.camera;
    let (view, proj) = caustics::frame::camera_matrices(cam, 1.0);
    let view_proj = proj * view;
    let forward = (cam.target - cam.eye).normalize().as_dvec3();
    let eye = cam.eye.as_dvec3();
    let a_px = 2.0 * (cam.fov_y_deg.to_radians() as f64 * 0.5).tan() / size as f64;
    let inside = |x: DVec3| x.cmpge(lo).all() && x.cmple(hi).all();
    // Centroids of the m^2 sub-triangles of the barycentric simplex.
    let mut lams = Vec::new();
    for i in 0..m {
        for j in 0..m - i {
            let (a, b) = (i as f64, j as f64);
            lams.push(DVec3::new(a + 1.0 / 3.0, b + 1.0 / 3.0, 0.0) / m as f64);
            if i + j + 1 < m {
                lams.push(DVec3::new(a + 2.0 / 3.0, b + 2.0 / 3.0, 0.0) / m as f64);
            }
        }
    }
    let mut sum = 0.0;
    for bm in beams {
        let v =
            bm.v.map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        let e =
            bm.e.map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        let y_max = bm.v[0][3] as f64;
        let dy = y_max / ny as f64;
        let phi = bm.flux[0] as f64;
        for k in 0..ny {
            let y = (k as f64 + 0.5) * dy;
            for l in &lams {
                let lam = DVec3::new(l.x, l.y, 1.0 - l.x - l.y);
                let x = lam.x * (v[0] + y * e[0])
                    + lam.y * (v[1] + y * e[1])
                    + lam.z * (v[2] + y * e[2]);
                if !inside(x) {
                    continue;
                }
                let clip = view_proj * x.as_vec3().extend(1.0);
                if clip.w <= 0.0 {
                    continue;
                }
                let ndc = clip.truncate() / clip.w;
                if ndc.x.abs() > 1.0 || ndc.y.abs() > 1.0 {
                    continue;
                }
                let to_x = x - eye;
                let t = to_x.length();
                let w = to_x / t;
                if bvh.occluded(&gpu, cam.eye, w.as_vec3(), 0.0, (t * (1.0 - 1e-5)) as f32) {
                    continue;
                }
                let el = lam.x * e[0] + lam.y * e[1] + lam.z * e[2];
                let len = el.length();
                let d = el / len;
                let s1 = y * len;
                let tau = (-sigma_t
                    * (length_in_box(x - s1 * d, x, lo, hi) + length_in_box(eye, x, lo, hi)))
                .exp();
                let cos_axis = w.dot(forward);
                let omega_px = a_px * a_px * cos_axis.powi(3);
                let c = sigma_s * hg_phase(d.dot(-w), g) * phi * tau * len * dy
                    / lams.len() as f64
                    / (t * t * omega_px);
                sum += c;
                let px = (((ndc.x + 1.0) * 0.5 * size as f32) as u32).min(size - 1);
                let py = (((ndc.y + 1.0) * 0.5 * size as f32) as u32).min(size - 1);
                bins[(py * size + px) as usize] += c;
            }
        }
    }
    (sum, bins)
}

/// Red summed over the image.
fn red_energy(img: &[f32]) -> f64 {
    img.chunks(4).map(|p| p[0] as f64).sum()
}

/// The fragments' in-scattering (exact ray-beam intervals, Gauss-Legendre)
/// against the same beams integrated over their volume on the CPU, and the
/// phase function: a point light over a flat mirror in volume_cone's
/// medium, the reflected beams diverging up through it, seen from the
/// side; g = +-0.7. Measured (64², 4² grid, 2 levels, 200 beams): ratio
/// 1.0028 (g = 0.7) and 1.0010 (g = -0.7), bound 1%; B(0.7) / B(-0.7) =
/// 0.1920 vs 0.1917 predicted (+0.17%, bound 1%). (Through a focus the pixel
/// centres under-sample the caustic's peak: on volume_cone seen from below
/// the same comparison reads 0.965, 0.981 and 0.990 at 64², 128² and 256².)
#[test]
fn beams_match_their_in_scattering_integral_and_the_phase_function() {
    let ctx = validated_context();
    let size = 64u32;
    let mut scene = canonical_scene("volume_cone");
    scene.materials = vec![Material {
        name: "mirror".into(),
        kind: MaterialKind::Mirror,
        color: Vec3::splat(0.9),
        ior: 1.0,
        absorption: Vec3::ZERO,
        texture: None,
        emission: Vec3::ZERO,
        specular: Vec3::ZERO,
        scattering: None,
    }];
    scene.objects = vec![object("mirror", floor_mesh(0.6, 1.5, 0))];
    scene.lights = vec![point_light(Vec3::new(0.0, 5.0, 0.8), 50.0)];
    scene.camera = camera(Vec3::new(3.5, 2.0, 3.5), Vec3::new(0.0, 4.0, 0.0), 50.0);
    let mut measured = Vec::new();
    let mut predicted = Vec::new();
    for g in [0.7f32, -0.7] {
        scene.medium.as_mut().unwrap().g = g;
        let f = render(
            &ctx,
            &scene,
            &["grid_size=4", "levels=2"],
            Component::VolumeCaustics.mask(),
            size,
        );
        let c = f.counts();
        let gpu = red_energy(&f.radiance());
        let (cpu, _) = beams_energy(&scene, &f.beams(&c), g as f64, size, 64, 6);
        println!(
            "g = {g}: {} beams, fragments {gpu:.5}, volume integral {cpu:.5}, ratio {:.4}",
            c.total_beams(),
            gpu / cpu
        );
        assert!(
            (gpu / cpu - 1.0).abs() < 0.01,
            "g = {g}: fragments {gpu} vs volume integral {cpu}"
        );
        measured.push(gpu);
        predicted.push(cpu);
    }
    let (m, p) = (measured[0] / measured[1], predicted[0] / predicted[1]);
    println!(
        "B(g = 0.7) / B(g = -0.7): fragments {m:.4}, predicted {p:.4}, relative {:+.4}",
        m / p - 1.0
    );
    assert!(m < 0.5, "back scattering toward this camera must dominate");
    assert!((m / p - 1.0).abs() < 0.01, "phase ratio {m} vs {p}");
    assert_validation_clean(&ctx);
}

/// Tight volumes (Sect. 4.3) against Ernst's prisms on volume_cone: the
/// same image (both contain every beam; each covered pixel integrates the
/// beam's exact interval) from fewer fragments. Measured (48², volume and surface caustics):
/// energy equal to +4.4e-8 relative, 346185 vs 408784 fragments (0.847 x).
#[test]
fn tight_volumes_lose_nothing_and_shade_fewer_fragments() {
    let ctx = validated_context();
    let scene = canonical_scene("volume_cone");
    let size = 48u32;
    let mut results = Vec::new();
    for volume in [0u32, 1] {
        let f = render(
            &ctx,
            &scene,
            &[&format!("volume={volume}")],
            Component::VolumeCaustics.mask() | Component::SurfaceCaustics.mask(),
            size,
        );
        results.push((energy(&f.radiance()), f.counts().fragments));
    }
    let ((prism, prism_frags), (tight, tight_frags)) = (results[0], results[1]);
    println!(
        "prism: energy {prism:.5}, {prism_frags} fragments; tight: energy {tight:.5} ({:+.2e}), {tight_frags} fragments ({:.3} x)",
        tight / prism - 1.0,
        tight_frags as f64 / prism_frags as f64
    );
    assert!((tight / prism - 1.0).abs() < 1e-4);
    assert!(tight_frags < prism_frags);
    assert_validation_clean(&ctx);
}

/// Bounds of one comparison with the reference.
#[derive(Clone, Copy)]
struct Bound {
    /// |relative total energy| against the reference's component.
    energy: f64,
    /// FLIP mean of the tonemapped images.
    flip: f32,
}

/// The reference's `component` of `scene` at size², pixels whose camera
/// ray meets a specular surface first zeroed (the reference also sees
/// caustics through the glass, by its camera chains), traced in two halves
/// to measure its own noise.
struct Truth {
    size: u32,
    photons: u64,
    mask: Vec<bool>,
    img: Vec<f32>,
    /// Relative energy difference and FLIP between the two halves.
    halves: f64,
    noise_flip: f32,
}

fn reference_truth(
    ctx: &Arc<Context>,
    scene: &Scene,
    component: Component,
    size: u32,
    photons: u64,
) -> Truth {
    reference_truth_with(
        ctx,
        scene,
        component,
        size,
        photons,
        ReferenceSettings::default(),
    )
}

/// `reference_truth` with the reference's settings given (a shorter
/// `max_depth` keeps the paths a technique draws).
fn reference_truth_with(
    ctx: &Arc<Context>,
    scene: &Scene,
    component: Component,
    size: u32,
    photons: u64,
    settings: ReferenceSettings,
) -> Truth {
    let mask = first_hit_mask(scene, size, true, |k| k == MaterialKind::Diffuse);
    let reference = reference_images(
        ctx,
        &ReferenceRequest::new(scene, size, photons)
            .in_halves()
            .with_settings(settings),
    );
    let half_a = masked(reference.first_half(component), &mask);
    let img = masked(reference.whole(component), &mask);
    let half_b = second_half(&img, &half_a);
    let (noise_flip, _) = flip(&tonemap(&half_b), &tonemap(&half_a), size);
    let halves = (energy(&half_b) - energy(&half_a)) / energy(&img);
    Truth {
        size,
        photons,
        mask,
        img,
        halves,
        noise_flip,
    }
}

/// `component` of `beams` on `scene` against the reference's (`truth`),
/// the same pixels zeroed; returns (relative energy, FLIP mean).
fn compare(
    ctx: &Arc<Context>,
    label: &str,
    scene: &Scene,
    component: Component,
    truth: &Truth,
    overrides: &[&str],
    bound: Bound,
) -> (f64, f64) {
    let size = truth.size;
    let t = energy(&truth.img);
    let beams = masked(
        &render(ctx, scene, overrides, component.mask(), size).radiance(),
        &truth.mask,
    );
    let rel = (energy(&beams) - t) / t;
    let (beams_ldr, truth_ldr) = (tonemap(&beams), tonemap(&truth.img));
    let (flip_mean, flip_map) = flip(&beams_ldr, &truth_ldr, size);
    println!(
        "{label}: reference energy {t:.4} ({} photons; halves differ by {:+.4}, FLIP {:.4}); beams {:.4}, relative {rel:+.4} (bound {}); FLIP mean {flip_mean:.4} (bound {})",
        truth.photons,
        truth.halves,
        truth.noise_flip,
        energy(&beams),
        bound.energy,
        bound.flip
    );
    if rel.abs() >= bound.energy || flip_mean >= bound.flip {
        let dir = write_comparison_pngs(
            &format!("beams_{label}"),
            size,
            &beams_ldr,
            &truth_ldr,
            &flip_map,
        );
        panic!("{label}: relative energy {rel:+.4}, FLIP mean {flip_mean:.4} (images in {dir})");
    }
    (rel, flip_mean as f64)
}

/// `compare` against a reference traced for this one comparison.
#[allow(clippy::too_many_arguments)]
fn matches_reference(
    ctx: &Arc<Context>,
    label: &str,
    scene: &Scene,
    component: Component,
    size: u32,
    photons: u64,
    overrides: &[&str],
    bound: Bound,
) -> (f64, f64) {
    let truth = reference_truth(ctx, scene, component, size, photons);
    compare(ctx, label, scene, component, &truth, overrides, bound)
}

// Bounds: measured plus a margin (energy |measured| + 0.03 to 0.05, FLIP
// mean 1.25 x measured); the reference's seeds are fixed.
//
// ball_lens, L S+ D, 1 M photons per size, the flux-conserving gather
// (caustic triangles clipped per pixel), with the two-sided refraction
// traced through the BVH (the default, `refraction=1`) and by Wyman's
// image-space exit (`refraction=0`):
//
// | size | reference halves (energy, FLIP) | image-space exit | traced |
// | 48² | -0.3%, 0.015 | -2.0%, FLIP 0.059 | -2.3%, FLIP 0.023 |
// | 64² | +0.03%, 0.018 | -2.3%, FLIP 0.057 | -2.8%, FLIP 0.024 |
// | 96² | +2.5%, 0.023 | -5.2%, FLIP 0.057 | -5.7%, FLIP 0.027 |
// | 128² (not in the test) | +0.07%, 0.028 | -2.4%, FLIP 0.056 | -3.0%, FLIP 0.028 |
//
// Spread over 48²-96²: 3.2 points (image-space exit), 3.4 (traced); the
// point-sampled gather this replaced swung from -43% to +42% between 64²
// and 128² (BENCHMARKS.md). The 96² outlier is within the reference's own
// noise there (its halves differ by 2.5%: few photons in the focus's
// brightest pixels). The deficit left is the light the grid drops at the
// lens's outline (5.8% of its solid angle at 3 levels) and, traced, the
// Fresnel reflections inside the glass, which are not followed. The
// image-space exit's FLIP is twice the traced one's: its false total
// internal reflection at the rim (`tir_remedy` 1) lights a faint ring.
// Bounds: energy measured + 0.03 (spread: 0.06), FLIP x 1.25.
#[test]
fn ball_lens_surface_energy_does_not_depend_on_image_size() {
    let ctx = validated_context();
    let scene = canonical_scene("ball_lens");
    let sizes = [48u32, 64, 96];
    // Per size: (energy, FLIP) bounds of the image-space exit and the traced mode.
    let bounds = [
        [(0.05, 0.074), (0.055, 0.03)],
        [(0.055, 0.071), (0.06, 0.03)],
        [(0.085, 0.071), (0.09, 0.034)],
    ];
    let mut energies = [Vec::new(), Vec::new()];
    for (&size, bound) in sizes.iter().zip(bounds) {
        let truth = reference_truth(&ctx, &scene, Component::SurfaceCaustics, size, 1_000_000);
        for (mode, overrides) in [&["refraction=0"][..], &[][..]].iter().enumerate() {
            let (energy, flip) = bound[mode];
            let (rel, _) = compare(
                &ctx,
                &format!("ball_lens_surface_{size}{}", ["_image_space", ""][mode]),
                &scene,
                Component::SurfaceCaustics,
                &truth,
                overrides,
                Bound { energy, flip },
            );
            energies[mode].push(rel);
        }
    }
    for (mode, e) in energies.iter().enumerate() {
        let spread =
            e.iter().cloned().fold(f64::MIN, f64::max) - e.iter().cloned().fold(f64::MAX, f64::min);
        println!(
            "{}: relative energies {e:+.4?} at {sizes:?}, spread {spread:.4}",
            ["image-space exit", "traced"][mode]
        );
        assert!(
            spread < 0.06,
            "the energy moves by {spread} with the image size"
        );
    }
    assert_validation_clean(&ctx);
}

/// The surface gather deposits each beam's flux on its receiver, whatever
/// the image size and on either side of the focus. The surface target
/// (flux per pixel, W) must hold at least the flux of the beams whose
/// caustic triangle lies wholly in view and at most that of all beams with
/// a caustic triangle (some lie partly outside the frame). On ball_lens
/// (no medium, the floor before the lens's focus) the same at every size,
/// down to a frame where a pixel spans about 0.3 m of floor. Measured
/// (traced refraction): 7346 beams, 6910 with a caustic triangle (landing
/// 3.9781 W, 3.9194 W of it wholly in view), deposited 3.9415 W at 24²,
/// 37² and 64² alike. On volume_cone without its medium the beams cross
/// their focus before the floor (inverted caustic triangles): traced,
/// landing 7.0885 W, 6.8885 W in view, deposited 6.9798 W; with Wyman's
/// image-space exit (`refraction=0`) landing 7.1747 W but only 6.3013 W
/// in view, deposited 6.4808 W: its false total internal reflection at
/// the rim throws light out of the frame, which the gather cannot keep
/// (BENCHMARKS.md, beams against the reference).
#[test]
fn surface_gather_deposits_each_beams_flux() {
    let ctx = validated_context();
    let deposited = |scene: &Scene, overrides: &[&str], size: u32| -> f64 {
        let (view, proj) = camera_matrices(&scene.camera, 1.0);
        let in_view = |c: &[Vec3; 3]| {
            c.iter().all(|&p| {
                let h = proj * view * p.extend(1.0);
                h.w > 0.0 && h.x.abs() < h.w && h.y.abs() < h.w
            })
        };
        let f = render(
            &ctx,
            scene,
            overrides,
            Component::SurfaceCaustics.mask(),
            size,
        );
        let c = f.counts();
        let beams = f.beams(&c);
        let (mut landing, mut in_frame, mut with_triangle) = (0.0f64, 0.0f64, 0);
        for b in &beams {
            if let Some(t) = b.caustic_triangle() {
                with_triangle += 1;
                landing += b.flux[1] as f64;
                if in_view(&t) {
                    in_frame += b.flux[1] as f64;
                }
            }
        }
        let target = f.tech.tracer.surface.download_rgba32f().unwrap();
        assert_finite(&target);
        let deposited: f64 = target.chunks(4).map(|p| p[1] as f64).sum();
        println!(
            "{size}² {overrides:?}: {} beams ({with_triangle} with a caustic triangle), landing {landing:.4} W ({in_frame:.4} W wholly in view), deposited {deposited:.4} W, {} caustic fragments",
            beams.len(),
            c.caustic_fragments
        );
        assert!(with_triangle > beams.len() / 2);
        assert!(
            deposited > in_frame * (1.0 - 1e-4) && deposited < landing * (1.0 + 1e-4),
            "deposited {deposited} W outside [{in_frame}, {landing}]"
        );
        deposited
    };
    let ball_lens = canonical_scene("ball_lens");
    let deposits: Vec<f64> = [24u32, 37, 64]
        .iter()
        .map(|&size| deposited(&ball_lens, &[], size))
        .collect();
    for d in &deposits {
        assert!(
            (d / deposits[0] - 1.0).abs() < 1e-4,
            "deposits {deposits:?}"
        );
    }
    let mut past_focus = canonical_scene("volume_cone");
    past_focus.medium = None;
    for overrides in [&[][..], &["refraction=0"][..]] {
        deposited(&past_focus, overrides, 64);
    }
    assert_validation_clean(&ctx);
}

// volume_cone, L S+ V, 64², 1 M photons (halves -0.06%, FLIP 0.009).
// Traced two-sided refraction (the default): -17.2% energy, FLIP 0.014.
// Of the reference's L S+ V, 7.7% is light that reflected inside the glass
// (paths with three or more specular events: 11.48 against 10.60 with
// `max_depth` 3, which keeps the reflection off the lens and the
// refraction in and out); beams compute both refractions at once and
// follow no reflection inside the object (Sect. 6: "caustics inside the
// object cannot be rendered"), so against those paths alone the deficit
// is -10.4%, FLIP 0.010: the lens's outline dropped by the grid (Sect.
// 4.1; 5 levels: -7.9%) and the pixel-centre sampling of the focus (the
// fragments against their own CPU volume integral through it: 0.965 at
// 64², 0.981 at 128², 0.990 at 256²; 128²: -13.6% against all paths).
// Wyman's image-space exit (`refraction=0`): -8.4%, FLIP 0.021: its false
// total internal reflections near the rim send light out sideways, which
// the camera sees in the haze, and that happens to offset the deficit
// (on the floor the same light lands out of view: -14.0%, against -3.1%
// traced; `medium_scenes_match_reference`). Bounds: energy |measured| +
// 0.03, FLIP 1.25 x measured.
#[test]
fn volume_cone_volume_caustics_match_reference() {
    let ctx = validated_context();
    let scene = canonical_scene("volume_cone");
    let truth = reference_truth(&ctx, &scene, Component::VolumeCaustics, 64, 1_000_000);
    let cases = [
        ("volume_cone_volume", &[][..], 0.205, 0.018),
        (
            "volume_cone_volume_image_space",
            &["refraction=0"][..],
            0.115,
            0.027,
        ),
    ];
    for (label, overrides, energy, flip) in cases {
        compare(
            &ctx,
            label,
            &scene,
            Component::VolumeCaustics,
            &truth,
            overrides,
            Bound { energy, flip },
        );
    }
    let two_events = ReferenceSettings {
        max_depth: 3,
        ..ReferenceSettings::default()
    };
    let truth = reference_truth_with(
        &ctx,
        &scene,
        Component::VolumeCaustics,
        64,
        1_000_000,
        two_events,
    );
    compare(
        &ctx,
        "volume_cone_volume_two_specular_events",
        &scene,
        Component::VolumeCaustics,
        &truth,
        &[],
        Bound {
            energy: 0.135,
            flip: 0.013,
        },
    );
    assert_validation_clean(&ctx);
}

/// One frame of `technique` (`beams` or `volume_lines`) drawing `component`,
/// timed per pass (host clock per submission on lavapipe), on a context
/// without validation: its image, the time of the passes whose names start
/// with one of `caustic_passes`, and the beam counts.
fn timed(
    ctx: &Arc<Context>,
    scene: &Scene,
    technique: &str,
    overrides: &[&str],
    component: Component,
    size: u32,
    caustic_passes: &[&str],
) -> (Vec<f32>, f64, Option<BeamCounts>) {
    let info = caustics::techniques::find(technique).unwrap();
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let params = caustics::params::Params::resolve(technique, info.params(), &o).unwrap();
    let mut scene_gpu = SceneGpu::new(ctx, scene, 0.0).unwrap();
    scene_gpu.components = component.mask();
    let targets = FrameTargets::new(ctx, size, size).unwrap();
    let mut tech = (info.create)(ctx, &params, scene, &scene_gpu, size, size).unwrap();
    scene_gpu.update_frame(scene, size, size, 0.0, 0).unwrap();
    let profiler = caustics::vk::Profiler::for_timing(ctx, 64).unwrap();
    // The first frame compiles the pipelines.
    profiler
        .frame(|rec| tech.record(rec, &scene_gpu, &targets))
        .unwrap();
    let passes = profiler
        .frame(|rec| tech.record(rec, &scene_gpu, &targets))
        .unwrap();
    tech.after_frame(0).unwrap();
    let ms = passes
        .iter()
        .filter(|p| caustic_passes.iter().any(|c| p.name.starts_with(c)))
        .map(|p| p.ms)
        .sum();
    let counts = (technique == "beams").then(|| {
        let c = tech.counters();
        let get = |n: &str| c.iter().find(|(k, _)| *k == n).map_or(0, |(_, v)| *v) as u32;
        BeamCounts {
            beams: [0, 1, 2, 3, 4, 5].map(|l| get(&format!("beams_level{l}"))),
            fragments: get("fragments"),
            ..Default::default()
        }
    });
    (targets.radiance.download_rgba32f().unwrap(), ms, counts)
}

/// For BENCHMARKS.md: Fig. 4 (adaptive against regular grids), Fig. 6
/// (tight against prism volumes) and beams against volume_lines, on
/// volume_cone's volume caustic (L S+ V) at `BEAMS_BENCH_SIZE` (default
/// 128) against the reference (2 M photons), in one run.
#[test]
#[ignore]
fn benchmark_statistics() {
    let size: u32 = std::env::var("BEAMS_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(128);
    let ctx = Context::new(&caustics::vk::ContextOptions {
        validation: false,
        sync_validation: false,
        device: None,
    })
    .unwrap();
    let scene = canonical_scene("volume_cone");
    let mask = first_hit_mask(&scene, size, true, |k| k == MaterialKind::Diffuse);
    let mut reference = ReferenceRenderer::new(
        &ctx,
        scene.clone(),
        size,
        size,
        0.0,
        ReferenceSettings::default(),
    )
    .unwrap();
    reference.trace(2_000_000, |_, _| {}).unwrap();
    let truth = masked(
        &reference.resolve(Component::VolumeCaustics).unwrap(),
        &mask,
    );
    drop(reference);
    let truth_ldr = tonemap(&truth);
    let t = energy(&truth);
    let compare = |img: &[f32]| {
        let img = masked(img, &mask);
        let (f, _) = flip(&tonemap(&img), &truth_ldr, size);
        (f, energy(&img) / t - 1.0)
    };
    println!("volume_cone, {size}², volume caustics against the reference (2 M photons)");
    println!("| technique | settings | beams | fragments | caustics ms | FLIP | energy |");
    println!("| --- | --- | ---: | ---: | ---: | ---: | ---: |");
    let beam_passes = ["beam grid", "beam refine", "beam volumes"];
    let configs: &[&[&str]] = &[
        &["grid_size=16", "levels=0"],
        &["grid_size=32", "levels=0"],
        &["grid_size=64", "levels=0"],
        &["grid_size=16", "levels=1"],
        &["grid_size=16", "levels=2"],
        &["grid_size=16", "levels=3"],
        &["grid_size=16", "levels=3", "volume=0"],
        &["grid_size=64", "levels=0", "volume=0"],
        // The oracle on discontinuities alone (Sect. 4.2 (a); the paper's
        // water scene: smooth refractors, refined at the silhouettes).
        &[
            "grid_size=16",
            "levels=1",
            "split_focus=0",
            "split_energy=1",
            "split_camera=10",
        ],
        &[
            "grid_size=16",
            "levels=2",
            "split_focus=0",
            "split_energy=1",
            "split_camera=10",
        ],
        &[
            "grid_size=16",
            "levels=3",
            "split_focus=0",
            "split_energy=1",
            "split_camera=10",
        ],
    ];
    for o in configs {
        let (img, ms, c) = timed(
            &ctx,
            &scene,
            "beams",
            o,
            Component::VolumeCaustics,
            size,
            &beam_passes,
        );
        let c = c.unwrap();
        let (f, e) = compare(&img);
        println!(
            "| beams | {} | {} | {} | {ms:.0} | {f:.4} | {e:+.3} |",
            o.join(" "),
            c.total_beams(),
            c.fragments
        );
    }
    for n in [128u32, 256, 512] {
        let o = format!("volume_buffer_size={n}");
        let (img, ms, _) = timed(
            &ctx,
            &scene,
            "volume_lines",
            &[&o, "photon_buffer_size=64"],
            Component::VolumeCaustics,
            size,
            &["volume segments", "volume lines"],
        );
        let (f, e) = compare(&img);
        println!("| volume_lines | {o} | | | {ms:.0} | {f:.4} | {e:+.3} |");
    }
}

/// The components add up to the frame (Fig. 8): direct and surface
/// caustics, airlight and volume caustics, each drawn alone, sum to
/// everything drawn at once. Measured (32², 1 level): worst pixel 2.4e-7
/// relative (bound 1e-4).
#[test]
fn components_add_up_to_the_frame() {
    let ctx = validated_context();
    let scene = canonical_scene("volume_cone");
    // Midpoint airlight samples: the same airlight in every render.
    let opts = ["airlight_jitter=0", "airlight_steps=16", "levels=1"];
    let draw = |mask: u32| render(&ctx, &scene, &opts, mask, 32).radiance();
    let all = draw(Component::All.mask());
    let parts = [
        draw(Component::Direct.mask() | Component::SurfaceCaustics.mask()),
        draw(Component::Airlight.mask()),
        draw(Component::VolumeCaustics.mask()),
    ];
    assert!(parts.iter().all(|p| energy(p) > 0.0));
    let mut worst = 0.0f32;
    for (i, d) in all.chunks(4).enumerate() {
        for k in 0..3 {
            let sum: f32 = parts.iter().map(|p| p[4 * i + k]).sum();
            worst = worst.max((d[k] - sum).abs() / d[k].abs().max(1e-3));
        }
    }
    println!("all vs the three parts: worst relative difference {worst:.2e}");
    assert!(worst < 1e-4, "{worst}");
    assert_validation_clean(&ctx);
}

/// The same bookkeeping under a directional light: flux E times the base
/// triangle's area projected on the light direction, and the lens's
/// projected disc pi r^2 between the kept and the kept plus dropped
/// X
#[test]
fn directional_beams_carry_the_irradiance_times_the_projected_area() {
    let ctx = validated_context();
    let mut scene = canonical_scene("ball_lens");
    lens_ior(&mut scene, 1.0);
    scene.lights = vec![directional_light(Vec3::new(0.3, -1.0, 0.2), 2.0)];
    let f = render(&ctx, &scene, &[], Component::SurfaceCaustics.mask(), 32);
    let c = f.counts();
    let disc = std::f64::consts::PI; // r = 1 m
    let kept = c.kept_measure as f64 / disc;
    let tiled = (c.kept_measure + c.dropped_measure) as f64 / disc;
    let ratio = c.flux_out as f64 / c.flux_in as f64;
    println!(
        "directional: flux_in {:.4} W = E x kept area {:.4} W; carried / entering {ratio:.5}; kept / disc {kept:.4}, (kept + dropped) / disc {tiled:.4}",
        c.flux_in,
        2.0 * c.kept_measure
    );
    assert!((c.flux_in / (2.0 * c.kept_measure) - 1.0).abs() < 1e-3);
    assert!((ratio - 1.0).abs() < 0.01);
    assert!(
        kept < 1.0 && tiled > 1.0,
        "kept {kept}, kept + dropped {tiled}"
    );
    assert_validation_clean(&ctx);
}

/// The extrusion's energy cut-off (Sect. 4.3) on volume_cone: divergent
/// beams (the front-face reflections fanning out through the medium) end
/// where their flux density falls below the cut-off times their base's,
/// trading their thin far ends for fragments. Measured (32²): 0.01 keeps
/// 0.9964 of the energy with 0.975x the fragments, 0.05 keeps 0.9097 with
/// 0.597x.
#[test]
fn energy_cutoff_trades_thin_light_for_fragments() {
    let ctx = validated_context();
    let scene = canonical_scene("volume_cone");
    let run = |cutoff: &str| {
        let f = render(
            &ctx,
            &scene,
            &[cutoff],
            Component::VolumeCaustics.mask(),
            32,
        );
        (energy(&f.radiance()), f.counts().fragments as f64)
    };
    let (full, full_frags) = run("extrusion_cutoff=0");
    let (light, light_frags) = run("extrusion_cutoff=0.01");
    let (heavy, heavy_frags) = run("extrusion_cutoff=0.05");
    println!(
        "cut-off 0.01: energy {:.4} x, fragments {:.3} x; 0.05: energy {:.4} x, fragments {:.3} x",
        light / full,
        light_frags / full_frags,
        heavy / full,
        heavy_frags / full_frags
    );
    assert!(light <= full * (1.0 + 1e-6) && light > 0.99 * full);
    assert!(heavy < light && heavy > 0.88 * full);
    assert!(
        heavy_frags < light_frags && light_frags <= full_frags && heavy_frags < 0.7 * full_frags
    );
    assert_validation_clean(&ctx);
}

/// The surface caustics' low-pass filter (Sect. 7) smooths the beam
/// boundaries' steps: on ball_lens the brightest pixel drops, the energy
/// stays (the filter keeps the deposited flux over the receivers of one
/// surface; moved between pixels of slightly different footprints, the
/// radiance's sum changes a little). Measured (64², radius 3): energy of
/// the floor seen directly 1.0019x, brightest pixel 0.241x.
#[test]
fn surface_filter_smooths_and_keeps_the_energy() {
    let ctx = validated_context();
    let scene = canonical_scene("ball_lens");
    // The floor seen directly (through the lens the refraction looks the
    // filtered image up elsewhere).
    let mask = first_hit_mask(&scene, 64, false, |k| k == MaterialKind::Diffuse);
    let run = |o: &str| {
        let img = masked(
            &render(&ctx, &scene, &[o], Component::SurfaceCaustics.mask(), 64).radiance(),
            &mask,
        );
        let peak = (0..64 * 64).map(|i| sum_rgb(&img, i)).fold(0.0, f64::max);
        (energy(&img), peak)
    };
    let (raw, raw_peak) = run("surface_filter=0");
    let (smooth, smooth_peak) = run("surface_filter=3");
    println!(
        "filter radius 3: energy {:.4} x, peak {:.3} x",
        smooth / raw,
        smooth_peak / raw_peak
    );
    assert!((smooth / raw - 1.0).abs() < 0.01);
    assert!(smooth_peak < raw_peak);
    assert_validation_clean(&ctx);
}

/// A periscope for multiple bounces (Sect. 6): a point light beside a 45
/// degree mirror, which turns its light down onto a ball lens (r = 1 m,
/// n = 1.5) over the floor, so the lens's caustic below it is an L S S D
/// path (mirror, then lens); the lamp also lights the lens directly (its
/// one-bounce caustic lands beside it), and part of the lens's reflection
/// meets the mirror (lens, then mirror).
const PERISCOPE: &str = r#"
[camera]
eye = [3.0, 5.0, 6.0]
target = [0.5, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 45.0

[[light]]
kind = "point"
position = [-3.0, 4.0, 0.0]
intensity = [60.0, 60.0, 60.0]

[[material]]
name = "glass"
kind = "dielectric"
ior = 1.5

[[material]]
name = "floor"
kind = "diffuse"
albedo = [0.8, 0.8, 0.8]

[[material]]
name = "mirror"
kind = "mirror"
reflectance = [0.9, 0.9, 0.9]

[[object]]
name = "lens"
shape = "sphere"
center = [0.0, 1.6, 0.0]
radius = 1.0
material = "glass"

[[object]]
name = "floor"
shape = "plane"
center = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
size = [10.0, 10.0]
material = "floor"

[[object]]
name = "mirror"
shape = "plane"
center = [0.0, 4.0, 0.0]
normal = [-0.70710678, -0.70710678, 0.0]
tangent = [0.0, 0.0, 1.0]
size = [2.0, 2.0]
material = "mirror"
"#;

fn periscope() -> Scene {
    Scene::from_str(PERISCOPE, std::path::Path::new("periscope.toml")).unwrap()
}

/// Closest hit of the ray on object `object` of the CPU BVH (`t > t_min`):
/// the point and the interpolated normal (as `hit_normal` on the GPU).
fn hit_on_object(
    bvh: &Bvh,
    tris: &[caustics::gpu::GpuTriangle],
    object: u32,
    o: DVec3,
    d: DVec3,
) -> Option<(DVec3, DVec3)> {
    let mut t0 = 1e-4f32;
    for _ in 0..8 {
        let h = bvh.intersect(tris, o.as_vec3(), d.as_vec3(), t0, 1e30)?;
        let tri = &tris[h.triangle as usize];
        if tri.p1[3].to_bits() != object {
            t0 = h.t * (1.0 + 1e-5);
            continue;
        }
        let n3 = |a: [f32; 4]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
        let (u, v) = (h.u as f64, h.v as f64);
        let n = ((1.0 - u - v) * n3(tri.n0) + u * n3(tri.n1) + v * n3(tri.n2)).normalize();
        return Some((o + h.t as f64 * d, n));
    }
    None
}

/// Multiple bounces (Sect. 6) on the periscope with absorbing glass (0.3
/// /m): every child beam carries its parent's flux (no medium: what
/// arrives is what the parent carries) times what the surface it came off
/// does to it, recomputed here on the CPU from the parent's edge rays
/// against the same tessellated scene (the CPU BVH, interpolated normals):
/// the mirror's reflectance 0.9; off the lens, the Fresnel reflectance F,
/// or (1 - F_in)(1 - F_out) exp(-sigma_a L) along the path through the
/// ball; factors averaged over the three edges, as the beam does (one flux
/// per beam). Measured (32², 2 levels): see the printout; bounds 1% on
/// the sum and on any child.
#[test]
fn bounced_beams_carry_their_parents_flux_times_fresnel_and_absorption() {
    let ctx = validated_context();
    let mut scene = periscope();
    let sigma_a = 0.3f64;
    let ior = 1.5f64;
    for m in &mut scene.materials {
        if m.kind == MaterialKind::Dielectric {
            m.absorption = Vec3::splat(sigma_a as f32);
        }
    }
    let triangles = scene.triangles(0.0);
    let bvh = Bvh::build(&triangles);
    let tris = bvh.gpu_triangles(&triangles);
    let object = |name: &str| scene.objects.iter().position(|o| o.name == name).unwrap() as u32;
    let (lens, mirror) = (object("lens"), object("mirror"));
    let f = render(
        &ctx,
        &scene,
        &["levels=2"],
        Component::SurfaceCaustics.mask(),
        32,
    );
    let c = f.counts();
    assert_eq!(c.beam_overflow, 0);
    let beams = f.beams(&c);
    let (mut predicted, mut carried) = (0.0f64, 0.0f64);
    let (mut off_mirror, mut off_lens, mut worst) = (0u32, 0u32, 0.0f64);
    let v3 = |a: [f32; 4]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    for child in beams.iter().filter(|b| b.bounce() == 2) {
        let parent = &beams[child.parent().expect("a bounced beam has a parent")];
        assert_eq!(parent.bounce(), 1);
        let parent_flux = parent.flux[1] as f64;
        assert!((child.incident[1] as f64 / parent_flux - 1.0).abs() < 1e-4);
        // The object the child came off: the one every edge meets first.
        let (o0, d0) = (v3(parent.v[0]), v3(parent.e[0]).normalize());
        let first = |target: u32| {
            hit_on_object(&bvh, &tris, target, o0, d0).map(|(x, _)| (x - o0).length())
        };
        let on_mirror = match (first(mirror), first(lens)) {
            (Some(a), Some(b)) => a < b,
            (a, _) => a.is_some(),
        };
        let mut factor = 0.0;
        for k in 0..3 {
            let (o, d) = (v3(parent.v[k]), v3(parent.e[k]).normalize());
            if on_mirror {
                assert!(hit_on_object(&bvh, &tris, mirror, o, d).is_some());
                factor += 0.9 / 3.0;
                continue;
            }
            let (x, n) = hit_on_object(&bvh, &tris, lens, o, d).expect("the edge meets the lens");
            let n = if n.dot(d) > 0.0 { -n } else { n };
            let f_in =
                caustics::radiometry::fresnel_dielectric(-d.dot(n) as f32, (1.0 / ior) as f32)
                    as f64;
            if child.kind() == 0 {
                factor += f_in / 3.0;
                continue;
            }
            // Through the ball: total internal reflections followed, as
            // traced_refraction does.
            let mut dir = refract(d, n, 1.0 / ior).unwrap();
            let (mut p, mut inside, mut t) = (x, 0.0, 1.0 - f_in);
            for _ in 0..8 {
                let (y, m) =
                    hit_on_object(&bvh, &tris, lens, p, dir).expect("the path leaves the lens");
                inside += (y - p).length();
                p = y;
                let m = if m.dot(dir) > 0.0 { -m } else { m };
                if refract(dir, m, ior).is_some() {
                    t *= 1.0
                        - caustics::radiometry::fresnel_dielectric(-dir.dot(m) as f32, ior as f32)
                            as f64;
                    break;
                }
                dir = dir - 2.0 * dir.dot(m) * m;
            }
            factor += t * (-sigma_a * inside).exp() / 3.0;
        }
        if on_mirror {
            off_mirror += 1;
        } else {
            off_lens += 1;
        }
        let expected = parent_flux * factor;
        let got = child.flux[1] as f64;
        worst = worst.max((got / expected - 1.0).abs());
        predicted += expected;
        carried += got;
    }
    let rel = carried / predicted - 1.0;
    println!(
        "{} beams, {off_lens} children off the lens, {off_mirror} off the mirror; children carry {carried:.5} W vs {predicted:.5} W predicted ({rel:+.2e}), worst child {worst:.2e}",
        beams.len()
    );
    assert!(off_mirror > 0 && off_lens > 0, "both bounce orders appear");
    assert!(
        rel.abs() < 0.01,
        "children carry {rel:+.4} of the prediction"
    );
    assert!(worst < 0.01, "worst child off by {worst:.4}");
    assert_validation_clean(&ctx);
}

// Multiple bounces against the reference, L S+ D, 64², 1 M photons
// (BENCHMARKS.md, "beams", multiple bounces; bounds: measured energy +
// 0.04, FLIP x 1.25). The periscope's caustic below the lens comes only
// through the mirror: with `bounces=1` the mirror's beams pass the lens and
// light its shadow evenly (energy -4.1%, FLIP 0.118); with the default 2
// they focus (-4.8%, FLIP 0.081; the reference's halves 0.059); with
// grid_size=32 -2.9%, FLIP 0.060. On mirror_caustic (-4.0%, FLIP 0.033)
// the two-bounce paths carry little light
// (the lamp's image in the mirror sees the lens below the mirror's top
// edge, so there are no mirror-then-lens paths; lens-then-mirror is the
// lens's faint reflection). The point-sampled gather this replaced missed
// the lens's focus, a few pixels wide (-25.0% at 64², -17% at 128²); the
// caustic triangles deposit its flux whole. (Measured with the default
// traced two-sided refraction; with Wyman's image-space exit, the default
// until 2026-12-02: periscope -7.2%, FLIP 0.095, one bounce -6.5%, 0.128,
// grid_size=32 -5.1%, 0.085; mirror_caustic -6.6%, 0.044.)
#[test]
fn multiple_bounces_match_reference() {
    let ctx = validated_context();
    let reference = |label: &str, scene: &Scene, overrides: &[&str], energy: f64, flip: f32| {
        matches_reference(
            &ctx,
            label,
            scene,
            Component::SurfaceCaustics,
            64,
            1_000_000,
            overrides,
            Bound { energy, flip },
        )
    };
    let (_, two) = reference("periscope_surface", &periscope(), &[], 0.09, 0.101);
    let (_, one) = reference(
        "periscope_surface_one_bounce",
        &periscope(),
        &["bounces=1"],
        0.085,
        0.148,
    );
    reference(
        "periscope_surface_fine",
        &periscope(),
        &["grid_size=32"],
        0.07,
        0.075,
    );
    reference(
        "mirror_caustic_surface",
        &canonical_scene("mirror_caustic"),
        &[],
        0.08,
        0.041,
    );
    assert!(two < one, "the second bounce brings the image closer to the reference: FLIP {two} vs {one} with one bounce");
    assert_validation_clean(&ctx);
}

/// Area lights (GUIDE §2) as `image_space` and `volume_lines` take them:
/// a small rect is a spot stand-in at its centre with the cosine profile
/// (I = L A cos theta). On `ball_lens` with the point light replaced by a
/// 5 cm rect of the same I0 = L A, the beams' surface caustic against the
/// reference's L S+ D (96², 1 M photons, refraction traced through the
/// BVH) must score as the point light's does. Measured: rect -5.81%, FLIP
/// 0.036 (the reference's halves 0.044); point -5.73%, 0.027 (bounds:
/// energy 9%, FLIP 0.045; rect vs point energy within 2%). Before the energy
/// criterion took the stand-ins' views into account the rect's triangles
/// all split (+2.0%). A 2 m rect 6.4 m from the lens, and a sphere light,
/// are refused by `check_scene` with a message naming the light.
#[test]
fn small_rect_lights_are_point_stand_ins() {
    let ctx = validated_context();
    let (point, rect, scene) = (
        BALL_LENS_POINT_LIGHT,
        ball_lens_rect_light,
        ball_lens_with_light,
    );
    let bound = Bound {
        energy: 0.09,
        flip: 0.045,
    };
    let small = scene(&rect(0.05));
    Beams::check_scene(&small).unwrap();
    let (rect_energy, rect_flip) = matches_reference(
        &ctx,
        "ball_lens_rect",
        &small,
        Component::SurfaceCaustics,
        96,
        1_000_000,
        &["refraction=1"],
        bound,
    );
    let (point_energy, point_flip) = matches_reference(
        &ctx,
        "ball_lens_point",
        &scene(point),
        Component::SurfaceCaustics,
        96,
        1_000_000,
        &["refraction=1"],
        bound,
    );
    println!(
        "rect stand-in: energy {rect_energy:+.4}, FLIP {rect_flip:.4}; point light: {point_energy:+.4}, {point_flip:.4}"
    );
    assert!((rect_energy - point_energy).abs() < 0.02);

    let err = Beams::check_scene(&scene(&rect(2.0))).unwrap_err();
    assert!(
        format!("{err:#}").contains("beams treats rect lights as points: area light 0"),
        "{err:#}"
    );
    let sphere = "[[light]]\nkind = \"sphere\"\ncenter = [0.0, 8.0, 0.0]\nradius = 0.05\nradiance = 1000.0\n";
    let err = Beams::check_scene(&scene(sphere)).unwrap_err();
    assert!(
        format!("{err:#}").contains("beams does not support sphere lights (area light 0)"),
        "{err:#}"
    );
    assert_validation_clean(&ctx);
}

// The media scenes, 64², default parameters: volume_cone 1 M photons,
// smoke 0.5 M (its heterogeneous transmittance makes the reference's
// photons about 2.5x dearer). Measured (reference halves in brackets):
// volume_cone L S+ D -3.08%, FLIP 0.0174 (-0.23%, 0.0104); smoke L S+ D
// -2.92%, FLIP 0.0143 (+0.52%, 0.0126); smoke L S+ V -17.86%, FLIP 0.0140
// (+0.42%, 0.0098; the volume deficit is volume_cone's, explained above
// `volume_cone_volume_caustics_match_reference`). With Wyman's image-space
// exit (`refraction=0`, the default until 2026-12-02) the surfaces read
// -14.0% and -14.5%: past the focus (the lens at 2.5 m focuses the spot at
// y = 0.44 m, above the floor) the rim light its false total internal
// reflection sends out sideways lands out of view (26% of the landing
// flux beyond 1.5 m of the axis against 13% traced;
// `surface_gather_deposits_each_beams_flux` shows the gather keeps every
// beam's flux there). Bounds: energy |measured| + 0.04, FLIP 1.25 x
// measured. 43-48 s on 2 loaded cores.
#[test]
fn medium_scenes_match_reference() {
    let ctx = validated_context();
    let smoke = canonical_scene("smoke");
    let cases = [
        (
            "volume_cone_surface",
            canonical_scene("volume_cone"),
            Component::SurfaceCaustics,
            1_000_000,
            0.071,
            0.022,
        ),
        (
            "smoke_surface",
            smoke.clone(),
            Component::SurfaceCaustics,
            500_000,
            0.07,
            0.018,
        ),
        (
            "smoke_volume",
            smoke,
            Component::VolumeCaustics,
            500_000,
            0.22,
            0.018,
        ),
    ];
    for (label, scene, component, photons, energy, flip) in cases {
        matches_reference(
            &ctx,
            label,
            &scene,
            component,
            64,
            photons,
            &[],
            Bound { energy, flip },
        );
    }
    assert_validation_clean(&ctx);
}
