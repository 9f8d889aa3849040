//! `pinhole`: Wand & Straßer 2003, "Real-Time Caustics": the reflector's
//! surface sampled into small regions, each "a set of (reflecting) pinhole
//! cameras that project an image of the light source onto the receiving
//! surfaces" (Sect. 3), the light held as cube environment maps.
//!
//! Every frame, on the GPU, nothing precomputed (glsl/pinhole/):
//! 1. "pinhole areas" (areas.comp): the reflector triangles' area CDF and
//!    total area A (mirrors, and dielectrics with `dielectrics` = 1).
//! 2. "pinhole candidates" (candidates.comp): M = `oversample` x N dense
//!    uniform random points on the reflector, in a hash grid.
//! 3. "pinhole samples" (select.comp): N sample points by one of Sect.
//!    3.2's four strategies (`strategy`: random, grid, quantized grid,
//!    neighbourhood-based removal, the default).
//! 4. "pinhole gradients" (gradients.comp): per sample point the normal
//!    gradient by Sect. 3.3's local linear regression over the dense
//!    candidates around it, rotated onto its principal directions; and one
//!    shadow ray per light (`light_visibility`).
//! 5. "pinhole clusters" (clusters.comp): K-means of the sample points into
//!    `clusters` clusters (Sect. 5's suggestion for lights near the
//!    reflector).
//! 6. "pinhole light maps" (light_maps.comp) and "pinhole light mips"
//!    (mips.comp): one cube map per cluster and emitter slot
//!    (`emitter_slots`), from the cluster's centre, with their mip chains:
//!    point and spot lights as spheres of radius `light_radius` with
//!    L = I / (pi r^2), a directional light as a sun disc of `sun_radius`
//!    with L = E / (pi sin^2 alpha) (glsl/common/punctual_emitters.glsl);
//!    rect and sphere area lights as they are; the environment's table and
//!    a sky's sun disc (glsl/common/emitters.glsl).
//! 7. "pinhole receivers" (receivers.comp): per diffuse pixel of the opaque
//!    frame, Sect. 3.1's sum over sample points (the equation is written in
//!    the shader), each lookup filtered over its Sect. 3.3 footprint with
//!    `textureGrad` (`filter`), each contribution checked by a shadow ray
//!    from the receiver to the sample point (`visibility`).
//!
//! The frame is the surface frame's (`passes::surface_frame`, as
//! image_space's): shadows, G-buffers and direct light into the opaque frame
//! (component `direct`), the receivers add the caustics to it (component
//! `surface_caustics`), then what the camera sees in mirrors and glass
//! (camera refraction).
//!
//! Cube maps are 2D-array images (six layers per map) with the face
//! selection done in the shader (glsl/pinhole/common.glsl), so that one
//! sampler reaches every cluster's maps without descriptor indexing or
//! cube-array support; the lookup's gradients are projected onto the face
//! as a cube lookup does. Filtering across face edges clamps to the face.
//!
//! Limits: one specular bounce (the paper's); the cube maps hold the
//! emitters, not the scene, so light blocked between emitter and reflector
//! is handled only by the per-sample shadow ray to each light's centre
//! (`light_visibility`), and a sample point sees a light from its cluster's
//! centre (parallax within a cluster: fewer clusters, more error). The
//! sample points are drawn with a fixed seed: a static scene gets the same
//! points every frame, a moving reflector new ones from its current
//! triangles.

pub mod bindings;
pub mod params;

use super::{CausticSources, Technique, TechniqueBuild};
use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::camera_refraction::RefractionPush;
use crate::passes::surface_frame::SurfaceFrame;
use crate::radiometry::Component;
use crate::scene::{EnvironmentKind, Scene};
use crate::shader_bindings as sb;
use crate::vk::{
    groups_8x8, Access, Buffer, BufferUsage, ComputePipeline, Context, DescriptorSet,
    DescriptorSetLayout, FrameRecorder, Image, ImageDesc, Sampler, VkResult,
};
use ash::vk;
use bindings as b;
use bytemuck::{Pod, Zeroable};
pub use params::{PinholeParams, PinholePush};
use std::mem::size_of;
use std::sync::Arc;

/// One reflector sample point, mirrored by `Sample` in
/// glsl/pinhole/common.glsl (written by the GPU only; tests read it back).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuSample {
    /// xyz position; w: material index (u32 bits).
    pub position: [f32; 4],
    /// xyz unit normal; w: cluster index (u32 bits).
    pub normal: [f32; 4],
    /// xyz principal direction u of the normal gradient; w: light
    /// visibility mask (u32 bits).
    pub tangent: [f32; 4],
    /// xyz dn/du.
    pub dn_du: [f32; 4],
    /// xyz dn/dv along v = normal x u.
    pub dn_dv: [f32; 4],
}
const _: () = assert!(size_of::<GpuSample>() == 80);
const SAMPLE_BYTES: u64 = size_of::<GpuSample>() as u64;
/// Bytes of one dense candidate (`Candidate`).
const CANDIDATE_BYTES: u64 = 32;
/// Bytes of the state block before its per-map normalisations.
const STATE_HEADER_BYTES: u64 = 16 + 16 * b::PINHOLE_MAX_CLUSTERS as u64;
const LIGHT_MAP_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Largest light-map image `build` accepts (its mips included).
const MAX_LIGHT_MAP_BYTES: u64 = 1 << 30;

/// The emitter slots of the light cube maps, in light_maps.comp's order:
/// the scene's punctual lights, its area lights, then (with an environment)
/// the environment's table and a sky's sun disc (an image's sun is in its
/// table); at least one.
pub fn emitter_slots(scene: &Scene) -> u32 {
    let environment = match scene.environment.as_ref().map(|e| &e.kind) {
        Some(EnvironmentKind::Sky(_)) => 2,
        Some(EnvironmentKind::Image(_)) => 1,
        None => 0,
    };
    ((scene.lights.len() + scene.emitters.len()) as u32 + environment).max(1)
}

pub struct Pinhole {
    /// Shadows, G-buffers, direct light on the opaque scene, camera refraction.
    pub surface: SurfaceFrame,
    /// The sample points (`Sample`), at most N.
    pub samples: Buffer,
    /// A, the kept count N, the grid cell, cluster centres, map normalisations.
    pub state: Buffer,
    cdf: Buffer,
    candidates: Buffer,
    heads: Buffer,
    next: Buffer,
    /// The light cube maps: K clusters x slots x 6 faces, with mips.
    pub light_map: Image,
    push: PinholePush,
    areas: ComputePipeline,
    candidates_pass: ComputePipeline,
    select: ComputePipeline,
    gradients: ComputePipeline,
    clusters: ComputePipeline,
    light_maps: ComputePipeline,
    mips: ComputePipeline,
    receivers: ComputePipeline,
    /// The sampling passes' set (buffers only).
    set: DescriptorSet,
    /// "pinhole light maps"' set.
    light_map_set: DescriptorSet,
    /// "pinhole receivers"' set.
    receivers_set: DescriptorSet,
    /// One set per mip level >= 1 (source: the level above).
    mip_sets: Vec<DescriptorSet>,
    _layouts: [DescriptorSetLayout; 3],
    _mip_layout: DescriptorSetLayout,
    sampler: Sampler,
}

impl Pinhole {
    pub fn new(
        ctx: &Arc<Context>,
        params: &PinholeParams,
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
            RefractionPush {
                tir_remedy: sb::TIR_CLAMP_CRITICAL,
                use_eq632: 1,
                search_steps: params.search_steps,
                exit: sb::CAMERA_EXIT_TRACED,
            },
        )?;
        let n = params.samples;
        let m = n * params.oversample;
        let hash_size = (2 * m).next_power_of_two();
        let slots = emitter_slots(scene);
        let k = params.clusters;
        let triangles = scene_gpu.triangle_count.max(1) as u64;
        let samples = Buffer::new(
            ctx,
            "pinhole samples",
            n as u64 * SAMPLE_BYTES,
            BufferUsage::Storage,
        )?;
        let state = Buffer::new(
            ctx,
            "pinhole state",
            STATE_HEADER_BYTES + 8 * (k * slots) as u64,
            BufferUsage::Storage,
        )?;
        let cdf = Buffer::new(ctx, "pinhole area cdf", 4 * triangles, BufferUsage::Storage)?;
        let candidates = Buffer::new(
            ctx,
            "pinhole candidates",
            m as u64 * CANDIDATE_BYTES,
            BufferUsage::Storage,
        )?;
        let heads = Buffer::new(
            ctx,
            "pinhole grid heads",
            4 * hash_size as u64,
            BufferUsage::Storage,
        )?;
        let next = Buffer::new(
            ctx,
            "pinhole grid links",
            4 * m as u64,
            BufferUsage::Storage,
        )?;
        let size = params.cube_size;
        let levels = 32 - size.leading_zeros();
        let light_map = Image::mipmapped(
            ctx,
            "pinhole light cube maps",
            ImageDesc {
                width: size,
                height: size,
                layers: k * slots * 6,
                format: LIGHT_MAP_FORMAT,
                usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED,
            },
            levels,
        )?;
        // One set (and layout) per group of passes, holding what the
        // group's shaders use: the sampling passes' buffers
        // (glsl/pinhole/common.glsl), the images the light-map and receiver
        // passes declare (`vk/pass.rs`).
        let layout_of = |shaders: &[&str]| DescriptorSetLayout::of_shaders(ctx, 1, shaders);
        let layouts = [
            layout_of(&[
                "pinhole/areas.comp",
                "pinhole/candidates.comp",
                "pinhole/select.comp",
                "pinhole/gradients.comp",
                "pinhole/clusters.comp",
            ])?,
            layout_of(&["pinhole/light_maps.comp"])?,
            layout_of(&["pinhole/receivers.comp"])?,
        ];
        let sampler = Sampler::trilinear_clamp(ctx)?;
        let buffers = [
            (b::PINHOLE_BINDING_SAMPLES, &samples),
            (b::PINHOLE_BINDING_STATE, &state),
            (b::PINHOLE_BINDING_CDF, &cdf),
            (b::PINHOLE_BINDING_CANDIDATES, &candidates),
            (b::PINHOLE_BINDING_HEADS, &heads),
            (b::PINHOLE_BINDING_NEXT, &next),
        ];
        let new_set = |layout: &DescriptorSetLayout| -> VkResult<DescriptorSet> {
            let set = DescriptorSet::new(ctx, layout)?;
            set.write_buffers(&buffers);
            Ok(set)
        };
        let (set, light_map_set, receivers_set) = (
            new_set(&layouts[0])?,
            new_set(&layouts[1])?,
            new_set(&layouts[2])?,
        );
        let mip_layout = DescriptorSetLayout::of_shaders(ctx, 1, &["pinhole/mips.comp"])?;
        let mip_sets = (1..levels)
            .map(|_| DescriptorSet::new(ctx, &mip_layout))
            .collect::<VkResult<Vec<_>>>()?;
        let push_size = size_of::<PinholePush>() as u32;
        let pipeline = |shader: &str, layout: &DescriptorSetLayout| {
            ComputePipeline::new(ctx, shader, &[&scene_gpu.layout, layout], push_size)
        };
        let areas = pipeline("pinhole/areas.comp", &layouts[0])?;
        let candidates_pass = pipeline("pinhole/candidates.comp", &layouts[0])?;
        let select = pipeline("pinhole/select.comp", &layouts[0])?;
        let gradients = pipeline("pinhole/gradients.comp", &layouts[0])?;
        let clusters = pipeline("pinhole/clusters.comp", &layouts[0])?;
        let light_maps = pipeline("pinhole/light_maps.comp", &layouts[1])?;
        let receivers = pipeline("pinhole/receivers.comp", &layouts[2])?;
        let mips = ComputePipeline::new(
            ctx,
            "pinhole/mips.comp",
            &[&scene_gpu.layout, &mip_layout],
            0,
        )?;
        let mut push = PinholePush {
            target: n,
            strategy: 0,
            candidates: m,
            clusters: k,
            slots,
            cube_size: size,
            flags: 0,
            hash_size,
            light_radius: 0.0,
            sun_cos: 1.0,
            epsilon: 0.0,
            medium_steps: params.direct.medium_steps,
            first_candidate: 0,
            pad: [0; 3],
        };
        params.apply_live(&mut push);
        Ok(Self {
            surface,
            samples,
            state,
            cdf,
            candidates,
            heads,
            next,
            light_map,
            push,
            areas,
            candidates_pass,
            select,
            gradients,
            clusters,
            light_maps,
            mips,
            receivers,
            set,
            light_map_set,
            receivers_set,
            mip_sets,
            _layouts: layouts,
            _mip_layout: mip_layout,
            sampler,
        })
    }

    /// Takes the live parameters of `params`.
    pub fn set_live(&mut self, params: &PinholeParams) {
        self.surface.set_live(&params.direct, params.search_steps);
        params.apply_live(&mut self.push);
    }

    /// Records the sample points, clusters, light maps and receivers'
    /// caustics into the opaque frame (steps 1-7 of the module's list).
    fn record_caustics(&self, rec: &mut FrameRecorder, scene: &SceneGpu) {
        let push = bytemuck::bytes_of(&self.push);
        let sets = [&scene.set, &self.set];
        let one = [1, 1, 1];
        // Each pass declares its next use of every buffer it touches; a
        // write after a write or read gets a barrier.
        let (r, w) = (Access::ComputeRead, Access::ComputeWrite);
        rec.pass("pinhole areas")
            .read(&scene.triangles, r)
            .write(&self.cdf, w)
            .write(&self.state, w)
            .write(&self.heads, w)
            .record(|c| c.dispatch(&self.areas, &sets, push, one));
        rec.pass("pinhole candidates")
            .read(&self.cdf, r)
            .read(&self.state, r)
            .write(&self.candidates, w)
            .write(&self.heads, w)
            .write(&self.next, w)
            .record(|c| {
                let groups = [self.push.candidates.div_ceil(64), 1, 1];
                c.dispatch(&self.candidates_pass, &sets, push, groups);
            });
        rec.pass("pinhole samples")
            .write(&self.candidates, w)
            .read(&self.heads, r)
            .read(&self.next, r)
            .write(&self.samples, w)
            .write(&self.state, w)
            .record(|c| {
                // One dispatch per chunk of candidates; each continues the
                // previous one's kept count and flags (ordered by the
                // declaration's barrier before each, `Commands`).
                for first in (0..self.push.candidates).step_by(b::PINHOLE_SELECT_CHUNK as usize) {
                    let chunk = PinholePush {
                        first_candidate: first,
                        ..self.push
                    };
                    c.dispatch(&self.select, &sets, bytemuck::bytes_of(&chunk), one);
                }
            });
        rec.pass("pinhole gradients")
            .read(&self.candidates, r)
            .read(&self.state, r)
            .write(&self.samples, w)
            .record(|c| {
                let groups = [self.push.target.div_ceil(64), 1, 1];
                c.dispatch(&self.gradients, &sets, push, groups);
            });
        rec.pass("pinhole clusters")
            .write(&self.samples, w)
            .write(&self.state, w)
            .record(|c| c.dispatch(&self.clusters, &sets, push, one));
        let set = &self.light_map_set;
        rec.pass("pinhole light maps")
            .write(&self.state, w)
            .storage_view(
                set,
                b::PINHOLE_BINDING_LIGHT_MAP_LEVEL0,
                &self.light_map,
                self.light_map.level_views[0],
                w,
            )
            .record(|c| {
                let s = self.push.cube_size.div_ceil(8);
                let groups = [s, s, self.light_map.desc.layers];
                c.dispatch(&self.light_maps, &[&scene.set, set], push, groups);
            });
        let mut mips = rec.pass("pinhole light mips");
        for (l, set) in self.mip_sets.iter().enumerate() {
            let views = &self.light_map.level_views;
            mips = mips
                .storage_view(
                    set,
                    b::PINHOLE_MIP_BINDING_SRC,
                    &self.light_map,
                    views[l],
                    w,
                )
                .storage_view(
                    set,
                    b::PINHOLE_MIP_BINDING_DST,
                    &self.light_map,
                    views[l + 1],
                    w,
                );
        }
        mips.record(|c| {
            for (l, set) in self.mip_sets.iter().enumerate() {
                // Level l + 1 reads level l, written by the previous
                // dispatch (the declaration's barrier again, `Commands`).
                let s = (self.push.cube_size >> (l + 1)).max(1).div_ceil(8);
                let groups = [s, s, self.light_map.desc.layers];
                c.dispatch(&self.mips, &[&scene.set, set], &[], groups);
            }
        });
        let gbuffer = self.surface.gbuffer();
        let opaque = self.surface.opaque();
        let set = &self.receivers_set;
        rec.pass("pinhole receivers")
            .sampled(
                set,
                b::PINHOLE_BINDING_LIGHT_MAP,
                &self.light_map,
                &self.sampler,
                r,
            )
            .storage_image(set, b::PINHOLE_BINDING_POSITION, &gbuffer.position, r)
            .storage_image(set, b::PINHOLE_BINDING_NORMAL, &gbuffer.normal, r)
            .storage_image(set, b::PINHOLE_BINDING_ALBEDO, &gbuffer.albedo, r)
            .storage_image(set, b::PINHOLE_BINDING_RADIANCE, opaque, w)
            .read(&self.samples, r)
            .read(&self.state, r)
            .record(|c| {
                let extent = opaque.extent();
                let groups = groups_8x8(extent.width, extent.height);
                c.dispatch(&self.receivers, &[&scene.set, set], push, groups);
            });
    }
}

impl TechniqueBuild for Pinhole {
    const NAME: &'static str = "pinhole";
    const DESCRIPTION: &'static str = "Wand & Straßer 2003: reflector sample points as pinhole cameras projecting cube maps of the lights onto the diffuse receivers, filtered by the normal gradient (surface caustics of one mirror bounce)";
    const COMPONENTS: &'static [Component] = &[
        Component::Direct,
        Component::SurfaceCaustics,
        Component::Emitted,
    ];
    const CAUSTIC_SOURCES: CausticSources = CausticSources::Reflection;
    type Params = PinholeParams;

    /// Thin sheets and emissive surfaces are outside its model.
    fn check_scene(scene: &Scene) -> anyhow::Result<()> {
        super::check_materials(scene, Self::NAME)
    }

    fn build(
        ctx: &Arc<Context>,
        params: &PinholeParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        // The light maps: clusters x emitter slots x 6 faces, RGBA32F with mips.
        let slots = emitter_slots(scene) as u64;
        if slots > b::PINHOLE_MAX_SLOTS as u64 {
            anyhow::bail!(
                "pinhole: the scene has {slots} emitters (lights, area lights, environment table and sun), more than the {} it handles",
                b::PINHOLE_MAX_SLOTS
            );
        }
        let layers = params.clusters as u64 * slots * 6;
        let size = params.cube_size as u64;
        let bytes = layers * size * size * 16 * 4 / 3;
        if layers > ctx.limits.max_image_array_layers as u64 || bytes > MAX_LIGHT_MAP_BYTES {
            anyhow::bail!(
                "pinhole: {} clusters x {slots} emitters x 6 faces of {size}² texels ({layers} layers, {} MiB) exceed the device's {} layers or {} MiB: lower `clusters` or `cube_size`",
                params.clusters,
                bytes >> 20,
                ctx.limits.max_image_array_layers,
                MAX_LIGHT_MAP_BYTES >> 20
            );
        }
        Ok(Self::new(ctx, params, scene, scene_gpu, width, height)?)
    }

    fn update_live(&mut self, params: &PinholeParams) -> bool {
        self.set_live(params);
        true
    }
}

impl Technique for Pinhole {
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
        // Every caustic pass only adds surface caustics
        // (`SceneGpu::draws`).
        if scene.draws(Component::SurfaceCaustics) {
            self.record_caustics(rec, scene);
        }
        self.surface.record_refraction(rec, scene, targets);
        Ok(())
    }

    /// The passes read the lights from the scene's buffer every frame; only
    /// the surface frame's shadow views move.
    fn set_lights(&mut self, lights: &[crate::scene::Light]) -> bool {
        self.surface.set_lights(lights)
    }

    /// The light cube maps are drawn every frame from the environment's
    /// constants on the GPU; the surface frame recomputes its SH.
    fn environment_changed(&mut self) -> bool {
        self.surface.environment_changed();
        true
    }
}
