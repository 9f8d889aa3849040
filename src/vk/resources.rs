//! Buffers backed by gpu-allocator, and the allocation they share with
//! images (`image.rs`). Each owns its allocation and returns it (and
//! destroys the Vulkan handle) on `Drop`; see the lifetime note in
//! `vk/mod.rs`.

use super::sync::ResourceState;
use super::{fault, limits, Context, VkResult};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::cell::Cell;
use std::sync::Arc;

/// Allocates memory for a buffer or image after checking that its heap can
/// hold it (`limits.rs`: on lavapipe an allocation beyond memory meets the
/// OOM killer, not an error code), and accounts for it there.
pub(super) fn allocate(
    ctx: &Context,
    name: &str,
    requirements: vk::MemoryRequirements,
    location: MemoryLocation,
    linear: bool,
) -> VkResult<Allocation> {
    ctx.memory.check(name, &requirements, location)?;
    fault::allocation()?;
    let allocation = ctx.allocator().allocate(&AllocationCreateDesc {
        name,
        requirements,
        location,
        linear,
        allocation_scheme: AllocationScheme::GpuAllocatorManaged,
    })?;
    ctx.memory
        .allocated(allocation.memory_properties(), allocation.size());
    Ok(allocation)
}

/// Returns an allocation made by `allocate`.
pub(super) fn free(ctx: &Context, allocation: Allocation) {
    ctx.memory
        .freed(allocation.memory_properties(), allocation.size());
    let _ = ctx.allocator().free(allocation);
}

/// What a buffer is for, which decides its usage flags and memory location.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferUsage {
    /// Device-local storage buffer, filled by upload or by shaders.
    Storage,
    /// Device-local storage buffer that is also read as indirect-draw arguments.
    StorageIndirect,
    /// Device-local uniform buffer, written per frame through
    /// `FrameRecorder::upload` (the frame's ring and a copy).
    Uniform,
    /// Host-visible buffer the GPU copies into for the CPU to read.
    Readback,
    /// Host-visible staging buffer the CPU writes for the GPU to copy from
    /// (and the upload ring, which the GPU also copies timestamps into).
    Upload,
}

pub struct Buffer {
    ctx: Arc<Context>,
    pub raw: vk::Buffer,
    pub size: u64,
    pub usage: BufferUsage,
    pub(super) state: Cell<ResourceState>,
    /// Unique for the process's lifetime (handles may be reused after a
    /// destroy): what a descriptor set remembers it points at.
    pub(super) id: u64,
    /// Whether the buffer was ever bound into a descriptor set or declared
    /// by a pass: from then on frames may read it.
    pub(super) bound: Cell<bool>,
    allocation: Option<Allocation>,
}

/// The next resource id (`Buffer::id`, `Image::id`).
pub(super) fn next_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl Buffer {
    pub fn new(ctx: &Arc<Context>, name: &str, size: u64, usage: BufferUsage) -> VkResult<Buffer> {
        let size = size.max(16);
        let transfer = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
        let (flags, location) = match usage {
            BufferUsage::Storage => (
                vk::BufferUsageFlags::STORAGE_BUFFER | transfer,
                MemoryLocation::GpuOnly,
            ),
            BufferUsage::StorageIndirect => (
                vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::INDIRECT_BUFFER
                    | transfer,
                MemoryLocation::GpuOnly,
            ),
            BufferUsage::Uniform => (
                vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
            ),
            BufferUsage::Readback => (vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu),
            // Also a copy destination: frames copy their timestamps into the ring.
            BufferUsage::Upload => (transfer, MemoryLocation::CpuToGpu),
        };
        if flags.contains(vk::BufferUsageFlags::STORAGE_BUFFER) {
            limits::check_storage_buffer(&ctx.limits, name, size)?;
        }
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(flags)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { ctx.device.create_buffer(&info, None) }?;
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let allocation = match allocate(ctx, name, requirements, location, true) {
            Ok(a) => a,
            Err(e) => {
                unsafe { ctx.device.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        unsafe {
            ctx.device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        }?;
        ctx.set_name(raw, name);
        Ok(Buffer {
            ctx: ctx.clone(),
            raw,
            size,
            usage,
            state: Cell::new(ResourceState::default()),
            id: next_id(),
            bound: Cell::new(false),
            allocation: Some(allocation),
        })
    }

    /// A device-local storage buffer holding `data`, uploaded through a staging buffer.
    pub fn with_data<T: bytemuck::Pod>(
        ctx: &Arc<Context>,
        name: &str,
        data: &[T],
        usage: BufferUsage,
    ) -> VkResult<Buffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let buffer = Buffer::new(ctx, name, bytes.len() as u64, usage)?;
        buffer.upload(bytes)?;
        Ok(buffer)
    }

    /// Copies `bytes` to the start of the buffer: directly when host-visible,
    /// else through a staging buffer and a blocking submission. Only while
    /// no frame that may read it is in flight: a buffer frames use is
    /// written for a frame through `FrameRecorder::upload` (its ring).
    pub fn upload(&self, bytes: &[u8]) -> VkResult<()> {
        if bytes.is_empty() {
            return Ok(());
        }
        let pending = self
            .ctx
            .frames_pending
            .load(std::sync::atomic::Ordering::Relaxed);
        assert!(
            !(self.bound.get() && pending > 0),
            "Buffer::upload of a buffer frames use while {pending} frame(s) are in flight: \
             write it through FrameRecorder::upload (the frame's upload ring), or wait for the frames"
        );
        if let Some(dst) = self.mapped() {
            // SAFETY: the mapping is at least `size` bytes and host-coherent (gpu-allocator CpuToGpu).
            unsafe {
                std::ptr::copy_nonoverlapping(
                    bytes.as_ptr(),
                    dst,
                    bytes.len().min(self.size as usize),
                )
            };
            return Ok(());
        }
        let staging = Buffer::new(
            &self.ctx,
            "staging",
            bytes.len() as u64,
            BufferUsage::Upload,
        )?;
        staging.upload(bytes)?;
        self.ctx.submit_and_wait(|cmd| unsafe {
            let region = vk::BufferCopy::default().size(bytes.len() as u64);
            self.ctx
                .device
                .cmd_copy_buffer(cmd, staging.raw, self.raw, &[region]);
            // A fence makes device writes visible to the host only; later
            // submissions read this buffer in shaders, indirect arguments or
            // copies, so make the copy available and visible to them all.
            let visible = vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COPY)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE);
            self.ctx.device.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().memory_barriers(&[visible]),
            );
        })?;
        Ok(())
    }

    /// Writes `bytes` at `offset` of a host-visible buffer (the upload ring;
    /// the caller knows the GPU is not reading that range).
    pub(super) fn write_at(&self, offset: u64, bytes: &[u8]) {
        let dst = self.mapped().expect("a host-visible buffer");
        assert!(offset + bytes.len() as u64 <= self.size);
        // SAFETY: in bounds (asserted) and host-coherent (gpu-allocator CpuToGpu).
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), dst.add(offset as usize), bytes.len())
        };
    }

    /// Reads `len` bytes at `offset` of a host-visible buffer (the upload
    /// ring; the caller has waited for the GPU's writes there).
    pub(super) fn read_at(&self, offset: u64, len: usize) -> Vec<u8> {
        let src = self.mapped().expect("a host-visible buffer");
        assert!(offset + len as u64 <= self.size);
        let mut out = vec![0u8; len];
        // SAFETY: in bounds (asserted); host-coherent memory.
        unsafe { std::ptr::copy_nonoverlapping(src.add(offset as usize), out.as_mut_ptr(), len) };
        out
    }

    /// Reads the whole buffer back to the host (blocking).
    pub fn download(&self) -> VkResult<Vec<u8>> {
        if let Some(src) = self.mapped() {
            let mut out = vec![0u8; self.size as usize];
            // SAFETY: mapping covers `size` bytes; the caller has waited for the writes.
            unsafe { std::ptr::copy_nonoverlapping(src, out.as_mut_ptr(), out.len()) };
            return Ok(out);
        }
        let readback = Buffer::new(&self.ctx, "readback", self.size, BufferUsage::Readback)?;
        self.ctx.submit_and_wait(|cmd| unsafe {
            let before = vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::COPY)
                .dst_access_mask(vk::AccessFlags2::TRANSFER_READ);
            let after = vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COPY)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                .dst_access_mask(vk::AccessFlags2::HOST_READ);
            self.ctx.device.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().memory_barriers(&[before]),
            );
            let region = vk::BufferCopy::default().size(self.size);
            self.ctx
                .device
                .cmd_copy_buffer(cmd, self.raw, readback.raw, &[region]);
            self.ctx.device.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().memory_barriers(&[after]),
            );
        })?;
        readback.download()
    }

    pub fn download_pod<T: bytemuck::Pod>(&self) -> VkResult<Vec<T>> {
        let bytes = self.download()?;
        Ok(bytemuck::pod_collect_to_vec(
            &bytes[..bytes.len() / std::mem::size_of::<T>() * std::mem::size_of::<T>()],
        ))
    }

    fn mapped(&self) -> Option<*mut u8> {
        self.allocation
            .as_ref()?
            .mapped_ptr()
            .map(|p| p.as_ptr() as *mut u8)
    }

    pub fn descriptor_info(&self) -> vk::DescriptorBufferInfo {
        vk::DescriptorBufferInfo::default()
            .buffer(self.raw)
            .offset(0)
            .range(vk::WHOLE_SIZE)
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            free(&self.ctx, a);
        }
        unsafe { self.ctx.device.destroy_buffer(self.raw, None) };
    }
}
