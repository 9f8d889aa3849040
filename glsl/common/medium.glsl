// Participating medium (GUIDE §2): sigma_s, sigma_a in 1/m scaled by a
// density field (constant, procedural noise or a grid), Henyey-Greenstein
// phase. The medium fills its bounds except where solid objects are.
// Requires scene.glsl, optics.glsl, random.glsl.
#ifndef COMMON_MEDIUM_GLSL
#define COMMON_MEDIUM_GLSL

bool medium_present() { return floatBitsToUint(medium.sigma_a.w) != DENSITY_NONE; }

float value_hash(ivec3 p) {
    return float(pcg_hash(uint(p.x) * 73856093u ^ pcg_hash(uint(p.y) * 19349663u ^ pcg_hash(uint(p.z) * 83492791u)))) *
           (1.0 / 4294967296.0);
}

// Trilinear value noise in [0, 1].
float value_noise(vec3 p) {
    ivec3 i = ivec3(floor(p));
    vec3 f = fract(p);
    vec3 w = f * f * (3.0 - 2.0 * f);
    float c000 = value_hash(i), c100 = value_hash(i + ivec3(1, 0, 0));
    float c010 = value_hash(i + ivec3(0, 1, 0)), c110 = value_hash(i + ivec3(1, 1, 0));
    float c001 = value_hash(i + ivec3(0, 0, 1)), c101 = value_hash(i + ivec3(1, 0, 1));
    float c011 = value_hash(i + ivec3(0, 1, 1)), c111 = value_hash(i + ivec3(1, 1, 1));
    return mix(mix(mix(c000, c100, w.x), mix(c010, c110, w.x), w.y),
               mix(mix(c001, c101, w.x), mix(c011, c111, w.x), w.y), w.z);
}

// Fractal sum of value noise normalised back to [0, 1], so the density's
// maximum is exactly the scale (the tracking majorant relies on it).
float fbm(vec3 p, uint octaves) {
    float sum = 0.0, weight = 1.0, total = 0.0;
    for (uint o = 0u; o < max(octaves, 1u); ++o) {
        sum += weight * value_noise(p);
        total += weight;
        weight *= 0.5;
        p *= 2.03;
    }
    return sum / total;
}

bool inside_medium_bounds(vec3 x) {
    return all(greaterThanEqual(x, medium.bounds_min.xyz)) && all(lessThanEqual(x, medium.bounds_max.xyz));
}

// Density multiplier at x (0 outside the bounds).
float medium_density(vec3 x) {
    if (!inside_medium_bounds(x)) return 0.0;
    uint kind = floatBitsToUint(medium.sigma_a.w);
    if (kind == DENSITY_CONSTANT) return medium.bounds_min.w;
    if (kind == DENSITY_NOISE) return medium.bounds_min.w * fbm(x * medium.noise.w + medium.noise.xyz, medium.dims.w);
    if (kind == DENSITY_GRID) {
        vec3 extent = medium.bounds_max.xyz - medium.bounds_min.xyz;
        vec3 g = (x - medium.bounds_min.xyz) / extent * vec3(medium.dims.xyz) - 0.5;
        ivec3 dims = ivec3(medium.dims.xyz);
        ivec3 i0 = clamp(ivec3(floor(g)), ivec3(0), dims - 1);
        ivec3 i1 = min(i0 + 1, dims - 1);
        vec3 f = clamp(g - vec3(i0), 0.0, 1.0);
        #define GRID(ix, iy, iz) density_grid[(iz * dims.y + iy) * dims.x + ix]
        float v = mix(mix(mix(GRID(i0.x, i0.y, i0.z), GRID(i1.x, i0.y, i0.z), f.x),
                          mix(GRID(i0.x, i1.y, i0.z), GRID(i1.x, i1.y, i0.z), f.x), f.y),
                      mix(mix(GRID(i0.x, i0.y, i1.z), GRID(i1.x, i0.y, i1.z), f.x),
                          mix(GRID(i0.x, i1.y, i1.z), GRID(i1.x, i1.y, i1.z), f.x), f.y), f.z);
        #undef GRID
        return v;
    }
    return 0.0;
}

// A scalar majorant of sigma_t over the medium (all channels).
float medium_majorant() {
    vec3 sigma_t = medium.sigma_s.rgb + medium.sigma_a.rgb;
    return max(sigma_t.r, max(sigma_t.g, sigma_t.b)) * medium.bounds_max.w;
}

// Clips the ray o + t d, t in [t0, t1], to the medium bounds. False when it misses.
bool clip_to_medium(vec3 o, vec3 d, inout float t0, inout float t1) {
    vec3 inv = 1.0 / d;
    vec3 a = (medium.bounds_min.xyz - o) * inv;
    vec3 b = (medium.bounds_max.xyz - o) * inv;
    vec3 lo = min(a, b), hi = max(a, b);
    t0 = max(t0, max(lo.x, max(lo.y, lo.z)));
    t1 = min(t1, min(hi.x, min(hi.y, hi.z)));
    return t0 < t1;
}

// Transmittance along o + t d for t in [0, dist] (the segment must be free of
// solid objects). Constant density: Beer-Lambert exactly; otherwise ratio
// tracking against the majorant (an unbiased estimate).
vec3 medium_transmittance(vec3 o, vec3 d, float dist, inout uint rng) {
    if (!medium_present()) return vec3(1.0);
    float t0 = 0.0, t1 = dist;
    if (!clip_to_medium(o, d, t0, t1)) return vec3(1.0);
    vec3 sigma_t = medium.sigma_s.rgb + medium.sigma_a.rgb;
    if (floatBitsToUint(medium.sigma_a.w) == DENSITY_CONSTANT) return exp(-sigma_t * medium.bounds_min.w * (t1 - t0));
    float majorant = medium_majorant();
    if (majorant <= 0.0) return vec3(1.0);
    vec3 tr = vec3(1.0);
    float t = t0;
    for (int i = 0; i < 4096; ++i) {
        t -= log(1.0 - rng_next(rng)) / majorant;
        if (t >= t1) break;
        tr *= 1.0 - sigma_t * medium_density(o + t * d) / majorant;
    }
    return tr;
}

// sigma_t at x (1/m, per channel): the coefficients times the density.
vec3 medium_sigma_t(vec3 x) {
    return (medium.sigma_s.rgb + medium.sigma_a.rgb) * medium_density(x);
}

// Deterministic transmittance for the real-time techniques (Hu et al. 2010
// Sect. 5.4, Fig. 11: "the attenuation ... is computed by ray marching with
// a fixed number of steps"): along o + t d, t in [0, dist], clipped to the
// medium bounds (free of solid objects, as medium_transmittance).
// Constant density: Beer-Lambert exactly, exp(-sigma_t * length). Noise or
// grid: the optical depth by the midpoint rule with `steps` equal steps over
// the clipped segment. Without a medium: exactly 1.
// A shader that defines MEDIUM_HOMOGENEOUS_ONLY before including this file
// guarantees a constant (or no) density and compiles only that case: the
// density field's code costs a CPU rasteriser in every fragment even when
// the branch is not taken (volume_lines' line fragments).
vec3 medium_transmittance_steps(vec3 o, vec3 d, float dist, uint steps) {
    if (!medium_present()) return vec3(1.0);
    float t0 = 0.0, t1 = dist;
    if (!clip_to_medium(o, d, t0, t1)) return vec3(1.0);
    vec3 sigma_t = medium.sigma_s.rgb + medium.sigma_a.rgb;
#ifdef MEDIUM_HOMOGENEOUS_ONLY
    return exp(-sigma_t * medium.bounds_min.w * (t1 - t0));
#else
    if (floatBitsToUint(medium.sigma_a.w) == DENSITY_CONSTANT) return exp(-sigma_t * medium.bounds_min.w * (t1 - t0));
    uint n = max(steps, 1u);
    float dt = (t1 - t0) / float(n);
    float density_sum = 0.0;
    for (uint i = 0u; i < n; ++i) density_sum += medium_density(o + (t0 + (float(i) + 0.5) * dt) * d);
    return exp(-sigma_t * (density_sum * dt));
#endif
}

// The far end of a light's shadow ray from x for transmittance: the light's
// position, or for a directional light far enough to leave the scene
// (the bounds clip it), as the reference's camera pass does.
float light_travel(float dist, vec3 x) {
    return dist > 1e29 ? 2.0 * frame.scene_sphere.w + length(x - frame.scene_sphere.xyz) : dist;
}

// Henyey-Greenstein phase, normalised over the sphere; cos_theta between the
// propagation directions before and after scattering.
float hg_phase(float cos_theta, float g) {
    float denom = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * PI * denom * sqrt(denom));
}

// Samples a new propagation direction around `d` with HG's pdf (exactly hg_phase).
vec3 sample_hg(vec3 d, float g, vec2 u) {
    float cos_t;
    if (abs(g) < 1e-3) {
        cos_t = 1.0 - 2.0 * u.x;
    } else {
        float s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        cos_t = (1.0 + g * g - s * s) / (2.0 * g);
    }
    cos_t = clamp(cos_t, -1.0, 1.0);
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    basis(d, t, b);
    return normalize(t * (sin_t * cos(phi)) + b * (sin_t * sin(phi)) + d * cos_t);
}

#endif
