// Real spherical harmonics of order 2 (9 coefficients) and the irradiance
// they give, after Ramamoorthi & Hanrahan 2001, "An Efficient Representation
// for Irradiance Environment Maps": Eq. 3 (the basis, in world x, y, z) and
// Eq. 7-8 (E(n) = sum_lm A_l L_lm Y_lm(n), A_0 = pi, A_1 = 2pi/3, A_2 = pi/4).
#ifndef DIRECT_SH_GLSL
#define DIRECT_SH_GLSL

void sh_basis(vec3 d, out float y[9]) {
    y[0] = 0.282095;
    y[1] = 0.488603 * d.y;
    y[2] = 0.488603 * d.z;
    y[3] = 0.488603 * d.x;
    y[4] = 1.092548 * d.x * d.y;
    y[5] = 1.092548 * d.y * d.z;
    y[6] = 0.315392 * (3.0 * d.z * d.z - 1.0);
    y[7] = 1.092548 * d.x * d.z;
    y[8] = 0.546274 * (d.x * d.x - d.y * d.y);
}

// Convolution with the clamped cosine, per band (Eq. 8).
const float SH_BAND_FACTOR[9] = float[9](
    3.14159265, 2.09439510, 2.09439510, 2.09439510,
    0.78539816, 0.78539816, 0.78539816, 0.78539816, 0.78539816);

#endif
