//! The demo's frame slots and per-swapchain-image semaphores.

use crate::vk::{Context, VkResult};
use ash::vk;
use std::sync::Arc;

/// One frame slot. Per GUIDE §7 it owns its fence, command pool and acquire
/// semaphore (render-finished semaphores are per swapchain image, in `State`).
pub(super) struct Frame {
    pub(super) ctx: Arc<Context>,
    pub(super) pool: vk::CommandPool,
    pub(super) cmd: vk::CommandBuffer,
    /// Signalled when this slot's presentation submission has finished.
    pub(super) fence: vk::Fence,
    /// Signalled by vkAcquireNextImageKHR; waited by this slot's submission.
    pub(super) acquired: vk::Semaphore,
}

impl Frame {
    pub(super) fn new(ctx: &Arc<Context>) -> VkResult<Frame> {
        let d = &ctx.device;
        unsafe {
            let pool = d.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(ctx.queue_family)
                    .flags(vk::CommandPoolCreateFlags::TRANSIENT),
                None,
            )?;
            // Owned from here on, so an error below destroys what was made
            // (Drop skips null handles' destruction: destroying null is a no-op).
            let mut frame = Frame {
                ctx: ctx.clone(),
                pool,
                cmd: vk::CommandBuffer::null(),
                fence: vk::Fence::null(),
                acquired: vk::Semaphore::null(),
            };
            frame.cmd = d.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1),
            )?[0];
            // Signalled, so the first wait on a fresh slot returns at once.
            frame.fence = d.create_fence(
                &vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED),
                None,
            )?;
            frame.acquired = d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?;
            Ok(frame)
        }
    }
}

impl Drop for Frame {
    fn drop(&mut self) {
        let d = &self.ctx.device;
        unsafe {
            d.destroy_semaphore(self.acquired, None);
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
        }
    }
}

/// Binary semaphores, one per swapchain image: a present waits on it, and it
/// is signalled again only after that image is re-acquired, which implies
/// the earlier present has consumed it.
pub(super) struct ImageSemaphores {
    pub(super) ctx: Arc<Context>,
    pub(super) raw: Vec<vk::Semaphore>,
}

impl ImageSemaphores {
    pub(super) fn new(ctx: &Arc<Context>, count: usize) -> VkResult<Self> {
        let mut s = ImageSemaphores {
            ctx: ctx.clone(),
            raw: Vec::new(),
        };
        for _ in 0..count {
            s.raw.push(unsafe {
                ctx.device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
            }?);
        }
        Ok(s)
    }
}

impl Drop for ImageSemaphores {
    fn drop(&mut self) {
        for s in &self.raw {
            unsafe { self.ctx.device.destroy_semaphore(*s, None) };
        }
    }
}
