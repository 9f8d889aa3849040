// beams: push constants of the bounding-volume pass (geometry and fragment
// stages), mirrored by `VolumePush` in src/techniques/beams/volumes.rs.
#ifndef BEAMS_VOLUME_PUSH_GLSL
#define BEAMS_VOLUME_PUSH_GLSL
layout(push_constant) uniform Push {
    uint volume_kind;  // BEAMS_VOLUME_PRISM or BEAMS_VOLUME_TIGHT
    uint quadrature;   // Gauss-Legendre points per interval (1-4)
    uint medium_steps; // midpoint steps of inhomogeneous transmittance
    uint pad;
} pc;
#endif
