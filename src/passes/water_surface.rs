//! Water surface: evaluates a water object's Gerstner surface
//! (glsl/common/water.glsl, the formula of src/scene/water.rs) at one time
//! on the GPU, one invocation per grid vertex, into a storage buffer of
//! `GpuWaterVertex` (position, normal) in the grid order of `Water::mesh`.
//! It is the input of the light-view raster of the water (the cascaded
//! caustic maps of Kougianos & Moustakas 2021, §3.1: water_photons' "ccm
//! raster" reads `vertices`); tests/suite/water_surface.rs checks it against the
//! CPU evaluation.

use crate::gpu::{GpuWaterVertex, GpuWave};
use crate::scene::Water;
use crate::shader_bindings as b;
use crate::vk::{
    Access, Buffer, BufferUsage, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    FrameRecorder, VkResult,
};
use bytemuck::{Pod, Zeroable};
use std::mem::size_of;
use std::sync::Arc;

/// Push constants of glsl/passes/water_surface.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct WaterSurfacePush {
    /// xy: centre (x, z); zw: size (x, z), m.
    center_size: [f32; 4],
    /// x: nx cells, y: nz cells, z: wave count, w: unused.
    grid: [u32; 4],
    /// x: time (s), y: base height (m), zw: unused.
    time_base_height: [f32; 4],
}

const _: () = assert!(size_of::<WaterSurfacePush>() == 48);

pub struct WaterSurface {
    pipeline: ComputePipeline,
    _layout: DescriptorSetLayout,
    set: DescriptorSet,
    _waves: Buffer,
    /// (nx + 1)(nz + 1) `GpuWaterVertex`, vertex (i, j) at j (nx + 1) + i,
    /// written by `record`.
    pub vertices: Buffer,
    push: WaterSurfacePush,
    groups: [u32; 3],
}

impl WaterSurface {
    pub fn new(ctx: &Arc<Context>, water: &Water) -> VkResult<Self> {
        let layout = DescriptorSetLayout::of_shaders(ctx, 0, &["passes/water_surface.comp"])?;
        let pipeline = ComputePipeline::new(
            ctx,
            "passes/water_surface.comp",
            &[&layout],
            size_of::<WaterSurfacePush>() as u32,
        )?;
        // A storage buffer cannot be empty: flat water binds one unused wave.
        let mut waves: Vec<GpuWave> = water.waves.iter().map(GpuWave::new).collect();
        if waves.is_empty() {
            waves.push(GpuWave::zeroed());
        }
        let waves = Buffer::with_data(ctx, "water waves", &waves, BufferUsage::Storage)?;
        let vertices = Buffer::new(
            ctx,
            "water surface vertices",
            (water.vertex_count() * size_of::<GpuWaterVertex>()) as u64,
            BufferUsage::Storage,
        )?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(b::WATER_SURFACE_BINDING_WAVES, &waves)
            .write_buffer(b::WATER_SURFACE_BINDING_VERTICES, &vertices);
        let [nx, nz] = water.resolution;
        let push = WaterSurfacePush {
            center_size: [water.center.x, water.center.y, water.size.x, water.size.y],
            grid: [nx, nz, water.waves.len() as u32, 0],
            time_base_height: [0.0, water.base_height, 0.0, 0.0],
        };
        let groups = [
            (nx + 1).div_ceil(b::WATER_SURFACE_GROUP_SIZE),
            (nz + 1).div_ceil(b::WATER_SURFACE_GROUP_SIZE),
            1,
        ];
        Ok(Self {
            pipeline,
            _layout: layout,
            set,
            _waves: waves,
            vertices,
            push,
            groups,
        })
    }

    /// Records the evaluation of the surface at `time` seconds into `vertices`.
    pub fn record(&self, rec: &mut FrameRecorder, time: f32) {
        let mut push = self.push;
        push.time_base_height[0] = time;
        // Every vertex is rewritten: the previous contents (and readers of
        // them, e.g. last frame's raster) only need to be ordered before.
        rec.pass("water surface")
            .write(&self.vertices, Access::ComputeWrite)
            .record(|c| {
                c.dispatch(
                    &self.pipeline,
                    &[&self.set],
                    bytemuck::bytes_of(&push),
                    self.groups,
                );
            });
    }
}
