// The Gerstner wave sum of water surfaces (GPU Gems 1 ch. 1 Eq. 9), the
// same operations in the same order as Water::surface_point in
// src/scene/water.rs (see its docs for the formula):
//   P(x0, t) = (x + Σ Q A D.x cos θ, base + Σ A sin θ, z + Σ Q A D.z cos θ),
//   θ = k D·x0 − ω t + φ,
// normal = normalize(∂P/∂z × ∂P/∂x), from the analytic derivatives.
#ifndef WATER_GLSL
#define WATER_GLSL

// One wave: GpuWave in src/gpu.rs.
struct Wave {
    vec4 direction_k_omega;          // xy: unit travel direction D as (x, z); z: k = 2π/λ; w: ω = k·speed
    vec4 amplitude_steepness_phase;  // x: A (m); y: Q; z: φ (rad); w: unused
};

// A displaced surface point and its derivatives with respect to the rest
// coordinates x and z.
struct WaterPoint {
    vec3 position;
    vec3 d_dx;
    vec3 d_dz;
};

WaterPoint water_at_rest(vec2 rest, float base_height) {
    WaterPoint p;
    p.position = vec3(rest.x, base_height, rest.y);
    p.d_dx = vec3(1.0, 0.0, 0.0);
    p.d_dz = vec3(0.0, 0.0, 1.0);
    return p;
}

void water_add_wave(inout WaterPoint p, vec2 rest, float time, Wave w) {
    vec2 d = w.direction_k_omega.xy;
    float k = w.direction_k_omega.z;
    float amplitude = w.amplitude_steepness_phase.x;
    float theta = k * dot(d, rest) - w.direction_k_omega.w * time + w.amplitude_steepness_phase.z;
    float s = sin(theta);
    float c = cos(theta);
    float qa = w.amplitude_steepness_phase.y * amplitude;
    p.position += vec3(qa * d.x * c, amplitude * s, qa * d.y * c);
    // d/dx0 of cos θ is −k D.x sin θ, of sin θ is k D.x cos θ (same for z).
    float horizontal = k * qa * s;
    float vertical = k * amplitude * c;
    p.d_dx += vec3(-horizontal * d.x * d.x, vertical * d.x, -horizontal * d.x * d.y);
    p.d_dz += vec3(-horizontal * d.x * d.y, vertical * d.y, -horizontal * d.y * d.y);
}

// Unit normal on the +y side (the waves never fold: Σ Q k A < 1 on load).
vec3 water_normal(WaterPoint p) {
    return normalize(cross(p.d_dz, p.d_dx));
}

#endif
