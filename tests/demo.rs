//! The windowed demo end to end: the built binary runs under a private Xvfb
//! server for 30 frames while resizing its window, with the validation layer
//! on. It must exit 0 with no validation error and no leak. Without Xvfb the
//! test fails (scripts/setup.sh installs it); it never passes silently.

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const LAVAPIPE_ICD: &str = "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json";

/// A private X server, killed on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn find_in_path(name: &str) -> Option<std::path::PathBuf> {
    std::env::var_os("PATH")?
        .to_str()?
        .split(':')
        .map(|d| Path::new(d).join(name))
        .find(|p| p.is_file())
}

/// Starts Xvfb on the first display number whose socket and lock are free.
fn start_xvfb() -> Xvfb {
    let xvfb = find_in_path("Xvfb").unwrap_or_else(|| {
        panic!(
            "Xvfb is not installed: the demo test needs an X server. \
             Run scripts/setup.sh (or `apt-get install xvfb xauth`)."
        )
    });
    let first = 100 + std::process::id() % 400;
    for n in first..first + 50 {
        let socket = format!("/tmp/.X11-unix/X{n}");
        let lock = format!("/tmp/.X{n}-lock");
        if Path::new(&socket).exists() || Path::new(&lock).exists() {
            continue;
        }
        let mut child = Command::new(&xvfb)
            .args([
                &format!(":{n}"),
                "-screen",
                "0",
                "800x600x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn Xvfb");
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            if Path::new(&socket).exists() {
                return Xvfb {
                    child,
                    display: format!(":{n}"),
                };
            }
            if child.try_wait().ok().flatten().is_some() {
                break; // lost a race for this display number: try the next
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = child.kill();
        let _ = child.wait();
    }
    panic!(
        "could not start Xvfb on any display :{first}..:{}",
        first + 50
    );
}

#[test]
fn demo_resizes_and_exits_cleanly_under_validation() {
    let x = start_xvfb();
    // The demo saves its pipeline cache here, not in the user's home.
    let cache_home = std::env::temp_dir().join(format!("caustics-demo-{}", std::process::id()));
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_caustics"))
        .args([
            "demo",
            "--scene",
            concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/ball_lens.toml"),
            "--width",
            "160",
            "--height",
            "120",
            "--resize-test",
            "--validate",
            "--frames",
            "30",
            "--exit",
        ])
        .env("DISPLAY", &x.display)
        .env(
            "VK_DRIVER_FILES",
            std::env::var_os("VK_DRIVER_FILES").unwrap_or_else(|| LAVAPIPE_ICD.into()),
        )
        .env("RUST_LOG", "warn")
        .env("XDG_CACHE_HOME", &cache_home)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run caustics demo");
    // A hung demo (a deadlocked fence) fails the test instead of hanging it.
    let deadline = Instant::now() + Duration::from_secs(300);
    while child.try_wait().expect("wait").is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("caustics demo did not exit within 300 s");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let out = child.wait_with_output().expect("demo output");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let report = format!(
        "exit {:?} after {:.1} s\n--- stdout\n{stdout}\n--- stderr\n{stderr}",
        out.status.code(),
        start.elapsed().as_secs_f64()
    );
    assert!(out.status.success(), "demo failed: {report}");
    for bad in ["Validation Error", "VUID-", "leak", "panicked"] {
        assert!(
            !stderr.to_lowercase().contains(&bad.to_lowercase()),
            "stderr mentions {bad:?}: {report}"
        );
    }
    assert!(
        stdout.contains("presented 30 frames"),
        "the demo did not present 30 frames: {report}"
    );
    let swapchains = stdout.matches("swapchain: ").count();
    assert!(
        swapchains >= 3,
        "--resize-test should recreate the swapchain at least twice: {report}"
    );
    // Per-pass timings use the same scope names as `caustics render`.
    assert!(stdout.contains("tonemap"), "no per-pass timings: {report}");
    // The pipeline cache was saved for the next start (at least its
    // 32-byte header: lavapipe's cache holds no pipelines).
    let cache = cache_home.join("caustics/pipelines.bin");
    let saved = std::fs::metadata(&cache).map(|m| m.len()).unwrap_or(0);
    assert!(
        saved >= 32,
        "no pipeline cache at {}: {report}",
        cache.display()
    );
    let _ = std::fs::remove_dir_all(&cache_home);
    eprintln!("{report}");
}
