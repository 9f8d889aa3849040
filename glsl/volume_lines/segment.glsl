// volume_lines: the volume caustic buffer entry.
#ifndef VOLUME_LINES_SEGMENT_GLSL
#define VOLUME_LINES_SEGMENT_GLSL

#include "volume_lines_bindings.glsl"

// One light ray after the specular object (Sect. 5.1, Fig. 4): from the
// exit point p1 to the surface point p2. Mirrors `GpuSegment` in
// src/techniques/volume_lines/lines.rs.
struct Segment {
    vec4 p1;   // xyz exit point; w: 1 valid, 0 no segment for this texel
    vec4 p2;   // xyz end point (first diffuse surface, or the scene's bounding sphere)
    vec4 flux; // rgb: Phi = I Omega_texel T0 T1 tau_glass tau(s, p0) (W); w: Omega_texel (sr) or A_texel (m^2)
};

#endif
