#version 460
// Light shafts under the water (issue 30; beyond Kougianos & Moustakas
// 2021, who leave volume caustics to future work). Every refracted photon
// of the trace is also the beam that carried its flux from the water point
// x_{0:0} down to its receiver hit x': a tube whose cross-section the
// photon differential gives at both ends (Eq. 10: `surface_u`, `surface_v`
// on the water, `axis_u`, `axis_v` on the receiver; between them each
// neighbour's ray is straight, so the cross-section moves linearly), so
// the tubes of neighbouring texels tile the water the way their splats
// tile the floor, in every cascade and across the seams, and a focusing
// tube narrows toward its focus. shafts.frag renders each tube by the
// beam x beam estimate of Hu et al. 2010 Eq. 3 with a box kernel of the
// tube's width.
// Drawn only for an eye under the surface (the host decides, shafts.rs):
// seen from above, the shafts lie behind the refracting surface, which
// this screen-space footprint does not bend.
// One instanced quad per photon (the trace's indirect draw, 4 vertices an
// instance), for those that stand for a block of texels (shafts.glsl,
// `shaft_stride`; the rest draw nothing): the segment's footprint on
// screen, clipped to the near plane,
// widened on each side by the tube's half-width projected at each end
// (a bound over all directions), and at least a pixel and a half.
#include "scene.glsl"
#include "common.glsl"
#include "shafts.glsl"

layout(set = 1, binding = WP_BINDING_PHOTONS, std430) readonly buffer PhotonBlock { Photon photons[]; };

layout(location = 0) flat out uint v_photon;

// Closer than this (m, view depth) the segment is clipped: the projection's
// near plane is at 0.01 m.
const float NEAR = 0.02;
const float MIN_HALF_WIDTH_PX = 1.5;

// Pixel coordinates of x at view depth z > 0.
vec2 to_pixels(vec3 x) {
    vec4 c = frame.view_proj * vec4(x, 1.0);
    return (c.xy / c.w * 0.5 + 0.5) * frame.viewport.xy;
}

void main() {
    v_photon = uint(gl_InstanceIndex);
    gl_Position = vec4(2.0, 2.0, 0.5, 1.0); // outside the view: nothing drawn
    ShaftTube tube;
    if (!shaft_tube(photons[gl_InstanceIndex], tube)) return;
    vec3 a = tube.start;
    vec3 b = tube.start + tube.dir * tube.len;
    vec3 va = (frame.view * vec4(a, 1.0)).xyz, vb = (frame.view * vec4(b, 1.0)).xyz;
    float za = -va.z, zb = -vb.z;
    if (za < NEAR && zb < NEAR) return;
    float clip = (NEAR - za) / (zb - za);
    vec3 a_clipped = za < NEAR ? mix(a, b, clip) : a;
    vec3 b_clipped = zb < NEAR ? mix(a, b, clip) : b;
    vec3 va_clipped = za < NEAR ? mix(va, vb, clip) : va;
    vec3 vb_clipped = zb < NEAR ? mix(va, vb, clip) : vb;
    za = max(za, NEAR);
    zb = max(zb, NEAR);
    // The tube's half-width at each end, at most half the sum of its axes.
    float focal = 0.5 * frame.viewport.y / frame.eye.w; // pixels per metre at unit depth
    float wa = 0.5 * max(length(tube.surface_u) + length(tube.surface_v), length(tube.end_u) + length(tube.end_v));
    // A width across the viewing ray at angle α off the axis projects to
    // wa f / (z cos α) = wa f d / z² pixels along the radial direction.
    float ha = max(wa * focal * length(va_clipped) / (za * za), MIN_HALF_WIDTH_PX);
    float hb = max(wa * focal * length(vb_clipped) / (zb * zb), MIN_HALF_WIDTH_PX);
    vec2 pa = to_pixels(a_clipped), pb = to_pixels(b_clipped);
    vec2 along = pb - pa;
    along = dot(along, along) > 1e-8 ? normalize(along) : vec2(1.0, 0.0);
    vec2 across = vec2(-along.y, along.x);
    uint corner = uint(gl_VertexIndex);
    bool at_b = corner >= 2u;
    float side = (corner & 1u) == 0u ? -1.0 : 1.0;
    float h = at_b ? hb : ha;
    vec2 q = (at_b ? pb + along * h : pa - along * h) + across * (side * h);
    gl_Position = vec4(q / frame.viewport.xy * 2.0 - 1.0, 0.5, 1.0);
}
