//! Values that parse but are out of their physical range (issue 18): OBJ/MTL
//! numbers (non-finite, negative, out of range) and the scene's physical
//! bounds (lengths, positions, intensities, speeds, scales), each rejected
//! with one line naming the file, the line and the field, exit code 1 from
//! the command line.

use caustics::scene::*;
use glam::Vec3;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

const LAVAPIPE_ICD: &str = "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json";

/// A fresh, empty folder under the system temp dir.
fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::SeqCst);
    let dir =
        std::env::temp_dir().join(format!("caustics-values-{}-{name}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

const HEAD: &str = "[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n\n\
[[light]]\nkind = \"point\"\nposition = [0.0, 5.0, 0.0]\nintensity = [10.0, 10.0, 10.0]\n\n\
[[material]]\nname = \"white\"\nkind = \"diffuse\"\nalbedo = 0.5\n\n";

const QUAD_OBJ: &str = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl a\nf 1 2 3 4\n";

/// Writes `files` and a scene whose one object is the mesh `m.obj` (with
/// `object_fields`); returns the scene's path.
fn mesh_scene(name: &str, files: &[(&str, &str)], object_fields: &str) -> PathBuf {
    let dir = temp_dir(name);
    for (f, text) in files {
        std::fs::write(dir.join(f), text).expect("write fixture");
    }
    let path = dir.join("scene.toml");
    let text = format!("{HEAD}[[object]]\nshape = \"mesh\"\npath = \"m.obj\"\n{object_fields}\n");
    std::fs::write(&path, text).expect("write scene");
    path
}

/// Loads `path`, expecting an error at `object[0].<field>` on the line of
/// the object's `path` that contains every `needles`.
fn rejected(path: &Path, field: &str, needles: &[&str]) -> String {
    let e = Scene::load(path).expect_err("must be rejected");
    let s = e.to_string();
    assert_eq!(e.field(), Some(field), "{s}");
    let text = std::fs::read_to_string(path).unwrap();
    let line = text.lines().position(|l| l.contains("m.obj")).unwrap() + 1;
    assert_eq!(e.line(), Some(line), "{s}");
    for n in needles {
        assert!(s.contains(n), "expected `{n}` in `{s}`");
    }
    assert_eq!(s.lines().count(), 1, "{s}");
    s
}

/// The `caustics render` of `scene` fails with exit code 1 and one line
/// containing every `needles`, before opening the device.
fn cli_rejects(scene: &Path, needles: &[&str]) {
    let out = scene.with_file_name("out").join("x.png");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_caustics"));
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        cmd.env("VK_DRIVER_FILES", LAVAPIPE_ICD);
    }
    let o = cmd
        .args(["render", "--width", "16", "--height", "16", "--scene"])
        .arg(scene)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("run caustics");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "expected `{n}` in `{stderr}`");
    }
    assert!(!out.exists() && !out.parent().unwrap().exists(), "{stderr}");
}

// ---------------------------------------------------------------- MTL values

#[test]
fn non_finite_and_out_of_range_mtl_values_are_rejected() {
    // (MTL statement(s) of material `a`, what the message says)
    let cases: &[(&str, &str)] = &[
        ("Kd nan 0.5 0.5", "Kd: must be finite, got NaN"),
        ("Kd 5 -3 0.5", "Kd: must be non-negative, got -3"),
        ("Kd 0.5 0.5 inf", "Kd: must be finite, got inf"),
        ("illum 3\nKs nan 1 1", "Ks: must be finite, got NaN"),
        ("Ka 0 -inf 0", "Ka: must be finite"),
        ("Ke -1 0 0", "Ke: must be non-negative"),
        ("Ns nan", "Ns: must be finite"),
        ("d 1.5", "d: must be within [0, 1], got 1.5"),
        ("Tf 5", "Tf: must be within [0, 1], got 5"),
        ("Tf 1 nan 1", "Tf: must be finite"),
        ("Tf one two", "Tf: expected numbers"),
        ("illum 7\nNi nan", "Ni: must be finite, got NaN"),
        ("illum 7\nNi inf", "Ni: must be finite, got inf"),
        ("illum 7\nNi 0", "within [1, 10], got 0"),
        ("illum 7\nNi -1", "within [1, 10], got -1"),
        ("illum 7\nNi 0.5", "within [1, 10], got 0.5"),
        ("illum 7\nNi 1e30", "within [1, 10], got 1"),
        ("illum 2\nNi nan", "Ni: must be finite"),
    ];
    for (i, (mtl, message)) in cases.iter().enumerate() {
        let files = [
            ("m.obj", QUAD_OBJ),
            ("m.mtl", &format!("newmtl a\n{mtl}\n") as &str),
        ];
        let path = mesh_scene(&format!("mtl{i}"), &files, "");
        rejected(
            &path,
            "object[0].path",
            &["MTL file", "m.mtl", "m.obj", "material `a`", message],
        );
        // The object's own material ignores the MTL and its values.
        let path = mesh_scene(&format!("mtl{i}-own"), &files, "material = \"white\"");
        Scene::load(&path).unwrap_or_else(|e| panic!("{mtl}: {e}"));
    }
    let files = [
        ("m.obj", QUAD_OBJ),
        ("m.mtl", "newmtl a\nillum 7\nNi nan\n"),
    ];
    cli_rejects(
        &mesh_scene("mtl-cli", &files, ""),
        &["object[0].path", "material `a`", "Ni: must be finite"],
    );
}

#[test]
fn valid_mtl_values_load_and_clamp_as_documented() {
    let mtl = "newmtl a\nKd 1.5 0.5 0\nNi 0\nd 1\nTf 1 1 1\nKa 1 1 1\nKs 0 0 0\n\
               newmtl glass\nillum 7\nNi 2.42\nTf xyz 0.5 0.5 0.5\n\
               newmtl plain\nTf spectral glass.rfl 1.0\n";
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
               usemtl a\nf 1 2 3\nusemtl glass\nf 1 3 4\nusemtl plain\nf 2 3 4\n";
    let path = mesh_scene("mtl-ok", &[("m.obj", obj), ("m.mtl", mtl)], "");
    let s = Scene::load(&path).expect("loads");
    let m = &s.objects[0].mesh;
    let mat = |i: usize| &s.materials[m.materials[i] as usize];
    // Kd above 1 is clamped; a diffuse material's `Ni 0` (exporters write
    // it) is not used.
    assert_eq!(
        (mat(0).kind, mat(0).color),
        (MaterialKind::Diffuse, Vec3::new(1.0, 0.5, 0.0))
    );
    assert_eq!((mat(1).kind, mat(1).ior), (MaterialKind::Dielectric, 2.42));
    assert_eq!(mat(2).kind, MaterialKind::Diffuse);
}

// ---------------------------------------------------------------- OBJ values

#[test]
fn non_finite_vertex_is_rejected_with_its_obj_line() {
    let obj = "# a quad\nv 0 0 0\nv 1 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3 4\n";
    let path = mesh_scene("v-nan", &[("m.obj", obj)], "material = \"white\"");
    rejected(
        &path,
        "object[0].path",
        &["m.obj:4:", "`v 1 nan 0`", "not finite"],
    );
    let obj = "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n";
    let path = mesh_scene("v-inf", &[("m.obj", obj)], "material = \"white\"");
    cli_rejects(&path, &["object[0].path", "m.obj:2:", "not finite"]);
}

#[test]
fn zero_and_non_finite_normals_are_recomputed() {
    // Counter-clockwise about +z: the face normal is +z.
    for (name, bad) in [
        ("zero", "vn 0 0 0"),
        ("nan", "vn nan 0 0"),
        ("inf", "vn 0 inf 0"),
    ] {
        let obj = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n{bad}\nf 1//1 2//2 3//1\n");
        let path = mesh_scene(
            &format!("vn-{name}"),
            &[("m.obj", &obj)],
            "material = \"white\"",
        );
        let s = Scene::load(&path).expect("loads");
        let m = &s.objects[0].mesh;
        assert_eq!(m.normals.len(), 3, "{bad}");
        for n in &m.normals {
            assert!((*n - Vec3::Z).length() < 1e-6, "{bad}: {n}");
        }
    }
}

// ---------------------------------------------------------------- physical bounds

const SPHERE: &str = "[[object]]\nshape = \"sphere\"\nradius = 1.0\nmaterial = \"white\"\n";

/// `text` is rejected at `field`, on the line holding `needle`, saying `message`.
fn rejects(text: &str, field: &str, needle: &str, message: &str) {
    let file = Path::new("bounds.toml");
    let e = match Scene::from_str(text, file) {
        Ok(_) => panic!("accepted a scene that should fail at {field}:\n{text}"),
        Err(e) => e,
    };
    let s = e.to_string();
    let line = text.lines().position(|l| l.contains(needle)).unwrap() + 1;
    assert!(
        s.starts_with(&format!("bounds.toml:{line}:")),
        "line {line}: {s}"
    );
    assert_eq!(e.field(), Some(field), "{s}");
    assert!(s.contains(message), "expected `{message}` in `{s}`");
}

#[test]
fn values_beyond_the_physical_bounds_are_rejected() {
    let light = |l: &str| {
        format!(
            "{}{l}\n{SPHERE}",
            HEAD.replace("intensity = [10.0, 10.0, 10.0]", "intensity = 1.0")
        )
    };
    let object = |extra: &str| {
        format!("{HEAD}[[object]]\nshape = \"sphere\"\nmaterial = \"white\"\n{extra}\n")
    };
    let cases: Vec<(String, &str, &str, &str)> = vec![
        (
            light("[[light]]\nkind = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = 3e38"),
            "light[1].intensity",
            "intensity = 3e38",
            "within ±1e10",
        ),
        (
            light("[[light]]\nkind = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [1.0, 2e10, 1.0]"),
            "light[1].irradiance[1]",
            "irradiance =",
            "within ±1e10",
        ),
        (
            light("[[light]]\nkind = \"point\"\nposition = [0.0, 3e6, 0.0]\nintensity = 1.0"),
            "light[1].position[1]",
            "3e6",
            "within ±1e6",
        ),
        (object("radius = 1e30"), "object[0].radius", "radius", "within ±1e6"),
        (object("radius = 1e-9"), "object[0].radius", "radius", "at least 1e-6"),
        (
            object("radius = 1.0\ntranslate = [3e38, 0.0, 0.0]"),
            "object[0].translate[0]",
            "translate",
            "within ±1e6",
        ),
        (
            object("radius = 1.0\nscale = [1.0, 1e-9, 1.0]"),
            "object[0].scale",
            "scale",
            "at least 1e-6",
        ),
        (
            object("radius = 1.0\nscale = 2e6"),
            "object[0].scale",
            "scale",
            "within ±1e6",
        ),
        (
            object("radius = 1.0\nanimate = { orbit_radius = 1.0, orbit_speed = 3e38 }"),
            "object[0].animate.orbit_speed",
            "orbit_speed",
            "within ±1e6",
        ),
        (
            object("radius = 1.0\nanimate = { spin = -5e6 }"),
            "object[0].animate.spin",
            "spin",
            "within ±1e6",
        ),
        (
            format!("{HEAD}{SPHERE}[medium]\nsigma_s = 1e7\nbounds = {{ min = [-1, -1, -1], max = [1, 1, 1] }}\n"),
            "medium.sigma_s",
            "sigma_s",
            "within ±1e6",
        ),
        (
            format!("{HEAD}[[object]]\nshape = \"plane\"\nsize = [1e-7, 1.0]\nmaterial = \"white\"\n"),
            "object[0].size[0]",
            "size",
            "at least 1e-6",
        ),
        (
            format!("{HEAD}{SPHERE}[output]\nexposure = 1e7\n"),
            "output.exposure",
            "exposure",
            "within ±1e6",
        ),
    ];
    for (text, field, needle, message) in &cases {
        rejects(text, field, needle, message);
    }
}

#[test]
fn real_inputs_are_within_the_bounds() {
    // A 1e6 W/sr searchlight, sunlight concentrated 1000x (1.4e6 W/m²), an
    // ocean 100 km across, a 10 µm sphere, a fast spin.
    let text = format!(
        "{}[[light]]\nkind = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = 1.4e6\n\n\
         [[object]]\nshape = \"plane\"\nsize = [1e5, 1e5]\nmaterial = \"white\"\n\n\
         [[object]]\nshape = \"sphere\"\nradius = 1e-5\nmaterial = \"white\"\nanimate = {{ spin = 36000.0 }}\n",
        HEAD.replace("intensity = [10.0, 10.0, 10.0]", "intensity = 1e6")
    );
    let s = Scene::from_str(&text, Path::new("real.toml")).expect("loads");
    s.check_at(1e5).expect("within bounds at any time");
}

#[test]
fn derived_positions_are_checked_at_the_requested_time() {
    // OBJ coordinates are not TOML numbers: 1e30 loads, then fails the
    // check before rendering, naming the object.
    let obj = "v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n";
    let path = mesh_scene("far", &[("m.obj", obj)], "material = \"white\"");
    let s = Scene::load(&path).expect("finite coordinates load");
    let e = s.check_at(0.0).expect_err("beyond the world extent");
    assert!(
        e.contains("scene.toml: object[0]: `mesh0` reaches 1e30 m") && e.contains("Bounds"),
        "{e}"
    );
    cli_rejects(&path, &["scene.toml: object[0]:", "beyond 1e7 m"]);
    // Within bounds at time 0, carried far away by an animation: the field
    // named is the animation.
    let obj = "v 0 0 0\nv 9.5e6 0 0\nv 0 1 0\nf 1 2 3\n";
    let path = mesh_scene(
        "orbit",
        &[("m.obj", obj)],
        "material = \"white\"\nanimate = { orbit_radius = 9e5, orbit_speed = 90.0 }",
    );
    let s = Scene::load(&path).expect("loads");
    s.check_at(1.0)
        .expect("at 90 degrees the orbit points along -z");
    let e = s.check_at(0.0).expect_err("at 0 it adds to +x");
    assert!(e.contains("object[0].animate:"), "{e}");
}

#[test]
fn time_beyond_the_bounds_is_refused() {
    let path = mesh_scene(
        "time",
        &[("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")],
        "material = \"white\"",
    );
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_caustics"));
    let o = cmd
        .args(["render", "--time", "1e30", "--scene"])
        .arg(&path)
        .arg("--out")
        .arg(path.with_file_name("o.png"))
        .env("VK_DRIVER_FILES", LAVAPIPE_ICD)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.starts_with("error: --time 1e30: must be a finite number of seconds within ±1e6"),
        "{stderr}"
    );
}
