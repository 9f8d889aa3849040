//! Airlight with volumetric shadows (Hu et al. 2010 Fig. 2 A; issue #4):
//! single scattering of the light that reaches the medium straight from the
//! lights, ray-marched per pixel along the camera ray and ADDED to the
//! frame's radiance (glsl/passes/airlight.comp).
//!
//! Radiometry (Hu Eq. 1 discretised as Eq. 2, the inner integral over
//! directions collapsed by the delta light):
//!   L_A = sum_i tau(v, x_i) sigma_s(x_i) sum_l p(theta) I_l / r^2
//!         tau(s_l, x_i) V_l(x_i) dt
//! in W m^-2 sr^-1 (I in W/sr; a directional light's irradiance E for
//! I / r^2), HG phase with the medium's g, V from the shadow maps (every
//! caster, glass included), transmittance exact for constant density and by
//! `medium_steps` midpoint steps otherwise. This is exactly what the
//! reference's `airlight` component (L V paths) converges to. The lights
//! are the GPU light buffer's (`frame::caustic_lights`): the scene's
//! own, with the technique's shadow maps, then the point stand-ins of small
//! rect lights (a spot at the centre with the cosine profile
//! I = L A max(cos θ, 0), so their airlight agrees with the surface light
//! and volume caustics the techniques draw from the same stand-ins) and of
//! an environment's sun (a directional light of its irradiance), each
//! shadowed by one BVH ray per sample (they have no shadow map). The
//! stand-in differs from the rect's own airlight by O((s/d)²) at distance d
//! (`frame::STAND_IN_MAX_SIZE_RATIO`). An environment's sky (beyond
//! its sun) and sphere lights scatter no airlight here. The camera ray
//! ends at the first surface of any kind (one BVH ray per pixel): the
//! reference has no L V path seen through glass, and a technique's
//! G-buffer may hold only the opaque surfaces.
//!
//! The samples are `airlight_steps` strata of the ray's part inside the
//! medium bounds, one per stratum at a common offset: a per-pixel,
//! per-frame random offset (`airlight_jitter` = 1: shadow edges turn into
//! noise instead of banding) or the midpoints (0).
//!
//! Where the scene's medium asks for it (`multiple_scattering`), the pass
//! also adds the approximate multiple scattering of
//! [`super::scattered_lights`]: virtual lights where the light scatters
//! once, lighting the medium along the camera ray (L V V E, unshadowed)
//! and the camera ray's diffuse surface (L V D E: the unoccluded sum times
//! the visible fraction of 16 BVH shadow rays), tagged `other`.
//!
//! A technique owns one `Airlight` next to its shadow maps, holds
//! [`AirlightParams`] as a group of its parameter struct (and passes its
//! `medium_steps`), and records it after the pass that writes the frame's
//! radiance.

use super::scattered_lights::{capacity, scattered_lights, GpuScatteredLight};
use crate::frame::SceneGpu;
use crate::passes::shadow::ShadowMaps;
use crate::scene::Scene;
use crate::shader_bindings as b;
use crate::vk::{
    groups_8x8, Access, Buffer, BufferUsage, ComputePipeline, Context, DescriptorSet,
    DescriptorSetLayout, FrameRecorder, Image, Sampler, VkResult,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

crate::declare_params! {
    /// The airlight's parameters, a group of every technique that records
    /// it; it also takes the technique's `medium_steps` (`DirectParams`).
    pub struct AirlightParams {
        airlight_steps: u32 [1, 1024] = 64, live,
            "airlight ray-march samples per pixel (strata of the camera ray inside the medium)";
        airlight_jitter: u32 [0, 1] = 1, live,
            "1: airlight samples at a random offset per pixel and frame (noise instead of banding); 0: stratum midpoints";
    }
}

/// Push constants of glsl/passes/airlight.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct AirlightPush {
    light_count: u32,
    lit_count: u32,
    steps: u32,
    medium_steps: u32,
    jitter: u32,
    /// Virtual lights of the multiple scattering (0: none).
    scattered_count: u32,
}

/// The virtual lights of an animated scene follow its geometry: the scene
/// (its lights' GPU order) and the time they were placed for.
struct Moving {
    scene: Scene,
    time: f32,
}

pub struct Airlight {
    push: AirlightPush,
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _layout: DescriptorSetLayout,
    sampler: Sampler,
    scattered: Buffer,
    /// The medium asks for multiple scattering (`Medium::multiple_scattering`).
    multiple_scattering: bool,
    moving: Option<Moving>,
}

impl Airlight {
    /// An airlight pass reading `shadows` (the technique's shadow maps of
    /// `scene`'s lights), with `medium_steps` midpoint steps through
    /// inhomogeneous media (`DirectParams::medium_steps`).
    pub fn new(
        ctx: &Arc<Context>,
        params: &AirlightParams,
        medium_steps: u32,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        shadows: &ShadowMaps,
    ) -> VkResult<Self> {
        let layout = DescriptorSetLayout::of_shaders(ctx, 1, &["passes/airlight.comp"])?;
        // Nearest: shadow.glsl fetches single texels and compares them itself.
        let sampler = Sampler::new(ctx, vk::Filter::NEAREST)?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(b::AIRLIGHT_BINDING_SHADOW_LIGHTS, &shadows.lights);
        let lights = crate::frame::caustic_lights(scene);
        let virtual_lights = scattered_lights(scene, &lights, scene_gpu.geometry_time);
        // Room for every light's rays and strata (a buffer is never empty).
        let capacity = capacity(lights.len()).max(1);
        let mut records = virtual_lights.clone();
        records.resize(capacity as usize, GpuScatteredLight::default());
        let scattered = Buffer::with_data(ctx, "scattered lights", &records, BufferUsage::Storage)?;
        set.write_buffer(b::AIRLIGHT_BINDING_SCATTERED_LIGHTS, &scattered);
        let ms = scene.medium.as_ref().is_some_and(|m| m.multiple_scattering);
        let moving = (ms && scene.is_animated()).then(|| Moving {
            scene: scene.clone(),
            time: scene_gpu.geometry_time,
        });
        let pipeline = ComputePipeline::new(
            ctx,
            "passes/airlight.comp",
            &[&scene_gpu.layout, &layout],
            std::mem::size_of::<AirlightPush>() as u32,
        )?;
        Ok(Self {
            push: AirlightPush {
                light_count: scene.lights.len().min(b::MAX_LIGHTS as usize) as u32,
                lit_count: lights.len() as u32,
                steps: params.airlight_steps,
                medium_steps,
                jitter: params.airlight_jitter,
                scattered_count: virtual_lights.len() as u32,
            },
            pipeline,
            set,
            _layout: layout,
            sampler,
            scattered,
            multiple_scattering: ms,
            moving,
        })
    }

    /// Takes new airlight parameters (both are push constants).
    pub fn set_live(&mut self, params: &AirlightParams) {
        self.push.steps = params.airlight_steps;
        self.push.jitter = params.airlight_jitter;
    }

    /// Whether the pass can follow moved lights in place: not with virtual
    /// lights, which are placed from them (the technique is rebuilt).
    pub fn follows_lights(&self) -> bool {
        !self.multiple_scattering
    }

    /// Records the "airlight" pass: adds L_A (times the airlight component's
    /// weight) to `out`, the frame's radiance, and the multiple scattering
    /// (times the `other` component's). `shadows` must be the maps given
    /// to `new`, already recorded this frame.
    pub fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        shadows: &ShadowMaps,
        out: &Image,
    ) {
        if let Some(m) = self
            .moving
            .as_mut()
            .filter(|m| m.time != scene.geometry_time)
        {
            let lights = crate::frame::caustic_lights(&m.scene);
            let mut records = scattered_lights(&m.scene, &lights, scene.geometry_time);
            self.push.scattered_count = records.len() as u32;
            records.resize(
                (self.scattered.size as usize / std::mem::size_of::<GpuScatteredLight>()).max(1),
                GpuScatteredLight::default(),
            );
            rec.upload(&self.scattered, bytemuck::cast_slice(&records));
            m.time = scene.geometry_time;
        }
        let (width, height) = (out.extent().width, out.extent().height);
        // The shadow maps' attachment writes must be visible to the
        // compute reads (GENERAL layout); `out` is read-modify-written
        // after the pass that wrote the surface radiance.
        rec.pass("airlight")
            .sampled(
                &self.set,
                b::AIRLIGHT_BINDING_SHADOW_MAP,
                &shadows.map,
                &self.sampler,
                Access::ComputeRead,
            )
            .storage_image(
                &self.set,
                b::AIRLIGHT_BINDING_RADIANCE,
                out,
                Access::ComputeWrite,
            )
            .record(|c| {
                let groups = groups_8x8(width, height);
                c.dispatch(
                    &self.pipeline,
                    &[&scene.set, &self.set],
                    bytemuck::bytes_of(&self.push),
                    groups,
                );
            });
    }
}
