#version 460
// Ground truth, camera side in the medium: in-scattered light seen through a
// specular chain (fog behind glass, a volume caustic in a mirror: L V S+ E,
// L S+ V S+ E), and multiple scattering seen directly (L .. [DV] V E, where
// the light tracer's connections to an eye inside the medium have infinite
// variance). The light tracer connects the other medium collisions to the
// eye along the camera ray's first segment (no delta surface in between), so
// this pass covers every later segment of a camera path, after at least one
// specular bounce, and the first segment's multiple scattering, by
// ray-marched visible points in the medium gathering the volume photon map
// of this pass (progressive photon mapping with the
// volume kernel, Knaus & Zwicker 2011 Sect. 5 / Jensen & Christensen 1998):
//     L = W sum_k dt T(eye, y_k) sum_p Phi_p p(theta_p) / (V(y_k) N_i)
// with V(y) the volume of the ball of radius r_v around y inside the
// medium's bounds ((4/3) pi r_v^3 away from its faces)
// over steps y_k of length dt = r_v (on the first segment at least a
// FIRST_SEGMENT_POINTS-th of it) from a jittered start (an unbiased
// quadrature of the segment integral), Phi_p the photon flux already
// weighted by sigma_s / majorant at its tentative collision (the collision
// density times that weight is sigma_s times the fluence), p the HG phase.
// The camera path is sampled afresh (its own jitter and Fresnel choices): it
// is another unbiased sample of the same chain distribution as camera.comp.
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// The share of the kernel ball around y (radius r) that lies inside the
// medium's bounds. Photons collide only there, so near a face of the box a
// ball that crosses it holds photons from part of its volume: dividing by
// the whole ball would darken a layer r thick along every face (measured:
// -12% on a 0.8 m slab with r_v = 0.2 m). Dividing by ball ∩ box removes
// that boundary bias; the share is counted on an 8^3 lattice over the
// ball's cube (about 268 points inside the ball, so within ~0.5%).
float kernel_share_inside_medium(vec3 y, float r) {
    vec3 lo = medium.bounds_min.xyz, hi = medium.bounds_max.xyz;
    if (all(greaterThanEqual(y - vec3(r), lo)) && all(lessThanEqual(y + vec3(r), hi))) return 1.0;
    const int n = 8;
    // Counted in integers: the lattice points inside the unit ball are a
    // constant, so the share is never 0/0.
    uint in_ball = 0u, in_both = 0u;
    for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
        vec3 u = (vec3(i, j, k) + 0.5) / float(n) * 2.0 - 1.0;
        if (dot(u, u) >= 1.0) continue;
        vec3 x = y + r * u;
        in_ball += 1u;
        if (all(greaterThanEqual(x, lo)) && all(lessThanEqual(x, hi))) in_both += 1u;
    }
    return float(in_both) / float(max(in_ball, 1u));
}

// The volume photons within r_v of y, weighted by the phase toward the eye
// (the camera ray travels along `dir`, so the light leaves y along -dir).
void gather_volume(uint index, vec3 y, vec3 dir, vec3 weight, uint tag_mask) {
    float r = pc.volume_radius;
    float side = 2.0 * r;
    ivec3 lo = grid_cell(y - vec3(r), side);
    ivec3 hi = grid_cell(y + vec3(r), side);
    float g = medium.sigma_s.w;
    float share = kernel_share_inside_medium(y, r);
    if (share <= 0.0) return;
    float kernel = 1.0 / (4.0 / 3.0 * PI * r * r * r * share);
    uint stored = min(volume_photon_count, pc.volume_capacity);
    vec3 sums[COMPONENT_COUNT];
    for (uint c = 0u; c < COMPONENT_COUNT; ++c) sums[c] = vec3(0.0);
    for (int cz = lo.z; cz <= hi.z; ++cz)
    for (int cy = lo.y; cy <= hi.y; ++cy)
    for (int cx = lo.x; cx <= hi.x; ++cx) {
        ivec3 c = ivec3(cx, cy, cz);
        uint i = volume_heads[grid_bucket(c, pc.volume_mask)];
        for (uint guard = 0u; i != REFERENCE_GRID_NONE && guard < stored; ++guard) {
            VolumePhoton photon = volume_photons[i];
            if (grid_cell(photon.position.xyz, side) == c) {
                vec3 d = photon.position.xyz - y;
                uint tag = floatBitsToUint(photon.position.w);
                if (dot(d, d) < r * r && (tag_mask & (1u << tag)) != 0u) {
                    sums[tag] += photon.flux.rgb * hg_phase(dot(photon.direction.xyz, -dir), g);
                }
            }
            i = volume_next[i];
        }
    }
    for (uint c = 0u; c < COMPONENT_COUNT; ++c) {
        if (any(greaterThan(sums[c], vec3(0.0)))) add_pass(index, c, weight * kernel * sums[c]);
    }
}

const uint FIRST_SEGMENT_POINTS = 8u;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= image_width() || p.y >= image_height()) return;
    uint index = p.y * image_width() + p.x;
    uint rng = rng_seed(index, pc.seed ^ 0x2c1b3c6du);
    SpecularState s = camera_ray(p, rng);

    for (uint depth = 0u; depth < pc.max_depth; ++depth) {
        Hit hit;
        bool found = trace_closest(s.origin, s.dir, 0.0, 1e30, hit);
        float t_hit = found ? hit.t : 1e30;
        if (s.inside) {
            s.weight *= exp(-s.inside_absorption * t_hit);
        } else {
            float t0 = 0.0, t1 = t_hit;
            bool in_medium = clip_to_medium(s.origin, s.dir, t0, t1);
            // On segment 0 the light tracer connects single scattering
            // and volume caustics (L S* V E) to the eye; multiple scattering
            // (a photon that scattered or bounced before, tag `other`) is
            // gathered here instead. Its connections near an eye inside the
            // medium have infinite variance (the 1/d^2 of the pinhole
            // measurement squared, integrated over the volume around the
            // eye, diverges): the fireflies that kept a medium-filled box
            // above 70% noise for minutes. The kernel's bias in this smooth
            // component vanishes as r_v shrinks.
            // That component varies slowly along the ray, so the first
            // segment takes FIRST_SEGMENT_POINTS stratified points (steps
            // no shorter than r_v); a step's weight is its length, so the
            // quadrature stays unbiased whatever the step.
            uint tag_mask = depth == 0u ? (1u << COMPONENT_OTHER) : 0xffffffffu;
            if (in_medium) {
                float step_length = pc.volume_radius;
                if (depth == 0u) step_length = max(step_length, (t1 - t0) / float(FIRST_SEGMENT_POINTS));
                vec3 w = s.weight * medium_transmittance(s.origin, s.dir, t0, rng);
                float t = t0 + rng_next(rng) * step_length;
                float previous = t0;
                for (uint k = 0u; k < 4096u && t < t1; ++k) {
                    w *= medium_transmittance(s.origin + previous * s.dir, s.dir, t - previous, rng);
                    gather_volume(index, s.origin + t * s.dir, s.dir, w * step_length, tag_mask);
                    previous = t;
                    t += step_length;
                }
            }
            s.weight *= medium_transmittance(s.origin, s.dir, t_hit, rng);
        }
        if (!found) break;
        Material m = materials[hit_material(hit)];
        vec3 x = s.origin + hit.t * s.dir;
        vec3 ng = hit_geometric_normal(hit);
        bool front = dot(s.dir, ng) < 0.0;
        if (floatBitsToUint(m.color.w) == MATERIAL_DIFFUSE) {
            // A `mixed` material's mirror part continues the chain (its
            // diffuse part is camera.comp's and the light tracer's).
            if (all(equal(m.specular.rgb, vec3(0.0)))) break;
            mirror_bounce(s, x, ng, hit_normal(hit), front, m.specular.rgb);
        } else {
            specular_bounce(s, x, ng, hit_normal(hit), front, m, rng_next(rng), true);
        }
        if (luminance(s.weight) <= 0.0) break;
    }
}
