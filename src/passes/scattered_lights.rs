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
//! from the stratum's midpoint with the phase function around the ray
//! (Φ_ray dimmed by the medium and the glass it crossed before):
//! I_v(ω') = Φ_v p(ω · ω'). The shader divides by max(d², r²), r the
//! light's half-spacing (the larger of Δ/2 and the rays' half-spacing
//! there): the clamp of instant radiosity, a bias confined to within r of
//! the lights. Scattering of order three and more scales the second by
//! 1 / (1 − a) (`Placer::again`: a, the chance that light scattered at the
//! light's place scatters again, from its distances to the medium's side
//! or a surface). Left out: the light a dielectric reflects (F), what the
//! surfaces reflect into the medium (L D V, beyond the reference's
//! `--diffuse-bounces 0`), and a density other than a constant (refused
//! when the scene is read).
//!
//! On `light_shaft` (128², 4 M reference photons, noise 11.7%):
//! `volume_lines`' frame −4.1% / FLIP 0.047 against the reference's,
//! −22.6% / 0.167 without; its `other` −13.9% / 0.048 (BENCHMARKS.md,
//! "Multiple scattering as an option").

use crate::bvh::Bvh;
use crate::gpu::GpuTriangle;
use crate::radiometry::{
    fresnel_dielectric, henyey_greenstein, spot_falloff, thin_sheet_reflectance,
};
use crate::scene::{Density, Light, LightKind, MaterialKind, Medium, Scene};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::f32::consts::PI;

/// Strata along each of a ray's segments in the medium, at most.
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
/// Directions of each light's estimate of scattering again (`again`).
const ESCAPE_DIRECTIONS: u32 = 32;

/// Rays per light (the side of their square, 2 to 4) and strata per
/// segment (1 to `STEPS`) for `lights` lights, within
/// `MAX_SCATTERED_LIGHTS`: 4 x 4 rays of 8 strata for one light, 2 x 2 of
/// 4 for eight.
pub fn layout(lights: usize) -> (u32, u32) {
    let per_light = MAX_SCATTERED_LIGHTS / (lights.max(1) as u32 * SEGMENTS);
    let side = (((per_light / STEPS) as f32).sqrt() as u32).clamp(2, 4);
    (side, (per_light / (side * side)).clamp(1, STEPS))
}

/// Room for the virtual lights of `lights` lights (at most
/// `MAX_SCATTERED_LIGHTS`).
pub fn capacity(lights: usize) -> u32 {
    let (side, steps) = layout(lights);
    lights as u32 * side * side * steps * SEGMENTS
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
    let placer = Placer {
        scene,
        medium,
        sigma_s: medium.sigma_s * density,
        sigma_t: (medium.sigma_s + medium.sigma_a) * density,
        triangles: bvh.gpu_triangles(&triangles),
        bvh,
        steps: layout(lights.len()).1,
    };
    let (centre, radius) = scene.bounding_sphere(time);
    let side = layout(lights.len()).0;
    let mut out = Vec::new();
    for light in lights {
        for (origin, dir, power, spacing) in light_rays(light, side, centre, radius) {
            placer.follow(origin, dir, power, spacing, &mut out);
        }
    }
    out
}

/// Most specular events a ray follows (a glass ball takes two).
const MAX_SPECULAR: u32 = 8;

/// What placing the lights of one scene needs.
struct Placer<'a> {
    scene: &'a Scene,
    medium: &'a Medium,
    /// Coefficients times the (constant) density.
    sigma_s: Vec3,
    sigma_t: Vec3,
    bvh: Bvh,
    triangles: Vec<GpuTriangle>,
    steps: u32,
}

impl Placer<'_> {
    /// The closest surface along a ray: distance, triangle and barycentrics.
    fn hit(&self, origin: Vec3, dir: Vec3) -> Option<crate::bvh::Hit> {
        self.bvh
            .intersect(&self.triangles, origin, dir, 1e-4, f32::INFINITY)
    }

    /// Follows one ray from the light through mirrors and glass (the
    /// transmitted part at a dielectric, 1 − F, or the reflected one under
    /// total internal reflection; Beer-Lambert inside), attenuated by the
    /// medium it crosses, placing virtual lights along its first
    /// `SEGMENTS` segments in the medium outside dielectrics, until it
    /// meets a diffuse surface or leaves the scene: light focused by glass
    /// scatters too (L S V, whose further paths are the reference's
    /// `other`).
    fn follow(
        &self,
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
            let hit = self.hit(origin, dir);
            let end = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
            if !inside_glass {
                // The lateral spacing grows with the distance from the
                // light (unchanged by the lens: a bias of the clamp radius
                // only).
                let lateral = (spacing.0 + spacing.1 * travelled, spacing.1);
                let place = segments < SEGMENTS;
                power *= self.scatter_along(origin, dir, end, power, lateral, place, out);
                segments += 1;
            }
            let Some(hit) = hit else { return };
            let tri = &self.triangles[hit.triangle as usize];
            let Some(material) = self.scene.materials.get(tri.p0[3].to_bits() as usize) else {
                return;
            };
            let (u, v) = (hit.u, hit.v);
            let normal = (Vec3::from_slice(&tri.n0[..3]) * (1.0 - u - v)
                + Vec3::from_slice(&tri.n1[..3]) * u
                + Vec3::from_slice(&tri.n2[..3]) * v)
                .normalize_or_zero();
            let point = origin + dir * hit.t;
            if inside_glass {
                power *= (-material.extinction() * hit.t).exp();
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
                // A `mixed` material's mirror part is left out too.
                MaterialKind::Diffuse => return,
            }
            origin = point + dir * 1e-4;
        }
    }

    /// Along one segment (power `power` from `origin` along `dir`, ending
    /// at `end`): appends its virtual lights when `place`, and returns the
    /// medium's transmittance over it (what goes on).
    #[allow(clippy::too_many_arguments)]
    fn scatter_along(
        &self,
        origin: Vec3,
        dir: Vec3,
        end: f32,
        power: Vec3,
        spacing: (f32, f32),
        place: bool,
        out: &mut Vec<GpuScatteredLight>,
    ) -> Vec3 {
        let (lo, hi) = (self.medium.bounds_min, self.medium.bounds_max);
        let Some((t0, t1)) = clip_to_box(origin, dir, lo, hi, end) else {
            return Vec3::ONE;
        };
        let through = (-self.sigma_t * (t1 - t0)).exp();
        if !place {
            return through;
        }
        let step = (t1 - t0) / self.steps as f32;
        for k in 0..self.steps {
            let start = t0 + k as f32 * step;
            let before = (-self.sigma_t * (start - t0)).exp();
            let flux = power * before * scattered_fraction(self.sigma_s, self.sigma_t, step);
            if flux.max_element() <= 0.0 {
                continue;
            }
            let t = start + 0.5 * step;
            let position = origin + dir * t;
            let r = (0.5 * step).max(0.5 * (spacing.0 + spacing.1 * t));
            let again = self.again(position, dir);
            let orders = Vec3::ONE / (Vec3::ONE - again.min(Vec3::splat(0.99)));
            out.push(GpuScatteredLight {
                position: position.extend(r).to_array(),
                power: (flux * orders).extend(0.0).to_array(),
                direction: dir.extend(0.0).to_array(),
            });
        }
        through
    }

    /// The chance a, per channel, that light scattered at x (arriving along
    /// `dir`) scatters again before it leaves the medium or meets a
    /// surface: (σs / σt) times the mean over its new directions, weighted
    /// by the phase function, of 1 − e^(−σt d), d the distance to the
    /// box's side or the first surface (`ESCAPE_DIRECTIONS` directions of
    /// a spherical Fibonacci set). The orders from the second on are then
    /// summed as the second's times Σ a^k = 1 / (1 − a): each further order
    /// taken to scatter again as often as the one before it, the
    /// approximation.
    fn again(&self, x: Vec3, dir: Vec3) -> Vec3 {
        let (lo, hi) = (self.medium.bounds_min, self.medium.bounds_max);
        let mut sum = Vec3::ZERO;
        let mut weights = 0.0;
        for k in 0..ESCAPE_DIRECTIONS {
            let w = fibonacci_direction(k, ESCAPE_DIRECTIONS);
            let phase = henyey_greenstein(dir.dot(w), self.medium.g);
            let d = self.hit(x, w).map_or(f32::INFINITY, |h| h.t);
            let d = clip_to_box(x, w, lo, hi, d).map_or(0.0, |(t0, t1)| t1 - t0);
            sum += phase * (Vec3::ONE - (-self.sigma_t * d).exp());
            weights += phase;
        }
        let albedo = self.sigma_s / self.sigma_t.max(Vec3::splat(1e-12));
        albedo * sum / weights.max(1e-12)
    }
}

/// (1 − e^(−σt Δ)) σs / σt, the fraction of the light entering a stratum
/// of length Δ that scatters in it (→ σs Δ as σt → 0).
fn scattered_fraction(sigma_s: Vec3, sigma_t: Vec3, step: f32) -> Vec3 {
    Vec3::select(
        sigma_t.cmpgt(Vec3::splat(1e-6)),
        (Vec3::ONE - (-sigma_t * step).exp()) * sigma_s / sigma_t.max(Vec3::splat(1e-6)),
        sigma_s * step,
    )
}

/// Direction k of n spread evenly over the sphere (a spherical Fibonacci
/// set).
fn fibonacci_direction(k: u32, n: u32) -> Vec3 {
    let z = 1.0 - (2.0 * k as f32 + 1.0) / n as f32;
    let phi = k as f32 * PI * (3.0 - 5.0f32.sqrt());
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
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
    // A point light's direction may be zero (it emits everywhere).
    let axis = light.direction.try_normalize().unwrap_or(Vec3::Y);
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

    const SIGMA_S: f32 = 0.7;
    const SIGMA_A: f32 = 0.3;

    /// A fog box x, y in [-1, 1], z in [-3, 3] (σs 0.7, σa 0.3, g 0.3),
    /// with `objects` (TOML) and a floor far below it.
    fn scene(objects: &str) -> Scene {
        let text = format!(
            "[camera]\neye = [0, 0, -8]\ntarget = [0, 0, 0]\n\
             [[light]]\nkind = \"point\"\nposition = [0, 0, -5]\nintensity = 1.0\n\
             [[material]]\nname = \"floor\"\nkind = \"diffuse\"\n\
             [[material]]\nname = \"glass\"\nkind = \"dielectric\"\nior = 1.5\nabsorption = [0.5, 0.5, 0.5]\n\
             [[object]]\nshape = \"plane\"\ncenter = [0, -20, 0]\nsize = [1, 1]\nmaterial = \"floor\"\n\
             {objects}\
             [medium]\nsigma_s = {SIGMA_S}\nsigma_a = {SIGMA_A}\ng = 0.3\n\
             bounds = {{ min = [-1, -1, -3], max = [1, 1, 3] }}\nmultiple_scattering = true\n"
        );
        Scene::from_str(&text, std::path::Path::new("fog.toml")).unwrap()
    }

    fn placer(scene: &Scene) -> Placer<'_> {
        let medium = scene.medium.as_ref().unwrap();
        let triangles = scene.triangles(0.0);
        let bvh = Bvh::build(&triangles);
        Placer {
            scene,
            medium,
            sigma_s: medium.sigma_s,
            sigma_t: medium.sigma_s + medium.sigma_a,
            triangles: bvh.gpu_triangles(&triangles),
            bvh,
            steps: STEPS,
        }
    }

    /// The lights' power before the higher orders' factor (red).
    fn second_order(p: &Placer, lights: &[GpuScatteredLight]) -> f32 {
        lights
            .iter()
            .map(|l| {
                let again = p.again(
                    Vec3::from_slice(&l.position[..3]),
                    Vec3::from_slice(&l.direction[..3]),
                );
                l.power[0] * (1.0 - again.x)
            })
            .sum()
    }

    /// A ray through the fog: its strata scatter the exact power a
    /// homogeneous medium scatters once, Φ (1 − e^(−σt L)) σs / σt, and
    /// what goes on is Φ e^(−σt L).
    #[test]
    fn strata_scatter_the_exact_single_scattered_power() {
        let s = scene("");
        let p = placer(&s);
        let mut out = Vec::new();
        let o = Vec3::new(0.0, 0.0, -5.0);
        let through = p.scatter_along(
            o,
            Vec3::Z,
            f32::INFINITY,
            Vec3::ONE,
            (0.0, 0.0),
            true,
            &mut out,
        );
        assert_eq!(out.len(), STEPS as usize);
        let st = SIGMA_S + SIGMA_A;
        let expected = (1.0 - (-st * 6.0f32).exp()) * SIGMA_S / st;
        let total = second_order(&p, &out);
        assert!((total - expected).abs() < 1e-5, "{total} vs {expected}");
        assert!((through.x - (-st * 6.0f32).exp()).abs() < 1e-6);
        // The midpoints of equal strata between z = -3 and 3.
        assert!((out[0].position[2] + 3.0 - 3.0 / STEPS as f32).abs() < 1e-5);
    }

    /// Through a glass slab (z in [-0.1, 0.1], n = 1.5, absorption 0.5/m)
    /// at normal incidence: the lights beyond it carry what the haze before
    /// it, both faces' transmittance (1 − F)², F = 0.04, and the glass's
    /// Beer-Lambert left, and none lie inside the glass.
    #[test]
    fn light_through_glass_is_attenuated_by_the_haze_before_it() {
        let s = scene("[[object]]\nshape = \"box\"\nmin = [-2, -2, -0.1]\nmax = [2, 2, 0.1]\nmaterial = \"glass\"\n");
        let p = placer(&s);
        let mut out = Vec::new();
        p.follow(
            Vec3::new(0.0, 0.0, -5.0),
            Vec3::Z,
            Vec3::ONE,
            (0.0, 0.0),
            &mut out,
        );
        assert_eq!(out.len(), 2 * STEPS as usize);
        assert!(out.iter().all(|l| l.position[2].abs() > 0.1));
        let (before, after): (Vec<_>, Vec<_>) = out.iter().partition(|l| l.position[2] < 0.0);
        let st = SIGMA_S + SIGMA_A;
        let leg = 2.9f32;
        let scattered = (1.0 - (-st * leg).exp()) * SIGMA_S / st;
        let glass = 0.96f32 * 0.96 * (-0.5f32 * 0.2).exp();
        let expected = (-st * leg).exp() * glass * scattered;
        let got = second_order(&p, &after);
        assert!(
            (got - expected).abs() < 1e-3 * expected,
            "{got} vs {expected}"
        );
        assert!((second_order(&p, &before) - scattered).abs() < 1e-5);
    }

    /// A medium that absorbs everything scatters nothing again; in a thin
    /// one, light scatters again with chance about σs times the mean
    /// distance to the box's side (phase-weighted), well under the mean
    /// chord; at the box's centre, toward the glass, less than away from
    /// it when the glass is near.
    #[test]
    fn scattering_again_follows_the_distance_to_the_boundary() {
        let s = scene("");
        let p = placer(&s);
        let again = p.again(Vec3::ZERO, Vec3::Z).x;
        // Escape distances from the centre lie between 1 (the x and y
        // sides) and 3 (the z ends).
        let st = SIGMA_S + SIGMA_A;
        let (lo, hi) = (
            SIGMA_S / st * (1.0 - (-st).exp()),
            SIGMA_S / st * (1.0 - (-3.0 * st).exp()),
        );
        assert!(again > lo && again < hi, "{lo} < {again} < {hi}");
        let edge = p.again(Vec3::new(0.95, 0.0, 0.0), Vec3::Z).x;
        assert!(
            edge < again,
            "{edge} near the side vs {again} at the centre"
        );
    }

    /// The rays of a point, a spot (with its smooth edge) and a directional
    /// light carry the light's power (`radiometry::light_power`) at the
    /// layout of one light.
    #[test]
    fn rays_carry_the_lights_power() {
        let base = Light {
            kind: LightKind::Point,
            position: Vec3::new(0.0, 3.0, 0.0),
            direction: Vec3::NEG_Y,
            intensity: Vec3::splat(2.0),
            cone_angle_deg: 12.0,
            cone_falloff_deg: 4.0,
        };
        let radius = 4.0;
        let side = layout(1).0;
        for kind in [LightKind::Point, LightKind::Spot, LightKind::Directional] {
            let light = Light { kind, ..base };
            let sum: f32 = light_rays(&light, side, Vec3::ZERO, radius)
                .iter()
                .map(|r| r.2.x)
                .sum();
            let expected = crate::radiometry::light_power(&light, radius).x;
            assert!(
                (sum - expected).abs() < 0.01 * expected,
                "{kind:?}: {sum} vs {expected}"
            );
        }
    }

    /// However many lights, the virtual lights stay within
    /// `MAX_SCATTERED_LIGHTS`.
    #[test]
    fn capacity_stays_within_the_cap() {
        for n in 1..=crate::shader_bindings::MAX_LIGHTS as usize + 4 {
            assert!(
                capacity(n) <= MAX_SCATTERED_LIGHTS,
                "{n} lights: {}",
                capacity(n)
            );
        }
        assert_eq!(layout(1), (4, 8));
    }
}
