//! The `direct` technique against analytic direct light: a diffuse plane lit
//! by a point, spot and directional light (L = albedo / pi * E), and a box
//! casting a shadow. Each test renders 128² on lavapipe with validation on,
//! default parameters (1024² shadow maps, PCF radius 1).
//!
//! Measured (lavapipe, Mesa 22.3.6; `cargo test --test direct -- --nocapture`):
//! - unoccluded plane, max relative error: point 1.2e-6, spot 1.4e-4 (its
//!   smoothstep edge is the most sensitive to position rounding), wide spot
//!   (cube) 1.2e-5, grazing directional (76°) 6e-8; the bound is 1%.
//! - box shadow, lit pixels: max relative error <= 2.0e-4; shadowed pixels:
//!   0 (exactly) where fully occluded; the bound is 1% of the lit value.
//! - shadow edges fall within 2 cm of the analytic edge at the box (the
//!   tests pass with a 2 cm margin and fail at 1 cm for the directional
//!   light, whose 1024² map spans the 11 m scene sphere: 1.1 cm per texel);
//!   the tests use 3 cm.
//! - with the bias switched off, lit pixels are off by up to 78% (acne), so
//!   these tests do see acne.

use caustics::frame::camera_matrices;
use caustics::params::{ParamSet, Params};
use caustics::radiometry::spot_falloff;
use caustics::renderer::Renderer;
use caustics::scene::{
    Camera, Light, LightKind, Material, MaterialKind, Mesh, Object, Output, Scene,
};
use caustics::techniques;
use caustics::vk::{Context, ContextOptions};
use glam::{DVec3, DVec4, Mat4, Vec3};
use std::f64::consts::PI;
use std::sync::Arc;

const SIZE: u32 = 128;
const ALBEDO: f32 = 0.5;
const PLANE_HALF: f32 = 4.0;
const BOX_MIN: Vec3 = Vec3::new(0.6, 0.0, -0.4);
const BOX_MAX: Vec3 = Vec3::new(1.4, 0.8, 0.4);

fn diffuse(name: &str) -> Material {
    Material {
        name: name.into(),
        kind: MaterialKind::Diffuse,
        color: Vec3::splat(ALBEDO),
        ior: 1.0,
        absorption: Vec3::ZERO,
        texture: None,
        emission: glam::Vec3::ZERO,
        specular: glam::Vec3::ZERO,
        scattering: None,
    }
}

fn plane() -> Object {
    let h = PLANE_HALF;
    Object {
        name: "floor".into(),
        mesh: Mesh {
            positions: vec![
                Vec3::new(-h, 0.0, -h),
                Vec3::new(h, 0.0, -h),
                Vec3::new(h, 0.0, h),
                Vec3::new(-h, 0.0, h),
            ],
            normals: vec![Vec3::Y; 4],
            uvs: Vec::new(),
            indices: vec![[0, 2, 1], [0, 3, 2]],
            materials: vec![0, 0],
        },
        transform: Mat4::IDENTITY,
        animation: None,
        water: None,
    }
}

/// An axis-aligned box with flat face normals (24 vertices, 12 triangles).
fn cuboid(lo: Vec3, hi: Vec3) -> Object {
    let mut mesh = Mesh::default();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = mesh.positions.len() as u32;
            for (a, b) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
                let mut p = Vec3::ZERO;
                p[axis] = if sign > 0.0 { hi[axis] } else { lo[axis] };
                p[u] = if a == 0 { lo[u] } else { hi[u] };
                p[v] = if b == 0 { lo[v] } else { hi[v] };
                mesh.positions.push(p);
                mesh.normals.push(n);
            }
            mesh.indices.push([base, base + 1, base + 2]);
            mesh.indices.push([base, base + 2, base + 3]);
            mesh.materials.extend([0, 0]);
        }
    }
    Object {
        name: "box".into(),
        mesh,
        transform: Mat4::IDENTITY,
        animation: None,
        water: None,
    }
}

fn scene(lights: Vec<Light>, with_box: bool) -> Scene {
    let mut objects = vec![plane()];
    if with_box {
        objects.push(cuboid(BOX_MIN, BOX_MAX));
    }
    Scene {
        source: "tests/direct.rs".into(),
        camera: Camera {
            eye: Vec3::new(0.0, 4.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 60.0,
        },
        lights,
        materials: vec![diffuse("floor")],
        objects,
        medium: None,
        output: Output { exposure: 1.0 },
        environment: None,
        emitters: Vec::new(),
        textures: Vec::new(),
    }
}

fn point_light() -> Light {
    Light {
        kind: LightKind::Point,
        position: Vec3::new(0.0, 2.0, 0.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::new(10.0, 6.0, 3.0),
        cone_angle_deg: 0.0,
        cone_falloff_deg: 0.0,
    }
}

/// Renders `scene` with the default parameters; returns RGBA radiance rows
/// top to bottom, after checking it holds no NaN/Inf.
fn render(scene: Scene) -> (Arc<Context>, Vec<f32>) {
    render_with(scene, &[])
}

/// `render` with parameter overrides ("name=value"). Renders two frames, so
/// the second one's barriers start from the first one's final states.
fn render_with(scene: Scene, overrides: &[&str]) -> (Arc<Context>, Vec<f32>) {
    // Validation messages go through `log`: show them when a test fails.
    let _ = env_logger::builder().is_test(true).try_init();
    let ctx = Context::new(&ContextOptions {
        validation: true,
        sync_validation: true,
        device: None,
    })
    .expect("Vulkan context (lavapipe)");
    let overrides: Vec<String> = overrides.iter().map(|o| o.to_string()).collect();
    let params = Params::resolve(
        "direct",
        techniques::direct::DirectParams::specs(),
        &overrides,
    )
    .unwrap();
    let radiance = {
        let mut renderer = Renderer::new(&ctx, scene, "direct", &params, SIZE, SIZE, 0.0).unwrap();
        renderer.render_frame(0.0).unwrap();
        renderer.render_frame(0.0).unwrap();
        renderer.radiance().unwrap()
    };
    assert_eq!(radiance.len(), (SIZE * SIZE * 4) as usize);
    assert!(
        radiance.iter().all(|v| v.is_finite()),
        "NaN or Inf in the radiance"
    );
    (ctx, radiance)
}

/// Camera ray (origin, unit direction) through the centre of pixel (px, py),
/// row 0 the top (the projection's y is flipped).
fn camera_ray(camera: &Camera, px: u32, py: u32) -> (DVec3, DVec3) {
    let (view, proj) = camera_matrices(camera, 1.0);
    let inv = (proj * view).as_dmat4().inverse();
    let x = 2.0 * (px as f64 + 0.5) / SIZE as f64 - 1.0;
    let y = 2.0 * (py as f64 + 0.5) / SIZE as f64 - 1.0;
    let unproject = |z: f64| {
        let p = inv * DVec4::new(x, y, z, 1.0);
        p.truncate() / p.w
    };
    let origin = camera.eye.as_dvec3();
    (origin, (unproject(0.5) - unproject(0.0)).normalize())
}

/// Where the ray meets the plane y = 0, if inside the floor by `margin`.
fn hit_floor(o: DVec3, d: DVec3, margin: f64) -> Option<DVec3> {
    if d.y >= 0.0 {
        return None;
    }
    let x = o + d * (-o.y / d.y);
    let h = PLANE_HALF as f64 - margin;
    (x.x.abs() < h && x.z.abs() < h).then_some(x)
}

/// Whether the segment o + t d, t in (t0, t1), meets the box grown by `grow`.
fn segment_hits_box(o: DVec3, d: DVec3, t0: f64, t1: f64, grow: f64) -> bool {
    let lo = BOX_MIN.as_dvec3() - grow;
    let hi = BOX_MAX.as_dvec3() + grow;
    let (mut near, mut far) = (t0, t1);
    for a in 0..3 {
        if d[a].abs() < 1e-12 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return false;
            }
            continue;
        }
        let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        near = near.max(ta.min(tb));
        far = far.min(ta.max(tb));
    }
    near < far
}

/// Unshadowed irradiance (W/m², rgb) from `light` at floor point x (normal +y).
fn irradiance(light: &Light, x: DVec3) -> DVec3 {
    let n = DVec3::Y;
    let intensity = light.intensity.as_dvec3();
    match light.kind {
        LightKind::Directional => {
            intensity * n.dot(-light.direction.as_dvec3().normalize()).max(0.0)
        }
        LightKind::Point | LightKind::Spot => {
            let v = light.position.as_dvec3() - x;
            let r2 = v.length_squared();
            let l = v / r2.sqrt();
            let mut i = intensity;
            if light.kind == LightKind::Spot {
                let cos_outer = light.cone_angle_deg.to_radians().cos();
                let cos_inner = (light.cone_angle_deg - light.cone_falloff_deg)
                    .max(0.0)
                    .to_radians()
                    .cos();
                let c = (-l).dot(light.direction.as_dvec3().normalize()) as f32;
                i *= spot_falloff(c, cos_outer, cos_inner) as f64;
            }
            i * n.dot(l).max(0.0) / r2
        }
    }
}

fn pixel(radiance: &[f32], px: u32, py: u32) -> DVec3 {
    let i = ((py * SIZE + px) * 4) as usize;
    DVec3::new(
        radiance[i] as f64,
        radiance[i + 1] as f64,
        radiance[i + 2] as f64,
    )
}

/// Compares every floor pixel with L = albedo / pi * E (no occluders): the
/// largest relative error per channel among pixels brighter than 1e-3 of the
/// peak, and the largest absolute error (relative to the peak) elsewhere.
/// Pixels whose ray misses the floor must read 0.
fn check_analytic(light: Light) -> (f64, usize) {
    let s = scene(vec![light], false);
    let camera = s.camera;
    let (ctx, radiance) = render(s);
    let mut expected = Vec::new();
    for py in 0..SIZE {
        for px in 0..SIZE {
            let (o, d) = camera_ray(&camera, px, py);
            match hit_floor(o, d, 1e-3) {
                Some(x) => {
                    let l = irradiance(&light, x) * (ALBEDO as f64 / PI);
                    expected.push((px, py, Some(l)));
                }
                None if hit_floor(o, d, -1e-3).is_none() => expected.push((px, py, None)),
                None => {} // on the floor's rim: coverage is a rasteriser's call
            }
        }
    }
    let peak = expected
        .iter()
        .filter_map(|e| e.2)
        .map(|l| l.max_element())
        .fold(0.0, f64::max);
    assert!(peak > 0.0);
    let (mut max_rel, mut max_abs, mut compared) = (0.0f64, 0.0f64, 0);
    for (px, py, e) in expected {
        let got = pixel(&radiance, px, py);
        match e {
            Some(l) => {
                for c in 0..3 {
                    if l[c] > 1e-3 * peak {
                        max_rel = max_rel.max((got[c] - l[c]).abs() / l[c]);
                    } else {
                        max_abs = max_abs.max((got[c] - l[c]).abs() / peak);
                    }
                }
                compared += 1;
            }
            None => assert_eq!(got, DVec3::ZERO, "background pixel ({px}, {py})"),
        }
    }
    println!(
        "{:?}: {compared} floor pixels, max relative error {max_rel:.2e}, max dark-pixel error {max_abs:.2e} of peak",
        light.kind
    );
    assert!(compared > SIZE as usize * SIZE as usize / 3);
    assert!(max_rel <= 0.01, "max relative error {max_rel}");
    assert!(max_abs <= 1e-3, "dark-pixel error {max_abs} of peak");
    assert_eq!(ctx.validation_counts().errors, 0, "validation errors");
    (max_rel, compared)
}

#[test]
fn point_light_on_plane_matches_analytic() {
    check_analytic(point_light());
}

#[test]
fn spot_light_on_plane_matches_analytic() {
    check_analytic(Light {
        kind: LightKind::Spot,
        position: Vec3::new(0.5, 2.0, 0.0),
        direction: Vec3::new(-0.3, -1.0, 0.2).normalize(),
        intensity: Vec3::new(8.0, 8.0, 5.0),
        cone_angle_deg: 40.0,
        cone_falloff_deg: 10.0,
    });
}

#[test]
fn wide_spot_light_uses_a_cube_and_matches_analytic() {
    // Wider than SPOT_CUBE_THRESHOLD_DEG: rendered as a cube like a point light.
    check_analytic(Light {
        kind: LightKind::Spot,
        position: Vec3::new(0.0, 1.5, 0.0),
        direction: Vec3::new(0.2, -1.0, -0.1).normalize(),
        intensity: Vec3::new(5.0, 5.0, 5.0),
        cone_angle_deg: 75.0,
        cone_falloff_deg: 15.0,
    });
}

#[test]
fn directional_light_on_plane_matches_analytic() {
    check_analytic(Light {
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        // Grazing (76° from the normal): stresses the slope-scaled bias.
        direction: Vec3::new(1.0, -0.25, 0.3).normalize(),
        intensity: Vec3::new(3.0, 2.0, 1.0),
        cone_angle_deg: 0.0,
        cone_falloff_deg: 0.0,
    });
}

/// The floor with the box on it, lit by `lights`. Per floor pixel the
/// expected radiance is the sum over the lights that see the floor point
/// (analytically: the segment to the light misses the box). Pixels within
/// `margin` of a shadow edge of any light are skipped; elsewhere:
/// - where the expected value is above 1e-3 of the peak, it agrees within 1%;
/// - everywhere, |got - expected| < 1% of the unshadowed sum (floored at
///   1e-3 of the peak), so fully shadowed pixels read under 1% of the lit value.
fn check_box_shadow(lights: &[Light]) {
    // Margin around the box (m) inside which a shadow edge may fall: the PCF
    // window and bias, a few shadow texels (5-11 mm each at 1024² here).
    check_box_shadow_with(lights, &[], 0.03);
}

fn check_box_shadow_with(lights: &[Light], overrides: &[&str], margin: f64) {
    let s = scene(lights.to_vec(), true);
    let camera = s.camera;
    let (ctx, radiance) = render_with(s, overrides);
    let lambert = ALBEDO as f64 / PI;
    // Floor points the camera sees clear of the box (by `margin`).
    let mut floor = Vec::new();
    for py in 0..SIZE {
        for px in 0..SIZE {
            let (o, d) = camera_ray(&camera, px, py);
            if let Some(x) = hit_floor(o, d, 1e-3) {
                if !segment_hits_box(o, d, 0.0, (x - o).length(), margin) {
                    floor.push((px, py, x));
                }
            }
        }
    }
    let peak = floor
        .iter()
        .map(|&(_, _, x)| {
            let e: DVec3 = lights.iter().map(|l| irradiance(l, x)).sum();
            e.max_element() * lambert
        })
        .fold(0.0, f64::max);
    let (mut shadowed, mut lit) = (0, 0);
    let (mut max_shadow_err, mut max_lit_rel) = (0.0f64, 0.0f64);
    'pixels: for (px, py, x) in floor {
        let (mut expected, mut total, mut occluded) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for light in lights {
            let (dir, dist) = match light.kind {
                LightKind::Directional => (-light.direction.as_dvec3().normalize(), 1e9),
                _ => {
                    let v = light.position.as_dvec3() - x;
                    (v.normalize(), v.length())
                }
            };
            let l = irradiance(light, x) * lambert;
            total += l;
            if segment_hits_box(x, dir, 1e-6, dist, -margin) {
                occluded += l;
            } else if segment_hits_box(x, dir, 1e-6, dist, margin) {
                continue 'pixels; // near this light's shadow edge
            } else {
                expected += l;
            }
        }
        let got = pixel(&radiance, px, py);
        if occluded.max_element() > 0.1 * total.max_element() {
            shadowed += 1;
        }
        for c in 0..3 {
            max_shadow_err =
                max_shadow_err.max((got[c] - expected[c]).abs() / total[c].max(1e-3 * peak));
            // Deep in a spot's falloff, relative error means nothing.
            if expected[c] > 1e-3 * peak {
                lit += usize::from(c == 0);
                max_lit_rel = max_lit_rel.max((got[c] - expected[c]).abs() / expected[c]);
            }
        }
    }
    let kinds: Vec<_> = lights.iter().map(|l| l.kind).collect();
    println!(
        "{kinds:?} box shadow: {shadowed} shadowed pixels, max |error| {max_shadow_err:.2e} of the unshadowed value; {lit} lit pixels, max relative error {max_lit_rel:.2e}"
    );
    assert!(
        shadowed > 25,
        "too few shadowed pixels to judge: {shadowed}"
    );
    assert!(lit > 1000, "too few lit pixels to judge: {lit}");
    assert!(
        max_shadow_err < 0.01,
        "a pixel is off by {max_shadow_err} of its unshadowed value"
    );
    assert!(max_lit_rel <= 0.01, "lit pixel off by {max_lit_rel}");
    assert_eq!(ctx.validation_counts().errors, 0, "validation errors");
}

fn spot_at_box() -> Light {
    Light {
        kind: LightKind::Spot,
        position: Vec3::new(0.0, 2.0, 0.0),
        direction: Vec3::new(1.2, -2.0, 0.0).normalize(),
        intensity: Vec3::new(8.0, 6.0, 4.0),
        cone_angle_deg: 50.0,
        cone_falloff_deg: 10.0,
    }
}

fn low_sun() -> Light {
    Light {
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: Vec3::new(1.0, -0.6, 0.3).normalize(),
        intensity: Vec3::new(3.0, 2.0, 1.0),
        cone_angle_deg: 0.0,
        cone_falloff_deg: 0.0,
    }
}

#[test]
fn box_casts_a_shadow_from_a_point_light() {
    check_box_shadow(&[point_light()]);
}

#[test]
fn box_casts_a_shadow_from_a_spot_light() {
    check_box_shadow(&[spot_at_box()]);
}

#[test]
fn box_casts_a_shadow_from_a_directional_light() {
    check_box_shadow(&[low_sun()]);
}

#[test]
fn three_lights_sum_with_their_own_shadows() {
    // Lights 1 and 2 read layers 6 and 12 of the shadow array: checks the
    // per-light layer offsets and the sum over lights.
    let spot = Light {
        position: Vec3::new(-1.5, 2.5, 1.0),
        direction: Vec3::new(2.5, -2.5, -1.0).normalize(),
        ..spot_at_box()
    };
    check_box_shadow(&[point_light(), spot, low_sun()]);
}

#[test]
fn wide_pcf_on_small_maps_keeps_lit_and_shadowed_regions_exact() {
    // 256² maps and a 9x9 PCF window: the bias grows with the window, so
    // fully lit and fully shadowed pixels stay exact; only the penumbra
    // widens (about 2 cm per texel at the box, +-4.5 texels).
    check_box_shadow_with(
        &[point_light()],
        &["shadow_map_size=256", "pcf_radius=4"],
        0.12,
    );
}

/// A live parameter (`pcf_radius`, a push constant) changes in place: no
/// rebuild, and the frame equals, bit for bit, that of a technique built
/// with the new value. A rebuild parameter among the changes rebuilds.
#[test]
fn live_parameters_apply_without_a_rebuild() {
    let (ctx, _) = render(scene(vec![point_light()], true));
    let specs = techniques::direct::DirectParams::specs();
    let params = |o: &[&str]| {
        let o: Vec<String> = o.iter().map(|s| s.to_string()).collect();
        Params::resolve("direct", specs, &o).unwrap()
    };
    let frame = |r: &mut Renderer| {
        r.render_frame(0.0).unwrap();
        r.radiance().unwrap()
    };
    let s = scene(vec![point_light()], true);
    let mut live = Renderer::new(&ctx, s.clone(), "direct", &params(&[]), SIZE, SIZE, 0.0).unwrap();
    let before = frame(&mut live);
    assert!(
        !live.set_params(&params(&["pcf_radius=3"])).unwrap(),
        "pcf_radius is live"
    );
    assert_eq!(live.params(), &params(&["pcf_radius=3"]));
    let after = frame(&mut live);
    assert_ne!(
        before, after,
        "a wider PCF filter changes the shadow's edge"
    );
    let mut built = Renderer::new(
        &ctx,
        s,
        "direct",
        &params(&["pcf_radius=3"]),
        SIZE,
        SIZE,
        0.0,
    )
    .unwrap();
    assert_eq!(after, frame(&mut built));
    assert!(
        live.set_params(&params(&["pcf_radius=2", "shadow_map_size=512"]))
            .unwrap(),
        "shadow_map_size needs a rebuild"
    );
    frame(&mut live);
    drop((live, built));
    let counts = ctx.validation_counts();
    assert_eq!(counts.errors, 0, "{:?}", ctx.validation_errors());
}
