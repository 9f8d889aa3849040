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

#endif
