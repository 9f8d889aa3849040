//! The beams themselves: per light, the adaptive projected grid ("beam
//! refine", one compute level at a time, driven by indirect arguments) and
//! the beams' bounding volumes ("beam volumes", one indirect draw, where
//! the scene has a medium) and their caustic triangles ("beam caustics",
//! one indirect draw: the flux-conserving surface gather); per
//! frame, "beam receivers" and "beam clear" before the lights, "beam apply"
//! (surface caustics into the opaque frame) and "beam composite" (volume
//! caustics into the frame) after them, and the counters' copy to the host.
//! The module doc of `beams` has the method.

use super::bindings as bb;
use super::BeamsParams;
use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::light_views::photon_view;
use crate::passes::light_views::{LightView, LightViewConsumer};
use crate::passes::specular_gbuffer::SpecularGBuffer;
use crate::passes::surface_frame::SurfaceFrame;
use crate::radiometry::luminance;
use crate::scene::{Density, Light, LightKind, Scene};
use crate::vk::{
    groups_8x8, Access, Buffer, BufferUsage, ComputePipeline, Context, DescriptorSet,
    DescriptorSetLayout, FrameRecorder, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc,
    VkResult, MAX_FRAMES_IN_FLIGHT,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::mem::size_of;
use std::sync::Arc;

/// One beam, mirrored by `Beam` in glsl/beams/beam.glsl (which documents
/// the fields).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuBeam {
    /// Base vertices; w: y_max, level (u32 bits), kind (u32 bits).
    pub v: [[f32; 4]; 3],
    /// Edge directions scaled to dot(e, n) = 1.
    pub e: [[f32; 4]; 3],
    /// Base plane normal; w: its offset.
    pub n: [f32; 4],
    /// A(y) coefficients; w: measure of the incident triangle (sr or m^2).
    pub area: [f32; 4],
    /// rgb flux (W).
    pub flux: [f32; 4],
    /// rgb flux entering the base triangle (W).
    pub incident: [f32; 4],
    /// Heights where the edges meet their first diffuse surface; w: that
    /// surface's object (u32 bits), `u32::MAX` where the three do not meet one.
    pub receiver: [f32; 4],
}
const _: () = assert!(size_of::<GpuBeam>() == 176);

impl GpuBeam {
    pub fn level(&self) -> u32 {
        self.v[1][3].to_bits()
    }
    pub fn kind(&self) -> u32 {
        self.v[2][3].to_bits()
    }
    /// 1 for the first specular event's beams, 2 for those they spawn, ...
    pub fn bounce(&self) -> u32 {
        self.e[0][3].to_bits()
    }
    /// The index of the beam this one was spawned by (Sect. 6).
    pub fn parent(&self) -> Option<usize> {
        let p = self.e[1][3].to_bits();
        (p != u32::MAX).then_some(p as usize)
    }
    /// A(y), the cross-section parallel to the base at height y (m^2, signed).
    pub fn area_at(&self, y: f32) -> f32 {
        self.area[0] + self.area[1] * y + self.area[2] * y * y
    }
    /// The caustic triangle (the beam's footprint on the one diffuse
    /// surface its three edge rays meet), if it has one.
    pub fn caustic_triangle(&self) -> Option<[glam::Vec3; 3]> {
        if self.receiver[3].to_bits() == u32::MAX {
            return None;
        }
        Some(std::array::from_fn(|k| {
            glam::Vec4::from(self.v[k]).truncate()
                + self.receiver[k] * glam::Vec4::from(self.e[k]).truncate()
        }))
    }
}

/// The counters of one frame, summed over its lights (`bench --json`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BeamCounts {
    /// Triangles the oracle looked at, per level.
    pub triangles: [u32; 6],
    /// Beams emitted, per level.
    pub beams: [u32; 6],
    pub beam_overflow: u32,
    pub triangle_overflow: u32,
    /// Measure (sr, or m^2 for directional light) of the kept base
    /// triangles and of those dropped at silhouettes.
    pub kept_measure: f32,
    pub dropped_measure: f32,
    /// Luminance flux (W) entering the kept triangles and carried by the beams.
    pub flux_in: f32,
    pub flux_out: f32,
    /// Fragments of the bounding volumes.
    pub fragments: u32,
    /// Fragments of the caustic triangles (the surface gather).
    pub caustic_fragments: u32,
}

impl BeamCounts {
    fn from_words(w: &[u32]) -> Self {
        let word = |i: u32| w[i as usize];
        let float = |i: u32| f32::from_bits(w[i as usize]);
        let mut c = BeamCounts::default();
        for l in 0..6 {
            c.triangles[l] = word(bb::BEAMS_STAT_TRIS + l as u32);
            c.beams[l] = word(bb::BEAMS_STAT_BEAMS + l as u32);
        }
        c.beam_overflow = word(bb::BEAMS_STAT_BEAM_OVERFLOW);
        c.triangle_overflow = word(bb::BEAMS_STAT_TRI_OVERFLOW);
        c.kept_measure = float(bb::BEAMS_STAT_KEPT_MEASURE);
        c.dropped_measure = float(bb::BEAMS_STAT_DROPPED_MEASURE);
        c.flux_in = float(bb::BEAMS_STAT_FLUX_IN);
        c.flux_out = float(bb::BEAMS_STAT_FLUX_OUT);
        c.fragments = word(bb::BEAMS_STAT_FRAGMENTS);
        c.caustic_fragments = word(bb::BEAMS_STAT_CAUSTIC_FRAGMENTS);
        c
    }

    pub fn total_beams(&self) -> u32 {
        self.beams.iter().sum()
    }

    /// The fraction of the grid's measure on the specular surfaces that
    /// was dropped at silhouettes.
    pub fn dropped_fraction(&self) -> f32 {
        let all = self.kept_measure + self.dropped_measure;
        if all > 0.0 {
            self.dropped_measure / all
        } else {
            0.0
        }
    }
}

/// Push constants of refine.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct RefinePush {
    origin: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    forward: [f32; 4],
    /// level, levels, base grid side, triangle capacity.
    grid: [u32; 4],
    /// beam capacity, TIR remedy, Eq. 6.3.2, medium steps.
    config: [u32; 4],
    /// relative depth, cos(normal angle), focus ratio, energy (W).
    split: [f32; 4],
    /// camera angular size (rad); refraction (u32 bits); extrusion cut-off;
    /// bounces (u32 bits).
    split2: [f32; 4],
}
const _: () = assert!(size_of::<RefinePush>() == 128);

/// Push constants of args.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ArgsPush {
    triangle_capacity: u32,
    beam_capacity: u32,
}

/// Push constants of the volume pass (glsl/beams/volume_push.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct VolumePush {
    volume_kind: u32,
    quadrature: u32,
    medium_steps: u32,
    pad: u32,
}

/// The layouts of `BeamSets`.
struct BeamLayouts {
    receivers: DescriptorSetLayout,
    beams: DescriptorSetLayout,
    filter: DescriptorSetLayout,
    apply: DescriptorSetLayout,
    composite: DescriptorSetLayout,
}

/// The tracer's descriptor sets, one per group of passes, each declaring
/// its own image bindings.
struct BeamSets {
    /// "beam receivers".
    receivers: DescriptorSet,
    /// "beam refine" (with the level arguments) and "beam volumes".
    beams: DescriptorSet,
    /// "beam filter".
    filter: DescriptorSet,
    /// "beam apply".
    apply: DescriptorSet,
    /// "beam composite".
    composite: DescriptorSet,
}

pub struct BeamTracer {
    /// The beams of the last light recorded.
    pub beams: Buffer,
    /// The volume caustics alone (rgb, component-weighted; a: fragments).
    pub volume: Image,
    /// Flux (W, rgb) the beams deposit on the receiver each pixel sees
    /// (caustic.frag; "beam apply" divides it by the pixel's footprint).
    pub surface: Image,
    /// The filter's intermediate (after the x pass).
    surface_filtered: Image,
    surface_filter: u32,
    triangles: [Buffer; 2],
    counters: Buffer,
    indirect: Buffer,
    receivers: Buffer,
    readbacks: Vec<Buffer>,
    refine: RefinePush,
    args: ArgsPush,
    volume_push: VolumePush,
    /// Light flux of a whole view (luminance W, per light): the energy
    /// criterion's reference.
    view_flux: Vec<f32>,
    split_energy: f32,
    light_view_size: u32,
    refine_pipeline: ComputePipeline,
    args_pipeline: ComputePipeline,
    receivers_pipeline: ComputePipeline,
    apply_pipeline: ComputePipeline,
    composite_pipeline: ComputePipeline,
    filter_pipeline: ComputePipeline,
    /// Only where the scene has a medium (without one the volumes have
    /// nothing to integrate and "beam volumes" is not drawn).
    volume_pipeline: Option<GraphicsPipeline>,
    caustic_pipeline: GraphicsPipeline,
    sets: BeamSets,
    _layouts: BeamLayouts,
}

/// The energy criterion's reference per light: the flux of its whole view
/// of the specular objects (luminance W: its intensity times the view's
/// solid angle, or its irradiance times the view's area).
fn view_fluxes(lights: &[Light], specular: Option<(glam::Vec3, f32)>, size: u32) -> Vec<f32> {
    lights
        .iter()
        .take(crate::shader_bindings::MAX_LIGHTS as usize)
        .enumerate()
        .map(|(l, light)| {
            let Some(v) = specular.and_then(|s| photon_view(light, l as u32, s, size)) else {
                return 0.0;
            };
            let h = v.origin[3];
            let measure = match light.kind {
                LightKind::Directional => 4.0 * h * h,
                // Solid angle of the square [-h, h]^2 of the tan plane.
                _ => 4.0 * (h * h / (1.0 + 2.0 * h * h).sqrt()).asin(),
            };
            luminance(light.intensity) * measure
        })
        .collect()
}

impl BeamTracer {
    /// The scene's lights moved: the energy criterion follows their views.
    pub fn set_lights(&mut self, lights: &[Light], specular: Option<(glam::Vec3, f32)>) {
        self.view_flux = view_fluxes(lights, specular, self.light_view_size);
    }

    /// Frames of `width` x `height`, with the technique's parameters
    /// (the light views' size, the grid, the split criteria, the volumes).
    pub fn new(
        ctx: &Arc<Context>,
        params: &BeamsParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        let light_view_size = params.light_view_size;
        let medium_steps = params.direct.medium_steps;
        let base = params.grid_size;
        // Each level holds at most 4x the previous one's; the lists are
        // sized for the deepest level (bounded by the beam capacity: a
        // level with more triangles than beams fits cannot be drawn anyway).
        let full = 2 * (base as u64).pow(2) * 4u64.pow(params.levels);
        let triangle_capacity = full
            .min(params.beam_capacity as u64)
            .max(2 * (base as u64).pow(2)) as u32;
        let triangles = [
            Buffer::new(
                ctx,
                "beam triangles A",
                triangle_capacity as u64 * 16,
                BufferUsage::Storage,
            )?,
            Buffer::new(
                ctx,
                "beam triangles B",
                triangle_capacity as u64 * 16,
                BufferUsage::Storage,
            )?,
        ];
        let beams = Buffer::new(
            ctx,
            "beams",
            params.beam_capacity as u64 * size_of::<GpuBeam>() as u64,
            BufferUsage::Storage,
        )?;
        let counters = Buffer::new(
            ctx,
            "beam counters",
            bb::BEAMS_COUNTER_WORDS as u64 * 4,
            BufferUsage::Storage,
        )?;
        let indirect = Buffer::new(
            ctx,
            "beam indirect arguments",
            bb::BEAMS_INDIRECT_WORDS as u64 * 4,
            BufferUsage::StorageIndirect,
        )?;
        let receivers = Buffer::new(
            ctx,
            "beam receivers",
            width as u64 * height as u64 * 32,
            BufferUsage::Storage,
        )?;
        let readbacks = (0..MAX_FRAMES_IN_FLIGHT)
            .map(|_| {
                Buffer::with_data(
                    ctx,
                    "beam counters readback",
                    &[0u32; bb::BEAMS_COUNTER_WORDS as usize],
                    BufferUsage::Readback,
                )
            })
            .collect::<VkResult<Vec<_>>>()?;
        let target = |name: &str| {
            Image::new(
                ctx,
                name,
                ImageDesc::new_2d(
                    width,
                    height,
                    vk::Format::R32G32B32A32_SFLOAT,
                    vk::ImageUsageFlags::COLOR_ATTACHMENT
                        | vk::ImageUsageFlags::STORAGE
                        | vk::ImageUsageFlags::TRANSFER_SRC,
                ),
            )
        };
        let volume = target("beam volume caustics")?;
        let surface_target = target("beam surface flux")?;
        let surface_filtered = target("beam surface flux, filtered in x")?;
        // One set (and layout) per group of passes, holding what the
        // group's shaders use (reflected from their SPIR-V); each pass
        // declares its image bindings (`vk/pass.rs`), and the buffers are
        // written into every set that has them.
        let layout_of = |shaders: &[&str]| DescriptorSetLayout::of_shaders(ctx, 1, shaders);
        let layouts = BeamLayouts {
            receivers: layout_of(&["beams/receivers.comp"])?,
            beams: layout_of(&[
                "beams/refine.comp",
                "beams/args.comp",
                "beams/volume.vert",
                "beams/volume.geom",
                "beams/volume.frag",
                "beams/volume_homogeneous.frag",
                "beams/caustic.geom",
                "beams/caustic.frag",
            ])?,
            filter: layout_of(&["beams/filter.comp"])?,
            apply: layout_of(&["beams/apply.comp"])?,
            composite: layout_of(&["beams/composite.comp"])?,
        };
        let buffers = [
            (bb::BEAMS_BINDING_TRIANGLES_A, &triangles[0]),
            (bb::BEAMS_BINDING_TRIANGLES_B, &triangles[1]),
            (bb::BEAMS_BINDING_BEAMS, &beams),
            (bb::BEAMS_BINDING_COUNTERS, &counters),
            (bb::BEAMS_BINDING_INDIRECT, &indirect),
            (bb::BEAMS_BINDING_RECEIVERS, &receivers),
        ];
        let new_set = |layout: &DescriptorSetLayout| -> VkResult<DescriptorSet> {
            let set = DescriptorSet::new(ctx, layout)?;
            set.write_buffers(&buffers);
            Ok(set)
        };
        let sets = BeamSets {
            receivers: new_set(&layouts.receivers)?,
            beams: new_set(&layouts.beams)?,
            filter: new_set(&layouts.filter)?,
            apply: new_set(&layouts.apply)?,
            composite: new_set(&layouts.composite)?,
        };
        let with = |layout| [&scene_gpu.layout, layout];
        let refine_pipeline = ComputePipeline::new(
            ctx,
            "beams/refine.comp",
            &with(&layouts.beams),
            size_of::<RefinePush>() as u32,
        )?;
        let args_pipeline = ComputePipeline::new(
            ctx,
            "beams/args.comp",
            &with(&layouts.beams),
            size_of::<ArgsPush>() as u32,
        )?;
        let receivers_pipeline =
            ComputePipeline::new(ctx, "beams/receivers.comp", &with(&layouts.receivers), 0)?;
        let apply_pipeline =
            ComputePipeline::new(ctx, "beams/apply.comp", &with(&layouts.apply), 4)?;
        let composite_pipeline =
            ComputePipeline::new(ctx, "beams/composite.comp", &with(&layouts.composite), 0)?;
        let filter_pipeline =
            ComputePipeline::new(ctx, "beams/filter.comp", &with(&layouts.filter), 8)?;
        // A constant density (or none) gets fragments compiled without the
        // density field's code (a CPU rasteriser pays for it in every
        // fragment, as volume_lines measured).
        let homogeneous = scene
            .medium
            .as_ref()
            .is_none_or(|m| matches!(m.density, Density::Constant(_)));
        let fragment = if homogeneous {
            "beams/volume_homogeneous.frag"
        } else {
            "beams/volume.frag"
        };
        let mut desc = GraphicsPipelineDesc::new("beams/volume.vert", fragment);
        desc.geometry = Some("beams/volume.geom");
        desc.color_formats = vec![vk::Format::R32G32B32A32_SFLOAT];
        desc.additive = true;
        desc.topology = vk::PrimitiveTopology::POINT_LIST;
        desc.push_size = size_of::<VolumePush>() as u32;
        let volume_pipeline = match scene.medium {
            Some(_) => Some(GraphicsPipeline::new(ctx, &desc, &with(&layouts.beams))?),
            None => None,
        };
        // The caustic triangles: the same points, one screen rectangle each.
        desc.geometry = Some("beams/caustic.geom");
        desc.fragment = "beams/caustic.frag";
        let caustic_pipeline = GraphicsPipeline::new(ctx, &desc, &with(&layouts.beams))?;

        // The lights the views are of: the scene's, then the stand-ins of
        // its sun and rect lights (without them the energy criterion of a
        // stand-in's view would split every triangle).
        let view_flux = view_fluxes(
            &crate::frame::caustic_lights(scene),
            crate::passes::light_views::specular_bounds(scene),
            light_view_size,
        );
        let cos_normal = params.split_normal.to_radians().cos();
        Ok(Self {
            beams,
            volume,
            surface: surface_target,
            surface_filtered,
            surface_filter: params.surface_filter,
            triangles,
            counters,
            indirect,
            receivers,
            readbacks,
            refine: RefinePush {
                origin: [0.0; 4],
                right: [0.0; 4],
                up: [0.0; 4],
                forward: [0.0; 4],
                grid: [0, params.levels, base, triangle_capacity],
                config: [
                    params.beam_capacity,
                    params.tir_remedy,
                    params.eq_6_3_2,
                    medium_steps,
                ],
                split: [params.split_depth, cos_normal, params.split_focus, 0.0],
                split2: [
                    params.split_camera,
                    f32::from_bits(params.refraction),
                    params.extrusion_cutoff,
                    f32::from_bits(params.bounces),
                ],
            },
            args: ArgsPush {
                triangle_capacity,
                beam_capacity: params.beam_capacity,
            },
            volume_push: VolumePush {
                volume_kind: params.volume,
                quadrature: params.quadrature,
                medium_steps,
                pad: 0,
            },
            view_flux,
            split_energy: params.split_energy,
            light_view_size,
            refine_pipeline,
            args_pipeline,
            receivers_pipeline,
            apply_pipeline,
            composite_pipeline,
            filter_pipeline,
            volume_pipeline,
            caustic_pipeline,
            sets,
            _layouts: layouts,
        })
    }

    /// The counters of the frame that ran in `slot`, once its fence has signalled.
    pub fn counts(&self, slot: usize) -> VkResult<BeamCounts> {
        let words: Vec<u32> = self.readbacks[slot].download_pod()?;
        Ok(BeamCounts::from_words(&words))
    }

    /// Records "beam receivers" and "beam clear", before the lights' passes
    /// (after `surface.record_opaque`).
    pub fn begin(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        surface: &SurfaceFrame,
        targets: &FrameTargets,
    ) {
        // The camera G-buffers were written by rasterisation; the
        // receivers are overwritten after last frame's fragments.
        let set = &self.sets.receivers;
        rec.pass("beam receivers")
            .storage_image(
                set,
                bb::BEAMS_BINDING_OPAQUE_POSITION,
                &surface.gbuffer().position,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bb::BEAMS_BINDING_OPAQUE_NORMAL,
                &surface.gbuffer().normal,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bb::BEAMS_BINDING_SPECULAR_POSITION,
                &surface.specular().front_position,
                Access::ComputeRead,
            )
            .write(&self.receivers, Access::ComputeWrite)
            .record(|c| {
                let groups = groups_8x8(targets.width, targets.height);
                c.dispatch(&self.receivers_pipeline, &[&scene.set, set], &[], groups);
            });
        // The frame's statistics start from zero (after last frame's
        // copy to the host); both targets are cleared.
        rec.pass("beam clear")
            .overwrite(&self.volume, Access::ColorAttachment)
            .overwrite(&self.surface, Access::ColorAttachment)
            .record(|c| {
                c.fill(&self.counters, 0);
                let colors = [
                    (self.volume.view, Some([0.0; 4])),
                    (self.surface.view, Some([0.0; 4])),
                ];
                c.render(self.volume.extent(), &colors, None, |_| {});
            });
    }

    /// Records "beam apply": the surface caustics into the opaque frame
    /// (before the surface frame's refraction reads it).
    pub fn apply(&self, rec: &mut FrameRecorder, scene: &SceneGpu, surface: &SurfaceFrame) {
        if self.surface_filter > 0 {
            let e = self.surface.extent();
            let groups = groups_8x8(e.width, e.height);
            // x: the volumes' blended irradiance -> the intermediate
            // (overwritten after last frame's y pass read it). Both
            // images are bound writable in both passes (one shader
            // picks the direction), so both are declared written.
            let set = &self.sets.filter;
            rec.pass("beam filter")
                .storage_image(
                    set,
                    bb::BEAMS_BINDING_SURFACE,
                    &self.surface,
                    Access::ComputeWrite,
                )
                .overwrite_storage_image(
                    set,
                    bb::BEAMS_BINDING_SURFACE_FILTERED,
                    &self.surface_filtered,
                    Access::ComputeWrite,
                )
                .read(&self.receivers, Access::ComputeRead)
                .record(|c| {
                    let push = [self.surface_filter, 0];
                    c.dispatch(
                        &self.filter_pipeline,
                        &[&scene.set, set],
                        bytemuck::cast_slice(&push),
                        groups,
                    );
                    // y: the intermediate -> the surface target (read-after-
                    // write one way, write-after-read the other: the
                    // declaration's barrier again, `Commands`).
                    let push = [self.surface_filter, 1];
                    c.dispatch(
                        &self.filter_pipeline,
                        &[&scene.set, set],
                        bytemuck::cast_slice(&push),
                        groups,
                    );
                });
        }
        // The volumes' blended writes are read; the opaque frame was
        // written by direct lighting.
        let set = &self.sets.apply;
        rec.pass("beam apply")
            .storage_image(
                set,
                bb::BEAMS_BINDING_SURFACE,
                &self.surface,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bb::BEAMS_BINDING_OPAQUE_POSITION,
                &surface.gbuffer().position,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bb::BEAMS_BINDING_OPAQUE_NORMAL,
                &surface.gbuffer().normal,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bb::BEAMS_BINDING_OPAQUE_ALBEDO,
                &surface.gbuffer().albedo,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bb::BEAMS_BINDING_OPAQUE_RADIANCE,
                surface.opaque(),
                Access::ComputeWrite,
            )
            .record(|c| {
                let e = surface.opaque().extent();
                let groups = groups_8x8(e.width, e.height);
                c.dispatch(
                    &self.apply_pipeline,
                    &[&scene.set, set],
                    bytemuck::bytes_of(&self.volume_push.medium_steps),
                    groups,
                );
            });
    }

    /// Records "beam composite" (the volume caustics added to the frame's
    /// radiance, after the refraction wrote it) and the counters' copy to
    /// this frame's read-back buffer.
    pub fn composite(&self, rec: &mut FrameRecorder, scene: &SceneGpu, targets: &FrameTargets) {
        let readback = &self.readbacks[rec.slot()];
        let set = &self.sets.composite;
        rec.pass("beam composite")
            .storage_image(
                set,
                bb::BEAMS_BINDING_VOLUME,
                &self.volume,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bb::BEAMS_BINDING_RADIANCE,
                &targets.radiance,
                Access::ComputeWrite,
            )
            .record(|c| {
                let groups = groups_8x8(targets.width, targets.height);
                c.dispatch(&self.composite_pipeline, &[&scene.set, set], &[], groups);
                c.read_back(&self.counters, readback, self.counters.size);
            });
    }
}

impl LightViewConsumer for BeamTracer {
    fn reads_gbuffer(&self) -> bool {
        true
    }

    /// Records "beam refine" (levels 0..=levels, each followed by its
    /// indirect arguments) and "beam volumes" for one light.
    fn record_light(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        light: usize,
        view: &LightView,
        light_view: &SpecularGBuffer,
    ) {
        let base = self.refine.grid[2];
        let first = 2 * base * base;
        let mut push = self.refine;
        push.origin = view.origin;
        push.right = view.right;
        push.up = view.up;
        push.forward = view.forward;
        push.split[3] = self.split_energy * self.view_flux.get(light).copied().unwrap_or(0.0);
        // This light's counts and level-0 arguments start anew, after
        // the previous light's draw read them (write-after-read).
        rec.pass("beam grid")
            .write(&self.counters, Access::TransferWrite)
            .write(&self.indirect, Access::TransferWrite)
            .record(|c| {
                let mut light_words = [0u32; bb::BEAMS_COUNTER_LIGHT_WORDS as usize];
                light_words[bb::BEAMS_COUNTER_TRIS as usize] = first;
                let mut args = [0u32; bb::BEAMS_INDIRECT_WORDS as usize];
                args[0] = first.div_ceil(bb::BEAMS_REFINE_GROUP);
                args[1] = 1;
                args[2] = 1;
                let words = bytemuck::cast_slice(&light_words);
                c.update(&self.counters, 0, words);
                let words = bytemuck::cast_slice(&args);
                c.update(&self.indirect, 0, words);
            });
        for level in 0..=self.refine.grid[1] {
            push.grid[0] = level;
            // The level's arguments as indirect dispatch; the counters,
            // lists and beams by atomics; the light view's attachments as
            // storage reads; the BVH after any refit.
            let set = &self.sets.beams;
            let pass = rec
                .pass("beam refine")
                .read(&self.indirect, Access::IndirectRead)
                .write(&self.counters, Access::ComputeWrite)
                .write(&self.triangles[0], Access::ComputeWrite)
                .write(&self.triangles[1], Access::ComputeWrite)
                .write(&self.beams, Access::ComputeWrite)
                .read(&scene.triangles, Access::ComputeRead);
            light_view
                .bind_reads(
                    pass,
                    set,
                    [
                        bb::BEAMS_BINDING_FRONT_POSITION,
                        bb::BEAMS_BINDING_FRONT_NORMAL,
                        bb::BEAMS_BINDING_BACK_POSITION,
                        bb::BEAMS_BINDING_BACK_NORMAL,
                    ],
                )
                .record(|c| {
                    c.dispatch_indirect(
                        &self.refine_pipeline,
                        &[&scene.set, set],
                        bytemuck::bytes_of(&push),
                        &self.indirect,
                        12 * level as u64,
                    );
                    // The next level's arguments (and the draw's) from the
                    // counts this level appended (read-after-write), written
                    // after this level's indirect read (write-after-read).
                    c.step()
                        .read(&self.counters, Access::ComputeRead)
                        .write(&self.indirect, Access::ComputeWrite)
                        .dispatch(
                            &self.args_pipeline,
                            &[&scene.set, set],
                            bytemuck::bytes_of(&self.args),
                            [1, 1, 1],
                        );
                });
        }
        // The volumes (nothing to integrate without a medium), then the
        // caustic triangles.
        if let Some(volume) = &self.volume_pipeline {
            self.draw_beams(rec, scene, "beam volumes", &self.volume, volume);
        }
        self.draw_beams(
            rec,
            scene,
            "beam caustics",
            &self.surface,
            &self.caustic_pipeline,
        );
    }
}

impl BeamTracer {
    /// Records one indirect draw of the beams (one point each, the
    /// geometry shader expands it) into `target`, blended additively.
    fn draw_beams(
        &self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        name: &'static str,
        target: &Image,
        pipeline: &GraphicsPipeline,
    ) {
        // Beams pulled by the geometry shader and read again by the
        // fragments; the draw's count as indirect arguments; the fragment
        // counters by fragment atomics; the receivers per pixel; the
        // caustic fragments' rays traverse the scene.
        let set = &self.sets.beams;
        rec.pass(name)
            .write(target, Access::ColorAttachment)
            .read(&self.beams, Access::GraphicsRead)
            .read(&self.indirect, Access::IndirectRead)
            .write(&self.counters, Access::FragmentWrite)
            .read(&self.receivers, Access::FragmentRead)
            .read(&scene.triangles, Access::FragmentRead)
            .record(|c| {
                c.render(target.extent(), &[(target.view, None)], None, |r| {
                    let push = bytemuck::bytes_of(&self.volume_push);
                    r.bind(pipeline, &[&scene.set, set], push);
                    r.draw_indirect(&self.indirect, 4 * bb::BEAMS_INDIRECT_DRAW as u64);
                });
            });
    }
}
