#version 460
// Splatting, fragment stage: the box of Eq. 20 convolved with a narrow tent
// (splat.vert), added into the screen-space caustic buffer: rgb caustic
// irradiance E (W/m^2), a the sum of kernel weights.
//
// Arrival side (GUIDE §2: a two-sided diffuse surface is lit on the side
// the light arrives at, never through itself). The depth test alone cannot
// tell the two faces of a thin surface apart: a photon that landed on the
// far face of a wall thinner than the depth bias, or on either face of an
// open quad (zero thickness), passes it where the camera sees the other
// face, and would light that face through the wall. The photon's normal
// faces the ray it arrived along (trace.comp); the camera G-buffer's
// normal faces the camera (passes/gbuffer.frag). The photon lights this
// pixel only if both point to the same side: dot > 0. Where no surface
// covers the pixel the G-buffer normal is 0 and nothing is deposited
// (the composite ignores those pixels anyway).
#include "water_photons_bindings.glsl"
// splat_weight only: kernel.glsl's other function needs the parameters.
#define WATER_PHOTONS_KERNEL_WEIGHT_ONLY
#include "kernel.glsl"

layout(set = 1, binding = WP_BINDING_GBUFFER_NORMAL) uniform sampler2D g_normal;

layout(location = 0) in vec2 v_local;
layout(location = 1) flat in vec3 v_irradiance;
layout(location = 2) flat in float v_ramp;
layout(location = 3) flat in vec3 v_normal;

layout(location = 0) out vec4 out_caustic;

void main() {
    vec3 seen = texelFetch(g_normal, ivec2(gl_FragCoord.xy), 0).xyz;
    if (dot(seen, v_normal) <= 0.0) discard;
    float w = splat_weight(v_local, v_ramp);
    out_caustic = vec4(v_irradiance * w, w);
}
