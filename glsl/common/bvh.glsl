// BVH traversal over the scene's triangles[] and bvh_nodes[] (scene.glsl must
// be included first). Mirrors src/bvh/traverse.rs line for line; keep them in
// step. Layout and guarantees: docs/BVH.md.
//
// Epsilon policy:
// - intersect_triangle: Moller-Trumbore, two-sided. Scale-free degeneracy
//   test: |det| <= 1e-5 * maxabs(e1) * maxabs(pv) is a miss (cosine between
//   e1 and pv = d x e2: zero for zero-area triangles and rays in the plane;
//   above rounding noise, so degenerate triangles never hit at garbage t).
//   Non-finite det is a miss; the barycentric tests are written so that NaN
//   fails them; edges inclusive. Hits need 0 < t < t_max;
//   the traversals additionally need t > t_min (caller's offset, t_min >= 0).
// - Slab test: direction components with |d| < 1e-30 become +-1e-30 before
//   inverting (no inf, no 0 * inf = NaN); the box exit distance, clamped to
//   the closest hit so far, is scaled by 1 + 2*gamma_3 (Ize 2013) so rounding
//   never culls a touched box.
// Empty tree: node 0 with count == 0 and left_or_first == 0 is the sentinel
// for "no triangles": every trace misses.
#ifndef COMMON_BVH_GLSL
#define COMMON_BVH_GLSL

#define BVH_MIN_DIR_COMPONENT 1e-30
#define BVH_BOX_EXIT_SCALE 1.00000048 // 1 + 4 * 2^-23 >= 1 + 2 * gamma_3
#define BVH_DET_EPSILON 1e-5

float bvh_max_abs(vec3 v) {
    vec3 a = abs(v);
    return max(max(a.x, a.y), a.z);
}

struct Hit {
    float t;
    uint triangle;    // index into triangles[] (leaf order)
    vec2 barycentric; // (u, v): weights of vertices 1 and 2; vertex 0 gets 1 - u - v
};

bool intersect_triangle(vec3 o, vec3 d, uint tri, float t_max, out float t, out vec2 uv) {
    t = 0.0;
    uv = vec2(0.0);
    vec3 p0 = triangles[tri].p0.xyz;
    vec3 e1 = triangles[tri].p1.xyz - p0;
    vec3 e2 = triangles[tri].p2.xyz - p0;
    vec3 pv = cross(d, e2);
    float det = dot(e1, pv);
    if (!(abs(det) > BVH_DET_EPSILON * bvh_max_abs(e1) * bvh_max_abs(pv)) || isinf(det)) return false;
    float inv_det = 1.0 / det;
    vec3 tv = o - p0;
    float u = dot(tv, pv) * inv_det;
    if (!(u >= 0.0 && u <= 1.0)) return false;
    vec3 qv = cross(tv, e1);
    float v = dot(d, qv) * inv_det;
    if (!(v >= 0.0 && u + v <= 1.0)) return false;
    float tt = dot(e2, qv) * inv_det;
    if (!(tt > 0.0 && tt < t_max)) return false;
    t = tt;
    uv = vec2(u, v);
    return true;
}

// 1 / d with tiny components clamped to +-BVH_MIN_DIR_COMPONENT (+0 and -0 both positive).
vec3 bvh_safe_inverse(vec3 d) {
    vec3 s = mix(vec3(BVH_MIN_DIR_COMPONENT), vec3(-BVH_MIN_DIR_COMPONENT), lessThan(d, vec3(0.0)));
    return vec3(1.0) / mix(d, s, lessThan(abs(d), vec3(BVH_MIN_DIR_COMPONENT)));
}

// Slab test: true if the ray overlaps node n's box within [t_min, t_max]; t_near = entry distance.
bool bvh_ray_box(uint n, vec3 o, vec3 inv_d, float t_min, float t_max, out float t_near) {
    vec3 t0 = (bvh_nodes[n].bounds_min - o) * inv_d;
    vec3 t1 = (bvh_nodes[n].bounds_max - o) * inv_d;
    vec3 tn = min(t0, t1);
    vec3 tf = max(t0, t1);
    t_near = max(max(tn.x, tn.y), max(tn.z, t_min));
    float t_far = min(min(min(tf.x, tf.y), tf.z), t_max) * BVH_BOX_EXIT_SCALE;
    return t_near <= t_far;
}

bool bvh_is_empty() {
    return bvh_nodes[0].count == 0u && bvh_nodes[0].left_or_first == 0u;
}

// Shared traversal: any_hit = true stops at the first hit (occlusion).
// Stack: one entry per level at most (the far child of each ancestor), and the
// builder guarantees depth <= BVH_STACK_SIZE - 1.
bool bvh_traverse(vec3 o, vec3 d, float t_min, float t_max, bool any_hit, out Hit hit) {
    hit.t = t_max;
    hit.triangle = 0xffffffffu;
    hit.barycentric = vec2(0.0);
    if (bvh_is_empty()) return false;
    vec3 inv_d = bvh_safe_inverse(d);
    float t_root;
    if (!bvh_ray_box(0u, o, inv_d, t_min, t_max, t_root)) return false;
    float closest = t_max;
    bool found = false;
    uint stack[BVH_STACK_SIZE];
    uint sp = 0u;
    uint node = 0u;
    // While-while (Aila & Laine 2009, "Understanding the efficiency of ray
    // traversal on GPUs"): down the inner nodes to a leaf, then its
    // triangles, then the next node off the stack. The lanes of a SIMD group
    // (llvmpipe's 8, a GPU's 32) wait for each other less than when every
    // step runs both a leaf's and an inner node's code: photons through
    // ball_lens_top's tessellated ball took 20% less time.
    bool done = false;
    while (!done) {
        uint count = bvh_nodes[node].count;
        while (count == 0u) {
            uint l = bvh_nodes[node].left_or_first;
            uint r = l + 1u;
            float dl, dr;
            bool hl = bvh_ray_box(l, o, inv_d, t_min, closest, dl);
            bool hr = bvh_ray_box(r, o, inv_d, t_min, closest, dr);
            if (hl && hr) {
                bool left_first = dl <= dr;
                stack[sp] = left_first ? r : l;
                sp += 1u;
                node = left_first ? l : r;
            } else if (hl || hr) {
                node = hl ? l : r;
            } else {
                if (sp == 0u) {
                    done = true;
                    break;
                }
                sp -= 1u;
                node = stack[sp];
            }
            count = bvh_nodes[node].count;
        }
        if (done) break;
        uint first = bvh_nodes[node].left_or_first;
        for (uint i = first; i < first + count; ++i) {
            float t;
            vec2 uv;
            if (intersect_triangle(o, d, i, closest, t, uv) && t > t_min && !triangle_cut_out(i, uv)) {
                closest = t;
                found = true;
                hit.t = t;
                hit.triangle = i;
                hit.barycentric = uv;
                if (any_hit) return true;
            }
        }
        if (sp == 0u) break;
        sp -= 1u;
        node = stack[sp];
    }
    return found;
}

// Closest hit with t_min < t < t_max.
bool trace_closest(vec3 origin, vec3 dir, float t_min, float t_max, out Hit hit) {
    return bvh_traverse(origin, dir, t_min, t_max, false, hit);
}

// True if anything lies on the ray with t_min < t < t_max (shadow/visibility rays).
bool trace_any(vec3 origin, vec3 dir, float t_min, float t_max) {
    Hit h;
    return bvh_traverse(origin, dir, t_min, t_max, true, h);
}

vec3 hit_position(Hit h, vec3 o, vec3 d) {
    return o + h.t * d;
}

// Normal of the triangle's plane, oriented by counter-clockwise winding
// (right-hand rule: (p1 - p0) x (p2 - p0)).
vec3 hit_geometric_normal(Hit h) {
    vec3 p0 = triangles[h.triangle].p0.xyz;
    return normalize(cross(triangles[h.triangle].p1.xyz - p0, triangles[h.triangle].p2.xyz - p0));
}

// Interpolated vertex normal, normalized; the geometric normal if the
// interpolation vanishes (opposing or zero vertex normals).
vec3 hit_normal(Hit h) {
    vec2 b = h.barycentric;
    vec3 n = (1.0 - b.x - b.y) * triangles[h.triangle].n0.xyz + b.x * triangles[h.triangle].n1.xyz
        + b.y * triangles[h.triangle].n2.xyz;
    float len2 = dot(n, n);
    return len2 > 0.0 ? n * inversesqrt(len2) : hit_geometric_normal(h);
}

uint hit_material(Hit h) {
    return triangle_material(h.triangle);
}

// Albedo of the (diffuse) surface hit: material colour times texture at the hit's UV.
vec3 hit_albedo(Hit h) {
    return material_albedo(hit_material(h), triangle_uv(h.triangle, h.barycentric));
}

#endif
