//! volume_lines' B: the volume caustic buffer of each light's rays
//! ("volume segments"), drawn as lines ("volume lines"), between the
//! per-frame "volume visibility" and "volume clear" before and "volume
//! composite" after (the module doc of `volume_lines` has the method).

use super::bindings;
use crate::frame::{FrameTargets, SceneGpu};
use crate::passes::light_views::{LightView, LightViewConsumer};
use crate::passes::specular_gbuffer::SpecularGBuffer;
use crate::passes::surface_frame::SurfaceFrame;
use crate::scene::{Density, Scene};
use crate::vk::{
    groups_8x8, Access, Buffer, BufferUsage, ComputePipeline, Context, DescriptorSet,
    DescriptorSetLayout, FrameRecorder, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc,
    VkResult,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::mem::size_of;
use std::sync::Arc;

/// One entry of the volume caustic buffer, mirrored by `Segment` in
/// glsl/volume_lines/volume_lines.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuSegment {
    /// xyz exit point p1; w = 1 for a light ray, 0 for none.
    pub p1: [f32; 4],
    /// xyz end point p2.
    pub p2: [f32; 4],
    /// rgb flux (W) after the specular object; w: the texel's solid angle
    /// (sr) or area (m^2).
    pub flux: [f32; 4],
}
const _: () = assert!(size_of::<GpuSegment>() == 48);

/// Push constants of segments.comp: the photon view and its parameters.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SegmentPush {
    origin: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    forward: [f32; 4],
    /// x: TIR remedy; y: Eq. 6.3.2 on; z: transmittance steps; w: the
    /// filter radius (f32 bits; the clipping margin).
    params: [u32; 4],
}

/// Push constants of lines.frag.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct LinePush {
    step: f32,
    radius: f32,
    line_raster: u32,
    transmittance_steps: u32,
}

pub struct VolumeRays {
    /// The volume caustic buffer of the last light recorded: N x N
    /// transmitted (or mirror-reflected) light rays, then N x N rays
    /// reflected off a dielectric's front face.
    pub segments: Buffer,
    /// B alone: radiance (rgb) and fragments per pixel (a).
    pub volume: Image,
    pub buffer_size: u32,
    /// Buffer entries drawn: the transmitted half, or both halves with
    /// `front_reflection`.
    draw_count: u32,
    /// Distance to the first surface per pixel (floats).
    visibility: Buffer,
    segment_params: [u32; 4],
    line_push: LinePush,
    segment_pipeline: ComputePipeline,
    visibility_pipeline: ComputePipeline,
    line_pipeline: GraphicsPipeline,
    composite_pipeline: ComputePipeline,
    set: DescriptorSet,
    /// "volume visibility"'s set.
    visibility_set: DescriptorSet,
    /// "volume composite"'s set.
    composite_set: DescriptorSet,
    _layouts: [DescriptorSetLayout; 3],
}

/// What `VolumeRays` takes from the technique's parameters.
pub struct RaySettings {
    /// N: light rays per side of the light view.
    pub buffer_size: u32,
    /// Delta_x and r (m).
    pub step: f32,
    pub radius: f32,
    pub transmittance_steps: u32,
    pub front_reflection: bool,
    /// `TIR_*` and Eq. 6.3.2 on (image_space's).
    pub tir_remedy: u32,
    pub eq_6_3_2: u32,
}

impl VolumeRays {
    /// Frames of `width` x `height`, over light views of `settings.buffer_size`.
    pub fn new(
        ctx: &Arc<Context>,
        settings: &RaySettings,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        let n = settings.buffer_size;
        let segments = Buffer::new(
            ctx,
            "volume caustic buffer",
            2 * (n as u64 * n as u64) * size_of::<GpuSegment>() as u64,
            BufferUsage::Storage,
        )?;
        let visibility = Buffer::new(
            ctx,
            "volume visibility",
            width as u64 * height as u64 * 4,
            BufferUsage::Storage,
        )?;
        let volume = Image::new(
            ctx,
            "volume caustic radiance",
            ImageDesc::new_2d(
                width,
                height,
                vk::Format::R32G32B32A32_SFLOAT,
                vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::STORAGE
                    | vk::ImageUsageFlags::TRANSFER_SRC,
            ),
        )?;
        use bindings as vb;
        // One set (and layout) per group of passes, holding what the
        // group's shaders use: each pass declares its own image bindings
        // (`vk/pass.rs`).
        let layout_of = |shaders: &[&str]| DescriptorSetLayout::of_shaders(ctx, 1, shaders);
        let layouts = [
            layout_of(&["volume_lines/visibility.comp"])?,
            layout_of(&[
                "volume_lines/segments.comp",
                "volume_lines/lines.vert",
                "volume_lines/lines.geom",
                "volume_lines/lines.frag",
                "volume_lines/lines_heterogeneous.frag",
            ])?,
            layout_of(&["volume_lines/composite.comp"])?,
        ];
        let buffers = [
            (vb::VOLUME_LINES_BINDING_SEGMENTS, &segments),
            (vb::VOLUME_LINES_BINDING_VISIBILITY, &visibility),
        ];
        let new_set = |layout: &DescriptorSetLayout| -> VkResult<DescriptorSet> {
            let set = DescriptorSet::new(ctx, layout)?;
            set.write_buffers(&buffers);
            Ok(set)
        };
        let (visibility_set, set, composite_set) = (
            new_set(&layouts[0])?,
            new_set(&layouts[1])?,
            new_set(&layouts[2])?,
        );
        let with = |layout| [&scene_gpu.layout, layout];
        let segment_pipeline = ComputePipeline::new(
            ctx,
            "volume_lines/segments.comp",
            &with(&layouts[1]),
            size_of::<SegmentPush>() as u32,
        )?;
        let visibility_pipeline =
            ComputePipeline::new(ctx, "volume_lines/visibility.comp", &with(&layouts[0]), 0)?;
        let composite_pipeline =
            ComputePipeline::new(ctx, "volume_lines/composite.comp", &with(&layouts[2]), 0)?;
        // A constant density (or none) gets fragments compiled without the
        // density field's code.
        let homogeneous = scene
            .medium
            .as_ref()
            .is_none_or(|m| matches!(m.density, Density::Constant(_)));
        let fragment = if homogeneous {
            "volume_lines/lines.frag"
        } else {
            "volume_lines/lines_heterogeneous.frag"
        };
        let mut desc = GraphicsPipelineDesc::new("volume_lines/lines.vert", fragment);
        desc.geometry = Some("volume_lines/lines.geom");
        desc.color_formats = vec![vk::Format::R32G32B32A32_SFLOAT];
        desc.additive = true;
        desc.topology = vk::PrimitiveTopology::POINT_LIST;
        desc.push_size = size_of::<LinePush>() as u32;
        let line_pipeline = GraphicsPipeline::new(ctx, &desc, &with(&layouts[1]))?;
        let transmittance_steps = settings.transmittance_steps;
        Ok(Self {
            segments,
            volume,
            buffer_size: n,
            draw_count: if settings.front_reflection {
                2 * n * n
            } else {
                n * n
            },
            visibility,
            segment_params: [
                settings.tir_remedy,
                settings.eq_6_3_2,
                transmittance_steps,
                settings.radius.to_bits(),
            ],
            line_push: LinePush {
                step: settings.step,
                radius: settings.radius,
                // Strict lines are 1-px rectangles about the line; otherwise
                // implementations rasterise a parallelogram (one fragment per
                // major-axis column, the Bresenham-like rule).
                line_raster: if ctx.limits.strict_lines == vk::TRUE {
                    bindings::LINE_RASTER_RECTANGULAR
                } else {
                    bindings::LINE_RASTER_PARALLELOGRAM
                },
                transmittance_steps,
            },
            segment_pipeline,
            visibility_pipeline,
            line_pipeline,
            composite_pipeline,
            visibility_set,
            set,
            composite_set,
            _layouts: layouts,
        })
    }

    /// Records "volume visibility" and "volume clear", before the lights'
    /// passes (after `surface.record_opaque`).
    pub fn begin(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        surface: &SurfaceFrame,
        targets: &FrameTargets,
    ) {
        // The camera G-buffers were written by rasterisation; the
        // distances are overwritten after last frame's line fragments.
        let set = &self.visibility_set;
        rec.pass("volume visibility")
            .storage_image(
                set,
                bindings::VOLUME_LINES_BINDING_OPAQUE_POSITION,
                &surface.gbuffer().position,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::VOLUME_LINES_BINDING_SPECULAR_POSITION,
                &surface.specular().front_position,
                Access::ComputeRead,
            )
            .write(&self.visibility, Access::ComputeWrite)
            .record(|c| {
                let groups = groups_8x8(targets.width, targets.height);
                c.dispatch(&self.visibility_pipeline, &[&scene.set, set], &[], groups);
            });
        rec.pass("volume clear")
            .overwrite(&self.volume, Access::ColorAttachment)
            .record(|c| {
                let colors = [(self.volume.view, Some([0.0; 4]))];
                c.render(self.volume.extent(), &colors, None, |_| {});
            });
    }

    /// Records "volume composite": B added to the frame's radiance (after
    /// the surface frame's refraction wrote it).
    pub fn composite(&self, rec: &mut FrameRecorder, scene: &SceneGpu, targets: &FrameTargets) {
        // The lines' blended writes are read; the frame's radiance was
        // written by the surface frame's refraction pass.
        let set = &self.composite_set;
        rec.pass("volume composite")
            .storage_image(
                set,
                bindings::VOLUME_LINES_BINDING_VOLUME,
                &self.volume,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::VOLUME_LINES_BINDING_RADIANCE,
                &targets.radiance,
                Access::ComputeWrite,
            )
            .record(|c| {
                let groups = groups_8x8(targets.width, targets.height);
                c.dispatch(&self.composite_pipeline, &[&scene.set, set], &[], groups);
            });
    }
}

impl LightViewConsumer for VolumeRays {
    fn reads_gbuffer(&self) -> bool {
        true
    }

    /// Records "volume segments" and "volume lines" for one light.
    fn record_light(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        _light: usize,
        view: &LightView,
        light_view: &SpecularGBuffer,
    ) {
        let push = SegmentPush {
            origin: view.origin,
            right: view.right,
            up: view.up,
            forward: view.forward,
            params: self.segment_params,
        };
        // The light view's attachment writes become storage reads; the
        // buffer is rewritten after the previous light's lines (or last
        // frame's) pulled it.
        let pass = rec
            .pass("volume segments")
            .write(&self.segments, Access::ComputeWrite)
            .read(&scene.triangles, Access::ComputeRead);
        light_view
            .bind_reads(
                pass,
                &self.set,
                [
                    bindings::VOLUME_LINES_BINDING_FRONT_POSITION,
                    bindings::VOLUME_LINES_BINDING_FRONT_NORMAL,
                    bindings::VOLUME_LINES_BINDING_BACK_POSITION,
                    bindings::VOLUME_LINES_BINDING_BACK_NORMAL,
                ],
            )
            .record(|c| {
                let groups = groups_8x8(self.buffer_size, self.buffer_size);
                c.dispatch(
                    &self.segment_pipeline,
                    &[&scene.set, &self.set],
                    bytemuck::bytes_of(&push),
                    groups,
                );
            });
        // Segments pulled by the geometry shader and read again by
        // the fragments (so the next light's segment pass waits for
        // both); the distances read by the fragments.
        rec.pass("volume lines")
            .write(&self.volume, Access::ColorAttachment)
            .read(&self.segments, Access::GraphicsRead)
            .read(&self.visibility, Access::FragmentRead)
            .record(|c| {
                c.render(
                    self.volume.extent(),
                    &[(self.volume.view, None)],
                    None,
                    |r| {
                        let push = bytemuck::bytes_of(&self.line_push);
                        r.bind(&self.line_pipeline, &[&scene.set, &self.set], push);
                        r.draw(self.draw_count);
                    },
                );
            });
    }
}
