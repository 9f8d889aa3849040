//! The `[medium]` table: scattering coefficients, phase, bounds and the
//! density (constant, noise or a raw grid file).

use super::values::{describe, non_negative_rgb, value_text};
use crate::scene::node::{Node, Tbl, R};
use crate::scene::paths::Confinement;
use crate::scene::types::*;
use glam::Vec3;

pub(super) fn medium(t: &Tbl, within: &Confinement) -> R<Medium> {
    t.check_keys(
        &[
            "sigma_s",
            "sigma_a",
            "g",
            "bounds",
            "density",
            "multiple_scattering",
        ],
        "[medium]",
    )?;
    let sigma_s = non_negative_rgb(t, "sigma_s", None)?;
    let sigma_a = non_negative_rgb(t, "sigma_a", Some(Vec3::ZERO))?;
    let g = t.f32_or("g", 0.0)?;
    if g.abs() >= 1.0 {
        return Err(t.err("g", format!("must be within (-1, 1), got {g}")));
    }
    let Some(b) = t.opt_table("bounds")? else {
        return Err(t.err(
            "bounds",
            "missing required field (a table { min = [..], max = [..] })",
        ));
    };
    b.check_keys(&["min", "max"], "medium.bounds")?;
    let (bounds_min, bounds_max) = (b.vec3("min")?, b.vec3("max")?);
    if bounds_min.cmpge(bounds_max).any() {
        return Err(b.err(
            "max",
            format!("must exceed min in every component: min {bounds_min}, max {bounds_max}"),
        ));
    }
    let density = match t.get("density") {
        None => Density::Constant(1.0),
        Some(n) if matches!(n.node, Node::Table(_)) => {
            density_table(&Tbl::of(t.src, t.field("density"), n)?, within)?
        }
        Some(_) => {
            let d = t.f32("density")?;
            if d < 0.0 {
                return Err(t.err("density", format!("must not be negative, got {d}")));
            }
            Density::Constant(d)
        }
    };
    let multiple_scattering = t.opt_bool("multiple_scattering")?.unwrap_or(false);
    // The scattered lights are placed along the lights' rays on the CPU,
    // which evaluates a constant density only (src/passes/scattered_lights.rs).
    if multiple_scattering && !matches!(density, Density::Constant(_)) {
        return Err(t.err(
            "multiple_scattering",
            "needs a constant density (a number), not a noise or grid density",
        ));
    }
    Ok(Medium {
        sigma_s,
        sigma_a,
        g,
        bounds_min,
        bounds_max,
        density,
        multiple_scattering,
    })
}

/// A dielectric material's `medium` table: what fills its inside, as
/// (absorption, scattering), both already times the constant `density`.
/// Homogeneous only: the inside has no bounds of its own for a grid, and
/// the real-time techniques march it in closed form.
pub(super) fn inside_dielectric(t: &Tbl) -> R<(Vec3, Option<Scattering>)> {
    t.check_keys(&["sigma_s", "sigma_a", "g", "density"], "material.medium")?;
    let sigma_s = non_negative_rgb(t, "sigma_s", None)?;
    let sigma_a = non_negative_rgb(t, "sigma_a", Some(Vec3::ZERO))?;
    let g = t.f32_or("g", 0.0)?;
    if g.abs() >= 1.0 {
        return Err(t.err("g", format!("must be within (-1, 1), got {g}")));
    }
    if t.get("density")
        .is_some_and(|n| !matches!(n.node, Node::Int(_) | Node::Float(_)))
    {
        return Err(t.err(
            "density",
            "inside a dielectric takes a constant density (a number), not a noise or grid table",
        ));
    }
    let density = t.f32_or("density", 1.0)?;
    if density < 0.0 {
        return Err(t.err("density", format!("must not be negative, got {density}")));
    }
    let sigma_s = sigma_s * density;
    let scattering = (sigma_s.max_element() > 0.0).then_some(Scattering { sigma_s, g });
    Ok((sigma_a * density, scattering))
}

fn density_table(t: &Tbl, within: &Confinement) -> R<Density> {
    if let Some(noise) = t.opt_table("noise")? {
        t.check_keys(&["noise"], "medium.density")?;
        noise.check_keys(
            &["scale", "frequency", "octaves", "offset"],
            "medium.density.noise",
        )?;
        let scale = noise.f32_or("scale", 1.0)?;
        if scale < 0.0 {
            return Err(noise.err("scale", format!("must not be negative, got {scale}")));
        }
        let frequency = noise.f32_or("frequency", 1.0)?;
        if frequency <= 0.0 {
            return Err(noise.err("frequency", format!("must be positive, got {frequency}")));
        }
        let octaves = noise.opt_u32("octaves")?.unwrap_or(4);
        if !(1..=16).contains(&octaves) {
            return Err(noise.err("octaves", format!("must be within [1, 16], got {octaves}")));
        }
        let offset = noise.vec3_or("offset", Vec3::ZERO)?;
        return Ok(Density::Noise {
            scale,
            frequency,
            octaves,
            offset,
        });
    }
    if t.has("grid") {
        t.check_keys(&["grid", "dims"], "medium.density")?;
        let rel = t.str("grid")?;
        let dims_node = t.req("dims")?;
        let dims_field = t.field("dims");
        let mut dims = [0u32; 3];
        match &dims_node.node {
            Node::Array(items) if items.len() == 3 => {
                for (i, item) in items.iter().enumerate() {
                    dims[i] = match item.node {
                        Node::Int(v) if (1..=65536).contains(&v) => v as u32,
                        ref other => {
                            return Err(t.src.err(
                                &item.span,
                                &format!("{dims_field}[{i}]"),
                                format!(
                                    "expected an integer within [1, 65536], got {}",
                                    value_text(other)
                                ),
                            ))
                        }
                    }
                }
            }
            other => {
                return Err(t.err(
                    "dims",
                    format!("expected an array of 3 integers, got {}", describe(other)),
                ))
            }
        }
        let full = within.file(rel).map_err(|e| t.err("grid", e))?;
        // The grid holds exactly its texels: its size is checked before
        // anything is read, and no more than that is read.
        let count = dims.iter().map(|&d| d as u64).product::<u64>();
        let cannot_read = |e: String| {
            t.err(
                "grid",
                format!("cannot read density grid {}: {e}", full.display()),
            )
        };
        crate::scene::input::check_regular(&full).map_err(cannot_read)?;
        let size = std::fs::metadata(&full)
            .map_err(|e| cannot_read(e.to_string()))?
            .len();
        if size != count * 4 {
            return Err(t.err(
                "grid",
                format!(
                    "density grid {} has {size} bytes; dims {}x{}x{} need {} (little-endian f32, x fastest)",
                    full.display(),
                    dims[0],
                    dims[1],
                    dims[2],
                    count * 4
                ),
            ));
        }
        let bytes = crate::scene::input::read_limited(&full, count * 4).map_err(cannot_read)?;
        let mut values: Vec<f32> = Vec::new();
        values
            .try_reserve_exact(count as usize)
            .map_err(|_| cannot_read(format!("cannot allocate {} bytes for it", count * 4)))?;
        values.extend(
            bytes
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
        );
        drop(bytes);
        if let Some((i, v)) = values
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(t.err(
                "grid",
                format!(
                    "density grid {}: value {i} is {v}, must be finite and non-negative",
                    full.display()
                ),
            ));
        }
        return Ok(Density::Grid { dims, values });
    }
    t.check_keys(&["noise", "grid", "dims"], "medium.density")?;
    Err(t.err(
        "noise",
        "density table needs `noise = { .. }` or `grid = \"file.raw\"` with `dims`",
    ))
}
