//! `beams`: binding numbers and constants shared with its shaders:
//! `build.rs` writes every `pub const NAME: u32` here as `#define NAME
//! value` into `beams_bindings.glsl` (which includes the shared
//! `bindings.glsl`). Plain `pub const X: u32 = N;` lines only.

// beams (src/techniques/beams/, glsl/beams/), descriptor set 1.
pub const BEAMS_BINDING_TRIANGLES_A: u32 = 0;
pub const BEAMS_BINDING_TRIANGLES_B: u32 = 1;
pub const BEAMS_BINDING_BEAMS: u32 = 2;
pub const BEAMS_BINDING_COUNTERS: u32 = 3;
pub const BEAMS_BINDING_INDIRECT: u32 = 4;
pub const BEAMS_BINDING_FRONT_POSITION: u32 = 5;
pub const BEAMS_BINDING_FRONT_NORMAL: u32 = 6;
pub const BEAMS_BINDING_BACK_POSITION: u32 = 7;
pub const BEAMS_BINDING_BACK_NORMAL: u32 = 8;
pub const BEAMS_BINDING_OPAQUE_POSITION: u32 = 9;
pub const BEAMS_BINDING_OPAQUE_NORMAL: u32 = 10;
pub const BEAMS_BINDING_OPAQUE_ALBEDO: u32 = 11;
pub const BEAMS_BINDING_SPECULAR_POSITION: u32 = 12;
pub const BEAMS_BINDING_RECEIVERS: u32 = 13;
pub const BEAMS_BINDING_VOLUME: u32 = 14;
pub const BEAMS_BINDING_SURFACE: u32 = 15;
pub const BEAMS_BINDING_OPAQUE_RADIANCE: u32 = 16;
pub const BEAMS_BINDING_RADIANCE: u32 = 17;
pub const BEAMS_BINDING_SURFACE_FILTERED: u32 = 18;

/// Refinement levels at most (Sect. 4.2; the grid coordinates are stored
/// at the finest level's resolution, base x 2^BEAMS_MAX_LEVELS).
pub const BEAMS_MAX_LEVELS: u32 = 5;
/// Threads per workgroup of the refinement passes.
pub const BEAMS_REFINE_GROUP: u32 = 64;

/// Layout of the counters buffer (u32 words): per light, reset when the
/// light starts (`BEAMS_COUNTER_TRIS` + level: triangles in that level's
/// input list; `BEAMS_COUNTER_BEAMS`: beams written), then per frame,
/// summed over the lights (triangles refined and beams emitted per level,
/// overflows, and the solid angle / area of kept and dropped triangles).
pub const BEAMS_COUNTER_TRIS: u32 = 0;
pub const BEAMS_COUNTER_BEAMS: u32 = 6;
pub const BEAMS_COUNTER_LIGHT_WORDS: u32 = 8;
pub const BEAMS_STAT_TRIS: u32 = 8;
pub const BEAMS_STAT_BEAMS: u32 = 14;
pub const BEAMS_STAT_BEAM_OVERFLOW: u32 = 20;
pub const BEAMS_STAT_TRI_OVERFLOW: u32 = 21;
/// f32 words (float atomics): measure (sr or m^2) of the base triangles
/// kept and dropped at silhouettes, flux (W, luminance) entering the kept
/// triangles and carried by the beams.
pub const BEAMS_STAT_KEPT_MEASURE: u32 = 22;
pub const BEAMS_STAT_DROPPED_MEASURE: u32 = 23;
pub const BEAMS_STAT_FLUX_IN: u32 = 24;
pub const BEAMS_STAT_FLUX_OUT: u32 = 25;
/// Fragments the bounding volumes shaded (Fig. 6).
pub const BEAMS_STAT_FRAGMENTS: u32 = 26;
/// Fragments the caustic triangles' rectangles shaded (the surface gather).
pub const BEAMS_STAT_CAUSTIC_FRAGMENTS: u32 = 27;
pub const BEAMS_COUNTER_WORDS: u32 = 28;

/// Layout of the indirect-arguments buffer (u32 words): one
/// `VkDispatchIndirectCommand` per level (3 words each), then the beams'
/// `VkDrawIndirectCommand` (4 words).
pub const BEAMS_INDIRECT_DRAW: u32 = 18;
pub const BEAMS_INDIRECT_WORDS: u32 = 22;

/// Beam kinds (`Beam.v1.w`).
pub const BEAM_REFLECTED: u32 = 0;
pub const BEAM_REFRACTED: u32 = 1;

/// Bounding volumes (Sect. 4.3): Ernst et al.'s prism, or the tight
/// six-side-triangle hull with the prism as its fallback.
pub const BEAMS_VOLUME_PRISM: u32 = 0;
pub const BEAMS_VOLUME_TIGHT: u32 = 1;

/// Two-sided refraction (Sect. 6): Wyman's image-space exit through the
/// light view's back faces (the paper uses a distance impostor), or the
/// exact path through the BVH.
pub const BEAMS_REFRACTION_IMAGE_SPACE: u32 = 0;
pub const BEAMS_REFRACTION_TRACED: u32 = 1;
