#version 460
// Splatting (Kougianos & Moustakas 2021 §3.2, Eqs. 16-20): one instanced
// quad per photon (vkCmdDrawIndirect, instanceCount written by trace.comp),
// the 4 corners lp of Eq. 17 as a triangle strip, on the hit's tangent
// plane, x = x'_{0:0} + a U + b V for (a, b) ∈ [−1, 1]².
// - WP_SPLAT_DIFFERENTIAL: U = ∂x'/∂u / 2, V = ∂x'/∂v / 2, the photon
//   differential's footprint itself: the parallelogram its texel maps to
//   (anisotropic, sheared as the beam is), centred on the hit.
// - WP_SPLAT_PAPER: Eq. 18's rectangle, U = q a lp_F / 2,
//   V = q lp_R / 2, q by Eq. 16 (texel pitch r/ccm_0 rather than
//   r/(ccm_0 − 1), so q_0 = 1 tiles a flat surface) with σ of Eq. 11, a by Eq. 19.
// - WP_SPLAT_FIXED: the same rectangle with σ = s^c (no differentials):
//   every photon of a cascade the same size.
// The kernel is the box of Eq. 20 (the paper's shaded quad, the mean
// I = R / (a q²)) convolved with a narrow tent of half-width h = 1/4 of a
// cascade-0 texel in the light's texel lattice: in the quad's coordinates
// (a, b) ∈ [−1, 1]² of the box, a trapezoid flat on |a| ≤ 1 − r, falling
// to 0 at |a| = 1 + r, r = h / B for a box of half-width B texels of
// cascade 0 (B = s^c / 2 for the differential's footprint). Its integral
// is the box's, 4 |U × V|, so
//   E(x) = Φ w(a) w(b) / (4 |U × V|)
// deposits exactly the photon's flux Φ. Why: the footprints of one cascade
// tile the receiver (flat water), and so do those of two cascades across
// their seam, because cascade c's ring lines up with cascade c − 1's
// border (Eq. 6 integral, src/cascades.rs); the sum of boxes is then 1
// everywhere and, the tent having the same width in the lattice for every
// cascade, so is the sum of the convolved boxes, seams included (a tent of
// one texel's width sums to one only within one lattice: ±25% bands at the
// seams for s = 2). The ramp also keeps the sum exact where a quad's edge
// passes through a pixel centre, which a bare box (weight 1 up to the
// edge) would count twice or not at all. The quad is moved toward the
// camera by a small fraction of its distance (the paper's depth bias) and
// tested against the camera's depth; the fragment stage keeps it only on
// the side of the surface the photon arrived at (splat.frag).
#include "scene.glsl"
#include "optics.glsl"
#include "common.glsl"
#include "kernel.glsl"

layout(set = 1, binding = WP_BINDING_PHOTONS, std430) readonly buffer PhotonBlock { Photon photons[]; };

layout(location = 0) out vec2 v_local;
layout(location = 1) flat out vec3 v_irradiance;
layout(location = 2) flat out float v_ramp;
layout(location = 3) flat out vec3 v_normal;

const vec2 LP[4] = vec2[4](vec2(-1.0, 1.0), vec2(1.0, 1.0), vec2(-1.0, -1.0), vec2(1.0, -1.0)); // Eq. 17

void main() {
    Photon p = photons[gl_InstanceIndex];
    vec3 hit = p.position.xyz;
    vec3 n = p.normal.xyz;
    vec3 u, v;
    float r;
    splat_axes(p, u, v, r);
    float area = 4.0 * length(cross(u, v));
    vec2 lp = LP[gl_VertexIndex] * (1.0 + r);
    vec3 x = hit + lp.x * u + lp.y * v;
    x += (frame.eye.xyz - x) * wp.paper.w;
    v_local = lp;
    v_ramp = r;
    v_normal = n;
    v_irradiance = area > 0.0 ? p.flux.rgb / area : vec3(0.0);
    gl_Position = frame.view_proj * vec4(x, 1.0);
}
