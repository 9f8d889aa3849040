//! Command-line errors (issue 18): every refusal is one line on stderr
//! naming the argument or scene field, exit code 1, no device line before
//! it and nothing created at `--out`; clap's own parse errors included.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const LAVAPIPE_ICD: &str = "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json";

fn run(args: &[&str], env: &[(&str, Option<&str>)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_caustics"));
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        c.env("VK_DRIVER_FILES", LAVAPIPE_ICD);
    }
    for (k, v) in env {
        match v {
            Some(v) => c.env(k, v),
            None => c.env_remove(k),
        };
    }
    c.args(args).output().expect("run caustics")
}

/// Exit code 1 and exactly one line on stderr, `error: ` first, containing
/// every `needles`.
fn one_line_error(o: &Output, needles: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "one line expected: {stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "expected `{n}` in {stderr}");
    }
    stderr
}

fn out_dir(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("caustics-cli-errors-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn manifest(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(rel)
        .to_string_lossy()
        .into_owned()
}

#[test]
fn parse_errors_are_one_line_naming_the_argument() {
    for (args, needle) in [
        (vec!["render", "--height", "-1"], "'--height <HEIGHT>'"),
        (vec!["render", "--width", "-3"], "'--width <WIDTH>'"),
        (vec!["render", "--frames", "many"], "'--frames <FRAMES>'"),
        (
            vec!["reference", "--photons", "1e99"],
            "'--photons <PHOTONS>'",
        ),
        (vec!["bench", "--warmup", "x"], "'--warmup <WARMUP>'"),
        (vec!["render", "--no-such-flag"], "'--no-such-flag'"),
        (vec!["paint"], "'paint'"),
    ] {
        one_line_error(&run(&args, &[]), &[needle, "--help"]);
    }
    // A negative time is a time, not an option.
    let o = run(&["render", "--time", "-1", "--width", "0"], &[]);
    one_line_error(&o, &["--width 0"]);
    let o = run(&["render", "--help"], &[]);
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stdout).contains("--technique"));
}

#[test]
fn a_parameter_given_twice_is_refused() {
    let o = run(
        &[
            "render",
            "--technique",
            "direct",
            "--param",
            "shadow_map_size=512",
            "--param",
            "shadow_map_size=1024",
        ],
        &[],
    );
    one_line_error(&o, &["--param shadow_map_size: given twice"]);
}

#[test]
fn a_scene_the_technique_cannot_use_fails_before_the_device() {
    let dir = out_dir("water");
    let out = dir.join("deep/x.png");
    let o = run(
        &[
            "render",
            "--technique",
            "water_photons",
            "--scene",
            &manifest("assets/scenes/ball_lens.toml"),
            "--width",
            "16",
            "--height",
            "16",
            "--out",
            out.to_str().unwrap(),
        ],
        &[],
    );
    one_line_error(
        &o,
        &["ball_lens.toml: object: water_photons needs a `water` object (shape = \"water\")"],
    );
    assert!(o.stdout.is_empty(), "no device opened");
    assert!(!dir.exists(), "nothing created at --out");
    // No sun: the light is named.
    let scene = dir.with_extension("toml");
    let text = std::fs::read_to_string(manifest("assets/scenes/water_pool.toml")).unwrap();
    let sun = "kind = \"directional\"\ndirection = [-0.35, -1.0, -0.45]\nirradiance = [1000.0, 980.0, 950.0]";
    assert!(text.contains(sun), "water_pool's sun changed");
    let point = "kind = \"point\"\nposition = [0.0, 10.0, 0.0]\nintensity = 100.0";
    let text = text.replace(sun, point);
    std::fs::write(&scene, text).unwrap();
    let o = run(
        &[
            "bench",
            "--technique",
            "water_photons",
            "--scene",
            scene.to_str().unwrap(),
        ],
        &[],
    );
    let e = one_line_error(&o, &["light: water_photons needs a directional light"]);
    assert!(!e.contains("device"), "{e}");
}

#[test]
fn photons_rounded_to_whole_passes_say_so() {
    let dir = out_dir("photons");
    let out = dir.join("r.png");
    let ball_lens = manifest("assets/scenes/ball_lens.toml");
    // An 8x8 reference of ball_lens: its stdout, after checking it succeeded.
    let traced = |photons: &str, pass_photons: &str| {
        let o = run(
            &[
                "reference",
                "--scene",
                &ball_lens,
                "--photons",
                photons,
                "--pass-photons",
                pass_photons,
                "--width",
                "8",
                "--height",
                "8",
                "--out",
                out.to_str().unwrap(),
            ],
            &[],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let stdout = traced("1", "262144");
    assert!(
        stdout.contains("--photons 1: rounded up to 262144, whole passes of 262144"),
        "{stdout}"
    );
    assert!(stdout.contains("traced 262144 photons"), "{stdout}");
    // Smaller passes: the count rounds to them.
    let stdout = traced("100", "64");
    assert!(
        stdout.contains("traced 128 photons in 2 passes"),
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(&dir);
    for bad in ["100", "0", "33554432"] {
        let o = run(
            &[
                "reference",
                "--pass-photons",
                bad,
                "--out",
                dir.join("r.png").to_str().unwrap(),
            ],
            &[],
        );
        one_line_error(
            &o,
            &[&format!(
                "--pass-photons must be a multiple of 64 from 64 to 16777216, got {bad}"
            )],
        );
        assert!(!dir.exists(), "nothing created at --out");
    }
    // An absurd count (it overflowed the rounding and panicked) is refused.
    let o = run(
        &[
            "reference",
            "--photons",
            "18446744073709551615",
            "--out",
            dir.join("r.png").to_str().unwrap(),
        ],
        &[],
    );
    one_line_error(
        &o,
        &["--photons 18446744073709551615: must be between 1 and 1e15"],
    );
    assert!(!dir.exists(), "nothing created at --out");
}

#[test]
fn demo_without_a_display_says_so_in_one_line() {
    let o = run(
        &["demo", "--technique", "direct"],
        &[("DISPLAY", None), ("WAYLAND_DISPLAY", None)],
    );
    let e = one_line_error(&o, &["demo needs a display", "DISPLAY"]);
    assert!(!e.contains(".cargo") && !e.contains(".rs:"), "{e}");
}

/// `render` of ball_lens with `direct` at `size`, `frames` frames, into a
/// fresh folder; with `fault` as `CAUSTICS_TEST_FAULT` (src/vk/fault.rs).
fn render_direct(name: &str, size: u32, frames: u32, fault: Option<&str>) -> (Output, PathBuf) {
    let scene = manifest("assets/scenes/ball_lens.toml");
    render_direct_scene(name, &scene, size, frames, fault)
}

/// `render_direct` of `scene`.
fn render_direct_scene(
    name: &str,
    scene: &str,
    size: u32,
    frames: u32,
    fault: Option<&str>,
) -> (Output, PathBuf) {
    let dir = out_dir(name);
    let out = dir.join("x.png");
    let size = size.to_string();
    let frames = frames.to_string();
    let o = run(
        &[
            "render",
            "--technique",
            "direct",
            "--scene",
            scene,
            "--width",
            &size,
            "--height",
            &size,
            "--frames",
            &frames,
            "--out",
            out.to_str().unwrap(),
        ],
        &[("CAUSTICS_TEST_FAULT", fault)],
    );
    (o, dir)
}

/// Device limits are checked before anything is allocated (src/vk/limits.rs):
/// a 16384² RGBA32F target is over lavapipe's maxResourceSize (4 GiB - 1);
/// at 11000² the radiance target (1.8 GiB) fits the 2 GiB heap and the
/// display image after it does not (measured: 90 MB peak RSS, 0.2 s, so
/// the check refuses before lavapipe's memory is touched). One line naming
/// the arguments and the limit, exit 1, nothing at --out.
#[test]
fn requests_over_the_device_limits_name_the_argument_and_the_limit() {
    let (o, dir) = render_direct("limit-resource", 16384, 1, None);
    one_line_error(
        &o,
        &[
            "--width 16384 --height 16384",
            "\"radiance\"",
            "maxResourceSize",
        ],
    );
    assert!(!dir.exists(), "nothing created at --out");
    let (o, dir) = render_direct("limit-heap", 11000, 1, None);
    one_line_error(
        &o,
        &[
            "--width 11000 --height 11000",
            "memory heap 0 holds 2.0 GiB",
        ],
    );
    assert!(!dir.exists(), "nothing created at --out");
}

/// VK_ERROR_DEVICE_LOST and VK_ERROR_OUT_OF_DEVICE_MEMORY, which lavapipe
/// cannot produce, injected by the test hook: during set-up (the first
/// queue operation), amid the frames (the 12th: set-up takes about 7, each
/// frame a submit and a wait) and at an allocation. Each is one line, exit
/// 1, nothing written.
#[test]
fn a_lost_device_or_its_memory_running_out_is_one_line_and_no_output() {
    for (name, fault, frames, needle) in [
        ("lost-setup", "device_lost:1", 1, "VK_ERROR_DEVICE_LOST"),
        ("lost-frames", "device_lost:12", 10, "VK_ERROR_DEVICE_LOST"),
        (
            "oom",
            "out_of_device_memory:3",
            1,
            "VK_ERROR_OUT_OF_DEVICE_MEMORY",
        ),
    ] {
        let (o, dir) = render_direct(name, 32, frames, Some(fault));
        one_line_error(&o, &[needle]);
        assert!(!dir.exists(), "{name}: nothing created at --out");
    }
    // Without the fault the same command writes its pair.
    let (o, dir) = render_direct("no-fault", 32, 10, None);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("x.png").exists() && dir.join("x.exr").exists());
    let _ = std::fs::remove_dir_all(dir);
}

/// Output into a closed pipe (`caustics render --technique list | head -1`)
/// ends the process by SIGPIPE, as Unix tools do, not by a panic in println!.
#[test]
fn a_closed_stdout_pipe_is_no_panic() {
    use std::os::unix::process::ExitStatusExt as _;
    use std::process::Stdio;
    // The read end is closed before the child starts: closing it after
    // spawn raced the child's first write, which a pipe's buffer accepts.
    let (reader, writer) = std::io::pipe().expect("pipe");
    drop(reader);
    let o = Command::new(env!("CARGO_BIN_EXE_caustics"))
        .args(["render", "--technique", "list"])
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .expect("run caustics");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(
        o.status.signal(),
        Some(13),
        "SIGPIPE: {:?} {stderr}",
        o.status
    );
}

/// `bench --memory-samples N` (the soak's leak check, scripts/soak.sh):
/// N samples evenly over the timed frames, in the JSON, each with the
/// host's RSS and gpu-allocator's live device memory.
#[test]
fn bench_samples_memory_over_the_timed_frames() {
    let dir = out_dir("memory");
    let json = dir.join("b.json");
    let o = run(
        &[
            "bench",
            "--technique",
            "direct",
            "--scene",
            &manifest("assets/scenes/ball_lens.toml"),
            "--param",
            "shadow_map_size=64",
            "--width",
            "16",
            "--height",
            "16",
            "--frames",
            "6",
            "--warmup",
            "1",
            "--memory-samples",
            "3",
            "--json",
            json.to_str().unwrap(),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let samples = report["memory"].as_array().expect("memory samples");
    let frames: Vec<u64> = samples
        .iter()
        .map(|s| s["frame"].as_u64().unwrap())
        .collect();
    assert_eq!(frames, vec![2, 4, 6]);
    for s in samples {
        assert!(s["host_rss"].as_u64().unwrap() > 1 << 20, "{s}");
        assert!(s["device_allocated"].as_u64().unwrap() > 0, "{s}");
        // Nothing is allocated per frame: every sample holds the same.
        assert_eq!(s["device_allocated"], samples[0]["device_allocated"]);
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// A valid scene whose triangles do not fit one storage buffer (a sphere of
/// 1200 segments: 1,437,600 triangles of 96 bytes, over lavapipe's
/// maxStorageBufferRange of 128 MiB, 1,398,101 triangles) is refused before
/// the BVH build, naming --scene, the count and the limit. Before, nothing
/// checked this limit.
#[test]
fn a_scene_over_the_storage_buffer_limit_is_refused() {
    let scene = std::env::temp_dir().join(format!(
        "caustics-cli-errors-{}-sphere.toml",
        std::process::id()
    ));
    std::fs::write(
        &scene,
        "[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n\n\
         [[light]]\nkind = \"point\"\nposition = [0.0, 5.0, 0.0]\nintensity = [10.0, 10.0, 10.0]\n\n\
         [[material]]\nname = \"m\"\nkind = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]\n\n\
         [[object]]\nshape = \"sphere\"\nradius = 1.0\nsegments = 1200\nmaterial = \"m\"\n",
    )
    .unwrap();
    let (o, dir) = render_direct_scene("triangles", scene.to_str().unwrap(), 16, 1, None);
    one_line_error(
        &o,
        &[
            "--scene ",
            "1437600 triangles: the device holds at most 1398101",
            "maxStorageBufferRange",
        ],
    );
    assert!(!dir.exists(), "nothing created at --out");
    let _ = std::fs::remove_file(scene);
}

/// `compare --reference` takes linear radiance only (issue 31): a PNG
/// (display values) and an EXR with a negative or infinite texel are
/// refused in one line naming the file, before the device, and no
/// comparison folder is made.
#[test]
fn compare_reference_must_be_finite_non_negative_exr() {
    let dir = out_dir("compare-reference");
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("reference.png");
    caustics::output::write_png(&png, 8, 8, &[128; 8 * 8 * 4]).unwrap();
    let negative = dir.join("negative.exr");
    let mut texels = vec![1.0f32; 8 * 8 * 4];
    texels[4 * 9] = -0.5;
    caustics::output::write_exr(&negative, 8, 8, &texels).unwrap();
    let infinite = dir.join("infinite.exr");
    texels[4 * 9] = f32::INFINITY;
    caustics::output::write_exr(&infinite, 8, 8, &texels).unwrap();
    let out = dir.join("out");
    for (reference, needle) in [
        (&png, "not an OpenEXR image"),
        (&negative, "texel (1, 1)"),
        (&infinite, "finite and non-negative"),
        (&dir, "not a regular file"),
    ] {
        let o = run(
            &[
                "compare",
                "--scene",
                &manifest("assets/scenes/ball_lens.toml"),
                "--width",
                "8",
                "--height",
                "8",
                "--reference",
                reference.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            &[],
        );
        let line = one_line_error(&o, &["--reference", needle]);
        assert!(line.contains(reference.to_str().unwrap()), "{line}");
        assert!(
            !String::from_utf8_lossy(&o.stdout).contains("device"),
            "{line}"
        );
        assert!(!out.exists(), "{line}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `dir/scene.toml`: a camera, a point light, one diffuse material `m`
/// (with `material`'s keys) and one object (`object`'s keys) made of it.
fn one_object_scene(dir: &Path, material: &str, object: &str) -> PathBuf {
    let scene = dir.join("scene.toml");
    let text = format!(
        "[camera]\neye = [0.0, 2.0, 4.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40.0\n\n\
         [[light]]\nkind = \"point\"\nposition = [0.0, 3.0, 0.0]\nintensity = [10.0, 10.0, 10.0]\n\n\
         [[material]]\nname = \"m\"\nkind = \"diffuse\"\n{material}\n\n\
         [[object]]\n{object}\nmaterial = \"m\"\n"
    );
    std::fs::write(&scene, text).unwrap();
    scene
}

/// Issue 31: a FIFO anywhere in a scene hung the program, `/dev/zero` was
/// read until memory ran out. Each is now one line naming the file, at
/// once (the child is killed after 60 s, which fails the test).
#[test]
fn special_files_in_a_scene_are_refused_without_reading_them() {
    let dir = out_dir("special-inputs");
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("mesh.obj");
    let made = Command::new("mkfifo").arg(&fifo).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
    let scene = one_object_scene(
        &dir,
        "albedo = 0.5",
        "shape = \"mesh\"\npath = \"mesh.obj\"",
    );
    let fifo_scene = dir.join("fifo.toml");
    assert!(Command::new("mkfifo")
        .arg(&fifo_scene)
        .status()
        .unwrap()
        .success());
    let cases = [
        (scene.clone(), "a FIFO, socket or device"),
        (fifo_scene.clone(), "a FIFO, socket or device"),
        (PathBuf::from("/dev/zero"), "not a regular file"),
        (dir.clone(), "a folder"),
    ];
    for (path, needle) in cases {
        let mut child = Command::new(env!("CARGO_BIN_EXE_caustics"))
            .args([
                "render",
                "--scene",
                path.to_str().unwrap(),
                "--width",
                "8",
                "--height",
                "8",
            ])
            .args(["--out", dir.join("x.png").to_str().unwrap()])
            .env("VK_DRIVER_FILES", LAVAPIPE_ICD)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let start = std::time::Instant::now();
        while child.try_wait().unwrap().is_none() {
            if start.elapsed() > std::time::Duration::from_secs(60) {
                let _ = child.kill();
                panic!("{}: still running after 60 s", path.display());
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let o = child.wait_with_output().unwrap();
        one_line_error(&o, &[needle]);
        assert!(!dir.join("x.png").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 31: an output path that names one of the scene's own inputs (here
/// its albedo texture, given as `--out`, and the same file reached as the
/// PNG written beside an EXR) was overwritten with exit 0.
#[test]
fn an_output_never_replaces_a_scene_input() {
    let dir = out_dir("input-as-output");
    std::fs::create_dir_all(&dir).unwrap();
    let texture = dir.join("tex.png");
    caustics::output::write_png(&texture, 2, 2, &[200; 16]).unwrap();
    let before = std::fs::read(&texture).unwrap();
    let scene = one_object_scene(
        &dir,
        "albedo_texture = \"tex.png\"",
        "shape = \"plane\"\nsize = [4.0, 4.0]",
    );
    for out in [texture.clone(), dir.join("tex.exr")] {
        let o = run(
            &[
                "render",
                "--scene",
                scene.to_str().unwrap(),
                "--width",
                "8",
                "--height",
                "8",
                "--out",
                out.to_str().unwrap(),
            ],
            &[],
        );
        one_line_error(&o, &["tex.png", "one of the scene's input files"]);
        assert_eq!(std::fs::read(&texture).unwrap(), before);
        assert!(!dir.join("tex.exr").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 31: a scene's mesh outside its folder was read. Now it is one
/// line naming the scene file, the field and the rule; `--allow-paths`
/// with the mesh's folder renders it, and a missing `--allow-paths`
/// folder is one line too.
#[test]
fn allow_paths_opens_a_folder_outside_the_scene_tree() {
    let dir = out_dir("allow-paths");
    let meshes = dir.join("meshes");
    std::fs::create_dir_all(&meshes).unwrap();
    std::fs::write(
        meshes.join("tri.obj"),
        "v -1 0 -1\nv 1 0 -1\nv 0 0 1\nf 1 3 2\n",
    )
    .unwrap();
    let scene_dir = dir.join("scene");
    std::fs::create_dir_all(&scene_dir).unwrap();
    let scene = one_object_scene(
        &scene_dir,
        "albedo = 0.5",
        "shape = \"mesh\"\npath = \"../meshes/tri.obj\"",
    );
    let out = dir.join("x.png");
    let (scene_arg, out_arg) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let run_with = |allow: &[&str]| {
        let mut args = vec![
            "render",
            "--scene",
            scene_arg,
            "--technique",
            "direct",
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            out_arg,
        ];
        args.extend(allow.iter().copied());
        run(&args, &[])
    };
    let o = run_with(&[]);
    one_line_error(
        &o,
        &[
            scene.to_str().unwrap(),
            "object[0].path",
            "it climbs above the folder",
            "--allow-paths",
        ],
    );
    assert!(!out.exists());
    let o = run_with(&["--allow-paths", meshes.to_str().unwrap()]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.exists());
    let missing = dir.join("missing");
    let o = run_with(&["--allow-paths", missing.to_str().unwrap()]);
    one_line_error(&o, &["--allow-paths", "missing"]);
    let _ = std::fs::remove_dir_all(&dir);
}
