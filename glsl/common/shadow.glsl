// Shadow map lookups (maps rendered by src/passes/shadow.rs). Before
// including, define SHADOW_SET, SHADOW_BINDING_LIGHTS (uniform buffer of
// ShadowLight[MAX_LIGHTS]) and SHADOW_BINDING_MAP (sampler2DArray of linear
// distances, 6 layers per light, sampled with texelFetch).
//
// Bias (all in world units, from the world size w of one shadow texel at
// the receiver: w = texel_per_metre * distance for perspective views,
// w = 2R / size for the orthographic one):
// - normal offset: the lookup point moves NORMAL_OFFSET_TEXELS * w along the
//   receiver's normal, off the surface toward the lit side, so a surface
//   never compares against its own rasterised samples at grazing angles;
// - slope-scaled depth bias: the receiver's distance is reduced by
//   w * (DEPTH_BIAS_TEXELS + SLOPE_BIAS * (pcf + 1) * tan(theta)), tan
//   clamped at MAX_SLOPE. A PCF tap up to pcf + 1 texels away (diagonal,
//   plus half a texel of rounding: < 1.5 (pcf + 1) w laterally) sees the
//   receiver's own plane at most that much nearer.
// Both scale with the texel, so fully lit surfaces are exactly lit (every
// tap passes) at any shadow map size, and light leaks only within about one
// texel of contact points, i.e. well under a pixel at 256² output with the
// default 1024² maps. The bias also lights a receiver whose occluder is
// nearer the light by less than it (tan theta large: a wall just under the
// water's surface, bias up to 30 texels); `shadow_visibility_band` reports
// those taps so that a pass with the BVH can ask a ray (direct lighting).
#ifndef COMMON_SHADOW_GLSL
#define COMMON_SHADOW_GLSL

#include "bindings.glsl"

struct ShadowLight {
    mat4 view_proj[6]; // world -> clip of each view
    vec4 origin;       // xyz light position / ortho eye; w: texel size per metre (radial) or metres (planar)
    vec4 direction;    // xyz light direction
    uvec4 info;        // x: SHADOW_RADIAL/SHADOW_PLANAR, y: views, z: first layer
};

layout(set = SHADOW_SET, binding = SHADOW_BINDING_LIGHTS, std140) uniform ShadowLightBlock {
    ShadowLight shadow_lights[MAX_LIGHTS];
};
// Define SHADOW_NO_MAP to get the views and their helpers without the map
// (passes that only project into the light's views, e.g. caustic splats).
#ifndef SHADOW_NO_MAP
layout(set = SHADOW_SET, binding = SHADOW_BINDING_MAP) uniform sampler2DArray shadow_map;
#endif

const float NORMAL_OFFSET_TEXELS = 1.0;
const float DEPTH_BIAS_TEXELS = 0.5;
const float SLOPE_BIAS = 1.5;
const float MAX_SLOPE = 10.0;

// tan of the angle between a receiver's normal and the light, from its
// cosine, clamped at MAX_SLOPE: the slope the biases scale with.
float shadow_slope_tan(float cos_t) {
    float c = clamp(cos_t, 1e-4, 1.0);
    return min(sqrt(max(1.0 - c * c, 0.0)) / c, MAX_SLOPE);
}

// The quantity a shadow texel stores, for world point x.
float shadow_receiver_depth(ShadowLight s, vec3 x) {
    vec3 d = x - s.origin.xyz;
    return s.info.x == SHADOW_PLANAR ? dot(d, s.direction.xyz) : length(d);
}

// Which of the light's views sees x: the cube face of the major axis
// (+x -x +y -y +z -z, the order of src/passes/shadow.rs CUBE_FACES).
uint shadow_view(ShadowLight s, vec3 x) {
    if (s.info.y == 1u) return 0u;
    vec3 v = x - s.origin.xyz;
    vec3 a = abs(v);
    if (a.x >= a.y && a.x >= a.z) return v.x >= 0.0 ? 0u : 1u;
    if (a.y >= a.z) return v.y >= 0.0 ? 2u : 3u;
    return v.z >= 0.0 ? 4u : 5u;
}

// World size of one shadow texel at x.
float shadow_texel_world(ShadowLight s, vec3 x) {
    return s.info.x == SHADOW_PLANAR ? s.origin.w : s.origin.w * length(x - s.origin.xyz);
}

#ifndef SHADOW_NO_MAP
// Fraction in [0, 1] of the (2 pcf + 1)^2 nearest-texel taps around x whose
// stored occluder is not nearer the light than x: 1 exactly where every tap
// is lit, 0 exactly where every tap is shadowed. n: unit normal on the lit
// side, to_light: unit direction toward the light. Points outside the
// light's maps (outside a spot's cone, outside the scene sphere) count as lit.
// `band`: the fraction of the taps counted lit only by the bias, their
// occluder nearer the light than x by less than it. The map cannot tell
// such an occluder (the water's surface just above a wall under it) from
// x's own surface; one ray can (glsl/direct/lighting.comp asks it).
float shadow_visibility_band(uint l, vec3 x, vec3 n, vec3 to_light, int pcf, out float band) {
    band = 0.0;
    ShadowLight s = shadow_lights[l];
    float tan_t = shadow_slope_tan(dot(n, to_light));
    float w = shadow_texel_world(s, x);
    vec3 xs = x + n * (NORMAL_OFFSET_TEXELS * w);
    uint view = shadow_view(s, xs);
    vec4 clip = s.view_proj[view] * vec4(xs, 1.0);
    if (clip.w <= 0.0) return 1.0;
    vec2 ndc = clip.xy / clip.w;
    if (any(greaterThan(abs(ndc), vec2(1.0)))) return 1.0;
    ivec2 size = textureSize(shadow_map, 0).xy;
    ivec2 centre = ivec2(floor((ndc * 0.5 + 0.5) * vec2(size)));
    int layer = int(s.info.z + view);
    float unbiased = shadow_receiver_depth(s, xs);
    float depth = unbiased - w * (DEPTH_BIAS_TEXELS + SLOPE_BIAS * float(pcf + 1) * tan_t);
    float lit = 0.0;
    float biased_lit = 0.0;
    for (int dy = -pcf; dy <= pcf; ++dy) {
        for (int dx = -pcf; dx <= pcf; ++dx) {
            ivec2 q = clamp(centre + ivec2(dx, dy), ivec2(0), size - 1);
            float stored = texelFetch(shadow_map, ivec3(q, layer), 0).r;
            lit += stored >= depth ? 1.0 : 0.0;
            biased_lit += stored >= depth && stored < unbiased ? 1.0 : 0.0;
        }
    }
    float taps = float((2 * pcf + 1) * (2 * pcf + 1));
    band = biased_lit / taps;
    return lit / taps;
}

float shadow_visibility(uint l, vec3 x, vec3 n, vec3 to_light, int pcf) {
    float band;
    return shadow_visibility_band(l, x, n, to_light, pcf, band);
}

#endif // SHADOW_NO_MAP

#endif
