//! `image_space`: Wyman 2005-06, image-space refraction and caustic maps.
//!
//! 1. The opaque frame (`SurfaceFrame::opaque`): direct light over a G-buffer that
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
//!    (T1), then the exit: by default (`camera_exit` 0) T1 traced through
//!    the BVH to the true second interface (a hybrid: Wyman's exit errs
//!    near silhouettes, docs/architecture/techniques.md); with
//!    `camera_exit` 1 Wyman's: d_V from the back-face depth, d~ by Eq.
//!    6.3.1, p2 = p1 + d~ T1,
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
//! Composed of passes (it holds no other technique): the surface frame
//! (`passes::surface_frame`), the light views (`passes::light_views`) and
//! the caustic map (`passes::caustic_map`, a light-view consumer).
//! Passes: "shadow maps", "gbuffer", "refractor gbuffer", "direct
//! lighting"; "caustic map clear", per light ("light view" in photon modes
//! 1 and 2) "caustic photons" and "caustic splat"; "caustic apply";
//! "refraction" (glsl/passes/camera_refraction.comp).
//! With `caustics_on_change` = 1 the caustic clear, photon and splat passes
//! run only when a light moved (`set_lights`) or the geometry's animation
//! time changed; other frames reuse the last caustic map.
//!
//! Limits: two interfaces only (light inside the glass is never reflected
//! again; the remedies stand in for TIR); the search only finds what the
//! camera sees, and a crossing deeper than one search step (plus a pixel's
//! depth footprint) is taken for a ray passing behind a nearer object;
//! where it finds nothing (a ray that leaves the view, or passes only
//! behind nearer objects) the ray is traced through the BVH instead and
//! the surface it meets shaded with its direct light, without the sky
//! light of an environment table or the surface caustics (screen-space
//! images: an off-screen surface lacks them); glass seen through
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

use super::{CausticSources, Technique, TechniqueBuild};
use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::caustic_map::CausticMap;
pub use crate::passes::caustic_map::ImageSpaceParams;
use crate::passes::light_views::LightViews;
use crate::passes::surface_frame::SurfaceFrame;
use crate::radiometry::Component;
use crate::scene::Scene;
use crate::vk::{Context, FrameRecorder, VkResult};
use std::sync::Arc;

pub struct ImageSpace {
    /// Shadows, G-buffers, direct light on the opaque scene (the specular
    /// surfaces cast shadows and caustics but are left out of it), and the
    /// camera refraction.
    pub surface: SurfaceFrame,
    /// Each light's view of the specular objects (photon texels).
    pub light_views: LightViews,
    pub caustics: CausticMap,
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
        let surface = SurfaceFrame::new(
            ctx,
            &params.direct,
            scene,
            scene_gpu,
            width,
            height,
            params.refraction(),
        )?;
        let light_views = LightViews::new(ctx, scene, scene_gpu, params.photon_buffer_size)?;
        let caustics = params.caustic_map(ctx, scene_gpu, &light_views)?;
        Ok(Self {
            surface,
            light_views,
            caustics,
        })
    }
}

impl TechniqueBuild for ImageSpace {
    const NAME: &'static str = "image_space";
    const DESCRIPTION: &'static str = "Wyman 2005-06: two-sided image-space refraction of what the camera sees through glass (and in mirrors), and caustic maps (photons through the specular objects, Gaussian splats, projected onto diffuse receivers)";
    const COMPONENTS: &'static [Component] = &[
        Component::Direct,
        Component::SurfaceCaustics,
        Component::Emitted,
    ];
    const CAUSTIC_SOURCES: CausticSources = CausticSources::All;
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

    /// Area lights become point stand-ins, within their size limit.
    fn check_scene(scene: &Scene) -> anyhow::Result<()> {
        super::check_materials(scene, Self::NAME)?;
        super::check_no_mixed(scene, Self::NAME)?;
        crate::frame::check_stand_ins(scene, Self::NAME).map_err(anyhow::Error::msg)
    }

    fn update_live(&mut self, params: &ImageSpaceParams) -> bool {
        self.set_live(params);
        true
    }
}

impl ImageSpace {
    /// Takes the live parameters of `params`.
    pub fn set_live(&mut self, params: &ImageSpaceParams) {
        self.surface.set_live(&params.direct, params.search_steps);
        self.caustics.set_on_change(params.caustics_on_change);
    }
}

impl Technique for ImageSpace {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) -> VkResult<()> {
        self.surface.record_opaque(rec, scene)?;
        // The caustic map's passes only add surface caustics
        // (`SceneGpu::draws`); a skipped map is not marked current.
        if scene.draws(Component::SurfaceCaustics) {
            if self.caustics.needs_update(scene) {
                self.caustics.begin(rec, scene, &self.light_views)?;
                self.light_views
                    .record(rec, scene, &mut [&mut self.caustics]);
            }
            self.caustics
                .apply(rec, scene, self.surface.gbuffer(), self.surface.opaque());
        }
        self.surface.record_refraction(rec, scene, targets);
        Ok(())
    }

    fn set_lights(&mut self, lights: &[crate::scene::Light]) -> bool {
        self.caustics.invalidate();
        self.surface.set_lights(lights) && self.light_views.set_lights(lights)
    }
}
