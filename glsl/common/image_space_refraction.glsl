// Two-sided image-space refraction (Wyman 2005; Wyman 2006, GPU Gems-style
// chapter "Interactive Refractions and Caustics Using Image-Space
// Techniques", Sect. "Approximate, Image-Space Refraction"), shared by the
// camera (glsl/passes/camera_refraction.comp) and the light
// (glsl/caustic_map/photons.comp, photon_mode 1): one code path, so the
// caustics and what the camera sees through the glass agree.
//
// The includer defines, before including this file,
//   bool back_face_normal(vec3 x, out vec3 n);
// which projects x into its view and returns the back-face normal texture's
// outward normal there, or false where the texel holds no back face.
#ifndef COMMON_IMAGE_SPACE_REFRACTION_GLSL
#define COMMON_IMAGE_SPACE_REFRACTION_GLSL

#include "optics.glsl"

// The second interface and the ray leaving it.
struct TwoSidedExit {
    vec3 p2;        // approximate exit point p1 + d~ T1
    vec3 dir;       // T2, the direction leaving the refractor
    float dist;     // d~, the path length inside (Beer-Lambert)
    float transmit; // 1 - F2 for a true refraction; 1 where a TIR remedy applied
    bool remedied;  // a TIR remedy replaced Snell at p2
};

// Follows the refracted ray through the refractor: v the unit incident
// direction, p1 the front interface, n1 its outward normal (facing v:
// dot(v, n1) < 0), ior the refractor's index (outside: 1), d_v the
// thickness along v (front to back-face texture), d_n the interpolated
// per-vertex d_N (<= 0: unknown), tir_remedy one of TIR_*, use_eq632
// whether a missing back-face normal is replaced by Eq. 6.3.2. Returns
// false when the ray cannot be followed (no refraction at p1, or no
// normal at p2 with Eq. 6.3.2 off): the caller drops the transmitted part.
bool two_sided_refraction(vec3 v, vec3 p1, vec3 n1, float ior, float d_v, float d_n,
                          uint tir_remedy, bool use_eq632, out TwoSidedExit e) {
    e = TwoSidedExit(p1, v, 0.0, 0.0, false);
    // Snell at the front interface: T1.
    vec3 t1;
    if (!refract_dir(v, n1, 1.0 / ior, t1)) return false;
    // Eq. 6.3.1: d~ = (theta_t / theta_i) d_V + (1 - theta_t / theta_i) d_N.
    // At normal incidence the ratio tends to sin(theta_t) / sin(theta_i) =
    // 1 / ior. With ior 1 it is 1 and d~ = d_V: exact. Without a
    // precomputed d_N, d~ = d_V (Wyman's own fallback).
    float theta_i = acos(clamp(-dot(v, n1), -1.0, 1.0));
    float theta_t = acos(clamp(-dot(t1, n1), -1.0, 1.0));
    float ratio = theta_i > 1e-4 ? theta_t / theta_i : 1.0 / ior;
    float d = d_n > 0.0 ? ratio * d_v + (1.0 - ratio) * d_n : d_v;
    e.dist = d;
    e.p2 = p1 + d * t1;
    // N2 from the back-face normal texture at p2's projection.
    vec3 n2;
    if (!back_face_normal(e.p2, n2)) {
        if (!use_eq632) return false;
        // d~ overshot past the back faces: the ray left through the side,
        // where the normal is perpendicular to the view. Eq. 6.3.2:
        // N2 = T1 - (V . T1) V. (T1 parallel to V: leave straight on.)
        n2 = t1 - dot(v, t1) * v;
        n2 = dot(n2, n2) > 1e-12 ? n2 : t1;
    }
    // Inside the glass the ray meets the back face from within: refract
    // about the normal facing it.
    vec3 n_in = -normalize(n2);
    if (dot(n_in, t1) > 0.0) n_in = -n_in;
    vec3 t2;
    if (refract_dir(t1, n_in, ior, t2)) {
        e.dir = t2;
        e.transmit = 1.0 - fresnel_dielectric(-dot(t1, n_in), ior);
        return true;
    }
    // Total internal reflection at p2 (for a convex refractor mostly an
    // artefact of d~): Wyman's three ad hoc remedies. All of the light
    // stays in the ray (transmit 1): TIR loses nothing, and the remedy
    // stands in for the unknown path that eventually leaves.
    e.remedied = true;
    e.transmit = 1.0;
    if (tir_remedy == TIR_SINGLE_REFRACTION) {
        e.dir = t1; // single refraction: T2 = T1
    } else if (tir_remedy == TIR_CLAMP_CRITICAL) {
        // Incident angle clamped to the critical angle: T2 leaves tangent
        // to the surface, perpendicular to its normal.
        vec3 tangent = t1 - dot(t1, n_in) * n_in;
        e.dir = dot(tangent, tangent) > 1e-12 ? normalize(tangent) : t1;
    } else {
        // Reflect at p2 and ignore further interactions with the refractor.
        e.dir = reflect(t1, n_in);
    }
    return true;
}

#endif
