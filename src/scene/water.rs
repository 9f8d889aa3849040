//! Water surfaces: a grid over an x/z rectangle displaced by a sum of
//! Gerstner waves, evaluated on the CPU (tessellation for every technique and
//! the reference) and, with the same formula, on the GPU
//! (glsl/common/water.glsl, src/passes/water_surface.rs).
//!
//! The Gerstner sum in the form of GPU Gems 1, ch. 1 (Finch, "Effective Water
//! Simulation from Physical Models", Eq. 9), also Tessendorf, "Simulating
//! Ocean Water" (2001, §4.6 choppy waves): a rest point x0 = (x, z) moves to
//!
//! ```text
//! P(x0, t) = ( x + Σ Q_i A_i D_i.x cos θ_i,
//!              base_height + Σ A_i sin θ_i,
//!              z + Σ Q_i A_i D_i.z cos θ_i ),
//! θ_i = k_i D_i · x0 − ω_i t + φ_i,   k_i = 2π / λ_i,   ω_i = k_i · speed_i,
//! ```
//!
//! with D_i the unit travel direction in the x/z plane, A_i the amplitude and
//! Q_i the steepness (0: a plain sine wave). The normal is the cross product
//! of the analytic partial derivatives ∂P/∂z × ∂P/∂x (exact, where GPU Gems
//! Eq. 12 evaluates an approximation at the displaced point).

use super::types::{Mesh, Water, Wave};
use glam::{Vec2, Vec3};
use std::f32::consts::TAU;

/// Standard gravity, m/s², for the deep-water dispersion relation ω² = g k.
pub const GRAVITY: f32 = 9.81;
/// Most cells along one side of a water grid.
pub const MAX_RESOLUTION: u32 = 4096;
/// Most cells of a water grid in all (4.2M triangles, ~0.35 GB of triangles).
pub const MAX_CELLS: u64 = 1 << 21;
/// Most waves on one water surface.
pub const MAX_WAVES: usize = 16;

impl Wave {
    /// Deep-water phase speed sqrt(g λ / 2π), m/s: the default `speed`
    /// (from the dispersion relation ω² = g k).
    pub fn deep_water_speed(wavelength: f32) -> f32 {
        (GRAVITY * wavelength / TAU).sqrt()
    }

    /// k = 2π / λ, rad/m.
    pub fn wavenumber(&self) -> f32 {
        TAU / self.wavelength
    }

    /// ω = k · speed, rad/s.
    pub fn angular_frequency(&self) -> f32 {
        self.wavenumber() * self.speed
    }

    /// Unit travel direction D as (x, z): (cos d, −sin d), counter-clockwise seen from +y.
    pub fn direction(&self) -> Vec2 {
        let (s, c) = self.direction_deg.to_radians().sin_cos();
        Vec2::new(c, -s)
    }

    /// Q k A: this wave's share of the fold-over bound (see [`Water::fold_measure`]).
    pub fn fold_share(&self) -> f32 {
        self.steepness * self.wavenumber() * self.amplitude
    }
}

impl Water {
    /// Rest position (x, z) of grid vertex (i, j), i along x in 0..=nx, j along z in 0..=nz.
    pub fn rest_position(&self, i: u32, j: u32) -> Vec2 {
        let [nx, nz] = self.resolution;
        let f = Vec2::new(i as f32 / nx as f32 - 0.5, j as f32 / nz as f32 - 0.5);
        self.center + self.size * f
    }

    /// Vertices of the grid, (nx + 1)(nz + 1).
    pub fn vertex_count(&self) -> usize {
        (self.resolution[0] as usize + 1) * (self.resolution[1] as usize + 1)
    }

    /// Σ Q_i k_i A_i. The map x0 -> P(x0).xz has Jacobian I − Σ Q_i k_i A_i
    /// sin θ_i D_i D_iᵀ, whose symmetric part has norm at most this sum: below
    /// 1 the surface never folds over itself (no loops at the crests).
    pub fn fold_measure(&self) -> f32 {
        self.waves.iter().map(Wave::fold_share).sum()
    }

    /// Whether `p` lies under the surface at `time`, within the water's
    /// rectangle: the rest point whose displaced position lies over p is
    /// found by fixed-point iteration (the horizontal displacement's
    /// Jacobian is within `fold_measure` < 1 of the identity, so it
    /// converges), then the heights are compared.
    pub fn is_below_surface(&self, p: Vec3, time: f32) -> bool {
        let target = Vec2::new(p.x, p.z);
        let half = self.size * 0.5;
        let mut rest = target;
        for _ in 0..8 {
            let (q, _) = self.surface_point(rest, time);
            rest += target - Vec2::new(q.x, q.z);
        }
        let inside = (rest - self.center).abs().cmple(half).all();
        inside && p.y < self.surface_point(rest, time).0.y
    }

    /// Whether the surface changes with time (some wave has height and speed).
    pub fn is_moving(&self) -> bool {
        self.waves
            .iter()
            .any(|w| w.amplitude != 0.0 && w.speed != 0.0)
    }

    /// Displaced position and unit normal (pointing up, +y side) of the rest
    /// point `rest` = (x, z) at `time` seconds: the Gerstner sum of the module
    /// docs, normal = normalize(∂P/∂z × ∂P/∂x).
    pub fn surface_point(&self, rest: Vec2, time: f32) -> (Vec3, Vec3) {
        let (position, d_dx, d_dz) = self.surface_derivatives(rest, time);
        (position, d_dz.cross(d_dx).normalize())
    }

    /// Displaced position P and its partial derivatives ∂P/∂x, ∂P/∂z with
    /// respect to the rest coordinates, at `rest` = (x, z) and `time`.
    /// glsl/common/water.glsl evaluates the same operations in the same order.
    pub fn surface_derivatives(&self, rest: Vec2, time: f32) -> (Vec3, Vec3, Vec3) {
        let mut position = Vec3::new(rest.x, self.base_height, rest.y);
        let mut d_dx = Vec3::X;
        let mut d_dz = Vec3::Z;
        for w in &self.waves {
            let d = w.direction();
            let k = w.wavenumber();
            let theta = k * d.dot(rest) - w.angular_frequency() * time + w.phase;
            let (sin, cos) = theta.sin_cos();
            let qa = w.steepness * w.amplitude;
            position += Vec3::new(qa * d.x * cos, w.amplitude * sin, qa * d.y * cos);
            // d/dx0 of cos θ is −k D.x sin θ, of sin θ is k D.x cos θ (same for z).
            let horizontal = k * qa * sin;
            let vertical = k * w.amplitude * cos;
            d_dx += Vec3::new(
                -horizontal * d.x * d.x,
                vertical * d.x,
                -horizontal * d.x * d.y,
            );
            d_dz += Vec3::new(
                -horizontal * d.x * d.y,
                vertical * d.y,
                -horizontal * d.y * d.y,
            );
        }
        (position, d_dx, d_dz)
    }

    /// The surface at `time` as a grid of smooth-shaded triangles, counter-
    /// clockwise seen from above (normals up). Vertex (i, j) is at index
    /// j (nx + 1) + i, the order of the GPU pass's output. `materials` is
    /// filled with `self.material`.
    pub fn mesh(&self, time: f32) -> Mesh {
        let [nx, nz] = self.resolution;
        let mut mesh = Mesh {
            positions: Vec::with_capacity(self.vertex_count()),
            normals: Vec::with_capacity(self.vertex_count()),
            uvs: Vec::with_capacity(self.vertex_count()),
            indices: Vec::with_capacity(2 * nx as usize * nz as usize),
            materials: Vec::new(),
        };
        for j in 0..=nz {
            for i in 0..=nx {
                let (p, n) = self.surface_point(self.rest_position(i, j), time);
                mesh.positions.push(p);
                mesh.normals.push(n);
                // UV over the rest grid: u along +x, v along +z.
                mesh.uvs
                    .push(Vec2::new(i as f32 / nx as f32, j as f32 / nz as f32));
            }
        }
        let stride = nx + 1;
        for j in 0..nz {
            for i in 0..nx {
                let a = j * stride + i;
                let (b, c, d) = (a + 1, a + 1 + stride, a + stride);
                // +x then +z turns clockwise seen from +y: a, c, b is counter-clockwise.
                mesh.indices.extend([[a, c, b], [a, d, c]]);
            }
        }
        mesh.materials = vec![self.material; mesh.indices.len()];
        mesh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn water(waves: Vec<Wave>) -> Water {
        Water {
            center: Vec2::new(1.0, -2.0),
            size: Vec2::new(8.0, 6.0),
            resolution: [16, 12],
            base_height: 0.5,
            material: 0,
            waves,
        }
    }

    fn wave(amplitude: f32, wavelength: f32, direction_deg: f32, steepness: f32) -> Wave {
        Wave {
            amplitude,
            wavelength,
            direction_deg,
            steepness,
            speed: Wave::deep_water_speed(wavelength),
            phase: 0.3,
        }
    }

    #[test]
    fn one_wave_without_steepness_is_a_sine() {
        let w = wave(0.2, 3.0, 30.0, 0.0);
        let water = water(vec![w]);
        let d = Vec2::new(30f32.to_radians().cos(), -30f32.to_radians().sin());
        for t in [0.0, 0.7, 5.0] {
            for (i, j) in [(0, 0), (3, 7), (16, 12), (9, 2)] {
                let rest = water.rest_position(i, j);
                let (p, n) = water.surface_point(rest, t);
                let theta = w.wavenumber() * d.dot(rest) - w.angular_frequency() * t + w.phase;
                // No horizontal motion; height a sine of the phase.
                assert!((p.x - rest.x).abs() < 1e-6 && (p.z - rest.y).abs() < 1e-6);
                assert!((p.y - (0.5 + 0.2 * theta.sin())).abs() < 1e-5, "{p}");
                // Normal of the heightfield y = h(x, z): (−∂h/∂x, 1, −∂h/∂z).
                let slope = w.wavenumber() * 0.2 * theta.cos();
                let expect = Vec3::new(-slope * d.x, 1.0, -slope * d.y).normalize();
                assert!((n - expect).length() < 1e-5, "{n} vs {expect}");
            }
        }
    }

    #[test]
    fn zero_amplitude_is_flat_at_base_height() {
        let water = water(vec![wave(0.0, 2.0, 10.0, 1.0), wave(0.0, 5.0, 200.0, 0.5)]);
        assert!(!water.is_moving());
        let mesh = water.mesh(3.0);
        for (k, (p, n)) in mesh.positions.iter().zip(&mesh.normals).enumerate() {
            let rest = water.rest_position(k as u32 % 17, k as u32 / 17);
            assert_eq!(*p, Vec3::new(rest.x, 0.5, rest.y));
            assert_eq!(*n, Vec3::Y);
        }
    }

    /// Normals are unit, point up, and are perpendicular to finite
    /// differences of the displaced surface along both grid directions.
    #[test]
    fn normals_match_finite_differences() {
        let water = water(vec![
            wave(0.10, 2.0, 15.0, 0.8),
            wave(0.05, 1.1, 130.0, 1.0),
            wave(0.08, 3.7, 260.0, 0.5),
        ]);
        assert!(water.fold_measure() < 1.0);
        let h = 1e-3;
        let mut worst = 0.0f32;
        for t in [0.0, 1.3, 10.0] {
            for j in 0..=12 {
                for i in 0..=16 {
                    let rest = water.rest_position(i, j);
                    let (_, n) = water.surface_point(rest, t);
                    assert!((n.length() - 1.0).abs() < 1e-5 && n.y > 0.0);
                    let at = |dx: f32, dz: f32| water.surface_point(rest + Vec2::new(dx, dz), t).0;
                    let tx = (at(h, 0.0) - at(-h, 0.0)) / (2.0 * h);
                    let tz = (at(0.0, h) - at(0.0, -h)) / (2.0 * h);
                    let fd = tz.cross(tx).normalize();
                    worst = worst.max((fd - n).length());
                }
            }
        }
        // Central differences in f32 at h = 1 mm: rounding of ~1e-7 m
        // positions over 2 mm gives ~1e-4 in the tangents.
        assert!(worst < 1e-3, "worst normal difference {worst}");
    }

    #[test]
    fn mesh_winds_counter_clockwise_about_its_normals() {
        let water = water(vec![wave(0.1, 2.0, 45.0, 0.7)]);
        let mesh = water.mesh(0.4);
        assert_eq!(mesh.positions.len(), 17 * 13);
        assert_eq!(mesh.indices.len(), 2 * 16 * 12);
        assert_eq!(mesh.materials.len(), mesh.indices.len());
        for t in &mesh.indices {
            let p = t.map(|i| mesh.positions[i as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            let avg: Vec3 = t.iter().map(|&i| mesh.normals[i as usize]).sum();
            assert!(n.dot(avg) > 0.0 && n.y > 0.0);
        }
        // The grid spans the rectangle at rest.
        let corner = water.rest_position(0, 0);
        assert_eq!(corner, Vec2::new(-3.0, -5.0));
        assert_eq!(water.rest_position(16, 12), Vec2::new(5.0, 1.0));
    }

    #[test]
    fn waves_travel_along_their_direction_at_their_speed() {
        let w = wave(0.2, 4.0, 90.0, 0.0);
        let water = water(vec![w]);
        // 90 degrees travels toward −z: the crest at z moves to z − speed t.
        let rest = Vec2::new(0.0, 0.0);
        let t = 0.25;
        let ahead = rest + Vec2::new(0.0, -w.speed * t);
        let (now, _) = water.surface_point(rest, 0.0);
        let (later, _) = water.surface_point(ahead, t);
        assert!((now.y - later.y).abs() < 1e-5);
        assert!((w.speed - (9.81f32 * 4.0 / TAU).sqrt()).abs() < 1e-6);
    }
}
