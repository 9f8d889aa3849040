#version 460
// Caustic maps, step 2 (fragment): a discrete Gaussian over the S x S
// sprite texels, sigma = S / 6, normalised so that its weights sum to 1:
// each photon adds exactly its flux to the map (additive blending). The
// map stores flux per texel (W); readers divide by the texel's receiver
// area (glsl/caustic_map/apply.comp) to get irradiance.
layout(push_constant) uniform Push {
    uint light;
    uint view;
    uint size;
    uint splat_size;
} pc;

layout(location = 0) flat in vec3 v_flux;
layout(location = 1) flat in vec2 v_centre;
layout(location = 0) out vec4 out_flux;

void main() {
    int half_size = int(pc.splat_size) / 2;
    float sigma = max(float(pc.splat_size) / 6.0, 0.3);
    float k = 1.0 / (2.0 * sigma * sigma);
    float norm1 = 0.0;
    for (int i = -half_size; i <= half_size; ++i) norm1 += exp(-float(i * i) * k);
    vec2 o = round(gl_FragCoord.xy - v_centre);
    float w = exp(-dot(o, o) * k) / (norm1 * norm1);
    out_flux = vec4(v_flux * w, w);
}
