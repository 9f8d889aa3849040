//! BVH invariants and CPU traversal against brute force. (Over 600 lines:
//! unit tests only, one per invariant, kept beside the code they test.)

use super::*;
use crate::gpu::GpuTriangle;
use glam::{Mat3, Vec3};
use std::time::Instant;

/// xorshift64*: deterministic, dependency-free randomness for tests.
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    /// Uniform in [0, 1).
    fn f(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }
    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
    fn dir(&mut self) -> Vec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

fn tri(a: Vec3, b: Vec3, c: Vec3) -> Triangle {
    let n = (b - a).cross(c - a).normalize_or_zero();
    Triangle {
        positions: [a, b, c],
        normals: [n; 3],
        uvs: [glam::Vec2::ZERO; 3],
        material: 0,
        object: 0,
    }
}

fn soup(n: usize, seed: u64) -> Vec<Triangle> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| {
            let c = rng.vec(-10.0, 10.0);
            let s = rng.range(0.05, 1.0);
            tri(c + rng.vec(-s, s), c + rng.vec(-s, s), c + rng.vec(-s, s))
        })
        .collect()
}

fn sphere(center: Vec3, radius: f32, rings: usize, segments: usize) -> Vec<Triangle> {
    let p = |i: usize, j: usize| {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        let ph = std::f32::consts::TAU * (j % segments) as f32 / segments as f32;
        // Exact poles, and the seam shares its vertices: a closed mesh.
        let (st, ct) = match i {
            0 => (0.0, 1.0),
            i if i == rings => (0.0, -1.0),
            _ => (th.sin(), th.cos()),
        };
        center + radius * Vec3::new(st * ph.cos(), ct, st * ph.sin())
    };
    let mut out = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            // The first ring's `d` and the last ring's `b`, `c` are the poles.
            if i != rings - 1 {
                out.push(tri(a, c, b));
            }
            if i != 0 {
                out.push(tri(a, d, c));
            }
        }
    }
    out
}

fn contains(outer_min: [f32; 3], outer_max: [f32; 3], p: Vec3) -> bool {
    (0..3).all(|k| outer_min[k] <= p[k] && p[k] <= outer_max[k])
}

/// Checks every structural invariant; returns nothing, panics with a reason.
fn check_tree(bvh: &Bvh, triangles: &[Triangle]) {
    let n = triangles.len();
    assert_eq!(bvh.triangle_order.len(), n);
    let mut seen = vec![false; n];
    for &t in &bvh.triangle_order {
        assert!(!seen[t as usize], "triangle {t} appears twice");
        seen[t as usize] = true;
    }
    if n == 0 {
        assert_eq!(bvh.nodes.len(), 1);
        assert_eq!((bvh.nodes[0].count, bvh.nodes[0].left_or_first), (0, 0));
        return;
    }
    let mut visited = vec![false; bvh.nodes.len()];
    let mut covered = vec![false; n];
    let mut leaves = 0;
    let mut max_depth = 0;
    let mut stack = vec![(0usize, 0u32)];
    while let Some((i, depth)) = stack.pop() {
        assert!(!visited[i], "node {i} reached twice");
        visited[i] = true;
        max_depth = max_depth.max(depth);
        let node = bvh.nodes[i];
        if node.count > 0 {
            leaves += 1;
            let first = node.left_or_first as usize;
            for (k, slot) in covered
                .iter_mut()
                .enumerate()
                .skip(first)
                .take(node.count as usize)
            {
                assert!(!*slot, "leaf slot {k} in two leaves");
                *slot = true;
                for p in triangles[bvh.triangle_order[k] as usize].positions {
                    assert!(
                        contains(node.bounds_min, node.bounds_max, p),
                        "node {i} does not contain a vertex of its triangle"
                    );
                }
            }
        } else {
            let l = node.left_or_first as usize;
            assert!(
                l > i && l + 1 < bvh.nodes.len(),
                "bad child index {l} of node {i}"
            );
            for c in [l, l + 1] {
                let ch = bvh.nodes[c];
                assert!(
                    contains(node.bounds_min, node.bounds_max, Vec3::from(ch.bounds_min)),
                    "node {i} does not contain child {c}"
                );
                assert!(
                    contains(node.bounds_min, node.bounds_max, Vec3::from(ch.bounds_max)),
                    "node {i} does not contain child {c}"
                );
                stack.push((c, depth + 1));
            }
        }
    }
    assert!(visited.iter().all(|&v| v), "unreachable nodes");
    assert!(covered.iter().all(|&c| c), "leaf slots not covered");
    assert_eq!(leaves, bvh.leaf_count);
    assert_eq!(max_depth, bvh.depth);
    assert!(
        bvh.depth <= MAX_DEPTH,
        "depth {} > {}",
        bvh.depth,
        MAX_DEPTH
    );
}

/// x_i = e^(160 i / n - 80): spans nearly the whole f32 range. Binned SAH on
/// such input peels off everything outside the first bin (the top ln 16 of
/// the log range) at each level: about 160 / ln 16 = 58 levels.
fn exp_x(i: usize, n: usize) -> f32 {
    (i as f32 * 160.0 / n as f32 - 80.0).exp()
}

fn exponential_line(n: usize) -> Vec<Triangle> {
    (0..n)
        .map(|i| {
            let x = exp_x(i, n);
            let s = 1e-3 * x;
            tri(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + s, s, 0.0),
                Vec3::new(x, s, s),
            )
        })
        .collect()
}

fn brute_force(tris: &[GpuTriangle], o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
    let mut closest = t_max;
    let mut best = None;
    for (i, tri) in tris.iter().enumerate() {
        if let Some((t, u, v)) = intersect_triangle(tri, o, d, closest) {
            if t > t_min {
                closest = t;
                best = Some(Hit {
                    t,
                    triangle: i as u32,
                    u,
                    v,
                });
            }
        }
    }
    best
}

/// Traces every ray both ways; the closest distance must agree exactly (both
/// use the same triangle test), the triangle where distances are unique.
/// Returns the number of hits.
fn cross_check(bvh: &Bvh, triangles: &[Triangle], rays: &[(Vec3, Vec3)]) -> usize {
    let gpu = bvh.gpu_triangles(triangles);
    let mut hits = 0;
    for (k, &(o, d)) in rays.iter().enumerate() {
        let a = bvh.intersect(&gpu, o, d, 1e-4, f32::INFINITY);
        let b = brute_force(&gpu, o, d, 1e-4, f32::INFINITY);
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                assert_eq!(a.t, b.t, "ray {k}: bvh t {} vs brute force t {}", a.t, b.t);
                if a.triangle != b.triangle {
                    // Equal t on two triangles (a shared edge or vertex): either is right.
                    assert!(
                        intersect_triangle(&gpu[a.triangle as usize], o, d, f32::INFINITY)
                            .is_some()
                    );
                }
                hits += 1;
            }
            _ => panic!("ray {k} ({o}, {d}): bvh {a:?} vs brute force {b:?}"),
        }
        assert_eq!(
            bvh.occluded(&gpu, o, d, 1e-4, f32::INFINITY),
            b.is_some(),
            "ray {k}: occluded disagrees"
        );
        if let Some(b) = b {
            // Shortened ray that stops just before the closest hit must find nothing.
            assert!(
                !bvh.occluded(&gpu, o, d, 1e-4, b.t)
                    || brute_force(&gpu, o, d, 1e-4, b.t).is_some()
            );
        }
    }
    hits
}

/// Half the rays aimed at random points on random triangles, half random.
fn rays_for(triangles: &[Triangle], n: usize, seed: u64, lo: f32, hi: f32) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|k| {
            let o = rng.vec(lo, hi);
            if k % 2 == 0 && !triangles.is_empty() {
                let t = &triangles[(rng.next_u64() % triangles.len() as u64) as usize];
                let (mut u, mut v) = (rng.f(), rng.f());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                let p = t.positions[0] * (1.0 - u - v) + t.positions[1] * u + t.positions[2] * v;
                (o, (p - o).normalize_or(Vec3::X))
            } else {
                (o, rng.dir())
            }
        })
        .collect()
}

#[test]
fn every_triangle_once_and_bounds_contain() {
    let tris = soup(5000, 1);
    let bvh = Bvh::build(&tris);
    check_tree(&bvh, &tris);
    assert!(bvh.leaf_count > 1 && bvh.depth > 1);
}

/// Rays across the exponential line, each at the scale of the triangle it
/// aims at (tests rays_for would aim at triangles far below one ulp of the
/// origin, where any two float evaluations of the hit distance disagree),
/// plus rays along it.
fn line_rays(n: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng(seed);
    (0..200)
        .map(|_| {
            let x = exp_x((rng.next_u64() % n as u64) as usize, n);
            (Vec3::new(x * 1.0001, 0.5e-3 * x, -x), Vec3::Z)
        })
        .chain((0..50).map(|_| (Vec3::new(-1.0, 0.0005, 0.0005), Vec3::X)))
        .collect()
}

#[test]
fn depth_bounded_on_exponential_line() {
    // 100k triangles along x at exponentially growing spacing (x_i = e^(160 i / n - 80)):
    // a SAH split peels off the far end each time, so without the median
    // fallback the tree would be far deeper than the GLSL stack.
    let n = 100_000;
    let tris = exponential_line(n);
    let unconstrained = super::build::build_with_max_depth(&tris, u32::MAX);
    let bvh = Bvh::build(&tris);
    println!(
        "exponential line: depth {} (SAH alone: {}), leaves {} in {:.1} ms",
        bvh.depth, unconstrained.depth, bvh.leaf_count, bvh.build_ms
    );
    assert!(
        unconstrained.depth > MAX_DEPTH,
        "input no longer adversarial: SAH depth {}",
        unconstrained.depth
    );
    check_tree(&bvh, &tris);
    cross_check(&bvh, &tris, &line_rays(n, 7));
}

#[test]
fn tight_depth_limit_forces_median_splits() {
    // The tightest limit the invariant allows: ceil(log2(n)) levels.
    let n = 20_000;
    let line = exponential_line(n);
    let soup = soup(n, 5);
    for (tris, rays) in [
        (&line, line_rays(n, 6)),
        (&soup, rays_for(&soup, 500, 6, -12.0, 12.0)),
    ] {
        let bvh = super::build::build_with_max_depth(tris, 15);
        check_tree(&bvh, tris);
        assert!(bvh.depth <= 15, "depth {} > limit 15", bvh.depth);
        cross_check(&bvh, tris, &rays);
    }
}

#[test]
fn coincident_and_zero_area_triangles() {
    // 1000 copies of one triangle: all centroids equal, split by count.
    let same = vec![tri(Vec3::ZERO, Vec3::X, Vec3::Y); 1000];
    let bvh = Bvh::build(&same);
    check_tree(&bvh, &same);
    let gpu = bvh.gpu_triangles(&same);
    let hit = bvh
        .intersect(
            &gpu,
            Vec3::new(0.25, 0.25, 1.0),
            -Vec3::Z,
            0.0,
            f32::INFINITY,
        )
        .expect("hit");
    assert_eq!(hit.t, 1.0);

    // Zero-area triangles (points and segments) mixed with a soup.
    let mut rng = Rng(3);
    let mut tris = soup(2000, 2);
    for _ in 0..500 {
        let p = rng.vec(-10.0, 10.0);
        let q = rng.vec(-10.0, 10.0);
        tris.push(tri(p, p, p));
        tris.push(tri(p, q, (p + q) * 0.5));
    }
    let bvh = Bvh::build(&tris);
    check_tree(&bvh, &tris);
    cross_check(&bvh, &tris, &rays_for(&tris, 2000, 4, -12.0, 12.0));

    // All triangles on one line (every box has zero area).
    let line: Vec<Triangle> = (0..300)
        .map(|i| {
            tri(
                Vec3::X * i as f32,
                Vec3::X * (i as f32 + 0.5),
                Vec3::X * (i as f32 + 1.0),
            )
        })
        .collect();
    let bvh = Bvh::build(&line);
    check_tree(&bvh, &line);
}

#[test]
fn empty_and_single_triangle() {
    let bvh = Bvh::build(&[]);
    check_tree(&bvh, &[]);
    assert!(bvh.is_empty());
    assert_eq!((bvh.depth, bvh.leaf_count), (0, 0));
    assert!(bvh.gpu_triangles(&[]).is_empty());
    assert!(bvh
        .intersect(&[], Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY)
        .is_none());
    assert!(!bvh.occluded(&[], Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY));
    let mut bvh2 = bvh.clone();
    bvh2.refit(&[]);
    assert_eq!(bvh2.nodes, bvh.nodes);

    let one = [tri(
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(1.0, 0.0, 2.0),
        Vec3::new(0.0, 1.0, 2.0),
    )];
    let bvh = Bvh::build(&one);
    check_tree(&bvh, &one);
    assert_eq!(
        (
            bvh.nodes.len(),
            bvh.nodes[0].count,
            bvh.depth,
            bvh.leaf_count
        ),
        (1, 1, 0, 1)
    );
    let gpu = bvh.gpu_triangles(&one);
    let h = bvh
        .intersect(&gpu, Vec3::new(0.25, 0.5, 0.0), Vec3::Z, 0.0, f32::INFINITY)
        .expect("hit");
    assert_eq!(h.triangle, 0);
    assert!(
        (h.t - 2.0).abs() < 1e-6 && (h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6,
        "{h:?}"
    );
    // Backface (two-sided), t_max and t_min limits.
    assert!(bvh
        .intersect(
            &gpu,
            Vec3::new(0.25, 0.5, 4.0),
            -Vec3::Z,
            0.0,
            f32::INFINITY
        )
        .is_some());
    assert!(bvh
        .intersect(&gpu, Vec3::new(0.25, 0.5, 0.0), Vec3::Z, 0.0, 1.9)
        .is_none());
    assert!(bvh
        .intersect(&gpu, Vec3::new(0.25, 0.5, 0.0), Vec3::Z, 2.1, f32::INFINITY)
        .is_none());
    assert!(bvh
        .intersect(
            &gpu,
            Vec3::new(0.75, 0.75, 0.0),
            Vec3::Z,
            0.0,
            f32::INFINITY
        )
        .is_none());
}

#[test]
fn traversal_matches_brute_force_on_soup() {
    let tris = soup(3000, 11);
    let bvh = Bvh::build(&tris);
    check_tree(&bvh, &tris);
    let hits = cross_check(&bvh, &tris, &rays_for(&tris, 4000, 12, -15.0, 15.0));
    assert!(hits > 2000, "only {hits} hits");
}

#[test]
fn traversal_matches_brute_force_on_sphere() {
    let tris = sphere(Vec3::new(0.3, -0.2, 0.1), 2.0, 48, 96);
    let bvh = Bvh::build(&tris);
    check_tree(&bvh, &tris);
    // From outside (aimed and random) and from inside (every ray hits).
    let hits = cross_check(&bvh, &tris, &rays_for(&tris, 3000, 21, -5.0, 5.0));
    assert!(hits > 1500);
    let mut rng = Rng(22);
    let inside: Vec<(Vec3, Vec3)> = (0..2000)
        .map(|_| (Vec3::new(0.3, -0.2, 0.1) + rng.vec(-1.0, 1.0), rng.dir()))
        .collect();
    assert_eq!(cross_check(&bvh, &tris, &inside), inside.len());
}

#[test]
fn axis_aligned_rays_and_flat_geometry() {
    // A flat grid (zero-thickness boxes) hit by rays with zero direction components.
    let mut tris = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            let (x, z) = (i as f32 * 0.5, j as f32 * 0.5);
            let (a, b, c, d) = (
                Vec3::new(x, 0.0, z),
                Vec3::new(x + 0.5, 0.0, z),
                Vec3::new(x + 0.5, 0.0, z + 0.5),
                Vec3::new(x, 0.0, z + 0.5),
            );
            tris.push(tri(a, c, b));
            tris.push(tri(a, d, c));
        }
    }
    let bvh = Bvh::build(&tris);
    check_tree(&bvh, &tris);
    let mut rng = Rng(31);
    let mut rays = Vec::new();
    for _ in 0..1000 {
        let p = Vec3::new(rng.range(-1.0, 21.0), 0.0, rng.range(-1.0, 21.0));
        rays.push((p + Vec3::Y * 3.0, -Vec3::Y));
        rays.push((p - Vec3::Y * 3.0, Vec3::Y));
        rays.push((p + Vec3::Y * 0.1, Vec3::X)); // parallel to the grid: misses
        rays.push((p, Vec3::new(0.0, -0.0, 1.0))); // in the plane: det = 0, misses
    }
    let hits = cross_check(&bvh, &tris, &rays);
    assert!(hits > 1000);
}

#[test]
fn refit_after_moving_triangles() {
    let mut tris = soup(3000, 41);
    let mut bvh = Bvh::build(&tris);
    let nodes_before = bvh.nodes.len();
    let mut rng = Rng(42);
    let rot = Mat3::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    for t in &mut tris {
        let shift = rng.vec(-2.0, 2.0);
        for p in &mut t.positions {
            *p = rot * (*p * 1.3) + shift;
        }
    }
    bvh.refit(&tris);
    assert_eq!(bvh.nodes.len(), nodes_before);
    check_tree(&bvh, &tris);
    cross_check(&bvh, &tris, &rays_for(&tris, 3000, 43, -18.0, 18.0));

    // A sphere translated and squashed.
    let mut s = sphere(Vec3::ZERO, 1.0, 24, 48);
    let mut bvh = Bvh::build(&s);
    for t in &mut s {
        for p in &mut t.positions {
            *p = *p * Vec3::new(2.0, 0.5, 1.0) + Vec3::new(5.0, 1.0, -2.0);
        }
    }
    bvh.refit(&s);
    check_tree(&bvh, &s);
    cross_check(&bvh, &s, &rays_for(&s, 2000, 44, -3.0, 9.0));
}

#[test]
fn build_200k_triangles() {
    let tris = soup(200_000, 51);
    let t0 = Instant::now();
    let bvh = Bvh::build(&tris);
    let wall = t0.elapsed().as_secs_f64() * 1e3;
    println!(
        "200k triangles: build_ms {:.1} (wall {:.1} ms), {} nodes, {} leaves, depth {}",
        bvh.build_ms,
        wall,
        bvh.nodes.len(),
        bvh.leaf_count,
        bvh.depth
    );
    check_tree(&bvh, &tris);
    cross_check(&bvh, &tris, &rays_for(&tris, 200, 52, -12.0, 12.0));
}

/// Triangles of `mesh` as one object with material 0.
fn mesh_triangles(mesh: &crate::scene::Mesh) -> Vec<Triangle> {
    mesh.indices
        .iter()
        .map(|t| Triangle {
            positions: t.map(|i| mesh.positions[i as usize]),
            normals: t.map(|i| mesh.normals[i as usize]),
            uvs: [glam::Vec2::ZERO; 3],
            material: 0,
            object: 0,
        })
        .collect()
}

/// d_N of every vertex of `triangles` (all refractors).
fn normal_thickness(triangles: &[Triangle]) -> Vec<f32> {
    let bvh = Bvh::build(triangles);
    let mut gpu = bvh.gpu_triangles(triangles);
    bvh.set_normal_thickness(&mut gpu, |_, _| true);
    gpu.iter()
        .flat_map(|t| [t.n0[3], t.n1[3], t.n2[3]])
        .collect()
}

/// On a UV sphere every vertex lies on the sphere and -N points through the
/// centre, so the ray meets the far side at distance r + rho, rho the
/// distance from the centre to the hit point. A point of a triangle whose
/// vertices lie on the sphere, x = sum b_i v_i, has |x|^2 = sum b_i b_j
/// v_i.v_j >= r^2 cos(gamma), gamma the widest angle between two of its
/// vertices, and gamma <= d_theta + d_phi (along a meridian, then a
/// parallel). So 2r >= d_N >= r (1 + sqrt(cos(d_theta + d_phi))), up to
/// float rounding (1e-5 r). With an even slice count the antipode of a
/// vertex is a vertex and d_N = 2r; with an odd one it falls inside a
/// triangle and the lower bound matters.
#[test]
fn normal_thickness_of_a_sphere_is_its_diameter() {
    for (segments, radius, centre) in [
        (64u32, 1.0f32, Vec3::new(0.0, 1.6, 0.0)),
        (33, 0.5, Vec3::new(3.0, -2.0, 1.0)),
    ] {
        let mesh = crate::scene::shapes::sphere(centre, radius, segments);
        let d = normal_thickness(&mesh_triangles(&mesh));
        let (slices, stacks) = (segments as f32, (segments / 2) as f32);
        let gamma = std::f32::consts::PI / stacks + std::f32::consts::TAU / slices;
        let lo = radius * (1.0 + gamma.cos().sqrt()) - 1e-5 * radius;
        let hi = 2.0 * radius * (1.0 + 1e-5);
        let (min, max) = d
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        println!("sphere r = {radius}, {segments} segments: d_N in [{min:.6}, {max:.6}], bounds [{lo:.6}, {hi:.6}]");
        assert!(
            min >= lo && max <= hi,
            "d_N in [{min}, {max}], bounds [{lo}, {hi}]"
        );
    }
}

/// A box slab: every vertex's flat normal crosses the slab face to face, so
/// d_N is the slab's extent along that normal (thickness 0.1 m for the top
/// and bottom faces), to float rounding.
#[test]
fn normal_thickness_of_a_slab_is_its_thickness() {
    let (min, max) = (Vec3::new(-1.0, 0.5, -0.7), Vec3::new(1.0, 0.6, 0.7));
    let tris = mesh_triangles(&crate::scene::shapes::cuboid(min, max));
    let extent = max - min;
    let bvh = Bvh::build(&tris);
    let mut gpu = bvh.gpu_triangles(&tris);
    bvh.set_normal_thickness(&mut gpu, |_, _| true);
    for t in &gpu {
        for n in [t.n0, t.n1, t.n2] {
            let normal = Vec3::new(n[0], n[1], n[2]);
            let expected = normal.abs().dot(extent);
            assert!(
                (n[3] - expected).abs() < 1e-5,
                "d_N {} along {normal}, expected {expected}",
                n[3]
            );
        }
    }
    // Not a refractor: 0.
    bvh.set_normal_thickness(&mut gpu, |_, _| false);
    assert!(gpu
        .iter()
        .all(|t| t.n0[3] == 0.0 && t.n1[3] == 0.0 && t.n2[3] == 0.0));
}

/// The ray skips other objects: a small box inside a big one (separate
/// objects) does not shorten the big one's d_N.
#[test]
fn normal_thickness_ignores_other_objects() {
    let mut tris = mesh_triangles(&crate::scene::shapes::cuboid(
        Vec3::splat(-1.0),
        Vec3::splat(1.0),
    ));
    let mut inner = mesh_triangles(&crate::scene::shapes::cuboid(
        Vec3::splat(-0.2),
        Vec3::splat(0.2),
    ));
    for t in &mut inner {
        t.object = 1;
    }
    tris.extend(inner);
    let bvh = Bvh::build(&tris);
    let mut gpu = bvh.gpu_triangles(&tris);
    bvh.set_normal_thickness(&mut gpu, |_, _| true);
    for t in &gpu {
        let expected = if t.p1[3].to_bits() == 0 { 2.0 } else { 0.4 };
        for d in [t.n0[3], t.n1[3], t.n2[3]] {
            assert!((d - expected).abs() < 1e-5, "d_N {d}, expected {expected}");
        }
    }
}
