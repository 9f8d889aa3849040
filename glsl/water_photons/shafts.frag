#version 460
// Light shafts under the water (shafts.vert): the beam x beam estimate of
// Hu et al. 2010 Eq. 3 (glsl/volume_lines/lines.glsl derives it) for one
// tube of flux Φ crossing this pixel's viewing ray at angle θ, at x on the
// viewing ray t from the eye and s from the tube's start x_{0:0}:
//   L = σ_s p(ω_tube, −ω_view) e^(−σ_t t) Φ(s) K(d) / sin θ,
// Φ(s) = Φ(x') e^(σ_t (t' − s)) the flux the tube still carries at x (the
// photon holds it at the receiver, t' from its start), d the distance
// between the two rays along ω_view × ω_tube and K a box of unit integral
// over d: the tube's width along that direction, |U(s)·n| + |V(s)·n| with
// U(s), V(s) its cross-section's axes moved linearly from the water's
// (`surface_u`, `surface_v`) to the receiver's (`axis_u`, `axis_v`); or,
// for a tube thinner than a pixel, the change of d across the pixel (Hu's
// one-pixel line). σ_s, σ_t and g are the water's medium's (its material:
// extinction in absorption_ior, scattering); the fragment is kept only in
// front of the first surface the pixel sees (the opaque G-buffer, or a
// specular front: the water's underside itself, glass). Component: volume
// caustics (light scattered after its refraction at the surface, L S V).
#include "scene.glsl"
#include "optics.glsl"
#include "random.glsl"
#include "medium.glsl"
#include "common.glsl"
#include "shafts.glsl"
#include "beam_crossing.glsl"

layout(set = 1, binding = WP_BINDING_PHOTONS, std430) readonly buffer PhotonBlock { Photon photons[]; };
layout(set = 1, binding = WP_BINDING_GBUFFER_POSITION) uniform sampler2D opaque_position;
layout(set = 1, binding = WP_BINDING_FRONT_POSITION) uniform sampler2D front_position;

layout(location = 0) flat in uint v_photon;
// rgb: radiance (W m^-2 sr^-1); a: 1 per fragment.
layout(location = 0) out vec4 out_radiance;

void main() {
    ShaftTube tube;
    if (!shaft_tube(photons[v_photon], tube)) discard;
    vec3 eye = frame.eye.xyz;
    vec2 frag = gl_FragCoord.xy;
    vec3 v = view_vector(frag);
    vec3 w = normalize(v);
    vec3 u = tube.dir;
    float len = tube.len;
    vec3 r = tube.start - eye;
    float b = dot(w, u);
    float sin2 = 1.0 - b * b;
    if (sin2 < 1e-8) discard; // the tube runs along the viewing ray
    // The closest points: t along the viewing ray, s along the tube.
    float t = (dot(w, r) - b * dot(u, r)) / sin2;
    float s = t * b - dot(u, r);
    if (t <= 0.0 || s < 0.0 || s > len) discard;
    ivec2 q = ivec2(frag);
    vec4 front = texelFetch(front_position, q, 0);
    vec4 opaque = texelFetch(opaque_position, q, 0);
    float t_surface = front.w >= 0.0 ? distance(front.xyz, eye) : opaque.w != 0.0 ? distance(opaque.xyz, eye) : 1e30;
    if (t >= t_surface) discard;

    vec3 n = normalize(cross(w, u));
    float d = dot(r, n);
    float f = s / max(len, 1e-30);
    vec3 axis_u = mix(tube.surface_u, tube.end_u, f);
    vec3 axis_v = mix(tube.surface_v, tube.end_v, f);
    float across = abs(dot(axis_u, n)) + abs(dot(axis_v, n));
    float width = max(across, length(ray_distance_per_pixel(frag, v, r, u)));
    if (!(width > 0.0) || abs(d) > 0.5 * width) discard;

    Material water = materials[wp.water.x];
    vec3 sigma_t = water.absorption_ior.rgb;
    vec3 flux = tube.flux * exp(sigma_t * (len - s));
    float phase = hg_phase(dot(u, -w), water.scattering.w);
    vec3 radiance = water.scattering.rgb * phase * exp(-sigma_t * t) * flux / (width * sqrt(sin2));
    out_radiance = vec4(radiance * component_weight(COMPONENT_VOLUME_CAUSTICS), 1.0);
}
