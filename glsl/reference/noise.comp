#version 460
// Ground truth: the remaining noise. Per pixel, the variance of the mean of
// P pass estimates, s^2 / P with s^2 the sample variance of their luminance;
// summed over the image with the mean luminance, so the host reports
// sqrt(mean variance of the mean) / mean luminance: the relative RMS error
// still to be averaged away.
#include "common.glsl"

layout(local_size_x = 64) in;

void main() {
    uint index = gl_GlobalInvocationID.x;
    if (index >= image_pixels() || pc.passes < 2.0) return;
    vec2 m = moments[index] / pc.passes;
    float variance = max(m.y - m.x * m.x, 0.0) * pc.passes / (pc.passes - 1.0);
    atomicAdd(noise_variance_sum, variance / pc.passes);
    atomicAdd(noise_mean_sum, m.x);
}
