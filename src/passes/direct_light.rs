//! Direct light with shadow maps, the base frame every technique adds to
//! (the `direct` technique is this pass alone). Radiometrically the ground truth's L D component for diffuse
//! surfaces seen directly: L = albedo / pi * sum over lights of E * V, with
//! E the light's irradiance (I cos / r^2 with spot falloff, or E cos for a
//! directional light) and V the shadow-map visibility. The taps that the
//! maps' depth bias alone counts lit (an occluder nearer the light than the
//! receiver by less than the bias: the water's surface just above a wall
//! under it, which the bias would light as a band a few texels tall) ask
//! one BVH shadow ray (`shadow_visibility_band` in glsl/common/shadow.glsl);
//! everywhere else the maps decide alone.
//!
//! Passes (each through `FrameRecorder::pass`):
//! 1. "shadow maps" (`passes::shadow`): every light's views, linear distance;
//! 2. "gbuffer" (`passes::gbuffer`): world position, normal, material;
//! 3. "direct lighting" (glsl/direct/lighting.comp): per pixel, into the
//!    frame's radiance image.
//!
//! Specular surfaces seen directly read 0; the background reads the
//! environment and an area light's front face its radiance (the emitted
//! component).
//!
//! Environment and area lights (docs/ARCHITECTURE.md, "Environment and
//! area lights in direct"): 0. "environment irradiance"
//! (glsl/direct/environment_sh.comp, recorded on the first frame and on the
//! first after the environment rotated, `environment_changed`) projects the
//! environment's table onto order-2 spherical harmonics (Ramamoorthi &
//! Hanrahan 2001); the lighting adds their irradiance, unoccluded, the
//! sky's sun as a directional light with one BVH shadow ray, and each area
//! light's exact unoccluded irradiance times one BVH shadow ray to its centre.
//!
//! In a scene with a medium the surface radiance is attenuated as the
//! ground truth attenuates it (Hu et al. 2010 Sect. 5.3, Fig. 2 C): each
//! light's irradiance by the transmittance tau(s, x) from the light to x and
//! the result by tau(x, v) to the eye. Transmittance is deterministic
//! (glsl/common/medium.glsl `medium_transmittance_steps`): Beer-Lambert on
//! the segment clipped to the medium's bounds for constant density, the
//! midpoint rule with `medium_steps` steps for noise and grid densities
//! (Hu Sect. 5.4). Without a medium the factors are exactly 1.

use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::gbuffer::{GBuffer, GBufferContents};
use crate::passes::shadow::ShadowMaps;
use crate::scene::Scene;
use crate::shader_bindings as b;
use crate::vk::{
    groups_8x8, Access, Buffer, BufferUsage, ComputePipeline, Context, DescriptorSet,
    DescriptorSetLayout, FrameRecorder, Sampler, VkResult,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

crate::declare_params! {
    /// `DirectLight`'s parameters (shadow maps, PCF, medium transmittance),
    /// a group in every technique built on it.
    pub struct DirectParams {
        shadow_map_size: u32 [64, 4096] = 1024, rebuild,
            "shadow map resolution per view (texels per side)";
        pcf_radius: i32 [0, 4] = 1, live,
            "percentage-closer filter half-width in shadow texels (0: one tap)";
        medium_steps: u32 [1, 256] = 16, rebuild,
            "midpoint steps of the transmittance through noise/grid media (constant density is exact)";
        sky_rays: u32 [0, 256] = 16, live,
            "BVH rays per pixel (cosine-weighted, stratified) that occlude the environment's SH irradiance, weighted by the sky's radiance along them; 0: unoccluded";
    }
}

/// Push constants of glsl/direct/lighting.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct LightingPush {
    light_count: u32,
    pcf_radius: i32,
    medium_steps: u32,
    sky_rays: u32,
}

pub struct DirectLight {
    pub shadows: ShadowMaps,
    pub gbuffer: GBuffer,
    pcf_radius: i32,
    medium_steps: u32,
    sky_rays: u32,
    light_count: u32,
    lighting: ComputePipeline,
    /// Projects the environment onto spherical harmonics (glsl/direct/environment_sh.comp).
    environment_sh: ComputePipeline,
    /// 9 rgb coefficients (vec4 each) of the environment's irradiance.
    sh: Buffer,
    /// Whether `sh` holds this scene's environment (computed on the first
    /// frame and again after `environment_changed`).
    sh_done: bool,
    set: DescriptorSet,
    /// "environment irradiance"'s set (the SH alone).
    sh_set: DescriptorSet,
    _layouts: [DescriptorSetLayout; 2],
    sampler: Sampler,
}

impl DirectLight {
    pub fn new(
        ctx: &Arc<Context>,
        params: &DirectParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> VkResult<Self> {
        Self::with_contents(
            ctx,
            params,
            scene,
            scene_gpu,
            width,
            height,
            GBufferContents::All,
        )
    }

    /// The same passes over a G-buffer holding `contents` (`image_space`
    /// lights the opaque scene behind its refractors).
    pub fn with_contents(
        ctx: &Arc<Context>,
        params: &DirectParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
        contents: GBufferContents,
    ) -> VkResult<Self> {
        let shadows = ShadowMaps::new(
            ctx,
            &scene_gpu.layout,
            &scene.lights,
            params.shadow_map_size,
        )?;
        let gbuffer = GBuffer::new(ctx, &scene_gpu.layout, width, height, contents)?;
        let layout = DescriptorSetLayout::of_shaders(ctx, 1, &["direct/lighting.comp"])?;
        // The environment projection's own set: the lighting set's image
        // bindings are declared by the lighting pass, which must be the
        // first to bind it in a frame.
        let sh_layout = DescriptorSetLayout::of_shaders(ctx, 1, &["direct/environment_sh.comp"])?;
        let sh = Buffer::new(
            ctx,
            "environment irradiance SH",
            9 * 16,
            BufferUsage::Storage,
        )?;
        // Nearest: the shader fetches single texels and compares them itself.
        let sampler = Sampler::new(ctx, vk::Filter::NEAREST)?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(b::DIRECT_BINDING_SHADOW_LIGHTS, &shadows.lights);
        let sh_set = DescriptorSet::new(ctx, &sh_layout)?;
        let environment_sh = ComputePipeline::new(
            ctx,
            "direct/environment_sh.comp",
            &[&scene_gpu.layout, &sh_layout],
            0,
        )?;
        let lighting = ComputePipeline::new(
            ctx,
            "direct/lighting.comp",
            &[&scene_gpu.layout, &layout],
            std::mem::size_of::<LightingPush>() as u32,
        )?;
        Ok(Self {
            light_count: scene.lights.len().min(b::MAX_LIGHTS as usize) as u32,
            shadows,
            gbuffer,
            pcf_radius: params.pcf_radius,
            medium_steps: params.medium_steps,
            sky_rays: params.sky_rays,
            lighting,
            environment_sh,
            sh,
            sh_done: false,
            set,
            sh_set,
            _layouts: [layout, sh_layout],
            sampler,
        })
    }

    /// The environment rotated: its irradiance SH is projected again on the
    /// next frame ("environment irradiance").
    pub fn environment_changed(&mut self) {
        self.sh_done = false;
    }

    /// Takes the live parameters of `params` (`pcf_radius`, `sky_rays`).
    pub fn set_live(&mut self, params: &DirectParams) {
        self.pcf_radius = params.pcf_radius;
        self.sky_rays = params.sky_rays;
    }

    /// Records "shadow maps", "gbuffer" and "direct lighting" into
    /// `targets.radiance` (every pixel).
    pub fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) -> VkResult<()> {
        self.shadows.record(rec, scene)?;
        self.gbuffer.record(rec, scene);
        let push = LightingPush {
            light_count: self.light_count,
            pcf_radius: self.pcf_radius,
            medium_steps: self.medium_steps,
            sky_rays: self.sky_rays,
        };
        if !self.sh_done {
            let set = &self.sh_set;
            rec.pass("environment irradiance")
                .buffer(
                    set,
                    b::DIRECT_BINDING_ENVIRONMENT_SH,
                    &self.sh,
                    Access::ComputeWrite,
                )
                .record(|c| c.dispatch(&self.environment_sh, &[&scene.set, set], &[], [1, 1, 1]));
            self.sh_done = true;
        }
        // The G-buffer's and shadow maps' attachment writes must be
        // visible to the compute reads (and move to GENERAL); the
        // radiance image is overwritten entirely, after waiting for last
        // frame's readers (tonemap, readback).
        let set = &self.set;
        let r = Access::ComputeRead;
        rec.pass("direct lighting")
            .storage_image(set, b::DIRECT_BINDING_POSITION, &self.gbuffer.position, r)
            .storage_image(set, b::DIRECT_BINDING_NORMAL, &self.gbuffer.normal, r)
            .storage_image(set, b::DIRECT_BINDING_ALBEDO, &self.gbuffer.albedo, r)
            .sampled(
                set,
                b::DIRECT_BINDING_SHADOW_MAP,
                &self.shadows.map,
                &self.sampler,
                r,
            )
            .buffer(set, b::DIRECT_BINDING_ENVIRONMENT_SH, &self.sh, r)
            .overwrite_storage_image(
                set,
                b::DIRECT_BINDING_RADIANCE,
                &targets.radiance,
                Access::ComputeWrite,
            )
            .record(|c| {
                let groups = groups_8x8(targets.width, targets.height);
                c.dispatch(
                    &self.lighting,
                    &[&scene.set, set],
                    bytemuck::bytes_of(&push),
                    groups,
                );
            });
        Ok(())
    }

    /// The scene's lights moved (same count and kinds); false if the shadow
    /// maps cannot take them in place.
    pub fn set_lights(&mut self, lights: &[crate::scene::Light]) -> bool {
        self.shadows.set_lights(lights)
    }
}
