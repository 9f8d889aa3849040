//! Synchronization validation is on for the whole suite
//! (`common::validated_context`, `ContextOptions::sync_validation`): every
//! test that asserts a clean validation log also asserts that no two
//! commands race. This canary checks the layer really reports a missing
//! barrier, so a silent suite means no hazard rather than no checking, also
//! between two passes of a frame (on lavapipe the profiler then records the
//! frame into one command buffer instead of waiting after every pass).

use crate::common;

use caustics::vk::{Buffer, BufferUsage, Profiler, TimingSource};

#[test]
fn a_missing_barrier_is_reported() {
    let ctx = common::validated_context();
    assert!(
        ctx.sync_validation,
        "the validation layer offers VK_EXT_validation_features (Debian's vulkan-validationlayers does): synchronization validation must be on"
    );
    let buffer = Buffer::new(&ctx, "canary", 256, BufferUsage::Storage).unwrap();
    ctx.submit_and_wait(|cmd| unsafe {
        // Two transfer writes to the same bytes with no barrier between them:
        // a write-after-write hazard.
        ctx.device.cmd_fill_buffer(cmd, buffer.raw, 0, 256, 1);
        ctx.device.cmd_fill_buffer(cmd, buffer.raw, 0, 256, 2);
    })
    .unwrap();
    let errors = ctx.validation_errors();
    assert!(
        errors
            .iter()
            .any(|e| e.contains("SYNC-HAZARD-WRITE-AFTER-WRITE")),
        "expected a write-after-write hazard, got: {errors:?}"
    );
}

#[test]
fn a_missing_barrier_between_passes_is_reported() {
    let ctx = common::validated_context();
    let buffer = Buffer::new(&ctx, "canary", 256, BufferUsage::Storage).unwrap();
    let profiler = Profiler::new(&ctx, 4).unwrap();
    if ctx.is_cpu() {
        assert_eq!(profiler.source, TimingSource::FrameClock);
    }
    profiler
        .frame(|rec| {
            // Each pass alone is fine; the second lacks the barrier that
            // orders it after the first.
            // (`third_party`: raw commands the recorder does not order.)
            let (device, raw) = (&ctx.device, buffer.raw);
            for (name, value) in [("first write", 1), ("second write", 2)] {
                rec.pass(name).record(|c| {
                    c.third_party(|cmd| unsafe { device.cmd_fill_buffer(cmd, raw, 0, 256, value) })
                });
            }
            Ok(())
        })
        .unwrap();
    let errors = ctx.validation_errors();
    assert!(
        errors
            .iter()
            .any(|e| e.contains("SYNC-HAZARD-WRITE-AFTER-WRITE")),
        "expected a write-after-write hazard between the passes, got: {errors:?}"
    );
}
