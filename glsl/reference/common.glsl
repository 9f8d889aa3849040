// Shared by the reference light tracer's shaders: descriptor set 1 (the
// accumulation buffers), push constants and the camera measurement.
#ifndef REFERENCE_COMMON_GLSL
#define REFERENCE_COMMON_GLSL

#define SCENE_SET 0
#include "scene.glsl"
#include "bvh.glsl"
#include "random.glsl"
#include "optics.glsl"
#include "lights.glsl"
#include "medium.glsl"

// Photon contributions, COMPONENT_COUNT images of width*height rgb floats,
// summed with float atomics; divided by the photon count when resolved.
layout(set = 1, binding = 0, std430) buffer PhotonAccum { float photon_accum[]; };
// Camera-side specular chains (eye -> S+ -> D, lit directly), summed per pass.
layout(set = 1, binding = 1, std430) buffer CameraAccum { float camera_accum[]; };

layout(push_constant) uniform Push {
    uint seed;            // a different value every dispatch
    uint max_depth;       // longest path (specular bounces + scattering events)
    uint diffuse_bounces; // photons continue this many times past diffuse surfaces
    uint component;       // resolve only: which image (COMPONENT_COUNT = all)
    float photon_count;   // resolve only: photons emitted so far
    float camera_passes;  // resolve only: camera-chain passes so far
    float exposure;       // unused here; keeps one push layout for every shader
    float pad;
} pc;

const float RAY_EPS = 1e-4;

uint image_width() { return uint(frame.viewport.x); }
uint image_height() { return uint(frame.viewport.y); }

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
    bool inside;             // inside a dielectric (no medium there)
    vec3 inside_absorption;  // that dielectric's absorption, 1/m
};

// Reflects at a mirror or reflects/refracts at a dielectric (exact Fresnel;
// reflection chosen with probability F keeps the weight unchanged; total
// internal reflection always reflects). `front`: the ray arrived on the side
// the geometric normal `ng` points to. Smooth shading normals can bend a new
// direction to the wrong side of the true surface at grazing angles; then the
// geometric normal is used instead, so the inside/outside state stays right.
void specular_bounce(inout SpecularState s, vec3 x, vec3 ng, vec3 ns, bool front, Material m, float u) {
    vec3 ng_in = front ? ng : -ng;                   // facing the arriving ray
    vec3 ns_in = dot(ns, ng_in) > 0.0 ? ns : -ns;
    uint kind = floatBitsToUint(m.color.w);
    if (kind == MATERIAL_MIRROR) {
        s.weight *= m.color.rgb;
        vec3 r = reflect(s.dir, ns_in);
        s.dir = dot(r, ng_in) > 0.0 ? r : reflect(s.dir, ng_in);
        s.origin = offset_origin(x, ng_in);
        return;
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
        s.dir = refracted;
        s.origin = offset_origin(x, -ng_in);
        s.inside = front;
        s.inside_absorption = m.absorption_ior.rgb;
    } else {
        vec3 r = reflect(s.dir, n);
        s.dir = dot(r, ng_in) > 0.0 ? r : reflect(s.dir, ng_in);
        s.origin = offset_origin(x, ng_in);
    }
}

#endif
