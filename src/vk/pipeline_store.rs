//! Pipeline reuse across rebuilds, and the driver's pipeline cache.
//!
//! A rebuild (a parameter that sizes resources, a new scene, a resize)
//! creates a new technique whose pipelines are mostly those of the old one.
//! Creating a pipeline compiles its shaders (50-200 ms each on lavapipe,
//! whose `VkPipelineCache` stays empty), so the store hands out the pipeline
//! already built for the same key instead: techniques call
//! `ComputePipeline::new`/`GraphicsPipeline::new` as before and get a shared
//! pipeline when nothing that reaches the driver changed.
//!
//! The key is everything `vkCreate*Pipelines` reads: each stage's shader (its
//! path under glsl/, which names one SPIR-V blob embedded at build time; the
//! entry point is always `main`), the specialisation constants, the pipeline layout's
//! description (each set's bindings, the push-constant size) and, for
//! graphics, the fixed-function state and attachment formats. The layout is
//! keyed by description, not by `VkDescriptorSetLayout` handle: a rebuilt
//! technique makes new set layouts with the same bindings, and sets allocated
//! from an identically defined layout are compatible with the pipeline's
//! (Vulkan spec, "Pipeline Layout Compatibility").
//!
//! Lifetime: the store holds weak references, so a pipeline lives while a
//! technique uses it, plus strong references to the last `KEPT` pipelines
//! handed out, so a rebuild that drops the old technique before making the
//! new one (a resize) still finds them. What the store keeps holds the
//! device (`ash::Device`), not the `Context`, so it makes no cycle; the
//! context empties the store before it destroys the device.
//!
//! On real GPUs the driver's `VkPipelineCache` also skips compilation for
//! pipelines the store no longer holds; the demo saves it to disk and loads
//! it at start (`load`, `save`), after checking its header against this
//! device.

use super::VkResult;
use ash::vk;
use std::collections::{HashMap, VecDeque};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, Weak};

/// How many recently handed-out pipelines the store keeps alive with no
/// technique holding them: more than any technique has (about ten), so one
/// drop-then-rebuild finds all of its pipelines.
const KEPT: usize = 64;

/// Specialisation constants of a pipeline: 32-bit values by `constant_id`
/// (GLSL `layout(constant_id = N) const uint/int/float/bool`; a bool is a
/// 32-bit `VkBool32`). Sorted by id so equal sets compare equal.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct Specialization {
    entries: Vec<(u32, [u8; 4])>,
}

impl Specialization {
    pub fn new() -> Self {
        Self::default()
    }

    fn with(mut self, id: u32, bytes: [u8; 4]) -> Self {
        match self.entries.binary_search_by_key(&id, |e| e.0) {
            Ok(i) => self.entries[i].1 = bytes,
            Err(i) => self.entries.insert(i, (id, bytes)),
        }
        self
    }

    pub fn u32(self, id: u32, value: u32) -> Self {
        self.with(id, value.to_ne_bytes())
    }

    pub fn i32(self, id: u32, value: i32) -> Self {
        self.with(id, value.to_ne_bytes())
    }

    pub fn f32(self, id: u32, value: f32) -> Self {
        self.with(id, value.to_ne_bytes())
    }

    pub fn bool(self, id: u32, value: bool) -> Self {
        self.u32(id, value as u32)
    }

    /// The map entries and data `VkSpecializationInfo` points at.
    pub(super) fn raw(&self) -> (Vec<vk::SpecializationMapEntry>, Vec<u8>) {
        let entries = self
            .entries
            .iter()
            .enumerate()
            .map(|(i, &(id, _))| vk::SpecializationMapEntry {
                constant_id: id,
                offset: 4 * i as u32,
                size: 4,
            })
            .collect();
        let data = self.entries.iter().flat_map(|e| e.1).collect();
        (entries, data)
    }
}

/// What a pipeline is created from (see the module comment). Built by
/// `pipeline.rs` from the same arguments it passes to the driver. The entry
/// point is `main` for every shader, so it is not part of the key.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) struct PipelineKey {
    pub stages: Stages,
    pub specialization: Specialization,
    /// Each set's (binding, descriptor type) list, in set order.
    pub sets: Vec<Vec<(u32, vk::DescriptorType)>>,
    pub push_size: u32,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) enum Stages {
    /// The compute shader's path under glsl/.
    Compute(String),
    /// The whole description: shader paths, fixed-function state,
    /// attachment formats.
    Graphics(GraphicsPipelineDesc<'static>),
}

/// A pipeline and its layout, shared by every technique that asked for the
/// same key; destroyed when the last holder lets go.
pub(super) struct SharedPipeline {
    device: ash::Device,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
}

impl Drop for SharedPipeline {
    fn drop(&mut self) {
        // Whoever holds this also holds the context (the pipeline wrappers)
        // or is the store, which the context empties before it destroys the
        // device: the device is alive here.
        unsafe {
            self.device.destroy_pipeline(self.raw, None);
            self.device.destroy_pipeline_layout(self.layout, None);
        }
    }
}

#[derive(Default)]
struct Entries {
    live: HashMap<PipelineKey, Weak<SharedPipeline>>,
    kept: VecDeque<Arc<SharedPipeline>>,
}

/// Counts since the context was made, for tests and measurements.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PipelineCounts {
    /// Pipelines the driver was asked to create.
    pub created: u64,
    /// Requests answered with a pipeline the store already held.
    pub reused: u64,
}

/// The outcome of `PipelineStore::load`.
#[derive(Debug, PartialEq, Eq)]
pub enum CacheLoad {
    /// The file's pipelines were merged into the cache (its size in bytes).
    Loaded(usize),
    /// No file there (the first run).
    Missing,
    /// The file was unreadable, corrupt, or made by another device or
    /// driver; it was ignored (and a warning logged) with the reason.
    Ignored(String),
}

/// The header every `VkPipelineCache` blob starts with
/// (`VkPipelineCacheHeaderVersionOne`, least significant byte first).
const HEADER_SIZE: usize = 32;

pub struct PipelineStore {
    device: ash::Device,
    cache: vk::PipelineCache,
    vendor_id: u32,
    device_id: u32,
    uuid: [u8; vk::UUID_SIZE],
    entries: Mutex<Entries>,
    created: AtomicU64,
    reused: AtomicU64,
    reuse: AtomicBool,
    use_cache: AtomicBool,
}

impl PipelineStore {
    /// A store for `device`; its driver cache starts empty (a failure to
    /// make one only costs speed: it is logged and pipelines go uncached).
    pub(super) fn new(device: &ash::Device, props: &vk::PhysicalDeviceProperties) -> Self {
        let cache = match unsafe {
            device.create_pipeline_cache(&vk::PipelineCacheCreateInfo::default(), None)
        } {
            Ok(c) => c,
            Err(e) => {
                log::warn!("no pipeline cache ({e}): pipelines are compiled every time");
                vk::PipelineCache::null()
            }
        };
        Self {
            device: device.clone(),
            cache,
            vendor_id: props.vendor_id,
            device_id: props.device_id,
            uuid: props.pipeline_cache_uuid,
            entries: Mutex::new(Entries::default()),
            created: AtomicU64::new(0),
            reused: AtomicU64::new(0),
            reuse: AtomicBool::new(true),
            use_cache: AtomicBool::new(true),
        }
    }

    pub fn counts(&self) -> PipelineCounts {
        PipelineCounts {
            created: self.created.load(Ordering::SeqCst),
            reused: self.reused.load(Ordering::SeqCst),
        }
    }

    /// Turns reuse off (every request creates a pipeline) or on: for
    /// measuring what reuse saves. Off also lets go of the kept pipelines.
    pub fn set_reuse(&self, on: bool) {
        self.reuse.store(on, Ordering::SeqCst);
        if !on {
            self.lock().kept.clear();
        }
    }

    /// Creates pipelines with or without the driver's `VkPipelineCache`: for
    /// measuring what the cache saves.
    pub fn set_driver_cache(&self, on: bool) {
        self.use_cache.store(on, Ordering::SeqCst);
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Entries> {
        self.entries
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The pipeline for `key`: the one the store holds, else a new one from
    /// `create(cache)`, which returns the pipeline and its layout.
    pub(super) fn get_or_create(
        &self,
        key: PipelineKey,
        create: impl FnOnce(vk::PipelineCache) -> VkResult<(vk::Pipeline, vk::PipelineLayout)>,
    ) -> VkResult<Arc<SharedPipeline>> {
        let reuse = self.reuse.load(Ordering::SeqCst);
        let mut entries = self.lock();
        if reuse {
            if let Some(shared) = entries.live.get(&key).and_then(Weak::upgrade) {
                self.reused.fetch_add(1, Ordering::SeqCst);
                keep(&mut entries.kept, &shared);
                return Ok(shared);
            }
        }
        let cache = if self.use_cache.load(Ordering::SeqCst) {
            self.cache
        } else {
            vk::PipelineCache::null()
        };
        let (raw, layout) = create(cache)?;
        self.created.fetch_add(1, Ordering::SeqCst);
        let shared = Arc::new(SharedPipeline {
            device: self.device.clone(),
            raw,
            layout,
        });
        if reuse {
            // Forget pipelines nobody holds any more, so the map stays as
            // small as what is alive.
            entries.live.retain(|_, w| w.strong_count() > 0);
            entries.live.insert(key, Arc::downgrade(&shared));
            keep(&mut entries.kept, &shared);
        }
        Ok(shared)
    }

    /// Merges the pipeline-cache file at `path` (made by `save`) into the
    /// cache. A missing file is the first run; a file whose header does not
    /// match this device and driver, or that the driver refuses, is ignored
    /// with a warning: a stale cache must never stop the program.
    pub fn load(&self, path: &Path) -> CacheLoad {
        let data = match std::fs::read(path) {
            Ok(d) => d,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return CacheLoad::Missing,
            Err(e) => return self.ignore(path, format!("cannot read it: {e}")),
        };
        if let Err(why) = self.check_header(&data) {
            return self.ignore(path, why);
        }
        if self.cache == vk::PipelineCache::null() {
            return self.ignore(path, "this device has no pipeline cache".into());
        }
        let info = vk::PipelineCacheCreateInfo::default().initial_data(&data);
        let loaded = match unsafe { self.device.create_pipeline_cache(&info, None) } {
            Ok(c) => c,
            Err(e) => return self.ignore(path, format!("the driver refused it ({e})")),
        };
        let merged = unsafe { self.device.merge_pipeline_caches(self.cache, &[loaded]) };
        unsafe { self.device.destroy_pipeline_cache(loaded, None) };
        match merged {
            Ok(()) => CacheLoad::Loaded(data.len()),
            Err(e) => self.ignore(path, format!("the driver could not merge it ({e})")),
        }
    }

    fn ignore(&self, path: &Path, why: String) -> CacheLoad {
        log::warn!("ignoring the pipeline cache {}: {why}", path.display());
        CacheLoad::Ignored(why)
    }

    /// Checks `VkPipelineCacheHeaderVersionOne` against this device: the
    /// driver would reject a foreign blob too, but not every driver checks
    /// carefully, and a clear reason in the log helps.
    fn check_header(&self, data: &[u8]) -> Result<(), String> {
        if data.len() < HEADER_SIZE {
            return Err(format!(
                "{} bytes, shorter than the {HEADER_SIZE}-byte header",
                data.len()
            ));
        }
        let word = |i: usize| u32::from_le_bytes([data[i], data[i + 1], data[i + 2], data[i + 3]]);
        let (size, version) = (word(0), word(4));
        if (size as usize) < HEADER_SIZE || size as usize > data.len() {
            return Err(format!("header size {size} is not valid"));
        }
        if version != vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32 {
            return Err(format!("header version {version} is not 1"));
        }
        let (vendor, device) = (word(8), word(12));
        if vendor != self.vendor_id || device != self.device_id {
            return Err(format!(
                "made for vendor {vendor:#x} device {device:#x}, this is vendor {:#x} device {:#x}",
                self.vendor_id, self.device_id
            ));
        }
        if data[16..32] != self.uuid {
            return Err("made by another driver version (pipeline cache UUID differs)".into());
        }
        Ok(())
    }

    /// Writes the cache to `path` (creating its folder), through a
    /// temporary file renamed into place so a crash never leaves half a
    /// file. Returns the bytes written.
    pub fn save(&self, path: &Path) -> std::io::Result<usize> {
        if self.cache == vk::PipelineCache::null() {
            return Ok(0);
        }
        let data = unsafe { self.device.get_pipeline_cache_data(self.cache) }
            .map_err(|e| std::io::Error::other(format!("vkGetPipelineCacheData: {e}")))?;
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, &data)?;
        std::fs::rename(&tmp, path)?;
        Ok(data.len())
    }

    /// Lets go of the kept pipelines and destroys the cache: called by the
    /// context, with the device idle, before it destroys the device.
    pub(super) fn destroy(&mut self) {
        let entries = self.entries.get_mut().unwrap_or_else(|p| p.into_inner());
        entries.kept.clear();
        entries.live.clear();
        if self.cache != vk::PipelineCache::null() {
            unsafe { self.device.destroy_pipeline_cache(self.cache, None) };
            self.cache = vk::PipelineCache::null();
        }
    }
}

/// Keeps `shared` among the most recently handed out, dropping the oldest
/// beyond `KEPT`.
fn keep(kept: &mut VecDeque<Arc<SharedPipeline>>, shared: &Arc<SharedPipeline>) {
    kept.retain(|k| !Arc::ptr_eq(k, shared));
    kept.push_back(shared.clone());
    if kept.len() > KEPT {
        kept.pop_front();
    }
}

/// How a graphics pipeline is built. Geometry comes from storage buffers
/// (vertex pulling), so there is no vertex input state.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct GraphicsPipelineDesc<'a> {
    pub vertex: &'a str,
    pub geometry: Option<&'a str>,
    pub fragment: &'a str,
    pub color_formats: Vec<vk::Format>,
    pub depth_format: Option<vk::Format>,
    pub depth_test: bool,
    pub depth_write: bool,
    /// Additive blending (one + one) on every colour attachment.
    pub additive: bool,
    /// With `additive`: the alpha channel keeps the minimum of what is
    /// written instead of the sum (a nearest depth beside summed colour).
    pub alpha_min: bool,
    pub cull: vk::CullModeFlags,
    pub topology: vk::PrimitiveTopology,
    pub push_size: u32,
    /// Specialisation constants, the same for every stage.
    pub specialization: Specialization,
}

impl<'a> GraphicsPipelineDesc<'a> {
    pub fn new(vertex: &'a str, fragment: &'a str) -> Self {
        Self {
            vertex,
            geometry: None,
            fragment,
            color_formats: Vec::new(),
            depth_format: None,
            depth_test: false,
            depth_write: false,
            additive: false,
            alpha_min: false,
            cull: vk::CullModeFlags::NONE,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            push_size: 0,
            specialization: Specialization::new(),
        }
    }
}
