//! The ground truth (GUIDE §3): a progressive light tracer in compute against
//! the BVH (glsl/reference/trace.comp), plus the camera-side specular chains
//! (glsl/reference/camera.comp), resolved into radiance per path type.

use crate::frame::{FrameTargets, SceneGpu};
// `Component` lives in `radiometry` (frame constants and techniques use it
// too); re-exported so `reference::Component` keeps naming the ground
// truth's path types for the CLI and the reference tests.
pub use crate::radiometry::Component;
use crate::shader_bindings as b;
use crate::vk::{
    barrier, Access, BindingKind, Buffer, BufferAccess, BufferUsage, ComputePipeline, Context,
    DescriptorSet, DescriptorSetLayout, FrameRecorder, ImageAccess, VkResult,
};
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

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

/// A sphere around every mirror and dielectric triangle of `scene` at
/// `time` (the box's centre and half diagonal), or None without any.
pub fn specular_sphere(scene: &crate::scene::Scene, time: f32) -> Option<(glam::Vec3, f32)> {
    use crate::scene::MaterialKind;
    let mut lo = glam::Vec3::splat(f32::INFINITY);
    let mut hi = glam::Vec3::splat(f32::NEG_INFINITY);
    for t in scene.triangles(time) {
        if scene.materials[t.material as usize].kind != MaterialKind::Diffuse {
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

/// Push constants of every reference shader (glsl/reference/common.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Push {
    seed: u32,
    max_depth: u32,
    diffuse_bounces: u32,
    component: u32,
    passes: f32,
    pass_photons: f32,
    radius: f32,
    volume_radius: f32,
    surface_mask: u32,
    volume_mask: u32,
    volume_capacity: u32,
    gather: u32,
    aim: [f32; 4],
    aim_share: f32,
    pad: [u32; 3],
}

/// What one pass leaves behind, for the progress report.
#[derive(Clone, Copy, Debug, Default)]
pub struct PassReport {
    /// Surface and volume gather radii the pass used (m).
    pub radius: f32,
    pub volume_radius: f32,
    /// Medium collisions the pass tried to store (more than the capacity: overflow).
    pub volume_photons: u32,
}

pub struct Reference {
    trace: ComputePipeline,
    camera: ComputePipeline,
    camera_volume: ComputePipeline,
    fold: ComputePipeline,
    noise: ComputePipeline,
    resolve: ComputePipeline,
    _layout: DescriptorSetLayout,
    set: DescriptorSet,
    total: Buffer,
    pass_sums: Buffer,
    moments: Buffer,
    visible_points: Buffer,
    surface_heads: Buffer,
    surface_next: Buffer,
    volume_photons: Buffer,
    volume_heads: Buffer,
    volume_next: Buffer,
    stats: Buffer,
    settings: ReferenceSettings,
    surface_table: u32,
    volume_table: u32,
    volume_capacity: u32,
    /// Where photons are aimed: centre and radius (0: nowhere).
    aim: [f32; 4],
    /// Radii of the next pass.
    radius: f32,
    volume_radius: f32,
    /// Photons traced so far.
    pub photons: u64,
    /// Passes so far (each: camera chains, one batch of photons, gathers).
    pub passes: u64,
    dispatches: u32,
    width: u32,
    height: u32,
}

impl Reference {
    /// `radius`: the first pass's surface gather radius (m); `aim`: the
    /// bounding sphere photons are aimed at (`specular_sphere`).
    pub fn new(
        ctx: &Arc<Context>,
        scene_gpu: &SceneGpu,
        targets: &FrameTargets,
        settings: ReferenceSettings,
        radius: f32,
        has_medium: bool,
        aim: Option<(glam::Vec3, f32)>,
    ) -> anyhow::Result<Self> {
        let accum_bytes = check_image_size(ctx, targets.width, targets.height)?;
        if !(radius.is_finite() && radius > 0.0) {
            anyhow::bail!("the photon-mapping radius must be positive and finite, got {radius}");
        }
        if !(0.0..1.0).contains(&settings.aim_share) {
            anyhow::bail!(
                "the aimed share of photons must lie in [0, 1), got {}",
                settings.aim_share
            );
        }
        if !(settings.alpha > 0.0 && settings.alpha < 1.0) {
            anyhow::bail!("alpha must lie in (0, 1), got {}", settings.alpha);
        }
        let pixels = targets.width as u64 * targets.height as u64;
        let storage = |binding| (binding, BindingKind::Storage);
        let layout = DescriptorSetLayout::new(
            ctx,
            &[
                storage(b::REFERENCE_BINDING_TOTAL),
                storage(b::REFERENCE_BINDING_PASS),
                (b::REFERENCE_BINDING_RADIANCE, BindingKind::StorageImage),
                storage(b::REFERENCE_BINDING_MOMENTS),
                storage(b::REFERENCE_BINDING_VISIBLE_POINTS),
                storage(b::REFERENCE_BINDING_SURFACE_HEADS),
                storage(b::REFERENCE_BINDING_SURFACE_NEXT),
                storage(b::REFERENCE_BINDING_VOLUME_PHOTONS),
                storage(b::REFERENCE_BINDING_VOLUME_HEADS),
                storage(b::REFERENCE_BINDING_VOLUME_NEXT),
                storage(b::REFERENCE_BINDING_STATS),
            ],
        )?;
        let sets = [&scene_gpu.layout, &layout];
        let push = std::mem::size_of::<Push>() as u32;
        let pipeline = |name| ComputePipeline::new(ctx, name, &sets, push);
        let buffer = |name, bytes| Buffer::new(ctx, name, bytes, BufferUsage::Storage);
        // A hash table twice as large as the points it holds keeps chains short.
        let surface_table = (2 * pixels).next_power_of_two().min(1 << 30) as u32;
        let volume_capacity = if has_medium && settings.photon_mapping {
            settings.volume_capacity
        } else {
            0
        };
        let volume_table = (2 * volume_capacity as u64).next_power_of_two().max(1) as u32;
        let vp_bytes = pixels * std::mem::size_of::<[f32; 12]>() as u64;
        let volume_bytes = volume_capacity as u64 * std::mem::size_of::<[f32; 12]>() as u64;
        if vp_bytes.max(volume_bytes) > ctx.limits.max_storage_buffer_range as u64 {
            anyhow::bail!(
                "the reference's photon-mapping buffers ({} MiB) exceed the device's {} MiB per buffer",
                vp_bytes.max(volume_bytes) >> 20,
                ctx.limits.max_storage_buffer_range >> 20
            );
        }
        let reference = Self {
            trace: pipeline("reference/trace.comp")?,
            camera: pipeline("reference/camera.comp")?,
            camera_volume: pipeline("reference/camera_volume.comp")?,
            fold: pipeline("reference/fold.comp")?,
            noise: pipeline("reference/noise.comp")?,
            resolve: pipeline("reference/resolve.comp")?,
            total: buffer("reference sums", accum_bytes)?,
            pass_sums: buffer("reference pass estimates", accum_bytes)?,
            moments: buffer("reference moments", pixels * 8)?,
            visible_points: buffer("reference visible points", vp_bytes)?,
            surface_heads: buffer("reference surface grid", surface_table as u64 * 4)?,
            surface_next: buffer("reference surface links", pixels * 4)?,
            volume_photons: buffer("reference volume photons", volume_bytes)?,
            volume_heads: buffer("reference volume grid", volume_table as u64 * 4)?,
            volume_next: buffer("reference volume links", volume_capacity as u64 * 4)?,
            stats: buffer("reference counters", 16)?,
            set: DescriptorSet::new(ctx, &layout)?,
            _layout: layout,
            settings,
            surface_table,
            volume_table,
            volume_capacity,
            aim: aim.map_or([0.0; 4], |(c, r)| [c.x, c.y, c.z, r]),
            radius,
            volume_radius: settings
                .volume_radius
                .unwrap_or(radius * VOLUME_RADIUS_FACTOR),
            photons: 0,
            passes: 0,
            dispatches: 0,
            width: targets.width,
            height: targets.height,
        };
        reference
            .set
            .write_buffer(b::REFERENCE_BINDING_TOTAL, &reference.total)
            .write_buffer(b::REFERENCE_BINDING_PASS, &reference.pass_sums)
            .write_storage_image(b::REFERENCE_BINDING_RADIANCE, &targets.radiance)
            .write_buffer(b::REFERENCE_BINDING_MOMENTS, &reference.moments)
            .write_buffer(
                b::REFERENCE_BINDING_VISIBLE_POINTS,
                &reference.visible_points,
            )
            .write_buffer(b::REFERENCE_BINDING_SURFACE_HEADS, &reference.surface_heads)
            .write_buffer(b::REFERENCE_BINDING_SURFACE_NEXT, &reference.surface_next)
            .write_buffer(
                b::REFERENCE_BINDING_VOLUME_PHOTONS,
                &reference.volume_photons,
            )
            .write_buffer(b::REFERENCE_BINDING_VOLUME_HEADS, &reference.volume_heads)
            .write_buffer(b::REFERENCE_BINDING_VOLUME_NEXT, &reference.volume_next)
            .write_buffer(b::REFERENCE_BINDING_STATS, &reference.stats);
        Ok(reference)
    }

    fn pass_photons(&self) -> u64 {
        self.settings.batch.div_ceil(64) as u64 * 64
    }

    fn push(&self, seed: u32, component: Component) -> Push {
        Push {
            seed,
            max_depth: self.settings.max_depth,
            diffuse_bounces: self.settings.diffuse_bounces,
            component: component.index(),
            passes: self.passes as f32,
            pass_photons: self.pass_photons() as f32,
            radius: self.radius,
            volume_radius: self.volume_radius,
            surface_mask: self.surface_table - 1,
            volume_mask: self.volume_table - 1,
            volume_capacity: self.volume_capacity,
            gather: self.settings.photon_mapping as u32,
            aim: self.aim,
            aim_share: self.settings.aim_share,
            pad: [0; 3],
        }
    }

    /// Clears the sums (first pass); records it through the recorder.
    pub fn record_clear(&mut self, rec: &mut FrameRecorder) {
        let ctx = rec.ctx().clone();
        let cleared = [&self.total, &self.pass_sums, &self.moments];
        rec.pass("reference clear", |cmd| {
            fill(&ctx, cmd, &cleared, 0);
        });
        self.photons = 0;
        self.passes = 0;
    }

    /// Records one pass: camera chains and visible points, one batch of
    /// photons (camera connections and surface gathers), the volume gather
    /// along camera chains (scenes with a medium), then the fold into the
    /// sums. Shrinks the radii for the next pass.
    pub fn record_pass(&mut self, rec: &mut FrameRecorder, scene_gpu: &SceneGpu) -> PassReport {
        let ctx = rec.ctx().clone();
        self.dispatches = self.dispatches.wrapping_add(1);
        let seed = self
            .dispatches
            .wrapping_mul(0x9E37_79B9)
            .wrapping_add(self.settings.seed.wrapping_mul(0x85EB_CA6B));
        let push = self.push(seed, Component::All);
        let push = bytemuck::bytes_of(&push);
        let sets = [&scene_gpu.set, &self.set];
        let pixel_groups = [self.width.div_ceil(8), self.height.div_ceil(8), 1];
        rec.pass("reference visible points", |cmd| {
            fill(&ctx, cmd, &[&self.surface_heads], b::REFERENCE_GRID_NONE);
            barrier(
                &ctx,
                cmd,
                &[],
                &[
                    BufferAccess::new(&self.pass_sums, Access::ComputeWrite),
                    BufferAccess::new(&self.visible_points, Access::ComputeWrite),
                    BufferAccess::new(&self.surface_heads, Access::ComputeWrite),
                    BufferAccess::new(&self.surface_next, Access::ComputeWrite),
                ],
            );
            self.camera.dispatch(cmd, &sets, push, pixel_groups);
        });
        rec.pass("reference photons", |cmd| {
            fill(&ctx, cmd, &[&self.volume_heads], b::REFERENCE_GRID_NONE);
            fill(&ctx, cmd, &[&self.stats], 0);
            barrier(
                &ctx,
                cmd,
                &[],
                &[
                    BufferAccess::new(&self.pass_sums, Access::ComputeWrite),
                    BufferAccess::new(&self.visible_points, Access::ComputeRead),
                    BufferAccess::new(&self.surface_heads, Access::ComputeRead),
                    BufferAccess::new(&self.surface_next, Access::ComputeRead),
                    BufferAccess::new(&self.volume_photons, Access::ComputeWrite),
                    BufferAccess::new(&self.volume_heads, Access::ComputeWrite),
                    BufferAccess::new(&self.volume_next, Access::ComputeWrite),
                    BufferAccess::new(&self.stats, Access::ComputeWrite),
                ],
            );
            self.trace
                .dispatch(cmd, &sets, push, [self.settings.batch.div_ceil(64), 1, 1]);
        });
        if self.volume_capacity > 0 {
            rec.pass("reference volume gather", |cmd| {
                barrier(
                    &ctx,
                    cmd,
                    &[],
                    &[
                        BufferAccess::new(&self.pass_sums, Access::ComputeWrite),
                        BufferAccess::new(&self.volume_photons, Access::ComputeRead),
                        BufferAccess::new(&self.volume_heads, Access::ComputeRead),
                        BufferAccess::new(&self.volume_next, Access::ComputeRead),
                        BufferAccess::new(&self.stats, Access::ComputeRead),
                    ],
                );
                self.camera_volume.dispatch(cmd, &sets, push, pixel_groups);
            });
        }
        rec.pass("reference fold", |cmd| {
            barrier(
                &ctx,
                cmd,
                &[],
                &[
                    BufferAccess::new(&self.pass_sums, Access::ComputeWrite),
                    BufferAccess::new(&self.total, Access::ComputeWrite),
                    BufferAccess::new(&self.moments, Access::ComputeWrite),
                ],
            );
            let pixels = self.width * self.height;
            self.fold
                .dispatch(cmd, &sets, push, [pixels.div_ceil(64), 1, 1]);
        });
        let report = PassReport {
            radius: self.radius,
            volume_radius: self.volume_radius,
            volume_photons: 0,
        };
        self.photons += self.pass_photons();
        self.passes += 1;
        let alpha = self.settings.alpha;
        self.radius = next_radius(self.radius, self.passes, alpha, 2);
        self.volume_radius = next_radius(self.volume_radius, self.passes, alpha, 3);
        report
    }

    /// Records the noise reduction over the image (counters 1 and 2 of `stats`).
    pub fn record_noise(&self, rec: &mut FrameRecorder, scene_gpu: &SceneGpu) {
        let ctx = rec.ctx().clone();
        let push = self.push(0, Component::All);
        let sets = [&scene_gpu.set, &self.set];
        rec.pass("reference noise", |cmd| {
            fill(&ctx, cmd, &[&self.stats], 0);
            barrier(
                &ctx,
                cmd,
                &[],
                &[
                    BufferAccess::new(&self.moments, Access::ComputeRead),
                    BufferAccess::new(&self.stats, Access::ComputeWrite),
                ],
            );
            let pixels = self.width * self.height;
            self.noise.dispatch(
                cmd,
                &sets,
                bytemuck::bytes_of(&push),
                [pixels.div_ceil(64), 1, 1],
            );
        });
    }

    /// Resolves `component` into the frame's radiance image.
    pub fn record_resolve(
        &self,
        rec: &mut FrameRecorder,
        scene_gpu: &SceneGpu,
        targets: &FrameTargets,
        component: Component,
    ) {
        let ctx = rec.ctx().clone();
        let push = self.push(0, component);
        let sets = [&scene_gpu.set, &self.set];
        rec.pass("reference resolve", |cmd| {
            barrier(
                &ctx,
                cmd,
                &[ImageAccess::discard(
                    &targets.radiance,
                    Access::ComputeWrite,
                )],
                &[BufferAccess::new(&self.total, Access::ComputeRead)],
            );
            self.resolve.dispatch(
                cmd,
                &sets,
                bytemuck::bytes_of(&push),
                [self.width.div_ceil(8), self.height.div_ceil(8), 1],
            );
        });
    }

    /// The counters the last pass (or noise reduction) left: volume photons
    /// stored, sum of the variance of the mean, sum of the mean.
    pub fn read_stats(&self) -> VkResult<(u32, f32, f32)> {
        let words: Vec<u32> = self.stats.download_pod()?;
        Ok((words[0], f32::from_bits(words[1]), f32::from_bits(words[2])))
    }

    /// The surface gather radius of the next pass (m).
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Medium collisions one pass can store.
    pub fn volume_capacity(&self) -> u32 {
        self.volume_capacity
    }
}

/// Fills whole buffers with `value` before a compute pass writes them.
fn fill(ctx: &Context, cmd: ash::vk::CommandBuffer, buffers: &[&Buffer], value: u32) {
    let accesses: Vec<_> = buffers
        .iter()
        .map(|b| BufferAccess::new(b, Access::TransferWrite))
        .collect();
    barrier(ctx, cmd, &[], &accesses);
    for b in buffers {
        // SAFETY: the buffer is alive and its barrier above orders the fill.
        unsafe {
            ctx.device
                .cmd_fill_buffer(cmd, b.raw, 0, ash::vk::WHOLE_SIZE, value)
        };
    }
}

/// Bytes of the photon sums for a `width` x `height` image: one rgb float sum
/// per pixel and path type, addressed by a 32-bit index. An error when the
/// device cannot hold them in one storage buffer.
pub fn check_image_size(ctx: &Context, width: u32, height: u32) -> anyhow::Result<u64> {
    let bytes = width as u64 * height as u64 * 3 * 4 * b::COMPONENT_COUNT as u64;
    let limit = (ctx.limits.max_storage_buffer_range as u64).min(u32::MAX as u64);
    if bytes > limit {
        anyhow::bail!(
            "{width}x{height} is too large for the reference on {}: its sums need {} MiB, the device allows {} MiB per buffer",
            ctx.info.name,
            bytes >> 20,
            limit >> 20
        );
    }
    Ok(bytes)
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
    pub reference: Reference,
    /// Seconds spent tracing so far (photons/s = photons / this).
    pub trace_seconds: f64,
    /// Milliseconds per stage of a pass, summed over passes (profiler names).
    pub pass_ms: Vec<(String, f64)>,
    /// Medium collisions dropped because a pass's volume photon map was full.
    pub volume_overflow: u64,
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
            scene.medium.is_some(),
            specular_sphere(&scene, time),
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
    /// milliseconds to `pass_ms` and counts volume photons that did not fit.
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
            let (stored, _, _) = self.reference.read_stats()?;
            report.volume_photons = stored;
            self.volume_overflow += stored.saturating_sub(self.reference.volume_capacity()) as u64;
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
        let (_, variance, mean) = self.reference.read_stats()?;
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

    pub fn photons_per_second(&self) -> f64 {
        if self.trace_seconds > 0.0 {
            self.reference.photons as f64 / self.trace_seconds
        } else {
            0.0
        }
    }
}
