#version 460
// Shadow map, fragment stage: the linear distance readers compare against
// (glsl/common/shadow.glsl shadow_receiver_depth computes the same). A
// cut-out (glsl/common/scene.glsl material_cut_out) casts no shadow.
#include "scene.glsl"

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 origin;
    vec4 direction;
} pc;

layout(location = 0) in vec3 v_position;
layout(location = 1) flat in uint v_material;
layout(location = 2) in vec2 v_uv;
layout(location = 0) out float out_distance;

void main() {
    if (material_cut_out(v_material, v_uv)) discard;
    vec3 d = v_position - pc.origin.xyz;
    out_distance = floatBitsToUint(pc.origin.w) == SHADOW_PLANAR ? dot(d, pc.direction.xyz) : length(d);
}
