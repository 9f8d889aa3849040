//! Reading the files a scene names (issue 31). Only regular files are
//! opened: a FIFO would block the program until a writer came, a device
//! such as `/dev/zero` never ends, a folder is no file. Each read stops at
//! a limit the format can need (docs/SCENES.md, "Limits"), so a wrong path
//! cannot fill the memory. The errors say why; the caller names the file.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Every file this process has opened as a scene input, so that the
/// command writing images can refuse to overwrite one of them
/// (`output::protect_inputs`).
static FILES_READ: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The files read as scene inputs so far (scene files, meshes, materials,
/// glTF files and buffers, grids, textures, environment images).
pub fn files_read() -> Vec<PathBuf> {
    FILES_READ.lock().map(|v| v.clone()).unwrap_or_default()
}

/// A scene's TOML text: scenes keep geometry in OBJ or glTF files, and a
/// TOML document takes tens of times its size in memory while parsed.
pub const MAX_SCENE_BYTES: u64 = 16 << 20;
/// An OBJ file (about 20 million triangles).
pub const MAX_OBJ_BYTES: u64 = 2 << 30;
/// An MTL file: material statements only.
pub const MAX_MTL_BYTES: u64 = 64 << 20;
/// A `.gltf`, `.glb` or glTF buffer: a GLB's length and a buffer's
/// `byteLength` are 32-bit in practice (the GLB header's field is a u32).
pub const MAX_GLTF_BYTES: u64 = u32::MAX as u64;

/// Err (why) unless `path` is a regular file, or a symbolic link to one;
/// Ok records it as read ([`files_read`]).
pub fn check_regular(path: &Path) -> Result<(), String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if meta.is_file() {
        if let Ok(mut files) = FILES_READ.lock() {
            files.push(path.to_path_buf());
        }
        return Ok(());
    }
    let what = if meta.is_dir() {
        "a folder"
    } else {
        "a FIFO, socket or device"
    };
    Err(format!("{what}, not a regular file"))
}

/// The whole of regular file `path`, at most `limit` bytes.
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    check_regular(path)?;
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let size = file.metadata().map_err(|e| e.to_string())?.len();
    if size > limit {
        return Err(format!(
            "{size} bytes, larger than {} MiB, the most such a file may hold",
            limit >> 20
        ));
    }
    // Reserved up front: memory that cannot be had is an error, not an abort.
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(size as usize + 1)
        .map_err(|_| format!("cannot allocate {size} bytes to read it"))?;
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > limit {
        return Err(format!(
            "larger than {} MiB, the most such a file may hold",
            limit >> 20
        ));
    }
    Ok(bytes)
}

/// [`read_limited`] as UTF-8 text.
pub fn read_text_limited(path: &Path, limit: u64) -> Result<String, String> {
    String::from_utf8(read_limited(path, limit)?).map_err(|_| "not UTF-8 text".to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_and_oversized_ones_are_refused_without_reading_them() {
        let e = read_limited(Path::new("/dev/zero"), 1 << 20).expect_err("a device");
        assert!(e.contains("not a regular file"), "{e}");
        let e = read_limited(Path::new("/"), 1).expect_err("a folder");
        assert!(e.contains("a folder"), "{e}");
        let dir = std::env::temp_dir().join(format!("caustics-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("fifo");
        if std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success())
        {
            // Would block in open() if it were opened.
            let e = read_limited(&fifo, 1).expect_err("a FIFO");
            assert!(e.contains("FIFO"), "{e}");
        }
        let file = dir.join("big");
        std::fs::write(&file, vec![b'x'; 3 << 20]).unwrap();
        let e = read_limited(&file, 2 << 20).expect_err("over the limit");
        assert!(e.contains("3145728 bytes, larger than 2 MiB"), "{e}");
        assert_eq!(read_limited(&file, 3 << 20).unwrap().len(), 3 << 20);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
