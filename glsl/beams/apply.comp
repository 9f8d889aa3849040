#version 460
// beams, Sect. 5.3 and Fig. 8 (D): the surface caustics (caustic.frag's
// surface target: the flux the beams deposited on the receiver each pixel
// sees) become irradiance E = flux / A, A the world area of the pixel's
// footprint on the receiver (its plane from the camera G-buffer's position
// and normal, footprint.glsl): the mean irradiance over the footprint.
// Then radiance L = albedo / pi * E, attenuated toward the eye by the
// medium (tau(x, v), Hu et al. 2010 Fig. 2 C), added to the opaque frame
// before the camera refraction reads it.
#include "scene.glsl"
#include "beams_bindings.glsl"
#include "optics.glsl"
#include "random.glsl"
#include "medium.glsl"
#include "footprint.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = BEAMS_BINDING_SURFACE, rgba32f) uniform readonly image2D surface;
layout(set = 1, binding = BEAMS_BINDING_OPAQUE_POSITION, rgba32f) uniform readonly image2D opaque_position;
layout(set = 1, binding = BEAMS_BINDING_OPAQUE_NORMAL, rgba32f) uniform readonly image2D opaque_normal;
layout(set = 1, binding = BEAMS_BINDING_OPAQUE_ALBEDO, rgba32f) uniform readonly image2D opaque_albedo;
layout(set = 1, binding = BEAMS_BINDING_OPAQUE_RADIANCE, rgba32f) uniform image2D opaque_radiance;

layout(push_constant) uniform Push {
    uint medium_steps;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(opaque_radiance)))) return;
    vec4 position = imageLoad(opaque_position, p);
    if (position.w == 0.0) return;
    vec3 flux = imageLoad(surface, p).rgb;
    if (all(equal(flux, vec3(0.0)))) return;
    vec3 x = position.xyz;
    vec3 corners[4];
    if (!pixel_footprint(vec2(p), x, normalize(imageLoad(opaque_normal, p).xyz), corners)) return;
    vec3 e = flux / quad_area(corners);
    vec3 to_eye = frame.eye.xyz - x;
    float eye_dist = length(to_eye);
    vec3 tau_eye = medium_transmittance_steps(x, to_eye / eye_dist, eye_dist, pc.medium_steps);
    vec3 albedo = imageLoad(opaque_albedo, p).rgb;
    vec4 prev = imageLoad(opaque_radiance, p);
    vec3 caustic = component_weight(COMPONENT_SURFACE_CAUSTICS) * albedo / PI * e * tau_eye;
    imageStore(opaque_radiance, p, vec4(prev.rgb + caustic, prev.a));
}
