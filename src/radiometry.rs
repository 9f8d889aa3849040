//! The shared radiometric conventions (GUIDE §2) as host-side functions.
//! Shaders implement the same formulas in `glsl/common/`; tests check both.

use crate::scene::{Light, LightKind};
use crate::shader_bindings as b;
use glam::Vec3;
use std::f32::consts::PI;

/// Rec. 709 luminance weights of linear rgb (`luminance()` in
/// glsl/common/optics.glsl): one number for an rgb power or radiance
/// (light selection, energy criteria, denoising weights).
pub const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// The luminance of linear rgb `c`.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(LUMINANCE)
}

/// Spot-light angular falloff: 1 inside `cos_inner`, 0 outside `cos_outer`,
/// smoothstep in cos(theta) between (glsl/common/lights.glsl: spot_falloff).
/// `cos_inner` > 1 marks the cosine profile of a rect light's stand-in
/// (`frame::LAMBERTIAN_FALLOFF`): max(cos θ, 0).
pub fn spot_falloff(cos_theta: f32, cos_outer: f32, cos_inner: f32) -> f32 {
    if cos_inner > 1.5 {
        return cos_theta.max(0.0);
    }
    if cos_inner <= cos_outer {
        return if cos_theta >= cos_outer { 1.0 } else { 0.0 };
    }
    let t = ((cos_theta - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Total emitted power (W per channel).
/// Point: 4 pi I. Spot: I times the falloff integrated over the sphere,
/// 2 pi [(1 - cos_inner) + (cos_inner - cos_outer) / 2] (a smoothstep integrates to
/// half its interval). Directional: E times the area of the disk its photons
/// leave, pi R^2, R the scene's bounding-sphere radius.
pub fn light_power(light: &Light, scene_radius: f32) -> Vec3 {
    match light.kind {
        LightKind::Point => light.intensity * 4.0 * PI,
        LightKind::Spot if light.cone_falloff_deg < 0.0 => light.intensity * PI,
        LightKind::Spot => {
            let cos_outer = light.cone_angle_deg.to_radians().cos();
            let cos_inner = (light.cone_angle_deg - light.cone_falloff_deg)
                .max(0.0)
                .to_radians()
                .cos();
            light.intensity * 2.0 * PI * ((1.0 - cos_inner) + 0.5 * (cos_inner - cos_outer))
        }
        LightKind::Directional => light.intensity * PI * scene_radius * scene_radius,
    }
}

/// Unpolarised Fresnel reflectance of a dielectric interface (exact equations),
/// `cos_i` the cosine of the incident angle, `eta` = n_incident / n_transmitted.
/// Returns 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let [s, p] = fresnel_polarised(cos_i, eta);
    0.5 * (s + p)
}

/// Fresnel reflectance of the s and p polarisations (perpendicular and
/// parallel to the plane of incidence), as [`fresnel_dielectric`].
pub fn fresnel_polarised(cos_i: f32, eta: f32) -> [f32; 2] {
    let cos_i = cos_i.abs().min(1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return [1.0; 2];
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    [r_s * r_s, r_p * r_p]
}

/// Reflectance of a thin dielectric sheet of index `ior` in air (a
/// `thin_dielectric` material) for light arriving at cos θ = `cos_i`; it
/// transmits the rest, undeflected. Derivation (incoherent, a sheet much
/// thicker than the light's coherence length, no absorption): each face
/// reflects r and transmits t = 1 − r of one polarisation, the same r at
/// the inner face (the Fresnel equations are symmetric in the two angles,
/// the Stokes relations). Light bounces between the faces: reflected r,
/// then t·r·t, t·r³·t, …; transmitted t·t, t·r²·t, …, so
///     R_sheet = r + t² r / (1 − r²) = 2r / (1 + r),
///     T_sheet = t² / (1 − r²) = (1 − r) / (1 + r),
/// with R_sheet + T_sheet = 1. The two polarisations do not mix at
/// parallel faces, so the series is summed for each and the two averaged
/// (unpolarised light). Both faces parallel: Snell's law twice gives back
/// the incident direction, with a lateral shift of the order of the
/// thickness, which a sheet of zero thickness has not. (pbrt-v4, Pharr,
/// Jakob & Humphreys 2023, §9.5.2 "Thin Dielectric BSDF", sums the same
/// series on the unpolarised reflectance.) glsl/common/optics.glsl
/// `thin_sheet_reflectance` is the same function.
pub fn thin_sheet_reflectance(cos_i: f32, ior: f32) -> f32 {
    let [s, p] = fresnel_polarised(cos_i, 1.0 / ior);
    0.5 * (2.0 * s / (1.0 + s) + 2.0 * p / (1.0 + p))
}

/// Henyey-Greenstein phase function, normalised over the sphere (1/(4 pi) at g = 0).
/// `cos_theta` is the cosine between the propagation directions before and after scattering.
pub fn henyey_greenstein(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}

/// A path-type component of the ground truth (Heckbert's notation), named
/// by the light's path up to the diffuse surface or medium point seen:
/// a caustic seen through water is still a surface caustic
/// (docs/ARCHITECTURE.md, "The ground truth").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Component {
    /// L D (and L D S+ E through the camera-side chains).
    Direct,
    /// L S+ D.
    SurfaceCaustics,
    /// L V: single scattering straight from the light.
    Airlight,
    /// L S+ V.
    VolumeCaustics,
    /// Everything else (diffuse interreflection, multiple scattering).
    Other,
    /// L S* E: the environment and area lights seen directly or through
    /// specular chains (the background, a lamp, the sky in a mirror).
    Emitted,
    /// The sum of all.
    All,
}

impl Component {
    pub const NAMED: [(&'static str, Component); 7] = [
        ("direct", Component::Direct),
        ("surface_caustics", Component::SurfaceCaustics),
        ("airlight", Component::Airlight),
        ("volume_caustics", Component::VolumeCaustics),
        ("other", Component::Other),
        ("emitted", Component::Emitted),
        ("all", Component::All),
    ];

    pub fn parse(name: &str) -> anyhow::Result<Component> {
        Self::NAMED
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, c)| *c)
            .ok_or_else(|| {
                let names: Vec<_> = Self::NAMED.iter().map(|(n, _)| *n).collect();
                anyhow::anyhow!("unknown component `{name}`; one of: {}", names.join(", "))
            })
    }

    pub fn name(self) -> &'static str {
        Self::NAMED
            .iter()
            .find(|(_, c)| *c == self)
            .map(|(n, _)| *n)
            .unwrap_or("all")
    }

    /// This component's bit in the frame constants' component mask
    /// (`component_weight` in glsl/common/scene.glsl); `All`: every bit.
    pub fn mask(self) -> u32 {
        match self {
            Component::All => (1 << b::COMPONENT_COUNT) - 1,
            c => 1 << c.index(),
        }
    }

    /// The component's number (`COMPONENT_*` in shader_bindings).
    pub fn index(self) -> u32 {
        match self {
            Component::Direct => b::COMPONENT_DIRECT,
            Component::SurfaceCaustics => b::COMPONENT_SURFACE_CAUSTICS,
            Component::Airlight => b::COMPONENT_AIRLIGHT,
            Component::VolumeCaustics => b::COMPONENT_VOLUME_CAUSTICS,
            Component::Other => b::COMPONENT_OTHER,
            Component::Emitted => b::COMPONENT_EMITTED,
            Component::All => b::COMPONENT_COUNT,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_normal_incidence_matches_closed_form() {
        let n = 1.5f32;
        let f0 = ((n - 1.0) / (n + 1.0)).powi(2);
        assert!((fresnel_dielectric(1.0, 1.0 / n) - f0).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, n) - f0).abs() < 1e-6);
        assert_eq!(
            fresnel_dielectric(0.1, 1.5),
            1.0,
            "total internal reflection"
        );
    }

    /// At normal incidence both polarisations reflect r = ((n-1)/(n+1))²
    /// and the sheet 2r/(1+r) (0.0769 for n = 1.5: the two faces' 4% each,
    /// less what the second face cannot reflect); ior 1 reflects nothing;
    /// at grazing incidence everything.
    #[test]
    fn thin_sheet_sums_the_inter_reflections() {
        let r = (0.5f32 / 2.5).powi(2);
        assert!((thin_sheet_reflectance(1.0, 1.5) - 2.0 * r / (1.0 + r)).abs() < 1e-6);
        // The series itself: r + t² r Σ r^2k.
        let t = 1.0 - r;
        let series: f32 = r + (0..20).map(|k| t * t * r * r.powi(2 * k)).sum::<f32>();
        assert!((thin_sheet_reflectance(1.0, 1.5) - series).abs() < 1e-6);
        assert_eq!(thin_sheet_reflectance(0.7, 1.0), 0.0);
        assert!(thin_sheet_reflectance(1e-4, 1.5) > 0.99);
    }

    #[test]
    fn henyey_greenstein_integrates_to_one() {
        for g in [-0.7f32, 0.0, 0.3, 0.7] {
            let n = 20000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let c = -1.0 + 2.0 * (i as f32 + 0.5) / n as f32;
                    henyey_greenstein(c, g) as f64 * 2.0 * std::f64::consts::PI * (2.0 / n as f64)
                })
                .sum();
            assert!((sum - 1.0).abs() < 1e-3, "g = {g}: {sum}");
        }
    }

    #[test]
    fn spot_power_matches_numerical_integral() {
        let light = Light {
            kind: LightKind::Spot,
            position: Vec3::ZERO,
            direction: Vec3::NEG_Y,
            intensity: Vec3::ONE,
            cone_angle_deg: 30.0,
            cone_falloff_deg: 10.0,
        };
        let (co, ci) = (30f32.to_radians().cos(), 20f32.to_radians().cos());
        let n = 100000;
        let numeric: f32 = (0..n)
            .map(|i| {
                let c = -1.0 + 2.0 * (i as f32 + 0.5) / n as f32;
                spot_falloff(c, co, ci) * 2.0 * PI * 2.0 / n as f32
            })
            .sum();
        let p = light_power(&light, 1.0).x;
        assert!((p - numeric).abs() / numeric < 1e-3, "{p} vs {numeric}");
    }
}
