//! `pinhole`: binding numbers and constants shared with its shaders
//! (`build.rs` writes each `pub const NAME: u32` as `#define NAME value` into
//! `pinhole_bindings.glsl`). Plain `pub const X: u32 = N;` lines only.

// Descriptor set 1 of every pinhole pass but the mips (src/techniques/pinhole/, glsl/pinhole/).
pub const PINHOLE_BINDING_SAMPLES: u32 = 0;
pub const PINHOLE_BINDING_STATE: u32 = 1;
pub const PINHOLE_BINDING_CDF: u32 = 2;
pub const PINHOLE_BINDING_CANDIDATES: u32 = 3;
pub const PINHOLE_BINDING_HEADS: u32 = 4;
pub const PINHOLE_BINDING_NEXT: u32 = 5;
pub const PINHOLE_BINDING_LIGHT_MAP_LEVEL0: u32 = 6;
pub const PINHOLE_BINDING_LIGHT_MAP: u32 = 7;
pub const PINHOLE_BINDING_POSITION: u32 = 8;
pub const PINHOLE_BINDING_NORMAL: u32 = 9;
pub const PINHOLE_BINDING_ALBEDO: u32 = 10;
pub const PINHOLE_BINDING_RADIANCE: u32 = 11;
// Descriptor set 1 of the mip pass (one set per level).
pub const PINHOLE_MIP_BINDING_SRC: u32 = 0;
pub const PINHOLE_MIP_BINDING_DST: u32 = 1;
/// Most sample-point clusters, each with its own light cube maps (Sect. 5).
pub const PINHOLE_MAX_CLUSTERS: u32 = 16;
/// Sampling strategies of Sect. 3.2.
pub const PINHOLE_STRATEGY_RANDOM: u32 = 0;
pub const PINHOLE_STRATEGY_GRID: u32 = 1;
pub const PINHOLE_STRATEGY_QUANTIZED_GRID: u32 = 2;
pub const PINHOLE_STRATEGY_NEIGHBOURHOOD: u32 = 3;
/// Bits of the push constants' `flags`.
pub const PINHOLE_FLAG_FILTER: u32 = 1;
pub const PINHOLE_FLAG_VISIBILITY: u32 = 2;
pub const PINHOLE_FLAG_LIGHT_VISIBILITY: u32 = 4;
pub const PINHOLE_FLAG_DIELECTRICS: u32 = 8;
/// Threads of the single-workgroup passes (scan, stratification, clusters).
pub const PINHOLE_GROUP: u32 = 256;
/// Candidates one dispatch of the selection (select.comp) visits.
pub const PINHOLE_SELECT_CHUNK: u32 = 4096;
/// Most emitter slots (light-visibility mask bits per sample point).
pub const PINHOLE_MAX_SLOTS: u32 = 32;
