//! caustics: real-time caustics techniques on raw Vulkan, side by side against
//! a GPU ground-truth light tracer. See docs/ARCHITECTURE.md for the map.

pub mod app;
pub mod bvh;
pub mod cache_dir;
pub mod compare;
pub mod emitters;
pub mod frame;
pub mod gpu;
pub mod output;
pub mod params;
pub mod passes;
pub mod radiometry;
pub mod reference;
pub mod renderer;
pub mod scene;
pub mod shader_bindings;
pub mod shaders;
pub mod techniques;
pub mod vk;
