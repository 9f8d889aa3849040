#version 460
// beams, Sect. 4.2 (the stream-out's replacement): after a refinement
// level, turns the atomic counters into the next levels' indirect
// dispatches (VkDispatchIndirectCommand, BEAMS_REFINE_GROUP threads per
// group) and the bounding volumes' indirect draw (VkDrawIndirectCommand:
// one point per beam), each clamped to its buffer's capacity. One thread.
#include "beams_bindings.glsl"

layout(local_size_x = 1) in;

layout(set = 1, binding = BEAMS_BINDING_COUNTERS, std430) readonly buffer CounterBlock { uint counters[]; };
layout(set = 1, binding = BEAMS_BINDING_INDIRECT, std430) writeonly buffer IndirectBlock { uint indirect[]; };

layout(push_constant) uniform Push {
    uint triangle_capacity;
    uint beam_capacity;
} pc;

void main() {
    for (uint l = 0u; l <= BEAMS_MAX_LEVELS; ++l) {
        uint n = min(counters[BEAMS_COUNTER_TRIS + l], pc.triangle_capacity);
        indirect[3u * l] = (n + BEAMS_REFINE_GROUP - 1u) / BEAMS_REFINE_GROUP;
        indirect[3u * l + 1u] = 1u;
        indirect[3u * l + 2u] = 1u;
    }
    indirect[BEAMS_INDIRECT_DRAW] = min(counters[BEAMS_COUNTER_BEAMS], pc.beam_capacity);
    indirect[BEAMS_INDIRECT_DRAW + 1u] = 1u;
    indirect[BEAMS_INDIRECT_DRAW + 2u] = 0u;
    indirect[BEAMS_INDIRECT_DRAW + 3u] = 0u;
}
