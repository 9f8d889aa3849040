//! The demo's per-swapchain-image semaphores. (Its frame slots are the
//! renderer's `vk::Frames`: fence, command buffer and acquire semaphore.)

/// Binary semaphores, one per swapchain image: a present waits on it, and it
/// is signalled again only after that image is re-acquired, which implies
/// the earlier present has consumed it.
pub(super) type ImageSemaphores = crate::vk::Semaphores;
