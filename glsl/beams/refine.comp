#version 460
// beams, Sects. 4.1-4.2 and 6: one level of the hierarchical projected grid.
//
// The paper refines with a geometry shader fed back through stream-out;
// this is its modern equivalent: one compute dispatch per level, whose
// thread count comes from the previous level through an indirect dispatch
// (args.comp turns the atomic counters into VkDispatchIndirectCommand and
// VkDrawIndirectCommand), appending children and beams through atomic
// counters.
//
// Level 0 (Sect. 4.1): the regular base x base grid over the light's view
// of the specular objects, two triangles per cell, generated from the
// thread index. Every grid vertex takes its position and normal from the
// light-space G-buffer texel it falls in ("projecting the grid onto the
// lit surfaces"). Grid coordinates are integers at the finest level's
// resolution (base << BEAMS_MAX_LEVELS), so children's midpoints are exact.
//
// Per triangle, the oracle (Sect. 4.2) splits it into four (edge
// midpoints) while levels remain and
//  (a) it spans a discontinuity: a vertex outside the specular surfaces
//      (silhouette), different materials, depths (distance from the light)
//      differing by more than `split.x` relative, or normals by more than
//      acos(split.y);
//  (b) its beam converges (the area function's smallest |A(y)| over the
//      beam below `split.z` times the base's |A(0)|) or carries more than
//      `split.w` W;
//  (c) the point of its central ray closest to the camera sees the beam's
//      cross-section there under more than `split2.x` radians.
// Otherwise it is final: a triangle with every vertex on one specular
// surface and no depth jump becomes one beam per specular event (mirror:
// reflected; dielectric: reflected and refracted, Fresnel splitting the
// flux, two-sided refraction through the back faces of the light-space
// G-buffer, Sect. 6, or exactly through the BVH); a triangle still crossing a silhouette at the last
// level is dropped, and its measure counted (`BEAMS_STAT_DROPPED_MEASURE`).
#extension GL_EXT_shader_atomic_float : require
#include "scene.glsl"
#include "beams_bindings.glsl"
#include "optics.glsl"
#include "lights.glsl"
#include "bvh.glsl"
#include "random.glsl"
#include "medium.glsl"
#include "beam.glsl"
#include "traced_refraction.glsl"

layout(local_size_x = BEAMS_REFINE_GROUP) in;

layout(set = 1, binding = BEAMS_BINDING_TRIANGLES_A, std430) buffer TrianglesA { uvec4 tris_a[]; };
layout(set = 1, binding = BEAMS_BINDING_TRIANGLES_B, std430) buffer TrianglesB { uvec4 tris_b[]; };
layout(set = 1, binding = BEAMS_BINDING_BEAMS, std430) writeonly buffer BeamBlock { Beam beams[]; };
// The counters (bindings.rs has the layout): u32 words, then the f32
// statistics summed by float atomics, then the fragment count.
layout(set = 1, binding = BEAMS_BINDING_COUNTERS, std430) buffer CounterBlock {
    uint counters[BEAMS_STAT_KEPT_MEASURE];
    float measures[4]; // kept measure, dropped measure, flux in (kept), flux out (beams): luminance W
    uint fragments;
};
layout(set = 1, binding = BEAMS_BINDING_FRONT_POSITION, rgba32f) uniform readonly image2D front_position;
layout(set = 1, binding = BEAMS_BINDING_FRONT_NORMAL, rgba32f) uniform readonly image2D front_normal;
layout(set = 1, binding = BEAMS_BINDING_BACK_POSITION, rgba32f) uniform readonly image2D back_position;
layout(set = 1, binding = BEAMS_BINDING_BACK_NORMAL, rgba32f) uniform readonly image2D back_normal;

layout(push_constant) uniform Push {
    vec4 origin;  // light view (passes::light_views::LightView): xyz origin; w half extent
    vec4 right;   // w: light index (uint bits)
    vec4 up;      // w: G-buffer size N (uint bits)
    vec4 forward; // w: SHADOW_RADIAL or SHADOW_PLANAR (uint bits)
    uvec4 grid;   // x: this level; y: levels; z: base grid side; w: triangle capacity per list
    uvec4 config; // x: beam capacity; y: TIR_* remedy; z: Eq. 6.3.2 on; w: medium steps
    vec4 split;   // x: relative depth; y: cos of the normal angle; z: focus ratio; w: energy (W)
    vec4 split2;  // x: camera-space angular size (rad); y: BEAMS_REFRACTION_* (uint bits); z: extrusion cut-off
} pc;

#define STAT_ADD(word, value) atomicAdd(counters[word], value)

bool planar_view() { return floatBitsToUint(pc.forward.w) == SHADOW_PLANAR; }
uint view_size() { return floatBitsToUint(pc.up.w); }

// The view texel x projects to, or (-1, -1) outside the view.
ivec2 light_texel(vec3 x) {
    uint n_size = view_size();
    vec3 v = x - pc.origin.xyz;
    vec2 st;
    if (planar_view()) {
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

// The back-face normal at x's texel, for image_space_refraction.glsl.
bool back_face_normal(vec3 x, out vec3 n) {
    n = vec3(0.0);
    ivec2 q = light_texel(x);
    if (q.x < 0 || imageLoad(back_position, q).w < 0.0) return false;
    n = imageLoad(back_normal, q).xyz;
    return true;
}

#include "image_space_refraction.glsl"

uint hit_object(Hit h) { return floatBitsToUint(triangles[h.triangle].p1.w); }

uint grid_fine() { return pc.grid.z << BEAMS_MAX_LEVELS; }

uvec2 unpack_vertex(uint v) { return uvec2(v & 0xffffu, v >> 16); }
uint pack_vertex(uvec2 g) { return g.x | (g.y << 16); }

// The G-buffer texel of grid vertex g (grid coordinates at the finest level).
ivec2 vertex_texel(uvec2 g) {
    int n = int(view_size());
    vec2 u = vec2(g) / float(grid_fine());
    return min(ivec2(u * float(n)), ivec2(n - 1));
}

// The light-view coordinates (tan plane or ortho plane) of a texel's centre.
vec2 texel_plane(ivec2 q) {
    return ((vec2(q) + 0.5) / float(view_size()) * 2.0 - 1.0) * pc.origin.w;
}

// Incident direction through the texel centre (perspective) or the view axis.
vec3 texel_direction(ivec2 q) {
    if (planar_view()) return pc.forward.xyz;
    vec2 st = texel_plane(q);
    return normalize(pc.forward.xyz + st.x * pc.right.xyz + st.y * pc.up.xyz);
}

// Solid angle of the spherical triangle of unit vectors a, b, c (Van
// Oosterom & Strackee 1983): tan(Omega / 2) = |a . (b x c)| / (1 + a.b + b.c + c.a).
float solid_angle(vec3 a, vec3 b, vec3 c) {
    return 2.0 * atan(abs(dot(a, cross(b, c))), 1.0 + dot(a, b) + dot(b, c) + dot(c, a));
}

// Flux (W) the light sends through the triangle of texels q0 q1 q2
// (GUIDE §2), and the triangle's measure: a point light I times the exact
// solid angle; a spot the integral of I(w) over it (the exact solid angles
// of 16 sub-triangles times the falloff at their centres); a directional
// light E times the area projected on its direction.
vec3 incident_flux(ivec2 q0, ivec2 q1, ivec2 q2, out float measure) {
    uint l = floatBitsToUint(pc.right.w);
    Light light = lights[l];
    if (planar_view()) {
        vec2 a = texel_plane(q0), b = texel_plane(q1), c = texel_plane(q2);
        measure = 0.5 * abs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
        return light.intensity.rgb * measure;
    }
    vec3 a = texel_direction(q0), b = texel_direction(q1), c = texel_direction(q2);
    measure = solid_angle(a, b, c);
    if (light_kind(l) != LIGHT_SPOT) return light.intensity.rgb * measure;
    const int S = 4;
    float sum = 0.0;
    for (int i = 0; i < S; ++i) {
        for (int j = 0; i + j < S; ++j) {
            for (int up = 0; up < 2; ++up) {
                if (up == 1 && i + j + 1 >= S) continue;
                ivec2 k0 = up == 0 ? ivec2(i, j) : ivec2(i + 1, j);
                ivec2 k1 = up == 0 ? ivec2(i + 1, j) : ivec2(i + 1, j + 1);
                ivec2 k2 = ivec2(i, j + 1);
                vec3 p0 = normalize(a + (float(k0.x) * (b - a) + float(k0.y) * (c - a)) / float(S));
                vec3 p1 = normalize(a + (float(k1.x) * (b - a) + float(k1.y) * (c - a)) / float(S));
                vec3 p2 = normalize(a + (float(k2.x) * (b - a) + float(k2.y) * (c - a)) / float(S));
                vec3 centre = normalize(p0 + p1 + p2);
                sum += solid_angle(p0, p1, p2) *
                       spot_falloff(dot(centre, light.direction.xyz), light.direction.w, light.intensity.w);
            }
        }
    }
    return light.intensity.rgb * sum;
}

// How far the edge ray (o, d) needs to be followed: to the first diffuse
// surface (specular ones are passed, as volume_lines' rays do), else, where
// it leaves the scene without meeting one, to where it leaves the medium's
// bounds (beyond them it lights nothing; 0 without a medium). Sect. 4.3's
// extrusion length from occlusion. `object` and `normal`: the diffuse
// surface met (~0u where none).
float edge_length(vec3 o, vec3 d, out uint object, out vec3 normal) {
    object = ~0u;
    normal = vec3(0.0);
    vec3 x = o;
    float travelled = 0.0;
    for (int i = 0; i < 16; ++i) {
        Hit h;
        if (!trace_closest(x, d, 0.0, 1e30, h)) break;
        vec3 hx = hit_position(h, x, d);
        travelled += h.t;
        if (material_kind(hit_material(h)) == MATERIAL_DIFFUSE) {
            object = hit_object(h);
            normal = hit_normal(h);
            return travelled;
        }
        float eps = 1e-4 * max(1.0, bvh_max_abs(hx));
        x = hx + d * eps;
        travelled += eps;
    }
    if (!medium_present()) return 0.0;
    float t0 = 0.0, t1 = 1e30;
    return clip_to_medium(o, d, t0, t1) ? t1 : 0.0;
}

// Builds the beam from the points p_k (where the light leaves the
// specular surface) along the unit directions d_k. Beam space (Sect. 4.3):
// the base plane is taken normal to the mean direction (so every edge has
// dot(d_k, n) > 0 even where the exit points' triangle is tilted or
// flipped, as after two refractions) through the exit point furthest along
// it; the other base vertices are moved forward along their edges onto
// that plane. y_max: the highest point where an edge ray meets a diffuse
// surface (the extrusion length from occlusion, Sect. 4.3), or, for a beam
// that bounces on (Sect. 6), the highest of its edges' hits on the next
// specular surface (stop[k] >= 0: the distance along d_k from p_k).
// The receiver (Sect. 5.3): the heights where the edges meet their first
// diffuse surface, kept as the beam's caustic triangle where all three
// meet one object with normals within the split angle, below the
// extrusion's end.
// Set where make_beam found no beam space (the triangle is too coarse for
// the beam's spread).
bool beam_too_wide = false;
// Set where the edges of a beam that does not bounce on meet different
// diffuse surfaces, or only some meet one: its footprint crosses a
// receiver's edge or crease (criterion (a) at the receiver's end).
bool receiver_split = false;

bool make_beam(vec3 p[3], vec3 d[3], float stop[3], vec3 flux, vec3 incident, float measure, uint kind,
               out Beam beam) {
    vec3 n = normalize(d[0] + d[1] + d[2]);
    float h = max(dot(p[0], n), max(dot(p[1], n), dot(p[2], n)));
    vec3 v[3], e[3];
    uint hit_obj[3] = uint[3](~0u, ~0u, ~0u);
    vec3 hit_n[3];
    float y_hit[3] = float[3](-1.0, -1.0, -1.0);
    float y_max = 0.0;
    float y_stop = 1e30; // the lowest edge hit on the next specular surface
    for (int k = 0; k < 3; ++k) {
        float c = dot(d[k], n);
        if (c < 0.2) { // edges more than ~78 degrees apart: no beam space
            beam_too_wide = true;
            return false;
        }
        e[k] = d[k] / c;
        v[k] = p[k] + (h - dot(p[k], n)) * e[k];
        if (stop[k] >= 0.0) {
            float y_hit = dot(p[k] + stop[k] * d[k], n) - h;
            y_max = max(y_max, y_hit);
            y_stop = min(y_stop, y_hit);
            continue;
        }
        float eps = 1e-4 * max(1.0, bvh_max_abs(p[k]));
        float s = edge_length(p[k] + d[k] * eps, d[k], hit_obj[k], hit_n[k]);
        if (s > 0.0) y_max = max(y_max, dot(p[k] + (s + eps) * d[k], n) - h);
        y_hit[k] = hit_obj[k] != ~0u ? dot(p[k] + (s + eps) * d[k], n) - h : -1.0;
    }
    vec3 b1 = v[1] - v[0], b2 = v[2] - v[0];
    vec3 f1 = e[1] - e[0], f2 = e[2] - e[0];
    vec3 area = 0.5 * vec3(dot(n, cross(b1, b2)), dot(n, cross(b1, f2) + cross(f1, b2)), dot(n, cross(f1, f2)));
    if (!(abs(area.x) > 0.0) || !(y_max > 0.0)) return false;
    // The energy cut-off (Sect. 4.3): a divergent beam (|A(y)| growing
    // from its base for all y > 0) is extruded only while its flux density
    // Phi / |A(y)| stays above `cutoff` times that at its base, i.e. up to
    // the height where |A(y)| = |A(0)| / cutoff: its far part, whose light
    // is spread too thin to matter. Converging beams (a lens's, which
    // spread again past their focus into the visible cone) are kept whole.
    float cutoff = pc.split2.z;
    bool divergent = area.x * area.y >= 0.0 && area.x * area.z >= 0.0;
    if (cutoff > 0.0 && divergent) {
        float target = area.x / cutoff; // same sign as A(0): A grows past it before any sign change
        float c0 = area.x - target, c1 = area.y, c2 = area.z;
        float y_cut = 1e30;
        if (abs(c2) > 1e-12 * max(abs(c1), abs(c0))) {
            float disc = c1 * c1 - 4.0 * c2 * c0;
            if (disc >= 0.0) {
                float r = sqrt(disc);
                float ya = (-c1 - r) / (2.0 * c2), yb = (-c1 + r) / (2.0 * c2);
                if (ya > 0.0) y_cut = ya;
                if (yb > 0.0) y_cut = min(y_cut, yb);
            }
        } else if (c1 != 0.0 && -c0 / c1 > 0.0) {
            y_cut = -c0 / c1;
        }
        y_max = min(y_max, y_cut);
    }
    // One receiver for the three edges: the caustic triangle.
    uint met = uint(hit_obj[0] != ~0u) + uint(hit_obj[1] != ~0u) + uint(hit_obj[2] != ~0u);
    bool one = met == 3u && hit_obj[1] == hit_obj[0] && hit_obj[2] == hit_obj[0];
    for (int k = 0; k < 3 && one; ++k) {
        if (abs(dot(hit_n[k], hit_n[(k + 1) % 3])) < pc.split.y || y_hit[k] > y_max) one = false;
    }
    if (met > 0u && !one) receiver_split = true;
    beam.receiver = vec4(y_hit[0], y_hit[1], y_hit[2], uintBitsToFloat(one ? hit_obj[0] : ~0u));
    beam.v0 = vec4(v[0], y_max * 1.001);
    beam.v1 = vec4(v[1], uintBitsToFloat(pc.grid.x));
    beam.v2 = vec4(v[2], uintBitsToFloat(kind));
    beam.e0 = vec4(e[0], 0.0); // w: bounce and parent, set by the caller
    beam.e1 = vec4(e[1], 0.0);
    beam.e2 = vec4(e[2], y_stop < 1e30 ? max(y_stop, 1e-9) : 0.0);
    beam.n = vec4(n, h);
    beam.area = vec4(area, measure);
    beam.flux = vec4(flux, 0.0);
    beam.incident = vec4(incident, 0.0);
    return true;
}

// Criterion (b): the smallest |A(y)| over [0, y_max] against |A(0)|.
float focus_ratio(Beam b) {
    float y_max = b.v0.w;
    float a0 = abs(beam_area(b, 0.0));
    float m = min(a0, abs(beam_area(b, y_max)));
    if (b.area.z != 0.0) {
        float ys = -b.area.y / (2.0 * b.area.z);
        if (ys > 0.0 && ys < y_max) m = min(m, abs(beam_area(b, ys)));
    }
    // A(y) changing sign inside means the beam passes a focus.
    if (beam_area(b, 0.0) * beam_area(b, y_max) < 0.0) m = 0.0;
    return m / a0;
}

// Criterion (c): the angular size of the beam's cross-section at the point
// of its central ray closest to the camera.
float camera_size(Beam b) {
    vec3 c = (b.v0.xyz + b.v1.xyz + b.v2.xyz) / 3.0;
    vec3 e = (b.e0.xyz + b.e1.xyz + b.e2.xyz) / 3.0; // dot(e, n) = 1
    float y = clamp(dot(frame.eye.xyz - c, e) / dot(e, e), 0.0, b.v0.w);
    vec3 x = c + y * e;
    return sqrt(abs(beam_area(b, y))) / max(length(x - frame.eye.xyz), 1e-6);
}

// Appends beam b; its index, or ~0u where the buffer is full. The flux
// statistic counts the first specular event's beams only (what the light
// sends into the kept triangles; later bounces re-split that flux).
uint emit(Beam b) {
    uint index = atomicAdd(counters[BEAMS_COUNTER_BEAMS], 1u);
    if (index >= pc.config.x) {
        STAT_ADD(BEAMS_STAT_BEAM_OVERFLOW, 1u);
        return ~0u;
    }
    beams[index] = b;
    STAT_ADD(BEAMS_STAT_BEAMS + pc.grid.x, 1u);
    if (floatBitsToUint(b.e0.w) == 1u)
        atomicAdd(measures[BEAMS_STAT_FLUX_OUT - BEAMS_STAT_KEPT_MEASURE], luminance(b.flux.rgb));
    return index;
}

// --- Multiple bounces (Sect. 6) ------------------------------------------
//
// A triangle's beams form a small tree: the first specular event's
// (reflected, refracted) beams, and, while `bounces` allows, the beams
// that one spawns where all three of its edge rays meet one further
// specular object (the beam ends there and its flux, times the medium's
// transmittance along it, is split again by that surface: a mirror's
// reflectance, or Fresnel between a reflected and a refracted beam traced
// through the object with Beer-Lambert absorption). Where only some edge
// rays meet it, the beam is partially intersected: the paper splits it,
// and so does the oracle here (criterion (a) for the beam tree); at the
// last level it is kept as a single beam whose edges pass the object (the
// one-bounce approximation) and spawns nothing.

// One beam still to be built: where its light leaves a specular surface
// (p, d), its flux, its generation and its parent's slot in `pending`.
struct Pending {
    vec3 p[3];
    vec3 d[3];
    vec3 flux;
    vec3 incident; // flux reaching the surface it leaves (before Fresnel and absorption)
    uint kind;
    uint bounce; // 1: the first specular event
    int parent;  // slot in `pending`, -1 for the first event
    uint source; // the object the light leaves (its own hits are not a bounce)
};
const int MAX_PENDING = 2 + 4 + 8; // bounces <= 3
Pending pending[MAX_PENDING];
int pending_count = 0;

void push_pending(vec3 p[3], vec3 d[3], vec3 flux, vec3 incident, uint kind, uint bounce, int parent, uint source) {
    if (pending_count >= MAX_PENDING) return;
    Pending e;
    e.p = p;
    e.d = d;
    e.flux = flux;
    e.incident = incident;
    e.kind = kind;
    e.bounce = bounce;
    e.parent = parent;
    e.source = source;
    pending[pending_count++] = e;
}

// The specular event at p[k] (light arriving along d[k], normals n[k]
// facing it, material m): the reflected and the refracted beams pushed as
// pending, Fresnel splitting each vertex's flux (the factors averaged
// over the three vertices, one flux per beam as in the paper). The first
// event may refract through the light view's back faces (q: its texels,
// d_n: Wyman's d_N); later ones are traced through the BVH.
void specular_event(vec3 p[3], vec3 d[3], vec3 n[3], uint m, vec3 flux, vec3 incident, uint bounce, int parent,
                    uint object, bool image_space, ivec2 q[3], float d_n[3]) {
    vec3 refl[3];
    for (int k = 0; k < 3; ++k) refl[k] = reflect(d[k], n[k]);
    if (material_kind(m) == MATERIAL_MIRROR) {
        push_pending(p, refl, flux * materials[m].color.rgb, incident, BEAM_REFLECTED, bounce, parent, object);
        return;
    }
    float ior = materials[m].absorption_ior.w;
    vec3 absorption = materials[m].absorption_ior.rgb;
    float f_refl = 0.0;
    vec3 f_refr = vec3(0.0);
    vec3 exit_p[3], exit_d[3];
    bool refracts = true;
    for (int k = 0; k < 3; ++k) {
        float f0 = fresnel_dielectric(-dot(d[k], n[k]), 1.0 / ior);
        f_refl += f0 / 3.0;
        if (!image_space) {
            vec3 factor;
            if (!traced_refraction(d[k], p[k], n[k], ior, absorption, exit_p[k], exit_d[k], factor)) {
                refracts = false;
                continue;
            }
            f_refr += (1.0 - f0) * factor / 3.0;
            continue;
        }
        vec4 bp = imageLoad(back_position, q[k]);
        if (bp.w < 0.0) {
            // No back face: an open sheet (d_N = 0) refracts once and its
            // beam starts at the interface; a closed refractor's texel
            // without one is its silhouette.
            vec3 t1;
            if (d_n[k] > 0.0 || !refract_dir(d[k], n[k], 1.0 / ior, t1)) { refracts = false; continue; }
            exit_p[k] = p[k];
            exit_d[k] = t1;
            f_refr += vec3(1.0 - f0) / 3.0;
        } else {
            TwoSidedExit x;
            if (!two_sided_refraction(d[k], p[k], n[k], ior, length(bp.xyz - p[k]), d_n[k],
                                      pc.config.y, pc.config.z != 0u, x)) { refracts = false; continue; }
            exit_p[k] = x.p2;
            exit_d[k] = x.dir;
            f_refr += (1.0 - f0) * x.transmit * exp(-absorption * x.dist) / 3.0;
        }
    }
    if (f_refl > 0.0) push_pending(p, refl, flux * f_refl, incident, BEAM_REFLECTED, bounce, parent, object);
    if (refracts) push_pending(exit_p, exit_d, flux * f_refr, incident, BEAM_REFRACTED, bounce, parent, object);
}

const uint EDGES_FREE = 0u;    // no edge ray meets a specular surface first
const uint EDGES_BOUNCE = 1u;  // all three meet one specular object first
const uint EDGES_PARTIAL = 2u; // some do

// Where the edge rays of pending beam e first meet a surface other than
// the one they leave: the hits (distance along d_k, point, normal facing
// the ray) and the classification above.
uint edge_hits(Pending e, out float dist[3], out vec3 hp[3], out vec3 hn[3], out uint material, out uint object) {
    uint specular = 0u;
    material = 0u;
    object = ~0u;
    bool one_object = true;
    for (int k = 0; k < 3; ++k) {
        dist[k] = -1.0;
        hp[k] = e.p[k];
        hn[k] = vec3(0.0);
        vec3 x = e.p[k];
        float travelled = 0.0;
        for (int i = 0; i < 4; ++i) {
            float eps = 1e-4 * max(1.0, bvh_max_abs(x));
            Hit h;
            if (!trace_closest(x + e.d[k] * eps, e.d[k], 0.0, 1e30, h)) break;
            travelled += h.t + eps;
            x = hit_position(h, x + e.d[k] * eps, e.d[k]);
            uint obj = hit_object(h);
            if (obj == e.source) continue; // the surface the beam leaves (a lens's rim)
            uint mat = hit_material(h);
            if (material_kind(mat) == MATERIAL_DIFFUSE) break;
            if (specular > 0u && obj != object) one_object = false;
            specular++;
            object = obj;
            material = mat;
            dist[k] = travelled;
            hp[k] = x;
            vec3 nn = hit_normal(h);
            hn[k] = dot(nn, e.d[k]) > 0.0 ? -nn : nn;
            break;
        }
    }
    if (specular == 0u) return EDGES_FREE;
    return specular == 3u && one_object ? EDGES_BOUNCE : EDGES_PARTIAL;
}

// The object whose surface the light view sees at p (hit from the light
// along d), ~0u if the short ray misses it.
uint object_at(vec3 p, vec3 d) {
    float delta = 1e-3 * max(1.0, bvh_max_abs(p));
    Hit h;
    return trace_closest(p - d * delta, d, 0.0, 2.0 * delta, h) ? hit_object(h) : ~0u;
}

void main() {
    uint level = pc.grid.x;
    uint count = min(counters[BEAMS_COUNTER_TRIS + level], pc.grid.w);
    uint index = gl_GlobalInvocationID.x;
    if (index >= count) return;
    STAT_ADD(BEAMS_STAT_TRIS + level, 1u);

    // The triangle's grid vertices.
    uvec2 g[3];
    if (level == 0u) {
        uint cell = index / 2u;
        uint s = 1u << BEAMS_MAX_LEVELS;
        uvec2 c = uvec2(cell % pc.grid.z, cell / pc.grid.z) * s;
        g[0] = c;
        if (index % 2u == 0u) {
            g[1] = c + uvec2(s, 0u);
            g[2] = c + uvec2(s, s);
        } else {
            g[1] = c + uvec2(s, s);
            g[2] = c + uvec2(0u, s);
        }
    } else {
        uvec4 t = (level % 2u == 1u) ? tris_b[index] : tris_a[index];
        for (int k = 0; k < 3; ++k) g[k] = unpack_vertex(t[k]);
    }

    // Vertices on the light-space G-buffer.
    ivec2 q[3];
    vec3 p[3], nrm[3], dir[3];
    float depth[3], d_n[3];
    uint mat[3];
    int valid = 0;
    bool same_material = true;
    for (int k = 0; k < 3; ++k) {
        q[k] = vertex_texel(g[k]);
        vec4 fp = imageLoad(front_position, q[k]);
        vec4 fnm = imageLoad(front_normal, q[k]);
        mat[k] = uint(fnm.w + 0.5);
        dir[k] = texel_direction(q[k]);
        p[k] = fp.xyz;
        d_n[k] = fp.w;
        nrm[k] = normalize(fnm.xyz);
        if (dot(nrm[k], dir[k]) > 0.0) nrm[k] = -nrm[k];
        depth[k] = planar_view() ? dot(fp.xyz - pc.origin.xyz, pc.forward.xyz) : length(fp.xyz - pc.origin.xyz);
        if (fp.w >= 0.0 && material_kind(mat[k]) != MATERIAL_DIFFUSE) valid++;
        if (k > 0 && mat[k] != mat[0]) same_material = false;
    }
    if (valid == 0) return; // outside the specular surfaces

    // (a) Discontinuities. A depth difference splits; it is a silhouette
    // (a jump between two surfaces, dropped at the last level) only where
    // the vertices also leave each other's tangent planes (an edge more
    // than 30 degrees off them): a surface seen at a grazing angle, as a
    // sphere near its rim, has steep but continuous depth and is kept.
    bool silhouette = valid < 3 || !same_material;
    bool split = silhouette;
    if (!silhouette) {
        float dmin = min(depth[0], min(depth[1], depth[2]));
        float dmax = max(depth[0], max(depth[1], depth[2]));
        if (dmax - dmin > pc.split.x * max(dmin, 1e-6)) {
            split = true;
            float off_plane = 0.0;
            for (int i = 0; i < 3; ++i) {
                for (int j = 0; j < 3; ++j) {
                    vec3 chord = p[j] - p[i];
                    float len = length(chord);
                    if (i != j && len > 0.0) off_plane = max(off_plane, abs(dot(chord, nrm[i])) / len);
                }
            }
            silhouette = off_plane > 0.5;
        }
        float c = min(dot(nrm[0], nrm[1]), min(dot(nrm[1], nrm[2]), dot(nrm[2], nrm[0])));
        split = split || c < pc.split.y;
    }

    // The beams of a triangle on one specular surface: the first
    // specular event, then the bounces (Sect. 6).
    Beam beam[MAX_PENDING];
    bool has[MAX_PENDING];
    for (int i = 0; i < MAX_PENDING; ++i) has[i] = false;
    float measure = 0.0;
    vec3 phi_in = vec3(0.0);
    uint bounces = floatBitsToUint(pc.split2.w);
    if (!silhouette) {
        phi_in = incident_flux(q[0], q[1], q[2], measure);
        // The medium between the light and the surface (a directional
        // light's rays come from beyond the medium's bounds).
        vec3 tau = vec3(0.0);
        for (int k = 0; k < 3; ++k) {
            vec3 src = planar_view() ? p[k] - dir[k] * light_travel(1e30, p[k]) : pc.origin.xyz;
            tau += bm_transmittance(src, p[k], pc.config.w) / 3.0;
        }
        bool image_space = floatBitsToUint(pc.split2.y) != BEAMS_REFRACTION_TRACED;
        specular_event(p, dir, nrm, mat[0], phi_in * tau, phi_in, 1u, -1, object_at(p[0], dir[0]), image_space, q,
                       d_n);
        for (int i = 0; i < MAX_PENDING; ++i) {
            if (i >= pending_count) break;
            Pending e = pending[i];
            float dist[3];
            vec3 hp[3], hn[3];
            uint hit_mat, hit_obj;
            uint edges = e.bounce < bounces ? edge_hits(e, dist, hp, hn, hit_mat, hit_obj) : EDGES_FREE;
            if (edges == EDGES_PARTIAL) split = true;
            if (edges != EDGES_BOUNCE) dist = float[3](-1.0, -1.0, -1.0);
            beam_too_wide = false;
            receiver_split = false;
            has[i] = make_beam(e.p, e.d, dist, e.flux, e.incident, measure, e.kind, beam[i]);
            if (receiver_split) split = true;
            // A bounced beam spreading too wide for one beam space (a coarse
            // triangle of a mirror's light across a lens) splits the triangle.
            if (beam_too_wide && e.bounce > 1u) split = true;
            if (!has[i]) continue;
            beam[i].e0.w = uintBitsToFloat(e.bounce);
            beam[i].e1.w = intBitsToFloat(e.parent); // a slot until emitted
            // (b) and (c) on every beam of the tree.
            if (focus_ratio(beam[i]) < pc.split.z) split = true;
            if (luminance(beam[i].flux.rgb) > pc.split.w) split = true;
            if (camera_size(beam[i]) > pc.split2.x) split = true;
            if (edges != EDGES_BOUNCE) continue;
            // The flux arriving at the next surface: the beam's, times the
            // medium's transmittance from its base along each edge.
            vec3 arriving = vec3(0.0);
            vec3 base[3] = vec3[3](beam[i].v0.xyz, beam[i].v1.xyz, beam[i].v2.xyz);
            for (int k = 0; k < 3; ++k) arriving += e.flux * bm_transmittance(base[k], hp[k], pc.config.w) / 3.0;
            specular_event(hp, e.d, hn, hit_mat, arriving, arriving, e.bounce + 1u, i, hit_obj, false, q, d_n);
        }
    }

    if (split && level < pc.grid.y) {
        uint base = atomicAdd(counters[BEAMS_COUNTER_TRIS + level + 1u], 4u);
        if (base + 4u <= pc.grid.w) {
            uvec2 m01 = (g[0] + g[1]) / 2u, m12 = (g[1] + g[2]) / 2u, m20 = (g[2] + g[0]) / 2u;
            uvec4 c0 = uvec4(pack_vertex(g[0]), pack_vertex(m01), pack_vertex(m20), 0u);
            uvec4 c1 = uvec4(pack_vertex(m01), pack_vertex(g[1]), pack_vertex(m12), 0u);
            uvec4 c2 = uvec4(pack_vertex(m20), pack_vertex(m12), pack_vertex(g[2]), 0u);
            uvec4 c3 = uvec4(pack_vertex(m01), pack_vertex(m12), pack_vertex(m20), 0u);
            // Level l writes the list level l + 1 reads: B from even levels, A from odd.
            if (level % 2u == 0u) {
                tris_b[base] = c0; tris_b[base + 1u] = c1; tris_b[base + 2u] = c2; tris_b[base + 3u] = c3;
            } else {
                tris_a[base] = c0; tris_a[base + 1u] = c1; tris_a[base + 2u] = c2; tris_a[base + 3u] = c3;
            }
            return;
        }
        STAT_ADD(BEAMS_STAT_TRI_OVERFLOW, 1u);
    }

    if (silhouette) {
        // Dropped: its measure from the texel directions of its vertices.
        float dropped;
        incident_flux(q[0], q[1], q[2], dropped);
        atomicAdd(measures[BEAMS_STAT_DROPPED_MEASURE - BEAMS_STAT_KEPT_MEASURE], dropped);
        return;
    }
    atomicAdd(measures[0], measure);
    atomicAdd(measures[BEAMS_STAT_FLUX_IN - BEAMS_STAT_KEPT_MEASURE], luminance(phi_in));
    // Parents come before their children in `pending`, so a child's slot
    // becomes its parent's buffer index (~0u: none, or not emitted).
    uint emitted[MAX_PENDING];
    for (int i = 0; i < MAX_PENDING; ++i) {
        emitted[i] = ~0u;
        if (i >= pending_count || !has[i]) continue;
        int parent = floatBitsToInt(beam[i].e1.w);
        beam[i].e1.w = uintBitsToFloat(parent >= 0 ? emitted[parent] : ~0u);
        emitted[i] = emit(beam[i]);
    }
}
