#version 460
// Camera G-buffer, vertex stage: vertex pulling from the scene's triangle
// buffer (triangle = gl_VertexIndex / 3, corner = gl_VertexIndex % 3).
#include "scene.glsl"

layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;
layout(location = 2) flat out uint v_material;
layout(location = 3) out vec2 v_uv;

void main() {
    uint tri = uint(gl_VertexIndex) / 3u;
    uint corner = uint(gl_VertexIndex) % 3u;
    Triangle t = triangles[tri];
    vec3 p = corner == 0u ? t.p0.xyz : (corner == 1u ? t.p1.xyz : t.p2.xyz);
    vec3 n = corner == 0u ? t.n0.xyz : (corner == 1u ? t.n1.xyz : t.n2.xyz);
    v_position = p;
    v_normal = n;
    v_material = floatBitsToUint(t.p0.w);
    TriangleUv uv = triangle_uvs[tri];
    v_uv = corner == 0u ? uv.uv01.xy : (corner == 1u ? uv.uv01.zw : uv.uv2.xy);
    gl_Position = frame.view_proj * vec4(p, 1.0);
}
