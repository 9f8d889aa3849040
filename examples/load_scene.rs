//! Times `Scene::load` on scene files (issue 18: load time per MB and for a
//! large OBJ): per file its size (the scene file plus the OBJ/MTL files it
//! names), the best of `--repeat` loads, the time per MB and the triangle
//! and material counts. `scripts/bench.sh loading` generates the inputs.
//!
//! ```sh
//! cargo run --release --example load_scene -- [--repeat 3] SCENE...
//! ```

use caustics::scene::Scene;
use std::path::Path;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut repeat = 3;
    if let Some(i) = args.iter().position(|a| a == "--repeat") {
        repeat = args
            .get(i + 1)
            .and_then(|r| r.parse().ok())
            .ok_or_else(|| anyhow::anyhow!("--repeat needs a count"))?;
        args.drain(i..i + 2);
    }
    for path in args.iter().map(Path::new) {
        let mut best = f64::INFINITY;
        let mut scene = None;
        for _ in 0..repeat.max(1) {
            let start = Instant::now();
            let s = Scene::load(path)?;
            best = best.min(start.elapsed().as_secs_f64());
            scene = Some(s);
        }
        let scene = scene.expect("loaded at least once");
        let bytes = input_bytes(path)?;
        let mb = bytes as f64 / 1e6;
        println!(
            "{}: {mb:.1} MB, {} triangles, {} materials: {:.0} ms (best of {repeat}), {:.0} ms per MB",
            path.display(),
            scene.triangle_count(),
            scene.materials.len(),
            best * 1e3,
            best * 1e3 / mb
        );
    }
    Ok(())
}

/// The scene file's size plus that of every file beside it (the OBJ, MTL
/// and other inputs the generated scenes keep in their own folder).
fn input_bytes(path: &Path) -> anyhow::Result<u64> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    let mut total = std::fs::metadata(path)?.len();
    if let Some(dir) = dir {
        for e in std::fs::read_dir(dir)? {
            let e = e?;
            if e.path() != path && e.file_type()?.is_file() {
                total += e.metadata()?.len();
            }
        }
    }
    Ok(total)
}
