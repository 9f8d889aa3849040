// TEMPORARY brute-force stand-in with the agreed interface; replaced by the BVH traversal.
#ifndef COMMON_BVH_GLSL
#define COMMON_BVH_GLSL
struct Hit { float t; uint triangle; vec2 barycentric; };
bool intersect_triangle(vec3 o, vec3 d, uint tri, float t_max, out float t, out vec2 uv) {
    vec3 p0 = triangles[tri].p0.xyz, e1 = triangles[tri].p1.xyz - p0, e2 = triangles[tri].p2.xyz - p0;
    vec3 pv = cross(d, e2); float det = dot(e1, pv); t = 0.0; uv = vec2(0.0);
    if (abs(det) < 1e-12) return false;
    float inv = 1.0 / det; vec3 tv = o - p0; float u = dot(tv, pv) * inv; if (u < 0.0 || u > 1.0) return false;
    vec3 qv = cross(tv, e1); float v = dot(d, qv) * inv; if (v < 0.0 || u + v > 1.0) return false;
    t = dot(e2, qv) * inv; uv = vec2(u, v); return t > 0.0 && t < t_max;
}
bool trace_closest(vec3 o, vec3 d, float t_min, float t_max, out Hit hit) {
    hit.t = t_max; hit.triangle = 0u; hit.barycentric = vec2(0.0); bool found = false;
    for (uint i = 0u; i < frame.counts.y; ++i) { float t; vec2 uv;
        if (intersect_triangle(o, d, i, hit.t, t, uv) && t > t_min) { hit.t = t; hit.triangle = i; hit.barycentric = uv; found = true; } }
    return found;
}
bool trace_any(vec3 o, vec3 d, float t_min, float t_max) { Hit h; return trace_closest(o, d, t_min, t_max, h); }
vec3 hit_normal(Hit h) { Triangle t = triangles[h.triangle]; vec2 b = h.barycentric;
    return normalize(t.n0.xyz * (1.0 - b.x - b.y) + t.n1.xyz * b.x + t.n2.xyz * b.y); }
vec3 hit_geometric_normal(Hit h) { Triangle t = triangles[h.triangle]; return normalize(cross(t.p1.xyz - t.p0.xyz, t.p2.xyz - t.p0.xyz)); }
uint hit_material(Hit h) { return floatBitsToUint(triangles[h.triangle].p0.w); }
#endif
