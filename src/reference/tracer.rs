//! The tracer's GPU side: its buffers, pipelines and the passes of one
//! progressive pass (clear, light tracing and camera chains, gather, noise,
//! resolve). `ReferenceRenderer` (mod.rs) drives it.

use super::{next_radius, ReferenceSettings, VOLUME_RADIUS_FACTOR};
use crate::frame::{FrameTargets, SceneGpu};
use crate::radiometry::Component;
use crate::shader_bindings as b;
use crate::vk::{
    groups_8x8, Access, Buffer, BufferUsage, ComputePipeline, Context, DescriptorSet,
    DescriptorSetLayout, FrameRecorder, VkResult,
};
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

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
    gather_capacity: u32,
    aim_guide: u32,
    fresnel_splits: u32,
}

/// The counters of `stats` (glsl/reference/common.glsl).
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    pub volume_photons: u32,
    pub noise_variance_sum: f32,
    pub noise_mean_sum: f32,
    pub gather_points: u32,
    pub longest_walk: u32,
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
    volume_points: ComputePipeline,
    volume_gather: ComputePipeline,
    aim_guide_build: ComputePipeline,
    fold: ComputePipeline,
    noise: ComputePipeline,
    resolve: ComputePipeline,
    _layout: DescriptorSetLayout,
    set: DescriptorSet,
    /// The resolve's own set: the same buffers plus the frame's radiance
    /// image, which its pass declares (the main set is bound by every
    /// other pass of the frame before it).
    resolve_set: DescriptorSet,
    total: Buffer,
    pass_sums: Buffer,
    moments: Buffer,
    visible_points: Buffer,
    surface_heads: Buffer,
    surface_next: Buffer,
    volume_photons: Buffer,
    volume_heads: Buffer,
    volume_next: Buffer,
    gather_points: Buffer,
    /// Per point, spot and directional light: the aim guide
    /// (glsl/reference/aim_guide.glsl), rebuilt before every photon pass.
    aim_guide: Buffer,
    /// Lights the guide is rebuilt for (0: no guide).
    guided_lights: u32,
    /// The guide's learning pass is traced (`record_pass`).
    learned: bool,
    stats: Buffer,
    settings: ReferenceSettings,
    surface_table: u32,
    volume_table: u32,
    volume_capacity: u32,
    gather_capacity: u32,
    /// Where photons are aimed: centre and radius (0: nowhere).
    aim: [f32; 4],
    /// The share of the point, spot and directional lights' photons aimed
    /// there (`aim_share_for`).
    aim_share: f32,
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

/// The share of the point, spot and directional lights' photons aimed at
/// the specular objects. The user's share (a mixture with the light's own
/// distribution), except where a photon that misses the specular objects'
/// sphere carries nothing to the image: without a medium and without
/// diffuse bounces it can only land on a diffuse surface straight from the
/// light, which is direct light, the camera side's shadow rays
/// (trace.comp `straight_from_sampled_light`), and stop. There every photon
/// is aimed: the estimate stays unbiased (what the aimed pdf leaves out is
/// zero) and on `ball_lens_top` twice the aimed photons cost about 1.3
/// times the time (a workgroup of mixed photons waits for its aimed ones).
fn aim_share_for(settings: &ReferenceSettings, has_medium: bool) -> f32 {
    let nothing_else = !has_medium && settings.diffuse_bounces == 0;
    if settings.aim_share > 0.0 && nothing_else {
        1.0
    } else {
        settings.aim_share
    }
}

/// Where light scatters in a scene: its `[medium]`, and media inside
/// dielectrics (`Material::holds_medium`).
#[derive(Clone, Copy, Debug)]
pub struct Media {
    pub scene: bool,
    pub inside_dielectrics: bool,
}

impl Media {
    pub fn of(scene: &crate::scene::Scene) -> Self {
        Self {
            scene: scene.medium.is_some(),
            inside_dielectrics: scene
                .materials
                .iter()
                .any(crate::scene::Material::holds_medium),
        }
    }
}

impl Reference {
    /// `radius`: the first pass's surface gather radius (m); `aim`: the
    /// bounding sphere photons are aimed at (`specular_sphere`); `lights`:
    /// the scene's point, spot and directional lights; `media`: where
    /// light scatters.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Arc<Context>,
        scene_gpu: &SceneGpu,
        targets: &FrameTargets,
        settings: ReferenceSettings,
        radius: f32,
        media: Media,
        aim: Option<(glam::Vec3, f32)>,
        lights: usize,
    ) -> anyhow::Result<Self> {
        let accum_bytes = check_image_size(ctx, targets.width, targets.height)?;
        let has_medium = media.scene || media.inside_dielectrics;
        let inside_media = media.inside_dielectrics;
        if !(radius.is_finite() && radius > 0.0) {
            anyhow::bail!("the photon-mapping radius must be positive and finite, got {radius}");
        }
        if !(0.0..1.0).contains(&settings.aim_share) {
            anyhow::bail!(
                "the aimed share of photons must lie in [0, 1), got {}",
                settings.aim_share
            );
        }
        if settings.fresnel_splits > b::REFERENCE_MAX_FRESNEL_SPLITS {
            anyhow::bail!(
                "the camera chains split at most {} Fresnel choices, got {}",
                b::REFERENCE_MAX_FRESNEL_SPLITS,
                settings.fresnel_splits
            );
        }
        if !(settings.alpha > 0.0 && settings.alpha < 1.0) {
            anyhow::bail!("alpha must lie in (0, 1), got {}", settings.alpha);
        }
        let pixels = targets.width as u64 * targets.height as u64;
        // Every pass binds the one set: its layout is what the passes'
        // shaders use.
        let layout = DescriptorSetLayout::of_shaders(
            ctx,
            1,
            &[
                "reference/trace.comp",
                "reference/camera.comp",
                "reference/volume_points.comp",
                "reference/volume_gather.comp",
                "reference/aim_guide.comp",
                "reference/fold.comp",
                "reference/noise.comp",
                "reference/resolve.comp",
            ],
        )?;
        let sets = [&scene_gpu.layout, &layout];
        let push = std::mem::size_of::<Push>() as u32;
        let pipeline = |name| ComputePipeline::new(ctx, name, &sets, push);
        let buffer = |name, bytes| Buffer::new(ctx, name, bytes, BufferUsage::Storage);
        // Visible points: one per branch of a pixel's camera chain
        // (camera.comp, "Fresnel splitting"); fewer splits where the
        // branches' points would not fit in one storage buffer.
        let point_bytes = std::mem::size_of::<[f32; 12]>() as u64;
        let range = ctx.limits.max_storage_buffer_range as u64;
        let mut settings = settings;
        while settings.fresnel_splits > 0
            && (pixels << settings.fresnel_splits) * point_bytes > range
        {
            settings.fresnel_splits -= 1;
        }
        let points = pixels << settings.fresnel_splits;
        // A hash table twice as large as the points it holds keeps chains short.
        let surface_table = (2 * points).next_power_of_two().min(1 << 30) as u32;
        let volume_capacity = if has_medium && settings.photon_mapping {
            settings.volume_capacity
        } else {
            0
        };
        let volume_table = (2 * volume_capacity as u64).next_power_of_two().max(1) as u32;
        // Gather points: FIRST_SEGMENT_POINTS (8) a pixel on the first
        // segment plus up to 32 on each later one (volume_points.comp); 24 a
        // pixel on average leaves room for a quarter of the image seen
        // through glass or in a mirror, up to 2^22 points (192 MiB). With a
        // medium inside a dielectric, 48 and 2^23: an eye under turbid
        // water has points on its first segment and on every segment the
        // surface reflects back into the water.
        let (per_pixel, most) = if inside_media {
            (48, 1 << 23)
        } else {
            (24, 1 << 22)
        };
        let gather_capacity = if volume_capacity > 0 {
            (pixels * per_pixel).min(most) as u32
        } else {
            0
        };
        let aim_share = aim_share_for(&settings, has_medium);
        // Aiming by the guide: only where photons are aimed at all.
        let guided_lights = if settings.aim_guide && aim.is_some() && settings.aim_share > 0.0 {
            lights as u32
        } else {
            0
        };
        let cells = u64::from(b::REFERENCE_GUIDE_ROWS * b::REFERENCE_GUIDE_COLUMNS);
        let guide_bytes =
            (4 * cells + u64::from(b::REFERENCE_GUIDE_ROWS)) * 4 * u64::from(guided_lights.max(1));
        let vp_bytes = points * point_bytes;
        let volume_bytes = volume_capacity as u64 * point_bytes;
        let gather_bytes = gather_capacity as u64 * point_bytes;
        let largest = vp_bytes.max(volume_bytes).max(gather_bytes);
        if largest > ctx.limits.max_storage_buffer_range as u64 {
            anyhow::bail!(
                "the reference's photon-mapping buffers ({} MiB) exceed the device's {} MiB per buffer",
                largest >> 20,
                ctx.limits.max_storage_buffer_range >> 20
            );
        }
        let reference = Self {
            trace: pipeline("reference/trace.comp")?,
            camera: pipeline("reference/camera.comp")?,
            volume_points: pipeline("reference/volume_points.comp")?,
            volume_gather: pipeline("reference/volume_gather.comp")?,
            aim_guide_build: pipeline("reference/aim_guide.comp")?,
            fold: pipeline("reference/fold.comp")?,
            noise: pipeline("reference/noise.comp")?,
            resolve: pipeline("reference/resolve.comp")?,
            total: buffer("reference sums", accum_bytes)?,
            pass_sums: buffer("reference pass estimates", accum_bytes)?,
            moments: buffer("reference moments", pixels * 8)?,
            visible_points: buffer("reference visible points", vp_bytes)?,
            surface_heads: buffer("reference surface grid", surface_table as u64 * 4)?,
            surface_next: buffer("reference surface links", points * 4)?,
            volume_photons: buffer("reference volume photons", volume_bytes)?,
            volume_heads: buffer("reference volume grid", volume_table as u64 * 4)?,
            volume_next: buffer("reference volume links", volume_capacity as u64 * 4)?,
            // Every buffer needs a size above 0.
            gather_points: buffer("reference gather points", gather_bytes.max(point_bytes))?,
            aim_guide: buffer("reference aim guide", guide_bytes)?,
            guided_lights,
            learned: false,
            stats: Buffer::new(ctx, "reference counters", 32, BufferUsage::StorageIndirect)?,
            set: DescriptorSet::new(ctx, &layout)?,
            resolve_set: DescriptorSet::new(ctx, &layout)?,
            _layout: layout,
            settings,
            surface_table,
            volume_table,
            volume_capacity,
            gather_capacity,
            aim: aim.map_or([0.0; 4], |(c, r)| [c.x, c.y, c.z, r]),
            aim_share,
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
        for set in [&reference.set, &reference.resolve_set] {
            set.write_buffer(b::REFERENCE_BINDING_TOTAL, &reference.total)
                .write_buffer(b::REFERENCE_BINDING_PASS, &reference.pass_sums)
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
                .write_buffer(b::REFERENCE_BINDING_STATS, &reference.stats)
                .write_buffer(b::REFERENCE_BINDING_GATHER_POINTS, &reference.gather_points)
                .write_buffer(b::REFERENCE_BINDING_AIM_GUIDE, &reference.aim_guide);
        }
        Ok(reference)
    }

    fn pass_photons(&self) -> u64 {
        self.settings.pass_photons()
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
            aim_share: self.aim_share,
            gather_capacity: self.gather_capacity,
            aim_guide: (self.guided_lights > 0) as u32,
            fresnel_splits: self.settings.fresnel_splits,
        }
    }

    /// Clears the sums and the aim guide (first pass); records it through the recorder.
    pub fn record_clear(&mut self, rec: &mut FrameRecorder) {
        rec.pass("reference clear").record(|c| {
            for buffer in [&self.total, &self.pass_sums, &self.moments, &self.aim_guide] {
                c.fill(buffer, 0);
            }
        });
        self.photons = 0;
        self.passes = 0;
        self.learned = false;
    }

    /// Records one pass: camera chains and visible points, one batch of
    /// photons (camera connections and surface gathers), the volume gather
    /// along camera chains (scenes with a medium), then the fold into the
    /// sums. Shrinks the radii for the next pass.
    ///
    /// With the aim guide, the first call records a learning pass before
    /// it: the same stages with a quarter of the photons, its estimate
    /// dropped instead of folded. Its
    /// photons are aimed uniformly (the guide has seen nothing yet), so on
    /// `ball_lens_top` 30 times fewer of them reach the image than in a
    /// guided pass, and as one of the passes the mean weighs equally it was
    /// most of the image's noise: FLIP 0.052 with it after five passes, 0.038
    /// without (BENCHMARKS.md "Fresnel splitting, every photon aimed").
    /// What it leaves is the guide's counts. Every counted pass stays an
    /// unbiased estimate given the guide it was aimed by.
    pub fn record_pass(&mut self, rec: &mut FrameRecorder, scene_gpu: &SceneGpu) -> PassReport {
        if self.guided_lights > 0 && !self.learned {
            self.learned = true;
            // A quarter of a pass: where the guide gains nothing (every
            // aimed photon useful), a cheap start.
            let photons = (self.pass_photons() / 4).max(64) / 64 * 64;
            self.record_stages(rec, scene_gpu, photons);
            rec.pass("reference learning pass, dropped")
                .write(&self.pass_sums, Access::ComputeWrite)
                .record(|c| c.fill(&self.pass_sums, 0));
        }
        self.record_stages(rec, scene_gpu, self.pass_photons());
        let push = self.push(0, Component::All);
        let sets = [&scene_gpu.set, &self.set];
        rec.pass("reference fold")
            .write(&self.pass_sums, Access::ComputeWrite)
            .write(&self.total, Access::ComputeWrite)
            .write(&self.moments, Access::ComputeWrite)
            .record(|c| {
                let pixels = self.width * self.height;
                let groups = [pixels.div_ceil(64), 1, 1];
                c.dispatch(&self.fold, &sets, bytemuck::bytes_of(&push), groups);
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

    /// Records a pass's stages up to the fold: camera chains and visible
    /// points, the guide, `photons` photons, the volume gather.
    fn record_stages(&mut self, rec: &mut FrameRecorder, scene_gpu: &SceneGpu, photons: u64) {
        self.dispatches = self.dispatches.wrapping_add(1);
        let seed = self
            .dispatches
            .wrapping_mul(0x9E37_79B9)
            .wrapping_add(self.settings.seed.wrapping_mul(0x85EB_CA6B));
        let push = self.push(seed, Component::All);
        let push = bytemuck::bytes_of(&push);
        let sets = [&scene_gpu.set, &self.set];
        let pixel_groups = groups_8x8(self.width, self.height);
        rec.pass("reference visible points")
            .write(&self.pass_sums, Access::ComputeWrite)
            .write(&self.visible_points, Access::ComputeWrite)
            .write(&self.surface_heads, Access::ComputeWrite)
            .write(&self.surface_next, Access::ComputeWrite)
            .record(|c| {
                c.fill(&self.surface_heads, b::REFERENCE_GRID_NONE);
                c.dispatch(&self.camera, &sets, push, pixel_groups);
            });
        if self.guided_lights > 0 {
            rec.pass("reference aim guide")
                .write(&self.aim_guide, Access::ComputeWrite)
                .record(|c| {
                    let groups = [self.guided_lights, 1, 1];
                    c.dispatch(&self.aim_guide_build, &sets, push, groups);
                });
        }
        rec.pass("reference photons")
            .write(&self.pass_sums, Access::ComputeWrite)
            .write(&self.aim_guide, Access::ComputeWrite)
            .read(&self.visible_points, Access::ComputeRead)
            .read(&self.surface_heads, Access::ComputeRead)
            .read(&self.surface_next, Access::ComputeRead)
            .write(&self.volume_photons, Access::ComputeWrite)
            .write(&self.volume_heads, Access::ComputeWrite)
            .write(&self.volume_next, Access::ComputeWrite)
            .write(&self.stats, Access::ComputeWrite)
            .record(|c| {
                c.fill(&self.volume_heads, b::REFERENCE_GRID_NONE);
                c.fill(&self.stats, 0);
                // The volume gather's dispatch is (x, 1, 1); volume_points.comp raises x.
                c.update(&self.stats, 20, bytemuck::cast_slice(&[1u32, 1]));
                let groups = [(photons / 64) as u32, 1, 1];
                c.dispatch(&self.trace, &sets, push, groups);
            });
        if self.volume_capacity > 0 {
            rec.pass("reference volume points")
                .write(&self.gather_points, Access::ComputeWrite)
                .write(&self.stats, Access::ComputeWrite)
                .record(|c| c.dispatch(&self.volume_points, &sets, push, pixel_groups));
            rec.pass("reference volume gather")
                .write(&self.pass_sums, Access::ComputeWrite)
                .read(&self.gather_points, Access::ComputeRead)
                .read(&self.volume_photons, Access::ComputeRead)
                .read(&self.volume_heads, Access::ComputeRead)
                .read(&self.volume_next, Access::ComputeRead)
                .write(&self.stats, Access::ComputeWrite)
                .read(&self.stats, Access::IndirectRead)
                .record(|c| c.dispatch_indirect(&self.volume_gather, &sets, push, &self.stats, 16));
        }
    }

    /// Records the noise reduction over the image (counters 1 and 2 of `stats`).
    pub fn record_noise(&self, rec: &mut FrameRecorder, scene_gpu: &SceneGpu) {
        let push = self.push(0, Component::All);
        let sets = [&scene_gpu.set, &self.set];
        rec.pass("reference noise")
            .read(&self.moments, Access::ComputeRead)
            .write(&self.stats, Access::ComputeWrite)
            .record(|c| {
                c.fill(&self.stats, 0);
                let pixels = self.width * self.height;
                let groups = [pixels.div_ceil(64), 1, 1];
                c.dispatch(&self.noise, &sets, bytemuck::bytes_of(&push), groups);
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
        let push = self.push(0, component);
        let sets = [&scene_gpu.set, &self.resolve_set];
        rec.pass("reference resolve")
            .overwrite_storage_image(
                &self.resolve_set,
                b::REFERENCE_BINDING_RADIANCE,
                &targets.radiance,
                Access::ComputeWrite,
            )
            .read(&self.total, Access::ComputeRead)
            .record(|c| {
                let groups = groups_8x8(self.width, self.height);
                c.dispatch(&self.resolve, &sets, bytemuck::bytes_of(&push), groups);
            });
    }

    /// The counters the last pass (or noise reduction) left.
    pub fn read_stats(&self) -> VkResult<Stats> {
        let words: Vec<u32> = self.stats.download_pod()?;
        Ok(Stats {
            volume_photons: words[0],
            noise_variance_sum: f32::from_bits(words[1]),
            noise_mean_sum: f32::from_bits(words[2]),
            gather_points: words[3],
            longest_walk: words[7],
        })
    }

    /// The surface gather radius of the next pass (m).
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Medium collisions one pass can store.
    pub fn volume_capacity(&self) -> u32 {
        self.volume_capacity
    }

    /// Gather points one pass can store.
    pub fn gather_capacity(&self) -> u32 {
        self.gather_capacity
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
