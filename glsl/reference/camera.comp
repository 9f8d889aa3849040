#version 460
// Ground truth, camera side: light tracing cannot connect a diffuse point to
// the eye through glass or a mirror (a delta BSDF in between), so pixels whose
// camera ray meets a specular surface first follow the specular chain from
// the eye (Fresnel-weighted random choice at dielectrics, absorption inside,
// medium transmittance along the way) to a diffuse surface and add its
// direct light there (path L D S+ E, counted in the direct component). One
// jittered sample per pixel per pass; resolve divides by the passes.
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

vec3 direct_light(vec3 x, vec3 n, vec3 albedo, inout uint rng) {
    vec3 sum = vec3(0.0);
    for (uint l = 0u; l < frame.counts.x; ++l) {
        vec3 to_light;
        float dist;
        vec3 e = light_irradiance(l, x, n, to_light, dist);
        if (all(equal(e, vec3(0.0)))) continue;
        vec3 o = offset_origin(x, n);
        float reach = dist > 1e29 ? 1e30 : dist * (1.0 - 1e-4);
        if (trace_any(o, to_light, 0.0, reach)) continue;
        float travel = dist > 1e29 ? 2.0 * frame.scene_sphere.w + length(x - frame.scene_sphere.xyz) : dist;
        sum += e * medium_transmittance(o, to_light, travel, rng);
    }
    return albedo / PI * sum;
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= image_width() || p.y >= image_height()) return;
    // A stream apart from the photon pass's (same seed, other constant).
    uint rng = rng_seed(p.y * image_width() + p.x, pc.seed ^ 0x68bc21ebu);
    vec2 jitter = vec2(rng_next(rng), rng_next(rng));
    vec2 ndc = (vec2(p) + jitter) / frame.viewport.xy * 2.0 - 1.0;
    vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    SpecularState s;
    s.origin = frame.eye.xyz;
    s.dir = normalize(far.xyz / far.w - s.origin);
    s.weight = vec3(1.0);
    s.inside = false;
    s.inside_absorption = vec3(0.0);

    vec3 result = vec3(0.0);
    for (uint depth = 0u; depth < pc.max_depth; ++depth) {
        Hit hit;
        if (!trace_closest(s.origin, s.dir, 0.0, 1e30, hit)) break;
        Material m = materials[hit_material(hit)];
        bool diffuse = floatBitsToUint(m.color.w) == MATERIAL_DIFFUSE;
        // The first hit is diffuse: the photon pass already covers this pixel.
        if (diffuse && depth == 0u) break;
        vec3 x = s.origin + hit.t * s.dir;
        // Every segment's attenuation: absorption inside glass, the medium outside.
        if (s.inside) s.weight *= exp(-s.inside_absorption * hit.t);
        else s.weight *= medium_transmittance(s.origin, s.dir, hit.t, rng);
        vec3 ng = hit_geometric_normal(hit);
        bool front = dot(s.dir, ng) < 0.0;
        if (diffuse) {
            result = s.weight * direct_light(x, front ? ng : -ng, m.color.rgb, rng);
            break;
        }
        specular_bounce(s, x, ng, hit_normal(hit), front, m, rng_next(rng));
    }
    uint base = (p.y * image_width() + p.x) * 3u;
    camera_accum[base + 0u] += result.r;
    camera_accum[base + 1u] += result.g;
    camera_accum[base + 2u] += result.b;
}
