//! A span-carrying TOML value tree. Every value keeps its byte range in the
//! source, so semantic errors can name `FILE:LINE:COL` and the field path.

use serde::de::{self, Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use std::fmt;
use std::ops::Range;
use toml::Spanned;

use super::error::{SceneError, Source};
use glam::Vec3;

/// One TOML value, children spanned.
#[derive(Clone, Debug)]
pub(crate) enum Node {
    Str(String),
    Int(i64),
    Float(f64),
    Bool(bool),
    Datetime,
    Array(Vec<SNode>),
    /// Keys in source order.
    Table(Vec<(String, SNode)>),
}

/// A value and its byte range in the scene file.
#[derive(Clone, Debug)]
pub(crate) struct SNode {
    pub node: Node,
    pub span: Range<usize>,
}

impl<'de> Deserialize<'de> for SNode {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = Spanned::<Node>::deserialize(d)?;
        let span = s.span();
        Ok(SNode {
            node: s.into_inner(),
            span,
        })
    }
}

impl Node {
    /// The TOML type name, for "expected X, got Y" messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            Node::Str(_) => "a string",
            Node::Int(_) => "an integer",
            Node::Float(_) => "a float",
            Node::Bool(_) => "a boolean",
            Node::Datetime => "a date-time",
            Node::Array(_) => "an array",
            Node::Table(_) => "a table",
        }
    }
}

struct NodeVisitor;

/// The key under which toml hands a date-time to a generic visitor.
const DATETIME_KEY: &str = "$__toml_private_datetime";

impl<'de> Visitor<'de> for NodeVisitor {
    type Value = Node;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a TOML value")
    }
    fn visit_bool<E: de::Error>(self, v: bool) -> Result<Node, E> {
        Ok(Node::Bool(v))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Node, E> {
        Ok(Node::Int(v))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Node, E> {
        i64::try_from(v)
            .map(Node::Int)
            .map_err(|_| E::custom("integer out of range"))
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Node, E> {
        Ok(Node::Float(v))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Node, E> {
        Ok(Node::Str(v.to_owned()))
    }
    fn visit_string<E: de::Error>(self, v: String) -> Result<Node, E> {
        Ok(Node::Str(v))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Node, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element::<SNode>()? {
            items.push(item);
        }
        Ok(Node::Array(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Node, A::Error> {
        let mut entries = Vec::new();
        while let Some(key) = map.next_key::<String>()? {
            if key == DATETIME_KEY {
                let _: de::IgnoredAny = map.next_value()?;
                return Ok(Node::Datetime);
            }
            let value = map.next_value::<SNode>()?;
            entries.push((key, value));
        }
        Ok(Node::Table(entries))
    }
}

impl<'de> Deserialize<'de> for Node {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(NodeVisitor)
    }
}

/// Parses a whole document: the root table's entries, each spanned.
pub(crate) fn parse_document(text: &str) -> Result<Vec<(String, SNode)>, toml::de::Error> {
    struct Root(Vec<(String, SNode)>);
    impl<'de> Deserialize<'de> for Root {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            match d.deserialize_any(NodeVisitor)? {
                Node::Table(entries) => Ok(Root(entries)),
                other => Err(de::Error::custom(format!(
                    "expected a table at the document root, got {}",
                    other.type_name()
                ))),
            }
        }
    }
    toml::from_str::<Root>(text).map(|r| r.0)
}

/// A table being read: typed getters with located errors. Every getter takes
/// the key; the error names `path.key` and points at the value (or at the
/// table when the key is missing).
pub(crate) struct Tbl<'a> {
    pub src: &'a Source<'a>,
    /// Field path of the table itself (`""` for the document root).
    pub path: String,
    pub span: Range<usize>,
    pub entries: &'a [(String, SNode)],
}

pub(crate) type R<T> = Result<T, SceneError>;

impl<'a> Tbl<'a> {
    pub fn root(src: &'a Source<'a>, entries: &'a [(String, SNode)]) -> Self {
        Tbl {
            src,
            path: String::new(),
            span: 0..0,
            entries,
        }
    }

    /// Reads `node` (found at `path`) as a table.
    pub fn of(src: &'a Source<'a>, path: String, node: &'a SNode) -> R<Self> {
        match &node.node {
            Node::Table(entries) => Ok(Tbl {
                src,
                path,
                span: node.span.clone(),
                entries,
            }),
            other => Err(src.err(
                &node.span,
                &path,
                format!("expected a table, got {}", other.type_name()),
            )),
        }
    }

    pub fn field(&self, key: &str) -> String {
        if self.path.is_empty() {
            key.to_owned()
        } else {
            format!("{}.{key}", self.path)
        }
    }

    pub fn get(&self, key: &str) -> Option<&'a SNode> {
        self.entries.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    pub fn has(&self, key: &str) -> bool {
        self.get(key).is_some()
    }

    /// An error about `key`, located at its value (or at the table when absent).
    pub fn err(&self, key: &str, message: impl Into<String>) -> SceneError {
        let span = self.get(key).map_or(&self.span, |n| &n.span);
        self.src.err(span, &self.field(key), message)
    }

    /// Rejects any key not in `allowed` (`what` names the table in the message).
    pub fn check_keys(&self, allowed: &[&str], what: &str) -> R<()> {
        for (k, v) in self.entries {
            if !allowed.contains(&k.as_str()) {
                return Err(self.src.err(
                    &v.span,
                    &self.field(k),
                    format!(
                        "unknown field `{k}` in {what}; expected one of: {}",
                        allowed.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    pub fn req(&self, key: &str) -> R<&'a SNode> {
        self.get(key)
            .ok_or_else(|| self.err(key, "missing required field"))
    }

    pub fn opt_f32(&self, key: &str) -> R<Option<f32>> {
        self.get(key)
            .map(|n| number(self.src, &self.field(key), n))
            .transpose()
    }

    pub fn f32(&self, key: &str) -> R<f32> {
        number(self.src, &self.field(key), self.req(key)?)
    }

    pub fn f32_or(&self, key: &str, default: f32) -> R<f32> {
        Ok(self.opt_f32(key)?.unwrap_or(default))
    }

    pub fn opt_vec3(&self, key: &str) -> R<Option<Vec3>> {
        self.get(key)
            .map(|n| vec3(self.src, &self.field(key), n, false))
            .transpose()
    }

    pub fn vec3(&self, key: &str) -> R<Vec3> {
        vec3(self.src, &self.field(key), self.req(key)?, false)
    }

    pub fn vec3_or(&self, key: &str, default: Vec3) -> R<Vec3> {
        Ok(self.opt_vec3(key)?.unwrap_or(default))
    }

    /// A colour-like triple: `[r, g, b]` or one number for all three.
    pub fn opt_rgb(&self, key: &str) -> R<Option<Vec3>> {
        self.get(key)
            .map(|n| vec3(self.src, &self.field(key), n, true))
            .transpose()
    }

    pub fn rgb(&self, key: &str) -> R<Vec3> {
        vec3(self.src, &self.field(key), self.req(key)?, true)
    }

    pub fn opt_u32(&self, key: &str) -> R<Option<u32>> {
        let Some(n) = self.get(key) else {
            return Ok(None);
        };
        match n.node {
            Node::Int(i) => u32::try_from(i).map(Some).map_err(|_| {
                self.src.err(
                    &n.span,
                    &self.field(key),
                    format!("must be a non-negative integer below 2^32, got {i}"),
                )
            }),
            ref other => Err(self.src.err(
                &n.span,
                &self.field(key),
                format!("expected an integer, got {}", other.type_name()),
            )),
        }
    }

    pub fn opt_str(&self, key: &str) -> R<Option<&'a str>> {
        let Some(n) = self.get(key) else {
            return Ok(None);
        };
        match &n.node {
            Node::Str(s) => Ok(Some(s)),
            other => Err(self.src.err(
                &n.span,
                &self.field(key),
                format!("expected a string, got {}", other.type_name()),
            )),
        }
    }

    pub fn str(&self, key: &str) -> R<&'a str> {
        self.req(key)?;
        self.opt_str(key).map(|s| s.unwrap_or_default())
    }

    pub fn opt_bool(&self, key: &str) -> R<Option<bool>> {
        let Some(n) = self.get(key) else {
            return Ok(None);
        };
        match n.node {
            Node::Bool(b) => Ok(Some(b)),
            ref other => Err(self.src.err(
                &n.span,
                &self.field(key),
                format!("expected a boolean, got {}", other.type_name()),
            )),
        }
    }

    pub fn opt_table(&self, key: &str) -> R<Option<Tbl<'a>>> {
        self.get(key)
            .map(|n| Tbl::of(self.src, self.field(key), n))
            .transpose()
    }

    /// `[[key]]`: an array of tables, each with path `key[i]`. Absent: empty.
    pub fn tables(&self, key: &str) -> R<Vec<Tbl<'a>>> {
        let Some(n) = self.get(key) else {
            return Ok(Vec::new());
        };
        let Node::Array(items) = &n.node else {
            return Err(self.src.err(
                &n.span,
                &self.field(key),
                format!(
                    "expected an array of tables (`[[{key}]]`), got {}",
                    n.node.type_name()
                ),
            ));
        };
        items
            .iter()
            .enumerate()
            .map(|(i, item)| Tbl::of(self.src, format!("{}[{i}]", self.field(key)), item))
            .collect()
    }
}

/// The largest magnitude of a number in a scene file (docs/SCENES.md,
/// "Bounds"): lengths and positions (m), angles (degrees), speeds, times,
/// coefficients (1/m), scales, exposure. Beyond 10^6 m an f32 position
/// resolves no better than 6 cm, and products of such values (an orbit at
/// some time, a transform) head for overflow.
pub const MAX_MAGNITUDE: f64 = 1e6;

/// The largest radiometric value (`intensity` in W/sr, `irradiance` in
/// W/m², `radiance` in W m⁻² sr⁻¹): wide enough for the sun's radiance
/// (about 2e7) and a millimetre-sized lamp's (1e5-1e6) with room to spare,
/// small enough that power and photon flux stay far from the f32 range.
pub const MAX_RADIOMETRIC: f64 = 1e10;

/// Fields (by their last key) that hold radiometric values: lights'
/// intensity and irradiance, area lights' radiance, and an environment
/// sky's sun, zenith and horizon radiances.
const RADIOMETRIC_KEYS: [&str; 6] = [
    "intensity",
    "irradiance",
    "radiance",
    "sun_radiance",
    "zenith",
    "horizon",
];

/// The bound on |value| for `field` (a dotted path such as
/// `light[0].intensity[1]`): by its last key.
fn magnitude_limit(field: &str) -> f64 {
    let key = field.rsplit('.').next().unwrap_or(field);
    let key = key.split('[').next().unwrap_or(key);
    if RADIOMETRIC_KEYS.contains(&key) {
        MAX_RADIOMETRIC
    } else {
        MAX_MAGNITUDE
    }
}

/// A finite number (integer or float) within the field's bound
/// ([`MAX_MAGNITUDE`], or [`MAX_RADIOMETRIC`] for light values).
pub(crate) fn number(src: &Source, field: &str, n: &SNode) -> R<f32> {
    let v = match n.node {
        Node::Int(i) => i as f64,
        Node::Float(f) if f.is_nan() => {
            return Err(src.err(&n.span, field, "must be a finite number, got nan"))
        }
        Node::Float(f) if !f.is_finite() || f.abs() > f32::MAX as f64 => {
            return Err(src.err(&n.span, field, format!("must be a finite number, got {f}")))
        }
        Node::Float(f) => f,
        ref other => {
            return Err(src.err(
                &n.span,
                field,
                format!("expected a number, got {}", other.type_name()),
            ))
        }
    };
    let limit = magnitude_limit(field);
    if v.abs() > limit {
        return Err(src.err(
            &n.span,
            field,
            format!("must be within ±{limit:e} (docs/SCENES.md, Bounds), got {v:e}"),
        ));
    }
    Ok(v as f32)
}

/// `[x, y, z]`, or (when `scalar_ok`) one number broadcast to all three.
pub(crate) fn vec3(src: &Source, field: &str, n: &SNode, scalar_ok: bool) -> R<Vec3> {
    match &n.node {
        Node::Array(items) if items.len() == 3 => {
            let mut v = [0.0; 3];
            for (i, item) in items.iter().enumerate() {
                v[i] = number(src, &format!("{field}[{i}]"), item)?;
            }
            Ok(Vec3::from(v))
        }
        Node::Array(items) => Err(src.err(
            &n.span,
            field,
            format!(
                "expected an array of 3 numbers, got {} elements",
                items.len()
            ),
        )),
        Node::Int(_) | Node::Float(_) if scalar_ok => Ok(Vec3::splat(number(src, field, n)?)),
        other => {
            let want = if scalar_ok {
                "a number or an array of 3 numbers"
            } else {
                "an array of 3 numbers"
            };
            Err(src.err(
                &n.span,
                field,
                format!("expected {want}, got {}", other.type_name()),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_cover_header_tables_and_arrays_of_tables() {
        let text = "a = 1\n[camera]\neye = [1.0, 2, 3]\n[[object]]\nr = 1.5\n[[object]]\nr = -1\nt = { x = 2 }\nd = 1979-05-27\n";
        let root = parse_document(text).expect("parses");
        for (k, v) in &root {
            eprintln!("{k}: {:?} {:?}", v.span, &text[v.span.clone()]);
        }
        let obj = &root.iter().find(|(k, _)| k == "object").expect("object").1;
        let Node::Array(items) = &obj.node else {
            panic!("array")
        };
        let Node::Table(t) = &items[1].node else {
            panic!("table")
        };
        assert_eq!(&text[t[0].1.span.clone()], "-1");
        assert!(matches!(t[2].1.node, Node::Datetime));
    }
}
