#version 460
// water_photons "water view": what the camera sees in and through the
// water surface (one interface: an open sheet, no back face, d_N = 0),
// per pixel of the camera's specular G-buffer whose front surface is the
// traced water. Runs after image_space's CameraRefraction, which keeps the
// other specular surfaces and every other pixel; here the water's pixels
// are recomputed:
//   L = F1 L(x_R) + (1 − F1)/n² exp(−σ_t t) L(x_T)
// (from under the water: F1 exp(−σ_t t) L(x_R) + (1 − F1) n² L(x_T), F1
// and x_T for light entering the water, total reflection outside Snell's
// window)
// (GUIDE §2: radiance leaving the water keeps L/n², times the Fresnel
// transmittance; glsl/passes/camera_refraction.comp derives it), with x_R and
// x_T the first hits of the reflected and refracted camera rays in the BVH
// (exact, where the image-space search of the opaque frame guesses).
//
// Why not the image-space search: it can only return what the camera sees
// directly in the opaque frame. Near a wall the refracted ray bends down
// to floor the wall hides from the camera (water_pool: a strip 0.2 m wide
// behind the near wall, 6% of the water's pixels at 128²), and near the
// image's edge it leaves the frame: the search then met the wall's top edge
// (whose neighbours' depth change it takes as its tolerance) and returned
// the wall's radiance, or the black environment, so the water's near edge
// looked cut short and jagged.
//
// L(x) at a diffuse hit x, on the side n_x the ray arrives at:
// - seen directly by the camera (x's pixel in the opaque frame shows x's
//   own surface, see seen_directly): the opaque frame's radiance there,
//   which holds the direct light and the splatted (denoised) caustics,
//   the same answer the rest of the frame gives for x;
// - hidden from the camera or outside the view: shaded here, albedo/π
//   (E_direct + E_caustic): E_direct from every light with a BVH shadow ray
//   (the water casts shadows, as in the direct pass's shadow maps; no
//   medium), E_caustic gathered from the photons with the splat's own
//   kernel (kernel.glsl), so a photon deposits the same irradiance at x as
//   its splat would on a visible pixel: Σ Φ w(a, b) / (4 |U × V|) over the
//   photons whose quad holds x (within the splat's depth tolerance, on the
//   side they arrived at). Photons are found through the trace's slot
//   image: the water point s from which light would reach x were the
//   water flat at its rest height (s = x − t (x_y − h)/t_y along the flat
//   surface's refracted or reflected sun direction t), projected into
//   every cascade, and the texels around it within the waves' reach: a
//   surface tilt α turns a refracted ray by at most α/2 (α (1 − cos θ_i /
//   (n cos θ_t)) ≤ 0.3 α at the pool's sun) and a reflected one by 2α,
//   over the path length from s, plus the rest height's error (Σ A)
//   and four texels for the footprints' extent. Not denoised.
// Reflected or refracted rays that meet a specular surface (the water
// again) or nothing see black: one specular interface, as the photons.
#include "scene.glsl"
#include "optics.glsl"
#include "lights.glsl"
#include "emitters.glsl"
#include "bvh.glsl"
#include "common.glsl"
#include "kernel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = WP_BINDING_PHOTONS, std430) readonly buffer PhotonBlock { Photon photons[]; };
layout(set = 1, binding = WP_BINDING_PHOTON_SLOTS, r32ui) uniform readonly uimage2DArray photon_slots;
layout(set = 1, binding = WP_BINDING_OPAQUE_RADIANCE, rgba32f) uniform readonly image2D opaque_radiance;
layout(set = 1, binding = WP_BINDING_GBUFFER_POSITION, rgba32f) uniform readonly image2D opaque_position;
layout(set = 1, binding = WP_BINDING_FRONT_POSITION, rgba32f) uniform readonly image2D front_position;
layout(set = 1, binding = WP_BINDING_FRONT_NORMAL, rgba32f) uniform readonly image2D front_normal;
layout(set = 1, binding = WP_BINDING_BACK_POSITION, rgba32f) uniform readonly image2D back_position;
layout(set = 1, binding = WP_BINDING_RADIANCE, rgba32f) uniform image2D radiance;
layout(set = 1, binding = WP_BINDING_SHAFTS, rgba32f) uniform readonly image2D shafts;

// N, the cascades (wp.size.z), a pipeline constant (WP_SPEC_CASCADES):
// as a uniform this loop's bound makes lavapipe recompile this shader at
// every bind (water_photons/bindings.rs).
layout(constant_id = WP_SPEC_CASCADES) const uint CASCADES = 1u;

// Texels searched around the flat-water estimate: at most this many on
// each side (a cap on the cost; the reach above decides below it).
const int MAX_REACH_TEXELS = 48;
const uint NONE = 0xffffffffu;

vec3 offset_along(vec3 x, vec3 n) {
    return x + n * (1e-4 * max(1.0, bvh_max_abs(x)));
}

#include "camera_pixels.glsl"

// The pixel that sees x (on the plane of normal n) itself, if the camera
// does (`seen_by_camera`); tolerance: the splat's relative depth bias.
bool seen_directly(vec3 x, vec3 n, out ivec2 q) {
    return seen_by_camera(x, n, max(wp.paper.w, 1e-3) * length(x - frame.eye.xyz), q);
}

vec3 direct_irradiance(vec3 x, vec3 n) {
    vec3 e = vec3(0.0);
    vec3 o = offset_along(x, n);
    for (uint l = 0u; l < uint(lights.length()); ++l) {
        vec3 to_light;
        float dist;
        vec3 el = light_irradiance(l, x, n, to_light, dist);
        if (all(equal(el, vec3(0.0)))) continue;
        if (!trace_any(o, to_light, 0.0, dist)) e += el;
    }
    return e;
}

// Caustic irradiance at x (receiver normal nx, the side the camera ray
// arrives at) from the photons whose splat quads hold x.
vec3 gather(vec3 x, vec3 nx) {
    vec3 l = normalize(wp.light_dir.xyz);
    float ior = materials[wp.water.x].absorption_ior.w;
    float h = uintBitsToFloat(wp.water.y);
    float slope = uintBitsToFloat(wp.water.z);
    float amplitude = uintBitsToFloat(wp.water.w);
    float tol = wp.paper.w * length(x - frame.eye.xyz) + 1e-4;
    vec3 sum = vec3(0.0);
    for (uint type = WP_RAY_REFLECTED; type <= WP_RAY_REFRACTED; ++type) {
        vec3 dir;
        if (type == WP_RAY_REFLECTED) {
            dir = reflect(l, vec3(0.0, 1.0, 0.0));
        } else if (!refract_dir(l, vec3(0.0, 1.0, 0.0), 1.0 / ior, dir)) {
            continue;
        }
        float along = (x.y - h) / dir.y;
        if (!(along > 0.0)) continue;
        vec3 s = x - dir * along;
        float turn = type == WP_RAY_REFLECTED ? 2.0 : 0.5;
        float reach = along * turn * slope + amplitude * length(dir.xz) / abs(dir.y) + amplitude;
        vec2 ls = (wp.light_view * vec4(s, 1.0)).xy;
        for (uint c = 0u; c < CASCADES; ++c) {
            float scale = pow(wp.cascade.x, float(c));
            vec2 extent = wp.range.xy * scale;
            vec2 uv = (ls / extent + 0.5) * vec2(wp.size.xy);
            vec2 texel = extent / vec2(wp.size.xy);
            ivec2 radius = min(ivec2(ceil(vec2(reach) / texel)) + 4, ivec2(MAX_REACH_TEXELS));
            ivec2 centre = ivec2(floor(uv));
            ivec2 lo = max(centre - radius, ivec2(0));
            ivec2 hi = min(centre + radius, ivec2(wp.size.xy) - 1);
            // Cascade c ≥ 1 traces only its ring: a window inside the
            // inner region (Eq. 6's border ΔX, ΔY) holds no photon.
            ivec2 border = ivec2(wp.modes.xy);
            if (c > 0u && all(greaterThanEqual(lo, border))
                && all(lessThan(hi, ivec2(wp.size.xy) - border))) continue;
            int layer = int(2u * c + type - WP_RAY_REFLECTED);
            for (int ty = lo.y; ty <= hi.y; ++ty) {
                for (int tx = lo.x; tx <= hi.x; ++tx) {
                    uint slot = imageLoad(photon_slots, ivec3(tx, ty, layer)).x;
                    if (slot == NONE) continue;
                    Photon p = photons[slot];
                    vec3 np = p.normal.xyz;
                    // The side the photon arrived at (splat.frag).
                    if (dot(np, nx) <= 0.0) continue;
                    vec3 d = x - p.position.xyz;
                    if (abs(dot(d, np)) > tol) continue;
                    vec3 u, v;
                    float r;
                    splat_axes(p, u, v, r);
                    float uu = dot(u, u), uv_ = dot(u, v), vv = dot(v, v);
                    float det = uu * vv - uv_ * uv_;
                    if (!(det > 0.0)) continue;
                    float du = dot(d, u), dv = dot(d, v);
                    vec2 ab = vec2(vv * du - uv_ * dv, uu * dv - uv_ * du) / det;
                    float w = splat_weight(ab, r);
                    if (w == 0.0) continue;
                    sum += p.flux.rgb * w / (4.0 * sqrt(det));
                }
            }
        }
    }
    return sum;
}

// Radiance toward the camera of the first surface along (o, d): see the header.
vec3 radiance_along(vec3 o, vec3 d, out float t_hit) {
    t_hit = 0.0;
    Hit h;
    // Escaped: the environment (the emitted component).
    if (!trace_closest(o, d, 0.0, 1e30, h)) return component_weight(COMPONENT_EMITTED) * environment_radiance(d);
    t_hit = h.t;
    uint m = hit_material(h);
    if (material_kind(m) != MATERIAL_DIFFUSE) return vec3(0.0);
    vec3 x = hit_position(h, o, d);
    vec3 n = hit_geometric_normal(h);
    if (dot(n, d) > 0.0) n = -n;
    ivec2 q;
    if (seen_directly(x, n, q)) return imageLoad(opaque_radiance, q).rgb;
    vec3 albedo = hit_albedo(h);
    return albedo / PI
        * (component_weight(COMPONENT_DIRECT) * direct_irradiance(x, n)
           + component_weight(COMPONENT_SURFACE_CAUSTICS) * gather(x, n));
}

// An eye under the surface looks through the water at everything it sees:
// a pixel's radiance loses exp(−σ_t d) over the distance d to its first
// surface (the turbid water's extinction, as the reference's camera
// connections and chains have it; 1 in clear water), and gains the light
// the water's medium scatters toward the eye in front of that surface
// (the shafts image; black unless the host drew them). The water's own
// pixels take both on top of the formula above; every other pixel (the
// floor, the walls, glass under the water) here, after the composite and
// the refraction pass wrote it. `under`: 1 while the eye is under the
// water (the host's test each frame), else 0; a factor, never a branch:
// lavapipe recompiles a shader at every bind while a uniform decides one
// of its branches (bindings.rs; water_photons' host-memory test).
void under_water_view(ivec2 p, vec4 fp, float under) {
    vec4 opaque = imageLoad(opaque_position, p);
    bool specular_first = fp.w >= 0.0;
    bool surface = specular_first || opaque.w != 0.0;
    float d = surface ? distance(specular_first ? fp.xyz : opaque.xyz, frame.eye.xyz) : 0.0;
    vec3 sigma_t = materials[wp.water.x].absorption_ior.rgb;
    // No surface at all under the water: the water goes on, black.
    vec3 kept = surface ? exp(-sigma_t * (d * under)) : vec3(1.0 - under);
    vec4 l = imageLoad(radiance, p);
    imageStore(radiance, p, vec4(l.rgb * kept + under * imageLoad(shafts, p).rgb, l.a));
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    // The host's test, each frame (Water::is_below_surface).
    float under = float(wp.shafts.y);
    vec4 fp = imageLoad(front_position, p);
    vec4 fn = imageLoad(front_normal, p);
    uint m = uint(fn.w + 0.5);
    // The water's pixels: its front specular surface, no thickness d_N
    // (fp.w = 0; -1 is none), no back face.
    bool water = fp.w == 0.0 && m == wp.water.x && imageLoad(back_position, p).w < 0.0;
    if (!water) {
        under_water_view(p, fp, under);
        return;
    }
    vec3 p1 = fp.xyz;
    vec3 v = normalize(p1 - frame.eye.xyz);
    vec3 n1 = normalize(fn.xyz);
    // Under the water the camera sees the surface's face turned away
    // (camera_refraction.comp): light enters the water, eta = n, Snell's
    // window and total reflection outside it, radiance times n^2; the
    // reflected leg runs in the water, the refracted one in air.
    bool inside = dot(n1, v) > 0.0;
    if (inside) n1 = -n1;
    float ior = materials[m].absorption_ior.w;
    float eta = inside ? ior : 1.0 / ior;
    vec3 sigma_t = materials[m].absorption_ior.rgb;
    float f1 = fresnel_dielectric(-dot(v, n1), eta);
    float t;
    vec3 l = f1 * radiance_along(offset_along(p1, n1), reflect(v, n1), t);
    if (inside) l *= exp(-sigma_t * t);
    vec3 t1;
    if (refract_dir(v, n1, eta, t1)) {
        vec3 behind = radiance_along(offset_along(p1, -n1), t1, t);
        l += (1.0 - f1) * eta * eta * (inside ? vec3(1.0) : exp(-sigma_t * t)) * behind;
    }
    if (inside) l *= exp(-sigma_t * distance(p1, frame.eye.xyz)); // the eye's own leg
    l += under * imageLoad(shafts, p).rgb;
    imageStore(radiance, p, vec4(l, 1.0));
}
