//! Small owned Vulkan objects the front ends need beside the frame slots
//! (`frame.rs`): binary semaphores and a command pool, each destroyed by
//! its `Drop` (the owner waits for the device first, as for every object).

use super::{Context, VkResult};
use ash::vk;
use std::sync::Arc;

/// Binary semaphores (the demo keeps one per swapchain image).
pub struct Semaphores {
    ctx: Arc<Context>,
    pub raw: Vec<vk::Semaphore>,
}

impl Semaphores {
    pub fn new(ctx: &Arc<Context>, count: usize) -> VkResult<Self> {
        let mut s = Semaphores {
            ctx: ctx.clone(),
            raw: Vec::with_capacity(count),
        };
        for _ in 0..count {
            // SAFETY: a plain binary semaphore on the live device; pushed at
            // once, so `Drop` destroys every one made so far on an error.
            let semaphore = unsafe {
                ctx.device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
            }?;
            s.raw.push(semaphore);
        }
        Ok(s)
    }
}

impl Drop for Semaphores {
    fn drop(&mut self) {
        for &s in &self.raw {
            // SAFETY: created by `new` on this device; no submission uses it now.
            unsafe { self.ctx.device.destroy_semaphore(s, None) };
        }
    }
}

/// A command pool on the context's queue family whose buffers can be reset
/// one by one (for a library that records its own blocking uploads).
pub struct CommandPool {
    ctx: Arc<Context>,
    pub raw: vk::CommandPool,
}

impl CommandPool {
    pub fn new(ctx: &Arc<Context>) -> VkResult<Self> {
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: a valid create info on the live device.
        let raw = unsafe { ctx.device.create_command_pool(&info, None) }?;
        Ok(CommandPool {
            ctx: ctx.clone(),
            raw,
        })
    }
}

impl Drop for CommandPool {
    fn drop(&mut self) {
        // SAFETY: created by `new` on this device; its buffers are done.
        unsafe { self.ctx.device.destroy_command_pool(self.raw, None) };
    }
}
