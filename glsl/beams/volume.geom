#version 460
// beams, Sect. 4.3 (Bounding Volumes): extrudes each beam into a closed
// convex volume that contains it, from its base triangle b_k and the far
// ends t_k = b_k + y_max e_k of its edges (the truncated beam is the convex
// hull of these six points: every cross-section is a triangle whose
// vertices lie on the edges between them).
// - BEAMS_VOLUME_PRISM, Ernst et al. 2005: three touching planes, each
//   through one base edge and the far end that leaves the whole beam on
//   its inner side, cut by the base plane and the far plane y = y_max.
// - BEAMS_VOLUME_TIGHT, Liktor & Dachsbacher's six triangles: each side
//   quad b_i b_j t_j t_i split along the diagonal that keeps the volume
//   convex (each side triangle is one edge of one triangle and a vertex of
//   the other), plus the base and far triangles: the convex hull itself
//   when every side admits such a diagonal. Where a side admits none (the
//   far triangle flipped over or twisted past the base: the hull has other
//   faces) the beam falls back to the prism. (The paper also falls back
//   when a side admits both diagonals, a near-planar side; here the
//   triangles share their vertices, so either diagonal is watertight and
//   the tight volume is kept.)
// Only the volume's back faces (seen from the eye, on the far side of
// their plane) are emitted: the rays through a convex volume leave it
// through exactly one back face, so every pixel the volume covers gets
// exactly one fragment, whose shader integrates the ray's whole interval
// inside the beam (volume.frag); depth testing is not used (fragments
// behind the first surface contribute up to it).
#include "scene.glsl"
#include "beams_bindings.glsl"
#include "optics.glsl"
#include "bvh.glsl"
#include "random.glsl"
#include "medium.glsl"
#include "beam.glsl"
#include "volume_push.glsl"

layout(points) in;
layout(triangle_strip, max_vertices = 24) out;

layout(set = 1, binding = BEAMS_BINDING_BEAMS, std430) readonly buffer BeamBlock { Beam beams[]; };

layout(location = 0) flat in uint v_beam[];
layout(location = 0) flat out uint g_beam;

vec3 inside_point;
float eps;

// Emits triangle a b c if it is a back face: its outward normal (away from
// inside_point) points away from the eye.
void face(vec3 a, vec3 b, vec3 c) {
    vec3 m = cross(b - a, c - a);
    if (dot(m, inside_point - a) > 0.0) m = -m;
    if (dot(m, a - frame.eye.xyz) <= 0.0) return;
    g_beam = v_beam[0];
    gl_Position = frame.view_proj * vec4(a, 1.0);
    EmitVertex();
    g_beam = v_beam[0];
    gl_Position = frame.view_proj * vec4(b, 1.0);
    EmitVertex();
    g_beam = v_beam[0];
    gl_Position = frame.view_proj * vec4(c, 1.0);
    EmitVertex();
    EndPrimitive();
}

// Largest signed distance of the points beyond the plane of a b c, oriented
// away from `inner` (<= eps: the plane supports all of them).
float beyond(vec3 a, vec3 b, vec3 c, vec3 inner, vec3 pts[6]) {
    vec3 m = cross(b - a, c - a);
    float len = length(m);
    if (len <= 0.0) return 1e30;
    m /= len;
    if (dot(m, inner - a) > 0.0) m = -m;
    float worst = -1e30;
    for (int i = 0; i < 6; ++i) worst = max(worst, dot(m, pts[i] - a));
    return worst;
}

void main() {
    Beam bm = beams[v_beam[0]];
    float y_max = bm.v0.w;
    vec3 b[3] = vec3[3](bm.v0.xyz, bm.v1.xyz, bm.v2.xyz);
    vec3 t[3] = vec3[3](b[0] + y_max * bm.e0.xyz, b[1] + y_max * bm.e1.xyz, b[2] + y_max * bm.e2.xyz);
    vec3 pts[6] = vec3[6](b[0], b[1], b[2], t[0], t[1], t[2]);
    vec3 centre = (b[0] + b[1] + b[2] + t[0] + t[1] + t[2]) / 6.0;
    float extent = 0.0;
    for (int i = 0; i < 6; ++i) extent = max(extent, length(pts[i] - centre));
    eps = 1e-5 * extent;

    if (pc.volume_kind == BEAMS_VOLUME_TIGHT) {
        // Per side, the convex diagonal: 0 (b_i, t_j), 1 (b_j, t_i), -1 none.
        int diag[3];
        bool ok = true;
        for (int i = 0; i < 3; ++i) {
            int j = (i + 1) % 3;
            if (beyond(b[i], b[j], t[j], centre, pts) <= eps && beyond(b[i], t[j], t[i], centre, pts) <= eps) {
                diag[i] = 0;
            } else if (beyond(b[i], b[j], t[i], centre, pts) <= eps && beyond(b[j], t[j], t[i], centre, pts) <= eps) {
                diag[i] = 1;
            } else {
                ok = false;
            }
        }
        if (ok) {
            inside_point = centre;
            face(b[0], b[1], b[2]);
            face(t[0], t[1], t[2]);
            for (int i = 0; i < 3; ++i) {
                int j = (i + 1) % 3;
                if (diag[i] == 0) {
                    face(b[i], b[j], t[j]);
                    face(b[i], t[j], t[i]);
                } else {
                    face(b[i], b[j], t[i]);
                    face(b[j], t[j], t[i]);
                }
            }
            return;
        }
    }

    // Ernst's prism: the touching plane of each base edge (i, j), through
    // the far end that leaves every point on its inner side (the hull's
    // face next to the base along that edge).
    vec3 n = bm.n.xyz;
    vec3 plane[3];
    for (int i = 0; i < 3; ++i) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        float best = 1e30;
        plane[i] = vec3(0.0);
        for (int c = 0; c < 3; ++c) {
            vec3 m = cross(b[j] - b[i], t[c] - b[i]);
            float len = length(m);
            if (len <= 0.0) continue;
            m /= len;
            if (dot(m, b[k] - b[i]) > 0.0) m = -m;
            float worst = -1e30;
            for (int p = 0; p < 6; ++p) worst = max(worst, dot(m, pts[p] - b[i]));
            if (worst < best) {
                best = worst;
                plane[i] = m;
            }
        }
    }
    // Far vertices: where the two touching planes through b_k meet the far
    // plane (edges (k-1, k) and (k, k+1)).
    vec3 q[3];
    for (int k = 0; k < 3; ++k) {
        vec3 line = cross(plane[(k + 2) % 3], plane[k]);
        float along = dot(line, n);
        q[k] = abs(along) > 1e-6 * length(line) ? b[k] + (y_max / along) * line : t[k];
    }
    inside_point = (b[0] + b[1] + b[2] + q[0] + q[1] + q[2]) / 6.0;
    face(b[0], b[1], b[2]);
    face(q[0], q[1], q[2]);
    for (int i = 0; i < 3; ++i) {
        int j = (i + 1) % 3;
        face(b[i], b[j], q[j]);
        face(b[i], q[j], q[i]);
    }
}
