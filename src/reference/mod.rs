//! The ground truth (GUIDE §3): a progressive light tracer in compute against
//! the BVH (glsl/reference/trace.comp), plus the camera-side specular chains
//! (glsl/reference/camera.comp), resolved into radiance per path type.

use crate::frame::{FrameTargets, SceneGpu};
// `Component` lives in `radiometry` (frame constants and techniques use it
// too); re-exported so `reference::Component` keeps naming the ground
// truth's path types for the CLI and the reference tests.
pub use crate::radiometry::Component;
use crate::vk::{Context, VkResult};
use std::sync::Arc;

mod tracer;

pub use tracer::{check_image_size, PassReport, Reference};

#[derive(Clone, Copy, Debug)]
pub struct ReferenceSettings {
    /// Photons per pass (rounded up to a multiple of 64).
    pub batch: u32,
    /// Longest path (specular bounces plus scattering events). Light
    /// trapped in a faceted diamond takes long chains: on
    /// assets/scenes/gemstone.toml a depth of 32 dropped 7% of the caustic
    /// flux landing on the floor (10% of the L S+ D image's energy;
    /// measured with the caustic map's traced photons), 128 drops 0.3%.
    pub max_depth: u32,
    /// Diffuse bounces photons continue through (0: direct and caustic light only).
    pub diffuse_bounces: u32,
    /// Mixed into every pass's random stream: runs with different seeds are
    /// independent estimates, runs with the same seed the same one.
    pub seed: u32,
    /// Progressive photon mapping at the end of camera-side specular chains
    /// (what is seen through glass, water and mirrors). Off: the light
    /// tracer and the chains' direct light only (the former reference).
    pub photon_mapping: bool,
    /// First pass's surface gather radius (m); None: `default_radius`.
    pub radius: Option<f32>,
    /// First pass's volume gather radius (m); None: VOLUME_RADIUS_FACTOR
    /// times the surface radius.
    pub volume_radius: Option<f32>,
    /// Knaus & Zwicker's alpha in (0, 1): the share of the radius' variance
    /// reduction kept each pass (2/3 as they recommend).
    pub alpha: f32,
    /// Medium collisions stored per pass for the volume gather.
    pub volume_capacity: u32,
    /// Share of the photons aimed at the bounding sphere of the specular
    /// objects (a mixture with the light's own distribution, unbiased for
    /// any share below 1; 0: none aimed).
    pub aim_share: f32,
    /// Aimed photons follow the aim guide (glsl/reference/aim_guide.glsl):
    /// where earlier passes' aimed photons reached the image. Off: uniform
    /// over the aimed region.
    pub aim_guide: bool,
    /// Camera chains split at this many of their first Fresnel choices
    /// (glsl/reference/camera.comp, "Fresnel splitting"), at most
    /// REFERENCE_MAX_FRESNEL_SPLITS: 2^splits visible points a pixel and
    /// pass. 0: every choice random, as a path tracer makes it.
    pub fresnel_splits: u32,
}

impl ReferenceSettings {
    /// Photons one pass traces: `batch` rounded up to whole workgroups of 64.
    pub fn pass_photons(&self) -> u64 {
        u64::from(self.batch.div_ceil(64)) * 64
    }

    /// Whole passes that trace at least `photons`.
    pub fn passes_for(&self, photons: u64) -> u64 {
        photons.div_ceil(self.pass_photons())
    }
}

/// The volume radius starts this many surface radii wide: a 3D density
/// needs a wider kernel than a 2D one for the same photon count.
pub const VOLUME_RADIUS_FACTOR: f32 = 3.0;

impl Default for ReferenceSettings {
    fn default() -> Self {
        Self {
            batch: 1 << 18,
            max_depth: 128,
            diffuse_bounces: 0,
            seed: 0,
            photon_mapping: true,
            radius: None,
            volume_radius: None,
            alpha: 2.0 / 3.0,
            volume_capacity: 1 << 21,
            aim_share: 0.5,
            aim_guide: true,
            fresnel_splits: crate::shader_bindings::REFERENCE_MAX_FRESNEL_SPLITS,
        }
    }
}

/// The first pass's surface gather radius: 1.5 pixel footprints at the
/// distance from the eye to the camera target, where the subject is. Small
/// enough that the blur it leaves is under two pixels there from the first
/// pass, large enough that a visible point on a caustic meets dozens of
/// photons per pass at 2^18 photons (ball_lens and water_pool at 128 px).
pub fn default_radius(camera: &crate::scene::Camera, height: u32) -> f32 {
    let distance = (camera.target - camera.eye).length().max(1e-3);
    let footprint = 2.0 * (camera.fov_y_deg.to_radians() * 0.5).tan() * distance / height as f32;
    1.5 * footprint
}

/// A sphere around every mirror, dielectric and `mixed` triangle of `scene` at
/// `time` (the box's centre and half diagonal), or None without any.
pub fn specular_sphere(scene: &crate::scene::Scene, time: f32) -> Option<(glam::Vec3, f32)> {
    use crate::scene::MaterialKind;
    let mut lo = glam::Vec3::splat(f32::INFINITY);
    let mut hi = glam::Vec3::splat(f32::NEG_INFINITY);
    for t in scene.triangles(time) {
        let m = &scene.materials[t.material as usize];
        if m.kind != MaterialKind::Diffuse || m.is_mixed() {
            for p in t.positions {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    (lo.x <= hi.x).then(|| ((lo + hi) * 0.5, ((hi - lo) * 0.5).length().max(1e-4)))
}

/// Knaus & Zwicker 2011 (probabilistic progressive photon mapping), Eq. 15
/// with the kernel's dimension d: r_{i+1}^d = r_i^d (i + alpha) / (i + 1)
/// for pass i = 1, 2, ...; d = 2 for surfaces, 3 for the volume. The
/// variance of pass i then grows as prod (i+1)/(i+alpha) while its bias
/// shrinks with r_i^2, and the mean over passes converges.
pub fn next_radius(radius: f32, pass: u64, alpha: f32, dimension: i32) -> f32 {
    let i = pass as f64;
    let ratio = (i + alpha as f64) / (i + 1.0);
    (radius as f64 * ratio.powf(1.0 / dimension as f64)) as f32
}

/// Everything `caustics reference` needs: the scene on the GPU, the output
/// images and the tracer, run batch by batch.
pub struct ReferenceRenderer {
    pub ctx: Arc<Context>,
    pub scene: crate::scene::Scene,
    pub scene_gpu: SceneGpu,
    pub targets: FrameTargets,
    pub tonemap: crate::passes::tonemap::Tonemap,
    pub profiler: crate::vk::Profiler,
    /// The tracer; callers read its progress through `photons`, `passes`
    /// and the other accessors below.
    reference: Reference,
    /// Seconds spent tracing so far (photons/s = photons / this).
    pub trace_seconds: f64,
    /// Milliseconds per stage of a pass, summed over passes (profiler names).
    pub pass_ms: Vec<(String, f64)>,
    /// Medium collisions dropped because a pass's volume photon map was full.
    pub volume_overflow: u64,
    /// Gather points dropped because a pass's gather point buffer was full.
    pub gather_overflow: u64,
    /// The longest cell walk of any pass's volume gather
    /// (`REFERENCE_GATHER_WALK_LIMIT`: walks were cut short, photons missed).
    pub longest_walk: u32,
}

impl ReferenceRenderer {
    pub fn new(
        ctx: &Arc<Context>,
        scene: crate::scene::Scene,
        width: u32,
        height: u32,
        time: f32,
        settings: ReferenceSettings,
    ) -> anyhow::Result<Self> {
        check_image_size(ctx, width, height)?;
        let scene_gpu = SceneGpu::new(ctx, &scene, time)?;
        scene_gpu.update_frame(&scene, width, height, time, 0)?;
        let targets = FrameTargets::new(ctx, width, height)?;
        let tonemap = crate::passes::tonemap::Tonemap::new(ctx, &targets.radiance)?;
        let radius = settings
            .radius
            .unwrap_or_else(|| default_radius(&scene.camera, height));
        let mut reference = Reference::new(
            ctx,
            &scene_gpu,
            &targets,
            settings,
            radius,
            tracer::Media::of(&scene),
            specular_sphere(&scene, time),
            scene.lights.len(),
        )?;
        let profiler = crate::vk::Profiler::new(ctx, 16)?;
        profiler.frame(|rec| {
            reference.record_clear(rec);
            Ok(())
        })?;
        Ok(Self {
            ctx: ctx.clone(),
            scene,
            scene_gpu,
            targets,
            tonemap,
            profiler,
            reference,
            trace_seconds: 0.0,
            pass_ms: Vec::new(),
            volume_overflow: 0,
            gather_overflow: 0,
            longest_walk: 0,
        })
    }

    /// Runs passes until at least `photons` more photons are traced.
    pub fn trace(&mut self, photons: u64, mut progress: impl FnMut(u64, u64)) -> VkResult<()> {
        let target = self.reference.photons + photons;
        let start_photons = self.reference.photons;
        while self.reference.photons < target {
            self.pass()?;
            progress(self.reference.photons - start_photons, photons);
        }
        Ok(())
    }

    /// Runs one pass (see `Reference::record_pass`); adds its per-stage
    /// milliseconds to `pass_ms` and counts volume photons and gather points
    /// that did not fit.
    pub fn pass(&mut self) -> VkResult<PassReport> {
        let start = std::time::Instant::now();
        let reference = &mut self.reference;
        let scene_gpu = &self.scene_gpu;
        let mut report = PassReport::default();
        let timings = self.profiler.frame(|rec| {
            report = reference.record_pass(rec, scene_gpu);
            Ok(())
        })?;
        self.trace_seconds += start.elapsed().as_secs_f64();
        for t in timings {
            match self.pass_ms.iter_mut().find(|(name, _)| *name == t.name) {
                Some((_, ms)) => *ms += t.ms,
                None => self.pass_ms.push((t.name, t.ms)),
            }
        }
        if self.reference.volume_capacity() > 0 {
            let stats = self.reference.read_stats()?;
            report.volume_photons = stats.volume_photons;
            let excess = |count: u32, capacity: u32| count.saturating_sub(capacity) as u64;
            self.volume_overflow += excess(stats.volume_photons, self.reference.volume_capacity());
            self.gather_overflow += excess(stats.gather_points, self.reference.gather_capacity());
            self.longest_walk = self.longest_walk.max(stats.longest_walk);
        }
        Ok(report)
    }

    /// The remaining noise: the RMS over pixels of the standard error of the
    /// mean of the pass estimates, relative to the mean pixel luminance
    /// (needs two passes; None before, or for a black image).
    pub fn noise(&mut self) -> VkResult<Option<f64>> {
        if self.reference.passes < 2 {
            return Ok(None);
        }
        let reference = &self.reference;
        let scene_gpu = &self.scene_gpu;
        self.profiler.frame(|rec| {
            reference.record_noise(rec, scene_gpu);
            Ok(())
        })?;
        let stats = self.reference.read_stats()?;
        let (variance, mean) = (stats.noise_variance_sum, stats.noise_mean_sum);
        Ok((mean > 0.0)
            .then(|| (variance as f64).sqrt() / mean as f64 * (self.pixels() as f64).sqrt()))
    }

    fn pixels(&self) -> u64 {
        self.targets.width as u64 * self.targets.height as u64
    }

    /// Radiance of one component (RGBA f32, rows top to bottom); also leaves it
    /// tonemapped in `tonemap.display`.
    pub fn resolve(&mut self, component: Component) -> VkResult<Vec<f32>> {
        let reference = &self.reference;
        let (scene_gpu, targets, tonemap) = (&self.scene_gpu, &self.targets, &self.tonemap);
        let exposure = self.scene.output.exposure;
        self.profiler.frame(|rec| {
            reference.record_resolve(rec, scene_gpu, targets, component);
            tonemap.record(rec, &targets.radiance, exposure);
            Ok(())
        })?;
        self.targets.radiance.download_rgba32f()
    }

    pub fn display(&self) -> VkResult<Vec<u8>> {
        self.tonemap.display.download_bytes(4)
    }

    /// Photons traced so far.
    pub fn photons(&self) -> u64 {
        self.reference.photons
    }

    /// Passes so far (each: camera chains, one batch of photons, gathers).
    pub fn passes(&self) -> u64 {
        self.reference.passes
    }

    /// The surface gather radius of the next pass (m).
    pub fn radius(&self) -> f32 {
        self.reference.radius()
    }

    /// Medium collisions one pass can store.
    pub fn volume_capacity(&self) -> u32 {
        self.reference.volume_capacity()
    }

    /// Gather points one pass can store.
    pub fn gather_capacity(&self) -> u32 {
        self.reference.gather_capacity()
    }

    pub fn photons_per_second(&self) -> f64 {
        if self.trace_seconds > 0.0 {
            self.reference.photons as f64 / self.trace_seconds
        } else {
            0.0
        }
    }
}
