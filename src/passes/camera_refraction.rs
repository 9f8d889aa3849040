//! What the camera sees in the specular objects: Wyman 2005-06 two-sided
//! image-space refraction (and mirror reflection) over the opaque frame
//! (image_space's camera side; water_photons draws its water with it too).
//! "refractor gbuffer": the camera's specular G-buffer
//! (`passes::specular_gbuffer`: nearest front faces with d_N, farthest back
//! faces); "refraction" (glsl/passes/camera_refraction.comp): per pixel,
//! Fresnel-weighted reflection plus the twice-refracted ray (its exit traced
//! through the BVH, or Wyman's approximation: `RefractionPush::exit`), each
//! found in the opaque frame by an image-space search, into the frame's
//! radiance.

use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::gbuffer::GBuffer;
use crate::passes::specular_gbuffer::{SpecularGBuffer, Viewpoint};
use crate::shader_bindings as b;
use crate::vk::{
    groups_8x8, Access, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    FrameRecorder, Image, VkResult,
};
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

/// Push constants of glsl/passes/camera_refraction.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct RefractionPush {
    /// `TIR_*`.
    pub tir_remedy: u32,
    /// 1: Eq. 6.3.2 where the back-face texel holds no normal.
    pub use_eq632: u32,
    /// Linear steps of the image-space search.
    pub search_steps: u32,
    /// `CAMERA_EXIT_*`: the second interface of a closed dielectric.
    pub exit: u32,
}

pub struct CameraRefraction {
    pub gbuffer: SpecularGBuffer,
    push: RefractionPush,
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _layout: DescriptorSetLayout,
}

impl CameraRefraction {
    /// Linear steps of the image-space search (a push constant: live).
    pub fn set_search_steps(&mut self, steps: u32) {
        self.push.search_steps = steps;
    }

    /// A refraction pass for frames of `extent`.
    pub fn new(
        ctx: &Arc<Context>,
        scene_gpu: &SceneGpu,
        extent: ash::vk::Extent2D,
        push: RefractionPush,
    ) -> VkResult<Self> {
        let gbuffer = SpecularGBuffer::new(ctx, &scene_gpu.layout, extent.width, extent.height)?;
        let layout = DescriptorSetLayout::of_shaders(ctx, 1, &["passes/camera_refraction.comp"])?;
        let set = DescriptorSet::new(ctx, &layout)?;
        let pipeline = ComputePipeline::new(
            ctx,
            "passes/camera_refraction.comp",
            &[&scene_gpu.layout, &layout],
            std::mem::size_of::<RefractionPush>() as u32,
        )?;
        Ok(Self {
            gbuffer,
            push,
            pipeline,
            set,
            _layout: layout,
        })
    }

    /// Records "refractor gbuffer": the camera's specular G-buffer, which
    /// `record` reads (and techniques may read before it).
    pub fn draw_gbuffer(&self, rec: &mut FrameRecorder, scene: &SceneGpu) {
        self.gbuffer
            .record(rec, "refractor gbuffer", scene, &Viewpoint::Camera);
    }

    /// Records "refraction" (after `draw_gbuffer`): reads `opaque` (all of
    /// it written by earlier passes) and `opaque_gbuffer`, writes every
    /// pixel of `targets.radiance`.
    pub fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        opaque: &Image,
        opaque_gbuffer: &GBuffer,
        targets: &FrameTargets,
    ) {
        // The specular G-buffer's attachment writes and the opaque frame's
        // compute writes (caustic apply) become visible; the output is
        // overwritten entirely after last frame's readers.
        let set = &self.set;
        let pass = rec.pass("refraction");
        let pass = self.gbuffer.bind_reads(
            pass,
            set,
            [
                b::REFRACTION_BINDING_FRONT_POSITION,
                b::REFRACTION_BINDING_FRONT_NORMAL,
                b::REFRACTION_BINDING_BACK_POSITION,
                b::REFRACTION_BINDING_BACK_NORMAL,
            ],
        );
        pass.storage_image(
            set,
            b::REFRACTION_BINDING_OPAQUE_RADIANCE,
            opaque,
            Access::ComputeRead,
        )
        .storage_image(
            set,
            b::REFRACTION_BINDING_OPAQUE_POSITION,
            &opaque_gbuffer.position,
            Access::ComputeRead,
        )
        .overwrite_storage_image(
            set,
            b::REFRACTION_BINDING_RADIANCE,
            &targets.radiance,
            Access::ComputeWrite,
        )
        .record(|c| {
            let groups = groups_8x8(targets.width, targets.height);
            c.dispatch(
                &self.pipeline,
                &[&scene.set, set],
                bytemuck::bytes_of(&self.push),
                groups,
            );
        });
    }
}
