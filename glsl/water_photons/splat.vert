#version 460
// Splatting (Kougianos & Moustakas 2021 §3.2, Eqs. 16-20): one instanced
// quad per photon (vkCmdDrawIndirect, instanceCount written by trace.comp),
// the 4 corners lp of Eq. 17 as a triangle strip, on the hit's tangent
// plane, x = x'_{0:0} + a U + b V for (a, b) ∈ [−1, 1]².
// - WP_SPLAT_DIFFERENTIAL: U = ∂x'/∂u, V = ∂x'/∂v, the photon differential's
//   footprint itself (anisotropic, sheared as the beam is).
// - WP_SPLAT_PAPER: Eq. 18's rectangle, U = q a lp_F / 2,
//   V = q lp_R / 2, q by Eq. 16 (texel pitch r/ccm_0 rather than
//   r/(ccm_0 − 1), so q_0 = 2 tiles a flat surface) with σ of Eq. 11, a by Eq. 19.
// - WP_SPLAT_FIXED: the same rectangle with σ = s^c (no differentials):
//   every photon of a cascade the same size.
// The fragment stage weighs with the tent (1 − |a|)(1 − |b|), whose
// integral over the quad is |U × V|, so the irradiance
//   E(x) = Φ (1 − |a|)(1 − |b|) / |U × V|
// deposits exactly the photon's flux Φ (Eq. 20's I = R / (a q²) is the
// quad's mean, |U × V| = a q² / 4). The quad is moved toward the camera by
// a small fraction of its distance (the paper's depth bias) and tested
// against the camera's depth.
#include "scene.glsl"
#include "optics.glsl"
#include "common.glsl"

layout(set = 1, binding = WP_BINDING_PHOTONS, std430) readonly buffer PhotonBlock { Photon photons[]; };

layout(location = 0) out vec2 v_local;
layout(location = 1) flat out vec3 v_irradiance;

const vec2 LP[4] = vec2[4](vec2(-1.0, 1.0), vec2(1.0, 1.0), vec2(-1.0, -1.0), vec2(1.0, -1.0)); // Eq. 17

void main() {
    Photon p = photons[gl_InstanceIndex];
    vec3 hit = p.position.xyz;
    vec3 n = p.normal.xyz;
    vec3 u, v;
    if (wp.modes.w == WP_SPLAT_DIFFERENTIAL) {
        u = p.axis_u.xyz;
        v = p.axis_v.xyz;
    } else {
        float c = p.position.w;
        float sigma = (wp.modes.w == WP_SPLAT_FIXED ? 1.0 : p.normal.w) * pow(wp.cascade.x, c); // Eq. 11
        float grid = sqrt(wp.range.x / float(wp.size.x) * wp.range.y / float(wp.size.y));
        float q = grid * wp.cascade.y * sigma; // Eq. 16
        vec3 w = p.dir.xyz;
        float a = 1.0 / (max(-dot(w, n), 0.0) + wp.paper.z); // Eq. 19
        vec3 lp_f = w - dot(w, n) * n;
        vec3 lp_r;
        if (dot(lp_f, lp_f) < 1e-12) {
            basis(n, lp_f, lp_r);
        } else {
            lp_f = normalize(lp_f);
            lp_r = cross(n, lp_f);
        }
        u = 0.5 * q * a * lp_f; // Eq. 18
        v = 0.5 * q * lp_r;
    }
    float area = length(cross(u, v));
    vec2 lp = LP[gl_VertexIndex];
    vec3 x = hit + lp.x * u + lp.y * v;
    x += (frame.eye.xyz - x) * wp.paper.w;
    v_local = lp;
    v_irradiance = area > 0.0 ? p.flux.rgb / area : vec3(0.0);
    gl_Position = frame.view_proj * vec4(x, 1.0);
}
