//! Passes shared by techniques: each owns its pipelines and records itself
//! through `FrameRecorder::pass`.

pub mod airlight;
pub mod caustic_map;
pub mod gbuffer;
pub mod shadow;
pub mod specular_gbuffer;
pub mod tonemap;
pub mod water_surface;
