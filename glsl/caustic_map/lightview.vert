#version 460
// Light-space G-buffer of the specular objects (Wyman 2005, two-sided
// refraction seen from the light): vertex pulling, the photon view's matrix.
#include "scene.glsl"

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 origin;  // xyz: light position or ortho plane centre; w: SHADOW_RADIAL/SHADOW_PLANAR (uint bits)
    vec4 forward; // xyz: view axis; w: LIGHT_VIEW_FRONT or LIGHT_VIEW_BACK (uint bits)
} pc;

layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;
layout(location = 2) flat out vec3 v_geometric;
layout(location = 3) flat out uint v_material;

void main() {
    uint tri = uint(gl_VertexIndex) / 3u;
    uint corner = uint(gl_VertexIndex) % 3u;
    Triangle t = triangles[tri];
    vec3 p = corner == 0u ? t.p0.xyz : (corner == 1u ? t.p1.xyz : t.p2.xyz);
    v_position = p;
    v_normal = corner == 0u ? t.n0.xyz : (corner == 1u ? t.n1.xyz : t.n2.xyz);
    v_geometric = cross(t.p1.xyz - t.p0.xyz, t.p2.xyz - t.p0.xyz);
    v_material = floatBitsToUint(t.p0.w);
    gl_Position = pc.view_proj * vec4(p, 1.0);
}
