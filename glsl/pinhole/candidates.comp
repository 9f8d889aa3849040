#version 460
// pinhole, step 2: M dense random points, uniform over the reflector's
// area (pick a triangle by its area through the CDF, then a uniform point
// in it), with the interpolated normal; each is linked into the hash grid
// (cell side state.cell). Sect. 3.2's "high density random sample set",
// from which every strategy selects, and Sect. 3.3's "denser set of sample
// points in the region around the main sample point".
#include "common.glsl"
#include "random.glsl"

layout(local_size_x = 64) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.candidates) return;
    uint n = frame.counts.y;
    float total = state.total_area;
    if (n == 0u || total <= 0.0) return;
    // A fixed seed: a static scene samples the same points every frame (no
    // flicker); moving reflectors are sampled anew from their triangles.
    uint rng = rng_seed(i, 0x5eedu);
    float u = rng_next(rng) * total;
    // First triangle whose inclusive prefix exceeds u (zero-area
    // triangles, i.e. non-reflectors, are never chosen).
    uint lo = 0u, hi = n - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) >> 1u;
        if (cdf[mid] > u) hi = mid; else lo = mid + 1u;
    }
    uint tri = lo;
    float r1 = sqrt(rng_next(rng)), r2 = rng_next(rng);
    float b1 = r1 * (1.0 - r2), b2 = r1 * r2; // uniform barycentrics
    Triangle t = triangles[tri];
    vec3 p = (1.0 - b1 - b2) * t.p0.xyz + b1 * t.p1.xyz + b2 * t.p2.xyz;
    vec3 nrm = (1.0 - b1 - b2) * t.n0.xyz + b1 * t.n1.xyz + b2 * t.n2.xyz;
    if (dot(nrm, nrm) < 1e-20) nrm = cross(t.p1.xyz - t.p0.xyz, t.p2.xyz - t.p0.xyz);
    candidates[i].position = vec4(p, uintBitsToFloat(triangle_material(tri)));
    candidates[i].normal = vec4(normalize(nrm), 0.0);
    uint h = grid_hash(grid_cell(p));
    next_candidate[i] = atomicExchange(heads[h], i);
}
