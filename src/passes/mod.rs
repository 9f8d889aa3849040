//! Passes shared by techniques: each owns its pipelines and records itself
//! through `FrameRecorder::pass`. Passes know no technique: they import
//! `frame`, `params`, the scene and the backend, and each other.

pub mod accumulate;
pub mod airlight;
pub mod camera_refraction;
pub mod caustic_map;
pub mod direct_light;
pub mod gbuffer;
mod image_compute;
pub mod light_views;
pub mod scattered_lights;
pub mod shadow;
pub mod specular_gbuffer;
pub mod surface_frame;
pub mod tonemap;
pub mod water_surface;
