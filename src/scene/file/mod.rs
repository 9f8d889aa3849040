//! The scene file schema: reading the spanned TOML tree into the resolved
//! model, validating every value (docs/SCENES.md lists the fields).

mod emitters;
mod materials;
mod medium;
mod objects;
mod values;
mod water_surface;

use super::error::Source;
use super::node::{self, Tbl, R};
use super::paths::{AllowedPaths, Confinement};
use super::types::*;
use glam::Vec3;
use materials::Materials;
use std::path::Path;
use values::{direction, non_negative_rgb, numbers2, unit_rgb};

/// Default vertical field of view, degrees.
pub const DEFAULT_FOV_Y_DEG: f32 = 45.0;

/// Parses and validates `text`, read from `path` (relative paths inside
/// resolve against its folder, and must stay in its tree or in an
/// `allowed` folder's).
pub(crate) fn parse(text: &str, path: &Path, allowed: &AllowedPaths) -> R<Scene> {
    let src = Source { path, text };
    let entries = node::parse_document(text).map_err(|e| {
        let span = e.span().unwrap_or(0..0);
        src.err(
            &span,
            "syntax",
            e.message()
                .trim()
                .lines()
                .map(str::trim)
                .collect::<Vec<_>>()
                .join("; "),
        )
    })?;
    let root = Tbl::root(&src, &entries);
    root.check_keys(
        &["camera", "light", "material", "object", "medium", "output"],
        "the scene",
    )?;
    let within = Confinement::scene(path, allowed);

    let camera = match root.opt_table("camera")? {
        Some(t) => camera(&t)?,
        None => return Err(root.err("camera", "missing required table [camera]")),
    };

    let light_tables = root.tables("light")?;
    if light_tables.is_empty() {
        return Err(root.err("light", "at least one [[light]] is required"));
    }
    let mut lights = Vec::new();
    let mut environment: Option<Environment> = None;
    let mut emitter_shapes = Vec::new();
    for t in &light_tables {
        match t.str("kind")? {
            "environment" => {
                if environment.is_some() {
                    return Err(t.err("kind", "a second environment light: at most one per scene"));
                }
                environment = Some(emitters::environment(t, &within)?);
            }
            "rect" | "sphere" => {
                if emitter_shapes.len() == emitters::MAX_EMITTERS {
                    return Err(t.err(
                        "kind",
                        format!(
                            "too many area lights, at most {} are supported",
                            emitters::MAX_EMITTERS
                        ),
                    ));
                }
                emitter_shapes.push(emitters::area_light(t)?);
            }
            _ => {
                if lights.len() == super::MAX_LIGHTS {
                    return Err(src.err(
                        &t.span,
                        &t.path,
                        format!(
                            "too many lights: at most {} point, spot and directional lights are supported",
                            super::MAX_LIGHTS
                        ),
                    ));
                }
                lights.push(light(t)?);
            }
        }
    }

    let mut materials = Materials::default();
    for t in root.tables("material")? {
        let m = material(&t, &within, &mut materials)?;
        let name = m.name.clone();
        if let Err(first) = materials.define(m) {
            return Err(t.err(
                "name",
                format!("duplicate material name `{name}` (also material[{first}])"),
            ));
        }
    }

    let object_tables = root.tables("object")?;
    if object_tables.is_empty() {
        return Err(root.err("object", "at least one [[object]] is required"));
    }
    let mut objects = Vec::with_capacity(object_tables.len());
    for (i, t) in object_tables.iter().enumerate() {
        objects.push(objects::object(t, i, &within, &mut materials)?);
    }

    let medium = root
        .opt_table("medium")?
        .map(|t| medium::medium(&t, &within))
        .transpose()?;
    let output = match root.opt_table("output")? {
        Some(t) => {
            t.check_keys(&["exposure"], "[output]")?;
            let exposure = t.f32_or("exposure", 1.0)?;
            if exposure <= 0.0 {
                return Err(t.err("exposure", format!("must be positive, got {exposure}")));
            }
            Output { exposure }
        }
        None => Output { exposure: 1.0 },
    };

    let (mut materials, textures) = materials.into_parts();
    let emitters = emitters::add_geometry(emitter_shapes, &mut materials, &mut objects);
    Ok(Scene {
        source: path.to_path_buf(),
        camera,
        lights,
        materials,
        textures,
        objects,
        medium,
        output,
        environment,
        emitters,
    })
}

fn camera(t: &Tbl) -> R<Camera> {
    t.check_keys(&["eye", "target", "up", "fov_y"], "[camera]")?;
    let eye = t.vec3("eye")?;
    let target = t.vec3("target")?;
    let up = direction(t, "up", Some(Vec3::Y))?;
    let fov_y_deg = t.f32_or("fov_y", DEFAULT_FOV_Y_DEG)?;
    let view = target - eye;
    if view.length() <= 1e-6 {
        return Err(t.err(
            "target",
            format!("must differ from camera.eye, both are {eye}"),
        ));
    }
    if view.normalize().cross(up).length() < 1e-4 {
        return Err(t.err(
            "up",
            format!(
                "must not be parallel to the view direction {}",
                view.normalize()
            ),
        ));
    }
    if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
        return Err(t.err(
            "fov_y",
            format!("must be within (0, 180) degrees, got {fov_y_deg}"),
        ));
    }
    Ok(Camera {
        eye,
        target,
        up,
        fov_y_deg,
    })
}

fn light(t: &Tbl) -> R<Light> {
    let kind = t.str("kind")?;
    let mut l = Light {
        kind: LightKind::Point,
        position: Vec3::ZERO,
        direction: Vec3::NEG_Y,
        intensity: Vec3::ZERO,
        cone_angle_deg: 0.0,
        cone_falloff_deg: 0.0,
    };
    match kind {
        "point" => {
            t.check_keys(&["kind", "position", "intensity"], "a point light")?;
            l.position = t.vec3("position")?;
            l.intensity = non_negative_rgb(t, "intensity", None)?;
        }
        "spot" => {
            t.check_keys(
                &[
                    "kind",
                    "position",
                    "direction",
                    "intensity",
                    "cone_angle",
                    "cone_falloff",
                ],
                "a spot light",
            )?;
            l.kind = LightKind::Spot;
            l.position = t.vec3("position")?;
            l.direction = direction(t, "direction", None)?;
            l.intensity = non_negative_rgb(t, "intensity", None)?;
            l.cone_angle_deg = t.f32("cone_angle")?;
            if !(l.cone_angle_deg > 0.0 && l.cone_angle_deg <= 90.0) {
                return Err(t.err(
                    "cone_angle",
                    format!("must be within (0, 90] degrees, got {}", l.cone_angle_deg),
                ));
            }
            l.cone_falloff_deg = t.f32_or("cone_falloff", 0.0)?;
            if l.cone_falloff_deg < 0.0 {
                return Err(t.err(
                    "cone_falloff",
                    format!("must not be negative, got {}", l.cone_falloff_deg),
                ));
            }
            if l.cone_falloff_deg > l.cone_angle_deg {
                return Err(t.err(
                    "cone_falloff",
                    format!(
                        "must not exceed cone_angle ({}), got {}",
                        l.cone_angle_deg, l.cone_falloff_deg
                    ),
                ));
            }
        }
        "directional" => {
            t.check_keys(&["kind", "direction", "irradiance"], "a directional light")?;
            l.kind = LightKind::Directional;
            l.direction = direction(t, "direction", None)?;
            l.intensity = non_negative_rgb(t, "irradiance", None)?;
        }
        other => {
            return Err(t.err(
                "kind",
                format!("unknown light kind `{other}`; expected point, spot, directional, environment, rect or sphere"),
            ))
        }
    }
    Ok(l)
}

fn material(t: &Tbl, within: &Confinement, materials: &mut Materials) -> R<Material> {
    let name = t.str("name")?;
    if name.trim().is_empty() {
        return Err(t.err("name", "must not be empty"));
    }
    let kind = t.str("kind")?;
    let mut m = Material {
        name: name.to_owned(),
        kind: MaterialKind::Diffuse,
        color: Vec3::ONE,
        ior: 1.0,
        absorption: Vec3::ZERO,
        texture: None,
        emission: Vec3::ZERO,
        specular: Vec3::ZERO,
        scattering: None,
    };
    match kind {
        "diffuse" => {
            t.check_keys(
                &[
                    "name",
                    "kind",
                    "albedo",
                    "albedo_texture",
                    "uv_scale",
                    "alpha_cutoff",
                ],
                "a diffuse material",
            )?;
            m.texture = albedo_texture(t, within, materials)?;
            // With a texture, `albedo` scales it (glTF's baseColorFactor).
            let default = if m.texture.is_some() { 1.0 } else { 0.8 };
            m.color = unit_rgb(t, "albedo", Vec3::splat(default))?;
        }
        "mixed" => {
            t.check_keys(
                &["name", "kind", "reflectance", "albedo"],
                "a mixed material",
            )?;
            m.specular = unit_rgb(t, "reflectance", Vec3::splat(0.5))?;
            m.color = unit_rgb(t, "albedo", Vec3::splat(0.3))?;
            let sum = m.specular + m.color;
            if sum.max_element() > 1.0 {
                return Err(t.err(
                    "albedo",
                    format!("reflectance + albedo must be at most 1 per channel (energy conservation), got {sum}"),
                ));
            }
        }
        "mirror" => {
            t.check_keys(&["name", "kind", "reflectance"], "a mirror material")?;
            m.kind = MaterialKind::Mirror;
            m.color = unit_rgb(t, "reflectance", Vec3::ONE)?;
        }
        "dielectric" => {
            t.check_keys(
                &["name", "kind", "ior", "absorption", "medium"],
                "a dielectric material",
            )?;
            m.kind = MaterialKind::Dielectric;
            m.ior = t.f32_or("ior", 1.5)?;
            if m.ior < 1.0 {
                return Err(t.err("ior", format!("must be at least 1, got {}", m.ior)));
            }
            m.absorption = non_negative_rgb(t, "absorption", Some(Vec3::ZERO))?;
            if let Some(inside) = t.opt_table("medium")? {
                if t.has("absorption") {
                    return Err(t.err(
                        "absorption",
                        "give the inside's absorption once, as medium.sigma_a",
                    ));
                }
                (m.absorption, m.scattering) = medium::inside_dielectric(&inside)?;
            }
        }
        "thin_dielectric" => {
            t.check_keys(&["name", "kind", "ior"], "a thin dielectric material")?;
            m.kind = MaterialKind::ThinDielectric;
            m.ior = t.f32_or("ior", 1.5)?;
            if m.ior < 1.0 {
                return Err(t.err("ior", format!("must be at least 1, got {}", m.ior)));
            }
        }
        other => {
            return Err(t.err(
                "kind",
                format!(
                    "unknown material kind `{other}`; expected diffuse, mirror, mixed, dielectric or thin_dielectric"
                ),
            ))
        }
    }
    Ok(m)
}

/// A diffuse material's `albedo_texture` (a path relative to the scene file,
/// inside its tree), `uv_scale` (two positive numbers, default [1, 1]) and
/// `alpha_cutoff` (in [0, 1], default 0: opaque).
fn albedo_texture(
    t: &Tbl,
    within: &Confinement,
    materials: &mut Materials,
) -> R<Option<AlbedoTexture>> {
    let Some(rel) = t.opt_str("albedo_texture")? else {
        for key in ["uv_scale", "alpha_cutoff"] {
            if t.has(key) {
                return Err(t.err(key, "needs an `albedo_texture`"));
            }
        }
        return Ok(None);
    };
    let index = within
        .file(rel)
        .and_then(|file| materials.texture(&file))
        .map_err(|e| t.err("albedo_texture", e))?;
    let uv_scale = if t.has("uv_scale") {
        numbers2(t, "uv_scale", true)?.into()
    } else {
        glam::Vec2::ONE
    };
    let alpha_cutoff = t.f32_or("alpha_cutoff", 0.0)?;
    if !(0.0..=1.0).contains(&alpha_cutoff) {
        return Err(t.err(
            "alpha_cutoff",
            format!("must be in [0, 1], got {alpha_cutoff}"),
        ));
    }
    Ok(Some(AlbedoTexture {
        index,
        uv_scale,
        alpha_cutoff,
        wrap: [Wrap::Repeat; 2],
    }))
}
