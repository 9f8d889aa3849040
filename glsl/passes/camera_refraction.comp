#version 460
// What the camera sees in the specular objects (technique image_space):
// Wyman 2005-06 two-sided image-space refraction, per pixel of the camera's
// specular G-buffer (front: nearest specular surface, with the
// interpolated per-vertex d_N; back: farthest back face of the
// dielectrics). Everything else is the opaque frame (direct light + surface
// caustics of the scene without its specular surfaces) copied through.
//
// Dielectric at p1 (normal N1 toward the viewer, view direction V):
//   L = F1 L(p1, R) + (1 - F1) T2 exp(-sigma_t d~) L(p2, T2)
// (sigma_t: the material's absorption plus its inside's scattering, the
// light scattered out of the ray; Material.absorption_ior)
// F1 the exact unpolarised Fresnel reflectance at p1, R the mirror
// direction, and p2, T2, d~ and the exit transmittance T2 = 1 - F2 (1 where
// a TIR remedy applied) from glsl/common/image_space_refraction.glsl
// (Eq. 6.3.1, back-face normal texture, Eq. 6.3.2, TIR remedies). Radiance
// entering glass is scaled by (n2/n1)^2 and leaving it by (n1/n2)^2: across
// the two interfaces the factors cancel, so no n^2 appears here.
// One interface (an open sheet such as a water surface: the back-face
// texel is empty and the pixel's d_N is 0, so the refractor has no back
// surface at all): L = F1 L(p1, R) + (1 - F1)/n^2 exp(-sigma_t t) L(x, T1),
// T1 Snell at p1 and x the opaque surface met along it at distance t.
// Derivation: basic radiance L/n^2 is conserved along a ray and across a
// smooth interface up to the transmitted fraction 1 - F (F symmetric in
// direction). The floor's radiance L(x, -T1) is radiance in the medium of
// index n; crossing into air (index 1) it becomes (1 - F1) L (1/n)^2, and
// Beer-Lambert attenuates it over the path t inside the medium. The
// opaque frame holds L(x) as radiance of the surface (albedo/pi E), the
// medium around the receiver being the refractor's. A camera under the
// sheet (its outward normal facing away; the specular G-buffer keeps the
// face for the camera) sees L = F1 exp(-sigma_t t) L(x_R) + (1 - F1) n^2
// L(x, T1), F1 and T1 for light entering the medium (total reflection past
// the critical angle: Snell's window), the reflected leg inside it.
// With `camera_exit` 0 (CAMERA_EXIT_TRACED, the default) p2, T2, the path
// inside and T2 = 1 - F2 come from the refracted ray traced through the
// BVH instead (glsl/common/traced_refraction.glsl, the exact interface
// that the approximation stands in for; total internal reflections
// followed): near a sphere's silhouette Wyman's d~ and back-face normal
// send the rim's rays to the wrong floor (+23% of the direct light seen
// through `ball_lens_top`'s ball, BENCHMARKS.md "Where users look").
// Mirror at p1: L = reflectance * L(p1, R).
// L(o, d): the image-space search of the opaque frame (below), the fast
// path; where it finds nothing (the ray leaves the view, or passes only
// behind nearer objects) the ray is traced through the scene's BVH instead
// (`traced_radiance`, a hybrid as later work after Wyman's does), and one
// that leaves the scene reads the environment (glsl/common/emitters.glsl,
// the emitted component).
#include "scene.glsl"
#include "optics.glsl"
#include "emitters.glsl"
#include "bvh.glsl"
#include "lights.glsl"
#include "random.glsl"
#include "traced_refraction.glsl"
#include "medium.glsl"
#include "traced_direct.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = REFRACTION_BINDING_OPAQUE_RADIANCE, rgba32f) uniform readonly image2D opaque_radiance;
layout(set = 1, binding = REFRACTION_BINDING_OPAQUE_POSITION, rgba32f) uniform readonly image2D opaque_position;
layout(set = 1, binding = REFRACTION_BINDING_FRONT_POSITION, rgba32f) uniform readonly image2D front_position;
layout(set = 1, binding = REFRACTION_BINDING_FRONT_NORMAL, rgba32f) uniform readonly image2D front_normal;
layout(set = 1, binding = REFRACTION_BINDING_BACK_POSITION, rgba32f) uniform readonly image2D back_position;
layout(set = 1, binding = REFRACTION_BINDING_BACK_NORMAL, rgba32f) uniform readonly image2D back_normal;
layout(set = 1, binding = REFRACTION_BINDING_RADIANCE, rgba32f) uniform writeonly image2D radiance;

layout(push_constant) uniform Push {
    uint tir_remedy;   // TIR_*
    uint use_eq632;    // 1: Eq. 6.3.2 where the back-face texel is empty
    uint search_steps; // linear steps of the image-space search
    uint exit;         // CAMERA_EXIT_*: the second interface traced or Wyman's
} pc;

const int BISECTIONS = 10;

#include "camera_pixels.glsl"

float view_depth(vec3 x) { return (frame.view_proj * vec4(x, 1.0)).w; }

// For the shared two-sided refraction: the camera's back-face normal at x.
bool back_face_normal(vec3 x, out vec3 n) {
    n = vec3(0.0);
    ivec2 q;
    float z;
    if (!camera_pixel(x, q, z) || imageLoad(back_position, q).w < 0.0) return false;
    n = imageLoad(back_normal, q).xyz;
    return true;
}

#include "image_space_refraction.glsl"

// True when x lies at or behind the opaque surface at its pixel (the ray
// has reached the surface); `gap` is how far behind, in view depth.
bool behind_opaque(vec3 x, out ivec2 q, out float gap) {
    float z;
    gap = 0.0;
    if (!camera_pixel(x, q, z)) return false;
    vec4 s = imageLoad(opaque_position, q);
    if (s.w == 0.0) return false; // background: nothing to meet there
    gap = z - view_depth(s.xyz);
    return gap >= 0.0;
}

// How much the opaque surface's view depth changes from pixel q to its
// neighbours: a ray meeting a surface seen at a grazing angle lands up to
// that far behind the depth stored at the pixel's centre.
float pixel_depth_extent(ivec2 q) {
    float z0 = view_depth(imageLoad(opaque_position, q).xyz);
    float extent = 0.0;
    ivec2 size = imageSize(opaque_position);
    for (int k = 0; k < 4; ++k) {
        ivec2 n = q + ivec2(k == 0 ? 1 : (k == 1 ? -1 : 0), k == 2 ? 1 : (k == 3 ? -1 : 0));
        if (any(lessThan(n, ivec2(0))) || any(greaterThanEqual(n, size))) continue;
        vec4 s = imageLoad(opaque_position, n);
        if (s.w != 0.0) extent = max(extent, abs(view_depth(s.xyz) - z0));
    }
    return extent;
}

// How far the ray (o, d) stays inside the view frustum (0 if o is outside):
// clip coordinates are linear in t, and each side is a half-space g(t) =
// g0 + t g1 >= 0. Shrunk a little so the last sample still projects inside.
float frustum_exit(vec3 o, vec3 d) {
    vec4 c0 = frame.view_proj * vec4(o, 1.0);
    vec4 c1 = frame.view_proj * vec4(d, 0.0);
    vec4 g0[2] = vec4[2](c0.wwww + vec4(-c0.x, c0.x, -c0.y, c0.y), vec4(c0.w - 1e-3));
    vec4 g1[2] = vec4[2](c1.wwww + vec4(-c1.x, c1.x, -c1.y, c1.y), vec4(c1.w));
    float t = 1e30;
    for (int k = 0; k < 2; ++k) {
        for (int j = 0; j < 4; ++j) {
            if (g0[k][j] < 0.0) return 0.0;
            if (g1[k][j] < 0.0) t = min(t, -g0[k][j] / g1[k][j]);
        }
    }
    return t * (1.0 - 1e-4);
}

// Midpoint steps of the fallback's transmittance in an inhomogeneous medium
// (exact for constant density), as `direct`'s default.
const uint FALLBACK_MEDIUM_STEPS = 16u;
// Specular surfaces a traced fallback ray passes through at most before
// it gives up (the opaque frame holds no specular surface, so neither
// does what stands in for it).
const uint FALLBACK_SPECULAR_SKIPS = 4u;

// The opaque frame's radiance `l` where the camera sees x itself
// (`seen_by_camera` within two pixel footprints at x's depth).
bool seen_in_opaque_frame(vec3 x, vec3 n, out vec3 l) {
    l = vec3(0.0);
    float footprint = 2.0 * view_depth(x) * frame.eye.w / frame.viewport.y;
    ivec2 q;
    if (!seen_by_camera(x, n, 2.0 * footprint, q)) return false;
    l = imageLoad(opaque_radiance, q).rgb;
    return true;
}

// What the opaque frame would hold for a surface it does not show: the ray
// (o, d) traced through the BVH, past specular surfaces, to its first
// diffuse surface x, and there (as glsl/direct/lighting.comp shades, with
// BVH shadow rays where it uses shadow maps) the direct light of the
// scene's punctual lights, of the environment's sun and of each area light
// (glsl/common/traced_direct.glsl), attenuated by the medium along the
// light's leg and from x back to o; an area light's front face gives its
// radiance; where the camera sees x itself, the opaque frame's radiance
// there instead (`seen_in_opaque_frame`). Not there, for a surface the
// camera does not see: the environment table's sky light on x and the
// surface caustics at x, which live only in screen-space images. A ray
// that escapes reads the environment. `t_hit`: the distance to x, -1 when
// it escapes.
vec3 traced_radiance(vec3 o, vec3 d, out float t_hit) {
    t_hit = -1.0;
    float t_min = 0.0;
    for (uint k = 0u; k <= FALLBACK_SPECULAR_SKIPS; ++k) {
        Hit hit;
        if (!trace_closest(o, d, t_min, 1e30, hit)) break;
        uint m = hit_material(hit);
        if (material_kind(m) != MATERIAL_DIFFUSE) {
            t_min = hit.t + 1e-4 * (1.0 + hit.t);
            continue;
        }
        t_hit = hit.t;
        vec3 x = o + hit.t * d;
        vec3 ng = hit_geometric_normal(hit);
        bool front = dot(d, ng) < 0.0;
        vec3 n_side = front ? ng : -ng;
        vec3 seen;
        if (seen_in_opaque_frame(x, n_side, seen)) return seen;
        vec3 ns = hit_normal(hit);
        vec3 n = dot(ns, n_side) > 0.0 ? ns : -ns;
        vec3 so = shadow_origin(x, n_side);
        vec3 e = vec3(0.0);
        for (uint l = 0u; l < frame.counts.x; ++l) {
            vec3 to_light;
            float dist;
            vec3 el = light_irradiance(l, x, n, to_light, dist);
            if (all(equal(el, vec3(0.0)))) continue;
            if (trace_any(so, to_light, 0.0, dist > 1e29 ? 1e30 : dist * (1.0 - 1e-4))) continue;
            e += el * medium_transmittance_steps(x, to_light, light_travel(dist, x), FALLBACK_MEDIUM_STEPS);
        }
        e += sun_and_area_irradiance(x, n, FALLBACK_MEDIUM_STEPS);
        vec3 emission = front ? materials[m].emission.rgb : vec3(0.0);
        vec3 l = component_weight(COMPONENT_DIRECT) * hit_albedo(hit) / PI * e
            + component_weight(COMPONENT_EMITTED) * emission;
        return l * medium_transmittance_steps(x, -d, hit.t, FALLBACK_MEDIUM_STEPS);
    }
    return component_weight(COMPONENT_EMITTED) * environment_radiance(d);
}

// Image-space search of the opaque frame along (o, d) (Wyman 2006 cites
// linear [Wyman05b] and binary [Policarpo05] searches; we do both): linear
// steps over the part of the ray inside both the view frustum and the
// scene's bounding sphere until the ray passes behind the opaque depth,
// then bisection between the last two steps. A crossing whose refined gap
// exceeds one step plus the surface's depth change across a pixel is the
// ray passing behind a nearer object, not meeting it: the march goes on.
// Past the frustum the search can find nothing (the frustum is convex, the
// ray never comes back): there, and where the march ends without a hit,
// it returns false and the caller traces the ray (`traced_radiance`).
// True: `l` is what the ray meets (the environment where it leaves the
// scene's sphere, t_hit -1 then).
bool search_opaque(vec3 o, vec3 d, out vec3 l, out float t_hit) {
    t_hit = -1.0;
    l = vec3(0.0);
    vec3 oc = o - frame.scene_sphere.xyz;
    float b = dot(oc, d);
    float disc = b * b - (dot(oc, oc) - frame.scene_sphere.w * frame.scene_sphere.w);
    if (disc <= 0.0) {
        l = component_weight(COMPONENT_EMITTED) * environment_radiance(d);
        return true;
    }
    float t_max = min(-b + sqrt(disc), frustum_exit(o, d));
    if (t_max <= 0.0) return false;
    float step = t_max / float(max(pc.search_steps, 1u));
    float t_prev = 0.0;
    for (uint i = 1u; i <= pc.search_steps; ++i) {
        float t = step * float(i);
        ivec2 q;
        float gap, z;
        if (!camera_pixel(o + t * d, q, z)) return false;
        if (behind_opaque(o + t * d, q, gap)) {
            float lo = t_prev, hi = t;
            for (int k = 0; k < BISECTIONS; ++k) {
                float mid = 0.5 * (lo + hi);
                ivec2 qm;
                float gm;
                if (behind_opaque(o + mid * d, qm, gm)) hi = mid; else lo = mid;
            }
            behind_opaque(o + hi * d, q, gap);
            if (gap <= step + pixel_depth_extent(q)) {
                t_hit = hi;
                l = imageLoad(opaque_radiance, q).rgb;
                return true;
            }
        }
        t_prev = t;
    }
    return false;
}

// The rays a pixel's specular surface sends on (the reflected one and the
// refracted one), each with its weight; `absorbing`: the open sheet's
// refracted ray, weighted by exp(-sigma_t t) over the distance t it
// travels to what it meets.
struct SecondaryRay {
    vec3 origin;
    vec3 dir;
    vec3 weight;
    bool absorbing;
    bool traced; // through the BVH first, not searched
};

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    vec4 fp = imageLoad(front_position, p);
    if (fp.w < 0.0) {
        imageStore(radiance, p, vec4(imageLoad(opaque_radiance, p).rgb, 1.0));
        return;
    }
    vec4 fn = imageLoad(front_normal, p);
    uint m = uint(fn.w + 0.5);
    vec3 p1 = fp.xyz;
    vec3 v = normalize(p1 - frame.eye.xyz);
    vec3 n1 = normalize(fn.xyz);
    // The camera on the inside of an open sheet (under the water): its
    // outward normal faces away. (Where the smooth normal's facing
    // disagrees with the face's, at grazing angles, both sides reflect
    // almost everything: F1 -> 1 outside, total reflection inside.)
    bool inside = dot(n1, v) > 0.0;
    if (inside) n1 = -n1;
    // The reflected ray starts on the surface; the opaque frame holds no
    // specular surface, so only the start's own pixel could be met early,
    // and its opaque surface lies behind p1.
    SecondaryRay rays[2];
    uint count = 1u;
    rays[0] = SecondaryRay(p1, reflect(v, n1), materials[m].color.rgb, false, false);
    vec3 sigma_t = materials[m].absorption_ior.rgb;
    if (material_kind(m) != MATERIAL_MIRROR) {
        float ior = materials[m].absorption_ior.w;
        // d_V: front to the farthest back face along this pixel's ray; a
        // sheet with no back face here has no thickness.
        vec4 bp = imageLoad(back_position, p);
        if (bp.w < 0.0 && fp.w <= 0.0) {
            // One interface (no back face here and no d_N: an open sheet,
            // see the header). Eq. 6.3.2 stays for closed objects whose
            // back-face texel at p2 is empty (d_N > 0 there). From the
            // inside the light enters the medium: eta = n, total
            // reflection past the critical angle, and radiance gains n^2
            // (L/n^2 conserved); the reflected ray stays in the medium
            // (absorbing), the refracted one leaves it.
            float eta = inside ? ior : 1.0 / ior;
            float f1 = fresnel_dielectric(-dot(v, n1), eta);
            rays[0].weight = vec3(f1);
            rays[0].absorbing = inside;
            // Both rays traced first: an open surface's refracted rays bend
            // under the walls around it, to floor the camera does not see,
            // where the search met the wall's top edge and returned the
            // wall (+12% of the direct light seen in `water_pool`,
            // BENCHMARKS.md "Where users look").
            rays[0].traced = true;
            vec3 t1;
            if (refract_dir(v, n1, eta, t1)) {
                rays[count++] = SecondaryRay(p1, t1, vec3((1.0 - f1) * eta * eta), !inside, true);
            }
        } else {
            float f1 = fresnel_dielectric(-dot(v, n1), 1.0 / ior);
            rays[0].weight = vec3(f1);
            vec3 exit_p, exit_d, through;
            if (pc.exit == CAMERA_EXIT_TRACED) {
                if (traced_refraction(v, p1, n1, ior, sigma_t, exit_p, exit_d, through)) {
                    rays[count++] = SecondaryRay(exit_p, exit_d, (1.0 - f1) * through, false, false);
                }
            } else {
                float d_v = bp.w >= 0.0 ? max(length(bp.xyz - p1), 0.0) : 0.0;
                TwoSidedExit e;
                if (two_sided_refraction(v, p1, n1, ior, d_v, fp.w, pc.tir_remedy, pc.use_eq632 != 0u, e)) {
                    vec3 absorbed = exp(-sigma_t * e.dist);
                    rays[count++] = SecondaryRay(e.p2, e.dir, (1.0 - f1) * e.transmit * absorbed, false, false);
                }
            }
        }
    }
    // One call site for the search and the traced fallback: inlined once
    // per ray kind they made this lavapipe's slowest shader to compile
    // (about 4 minutes of LLVM on a fresh shader cache, BENCHMARKS.md).
    vec3 l = vec3(0.0);
    for (uint k = 0u; k < count; ++k) {
        vec3 seen;
        float t;
        bool found = !rays[k].traced && search_opaque(rays[k].origin, rays[k].dir, seen, t);
        if (!found) seen = traced_radiance(rays[k].origin, rays[k].dir, t);
        vec3 absorbed = rays[k].absorbing ? exp(-sigma_t * max(t, 0.0)) : vec3(1.0);
        l += rays[k].weight * absorbed * seen;
    }
    imageStore(radiance, p, vec4(l, 1.0));
}
