//! End-to-end tests of the `caustics` command line: the built binary is run as
//! a process. Bad input must end with a non-zero exit code, one clear
//! `error: ` message (scene errors as `FILE:LINE:COL: FIELD: message`), no
//! panic or backtrace, and no image (or partial image) left behind. Every
//! canonical scene must render and reference-render cleanly under the
//! validation layer. The library-level rejection paths are covered in
//! tests/scene_loading.rs; these tests check the process behaviour.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

const LAVAPIPE_ICD: &str = "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json";

// ---------------------------------------------------------------- helpers

/// The built `caustics` binary, on lavapipe unless the environment picks a driver.
fn caustics() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_caustics"));
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        c.env("VK_DRIVER_FILES", LAVAPIPE_ICD);
    }
    c
}

struct Outcome {
    code: Option<i32>,
    stdout: String,
    stderr: String,
    what: String,
}

impl Outcome {
    fn describe(&self) -> String {
        format!(
            "`{}` exited with {:?}\n--- stdout\n{}\n--- stderr\n{}",
            self.what, self.code, self.stdout, self.stderr
        )
    }
}

fn run_with(args: &[&str], backtrace: bool) -> Outcome {
    let mut cmd = caustics();
    cmd.args(args);
    if backtrace {
        cmd.env("RUST_BACKTRACE", "1");
    } else {
        cmd.env_remove("RUST_BACKTRACE");
    }
    let out = cmd.output().expect("run the caustics binary");
    Outcome {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        what: format!(
            "{}caustics {}",
            if backtrace { "RUST_BACKTRACE=1 " } else { "" },
            args.join(" ")
        ),
    }
}

fn run(args: &[&str]) -> Outcome {
    run_with(args, false)
}

/// A fresh, empty folder under the system temp dir.
fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::SeqCst);
    let dir = std::env::temp_dir().join(format!("caustics-cli-{}-{name}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

fn manifest(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 temp path")
}

/// Non-zero exit, a message starting with `error: ` that contains every
/// `needles`, and no panic or backtrace text.
fn assert_clean_failure(o: &Outcome, expected_code: Option<i32>, needles: &[&str]) {
    match expected_code {
        Some(c) => assert_eq!(o.code, Some(c), "{}", o.describe()),
        None => assert!(
            o.code.is_some_and(|c| c != 0),
            "expected a non-zero exit code: {}",
            o.describe()
        ),
    }
    assert!(
        o.stderr.starts_with("error: "),
        "stderr must start with `error: `: {}",
        o.describe()
    );
    let lower = o.stderr.to_lowercase();
    for bad in ["panicked", "backtrace", "stack backtrace"] {
        assert!(!lower.contains(bad), "`{bad}` in stderr: {}", o.describe());
    }
    for n in needles {
        assert!(o.stderr.contains(n), "expected `{n}`: {}", o.describe());
    }
}

/// No image and no partial image under `dir` (searched recursively).
fn assert_no_images(dir: &Path) {
    fn walk(dir: &Path, found: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, found);
            } else {
                let name = p.file_name().unwrap().to_string_lossy().to_lowercase();
                if name.ends_with(".png") || name.ends_with(".exr") || name.contains(".partial") {
                    found.push(p);
                }
            }
        }
    }
    let mut found = Vec::new();
    walk(dir, &mut found);
    assert!(found.is_empty(), "files left behind: {found:?}");
}

/// 1-based line of the first line containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("`{needle}` not in text"))
        + 1
}

const HEAD: &str = "[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n\n\
[[light]]\nkind = \"point\"\nposition = [0.0, 5.0, 0.0]\nintensity = [10.0, 10.0, 10.0]\n\n\
[[material]]\nname = \"white\"\nkind = \"diffuse\"\nalbedo = 0.5\n\n";
const SPHERE: &str = "[[object]]\nshape = \"sphere\"\nradius = 1.0\nmaterial = \"white\"\n";

/// A broken scene: its text, extra files beside it, and what the error must say.
struct BadScene {
    name: &'static str,
    text: String,
    files: &'static [(&'static str, &'static str)],
    field: &'static str,
    /// Text on the line the error must point at.
    at: &'static str,
    message: &'static str,
}

fn bad_scenes() -> Vec<BadScene> {
    vec![
        BadScene {
            name: "syntax",
            text: format!("{HEAD}{SPHERE}\n[output]\nexposure = = 2\n"),
            files: &[],
            field: "syntax",
            at: "exposure = = 2",
            message: "",
        },
        BadScene {
            name: "unknown-key",
            text: format!(
                "{HEAD}[[object]]\nshape = \"sphere\"\nradius = 1.0\nraduis = 2.0\nmaterial = \"white\"\n"
            ),
            files: &[],
            field: "object[0].raduis",
            at: "raduis",
            message: "unknown field",
        },
        BadScene {
            name: "negative-radius",
            text: format!(
                "{HEAD}[[object]]\nshape = \"sphere\"\nradius = -1.0\nmaterial = \"white\"\n"
            ),
            files: &[],
            field: "object[0].radius",
            at: "radius = -1.0",
            message: "must be positive",
        },
        BadScene {
            name: "missing-material",
            text: format!("{HEAD}[[object]]\nshape = \"sphere\"\nradius = 1.0\nmaterial = \"nope\"\n"),
            files: &[],
            field: "object[0].material",
            at: "\"nope\"",
            message: "unknown material `nope`",
        },
        BadScene {
            name: "ior-below-1",
            text: format!(
                "{HEAD}[[material]]\nname = \"g\"\nkind = \"dielectric\"\nior = 0.9\n\n{SPHERE}"
            ),
            files: &[],
            field: "material[1].ior",
            at: "ior = 0.9",
            message: "at least 1",
        },
        BadScene {
            name: "nan",
            text: format!("{HEAD}[[object]]\nshape = \"sphere\"\nradius = nan\nmaterial = \"white\"\n"),
            files: &[],
            field: "object[0].radius",
            at: "radius = nan",
            message: "finite",
        },
        BadScene {
            name: "missing-obj",
            text: format!(
                "{HEAD}[[object]]\nshape = \"mesh\"\npath = \"meshes/gone.obj\"\nmaterial = \"white\"\n"
            ),
            files: &[],
            field: "object[0].path",
            at: "gone.obj",
            message: "gone.obj",
        },
        BadScene {
            name: "broken-obj",
            text: format!(
                "{HEAD}[[object]]\nshape = \"mesh\"\npath = \"broken.obj\"\nmaterial = \"white\"\n"
            ),
            files: &[("broken.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n")],
            field: "object[0].path",
            at: "broken.obj",
            message: "broken.obj",
        },
    ]
}

// ---------------------------------------------------------------- bad input

#[test]
fn broken_scenes_fail_cleanly_in_render_and_reference() {
    for bad in bad_scenes() {
        let dir = temp_dir(bad.name);
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, &bad.text).unwrap();
        for (file, contents) in bad.files {
            std::fs::write(dir.join(file), contents).unwrap();
        }
        let line = line_of(&bad.text, bad.at);
        let prefix = format!("error: {}:{line}:", scene.display());
        let field = format!(": {}: ", bad.field);
        let out = dir.join("out");
        for command in ["render", "reference"] {
            for backtrace in [false, true] {
                let x = out.join("x.png");
                let mut args = vec![
                    command,
                    "--scene",
                    s(&scene),
                    "--width",
                    "32",
                    "--height",
                    "32",
                    "--out",
                    s(&x),
                ];
                if command == "reference" {
                    args.extend(["--photons", "1000"]);
                }
                let o = run_with(&args, backtrace);
                assert_clean_failure(&o, Some(1), &[&field, bad.message]);
                assert!(
                    o.stderr.starts_with(&prefix),
                    "{}: expected `{prefix}`: {}",
                    bad.name,
                    o.describe()
                );
                assert_eq!(
                    o.stderr.lines().count(),
                    1,
                    "{}: one line of error expected: {}",
                    bad.name,
                    o.describe()
                );
                assert!(o.stdout.is_empty(), "{}", o.describe());
                assert_no_images(&dir);
            }
        }
    }
}

#[test]
fn missing_scene_file_is_named_once() {
    let dir = temp_dir("missing");
    let scene = dir.join("nowhere.toml");
    for command in ["render", "reference", "bench"] {
        for backtrace in [false, true] {
            let mut args = vec![
                command,
                "--scene",
                s(&scene),
                "--width",
                "32",
                "--height",
                "32",
            ];
            let x = dir.join("out/x.png");
            if command != "bench" {
                args.extend(["--out", s(&x)]);
            }
            let o = run_with(&args, backtrace);
            let prefix = format!("error: {}: cannot read scene file", scene.display());
            assert_clean_failure(&o, Some(1), &[&prefix]);
            // The OS reason appears once: the error chain is not printed twice.
            assert_eq!(
                o.stderr.matches("No such file or directory").count(),
                1,
                "{}",
                o.describe()
            );
            assert_no_images(&dir);
        }
    }
}

/// Bad command-line values: each fails before any work with a clear message.
#[test]
fn bad_arguments_fail_cleanly() {
    let dir = temp_dir("args");
    let scene = manifest("assets/scenes/ball_lens.toml");
    let scene = s(&scene);
    let out = dir.join("out/x.png");
    let out = s(&out);
    let jpg = dir.join("out/x.jpg");
    let jpg = s(&jpg);
    let small = ["--width", "32", "--height", "32"];
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec!["render", "--technique", "nope"],
            vec!["unknown technique `nope`", "available: direct"],
        ),
        (
            vec!["bench", "--technique", "nope"],
            vec!["unknown technique `nope`", "available: direct"],
        ),
        (
            vec!["render", "--param", "nope=1"],
            vec![
                "--param nope",
                "no such parameter",
                "shadow_map_size",
                "pcf_radius",
            ],
        ),
        (
            vec!["bench", "--param", "nope=1"],
            vec!["--param nope", "no such parameter"],
        ),
        (
            vec!["render", "--param", "shadow_map_size=5"],
            vec!["--param shadow_map_size=5", "[64, 4096]"],
        ),
        (
            vec!["render", "--param", "shadow_map_size=100.5"],
            vec!["whole number"],
        ),
        (
            vec!["render", "--param", "pcf_radius=abc"],
            vec!["--param pcf_radius", "not a number"],
        ),
        (
            vec!["render", "--param", "pcf_radius"],
            vec!["expected NAME=VALUE"],
        ),
        (vec!["render", "--out", jpg], vec!["x.jpg", ".png or .exr"]),
        (
            vec!["reference", "--out", jpg],
            vec!["x.jpg", ".png or .exr"],
        ),
        (
            vec!["render", "--width", "0"],
            vec!["--width 0", "between 1 and 16384"],
        ),
        (
            vec!["reference", "--height", "0"],
            vec!["--height 0", "between 1 and 16384"],
        ),
        (vec!["render", "--width", "100000"], vec!["--width 100000"]),
        (vec!["render", "--time", "nan"], vec!["--time", "finite"]),
        (vec!["render", "--frames", "0"], vec!["--frames"]),
        (vec!["bench", "--frames", "0"], vec!["--frames"]),
        (
            vec!["bench", "--frames", "2", "--memory-samples", "3"],
            vec!["--memory-samples 3: at most --frames (2)"],
        ),
        (vec!["reference", "--photons", "0"], vec!["--photons"]),
        (
            vec!["reference", "--component", "nope"],
            vec!["unknown component `nope`", "surface_caustics"],
        ),
        (
            vec!["render", "--component", "nope"],
            vec!["unknown component `nope`", "surface_caustics"],
        ),
        (
            vec![
                "render",
                "--technique",
                "direct",
                "--component",
                "surface_caustics",
            ],
            vec![
                "technique `direct` does not render component `surface_caustics`",
                "it renders: direct, emitted, all",
            ],
        ),
        (
            vec!["render", "--device", "99"],
            vec!["no device matches --device \"99\"", "caustics info"],
        ),
        (
            vec!["reference", "--device", "99"],
            vec!["no device matches --device \"99\"", "caustics info"],
        ),
        (
            vec!["bench", "--device", "no-such-gpu"],
            vec!["no device matches --device \"no-such-gpu\""],
        ),
    ];
    for (args, needles) in cases {
        let mut all = args.clone();
        all.extend(["--scene", scene]);
        for pair in small.chunks(2) {
            if !args.contains(&pair[0]) {
                all.extend(pair);
            }
        }
        if args[0] != "bench" && !args.contains(&"--out") {
            all.extend(["--out", out]);
        }
        for backtrace in [false, true] {
            let o = run_with(&all, backtrace);
            assert_clean_failure(&o, Some(1), &needles);
            assert_no_images(&dir);
        }
    }
}

/// An output that cannot be written is refused before any rendering, and
/// neither image of the pair (nor a partial one) is left behind.
#[test]
fn unwritable_outputs_fail_before_rendering() {
    let scene = manifest("assets/scenes/ball_lens.toml");
    for command in ["render", "reference"] {
        let dir = temp_dir("unwritable");
        // The PNG sibling of the requested EXR is a folder.
        std::fs::create_dir_all(dir.join("x.png")).unwrap();
        // A regular file where the output folder should be.
        std::fs::write(dir.join("file"), "").unwrap();
        for (out, needle) in [
            (dir.join("x.exr"), "x.png is a folder"),
            (dir.join("x.png"), "x.png is a folder"),
            (dir.join("file/y.png"), "cannot create folder"),
        ] {
            let o = run_with(
                &[
                    command,
                    "--scene",
                    s(&scene),
                    "--width",
                    "32",
                    "--height",
                    "32",
                    "--photons",
                    "1000",
                    "--out",
                    s(&out),
                ]
                .into_iter()
                .filter(|a| command == "reference" || (*a != "--photons" && *a != "1000"))
                .collect::<Vec<_>>(),
                true,
            );
            assert_clean_failure(&o, Some(1), &[needle, s(&out)]);
            assert!(
                o.stdout.is_empty(),
                "rendered before failing: {}",
                o.describe()
            );
            assert!(!dir.join("x.exr").exists(), "{}", o.describe());
            for e in std::fs::read_dir(&dir).unwrap() {
                let name = e.unwrap().file_name().to_string_lossy().into_owned();
                assert!(!name.contains(".partial"), "{name} left behind");
            }
        }
    }
}

/// Values the argument parser itself rejects: one line, exit code 1 like
/// every other bad input (tests/cli_errors.rs checks the argument is named).
#[test]
fn unparsable_arguments_are_usage_errors() {
    for args in [
        vec!["render", "--width", "-3"],
        vec!["render", "--frames", "many"],
        vec!["reference", "--photons", "1e99"],
        vec!["render", "--no-such-flag"],
        vec!["paint"],
    ] {
        let o = run_with(&args, true);
        assert_clean_failure(&o, Some(1), &[]);
        assert_eq!(o.stderr.lines().count(), 1, "{}", o.describe());
    }
}

// ---------------------------------------------------------------- listings

#[test]
fn technique_list_shows_direct_and_its_parameters() {
    let o = run(&["render", "--technique", "list"]);
    assert_eq!(o.code, Some(0), "{}", o.describe());
    for spec in caustics::techniques::find("direct").unwrap().params() {
        assert!(
            o.stdout.contains(&format!("--param {}=VALUE", spec.name)),
            "`{}` not listed: {}",
            spec.name,
            o.describe()
        );
    }
    assert!(o.stdout.contains("  direct "), "{}", o.describe());
    assert!(o.stdout.contains("shadow_map_size"), "{}", o.describe());
    assert!(o.stdout.contains("reference"), "{}", o.describe());
}

#[test]
fn info_lists_the_device_with_every_required_feature() {
    let o = run(&["info"]);
    assert_eq!(o.code, Some(0), "{}", o.describe());
    let first = o.stdout.lines().next().unwrap_or_default();
    assert!(first.starts_with("[0] "), "{}", o.describe());
    let on_lavapipe = std::env::var("VK_DRIVER_FILES").map_or(true, |v| v.contains("lvp_icd"));
    if on_lavapipe {
        assert!(first.contains("llvmpipe"), "{}", o.describe());
    }
    for f in caustics::vk::RequiredFeature::ALL {
        let line = format!("yes {}", f.name());
        assert!(
            o.stdout.lines().any(|l| l.trim() == line),
            "`{line}` missing: {}",
            o.describe()
        );
    }
    assert!(!o.stdout.contains("NO "), "{}", o.describe());
}

/// `render --component` splits a frame into its path-type components: with
/// `image_space` on the ball lens, direct + surface caustics is the full
/// frame (the technique adds the caustic term onto the direct term, so the
/// sum holds to float rounding), the caustic part is not empty, and it is
/// zero where the component mask drops it.
#[test]
fn render_components_add_up_to_the_frame() {
    let dir = temp_dir("components");
    let scene = manifest("assets/scenes/ball_lens.toml");
    let mut images = Vec::new();
    for component in ["all", "direct", "surface_caustics"] {
        let exr = dir.join(format!("{component}.exr"));
        let o = run(&[
            "render",
            "--scene",
            s(&scene),
            "--technique",
            "image_space",
            "--param",
            "photon_buffer_size=128",
            "--param",
            "caustic_map_size=128",
            "--component",
            component,
            "--width",
            "64",
            "--height",
            "64",
            "--validate",
            "--out",
            s(&exr),
        ]);
        assert_eq!(o.code, Some(0), "{}", o.describe());
        assert_silent_teardown(&o);
        check_exr(&exr, 64, 64);
        images.push(caustics::output::read_exr(&exr).expect("read EXR").2);
    }
    let (all, direct, caustic) = (&images[0], &images[1], &images[2]);
    let total = |img: &[f32]| {
        img.chunks_exact(4)
            .map(|p| (p[0] + p[1] + p[2]) as f64)
            .sum::<f64>()
    };
    let (e_all, e_direct, e_caustic) = (total(all), total(direct), total(caustic));
    assert!(e_caustic > 0.01 * e_all, "caustic {e_caustic} of {e_all}");
    assert!(e_direct > 0.5 * e_all, "direct {e_direct} of {e_all}");
    for ((a, d), c) in all
        .chunks_exact(4)
        .zip(direct.chunks_exact(4))
        .zip(caustic.chunks_exact(4))
    {
        for k in 0..3 {
            let sum = d[k] + c[k];
            assert!(
                (a[k] - sum).abs() <= 1e-5 * a[k].abs().max(1.0),
                "all {} != direct {} + caustic {}",
                a[k],
                d[k],
                c[k]
            );
        }
    }
}

// ---------------------------------------------------------------- canonical scenes

fn canonical_scenes() -> Vec<PathBuf> {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(manifest("assets/scenes"))
        .expect("assets/scenes")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 7, "canonical scenes: {scenes:?}");
    scenes
}

/// Reads the EXR; asserts every value is finite and the total energy positive.
fn check_exr(path: &Path, width: u32, height: u32) -> f64 {
    let (w, h, rgba) = caustics::output::read_exr(path).expect("read EXR");
    assert_eq!((w, h), (width, height), "{}", path.display());
    let bad = rgba.iter().filter(|v| !v.is_finite()).count();
    assert_eq!(bad, 0, "{}: {bad} NaN/Inf values", path.display());
    let energy: f64 = rgba
        .chunks_exact(4)
        .map(|p| (p[0] + p[1] + p[2]) as f64)
        .sum();
    assert!(energy > 0.0, "{}: no light at all", path.display());
    energy
}

/// The whole run, teardown included, was silent: leaked Vulkan objects are
/// reported by the validation layer at vkDestroyDevice and leaked memory by
/// gpu-allocator at shutdown, both after the exit code is decided, so the
/// log is what shows them.
fn assert_silent_teardown(o: &Outcome) {
    for bad in ["Validation Error", "VUID-", "leak"] {
        assert!(
            !o.stderr.contains(bad),
            "`{bad}` in stderr: {}",
            o.describe()
        );
    }
}

#[test]
fn every_canonical_scene_renders() {
    let dir = temp_dir("sweep-render");
    for scene in canonical_scenes() {
        let stem = scene.file_stem().unwrap().to_str().unwrap();
        let exr = dir.join(format!("{stem}.exr"));
        let mut args = vec![
            "render",
            "--scene",
            s(&scene),
            "--width",
            "64",
            "--height",
            "64",
            "--frames",
            "2",
            "--validate",
            "--out",
            s(&exr),
        ];
        // smoke's volume_lines draws 512² light rays through fractal noise
        // whatever the image size (6 s a frame here, 14 s of the sweep
        // alone); 128² rays run the same shaders (2.4 s).
        if stem == "smoke" {
            args.extend(["--param", "volume_buffer_size=128"]);
        }
        let o = run(&args);
        assert_eq!(o.code, Some(0), "{}", o.describe());
        assert!(
            o.stdout.contains("gbuffer") && o.stdout.contains(" ms"),
            "no per-pass timings: {}",
            o.describe()
        );
        assert!(exr.with_extension("png").is_file(), "{}", o.describe());
        assert_silent_teardown(&o);
        check_exr(&exr, 64, 64);
    }
    // Nothing but the finished images.
    for e in std::fs::read_dir(&dir).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.contains(".partial"), "{name} left behind");
    }
}

#[test]
fn every_canonical_scene_reference_renders() {
    let dir = temp_dir("sweep-reference");
    for scene in canonical_scenes() {
        let stem = scene.file_stem().unwrap().to_str().unwrap();
        let exr = dir.join(format!("{stem}_ref.exr"));
        let o = run(&[
            "reference",
            "--scene",
            s(&scene),
            "--width",
            "48",
            "--height",
            "48",
            // Two passes of few photons: every shader runs, and the fold
            // of one pass into the next; what is checked (a clean exit, no
            // validation message, a finite image with light in it) needs
            // no more (was one pass of 262,144: 40 s for the sweep, now 22).
            "--pass-photons",
            "16384",
            "--photons",
            "32768",
            "--validate",
            "--out",
            s(&exr),
        ]);
        assert_eq!(o.code, Some(0), "{}", o.describe());
        assert!(o.stdout.contains("traced "), "{}", o.describe());
        assert!(exr.with_extension("png").is_file(), "{}", o.describe());
        assert_silent_teardown(&o);
        check_exr(&exr, 48, 48);
    }
    for e in std::fs::read_dir(&dir).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.contains(".partial"), "{name} left behind");
    }
}

/// Issue 31: the default scene is a path relative to a checkout; run from
/// any other folder, the binary finds it above itself (a checkout's
/// `target/`) instead of failing with "cannot read scene file".
#[test]
fn the_default_scene_is_found_from_any_folder() {
    let dir = temp_dir("default-scene");
    std::fs::create_dir_all(&dir).unwrap();
    let o = caustics()
        .current_dir(&dir)
        .args([
            "render", "--width", "16", "--height", "16", "--out", "x.exr",
        ])
        .output()
        .expect("run the caustics binary");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    check_exr(&dir.join("x.exr"), 16, 16);
    let _ = std::fs::remove_dir_all(&dir);
}
