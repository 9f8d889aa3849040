#version 460
// volume_lines: adds the volume caustic image (B, already weighted by its
// component) to the frame (A + C), Fig. 2's sum.
#include "scene.glsl"
#include "volume_lines_bindings.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = VOLUME_LINES_BINDING_VOLUME, rgba32f) uniform readonly image2D volume;
layout(set = 1, binding = VOLUME_LINES_BINDING_RADIANCE, rgba32f) uniform image2D radiance;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(radiance);
    if (p.x >= size.x || p.y >= size.y) return;
    imageStore(radiance, p, imageLoad(radiance, p) + vec4(imageLoad(volume, p).rgb, 0.0));
}
