//! The resolved scene model: what a parsed and validated scene file becomes.
//! Everything here is in world units (metres) and the shared radiometry
//! (docs/SCENES.md, GUIDE §2): point/spot intensity in W/sr, directional
//! irradiance in W/m^2, media coefficients in 1/m.

use glam::{Mat4, Vec2, Vec3};
use std::path::PathBuf;

#[derive(Clone, Debug)]
pub struct Scene {
    /// The file the scene was read from (relative paths inside it resolve against its folder).
    pub source: PathBuf,
    pub camera: Camera,
    pub lights: Vec<Light>,
    pub materials: Vec<Material>,
    pub objects: Vec<Object>,
    pub medium: Option<Medium>,
    pub output: Output,
    /// The environment light (`kind = "environment"`), at most one.
    pub environment: Option<Environment>,
    /// Area lights (`kind = "rect"`, `"sphere"`), in file order. Each also
    /// has an object (its geometry, so it is seen and casts shadows) and a
    /// material (black, emitting `radiance` from its front faces) appended
    /// after the file's: `Emitter::object` and `Emitter::material`.
    pub emitters: Vec<Emitter>,
    /// Decoded albedo textures (`AlbedoTexture::index` points here), one per
    /// distinct file.
    pub textures: Vec<Texture>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightKind {
    Point,
    Spot,
    Directional,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub kind: LightKind,
    /// Position (point, spot). Unused for directional lights.
    pub position: Vec3,
    /// Unit vector: the way light travels (spot axis, directional direction).
    pub direction: Vec3,
    /// W/sr per channel for point and spot lights; W/m^2 (irradiance on a
    /// surface facing the light) for directional lights.
    pub intensity: Vec3,
    /// Spot only: half-angle of the cone in degrees (zero intensity outside).
    pub cone_angle_deg: f32,
    /// Spot only: width in degrees of the smooth edge inside the cone over
    /// which intensity falls from full to zero.
    pub cone_falloff_deg: f32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialKind {
    Diffuse,
    Mirror,
    Dielectric,
    /// A thin dielectric sheet (a window pane, glTF thin-walled
    /// transmission): Fresnel at both faces, the inter-reflections between
    /// them summed, no net deflection (`radiometry::thin_sheet_reflectance`).
    ThinDielectric,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// A `mixed` material (docs/SCENES.md) is `Diffuse` with a non-zero
    /// `specular`: every pass that knows only diffuse surfaces renders its
    /// diffuse part.
    pub kind: MaterialKind,
    /// Diffuse: albedo. Mirror: reflectance per channel. Dielectric: unused (1).
    pub color: Vec3,
    /// Dielectric, thin dielectric: index of refraction (>= 1). Others: 1.
    pub ior: f32,
    /// Dielectric: Beer-Lambert absorption coefficient inside, 1/m. Others: 0.
    pub absorption: Vec3,
    /// Diffuse only: the albedo is `color` times this texture at the
    /// surface's UV (docs/SCENES.md, "Albedo textures").
    pub texture: Option<AlbedoTexture>,
    /// Radiance (W m^-2 sr^-1) emitted from the front faces (the side the
    /// geometric normal points to): non-zero on an area light's own
    /// material (black diffuse, `Emitter`) and on a glTF emissive diffuse
    /// material, whose every triangle is then an area light of its own
    /// (`GpuEmitter::emissive_triangles`).
    pub emission: Vec3,
    /// Diffuse only: the mirror reflectance per channel of a `mixed`
    /// material's specular part (a perfect mirror reflection added to the
    /// Lambertian `color`; `color + specular` <= 1 per channel). 0 for a
    /// plain diffuse surface and for other kinds.
    pub specular: Vec3,
    /// Dielectric only: the participating medium that fills its inside
    /// (turbid water, milky glass) scatters with this; its absorption is
    /// `absorption`. None: the inside only absorbs.
    pub scattering: Option<Scattering>,
}

/// Scattering inside a dielectric (docs/SCENES.md, "A medium inside a
/// dielectric"): homogeneous, with a Henyey-Greenstein phase.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scattering {
    /// Scattering coefficient per channel, 1/m (> 0 in some channel).
    pub sigma_s: Vec3,
    /// Henyey-Greenstein asymmetry, in (-1, 1).
    pub g: f32,
}

impl Material {
    /// A `mixed` material: diffuse with a mirror part (`specular` > 0).
    pub fn is_mixed(&self) -> bool {
        self.kind == MaterialKind::Diffuse && self.specular.max_element() > 0.0
    }

    /// What a ray loses per metre inside (1/m): the absorption plus the
    /// scattering of a medium there (light scattered out of the ray).
    pub fn extinction(&self) -> Vec3 {
        self.absorption + self.scattering.map_or(Vec3::ZERO, |s| s.sigma_s)
    }

    /// A dielectric whose inside scatters (`scattering`).
    pub fn holds_medium(&self) -> bool {
        self.kind == MaterialKind::Dielectric && self.scattering.is_some()
    }
}

/// An environment light: radiance arriving from every direction at
/// infinity (docs/SCENES.md, "Environment light").
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    pub kind: EnvironmentKind,
    /// Radiance multiplier.
    pub scale: f32,
    /// Rotation about +y in degrees (right-handed) from the image's frame to
    /// the world. A sky's sun direction is stored already rotated.
    pub rotate_deg: f32,
}

#[derive(Clone, Debug, PartialEq)]
pub enum EnvironmentKind {
    /// An equirectangular image of linear radiance (`Texture::texels`):
    /// u = φ / 2π (φ from +x toward +z), v = θ / π (θ from +y), row 0 at +y.
    Image(Texture),
    Sky(Sky),
}

/// A sun disc plus a sky gradient (docs/SCENES.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sky {
    /// Unit vector from the scene toward the sun's centre, world space
    /// (after `rotate`).
    pub sun_direction: Vec3,
    /// Angular radius α of the sun disc, degrees.
    pub sun_radius_deg: f32,
    /// Radiance of the disc, W m^-2 sr^-1.
    pub sun_radiance: Vec3,
    /// Sky radiance straight up and at (and below) the horizon; in between
    /// linear in the sine of the elevation.
    pub zenith: Vec3,
    pub horizon: Vec3,
}

/// An area light's shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EmitterShape {
    /// A one-sided Lambertian rectangle emitting to the side of `normal`;
    /// `tangent` (unit, perpendicular to `normal`) is the direction of the
    /// `size[0]` side.
    Rect {
        center: Vec3,
        normal: Vec3,
        tangent: Vec3,
        size: [f32; 2],
    },
    /// A Lambertian sphere emitting outward from every point.
    Sphere { center: Vec3, radius: f32 },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    pub shape: EmitterShape,
    /// W m^-2 sr^-1.
    pub radiance: Vec3,
    /// Index of its geometry in `Scene::objects`.
    pub object: u32,
    /// Index of its material in `Scene::materials`.
    pub material: u32,
}

/// A diffuse material's albedo texture: which one and how often it repeats.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlbedoTexture {
    /// Index into `Scene::textures`.
    pub index: u32,
    /// The lookup is at `uv * uv_scale` (repeat wrap), so `uv_scale` = (4, 4)
    /// tiles a [0, 1]² face four times each way.
    pub uv_scale: Vec2,
    /// Cut-out threshold (glTF `alphaMode = MASK`): where the texture's
    /// alpha is below it the surface is absent from every pass (camera and
    /// shadow rasterisation, every traced ray). 0: opaque.
    pub alpha_cutoff: f32,
    /// How u and v outside [0, 1] (after `uv_scale`) map into the texture
    /// (glTF sampler `wrapS`, `wrapT`; TOML and MTL textures repeat).
    pub wrap: [Wrap; 2],
}

/// A texture's wrap mode along one axis (glTF sampler `wrapS`/`wrapT`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    /// fract(u): tiles.
    #[default]
    Repeat,
    /// clamp(u, 0, 1): the edge texels extend.
    ClampToEdge,
    /// Every other tile mirrored: 1 - |1 - (u mod 2)|.
    MirroredRepeat,
}

/// A decoded image: linear RGB per texel (8-bit files decoded from sRGB,
/// EXR taken as linear), rows top to bottom. UV (0, 0) is the top-left
/// corner, the OBJ `vt` (0, 0) the bottom-left: see docs/SCENES.md.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 3]>,
    /// Coverage per texel (stored linearly, never sRGB-decoded), or empty
    /// when the file has no alpha channel (opaque).
    pub alpha: Vec<f32>,
}

/// Triangle geometry in an object's local space.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    /// One normal per position (computed when the source has none).
    pub normals: Vec<Vec3>,
    /// One texture coordinate per position, or empty (all zero then).
    pub uvs: Vec<Vec2>,
    pub indices: Vec<[u32; 3]>,
    /// Scene material index per triangle.
    pub materials: Vec<u32>,
}

#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Animation {
    /// Spin about `spin_axis` (through the object's origin after scale/rotate) in degrees per second.
    pub spin_deg_per_s: f32,
    pub spin_axis: Vec3,
    /// Orbit about `orbit_center` around the world y axis: radius (m) and degrees per second.
    pub orbit_center: Vec3,
    pub orbit_radius: f32,
    pub orbit_deg_per_s: f32,
    /// Vertical bob: amplitude (m) and frequency (Hz).
    pub bob_amplitude: f32,
    pub bob_hz: f32,
}

#[derive(Clone, Debug)]
pub struct Object {
    pub name: String,
    pub mesh: Mesh,
    /// Static placement (translate/rotate/scale from the file), local -> world.
    pub transform: Mat4,
    pub animation: Option<Animation>,
    /// A `water` object's surface: `mesh` then holds its tessellation at
    /// time 0, and `Scene::triangles(t)` re-tessellates it at `t`
    /// (src/scene/water.rs). Water has no transform or animation of its own.
    pub water: Option<Water>,
}

/// One Gerstner wave of a water surface (docs/SCENES.md, src/scene/water.rs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wave {
    /// Crest height above the still surface, m.
    pub amplitude: f32,
    /// Crest-to-crest distance, m (> 0).
    pub wavelength: f32,
    /// Travel direction in degrees, counter-clockwise seen from +y, 0 = +x,
    /// 90 = -z (the `animate` orbit's convention).
    pub direction_deg: f32,
    /// Gerstner steepness Q in [0, 1]: horizontal displacement Q A D cos θ
    /// (0: a plain sine wave).
    pub steepness: f32,
    /// Phase speed, m/s (>= 0): ω = 2π/λ · speed.
    pub speed: f32,
    /// Phase offset φ, radians.
    pub phase: f32,
}

/// A heightfield of water over an x/z rectangle, displaced by a sum of
/// Gerstner waves.
#[derive(Clone, Debug, PartialEq)]
pub struct Water {
    /// Middle of the rectangle, (x, z), m.
    pub center: Vec2,
    /// Extent along x and z, m (> 0).
    pub size: Vec2,
    /// Grid cells along x and z: (nx + 1)(nz + 1) vertices, 2 nx nz triangles.
    pub resolution: [u32; 2],
    /// Height (y) of the still surface, m.
    pub base_height: f32,
    /// Scene material index of every triangle.
    pub material: u32,
    pub waves: Vec<Wave>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Density {
    /// Uniform density multiplier.
    Constant(f32),
    /// Procedural fractal value noise in [0, 1] scaled by `scale`:
    /// density(x) = scale * fbm(x * frequency + offset) (glsl/common/medium.glsl).
    Noise {
        scale: f32,
        frequency: f32,
        octaves: u32,
        offset: Vec3,
    },
    /// A grid of densities over the medium bounds, x fastest, trilinear.
    Grid { dims: [u32; 3], values: Vec<f32> },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    pub sigma_s: Vec3,
    pub sigma_a: Vec3,
    pub g: f32,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
    pub density: Density,
    /// The real-time techniques add an approximate multiple scattering
    /// (light scattered twice in the medium, or scattered and then
    /// reflected by a surface: src/passes/scattered_lights.rs); the reference
    /// always renders all of it.
    pub multiple_scattering: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output {
    /// Exposure multiplier applied to radiance before the tonemap of PNG output.
    pub exposure: f32,
}

/// A world-space triangle as the renderer consumes it (raster and BVH).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub positions: [Vec3; 3],
    pub normals: [Vec3; 3],
    pub uvs: [Vec2; 3],
    pub material: u32,
    pub object: u32,
}
