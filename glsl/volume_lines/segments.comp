#version 460
// volume_lines, Sect. 5.1 (Generating Line Primitives): one light ray per
// texel of the light's view of the specular objects, followed through one
// reflection (mirrors) or two refractions (dielectrics) to its exit point
// p1 and direction w'_l, and on to p2 on the first diffuse surface; written
// to the volume caustic buffer: N^2 Segments, one per texel, invalid ones
// flagged with p1.w = 0, then N^2 more for the Fresnel reflection off a
// dielectric's front face (a one-bounce reflection, as Hu's gemstone
// draws both; flagged invalid for other texels).
//
// The view is the light's view of the specular objects
// (src/passes/light_views.rs `photon_view`: a frustum fitted to their
// bounding sphere, or an orthographic box for directional light), and the
// front/back G-buffers are `passes::specular_gbuffer` drawn from it by
// `LightViews`, as Hu's "front-
// and back-facing depth and normal maps of the specular objects".
// Two-bounce refraction is Wyman's two-sided image-space refraction
// (glsl/common/image_space_refraction.glsl, the code image_space runs for
// the camera and its photon_mode 1): Snell at the front face, the second
// interface at d~ (Eq. 6.3.1) with its normal from the back-face map, Snell
// again, with the selected TIR remedy.
//
// Flux (GUIDE §2): Phi = I(w) Omega_texel for point and spot lights (exact
// texel solid angle), E A_texel for directional light, times the Fresnel
// transmittances T0 = 1 - F0 and T1 = 1 - F1 (reflectance for mirrors),
// Beer-Lambert in the glass and the medium's tau(s, p0) from the light to
// the object: Eq. 3's L_in Delta_omega without the tau(p1, x_l) the
// fragments add.
//
// p2: Hu intersects the exit ray with the light's depth map of the scene
// without the specular objects, and a scene bounding sphere where that
// misses. We land it exactly through the BVH instead (the caustic map's
// photons do the same), passing through specular surfaces, and fall back
// to the scene's bounding sphere (frame.scene_sphere) when it leaves.
#include "scene.glsl"
#include "volume_lines_bindings.glsl"
#include "optics.glsl"
#include "lights.glsl"
#include "bvh.glsl"
#include "random.glsl"
#include "medium.glsl"
#include "volume_lines.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = VOLUME_LINES_BINDING_SEGMENTS, std430) writeonly buffer SegmentBlock { Segment segments[]; };
layout(set = 1, binding = VOLUME_LINES_BINDING_FRONT_POSITION, rgba32f) uniform readonly image2D front_position;
layout(set = 1, binding = VOLUME_LINES_BINDING_FRONT_NORMAL, rgba32f) uniform readonly image2D front_normal;
layout(set = 1, binding = VOLUME_LINES_BINDING_BACK_POSITION, rgba32f) uniform readonly image2D back_position;
layout(set = 1, binding = VOLUME_LINES_BINDING_BACK_NORMAL, rgba32f) uniform readonly image2D back_normal;

layout(push_constant) uniform Push {
    vec4 origin;  // xyz: light position (perspective) or ortho plane centre; w: half-width (tan or metres)
    vec4 right;   // xyz; w: light index (uint bits)
    vec4 up;      // xyz; w: view size N (uint bits)
    vec4 forward; // xyz; w: SHADOW_RADIAL (perspective) or SHADOW_PLANAR (ortho) (uint bits)
    uvec4 params; // x: TIR_* remedy; y: 1 = Eq. 6.3.2 on; z: transmittance steps; w: filter radius r (float bits)
} pc;

// Solid angle of the tan-plane rectangle [u0,u1] x [v0,v1] at unit
// distance: 2x2 Gauss-Legendre quadrature of du dv / (1 + u^2 + v^2)^(3/2),
// the same rule as the caustic map's photons (error O(h^4)).
float texel_solid_angle(float u0, float u1, float v0, float v1) {
    const float g = 0.5773502691896258; // 1/sqrt(3)
    float hu = 0.5 * (u1 - u0), hv = 0.5 * (v1 - v0);
    float cu = 0.5 * (u1 + u0), cv = 0.5 * (v1 + v0);
    float sum = 0.0;
    for (int i = 0; i < 2; ++i) {
        for (int j = 0; j < 2; ++j) {
            float u = cu + (i == 0 ? -g : g) * hu;
            float v = cv + (j == 0 ? -g : g) * hv;
            float r2 = 1.0 + u * u + v * v;
            sum += inversesqrt(r2 * r2 * r2);
        }
    }
    return sum * hu * hv;
}

// The view texel x projects to, or (-1, -1) outside the view.
ivec2 light_texel(vec3 x) {
    uint n_size = floatBitsToUint(pc.up.w);
    vec3 v = x - pc.origin.xyz;
    vec2 st;
    if (floatBitsToUint(pc.forward.w) == SHADOW_PLANAR) {
        st = vec2(dot(v, pc.right.xyz), dot(v, pc.up.xyz));
    } else {
        float z = dot(v, pc.forward.xyz);
        if (z <= 0.0) return ivec2(-1);
        st = vec2(dot(v, pc.right.xyz), dot(v, pc.up.xyz)) / z;
    }
    ivec2 q = ivec2(floor((st / pc.origin.w * 0.5 + 0.5) * float(n_size)));
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(n_size)))) return ivec2(-1);
    return q;
}

// The back-face normal at x's texel, for image_space_refraction.glsl.
bool back_face_normal(vec3 x, out vec3 n) {
    n = vec3(0.0);
    ivec2 q = light_texel(x);
    if (q.x < 0 || imageLoad(back_position, q).w < 0.0) return false;
    n = imageLoad(back_normal, q).xyz;
    return true;
}

#include "image_space_refraction.glsl"

// p2: the first diffuse surface along (o, d), specular surfaces passed
// through; where the ray leaves the scene, its exit from the scene's
// bounding sphere.
vec3 segment_end(vec3 o, vec3 d) {
    vec3 x = o;
    for (int i = 0; i < 16; ++i) {
        Hit h;
        if (!trace_closest(x, d, 0.0, 1e30, h)) break;
        vec3 hx = hit_position(h, x, d);
        if (material_kind(hit_material(h)) == MATERIAL_DIFFUSE) return hx;
        x = hx + d * (1e-4 * max(1.0, bvh_max_abs(hx)));
    }
    vec3 c = frame.scene_sphere.xyz;
    float r = frame.scene_sphere.w;
    vec3 oc = o - c;
    float b = dot(oc, d);
    float disc = b * b - (dot(oc, oc) - r * r);
    return o + max(-b + sqrt(max(disc, 0.0)), 0.0) * d;
}

// Clips the light ray a -> b to the medium's bounds, outside which it
// scatters nothing (sigma_s = 0) and would only cost fragments: the
// reflected rays run on to the scene's bounding sphere. A clipped end is
// pushed back out by two pixels' footprint plus the filter radius r,
// taken along the line (from the camera: at distance t a pixel spans
// t a_px across the view, and a length across the view spans that over
// sin(theta) along a line at angle theta to it). Fragments past the end
// would still reach step points inside the medium (within r) and pixels
// near the rasterised end are dropped, so the end must lie where neither
// matters; without the margin a line pointing at a camera outside the
// medium lost 2.7% of its light. The transmittance
// from a clipped start is unchanged (no medium before it). False where the
// ray misses the medium (no line); unclipped without a medium, so every
// light ray is still drawn (and gives exactly 0).
float end_margin(vec3 x, vec3 d) {
    vec3 to_x = x - frame.eye.xyz;
    float t = length(to_x);
    float a_px = 2.0 * frame.eye.w / frame.viewport.y;
    float sin_theta = length(cross(to_x / max(t, 1e-20), d));
    return (2.0 * t * a_px + uintBitsToFloat(pc.params.w)) / max(sin_theta, 1e-3);
}

bool clip_segment(inout vec3 a, inout vec3 b) {
    if (!medium_present()) return true;
    vec3 d = b - a;
    float len = length(d);
    if (len <= 0.0) return false;
    d /= len;
    float t0 = 0.0, t1 = len;
    if (!clip_to_medium(a, d, t0, t1)) return false;
    if (t1 < len) t1 = min(len, t1 + end_margin(a + t1 * d, d));
    if (t0 > 0.0) t0 = max(0.0, t0 - end_margin(a + t0 * d, d));
    b = a + t1 * d;
    a = a + t0 * d;
    return true;
}

void main() {
    uint n_size = floatBitsToUint(pc.up.w);
    uvec2 id = gl_GlobalInvocationID.xy;
    if (id.x >= n_size || id.y >= n_size) return;
    uint index = id.y * n_size + id.x;
    uint l = floatBitsToUint(pc.right.w);
    bool planar = floatBitsToUint(pc.forward.w) == SHADOW_PLANAR;
    float h = pc.origin.w;
    float s0 = (2.0 * float(id.x) / float(n_size) - 1.0) * h;
    float s1 = (2.0 * float(id.x + 1u) / float(n_size) - 1.0) * h;
    float t0 = (2.0 * float(id.y) / float(n_size) - 1.0) * h;
    float t1 = (2.0 * float(id.y + 1u) / float(n_size) - 1.0) * h;
    float s = 0.5 * (s0 + s1), t = 0.5 * (t0 + t1);

    vec3 o, d, phi;
    float measure;
    Light light = lights[l];
    if (planar) {
        o = pc.origin.xyz + s * pc.right.xyz + t * pc.up.xyz;
        d = pc.forward.xyz;
        measure = (s1 - s0) * (t1 - t0);
        phi = light.intensity.rgb * measure;
    } else {
        o = pc.origin.xyz;
        d = normalize(pc.forward.xyz + s * pc.right.xyz + t * pc.up.xyz);
        measure = texel_solid_angle(s0, s1, t0, t1);
        vec3 intensity = light.intensity.rgb;
        if (light_kind(l) == LIGHT_SPOT) {
            intensity *= spot_falloff(dot(d, light.direction.xyz), light.direction.w, light.intensity.w);
        }
        phi = intensity * measure;
    }
    uint count = n_size * n_size;
    segments[index] = Segment(vec4(0.0), vec4(0.0), vec4(0.0, 0.0, 0.0, measure));
    segments[count + index] = Segment(vec4(0.0), vec4(0.0), vec4(0.0, 0.0, 0.0, measure));

    // p0: the specular surface this texel sees first (diffuse geometry in
    // front of it marks the texel not covered).
    vec4 fp = imageLoad(front_position, ivec2(id));
    if (fp.w < 0.0) return;
    vec4 fn = imageLoad(front_normal, ivec2(id));
    uint m = uint(fn.w + 0.5);
    uint kind = material_kind(m);
    if (kind == MATERIAL_DIFFUSE) return;
    vec3 p0 = fp.xyz;
    float d_n = fp.w;
    vec3 n = normalize(fn.xyz);
    if (dot(n, d) > 0.0) n = -n;

    // tau(s, p0): the medium between the light and the object (a
    // directional light's rays come from beyond the medium's bounds, to
    // which vl_transmittance clips).
    phi *= vl_transmittance(planar ? p0 - d * light_travel(1e30, p0) : o, p0, pc.params.z);

    vec3 p1, dir;
    if (kind == MATERIAL_MIRROR) {
        // One-bounce reflection: T0 = the mirror's reflectance.
        p1 = p0;
        dir = reflect(d, n);
        phi *= materials[m].color.rgb;
    } else {
        float ior = materials[m].absorption_ior.w;
        vec3 absorption = materials[m].absorption_ior.rgb;
        vec3 t_1;
        if (!refract_dir(d, n, 1.0 / ior, t_1)) return;
        // The Fresnel reflection at the front face is a one-bounce
        // reflection of its own (part of L S+ V): second half of the buffer.
        float f0 = fresnel_dielectric(-dot(d, n), 1.0 / ior);
        vec3 r = reflect(d, n);
        vec3 a = p0, b = segment_end(p0, r);
        if (clip_segment(a, b)) segments[count + index] = Segment(vec4(a, 1.0), vec4(b, 0.0), vec4(phi * f0, measure));
        phi *= 1.0 - f0; // T0
        vec4 bp = imageLoad(back_position, ivec2(id));
        if (bp.w < 0.0) {
            // No back face: a closed refractor's silhouette texel (d_N > 0)
            // is dropped, an open sheet (d_N = 0, e.g. water) refracts
            // once and its segment starts at the interface.
            if (d_n > 0.0) return;
            p1 = p0;
            dir = t_1;
        } else {
            TwoSidedExit e;
            if (!two_sided_refraction(d, p0, n, ior, length(bp.xyz - p0), d_n, pc.params.x, pc.params.y != 0u, e)) return;
            phi *= e.transmit * exp(-absorption * e.dist); // T1, Beer-Lambert in the glass
            p1 = e.p2;
            dir = e.dir;
        }
    }
    if (all(equal(phi, vec3(0.0)))) return;
    vec3 p2 = segment_end(p1, dir);
    if (clip_segment(p1, p2)) segments[index] = Segment(vec4(p1, 1.0), vec4(p2, 0.0), vec4(phi, measure));
}
