#version 460
// pinhole, step 4: per sample point, the normal gradient of Sect. 3.3 and
// the visibility of each light.
// "We take a denser set of sample points in the region around the main
// sample point [the dense candidates within the sample spacing
// rho = sqrt(A/N)]. We determine a tangent plane by computing the average
// normal and establish a local coordinate frame u,v in this plane. We
// project all sample points into the plane and examine the normals at these
// points. Using linear regression, we fit a linear function
// n(u,v) = n + u dn/du + v dn/dv to the sample points, yielding a matrix
// grad n = (dn/du | dn/dv)." The least-squares fit of n_k = a + b u_k + c v_k
// solves the 3x3 normal equations (one right-hand side per component).
// "The directions are computed by an eigenspace transformation of the
// matrix grad n": the symmetric 2x2 part of grad n in the tangent frame,
// S = [u.b, (u.c + v.b)/2; (u.c + v.b)/2, v.c], has the principal
// directions at angle theta = atan2(2 S01, S00 - S11) / 2; u, v and the
// derivatives are rotated onto them.
// Light visibility (beyond the paper, which has none): one shadow ray per
// sample point and emitter slot, from the side of the surface the light is
// on; bit s of the mask gates slot s's cube map at this sample.
#include "common.glsl"
#include "optics.glsl"
#include "bvh.glsl"
#include "emitters.glsl"

layout(local_size_x = 64) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint count = state.count;
    if (i >= count) return;
    vec3 p = samples[i].position.xyz;
    vec3 n = samples[i].normal.xyz;
    float rho = sqrt(state.total_area / float(count));
    // Average normal of the neighbourhood (oriented like n).
    ivec3 c = grid_cell(p);
    vec3 nsum = vec3(0.0);
    for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
    for (int x = -1; x <= 1; ++x) {
        for (uint j = heads[grid_hash(c + ivec3(x, y, z))]; j != NONE; j = next_candidate[j]) {
            vec3 d = candidates[j].position.xyz - p;
            if (dot(d, d) > rho * rho) continue;
            vec3 nj = candidates[j].normal.xyz;
            nsum += dot(nj, n) < 0.0 ? -nj : nj;
        }
    }
    vec3 nbar = dot(nsum, nsum) > 0.0 ? normalize(nsum) : n;
    vec3 u = normalize(abs(nbar.x) < 0.9 ? cross(nbar, vec3(1.0, 0.0, 0.0)) : cross(nbar, vec3(0.0, 1.0, 0.0)));
    vec3 v = cross(nbar, u);
    // Normal equations of the linear fit in the tangent plane.
    float m = 0.0, su = 0.0, sv = 0.0, suu = 0.0, suv = 0.0, svv = 0.0;
    vec3 sn = vec3(0.0), sun = vec3(0.0), svn = vec3(0.0);
    for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
    for (int x = -1; x <= 1; ++x) {
        for (uint j = heads[grid_hash(c + ivec3(x, y, z))]; j != NONE; j = next_candidate[j]) {
            vec3 d = candidates[j].position.xyz - p;
            if (dot(d, d) > rho * rho) continue;
            vec3 nj = candidates[j].normal.xyz;
            nj = dot(nj, n) < 0.0 ? -nj : nj;
            float uk = dot(d, u), vk = dot(d, v);
            m += 1.0; su += uk; sv += vk;
            suu += uk * uk; suv += uk * vk; svv += vk * vk;
            sn += nj; sun += uk * nj; svn += vk * nj;
        }
    }
    // Cramer's rule for [a b c]; a degenerate neighbourhood (fewer than
    // three points off one line) gives no gradient.
    float det = m * (suu * svv - suv * suv) - su * (su * svv - suv * sv) + sv * (su * suv - suu * sv);
    vec3 dn_du = vec3(0.0), dn_dv = vec3(0.0);
    if (m >= 3.0 && abs(det) > 1e-6 * m * m * m * rho * rho * rho * rho) {
        // b = det([m sn sv; su sun suv; sv svn svv]) / det, c likewise.
        dn_du = (m * (sun * svv - suv * svn) - sn * (su * svv - suv * sv) + sv * (su * svn - sun * sv)) / det;
        dn_dv = (m * (suu * svn - sun * suv) - su * (su * svn - sun * sv) + sn * (su * suv - suu * sv)) / det;
    }
    float s00 = dot(u, dn_du), s11 = dot(v, dn_dv), s01 = 0.5 * (dot(u, dn_dv) + dot(v, dn_du));
    float theta = 0.5 * atan(2.0 * s01, s00 - s11);
    float ct = cos(theta), st = sin(theta);
    vec3 u2 = ct * u + st * v;
    vec3 du2 = ct * dn_du + st * dn_dv;
    vec3 dv2 = -st * dn_du + ct * dn_dv;
    // The principal frame is built on nbar; the sample keeps its own normal,
    // and u is made tangent to it.
    u2 = normalize(u2 - dot(u2, n) * n);
    uint mask = 0u;
    if ((pc.flags & PINHOLE_FLAG_LIGHT_VISIBILITY) == 0u) {
        mask = 0xffffffffu;
    } else {
        // Slots as in light_maps.comp: one ray to each punctual light, to
        // each area light's centre and toward a sky's sun; the
        // environment's table, light from every direction, is not gated.
        uint punctual = frame.counts.x, env = punctual + frame.components.y;
        for (uint slot = 0u; slot < pc.slots; ++slot) {
            vec3 to_light;
            float dist;
            if (slot < punctual) {
                if (light_kind(slot) == LIGHT_DIRECTIONAL) {
                    to_light = -lights[slot].direction.xyz;
                    dist = 1e30;
                } else {
                    vec3 dl = lights[slot].position.xyz - p;
                    dist = length(dl);
                    to_light = dl / dist;
                }
            } else if (slot < env) {
                emitter_shadow_target(slot - punctual, p, to_light, dist);
            } else if (slot == env + 1u) {
                if (environment_sun_solid_angle() == 0.0) continue; // no sun disc
                to_light = environment.sun.xyz;
                dist = 1e30;
            } else {
                mask |= 1u << slot;
                continue;
            }
            vec3 side = dot(n, to_light) >= 0.0 ? n : -n;
            float eps = 1e-4 * max(1.0, bvh_max_abs(p));
            if (!trace_any(p + side * eps, to_light, 0.0, dist)) mask |= 1u << slot;
        }
    }
    samples[i].tangent = vec4(u2, uintBitsToFloat(mask));
    samples[i].dn_du = vec4(du2, 0.0);
    samples[i].dn_dv = vec4(dv2, 0.0);
}
