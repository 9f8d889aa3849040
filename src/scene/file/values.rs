//! Value checks shared by the scene tables: directions, colours, positive
//! numbers, pairs, and how a wrong value is described in an error.

use crate::scene::node::{self, Node, Tbl, R};
use glam::Vec3;

/// A non-zero vector, normalised.
pub(super) fn direction(t: &Tbl, key: &str, default: Option<Vec3>) -> R<Vec3> {
    let v = match default {
        Some(d) => t.vec3_or(key, d)?,
        None => t.vec3(key)?,
    };
    let len = v.length();
    if !(len > 1e-12 && len.is_finite()) {
        return Err(t.err(key, format!("must be a non-zero direction, got {v}")));
    }
    Ok(v / len)
}

pub(super) fn non_negative_rgb(t: &Tbl, key: &str, default: Option<Vec3>) -> R<Vec3> {
    let v = match default {
        Some(d) => t.opt_rgb(key)?.unwrap_or(d),
        None => t.rgb(key)?,
    };
    if v.min_element() < 0.0 {
        return Err(t.err(key, format!("must not be negative, got {v}")));
    }
    Ok(v)
}

pub(super) fn unit_rgb(t: &Tbl, key: &str, default: Vec3) -> R<Vec3> {
    let v = non_negative_rgb(t, key, Some(default))?;
    if v.max_element() > 1.0 {
        return Err(t.err(key, format!("must be within [0, 1], got {v}")));
    }
    Ok(v)
}

/// The smallest positive length (radius, size, wavelength), scale or UV
/// scale (docs/SCENES.md, Bounds): a micrometre; below it a triangle's
/// edges vanish in f32 next to positions of metres.
pub(crate) const MIN_POSITIVE: f32 = 1e-6;

/// A positive number, at least [`MIN_POSITIVE`].
pub(super) fn positive(t: &Tbl, key: &str) -> R<f32> {
    let v = t.f32(key)?;
    if v <= 0.0 {
        return Err(t.err(key, format!("must be positive, got {v}")));
    }
    if v < MIN_POSITIVE {
        return Err(t.err(key, too_small(v)));
    }
    Ok(v)
}

fn too_small(v: f32) -> String {
    format!("must be at least {MIN_POSITIVE:e} (docs/SCENES.md, Bounds), got {v:e}")
}

/// Two positive numbers `[a, b]`.
pub(super) fn size2(t: &Tbl, key: &str) -> R<[f32; 2]> {
    numbers2(t, key, true)
}

/// Two numbers `[a, b]`, positive ones when `positive`.
pub(super) fn numbers2(t: &Tbl, key: &str, positive: bool) -> R<[f32; 2]> {
    let n = t.req(key)?;
    let field = t.field(key);
    let items = match &n.node {
        Node::Array(items) if items.len() == 2 => items,
        other => {
            return Err(t.err(
                key,
                format!("expected an array of 2 numbers, got {}", describe(other)),
            ))
        }
    };
    let mut out = [0.0; 2];
    for (i, item) in items.iter().enumerate() {
        out[i] = node::number(t.src, &format!("{field}[{i}]"), item)?;
        if positive && out[i] <= 0.0 {
            return Err(t.src.err(
                &item.span,
                &format!("{field}[{i}]"),
                format!("must be positive, got {}", out[i]),
            ));
        }
        if positive && out[i] < MIN_POSITIVE {
            return Err(t
                .src
                .err(&item.span, &format!("{field}[{i}]"), too_small(out[i])));
        }
    }
    Ok(out)
}

pub(super) fn describe(n: &Node) -> String {
    match n {
        Node::Array(items) => format!("an array of {} elements", items.len()),
        other => other.type_name().to_owned(),
    }
}

pub(super) fn value_text(n: &Node) -> String {
    match n {
        Node::Int(v) => v.to_string(),
        Node::Float(v) => v.to_string(),
        other => other.type_name().to_owned(),
    }
}
