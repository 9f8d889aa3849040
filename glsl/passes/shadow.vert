#version 460
// Shadow map, vertex stage: vertex pulling, one light view from push constants.
#include "scene.glsl"

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 origin;    // xyz light position / ortho eye; w: SHADOW_RADIAL or SHADOW_PLANAR (uint bits)
    vec4 direction; // xyz light direction (planar)
} pc;

layout(location = 0) out vec3 v_position;
layout(location = 1) flat out uint v_material;
layout(location = 2) out vec2 v_uv;

void main() {
    uint tri = uint(gl_VertexIndex) / 3u;
    uint corner = uint(gl_VertexIndex) % 3u;
    Triangle t = triangles[tri];
    vec3 p = corner == 0u ? t.p0.xyz : (corner == 1u ? t.p1.xyz : t.p2.xyz);
    v_position = p;
    v_material = floatBitsToUint(t.p0.w);
    TriangleUv uv = triangle_uvs[tri];
    v_uv = corner == 0u ? uv.uv01.xy : (corner == 1u ? uv.uv01.zw : uv.uv2.xy);
    gl_Position = pc.view_proj * vec4(p, 1.0);
}
