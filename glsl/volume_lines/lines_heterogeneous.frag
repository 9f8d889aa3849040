#version 460
// volume_lines: the line fragments (lines.glsl) for inhomogeneous media
// (noise or grid density; Sect. 5.4).
#include "lines.glsl"
