// Emitters seen along a ray, as radiance (W m^-2 sr^-1): what an environment
// map of the lights holds (Wand & Strasser 2003 Sect. 3.1: "represent the
// incoming light as an environment map"). Point and spot lights, which have
// no extent in the scene model, are drawn as spheres of a stated radius r
// with the radiance that gives their intensity, L = I / (pi r^2) (a sphere
// of radius r and radiance L has intensity pi r^2 L in every direction;
// spot: I times its cone profile toward the viewer); a directional light as
// a sun disc of angular radius alpha with L = E / (pi sin^2 alpha), so that a
// surface facing it receives exactly E (integral of L cos over the cap).
// Requires scene.glsl, lights.glsl, optics.glsl.
#ifndef COMMON_PUNCTUAL_EMITTERS_GLSL
#define COMMON_PUNCTUAL_EMITTERS_GLSL

#include "emitters.glsl"

// Radiance of light l seen from `origin` along unit `dir`, 0 where the ray
// misses it. `radius`: r of point and spot lights (m); `sun_cos`: cos alpha.
vec3 light_emitter_radiance(uint l, vec3 origin, vec3 dir, float radius, float sun_cos) {
    Light light = lights[l];
    uint kind = floatBitsToUint(light.position.w);
    if (kind == LIGHT_DIRECTIONAL) {
        if (dot(dir, -light.direction.xyz) < sun_cos) return vec3(0.0);
        float sin2 = max(1.0 - sun_cos * sun_cos, 1e-12);
        return light.intensity.rgb / (PI * sin2);
    }
    if (!ray_meets_sphere(origin, dir, light.position.xyz, radius)) return vec3(0.0);
    vec3 intensity = light.intensity.rgb;
    if (kind == LIGHT_SPOT) {
        vec3 to_origin = normalize(origin - light.position.xyz);
        intensity *= spot_falloff(dot(to_origin, light.direction.xyz), light.direction.w, light.intensity.w);
    }
    return intensity / (PI * radius * radius);
}

// Solid angle the emitter of light l subtends from `origin` (the sphere's
// cap 2 pi (1 - sqrt(1 - r^2/D^2)), the sun's 2 pi (1 - cos alpha)).
float light_emitter_solid_angle(uint l, vec3 origin, float radius, float sun_cos) {
    Light light = lights[l];
    if (floatBitsToUint(light.position.w) == LIGHT_DIRECTIONAL) return 2.0 * PI * (1.0 - sun_cos);
    return sphere_solid_angle(origin, light.position.xyz, radius);
}

#endif
