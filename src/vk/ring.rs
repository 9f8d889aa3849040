//! A frame's upload ring: host-visible memory the host writes that frame's
//! data into (and the frame copies its timestamps into), reset once the
//! frame's fence has signalled (`vk/frame.rs`).

use super::{Buffer, BufferUsage, Context, VkResult};
use ash::vk;
use std::sync::Arc;

/// Host-visible chunks the host writes a frame's data into; reset once the
/// frame's fence has signalled. Grows by adding a chunk; the chunks are
/// merged into one at the next reset (the GPU is done with them then).
pub(super) struct Ring {
    chunks: Vec<Buffer>,
    used: u64,
}

const RING_ALIGN: u64 = 256;
const RING_MIN: u64 = 64 * 1024;

impl Ring {
    pub(super) fn new() -> Ring {
        Ring {
            chunks: Vec::new(),
            used: 0,
        }
    }

    /// `len` bytes at `offset` of chunk `chunk`, once the GPU is done with it.
    pub(super) fn read(&self, chunk: usize, offset: u64, len: usize) -> Vec<u8> {
        self.chunks[chunk].read_at(offset, len)
    }

    /// Frees the chunks (the slot is being destroyed, its frame done).
    pub(super) fn clear(&mut self) {
        self.chunks.clear();
    }

    /// Copies `bytes` into the ring; returns the chunk's index, its buffer and the offset.
    pub(super) fn alloc(
        &mut self,
        ctx: &Arc<Context>,
        bytes: &[u8],
    ) -> VkResult<(usize, vk::Buffer, u64)> {
        let size = bytes.len() as u64;
        let offset = self.used.next_multiple_of(RING_ALIGN);
        let fits = self.chunks.last().is_some_and(|c| offset + size <= c.size);
        let offset = if fits {
            offset
        } else {
            let last = self.chunks.last().map_or(0, |c| c.size);
            let capacity = size.max(2 * last).max(RING_MIN);
            self.chunks.push(Buffer::new(
                ctx,
                "upload ring",
                capacity,
                BufferUsage::Upload,
            )?);
            0
        };
        let chunk = self.chunks.last().expect("a chunk");
        chunk.write_at(offset, bytes);
        self.used = offset + size;
        Ok((self.chunks.len() - 1, chunk.raw, offset))
    }

    pub(super) fn reset(&mut self, ctx: &Arc<Context>) -> VkResult<()> {
        if self.chunks.len() > 1 {
            let total: u64 = self.chunks.iter().map(|c| c.size).sum();
            self.chunks.clear();
            self.chunks
                .push(Buffer::new(ctx, "upload ring", total, BufferUsage::Upload)?);
        }
        self.used = 0;
        Ok(())
    }
}
