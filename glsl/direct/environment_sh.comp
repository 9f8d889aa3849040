#version 460
// The environment's irradiance for `direct`: projects its radiance table
// (glsl/common/emitters.glsl; a sky's sun is not in it, an image's sun is
// left out: lighting.comp takes both as a directional light) onto the 9 real
// spherical harmonics of order 2, L_lm = sum over texels of
// L(w) Y_lm(w) dOmega_texel, dOmega_texel = (2 pi / W)(cos theta_0 - cos theta_1)
// exactly, and stores A_l L_lm (sh.glsl), so lighting.comp's irradiance is
// E(n) = sum_lm coefficient_lm Y_lm(n). One workgroup; run when the
// environment changes (src/passes/direct_light.rs).
#include "scene.glsl"
#include "optics.glsl"
#include "emitters.glsl"
#include "sh.glsl"

layout(local_size_x = DIRECT_SH_GROUP_SIZE) in;

layout(set = 1, binding = DIRECT_BINDING_ENVIRONMENT_SH, std430) writeonly buffer ShBlock { vec4 sh[9]; };

shared vec3 partial[9][DIRECT_SH_GROUP_SIZE];

void main() {
    uint tid = gl_LocalInvocationID.x;
    vec3 acc[9];
    for (int k = 0; k < 9; ++k) acc[k] = vec3(0.0);
    if (environment_present()) {
        uint w = uint(environment.table.x), h = uint(environment.table.y);
        for (uint i = tid; i < w * h; i += DIRECT_SH_GROUP_SIZE) {
            uint x = i % w, y = i / w;
            vec2 uv = (vec2(x, y) + 0.5) / vec2(w, h);
            vec3 d = environment_to_world(equirect_dir(uv));
            float omega = 2.0 * PI / float(w) * (cos(PI * float(y) / float(h)) - cos(PI * float(y + 1u) / float(h)));
            vec3 l = texelFetch(environment_map, ivec3(x, y, 0), 0).rgb;
            // An image's sun is lit as a directional light with a shadow.
            if (environment_image_sun_texel(d, l)) continue;
            l *= omega;
            float basis[9];
            sh_basis(d, basis);
            for (int k = 0; k < 9; ++k) acc[k] += l * basis[k];
        }
    }
    for (int k = 0; k < 9; ++k) partial[k][tid] = acc[k];
    barrier();
    for (uint stride = DIRECT_SH_GROUP_SIZE / 2u; stride > 0u; stride /= 2u) {
        if (tid < stride) {
            for (int k = 0; k < 9; ++k) partial[k][tid] += partial[k][tid + stride];
        }
        barrier();
    }
    if (tid < 9u) sh[tid] = vec4(partial[tid][0] * SH_BAND_FACTOR[tid], 0.0);
}
