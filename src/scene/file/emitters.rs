//! `[[light]]` tables of kind `environment` (an HDR image or a sun-and-sky)
//! and the area lights `rect` and `sphere`, whose geometry joins the scene's
//! objects (docs/SCENES.md, "Environment light", "Area lights").

use super::values::{direction, non_negative_rgb, positive, size2};
use crate::scene::node::{Tbl, R};
use crate::scene::paths::Confinement;
use crate::scene::types::*;
use crate::scene::{shapes, texture};
use glam::{Mat4, Quat, Vec3};
use image::DynamicImage;
use std::path::Path;

/// Most area lights a scene may hold.
pub const MAX_EMITTERS: usize = 64;
/// Tessellation of a sphere light's geometry (what the camera sees and what
/// casts shadows; its emission is sampled on the exact sphere).
pub const EMITTER_SPHERE_SEGMENTS: u32 = 64;

pub(super) fn environment(t: &Tbl, within: &Confinement) -> R<Environment> {
    t.check_keys(
        &["kind", "path", "sky", "scale", "rotate"],
        "an environment light",
    )?;
    let scale = t.f32_or("scale", 1.0)?;
    if scale < 0.0 {
        return Err(t.err("scale", format!("must not be negative, got {scale}")));
    }
    let rotate_deg = t.f32_or("rotate", 0.0)?;
    let kind = match (t.opt_str("path")?, t.opt_table("sky")?) {
        (Some(_), Some(_)) => return Err(t.err("sky", "give either `path` or `sky`, not both")),
        (None, None) => {
            return Err(t.err(
                "path",
                "an environment light needs `path` (an HDR image) or `sky`",
            ))
        }
        (Some(rel), None) => {
            let image = within.file(rel).and_then(|file| load_hdr(&file));
            EnvironmentKind::Image(image.map_err(|e| t.err("path", e))?)
        }
        (None, Some(sky_table)) => EnvironmentKind::Sky(sky(&sky_table, rotate_deg)?),
    };
    Ok(Environment {
        kind,
        scale,
        rotate_deg,
    })
}

fn sky(t: &Tbl, rotate_deg: f32) -> R<Sky> {
    t.check_keys(
        &[
            "sun_direction",
            "sun_radius",
            "sun_radiance",
            "zenith",
            "horizon",
        ],
        "a sky",
    )?;
    let local = direction(t, "sun_direction", None)?;
    let sun_radius_deg = positive(t, "sun_radius")?;
    if sun_radius_deg > 45.0 {
        return Err(t.err(
            "sun_radius",
            format!("must be within (0, 45] degrees, got {sun_radius_deg}"),
        ));
    }
    Ok(Sky {
        sun_direction: Quat::from_rotation_y(rotate_deg.to_radians()) * local,
        sun_radius_deg,
        sun_radiance: non_negative_rgb(t, "sun_radiance", None)?,
        zenith: non_negative_rgb(t, "zenith", None)?,
        horizon: non_negative_rgb(t, "horizon", None)?,
    })
}

/// An equirectangular HDR image (Radiance RGBE `.hdr` or OpenEXR) as linear
/// radiance. Other formats, images over [`texture::ENVIRONMENT_LIMITS`],
/// undecodable or truncated files and negative or non-finite texels are
/// refused; the message names the file.
pub fn load_hdr(path: &Path) -> Result<Texture, String> {
    crate::scene::input::check_regular(path)
        .map_err(|e| format!("cannot open environment image {}: {e}", path.display()))?;
    let reader = image::ImageReader::open(path)
        .map_err(|e| format!("cannot open environment image {}: {e}", path.display()))?
        .with_guessed_format()
        .map_err(|e| format!("cannot read environment image {}: {e}", path.display()))?;
    match reader.format() {
        Some(image::ImageFormat::Hdr | image::ImageFormat::OpenExr) => {}
        other => {
            return Err(format!(
                "environment image {} is not an HDR image (.hdr Radiance RGBE or .exr){}",
                path.display(),
                other.map_or(String::new(), |f| format!(", it is {f:?}"))
            ))
        }
    }
    let decoded = texture::decode_limited(reader, path, &texture::ENVIRONMENT_LIMITS)?;
    let (width, height) = (decoded.width(), decoded.height());
    if width < 2 || height < 1 {
        return Err(format!(
            "environment image {} is {width}x{height}, too small",
            path.display()
        ));
    }
    let mut texels: Vec<[f32; 3]> = texture::reserved(width as usize * height as usize, || {
        format!("environment image {} ({width}x{height})", path.display())
    })?;
    match decoded {
        DynamicImage::ImageRgb32F(image) => texels.extend(image.pixels().map(|p| p.0)),
        other => texels.extend(other.into_rgb32f().pixels().map(|p| p.0)),
    }
    // The radiometric bound of every scene value (docs/SCENES.md, Bounds):
    // above it the table's sums and the photons' flux leave the f32 range
    // and the render would fail at its end with a NaN naming no file.
    let bound = crate::scene::MAX_RADIOMETRIC as f32;
    if let Some(i) = texels.iter().position(|t| {
        t.iter()
            .any(|c| !(c.is_finite() && *c >= 0.0 && *c <= bound))
    }) {
        return Err(format!(
            "environment image {}: texel ({}, {}) is {:?}, not a radiance within 0 and {bound:e}",
            path.display(),
            i as u32 % width,
            i as u32 / width,
            texels[i]
        ));
    }
    Ok(Texture {
        path: path.to_path_buf(),
        width,
        height,
        texels,
        alpha: Vec::new(),
    })
}

/// A `rect` or `sphere` light's shape, radiance and (a sphere's) `animate`
/// motion.
pub(super) fn area_light(t: &Tbl) -> R<(EmitterShape, Vec3, Option<Animation>)> {
    let shape = match t.str("kind")? {
        "rect" => {
            t.check_keys(
                &["kind", "center", "normal", "size", "tangent", "radiance"],
                "a rect light",
            )?;
            let center = t.vec3("center")?;
            let normal = direction(t, "normal", None)?;
            let size = size2(t, "size")?;
            let tangent = match t.opt_vec3("tangent")? {
                None => shapes::basis(normal).0,
                Some(tan) => {
                    let off = tan - normal * normal.dot(tan);
                    if tan.length() <= 1e-12 || off.length() <= 1e-6 * tan.length() {
                        return Err(t.err(
                            "tangent",
                            format!("must be non-zero and not parallel to normal, got {tan}"),
                        ));
                    }
                    off.normalize()
                }
            };
            EmitterShape::Rect {
                center,
                normal,
                tangent,
                size,
            }
        }
        _ => {
            t.check_keys(
                &["kind", "center", "radius", "radiance", "animate"],
                "a sphere light",
            )?;
            EmitterShape::Sphere {
                center: t.vec3("center")?,
                radius: positive(t, "radius")?,
            }
        }
    };
    let motion = match shape {
        EmitterShape::Sphere { .. } => super::objects::animation(t)?,
        EmitterShape::Rect { .. } => None,
    };
    Ok((shape, non_negative_rgb(t, "radiance", None)?, motion))
}

/// Appends each area light's geometry (an object named `light[i]`) and
/// material (black diffuse emitting its radiance from the front faces). A
/// sphere's mesh is built about the origin and placed by its object's
/// transform, a translation to `center`, so that its `animate` motion
/// moves it as it moves any object (`Scene::emitter_at`).
pub(super) fn add_geometry(
    lights: Vec<(EmitterShape, Vec3, Option<Animation>)>,
    materials: &mut Vec<Material>,
    objects: &mut Vec<Object>,
) -> Vec<Emitter> {
    lights
        .into_iter()
        .enumerate()
        .map(|(i, (shape, radiance, animation))| {
            let material = materials.len() as u32;
            materials.push(Material {
                name: format!("area light {i}"),
                kind: MaterialKind::Diffuse,
                color: Vec3::ZERO,
                ior: 1.0,
                absorption: Vec3::ZERO,
                texture: None,
                emission: radiance,
                specular: Vec3::ZERO,
                scattering: None,
            });
            let (mut mesh, transform) = match shape {
                EmitterShape::Rect {
                    center,
                    normal,
                    tangent,
                    size,
                } => (
                    shapes::plane(center, normal, Some(tangent), size),
                    Mat4::IDENTITY,
                ),
                EmitterShape::Sphere { center, radius } => (
                    shapes::sphere(Vec3::ZERO, radius, EMITTER_SPHERE_SEGMENTS),
                    Mat4::from_translation(center),
                ),
            };
            mesh.materials = vec![material; mesh.indices.len()];
            let object = objects.len() as u32;
            objects.push(Object {
                name: format!("area light {i}"),
                mesh,
                transform,
                animation,
                water: None,
            });
            Emitter {
                shape,
                radiance,
                object,
                material,
            }
        })
        .collect()
}
