#version 460
// Camera G-buffer, fragment stage: world position (w = 1: covered) and the
// smooth normal turned toward the camera (two-sided surfaces) with the
// material index in w, and the albedo (alpha: front face seen; glsl/common/scene.glsl
// `material_albedo_grad`: colour times texture, mip level from the UV's
// screen-space derivatives). With `opaque_only` the specular surfaces are left
// out (image_space refracts and reflects them in a later pass).
#include "scene.glsl"

layout(push_constant) uniform Push {
    uint opaque_only;
} pc;

layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) flat in uint v_material;
layout(location = 3) in vec2 v_uv;

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out vec4 out_albedo;

void main() {
    // Derivatives before any branch (they need the whole quad).
    vec2 duv_dx = dFdx(v_uv);
    vec2 duv_dy = dFdy(v_uv);
    if (pc.opaque_only != 0u && material_kind(v_material) != MATERIAL_DIFFUSE) discard;
    if (material_cut_out(v_material, v_uv)) discard;
    vec3 n = normalize(v_normal);
    // alpha of the albedo: 1 where the camera sees the front face (the side
    // an area light emits to; lighting.comp adds the emission there).
    bool front = dot(n, frame.eye.xyz - v_position) >= 0.0;
    if (!front) n = -n;
    out_position = vec4(v_position, 1.0);
    out_normal = vec4(n, float(v_material));
    out_albedo = vec4(material_albedo_grad(v_material, v_uv, duv_dx, duv_dy), front ? 1.0 : 0.0);
}
