#version 460
// beams, Sect. 5.3: the flux-conserving surface gather. Per pixel the
// caustic triangle's rectangle (caustic.geom) covers, the flux the beam
// deposits on the receiver this pixel sees, into the surface target
// (additive; apply.comp divides each pixel's flux by its footprint's area).
//
// The beam's flux Phi crosses its footprint on the receiver, the caustic
// triangle c_k = v_k + y_k e_k of its edge rays' hits (straight edges: the
// beam's sides are bilinear patches, whose curved traces on a plane the
// chord stands for). Integrating the issue's irradiance
// E = Phi |d . n_r| / (A(y) |d . n_delta|) over the triangle gives Phi.
// The pixel's share is the part of the triangle inside the pixel's
// footprint on the triangle's plane (footprint.glsl), clipped exactly
// (Sutherland-Hodgman, the triangle against the footprint quad): flux =
// Phi * area(triangle ∩ footprint) / area(triangle). The footprints of
// neighbouring pixels tile the plane, so the shares of all pixels sum to
// Phi: a beam smaller than a pixel deposits all its flux in the pixel(s)
// it lands in, a focus a few pixels wide keeps its energy, and the total
// does not depend on the image size. Within the triangle the flux is
// spread uniformly over its area (E's variation inside one beam, 1/A(y)
// and the obliquity, is what refinement resolves; the paper's one area
// function per beam makes it uniform across a cross-section too). A
// degenerate triangle (a focus on the receiver: area below 1e-6 of its
// longest edge squared) is a point: all its flux goes to the pixel whose
// footprint on the receiver's plane holds its centroid.
//
// A pixel receives only where it sees the surface the triangle lies on
// (its receiver within 1% of its distance plus a tenth of the triangle's
// size of the triangle's plane, normals within 25 degrees: an occluder in
// front, or another surface, gets nothing), the light arrives on the side
// the camera sees, and no diffuse surface blocks the beam between its
// base and the receiver point (a BVH ray, beam_path_clear, for footprints
// larger than the pixel's: the edge rays, which end at the first diffuse
// surface, already clear a smaller one); the medium's
// transmittance along the beam from its base applies (the light side up
// to the base is in Phi already).
#include "scene.glsl"
#include "beams_bindings.glsl"
#include "optics.glsl"
#include "bvh.glsl"
#include "random.glsl"
#include "medium.glsl"
#include "beam.glsl"
#include "footprint.glsl"
#include "volume_push.glsl"
#include "receiver.glsl"

layout(set = 1, binding = BEAMS_BINDING_BEAMS, std430) readonly buffer BeamBlock { Beam beams[]; };
layout(set = 1, binding = BEAMS_BINDING_COUNTERS, std430) buffer CounterBlock { uint counters[]; };
layout(set = 1, binding = BEAMS_BINDING_RECEIVERS, std430) readonly buffer ReceiverBlock { Receiver receivers[]; };

layout(location = 0) flat in uint g_beam;
// rgb: flux (W) deposited on the receiver this pixel sees.
layout(location = 0) out vec4 out_flux;

float cross2(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }

// Area of the polygon p[0..n) (shoelace).
float polygon_area(vec2 p[8], int n) {
    float s = 0.0;
    for (int i = 0; i < n; ++i) s += cross2(p[i], p[(i + 1) % n]);
    return 0.5 * abs(s);
}

// The part of triangle `tri` inside the convex quad `quad`: its area, and
// the mean of its vertices (a point inside it). Sutherland-Hodgman: the
// triangle clipped by the quad's four edges (at most 7 vertices).
float overlap(vec2 tri[3], vec2 quad[4], out vec2 mean) {
    vec2 poly[8];
    int n = 3;
    for (int i = 0; i < 3; ++i) poly[i] = tri[i];
    float orient = cross2(quad[1] - quad[0], quad[2] - quad[0]) >= 0.0 ? 1.0 : -1.0;
    // Exact shortcuts first: the triangle wholly outside one edge (most of
    // the rectangle's pixels), or wholly inside all four (a triangle
    // smaller than the pixel), need no clipping.
    bool inside = true;
    for (int e = 0; e < 4; ++e) {
        vec2 a = quad[e], edge = quad[(e + 1) % 4] - a;
        vec3 s = orient * vec3(cross2(edge, tri[0] - a), cross2(edge, tri[1] - a), cross2(edge, tri[2] - a));
        if (all(lessThan(s, vec3(0.0)))) return 0.0;
        inside = inside && all(greaterThanEqual(s, vec3(0.0)));
    }
    if (inside) {
        mean = (tri[0] + tri[1] + tri[2]) / 3.0;
        return polygon_area(poly, 3);
    }
    for (int e = 0; e < 4; ++e) {
        vec2 a = quad[e], edge = quad[(e + 1) % 4] - a;
        vec2 next[8];
        int m = 0;
        for (int i = 0; i < n; ++i) {
            vec2 p = poly[i], q = poly[(i + 1) % n];
            float dp = orient * cross2(edge, p - a), dq = orient * cross2(edge, q - a);
            if (dp >= 0.0 && m < 8) next[m++] = p;
            if ((dp >= 0.0) != (dq >= 0.0) && m < 8) next[m++] = p + (q - p) * (dp / (dp - dq));
        }
        n = m;
        poly = next;
        if (n < 3) return 0.0;
    }
    mean = vec2(0.0);
    for (int i = 0; i < n; ++i) mean += poly[i];
    mean /= float(n);
    return polygon_area(poly, n);
}

// Whether point o lies in the convex quad, half-open (edges 0 and 3 in,
// 1 and 2 out) so a point on the edge two pixels share goes to one.
bool in_quad(vec2 quad[4], vec2 o) {
    float orient = cross2(quad[1] - quad[0], quad[2] - quad[0]) >= 0.0 ? 1.0 : -1.0;
    for (int e = 0; e < 4; ++e) {
        float s = orient * cross2(quad[(e + 1) % 4] - quad[e], o - quad[e]);
        if (e == 0 || e == 3 ? s < 0.0 : s <= 0.0) return false;
    }
    return true;
}

void main() {
    atomicAdd(counters[BEAMS_STAT_CAUSTIC_FRAGMENTS], 1u);
    out_flux = vec4(0.0);
    Beam b = beams[g_beam];
    ivec2 px = ivec2(gl_FragCoord.xy);
    Receiver r = receivers[px.y * int(frame.viewport.x) + px.x];
    if (r.normal.w <= 0.0) return;
    vec3 x = r.position.xyz, n_r = r.normal.xyz;

    vec3 c[3];
    beam_caustic_triangle(b, c);
    vec3 e1 = c[1] - c[0], e2 = c[2] - c[0], e3 = c[2] - c[1];
    vec3 normal = cross(e1, e2);
    float size2 = max(dot(e1, e1), max(dot(e2, e2), dot(e3, e3)));
    float twice_area = length(normal);
    bool point = !(twice_area > 1e-6 * size2);
    // The plane the shares are measured on: the triangle's, or for a
    // point the receiver's through its centroid.
    vec3 q = point ? (c[0] + c[1] + c[2]) / 3.0 : c[0];
    vec3 m = point ? n_r : normal / twice_area;
    if (abs(dot(x - q, m)) > 0.01 * length(x - frame.eye.xyz) + 0.1 * sqrt(size2) || abs(dot(n_r, m)) < 0.9) return;

    vec3 corners[4];
    if (!pixel_footprint(floor(gl_FragCoord.xy), q, m, corners)) return;
    vec3 u = point ? normalize(cross(m, abs(m.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0))) : normalize(e1);
    vec3 v = cross(m, u);
    vec2 quad[4];
    for (int i = 0; i < 4; ++i) quad[i] = vec2(dot(corners[i], u), dot(corners[i], v));
    float share;
    vec3 lam;
    if (point) {
        if (!in_quad(quad, vec2(0.0))) return;
        share = 1.0;
        lam = vec3(1.0 / 3.0);
    } else {
        vec2 tri[3] = vec2[3](vec2(0.0), vec2(dot(e1, u), dot(e1, v)), vec2(dot(e2, u), dot(e2, v)));
        vec2 poly[8];
        for (int i = 0; i < 3; ++i) poly[i] = tri[i];
        float whole = polygon_area(poly, 3);
        vec2 mean;
        float part = overlap(tri, quad, mean);
        if (!(part > 0.0) || !(whole > 0.0)) return;
        share = min(part / whole, 1.0);
        // Barycentric coordinates of the overlap's mean point: where on
        // the beam this pixel's light comes from.
        float d = cross2(tri[1], tri[2]);
        lam.y = cross2(mean, tri[2]) / d;
        lam.z = cross2(tri[1], mean) / d;
        lam.x = 1.0 - lam.y - lam.z;
        lam = max(lam, vec3(0.0));
        lam /= lam.x + lam.y + lam.z;
    }

    vec3 d = normalize(beam_direction(b, lam));
    if (dot(d, n_r) >= 0.0) return; // the light arrives on the far side
    vec3 base = lam.x * b.v0.xyz + lam.y * b.v1.xyz + lam.z * b.v2.xyz;
    // The edge rays reached the triangle's corners unblocked (they end at
    // the first diffuse surface), so a footprint smaller than the pixel's
    // needs no ray of its own: what could block light inside it is
    // smaller than the pixel. Larger ones trace the ray from the receiver
    // point (shadow edges inside a beam).
    bool small = point || 0.5 * twice_area < quad_area(corners);
    if (!small && !beam_path_clear(x + n_r * (1e-4 * max(1.0, bvh_max_abs(x))), base)) return;
    vec3 tau = bm_transmittance(base, x, pc.medium_steps);
    out_flux = vec4(b.flux.rgb * tau * share, 0.0);
}
