//! Shadow maps for every light of the scene, rendered from the light each
//! frame, plus the per-light view matrices the readers project with.
//!
//! Storage: one 2D-array R32F image with `SHADOW_LAYERS_PER_LIGHT` (6) layers
//! per light, light l owning layers 6l..6l+5, so one descriptor binds every
//! map. A texel stores a *linear* distance, never a raster depth:
//! - point light (and a spot wider than `SPOT_CUBE_THRESHOLD_DEG`): a cube of
//!   six 90° perspective views (+x -x +y -y +z -z), distance |x - light|;
//! - spot light: one perspective view on the axis with fov = 2 x cone angle,
//!   distance |x - light|;
//! - directional light: one orthographic view fitted to the scene's bounding
//!   sphere, depth along the light direction from the ortho near plane.
//!
//! Texels nothing covers hold `SHADOW_CLEAR` (lit). A D32 attachment (one
//! layer, reused view after view) does the raster depth test.
//!
//! Readers use `glsl/common/shadow.glsl` (`shadow_visibility`) with
//! `ShadowMaps::map` bound as a sampled 2D array and `ShadowMaps::lights` as a
//! uniform buffer of `GpuShadowLight[MAX_LIGHTS]`. The bias is documented
//! there.

use crate::frame::SceneGpu;
use crate::scene::{Light, LightKind};
use crate::shader_bindings as b;
use crate::vk::{
    Access, Buffer, BufferUsage, Context, DescriptorSetLayout, FrameRecorder, GraphicsPipeline,
    GraphicsPipelineDesc, Image, ImageDesc, VkResult,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use std::mem::size_of;
use std::sync::Arc;

pub const DISTANCE_FORMAT: vk::Format = vk::Format::R32_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
/// What an uncovered texel holds: farther than anything, so always lit.
pub const SHADOW_CLEAR: f32 = 1e30;
/// A spot whose cone half-angle exceeds this gets a full cube like a point
/// light: one perspective view of fov 2 x angle would waste most of its
/// texels near the rim (and cannot reach 180°).
pub const SPOT_CUBE_THRESHOLD_DEG: f32 = 60.0;

/// One light's shadow views, mirrored by `ShadowLight` in glsl/common/shadow.glsl (std140).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuShadowLight {
    /// World -> clip of each view (only the first `info.y` are used).
    pub view_proj: [[[f32; 4]; 4]; 6],
    /// xyz: light position (radial) or the ortho view's eye (planar);
    /// w: world size of one texel, per metre of distance (radial) or in metres (planar).
    pub origin: [f32; 4],
    /// xyz: unit light direction (planar depth axis); w reserved.
    pub direction: [f32; 4],
    /// x: SHADOW_RADIAL or SHADOW_PLANAR; y: views (1 or 6); z: first layer; w reserved.
    pub info: [u32; 4],
}

const _: () = {
    assert!(size_of::<GpuShadowLight>() == 432);
    assert!(size_of::<GpuShadowLight>() % 16 == 0);
    assert!(std::mem::offset_of!(GpuShadowLight, origin) == 384);
    assert!(std::mem::offset_of!(GpuShadowLight, info) == 416);
};

/// Push constants of glsl/passes/shadow.vert/.frag: one view.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ShadowPush {
    view_proj: [[f32; 4]; 4],
    /// xyz origin; w: mode (uint bits).
    origin: [f32; 4],
    direction: [f32; 4],
}

/// Face directions and up vectors of a cube map's six views. Any consistent
/// set works: readers pick the face by the major axis in the same order and
/// project with the stored matrix.
const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::NEG_Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::NEG_Z),
    (Vec3::Z, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_Y),
];

/// An up vector not parallel to `dir`.
fn up_for(dir: Vec3) -> Vec3 {
    if dir.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}

/// The shadow views of `light` for a scene inside `sphere`, at `size` texels,
/// its maps starting at layer `first_layer`.
pub fn shadow_views(
    light: &Light,
    sphere: (Vec3, f32),
    size: u32,
    first_layer: u32,
) -> GpuShadowLight {
    let (centre, radius) = sphere;
    let radius = radius.max(1e-3);
    let dir = light.direction.normalize_or(Vec3::NEG_Y);
    let mut out = GpuShadowLight::zeroed();
    match light.kind {
        LightKind::Point | LightKind::Spot => {
            let pos = light.position;
            // The farthest scene point, with a margin; near small against it
            // (the stored value is linear distance, so depth precision only
            // decides raster ordering).
            let far = ((pos - centre).length() + radius) * 1.01;
            let near = (far * 1e-3).max(1e-4);
            let cube =
                light.kind == LightKind::Point || light.cone_angle_deg > SPOT_CUBE_THRESHOLD_DEG;
            let half_fov = if cube {
                45f32.to_radians()
            } else {
                light.cone_angle_deg.to_radians().max(1e-3)
            };
            let proj = Mat4::perspective_rh(2.0 * half_fov, 1.0, near, far);
            if cube {
                for (i, (face, up)) in CUBE_FACES.iter().enumerate() {
                    let view = Mat4::look_at_rh(pos, pos + *face, *up);
                    out.view_proj[i] = (proj * view).to_cols_array_2d();
                }
            } else {
                let view = Mat4::look_at_rh(pos, pos + dir, up_for(dir));
                out.view_proj[0] = (proj * view).to_cols_array_2d();
            }
            // A texel spans 2 tan(half_fov) / size in the view's tan plane:
            // at most that many metres per metre of distance.
            let texel = 2.0 * half_fov.tan() / size as f32;
            out.origin = pos.extend(texel).to_array();
            out.direction = dir.extend(0.0).to_array();
            out.info = [b::SHADOW_RADIAL, if cube { 6 } else { 1 }, first_layer, 0];
        }
        LightKind::Directional => {
            let margin = 0.01 * radius;
            let extent = radius + margin;
            let eye = centre - dir * extent;
            let view = Mat4::look_at_rh(eye, centre, up_for(dir));
            let proj = Mat4::orthographic_rh(-extent, extent, -extent, extent, 0.0, 2.0 * extent);
            out.view_proj[0] = (proj * view).to_cols_array_2d();
            out.origin = eye.extend(2.0 * extent / size as f32).to_array();
            out.direction = dir.extend(0.0).to_array();
            out.info = [b::SHADOW_PLANAR, 1, first_layer, 0];
        }
    }
    out
}

pub struct ShadowMaps {
    /// Linear distances, `SHADOW_LAYERS_PER_LIGHT` layers per light (R32F,
    /// colour attachment + sampled + storage).
    pub map: Image,
    /// `GpuShadowLight[MAX_LIGHTS]`, host-visible uniform buffer.
    pub lights: Buffer,
    pub size: u32,
    depth: Image,
    scene_lights: Vec<Light>,
    pipeline: GraphicsPipeline,
}

impl ShadowMaps {
    /// Maps of `size` x `size` texels for the first `MAX_LIGHTS` of `lights`
    /// (the scene loader rejects more; extra lights would get no map).
    pub fn new(
        ctx: &Arc<Context>,
        scene_layout: &DescriptorSetLayout,
        lights: &[Light],
        size: u32,
    ) -> VkResult<Self> {
        if lights.len() > b::MAX_LIGHTS as usize {
            log::warn!(
                "{} lights: only the first {} get shadow maps",
                lights.len(),
                b::MAX_LIGHTS
            );
        }
        let scene_lights: Vec<Light> = lights
            .iter()
            .take(b::MAX_LIGHTS as usize)
            .copied()
            .collect();
        let layers = b::SHADOW_LAYERS_PER_LIGHT * (scene_lights.len() as u32).max(1);
        let map = Image::new(
            ctx,
            "shadow maps (distance)",
            ImageDesc {
                width: size,
                height: size,
                layers,
                format: DISTANCE_FORMAT,
                usage: vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::STORAGE,
            },
        )?;
        let depth = Image::new(
            ctx,
            "shadow depth",
            ImageDesc::new_2d(
                size,
                size,
                DEPTH_FORMAT,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            ),
        )?;
        let lights_buf = Buffer::new(
            ctx,
            "shadow lights",
            (size_of::<GpuShadowLight>() * b::MAX_LIGHTS as usize) as u64,
            BufferUsage::Uniform,
        )?;
        let mut desc = GraphicsPipelineDesc::new("passes/shadow.vert", "passes/shadow.frag");
        desc.color_formats = vec![DISTANCE_FORMAT];
        desc.depth_format = Some(DEPTH_FORMAT);
        desc.depth_test = true;
        desc.depth_write = true;
        // Two-sided: both faces occlude.
        desc.cull = vk::CullModeFlags::NONE;
        desc.push_size = size_of::<ShadowPush>() as u32;
        let pipeline = GraphicsPipeline::new(ctx, &desc, &[scene_layout])?;
        Ok(Self {
            map,
            lights: lights_buf,
            size,
            depth,
            scene_lights,
            pipeline,
        })
    }

    /// Moves the lights (same count and kinds as at creation: the maps keep
    /// their layers); the views are recomputed when the pass is recorded.
    /// Returns false, changing nothing, when the light list differs otherwise.
    pub fn set_lights(&mut self, lights: &[Light]) -> bool {
        let n = lights.len().min(b::MAX_LIGHTS as usize);
        if n != self.scene_lights.len()
            || lights.len() > b::MAX_LIGHTS as usize
            || lights
                .iter()
                .zip(&self.scene_lights)
                .any(|(a, b)| a.kind != b.kind)
        {
            return false;
        }
        self.scene_lights.copy_from_slice(&lights[..n]);
        true
    }

    /// The views of every light for the scene's current bounding sphere.
    pub fn views(&self, sphere: (Vec3, f32)) -> Vec<GpuShadowLight> {
        self.scene_lights
            .iter()
            .enumerate()
            .map(|(l, light)| {
                shadow_views(
                    light,
                    sphere,
                    self.size,
                    l as u32 * b::SHADOW_LAYERS_PER_LIGHT,
                )
            })
            .collect()
    }

    /// Records the pass "shadow maps": every view of every light.
    pub fn record(&self, rec: &mut FrameRecorder, scene: &SceneGpu) -> VkResult<()> {
        let views = self.views(scene.sphere);
        // Through the frame's upload ring: earlier frames may still read the buffer.
        rec.upload(&self.lights, bytemuck::cast_slice(&views));
        // Every used layer is cleared and redrawn: discard the contents,
        // but wait for last frame's readers (write-after-read). The
        // triangle buffer is pulled by the vertex shader. One depth image
        // serves every view: each view's clear and tests wait for the
        // previous view's depth writes (write-after-write), as the
        // declaration holds again before each rendering scope.
        rec.pass("shadow maps")
            .overwrite(&self.map, Access::ColorAttachment)
            .overwrite(&self.depth, Access::DepthAttachment)
            .read(&scene.triangles, Access::VertexRead)
            .record(|c| {
                let extent = self.map.extent();
                for v in &views {
                    let mode = f32::from_bits(v.info[0]);
                    for face in 0..v.info[1] {
                        let layer = (v.info[2] + face) as usize;
                        let colors = [(self.map.layer_views[layer], Some([SHADOW_CLEAR; 4]))];
                        c.render(extent, &colors, Some((self.depth.view, true)), |r| {
                            if scene.triangle_count > 0 {
                                let push = ShadowPush {
                                    view_proj: v.view_proj[face as usize],
                                    origin: [v.origin[0], v.origin[1], v.origin[2], mode],
                                    direction: v.direction,
                                };
                                r.bind(&self.pipeline, &[&scene.set], bytemuck::bytes_of(&push));
                                r.draw(3 * scene.triangle_count);
                            }
                        });
                    }
                }
            });
        Ok(())
    }
}
