#version 460
// pinhole, step 1 (one workgroup): the reflector's area distribution for
// uniform sampling over its surface (Sect. 3.2: "we try to place sample
// points uniformly over the surface"): cdf[i] = the area of the reflector
// triangles among triangles[0..i] (inclusive prefix sum; other triangles
// add 0), A = the total. Also resets the frame's state and the hash grid.
// Every frame, from the current (possibly animated) triangles.
#include "common.glsl"

layout(local_size_x = PINHOLE_GROUP) in;

shared float partial[PINHOLE_GROUP];

void main() {
    uint tid = gl_LocalInvocationID.x;
    for (uint i = tid; i < pc.hash_size; i += PINHOLE_GROUP) heads[i] = NONE;
    for (uint i = tid; i < pc.clusters * pc.slots; i += PINHOLE_GROUP) state.map_norm[i] = vec2(0.0);
    uint n = frame.counts.y;
    float running = 0.0;
    for (uint base = 0u; base < n; base += PINHOLE_GROUP) {
        uint i = base + tid;
        float a = 0.0;
        if (i < n && reflector_material(triangle_material(i))) {
            vec3 p0 = triangles[i].p0.xyz;
            a = 0.5 * length(cross(triangles[i].p1.xyz - p0, triangles[i].p2.xyz - p0));
        }
        partial[tid] = a;
        barrier();
        // Hillis-Steele inclusive scan of the chunk.
        for (uint off = 1u; off < PINHOLE_GROUP; off <<= 1u) {
            float v = tid >= off ? partial[tid - off] : 0.0;
            barrier();
            partial[tid] += v;
            barrier();
        }
        if (i < n) cdf[i] = running + partial[tid];
        running += partial[PINHOLE_GROUP - 1u];
        barrier();
    }
    if (tid == 0u) {
        state.total_area = running;
        state.count = 0u;
        state.kept_rounds = 0u;
        // Hash-grid cell: a surface of area A crosses about 1.5 A / h^2
        // cells of side h (isotropic orientations), so h = sqrt(1.5 A / N)
        // gives about N occupied cells (grid stratification).
        state.cell = max(sqrt(1.5 * running / float(pc.target)), 1e-6);
    }
}
