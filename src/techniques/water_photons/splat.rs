//! Splatting and composite (Kougianos & Moustakas 2021 §3.2, Eqs. 16-20).
//!
//! "photon splat": `vkCmdDrawIndirect` with the trace's draw buffer, one
//! instanced 4-vertex strip per photon (glsl/water_photons/splat.*), depth
//! tested (not written) against the camera G-buffer's depth and kept only
//! where the G-buffer's surface shows the camera the side the photon
//! arrived on (its normal, faced to the camera, against the photon's,
//! faced to the ray: a thin wall is not lit through itself), added into
//! the screen-space caustic buffer: RGBA32F, rgb the caustic irradiance E
//! (W/m²) on the visible receiver, a the sum of kernel weights.
//! "caustic composite" (glsl/water_photons/composite.comp): L += albedo/π · E
//! on diffuse pixels, reading whichever image `Composite::new` was given
//! (the caustic buffer, or a denoised copy of it).

use super::bindings;
use super::WpParamsBuffer;
use crate::frame::SceneGpu;
use crate::passes::gbuffer::{GBuffer, DEPTH_FORMAT};
use crate::vk::{
    groups_8x8, Access, Buffer, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    FrameRecorder, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc, Sampler,
    Specialization, VkResult,
};
use ash::vk;
use std::sync::Arc;

pub const CAUSTIC_BUFFER_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const SPLAT_SHADERS: [&str; 2] = ["water_photons/splat.vert", "water_photons/splat.frag"];

pub struct Splat {
    /// Screen-space caustic irradiance (rgb, W/m²) and kernel weight sum (a).
    pub caustics: Image,
    pipeline: GraphicsPipeline,
    set: DescriptorSet,
    sampler: Sampler,
    _layout: DescriptorSetLayout,
}

impl Splat {
    pub fn new(
        ctx: &Arc<Context>,
        scene_gpu: &SceneGpu,
        params: &WpParamsBuffer,
        photons: &Buffer,
        specialization: &Specialization,
        width: u32,
        height: u32,
    ) -> VkResult<Self> {
        let caustics = Image::new(
            ctx,
            "caustic buffer",
            ImageDesc::new_2d(
                width,
                height,
                CAUSTIC_BUFFER_FORMAT,
                vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::STORAGE
                    | vk::ImageUsageFlags::SAMPLED,
            ),
        )?;
        // Nearest: splat.frag fetches the G-buffer texel under the fragment.
        let sampler = Sampler::new(ctx, vk::Filter::NEAREST)?;
        let (layout, set, pipeline) = photon_quads(
            ctx,
            scene_gpu,
            params,
            photons,
            SPLAT_SHADERS,
            CAUSTIC_BUFFER_FORMAT,
            |desc| {
                desc.depth_format = Some(DEPTH_FORMAT);
                desc.depth_test = true;
                desc.depth_write = false;
                desc.specialization = specialization.clone();
            },
        )?;
        Ok(Self {
            caustics,
            pipeline,
            set,
            sampler,
            _layout: layout,
        })
    }

    /// Records "photon splat": clears the caustic buffer and draws
    /// `draw`'s instance count of quads.
    pub fn record(
        &self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        gbuffer: &GBuffer,
        photons: &Buffer,
        draw: &Buffer,
    ) {
        // The trace's atomics (instanceCount) must be visible to the
        // indirect read, its photon writes to the vertex shader; the
        // G-buffer's depth is tested (read) and its normals read by
        // the fragment stage (the arrival side test), the caustic
        // buffer overwritten after last frame's composite read it.
        rec.pass("photon splat")
            .overwrite(&self.caustics, Access::ColorAttachment)
            .write(&gbuffer.depth, Access::DepthAttachment)
            .sampled(
                &self.set,
                bindings::WP_BINDING_GBUFFER_NORMAL,
                &gbuffer.normal,
                &self.sampler,
                Access::FragmentRead,
            )
            .read(draw, Access::IndirectRead)
            .read(photons, Access::VertexRead)
            .record(|c| {
                let colors = [(self.caustics.view, Some([0.0; 4]))];
                let depth = Some((gbuffer.depth.view, false));
                c.render(self.caustics.extent(), &colors, depth, |r| {
                    r.bind(&self.pipeline, &[&scene.set, &self.set], &[]);
                    r.draw_indirect(draw, 0);
                });
            });
    }
}

/// The pipeline of an instanced draw of one 4-vertex strip per photon
/// (the trace's indirect draw), its vertex and fragment shaders `shaders`,
/// added into one `format` attachment, with its set 1 holding
/// the parameters and the photons; `configure` adds the rest (depth,
/// specialisation). Shared by the splat and the shafts.
pub(super) fn photon_quads(
    ctx: &Arc<Context>,
    scene_gpu: &SceneGpu,
    params: &WpParamsBuffer,
    photons: &Buffer,
    shaders: [&'static str; 2],
    format: vk::Format,
    configure: impl FnOnce(&mut GraphicsPipelineDesc),
) -> VkResult<(DescriptorSetLayout, DescriptorSet, GraphicsPipeline)> {
    let layout = DescriptorSetLayout::of_shaders(ctx, 1, &shaders)?;
    let set = DescriptorSet::new(ctx, &layout)?;
    set.write_buffer(bindings::WP_BINDING_PARAMS, &params.0)
        .write_buffer(bindings::WP_BINDING_PHOTONS, photons);
    let mut desc = GraphicsPipelineDesc::new(shaders[0], shaders[1]);
    desc.color_formats = vec![format];
    desc.additive = true;
    desc.topology = vk::PrimitiveTopology::TRIANGLE_STRIP;
    configure(&mut desc);
    let pipeline = GraphicsPipeline::new(ctx, &desc, &[&scene_gpu.layout, &layout])?;
    Ok((layout, set, pipeline))
}

/// L += albedo/π · E_caustic on the diffuse receivers of a G-buffer.
pub struct Composite {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _layout: DescriptorSetLayout,
}

impl Composite {
    pub fn new(ctx: &Arc<Context>, scene_gpu: &SceneGpu) -> VkResult<Self> {
        let layout = DescriptorSetLayout::of_shaders(ctx, 1, &["water_photons/composite.comp"])?;
        let set = DescriptorSet::new(ctx, &layout)?;
        let pipeline = ComputePipeline::new(
            ctx,
            "water_photons/composite.comp",
            &[&scene_gpu.layout, &layout],
            0,
        )?;
        Ok(Self {
            pipeline,
            set,
            _layout: layout,
        })
    }

    pub fn record(
        &self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        caustics: &Image,
        gbuffer: &GBuffer,
        radiance: &Image,
    ) {
        // The splat's attachment writes and the direct pass's radiance
        // writes before this read-modify-write.
        let set = &self.set;
        rec.pass("caustic composite")
            .storage_image(
                set,
                bindings::WP_BINDING_CAUSTICS,
                caustics,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_GBUFFER_POSITION,
                &gbuffer.position,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_GBUFFER_NORMAL,
                &gbuffer.normal,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_GBUFFER_ALBEDO,
                &gbuffer.albedo,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_RADIANCE,
                radiance,
                Access::ComputeWrite,
            )
            .record(|c| {
                let e = radiance.extent();
                let groups = groups_8x8(e.width, e.height);
                c.dispatch(&self.pipeline, &[&scene.set, &self.set], &[], groups);
            });
    }
}
