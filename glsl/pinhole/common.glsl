// pinhole (Wand & Strasser 2003): what its passes share: the sample points,
// the frame's state, the hash grid of candidate points, the cube-map layout.
// Mirrors src/techniques/pinhole/ (GpuSample, the state's size, PinholePush).
#ifndef PINHOLE_COMMON_GLSL
#define PINHOLE_COMMON_GLSL

#include "scene.glsl"
#include "pinhole_bindings.glsl"

// One reflector sample point: a pinhole camera (Sect. 3.1) with the
// differential of Sect. 3.3.
struct Sample {
    vec4 position; // xyz; w: material index (uint bits)
    vec4 normal;   // xyz unit; w: cluster index (uint bits)
    vec4 tangent;  // xyz: principal direction u of grad n (unit); w: light visibility mask (uint bits)
    vec4 dn_du;    // xyz: dn/du along u
    vec4 dn_dv;    // xyz: dn/dv along v = normal x u
};

// A dense candidate point (Sect. 3.2's "high density random sample set").
struct Candidate {
    vec4 position; // xyz; w: material index (uint bits)
    vec4 normal;   // xyz unit interpolated normal
};

layout(set = 1, binding = PINHOLE_BINDING_SAMPLES, std430) buffer SampleBlock { Sample samples[]; };
layout(set = 1, binding = PINHOLE_BINDING_STATE, std430) buffer StateBlock {
    float total_area; // reflector area A (m^2)
    uint count;       // sample points kept this frame (N)
    float cell;       // hash-grid cell side (m)
    uint kept_rounds; // neighbourhood stratification: rounds run
    vec4 centres[PINHOLE_MAX_CLUSTERS];  // cluster centres (cube-map origins)
    // per (cluster, emitter slot): x = sum of coverage x texel solid angle,
    // y = the emitter's exact solid angle from the centre, or
    // PINHOLE_MAP_EXACT for a map that needs no renormalisation
    vec2 map_norm[];
} state;

const float PINHOLE_MAP_EXACT = -1.0;

layout(set = 1, binding = PINHOLE_BINDING_CDF, std430) buffer CdfBlock { float cdf[]; };
layout(set = 1, binding = PINHOLE_BINDING_CANDIDATES, std430) buffer CandidateBlock { Candidate candidates[]; };
layout(set = 1, binding = PINHOLE_BINDING_HEADS, std430) buffer HeadBlock { uint heads[]; };
layout(set = 1, binding = PINHOLE_BINDING_NEXT, std430) buffer NextBlock { uint next_candidate[]; };

layout(push_constant) uniform Push {
    uint target;        // N requested
    uint strategy;      // PINHOLE_STRATEGY_*
    uint candidates;    // M dense candidates
    uint clusters;      // K
    uint slots;         // emitter slots per cluster (light_maps.comp)
    uint cube_size;     // texels per cube face side
    uint flags;         // PINHOLE_FLAG_*
    uint hash_size;     // entries of heads[] (power of two)
    float light_radius; // r of point/spot emitters (m)
    float sun_cos;      // cos of the sun disc's angular radius
    float epsilon;      // the paper's epsilon, in units of the sample diameter squared
    uint medium_steps;  // midpoint steps of inhomogeneous transmittance
    uint first_candidate; // select: the first candidate of this dispatch
    uint pad1;
    uint pad2;
} pc;

const uint NONE = 0xffffffffu;

// The factor a cluster-k map of `slot` is scaled by (light_maps.comp): the
// emitter's exact solid angle over the map's sampled coverage; 0 when the
// emitter covers none of the map.
float map_scale(uint k, uint slot) {
    vec2 norm = state.map_norm[k * pc.slots + slot];
    if (norm.x <= 0.0) return 0.0;
    return norm.y == PINHOLE_MAP_EXACT ? 1.0 : norm.y / norm.x;
}

// Whether material m reflects specularly: a mirror, a `mixed` material's
// mirror part (which is also a diffuse receiver: the paper's self-reflecting
// cup), a dielectric with the DIELECTRICS flag.
bool reflector_material(uint m) {
    uint kind = material_kind(m);
    return kind == MATERIAL_MIRROR
        || (kind == MATERIAL_DIFFUSE && any(greaterThan(material_specular(m), vec3(0.0))))
        || ((pc.flags & PINHOLE_FLAG_DIELECTRICS) != 0u && kind == MATERIAL_DIELECTRIC);
}

ivec3 grid_cell(vec3 p) { return ivec3(floor(p / state.cell)); }

uint grid_hash(ivec3 c) {
    uint h = uint(c.x) * 73856093u ^ uint(c.y) * 19349663u ^ uint(c.z) * 83492791u;
    return h & (pc.hash_size - 1u);
}

// Cube faces: +x, -x, +y, -y, +z, -z; (s, t) in [-1, 1]^2 on the face.
vec3 cube_direction(uint face, vec2 st) {
    float s = st.x, t = st.y;
    if (face == 0u) return vec3(1.0, -t, -s);
    if (face == 1u) return vec3(-1.0, -t, s);
    if (face == 2u) return vec3(s, 1.0, t);
    if (face == 3u) return vec3(s, -1.0, -t);
    if (face == 4u) return vec3(s, -t, 1.0);
    return vec3(-s, -t, -1.0);
}

// The face a direction falls on, its major-axis component m (signed) and
// the unnormalised face coordinates (sc, tc), with (s, t) = (sc, tc) / |m|.
uint cube_face(vec3 d, out float m, out vec2 sctc) {
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        m = d.x;
        if (d.x > 0.0) { sctc = vec2(-d.z, -d.y); return 0u; }
        sctc = vec2(d.z, -d.y); return 1u;
    }
    if (a.y >= a.z) {
        m = d.y;
        if (d.y > 0.0) { sctc = vec2(d.x, d.z); return 2u; }
        sctc = vec2(d.x, -d.z); return 3u;
    }
    m = d.z;
    if (d.z > 0.0) { sctc = vec2(d.x, -d.y); return 4u; }
    sctc = vec2(-d.x, -d.y); return 5u;
}

// The face coordinates of `d` on a given face (for gradients: d's own face).
vec2 cube_face_coords(uint face, vec3 d) {
    if (face == 0u) return vec2(-d.z, -d.y) / abs(d.x);
    if (face == 1u) return vec2(d.z, -d.y) / abs(d.x);
    if (face == 2u) return vec2(d.x, d.z) / abs(d.y);
    if (face == 3u) return vec2(d.x, -d.z) / abs(d.y);
    if (face == 4u) return vec2(d.x, -d.y) / abs(d.z);
    return vec2(-d.x, -d.y) / abs(d.z);
}

// Layer of the 2D array holding face `face` of emitter slot `slot`'s map of cluster `k`.
uint cube_layer(uint k, uint slot, uint face) { return (k * pc.slots + slot) * 6u + face; }

#endif
