//! OBJ/MTL meshes via `tobj`.
//!
//! Rules (docs/SCENES.md):
//! - Faces are triangulated (quads and n-gons as fans); points and lines are ignored.
//! - Negative (relative) indices are resolved by tobj.
//! - Normals: when every face vertex has a normal in the file, those are used
//!   (normalised); otherwise smooth, area-weighted vertex normals are computed
//!   over shared positions.
//! - Texture coordinates (`vt`) are kept, with v flipped (OBJ's v = 0 is the
//!   image's bottom row, the renderer's the top row); without them UVs are 0.
//! - Materials from the MTL become scene materials named `"<obj file name>:<mtl name>"`
//!   (see [`convert_material`]); a diffuse one's `map_Kd` is its albedo texture.

use super::paths::Confinement;
use super::types::{Material, MaterialKind, Mesh};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Per-triangle material marker for faces with no `usemtl` (or an unknown one).
pub const NO_MATERIAL: u32 = u32::MAX;

/// An OBJ file read and converted.
#[derive(Debug)]
pub struct ObjMesh {
    /// `materials` holds indices into `ObjMesh::materials`, or [`NO_MATERIAL`].
    pub mesh: Mesh,
    /// MTL materials converted, named `"<obj file name>:<mtl name>"`.
    pub materials: Vec<Material>,
    /// Per material, the `map_Kd` file of a diffuse one (resolved against
    /// the OBJ's folder): the caller decodes it and sets `Material::texture`.
    pub albedo_textures: Vec<Option<PathBuf>>,
    /// The MTL files the OBJ names that could not be read (path, why).
    pub mtl_errors: Vec<(PathBuf, String)>,
    /// Whether the file gave normals for every face vertex.
    pub had_normals: bool,
}

/// MTL to scene material: `illum` 4, 6 or 7, or `Ni` > 1 with `d` < 1, make a
/// dielectric of ior `Ni` (1.5 when absent); `illum 3` a mirror of
/// reflectance `Ks` (1 when absent); anything else a diffuse of albedo `Kd`
/// (0.8 when absent). Colours are clamped to [0, 1]. The values are assumed
/// checked by [`check_mtl_values`].
pub fn convert_material(prefix: &str, m: &tobj::Material) -> Material {
    let rgb = |c: Option<[f32; 3]>, default: f32| {
        c.map_or(Vec3::splat(default), Vec3::from)
            .clamp(Vec3::ZERO, Vec3::ONE)
    };
    let name = format!("{prefix}:{}", m.name);
    if is_dielectric(m) {
        Material {
            name,
            kind: MaterialKind::Dielectric,
            color: Vec3::ONE,
            ior: m.optical_density.unwrap_or(1.5),
            absorption: Vec3::ZERO,
            texture: None,
            emission: Vec3::ZERO,
            specular: Vec3::ZERO,
            scattering: None,
        }
    } else if m.illumination_model == Some(3) {
        Material {
            name,
            kind: MaterialKind::Mirror,
            color: rgb(m.specular, 1.0),
            ior: 1.0,
            absorption: Vec3::ZERO,
            texture: None,
            emission: Vec3::ZERO,
            specular: Vec3::ZERO,
            scattering: None,
        }
    } else {
        Material {
            name,
            kind: MaterialKind::Diffuse,
            color: rgb(m.diffuse, 0.8),
            ior: 1.0,
            absorption: Vec3::ZERO,
            texture: None,
            emission: Vec3::ZERO,
            specular: Vec3::ZERO,
            scattering: None,
        }
    }
}

/// `illum` 4, 6 or 7, or `Ni` > 1 with `d` < 1.
fn is_dielectric(m: &tobj::Material) -> bool {
    let transparent =
        m.optical_density.is_some_and(|n| n > 1.0) && m.dissolve.is_some_and(|d| d < 1.0);
    matches!(m.illumination_model, Some(4 | 6 | 7)) || transparent
}

/// Relative (negative) indices of faces, lines and points must stay within
/// the `v`, `vt` and `vn` statements before them: tobj 4 turns one that
/// reaches before the first into a huge index and overflows (a panic, found
/// by tests/suite/fuzz.rs). One pass over the bytes; only statements holding a
/// `-` are parsed. The error is (1-based line, message).
fn check_relative_indices(bytes: &[u8]) -> Result<(), (usize, String)> {
    let mut counts = [0i64; 3]; // v, vt, vn
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = line.trim_ascii_start();
        match line {
            [b'v', b' ' | b'\t', ..] => counts[0] += 1,
            [b'v', b't', b' ' | b'\t', ..] => counts[1] += 1,
            [b'v', b'n', b' ' | b'\t', ..] => counts[2] += 1,
            [b'f' | b'l' | b'p', b' ' | b'\t', rest @ ..] if rest.contains(&b'-') => {
                let text = String::from_utf8_lossy(line);
                for corner in text.split_whitespace().skip(1) {
                    for (k, index) in corner.split('/').enumerate().take(3) {
                        let Ok(x) = index.parse::<i64>() else {
                            continue;
                        };
                        if x < 0 && counts[k] + x < 0 {
                            let what = ["v", "vt", "vn"][k];
                            return Err((
                                i + 1,
                                format!(
                                    "`{}`: relative index {x} reaches before the first `{what}` ({} so far)",
                                    text.trim(),
                                    counts[k]
                                ),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// `Ka`, `Kd`, `Ks` and `Ke` with one number mean that number for r, g
/// and b (the MTL format's rule); tobj 4 reads exactly three and panics on
/// fewer (found by tests/suite/fuzz.rs), so one is repeated here and none or two
/// are an error naming the line.
fn complete_colours(text: &str) -> Result<String, String> {
    let mut out = String::with_capacity(text.len() + 16);
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or("");
        let values: Vec<&str> = words.collect();
        if matches!(key, "Ka" | "Kd" | "Ks" | "Ke") {
            match values.len() {
                1 => {
                    let v = values[0];
                    out.push_str(&format!("{key} {v} {v} {v}\n"));
                    continue;
                }
                0 | 2 => {
                    return Err(format!(
                        "line {}: `{}`: {key} needs 3 numbers (or 1 for all three)",
                        i + 1,
                        line.trim()
                    ))
                }
                _ => {}
            }
        }
        out.push_str(line);
        out.push('\n');
    }
    Ok(out)
}

/// The largest `Ni` a dielectric may have: the top of the MTL format's
/// range (0.001 to 10); diamond is 2.42.
pub const MAX_MTL_IOR: f32 = 10.0;

/// Checks an MTL material's numbers (docs/SCENES.md): every number of
/// `Ka`, `Kd`, `Ks`, `Ke`, `Tf`, `Ns`, `d` and `Ni` finite; `Kd`, `Ks`,
/// `Ke` not negative (above 1, `Kd` and `Ks` are clamped to 1 on
/// conversion); `d` and `Tf` within [0, 1]; the `Ni` of a material that
/// becomes a dielectric within [1, 10]. The error names the material and
/// the statement.
pub fn check_mtl_values(m: &tobj::Material) -> Result<(), String> {
    let bad = |key: &str, why: String| format!("material `{}`: {key}: {why}", m.name);
    let finite = |key: &str, v: &[f32]| -> Result<(), String> {
        match v.iter().find(|x| !x.is_finite()) {
            Some(x) => Err(bad(key, format!("must be finite, got {x}"))),
            None => Ok(()),
        }
    };
    let in_range = |key: &str, v: &[f32], lo: f32, hi: f32, what: &str| -> Result<(), String> {
        finite(key, v)?;
        match v.iter().find(|&&x| !(lo..=hi).contains(&x)) {
            Some(x) => Err(bad(key, format!("must be {what}, got {x}"))),
            None => Ok(()),
        }
    };
    for (key, c) in [
        ("Ka", m.ambient),
        ("Kd", m.diffuse),
        ("Ks", m.specular),
        ("Ke", m.emissive),
    ] {
        let Some(c) = c else { continue };
        match key {
            "Ka" => finite(key, &c)?,
            _ => in_range(key, &c, 0.0, f32::INFINITY, "non-negative")?,
        }
    }
    if let Some(ns) = m.shininess {
        finite("Ns", &[ns])?;
    }
    if let Some(d) = m.dissolve {
        in_range("d", &[d], 0.0, 1.0, "within [0, 1]")?;
    }
    if let Some(tf) = m.unknown_param.get("Tf") {
        let mut words = tf.split_whitespace().peekable();
        // `Tf spectral file.rfl [factor]` names a file; `Tf xyz x y z` is CIE XYZ.
        if words.peek() != Some(&"spectral") {
            if words.peek() == Some(&"xyz") {
                words.next();
            }
            let values = words
                .map(|w| w.parse::<f32>())
                .collect::<Result<Vec<f32>, _>>()
                .map_err(|_| bad("Tf", format!("expected numbers, got `{tf}`")))?;
            in_range("Tf", &values, 0.0, 1.0, "within [0, 1]")?;
        }
    }
    if let Some(ni) = m.optical_density {
        finite("Ni", &[ni])?;
        if is_dielectric(m) && !(1.0..=MAX_MTL_IOR).contains(&ni) {
            return Err(bad(
                "Ni",
                format!(
                    "the index of refraction of a dielectric must be within [1, {MAX_MTL_IOR}], got {ni}"
                ),
            ));
        }
    }
    Ok(())
}

/// Reads an OBJ file (and the MTL files it names, relative to it). The
/// MTL files and the textures they name must lie `within` the scene's
/// trees (a refused one is an error even when the object's `material`
/// would ignore the MTL: it is never read). The error is a message that
/// names the file.
pub fn load(path: &Path, within: &Confinement) -> Result<ObjMesh, String> {
    let bytes = super::input::read_limited(path, super::input::MAX_OBJ_BYTES)
        .map_err(|e| format!("cannot open OBJ file {}: {e}", path.display()))?;
    check_relative_indices(&bytes)
        .map_err(|(line, why)| format!("OBJ file {}:{line}: {why}", path.display()))?;
    let mut reader = &bytes[..];
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mtl_errors = std::cell::RefCell::new(Vec::new());
    let refused = std::cell::RefCell::new(None);
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, |mtl: &Path| {
        let full = match within.resolve(&dir, mtl) {
            Ok(full) => full,
            Err(why) => {
                refused.borrow_mut().get_or_insert(why);
                return Err(tobj::LoadError::OpenFileFailed);
            }
        };
        let result = super::input::read_text_limited(&full, super::input::MAX_MTL_BYTES)
            .map_err(|e| format!("cannot read it: {e}"))
            .and_then(|text| complete_colours(&text))
            .and_then(|text| {
                tobj::load_mtl_buf(&mut text.as_bytes()).map_err(|e| format!("cannot read it: {e}"))
            })
            .and_then(|(materials, names)| {
                materials.iter().try_for_each(check_mtl_values)?;
                Ok((materials, names))
            });
        if let Err(e) = &result {
            mtl_errors.borrow_mut().push((full, e.clone()));
        }
        result.map_err(|_| tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| format!("cannot load OBJ file {}: {e}", path.display()))?;
    if let Some(why) = refused.into_inner() {
        return Err(format!("OBJ file {}: mtllib {why}", path.display()));
    }
    // An MTL that failed is reported through `mtl_errors`; tobj's own error is redundant.
    let materials = materials.unwrap_or_default();

    let prefix = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let mut converted: Vec<Material> = materials
        .iter()
        .map(|m| convert_material(&prefix, m))
        .collect();
    let mut albedo_textures = Vec::with_capacity(materials.len());
    for (m, c) in materials.iter().zip(&mut converted) {
        let texture = m
            .diffuse_texture
            .as_deref()
            .map(str::trim)
            .filter(|t| c.kind == MaterialKind::Diffuse && !t.is_empty())
            .map(|t| within.resolve(&dir, Path::new(t)))
            .transpose()
            .map_err(|why| {
                format!(
                    "OBJ file {}: map_Kd of MTL material `{}`: {why}",
                    path.display(),
                    m.name
                )
            })?;
        // `Kd` scales `map_Kd`; without a `Kd` the texture stands alone.
        if texture.is_some() && m.diffuse.is_none() {
            c.color = Vec3::ONE;
        }
        albedo_textures.push(texture);
    }

    let mut mesh = Mesh::default();
    let mut all_normals = true;
    // File normals that are zero or not finite (`vn 0 0 0`, `vn nan 0 0`).
    let mut bad_normals = 0;
    for model in &models {
        let m = &model.mesh;
        if m.indices.len() % 3 != 0 || m.indices.is_empty() {
            continue;
        }
        let material = m
            .material_id
            .filter(|&i| i < materials.len())
            .map_or(NO_MATERIAL, |i| i as u32);
        let npos = m.positions.len() / 3;
        let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(Vec3::from_slice).collect();
        if positions.iter().any(|p| !p.is_finite()) {
            // tobj keeps no line numbers: find the statement in the file.
            let at = first_non_finite(path, "v")
                .map_or_else(String::new, |(line, text)| format!(":{line}: `{text}`"));
            return Err(format!(
                "OBJ file {}{at}: a vertex position of object `{}` is not finite",
                path.display(),
                model.name
            ));
        }
        if let Some(&bad) = m.indices.iter().find(|&&i| i as usize >= npos) {
            return Err(format!(
                "OBJ file {}: face index {bad} out of range",
                path.display()
            ));
        }
        let nnorm = m.normals.len() / 3;
        let has_normals = m.normal_indices.len() == m.indices.len()
            && m.normal_indices.iter().all(|&i| (i as usize) < nnorm);
        let ntex = m.texcoords.len() / 2;
        let has_uvs = m.texcoord_indices.len() == m.indices.len()
            && m.texcoord_indices.iter().all(|&i| (i as usize) < ntex);
        all_normals &= has_normals;
        // Without normals in the file: smooth, area-weighted normals over
        // shared positions (each face's unnormalised cross product summed).
        let mut smooth = Vec::new();
        if !has_normals {
            smooth = vec![Vec3::ZERO; npos];
            for t in m.indices.chunks_exact(3) {
                let p = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
                let n = (p[1] - p[0]).cross(p[2] - p[0]);
                for &i in t {
                    smooth[i as usize] += n;
                }
            }
        }
        // One vertex per distinct (position, normal, texcoord) triple.
        let base = mesh.positions.len() as u32;
        let mut map: HashMap<(u32, u32, u32), u32> = HashMap::with_capacity(m.indices.len());
        let mut remap = Vec::with_capacity(m.indices.len());
        for (k, &pi) in m.indices.iter().enumerate() {
            let ni = if has_normals {
                m.normal_indices[k]
            } else {
                u32::MAX
            };
            let ti = if has_uvs {
                m.texcoord_indices[k]
            } else {
                u32::MAX
            };
            let next = base + map.len() as u32;
            let idx = *map.entry((pi, ni, ti)).or_insert_with(|| {
                let n = if has_normals {
                    Vec3::from_slice(&m.normals[ni as usize * 3..ni as usize * 3 + 3])
                } else {
                    smooth[pi as usize]
                };
                let uv = if has_uvs {
                    let t = &m.texcoords[ti as usize * 2..ti as usize * 2 + 2];
                    Vec2::new(t[0], 1.0 - t[1])
                } else {
                    Vec2::ZERO
                };
                mesh.positions.push(positions[pi as usize]);
                let n = if n.is_finite() {
                    n.normalize_or_zero()
                } else {
                    Vec3::ZERO
                };
                bad_normals += usize::from(has_normals && n == Vec3::ZERO);
                mesh.normals.push(n);
                mesh.uvs.push(if uv.is_finite() { uv } else { Vec2::ZERO });
                next
            });
            remap.push(idx);
        }
        for t in remap.chunks_exact(3) {
            mesh.indices.push([t[0], t[1], t[2]]);
            mesh.materials.push(material);
        }
    }
    if mesh.indices.is_empty() {
        return Err(format!("OBJ file {} has no faces", path.display()));
    }
    if bad_normals > 0 {
        log::warn!(
            "OBJ file {}: {bad_normals} vertex normal(s) zero or not finite (first: {}); they take the normal of a face using them",
            path.display(),
            first_non_finite(path, "vn")
                .map_or_else(|| "a zero `vn`".to_owned(), |(l, t)| format!("line {l}, `{t}`")),
        );
    }
    fix_zero_normals(&mut mesh);
    Ok(ObjMesh {
        mesh,
        materials: converted,
        albedo_textures,
        mtl_errors: mtl_errors.into_inner(),
        had_normals: all_normals,
    })
}

/// The first `keyword` statement (`v`, `vn`) of an OBJ file with a number
/// that is not finite: its 1-based line and its text. Read again only when
/// loading has found one, so loading stays one pass.
fn first_non_finite(path: &Path, keyword: &str) -> Option<(usize, String)> {
    let text = super::input::read_text_limited(path, super::input::MAX_OBJ_BYTES).ok()?;
    text.lines().enumerate().find_map(|(i, line)| {
        let mut words = line.split_whitespace();
        let bad = words.next() == Some(keyword)
            && words.any(|w| w.parse::<f32>().is_ok_and(|x| !x.is_finite()));
        bad.then(|| (i + 1, line.trim().to_owned()))
    })
}

/// Adds each triangle's area-weighted face normal (the unnormalised cross
/// product) to its vertices, then normalises: smooth, area-weighted normals.
pub(crate) fn accumulate_normals(mesh: &mut Mesh, range: std::ops::Range<usize>) {
    for t in &mesh.indices[range.clone()] {
        let p = t.map(|i| mesh.positions[i as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        for &i in t {
            mesh.normals[i as usize] += n;
        }
    }
    for t in &mesh.indices[range] {
        for &i in t {
            let n = &mut mesh.normals[i as usize];
            *n = n.normalize_or_zero();
        }
    }
}

/// Vertices left without a usable normal (only degenerate faces, or a zero
/// normal in the file) take the normal of a face that uses them, or +y.
pub(crate) fn fix_zero_normals(mesh: &mut Mesh) {
    if mesh.normals.iter().all(|n| *n != Vec3::ZERO) {
        return;
    }
    for t in &mesh.indices {
        let p = t.map(|i| mesh.positions[i as usize]);
        let face = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or(Vec3::Y);
        for &i in t {
            if mesh.normals[i as usize] == Vec3::ZERO {
                mesh.normals[i as usize] = face;
            }
        }
    }
    for n in &mut mesh.normals {
        if *n == Vec3::ZERO {
            *n = Vec3::Y;
        }
    }
}
