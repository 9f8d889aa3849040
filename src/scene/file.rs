//! The scene file schema: reading the spanned TOML tree into the resolved
//! model, validating every value (docs/SCENES.md lists the fields).

use super::error::Source;
use super::node::{self, Node, Tbl, R};
use super::obj;
use super::shapes;
use super::types::*;
use super::water;
use crate::shader_bindings::MAX_LIGHTS;
use glam::{Mat4, Quat, Vec3};
use std::path::Path;

/// Default vertical field of view, degrees.
pub const DEFAULT_FOV_Y_DEG: f32 = 45.0;

/// Parses and validates `text`, read from `path` (relative paths inside resolve against its folder).
pub(crate) fn parse(text: &str, path: &Path) -> R<Scene> {
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
    let dir = path.parent().unwrap_or(Path::new(""));

    let camera = match root.opt_table("camera")? {
        Some(t) => camera(&t)?,
        None => return Err(root.err("camera", "missing required table [camera]")),
    };

    let light_tables = root.tables("light")?;
    if light_tables.is_empty() {
        return Err(root.err("light", "at least one [[light]] is required"));
    }
    if light_tables.len() > MAX_LIGHTS as usize {
        let extra = &light_tables[MAX_LIGHTS as usize];
        return Err(src.err(
            &extra.span,
            &extra.path,
            format!(
                "too many lights: {}, at most {MAX_LIGHTS} are supported",
                light_tables.len()
            ),
        ));
    }
    let lights = light_tables.iter().map(light).collect::<R<Vec<_>>>()?;

    let mut materials = Vec::new();
    for t in root.tables("material")? {
        let m = material(&t)?;
        if let Some(first) = materials.iter().position(|x: &Material| x.name == m.name) {
            return Err(t.err(
                "name",
                format!(
                    "duplicate material name `{}` (also material[{first}])",
                    m.name
                ),
            ));
        }
        materials.push(m);
    }
    let defined = materials.len();

    let object_tables = root.tables("object")?;
    if object_tables.is_empty() {
        return Err(root.err("object", "at least one [[object]] is required"));
    }
    let mut objects = Vec::with_capacity(object_tables.len());
    for (i, t) in object_tables.iter().enumerate() {
        objects.push(object(t, i, dir, &mut materials, defined)?);
    }

    let medium = root
        .opt_table("medium")?
        .map(|t| medium(&t, dir))
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

    Ok(Scene {
        source: path.to_path_buf(),
        camera,
        lights,
        materials,
        objects,
        medium,
        output,
    })
}

/// A non-zero vector, normalised.
fn direction(t: &Tbl, key: &str, default: Option<Vec3>) -> R<Vec3> {
    let v = match default {
        Some(d) => t.vec3_or(key, d)?,
        None => t.vec3(key)?,
    };
    let len = v.length();
    if !(len > 1e-12 && len.is_finite()) {
        return Err(t.err(key, format!("must be a non-zero direction, got {v}")));
    }
    Ok(v / len)
}

fn non_negative_rgb(t: &Tbl, key: &str, default: Option<Vec3>) -> R<Vec3> {
    let v = match default {
        Some(d) => t.opt_rgb(key)?.unwrap_or(d),
        None => t.rgb(key)?,
    };
    if v.min_element() < 0.0 {
        return Err(t.err(key, format!("must not be negative, got {v}")));
    }
    Ok(v)
}

fn unit_rgb(t: &Tbl, key: &str, default: Vec3) -> R<Vec3> {
    let v = non_negative_rgb(t, key, Some(default))?;
    if v.max_element() > 1.0 {
        return Err(t.err(key, format!("must be within [0, 1], got {v}")));
    }
    Ok(v)
}

fn positive(t: &Tbl, key: &str) -> R<f32> {
    let v = t.f32(key)?;
    if v <= 0.0 {
        return Err(t.err(key, format!("must be positive, got {v}")));
    }
    Ok(v)
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
                format!("unknown light kind `{other}`; expected point, spot or directional"),
            ))
        }
    }
    Ok(l)
}

fn material(t: &Tbl) -> R<Material> {
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
    };
    match kind {
        "diffuse" => {
            t.check_keys(&["name", "kind", "albedo"], "a diffuse material")?;
            m.color = unit_rgb(t, "albedo", Vec3::splat(0.8))?;
        }
        "mirror" => {
            t.check_keys(&["name", "kind", "reflectance"], "a mirror material")?;
            m.kind = MaterialKind::Mirror;
            m.color = unit_rgb(t, "reflectance", Vec3::ONE)?;
        }
        "dielectric" => {
            t.check_keys(
                &["name", "kind", "ior", "absorption"],
                "a dielectric material",
            )?;
            m.kind = MaterialKind::Dielectric;
            m.ior = t.f32_or("ior", 1.5)?;
            if m.ior < 1.0 {
                return Err(t.err("ior", format!("must be at least 1, got {}", m.ior)));
            }
            m.absorption = non_negative_rgb(t, "absorption", Some(Vec3::ZERO))?;
        }
        other => {
            return Err(t.err(
                "kind",
                format!("unknown material kind `{other}`; expected diffuse, mirror or dielectric"),
            ))
        }
    }
    Ok(m)
}

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

/// Reads `[[object]]` number `index`; MTL materials it brings are appended to `materials`
/// (the first `defined` of which come from `[[material]]`).
fn object(
    t: &Tbl,
    index: usize,
    dir: &Path,
    materials: &mut Vec<Material>,
    defined: usize,
) -> R<Object> {
    let shape = t.str("shape")?;
    let extra: &[&str] = match shape {
        "sphere" => &["center", "radius", "segments"],
        "plane" => &["center", "normal", "size", "tangent"],
        "box" => &["min", "max"],
        "torus" => &["center", "axis", "radii", "segments"],
        "cylinder" => &["p0", "p1", "radius", "caps", "segments"],
        "mesh" => &["path"],
        "water" => &[],
        other => {
            return Err(t.err(
                "shape",
                format!(
                    "unknown shape `{other}`; expected sphere, plane, box, torus, cylinder, mesh or water"
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
        Some(m) => match materials[..defined].iter().position(|x| x.name == m) {
            Some(i) => Some(i as u32),
            None => {
                let known: Vec<&str> = materials[..defined]
                    .iter()
                    .map(|x| x.name.as_str())
                    .collect();
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
        None if shape == "mesh" => None,
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
        _ => return mesh_object(t, name, dir, material, materials, defined),
    };
    let material = material.unwrap_or_default();
    mesh.materials = vec![material; mesh.indices.len()];
    Ok(Object {
        name,
        mesh,
        transform: transform(t)?,
        animation: animation(t)?,
        water: None,
    })
}

const WATER_KEYS: [&str; 8] = [
    "shape",
    "name",
    "material",
    "center",
    "size",
    "resolution",
    "base_height",
    "wave",
];

fn water_surface(t: &Tbl, material: u32) -> R<Water> {
    let center = match t.get("center") {
        Some(_) => numbers2(t, "center", false)?,
        None => [0.0; 2],
    };
    let size = size2(t, "size")?;
    let resolution = water_resolution(t)?;
    let base_height = t.f32_or("base_height", 0.0)?;
    let wave_tables = t.tables("wave")?;
    if wave_tables.len() > water::MAX_WAVES {
        let extra = &wave_tables[water::MAX_WAVES];
        return Err(t.src.err(
            &extra.span,
            &extra.path,
            format!(
                "too many waves: {}, at most {} are supported",
                wave_tables.len(),
                water::MAX_WAVES
            ),
        ));
    }
    let waves = wave_tables.iter().map(wave).collect::<R<Vec<_>>>()?;
    let surface = Water {
        center: center.into(),
        size: size.into(),
        resolution,
        base_height,
        material,
        waves,
    };
    let fold = surface.fold_measure();
    if fold >= 1.0 {
        return Err(t.err(
            "wave",
            format!(
                "the waves fold over themselves: the sum of steepness * 2 pi * amplitude / wavelength is {fold}, must be below 1"
            ),
        ));
    }
    Ok(surface)
}

/// `resolution = [nx, nz]`: cells per side within [1, MAX_RESOLUTION], at most MAX_CELLS in all.
fn water_resolution(t: &Tbl) -> R<[u32; 2]> {
    let n = t.req("resolution")?;
    let field = t.field("resolution");
    let items = match &n.node {
        Node::Array(items) if items.len() == 2 => items,
        other => {
            return Err(t.err(
                "resolution",
                format!("expected an array of 2 integers, got {}", describe(other)),
            ))
        }
    };
    let mut out = [0u32; 2];
    for (i, item) in items.iter().enumerate() {
        out[i] = match item.node {
            Node::Int(v) if (1..=water::MAX_RESOLUTION as i64).contains(&v) => v as u32,
            ref other => {
                return Err(t.src.err(
                    &item.span,
                    &format!("{field}[{i}]"),
                    format!(
                        "expected an integer within [1, {}], got {}",
                        water::MAX_RESOLUTION,
                        value_text(other)
                    ),
                ))
            }
        };
    }
    let cells = out[0] as u64 * out[1] as u64;
    if cells > water::MAX_CELLS {
        return Err(t.err(
            "resolution",
            format!(
                "{} x {} = {cells} cells, at most {} are supported",
                out[0],
                out[1],
                water::MAX_CELLS
            ),
        ));
    }
    Ok(out)
}

fn wave(t: &Tbl) -> R<Wave> {
    t.check_keys(
        &[
            "amplitude",
            "wavelength",
            "direction",
            "steepness",
            "speed",
            "phase",
        ],
        "a wave",
    )?;
    let amplitude = t.f32("amplitude")?;
    if amplitude < 0.0 {
        return Err(t.err(
            "amplitude",
            format!("must not be negative, got {amplitude}"),
        ));
    }
    let wavelength = positive(t, "wavelength")?;
    let steepness = t.f32_or("steepness", 0.0)?;
    if !(0.0..=1.0).contains(&steepness) {
        return Err(t.err(
            "steepness",
            format!("must be within [0, 1], got {steepness}"),
        ));
    }
    let speed = t.f32_or("speed", Wave::deep_water_speed(wavelength))?;
    if speed < 0.0 {
        return Err(t.err("speed", format!("must not be negative, got {speed}")));
    }
    Ok(Wave {
        amplitude,
        wavelength,
        direction_deg: t.f32_or("direction", 0.0)?,
        steepness,
        speed,
        phase: t.f32_or("phase", 0.0)?,
    })
}

/// Two positive numbers `[a, b]`.
fn size2(t: &Tbl, key: &str) -> R<[f32; 2]> {
    numbers2(t, key, true)
}

/// Two numbers `[a, b]`, positive ones when `positive`.
fn numbers2(t: &Tbl, key: &str, positive: bool) -> R<[f32; 2]> {
    let n = t.req(key)?;
    let field = t.field(key);
    let items = match &n.node {
        Node::Array(items) if items.len() == 2 => items,
        other => {
            return Err(t.err(
                key,
                format!("expected an array of 2 numbers, got {}", describe(other)),
            ))
        }
    };
    let mut out = [0.0; 2];
    for (i, item) in items.iter().enumerate() {
        out[i] = node::number(t.src, &format!("{field}[{i}]"), item)?;
        if positive && out[i] <= 0.0 {
            return Err(t.src.err(
                &item.span,
                &format!("{field}[{i}]"),
                format!("must be positive, got {}", out[i]),
            ));
        }
    }
    Ok(out)
}

fn describe(n: &Node) -> String {
    match n {
        Node::Array(items) => format!("an array of {} elements", items.len()),
        other => other.type_name().to_owned(),
    }
}

fn mesh_object(
    t: &Tbl,
    name: String,
    dir: &Path,
    material: Option<u32>,
    materials: &mut Vec<Material>,
    defined: usize,
) -> R<Object> {
    let rel = t.str("path")?;
    let full = dir.join(rel);
    let loaded = obj::load(&full).map_err(|e| t.err("path", e))?;
    let mut mesh = loaded.mesh;
    match material {
        Some(m) => mesh.materials.iter_mut().for_each(|x| *x = m),
        None => {
            if let Some((mtl, why)) = loaded.mtl_errors.first() {
                return Err(t.err(
                    "path",
                    format!(
                        "cannot read MTL file {} named by OBJ file {}: {why} (set `material` on the object to ignore the MTL)",
                        mtl.display(),
                        full.display()
                    ),
                ));
            }
            if mesh.materials.contains(&obj::NO_MATERIAL) {
                return Err(t.err(
                    "material",
                    format!(
                        "OBJ file {} has faces without an MTL material: set `material` on the object",
                        full.display()
                    ),
                ));
            }
            // Map the OBJ's materials to scene materials, sharing identical ones
            // (the same OBJ used twice).
            let mut map = vec![None; loaded.materials.len()];
            for x in &mut mesh.materials {
                let slot = &mut map[*x as usize];
                let index = match *slot {
                    Some(i) => i,
                    None => {
                        let m = &loaded.materials[*x as usize];
                        let i = match materials.iter().position(|e| e.name == m.name) {
                            Some(i) if i >= defined && materials[i] == *m => i,
                            Some(_) => {
                                return Err(t.err(
                                    "path",
                                    format!(
                                        "MTL material name `{}` collides with another material",
                                        m.name
                                    ),
                                ))
                            }
                            None => {
                                materials.push(m.clone());
                                materials.len() - 1
                            }
                        };
                        *slot = Some(i);
                        i
                    }
                };
                *x = index as u32;
            }
        }
    }
    Ok(Object {
        name,
        mesh,
        transform: transform(t)?,
        animation: animation(t)?,
        water: None,
    })
}

/// `translate * rotate_z * rotate_y * rotate_x * scale`: scale first, then X, Y, Z rotations, then translation.
fn transform(t: &Tbl) -> R<Mat4> {
    let translate = t.vec3_or("translate", Vec3::ZERO)?;
    let rotate = t.vec3_or("rotate", Vec3::ZERO)?;
    let scale = t.opt_rgb("scale")?.unwrap_or(Vec3::ONE);
    if scale.abs().min_element() < 1e-12 {
        return Err(t.err(
            "scale",
            format!("must not be zero in any component, got {scale}"),
        ));
    }
    let r = rotate * (std::f32::consts::PI / 180.0);
    let q = Quat::from_rotation_z(r.z) * Quat::from_rotation_y(r.y) * Quat::from_rotation_x(r.x);
    Ok(Mat4::from_translation(translate) * Mat4::from_quat(q) * Mat4::from_scale(scale))
}

fn animation(t: &Tbl) -> R<Option<Animation>> {
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

fn medium(t: &Tbl, dir: &Path) -> R<Medium> {
    t.check_keys(
        &["sigma_s", "sigma_a", "g", "bounds", "density"],
        "[medium]",
    )?;
    let sigma_s = non_negative_rgb(t, "sigma_s", None)?;
    let sigma_a = non_negative_rgb(t, "sigma_a", Some(Vec3::ZERO))?;
    let g = t.f32_or("g", 0.0)?;
    if g.abs() >= 1.0 {
        return Err(t.err("g", format!("must be within (-1, 1), got {g}")));
    }
    let Some(b) = t.opt_table("bounds")? else {
        return Err(t.err(
            "bounds",
            "missing required field (a table { min = [..], max = [..] })",
        ));
    };
    b.check_keys(&["min", "max"], "medium.bounds")?;
    let (bounds_min, bounds_max) = (b.vec3("min")?, b.vec3("max")?);
    if bounds_min.cmpge(bounds_max).any() {
        return Err(b.err(
            "max",
            format!("must exceed min in every component: min {bounds_min}, max {bounds_max}"),
        ));
    }
    let density = match t.get("density") {
        None => Density::Constant(1.0),
        Some(n) if matches!(n.node, Node::Table(_)) => {
            density_table(&Tbl::of(t.src, t.field("density"), n)?, dir)?
        }
        Some(_) => {
            let d = t.f32("density")?;
            if d < 0.0 {
                return Err(t.err("density", format!("must not be negative, got {d}")));
            }
            Density::Constant(d)
        }
    };
    Ok(Medium {
        sigma_s,
        sigma_a,
        g,
        bounds_min,
        bounds_max,
        density,
    })
}

fn density_table(t: &Tbl, dir: &Path) -> R<Density> {
    if let Some(noise) = t.opt_table("noise")? {
        t.check_keys(&["noise"], "medium.density")?;
        noise.check_keys(
            &["scale", "frequency", "octaves", "offset"],
            "medium.density.noise",
        )?;
        let scale = noise.f32_or("scale", 1.0)?;
        if scale < 0.0 {
            return Err(noise.err("scale", format!("must not be negative, got {scale}")));
        }
        let frequency = noise.f32_or("frequency", 1.0)?;
        if frequency <= 0.0 {
            return Err(noise.err("frequency", format!("must be positive, got {frequency}")));
        }
        let octaves = noise.opt_u32("octaves")?.unwrap_or(4);
        if !(1..=16).contains(&octaves) {
            return Err(noise.err("octaves", format!("must be within [1, 16], got {octaves}")));
        }
        let offset = noise.vec3_or("offset", Vec3::ZERO)?;
        return Ok(Density::Noise {
            scale,
            frequency,
            octaves,
            offset,
        });
    }
    if t.has("grid") {
        t.check_keys(&["grid", "dims"], "medium.density")?;
        let rel = t.str("grid")?;
        let dims_node = t.req("dims")?;
        let dims_field = t.field("dims");
        let mut dims = [0u32; 3];
        match &dims_node.node {
            Node::Array(items) if items.len() == 3 => {
                for (i, item) in items.iter().enumerate() {
                    dims[i] = match item.node {
                        Node::Int(v) if (1..=65536).contains(&v) => v as u32,
                        ref other => {
                            return Err(t.src.err(
                                &item.span,
                                &format!("{dims_field}[{i}]"),
                                format!(
                                    "expected an integer within [1, 65536], got {}",
                                    value_text(other)
                                ),
                            ))
                        }
                    }
                }
            }
            other => {
                return Err(t.err(
                    "dims",
                    format!("expected an array of 3 integers, got {}", describe(other)),
                ))
            }
        }
        let full = dir.join(rel);
        let bytes = std::fs::read(&full).map_err(|e| {
            t.err(
                "grid",
                format!("cannot read density grid {}: {e}", full.display()),
            )
        })?;
        let count = dims.iter().map(|&d| d as u64).product::<u64>();
        if bytes.len() as u64 != count * 4 {
            return Err(t.err(
                "grid",
                format!(
                    "density grid {} has {} bytes; dims {}x{}x{} need {} (little-endian f32, x fastest)",
                    full.display(),
                    bytes.len(),
                    dims[0],
                    dims[1],
                    dims[2],
                    count * 4
                ),
            ));
        }
        let values: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        if let Some((i, v)) = values
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(t.err(
                "grid",
                format!(
                    "density grid {}: value {i} is {v}, must be finite and non-negative",
                    full.display()
                ),
            ));
        }
        return Ok(Density::Grid { dims, values });
    }
    t.check_keys(&["noise", "grid", "dims"], "medium.density")?;
    Err(t.err(
        "noise",
        "density table needs `noise = { .. }` or `grid = \"file.raw\"` with `dims`",
    ))
}

fn value_text(n: &Node) -> String {
    match n {
        Node::Int(v) => v.to_string(),
        Node::Float(v) => v.to_string(),
        other => other.type_name().to_owned(),
    }
}
