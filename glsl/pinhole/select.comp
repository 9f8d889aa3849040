#version 460
// pinhole, step 3 (one workgroup, deterministic): the reflector sample
// points, selected from the M dense candidates by one of Sect. 3.2's four
// strategies. Candidates are i.i.d. uniform, so their index order is a
// random order; they are visited in rounds of PINHOLE_GROUP in that order,
// and the kept ones are appended (prefix sum within the round) until N
// are kept:
//   random (1): every candidate (the first N);
//   grid stratification (2): "fix a three dimensional grid of cubes in
//     space. In each grid cell, we chose only one of the sample points and
//     delete all others": the first candidate of each cell (cell side
//     h = sqrt(1.5 A / N), about N occupied cells);
//   quantized grid (3): the same, "but all sample points are quantized to
//     the grid cells": moved to the cell's centre (normal kept);
//   neighbourhood-based (4): "remove superfluous points in a greedy
//     manner. If a point is still covered by a sphere around another
//     point with fixed diameter, it is regarded as superfluous": a
//     candidate is removed if a kept one lies within delta = 0.75 sqrt(A/N)
//     (the random sequential adsorption limit of discs of that spacing is
//     about 1.2 N points, so N are reached before the surface is full and
//     the kept ones spread over all of it). Within one round, a candidate
//     is also removed by an earlier candidate of the round that passed the
//     test (greedy order kept, conservatively).
// The candidates' `normal.w` marks the kept ones (neighbourhood test).
// One dispatch handles PINHOLE_SELECT_CHUNK candidates from
// pc.first_candidate on, carrying the kept count in state.count (the host
// records ceil(M / chunk) dispatches): one dispatch over all candidates
// stopped early on lavapipe (on `ring`: no point at all at N = 3800 or
// 10,000, 1986 of 2,000 at N = 2,000 with 32,000 candidates; no validation
// message, buffer memory barriers made no difference; the cause is not
// known), while chunks of this size gave every point in every case tried.
#include "common.glsl"

layout(local_size_x = PINHOLE_GROUP) in;

shared uint flags[PINHOLE_GROUP];
shared uint scan[PINHOLE_GROUP];
shared uint base_count;

bool first_in_cell(uint i, vec3 p) {
    ivec3 c = grid_cell(p);
    for (uint j = heads[grid_hash(c)]; j != NONE; j = next_candidate[j]) {
        if (j < i && all(equal(grid_cell(candidates[j].position.xyz), c))) return false;
    }
    return true;
}

// No kept candidate of an earlier round within delta of p.
bool uncovered(vec3 p, float delta, uint round_base) {
    ivec3 c = grid_cell(p);
    for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
    for (int x = -1; x <= 1; ++x) {
        for (uint j = heads[grid_hash(c + ivec3(x, y, z))]; j != NONE; j = next_candidate[j]) {
            if (j >= round_base || candidates[j].normal.w == 0.0) continue;
            vec3 d = candidates[j].position.xyz - p;
            if (dot(d, d) < delta * delta) return false;
        }
    }
    return true;
}

// Covered by an earlier candidate of this round that passed `uncovered`.
bool covered_in_round(uint i, vec3 p, float delta, uint round_base) {
    ivec3 c = grid_cell(p);
    for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
    for (int x = -1; x <= 1; ++x) {
        for (uint j = heads[grid_hash(c + ivec3(x, y, z))]; j != NONE; j = next_candidate[j]) {
            if (j < round_base || j >= i || flags[j - round_base] == 0u) continue;
            vec3 d = candidates[j].position.xyz - p;
            if (dot(d, d) < delta * delta) return true;
        }
    }
    return false;
}

void main() {
    uint tid = gl_LocalInvocationID.x;
    if (tid == 0u) base_count = state.count;
    barrier();
    if (state.total_area <= 0.0) return; // uniform: no reflector
    float delta = 0.75 * sqrt(state.total_area / float(pc.target));
    uint rounds = 0u;
    uint end = min(pc.candidates, pc.first_candidate + PINHOLE_SELECT_CHUNK);
    for (uint round_base = pc.first_candidate; round_base < end; round_base += PINHOLE_GROUP) {
        if (base_count >= pc.target) break; // uniform: read after a barrier
        rounds += 1u;
        uint i = round_base + tid;
        bool keep = false;
        vec3 p = vec3(0.0);
        if (i < pc.candidates) {
            p = candidates[i].position.xyz;
            if (pc.strategy == PINHOLE_STRATEGY_RANDOM) keep = true;
            else if (pc.strategy == PINHOLE_STRATEGY_NEIGHBOURHOOD) keep = uncovered(p, delta, round_base);
            else keep = first_in_cell(i, p);
        }
        flags[tid] = keep ? 1u : 0u;
        barrier();
        if (pc.strategy == PINHOLE_STRATEGY_NEIGHBOURHOOD && keep) {
            keep = !covered_in_round(i, p, delta, round_base);
        }
        barrier();
        flags[tid] = keep ? 1u : 0u;
        scan[tid] = flags[tid];
        barrier();
        for (uint off = 1u; off < PINHOLE_GROUP; off <<= 1u) {
            uint v = tid >= off ? scan[tid - off] : 0u;
            barrier();
            scan[tid] += v;
            barrier();
        }
        uint idx = base_count + scan[tid] - 1u;
        if (keep && idx < pc.target) {
            vec4 pos = candidates[i].position;
            if (pc.strategy == PINHOLE_STRATEGY_QUANTIZED_GRID) {
                pos.xyz = (vec3(grid_cell(pos.xyz)) + 0.5) * state.cell;
            }
            samples[idx].position = pos;
            samples[idx].normal = vec4(candidates[i].normal.xyz, 0.0);
        } else {
            keep = false;
        }
        if (i < pc.candidates) candidates[i].normal.w = keep ? 1.0 : 0.0;
        // The next round reads these flags from other invocations.
        memoryBarrierBuffer();
        barrier();
        if (tid == 0u) base_count = min(base_count + scan[PINHOLE_GROUP - 1u], pc.target);
        barrier();
    }
    if (tid == 0u) {
        state.count = base_count;
        state.kept_rounds += rounds;
    }
}
