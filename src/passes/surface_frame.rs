//! The surface frame: what every technique that draws specular objects over
//! a lit scene composes (image_space, volume_lines, water_photons, and the
//! coming ones), so none of them holds another technique.
//!
//! 1. `record_opaque`: "shadow maps" (every caster, specular ones
//!    included), "gbuffer" of the opaque scene (the specular surfaces left
//!    out), "refractor gbuffer" (the camera's specular G-buffer: nearest
//!    front faces with d_N, farthest back faces), "direct lighting" into the
//!    opaque frame `opaque`.
//! 2. The technique adds its surface caustics to `opaque` (it reads
//!    `gbuffer()` for the receivers).
//! 3. `record_refraction`: "refraction" (`passes::camera_refraction`,
//!    Wyman's two-sided image-space refraction) writes every pixel of the
//!    frame's radiance: the opaque frame where no specular surface is seen,
//!    else what the camera sees in it.
//!
//! Outputs, each valid after the step that writes it: `shadows()`,
//! `gbuffer()`, `specular()` after 1; `opaque()` after 2; the frame's
//! radiance after 3.

use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::camera_refraction::{CameraRefraction, RefractionPush};
use crate::passes::direct_light::{DirectLight, DirectParams};
use crate::passes::gbuffer::{GBuffer, GBufferContents};
use crate::passes::shadow::ShadowMaps;
use crate::passes::specular_gbuffer::SpecularGBuffer;
use crate::scene::{Light, Scene};
use crate::vk::{Context, FrameRecorder, Image, VkResult};
use std::sync::Arc;

pub struct SurfaceFrame {
    /// Direct light on the opaque scene (its G-buffer leaves the specular
    /// surfaces out; they still cast shadows).
    direct: DirectLight,
    /// The opaque frame: direct light (+ the technique's surface caustics)
    /// without the specular surfaces, what the refraction looks up.
    opaque: FrameTargets,
    refraction: CameraRefraction,
}

impl SurfaceFrame {
    /// `refraction`: the camera refraction's push constants (TIR remedy,
    /// Eq. 6.3.2, search steps).
    pub fn new(
        ctx: &Arc<Context>,
        params: &DirectParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
        refraction: RefractionPush,
    ) -> VkResult<Self> {
        let direct = DirectLight::with_contents(
            ctx,
            params,
            scene,
            scene_gpu,
            width,
            height,
            GBufferContents::Opaque,
        )?;
        let opaque = FrameTargets::new(ctx, width, height)?;
        let refraction =
            CameraRefraction::new(ctx, scene_gpu, opaque.radiance.extent(), refraction)?;
        Ok(Self {
            direct,
            opaque,
            refraction,
        })
    }

    /// The opaque scene's G-buffer (positions, normals, materials).
    pub fn gbuffer(&self) -> &GBuffer {
        &self.direct.gbuffer
    }

    /// Every light's shadow maps (every caster).
    pub fn shadows(&self) -> &ShadowMaps {
        &self.direct.shadows
    }

    /// The camera's specular G-buffer (front and back faces).
    pub fn specular(&self) -> &SpecularGBuffer {
        &self.refraction.gbuffer
    }

    /// The opaque frame's radiance (RGBA32F).
    pub fn opaque(&self) -> &Image {
        &self.opaque.radiance
    }

    /// Step 1: shadows, G-buffers, direct light into the opaque frame.
    pub fn record_opaque(&mut self, rec: &mut FrameRecorder, scene: &SceneGpu) -> VkResult<()> {
        self.direct.record(rec, scene, &self.opaque)?;
        self.refraction.draw_gbuffer(rec, scene);
        Ok(())
    }

    /// Step 3: the frame's radiance from the opaque frame and the specular
    /// surfaces.
    pub fn record_refraction(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) {
        self.refraction.record(
            rec,
            scene,
            &self.opaque.radiance,
            &self.direct.gbuffer,
            targets,
        );
    }

    /// Live parameters: PCF radius, the refraction's search steps.
    pub fn set_live(&mut self, params: &DirectParams, search_steps: u32) {
        self.direct.set_live(params);
        self.refraction.set_search_steps(search_steps);
    }

    /// The scene's lights moved (same count and kinds).
    pub fn set_lights(&mut self, lights: &[Light]) -> bool {
        self.direct.set_lights(lights)
    }

    /// The environment rotated (`DirectLight::environment_changed`).
    pub fn environment_changed(&mut self) {
        self.direct.environment_changed();
    }
}
