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
}
