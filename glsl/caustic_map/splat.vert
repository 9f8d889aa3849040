#version 460
// Caustic maps, step 2: one point sprite per photon (vertex pulling from the
// photon buffer) into one layer (view) of the light's caustic map, which
// uses the same views as the light's shadow map (cube faces for a point
// light, one perspective view for a spot, one orthographic view for a
// directional light) at the caustic-map resolution.
//
// The sprite keeps the photon's sub-texel position (snapping it to texel
// centres aliases against the photon grid: measured up to 9% ripple at
// 512^2/512^2). Its Gaussian is evaluated at the S x S texel centres
// nearest the photon, which a sprite of S + 1 texels always covers with
// half a texel to spare, and normalised over exactly those centres in the
// fragment shader, so each photon adds exactly its flux (flux
// conservation). Photons that did not land, that belong to another view,
// or that land outside the map are culled.
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
layout(location = 2) flat out float v_depth; // where it landed, as shadow maps measure depth

void main() {
    Photon p = photons[gl_VertexIndex];
    gl_PointSize = float(pc.splat_size + 1u);
    v_flux = p.flux.rgb;
    v_centre = vec2(0.0);
    v_depth = 0.0;
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0); // outside the clip volume: culled
    if (p.position.w == 0.0) return;
    ShadowLight s = shadow_lights[pc.light];
    if (shadow_view(s, p.position.xyz) != pc.view) return;
    vec4 clip = s.view_proj[pc.view] * vec4(p.position.xyz, 1.0);
    if (clip.w <= 0.0) return;
    vec2 ndc = clip.xy / clip.w;
    vec2 pix = (ndc * 0.5 + 0.5) * float(pc.size);
    if (any(lessThan(pix, vec2(0.0))) || any(greaterThanEqual(pix, vec2(float(pc.size))))) return;
    v_centre = pix;
    v_depth = shadow_receiver_depth(s, p.position.xyz);
    gl_Position = vec4(ndc, 0.5, 1.0);
}
