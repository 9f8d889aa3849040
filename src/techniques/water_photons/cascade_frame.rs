//! Where the cascaded caustic maps lie: Eq. 1's light view over the water,
//! followed as the camera moves, and the water's bounds and wave data the
//! shaders need.

use super::cascades::{light_position, CascadeLayout, LightRange};
use crate::scene::Water;
use glam::{Mat4, Vec3};

/// Light view and cascades of one directional light over one water surface.
#[derive(Clone, Copy, Debug)]
pub struct CascadeFrame {
    pub view: Mat4,
    pub range: LightRange,
    pub layout: CascadeLayout,
}

impl CascadeFrame {
    /// Eq. 1's light view from `origin` (the camera position) along the
    /// light `dir`, far enough back that the whole water lies ahead; depth
    /// range over the water's bounds; cascade 0 `range` metres wide, or
    /// (range 0) so wide that cascade N − 1 covers the water.
    pub fn new(water: &Water, origin: Vec3, dir: Vec3, layout: CascadeLayout, range: f32) -> Self {
        let dir = dir.normalize();
        let (lo, hi) = water_bounds(water);
        let corners: Vec<Vec3> = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let behind = corners
            .iter()
            .map(|c| -(*c - origin).dot(dir))
            .fold(0.0f32, f32::max);
        let back = behind + 1.0;
        // `cascades::light_view` keeps +y up, which turns the texel grid
        // against the water's x/z grid under a high sun; up = +z (or +y for
        // a low sun) lines the two up, so the water fills the map.
        let up = if dir.y.abs() > 0.5 { Vec3::Z } else { Vec3::Y };
        let view = Mat4::look_to_rh(light_position(origin, dir, 0.0, back), dir, up);
        let local: Vec<Vec3> = corners.iter().map(|c| view.transform_point3(*c)).collect();
        // View space looks down −z: depth = −z.
        let near = local.iter().map(|p| -p.z).fold(f32::MAX, f32::min) - 0.5;
        let far = local.iter().map(|p| -p.z).fold(f32::MIN, f32::max) + 0.5;
        let half = local
            .iter()
            .map(|p| p.x.abs().max(p.y.abs()))
            .fold(0.0f32, f32::max)
            * 1.001;
        let width = if range > 0.0 {
            range
        } else {
            2.0 * half / layout.scale.powi(layout.levels as i32 - 1)
        };
        Self {
            view,
            range: LightRange {
                width,
                height: width,
                near: near.max(1e-3),
                far,
            },
            layout,
        }
    }

    /// Cascade c's world → clip (Eq. 2 × Eq. 1).
    pub fn view_proj(&self, c: u32) -> Mat4 {
        self.layout.projection(&self.range, c) * self.view
    }
}

/// `WpParams.water`: the material index, then (as f32 bits) the rest
/// height h, a bound on the surface slope |∇η| and the summed amplitude
/// Σ A, which size the water view's photon search (view.comp). For a sum
/// of Gerstner waves |∇η| ≤ Σ k A / (1 − Σ Q k A), k = 2π/λ (the crest
/// sharpened by the horizontal steepness Q; no folds while Σ Q k A < 1).
pub(super) fn water_uniform(water: &Water) -> [u32; 4] {
    let k = |w: &crate::scene::Wave| std::f32::consts::TAU / w.wavelength;
    let ka: f32 = water.waves.iter().map(|w| k(w) * w.amplitude).sum();
    let qka: f32 = water
        .waves
        .iter()
        .map(|w| w.steepness * k(w) * w.amplitude)
        .sum();
    let slope = ka / (1.0 - qka).max(0.1);
    let amplitude: f32 = water.waves.iter().map(|w| w.amplitude).sum();
    [
        water.material,
        water.base_height.to_bits(),
        slope.to_bits(),
        amplitude.to_bits(),
    ]
}

/// Axis-aligned bounds of a water surface over all times: the rest
/// rectangle grown by the waves' horizontal and vertical reach.
pub fn water_bounds(water: &Water) -> (Vec3, Vec3) {
    let vertical: f32 = water.waves.iter().map(|w| w.amplitude).sum();
    let horizontal: f32 = water.waves.iter().map(|w| w.amplitude * w.steepness).sum();
    let half = water.size * 0.5 + glam::Vec2::splat(horizontal);
    (
        Vec3::new(
            water.center.x - half.x,
            water.base_height - vertical,
            water.center.y - half.y,
        ),
        Vec3::new(
            water.center.x + half.x,
            water.base_height + vertical,
            water.center.y + half.y,
        ),
    )
}
