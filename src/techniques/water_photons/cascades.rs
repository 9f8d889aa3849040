//! Cascaded caustic maps (CCMs): their layout on the CPU, after Kougianos &
//! Moustakas 2021, "Large-scale ray traced water caustics in real-time using
//! cascaded caustic maps", §3.1 and Appendix A: plain arithmetic, in a
//! module of its own because the shaders mirror it and the tests check it.
//!
//! N cascades share one light view (Eq. 1) and one texture resolution
//! ccm_0 (Eq. 3); cascade c's orthographic projection covers s^c times the
//! light's range r (Eq. 2), so cascade c − 1 covers the central 1/s of
//! cascade c. Photons are emitted once per texel: all of cascade 0, and only
//! the border ring of cascades 1..N−1 (width ΔX, height ΔY, Eq. 6) whose
//! centre is already covered by the finer cascade (Algorithm 1). A texel of
//! cascade c covers s^(2c) times the area of a cascade-0 texel, so its
//! photon carries s^(2c) times the flux (Eq. 7).
//!
//! Deviations from the paper, all where it is ambiguous or off by one:
//! - Eq. 6 gives ΔX = ccm_0.x (1 − 1/s) / 2, not always an integer. We take
//!   ΔX = round(ccm_0.x (1 − 1/s) / 2) (halves up), which is exactly the
//!   number of texels per side whose centre lies outside the finer cascade's
//!   region (texel centres are where photons are sampled, Algorithm 3
//!   line 8); a texel whose centre lies on the region's edge, possible only
//!   when the unrounded value is a half-integer, goes to the coarser cascade.
//!   Same for ΔY.
//! - Eq. 4, ccm_i = ccm_0 (1 − 1/s²), is then the ring's area
//!   W H − (W − 2ΔX)(H − 2ΔY): equal whenever Eq. 6 is integral (every power
//!   of two ccm_0 ≥ 8 with s = 2 or 4), else the exact count of the ring.
//! - Eq. 5 sums i = 0..N; there are N cascades, i = 0..N−1.
//! - Algorithm 1: line 24 must subtract Region0 (not Region1), line 33
//!   Region1 (not Region0); line 26 must test x ≥ ΔX (with x > ΔX column ΔX,
//!   inside the finer cascade, would be dispatched and column W − ΔX never);
//!   the loop of lines 16-39 runs over cascades 1..N−1 (bound[N] does not
//!   exist). Every level's texel coordinates are in ccm_0 (one texture array).
//! - Eq. 2's third row is garbled in print; we use the standard orthographic
//!   map of depth near..far to 0..1 (glam's `orthographic_rh`, Vulkan).

use anyhow::{ensure, Result};
use glam::{Mat4, Vec3};

/// The extent of a directional light's view: width and height (m) of the
/// innermost cascade, and its depth range along the light (m), r in §3.1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightRange {
    pub width: f32,
    pub height: f32,
    pub near: f32,
    pub far: f32,
}

/// Eq. 3: the innermost cascade's resolution (square) from the light's
/// range and the CCM precision p (m per texel asked): the smallest of 256,
/// 512, 1024 covering r_max / p texels, at most 2048.
pub fn inner_cascade_size(range: &LightRange, precision: f32) -> u32 {
    let texels = range.width.max(range.height) / precision;
    if texels < 256.0 {
        256
    } else if texels < 512.0 {
        512
    } else if texels < 1024.0 {
        1024
    } else {
        2048
    }
}

/// Eq. 1: the light's position, l_pos = o − l_dir (z_near + z_far): back from
/// the camera origin `o` along the light's unit direction by the depth of the
/// camera's view frustum, so the light view sees everything the camera does.
pub fn light_position(camera_origin: Vec3, light_dir: Vec3, z_near: f32, z_far: f32) -> Vec3 {
    camera_origin - light_dir * (z_near + z_far)
}

/// The light view matrix shared by every cascade (§3.1): at [`light_position`],
/// looking along the unit `light_dir`, up +y (or +z when the light is vertical).
pub fn light_view(camera_origin: Vec3, light_dir: Vec3, z_near: f32, z_far: f32) -> Mat4 {
    let up = if light_dir.cross(Vec3::Y).length() > 1e-3 {
        Vec3::Y
    } else {
        Vec3::Z
    };
    Mat4::look_to_rh(
        light_position(camera_origin, light_dir, z_near, z_far),
        light_dir,
        up,
    )
}

/// The cascades of one light: resolution, count and scale factor, and the
/// dispatch layout derived from them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeLayout {
    /// ccm_0: texels (x, y) of every cascade (one texture array layer each).
    pub size: [u32; 2],
    /// N, the number of cascades.
    pub levels: u32,
    /// s > 1: each cascade covers s times the extent of the previous one.
    pub scale: f32,
    /// (ΔX, ΔY) of Eq. 6, rounded (module docs): the ring's width in texels.
    pub border: [u32; 2],
}

impl CascadeLayout {
    /// A layout of `levels` cascades of `size` texels, each `scale` times the
    /// extent of the previous one. Rejects zero sizes or levels, a scale
    /// not above 1, and (with more than one level) a scale so close to 1
    /// that the ring of Eq. 6 is empty.
    pub fn new(size: [u32; 2], levels: u32, scale: f32) -> Result<Self> {
        ensure!(
            size[0] > 0 && size[1] > 0,
            "cascade size must be positive, got {size:?}"
        );
        ensure!(levels >= 1, "at least one cascade is needed");
        ensure!(
            scale.is_finite() && scale > 1.0,
            "cascade scale factor must be above 1, got {scale}"
        );
        // Eq. 6, rounded halves up (module docs); at most half the side, which
        // an odd side would exceed for a scale so large that 1 - 1/s rounds
        // to 1.
        let border = size.map(|n| {
            ((n as f64 * (1.0 - 1.0 / scale as f64) * 0.5 + 0.5).floor() as u32).min(n / 2)
        });
        let layout = Self {
            size,
            levels,
            scale,
            border,
        };
        ensure!(
            levels == 1 || layout.ring_threads() > 0,
            "cascade scale factor {scale} leaves no border ring on {size:?} texels"
        );
        Ok(layout)
    }

    fn ring_threads(&self) -> u64 {
        let [w, h] = self.size.map(u64::from);
        let [dx, dy] = self.border.map(u64::from);
        w * h - (w - 2 * dx) * (h - 2 * dy)
    }

    /// Eq. 4: threads dispatched for cascade `c`: every texel of cascade 0,
    /// the border ring W H − (W − 2ΔX)(H − 2ΔY) (= ccm_0 (1 − 1/s²) when ΔX
    /// and ΔY are integral) of the others.
    pub fn threads_in(&self, c: u32) -> u64 {
        if c == 0 {
            self.size[0] as u64 * self.size[1] as u64
        } else {
            self.ring_threads()
        }
    }

    /// Eq. 5: threads dispatched for all cascades, Σ_{c=0}^{N−1} ccm_c.
    pub fn total_threads(&self) -> u64 {
        (0..self.levels).map(|c| self.threads_in(c)).sum()
    }

    /// Algorithm 1 (corrected, module docs): thread `thread` of the
    /// [`total_threads`](Self::total_threads) dispatch → (texel (x, y), cascade c).
    /// Threads of cascade 0 fill its texels row by row; each further
    /// cascade's threads fill its ring: ΔY full rows at the top (Region0),
    /// then ΔX columns at each side of the remaining H − 2ΔY rows
    /// (Region1), then ΔY full rows at the bottom. `None` past the end.
    pub fn texel_of(&self, thread: u64) -> Option<([u32; 2], u32)> {
        let [w, h] = self.size.map(u64::from);
        let [dx, dy] = self.border.map(u64::from);
        if thread < w * h {
            return Some(([(thread % w) as u32, (thread / w) as u32], 0));
        }
        let ring = self.ring_threads();
        if ring == 0 {
            return None;
        }
        let beyond = thread - w * h;
        let cascade = 1 + beyond / ring;
        if cascade >= self.levels as u64 {
            return None;
        }
        let local = beyond % ring;
        let region0 = w * dy;
        let region1 = region0 + 2 * dx * (h - 2 * dy);
        let (x, y) = if local < region0 {
            (local % w, local / w)
        } else if local < region1 {
            let l = local - region0;
            let mut x = l % (2 * dx);
            if x >= dx {
                // The right-hand column block starts at W − ΔX.
                x += w - 2 * dx;
            }
            (x, dy + l / (2 * dx))
        } else {
            let l = local - region1;
            (l % w, h - dy + l / w)
        };
        Some(([x as u32, y as u32], cascade as u32))
    }

    /// Eq. 7: the light's intensity scale for cascade `c`, s^(2c): a texel of
    /// cascade c covers s^(2c) times the area of a cascade-0 texel, so a
    /// photon through it carries s^(2c) times the flux.
    pub fn intensity_scale(&self, c: u32) -> f32 {
        self.scale.powi(2 * c as i32)
    }

    /// Eq. 2: cascade `c`'s orthographic projection, covering r.width s^c ×
    /// r.height s^c around the light's axis and depths r.near..r.far along it
    /// (to 0..1). Texel (x, y) of the cascade has its centre at NDC
    /// (2 (x + ½) / W − 1, 2 (y + ½) / H − 1).
    pub fn projection(&self, range: &LightRange, c: u32) -> Mat4 {
        let grow = self.scale.powi(c as i32);
        let (hw, hh) = (0.5 * range.width * grow, 0.5 * range.height * grow);
        Mat4::orthographic_rh(-hw, hw, -hh, hh, range.near, range.far)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every thread maps to a unique (texel, cascade); the dispatched texels
    /// of cascade c ≥ 1 are exactly those whose centre lies outside the
    /// region covered by cascade c − 1, found through the projections of
    /// Eq. 2 (texel centre of cascade c → world → NDC of cascade c − 1);
    /// counts follow Eqs. 4-5.
    fn check(layout: &CascadeLayout, eq4_exact: bool) {
        let [w, h] = layout.size;
        let range = LightRange {
            width: 300.0,
            height: 200.0,
            near: 1.0,
            far: 500.0,
        };
        let view = light_view(
            Vec3::new(3.0, 10.0, -4.0),
            Vec3::new(0.3, -1.0, 0.2).normalize(),
            0.1,
            400.0,
        );
        let plane = (w as usize) * (h as usize);
        let mut seen = vec![false; plane * layout.levels as usize];
        let total = layout.total_threads();
        for thread in 0..total {
            let ([x, y], c) = layout
                .texel_of(thread)
                .unwrap_or_else(|| panic!("thread {thread} of {total} unmapped"));
            assert!(
                x < w && y < h && c < layout.levels,
                "{layout:?}: thread {thread}"
            );
            let slot = c as usize * plane + y as usize * w as usize + x as usize;
            assert!(
                !seen[slot],
                "{layout:?}: texel ({x}, {y}) of cascade {c} twice"
            );
            seen[slot] = true;
        }
        assert_eq!(layout.texel_of(total), None);

        // Cascade c's texel centres in cascade c − 1's NDC: the same 1/s scaling for every c.
        let to_finer: Vec<Mat4> = (1..layout.levels)
            .map(|c| {
                layout.projection(&range, c - 1)
                    * view
                    * (layout.projection(&range, c) * view).inverse()
            })
            .collect();
        for c in 0..layout.levels {
            let mut dispatched = 0u64;
            for y in 0..h {
                for x in 0..w {
                    let hit = seen[c as usize * plane + (y * w + x) as usize];
                    dispatched += hit as u64;
                    if c == 0 {
                        assert!(hit, "cascade 0 texel ({x}, {y}) not dispatched");
                        continue;
                    }
                    let ndc = Vec3::new(
                        2.0 * (x as f32 + 0.5) / w as f32 - 1.0,
                        2.0 * (y as f32 + 0.5) / h as f32 - 1.0,
                        0.5,
                    );
                    let finer = to_finer[c as usize - 1].project_point3(ndc);
                    let edge = 1e-4;
                    let inside = finer.x.abs() < 1.0 - edge && finer.y.abs() < 1.0 - edge;
                    let outside = finer.x.abs() > 1.0 + edge || finer.y.abs() > 1.0 + edge;
                    assert!(
                        !inside || !hit,
                        "{layout:?}: cascade {c} texel ({x}, {y}) covered by cascade {} yet dispatched",
                        c - 1
                    );
                    assert!(
                        hit || !outside,
                        "{layout:?}: cascade {c} texel ({x}, {y}) outside cascade {} yet not dispatched",
                        c - 1
                    );
                }
            }
            assert_eq!(dispatched, layout.threads_in(c), "{layout:?} cascade {c}");
            if c > 0 && eq4_exact {
                // Eq. 4 as printed: ccm_0 (1 − 1/s²).
                let eq4 = w as f64 * h as f64 * (1.0 - 1.0 / (layout.scale as f64).powi(2));
                assert_eq!(dispatched as f64, eq4, "{layout:?}");
            }
        }
        let eq5: u64 = (0..layout.levels).map(|c| layout.threads_in(c)).sum();
        assert_eq!(total, eq5);
    }

    #[test]
    fn algorithm_1_covers_each_texel_once_for_the_papers_settings() {
        for size in [256, 512, 1024, 2048] {
            for scale in [2.0, 4.0] {
                for levels in 1..=4 {
                    let layout = CascadeLayout::new([size, size], levels, scale).unwrap();
                    // Eq. 6 is integral here: ΔX = size (1 − 1/s) / 2.
                    assert_eq!(
                        layout.border[0] as f32,
                        size as f32 * (1.0 - 1.0 / scale) / 2.0
                    );
                    check(&layout, true);
                }
            }
        }
    }

    #[test]
    fn rounding_of_eq_6_keeps_the_ring_exact() {
        // Non-integral ΔX, ΔY, non-square maps, non-integral s.
        for (size, scale) in [
            ([256, 256], 3.0),
            ([300, 170], 2.0),
            ([257, 129], 4.0),
            ([64, 48], 1.7),
            ([10, 6], 5.0),
        ] {
            let layout = CascadeLayout::new(size, 3, scale).unwrap();
            check(&layout, false);
        }
        // Eq. 6 rounded: 7 (1 − 1/2) / 2 = 1.75 → 2; 6 (1 − 1/2) / 2 = 1.5 → 2
        // (a half: the texel centred on the edge goes to the coarser cascade);
        // 10 (1 − 1/5) / 2 = 4; 6 (1 − 1/5) / 2 = 2.4 → 2.
        let half = CascadeLayout::new([7, 6], 2, 2.0).unwrap();
        assert_eq!(half.border, [2, 2]);
        check(&half, false);
        assert_eq!(CascadeLayout::new([10, 6], 2, 5.0).unwrap().border, [4, 2]);
        // 1 - 1/s rounds to 1: the ring stays within an odd side.
        assert_eq!(CascadeLayout::new([5, 7], 2, 1e30).unwrap().border, [2, 3]);
    }

    #[test]
    fn bad_layouts_are_refused() {
        assert!(CascadeLayout::new([0, 256], 2, 2.0).is_err());
        assert!(CascadeLayout::new([256, 256], 0, 2.0).is_err());
        for scale in [1.0, 0.5, f32::NAN, f32::INFINITY] {
            assert!(CascadeLayout::new([256, 256], 2, scale).is_err(), "{scale}");
        }
        // 1 − 1/1.01 of 16 texels is under a texel: no ring to dispatch.
        let err = CascadeLayout::new([16, 16], 2, 1.01).unwrap_err();
        assert!(err.to_string().contains("no border ring"), "{err}");
        assert!(CascadeLayout::new([16, 16], 1, 1.01).is_ok());
    }

    #[test]
    fn eq_3_picks_the_inner_size_from_range_and_precision() {
        let range = |r: f32| LightRange {
            width: r,
            height: r / 2.0,
            near: 0.0,
            far: 1.0,
        };
        assert_eq!(inner_cascade_size(&range(500.0), 2.0), 256);
        assert_eq!(inner_cascade_size(&range(511.0), 1.0), 512);
        assert_eq!(inner_cascade_size(&range(512.0), 1.0), 1024);
        assert_eq!(inner_cascade_size(&range(2047.0), 2.0), 1024);
        // The paper's §4 setting: r = 3000, p = 2 → 2048.
        assert_eq!(inner_cascade_size(&range(3000.0), 2.0), 2048);
        assert_eq!(inner_cascade_size(&range(1e6), 1.0), 2048);
    }

    #[test]
    fn eq_7_scales_by_texel_area() {
        let layout = CascadeLayout::new([512, 512], 4, 2.0).unwrap();
        assert_eq!(
            (0..4)
                .map(|c| layout.intensity_scale(c))
                .collect::<Vec<_>>(),
            [1.0, 4.0, 16.0, 64.0]
        );
        let layout = CascadeLayout::new([512, 512], 3, 4.0).unwrap();
        assert_eq!(layout.intensity_scale(2), 256.0);
    }

    #[test]
    fn eq_1_and_2_place_and_size_the_light_view() {
        let o = Vec3::new(1.0, 2.0, 3.0);
        let dir = Vec3::new(0.0, -0.6, -0.8);
        let pos = light_position(o, dir, 0.5, 99.5);
        assert!((pos - (o - dir * 100.0)).length() < 1e-4);
        let view = light_view(o, dir, 0.5, 99.5);
        // The camera origin lies on the light's axis, 100 m ahead.
        let local = view.transform_point3(o);
        assert!(
            local.truncate().length() < 1e-3 && (local.z + 100.0).abs() < 1e-3,
            "{local}"
        );
        // Straight down works too (up falls back to +z).
        let down = light_view(o, Vec3::NEG_Y, 0.5, 9.5);
        assert!(down.is_finite());

        let range = LightRange {
            width: 40.0,
            height: 20.0,
            near: 10.0,
            far: 210.0,
        };
        let layout = CascadeLayout::new([256, 256], 3, 4.0).unwrap();
        for c in 0..3 {
            let p = layout.projection(&range, c);
            let grow = 4f32.powi(c as i32);
            // Half-extents r s^c / 2 to NDC ±1; depths near..far (−z in view space) to 0..1.
            let corner = p.project_point3(Vec3::new(20.0 * grow, -10.0 * grow, -10.0));
            assert!(
                (corner - Vec3::new(1.0, -1.0, 0.0)).length() < 1e-5,
                "{corner}"
            );
            let far = p.project_point3(Vec3::new(0.0, 0.0, -210.0));
            assert!((far.z - 1.0).abs() < 1e-5, "{far}");
        }
    }
}
