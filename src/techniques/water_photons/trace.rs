//! Photon differential tracing (glsl/water_photons/trace.comp, Algorithms
//! 1-3) into an append buffer of photons, and the synchronisation of its
//! atomic counter (GUIDE §7: reset, atomic writes, indirect read, readback).
//!
//! The draw buffer holds a `VkDrawIndirectCommand` (4 vertices, instanceCount
//! = photons written) followed by `requested` (photons the trace wanted to
//! write). The shader writes a photon only into a slot below the capacity,
//! so nothing lands past the buffer; requested − written is the overflow,
//! copied to a host-visible buffer each frame and reported (a logged warning
//! and [`PhotonCounts`]).

use super::bindings;
use super::cascades::CascadeLayout;
use super::WpParamsBuffer;
use crate::frame::SceneGpu;
use crate::vk::{
    Access, Buffer, BufferUsage, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    FrameRecorder, Image, ImageDesc, VkResult, MAX_FRAMES_IN_FLIGHT,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use std::mem::size_of;
use std::sync::Arc;

/// One photon, mirrored by `Photon` in glsl/water_photons/common.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuWaterPhoton {
    /// xyz hit x'; w: cascade c.
    pub position: [f32; 4],
    /// xyz receiver normal facing the ray; w: sqrt(A'/A), Eq. 11 without s^c.
    pub normal: [f32; 4],
    /// xyz ∂x'/∂u on the receiver's tangent plane; w: ray type (`WP_RAY_*`).
    pub axis_u: [f32; 4],
    /// xyz ∂x'/∂v; w: hit distance t' (m).
    pub axis_v: [f32; 4],
    /// rgb flux Φ (W; paper mode: R of Eq. 12); w: surface parallelogram area A (m²).
    pub flux: [f32; 4],
    /// xyz ray direction; w: 0.
    pub dir: [f32; 4],
    /// xyz the texel's neighbour offsets on the water surface, ∂x/∂u and
    /// ∂x/∂v (Eq. 10 at the ray's start: with `axis_u`, `axis_v` at its
    /// end, the beam's cross-section along the whole ray, shafts.glsl);
    /// `surface_u` w: k where the texel starts a k x k block of shafts, else 0.
    pub surface_u: [f32; 4],
    pub surface_v: [f32; 4],
}
const _: () = assert!(size_of::<GpuWaterPhoton>() == 128);

/// The draw buffer: `VkDrawIndirectCommand` + the requested counter.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct DrawCounters {
    vertex_count: u32,
    instance_count: u32,
    first_vertex: u32,
    first_instance: u32,
    requested: u32,
    pad: [u32; 3],
}
const _: () = assert!(size_of::<DrawCounters>() == 32);

/// Photons of the last traced frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PhotonCounts {
    /// Written into the buffer (= the splat's instance count).
    pub written: u32,
    /// Diffuse receiver hits the trace wanted to store.
    pub requested: u32,
    pub capacity: u32,
}

impl PhotonCounts {
    pub fn overflow(&self) -> u32 {
        self.requested.saturating_sub(self.written)
    }
}

/// Photons after the capacity, filled with this bit pattern at creation: a
/// guard the trace must never touch (tests/suite/water_photons.rs checks it).
pub const GUARD_PHOTONS: u32 = 4;
pub const GUARD_WORD: u32 = 0xDEAD_BEEF;

pub struct Trace {
    /// `capacity + GUARD_PHOTONS` photons.
    pub photons: Buffer,
    /// R32UI, ccm_0² × 2N layers: layer 2 c + type holds, per texel of
    /// cascade c, the slot of the photon it sent along ray type `type`
    /// (`WP_RAY_*`), `u32::MAX` where none: the water view's gather index.
    pub slots: Image,
    /// `DrawCounters`: indirect arguments and counters.
    pub draw: Buffer,
    /// Host-visible copies of `draw`, one per frame slot (`rec.slot()`), so
    /// a frame's counts are not overwritten by the next frame in flight.
    readbacks: Vec<Buffer>,
    /// The slot of the last frame recorded.
    pub last_slot: std::cell::Cell<usize>,
    pub capacity: u32,
    threads: u64,
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _layout: DescriptorSetLayout,
}

impl Trace {
    pub fn new(
        ctx: &Arc<Context>,
        scene_gpu: &SceneGpu,
        params: &WpParamsBuffer,
        layout_c: &CascadeLayout,
        capacity: u32,
    ) -> VkResult<Self> {
        let words = (capacity as usize + GUARD_PHOTONS as usize) * size_of::<GpuWaterPhoton>() / 4;
        let photons = Buffer::with_data(
            ctx,
            "water photons",
            &vec![GUARD_WORD; words],
            BufferUsage::Storage,
        )?;
        let draw = Buffer::new(
            ctx,
            "water photon draw",
            size_of::<DrawCounters>() as u64,
            BufferUsage::StorageIndirect,
        )?;
        // Zero counts until the first trace lands.
        let readbacks = (0..MAX_FRAMES_IN_FLIGHT)
            .map(|_| {
                Buffer::with_data(
                    ctx,
                    "water photon counts",
                    &[DrawCounters::zeroed()],
                    BufferUsage::Readback,
                )
            })
            .collect::<VkResult<Vec<_>>>()?;
        let slots = Image::new_array(
            ctx,
            "water photon slots",
            ImageDesc {
                width: layout_c.size[0],
                height: layout_c.size[1],
                layers: 2 * layout_c.levels,
                format: vk::Format::R32_UINT,
                usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST,
            },
        )?;
        let layout = DescriptorSetLayout::of_shaders(ctx, 1, &["water_photons/trace.comp"])?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(bindings::WP_BINDING_PARAMS, &params.0)
            .write_buffer(bindings::WP_BINDING_PHOTONS, &photons)
            .write_buffer(bindings::WP_BINDING_DRAW, &draw);
        let pipeline = ComputePipeline::new(
            ctx,
            "water_photons/trace.comp",
            &[&scene_gpu.layout, &layout],
            0,
        )?;
        Ok(Self {
            photons,
            slots,
            draw,
            readbacks,
            last_slot: Default::default(),
            capacity,
            threads: layout_c.total_threads(),
            pipeline,
            set,
            _layout: layout,
        })
    }

    /// The counts of the frame that ran in `slot`, once its fence has signalled.
    pub fn counts(&self, slot: usize) -> VkResult<PhotonCounts> {
        let c: Vec<DrawCounters> = self.readbacks[slot].download_pod()?;
        Ok(PhotonCounts {
            written: c[0].instance_count,
            requested: c[0].requested,
            capacity: self.capacity,
        })
    }

    /// Records "photon trace": counter reset, the trace, the counts' copy to
    /// the host; afterwards `draw` is ready as indirect arguments and
    /// `photons` for the vertex shader.
    pub fn record(
        &self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        ccm_position: &Image,
        ccm_normal: &Image,
    ) {
        self.last_slot.set(rec.slot());
        let readback = &self.readbacks[rec.slot()];
        // Reset by a transfer write, after last frame's indirect read
        // and copy (write-after-read).
        // The slots are cleared the same way, after last frame's
        // water view read them: a texel that sends no photon this
        // frame (and the inner texels of cascades ≥ 1, never written)
        // must read "none".
        rec.pass("photon reset")
            .overwrite(&self.slots, Access::TransferWrite)
            .write(&self.draw, Access::TransferWrite)
            .record(|c| {
                let reset = DrawCounters {
                    vertex_count: 4,
                    ..Zeroable::zeroed()
                };
                let none = vk::ClearColorValue {
                    uint32: [u32::MAX; 4],
                };
                c.update(&self.draw, 0, bytemuck::bytes_of(&reset));
                c.clear_image(&self.slots, none);
            });
        // The reset before the atomics; the CCM attachments before the
        // storage-image reads; the photons after last frame's vertex reads;
        // the BVH after any refit.
        let set = &self.set;
        rec.pass("photon trace")
            .storage_image(
                set,
                bindings::WP_BINDING_CCM_POSITION,
                ccm_position,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_CCM_NORMAL,
                ccm_normal,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                bindings::WP_BINDING_PHOTON_SLOTS,
                &self.slots,
                Access::ComputeWrite,
            )
            .write(&self.draw, Access::ComputeWrite)
            .write(&self.photons, Access::ComputeWrite)
            .read(&scene.triangles, Access::ComputeRead)
            .record(|c| {
                let per_row =
                    (bindings::WP_TRACE_GROUP_SIZE * bindings::WP_TRACE_GROUPS_PER_ROW) as u64;
                let groups = if self.threads <= per_row {
                    [
                        self.threads.div_ceil(bindings::WP_TRACE_GROUP_SIZE as u64) as u32,
                        1,
                        1,
                    ]
                } else {
                    [
                        bindings::WP_TRACE_GROUPS_PER_ROW,
                        self.threads.div_ceil(per_row) as u32,
                        1,
                    ]
                };
                c.dispatch(&self.pipeline, &[&scene.set, set], &[], groups);
                // The atomics done, the counts go to the host.
                c.read_back(&self.draw, readback, self.draw.size);
            });
    }
}
