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
    /// Photons per dispatch.
    pub batch: u32,
    /// Longest path (specular bounces plus scattering events). Light
    /// trapped in a faceted diamond takes long chains: on
    /// assets/scenes/gemstone.toml a depth of 32 dropped 7% of the caustic
    /// flux landing on the floor (10% of the L S+ D image's energy;
    /// measured with the caustic map's traced photons), 128 drops 0.3%.
    pub max_depth: u32,
    /// Diffuse bounces photons continue through (0: direct and caustic light only).
    pub diffuse_bounces: u32,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        Self {
            batch: 1 << 18,
            max_depth: 128,
            diffuse_bounces: 0,
        }
    }
}

/// Push constants of every reference shader (glsl/reference/common.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Push {
    seed: u32,
    max_depth: u32,
    diffuse_bounces: u32,
    component: u32,
    photon_count: f32,
    camera_passes: f32,
    exposure: f32,
    pad: f32,
}

pub struct Reference {
    trace: ComputePipeline,
    camera: ComputePipeline,
    resolve: ComputePipeline,
    _layout: DescriptorSetLayout,
    set: DescriptorSet,
    photon_accum: Buffer,
    camera_accum: Buffer,
    settings: ReferenceSettings,
    /// Photons traced so far.
    pub photons: u64,
    /// Camera-chain passes so far.
    pub camera_passes: u64,
    dispatches: u32,
    width: u32,
    height: u32,
}

impl Reference {
    pub fn new(
        ctx: &Arc<Context>,
        scene_gpu: &SceneGpu,
        targets: &FrameTargets,
        settings: ReferenceSettings,
    ) -> anyhow::Result<Self> {
        let accum_bytes = check_image_size(ctx, targets.width, targets.height)?;
        let layout = DescriptorSetLayout::new(
            ctx,
            &[
                (0, BindingKind::Storage),
                (1, BindingKind::Storage),
                (2, BindingKind::StorageImage),
            ],
        )?;
        let sets = [&scene_gpu.layout, &layout];
        let push = std::mem::size_of::<Push>() as u32;
        let trace = ComputePipeline::new(ctx, "reference/trace.comp", &sets, push)?;
        let camera = ComputePipeline::new(ctx, "reference/camera.comp", &sets, push)?;
        let resolve = ComputePipeline::new(ctx, "reference/resolve.comp", &sets, push)?;
        let photon_accum = Buffer::new(
            ctx,
            "reference photon sums",
            accum_bytes,
            BufferUsage::Storage,
        )?;
        let camera_accum = Buffer::new(
            ctx,
            "reference camera sums",
            targets.width as u64 * targets.height as u64 * 3 * 4,
            BufferUsage::Storage,
        )?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(0, &photon_accum)
            .write_buffer(1, &camera_accum)
            .write_storage_image(2, &targets.radiance);
        Ok(Self {
            trace,
            camera,
            resolve,
            _layout: layout,
            set,
            photon_accum,
            camera_accum,
            settings,
            photons: 0,
            camera_passes: 0,
            dispatches: 0,
            width: targets.width,
            height: targets.height,
        })
    }

    fn push(&self, seed: u32, component: Component) -> Push {
        Push {
            seed,
            max_depth: self.settings.max_depth,
            diffuse_bounces: self.settings.diffuse_bounces,
            component: component.index(),
            photon_count: self.photons as f32,
            camera_passes: self.camera_passes as f32,
            exposure: 1.0,
            pad: 0.0,
        }
    }

    /// Clears the sums (first pass); records it through the recorder.
    pub fn record_clear(&mut self, rec: &mut FrameRecorder) {
        let ctx = rec.ctx().clone();
        rec.pass("reference clear", |cmd| unsafe {
            barrier(
                &ctx,
                cmd,
                &[],
                &[
                    BufferAccess::new(&self.photon_accum, Access::TransferWrite),
                    BufferAccess::new(&self.camera_accum, Access::TransferWrite),
                ],
            );
            ctx.device
                .cmd_fill_buffer(cmd, self.photon_accum.raw, 0, ash::vk::WHOLE_SIZE, 0);
            ctx.device
                .cmd_fill_buffer(cmd, self.camera_accum.raw, 0, ash::vk::WHOLE_SIZE, 0);
        });
        self.photons = 0;
        self.camera_passes = 0;
    }

    /// Records one batch of photons and one camera-chain pass.
    pub fn record_batch(&mut self, rec: &mut FrameRecorder, scene_gpu: &SceneGpu) {
        let ctx = rec.ctx().clone();
        self.dispatches = self.dispatches.wrapping_add(1);
        let seed = self.dispatches.wrapping_mul(0x9E37_79B9);
        let push = self.push(seed, Component::All);
        let sets = [&scene_gpu.set, &self.set];
        rec.pass("reference photons", |cmd| {
            barrier(
                &ctx,
                cmd,
                &[],
                &[BufferAccess::new(&self.photon_accum, Access::ComputeWrite)],
            );
            self.trace.dispatch(
                cmd,
                &sets,
                bytemuck::bytes_of(&push),
                [self.settings.batch.div_ceil(64), 1, 1],
            );
        });
        rec.pass("reference camera chains", |cmd| {
            barrier(
                &ctx,
                cmd,
                &[],
                &[BufferAccess::new(&self.camera_accum, Access::ComputeWrite)],
            );
            self.camera.dispatch(
                cmd,
                &sets,
                bytemuck::bytes_of(&push),
                [self.width.div_ceil(8), self.height.div_ceil(8), 1],
            );
        });
        self.photons += self.settings.batch.div_ceil(64) as u64 * 64;
        self.camera_passes += 1;
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
                &[
                    BufferAccess::new(&self.photon_accum, Access::ComputeRead),
                    BufferAccess::new(&self.camera_accum, Access::ComputeRead),
                ],
            );
            self.resolve.dispatch(
                cmd,
                &sets,
                bytemuck::bytes_of(&push),
                [self.width.div_ceil(8), self.height.div_ceil(8), 1],
            );
        });
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
        let mut reference = Reference::new(ctx, &scene_gpu, &targets, settings)?;
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
        })
    }

    /// Traces at least `photons` more photons in batches; `progress(done, total)`
    /// is called after each batch.
    pub fn trace(&mut self, photons: u64, mut progress: impl FnMut(u64, u64)) -> VkResult<()> {
        let target = self.reference.photons + photons;
        let start_photons = self.reference.photons;
        while self.reference.photons < target {
            let start = std::time::Instant::now();
            let reference = &mut self.reference;
            let scene_gpu = &self.scene_gpu;
            self.profiler.frame(|rec| {
                reference.record_batch(rec, scene_gpu);
                Ok(())
            })?;
            self.trace_seconds += start.elapsed().as_secs_f64();
            progress(self.reference.photons - start_photons, photons);
        }
        Ok(())
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
