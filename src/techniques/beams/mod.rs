//! `beams`: adaptive caustic beams, surface and volume caustics in
//! single-scattering media (Liktor & Dachsbacher 2011, "Real-Time Volume
//! Caustics with Adaptive Beam Tracing"), over the shared surface frame.
//!
//! The frame is the paper's Fig. 8 sum, composed as `volume_lines` composes
//! Hu's: the surface radiance (direct light from `passes::surface_frame`
//! plus the beams' surface caustics, attenuated by the medium toward the
//! eye), + airlight with volumetric shadows (`passes::airlight`), + the
//! beams' volume caustics. Components `direct`, `surface_caustics`,
//! `airlight`, `volume_caustics`, each writable alone.
//!
//! Per light (`passes::light_views`, the one per-light loop):
//! 1. "light view": the light's front/back G-buffer of the specular objects
//!    (Sect. 4.1's "caustic geometry buffers"; perspective from a point or
//!    spot light, orthographic along a directional one).
//! 2. "beam grid" + "beam refine" x (levels + 1) (glsl/beams/refine.comp):
//!    the hierarchical projected grid (Sect. 4.1, `grid_size`^2 cells of two
//!    triangles) refined adaptively (Sect. 4.2: discontinuity, focus or
//!    energy, camera proximity) by one compute dispatch per level. The
//!    paper's geometry shader with stream-out becomes its modern
//!    equivalent: compute passes appending children and beams through
//!    atomic counters, each next level and the draw sized by indirect
//!    arguments a one-thread pass (args.comp) writes from the counters.
//!    Final triangles become beams (Sects. 4.3, 6): the base at the first
//!    specular interaction, edges by reflection and by two-sided
//!    refraction (exactly through the BVH by default, or Wyman's
//!    image-space exit through the back faces of the light's G-buffer:
//!    `refraction`), Fresnel splitting the flux; flux from the light's
//!    radiometry (point: I times the exact solid angle of the base
//!    triangle; spot: the integral of I over it; directional: E times the
//!    projected area), times Fresnel and Beer-Lambert absorption and the
//!    medium's transmittance from the light; the area function A(y).
//! 3. "beam volumes" (volume.vert/geom/frag, where the scene has a
//!    medium): one point per beam, drawn indirect; the geometry shader
//!    extrudes the beam's bounding volume (Ernst's prism, or the tight
//!    six-triangle hull with the prism as fallback, `volume`), emitting
//!    only back faces so each covered pixel gets one fragment; the fragment
//!    integrates the in-scattering over the camera ray's exact interval
//!    inside the beam (Sect. 5, Gauss-Legendre, `quadrature` points) into
//!    the volume target.
//! 4. "beam caustics" (volume.vert, caustic.geom/frag): the surface
//!    caustics as caustic triangles, a flux-conserving gather. A beam
//!    whose three edge rays meet one diffuse surface (refine.comp records
//!    the heights of their hits; a beam whose edges meet different
//!    surfaces, or only some of them meet one, is split like a
//!    discontinuity) has a footprint there, the triangle of the hits. Its
//!    screen bounding box grown by half a pixel is drawn as one quad (a
//!    conservative rasterisation: every pixel the footprint touches gets
//!    exactly one fragment, however small the footprint), and each
//!    fragment deposits the beam's flux times the fraction of the
//!    footprint's area inside the pixel's footprint on the footprint's
//!    plane (an exact polygon clip, footprint.glsl / caustic.frag), where
//!    the pixel sees that surface, the light arrives on its seen side and
//!    no diffuse surface blocks the beam (a BVH ray to the base), times
//!    the medium's transmittance along the beam. Pixel footprints tile
//!    the plane, so the shares of a beam sum to its flux: the issue's
//!    E = Phi |d . n_r| / (A(y) |d . n_Delta|) integrated over the pixel
//!    instead of sampled at its centre, and the surface caustic's energy
//!    does not depend on the image size (a focus a few pixels wide, or a
//!    beam smaller than a pixel, keeps its flux). "beam apply" divides
//!    each pixel's flux by its footprint's area on the receiver (from the
//!    camera G-buffer's depth and normal): the mean irradiance over the
//!    pixel. Within one beam the flux is spread uniformly over the
//!    footprint (as the paper's one area function per beam spreads it
//!    over a cross-section), so the variation of E inside a beam is what
//!    refinement resolves. This replaced a point-sampled gather (each
//!    beam's E at the pixel centres' receiver points, in the volumes'
//!    fragments), whose energy on `ball_lens` swung with the image size
//!    (-43% to +42%, BENCHMARKS.md).
//!
//! Per frame: "beam receivers" and "beam clear" before the lights, "beam
//! filter" (the paper's optional low-pass filter of the surface caustics,
//! `surface_filter`, on the deposited flux, which it keeps), "beam apply"
//! (surface caustics into the opaque frame) before the camera
//! refraction, "beam composite" (volume caustics) after it, "airlight"
//! last. Counters (beams and triangles per level, the dropped fraction,
//! volume and caustic fragments) go to `bench --json` through `counters`.
//!
//! Multiple bounces (Sect. 6, `bounces`): a beam whose three edge rays
//! meet one further specular object ends there (its extrusion stops at
//! that surface, and it has no caustic triangle) and spawns that surface's
//! reflected and refracted beams (Fresnel split, refraction traced through
//! the BVH with Beer-Lambert absorption), each child recording its parent
//! (`GpuBeam::parent`); a beam only partly meeting it splits its triangle,
//! and at the last level passes the object as a one-bounce beam.
//!
//! Limits (documented): the flux is uniform across a beam (one area function
//! per beam, as in the paper; Fresnel and absorption factors averaged over
//! its three vertices); the beam's base plane is normal to the mean edge
//! direction rather than the surface triangle (an equivalent beam space
//! that stays valid after two refractions); area lights are point stand-ins
//! (small rects only, `check_scene`). Surface caustics: the footprint is
//! the straight triangle of the edge hits (on a curved receiver, the
//! chord; a pixel receives where its receiver lies within 1% of its
//! distance plus a tenth of the triangle's size of that plane); a beam
//! still crossing a receiver's edge at the last level deposits nothing,
//! nor does the part of a footprint hidden from the camera; a degenerate
//! footprint (a focus exactly on the receiver) goes whole to the pixel
//! holding its centroid.

pub mod bindings;
mod tracer;

pub use tracer::{BeamCounts, BeamTracer, GpuBeam};

use super::{CausticSources, Technique, TechniqueBuild};
use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::airlight::{Airlight, AirlightParams};
use crate::passes::camera_refraction::RefractionPush;
use crate::passes::direct_light::DirectParams;
use crate::passes::light_views::LightViews;
use crate::passes::surface_frame::SurfaceFrame;
use crate::radiometry::Component;
use crate::scene::{Light, Scene};
use crate::vk::{Context, FrameRecorder};
use std::sync::Arc;

crate::declare_params! {
    /// `beams`' parameters: the surface frame's and the airlight's, then
    /// the beams' own (Sects. 4-5).
    pub struct BeamsParams {
        @group direct: DirectParams;
        @group airlight: AirlightParams;
        light_view_size: u32 [64, 2048] = 512, rebuild,
            "light-space G-buffer resolution (texels per side) the projected grid's vertices sample";
        grid_size: u32 [2, 64] = 16, rebuild,
            "base projected grid: cells per side of the light's view (Sect. 4.1; two triangles per cell)";
        levels: u32 [0, 5] = 3, rebuild,
            "adaptive refinement levels (Sect. 4.2; 0: the regular grid alone)";
        split_depth: f32 [0.001, 10.0] = 0.05, rebuild,
            "split (a): depths (distance from the light) of a triangle's vertices differing by more than this fraction (a silhouette: dropped at the last level)";
        split_normal: f32 [0.1, 180.0] = 15.0, rebuild,
            "split (a): normals of a triangle's vertices differing by more than this angle (degrees)";
        split_focus: f32 [0.0, 1.0] = 0.1, rebuild,
            "split (b): the beam converges, its smallest cross-section |A(y)| below this fraction of its base's";
        split_energy: f32 [0.0, 1.0] = 0.005, rebuild,
            "split (b): the beam carries more than this fraction of the flux of the light's whole view";
        split_camera: f32 [0.0, 10.0] = 0.05, rebuild,
            "split (c): the beam's cross-section at its central ray's point closest to the camera spans more than this angle (radians)";
        extrusion_cutoff: f32 [0.0, 1.0] = 0.0, rebuild,
            "energy cut-off of the extrusion (Sect. 4.3): a divergent beam ends where its flux density falls below this fraction of its base's (0: beams end at the first diffuse surface or the medium's bounds only)";
        surface_filter: u32 [0, 8] = 0, rebuild,
            "low-pass filter of the surface caustics (Sect. 7): Gaussian radius in pixels over receivers of one surface (0: off)";
        volume: u32 [0, 1] = 1, rebuild,
            "bounding volumes (Sect. 4.3): 0 Ernst's prism, 1 the tight six-triangle hull (prism where it is not convex)";
        quadrature: u32 [1, 4] = 3, rebuild,
            "Gauss-Legendre points per interval of a camera ray inside a beam (Sect. 5)";
        refraction: u32 [0, 1] = 1, rebuild,
            "two-sided refraction (Sect. 6): 1 exactly through the BVH (internal total reflections followed; the exact intersection the paper's distance impostor approximates), 0 Wyman's image-space exit through the light view's back faces (approximate: its false total internal reflection near a sphere's rim throws light out sideways)";
        bounces: u32 [1, 3] = 2, rebuild,
            "specular events per beam path (Sect. 6): a beam whose edge rays all meet a further specular object ends there and spawns its reflected / refracted beams, up to this many events (1: one event, edges pass further specular surfaces)";
        tir_remedy: u32 [0, 2] = 1, rebuild,
            "total internal reflection at the approximated exit of two-sided refraction (as image_space's): 0 single refraction, 1 clamp to the critical angle, 2 reflect";
        eq_6_3_2: u32 [0, 1] = 1, rebuild,
            "1: a missing back-face normal at the exit is replaced by Wyman's Eq. 6.3.2";
        camera_exit: u32 [0, 1] = 0, rebuild,
            "what the camera sees through closed glass: 0 the refracted ray traced through the BVH to its exit (exact, total internal reflections followed); 1 Wyman's two-sided image-space exit (Eq. 6.3.1 distance, back-face normals; approximate, it sends rays near the silhouette to the wrong place)";
        search_steps: u32 [4, 256] = 32, rebuild,
            "linear steps of the camera refraction's image-space search (what the camera sees through glass)";
        beam_capacity: u32 [1024, 4194304] = 262144, rebuild,
            "beams per light at most (more are counted as overflow and not drawn)";
    }
}

pub struct Beams {
    /// The surface frame: shadows, G-buffers, direct light, camera refraction.
    pub surface: SurfaceFrame,
    /// Each light's view of the specular objects.
    pub light_views: LightViews,
    /// The beams, their volumes and the two caustic targets.
    pub tracer: BeamTracer,
    /// Airlight with volumetric shadows from the surface frame's shadow maps.
    pub airlight: Airlight,
    last_counts: Option<BeamCounts>,
    /// Per frame slot: whether its latest frame traced beams (a frame that
    /// draws neither caustic component does not, `SceneGpu::draws`, and
    /// copies no counters).
    traced: Vec<bool>,
}

impl TechniqueBuild for Beams {
    const NAME: &'static str = "beams";
    const DESCRIPTION: &'static str = "Liktor & Dachsbacher 2011: adaptive caustic beams from a hierarchical projected grid on the light's G-buffer, bounding volumes extruded by a geometry shader, in-scattering and surface caustics per fragment, plus ray-marched airlight";
    const COMPONENTS: &'static [Component] = &[
        Component::Direct,
        Component::SurfaceCaustics,
        Component::Airlight,
        Component::VolumeCaustics,
        Component::Other,
        Component::Emitted,
    ];
    /// On `water_pool` it draws 0.1% of the water's surface caustics
    /// (BENCHMARKS.md, "Where users look"): its beams are the light view's
    /// closed refractors' (two-sided refraction, Sect. 6).
    const CAUSTIC_SOURCES: CausticSources = CausticSources::Solids;
    type Params = BeamsParams;

    /// Thin sheets and emissive surfaces are outside its model. Area lights
    /// become point stand-ins (`frame::caustic_lights`: a rect is a
    /// spot at its centre with the cosine profile, I = L A cos theta, whose
    /// light view and beams are a spot's), within their size limit; sphere
    /// lights are refused.
    fn check_scene(scene: &Scene) -> anyhow::Result<()> {
        super::check_materials(scene, Self::NAME)?;
        super::check_no_mixed(scene, Self::NAME)?;
        crate::frame::check_stand_ins(scene, Self::NAME).map_err(anyhow::Error::msg)
    }

    fn build(
        ctx: &Arc<Context>,
        params: &BeamsParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        let surface = SurfaceFrame::new(
            ctx,
            &params.direct,
            scene,
            scene_gpu,
            width,
            height,
            RefractionPush {
                tir_remedy: params.tir_remedy,
                use_eq632: params.eq_6_3_2,
                search_steps: params.search_steps,
                exit: params.camera_exit,
            },
        )?;
        let light_views = LightViews::new(ctx, scene, scene_gpu, params.light_view_size)?;
        let airlight = Airlight::new(
            ctx,
            &params.airlight,
            params.direct.medium_steps,
            scene,
            scene_gpu,
            surface.shadows(),
        )?;
        let tracer = BeamTracer::new(ctx, params, scene, scene_gpu, width, height)?;
        Ok(Self {
            surface,
            light_views,
            tracer,
            airlight,
            last_counts: None,
            traced: Vec::new(),
        })
    }

    fn update_live(&mut self, params: &BeamsParams) -> bool {
        self.surface.set_live(&params.direct, params.search_steps);
        self.airlight.set_live(&params.airlight);
        true
    }
}

impl Beams {
    /// The counters of the last completed frame (None when it traced no
    /// beams).
    pub fn counts(&self) -> Option<BeamCounts> {
        self.last_counts
    }
}

impl Technique for Beams {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) -> crate::vk::VkResult<()> {
        // The beams only add surface and volume caustics: a frame that
        // draws neither skips them (`SceneGpu::draws`).
        let traced =
            scene.draws(Component::SurfaceCaustics) || scene.draws(Component::VolumeCaustics);
        let slot = rec.slot();
        if self.traced.len() <= slot {
            self.traced.resize(slot + 1, false);
        }
        self.traced[slot] = traced;
        self.surface.record_opaque(rec, scene)?;
        if traced {
            self.tracer.begin(rec, scene, &self.surface, targets);
            self.light_views.record(rec, scene, &mut [&mut self.tracer]);
            self.tracer.apply(rec, scene, &self.surface);
        }
        self.surface.record_refraction(rec, scene, targets);
        if traced {
            self.tracer.composite(rec, scene, targets);
        }
        self.airlight
            .record(rec, scene, self.surface.shadows(), &targets.radiance);
        Ok(())
    }

    fn set_lights(&mut self, lights: &[Light]) -> bool {
        if !(self.airlight.follows_lights()
            && self.surface.set_lights(lights)
            && self.light_views.set_lights(lights))
        {
            return false;
        }
        self.tracer
            .set_lights(self.light_views.lights(), self.light_views.specular());
        true
    }

    fn after_frame(&mut self, slot: usize) -> crate::vk::VkResult<()> {
        if !self.traced.get(slot).copied().unwrap_or(false) {
            self.last_counts = None;
            return Ok(());
        }
        let counts = self.tracer.counts(slot)?;
        if counts.beam_overflow > 0 || counts.triangle_overflow > 0 {
            log::warn!(
                "beams: {} beams and {} split triangles did not fit (raise beam_capacity)",
                counts.beam_overflow,
                counts.triangle_overflow
            );
        }
        self.last_counts = Some(counts);
        Ok(())
    }

    fn counters(&self) -> Vec<(&'static str, u64)> {
        const BEAMS: [&str; 6] = [
            "beams_level0",
            "beams_level1",
            "beams_level2",
            "beams_level3",
            "beams_level4",
            "beams_level5",
        ];
        const TRIS: [&str; 6] = [
            "triangles_level0",
            "triangles_level1",
            "triangles_level2",
            "triangles_level3",
            "triangles_level4",
            "triangles_level5",
        ];
        let Some(c) = self.last_counts else {
            return Vec::new();
        };
        let mut out = vec![("beams", c.total_beams() as u64)];
        for l in 0..6 {
            out.push((BEAMS[l], c.beams[l] as u64));
            out.push((TRIS[l], c.triangles[l] as u64));
        }
        out.push((
            "dropped_per_million",
            (c.dropped_fraction() as f64 * 1e6).round() as u64,
        ));
        out.push(("fragments", c.fragments as u64));
        out.push(("caustic_fragments", c.caustic_fragments as u64));
        out.push(("beam_overflow", c.beam_overflow as u64));
        out.push(("triangle_overflow", c.triangle_overflow as u64));
        out
    }
}
