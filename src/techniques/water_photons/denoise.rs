//! The caustics denoiser of `water_photons` (Kougianos & Moustakas 2021,
//! Sect. 3.3, Algorithm 4): iterated cross-bilateral blurs of the
//! screen-space caustic buffer, separable (each pass is a sub-pass along x,
//! the paper's "column-wise" one, then a sub-pass along y), with weights
//! that stop at geometric edges and a kernel radius that adapts to how
//! bright the caustic is relative to the scene's lighting.
//!
//! Weights between pixels p and q (`glsl/water_photons/denoise.comp`):
//! - Eq. 21 w = w_z · w_pos;
//! - Eq. 22 w_z = 1 / (|z(p) − z(q)| + ε), z the view-space depth
//!   `dot(x − eye, forward)` from the camera G-buffer's world position,
//!   ε = 0.01 m (Algorithm 4's 1.0 in Unreal's centimetres);
//! - Eq. 23 w_pos = 1 / (1 + 10 d·d / δ²), d the world-space offset;
//! - Eq. 24 C(p) = Σ w C(q) / Σ w over the footprint, p itself included
//!   with weight 1 (Eq. 22 is used times ε, which the normalisation cancels).
//!
//! Radius (Eqs. 25-28): C_scene = 0.114 · lum(L_min) (Eq. 25; Algorithm 4
//! line 7 prints 0.144, the text and equation say 0.114, which we use).
//! Per pixel, from lum(C(p)) of the sub-pass's input:
//! below 0.1 C_scene ρ = 15, λ = 5 (stride), δ = 0.15 m; below 0.5 C_scene
//! ρ = 10, λ = 1, δ = 0.02 m; else ρ = 5, λ = 1, δ = 0.01 m (the paper's
//! δ = 15 / 2 / 1 in centimetres). The fixed-radius filter of the paper's
//! refs [6, 10] is the same kernel with ρ a parameter, λ = 1, δ = 0.01 m
//! (the third level, which the paper calls "the fixed radius case").
//!
//! L_min. The paper takes "the minimum light luminance among all scene
//! lights" (Appendix D: the intensity of the dimmest light) and compares
//! it with the caustic buffer's intensity. Our caustic buffer holds
//! irradiance E (W/m²), so L_min here is the irradiance each light delivers
//! to the scene at normal incidence, computed from the scene
//! ([`scene_l_min`]): a directional light's E as given, a point or spot
//! light's on-axis I / d², d the distance from the light to the centre of
//! the scene's bounding sphere, or the sphere's radius when the light is
//! inside it (the typical distance to the receivers around it). The
//! dimmest light by luminance (Rec. 709, as `luminance()` in
//! glsl/common/optics.glsl) wins.
//!
//! Physics: the output is still irradiance (W/m²). Each pixel's weights are
//! normalised (Eq. 24), so a constant buffer stays constant (bit-exact: the
//! shader evaluates Eq. 24 as C(p) + Σ w (C(q) − C(p)) / Σ w), zero stays
//! zero, and every output is a convex combination of inputs (no NaN from
//! the division: the sum of weights is at least 1). A gather filter
//! normalises rows, not columns, of its weight matrix, so it conserves total
//! energy only approximately: tests/suite/denoise.rs measures the change on a
//! sparse photon image (an adaptive kernel that gathers wide into dark
//! pixels and narrow at bright ones adds energy around isolated photons).

use super::bindings;
use crate::radiometry::luminance;
use crate::scene::{Camera, Light, LightKind, Scene};
use crate::vk::{
    Access, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout, FrameRecorder, Image,
    ImageDesc, Profiler, TimingSource,
};
use anyhow::{bail, ensure, Context as _};
use ash::vk;
use glam::Vec3;
use std::sync::Arc;

crate::declare_params! {
    /// The denoiser's parameters, a group of `water_photons`'.
    pub struct DenoiseParams {
        denoise: u32 [0, 2] = 1, rebuild,
            "caustics denoiser: 0 none, 1 adaptive radius (Kougianos 2021 Eqs. 25-28), 2 fixed radius (refs [6, 10])";
        denoise_passes: u32 [1, 16] = 1, rebuild,
            "denoise passes, each a sub-pass along x then along y";
        denoise_radius: u32 [1, 32] = 5, rebuild,
            "kernel radius in pixels of the fixed-radius denoiser";
    }
}

/// Eq. 25's experimentally defined constant.
pub const C_SCENE_FACTOR: f32 = 0.114;
/// Eq. 22's ε in metres (Algorithm 4 line 22: 1 UE4 unit, a centimetre).
pub const DEPTH_EPSILON: f32 = 0.01;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DenoiseKind {
    /// Radius, stride and distance scale per pixel by Eqs. 26-28.
    Adaptive,
    /// One radius for every pixel (refs [6, 10]).
    Fixed,
}

impl DenoiseKind {
    fn code(self) -> u32 {
        match self {
            DenoiseKind::Adaptive => bindings::DENOISE_KIND_ADAPTIVE,
            DenoiseKind::Fixed => bindings::DENOISE_KIND_FIXED,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            DenoiseKind::Adaptive => "adaptive",
            DenoiseKind::Fixed => "fixed",
        }
    }
}

/// What one denoiser does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DenoiseConfig {
    pub kind: DenoiseKind,
    /// Passes, each a sub-pass along x then one along y.
    pub passes: u32,
    /// Kernel radius in pixels of `DenoiseKind::Fixed` (unused by `Adaptive`).
    pub fixed_radius: u32,
}

impl DenoiseConfig {
    /// From the parameters; `None` when `denoise` = 0 (off).
    pub fn from_params(params: &DenoiseParams) -> Option<DenoiseConfig> {
        let kind = match params.denoise {
            0 => return None,
            1 => DenoiseKind::Adaptive,
            _ => DenoiseKind::Fixed,
        };
        Some(DenoiseConfig {
            kind,
            passes: params.denoise_passes,
            fixed_radius: params.denoise_radius,
        })
    }
}

/// Push constants of glsl/water_photons/denoise.comp.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    eye_c_scene: [f32; 4],
    forward_epsilon: [f32; 4],
    mode: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<Push>() == 48);

/// Eq. 25: the luminance threshold C_scene (W/m²) from L_min (see the module doc).
pub fn c_scene(l_min: Vec3) -> f32 {
    C_SCENE_FACTOR * luminance(l_min)
}

/// L_min of Eq. 25 for `scene` at `time`: the irradiance (W/m², rgb) of
/// its dimmest light by luminance (module doc). Zero without lights, which
/// makes every caustic pixel "bright" (the smallest kernel).
pub fn scene_l_min(scene: &Scene, time: f32) -> Vec3 {
    let (centre, radius) = scene.bounding_sphere(time);
    lights_l_min(&scene.lights, centre, radius)
}

/// `scene_l_min` for `lights` around a scene bounded by the sphere
/// (`centre`, `radius`).
pub fn lights_l_min(lights: &[Light], centre: Vec3, radius: f32) -> Vec3 {
    lights
        .iter()
        .map(|light| match light.kind {
            LightKind::Directional => light.intensity,
            LightKind::Point | LightKind::Spot => {
                let d = (light.position - centre).length().max(radius);
                if d > 0.0 {
                    light.intensity / (d * d)
                } else {
                    // A scene without extent: no receivers to light.
                    Vec3::ZERO
                }
            }
        })
        .min_by(|a, b| luminance(*a).total_cmp(&luminance(*b)))
        .unwrap_or(Vec3::ZERO)
}

/// Filters one caustic buffer in place through a scratch image.
pub struct Denoiser {
    pub config: DenoiseConfig,
    pipeline: ComputePipeline,
    _layout: DescriptorSetLayout,
    /// caustics -> scratch (sub-pass along x).
    set_x: DescriptorSet,
    /// scratch -> caustics (sub-pass along y).
    set_y: DescriptorSet,
    scratch: Image,
}

fn check_rgba32f_storage(image: &Image, what: &str) -> anyhow::Result<()> {
    ensure!(
        image.desc.format == vk::Format::R32G32B32A32_SFLOAT,
        "denoiser: the {what} image must be RGBA32F, not {:?}",
        image.desc.format
    );
    ensure!(
        image.desc.usage.contains(vk::ImageUsageFlags::STORAGE),
        "denoiser: the {what} image needs STORAGE usage"
    );
    Ok(())
}

impl Denoiser {
    /// A denoiser for `caustics` (RGBA32F irradiance, rgb W/m²) over the
    /// camera G-buffer `position` (RGBA32F, xyz world, w coverage; see
    /// src/passes/gbuffer.rs) of the same size. Both images are bound here,
    /// once, and `record` must be given the same two.
    pub fn new(
        ctx: &Arc<Context>,
        config: DenoiseConfig,
        caustics: &Image,
        position: &Image,
    ) -> anyhow::Result<Self> {
        if config.passes == 0 {
            bail!("denoiser: passes must be at least 1 (use denoise=0 to switch it off)");
        }
        if config.kind == DenoiseKind::Fixed && config.fixed_radius == 0 {
            bail!("denoiser: the fixed radius must be at least 1 pixel");
        }
        check_rgba32f_storage(caustics, "caustics")?;
        check_rgba32f_storage(position, "G-buffer position")?;
        ensure!(
            caustics.extent() == position.extent(),
            "denoiser: caustics {}x{} and G-buffer {}x{} differ in size",
            caustics.desc.width,
            caustics.desc.height,
            position.desc.width,
            position.desc.height
        );
        let layout = DescriptorSetLayout::of_shaders(ctx, 0, &["water_photons/denoise.comp"])?;
        let pipeline = ComputePipeline::new(
            ctx,
            "water_photons/denoise.comp",
            &[&layout],
            std::mem::size_of::<Push>() as u32,
        )?;
        let scratch = Image::new(
            ctx,
            "denoise scratch",
            ImageDesc::new_2d(
                caustics.desc.width,
                caustics.desc.height,
                vk::Format::R32G32B32A32_SFLOAT,
                vk::ImageUsageFlags::STORAGE,
            ),
        )?;
        // One set per axis: each sub-pass declares its own bindings.
        let set_x = DescriptorSet::new(ctx, &layout)?;
        let set_y = DescriptorSet::new(ctx, &layout)?;
        Ok(Self {
            config,
            pipeline,
            _layout: layout,
            set_x,
            set_y,
            scratch,
        })
    }

    /// `DenoiseConfig::from_params`, then `new`; `None` when switched off.
    pub fn from_params(
        ctx: &Arc<Context>,
        params: &DenoiseParams,
        caustics: &Image,
        position: &Image,
    ) -> anyhow::Result<Option<Self>> {
        DenoiseConfig::from_params(params)
            .map(|config| Self::new(ctx, config, caustics, position))
            .transpose()
    }

    /// Records `passes` x 2 timed sub-passes ("denoise <kind> <k> x|y")
    /// filtering `caustics` in place. The camera's `eye` and unit `forward`
    /// give the view-space depth of Eq. 22; `l_min` is Eq. 25's L_min (W/m², e.g. [`scene_l_min`]).
    /// Afterwards `caustics`' last access is a compute write.
    pub fn record(
        &self,
        rec: &mut FrameRecorder,
        caustics: &Image,
        position: &Image,
        eye: Vec3,
        forward: Vec3,
        l_min: Vec3,
    ) {
        assert!(
            caustics.extent() == self.scratch.extent()
                && position.extent() == self.scratch.extent(),
            "Denoiser::record: images of another size than it was built for"
        );
        let push = |axis: u32| Push {
            eye_c_scene: eye.extend(c_scene(l_min)).to_array(),
            forward_epsilon: forward.extend(DEPTH_EPSILON).to_array(),
            mode: [axis, self.config.kind.code(), self.config.fixed_radius, 0],
        };
        let groups = [
            caustics.desc.width.div_ceil(bindings::DENOISE_GROUP_SIZE),
            caustics.desc.height.div_ceil(bindings::DENOISE_GROUP_SIZE),
            1,
        ];
        let kind = self.config.kind.name();
        // Each pass: x reads the caustics (written by the splats or the
        // previous pass) and overwrites all of the scratch image, after the
        // previous pass's y sub-pass has read it (write-after-read); y reads
        // the scratch and rewrites every caustic pixel, whose old contents
        // are discarded once the x sub-pass has read them.
        let sub_passes = [
            (
                "x",
                &self.set_x,
                caustics,
                &self.scratch,
                bindings::DENOISE_AXIS_X,
            ),
            (
                "y",
                &self.set_y,
                &self.scratch,
                caustics,
                bindings::DENOISE_AXIS_Y,
            ),
        ];
        for k in 0..self.config.passes {
            for (name, set, input, output, axis) in sub_passes {
                rec.pass(&format!("denoise {kind} {k} {name}"))
                    .storage_image(
                        set,
                        bindings::DENOISE_BINDING_INPUT,
                        input,
                        Access::ComputeRead,
                    )
                    .storage_image(
                        set,
                        bindings::DENOISE_BINDING_POSITION,
                        position,
                        Access::ComputeRead,
                    )
                    .overwrite_storage_image(
                        set,
                        bindings::DENOISE_BINDING_OUTPUT,
                        output,
                        Access::ComputeWrite,
                    )
                    .record(|c| {
                        c.dispatch(
                            &self.pipeline,
                            &[set],
                            bytemuck::bytes_of(&push(axis)),
                            groups,
                        )
                    });
            }
        }
    }
}

/// One adaptive pass against `fixed_passes` fixed-radius passes on the same
/// caustic buffer: the paper's claim (iii) (Sect. 4, Figs. 12-13: one
/// adaptive pass looks like ten fixed ones at about a fifth of the cost).
pub struct AdaptiveVsFixed {
    /// Filtered buffers, RGBA f32 row-major (irradiance, W/m²).
    pub adaptive: Vec<f32>,
    pub fixed: Vec<f32>,
    /// Milliseconds per frame of all denoise sub-passes, averaged over the
    /// timed frames (after one warm-up frame each).
    pub adaptive_ms: f64,
    pub fixed_ms: f64,
    pub timing: TimingSource,
}

impl AdaptiveVsFixed {
    /// How many times longer the fixed passes take than the adaptive pass.
    pub fn speedup(&self) -> f64 {
        self.fixed_ms / self.adaptive_ms
    }
}

/// Runs both denoisers on copies of `input` (left untouched) over the
/// G-buffer `position`, each for `frames` timed frames after a warm-up, and
/// reads both results back. FLIP between the two is the caller's (nv-flip is
/// a test dependency; tests/suite/denoise.rs has the helper).
#[allow(clippy::too_many_arguments)]
pub fn adaptive_vs_fixed(
    ctx: &Arc<Context>,
    input: &Image,
    position: &Image,
    camera: &Camera,
    l_min: Vec3,
    fixed_passes: u32,
    fixed_radius: u32,
    frames: u32,
) -> anyhow::Result<AdaptiveVsFixed> {
    ensure!(frames >= 1, "adaptive_vs_fixed: frames must be at least 1");
    let work = Image::new(
        ctx,
        "denoise comparison",
        ImageDesc::new_2d(
            input.desc.width,
            input.desc.height,
            vk::Format::R32G32B32A32_SFLOAT,
            vk::ImageUsageFlags::STORAGE,
        ),
    )?;
    // Per-pass times even under synchronization validation: this is a
    // measurement (its passes are validated in whole frames by the
    // technique's tests).
    let profiler = Profiler::for_timing(ctx, 2 * fixed_passes.max(1) + 2)?;
    let run = |config: DenoiseConfig| -> anyhow::Result<(Vec<f32>, f64)> {
        let denoiser = Denoiser::new(ctx, config, &work, position)?;
        let mut total_ms = 0.0;
        for frame in 0..=frames {
            let timings = profiler.frame(|rec| {
                rec.pass("denoise input copy").record(|c| {
                    c.copy_image(input, &work);
                });
                denoiser.record(
                    rec,
                    &work,
                    position,
                    camera.eye,
                    (camera.target - camera.eye).normalize(),
                    l_min,
                );
                Ok(())
            })?;
            // Frame 0 pays pipeline compilation (GUIDE §8): not timed.
            if frame > 0 {
                total_ms += timings
                    .iter()
                    .filter(|t| t.name != "denoise input copy")
                    .map(|t| t.ms)
                    .sum::<f64>();
            }
        }
        let pixels = work
            .download_rgba32f()
            .context("reading the denoised buffer back")?;
        Ok((pixels, total_ms / frames as f64))
    };
    let (adaptive, adaptive_ms) = run(DenoiseConfig {
        kind: DenoiseKind::Adaptive,
        passes: 1,
        fixed_radius,
    })?;
    let (fixed, fixed_ms) = run(DenoiseConfig {
        kind: DenoiseKind::Fixed,
        passes: fixed_passes,
        fixed_radius,
    })?;
    Ok(AdaptiveVsFixed {
        adaptive,
        fixed,
        adaptive_ms,
        fixed_ms,
        timing: profiler.source,
    })
}
