// Geometric optics shared by every technique and the reference (GUIDE §2):
// exact unpolarised Fresnel, Snell refraction, mirror reflection, and the
// sampling helpers that go with them.
#ifndef COMMON_OPTICS_GLSL
#define COMMON_OPTICS_GLSL

const float PI = 3.14159265358979323846;

// Unpolarised Fresnel reflectance; cos_i = |cos| of the incident angle,
// eta = n_incident / n_transmitted. 1 under total internal reflection.
// Fresnel reflectance of the s and p polarisations (x, y), as below.
vec2 fresnel_polarised(float cos_i, float eta) {
    cos_i = min(abs(cos_i), 1.0);
    float sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) return vec2(1.0);
    float cos_t = sqrt(1.0 - sin2_t);
    float rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return vec2(rs * rs, rp * rp);
}

float fresnel_dielectric(float cos_i, float eta) {
    vec2 r = fresnel_polarised(cos_i, eta);
    return 0.5 * (r.x + r.y);
}

// Reflectance of a thin dielectric sheet of index `ior` in air, light
// arriving at |cos| = cos_i; the rest passes straight through. Per
// polarisation the inter-reflections between the two faces sum to
// R = r + t^2 r / (1 - r^2) = 2r / (1 + r), T = (1 - r) / (1 + r);
// averaged over s and p. Derivation and citation: src/radiometry.rs
// `thin_sheet_reflectance`.
float thin_sheet_reflectance(float cos_i, float ior) {
    vec2 r = fresnel_polarised(cos_i, 1.0 / ior);
    vec2 sheet = 2.0 * r / (1.0 + r);
    return 0.5 * (sheet.x + sheet.y);
}

// Snell's law: d incident (unit), n the normal on the incident side
// (dot(d, n) < 0), eta = n_incident / n_transmitted. Returns false under TIR.
bool refract_dir(vec3 d, vec3 n, float eta, out vec3 t) {
    float cos_i = -dot(d, n);
    float sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) { t = vec3(0.0); return false; }
    t = normalize(eta * d + (eta * cos_i - sqrt(1.0 - sin2_t)) * n);
    return true;
}

// An orthonormal basis around unit n (Duff et al. 2017).
void basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

vec3 uniform_sphere(vec2 u) {
    float z = 1.0 - 2.0 * u.x;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
}

// Uniform direction in the cone of half-angle acos(cos_max) around `axis`.
vec3 uniform_cone(vec2 u, vec3 axis, float cos_max) {
    float cos_t = 1.0 - u.x * (1.0 - cos_max);
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    basis(axis, t, b);
    return normalize(t * (sin_t * cos(phi)) + b * (sin_t * sin(phi)) + axis * cos_t);
}

// The inverse of uniform_cone: the u that maps to `dir` (inside the cone).
vec2 uniform_cone_coords(vec3 dir, vec3 axis, float cos_max) {
    vec3 t, b;
    basis(axis, t, b);
    float phi = atan(dot(dir, b), dot(dir, t));
    if (phi < 0.0) phi += 2.0 * PI;
    return vec2((1.0 - dot(dir, axis)) / (1.0 - cos_max), phi / (2.0 * PI));
}

vec3 cosine_hemisphere(vec2 u, vec3 n) {
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    basis(n, t, b);
    return normalize(t * (r * cos(phi)) + b * (r * sin(phi)) + n * sqrt(max(0.0, 1.0 - u.x)));
}

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

#endif
