#version 460
// Test probe (tests/bvh_gpu.rs): traces one ray per invocation with
// trace_closest and trace_any so the host can compare GPU traversal against
// Bvh::intersect / Bvh::occluded on the CPU. Set 0 is the scene
// (SceneGpu's layout), set 1 the probe's buffers.
// rays[i]: origin.xyz, t_min in w; direction.xyz, t_max in w.
// results[i]: (t, triangle as uint bits, u, v); a miss writes (-1, 0xffffffff, 0, 0).
// any_results[i]: 1 if trace_any finds an occluder, else 0.
#define SCENE_SET 0
#include "scene.glsl"
#include "bvh.glsl"

layout(local_size_x = 64) in;

struct ProbeRay {
    vec4 origin_tmin;
    vec4 dir_tmax;
};

layout(set = 1, binding = PROBE_BINDING_RAYS, std430) readonly buffer RayBlock { ProbeRay rays[]; };
layout(set = 1, binding = PROBE_BINDING_RESULTS, std430) writeonly buffer ResultBlock { vec4 results[]; };
layout(set = 1, binding = PROBE_BINDING_ANY, std430) writeonly buffer AnyBlock { uint any_results[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(rays.length())) return;
    ProbeRay r = rays[i];
    Hit h;
    if (trace_closest(r.origin_tmin.xyz, r.dir_tmax.xyz, r.origin_tmin.w, r.dir_tmax.w, h)) {
        results[i] = vec4(h.t, uintBitsToFloat(h.triangle), h.barycentric);
    } else {
        results[i] = vec4(-1.0, uintBitsToFloat(0xffffffffu), 0.0, 0.0);
    }
    any_results[i] = trace_any(r.origin_tmin.xyz, r.dir_tmax.xyz, r.origin_tmin.w, r.dir_tmax.w) ? 1u : 0u;
}
