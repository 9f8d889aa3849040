#version 460
// pinhole, step 7: the mip chain of the light cube maps (level l = the
// 2x2 box average of level l-1, every layer), which the receivers'
// textureGrad filters over (Sect. 3.3).
layout(local_size_x = 8, local_size_y = 8) in;

#include "pinhole_bindings.glsl"

layout(set = 1, binding = PINHOLE_MIP_BINDING_SRC, rgba32f) uniform readonly image2DArray src;
layout(set = 1, binding = PINHOLE_MIP_BINDING_DST, rgba32f) uniform writeonly image2DArray dst;

void main() {
    ivec3 id = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(id.xy, imageSize(dst).xy))) return;
    ivec2 s = id.xy * 2;
    vec4 v = imageLoad(src, ivec3(s, id.z)) + imageLoad(src, ivec3(s + ivec2(1, 0), id.z))
        + imageLoad(src, ivec3(s + ivec2(0, 1), id.z)) + imageLoad(src, ivec3(s + ivec2(1, 1), id.z));
    imageStore(dst, id, 0.25 * v);
}
