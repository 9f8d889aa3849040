// beams, Sect. 5: per fragment of a beam's bounding volume (one per pixel
// the volume covers, volume.geom), the beam's in-scattering along the
// pixel's camera ray (beam_inscatter: the exact interval(s) inside the
// beam, Gauss-Legendre along them, up to the first surface the pixel sees,
// diffuse or specular) into the volume target, blended additively; alpha
// counts fragments. (The surface caustics are the caustic triangles'
// pass, caustic.geom / caustic.frag.) The body of
// volume.frag (inhomogeneous media) and volume_homogeneous.frag (constant
// density or none: the density field compiled out, as volume_lines does).
#extension GL_EXT_shader_atomic_float : require
#include "scene.glsl"
#include "beams_bindings.glsl"
#include "optics.glsl"
#include "bvh.glsl"
#include "random.glsl"
#include "medium.glsl"
#include "beam.glsl"
#include "volume_push.glsl"

layout(set = 1, binding = BEAMS_BINDING_BEAMS, std430) readonly buffer BeamBlock { Beam beams[]; };
layout(set = 1, binding = BEAMS_BINDING_COUNTERS, std430) buffer CounterBlock {
    uint counters[BEAMS_STAT_KEPT_MEASURE];
    float measures[4];
    uint fragments;
};
#include "receiver.glsl"
layout(set = 1, binding = BEAMS_BINDING_RECEIVERS, std430) readonly buffer ReceiverBlock { Receiver receivers[]; };

layout(location = 0) flat in uint g_beam;
// rgb: in-scattered radiance (W m^-2 sr^-1), component-weighted; a: 1 per fragment.
layout(location = 0) out vec4 out_volume;

void main() {
    atomicAdd(fragments, 1u);
    Beam b = beams[g_beam];
    vec3 eye = frame.eye.xyz;
    vec2 ndc = gl_FragCoord.xy / frame.viewport.xy * 2.0 - 1.0;
    vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    vec3 w = normalize(far.xyz / far.w - eye);
    Receiver r = receivers[uint(gl_FragCoord.y) * uint(frame.viewport.x) + uint(gl_FragCoord.x)];
    vec3 volume = vec3(0.0);
    if (medium_present()) volume = beam_inscatter(b, eye, w, r.position.w, pc.quadrature, pc.medium_steps);
    out_volume = vec4(volume * component_weight(COMPONENT_VOLUME_CAUSTICS), 1.0);
}
