#version 460
// Ground truth: the end of a pass. Adds this pass's estimate of every
// component into the running sums, clears it for the next pass, and keeps
// per pixel the sum and the sum of squares of the pass estimates' luminance
// (the passes are independent estimates, so their spread is the noise).
#include "common.glsl"

layout(local_size_x = 64) in;

void main() {
    uint index = gl_GlobalInvocationID.x;
    if (index >= image_pixels()) return;
    float lum = 0.0;
    for (uint c = 0u; c < COMPONENT_COUNT; ++c) {
        uint base = (c * image_pixels() + index) * 3u;
        vec3 v = vec3(pass_accum[base], pass_accum[base + 1u], pass_accum[base + 2u]);
        total_accum[base] += v.r;
        total_accum[base + 1u] += v.g;
        total_accum[base + 2u] += v.b;
        pass_accum[base] = 0.0;
        pass_accum[base + 1u] = 0.0;
        pass_accum[base + 2u] = 0.0;
        lum += luminance(v);
    }
    moments[index] += vec2(lum, lum * lum);
}
