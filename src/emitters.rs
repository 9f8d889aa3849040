//! Environment and area light radiometry on the host (GUIDE §2): the
//! equirectangular mapping, the sky gradient, the luminance CDF the
//! reference samples, the sun's irradiance and the powers used to pick a
//! light. `glsl/common/emitters.glsl` evaluates the same formulas on the
//! GPU; the point-light stand-ins the real-time techniques draw in their
//! place are `frame/stand_ins.rs`.

use crate::radiometry::LUMINANCE;
use crate::scene::{Emitter, EmitterShape, Environment, EnvironmentKind, Sky};
use glam::{Quat, Vec3};
use std::f32::consts::PI;

/// Resolution of the equirectangular table a `sky` is rasterised into (its
/// gradient is smooth; the sun is evaluated analytically, not tabulated).
pub const SKY_TABLE_SIZE: (u32, u32) = (256, 128);

/// Share of the environment's sampling density spread uniformly (by texel
/// solid angle) over all texels, so that every direction the bilinear
/// lookup can give radiance to has a positive pdf (unbiased emission).
pub const UNIFORM_SHARE: f32 = 0.01;

/// Unit direction of the equirectangular coordinate `(u, v)` in the image's
/// own frame: φ = 2π u from +x toward +z, θ = π v from +y.
pub fn equirect_dir(u: f32, v: f32) -> Vec3 {
    let (st, ct) = (PI * v).sin_cos();
    let (sp, cp) = (2.0 * PI * u).sin_cos();
    Vec3::new(st * cp, ct, st * sp)
}

/// Inverse of [`equirect_dir`]: `(u, v)` in [0, 1)² x [0, 1].
pub fn equirect_uv(d: Vec3) -> (f32, f32) {
    let phi = d.z.atan2(d.x);
    let u = phi / (2.0 * PI);
    (u - u.floor(), d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// The image frame -> world rotation of an environment (`rotate` about +y).
pub fn rotation(env: &Environment) -> Quat {
    Quat::from_rotation_y(env.rotate_deg.to_radians())
}

/// Sky gradient radiance toward `d` (world, unit), without the sun:
/// horizon at and below the horizon, zenith straight up, linear in the sine
/// of the elevation between.
pub fn sky_gradient(sky: &Sky, d: Vec3) -> Vec3 {
    let s = d.y.clamp(0.0, 1.0);
    sky.horizon + (sky.zenith - sky.horizon) * s
}

/// Solid angle of the sun disc, 2π(1 − cos α).
pub fn sun_solid_angle(sky: &Sky) -> f32 {
    2.0 * PI * (1.0 - sky.sun_radius_deg.to_radians().cos())
}

/// The directional light an environment's sun stands for: the way its
/// light travels and its irradiance on a surface facing it. A sky's sun:
/// E = L · 2π(1 − cos α) (radiance times the disc's solid angle; the exact
/// π L sin²α differs by α²/4 relative, under 1e-4 below 1°), times
/// `scale`. An image's: the sun [`extract_sun`] finds in it.
pub fn sun_irradiance(env: &Environment) -> Option<(Vec3, Vec3)> {
    match &env.kind {
        EnvironmentKind::Sky(sky) if sky.sun_radiance.max_element() > 0.0 => Some((
            -sky.sun_direction,
            sky.sun_radiance * sun_solid_angle(sky) * env.scale,
        )),
        EnvironmentKind::Sky(_) => None,
        EnvironmentKind::Image(_) => {
            let (w, h, texels) = table(env);
            extract_sun(w, h, &texels).map(|s| (-(rotation(env) * s.direction), s.irradiance))
        }
    }
}

/// A sun found in an equirectangular table (image frame): the texels
/// within [`SUN_SEARCH_DEG`] of the brightest one whose luminance exceeds
/// `threshold` (50 times the table's mean luminance over the sphere, at
/// least 1e-3 of the peak); none when the peak is below that.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtractedSun {
    /// Unit direction toward the sun (image frame): the texels' mean
    /// direction weighted by luminance times solid angle.
    pub direction: Vec3,
    /// Direction of the brightest texel and the cosine of the search cone
    /// around it: a texel belongs to the sun when it lies in this cone and
    /// is brighter than `threshold` (glsl/direct/environment_sh.comp leaves
    /// exactly those out of the sky's spherical harmonics).
    pub peak: Vec3,
    pub cos_search: f32,
    pub threshold: f32,
    /// Σ L ΔΩ over the sun's texels: irradiance on a surface facing it.
    pub irradiance: Vec3,
}

/// Half-angle of the cone around an image's brightest texel searched for
/// the rest of its sun.
pub const SUN_SEARCH_DEG: f32 = 10.0;

pub fn extract_sun(w: u32, h: u32, texels: &[[f32; 3]]) -> Option<ExtractedSun> {
    let lum = |t: &[f32; 3]| Vec3::from(*t).dot(LUMINANCE);
    let dir =
        |i: u32, j: u32| equirect_dir((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
    let mut integral = 0.0f64;
    let (mut peak_i, mut peak_l) = (0usize, -1.0f32);
    for (k, t) in texels.iter().enumerate() {
        let l = lum(t);
        integral += (l * texel_solid_angle(k as u32 / w, w, h)) as f64;
        if l > peak_l {
            (peak_i, peak_l) = (k, l);
        }
    }
    let mean = (integral / (4.0 * std::f64::consts::PI)) as f32;
    let threshold = (50.0 * mean).max(1e-3 * peak_l);
    if peak_l.is_nan() || peak_l <= threshold {
        return None;
    }
    let peak = dir(peak_i as u32 % w, peak_i as u32 / w);
    let cos_search = SUN_SEARCH_DEG.to_radians().cos();
    let (mut sum_d, mut e) = (Vec3::ZERO, Vec3::ZERO);
    for (k, t) in texels.iter().enumerate() {
        let (i, j) = (k as u32 % w, k as u32 / w);
        let d = dir(i, j);
        if d.dot(peak) >= cos_search && lum(t) > threshold {
            let omega = texel_solid_angle(j, w, h);
            e += Vec3::from(*t) * omega;
            sum_d += d * lum(t) * omega;
        }
    }
    Some(ExtractedSun {
        direction: sum_d.normalize(),
        peak,
        cos_search,
        threshold,
        irradiance: e,
    })
}

/// The environment as an equirectangular table of radiance in the image's
/// frame, `scale` applied (the sky's gradient rasterised at
/// [`SKY_TABLE_SIZE`] texel centres; the sun is not in it):
/// `(width, height, texels)`, rows from +y down.
pub fn table(env: &Environment) -> (u32, u32, Vec<[f32; 3]>) {
    match &env.kind {
        EnvironmentKind::Image(t) => (
            t.width,
            t.height,
            t.texels
                .iter()
                .map(|c| (Vec3::from(*c) * env.scale).to_array())
                .collect(),
        ),
        EnvironmentKind::Sky(sky) => {
            let (w, h) = SKY_TABLE_SIZE;
            let rot = rotation(env);
            let texels = (0..h)
                .flat_map(|j| (0..w).map(move |i| (i, j)))
                .map(|(i, j)| {
                    let d = rot
                        * equirect_dir((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
                    (sky_gradient(sky, d) * env.scale).to_array()
                })
                .collect();
            (w, h, texels)
        }
    }
}

/// Solid angle of a texel in row `j` of an equirectangular table `w` x `h`.
pub fn texel_solid_angle(j: u32, w: u32, h: u32) -> f32 {
    let t0 = PI * j as f32 / h as f32;
    let t1 = PI * (j + 1) as f32 / h as f32;
    2.0 * PI / w as f32 * (t0.cos() - t1.cos())
}

/// The sampling tables of an equirectangular radiance table: the marginal
/// CDF over rows (h + 1 values from 0 to 1) followed by each row's
/// conditional CDF over columns (w + 1 values each). A texel's weight is
/// its luminance times its solid angle (the sin θ of the equirectangular
/// Jacobian), plus [`UNIFORM_SHARE`] of the mean spread by solid angle.
/// Also returns ∫ lum(L) dω over the sphere (W m^-2 per unit of emitting
/// area across the beam).
pub fn sampling_tables(w: u32, h: u32, texels: &[[f32; 3]]) -> (Vec<f32>, f32) {
    let (wu, hu) = (w as usize, h as usize);
    let mut weights = vec![0.0f64; wu * hu];
    let mut integral = 0.0f64;
    for j in 0..hu {
        let omega = texel_solid_angle(j as u32, w, h) as f64;
        for i in 0..wu {
            let lum = Vec3::from(texels[j * wu + i]).dot(LUMINANCE) as f64;
            weights[j * wu + i] = lum * omega;
            integral += lum * omega;
        }
    }
    let uniform = UNIFORM_SHARE as f64 * integral.max(1e-30) / (4.0 * std::f64::consts::PI);
    for j in 0..hu {
        let omega = texel_solid_angle(j as u32, w, h) as f64;
        for i in 0..wu {
            weights[j * wu + i] += uniform * omega;
        }
    }
    let mut out = Vec::with_capacity(hu + 1 + hu * (wu + 1));
    let rows: Vec<f64> = (0..hu)
        .map(|j| weights[j * wu..(j + 1) * wu].iter().sum())
        .collect();
    let total: f64 = rows.iter().sum();
    let mut acc = 0.0;
    out.push(0.0);
    for r in &rows {
        acc += r;
        out.push((acc / total) as f32);
    }
    *out.last_mut().unwrap() = 1.0;
    for (j, r) in rows.iter().enumerate() {
        let mut acc = 0.0;
        out.push(0.0);
        for i in 0..wu {
            acc += weights[j * wu + i];
            out.push((acc / r) as f32);
        }
        *out.last_mut().unwrap() = 1.0;
    }
    (out, integral as f32)
}

/// Emitted power (W per channel) of an area light: π L A for a one-sided
/// rect, π L 4π r² for a sphere.
pub fn emitter_power(e: &Emitter) -> Vec3 {
    e.radiance * PI * emitter_area(&e.shape)
}

pub fn emitter_area(shape: &EmitterShape) -> f32 {
    match *shape {
        EmitterShape::Rect { size, .. } => size[0] * size[1],
        EmitterShape::Sphere { radius, .. } => 4.0 * PI * radius * radius,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equirect_round_trip() {
        for &(u, v) in &[(0.1, 0.3), (0.7, 0.9), (0.5, 0.5), (0.99, 0.01)] {
            let (u2, v2) = equirect_uv(equirect_dir(u, v));
            assert!((u - u2).abs() < 1e-5 && (v - v2).abs() < 1e-5, "{u} {v}");
        }
        assert!((equirect_dir(0.0, 0.0) - Vec3::Y).length() < 1e-6);
        assert!((equirect_dir(0.25, 0.5) - Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn texel_solid_angles_cover_the_sphere() {
        let (w, h) = (64, 32);
        let sum: f32 = (0..h).map(|j| texel_solid_angle(j, w, h) * w as f32).sum();
        assert!((sum - 4.0 * PI).abs() < 1e-4);
    }

    #[test]
    fn a_bright_blob_is_extracted_as_the_sun() {
        let (w, h) = (64u32, 32u32);
        let mut texels = vec![[1.0f32; 3]; (w * h) as usize];
        // Two texels near (u, v) = (0.5, 0.3), 1e4 times the sky.
        for i in [31usize, 32] {
            texels[9 * w as usize + i] = [1e4, 2e4, 3e4];
        }
        let sun = extract_sun(w, h, &texels).expect("a sun");
        let omega = texel_solid_angle(9, w, h);
        assert!(
            (sun.irradiance - Vec3::new(2e4, 4e4, 6e4) * omega).length()
                < 1e-2 * sun.irradiance.length()
        );
        let expected = equirect_dir(0.5, 9.5 / 32.0);
        assert!(sun.direction.dot(expected) > 0.9999, "{}", sun.direction);
        assert!(extract_sun(w, h, &vec![[1.0; 3]; (w * h) as usize]).is_none());
    }

    #[test]
    fn constant_table_integrates_to_four_pi_l() {
        let (w, h) = (32, 16);
        let texels = vec![[2.0; 3]; (w * h) as usize];
        let (cdf, integral) = sampling_tables(w, h, &texels);
        assert!((integral - 2.0 * 4.0 * PI).abs() < 1e-3);
        assert_eq!(cdf.len(), (h + 1 + h * (w + 1)) as usize);
        // Rows are weighted by their solid angle: the equator's row most.
        let p = |j: usize| cdf[j + 1] - cdf[j];
        assert!(p(8) > p(0) * 5.0);
    }
}
