//! The contact sheet: a grid of equally sized images, each with a label
//! under it (the technique's name, FLIP, energy and milliseconds), as one
//! RGB8 image.

use super::font::{draw_text, text_width, GLYPH_H};

/// One cell: an RGB8 image of the sheet's tile size and its label lines.
pub struct Tile {
    pub rgb: Vec<u8>,
    pub lines: Vec<String>,
}

/// A composed sheet.
pub struct Sheet {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

/// The largest side of a sheet's tile: bigger images are shrunk to fit
/// (`thumbnail`), so a 1080p comparison keeps a sheet of a sensible size
/// and `caustics compare` holds only these thumbnails, not the images.
pub const TILE_MAX: u32 = 384;

/// The tile size of a `width` x `height` image: itself, or shrunk to fit
/// `TILE_MAX` with its aspect kept.
pub fn tile_size(width: u32, height: u32) -> (u32, u32) {
    let side = width.max(height);
    if side <= TILE_MAX {
        return (width, height);
    }
    let fit = |v: u32| ((v as u64 * TILE_MAX as u64 + side as u64 / 2) / side as u64).max(1) as u32;
    (fit(width), fit(height))
}

/// An RGB8 image shrunk to `tile_size` by averaging the source pixels each
/// tile pixel covers (a box filter); an image that fits is returned as is.
pub fn thumbnail(rgb: Vec<u8>, width: u32, height: u32) -> Vec<u8> {
    let (tw, th) = tile_size(width, height);
    if (tw, th) == (width, height) {
        return rgb;
    }
    let span = |t: u32, n: u32, of: u32| {
        let a = (t as u64 * of as u64 / n as u64) as u32;
        let b = (((t + 1) as u64 * of as u64).div_ceil(n as u64) as u32).max(a + 1);
        a..b.min(of)
    };
    let mut out = Vec::with_capacity((3 * tw * th) as usize);
    for ty in 0..th {
        let ys = span(ty, th, height);
        for tx in 0..tw {
            let xs = span(tx, tw, width);
            let mut sum = [0u32; 3];
            let mut n = 0;
            for y in ys.clone() {
                for x in xs.clone() {
                    let i = (3 * (y * width + x)) as usize;
                    for c in 0..3 {
                        sum[c] += rgb[i + c] as u32;
                    }
                    n += 1;
                }
            }
            out.extend(sum.map(|v| ((v + n / 2) / n) as u8));
        }
    }
    out
}

const PAD: u32 = 4;
const BACKGROUND: [u8; 3] = [24, 24, 24];
const INK: [u8; 3] = [230, 230, 230];

/// Lays out `rows` of tiles, each image `width` x `height`, one row of the
/// grid per entry (rows may differ in length; empty cells stay background).
/// Labels are drawn at 1 font pixel per pixel under 256-pixel images, else
/// 2; cells widen to fit the longest label line.
pub fn compose(rows: &[Vec<Tile>], width: u32, height: u32) -> Sheet {
    let scale = if width < 256 { 1 } else { 2 };
    let line_h = (GLYPH_H + 2) * scale;
    let lines = rows
        .iter()
        .flatten()
        .map(|t| t.lines.len() as u32)
        .max()
        .unwrap_or(0);
    let label_w = rows
        .iter()
        .flatten()
        .flat_map(|t| t.lines.iter().map(|l| text_width(l, scale)))
        .max()
        .unwrap_or(0);
    let cell_w = width.max(label_w) + PAD;
    let cell_h = height + lines * line_h + 2 * PAD;
    let columns = rows.iter().map(Vec::len).max().unwrap_or(0) as u32;
    let sheet_w = (columns * cell_w + PAD).max(1);
    let sheet_h = (rows.len() as u32 * cell_h + PAD).max(1);
    let mut rgb: Vec<u8> = BACKGROUND
        .iter()
        .copied()
        .cycle()
        .take((3 * sheet_w * sheet_h) as usize)
        .collect();
    for (r, row) in rows.iter().enumerate() {
        for (c, tile) in row.iter().enumerate() {
            let (x0, y0) = (PAD + c as u32 * cell_w, PAD + r as u32 * cell_h);
            for y in 0..height {
                let src = (3 * y * width) as usize;
                let dst = (3 * ((y0 + y) * sheet_w + x0)) as usize;
                rgb[dst..dst + 3 * width as usize]
                    .copy_from_slice(&tile.rgb[src..src + 3 * width as usize]);
            }
            for (i, line) in tile.lines.iter().enumerate() {
                let y = y0 + height + PAD / 2 + i as u32 * line_h;
                draw_text(&mut rgb, sheet_w, x0, y, line, scale, INK);
            }
        }
    }
    Sheet {
        width: sheet_w,
        height: sheet_h,
        rgb,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_land_in_their_cells_with_room_for_labels() {
        let tile = |v: u8, label: &str| Tile {
            rgb: vec![v; 3 * 8 * 8],
            lines: vec![label.to_owned()],
        };
        let rows = vec![
            vec![tile(200, "reference")],
            vec![tile(100, "a"), tile(50, "b")],
        ];
        let s = compose(&rows, 8, 8);
        let cell_w = text_width("reference", 1) + PAD;
        assert_eq!(s.width, 2 * cell_w + PAD);
        let at = |x: u32, y: u32| s.rgb[(3 * (y * s.width + x)) as usize];
        assert_eq!(at(PAD, PAD), 200);
        let cell_h = 8 + (GLYPH_H + 2) + 2 * PAD;
        assert_eq!(at(PAD + cell_w + 7, PAD + cell_h + 7), 50);
        // The empty cell stays background.
        assert_eq!(at(PAD + cell_w, PAD), BACKGROUND[0]);
    }

    #[test]
    fn thumbnails_keep_small_images_and_average_big_ones() {
        assert_eq!(tile_size(64, 64), (64, 64));
        assert_eq!(tile_size(1920, 1080), (384, 216));
        let small = vec![7u8; 3 * 4 * 4];
        assert_eq!(thumbnail(small.clone(), 4, 4), small);
        // 768 x 2: left half 0, right half 200, shrunk 2:1 to 384 x 1.
        let rgb: Vec<u8> = (0..2)
            .flat_map(|_| (0..768).flat_map(|x| [if x < 384 { 0 } else { 200 }; 3]))
            .collect();
        let t = thumbnail(rgb, 768, 2);
        assert_eq!(t.len(), 3 * 384);
        assert_eq!((t[0], t[3 * 191], t[3 * 192], t[3 * 383]), (0, 0, 200, 200));
    }
}
