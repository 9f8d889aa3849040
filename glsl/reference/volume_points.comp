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
// of this pass (progressive photon mapping with the volume kernel, Knaus &
// Zwicker 2011 Sect. 5 / Jensen & Christensen 1998):
//     L = W sum_k dt T(eye, y_k) sum_p Phi_p p(theta_p) / (V(y_k) N_i)
// with V(y) the volume of the ball of radius r_v around y inside the
// medium's bounds ((4/3) pi r_v^3 away from its faces), over steps y_k of
// length dt = max(r_v, segment / points) from a jittered start (an unbiased
// quadrature of the segment integral whatever the step; FIRST_SEGMENT_POINTS
// on the first segment, at most LATER_SEGMENT_POINTS on later ones), Phi_p
// the photon flux already weighted by sigma_s / majorant at its tentative
// collision (the collision density times that weight is sigma_s times the
// fluence), p the HG phase.
// This pass follows the camera paths and appends the points y_k with their
// weights W dt T / V; volume_gather.comp sums the photons around each, one
// grid cell an invocation. (Gathering here, up to hundreds of points times
// thousands of photons per invocation, passed llvmpipe's limit of 65535
// loop iterations per shader invocation, after which every loop exits
// silently: the gather lost up to 45% of its photons, BENCHMARKS.md.)
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

// The share of the kernel ball around y (radius r) inside a dielectric's
// medium (turbid water), which its surfaces bound: the ball less the cap
// beyond the nearest surface within r, taken as a plane at distance u r
// from y, V_cap / V = (1 - u)^2 (2 + u) / 4. The plane's distance is the
// least over six axis rays of t |cos| at their hits. Without it a layer r_v
// thick under the water's surface and over the floor lost 19% of its
// light on average (half of it at the surface itself). Where two surfaces
// meet within r (the pool's corners) only the nearer is counted.
float kernel_share_inside_dielectric(vec3 y, float r) {
    float nearest = r;
    for (uint k = 0u; k < 6u; ++k) {
        vec3 axis = vec3(0.0);
        axis[k >> 1] = (k & 1u) == 0u ? 1.0 : -1.0;
        Hit hit;
        if (trace_closest(y, axis, 0.0, r, hit)) {
            nearest = min(nearest, hit.t * abs(dot(axis, hit_geometric_normal(hit))));
        }
    }
    float u = nearest / r;
    return 1.0 - (1.0 - u) * (1.0 - u) * (2.0 + u) / 4.0;
}

// Appends a gather point at y: the camera path's weight times the step
// and the kernel's normalisation 1 / V(y), so volume_gather.comp only sums
// photons times the phase (HG with `g`, kept in weight.w). `in_box`: y is
// in the scene's medium (bounded by its box), else inside a dielectric.
void append_gather_point(uint index, vec3 y, vec3 dir, vec3 weight, uint tag_mask, float g, bool in_box) {
    float r = pc.volume_radius;
    if (luminance(weight) <= 0.0) return;
    float share = in_box ? kernel_share_inside_medium(y, r) : kernel_share_inside_dielectric(y, r);
    if (share <= 0.0 || luminance(weight) <= 0.0) return;
    uint slot = atomicAdd(gather_point_count, 1u);
    if (slot >= pc.gather_capacity) return; // counted: the host reports the overflow
    GatherPoint point;
    point.position = vec4(y, uintBitsToFloat(index));
    point.direction = vec4(dir, uintBitsToFloat(tag_mask));
    point.weight = vec4(weight / (4.0 / 3.0 * PI * r * r * r * share), g);
    gather_points[slot] = point;
    // The gather's indirect dispatch covers every appended point's cells.
    atomicMax(gather_groups_x, ((slot + 1u) * GATHER_CELLS + 63u) / 64u);
}

// Gather points on the first segment and, at most, on each later one.
const uint FIRST_SEGMENT_POINTS = 8u;
const uint LATER_SEGMENT_POINTS = 32u;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= image_width() || p.y >= image_height()) return;
    uint index = p.y * image_width() + p.x;
    uint rng = rng_seed(index, pc.seed ^ 0x2c1b3c6du);
    SpecularState s = camera_ray(p, eye_state(), rng);

    for (uint depth = 0u; depth < pc.max_depth; ++depth) {
        Hit hit;
        bool found = trace_closest(s.origin, s.dir, 0.0, 1e30, hit);
        float t_hit = found ? hit.t : 1e30;
        // The scene's medium outside dielectrics; inside one, its own
        // medium where it holds one (turbid water), up to the next surface.
        bool inside_medium = scatters_inside(s);
        if (s.inside && !inside_medium) {
            s.weight *= exp(-s.inside_extinction * t_hit);
        } else {
            float t0 = 0.0, t1 = t_hit;
            bool in_medium = inside_medium;
            if (inside_medium) t1 = min(t_hit, light_travel(1e30, s.origin));
            else in_medium = clip_to_medium(s.origin, s.dir, t0, t1);
            float g = inside_medium ? s.inside_scattering.w : medium.sigma_s.w;
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
            // Inside a dielectric's medium the first segment gathers every
            // path type (trace.comp connects none there), at the first
            // segment's FIRST_SEGMENT_POINTS.
            bool gathers_all = depth > 0u || inside_medium;
            uint tag_mask = gathers_all ? 0xffffffffu : (1u << COMPONENT_OTHER);
            if (in_medium) {
                uint points = depth > 0u ? LATER_SEGMENT_POINTS : FIRST_SEGMENT_POINTS;
                float step_length = max(pc.volume_radius, (t1 - t0) / float(points));
                vec3 w = s.weight * region_transmittance(s, s.origin, s.dir, t0, rng);
                float t = t0 + rng_next(rng) * step_length;
                float previous = t0;
                for (uint k = 0u; k <= points && t < t1; ++k) {
                    w *= region_transmittance(s, s.origin + previous * s.dir, s.dir, t - previous, rng);
                    append_gather_point(index, s.origin + t * s.dir, s.dir, w * step_length, tag_mask, g, !inside_medium);
                    previous = t;
                    t += step_length;
                }
            }
            s.weight *= region_transmittance(s, s.origin, s.dir, t_hit, rng);
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
