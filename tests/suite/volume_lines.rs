//! The `volume_lines` technique (Hu et al. 2010, line-based volume
//! caustics) against physics and the ground truth. Lavapipe, validation on,
//! 128² frames; B (the volume caustic, L S+ V) is drawn alone through the
//! component mask, so what is measured is exactly what
//! `render --component volume_caustics` writes.
//!
//! Measured (lavapipe, Mesa 22.3.6; `cargo test --release --test volume_lines -- --nocapture`):
//! - no_scattering_no_volume_caustic: sigma_s = 0 gives exactly 0 (rgb)
//!   while the lines are still drawn.
//! - optically_thin_volume_caustic_is_linear_in_sigma_s (sigma_a = 0):
//!   sigma_s 0.002 -> 0.004 multiplies B's energy by 1.9546 (2 times the
//!   extra extinction along ~12 m of path, exp(-0.002 * 12) = 0.977;
//!   bound 5%).
//! - lines_match_the_beam_integral_and_the_phase_function (128² buffer,
//!   camera below the lens looking up the cone, no floor): the image's
//!   energy against the CPU integral of the same light rays
//!   (sigma_s p Phi tau ds / (t^2 Omega_px)): ratio 0.9972 (g = 0.7) and
//!   0.9971 (g = -0.7) (bound 1.5%), which checks the line radiometry
//!   (w_world sin theta, the normalised step-point weights) without the
//!   reference; B(0.7) / B(-0.7) = 25.498 vs 25.495 predicted by HG over
//!   the actual angles (+1e-4; bound 1%).
//! - one_line_per_texel_that_sees_the_lens (256² buffer): 15600
//!   transmitted lines = 15600 covered front texels, 15600 reflected
//!   lines, 15598 CPU rays through the texel centres meet the lens first
//!   (silhouette ties; bound 0.2%).
//! - components_add_up_to_the_frame: A alone + B alone + C (direct and
//!   surface caustics)
//!   alone = the whole frame, worst pixel 1.2e-7 relative (bound 1e-4).
//! - filter_radius_beyond_sixteen_steps_is_refused: r = 50 Delta_x is an
//!   error naming the parameter and the limit.
//! - against the reference's L S+ V (128², 2 M photons, default
//!   parameters: 512² buffer, Delta_x = r = 0.2, tir_remedy 1), pixels
//!   whose camera ray meets glass first zeroed in both, relative energy
//!   and FLIP mean (the reference's two halves in brackets):
//!   volume_cone g = -0.7: +16.4%, 0.0184 (+0.07%, 0.0082);
//!   volume_cone g = 0: +1.7%, 0.0212 (+0.3%, 0.0100);
//!   volume_cone g = 0.7: +3.2%, 0.0133 (-3.2%, 0.0109);
//!   smoke: +1.4%, 0.0214 (+0.07%, 0.0088).
//!   The tests trace 1 M photons since 2026-12-03 (issue 26, half the
//!   time, bounds unchanged): +15.2%, 0.0192 (-1.8%, 0.0108); +1.1%,
//!   0.0218 (-0.2%, 0.0138); +3.4%, 0.0138 (-2.8%, 0.0129); smoke +1.1%,
//!   0.0218 (-0.2%, 0.0116).
//!   The lines' own radiometry is within 0.3% (above); what differs is the
//!   light rays: Eq. 6.3.1's exit misses the sphere's true one, and near
//!   the rim the approximated exit meets total internal reflection that a
//!   sphere does not have, which the default remedy (clamp to the critical
//!   angle) sends out tangentially: "wings" of light leaving the lens
//!   sideways, brightest in backscatter (g = -0.7; with tir_remedy 0
//!   it reads -22.3%, with 2 -11.9% but +70% at g = 0.7); light
//!   reflected inside the glass is not drawn (it is in the reference).

use crate::common;

use caustics::bvh::Bvh;
use caustics::frame::{FrameTargets, SceneGpu};
use caustics::params::ParamSet;
use caustics::passes::light_views::{photon_view, specular_bounds};
use caustics::reference::Component;
use caustics::scene::{MaterialKind, Scene};
use caustics::techniques::volume_lines::{GpuSegment, VolumeLines, VolumeLinesParams};
use caustics::techniques::Technique;
use caustics::vk::Context;
use common::*;
use glam::Vec3;
use std::sync::Arc;

const SIZE: u32 = 128;

struct Frame {
    tech: VolumeLines,
    targets: FrameTargets,
    _scene_gpu: SceneGpu,
}

impl Frame {
    fn radiance(&self) -> Vec<f32> {
        let img = self.targets.radiance.download_rgba32f().unwrap();
        assert_finite(&img);
        img
    }

    fn segments(&self) -> Vec<GpuSegment> {
        self.tech.rays.segments.download_pod().unwrap()
    }
}

/// One `volume_lines` frame of `scene` at SIZE², drawing only the
/// components in `mask`.
fn render(ctx: &Arc<Context>, scene: &Scene, overrides: &[&str], mask: u32) -> Frame {
    render_at(ctx, scene, overrides, mask, SIZE)
}

fn render_at(ctx: &Arc<Context>, scene: &Scene, overrides: &[&str], mask: u32, size: u32) -> Frame {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let params = VolumeLinesParams::parse("volume_lines", &overrides).unwrap();
    let mut scene_gpu = SceneGpu::new(ctx, scene, 0.0).unwrap();
    scene_gpu.components = mask;
    let targets = FrameTargets::new(ctx, size, size).unwrap();
    let mut tech = VolumeLines::new(ctx, &params, scene, &scene_gpu, size, size).unwrap();
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

/// B alone.
fn volume_caustic(ctx: &Arc<Context>, scene: &Scene, overrides: &[&str]) -> Vec<f32> {
    render(ctx, scene, overrides, Component::VolumeCaustics.mask()).radiance()
}

fn set_medium(scene: &mut Scene, sigma_s: f32, sigma_a: f32, g: f32) {
    let m = scene.medium.as_mut().expect("scene has a medium");
    m.sigma_s = Vec3::splat(sigma_s);
    m.sigma_a = Vec3::splat(sigma_a);
    m.g = g;
}

#[test]
fn no_scattering_no_volume_caustic() {
    let ctx = validated_context();
    let mut scene = canonical_scene("volume_cone");
    set_medium(&mut scene, 0.0, 0.005, 0.0);
    let f = render(&ctx, &scene, &[], Component::VolumeCaustics.mask());
    let valid = f.segments().iter().filter(|s| s.p1[3] > 0.0).count();
    assert!(valid > 1000, "the light rays are still drawn ({valid})");
    let img = f.radiance();
    let max = img
        .chunks(4)
        .flat_map(|p| &p[..3])
        .fold(0.0f32, |a, &v| a.max(v.abs()));
    assert_eq!(max, 0.0, "sigma_s = 0 must give exactly no volume caustic");
    assert_validation_clean(&ctx);
}

#[test]
fn optically_thin_volume_caustic_is_linear_in_sigma_s() {
    let ctx = validated_context();
    let mut scene = canonical_scene("volume_cone");
    set_medium(&mut scene, 0.002, 0.0, 0.0);
    let one = energy(&volume_caustic(&ctx, &scene, &[]));
    set_medium(&mut scene, 0.004, 0.0, 0.0);
    let two = energy(&volume_caustic(&ctx, &scene, &[]));
    let ratio = two / one;
    println!("sigma_s 0.002 -> 0.004: B energy {one:.6} -> {two:.6}, ratio {ratio:.4}");
    assert!(one > 0.0);
    assert!((ratio / 2.0 - 1.0).abs() < 0.05, "ratio {ratio}");
    assert_validation_clean(&ctx);
}

/// Bounds of one comparison with the reference.
struct Bound {
    /// |relative total energy| of B against the reference's L S+ V.
    energy: f64,
    /// FLIP mean of the tonemapped images.
    flip: f32,
}

/// B on `scene` (defaults: Delta_x = r = 0.2) against the reference's
/// volume_caustics component with `photons` photons (two halves, to report
/// the reference's own noise).
fn matches_reference(ctx: &Arc<Context>, label: &str, scene: &Scene, photons: u64, bound: Bound) {
    // The lines do not show the medium seen through glass (Hu Sect. 5.3:
    // B is drawn along camera rays only), while the reference does (its
    // volume gather along camera chains): pixels whose camera ray meets a
    // specular surface first are zeroed in both images.
    let mask = first_hit_mask(scene, SIZE, true, |k| k == MaterialKind::Diffuse);
    let reference = reference_images(
        ctx,
        &ReferenceRequest::new(scene, SIZE, photons).in_halves(),
    );
    let half_a = masked(reference.first_half(Component::VolumeCaustics), &mask);
    let truth = masked(reference.whole(Component::VolumeCaustics), &mask);
    let half_b = second_half(&truth, &half_a);
    let (noise_flip, _) = flip(&tonemap(&half_b), &tonemap(&half_a), SIZE);
    let t = energy(&truth);
    let halves = (energy(&half_b) - energy(&half_a)) / t;
    let lines = masked(&volume_caustic(ctx, scene, &[]), &mask);
    let rel = (energy(&lines) - t) / t;
    let (lines_ldr, truth_ldr) = (tonemap(&lines), tonemap(&truth));
    let (flip_mean, flip_map) = flip(&lines_ldr, &truth_ldr, SIZE);
    println!(
        "{label}: reference L S+ V energy {t:.4} ({photons} photons; halves differ by {halves:+.4}, FLIP {noise_flip:.4}); lines {:.4}, relative {rel:+.4} (bound {}); FLIP mean {flip_mean:.4} (bound {})",
        energy(&lines),
        bound.energy,
        bound.flip
    );
    if rel.abs() >= bound.energy || flip_mean >= bound.flip {
        let dir = write_comparison_pngs(
            &format!("volume_lines_{label}"),
            SIZE,
            &lines_ldr,
            &truth_ldr,
            &flip_map,
        );
        panic!("{label}: relative energy {rel:+.4}, FLIP mean {flip_mean:.4} (images in {dir})");
    }
}

/// The smallest count whose measurements (the file's header) stay inside
/// every bound.
const PHOTONS_REFERENCE: u64 = 1_000_000;

// Bounds: measured (see the file's header) plus a margin: energy
// |measured| + 0.03, FLIP mean 1.25 x measured, rounded up to 0.005. The
// reference's seeds are fixed, so a rerun on lavapipe repeats the
// measurement.
#[test]
fn volume_cone_matches_reference() {
    let ctx = validated_context();
    for (g, bound) in [
        (
            -0.7f32,
            Bound {
                energy: 0.195,
                flip: 0.025,
            },
        ),
        (
            0.0,
            Bound {
                energy: 0.05,
                flip: 0.03,
            },
        ),
        (
            0.7,
            Bound {
                energy: 0.065,
                flip: 0.02,
            },
        ),
    ] {
        let mut scene = canonical_scene("volume_cone");
        scene.medium.as_mut().unwrap().g = g;
        matches_reference(
            &ctx,
            &format!("volume_cone_g{g}"),
            &scene,
            PHOTONS_REFERENCE,
            bound,
        );
    }
    assert_validation_clean(&ctx);
}

#[test]
fn smoke_matches_reference() {
    let ctx = validated_context();
    matches_reference(
        &ctx,
        "smoke",
        &canonical_scene("smoke"),
        PHOTONS_REFERENCE,
        Bound {
            energy: 0.045,
            flip: 0.03,
        },
    );
    assert_validation_clean(&ctx);
}

/// Sum over the SIZE² image of the single-scattered radiance of the light
/// rays in `segments`, by the physics the lines stand for, independent of
/// line rasterisation: a length ds of a light ray of flux Phi sends the
/// intensity sigma_s p Phi tau ds toward the camera, which spreads it over
/// pixels of solid angle Omega_px, so
///   sum_px L_px = sum_seg int sigma_s p(cos) Phi tau(p1, x) tau(x, eye) V(x) / (t^2 Omega_px(x)) ds,
/// Omega_px = (2 tan(fov/2) / SIZE)^2 cos^3(angle off the axis), V = in the
/// frustum and not behind a surface (CPU BVH). Homogeneous medium only.
/// Returns the integral for each phase asymmetry in `gs` (midpoint rule,
/// `samples` points per segment).
fn beam_energy(scene: &Scene, segments: &[GpuSegment], gs: &[f64], samples: u32) -> Vec<f64> {
    let medium = scene.medium.as_ref().unwrap();
    let caustics::scene::Density::Constant(density) = medium.density else {
        panic!("homogeneous media only");
    };
    let (lo, hi) = (medium.bounds_min, medium.bounds_max);
    let sigma_s = (medium.sigma_s.x * density) as f64;
    let sigma_t = ((medium.sigma_s.x + medium.sigma_a.x) * density) as f64;
    let tris = scene.triangles(0.0);
    let bvh = Bvh::build(&tris);
    let gpu = bvh.gpu_triangles(&tris);
    let cam = &scene.camera;
    let (view, proj) = caustics::frame::camera_matrices(cam, 1.0);
    let view_proj = proj * view;
    let forward = (cam.target - cam.eye).normalize();
    let a_px = 2.0 * (cam.fov_y_deg.to_radians() * 0.5).tan() as f64 / SIZE as f64;
    let inside = |x: Vec3| x.cmpge(lo).all() && x.cmple(hi).all();
    let mut sums = vec![0.0f64; gs.len()];
    for s in segments.iter().filter(|s| s.p1[3] > 0.0) {
        let p1 = Vec3::from_slice(&s.p1[..3]);
        let p2 = Vec3::from_slice(&s.p2[..3]);
        let len = (p2 - p1).length();
        let u = (p2 - p1) / len;
        let ds = len / samples as f32;
        for i in 0..samples {
            let x = p1 + u * ((i as f32 + 0.5) * ds);
            if !inside(x) {
                continue;
            }
            let clip = view_proj * x.extend(1.0);
            if clip.w <= 0.0 {
                continue;
            }
            let ndc = clip.truncate() / clip.w;
            if ndc.x.abs() > 1.0 || ndc.y.abs() > 1.0 {
                continue;
            }
            let to_x = x - cam.eye;
            let t = to_x.length();
            let w = to_x / t;
            if bvh.occluded(&gpu, cam.eye, w, 0.0, t * (1.0 - 1e-5)) {
                continue;
            }
            let tau = (-sigma_t
                * (length_in_box(p1.as_dvec3(), x.as_dvec3(), lo.as_dvec3(), hi.as_dvec3())
                    + length_in_box(
                        cam.eye.as_dvec3(),
                        x.as_dvec3(),
                        lo.as_dvec3(),
                        hi.as_dvec3(),
                    )))
            .exp();
            let cos_axis = w.dot(forward) as f64;
            let omega_px = a_px * a_px * cos_axis.powi(3);
            let common =
                sigma_s * s.flux[0] as f64 * tau * ds as f64 / (t as f64 * t as f64 * omega_px);
            for (sum, &g) in sums.iter_mut().zip(gs) {
                *sum += common * hg_phase(u.dot(-w) as f64, g);
            }
        }
    }
    sums
}

/// Red summed over the image.
fn red_energy(img: &[f32]) -> f64 {
    img.chunks(4).map(|p| p[0] as f64).sum()
}

/// The line radiometry (Eq. 3 with the rasterised line as the beam kernel)
/// against the same light rays integrated on the CPU, and the phase
/// function's effect: a camera below the lens looking up the cone (toward
/// the light), no floor, g = +-0.7.
#[test]
fn lines_match_the_beam_integral_and_the_phase_function() {
    let ctx = validated_context();
    let mut scene = canonical_scene("volume_cone");
    scene.objects.retain(|o| o.name != "floor");
    scene.camera = camera(Vec3::new(0.0, -2.0, 1.5), Vec3::new(0.0, 1.0, 0.0), 30.0);
    let mut measured = Vec::new();
    let mut predicted = Vec::new();
    for g in [0.7f32, -0.7] {
        scene.medium.as_mut().unwrap().g = g;
        let f = render(
            &ctx,
            &scene,
            &["volume_buffer_size=128"],
            Component::VolumeCaustics.mask(),
        );
        let gpu = red_energy(&f.radiance());
        let cpu = beam_energy(&scene, &f.segments(), &[g as f64], 400)[0];
        println!(
            "g = {g}: lines {gpu:.5}, beam integral {cpu:.5}, ratio {:.4}",
            gpu / cpu
        );
        assert!(
            (gpu / cpu - 1.0).abs() < 0.015,
            "g = {g}: lines {gpu} vs beam integral {cpu}"
        );
        measured.push(gpu);
        predicted.push(cpu);
    }
    let (m, p) = (measured[0] / measured[1], predicted[0] / predicted[1]);
    println!(
        "B(g = 0.7) / B(g = -0.7): lines {m:.4}, predicted {p:.4}, relative {:+.4}",
        m / p - 1.0
    );
    assert!(
        m > 10.0,
        "forward scattering toward this camera must dominate"
    );
    assert!((m / p - 1.0).abs() < 0.01, "phase ratio {m} vs {p}");
    assert_validation_clean(&ctx);
}

/// One line per light-space texel whose centre ray meets a specular object
/// first: the valid entries of the volume caustic buffer against a CPU ray
/// cast (BVH) through the same texels of the same light view.
#[test]
fn one_line_per_texel_that_sees_the_lens() {
    let ctx = validated_context();
    let scene = canonical_scene("volume_cone");
    let n = 256u32;
    let f = render(
        &ctx,
        &scene,
        &[&format!("volume_buffer_size={n}")],
        Component::VolumeCaustics.mask(),
    );
    let segments = f.segments();
    let (transmitted, reflected) = segments.split_at((n * n) as usize);
    let lines = transmitted.iter().filter(|s| s.p1[3] > 0.0).count();
    let reflections = reflected.iter().filter(|s| s.p1[3] > 0.0).count();
    let covered = f
        .tech
        .light_views
        .gbuffer
        .front_position
        .download_rgba32f()
        .unwrap()
        .chunks(4)
        .filter(|p| p[3] >= 0.0)
        .count();
    let view = photon_view(&scene.lights[0], 0, specular_bounds(&scene).unwrap(), n).unwrap();
    let origin = Vec3::from_slice(&view.origin[..3]);
    let (right, up, forward) = (
        Vec3::from_slice(&view.right[..3]),
        Vec3::from_slice(&view.up[..3]),
        Vec3::from_slice(&view.forward[..3]),
    );
    let h = view.origin[3];
    let tris = scene.triangles(0.0);
    let bvh = Bvh::build(&tris);
    let gpu = bvh.gpu_triangles(&tris);
    let mut cast = 0usize;
    for j in 0..n {
        for i in 0..n {
            let s = (2.0 * (i as f32 + 0.5) / n as f32 - 1.0) * h;
            let t = (2.0 * (j as f32 + 0.5) / n as f32 - 1.0) * h;
            let d = (forward + s * right + t * up).normalize();
            if bvh
                .intersect(&gpu, origin, d, 0.0, f32::MAX)
                .is_some_and(|hit| {
                    let m = gpu[hit.triangle as usize].p0[3].to_bits() as usize;
                    scene.materials[m].kind != MaterialKind::Diffuse
                })
            {
                cast += 1;
            }
        }
    }
    println!("{n}² light texels: {lines} transmitted and {reflections} reflected lines, {covered} covered front texels, {cast} CPU rays meet the lens first");
    assert!(cast > 1000);
    assert_eq!(
        lines, covered,
        "every covered texel of the light view makes a line"
    );
    assert!(
        (lines as f64 - cast as f64).abs() <= 0.002 * cast as f64,
        "{lines} lines vs {cast} texels seeing the lens"
    );
    assert_validation_clean(&ctx);
}

/// For BENCHMARKS.md (scripts/bench.sh volume_lines): lines drawn, pixels
/// covered and fragments shaded on volume_cone over Hu's Table 2 sweep.
#[test]
#[ignore]
fn coverage_statistics() {
    let ctx = validated_context();
    let scene = canonical_scene("volume_cone");
    println!("| volume caustic buffer | screen | lines | covered pixels | fragments |");
    println!("| ---: | ---: | ---: | ---: | ---: |");
    for buffer in [256u32, 512, 1024] {
        for size in [256u32, 512, 1024] {
            let f = render_at(
                &ctx,
                &scene,
                &[
                    &format!("volume_buffer_size={buffer}"),
                    "photon_buffer_size=64",
                    "caustic_map_size=64",
                ],
                Component::VolumeCaustics.mask(),
                size,
            );
            let lines = f.segments().iter().filter(|s| s.p1[3] > 0.0).count();
            let volume = f.tech.rays.volume.download_rgba32f().unwrap();
            let covered = volume.chunks(4).filter(|p| p[3] > 0.0).count();
            let fragments: f64 = volume.chunks(4).map(|p| p[3] as f64).sum();
            println!("| {buffer}² | {size}x{size} | {lines} | {covered} | {fragments:.0} |");
        }
    }
    assert_validation_clean(&ctx);
}

#[test]
fn filter_radius_beyond_sixteen_steps_is_refused() {
    let ctx = validated_context();
    let scene = canonical_scene("volume_cone");
    let overrides = ["ray_step=0.01".to_string(), "filter_radius=0.5".to_string()];
    let params = VolumeLinesParams::parse("volume_lines", &overrides).unwrap();
    let scene_gpu = SceneGpu::new(&ctx, &scene, 0.0).unwrap();
    let err = match VolumeLines::new(&ctx, &params, &scene, &scene_gpu, 64, 64) {
        Ok(_) => panic!("accepted r = 50 Delta_x"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("filter_radius") && err.contains("16 x ray_step"),
        "{err}"
    );
    assert_validation_clean(&ctx);
}

/// The components add up to the frame (Hu's Fig. 2, D = A + B + C): A
/// (airlight), B (volume caustics) and C (direct and surface caustics),
/// each drawn alone, sum to everything drawn at once.
#[test]
fn components_add_up_to_the_frame() {
    let ctx = validated_context();
    let scene = canonical_scene("volume_cone");
    // Midpoint airlight samples: the same A in every render.
    let opts = [
        "volume_buffer_size=128",
        "photon_buffer_size=64",
        "airlight_jitter=0",
        "airlight_steps=16",
    ];
    let all = render(&ctx, &scene, &opts, Component::All.mask()).radiance();
    let a = render(&ctx, &scene, &opts, Component::Airlight.mask()).radiance();
    let b = render(&ctx, &scene, &opts, Component::VolumeCaustics.mask()).radiance();
    let c = render(
        &ctx,
        &scene,
        &opts,
        Component::Direct.mask() | Component::SurfaceCaustics.mask(),
    )
    .radiance();
    assert!(energy(&a) > 0.0 && energy(&b) > 0.0 && energy(&c) > 0.0);
    let mut worst = 0.0f32;
    for (((d, a), b), c) in all
        .chunks(4)
        .zip(a.chunks(4))
        .zip(b.chunks(4))
        .zip(c.chunks(4))
    {
        for k in 0..3 {
            let err = (d[k] - a[k] - b[k] - c[k]).abs() / d[k].abs().max(1e-3);
            worst = worst.max(err);
        }
    }
    println!("all vs A + B + C: worst relative difference {worst:.2e}");
    assert!(worst < 1e-4, "{worst}");
    assert_validation_clean(&ctx);
}
