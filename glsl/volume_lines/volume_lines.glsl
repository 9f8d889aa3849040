// volume_lines (Hu et al. 2010): the medium helpers shared by the segment
// pass and the line fragments. Requires scene.glsl and medium.glsl.
// MEDIUM_HOMOGENEOUS_ONLY (lines.frag; see medium.glsl) compiles the
// constant-density case alone: the caller guarantees the medium is constant
// or absent.
#ifndef VOLUME_LINES_GLSL
#define VOLUME_LINES_GLSL

#include "segment.glsl"

// Transmittance of the medium from a to b (Sect. 5.4): the shared
// medium_transmittance_steps (exact for a constant density, a coarse
// midpoint rule otherwise: Fig. 11, the caustic's brightness comes from the
// summed line contributions, not from this integral). Solid objects on the
// way are ignored: callers pass segments in free space.
vec3 vl_transmittance(vec3 a, vec3 b, uint steps) {
    float len = length(b - a);
    if (len <= 0.0) return vec3(1.0);
    return medium_transmittance_steps(a, (b - a) / len, len, steps);
}

// sigma_s at x (1/m): 0 outside the medium's bounds or without a medium.
vec3 vl_sigma_s(vec3 x) {
    if (!medium_present()) return vec3(0.0);
#ifdef MEDIUM_HOMOGENEOUS_ONLY
    return inside_medium_bounds(x) ? medium.sigma_s.rgb * medium.bounds_min.w : vec3(0.0);
#else
    return medium.sigma_s.rgb * medium_density(x);
#endif
}

#endif
