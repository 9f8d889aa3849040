//! The approximate multiple scattering of the airlight pass (issue 28,
//! `[medium] multiple_scattering = true`): the light that the medium
//! scatters once becomes virtual point lights (Keller 1997's instant
//! radiosity; in media, Raab et al. 2008 and Engelhardt et al. 2010),
//! which then light the medium a second time (L V V E) and the surfaces
//! (L V D E) in glsl/passes/airlight.comp. Tagged `other`, the
//! reference's component of those paths.
//!
//! Placement, per punctual light (the scene's and the stand-ins of
//! `frame::caustic_lights`): K (`rays_side`²) directions stratified over
//! what it emits (a spot's cone and a point's sphere uniformly in solid angle, a
//! directional light's disk of the scene's bounding radius uniformly in
//! area), each ray traced on the CPU through mirrors and glass (`follow`)
//! to its first diffuse surface, each of its segments' part in the
//! medium's box (outside glass) cut into `STEPS` equal strata. A stratum
//! of length Δ at optical depth τ₀ from the light scatters the exact power
//! of a homogeneous medium,
//!   Φ_v = Φ_ray e^(−σt τ₀) (1 − e^(−σt Δ)) σs / σt,
//! (Φ_ray = I(ω) Δω, or E π R² / K for a directional light) and emits it
//! from the stratum's midpoint with the phase function around the ray:
//! I_v(ω') = Φ_v p(ω · ω'). The shader divides by max(d², r²), r the
//! light's half-spacing (the larger of Δ/2 and the rays' half-spacing
//! there): the clamp of instant radiosity, a bias confined to within r of
//! the lights. Scattering of order three and more scales the second by
//! 1 / (1 − a) (`higher_orders`: a, the chance that scattered light
//! scatters again, from the box's mean chord). Left out: the light a
//! dielectric reflects (F), what the surfaces reflect into the medium
//! (L D V, beyond the reference's `--diffuse-bounces 0`), and a density
//! other than a constant (refused when the scene is read).
//!
//! On `light_shaft` (128², 4 M reference photons, noise 11.7%): the
//! frame −2.2% / FLIP 0.043 against the reference's, −22.6% / 0.167
//! without; its `other` −5.2% / 0.039 (BENCHMARKS.md, "Where users
//! look").

use crate::bvh::Bvh;
use crate::gpu::GpuTriangle;
use crate::radiometry::{fresnel_dielectric, spot_falloff, thin_sheet_reflectance};
use crate::scene::{Density, Light, LightKind, MaterialKind, Medium, Scene};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::f32::consts::PI;

/// Strata along each of a ray's segments in the medium.
pub const STEPS: u32 = 8;
/// Segments in the medium a ray places lights along: before and after a
/// glass object (its own inside has no medium).
pub const SEGMENTS: u32 = 2;
/// Most virtual lights in all: each pixel loops over them at 8 strata and
/// at its surface (16 shadow rays), which must stay within llvmpipe's
/// 65535 loop iterations per invocation (docs/architecture/reference.md).
/// On `light_shaft` 16 rays (256 lights) match 36 (576) within 0.001 in
/// FLIP and 0.2% in energy, at less than half the pass's time.
pub const MAX_SCATTERED_LIGHTS: u32 = 256;

/// The side of the square of rays per light for `lights` lights: 4 (16
/// rays) for one, fewer as lights share `MAX_SCATTERED_LIGHTS`, at least 2.
pub fn rays_side(lights: usize) -> u32 {
    let per_light = MAX_SCATTERED_LIGHTS / (lights.max(1) as u32 * STEPS * SEGMENTS);
    ((per_light as f32).sqrt() as u32).clamp(2, 6)
}

/// Room for the virtual lights of `lights` lights.
pub fn capacity(lights: usize) -> u32 {
    let side = rays_side(lights);
    lights as u32 * side * side * STEPS * SEGMENTS
}

/// One virtual light (glsl/passes/airlight.comp `ScatteredLight`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GpuScatteredLight {
    /// xyz position; w = clamp radius r (m).
    pub position: [f32; 4],
    /// rgb scattered power Φ_v (W); w unused.
    pub power: [f32; 4],
    /// xyz unit direction of the light before it scattered; w unused.
    pub direction: [f32; 4],
}

/// The virtual lights of `scene`'s medium at `time`, for `lights` (the GPU
/// light buffer's, `frame::caustic_lights`); empty without a medium that
/// asks for multiple scattering.
pub fn scattered_lights(scene: &Scene, lights: &[Light], time: f32) -> Vec<GpuScatteredLight> {
    let Some(medium) = scene.medium.as_ref().filter(|m| m.multiple_scattering) else {
        return Vec::new();
    };
    let Density::Constant(density) = medium.density else {
        return Vec::new();
    };
    let triangles = scene.triangles(time);
    let bvh = Bvh::build(&triangles);
    let gpu = bvh.gpu_triangles(&triangles);
    let (centre, radius) = scene.bounding_sphere(time);
    let side = rays_side(lights.len());
    let mut out = Vec::new();
    for light in lights {
        for (origin, dir, power, spacing) in light_rays(light, side, centre, radius) {
            follow(
                scene, medium, density, &bvh, &gpu, origin, dir, power, spacing, &mut out,
            );
        }
    }
    out
}

/// Most specular events a ray follows (a glass ball takes two).
const MAX_SPECULAR: u32 = 8;

/// Follows one ray from the light through mirrors and glass (the
/// transmitted part at a dielectric, 1 − F, or the reflected one under
/// total internal reflection; Beer-Lambert inside), placing virtual lights
/// along each of its segments in the medium outside dielectrics, until it
/// meets a diffuse surface or leaves the scene: light focused by glass
/// scatters too (L S V, whose further paths are the reference's `other`).
#[allow(clippy::too_many_arguments)]
fn follow(
    scene: &Scene,
    medium: &Medium,
    density: f32,
    bvh: &Bvh,
    triangles: &[GpuTriangle],
    mut origin: Vec3,
    mut dir: Vec3,
    mut power: Vec3,
    spacing: (f32, f32),
    out: &mut Vec<GpuScatteredLight>,
) {
    let mut inside_glass = false;
    let mut travelled = 0.0;
    let mut segments = 0;
    for _ in 0..=MAX_SPECULAR {
        let hit = bvh.intersect(triangles, origin, dir, 1e-4, f32::INFINITY);
        let end = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
        if !inside_glass && segments < SEGMENTS {
            segments += 1;
            // The lateral spacing grows with the distance from the light
            // (unchanged by the lens: a bias of the clamp radius only).
            let lateral = (spacing.0 + spacing.1 * travelled, spacing.1);
            scatter_along(medium, density, origin, dir, end, power, lateral, out);
        }
        let Some(hit) = hit else { return };
        let tri = &triangles[hit.triangle as usize];
        let Some(material) = scene.materials.get(tri.p0[3].to_bits() as usize) else {
            return;
        };
        let (u, v) = (hit.u, hit.v);
        let normal = (Vec3::from_slice(&tri.n0[..3]) * (1.0 - u - v)
            + Vec3::from_slice(&tri.n1[..3]) * u
            + Vec3::from_slice(&tri.n2[..3]) * v)
            .normalize_or_zero();
        let point = origin + dir * hit.t;
        if inside_glass {
            power *= (-material.absorption * hit.t).exp();
        }
        travelled += hit.t;
        match material.kind {
            MaterialKind::Mirror => {
                power *= material.color;
                dir = reflect(dir, normal);
            }
            MaterialKind::Dielectric => {
                let entering = dir.dot(normal) < 0.0;
                let n = if entering { normal } else { -normal };
                let eta = if entering {
                    1.0 / material.ior
                } else {
                    material.ior
                };
                let cos_i = -dir.dot(n);
                match refract(dir, n, eta) {
                    Some(t) => {
                        power *= 1.0 - fresnel_dielectric(cos_i, eta);
                        dir = t;
                        inside_glass = entering;
                    }
                    None => dir = reflect(dir, n),
                }
            }
            // A thin sheet passes its transmitted part straight on.
            MaterialKind::ThinDielectric => {
                power *= 1.0 - thin_sheet_reflectance(dir.dot(normal).abs(), material.ior);
            }
            MaterialKind::Diffuse => return,
        }
        origin = point + dir * 1e-4;
    }
}

fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Refraction of `d` at normal `n` (facing against `d`) with relative
/// index `eta` = n_i / n_t; None under total internal reflection.
fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| (d * eta + n * (eta * cos_i - k.sqrt())).normalize())
}

/// The rays of `light`: origin, unit direction, power (W) and the lateral
/// spacing of neighbouring rays as a function of distance, (a, b) with
/// spacing(t) = a + b t.
fn light_rays(
    light: &Light,
    side: u32,
    centre: Vec3,
    radius: f32,
) -> Vec<(Vec3, Vec3, Vec3, (f32, f32))> {
    let n = side;
    let count = (n * n) as f32;
    let mut rays = Vec::with_capacity((n * n) as usize);
    let axis = light.direction.normalize_or_zero();
    let (tangent, bitangent) = axis.any_orthonormal_pair();
    for i in 0..n {
        for j in 0..n {
            let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let phi = 2.0 * PI * v;
            let around = tangent * phi.cos() + bitangent * phi.sin();
            match light.kind {
                LightKind::Directional => {
                    // A disk of the bounding radius, uniform in area.
                    let r = radius * u.sqrt();
                    let origin = centre + around * r - axis * (2.0 * radius);
                    let side = (PI * radius * radius / count).sqrt();
                    let power = light.intensity * (PI * radius * radius / count);
                    rays.push((origin, axis, power, (side, 0.0)));
                }
                LightKind::Point | LightKind::Spot => {
                    let (cos_outer, cos_inner, cos_max) = match light.kind {
                        LightKind::Point => (-1.0, -1.0, -1.0),
                        // A rect light's stand-in: the cosine profile.
                        _ if light.cone_falloff_deg < 0.0 => (0.0, 2.0, 0.0),
                        _ => {
                            let outer = light.cone_angle_deg.to_radians();
                            let inner = (light.cone_angle_deg - light.cone_falloff_deg)
                                .max(0.0)
                                .to_radians();
                            (outer.cos(), inner.cos(), outer.cos())
                        }
                    };
                    // Uniform in solid angle over the cap cos θ >= cos_max.
                    let solid_angle = 2.0 * PI * (1.0 - cos_max);
                    let cos_t = 1.0 - u * (1.0 - cos_max);
                    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                    let dir = (axis * cos_t + around * sin_t).normalize();
                    let falloff = match light.kind {
                        LightKind::Point => 1.0,
                        _ => spot_falloff(cos_t, cos_outer, cos_inner),
                    };
                    let d_omega = solid_angle / count;
                    let power = light.intensity * (falloff * d_omega);
                    rays.push((light.position, dir, power, (0.0, d_omega.sqrt())));
                }
            }
        }
    }
    rays
}

/// Appends the virtual lights of one ray (power `power` from `origin`
/// along `dir`, ending at `end`) in `medium` of constant `density`.
#[allow(clippy::too_many_arguments)]
fn scatter_along(
    medium: &Medium,
    density: f32,
    origin: Vec3,
    dir: Vec3,
    end: f32,
    power: Vec3,
    spacing: (f32, f32),
    out: &mut Vec<GpuScatteredLight>,
) {
    let Some((t0, t1)) = clip_to_box(origin, dir, medium.bounds_min, medium.bounds_max, end) else {
        return;
    };
    let sigma_s = medium.sigma_s * density;
    let sigma_t = (medium.sigma_s + medium.sigma_a) * density;
    let step = (t1 - t0) / STEPS as f32;
    for k in 0..STEPS {
        let start = t0 + k as f32 * step;
        let before = (-sigma_t * (start - t0)).exp();
        // (1 − e^(−σt Δ)) σs / σt, → σs Δ as σt → 0.
        let scattered = Vec3::select(
            sigma_t.cmpgt(Vec3::splat(1e-6)),
            (Vec3::ONE - (-sigma_t * step).exp()) * sigma_s / sigma_t.max(Vec3::splat(1e-6)),
            sigma_s * step,
        );
        let flux = power * before * scattered * higher_orders(medium, density);
        if flux.max_element() <= 0.0 {
            continue;
        }
        let t = start + 0.5 * step;
        let r = (0.5 * step).max(0.5 * (spacing.0 + spacing.1 * t));
        out.push(GpuScatteredLight {
            position: (origin + dir * t).extend(r).to_array(),
            power: flux.extend(0.0).to_array(),
            direction: dir.extend(0.0).to_array(),
        });
    }
}

/// The factor that adds scattering of order three and more to the second:
/// light scattered once goes on to scatter again before it leaves the
/// medium with probability a = (σs / σt)(1 − e^(−σt ℓ)), ℓ the box's mean
/// chord length 4V/S (Cauchy's formula for a convex body crossed by
/// uniformly random lines), so the orders from the second on sum to the
/// second's times Σ a^k = 1 / (1 − a) (each order spread like the one
/// before it: the approximation).
fn higher_orders(medium: &Medium, density: f32) -> Vec3 {
    let size = medium.bounds_max - medium.bounds_min;
    let volume = size.x * size.y * size.z;
    let surface = 2.0 * (size.x * size.y + size.y * size.z + size.z * size.x);
    let chord = 4.0 * volume / surface;
    let sigma_t = (medium.sigma_s + medium.sigma_a) * density;
    let albedo = medium.sigma_s / (medium.sigma_s + medium.sigma_a).max(Vec3::splat(1e-12));
    let again = albedo * (Vec3::ONE - (-sigma_t * chord).exp());
    Vec3::ONE / (Vec3::ONE - again.min(Vec3::splat(0.99)))
}

/// The part (t0, t1) of the ray within (0, end) inside the box, if any.
fn clip_to_box(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3, end: f32) -> Option<(f32, f32)> {
    let inv = d.recip();
    let (a, b) = ((lo - o) * inv, (hi - o) * inv);
    let t0 = a.min(b).max_element().max(0.0);
    let t1 = a.max(b).min_element().min(end);
    (t0 < t1 && t1.is_finite()).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fog(sigma_s: f32, sigma_a: f32) -> Medium {
        Medium {
            sigma_s: Vec3::splat(sigma_s),
            sigma_a: Vec3::splat(sigma_a),
            g: 0.0,
            bounds_min: Vec3::splat(-1.0),
            bounds_max: Vec3::splat(1.0),
            density: Density::Constant(1.0),
            multiple_scattering: true,
        }
    }

    /// A ray across a homogeneous slab: the strata's powers add up to the
    /// power scattered once, Φ (1 − e^(−σt L)) σs / σt, whatever the split
    /// (times the higher orders' factor).
    #[test]
    fn strata_scatter_the_exact_single_scattered_power() {
        let (sigma_s, sigma_a) = (0.7, 0.3);
        let mut out = Vec::new();
        let o = Vec3::new(0.0, 0.0, -5.0);
        scatter_along(
            &fog(sigma_s, sigma_a),
            1.0,
            o,
            Vec3::Z,
            f32::INFINITY,
            Vec3::ONE,
            (0.0, 0.0),
            &mut out,
        );
        assert_eq!(out.len(), STEPS as usize);
        let orders = higher_orders(&fog(sigma_s, sigma_a), 1.0).x;
        let total: f32 = out.iter().map(|l| l.power[0]).sum::<f32>() / orders;
        let expected =
            (1.0 - (-(sigma_s + sigma_a) * 2.0f32).exp()) * sigma_s / (sigma_s + sigma_a);
        assert!((total - expected).abs() < 1e-5, "{total} vs {expected}");
        // The midpoints of equal strata between z = -1 and 1.
        assert!((out[0].position[2] + 1.0 - 1.0 / STEPS as f32).abs() < 1e-5);
        // A ray that ends at a surface halfway scatters only before it.
        let mut cut = Vec::new();
        scatter_along(
            &fog(sigma_s, sigma_a),
            1.0,
            o,
            Vec3::Z,
            5.0,
            Vec3::ONE,
            (0.0, 0.0),
            &mut cut,
        );
        let total: f32 = cut.iter().map(|l| l.power[0]).sum::<f32>() / orders;
        let expected =
            (1.0 - (-(sigma_s + sigma_a) * 1.0f32).exp()) * sigma_s / (sigma_s + sigma_a);
        assert!((total - expected).abs() < 1e-5, "{total} vs {expected}");
    }

    /// The box's mean chord is 4V/S (a cube of side 2: 4/3); a medium that
    /// absorbs everything or is thin adds nothing past the second order.
    #[test]
    fn higher_orders_follow_the_mean_chord() {
        let (s, a) = (0.7f32, 0.3f32);
        let expected = 1.0 / (1.0 - s / (s + a) * (1.0 - (-(s + a) * 4.0f32 / 3.0).exp()));
        assert!((higher_orders(&fog(s, a), 1.0).x - expected).abs() < 1e-5);
        assert_eq!(higher_orders(&fog(0.0, 1.0), 1.0).x, 1.0);
        assert!((higher_orders(&fog(1e-4, 0.0), 1.0).x - 1.0).abs() < 1e-3);
    }

    /// The rays of a point, a spot and a directional light carry the
    /// light's power (`radiometry::light_power`).
    #[test]
    fn rays_carry_the_lights_power() {
        let base = Light {
            kind: LightKind::Point,
            position: Vec3::new(0.0, 3.0, 0.0),
            direction: Vec3::NEG_Y,
            intensity: Vec3::splat(2.0),
            cone_angle_deg: 30.0,
            cone_falloff_deg: 0.0,
        };
        let radius = 4.0;
        for kind in [LightKind::Point, LightKind::Spot, LightKind::Directional] {
            let light = Light { kind, ..base };
            let sum: f32 = light_rays(&light, 6, Vec3::ZERO, radius)
                .iter()
                .map(|r| r.2.x)
                .sum();
            let expected = crate::radiometry::light_power(&light, radius).x;
            assert!(
                (sum - expected).abs() < 1e-3 * expected,
                "{kind:?}: {sum} vs {expected}"
            );
        }
    }
}
