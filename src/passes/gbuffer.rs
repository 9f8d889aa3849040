//! Camera G-buffer: every triangle rasterised from the camera (vertex pulling
//! from the scene's triangle buffer, `frame.view_proj`) into world position
//! and world normal + material index, with a D32 depth test. Techniques that
//! shade per pixel (direct light, caustic receivers) read it in compute.
//!
//! Layout of the targets (both RGBA32F, storage + sampled):
//! - `position`: xyz world position; w = 1 where a surface covers the pixel,
//!   0 for background (cleared to zero).
//! - `normal`: xyz unit smooth normal flipped to face the camera (surfaces are
//!   two-sided); w = material index as a float (exact below 2^24).
//! - `albedo`: rgb the surface's albedo (diffuse; reflectance for a
//!   mirror): material colour times its albedo texture, filtered over the
//!   pixel's footprint (trilinear, mip level from the UV derivatives). The
//!   lookup is done once here so every technique shading the G-buffer reads
//!   the same value; w = 1.
//!
//! `GBufferContents::Opaque` leaves the specular surfaces out (`image_space`
//! sees the opaque scene behind them and adds them by image-space refraction).

use crate::frame::SceneGpu;
use crate::vk::{
    Access, Context, DescriptorSetLayout, FrameRecorder, GraphicsPipeline, GraphicsPipelineDesc,
    Image, ImageDesc, VkResult,
};
use ash::vk;
use std::sync::Arc;

pub const POSITION_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const NORMAL_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// 32-bit: an untextured albedo passes through exactly.
pub const ALBEDO_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// Which surfaces the G-buffer holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GBufferContents {
    /// Every surface.
    All,
    /// Diffuse surfaces only: mirrors and dielectrics are skipped.
    Opaque,
}

pub struct GBuffer {
    pub position: Image,
    pub normal: Image,
    pub albedo: Image,
    pub depth: Image,
    pub contents: GBufferContents,
    pipeline: GraphicsPipeline,
}

impl GBuffer {
    /// Targets of `width` x `height`; `scene_layout` is set 0 (`SceneGpu::layout`).
    pub fn new(
        ctx: &Arc<Context>,
        scene_layout: &DescriptorSetLayout,
        width: u32,
        height: u32,
        contents: GBufferContents,
    ) -> VkResult<Self> {
        let color_usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED;
        let position = Image::new(
            ctx,
            "gbuffer position",
            ImageDesc::new_2d(width, height, POSITION_FORMAT, color_usage),
        )?;
        let normal = Image::new(
            ctx,
            "gbuffer normal+material",
            ImageDesc::new_2d(width, height, NORMAL_FORMAT, color_usage),
        )?;
        let albedo = Image::new(
            ctx,
            "gbuffer albedo",
            ImageDesc::new_2d(width, height, ALBEDO_FORMAT, color_usage),
        )?;
        let depth = Image::new(
            ctx,
            "gbuffer depth",
            ImageDesc::new_2d(
                width,
                height,
                DEPTH_FORMAT,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
            ),
        )?;
        let mut desc = GraphicsPipelineDesc::new("passes/gbuffer.vert", "passes/gbuffer.frag");
        desc.color_formats = vec![POSITION_FORMAT, NORMAL_FORMAT, ALBEDO_FORMAT];
        desc.depth_format = Some(DEPTH_FORMAT);
        desc.depth_test = true;
        desc.depth_write = true;
        // Two-sided surfaces: no culling; the fragment shader flips normals.
        desc.cull = vk::CullModeFlags::NONE;
        desc.push_size = 4;
        let pipeline = GraphicsPipeline::new(ctx, &desc, &[scene_layout])?;
        Ok(Self {
            position,
            normal,
            albedo,
            depth,
            contents,
            pipeline,
        })
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.position.extent()
    }

    /// Records the pass "gbuffer". Afterwards the targets' last access is
    /// `ColorAttachment`/`DepthAttachment`; readers declare theirs with `barrier`.
    pub fn record(&self, rec: &mut FrameRecorder, scene: &SceneGpu) {
        // Every target is cleared and redrawn, so earlier contents are
        // discarded; the barrier still waits for last frame's readers
        // (write-after-read). The triangle buffer is read by the vertex
        // shader: any earlier write to it (upload, refit) must be visible.
        rec.pass("gbuffer")
            .overwrite(&self.position, Access::ColorAttachment)
            .overwrite(&self.normal, Access::ColorAttachment)
            .overwrite(&self.albedo, Access::ColorAttachment)
            .overwrite(&self.depth, Access::DepthAttachment)
            .read(&scene.triangles, Access::VertexRead)
            .read(&scene.triangle_uvs, Access::VertexRead)
            .record(|c| {
                let colors = [
                    (self.position.view, Some([0.0; 4])),
                    (self.normal.view, Some([0.0; 4])),
                    (self.albedo.view, Some([0.0; 4])),
                ];
                c.render(self.extent(), &colors, Some((self.depth.view, true)), |r| {
                    if scene.triangle_count > 0 {
                        let opaque_only = u32::from(self.contents == GBufferContents::Opaque);
                        r.bind(
                            &self.pipeline,
                            &[&scene.set],
                            bytemuck::bytes_of(&opaque_only),
                        );
                        r.draw(3 * scene.triangle_count);
                    }
                });
            });
    }
}
