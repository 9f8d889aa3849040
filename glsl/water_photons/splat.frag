#version 460
// Splatting, fragment stage: the tent kernel (splat.vert), added into the
// screen-space caustic buffer: rgb caustic irradiance E (W/m^2), a the sum
// of kernel weights.
layout(location = 0) in vec2 v_local;
layout(location = 1) flat in vec3 v_irradiance;

layout(location = 0) out vec4 out_caustic;

void main() {
    vec2 k = max(1.0 - abs(v_local), vec2(0.0));
    float w = k.x * k.y;
    out_caustic = vec4(v_irradiance * w, w);
}
