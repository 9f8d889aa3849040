//! Wyman's d_N (2005; Wyman 2006 §"Approximating Distance d_1"): per vertex
//! of a refractor, the distance from the vertex to the far side of the same
//! object along the inward normal -N. The image-space refraction of
//! `image_space` interpolates it across each triangle and blends it with
//! the view-direction thickness d_V by Eq. 6.3.1. Wyman precomputes it by
//! ray tracing and keeps it in the normal's w component; so do we
//! (`GpuTriangle::n0..n2` w).

use super::Bvh;
use crate::gpu::GpuTriangle;
use glam::Vec3;

/// Hits on other objects skipped before giving up (an object nested in
/// the refractor, or neighbours touching it).
const MAX_SKIPPED_HITS: usize = 64;
/// Fraction of the way from a vertex to its triangle's centroid where its
/// ray starts. On a sphere of radius r the ray then misses the centre by
/// `CENTROID_PULL` times the vertex-centroid distance s, which shortens d_N
/// by about s^2 CENTROID_PULL^2 / r (1e-8 r for s = r / 10): negligible.
const CENTROID_PULL: f32 = 1e-3;

impl Bvh {
    /// Writes d_N into the w component of every vertex normal of the
    /// triangles `is_refractor` accepts (given the material index), and 0
    /// into the others'. `tris` is the leaf-order array this tree indexes
    /// (`gpu_triangles`). The ray leaves the vertex (pulled a hair toward
    /// the triangle's centroid) displaced inward along -N by a
    /// scale-relative epsilon (so it does not hit the vertex's own
    /// triangles) and stops at the first hit on the same object (the object
    /// index in `p1.w`); d_N counts from the ray's start. Where it meets
    /// nothing of the object (an open surface, or a normal pointing out of
    /// a sliver), d_N = 0, which the shaders read as "unknown" and replace
    /// by d_V (Wyman's fallback when precomputation is impossible).
    pub fn set_normal_thickness(
        &self,
        tris: &mut [GpuTriangle],
        is_refractor: impl Fn(u32, u32) -> bool,
    ) {
        let thickness: Vec<[f32; 3]> = tris
            .iter()
            .map(|t| {
                let object = t.p1[3].to_bits();
                if !is_refractor(t.p0[3].to_bits(), object) {
                    return [0.0; 3];
                }
                let centroid = (v3(t.p0) + v3(t.p1) + v3(t.p2)) / 3.0;
                let corner = |p: [f32; 4], n: [f32; 4]| {
                    // Start a hair inside the triangle: a ray from the
                    // vertex itself runs along the edges of its neighbours
                    // and through the opposite vertex or edge on boxes and
                    // spheres (a pole), where rounding loses every hit.
                    let x = v3(p) + (centroid - v3(p)) * CENTROID_PULL;
                    self.thickness_along(tris, object, x, -v3(n).normalize_or_zero())
                };
                [corner(t.p0, t.n0), corner(t.p1, t.n1), corner(t.p2, t.n2)]
            })
            .collect();
        for (t, d) in tris.iter_mut().zip(thickness) {
            t.n0[3] = d[0];
            t.n1[3] = d[1];
            t.n2[3] = d[2];
        }
    }

    /// Distance from `x` along unit `dir` to the first surface of `object`
    /// past a small offset, or 0 when there is none.
    fn thickness_along(&self, tris: &[GpuTriangle], object: u32, x: Vec3, dir: Vec3) -> f32 {
        if dir == Vec3::ZERO {
            return 0.0;
        }
        let offset = 1e-4 * x.abs().max_element().max(1.0);
        let origin = x + dir * offset;
        let mut t_min = 0.0;
        for _ in 0..MAX_SKIPPED_HITS {
            let Some(hit) = self.intersect(tris, origin, dir, t_min, f32::MAX) else {
                return 0.0;
            };
            if tris[hit.triangle as usize].p1[3].to_bits() == object {
                return offset + hit.t;
            }
            t_min = hit.t;
        }
        0.0
    }
}

fn v3(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}
