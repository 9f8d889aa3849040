//! Where caustics keeps what it can recompute (the demo's pipeline cache,
//! `compare`'s references): `$CAUSTICS_CACHE_DIR`, else
//! `$XDG_CACHE_HOME/caustics`, else `~/.cache/caustics`. The first gives a
//! test or a script a private cache without moving the driver's: Mesa keeps
//! its shader cache under `$XDG_CACHE_HOME` too, and lavapipe without it
//! compiles every shader again (12 s of the demo's first frame).

use std::path::PathBuf;

/// The cache folder, or None when no variable names one (no home).
pub fn cache_dir() -> Option<PathBuf> {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    var("CAUSTICS_CACHE_DIR").map(PathBuf::from).or_else(|| {
        var("XDG_CACHE_HOME")
            .map(PathBuf::from)
            .or_else(|| var("HOME").map(|h| PathBuf::from(h).join(".cache")))
            .map(|base| base.join("caustics"))
    })
}
