//! A whole scene of one glTF file (`caustics render --scene model.glb`).

use super::*;

/// How a glTF file becomes a whole scene (`caustics render --scene model.glb`).
#[derive(Clone, Debug)]
pub struct GltfSceneOptions {
    /// Add a diffuse floor (albedo [`FLOOR_ALBEDO`]) under the model.
    pub floor: bool,
    /// Folders whose files the URIs may name besides the file's own tree.
    pub allowed: AllowedPaths,
}

impl Default for GltfSceneOptions {
    fn default() -> Self {
        GltfSceneOptions {
            floor: true,
            allowed: AllowedPaths::default(),
        }
    }
}

/// Albedo of the default floor.
pub const FLOOR_ALBEDO: f32 = 0.8;

/// Irradiance of the default sun when the file has no lights, W/m² (the
/// pool scenes' sun: `assets/scenes/water_pool.toml`).
pub const DEFAULT_SUN_IRRADIANCE: f32 = 1000.0;

/// Exposure of a glTF scene lit by the default sun (as the pool scenes:
/// radiance of a white diffuse surface facing it, ~320, times this is ~1).
pub const DEFAULT_SUN_EXPOSURE: f32 = 0.004;

/// A whole scene of a glTF file: its meshes as one object, the file's
/// camera (else one framing the model), its lights (else a sun), and a
/// floor unless `options` leaves it out. Warnings go to the log.
pub fn scene(path: &Path, options: &GltfSceneOptions) -> Result<Scene, GltfError> {
    let mut asset = load_allowing(path, &options.allowed)?;
    if asset.lights.len() > crate::scene::MAX_LIGHTS {
        return Err(GltfError {
            file: path.to_path_buf(),
            at: "extensions.KHR_lights_punctual".into(),
            message: format!(
                "the scene uses {} lights, at most {} are supported",
                asset.lights.len(),
                crate::scene::MAX_LIGHTS
            ),
        });
    }
    // Only a file that loads warns: a refused one is one line of error.
    for w in &asset.warnings {
        log::warn!("{w}");
    }
    let (lo, hi) = asset
        .mesh
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let center = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    asset.transform_uvs();
    let mut materials = asset.materials;
    // One texture per image, in the order materials first use them.
    let mut textures: Vec<Texture> = Vec::new();
    let mut by_path = std::collections::HashMap::new();
    for (m, t) in materials.iter_mut().zip(asset.base_color_textures) {
        let Some(t) = t else { continue };
        let (alpha_cutoff, wrap) = (t.alpha_cutoff, t.wrap);
        let index = *by_path.entry(t.pixels.path.clone()).or_insert_with(|| {
            textures.push(t.pixels);
            textures.len() - 1
        });
        m.texture = Some(AlbedoTexture {
            index: index as u32,
            uv_scale: Vec2::ONE,
            alpha_cutoff,
            wrap,
        });
    }
    let mut objects = vec![Object {
        name: path
            .file_stem()
            .map_or("gltf".into(), |s| s.to_string_lossy().into_owned()),
        mesh: asset.mesh,
        transform: Mat4::IDENTITY,
        animation: None,
        water: None,
    }];
    if options.floor {
        let material = materials.len() as u32;
        materials.push(Material {
            texture: None,
            emission: Vec3::ZERO,
            specular: Vec3::ZERO,
            scattering: None,
            name: "floor".into(),
            kind: MaterialKind::Diffuse,
            color: Vec3::splat(FLOOR_ALBEDO),
            ior: 1.0,
            absorption: Vec3::ZERO,
        });
        // Just below the model so a model standing on y = min does not
        // share its plane with the floor.
        let y = lo.y - 1e-3 * radius;
        let mut mesh = crate::scene::shapes::plane(
            Vec3::new(center.x, y, center.z),
            Vec3::Y,
            None,
            [6.0 * radius, 6.0 * radius],
        );
        mesh.materials = vec![material; mesh.indices.len()];
        objects.push(Object {
            name: "floor".into(),
            mesh,
            transform: Mat4::IDENTITY,
            animation: None,
            water: None,
        });
    }
    let camera = asset.camera.unwrap_or_else(|| {
        let fov_y_deg = crate::scene::DEFAULT_FOV_Y_DEG;
        let distance = 1.2 * radius / (fov_y_deg.to_radians() * 0.5).sin();
        Camera {
            eye: center + Vec3::new(0.0, 0.5, 1.0).normalize() * distance,
            target: center,
            up: Vec3::Y,
            fov_y_deg,
        }
    });
    let (lights, exposure) = if asset.lights.is_empty() {
        let sun = Light {
            kind: LightKind::Directional,
            position: Vec3::ZERO,
            direction: Vec3::new(-0.35, -1.0, -0.45).normalize(),
            intensity: Vec3::splat(DEFAULT_SUN_IRRADIANCE),
            cone_angle_deg: 0.0,
            cone_falloff_deg: 0.0,
        };
        (vec![sun], DEFAULT_SUN_EXPOSURE)
    } else {
        (asset.lights, 1.0)
    };
    Ok(Scene {
        source: path.to_path_buf(),
        camera,
        lights,
        materials,
        textures,
        objects,
        medium: None,
        output: Output { exposure },
        environment: None,
        emitters: Vec::new(),
    })
}
