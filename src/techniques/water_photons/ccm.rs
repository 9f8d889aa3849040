//! The cascaded caustic map (CCM) raster (Kougianos & Moustakas 2021 §3.1):
//! the water surface, evaluated on the GPU (`passes::water_surface`), drawn
//! from the light into a 2D texture array with one layer per cascade:
//! world position (w = 1 where water covers the texel) and smooth normal.
//! Cascade c's view-projection is Eq. 2 (`CascadeLayout::projection`) times
//! the shared light view of Eq. 1 (`cascades::light_view`).

use super::bindings;
use crate::passes::water_surface::WaterSurface;
use crate::scene::Water;
use crate::vk::{
    Access, Context, DescriptorSet, DescriptorSetLayout, FrameRecorder, GraphicsPipeline,
    GraphicsPipelineDesc, Image, ImageDesc, VkResult,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::Mat4;
use std::mem::size_of;
use std::sync::Arc;

pub const CCM_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// Push constants of glsl/water_photons/ccm.vert.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct CcmPush {
    view_proj: [[f32; 4]; 4],
    grid: [u32; 4],
}
const _: () = assert!(size_of::<CcmPush>() == 80);

pub struct Ccm {
    pub surface: WaterSurface,
    /// World position per texel, one layer per cascade (w = 1: water).
    pub position: Image,
    /// Smooth unit normal (+y side) per texel (w = 1: water).
    pub normal: Image,
    depth: Image,
    pipeline: GraphicsPipeline,
    set: DescriptorSet,
    _layout: DescriptorSetLayout,
    grid: [u32; 2],
}

impl Ccm {
    /// `size`² texels per cascade, `levels` cascades, for `water`.
    pub fn new(ctx: &Arc<Context>, water: &Water, size: u32, levels: u32) -> VkResult<Self> {
        let surface = WaterSurface::new(ctx, water)?;
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED;
        let desc = |format, usage| ImageDesc {
            width: size,
            height: size,
            layers: levels,
            format,
            usage,
        };
        // Array views even for one cascade: the trace reads image2DArray.
        let position = Image::new_array(ctx, "ccm position", desc(CCM_FORMAT, usage))?;
        let normal = Image::new_array(ctx, "ccm normal", desc(CCM_FORMAT, usage))?;
        let depth = Image::new(
            ctx,
            "ccm depth",
            desc(DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        )?;
        let layout = DescriptorSetLayout::of_shaders(
            ctx,
            0,
            &["water_photons/ccm.vert", "water_photons/ccm.frag"],
        )?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(bindings::WP_BINDING_WATER_VERTICES, &surface.vertices);
        let mut desc =
            GraphicsPipelineDesc::new("water_photons/ccm.vert", "water_photons/ccm.frag");
        desc.color_formats = vec![CCM_FORMAT, CCM_FORMAT];
        desc.depth_format = Some(DEPTH_FORMAT);
        desc.depth_test = true;
        desc.depth_write = true;
        desc.push_size = size_of::<CcmPush>() as u32;
        let pipeline = GraphicsPipeline::new(ctx, &desc, &[&layout])?;
        Ok(Self {
            surface,
            position,
            normal,
            depth,
            pipeline,
            set,
            _layout: layout,
            grid: water.resolution,
        })
    }

    /// Records "water surface" (the Gerstner sum at `time`) and "ccm raster"
    /// (one layer per entry of `view_projs`, nearest water to the light).
    pub fn record(&self, rec: &mut FrameRecorder, time: f32, view_projs: &[Mat4]) {
        self.surface.record(rec, time);
        // The vertices written by compute are pulled by the vertex
        // shader; every layer is cleared and redrawn (last frame's
        // trace reads done first).
        rec.pass("ccm raster")
            .overwrite(&self.position, Access::ColorAttachment)
            .overwrite(&self.normal, Access::ColorAttachment)
            .overwrite(&self.depth, Access::DepthAttachment)
            .read(&self.surface.vertices, Access::VertexRead)
            .record(|c| {
                let extent = self.position.extent();
                for (layer, view_proj) in view_projs.iter().enumerate() {
                    let colors = [
                        (self.position.layer_views[layer], Some([0.0; 4])),
                        (self.normal.layer_views[layer], Some([0.0; 4])),
                    ];
                    let depth = Some((self.depth.layer_views[layer], true));
                    c.render(extent, &colors, depth, |r| {
                        let push = CcmPush {
                            view_proj: view_proj.to_cols_array_2d(),
                            grid: [self.grid[0], self.grid[1], 0, 0],
                        };
                        r.bind(&self.pipeline, &[&self.set], bytemuck::bytes_of(&push));
                        r.draw(6 * self.grid[0] * self.grid[1]);
                    });
                }
            });
    }
}
