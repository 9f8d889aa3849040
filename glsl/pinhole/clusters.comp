#version 460
// pinhole, step 5 (one workgroup): clusters of sample points, each with its
// own light cube maps centred on it. Sect. 3.1 uses one environment map,
// "sufficient if all light sources are far away"; Sect. 5: "the light
// sources are assumed to be far away from the reflector. If this is not the
// case, it could be necessary to compute multiple cube maps for different
// clusters of sample points". K-means (Lloyd) on the sample positions:
// centres start at K sample points spread through the (random) index order,
// then PINHOLE_KMEANS_ITERATIONS rounds of assign-nearest / move-to-mean.
// The cluster index goes to samples[i].normal.w; centres[k].w = 1 marks a
// cluster in use (K may exceed N).
#include "common.glsl"

#define PINHOLE_KMEANS_ITERATIONS 8

layout(local_size_x = PINHOLE_GROUP) in;

shared vec4 red[PINHOLE_GROUP];

uint nearest(vec3 p, uint k_count) {
    uint best = 0u;
    float best_d = 1e38;
    for (uint k = 0u; k < k_count; ++k) {
        vec3 d = p - state.centres[k].xyz;
        float dd = dot(d, d);
        if (dd < best_d) { best_d = dd; best = k; }
    }
    return best;
}

void main() {
    uint tid = gl_LocalInvocationID.x;
    uint count = state.count;
    uint k_count = min(pc.clusters, count);
    if (tid < PINHOLE_MAX_CLUSTERS) {
        state.centres[tid] = tid < k_count
            ? vec4(samples[(tid * count) / k_count].position.xyz, 1.0)
            : vec4(0.0);
    }
    // Every invocation reads the centres (buffer memory) next.
    memoryBarrierBuffer();
    barrier();
    if (k_count == 0u) return; // uniform
    for (int it = 0; it <= PINHOLE_KMEANS_ITERATIONS; ++it) {
        for (uint i = tid; i < count; i += PINHOLE_GROUP) {
            samples[i].normal.w = uintBitsToFloat(nearest(samples[i].position.xyz, k_count));
        }
        barrier();
        if (it == PINHOLE_KMEANS_ITERATIONS) break; // the last assignment stays
        for (uint k = 0u; k < k_count; ++k) {
            vec4 s = vec4(0.0);
            for (uint i = tid; i < count; i += PINHOLE_GROUP) {
                if (floatBitsToUint(samples[i].normal.w) == k) s += vec4(samples[i].position.xyz, 1.0);
            }
            red[tid] = s;
            barrier();
            for (uint off = PINHOLE_GROUP / 2u; off > 0u; off >>= 1u) {
                if (tid < off) red[tid] += red[tid + off];
                barrier();
            }
            if (tid == 0u && red[0].w > 0.0) state.centres[k] = vec4(red[0].xyz / red[0].w, 1.0);
            memoryBarrierBuffer();
            barrier();
        }
    }
}
