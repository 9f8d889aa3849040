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
