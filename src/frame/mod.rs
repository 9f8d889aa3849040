//! What every pass of a frame reads and writes besides its own resources:
//! the scene on the GPU (descriptor set 0) and the frame's targets.
//!
//! Layer rule: `frame` sits below `passes`; it imports `vk`, `scene`, `bvh`,
//! `gpu`, `radiometry`, `emitters` and `shader_bindings`, never `passes`, `techniques`,
//! `renderer` or `reference` (docs/ARCHITECTURE.md, "Layers").

mod environment;
mod scene_gpu;
mod stand_ins;
mod targets;
mod textures;

pub use environment::EnvironmentGpu;
pub use scene_gpu::{camera_matrices, GeometryStats, SceneGpu};
pub use stand_ins::{caustic_lights, check_stand_ins, LAMBERTIAN_FALLOFF, STAND_IN_MAX_SIZE_RATIO};
pub use targets::FrameTargets;
pub use textures::AlbedoTextures;
