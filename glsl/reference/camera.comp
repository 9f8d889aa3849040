#version 460
// Ground truth, camera side (GUIDE §3). A light tracer cannot connect a
// diffuse point to the eye through glass or a mirror (a delta BSDF sits on
// the connection), so a pixel whose camera ray meets a specular surface first
// follows the specular chain from the eye (Fresnel-weighted random choice at
// dielectrics, absorption inside, medium transmittance, the (n_t/n_i)^2 of
// radiance at each refraction) to its first diffuse point x, a visible point.
// There, per pass and pixel:
//   - direct light by a shadow ray to each light (path L D S+ E, the direct
//     component), unbiased; so too at a diffuse first hit (L D E);
//   - the visible point is stored in a hash grid; the photon pass that
//     follows adds every photon landing within r of it on the side the
//     camera sees, except photons straight from the light (those are the
//     direct light above): L S+ D S+ E, L D+ D S+ E, L V D S+ E (trace.comp).
// Emitters (L S* E, the emitted component): EMISSION_GRID^2 camera chains
// of their own a pixel and pass (`chain_emission`) add the environment's
// radiance where they escape and an area light's where they meet its front
// face, whether directly (the background, a lamp) or after specular bounces
// (in a mirror, through glass and water).
// How the path space splits: the direct light of the point, spot,
// directional, rect and triangle lights is this pass's, by shadow rays,
// which converge far sooner than photons: at every pixel's diffuse point,
// seen directly or through a specular chain (L D S* E), and along the
// camera ray's first segment (single scattering, L V E). Of
// every other path, a pixel sample whose first hit is diffuse is the light
// tracer's (its camera connections, trace.comp), one whose first hit is
// specular this pass's (the photon gather). So no path is counted twice.
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// Ratio tracking's transmittance estimate averaged over
// TRANSMITTANCE_ESTIMATES runs: in a heterogeneous medium one run is often
// 0 or 1, and the shadow rays here carry one sample per pixel and pass
// where photons brought thousands (measured on `smoke`: the direct
// image's total varied 0.4% between seeds at 8 M photons with one run).
// Constant density: exact, computed once.
const uint TRANSMITTANCE_ESTIMATES = 8u;
vec3 mean_transmittance(vec3 o, vec3 d, float dist, inout uint rng) {
    if (!medium_present() || floatBitsToUint(medium.sigma_a.w) == DENSITY_CONSTANT) {
        return medium_transmittance(o, d, dist, rng);
    }
    vec3 sum = vec3(0.0);
    for (uint k = 0u; k < TRANSMITTANCE_ESTIMATES; ++k) sum += medium_transmittance(o, d, dist, rng);
    return sum / float(TRANSMITTANCE_ESTIMATES);
}

// The share of a light's arriving irradiance that reaches o along
// `to_light` from `dist` away (directional: 1e30): 0 when something blocks
// the shadow ray, which stops `shorten` (relative) short of the light so as
// not to meet an area light's own triangles, else the medium's
// transmittance.
vec3 light_visibility(vec3 o, vec3 to_light, float dist, float shorten, inout uint rng) {
    float reach = dist > 1e29 ? 1e30 : dist * (1.0 - shorten);
    if (trace_any(o, to_light, 0.0, reach)) return vec3(0.0);
    float travel = dist > 1e29 ? 2.0 * frame.scene_sphere.w + length(o - frame.scene_sphere.xyz) : dist;
    return mean_transmittance(o, to_light, travel, rng);
}

const float PUNCTUAL_SHADOW_SHORTEN = 1e-4;
const float AREA_SHADOW_SHORTEN = 1e-3; // as emitter_shadow_target

// What arrives at x, on a surface facing the light, from the point y (normal
// ny) of an area light sampled uniformly over its area (pdf 1/A):
// L cos_y A / d^2; `to_light` (unit) and `dist` describe the shadow ray.
vec3 area_light_arriving(Emitter em, vec3 y, vec3 ny, float area, vec3 x, out vec3 to_light, out float dist) {
    vec3 v = y - x;
    dist = length(v);
    to_light = v / dist;
    return em.radiance.rgb * (max(-dot(ny, to_light), 0.0) * area / (dist * dist));
}

// Radiance toward the eye from diffuse point x (normal n on the seen side,
// albedo a): the direct light of every light camera.comp samples, each by
// one shadow ray a pass: point, spot and directional lights exactly, rect
// and triangle lights at a point uniform over their area
//     E = L cos_y cos_x A / d^2   (pdf 1/A).
vec3 direct_light(vec3 x, vec3 n, vec3 albedo, inout uint rng) {
    vec3 sum = vec3(0.0);
    vec3 o = offset_origin(x, n);
    for (uint l = 0u; l < frame.counts.x; ++l) {
        vec3 to_light;
        float dist;
        vec3 e = light_irradiance(l, x, n, to_light, dist);
        if (all(equal(e, vec3(0.0)))) continue;
        sum += e * light_visibility(o, to_light, dist, PUNCTUAL_SHADOW_SHORTEN, rng);
    }
    for (uint a = 0u; a < frame.components.y; ++a) {
        Emitter em = emitters[a];
        if (!emitter_sampled_by_camera(em)) continue;
        vec3 y, ny;
        float area;
        sample_emitter_point(em, vec2(rng_next(rng), rng_next(rng)), y, ny, area);
        vec3 w;
        float dist;
        vec3 e = area_light_arriving(em, y, ny, area, x, w, dist) * max(dot(n, w), 0.0);
        if (all(equal(e, vec3(0.0)))) continue;
        sum += e * light_visibility(o, w, dist, AREA_SHADOW_SHORTEN, rng);
    }
    return albedo / PI * sum;
}

// A distance t on [t0, t1] along o + t d for a light at p: equiangular
// (Kulla & Fajardo 2012, "Importance sampling techniques for path tracing in
// participating media", Sect. 4.1: t = delta + D tan(theta), pdf = D /
// ((theta_b - theta_a)(D^2 + (t - delta)^2)), D the light's distance from
// the ray line and delta its foot), which cancels the 1/d^2 near the light;
// a light at infinity (directional): uniform.
float sample_segment(vec3 p, bool at_infinity, vec3 o, vec3 d, float t0, float t1, float u, out float pdf) {
    if (at_infinity) {
        pdf = 1.0 / (t1 - t0);
        return mix(t0, t1, u);
    }
    float foot = dot(p - o, d);
    float D = max(length(p - (o + foot * d)), 1e-6);
    float theta_a = atan((t0 - foot) / D), theta_b = atan((t1 - foot) / D);
    float t = clamp(foot + D * tan(mix(theta_a, theta_b, u)), t0, t1);
    float h = t - foot;
    pdf = D / ((theta_b - theta_a) * (D * D + h * h));
    return t;
}

// Single scattering along the camera ray's first segment, from the eye `o`
// along `d` to `t_end` (L V E, the airlight component): the integral of
// T(o, x_t) sigma_s(x_t) p(theta) E(x_t) V(x_t) dt over the segment's part
// inside the medium (a spot's: inside its cone, `spot_cone_interval`), by
// AIRLIGHT_SAMPLES samples per light and pass, stratified in t
// (`sample_segment`; an area light: each about a point uniform over it,
// E = L cos_y A / d^2). trace.comp leaves these paths to this estimate.
const uint AIRLIGHT_SAMPLES = 4u; // the ball's shadow in a spot's cone needs a few
vec3 airlight(vec3 o, vec3 d, float t_end, inout uint rng) {
    float segment_start = 0.0, segment_end = t_end;
    if (!medium_present() || !clip_to_medium(o, d, segment_start, segment_end) || !(segment_end > segment_start)) {
        return vec3(0.0);
    }
    float g = medium.sigma_s.w;
    vec3 sum = vec3(0.0);
    uint punctual = frame.counts.x;
    for (uint l = 0u; l < punctual + frame.components.y; ++l) {
        bool is_area = l >= punctual;
        Emitter em;
        if (is_area) {
            em = emitters[l - punctual];
            if (!emitter_sampled_by_camera(em)) continue;
        }
        float t0 = segment_start, t1 = segment_end;
        if (!is_area && !spot_cone_interval(l, o, d, t0, t1)) continue;
        bool at_infinity = !is_area && floatBitsToUint(lights[l].position.w) == LIGHT_DIRECTIONAL;
        for (uint k = 0u; k < AIRLIGHT_SAMPLES; ++k) {
            vec3 p = is_area ? vec3(0.0) : lights[l].position.xyz;
            vec3 np = vec3(0.0);
            float area = 0.0;
            if (is_area) sample_emitter_point(em, vec2(rng_next(rng), rng_next(rng)), p, np, area);
            float pdf;
            float u = (float(k) + rng_next(rng)) / float(AIRLIGHT_SAMPLES);
            float t = sample_segment(p, at_infinity, o, d, t0, t1, u, pdf);
            if (!(pdf > 0.0)) continue;
            vec3 x = o + t * d;
            vec3 sigma_s = medium.sigma_s.rgb * medium_density(x);
            if (all(equal(sigma_s, vec3(0.0)))) continue;
            vec3 to_light;
            float dist;
            vec3 e = is_area ? area_light_arriving(em, p, np, area, x, to_light, dist)
                             : light_arriving(l, x, to_light, dist);
            if (all(equal(e, vec3(0.0)))) continue;
            float shorten = is_area ? AREA_SHADOW_SHORTEN : PUNCTUAL_SHADOW_SHORTEN;
            vec3 tr = mean_transmittance(o, d, t, rng) * light_visibility(x, to_light, dist, shorten, rng);
            sum += tr * sigma_s * hg_phase(dot(to_light, d), g) * e / (pdf * float(AIRLIGHT_SAMPLES));
        }
    }
    return sum;
}

// Radiance emitted toward a camera path of state `s` at its next hit: the
// environment where it escapes (from outside glass), an area light's front
// face; 0 elsewhere.
vec3 emitted_radiance(SpecularState s, bool found, Hit hit) {
    if (!found) return environment_present() && !s.inside ? environment_radiance(s.dir) : vec3(0.0);
    Material m = materials[hit_material(hit)];
    bool emitter = floatBitsToUint(m.color.w) == MATERIAL_DIFFUSE && any(greaterThan(m.emission.rgb, vec3(0.0)));
    return emitter && dot(s.dir, hit_geometric_normal(hit)) < 0.0 ? m.emission.rgb : vec3(0.0);
}

// The attenuation of the segment from s.origin along s.dir to the next hit
// (`found`) or out of the scene: the extinction inside glass or water, the
// medium outside (one ratio-tracking run: the EMISSION_GRID^2 chains
// already average).
vec3 segment_attenuation(SpecularState s, bool found, float t, inout uint rng) {
    if (s.inside && !found) return vec3(0.0);
    float travel = found ? t : 2.0 * frame.scene_sphere.w + length(s.origin - frame.scene_sphere.xyz);
    return region_transmittance(s, s.origin, s.dir, travel, rng);
}

// The emitted component (L S* E): the emitters a camera ray meets directly
// (the background, a lamp) or through its specular chain (in a mirror,
// through glass and water). A `mixed` material's mirror part always
// continues the chain, weighted by its reflectance (its diffuse part emits
// nothing further here). At a Fresnel choice the branch not taken is traced
// one hit further and its emission counted with the weight of not taking
// it, the branch taken counting its next hit's with the weight of taking
// it: the expectation is the plain choice's, f E_r + (1 - f) E_t, while a
// lamp or the sky reflected in glass (F = 4%: one sample in 25 at 25 times
// the reflection's radiance) no longer comes as fireflies (on `medium_box`
// its lamp's reflection in the sphere held the noise above 70%).
vec3 chain_emission(SpecularState s, inout uint rng) {
    vec3 sum = vec3(0.0);
    float share = 1.0; // of the emission met at the next hit
    for (uint depth = 0u; depth < pc.max_depth; ++depth) {
        Hit hit;
        bool found = trace_closest(s.origin, s.dir, 0.0, 1e30, hit);
        Material m;
        bool diffuse = false, continues = false;
        if (found) {
            m = materials[hit_material(hit)];
            diffuse = floatBitsToUint(m.color.w) == MATERIAL_DIFFUSE;
            continues = !(diffuse && all(equal(m.specular.rgb, vec3(0.0))));
        }
        vec3 radiance = emitted_radiance(s, found, hit);
        bool emits = any(greaterThan(radiance, vec3(0.0)));
        if (!emits && !continues) break; // no attenuation to compute
        vec3 tr = segment_attenuation(s, found, found ? hit.t : 0.0, rng);
        sum += share * s.weight * tr * radiance;
        if (!continues) break;
        s.weight *= tr;
        vec3 x = s.origin + hit.t * s.dir;
        vec3 ng = hit_geometric_normal(hit);
        bool front = dot(s.dir, ng) < 0.0;
        if (diffuse) {
            mirror_bounce(s, x, ng, hit_normal(hit), front, m.specular.rgb);
            share = 1.0;
            continue;
        }
        SpecularState reflected = s;
        SpecularState other = s;
        float p_reflect = specular_bounce(reflected, x, ng, hit_normal(hit), front, m, -1.0, true);
        specular_bounce(other, x, ng, hit_normal(hit), front, m, 2.0, true);
        share = p_reflect;
        if (rng_next(rng) < p_reflect) {
            s = reflected;
        } else {
            s = other;
            other = reflected;
            share = 1.0 - p_reflect;
        }
        if (share < 1.0) {
            Hit other_hit;
            bool other_found = trace_closest(other.origin, other.dir, 0.0, 1e30, other_hit);
            vec3 other_radiance = emitted_radiance(other, other_found, other_hit);
            if (any(greaterThan(other_radiance, vec3(0.0)))) {
                vec3 other_tr = segment_attenuation(other, other_found, other_found ? other_hit.t : 0.0, rng);
                sum += (1.0 - share) * other.weight * other_tr * other_radiance;
            }
        }
        if (luminance(s.weight) <= 0.0) break;
    }
    return sum;
}

// Camera rays a pixel traces a pass for the emitted component alone, one
// per cell of an EMISSION_GRID^2 stratification of the pixel: an emitter's
// edge seen directly or through glass (the lamp reflected in
// `medium_box`'s sphere, 40 times the image's mean radiance, and its tiny
// image refracted through the sphere, 900 times) is pixel coverage noise,
// which one random sample a pass left at 15% of the image's noise after 5
// minutes; a chain is one ray per bounce, cheap beside a pass's photons.
const uint EMISSION_GRID = 4u;

// Fresnel splitting. A camera chain that met glass chose reflection or
// refraction at random, one visible point a pixel and pass: on
// `ball_lens_top` the floor reflected in the ball (F = 4% at the centre,
// towards 1 at the rim) came as one pass in 25 at 25 times its share, and
// that choice made most of the view's noise. Here a pixel's chain is
// followed as 2^S branches (S = pc.fresnel_splits): branch b takes, at its
// j-th Fresnel choice (j < S; 0 < F < 1: dielectrics and thin sheets),
// reflection when bit j of b is set, weighted by F, else refraction,
// weighted by 1 - F; later choices stay random. Every branch draws from the
// same random stream (what only branch 0 samples draws from another), so
// branches agree up to their first differing bit. A path whose chain ended
// after j < S choices is the same in every branch that differs only in
// bits j and above: only the branch with those bits clear counts it
// (`counted`), which keeps the sum over the branches the expectation of
// the random choices, F x_r + (1 - F) x_t at each split.

// Follows branch `branch` of the camera chain from s: the direct light of
// its diffuse point (`direct`, the pass's direct component) and its visible
// point (`vp`, position.w = 0 for none); returns the Fresnel choices it
// forced. Branch 0 also adds the first segment's airlight and a diffuse
// first hit's direct light, which every branch shares, sampled with
// `first_rng` so that `rng` stays the same stream in every branch.
uint follow_chain(uint index, uint branch, SpecularState s, inout uint rng, inout uint first_rng, out vec3 direct,
                  out VisiblePoint vp) {
    vp.position = vec4(0.0);
    vp.normal = vec4(0.0);
    vp.weight = vec4(0.0);
    direct = vec3(0.0);
    uint forced = 0u;
    for (uint depth = 0u; depth < pc.max_depth; ++depth) {
        Hit hit;
        bool found = trace_closest(s.origin, s.dir, 0.0, 1e30, hit);
        // The scene's medium before any specular bounce; an eye inside a
        // dielectric sees only light that came in through its surface.
        if (depth == 0u && branch == 0u && !s.inside) {
            add_pass(index, COMPONENT_AIRLIGHT, airlight(s.origin, s.dir, found ? hit.t : 1e30, first_rng));
        }
        if (!found) break;
        Material m = materials[hit_material(hit)];
        bool diffuse = floatBitsToUint(m.color.w) == MATERIAL_DIFFUSE;
        vec3 ng = hit_geometric_normal(hit);
        bool front = dot(s.dir, ng) < 0.0;
        // A `mixed` material: a diffuse one with a mirror part.
        vec3 mirror = diffuse ? m.specular.rgb : vec3(0.0);
        bool mixed = any(greaterThan(mirror, vec3(0.0)));
        vec3 x = s.origin + hit.t * s.dir;
        // Every segment's attenuation: the extinction inside glass or water
        // (what a medium there scatters in is volume_points.comp's), the
        // medium outside.
        if (s.inside) s.weight *= exp(-s.inside_extinction * hit.t);
        else s.weight *= mean_transmittance(s.origin, s.dir, hit.t, rng);
        if (diffuse && depth == 0u) {
            // The first hit is diffuse: its direct light (L D E) by shadow
            // rays here (`direct_light`), every other path ending there by
            // the light tracer's camera connections (trace.comp skips those
            // of photons straight from a light sampled here). A mixed
            // material's mirror part goes on below.
            vec3 seen_side = front ? ng : -ng;
            if (branch == 0u) {
                add_pass(index, COMPONENT_DIRECT, s.weight * direct_light(x, seen_side, hit_albedo(hit), first_rng));
            }
            if (!mixed) break;
        }
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
            direct = s.weight * direct_light(x, seen_side, albedo, rng);
            vec3 weight = s.weight * albedo / PI;
            if (pc.gather != 0u && any(greaterThan(weight, vec3(0.0)))) {
                vp.position = vec4(x, 1.0);
                vp.normal = vec4(seen_side, 0.0);
                vp.weight = vec4(weight, 0.0);
            }
            break;
        }
        float u = rng_next(rng);
        if (forced < pc.fresnel_splits) {
            SpecularState probe = s;
            float f = specular_bounce(probe, x, ng, hit_normal(hit), front, m, -1.0, true);
            if (f > 0.0 && f < 1.0) {
                bool reflects = ((branch >> forced) & 1u) != 0u;
                forced += 1u;
                if (reflects) {
                    s = probe;
                    s.weight *= f;
                } else {
                    specular_bounce(s, x, ng, hit_normal(hit), front, m, 2.0, true);
                    s.weight *= 1.0 - f;
                }
                if (luminance(s.weight) <= 0.0) break;
                continue;
            }
        }
        specular_bounce(s, x, ng, hit_normal(hit), front, m, u, true);
    }
    return forced;
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= image_width() || p.y >= image_height()) return;
    uint index = p.y * image_width() + p.x;
    // A stream apart from the photon pass's (same seed, other constant).
    uint rng = rng_seed(index, pc.seed ^ 0x68bc21ebu);
    SpecularState at_eye = eye_state();
    SpecularState s = camera_ray(p, at_eye, rng);

    vec3 emitted = vec3(0.0);
    // Without area lights or an environment nothing is seen emitting.
    uint emission_samples = frame.components.y > 0u || environment_present() ? EMISSION_GRID * EMISSION_GRID : 0u;
    for (uint k = 0u; k < emission_samples; ++k) {
        vec2 cell = vec2(k % EMISSION_GRID, k / EMISSION_GRID);
        vec2 jitter = (cell + vec2(rng_next(rng), rng_next(rng))) / float(EMISSION_GRID);
        emitted += chain_emission(camera_ray_through(p, jitter, at_eye), rng);
    }
    if (emission_samples > 0u) add_pass(index, COMPONENT_EMITTED, emitted / float(emission_samples));

    uint first_rng = rng_seed(index, pc.seed ^ 0x5bd1e995u);
    uint forced[1u << REFERENCE_MAX_FRESNEL_SPLITS];
    uint branches = visible_points_per_pixel();
    for (uint branch = 0u; branch < branches; ++branch) {
        VisiblePoint vp;
        vp.position = vec4(0.0);
        vp.normal = vec4(0.0);
        vp.weight = vec4(0.0);
        vec3 direct = vec3(0.0);
        // Branch b agrees with b less its highest bit up to that bit's
        // choice: when that branch ended sooner, so does this one, the same
        // path, which only the other counts.
        uint top = branch == 0u ? 0u : uint(findMSB(branch));
        uint parent = branch == 0u ? 0u : branch ^ (1u << top);
        bool repeats = branch != 0u && forced[parent] <= top;
        forced[branch] = repeats ? forced[parent] : 0u;
        if (!repeats) {
            uint branch_rng = rng;
            forced[branch] = follow_chain(index, branch, s, branch_rng, first_rng, direct, vp);
        }
        bool counted = !repeats && (branch >> forced[branch]) == 0u;
        if (!counted) vp.position.w = 0.0;
        if (counted) add_pass(index, COMPONENT_DIRECT, direct);
        uint point = index * branches + branch;
        visible_points[point] = vp;
        if (vp.position.w != 0.0) {
            // Push onto the bucket's list (heads were cleared to GRID_NONE).
            uint bucket = grid_bucket(grid_cell(vp.position.xyz, 2.0 * pc.radius), pc.surface_mask);
            surface_next[point] = atomicExchange(surface_heads[bucket], point);
        }
    }
}
