// beams: what the bounding-volume fragments need of the pixel they shade,
// written per pixel by receivers.comp from the camera G-buffers (a buffer,
// since storage images cannot be read in the layout fragment reads use).
#ifndef BEAMS_RECEIVER_GLSL
#define BEAMS_RECEIVER_GLSL
struct Receiver {
    vec4 position; // xyz: the diffuse surface the pixel sees (opaque G-buffer); w: distance to the first surface of any kind
    vec4 normal;   // xyz: its normal, toward the camera; w: 1 where there is a diffuse receiver, else 0
};
#endif
