//! The Vulkan backend: instance and device, memory, buffers and images,
//! pipelines and descriptors, command submission, barriers, the GPU profiler
//! and readback. It knows nothing about caustics; passes and techniques are
//! built on top of it (docs/ARCHITECTURE.md).
//!
//! Lifetime model: every object is owned by a Rust value and destroyed by its
//! `Drop`. Values hold an `Arc` of the device, so the device outlives them.
//! Whatever a frame in flight may still use is handed to
//! `Frames::defer_release` and dropped after that frame's fence
//! (`vk/frame.rs`), so `Drop` never frees what the GPU may still read.
//! Pipelines are shared: equal ones come from the context's `PipelineStore`
//! and are destroyed when the last holder (or the store's short keep list)
//! lets go.

mod commands;
mod context;
mod descriptors;
mod device;
mod fault;
mod frame;
mod host_memory;
mod image;
mod instance;
mod limits;
mod objects;
mod pass;
mod pipeline;
mod pipeline_create;
mod pipeline_store;
mod profiler;
mod reflect;
mod resources;
mod ring;
mod swapchain;
mod sync;

pub use commands::{Commands, Rendering, Step};
pub use context::{Context, ContextOptions, ValidationCounts};
pub use descriptors::{DescriptorSet, DescriptorSetLayout, Sampler, SetResource};
pub use device::{DeviceInfo, RequiredFeature};
pub use frame::{
    FrameOptions, FrameRecorder, FrameSync, FrameTiming, Frames, PassTiming, TimingSource,
    MAX_FRAMES_IN_FLIGHT,
};
pub use host_memory::{rust_heap, vulkan_host_memory, CountingAllocator, HostCount};
pub use image::{Image, ImageDesc};
pub use limits::{bytes, host_rss, trim_host_heap, MemoryHeaps, MemoryReport};
pub use objects::{CommandPool, Semaphores};
pub use pass::Pass;
pub use pipeline::{groups_8x8, ComputePipeline, GraphicsPipeline};
pub use pipeline_store::{
    CacheLoad, GraphicsPipelineDesc, PipelineCounts, PipelineStore, Specialization,
};
pub use profiler::Profiler;
pub use resources::{Buffer, BufferUsage};
pub use swapchain::{Acquired, Surface, Swapchain};
pub use sync::{Access, Resource};
use sync::{BufferAccess, ImageAccess};

pub use ash::vk;

/// Errors at the backend boundary: typed, so callers can tell a device
/// problem from a missing feature or a driver error.
#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error("could not load the Vulkan loader (libvulkan.so.1): {0}. Install it with `apt-get install libvulkan1 mesa-vulkan-drivers`")]
    Loader(String),
    #[error("no Vulkan device found. Install Mesa's lavapipe with `apt-get install mesa-vulkan-drivers`")]
    NoDevice,
    #[error("no device matches --device {0:?}; `caustics info` lists them")]
    DeviceNotFound(String),
    #[error("device \"{device}\" lacks required feature(s): {missing}")]
    MissingFeatures { device: String, missing: String },
    #[error("the Khronos validation layer (VK_LAYER_KHRONOS_validation) is not installed: `apt-get install vulkan-validationlayers`")]
    NoValidationLayer,
    #[error("the device ran out of memory (VK_ERROR_OUT_OF_DEVICE_MEMORY)")]
    OutOfDeviceMemory,
    #[error("the host ran out of memory (VK_ERROR_OUT_OF_HOST_MEMORY)")]
    OutOfHostMemory,
    #[error("the device was lost (VK_ERROR_DEVICE_LOST: the GPU hung, faulted or was reset)")]
    DeviceLost,
    /// A request over one of the device's limits, refused before anything
    /// was made or allocated (`limits.rs`): names the resource and the limit.
    #[error("{0}")]
    OverLimit(String),
    #[error("memory allocation failed: {0}")]
    Allocation(#[from] gpu_allocator::AllocationError),
    #[error("{0} object(s) still held the Vulkan device at shutdown (leaked resources)")]
    Leaked(usize),
    #[error("Vulkan call failed: {0}")]
    Vulkan(vk::Result),
}

impl From<vk::Result> for VkError {
    fn from(r: vk::Result) -> Self {
        match r {
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => VkError::OutOfDeviceMemory,
            vk::Result::ERROR_OUT_OF_HOST_MEMORY => VkError::OutOfHostMemory,
            vk::Result::ERROR_DEVICE_LOST => VkError::DeviceLost,
            other => VkError::Vulkan(other),
        }
    }
}

pub type VkResult<T> = Result<T, VkError>;
