// Where the frame's camera sees a world point, and whether it sees the
// point itself in the opaque frame (the frame without its specular
// surfaces). Shared by glsl/passes/camera_refraction.comp and
// glsl/water_photons/view.comp, which trace rays the camera does not see
// and read the opaque frame where their hit is on screen after all.
//
// The includer declares, before including this file,
//   layout(...) uniform readonly image2D opaque_position;
// the opaque frame's world position per pixel (w = 0: the background).
#ifndef COMMON_CAMERA_PIXELS_GLSL
#define COMMON_CAMERA_PIXELS_GLSL

// The pixel x projects to and its view depth (clip w); false behind the
// camera or outside the image.
bool camera_pixel(vec3 x, out ivec2 q, out float depth) {
    vec4 c = frame.view_proj * vec4(x, 1.0);
    depth = c.w;
    q = ivec2(-1);
    if (c.w <= 1e-6) return false;
    vec2 pixel = (c.xy / c.w * 0.5 + 0.5) * frame.viewport.xy;
    if (any(lessThan(pixel, vec2(0.0))) || any(greaterThanEqual(pixel, frame.viewport.xy))) return false;
    q = ivec2(pixel);
    return true;
}

// The pixel q that sees x (on the plane of normal n) itself: x inside the
// view, and the opaque frame's surface at q on x's plane within `tol`.
// That surface and x lie on one camera ray (the pixel's footprint aside),
// which meets the plane once, so it is x; an occluder (a wall's top, a
// column) or a silhouette's far side lies off the plane.
bool seen_by_camera(vec3 x, vec3 n, float tol, out ivec2 q) {
    float depth;
    if (!camera_pixel(x, q, depth)) return false;
    vec4 g = imageLoad(opaque_position, q);
    return g.w != 0.0 && abs(dot(g.xyz - x, n)) <= tol;
}

#endif
