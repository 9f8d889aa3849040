//! Helpers shared by the integration tests: a validated lavapipe context,
//! scenes built in code, camera rays, and image statistics.
#![allow(dead_code)]

pub mod gltf_builder;
pub mod reference_cache;
pub use reference_cache::{
    camera_side, reference_images, ReferenceImages, ReferenceRequest, CAMERA_SIDE_BATCH,
};

use caustics::frame::camera_matrices;
use caustics::scene::*;
use caustics::vk::{Context, ContextOptions};
use glam::{Mat4, Vec3};
use std::path::PathBuf;
use std::sync::Arc;

/// A context with the Khronos validation layer on; tests end with `assert_validation_clean`.
/// A context with the validation layer and its synchronization validation
/// on: any error, a hazard between commands included, fails the test
/// (`assert_validation_clean`).
pub fn validated_context() -> Arc<Context> {
    let ctx = Context::new(&ContextOptions {
        validation: true,
        sync_validation: true,
        device: None,
    })
    .expect("Vulkan context with validation");
    if !ctx.sync_validation {
        eprintln!("note: the validation layer offers no synchronization validation");
    }
    ctx
}

pub fn assert_validation_clean(ctx: &Context) {
    let counts = ctx.validation_counts();
    assert_eq!(
        counts.errors,
        0,
        "the validation layer reported {} error(s):\n{}",
        counts.errors,
        ctx.validation_errors().join("\n")
    );
}

pub fn diffuse(name: &str, albedo: f32) -> Material {
    Material {
        name: name.into(),
        kind: MaterialKind::Diffuse,
        color: Vec3::splat(albedo),
        ior: 1.0,
        absorption: Vec3::ZERO,
        texture: None,
        emission: glam::Vec3::ZERO,
        specular: glam::Vec3::ZERO,
        scattering: None,
    }
}

pub fn dielectric(name: &str, ior: f32) -> Material {
    Material {
        name: name.into(),
        kind: MaterialKind::Dielectric,
        color: Vec3::ONE,
        ior,
        absorption: Vec3::ZERO,
        texture: None,
        emission: glam::Vec3::ZERO,
        specular: glam::Vec3::ZERO,
        scattering: None,
    }
}

/// An axis-aligned rectangle at height `y`, normal +y, centred on the origin.
pub fn floor_mesh(half: f32, y: f32, material: u32) -> Mesh {
    Mesh {
        positions: vec![
            Vec3::new(-half, y, -half),
            Vec3::new(half, y, -half),
            Vec3::new(half, y, half),
            Vec3::new(-half, y, half),
        ],
        normals: vec![Vec3::Y; 4],
        uvs: Vec::new(),
        indices: vec![[0, 2, 1], [0, 3, 2]],
        materials: vec![material; 2],
    }
}

/// A closed axis-aligned box with flat outward normals.
pub fn box_mesh(min: Vec3, max: Vec3, material: u32) -> Mesh {
    let mut m = Mesh::default();
    let faces: [(Vec3, [Vec3; 4]); 6] = [
        (
            Vec3::X,
            [
                Vec3::new(max.x, min.y, min.z),
                Vec3::new(max.x, max.y, min.z),
                Vec3::new(max.x, max.y, max.z),
                Vec3::new(max.x, min.y, max.z),
            ],
        ),
        (
            Vec3::NEG_X,
            [
                Vec3::new(min.x, min.y, max.z),
                Vec3::new(min.x, max.y, max.z),
                Vec3::new(min.x, max.y, min.z),
                Vec3::new(min.x, min.y, min.z),
            ],
        ),
        (
            Vec3::Y,
            [
                Vec3::new(min.x, max.y, min.z),
                Vec3::new(min.x, max.y, max.z),
                Vec3::new(max.x, max.y, max.z),
                Vec3::new(max.x, max.y, min.z),
            ],
        ),
        (
            Vec3::NEG_Y,
            [
                Vec3::new(min.x, min.y, max.z),
                Vec3::new(min.x, min.y, min.z),
                Vec3::new(max.x, min.y, min.z),
                Vec3::new(max.x, min.y, max.z),
            ],
        ),
        (
            Vec3::Z,
            [
                Vec3::new(max.x, min.y, max.z),
                Vec3::new(max.x, max.y, max.z),
                Vec3::new(min.x, max.y, max.z),
                Vec3::new(min.x, min.y, max.z),
            ],
        ),
        (
            Vec3::NEG_Z,
            [
                Vec3::new(min.x, min.y, min.z),
                Vec3::new(min.x, max.y, min.z),
                Vec3::new(max.x, max.y, min.z),
                Vec3::new(max.x, min.y, min.z),
            ],
        ),
    ];
    for (n, corners) in faces {
        let base = m.positions.len() as u32;
        // Wind counter-clockwise seen from outside (along n).
        let [a, b, c, _] = corners;
        let ccw = (b - a).cross(c - a).dot(n) > 0.0;
        for p in corners {
            m.positions.push(p);
            m.normals.push(n);
        }
        if ccw {
            m.indices.push([base, base + 1, base + 2]);
            m.indices.push([base, base + 2, base + 3]);
        } else {
            m.indices.push([base, base + 2, base + 1]);
            m.indices.push([base, base + 3, base + 2]);
        }
        m.materials.extend([material, material]);
    }
    m
}

/// A UV sphere with smooth outward normals.
pub fn sphere_mesh(center: Vec3, radius: f32, material: u32, segments: u32) -> Mesh {
    let (nu, nv) = (segments * 2, segments);
    let mut m = Mesh::default();
    for j in 0..=nv {
        let theta = std::f32::consts::PI * j as f32 / nv as f32;
        for i in 0..=nu {
            let phi = 2.0 * std::f32::consts::PI * i as f32 / nu as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            m.positions.push(center + n * radius);
            m.normals.push(n);
        }
    }
    let row = nu + 1;
    for j in 0..nv {
        for i in 0..nu {
            let a = j * row + i;
            let (b, c, d) = (a + 1, a + row, a + row + 1);
            if j != 0 {
                m.indices.push([a, b, c]);
                m.materials.push(material);
            }
            if j != nv - 1 {
                m.indices.push([b, d, c]);
                m.materials.push(material);
            }
        }
    }
    m
}

pub fn object(name: &str, mesh: Mesh) -> Object {
    Object {
        name: name.into(),
        mesh,
        transform: Mat4::IDENTITY,
        animation: None,
        water: None,
    }
}

pub fn point_light(position: Vec3, intensity: f32) -> Light {
    Light {
        kind: LightKind::Point,
        position,
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(intensity),
        cone_angle_deg: 0.0,
        cone_falloff_deg: 0.0,
    }
}

pub fn directional_light(direction: Vec3, irradiance: f32) -> Light {
    Light {
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: direction.normalize(),
        intensity: Vec3::splat(irradiance),
        cone_angle_deg: 0.0,
        cone_falloff_deg: 0.0,
    }
}

pub fn scene(
    camera: Camera,
    lights: Vec<Light>,
    materials: Vec<Material>,
    objects: Vec<Object>,
) -> Scene {
    Scene {
        source: PathBuf::from("<test>"),
        camera,
        lights,
        materials,
        objects,
        medium: None,
        output: Output { exposure: 1.0 },
        environment: None,
        emitters: Vec::new(),
        textures: Vec::new(),
    }
}

pub fn camera(eye: Vec3, target: Vec3, fov_y_deg: f32) -> Camera {
    Camera {
        eye,
        target,
        up: Vec3::Y,
        fov_y_deg,
    }
}

/// The world-space ray through the centre of pixel (px, py) (row 0 at the top).
pub fn pixel_ray(camera: &Camera, width: u32, height: u32, px: u32, py: u32) -> (Vec3, Vec3) {
    let (view, proj) = camera_matrices(camera, width as f32 / height as f32);
    let inv = (proj * view).inverse();
    let ndc_x = 2.0 * (px as f32 + 0.5) / width as f32 - 1.0;
    let ndc_y = 2.0 * (py as f32 + 0.5) / height as f32 - 1.0;
    let far = inv.project_point3(Vec3::new(ndc_x, ndc_y, 1.0));
    (camera.eye, (far - camera.eye).normalize())
}

/// Red channel of pixel (x, y) of an RGBA f32 image.
pub fn red(rgba: &[f32], width: u32, x: u32, y: u32) -> f32 {
    rgba[((y * width + x) * 4) as usize]
}

pub fn assert_finite(rgba: &[f32]) {
    assert!(rgba.iter().all(|v| v.is_finite()), "image has NaN or Inf");
}

/// rgb summed over an RGBA f32 image.
/// The largest absolute difference between two images.
pub fn max_difference(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max)
}

/// Asserts that two renders of the same frame by `water_photons` agree up to
/// the reordering of its splats' floating-point sums. It appends photons with
/// atomics, so their order in the buffer, and with it the order of the sums
/// that splat them into the caustic image, may differ from run to run (on
/// lavapipe it does when the machine is loaded: the order follows its worker
/// threads). Splats add positive flux, so a pixel is a sum of positive
/// float32 terms, and reordering N terms changes it by at most about
/// N·2^-24 of the pixel; with up to ~1000 splats on a pixel that is 6e-5 of
/// it, hence the bound of 1e-4 of the image's peak.
pub fn assert_equal_up_to_splat_order(a: &[f32], b: &[f32], what: &str) {
    let peak = a.iter().fold(0f32, |m, v| m.max(v.abs()));
    let worst = max_difference(a, b);
    assert!(
        worst <= 1e-4 * peak,
        "{what}: worst difference {worst} of peak {peak}"
    );
}

pub fn energy(img: &[f32]) -> f64 {
    img.chunks(4).map(|p| (p[0] + p[1] + p[2]) as f64).sum()
}

/// An RGBA f32 image with the pixels outside `mask` set to 0 (the rgb of
/// those inside kept, alpha 0): comparisons restricted to comparable pixels.
pub fn masked(img: &[f32], mask: &[bool]) -> Vec<f32> {
    img.chunks(4)
        .zip(mask)
        .flat_map(|(p, &keep)| {
            if keep {
                [p[0], p[1], p[2], 0.0]
            } else {
                [0.0; 4]
            }
        })
        .collect()
}

/// RGB bytes of an RGBA8 image.
pub fn rgb8(rgba: &[u8]) -> Vec<u8> {
    caustics::compare::metrics::rgb8(rgba)
}

/// glsl/common/tonemap.glsl on the CPU at exposure 1 (RGBA8), the code
/// `caustics compare` uses (`caustics::compare::metrics::tonemap`).
pub fn tonemap(rgba: &[f32]) -> Vec<u8> {
    caustics::compare::metrics::tonemap(rgba, 1.0)
}

/// FLIP mean error of `test` against `reference` (tonemapped RGBA8, `size`
/// x `size`) and the error map: `caustics compare`'s code path.
pub fn flip(
    test: &[u8],
    reference: &[u8],
    size: u32,
) -> (f32, caustics::compare::metrics::FlipMap) {
    caustics::compare::metrics::flip(test, reference, size, size)
}

/// Writes `<name>_actual.png`, `<name>_reference.png` and
/// `<name>_difference.png` (the FLIP map) to `$CARGO_TARGET_TMPDIR/test-output/`
/// and returns that folder.
pub fn write_comparison_pngs(
    name: &str,
    size: u32,
    actual: &[u8],
    reference: &[u8],
    flip_map: &caustics::compare::metrics::FlipMap,
) -> String {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("test-output");
    std::fs::create_dir_all(&dir).unwrap();
    let save = |suffix: &str, rgb: &[u8]| {
        let path = dir.join(format!("{name}_{suffix}.png"));
        image::save_buffer(&path, rgb, size, size, image::ExtendedColorType::Rgb8).unwrap();
    };
    save("actual", &rgb8(actual));
    save("reference", &rgb8(reference));
    save("difference", &flip_map.magma_rgb8());
    dir.display().to_string()
}

/// One `image_space` frame of `scene` at `size`², rendered straight
/// through the technique (no tonemap), with its resources kept for reading.
pub struct ImageSpaceFrame {
    pub tech: caustics::techniques::image_space::ImageSpace,
    pub scene_gpu: caustics::frame::SceneGpu,
    pub targets: caustics::frame::FrameTargets,
}

pub fn render_image_space(
    ctx: &Arc<Context>,
    scene: &Scene,
    overrides: &[&str],
    size: u32,
) -> ImageSpaceFrame {
    use caustics::frame::{FrameTargets, SceneGpu};
    use caustics::params::ParamSet;
    use caustics::techniques::image_space::{ImageSpace, ImageSpaceParams};
    use caustics::techniques::Technique;
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let params = ImageSpaceParams::parse("image_space", &overrides).unwrap();
    let scene_gpu = SceneGpu::new(ctx, scene, 0.0).unwrap();
    let targets = FrameTargets::new(ctx, size, size).unwrap();
    let mut tech = ImageSpace::new(ctx, &params, scene, &scene_gpu, size, size).unwrap();
    scene_gpu.update_frame(scene, size, size, 0.0, 0).unwrap();
    let profiler = caustics::vk::Profiler::new(ctx, 64).unwrap();
    profiler
        .frame(|rec| tech.record(rec, &scene_gpu, &targets))
        .unwrap();
    ImageSpaceFrame {
        tech,
        scene_gpu,
        targets,
    }
}

/// The second half of a reference rendered in two equal halves: the
/// resolve divides by the photon count, so half_b = 2 whole - half_a.
pub fn second_half(whole: &[f32], half_a: &[f32]) -> Vec<f32> {
    whole.iter().zip(half_a).map(|(t, a)| 2.0 * t - a).collect()
}

/// Henyey-Greenstein phase on the CPU, normalised over the sphere; `cos`
/// between the propagation directions before and after scattering
/// (glsl/common/medium.glsl `hg_phase`).
pub fn hg_phase(cos: f64, g: f64) -> f64 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * std::f64::consts::PI * denom * denom.sqrt())
}

/// Snell refraction of the unit direction `d` at a surface whose unit
/// normal `n` faces against `d`, `eta` = n_incident / n_transmitted; None
/// under total internal reflection.
pub fn refract(d: glam::DVec3, n: glam::DVec3, eta: f64) -> Option<glam::DVec3> {
    let c = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - c * c);
    (k >= 0.0).then(|| eta * d + (eta * c - k.sqrt()) * n)
}

/// Length of the segment a -> b inside the axis-aligned box [lo, hi].
pub fn length_in_box(a: glam::DVec3, b: glam::DVec3, lo: glam::DVec3, hi: glam::DVec3) -> f64 {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k].abs() < 1e-300 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return 0.0;
            }
            continue;
        }
        let (u, v) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    (t1 - t0).max(0.0) * d.length()
}

/// Per pixel of a `size`² frame of `s` (row-major): `keep` of the material
/// kind the camera ray hits first (CPU BVH), or `on_miss` where it hits
/// nothing.
pub fn first_hit_mask(
    s: &Scene,
    size: u32,
    on_miss: bool,
    keep: impl Fn(MaterialKind) -> bool,
) -> Vec<bool> {
    let tris = s.triangles(0.0);
    let bvh = caustics::bvh::Bvh::build(&tris);
    let gpu = bvh.gpu_triangles(&tris);
    (0..size * size)
        .map(|i| {
            let (o, d) = pixel_ray(&s.camera, size, size, i % size, i / size);
            bvh.intersect(&gpu, o, d, 0.0, f32::MAX)
                .map_or(on_miss, |h| {
                    let m = gpu[h.triangle as usize].p0[3].to_bits() as usize;
                    keep(s.materials[m].kind)
                })
        })
        .collect()
}

/// `mask` (row-major, `size`²) with every pixel dropped that has a dropped
/// pixel among its 8 neighbours (beyond the image border counts as kept):
/// what a pixel-centre mask means for a renderer that jitters its rays
/// over the pixel, where a surface's edge may cross a kept pixel.
pub fn eroded(mask: &[bool], size: u32) -> Vec<bool> {
    let n = size as i64;
    let kept =
        |u: i64, v: i64| !(0..n).contains(&u) || !(0..n).contains(&v) || mask[(v * n + u) as usize];
    (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            (-1..=1).all(|dy| (-1..=1).all(|dx| kept(x + dx, y + dy)))
        })
        .collect()
}

/// rgb summed, the quantity compared per pixel.
pub fn sum_rgb(img: &[f32], i: usize) -> f64 {
    (img[i * 4] + img[i * 4 + 1] + img[i * 4 + 2]) as f64
}

/// Pixels away from discontinuities of a noise-free image (`size`²): the
/// 3x3 neighbourhood spans at most 15% of its maximum + 0.02.
pub fn smooth_mask(img: &[f32], size: u32) -> Vec<bool> {
    let s = size as i32;
    (0..s * s)
        .map(|i| {
            let (x, y) = (i % s, i / s);
            let (mut lo, mut hi) = (f64::MAX, f64::MIN);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = ((x + dx).clamp(0, s - 1), (y + dy).clamp(0, s - 1));
                    let v = sum_rgb(img, (ny * s + nx) as usize);
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
            hi - lo <= 0.15 * hi + 0.02
        })
        .collect()
}

pub struct Blocks {
    pub mean: f64,
    pub worst: f64,
    pub worst_at: (u32, u32),
    pub used: usize,
}

/// Relative error of `block`² block sums over the pixels in `mask` (images
/// `size`²): blocks less than a quarter covered by the mask, or darker than
/// 10% of the reference's mean (too few photons for a relative error), are
/// skipped.
pub fn block_errors(
    actual: &[f32],
    reference: &[f32],
    mask: &[bool],
    size: u32,
    block: u32,
) -> Blocks {
    let n = (size * size) as usize;
    let mean_r = (0..n).map(|i| sum_rgb(reference, i)).sum::<f64>() / n as f64;
    let mut b = Blocks {
        mean: 0.0,
        worst: 0.0,
        worst_at: (0, 0),
        used: 0,
    };
    for by in 0..size / block {
        for bx in 0..size / block {
            let (mut a, mut r, mut count) = (0.0, 0.0, 0);
            for y in by * block..(by + 1) * block {
                for x in bx * block..(bx + 1) * block {
                    let i = (y * size + x) as usize;
                    if mask[i] {
                        a += sum_rgb(actual, i);
                        r += sum_rgb(reference, i);
                        count += 1;
                    }
                }
            }
            if count < (block * block / 4) as usize || r / (count as f64) < 0.1 * mean_r {
                continue;
            }
            let e = ((a - r) / r).abs();
            b.mean += e;
            b.used += 1;
            if e > b.worst {
                b.worst = e;
                b.worst_at = (bx, by);
            }
        }
    }
    b.mean /= b.used.max(1) as f64;
    b
}

/// `ball_lens.toml`'s point light, as its TOML reads.
pub const BALL_LENS_POINT_LIGHT: &str =
    "[[light]]\nkind = \"point\"\nposition = [0.0, 8.0, 0.0]\nintensity = [60.0, 60.0, 60.0]\n";

/// assets/scenes/<name>.toml, loaded.
pub fn canonical_scene(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(format!("{name}.toml"));
    Scene::load(&path).unwrap()
}

/// `ball_lens.toml` with its point light replaced by `light` (TOML).
pub fn ball_lens_with_light(light: &str) -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ball_lens.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(BALL_LENS_POINT_LIGHT));
    Scene::from_str(&text.replace(BALL_LENS_POINT_LIGHT, light), &path).unwrap()
}

/// A square rect light of side `size` (m) in place of `ball_lens`'s point
/// light, facing down, with the same on-axis intensity I0 = L A = 60 W/sr.
pub fn ball_lens_rect_light(size: f32) -> String {
    format!(
        "[[light]]\nkind = \"rect\"\ncenter = [0.0, 8.0, 0.0]\nnormal = [0.0, -1.0, 0.0]\nsize = [{size}, {size}]\nradiance = {}\n",
        60.0 / (size * size)
    )
}

/// The reference of `scene` at `size`² with the default settings, traced
/// with `photons` photons (or read from the reference cache).
pub fn traced_reference(
    ctx: &Arc<Context>,
    scene: &Scene,
    size: u32,
    photons: u64,
) -> Arc<ReferenceImages> {
    reference_images(ctx, &ReferenceRequest::new(scene, size, photons))
}
