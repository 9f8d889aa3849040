//! Writing images: EXR holds linear radiance (32-bit float, the truth), PNG
//! holds the tonemapped 8-bit sRGB display image. Files are written to a
//! temporary name and renamed, so a failure never leaves a partial image.

use anyhow::Context as _;
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Exr,
}

/// The format an output path asks for, by extension.
pub fn format_of(path: &Path) -> anyhow::Result<ImageFormat> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("png") => Ok(ImageFormat::Png),
        Some("exr") => Ok(ImageFormat::Exr),
        _ => anyhow::bail!(
            "--out {}: the file name must end in .png or .exr",
            path.display()
        ),
    }
}

/// The same path with the other format's extension.
pub fn sibling(path: &Path, format: ImageFormat) -> PathBuf {
    path.with_extension(match format {
        ImageFormat::Png => "png",
        ImageFormat::Exr => "exr",
    })
}

/// Checks, before any rendering, that `out` can be written: its format is
/// known, its folder exists (created if needed) and neither `out` nor its
/// sibling in the other format is a folder. Returns the (EXR, PNG) paths.
pub fn prepare(out: &Path) -> anyhow::Result<(PathBuf, PathBuf)> {
    let (exr, png) = match format_of(out)? {
        ImageFormat::Exr => (out.to_path_buf(), sibling(out, ImageFormat::Png)),
        ImageFormat::Png => (sibling(out, ImageFormat::Exr), out.to_path_buf()),
    };
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| {
            format!(
                "--out {}: cannot create folder {}",
                out.display(),
                dir.display()
            )
        })?;
    }
    for p in [&exr, &png] {
        if p.is_dir() {
            anyhow::bail!("--out {}: {} is a folder", out.display(), p.display());
        }
    }
    Ok((exr, png))
}

fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create folder {}", dir.display()))?;
    }
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("img");
    let tmp = path.with_extension(format!("partial.{ext}"));
    match write(&tmp) {
        Ok(()) => std::fs::rename(&tmp, path).or_else(|e| {
            let _ = std::fs::remove_file(&tmp);
            Err(e).with_context(|| format!("cannot write {}", path.display()))
        }),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// Writes linear RGBA f32 radiance as an OpenEXR file.
pub fn write_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> anyhow::Result<()> {
    let image = image::Rgba32FImage::from_raw(width, height, rgba.to_vec())
        .ok_or_else(|| anyhow::anyhow!("radiance buffer has the wrong size"))?;
    write_atomically(path, |tmp| {
        image
            .save_with_format(tmp, image::ImageFormat::OpenExr)
            .with_context(|| format!("cannot write {}", path.display()))
    })
}

/// Writes 8-bit sRGB RGBA as a PNG file.
pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> anyhow::Result<()> {
    let image = image::RgbaImage::from_raw(width, height, rgba8.to_vec())
        .ok_or_else(|| anyhow::anyhow!("display buffer has the wrong size"))?;
    write_atomically(path, |tmp| {
        image
            .save_with_format(tmp, image::ImageFormat::Png)
            .with_context(|| format!("cannot write {}", path.display()))
    })
}

/// Reads an EXR back as RGBA f32 (tests and comparisons).
pub fn read_exr(path: &Path) -> anyhow::Result<(u32, u32, Vec<f32>)> {
    let img = image::open(path)
        .with_context(|| format!("cannot read {}", path.display()))?
        .into_rgba32f();
    Ok((img.width(), img.height(), img.into_raw()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_rename_leaves_no_partial_file() {
        let dir = std::env::temp_dir().join(format!("caustics-output-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        // The target is a folder: the temporary file is written, the rename fails.
        let target = dir.join("x.png");
        std::fs::create_dir_all(&target).unwrap();
        let e = write_png(&target, 1, 1, &[0, 0, 0, 255]).expect_err("a folder is in the way");
        assert!(e.to_string().contains("cannot write"), "{e:#}");
        assert!(!dir.join("x.partial.png").exists());
        assert!(prepare(&dir.join("x.exr")).is_err());
        assert!(prepare(&dir.join("sub/y.exr")).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
