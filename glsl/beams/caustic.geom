#version 460
// beams, Sect. 5.3 (surface caustics as caustic triangles): one point per
// beam (volume.vert, drawn indirect like the volumes). A beam whose three
// edge rays meet one diffuse surface has a footprint there, the caustic
// triangle of their hits; this emits the screen rectangle that holds every
// pixel whose square meets that triangle's projection (its bounding box,
// after clipping the triangle to the space in front of the eye, grown by
// half a pixel: a pixel meets the triangle only if its centre lies within
// half a pixel of it), as one quad, so each such pixel gets exactly one
// fragment, including pixels the triangle only touches and triangles
// smaller than a pixel (a conservative rasterisation). caustic.frag
// computes each pixel's exact share.
#include "scene.glsl"
#include "beams_bindings.glsl"
#include "optics.glsl"
#include "bvh.glsl"
#include "random.glsl"
#include "medium.glsl"
#include "beam.glsl"

layout(points) in;
layout(triangle_strip, max_vertices = 4) out;

layout(set = 1, binding = BEAMS_BINDING_BEAMS, std430) readonly buffer BeamBlock { Beam beams[]; };

layout(location = 0) flat in uint v_beam[];
layout(location = 0) flat out uint g_beam;

// Clip-space w below which a point counts as behind the eye.
const float W_MIN = 1e-4;

vec2 lo = vec2(1e30), hi = vec2(-1e30);

void extend(vec4 h) {
    vec2 p = (h.xy / h.w * 0.5 + 0.5) * frame.viewport.xy;
    lo = min(lo, p);
    hi = max(hi, p);
}

void corner(vec2 p) {
    g_beam = v_beam[0];
    gl_Position = vec4(p / frame.viewport.xy * 2.0 - 1.0, 0.5, 1.0);
    EmitVertex();
}

void main() {
    Beam b = beams[v_beam[0]];
    if (!beam_has_receiver(b)) return;
    vec3 c[3];
    beam_caustic_triangle(b, c);
    vec4 h[3];
    for (int k = 0; k < 3; ++k) h[k] = frame.view_proj * vec4(c[k], 1.0);
    // The triangle's part in front of the eye (w > W_MIN), by its
    // vertices there and its edges' crossings of w = W_MIN.
    for (int k = 0; k < 3; ++k) {
        int j = (k + 1) % 3;
        bool in_k = h[k].w > W_MIN, in_j = h[j].w > W_MIN;
        if (in_k) extend(h[k]);
        if (in_k != in_j) extend(mix(h[k], h[j], (W_MIN - h[k].w) / (h[j].w - h[k].w)));
    }
    // A margin of 0.01 pixel over the half pixel: pixels that only touch
    // the triangle get a fragment with no share, none is missed.
    lo = max(lo - 0.51, vec2(0.0));
    hi = min(hi + 0.51, frame.viewport.xy);
    if (!(hi.x > lo.x && hi.y > lo.y)) return;
    corner(lo);
    corner(vec2(hi.x, lo.y));
    corner(vec2(lo.x, hi.y));
    corner(hi);
    EndPrimitive();
}
