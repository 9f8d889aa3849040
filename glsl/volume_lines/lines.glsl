// volume_lines, Sects. 4 and 5.2 (the body of lines.frag and
// lines_heterogeneous.frag): the radiance one light ray scatters into
// this pixel, Eq. 3 with the regular-step resampling of Fig. 5.
//
// The viewing ray v + t w meets the light ray p1 + s w'_l (closest points)
// at x_l, t = t_l. A thin tube of flux Phi crossing the viewing ray at
// angle theta adds, by the beam x beam estimate (single scattering),
//   L = sigma_s p(w, w'_l) tau(v, x) tau(p1, x) Phi K(d) / sin(theta),
// d the distance between the two rays along w x w'_l and K a 1D kernel in
// d of unit integral. (Why: the tube's cross-section A_perp holds
// irradiance Phi / A_perp, and a viewing ray crosses A_perp / sin(theta)
// of it per unit d of offset, so integrating the scattered radiance along
// the viewing ray, sigma_s p L_in dw dx of Eq. 2, and averaging over d
// gives Phi / sin(theta) per unit d.) The rasterised line is that kernel:
// a pixel gets a fragment when its centre lies in the line's footprint,
// a box in d whose width is the change of d across that footprint:
//   rectangular (strict) lines, 1 px wide perpendicular to the line:
//     w_world = |grad_px d|;
//   parallelogram lines (one fragment per column of the major axis,
//   Bresenham-like), 1 px along the minor axis:
//     w_world = max(|dd/dx|, |dd/dy|) = |grad_px d| max(|dx|,|dy|)/length
//     of the projected line direction;
// both measured here from the viewing rays half a pixel to either side
// (d is 0 along the projected line, so its gradient is perpendicular to
// it and the minor axis is the one along which d changes faster). So
// K = 1 / w_world inside the footprint and
//   L_in Delta_omega Delta_x summed over the step points = Phi tau / (w_world sin theta),
// the Phi of the volume caustic buffer already holding T0, T1, the glass's
// Beer-Lambert and tau(s, p0).
// Fig. 5: the contribution is not taken at x_l but redistributed to the
// regular ray-marching points x_k = k Delta_x (k >= 1) within the filter
// support r of t_l, with Jensen's normalised Gaussian filter weights
// (normalised to sum 1, so the resampling moves energy, never adds it);
// sigma_s, p, tau(v, x_k) and tau(p1, x_k) are evaluated at each x_k.
// Visibility (Sect. 5.3): the fragment is culled when x_l lies behind the
// first surface the pixel sees (diffuse or specular: refractors are
// opaque to the volume caustic); step points behind it are skipped and the
// weights renormalised over those in front (a ray march stops at the
// surface), or x_l itself takes the weight when none is.
#include "scene.glsl"
#include "volume_lines_bindings.glsl"
#include "optics.glsl"
#include "random.glsl"
#include "medium.glsl"
#include "volume_lines.glsl"
#include "beam_crossing.glsl"

layout(set = 1, binding = VOLUME_LINES_BINDING_SEGMENTS, std430) readonly buffer SegmentBlock { Segment segments[]; };
layout(set = 1, binding = VOLUME_LINES_BINDING_VISIBILITY, std430) readonly buffer VisibilityBlock { float surface_distance[]; };

layout(push_constant) uniform Push {
    float step;           // Delta_x (m)
    float radius;         // filter support r (m)
    uint line_raster;     // LINE_RASTER_*
    uint transmittance_steps;
} pc;

layout(location = 0) flat in uint g_segment;
// rgb: radiance (W m^-2 sr^-1); a: 1 per fragment (coverage statistics).
layout(location = 0) out vec4 out_radiance;

// Most regular step points one fragment visits: r <= 16 Delta_x
// (checked on the host).
const int MAX_STEP_POINTS = 33;

// Jensen's normalised Gaussian filter (Realistic Image Synthesis Using
// Photon Mapping, 2001), support r; the constant alpha cancels in the
// normalisation.
float jensen_gaussian(float x, float r) {
    const float beta = 1.953;
    return 1.0 - (1.0 - exp(-beta * x * x / (2.0 * r * r))) / (1.0 - exp(-beta));
}

void main() {
    Segment s = segments[g_segment];
    vec3 eye = frame.eye.xyz;
    vec3 v = view_vector(gl_FragCoord.xy);
    vec3 w = normalize(v);
    vec3 seg = s.p2.xyz - s.p1.xyz;
    float len = length(seg);
    if (len <= 0.0) discard;
    vec3 u = seg / len;
    vec3 r = s.p1.xyz - eye;
    float b = dot(w, u);
    float sin2 = 1.0 - b * b;
    if (sin2 < 1e-8) discard; // the light ray runs along the viewing ray
    float t_l = (dot(w, r) - b * dot(u, r)) / sin2;
    uint pixel = uint(gl_FragCoord.y) * uint(frame.viewport.x) + uint(gl_FragCoord.x);
    float t_surface = surface_distance[pixel];
    if (t_l <= 0.0 || t_l >= t_surface) discard;

    // Kernel width in d (metres) of this line's rasterised footprint.
    vec2 dd = ray_distance_per_pixel(gl_FragCoord.xy, v, r, u);
    float width = pc.line_raster == LINE_RASTER_RECTANGULAR ? length(dd) : max(abs(dd.x), abs(dd.y));
    if (!(width > 0.0)) discard;

    float cos_scatter = dot(u, -w); // before: along u; after: toward the camera
    float phase = hg_phase(cos_scatter, medium.sigma_s.w);

    // Fig. 5: regular step points within r of t_l, weights normalised.
    int k0 = max(1, int(ceil((t_l - pc.radius) / pc.step)));
    int k1 = int(floor((t_l + pc.radius) / pc.step));
    k1 = min(k1, k0 + MAX_STEP_POINTS - 1);
    float total = 0.0, visible = 0.0;
    for (int k = k0; k <= k1; ++k) {
        float t = float(k) * pc.step;
        float g = jensen_gaussian(t - t_l, pc.radius);
        total += g;
        if (t < t_surface) visible += g;
    }
    if (total <= 0.0) discard; // no step point within the support (2 r < Delta_x)
    vec3 sum = vec3(0.0);
    if (visible > 0.0) {
        for (int k = k0; k <= k1; ++k) {
            float t = float(k) * pc.step;
            if (t >= t_surface) continue;
            vec3 x = eye + t * w;
            float g = jensen_gaussian(t - t_l, pc.radius) / visible;
            sum += g * vl_sigma_s(x) * vl_transmittance(eye, x, pc.transmittance_steps) *
                   vl_transmittance(s.p1.xyz, x, pc.transmittance_steps);
        }
    } else {
        vec3 x = eye + t_l * w;
        sum = vl_sigma_s(x) * vl_transmittance(eye, x, pc.transmittance_steps) *
              vl_transmittance(s.p1.xyz, x, pc.transmittance_steps);
    }
    vec3 radiance = sum * phase * s.flux.rgb / (width * sqrt(sin2));
    out_radiance = vec4(radiance * component_weight(COMPONENT_VOLUME_CAUSTICS), 1.0);
}
