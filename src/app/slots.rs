//! The demo's per-swapchain-image semaphores. (Its frame slots are the
//! renderer's `vk::Frames`: fence, command buffer and acquire semaphore.)

use crate::vk::{Context, VkResult};
use ash::vk;
use std::sync::Arc;

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
