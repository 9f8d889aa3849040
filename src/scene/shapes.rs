//! Procedural shapes tessellated into triangle meshes.
//!
//! All meshes are in the object's local space. Triangles wind
//! counter-clockwise seen from the side their normal points to, and normals of
//! closed shapes point outward. `materials` is left empty: the caller fills it.
//!
//! Texture coordinates (docs/SCENES.md, "UV parameterisations"): every shape
//! maps onto [0, 1]², u and v along the directions named at each shape, v
//! growing away from the texture's top row.

use super::types::Mesh;
use glam::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// Default tessellation of curved shapes (segments around the main circle).
pub const DEFAULT_SEGMENTS: u32 = 64;
/// Fewest segments accepted for a curved shape.
pub const MIN_SEGMENTS: u32 = 3;
/// Most segments accepted for a curved shape (keeps meshes under ~10M triangles).
pub const MAX_SEGMENTS: u32 = 2048;

/// Two unit vectors `(u, v)` with `u x v = w` for a unit `w`.
pub fn basis(w: Vec3) -> (Vec3, Vec3) {
    let helper = if w.x.abs() < 0.9 { Vec3::X } else { Vec3::Z };
    let u = (helper - w * w.dot(helper)).normalize();
    let v = w.cross(u);
    (u, v)
}

/// Adds the triangles of a (cols+1) x (rows+1) vertex grid starting at
/// `base`, where stepping a column then a row turns counter-clockwise seen
/// from outside. Triangles with two coincident corners (poles) are skipped.
fn grid(mesh: &mut Mesh, base: u32, cols: u32, rows: u32) {
    let stride = cols + 1;
    for j in 0..rows {
        for i in 0..cols {
            let a = base + j * stride + i;
            let b = a + 1;
            let c = b + stride;
            let d = a + stride;
            for tri in [[a, b, c], [a, c, d]] {
                let p = tri.map(|k| mesh.positions[k as usize]);
                if p[0] != p[1] && p[1] != p[2] && p[0] != p[2] {
                    mesh.indices.push(tri);
                }
            }
        }
    }
}

/// UV sphere: `segments` around the y axis, `segments / 2` (at least 2) from
/// pole to pole, smooth normals. UV: u = φ / 2π (φ the angle from +x toward
/// +z), v = θ / π (θ from the +y pole).
pub fn sphere(center: Vec3, radius: f32, segments: u32) -> Mesh {
    let slices = segments.max(MIN_SEGMENTS);
    let stacks = (segments / 2).max(2);
    let mut mesh = Mesh::default();
    for j in 0..=stacks {
        let theta = PI * j as f32 / stacks as f32;
        let (st, ct) = theta.sin_cos();
        for i in 0..=slices {
            // Reuse the exact seam/pole positions so they compare equal.
            let phi = TAU * (i % slices) as f32 / slices as f32;
            let (sp, cp) = phi.sin_cos();
            let d = if j == 0 {
                Vec3::Y
            } else if j == stacks {
                Vec3::NEG_Y
            } else {
                Vec3::new(st * cp, ct, st * sp)
            };
            mesh.positions.push(center + radius * d);
            mesh.normals.push(d);
            mesh.uvs.push(Vec2::new(
                i as f32 / slices as f32,
                j as f32 / stacks as f32,
            ));
        }
    }
    grid(&mut mesh, 0, slices, stacks);
    mesh
}

/// A w x h rectangle centred at `center` facing `normal`, its w side along
/// `tangent` (projected onto the plane; any perpendicular when `None`).
/// The caller guarantees unit `normal` and a tangent not parallel to it.
/// UV: u from 0 to 1 along the w side (the tangent), v from 0 to 1 along
/// `normal x tangent`.
pub fn plane(center: Vec3, normal: Vec3, tangent: Option<Vec3>, size: [f32; 2]) -> Mesh {
    let u = match tangent {
        Some(t) => (t - normal * normal.dot(t)).normalize(),
        None => basis(normal).0,
    };
    let v = normal.cross(u);
    let (hu, hv) = (u * size[0] * 0.5, v * size[1] * 0.5);
    Mesh {
        positions: vec![
            center - hu - hv,
            center + hu - hv,
            center + hu + hv,
            center - hu + hv,
        ],
        normals: vec![normal; 4],
        uvs: QUAD_UVS.to_vec(),
        indices: vec![[0, 1, 2], [0, 2, 3]],
        materials: Vec::new(),
    }
}

/// UVs of the corners of a quad `c - u - v, c + u - v, c + u + v, c - u + v`.
const QUAD_UVS: [Vec2; 4] = [
    Vec2::new(0.0, 0.0),
    Vec2::new(1.0, 0.0),
    Vec2::new(1.0, 1.0),
    Vec2::new(0.0, 1.0),
];

/// Axis-aligned box, 24 vertices, 12 triangles, flat outward normals.
/// UV: each face is [0, 1]² on its own, u along the face's first in-plane
/// axis and v along its second, the pair turning counter-clockwise seen from
/// outside (faces ±x: (y, z) / (z, y), ±y: (z, x) / (x, z), ±z: (x, y) / (y, x)).
pub fn cuboid(min: Vec3, max: Vec3) -> Mesh {
    let mid = (min + max) * 0.5;
    let half = (max - min) * 0.5;
    let axes = [Vec3::X, Vec3::Y, Vec3::Z];
    let mut mesh = Mesh::default();
    for k in 0..3 {
        let a = axes[(k + 1) % 3];
        let b = axes[(k + 2) % 3];
        for s in [-1.0f32, 1.0] {
            let n = axes[k] * s;
            let (u, v) = if s > 0.0 { (a, b) } else { (b, a) };
            let fc = mid + n * half[k];
            let hu = u * half.dot(u.abs());
            let hv = v * half.dot(v.abs());
            let base = mesh.positions.len() as u32;
            mesh.positions
                .extend([fc - hu - hv, fc + hu - hv, fc + hu + hv, fc - hu + hv]);
            mesh.normals.extend([n; 4]);
            mesh.uvs.extend(QUAD_UVS);
            mesh.indices
                .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
        }
    }
    mesh
}

/// Torus around unit `axis`: `segments` around the axis, `segments / 2` (at
/// least 3) around the tube. UV: u = angle around the axis / 2π, v = angle
/// around the tube / 2π (0 on the outer equator).
pub fn torus(center: Vec3, axis: Vec3, major: f32, minor: f32, segments: u32) -> Mesh {
    let (u, v) = basis(axis);
    let cols = segments.max(MIN_SEGMENTS);
    let rows = (segments / 2).max(MIN_SEGMENTS);
    let mut mesh = Mesh::default();
    for j in 0..=rows {
        let psi = TAU * (j % rows) as f32 / rows as f32;
        let (sq, cq) = psi.sin_cos();
        for i in 0..=cols {
            let phi = TAU * (i % cols) as f32 / cols as f32;
            let (sp, cp) = phi.sin_cos();
            let radial = u * cp + v * sp;
            let n = radial * cq + axis * sq;
            mesh.positions.push(center + radial * major + n * minor);
            mesh.normals.push(n);
            mesh.uvs
                .push(Vec2::new(i as f32 / cols as f32, j as f32 / rows as f32));
        }
    }
    grid(&mut mesh, 0, cols, rows);
    mesh
}

/// Cylinder from `p0` to `p1` (distinct): smooth sides, optional flat caps.
/// UV: the side has u = angle around the axis / 2π, v = 0 at `p0` and 1 at
/// `p1`; each cap maps the disc into [0, 1]² from above, (u, v) = (1 + (x, y)
/// / radius) / 2 in the cap's basis (the side's angle 0 at +u).
pub fn cylinder(p0: Vec3, p1: Vec3, radius: f32, caps: bool, segments: u32) -> Mesh {
    let w = (p1 - p0).normalize();
    let (u, v) = basis(w);
    let cols = segments.max(MIN_SEGMENTS);
    let ring: Vec<Vec3> = (0..=cols)
        .map(|i| {
            let (s, c) = (TAU * (i % cols) as f32 / cols as f32).sin_cos();
            u * c + v * s
        })
        .collect();
    let mut mesh = Mesh::default();
    for (v_end, end) in [(0.0, p0), (1.0, p1)] {
        for (i, &r) in ring.iter().enumerate() {
            mesh.positions.push(end + r * radius);
            mesh.normals.push(r);
            mesh.uvs.push(Vec2::new(i as f32 / cols as f32, v_end));
        }
    }
    grid(&mut mesh, 0, cols, 1);
    if caps {
        for (end, n) in [(p0, -w), (p1, w)] {
            let centre = mesh.positions.len() as u32;
            mesh.positions.push(end);
            mesh.normals.push(n);
            mesh.uvs.push(Vec2::splat(0.5));
            for &r in &ring[..cols as usize] {
                mesh.positions.push(end + r * radius);
                mesh.normals.push(n);
                let uv = Vec2::new(r.dot(u), r.dot(v)) * 0.5 + 0.5;
                mesh.uvs.push(uv.clamp(Vec2::ZERO, Vec2::ONE));
            }
            for i in 0..cols {
                let a = centre + 1 + i;
                let b = centre + 1 + (i + 1) % cols;
                // Ring order is counter-clockwise seen from +w.
                mesh.indices.push(if n == w {
                    [centre, a, b]
                } else {
                    [centre, b, a]
                });
            }
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle's geometric normal agrees with its vertex normals, and
    /// (for closed convex-ish shapes) points away from `inside`.
    fn check(mesh: &Mesh, inside: Option<Vec3>) {
        assert_eq!(mesh.positions.len(), mesh.normals.len());
        assert_eq!(mesh.positions.len(), mesh.uvs.len());
        for uv in &mesh.uvs {
            assert!(
                uv.cmpge(Vec2::ZERO).all() && uv.cmple(Vec2::ONE).all(),
                "{uv}"
            );
        }
        assert!(!mesh.indices.is_empty());
        for t in &mesh.indices {
            let p = t.map(|i| mesh.positions[i as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            assert!(n.length() > 0.0, "degenerate triangle {p:?}");
            let avg: Vec3 = t.iter().map(|&i| mesh.normals[i as usize]).sum();
            assert!(n.dot(avg) > 0.0, "winding disagrees with normals at {p:?}");
            if let Some(c) = inside {
                let centroid = (p[0] + p[1] + p[2]) / 3.0;
                assert!(n.dot(centroid - c) > 0.0, "normal points inward at {p:?}");
            }
        }
        for n in &mesh.normals {
            assert!((n.length() - 1.0).abs() < 1e-4);
        }
    }

    #[test]
    fn sphere_is_closed_outward_and_on_the_surface() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        let m = sphere(c, 2.0, 16);
        check(&m, Some(c));
        for p in &m.positions {
            assert!(((*p - c).length() - 2.0).abs() < 1e-5);
        }
        assert_eq!(m.indices.len(), 2 * 16 * 8 - 2 * 16);
    }

    #[test]
    fn box_has_twelve_outward_triangles() {
        let m = cuboid(Vec3::new(-1.0, 0.0, -2.0), Vec3::new(1.0, 3.0, 2.0));
        assert_eq!(m.indices.len(), 12);
        check(&m, Some(Vec3::new(0.0, 1.5, 0.0)));
    }

    #[test]
    fn torus_and_cylinder_are_outward() {
        let axis = Vec3::new(1.0, 1.0, 0.0).normalize();
        let m = torus(Vec3::ZERO, axis, 2.0, 0.5, 24);
        check(&m, None);
        // Outward from the tube's centre circle.
        let (u, v) = basis(axis);
        for t in &m.indices {
            let p = t.map(|i| m.positions[i as usize]);
            let c = (p[0] + p[1] + p[2]) / 3.0;
            let radial = (c - axis * axis.dot(c)).normalize();
            let core = radial * 2.0;
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            assert!(n.dot(c - core) > 0.0);
            assert!(radial.dot(u).abs() <= 1.0 + 1e-5 && radial.dot(v).abs() <= 1.0 + 1e-5);
        }
        let p0 = Vec3::new(0.0, -1.0, 0.0);
        let p1 = Vec3::new(0.0, 1.0, 0.5);
        let closed = cylinder(p0, p1, 0.7, true, 20);
        check(&closed, Some((p0 + p1) * 0.5));
        let open = cylinder(p0, p1, 0.7, false, 20);
        assert_eq!(open.indices.len(), 40);
        check(&open, Some((p0 + p1) * 0.5));
    }

    #[test]
    fn plane_faces_its_normal_with_w_along_tangent() {
        let n = Vec3::new(0.0, 0.0, -1.0);
        let m = plane(Vec3::ONE, n, Some(Vec3::Y), [4.0, 2.0]);
        check(&m, Some(Vec3::ONE - n));
        let ext = m.positions[1] - m.positions[0];
        assert!((ext - Vec3::Y * 4.0).length() < 1e-5);
        let default = plane(Vec3::ZERO, Vec3::Y, None, [1.0, 1.0]);
        check(&default, Some(-Vec3::Y));
        // u runs along the tangent: the corner at +w/2 has u = 1.
        assert_eq!(m.uvs[1] - m.uvs[0], Vec2::X);
    }

    #[test]
    fn sphere_uv_follows_the_angles() {
        let m = sphere(Vec3::ZERO, 1.0, 8);
        for (p, uv) in m.positions.iter().zip(&m.uvs) {
            let theta = p.y.clamp(-1.0, 1.0).acos();
            assert!((uv.y - theta / PI).abs() < 1e-5, "{p} {uv}");
            if p.y.abs() < 0.999 {
                let phi = p.z.atan2(p.x).rem_euclid(TAU);
                let u = if uv.x == 1.0 { 0.0 } else { uv.x };
                assert!((u * TAU - phi).abs() < 1e-4, "{p} {uv}");
            }
        }
    }
}
