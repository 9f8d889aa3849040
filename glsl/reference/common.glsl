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

#endif
