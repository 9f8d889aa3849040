// beams (Liktor & Dachsbacher 2011): the caustic beam, its area function
// what a camera ray gathers from it, and its footprint on the receivers.
// Shared by the refinement pass (refine.comp, which builds beams), the
// bounding volumes (volume.geom) and their fragments (volume.frag), and the
// caustic triangles (caustic.geom, caustic.frag). Requires scene.glsl,
// beams_bindings.glsl, optics.glsl, bvh.glsl, random.glsl, medium.glsl.
#ifndef BEAMS_BEAM_GLSL
#define BEAMS_BEAM_GLSL

// One caustic beam (Sect. 4.3, Fig. 2): a base triangle v0 v1 v2 and three
// edge rays v_k + y e_k. Beam space (Ernst et al. 2005): the base lies in
// the plane dot(x, n) = n.w, y = dot(x, n) - n.w is the height above it,
// and the edge directions are scaled so that dot(e_k, n) = 1, so the
// cross-section parallel to the base at height y is the triangle
// v_k + y e_k and its signed area is the quadratic
//   A(y) = area.x + area.y y + area.z y^2 = dot(area.xyz, vec3(1, y, y^2)).
// Mirrors `GpuBeam` in src/techniques/beams/tracer.rs.
struct Beam {
    vec4 v0;       // base vertex 0; w: y_max, the extrusion (height of the far end)
    vec4 v1;       // w: refinement level (uint bits)
    vec4 v2;       // w: BEAM_REFLECTED or BEAM_REFRACTED (uint bits)
    vec4 e0;       // edge direction, dot(e, n) = 1; w: bounce, 1 at the first specular event (uint bits)
    vec4 e1;       // w: the parent beam's index, ~0u for the first event's (uint bits)
    vec4 e2;       // w: > 0 where the beam ends on a further specular surface (Sect. 6): the lowest height its edges meet it
    vec4 n;        // unit normal of the base plane; w: the plane's offset dot(v_k, n)
    vec4 area;     // A(y) coefficients (m^2, signed); w: measure of the incident triangle (sr or m^2)
    vec4 flux;     // rgb: flux carried by the beam (W)
    vec4 incident; // rgb: flux entering the base triangle from the light (W), before Fresnel and absorption
    vec4 receiver; // xyz: heights y_k where edge k meets its first diffuse surface; w: that surface's object (uint bits), ~0u where the three do not meet one
};

float beam_area(Beam b, float y) { return dot(b.area.xyz, vec3(1.0, y, y * y)); }

bool same_sign(vec3 a) {
    return (all(greaterThanEqual(a, vec3(0.0))) || all(lessThanEqual(a, vec3(0.0)))) && any(notEqual(a, vec3(0.0)));
}

// The beam's local (unnormalised) direction at barycentric lam: the
// interpolated edge direction, dot(e, n) = 1, so |e| = 1 / dot(d, n).
vec3 beam_direction(Beam b, vec3 lam) {
    return lam.x * b.e0.xyz + lam.y * b.e1.xyz + lam.z * b.e2.xyz;
}

// Transmittance from a to b (the medium's bounds clip it; solid objects on
// the way are ignored, as volume_lines does).
vec3 bm_transmittance(vec3 a, vec3 b, uint steps) {
    float len = length(b - a);
    if (len <= 0.0) return vec3(1.0);
    return medium_transmittance_steps(a, (b - a) / len, len, steps);
}

// What beam b delivers at x (inside it, at height y, barycentric lam):
// the flux density across the beam E_perp = Phi / (A(y) |d . n|) (A(y) is
// the cross-section parallel to the base, so the one perpendicular to the
// local direction d is A(y) |d . n|), times the medium's transmittance
// along the beam from its base (the light side up to the base is in Phi
// already). Also returns d and the path length s1 from the base.
vec3 beam_flux_density(Beam b, vec3 x, float y, vec3 lam, uint steps, out vec3 d, out float s1) {
    vec3 e = beam_direction(b, lam);
    float el = length(e);
    d = e / el;
    s1 = max(y, 0.0) * el; // |e| y: the length of the edge ray from the base to height y
    float a = abs(beam_area(b, y));
    if (!(a > 0.0)) return vec3(0.0);
    return b.flux.rgb * el / a * bm_transmittance(x - s1 * d, x, steps);
}

// --- In-scattering along a camera ray (Sect. 5) -------------------------

// Real roots of c0 + c1 t + c2 t^2 in (lo, hi), appended to p[count..].
void quadratic_roots(float c0, float c1, float c2, float lo, float hi, inout float p[8], inout int count) {
    float r[2];
    int m = 0;
    float scale = max(max(abs(c0), abs(c1)), abs(c2));
    if (scale == 0.0) return;
    if (abs(c2) <= 1e-7 * scale) {
        if (abs(c1) > 0.0) { r[0] = -c0 / c1; m = 1; }
    } else {
        float disc = c1 * c1 - 4.0 * c2 * c0;
        if (disc >= 0.0) {
            // The numerically stable pair (no cancellation).
            float q = -0.5 * (c1 + (c1 >= 0.0 ? 1.0 : -1.0) * sqrt(disc));
            r[0] = q / c2;
            r[1] = q != 0.0 ? c0 / q : r[0];
            m = 2;
        }
    }
    for (int i = 0; i < m; ++i) {
        if (r[i] > lo && r[i] < hi && count < 8) p[count++] = r[i];
    }
}

// Gauss-Legendre nodes and weights on [-1, 1], 1 to 4 points.
void gauss_legendre(uint n, uint i, out float x, out float w) {
    if (n <= 1u) { x = 0.0; w = 2.0; return; }
    if (n == 2u) { x = i == 0u ? -0.5773502692 : 0.5773502692; w = 1.0; return; }
    if (n == 3u) {
        x = i == 0u ? -0.7745966692 : (i == 1u ? 0.0 : 0.7745966692);
        w = i == 1u ? 0.8888888889 : 0.5555555556;
        return;
    }
    const float xs[4] = float[4](-0.8611363116, -0.3399810436, 0.3399810436, 0.8611363116);
    const float ws[4] = float[4](0.3478548451, 0.6521451549, 0.6521451549, 0.3478548451);
    x = xs[i];
    w = ws[i];
}

// sigma_s at x (1/m): 0 outside the medium's bounds or without a medium.
vec3 bm_sigma_s(vec3 x) {
    if (!medium_present()) return vec3(0.0);
#ifdef MEDIUM_HOMOGENEOUS_ONLY
    return inside_medium_bounds(x) ? medium.sigma_s.rgb * medium.bounds_min.w : vec3(0.0);
#else
    return medium.sigma_s.rgb * medium_density(x);
#endif
}

// Radiance beam b scatters toward the eye along the unit camera ray
// eye + t w, t < t_surface (fragments behind the first surface the pixel
// sees contribute up to it only). Sect. 5's integral
//   L = int sigma_s(x) p(d . -w) E_perp(x) tau(x, eye) dt
// over the exact interval(s) of the ray inside the beam (instead of the
// paper's scan-plane estimate and single midpoint: along the ray the
// height y is linear in t and the three sub-areas quadratic, so the
// interval ends are their roots), each integrated by `points`-point
// Gauss-Legendre (E_perp varies as 1 / A(y): no closed form).
vec3 beam_inscatter(Beam b, vec3 eye, vec3 w, float t_surface, uint points, uint steps) {
    vec3 n = b.n.xyz;
    // t measured from the ray point nearest the base's base_centre, so the
    // quadratics' coefficients do not cancel.
    vec3 base_centre = (b.v0.xyz + b.v1.xyz + b.v2.xyz) / 3.0;
    float tc = dot(base_centre - eye, w);
    vec3 o = eye + tc * w;
    float lo = -tc, hi = t_surface - tc;
    // The slab 0 <= y <= y_max.
    float yo = dot(o, n) - b.n.w, yw = dot(w, n);
    float y_max = b.v0.w;
    if (abs(yw) > 1e-12) {
        float ta = (0.0 - yo) / yw, tb = (y_max - yo) / yw;
        lo = max(lo, min(ta, tb));
        hi = min(hi, max(ta, tb));
    } else if (yo < 0.0 || yo > y_max) {
        return vec3(0.0);
    }
    if (!(hi > lo)) return vec3(0.0);
    // Sub-areas along the ray: c_k - x = P_k + t Q_k.
    vec3 p0 = b.v0.xyz - o + yo * b.e0.xyz, q0 = yw * b.e0.xyz - w;
    vec3 p1 = b.v1.xyz - o + yo * b.e1.xyz, q1 = yw * b.e1.xyz - w;
    vec3 p2 = b.v2.xyz - o + yo * b.e2.xyz, q2 = yw * b.e2.xyz - w;
    vec3 a0 = 0.5 * vec3(dot(n, cross(p1, p2)), dot(n, cross(p2, p0)), dot(n, cross(p0, p1)));
    vec3 a1 = 0.5 * vec3(dot(n, cross(p1, q2) + cross(q1, p2)), dot(n, cross(p2, q0) + cross(q2, p0)),
                         dot(n, cross(p0, q1) + cross(q0, p1)));
    vec3 a2 = 0.5 * vec3(dot(n, cross(q1, q2)), dot(n, cross(q2, q0)), dot(n, cross(q0, q1)));
    float p[8];
    int count = 0;
    p[count++] = lo;
    for (int k = 0; k < 3; ++k) quadratic_roots(a0[k], a1[k], a2[k], lo, hi, p, count);
    if (count < 8) p[count++] = hi;
    // Insertion sort (at most 8).
    for (int i = 1; i < count; ++i) {
        float v = p[i];
        int j = i - 1;
        while (j >= 0 && p[j] > v) { p[j + 1] = p[j]; --j; }
        p[j + 1] = v;
    }
    float g = medium.sigma_s.w;
    vec3 sum = vec3(0.0);
    for (int i = 0; i + 1 < count; ++i) {
        float ta = p[i], tb = p[i + 1];
        if (!(tb > ta)) continue;
        float tm = 0.5 * (ta + tb);
        if (!same_sign(a0 + tm * (a1 + tm * a2))) continue;
        float half_len = 0.5 * (tb - ta);
        for (uint k = 0u; k < max(points, 1u); ++k) {
            float xk, wk;
            gauss_legendre(points, k, xk, wk);
            float t = tm + half_len * xk;
            vec3 sub = a0 + t * (a1 + t * a2);
            float total = sub.x + sub.y + sub.z;
            if (total == 0.0) continue;
            vec3 x = o + t * w;
            float y = yo + yw * t;
            vec3 d;
            float s1;
            vec3 e_perp = beam_flux_density(b, x, y, sub / total, steps, d, s1);
            sum += wk * half_len * bm_sigma_s(x) * hg_phase(dot(d, -w), g) * e_perp * bm_transmittance(eye, x, steps);
        }
    }
    return sum;
}

// --- Surface caustics (Sect. 5.3): the caustic triangle ----------------

// Whether the beam's three edge rays meet one diffuse surface: then the
// beam's footprint there (beam ∩ receiver) is the caustic triangle of
// their hits c_k = v_k + y_k e_k (beam_caustic_triangle), which the
// surface gather (caustic.frag) spreads over the pixels it covers.
bool beam_has_receiver(Beam b) { return floatBitsToUint(b.receiver.w) != ~0u; }

void beam_caustic_triangle(Beam b, out vec3 c[3]) {
    c[0] = b.v0.xyz + b.receiver.x * b.e0.xyz;
    c[1] = b.v1.xyz + b.receiver.y * b.e1.xyz;
    c[2] = b.v2.xyz + b.receiver.z * b.e2.xyz;
}

// True if no diffuse surface lies on the segment from x to the beam's base
// point `base` (the beam reaches x: its light arrives unblocked). Specular
// surfaces are passed, as the edge rays of a beam that does not bounce on
// pass them, and so is the emitting surface itself, which between the base
// vertices bulges past the base plane.
bool beam_path_clear(vec3 x, vec3 base) {
    vec3 d = base - x;
    float left = length(d);
    if (!(left > 0.0)) return true;
    d /= left;
    vec3 o = x;
    for (int i = 0; i < 16 && left > 0.0; ++i) {
        Hit h;
        if (!trace_closest(o, d, 0.0, left, h)) return true;
        if (material_kind(hit_material(h)) == MATERIAL_DIFFUSE) return false;
        vec3 p = hit_position(h, o, d);
        float eps = 1e-4 * max(1.0, bvh_max_abs(p));
        o = p + d * eps;
        left -= h.t + eps;
    }
    return true;
}

#endif
