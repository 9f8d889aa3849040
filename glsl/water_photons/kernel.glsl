// The photon splat's footprint and kernel (Kougianos & Moustakas 2021
// Eqs. 16-20, see splat.vert for the derivation), shared by the splat
// (screen-space scatter) and the water view's gather at receivers the
// camera sees only through the water (view.comp), so both deposit the
// same irradiance. splat_axes requires optics.glsl (basis) and common.glsl
// (wp, Photon); WATER_PHOTONS_KERNEL_WEIGHT_ONLY leaves it out.
#ifndef WATER_PHOTONS_KERNEL_GLSL
#define WATER_PHOTONS_KERNEL_GLSL

// The box of Eq. 20 convolved with the tent: 1 on |a| <= 1 - r, 0 at
// |a| = 1 + r, linear between (integral 2 per axis).
float splat_weight(vec2 local, float r) {
    vec2 k = clamp((1.0 + r - abs(local)) / (2.0 * r), 0.0, 1.0);
    return k.x * k.y;
}

#ifndef WATER_PHOTONS_KERNEL_WEIGHT_ONLY
// h: the kernel's ramp half-width in cascade-0 texels (splat.vert).
const float RAMP_TEXELS = 0.25;

// The splat mode (WP_SPLAT_*, also wp.modes.w), fixed when the pipeline is
// created (WP_SPEC_SPLAT_MODE): read from the uniform block, it makes
// lavapipe recompile view.comp at every bind (water_photons/bindings.rs).
layout(constant_id = WP_SPEC_SPLAT_MODE) const uint SPLAT_MODE = WP_SPLAT_DIFFERENTIAL;

// The quad x = hit + a U + b V, (a, b) in [-1, 1]^2, of photon p, and
// r, the ramp half-width in units of the box's half-width (at most 1).
void splat_axes(Photon p, out vec3 u, out vec3 v, out float r) {
    vec3 n = p.normal.xyz;
    // The box's half-width B in cascade-0 texels.
    float half_texels;
    if (SPLAT_MODE == WP_SPLAT_DIFFERENTIAL) {
        u = 0.5 * p.axis_u.xyz;
        v = 0.5 * p.axis_v.xyz;
        half_texels = 0.5 * pow(wp.cascade.x, p.position.w);
    } else {
        float c = p.position.w;
        float sigma = (SPLAT_MODE == WP_SPLAT_FIXED ? 1.0 : p.normal.w) * pow(wp.cascade.x, c); // Eq. 11
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
        half_texels = 0.5 * wp.cascade.y * sigma;
    }
    // At most 1: the flat top keeps the trapezoid's integral the box's.
    r = min(RAMP_TEXELS / half_texels, 1.0);
}
#endif

#endif
