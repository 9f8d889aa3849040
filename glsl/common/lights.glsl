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

// Irradiance at x from light l on a surface facing it (I / d^2 with the
// spot's falloff, or a directional light's E), ignoring visibility;
// `to_light` (unit) and `dist` describe the shadow ray. 0 at the light's
// own position: the 1 / d^2 singularity is integrable only across it (a
// medium sample there), not at it.
vec3 light_arriving(uint l, vec3 x, out vec3 to_light, out float dist) {
    Light light = lights[l];
    uint kind = floatBitsToUint(light.position.w);
    if (kind == LIGHT_DIRECTIONAL) {
        to_light = -light.direction.xyz;
        dist = 1e30;
        return light.intensity.rgb;
    }
    vec3 v = light.position.xyz - x;
    dist = length(v);
    to_light = v / max(dist, 1e-30);
    vec3 intensity = light.intensity.rgb;
    if (kind == LIGHT_SPOT) {
        intensity *= spot_falloff(dot(-to_light, light.direction.xyz), light.direction.w, light.intensity.w);
    }
    if (dist < 1e-6) return vec3(0.0);
    return intensity / (dist * dist);
}

// Narrows [t0, t1] on the ray o + t d to a superset of the part inside
// spot light l's cone (cos_outer = light.direction.w), where its falloff is
// non-zero; false when none is. Other lights, and spots 60 degrees wide or
// more, keep the interval. The cone's forward nappe is convex, so the ray
// meets it in one interval: between the roots of
//     ((v + t d) . a)^2 - cos^2 |v + t d|^2 = 0   (v = o - apex, a the axis)
// on the side (v + t d) . a >= 0. Rounding can only widen the interval
// (a margin is added), never cut it: an estimator sampling in it stays
// unbiased.
bool spot_cone_interval(uint l, vec3 o, vec3 d, inout float t0, inout float t1) {
    Light light = lights[l];
    float c = light.direction.w;
    if (floatBitsToUint(light.position.w) != LIGHT_SPOT || light.intensity.w > 1.5 || c < 0.5) return true;
    vec3 a = light.direction.xyz;
    vec3 v = o - light.position.xyz;
    float da = dot(d, a), va = dot(v, a), c2 = c * c;
    float A = da * da - c2;
    float B = 2.0 * (da * va - c2 * dot(d, v));
    float C = va * va - c2 * dot(v, v);
    float lo = -1e30, hi = 1e30;
    // The half-space in front of the apex.
    if (da > 0.0) lo = -va / da;
    else if (da < 0.0) hi = -va / da;
    else if (va < 0.0) return false;
    float disc = B * B - 4.0 * A * C;
    if (abs(A) > 1e-7) {
        if (disc < 0.0) {
            if (A < 0.0) return false; // f < 0 everywhere: outside the cone
        } else {
            float q = -0.5 * (B + (B >= 0.0 ? sqrt(disc) : -sqrt(disc)));
            float r1 = q / A, r2 = abs(q) > 0.0 ? C / q : r1;
            float ra = min(r1, r2), rb = max(r1, r2);
            if (A < 0.0) {
                lo = max(lo, ra);
                hi = min(hi, rb);
            } else if (da > 0.0) {
                lo = max(lo, rb); // the forward nappe: past the far root
            } else {
                hi = min(hi, ra); // before the near root
            }
        }
    }
    float margin = 1e-4 * (1.0 + abs(lo) + abs(hi));
    t0 = max(t0, lo - margin);
    t1 = min(t1, hi + margin);
    return t1 > t0;
}

// Irradiance at x from light l on a surface with normal n, ignoring
// visibility; `to_light` (unit) and `dist` describe the shadow ray.
vec3 light_irradiance(uint l, vec3 x, vec3 n, out vec3 to_light, out float dist) {
    return light_arriving(l, x, to_light, dist) * max(dot(n, to_light), 0.0);
}

#endif
