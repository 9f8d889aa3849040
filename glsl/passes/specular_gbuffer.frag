#version 460
// Specular G-buffer, fragment stage. Front pass: the nearest specular
// surface (dielectric faces whose winding normal faces the viewer; mirrors
// and, in the camera's view, open sheets from either side). Back pass: the
// farthest dielectric face turned away from the viewer (reversed depth,
// see the vertex stage; not an open sheet's in the camera's view). Stores world
// position with the interpolated d_N in w (clear value -1: not covered) and
// the smooth outward normal with the material index in w.
// Diffuse geometry occludes in the front pass: it writes its depth and
// marks the texel not covered (w = -1), so glass behind an opaque object
// is not refracted over it (camera) and emits no photons from its shadow
// (light view). The back pass ignores diffuse geometry: it wants the
// refractor's own farthest back face, and an opaque object inside or
// behind the refractor must not replace it (back texels are read at the
// projection of p2, inside the refractor, where its own back face is the
// one wanted even where something opaque hides it from the viewer).
#include "scene.glsl"

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 origin;
    vec4 forward;
} pc;

layout(location = 0) in vec3 v_position;
layout(location = 1) in vec4 v_normal;
layout(location = 2) flat in vec3 v_geometric;
layout(location = 3) flat in uint v_material;

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    uint kind = material_kind(v_material);
    bool back_pass = floatBitsToUint(pc.forward.w) == SPECULAR_GBUFFER_BACK;
    if (kind == MATERIAL_DIFFUSE) {
        if (back_pass) discard;
        out_position = vec4(0.0, 0.0, 0.0, -1.0); // NOT_COVERED
        out_normal = vec4(0.0);
        return;
    }
    uint view = floatBitsToUint(pc.origin.w);
    vec3 ray = view == SHADOW_PLANAR ? pc.forward.xyz
             : v_position - (view == SPECULAR_VIEW_CAMERA ? frame.eye.xyz : pc.origin.xyz);
    bool facing_viewer = dot(v_geometric, ray) < 0.0;
    // An open sheet (a water surface: d_N = 0 at its corners, the
    // thickness ray met nothing of the object) has one interface, and the
    // camera may be on either side of it: seen from below, its face turned
    // away is the camera's nearest specular surface (camera_refraction.comp
    // refracts it from the inside), never a second interface.
    bool camera_sheet = view == SPECULAR_VIEW_CAMERA && v_normal.w <= 0.0;
    if (back_pass) {
        if (kind != MATERIAL_DIELECTRIC || facing_viewer || camera_sheet) discard;
    } else if (kind == MATERIAL_DIELECTRIC && !facing_viewer && !camera_sheet) {
        discard;
    }
    out_position = vec4(v_position, back_pass ? 0.0 : max(v_normal.w, 0.0));
    out_normal = vec4(normalize(v_normal.xyz), float(v_material));
}
