#version 460
// Linear radiance -> display-referred 8-bit sRGB (glsl/common/tonemap.glsl).
#include "tonemap.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D radiance;
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D display;
layout(push_constant) uniform Push { float exposure; } pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    vec3 l = imageLoad(radiance, p).rgb;
    // NaN or Inf must never reach a display silently: show them magenta.
    bool bad = any(isnan(l)) || any(isinf(l));
    imageStore(display, p, vec4(bad ? vec3(1.0, 0.0, 1.0) : tonemap(l, pc.exposure), 1.0));
}
