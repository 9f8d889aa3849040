#version 460
// beams: the bounding volumes' fragments (volume.glsl), any medium.
#include "volume.glsl"
