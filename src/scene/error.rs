//! Scene errors. Everything wrong with a scene file is reported as
//! `FILE:LINE:COL: FIELD: message`, FIELD being the dotted path of the value
//! (`object[2].radius`, `light[0].direction`, `medium.density.grid`).

use std::io;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file itself could not be read (missing, unreadable, not UTF-8).
    #[error("{}: cannot read scene file: {source}", .path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// Something wrong at a place in the scene file (syntax, types, values, or
    /// a file it refers to: OBJ, MTL, density grid).
    #[error("{}:{line}:{column}: {field}: {message}", .file.display())]
    At {
        file: PathBuf,
        /// 1-based line of the offending value.
        line: usize,
        /// 1-based column (in characters) of the offending value.
        column: usize,
        /// Dotted path of the offending field, e.g. `object[2].radius`.
        field: String,
        message: String,
    },
    /// A glTF file given as the scene (`--scene model.glb`) is bad:
    /// `FILE: GLTF_PATH: message`.
    #[error(transparent)]
    Gltf(#[from] super::gltf::GltfError),
}

impl SceneError {
    /// The field path of an `At` error.
    pub fn field(&self) -> Option<&str> {
        match self {
            SceneError::At { field, .. } => Some(field),
            SceneError::Gltf(e) => Some(&e.at),
            SceneError::Read { .. } => None,
        }
    }

    /// The 1-based line of an `At` error.
    pub fn line(&self) -> Option<usize> {
        match self {
            SceneError::At { line, .. } => Some(*line),
            SceneError::Read { .. } | SceneError::Gltf(_) => None,
        }
    }
}

/// 1-based line and column (in characters) of a byte offset in `text`.
pub(crate) fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.bytes().filter(|&b| b == b'\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}

/// The scene file being read: turns spans into located errors.
pub(crate) struct Source<'a> {
    pub path: &'a Path,
    pub text: &'a str,
}

impl Source<'_> {
    pub fn err(&self, span: &Range<usize>, field: &str, message: impl Into<String>) -> SceneError {
        let (line, column) = line_col(self.text, span.start);
        SceneError::At {
            file: self.path.to_path_buf(),
            line,
            column,
            field: if field.is_empty() {
                "(document)".into()
            } else {
                escape_control(field)
            },
            message: escape_control(&message.into()),
        }
    }
}

/// `text` with control characters escaped (`\n`, `\t`, `\u{1b}`): a
/// message quoting a key or string from the file (which TOML lets hold
/// escaped newlines) stays one line (found by tests/suite/fuzz.rs).
pub fn escape_control(text: &str) -> String {
    if !text.chars().any(char::is_control) {
        return text.to_owned();
    }
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_stay_one_line() {
        let src = Source {
            path: Path::new("s.toml"),
            text: "a = 1\n",
        };
        let e = src.err(&(0..1), "light[0].\"a\nb\"", "unknown kind `poi\nt\t`");
        assert_eq!(
            e.to_string(),
            "s.toml:1:1: light[0].\"a\\nb\": unknown kind `poi\\nt\\t`"
        );
    }

    #[test]
    fn line_col_counts_lines_and_chars() {
        let t = "ab\ncé = 1\n";
        assert_eq!(line_col(t, 0), (1, 1));
        assert_eq!(line_col(t, 3), (2, 1));
        assert_eq!(line_col(t, 3 + "cé ".len()), (2, 4));
        assert_eq!(line_col(t, 1000), (3, 1));
    }
}
