//! Host memory the renderer itself owns, counted where it is allocated, so a
//! leak check can tell it from the process's resident set (`host_rss`), which
//! also holds the driver's and the validation layer's own caches.
//!
//! - Vulkan host memory: every instance- and device-scope allocation the
//!   loader, the layers and the driver make through the application's
//!   `VkAllocationCallbacks` (Vulkan spec, "Host Memory"). The context
//!   passes `HOST_ALLOCATION_CALLBACKS` to vkCreateInstance and
//!   vkCreateDevice. Objects created with a null allocator then allocate
//!   through the device's on Mesa (`vk_object_alloc` falls back to
//!   `device->alloc`; the spec does not require it, so other drivers may
//!   count only the instance and device), so there this counts what the
//!   objects and command buffers the renderer creates hold, plus what the
//!   loader and layers allocate through the callbacks. What a driver
//!   allocates with plain malloc for its own work (llvmpipe's rasteriser
//!   bins, compiled shader variants) is not counted here: it shows only in
//!   the RSS. A sample may catch a small block the driver's queue thread
//!   frees just after the fence (168 bytes on lavapipe).
//! - The Rust heap: `CountingAllocator`, the `caustics` binary's global
//!   allocator. Library users that install another allocator get `None`
//!   from `rust_heap`.

use ash::vk;
use std::alloc::{GlobalAlloc, Layout, System};
use std::ffi::c_void;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// Live bytes and allocations of one counter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HostCount {
    pub bytes: u64,
    pub allocations: u64,
}

struct Counter {
    bytes: AtomicU64,
    allocations: AtomicU64,
}

impl Counter {
    const fn new() -> Self {
        Counter {
            bytes: AtomicU64::new(0),
            allocations: AtomicU64::new(0),
        }
    }

    fn add(&self, size: usize) {
        self.bytes.fetch_add(size as u64, Ordering::Relaxed);
        self.allocations.fetch_add(1, Ordering::Relaxed);
    }

    fn remove(&self, size: usize) {
        self.bytes.fetch_sub(size as u64, Ordering::Relaxed);
        self.allocations.fetch_sub(1, Ordering::Relaxed);
    }

    fn read(&self) -> HostCount {
        HostCount {
            bytes: self.bytes.load(Ordering::Relaxed),
            allocations: self.allocations.load(Ordering::Relaxed),
        }
    }
}

static VULKAN_HOST: Counter = Counter::new();
static RUST_HEAP: Counter = Counter::new();
static RUST_HEAP_COUNTED: AtomicBool = AtomicBool::new(false);

/// What the Vulkan callbacks hand out and have not been given back.
pub fn vulkan_host_memory() -> HostCount {
    VULKAN_HOST.read()
}

/// The Rust heap in use, when `CountingAllocator` is the global allocator.
pub fn rust_heap() -> Option<HostCount> {
    RUST_HEAP_COUNTED
        .load(Ordering::Relaxed)
        .then(|| RUST_HEAP.read())
}

/// The system allocator, counting live bytes and allocations.
pub struct CountingAllocator;

/// Marks the Rust heap as counted (a read first: no shared write on every
/// allocation).
fn note_counting() {
    if !RUST_HEAP_COUNTED.load(Ordering::Relaxed) {
        RUST_HEAP_COUNTED.store(true, Ordering::Relaxed);
    }
}

// SAFETY: every call is forwarded to `System` with the caller's layout; the
// counters only observe sizes.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc(layout);
        if !p.is_null() {
            note_counting();
            RUST_HEAP.add(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc_zeroed(layout);
        if !p.is_null() {
            note_counting();
            RUST_HEAP.add(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout);
        RUST_HEAP.remove(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = System.realloc(ptr, layout, new_size);
        if !p.is_null() {
            RUST_HEAP.remove(layout.size());
            RUST_HEAP.add(new_size);
        }
        p
    }
}

// Each Vulkan block is preceded by a header that records its size and
// alignment (the free and reallocation callbacks get only the pointer). The
// header takes `align` bytes, at least HEADER, so the block stays aligned.
const HEADER: usize = 16;

fn layout_for(size: usize, alignment: usize) -> Option<(Layout, usize)> {
    let align = alignment.max(HEADER).checked_next_power_of_two()?;
    let total = size.checked_add(align)?;
    Layout::from_size_align(total, align)
        .ok()
        .map(|l| (l, align))
}

/// The block's size and alignment, read from its header.
///
/// # Safety
/// `p` must come from `vulkan_allocate` and not have been freed.
unsafe fn header(p: *mut u8) -> (usize, usize) {
    let words = p.sub(HEADER) as *const usize;
    (words.read(), words.add(1).read())
}

/// The counter a callback's user data points to.
///
/// # Safety
/// `user` must be null or point to a `Counter` that outlives the call.
unsafe fn counter<'a>(user: *mut c_void) -> Option<&'a Counter> {
    (user as *const Counter).as_ref()
}

/// vkAllocationFunction: null on failure (the caller reports
/// VK_ERROR_OUT_OF_HOST_MEMORY); a size of 0 gets a valid empty block.
/// Never unwinds.
unsafe extern "system" fn vulkan_allocate(
    user: *mut c_void,
    size: usize,
    alignment: usize,
    _scope: vk::SystemAllocationScope,
) -> *mut c_void {
    let Some((layout, align)) = layout_for(size, alignment) else {
        return std::ptr::null_mut();
    };
    let raw = System.alloc(layout);
    if raw.is_null() {
        return std::ptr::null_mut();
    }
    let p = raw.add(align);
    let words = p.sub(HEADER) as *mut usize;
    words.write(size);
    words.add(1).write(align);
    if let Some(c) = counter(user) {
        c.add(size);
    }
    p as *mut c_void
}

/// vkFreeFunction: null is allowed and ignored.
unsafe extern "system" fn vulkan_free(user: *mut c_void, memory: *mut c_void) {
    if memory.is_null() {
        return;
    }
    let p = memory as *mut u8;
    let (size, align) = header(p);
    if let Some(c) = counter(user) {
        c.remove(size);
    }
    System.dealloc(
        p.sub(align),
        Layout::from_size_align_unchecked(size + align, align),
    );
}

/// vkReallocationFunction, with the spec's cases: a null original
/// allocates, size 0 frees (and returns null), otherwise a new block keeps
/// the smaller of the two sizes' contents; on failure the original stays
/// valid and null is returned.
unsafe extern "system" fn vulkan_reallocate(
    user: *mut c_void,
    original: *mut c_void,
    size: usize,
    alignment: usize,
    scope: vk::SystemAllocationScope,
) -> *mut c_void {
    if original.is_null() {
        return vulkan_allocate(user, size, alignment, scope);
    }
    if size == 0 {
        vulkan_free(user, original);
        return std::ptr::null_mut();
    }
    let (old_size, _) = header(original as *mut u8);
    let new = vulkan_allocate(user, size, alignment, scope);
    if new.is_null() {
        return new;
    }
    std::ptr::copy_nonoverlapping(original as *const u8, new as *mut u8, old_size.min(size));
    vulkan_free(user, original);
    new
}

/// The callbacks the context creates and destroys its instance and device
/// with, counting into `vulkan_host_memory` (as ash takes them).
pub(super) const HOST_CALLBACKS: Option<&vk::AllocationCallbacks<'static>> =
    Some(&HOST_ALLOCATION_CALLBACKS);

/// The callbacks themselves.
pub static HOST_ALLOCATION_CALLBACKS: vk::AllocationCallbacks<'static> = vk::AllocationCallbacks {
    p_user_data: &VULKAN_HOST as *const Counter as *mut c_void,
    pfn_allocation: Some(vulkan_allocate),
    pfn_reallocation: Some(vulkan_reallocate),
    pfn_free: Some(vulkan_free),
    pfn_internal_allocation: None,
    pfn_internal_free: None,
    _marker: std::marker::PhantomData,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vulkan_callbacks_align_count_and_keep_contents() {
        let scope = vk::SystemAllocationScope::OBJECT;
        // A counter of its own: the process-wide one also sees the Vulkan
        // objects of tests running beside this one.
        let own = Counter::new();
        let user = &own as *const Counter as *mut c_void;
        unsafe {
            let p = vulkan_allocate(user, 100, 64, scope);
            assert!(!p.is_null());
            assert_eq!(p as usize % 64, 0);
            std::ptr::write_bytes(p as *mut u8, 7, 100);
            let grown = vulkan_reallocate(user, p, 1000, 64, scope);
            assert_eq!(grown as usize % 64, 0);
            assert!(std::slice::from_raw_parts(grown as *const u8, 100)
                .iter()
                .all(|&b| b == 7));
            let q = vulkan_reallocate(user, std::ptr::null_mut(), 8, 1, scope);
            assert_eq!(q as usize % HEADER, 0);
            assert_eq!(
                own.read(),
                HostCount {
                    bytes: 1008,
                    allocations: 2
                }
            );
            assert!(vulkan_reallocate(user, grown, 0, 64, scope).is_null());
            vulkan_free(user, q);
            vulkan_free(user, std::ptr::null_mut());
            assert_eq!(own.read(), HostCount::default());
            let empty = vulkan_allocate(user, 0, 8, scope);
            assert!(!empty.is_null());
            vulkan_free(user, empty);
            assert_eq!(own.read(), HostCount::default());
            assert!(vulkan_allocate(user, usize::MAX - 8, 8, scope).is_null());
        }
    }
}
