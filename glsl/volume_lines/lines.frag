#version 460
// volume_lines: the line fragments (lines.glsl) for homogeneous media (or
// none): transmittance and sigma_s without the density field's code,
// which a CPU rasteriser would otherwise pay for in every fragment.
#define MEDIUM_HOMOGENEOUS_ONLY
#include "lines.glsl"
