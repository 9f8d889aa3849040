#version 460
// Photon differential tracing (Kougianos & Moustakas 2021, Algorithm 3 and
// Algorithm 2) against the scene's BVH.
//
// One invocation per thread of Eq. 5; Algorithm 1 (cascades.glsl) maps it to
// a texel of cascade c. Where the CCM holds water there (line 17):
// - a shadow ray toward the light (lines 18-23): a water point the light
//   does not reach emits nothing;
// - the reflected and the refracted ray from x_{0:0} (the paper traces both;
//   line 24 onwards, the refracted case "implemented in a similar fashion");
// - for each ray that lands on a diffuse receiver (line 33 takes front
//   faces only; we take either side, as the reference does), the photon
//   differential: the neighbours (u+1, v) and
//   (u, v+1) (Eq. 10; the left or lower neighbour, negated, where the right
//   or upper one holds no water) send their own rays, which we intersect
//   with the receiver's tangent plane at the hit ("projected down onto the
//   tangential surface", §3.2; Algorithm 2 takes t' along every ray
//   instead, the same on a plane parallel to flat water), giving
//   ∂x'/∂u, ∂x'/∂v and the caustic triangle A' (Eq. 11: σ = sqrt(A'/A) s^c).
// - the photon is appended through an atomic counter (line 35) that never
//   writes past the buffer: `requested` counts every photon, a slot below
//   the capacity is written and then counted in the VkDrawIndirectCommand's
//   instanceCount, so the splat draws exactly the photons written and
//   requested − instanceCount is the overflow.
//
// Radiometry (physical mode, WP_INTENSITY_PHYSICAL): the texel of cascade c
// covers A_⊥ = (r.width s^c / W)(r.height s^c / H) perpendicular to the
// light (Eq. 7 is the s^(2c)), so the beam through it carries Φ = E A_⊥; the
// exact Fresnel reflectance F splits it into F Φ reflected and (1 − F) Φ
// refracted, and the refracted part loses exp(−σ_t t') to the water's
// extinction (its absorption, and the scattering of a medium in it: the
// light scattered out of the beam reaches the floor as no caustic). Paper mode (WP_INTENSITY_PAPER): R = L I_att F (Eq. 12) with
// L = E A_⊥, I_att of Eq. 13 and the stylised Fresnel of Eqs. 14-15.
#include "scene.glsl"
#include "optics.glsl"
#include "bvh.glsl"
#include "common.glsl"
#include "cascades.glsl"

layout(local_size_x = WP_TRACE_GROUP_SIZE) in;

layout(set = 1, binding = WP_BINDING_CCM_POSITION, rgba32f) uniform readonly image2DArray ccm_position;
layout(set = 1, binding = WP_BINDING_CCM_NORMAL, rgba32f) uniform readonly image2DArray ccm_normal;
layout(set = 1, binding = WP_BINDING_PHOTONS, std430) writeonly buffer PhotonBlock { Photon photons[]; };
// A VkDrawIndirectCommand followed by the requested-photon counter.
layout(set = 1, binding = WP_BINDING_DRAW, std430) buffer DrawBlock {
    uint vertex_count;
    uint instance_count;
    uint first_vertex;
    uint first_instance;
    uint requested;
} draw;
// Layer 2 c + (type − WP_RAY_REFLECTED): the slot of the photon the texel
// sent along that ray type, ~0 where none (cleared before the trace): the
// water view gathers photons by texel (view.comp).
layout(set = 1, binding = WP_BINDING_PHOTON_SLOTS, r32ui) uniform writeonly uimage2DArray photon_slots;

bool ccm_fetch(ivec2 t, uint c, out vec3 x, out vec3 n) {
    x = vec3(0.0);
    n = vec3(0.0, 1.0, 0.0);
    if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, ivec2(wp.size.xy)))) return false;
    vec4 p = imageLoad(ccm_position, ivec3(t, int(c)));
    if (p.w == 0.0) return false;
    x = p.xyz;
    n = normalize(imageLoad(ccm_normal, ivec3(t, int(c))).xyz);
    return true;
}

vec3 offset_origin(vec3 x, vec3 n) {
    return x + n * (1e-4 * max(1.0, bvh_max_abs(x)));
}

// The reflected (type WP_RAY_REFLECTED) or refracted ray leaving a water
// point with normal n for light travelling along l; false under total
// internal reflection (light from below the surface).
bool leave(uint type, vec3 l, vec3 n, float eta, out vec3 dir) {
    if (type == WP_RAY_REFLECTED) {
        dir = reflect(l, n);
        return true;
    }
    return refract_dir(l, n, eta, dir);
}

// Where the neighbour's ray (origin o, direction d) meets the plane through
// `hit` with normal `nh`; along t' (Algorithm 2 line 4) where it runs parallel.
vec3 on_tangent_plane(vec3 o, vec3 d, vec3 hit, vec3 nh, float t_hit) {
    float denom = dot(d, nh);
    float t = abs(denom) > 1e-6 ? dot(hit - o, nh) / denom : t_hit;
    return o + (t > 0.0 ? t : t_hit) * d;
}

// Eq. 13, as printed, for t' in [0, t_max] (paper mode traces no further,
// the DXR TMax the paper relies on), where u = 1 − t'/t_max lies in [0, 1]
// and I_att in [0, 1]; the clamp only guards rounding at t' = t_max.
float intensity_attenuation(float t) {
    float u = 1.0 - t / wp.paper.y;
    float g = wp.paper.x;
    return max(u > g ? 1.0 - (u - g) / (1.0 - g) : 1.0 - (g - u) / g, 0.0);
}

void main() {
    uint thread = gl_GlobalInvocationID.y * (WP_TRACE_GROUP_SIZE * WP_TRACE_GROUPS_PER_ROW) + gl_GlobalInvocationID.x;
    uvec2 texel;
    uint c;
    if (!ccm_texel_of(thread, wp.size.xy, wp.modes.xy, wp.size.z, texel, c)) return;
    ivec2 t = ivec2(texel);
    vec3 x00, n00;
    if (!ccm_fetch(t, c, x00, n00)) return;

    vec3 l = normalize(wp.light_dir.xyz);
    // Lines 18-23: is the water point lit?
    if (trace_any(offset_origin(x00, -l), -l, 0.0, 1e30)) return;
    // Neighbours for Eq. 10: right (or left, negated) and up (or down).
    vec3 xu, nu, xv, nv;
    float su = 1.0, sv = 1.0;
    bool has_u = ccm_fetch(t + ivec2(1, 0), c, xu, nu);
    if (!has_u) { has_u = ccm_fetch(t - ivec2(1, 0), c, xu, nu); su = -1.0; }
    bool has_v = ccm_fetch(t + ivec2(0, 1), c, xv, nv);
    if (!has_v) { has_v = ccm_fetch(t - ivec2(0, 1), c, xv, nv); sv = -1.0; }
    // A water texel with no water neighbour along an axis has no footprint.
    if (!has_u || !has_v) return;
    vec3 dxu = su * (xu - x00);
    vec3 dxv = sv * (xv - x00);
    // The surface triangle's area A_{xω} (as a parallelogram: the ratio is the same).
    float area_surface = length(cross(dxu, dxv));
    if (area_surface <= 0.0) return;

    float scale_c = pow(wp.cascade.x, float(c));
    // Eq. 7: the texel's area perpendicular to the light, s^(2c) times cascade 0's.
    float texel_area = wp.range.x * wp.range.y / float(wp.size.x * wp.size.y) * scale_c * scale_c;
    vec3 beam = wp.irradiance.rgb * texel_area;

    uint material = wp.water.x;
    float ior = materials[material].absorption_ior.w;
    vec3 sigma_t = materials[material].absorption_ior.rgb;
    float eta = 1.0 / max(ior, 1e-6);
    // The side of the surface the light arrives on (the water's normals
    // face +y; a sun above always sees that side).
    vec3 n = dot(l, n00) < 0.0 ? n00 : -n00;
    float cos_i = -dot(l, n);
    float fresnel = fresnel_dielectric(cos_i, eta);

    for (uint type = WP_RAY_REFLECTED; type <= WP_RAY_REFRACTED; ++type) {
        vec3 dir;
        if (!leave(type, l, n, eta, dir)) continue;
        vec3 origin = offset_origin(x00, type == WP_RAY_REFLECTED ? n : -n);
        Hit h;
        // Paper mode: rays end at t_max (Eq. 13's range, DXR's TMax in the
        // paper), so a farther receiver is a miss, never a negative I_att.
        float t_end = wp.modes.z == WP_INTENSITY_PAPER ? wp.paper.y : 1e30;
        if (!trace_closest(origin, dir, 0.0, t_end, h)) continue;
        // Only diffuse receivers take photons (one specular bounce: L S D).
        uint hm = hit_material(h);
        if (material_kind(hm) != MATERIAL_DIFFUSE) continue;
        vec3 hit = hit_position(h, origin, dir);
        // Line 33 keeps front faces only; our diffuse surfaces are
        // two-sided, as in the reference light tracer (a photon lands on
        // the side it arrives on whatever the winding; an open mesh such
        // as a plane is lit from either side): face the normal toward the ray.
        vec3 ng = hit_geometric_normal(h);
        if (dot(dir, ng) > 0.0) ng = -ng;

        // Algorithm 2: the neighbours' rays, with their own normals.
        vec3 nu_s = dot(l, nu) < 0.0 ? nu : -nu;
        vec3 nv_s = dot(l, nv) < 0.0 ? nv : -nv;
        vec3 du, dv;
        if (!leave(type, l, nu_s, eta, du) || !leave(type, l, nv_s, eta, dv)) continue;
        vec3 axis_u = su * (on_tangent_plane(xu, du, hit, ng, h.t) - hit);
        vec3 axis_v = sv * (on_tangent_plane(xv, dv, hit, ng, h.t) - hit);
        float area_caustic = length(cross(axis_u, axis_v));
        // Eq. 11 without s^c (the axes are already in cascade c's texel steps).
        float sigma = sqrt(area_caustic / area_surface);
        if (!(sigma > 0.0) || isinf(sigma)) continue;

        vec3 flux;
        if (wp.modes.z == WP_INTENSITY_PAPER) {
            // Eqs. 12-15.
            float f_refl = wp.cascade.z + (1.0 - wp.cascade.z) * pow(max(1.0 - dot(-l, n), 0.0), wp.cascade.w);
            float f = type == WP_RAY_REFLECTED ? f_refl : 1.0 - f_refl;
            flux = beam * intensity_attenuation(h.t) * f;
        } else {
            float f = type == WP_RAY_REFLECTED ? fresnel : 1.0 - fresnel;
            flux = beam * f;
            if (type == WP_RAY_REFRACTED) flux *= exp(-sigma_t * h.t);
        }
        if (all(equal(flux, vec3(0.0)))) continue;

        uint slot = atomicAdd(draw.requested, 1u);
        if (slot >= wp.size.w) continue; // overflow: counted, not written
        Photon p;
        p.position = vec4(hit, float(c));
        p.normal = vec4(ng, sigma);
        p.axis_u = vec4(axis_u, float(type));
        p.axis_v = vec4(axis_v, h.t);
        p.flux = vec4(flux, area_surface);
        p.dir = vec4(dir, 0.0);
        // One shaft tube per k x k block of texels (shafts.glsl).
        uint k = max(wp.shafts.x, 1u);
        p.surface_u = vec4(dxu, all(equal(texel % k, uvec2(0u))) ? float(k) : 0.0);
        p.surface_v = vec4(dxv, 0.0);
        photons[slot] = p;
        imageStore(photon_slots, ivec3(t, int(2u * c + type - WP_RAY_REFLECTED)), uvec4(slot));
        atomicAdd(draw.instance_count, 1u);
    }
}
