#version 460
// Probe for tests/water_photons.rs: Algorithm 1 as the trace shader runs it
// (glsl/water_photons/cascades.glsl), one thread per id, writing
// (x, y, cascade, 1) or (0, 0, 0, 0) past the end.
#include "bindings.glsl"
#include "../water_photons/cascades.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = PROBE_BINDING_RESULTS, std430) writeonly buffer Results { uvec4 results[]; };

layout(push_constant) uniform Push {
    uvec4 size_levels; // x, y: ccm_0; z: N; w: threads to run
    uvec4 border;      // x, y: ΔX, ΔY
} pc;

void main() {
    uint thread = gl_GlobalInvocationID.x;
    if (thread >= pc.size_levels.w) return;
    uvec2 texel;
    uint c;
    bool ok = ccm_texel_of(thread, pc.size_levels.xy, pc.border.xy, pc.size_levels.z, texel, c);
    results[thread] = ok ? uvec4(texel, c, 1u) : uvec4(0u);
}
