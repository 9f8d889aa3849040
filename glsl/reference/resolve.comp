#version 460
// Ground truth: turns the accumulation buffers into radiance (W m^-2 sr^-1):
// photon sums divided by the photons emitted, camera-chain sums by their
// passes. `component` selects one path type, or COMPONENT_COUNT for the sum.
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 1, binding = 2, rgba32f) uniform writeonly image2D radiance_out;

vec3 photon_image(uint component, uvec2 p) {
    uint base = ((component * image_height() + p.y) * image_width() + p.x) * 3u;
    return vec3(photon_accum[base], photon_accum[base + 1u], photon_accum[base + 2u]) / max(pc.photon_count, 1.0);
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= image_width() || p.y >= image_height()) return;
    vec3 sum = vec3(0.0);
    for (uint c = 0u; c < COMPONENT_COUNT; ++c) {
        if (pc.component == c || pc.component == COMPONENT_COUNT) sum += photon_image(c, p);
    }
    if (pc.component == COMPONENT_DIRECT || pc.component == COMPONENT_COUNT) {
        uint base = (p.y * image_width() + p.x) * 3u;
        sum += vec3(camera_accum[base], camera_accum[base + 1u], camera_accum[base + 2u]) / max(pc.camera_passes, 1.0);
    }
    imageStore(radiance_out, ivec2(p), vec4(sum, 1.0));
}
