// Two-sided refraction exactly through the BVH: the exact second interface
// that Wyman's image-space exit (image_space_refraction.glsl) and Liktor's
// distance impostor approximate. Shared by beams' light side
// (glsl/beams/refine.comp, `refraction` 1) and the camera's view through
// glass (glsl/passes/camera_refraction.comp, `camera_exit` 0), so light
// and eye follow the same paths.
//
// Snell into the glass at p, then the ray inside to the next surface,
// refracted out, or reflected where it meets total internal reflection (up
// to 8 times); Beer-Lambert over the path inside. The partial Fresnel
// reflections inside are not followed (their light is lost, as with the
// image-space exit): `factor` holds the exit's 1 - F2 and the absorption,
// not the entry's 1 - F1. False where the ray does not leave.
// The includer includes bvh.glsl and optics.glsl first.
#ifndef COMMON_TRACED_REFRACTION_GLSL
#define COMMON_TRACED_REFRACTION_GLSL

bool traced_refraction(vec3 d, vec3 p, vec3 n, float ior, vec3 absorption,
                       out vec3 exit_p, out vec3 exit_d, out vec3 factor) {
    exit_p = p;
    exit_d = d;
    factor = vec3(1.0);
    vec3 dir;
    if (!refract_dir(d, n, 1.0 / ior, dir)) return false;
    vec3 x = p;
    for (int i = 0; i < 8; ++i) {
        float eps = 1e-4 * max(1.0, bvh_max_abs(x));
        vec3 o = x + dir * eps;
        Hit h;
        if (!trace_closest(o, dir, 0.0, 1e30, h)) return false;
        x = hit_position(h, o, dir);
        factor *= exp(-absorption * (h.t + eps));
        vec3 nn = hit_normal(h);
        if (dot(nn, dir) > 0.0) nn = -nn;
        vec3 out_dir;
        if (refract_dir(dir, nn, ior, out_dir)) {
            factor *= 1.0 - fresnel_dielectric(-dot(dir, nn), ior);
            exit_p = x;
            exit_d = out_dir;
            return true;
        }
        dir = reflect(dir, nn);
    }
    return false;
}

#endif
