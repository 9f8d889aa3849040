//! The integration tests, one binary (one link of the crate instead of one
//! per file). Each module is a test group, named as its file; run one group
//! with `cargo test --test suite -- GROUP::` (e.g. `reference::`), one test
//! with its full path. Every test that renders opens its own validated context
//! (`common::validated_context`), so groups share nothing but the process
//! and the reference cache (`common::reference_cache`).
//!
//! The loaders' scaling tests are a binary of their own,
//! tests/scene_scaling.rs: they time the loaders, which the suite's other
//! tests, running beside them, would disturb.

mod common;

mod accumulation;
mod airlight;
mod beams;
mod bvh_gpu;
mod cli;
mod cli_errors;
mod compare;
mod demo;
mod denoise;
mod direct;
mod direct_lights;
mod direct_vs_reference;
mod environment_rotation;
mod frames_in_flight;
mod fuzz;
mod gltf;
mod image_space;
mod image_space_refraction;
mod interrupt;
mod lights_scene;
mod live_params;
mod medium_attenuation;
mod mixed_material;
mod moving_lights;
mod multiple_scattering;
mod overlay_layout;
mod pinhole;
mod pipeline_reuse;
mod reference;
mod reference_lights;
mod reference_ppm;
mod resize_storm;
mod scene_loading;
mod scene_values;
mod sync_validation;
mod textures;
mod views;
mod volume_lines;
mod water_medium;
mod water_photons;
mod water_surface;
