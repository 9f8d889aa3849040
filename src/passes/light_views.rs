//! Light views: each light's viewpoint of the specular objects and their
//! light-space front/back G-buffer, drawn once per light and frame for
//! every consumer (the caustic map's photons, volume_lines' light rays, and
//! any later technique that shoots light through the specular objects).
//!
//! A light's view is an N x N texel grid fitted to the bounding sphere of
//! the specular objects: a perspective frustum from a point or spot light,
//! an orthographic box along a directional light. Texel (i, j) of the grid
//! is texel (i, j) of the rasterised G-buffer (`photon_view_proj`), so a
//! compute pass with one thread per texel reads its own G-buffer texel.
//!
//! `LightViews::record` is the one per-light loop "light-view G-buffer ->
//! the consumers' passes": each consumer records its compute and raster
//! passes for a light right after that light's G-buffer is drawn (drawn
//! only if some consumer reads it), so consumers of the same resolution
//! share one G-buffer and one draw per light.

use crate::frame::SceneGpu;
use crate::passes::specular_gbuffer::{SpecularGBuffer, Viewpoint};
use crate::scene::{Light, LightKind, MaterialKind, Scene};
use crate::shader_bindings as b;
use crate::vk::{Context, FrameRecorder, VkResult};
use glam::{Mat4, Vec3};
use std::sync::Arc;

/// One light's view of the specular objects, as the shaders take it (the
/// first four vec4 of photons.comp's and segments.comp's push constants):
/// `origin.w` the half extent (tan of the half angle, or metres),
/// `right.w` the light index, `up.w` the grid size, `forward.w` the kind
/// (`SHADOW_RADIAL` perspective, `SHADOW_PLANAR` orthographic), all as
/// f32 bits where integers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightView {
    pub origin: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub forward: [f32; 4],
}

impl LightView {
    pub fn orthographic(&self) -> bool {
        self.forward[3].to_bits() == b::SHADOW_PLANAR
    }

    /// The rasteriser's viewpoint of the same texel grid (specular G-buffer).
    pub fn viewpoint(&self, specular: (Vec3, f32)) -> Viewpoint {
        Viewpoint::Light {
            view_proj: photon_view_proj(self, specular),
            origin: Vec3::from_slice(&self.origin[..3]),
            forward: Vec3::from_slice(&self.forward[..3]),
            orthographic: self.orthographic(),
        }
    }
}

/// The light-space view of `light` fitted to the sphere `(centre,
/// radius)` around the specular objects, at `size` texels; `None` when a
/// point or spot light sits inside the sphere (no frustum can hold it).
pub fn photon_view(
    light: &Light,
    light_index: u32,
    specular: (Vec3, f32),
    size: u32,
) -> Option<LightView> {
    let (centre, radius) = specular;
    let (origin, forward, half, mode) = match light.kind {
        LightKind::Directional => {
            let f = light.direction.normalize_or(Vec3::NEG_Y);
            let extent = radius * 1.01;
            (centre - f * (2.0 * extent), f, extent, b::SHADOW_PLANAR)
        }
        LightKind::Point | LightKind::Spot => {
            let to = centre - light.position;
            let d = to.length();
            if d <= radius * 1.0001 {
                return None;
            }
            let alpha = ((radius / d).asin() * 1.01).min(1.5);
            (light.position, to / d, alpha.tan(), b::SHADOW_RADIAL)
        }
    };
    let up0 = if forward.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    let right = forward.cross(up0).normalize();
    let up = right.cross(forward);
    Some(LightView {
        origin: origin.extend(half).to_array(),
        right: right.extend(f32::from_bits(light_index)).to_array(),
        up: up.extend(f32::from_bits(size)).to_array(),
        forward: forward.extend(f32::from_bits(mode)).to_array(),
    })
}

/// World -> clip of a light view (rasteriser's view of the same texel grid:
/// texel (i, j) of the raster is photon (i, j)), for specular objects in
/// the sphere `specular`.
pub fn photon_view_proj(v: &LightView, specular: (Vec3, f32)) -> Mat4 {
    let origin = Vec3::from_slice(&v.origin[..3]);
    let forward = Vec3::from_slice(&v.forward[..3]);
    let up = Vec3::from_slice(&v.up[..3]);
    let h = v.origin[3];
    let (centre, radius) = specular;
    let view = Mat4::look_at_rh(origin, origin + forward, up);
    let proj = if v.orthographic() {
        let far = (centre - origin).dot(forward) + 2.0 * radius;
        Mat4::orthographic_rh(-h, h, -h, h, 0.0, far)
    } else {
        let d = (centre - origin).length();
        let far = d + 1.05 * radius;
        let near = (d - 1.05 * radius).max(far * 1e-4);
        Mat4::perspective_rh(2.0 * h.atan(), 1.0, near, far)
    };
    proj * view
}

/// Bounding sphere of every non-diffuse triangle of `scene` at time 0.
pub fn specular_bounds(scene: &Scene) -> Option<(Vec3, f32)> {
    let mut lo = Vec3::splat(f32::MAX);
    let mut hi = Vec3::splat(f32::MIN);
    let mut any = false;
    for t in scene.triangles(0.0) {
        let kind = scene.materials.get(t.material as usize).map(|m| m.kind);
        if matches!(kind, Some(MaterialKind::Diffuse) | None) {
            continue;
        }
        any = true;
        for p in t.positions {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    any.then(|| ((lo + hi) * 0.5, ((hi - lo) * 0.5).length().max(1e-4)))
}

/// What a consumer of the light views records per light.
pub trait LightViewConsumer {
    /// Whether its passes read the light-space G-buffer (else it is not
    /// drawn for this consumer; its images stay bound in GENERAL layout).
    fn reads_gbuffer(&self) -> bool;

    /// Records this consumer's passes for light `light` seen through
    /// `view`, after `gbuffer` holds that view (when any consumer reads it).
    fn record_light(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        light: usize,
        view: &LightView,
        gbuffer: &SpecularGBuffer,
    );
}

/// Every light's view of the specular objects at one resolution, and the
/// specular G-buffer they are drawn into (one light at a time).
pub struct LightViews {
    /// Front/back faces of the specular objects from the light being
    /// recorded, `size` x `size`.
    pub gbuffer: SpecularGBuffer,
    pub size: u32,
    lights: Vec<Light>,
    specular: Option<(Vec3, f32)>,
}

impl LightViews {
    /// Views of `size`^2 texels of the scene's first `MAX_LIGHTS` lights,
    /// stand-ins included.
    pub fn new(
        ctx: &Arc<Context>,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        size: u32,
    ) -> VkResult<Self> {
        Ok(Self {
            gbuffer: SpecularGBuffer::new(ctx, &scene_gpu.layout, size, size)?,
            size,
            // With the stand-ins of the environment's sun and the rect
            // lights (`frame::caustic_lights`, the GPU light buffer's order).
            lights: crate::frame::caustic_lights(scene),
            specular: specular_bounds(scene),
        })
    }

    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// The specular objects' bounding sphere (None: there are none).
    pub fn specular(&self) -> Option<(Vec3, f32)> {
        self.specular
    }

    /// The view of light `l` (None: no specular objects, or a point light
    /// inside their bounding sphere).
    pub fn view(&self, l: usize) -> Option<LightView> {
        photon_view(&self.lights[l], l as u32, self.specular?, self.size)
    }

    /// The scene's lights moved (same count and kinds): the next `record`
    /// views them from the new places. False if the lights cannot be taken
    /// in place (the technique is rebuilt then).
    pub fn set_lights(&mut self, lights: &[Light]) -> bool {
        if lights.len() != self.lights.len()
            || lights
                .iter()
                .zip(&self.lights)
                .any(|(a, b)| a.kind != b.kind)
        {
            return false;
        }
        self.lights.copy_from_slice(lights);
        true
    }

    /// The per-light loop: for every light with a view, "light view" (the
    /// specular G-buffer, if a consumer reads it), then each consumer's
    /// passes in order.
    pub fn record(
        &self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        consumers: &mut [&mut dyn LightViewConsumer],
    ) {
        let draw = consumers.iter().any(|c| c.reads_gbuffer());
        for l in 0..self.lights.len() {
            let Some(view) = self.view(l) else {
                if self.specular.is_some() {
                    log::warn!(
                        "light {l} lies inside the specular objects' bounds: no caustics from it"
                    );
                }
                continue;
            };
            if draw {
                let viewpoint = view.viewpoint(self.specular.unwrap_or_default());
                // Overwritten entirely; the barriers wait for the previous
                // light's readers.
                self.gbuffer.record(rec, "light view", scene, &viewpoint);
            }
            for c in consumers.iter_mut() {
                c.record_light(rec, scene, l, &view, &self.gbuffer);
            }
        }
    }
}
