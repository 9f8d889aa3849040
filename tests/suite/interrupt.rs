//! Killed while writing (issue 18): `render`, `compare` and `bench --json` interrupted
//! by SIGTERM or SIGINT at any moment leave either the complete output (the
//! signal came after it was written) or nothing at the output names, and
//! never a temporary; `reference` interrupted finishes the pass in flight
//! and writes a complete pair with its photon count.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStderr, Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

const LAVAPIPE_ICD: &str = "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json";

fn caustics() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_caustics"));
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        c.env("VK_DRIVER_FILES", LAVAPIPE_ICD);
    }
    c.stdout(Stdio::piped()).stderr(Stdio::piped());
    c
}

fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::SeqCst);
    let dir = std::env::temp_dir().join(format!(
        "caustics-interrupt-{}-{name}-{n}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Sends SIG`name` to `child` (which may have exited on its own just before).
fn signal(child: &Child, name: &str) {
    Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .stderr(Stdio::null())
        .status()
        .expect("run kill");
}

/// The names in `dir` (empty when it does not exist), sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// Waits until a file whose name contains `needle` appears in `dir`.
fn wait_for_file(dir: &Path, needle: &str, child: &mut Child) -> bool {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(120) {
        if names(dir).iter().any(|n| n.contains(needle)) {
            return true;
        }
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    false
}

/// Spawns `caustics ARGS` with a 2 s pause after each temporary it writes
/// (the test hook) and returns once the first temporary is in `out`.
fn spawn_until_writing<S: AsRef<std::ffi::OsStr>>(
    args: impl IntoIterator<Item = S>,
    out: &Path,
) -> Child {
    let mut child = caustics()
        .args(args)
        .env("CAUSTICS_TEST_WRITE_PAUSE_MS", "2000")
        .spawn()
        .expect("spawn");
    assert!(
        wait_for_file(out, ".partial", &mut child),
        "no temporary seen"
    );
    child
}

/// Either the complete pair (exit 0) or nothing at all (exit 128 + signal,
/// one line of error), and no temporary either way.
fn assert_all_or_nothing(out: &Path, child: Child, signal_number: i32, wanted: &[&str]) {
    let o = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&o.stderr);
    let files = names(out);
    match o.status.code() {
        Some(0) => assert_eq!(files, wanted, "{stderr}"),
        Some(c) => {
            assert_eq!(c, 128 + signal_number, "{stderr}");
            assert!(files.is_empty(), "left behind: {files:?}; {stderr}");
            assert!(stderr.contains("error: interrupted by"), "{stderr}");
            assert!(!stderr.contains("panicked"), "{stderr}");
        }
        // Before the handler was installed (the first milliseconds), the
        // default action ends the process: nothing was written yet.
        None => assert!(files.is_empty(), "left behind: {files:?}; {stderr}"),
    }
}

/// A cheap pseudo-random sequence (no dependency): the moments to signal.
fn moments(n: usize, max: Duration) -> Vec<Duration> {
    let mut x = (std::process::id() as u64) ^ 0x9e37_79b9_7f4a_7c15;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            max.mul_f64((x % 10_000) as f64 / 10_000.0)
        })
        .collect()
}

fn render_args(out: &Path) -> Vec<String> {
    [
        "render",
        "--scene",
        concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/ball_lens.toml"),
        "--technique",
        "direct",
        "--width",
        "32",
        "--height",
        "32",
        "--out",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([out.join("x.png").to_string_lossy().into_owned()])
    .collect()
}

/// SIGTERM just after the first image's temporary is written (the write
/// paused there by the test hook): nothing at either output name, no
/// temporary.
#[test]
fn render_killed_while_writing_leaves_nothing() {
    for (sig, number) in [("TERM", 15), ("INT", 2)] {
        let out = temp_dir("writing").join("out");
        let child = spawn_until_writing(render_args(&out), &out);
        signal(&child, sig);
        let o = child.wait_with_output().expect("wait");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(128 + number), "{stderr}");
        assert_eq!(names(&out), Vec::<String>::new(), "{stderr}");
        assert_eq!(
            stderr.lines().last(),
            Some(format!("error: interrupted by SIG{sig}; no output written").as_str()),
            "{stderr}"
        );
    }
}

/// SIGTERM at random moments of whole runs (loading, device, frames,
/// writing): all or nothing, never a temporary.
#[test]
fn render_killed_at_random_moments_is_all_or_nothing() {
    // One run measured, then signals spread over its length (and past it,
    // so that some runs finish).
    let out = temp_dir("timing").join("out");
    let start = Instant::now();
    let o = caustics().args(render_args(&out)).output().expect("run");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let length = start.elapsed();
    for (i, at) in moments(6, length.mul_f64(1.2)).into_iter().enumerate() {
        let out = temp_dir(&format!("random{i}")).join("out");
        let child = caustics()
            .args(render_args(&out))
            .env("CAUSTICS_TEST_WRITE_PAUSE_MS", "100")
            .spawn()
            .expect("spawn");
        std::thread::sleep(at);
        signal(&child, "TERM");
        assert_all_or_nothing(&out, child, 15, &["x.exr", "x.png"]);
    }
}

/// `compare` writes each file to its temporary as soon as it is made
/// (`output::Batch`); SIGTERM after the first of them leaves no file and no
/// temporary in its folder.
#[test]
fn compare_killed_while_writing_leaves_nothing() {
    let out = temp_dir("compare").join("out");
    let child = spawn_until_writing(
        [
            "compare",
            "--scene",
            concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/ball_lens.toml"),
            "--techniques",
            "direct",
            "--width",
            "16",
            "--height",
            "16",
            "--photons",
            "262144",
            "--frames",
            "1",
            "--no-cache",
            "--out",
            out.to_str().unwrap(),
        ],
        &out,
    );
    signal(&child, "TERM");
    // It pauses 2 s after each of its dozens of files: the signal lands.
    assert_all_or_nothing(&out, child, 15, &[]);
}

/// `bench --json` interrupted while the JSON is written leaves no JSON and
/// no temporary.
#[test]
fn bench_json_killed_while_writing_leaves_nothing() {
    let out = temp_dir("bench").join("out");
    let json = out.join("b.json");
    let child = spawn_until_writing(
        [
            "bench",
            "--technique",
            "direct",
            "--width",
            "16",
            "--height",
            "16",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--json",
            json.to_str().unwrap(),
        ],
        &out,
    );
    signal(&child, "TERM");
    assert_all_or_nothing(&out, child, 15, &["b.json"]);
}

/// Reads `child`'s stderr until a line `is_it` accepts (failing if it ends
/// first): the reader, for the rest, and what was read.
fn stderr_until(
    child: &mut Child,
    is_it: impl Fn(&str) -> bool,
) -> (BufReader<ChildStderr>, String) {
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    loop {
        let mut line = String::new();
        assert!(
            stderr.read_line(&mut line).unwrap() > 0,
            "ended first: {seen}"
        );
        seen.push_str(&line);
        if is_it(&line) {
            return (stderr, seen);
        }
    }
}

/// Issue 31: `bench` interrupted while it times frames reports the frames
/// it timed, on stdout and in its JSON marked partial (it threw every
/// result away before).
#[test]
fn bench_interrupted_reports_what_it_timed() {
    let out = temp_dir("bench-partial").join("out");
    let json = out.join("b.json");
    let asked = 10_000_000;
    let mut child = caustics()
        .args([
            "bench",
            "--technique",
            "direct",
            "--width",
            "8",
            "--height",
            "8",
        ])
        .args(["--frames", &asked.to_string(), "--json"])
        .arg(&json)
        .spawn()
        .expect("spawn");
    let (mut stderr, seen) = stderr_until(&mut child, |line| line.starts_with("timing "));
    std::thread::sleep(Duration::from_millis(500));
    signal(&child, "TERM");
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    let o = child.wait_with_output().expect("wait");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{seen}{rest}\n{stdout}");
    assert!(stdout.contains("partial"), "{stdout}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).expect("the JSON")).unwrap();
    assert_eq!(report["partial"], serde_json::Value::Bool(true), "{report}");
    let frames = report["frames"].as_u64().expect("frames");
    assert!(frames > 0 && frames < asked, "{frames}");
}

/// The progressive reference interrupted after its first pass finishes
/// that pass and writes the complete pair, saying how many photons it holds.
#[test]
fn reference_interrupted_writes_what_it_has() {
    let out = temp_dir("reference").join("out");
    let mut child = caustics()
        .args([
            "reference",
            "--width",
            "16",
            "--height",
            "16",
            "--photons",
            "100000000000",
            "--out",
        ])
        .arg(out.join("r.exr"))
        .spawn()
        .expect("spawn");
    // Each pass prints a progress line when stderr is not a terminal.
    let (mut stderr, seen) = stderr_until(&mut child, |line| line.contains("photons, pass"));
    signal(&child, "INT");
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    let o = child.wait_with_output().expect("wait");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{seen}{rest}\n{stdout}");
    assert_eq!(names(&out), vec!["r.exr", "r.png"], "{seen}{rest}");
    let photons: u64 = stdout
        .split("interrupted: writing the ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no photon count in: {stdout}"));
    // Whole passes of 262,144 photons, far fewer than asked.
    assert!(photons > 0 && photons % 262_144 == 0, "{photons}");
    assert!(
        stdout.contains(&format!("traced {photons} photons")),
        "{stdout}"
    );
    let (w, h, rgba) = caustics::output::read_exr(&out.join("r.exr")).expect("complete EXR");
    assert_eq!((w, h), (16, 16));
    assert!(rgba.iter().all(|v| v.is_finite()) && rgba.iter().any(|&v| v > 0.0));
}
