//! Albedo textures: decoding image files into linear RGB, and the CPU side
//! of the GPU texture array (every texture resized to one square layer
//! size, with its mip chain).
//!
//! Lavapipe 22.3 has no descriptor indexing, so the shaders cannot index an
//! array of differently sized textures: all albedo textures share one 2D
//! array image (docs/ARCHITECTURE.md, "Albedo textures").

use super::types::Texture;
use glam::Vec3;
use image::imageops::{self, FilterType};
use image::{DynamicImage, ImageDecoder, ImageReader, Rgba32FImage};
use std::io::{BufRead, Seek};
use std::path::Path;

/// Largest layer of the texture array (texels per side): larger files are
/// scaled down to it.
pub const MAX_LAYER_SIZE: u32 = 1024;

/// The sRGB transfer function's inverse (IEC 61966-2-1): an 8-bit code
/// value `c` / 255 to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads a PNG, JPEG or EXR file. 8- and 16-bit
/// integer images are sRGB-encoded and decoded to linear; float images
/// (EXR) are linear already. Alpha, when the file has it, is kept as it is
/// (coverage, never sRGB-encoded) for cut-outs. The error says why.
pub fn load(path: &Path) -> Result<Texture, String> {
    crate::scene::input::check_regular(path)
        .map_err(|e| format!("cannot open texture {}: {e}", path.display()))?;
    let reader = ImageReader::open(path)
        .map_err(|e| format!("cannot open texture {}: {e}", path.display()))?
        .with_guessed_format()
        .map_err(|e| format!("cannot read texture {}: {e}", path.display()))?;
    from_image(decode_limited(reader, path, &TEXTURE_LIMITS)?, path)
}

/// An image file's bytes held in memory (a glTF image in a buffer view or
/// a `data:` URI), decoded as [`load`] decodes a file; `name` stands for
/// the path in the texture and its errors.
pub fn decode(bytes: &[u8], name: &Path) -> Result<Texture, String> {
    let reader = ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read texture {}: {e}", name.display()))?;
    from_image(decode_limited(reader, name, &TEXTURE_LIMITS)?, name)
}

/// What decoding one kind of image file may take (docs/SCENES.md,
/// "Limits"): checked against the file's header before the decoder
/// allocates its pixels, and given to the decoder as `image::Limits`.
#[derive(Clone, Copy, Debug)]
pub struct DecodeLimits {
    /// The kind of image, in messages ("texture").
    pub what: &'static str,
    /// Most texels per side.
    pub side: u32,
    /// Most bytes of decoded pixels (the decoder's own allocation).
    pub bytes: u64,
}

/// Albedo textures: 16384 per side, as the largest 2D image of most GPUs
/// (larger files are box-filtered down anyway, [`MAX_DECODED_SIDE`]), and
/// 1 GiB of decoded pixels (a 16384² RGBA8 image; an 8192² 16-bit RGBA or
/// a 4096 x 8192 float RGBA one).
pub const TEXTURE_LIMITS: DecodeLimits = DecodeLimits {
    what: "texture",
    side: 16384,
    bytes: 1 << 30,
};

/// Environment images: 8192 per side and 512 MiB of decoded pixels, an 8K
/// equirectangular image (8192 x 4096) of float RGBA. Larger ones are
/// refused rather than downsampled: a sun a few texels wide would lose its
/// peak, and with it the caustics it casts.
pub const ENVIRONMENT_LIMITS: DecodeLimits = DecodeLimits {
    what: "environment image",
    side: 8192,
    bytes: 512 << 20,
};

/// Decodes `reader`'s image within `limits`: its header's size is checked
/// first (a small file may declare a huge image), the message naming the
/// file, its size and the limit; then the decoder runs under the same
/// limits as `image::Limits`.
pub fn decode_limited<R: BufRead + Seek>(
    mut reader: ImageReader<R>,
    name: &Path,
    limits: &DecodeLimits,
) -> Result<DynamicImage, String> {
    let what = limits.what;
    let cannot = |e: image::ImageError| format!("cannot decode {what} {}: {e}", name.display());
    let mut header = image::Limits::default();
    header.max_alloc = Some(limits.bytes);
    reader.limits(header);
    let mut decoder = reader.into_decoder().map_err(cannot)?;
    let (width, height) = decoder.dimensions();
    if width.max(height) > limits.side {
        return Err(format!(
            "{what} {} is {width}x{height}, larger than {} texels per side, the most a {what} may have (docs/SCENES.md, \"Limits\")",
            name.display(),
            limits.side
        ));
    }
    let bytes = decoder.total_bytes();
    if bytes > limits.bytes {
        return Err(format!(
            "{what} {} is {width}x{height} of {:?}: decoded it takes {} MiB, more than {} MiB, the most a {what} may take (docs/SCENES.md, \"Limits\")",
            name.display(),
            decoder.color_type(),
            bytes.div_ceil(1 << 20),
            limits.bytes >> 20
        ));
    }
    let mut full = image::Limits::default();
    full.max_image_width = Some(limits.side);
    full.max_image_height = Some(limits.side);
    full.max_alloc = Some(limits.bytes);
    decoder.set_limits(full).map_err(cannot)?;
    DynamicImage::from_decoder(decoder).map_err(cannot)
}

/// A vector of `len` elements reserved up front: memory that cannot be
/// had is an error naming `what` and the size, not an abort.
pub fn reserved<T>(len: usize, what: impl FnOnce() -> String) -> Result<Vec<T>, String> {
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| {
        format!(
            "{}: cannot allocate {} MiB",
            what(),
            (len * std::mem::size_of::<T>()).div_ceil(1 << 20)
        )
    })?;
    Ok(v)
}

/// Rows converted to floats at a time, so that no full-size float copy of
/// the decoded image is made besides the texture's own texels.
const STRIP_ROWS: u32 = 64;

/// Largest side a decoded texture keeps before its float copies are made
/// (4 x MAX_LAYER_SIZE, so the layer's own filtering still has 4 texels per
/// texel to average): an 8192² PNG of 261 KB took 4.3 GB as floats and
/// mip chain, a 16384 x 8192 one aborted (issue 31).
pub const MAX_DECODED_SIDE: u32 = 4 * MAX_LAYER_SIZE;

/// `decoded` box-filtered by the smallest whole factor that brings both
/// sides to [`MAX_DECODED_SIDE`] or below, in linear values (8- and 16-bit
/// images are sRGB: averaging their codes would darken every contrast),
/// a strip of rows at a time so that no full-size float copy is made.
/// Smaller images are returned as they are.
fn shrink_large(decoded: DynamicImage) -> DynamicImage {
    let (w, h) = (decoded.width(), decoded.height());
    let k = w.max(h).div_ceil(MAX_DECODED_SIDE);
    if k <= 1 {
        return decoded;
    }
    let linear = matches!(
        decoded,
        DynamicImage::ImageRgb32F(_) | DynamicImage::ImageRgba32F(_)
    );
    let (nw, nh) = (w.div_ceil(k), h.div_ceil(k));
    let mut out = Rgba32FImage::new(nw, nh);
    for oy in 0..nh {
        let rows = k.min(h - oy * k);
        let strip = decoded.crop_imm(0, oy * k, w, rows).into_rgba32f();
        for ox in 0..nw {
            let cols = k.min(w - ox * k);
            let mut sum = [0.0f64; 4];
            for y in 0..rows {
                for x in ox * k..ox * k + cols {
                    let p = strip.get_pixel(x, y).0;
                    for c in 0..4 {
                        let v = if linear || c == 3 {
                            p[c]
                        } else {
                            srgb_to_linear(p[c])
                        };
                        sum[c] += v as f64;
                    }
                }
            }
            let n = (rows * cols) as f64;
            out.put_pixel(ox, oy, image::Rgba(sum.map(|v| (v / n) as f32)));
        }
    }
    DynamicImage::ImageRgba32F(out)
}

fn from_image(decoded: DynamicImage, path: &Path) -> Result<Texture, String> {
    let (width, height) = (decoded.width(), decoded.height());
    if width == 0 || height == 0 {
        return Err(format!("texture {} is empty", path.display()));
    }
    let has_alpha = decoded.color().has_alpha();
    let decoded = shrink_large(decoded);
    let (width, height) = (decoded.width(), decoded.height());
    let linear = matches!(
        decoded,
        DynamicImage::ImageRgb32F(_) | DynamicImage::ImageRgba32F(_)
    );
    // At most MAX_DECODED_SIDE² texels: 12 bytes each, 4 more with alpha
    // (256 MiB at the most), reserved before any is converted.
    let count = width as usize * height as usize;
    let size = || format!("texture {} ({width}x{height})", path.display());
    let mut texels: Vec<[f32; 3]> = reserved(count, size)?;
    let mut alpha: Vec<f32> = reserved(if has_alpha { count } else { 0 }, size)?;
    for top in (0..height).step_by(STRIP_ROWS as usize) {
        let rows = STRIP_ROWS.min(height - top);
        let strip = decoded.crop_imm(0, top, width, rows).into_rgba32f();
        for p in strip.pixels() {
            let rgb = [p.0[0], p.0[1], p.0[2]];
            texels.push(if linear { rgb } else { rgb.map(srgb_to_linear) });
            if has_alpha {
                alpha.push(p.0[3]);
            }
        }
    }
    if let Some(i) = alpha.iter().position(|a| !(0.0..=1.0).contains(a)) {
        return Err(format!(
            "texture {}: texel {i} has alpha {}, outside [0, 1]",
            path.display(),
            alpha[i]
        ));
    }
    if alpha.iter().all(|&a| a == 1.0) {
        alpha.clear();
    }
    if let Some(i) = texels.iter().position(|t| !Vec3::from(*t).is_finite()) {
        return Err(format!(
            "texture {}: texel {i} is not finite",
            path.display()
        ));
    }
    // An albedo is a reflectance: outside [0, 1] it breaks energy
    // conservation (and above 65504 the RGBA16F array would hold +Inf).
    if let Some(i) = texels
        .iter()
        .position(|t| t.iter().any(|c| !(0.0..=1.0).contains(c)))
    {
        return Err(format!(
            "texture {}: texel {i} is {:?}, outside [0, 1] (an albedo)",
            path.display(),
            texels[i]
        ));
    }
    Ok(Texture {
        path: path.to_path_buf(),
        width,
        height,
        texels,
        alpha,
    })
}

/// Side of the texture array's layers for `textures`: the largest width or
/// height among them rounded up to a power of two, at most
/// [`MAX_LAYER_SIZE`]; 1 without textures.
pub fn layer_size(textures: &[Texture]) -> u32 {
    let largest = textures
        .iter()
        .map(|t| t.width.max(t.height))
        .max()
        .unwrap_or(1);
    largest.next_power_of_two().min(MAX_LAYER_SIZE)
}

/// The mip chain of `texture` resized to `size` x `size` (a power of two):
/// level 0 resampled with a triangle (bilinear) filter, each next level the
/// 2x2 box average of the one before, down to 1x1. RGBA (alpha 1 without
/// one in the file), rows top to bottom. Filtering happens on linear values,
/// as it must for radiometry; alpha is coverage, filtered the same way.
///
/// With alpha (cut-outs), colour is filtered **coverage-weighted**
/// (premultiplied: colour = Σ α c / Σ α), so a texel on a cut-out's edge
/// takes the colour of its kept part only; and every texel without
/// coverage whose neighbours have some takes their coverage-weighted
/// colour ([`dilate_into_transparent`]), so the shader's bilinear taps
/// across the edge blend no colour of the cut-away texels into what stays.
///
/// One RGBA float copy of the texture is alive at a time besides the chain
/// (16 bytes a texel: 256 MiB for the largest, [`MAX_DECODED_SIDE`]²).
pub fn mip_chain(texture: &Texture, size: u32) -> Vec<Vec<[f32; 4]>> {
    let has_alpha = !texture.alpha.is_empty();
    // The texture at `size` x `size`, its colour premultiplied by alpha or not.
    let level0_of = |premultiplied: bool| -> Vec<[f32; 4]> {
        let texels = texture.texels.iter().enumerate().map(|(i, t)| {
            let t = [
                t[0],
                t[1],
                t[2],
                texture.alpha.get(i).copied().unwrap_or(1.0),
            ];
            if premultiplied {
                premultiply(t)
            } else {
                t
            }
        });
        if (texture.width, texture.height) == (size, size) {
            return texels.collect();
        }
        let flat: Vec<f32> = texels.flatten().collect();
        let image = Rgba32FImage::from_raw(texture.width, texture.height, flat)
            .expect("texel count matches the size");
        imageops::resize(&image, size, size, FilterType::Triangle)
            .pixels()
            .map(|p| p.0)
            .collect()
    };
    let side = size as usize;
    let mut level0 = level0_of(false);
    if has_alpha {
        let weighted = level0_of(true);
        for (t, w) in level0.iter_mut().zip(&weighted) {
            *t = unpremultiply(*w, *t);
        }
        dilate_into_transparent(&mut level0, side);
    }
    let mut levels = vec![level0];
    let mut side = side;
    while side > 1 {
        let prev = levels.last().expect("level 0 exists");
        let half = side / 2;
        let mut next = Vec::with_capacity(half * half);
        for y in 0..half {
            for x in 0..half {
                let mut sum = [0.0f32; 4];
                let mut weighted = [0.0f32; 4];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let t = prev[(2 * y + dy) * side + 2 * x + dx];
                    let w = premultiply(t);
                    for c in 0..4 {
                        sum[c] += 0.25 * t[c];
                        weighted[c] += 0.25 * w[c];
                    }
                }
                next.push(if has_alpha {
                    unpremultiply(weighted, sum)
                } else {
                    sum
                });
            }
        }
        if has_alpha {
            dilate_into_transparent(&mut next, half);
        }
        levels.push(next);
        side = half;
    }
    levels
}

fn premultiply(t: [f32; 4]) -> [f32; 4] {
    [t[0] * t[3], t[1] * t[3], t[2] * t[3], t[3]]
}

/// Straight colour from a premultiplied average `w`; where it has no
/// coverage, the plain average `fallback`.
fn unpremultiply(w: [f32; 4], fallback: [f32; 4]) -> [f32; 4] {
    if w[3] > 0.0 {
        [w[0] / w[3], w[1] / w[3], w[2] / w[3], w[3]]
    } else {
        [fallback[0], fallback[1], fallback[2], 0.0]
    }
}

/// Gives every texel of coverage 0 that has a covered texel among its 8
/// neighbours (wrapping around, as the repeat sampler does) the
/// coverage-weighted colour of those neighbours; its alpha stays 0. One
/// ring is what a bilinear tap reaches.
fn dilate_into_transparent(texels: &mut [[f32; 4]], side: usize) {
    let source = texels.to_vec();
    for y in 0..side {
        for x in 0..side {
            if source[y * side + x][3] > 0.0 {
                continue;
            }
            let mut w = [0.0f32; 4];
            for dy in [side - 1, 0, 1] {
                for dx in [side - 1, 0, 1] {
                    let n = premultiply(source[((y + dy) % side) * side + (x + dx) % side]);
                    for c in 0..4 {
                        w[c] += n[c];
                    }
                }
            }
            if w[3] > 0.0 {
                let t = &mut texels[y * side + x];
                *t = [w[0] / w[3], w[1] / w[3], w[2] / w[3], 0.0];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn texture(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Texture {
        Texture {
            path: PathBuf::from("t.png"),
            width,
            height,
            texels,
            alpha: Vec::new(),
        }
    }

    /// Issue 31: a texture wider than MAX_DECODED_SIDE is box-filtered
    /// before its float copies, in linear values: black and white columns
    /// average to 0.5, not to the 0.216 of their averaged sRGB codes.
    #[test]
    fn large_textures_shrink_in_linear_values() {
        let (w, h) = (MAX_DECODED_SIDE * 2 + 1, 3);
        let img = image::RgbImage::from_fn(w, h, |x, _| {
            image::Rgb(if x % 2 == 0 { [255; 3] } else { [0; 3] })
        });
        let t = from_image(DynamicImage::ImageRgb8(img), Path::new("wide.png")).unwrap();
        // 8193 columns: boxes of 3 (the smallest factor to 4096 or less),
        // holding 2 white columns of 3, then 1 of 3, alternately.
        assert_eq!((t.width, t.height), (w.div_ceil(3), 1));
        assert!(
            (t.texels[0][0] - 2.0 / 3.0).abs() < 1e-5,
            "{:?}",
            t.texels[0]
        );
        assert!(
            (t.texels[1][0] - 1.0 / 3.0).abs() < 1e-5,
            "{:?}",
            t.texels[1]
        );
        let small = image::RgbImage::from_pixel(4, 4, image::Rgb([128; 3]));
        let t = from_image(DynamicImage::ImageRgb8(small), Path::new("small.png")).unwrap();
        assert_eq!((t.width, t.height), (4, 4));
    }

    #[test]
    fn srgb_decode_matches_the_standard_at_its_ends_and_knee() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // Both branches meet at the knee (continuity of IEC 61966-2-1).
        let below = 0.04045 / 12.92;
        let above = ((0.04045f32 + 0.055) / 1.055).powf(2.4);
        assert!((below - above).abs() < 1e-6);
        // Code 188 decodes to about 0.5029 (tables of sRGB).
        assert!((srgb_to_linear(188.0 / 255.0) - 0.5029).abs() < 1e-4);
    }

    /// JPEG files decode as sRGB like PNG: a flat colour (its 8x8 blocks
    /// hold only a DC term, which baseline JPEG at quality 100 keeps to
    /// within a code) comes back as the decoded sRGB value of its codes.
    #[test]
    fn jpeg_decodes_as_srgb() {
        let rgb = [200u8, 120, 40];
        let image = image::RgbImage::from_pixel(16, 16, image::Rgb(rgb));
        let mut bytes = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 100)
            .encode_image(&image)
            .unwrap();
        let t = decode(&bytes, Path::new("flat.jpg")).unwrap();
        assert_eq!((t.width, t.height), (16, 16));
        for texel in &t.texels {
            for (c, &code) in texel.iter().zip(&rgb) {
                let lo = srgb_to_linear((code as f32 - 2.0) / 255.0);
                let hi = srgb_to_linear((code as f32 + 2.0) / 255.0);
                assert!((lo..=hi).contains(c), "{c} not within 2 codes of {code}");
            }
        }
    }

    /// EXR texels are linear albedos: one above 1 is refused, naming it.
    #[test]
    fn exr_albedo_above_one_is_refused() {
        let mut image = image::Rgb32FImage::from_pixel(2, 2, image::Rgb([0.5, 0.5, 0.5]));
        image.put_pixel(1, 0, image::Rgb([0.5, 2.0, 0.5]));
        let mut bytes = std::io::Cursor::new(Vec::new());
        DynamicImage::ImageRgb32F(image)
            .write_to(&mut bytes, image::ImageFormat::OpenExr)
            .unwrap();
        let e = decode(bytes.get_ref(), Path::new("hot.exr")).unwrap_err();
        assert!(
            e.contains("hot.exr") && e.contains("texel 1") && e.contains("[0, 1]"),
            "{e}"
        );
    }

    #[test]
    fn layer_size_is_a_capped_power_of_two() {
        assert_eq!(layer_size(&[]), 1);
        let t = texture(3, 5, vec![[0.0; 3]; 15]);
        assert_eq!(layer_size(&[t]), 8);
        let big = texture(3000, 1, vec![[0.0; 3]; 3000]);
        assert_eq!(layer_size(&[big]), MAX_LAYER_SIZE);
    }

    #[test]
    fn mip_chain_keeps_the_mean_down_to_one_texel() {
        // A 4x4 checker of 0 and 1: every level's mean is 1/2.
        let texels = (0..16).map(|i| [((i % 4 + i / 4) % 2) as f32; 3]).collect();
        let levels = mip_chain(&texture(4, 4, texels), 4);
        assert_eq!(levels.len(), 3);
        for level in &levels {
            let mean: f32 = level.iter().map(|t| t[0]).sum::<f32>() / level.len() as f32;
            assert!((mean - 0.5).abs() < 1e-6, "{mean}");
        }
        assert_eq!(levels[2], vec![[0.5, 0.5, 0.5, 1.0]]);
    }

    #[test]
    fn a_constant_texture_stays_constant_when_resized() {
        let levels = mip_chain(&texture(3, 2, vec![[0.25, 0.5, 0.75]; 6]), 4);
        for level in &levels {
            for t in level {
                for (a, b) in t.iter().zip([0.25, 0.5, 0.75, 1.0]) {
                    assert!((a - b).abs() < 1e-6, "{t:?}");
                }
            }
        }
    }

    /// A cut-out's mip chain weights colour by coverage: a texture whose
    /// left half is red and kept, right half green and cut away, keeps no
    /// green anywhere a bilinear tap of any level can reach from the kept
    /// half (before the fix: level 2 was (0.5, 0.5, 0), half green), and
    /// coverage itself is still the plain box average.
    #[test]
    fn cut_out_mips_do_not_bleed_transparent_colour() {
        let texels = (0..64)
            .map(|i| {
                if i % 8 < 4 {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 1.0, 0.0]
                }
            })
            .collect();
        let mut t = texture(8, 8, texels);
        t.alpha = (0..64).map(|i| if i % 8 < 4 { 1.0 } else { 0.0 }).collect();
        let levels = mip_chain(&t, 8);
        assert_eq!(levels.len(), 4);
        for (l, level) in levels.iter().enumerate() {
            let side = 8 >> l;
            for (i, texel) in level.iter().enumerate() {
                let x = i % side;
                let covered = |x: usize| x < side / 2;
                let alpha = if side == 1 {
                    0.5
                } else {
                    covered(x) as u32 as f32
                };
                assert_eq!(texel[3], alpha, "level {l} texel {i}");
                // Covered texels by weighting, transparent ones next to a
                // covered one (wrapping) by dilation: the kept colour.
                let reached = side == 1
                    || covered(x)
                    || covered((x + 1) % side)
                    || covered((x + side - 1) % side);
                if reached {
                    assert_eq!(&texel[..3], &[1.0, 0.0, 0.0], "level {l} texel {i}");
                }
            }
        }
        // Partial coverage: weights 1 and 1/3 give (3 c1 + c2) / 4.
        let mut t = texture(
            2,
            2,
            vec![
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
        );
        t.alpha = vec![1.0, 1.0 / 3.0, 1.0, 1.0 / 3.0];
        let top = &mip_chain(&t, 2)[1][0];
        for (a, b) in top.iter().zip([0.75, 0.25, 0.0, 2.0 / 3.0]) {
            assert!((a - b).abs() < 1e-6, "{top:?}");
        }
    }
}
