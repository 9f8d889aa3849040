// The environment light and area lights (GUIDE §2: both in radiance,
// W m^-2 sr^-1): evaluation for any pass, sampling for the reference.
// Mirrors src/environment.rs. Requires scene.glsl and optics.glsl.
//
// Equirectangular convention (docs/SCENES.md): in the image's frame,
// u = phi / 2pi with phi from +x toward +z, v = theta / pi with theta from
// +y (row 0 is straight up); the image frame turns into the world by
// `rotate` about +y.
#ifndef COMMON_EMITTERS_GLSL
#define COMMON_EMITTERS_GLSL

bool environment_present() { return environment.params.x != 0.0; }

// World -> image frame (rotation by -rotate about +y) and back.
vec3 environment_to_image(vec3 d) {
    float c = environment.params.z, s = environment.params.w;
    return vec3(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}
vec3 environment_to_world(vec3 d) {
    float c = environment.params.z, s = environment.params.w;
    return vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

vec2 equirect_uv(vec3 d) {
    float u = atan(d.z, d.x) / (2.0 * PI);
    return vec2(u - floor(u), acos(clamp(d.y, -1.0, 1.0)) / PI);
}

vec3 equirect_dir(vec2 uv) {
    float theta = PI * uv.y, phi = 2.0 * PI * uv.x;
    return vec3(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
}

// The tabulated part (an image, or a sky's gradient), bilinear; repeat in
// u, clamped to texel centres in v so the poles do not wrap.
vec3 environment_table_radiance(vec3 dir) {
    vec2 uv = equirect_uv(environment_to_image(dir));
    float h = environment.table.y;
    uv.y = clamp(uv.y, 0.5 / h, 1.0 - 0.5 / h);
    return textureLod(environment_map, vec3(uv, 0.0), 0.0).rgb;
}

// A sky's sun disc (0 elsewhere and without a sun).
vec3 environment_sun_radiance(vec3 dir) {
    return dot(dir, environment.sun.xyz) >= environment.sun.w ? environment.sun_radiance.rgb : vec3(0.0);
}

// Radiance arriving from direction `dir` (unit, world, pointing away from
// the scene): what an escaping ray sees. 0 without an environment.
vec3 environment_radiance(vec3 dir) {
    if (!environment_present()) return vec3(0.0);
    return environment_table_radiance(dir) + environment_sun_radiance(dir);
}

// Index k with cdf[base + k] <= u < cdf[base + k + 1], k in [0, n).
uint environment_cdf_search(uint base, uint n, float u) {
    uint lo = 0u, hi = n;
    while (hi - lo > 1u) {
        uint mid = (lo + hi) / 2u;
        if (environment_cdf[base + mid] <= u) lo = mid;
        else hi = mid;
    }
    return lo;
}

// Samples a direction of the tabulated part by its luminance (times texel
// solid angle; src/environment.rs sampling_tables): a row by the marginal
// CDF, a column by the row's CDF, a uniform point in the texel. `pdf` is per
// unit solid angle: p(u, v) / (2 pi^2 sin theta), the equirectangular
// Jacobian (d omega = 2 pi^2 sin theta du dv).
vec3 sample_environment_table(vec2 u, out float pdf) {
    uint w = uint(environment.table.x), h = uint(environment.table.y);
    uint j = environment_cdf_search(0u, h, u.x);
    float r0 = environment_cdf[j], p_row = environment_cdf[j + 1u] - r0;
    uint base = h + 1u + j * (w + 1u);
    uint i = environment_cdf_search(base, w, u.y);
    float c0 = environment_cdf[base + i], p_col = environment_cdf[base + i + 1u] - c0;
    vec2 within = clamp(vec2((u.y - c0) / max(p_col, 1e-30), (u.x - r0) / max(p_row, 1e-30)), 0.0, 1.0);
    vec2 uv = (vec2(float(i), float(j)) + within) / vec2(float(w), float(h));
    float sin_theta = max(sin(PI * uv.y), 1e-7);
    pdf = p_row * p_col * float(w) * float(h) / (2.0 * PI * PI * sin_theta);
    return environment_to_world(equirect_dir(uv));
}

// Unoccluded irradiance at x (normal n) from a Lambertian polygon of
// radiance `radiance`, its `count` (3 or 4) corners q relative to x,
// emitting to the side `nr` points to: Lambert's polygon formula,
// E = L/2 |sum_i Theta_i (n . gamma_i)| with Theta_i the angle edge i
// subtends at x and gamma_i the unit normal of the plane through x and
// that edge (Arvo 1995, "Applications of Irradiance Tensors to the
// Simulation of Non-Lambertian Phenomena", Sect. 3), after clipping the
// polygon to the receiver's upper half-space; 0 behind the emitting side.
// Exact.
vec3 polygon_irradiance(vec3 q[4], int count, vec3 nr, vec3 radiance, vec3 n) {
    if (dot(-q[0], nr) <= 0.0) return vec3(0.0);
    vec3 p[8];
    int m = 0;
    for (int i = 0; i < count; ++i) {
        vec3 a = q[i], b = q[(i + 1) % count];
        float da = dot(a, n), db = dot(b, n);
        if (da >= 0.0) p[m++] = a;
        if ((da >= 0.0) != (db >= 0.0)) p[m++] = a + (b - a) * (da / (da - db));
    }
    float sum = 0.0;
    for (int i = 0; i < m; ++i) {
        vec3 a = normalize(p[i]), b = normalize(p[(i + 1) % m]);
        vec3 g = cross(a, b);
        float len = length(g);
        if (len < 1e-12) continue;
        sum += atan(len, dot(a, b)) * dot(g / len, n);
    }
    return radiance * (0.5 * abs(sum));
}

// Rect area light `em` (polygon_irradiance).
vec3 rect_irradiance(Emitter em, vec3 x, vec3 n) {
    vec3 c = em.position.xyz, nr = em.normal.xyz, t = em.tangent.xyz;
    vec3 hu = t * (0.5 * em.normal.w), hv = cross(nr, t) * (0.5 * em.tangent.w);
    vec3 q[4] = vec3[4](c - hu - hv - x, c + hu - hv - x, c + hu + hv - x, c - hu + hv - x);
    return polygon_irradiance(q, 4, nr, em.radiance.rgb, n);
}

// Emissive triangle `em` (EMITTER_TRIANGLE; polygon_irradiance).
vec3 triangle_irradiance(Emitter em, vec3 x, vec3 n) {
    vec3 p0 = em.position.xyz - x, e1 = em.normal.xyz, e2 = em.tangent.xyz;
    vec3 q[4] = vec3[4](p0, p0 + e1, p0 + e2, p0);
    return polygon_irradiance(q, 3, normalize(cross(e1, e2)), em.radiance.rgb, n);
}

// Unoccluded irradiance at x (normal n) from sphere light `em`: a
// Lambertian sphere of radiance L seen whole above the receiver's horizon
// gives exactly E = pi L (r/d)^2 cos(omega) (it acts as a point of
// intensity pi r^2 L); where the sphere dips below the horizon (within r of
// the receiver's plane) this clamped form is an approximation.
vec3 sphere_irradiance(Emitter em, vec3 x, vec3 n) {
    vec3 v = em.position.xyz - x;
    float d2 = dot(v, v);
    float r = em.normal.w;
    if (d2 <= r * r) return vec3(0.0);
    return em.radiance.rgb * (PI * r * r / d2) * max(dot(n, v * inversesqrt(d2)), 0.0);
}

// The point area light e's shadow is taken from (its centre; an emissive
// triangle's centroid) as seen from x: the direction toward it and how far
// a shadow ray may go before it would meet the light's own geometry.
void emitter_shadow_target(uint e, vec3 x, out vec3 to_light, out float reach) {
    Emitter em = emitters[e];
    uint kind = floatBitsToUint(em.position.w);
    vec3 target = kind == EMITTER_TRIANGLE
        ? em.position.xyz + (em.normal.xyz + em.tangent.xyz) / 3.0
        : em.position.xyz;
    vec3 v = target - x;
    float d = length(v);
    to_light = v / max(d, 1e-30);
    reach = kind == EMITTER_RECT || kind == EMITTER_TRIANGLE
        ? d * (1.0 - 1e-3)
        : d - em.normal.w * 1.001; // short of the inscribed tessellation
}

// The unoccluded irradiance from area light e, with its shadow target
// (emitter_shadow_target).
vec3 emitter_irradiance(uint e, vec3 x, vec3 n, out vec3 to_light, out float reach) {
    emitter_shadow_target(e, x, to_light, reach);
    Emitter em = emitters[e];
    uint kind = floatBitsToUint(em.position.w);
    if (kind == EMITTER_TRIANGLE) return triangle_irradiance(em, x, n);
    if (kind == EMITTER_RECT) return rect_irradiance(em, x, n);
    return sphere_irradiance(em, x, n);
}

// Whether the ray origin + t dir (unit dir, t > 0) meets the sphere of
// radius r around `centre`.
bool ray_meets_sphere(vec3 origin, vec3 dir, vec3 centre, float r) {
    vec3 oc = centre - origin;
    float tc = dot(oc, dir);
    return tc > 0.0 && dot(oc, oc) - tc * tc <= r * r;
}

// Solid angle of the sphere of radius r around `centre` seen from `origin`:
// the cap 2 pi (1 - sqrt(1 - r^2/D^2)); 4 pi from inside.
float sphere_solid_angle(vec3 origin, vec3 centre, float r) {
    float d2 = dot(centre - origin, centre - origin);
    if (d2 <= r * r) return 4.0 * PI;
    float s2 = r * r / d2;
    // 1 - sqrt(1 - s2) without cancellation.
    return 2.0 * PI * s2 / (1.0 + sqrt(1.0 - s2));
}

// Radiance of area light e seen from `origin` along unit `dir`: its
// radiance where the ray meets it (a rect only from its emitting side),
// else 0. The light's own geometry is not consulted: what an environment
// map of the emitters holds (glsl/pinhole/light_maps.comp).
vec3 area_emitter_radiance(uint e, vec3 origin, vec3 dir) {
    Emitter em = emitters[e];
    if (floatBitsToUint(em.position.w) == EMITTER_SPHERE) {
        return ray_meets_sphere(origin, dir, em.position.xyz, em.normal.w) ? em.radiance.rgb : vec3(0.0);
    }
    vec3 nr = em.normal.xyz;
    float facing = -dot(dir, nr);
    float h = dot(origin - em.position.xyz, nr); // height above the emitting side
    if (facing <= 0.0 || h <= 0.0) return vec3(0.0);
    vec3 q = origin + dir * (h / facing) - em.position.xyz;
    vec3 t = em.tangent.xyz;
    bool inside = abs(dot(q, t)) <= 0.5 * em.normal.w && abs(dot(q, cross(nr, t))) <= 0.5 * em.tangent.w;
    return inside ? em.radiance.rgb : vec3(0.0);
}

// Solid angle of the triangle (a, b, c) (vectors from the viewpoint):
// tan(Omega / 2) = |a . (b x c)| / (|a||b||c| + (a.b)|c| + (a.c)|b| +
// (b.c)|a|) (Van Oosterom & Strackee 1983, "The Solid Angle of a Plane
// Triangle", IEEE Trans. Biomed. Eng. 30(2)).
float triangle_solid_angle(vec3 a, vec3 b, vec3 c) {
    float la = length(a), lb = length(b), lc = length(c);
    float num = abs(dot(a, cross(b, c)));
    float den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    return 2.0 * atan(num, den);
}

// Solid angle area light e subtends from `origin`: the sphere's cap, the
// rect's two triangles (0 behind its emitting side, which is dark).
float area_emitter_solid_angle(uint e, vec3 origin) {
    Emitter em = emitters[e];
    if (floatBitsToUint(em.position.w) == EMITTER_SPHERE) return sphere_solid_angle(origin, em.position.xyz, em.normal.w);
    vec3 c = em.position.xyz - origin, nr = em.normal.xyz, t = em.tangent.xyz;
    if (dot(c, nr) >= 0.0) return 0.0;
    vec3 hu = t * (0.5 * em.normal.w), hv = cross(nr, t) * (0.5 * em.tangent.w);
    vec3 p0 = c - hu - hv, p1 = c + hu - hv, p2 = c + hu + hv, p3 = c - hu + hv;
    return triangle_solid_angle(p0, p1, p2) + triangle_solid_angle(p0, p2, p3);
}

// The solid angle of a sky's sun disc, 2 pi (1 - cos alpha); 0 without one.
float environment_sun_solid_angle() {
    if (!environment_present() || environment.sun.w > 1.0) return 0.0;
    return 2.0 * PI * (1.0 - environment.sun.w);
}

// The environment's sun as a directional light: a sky's sun, E = L 2 pi
// (1 - cos alpha), or the sun found in an image (src/environment.rs
// extract_sun; the reference samples it as part of the table). `to_sun`:
// toward it. For techniques that need a directional light (`direct`).
vec3 environment_sun_irradiance(out vec3 to_sun) {
    to_sun = environment.sun.xyz;
    if (!environment_present()) return vec3(0.0);
    if (environment.sun.w <= 1.0) return environment.sun_radiance.rgb * (2.0 * PI * (1.0 - environment.sun.w));
    to_sun = environment.image_sun_direction.xyz;
    return environment.image_sun_peak.w <= 1.0 ? environment.image_sun_irradiance.rgb : vec3(0.0);
}

// Whether an image texel (direction d, world; radiance l) belongs to the
// image's sun, which `direct` takes as a directional light instead.
bool environment_image_sun_texel(vec3 d, vec3 l) {
    return environment.image_sun_peak.w <= 1.0 && dot(d, environment.image_sun_peak.xyz) >= environment.image_sun_peak.w
        && luminance(l) > environment.image_sun_direction.w;
}

#endif
