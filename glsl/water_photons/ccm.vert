#version 460
// CCM raster, vertex stage (Kougianos & Moustakas 2021 §3.1): the water
// surface evaluated on the GPU (passes/water_surface.comp, one
// GpuWaterVertex per grid vertex) pulled as the triangles of
// `Water::mesh` (cell (i, j): a c b, a d c), projected by cascade c's
// orthographic light view (Eq. 2 × Eq. 1).
#include "water_photons_bindings.glsl"

struct WaterVertex {
    vec4 position;
    vec4 normal;
};

layout(set = 0, binding = WP_BINDING_WATER_VERTICES, std430) readonly buffer Vertices { WaterVertex vertices[]; };

layout(push_constant) uniform Push {
    mat4 view_proj;
    uvec4 grid; // x: nx cells, y: nz cells
} pc;

layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;

void main() {
    uint cell = uint(gl_VertexIndex) / 6u;
    uint corner = uint(gl_VertexIndex) % 6u;
    uint nx = pc.grid.x;
    uint i = cell % nx, j = cell / nx;
    uint stride = nx + 1u;
    uint a = j * stride + i;
    uint b = a + 1u, c = a + 1u + stride, d = a + stride;
    uint idx[6] = uint[6](a, c, b, a, d, c);
    WaterVertex v = vertices[idx[corner]];
    v_position = v.position.xyz;
    v_normal = v.normal.xyz;
    gl_Position = pc.view_proj * vec4(v.position.xyz, 1.0);
}
