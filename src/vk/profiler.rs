//! One frame at a time, waited for: `Profiler` runs a single `Frames` slot
//! and waits for each frame (tests, the reference, calibrations).

use super::frame::{FrameOptions, FrameRecorder, FrameSync, Frames, PassTiming, TimingSource};
use super::{Context, VkResult};
use std::sync::Arc;

/// One frame at a time, waited for: tests, the reference, calibrations.
pub struct Profiler {
    frames: std::cell::RefCell<Frames>,
    pub source: TimingSource,
}

impl Profiler {
    /// Timestamps in one command buffer on a GPU; one command buffer per
    /// frame timed by the host clock on a CPU device.
    pub fn new(ctx: &Arc<Context>, max_passes: u32) -> VkResult<Self> {
        Self::with(ctx, max_passes, false)
    }

    /// For measurements that need each pass's time: per-pass host clock on
    /// a CPU device, timestamps on a GPU.
    pub fn for_timing(ctx: &Arc<Context>, max_passes: u32) -> VkResult<Self> {
        Self::with(ctx, max_passes, true)
    }

    fn with(ctx: &Arc<Context>, max_passes: u32, per_pass: bool) -> VkResult<Self> {
        let frames = Frames::new(
            ctx,
            FrameOptions {
                frames_in_flight: 1,
                per_pass,
                max_passes,
            },
        )?;
        Ok(Profiler {
            source: frames.source,
            frames: std::cell::RefCell::new(frames),
        })
    }

    /// Records, submits and waits for one frame; returns each pass's time.
    pub fn frame(
        &self,
        record: impl FnOnce(&mut FrameRecorder) -> VkResult<()>,
    ) -> VkResult<Vec<PassTiming>> {
        let mut frames = self.frames.borrow_mut();
        let (mut rec, _) = frames.begin_frame()?;
        let recorded = record(&mut rec);
        let submitted = rec.submit(&FrameSync::default());
        let mut done = frames.wait_all()?;
        recorded?;
        submitted?;
        Ok(done.pop().map(|t| t.passes).unwrap_or_default())
    }
}
