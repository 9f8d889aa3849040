//! `volume_lines`: binding numbers and constants shared with its shaders:
//! `build.rs` writes every `pub const NAME: u32` here as `#define NAME
//! value` into `volume_lines_bindings.glsl` (which includes the shared
//! `bindings.glsl`). Plain `pub const X: u32 = N;` lines only.

// volume_lines (src/techniques/volume_lines/, glsl/volume_lines/), descriptor set 1.
pub const VOLUME_LINES_BINDING_SEGMENTS: u32 = 0;
pub const VOLUME_LINES_BINDING_FRONT_POSITION: u32 = 1;
pub const VOLUME_LINES_BINDING_FRONT_NORMAL: u32 = 2;
pub const VOLUME_LINES_BINDING_BACK_POSITION: u32 = 3;
pub const VOLUME_LINES_BINDING_BACK_NORMAL: u32 = 4;
pub const VOLUME_LINES_BINDING_VISIBILITY: u32 = 5;
pub const VOLUME_LINES_BINDING_OPAQUE_POSITION: u32 = 6;
pub const VOLUME_LINES_BINDING_SPECULAR_POSITION: u32 = 7;
pub const VOLUME_LINES_BINDING_VOLUME: u32 = 8;
pub const VOLUME_LINES_BINDING_RADIANCE: u32 = 9;
/// How the device rasterises 1-pixel lines (push constant of lines.frag):
/// strict (a 1-px-wide rectangle about the line) or not (a parallelogram
/// one pixel tall along the minor axis, i.e. one fragment per column).
pub const LINE_RASTER_RECTANGULAR: u32 = 0;
pub const LINE_RASTER_PARALLELOGRAM: u32 = 1;
