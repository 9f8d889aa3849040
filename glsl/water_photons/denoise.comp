#version 460
// One separable sub-pass of the caustics denoiser of Kougianos & Moustakas
// 2021, Sect. 3.3 and Algorithm 4 (src/techniques/water_photons/denoise.rs):
// a cross-bilateral gather along one image axis whose weights stop at depth
// and world-position edges (Eqs. 21-24), with a kernel radius, sample stride
// and distance scale picked per pixel from the caustic's luminance relative
// to the scene's dimmest light (Eqs. 25-28), or one fixed radius.
//
// Units: caustic irradiance E (W/m^2, rgb) in and out; lengths in metres.
// The paper's prototype ran in Unreal Engine 4, whose unit is the
// centimetre: its epsilon = 1 (Algorithm 4 line 22) and delta = 15 / 2 / 1
// (Eq. 28) are 0.01 m and 0.15 / 0.02 / 0.01 m here.
#include "water_photons_bindings.glsl"
#include "optics.glsl"

layout(local_size_x = DENOISE_GROUP_SIZE, local_size_y = DENOISE_GROUP_SIZE) in;
layout(set = 0, binding = DENOISE_BINDING_INPUT, rgba32f) uniform readonly image2D src;
layout(set = 0, binding = DENOISE_BINDING_OUTPUT, rgba32f) uniform writeonly image2D dst;
// Camera G-buffer position: xyz world position, w = 1 where a surface covers the pixel.
layout(set = 0, binding = DENOISE_BINDING_POSITION, rgba32f) uniform readonly image2D gposition;

layout(push_constant) uniform Push {
    // xyz: camera position; w: C_scene, the luminance threshold of Eq. 25 (W/m^2).
    vec4 eye_c_scene;
    // xyz: unit view direction (view-space depth z = dot(x - eye, forward)); w: epsilon of Eq. 22 (m).
    vec4 forward_epsilon;
    // x: DENOISE_AXIS_*, y: DENOISE_KIND_*, z: fixed radius (pixels), w: unused.
    uvec4 mode;
} pc;

// Eq. 28's delta for the fixed kernel: the paper's third level "falls back
// to the fixed radius case" (Sect. 3.3), 1 UE4 unit = 0.01 m.
const float FIXED_DELTA = 0.01;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(src);
    if (any(greaterThanEqual(p, size))) return;
    vec4 cp = imageLoad(src, p);
    vec4 xp = imageLoad(gposition, p);
    // Background: no surface receives caustics there and none to weigh by.
    if (xp.w == 0.0) {
        imageStore(dst, p, cp);
        return;
    }
    vec3 eye = pc.eye_c_scene.xyz;
    vec3 forward = pc.forward_epsilon.xyz;
    float epsilon = pc.forward_epsilon.w;
    float zp = dot(xp.xyz - eye, forward);

    int rho;      // kernel radius (pixels)
    int lambda;   // sample stride (pixels)
    float delta;  // distance scale of Eq. 23 (m)
    if (pc.mode.y == DENOISE_KIND_ADAPTIVE) {
        // Eqs. 26-28 (Algorithm 4 lines 8-15): the dimmer the caustic relative
        // to C_scene, the noisier it is, the wider and sparser the kernel.
        float c_scene = pc.eye_c_scene.w;
        float lum_cp = luminance(cp.rgb);
        if (lum_cp < 0.1 * c_scene) {
            rho = 15; lambda = 5; delta = 0.15;
        } else if (lum_cp < 0.5 * c_scene) {
            rho = 10; lambda = 1; delta = 0.02;
        } else {
            rho = 5; lambda = 1; delta = 0.01;
        }
    } else {
        rho = int(pc.mode.z); lambda = 1; delta = FIXED_DELTA;
    }

    ivec2 axis = pc.mode.x == DENOISE_AXIS_X ? ivec2(1, 0) : ivec2(0, 1);
    // Eq. 24 with q = p included: w(p, p) = 1 once Eq. 22 is scaled by
    // epsilon (epsilon / (|dz| + epsilon): the same weights up to a constant,
    // which Eq. 24's normalisation removes; Algorithm 4 starts sum_w at 1 with
    // epsilon = 1 for the same reason). sum_w >= 1, so the division is safe.
    // Eq. 24 is evaluated as C(p) + sum w (C(q) - C(p)) / sum w, the same
    // value, so that a constant buffer comes out bit-exact (no rounding of
    // the weighted sum).
    vec3 sum = vec3(0.0);
    float sum_w = 1.0;
    for (int i = -rho; i <= rho; i += lambda) {
        if (i == 0) continue;
        ivec2 q = p + i * axis;
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
        vec4 xq = imageLoad(gposition, q);
        if (xq.w == 0.0) continue;
        float zq = dot(xq.xyz - eye, forward);
        float w_z = epsilon / (abs(zp - zq) + epsilon);           // Eq. 22 (times epsilon)
        vec3 d = xp.xyz - xq.xyz;
        float w_pos = 1.0 / (1.0 + 10.0 * dot(d, d) / (delta * delta)); // Eq. 23
        float w = w_z * w_pos;                                     // Eq. 21
        sum += w * (imageLoad(src, q).rgb - cp.rgb);
        sum_w += w;
    }
    imageStore(dst, p, vec4(cp.rgb + sum / sum_w, cp.a));          // Eq. 24
}
