//! Specular G-buffer (Wyman 2005-06, two-sided image-space refraction): the
//! specular objects seen from one viewpoint, the camera (`image_space`'s
//! refraction pass) or a light (caustic map photons, `photon_mode` 1 and 2).
//! Two raster passes over every triangle (vertex pulling), specular ones
//! kept by glsl/passes/specular_gbuffer.frag:
//! - front: the nearest dielectric face turned toward the viewer, or the
//!   nearest mirror face; position with the interpolated per-vertex d_N
//!   (`Bvh::set_normal_thickness`) in w, normal with the material in w;
//!   diffuse geometry writes depth here and marks its texels not covered,
//!   so a refractor behind an opaque object is hidden by it;
//! - back: the farthest dielectric face turned away from the viewer
//!   (Wyman's preferred second interface for non-convex refractors: "the
//!   surface farthest from the eye"), position and normal; diffuse
//!   geometry is ignored (it must not replace the refractor's back face).
//!
//! Layout (RGBA32F each, storage + colour attachment): position xyz, w =
//! d_N (front) or 0 (back), -1 where nothing covers the texel; normal xyz
//! the smooth outward normal, w = material index as a float.

use crate::frame::SceneGpu;
use crate::shader_bindings as b;
use crate::vk::{
    Access, Commands, Context, DescriptorSet, DescriptorSetLayout, FrameRecorder, GraphicsPipeline,
    GraphicsPipelineDesc, Image, ImageDesc, Pass, VkResult,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use std::mem::size_of;
use std::sync::Arc;

pub const SPECULAR_GBUFFER_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Clear value of the position targets: w < 0 marks "no specular surface".
pub const NOT_COVERED: [f32; 4] = [0.0, 0.0, 0.0, -1.0];

/// Push constants of glsl/passes/specular_gbuffer.*.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SpecularGBufferPush {
    view_proj: [[f32; 4]; 4],
    /// xyz: the light (or ortho plane centre); w: SHADOW_RADIAL, SHADOW_PLANAR
    /// or SPECULAR_VIEW_CAMERA (bits).
    origin: [f32; 4],
    /// xyz: view axis; w: SPECULAR_GBUFFER_FRONT or SPECULAR_GBUFFER_BACK (bits).
    forward: [f32; 4],
}

/// Where the specular objects are seen from.
#[derive(Clone, Copy, Debug)]
pub enum Viewpoint {
    /// The frame's camera (`frame.view_proj`, `frame.eye`).
    Camera,
    /// A light's photon view.
    Light {
        /// World to clip (Vulkan depth 0..1).
        view_proj: Mat4,
        /// Light position (perspective), or a point of the ortho plane.
        origin: Vec3,
        /// View axis (the rays' direction for an orthographic view).
        forward: Vec3,
        orthographic: bool,
    },
}

pub struct SpecularGBuffer {
    pub front_position: Image,
    pub front_normal: Image,
    pub back_position: Image,
    pub back_normal: Image,
    depth: Image,
    pipeline: GraphicsPipeline,
}

impl SpecularGBuffer {
    pub fn new(
        ctx: &Arc<Context>,
        scene_layout: &DescriptorSetLayout,
        width: u32,
        height: u32,
    ) -> VkResult<Self> {
        let target = |name: &str| {
            Image::new(
                ctx,
                name,
                ImageDesc::new_2d(
                    width,
                    height,
                    SPECULAR_GBUFFER_FORMAT,
                    // Sampled: fragment shaders fetch it (water_photons' shafts).
                    vk::ImageUsageFlags::COLOR_ATTACHMENT
                        | vk::ImageUsageFlags::STORAGE
                        | vk::ImageUsageFlags::SAMPLED,
                ),
            )
        };
        let front_position = target("specular front position")?;
        let front_normal = target("specular front normal")?;
        let back_position = target("specular back position")?;
        let back_normal = target("specular back normal")?;
        let depth = Image::new(
            ctx,
            "specular depth",
            ImageDesc::new_2d(
                width,
                height,
                vk::Format::D32_SFLOAT,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            ),
        )?;
        let mut desc = GraphicsPipelineDesc::new(
            "passes/specular_gbuffer.vert",
            "passes/specular_gbuffer.frag",
        );
        desc.color_formats = vec![SPECULAR_GBUFFER_FORMAT, SPECULAR_GBUFFER_FORMAT];
        desc.depth_format = Some(vk::Format::D32_SFLOAT);
        desc.depth_test = true;
        desc.depth_write = true;
        desc.push_size = size_of::<SpecularGBufferPush>() as u32;
        let pipeline = GraphicsPipeline::new(ctx, &desc, &[scene_layout])?;
        Ok(Self {
            front_position,
            front_normal,
            back_position,
            back_normal,
            depth,
            pipeline,
        })
    }

    /// Records the pass `name`: the front and back draws. Every target is
    /// overwritten; the barriers wait for the previous readers
    /// (write-after-read) and for writes to the triangles.
    pub fn record(&self, rec: &mut FrameRecorder, name: &str, scene: &SceneGpu, view: &Viewpoint) {
        rec.pass(name)
            .overwrite(&self.front_position, Access::ColorAttachment)
            .overwrite(&self.front_normal, Access::ColorAttachment)
            .overwrite(&self.back_position, Access::ColorAttachment)
            .overwrite(&self.back_normal, Access::ColorAttachment)
            .overwrite(&self.depth, Access::DepthAttachment)
            .read(&scene.triangles, Access::VertexRead)
            .record(|c| self.draw(c, scene, view));
    }

    /// The front draw, then the back draw; the depth image both use is
    /// ordered between them by the pass's declaration (write-after-write).
    fn draw(&self, c: &mut Commands, scene: &SceneGpu, view: &Viewpoint) {
        let extent = self.front_position.extent();
        let (view_proj, origin, forward, kind) = match *view {
            Viewpoint::Camera => (
                Mat4::IDENTITY,
                Vec3::ZERO,
                Vec3::ZERO,
                b::SPECULAR_VIEW_CAMERA,
            ),
            Viewpoint::Light {
                view_proj,
                origin,
                forward,
                orthographic,
            } => (
                view_proj,
                origin,
                forward,
                if orthographic {
                    b::SHADOW_PLANAR
                } else {
                    b::SHADOW_RADIAL
                },
            ),
        };
        for (pass, position, normal) in [
            (
                b::SPECULAR_GBUFFER_FRONT,
                &self.front_position,
                &self.front_normal,
            ),
            (
                b::SPECULAR_GBUFFER_BACK,
                &self.back_position,
                &self.back_normal,
            ),
        ] {
            let colors = [
                (position.view, Some(NOT_COVERED)),
                (normal.view, Some([0.0; 4])),
            ];
            c.render(extent, &colors, Some((self.depth.view, true)), |r| {
                if scene.triangle_count > 0 {
                    let push = SpecularGBufferPush {
                        view_proj: view_proj.to_cols_array_2d(),
                        origin: origin.extend(f32::from_bits(kind)).to_array(),
                        forward: forward.extend(f32::from_bits(pass)).to_array(),
                    };
                    r.bind(&self.pipeline, &[&scene.set], bytemuck::bytes_of(&push));
                    r.draw(3 * scene.triangle_count);
                }
            });
        }
    }

    /// Declares the compute reads of all four targets by `pass` through
    /// `set`'s storage-image `bindings` (front position, front normal, back
    /// position, back normal).
    pub fn bind_reads<'r, 'f, 'a>(
        &'a self,
        pass: Pass<'r, 'f, 'a>,
        set: &'a DescriptorSet,
        bindings: [u32; 4],
    ) -> Pass<'r, 'f, 'a> {
        pass.storage_image(set, bindings[0], &self.front_position, Access::ComputeRead)
            .storage_image(set, bindings[1], &self.front_normal, Access::ComputeRead)
            .storage_image(set, bindings[2], &self.back_position, Access::ComputeRead)
            .storage_image(set, bindings[3], &self.back_normal, Access::ComputeRead)
    }
}
