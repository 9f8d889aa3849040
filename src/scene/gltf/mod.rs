//! glTF 2.0 files (`.gltf` with its buffers, or `.glb`) through the `gltf`
//! crate: the meshes of the default scene with their node transforms, the
//! materials mapped to the project's radiometry (base colour textures
//! decoded, `KHR_texture_transform` applied to `TEXCOORD_0`), the file's
//! camera and its `KHR_lights_punctual` lights. docs/SCENES.md ("glTF 2.0") states every
//! rule and mapping; `load` reads a file into a [`GltfAsset`], `scene` makes
//! a whole scene of one (`caustics render --scene model.glb`).
//!
//! Bad input is a [`GltfError`] naming the file and the glTF path of the
//! offending value (`meshes[2].primitives[0].attributes.NORMAL`). Every
//! accessor is checked (type, bounds, finite values, index range) before the
//! crate's reader touches it, so no file makes the loader panic.

mod files;
mod loader;
mod material;
mod scene;

use super::obj::{accumulate_normals, fix_zero_normals};
use super::paths::{AllowedPaths, Confinement};
use super::texture;
use super::types::*;
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use ::gltf::texture::WrappingMode;
use ::gltf::{json, Document, Semantic};
use files::*;
use glam::{Mat3, Mat4, Vec2, Vec3};
use loader::*;
use material::*;
pub use scene::*;
use std::borrow::Cow;
use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};

/// Luminous efficacy used to turn glTF's photometric light units into the
/// project's radiometric ones: 683 lm/W (the peak of the photopic curve,
/// 555 nm, the definition of the candela). Candela / 683 = W/sr and
/// lux / 683 = W/m², so a light exported from a tool in this "physical"
/// convention (Blender's default) comes back with its watts.
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Roughness up to which a glTF surface counts as smooth (a mirror or a
/// smooth dielectric) without a warning.
pub const SMOOTH_ROUGHNESS: f32 = 0.05;

/// Metals rougher than this become diffuse (their lobe is nearer a
/// Lambertian one than a mirror's); smoother ones become mirrors.
pub const ROUGH_METAL_LIMIT: f32 = 0.5;

/// Required extensions this loader reads (docs/SCENES.md).
const SUPPORTED_EXTENSIONS: [&str; 6] = [
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_ior",
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
];

/// A glTF file that could not be loaded: the file, the glTF path of the
/// offending value (empty for the file as a whole) and why.
#[derive(Debug)]
pub struct GltfError {
    pub file: PathBuf,
    /// glTF JSON path, e.g. `meshes[2].primitives[0].attributes.NORMAL`.
    pub at: String,
    pub message: String,
}

impl fmt::Display for GltfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // The file's own strings (names, URIs) may hold newlines: one line.
        let message = super::escape_control(&self.message);
        if self.at.is_empty() {
            write!(f, "{}: {message}", self.file.display())
        } else {
            let at = super::escape_control(&self.at);
            write!(f, "{}: {at}: {message}", self.file.display())
        }
    }
}

impl std::error::Error for GltfError {}

/// A material's `baseColorTexture`: its image decoded, and the
/// `KHR_texture_transform` its UVs go through.
#[derive(Clone, Debug)]
pub struct TextureRef {
    /// Index into the file's `textures`.
    pub texture: usize,
    /// Index into the file's `images`.
    pub image: usize,
    /// The image, decoded. Its `path` is the image file for a relative or
    /// `file:` URI (shared with a scene's `albedo_texture` of that file),
    /// else `<glTF file>#images[i]`.
    pub pixels: Texture,
    /// The `TEXCOORD_n` set the texture reads (after `KHR_texture_transform`'s override).
    pub tex_coord: u32,
    /// `KHR_texture_transform`: uv' = T(offset) R(rotation) S(scale) uv.
    pub offset: Vec2,
    /// Radians (the extension's GLSL: u' = u cos r - v sin r, v' = u sin r + v cos r).
    pub rotation: f32,
    pub scale: Vec2,
    /// `alphaMode = MASK` on a diffuse material: the surface is cut out
    /// where the texture's alpha is below this (`AlbedoTexture::alpha_cutoff`);
    /// 0 for an opaque material.
    pub alpha_cutoff: f32,
    /// The sampler's `wrapS`, `wrapT` (glTF default: repeat).
    pub wrap: [Wrap; 2],
}

impl TextureRef {
    /// `KHR_texture_transform` of one texture coordinate, the extension's
    /// `translation * rotation * scale` (GLSL column-major matrices): an
    /// affine map, so transforming the vertices' UVs equals transforming
    /// every interpolated UV.
    pub fn transform(&self, uv: Vec2) -> Vec2 {
        let s = uv * self.scale;
        let (sin, cos) = self.rotation.sin_cos();
        Vec2::new(cos * s.x - sin * s.y, sin * s.x + cos * s.y) + self.offset
    }
}

/// A glTF file read and converted.
#[derive(Debug)]
pub struct GltfAsset {
    /// Every triangle of the default scene in the file's root space (node
    /// transforms applied); `materials` index [`GltfAsset::materials`].
    /// `mesh.uvs` is `TEXCOORD_0` per vertex ((0, 0) where a primitive has
    /// none), before any `KHR_texture_transform`
    /// ([`GltfAsset::transform_uvs`]).
    pub mesh: Mesh,
    /// The materials the triangles use, converted (named `<file name>:<material name>`).
    pub materials: Vec<Material>,
    /// Per material, its `baseColorTexture`.
    pub base_color_textures: Vec<Option<TextureRef>>,
    /// The first camera met in the scene's node tree, if any.
    pub camera: Option<Camera>,
    /// `KHR_lights_punctual` lights of the scene's nodes, in project units.
    pub lights: Vec<Light>,
    /// One line per material that maps to its nearest supported material,
    /// and per feature read but not rendered; printed by whoever loads.
    pub warnings: Vec<String>,
    /// Whether every primitive gave normals (else smooth ones were computed).
    pub had_normals: bool,
}

/// Whether `path` names a glTF file (by its extension, `.gltf` or `.glb`).
pub fn is_gltf_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Reads a glTF file (its buffers relative to it, inside its folder's
/// tree). Every image file must exist; the base colour textures of the
/// materials the scene uses are decoded.
pub fn load(path: &Path) -> Result<GltfAsset, GltfError> {
    load_allowing(path, &AllowedPaths::default())
}

/// [`load`], the URIs also naming files in the trees of the `allowed`
/// folders (`--allow-paths`).
pub fn load_allowing(path: &Path, allowed: &AllowedPaths) -> Result<GltfAsset, GltfError> {
    let fail = |at: &str, message: String| GltfError {
        file: path.to_path_buf(),
        at: at.to_owned(),
        message,
    };
    let bytes = crate::scene::input::read_limited(path, crate::scene::input::MAX_GLTF_BYTES)
        .map_err(|e| fail("", format!("cannot read glTF file: {e}")))?;
    let (json_bytes, blob) = if bytes.starts_with(b"glTF") {
        // The header's length is the whole file's (glTF 2.0, 4.4.2): bytes
        // past it are not part of the asset, a file cut short is damaged.
        let declared = bytes
            .get(8..12)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        if declared.is_some_and(|n| n as usize != bytes.len()) {
            return Err(fail(
                "",
                format!(
                    "not a valid GLB container: its header gives a length of {} bytes, the file has {}",
                    declared.unwrap_or(0),
                    bytes.len()
                ),
            ));
        }
        let glb = ::gltf::Glb::from_slice(&bytes)
            .map_err(|e| fail("", format!("not a valid GLB container: {e}")))?;
        (glb.json, glb.bin)
    } else {
        (Cow::Borrowed(&bytes[..]), None)
    };
    let root: json::Root = json::deserialize::from_slice(&json_bytes)
        .map_err(|e| fail("", format!("not valid glTF JSON: {e}")))?;
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            let why = match ext.as_str() {
                "KHR_draco_mesh_compression" | "EXT_meshopt_compression" => format!(
                    "required extension {ext} (compressed geometry) is not supported: the file must be decompressed first"
                ),
                _ => format!("required extension {ext} is not supported"),
            };
            return Err(fail(&format!("extensionsRequired[{i}]"), why));
        }
    }
    let ignored: Vec<String> = root
        .extensions_used
        .iter()
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(&e.as_str()))
        .map(|e| {
            format!(
                "{}: extension {e} is used by the file but ignored",
                path.display()
            )
        })
        .collect();
    // gltf-json 1.4.1's validation indexes the POSITION accessor before it
    // checks that it exists (a panic, found by tests/suite/fuzz.rs): check first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = prim.attributes.get(&json::validation::Checked::Valid(
                json::mesh::Semantic::Positions,
            ));
            if let Some(a) = position.filter(|a| a.value() >= root.accessors.len()) {
                return Err(fail(
                    &format!("meshes[{m}].primitives[{p}].attributes.POSITION"),
                    format!(
                        "accessor {} does not exist (the file has {})",
                        a.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    let document = Document::from_json(root).map_err(|e| match e {
        ::gltf::Error::Validation(errors) => {
            let (p, why) = &errors[0];
            let more = match errors.len() {
                1 => String::new(),
                n => format!(" (and {} more problem(s))", n - 1),
            };
            fail(&p.to_string(), format!("{why}{more}"))
        }
        other => fail("", other.to_string()),
    })?;
    let within = Confinement::gltf(path, allowed);
    let buffers = read_buffers(&document, blob.as_deref(), &within, &fail)?;
    check_images(&document, &within, &fail)?;

    let file_name = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let mut reader = Loader {
        fail: &fail,
        buffers: &buffers,
        file_name,
        within,
        asset: GltfAsset {
            mesh: Mesh::default(),
            materials: Vec::new(),
            base_color_textures: Vec::new(),
            camera: None,
            lights: Vec::new(),
            warnings: ignored,
            had_normals: true,
        },
        material_map: HashMap::new(),
        material_names: HashMap::new(),
        computed: Vec::new(),
        images: HashMap::new(),
        gltf_path: path,
    };
    let Some(scene) = document
        .default_scene()
        .or_else(|| document.scenes().next())
    else {
        return Err(fail("scenes", "the file has no scene".into()));
    };
    // Depth-first in file order. glTF nodes form strict trees: a node met
    // twice (a cycle, or two parents) is refused, which also bounds the walk.
    let mut seen = vec![false; document.nodes().count()];
    let mut stack: Vec<(::gltf::Node, Mat4)> = scene
        .nodes()
        .map(|n| (n, Mat4::IDENTITY))
        .collect::<Vec<_>>();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(fail(
                &format!("nodes[{}]", node.index()),
                "the node is met twice in the scene's hierarchy (a cycle, or two parents): glTF nodes form strict trees".into(),
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(fail(
                &format!("nodes[{}]", node.index()),
                "the node's transform is not finite".into(),
            ));
        }
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                reader.primitive(&mesh, &prim, world)?;
            }
        }
        if let Some(cam) = node.camera() {
            if reader.asset.camera.is_none() {
                reader.camera(&cam, world);
            }
        }
        if let Some(light) = node.light() {
            reader.light(&light, world)?;
        }
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    let Loader {
        mut asset,
        computed,
        ..
    } = reader;
    if asset.mesh.indices.is_empty() {
        return Err(fail(
            "scenes",
            "the default scene has no triangles (no mesh primitives)".into(),
        ));
    }
    for range in computed {
        accumulate_normals(&mut asset.mesh, range);
    }
    fix_zero_normals(&mut asset.mesh);
    Ok(asset)
}

impl GltfAsset {
    /// Puts each vertex's UV through the `KHR_texture_transform` of its
    /// material's base colour texture, for rendering with the file's
    /// materials (a replacing material reads the untransformed
    /// `TEXCOORD_0`). A vertex belongs to one primitive, hence one
    /// material.
    pub fn transform_uvs(&mut self) {
        let mut done = vec![false; self.mesh.uvs.len()];
        for (t, &m) in self.mesh.indices.iter().zip(&self.mesh.materials) {
            let Some(tex) = &self.base_color_textures[m as usize] else {
                continue;
            };
            for &i in t {
                if !std::mem::replace(&mut done[i as usize], true) {
                    self.mesh.uvs[i as usize] = tex.transform(self.mesh.uvs[i as usize]);
                }
            }
        }
    }
}

type Fail<'a> = &'a dyn Fn(&str, String) -> GltfError;
