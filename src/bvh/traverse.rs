//! CPU traversal: a line-for-line mirror of `glsl/common/bvh.glsl`, so tests
//! can cross-check the tree against brute force here and the lead can
//! cross-check GPU results against these. Keep the two files in step.
//!
//! Epsilon policy (both sides):
//! - Ray-triangle (Möller–Trumbore, two-sided): scale-free degeneracy test
//!   `|det| <= 1e-5 * maxabs(e1) * maxabs(pv)` is a miss (`pv = d x e2`, so
//!   `det / (|e1| |pv|)` is the cosine between e1 and pv: it vanishes for
//!   zero-area triangles and rays in the triangle's plane; the threshold sits
//!   above float rounding noise so degenerate triangles never report hits at
//!   garbage distances, and only rejects hits that graze a sliver at ~1e-5
//!   rad). Non-finite det is a miss; barycentric tests are written so that NaN
//!   fails them; edges are inclusive (u >= 0, v >= 0, u + v <= 1) so a ray
//!   through a shared edge finds at least one of the two triangles. A hit
//!   needs `0 < t < t_max`; the traversal additionally needs `t > t_min`
//!   (the caller's self-intersection offset, `t_min >= 0`).
//! - Ray-box (slab test): direction components with |d| < 1e-30 are replaced
//!   by ±1e-30 (sign of d, +0 and -0 both positive) before inverting, so the
//!   inverse is finite and `0 * inf = NaN` never occurs. The box's exit
//!   distance, after clamping to the current closest hit, is scaled by 1 + 2γ₃
//!   (Ize 2013, "Robust BVH ray traversal") so rounding never culls a box the
//!   ray touches, nor a box entered a few ulps beyond the closest hit (the
//!   triangle test's own t carries rounding error too).

use super::Bvh;
use crate::gpu::{GpuBvhNode, GpuTriangle};
use crate::shader_bindings::BVH_STACK_SIZE;
use glam::Vec3;

/// Closest hit: `triangle` indexes the leaf-order triangle array
/// (`Bvh::gpu_triangles`); `u`, `v` weight vertices 1 and 2 (vertex 0 gets 1 - u - v).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
    pub u: f32,
    pub v: f32,
}

/// Smallest direction magnitude used for the inverse direction.
pub const MIN_DIR_COMPONENT: f32 = 1e-30;
/// Relative determinant threshold of the ray-triangle test (see module docs).
pub const DET_EPSILON: f32 = 1e-5;
/// At least 1 + 2γ₃ (γₙ = nε / (1 - nε), ε = 2⁻²⁴, so 2γ₃ ≈ 3.58e-7),
/// rounded up to the next float: 1 + 4 · 2⁻²³ = 1.00000048.
pub const BOX_EXIT_SCALE: f32 = 1.0 + 4.0 * f32::EPSILON;

#[inline]
fn v3(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

#[inline]
fn max_abs(v: Vec3) -> f32 {
    v.x.abs().max(v.y.abs()).max(v.z.abs())
}

/// Möller–Trumbore (1997), two-sided. Returns (t, u, v) for `0 < t < t_max`.
/// The negated comparisons are deliberate: NaN fails every test (a miss).
#[inline]
#[allow(clippy::neg_cmp_op_on_partial_ord, clippy::manual_range_contains)]
pub fn intersect_triangle(
    tri: &GpuTriangle,
    o: Vec3,
    d: Vec3,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    let p0 = v3(tri.p0);
    let e1 = v3(tri.p1) - p0;
    let e2 = v3(tri.p2) - p0;
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if !(det.abs() > DET_EPSILON * max_abs(e1) * max_abs(pv)) || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let tv = o - p0;
    let u = tv.dot(pv) * inv_det;
    if !(u >= 0.0 && u <= 1.0) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = d.dot(qv) * inv_det;
    if !(v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    let t = e2.dot(qv) * inv_det;
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    Some((t, u, v))
}

/// 1 / d with tiny components clamped to ±MIN_DIR_COMPONENT (see module docs).
#[inline]
pub(crate) fn safe_inverse(d: Vec3) -> Vec3 {
    let f = |x: f32| {
        let x = if x.abs() < MIN_DIR_COMPONENT {
            if x < 0.0 {
                -MIN_DIR_COMPONENT
            } else {
                MIN_DIR_COMPONENT
            }
        } else {
            x
        };
        1.0 / x
    };
    Vec3::new(f(d.x), f(d.y), f(d.z))
}

/// Slab test: entry distance if the ray overlaps the box within [t_min, t_max].
#[inline]
fn ray_box(n: &GpuBvhNode, o: Vec3, inv_d: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
    let t0 = (Vec3::from(n.bounds_min) - o) * inv_d;
    let t1 = (Vec3::from(n.bounds_max) - o) * inv_d;
    let tn = t0.min(t1);
    let tf = t0.max(t1);
    let t_near = tn.x.max(tn.y).max(tn.z.max(t_min));
    let t_far = tf.x.min(tf.y).min(tf.z).min(t_max) * BOX_EXIT_SCALE;
    if t_near <= t_far {
        Some(t_near)
    } else {
        None
    }
}

impl Bvh {
    /// True for the empty-tree sentinel root (count 0, left child 0).
    #[inline]
    fn root_is_sentinel(&self) -> bool {
        self.nodes[0].count == 0 && self.nodes[0].left_or_first == 0
    }

    /// Closest hit with `t_min < t < t_max` against `triangles` in leaf order
    /// (`self.gpu_triangles(..)`). Same traversal as GLSL `trace_closest`.
    pub fn intersect(
        &self,
        triangles: &[GpuTriangle],
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<Hit> {
        self.traverse(triangles, origin, dir, t_min, t_max, false)
    }

    /// True if anything lies on the ray with `t_min < t < t_max` (GLSL `trace_any`).
    pub fn occluded(
        &self,
        triangles: &[GpuTriangle],
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        self.traverse(triangles, origin, dir, t_min, t_max, true)
            .is_some()
    }

    fn traverse(
        &self,
        tris: &[GpuTriangle],
        o: Vec3,
        d: Vec3,
        t_min: f32,
        t_max: f32,
        any: bool,
    ) -> Option<Hit> {
        if self.root_is_sentinel() {
            return None;
        }
        let inv_d = safe_inverse(d);
        ray_box(&self.nodes[0], o, inv_d, t_min, t_max)?;
        let mut closest = t_max;
        let mut best = None;
        let mut stack = [0u32; BVH_STACK_SIZE as usize];
        let mut sp = 0usize;
        let mut node = 0u32;
        // While-while (Aila & Laine 2009): down the inner nodes to a leaf,
        // then its triangles, then the next node off the stack.
        'rays: loop {
            let mut n = &self.nodes[node as usize];
            while n.count == 0 {
                let l = n.left_or_first;
                let r = l + 1;
                let hl = ray_box(&self.nodes[l as usize], o, inv_d, t_min, closest);
                let hr = ray_box(&self.nodes[r as usize], o, inv_d, t_min, closest);
                match (hl, hr) {
                    (Some(dl), Some(dr)) => {
                        let (near, far) = if dl <= dr { (l, r) } else { (r, l) };
                        stack[sp] = far;
                        sp += 1;
                        node = near;
                    }
                    (Some(_), None) => node = l,
                    (None, Some(_)) => node = r,
                    (None, None) => {
                        if sp == 0 {
                            break 'rays;
                        }
                        sp -= 1;
                        node = stack[sp];
                    }
                }
                n = &self.nodes[node as usize];
            }
            for i in n.left_or_first..n.left_or_first + n.count {
                if let Some((t, u, v)) = intersect_triangle(&tris[i as usize], o, d, closest) {
                    if t > t_min {
                        closest = t;
                        best = Some(Hit {
                            t,
                            triangle: i,
                            u,
                            v,
                        });
                        if any {
                            return best;
                        }
                    }
                }
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            node = stack[sp];
        }
        best
    }
}
