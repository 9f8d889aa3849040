//! GPU-side layouts of the scene, shared with `glsl/common/scene.glsl`.
//! Every struct is made of 16-byte vectors only, so std430 and `#[repr(C)]`
//! agree without padding rules; the const assertions below pin sizes and
//! offsets, and the GLSL side mirrors the same field order.

use crate::scene::{
    Density, Emitter, EmitterShape, Light, LightKind, Material, MaterialKind, Medium, Scene,
    Triangle, Wave, Wrap,
};
use crate::shader_bindings as b;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};
use std::mem::{offset_of, size_of};

/// One world-space triangle in BVH leaf order; rasterised by vertex pulling
/// (gl_VertexIndex / 3) and traced by the BVH, so both see the same data.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuTriangle {
    /// xyz position of vertex 0; w = material index (uint bits).
    pub p0: [f32; 4],
    /// w = object index (uint bits).
    pub p1: [f32; 4],
    pub p2: [f32; 4],
    /// Vertex normals; w = Wyman's d_N for refractors (distance to the far
    /// side of the object along -N, `Bvh::set_normal_thickness`), else 0.
    pub n0: [f32; 4],
    pub n1: [f32; 4],
    pub n2: [f32; 4],
}

/// The texture coordinates of one triangle, in the same (leaf) order as the
/// triangle buffer but a buffer of their own (binding BINDING_TRIANGLE_UVS):
/// BVH traversal reads only `GpuTriangle`, and widening that to 128 bytes
/// would add a third to the memory every ray's intersection tests fetch, for
/// data only a diffuse hit's shading needs (once per hit, not per test).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuTriangleUv {
    /// xy: UV of vertex 0; zw: UV of vertex 1.
    pub uv01: [f32; 4],
    /// xy: UV of vertex 2; zw: unused.
    pub uv2: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuBvhNode {
    pub bounds_min: [f32; 3],
    /// Inner node: index of the left child (right = left + 1). Leaf: first triangle.
    pub left_or_first: u32,
    pub bounds_max: [f32; 3],
    /// 0 for an inner node, else the number of triangles in the leaf.
    pub count: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMaterial {
    /// rgb albedo / reflectance; w = kind (uint bits).
    pub color: [f32; 4],
    /// rgb extinction inside a dielectric (1/m): its absorption plus the
    /// scattering of the medium inside it (`Material::extinction`), which
    /// takes light out of a ray as surely as absorption does; w = ior.
    pub absorption_ior: [f32; 4],
    /// x = albedo texture layer in bits 0-15 and the wrap modes of u and v
    /// (WRAP_*) in bits 16-17 and 18-19 (int bits, -1: none); yz = uv_scale; w = alpha
    /// cutoff (0: opaque). A diffuse albedo is `color.rgb` times the layer at
    /// `uv * uv_scale`; where the layer's alpha is below the cutoff the
    /// surface is cut out.
    pub texture: [f32; 4],
    /// rgb radiance emitted from front faces (area lights' own material); w unused.
    pub emission: [f32; 4],
    /// rgb mirror reflectance of a `mixed` material's specular part (kind
    /// diffuse; 0 otherwise); w unused.
    pub specular: [f32; 4],
    /// rgb scattering coefficient (1/m) of the medium inside a dielectric
    /// (`Material::scattering`; 0: none); w = its Henyey-Greenstein g.
    pub scattering: [f32; 4],
}

/// An area light (glsl/common/scene.glsl `Emitter`): what the reference
/// samples photons from. Its geometry is ordinary triangles with an
/// emitting material.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuEmitter {
    /// xyz centre (triangle: vertex 0); w = kind (EMITTER_*, uint bits).
    pub position: [f32; 4],
    /// xyz unit normal (rect: the side it emits to; triangle: the edge to
    /// vertex 1); w = width (rect), radius (sphere) or area (triangle).
    pub normal: [f32; 4],
    /// xyz unit tangent, the direction of the width (rect; triangle: the
    /// edge to vertex 2); w = height (rect).
    pub tangent: [f32; 4],
    /// rgb radiance; w = power (luminance, W) for light selection.
    pub radiance: [f32; 4],
}

/// The environment light's constants, the head of the BINDING_ENVIRONMENT_DATA
/// buffer (its sampling tables follow, `emitters::sampling_tables`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuEnvironment {
    /// x = 1 when the scene has an environment; y unused; zw = cos, sin of
    /// the rotation about +y (image frame -> world).
    pub params: [f32; 4],
    /// xyz unit direction toward the sun (world); w = cos of its angular radius (2: no sun).
    pub sun: [f32; 4],
    /// rgb sun radiance (scaled); w = sun power (luminance, W: L Ω π R²).
    pub sun_radiance: [f32; 4],
    /// x width, y height of the table; z = table power (luminance, W:
    /// π R² ∫ L dω); w unused.
    pub table: [f32; 4],
    /// The sun found in an image's table (`emitters::extract_sun`), for
    /// `direct` only: xyz its peak texel's direction (world), w the cosine
    /// of the search cone (2: none).
    pub image_sun_peak: [f32; 4],
    /// xyz its mean direction toward the sun (world); w its luminance threshold.
    pub image_sun_direction: [f32; 4],
    /// rgb its irradiance on a surface facing it (W/m²); w unused.
    pub image_sun_irradiance: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLight {
    /// xyz position; w = kind (uint bits).
    pub position: [f32; 4],
    /// xyz unit direction light travels; w = cos(cone half-angle).
    pub direction: [f32; 4],
    /// rgb W/sr (point, spot) or W/m^2 (directional); w = cos(half-angle - falloff).
    pub intensity: [f32; 4],
    /// x = emitted power used to pick lights (W, luminance-weighted sum over rgb), yzw reserved.
    pub power: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMedium {
    /// rgb sigma_s (1/m); w = Henyey-Greenstein g.
    pub sigma_s: [f32; 4],
    /// rgb sigma_a (1/m); w = density kind (uint bits, DENSITY_NONE when no medium).
    pub sigma_a: [f32; 4],
    /// xyz bounds min; w = density scale (constant value, or noise scale).
    pub bounds_min: [f32; 4],
    /// xyz bounds max; w = maximum density (the majorant's multiplier).
    pub bounds_max: [f32; 4],
    /// xyz noise offset; w = noise frequency (1/m).
    pub noise: [f32; 4],
    /// xyz grid dimensions; w = noise octaves.
    pub dims: [u32; 4],
}

/// Per-frame constants (uniform buffer, binding BINDING_FRAME).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuFrame {
    pub view: [[f32; 4]; 4],
    pub proj: [[f32; 4]; 4],
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    /// xyz camera position; w = tan(fov_y / 2).
    pub eye: [f32; 4],
    /// x width, y height (pixels), z aspect, w animation time (s).
    pub viewport: [f32; 4],
    /// xyz centre, w radius of the scene's bounding sphere.
    pub scene_sphere: [f32; 4],
    /// x lights, y triangles, z materials, w frame index.
    pub counts: [u32; 4],
    /// x: the path-type components techniques draw, a bit mask
    /// (1 << COMPONENT_*; `Component::mask`); y: area lights; z: still
    /// frames accumulated before this one (`SceneGpu::still_frames`); w reserved.
    pub components: [u32; 4],
}

/// One Gerstner wave (glsl/common/water.glsl `Wave`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuWave {
    /// xy: unit travel direction D as (x, z); z: k = 2π/λ (rad/m); w: ω = k·speed (rad/s).
    pub direction_k_omega: [f32; 4],
    /// x: amplitude (m); y: steepness Q; z: phase (rad); w: unused.
    pub amplitude_steepness_phase: [f32; 4],
}

/// One evaluated water grid vertex (glsl/passes/water_surface.comp `WaterVertex`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuWaterVertex {
    /// xyz world position; w = 1.
    pub position: [f32; 4],
    /// xyz unit normal (+y side); w = 0.
    pub normal: [f32; 4],
}

const _: () = {
    assert!(size_of::<GpuWave>() == 32);
    assert!(offset_of!(GpuWave, amplitude_steepness_phase) == 16);
    assert!(size_of::<GpuWaterVertex>() == 32);
    assert!(offset_of!(GpuWaterVertex, normal) == 16);
    assert!(size_of::<GpuTriangle>() == 96);
    assert!(size_of::<GpuBvhNode>() == 32);
    assert!(offset_of!(GpuBvhNode, count) == 28);
    assert!(size_of::<GpuTriangleUv>() == 32);
    assert!(offset_of!(GpuTriangleUv, uv2) == 16);
    assert!(size_of::<GpuMaterial>() == 96);
    assert!(offset_of!(GpuMaterial, texture) == 32);
    assert!(offset_of!(GpuMaterial, emission) == 48);
    assert!(offset_of!(GpuMaterial, specular) == 64);
    assert!(size_of::<GpuEmitter>() == 64);
    assert!(size_of::<GpuEnvironment>() == 112);
    assert!(size_of::<GpuLight>() == 64);
    assert!(size_of::<GpuMedium>() == 96);
    assert!(offset_of!(GpuMedium, dims) == 80);
    assert!(size_of::<GpuFrame>() == 336);
    assert!(offset_of!(GpuFrame, eye) == 256);
    assert!(offset_of!(GpuFrame, counts) == 304);
    assert!(offset_of!(GpuFrame, components) == 320);
};

impl GpuWave {
    pub fn new(w: &Wave) -> Self {
        let d = w.direction();
        Self {
            direction_k_omega: [d.x, d.y, w.wavenumber(), w.angular_frequency()],
            amplitude_steepness_phase: [w.amplitude, w.steepness, w.phase, 0.0],
        }
    }
}

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

impl GpuTriangle {
    pub fn new(t: &Triangle) -> Self {
        let [p0, p1, p2] = t.positions;
        let [n0, n1, n2] = t.normals;
        Self {
            p0: v4(p0, f32::from_bits(t.material)),
            p1: v4(p1, f32::from_bits(t.object)),
            p2: v4(p2, 0.0),
            n0: v4(n0, 0.0),
            n1: v4(n1, 0.0),
            n2: v4(n2, 0.0),
        }
    }
}

impl GpuTriangleUv {
    pub fn new(t: &Triangle) -> Self {
        let [a, b, c] = t.uvs;
        Self {
            uv01: [a.x, a.y, b.x, b.y],
            uv2: [c.x, c.y, 0.0, 0.0],
        }
    }
}

impl GpuMaterial {
    pub fn new(m: &Material) -> Self {
        let kind = match m.kind {
            MaterialKind::Diffuse => b::MATERIAL_DIFFUSE,
            MaterialKind::Mirror => b::MATERIAL_MIRROR,
            MaterialKind::Dielectric => b::MATERIAL_DIELECTRIC,
            MaterialKind::ThinDielectric => b::MATERIAL_THIN_DIELECTRIC,
        };
        let wrap_code = |w: Wrap| match w {
            Wrap::Repeat => b::WRAP_REPEAT,
            Wrap::ClampToEdge => b::WRAP_CLAMP_TO_EDGE,
            Wrap::MirroredRepeat => b::WRAP_MIRRORED_REPEAT,
        };
        // The layer in bits 0-15 (the array holds far fewer), the wrap
        // modes above it; -1 (all bits) without a texture.
        let (layer, uv_scale, alpha_cutoff) = match m.texture {
            Some(t) if m.kind == MaterialKind::Diffuse => (
                (t.index | wrap_code(t.wrap[0]) << 16 | wrap_code(t.wrap[1]) << 18) as i32,
                t.uv_scale,
                t.alpha_cutoff,
            ),
            _ => (-1, glam::Vec2::ONE, 0.0),
        };
        Self {
            color: v4(m.color, f32::from_bits(kind)),
            absorption_ior: v4(m.extinction(), m.ior),
            texture: [
                f32::from_bits(layer as u32),
                uv_scale.x,
                uv_scale.y,
                alpha_cutoff,
            ],
            emission: v4(m.emission, 0.0),
            specular: v4(m.specular, 0.0),
            scattering: match m.scattering {
                Some(s) if m.kind == MaterialKind::Dielectric => v4(s.sigma_s, s.g),
                _ => [0.0; 4],
            },
        }
    }
}

impl GpuLight {
    /// `scene_radius` is the radius of the scene's bounding sphere: a directional
    /// light's photons leave a disk of that radius, so its power is E * pi * R^2.
    pub fn new(l: &Light, scene_radius: f32) -> Self {
        let kind = match l.kind {
            LightKind::Point => b::LIGHT_POINT,
            LightKind::Spot => b::LIGHT_SPOT,
            LightKind::Directional => b::LIGHT_DIRECTIONAL,
        };
        let outer = l.cone_angle_deg.to_radians();
        let inner = (l.cone_angle_deg - l.cone_falloff_deg)
            .max(0.0)
            .to_radians();
        let (cos_outer, cos_inner) = match l.kind {
            // A rect light's stand-in: the cosine profile (spot_falloff).
            LightKind::Spot if l.cone_falloff_deg < 0.0 => (0.0, 2.0),
            LightKind::Spot => (outer.cos(), inner.cos()),
            _ => (-1.0, -1.0),
        };
        Self {
            position: v4(l.position, f32::from_bits(kind)),
            direction: v4(l.direction.normalize_or_zero(), cos_outer),
            intensity: v4(l.intensity, cos_inner),
            power: [
                crate::radiometry::light_power(l, scene_radius).dot(crate::radiometry::LUMINANCE),
                0.0,
                0.0,
                0.0,
            ],
        }
    }
}

impl GpuEmitter {
    /// Every triangle of `triangles` (world space) whose material emits and
    /// that is not an area light's own geometry (which its rect or sphere
    /// record samples): an EMITTER_TRIANGLE record of power π L A, emitting
    /// from its front face (the side `cross(p1 - p0, p2 - p0)` points to, as
    /// `hit_geometric_normal`).
    pub fn emissive_triangles(scene: &Scene, triangles: &[Triangle]) -> Vec<Self> {
        triangles
            .iter()
            .filter(|t| !scene.emitters.iter().any(|e| e.object == t.object))
            .filter_map(|t| {
                let l = scene.materials.get(t.material as usize)?.emission;
                let [p0, p1, p2] = t.positions;
                let area = 0.5 * (p1 - p0).cross(p2 - p0).length();
                (l.max_element() > 0.0 && area > 0.0).then(|| Self {
                    position: v4(p0, f32::from_bits(b::EMITTER_TRIANGLE)),
                    normal: v4(p1 - p0, area),
                    tangent: v4(p2 - p0, 0.0),
                    radiance: v4(
                        l,
                        (l * std::f32::consts::PI * area).dot(crate::radiometry::LUMINANCE),
                    ),
                })
            })
            .collect()
    }

    pub fn new(e: &Emitter) -> Self {
        let power = crate::emitters::emitter_power(e).dot(crate::radiometry::LUMINANCE);
        let radiance = v4(e.radiance, power);
        match e.shape {
            EmitterShape::Rect {
                center,
                normal,
                tangent,
                size,
            } => Self {
                position: v4(center, f32::from_bits(b::EMITTER_RECT)),
                normal: v4(normal, size[0]),
                tangent: v4(tangent, size[1]),
                radiance,
            },
            EmitterShape::Sphere { center, radius } => Self {
                position: v4(center, f32::from_bits(b::EMITTER_SPHERE)),
                normal: v4(Vec3::Y, radius),
                tangent: v4(Vec3::X, 0.0),
                radiance,
            },
        }
    }
}

impl GpuMedium {
    pub fn none() -> Self {
        let mut m = Self::zeroed();
        m.sigma_a[3] = f32::from_bits(b::DENSITY_NONE);
        m
    }

    pub fn new(m: &Medium) -> Self {
        let (kind, scale, noise, dims) = match &m.density {
            Density::Constant(d) => (b::DENSITY_CONSTANT, *d, Vec4::ZERO, [0; 4]),
            Density::Noise {
                scale,
                frequency,
                octaves,
                offset,
            } => (
                b::DENSITY_NOISE,
                *scale,
                offset.extend(*frequency),
                [0, 0, 0, *octaves],
            ),
            Density::Grid { dims, .. } => (
                b::DENSITY_GRID,
                1.0,
                Vec4::ZERO,
                [dims[0], dims[1], dims[2], 0],
            ),
        };
        Self {
            sigma_s: v4(m.sigma_s, m.g),
            sigma_a: v4(m.sigma_a, f32::from_bits(kind)),
            bounds_min: v4(m.bounds_min, scale),
            bounds_max: v4(m.bounds_max, m.max_density()),
            noise: noise.to_array(),
            dims,
        }
    }
}

impl GpuFrame {
    pub fn mat(m: Mat4) -> [[f32; 4]; 4] {
        m.to_cols_array_2d()
    }
}
