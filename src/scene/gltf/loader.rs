//! The loader proper: every accessor checked, then meshes (node transforms
//! applied), materials, images, camera and lights into a `GltfAsset`.

use super::*;

pub(super) struct Loader<'a> {
    pub(super) fail: Fail<'a>,
    pub(super) buffers: &'a [Cow<'a, [u8]>],
    pub(super) file_name: String,
    pub(super) within: Confinement<'a>,
    pub(super) asset: GltfAsset,
    /// glTF material index (None: the default material) -> asset material.
    pub(super) material_map: HashMap<Option<usize>, Option<u32>>,
    /// Names given so far -> count, to keep names unique within the file.
    pub(super) material_names: HashMap<String, usize>,
    /// Index ranges whose normals are computed (primitives without NORMAL).
    pub(super) computed: Vec<std::ops::Range<usize>>,
    /// Images decoded so far, by index into the file's `images`.
    pub(super) images: HashMap<usize, Texture>,
    pub(super) gltf_path: &'a Path,
}

impl Loader<'_> {
    /// Checks an accessor before it is read: element type, a buffer view,
    /// no sparse storage, a stride that fits the element, and all of its
    /// elements inside the view and the view inside the buffer.
    pub(super) fn check_accessor(
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
        // Sizes from the file are checked as they multiply: a count of
        // 2^62 must not wrap to a small size that fits the view.
        let buffer_len = self.buffers[view.buffer().index()].len();
        let view_end = view.offset().checked_add(view.length());
        if view_end.is_none_or(|end| end > buffer_len) {
            return Err(fail(format!(
                "bufferView {} ({} bytes from byte {}) runs past the end of buffer {} ({buffer_len} bytes)",
                view.index(),
                view.length(),
                view.offset(),
                view.buffer().index()
            )));
        }
        let end = stride
            .checked_mul(a.count() - 1)
            .and_then(|b| b.checked_add(a.offset()))
            .and_then(|b| b.checked_add(elem));
        if end.is_none_or(|end| end > view.length()) {
            return Err(fail(format!(
                "{} elements of {elem} bytes, {stride} apart, from byte {} do not fit bufferView {} ({} bytes)",
                a.count(),
                a.offset(),
                view.index(),
                view.length()
            )));
        }
        Ok(())
    }

    /// A vertex attribute besides POSITION: a sound accessor of `n` elements.
    pub(super) fn check_attribute(
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
    pub(super) fn primitive(
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
    pub(super) fn material(&mut self, m: &::gltf::Material) -> Result<Option<u32>, GltfError> {
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
        // KHR_materials_volume: a distance of 0 or less is outside the
        // extension's schema (exclusive minimum 0), not "opaque".
        if let (Some(v), Some(i)) = (m.volume(), m.index()) {
            let d = v.attenuation_distance();
            if d.is_nan() || d <= 0.0 {
                return Err((self.fail)(
                    &format!("materials[{i}].extensions.KHR_materials_volume.attenuationDistance"),
                    format!("is {d}: must be above 0"),
                ));
            }
        }
        let (material, coverage, notes) = convert_material(name.clone(), m);
        let mut texture = self.texture_ref(m)?;
        if let (Some(t), Coverage::Mask(threshold)) = (texture.as_mut(), coverage) {
            t.alpha_cutoff = threshold;
        }
        if !notes.is_empty() {
            let at = m.index().map_or("the default material".to_owned(), |i| {
                format!("materials[{i}]")
            });
            self.asset.warnings.push(format!(
                "glTF material `{name}` ({at}): {}",
                notes.join("; ")
            ));
        }
        let index = if coverage == Coverage::CutOut {
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
    pub(super) fn texture_ref(
        &mut self,
        m: &::gltf::Material,
    ) -> Result<Option<TextureRef>, GltfError> {
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
        let sampler = texture.sampler();
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
            alpha_cutoff: 0.0,
            wrap: [sampler.wrap_s(), sampler.wrap_t()].map(|w| match w {
                WrappingMode::Repeat => Wrap::Repeat,
                WrappingMode::ClampToEdge => Wrap::ClampToEdge,
                WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
            }),
        }))
    }

    /// An image's texels: from its buffer view, its `data:` URI or its file
    /// (docs/SCENES.md lists the formats). Errors name `images[i].uri` or
    /// `images[i].bufferView`.
    pub(super) fn decode_image(&self, image: &::gltf::Image) -> Result<Texture, GltfError> {
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
                    let bytes = read_uri(uri, &self.within).map_err(|e| (self.fail)(&at, e))?;
                    return texture::decode(&bytes, &embedded).map_err(|e| (self.fail)(&at, e));
                }
                let file = uri_file(uri, &self.within).map_err(|e| (self.fail)(&at, e))?;
                texture::load(&file).map_err(|e| (self.fail)(&at, e))
            }
        }
    }

    /// A glTF camera on a node: it looks down the node's -z with +y up.
    pub(super) fn camera(&mut self, cam: &::gltf::Camera, world: Mat4) {
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
    /// Negative values, which the extension's schema forbids, are refused.
    pub(super) fn light(
        &mut self,
        l: &::gltf::khr_lights_punctual::Light,
        world: Mat4,
    ) -> Result<(), GltfError> {
        use ::gltf::khr_lights_punctual::Kind;
        let at = format!("extensions.KHR_lights_punctual.lights[{}]", l.index());
        let color = Vec3::from(l.color());
        if !(l.intensity() >= 0.0 && color.min_element() >= 0.0) {
            return Err((self.fail)(
                &at,
                format!(
                    "intensity {} and color {color}: both must be 0 or more",
                    l.intensity()
                ),
            ));
        }
        let power = color * l.intensity() / LUMENS_PER_WATT;
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
        Ok(())
    }
}
