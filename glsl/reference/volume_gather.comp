#version 460
// Ground truth: the volume photon map's gather at the points
// volume_points.comp appended (see there for the estimator), one invocation
// per point and grid cell: the ball of radius r_v around a point overlaps
// at most 3x3x3 cells of side r_v, and each invocation walks one cell's
// chain, so no invocation's loops come near llvmpipe's limit of 65535
// iterations (one counter per invocation for all its loops; past it every
// loop exits silently). The longest walk is counted in `stats` so that a
// walk the guard cut short is reported, never silent.
#include "common.glsl"

layout(local_size_x = 64) in;

void main() {
    uint id = gl_GlobalInvocationID.x;
    uint point_index = id / GATHER_CELLS;
    if (point_index >= min(gather_point_count, pc.gather_capacity)) return;
    GatherPoint point = gather_points[point_index];
    vec3 y = point.position.xyz;
    float r = pc.volume_radius;
    float side = volume_cell_side();
    uint j = id % GATHER_CELLS;
    ivec3 c = grid_cell(y - vec3(r), side) + ivec3(j % 3u, (j / 3u) % 3u, j / 9u);
    if (any(greaterThan(c, grid_cell(y + vec3(r), side)))) return;
    // A cell whose box misses the ball holds no photon within r.
    vec3 nearest = clamp(y, vec3(c) * side, vec3(c + 1) * side);
    if (dot(nearest - y, nearest - y) >= r * r) return;

    vec3 dir = point.direction.xyz;
    uint tag_mask = floatBitsToUint(point.direction.w);
    float g = point.weight.w; // the phase of the medium the point lies in
    uint links = min(min(volume_photon_count, pc.volume_capacity), REFERENCE_GATHER_WALK_LIMIT);
    vec3 sums[COMPONENT_COUNT];
    for (uint k = 0u; k < COMPONENT_COUNT; ++k) sums[k] = vec3(0.0);
    uint i = volume_heads[grid_bucket(c, pc.volume_mask)];
    uint walked = 0u;
    for (; i != REFERENCE_GRID_NONE && walked < links; ++walked) {
        VolumePhoton photon = volume_photons[i];
        vec3 d = photon.position.xyz - y;
        uint tag = floatBitsToUint(photon.position.w);
        // Other cells share the bucket: the distance test alone is enough
        // only for this cell's photons (another cell's would be counted twice).
        if (grid_cell(photon.position.xyz, side) == c && dot(d, d) < r * r && (tag_mask & (1u << tag)) != 0u) {
            sums[tag] += photon.flux.rgb * hg_phase(dot(photon.direction.xyz, -dir), g);
        }
        i = volume_next[i];
    }
    // A plain read first: once a long walk is recorded, shorter ones need
    // no atomic on this one shared word (every invocation would contend).
    if (walked > gather_longest_walk) atomicMax(gather_longest_walk, walked);
    uint pixel = floatBitsToUint(point.position.w);
    for (uint k = 0u; k < COMPONENT_COUNT; ++k) {
        if (any(greaterThan(sums[k], vec3(0.0)))) add_pass(pixel, k, point.weight.rgb * sums[k]);
    }
}
