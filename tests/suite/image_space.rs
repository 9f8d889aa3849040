//! The `image_space` technique (Wyman 2005-06 caustic maps) against physics
//! and the ground truth. Lavapipe, validation on, 128² frames. Scene: point
//! light of 60 W/sr at (0, 8, 0), glass sphere (64 segments) r = 1 m at
//! (0, 1.6, 0), diffuse floor (albedo 0.8).
//!
//! Measured (lavapipe, Mesa 22.3.6; `cargo test --test image_space -- --nocapture`):
//! - splat_conserves_flux (256² photons, 256² map, 7² splats): photon flux
//!   4.107764 W, caustic-map flux 4.107763 W, relative 1.9e-7 (bound 1e-4:
//!   float summation only).
//! - floor_flux_matches_fresnel_transmission (256²): I * sum(Omega_texel)
//!   over the photon texels whose centre ray meets the sphere (CPU BVH)
//!   4.6256 W vs analytic 2 pi I (1 - cos) 4.6304 W (1.0e-3: the mesh
//!   silhouette; bound 1%); refracted flux on the floor 3.8724 W vs the
//!   integral of I (1 - F)^2 dOmega 3.8671 W (+1.4e-3; bound 5%; traced
//!   photons also follow partial internal reflections, T R R T ..., which
//!   the (1 - F)^2 integral leaves out; keeping only transmission gave
//!   3.8656 W, -3.7e-4).
//! - photon_mode=2 (light-space G-buffers, back-face march), 256²: refracted
//!   flux on the floor 3.8607 W vs 3.8671 W (1.6e-3; bound 5%).
//!   photon_mode=1 (Eq. 6.3.1): 21% of the entering photons
//!   (3336 of 15944) meet total internal reflection at the approximated
//!   exit (a sphere has none: d~ falls short near the rim). Dropping them
//!   (or Wyman's "reflect and ignore the refractor", which sends them up
//!   past the light) lost 20.7% of the flux; clamping to the critical angle
//!   (his second fix, flux kept) gives entering 4.6256 W, floor 3.9268 W vs
//!   3.8671 W (+1.5%; bound 5%). With the shared two-sided refraction code
//!   and per-vertex d_N (instead of a BVH cast per photon): floor 3.9275 W
//!   (+1.6%; 3.9275 W, +1.56%, measured again with the entering flux by
//!   ray cast).
//! - open_sheet_photons_refract_once_in_every_mode (open IOR 1.33 sheet,
//!   directional 3 W/m^2, 256²): 11.8609 W on the floor in photon modes
//!   0, 1 and 2 vs (1 - F(0)) E A = 11.7593 W (+8.6e-3, sheet-edge texels;
//!   bound 2%, modes agree to 1e-4); modes 1 and 2 landed 0 W before.
//! - ior_one_gives_back_the_shadowed_light (512²/512², defaults): inside the
//!   shadow cone (0.02 rad from its rim left out) worst pixel 0.15%, mean
//!   1.7e-4 (photon_mode 1 and 2: worst 0.15%, mean 1.7e-5); outside
//!   exactly equal; bound 2%. Same test with a spot light (30° cone; its
//!   caustic views are a point light's six cube faces, since specular
//!   objects send light outside the cone): worst 0.15%, mean 1.7e-4 (with
//!   one perspective view over the cone: worst 0.34%); with a directional light
//!   along (0.3, -1, 0.2) (orthographic views, 0.2 m rim band): worst
//!   0.15%, mean 2.1e-4. (Snapping splats to texel
//!   centres gave 8.8% worst pixel from aliasing: hence sub-texel splats.)
//! - ball_lens_focus (512²/512²): paraxial photons (impact 0.03-0.1 R) cross
//!   the axis 4.9 mm from the thick-lens paraxial focus (tolerance 18.1 mm =
//!   the exact longitudinal aberration at 0.1 R, 8.1 mm, + 1 cm); on a floor
//!   in that plane the brightest caustic texel lies 2.3 cm off the axis
//!   (tolerance one texel footprint, 3.3 cm), E = 84.8 W/m² = 99x the
//!   unfocused irradiance. Peak irradiance is higher 0.4 m nearer the lens
//!   (149 W/m²; 20.6 W/m² 0.4 m beyond): at splat resolution the circle of
//!   least confusion of this strongly aberrated lens gathers more flux.
//! - *_caustics_match_reference (assets/scenes/{ball_lens,ring,gemstone}.toml
//!   at 128², time 0, default 512² photons and 512² maps; the caustic image
//!   image_space minus direct vs the reference's L S+ D, fixed seeds; FLIP
//!   mean of the two tonemapped images; measured at 8M photons, 24-30 s per
//!   scene; the tests trace 4M since 2026-12-03, second table):
//!
//!   | scene | reference halves (4M vs 4M) | photon_mode 0 | 1 | 2 |
//!   | --- | --- | --- | --- | --- |
//!   | ball_lens | energy -1.1%, FLIP 0.042 | energy -1.49%, FLIP 0.0285 | -0.84%, 0.0665 | -1.97%, 0.0284 |
//!   | ring | +0.96%, 0.104 | +1.33%, 0.0758 | +1.32%, 0.0757 | - |
//!   | gemstone | -0.48%, 0.030 | -0.36%, 0.0463 | +571%, 0.180 | - |
//!
//!   Since the reference samples direct light from the camera, its photons
//!   all go to the caustics; the tests trace 4M (2026-12-03, issue 26:
//!   half the time, every bound unchanged) and measure:
//!
//!   | scene | reference halves (2M vs 2M) | photon_mode 0 | 1 | 2 |
//!   | --- | --- | --- | --- | --- |
//!   | ball_lens | energy -0.02%, FLIP 0.018 | -1.75%, 0.0145 | -1.11%, 0.0592 | -2.23%, 0.0141 |
//!   | ring | +0.03%, 0.052 | +0.26%, 0.0471 | +0.25%, 0.0471 | - |
//!   | gemstone | +0.41%, 0.034 | -0.06%, 0.0469 | +572.5%, 0.180 | - |
//!   | still_life | -0.29%, 0.018 | -2.45%, 0.0178 | - | - |
//!
//!   Gemstone's mode 1 reads 0.005 under its energy bound, which records a
//!   known limit (below) rather than a tolerance.
//!
//!   (The reference follows paths of up to 128 interfaces; with its former
//!   32 it missed 10% of the gemstone's caustic energy: mode 0 read +11.2%
//!   against it, +0.3% with its own chains cut at the same depth.)
//!   ball_lens: mode 0 follows partial internal reflections (chosen with
//!   probability F, as the reference does; -1.95% when it kept only
//!   transmission). Mode 1's FLIP is higher: the halo and dark spots of
//!   Eq. 6.3.1 (src/passes/caustic_map.rs).
//!   ring: mode 0 lies within the reference's own noise (its FLIP against
//!   the 8M truth is below that of the two 4M halves against each other).
//!   Mode 1 matches mode 0 since the light-space front pass
//!   (passes::specular_gbuffer) keeps mirror faces seen from either side
//!   (before, the inside of the open cylinder, the back of its faces, was
//!   culled and mode 1 lost the caustic inside the ring: -38.7%).
//!   gemstone (diamond, n = 2.42, flat facets): mode 0 had 39% of the
//!   reference's energy (-61.1%, FLIP 0.105). Measured causes, in photon
//!   flux (512² photons, 10.42 W enter the gem, about 8.4 W refracted):
//!   keeping only transmission dropped 1.42 W of partial internal
//!   reflections and 8 bounces dropped 1.57 W more (landed photons take 10
//!   total internal reflections on average; 128 bounces leave 0.007 W);
//!   and the spot's caustic view, its cone, culled the 23% of the landing
//!   flux that the facets throw outside the cone. Floor flux 1.24 W before,
//!   2.24 W after. Mode 1 (+571%, 6.7x the caustic image) creates no
//!   energy: 8.89 W of the 10.42 W land (gemstone_photons_create_no_energy),
//!   and the image's energy equals the light-tracer estimate from its photon
//!   buffer (2580 vs 2622; mode 0: 389.55 vs 389.59), so splat and apply add
//!   nothing. It puts the light in the wrong place: 99.2% of the photons
//!   meet total internal reflection at the approximated exit (the
//!   pavilion's facets are cut beyond the 24.4° critical angle), and the
//!   TIR remedy (Wyman's "fill these regions with plausible colors", flux
//!   kept) sends each one down to the floor, 85% of it within 1 m of the
//!   gem's axis, where the diamond really returns 79% of the refracted
//!   light upwards through the crown. Two interfaces cannot say where
//!   trapped light leaves; that error is inherent to Eq. 6.3.1.
//! - mirror_ring_cardioid_cusp (512² photons, 512² map, 3² splats,
//!   directional light at elevation atan 1/2 on a 1 m mirror ring of
//!   reflectance 0.9): reflected flux landing inside the ring 2.2994 W vs
//!   2.3002 W from the analytic cylinder (-3.4e-4; bound 1%); brightest
//!   caustic texel at (0.528, -0.004) m vs the cusp (0.5, 0): off by
//!   (+2.8, -0.4) cm, tolerance (3.8, 1.7) cm (splat half-width + half a
//!   texel of floor footprint). The peak sits on the wall's side of the cusp,
//!   where the nephroid's two branches and the three-ray region blur in.
//! - caustics_on_change_reuses_the_map_until_something_moves (gemstone,
//!   64², 128² photons and map): frames at an unchanged time record no
//!   photon pass and are bit-identical to recomputing; a new time and a
//!   moved light recompute (bit-identical too).

use crate::common;

use caustics::params::{ParamSet, Params};
use caustics::passes::caustic_map::GpuPhoton;
use caustics::radiometry::fresnel_dielectric;
use caustics::scene::{Light, LightKind, Scene};
use caustics::shader_bindings as b;
use caustics::techniques::image_space::ImageSpaceParams;
use caustics::vk::Context;
use common::*;
use glam::{DVec3, Vec3};
use std::f64::consts::PI;
use std::sync::Arc;

const LIGHT: Vec3 = Vec3::new(0.0, 8.0, 0.0);
const INTENSITY: f32 = 60.0;
const CENTRE: Vec3 = Vec3::new(0.0, 1.6, 0.0);
const RADIUS: f32 = 1.0;
const ALBEDO: f32 = 0.8;
const SIZE: u32 = 128;
/// The reference's photons for the caustic comparisons, per scene: the
/// smallest count whose two halves differ (FLIP mean) by no more than the
/// halves of the reference the bounds were measured against (2 M vs 2 M,
/// the file's header). Since the reference's Fresnel splitting and aim
/// guide (issue 27) its noise at 4 M is 0.011 (ball_lens, still_life),
/// 0.026 (ring), 0.025 (gemstone); noise grows as 1/sqrt(photons).
/// Measured at these counts (2026-12-07), halves and mode 0: ball_lens
/// 0.0152, -0.0183 / 0.0130; ring 0.0431, +0.0030 / 0.0428; gemstone
/// 0.0308, -0.0020 / 0.0465; still_life 0.0153, -0.0256 / 0.0172.
const PHOTONS_BALL_LENS: u64 = 3 << 19;
const PHOTONS_RING: u64 = 1 << 20;
const PHOTONS_GEMSTONE: u64 = 5 << 19;
const PHOTONS_STILL_LIFE: u64 = 3 << 19;

fn ball_scene(ior: Option<f32>, floor_y: f32) -> Scene {
    ball_scene_lit(ior, floor_y, point_light(LIGHT, INTENSITY))
}

fn ball_scene_lit(ior: Option<f32>, floor_y: f32, light: Light) -> Scene {
    let mut objects = vec![object("floor", floor_mesh(5.0, floor_y, 0))];
    if ior.is_some() {
        objects.push(object("lens", sphere_mesh(CENTRE, RADIUS, 1, 64)));
    }
    scene(
        camera(Vec3::new(0.0, 5.0, 7.0), Vec3::new(0.0, 0.8, 0.0), 40.0),
        vec![light],
        vec![
            diffuse("floor", ALBEDO),
            dielectric("glass", ior.unwrap_or(1.5)),
        ],
        objects,
    )
}

type Frame = ImageSpaceFrame;

fn render(ctx: &Arc<Context>, scene: &Scene, overrides: &[&str]) -> Frame {
    render_image_space(ctx, scene, overrides, SIZE)
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
    floor_flux(0);
}

#[test]
fn floor_flux_matches_fresnel_transmission_image_space() {
    floor_flux(1);
}

#[test]
fn floor_flux_matches_fresnel_transmission_back_march() {
    floor_flux(2);
}

fn floor_flux(mode: u32) {
    let ctx = validated_context();
    let s = ball_scene(Some(1.5), 0.0);
    let mode = format!("photon_mode={mode}");
    let f = render(
        &ctx,
        &s,
        &["photon_buffer_size=256", "caustic_map_size=256", &mode],
    );
    let ph = photons(&f);
    let n2 = ph.len() / 2;
    let refracted: f64 = ph[..n2]
        .iter()
        .filter(|p| p.position[3] == 1.0 && p.position[1].abs() < 1e-3)
        .map(|p| p.flux[0] as f64)
        .sum();
    // I * Omega over the photon texels whose centre ray meets the sphere
    // (not the photons that landed: a traced photon may reflect inside and
    // leave upwards).
    let entering_measured = flux_into_specular(&f, &s);
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

/// Floor pixels of the test camera: (index, floor point), skipping pixels
/// whose ray meets the sphere (with a margin).
fn floor_pixels(s: &Scene) -> Vec<(usize, Vec3)> {
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
            out.push(((py * SIZE + px) as usize, x));
        }
    }
    out
}

#[test]
fn ior_one_gives_back_the_shadowed_light() {
    ior_one(0);
}

#[test]
fn ior_one_gives_back_the_shadowed_light_image_space() {
    ior_one(1);
}

#[test]
fn ior_one_gives_back_the_shadowed_light_back_march() {
    ior_one(2);
}

fn ior_one(mode: u32) {
    // The shadow's rim blurs by (splat/2 + 1) caustic texels of 2 / 512 rad
    // on the -y cube face and by about a shadow texel of PCF: skip 0.02 rad
    // either side, 0.128 m at the sphere's distance (6.4 m).
    ior_one_with(mode, point_light(LIGHT, INTENSITY), 0.128);
}

#[test]
fn ior_one_gives_back_the_shadowed_light_spot() {
    let light = Light {
        kind: LightKind::Spot,
        cone_angle_deg: 30.0,
        cone_falloff_deg: 5.0,
        ..point_light(LIGHT, INTENSITY)
    };
    // One 60° view at 512²: texels of 2 tan 30° / 512 rad, smaller than the
    // cube face's: the point light's band is ample.
    ior_one_with(0, light, 0.128);
}

#[test]
fn ior_one_gives_back_the_shadowed_light_directional() {
    // Orthographic caustic map over the scene sphere (radius ~7.2 m): texels
    // of 2.8 cm at 512², splat half-width 3.5 texels + PCF: skip 0.2 m.
    let light = directional_light(Vec3::new(0.3, -1.0, 0.2), 3.0);
    ior_one_with(0, light, 0.2);
}

/// IOR 1: the floor's radiance with the sphere equals the radiance without
/// it, away from the shadow's rim: `band` metres either side of the sphere's
/// silhouette, measured as the distance from the sphere's centre to the
/// light's ray through the floor point.
fn ior_one_with(mode: u32, light: Light, band: f32) {
    let ctx = validated_context();
    let with = ball_scene_lit(Some(1.0), 0.0, light);
    let without = ball_scene_lit(None, 0.0, light);
    let mode = format!("photon_mode={mode}");
    let a = render(&ctx, &with, &[&mode]);
    let b_ = render(&ctx, &without, &[&mode]);
    let ra = a.targets.radiance.download_rgba32f().unwrap();
    let rb = b_.targets.radiance.download_rgba32f().unwrap();
    assert_finite(&ra);
    let (mut worst_in, mut worst_out) = (0.0f32, 0.0f32);
    let (mut sum_a, mut sum_b, mut n_in) = (0.0f64, 0.0f64, 0);
    for (i, x) in floor_pixels(&with) {
        let dir = match light.kind {
            LightKind::Directional => light.direction.normalize(),
            _ => (x - light.position).normalize(),
        };
        let line = (CENTRE - x).cross(dir).length();
        let (va, vb) = (ra[4 * i], rb[4 * i]);
        if vb <= 0.0 {
            continue; // outside a spot's cone
        }
        let rel = (va - vb).abs() / vb;
        if line < RADIUS - band {
            worst_in = worst_in.max(rel);
            sum_a += va as f64;
            sum_b += vb as f64;
            n_in += 1;
        } else if line > RADIUS + band {
            worst_out = worst_out.max(rel);
        }
    }
    let mean_rel = (sum_a - sum_b).abs() / sum_b;
    println!(
        "IOR 1, {:?} light, {mode}: {n_in} pixels inside the shadow: worst relative error {worst_in:.4}, mean {mean_rel:.2e}; outside: worst {worst_out:.2e}",
        light.kind
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

/// Solid angle of the tan-plane rectangle [u0,u1] x [v0,v1] (exact).
fn rect_solid_angle(u0: f64, u1: f64, v0: f64, v1: f64) -> f64 {
    let f = |u: f64, v: f64| (u * v / (1.0 + u * u + v * v).sqrt()).atan();
    f(u1, v1) - f(u0, v1) - f(u1, v0) + f(u0, v0)
}

/// The brightest texel of light 0's -y cube face (the floor's view) as
/// (floor point, irradiance there from the caustic map).
fn caustic_peak(f: &Frame, floor_y: f32) -> (Vec3, f64) {
    let size = f.tech.caustics.map_size;
    let view = f
        .tech
        .caustics
        .views(f.tech.light_views.lights(), f.scene_gpu.sphere)[0];
    let layer = 3; // -y (CUBE_FACES order +x -x +y -y +z -z)
    let texels = f.tech.caustics.map.download_layer_rgba32f(layer).unwrap();
    let inv = glam::Mat4::from_cols_array_2d(&view.view_proj[layer as usize]).inverse();
    let mut best = (Vec3::ZERO, 0.0f64);
    for ty in 0..size {
        for tx in 0..size {
            let flux = texels[((ty * size + tx) * 4) as usize] as f64;
            if flux <= 0.0 {
                continue;
            }
            let ndc = |t: u32| 2.0 * (t as f32 + 0.5) / size as f32 - 1.0;
            let p = inv.project_point3(Vec3::new(ndc(tx), ndc(ty), 0.5));
            let d = (p - LIGHT).normalize();
            if d.y >= 0.0 {
                continue;
            }
            let x = LIGHT + d * ((floor_y - LIGHT.y) / d.y);
            let dist = (x - LIGHT).length() as f64;
            let cos = (-d.y) as f64;
            let edge = |t: u32| 2.0 * t as f64 / size as f64 - 1.0;
            let omega = rect_solid_angle(edge(tx), edge(tx + 1), edge(ty), edge(ty + 1));
            let e = flux * cos / (omega * dist * dist);
            if e > best.1 {
                best = (x, e);
            }
        }
    }
    best
}

/// Where a ray from the light at angle `beta` off the axis crosses the axis
/// after refracting into and out of the analytic sphere (f64, in metres of y).
fn axis_crossing(beta: f64, ior: f64) -> f64 {
    let l = DVec3::new(0.0, LIGHT.y as f64, 0.0);
    let c = DVec3::new(0.0, CENTRE.y as f64, 0.0);
    let r = RADIUS as f64;
    let refract = |d: DVec3, n: DVec3, eta: f64| {
        let cos_i = -d.dot(n);
        let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
        (eta * d + (eta * cos_i - k.sqrt()) * n).normalize()
    };
    let hit = |o: DVec3, d: DVec3, far: bool| {
        let oc = o - c;
        let b = oc.dot(d);
        let disc = (b * b - (oc.length_squared() - r * r)).sqrt();
        o + d * if far { -b + disc } else { -b - disc }
    };
    let d0 = DVec3::new(beta.sin(), -beta.cos(), 0.0);
    let p1 = hit(l, d0, false);
    let d1 = refract(d0, (p1 - c) / r, 1.0 / ior);
    let p2 = hit(p1, d1, true);
    let d2 = refract(d1, -(p2 - c) / r, ior);
    p2.y + (-p2.x / d2.x) * d2.y
}

#[test]
fn ball_lens_focus() {
    let ctx = validated_context();
    // Paraxial ball lens (principal planes at the centre): f = n R / (2 (n - 1)),
    // image distance s' = 1 / (1/f - 1/s) from the centre for the light at s.
    let n = 1.5f64;
    let f_len = n * RADIUS as f64 / (2.0 * (n - 1.0));
    let s_obj = (LIGHT - CENTRE).length() as f64;
    let s_img = 1.0 / (1.0 / f_len - 1.0 / s_obj);
    let y_focus = (CENTRE.y as f64 - s_img) as f32;
    let params = ["photon_buffer_size=512", "caustic_map_size=512"];

    // 1. Paraxial photons cross the axis at the paraxial focus. Photons whose
    // ray from the light passes the centre at impact parameter b in
    // [0.03, 0.1] R (nearer the axis the crossing is ill-conditioned);
    // tolerance: the exact longitudinal aberration at b = 0.1 R plus 1 cm
    // for the 64-segment mesh.
    let fr = render(&ctx, &ball_scene(Some(1.5), y_focus), &params);
    let view = fr.tech.light_views.view(0).unwrap();
    let size = fr.tech.caustics.photon_size;
    let (right, up, fwd) = (
        Vec3::from_slice(&view.right[..3]),
        Vec3::from_slice(&view.up[..3]),
        Vec3::from_slice(&view.forward[..3]),
    );
    let h = view.origin[3];
    let ph = photons(&fr);
    let (mut sum_y, mut sum_w) = (0.0f64, 0.0f64);
    for iy in 0..size {
        for ix in 0..size {
            let p = ph[(iy * size + ix) as usize];
            if p.position[3] != 1.0 {
                continue;
            }
            let su = (2.0 * (ix as f32 + 0.5) / size as f32 - 1.0) * h;
            let sv = (2.0 * (iy as f32 + 0.5) / size as f32 - 1.0) * h;
            let d0 = (fwd + su * right + sv * up).normalize();
            let b_imp = s_obj * (d0.angle_between(fwd) as f64).sin();
            if !(0.03..=0.1).contains(&(b_imp / RADIUS as f64)) {
                continue;
            }
            let (px, py, pz) = (
                p.position[0] as f64,
                p.position[1] as f64,
                p.position[2] as f64,
            );
            let (dx, dy, dz) = (p.dir[0] as f64, p.dir[1] as f64, p.dir[2] as f64);
            let t = -(px * dx + pz * dz) / (dx * dx + dz * dz);
            sum_y += p.flux[0] as f64 * (py + t * dy);
            sum_w += p.flux[0] as f64;
        }
    }
    let crossing = sum_y / sum_w;
    let beta_01 = (0.1 * RADIUS as f64 / s_obj).asin();
    let la = (axis_crossing(beta_01, n) - y_focus as f64).abs();
    let tol = la + 0.01;
    println!(
        "paraxial focus y = {y_focus:.4} m; paraxial photons (b <= 0.1 R) cross the axis at y = {crossing:.4} m (error {:.4} m, tolerance {tol:.4} m = aberration {la:.4} + 0.01)",
        (crossing - y_focus as f64).abs()
    );
    assert!((crossing - y_focus as f64).abs() < tol);

    // 2. On a floor in the paraxial plane, the brightest caustic texel holds
    // the focus: tolerance one texel's footprint (the -y face spans 2 tan 45°
    // over 512 texels at 8.36 m: 3.3 cm; the brightest texel's centre lies
    // within sqrt(2)/2 of a texel of the focus).
    let texel = 2.0 / 512.0 * (LIGHT.y - y_focus);
    let (x0, e0) = caustic_peak(&fr, y_focus);
    let off = (x0.x * x0.x + x0.z * x0.z).sqrt();
    let e_direct = INTENSITY as f64 / ((LIGHT.y - y_focus) as f64).powi(2);
    println!(
        "brightest texel {off:.4} m off the axis (tolerance {texel:.4} m), E = {e0:.1} W/m^2 = {:.0} x the unfocused {e_direct:.3} W/m^2",
        e0 / e_direct
    );
    assert!(off < texel, "peak {off} m off the axis");
    assert!(e0 > 20.0 * e_direct);
    // For the record: the peak is not highest in the paraxial plane once the
    // splat blurs at ~sigma: the circle of least confusion (nearer the lens,
    // spherical aberration) gathers more flux within a splat.
    for dy in [0.4f32, -0.4] {
        let y = y_focus + dy;
        let fr = render(&ctx, &ball_scene(Some(1.5), y), &params);
        let (_, e) = caustic_peak(&fr, y);
        println!("floor at y = {y:.3} m: peak caustic irradiance {e:.1} W/m^2");
    }
    assert_validation_clean(&ctx);
}

/// The bound of one photon mode against the reference on one scene.
struct Bound {
    photon_mode: u32,
    /// |relative total energy| of the caustic image.
    energy: f64,
    /// FLIP mean of the tonemapped caustic image.
    flip: f32,
}

/// The caustic image of `image_space` (its frame minus the `direct` frame:
/// L S+ D on diffuse receivers) on assets/scenes/`name`.toml at SIZE² and
/// time 0, against the reference's L S+ D component (`photons` photons)
/// with the same camera: relative total energy and FLIP mean of the two
/// tonemapped images, for each photon mode in `bounds` (passed explicitly,
/// so a change of the default keeps every mode measured). Only pixels whose
/// camera ray meets a diffuse surface first are compared: through the
/// glass `image_space` shows L S+ D S+ E paths, which the reference does
/// not estimate (docs/ARCHITECTURE.md, "What the ground truth does not
/// cover"); the others read 0 in both images and stay in the FLIP mean.
fn caustics_match_reference(name: &str, photons: u64, bounds: &[Bound]) {
    use caustics::reference::Component;
    use caustics::renderer::Renderer;
    let ctx = validated_context();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(format!("{name}.toml"));
    let load = || Scene::load(&path).unwrap();
    let frame = |technique: &str, overrides: &[String]| {
        let params = Params::resolve(
            technique,
            caustics::techniques::find(technique).unwrap().params(),
            overrides,
        )
        .unwrap();
        let mut r = Renderer::new(&ctx, load(), technique, &params, SIZE, SIZE, 0.0).unwrap();
        r.render_frame(0.0).unwrap();
        r.radiance().unwrap()
    };
    let mask = first_hit_mask(&load(), SIZE, false, |k| {
        k == caustics::scene::MaterialKind::Diffuse
    });
    let masked = |img: Vec<f32>| masked(&img, &mask);
    // Two halves, to measure the reference's own noise in FLIP terms.
    let reference = reference_images(
        &ctx,
        &ReferenceRequest::new(&load(), SIZE, photons).in_halves(),
    );
    let half_a = masked(reference.first_half(Component::SurfaceCaustics).to_vec());
    let truth = masked(reference.whole(Component::SurfaceCaustics).to_vec());
    let half_b = second_half(&truth, &half_a);
    let (noise_flip, _) = flip(&tonemap(&half_b), &tonemap(&half_a), SIZE);
    let truth_ldr = tonemap(&truth);
    let t = energy(&truth);
    let halves = (energy(&half_b) - energy(&half_a)) / t;
    println!(
        "{name}: reference L S+ D energy {t:.2} ({} M photons); its two halves differ by {halves:+.4} in energy, {noise_flip:.4} in FLIP mean",
        reference.photons / 1_000_000
    );
    assert!(t > 0.0, "{name}: the reference has no caustic");
    let direct = masked(frame("direct", &[]));
    let mut failures = Vec::new();
    for bound in bounds {
        let mode = bound.photon_mode;
        let full = masked(frame("image_space", &[format!("photon_mode={mode}")]));
        assert_finite(&full);
        let caustic: Vec<f32> = full.iter().zip(&direct).map(|(a, b)| a - b).collect();
        let rel = (energy(&caustic) - t) / t;
        let caustic_ldr = tonemap(&caustic);
        let (flip_mean, flip_map) = flip(&caustic_ldr, &truth_ldr, SIZE);
        println!(
            "{name}, photon_mode={mode}: caustic energy {:.2}, relative {rel:+.4} (bound {}); FLIP mean {flip_mean:.4} (bound {})",
            energy(&caustic),
            bound.energy,
            bound.flip
        );
        if rel.abs() >= bound.energy || flip_mean >= bound.flip {
            let dir = write_comparison_pngs(
                &format!("image_space_{name}_mode{mode}"),
                SIZE,
                &caustic_ldr,
                &truth_ldr,
                &flip_map,
            );
            failures.push(format!(
                "photon_mode={mode}: relative energy {rel:+.4}, FLIP mean {flip_mean:.4} (images in {dir})"
            ));
        }
    }
    assert!(failures.is_empty(), "{name}: {}", failures.join("; "));
    assert_validation_clean(&ctx);
}

// Bounds of the three comparisons: measured (see the file's header) plus a
// margin: energy |measured| + 0.02, FLIP mean 1.25 x measured, each rounded
// up to 0.005. The reference's seeds are fixed, so a rerun on lavapipe
// repeats the measurement; the margin covers other drivers' rounding and
// float-atomic order (the reference's two halves differ by up to 1% in
// energy). The bound far above the others records a known limit
// (gemstone, photon_mode 1: two interfaces for a diamond that traps its
// light, see the file's header), so that it cannot grow unnoticed.
#[test]
fn ball_lens_caustics_match_reference() {
    caustics_match_reference(
        "ball_lens",
        PHOTONS_BALL_LENS,
        &[
            Bound {
                photon_mode: 0,
                energy: 0.035,
                flip: 0.04,
            },
            Bound {
                photon_mode: 1,
                energy: 0.03,
                flip: 0.085,
            },
            Bound {
                photon_mode: 2,
                energy: 0.04,
                flip: 0.04,
            },
        ],
    );
}

#[test]
fn ring_caustics_match_reference() {
    caustics_match_reference(
        "ring",
        PHOTONS_RING,
        &[
            Bound {
                photon_mode: 0,
                energy: 0.035,
                flip: 0.095,
            },
            Bound {
                photon_mode: 1,
                energy: 0.035,
                flip: 0.095,
            },
        ],
    );
}

#[test]
fn gemstone_caustics_match_reference() {
    caustics_match_reference(
        "gemstone",
        PHOTONS_GEMSTONE,
        &[
            Bound {
                photon_mode: 0,
                energy: 0.025,
                flip: 0.06,
            },
            Bound {
                photon_mode: 1,
                energy: 5.73,
                flip: 0.225,
            },
        ],
    );
}

/// The default scene, a showcase (tinted glass, coloured receivers, a spot
/// light), in the default photon mode, which `auto` renders it with.
/// Measured on lavapipe: energy -0.0248, FLIP mean 0.0167 (the reference's
/// two halves: +0.0008 and 0.0139); at the 4M photons traced since
/// 2026-12-03: -0.0245, 0.0178 (halves -0.0029 and 0.0178); bounds as above.
#[test]
fn still_life_caustics_match_reference() {
    caustics_match_reference(
        "still_life",
        PHOTONS_STILL_LIFE,
        &[Bound {
            photon_mode: 0,
            energy: 0.045,
            flip: 0.025,
        }],
    );
}

/// Flux (W, red) that the point or spot light 0 of `s` sends through the
/// photon view of `f` into texels whose centre ray meets a specular surface
/// first (CPU BVH): I * falloff * Omega_texel, as photons.comp emits it.
fn flux_into_specular(f: &Frame, s: &Scene) -> f64 {
    use caustics::bvh::Bvh;
    use caustics::radiometry::spot_falloff;
    use caustics::scene::MaterialKind;
    let tris = s.triangles(0.0);
    let bvh = Bvh::build(&tris);
    let gpu = bvh.gpu_triangles(&tris);
    let light = s.lights[0];
    assert_ne!(light.kind, LightKind::Directional);
    let cos_outer = light.cone_angle_deg.to_radians().cos();
    let cos_inner = (light.cone_angle_deg - light.cone_falloff_deg)
        .max(0.0)
        .to_radians()
        .cos();
    let axis = light.direction.normalize();
    let v = f.tech.light_views.view(0).unwrap();
    let n = f.tech.caustics.photon_size;
    let (origin, right, up, forward) = (
        Vec3::from_slice(&v.origin[..3]),
        Vec3::from_slice(&v.right[..3]),
        Vec3::from_slice(&v.up[..3]),
        Vec3::from_slice(&v.forward[..3]),
    );
    let h = v.origin[3] as f64;
    let edge = |i: u32| (2.0 * i as f64 / n as f64 - 1.0) * h;
    let mut flux = 0.0;
    for j in 0..n {
        for i in 0..n {
            let (s0, s1, t0, t1) = (edge(i), edge(i + 1), edge(j), edge(j + 1));
            let d = (forward + (0.5 * (s0 + s1)) as f32 * right + (0.5 * (t0 + t1)) as f32 * up)
                .normalize();
            let specular = bvh
                .intersect(&gpu, origin, d, 0.0, f32::MAX)
                .is_some_and(|hit| {
                    let m = gpu[hit.triangle as usize].p0[3].to_bits() as usize;
                    s.materials[m].kind != MaterialKind::Diffuse
                });
            if specular {
                let falloff = match light.kind {
                    LightKind::Spot => spot_falloff(d.dot(axis), cos_outer, cos_inner) as f64,
                    _ => 1.0,
                };
                flux += light.intensity.x as f64 * falloff * rect_solid_angle(s0, s1, t0, t1);
            }
        }
    }
    flux
}

/// No photon mode creates energy: on assets/scenes/gemstone.toml (diamond,
/// where nearly every photon meets total internal reflection inside) the
/// flux of the photons landing on diffuse surfaces (both halves of the
/// buffer) must not exceed the flux entering the gem through the light
/// view, in every photon mode and, in mode 1, with every TIR remedy and
/// Eq. 6.3.2 on and off. Fresnel and Beer-Lambert only take flux away, and
/// TIR keeps it; a remedy or an approximated interface that gave more back
/// would exceed the bound.
#[test]
fn gemstone_photons_create_no_energy() {
    let ctx = validated_context();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/gemstone.toml");
    let s = Scene::load(&path).unwrap();
    let mut configs = vec![vec!["photon_mode=0".to_string()]];
    configs.push(vec!["photon_mode=2".to_string()]);
    for remedy in [
        b::TIR_SINGLE_REFRACTION,
        b::TIR_CLAMP_CRITICAL,
        b::TIR_REFLECT,
    ] {
        for eq632 in [0, 1] {
            configs.push(vec![
                "photon_mode=1".to_string(),
                format!("tir_remedy={remedy}"),
                format!("eq_6_3_2={eq632}"),
            ]);
        }
    }
    let mut entering = None;
    for config in &configs {
        let mut overrides: Vec<&str> = config.iter().map(|o| o.as_str()).collect();
        overrides.extend(["photon_buffer_size=256", "caustic_map_size=256"]);
        let f = render(&ctx, &s, &overrides);
        let entering = *entering.get_or_insert_with(|| flux_into_specular(&f, &s));
        let landed: f64 = photons(&f)
            .iter()
            .filter(|p| p.position[3] == 1.0)
            .map(|p| p.flux[0] as f64)
            .sum();
        println!(
            "{}: landed {landed:.4} W of {entering:.4} W entering the gem ({:.3})",
            config.join(" "),
            landed / entering
        );
        assert!(
            landed <= entering * 1.005,
            "{}: {landed} W landed, more than the {entering} W that entered",
            config.join(" ")
        );
    }
    assert_validation_clean(&ctx);
}

/// `caustics_on_change=1` on assets/scenes/gemstone.toml (animated: the gem
/// spins): a frame at an unchanged time skips the photon and splat passes
/// and gives the same image as recomputing; a new animation time or a moved
/// light recomputes, and matches a renderer that recomputes every frame.
#[test]
fn caustics_on_change_reuses_the_map_until_something_moves() {
    use caustics::renderer::Renderer;
    let ctx = validated_context();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/gemstone.toml");
    let renderer = |on_change: u32| {
        let overrides = [
            "photon_buffer_size=128".to_string(),
            "caustic_map_size=128".to_string(),
            format!("caustics_on_change={on_change}"),
        ];
        let params = Params::resolve("image_space", ImageSpaceParams::specs(), &overrides).unwrap();
        Renderer::new(
            &ctx,
            Scene::load(&path).unwrap(),
            "image_space",
            &params,
            64,
            64,
            0.0,
        )
        .unwrap()
    };
    let mut cached = renderer(1);
    let mut every_frame = renderer(0);
    // Renders both at `time`; checks whether `cached` shot photons and that
    // its image equals the recomputed one; returns that image.
    let frame = |cached: &mut Renderer,
                 every_frame: &mut Renderer,
                 time: f32,
                 recomputes: bool,
                 what: &str| {
        let shot = |r: &mut Renderer| {
            r.render_frame(time)
                .unwrap()
                .iter()
                .any(|t| t.name == "caustic photons")
        };
        assert_eq!(
            shot(cached),
            recomputes,
            "{what}: caustic photons recorded?"
        );
        assert!(shot(every_frame));
        let (a, b) = (cached.radiance().unwrap(), every_frame.radiance().unwrap());
        assert_finite(&a);
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max);
        println!("{what}: photons shot {recomputes}, largest difference from recomputing {worst:e}, energy {:.4}", energy(&a));
        assert_eq!(a, b, "{what}: image differs from a recomputed caustic map");
        a
    };
    let first = frame(&mut cached, &mut every_frame, 0.0, true, "first frame");
    frame(
        &mut cached,
        &mut every_frame,
        0.0,
        false,
        "same time, nothing moved",
    );
    let rotated = frame(
        &mut cached,
        &mut every_frame,
        0.5,
        true,
        "gem rotated (time 0.5 s)",
    );
    frame(&mut cached, &mut every_frame, 0.5, false, "same time again");
    for r in [&mut cached, &mut every_frame] {
        r.scene.lights[0].position += Vec3::new(0.4, 0.0, -0.3);
        r.lights_changed(0.5).unwrap();
    }
    let moved = frame(&mut cached, &mut every_frame, 0.5, true, "light moved");
    frame(
        &mut cached,
        &mut every_frame,
        0.5,
        false,
        "after the move, nothing moved",
    );
    // The changes were visible, so a stale map would have failed above.
    assert_ne!(first, rotated);
    assert_ne!(rotated, moved);
    assert_validation_clean(&ctx);
}

const RING_RADIUS: f64 = 1.0;
const RING_HEIGHT: f64 = 0.5;
const RING_REFLECTANCE: f32 = 0.9;
/// Slope of the ring test's directional light: tan(elevation) = 1/2.
const RING_LIGHT_SLOPE: f64 = 0.5;
const RING_IRRADIANCE: f32 = 3.0;

/// Expected flux reflected by the inside of an analytic open cylinder
/// (radius R, height H, base on the floor, mirror reflectance rho) onto the
/// floor inside it, for directional light along (1, -slope, 0) of irradiance
/// E: every ray entering through the top disk (flux E sin(elevation) per unit
/// area of the disk) is followed through its reflections (the horizontal
/// direction mirrors about the wall's normal, the descent per horizontal
/// metre stays `slope`) until it reaches the floor; it carries rho^k after k
/// reflections and counts if k >= 1. Midpoint rule on an n x n grid.
fn ring_reflected_flux(n: usize) -> f64 {
    let (r, slope) = (RING_RADIUS, RING_LIGHT_SLOPE);
    let sin_elev = slope / (1.0 + slope * slope).sqrt();
    let cell = 2.0 * r / n as f64;
    let mut flux = 0.0;
    for i in 0..n {
        for j in 0..n {
            let (mut x, mut z) = (-r + (i as f64 + 0.5) * cell, -r + (j as f64 + 0.5) * cell);
            if x * x + z * z >= r * r {
                continue;
            }
            let (mut dx, mut dz, mut y, mut weight) = (1.0f64, 0.0f64, RING_HEIGHT, 1.0f64);
            let mut reflections = 0;
            loop {
                // Horizontal distance to the wall along (dx, dz) from inside.
                let b = x * dx + z * dz;
                let l = -b + (b * b - (x * x + z * z - r * r)).sqrt();
                let y_wall = y - l * slope;
                if y_wall <= 0.0 {
                    break; // lands on the floor before the wall
                }
                x += l * dx;
                z += l * dz;
                y = y_wall;
                let (nx, nz) = (-x / r, -z / r);
                let dn = dx * nx + dz * nz;
                dx -= 2.0 * dn * nx;
                dz -= 2.0 * dn * nz;
                weight *= RING_REFLECTANCE as f64;
                reflections += 1;
            }
            if reflections > 0 {
                flux += weight;
            }
        }
    }
    flux * RING_IRRADIANCE as f64 * sin_elev * cell * cell
}

/// A mirror ring (open cylinder, r = 1 m, 0.5 m tall, 128 segments,
/// reflectance 0.9) on a 3 x 3 m floor under directional light at elevation
/// atan(1/2) travelling along +x. Seen from above, parallel light reflected
/// inside a circle forms a nephroid whose cusp is the paraxial focus of the
/// concave mirror, R/2 from the wall, i.e. at (R/2, 0, 0). The wall is
/// vertical, so reflection keeps the descent per horizontal metre: a ray
/// meeting the wall at height h lands h / slope further on. The floor
/// therefore shows the plan-view ray pattern wherever the landing distances
/// reach it, and the cusp is on the floor if some paraxial ray meets the
/// wall at h = slope R / 2 = 0.25 m: the wall is lit from the floor to its
/// top (light passing over the near wall drops 2 R slope = 1 m by the far
/// wall), so it is.
#[test]
fn mirror_ring_cardioid_cusp() {
    let ctx = validated_context();
    let mirror = caustics::scene::Material {
        name: "chrome".into(),
        kind: caustics::scene::MaterialKind::Mirror,
        color: Vec3::splat(RING_REFLECTANCE),
        ior: 1.0,
        absorption: Vec3::ZERO,
        texture: None,
        emission: glam::Vec3::ZERO,
        specular: glam::Vec3::ZERO,
        scattering: None,
    };
    let mut ring = caustics::scene::shapes::cylinder(
        Vec3::ZERO,
        Vec3::new(0.0, RING_HEIGHT as f32, 0.0),
        RING_RADIUS as f32,
        false,
        128,
    );
    ring.materials = vec![1; ring.indices.len()];
    let light_dir = Vec3::new(1.0, -RING_LIGHT_SLOPE as f32, 0.0);
    let s = scene(
        camera(Vec3::new(0.0, 4.0, 2.5), Vec3::ZERO, 40.0),
        vec![directional_light(light_dir, RING_IRRADIANCE)],
        vec![diffuse("floor", ALBEDO), mirror],
        vec![
            object("floor", floor_mesh(1.5, 0.0, 0)),
            object("ring", ring),
        ],
    );
    let splat = 3u32;
    let f = render(
        &ctx,
        &s,
        &[
            "photon_buffer_size=512",
            "caustic_map_size=512",
            &format!("splat_size={splat}"),
        ],
    );

    // Flux: the photons reflected onto the floor inside the ring carry
    // rho^k of the flux entering through its top. Bound 1%: the 128-gon's
    // opening is 0.04% smaller than the circle, and the photon grid (5.7 mm)
    // resolves the aperture's rim and the rays' landing inside or beyond
    // the wall to well under 1%.
    let ph = photons(&f);
    let n2 = ph.len() / 2;
    let landed = |inside: bool| -> f64 {
        ph[n2..]
            .iter()
            .filter(|p| p.position[3] == 1.0)
            .filter(|p| (p.position[0].hypot(p.position[2]) < RING_RADIUS as f32) == inside)
            .map(|p| p.flux[0] as f64)
            .sum()
    };
    let (inside, outside) = (landed(true), landed(false));
    let expected = ring_reflected_flux(2000);
    let rel = (inside - expected) / expected;
    println!(
        "reflected flux landing inside the ring {inside:.4} W (outside, off the convex outer wall: {outside:.4} W), analytic {expected:.4} W, relative {rel:+.2e}"
    );
    assert!(
        rel.abs() < 0.02,
        "reflected flux inside the ring off by {rel}"
    );

    // The cusp: the brightest caustic-map texel (orthographic view, one
    // layer), taken to the floor along the light.
    let size = f.tech.caustics.map_size;
    let view = f
        .tech
        .caustics
        .views(f.tech.light_views.lights(), f.scene_gpu.sphere)[0];
    let inv = glam::Mat4::from_cols_array_2d(&view.view_proj[0]).inverse();
    let d = light_dir.normalize();
    let to_floor = |tx: f32, ty: f32| {
        let ndc = |t: f32| 2.0 * (t + 0.5) / size as f32 - 1.0;
        let p = inv.project_point3(Vec3::new(ndc(tx), ndc(ty), 0.5));
        p + d * (-p.y / d.y)
    };
    let texels = f.tech.caustics.map.download_layer_rgba32f(0).unwrap();
    let (mut best, mut best_flux) = ((0, 0), 0.0f32);
    for ty in 0..size {
        for tx in 0..size {
            let flux = texels[((ty * size + tx) * 4) as usize];
            if flux > best_flux {
                (best, best_flux) = ((tx, ty), flux);
            }
        }
    }
    let peak = to_floor(best.0 as f32, best.1 as f32);
    // Tolerance: a splat blurs over (S/2) texels either side of a photon, and
    // away from the cusp the irradiance falls off along the axis on both sides,
    // so the blurred maximum lies within S/2 texels of it; plus half a texel
    // for the texel grid. A texel's floor footprint, per axis, from its
    // neighbours (the view is slanted: it stretches along x by 1/sin(elevation)).
    let (u, v) = (
        to_floor(1.0, 0.0) - to_floor(0.0, 0.0),
        to_floor(0.0, 1.0) - to_floor(0.0, 0.0),
    );
    let reach = (splat as f32 + 1.0) / 2.0;
    let tol_x = reach * (u.x.abs() + v.x.abs());
    let tol_z = reach * (u.z.abs() + v.z.abs());
    let cusp = Vec3::new(RING_RADIUS as f32 / 2.0, 0.0, 0.0);
    println!(
        "brightest caustic texel on the floor at ({:.4}, {:.4}); cusp (paraxial focus) at ({:.4}, 0): off by ({:+.4}, {:+.4}) m, tolerance ({tol_x:.4}, {tol_z:.4}) m",
        peak.x,
        peak.z,
        cusp.x,
        peak.x - cusp.x,
        peak.z
    );
    assert!((peak.x - cusp.x).abs() < tol_x, "cusp x: {}", peak.x);
    assert!(peak.z.abs() < tol_z, "cusp z: {}", peak.z);
    assert!(
        peak.x.hypot(peak.z) < RING_RADIUS as f32,
        "caustic outside the ring"
    );
    assert_validation_clean(&ctx);
}

/// An open water sheet (IOR 1.33, 2 m x 2 m at y = 1, no bottom: empty
/// back-face texels and d_N = 0) under a directional light straight down
/// (E = 3 W/m^2): every photon mode lands (1 - F(0)) E A = 11.759 W on the
/// floor (one interface, normal incidence). Before the single-interface
/// rule photon modes 1 and 2 dropped every such photon (0 W). Measured
/// 11.8609 W in all three modes (+8.6e-3: photon texels whose centre meets
/// the sheet carry their whole area across its edges); bounds: 2% against
/// the analytic flux, 1e-4 between modes 1/2 and the traced mode 0.
#[test]
fn open_sheet_photons_refract_once_in_every_mode() {
    let ctx = validated_context();
    let s = scene(
        camera(Vec3::new(0.0, 3.0, 3.0), Vec3::new(0.0, 0.5, 0.0), 40.0),
        vec![directional_light(Vec3::NEG_Y, 3.0)],
        vec![diffuse("floor", ALBEDO), dielectric("water", 1.33)],
        vec![
            object("floor", floor_mesh(5.0, 0.0, 0)),
            object("water surface", floor_mesh(1.0, 1.0, 1)),
        ],
    );
    let expected = (1.0 - fresnel_dielectric(1.0, 1.0 / 1.33) as f64) * 3.0 * 4.0;
    let mut traced = 0.0;
    for mode in 0..3 {
        let m = format!("photon_mode={mode}");
        let f = render(
            &ctx,
            &s,
            &["photon_buffer_size=256", "caustic_map_size=256", &m],
        );
        let ph = photons(&f);
        let refracted: f64 = ph[..ph.len() / 2]
            .iter()
            .filter(|p| p.position[3] == 1.0 && p.position[1].abs() < 1e-3)
            .map(|p| p.flux[0] as f64)
            .sum();
        let rel = (refracted - expected).abs() / expected;
        println!("open sheet, photon_mode {mode}: refracted flux on the floor {refracted:.4} W, analytic (1 - F(0)) E A {expected:.4} W, relative error {rel:.2e}");
        assert!(rel < 0.02, "photon_mode {mode}: relative error {rel}");
        if mode == 0 {
            traced = refracted;
        }
        let vs_traced = (refracted - traced).abs() / traced;
        assert!(
            vs_traced < 1e-4,
            "photon_mode {mode} vs traced: {vs_traced}"
        );
    }
    assert_validation_clean(&ctx);
}
