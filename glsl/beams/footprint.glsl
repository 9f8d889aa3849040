// beams, Sect. 5.3: a pixel's footprint on a plane, for the flux-conserving
// surface gather (caustic.frag deposits flux, apply.comp turns it into
// irradiance). The footprint of pixel [f, f + 1]^2 (framebuffer
// coordinates) on the plane through q with normal m is where the camera
// rays through its four corners meet the plane: a convex quad, exact for a
// plane (perspective maps the square onto it). Neighbouring pixels' quads
// on one plane share their corners, so they tile it: what is spread over
// them by overlap area sums to the whole. Requires scene.glsl.
#ifndef BEAMS_FOOTPRINT_GLSL
#define BEAMS_FOOTPRINT_GLSL

// Unit direction of the camera ray through framebuffer position f (pixels).
vec3 camera_ray(vec2 f) {
    vec2 ndc = f / frame.viewport.xy * 2.0 - 1.0;
    vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    return normalize(far.xyz / far.w - frame.eye.xyz);
}

// The footprint's corners relative to q, counter-clockwise in the pixel
// ((0,0), (1,0), (1,1), (0,1) from f); false where a corner's ray does
// not meet the plane in front of the eye (the plane's horizon crosses the
// pixel).
bool pixel_footprint(vec2 f, vec3 q, vec3 m, out vec3 corners[4]) {
    const vec2 offsets[4] = vec2[4](vec2(0.0), vec2(1.0, 0.0), vec2(1.0), vec2(0.0, 1.0));
    vec3 to_plane = q - frame.eye.xyz;
    float h = dot(to_plane, m);
    for (int i = 0; i < 4; ++i) {
        vec3 w = camera_ray(f + offsets[i]);
        float t = h / dot(w, m);
        if (!(t > 0.0) || isinf(t)) return false;
        // Relative to q: t w - (q - eye), without the eye's large coordinates.
        corners[i] = t * w - to_plane;
    }
    return true;
}

// World area of a planar convex quad.
float quad_area(vec3 c[4]) { return 0.5 * length(cross(c[2] - c[0], c[3] - c[1])); }

#endif
