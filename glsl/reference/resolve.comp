#version 460
// Ground truth: turns the running sums into radiance (W m^-2 sr^-1), the
// mean of the pass estimates. `component` selects one path type, or
// COMPONENT_COUNT for the sum.
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 1, binding = REFERENCE_BINDING_RADIANCE, rgba32f) uniform writeonly image2D radiance_out;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= image_width() || p.y >= image_height()) return;
    uint index = p.y * image_width() + p.x;
    vec3 sum = vec3(0.0);
    for (uint c = 0u; c < COMPONENT_COUNT; ++c) {
        if (pc.component == c || pc.component == COMPONENT_COUNT) {
            uint base = (c * image_pixels() + index) * 3u;
            sum += vec3(total_accum[base], total_accum[base + 1u], total_accum[base + 2u]);
        }
    }
    imageStore(radiance_out, ivec2(p), vec4(sum / max(pc.passes, 1.0), 1.0));
}
