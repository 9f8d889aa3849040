#version 460
// CCM raster, fragment stage: the water's world position and smooth normal
// per texel of the cascade (w = 1: water covers the texel; cleared to 0).
layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    out_position = vec4(v_position, 1.0);
    out_normal = vec4(normalize(v_normal), 1.0);
}
