// The fixed display transform for PNG output and the demo (docs/OUTPUT in
// README): radiance times exposure, Reinhard per channel x / (1 + x), then
// the sRGB transfer function. EXR output stays linear radiance.
#ifndef COMMON_TONEMAP_GLSL
#define COMMON_TONEMAP_GLSL

vec3 srgb_encode(vec3 linear) {
    vec3 lo = linear * 12.92;
    vec3 hi = 1.055 * pow(linear, vec3(1.0 / 2.4)) - 0.055;
    return mix(hi, lo, lessThanEqual(linear, vec3(0.0031308)));
}

vec3 tonemap(vec3 radiance, float exposure) {
    vec3 x = max(radiance * exposure, vec3(0.0));
    return srgb_encode(x / (1.0 + x));
}

#endif
