//! Binned SAH construction and refit.
//!
//! Cost model: the surface area heuristic (MacDonald & Booth 1990, "Heuristics
//! for ray tracing using space subdivision"): a split of node P into L and R
//! costs `C_trav + C_isect * (A(L) N(L) + A(R) N(R)) / A(P)`, a leaf costs
//! `C_isect * N(P)`. Candidate planes are the boundaries of `SAH_BINS` equal
//! bins over the centroid bounds on their widest axis (binned building after
//! Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"),
//! so each node costs O(N) (bin, sweep, partition) and the build O(N log N).
//!
//! Depth guarantee: the builder keeps the invariant
//! `depth + ceil(log2(count)) <= MAX_DEPTH` for every node. Where a SAH split
//! could break it (`depth + ceil(log2(count)) >= MAX_DEPTH`) the node is split
//! at the median centroid instead, which halves the count and so keeps it;
//! a SAH split has both sides non-empty, so each child has at most `count - 1`
//! triangles and one more level, which keeps it too. At the root the invariant
//! holds for any count below 2^MAX_DEPTH, hence `depth <= MAX_DEPTH` for all
//! leaves and a traversal stack of `BVH_STACK_SIZE = MAX_DEPTH + 1` entries
//! never overflows.

use super::Bvh;
use crate::gpu::GpuBvhNode;
use crate::scene::Triangle;
use crate::shader_bindings::BVH_STACK_SIZE;
use glam::Vec3;
use std::time::Instant;

/// Number of SAH bins on the chosen axis.
pub const SAH_BINS: usize = 16;
/// SAH cost of visiting an inner node (relative to one triangle test).
pub const COST_TRAVERSAL: f32 = 1.0;
/// SAH cost of one ray-triangle test.
pub const COST_INTERSECT: f32 = 1.0;
/// Nodes with at most this many triangles always become leaves.
pub const LEAF_SIZE: usize = 4;
/// Nodes with more triangles than this are always split, even where the SAH
/// prefers a leaf (keeps per-leaf work on the GPU bounded).
pub const MAX_LEAF_SIZE: usize = 16;
/// Deepest leaf allowed (root = depth 0): the GLSL stack holds one entry per level.
pub const MAX_DEPTH: u32 = BVH_STACK_SIZE - 1;

#[derive(Clone, Copy, Debug)]
pub(crate) struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn of_triangle(p: &[Vec3; 3]) -> Aabb {
        Aabb {
            min: p[0].min(p[1]).min(p[2]),
            max: p[0].max(p[1]).max(p[2]),
        }
    }

    pub fn grow(&mut self, o: &Aabb) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }

    pub fn grow_point(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Surface area; 0 for an empty box.
    pub fn area(&self) -> f32 {
        let d = self.max - self.min;
        if d.x < 0.0 || d.y < 0.0 || d.z < 0.0 {
            return 0.0;
        }
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
}

struct Task {
    node: usize,
    first: usize,
    count: usize,
    depth: u32,
}

fn ceil_log2(n: usize) -> u32 {
    if n <= 1 {
        0
    } else {
        usize::BITS - (n - 1).leading_zeros()
    }
}

fn empty_tree(start: Instant) -> Bvh {
    let root = GpuBvhNode {
        bounds_min: [f32::MAX; 3],
        left_or_first: 0,
        bounds_max: [-f32::MAX; 3],
        count: 0,
    };
    Bvh {
        nodes: vec![root],
        triangle_order: Vec::new(),
        build_ms: elapsed_ms(start),
        depth: 0,
        leaf_count: 0,
    }
}

fn elapsed_ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// Per-triangle data the builder works on, indexed by original triangle index.
struct Prims {
    boxes: Vec<Aabb>,
    centroids: Vec<Vec3>,
}

pub(crate) fn build(triangles: &[Triangle]) -> Bvh {
    build_with_max_depth(triangles, MAX_DEPTH)
}

/// `build` with another depth limit (tests use it to exercise the median
/// fallback and to measure unconstrained SAH depth). Needs
/// `max_depth >= ceil(log2(triangles.len()))`.
pub(crate) fn build_with_max_depth(triangles: &[Triangle], max_depth: u32) -> Bvh {
    let start = Instant::now();
    let n = triangles.len();
    if n == 0 {
        return empty_tree(start);
    }
    assert!(n < u32::MAX as usize, "BVH: too many triangles ({n})");
    assert!(
        max_depth >= ceil_log2(n),
        "BVH: depth limit {max_depth} below log2 of {n} triangles"
    );
    let boxes: Vec<Aabb> = triangles
        .iter()
        .map(|t| Aabb::of_triangle(&t.positions))
        .collect();
    // The centroid of the triangle's box (not the vertex mean): the usual binning key.
    let centroids = boxes.iter().map(|b| (b.min + b.max) * 0.5).collect();
    let prims = Prims { boxes, centroids };

    let mut order: Vec<u32> = (0..n as u32).collect();
    let mut nodes: Vec<GpuBvhNode> = Vec::with_capacity(2 * n.div_ceil(LEAF_SIZE).max(1));
    nodes.push(GpuBvhNode::zeroed_node());
    let mut depth = 0;
    let mut leaf_count = 0;
    // Explicit work stack: no recursion, so adversarial inputs cannot overflow the thread stack.
    let mut tasks = vec![Task {
        node: 0,
        first: 0,
        count: n,
        depth: 0,
    }];
    while let Some(task) = tasks.pop() {
        let slice = &mut order[task.first..task.first + task.count];
        let mut bounds = Aabb::EMPTY;
        let mut cbounds = Aabb::EMPTY;
        for &i in slice.iter() {
            bounds.grow(&prims.boxes[i as usize]);
            cbounds.grow_point(prims.centroids[i as usize]);
        }
        depth = depth.max(task.depth);
        let split = if task.count <= LEAF_SIZE {
            None
        } else {
            choose_split(slice, &prims, &bounds, &cbounds, task.depth, max_depth)
        };
        let node = &mut nodes[task.node];
        node.bounds_min = bounds.min.to_array();
        node.bounds_max = bounds.max.to_array();
        match split {
            None => {
                node.left_or_first = task.first as u32;
                node.count = task.count as u32;
                leaf_count += 1;
            }
            Some(left_count) => {
                let left = nodes.len();
                nodes[task.node].left_or_first = left as u32;
                nodes[task.node].count = 0;
                nodes.push(GpuBvhNode::zeroed_node());
                nodes.push(GpuBvhNode::zeroed_node());
                let d = task.depth + 1;
                tasks.push(Task {
                    node: left + 1,
                    first: task.first + left_count,
                    count: task.count - left_count,
                    depth: d,
                });
                tasks.push(Task {
                    node: left,
                    first: task.first,
                    count: left_count,
                    depth: d,
                });
            }
        }
    }
    debug_assert!(depth <= max_depth);
    Bvh {
        nodes,
        triangle_order: order,
        build_ms: elapsed_ms(start),
        depth,
        leaf_count,
    }
}

trait Zeroed {
    fn zeroed_node() -> Self;
}
impl Zeroed for GpuBvhNode {
    fn zeroed_node() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

/// Bin of a centroid coordinate; binning and partitioning must use the same function.
#[inline]
fn bin_of(c: f32, cmin: f32, scale: f32) -> usize {
    // `as usize` saturates (and maps NaN to 0), so every value lands in a valid bin.
    (((c - cmin) * scale) as usize).min(SAH_BINS - 1)
}

/// Decides how to split `slice` (the node's triangles): `None` makes a leaf,
/// `Some(k)` means the slice has been reordered so its first `k` triangles
/// form the left child (`0 < k < len`).
fn choose_split(
    slice: &mut [u32],
    prims: &Prims,
    bounds: &Aabb,
    cbounds: &Aabb,
    depth: u32,
    max_depth: u32,
) -> Option<usize> {
    let count = slice.len();
    let extent = cbounds.max - cbounds.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let cmin = cbounds.min[axis];
    let ext = extent[axis];
    if ext.is_nan() || ext <= 0.0 {
        // All centroids equal (or non-finite input): no plane separates them; split by count.
        return Some(count / 2);
    }
    if depth.saturating_add(ceil_log2(count)) >= max_depth {
        return Some(median_split(slice, prims, axis));
    }

    // Wald 2007: bin the centroids, then sweep the bin boundaries from both sides.
    let scale = SAH_BINS as f32 / ext;
    let mut bin_bounds = [Aabb::EMPTY; SAH_BINS];
    let mut bin_count = [0usize; SAH_BINS];
    for &i in slice.iter() {
        let b = bin_of(prims.centroids[i as usize][axis], cmin, scale);
        bin_bounds[b].grow(&prims.boxes[i as usize]);
        bin_count[b] += 1;
    }
    // right_area[p] / right_count[p]: bins p.. (right of plane p, planes 1..SAH_BINS-1).
    let mut right_area = [0.0f32; SAH_BINS];
    let mut right_count = [0usize; SAH_BINS];
    let mut acc = Aabb::EMPTY;
    let mut acc_n = 0;
    for p in (1..SAH_BINS).rev() {
        acc.grow(&bin_bounds[p]);
        acc_n += bin_count[p];
        right_area[p] = acc.area();
        right_count[p] = acc_n;
    }
    // SAH costs multiplied by A(P) so that flat or zero-area nodes need no division.
    let mut best_plane = 0;
    let mut best_cost = f32::INFINITY;
    let mut acc = Aabb::EMPTY;
    let mut acc_n = 0;
    for p in 1..SAH_BINS {
        acc.grow(&bin_bounds[p - 1]);
        acc_n += bin_count[p - 1];
        if acc_n == 0 || right_count[p] == 0 {
            continue;
        }
        let cost =
            COST_INTERSECT * (acc.area() * acc_n as f32 + right_area[p] * right_count[p] as f32);
        if cost < best_cost {
            best_cost = cost;
            best_plane = p;
        }
    }
    if best_plane == 0 {
        // Cannot happen for a positive extent (the extreme centroids fall in bins 0 and
        // SAH_BINS - 1), kept as a safe fallback.
        return Some(median_split(slice, prims, axis));
    }
    let parent_area = bounds.area();
    let split_cost = COST_TRAVERSAL * parent_area + best_cost;
    let leaf_cost = COST_INTERSECT * count as f32 * parent_area;
    if split_cost >= leaf_cost && count <= MAX_LEAF_SIZE {
        return None;
    }

    // In-place partition: bins below best_plane go left.
    let (mut lo, mut hi) = (0usize, count);
    while lo < hi {
        if bin_of(prims.centroids[slice[lo] as usize][axis], cmin, scale) < best_plane {
            lo += 1;
        } else {
            hi -= 1;
            slice.swap(lo, hi);
        }
    }
    if lo == 0 || lo == count {
        return Some(median_split(slice, prims, axis));
    }
    Some(lo)
}

/// Object median along `axis`: reorders `slice` so its lower half holds the
/// smaller centroids (O(N) selection, no full sort) and returns len / 2.
fn median_split(slice: &mut [u32], prims: &Prims, axis: usize) -> usize {
    let mid = slice.len() / 2;
    slice.select_nth_unstable_by(mid, |&a, &b| {
        prims.centroids[a as usize][axis].total_cmp(&prims.centroids[b as usize][axis])
    });
    mid
}

pub(crate) fn refit(bvh: &mut Bvh, triangles: &[Triangle]) {
    assert_eq!(
        triangles.len(),
        bvh.triangle_order.len(),
        "refit: triangle count differs from the build input"
    );
    if bvh.is_empty() {
        return;
    }
    // Children are stored after their parents, so a reverse sweep is bottom-up.
    for i in (0..bvh.nodes.len()).rev() {
        let node = bvh.nodes[i];
        let mut b = Aabb::EMPTY;
        if node.count > 0 {
            let first = node.left_or_first as usize;
            for &t in &bvh.triangle_order[first..first + node.count as usize] {
                b.grow(&Aabb::of_triangle(&triangles[t as usize].positions));
            }
        } else {
            for c in [node.left_or_first as usize, node.left_or_first as usize + 1] {
                let child = &bvh.nodes[c];
                b.grow(&Aabb {
                    min: Vec3::from(child.bounds_min),
                    max: Vec3::from(child.bounds_max),
                });
            }
        }
        bvh.nodes[i].bounds_min = b.min.to_array();
        bvh.nodes[i].bounds_max = b.max.to_array();
    }
}
