// water_photons: the parameters shared by its passes and the photon record
// (src/techniques/water_photons/mod.rs mirrors both: WpParams, GpuWaterPhoton).
#ifndef WATER_PHOTONS_COMMON_GLSL
#define WATER_PHOTONS_COMMON_GLSL

#include "water_photons_bindings.glsl"

layout(set = 1, binding = WP_BINDING_PARAMS, std140) uniform WpParams {
    mat4 light_view;   // Eq. 1: shared by every cascade
    vec4 light_dir;    // xyz: unit direction the light travels
    vec4 irradiance;   // rgb: E of the directional light on a surface facing it (W/m^2)
    vec4 range;        // x, y: width and height of cascade 0 (m); z, w: near, far
    uvec4 size;        // x, y: ccm_0 texels; z: cascades N; w: photon capacity
    uvec4 modes;       // x, y: border (ΔX, ΔY) of Eq. 6; z: WP_INTENSITY_*; w: WP_SPLAT_*
    vec4 cascade;      // x: scale s; y: q_0 (Eq. 16); z: F_frac, w: F_exp (Eq. 14)
    vec4 paper;        // x: γ, y: t_max (Eq. 13); z: ε (Eq. 19); w: depth bias (relative)
    uvec4 water;       // x: the water's material index; y, z, w (f32 bits): rest height h, slope bound, Σ amplitude (view.comp)
    uvec4 shafts;      // x: block stride k of the shaft tubes (shafts.glsl); y: 1 while the eye is under the water
} wp;

// One photon (Algorithm 3 lines 36-41, and the ray's start for the
// shafts), 128 bytes.
struct Photon {
    vec4 position;  // xyz: hit x'_{0:0}; w: cascade c
    vec4 normal;    // xyz: receiver normal n'_{0:0} facing the ray; w: sqrt(A'/A) (Eq. 11 without s^c)
    vec4 axis_u;    // xyz: ∂x'/∂u on the receiver's tangent plane; w: ray type WP_RAY_*
    vec4 axis_v;    // xyz: ∂x'/∂v; w: hit distance t'
    vec4 flux;      // rgb: flux Φ (W) at the hit, or the paper's ray intensity R (Eq. 12); w: surface triangle area A (m^2)
    vec4 dir;       // xyz: ray direction ω; w: 0
    vec4 surface_u; // xyz: ∂x/∂u on the water surface (Eq. 10 at the ray's start); w: k, its texel starts a k x k block of shafts (0: it does not)
    vec4 surface_v; // xyz: ∂x/∂v there; w: 0
};

#endif
