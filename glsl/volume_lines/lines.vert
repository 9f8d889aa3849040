#version 460
// volume_lines, Sect. 5.1: one point per volume caustic buffer texel; the
// geometry shader (lines.geom) reads its segment and emits the line.
layout(location = 0) flat out uint v_segment;

void main() {
    v_segment = uint(gl_VertexIndex);
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
