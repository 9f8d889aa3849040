//! Test hook: failures lavapipe cannot produce on request (issue 18). A
//! CPU device is never lost, and where it runs out of memory the kernel's
//! OOM killer ends the process first. `CAUSTICS_TEST_FAULT` makes the
//! backend fail as a GPU would, so tests can check that the command line
//! reports one clear line, exits 1 and writes nothing:
//!
//! - `device_lost:N`: from the N-th queue submission or fence wait on
//!   (counting from 1, all of them: `Context::submit_and_wait`, a frame's
//!   submit and the wait for its fence) each returns VK_ERROR_DEVICE_LOST,
//!   as a lost device keeps doing.
//! - `out_of_device_memory:N`: the N-th allocation fails with
//!   VK_ERROR_OUT_OF_DEVICE_MEMORY.
//!
//! Read here only, once. The work itself still runs on the real device, so
//! teardown waits for it as usual (`Frames::drop` idles the device after a
//! failed wait). Not for users: it is documented in docs/ARCHITECTURE.md
//! with the tests.

use ash::vk;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

pub(super) const VAR: &str = "CAUSTICS_TEST_FAULT";

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Fault {
    DeviceLost(u64),
    OutOfDeviceMemory(u64),
}

fn fault() -> Option<Fault> {
    static FAULT: OnceLock<Option<Fault>> = OnceLock::new();
    *FAULT.get_or_init(|| parse(&std::env::var(VAR).ok()?))
}

fn parse(text: &str) -> Option<Fault> {
    let (kind, n) = text.split_once(':')?;
    let n: u64 = n.trim().parse().ok().filter(|&n| n >= 1)?;
    match kind.trim() {
        "device_lost" => Some(Fault::DeviceLost(n)),
        "out_of_device_memory" => Some(Fault::OutOfDeviceMemory(n)),
        _ => None,
    }
}

static QUEUE_OPS: AtomicU64 = AtomicU64::new(0);
static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

/// Before a queue submission or fence wait: the injected device loss, if due.
pub(super) fn queue_op() -> Result<(), vk::Result> {
    if let Some(Fault::DeviceLost(n)) = fault() {
        if QUEUE_OPS.fetch_add(1, Ordering::SeqCst) + 1 >= n {
            return Err(vk::Result::ERROR_DEVICE_LOST);
        }
    }
    Ok(())
}

/// Before an allocation: the injected out-of-memory, if due.
pub(super) fn allocation() -> Result<(), vk::Result> {
    if let Some(Fault::OutOfDeviceMemory(n)) = fault() {
        if ALLOCATIONS.fetch_add(1, Ordering::SeqCst) + 1 == n {
            return Err(vk::Result::ERROR_OUT_OF_DEVICE_MEMORY);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_forms_only() {
        assert_eq!(parse("device_lost:3"), Some(Fault::DeviceLost(3)));
        assert_eq!(
            parse("out_of_device_memory:1"),
            Some(Fault::OutOfDeviceMemory(1))
        );
        assert_eq!(parse("device_lost:0"), None);
        assert_eq!(parse("device_lost"), None);
        assert_eq!(parse("lost:2"), None);
    }
}
