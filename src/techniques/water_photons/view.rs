//! "water view" (glsl/water_photons/view.comp): the camera's view of the
//! water surface, recomputed after the surface frame's camera refraction on the
//! pixels whose nearest specular surface is the traced water (one
//! interface): the reflected and refracted camera rays traced through the
//! BVH; a hit the camera sees directly takes the opaque frame's radiance
//! (direct + splatted caustics), a hit hidden from it (behind a wall,
//! outside the view) is shaded there, its caustic gathered from the
//! photons through the trace's slot image with the splat's kernel.
//! The cascade count and the splat mode are specialisation constants
//! (`WP_SPEC_*`): as uniform reads they made lavapipe recompile the shader
//! at every bind, +1.85 MB host memory a frame (BENCHMARKS.md, "Soak").

use super::bindings;
use super::WpParamsBuffer;
use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::gbuffer::GBuffer;
use crate::passes::specular_gbuffer::SpecularGBuffer;
use crate::vk::{
    groups_8x8, Access, Buffer, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    FrameRecorder, Image, Specialization, VkResult,
};
use std::sync::Arc;

pub struct WaterView {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _layout: DescriptorSetLayout,
}

impl WaterView {
    pub fn new(
        ctx: &Arc<Context>,
        scene_gpu: &SceneGpu,
        params: &WpParamsBuffer,
        photons: &Buffer,
        specialization: &Specialization,
    ) -> VkResult<Self> {
        let layout = DescriptorSetLayout::of_shaders(ctx, 1, &["water_photons/view.comp"])?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(bindings::WP_BINDING_PARAMS, &params.0)
            .write_buffer(bindings::WP_BINDING_PHOTONS, photons);
        let pipeline = ComputePipeline::specialized(
            ctx,
            "water_photons/view.comp",
            specialization,
            &[&scene_gpu.layout, &layout],
            0,
        )?;
        Ok(Self {
            pipeline,
            set,
            _layout: layout,
        })
    }

    /// Records "water view": reads the photons and their slots (the trace),
    /// the opaque frame (composite) and the specular G-buffer (refraction
    /// pass), rewrites the water's pixels of `targets.radiance`.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        photons: &Buffer,
        slots: &Image,
        opaque: &Image,
        opaque_gbuffer: &GBuffer,
        specular: &SpecularGBuffer,
        shafts: &Image,
        targets: &FrameTargets,
    ) {
        // The trace's photon and slot writes, the composite's radiance
        // writes and the refraction pass's radiance writes (this pass
        // rewrites some of its pixels: write after write) before these
        // reads; the specular G-buffer's attachments were made visible
        // to compute by the refraction pass's barrier.
        let set = &self.set;
        rec.pass("water view")
            .storage_image(
                set,
                bindings::WP_BINDING_PHOTON_SLOTS,
                slots,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_OPAQUE_RADIANCE,
                opaque,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_GBUFFER_POSITION,
                &opaque_gbuffer.position,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_FRONT_POSITION,
                &specular.front_position,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_FRONT_NORMAL,
                &specular.front_normal,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_BACK_POSITION,
                &specular.back_position,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_SHAFTS,
                shafts,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_RADIANCE,
                &targets.radiance,
                Access::ComputeWrite,
            )
            .read(photons, Access::ComputeRead)
            .record(|c| {
                let groups = groups_8x8(targets.width, targets.height);
                c.dispatch(&self.pipeline, &[&scene.set, set], &[], groups);
            });
    }
}
