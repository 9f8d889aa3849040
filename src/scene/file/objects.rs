//! `[[object]]` tables: procedural shapes, OBJ meshes (with their MTL
//! materials), glTF files (with their materials), transforms and animation.

use super::materials::Materials;
use super::values::{direction, positive, size2};
use super::water_surface::{water_surface, WATER_KEYS};
use crate::scene::node::Tbl;
use crate::scene::node::R;
use crate::scene::paths::Confinement;
use crate::scene::types::*;
use crate::scene::{gltf, obj, shapes};
use glam::{Mat4, Quat, Vec2, Vec3};

const COMMON_OBJECT_KEYS: [&str; 7] = [
    "shape",
    "name",
    "material",
    "translate",
    "rotate",
    "scale",
    "animate",
];

fn segments(t: &Tbl) -> R<u32> {
    let s = t.opt_u32("segments")?.unwrap_or(shapes::DEFAULT_SEGMENTS);
    if !(shapes::MIN_SEGMENTS..=shapes::MAX_SEGMENTS).contains(&s) {
        return Err(t.err(
            "segments",
            format!(
                "must be within [{}, {}], got {s}",
                shapes::MIN_SEGMENTS,
                shapes::MAX_SEGMENTS
            ),
        ));
    }
    Ok(s)
}

/// Reads `[[object]]` number `index`; MTL materials it brings are added to `materials`.
pub(super) fn object(
    t: &Tbl,
    index: usize,
    within: &Confinement,
    materials: &mut Materials,
) -> R<Object> {
    let shape = t.str("shape")?;
    let extra: &[&str] = match shape {
        "sphere" => &["center", "radius", "segments"],
        "plane" => &["center", "normal", "size", "tangent"],
        "box" => &["min", "max"],
        "torus" => &["center", "axis", "radii", "segments"],
        "cylinder" => &["p0", "p1", "radius", "caps", "segments"],
        "mesh" | "gltf" => &["path"],
        "water" => &[],
        other => {
            return Err(t.err(
                "shape",
                format!(
                    "unknown shape `{other}`; expected sphere, plane, box, torus, cylinder, mesh, gltf or water"
                ),
            ))
        }
    };
    let allowed: Vec<&str> = if shape == "water" {
        // Water lies in world space (its waves are world x/z functions), so it
        // takes no transform or animation: `center` and `base_height` place it.
        WATER_KEYS.to_vec()
    } else {
        COMMON_OBJECT_KEYS.iter().chain(extra).copied().collect()
    };
    t.check_keys(&allowed, &format!("a {shape} object"))?;

    let name = t
        .opt_str("name")?
        .map_or_else(|| format!("{shape}{index}"), str::to_owned);
    let material = match t.opt_str("material")? {
        Some(m) => match materials.defined_index(m) {
            Some(i) => Some(i as u32),
            None => {
                let known = materials.defined_names();
                let known = if known.is_empty() {
                    "none".to_owned()
                } else {
                    known.join(", ")
                };
                return Err(t.err(
                    "material",
                    format!("unknown material `{m}`; defined: {known}"),
                ));
            }
        },
        None if shape == "mesh" || shape == "gltf" => None,
        None => return Err(t.err("material", "missing required field (the material name)")),
    };

    let mut mesh = match shape {
        "sphere" => shapes::sphere(
            t.vec3_or("center", Vec3::ZERO)?,
            positive(t, "radius")?,
            segments(t)?,
        ),
        "plane" => {
            let normal = direction(t, "normal", Some(Vec3::Y))?;
            let tangent = match t.opt_vec3("tangent")? {
                Some(tan) => {
                    let off = tan - normal * normal.dot(tan);
                    if off.length() <= 1e-6 * tan.length().max(1e-30) || tan.length() <= 1e-12 {
                        return Err(t.err(
                            "tangent",
                            format!("must be non-zero and not parallel to normal, got {tan}"),
                        ));
                    }
                    Some(tan)
                }
                None => None,
            };
            let size = size2(t, "size")?;
            shapes::plane(t.vec3_or("center", Vec3::ZERO)?, normal, tangent, size)
        }
        "box" => {
            let (min, max) = (t.vec3("min")?, t.vec3("max")?);
            if min.cmpge(max).any() {
                return Err(t.err(
                    "max",
                    format!("must exceed min in every component: min {min}, max {max}"),
                ));
            }
            shapes::cuboid(min, max)
        }
        "torus" => {
            let axis = direction(t, "axis", Some(Vec3::Y))?;
            let [major, minor] = size2(t, "radii")?;
            if minor >= major {
                return Err(t.err(
                    "radii",
                    format!("minor radius must be below major radius, got [{major}, {minor}]"),
                ));
            }
            shapes::torus(
                t.vec3_or("center", Vec3::ZERO)?,
                axis,
                major,
                minor,
                segments(t)?,
            )
        }
        "cylinder" => {
            let (p0, p1) = (t.vec3("p0")?, t.vec3("p1")?);
            if (p1 - p0).length() <= 1e-6 {
                return Err(t.err("p1", format!("must differ from p0, both are {p0}")));
            }
            let radius = positive(t, "radius")?;
            let caps = t.opt_bool("caps")?.unwrap_or(true);
            shapes::cylinder(p0, p1, radius, caps, segments(t)?)
        }
        "water" => {
            let surface = water_surface(t, material.unwrap_or_default())?;
            return Ok(Object {
                name,
                mesh: surface.mesh(0.0),
                transform: Mat4::IDENTITY,
                animation: None,
                water: Some(surface),
            });
        }
        "gltf" => return gltf_object(t, name, within, material, materials),
        _ => return mesh_object(t, name, within, material, materials),
    };
    let material = material.unwrap_or_default();
    mesh.materials = vec![material; mesh.indices.len()];
    placed(t, name, mesh)
}

/// An object of `mesh` with the table's `translate`/`rotate`/`scale` and `animate`.
fn placed(t: &Tbl, name: String, mesh: Mesh) -> R<Object> {
    Ok(Object {
        name,
        mesh,
        transform: transform(t)?,
        animation: animation(t)?,
        water: None,
    })
}

/// A mesh read from a file: `material`, when set, replaces the file's
/// materials; otherwise they join the scene's (`import_materials`).
fn file_object(
    t: &Tbl,
    name: String,
    mut mesh: Mesh,
    material: Option<u32>,
    imported: &[Material],
    texture: &mut ImportTexture,
    materials: &mut Materials,
) -> R<Object> {
    match material {
        Some(m) => mesh.materials.iter_mut().for_each(|x| *x = m),
        None => import_materials(t, &mut mesh, imported, texture, materials)?,
    }
    placed(t, name, mesh)
}

fn mesh_object(
    t: &Tbl,
    name: String,
    within: &Confinement,
    material: Option<u32>,
    materials: &mut Materials,
) -> R<Object> {
    let full = within.file(t.str("path")?).map_err(|e| t.err("path", e))?;
    let loaded = obj::load(&full, within).map_err(|e| t.err("path", e))?;
    if material.is_none() {
        if let Some((mtl, why)) = loaded.mtl_errors.first() {
            return Err(t.err(
                "path",
                format!(
                    "MTL file {} named by OBJ file {}: {why} (set `material` on the object to ignore the MTL)",
                    mtl.display(),
                    full.display()
                ),
            ));
        }
        if loaded.mesh.materials.contains(&obj::NO_MATERIAL) {
            return Err(t.err(
                "material",
                format!(
                    "OBJ file {} has faces without an MTL material: set `material` on the object",
                    full.display()
                ),
            ));
        }
    }
    // An MTL `map_Kd` is the material's texture, at the OBJ's own UVs.
    let mut texture = |materials: &mut Materials, i: usize| -> R<Option<AlbedoTexture>> {
        let Some(path) = &loaded.albedo_textures[i] else {
            return Ok(None);
        };
        let index = materials.texture(path).map_err(|e| {
            t.err(
                "path",
                format!("map_Kd of MTL material `{}`: {e}", loaded.materials[i].name),
            )
        })?;
        Ok(Some(AlbedoTexture {
            index,
            uv_scale: Vec2::ONE,
            alpha_cutoff: 0.0,
            wrap: [Wrap::Repeat; 2],
        }))
    };
    file_object(
        t,
        name,
        loaded.mesh,
        material,
        &loaded.materials,
        &mut texture,
        materials,
    )
}

/// The albedo texture of a loaded file's material `i` (added to the
/// scene's textures), if it has one.
type ImportTexture<'a> = dyn FnMut(&mut Materials, usize) -> R<Option<AlbedoTexture>> + 'a;

/// Maps a loaded file's materials (indices into `imported` in
/// `mesh.materials`) to scene materials, adding only those faces use and
/// sharing identical ones (the same file used twice).
fn import_materials(
    t: &Tbl,
    mesh: &mut Mesh,
    imported: &[Material],
    texture: &mut ImportTexture,
    materials: &mut Materials,
) -> R<()> {
    let mut map = vec![None; imported.len()];
    for x in &mut mesh.materials {
        let slot = &mut map[*x as usize];
        let index = match *slot {
            Some(i) => i,
            None => {
                let mut m = imported[*x as usize].clone();
                m.texture = texture(materials, *x as usize)?;
                let i = materials.add_mtl(&m).ok_or_else(|| {
                    t.err(
                        "path",
                        format!("material name `{}` collides with another material", m.name),
                    )
                })?;
                *slot = Some(i);
                i
            }
        };
        *x = index as u32;
    }
    Ok(())
}

/// A `shape = "gltf"` object: every triangle of the file's default scene
/// (its node transforms applied) as one object; the file's camera and
/// lights are not used (the scene file has its own). `material`, when set,
/// replaces the file's materials.
fn gltf_object(
    t: &Tbl,
    name: String,
    within: &Confinement,
    material: Option<u32>,
    materials: &mut Materials,
) -> R<Object> {
    let full = within.file(t.str("path")?).map_err(|e| t.err("path", e))?;
    let mut loaded =
        gltf::load_allowing(&full, within.allowed()).map_err(|e| t.err("path", e.to_string()))?;
    if material.is_none() {
        for w in &loaded.warnings {
            log::warn!("{w}");
        }
        // The file's textures read the UVs through their KHR_texture_transform.
        loaded.transform_uvs();
    }
    // A base colour texture joins the scene's textures (an image file shared
    // with any other use of it); its transform is already in the UVs.
    let textures = &loaded.base_color_textures;
    let mut texture = |materials: &mut Materials, i: usize| -> R<Option<AlbedoTexture>> {
        Ok(textures[i].as_ref().map(|t| AlbedoTexture {
            index: materials.add_texture(t.pixels.clone()),
            uv_scale: Vec2::ONE,
            alpha_cutoff: t.alpha_cutoff,
            wrap: t.wrap,
        }))
    };
    file_object(
        t,
        name,
        loaded.mesh,
        material,
        &loaded.materials,
        &mut texture,
        materials,
    )
}

/// `translate * rotate_z * rotate_y * rotate_x * scale`: scale first, then X, Y, Z rotations, then translation.
fn transform(t: &Tbl) -> R<Mat4> {
    let translate = t.vec3_or("translate", Vec3::ZERO)?;
    let rotate = t.vec3_or("rotate", Vec3::ZERO)?;
    let scale = t.opt_rgb("scale")?.unwrap_or(Vec3::ONE);
    if scale.abs().min_element() < super::values::MIN_POSITIVE {
        return Err(t.err(
            "scale",
            format!(
                "must not be zero in any component (|scale| at least {:e}, docs/SCENES.md, Bounds), got {scale}",
                super::values::MIN_POSITIVE
            ),
        ));
    }
    let r = rotate * (std::f32::consts::PI / 180.0);
    let q = Quat::from_rotation_z(r.z) * Quat::from_rotation_y(r.y) * Quat::from_rotation_x(r.x);
    Ok(Mat4::from_translation(translate) * Mat4::from_quat(q) * Mat4::from_scale(scale))
}

/// An `animate` table (objects and sphere lights; docs/SCENES.md).
pub(super) fn animation(t: &Tbl) -> R<Option<Animation>> {
    let Some(a) = t.opt_table("animate")? else {
        return Ok(None);
    };
    a.check_keys(
        &[
            "spin",
            "spin_axis",
            "orbit_radius",
            "orbit_speed",
            "orbit_center",
            "bob_amplitude",
            "bob_frequency",
        ],
        "animate",
    )?;
    let anim = Animation {
        spin_deg_per_s: a.f32_or("spin", 0.0)?,
        spin_axis: direction(&a, "spin_axis", Some(Vec3::Y))?,
        orbit_center: a.vec3_or("orbit_center", Vec3::ZERO)?,
        orbit_radius: a.f32_or("orbit_radius", 0.0)?,
        orbit_deg_per_s: a.f32_or("orbit_speed", 0.0)?,
        bob_amplitude: a.f32_or("bob_amplitude", 0.0)?,
        bob_hz: a.f32_or("bob_frequency", 0.0)?,
    };
    if anim.orbit_radius < 0.0 {
        return Err(a.err(
            "orbit_radius",
            format!("must not be negative, got {}", anim.orbit_radius),
        ));
    }
    if anim.bob_hz < 0.0 {
        return Err(a.err(
            "bob_frequency",
            format!("must not be negative, got {}", anim.bob_hz),
        ));
    }
    Ok(Some(anim))
}
