#version 460
// Specular G-buffer (Wyman 2005-06 two-sided refraction), vertex stage:
// vertex pulling, seen from the camera or from a light (push constants).
// The back pass reverses depth (z' = w - z, still within [0, w]) so the
// usual less-or-equal test keeps the farthest back face: Wyman's preferred
// second interface for non-convex refractors (Sect. "Fixing Problem Cases").
#include "scene.glsl"

layout(push_constant) uniform Push {
    mat4 view_proj; // unused for SPECULAR_VIEW_CAMERA (frame.view_proj)
    vec4 origin;    // xyz: light position or ortho plane centre; w: SHADOW_RADIAL, SHADOW_PLANAR or SPECULAR_VIEW_CAMERA (uint bits)
    vec4 forward; // xyz: view axis; w: SPECULAR_GBUFFER_FRONT or SPECULAR_GBUFFER_BACK (uint bits)
} pc;

layout(location = 0) out vec3 v_position;
layout(location = 1) out vec4 v_normal; // xyz: smooth normal; w: d_N
layout(location = 2) flat out vec3 v_geometric;
layout(location = 3) flat out uint v_material;

void main() {
    uint tri = uint(gl_VertexIndex) / 3u;
    uint corner = uint(gl_VertexIndex) % 3u;
    Triangle t = triangles[tri];
    vec3 p = corner == 0u ? t.p0.xyz : (corner == 1u ? t.p1.xyz : t.p2.xyz);
    v_position = p;
    v_normal = corner == 0u ? t.n0 : (corner == 1u ? t.n1 : t.n2);
    v_geometric = cross(t.p1.xyz - t.p0.xyz, t.p2.xyz - t.p0.xyz);
    v_material = floatBitsToUint(t.p0.w);
    bool camera = floatBitsToUint(pc.origin.w) == SPECULAR_VIEW_CAMERA;
    gl_Position = (camera ? frame.view_proj : pc.view_proj) * vec4(p, 1.0);
    if (floatBitsToUint(pc.forward.w) == SPECULAR_GBUFFER_BACK) {
        gl_Position.z = gl_Position.w - gl_Position.z;
    }
}
