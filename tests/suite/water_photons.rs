//! `water_photons` (Kougianos & Moustakas 2021) on lavapipe, validation on.
//!
//! - Algorithm 1 in the trace shader maps threads exactly as the CPU
//!   (`CascadeLayout::texel_of`).
//! - Flat water: every photon differential keeps its area (σ = 1 within
//!   1%), and the caustic on a floor parallel to the water is the analytic
//!   E cos θ_i (1 − F) (within 1% where the splats tile).
//! - A long Gerstner crest focuses: σ < 1 under the crest, matching the
//!   paraxial prediction σ = sqrt(1 − d A k² (n − 1)/n) within 5%.
//! - Through the crest's focusing, every splat mode deposits the landed
//!   photons' flux (the irradiance integrated over the floor's pixels).
//! - Water of IOR 1: the whole frame (shadowed direct light + caustic +
//!   camera refraction) gives back the `direct` frame without the water.
//! - The photon count equals a CPU replay of the trace (CPU BVH, rays from
//!   the CCM read back).
//! - A tiny photon capacity: the overflow is counted and reported, nothing
//!   is written past the capacity (guard words intact), the draw's instance
//!   count is the capacity.
//! - water_pool seen from a camera below the surface (module docs of
//!   `water_photons`): the surface-caustics energy within 4% of the
//!   reference's L S+ D component, over the pixels whose camera ray meets
//!   a diffuse surface under the water without crossing the surface. This test keeps the camera
//!   under water, where the floor is seen directly; the view from above
//!   (L S D S E, photon mapping in the reference) is tests/views.rs.
//! - Flat water seen from above: the frame's radiance on the floor is the
//!   analytic T(θ_s) T(θ_v) albedo E cos θ_s / (π n²) (GUIDE §2), on floor
//!   the camera also sees directly and on floor a near wall hides from it
//!   (seen only through the water: the water view's photon gather).
//! - A thin open wall lit on one side under the water: the caustic on the
//!   lit side is analytic, the other side (same depth) stays dark.
//! - Host memory stays flat over 60 frames (`bench --memory-samples`): no
//!   shader of the technique makes lavapipe recompile it at every bind.

use crate::common;

use caustics::frame::{FrameTargets, SceneGpu};
use caustics::gpu::GpuTriangle;
use caustics::params::{ParamSet, Params};
use caustics::scene::{MaterialKind, Scene, Water, Wave};
use caustics::shader_bindings as b;
use caustics::techniques::water_photons::cascades::CascadeLayout;
use caustics::techniques::water_photons::{
    GpuWaterPhoton, WaterPhotons, WaterPhotonsParams, GUARD_PHOTONS, GUARD_WORD,
};
use caustics::techniques::Technique;
use caustics::vk::{
    Buffer, BufferUsage, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout, Profiler,
};
use common::*;
use glam::{Vec2, Vec3};
use std::sync::Arc;

const SIZE: u32 = 128;

struct Run {
    technique: WaterPhotons,
    scene_gpu: SceneGpu,
    /// The frame targets the technique records into.
    targets: FrameTargets,
}

fn render(ctx: &Arc<Context>, scene: &Scene, overrides: &[&str], size: u32) -> Run {
    render_at(ctx, scene, overrides, size, 0.0)
}

/// One frame with the geometry (and the GPU water surface) at `time`.
fn render_at(ctx: &Arc<Context>, scene: &Scene, overrides: &[&str], size: u32, time: f32) -> Run {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let params = WaterPhotonsParams::parse("water_photons", &overrides).unwrap();
    let scene_gpu = SceneGpu::new(ctx, scene, time).unwrap();
    scene_gpu.update_frame(scene, size, size, time, 0).unwrap();
    let targets = FrameTargets::new(ctx, size, size).unwrap();
    let mut technique = WaterPhotons::new(ctx, &params, scene, &scene_gpu, size, size).unwrap();
    let profiler = Profiler::new(ctx, 32).unwrap();
    profiler
        .frame(|rec| technique.record(rec, &scene_gpu, &targets))
        .unwrap();
    Run {
        technique,
        scene_gpu,
        targets,
    }
}

fn photons(run: &Run) -> Vec<GpuWaterPhoton> {
    let counts = run.technique.photon_counts().unwrap();
    let all: Vec<GpuWaterPhoton> = run.technique.trace.photons.download_pod().unwrap();
    all[..counts.written as usize].to_vec()
}

fn water(size: Vec2, resolution: [u32; 2], base_height: f32, waves: Vec<Wave>) -> Water {
    Water {
        center: Vec2::ZERO,
        size,
        resolution,
        base_height,
        material: 1,
        waves,
    }
}

/// A 40 m floor at y = 0 (material 0), water (material 1, IOR 1.33) above.
fn water_scene(water: Water, light_dir: Vec3, eye: Vec3) -> Scene {
    let mut w = object("water", water.mesh(0.0));
    w.water = Some(water);
    scene(
        camera(eye, Vec3::ZERO, 50.0),
        vec![directional_light(light_dir, 1000.0)],
        vec![diffuse("floor", 0.8), dielectric("water", 1.33)],
        vec![object("floor", floor_mesh(20.0, 0.0, 0)), w],
    )
}

#[test]
fn algorithm_1_on_the_gpu_matches_the_cpu() {
    let ctx = validated_context();
    let set_layout =
        DescriptorSetLayout::of_shaders(&ctx, 0, &["tests/ccm_distribution.comp"]).unwrap();
    let pipeline =
        ComputePipeline::new(&ctx, "tests/ccm_distribution.comp", &[&set_layout], 32).unwrap();
    for (size, levels, scale) in [
        ([64, 64], 1, 2.0),
        ([64, 64], 4, 2.0),
        ([128, 128], 3, 4.0),
        ([60, 34], 3, 3.0),
        ([7, 6], 2, 2.0),
        ([257, 129], 2, 1.7),
    ] {
        let layout = CascadeLayout::new(size, levels, scale).unwrap();
        // A few threads past the end too: they must map to nothing.
        let threads = layout.total_threads() as u32 + 70;
        let results =
            Buffer::new(&ctx, "probe", threads as u64 * 16, BufferUsage::Storage).unwrap();
        let set = DescriptorSet::new(&ctx, &set_layout).unwrap();
        set.write_buffer(b::PROBE_BINDING_RESULTS, &results);
        let push: [u32; 8] = [
            size[0],
            size[1],
            levels,
            threads,
            layout.border[0],
            layout.border[1],
            0,
            0,
        ];
        ctx.submit_commands_and_wait(|c| {
            c.dispatch(
                &pipeline,
                &[&set],
                bytemuck::bytes_of(&push),
                [threads.div_ceil(64), 1, 1],
            )
        })
        .unwrap();
        let gpu: Vec<[u32; 4]> = results.download_pod().unwrap();
        for (thread, g) in gpu.iter().enumerate().take(threads as usize) {
            let cpu = layout
                .texel_of(thread as u64)
                .map(|([x, y], c)| [x, y, c, 1])
                .unwrap_or([0; 4]);
            assert_eq!(*g, cpu, "{layout:?}: thread {thread}");
        }
    }
    assert_validation_clean(&ctx);
}

/// Flat water, N = 1, 2, 3 cascades (s = 2): the floor's caustic is uniform
/// across the cascades' seams (the box splats of the ring tile with the
/// finer cascade's), and a photon of cascade c carries s^(2c) times the flux
/// of one of cascade 0 (Eq. 7).
#[test]
fn flat_water_gives_a_uniform_caustic() {
    let ctx = validated_context();
    let light = Vec3::new(0.3, -1.0, 0.2).normalize();
    let s = water_scene(
        water(Vec2::new(4.0, 4.0), [16, 16], 1.0, vec![]),
        light,
        Vec3::new(0.0, 1.0, 0.0) - light * 5.0,
    );
    // E = E_light cos θ_i (1 − F) on the floor, away from the beam's edges.
    let cos_i = -light.y as f64;
    let eta = 1.0 / 1.33f64;
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    let cos_t = (1.0 - sin_t2).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let f = 0.5 * (rs * rs + rp * rp);
    let expected = 1000.0 * cos_i * (1.0 - f);
    // Where the refracted beam's centre lands: the water's centre moved along the refracted ray.
    let t_dir = {
        let l = light.as_dvec3();
        let n = glam::DVec3::Y;
        (eta * l + (eta * cos_i - cos_t) * n).normalize()
    };
    let centre = (glam::DVec3::new(0.0, 1.0, 0.0) + t_dir * (1.0 / -t_dir.y)).as_vec3();
    for cascades in [1u32, 2, 3] {
        let run = render(
            &ctx,
            &s,
            &["ccm_size=64", &format!("cascades={cascades}")],
            SIZE,
        );
        let p = photons(&run);
        let refracted: Vec<_> = p
            .iter()
            .filter(|p| {
                p.axis_u[3]
                    == caustics::techniques::water_photons::bindings::WP_RAY_REFRACTED as f32
            })
            .collect();
        assert!(
            refracted.len() > 1000,
            "{} refracted photons",
            refracted.len()
        );
        let (lo, hi) = refracted.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| {
            (lo.min(p.normal[3]), hi.max(p.normal[3]))
        });
        println!(
            "flat water, N = {cascades}: {} refracted photons, σ in [{lo:.5}, {hi:.5}]",
            refracted.len()
        );
        assert!(
            (lo - 1.0).abs() < 0.01 && (hi - 1.0).abs() < 0.01,
            "σ in [{lo}, {hi}]"
        );
        // Reflected photons leave upward: nothing above to land on.
        assert_eq!(refracted.len(), p.len());
        // Eq. 7 on the GPU: every photon of cascade c has s^(2c) = 4^c
        // times cascade 0's flux (flat water: same Fresnel everywhere).
        let phi0 = refracted
            .iter()
            .find(|p| p.position[3] == 0.0)
            .expect("a photon of cascade 0")
            .flux[0] as f64;
        for c in 0..cascades {
            let of_c: Vec<_> = refracted
                .iter()
                .filter(|p| p.position[3] == c as f32)
                .collect();
            assert!(!of_c.is_empty(), "no photon of cascade {c}");
            let worst = of_c
                .iter()
                .map(|p| (p.flux[0] as f64 / (phi0 * 4f64.powi(c as i32)) - 1.0).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-4, "cascade {c}: flux ratio off 4^c by {worst}");
        }
        let caustics = run.technique.splat.caustics.download_rgba32f().unwrap();
        let position = run
            .technique
            .surface
            .gbuffer()
            .position
            .download_rgba32f()
            .unwrap();
        let (mut n, mut worst) = (0, 0.0f64);
        for i in 0..(SIZE * SIZE) as usize {
            let x = Vec3::from_slice(&position[4 * i..4 * i + 3]);
            if position[4 * i + 3] == 0.0 || x.y.abs() > 1e-3 {
                continue;
            }
            let d = x - centre;
            if d.x.abs() > 1.5 || d.z.abs() > 1.5 {
                continue;
            }
            let e = caustics[4 * i] as f64;
            worst = worst.max((e - expected).abs() / expected);
            n += 1;
        }
        println!(
            "flat water, N = {cascades}: {n} floor pixels, E expected {expected:.3} W/m², worst relative error {worst:.5}"
        );
        assert!(n > 500, "{n} pixels checked");
        assert!(worst < 0.01, "N = {cascades}: worst relative error {worst}");
    }
    assert_validation_clean(&ctx);
}

/// The focusing scene: an 8 x 2 m strip of water at 2 m over the floor,
/// one long wave along x (A = 0.3 m, λ = 4 m, no steepness), the sun
/// straight down.
const CREST_A: f32 = 0.3;
const CREST_LAMBDA: f32 = 4.0;
const CREST_BASE: f32 = 2.0;

fn crest_scene() -> Scene {
    let wave = Wave {
        amplitude: CREST_A,
        wavelength: CREST_LAMBDA,
        direction_deg: 0.0,
        steepness: 0.0,
        speed: 0.0,
        phase: 0.0,
    };
    water_scene(
        water(Vec2::new(8.0, 2.0), [256, 8], CREST_BASE, vec![wave]),
        Vec3::NEG_Y,
        Vec3::new(0.5, 8.0, 3.0),
    )
}

#[test]
fn a_crest_focuses_as_a_lens() {
    let ctx = validated_context();
    let run = render(&ctx, &crest_scene(), &["ccm_size=128", "cascades=1"], SIZE);
    let p = photons(&run);
    let refracted: Vec<_> = p
        .iter()
        .filter(|p| {
            p.axis_u[3] == caustics::techniques::water_photons::bindings::WP_RAY_REFRACTED as f32
        })
        .collect();
    // Paraxial: under the crest (slope 0, curvature κ = A k²) a ray at
    // offset δ leaves tilted by (1 − 1/n) κ δ toward the axis, so after the
    // depth d to the floor the strip δ shrinks to δ (1 − d κ (n − 1)/n);
    // along the crest nothing changes, so σ² = A'/A is that factor.
    let k = std::f32::consts::TAU / CREST_LAMBDA;
    let d = CREST_BASE + CREST_A;
    let n = 1.33;
    let predicted = (1.0 - d * CREST_A * k * k * (n - 1.0) / n).sqrt();
    let min = refracted
        .iter()
        .map(|p| p.normal[3])
        .fold(f32::MAX, f32::min);
    let max = refracted
        .iter()
        .map(|p| p.normal[3])
        .fold(f32::MIN, f32::max);
    println!(
        "crest: {} refracted photons, σ in [{min:.4}, {max:.4}], paraxial crest σ {predicted:.4}",
        refracted.len()
    );
    assert!(
        (min - predicted).abs() < 0.05 * predicted,
        "min σ {min}, predicted {predicted}"
    );
    // Troughs spread the light.
    assert!(max > 1.1, "max σ {max}");
    // The crests: sin(k x) = 1 at x = 1 and x = −3.
    for p in refracted.iter().filter(|p| p.normal[3] < 0.85) {
        let x = p.position[0];
        assert!(
            (x - 1.0).abs() < 0.8 || (x + 3.0).abs() < 0.8,
            "focused photon (σ {}) at x = {x}, not under a crest",
            p.normal[3]
        );
    }
    assert_validation_clean(&ctx);
}

fn offset(x: Vec3, n: Vec3) -> Vec3 {
    x + n * (1e-4 * x.abs().max_element().max(1.0))
}

/// The trace replayed on the CPU: rays from the CCM texels read back
/// (Algorithm 1's threads), the CPU BVH, the same acceptance (water texel
/// with a neighbour along each axis, lit, front face of a diffuse receiver).
fn cpu_photon_count(run: &Run, s: &Scene, time: f32) -> u64 {
    let tech = &run.technique;
    let layout = tech.frame.layout;
    let [w, h] = layout.size;
    let read = |img: &caustics::vk::Image| -> Vec<Vec<f32>> {
        (0..layout.levels)
            .map(|c| img.download_layer_rgba32f(c).unwrap())
            .collect()
    };
    let (pos, nrm) = (read(&tech.ccm.position), read(&tech.ccm.normal));
    let fetch = |x: i64, y: i64, c: usize| -> Option<(Vec3, Vec3)> {
        if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
            return None;
        }
        let i = 4 * (y as usize * w as usize + x as usize);
        (pos[c][i + 3] != 0.0).then(|| {
            (
                Vec3::from_slice(&pos[c][i..i + 3]),
                Vec3::from_slice(&nrm[c][i..i + 3]).normalize(),
            )
        })
    };
    let bvh = run.scene_gpu.bvh();
    let tris: Vec<GpuTriangle> = SceneGpu::gpu_triangles(s, bvh, &s.triangles(time));
    let l = s.lights[0].direction.normalize();
    let water = s.objects.iter().find_map(|o| o.water.as_ref()).unwrap();
    let eta = 1.0 / s.materials[water.material as usize].ior;
    let mut count = 0;
    for thread in 0..layout.total_threads() {
        let ([x, y], c) = layout.texel_of(thread).unwrap();
        let (x, y, c) = (x as i64, y as i64, c as usize);
        let Some((x00, n00)) = fetch(x, y, c) else {
            continue;
        };
        let has_u = fetch(x + 1, y, c).or_else(|| fetch(x - 1, y, c)).is_some();
        let has_v = fetch(x, y + 1, c).or_else(|| fetch(x, y - 1, c)).is_some();
        if !has_u || !has_v || bvh.occluded(&tris, offset(x00, -l), -l, 0.0, 1e30) {
            continue;
        }
        let n = if l.dot(n00) < 0.0 { n00 } else { -n00 };
        let cos_i = -l.dot(n);
        let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
        let refracted = (eta * l + (eta * cos_i - (1.0 - sin2_t).sqrt()) * n).normalize();
        for (dir, side) in [(l - 2.0 * l.dot(n) * n, n), (refracted, -n)] {
            let origin = offset(x00, side);
            let Some(hit) = bvh.intersect(&tris, origin, dir, 0.0, 1e30) else {
                continue;
            };
            let t = tris[hit.triangle as usize];
            let m = t.p0[3].to_bits() as usize;
            if s.materials[m].kind != MaterialKind::Diffuse {
                continue;
            }
            // Diffuse surfaces are two-sided (either face takes photons).
            count += 1;
        }
    }
    count
}

fn pool() -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/water_pool.toml");
    Scene::load(&path).unwrap()
}

#[test]
fn photon_count_matches_a_cpu_replay() {
    let ctx = validated_context();
    let s = pool();
    // At t = 1.3 s: the GPU-evaluated surface the CCM holds and the CPU
    // tessellation the BVH holds move together.
    let run = render_at(&ctx, &s, &["ccm_size=96", "cascades=2"], 64, 1.3);
    let counts = run.technique.photon_counts().unwrap();
    let cpu = cpu_photon_count(&run, &s, 1.3);
    println!("water_pool: GPU {counts:?}, CPU replay {cpu}");
    assert_eq!(counts.overflow(), 0);
    // Rays grazing a triangle edge may fall either way between the two
    // traversals' roundings: a handful at most.
    let diff = (counts.written as i64 - cpu as i64).unsigned_abs();
    assert!(cpu > 3000, "{cpu} photons");
    assert!(
        diff <= 2 + cpu / 2000,
        "GPU {} vs CPU {cpu}",
        counts.written
    );
    assert_validation_clean(&ctx);
}

#[test]
fn overflow_is_counted_and_nothing_is_written_past_the_buffer() {
    let ctx = validated_context();
    let light = Vec3::new(0.3, -1.0, 0.2).normalize();
    let s = water_scene(
        water(Vec2::new(4.0, 4.0), [16, 16], 1.0, vec![]),
        light,
        Vec3::new(0.0, 1.0, 0.0) - light * 5.0,
    );
    let run = render(
        &ctx,
        &s,
        &["ccm_size=64", "cascades=1", "photon_capacity=100"],
        64,
    );
    let counts = run.technique.photon_counts().unwrap();
    println!("tiny buffer: {counts:?}");
    assert_eq!(counts.capacity, 100);
    assert_eq!(counts.written, 100);
    assert!(counts.requested > 3000, "{counts:?}");
    assert_eq!(counts.overflow(), counts.requested - 100);
    let words: Vec<u32> = run.technique.trace.photons.download_pod().unwrap();
    let per = std::mem::size_of::<GpuWaterPhoton>() / 4;
    assert_eq!(words.len(), (100 + GUARD_PHOTONS as usize) * per);
    assert!(
        words[100 * per..].iter().all(|&w| w == GUARD_WORD),
        "guard overwritten"
    );
    assert!(
        words[..100 * per].iter().all(|&w| w != GUARD_WORD),
        "a slot left unwritten"
    );
    // The draw's instance count is what was written.
    let draw: Vec<u32> = run.technique.trace.draw.download_pod().unwrap();
    assert_eq!(&draw[..5], &[4, 100, 0, 0, counts.requested]);
    assert_validation_clean(&ctx);
}

/// rgb summed over the pixels where `mask` holds.
fn masked_energy(img: &[f32], mask: &[bool]) -> f64 {
    img.chunks(4)
        .zip(mask)
        .filter(|(_, &m)| m)
        .map(|(p, _)| (p[0] + p[1] + p[2]) as f64)
        .sum()
}

/// One `water_photons` frame of `s` with `overrides`, surface caustics
/// only: the radiance and the trace + splat time (ms, wall clock on lavapipe).
/// The surface-caustics component of one frame, with the trace + splat
/// milliseconds and the denoise milliseconds of the second (timed) frame.
fn caustic_frame(ctx: &Arc<Context>, s: Scene, overrides: &[&str]) -> (Vec<f32>, f64, f64) {
    use caustics::radiometry::Component;
    use caustics::renderer::Renderer;
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let params = Params::resolve("water_photons", WaterPhotonsParams::specs(), &overrides).unwrap();
    let mut r = Renderer::new(ctx, s, "water_photons", &params, SIZE, SIZE, 0.0).unwrap();
    r.scene_gpu.components = Component::SurfaceCaustics.mask();
    // The second frame is timed: the first pays the pipelines' compilation.
    r.render_frame(0.0).unwrap();
    let timings = r.render_frame(0.0).unwrap();
    let ms = timings
        .iter()
        .filter(|t| t.name == "photon trace" || t.name == "photon splat")
        .map(|t| t.ms)
        .sum();
    let denoise_ms = timings
        .iter()
        .filter(|t| t.name.starts_with("denoise "))
        .map(|t| t.ms)
        .sum();
    let img = r.radiance().unwrap();
    assert_finite(&img);
    (img, ms, denoise_ms)
}

/// FLIP mean over the pixels where `mask` holds.
fn masked_flip_mean(map: &caustics::compare::metrics::FlipMap, mask: &[bool]) -> f64 {
    let v = map.values();
    let (sum, n) = v
        .iter()
        .zip(mask)
        .filter(|(_, &m)| m)
        .fold((0.0, 0), |(s, n), (e, _)| (s + *e as f64, n + 1));
    sum / n as f64
}

/// water_pool from a camera under the surface (module docs): the default
/// settings against the reference's L S+ D component over the pixels that
/// see a diffuse surface under the water directly (energy within 4%,
/// FLIP bounded); then the paper's two claims at lavapipe sizes, whose
/// numbers BENCHMARKS.md records: (i) 2 cascades over the range r vs 1
/// cascade over 2r (both at the same ccm_0: the defaults with `cascades`
/// 2 and 1), FLIP over the inner cascade's region; (ii) photon
/// differentials at ccm_0 = 128 vs fixed splats at 256, both undenoised
/// (the paper's Fig. 10); (iii) one adaptive denoise pass vs ten
/// fixed-radius passes on the same frame: FLIP between the two and the
/// time ratio. Every variant keeps the energy within 4%.
#[test]
fn pool_caustics_from_below_match_the_reference() {
    use caustics::reference::Component;
    use caustics::techniques::water_photons::CascadeFrame;
    let ctx = validated_context();
    let below = || {
        let mut s = pool();
        // Under the surface (1.2 m), looking down the pool at the floor.
        s.camera = camera(Vec3::new(0.5, 0.9, 2.6), Vec3::new(-0.3, 0.0, -1.0), 60.0);
        s
    };
    let truth = traced_reference(&ctx, &below(), SIZE, 4_000_000)
        .whole(Component::SurfaceCaustics)
        .to_vec();
    let truth_ldr = tonemap(&scaled(&truth));

    // The compared pixels: those whose first hit is a diffuse surface
    // below the water plane (reached without crossing the water; a pixel
    // whose ray crosses the surface sees through it, an L S D S E path
    // compared in tests/views.rs); and of those, the
    // inner cascade's region of the 2-cascade default.
    let s = below();
    let w = s.objects.iter().find_map(|o| o.water.clone()).unwrap();
    let layout = CascadeLayout::new([128, 128], 2, 2.0).unwrap();
    let frame = CascadeFrame::new(&w, s.camera.eye, s.lights[0].direction, layout, 0.0);
    let inner = frame.view_proj(0);
    let tris = s.triangles(0.0);
    let bvh = caustics::bvh::Bvh::build(&tris);
    let gpu = bvh.gpu_triangles(&tris);
    let (mut compared, mut near) = (Vec::new(), Vec::new());
    for py in 0..SIZE {
        for px in 0..SIZE {
            let (o, d) = pixel_ray(&s.camera, SIZE, SIZE, px, py);
            let hit = bvh.intersect(&gpu, o, d, 0.0, f32::MAX).map(|h| {
                let material = gpu[h.triangle as usize].p0[3].to_bits() as usize;
                (o + d * h.t, s.materials[material].kind)
            });
            let diffuse_below =
                hit.is_some_and(|(x, kind)| kind == MaterialKind::Diffuse && x.y < w.base_height);
            compared.push(diffuse_below);
            near.push(
                diffuse_below && {
                    let ndc = inner.project_point3(hit.unwrap().0);
                    ndc.x.abs() < 1.0 && ndc.y.abs() < 1.0
                },
            );
        }
    }
    let e_truth = masked_energy(&truth, &compared);
    println!(
        "pool from below: {} of {} pixels compared, {} in the inner cascade's region",
        compared.iter().filter(|&&m| m).count(),
        compared.len(),
        near.iter().filter(|&&m| m).count()
    );

    let variants: [(&str, &[&str]); 8] = [
        (
            "default (ccm 256, N 2, adaptive denoise)",
            &["ccm_size=256"],
        ),
        (
            "(i) N 2 over r, ccm 128",
            &["ccm_size=128", "cascades=2", "denoise=0"],
        ),
        (
            "(i) N 1 over 2r, ccm 128",
            &["ccm_size=128", "cascades=1", "denoise=0"],
        ),
        (
            "(ii) differentials, ccm 128, N 1",
            &["ccm_size=128", "cascades=1", "splat_mode=0", "denoise=0"],
        ),
        (
            "(ii) fixed splats, ccm 256, N 1",
            &["ccm_size=256", "cascades=1", "splat_mode=2", "denoise=0"],
        ),
        (
            "(ii) differentials, ccm 256, N 1",
            &["ccm_size=256", "cascades=1", "splat_mode=0", "denoise=0"],
        ),
        (
            "(iii) 1 adaptive denoise pass, ccm 128",
            &["ccm_size=128", "denoise=1", "denoise_passes=1"],
        ),
        (
            "(iii) 10 fixed-radius denoise passes, ccm 128",
            &["ccm_size=128", "denoise=2", "denoise_passes=10"],
        ),
    ];
    let mut flips = Vec::new();
    let mut denoised = Vec::new();
    for (i, (name, overrides)) in variants.iter().enumerate() {
        let (img, ms, denoise_ms) = caustic_frame(&ctx, below(), overrides);
        let e = masked_energy(&img, &compared);
        let rel = (e - e_truth) / e_truth;
        let ldr = tonemap(&scaled(&img));
        let (_, flip_map) = flip(&ldr, &truth_ldr, SIZE);
        let flip_mean = masked_flip_mean(&flip_map, &compared);
        let flip_near = masked_flip_mean(&flip_map, &near);
        println!(
            "pool from below, {name}: L S D energy relative {rel:+.4}; FLIP mean {flip_mean:.4}, inner cascade region {flip_near:.4}; trace + splat {ms:.1} ms, denoise {denoise_ms:.1} ms"
        );
        let dir = write_comparison_pngs(
            &format!("water_photons_pool_below_{i}"),
            SIZE,
            &ldr,
            &truth_ldr,
            &flip_map,
        );
        // Measured −1.54% to −0.25% over the variants; bound 2.5x the worst.
        assert!(
            rel.abs() < 0.04,
            "{name}: relative energy {rel:+.4} (images in {dir})"
        );
        flips.push((flip_mean, flip_near));
        denoised.push((ldr, denoise_ms));
    }
    // Claim (iii): one adaptive pass against ten fixed-radius passes.
    let (adaptive, fixed) = (&denoised[6], &denoised[7]);
    let (flip_between, _) = flip(&adaptive.0, &fixed.0, SIZE);
    println!(
        "(iii) 1 adaptive vs 10 fixed-radius denoise passes: FLIP between them {flip_between:.4}; time {:.2} ms vs {:.2} ms, ratio {:.2}",
        adaptive.1,
        fixed.1,
        fixed.1 / adaptive.1
    );
    // Measured 0.0269 (lavapipe, 128²): the two look alike, as the paper
    // finds (its Fig. 12); bound about 2x. The time ratio is a benchmark
    // (BENCHMARKS.md), not asserted.
    assert!(
        flip_between < 0.045,
        "1 adaptive vs 10 fixed passes: FLIP {flip_between:.4}"
    );
    // Over the compared pixels: measured 0.0942 with the default adaptive
    // denoise pass (lavapipe; most of it the reference's own noise at 4M
    // photons); bound 1.25x.
    assert!(flips[0].0 < 0.118, "FLIP mean {:.4}", flips[0].0);
    // Claim (i): the finer inner cascade is closer to the truth where it
    // reaches (measured 0.1013 vs 0.1261).
    assert!(
        flips[1].1 < flips[2].1,
        "inner-region FLIP: 2 cascades {:.4}, 1 cascade {:.4}",
        flips[1].1,
        flips[2].1
    );
    assert_validation_clean(&ctx);
}

/// The pool's exposure (assets/scenes/water_pool.toml) before the test tonemap.
fn scaled(img: &[f32]) -> Vec<f32> {
    img.iter().map(|v| v * 0.004).collect()
}

/// Mean and worst relative deviation from `expected` of the caustic
/// irradiance on floor pixels within `half` m of the refracted beam's centre.
fn floor_irradiance(run: &Run, centre: Vec3, half: f32, expected: f64) -> (f64, f64, usize) {
    let caustics = run.technique.splat.caustics.download_rgba32f().unwrap();
    let position = run
        .technique
        .surface
        .gbuffer()
        .position
        .download_rgba32f()
        .unwrap();
    let (mut sum, mut worst, mut n) = (0.0, 0.0f64, 0);
    for i in 0..position.len() / 4 {
        let x = Vec3::from_slice(&position[4 * i..4 * i + 3]);
        let d = x - centre;
        if position[4 * i + 3] == 0.0 || x.y.abs() > 1e-3 || d.x.abs() > half || d.z.abs() > half {
            continue;
        }
        let e = caustics[4 * i] as f64;
        sum += e;
        worst = worst.max((e - expected).abs() / expected);
        n += 1;
    }
    (sum / n as f64 / expected - 1.0, worst, n)
}

#[test]
fn paper_splats_and_intensity() {
    let ctx = validated_context();
    // Straight down: Eq. 19's a = 1 and the quads tile the floor's grid.
    let s = water_scene(
        water(Vec2::new(4.0, 4.0), [16, 16], 1.0, vec![]),
        Vec3::NEG_Y,
        Vec3::new(0.0, 5.0, 2.0),
    );
    let f = {
        let r = (1.0 - 1.33f64) / (1.0 + 1.33);
        r * r
    };
    let expected = 1000.0 * (1.0 - f);
    // Splats of Eqs. 16-19, with σ (mode 1) or fixed (mode 2): q_0 = 1 boxes
    // on the texel lattice tile exactly, so both give E (1 − F) inside.
    for mode in [1, 2] {
        let run = render(
            &ctx,
            &s,
            &["ccm_size=64", "cascades=1", &format!("splat_mode={mode}")],
            SIZE,
        );
        let (mean, worst, n) = floor_irradiance(&run, Vec3::ZERO, 1.5, expected);
        println!("splat_mode={mode}: {n} pixels, mean {mean:+.5}, worst {worst:.5}");
        assert!(
            n > 500 && mean.abs() < 0.01 && worst < 0.02,
            "splat_mode={mode}"
        );
    }
    // Paper intensity: R = L I_att F (Eqs. 12-15) per photon.
    let run = render(
        &ctx,
        &s,
        &[
            "ccm_size=64",
            "cascades=1",
            "intensity_mode=1",
            "attenuation_t_max=10",
        ],
        SIZE,
    );
    let frame = run.technique.frame;
    let texel = frame.range.width * frame.range.height / (64.0 * 64.0);
    let (gamma, t_max, f_frac, f_exp) = (0.95f32, 10.0f32, 0.02f32, 5.0f32);
    let p = photons(&run);
    assert!(p.len() > 1000);
    for p in &p {
        let t = p.axis_v[3];
        let u = 1.0 - t / t_max;
        let i_att = if u > gamma {
            1.0 - (u - gamma) / (1.0 - gamma)
        } else {
            1.0 - (gamma - u) / gamma
        };
        // Straight down onto flat water: −l·n = 1, F_refl = F_frac.
        let f_refl = f_frac + (1.0 - f_frac) * 0.0f32.powf(f_exp);
        let r = 1000.0 * texel * i_att * (1.0 - f_refl);
        assert!(
            (p.flux[0] - r).abs() <= 1e-4 * r,
            "photon at t' = {t}: R {} vs Eq. 12 {r}",
            p.flux[0]
        );
    }
    // The floor lies 1 m under the water: with t_max = 0.5 m the rays end
    // before it (the paper's TMax), so nothing lands and nothing is
    // negative (Eq. 13 as printed is negative past t_max).
    let run = render(
        &ctx,
        &s,
        &[
            "ccm_size=64",
            "cascades=1",
            "intensity_mode=1",
            "attenuation_t_max=0.5",
        ],
        SIZE,
    );
    let p = photons(&run);
    let caustics = run.technique.splat.caustics.download_rgba32f().unwrap();
    let negative = caustics.iter().filter(|v| **v < 0.0).count();
    let lit = caustics.iter().filter(|v| **v > 0.0).count();
    println!(
        "t_max below the floor: {} photons, {negative} negative and {lit} positive values",
        p.len()
    );
    assert!(p.is_empty(), "{} photons beyond t_max", p.len());
    assert_eq!((negative, lit), (0, 0));
    assert_validation_clean(&ctx);
}

/// `caustics render --technique water_photons` on a scene it cannot render,
/// or with a bad parameter: a message naming the cause, exit code 1.
#[test]
fn unusable_scenes_and_parameters_are_refused() {
    let run = |scene: &str, params: &[&str]| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_caustics"));
        c.env(
            "VK_DRIVER_FILES",
            "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json",
        )
        .args([
            "render",
            "--technique",
            "water_photons",
            "--width",
            "32",
            "--height",
            "32",
        ])
        .args(["--scene", scene, "--out"])
        .arg(std::env::temp_dir().join("water_photons_refused.png"));
        for p in params {
            c.args(["--param", p]);
        }
        let out = c.output().unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).to_string(),
        )
    };
    let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    // ball_lens: no water, and a point light.
    let (code, err) = run(assets.join("ball_lens.toml").to_str().unwrap(), &[]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("water_photons needs a `water` object"),
        "{err}"
    );
    let pool = assets.join("water_pool.toml");
    let (code, err) = run(pool.to_str().unwrap(), &["cascades=5"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("--param cascades=5: must be a whole number in [1, 4]"),
        "{err}"
    );
    let (code, err) = run(pool.to_str().unwrap(), &["photon_capacity=33554432"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("the device binds at most"), "{err}");
    let (code, err) = run(
        pool.to_str().unwrap(),
        &["cascade_scale=1.01", "ccm_size=16"],
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("cascade_scale"), "{err}");

    // Water under a point light only.
    let ctx = validated_context();
    let mut s = water_scene(
        water(Vec2::new(4.0, 4.0), [4, 4], 1.0, vec![]),
        Vec3::NEG_Y,
        Vec3::new(0.0, 5.0, 2.0),
    );
    s.lights = vec![point_light(Vec3::new(0.0, 5.0, 0.0), 100.0)];
    let params = WaterPhotonsParams::default();
    let scene_gpu = SceneGpu::new(&ctx, &s, 0.0).unwrap();
    let err = WaterPhotons::new(&ctx, &params, &s, &scene_gpu, 32, 32)
        .err()
        .expect("refused");
    assert!(
        err.to_string().contains("needs a directional light"),
        "{err}"
    );
    // A second water body or a second sun: refused, naming it.
    let check = caustics::techniques::find("water_photons")
        .unwrap()
        .check_scene;
    let mut two_waters = Scene::load(&pool).unwrap();
    let mut second = two_waters
        .objects
        .iter()
        .find(|o| o.water.is_some())
        .unwrap()
        .clone();
    second.name = "second pool".into();
    two_waters.objects.push(second);
    let err = check(&two_waters).unwrap_err().to_string();
    assert!(
        err.contains("object `second pool`: water_photons renders one water body (`water`)"),
        "{err}"
    );
    let mut two_suns = Scene::load(&pool).unwrap();
    two_suns.lights.push(two_suns.lights[0]);
    let err = check(&two_suns).unwrap_err().to_string();
    assert!(
        err.contains("light: water_photons traces the caustics of one sun, and the scene has 2 directional lights"),
        "{err}"
    );
    assert_validation_clean(&ctx);
}

/// `ccm_precision` sizes the cascades by Eq. 3 from the derived range.
#[test]
fn eq_3_sizes_the_cascades_from_the_precision() {
    let ctx = validated_context();
    let s = water_scene(
        water(Vec2::new(4.0, 4.0), [4, 4], 1.0, vec![]),
        Vec3::NEG_Y,
        Vec3::new(0.0, 5.0, 2.0),
    );
    let scene_gpu = SceneGpu::new(&ctx, &s, 0.0).unwrap();
    for (precision, cascades, size) in [(0.05, 1, 256), (0.01, 1, 1024), (0.01, 2, 512)] {
        let overrides = [
            format!("ccm_precision={precision}"),
            format!("cascades={cascades}"),
        ];
        let params = WaterPhotonsParams::parse("water_photons", &overrides).unwrap();
        let t = WaterPhotons::new(&ctx, &params, &s, &scene_gpu, 32, 32).unwrap();
        let r = t.frame.range;
        // The camera is 2 m off the water's centre along z: cascade N − 1 spans
        // 2 × (2 + 2) m (+0.1%), cascade 0 that / 2^(N − 1).
        assert!(
            (r.width - 8.008 / 2f32.powi(cascades - 1)).abs() < 1e-3,
            "{r:?}"
        );
        assert_eq!(
            t.frame.layout.size,
            [size, size],
            "p = {precision}, N = {cascades}"
        );
    }
    assert_validation_clean(&ctx);
}

/// Flux conservation through focusing: the caustic irradiance integrated
/// over the floor (pixel footprints from the G-buffer's positions) equals
/// the flux of the photons that landed there, for the differential splats
/// and both rectangle modes (each quad deposits its photon's flux, whatever
/// its size).
#[test]
fn splats_conserve_the_flux_of_a_focusing_crest() {
    let ctx = validated_context();
    let mut s = crest_scene();
    s.camera = camera(Vec3::new(0.0, 10.0, 3.0), Vec3::ZERO, 70.0);
    const PX: u32 = 256;
    for mode in [0, 1, 2] {
        let run = render(
            &ctx,
            &s,
            &["ccm_size=128", "cascades=1", &format!("splat_mode={mode}")],
            PX,
        );
        let flux: f64 = photons(&run).iter().map(|p| p.flux[0] as f64).sum();
        let e = run.technique.splat.caustics.download_rgba32f().unwrap();
        let pos = run
            .technique
            .surface
            .gbuffer()
            .position
            .download_rgba32f()
            .unwrap();
        let at = |x: u32, y: u32| {
            let i = 4 * (y * PX + x) as usize;
            (pos[i + 3] != 0.0).then(|| Vec3::from_slice(&pos[i..i + 3]))
        };
        let mut integral = 0.0f64;
        for y in 0..PX - 1 {
            for x in 0..PX - 1 {
                let (Some(p), Some(px), Some(py)) = (at(x, y), at(x + 1, y), at(x, y + 1)) else {
                    continue;
                };
                let area = (px - p).cross(py - p).length() as f64;
                integral += e[4 * (y * PX + x) as usize] as f64 * area;
            }
        }
        let rel = integral / flux - 1.0;
        println!("crest, splat_mode={mode}: photon flux {flux:.2} W, integrated irradiance {integral:.2} W ({rel:+.4})");
        assert!(rel.abs() < 0.02, "splat_mode={mode}: {rel:+.4}");
    }
    assert_validation_clean(&ctx);
}

/// Water of IOR 1 bends nothing and reflects nothing: the whole frame
/// (direct light, whose shadow maps hold the water, + the caustic the water
/// sends, seen through the surface by the camera refraction) equals the
/// `direct` frame of the scene without the water, on the floor under the
/// water's middle; with the surface-caustics component off, that floor is
/// dark (the water's shadow).
#[test]
fn ior_one_water_gives_back_the_direct_frame() {
    use caustics::radiometry::Component;
    use caustics::renderer::Renderer;
    let ctx = validated_context();
    let light = Vec3::new(0.3, -1.0, 0.2).normalize();
    let eye = Vec3::new(0.5, 5.0, 3.0);
    let mut with_water = water_scene(water(Vec2::new(4.0, 4.0), [8, 8], 1.0, vec![]), light, eye);
    with_water.materials[1].ior = 1.0;
    let mut without = with_water.clone();
    without.objects.truncate(1);
    let frame = |s: &Scene, technique: &str, overrides: &[String], mask: u32| {
        let params = Params::resolve(
            technique,
            caustics::techniques::find(technique).unwrap().params(),
            overrides,
        )
        .unwrap();
        let mut r = Renderer::new(&ctx, s.clone(), technique, &params, SIZE, SIZE, 0.0).unwrap();
        r.scene_gpu.components = mask;
        r.render_frame(0.0).unwrap();
        r.radiance().unwrap()
    };
    let ours = frame(
        &with_water,
        "water_photons",
        &["ccm_size=128".into(), "cascades=1".into()],
        Component::All.mask(),
    );
    let dark = frame(
        &with_water,
        "water_photons",
        &["ccm_size=128".into(), "cascades=1".into()],
        Component::Direct.mask(),
    );
    let truth = frame(&without, "direct", &[], Component::All.mask());
    // Floor points whose light came through the water's middle: (x, 0, z)
    // with (x, 0, z) − l t at the water's height inside ±1.2 m, found per
    // pixel by the camera ray.
    let (mut n, mut worst, mut darkest) = (0, 0.0f32, 0.0f32);
    for py in 0..SIZE {
        for px in 0..SIZE {
            let (o, d) = pixel_ray(&with_water.camera, SIZE, SIZE, px, py);
            if d.y >= 0.0 {
                continue;
            }
            let floor = o + d * (-o.y / d.y);
            let at_water = floor - light * (1.0 / -light.y);
            if at_water.x.abs() > 1.2 || at_water.z.abs() > 1.2 {
                continue;
            }
            let i = 4 * (py * SIZE + px) as usize;
            worst = worst.max((ours[i] - truth[i]).abs() / truth[i]);
            darkest = darkest.max(dark[i] / truth[i]);
            n += 1;
        }
    }
    println!("IOR 1: {n} floor pixels, worst relative difference {worst:.5}, direct-only at most {darkest:.5} of the lit floor");
    assert!(n > 1000, "{n}");
    assert!(worst < 0.01, "worst {worst}");
    assert!(darkest < 0.01, "direct only {darkest}");
    assert_validation_clean(&ctx);
}

/// Eq. 1: the light view is centred on the camera, frame by frame (the
/// camera's position lies on the light's axis through the cascades' centre).
#[test]
fn the_cascades_follow_the_camera() {
    let ctx = validated_context();
    let light = Vec3::new(0.3, -1.0, 0.2).normalize();
    let mut s = water_scene(
        water(Vec2::new(4.0, 4.0), [8, 8], 1.0, vec![]),
        light,
        Vec3::new(0.5, 5.0, 3.0),
    );
    let mut run = render(&ctx, &s, &["ccm_size=64", "cascades=2"], 64);
    let profiler = Profiler::new(&ctx, 32).unwrap();
    for eye in [Vec3::new(0.5, 5.0, 3.0), Vec3::new(-2.0, 3.0, 1.0)] {
        s.camera.eye = eye;
        run.scene_gpu.update_frame(&s, 64, 64, 0.0, 1).unwrap();
        profiler
            .frame(|rec| run.technique.record(rec, &run.scene_gpu, &run.targets))
            .unwrap();
        let local = run.technique.frame.view.transform_point3(eye);
        assert!(
            local.x.abs() < 1e-4 && local.y.abs() < 1e-4,
            "{eye}: {local}"
        );
    }
    assert_validation_clean(&ctx);
}

/// A one-frame `caustics render` whose photon buffer overflows reports it
/// (the counts are read after the frame's fence, `Technique::after_frame`),
/// still exits 0 with a valid image; `caustics bench --json` writes the
/// frame's photon counts.
#[test]
fn a_one_frame_render_reports_overflow() {
    let pool =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/water_pool.toml");
    let dir = std::env::temp_dir().join(format!("water_photons_overflow_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exr = dir.join("pool.exr");
    let json = dir.join("bench.json");
    let caustics = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_caustics"))
            .args(args)
            .args([
                "--scene",
                pool.to_str().unwrap(),
                "--technique",
                "water_photons",
            ])
            .args(["--width", "48", "--height", "48", "--validate"])
            .args(["--param", "ccm_size=64", "--param", "photon_capacity=50"])
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).to_string(),
        )
    };
    let (code, err) = caustics(&["render", "--out", exr.to_str().unwrap()]);
    println!("render stderr: {err}");
    assert_eq!(code, Some(0), "{err}");
    assert!(
        err.contains("photons did not fit the buffer of 50"),
        "no overflow warning: {err}"
    );
    assert!(!err.contains("Validation Error"), "{err}");
    let (w, h, rgba) = caustics::output::read_exr(&exr).unwrap();
    assert_eq!((w, h), (48, 48));
    assert!(rgba.iter().all(|v| v.is_finite() && *v >= 0.0));
    assert!(rgba.iter().any(|v| *v > 0.0));

    let (code, err) = caustics(&[
        "bench",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        err.contains("photons did not fit the buffer of 50"),
        "{err}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let counters = &report["counters"];
    println!("bench counters: {counters}");
    assert_eq!(counters["photon_capacity"], 50);
    assert_eq!(counters["photons_written"], 50);
    let requested = counters["photons_requested"].as_u64().unwrap();
    assert!(requested > 50, "{counters}");
    assert_eq!(
        counters["photons_overflow"].as_u64().unwrap(),
        requested - 50
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// ocean_large (400 m basin, walls 200 m away, low sun) at 96², ccm_0 128,
/// otherwise the defaults: the frame is finite and non-negative, the
/// seabed under the water carries caustics, nothing overflows, validation
/// is clean. Also measured (BENCHMARKS.md): the adaptive denoiser's energy
/// change on this frame's sparse far caustics, and the caustic energy with
/// a 10x smaller depth bias (splats leaking through occluders would lose
/// energy there).
#[test]
fn ocean_large_renders_with_caustics_on_the_seabed() {
    use caustics::radiometry::Component;
    use caustics::renderer::Renderer;
    const PX: u32 = 96;
    let ctx = validated_context();
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ocean_large.toml");
    let frame = |overrides: &[&str], components: Option<u32>| {
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        let params =
            Params::resolve("water_photons", WaterPhotonsParams::specs(), &overrides).unwrap();
        let s = Scene::load(&path).unwrap();
        let mut r = Renderer::new(&ctx, s, "water_photons", &params, PX, PX, 0.0).unwrap();
        if let Some(mask) = components {
            r.scene_gpu.components = mask;
        }
        r.render_frame(0.0).unwrap();
        let img = r.radiance().unwrap();
        let counters: std::collections::BTreeMap<_, _> =
            r.technique_counters().into_iter().collect();
        (img, counters)
    };
    let (full, counters) = frame(&["ccm_size=128"], None);
    println!("ocean_large: {counters:?}");
    assert_finite(&full);
    assert!(full.iter().all(|v| *v >= 0.0), "negative radiance");
    assert_eq!(counters["photons_overflow"], 0);
    assert!(counters["photons_written"] > 1000, "{counters:?}");
    let caustic_energy =
        |img: &[f32]| -> f64 { img.chunks(4).map(|p| (p[0] + p[1] + p[2]) as f64).sum() };
    let caustics_only = Some(Component::SurfaceCaustics.mask());
    let (caustic, _) = frame(&["ccm_size=128"], caustics_only);
    assert_finite(&caustic);
    assert!(caustic.iter().all(|v| *v >= 0.0));
    let lit = caustic.chunks(4).filter(|p| p[0] > 0.0).count();
    let e = caustic_energy(&caustic);
    println!(
        "ocean_large: surface caustics on {lit} of {} pixels, energy {e:.4}",
        PX * PX
    );
    // The camera looks across the water at the seabed: caustics on a good
    // part of the image.
    assert!(lit > (PX * PX / 10) as usize, "{lit} pixels with caustics");
    let (undenoised, _) = frame(&["ccm_size=128", "denoise=0"], caustics_only);
    let e0 = caustic_energy(&undenoised);
    println!(
        "ocean_large: adaptive denoiser energy change {:+.6} ({e:.2} vs {e0:.2} undenoised), pixels changed by > 1%: {}",
        e / e0 - 1.0,
        caustic
            .chunks(4)
            .zip(undenoised.chunks(4))
            .filter(|(a, b)| (a[0] - b[0]).abs() > 0.01 * b[0].max(1e-6))
            .count()
    );
    let (small_bias, _) = frame(&["ccm_size=128", "depth_bias=0.001"], caustics_only);
    let e_bias = caustic_energy(&small_bias);
    println!(
        "ocean_large: depth_bias 0.001 vs 0.01: caustic energy {:+.4}, pixels differing by > 1%: {}",
        e_bias / e - 1.0,
        small_bias
            .chunks(4)
            .zip(caustic.chunks(4))
            .filter(|(a, b)| (a[0] - b[0]).abs() > 0.01 * b[0].max(1e-6))
            .count()
    );
    assert_validation_clean(&ctx);
}

/// Diffuse surfaces are two-sided, as in the reference light tracer: a
/// floor facing down (normals and winding reversed, an open mesh seen from
/// behind) under flat water takes the same photons, with the same flux and
/// footprints, as the floor facing up.
#[test]
fn a_floor_facing_away_takes_the_same_photons() {
    let ctx = validated_context();
    let light = Vec3::new(0.3, -1.0, 0.2).normalize();
    let up = water_scene(
        water(Vec2::new(4.0, 4.0), [16, 16], 1.0, vec![]),
        light,
        Vec3::new(0.0, 1.0, 0.0) - light * 5.0,
    );
    let mut down = up.clone();
    let floor = down.objects.iter_mut().find(|o| o.name == "floor").unwrap();
    floor.mesh.normals = vec![Vec3::NEG_Y; 4];
    floor.mesh.indices = vec![[0, 1, 2], [0, 2, 3]];
    let overrides = ["ccm_size=64", "cascades=1"];
    let (a, b) = (
        photons(&render(&ctx, &up, &overrides, 64)),
        photons(&render(&ctx, &down, &overrides, 64)),
    );
    let flux = |p: &[GpuWaterPhoton]| p.iter().map(|p| p.flux[0] as f64).sum::<f64>();
    println!(
        "floor up: {} photons, {:.3} W; floor facing away: {} photons, {:.3} W",
        a.len(),
        flux(&a),
        b.len(),
        flux(&b)
    );
    assert!(a.len() > 1000);
    assert_eq!(a.len(), b.len());
    assert!((flux(&a) - flux(&b)).abs() <= 1e-5 * flux(&a));
    // Same receiver normal (facing the ray) and footprint: the photons
    // differ by order only.
    let key = |p: &GpuWaterPhoton| {
        (
            (p.position[0] * 1e4).round() as i64,
            (p.position[2] * 1e4).round() as i64,
        )
    };
    let mut a = a;
    let mut b = b;
    a.sort_by_key(key);
    b.sort_by_key(key);
    for (p, q) in a.iter().zip(&b) {
        assert_eq!(p.normal[1], q.normal[1]);
        assert!((p.normal[3] - q.normal[3]).abs() < 1e-4);
    }
    assert_validation_clean(&ctx);
}

/// Exact unpolarised Fresnel transmittance 1 − F from air into a medium of
/// index `n` at incidence cos θ = `cos_i`.
fn fresnel_transmittance(cos_i: f64, n: f64) -> f64 {
    let eta = 1.0 / n;
    let cos_t = (1.0 - eta * eta * (1.0 - cos_i * cos_i)).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    1.0 - 0.5 * (rs * rs + rp * rp)
}

/// Flat, non-absorbing water (n = 1.33) over a diffuse floor under the sun,
/// seen from above (GUIDE §2): on every floor pixel the camera sees through
/// the water, the frame's radiance is
///   L = T(θ_s) T(θ_v) albedo E cos θ_s / (π n²),
/// T the Fresnel transmittance at the sun's and the view's zenith angle
/// (the photon's flux through the surface, then the radiance leaving it)
/// and 1/n² the radiance law across the interface. The reflected sky is
/// black, so nothing else adds. A wall at the water's near edge (as the
/// pool's) hides from the camera a strip of floor that it sees through the
/// water (the refracted ray bends down behind the wall's edge): those
/// pixels ("hidden") are shaded by the water view's own photon gather,
/// the others ("visible") read the splatted frame; both must give L.
/// Pixels are those whose refracted camera ray meets the floor inside the
/// uniformly lit square (away from the beam's edges and the wall).
#[test]
fn flat_water_seen_from_above_has_the_analytic_radiance() {
    use caustics::reference::Component;
    use caustics::renderer::Renderer;
    use glam::DVec3;
    const N: u32 = 64;
    let ctx = validated_context();
    let light = Vec3::new(0.3, -1.0, 0.2).normalize();
    let mut s = water_scene(
        water(Vec2::new(6.0, 6.0), [12, 12], 1.0, vec![]),
        light,
        Vec3::new(0.3, 4.0, 5.5),
    );
    s.camera.target = Vec3::new(0.3, 0.0, 0.5);
    let (wall_lo, wall_hi) = (Vec3::new(-3.3, 0.0, 3.0), Vec3::new(3.3, 1.3, 3.3));
    // A darker wall than the floor: a pixel that shows the wall's top in
    // place of the hidden floor is off by far more than the bounds.
    s.materials.push(diffuse("wall", 0.3));
    s.objects
        .push(object("near wall", box_mesh(wall_lo, wall_hi, 2)));
    let (wall_lo, wall_hi) = (wall_lo.as_dvec3(), wall_hi.as_dvec3());
    let ior = 1.33f64;
    let albedo = 0.8f64;
    let cos_s = -light.y as f64;
    let t_s = fresnel_transmittance(cos_s, ior);
    let refract = |d: DVec3| {
        // Into the water through a surface of normal +y.
        let eta = 1.0 / ior;
        let cos_i = -d.y;
        let cos_t = (1.0 - eta * eta * (1.0 - cos_i * cos_i)).sqrt();
        (eta * d + (eta * cos_i - cos_t) * DVec3::Y).normalize()
    };
    // The square of floor the refracted sunlight covers: the water's
    // square moved along the refracted ray by the water's height.
    let ts = refract(light.as_dvec3());
    let lit_centre = ts * (1.0 / -ts.y);
    // Measured: see the asserts.
    for (overrides, mean_bound, worst_bound) in [
        (&["ccm_size=128", "cascades=1"][..], 0.005, 0.01),
        (&[][..], 0.005, 0.03),
    ] {
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        let params =
            Params::resolve("water_photons", WaterPhotonsParams::specs(), &overrides).unwrap();
        let mut r = Renderer::new(&ctx, s.clone(), "water_photons", &params, N, N, 0.0).unwrap();
        r.scene_gpu.components = Component::All.mask();
        r.render_frame(0.0).unwrap();
        let img = r.radiance().unwrap();
        assert_finite(&img);
        // (pixels, sum of relative errors, worst) for visible and hidden floor.
        let mut stats = [(0usize, 0.0f64, 0.0f64); 2];
        for py in 0..N {
            for px in 0..N {
                let (o, d) = pixel_ray(&s.camera, N, N, px, py);
                let (o, d) = (o.as_dvec3(), d.as_dvec3());
                if d.y >= 0.0 {
                    continue;
                }
                let at_water = o + d * ((1.0 - o.y) / d.y);
                if at_water.x.abs() > 2.8
                    || at_water.z.abs() > 2.8
                    || length_in_box(o, at_water, wall_lo, wall_hi) > 0.0
                {
                    continue;
                }
                let dt = refract(d);
                let floor = at_water + dt * (1.0 / -dt.y);
                if (floor.x - lit_centre.x).abs() > 2.6 || (floor.z - lit_centre.z).abs() > 2.6 {
                    continue;
                }
                let hidden = length_in_box(o, floor, wall_lo, wall_hi) > 0.0;
                let t_v = fresnel_transmittance(-d.y, ior);
                let expected =
                    t_s * t_v * albedo * 1000.0 * cos_s / (std::f64::consts::PI * ior * ior);
                let i = 4 * (py * N + px) as usize;
                let rel = img[i] as f64 / expected - 1.0;
                let st = &mut stats[hidden as usize];
                st.0 += 1;
                st.1 += rel;
                if rel.abs() > st.2.abs() {
                    st.2 = rel;
                }
            }
        }
        for (k, name) in ["visible", "hidden"].iter().enumerate() {
            let (n, sum, worst) = stats[k];
            let mean = sum / n as f64;
            println!(
                "flat water from above, {overrides:?}: {n} {name} floor pixels, T(θ_s) = {t_s:.5}, mean relative error {mean:+.5}, worst {worst:+.5}"
            );
            assert!(
                n > if k == 0 { 300 } else { 40 },
                "{n} {name} pixels checked"
            );
            assert!(
                mean.abs() < mean_bound && worst.abs() < worst_bound,
                "{overrides:?}, {name}: mean {mean}, worst {worst}"
            );
        }
    }
    assert_validation_clean(&ctx);
}

/// GUIDE §2: a two-sided diffuse surface is lit on the side the light
/// arrives at and never through itself. A thin wall (one open quad, x =
/// −0.5, 0.6 m high) stands under flat water; the refracted sunlight
/// (travelling toward +x) lands on its −x face. Seen from a camera on the
/// −x side, the wall's pixels of the caustic buffer hold the analytic
/// E cos θ_s T(θ_s) |t_x| / |t_y| (t the refracted direction; pixels at
/// least a footprint, ~0.1 m up the wall, from its top edge, where fewer
/// boxes overlap); seen from a camera on the +x side, at the same depth,
/// they hold nothing (the splat's arrival side test: before it, the dark
/// side took the lit side's 201 W/m²).
#[test]
fn a_thin_wall_lit_on_one_side_stays_dark_on_the_other() {
    let ctx = validated_context();
    let light = Vec3::new(0.3, -1.0, 0.2).normalize();
    let mut s = water_scene(
        water(Vec2::new(4.0, 4.0), [8, 8], 1.0, vec![]),
        light,
        Vec3::ZERO,
    );
    let x = -0.5;
    let wall = caustics::scene::Mesh {
        positions: vec![
            Vec3::new(x, 0.0, -1.0),
            Vec3::new(x, 0.0, 1.0),
            Vec3::new(x, 0.6, 1.0),
            Vec3::new(x, 0.6, -1.0),
        ],
        normals: vec![Vec3::X; 4],
        uvs: Vec::new(),
        indices: vec![[0, 1, 2], [0, 2, 3]],
        materials: vec![0; 2],
    };
    s.objects.push(object("thin wall", wall));
    let (cos_s, t_s) = {
        let cos_s = -light.y as f64;
        (cos_s, fresnel_transmittance(cos_s, 1.33))
    };
    let t = {
        let eta = 1.0 / 1.33f64;
        let cos_t = (1.0 - eta * eta * (1.0 - cos_s * cos_s)).sqrt();
        (eta * light.as_dvec3() + (eta * cos_s - cos_t) * glam::DVec3::Y).normalize()
    };
    let expected = 1000.0 * cos_s * t_s * t.x.abs() / t.y.abs();
    let target = Vec3::new(x, 0.3, 0.0);
    let mut results = vec![];
    for (side, eye) in [
        ("lit", Vec3::new(-3.0, 3.0, 0.4)),
        ("dark", Vec3::new(2.0, 3.0, 0.4)),
    ] {
        s.camera = camera(eye, target, 50.0);
        let run = render(&ctx, &s, &["ccm_size=128", "cascades=1", "denoise=0"], 64);
        let caustics = run.technique.splat.caustics.download_rgba32f().unwrap();
        let position = run
            .technique
            .surface
            .gbuffer()
            .position
            .download_rgba32f()
            .unwrap();
        let (mut n, mut sum, mut max) = (0usize, 0.0f64, 0.0f64);
        for i in 0..64 * 64 {
            let p = Vec3::from_slice(&position[4 * i..4 * i + 3]);
            if position[4 * i + 3] == 0.0
                || (p.x - x).abs() > 1e-3
                || !(0.1..0.4).contains(&p.y)
                || p.z.abs() > 0.7
            {
                continue;
            }
            let e = caustics[4 * i] as f64;
            sum += e;
            max = max.max(e);
            n += 1;
        }
        println!(
            "thin wall, {side} side: {n} pixels, mean E {:.3} W/m², max {max:.3} (lit side analytic {expected:.3})",
            sum / n as f64
        );
        assert!(n > 40, "{side}: {n} wall pixels");
        results.push((sum / n as f64, max));
    }
    let (lit, _) = results[0];
    let (_, dark_max) = results[1];
    // Measured: lit 202.266 vs 202.263 W/m² (+0.002%), dark 0.
    assert!(
        (lit / expected - 1.0).abs() < 0.01,
        "lit side: {lit} vs {expected}"
    );
    assert!(
        dark_max < 1e-3 * expected,
        "dark side: up to {dark_max} W/m²"
    );
    assert_validation_clean(&ctx);
}

/// 60 frames of `bench` at 32² on water_pool, memory sampled every 10
/// frames between frames (after glibc's malloc_trim, so memory in use).
/// - What the renderer owns is the same at every sample: the Rust heap and
///   the device memory to the byte, the Vulkan host allocations to one
///   small block (vk/host_memory.rs).
/// - The host RSS after frame 60 is at most 16 MiB above the one after frame
///   10. Measured: no trend; 165.19, 165.18, 165.16, 165.17, 166.78, 165.18
///   MiB (2026-12-02, debug build). It gets a margin because lavapipe keeps
///   a finished scene's rasteriser bins until it reuses the scene, 4.5 MiB
///   on water_pool at some samples (BENCHMARKS.md "Soak"). With the
///   cascade count and the splat mode read from the uniform block, lavapipe
///   (Mesa 22.3) recompiled view.comp at every bind and kept each copy:
///   +1.85 MB a frame, about 90 MiB over these 50 frames
///   (examples/lavapipe_rebind.rs), memory only the RSS sees.
#[test]
fn host_memory_stays_flat_over_frames() {
    let json = std::env::temp_dir().join(format!("water_photons_rss_{}.json", std::process::id()));
    let scene =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/water_pool.toml");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_caustics"))
        .env(
            "VK_DRIVER_FILES",
            "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json",
        )
        .args(["bench", "--technique", "water_photons", "--scene"])
        .arg(&scene)
        .args([
            "--width", "32", "--height", "32", "--frames", "60", "--warmup", "5",
        ])
        .args(["--param", "shadow_map_size=256", "--param", "ccm_size=64"])
        .args(["--memory-samples", "6", "--json"])
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let _ = std::fs::remove_file(&json);
    let series = |key: &str| -> Vec<i64> {
        report["memory"]
            .as_array()
            .expect("memory samples")
            .iter()
            .map(|s| s[key].as_i64().unwrap_or_else(|| panic!("{key} in {s}")))
            .collect()
    };
    let rss = series("host_rss");
    println!("host RSS after frames 10, 20, ..., 60: {rss:?} bytes");
    let growth = rss[rss.len() - 1] - rss[0];
    assert!(
        growth <= 16 << 20,
        "host RSS grew {growth} bytes over 50 frames: {rss:?}"
    );
    // What the renderer owns, counted where it is allocated
    // (vk/host_memory.rs): the Rust heap and the device memory are the same
    // at every sample, to the byte (the bench reserves its own records up
    // front, and a frame frees what it allocates). The Vulkan host memory
    // may hold one small block more or less: lavapipe's queue thread frees
    // a 168-byte block just after the fence, which a sample can beat.
    for (key, slack) in [
        ("rust_heap", 0),
        ("rust_heap_allocations", 0),
        ("device_allocated", 0),
        ("vulkan_host", 4096),
        ("vulkan_host_allocations", 4),
    ] {
        let v = series(key);
        println!("{key}: {v:?}");
        assert!(v[0] > 0, "{key} not counted: {v:?}");
        assert!(
            v.iter().all(|&x| (x - v[0]).abs() <= slack),
            "{key} changed between samples by more than {slack}: {v:?}"
        );
    }
}
