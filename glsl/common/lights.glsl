// Light radiometry (GUIDE §2): point and spot lights emit intensity I (W/sr),
// directional lights deliver irradiance E (W/m^2) on a surface facing them.
// Requires scene.glsl.
#ifndef COMMON_LIGHTS_GLSL
#define COMMON_LIGHTS_GLSL

// Spot falloff: smoothstep in cos(theta) from the cone edge (cos_outer) to
// cos_inner; mirrors src/radiometry.rs spot_falloff.
// cos_inner > 1 marks the cosine profile of a rect light's stand-in
// (src/environment.rs stand_in_lights): max(cos theta, 0).
float spot_falloff(float cos_theta, float cos_outer, float cos_inner) {
    if (cos_inner > 1.5) return max(cos_theta, 0.0);
    if (cos_inner <= cos_outer) return cos_theta >= cos_outer ? 1.0 : 0.0;
    return smoothstep(cos_outer, cos_inner, cos_theta);
}

// Irradiance at x from light l on a surface with normal n, ignoring
// visibility; `to_light` (unit) and `dist` describe the shadow ray.
vec3 light_irradiance(uint l, vec3 x, vec3 n, out vec3 to_light, out float dist) {
    Light light = lights[l];
    uint kind = floatBitsToUint(light.position.w);
    if (kind == LIGHT_DIRECTIONAL) {
        to_light = -light.direction.xyz;
        dist = 1e30;
        return light.intensity.rgb * max(dot(n, to_light), 0.0);
    }
    vec3 v = light.position.xyz - x;
    dist = length(v);
    to_light = v / dist;
    vec3 intensity = light.intensity.rgb;
    if (kind == LIGHT_SPOT) {
        intensity *= spot_falloff(dot(-to_light, light.direction.xyz), light.direction.w, light.intensity.w);
    }
    return intensity * max(dot(n, to_light), 0.0) / (dist * dist);
}

#endif
