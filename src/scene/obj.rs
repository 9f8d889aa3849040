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

use super::types::{Material, MaterialKind, Mesh};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::io::BufReader;
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
/// (0.8 when absent). Colours are clamped to [0, 1].
pub fn convert_material(prefix: &str, m: &tobj::Material) -> Material {
    let rgb = |c: Option<[f32; 3]>, default: f32| {
        c.map_or(Vec3::splat(default), Vec3::from)
            .clamp(Vec3::ZERO, Vec3::ONE)
    };
    let ni = m.optical_density.filter(|n| n.is_finite());
    let illum = m.illumination_model.unwrap_or(2);
    let transparent = ni.is_some_and(|n| n > 1.0) && m.dissolve.is_some_and(|d| d < 1.0);
    let name = format!("{prefix}:{}", m.name);
    if matches!(illum, 4 | 6 | 7) || transparent {
        Material {
            name,
            kind: MaterialKind::Dielectric,
            color: Vec3::ONE,
            ior: ni.filter(|&n| n >= 1.0).unwrap_or(1.5),
            absorption: Vec3::ZERO,
            texture: None,
            emission: Vec3::ZERO,
        }
    } else if illum == 3 {
        Material {
            name,
            kind: MaterialKind::Mirror,
            color: rgb(m.specular, 1.0),
            ior: 1.0,
            absorption: Vec3::ZERO,
            texture: None,
            emission: Vec3::ZERO,
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
        }
    }
}

/// Reads an OBJ file (and the MTL files it names, relative to it).
/// The error is a message that names the file.
pub fn load(path: &Path) -> Result<ObjMesh, String> {
    let file = std::fs::File::open(path)
        .map_err(|e| format!("cannot open OBJ file {}: {e}", path.display()))?;
    let mut reader = BufReader::new(file);
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mtl_errors = std::cell::RefCell::new(Vec::new());
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, |mtl: &Path| {
        let full = dir.join(mtl);
        let result = std::fs::File::open(&full)
            .map_err(|e| e.to_string())
            .and_then(|f| tobj::load_mtl_buf(&mut BufReader::new(f)).map_err(|e| e.to_string()));
        if let Err(e) = &result {
            mtl_errors.borrow_mut().push((full, e.clone()));
        }
        result.map_err(|_| tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| format!("cannot load OBJ file {}: {e}", path.display()))?;
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
            .map(|t| dir.join(t));
        // `Kd` scales `map_Kd`; without a `Kd` the texture stands alone.
        if texture.is_some() && m.diffuse.is_none() {
            c.color = Vec3::ONE;
        }
        albedo_textures.push(texture);
    }

    let mut mesh = Mesh::default();
    let mut all_normals = true;
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
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(format!(
                "OBJ file {}: vertex position {i} of object `{}` is not finite",
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
                mesh.normals.push(if n.is_finite() {
                    n.normalize_or_zero()
                } else {
                    Vec3::ZERO
                });
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
    fix_zero_normals(&mut mesh);
    Ok(ObjMesh {
        mesh,
        materials: converted,
        albedo_textures,
        mtl_errors: mtl_errors.into_inner(),
        had_normals: all_normals,
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
