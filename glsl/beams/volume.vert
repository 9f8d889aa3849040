#version 460
// beams, Sect. 4.3: one point per beam (drawn indirect with the count the
// refinement wrote); the geometry shader (volume.geom) extrudes it.
layout(location = 0) flat out uint v_beam;

void main() {
    v_beam = uint(gl_VertexIndex);
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
