//! Frames in flight. `Frames` owns N per-frame contexts (default 2); each has
//! its command pool and buffer, fence, acquire semaphore (for presentation),
//! timestamp query pool, upload ring and deferred-release list. (Over 600
//! lines: `Frames` and its `FrameRecorder` share the slot state and its
//! invariants below; the ring and the one-frame `Profiler` are apart.)
//! `begin_frame` waits only for the fence of the frame that last used the
//! same slot, N frames ago; `FrameRecorder::submit` submits without waiting.
//!
//! What this makes safe, and what it relies on:
//! - Everything the host writes for a frame (frame constants, light views,
//!   animated geometry, technique uniforms) goes through `FrameRecorder::upload`:
//!   the bytes land in this slot's ring, which the GPU reads only during this
//!   frame, and a copy in the frame's command buffer moves them into the
//!   device-local destination. The destination is shared by all frames but
//!   written only by the GPU, in queue order, behind barriers, so frame k+1's
//!   copy cannot overtake frame k's reads.
//! - Every GPU-only image and buffer is likewise shared, ordered by the
//!   barriers `vk/sync.rs` derives from its tracked state: recording order is
//!   submission order, so the tracked state is right across frames.
//! - Whatever a frame in flight may still use is dropped through
//!   `Frames::defer_release`, after that frame's fence, never by an early `Drop`.
//! - A descriptor set may not be rewritten while a frame in flight uses it:
//!   a rewrite during recording first calls `FrameRecorder::wait_for_other_frames`.
//!
//! Timing (GUIDE §8): on a GPU, timestamp pairs around each pass in the
//! frame's command buffer, copied into its ring by that command buffer and
//! read when its fence has signalled. On a CPU device
//! whose timestamps miss compute, the frame is timed by the host clock
//! (submit to observed completion), frames still overlap, and per-pass numbers
//! come only on request (`per_pass`): one submission per pass, each waited for.

use super::pass::Pass;
use super::ring::Ring;
use super::sync::barrier;
use super::{fault, Access, Buffer, BufferAccess, Context, VkError, VkResult};
use ash::vk;
use std::any::Any;
use std::collections::VecDeque;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The most frames a `Frames` may keep in flight (techniques size per-frame
/// read-back buffers by it).
pub const MAX_FRAMES_IN_FLIGHT: usize = 4;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum TimingSource {
    /// vkCmdWriteTimestamp2 pairs, converted with timestampPeriod.
    Timestamps,
    /// One submission per pass, host wall clock from submit to fence (on
    /// request: the host waits after every pass, so frames cannot overlap).
    WallClock,
    /// A CPU device: the whole frame in one command buffer, frames overlap;
    /// the frame is timed by the host clock and the per-pass timestamps miss
    /// compute dispatches.
    FrameClock,
}

impl TimingSource {
    pub fn describe(self) -> &'static str {
        match self {
            TimingSource::Timestamps => "GPU timestamp queries",
            TimingSource::WallClock => {
                "wall clock per pass submission (CPU device: its timestamps miss compute)"
            }
            TimingSource::FrameClock => {
                "one command buffer per frame, host clock per frame; per-pass timestamps miss compute (CPU device)"
            }
        }
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct PassTiming {
    pub name: String,
    pub ms: f64,
}

/// How a `Frames` runs.
#[derive(Clone, Copy, Debug)]
pub struct FrameOptions {
    /// 1 to `MAX_FRAMES_IN_FLIGHT`.
    pub frames_in_flight: usize,
    /// On a CPU device: one submission per pass, timed by the host clock.
    pub per_pass: bool,
    /// Timestamp pairs per frame.
    pub max_passes: u32,
}

impl Default for FrameOptions {
    fn default() -> Self {
        FrameOptions {
            frames_in_flight: 2,
            per_pass: false,
            max_passes: 64,
        }
    }
}

/// A completed frame's timings.
#[derive(Clone, Debug)]
pub struct FrameTiming {
    /// Which slot it ran in (per-frame read-back buffers are indexed by it).
    pub slot: usize,
    pub passes: Vec<PassTiming>,
    /// Host clock from submission to the host seeing its fence signalled:
    /// the frame's GPU time when one frame is in flight; with more it also
    /// holds the time queued behind the frame before.
    pub submit_to_done_ms: f64,
}

struct Pending {
    names: Vec<String>,
    /// Where in the ring the frame's command buffer copied its timestamps
    /// (chunk, offset).
    ticks: Option<(usize, u64)>,
    wall_ms: Vec<f64>,
    submitted: Instant,
}

struct Slot {
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    acquired: vk::Semaphore,
    queries: vk::QueryPool,
    ring: Ring,
    release: Vec<Box<dyn Any>>,
    pending: Option<Pending>,
}

pub struct Frames {
    ctx: Arc<Context>,
    slots: Vec<Slot>,
    /// The slot the next frame uses.
    next: usize,
    /// Slots with a submitted frame, oldest first.
    order: VecDeque<usize>,
    /// Frames `FrameRecorder::wait_for_other_frames` completed, oldest
    /// first, handed out by the next `begin_frame` or `wait_all` so their
    /// timings and read-backs are not lost.
    completed_early: Vec<FrameTiming>,
    max_passes: u32,
    pub source: TimingSource,
    /// Host time spent in `begin_frame` waiting for a slot's fence, and in
    /// `wait_all`, since creation.
    pub host_wait: Duration,
    /// Host time spent inside vkQueueSubmit2 since creation (a CPU driver
    /// may block there: lavapipe runs the submission's work before
    /// returning when its queue is busy).
    pub host_submit: Duration,
}

impl Frames {
    pub fn new(ctx: &Arc<Context>, options: FrameOptions) -> VkResult<Frames> {
        let n = options.frames_in_flight.clamp(1, MAX_FRAMES_IN_FLIGHT);
        let source = match (ctx.is_cpu(), options.per_pass) {
            (false, _) => TimingSource::Timestamps,
            (true, true) => TimingSource::WallClock,
            (true, false) => TimingSource::FrameClock,
        };
        let mut frames = Frames {
            ctx: ctx.clone(),
            slots: Vec::new(),
            next: 0,
            order: VecDeque::new(),
            completed_early: Vec::new(),
            max_passes: options.max_passes,
            source,
            host_wait: Duration::ZERO,
            host_submit: Duration::ZERO,
        };
        for _ in 0..n {
            let slot = frames.new_slot()?;
            frames.slots.push(slot);
        }
        Ok(frames)
    }

    /// Makes one slot; what is made before an error is pushed into a slot
    /// with null handles, which `Drop` skips (destroying null is a no-op).
    fn new_slot(&self) -> VkResult<Slot> {
        let d = &self.ctx.device;
        let mut slot = Slot {
            pool: vk::CommandPool::null(),
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            acquired: vk::Semaphore::null(),
            queries: vk::QueryPool::null(),
            ring: Ring::new(),
            release: Vec::new(),
            pending: None,
        };
        let result = (|| unsafe {
            slot.pool = d.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(self.ctx.queue_family)
                    .flags(vk::CommandPoolCreateFlags::TRANSIENT),
                None,
            )?;
            slot.cmd = d.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(slot.pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1),
            )?[0];
            slot.fence = d.create_fence(&vk::FenceCreateInfo::default(), None)?;
            slot.acquired = d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?;
            slot.queries = d.create_query_pool(
                &vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::TIMESTAMP)
                    .query_count(self.max_passes * 2),
                None,
            )?;
            Ok::<(), VkError>(())
        })();
        match result {
            Ok(()) => Ok(slot),
            Err(e) => {
                self.destroy_slot(&mut slot);
                Err(e)
            }
        }
    }

    fn destroy_slot(&self, slot: &mut Slot) {
        let d = &self.ctx.device;
        slot.release.clear();
        slot.ring.clear();
        unsafe {
            d.destroy_query_pool(slot.queries, None);
            d.destroy_semaphore(slot.acquired, None);
            d.destroy_fence(slot.fence, None);
            d.destroy_command_pool(slot.pool, None);
        }
    }

    pub fn frames_in_flight(&self) -> usize {
        self.slots.len()
    }

    /// Frames submitted and not yet seen complete.
    pub fn pending(&self) -> usize {
        self.order.len()
    }

    /// Starts the next frame: waits for the fence of the frame that last used
    /// its slot (N frames ago; the only host wait of the loop), then frees
    /// that frame's releases, resets its ring and command pool. Returns the
    /// recorder and the timings of every frame completed since the last
    /// call, oldest first: that older frame's, if it had one, after any that
    /// `wait_for_other_frames` completed meanwhile.
    pub fn begin_frame(&mut self) -> VkResult<(FrameRecorder<'_>, Vec<FrameTiming>)> {
        let index = self.next;
        let mut done = std::mem::take(&mut self.completed_early);
        if self.slots[index].pending.is_some() {
            self.order.retain(|&s| s != index);
            match self.complete(index) {
                Ok(t) => done.push(t),
                Err(e) => {
                    // Frames completed before keep their timings.
                    self.completed_early = done;
                    return Err(e);
                }
            }
        }
        let ctx = self.ctx.clone();
        let slot = &mut self.slots[index];
        slot.ring.reset(&ctx)?;
        unsafe {
            ctx.device
                .reset_command_pool(slot.pool, vk::CommandPoolResetFlags::empty())?;
            ctx.device.begin_command_buffer(
                slot.cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?;
            if self.source != TimingSource::WallClock {
                ctx.device
                    .cmd_reset_query_pool(slot.cmd, slot.queries, 0, self.max_passes * 2);
            }
        }
        let serial = ctx
            .frame_serial
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed)
            + 1;
        let recorder = FrameRecorder {
            serial,
            frames: self,
            slot: index,
            names: Vec::new(),
            wall_ms: Vec::new(),
            error: None,
        };
        Ok((recorder, done))
    }

    /// Waits for slot `index`'s frame, releases what it held and reads its timings.
    fn complete(&mut self, index: usize) -> VkResult<FrameTiming> {
        let ctx = self.ctx.clone();
        let slot = &mut self.slots[index];
        let start = Instant::now();
        let waited = (|| unsafe {
            ctx.device.wait_for_fences(&[slot.fence], true, u64::MAX)?;
            fault::queue_op()?;
            ctx.device.reset_fences(&[slot.fence])?;
            Ok::<(), VkError>(())
        })();
        // Not pending any more, even when the wait failed (a lost device).
        ctx.frames_pending.fetch_sub(1, Ordering::Relaxed);
        waited?;
        let waited = start.elapsed();
        self.host_wait += waited;
        let done = Instant::now();
        // The frame has completed: nothing it used is read any more.
        slot.release.clear();
        let pending = slot.pending.take().expect("a submitted frame");
        let passes = match self.source {
            TimingSource::WallClock => pending
                .names
                .into_iter()
                .zip(pending.wall_ms)
                .map(|(name, ms)| PassTiming { name, ms })
                .collect(),
            TimingSource::Timestamps | TimingSource::FrameClock => match pending.ticks {
                Some((chunk, offset)) => {
                    let bytes = slot.ring.read(chunk, offset, pending.names.len() * 16);
                    let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&bytes);
                    timings(&ctx, pending.names, &ticks)
                }
                None => Vec::new(),
            },
        };
        Ok(FrameTiming {
            slot: index,
            passes,
            submit_to_done_ms: (done - pending.submitted).as_secs_f64() * 1e3,
        })
    }

    /// Waits for every frame in flight (oldest first) and returns their
    /// timings: headless `render` and `bench` call it once at the end.
    pub fn wait_all(&mut self) -> VkResult<Vec<FrameTiming>> {
        let mut out = std::mem::take(&mut self.completed_early);
        while let Some(index) = self.order.pop_front() {
            match self.complete(index) {
                Ok(t) => out.push(t),
                Err(e) => {
                    // Frames completed before keep their timings.
                    self.completed_early = out;
                    return Err(e);
                }
            }
        }
        Ok(out)
    }

    /// Drops `value` once no frame submitted so far can use it: after the
    /// fence of the newest frame in flight (frames complete in order), or
    /// now when none is in flight.
    pub fn defer_release(&mut self, value: impl Any) {
        if let Some(&newest) = self.order.back() {
            self.slots[newest].release.push(Box::new(value));
        }
    }
}

/// Pass times from each pass's pair of raw timestamps.
fn timings(ctx: &Context, names: Vec<String>, ticks: &[u64]) -> Vec<PassTiming> {
    let mask = if ctx.timestamp_valid_bits >= 64 {
        u64::MAX
    } else {
        (1u64 << ctx.timestamp_valid_bits) - 1
    };
    names
        .into_iter()
        .enumerate()
        .map(|(i, name)| {
            // Wrapping subtraction within the valid bits: the counter may wrap mid-frame.
            let delta = ticks[2 * i + 1].wrapping_sub(ticks[2 * i]) & mask;
            PassTiming {
                name,
                ms: delta as f64 * ctx.timestamp_period * 1e-6,
            }
        })
        .collect()
}

impl Drop for Frames {
    fn drop(&mut self) {
        // Nothing a slot owns may go while its frame runs. After a failed
        // wait (a lost device) the frames behind it are not waited for one
        // by one: idle the device instead.
        if self.wait_all().is_err() {
            self.ctx.wait_idle();
        }
        let mut slots = std::mem::take(&mut self.slots);
        for slot in &mut slots {
            self.destroy_slot(slot);
        }
    }
}

/// Semaphores a frame's submission waits on and signals (the demo's
/// acquire and render-finished semaphores).
#[derive(Default)]
pub struct FrameSync {
    pub waits: Vec<(vk::Semaphore, vk::PipelineStageFlags2)>,
    pub signals: Vec<(vk::Semaphore, vk::PipelineStageFlags2)>,
}

/// Records one frame: every pass goes through `pass`, every host write
/// through `upload`; `submit` ends it.
pub struct FrameRecorder<'a> {
    frames: &'a mut Frames,
    slot: usize,
    serial: u64,
    names: Vec<String>,
    wall_ms: Vec<f64>,
    error: Option<VkError>,
}

impl<'a> FrameRecorder<'a> {
    pub fn ctx(&self) -> &Arc<Context> {
        &self.frames.ctx
    }

    /// This frame's slot, 0 to `frames_in_flight() - 1`.
    pub fn slot(&self) -> usize {
        self.slot
    }

    /// Signalled by vkAcquireNextImageKHR for this frame (the demo).
    pub fn acquire_semaphore(&self) -> vk::Semaphore {
        self.frames.slots[self.slot].acquired
    }

    fn per_pass(&self) -> bool {
        self.frames.source == TimingSource::WallClock
    }

    /// Starts declaring one named pass (`vk/pass.rs`): what it reads, writes
    /// and binds; its `record` emits the barriers, writes the bindings and
    /// records it. Every pass of every technique goes through here.
    pub fn pass<'r, 'res>(&'r mut self, name: &str) -> Pass<'r, 'a, 'res> {
        Pass::new(self, name)
    }

    /// The frame's serial number (the context's count of frames begun).
    pub(super) fn serial(&self) -> u64 {
        self.serial
    }

    /// Records one named pass (its barrier is the first command `record`
    /// records): timed, or `untimed` into the frame's command buffer.
    pub(super) fn record_pass<R>(
        &mut self,
        name: &str,
        untimed: bool,
        record: impl FnOnce(vk::CommandBuffer) -> R,
    ) -> Option<R> {
        if self.error.is_some() {
            return None;
        }
        let ctx = self.frames.ctx.clone();
        let cmd = self.frames.slots[self.slot].cmd;
        if untimed {
            ctx.begin_label(cmd, name);
            let result = record(cmd);
            ctx.end_label(cmd);
            return Some(result);
        }
        let result = if self.per_pass() {
            let start = Instant::now();
            let submitted = ctx.submit_and_wait(|cmd| {
                ctx.begin_label(cmd, name);
                let result = record(cmd);
                ctx.end_label(cmd);
                result
            });
            match submitted {
                Ok(result) => {
                    self.wall_ms.push(start.elapsed().as_secs_f64() * 1e3);
                    Some(result)
                }
                Err(e) => {
                    self.error = Some(e);
                    return None;
                }
            }
        } else {
            let pool = self.frames.slots[self.slot].queries;
            let index = self.names.len() as u32;
            if index >= self.frames.max_passes {
                panic!(
                    "frame recorder: more than {} passes",
                    self.frames.max_passes
                );
            }
            ctx.begin_label(cmd, name);
            unsafe {
                ctx.device.cmd_write_timestamp2(
                    cmd,
                    vk::PipelineStageFlags2::TOP_OF_PIPE,
                    pool,
                    index * 2,
                )
            };
            let result = record(cmd);
            unsafe {
                ctx.device.cmd_write_timestamp2(
                    cmd,
                    vk::PipelineStageFlags2::BOTTOM_OF_PIPE,
                    pool,
                    index * 2 + 1,
                )
            };
            ctx.end_label(cmd);
            Some(result)
        };
        self.names.push(name.to_string());
        result
    }

    /// Writes `bytes` to the start of `dst` for this frame: into the frame's
    /// ring, then a copy in the frame's command buffer, declared through the
    /// same barrier engine as the passes: it waits for `dst`'s last write
    /// and for every read since the last upload (`Access::AnyRead`: shaders
    /// reading it through a set, such as set 0's frame constants, declare
    /// nothing), and every later command sees the new contents.
    pub fn upload(&mut self, dst: &Buffer, bytes: &[u8]) {
        if bytes.is_empty() || self.error.is_some() {
            return;
        }
        assert!(
            bytes.len() as u64 <= dst.size,
            "upload larger than its buffer"
        );
        let ctx = self.frames.ctx.clone();
        let (_, src, offset) = match self.frames.slots[self.slot].ring.alloc(&ctx, bytes) {
            Ok(a) => a,
            Err(e) => {
                self.error = Some(e);
                return;
            }
        };
        // Declared like a pass's accesses: the copy waits for the previous
        // upload's readers (`AnyRead`: passes read these buffers through
        // their sets without declaring it) and the buffer's last write; the
        // new contents are then made visible to every later command.
        let copy = |cmd: vk::CommandBuffer| {
            barrier(
                &ctx,
                cmd,
                &[],
                &[BufferAccess::new(dst, Access::TransferWrite)],
            );
            let region = vk::BufferCopy::default()
                .src_offset(offset)
                .size(bytes.len() as u64);
            unsafe { ctx.device.cmd_copy_buffer(cmd, src, dst.raw, &[region]) };
            barrier(&ctx, cmd, &[], &[BufferAccess::new(dst, Access::AnyRead)]);
        };
        if self.per_pass() {
            // Passes are separate submissions here: the copy must run before
            // the next one, so it is a submission of its own.
            if let Err(e) = ctx.submit_and_wait(copy) {
                self.error = Some(e);
            }
        } else {
            copy(self.frames.slots[self.slot].cmd);
        }
    }

    /// Waits for every other frame in flight. For the rare descriptor-set
    /// rewrite during recording (a technique binding new frame targets):
    /// a set may not be updated while a submitted frame can still use it.
    /// Their timings reach the caller of the next `begin_frame` or
    /// `wait_all`; an error is returned by `submit`.
    pub fn wait_for_other_frames(&mut self) {
        let others: Vec<usize> = self.frames.order.drain(..).collect();
        for index in others {
            match self.frames.complete(index) {
                Ok(done) => self.frames.completed_early.push(done),
                Err(e) => {
                    self.error.get_or_insert(e);
                }
            }
        }
    }

    /// Records the copy of the frame's timestamps into its ring, read by the
    /// host after the fence. Not vkGetQueryPoolResults: lavapipe's waits for
    /// everything submitted, which made the host wait for the next frame in
    /// flight too (measured 110-130 ms per frame at 256x256 with 2 in flight).
    fn copy_timestamps(&mut self) -> VkResult<Option<(usize, u64)>> {
        let count = self.names.len() as u32 * 2;
        if self.per_pass() || count == 0 {
            return Ok(None);
        }
        let ctx = self.frames.ctx.clone();
        let slot = &mut self.frames.slots[self.slot];
        let zeros = vec![0u8; count as usize * 8];
        let (chunk, buffer, offset) = slot.ring.alloc(&ctx, &zeros)?;
        unsafe {
            // WAIT: the copy waits for the timestamps to be written.
            ctx.device.cmd_copy_query_pool_results(
                slot.cmd,
                slot.queries,
                0,
                count,
                buffer,
                offset,
                8,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            );
            let to_host = vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COPY)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                .dst_access_mask(vk::AccessFlags2::HOST_READ);
            ctx.device.cmd_pipeline_barrier2(
                slot.cmd,
                &vk::DependencyInfo::default().memory_barriers(&[to_host]),
            );
        }
        Ok(Some((chunk, offset)))
    }

    /// Ends and submits the frame without waiting for it. Returns the
    /// recording's first error, if any (the frame is still submitted, so its
    /// slot's fence signals).
    pub fn submit(mut self, sync: &FrameSync) -> VkResult<()> {
        let ctx = self.frames.ctx.clone();
        let index = self.slot;
        let ticks = self.copy_timestamps()?;
        let slot = &mut self.frames.slots[index];
        unsafe { ctx.device.end_command_buffer(slot.cmd) }?;
        let waits = semaphore_infos(&sync.waits);
        let signals = semaphore_infos(&sync.signals);
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(slot.cmd)];
        let submit = vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals);
        let start = Instant::now();
        fault::queue_op()?;
        unsafe { ctx.device.queue_submit2(ctx.queue, &[submit], slot.fence) }?;
        ctx.frames_pending.fetch_add(1, Ordering::Relaxed);
        self.frames.host_submit += start.elapsed();
        slot.pending = Some(Pending {
            ticks,
            names: std::mem::take(&mut self.names),
            wall_ms: std::mem::take(&mut self.wall_ms),
            submitted: Instant::now(),
        });
        self.frames.order.push_back(index);
        self.frames.next = (index + 1) % self.frames.slots.len();
        match self.error.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

fn semaphore_infos(
    list: &[(vk::Semaphore, vk::PipelineStageFlags2)],
) -> Vec<vk::SemaphoreSubmitInfo<'static>> {
    list.iter()
        .map(|&(s, stage)| {
            vk::SemaphoreSubmitInfo::default()
                .semaphore(s)
                .stage_mask(stage)
        })
        .collect()
}
