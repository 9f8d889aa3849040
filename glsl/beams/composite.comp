#version 460
// beams, Fig. 8: adds the volume caustics (C, already weighted by their
// component) to the frame (surface radiance, airlight comes after).
#include "scene.glsl"
#include "beams_bindings.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = BEAMS_BINDING_VOLUME, rgba32f) uniform readonly image2D volume;
layout(set = 1, binding = BEAMS_BINDING_RADIANCE, rgba32f) uniform image2D radiance;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    imageStore(radiance, p, imageLoad(radiance, p) + vec4(imageLoad(volume, p).rgb, 0.0));
}
