#version 460
// Splatting, fragment stage: the box of Eq. 20 convolved with a narrow tent
// (splat.vert), added into the screen-space caustic buffer: rgb caustic
// irradiance E (W/m^2), a the sum of kernel weights.
layout(location = 0) in vec2 v_local;
layout(location = 1) flat in vec3 v_irradiance;
layout(location = 2) flat in float v_ramp;

layout(location = 0) out vec4 out_caustic;

void main() {
    // 1 on |a| <= 1 - r, 0 at |a| = 1 + r, linear between (integral 2).
    vec2 k = clamp((1.0 + v_ramp - abs(v_local)) / (2.0 * v_ramp), 0.0, 1.0);
    float w = k.x * k.y;
    out_caustic = vec4(v_irradiance * w, w);
}
