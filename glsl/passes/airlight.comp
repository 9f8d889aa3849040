#version 460
// Airlight with volumetric shadows (Hu et al. 2010 Fig. 2 A): single
// scattering of light that reaches the medium straight from the lights,
// ray-marched along each pixel's camera ray, ADDED to the frame's radiance.
//
// Hu's Eq. 1, L(v, w) = integral over the ray of tau(v, x) sigma_s(x)
// integral p(x, w, w') L_in(x, w') dw' dx, with a point or spot light of
// intensity I (a delta in w') collapses the inner integral to
//   p(theta) I(w_l) / r^2 * tau(s, x) * V(s, x),
// (a directional light: p(theta) E tau V), so Eq. 2's discretisation is
//   L_A = sum_i tau(v, x_i) sigma_s(x_i) sum_l p(theta_il) I_l / r_il^2
//         tau(s_l, x_i) V_l(x_i) dt,
// the same radiance as the reference's L V component (glsl/reference/
// trace.comp: photons straight from the light, scattered once, connected to
// the eye). Conventions:
// - the ray ends at the first surface of ANY kind along the pixel centre's
//   ray, found with one closest-hit ray through the BVH: the reference's
//   camera connection of a medium event is blocked by every surface, glass
//   included (the light scattered behind glass reaches the eye refracted:
//   that is no L V path), and a technique's G-buffer may leave the glass out;
// - the march covers the part of that ray inside the medium bounds
//   (elsewhere the density is 0) in `steps` equal strata, one sample per
//   stratum at the offset u (a per-pixel, per-frame hash when jittered,
//   otherwise 0.5: the midpoint rule);
// - tau(v, x_i) accumulates the optical depth of the strata before x_i plus
//   u dt of its own (exact for constant density);
// - tau(s, x) by medium.glsl's deterministic transmittance (exact for
//   constant density, `medium_steps` midpoint steps otherwise);
// - V from the shadow maps, which hold every caster, glass included: light
//   that crossed a specular surface belongs to the volume caustics (B);
//   the lights after the shadow-mapped ones (the point stand-ins of rect
//   lights, a spot at the rect's centre with the cosine profile
//   I = L A max(cos theta, 0), and of the environment's sun: src/environment.rs
//   stand_in_lights) have no shadow map: V is one BVH shadow ray to the
//   stand-in (every surface blocks it, glass included, as the maps do);
// - HG phase (medium.glsl) with cos(theta) between the propagation
//   directions: from the light to x, and from x to the eye.
// With `scattered_count` virtual lights (src/passes/scattered_lights.rs:
// where the light scatters once, power Phi_v, emitting Phi_v p(w_v . w')),
// the approximate multiple scattering, weighted by the `other` component:
// - L V V E, the same discretisation of Hu's Eq. 1 with the virtual lights
//   as its sources, over MS_STEPS strata (the field is smooth): at x,
//   sum_v Phi_v p(w_v . w) / max(d^2, r_v^2) exp(-sigma_t d) p(w . -dir),
//   w = (x - p_v) / d, unshadowed (objects inside the box, glass included,
//   neither block nor bend it: the approximation);
// - L V D E at the camera ray's first surface, if diffuse:
//   albedo / pi sum_v Phi_v p(w_v . w) cos / max(d^2, r_v^2) tau, times
//   the visible fraction from MS_SHADOW_RAYS BVH shadow rays (below) and
//   tau(eye, x).
#include "scene.glsl"
#include "optics.glsl"
#include "random.glsl"
#include "lights.glsl"
#include "medium.glsl"
#include "bvh.glsl"
#include "emitters.glsl"
#include "traced_direct.glsl"

#define SHADOW_SET 1
#define SHADOW_BINDING_LIGHTS AIRLIGHT_BINDING_SHADOW_LIGHTS
#define SHADOW_BINDING_MAP AIRLIGHT_BINDING_SHADOW_MAP
#include "shadow.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = AIRLIGHT_BINDING_RADIANCE, rgba32f) uniform image2D radiance;

layout(push_constant) uniform Push {
    uint light_count;  // lights with shadow maps (<= MAX_LIGHTS)
    uint lit_count;    // all lights in the buffer: then the stand-ins, shadowed by BVH rays
    uint steps;        // strata along the camera ray inside the medium
    uint medium_steps; // midpoint steps of inhomogeneous light-side transmittance
    uint jitter;       // 1: per-pixel random stratum offset; 0: midpoints
    uint scattered_count; // virtual lights of the multiple scattering (0: none)
} pc;

struct ScatteredLight {
    vec4 position;  // xyz; w: clamp radius r_v
    vec4 power;     // rgb Phi_v (W)
    vec4 direction; // xyz: propagation before it scattered
};
layout(set = 1, binding = AIRLIGHT_BINDING_SCATTERED_LIGHTS, std430) readonly buffer ScatteredBlock {
    ScatteredLight scattered[];
};

// Strata of the multiple scattering's march (a smooth field: fewer than
// the airlight's, which resolves shadow edges).
const uint MS_STEPS = 8u;

// Radiant intensity (W/sr) of virtual light v toward the unit direction w,
// over max(d^2, r_v^2): the clamp of instant radiosity.
vec3 scattered_intensity(uint v, vec3 w, float d2, float g) {
    float r = scattered[v].position.w;
    return scattered[v].power.rgb * hg_phase(dot(scattered[v].direction.xyz, w), g) / max(d2, r * r);
}

// L V V E along the camera ray's part [t0, t1] in the medium (constant
// density: the scattered lights need one), radiance toward the eye.
vec3 multiple_scattering_medium(vec3 eye, vec3 dir, float t0, float t1, float u) {
    vec3 sigma_t = (medium.sigma_s.rgb + medium.sigma_a.rgb) * medium.bounds_min.w;
    vec3 sigma_s = medium.sigma_s.rgb * medium.bounds_min.w;
    float g = medium.sigma_s.w;
    float dt = (t1 - t0) / float(MS_STEPS);
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < MS_STEPS; ++i) {
        float t = t0 + (float(i) + u) * dt;
        vec3 x = eye + t * dir;
        vec3 in_scatter = vec3(0.0);
        for (uint v = 0u; v < pc.scattered_count; ++v) {
            vec3 to = x - scattered[v].position.xyz;
            float d2 = max(dot(to, to), 1e-12);
            float d = sqrt(d2);
            vec3 w = to / d;
            in_scatter += scattered_intensity(v, w, d2, g) * exp(-sigma_t * d) * hg_phase(dot(w, -dir), g);
        }
        sum += exp(-sigma_t * (t - t0)) * sigma_s * in_scatter;
    }
    return sum * dt;
}

// Shadow rays per pixel of the surface term (below).
const uint MS_SHADOW_RAYS = 16u;

// The unoccluded contribution of virtual light v at x (normal n), before
// albedo / pi: irradiance, exact for a constant density.
vec3 scattered_irradiance(uint v, vec3 x, vec3 n, float g) {
    vec3 to = scattered[v].position.xyz - x;
    float d2 = max(dot(to, to), 1e-12);
    float d = sqrt(d2);
    vec3 l = to / d;
    float cos_s = dot(n, l);
    if (cos_s <= 0.0) return vec3(0.0);
    return scattered_intensity(v, -l, d2, g) * cos_s * medium_transmittance_steps(x, l, d, 1u);
}

// L V D E at the diffuse point x (normal n, facing the eye), before the
// view leg's transmittance. The sum over every virtual light is taken
// unoccluded, then scaled by the fraction of it that the shadow rays of
// MS_SHADOW_RAYS of them see, weighted by their contributions c_k:
// V = sum_k c_k v_k / sum_k c_k, the lights every (N / K)-th from a
// per-pixel random offset u (the ratio estimate of the sky's visibility
// in glsl/direct/lighting.comp: exact unoccluded, a fixed pattern in
// motion, averaged by the still frames' accumulation).
vec3 multiple_scattering_surface(vec3 x, vec3 n, vec3 albedo, float u) {
    float g = medium.sigma_s.w;
    vec3 e = vec3(0.0);
    for (uint v = 0u; v < pc.scattered_count; ++v) e += scattered_irradiance(v, x, n, g);
    if (all(equal(e, vec3(0.0)))) return vec3(0.0);
    vec3 origin = shadow_origin(x, n);
    float seen = 0.0, all_of = 0.0;
    uint k_count = min(MS_SHADOW_RAYS, pc.scattered_count);
    for (uint k = 0u; k < k_count; ++k) {
        uint v = min(uint((float(k) + u) * float(pc.scattered_count) / float(k_count)), pc.scattered_count - 1u);
        float c = dot(scattered_irradiance(v, x, n, g), vec3(1.0));
        if (c <= 0.0) continue;
        vec3 to = scattered[v].position.xyz - x;
        float d = length(to);
        all_of += c;
        if (!trace_any(origin, to / d, 0.0, d)) seen += c;
    }
    float visible = all_of > 0.0 ? seen / all_of : 1.0;
    return albedo / PI * e * visible;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    float weight = component_weight(COMPONENT_AIRLIGHT);
    float ms_weight = pc.scattered_count > 0u ? component_weight(COMPONENT_OTHER) : 0.0;
    if ((weight == 0.0 && ms_weight == 0.0) || !medium_present()) return;

    vec3 eye = frame.eye.xyz;
    vec2 ndc = (vec2(p) + 0.5) / frame.viewport.xy * 2.0 - 1.0;
    vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    vec3 dir = normalize(far.xyz / far.w - eye);
    Hit hit;
    bool surface = trace_closest(eye, dir, 0.0, 1e30, hit);
    float t_hit = surface ? hit.t : 1e30;
    uint rng = rng_seed(uint(p.y) * uint(frame.viewport.x) + uint(p.x), frame.counts.w ^ 0x3c6ef372u);
    float u = pc.jitter != 0u ? rng_next(rng) : 0.5;
    float u_shadow = pc.jitter != 0u ? rng_next(rng) : 0.5;
    vec3 ms = vec3(0.0);
    if (ms_weight > 0.0 && surface && material_kind(hit_material(hit)) == MATERIAL_DIFFUSE) {
        vec3 x = hit_position(hit, eye, dir);
        vec3 n = hit_geometric_normal(hit);
        n = dot(n, dir) > 0.0 ? -n : n;
        ms += multiple_scattering_surface(x, n, hit_albedo(hit), u_shadow)
            * medium_transmittance_steps(eye, dir, t_hit, 1u);
    }
    float t1 = t_hit;
    float t0 = 0.0;
    if (!clip_to_medium(eye, dir, t0, t1)) {
        if (ms_weight > 0.0) {
            vec4 prev = imageLoad(radiance, p);
            imageStore(radiance, p, vec4(prev.rgb + ms_weight * ms, prev.a));
        }
        return;
    }
    if (ms_weight > 0.0) ms += multiple_scattering_medium(eye, dir, t0, t1, u);

    // No single-scattering strata when only `other` is drawn.
    uint n = weight > 0.0 ? max(pc.steps, 1u) : 0u;
    float dt = (t1 - t0) / float(max(n, 1u));
    vec3 sigma_s = medium.sigma_s.rgb;
    vec3 sigma_t = medium.sigma_s.rgb + medium.sigma_a.rgb;
    float g = medium.sigma_s.w;
    vec3 depth = vec3(0.0); // optical depth from the eye to the current stratum's start
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < n; ++i) {
        vec3 x = eye + (t0 + (float(i) + u) * dt) * dir;
        float density = medium_density(x);
        vec3 tau_eye = exp(-(depth + sigma_t * (density * u * dt)));
        depth += sigma_t * (density * dt);
        if (density <= 0.0) continue;
        vec3 in_scatter = vec3(0.0);
        for (uint l = 0u; l < pc.lit_count; ++l) {
            // What arrives without medium or occluders, and the
            // propagation direction (light -> x) for the phase.
            vec3 to_light;
            float dist;
            vec3 li = light_arriving(l, x, to_light, dist);
            if (all(equal(li, vec3(0.0)))) continue;
            vec3 dir_in = -to_light;
            // A point in the medium has no surface: the lookup is offset
            // toward the light, with no slope (n = to_light).
            float v = l < pc.light_count ? shadow_visibility(l, x, to_light, to_light, 0)
                                         : (trace_any(x, to_light, 0.0, dist) ? 0.0 : 1.0);
            if (v == 0.0) continue;
            vec3 tau_light = medium_transmittance_steps(x, to_light, light_travel(dist, x), pc.medium_steps);
            in_scatter += li * v * tau_light * hg_phase(dot(dir_in, -dir), g);
        }
        sum += tau_eye * sigma_s * density * in_scatter;
    }
    vec4 prev = imageLoad(radiance, p);
    imageStore(radiance, p, vec4(prev.rgb + weight * sum * dt + ms_weight * ms, prev.a));
}
