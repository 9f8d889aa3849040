//! `water_photons`: Kougianos & Moustakas 2021, "Large-scale ray traced
//! water caustics in real-time using cascaded caustic maps" (§3, Fig. 1):
//!
//! 1. "water surface" + "ccm raster" (`ccm`): the water's Gerstner surface
//!    evaluated on the GPU and rasterised from the directional light into
//!    the cascaded caustic maps: N cascades of ccm_0² texels, scale s, one
//!    orthographic projection each (Eq. 2) from one light view (Eq. 1,
//!    centred on the camera's position, followed frame by frame), layer c of a 2D
//!    array holding world position and normal (cascades.rs).
//! 2. "photon trace" (`trace`, glsl/water_photons/trace.comp): Algorithm 1
//!    maps each thread to (texel, cascade); Algorithm 3 traces a shadow ray,
//!    then the reflected and refracted rays through the BVH; a diffuse hit
//!    (either face: diffuse surfaces are two-sided, as in the reference;
//!    the paper's line 33 keeps front faces only) appends a photon with its differential (Eq. 10, Algorithm
//!    2: the footprint ∂x'/∂u, ∂x'/∂v on the receiver's tangent plane and
//!    σ of Eq. 11) through an atomic counter that is also the indirect
//!    draw's instance count, clamped to the capacity (overflow reported).
//! 3. "photon splat" (`splat`): one instanced quad per photon by
//!    vkCmdDrawIndirect, on the tangent plane, depth-tested against the
//!    camera's depth and kept only on pixels whose surface shows the
//!    camera the side the photon arrived on (the G-buffer normal, faced to
//!    the camera, against the photon's, faced to its ray: dot > 0), additive
//!    into the screen-space caustic buffer of irradiance E (W/m²). The
//!    depth test alone let a photon on one face of a surface thinner than
//!    the depth bias (an open quad: zero) light the other face: a thin wall
//!    lit through itself (GUIDE §2; tests/suite/water_photons.rs measures 201 of
//!    202 W/m² on the dark side before, 0 after). It also stops splats
//!    spilling across creases (floor onto wall, dot = 0).
//! 4. "denoise <kind> <k> x|y" (`denoise`, glsl/water_photons/denoise.comp):
//!    the adaptive-radius cross-bilateral filter of §3.3 (Eqs. 21-28,
//!    Algorithm 4) or the fixed-radius one it improves on, `denoise_passes`
//!    times, in place on the caustic buffer (`denoise` 0 skips it).
//! 5. "caustic composite": L += albedo/π · E on the diffuse receivers of
//!    the opaque frame (`passes::surface_frame`: direct light over a
//!    G-buffer without the water), then the surface frame's camera
//!    refraction draws the specular surfaces by an image-space search of
//!    that frame.
//! 6. "water view" (`view`, glsl/water_photons/view.comp): the traced
//!    water's own pixels (one interface) are redrawn, L = F1 L(x_R) +
//!    (1 − F1)/n² e^(−σ_a t) L(x_T) with x_R, x_T the first hits of the
//!    reflected and refracted camera rays in the BVH. L(x) is the opaque
//!    frame's radiance where x's pixel shows x's own surface, else (x
//!    hidden from the camera, or outside the view) albedo/π (E_direct +
//!    E_caustic) shaded at x: BVH shadow rays, and the photons gathered
//!    through the trace's slot image (the photon slot per texel, cascade
//!    and ray type) with the splat's own kernel (kernel.glsl), within the
//!    reach the waves' slope allows around the flat-water source texel.
//!    Why: the camera above the pool sees, through the water, floor that a
//!    wall hides from its direct view (the refracted ray bends down behind
//!    the near wall's edge: 627 of 9853 water pixels of water_pool at
//!    128²), and floor outside the view near the image's edge; the
//!    image-space search has no data there and returned the wall top's
//!    radiance or black, so the water's near edge looked cut short and
//!    jagged. Measured on flat water behind a wall
//!    (tests/suite/water_photons.rs): hidden and visible floor pixels within
//!    0.5% (defaults) of T(θ_s) T(θ_v) albedo E cos θ_s / (π n²).
//!
//! Radiometry. Physical mode (`intensity_mode` 0, default): a texel of
//! cascade c covers A_⊥ = (r_w s^c / ccm_0)(r_h s^c / ccm_0) across the
//! beam (Eq. 7's s^(2c) is the ratio to cascade 0), so its photon leaves
//! the water with Φ = E_light A_⊥ times the exact Fresnel F (reflected) or
//! 1 − F and the water's Beer-Lambert absorption (refracted). The splat
//! deposits exactly Φ: E(x) = Φ / (4 |U × V|), a box over the quad
//! x = x' + a U + b V, (a, b) ∈ [−1, 1]² (Eq. 20's I = R / (a q²), the
//! paper's shaded quad). On a regular lattice of photons (flat water) the
//! boxes tile exactly, so the caustic is uniform: E = E_light cos θ_i
//! (1 − F) on a floor parallel to the water; across the seam between
//! cascade c − 1 and cascade c's ring as well, since the ring's texels line
//! up with the finer cascade's border when Eq. 6 is integral (a tent kernel
//! sums to one only within one lattice: ±25% bands at the seams for s = 2).
//! Where Eq. 6 is rounded (cascades.rs), the ring's inner edge is off
//! the finer cascade's border by |ΔX − ccm_0 (1 − 1/s)/2| < 1/2 texel of
//! cascade c: a band of that width along the seam is covered twice (ΔX
//! rounded up) or not at all (rounded down), E doubled or zero there; the
//! default s = 2 with a power-of-two ccm_0 keeps Eq. 6 integral. Measured
//! on the flat-water test scene with s = 3, ccm_0 64 (ΔX = 21.33 rounded to
//! 21, a gap of a third of a cascade-1 texel): 95 of 4464 floor pixels off
//! by more than 1%, down to 8.5% of E in the band, the mean over the 3 m
//! square 1.3% low (N = 2 and 3 alike). Paper mode
//! (1): R = L I_att F of Eqs. 12-15 (attenuation γ, t_max; stylised Fresnel
//! F_frac, F_exp) in place of the flux, same splat.
//! Splat shapes (`splat_mode`): 0, the differential's own parallelogram,
//! the footprint of the photon's texel (U, V = ∂x'/∂u / 2, ∂x'/∂v / 2); 1, Eqs. 16-19's rectangle (size q from σ,
//! stretched by a along the projected ray); 2, fixed splats: that rectangle
//! with σ = s^c, no differentials (the paper's comparison).
//!
//! Light: the scene's first directional light (the paper's sun), else the
//! environment's sun as a directional light (`emitters::sun_irradiance`); a scene
//! without one, or without a water object, is refused. The first water
//! object is the one traced. The light range (`light_range` 0) is derived
//! so that the outermost cascade covers the whole water seen from Eq. 1's
//! origin; the depth range spans the water's bounds.
//!
//! Deviations from the paper: the light view's up vector is +z under a
//! high sun (`CascadeFrame::new`), so the texel grid lines up with the
//! water's; Eq. 16's grid pitch is r / ccm_0 (the printed r / (ccm_0 − 1)
//! would leave q_0 = 1 boxes overlapping); the neighbours' rays of
//! Algorithm 2 meet the receiver's tangent plane instead of stopping at t'
//! (the same on a plane parallel to flat water, exact on any plane);
//! Algorithm 3 line 24 prints reflect(LDir, n10), we reflect about the
//! photon's own normal n00 (n10 belongs to the right neighbour's ray,
//! Algorithm 2); Algorithm 3 lines 4-6 loop the scale up to c inclusive,
//! s^(2(c+1)), contradicting Eq. 7's L = s^(2c): we use Eq. 7 (a texel of
//! cascade c covers s^(2c) cascade-0 texels, so its flux is s^(2c) times
//! theirs); Eq. 1's back-off l_pos = o − l_dir (z_near + z_far) is replaced
//! by a back-off from the water's extent (`CascadeFrame::new`: 1 m behind
//! the rearmost corner of the water's bounds seen from o), so every water
//! point lies in front of the light whatever the depth range; the
//! denoiser's z in Eq. 22 is the linear view depth in metres (from the
//! G-buffer's world positions) where Algorithm 4 loads the depth buffer:
//! a nonlinear perspective depth would make Eq. 22's ε mean different
//! distances near and far, while metres keep ε a physical tolerance; paper
//! mode traces the reflected and refracted rays only up to t_max (the
//! paper's DXR TMax), so Eq. 13's u = 1 − t'/t_max stays in [0, 1]; the
//! paper splats only onto points the camera sees directly and does not say
//! how the water itself is drawn: the water view (step 6) is ours.
//!
//! Limits: one specular bounce (L S D): photons whose ray meets another
//! specular surface first are dropped, so light reflected back under the
//! water by total internal reflection is missing (and the water view's rays
//! that meet the water again see black); the water view's gathered
//! caustics (hidden receivers only) are not denoised, and its search
//! reach assumes a refracted ray turns by at most half the surface's tilt
//! (true below a sun zenith angle of about 60°); the adaptive denoiser
//! (Eq. 21: depth and position weights only) spreads caustics across
//! creases within its δ: on the thin-wall test the dark side, 0 without
//! the denoiser, takes a mean 4.1 W/m² (max 18.9) of the lit floor beside
//! it (202 W/m² on the lit side); photons whose
//! neighbours (both sides along u or v) hold no water have no footprint
//! and are dropped (texels on the water's rim); splats overlapping a
//! depth edge spill onto the surface behind. The depth bias is relative
//! (1% of the distance, 2 m at 200 m): on ocean_large a 10x smaller bias
//! rejects 48% of the caustic energy (the far seabed fails the depth test
//! against itself), so 1% stays; a splat up to that distance behind an
//! occluder passes the test and leaks onto it (not measured: ocean_large's
//! walls stand at the seabed's edge with no receiver behind them).
//!
//! (Over 600 lines: about 100 are this map of the paper onto the passes;
//! the passes themselves live in ccm.rs, trace.rs, splat.rs, denoise.rs.)

pub mod bindings;
mod cascade_frame;
pub mod cascades;
mod ccm;
pub mod denoise;
mod params;
mod shafts;
mod splat;
mod trace;
mod view;

use cascade_frame::water_uniform;
pub use cascade_frame::{water_bounds, CascadeFrame};
pub use ccm::Ccm;
pub use denoise::{DenoiseParams, Denoiser};
pub use params::{GpuWpParams, WaterPhotonsParams, WpParamsBuffer};
use shafts::Shafts;
use splat::{Composite, Splat};
pub use trace::{GpuWaterPhoton, PhotonCounts, Trace, GUARD_PHOTONS, GUARD_WORD};
pub use view::WaterView;

use super::{CausticSources, Technique, TechniqueBuild};
use crate::frame::{FrameTargets, SceneGpu};
use crate::gpu::GpuFrame;
use crate::passes::camera_refraction::RefractionPush;
use crate::passes::surface_frame::SurfaceFrame;
use crate::radiometry::Component;
use crate::scene::{Light, LightKind, Scene, Water};
use crate::shader_bindings as b;
use crate::vk::{Buffer, BufferUsage, Context, FrameRecorder, Specialization, VkResult};
use anyhow::Context as _;
use cascades::{inner_cascade_size, CascadeLayout};
use glam::{Mat4, Vec3};
use std::mem::size_of;
use std::sync::Arc;

pub struct WaterPhotons {
    /// Shadows, G-buffers and direct light on the scene without the water
    /// (it still casts shadows), whose opaque frame gets the caustics and
    /// is what the camera refraction looks up.
    pub surface: SurfaceFrame,
    pub ccm: Ccm,
    pub trace: Trace,
    pub splat: Splat,
    /// `None` when `denoise` = 0.
    pub denoiser: Option<Denoiser>,
    /// Eq. 25's L_min (W/m²) from the scene's lights.
    l_min: Vec3,
    /// The scene's bounding sphere, for `l_min` when lights change.
    scene_sphere: (Vec3, f32),
    composite: Composite,
    shafts: Shafts,
    /// The live `shafts` parameter: draw the shafts under a turbid water.
    shafts_on: bool,
    /// The water's material holds a medium (`Material::holds_medium`)
    /// and the photons carry physical flux: the shafts have something to show.
    shafts_possible: bool,
    view: WaterView,
    pub frame: CascadeFrame,
    params: WpParamsBuffer,
    gpu_params: GpuWpParams,
    /// Eq. 1's origin o: the camera position the cascades were placed for.
    camera_origin: Vec3,
    light: Light,
    /// The environment's sun as a directional light: the light when the
    /// scene has no directional one.
    env_sun: Option<Light>,
    range_param: f32,
    water: Water,
    /// The last completed frame's photon counts (`after_frame`).
    last_counts: Option<PhotonCounts>,
}

fn first_directional(lights: &[Light]) -> Option<&Light> {
    lights.iter().find(|l| l.kind == LightKind::Directional)
}

/// The environment's sun (a sky's, or one found in an image) as the
/// directional light it stands for (docs/SCENES.md), if it has one.
fn environment_sun(scene: &Scene) -> Option<Light> {
    let (direction, irradiance) = scene
        .environment
        .as_ref()
        .and_then(crate::emitters::sun_irradiance)?;
    Some(Light {
        kind: LightKind::Directional,
        position: glam::Vec3::ZERO,
        direction,
        intensity: irradiance,
        cone_angle_deg: 0.0,
        cone_falloff_deg: 0.0,
    })
}

/// The shafts' blocks of k x k texels (shafts.glsl) tile a cascade only
/// where k divides its side and its ring's border (Eq. 6): a block
/// across the border would count the inner cascade's light twice and
/// leave texels past it in no block.
fn check_shaft_stride(k: u32, layout: &CascadeLayout) -> anyhow::Result<()> {
    let [w, h] = layout.size;
    let [bx, by] = layout.border;
    let divides = |n: u32| n % k == 0;
    if !(divides(w) && divides(h) && (layout.levels == 1 || (divides(bx) && divides(by)))) {
        anyhow::bail!(
            "--param shaft_stride={k}: must divide the caustic maps' side ({w} x {h}) and their rings' border ({bx} x {by} texels)"
        );
    }
    Ok(())
}

/// `lights` and the environment's sun.
fn with_sun(lights: &[Light], sun: Option<Light>) -> Vec<Light> {
    lights.iter().copied().chain(sun).collect()
}

impl WaterPhotons {
    pub fn new(
        ctx: &Arc<Context>,
        params: &WaterPhotonsParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        let water = scene
            .objects
            .iter()
            .find_map(|o| o.water.clone())
            .context("water_photons needs a `water` object in the scene")?;
        let env_sun = environment_sun(scene);
        let light = first_directional(&scene.lights)
            .copied()
            .or(env_sun)
            .context(
                "water_photons needs a directional light (the paper's sun) or an environment with a sun",
            )?;
        let levels = params.cascades;
        let scale = params.cascade_scale;
        let range_param = params.light_range;
        let precision = params.ccm_precision;
        let size = if precision > 0.0 {
            // Eq. 3 from the range, which does not depend on ccm_0.
            let probe = CascadeLayout::new([256, 256], levels, scale)?;
            let frame = CascadeFrame::new(
                &water,
                scene.camera.eye,
                light.direction,
                probe,
                range_param,
            );
            inner_cascade_size(&frame.range, precision)
        } else {
            params.ccm_size
        };
        let layout = CascadeLayout::new([size, size], levels, scale)?;
        check_shaft_stride(params.shaft_stride, &layout)?;
        let frame = CascadeFrame::new(
            &water,
            scene.camera.eye,
            light.direction,
            layout,
            range_param,
        );
        // The photon buffer is one storage-buffer binding: the device's
        // maxStorageBufferRange bounds it (128 MiB on lavapipe: 1.4M photons).
        let photon_bytes = size_of::<GpuWaterPhoton>() as u64;
        let device_max =
            ctx.limits.max_storage_buffer_range as u64 / photon_bytes - GUARD_PHOTONS as u64;
        let capacity = match params.photon_capacity as u64 {
            0 => {
                let wanted = 2 * layout.total_threads();
                if wanted > device_max {
                    log::warn!(
                        "water_photons: {wanted} photon slots (2 per thread of {levels} cascades of {size}²) exceed the device's storage buffer range; using {device_max}, overflow is possible"
                    );
                }
                wanted.min(device_max)
            }
            n => n,
        };
        anyhow::ensure!(
            capacity <= device_max,
            "photon_capacity={capacity}: the device binds at most {device_max} photons ({} bytes each) in one storage buffer",
            photon_bytes
        );
        let capacity = capacity as u32;
        let surface = SurfaceFrame::new(
            ctx,
            &params.direct,
            scene,
            scene_gpu,
            width,
            height,
            RefractionPush {
                tir_remedy: b::TIR_CLAMP_CRITICAL,
                use_eq632: 1,
                search_steps: params.search_steps,
                exit: b::CAMERA_EXIT_TRACED,
            },
        )?;
        let params_buffer = WpParamsBuffer(Buffer::new(
            ctx,
            "water_photons params",
            size_of::<GpuWpParams>() as u64,
            BufferUsage::Uniform,
        )?);
        let ccm = Ccm::new(ctx, &water, size, levels)?;
        let trace = Trace::new(ctx, scene_gpu, &params_buffer, &layout, capacity)?;
        // The cascade count and the splat mode as pipeline constants
        // (bindings.rs, WP_SPEC_*), not uniform reads: lavapipe would
        // recompile the water view at every bind.
        let specialization = Specialization::new()
            .u32(bindings::WP_SPEC_CASCADES, levels)
            .u32(bindings::WP_SPEC_SPLAT_MODE, params.splat_mode);
        let splat = Splat::new(
            ctx,
            scene_gpu,
            &params_buffer,
            &trace.photons,
            &specialization,
            width,
            height,
        )?;
        let denoiser = Denoiser::from_params(
            ctx,
            &params.denoise,
            &splat.caustics,
            &surface.gbuffer().position,
        )?;
        let scene_sphere = scene.bounding_sphere(0.0);
        // The composite reads the splat's caustic buffer (denoised in place).
        let composite = Composite::new(ctx, scene_gpu)?;
        let shafts = Shafts::new(
            ctx,
            scene_gpu,
            &params_buffer,
            &trace.photons,
            width,
            height,
        )?;
        let shafts_possible = params.intensity_mode == bindings::WP_INTENSITY_PHYSICAL
            && scene
                .materials
                .get(water.material as usize)
                .is_some_and(|m| m.holds_medium());
        let view = WaterView::new(
            ctx,
            scene_gpu,
            &params_buffer,
            &trace.photons,
            &specialization,
        )?;
        let gpu_params = GpuWpParams {
            light_view: Mat4::IDENTITY.to_cols_array_2d(),
            light_dir: [0.0; 4],
            irradiance: [0.0; 4],
            range: [0.0; 4],
            size: [size, size, levels, capacity],
            modes: [
                layout.border[0],
                layout.border[1],
                params.intensity_mode,
                params.splat_mode,
            ],
            cascade: [
                layout.scale,
                params.quad_size,
                params.fresnel_frac,
                params.fresnel_exp,
            ],
            paper: [
                params.attenuation_gamma,
                params.attenuation_t_max,
                // ε of Eq. 19.
                1e-3,
                params.depth_bias,
            ],
            water: water_uniform(&water),
            shafts: [params.shaft_stride, 0, 0, 0],
        };
        let mut technique = Self {
            surface,
            ccm,
            trace,
            splat,
            denoiser,
            l_min: denoise::lights_l_min(
                &with_sun(&scene.lights, env_sun),
                scene_sphere.0,
                scene_sphere.1,
            ),
            env_sun,
            scene_sphere,
            composite,
            shafts,
            shafts_on: params.shafts != 0,
            shafts_possible,
            view,
            frame,
            params: params_buffer,
            gpu_params,
            camera_origin: scene.camera.eye,
            light,
            range_param,
            water,
            last_counts: None,
        };
        technique.set_light(&light);
        Ok(technique)
    }

    fn set_light(&mut self, light: &Light) {
        self.light = *light;
        self.frame = CascadeFrame::new(
            &self.water,
            self.camera_origin,
            light.direction,
            self.frame.layout,
            self.range_param,
        );
        let p = &mut self.gpu_params;
        p.light_view = self.frame.view.to_cols_array_2d();
        p.light_dir = light.direction.normalize().extend(0.0).to_array();
        p.irradiance = light.intensity.extend(0.0).to_array();
        let r = self.frame.range;
        p.range = [r.width, r.height, r.near, r.far];
        p.water = water_uniform(&self.water);
    }

    /// Photons written and requested in the last frame recorded, once it
    /// has completed.
    pub fn photon_counts(&self) -> VkResult<PhotonCounts> {
        self.trace.counts(self.trace.last_slot.get())
    }
}

impl TechniqueBuild for WaterPhotons {
    const NAME: &'static str = "water_photons";
    const DESCRIPTION: &'static str = "Kougianos & Moustakas 2021: cascaded caustic maps of the water from the sun, photon differentials traced through the BVH, splats drawn indirect into a screen-space caustic buffer";
    const COMPONENTS: &'static [Component] = &[
        Component::Direct,
        Component::SurfaceCaustics,
        // The shafts of a turbid water, seen from under its surface.
        Component::VolumeCaustics,
        Component::Emitted,
    ];
    const CAUSTIC_SOURCES: CausticSources = CausticSources::Water;
    type Params = WaterPhotonsParams;

    fn build(
        ctx: &Arc<Context>,
        params: &WaterPhotonsParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        Self::new(ctx, params, scene, scene_gpu, width, height)
    }

    /// A `water` object and a directional light (the paper's sun), named
    /// as the scene fields that lack them.
    fn check_scene(scene: &Scene) -> anyhow::Result<()> {
        super::check_materials(scene, Self::NAME)?;
        super::check_no_mixed(scene, Self::NAME)?;
        let file = scene.source.display();
        if !scene.objects.iter().any(|o| o.water.is_some()) {
            anyhow::bail!(
                "{file}: object: water_photons needs a `water` object (shape = \"water\"); the scene has none"
            );
        }
        if first_directional(&scene.lights).is_none() && environment_sun(scene).is_none() {
            anyhow::bail!(
                "{file}: light: water_photons needs a directional light (the paper's sun, kind = \"directional\") or an environment with a sun; the scene has neither"
            );
        }
        // One water body under one sun: more would be drawn without their
        // caustics, so they are refused rather than left out unseen.
        let mut waters = scene.objects.iter().filter(|o| o.water.is_some());
        let first = waters.next().map(|o| o.name.as_str()).unwrap_or_default();
        if let Some(extra) = waters.next() {
            anyhow::bail!(
                "{file}: object `{}`: water_photons renders one water body (`{first}`); remove the other or choose another technique",
                extra.name
            );
        }
        let suns = scene
            .lights
            .iter()
            .filter(|l| l.kind == LightKind::Directional)
            .count();
        match (suns, environment_sun(scene).is_some()) {
            (2.., _) => anyhow::bail!(
                "{file}: light: water_photons traces the caustics of one sun, and the scene has {suns} directional lights; remove all but one or choose another technique"
            ),
            (1, true) => anyhow::bail!(
                "{file}: light: water_photons traces the caustics of one sun, and the scene has a directional light and an environment with a sun; remove one or choose another technique"
            ),
            _ => Ok(()),
        }
    }

    fn update_live(&mut self, params: &WaterPhotonsParams) -> bool {
        self.shafts_on = params.shafts != 0;
        // A stride that does not tile these cascades: rebuilt, whose check
        // says why.
        if check_shaft_stride(params.shaft_stride, &self.frame.layout).is_err() {
            return false;
        }
        self.gpu_params.shafts[0] = params.shaft_stride;
        self.surface.set_live(&params.direct, params.search_steps);
        true
    }
}

impl Technique for WaterPhotons {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) -> VkResult<()> {
        // Eq. 1 follows the camera: this frame's constants hold its eye.
        let constants: GpuFrame = scene.frame_constants();
        let eye = Vec3::from_slice(&constants.eye[..3]);
        // View space looks down -z: the camera's forward is -(third row of the view).
        let view = Mat4::from_cols_array_2d(&constants.view);
        let forward = -view.row(2).truncate();
        if eye != self.camera_origin {
            self.camera_origin = eye;
            let light = self.light;
            self.set_light(&light);
        }
        // The eye under the water: the water view attenuates the whole
        // frame by the water between, and the shafts are drawn.
        let under_water = self.water.is_below_surface(eye, scene.geometry_time);
        self.gpu_params.shafts[1] = u32::from(under_water);
        // Through the frame's upload ring: earlier frames may still read the buffer.
        rec.upload(&self.params.0, bytemuck::bytes_of(&self.gpu_params));
        self.surface.record_opaque(rec, scene)?;
        let view_projs: Vec<Mat4> = (0..self.frame.layout.levels)
            .map(|c| self.frame.view_proj(c))
            .collect();
        self.ccm.record(rec, scene.geometry_time, &view_projs);
        self.trace
            .record(rec, scene, &self.ccm.position, &self.ccm.normal);
        self.splat.record(
            rec,
            scene,
            self.surface.gbuffer(),
            &self.trace.photons,
            &self.trace.draw,
        );
        if let Some(denoiser) = &self.denoiser {
            denoiser.record(
                rec,
                &self.splat.caustics,
                &self.surface.gbuffer().position,
                eye,
                forward,
                self.l_min,
            );
        }
        self.composite.record(
            rec,
            scene,
            &self.splat.caustics,
            self.surface.gbuffer(),
            self.surface.opaque(),
        );
        self.surface.record_refraction(rec, scene, targets);
        self.shafts.record(
            rec,
            scene,
            &self.trace.photons,
            &self.trace.draw,
            self.surface.gbuffer(),
            self.surface.specular(),
            self.shafts_on && self.shafts_possible && under_water,
        );
        self.view.record(
            rec,
            scene,
            &self.trace.photons,
            &self.trace.slots,
            self.surface.opaque(),
            self.surface.gbuffer(),
            self.surface.specular(),
            &self.shafts.image,
            targets,
        );
        Ok(())
    }

    /// The frame's photon counts (copied to the host by "photon trace"),
    /// read once the frame has completed: overflow is reported for the
    /// frame that overflowed, the last one included.
    fn after_frame(&mut self, slot: usize) -> VkResult<()> {
        let counts = self.trace.counts(slot)?;
        if counts.overflow() > 0 {
            log::warn!(
                "water_photons: {} of {} photons did not fit the buffer of {} (raise photon_capacity)",
                counts.overflow(),
                counts.requested,
                counts.capacity
            );
        }
        self.last_counts = Some(counts);
        Ok(())
    }

    fn counters(&self) -> Vec<(&'static str, u64)> {
        self.last_counts
            .map(|c| {
                vec![
                    ("photons_written", c.written.into()),
                    ("photons_requested", c.requested.into()),
                    ("photon_capacity", c.capacity.into()),
                    ("photons_overflow", c.overflow().into()),
                ]
            })
            .unwrap_or_default()
    }

    fn set_lights(&mut self, lights: &[Light]) -> bool {
        let Some(light) = first_directional(lights).copied().or(self.env_sun) else {
            return false;
        };
        self.set_light(&light);
        self.l_min = denoise::lights_l_min(
            &with_sun(lights, self.env_sun),
            self.scene_sphere.0,
            self.scene_sphere.1,
        );
        self.surface.set_lights(lights)
    }
}
