#version 460
// Probe for tests/pipeline_reuse.rs: writes its push constant times a
// specialisation constant, so the test sees which specialisation ran.
#include "bindings.glsl"

layout(local_size_x = 1) in;

layout(constant_id = 0) const uint FACTOR = 1u;

layout(set = 0, binding = PROBE_BINDING_RESULTS, std430) writeonly buffer Results { uint results[]; };

layout(push_constant) uniform Push {
    uint value;
} pc;

void main() {
    results[0] = pc.value * FACTOR;
}
