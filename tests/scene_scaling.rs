//! Loading scales linearly with the file (issue 18): a scene twice as large
//! loads in about twice the time. Measured on sizes n, 2n, 4n, 8n (the best
//! of several loads each, so a busy machine's noise does not decide), for a
//! TOML scene of many materials and objects and for an OBJ of many faces
//! and MTL materials. A quadratic check (one list scan per material, the
//! old duplicate-name check) makes each doubling cost 4x and fails here.
//!
//! Its own test binary, not a module of tests/suite: it measures wall time,
//! and cargo runs test binaries one after another, so nothing else runs
//! beside it. Inside the suite, beside the reference renders, a doubling
//! measured 3.06x (2026-12-03) and the test failed for the load, not for
//! the loader. The glTF loader's test (thread CPU time) moved here from
//! tests/suite/gltf.rs for the same reason: in the suite it read 3x once.

#[allow(dead_code)]
#[path = "suite/common/gltf_builder.rs"]
mod gltf_builder;
use gltf_builder::Gltf;

use caustics::scene::gltf as loader;
use caustics::scene::{Mesh, Scene};
use glam::{Vec2, Vec3};
use serde_json::json;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const HEAD: &str = "[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n\n\
[[light]]\nkind = \"point\"\nposition = [0.0, 5.0, 0.0]\nintensity = [10.0, 10.0, 10.0]\n\n";

/// A scene of `n` materials (all three kinds) and `n / 4` boxes, each
/// naming its own material.
fn toml_scene(n: usize) -> String {
    let mut s = String::from(HEAD);
    for i in 0..n {
        match i % 3 {
            0 => writeln!(s, "[[material]]\nname = \"m{i}\"\nkind = \"diffuse\"\nalbedo = [0.5, 0.4, 0.3]"),
            1 => writeln!(s, "[[material]]\nname = \"m{i}\"\nkind = \"mirror\"\nreflectance = 0.9"),
            _ => writeln!(s, "[[material]]\nname = \"m{i}\"\nkind = \"dielectric\"\nior = 1.5\nabsorption = [0.1, 0.2, 0.3]"),
        }
        .unwrap();
    }
    for i in (0..n).step_by(4) {
        writeln!(
            s,
            "[[object]]\nname = \"box{i}\"\nshape = \"box\"\nmin = [{i}.0, 0.0, 0.0]\nmax = [{i}.5, 1.0, 1.0]\nmaterial = \"m{i}\"\ntranslate = [0.0, 1.0, 0.0]\nrotate = [0.0, 30.0, 0.0]"
        )
        .unwrap();
    }
    s
}

/// An OBJ of `n` quads over a grid of vertices, each quad with its own MTL
/// material, and that MTL; in `dir`, returns the scene loading it.
fn obj_scene(dir: &Path, n: usize) -> PathBuf {
    let (mut obj, mut mtl) = (String::from("mtllib m.mtl\n"), String::new());
    for i in 0..=n {
        writeln!(obj, "v {i} 0 0\nv {i} 1 0").unwrap();
    }
    for i in 0..n {
        let (a, b) = (2 * i + 1, 2 * i + 3);
        writeln!(obj, "usemtl m{i}\nf {a} {b} {} {}", b + 1, a + 1).unwrap();
        writeln!(mtl, "newmtl m{i}\nKd 0.5 0.5 0.5\nNi 1.0\nillum 2").unwrap();
    }
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    std::fs::write(dir.join("m.mtl"), mtl).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        format!("{HEAD}[[object]]\nshape = \"mesh\"\npath = \"m.obj\"\n"),
    )
    .unwrap();
    scene
}

/// The tests measure one at a time, their inputs built under the lock too
/// (the test harness runs them on parallel threads: one test building its
/// 32,000-material text while another timed its largest size read a
/// doubling of 3.26x in CI, the allocator and the caches shared).
static MEASURING: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Per input `i` of `inputs`, the best of `repeats` runs of `load(i)`, the
/// inputs taken in turn: a slow spell of the machine then slows one run of
/// every size, not every run of one size (the best of 5 runs of the largest
/// OBJ, taken one after another, read a doubling of 3.74x once, while
/// 2.2-2.5x is usual there).
fn best_of_each(inputs: usize, repeats: usize, mut load: impl FnMut(usize)) -> Vec<Duration> {
    let mut best = vec![Duration::MAX; inputs];
    for _ in 0..repeats {
        for (i, b) in best.iter_mut().enumerate() {
            let t = Instant::now();
            load(i);
            *b = (*b).min(t.elapsed());
        }
    }
    best
}

/// Asserts the times for sizes n, 2n, 4n, 8n grow linearly: over the
/// three doublings at most 20x (linear is 8; measured 6.6-12 on the loaded
/// 2-core machine, where the larger sizes leave the caches; the quadratic
/// name check measured 39x), and no single doubling above 3x (quadratic:
/// 4x, measured 5.5x).
fn assert_linear(what: &str, sizes: &[usize], times: &[Duration]) {
    let ms: Vec<f64> = times.iter().map(|t| t.as_secs_f64() * 1e3).collect();
    let report: Vec<String> = sizes
        .iter()
        .zip(&ms)
        .map(|(n, t)| format!("{n}: {t:.1} ms"))
        .collect();
    eprintln!("{what}: {}", report.join(", "));
    for w in ms.windows(2) {
        assert!(
            w[1] / w[0] < 3.0,
            "{what}: a doubling cost {:.2}x: {report:?}",
            w[1] / w[0]
        );
    }
    let total = ms[ms.len() - 1] / ms[0];
    assert!(
        total < 20.0,
        "{what}: 8x the size cost {total:.1}x: {report:?}"
    );
}

/// Sizes for the TOML scene and for the OBJ (whose smallest size is past
/// the sizes where everything fits the caches: 2,000 to 4,000 quads cost
/// 2.8x, every later doubling 2.1-2.4x, measured up to 64,000).
const SIZES: [usize; 4] = [4_000, 8_000, 16_000, 32_000];
const OBJ_SIZES: [usize; 4] = [4_000, 8_000, 16_000, 32_000];

#[test]
fn toml_scene_loading_is_linear() {
    let path = Path::new("scaling.toml");
    let _one_at_a_time = MEASURING.lock().unwrap_or_else(|e| e.into_inner());
    let texts: Vec<String> = SIZES.iter().map(|&n| toml_scene(n)).collect();
    let times = best_of_each(texts.len(), 3, |i| {
        let s = Scene::from_str(&texts[i], path).expect("loads");
        assert_eq!(s.materials.len(), s.objects.len() * 4);
    });
    let last = texts.last().unwrap().len() as f64 / 1e6;
    eprintln!(
        "{:.1} MB in {:.0} ms: {:.0} ms per MB",
        last,
        times.last().unwrap().as_secs_f64() * 1e3,
        times.last().unwrap().as_secs_f64() * 1e3 / last
    );
    assert_linear("TOML scene, n materials + n/4 boxes", &SIZES, &times);
}

#[test]
fn obj_with_many_materials_loads_linearly() {
    let root = std::env::temp_dir().join(format!("caustics-scaling-{}", std::process::id()));
    let _one_at_a_time = MEASURING.lock().unwrap_or_else(|e| e.into_inner());
    let scenes: Vec<PathBuf> = OBJ_SIZES
        .iter()
        .map(|&n| {
            let dir = root.join(n.to_string());
            std::fs::create_dir_all(&dir).unwrap();
            obj_scene(&dir, n)
        })
        .collect();
    // 11 rounds: with 5, a clean CI run still read one doubling at 3.01x
    // (a fast 8,000 against a slow 4,000); with 11, 2.0-2.6x over 5 runs.
    let times = best_of_each(scenes.len(), 11, |i| {
        let s = Scene::load(&scenes[i]).expect("loads");
        assert_eq!(s.materials.len(), OBJ_SIZES[i]);
    });
    let _ = std::fs::remove_dir_all(&root);
    assert_linear("OBJ of n quads and n MTL materials", &OBJ_SIZES, &times);
}

// ------------------------------------------------------------ glTF

/// A grid of `n` x `n` quads (2 n² triangles) with normals and UVs, as .glb.
fn grid_glb(dir: &Path, n: u32) -> PathBuf {
    let mut m = Mesh::default();
    let mut uv = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            m.positions.push(Vec3::new(u, (u * 7.0).sin() * 0.05, v));
            m.normals.push(Vec3::Y);
            uv.push(Vec2::new(u, v));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            m.indices.push([a, a + n + 1, a + 1]);
            m.indices.push([a + 1, a + n + 1, a + n + 2]);
        }
    }
    let mut g = Gltf::new();
    let mesh = g.mesh(&m, true, None);
    let uv_acc = g.vec2s(&uv);
    g.root["meshes"][mesh]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv_acc);
    g.root_node(json!({"mesh": mesh}));
    g.write_glb(dir, &format!("grid{n}"))
}

/// CPU time of the calling thread in seconds, from the scheduler's own
/// accounting (`/proc/thread-self/schedstat`, nanoseconds): what the load
/// costs, untouched by how many other processes share the cores.
fn thread_cpu_seconds() -> f64 {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat")
        .expect("/proc/thread-self/schedstat (Linux)");
    let ns: u64 = text.split_whitespace().next().unwrap().parse().unwrap();
    ns as f64 * 1e-9
}

/// The loader's CPU time on `path` (it runs on the calling thread).
fn load_seconds(path: &Path) -> f64 {
    let start = thread_cpu_seconds();
    let a = loader::load(path).unwrap();
    let s = thread_cpu_seconds() - start;
    assert!(!a.mesh.indices.is_empty());
    s
}

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Twice the triangles take at most about twice the time (3x allowed for
/// noise; a quadratic step would give 4x). Timed as the thread's CPU time
/// (wall clock on 2 cores shared with parallel tests and builds varied 3x
/// between runs), the two sizes in turn, median of 7 each; both are large
/// enough that the allocator serves them alike (fresh pages).
#[test]
fn loading_scales_linearly_with_the_triangle_count() {
    let _one_at_a_time = MEASURING.lock().unwrap_or_else(|e| e.into_inner());
    let dir = std::env::temp_dir().join(format!("caustics-gltf-scaling-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // 2 * 226² = 102,152 and 2 * 320² = 204,800 triangles.
    let (small, large) = (grid_glb(&dir, 226), grid_glb(&dir, 320));
    load_seconds(&small); // warm the file cache and the allocator
    load_seconds(&large);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..7 {
        a.push(load_seconds(&small));
        b.push(load_seconds(&large));
    }
    let (a, b) = (median(a), median(b));
    eprintln!(
        "load (thread CPU time): 102,152 triangles {:.1} ms, 204,800 {:.1} ms",
        a * 1e3,
        b * 1e3
    );
    assert!(b < 3.0 * a, "{b} s for twice the triangles of {a} s");
}
