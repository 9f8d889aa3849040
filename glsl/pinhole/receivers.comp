#version 460
// pinhole, step 8: the caustics on the diffuse receivers (Sect. 3.1). Per
// pixel of the camera's opaque G-buffer (diffuse surfaces), a sum over the
// N reflector sample points, each "a set of (reflecting) pinhole cameras
// that project an image of the light source onto the receiving surfaces":
//
//   E(p_d) = A/N * sum_s  R_s L_map(k_s, r_s) V_s  <n_s, -d_n> <n_d, d_n> / (<d, d> + eps)
//
// with d = p_s - p_d, d_n = d / |d|, r_s = reflect(d_n, n_s) the lookup
// direction (the paper's "takes the vector d from the current raster
// position on the receiver p_d to the sample point p_s and reflects it at
// the normal n_s of the point sample"), the scalar products clamped to
// [0, 1] ("to perform backface culling"; a mirror is two-sided, so n_s is
// taken on the receiver's side), eps = epsilon x (diameter of one sample's
// region)^2 = epsilon x 4 A / (pi N) ("in the range of the diameter of the
// surface region that is represented by one sample point squared"), and
// A/N "the total surface area by the number of sample points". R_s: the
// mirror's reflectance (a `mixed` material's mirror part: the receivers
// include the reflector itself, the paper's self-reflecting cup), or a dielectric's Fresnel reflectance at <n_s,-d_n>
// (Sect. 5: "a simple modulation of the reflected intensity depending on
// the incident angle (e.g. for a Fresnel term) is straightforward"; the
// light must arrive from outside, the side the geometric normal faces).
// L_map: the cube map of sample s's cluster k_s, one per emitter slot,
// gated by the slot's light-visibility bit V_s, scaled by the map's
// normalisation (light_maps.comp). The pixel's radiance gains
// albedo / pi * E (times the transmittance to the eye in a medium).
//
// Anti-aliasing (Sect. 3.3, flag FILTER): "the footprint parallelogram is
// then estimated by finite differencing: we calculate the reflection vector
// at three points: the center point p and two points p_u, p_v on the
// tangential plane of the surface with a distance r to the center where r
// is half the sample spacing ... the normals n_u = n + r dn/du and
// n_v = n + r dn/dv are used"; fp_u = r(p_u) - r(p), fp_v = r(p_v) - r(p).
// The footprint spans one sample's region (p - r .. p + r): 2 fp_u, 2 fp_v,
// filtered by `lookup_footprint` (textureGrad probes).
//
// Visibility (beyond the paper, flag VISIBILITY): one BVH shadow ray from
// the receiver to the sample point, traced only where the term is nonzero.
#include "common.glsl"
#include "optics.glsl"
#include "bvh.glsl"
#include "random.glsl"
#include "medium.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

#define PINHOLE_MAX_PROBES 16

layout(set = 1, binding = PINHOLE_BINDING_LIGHT_MAP) uniform sampler2DArray light_map;
layout(set = 1, binding = PINHOLE_BINDING_POSITION, rgba32f) uniform readonly image2D g_position;
layout(set = 1, binding = PINHOLE_BINDING_NORMAL, rgba32f) uniform readonly image2D g_normal;
layout(set = 1, binding = PINHOLE_BINDING_ALBEDO, rgba32f) uniform readonly image2D g_albedo;
layout(set = 1, binding = PINHOLE_BINDING_RADIANCE, rgba32f) uniform image2D radiance;

// Radiance of the cluster-k map of `slot` along r, point-sampled
// (bilinear, level 0).
vec3 lookup_point(uint k, uint slot, vec3 r) {
    float m;
    vec2 sctc;
    uint face = cube_face(r, m, sctc);
    return textureLod(light_map, vec3(sctc / abs(m) * 0.5 + 0.5, float(cube_layer(k, slot, face))), 0.0).rgb;
}

// One isotropic probe at direction r with direction-space gradients g1, g2
// (full widths), projected onto r's face: d(s,t) = d(sc/|m|, tc/|m|), as a
// cube lookup does with 3D gradients; uv = st / 2 + 1/2.
vec3 probe(uint k, uint slot, vec3 r, vec3 g1, vec3 g2) {
    float m;
    vec2 sctc;
    uint face = cube_face(r, m, sctc);
    vec2 st = sctc / abs(m);
    vec2 d1 = 0.5 * (cube_face_coords(face, r + g1) - st);
    vec2 d2 = 0.5 * (cube_face_coords(face, r + g2) - st);
    return textureGrad(light_map, vec3(st * 0.5 + 0.5, float(cube_layer(k, slot, face))), d1, d2).rgb;
}

// The mean radiance over the footprint parallelogram r + a g_u + b g_v,
// a, b in [-1/2, 1/2], by footprint assembly (Schilling et al. 1996, the
// paper's reference 18 for what "texldd" does in hardware): n isotropic
// probes spaced along the longer axis, each filtered over the shorter axis
// and 1/n of the longer one (n = the axes' length ratio, at most 16, the
// paper's 16x anisotropy). Done in the shader so that every device filters
// alike (lavapipe has no anisotropic sampling).
vec3 lookup_footprint(uint k, uint slot, vec3 r, vec3 g_u, vec3 g_v) {
    vec3 major = g_u, minor = g_v;
    if (dot(g_v, g_v) > dot(g_u, g_u)) { major = g_v; minor = g_u; }
    float ratio = sqrt(dot(major, major) / max(dot(minor, minor), 1e-30));
    int n = int(clamp(ceil(ratio), 1.0, float(PINHOLE_MAX_PROBES)));
    vec3 step_major = major / float(n);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < n; ++i) {
        vec3 ri = r + ((float(i) + 0.5) / float(n) - 0.5) * major;
        sum += probe(k, slot, ri, step_major, minor);
    }
    return sum / float(n);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, imageSize(radiance)))) return;
    vec4 position = imageLoad(g_position, px);
    if (position.w == 0.0) return;
    vec4 nm = imageLoad(g_normal, px);
    if (material_kind(uint(nm.w + 0.5)) != MATERIAL_DIFFUSE) return;
    uint count = state.count;
    if (count == 0u) return;
    vec3 pd = position.xyz;
    vec3 nd = normalize(nm.xyz);
    float area_share = state.total_area / float(count);     // A / N
    float eps = pc.epsilon * 4.0 * area_share / PI;          // epsilon x diameter^2
    float r_half = 0.5 * sqrt(area_share);                   // half the sample spacing
    bool filtered = (pc.flags & PINHOLE_FLAG_FILTER) != 0u;
    bool visibility = (pc.flags & PINHOLE_FLAG_VISIBILITY) != 0u;
    float offset = 1e-4 * max(1.0, bvh_max_abs(pd));
    vec3 e = vec3(0.0);
    for (uint s = 0u; s < count; ++s) {
        Sample smp = samples[s];
        vec3 d = smp.position.xyz - pd;
        float dist2 = dot(d, d);
        vec3 dn = d * inversesqrt(dist2);
        float cos_d = dot(nd, dn);
        if (cos_d <= 0.0) continue;
        vec3 ns = smp.normal.xyz;
        float cos_s = -dot(ns, dn);
        uint material = floatBitsToUint(smp.position.w);
        vec3 reflectance;
        if (material_kind(material) == MATERIAL_DIELECTRIC) {
            // Light and receiver outside: the side the normal faces.
            if (cos_s <= 0.0) continue;
            reflectance = vec3(fresnel_dielectric(cos_s, 1.0 / materials[material].absorption_ior.w));
        } else {
            // A mirror, or a mixed material's mirror part.
            reflectance = material_kind(material) == MATERIAL_MIRROR
                ? materials[material].color.rgb : material_specular(material);
            if (cos_s < 0.0) { ns = -ns; cos_s = -cos_s; }
        }
        if (cos_s <= 0.0) continue;
        vec3 r = reflect(dn, ns);
        vec3 fp_u = vec3(0.0), fp_v = vec3(0.0);
        if (filtered) {
            float sign_n = dot(ns, smp.normal.xyz) < 0.0 ? -1.0 : 1.0;
            vec3 u = smp.tangent.xyz;
            vec3 v = cross(smp.normal.xyz, u);
            vec3 nu = normalize(ns + sign_n * r_half * smp.dn_du.xyz);
            vec3 nv = normalize(ns + sign_n * r_half * smp.dn_dv.xyz);
            fp_u = reflect(normalize(d + r_half * u), nu) - r;
            fp_v = reflect(normalize(d + r_half * v), nv) - r;
        }
        uint k = floatBitsToUint(smp.normal.w);
        uint mask = floatBitsToUint(smp.tangent.w);
        vec3 l = vec3(0.0);
        for (uint slot = 0u; slot < pc.slots; ++slot) {
            if ((mask & (1u << slot)) == 0u) continue;
            float scale = map_scale(k, slot);
            if (scale == 0.0) continue;
            vec3 radiance_map = filtered
                ? lookup_footprint(k, slot, r, 2.0 * fp_u, 2.0 * fp_v)
                : lookup_point(k, slot, r);
            l += scale * radiance_map;
        }
        vec3 term = reflectance * l * (cos_s * cos_d / (dist2 + eps));
        if (all(equal(term, vec3(0.0)))) continue;
        if (visibility) {
            float dist = sqrt(dist2);
            if (trace_any(pd + nd * offset, dn, 0.0, dist - 2.0 * offset)) continue;
        }
        e += term;
    }
    e *= area_share;
    vec3 albedo = imageLoad(g_albedo, px).rgb;
    vec4 prev = imageLoad(radiance, px);
    vec3 to_eye = frame.eye.xyz - pd;
    float eye_dist = length(to_eye);
    vec3 tau_eye = medium_transmittance_steps(pd, to_eye / eye_dist, eye_dist, pc.medium_steps);
    vec3 caustic = component_weight(COMPONENT_SURFACE_CAUSTICS) * albedo / PI * e * tau_eye;
    imageStore(radiance, px, vec4(prev.rgb + caustic, prev.a));
}
