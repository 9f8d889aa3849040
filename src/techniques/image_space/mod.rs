//! `image_space`: Wyman 2005-06, image-space refraction and caustic maps.
//!
//! 1. The opaque frame (`opaque`): the `direct` passes over a G-buffer that
//!    leaves the specular surfaces out (they still cast shadows: the shadow
//!    maps hold every caster), plus, on diffuse receivers, L = albedo / pi *
//!    E_caustic from the caustic map (`passes::caustic_map`): the light the
//!    specular objects redirect, which includes the light their shadow
//!    removed, so with IOR 1 the shadow is filled back in.
//! 2. What the camera sees in the specular objects (`refraction`), Wyman's
//!    two-sided image-space refraction: the camera's specular G-buffer
//!    (`passes::specular_gbuffer`: nearest front faces with the per-vertex
//!    d_N interpolated, farthest back faces: Wyman's preferred second
//!    interface for non-convex refractors); per pixel, Snell at the front
//!    (T1), d_V from the back-face depth, d~ by Eq. 6.3.1, p2 = p1 + d~ T1,
//!    N2 from the back-face normal texture at p2's projection (Eq. 6.3.2
//!    where the texel is empty), Snell again (T2) with the selected TIR
//!    remedy; T2 and the Fresnel reflection ray are searched in the opaque
//!    frame's depth (linear steps, then bisection) and read its radiance:
//!    L = F1 L_reflected + (1 - F1)(1 - F2) exp(-sigma_a d~) L_behind.
//!    Mirrors: L = reflectance * L_reflected by the same search.
//!    The refraction math is glsl/common/image_space_refraction.glsl,
//!    shared with the caustic photons of `photon_mode` 1 (Wyman: "render
//!    the specular objects from the light ... with the same code").
//!
//! Passes: "shadow maps", "gbuffer", "direct lighting"; "caustic map
//! clear", per light ("caustic light view" in photon modes 1 and 2)
//! "caustic photons" and "caustic splat"; "caustic apply"; "refractor
//! gbuffer"; "refraction" (glsl/image_space/refraction.comp).
//! With `caustics_on_change` = 1 the caustic clear, photon and splat passes
//! run only when a light moved (`set_lights`) or the geometry's animation
//! time changed; other frames reuse the last caustic map.
//!
//! Limits: two interfaces only (light inside the glass is never reflected
//! again; the remedies stand in for TIR); rays that leave the view or the
//! scene's bounding sphere read the environment, which is black (scene
//! files have no background; the reference also gives escaping rays 0);
//! the search only finds what the camera sees (no surface hidden behind
//! another or off screen), and a crossing deeper than one search step (plus
//! a pixel's depth footprint) is taken for a ray passing behind a nearer
//! object; glass seen through
//! glass (nested or overlapping refractors) is not refracted twice: the
//! opaque frame has no specular surfaces. Open sheets (water: a dielectric
//! with no back surface, i.e. an empty back-face texel and d_N = 0) are one
//! interface: Snell once at p1, L = F1 L_reflected + (1 - F1)/n^2
//! exp(-sigma_a t) L_behind (radiance leaving the medium into air), and
//! photon modes 1 and 2 refract such photons once and land them through
//! the BVH; a camera below the sheet sees it as a back face, not refracted
//! (the opaque frame). Diffuse geometry occludes in the specular G-buffer's
//! front pass, so glass behind an opaque object is not drawn over it; the
//! back pass ignores diffuse geometry and keeps the farthest back face of
//! any refractor, so two refractors one behind the other (with or without
//! an opaque object between) share one back-face texture.

mod refraction;

pub use refraction::{CameraRefraction, RefractionPush};

use super::direct::{Direct, DirectParams};
use super::{Technique, TechniqueBuild};
use crate::frame::{FrameTargets, SceneGpu};
use crate::params::{ParamSet, Params};
use crate::passes::caustic_map::{CausticMap, PhotonPaths};
use crate::passes::gbuffer::GBufferContents;
use crate::radiometry::Component;
use crate::scene::Scene;
use crate::shader_bindings as b;
use crate::vk::{
    barrier, Access, BindingKind, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    FrameRecorder, ImageAccess, Sampler, VkResult,
};
use ash::vk;
use std::sync::Arc;

crate::declare_params! {
    /// `image_space`'s parameters: `Direct`'s, then the caustic map's and
    /// the camera refraction's.
    pub struct ImageSpaceParams {
        @group direct: DirectParams;
        photon_buffer_size: u32 [64, 1024] = 512, rebuild,
            "photon buffer resolution (photons per side of the light view)";
        caustic_map_size: u32 [64, 1024] = 512, rebuild,
            "caustic map resolution per light view (texels per side)";
        splat_size: u32 [1, 15] = 7, rebuild,
            "photon splat width in caustic-map texels (odd; an even value is raised by 1)";
        photon_mode: u32 [0, 2] = 0, rebuild,
            "0: photon paths traced exactly through the BVH; 1: Wyman's two-sided image-space refraction from light-space front/back G-buffers (Eq. 6.3.1 distance); 2: the same G-buffers, the refracted ray marched against the back-face map (exact for convex objects)";
        tir_remedy: u32 [0, 2] = 1, rebuild,
            "total internal reflection at the approximated exit (Wyman 2006's ad hoc remedies; camera and photon_mode 1): 0 single refraction (T2 = T1), 1 clamp to the critical angle (T2 tangent to the back face), 2 reflect and ignore the refractor. Default 1, of the two Wyman recommends (the first 'behaves poorly in dynamic scenes'): a reflected ray heads back toward the camera or the light, where the image-space search has no data and photons fly up past the light, while the clamped ray goes on through, as the light does on average";
        eq_6_3_2: u32 [0, 1] = 1, rebuild,
            "1: where d~ overshoots and the back-face texel holds no normal, use Wyman's Eq. 6.3.2 (N2 = T1 - (V.T1) V, the exit through the side); 0: drop the transmitted light there";
        search_steps: u32 [4, 256] = 32, live,
            "linear steps of the image-space search of refracted and reflected camera rays against the opaque frame (then 10 bisections)";
        caustics_on_change: bool [0, 1] = 0, live,
            "1: recompute the caustic map only when a light moved or animated geometry changed, reusing the last one otherwise; 0: every frame (benchmarks)";
    }
}

pub struct ImageSpace {
    /// Direct light on the opaque scene (its G-buffer leaves the specular
    /// surfaces out; they still cast shadows and caustics).
    pub direct: Direct,
    pub caustics: CausticMap,
    /// The opaque frame: direct light + surface caustics without the
    /// specular surfaces, what the refraction pass looks up.
    pub opaque: FrameTargets,
    pub refraction: CameraRefraction,
    apply: ComputePipeline,
    set: DescriptorSet,
    /// `caustics_on_change`: reuse the caustic map while nothing it depends
    /// on moved (Wyman 2006, "Putting it Together": "we only update the
    /// caustic map after changes to the light or scene geometry").
    caustics_on_change: bool,
    /// Geometry time the caustic map was computed for; `None` when it must
    /// be recomputed (never computed, or a light moved).
    caustics_geometry_time: Option<f32>,
    _layout: DescriptorSetLayout,
    _sampler: Sampler,
}

impl ImageSpace {
    pub fn new(
        ctx: &Arc<Context>,
        params: &ImageSpaceParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> VkResult<Self> {
        let direct = Direct::with_contents(
            ctx,
            &params.direct,
            scene,
            scene_gpu,
            width,
            height,
            GBufferContents::Opaque,
        )?;
        let opaque = FrameTargets::new(ctx, width, height)?;
        let tir_remedy = params.tir_remedy;
        let use_eq632 = params.eq_6_3_2;
        let caustics = CausticMap::new(
            ctx,
            scene,
            scene_gpu,
            params.photon_buffer_size,
            params.caustic_map_size,
            params.splat_size,
            PhotonPaths {
                mode: params.photon_mode,
                tir_remedy,
                use_eq632: use_eq632 != 0,
                medium_steps: params.direct.medium_steps,
            },
        )?;
        let layout = DescriptorSetLayout::new(
            ctx,
            &[
                (b::CAUSTIC_BINDING_VIEWS, BindingKind::Uniform),
                (b::CAUSTIC_BINDING_MAP, BindingKind::Sampled),
                (b::CAUSTIC_BINDING_POSITION, BindingKind::StorageImage),
                (b::CAUSTIC_BINDING_NORMAL, BindingKind::StorageImage),
                (b::CAUSTIC_BINDING_ALBEDO, BindingKind::StorageImage),
                (b::CAUSTIC_BINDING_RADIANCE, BindingKind::StorageImage),
            ],
        )?;
        let sampler = Sampler::new(ctx, vk::Filter::NEAREST)?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(b::CAUSTIC_BINDING_VIEWS, &caustics.views)
            .write_sampled_image(
                b::CAUSTIC_BINDING_MAP,
                &caustics.map,
                &sampler,
                vk::ImageLayout::GENERAL,
            )
            .write_storage_image(b::CAUSTIC_BINDING_POSITION, &direct.gbuffer.position)
            .write_storage_image(b::CAUSTIC_BINDING_NORMAL, &direct.gbuffer.normal)
            .write_storage_image(b::CAUSTIC_BINDING_ALBEDO, &direct.gbuffer.albedo)
            .write_storage_image(b::CAUSTIC_BINDING_RADIANCE, &opaque.radiance);
        let apply = ComputePipeline::new(
            ctx,
            "caustic_map/apply.comp",
            &[&scene_gpu.layout, &layout],
            size_of::<[u32; 2]>() as u32,
        )?;
        let refraction = CameraRefraction::new(
            ctx,
            scene_gpu,
            &opaque.radiance,
            &direct.gbuffer,
            RefractionPush {
                tir_remedy,
                use_eq632,
                search_steps: params.search_steps,
                pad: 0,
            },
        )?;
        Ok(Self {
            direct,
            caustics,
            opaque,
            refraction,
            apply,
            set,
            caustics_on_change: params.caustics_on_change,
            caustics_geometry_time: None,
            _layout: layout,
            _sampler: sampler,
        })
    }
}

impl TechniqueBuild for ImageSpace {
    const NAME: &'static str = "image_space";
    const DESCRIPTION: &'static str = "Wyman 2005-06: two-sided image-space refraction of what the camera sees through glass (and in mirrors), and caustic maps (photons through the specular objects, Gaussian splats, projected onto diffuse receivers)";
    const COMPONENTS: &'static [Component] = &[Component::Direct, Component::SurfaceCaustics];
    type Params = ImageSpaceParams;

    fn build(
        ctx: &Arc<Context>,
        params: &ImageSpaceParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        Ok(Self::new(ctx, params, scene, scene_gpu, width, height)?)
    }
}

impl ImageSpace {
    /// Takes the live parameters of `params`.
    pub fn set_live(&mut self, params: &ImageSpaceParams) {
        self.direct.set_live(&params.direct);
        self.refraction.set_search_steps(params.search_steps);
        if params.caustics_on_change != self.caustics_on_change {
            self.caustics_on_change = params.caustics_on_change;
            self.caustics_geometry_time = None;
        }
    }
}

impl Technique for ImageSpace {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn update_live(&mut self, params: &Params) -> anyhow::Result<bool> {
        self.set_live(&ImageSpaceParams::from_params(params)?);
        Ok(true)
    }

    fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) -> VkResult<()> {
        self.direct.record(rec, scene, &self.opaque)?;
        if !self.caustics_on_change || self.caustics_geometry_time != Some(scene.geometry_time) {
            self.caustics.record(rec, scene)?;
            self.caustics_geometry_time = Some(scene.geometry_time);
        }
        let ctx = rec.ctx().clone();
        // apply.comp's push constants: light count, medium steps.
        let push = [self.caustics.light_count(), self.caustics.medium_steps];
        rec.pass("caustic apply", |cmd| {
            // The splats' attachment writes and the direct pass's radiance
            // writes must be visible to this read-modify-write.
            barrier(
                &ctx,
                cmd,
                &[
                    ImageAccess::new(&self.caustics.map, Access::ComputeRead),
                    ImageAccess::new(&self.direct.gbuffer.position, Access::ComputeRead),
                    ImageAccess::new(&self.direct.gbuffer.normal, Access::ComputeRead),
                    ImageAccess::new(&self.direct.gbuffer.albedo, Access::ComputeRead),
                    ImageAccess::new(&self.opaque.radiance, Access::ComputeWrite),
                ],
                &[],
            );
            let groups = [targets.width.div_ceil(8), targets.height.div_ceil(8), 1];
            self.apply.dispatch(
                cmd,
                &[&scene.set, &self.set],
                bytemuck::bytes_of(&push),
                groups,
            );
        });
        self.refraction.record(
            rec,
            scene,
            &self.opaque.radiance,
            &self.direct.gbuffer,
            targets,
        );
        Ok(())
    }

    fn set_lights(&mut self, lights: &[crate::scene::Light]) -> bool {
        self.caustics_geometry_time = None;
        self.direct.set_lights(lights) && self.caustics.set_lights(lights)
    }
}
