//! The JSON both `caustics compare` (report.json) and `caustics bench
//! --json` write, documented field by field in docs/REPORTS.md, and the
//! Markdown view of a comparison (report.md).

use super::metrics::Metrics;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Bumped when a field changes meaning or goes away.
pub const SCHEMA: &str = "caustics-report/1";

/// Where and how it ran: the first fields of every report.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunInfo {
    pub schema: String,
    pub device: String,
    pub driver: String,
    /// How frames were timed (`vk::TimingSource::describe`).
    pub timing_source: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// Animation time of the frame, seconds.
    pub time: f32,
}

/// One pass over the timed frames.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PassStats {
    pub name: String,
    /// Median over frames.
    pub ms: f64,
    pub min_ms: f64,
}

/// A technique's frame cost.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Timing {
    /// Frames timed (after the warm-up).
    pub frames: u32,
    /// Host wall clock over the timed frames / frames.
    pub frame_ms: f64,
    pub passes_ms: Vec<PassStats>,
}

/// The ground truth a comparison used.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceInfo {
    /// "traced", "cache" or "file".
    pub source: String,
    /// The EXR given with `--reference`, or the cache folder.
    pub path: Option<String>,
    pub photons: u64,
    pub passes: u64,
    pub trace_seconds: f64,
    pub diffuse_bounces: u32,
    /// The reference's own noise: its first half-run against its second
    /// (equal photon counts), full frame. A technique whose FLIP is below
    /// this FLIP is indistinguishable from the reference at this budget.
    pub noise: Option<Metrics>,
}

/// One component of a technique against the reference's same component.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ComponentResult {
    pub component: String,
    pub metrics: Metrics,
}

/// One technique in a comparison.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TechniqueResult {
    pub technique: String,
    pub params: BTreeMap<String, f32>,
    pub timing: Timing,
    /// The full frame against the reference's full frame.
    pub full: Metrics,
    /// With components not applicable: the frame less the technique's own
    /// images of them, against the reference's frame less its images of
    /// them (what the technique claims to render against the matching
    /// components). None where every component is scored.
    #[serde(default)]
    pub modelled: Option<Metrics>,
    /// Each component the technique renders against the reference's
    /// matching path-type component (none with a `--reference` file).
    pub components: Vec<ComponentResult>,
    /// Components not scored: those the scene has more of than the
    /// technique models (`TechniqueInfo::not_modelled`; their images are
    /// written), and those of the reference's that hold light and the
    /// technique does not render at all.
    #[serde(default)]
    pub not_applicable: Vec<NotApplicable>,
}

/// A component left unscored, and why (e.g. `pinhole`'s surface caustics
/// on a scene with glass: it renders reflection caustics only).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct NotApplicable {
    pub component: String,
    pub reason: String,
}

/// A technique left out, and why (e.g. `water_photons` without water).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Skipped {
    pub technique: String,
    pub reason: String,
}

/// report.json of `caustics compare`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CompareReport {
    #[serde(flatten)]
    pub run: RunInfo,
    pub exposure: f32,
    pub reference: ReferenceInfo,
    pub techniques: Vec<TechniqueResult>,
    pub skipped: Vec<Skipped>,
}

/// A relative energy as a signed percentage ("undefined" for None).
pub fn signed_percent(x: Option<f64>) -> String {
    x.map_or("undefined".into(), |x| format!("{:+.2}%", 100.0 * x))
}

impl CompareReport {
    /// report.md: the run, the reference and its noise, one table row per
    /// technique and component, and the per-pass split.
    pub fn markdown(&self) -> String {
        let r = &self.run;
        let mut md = format!(
            "# caustics compare: {}\n\n{}x{} at t = {} s on {} ({}), frames timed by {}.\n\n",
            r.scene, r.width, r.height, r.time, r.device, r.driver, r.timing_source
        );
        let re = &self.reference;
        md += &format!(
            "Reference: {} ({} photons in {} passes, {:.1} s, {} diffuse bounces){}.\n",
            re.source,
            re.photons,
            re.passes,
            re.trace_seconds,
            re.diffuse_bounces,
            re.path
                .as_ref()
                .map(|p| format!(", {p}"))
                .unwrap_or_default()
        );
        match &re.noise {
            Some(n) => {
                md += &format!(
                    "Its own noise (one half-run against the other): FLIP {:.4}, energy {}. A FLIP below it reads as indistinguishable from the reference.\n\n",
                    n.flip,
                    signed_percent(n.energy)
                )
            }
            None => md += "Its own noise is unknown (a reference file).\n\n",
        }
        md += "FLIP is LDR-FLIP after the display transform at the scene's exposure; energy is (technique − reference) / reference over the image.\n\n";
        md += "| technique | component | FLIP | energy | RMSE | frame ms |\n";
        md += "| --- | --- | --- | --- | --- | --- |\n";
        for t in &self.techniques {
            let row = |c: &str, m: &Metrics| {
                format!(
                    "| {} | {c} | {:.4} | {} | {:.4e} | {:.2} |\n",
                    t.technique,
                    m.flip,
                    signed_percent(m.energy),
                    m.rmse,
                    t.timing.frame_ms
                )
            };
            md += &row("full frame", &t.full);
            if let Some(m) = &t.modelled {
                md += &row("modelled components", m);
            }
            for c in &t.components {
                md += &row(&c.component, &c.metrics);
            }
            for n in &t.not_applicable {
                md += &format!(
                    "| {} | {} | not applicable: {} | | | |\n",
                    t.technique, n.component, n.reason
                );
            }
        }
        for s in &self.skipped {
            md += &format!("| {} | skipped: {} | | | | |\n", s.technique, s.reason);
        }
        md += "\n## Per pass (median ms over the timed frames)\n\n";
        for t in &self.techniques {
            let passes: Vec<String> = t
                .timing
                .passes_ms
                .iter()
                .map(|p| format!("{} {:.3}", p.name, p.ms))
                .collect();
            md += &format!("- **{}**: {}\n", t.technique, passes.join(", "));
        }
        md
    }
}

/// `caustics bench --json`: the run, the technique's timing (the fields of
/// [`Timing`] at the top level) and what only a benchmark measures.
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    #[serde(flatten)]
    pub run: RunInfo,
    pub technique: String,
    pub params: BTreeMap<String, f32>,
    pub warmup: u32,
    pub frames_in_flight: usize,
    #[serde(flatten)]
    pub timing: Timing,
    /// Median over frames of submission to fence (includes queueing with
    /// more than one frame in flight).
    pub submit_to_done_ms: f64,
    /// Host time blocked on fences, per frame.
    pub host_wait_ms: f64,
    /// Host time inside vkQueueSubmit2, per frame.
    pub host_submit_ms: f64,
    pub geometry: crate::frame::GeometryStats,
    /// The technique's named counts of its last frame (`Technique::counters`).
    pub counters: BTreeMap<String, u64>,
    /// Memory sampled over the timed frames (`bench --memory-samples`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub memory: Vec<MemorySample>,
    /// A SIGINT or SIGTERM stopped the timed frames early: `frames` is how
    /// many were timed, fewer than asked.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub partial: bool,
}

/// Host and device memory after `frame` timed frames completed (none in
/// flight).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct MemorySample {
    pub frame: u32,
    /// The process's resident set (VmRSS), bytes, after the malloc heap's
    /// free pages were returned (`trim_host_heap`; glibc only): memory in
    /// use, which a leak makes grow.
    pub host_rss: u64,
    /// VmRSS just before that trim: with the pages the allocator keeps.
    pub host_rss_untrimmed: u64,
    /// Whether the trim ran (false where the C library is not glibc:
    /// `host_rss` then equals `host_rss_untrimmed`, allocator cache and all).
    pub host_heap_trimmed: bool,
    /// gpu-allocator's live allocations: bytes, count, and the bytes of
    /// its memory blocks.
    pub device_allocated: u64,
    pub device_allocations: usize,
    pub device_capacity: u64,
    /// Host memory the renderer owns (`vk/host_memory.rs`), counted where it
    /// is allocated, which the RSS mixes with the driver's own caches: live
    /// bytes and allocations made through its Vulkan allocation callbacks
    /// (the instance, the device, their objects and command buffers)...
    pub vulkan_host: u64,
    pub vulkan_host_allocations: u64,
    /// ...and the Rust heap in use (the `caustics` binary counts it).
    pub rust_heap: Option<u64>,
    pub rust_heap_allocations: Option<u64>,
}

/// Each pass's times over `frames`, in the order of the first frame (a
/// repeated pass name collects all its occurrences).
pub fn per_pass(frames: &[crate::vk::FrameTiming]) -> Vec<(String, Vec<f64>)> {
    let mut by_name: Vec<(String, Vec<f64>)> = Vec::new();
    for f in frames {
        for (i, p) in f.passes.iter().enumerate() {
            match by_name.iter_mut().find(|(n, _)| *n == p.name) {
                Some((_, v)) if v.len() < frames.len() * (i + 1) => v.push(p.ms),
                Some(_) => {}
                None => by_name.push((p.name.clone(), vec![p.ms])),
            }
        }
    }
    by_name
}

/// Appends `more` (a [`per_pass`] of later frames) to `all`, pass by pass:
/// long runs keep their timings as numbers, not as frames.
pub fn extend_per_pass(all: &mut Vec<(String, Vec<f64>)>, more: Vec<(String, Vec<f64>)>) {
    for (name, ms) in more {
        match all.iter_mut().find(|(n, _)| *n == name) {
            Some((_, v)) => v.extend(ms),
            None => all.push((name, ms)),
        }
    }
}

/// Each pass's median and minimum over `frames` ([`per_pass`]).
pub fn pass_stats(frames: &[crate::vk::FrameTiming]) -> Vec<PassStats> {
    stats_per_pass(per_pass(frames))
}

/// Each pass's median and minimum of its times.
pub fn stats_per_pass(by_name: Vec<(String, Vec<f64>)>) -> Vec<PassStats> {
    by_name
        .into_iter()
        .map(|(name, ms)| PassStats {
            name,
            ms: median(&ms),
            min_ms: ms.iter().copied().fold(f64::INFINITY, f64::min),
        })
        .collect()
}

/// The median of `values` (0 for none).
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}
