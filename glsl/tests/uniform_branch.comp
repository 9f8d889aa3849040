#version 460
// Reproduction for examples/lavapipe_rebind.rs: a loop whose trip count
// and a branch whose side a uniform block decides (as water_photons'
// view.comp did with its cascade count and splat mode), or the same two
// values as specialisation constants (FROM_CONSTANTS = 1).
#include "bindings.glsl"

layout(local_size_x = 64) in;

layout(constant_id = 0) const uint FROM_CONSTANTS = 0u;
layout(constant_id = 1) const uint COUNT = 2u;
layout(constant_id = 2) const uint MODE = 0u;

layout(set = 0, binding = PROBE_BINDING_PARAMS, std140) uniform Params {
    uvec4 count_mode; // x: trip count, y: branch
} params;
layout(set = 0, binding = PROBE_BINDING_RESULTS, std430) buffer Results { vec4 results[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint count = FROM_CONSTANTS != 0u ? COUNT : params.count_mode.x;
    uint mode = FROM_CONSTANTS != 0u ? MODE : params.count_mode.y;
    vec4 acc = results[i];
    for (uint c = 0u; c < count; ++c) {
        if (mode == 0u) {
            acc = sin(acc * 1.3 + float(c)) + cos(acc.yzwx * 0.7);
            acc = acc * acc.wxyz + exp(-abs(acc.zwxy));
        } else {
            acc = cos(acc * 0.9 - float(c)) * sin(acc.wzyx * 1.1);
            acc = sqrt(abs(acc)) + log(1.0 + abs(acc.yxwz));
        }
    }
    results[i] = acc;
}
