//! The one choke point every pass goes through: `FrameRecorder::pass` wraps
//! the pass in a debug-utils label (so captures read by pass name) and a
//! timing scope.
//!
//! Two timing sources: GPU timestamp queries around each pass in one command
//! buffer (real GPUs), or, on CPU implementations such as lavapipe whose
//! timestamps do not measure compute dispatches (GUIDE §8), one submission
//! per pass timed by the host clock. The source in use is reported with
//! every timing.
//!
//! Under synchronization validation a CPU device records the frame into one
//! command buffer too (`TimingSource::ValidatedFrame`): the host wait after
//! every pass of the wall-clock mode would order each pass after the last
//! and hide a missing barrier between two passes from the layer.

use super::{Context, VkResult};
use ash::vk;
use std::sync::Arc;
use std::time::Instant;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum TimingSource {
    /// vkCmdWriteTimestamp2 pairs, converted with timestampPeriod.
    Timestamps,
    /// One submission per pass, host wall clock from submit to fence.
    WallClock,
    /// A CPU device under synchronization validation: the whole frame in one
    /// command buffer with timestamps, which miss compute dispatches there.
    ValidatedFrame,
}

impl TimingSource {
    pub fn describe(self) -> &'static str {
        match self {
            TimingSource::Timestamps => "GPU timestamp queries",
            TimingSource::WallClock => {
                "wall clock per pass submission (CPU device: its timestamps miss compute)"
            }
            TimingSource::ValidatedFrame => {
                "GPU timestamp queries in one command buffer for synchronization validation (CPU device: they miss compute)"
            }
        }
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct PassTiming {
    pub name: String,
    pub ms: f64,
}

pub struct Profiler {
    ctx: Arc<Context>,
    pool: vk::QueryPool,
    capacity: u32,
    pub source: TimingSource,
}

/// Records one frame's passes; see `Profiler::frame`.
pub struct FrameRecorder<'a> {
    profiler: &'a Profiler,
    /// The frame's command buffer in timestamp mode.
    cmd: Option<vk::CommandBuffer>,
    names: Vec<String>,
    wall_ms: Vec<f64>,
    error: Option<super::VkError>,
}

impl Profiler {
    /// The profiler for frames: timestamps in one command buffer on a GPU;
    /// on a CPU device one submission per pass timed by the host clock, or
    /// one command buffer per frame when synchronization validation is on
    /// (see the module doc).
    pub fn new(ctx: &Arc<Context>, max_passes: u32) -> VkResult<Self> {
        let source = match (ctx.is_cpu(), ctx.sync_validation) {
            (false, _) => TimingSource::Timestamps,
            (true, false) => TimingSource::WallClock,
            (true, true) => TimingSource::ValidatedFrame,
        };
        Self::with_source(ctx, max_passes, source)
    }

    /// A profiler for measurements that need each pass's time whatever the
    /// validation: per-pass host clock on a CPU device, timestamps on a GPU.
    pub fn for_timing(ctx: &Arc<Context>, max_passes: u32) -> VkResult<Self> {
        let source = if ctx.is_cpu() {
            TimingSource::WallClock
        } else {
            TimingSource::Timestamps
        };
        Self::with_source(ctx, max_passes, source)
    }

    fn with_source(ctx: &Arc<Context>, max_passes: u32, source: TimingSource) -> VkResult<Self> {
        let capacity = max_passes * 2;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity);
        let pool = unsafe { ctx.device.create_query_pool(&info, None) }?;
        Ok(Self {
            ctx: ctx.clone(),
            pool,
            capacity,
            source,
        })
    }

    /// Records and runs one frame: `record` calls `FrameRecorder::pass` for
    /// each pass. Returns each pass's time in milliseconds once the GPU has
    /// finished the frame (the host waits: headless rendering and benchmarks).
    pub fn frame(
        &self,
        record: impl FnOnce(&mut FrameRecorder) -> VkResult<()>,
    ) -> VkResult<Vec<PassTiming>> {
        let ctx = &self.ctx;
        let mut recorder = FrameRecorder {
            profiler: self,
            cmd: None,
            names: Vec::new(),
            wall_ms: Vec::new(),
            error: None,
        };
        match self.source {
            TimingSource::WallClock => {
                record(&mut recorder)?;
                if let Some(e) = recorder.error {
                    return Err(e);
                }
                Ok(recorder
                    .names
                    .into_iter()
                    .zip(recorder.wall_ms)
                    .map(|(name, ms)| PassTiming { name, ms })
                    .collect())
            }
            TimingSource::Timestamps | TimingSource::ValidatedFrame => {
                let pool = self.pool;
                let capacity = self.capacity;
                ctx.submit_and_wait(|cmd| {
                    unsafe { ctx.device.cmd_reset_query_pool(cmd, pool, 0, capacity) };
                    recorder.cmd = Some(cmd);
                    record(&mut recorder)
                })??;
                if let Some(e) = recorder.error {
                    return Err(e);
                }
                let count = recorder.names.len() * 2;
                if count == 0 {
                    return Ok(Vec::new());
                }
                let mut ticks = vec![0u64; count];
                unsafe {
                    ctx.device.get_query_pool_results(
                        pool,
                        0,
                        &mut ticks,
                        vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                    )
                }?;
                let mask = if ctx.timestamp_valid_bits >= 64 {
                    u64::MAX
                } else {
                    (1u64 << ctx.timestamp_valid_bits) - 1
                };
                Ok(recorder
                    .names
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
                    .collect())
            }
        }
    }
}

impl FrameRecorder<'_> {
    pub fn ctx(&self) -> &Arc<Context> {
        &self.profiler.ctx
    }

    /// Records one named pass. Every pass of every technique goes through here.
    pub fn pass(&mut self, name: &str, record: impl FnOnce(vk::CommandBuffer)) {
        if self.error.is_some() {
            return;
        }
        let ctx = self.profiler.ctx.clone();
        match self.cmd {
            Some(cmd) => {
                let index = self.names.len() as u32;
                if index * 2 + 1 >= self.profiler.capacity {
                    panic!(
                        "profiler capacity of {} passes exceeded",
                        self.profiler.capacity / 2
                    );
                }
                ctx.begin_label(cmd, name);
                unsafe {
                    ctx.device.cmd_write_timestamp2(
                        cmd,
                        vk::PipelineStageFlags2::TOP_OF_PIPE,
                        self.profiler.pool,
                        index * 2,
                    )
                };
                record(cmd);
                unsafe {
                    ctx.device.cmd_write_timestamp2(
                        cmd,
                        vk::PipelineStageFlags2::BOTTOM_OF_PIPE,
                        self.profiler.pool,
                        index * 2 + 1,
                    )
                };
                ctx.end_label(cmd);
            }
            None => {
                let start = Instant::now();
                let result = ctx.submit_and_wait(|cmd| {
                    ctx.begin_label(cmd, name);
                    record(cmd);
                    ctx.end_label(cmd);
                });
                if let Err(e) = result {
                    self.error = Some(e);
                    return;
                }
                self.wall_ms.push(start.elapsed().as_secs_f64() * 1e3);
            }
        }
        self.names.push(name.to_string());
    }
}

impl Drop for Profiler {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}
