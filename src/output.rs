//! Writing images: EXR holds linear radiance (32-bit float, the truth), PNG
//! holds the tonemapped 8-bit sRGB display image. Outputs are written to
//! temporary names in their folder and renamed together at the end
//! ([`write_files`], or [`Batch`] for files written as they are made), so
//! a failure, or a process interrupted by a signal (whose handler calls
//! [`abandon_temporaries`]), never leaves a partial file, nor one image of
//! a pair without the other, and the files they replace stay whole until
//! every new one is in place. Only regular files are replaced (never a
//! link, FIFO or device: [`check_replaceable`]); what a killed run left is
//! removed by the next run writing the same names.

use anyhow::Context as _;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

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
/// known, neither `out` nor its sibling in the other format is a folder,
/// and its folder exists or can be created (the nearest existing folder
/// above it takes a new file). Creates nothing. Returns the (EXR, PNG)
/// paths.
pub fn prepare(out: &Path) -> anyhow::Result<(PathBuf, PathBuf)> {
    let (exr, png) = match format_of(out)? {
        ImageFormat::Exr => (out.to_path_buf(), sibling(out, ImageFormat::Png)),
        ImageFormat::Png => (sibling(out, ImageFormat::Exr), out.to_path_buf()),
    };
    check_writable(out, "--out")?;
    for p in [&exr, &png] {
        if p.is_dir() {
            anyhow::bail!("--out {}: {} is a folder", out.display(), p.display());
        }
        check_replaceable(p).with_context(|| format!("--out {}", out.display()))?;
    }
    Ok((exr, png))
}

/// Checks that the file `path` (named by the option `option`) could be
/// written without creating anything: its nearest existing ancestor folder
/// is a folder that takes a new file (probed by creating and removing one).
pub fn check_writable(path: &Path, option: &str) -> anyhow::Result<()> {
    let dir = folder_of(path);
    let mut existing = dir.as_path();
    while !existing.exists() {
        match existing.parent() {
            Some(p) => {
                existing = if p.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    p
                }
            }
            None => break,
        }
    }
    if !existing.is_dir() {
        anyhow::bail!(
            "{option} {}: cannot create folder {}: {} is not a folder",
            path.display(),
            dir.display(),
            existing.display()
        );
    }
    let probe = existing.join(format!(".caustics-probe-{}", std::process::id()));
    match File::create_new(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(e).with_context(|| {
            format!(
                "{option} {}: cannot write in folder {}",
                path.display(),
                existing.display()
            )
        }),
    }
}

/// Files (device and inode) that no output may replace: the scene's own
/// inputs, registered by the command once the scene is loaded.
static INPUTS: Mutex<Vec<(u64, u64)>> = Mutex::new(Vec::new());

/// Forbids every output from replacing any of `files` (the scene file, its
/// meshes, textures, environment map, ...), whatever path names them.
pub fn protect_inputs(files: &[PathBuf]) {
    use std::os::unix::fs::MetadataExt;
    let mut inputs = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
    for f in files {
        if let Ok(m) = std::fs::metadata(f) {
            inputs.push((m.dev(), m.ino()));
        }
    }
}

/// An output replaces only a regular file: renaming a temporary over a
/// symbolic link, a FIFO or a device node would replace the link or the
/// node itself (as root, `/dev/full` became a regular file); nor one of
/// the scene's inputs ([`protect_inputs`]).
pub fn check_replaceable(path: &Path) -> anyhow::Result<()> {
    use std::os::unix::fs::MetadataExt;
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return Ok(()); // nothing there (or unreadable: the write will say)
    };
    let input = INPUTS
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .contains(&(meta.dev(), meta.ino()));
    let what = if input {
        "one of the scene's input files"
    } else if meta.file_type().is_symlink() {
        "a symbolic link"
    } else if meta.is_dir() {
        "a folder"
    } else if !meta.is_file() {
        "a FIFO, socket or device"
    } else {
        return Ok(());
    };
    anyhow::bail!(
        "{}: {what}; an output replaces only a regular file that is not an input",
        path.display()
    )
}

fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The temporaries being written, process-wide, so that a signal handler
/// can remove them ([`abandon_temporaries`]). A temporary is created and a
/// batch renamed only with this lock held.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn temporaries() -> MutexGuard<'static, Vec<PathBuf>> {
    TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes every temporary output being written and returns the lock that
/// keeps new ones from being created or renamed into place: for a signal
/// handler that then ends the process without releasing it, so that
/// nothing appears at an output name after the signal.
pub fn abandon_temporaries() -> MutexGuard<'static, Vec<PathBuf>> {
    let mut list = temporaries();
    for p in list.drain(..) {
        let _ = std::fs::remove_file(p);
    }
    list
}

/// Writes an output file's bytes.
pub type WriteBytes<'a> = Box<dyn FnOnce(&mut BufWriter<File>) -> anyhow::Result<()> + 'a>;

/// One output file: where it goes and how its bytes are written.
pub struct OutputFile<'a> {
    pub path: &'a Path,
    pub write: WriteBytes<'a>,
}

/// Writes every file of `files` to a temporary name beside it (a hidden
/// `.NAME.PID.partial`) and, once all are written, renames them into place
/// together: all of them or none appear (a failure removes what was already
/// renamed and every temporary).
pub fn write_files(files: Vec<OutputFile>) -> anyhow::Result<()> {
    let mut batch = Batch::default();
    for f in files {
        batch.write(f)?;
    }
    batch.commit()
}

/// Files written one at a time, each to its temporary as soon as it is
/// known, and renamed into place together by [`Batch::commit`], in the
/// order they were written: what [`write_files`] does for files held in
/// memory, for a producer that must not hold them all (`caustics
/// compare`). Until the commit only temporaries exist; a batch dropped
/// uncommitted (an error) removes them, and a signal's handler removes them
/// through [`abandon_temporaries`].
#[derive(Default)]
pub struct Batch {
    /// (temporary, final path), in the order written.
    written: Vec<(PathBuf, PathBuf)>,
}

impl Batch {
    /// Writes `f` to its temporary now.
    pub fn write(&mut self, f: OutputFile) -> anyhow::Result<()> {
        let dir = folder_of(f.path);
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create folder {}", dir.display()))?;
        check_replaceable(f.path)?;
        let name = f
            .path
            .file_name()
            .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        remove_stale_temporaries(&dir, &name);
        let tmp = sibling_temporary(f.path, "partial");
        // Created with the lock held: after a signal's handler took it,
        // no temporary can appear.
        let file = {
            let mut list = temporaries();
            let file =
                File::create(&tmp).with_context(|| format!("cannot write {}", f.path.display()))?;
            list.push(tmp.clone());
            file
        };
        self.written.push((tmp, f.path.to_path_buf()));
        let mut w = BufWriter::new(file);
        (f.write)(&mut w)
            .and_then(|()| Ok(w.flush()?))
            .with_context(|| format!("cannot write {}", f.path.display()))?;
        test_pause();
        Ok(())
    }

    /// How many files were written.
    pub fn len(&self) -> usize {
        self.written.len()
    }

    /// Whether no file was written.
    pub fn is_empty(&self) -> bool {
        self.written.is_empty()
    }

    /// Renames every temporary into place, in the order written. The files
    /// they replace are moved aside first (`.NAME.PID.previous`) and
    /// removed only once every new file is in place: on a failure the new
    /// files already renamed are removed and the previous ones put back,
    /// so the earlier output survives whole (and, on drop, the
    /// temporaries go).
    pub fn commit(mut self) -> anyhow::Result<()> {
        let mut list = temporaries();
        for (_, path) in &self.written {
            check_replaceable(path)?;
        }
        // (final path, where its previous file waits, if it had one)
        let mut placed: Vec<(PathBuf, Option<PathBuf>)> = Vec::new();
        let mut failure = None;
        for (tmp, path) in &self.written {
            let previous = path.is_file().then(|| sibling_temporary(path, "previous"));
            if let Some(previous) = &previous {
                if let Err(e) = std::fs::rename(path, previous) {
                    failure = Some((e, format!("cannot write {}", path.display())));
                    break;
                }
            }
            if let Err(e) = std::fs::rename(tmp, path) {
                if let Some(previous) = &previous {
                    let _ = std::fs::rename(previous, path);
                }
                failure = Some((e, format!("cannot write {}", path.display())));
                break;
            }
            list.retain(|p| p != tmp);
            placed.push((path.clone(), previous));
        }
        if let Some((e, message)) = failure {
            for (path, previous) in placed.iter().rev() {
                let _ = std::fs::remove_file(path);
                if let Some(previous) = previous {
                    let _ = std::fs::rename(previous, path);
                }
            }
            let placed: Vec<&PathBuf> = placed.iter().map(|(p, _)| p).collect();
            self.written.retain(|(_, p)| !placed.contains(&p));
            return Err(e).context(message);
        }
        for (_, previous) in placed {
            if let Some(previous) = previous {
                let _ = std::fs::remove_file(previous);
            }
        }
        self.written.clear();
        Ok(())
    }
}

impl Drop for Batch {
    /// An uncommitted batch removes its temporaries.
    fn drop(&mut self) {
        let mut list = temporaries();
        for (tmp, _) in &self.written {
            let _ = std::fs::remove_file(tmp);
            list.retain(|p| p != tmp);
        }
    }
}

/// A hidden file beside `path` for this process: `.NAME.PID.KIND`.
fn sibling_temporary(path: &Path, kind: &str) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    folder_of(path).join(format!(".{name}.{}.{kind}", std::process::id()))
}

/// Removes what a killed run left beside output `name` in `dir`: its
/// `.NAME.PID.partial` temporaries and `.NAME.PID.previous` files whose
/// process no longer runs (`/proc/PID` is gone; where there is no `/proc`,
/// nothing is removed). A `.previous` file of a dead run is the earlier
/// output it had moved aside; it goes back in place when no output took it.
fn remove_stale_temporaries(dir: &Path, name: &str) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let prefix = format!(".{name}.");
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let Some(rest) = file.strip_prefix(&prefix) else {
            continue;
        };
        let Some((pid, kind)) = rest.split_once('.') else {
            continue;
        };
        let alive = pid.parse::<u32>().is_ok_and(|pid| {
            pid == std::process::id() || Path::new("/proc").join(pid.to_string()).exists()
        });
        if alive || pid.parse::<u32>().is_err() {
            continue;
        }
        let stale = entry.path();
        match kind {
            "partial" => {
                let _ = std::fs::remove_file(&stale);
            }
            "previous" => {
                let output = dir.join(name);
                if output.exists() {
                    let _ = std::fs::remove_file(&stale);
                } else {
                    let _ = std::fs::rename(&stale, &output);
                }
            }
            _ => {}
        }
    }
}

/// A test hook (tests/suite/interrupt.rs): `CAUSTICS_TEST_WRITE_PAUSE_MS` pauses
/// after each temporary is written, so that a test can aim a signal at the
/// moment between writing and renaming.
fn test_pause() {
    if let Some(ms) = std::env::var("CAUSTICS_TEST_WRITE_PAUSE_MS")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
}

/// Linear RGBA f32 radiance as an OpenEXR file.
pub fn exr_file<'a>(path: &'a Path, width: u32, height: u32, rgba: &'a [f32]) -> OutputFile<'a> {
    OutputFile {
        path,
        write: Box::new(move |w| {
            let image = image::Rgba32FImage::from_raw(width, height, rgba.to_vec())
                .ok_or_else(|| anyhow::anyhow!("radiance buffer has the wrong size"))?;
            Ok(image.write_to(w, image::ImageFormat::OpenExr)?)
        }),
    }
}

/// 8-bit sRGB RGBA as a PNG file.
pub fn png_file<'a>(path: &'a Path, width: u32, height: u32, rgba8: &'a [u8]) -> OutputFile<'a> {
    OutputFile {
        path,
        write: Box::new(move |w| {
            let image = image::RgbaImage::from_raw(width, height, rgba8.to_vec())
                .ok_or_else(|| anyhow::anyhow!("display buffer has the wrong size"))?;
            Ok(image.write_to(w, image::ImageFormat::Png)?)
        }),
    }
}

/// Writes linear RGBA f32 radiance as an OpenEXR file.
pub fn write_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> anyhow::Result<()> {
    write_files(vec![exr_file(path, width, height, rgba)])
}

/// Writes 8-bit sRGB RGBA as a PNG file.
pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> anyhow::Result<()> {
    write_files(vec![png_file(path, width, height, rgba8)])
}

/// Reads an EXR back as RGBA f32 (tests and comparisons).
/// Refuses, in one message naming the file, anything but a regular file
/// holding an OpenEXR image (a PNG holds display values, not radiance) and
/// any texel that is not finite or whose rgb is negative. Decoding keeps
/// the image crate's default limits (at most 512 MiB allocated).
pub fn read_exr(path: &Path) -> anyhow::Result<(u32, u32, Vec<f32>)> {
    let cannot_read = || format!("cannot read {}", path.display());
    if !std::fs::metadata(path).with_context(cannot_read)?.is_file() {
        anyhow::bail!("{}: not a regular file", path.display());
    }
    let reader = image::ImageReader::open(path)
        .with_context(cannot_read)?
        .with_guessed_format()
        .with_context(cannot_read)?;
    if reader.format() != Some(image::ImageFormat::OpenExr) {
        anyhow::bail!(
            "{}: not an OpenEXR image (linear radiance is read from EXR files only)",
            path.display()
        );
    }
    let img = reader.decode().with_context(cannot_read)?.into_rgba32f();
    let (width, height) = (img.width(), img.height());
    let texels = img.into_raw();
    let bad = texels
        .chunks_exact(4)
        .position(|t| !t.iter().all(|v| v.is_finite()) || t[..3].iter().any(|v| *v < 0.0));
    if let Some(i) = bad {
        let (x, y) = (i as u32 % width, i as u32 / width);
        anyhow::bail!(
            "{}: texel ({x}, {y}) is {:?}: radiance must be finite and non-negative",
            path.display(),
            &texels[4 * i..4 * i + 3]
        );
    }
    Ok((width, height, texels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_rename_leaves_no_partial_file() {
        let dir = std::env::temp_dir().join(format!("caustics-output-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        // The target is a folder: refused before anything is written.
        let target = dir.join("x.png");
        std::fs::create_dir_all(&target).unwrap();
        let e = write_png(&target, 1, 1, &[0, 0, 0, 255]).expect_err("a folder is in the way");
        assert!(e.to_string().contains("a folder"), "{e:#}");
        // A pair whose PNG cannot be placed: the earlier EXR survives as it was.
        let exr = dir.join("x.exr");
        std::fs::write(&exr, "earlier output").unwrap();
        let e = write_files(vec![
            exr_file(&exr, 1, 1, &[0.0; 4]),
            png_file(&target, 1, 1, &[0, 0, 0, 255]),
        ])
        .expect_err("a folder is in the way");
        assert!(e.to_string().contains("a folder"), "{e:#}");
        assert_eq!(std::fs::read_to_string(&exr).unwrap(), "earlier output");
        std::fs::remove_file(&exr).unwrap();
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(
            left,
            vec![std::ffi::OsString::from("x.png")],
            "only the folder in the way"
        );
        assert!(prepare(&dir.join("x.exr")).is_err());
        assert!(prepare(&dir.join("sub/y.exr")).is_ok());
        assert!(!dir.join("sub").exists(), "prepare creates nothing");
        std::fs::write(dir.join("file"), "").unwrap();
        let e = prepare(&dir.join("file/z.png")).expect_err("a file is in the way");
        assert!(e.to_string().contains("is not a folder"), "{e:#}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_batch_shows_its_files_only_when_committed() {
        let dir = std::env::temp_dir().join(format!("caustics-batch-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let names = |dir: &Path| -> Vec<String> {
            let mut v: Vec<String> = std::fs::read_dir(dir)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        let (a, b) = (dir.join("a.exr"), dir.join("b.png"));
        let mut batch = Batch::default();
        batch.write(exr_file(&a, 1, 1, &[0.0; 4])).unwrap();
        batch.write(png_file(&b, 1, 1, &[0, 0, 0, 255])).unwrap();
        assert_eq!(batch.len(), 2);
        assert!(names(&dir).iter().all(|n| n.ends_with(".partial")));
        drop(batch);
        assert!(
            names(&dir).is_empty(),
            "an uncommitted batch leaves nothing"
        );
        let mut batch = Batch::default();
        batch.write(exr_file(&a, 1, 1, &[0.0; 4])).unwrap();
        batch.write(png_file(&b, 1, 1, &[0, 0, 0, 255])).unwrap();
        batch.commit().unwrap();
        assert_eq!(names(&dir), vec!["a.exr", "b.png"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Issue 31: an output path holding a symbolic link or a FIFO is
    /// refused and left as it was; a replaced regular file is replaced
    /// only once the new one is complete; temporaries of a run killed
    /// with SIGKILL are removed by the next run into the same place.
    #[test]
    fn outputs_replace_only_regular_files_and_clean_up_after_killed_runs() {
        let dir = std::env::temp_dir().join(format!("caustics-replace-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let kept = dir.join("kept.txt");
        std::fs::write(&kept, "not an image").unwrap();
        let link = dir.join("link.png");
        std::os::unix::fs::symlink(&kept, &link).unwrap();
        let fifo = dir.join("fifo.png");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        let mut special = vec![(link.clone(), "symbolic link")];
        if made.is_ok_and(|s| s.success()) {
            special.push((fifo.clone(), "FIFO"));
        }
        for (path, what) in &special {
            let e = write_png(path, 1, 1, &[0, 0, 0, 255]).expect_err("refused");
            assert!(e.to_string().contains(what), "{e:#}");
            let e = prepare(path).expect_err("refused before rendering");
            assert!(format!("{e:#}").contains(what), "{e:#}");
        }
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read_to_string(&kept).unwrap(), "not an image");

        // A run killed between writing and renaming (a PID that no longer
        // runs): its temporary goes; its moved-aside earlier output comes back.
        let out = dir.join("r.png");
        let dead = u32::MAX - 1;
        std::fs::write(dir.join(format!(".r.png.{dead}.partial")), "half").unwrap();
        std::fs::write(dir.join(format!(".q.png.{dead}.previous")), "earlier q").unwrap();
        write_png(&out, 1, 1, &[0, 0, 0, 255]).unwrap();
        write_png(&dir.join("q.png"), 1, 1, &[0, 0, 0, 255]).unwrap();
        let mut left: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        let mut expected = vec!["kept.txt", "link.png", "q.png", "r.png"];
        if special.len() == 2 {
            expected.insert(0, "fifo.png");
        }
        assert_eq!(left, expected);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
