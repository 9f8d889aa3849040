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
    uint rng = rng_seed(p.y * image_width() + p.x, pc.seed);
    vec2 jitter = vec2(rng_next(rng), rng_next(rng));
    vec2 ndc = (vec2(p) + jitter) / frame.viewport.xy * 2.0 - 1.0;
    vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    vec3 o = frame.eye.xyz;
    vec3 d = normalize(far.xyz / far.w - o);

    vec3 throughput = vec3(1.0);
    bool inside = false;
    vec3 inside_absorption = vec3(0.0);
    vec3 result = vec3(0.0);
    for (uint depth = 0u; depth < pc.max_depth; ++depth) {
        Hit hit;
        if (!trace_closest(o, d, 0.0, 1e30, hit)) break;
        vec3 x = o + hit.t * d;
        if (inside) throughput *= exp(-inside_absorption * hit.t);
        else if (depth > 0u) throughput *= medium_transmittance(o, d, hit.t, rng);
        vec3 ng = hit_geometric_normal(hit);
        vec3 ns = hit_normal(hit);
        bool front = dot(d, ng) < 0.0;
        vec3 ng_in = front ? ng : -ng;
        vec3 ns_in = dot(ns, ng_in) > 0.0 ? ns : -ns;
        Material m = materials[hit_material(hit)];
        uint kind = floatBitsToUint(m.color.w);
        if (kind == MATERIAL_DIFFUSE) {
            // The first hit is diffuse: the photon pass already covers this pixel.
            if (depth > 0u) result = throughput * direct_light(x, ng_in, m.color.rgb, rng);
            break;
        } else if (kind == MATERIAL_MIRROR) {
            throughput *= m.color.rgb;
            d = reflect(d, ns_in);
            o = offset_origin(x, ng_in);
        } else {
            float ior = m.absorption_ior.w;
            float eta = front ? 1.0 / ior : ior;
            float f = fresnel_dielectric(-dot(d, ns_in), eta);
            vec3 refracted;
            if (rng_next(rng) < f || !refract_dir(d, ns_in, eta, refracted)) {
                d = reflect(d, ns_in);
                o = offset_origin(x, ng_in);
            } else {
                d = refracted;
                o = offset_origin(x, -ng_in);
                inside = front;
                inside_absorption = m.absorption_ior.rgb;
            }
        }
    }
    // The eye's own segment to the first specular hit is attenuated here too.
    uint base = (p.y * image_width() + p.x) * 3u;
    if (any(greaterThan(result, vec3(0.0)))) {
        Hit first;
        vec3 d0 = normalize(far.xyz / far.w - frame.eye.xyz);
        if (trace_closest(frame.eye.xyz, d0, 0.0, 1e30, first)) {
            result *= medium_transmittance(frame.eye.xyz, d0, first.t, rng);
        }
    }
    camera_accum[base + 0u] += result.r;
    camera_accum[base + 1u] += result.g;
    camera_accum[base + 2u] += result.b;
}
