// Shared by the reference light tracer's shaders: descriptor set 1 (the
// accumulation buffers), push constants and the camera measurement.
#ifndef REFERENCE_COMMON_GLSL
#define REFERENCE_COMMON_GLSL

#extension GL_EXT_shader_atomic_float : require

#define SCENE_SET 0
#include "scene.glsl"
#include "bvh.glsl"
#include "random.glsl"
#include "optics.glsl"
#include "lights.glsl"
#include "medium.glsl"
#include "emitters.glsl"

// Every estimate of one pass is radiance (W m^-2 sr^-1) added into `pass_accum`
// (COMPONENT_COUNT images of width*height rgb floats, float atomics); the fold
// pass adds it to `total_accum` and clears it, so the image after P passes is
// total / P and the spread of the pass estimates measures the noise.
layout(set = 1, binding = REFERENCE_BINDING_TOTAL, std430) buffer TotalAccum { float total_accum[]; };
layout(set = 1, binding = REFERENCE_BINDING_PASS, std430) buffer PassAccum { float pass_accum[]; };
// Per pixel: sum over passes of the pass estimate's luminance, and of its square.
layout(set = 1, binding = REFERENCE_BINDING_MOMENTS, std430) buffer Moments { vec2 moments[]; };

// Progressive photon mapping (Knaus & Zwicker 2011): a visible point is the
// first diffuse point a camera path reaches through at least one specular
// bounce (camera.comp), kept in a hash grid of cell side 2 r so that a
// photon finds every point within r in at most 2x2x2 cells. A pixel has
// one per branch of its camera chain a pass (camera.comp, "Fresnel
// splitting"): point i belongs to pixel i >> pc.fresnel_splits.
struct VisiblePoint {
    vec4 position; // w: 1 when the pixel has a visible point this pass
    vec4 normal;   // the side of the surface the camera path sees
    vec4 weight;   // camera path weight times the BRDF albedo / pi
};
layout(set = 1, binding = REFERENCE_BINDING_VISIBLE_POINTS, std430) buffer VisiblePoints { VisiblePoint visible_points[]; };
layout(set = 1, binding = REFERENCE_BINDING_SURFACE_HEADS, std430) buffer SurfaceHeads { uint surface_heads[]; };
layout(set = 1, binding = REFERENCE_BINDING_SURFACE_NEXT, std430) buffer SurfaceNext { uint surface_next[]; };

// Volume photon map: every tentative medium collision of the photon pass,
// with its flux already weighted by sigma_s / majorant (the same weight its
// camera connection gets), in a hash grid of cell side r_v: the ball of
// radius r_v around a gather point overlaps at most 3x3x3 cells, each of
// which volume_gather.comp walks in its own invocation.
struct VolumePhoton {
    vec4 position; // w: path-type tag (uint bits)
    vec4 direction;
    vec4 flux;     // W, divided by the photons emitted this pass
};
layout(set = 1, binding = REFERENCE_BINDING_VOLUME_PHOTONS, std430) buffer VolumePhotons { VolumePhoton volume_photons[]; };
layout(set = 1, binding = REFERENCE_BINDING_VOLUME_HEADS, std430) buffer VolumeHeads { uint volume_heads[]; };
layout(set = 1, binding = REFERENCE_BINDING_VOLUME_NEXT, std430) buffer VolumeNext { uint volume_next[]; };

// A point on a camera path in the medium where the volume photon map is
// gathered (volume_points.comp appends them, volume_gather.comp sums).
struct GatherPoint {
    vec4 position;  // w: pixel index (uint bits)
    vec4 direction; // the camera ray's direction; w: path-type mask (uint bits)
    vec4 weight;    // camera path weight times the quadrature step (m); w: HG g there
};
layout(set = 1, binding = REFERENCE_BINDING_GATHER_POINTS, std430) buffer GatherPoints { GatherPoint gather_points[]; };
// Cells a gather point's ball can overlap: one volume_gather.comp invocation each.
const uint GATHER_CELLS = 27u;

layout(set = 1, binding = REFERENCE_BINDING_STATS, std430) buffer Stats {
    uint volume_photon_count;
    float noise_variance_sum;
    float noise_mean_sum;
    uint gather_point_count;   // appended this pass (may pass the capacity)
    // VkDispatchIndirectCommand of volume_gather.comp (byte 16):
    uint gather_groups_x, gather_groups_y, gather_groups_z;
    uint gather_longest_walk;  // the most photons one cell walk visited this pass
};

layout(push_constant) uniform Push {
    uint seed;             // a different value every dispatch
    uint max_depth;        // longest path (specular bounces + scattering events)
    uint diffuse_bounces;  // photons continue this many times past diffuse surfaces
    uint component;        // resolve only: which image (COMPONENT_COUNT = all)
    float passes;          // resolve and noise: passes so far
    float pass_photons;    // photons emitted per pass
    float radius;          // surface gather radius r_i of this pass (m)
    float volume_radius;   // volume gather radius of this pass (m)
    uint surface_mask;     // surface hash table size - 1 (a power of two)
    uint volume_mask;      // volume hash table size - 1
    uint volume_capacity;  // volume photons stored at most (0: no volume photon map)
    uint gather;           // 1: progressive photon mapping on (0: light tracer only)
    vec4 aim;              // bounding sphere of the specular triangles (w = 0: none)
    float aim_share;       // share of photons aimed at it
    uint gather_capacity;  // gather points stored at most
    uint aim_guide;        // 1: aimed photons follow the aim guide (aim_guide.glsl)
    uint fresnel_splits;   // camera chains split at this many Fresnel choices (camera.comp)
} pc;

uint image_width() { return uint(frame.viewport.x); }
uint image_height() { return uint(frame.viewport.y); }
uint image_pixels() { return image_width() * image_height(); }
// Visible points a pixel has room for a pass: one per camera chain branch.
uint visible_points_per_pixel() { return 1u << pc.fresnel_splits; }

// Adds the radiance estimate `value` to pixel `index` of this pass's image `component`.
void add_pass(uint index, uint component, vec3 value) {
    if (all(equal(value, vec3(0.0)))) return; // no atomics for nothing
    uint base = (component * image_pixels() + index) * 3u;
    atomicAdd(pass_accum[base + 0u], value.r);
    atomicAdd(pass_accum[base + 1u], value.g);
    atomicAdd(pass_accum[base + 2u], value.b);
}

// The hash-grid cell of x for cells of side `side`, and its bucket.
ivec3 grid_cell(vec3 x, float side) { return ivec3(floor(x / side)); }
float volume_cell_side() { return pc.volume_radius; }
uint grid_bucket(ivec3 c, uint mask) {
    return (uint(c.x) * 73856093u ^ uint(c.y) * 19349663u ^ uint(c.z) * 83492791u) & mask;
}

const float RAY_EPS = 1e-4;

// Offsets a ray origin off a surface along the side `side_normal` points to,
// scaled with the magnitude of the position to survive float rounding.
vec3 offset_origin(vec3 x, vec3 side_normal) {
    return x + side_normal * (RAY_EPS * (1.0 + max(abs(x.x), max(abs(x.y), abs(x.z)))));
}

// The state of a ray or photon travelling through specular chains.
struct SpecularState {
    vec3 origin;
    vec3 dir;
    vec3 weight;
    bool inside;             // inside a dielectric (the scene's [medium] is not there)
    vec3 inside_extinction;  // that dielectric's sigma_t: absorption + scattering, 1/m
    vec4 inside_scattering;  // the medium inside it: sigma_s (rgb, 1/m; 0: none), HG g (w)
};

// Crossing into dielectric m, or out of it (one level: dielectrics do not nest).
void enter_dielectric(inout SpecularState s, Material m) {
    s.inside = true;
    s.inside_scattering = m.scattering;
    s.inside_extinction = m.absorption_ior.rgb; // absorption + scattering
}
void leave_dielectric(inout SpecularState s) {
    s.inside = false;
    s.inside_extinction = vec3(0.0);
    s.inside_scattering = vec4(0.0);
}

// Inside a dielectric whose medium scatters (turbid water): free-flight
// sampling there, like the scene's [medium] outside.
bool scatters_inside(SpecularState s) {
    return s.inside && any(greaterThan(s.inside_scattering.rgb, vec3(0.0)));
}

// Transmittance along o + t d, t in [0, dist], a segment free of surfaces
// that lies where s is: inside its dielectric (homogeneous: Beer-Lambert
// with the inside's extinction) or outside (the scene's medium,
// `medium_transmittance`).
vec3 region_transmittance(SpecularState s, vec3 o, vec3 d, float dist, inout uint rng) {
    if (s.inside) return exp(-s.inside_extinction * dist);
    return medium_transmittance(o, d, dist, rng);
}

// Mirror reflection of reflectance `reflectance` on the side the ray
// arrives at (a mirror, or a `mixed` material's mirror part), about the
// shading normal, or the geometric one where the shading normal would send
// the ray below the surface.
void mirror_bounce(inout SpecularState s, vec3 x, vec3 ng, vec3 ns, bool front, vec3 reflectance) {
    vec3 ng_in = front ? ng : -ng;                   // facing the arriving ray
    vec3 ns_in = dot(ns, ng_in) > 0.0 ? ns : -ns;
    s.weight *= reflectance;
    vec3 r = reflect(s.dir, ns_in);
    s.dir = dot(r, ng_in) > 0.0 ? r : reflect(s.dir, ng_in);
    s.origin = offset_origin(x, ng_in);
}

// Reflects at a mirror, reflects or passes a thin dielectric sheet, or
// reflects/refracts at a dielectric (exact Fresnel;
// reflection chosen with probability F keeps the weight unchanged; total
// internal reflection always reflects). `front`: the ray arrived on the side
// the geometric normal `ng` points to. Smooth shading normals can bend a new
// direction to the wrong side of the true surface at grazing angles; then the
// geometric normal is used instead, so the inside/outside state stays right.
// `carries_radiance`: a camera (importance) path carries radiance, which
// crossing an interface from index n_i to n_t scales by (n_t/n_i)^2 in the
// light's direction of travel (radiance / n^2 is invariant): a camera ray
// entering water from the air sees L_water / n^2. Photons carry flux, which
// no such factor touches.
// Returns the probability of the reflected branch (1 at a mirror and under
// total internal reflection): u < it reflects, so u = -1 forces reflection
// and u = 2 the other branch, with the weights a random choice gives.
float specular_bounce(inout SpecularState s, vec3 x, vec3 ng, vec3 ns, bool front, Material m, float u, bool carries_radiance) {
    uint kind = floatBitsToUint(m.color.w);
    if (kind == MATERIAL_MIRROR) {
        mirror_bounce(s, x, ng, ns, front, m.color.rgb);
        return 1.0;
    }
    vec3 ng_in = front ? ng : -ng;                   // facing the arriving ray
    vec3 ns_in = dot(ns, ng_in) > 0.0 ? ns : -ns;
    if (kind == MATERIAL_THIN_DIELECTRIC) {
        // A thin sheet (optics.glsl thin_sheet_reflectance): reflected with
        // probability R_sheet (about the shading normal, as a mirror), else
        // through undeflected; in and out of one medium, so no (n_t/n_i)^2.
        vec3 n = ns_in;
        float r_sheet = thin_sheet_reflectance(dot(s.dir, n), m.absorption_ior.w);
        if (u < r_sheet) {
            vec3 r = reflect(s.dir, n);
            s.dir = dot(r, ng_in) > 0.0 ? r : reflect(s.dir, ng_in);
            s.origin = offset_origin(x, ng_in);
        } else {
            s.origin = offset_origin(x, -ng_in);
        }
        return r_sheet;
    }
    float ior = m.absorption_ior.w;
    float eta = front ? 1.0 / ior : ior;
    vec3 n = ns_in;
    float f = fresnel_dielectric(-dot(s.dir, n), eta);
    vec3 refracted;
    bool refracts = u >= f && refract_dir(s.dir, n, eta, refracted);
    if (refracts && dot(refracted, ng_in) >= 0.0) {
        // Bent back out by the shading normal: refract about the true surface.
        n = ng_in;
        refracts = refract_dir(s.dir, n, eta, refracted);
    }
    if (refracts) {
        // eta = n(side the ray comes from) / n(side it enters); the light
        // travels the other way, from index 1/eta-side to the ray's side.
        if (carries_radiance) s.weight *= eta * eta;
        s.dir = refracted;
        s.origin = offset_origin(x, -ng_in);
        if (front) enter_dielectric(s, m);
        else leave_dielectric(s);
    } else {
        vec3 r = reflect(s.dir, n);
        s.dir = dot(r, ng_in) > 0.0 ? r : reflect(s.dir, ng_in);
        s.origin = offset_origin(x, ng_in);
    }
    return f;
}

// A point y uniform over area light `em` (pdf 1 / area) and the normal n
// it emits along there: rect and triangle, one-sided (the triangle's front
// being the side cross(p1 - p0, p2 - p0) points to; a triangle by Shirley's
// warp, barycentrics (1 - sqrt(u1), sqrt(u1) (1 - u2), sqrt(u1) u2));
// sphere: on the exact sphere, outward (A = 4 pi r^2), outside its
// inscribed tessellation.
void sample_emitter_point(Emitter em, vec2 u, out vec3 y, out vec3 n, out float area) {
    uint kind = floatBitsToUint(em.position.w);
    if (kind == EMITTER_TRIANGLE) {
        vec3 e1 = em.normal.xyz, e2 = em.tangent.xyz;
        n = normalize(cross(e1, e2));
        float su = sqrt(u.x);
        y = em.position.xyz + e1 * (su * (1.0 - u.y)) + e2 * (su * u.y);
        area = em.normal.w;
    } else if (kind == EMITTER_RECT) {
        n = em.normal.xyz;
        vec3 t = em.tangent.xyz;
        vec3 b = cross(n, t);
        y = em.position.xyz + t * ((u.x - 0.5) * em.normal.w) + b * ((u.y - 0.5) * em.tangent.w);
        area = em.normal.w * em.tangent.w;
    } else {
        n = uniform_sphere(u);
        float r = em.normal.w;
        y = em.position.xyz + n * r;
        area = 4.0 * PI * r * r;
    }
}

// Area lights whose direct light camera.comp samples by shadow rays (so
// trace.comp leaves their photons' first hits to it): rects and triangles.
// Not spheres: a point on the exact sphere lies outside its tessellation,
// which would block every shadow ray toward it.
bool emitter_sampled_by_camera(Emitter em) {
    uint kind = floatBitsToUint(em.position.w);
    return kind == EMITTER_RECT || kind == EMITTER_TRIANGLE;
}

const uint NO_DIELECTRIC = 0xffffffffu;

// The material of the dielectric around p: walking straight up from p
// through every surface, the first dielectric met from its back face
// whose front face the walk did not cross first (the underside of water
// above a floating or submerged object, the inside of a closed glass
// object), else NO_DIELECTRIC. One level: a dielectric entered on the way
// is left again before another counts.
uint dielectric_around(vec3 p) {
    vec3 up = vec3(0.0, 1.0, 0.0);
    vec3 o = p;
    uint entered = NO_DIELECTRIC;
    for (uint step = 0u; step < 32u; ++step) {
        Hit h;
        if (!trace_closest(o, up, 0.0, 1e30, h)) return NO_DIELECTRIC;
        uint m = hit_material(h);
        vec3 ng = hit_geometric_normal(h);
        bool from_back = dot(up, ng) > 0.0;
        if (material_kind(m) == MATERIAL_DIELECTRIC) {
            if (!from_back) entered = m;
            else if (m == entered) entered = NO_DIELECTRIC;
            else return m;
        }
        o = offset_origin(o + h.t * up, from_back ? ng : -ng);
    }
    return NO_DIELECTRIC;
}

// The state of a camera path at the eye (weight 1, no direction yet):
// inside the dielectric around the eye (`dielectric_around`: under water,
// in a closed glass object), else outside. Lights are assumed outside
// every dielectric.
SpecularState eye_state() {
    SpecularState s;
    s.origin = frame.eye.xyz;
    s.dir = vec3(0.0, 1.0, 0.0);
    s.weight = vec3(1.0);
    leave_dielectric(s);
    uint around = dielectric_around(s.origin);
    if (around != NO_DIELECTRIC) enter_dielectric(s, materials[around]);
    return s;
}

// A camera ray through a uniformly jittered point of pixel p, from the
// eye's state `at_eye` (`eye_state`).
SpecularState camera_ray_through(uvec2 p, vec2 jitter, SpecularState at_eye) {
    vec2 ndc = (vec2(p) + jitter) / frame.viewport.xy * 2.0 - 1.0;
    vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    SpecularState s = at_eye;
    s.dir = normalize(far.xyz / far.w - s.origin);
    return s;
}

// The camera ray through a uniform random point of pixel p.
SpecularState camera_ray(uvec2 p, SpecularState at_eye, inout uint rng) {
    return camera_ray_through(p, vec2(rng_next(rng), rng_next(rng)), at_eye);
}

#endif
