#version 460
// Composite: the screen-space caustic irradiance onto the diffuse receivers
// the camera sees (as glsl/caustic_map/apply.comp): L += albedo / π · E,
// weighted by the surface-caustics component (L S D paths).
#include "scene.glsl"
#include "water_photons_bindings.glsl"
#include "optics.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = WP_BINDING_CAUSTICS, rgba32f) uniform readonly image2D caustics;
layout(set = 1, binding = WP_BINDING_GBUFFER_POSITION, rgba32f) uniform readonly image2D g_position;
layout(set = 1, binding = WP_BINDING_GBUFFER_NORMAL, rgba32f) uniform readonly image2D g_normal;
layout(set = 1, binding = WP_BINDING_GBUFFER_ALBEDO, rgba32f) uniform readonly image2D g_albedo;
layout(set = 1, binding = WP_BINDING_RADIANCE, rgba32f) uniform image2D radiance;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    if (imageLoad(g_position, p).w == 0.0) return;
    uint material = uint(imageLoad(g_normal, p).w + 0.5);
    if (material_kind(material) != MATERIAL_DIFFUSE) return;
    vec3 e = imageLoad(caustics, p).rgb;
    vec3 albedo = imageLoad(g_albedo, p).rgb;
    vec4 prev = imageLoad(radiance, p);
    imageStore(radiance, p, vec4(prev.rgb + component_weight(COMPONENT_SURFACE_CAUSTICS) * albedo / PI * e, prev.a));
}
