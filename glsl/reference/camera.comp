#version 460
// Ground truth, camera side (GUIDE §3). A light tracer cannot connect a
// diffuse point to the eye through glass or a mirror (a delta BSDF sits on
// the connection), so a pixel whose camera ray meets a specular surface first
// follows the specular chain from the eye (Fresnel-weighted random choice at
// dielectrics, absorption inside, medium transmittance, the (n_t/n_i)^2 of
// radiance at each refraction) to its first diffuse point x, a visible point.
// There, per pass and pixel:
//   - direct light by a shadow ray to each light (path L D S+ E, the direct
//     component), unbiased;
//   - the visible point is stored in a hash grid; the photon pass that
//     follows adds every photon landing within r of it on the side the
//     camera sees, except photons straight from the light (those are the
//     direct light above): L S+ D S+ E, L D+ D S+ E, L V D S+ E (trace.comp).
// Emitters (L S* E, the emitted component): a camera path that escapes adds
// the environment's radiance, one that meets an area light's front face
// adds its radiance, whether directly (depth 0: the background, a lamp) or
// after specular bounces (in a mirror, through glass and water).
// How the path space splits: a pixel sample whose first hit is diffuse is
// the light tracer's (its camera connections, trace.comp); one whose first
// hit is specular is this pass's. So no path is counted twice.
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
    uint index = p.y * image_width() + p.x;
    // A stream apart from the photon pass's (same seed, other constant).
    uint rng = rng_seed(index, pc.seed ^ 0x68bc21ebu);
    SpecularState s = camera_ray(p, rng);
    VisiblePoint vp;
    vp.position = vec4(0.0);
    vp.normal = vec4(0.0);
    vp.weight = vec4(0.0);

    for (uint depth = 0u; depth < pc.max_depth; ++depth) {
        Hit hit;
        if (!trace_closest(s.origin, s.dir, 0.0, 1e30, hit)) {
            // Escaped: the environment, seen directly or through the chain
            // (L S* E, the emitted component).
            if (environment_present() && !s.inside) {
                float travel = 2.0 * frame.scene_sphere.w + length(s.origin - frame.scene_sphere.xyz);
                vec3 tr = medium_transmittance(s.origin, s.dir, travel, rng);
                add_pass(index, COMPONENT_EMITTED, s.weight * tr * environment_radiance(s.dir));
            }
            break;
        }
        Material m = materials[hit_material(hit)];
        bool diffuse = floatBitsToUint(m.color.w) == MATERIAL_DIFFUSE;
        vec3 ng = hit_geometric_normal(hit);
        bool front = dot(s.dir, ng) < 0.0;
        // An area light's front face, seen directly or through the chain.
        if (diffuse && front && any(greaterThan(m.emission.rgb, vec3(0.0)))) {
            vec3 tr = s.inside ? exp(-s.inside_absorption * hit.t) : medium_transmittance(s.origin, s.dir, hit.t, rng);
            add_pass(index, COMPONENT_EMITTED, s.weight * tr * m.emission.rgb);
        }
        // A `mixed` material: a diffuse one with a mirror part.
        vec3 mirror = diffuse ? m.specular.rgb : vec3(0.0);
        bool mixed = any(greaterThan(mirror, vec3(0.0)));
        // The first hit is diffuse: the light tracer covers this sample (of
        // a mixed material, its diffuse part; the mirror part goes on below).
        if (diffuse && depth == 0u && !mixed) break;
        vec3 x = s.origin + hit.t * s.dir;
        // Every segment's attenuation: absorption inside glass, the medium outside.
        if (s.inside) s.weight *= exp(-s.inside_absorption * hit.t);
        else s.weight *= medium_transmittance(s.origin, s.dir, hit.t, rng);
        if (diffuse) {
            vec3 albedo = hit_albedo(hit);
            // Past the first hit a mixed material's diffuse part (the visible
            // point) is taken with probability p = lum(albedo) / (lum(albedo)
            // + lum(specular)), else its mirror part, the weight divided by
            // the choice's probability; at the first hit only the mirror
            // part (weight specular), the light tracer having the rest.
            bool take_diffuse = depth > 0u;
            if (mixed && take_diffuse) {
                float p = luminance(albedo) / (luminance(albedo) + luminance(mirror));
                take_diffuse = rng_next(rng) < p;
                s.weight /= take_diffuse ? p : 1.0 - p;
            }
            if (!take_diffuse) {
                mirror_bounce(s, x, ng, hit_normal(hit), front, mirror);
                continue;
            }
            vec3 seen_side = front ? ng : -ng;
            add_pass(index, COMPONENT_DIRECT, s.weight * direct_light(x, seen_side, albedo, rng));
            vec3 weight = s.weight * albedo / PI;
            if (pc.gather != 0u && any(greaterThan(weight, vec3(0.0)))) {
                vp.position = vec4(x, 1.0);
                vp.normal = vec4(seen_side, 0.0);
                vp.weight = vec4(weight, 0.0);
            }
            break;
        }
        specular_bounce(s, x, ng, hit_normal(hit), front, m, rng_next(rng), true);
    }
    visible_points[index] = vp;
    if (vp.position.w != 0.0) {
        // Push onto the bucket's list (heads were cleared to GRID_NONE).
        uint bucket = grid_bucket(grid_cell(vp.position.xyz, 2.0 * pc.radius), pc.surface_mask);
        surface_next[index] = atomicExchange(surface_heads[bucket], index);
    }
}
