//! Descriptor binding numbers and shared constants (the scene's set 0, the
//! shared passes, the ground truth): the one source of truth for both Rust
//! and GLSL. `build.rs` reads this file and writes every
//! `pub const NAME: u32` as `#define NAME value` into the generated header
//! `bindings.glsl`, which shaders `#include`. A technique's own constants
//! live in its folder (`src/techniques/<name>/bindings.rs`, generated into
//! `<name>_bindings.glsl` the same way). Keep these files to plain
//! `pub const X: u32 = N;` lines so the build script can read them.

// Set 0: the scene, shared by every pass that reads geometry.
pub const BINDING_FRAME: u32 = 0;
pub const BINDING_TRIANGLES: u32 = 1;
pub const BINDING_BVH_NODES: u32 = 2;
pub const BINDING_MATERIALS: u32 = 3;
pub const BINDING_LIGHTS: u32 = 4;
pub const BINDING_MEDIUM: u32 = 5;
pub const BINDING_DENSITY_GRID: u32 = 6;
/// Per-triangle UVs (leaf order, `GpuTriangleUv`).
pub const BINDING_TRIANGLE_UVS: u32 = 7;
/// The albedo texture array (sampler2DArray; src/frame/textures.rs).
pub const BINDING_ALBEDO_TEXTURES: u32 = 8;
/// Area lights (`GpuEmitter`), at least one record (zeroed when none).
pub const BINDING_EMITTERS: u32 = 9;
/// The environment's equirectangular radiance table (sampler2D, RGBA32F).
pub const BINDING_ENVIRONMENT: u32 = 10;
/// The environment's constants (`GpuEnvironment`) and sampling tables.
pub const BINDING_ENVIRONMENT_DATA: u32 = 11;

// Area light kinds (GpuEmitter.position.w as uint bits).
pub const EMITTER_RECT: u32 = 0;
pub const EMITTER_SPHERE: u32 = 1;
/// An emissive triangle (a glTF `emissiveFactor`): position = vertex 0,
/// normal.xyz = edge to vertex 1, tangent.xyz = edge to vertex 2.
pub const EMITTER_TRIANGLE: u32 = 2;

// Material kinds (GpuMaterial.color.w as uint bits).
pub const MATERIAL_DIFFUSE: u32 = 0;
pub const MATERIAL_MIRROR: u32 = 1;
pub const MATERIAL_DIELECTRIC: u32 = 2;
pub const MATERIAL_THIN_DIELECTRIC: u32 = 3;

// Texture wrap modes (glTF sampler wrapS/wrapT), packed per axis into
// GpuMaterial.texture.x above the layer (bits 16-17: u, 18-19: v).
pub const WRAP_REPEAT: u32 = 0;
pub const WRAP_CLAMP_TO_EDGE: u32 = 1;
pub const WRAP_MIRRORED_REPEAT: u32 = 2;

// Light kinds (GpuLight.position.w as uint bits).
pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_DIRECTIONAL: u32 = 2;

// Medium density kinds (GpuMedium.sigma_a.w as uint bits).
pub const DENSITY_NONE: u32 = 0;
pub const DENSITY_CONSTANT: u32 = 1;
pub const DENSITY_NOISE: u32 = 2;
pub const DENSITY_GRID: u32 = 3;

// Reference light tracer: path-type components of the accumulation buffer.
pub const COMPONENT_DIRECT: u32 = 0;
pub const COMPONENT_SURFACE_CAUSTICS: u32 = 1;
pub const COMPONENT_AIRLIGHT: u32 = 2;
pub const COMPONENT_VOLUME_CAUSTICS: u32 = 3;
pub const COMPONENT_OTHER: u32 = 4;
/// L S* E: emitters (the environment, area lights) seen directly or
/// through specular chains.
pub const COMPONENT_EMITTED: u32 = 5;
pub const COMPONENT_COUNT: u32 = 6;

/// Most lights a scene may hold (one shadow map slot of 6 layers each).
pub const MAX_LIGHTS: u32 = 8;
/// BVH traversal stack depth in GLSL; the CPU builder guarantees the tree is no deeper.
pub const BVH_STACK_SIZE: u32 = 48;

// Shadow maps (src/passes/shadow.rs, glsl/common/shadow.glsl): every light
// owns SHADOW_LAYERS_PER_LIGHT layers of one 2D-array image (light l: layers
// 6l..6l+5); a point light uses all six (cube faces +x -x +y -y +z -z), a
// spot or directional light layer 6l only.
pub const SHADOW_LAYERS_PER_LIGHT: u32 = 6;
// What a shadow texel stores: distance to the light's position (point, spot)
// or depth along the light's direction from its ortho plane (directional).
pub const SHADOW_RADIAL: u32 = 0;
pub const SHADOW_PLANAR: u32 = 1;

// Direct light pass, descriptor set 1 (src/passes/direct_light.rs, glsl/direct/lighting.comp).
pub const DIRECT_BINDING_POSITION: u32 = 0;
pub const DIRECT_BINDING_NORMAL: u32 = 1;
pub const DIRECT_BINDING_RADIANCE: u32 = 2;
pub const DIRECT_BINDING_SHADOW_MAP: u32 = 3;
pub const DIRECT_BINDING_SHADOW_LIGHTS: u32 = 4;
pub const DIRECT_BINDING_ALBEDO: u32 = 5;
/// The environment's irradiance as 9 spherical-harmonic coefficients (rgb, vec4 each).
pub const DIRECT_BINDING_ENVIRONMENT_SH: u32 = 6;
/// Workgroup size of glsl/direct/environment_sh.comp (one workgroup).
pub const DIRECT_SH_GROUP_SIZE: u32 = 64;

// BVH probe (glsl/tests/bvh_probe.comp, tests/suite/bvh_gpu.rs), descriptor set 1
// (set 0 is the scene). Numbers kept from the probe's first version.
pub const PROBE_BINDING_RAYS: u32 = 10;
pub const PROBE_BINDING_RESULTS: u32 = 11;
pub const PROBE_BINDING_ANY: u32 = 12;
/// A uniform block (glsl/tests/uniform_branch.comp, examples/lavapipe_rebind.rs).
pub const PROBE_BINDING_PARAMS: u32 = 13;

// Caustic maps (src/passes/caustic_map.rs, glsl/caustic_map/), descriptor set 1.
pub const CAUSTIC_BINDING_PHOTONS: u32 = 0;
pub const CAUSTIC_BINDING_VIEWS: u32 = 1;
pub const CAUSTIC_BINDING_MAP: u32 = 2;
pub const CAUSTIC_BINDING_POSITION: u32 = 3;
pub const CAUSTIC_BINDING_NORMAL: u32 = 4;
pub const CAUSTIC_BINDING_RADIANCE: u32 = 5;
/// Photon buffer halves: refracted photons first, then reflected ones.
pub const PHOTON_REFRACTED: u32 = 0;
pub const PHOTON_REFLECTED: u32 = 1;
// Light-space G-buffers of the specular objects (image-space photon mode).
pub const CAUSTIC_BINDING_FRONT_POSITION: u32 = 6;
pub const CAUSTIC_BINDING_FRONT_NORMAL: u32 = 7;
pub const CAUSTIC_BINDING_BACK_POSITION: u32 = 8;
pub const CAUSTIC_BINDING_BACK_NORMAL: u32 = 9;
/// The camera G-buffer's albedo (caustic apply).
pub const CAUSTIC_BINDING_ALBEDO: u32 = 10;
/// Photon modes (`photon_mode` parameter of image_space).
pub const PHOTON_MODE_TRACED: u32 = 0;
pub const PHOTON_MODE_IMAGE_SPACE: u32 = 1;
pub const PHOTON_MODE_BACK_MARCH: u32 = 2;
/// Specialisation constant ids of caustic_map/photons.comp: its rebuild
/// parameters, so each pipeline compiles only the chosen path code.
pub const CAUSTIC_SPEC_PHOTON_MODE: u32 = 0;
pub const CAUSTIC_SPEC_TIR_REMEDY: u32 = 1;
pub const CAUSTIC_SPEC_EQ632: u32 = 2;
/// Specular G-buffer passes (src/passes/specular_gbuffer.rs): nearest front
/// faces, farthest back faces.
pub const SPECULAR_GBUFFER_FRONT: u32 = 0;
pub const SPECULAR_GBUFFER_BACK: u32 = 1;
/// Specular G-buffer viewpoint kinds besides SHADOW_RADIAL (a light's
/// perspective view) and SHADOW_PLANAR (orthographic): the frame's camera.
pub const SPECULAR_VIEW_CAMERA: u32 = 2;
/// Total internal reflection (or no exit) at the approximated second
/// interface of two-sided image-space refraction: Wyman 2006's three ad hoc
/// remedies (`tir_remedy` parameter of image_space).
pub const TIR_SINGLE_REFRACTION: u32 = 0;
pub const TIR_CLAMP_CRITICAL: u32 = 1;
pub const TIR_REFLECT: u32 = 2;
/// The second interface of what the camera sees through a closed
/// dielectric (`camera_exit` parameter): traced through the BVH, or
/// Wyman's two-sided image-space approximation.
pub const CAMERA_EXIT_TRACED: u32 = 0;
pub const CAMERA_EXIT_TWO_SIDED: u32 = 1;

// Camera refraction (src/passes/camera_refraction.rs,
// glsl/passes/camera_refraction.comp), descriptor set 1.
pub const REFRACTION_BINDING_OPAQUE_RADIANCE: u32 = 0;
pub const REFRACTION_BINDING_OPAQUE_POSITION: u32 = 1;
pub const REFRACTION_BINDING_FRONT_POSITION: u32 = 2;
pub const REFRACTION_BINDING_FRONT_NORMAL: u32 = 3;
pub const REFRACTION_BINDING_BACK_POSITION: u32 = 4;
pub const REFRACTION_BINDING_BACK_NORMAL: u32 = 5;
pub const REFRACTION_BINDING_RADIANCE: u32 = 6;

// Water surface pass (src/passes/water_surface.rs, glsl/passes/water_surface.comp), set 0.
pub const WATER_SURFACE_BINDING_WAVES: u32 = 0;
pub const WATER_SURFACE_BINDING_VERTICES: u32 = 1;
/// Workgroup side of the water surface pass (8 x 8 grid vertices).
pub const WATER_SURFACE_GROUP_SIZE: u32 = 8;

// Airlight pass (src/passes/airlight.rs, glsl/passes/airlight.comp), descriptor set 1.
pub const AIRLIGHT_BINDING_RADIANCE: u32 = 0;
pub const AIRLIGHT_BINDING_SHADOW_MAP: u32 = 1;
pub const AIRLIGHT_BINDING_SHADOW_LIGHTS: u32 = 2;
/// The virtual lights of the approximate multiple scattering (src/passes/scattered_lights.rs).
pub const AIRLIGHT_BINDING_SCATTERED_LIGHTS: u32 = 3;
// Ground truth (src/reference/, glsl/reference/), descriptor set 1.
/// Running sums over passes, COMPONENT_COUNT rgb images.
pub const REFERENCE_BINDING_TOTAL: u32 = 0;
/// This pass's radiance estimates, COMPONENT_COUNT rgb images, folded into
/// the sums (and cleared) at the end of every pass.
pub const REFERENCE_BINDING_PASS: u32 = 1;
pub const REFERENCE_BINDING_RADIANCE: u32 = 2;
/// Per pixel: sum and sum of squares of the pass estimates' luminance.
pub const REFERENCE_BINDING_MOMENTS: u32 = 3;
/// One visible point per pixel and pass (progressive photon mapping).
pub const REFERENCE_BINDING_VISIBLE_POINTS: u32 = 4;
/// Hash grid over the visible points: bucket heads, then one link per point.
pub const REFERENCE_BINDING_SURFACE_HEADS: u32 = 5;
pub const REFERENCE_BINDING_SURFACE_NEXT: u32 = 6;
/// Photons stored at medium collisions, their hash grid and its links.
pub const REFERENCE_BINDING_VOLUME_PHOTONS: u32 = 7;
pub const REFERENCE_BINDING_VOLUME_HEADS: u32 = 8;
pub const REFERENCE_BINDING_VOLUME_NEXT: u32 = 9;
/// Counters: [0] volume photons stored this pass (may pass the capacity),
/// [1] noise sum of the variance of the mean, [2] sum of the mean,
/// [3] gather points appended (may pass their capacity), [4..7] the volume
/// gather's dispatch arguments, [7] its longest cell walk.
pub const REFERENCE_BINDING_STATS: u32 = 10;
/// Points on camera paths in the medium where the volume photon map is gathered.
pub const REFERENCE_BINDING_GATHER_POINTS: u32 = 11;
/// The aim guide (glsl/reference/aim_guide.glsl): per point, spot and
/// directional light, what its aimed photons were useful for, by where they
/// were aimed, and the distribution the next pass aims by.
pub const REFERENCE_BINDING_AIM_GUIDE: u32 = 12;
/// The aim guide's grid over the aimed region's sample square: rows over
/// the radial coordinate, columns over the angle about the axis.
pub const REFERENCE_GUIDE_ROWS: u32 = 64;
pub const REFERENCE_GUIDE_COLUMNS: u32 = 32;
/// The camera chains split at up to this many of their first Fresnel
/// choices (glsl/reference/camera.comp, `ReferenceSettings::fresnel_splits`):
/// 2^splits visible points a pixel and pass, one per branch.
pub const REFERENCE_MAX_FRESNEL_SPLITS: u32 = 2;
/// End of a hash-grid chain.
pub const REFERENCE_GRID_NONE: u32 = 4294967295;
/// The volume gather stops a cell's chain after this many links (below
/// llvmpipe's 65535 loop iterations per invocation, past which every loop
/// of the invocation exits silently); a walk that reaches it is reported.
pub const REFERENCE_GATHER_WALK_LIMIT: u32 = 60000;
