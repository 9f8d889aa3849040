#version 460
// volume_lines, Sect. 5.1: "we render point primitives to achieve a read
// back of p1 and p2 ... into the geometry shader stage. This way, a line
// primitive can be constructed": the segment p1 -> p2 projected by the
// camera; texels with no segment emit nothing.
#include "scene.glsl"
#include "volume_lines_bindings.glsl"
#include "segment.glsl"

layout(points) in;
layout(line_strip, max_vertices = 2) out;

layout(set = 1, binding = VOLUME_LINES_BINDING_SEGMENTS, std430) readonly buffer SegmentBlock { Segment segments[]; };

layout(location = 0) flat in uint v_segment[];
layout(location = 0) flat out uint g_segment;

void main() {
    uint i = v_segment[0];
    Segment s = segments[i];
    if (s.p1.w <= 0.0) return;
    g_segment = i;
    gl_Position = frame.view_proj * vec4(s.p1.xyz, 1.0);
    EmitVertex();
    g_segment = i;
    gl_Position = frame.view_proj * vec4(s.p2.xyz, 1.0);
    EmitVertex();
    EndPrimitive();
}
