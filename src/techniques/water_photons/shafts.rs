//! "shafts": the light a medium in the water scatters toward an eye under
//! the surface (glsl/water_photons/shafts.*; issue 30, beyond the paper):
//! `vkCmdDrawIndirect` with the trace's draw buffer, one instanced
//! 4-vertex strip per photon over its refracted ray's footprint on screen,
//! each fragment adding the beam x beam estimate of Hu et al. 2010 Eq. 3
//! for that ray's tube into an RGBA32F radiance image, which the water view
//! adds to the frame. The image is cleared every frame and drawn into only
//! while the eye is under a water that holds a medium and `shafts` is on.

use super::bindings;
use super::splat::photon_quads;
use super::WpParamsBuffer;
use crate::frame::SceneGpu;
use crate::passes::gbuffer::GBuffer;
use crate::passes::specular_gbuffer::SpecularGBuffer;
use crate::vk::{
    Access, Buffer, Context, DescriptorSet, DescriptorSetLayout, FrameRecorder, GraphicsPipeline,
    Image, ImageDesc, Sampler, VkResult,
};
use ash::vk;
use std::sync::Arc;

const SHAFTS_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const SHAFTS_SHADERS: [&str; 2] = ["water_photons/shafts.vert", "water_photons/shafts.frag"];

pub struct Shafts {
    /// Radiance scattered toward the eye in front of each pixel's surface (rgb).
    pub image: Image,
    pipeline: GraphicsPipeline,
    set: DescriptorSet,
    /// Nearest: shafts.frag fetches the G-buffers' texel under the fragment.
    sampler: Sampler,
    _layout: DescriptorSetLayout,
}

impl Shafts {
    pub fn new(
        ctx: &Arc<Context>,
        scene_gpu: &SceneGpu,
        params: &WpParamsBuffer,
        photons: &Buffer,
        width: u32,
        height: u32,
    ) -> VkResult<Self> {
        let image = Image::new(
            ctx,
            "shafts",
            ImageDesc::new_2d(
                width,
                height,
                SHAFTS_FORMAT,
                vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE,
            ),
        )?;
        let sampler = Sampler::new(ctx, vk::Filter::NEAREST)?;
        let (layout, set, pipeline) = photon_quads(
            ctx,
            scene_gpu,
            params,
            photons,
            SHAFTS_SHADERS,
            SHAFTS_FORMAT,
            |_| {},
        )?;
        Ok(Self {
            image,
            pipeline,
            set,
            sampler,
            _layout: layout,
        })
    }

    /// Records "shafts": clears the image and, when `draw_shafts`, draws
    /// `draw`'s instance count of quads, each fragment tested against the
    /// first surface its pixel sees (the opaque G-buffer's position, the
    /// specular G-buffer's front).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        photons: &Buffer,
        draw: &Buffer,
        opaque_gbuffer: &GBuffer,
        specular: &SpecularGBuffer,
        draw_shafts: bool,
    ) {
        // The trace's photon writes and its instance count before the
        // vertex and fragment reads and the indirect read; the G-buffers'
        // writes before the fragment reads; last frame's water view read
        // of the image before this clear.
        let set = &self.set;
        rec.pass("shafts")
            .overwrite(&self.image, Access::ColorAttachment)
            .sampled(
                set,
                bindings::WP_BINDING_GBUFFER_POSITION,
                &opaque_gbuffer.position,
                &self.sampler,
                Access::FragmentRead,
            )
            .sampled(
                set,
                bindings::WP_BINDING_FRONT_POSITION,
                &specular.front_position,
                &self.sampler,
                Access::FragmentRead,
            )
            .read(draw, Access::IndirectRead)
            .read(photons, Access::GraphicsRead)
            .record(|c| {
                let colors = [(self.image.view, Some([0.0; 4]))];
                c.render(self.image.extent(), &colors, None, |r| {
                    if draw_shafts {
                        r.bind(&self.pipeline, &[&scene.set, set], &[]);
                        r.draw_indirect(draw, 0);
                    }
                });
            });
    }
}
