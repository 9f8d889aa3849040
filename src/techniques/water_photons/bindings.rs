//! `water_photons`: binding numbers and constants shared with its shaders:
//! `build.rs` writes every `pub const NAME: u32` here as `#define NAME
//! value` into `water_photons_bindings.glsl` (which includes the shared
//! `bindings.glsl`). Plain `pub const X: u32 = N;` lines only.

// water_photons caustics denoiser (src/techniques/water_photons/denoise.rs,
// glsl/water_photons/denoise.comp), descriptor set 0.
pub const DENOISE_BINDING_INPUT: u32 = 0;
pub const DENOISE_BINDING_OUTPUT: u32 = 1;
pub const DENOISE_BINDING_POSITION: u32 = 2;
/// Kernel radius choice (Kougianos 2021 Sect. 3.3): per pixel by Eqs. 26-28,
/// or one constant radius (the filter of their refs [6, 10]).
pub const DENOISE_KIND_ADAPTIVE: u32 = 1;
pub const DENOISE_KIND_FIXED: u32 = 2;
/// Sub-pass axis: neighbours along x (the paper's "column-wise" sub-pass,
/// Algorithm 4 line 18), then along y.
pub const DENOISE_AXIS_X: u32 = 0;
pub const DENOISE_AXIS_Y: u32 = 1;
/// Workgroup side of the denoise sub-passes (8 x 8 pixels).
pub const DENOISE_GROUP_SIZE: u32 = 8;
// water_photons (src/techniques/water_photons/, glsl/water_photons/),
// descriptor set 1 of each pass.
pub const WP_BINDING_PARAMS: u32 = 0;
pub const WP_BINDING_WATER_VERTICES: u32 = 1;
pub const WP_BINDING_CCM_POSITION: u32 = 2;
pub const WP_BINDING_CCM_NORMAL: u32 = 3;
pub const WP_BINDING_PHOTONS: u32 = 4;
pub const WP_BINDING_DRAW: u32 = 5;
pub const WP_BINDING_CAUSTICS: u32 = 6;
pub const WP_BINDING_GBUFFER_POSITION: u32 = 7;
pub const WP_BINDING_GBUFFER_NORMAL: u32 = 8;
pub const WP_BINDING_GBUFFER_ALBEDO: u32 = 15;
pub const WP_BINDING_RADIANCE: u32 = 9;
// water_photons "water view": the photon slot per (texel, cascade, ray
// type) written by the trace, and the camera's view of the water.
pub const WP_BINDING_PHOTON_SLOTS: u32 = 10;
pub const WP_BINDING_OPAQUE_RADIANCE: u32 = 11;
pub const WP_BINDING_FRONT_POSITION: u32 = 12;
pub const WP_BINDING_FRONT_NORMAL: u32 = 13;
pub const WP_BINDING_BACK_POSITION: u32 = 14;
// water_photons "shafts": the light scattered by a medium in the water,
// seen from under the surface (shafts.rs), which the water view adds.
pub const WP_BINDING_SHAFTS: u32 = 16;
/// Most cascades of a cascaded caustic map (Kougianos & Moustakas 2021 use 1-4).
pub const WP_MAX_CASCADES: u32 = 4;
/// Trace threads per workgroup, and workgroups per dispatch row.
pub const WP_TRACE_GROUP_SIZE: u32 = 64;
pub const WP_TRACE_GROUPS_PER_ROW: u32 = 1024;
/// Intensity modes: exact Fresnel, flux per photon (physical); Eqs. 13-14 (paper).
pub const WP_INTENSITY_PHYSICAL: u32 = 0;
pub const WP_INTENSITY_PAPER: u32 = 1;
/// Splat modes: the photon differential's footprint; Eqs. 16-19's quad with
/// σ from the differentials; the same quad with σ = s^c (fixed splats).
pub const WP_SPLAT_DIFFERENTIAL: u32 = 0;
pub const WP_SPLAT_PAPER: u32 = 1;
pub const WP_SPLAT_FIXED: u32 = 2;
/// Specialisation constant ids: the cascade count N (view.comp's loop over
/// the cascades) and the splat mode (kernel.glsl's branch). Both are
/// `rebuild` parameters, so they are constants of the pipeline rather than
/// uniform reads: lavapipe (Mesa 22.3) recompiles a compute shader at every
/// bind while a uniform decides one of its branches or trip counts and keeps
/// every copy (view.rs; BENCHMARKS.md, "Soak").
pub const WP_SPEC_CASCADES: u32 = 0;
pub const WP_SPEC_SPLAT_MODE: u32 = 1;
/// Ray types of a photon (Algorithm 3 line 37).
pub const WP_RAY_REFLECTED: u32 = 0;
pub const WP_RAY_REFRACTED: u32 = 1;
