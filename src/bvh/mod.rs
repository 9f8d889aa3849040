//! Bounding volume hierarchy over the scene's world-space triangles: a binned
//! SAH build on the CPU (`build`), bottom-up refit for animated geometry
//! (`refit`), the flat GPU layout (`GpuBvhNode`, `GpuTriangle` in leaf order),
//! and a CPU traversal (`intersect`, `occluded`) that mirrors
//! `glsl/common/bvh.glsl` step for step. See docs/BVH.md.
//!
//! Layout: node 0 is the root. An inner node has `count == 0` and stores the
//! index of its left child in `left_or_first`; the right child is `left + 1`.
//! A leaf has `count > 0` and stores the first index into the reordered
//! triangle array (`gpu_triangles`). Children are always stored after their
//! parent, so a reverse sweep over `nodes` visits children before parents.
//!
//! The empty tree (no triangles) is a single node with `count == 0` and
//! `left_or_first == 0` (an "inner node that is its own child", which no real
//! inner node can be since children start at index 1) and an inverted box
//! (min = +f32::MAX, max = -f32::MAX). Both traversals check that sentinel
//! first and report a miss.

mod build;
mod thickness;
mod traverse;

#[cfg(test)]
mod tests;

pub use build::{COST_INTERSECT, COST_TRAVERSAL, LEAF_SIZE, MAX_DEPTH, MAX_LEAF_SIZE, SAH_BINS};
pub use traverse::{intersect_triangle, Hit};

use crate::gpu::GpuBvhNode;
use crate::gpu::GpuTriangle;
use crate::scene::Triangle;

#[derive(Clone, Debug)]
pub struct Bvh {
    /// Flat node array, root first (see the module docs for the layout).
    pub nodes: Vec<GpuBvhNode>,
    /// Leaf order -> original triangle index: leaf position `i` holds
    /// `triangles[triangle_order[i]]` of the build input.
    pub triangle_order: Vec<u32>,
    /// Wall-clock time of `build`, milliseconds (`refit` leaves it unchanged).
    pub build_ms: f64,
    /// Longest root-to-leaf path in edges (root alone = 0); always `<= MAX_DEPTH`.
    pub depth: u32,
    /// Number of leaves (0 for the empty tree).
    pub leaf_count: usize,
}

impl Bvh {
    /// Binned SAH build; see `build.rs` in this module.
    pub fn build(triangles: &[Triangle]) -> Bvh {
        build::build(triangles)
    }

    /// True for the tree built from zero triangles (the sentinel root).
    pub fn is_empty(&self) -> bool {
        self.triangle_order.is_empty()
    }

    /// The triangles in leaf order, ready for the GPU triangle buffer.
    /// `triangles` must be the slice the tree was built (or refitted) from.
    pub fn gpu_triangles(&self, triangles: &[Triangle]) -> Vec<GpuTriangle> {
        assert_eq!(
            triangles.len(),
            self.triangle_order.len(),
            "gpu_triangles: triangle count differs from the build input"
        );
        self.triangle_order
            .iter()
            .map(|&i| GpuTriangle::new(&triangles[i as usize]))
            .collect()
    }

    /// Recomputes every node's bounds bottom-up for moved triangles. The
    /// topology is kept: `triangles` must have the same count and order as the
    /// build input. Quality degrades as triangles move far from where they
    /// were built; rebuild when traversal cost grows.
    pub fn refit(&mut self, triangles: &[Triangle]) {
        build::refit(self, triangles)
    }
}
