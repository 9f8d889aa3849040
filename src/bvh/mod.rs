//! TEMPORARY stand-in (one leaf holding every triangle) until the SAH builder lands.
use crate::gpu::{GpuBvhNode, GpuTriangle};
use crate::scene::Triangle;
pub struct Bvh {
    pub nodes: Vec<GpuBvhNode>,
    pub triangle_order: Vec<u32>,
    pub build_ms: f64,
    pub depth: u32,
    pub leaf_count: usize,
}
pub fn build(t: &[Triangle]) -> Bvh {
    Bvh {
        nodes: vec![GpuBvhNode {
            bounds_min: [-1e30; 3],
            left_or_first: 0,
            bounds_max: [1e30; 3],
            count: t.len() as u32,
        }],
        triangle_order: (0..t.len() as u32).collect(),
        build_ms: 0.0,
        depth: 1,
        leaf_count: 1,
    }
}
impl Bvh {
    pub fn gpu_triangles(&self, t: &[Triangle]) -> Vec<GpuTriangle> {
        self.triangle_order
            .iter()
            .map(|&i| GpuTriangle::new(&t[i as usize]))
            .collect()
    }
    pub fn refit(&mut self, _: &[Triangle]) {}
}
