#version 460
// pinhole, step 6: the light cube maps (Sect. 3.1: "represent the incoming
// light as an environment map ... a cube environment map that can be
// generated easily on-the-fly"), one per cluster centre and emitter slot,
// level 0, every frame (moving lights cost nothing extra). Each texel holds
// the mean radiance over its solid angle, from 4x4 sub-texel directions.
// Small emitters cover few texels, so the map's integral of L over solid
// angle is off by the sub-texel sampling; each map's coverage integral
// (sum of covered fraction x texel solid angle) goes to map_norm[].x and
// the emitter's exact solid angle to .y: the receivers scale the map by
// y / x, so the map carries exactly L * Omega_emitter (y =
// PINHOLE_MAP_EXACT: the map is taken as it is).
#extension GL_EXT_shader_atomic_float : require
#include "common.glsl"
#include "optics.glsl"
#include "lights.glsl"
#include "emitters.glsl"
#include "punctual_emitters.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = PINHOLE_BINDING_LIGHT_MAP_LEVEL0, rgba32f) uniform writeonly image2DArray light_map0;

#define PINHOLE_SUBSAMPLES 4

// The emitter slots of every cluster's maps (src/techniques/pinhole
// `emitter_slots`), each one glsl/common radiance function:
//   [0, L)        the scene's point, spot and directional lights
//                 (glsl/common/punctual_emitters.glsl), L = frame.counts.x;
//   [L, L + E)    its rect and sphere area lights (glsl/common/emitters.glsl),
//                 E = frame.components.y;
//   L + E         the environment's table (an image, or a sky's gradient),
//   L + E + 1     a sky's sun disc (no slot for an image, whose sun is in
//                 its table); both present only with an environment light.
// The environment is distant (Sect. 5: "one environment map assumes
// distant light sources"), so its maps are the same from every cluster.

// Radiance of emitter slot `slot` seen from `origin` along `dir`.
vec3 emitter_radiance(uint slot, vec3 origin, vec3 dir) {
    uint punctual = frame.counts.x, areas = frame.components.y;
    if (slot < punctual) return light_emitter_radiance(slot, origin, dir, pc.light_radius, pc.sun_cos);
    if (slot < punctual + areas) return area_emitter_radiance(slot - punctual, origin, dir);
    if (!environment_present()) return vec3(0.0);
    if (slot == punctual + areas) return environment_table_radiance(dir);
    if (slot == punctual + areas + 1u) return environment_sun_radiance(dir);
    return vec3(0.0);
}

// The exact solid angle of slot `slot`'s emitter from `origin`, or
// PINHOLE_MAP_EXACT for the environment's table, which covers whole texels
// and needs no renormalisation.
float emitter_solid_angle(uint slot, vec3 origin) {
    uint punctual = frame.counts.x, areas = frame.components.y;
    if (slot < punctual) return light_emitter_solid_angle(slot, origin, pc.light_radius, pc.sun_cos);
    if (slot < punctual + areas) return area_emitter_solid_angle(slot - punctual, origin);
    if (slot == punctual + areas) return PINHOLE_MAP_EXACT;
    if (slot == punctual + areas + 1u) return environment_sun_solid_angle();
    return 0.0;
}

void main() {
    uint size = pc.cube_size;
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= size || id.y >= size) return;
    uint layer = id.z;
    uint face = layer % 6u;
    uint slot = (layer / 6u) % pc.slots;
    uint k = layer / (6u * pc.slots);
    vec4 centre = state.centres[k];
    if (centre.w == 0.0) return; // cluster not in use this frame
    vec3 sum = vec3(0.0);
    float covered = 0.0;
    for (int sy = 0; sy < PINHOLE_SUBSAMPLES; ++sy)
    for (int sx = 0; sx < PINHOLE_SUBSAMPLES; ++sx) {
        vec2 st = (vec2(id.xy) + (vec2(sx, sy) + 0.5) / float(PINHOLE_SUBSAMPLES)) / float(size) * 2.0 - 1.0;
        vec3 l = emitter_radiance(slot, centre.xyz, normalize(cube_direction(face, st)));
        sum += l;
        covered += any(greaterThan(l, vec3(0.0))) ? 1.0 : 0.0;
    }
    const float n_sub = float(PINHOLE_SUBSAMPLES * PINHOLE_SUBSAMPLES);
    imageStore(light_map0, ivec3(id.xy, layer), vec4(sum / n_sub, 1.0));
    uint norm = k * pc.slots + slot;
    if (covered > 0.0) {
        // Texel solid angle at its centre: (2/S)^2 / (1 + s^2 + t^2)^(3/2).
        vec2 st = (vec2(id.xy) + 0.5) / float(size) * 2.0 - 1.0;
        float r2 = 1.0 + dot(st, st);
        float omega = 4.0 / float(size * size) * inversesqrt(r2 * r2 * r2);
        atomicAdd(state.map_norm[norm].x, covered / n_sub * omega);
    }
    if (face == 0u && id.x == 0u && id.y == 0u) {
        state.map_norm[norm].y = emitter_solid_angle(slot, centre.xyz);
    }
}
