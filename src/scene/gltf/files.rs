//! The file's bytes: buffers and images from the GLB chunk, `data:` URIs or
//! files beside the glTF.

use super::*;

/// Every buffer's bytes: the GLB chunk (borrowed, not copied), a base64
/// `data:` URI or a file beside the glTF, at least `byteLength` long.
pub(super) fn read_buffers<'b>(
    document: &Document,
    blob: Option<&'b [u8]>,
    within: &Confinement,
    fail: Fail,
) -> Result<Vec<Cow<'b, [u8]>>, GltfError> {
    let mut out = Vec::new();
    for b in document.buffers() {
        let at = format!("buffers[{}]", b.index());
        let data = match b.source() {
            ::gltf::buffer::Source::Bin => blob.map(Cow::Borrowed).ok_or_else(|| {
                fail(
                    &at,
                    "refers to the GLB binary chunk, but the file has none".into(),
                )
            })?,
            ::gltf::buffer::Source::Uri(uri) => {
                Cow::Owned(read_uri(uri, within).map_err(|e| fail(&format!("{at}.uri"), e))?)
            }
        };
        if data.len() < b.length() {
            return Err(fail(
                &format!("{at}.byteLength"),
                format!("is {} but the data holds {} bytes", b.length(), data.len()),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// A URI's bytes: a base64 `data:` URI decoded, else a file ([`uri_file`]).
pub(super) fn read_uri(uri: &str, within: &Confinement) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let payload = rest
            .split_once(";base64,")
            .map(|(_, p)| p)
            .ok_or("only base64 data URIs are supported")?;
        return base64_decode(payload).ok_or_else(|| "invalid base64 data".into());
    }
    let file = uri_file(uri, within)?;
    crate::scene::input::read_limited(&file, crate::scene::input::MAX_GLTF_BYTES)
        .map_err(|e| format!("cannot read {}: {e}", file.display()))
}

/// The file a non-`data:` URI names: a relative reference, percent-decoded,
/// resolved by the scene's one path rule ([`Confinement::resolve`]: inside
/// the glTF file's folder tree or an `--allow-paths` folder; issue 31: a
/// downloaded asset must not read `/etc/passwd`). A scheme (`file:`
/// included) and an absolute path (`/...`, even one inside the tree: an
/// asset that names one is not portable) are refused before that, and `..`
/// is checked after percent-decoding, so `%2e%2e/` too.
pub(super) fn uri_file(uri: &str, within: &Confinement) -> Result<PathBuf, String> {
    if uri.contains(':') {
        return Err(format!(
            "URI `{uri}`: a scheme (file:, http:, ...) or drive; only relative references to files are read"
        ));
    }
    let decoded = percent_decode(uri);
    if decoded.starts_with(['/', '\\']) {
        return Err(format!(
            "URI `{uri}`: an absolute path; only references relative to the glTF file are read"
        ));
    }
    within.file(decoded).map_err(|e| format!("URI {e}"))
}

pub(super) fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = b.get(i + 1..i + 3).and_then(|h| {
            std::str::from_utf8(h)
                .ok()
                .and_then(|h| u8::from_str_radix(h, 16).ok())
        });
        match (b[i], hex) {
            (b'%', Some(v)) => {
                out.push(v);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Standard base64 (RFC 4648, `=` padding optional); `None` on a bad character.
pub(super) fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' => Some(62),
        b'/' => Some(63),
        _ => None,
    };
    let s = s.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0);
    for &c in s {
        acc = (acc << 6) | value(c)? as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    Some(out)
}

/// Every image given by a file URI must exist (images are not decoded here).
pub(super) fn check_images(
    document: &Document,
    within: &Confinement,
    fail: Fail,
) -> Result<(), GltfError> {
    for image in document.images() {
        if let ::gltf::image::Source::Uri { uri, .. } = image.source() {
            if uri.starts_with("data:") {
                continue;
            }
            let at = format!("images[{}].uri", image.index());
            let file = uri_file(uri, within).map_err(|e| fail(&at, e))?;
            if !file.is_file() {
                return Err(fail(
                    &at,
                    format!("image file {} not found", file.display()),
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_with_and_without_padding() {
        assert_eq!(base64_decode("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64_decode("aGVsbG8").unwrap(), b"hello");
        assert_eq!(base64_decode("AAECAw==").unwrap(), [0, 1, 2, 3]);
        assert!(base64_decode("a*b").is_none());
    }

    #[test]
    fn percent_decoding_of_uris() {
        assert_eq!(percent_decode("my%20model.bin"), "my model.bin");
        assert_eq!(percent_decode("100%"), "100%");
    }
}
