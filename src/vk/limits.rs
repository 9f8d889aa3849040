//! The device's limits, checked before anything is made or allocated
//! (issue 18). A request over `maxImageDimension2D`, `maxImageArrayLayers`
//! or `maxStorageBufferRange` would be invalid usage; one over what a
//! memory heap can still hold would, on lavapipe, not return
//! VK_ERROR_OUT_OF_DEVICE_MEMORY but meet the kernel's OOM killer (its heap
//! is the machine's RAM). So `Buffer::new` and `Image::new` ask here first
//! and fail with [`VkError::OverLimit`], which names the resource, the
//! request and the limit; callers add the argument or field behind it.
//!
//! Memory is accounted per heap: the bytes of this process's live
//! allocations (as gpu-allocator sizes them), against the heap's size. The
//! heap is the one gpu-allocator will choose (the same memory-type
//! preference as its `allocate`). Not counted: gpu-allocator's unused rest
//! of its memory blocks (at most one partly used 256 MiB block per memory
//! type), other processes' use of the device (VK_EXT_memory_budget would
//! tell; not used, lavapipe lacks it).

use super::{VkError, VkResult};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::atomic::{AtomicU64, Ordering};

/// What this process holds per memory heap, and the heaps' sizes.
pub struct MemoryHeaps {
    heaps: Vec<vk::MemoryHeap>,
    types: Vec<vk::MemoryType>,
    used: Vec<AtomicU64>,
}

/// Device memory in use, from gpu-allocator's report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct MemoryReport {
    /// Bytes of live allocations.
    pub allocated: u64,
    /// Bytes of memory blocks gpu-allocator holds from the driver.
    pub capacity: u64,
    /// Live allocations.
    pub allocations: usize,
}

impl MemoryHeaps {
    pub(super) fn new(props: &vk::PhysicalDeviceMemoryProperties) -> Self {
        let heaps = props.memory_heaps[..props.memory_heap_count as usize].to_vec();
        MemoryHeaps {
            used: heaps.iter().map(|_| AtomicU64::new(0)).collect(),
            heaps,
            types: props.memory_types[..props.memory_type_count as usize].to_vec(),
        }
    }

    /// The heap gpu-allocator allocates `type_bits` at `location` from: the
    /// first memory type with the preferred flags, else with the required
    /// ones (gpu-allocator 0.28, `Allocator::allocate`).
    fn heap_for(&self, type_bits: u32, location: MemoryLocation) -> Option<usize> {
        use vk::MemoryPropertyFlags as F;
        let (preferred, required) = match location {
            MemoryLocation::GpuOnly => (F::DEVICE_LOCAL, F::DEVICE_LOCAL),
            MemoryLocation::CpuToGpu => (
                F::HOST_VISIBLE | F::HOST_COHERENT | F::DEVICE_LOCAL,
                F::HOST_VISIBLE | F::HOST_COHERENT,
            ),
            MemoryLocation::GpuToCpu => (
                F::HOST_VISIBLE | F::HOST_COHERENT | F::HOST_CACHED,
                F::HOST_VISIBLE | F::HOST_COHERENT,
            ),
            MemoryLocation::Unknown => (F::empty(), F::empty()),
        };
        let find = |flags: F| {
            self.types
                .iter()
                .enumerate()
                .find(|(i, t)| type_bits & (1 << i) != 0 && t.property_flags.contains(flags))
        };
        find(preferred)
            .or_else(|| find(required))
            .map(|(_, t)| t.heap_index as usize)
    }

    /// The heap of an allocation with these memory properties.
    fn heap_of(&self, flags: vk::MemoryPropertyFlags) -> Option<usize> {
        self.types
            .iter()
            .find(|t| t.property_flags == flags)
            .map(|t| t.heap_index as usize)
    }

    /// Fails unless the heap `requirements` at `location` go to can still
    /// take them.
    pub(super) fn check(
        &self,
        name: &str,
        requirements: &vk::MemoryRequirements,
        location: MemoryLocation,
    ) -> VkResult<()> {
        let Some(heap) = self.heap_for(requirements.memory_type_bits, location) else {
            return Ok(()); // gpu-allocator reports the missing memory type
        };
        let size = self.heaps[heap].size;
        let used = self.used[heap].load(Ordering::SeqCst);
        if used.saturating_add(requirements.size) > size {
            return Err(VkError::OverLimit(format!(
                "\"{name}\" needs {} of device memory, but memory heap {heap} holds {} and {} of it is in use",
                bytes(requirements.size),
                bytes(size),
                bytes(used)
            )));
        }
        Ok(())
    }

    pub(super) fn allocated(&self, flags: vk::MemoryPropertyFlags, size: u64) {
        if let Some(h) = self.heap_of(flags) {
            self.used[h].fetch_add(size, Ordering::SeqCst);
        }
    }

    pub(super) fn freed(&self, flags: vk::MemoryPropertyFlags, size: u64) {
        if let Some(h) = self.heap_of(flags) {
            self.used[h].fetch_sub(size, Ordering::SeqCst);
        }
    }

    /// Each heap's (size, bytes this process holds in it).
    pub fn heaps(&self) -> Vec<(u64, u64)> {
        self.heaps
            .iter()
            .zip(&self.used)
            .map(|(h, u)| (h.size, u.load(Ordering::SeqCst)))
            .collect()
    }

    /// The largest device-local heap's size.
    pub fn device_local_heap(&self) -> u64 {
        self.heaps
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .map(|h| h.size)
            .max()
            .unwrap_or(0)
    }
}

/// Bytes per texel of the formats the renderer uses (a lower bound of 1 for
/// any other).
fn texel_bytes(format: vk::Format) -> u64 {
    use vk::Format as F;
    match format {
        F::R32G32B32A32_SFLOAT => 16,
        F::R16G16B16A16_SFLOAT | F::D32_SFLOAT_S8_UINT => 8,
        F::R8G8B8A8_UNORM
        | F::B8G8R8A8_UNORM
        | F::R32_SFLOAT
        | F::R32_UINT
        | F::D32_SFLOAT
        | F::D24_UNORM_S8_UINT
        | F::X8_D24_UNORM_PACK32 => 4,
        F::D16_UNORM => 2,
        _ => 1,
    }
}

/// Checks a 2D image against what the device offers for its format and
/// usage (`vkGetPhysicalDeviceImageFormatProperties`: extent, layers and
/// `maxResourceSize`, which vkCreateImage must not exceed).
pub(super) fn check_image_format(
    ctx: &super::Context,
    name: &str,
    info: &vk::ImageCreateInfo,
) -> VkResult<()> {
    let Ok(props) = (unsafe {
        ctx.instance.get_physical_device_image_format_properties(
            ctx.physical_device,
            info.format,
            info.image_type,
            info.tiling,
            info.usage,
            info.flags,
        )
    }) else {
        return Ok(()); // an unsupported format: vkCreateImage says so
    };
    let e = info.extent;
    let size =
        e.width as u64 * e.height as u64 * info.array_layers as u64 * texel_bytes(info.format);
    if e.width > props.max_extent.width
        || e.height > props.max_extent.height
        || info.array_layers > props.max_array_layers
        || size > props.max_resource_size
    {
        return Err(VkError::OverLimit(format!(
            "image \"{name}\" of {}x{} pixels, {} layer(s), at least {size} bytes: the device offers {:?} images up to {}x{}, {} layers, {} bytes (maxResourceSize)",
            e.width,
            e.height,
            info.array_layers,
            info.format,
            props.max_extent.width,
            props.max_extent.height,
            props.max_array_layers,
            props.max_resource_size
        )));
    }
    Ok(())
}

/// Checks a 2D image's extent and layers against the device's limits.
pub(super) fn check_image(
    limits: &vk::PhysicalDeviceLimits,
    name: &str,
    width: u32,
    height: u32,
    layers: u32,
) -> VkResult<()> {
    let max = limits.max_image_dimension2_d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(VkError::OverLimit(format!(
            "image \"{name}\" of {width}x{height} pixels: the device's 2D images are 1 to {max} pixels a side (maxImageDimension2D)"
        )));
    }
    if layers == 0 || layers > limits.max_image_array_layers {
        return Err(VkError::OverLimit(format!(
            "image \"{name}\" of {layers} layers: the device allows 1 to {} (maxImageArrayLayers)",
            limits.max_image_array_layers
        )));
    }
    Ok(())
}

/// Checks a storage buffer's size: shaders bind every storage buffer whole.
pub(super) fn check_storage_buffer(
    limits: &vk::PhysicalDeviceLimits,
    name: &str,
    size: u64,
) -> VkResult<()> {
    let max = limits.max_storage_buffer_range as u64;
    if size > max {
        return Err(VkError::OverLimit(format!(
            "storage buffer \"{name}\" of {}: the device binds at most {} (maxStorageBufferRange)",
            bytes(size),
            bytes(max)
        )));
    }
    Ok(())
}

/// The process's resident set size (VmRSS in /proc/self/status) in bytes;
/// `None` where the file or the field is missing (not Linux). On lavapipe
/// it holds the device's memory and the driver's compiled shaders too.
pub fn host_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().strip_suffix("kB"))
        .and_then(|kb| kb.trim().parse::<u64>().ok())
        .map(|kb| kb * 1024)
}

/// Returns the malloc heap's free pages to the system: glibc's
/// `malloc_trim(0)`, which walks every arena (the main thread's and those of
/// lavapipe's and the validation layer's threads) and releases the free
/// pages that glibc otherwise keeps for reuse. It frees no live allocation,
/// so the RSS after it is memory in use: a leak (live memory that grows)
/// still shows, while the arenas' retained pages, which go up and down with
/// which thread freed what, no longer scatter the samples. Returns whether
/// a trim ran: only with glibc; elsewhere (musl, macOS, Windows) nothing
/// happens and the RSS keeps the allocator's cache.
pub fn trim_host_heap() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: malloc_trim takes the arenas' locks itself and is safe to
        // call while other threads allocate; it only returns free pages.
        unsafe { libc::malloc_trim(0) };
        true
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}

/// `n` bytes in binary units, for messages.
pub fn bytes(n: u64) -> String {
    const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut v = n as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{n} bytes")
    } else {
        format!("{v:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn heaps() -> MemoryHeaps {
        let mut props = vk::PhysicalDeviceMemoryProperties {
            memory_heap_count: 2,
            memory_type_count: 2,
            ..Default::default()
        };
        props.memory_heaps[0] = vk::MemoryHeap {
            size: 1 << 30,
            flags: vk::MemoryHeapFlags::DEVICE_LOCAL,
        };
        props.memory_heaps[1] = vk::MemoryHeap {
            size: 4 << 30,
            flags: vk::MemoryHeapFlags::empty(),
        };
        props.memory_types[0] = vk::MemoryType {
            property_flags: vk::MemoryPropertyFlags::DEVICE_LOCAL,
            heap_index: 0,
        };
        props.memory_types[1] = vk::MemoryType {
            property_flags: vk::MemoryPropertyFlags::HOST_VISIBLE
                | vk::MemoryPropertyFlags::HOST_COHERENT,
            heap_index: 1,
        };
        MemoryHeaps::new(&props)
    }

    fn req(size: u64) -> vk::MemoryRequirements {
        vk::MemoryRequirements {
            size,
            alignment: 256,
            memory_type_bits: 0b11,
        }
    }

    #[test]
    fn a_heap_refuses_what_it_cannot_hold_any_more() {
        let h = heaps();
        h.check("a", &req(1 << 30), MemoryLocation::GpuOnly)
            .unwrap();
        let e = h
            .check("a", &req((1 << 30) + 1), MemoryLocation::GpuOnly)
            .unwrap_err()
            .to_string();
        assert!(e.contains("\"a\"") && e.contains("1.0 GiB"), "{e}");
        h.allocated(vk::MemoryPropertyFlags::DEVICE_LOCAL, 768 << 20);
        assert!(h
            .check("b", &req(256 << 20), MemoryLocation::GpuOnly)
            .is_ok());
        assert!(h
            .check("b", &req((256 << 20) + 1), MemoryLocation::GpuOnly)
            .is_err());
        // The host heap is apart.
        assert!(h
            .check("c", &req(3 << 30), MemoryLocation::GpuToCpu)
            .is_ok());
        h.freed(vk::MemoryPropertyFlags::DEVICE_LOCAL, 768 << 20);
        assert_eq!(h.heaps(), vec![(1 << 30, 0), (4 << 30, 0)]);
    }

    #[test]
    fn images_and_storage_buffers_within_the_limits() {
        let limits = vk::PhysicalDeviceLimits {
            max_image_dimension2_d: 16384,
            max_image_array_layers: 2048,
            max_storage_buffer_range: 1 << 27,
            ..Default::default()
        };
        assert!(check_image(&limits, "i", 16384, 1, 1).is_ok());
        let e = check_image(&limits, "i", 16385, 1, 1)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("maxImageDimension2D") && e.contains("16384"),
            "{e}"
        );
        assert!(check_image(&limits, "i", 0, 1, 1).is_err());
        assert!(check_image(&limits, "i", 1, 1, 2049).is_err());
        assert!(check_storage_buffer(&limits, "b", 1 << 27).is_ok());
        let e = check_storage_buffer(&limits, "b", (1 << 27) + 1)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("maxStorageBufferRange") && e.contains("128.0 MiB"),
            "{e}"
        );
    }
}
