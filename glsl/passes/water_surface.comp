#version 460
// Evaluates a water grid's Gerstner surface at one time (glsl/common/water.glsl):
// one invocation per grid vertex (i, j), written at index j (nx + 1) + i as
// GpuWaterVertex (src/gpu.rs): position.xyz, normal.xyz.
#include "bindings.glsl"
#include "water.glsl"

layout(local_size_x = WATER_SURFACE_GROUP_SIZE, local_size_y = WATER_SURFACE_GROUP_SIZE) in;

struct WaterVertex {
    vec4 position;
    vec4 normal;
};

layout(set = 0, binding = WATER_SURFACE_BINDING_WAVES, std430) readonly buffer WaveBlock { Wave waves[]; };
layout(set = 0, binding = WATER_SURFACE_BINDING_VERTICES, std430) writeonly buffer VertexBlock { WaterVertex vertices[]; };

// WaterSurfacePush in src/passes/water_surface.rs.
layout(push_constant) uniform Push {
    vec4 center_size;        // xy: centre (x, z); zw: size (x, z), m
    uvec4 grid;              // x: nx cells, y: nz cells, z: wave count
    vec4 time_base_height;   // x: time (s), y: base height (m)
} pc;

void main() {
    uvec2 ij = gl_GlobalInvocationID.xy;
    if (ij.x > pc.grid.x || ij.y > pc.grid.y) return;
    // Water::rest_position: centre + size · (i/nx − ½, j/nz − ½).
    vec2 f = vec2(float(ij.x) / float(pc.grid.x) - 0.5, float(ij.y) / float(pc.grid.y) - 0.5);
    vec2 rest = pc.center_size.xy + pc.center_size.zw * f;
    float time = pc.time_base_height.x;
    WaterPoint p = water_at_rest(rest, pc.time_base_height.y);
    for (uint w = 0u; w < pc.grid.z; w++) {
        water_add_wave(p, rest, time, waves[w]);
    }
    vertices[ij.y * (pc.grid.x + 1u) + ij.x] = WaterVertex(vec4(p.position, 1.0), vec4(water_normal(p), 0.0));
}
