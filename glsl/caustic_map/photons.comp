#version 460
// Caustic maps, step 1: the photon buffer (Wyman & Davis 2006, "Approximate,
// Image-Space Caustics": render the specular objects from the light and
// store where each texel's photon lands).
//
// One invocation per texel of the light-space photon view: a perspective
// frustum fitted to the specular objects' bounding sphere (point and spot
// lights) or an orthographic box (directional). The photon leaves the light
// through the texel centre carrying
//   point/spot:  Phi = I * falloff * Omega_texel, Omega_texel the texel's
//                exact solid angle (2x2 Gauss-Legendre quadrature of
//                dOmega = du dv / (1 + u^2 + v^2)^(3/2) over the texel in
//                the tan plane: error O(h^4), below float rounding);
//   directional: Phi = E * A_texel (texel area perpendicular to the light).
// Three ways to find the refracted path (specialisation constant PHOTON_MODE):
// - PHOTON_MODE_TRACED (default): interfaces and landing point by tracing
//   the BVH; exact in expectation, any number of interfaces (see below).
// - PHOTON_MODE_IMAGE_SPACE: Wyman 2005's two-sided refraction from the
//   light (the chapter's caustics section: "render the specular objects
//   from the light ... with the same refraction code"): front interface
//   p1, N1 and the interpolated per-vertex d_N from the light-space front
//   G-buffer; d_V to the (farthest) back face at the same texel; the
//   shared glsl/common/image_space_refraction.glsl (Eq. 6.3.1, N2 from the
//   back-face normal texture at p2's projection, Eq. 6.3.2 where it holds
//   none, the selected TIR remedy), exactly as the camera uses it.
// - PHOTON_MODE_BACK_MARCH: the same G-buffers, but p2 where the refracted
//   ray passes behind the back-face map (exact for convex objects); photons
//   meeting TIR or no back face there are dropped.
// In both light-space modes the exit ray is landed on the first diffuse
// surface through the BVH (Wyman intersects the light-space depth map of
// the receivers; the BVH is exact), passing through further specular
// surfaces unrefracted.
// At the first dielectric interface the photon splits: the reflected part
// (Fresnel F) goes to the second half of the buffer, the transmitted part
// (1 - F) to the first. At each further interface the traced chains
// reflect with probability F and refract with 1 - F, weight unchanged (as
// the reference does; unbiased in expectation), from a per-texel hash
// random number; total internal reflection always reflects. Partial
// internal reflections matter: keeping only transmission (weight 1 - F)
// lost 61% of the gemstone's caustic (diamond reflects >= 17% inside at
// every exit). Mirrors reflect with their reflectance. A photon that leaves
// the scene or runs out of bounces is dropped (w = 0).
// In a participating medium (Hu et al. 2010 Sect. 5.3) the flux is
// attenuated along every segment through air, light -> first specular
// surface, between interfaces outside the objects, exit -> receiver, by the
// deterministic transmittance of glsl/common/medium.glsl (`steps.x` midpoint
// steps for noise/grid densities); inside solid objects there is no medium
// (as in the reference). The camera side (receiver -> eye) is apply.comp's.
#include "scene.glsl"
#include "optics.glsl"
#include "lights.glsl"
#include "bvh.glsl"
#include "photon.glsl"
#include "random.glsl"
#include "medium.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = CAUSTIC_BINDING_PHOTONS, std430) writeonly buffer PhotonBlock { Photon photons[]; };

layout(push_constant) uniform Push {
    vec4 origin;  // xyz: light position (perspective) or ortho plane centre; w: half-width (tan or metres)
    vec4 right;   // xyz; w: light index (uint bits)
    vec4 up;      // xyz; w: photon view size N (uint bits)
    vec4 forward; // xyz; w: SHADOW_RADIAL (perspective) or SHADOW_PLANAR (ortho) (uint bits)
    uvec4 steps;  // x: midpoint steps of the medium transmittance
} pc;

// The rebuild parameters, as specialisation constants: a pipeline holds only
// its mode's path code (the traced mode none of the image-space search).
layout(constant_id = CAUSTIC_SPEC_PHOTON_MODE) const uint PHOTON_MODE = PHOTON_MODE_TRACED;
layout(constant_id = CAUSTIC_SPEC_TIR_REMEDY) const uint TIR_REMEDY = TIR_CLAMP_CRITICAL;
layout(constant_id = CAUSTIC_SPEC_EQ632) const bool USE_EQ632 = true;

// Transmittance of the medium over the air segment o + t d, t in [0, dist].
vec3 air_transmittance(vec3 o, vec3 d, float dist) {
    return medium_transmittance_steps(o, d, dist, pc.steps.x);
}

// tau(s, x) of the first leg, from the light to the first hit x along d
// (emitted at o, `dist` from x). A planar (directional) view's origin is a
// plane just outside the specular objects, not the light: the light's path
// starts far enough back to cross the whole medium (light_travel, as
// `direct` and the airlight do).
vec3 light_leg_transmittance(vec3 o, vec3 d, float dist, vec3 x, bool planar) {
    if (!planar) return air_transmittance(o, d, dist);
    float back = light_travel(1e30, x);
    return air_transmittance(x - d * back, d, back);
}

// Light-space specular G-buffer (src/passes/specular_gbuffer.rs; photon
// modes 1 and 2): nearest front faces and farthest back faces, position
// (w: d_N at the front, < 0 where not covered) and outward smooth normal
// (w: material).
layout(set = 1, binding = CAUSTIC_BINDING_FRONT_POSITION, rgba32f) uniform readonly image2D front_position;
layout(set = 1, binding = CAUSTIC_BINDING_FRONT_NORMAL, rgba32f) uniform readonly image2D front_normal;
layout(set = 1, binding = CAUSTIC_BINDING_BACK_POSITION, rgba32f) uniform readonly image2D back_position;
layout(set = 1, binding = CAUSTIC_BINDING_BACK_NORMAL, rgba32f) uniform readonly image2D back_normal;

// Interfaces a chain may meet after the first. Light trapped in a faceted
// diamond takes long chains (landed photons: 10 total internal reflections
// on average): on assets/scenes/gemstone.toml 8 bounces dropped 2.14 W of
// the 8.44 W refracted into the gem, 32 dropped 0.48 W, 64 0.10 W, 128
// 0.007 W (0.08%).
const int MAX_BOUNCES = 128;

vec3 offset_origin(vec3 x, vec3 n) {
    return x + n * (1e-4 * max(1.0, bvh_max_abs(x)));
}

// Solid angle of the tan-plane rectangle [u0,u1] x [v0,v1] at unit distance.
float texel_solid_angle(float u0, float u1, float v0, float v1) {
    const float g = 0.5773502691896258; // 1/sqrt(3)
    float hu = 0.5 * (u1 - u0), hv = 0.5 * (v1 - v0);
    float cu = 0.5 * (u1 + u0), cv = 0.5 * (v1 + v0);
    float sum = 0.0;
    for (int i = 0; i < 2; ++i) {
        for (int j = 0; j < 2; ++j) {
            float u = cu + (i == 0 ? -g : g) * hu;
            float v = cv + (j == 0 ? -g : g) * hv;
            float r2 = 1.0 + u * u + v * v;
            sum += inversesqrt(r2 * r2 * r2);
        }
    }
    return sum * hu * hv; // 4 points of weight 1 on [-1,1]^2, Jacobian hu hv
}

// Follows a specular chain from (o, d) with weight w, choosing reflection or
// refraction at dielectric interfaces with `rng`; true if it lands on a
// diffuse surface (p3, arrival direction in `d`).
bool follow(vec3 o, inout vec3 d, inout vec3 w, bool inside, vec3 absorption, inout uint rng, out vec3 p3) {
    p3 = vec3(0.0);
    for (int bounce = 0; bounce < MAX_BOUNCES; ++bounce) {
        Hit h;
        if (!trace_closest(o, d, 0.0, 1e30, h)) return false;
        vec3 x = hit_position(h, o, d);
        if (inside) w *= exp(-absorption * h.t);
        else w *= air_transmittance(o, d, h.t);
        uint m = hit_material(h);
        uint kind = material_kind(m);
        if (kind == MATERIAL_DIFFUSE) {
            p3 = x;
            return true;
        }
        vec3 ng = hit_geometric_normal(h);
        bool front = dot(d, ng) < 0.0;
        vec3 ng_in = front ? ng : -ng;
        vec3 ns = hit_normal(h);
        vec3 n = dot(ns, ng_in) > 0.0 ? ns : -ns;
        if (kind == MATERIAL_MIRROR) {
            w *= materials[m].color.rgb;
            vec3 r = reflect(d, n);
            d = dot(r, ng_in) > 0.0 ? r : reflect(d, ng_in);
            o = offset_origin(x, ng_in);
            continue;
        }
        float eta = front ? 1.0 / materials[m].absorption_ior.w : materials[m].absorption_ior.w;
        vec3 t;
        bool ok = refract_dir(d, n, eta, t);
        if (ok && dot(t, ng_in) >= 0.0) {
            n = ng_in;
            ok = refract_dir(d, n, eta, t);
        }
        if (ok && rng_next(rng) >= fresnel_dielectric(-dot(d, n), eta)) {
            d = t;
            o = offset_origin(x, -ng_in);
            inside = front;
            absorption = materials[m].absorption_ior.rgb;
        } else {
            // Partial reflection (probability F) or total internal reflection.
            vec3 r = reflect(d, n);
            d = dot(r, ng_in) > 0.0 ? r : reflect(d, ng_in);
            o = offset_origin(x, ng_in);
        }
    }
    return false;
}

// Lands a photon leaving the specular objects at o along d on the first
// diffuse surface, passing through specular ones unrefracted (image-space
// mode: the caustic map models one refractor's two interfaces).
bool land(vec3 o, vec3 d, out vec3 p3) {
    p3 = vec3(0.0);
    for (int i = 0; i < 16; ++i) {
        Hit h;
        if (!trace_closest(o, d, 0.0, 1e30, h)) return false;
        vec3 x = hit_position(h, o, d);
        if (material_kind(hit_material(h)) == MATERIAL_DIFFUSE) {
            p3 = x;
            return true;
        }
        o = x + d * (1e-4 * max(1.0, bvh_max_abs(x)));
    }
    return false;
}

// The photon-view texel x projects to, or (-1, -1) outside the view.
ivec2 light_texel(vec3 x) {
    uint n_size = floatBitsToUint(pc.up.w);
    vec3 v = x - pc.origin.xyz;
    vec2 st;
    if (floatBitsToUint(pc.forward.w) == SHADOW_PLANAR) {
        st = vec2(dot(v, pc.right.xyz), dot(v, pc.up.xyz));
    } else {
        float z = dot(v, pc.forward.xyz);
        if (z <= 0.0) return ivec2(-1);
        st = vec2(dot(v, pc.right.xyz), dot(v, pc.up.xyz)) / z;
    }
    ivec2 q = ivec2(floor((st / pc.origin.w * 0.5 + 0.5) * float(n_size)));
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(n_size)))) return ivec2(-1);
    return q;
}

// Depth of x along the light's rays (distance, or depth along the axis).
float light_depth(vec3 x) {
    vec3 v = x - pc.origin.xyz;
    return floatBitsToUint(pc.forward.w) == SHADOW_PLANAR ? dot(v, pc.forward.xyz) : length(v);
}

// True if x lies at or behind the back surface stored at its texel (or
// outside the back faces' coverage: the ray has left the object).
bool behind_back(vec3 x) {
    ivec2 q = light_texel(x);
    if (q.x < 0) return true;
    vec4 b = imageLoad(back_position, q);
    if (b.w < 0.0) return true;
    return light_depth(x) >= light_depth(b.xyz);
}

// The back-face normal at x's light-view texel (for the shared two-sided
// refraction code), false where no back face covers it.
bool back_face_normal(vec3 x, out vec3 n) {
    n = vec3(0.0);
    ivec2 q = light_texel(x);
    if (q.x < 0 || imageLoad(back_position, q).w < 0.0) return false;
    n = imageLoad(back_normal, q).xyz;
    return true;
}

#include "image_space_refraction.glsl"

// `land` for a photon leaving the refractor at o: the flux is attenuated by
// the medium over the straight path to the receiver.
bool land_through_air(vec3 o, vec3 d, inout vec3 w, out vec3 p3) {
    if (!land(o, d, p3)) return false;
    w *= air_transmittance(o, d, length(p3 - o));
    return true;
}

// The refracted photon of texel `id` through the refractor seen from the
// light, entering at p1 (outward normal n1 facing the light, incident
// direction d, material m, interpolated d_N), weight w already times
// 1 - F1: lands it on a diffuse surface (p3, arrival direction `dir`).
// Mode 1: Wyman's two-sided refraction (shared with the camera). Mode 2:
// the refracted ray marched against the back-face map instead of Eq. 6.3.1
// (steps of max(d_V, d_N) / 32, then 16 bisections); exact for convex
// objects up to the map's resolution.
bool image_space_refraction(uvec2 id, vec3 p1, vec3 n1, vec3 d, uint m, float d_n, inout vec3 w, out vec3 p3, out vec3 dir) {
    p3 = vec3(0.0);
    dir = vec3(0.0);
    float ior = materials[m].absorption_ior.w;
    vec4 bp = imageLoad(back_position, ivec2(id));
    if (bp.w < 0.0) {
        // No back face at this texel. With d_N > 0 the refractor is closed
        // and its back face just missed (silhouette): dropped, as before.
        // With d_N = 0 it has no back surface (an open sheet, e.g. water):
        // one interface, as the camera does it (refraction.comp): refract
        // once at p1 and land through the BVH, Beer-Lambert over the path
        // to the landing point (flux crosses with 1 - F1 only, no n^2).
        if (d_n > 0.0) return false;
        vec3 t1;
        if (!refract_dir(d, n1, 1.0 / ior, t1)) return false;
        if (!land(p1, t1, p3)) return false;
        w *= exp(-materials[m].absorption_ior.rgb * length(p3 - p1));
        dir = t1;
        return true;
    }
    float d_v = length(bp.xyz - p1);
    if (PHOTON_MODE == PHOTON_MODE_IMAGE_SPACE) {
        TwoSidedExit e;
        if (!two_sided_refraction(d, p1, n1, ior, d_v, d_n, TIR_REMEDY, USE_EQ632, e)) return false;
        w *= e.transmit * exp(-materials[m].absorption_ior.rgb * e.dist);
        dir = e.dir;
        return land_through_air(e.p2, e.dir, w, p3);
    }
    // PHOTON_MODE_BACK_MARCH
    vec3 t1;
    if (!refract_dir(d, n1, 1.0 / ior, t1)) return false;
    float t_max = 1.05 * max(max(d_v, d_n), 1e-4);
    float lo = 0.0, hi = -1.0;
    for (int i = 1; i <= 32; ++i) {
        float t = t_max * float(i) / 32.0;
        if (behind_back(p1 + t * t1)) { hi = t; break; }
        lo = t;
    }
    if (hi < 0.0) return false;
    for (int i = 0; i < 16; ++i) {
        float mid = 0.5 * (lo + hi);
        if (behind_back(p1 + mid * t1)) hi = mid; else lo = mid;
    }
    vec3 p2 = p1 + hi * t1;
    vec3 n2;
    if (!back_face_normal(p2, n2)) return false;
    n2 = -normalize(n2); // facing the ray inside the glass
    if (dot(n2, t1) > 0.0) n2 = -n2;
    vec3 t2;
    if (!refract_dir(t1, n2, ior, t2)) return false;
    w *= exp(-materials[m].absorption_ior.rgb * hi) * (1.0 - fresnel_dielectric(-dot(t1, n2), ior));
    dir = t2;
    return land_through_air(p2, t2, w, p3);
}

void main() {
    uint n_size = floatBitsToUint(pc.up.w);
    uvec2 id = gl_GlobalInvocationID.xy;
    if (id.x >= n_size || id.y >= n_size) return;
    uint index = id.y * n_size + id.x;
    uint count = n_size * n_size;
    uint l = floatBitsToUint(pc.right.w);
    bool planar = floatBitsToUint(pc.forward.w) == SHADOW_PLANAR;
    float h = pc.origin.w;
    float s0 = (2.0 * float(id.x) / float(n_size) - 1.0) * h;
    float s1 = (2.0 * float(id.x + 1u) / float(n_size) - 1.0) * h;
    float t0 = (2.0 * float(id.y) / float(n_size) - 1.0) * h;
    float t1 = (2.0 * float(id.y + 1u) / float(n_size) - 1.0) * h;
    float s = 0.5 * (s0 + s1), t = 0.5 * (t0 + t1);

    vec3 o, d, w;
    float measure;
    Light light = lights[l];
    if (planar) {
        o = pc.origin.xyz + s * pc.right.xyz + t * pc.up.xyz;
        d = pc.forward.xyz;
        measure = (s1 - s0) * (t1 - t0);
        w = light.intensity.rgb * measure;
    } else {
        o = pc.origin.xyz;
        d = normalize(pc.forward.xyz + s * pc.right.xyz + t * pc.up.xyz);
        measure = texel_solid_angle(s0, s1, t0, t1);
        vec3 intensity = light.intensity.rgb;
        if (light_kind(l) == LIGHT_SPOT) {
            intensity *= spot_falloff(dot(d, light.direction.xyz), light.direction.w, light.intensity.w);
        }
        w = intensity * measure;
    }
    Photon none = Photon(vec4(0.0), vec4(0.0, 0.0, 0.0, measure), vec4(0.0));
    photons[index] = none;
    photons[count + index] = none;
    if (all(equal(w, vec3(0.0)))) return;

    // The first surface: only photons meeting a specular object first make
    // caustics. Traced: the BVH; image space: the front-face G-buffer (its
    // position lies on this texel's centre ray).
    bool image_space = PHOTON_MODE != PHOTON_MODE_TRACED;
    uint m;
    vec3 x, ng, ns;
    float d_n = 0.0;
    bool front = true;
    if (image_space) {
        vec4 fp = imageLoad(front_position, ivec2(id));
        if (fp.w < 0.0) return;
        d_n = fp.w;
        vec4 fn = imageLoad(front_normal, ivec2(id));
        m = uint(fn.w + 0.5);
        x = fp.xyz;
        w *= light_leg_transmittance(o, d, dot(x - o, d), x, planar);
        ns = normalize(fn.xyz);
        ng = dot(ns, d) < 0.0 ? ns : -ns;
    } else {
        Hit hit;
        if (!trace_closest(o, d, 0.0, 1e30, hit)) return;
        m = hit_material(hit);
        x = hit_position(hit, o, d);
        w *= light_leg_transmittance(o, d, hit.t, x, planar);
        ng = hit_geometric_normal(hit);
        front = dot(d, ng) < 0.0;
        ns = hit_normal(hit);
    }
    uint kind = material_kind(m);
    if (kind == MATERIAL_DIFFUSE) return;
    vec3 ng_in = front ? ng : -ng;
    vec3 n = dot(ns, ng_in) > 0.0 ? ns : -ns;

    // Reflected photon (mirror: reflectance; dielectric: Fresnel F).
    vec3 r = reflect(d, n);
    r = dot(r, ng_in) > 0.0 ? r : reflect(d, ng_in);
    float eta = 1.0;
    float f = 1.0;
    vec3 wr = w * materials[m].color.rgb;
    if (kind == MATERIAL_DIELECTRIC) {
        eta = front ? 1.0 / materials[m].absorption_ior.w : materials[m].absorption_ior.w;
        f = fresnel_dielectric(-dot(d, n), eta);
        wr = w * f;
    }
    // Independent streams for the two chains of this texel.
    uint rng_reflected = rng_seed(index, 0u);
    uint rng_refracted = rng_seed(index, 1u);
    vec3 p3;
    vec3 dr = r;
    if (any(greaterThan(wr, vec3(0.0))) && follow(offset_origin(x, ng_in), dr, wr, false, vec3(0.0), rng_reflected, p3)) {
        photons[count + index] = Photon(vec4(p3, 1.0), vec4(wr, measure), vec4(dr, 0.0));
    }
    if (kind != MATERIAL_DIELECTRIC) return;

    // Refracted photon: Snell at the front interface, weight 1 - F, then the chain.
    vec3 tdir;
    bool ok = refract_dir(d, n, eta, tdir);
    vec3 nt = n;
    if (ok && dot(tdir, ng_in) >= 0.0) {
        nt = ng_in;
        ok = refract_dir(d, nt, eta, tdir);
    }
    if (!ok) return;
    vec3 wt = w * (1.0 - fresnel_dielectric(-dot(d, nt), eta));
    if (image_space) {
        vec3 dt;
        if (image_space_refraction(id, x, n, d, m, d_n, wt, p3, dt)) {
            photons[index] = Photon(vec4(p3, 1.0), vec4(wt, measure), vec4(dt, 0.0));
        }
        return;
    }
    if (follow(offset_origin(x, -ng_in), tdir, wt, front, materials[m].absorption_ior.rgb, rng_refracted, p3)) {
        photons[index] = Photon(vec4(p3, 1.0), vec4(wt, measure), vec4(tdir, 0.0));
    }
}
