//! Property tests (issue 18) over the three loaders: TOML scenes, OBJ/MTL
//! meshes, glTF files. Inputs are generated from each format's statements
//! with hostile values (NaN, infinities, huge and tiny numbers, negative and
//! out-of-range indices, wrong types, missing parts); the properties: no
//! panic, every error is one line, and a scene that loads passes or fails
//! `Scene::check_at` without a panic either.
//!
//! The suite runs `FUZZ_CASES` cases per loader (default 256: a few
//! seconds); BENCHMARKS.md records a longer run
//! (`FUZZ_CASES=5000 cargo test --release --test fuzz`). Crashes found
//! became regular tests (`found_*` below).

use caustics::scene::paths::Confinement;
use caustics::scene::{gltf, obj, AllowedPaths, Scene};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

fn cases() -> u32 {
    std::env::var("FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256)
}

fn runner() -> TestRunner {
    TestRunner::new(Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    })
}

fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::SeqCst);
    let dir = std::env::temp_dir().join(format!("caustics-fuzz-{}-{name}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// An error message is one line.
fn one_line(what: &str, e: &str) -> Result<(), TestCaseError> {
    prop_assert!(!e.contains('\n'), "{what}: a multi-line error: {e}");
    prop_assert!(!e.is_empty(), "{what}: an empty error");
    Ok(())
}

/// A loaded scene's derived checks run without a panic, at a few times.
fn check_loaded(s: &Scene) {
    for t in [0.0, 1.5, -1e6] {
        let _ = s.check_at(t);
    }
    let _ = s.triangle_count();
    let _ = s.bounding_sphere(0.0);
}

// ---------------------------------------------------------------- values

/// Numbers as TOML writes them: ordinary, huge, tiny, negative, non-finite.
fn toml_number() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-10.0f64..10.0).prop_map(|v| format!("{v:.3}")),
        1 => (-5i64..5).prop_map(|v| v.to_string()),
        1 => prop::sample::select(vec![
            "0", "0.0", "-0.0", "1e-30", "-1e-9", "1e6", "1e7", "3e38", "-3e38", "1e300",
            "nan", "inf", "-inf", "9223372036854775807", "1e10", "2e10",
        ])
        .prop_map(str::to_owned),
    ]
}

/// A TOML value of any shape: numbers, vec3s (some of the wrong length),
/// strings (some of them names the schema knows), booleans, tables.
fn toml_value() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        4 => toml_number(),
        3 => prop::collection::vec(toml_number(), 3).prop_map(|v| format!("[{}]", v.join(", "))),
        1 => prop::collection::vec(toml_number(), 0..5).prop_map(|v| format!("[{}]", v.join(", "))),
        2 => prop::sample::select(vec![
            "\"point\"", "\"spot\"", "\"directional\"", "\"diffuse\"", "\"mirror\"",
            "\"dielectric\"", "\"sphere\"", "\"plane\"", "\"box\"", "\"torus\"", "\"cylinder\"",
            "\"mesh\"", "\"gltf\"", "\"water\"", "\"m\"", "\"\"", "\"nowhere.obj\"", "true",
            "false", "1979-05-27",
        ])
        .prop_map(str::to_owned),
    ];
    leaf.prop_recursive(2, 8, 4, |inner| {
        prop::collection::vec((field_name(), inner), 0..4).prop_map(|kv| {
            let body: Vec<String> = kv.into_iter().map(|(k, v)| format!("{k} = {v}")).collect();
            format!("{{ {} }}", body.join(", "))
        })
    })
}

/// Keys of the schema (and one unknown).
fn field_name() -> impl Strategy<Value = &'static str> {
    prop::sample::select(vec![
        "kind",
        "name",
        "shape",
        "material",
        "position",
        "direction",
        "intensity",
        "irradiance",
        "cone_angle",
        "cone_falloff",
        "albedo",
        "reflectance",
        "ior",
        "absorption",
        "radius",
        "center",
        "segments",
        "size",
        "normal",
        "tangent",
        "min",
        "max",
        "radii",
        "axis",
        "p0",
        "p1",
        "caps",
        "translate",
        "rotate",
        "scale",
        "animate",
        "spin",
        "spin_axis",
        "orbit_radius",
        "orbit_speed",
        "orbit_center",
        "bob_amplitude",
        "bob_frequency",
        "resolution",
        "base_height",
        "wave",
        "amplitude",
        "wavelength",
        "steepness",
        "speed",
        "phase",
        "sigma_s",
        "sigma_a",
        "g",
        "bounds",
        "density",
        "noise",
        "frequency",
        "octaves",
        "offset",
        "exposure",
        "eye",
        "target",
        "up",
        "fov_y",
        "uv_scale",
        "bogus",
    ])
}

// ---------------------------------------------------------------- TOML scenes

/// One `[[table]]` or `[table]` with a kind-appropriate start and random
/// fields.
fn toml_table() -> impl Strategy<Value = String> {
    let header = prop::sample::select(vec![
        "[[light]]\nkind = \"point\"\nposition = [0, 5, 0]\nintensity = 10",
        "[[light]]\nkind = \"spot\"",
        "[[light]]\nkind = \"directional\"",
        "[[material]]\nname = \"m\"\nkind = \"diffuse\"",
        "[[material]]\nname = \"g\"\nkind = \"dielectric\"",
        "[[material]]\nkind = \"mirror\"",
        "[[object]]\nshape = \"sphere\"\nmaterial = \"m\"\nradius = 1",
        "[[object]]\nshape = \"plane\"\nmaterial = \"m\"",
        "[[object]]\nshape = \"box\"\nmaterial = \"m\"",
        "[[object]]\nshape = \"torus\"\nmaterial = \"m\"",
        "[[object]]\nshape = \"cylinder\"\nmaterial = \"m\"",
        "[[object]]\nshape = \"water\"\nmaterial = \"g\"\nsize = [2, 2]\nresolution = [4, 4]",
        "[[object]]\nshape = \"mesh\"\npath = \"m.obj\"",
        "[medium]\nsigma_s = 0.1\nbounds = { min = [-1, -1, -1], max = [1, 1, 1] }",
        "[output]",
        "[camera]",
    ]);
    (
        header,
        prop::collection::vec((field_name(), toml_value()), 0..5),
    )
        .prop_map(|(h, fields)| {
            let mut t = h.to_owned();
            for (k, v) in fields {
                if !t.contains(&format!("\n{k} =")) {
                    t.push_str(&format!("\n{k} = {v}"));
                }
            }
            t
        })
}

const BASE: &str = "[camera]\neye = [0, 2, 5]\ntarget = [0, 0, 0]\n\n\
[[light]]\nkind = \"point\"\nposition = [0, 5, 0]\nintensity = 10\n\n\
[[material]]\nname = \"white\"\nkind = \"diffuse\"\n\n\
[[object]]\nshape = \"sphere\"\nradius = 1\nmaterial = \"white\"\n";

#[test]
fn toml_scenes_never_panic_and_errors_are_one_line() {
    let dir = temp_dir("toml");
    std::fs::write(dir.join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let path = dir.join("s.toml");
    let strategy = (any::<bool>(), prop::collection::vec(toml_table(), 0..6));
    runner()
        .run(&strategy, |(keep_base, tables)| {
            let mut text = if keep_base {
                BASE.to_owned()
            } else {
                String::new()
            };
            for t in &tables {
                text.push('\n');
                text.push_str(t);
                text.push('\n');
            }
            match Scene::from_str(&text, &path) {
                Ok(s) => check_loaded(&s),
                Err(e) => one_line(&text, &e.to_string())?,
            }
            Ok(())
        })
        .unwrap();
}

/// Arbitrary text, and arbitrary bytes cut into a valid scene: the TOML
/// parser's errors are one line too.
#[test]
fn arbitrary_text_never_panics() {
    let path = Path::new("text.toml");
    let strategy = (0..BASE.len(), ".{0,40}");
    runner()
        .run(&strategy, |(at, insert)| {
            let mut at = at;
            while !BASE.is_char_boundary(at) {
                at -= 1;
            }
            let text = format!("{}{insert}{}", &BASE[..at], &BASE[at..]);
            match Scene::from_str(&text, path) {
                Ok(s) => check_loaded(&s),
                Err(e) => one_line(&text, &e.to_string())?,
            }
            Ok(())
        })
        .unwrap();
}

// ---------------------------------------------------------------- OBJ / MTL

fn obj_number() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => (-2.0f32..2.0).prop_map(|v| format!("{v:.3}")),
        1 => prop::sample::select(vec![
            "0", "nan", "inf", "-inf", "1e30", "-1e38", "1e-40", "x", "", "1e400",
        ])
        .prop_map(str::to_owned),
    ]
}

/// A face corner: `v`, `v/vt`, `v//vn` or `v/vt/vn`, with indices that
/// may be negative, zero or past the end.
fn corner() -> impl Strategy<Value = String> {
    let index = prop_oneof![6 => 1i64..8, 1 => -8i64..0, 1 => Just(0i64), 1 => 8i64..100];
    (index.clone(), index.clone(), index, 0..4u8).prop_map(|(v, t, n, form)| match form {
        0 => format!("{v}"),
        1 => format!("{v}/{t}"),
        2 => format!("{v}//{n}"),
        _ => format!("{v}/{t}/{n}"),
    })
}

fn obj_line() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => prop::collection::vec(obj_number(), 3).prop_map(|v| format!("v {}", v.join(" "))),
        1 => prop::collection::vec(obj_number(), 0..5).prop_map(|v| format!("v {}", v.join(" "))),
        2 => prop::collection::vec(obj_number(), 3).prop_map(|v| format!("vn {}", v.join(" "))),
        2 => prop::collection::vec(obj_number(), 2).prop_map(|v| format!("vt {}", v.join(" "))),
        5 => prop::collection::vec(corner(), 1..6).prop_map(|c| format!("f {}", c.join(" "))),
        1 => prop::sample::select(vec!["a", "b", "missing", ""]).prop_map(|m| format!("usemtl {m}")),
        1 => prop::sample::select(vec![
            "o part", "g group", "s 1", "s off", "l 1 2", "p 1", "mtllib m.mtl",
            "mtllib other.mtl", "# comment", "", "   ", "\u{e9}t\u{e9} 1 2 3",
        ])
        .prop_map(str::to_owned),
    ]
}

fn mtl_line() -> impl Strategy<Value = String> {
    let rgb = prop::collection::vec(obj_number(), 1..4).prop_map(|v| v.join(" "));
    prop_oneof![
        2 => prop::sample::select(vec!["a", "b", "a b"]).prop_map(|m| format!("newmtl {m}")),
        2 => (prop::sample::select(vec!["Kd", "Ks", "Ka", "Ke", "Tf"]), rgb)
            .prop_map(|(k, v)| format!("{k} {v}")),
        2 => (prop::sample::select(vec!["Ni", "d", "Ns", "Tr"]), obj_number())
            .prop_map(|(k, v)| format!("{k} {v}")),
        1 => (0u16..300).prop_map(|i| format!("illum {i}")),
        1 => prop::sample::select(vec![
            "map_Kd tex.png", "map_Kd missing.png", "map_Kd", "Tf xyz 0.5 0.5 0.5",
            "Tf spectral a.rfl", "newmtl", "\u{e9}t\u{e9} 1",
        ])
        .prop_map(str::to_owned),
    ]
}

/// OBJ file `path` read as a scene beside it reads it.
fn load_obj(path: &Path) -> Result<obj::ObjMesh, String> {
    obj::load(path, &Confinement::scene(path, &AllowedPaths::default()))
}

#[test]
fn obj_and_mtl_never_panic_and_errors_are_one_line() {
    let dir = temp_dir("obj");
    let scene = dir.join("s.toml");
    let strategy = (
        prop::collection::vec(obj_line(), 0..24),
        prop::collection::vec(mtl_line(), 0..12),
        any::<bool>(),
    );
    runner()
        .run(&strategy, |(obj_lines, mtl_lines, own_material)| {
            let obj_text = format!("mtllib m.mtl\n{}\n", obj_lines.join("\n"));
            let mtl_text = mtl_lines.join("\n");
            std::fs::write(dir.join("m.obj"), &obj_text).unwrap();
            std::fs::write(dir.join("m.mtl"), &mtl_text).unwrap();
            let what = format!("OBJ:\n{obj_text}\nMTL:\n{mtl_text}");
            if let Err(e) = load_obj(&dir.join("m.obj")) {
                one_line(&what, &e)?;
            }
            let material = if own_material {
                "material = \"white\"\n"
            } else {
                ""
            };
            let text =
                format!("{BASE}\n[[object]]\nshape = \"mesh\"\npath = \"m.obj\"\n{material}");
            std::fs::write(&scene, text).unwrap();
            match Scene::load(&scene) {
                Ok(s) => {
                    check_loaded(&s);
                    for n in &s.objects[1].mesh.normals {
                        prop_assert!(
                            n.is_finite() && (n.length() - 1.0).abs() < 1e-3,
                            "{what}: normal {n}"
                        );
                    }
                }
                Err(e) => one_line(&what, &e.to_string())?,
            }
            Ok(())
        })
        .unwrap();
}

// ---------------------------------------------------------------- glTF

/// A valid glTF (a triangle with normals, indices, a material, a node
/// with a matrix, a light) and its .bin.
fn gltf_base() -> (Value, Vec<u8>) {
    let mut bin = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        bin.extend(v.iter().flat_map(|x| x.to_le_bytes()));
    }
    for _ in 0..3 {
        bin.extend([0.0f32, 0.0, 1.0].iter().flat_map(|x| x.to_le_bytes()));
    }
    bin.extend([0u32, 1, 2].iter().flat_map(|x| x.to_le_bytes()));
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"mesh": 0, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 3, 0]}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0, "mode": 4}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
                       "extensions": {"KHR_materials_ior": {"ior": 1.5}}}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5125, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 36},
            {"buffer": 0, "byteOffset": 72, "byteLength": 12}
        ],
        "buffers": [{"uri": "m.bin", "byteLength": 84}],
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_ior"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 100.0, "color": [1, 1, 1]}]}}
    });
    (doc, bin)
}

/// Places in the document a mutation may change (JSON pointers).
const GLTF_SITES: &[&str] = &[
    "/scene",
    "/scenes/0/nodes/0",
    "/nodes/0/mesh",
    "/nodes/0/matrix/0",
    "/nodes/0/matrix/12",
    "/nodes/0/matrix/15",
    "/nodes/1/translation/1",
    "/meshes/0/primitives/0/attributes/POSITION",
    "/meshes/0/primitives/0/attributes/NORMAL",
    "/meshes/0/primitives/0/indices",
    "/meshes/0/primitives/0/material",
    "/meshes/0/primitives/0/mode",
    "/accessors/0/count",
    "/accessors/0/componentType",
    "/accessors/0/type",
    "/accessors/0/bufferView",
    "/accessors/1/count",
    "/accessors/2/count",
    "/accessors/2/componentType",
    "/bufferViews/0/byteOffset",
    "/bufferViews/0/byteLength",
    "/bufferViews/2/byteLength",
    "/buffers/0/byteLength",
    "/buffers/0/uri",
    "/materials/0/pbrMetallicRoughness/baseColorFactor/0",
    "/materials/0/pbrMetallicRoughness/metallicFactor",
    "/materials/0/extensions/KHR_materials_ior/ior",
    "/extensions/KHR_lights_punctual/lights/0/intensity",
    "/extensions/KHR_lights_punctual/lights/0/type",
    "/nodes/1/extensions/KHR_lights_punctual/light",
    "/extensionsUsed/0",
    "/asset/version",
];

fn json_value() -> impl Strategy<Value = Value> {
    prop_oneof![
        3 => (-4i64..100).prop_map(|v| json!(v)),
        2 => prop::sample::select(vec![
            json!(-1), json!(0), json!(5120), json!(5121), json!(5123), json!(5125), json!(5126),
            json!(4294967295u64), json!(1e300), json!(-1e300), json!(3e38), json!(1e-45),
            json!(0.5), json!("VEC2"), json!("SCALAR"), json!("MAT4"), json!("gone.bin"),
            json!("data:application/octet-stream;base64,AAAA"), json!("spot"),
            json!("KHR_draco_mesh_compression"), json!(null), json!([]), json!({}), json!(true),
        ]),
    ]
}

#[test]
fn gltf_files_never_panic_and_errors_are_one_line() {
    let dir = temp_dir("gltf");
    let path = dir.join("m.gltf");
    let strategy = (
        prop::collection::vec((prop::sample::select(GLTF_SITES), json_value()), 0..4),
        prop::collection::vec((0usize..84, any::<u8>()), 0..3),
        0usize..84,
    );
    runner()
        .run(&strategy, |(edits, flips, cut)| {
            let (mut doc, mut bin) = gltf_base();
            for (site, v) in &edits {
                if let Some(slot) = doc.pointer_mut(site) {
                    *slot = v.clone();
                }
            }
            for (at, byte) in &flips {
                bin[*at] = *byte;
            }
            // Sometimes a short buffer.
            if edits.len() == 3 {
                bin.truncate(cut);
            }
            std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
            std::fs::write(dir.join("m.bin"), &bin).unwrap();
            let what = format!("{doc}\nbin flips {flips:?}");
            if let Err(e) = gltf::load(&path) {
                one_line(&what, &e.to_string())?;
            }
            match Scene::load(&path) {
                Ok(s) => check_loaded(&s),
                Err(e) => one_line(&what, &e.to_string())?,
            }
            Ok(())
        })
        .unwrap();
}

// ---------------------------------------------------------------- crashes found

/// The error of a load that must fail.
fn refused<T>(r: Result<T, impl std::fmt::Display>) -> String {
    match r {
        Ok(_) => panic!("accepted an input that must be refused"),
        Err(e) => e.to_string(),
    }
}

/// gltf-json 1.4.1 indexed a POSITION accessor that does not exist (a
/// panic in its validation): now one line naming the attribute.
#[test]
fn found_position_accessor_out_of_range() {
    let dir = temp_dir("found-gltf");
    let path = dir.join("m.gltf");
    let (mut doc, bin) = gltf_base();
    *doc.pointer_mut("/meshes/0/primitives/0/attributes/POSITION")
        .unwrap() = json!(54);
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    std::fs::write(dir.join("m.bin"), &bin).unwrap();
    let e = refused(gltf::load(&path));
    assert!(
        e.contains("meshes[0].primitives[0].attributes.POSITION: accessor 54 does not exist (the file has 3)"),
        "{e}"
    );
    assert!(!e.contains('\n'));
}

/// tobj 4 panicked on `Kd` (and `Ka`, `Ks`, `Ke`) with fewer than three
/// numbers: one number now means grey, none or two are an error naming the
/// line.
#[test]
fn found_mtl_colour_with_fewer_than_three_numbers() {
    let dir = temp_dir("found-mtl");
    std::fs::write(
        dir.join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    )
    .unwrap();
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        format!("{BASE}\n[[object]]\nshape = \"mesh\"\npath = \"m.obj\"\n"),
    )
    .unwrap();
    std::fs::write(dir.join("m.mtl"), "newmtl a\nKd 0.25\n").unwrap();
    let s = Scene::load(&scene).expect("one number is grey");
    let m = &s.materials[s.objects[1].mesh.materials[0] as usize];
    assert_eq!(m.color, glam::Vec3::splat(0.25));
    for bad in ["Kd 1.724 -1e38", "Ks", "Ka 1 2"] {
        std::fs::write(dir.join("m.mtl"), format!("newmtl a\n{bad}\n")).unwrap();
        let e = refused(Scene::load(&scene));
        assert!(
            e.contains("m.mtl")
                && e.contains(&format!("line 2: `{bad}`"))
                && e.contains("needs 3 numbers"),
            "{e}"
        );
    }
}

/// tobj 4 overflowed on a relative index reaching before the first
/// vertex, texture coordinate or normal (a panic): now an error naming the
/// OBJ line.
#[test]
fn found_relative_index_before_the_first_vertex() {
    let dir = temp_dir("found-relative");
    let path = dir.join("m.obj");
    for (obj, line, index) in [
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-5 2/1 3/1\n",
            5,
            "-5",
        ),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", 4, "-4"),
        ("v 0 0 0\nvn 0 0 1\nf 1//-2 1//1 1//1\nv 1 0 0\n", 3, "-2"),
    ] {
        std::fs::write(&path, obj).unwrap();
        let e = refused(load_obj(&path));
        assert!(
            e.contains(&format!("m.obj:{line}: `"))
                && e.contains(&format!("relative index {index} reaches before the first")),
            "{e}"
        );
    }
    // In range: loads (the last three vertices).
    std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n").unwrap();
    assert_eq!(load_obj(&path).expect("loads").mesh.indices.len(), 1);
}

/// A TOML string holding an escaped newline (`kind = "poi\nt"`) was quoted
/// raw in the message, which then took two lines: control characters are
/// now escaped in every scene and glTF error.
#[test]
fn found_newline_quoted_in_an_error() {
    let text = BASE.replace("kind = \"point\"", "kind = \"poi\\nt\"");
    let e = refused(Scene::from_str(&text, Path::new("s.toml")));
    assert!(e.contains("unknown light kind `poi\\nt`"), "{e}");
    assert!(!e.contains('\n'), "{e}");
    let dir = temp_dir("found-newline");
    let path = dir.join("m.gltf");
    let (mut doc, bin) = gltf_base();
    doc["extensionsRequired"] = json!(["EXT_a\nb"]);
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    std::fs::write(dir.join("m.bin"), &bin).unwrap();
    let e = refused(gltf::load(&path));
    assert!(e.contains("EXT_a\\nb") && !e.contains('\n'), "{e}");
}
