#version 460
// Direct light with shadows (technique `direct`), per G-buffer pixel:
// L = albedo / pi * sum_l E_l * V_l for diffuse surfaces, where E_l is the
// light's irradiance (glsl/common/lights.glsl: I cos / r^2 with the spot
// falloff, or E cos for directional light) and V_l the shadow-map visibility.
// Specular surfaces seen directly get 0: the ground truth follows specular
// chains, which later techniques add. The background is the environment
// (glsl/common/emitters.glsl) and an area light's front face its radiance:
// both the emitted component.
// In a participating medium (Hu et al. 2010 Sect. 5.3, Fig. 2 C) each
// light's irradiance is attenuated by the transmittance tau(s, x) from the
// light to x, and the surface radiance by tau(x, v) toward the eye, both
// from glsl/common/medium.glsl's deterministic estimate (exact for constant
// density, `medium_steps` midpoint steps otherwise); exactly 1 without one.
#include "scene.glsl"
#include "lights.glsl"
#include "optics.glsl"
#include "random.glsl"
#include "medium.glsl"
#include "emitters.glsl"
#include "bvh.glsl"
#include "traced_direct.glsl"
#include "sh.glsl"

#define SHADOW_SET 1
#define SHADOW_BINDING_LIGHTS DIRECT_BINDING_SHADOW_LIGHTS
#define SHADOW_BINDING_MAP DIRECT_BINDING_SHADOW_MAP
#include "shadow.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = DIRECT_BINDING_POSITION, rgba32f) uniform readonly image2D g_position;
layout(set = 1, binding = DIRECT_BINDING_NORMAL, rgba32f) uniform readonly image2D g_normal;
layout(set = 1, binding = DIRECT_BINDING_ALBEDO, rgba32f) uniform readonly image2D g_albedo;
layout(set = 1, binding = DIRECT_BINDING_RADIANCE, rgba32f) uniform writeonly image2D radiance;
layout(push_constant) uniform Push {
    uint light_count; // lights with shadow maps (<= MAX_LIGHTS)
    int pcf_radius;   // PCF window half-width in texels
    uint medium_steps; // midpoint steps of inhomogeneous transmittance
    uint sky_rays;     // rays of the environment's visibility (0: unoccluded)
} pc;

// A_l L_lm of the environment's table (environment_sh.comp).
layout(set = 1, binding = DIRECT_BINDING_ENVIRONMENT_SH, std430) readonly buffer ShBlock { vec4 sh[9]; };

// The fraction of the environment's table that x (normal n) sees, weighted
// as its irradiance weighs it: over K = sky_rays cosine-weighted directions
// w_k, V = sum_k l_k v_k / sum_k l_k, with l_k the luminance of the table
// along w_k (an image's sun texels excluded: the sun has its own shadow
// ray) and v_k = 1 where a BVH ray from x along w_k escapes. The
// directions are a stratified (Hammersley-like: k + 1/2 over K in one
// dimension, a golden-ratio sequence in the other) set, rotated per pixel
// by a random offset (Cranley-Patterson), so the noise is a fixed pattern,
// not flicker, in motion; each frame of a still view (frame.components.z,
// passes/accumulate.comp) draws new offsets, which the accumulation
// averages. The cosine-weighted estimate of E = int L v cos dw is
// pi/K sum_k L_k v_k; dividing by the same estimate without v leaves the
// occluded fraction, which scales the noise-free SH irradiance. Exact
// unoccluded (V = 1) and for a sky of constant radiance as K grows; 1
// without rays or for a black table.
float sky_visibility(vec3 x, vec3 n, ivec2 p) {
    if (pc.sky_rays == 0u) return 1.0;
    uint rng = rng_seed(uint(p.y) * 65536u + uint(p.x), 0x5bd1e995u ^ (frame.components.z * 0x9e3779b9u));
    vec2 shift = vec2(rng_next(rng), rng_next(rng));
    vec3 o = shadow_origin(x, n);
    float seen = 0.0, total = 0.0;
    for (uint k = 0u; k < pc.sky_rays; ++k) {
        vec2 u = fract(vec2((float(k) + 0.5) / float(pc.sky_rays), float(k) * 0.6180339887) + shift);
        vec3 w = cosine_hemisphere(u, n);
        vec3 l = environment_table_radiance(w);
        if (environment_image_sun_texel(w, l)) continue;
        float weight = luminance(l);
        total += weight;
        if (weight > 0.0 && !trace_any(o, w, 0.0, 1e30)) seen += weight;
    }
    return total > 0.0 ? seen / total : 1.0;
}

// Irradiance at x (normal n, facing the camera) from the environment and the
// area lights (docs/ARCHITECTURE.md, "Environment and area lights in
// direct"): the environment's table by its order-2 spherical-harmonic
// irradiance times its visibility (sky_visibility); the environment's sun
// and each area light by BVH shadow rays (glsl/common/traced_direct.glsl).
vec3 extended_irradiance(vec3 x, vec3 n, ivec2 p) {
    vec3 e = vec3(0.0);
    if (environment_present()) {
        float y[9];
        sh_basis(n, y);
        vec3 sky = vec3(0.0);
        for (int k = 0; k < 9; ++k) sky += sh[k].rgb * y[k];
        e += max(sky, vec3(0.0)) * sky_visibility(x, n, p);
    }
    return e + sun_and_area_irradiance(x, n, pc.medium_steps);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    vec4 position = imageLoad(g_position, p);
    if (position.w == 0.0) {
        // The background: the environment along the pixel centre's ray
        // (through the medium's bounds), the emitted component.
        vec2 ndc = (vec2(p) + 0.5) / frame.viewport.xy * 2.0 - 1.0;
        vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
        vec3 dir = normalize(far.xyz / far.w - frame.eye.xyz);
        vec3 background = environment_radiance(dir);
        if (environment_present()) {
            float travel = 2.0 * frame.scene_sphere.w + length(frame.eye.xyz - frame.scene_sphere.xyz);
            background *= medium_transmittance_steps(frame.eye.xyz, dir, travel, pc.medium_steps);
        }
        imageStore(radiance, p, vec4(component_weight(COMPONENT_EMITTED) * background, 0.0));
        return;
    }
    vec4 nm = imageLoad(g_normal, p);
    uint material = uint(nm.w + 0.5);
    if (material_kind(material) != MATERIAL_DIFFUSE) {
        imageStore(radiance, p, vec4(0.0, 0.0, 0.0, 1.0));
        return;
    }
    vec3 x = position.xyz;
    vec3 n = normalize(nm.xyz);
    vec3 e_sum = vec3(0.0);
    for (uint l = 0u; l < pc.light_count; ++l) {
        vec3 to_light;
        float dist;
        vec3 e = light_irradiance(l, x, n, to_light, dist);
        if (all(equal(e, vec3(0.0)))) continue;
        // The taps lit only by the bias ask one ray toward the light: the
        // map's bias would light a band under an occluder just above x
        // (the waterline on the columns under the water).
        float band;
        float v = shadow_visibility_band(l, x, n, to_light, pc.pcf_radius, band);
        if (band > 0.0 && trace_any(shadow_origin(x, n), to_light, 0.0, dist)) v -= band;
        if (v == 0.0) continue;
        e_sum += e * v * medium_transmittance_steps(x, to_light, light_travel(dist, x), pc.medium_steps);
    }
    e_sum += extended_irradiance(x, n, p);
    vec4 albedo = imageLoad(g_albedo, p);
    // An area light's front face (albedo.a: the camera sees the front).
    vec3 emission = albedo.a > 0.5 ? materials[material].emission.rgb : vec3(0.0);
    vec3 to_eye = frame.eye.xyz - x;
    float eye_dist = length(to_eye);
    vec3 tau_eye = medium_transmittance_steps(x, to_eye / eye_dist, eye_dist, pc.medium_steps);
    vec3 l = component_weight(COMPONENT_DIRECT) * albedo.rgb / PI * e_sum
        + component_weight(COMPONENT_EMITTED) * emission;
    imageStore(radiance, p, vec4(l * tau_eye, 1.0));
}
