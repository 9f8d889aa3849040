// GPU scene layout: mirrors src/gpu.rs field for field (16-byte vectors only,
// so std430 equals the Rust #[repr(C)] layout; src/gpu.rs asserts the sizes).
// Include after defining SCENE_SET (the descriptor set index of the scene).
#ifndef COMMON_SCENE_GLSL
#define COMMON_SCENE_GLSL

#include "bindings.glsl"

#ifndef SCENE_SET
#define SCENE_SET 0
#endif

struct Triangle {
    vec4 p0; // w: material index (uint bits)
    vec4 p1; // w: object index (uint bits)
    vec4 p2;
    vec4 n0; // w: Wyman's d_N for refractors (distance to the far side along -n), else 0
    vec4 n1;
    vec4 n2;
};

// A triangle's UVs (src/gpu.rs GpuTriangleUv), same index as triangles[].
struct TriangleUv {
    vec4 uv01; // xy: vertex 0, zw: vertex 1
    vec4 uv2;  // xy: vertex 2
};

struct BvhNode {
    vec3 bounds_min;
    uint left_or_first; // inner: left child (right = left + 1); leaf: first triangle
    vec3 bounds_max;
    uint count;         // 0: inner node; else triangles in the leaf
};

struct Material {
    vec4 color;          // rgb albedo/reflectance; w: kind (uint bits)
    vec4 absorption_ior; // rgb extinction inside a dielectric, 1/m (absorption + the inside's scattering); w: ior
    vec4 albedo_texture; // x: layer in bits 0-15, wrap u/v (WRAP_*) in bits 16-17/18-19 (int bits, -1: none); yz: uv_scale; w: alpha cutoff
    vec4 emission;       // rgb radiance emitted from front faces (area lights)
    vec4 specular;       // rgb mirror reflectance of a `mixed` material (kind diffuse); 0 otherwise
    vec4 scattering;     // dielectric: rgb sigma_s of the medium inside (1/m, 0: none); w: HG g
};

// An area light (src/gpu.rs GpuEmitter); its geometry is ordinary
// triangles whose material emits.
struct Emitter {
    vec4 position; // xyz centre; w: kind EMITTER_* (uint bits)
    vec4 normal;   // xyz unit normal (rect); w: width (rect) or radius (sphere)
    vec4 tangent;  // xyz unit direction of the width (rect); w: height (rect)
    vec4 radiance; // rgb W m^-2 sr^-1; w: luminance power for light selection
};

// The environment light (src/gpu.rs GpuEnvironment).
struct EnvironmentInfo {
    vec4 params;       // x: 1 when present; zw: cos, sin of the rotation about +y
    vec4 sun;          // xyz toward the sun (world); w: cos of its angular radius (2: none)
    vec4 sun_radiance; // rgb; w: luminance power for light selection
    vec4 table;        // x width, y height of the radiance table; z: its luminance power
    // The sun found in an image (src/environment.rs extract_sun), for direct:
    vec4 image_sun_peak;       // xyz peak texel's direction; w: cos of the search cone (2: none)
    vec4 image_sun_direction;  // xyz mean direction toward it; w: luminance threshold
    vec4 image_sun_irradiance; // rgb irradiance facing it
};

struct Light {
    vec4 position;  // w: kind (uint bits)
    vec4 direction; // unit, the way light travels; w: cos(cone half-angle)
    vec4 intensity; // rgb W/sr or W/m^2; w: cos(half-angle - falloff)
    vec4 power;     // x: luminance power for light selection
};

struct Medium {
    vec4 sigma_s;    // rgb 1/m; w: g
    vec4 sigma_a;    // rgb 1/m; w: density kind (uint bits)
    vec4 bounds_min; // w: density scale
    vec4 bounds_max; // w: maximum density
    vec4 noise;      // xyz offset; w: frequency
    uvec4 dims;      // xyz grid dims; w: noise octaves
};

layout(set = SCENE_SET, binding = BINDING_FRAME, std140) uniform FrameBlock {
    mat4 view;
    mat4 proj;
    mat4 view_proj;
    mat4 inv_view_proj;
    vec4 eye;          // w: tan(fov_y/2)
    vec4 viewport;     // width, height, aspect, time
    vec4 scene_sphere; // centre, radius
    uvec4 counts;      // lights, triangles, materials, frame index
    uvec4 components;  // x: bit mask of the components drawn (1 << COMPONENT_*); y: area lights; z: still frames before this one
} frame;

// 1.0 when the path-type component `c` (COMPONENT_*) is drawn this frame,
// else 0.0: techniques multiply each component's radiance by it (the
// demo's C key, `caustics render --component`).
float component_weight(uint c) { return (frame.components.x & (1u << c)) != 0u ? 1.0 : 0.0; }

layout(set = SCENE_SET, binding = BINDING_TRIANGLES, std430) readonly buffer TriangleBlock { Triangle triangles[]; };
layout(set = SCENE_SET, binding = BINDING_BVH_NODES, std430) readonly buffer BvhBlock { BvhNode bvh_nodes[]; };
layout(set = SCENE_SET, binding = BINDING_MATERIALS, std430) readonly buffer MaterialBlock { Material materials[]; };
layout(set = SCENE_SET, binding = BINDING_LIGHTS, std430) readonly buffer LightBlock { Light lights[]; };
layout(set = SCENE_SET, binding = BINDING_MEDIUM, std430) readonly buffer MediumBlock { Medium medium; };
layout(set = SCENE_SET, binding = BINDING_DENSITY_GRID, std430) readonly buffer DensityBlock { float density_grid[]; };
layout(set = SCENE_SET, binding = BINDING_TRIANGLE_UVS, std430) readonly buffer TriangleUvBlock { TriangleUv triangle_uvs[]; };
// Every albedo texture, one layer each (src/frame/textures.rs): trilinear,
// repeat wrap (other wrap modes: material_texture_coordinate).
layout(set = SCENE_SET, binding = BINDING_ALBEDO_TEXTURES) uniform sampler2DArray albedo_textures;
layout(set = SCENE_SET, binding = BINDING_EMITTERS, std430) readonly buffer EmitterBlock { Emitter emitters[]; };
// The environment's equirectangular radiance (linear, bilinear; glsl/common/emitters.glsl).
layout(set = SCENE_SET, binding = BINDING_ENVIRONMENT) uniform sampler2DArray environment_map;
// Its constants, then the sampling tables: the marginal CDF over rows
// (height + 1 values), then each row's CDF over columns (width + 1 each).
layout(set = SCENE_SET, binding = BINDING_ENVIRONMENT_DATA, std430) readonly buffer EnvironmentBlock {
    EnvironmentInfo environment;
    float environment_cdf[];
};

uint triangle_material(uint tri) { return floatBitsToUint(triangles[tri].p0.w); }
uint material_kind(uint m) { return floatBitsToUint(materials[m].color.w); }
uint light_kind(uint l) { return floatBitsToUint(lights[l].position.w); }

// The mirror part of material m: a `mixed` material's specular reflectance
// (its kind is diffuse: the Lambertian part), 0 for every other material.
vec3 material_specular(uint m) { return materials[m].specular.rgb; }

// UV at barycentric b (weights of vertices 1 and 2) of triangle `tri`.
vec2 triangle_uv(uint tri, vec2 b) {
    TriangleUv t = triangle_uvs[tri];
    return (1.0 - b.x - b.y) * t.uv01.xy + b.x * t.uv01.zw + b.y * t.uv2.xy;
}

// Material m's texture array layer (-1: none).
int material_layer(uint m) {
    int packed = floatBitsToInt(materials[m].albedo_texture.x);
    return packed < 0 ? -1 : packed & 0xffff;
}

// One texture coordinate through wrap mode `wrap` (WRAP_*; glTF sampler
// wrapS/wrapT): repeat is the sampler's own; clamp-to-edge and mirrored
// repeat fold the coordinate into [0, 1] here and then keep it `margin`
// inside the edges, so the repeat sampler's bilinear taps never reach
// across to the opposite edge.
float wrap_coordinate(float u, uint wrap, float margin) {
    if (wrap == WRAP_REPEAT) return u;
    if (wrap == WRAP_MIRRORED_REPEAT) u = 1.0 - abs(1.0 - mod(u, 2.0));
    return clamp(u, margin, 1.0 - margin);
}

// The array coordinate of material m's texture at `uv` (times uv_scale,
// wrapped). `lod` is the mip level the lookup filters at: the clamp margin
// is half a texel of the coarser level a trilinear lookup reads, exact
// there and within a texel of the finer one.
vec3 material_texture_coordinate(uint m, vec2 uv, float lod) {
    int packed = floatBitsToInt(materials[m].albedo_texture.x);
    uvec2 wrap = (uvec2(packed) >> uvec2(16u, 18u)) & 3u;
    vec2 st = uv * materials[m].albedo_texture.yz;
    if (wrap != uvec2(WRAP_REPEAT)) {
        float margin = 0.5 * exp2(ceil(max(lod, 0.0))) / float(textureSize(albedo_textures, 0).x);
        st = vec2(wrap_coordinate(st.x, wrap.x, margin), wrap_coordinate(st.y, wrap.y, margin));
    }
    return vec3(st, float(packed & 0xffff));
}

// Albedo of diffuse material m at `uv`: its colour times its texture (if
// any) at uv * uv_scale, wrapped, filtered over the footprint given by the
// UV derivatives across a pixel (docs/SCENES.md, "Albedo textures").
vec3 material_albedo_grad(uint m, vec2 uv, vec2 duv_dx, vec2 duv_dy) {
    vec3 c = materials[m].color.rgb;
    if (material_layer(m) < 0) return c;
    vec2 s = materials[m].albedo_texture.yz;
    vec2 dx = duv_dx * s, dy = duv_dy * s;
    // The level the lookup reads (the larger footprint axis, as the
    // Vulkan spec's isotropic LOD): only to size the clamp margin.
    float size = float(textureSize(albedo_textures, 0).x);
    float lod = log2(max(max(length(dx), length(dy)) * size, 1e-30));
    return c * textureGrad(albedo_textures, material_texture_coordinate(m, uv, lod), dx, dy).rgb;
}

// The same at the finest mip level (bilinear): for ray hits, which have no
// pixel footprint; an estimator that averages many of them per pixel (the
// reference) filters the texture by its own sampling.
vec3 material_albedo(uint m, vec2 uv) {
    return material_albedo_grad(m, uv, vec2(0.0), vec2(0.0));
}

// Whether material m is cut out at `uv` (glTF alphaMode MASK, docs/SCENES.md
// "Cut-outs"): its texture's alpha below the material's cutoff, read at the
// finest level (bilinear) by every pass, rasterised or traced, so a
// cut-out has one shape for the camera, the shadow maps and every ray at
// any distance (a coarser, box-filtered alpha level would thin it).
bool material_cut_out(uint m, vec2 uv) {
    float cutoff = materials[m].albedo_texture.w;
    if (cutoff <= 0.0) return false;
    return textureLod(albedo_textures, material_texture_coordinate(m, uv, 0.0), 0.0).a < cutoff;
}

bool triangle_cut_out(uint tri, vec2 b) {
    uint m = triangle_material(tri);
    if (materials[m].albedo_texture.w <= 0.0) return false;
    return material_cut_out(m, triangle_uv(tri, b));
}

#endif
