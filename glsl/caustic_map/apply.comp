#version 460
// Caustic maps, step 3: project the light-space caustic map onto the diffuse
// receivers of the camera G-buffer and add L = albedo / pi * E_caustic to
// the radiance already there (the `direct` frame).
//
// The map holds flux per texel Phi (W). The texel's footprint on a receiver
// at x with unit normal n has area
//   perspective view: A = Omega_texel * d^2 / cos(theta)  (d = |x - light|,
//                     theta between n and the direction to the light,
//                     Omega_texel the texel's exact solid angle),
//   orthographic:     A = a_texel / cos(theta)            (a_texel = texel side^2),
// so E = Phi / A, exactly the flux that landed in that texel spread over the
// area it covers on this receiver (flux is conserved: the integral of E over
// a planar receiver is the sum of the texels' flux).
//
// A texel's flux belongs to the receivers where its photons landed. The map
// is indexed along the light's view, so one texel also covers receivers in
// front of and behind them; its alpha holds the photons' nearest landing
// depth (splat.frag). Receivers nearer the light than that (beyond a
// splat's reach) get none of the flux: the top of the pool's wall, lit
// directly above the floor that the refracted light reaches behind it.
// Receivers behind it get none where a diffuse surface lies between them
// and that depth (the BVH along the straight line toward the light,
// skipping specular surfaces, which the photons went through): the floor
// in a column's shadow behind the photons on the column. Nothing farther
// toward the light is asked: the photons' own paths, traced, already met
// what occludes them (the floor by the pool's wall, reached by light bent
// under the wall's straight shadow).
//
// In a participating medium the photons' flux already carries the light
// side's transmittance (photons.comp); the caustic radiance is attenuated
// toward the eye by tau(x, v) (Hu et al. 2010 Sect. 5.3, Fig. 2 C).
#include "scene.glsl"
#include "optics.glsl"
#include "bvh.glsl"
#include "random.glsl"
#include "medium.glsl"

#define SHADOW_SET 1
#define SHADOW_BINDING_LIGHTS CAUSTIC_BINDING_VIEWS
#define SHADOW_NO_MAP
#include "shadow.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = CAUSTIC_BINDING_MAP) uniform sampler2DArray caustic_map;
layout(set = 1, binding = CAUSTIC_BINDING_POSITION, rgba32f) uniform readonly image2D g_position;
layout(set = 1, binding = CAUSTIC_BINDING_NORMAL, rgba32f) uniform readonly image2D g_normal;
layout(set = 1, binding = CAUSTIC_BINDING_ALBEDO, rgba32f) uniform readonly image2D g_albedo;
layout(set = 1, binding = CAUSTIC_BINDING_RADIANCE, rgba32f) uniform image2D radiance;

layout(push_constant) uniform Push {
    uint light_count;
    uint medium_steps; // midpoint steps of inhomogeneous transmittance
    uint splat_size;   // sprite width in texels (splat.frag)
} pc;

// Solid angle of the tan-plane rectangle [u0,u1] x [v0,v1] (2x2 Gauss-Legendre,
// as in photons.comp).
float texel_solid_angle(float u0, float u1, float v0, float v1) {
    const float g = 0.5773502691896258;
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

// True if no diffuse surface lies between x and the light (specular ones are skipped).
bool diffuse_visible(vec3 x, vec3 to_light, float dist) {
    vec3 o = x;
    float travelled = 0.0;
    for (int i = 0; i < 32; ++i) {
        Hit h;
        if (!trace_closest(o, to_light, 0.0, dist - travelled, h)) return true;
        if (material_kind(hit_material(h)) == MATERIAL_DIFFUSE) return false;
        vec3 p = hit_position(h, o, to_light);
        travelled += h.t;
        o = p + to_light * (1e-4 * max(1.0, bvh_max_abs(p)));
        travelled += 1e-4 * max(1.0, bvh_max_abs(p));
        if (travelled >= dist) return true;
    }
    return true;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    vec4 position = imageLoad(g_position, p);
    if (position.w == 0.0) return;
    vec4 nm = imageLoad(g_normal, p);
    uint material = uint(nm.w + 0.5);
    if (material_kind(material) != MATERIAL_DIFFUSE) return;
    vec3 x = position.xyz;
    vec3 n = normalize(nm.xyz);
    ivec2 size = textureSize(caustic_map, 0).xy;
    vec3 e_sum = vec3(0.0);
    for (uint l = 0u; l < pc.light_count; ++l) {
        ShadowLight s = shadow_lights[l];
        uint view = shadow_view(s, x);
        vec4 clip = s.view_proj[view] * vec4(x, 1.0);
        if (clip.w <= 0.0) continue;
        vec2 ndc = clip.xy / clip.w;
        if (any(greaterThan(abs(ndc), vec2(1.0)))) continue;
        ivec2 texel = clamp(ivec2(floor((ndc * 0.5 + 0.5) * vec2(size))), ivec2(0), size - 1);
        vec4 stored = texelFetch(caustic_map, ivec3(texel, int(s.info.z + view)), 0);
        vec3 flux = stored.rgb;
        if (all(equal(flux, vec3(0.0)))) continue;
        vec3 to_light;
        float dist;
        float area;
        if (s.info.x == SHADOW_PLANAR) {
            to_light = -s.direction.xyz;
            dist = 1e30;
            area = s.origin.w * s.origin.w;
        } else {
            vec3 v = s.origin.xyz - x;
            dist = length(v);
            to_light = v / dist;
            // origin.w = 2 tan(half fov) / size: texel edges in the tan plane.
            float h = s.origin.w * float(size.x) * 0.5;
            float u0 = (2.0 * float(texel.x) / float(size.x) - 1.0) * h;
            float u1 = (2.0 * float(texel.x + 1) / float(size.x) - 1.0) * h;
            float v0 = (2.0 * float(texel.y) / float(size.y) - 1.0) * h;
            float v1 = (2.0 * float(texel.y + 1) / float(size.y) - 1.0) * h;
            area = texel_solid_angle(u0, u1, v0, v1) * dist * dist;
        }
        float cos_t = dot(n, to_light);
        if (cos_t <= 0.0) continue;
        // Where the texel's photons landed (header): the map has no depth
        // of its own (Wyman 2006, "Rendering the Caustic Map", keeps the
        // light's depth map beside it); the tolerance covers a splat's
        // reach across a sloped receiver, as the shadow maps' slope bias
        // does (shadow.glsl).
        float reach = shadow_texel_world(s, x)
            * (1.0 + (0.5 * float(pc.splat_size) + 1.0) * shadow_slope_tan(cos_t));
        float behind = shadow_receiver_depth(s, x) - stored.a;
        if (behind < -reach) continue;
        float segment = min(dist, max(behind, 0.0) + reach);
        if (!diffuse_visible(x + n * (1e-4 * max(1.0, bvh_max_abs(x))), to_light, segment)) continue;
        e_sum += flux * cos_t / area;
    }
    vec3 albedo = imageLoad(g_albedo, p).rgb;
    vec4 prev = imageLoad(radiance, p);
    vec3 to_eye = frame.eye.xyz - x;
    float eye_dist = length(to_eye);
    vec3 tau_eye = medium_transmittance_steps(x, to_eye / eye_dist, eye_dist, pc.medium_steps);
    vec3 caustic = component_weight(COMPONENT_SURFACE_CAUSTICS) * albedo / PI * e_sum * tau_eye;
    imageStore(radiance, p, vec4(prev.rgb + caustic, prev.a));
}
