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

use super::obj::{accumulate_normals, fix_zero_normals};
use super::texture;
use super::types::*;
use crate::shader_bindings::MAX_LIGHTS;
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use ::gltf::{json, Document, Semantic};
use glam::{Mat3, Mat4, Vec2, Vec3};
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
        if self.at.is_empty() {
            write!(f, "{}: {}", self.file.display(), self.message)
        } else {
            write!(f, "{}: {}: {}", self.file.display(), self.at, self.message)
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

/// Reads a glTF file (its buffers relative to it). Every image file must
/// exist; the base colour textures of the materials the scene uses are
/// decoded.
pub fn load(path: &Path) -> Result<GltfAsset, GltfError> {
    let fail = |at: &str, message: String| GltfError {
        file: path.to_path_buf(),
        at: at.to_owned(),
        message,
    };
    let bytes = std::fs::read(path).map_err(|e| fail("", format!("cannot read glTF file: {e}")))?;
    let (json_bytes, blob) = if bytes.starts_with(b"glTF") {
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
    let dir = path.parent().unwrap_or(Path::new(""));
    let buffers = read_buffers(&document, blob.as_deref(), dir, &fail)?;
    check_images(&document, dir, &fail)?;

    let file_name = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let mut reader = Loader {
        fail: &fail,
        buffers: &buffers,
        file_name,
        dir,
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
            reader.light(&light, world);
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

/// Every buffer's bytes: the GLB chunk (borrowed, not copied), a base64
/// `data:` URI or a file beside the glTF, at least `byteLength` long.
fn read_buffers<'b>(
    document: &Document,
    blob: Option<&'b [u8]>,
    dir: &Path,
    fail: Fail,
) -> Result<Vec<Cow<'b, [u8]>>, GltfError> {
    let mut out = Vec::new();
    for b in document.buffers() {
        let at = format!("buffers[{}]", b.index());
        let data = match b.source() {
            ::gltf::buffer::Source::Bin => blob.map(Cow::Borrowed).ok_or_else(|| {
                fail(
                    &at,
                    "refers to the GLB binary chunk, but the file has none".into(),
                )
            })?,
            ::gltf::buffer::Source::Uri(uri) => {
                Cow::Owned(read_uri(uri, dir).map_err(|e| fail(&format!("{at}.uri"), e))?)
            }
        };
        if data.len() < b.length() {
            return Err(fail(
                &format!("{at}.byteLength"),
                format!("is {} but the data holds {} bytes", b.length(), data.len()),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// A URI's bytes: a base64 `data:` URI decoded, else a file (relative to `dir`).
fn read_uri(uri: &str, dir: &Path) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let payload = rest
            .split_once(";base64,")
            .map(|(_, p)| p)
            .ok_or("only base64 data URIs are supported")?;
        return base64_decode(payload).ok_or_else(|| "invalid base64 data".into());
    }
    let file = uri_file(uri, dir).ok_or_else(|| format!("unsupported URI scheme in `{uri}`"))?;
    std::fs::read(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))
}

/// The file a non-`data:` URI names: `file:` or relative (percent-decoded).
fn uri_file(uri: &str, dir: &Path) -> Option<PathBuf> {
    if let Some(p) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        return Some(PathBuf::from(percent_decode(p)));
    }
    if uri.contains(':') {
        return None;
    }
    Some(dir.join(percent_decode(uri)))
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = b.get(i + 1..i + 3).and_then(|h| {
            std::str::from_utf8(h)
                .ok()
                .and_then(|h| u8::from_str_radix(h, 16).ok())
        });
        match (b[i], hex) {
            (b'%', Some(v)) => {
                out.push(v);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Standard base64 (RFC 4648, `=` padding optional); `None` on a bad character.
fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' => Some(62),
        b'/' => Some(63),
        _ => None,
    };
    let s = s.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0);
    for &c in s {
        acc = (acc << 6) | value(c)? as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    Some(out)
}

/// Every image given by a file URI must exist (images are not decoded here).
fn check_images(document: &Document, dir: &Path, fail: Fail) -> Result<(), GltfError> {
    for image in document.images() {
        if let ::gltf::image::Source::Uri { uri, .. } = image.source() {
            if uri.starts_with("data:") {
                continue;
            }
            let at = format!("images[{}].uri", image.index());
            let file = uri_file(uri, dir)
                .ok_or_else(|| fail(&at, format!("unsupported URI scheme in `{uri}`")))?;
            if !file.is_file() {
                return Err(fail(
                    &at,
                    format!("image file {} not found", file.display()),
                ));
            }
        }
    }
    Ok(())
}

struct Loader<'a> {
    fail: Fail<'a>,
    buffers: &'a [Cow<'a, [u8]>],
    file_name: String,
    dir: &'a Path,
    asset: GltfAsset,
    /// glTF material index (None: the default material) -> asset material.
    material_map: HashMap<Option<usize>, Option<u32>>,
    /// Names given so far -> count, to keep names unique within the file.
    material_names: HashMap<String, usize>,
    /// Index ranges whose normals are computed (primitives without NORMAL).
    computed: Vec<std::ops::Range<usize>>,
    /// Images decoded so far, by index into the file's `images`.
    images: HashMap<usize, Texture>,
    gltf_path: &'a Path,
}

impl Loader<'_> {
    /// Checks an accessor before it is read: element type, a buffer view,
    /// no sparse storage, a stride that fits the element, and all of its
    /// elements inside the view and the view inside the buffer.
    fn check_accessor(
        &self,
        a: &::gltf::Accessor,
        at: &str,
        dims: Dimensions,
        types: &[DataType],
    ) -> Result<(), GltfError> {
        let fail = |m: String| (self.fail)(at, format!("accessor {}: {m}", a.index()));
        if a.dimensions() != dims || !types.contains(&a.data_type()) {
            return Err(fail(format!(
                "is {:?} {:?}, expected {:?} of {:?}",
                a.dimensions(),
                a.data_type(),
                dims,
                types
            )));
        }
        if a.sparse().is_some() {
            return Err(fail("sparse accessors are not supported".into()));
        }
        if a.count() == 0 {
            return Err(fail("has count 0".into()));
        }
        let Some(view) = a.view() else {
            return Err(fail("has no bufferView".into()));
        };
        let elem = a.size();
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(fail(format!(
                "bufferView {} has byteStride {stride}, below the element size {elem}",
                view.index()
            )));
        }
        let buffer_len = self.buffers[view.buffer().index()].len();
        if view.offset() + view.length() > buffer_len {
            return Err(fail(format!(
                "bufferView {} (bytes {}..{}) runs past the end of buffer {} ({buffer_len} bytes)",
                view.index(),
                view.offset(),
                view.offset() + view.length(),
                view.buffer().index()
            )));
        }
        let end = a.offset() + stride * (a.count() - 1) + elem;
        if end > view.length() {
            return Err(fail(format!(
                "{} elements from byte {} need {end} bytes, bufferView {} has {}",
                a.count(),
                a.offset(),
                view.index(),
                view.length()
            )));
        }
        Ok(())
    }

    /// A vertex attribute besides POSITION: a sound accessor of `n` elements.
    fn check_attribute(
        &self,
        a: &::gltf::Accessor,
        at: &str,
        dims: Dimensions,
        types: &[DataType],
        n: usize,
    ) -> Result<(), GltfError> {
        self.check_accessor(a, at, dims, types)?;
        if a.count() != n {
            return Err((self.fail)(
                at,
                format!("has {} elements, POSITION has {n}", a.count()),
            ));
        }
        Ok(())
    }

    /// Appends one primitive, transformed by `world`, to the asset's mesh.
    fn primitive(
        &mut self,
        mesh: &::gltf::Mesh,
        prim: &::gltf::Primitive,
        world: Mat4,
    ) -> Result<(), GltfError> {
        let base_at = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        let at = |s: &str| format!("{base_at}{s}");
        if prim.mode() != Mode::Triangles {
            return Err((self.fail)(
                &at(".mode"),
                format!(
                    "mode {} ({:?}) is not supported: only TRIANGLES (4)",
                    prim.mode().as_gl_enum(),
                    prim.mode()
                ),
            ));
        }
        let Some(material) = self.material(&prim.material())? else {
            return Ok(()); // cut out entirely by alphaMode MASK
        };
        let pos_at = at(".attributes.POSITION");
        let pos = prim
            .get(&Semantic::Positions)
            .ok_or_else(|| (self.fail)(&pos_at, "missing".into()))?;
        self.check_accessor(&pos, &pos_at, Dimensions::Vec3, &[DataType::F32])?;
        let buffers = self.buffers;
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| (self.fail)(&pos_at, "cannot be read".into()))?
            .map(Vec3::from)
            .collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err((self.fail)(
                &pos_at,
                format!("vertex {i} is not finite ({})", positions[i]),
            ));
        }
        let n = positions.len();
        let normals: Option<Vec<Vec3>> = match prim.get(&Semantic::Normals) {
            Some(acc) => {
                let nat = at(".attributes.NORMAL");
                self.check_attribute(&acc, &nat, Dimensions::Vec3, &[DataType::F32], n)?;
                let read = reader
                    .read_normals()
                    .ok_or_else(|| (self.fail)(&nat, "cannot be read".into()))?;
                Some(
                    read.map(|v| {
                        let v = Vec3::from(v);
                        if v.is_finite() {
                            v.normalize_or_zero()
                        } else {
                            Vec3::ZERO
                        }
                    })
                    .collect(),
                )
            }
            None => None,
        };
        let uvs: Option<Vec<Vec2>> = match prim.get(&Semantic::TexCoords(0)) {
            Some(acc) => {
                let tat = at(".attributes.TEXCOORD_0");
                let types = [DataType::F32, DataType::U8, DataType::U16];
                self.check_attribute(&acc, &tat, Dimensions::Vec2, &types, n)?;
                let read = reader
                    .read_tex_coords(0)
                    .ok_or_else(|| (self.fail)(&tat, "cannot be read".into()))?;
                Some(read.into_f32().map(Vec2::from).collect())
            }
            None => None,
        };
        let indices: Vec<u32> = match prim.indices() {
            Some(acc) => {
                let iat = at(".indices");
                self.check_accessor(
                    &acc,
                    &iat,
                    Dimensions::Scalar,
                    &[DataType::U8, DataType::U16, DataType::U32],
                )?;
                let idx: Vec<u32> = reader
                    .read_indices()
                    .ok_or_else(|| (self.fail)(&iat, "cannot be read".into()))?
                    .into_u32()
                    .collect();
                if let Some(k) = idx.iter().position(|&i| i as usize >= n) {
                    return Err((self.fail)(
                        &iat,
                        format!(
                            "index {} (element {k}) is out of range: POSITION has {n} vertices",
                            idx[k]
                        ),
                    ));
                }
                if idx.len() % 3 != 0 {
                    return Err((self.fail)(
                        &iat,
                        format!("count {} is not a multiple of 3 (TRIANGLES)", idx.len()),
                    ));
                }
                idx
            }
            None => {
                if n % 3 != 0 {
                    return Err((self.fail)(
                        &pos_at,
                        format!("count {n} is not a multiple of 3 (TRIANGLES without indices)"),
                    ));
                }
                (0..n as u32).collect()
            }
        };

        // Node transform: positions by `world`, normals by its inverse
        // transpose; a mirroring transform reverses the winding (glTF 2.0
        // §3.7.4: the determinant's sign flips front faces).
        let normal_m = Mat3::from_mat4(world).inverse().transpose();
        let flip = world.determinant() < 0.0;
        let out = &mut self.asset.mesh;
        let base = out.positions.len() as u32;
        out.positions
            .extend(positions.iter().map(|&p| world.transform_point3(p)));
        match &normals {
            Some(ns) => out
                .normals
                .extend(ns.iter().map(|&v| (normal_m * v).normalize_or_zero())),
            None => out.normals.extend(std::iter::repeat_n(Vec3::ZERO, n)),
        }
        match uvs {
            Some(uv) => out.uvs.extend(uv),
            None => out.uvs.extend(std::iter::repeat_n(Vec2::ZERO, n)),
        }
        let first = out.indices.len();
        for t in indices.chunks_exact(3) {
            let t = [base + t[0], base + t[1], base + t[2]];
            out.indices.push(if flip { [t[0], t[2], t[1]] } else { t });
            out.materials.push(material);
        }
        if normals.is_none() {
            self.asset.had_normals = false;
            self.computed.push(first..out.indices.len());
        }
        Ok(())
    }

    /// The asset material of a glTF material (converted on first use), or
    /// `None` when `alphaMode = MASK` cuts the whole surface out.
    fn material(&mut self, m: &::gltf::Material) -> Result<Option<u32>, GltfError> {
        if let Some(&i) = self.material_map.get(&m.index()) {
            return Ok(i);
        }
        let label = match m.name() {
            Some(n) => n.to_owned(),
            None => match m.index() {
                Some(i) => format!("materials[{i}]"),
                None => "default".to_owned(),
            },
        };
        let count = self.material_names.entry(label.clone()).or_insert(0);
        *count += 1;
        let label = match (*count, m.index()) {
            (1, _) => label,
            (_, Some(i)) => format!("{label}#{i}"),
            (_, None) => format!("{label}#default"),
        };
        let name = format!("{}:{label}", self.file_name);
        let (material, cut_out, notes) = convert_material(name.clone(), m);
        let texture = self.texture_ref(m)?;
        if !notes.is_empty() {
            let at = m.index().map_or("the default material".to_owned(), |i| {
                format!("materials[{i}]")
            });
            self.asset.warnings.push(format!(
                "glTF material `{name}` ({at}): {}",
                notes.join("; ")
            ));
        }
        let index = if cut_out {
            None
        } else {
            self.asset.materials.push(material);
            self.asset.base_color_textures.push(texture);
            Some(self.asset.materials.len() as u32 - 1)
        };
        self.material_map.insert(m.index(), index);
        Ok(index)
    }

    /// A material's base colour texture, its image decoded (once per image).
    fn texture_ref(&mut self, m: &::gltf::Material) -> Result<Option<TextureRef>, GltfError> {
        let Some(info) = m.pbr_metallic_roughness().base_color_texture() else {
            return Ok(None);
        };
        let texture = info.texture();
        let image = texture.source();
        let (mut offset, mut rotation, mut scale, mut tex_coord) =
            (Vec2::ZERO, 0.0, Vec2::ONE, info.tex_coord());
        if let Some(t) = info.texture_transform() {
            offset = Vec2::from(t.offset());
            rotation = t.rotation();
            scale = Vec2::from(t.scale());
            tex_coord = t.tex_coord().unwrap_or(tex_coord);
        }
        if tex_coord != 0 {
            let at = m.index().map_or("the default material".to_owned(), |i| {
                format!("materials[{i}]")
            });
            self.asset.warnings.push(format!(
                "{}: {at}: the base colour texture reads TEXCOORD_{tex_coord}: TEXCOORD_0 is used (the only set read)",
                self.gltf_path.display()
            ));
        }
        let pixels = match self.images.get(&image.index()) {
            Some(p) => p.clone(),
            None => {
                let p = self.decode_image(&image)?;
                self.images.insert(image.index(), p.clone());
                p
            }
        };
        Ok(Some(TextureRef {
            texture: texture.index(),
            image: image.index(),
            pixels,
            tex_coord,
            offset,
            rotation,
            scale,
        }))
    }

    /// An image's texels: from its buffer view, its `data:` URI or its file
    /// (docs/SCENES.md lists the formats). Errors name `images[i].uri` or
    /// `images[i].bufferView`.
    fn decode_image(&self, image: &::gltf::Image) -> Result<Texture, GltfError> {
        let i = image.index();
        let embedded = PathBuf::from(format!("{}#images[{i}]", self.gltf_path.display()));
        match image.source() {
            ::gltf::image::Source::View { view, .. } => {
                let at = format!("images[{i}].bufferView");
                let buffer = &self.buffers[view.buffer().index()];
                let bytes = buffer
                    .get(view.offset()..view.offset() + view.length())
                    .ok_or_else(|| {
                        (self.fail)(
                            &at,
                            format!(
                                "bufferView {} (bytes {}..{}) runs past the end of buffer {} ({} bytes)",
                                view.index(),
                                view.offset(),
                                view.offset() + view.length(),
                                view.buffer().index(),
                                buffer.len()
                            ),
                        )
                    })?;
                texture::decode(bytes, &embedded).map_err(|e| (self.fail)(&at, e))
            }
            ::gltf::image::Source::Uri { uri, .. } => {
                let at = format!("images[{i}].uri");
                if uri.starts_with("data:") {
                    let bytes = read_uri(uri, self.dir).map_err(|e| (self.fail)(&at, e))?;
                    return texture::decode(&bytes, &embedded).map_err(|e| (self.fail)(&at, e));
                }
                let file = uri_file(uri, self.dir).ok_or_else(|| {
                    (self.fail)(&at, format!("unsupported URI scheme in `{uri}`"))
                })?;
                texture::load(&file).map_err(|e| (self.fail)(&at, e))
            }
        }
    }

    /// A glTF camera on a node: it looks down the node's -z with +y up.
    fn camera(&mut self, cam: &::gltf::Camera, world: Mat4) {
        let fov_y_deg = match cam.projection() {
            ::gltf::camera::Projection::Perspective(p) => p.yfov().to_degrees(),
            ::gltf::camera::Projection::Orthographic(_) => {
                self.asset.warnings.push(format!(
                    "cameras[{}] is orthographic: not supported, a framing camera is used",
                    cam.index()
                ));
                return;
            }
        };
        let eye = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        if forward == Vec3::ZERO
            || forward.cross(up).length() < 1e-4
            || !(fov_y_deg > 0.0 && fov_y_deg < 180.0)
        {
            self.asset.warnings.push(format!(
                "cameras[{}]: degenerate view or field of view {fov_y_deg}°: a framing camera is used",
                cam.index()
            ));
            return;
        }
        self.asset.camera = Some(Camera {
            eye,
            target: eye + forward,
            up,
            fov_y_deg,
        });
    }

    /// A `KHR_lights_punctual` light on a node, in project units
    /// ([`LUMENS_PER_WATT`]): it shines down the node's -z.
    fn light(&mut self, l: &::gltf::khr_lights_punctual::Light, world: Mat4) {
        use ::gltf::khr_lights_punctual::Kind;
        let power =
            Vec3::from(l.color()).max(Vec3::ZERO) * l.intensity().max(0.0) / LUMENS_PER_WATT;
        let direction = world
            .transform_vector3(Vec3::NEG_Z)
            .try_normalize()
            .unwrap_or(Vec3::NEG_Y);
        let mut light = Light {
            kind: LightKind::Point,
            position: world.transform_point3(Vec3::ZERO),
            direction,
            intensity: power,
            cone_angle_deg: 0.0,
            cone_falloff_deg: 0.0,
        };
        match l.kind() {
            Kind::Directional => light.kind = LightKind::Directional,
            Kind::Point => {}
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                let outer = outer_cone_angle.to_degrees().clamp(1e-3, 90.0);
                let inner = inner_cone_angle.to_degrees().clamp(0.0, outer);
                light.kind = LightKind::Spot;
                light.cone_angle_deg = outer;
                light.cone_falloff_deg = outer - inner;
            }
        }
        self.asset.lights.push(light);
    }
}

/// glTF material -> project material (docs/SCENES.md, "glTF materials"):
/// the material, whether `alphaMode = MASK` cuts it out entirely, and the
/// ways it differs from the file (one warning line per material).
fn convert_material(name: String, m: &::gltf::Material) -> (Material, bool, Vec<String>) {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, alpha] = pbr.base_color_factor();
    let base = Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE);
    let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
    let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
    let mut notes = Vec::new();
    let mut cut_out = false;
    match m.alpha_mode() {
        ::gltf::material::AlphaMode::Opaque => {}
        ::gltf::material::AlphaMode::Mask => {
            let cutoff = m.alpha_cutoff().unwrap_or(0.5);
            if pbr.base_color_texture().is_some() {
                notes.push("alphaMode MASK with a baseColorTexture: the cut-out is not applied (rendered opaque)".to_owned());
            } else if alpha < cutoff {
                // Without a texture alpha is one constant: the whole surface
                // is either kept or cut out.
                cut_out = true;
                notes.push(format!(
                    "alphaMode MASK with alpha {alpha} below alphaCutoff {cutoff}: its triangles are cut out"
                ));
            }
        }
        ::gltf::material::AlphaMode::Blend => {
            notes.push("alphaMode BLEND is not supported: rendered opaque".to_owned())
        }
    }
    let emission = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
    if emission.max_element() > 0.0 {
        notes.push(format!(
            "emissive {emission} is not rendered (no area emitters yet)"
        ));
    }
    let mut out = Material {
        texture: None,
        name,
        kind: MaterialKind::Diffuse,
        color: base,
        ior: 1.0,
        absorption: Vec3::ZERO,
    };
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    if transmission > 0.0 {
        out.kind = MaterialKind::Dielectric;
        out.color = Vec3::ONE;
        if transmission < 1.0 {
            notes.push(format!(
                "transmission {transmission} rendered as 1 (a clear dielectric)"
            ));
        }
        if roughness > SMOOTH_ROUGHNESS {
            notes.push(format!(
                "rough transmission (roughness {roughness}) rendered smooth"
            ));
        }
        if base != Vec3::ONE {
            notes.push(format!(
                "the base colour {base} tinting the transmission is not applied"
            ));
        }
        match m.volume().filter(|v| v.thickness_factor() > 0.0) {
            Some(v) => {
                let ior = m.ior().unwrap_or(1.5);
                out.ior = if ior >= 1.0 {
                    ior
                } else {
                    notes.push(format!("ior {ior} below 1 rendered as 1.5"));
                    1.5
                };
                // KHR_materials_volume: transmittance over attenuationDistance
                // d is attenuationColor c, so Beer-Lambert σa = -ln(c)/d
                // (an infinite distance, the default, absorbs nothing).
                let d = v.attenuation_distance();
                if d.is_finite() && d > 0.0 {
                    let c = Vec3::from(v.attenuation_color()).clamp(Vec3::splat(1e-6), Vec3::ONE);
                    out.absorption = Vec3::new(-c.x.ln(), -c.y.ln(), -c.z.ln()) / d;
                }
            }
            None => {
                // Thin-walled (the glTF default without a volume): a sheet
                // with Fresnel at both faces and no net deflection. The
                // nearest supported material keeps its geometry optics: a
                // dielectric of ior 1 lets light through undeflected (it
                // drops the sheet's ~8% Fresnel reflection).
                out.ior = 1.0;
                notes.push("thin-walled transmission (no KHR_materials_volume) rendered as a dielectric of ior 1: undeflected, without the sheet's Fresnel reflection".to_owned());
            }
        }
    } else if metallic >= 0.5 {
        if metallic < 1.0 {
            notes.push(format!("metallic {metallic} rendered as a metal"));
        }
        if roughness <= ROUGH_METAL_LIMIT {
            out.kind = MaterialKind::Mirror;
            if roughness > SMOOTH_ROUGHNESS {
                notes.push(format!(
                    "rough metal (roughness {roughness}) rendered as a smooth mirror"
                ));
            }
        } else {
            notes.push(format!(
                "rough metal (roughness {roughness}) rendered diffuse with albedo = base colour"
            ));
        }
    } else if metallic > 0.0 {
        notes.push(format!(
            "metallic {metallic} rendered as a non-metal (diffuse)"
        ));
    }
    (out, cut_out, notes)
}

/// How a glTF file becomes a whole scene (`caustics render --scene model.glb`).
#[derive(Clone, Copy, Debug)]
pub struct GltfSceneOptions {
    /// Add a diffuse floor (albedo [`FLOOR_ALBEDO`]) under the model.
    pub floor: bool,
}

impl Default for GltfSceneOptions {
    fn default() -> Self {
        GltfSceneOptions { floor: true }
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
    let mut asset = load(path)?;
    if asset.lights.len() > MAX_LIGHTS as usize {
        return Err(GltfError {
            file: path.to_path_buf(),
            at: "extensions.KHR_lights_punctual".into(),
            message: format!(
                "the scene uses {} lights, at most {MAX_LIGHTS} are supported",
                asset.lights.len()
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
    for (m, t) in materials.iter_mut().zip(asset.base_color_textures) {
        let Some(t) = t else { continue };
        let index = match textures.iter().position(|x| x.path == t.pixels.path) {
            Some(i) => i,
            None => {
                textures.push(t.pixels);
                textures.len() - 1
            }
        };
        m.texture = Some(AlbedoTexture {
            index: index as u32,
            uv_scale: Vec2::ONE,
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
            name: "floor".into(),
            kind: MaterialKind::Diffuse,
            color: Vec3::splat(FLOOR_ALBEDO),
            ior: 1.0,
            absorption: Vec3::ZERO,
        });
        // Just below the model so a model standing on y = min does not
        // share its plane with the floor.
        let y = lo.y - 1e-3 * radius;
        let mut mesh = super::shapes::plane(
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
        let fov_y_deg = super::DEFAULT_FOV_Y_DEG;
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
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_with_and_without_padding() {
        assert_eq!(base64_decode("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64_decode("aGVsbG8").unwrap(), b"hello");
        assert_eq!(base64_decode("AAECAw==").unwrap(), [0, 1, 2, 3]);
        assert!(base64_decode("a*b").is_none());
    }

    #[test]
    fn percent_decoding_of_uris() {
        assert_eq!(percent_decode("my%20model.bin"), "my model.bin");
        assert_eq!(percent_decode("100%"), "100%");
    }
}
