//! `shape = "water"` objects: the surface's extent, grid resolution and
//! Gerstner waves (docs/SCENES.md).

use super::values::{describe, numbers2, positive, size2, value_text};
use crate::scene::node::{Node, Tbl, R};
use crate::scene::types::*;
use crate::scene::water;

pub(super) const WATER_KEYS: [&str; 8] = [
    "shape",
    "name",
    "material",
    "center",
    "size",
    "resolution",
    "base_height",
    "wave",
];

pub(super) fn water_surface(t: &Tbl, material: u32) -> R<Water> {
    let center = match t.get("center") {
        Some(_) => numbers2(t, "center", false)?,
        None => [0.0; 2],
    };
    let size = size2(t, "size")?;
    let resolution = water_resolution(t)?;
    let base_height = t.f32_or("base_height", 0.0)?;
    let wave_tables = t.tables("wave")?;
    if wave_tables.len() > water::MAX_WAVES {
        let extra = &wave_tables[water::MAX_WAVES];
        return Err(t.src.err(
            &extra.span,
            &extra.path,
            format!(
                "too many waves: {}, at most {} are supported",
                wave_tables.len(),
                water::MAX_WAVES
            ),
        ));
    }
    let waves = wave_tables.iter().map(wave).collect::<R<Vec<_>>>()?;
    let surface = Water {
        center: center.into(),
        size: size.into(),
        resolution,
        base_height,
        material,
        waves,
    };
    let fold = surface.fold_measure();
    if fold >= 1.0 {
        return Err(t.err(
            "wave",
            format!(
                "the waves fold over themselves: the sum of steepness * 2 pi * amplitude / wavelength is {fold}, must be below 1"
            ),
        ));
    }
    Ok(surface)
}

/// `resolution = [nx, nz]`: cells per side within [1, MAX_RESOLUTION], at most MAX_CELLS in all.
fn water_resolution(t: &Tbl) -> R<[u32; 2]> {
    let n = t.req("resolution")?;
    let field = t.field("resolution");
    let items = match &n.node {
        Node::Array(items) if items.len() == 2 => items,
        other => {
            return Err(t.err(
                "resolution",
                format!("expected an array of 2 integers, got {}", describe(other)),
            ))
        }
    };
    let mut out = [0u32; 2];
    for (i, item) in items.iter().enumerate() {
        out[i] = match item.node {
            Node::Int(v) if (1..=water::MAX_RESOLUTION as i64).contains(&v) => v as u32,
            ref other => {
                return Err(t.src.err(
                    &item.span,
                    &format!("{field}[{i}]"),
                    format!(
                        "expected an integer within [1, {}], got {}",
                        water::MAX_RESOLUTION,
                        value_text(other)
                    ),
                ))
            }
        };
    }
    let cells = out[0] as u64 * out[1] as u64;
    if cells > water::MAX_CELLS {
        return Err(t.err(
            "resolution",
            format!(
                "{} x {} = {cells} cells, at most {} are supported",
                out[0],
                out[1],
                water::MAX_CELLS
            ),
        ));
    }
    Ok(out)
}

fn wave(t: &Tbl) -> R<Wave> {
    t.check_keys(
        &[
            "amplitude",
            "wavelength",
            "direction",
            "steepness",
            "speed",
            "phase",
        ],
        "a wave",
    )?;
    let amplitude = t.f32("amplitude")?;
    if amplitude < 0.0 {
        return Err(t.err(
            "amplitude",
            format!("must not be negative, got {amplitude}"),
        ));
    }
    let wavelength = positive(t, "wavelength")?;
    let steepness = t.f32_or("steepness", 0.0)?;
    if !(0.0..=1.0).contains(&steepness) {
        return Err(t.err(
            "steepness",
            format!("must be within [0, 1], got {steepness}"),
        ));
    }
    let speed = t.f32_or("speed", Wave::deep_water_speed(wavelength))?;
    if speed < 0.0 {
        return Err(t.err("speed", format!("must not be negative, got {speed}")));
    }
    Ok(Wave {
        amplitude,
        wavelength,
        direction_deg: t.f32_or("direction", 0.0)?,
        steepness,
        speed,
        phase: t.f32_or("phase", 0.0)?,
    })
}
