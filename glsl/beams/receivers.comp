#version 460
// beams, Sect. 5.3 (Fig. 3, "screen space G-buffers provide the data for
// culling the beams and rendering surface caustics"): per pixel, the
// diffuse receiver the camera sees (the opaque G-buffer, specular
// surfaces left out, so receivers seen through glass get their caustics
// too) and the distance to the first surface of any kind (diffuse, or a
// specular front face from the camera's specular G-buffer: refractors hide
// the volume caustic behind them, as in volume_lines).
#include "scene.glsl"
#include "beams_bindings.glsl"
#include "receiver.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = BEAMS_BINDING_OPAQUE_POSITION, rgba32f) uniform readonly image2D opaque_position;
layout(set = 1, binding = BEAMS_BINDING_OPAQUE_NORMAL, rgba32f) uniform readonly image2D opaque_normal;
layout(set = 1, binding = BEAMS_BINDING_SPECULAR_POSITION, rgba32f) uniform readonly image2D specular_position;
layout(set = 1, binding = BEAMS_BINDING_RECEIVERS, std430) writeonly buffer ReceiverBlock { Receiver receivers[]; };

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(opaque_position);
    if (p.x >= size.x || p.y >= size.y) return;
    vec4 o = imageLoad(opaque_position, p);
    vec4 s = imageLoad(specular_position, p);
    float t = o.w > 0.0 ? length(o.xyz - frame.eye.xyz) : 1e30;
    if (s.w >= 0.0) t = min(t, length(s.xyz - frame.eye.xyz));
    Receiver r;
    r.position = vec4(o.xyz, t);
    r.normal = vec4(o.w > 0.0 ? normalize(imageLoad(opaque_normal, p).xyz) : vec3(0.0), o.w > 0.0 ? 1.0 : 0.0);
    receivers[p.y * size.x + p.x] = r;
}
