//! Scenes: TOML files (docs/SCENES.md) parsed, validated and resolved into
//! the model of `types.rs`, with procedural shapes and OBJ meshes triangulated.

mod types;
pub use types::*;

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

// TEMPORARY until the loader lands.
impl Scene {
    pub fn triangles(&self, _time: f32) -> Vec<Triangle> {
        let mut out = Vec::new();
        for (oi, o) in self.objects.iter().enumerate() {
            let nm = o.transform.inverse().transpose();
            for (ti, idx) in o.mesh.indices.iter().enumerate() {
                out.push(Triangle {
                    positions: idx
                        .map(|i| o.transform.transform_point3(o.mesh.positions[i as usize])),
                    normals: idx
                        .map(|i| nm.transform_vector3(o.mesh.normals[i as usize]).normalize()),
                    material: o.mesh.materials[ti],
                    object: oi as u32,
                });
            }
        }
        out
    }
    pub fn is_animated(&self) -> bool {
        false
    }
    pub fn bounding_sphere(&self, time: f32) -> (glam::Vec3, f32) {
        let t = self.triangles(time);
        let mut lo = glam::Vec3::splat(f32::MAX);
        let mut hi = glam::Vec3::splat(f32::MIN);
        for tri in &t {
            for p in tri.positions {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
    }
}
pub const DEFAULT_SCENE: &str = "assets/scenes/ball_lens.toml";
impl Scene {
    pub fn load(path: &std::path::Path) -> anyhow::Result<Scene> { anyhow::bail!("TEMPORARY: loader not merged yet ({})", path.display()) }
}
