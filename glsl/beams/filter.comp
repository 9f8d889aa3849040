#version 460
// beams, Sect. 7 ("Surface caustics"): the optional low-pass filter of the
// surface caustics. With one area function per beam the irradiance jumps
// at beam boundaries; the paper renders the surface caustics to their own
// target and low-pass filters it. One separable pass per axis (X: surface
// -> filtered, Y: filtered -> surface), a Gaussian of standard deviation
// radius / 2 pixels over +-radius among the neighbours that see a receiver
// on the same surface (normals within 25 degrees, distances from the eye
// within 5%), so the filter never mixes a caustic into the background or
// across a silhouette. Each input pixel's weights are normalised over its
// own neighbours (a scatter written as a gather: out(p) = sum_q in(q)
// w(p, q) / W(q), W(q) = sum_p' w(p', q)), so the pixels' sum is kept:
// the target holds flux (W, caustic.frag), so the filter moves light
// between neighbouring receiver pixels and conserves it.
#include "scene.glsl"
#include "beams_bindings.glsl"
#include "receiver.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = BEAMS_BINDING_SURFACE, rgba32f) uniform image2D surface;
layout(set = 1, binding = BEAMS_BINDING_SURFACE_FILTERED, rgba32f) uniform image2D filtered;
layout(set = 1, binding = BEAMS_BINDING_RECEIVERS, std430) readonly buffer ReceiverBlock { Receiver receivers[]; };

layout(push_constant) uniform Push {
    int radius;
    uint axis; // 0: x (surface -> filtered), 1: y (filtered -> surface)
} pc;

// Whether pixels a and b see one surface (symmetric in a and b).
bool same_surface(Receiver a, Receiver b) {
    if (a.normal.w <= 0.0 || b.normal.w <= 0.0 || dot(a.normal.xyz, b.normal.xyz) < 0.9) return false;
    float ta = length(a.position.xyz - frame.eye.xyz), tb = length(b.position.xyz - frame.eye.xyz);
    return abs(ta - tb) <= 0.05 * min(ta, tb);
}

float gaussian(int k) {
    float sigma = 0.5 * float(pc.radius);
    return exp(-0.5 * float(k * k) / (sigma * sigma));
}

Receiver receiver_at(ivec2 q, ivec2 size) { return receivers[q.y * size.x + q.x]; }

bool inside(ivec2 q, ivec2 size) { return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size)); }

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(surface);
    if (p.x >= size.x || p.y >= size.y) return;
    Receiver r = receiver_at(p, size);
    ivec2 step = pc.axis == 0u ? ivec2(1, 0) : ivec2(0, 1);
    vec4 sum = vec4(0.0);
    if (r.normal.w > 0.0) {
        for (int k = -pc.radius; k <= pc.radius; ++k) {
            ivec2 q = p + k * step;
            if (!inside(q, size)) continue;
            Receiver s = receiver_at(q, size);
            if (!same_surface(r, s)) continue;
            // W(q): q's weights over its own neighbours.
            float total = 0.0;
            for (int j = -pc.radius; j <= pc.radius; ++j) {
                ivec2 o = q + j * step;
                if (inside(o, size) && same_surface(s, receiver_at(o, size))) total += gaussian(j);
            }
            vec4 value = pc.axis == 0u ? imageLoad(surface, q) : imageLoad(filtered, q);
            sum += value * (gaussian(k) / total);
        }
    }
    if (pc.axis == 0u) {
        imageStore(filtered, p, sum);
    } else {
        imageStore(surface, p, sum);
    }
}
