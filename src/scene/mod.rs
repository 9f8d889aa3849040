//! Scenes: TOML files (docs/SCENES.md) parsed, validated and resolved into
//! the model of `types.rs`, with procedural shapes and OBJ meshes triangulated.
//!
//! - `file.rs`: the schema and its validation (every error located `FILE:LINE:COL: FIELD`).
//! - `node.rs`: the span-carrying TOML tree the schema reads from.
//! - `shapes.rs`: procedural tessellation; `obj.rs`: OBJ/MTL through tobj;
//!   `gltf/`: glTF 2.0 files (objects, or a whole scene of one file).
//! - `water.rs`: water surfaces (Gerstner waves), re-tessellated per time.
//! - `paths.rs`: where the files a scene names may be (its folder's tree,
//!   `--allow-paths`); `input.rs`: how they are read (regular files, size limits).
//! - this file: loading, animation and world-space queries.

mod bounds;
mod error;
mod file;
pub mod gltf;
pub mod input;
mod node;
pub mod obj;
pub mod paths;
pub mod shapes;
pub mod texture;
mod types;
pub mod water;

pub use bounds::{MAX_EMISSIVE_TRIANGLES, MAX_LIGHTS, MAX_WORLD_EXTENT};
pub use error::{escape_control, SceneError};
pub use file::DEFAULT_FOV_Y_DEG;
pub use node::{MAX_MAGNITUDE, MAX_RADIOMETRIC};
pub use paths::AllowedPaths;
pub use types::*;

use glam::{Mat3, Mat4, Quat, Vec3};
use std::borrow::Cow;
use std::path::Path;

/// The scene the CLI and demo open when none is given: a showcase of
/// surface caustics (tinted glass on coloured surfaces under a spot light).
/// The physics scenes (ball_lens, ring, ...) are named by the tests that
/// use them.
pub const DEFAULT_SCENE: &str = "assets/scenes/still_life.toml";

/// Where [`DEFAULT_SCENE`] is: under the working directory (a checkout),
/// else under a folder above the executable (`target/release/caustics` of
/// a checkout run from elsewhere), else under the checkout the binary was
/// built from (`cargo install --path .`); the first when none has it (its
/// error then names the path as given).
pub fn default_scene_path() -> std::path::PathBuf {
    let relative = Path::new(DEFAULT_SCENE);
    let exe = std::env::current_exe().ok();
    let above_exe = exe.iter().flat_map(|e| e.ancestors().skip(1));
    std::iter::once(Path::new(""))
        .chain(above_exe)
        .chain(std::iter::once(Path::new(env!("CARGO_MANIFEST_DIR"))))
        .map(|dir| dir.join(relative))
        .find(|p| p.is_file())
        .unwrap_or_else(|| relative.to_path_buf())
}

impl Scene {
    /// Reads and validates a scene file. Relative paths inside it (OBJ meshes,
    /// density grids) resolve against the file's folder, and every file it
    /// names must lie in that folder's tree ([`paths`]). A `.gltf` or `.glb`
    /// file is a whole scene of its own ([`gltf::scene`] with the default
    /// options: a floor, the file's camera and lights or defaults).
    /// The default scene ([`DEFAULT_SCENE`]) is found from any working
    /// directory ([`default_scene_path`]).
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Self::load_allowing(path, &AllowedPaths::default())
    }

    /// [`Scene::load`], the files the scene names also read from the trees
    /// of the `allowed` folders (`--allow-paths`).
    pub fn load_allowing(path: &Path, allowed: &AllowedPaths) -> Result<Scene, SceneError> {
        let found;
        let path = if path == Path::new(DEFAULT_SCENE) {
            found = default_scene_path();
            found.as_path()
        } else {
            path
        };
        let start = std::time::Instant::now();
        let scene = if gltf::is_gltf_path(path) {
            let options = gltf::GltfSceneOptions {
                allowed: allowed.clone(),
                ..Default::default()
            };
            gltf::scene(path, &options)?
        } else {
            Self::load_toml(path, allowed)?
        };
        // The load phase's cost (RUST_LOG=info): scripts/gltf-bench.sh reads it.
        log::info!(
            "scene {} loaded in {:.1} ms ({} triangles)",
            path.display(),
            start.elapsed().as_secs_f64() * 1e3,
            scene.triangle_count()
        );
        Ok(scene)
    }

    fn load_toml(path: &Path, allowed: &AllowedPaths) -> Result<Scene, SceneError> {
        let text = input::read_text_limited(path, input::MAX_SCENE_BYTES).map_err(|why| {
            SceneError::Read {
                path: path.to_path_buf(),
                source: std::io::Error::other(why),
            }
        })?;
        file::parse(&text, path, allowed)
    }

    /// Parses scene text as if read from `source` (used in messages and to
    /// resolve relative paths, confined to its folder's tree; the file
    /// itself need not exist).
    pub fn from_str(text: &str, source: &Path) -> Result<Scene, SceneError> {
        file::parse(text, source, &AllowedPaths::default())
    }

    /// Index of the material called `name`.
    pub fn material_index(&self, name: &str) -> Option<u32> {
        self.materials
            .iter()
            .position(|m| m.name == name)
            .map(|i| i as u32)
    }

    /// Total triangle count over all objects.
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.indices.len()).sum()
    }

    /// Sets the environment's `rotate` (degrees about +y) as loading the
    /// file with that value would: a sky's sun direction, stored rotated,
    /// turns with it. False (nothing changed) without an environment.
    pub fn set_environment_rotation(&mut self, rotate_deg: f32) -> bool {
        let Some(env) = self.environment.as_mut() else {
            return false;
        };
        if let EnvironmentKind::Sky(sky) = &mut env.kind {
            let turn = Quat::from_rotation_y(rotate_deg.to_radians())
                * Quat::from_rotation_y(-env.rotate_deg.to_radians());
            sky.sun_direction = (turn * sky.sun_direction).normalize();
        }
        env.rotate_deg = rotate_deg;
        true
    }

    /// Whether any object moves with time (an `animate` block that moves,
    /// or water with waves that have height and speed).
    pub fn is_animated(&self) -> bool {
        self.objects.iter().any(|o| {
            o.animation.is_some_and(|a| a.is_moving())
                || o.water.as_ref().is_some_and(Water::is_moving)
        })
    }

    /// Local -> world transform of object `index` at `time` seconds:
    ///
    /// `T(offset(t)) * T(p) * R_spin(t) * T(-p) * transform`, where `transform` is the
    /// static `T * Rz * Ry * Rx * S` from the file and `p` its translation. So the
    /// object is scaled, rotated, spun about `spin_axis` through its own origin,
    /// translated, and then moved by the animation offset (orbit + bob, see
    /// [`Animation::offset`]). Without an `animate` table this is `transform`.
    ///
    /// Panics if `index` is not an object index.
    pub fn object_transform(&self, index: usize, time: f32) -> Mat4 {
        let o = &self.objects[index];
        match &o.animation {
            None => o.transform,
            Some(a) => {
                let p = o.transform.w_axis.truncate();
                Mat4::from_translation(a.offset(time) + p)
                    * Mat4::from_quat(a.spin(time))
                    * Mat4::from_translation(-p)
                    * o.transform
            }
        }
    }

    /// Area light `index` at `time` seconds: a sphere light with an
    /// `animate` table is where its object's transform puts its centre
    /// (the sphere's mesh is built about its object's origin); the rest do
    /// not move.
    ///
    /// Panics if `index` is not an area-light index.
    pub fn emitter_at(&self, index: usize, time: f32) -> Emitter {
        let mut e = self.emitters[index];
        if let EmitterShape::Sphere { center, .. } = &mut e.shape {
            if self.objects[e.object as usize].animation.is_some() {
                *center = self
                    .object_transform(e.object as usize, time)
                    .transform_point3(Vec3::ZERO);
            }
        }
        e
    }

    /// All triangles in world space at `time`: positions by the object
    /// transform, normals by its inverse transpose (normalised). Winding is
    /// kept counter-clockwise about the normal when a transform mirrors.
    pub fn triangles(&self, time: f32) -> Vec<Triangle> {
        let mut out = Vec::with_capacity(self.triangle_count());
        for (oi, o) in self.objects.iter().enumerate() {
            let m = self.object_transform(oi, time);
            let n = Mat3::from_mat4(m).inverse().transpose();
            let flip = m.determinant() < 0.0;
            let mesh = o.mesh_at(time);
            let positions: Vec<Vec3> = mesh
                .positions
                .iter()
                .map(|&p| m.transform_point3(p))
                .collect();
            let normals: Vec<Vec3> = mesh
                .normals
                .iter()
                .map(|&v| (n * v).normalize_or_zero())
                .collect();
            for (t, &material) in mesh.indices.iter().zip(&mesh.materials) {
                let mut t = if flip { [t[0], t[2], t[1]] } else { *t };
                // Renderers tell inside from outside by the winding (the
                // geometric normal); where a file's normals disagree with its
                // winding, the normals win.
                let [a, b, c] = t.map(|i| positions[i as usize]);
                let shading = t.iter().map(|&i| normals[i as usize]).sum::<Vec3>();
                if (b - a).cross(c - a).dot(shading) < 0.0 {
                    t.swap(1, 2);
                }
                out.push(Triangle {
                    positions: t.map(|i| positions[i as usize]),
                    normals: t.map(|i| normals[i as usize]),
                    uvs: t.map(|i| mesh.uvs.get(i as usize).copied().unwrap_or_default()),
                    material,
                    object: oi as u32,
                });
            }
        }
        out
    }

    /// Axis-aligned bounds `(min, max)` of every triangle at `time`
    /// (both zero for a scene without geometry).
    pub fn bounds(&self, time: f32) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for (oi, o) in self.objects.iter().enumerate() {
            let m = self.object_transform(oi, time);
            for &p in &o.mesh_at(time).positions {
                let w = m.transform_point3(p);
                lo = lo.min(w);
                hi = hi.max(w);
            }
        }
        if lo.x > hi.x {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (lo, hi)
        }
    }

    /// Sphere around [`Scene::bounds`] and the medium's box: its centre, radius
    /// half the diagonal. Directional lights emit from a disk of this radius,
    /// so it must hold everything light can interact with.
    pub fn bounding_sphere(&self, time: f32) -> (Vec3, f32) {
        let (mut lo, mut hi) = self.bounds(time);
        if let Some(m) = &self.medium {
            if self.objects.is_empty() {
                (lo, hi) = (m.bounds_min, m.bounds_max);
            } else {
                lo = lo.min(m.bounds_min);
                hi = hi.max(m.bounds_max);
            }
        }
        ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
    }
}

impl Object {
    /// The object's local-space mesh at `time`: water re-tessellated with its
    /// waves at that time, anything else its static mesh.
    pub fn mesh_at(&self, time: f32) -> Cow<'_, Mesh> {
        match &self.water {
            Some(w) => Cow::Owned(w.mesh(time)),
            None => Cow::Borrowed(&self.mesh),
        }
    }
}

impl Animation {
    /// Whether this animation changes anything with time.
    pub fn is_moving(&self) -> bool {
        self.spin_deg_per_s != 0.0
            || (self.orbit_deg_per_s != 0.0 && self.orbit_radius != 0.0)
            || (self.bob_amplitude != 0.0 && self.bob_hz != 0.0)
    }

    /// Rotation about `spin_axis` by `spin * time` degrees (right-handed).
    pub fn spin(&self, time: f32) -> Quat {
        Quat::from_axis_angle(self.spin_axis, (self.spin_deg_per_s * time).to_radians())
    }

    /// World-space translation added at `time`:
    /// `orbit_center + orbit_radius * (cos a, 0, -sin a) + (0, bob_amplitude * sin(2 pi bob_hz time), 0)`
    /// with `a = orbit_speed * time` (counter-clockwise seen from +y). The
    /// object's own `translate` is relative to this point.
    pub fn offset(&self, time: f32) -> Vec3 {
        let (s, c) = (self.orbit_deg_per_s * time).to_radians().sin_cos();
        let bob = self.bob_amplitude * (std::f32::consts::TAU * self.bob_hz * time).sin();
        self.orbit_center + self.orbit_radius * Vec3::new(c, 0.0, -s) + Vec3::new(0.0, bob, 0.0)
    }
}

impl Medium {
    /// The largest density anywhere in the medium: the majorant's multiplier for
    /// delta/ratio tracking.
    pub fn max_density(&self) -> f32 {
        match &self.density {
            Density::Constant(d) => *d,
            Density::Noise { scale, .. } => *scale,
            Density::Grid { values, .. } => values.iter().copied().fold(0.0, f32::max),
        }
    }
}
