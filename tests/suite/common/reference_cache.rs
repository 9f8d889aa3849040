//! Reference renders traced once per content (issue 26): the tests that
//! compare with the ground truth ask for it here, and a render is traced on
//! the first request and then served from memory (other tests of the run)
//! and from `target/tmp/reference-cache/` (later runs).
//!
//! The cache is content-addressed: the key hashes everything that decides
//! the images, so a change of any input is a miss, never a stale hit:
//! - the scene as resolved (its `Debug` text: every position, material,
//!   light and texel; Rust prints floats so that they read back exactly;
//!   not the path it was loaded by),
//! - the image size, the `ReferenceSettings` (seed included), the photon
//!   count and whether it is traced in two halves,
//! - the renderer's code: every file under `src/` and `glsl/`, `build.rs`,
//!   `Cargo.toml` and `Cargo.lock` (so the shaders and the tracer),
//! - the device and driver it was traced on.
//!
//! Every component is resolved at every checkpoint (a resolve costs a small
//! fraction of a pass), so tests that trace the same light but read other
//! components share one render. The tests of the reference itself
//! (`reference`, `reference_lights`, `reference_ppm`) trace their own: they
//! test the tracer, not a comparison against it.
//!
//! `CAUSTICS_REFERENCE_CACHE=off` traces everything anew (nothing read or
//! written); deleting the folder does the same once.

use caustics::reference::{Component, ReferenceRenderer, ReferenceSettings};
use caustics::scene::Scene;
use caustics::vk::Context;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

/// What to trace: `scene` at `width` x `height`, time 0, `photons` photons
/// with `settings`; with `halves`, in two equal halves, resolved after each.
#[derive(Clone, Debug)]
pub struct ReferenceRequest<'a> {
    pub scene: &'a Scene,
    pub width: u32,
    pub height: u32,
    pub settings: ReferenceSettings,
    pub photons: u64,
    pub halves: bool,
}

impl<'a> ReferenceRequest<'a> {
    /// `photons` at `size`², default settings, in one run.
    pub fn new(scene: &'a Scene, size: u32, photons: u64) -> Self {
        Self {
            scene,
            width: size,
            height: size,
            settings: ReferenceSettings::default(),
            photons,
            halves: false,
        }
    }

    /// The same, traced in two halves (`first_half` then reads the first).
    pub fn in_halves(self) -> Self {
        Self {
            halves: true,
            ..self
        }
    }

    pub fn with_settings(self, settings: ReferenceSettings) -> Self {
        Self { settings, ..self }
    }
}

/// Every component of one reference render (RGBA f32, rows top to bottom).
pub struct ReferenceImages {
    /// Photons traced in all.
    pub photons: u64,
    /// `ReferenceRenderer::noise` after the last photon.
    pub noise: Option<f64>,
    /// Per `Component::NAMED` entry: after the first half (empty without
    /// halves), and after all photons.
    first_half: Vec<Vec<f32>>,
    whole: Vec<Vec<f32>>,
}

fn component_index(c: Component) -> usize {
    Component::NAMED
        .iter()
        .position(|(_, n)| *n == c)
        .expect("a named component")
}

impl ReferenceImages {
    /// Component `c` after all photons.
    pub fn whole(&self, c: Component) -> &[f32] {
        &self.whole[component_index(c)]
    }

    /// Component `c` after the first half of the photons (asked `in_halves`).
    pub fn first_half(&self, c: Component) -> &[f32] {
        let img = &self.first_half[component_index(c)];
        assert!(!img.is_empty(), "the reference was not traced in halves");
        img
    }

    fn trace(ctx: &Arc<Context>, req: &ReferenceRequest) -> Self {
        let mut r = ReferenceRenderer::new(
            ctx,
            req.scene.clone(),
            req.width,
            req.height,
            0.0,
            req.settings,
        )
        .expect("reference renderer");
        let resolve_all = |r: &mut ReferenceRenderer| -> Vec<Vec<f32>> {
            Component::NAMED
                .iter()
                .map(|(_, c)| r.resolve(*c).expect("reference resolve"))
                .collect()
        };
        let mut first_half = Vec::new();
        if req.halves {
            r.trace(req.photons / 2, |_, _| {})
                .expect("reference trace");
            first_half = resolve_all(&mut r);
            r.trace(req.photons / 2, |_, _| {})
                .expect("reference trace");
        } else {
            r.trace(req.photons, |_, _| {}).expect("reference trace");
        }
        let whole = resolve_all(&mut r);
        let noise = r.noise().expect("reference noise");
        Self {
            photons: r.reference.photons,
            noise,
            first_half,
            whole,
        }
    }

    const MAGIC: &'static [u8; 8] = b"CAUREF01";

    fn to_bytes(&self) -> Vec<u8> {
        let mut out = Self::MAGIC.to_vec();
        out.extend(self.photons.to_le_bytes());
        out.extend(self.noise.unwrap_or(f64::NAN).to_le_bytes());
        for list in [&self.first_half, &self.whole] {
            out.extend((list.len() as u64).to_le_bytes());
            for img in list {
                out.extend((img.len() as u64).to_le_bytes());
                out.extend(img.iter().flat_map(|v| v.to_le_bytes()));
            }
        }
        out
    }

    /// None for a file that is not one whole cache entry (a torn or foreign
    /// file is a miss, traced again).
    fn from_bytes(bytes: &[u8]) -> Option<Self> {
        let mut at = 0usize;
        let mut take = |n: usize| -> Option<&[u8]> {
            let s = bytes.get(at..at.checked_add(n)?)?;
            at += n;
            Some(s)
        };
        if take(8)? != Self::MAGIC {
            return None;
        }
        let u64_at = |s: &[u8]| u64::from_le_bytes(s.try_into().unwrap());
        let photons = u64_at(take(8)?);
        let noise = f64::from_le_bytes(take(8)?.try_into().unwrap());
        let mut lists = Vec::new();
        for _ in 0..2 {
            let count = u64_at(take(8)?) as usize;
            let mut list = Vec::new();
            for _ in 0..count {
                let len = u64_at(take(8)?) as usize;
                let raw = take(len.checked_mul(4)?)?;
                list.push(
                    raw.chunks_exact(4)
                        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                );
            }
            lists.push(list);
        }
        if at != bytes.len() {
            return None;
        }
        let whole = lists.pop()?;
        let first_half = lists.pop()?;
        Some(Self {
            photons,
            noise: (!noise.is_nan()).then_some(noise),
            first_half,
            whole,
        })
    }
}

/// A 128-bit content hash: two SipHash-1-3 streams with different keys
/// (std's `DefaultHasher::new()` has fixed keys, so it is stable for a
/// given toolchain; a toolchain that hashes otherwise only misses).
struct ContentHash([std::collections::hash_map::DefaultHasher; 2]);

impl ContentHash {
    fn new() -> Self {
        let mut h = [
            std::collections::hash_map::DefaultHasher::new(),
            std::collections::hash_map::DefaultHasher::new(),
        ];
        1u8.hash(&mut h[1]);
        Self(h)
    }
    fn add(&mut self, bytes: &[u8]) {
        for h in &mut self.0 {
            bytes.len().hash(h);
            h.write(bytes);
        }
    }
    fn hex(&self) -> String {
        format!("{:016x}{:016x}", self.0[0].finish(), self.0[1].finish())
    }
}

/// The hash of the renderer's code as it is on disk now (see the module
/// docs), computed once per process.
fn code_hash() -> &'static str {
    static HASH: OnceLock<String> = OnceLock::new();
    HASH.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut files = Vec::new();
        for dir in ["src", "glsl"] {
            collect_files(&root.join(dir), &mut files);
        }
        for file in ["build.rs", "Cargo.toml", "Cargo.lock"] {
            files.push(root.join(file));
        }
        files.sort();
        let mut h = ContentHash::new();
        for f in files {
            h.add(f.strip_prefix(root).unwrap().to_string_lossy().as_bytes());
            h.add(&std::fs::read(&f).unwrap_or_default());
        }
        h.hex()
    })
}

fn collect_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let path = e.path();
        if path.is_dir() {
            collect_files(&path, out);
        } else {
            out.push(path);
        }
    }
}

fn key(ctx: &Context, req: &ReferenceRequest) -> String {
    let mut h = ContentHash::new();
    h.add(code_hash().as_bytes());
    h.add(format!("{} {}", ctx.info.name, ctx.info.driver).as_bytes());
    // The file a scene came from only resolved its relative paths while it
    // was loaded; the same file loaded by another path is the same scene.
    let scene = Scene {
        source: PathBuf::new(),
        ..req.scene.clone()
    };
    h.add(format!("{scene:?}").as_bytes());
    h.add(
        format!(
            "{}x{} {:?} {} {}",
            req.width, req.height, req.settings, req.photons, req.halves
        )
        .as_bytes(),
    );
    h.hex()
}

fn cache_dir() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("reference-cache")
}

fn cache_enabled() -> bool {
    std::env::var("CAUSTICS_REFERENCE_CACHE").map_or(true, |v| v != "off")
}

/// The reference render `req` asks for: from this run's memory, else from
/// the cache folder, else traced (and stored in both). Tests asking for the
/// same key at once wait for one trace.
pub fn reference_images(ctx: &Arc<Context>, req: &ReferenceRequest) -> Arc<ReferenceImages> {
    if !cache_enabled() {
        return Arc::new(ReferenceImages::trace(ctx, req));
    }
    type Slot = Arc<Mutex<Option<Arc<ReferenceImages>>>>;
    static SLOTS: OnceLock<Mutex<HashMap<String, Slot>>> = OnceLock::new();
    let key = key(ctx, req);
    let slot = SLOTS
        .get_or_init(Default::default)
        .lock()
        .unwrap()
        .entry(key.clone())
        .or_default()
        .clone();
    // Held while tracing: a second test with the same key waits here.
    let mut slot = slot.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(images) = slot.as_ref() {
        return images.clone();
    }
    let path = cache_dir().join(format!("{key}.bin"));
    let images = match std::fs::read(&path)
        .ok()
        .and_then(|b| ReferenceImages::from_bytes(&b))
    {
        Some(images) => {
            eprintln!("reference cache: hit {}", path.display());
            images
        }
        None => {
            let start = std::time::Instant::now();
            let images = ReferenceImages::trace(ctx, req);
            eprintln!(
                "reference cache: traced {} ({}x{}, {} photons) in {:.1} s",
                req.scene.source.display(),
                req.width,
                req.height,
                images.photons,
                start.elapsed().as_secs_f64()
            );
            store(&path, &images.to_bytes());
            images
        }
    };
    let images = Arc::new(images);
    *slot = Some(images.clone());
    images
}

/// Writes the entry beside its place and renames it there, so a reader
/// never sees half a file; a failure to store only costs a later trace.
fn store(path: &Path, bytes: &[u8]) {
    let dir = path.parent().unwrap();
    let tmp = dir.join(format!(
        ".{}.{}.tmp",
        path.file_name().unwrap().to_string_lossy(),
        std::process::id()
    ));
    let ok = std::fs::create_dir_all(dir).is_ok()
        && std::fs::write(&tmp, bytes).is_ok()
        && std::fs::rename(&tmp, path).is_ok();
    if !ok {
        let _ = std::fs::remove_file(&tmp);
        eprintln!("reference cache: could not store {}", path.display());
    }
}
