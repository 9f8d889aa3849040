//! `volume_lines`: line-based volume caustics in single-scattering media
//! (Hu, Dong, Ihrke, Grosch, Yuan, Seidel 2010, "Interactive Volume Caustics in
//! Single-Scattering Media"), over image_space's surface frame.
//!
//! The frame is Hu's Fig. 2 sum: C (surface radiance with surface caustics
//! and what the camera sees through glass) is `image_space`'s frame as it
//! is (the same building blocks: `passes::surface_frame`,
//! `passes::caustic_map`); B (light scattered once in the medium after one or more specular
//! events, the reference's L S+ V) is added by this module's passes, per
//! light:
//! 1. "light view" (`passes::light_views`): the light's view of the
//!    specular objects (the frustum fitted to them; orthographic for
//!    directional light), front and back faces (Sect. 5.1, step 1); drawn
//!    once for the caustic map's photons and these rays when both have the
//!    same resolution (`photon_buffer_size` = `volume_buffer_size`).
//! 2. "volume segments" (glsl/volume_lines/segments.comp): per texel of that
//!    view, one-bounce reflection (mirrors) or two-bounce refraction
//!    (Wyman's two-sided refraction, shared with `image_space`) gives the
//!    exit point p1 and direction w'_l; p2 is the first diffuse surface
//!    along it (BVH; the scene's bounding sphere where it leaves). Stored
//!    with its flux Phi = I Omega_texel T0 T1 tau_glass tau(s, p0) in the
//!    volume caustic buffer (`GpuSegment`, one per texel, invalid ones
//!    flagged), followed by a second N x N half holding the Fresnel
//!    reflection F0 off a dielectric's front face (a one-bounce
//!    reflection; both are L S+ V; `front_reflection` = 0 leaves it
//!    undrawn). Each ray is clipped to the medium's bounds, with a margin
//!    of two pixels' footprint plus r so the line's rasterised end cuts
//!    nothing that scatters.
//! 3. "volume lines": one point per buffer entry (`vkCmdDraw`, vertex pulling); the
//!    geometry shader emits the camera-space line p1 -> p2; the fragment
//!    shader evaluates Eq. 3 with the regular-step resampling of Fig. 5 and
//!    blends additively into `volume` (RGBA32F; alpha counts fragments).
//!    Radiometry (glsl/volume_lines/lines.glsl has the derivation): a line
//!    is a beam x beam kernel, L = sigma_s p tau Phi / (w_world sin theta),
//!    w_world the width in metres, perpendicular to both rays, of the
//!    line's rasterised footprint (1 px wide, rectangular or parallelogram
//!    depending on the device's `strictLines`), redistributed over the
//!    ray-marching points k Delta_x within the filter support r of x_l
//!    with normalised Gaussian weights. No scale factor. This is how Eq. 3's
//!    L_in Delta_omega Delta_x is made radiometric (the issue's "Delta_omega
//!    from the light's radiometry"): L_in Delta_omega is the irradiance of
//!    the light tube, Phi over its cross-section, and the line's kernel
//!    over the beam-to-ray distance integrates the tube along the viewing
//!    ray; Delta_x then only picks where along the ray the contribution
//!    lands (Fig. 5's resampling), not how much, so the energy does not
//!    depend on Delta_x (as long as r >= Delta_x / 2, so that every line
//!    reaches a step point).
//!
//! Once per frame: "volume visibility" (the distance to the first surface,
//! diffuse or specular, per pixel: Sect. 5.3's culling; refractors hide the
//! volume caustic behind them) before the lines, "volume composite" (adds B
//! to the frame) after them.
//!
//! Homogeneous media use exact transmittance, with fragments compiled
//! without the density field (lines.frag; on a CPU rasteriser that code
//! made them 2.4x slower); inhomogeneous ones (noise, grid) a
//! `transmittance_steps`-point midpoint rule (lines_heterogeneous.frag,
//! Sect. 5.4).
//!
//! Cost: the lines pass is fragment-bound; fragments grow with buffer
//! texels x screen side (BENCHMARKS.md). The front-face reflections cross
//! the whole medium and make most of the fragments.
//!
//! Checked (tests/suite/volume_lines.rs): the image's energy against a CPU
//! integral of the same light rays within 0.3%, HG's g = +-0.7 ratio
//! within 1e-4, and against the reference's L S+ V on volume_cone and
//! smoke (+1.4% to +3.2% energy; +16% at g = -0.7, see below).
//!
//! Limits: two interfaces (light reflected inside the glass is not
//! drawn); near a sphere's rim Eq. 6.3.1's exit meets a total internal
//! reflection the sphere does not have, and the default remedy (clamp)
//! sends those rays out tangentially (the main excess at g = -0.7); one
//! segment per texel (no chains of several objects); p2 comes from the
//! BVH, not from a light-space depth map as in Hu; lines with a
//! parallelogram rasteriser (no `strictLines`) assume the one-fragment-
//! per-column rule, not verified here (lavapipe has strict lines); the camera sees no volume caustic through glass or
//! in mirrors (Sect. 5.3; the reference cannot show those paths either);
//! a point light inside the specular objects' bounding sphere gets no
//! volume caustic (logged).
//!
//! A (airlight and volumetric shadows, the reference's L V) is
//! `passes::airlight`, recorded last ("airlight"): a ray march along each
//! camera ray with the shadow maps of C (every caster, glass included),
//! added to the frame. So the whole frame is Hu's D = A + B + C, and
//! `--component` writes each alone (direct and surface_caustics are C's
//! two parts, airlight is A, volume_caustics is B).

pub mod bindings;
mod lines;

pub use lines::{GpuSegment, VolumeRays};

use super::{CausticSources, Technique, TechniqueBuild};
use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::airlight::{Airlight, AirlightParams};
use crate::passes::caustic_map::{CausticMap, ImageSpaceParams};
use crate::passes::light_views::{LightViewConsumer, LightViews};
use crate::passes::surface_frame::SurfaceFrame;
use crate::radiometry::Component;
use crate::scene::{Light, Scene};
use crate::vk::{Context, FrameRecorder};
use lines::RaySettings;
use std::sync::Arc;

crate::declare_params! {
    /// `volume_lines`' parameters: image_space's (passed through to C,
    /// whatever they are) and the airlight's (A), then B's own.
    pub struct VolumeLinesParams {
        @group image_space: ImageSpaceParams;
        @group airlight: AirlightParams;
        volume_buffer_size: u32 [64, 2048] = 512, rebuild,
            "volume caustic buffer resolution (light rays per side of the light's view of the specular objects)";
        ray_step: f32 [0.005, 5.0] = 0.2, rebuild,
            "Delta_x (m): the regular ray-marching step the line contributions are redistributed to (Hu Eq. 3, Fig. 5)";
        filter_radius: f32 [0.005, 5.0] = 0.2, rebuild,
            "r (m): support of the normalised Gaussian that spreads a line's contribution over the step points (Hu uses r = Delta_x; at most 16 Delta_x; below Delta_x / 2 some lines reach no step point and are lost)";
        transmittance_steps: u32 [1, 64] = 4, rebuild,
            "midpoint-rule samples per transmittance integral in inhomogeneous media (Hu Sect. 5.4; homogeneous media are exact)";
        front_reflection: bool [0, 1] = 1, rebuild,
            "1: also draw the light reflected off a dielectric's front face (Fresnel F0; part of L S+ V, 14% of volume_cone's volume caustic at g = 0, but long lines across the whole medium: most of the fragments); 0: Hu's two-bounce refraction only";
    }
}

/// Most regular step points a fragment visits (glsl/volume_lines/lines.frag).
const MAX_RADIUS_IN_STEPS: f32 = 16.0;

pub struct VolumeLines {
    /// C's frame: shadows, G-buffers, direct light, camera refraction.
    pub surface: SurfaceFrame,
    /// C's surface caustics, added to the surface frame's opaque frame.
    pub caustics: CausticMap,
    /// Each light's view of the specular objects at `volume_buffer_size`
    /// (the caustic map's too when `photon_buffer_size` is the same).
    pub light_views: LightViews,
    /// The caustic map's light views when its resolution differs.
    caustic_views: Option<LightViews>,
    /// B: the light rays, their lines, the volume caustic image.
    pub rays: VolumeRays,
    /// A: airlight with volumetric shadows from C's shadow maps.
    pub airlight: Airlight,
}

impl VolumeLines {
    pub fn new(
        ctx: &Arc<Context>,
        params: &VolumeLinesParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        let step = params.ray_step;
        let radius = params.filter_radius;
        if radius > MAX_RADIUS_IN_STEPS * step {
            anyhow::bail!(
                "--param filter_radius={radius}: must be at most {MAX_RADIUS_IN_STEPS} x ray_step ({})",
                MAX_RADIUS_IN_STEPS * step
            );
        }
        let c = &params.image_space;
        let surface = SurfaceFrame::new(
            ctx,
            &c.direct,
            scene,
            scene_gpu,
            width,
            height,
            c.refraction(),
        )?;
        let light_views = LightViews::new(ctx, scene, scene_gpu, params.volume_buffer_size)?;
        let caustic_views = if c.photon_buffer_size == params.volume_buffer_size {
            None
        } else {
            Some(LightViews::new(
                ctx,
                scene,
                scene_gpu,
                c.photon_buffer_size,
            )?)
        };
        let caustics = c.caustic_map(
            ctx,
            scene_gpu,
            caustic_views.as_ref().unwrap_or(&light_views),
        )?;
        let airlight = Airlight::new(
            ctx,
            &params.airlight,
            c.direct.medium_steps,
            scene,
            scene_gpu,
            surface.shadows(),
        )?;
        let rays = VolumeRays::new(
            ctx,
            &RaySettings {
                buffer_size: params.volume_buffer_size,
                step,
                radius,
                transmittance_steps: params.transmittance_steps,
                front_reflection: params.front_reflection,
                tir_remedy: c.tir_remedy,
                eq_6_3_2: c.eq_6_3_2,
            },
            scene,
            scene_gpu,
            width,
            height,
        )?;
        Ok(Self {
            surface,
            caustics,
            light_views,
            caustic_views,
            rays,
            airlight,
        })
    }
}

impl TechniqueBuild for VolumeLines {
    const NAME: &'static str = "volume_lines";
    const DESCRIPTION: &'static str = "Hu et al. 2010: volume caustics as lines (light rays after one reflection or two refractions, drawn by a geometry shader, Eq. 3 per fragment), plus ray-marched airlight with volumetric shadows, over image_space's surface radiance attenuated by the medium";
    const COMPONENTS: &'static [Component] = &[
        Component::Direct,
        Component::SurfaceCaustics,
        Component::Airlight,
        Component::VolumeCaustics,
        Component::Other,
        Component::Emitted,
    ];
    const CAUSTIC_SOURCES: CausticSources = CausticSources::All;
    type Params = VolumeLinesParams;

    fn build(
        ctx: &Arc<Context>,
        params: &VolumeLinesParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        Self::new(ctx, params, scene, scene_gpu, width, height)
    }

    /// Area lights become point stand-ins, within their size limit.
    fn check_scene(scene: &Scene) -> anyhow::Result<()> {
        super::check_materials(scene, Self::NAME)?;
        super::check_no_mixed(scene, Self::NAME)?;
        crate::frame::check_stand_ins(scene, Self::NAME).map_err(anyhow::Error::msg)
    }

    fn update_live(&mut self, params: &VolumeLinesParams) -> bool {
        let c = &params.image_space;
        self.surface.set_live(&c.direct, c.search_steps);
        self.caustics.set_on_change(c.caustics_on_change);
        self.airlight.set_live(&params.airlight);
        true
    }
}

impl Technique for VolumeLines {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) -> crate::vk::VkResult<()> {
        self.surface.record_opaque(rec, scene)?;
        // The caustic map only adds surface caustics and B's rays only
        // volume caustics: each runs only when its component is drawn
        // (`SceneGpu::draws`; a skipped map is not marked current).
        let surface = scene.draws(Component::SurfaceCaustics);
        let rays = scene.draws(Component::VolumeCaustics);
        if rays {
            self.rays.begin(rec, scene, &self.surface, targets);
        }
        let caustics = surface && self.caustics.needs_update(scene);
        if caustics {
            let views = self.caustic_views.as_ref().unwrap_or(&self.light_views);
            self.caustics.begin(rec, scene, views)?;
        }
        // One loop over the lights for the caustic map's photons and B's
        // rays when they share a resolution (one light view each).
        let mut consumers: Vec<&mut dyn LightViewConsumer> = Vec::with_capacity(2);
        if caustics {
            match &self.caustic_views {
                Some(views) => views.record(rec, scene, &mut [&mut self.caustics]),
                None => consumers.push(&mut self.caustics),
            }
        }
        if rays {
            consumers.push(&mut self.rays);
        }
        if !consumers.is_empty() {
            self.light_views.record(rec, scene, &mut consumers);
        }
        if surface {
            self.caustics
                .apply(rec, scene, self.surface.gbuffer(), self.surface.opaque());
        }
        self.surface.record_refraction(rec, scene, targets);
        if rays {
            self.rays.composite(rec, scene, targets);
        }
        // A: single scattering straight from the lights, shadowed by every
        // object (the shadow maps C recorded this frame).
        self.airlight
            .record(rec, scene, self.surface.shadows(), &targets.radiance);
        Ok(())
    }

    fn set_lights(&mut self, lights: &[Light]) -> bool {
        self.caustics.invalidate();
        self.airlight.follows_lights()
            && self.surface.set_lights(lights)
            && self.light_views.set_lights(lights)
            && self
                .caustic_views
                .as_mut()
                .is_none_or(|v| v.set_lights(lights))
    }
}
