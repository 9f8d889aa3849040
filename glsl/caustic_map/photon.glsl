// Photon buffer layout shared by glsl/caustic_map/*.
// Mirrors `GpuPhoton` in src/passes/caustic_map.rs (std430, 48 bytes).
#ifndef CAUSTIC_PHOTON_GLSL
#define CAUSTIC_PHOTON_GLSL

struct Photon {
    vec4 position; // xyz: landing point p3 on a diffuse receiver; w: 1 if the photon landed, else 0
    vec4 flux;     // rgb: flux in W carried to p3; w: light-space solid angle (or area) of its texel
    vec4 dir;      // xyz: unit direction of arrival at p3; w unused
};

#endif
