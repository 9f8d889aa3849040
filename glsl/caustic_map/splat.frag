#version 460
// Caustic maps, step 2 (fragment): a Gaussian of sigma = S / 6 texels
// around the photon's exact position p, evaluated at the S x S texel
// centres nearest p (per axis the S centres in [p - S/2, p + S/2]) and
// normalised by its sum over exactly those centres: each photon adds
// exactly its flux to the map (additive blending). The sprite is S + 1
// texels wide, so fragments outside that set are discarded. The map stores
// flux per texel (W); glsl/caustic_map/apply.comp divides by the texel's
// receiver area to get irradiance. Alpha holds the nearest depth (distance
// along the light's view, shadow.glsl's measure) at which a photon splatted
// into the texel landed.
layout(push_constant) uniform Push {
    uint light;
    uint view;
    uint size;
    uint splat_size;
} pc;

layout(location = 0) flat in vec3 v_flux;
layout(location = 1) flat in vec2 v_centre; // photon position in texel units
layout(location = 2) flat in float v_depth;

layout(location = 0) out vec4 out_flux;

void main() {
    float s = float(pc.splat_size);
    float sigma = max(s / 6.0, 0.3);
    float k = 1.0 / (2.0 * sigma * sigma);
    // First of the S centres, per axis.
    vec2 c0 = ceil(v_centre - 0.5 * s - 0.5) + 0.5;
    vec2 idx = floor(gl_FragCoord.xy - c0 + 0.5);
    if (any(lessThan(idx, vec2(0.0))) || any(greaterThanEqual(idx, vec2(s)))) discard;
    vec2 norm = vec2(0.0);
    for (uint i = 0u; i < pc.splat_size; ++i) {
        vec2 dd = c0 + float(i) - v_centre;
        norm += exp(-dd * dd * k);
    }
    vec2 o = gl_FragCoord.xy - v_centre;
    vec2 w2 = exp(-o * o * k) / norm;
    float w = w2.x * w2.y;
    // Alpha keeps the nearest landing depth of the texel's photons (min
    // blending): apply.comp gives a texel's flux only to receivers there.
    out_flux = vec4(v_flux * w, v_depth);
}
