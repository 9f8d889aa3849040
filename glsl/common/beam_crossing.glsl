// A pixel's viewing ray crossing a light ray (a thin beam of light in a
// medium), for the beam x beam estimate of Hu et al. 2010 Eq. 3: the
// viewing ray through a fragment, the signed distance between the two
// rays, and how much that distance changes across one pixel (the width of
// the 1D kernel a one-pixel footprint stands for). Shared by
// glsl/volume_lines/lines.glsl and glsl/water_photons/shafts.frag.
// Requires scene.glsl (the frame constants).
#ifndef COMMON_BEAM_CROSSING_GLSL
#define COMMON_BEAM_CROSSING_GLSL

// Unnormalised direction of the viewing ray through `frag` (window
// coordinates): the far-plane point minus the eye. For a perspective
// projection the unprojected far-plane point's w does not depend on the
// pixel, so this is affine in `frag` (offsets may reuse one evaluation).
vec3 view_vector(vec2 frag) {
    vec2 ndc = frag / frame.viewport.xy * 2.0 - 1.0;
    vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    return far.xyz / far.w - frame.eye.xyz;
}

// Signed distance between the viewing ray along `v` (any length) and the
// light ray through eye + r with unit direction u, along v x u.
float ray_distance(vec3 v, vec3 r, vec3 u) {
    vec3 n = cross(v, u);
    return dot(r, n) * inversesqrt(max(dot(n, n), 1e-30));
}

// The change of that distance across the pixel at `frag` (viewing vector
// v = view_vector(frag)), along x and along y, from the viewing rays half
// a pixel to either side.
vec2 ray_distance_per_pixel(vec2 frag, vec3 v, vec3 r, vec3 u) {
    // Half a pixel to the right and down (affine, see view_vector).
    vec3 half_x = 0.5 * (view_vector(frag + vec2(1.0, 0.0)) - v);
    vec3 half_y = 0.5 * (view_vector(frag + vec2(0.0, 1.0)) - v);
    return vec2(ray_distance(v + half_x, r, u) - ray_distance(v - half_x, r, u),
                ray_distance(v + half_y, r, u) - ray_distance(v - half_y, r, u));
}

#endif
