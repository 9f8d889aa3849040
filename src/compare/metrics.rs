//! Image metrics shared by `caustics compare` and the tests, so the two
//! cannot disagree: the display transform on the CPU, FLIP (NVIDIA's
//! `nv-flip`, the authors' implementation), relative energy and RMSE.
//!
//! FLIP here is **LDR-FLIP** after the project's fixed display transform
//! (glsl/common/tonemap.glsl: radiance × exposure, Reinhard x / (1 + x),
//! sRGB, 8 bits) at the scene's exposure: what a viewer of the PNGs sees.
//! It is not HDR-FLIP (the authors' exposure sweep): the display transform
//! already compresses the whole range into the image, and one transform
//! keeps the number comparable to the tests' bounds.

/// glsl/common/tonemap.glsl on the CPU: RGBA f32 radiance to RGBA8 sRGB.
/// Negative radiance (a difference of two images) reads as 0.
pub fn tonemap(rgba: &[f32], exposure: f32) -> Vec<u8> {
    let encode = |l: f32| {
        let x = (l * exposure).max(0.0);
        let x = x / (1.0 + x);
        let s = if x <= 0.0031308 {
            x * 12.92
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        };
        (s.clamp(0.0, 1.0) * 255.0).round() as u8
    };
    rgba.chunks(4)
        .flat_map(|p| [encode(p[0]), encode(p[1]), encode(p[2]), 255])
        .collect()
}

/// RGB8 from RGBA8.
pub fn rgb8(rgba: &[u8]) -> Vec<u8> {
    rgba.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect()
}

/// Opaque RGBA8 from RGB8.
pub fn rgba8(rgb: &[u8]) -> Vec<u8> {
    rgb.chunks(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect()
}

/// A FLIP error map: one value in [0, 1] per pixel.
pub struct FlipMap {
    pub width: u32,
    pub height: u32,
    map: nv_flip::FlipImageFloat,
}

impl FlipMap {
    /// The map through the authors' magma colour map, RGB8 (the colour
    /// scale of the FLIP paper's figures).
    pub fn magma_rgb8(&self) -> Vec<u8> {
        self.map.apply_color_lut(&nv_flip::magma_lut()).to_vec()
    }

    /// The per-pixel errors, row by row.
    pub fn values(&self) -> Vec<f32> {
        self.map.to_vec()
    }
}

/// FLIP mean error (nv-flip at its default 67 pixels per degree) of `test`
/// against `reference`, both tonemapped RGBA8 of `width` x `height`, and
/// the error map.
pub fn flip(test: &[u8], reference: &[u8], width: u32, height: u32) -> (f32, FlipMap) {
    let t = nv_flip::FlipImageRgb8::with_data(width, height, &rgb8(test));
    let r = nv_flip::FlipImageRgb8::with_data(width, height, &rgb8(reference));
    let map = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mean = nv_flip::FlipPool::from_image(&map).mean();
    (mean, FlipMap { width, height, map })
}

/// Sum of r + g + b over an RGBA image (its total energy up to a constant).
pub fn energy(rgba: &[f32]) -> f64 {
    rgba.chunks(4)
        .map(|p| p[0] as f64 + p[1] as f64 + p[2] as f64)
        .sum()
}

/// (energy(test) − energy(reference)) / energy(reference): signed, 0 for
/// equal totals; 0 when both are black, None (undefined) when only the
/// reference is.
pub fn relative_energy(test: &[f32], reference: &[f32]) -> Option<f64> {
    let (t, r) = (energy(test), energy(reference));
    if r == 0.0 {
        return (t == 0.0).then_some(0.0);
    }
    Some((t - r) / r)
}

/// Root mean square of the rgb differences, in radiance units.
pub fn rmse(test: &[f32], reference: &[f32]) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (a, b) in test.chunks(4).zip(reference.chunks(4)) {
        for c in 0..3 {
            let d = a[c] as f64 - b[c] as f64;
            sum += d * d;
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        (sum / n as f64).sqrt()
    }
}

/// A test image against a reference image of the same size.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Metrics {
    /// LDR-FLIP mean at the scene's exposure (module docs).
    pub flip: f32,
    /// `relative_energy`: signed; None (JSON null) when the reference is
    /// black and the test image is not.
    pub energy: Option<f64>,
    pub rmse: f64,
}

/// Every metric of `test` against `reference` (RGBA f32, `width` x
/// `height`), FLIP after the display transform at `exposure`; with the
/// FLIP map.
pub fn compare(
    test: &[f32],
    reference: &[f32],
    width: u32,
    height: u32,
    exposure: f32,
) -> (Metrics, FlipMap) {
    let (flip_mean, map) = flip(
        &tonemap(test, exposure),
        &tonemap(reference, exposure),
        width,
        height,
    );
    (
        Metrics {
            flip: flip_mean,
            energy: relative_energy(test, reference),
            rmse: rmse(test, reference),
        },
        map,
    )
}

/// The second half of a progressive run from the whole and the first half
/// (equal photon counts): whole = (a + b) / 2, so b = 2 whole − a. The two
/// halves are independent estimates; their difference is the reference's
/// own noise.
pub fn second_half(whole: &[f32], first_half: &[f32]) -> Vec<f32> {
    whole
        .iter()
        .zip(first_half)
        .map(|(w, a)| 2.0 * w - a)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_against_itself_scores_zero() {
        let img: Vec<f32> = (0..16 * 16 * 4).map(|i| (i % 7) as f32 * 0.1).collect();
        let (m, _) = compare(&img, &img, 16, 16, 1.0);
        assert_eq!((m.flip, m.energy, m.rmse), (0.0, Some(0.0), 0.0));
    }

    #[test]
    fn energy_and_rmse_measure_what_they_say() {
        let reference = vec![1.0f32; 4 * 4];
        let brighter: Vec<f32> = reference.iter().map(|v| v * 1.5).collect();
        assert!((relative_energy(&brighter, &reference).unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(relative_energy(&brighter, &[0.0; 16]), None);
        assert_eq!(relative_energy(&[0.0; 16], &[0.0; 16]), Some(0.0));
        assert!((rmse(&brighter, &reference) - 0.5).abs() < 1e-12);
        let (m, _) = compare(&brighter, &reference, 2, 2, 1.0);
        assert!(m.flip > 0.0);
    }

    #[test]
    fn tonemap_matches_the_shader_formula_at_its_ends() {
        assert_eq!(tonemap(&[0.0, 1e9, -1.0, 1.0], 1.0), vec![0, 255, 0, 255]);
        // x = 1: Reinhard 0.5, sRGB 0.7354 -> 188.
        assert_eq!(tonemap(&[1.0, 0.5, 0.25, 1.0], 1.0)[0], 188);
        assert_eq!(tonemap(&[0.5, 0.0, 0.0, 1.0], 2.0)[0], 188);
    }
}
