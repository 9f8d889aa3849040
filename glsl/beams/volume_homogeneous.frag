#version 460
// beams: the bounding volumes' fragments (volume.glsl) for a constant
// density or none: transmittance and sigma_s without the density field.
#define MEDIUM_HOMOGENEOUS_ONLY
#include "volume.glsl"
