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
#include "scene.glsl"
#include "optics.glsl"
#include "random.glsl"
#include "lights.glsl"
#include "medium.glsl"
#include "bvh.glsl"

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
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    float weight = component_weight(COMPONENT_AIRLIGHT);
    if (weight == 0.0 || !medium_present()) return;

    vec3 eye = frame.eye.xyz;
    vec2 ndc = (vec2(p) + 0.5) / frame.viewport.xy * 2.0 - 1.0;
    vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    vec3 dir = normalize(far.xyz / far.w - eye);
    Hit hit;
    float t1 = trace_closest(eye, dir, 0.0, 1e30, hit) ? hit.t : 1e30;
    float t0 = 0.0;
    if (!clip_to_medium(eye, dir, t0, t1)) return;

    uint n = max(pc.steps, 1u);
    float dt = (t1 - t0) / float(n);
    uint rng = rng_seed(uint(p.y) * uint(frame.viewport.x) + uint(p.x), frame.counts.w ^ 0x3c6ef372u);
    float u = pc.jitter != 0u ? rng_next(rng) : 0.5;
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
    imageStore(radiance, p, vec4(prev.rgb + weight * sum * dt, prev.a));
}
