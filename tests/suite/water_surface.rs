//! The water surface pass (glsl/passes/water_surface.comp) against the CPU
//! Gerstner sum (`Water::surface_point`) on every grid vertex, for the two
//! canonical water scenes (3-4 waves each, steepness 0.5-0.8) and a steep
//! test surface, at several times, on lavapipe with validation on.
//!
//! Tolerance, per wave i with Θ_i the largest |k D·x0| + |ω t| + |φ| over
//! the grid: both sides round θ in f32 (a few operations of unit roundoff
//! u = 2^-24 each, |δθ| ≤ 8 u Θ_i together), and the GPU's sin and cos may
//! be off by E = 2^-11 (the Vulkan precision bound for sin/cos), so
//! |δ sin|, |δ cos| ≤ 8 u Θ_i + E. The position moves by A_i(1 + Q_i) per
//! unit of that, the derivatives a = ∂P/∂z, b = ∂P/∂x by δ = Σ k_i A_i
//! (1 + Q_i) per unit; the normal normalize(a × b) then moves by at most
//! 2 (|a| + |b|) δ / |a × b| (first order, with a factor 2 of margin for the
//! normalisation), taken per vertex from the CPU's derivatives. Plus the
//! f32 rounding of the positions themselves (a few u of |P|).
//!
//! Measured (lavapipe, Mesa 22.3.6; `cargo test --test water_surface -- --nocapture`):
//! worst position differences 7e-7 m (water_pool), 1.5e-5 m (ocean_large:
//! one f32 ulp at 200 m) and 1e-6 m (steep), against bounds of 6e-5 to
//! 1.3e-3 m; worst normal differences 7e-6 (steep, t = 100 s) against
//! per-vertex bounds of 2e-4 to 1.5e-3. lavapipe's sin and cos are far more
//! accurate than the 2^-11 the bound allows. Runtime about 0.2 s.

use crate::common;

use caustics::gpu::GpuWaterVertex;
use caustics::passes::water_surface::WaterSurface;
use caustics::scene::{Scene, Water, Wave};
use caustics::vk::Profiler;
use common::*;
use glam::{Vec2, Vec3};
use std::path::Path;

const U: f32 = 1.0 / (1u32 << 24) as f32;
const E_TRIG: f32 = 1.0 / 2048.0;

/// (position tolerance, derivative tolerance δ) at `time`, as derived in the module docs.
fn tolerances(water: &Water, time: f32) -> (f32, f32) {
    let reach = (water.center.abs() + water.size * 0.5).length();
    let mut dpos = 0.0;
    let mut dderiv = 0.0;
    for w in &water.waves {
        let theta = w.wavenumber() * reach + (w.angular_frequency() * time).abs() + w.phase.abs();
        let trig = 8.0 * U * theta + E_TRIG;
        dpos += w.amplitude * (1.0 + w.steepness) * trig;
        dderiv += w.wavenumber() * w.amplitude * (1.0 + w.steepness) * trig;
    }
    let magnitude =
        reach + water.base_height.abs() + water.waves.iter().map(|w| w.amplitude).sum::<f32>();
    (dpos + 8.0 * U * magnitude, dderiv + 8.0 * U)
}

fn check(ctx: &std::sync::Arc<caustics::vk::Context>, name: &str, water: &Water) {
    let pass = WaterSurface::new(ctx, water).expect("water surface pass");
    let profiler = Profiler::new(ctx, 4).expect("profiler");
    let [nx, nz] = water.resolution;
    for time in [0.0, 1.7, 12.5, 100.0] {
        let timings = profiler
            .frame(|rec| {
                pass.record(rec, time);
                Ok(())
            })
            .expect("frame");
        assert_eq!(timings[0].name, "water surface");
        let gpu: Vec<GpuWaterVertex> = pass.vertices.download_pod().expect("read back");
        assert_eq!(gpu.len(), water.vertex_count());
        let (tol_p, tol_n) = tolerances(water, time);
        let (mut worst_p, mut worst_n) = (0.0f32, 0.0f32);
        for j in 0..=nz {
            for i in 0..=nx {
                let (p, n) = water.surface_point(water.rest_position(i, j), time);
                let v = gpu[(j * (nx + 1) + i) as usize];
                worst_p = worst_p.max((Vec3::from_slice(&v.position) - p).abs().max_element());
                worst_n = worst_n.max((Vec3::from_slice(&v.normal) - n).abs().max_element());
                assert_eq!((v.position[3], v.normal[3]), (1.0, 0.0));
            }
        }
        println!(
            "{name} t={time}: worst |Δposition| {worst_p:.3e} m (bound {tol_p:.3e}), worst |Δnormal| {worst_n:.3e} (bound {tol_n:.3e})"
        );
        assert!(
            worst_p <= tol_p,
            "{name} t={time}: position off by {worst_p} > {tol_p}"
        );
        assert!(
            worst_n <= tol_n,
            "{name} t={time}: normal off by {worst_n} > {tol_n}"
        );
    }
}

fn scene_water(name: &str) -> Water {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("assets/scenes/{name}.toml"));
    let scene = Scene::load(&path).expect(name);
    scene
        .objects
        .iter()
        .find_map(|o| o.water.clone())
        .expect("water")
}

#[test]
fn gpu_surface_equals_the_cpu_gerstner_sum() {
    let ctx = validated_context();
    check(&ctx, "water_pool", &scene_water("water_pool"));
    check(&ctx, "ocean_large", &scene_water("ocean_large"));
    // Steep, high waves close to folding (Σ Q k A = 0.89), odd grid sizes
    // that leave partial workgroups, an off-centre rectangle.
    let wave = |amplitude, wavelength, direction_deg, steepness, phase| Wave {
        amplitude,
        wavelength,
        direction_deg,
        steepness,
        speed: Wave::deep_water_speed(wavelength),
        phase,
    };
    let steep = Water {
        center: Vec2::new(-3.0, 7.5),
        size: Vec2::new(9.0, 5.0),
        resolution: [37, 19],
        base_height: -0.4,
        material: 0,
        waves: vec![
            wave(0.2, 3.0, 10.0, 1.0, 0.0),
            wave(0.07, 1.7, 100.0, 0.9, 2.0),
            wave(0.025, 0.9, 220.0, 0.8, -1.0),
            wave(0.008, 0.5, 300.0, 1.0, 4.0),
        ],
    };
    assert!(
        (0.8..1.0).contains(&steep.fold_measure()),
        "{}",
        steep.fold_measure()
    );
    check(&ctx, "steep", &steep);
    // Flat water (no waves) is the plane at base height.
    let flat = Water {
        waves: Vec::new(),
        ..steep
    };
    check(&ctx, "flat", &flat);
    assert_validation_clean(&ctx);
}

/// `Water::is_below_surface` (where `water_photons` draws its shafts): on
/// `water_pool`'s waves at t = 1.3 s, a point 1 cm under the displaced
/// surface above a rest point is below it and one 1 cm over it is not,
/// for rest points across the pool (the surface's horizontal displacement
/// is undone by the search); outside the rectangle nothing is.
#[test]
fn points_under_the_waves_are_below_the_surface() {
    let water = scene_water("water_pool");
    let time = 1.3;
    let mut checked = 0;
    for i in 1..20 {
        for j in 1..20 {
            let rest = Vec2::new(-3.0 + 0.3 * i as f32, -3.0 + 0.3 * j as f32);
            let (p, _) = water.surface_point(rest, time);
            assert!(
                water.is_below_surface(p - Vec3::Y * 0.01, time),
                "{p} - 1 cm"
            );
            assert!(
                !water.is_below_surface(p + Vec3::Y * 0.01, time),
                "{p} + 1 cm"
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 361);
    assert!(!water.is_below_surface(Vec3::new(3.5, 0.5, 0.0), time));
    assert!(!water.is_below_surface(Vec3::new(0.0, 0.5, -3.5), time));
}
