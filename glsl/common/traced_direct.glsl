// Direct light at a diffuse point by BVH shadow rays, for the lights that
// need no shadow map: each area light (its exact unoccluded irradiance,
// glsl/common/emitters.glsl, times one shadow ray toward its centre) and
// the environment's sun (a sky's, or the one found in an image: one shadow
// ray toward its centre), each attenuated by the medium along its leg
// (`medium_steps` midpoint steps; exact for constant density). Shared by
// `direct`'s lighting and `image_space`'s traced fallback.
// Requires scene.glsl, bvh.glsl, emitters.glsl, medium.glsl.
#ifndef COMMON_TRACED_DIRECT_GLSL
#define COMMON_TRACED_DIRECT_GLSL

// Offsets a shadow ray's origin off the surface along n, scaled with |x| to
// survive float rounding.
vec3 shadow_origin(vec3 x, vec3 n) {
    return x + n * (1e-4 * (1.0 + max(abs(x.x), max(abs(x.y), abs(x.z)))));
}

// Irradiance at x (normal n) from the environment's sun and the area lights.
vec3 sun_and_area_irradiance(vec3 x, vec3 n, uint medium_steps) {
    vec3 e = vec3(0.0);
    if (environment_present()) {
        vec3 to_sun;
        vec3 sun = environment_sun_irradiance(to_sun);
        float cos_sun = dot(n, to_sun);
        if (cos_sun > 0.0 && any(greaterThan(sun, vec3(0.0)))
                && !trace_any(shadow_origin(x, n), to_sun, 0.0, 1e30)) {
            e += sun * cos_sun * medium_transmittance_steps(x, to_sun, light_travel(1e30, x), medium_steps);
        }
    }
    for (uint i = 0u; i < frame.components.y; ++i) {
        vec3 to_light;
        float reach;
        vec3 ei = emitter_irradiance(i, x, n, to_light, reach);
        if (all(equal(ei, vec3(0.0)))) continue;
        if (trace_any(shadow_origin(x, n), to_light, 0.0, reach)) continue;
        e += ei * medium_transmittance_steps(x, to_light, reach, medium_steps);
    }
    return e;
}

#endif
