#version 460
// Shadow map, fragment stage: the linear distance readers compare against
// (glsl/common/shadow.glsl shadow_receiver_depth computes the same).
#include "bindings.glsl"

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 origin;
    vec4 direction;
} pc;

layout(location = 0) in vec3 v_position;
layout(location = 0) out float out_distance;

void main() {
    vec3 d = v_position - pc.origin.xyz;
    out_distance = floatBitsToUint(pc.origin.w) == SHADOW_PLANAR ? dot(d, pc.direction.xyz) : length(d);
}
