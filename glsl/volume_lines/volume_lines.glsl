// volume_lines (Hu et al. 2010): the medium helpers shared by the segment
// pass and the line fragments. Requires scene.glsl and medium.glsl.
// VL_HOMOGENEOUS_ONLY (lines.frag) compiles the constant-density case
// alone: the caller guarantees the medium is constant or absent.
#ifndef VOLUME_LINES_GLSL
#define VOLUME_LINES_GLSL

#include "segment.glsl"

// Transmittance of the medium from a to b (Sect. 5.4): exact Beer-Lambert
// for a constant density; otherwise the midpoint rule with `steps` samples
// over the part of the segment inside the medium's bounds (a deliberately
// coarse numerical integral, Fig. 11: the caustic's brightness comes from
// the summed line contributions, not from this integral). Solid objects on
// the way are ignored: callers pass segments in free space.
vec3 vl_transmittance(vec3 a, vec3 b, uint steps) {
    if (!medium_present()) return vec3(1.0);
    vec3 d = b - a;
    float len = length(d);
    if (len <= 0.0) return vec3(1.0);
    d /= len;
    float t0 = 0.0, t1 = len;
    if (!clip_to_medium(a, d, t0, t1)) return vec3(1.0);
    vec3 sigma_t = medium.sigma_s.rgb + medium.sigma_a.rgb;
#ifdef VL_HOMOGENEOUS_ONLY
    return exp(-sigma_t * medium.bounds_min.w * (t1 - t0));
#else
    if (floatBitsToUint(medium.sigma_a.w) == DENSITY_CONSTANT) return exp(-sigma_t * medium.bounds_min.w * (t1 - t0));
    uint n = max(steps, 1u);
    float dt = (t1 - t0) / float(n);
    float optical = 0.0;
    for (uint i = 0u; i < n; ++i) optical += medium_density(a + (t0 + (float(i) + 0.5) * dt) * d);
    return exp(-sigma_t * optical * dt);
#endif
}

// sigma_s at x (1/m): 0 outside the medium's bounds or without a medium.
vec3 vl_sigma_s(vec3 x) {
    if (!medium_present()) return vec3(0.0);
#ifdef VL_HOMOGENEOUS_ONLY
    return inside_medium_bounds(x) ? medium.sigma_s.rgb * medium.bounds_min.w : vec3(0.0);
#else
    return medium.sigma_s.rgb * medium_density(x);
#endif
}

#endif
