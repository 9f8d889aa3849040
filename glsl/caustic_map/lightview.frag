#version 460
// Light-space G-buffer, fragment stage: specular surfaces only; the front
// pass keeps faces whose (winding) normal faces the light, the back pass
// the others, each the nearest by the depth test. Stores world position
// (w = 1: covered) and the smooth normal (outward, as given) with the
// material index in w.
#include "scene.glsl"

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 origin;
    vec4 forward;
} pc;

layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) flat in vec3 v_geometric;
layout(location = 3) flat in uint v_material;

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    if (material_kind(v_material) == MATERIAL_DIFFUSE) discard;
    vec3 ray = floatBitsToUint(pc.origin.w) == SHADOW_PLANAR ? pc.forward.xyz : v_position - pc.origin.xyz;
    bool facing_light = dot(v_geometric, ray) < 0.0;
    bool want_front = floatBitsToUint(pc.forward.w) == LIGHT_VIEW_FRONT;
    if (facing_light != want_front) discard;
    out_position = vec4(v_position, 1.0);
    out_normal = vec4(normalize(v_normal), float(v_material));
}
