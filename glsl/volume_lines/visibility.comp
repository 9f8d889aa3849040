#version 460
// volume_lines, Sect. 5.3: the distance along each viewing ray to the first
// surface, diffuse (the opaque G-buffer) or specular (the camera's specular
// G-buffer front faces: refractors hide the volume caustic behind them),
// for lines.frag's culling. 1e30 where the ray meets nothing.
#include "scene.glsl"
#include "volume_lines_bindings.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = VOLUME_LINES_BINDING_OPAQUE_POSITION, rgba32f) uniform readonly image2D opaque_position;
layout(set = 1, binding = VOLUME_LINES_BINDING_SPECULAR_POSITION, rgba32f) uniform readonly image2D specular_position;
layout(set = 1, binding = VOLUME_LINES_BINDING_VISIBILITY, std430) writeonly buffer VisibilityBlock { float surface_distance[]; };

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(opaque_position);
    if (p.x >= size.x || p.y >= size.y) return;
    float t = 1e30;
    vec4 o = imageLoad(opaque_position, p);
    if (o.w > 0.0) t = length(o.xyz - frame.eye.xyz);
    vec4 sp = imageLoad(specular_position, p);
    if (sp.w >= 0.0) t = min(t, length(sp.xyz - frame.eye.xyz));
    surface_distance[p.y * size.x + p.x] = t;
}
