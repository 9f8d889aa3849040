//! Reference renders traced once per content (issue 26): the tests that
//! compare with the ground truth ask for it here, and a render is traced on
//! the first request and then served from memory (other tests of the run)
//! and from `target/tmp/reference-cache/` (later runs).
//!
//! The cache is content-addressed (`caustics compare`'s `cache_key`, with
//! the tests' additions): the key hashes everything that decides the
//! images, so a change of any input is a miss, never a stale hit:
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

use caustics::compare::{cache_key, stable_hash, ReferenceKey};
use caustics::reference::{Component, ReferenceRenderer, ReferenceSettings};
use caustics::scene::Scene;
use caustics::vk::Context;
use std::collections::HashMap;
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

    /// The same passes (per half too), each of `CAMERA_SIDE_BATCH` photons:
    /// for comparisons that read only what `camera_side` says.
    pub fn camera_side(self) -> Self {
        let runs = if self.halves { 2 } else { 1 };
        let (settings, photons) = camera_side(self.settings, self.photons / runs);
        Self {
            settings,
            photons: photons * runs,
            ..self
        }
    }
}

/// Photons per pass of a camera-side reference (`camera_side`).
pub const CAMERA_SIDE_BATCH: u32 = 4096;

/// Settings and photon count that trace the same number of passes as
/// `settings` with `photons`, each of `CAMERA_SIDE_BATCH` photons. What
/// the reference samples from the camera (from point, spot, directional,
/// rect and triangle lights: the direct light, and the single scattering
/// where no ray of the pixel meets a specular surface first: glass, a
/// mirror or a mixed material; glsl/reference/camera.comp)
/// comes out bit for bit the same: the camera's random streams follow the
/// pass and the pixel, and no photon from those lights adds to it
/// (`reference::camera_side_components_do_not_depend_on_the_photons`).
/// A comparison that reads only those components gets the same images for
/// the camera's pass alone, where the photons were 90% of the time.
pub fn camera_side(settings: ReferenceSettings, photons: u64) -> (ReferenceSettings, u64) {
    let passes = settings.passes_for(photons);
    let settings = ReferenceSettings {
        batch: CAMERA_SIDE_BATCH,
        ..settings
    };
    (settings, passes * CAMERA_SIDE_BATCH as u64)
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
            photons: r.photons(),
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

/// The hash of the renderer's code as it is on disk now (see the module
/// docs), computed once per process.
fn code_hash() -> u64 {
    static HASH: OnceLock<u64> = OnceLock::new();
    *HASH.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut files = Vec::new();
        for dir in ["src", "glsl"] {
            collect_files(&root.join(dir), &mut files);
        }
        for file in ["build.rs", "Cargo.toml", "Cargo.lock"] {
            files.push(root.join(file));
        }
        files.sort();
        let parts: Vec<(String, Vec<u8>)> = files
            .iter()
            .map(|f| {
                let name = f.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                (name, std::fs::read(f).unwrap_or_default())
            })
            .collect();
        stable_hash(
            parts
                .iter()
                .flat_map(|(name, bytes)| [name.as_bytes(), bytes.as_slice()]),
        )
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

/// `caustics compare`'s cache key (the resolved scene, the size, the
/// settings, the reference shaders) with what the tests need beside it:
/// the photon schedule, the host code and the device.
fn key(device: &str, req: &ReferenceRequest) -> String {
    // The file a scene came from only resolved its relative paths while it
    // was loaded; the same file loaded by another path is the same scene.
    let scene = Scene {
        source: PathBuf::new(),
        ..req.scene.clone()
    };
    let key = ReferenceKey {
        width: req.width,
        height: req.height,
        time: 0.0,
        diffuse_bounces: req.settings.diffuse_bounces,
        budget: format!(
            "photons {} in halves {}; code {:016x}; device {device}",
            req.photons,
            req.halves,
            code_hash(),
        ),
        settings: format!("{:?}", req.settings),
    };
    cache_key(&scene, &key)
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
    let key = key(&format!("{} {}", ctx.info.name, ctx.info.driver), req);
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

/// Every input of the key changes it, the same inputs give the same key
/// (whatever path the scene was loaded by), and an entry reads back as it
/// was written while a torn one reads as a miss.
#[test]
fn reference_cache_key_and_entries() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ball_lens.toml");
    let scene = Scene::load(&path).unwrap();
    let req = ReferenceRequest::new(&scene, 64, 1 << 20);
    let base = key("lavapipe", &req);
    let same_file = Scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/environments/../ball_lens.toml"),
    )
    .unwrap();
    assert_eq!(
        base,
        key("lavapipe", &ReferenceRequest::new(&same_file, 64, 1 << 20))
    );
    let mut brighter = scene.clone();
    brighter.lights[0].intensity *= 2.0;
    let seeded = ReferenceSettings {
        seed: 1,
        ..ReferenceSettings::default()
    };
    let changed = [
        key("another device", &req),
        key("lavapipe", &ReferenceRequest::new(&brighter, 64, 1 << 20)),
        key(
            "lavapipe",
            &ReferenceRequest {
                width: 65,
                ..req.clone()
            },
        ),
        key(
            "lavapipe",
            &ReferenceRequest {
                height: 65,
                ..req.clone()
            },
        ),
        key("lavapipe", &ReferenceRequest::new(&scene, 64, 1 << 21)),
        key("lavapipe", &req.clone().in_halves()),
        key("lavapipe", &req.clone().with_settings(seeded)),
    ];
    for (i, k) in changed.iter().enumerate() {
        assert_ne!(*k, base, "input {i} left the key unchanged");
    }

    let images = ReferenceImages {
        photons: 1 << 20,
        noise: Some(0.25),
        first_half: vec![vec![1.0, -2.5, f32::MAX, 0.0]; Component::NAMED.len()],
        whole: vec![vec![0.5; 8]; Component::NAMED.len()],
    };
    let bytes = images.to_bytes();
    let back = ReferenceImages::from_bytes(&bytes).expect("a whole entry");
    assert_eq!(back.photons, images.photons);
    assert_eq!(back.noise, images.noise);
    assert_eq!(back.first_half, images.first_half);
    assert_eq!(back.whole, images.whole);
    assert!(ReferenceImages::from_bytes(&bytes[..bytes.len() - 1]).is_none());
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(ReferenceImages::from_bytes(&longer).is_none());
    assert!(ReferenceImages::from_bytes(b"CAUREF00").is_none());
}
