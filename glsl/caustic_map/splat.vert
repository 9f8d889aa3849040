#version 460
// Caustic maps, step 2: one point sprite per photon (vertex pulling from the
// photon buffer) into one layer (view) of the light's caustic map, which
// uses the same views as the light's shadow map (cube faces for a point
// light, one perspective view for a spot, one orthographic view for a
// directional light) at the caustic-map resolution.
//
// The sprite is centred on the centre of the texel the photon lands in
// (sub-texel position dropped, at most half a texel): with an odd size S
// the sprite then covers exactly S x S texel centres, so the fragment
// shader's discrete Gaussian weights sum to exactly 1 (flux conservation).
// Photons that did not land, or that belong to another view, are culled.
#include "scene.glsl"
#include "photon.glsl"

#define SHADOW_SET 1
#define SHADOW_BINDING_LIGHTS CAUSTIC_BINDING_VIEWS
#define SHADOW_NO_MAP
#include "shadow.glsl"

layout(set = 1, binding = CAUSTIC_BINDING_PHOTONS, std430) readonly buffer PhotonBlock { Photon photons[]; };

layout(push_constant) uniform Push {
    uint light;      // index into shadow_lights (the caustic views)
    uint view;       // which of the light's views this draw fills
    uint size;       // caustic map texels per side
    uint splat_size; // sprite width in texels (odd)
} pc;

layout(location = 0) flat out vec3 v_flux;
layout(location = 1) flat out vec2 v_centre;

void main() {
    Photon p = photons[gl_VertexIndex];
    gl_PointSize = float(pc.splat_size);
    v_flux = p.flux.rgb;
    v_centre = vec2(0.0);
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0); // outside the clip volume: culled
    if (p.position.w == 0.0) return;
    ShadowLight s = shadow_lights[pc.light];
    if (shadow_view(s, p.position.xyz) != pc.view) return;
    vec4 clip = s.view_proj[pc.view] * vec4(p.position.xyz, 1.0);
    if (clip.w <= 0.0) return;
    vec2 ndc = clip.xy / clip.w;
    vec2 texel = floor((ndc * 0.5 + 0.5) * float(pc.size));
    if (any(lessThan(texel, vec2(0.0))) || any(greaterThanEqual(texel, vec2(float(pc.size))))) return;
    v_centre = texel + 0.5;
    gl_Position = vec4(v_centre / float(pc.size) * 2.0 - 1.0, 0.5, 1.0);
}
