//! Scene loading: canonical scenes, every rejection path (message names the
//! file, the line and the field), OBJ meshes from the wild, transforms and
//! animation.

use caustics::scene::*;
use glam::Vec3;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

// ---------------------------------------------------------------- helpers

/// A fresh, empty folder under the system temp dir.
fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::SeqCst);
    let dir =
        std::env::temp_dir().join(format!("caustics-scene-{}-{name}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

fn write(path: &Path, contents: impl AsRef<[u8]>) {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).expect("create dir");
    }
    std::fs::write(path, contents).expect("write fixture");
}

const CAMERA: &str = "[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n";
const LIGHT: &str =
    "[[light]]\nkind = \"point\"\nposition = [0.0, 5.0, 0.0]\nintensity = [10.0, 10.0, 10.0]\n";
const MATERIAL: &str = "[[material]]\nname = \"white\"\nkind = \"diffuse\"\nalbedo = 0.5\n";
const OBJECT: &str = "[[object]]\nshape = \"sphere\"\nradius = 1.0\nmaterial = \"white\"\n";

/// A valid scene with `extra` appended.
fn base(extra: &str) -> String {
    format!("{CAMERA}\n{LIGHT}\n{MATERIAL}\n{OBJECT}\n{extra}")
}

/// A valid scene whose camera table body is `camera`.
fn with_camera(camera: &str) -> String {
    format!("[camera]\n{camera}\n\n{LIGHT}\n{MATERIAL}\n{OBJECT}")
}

/// 1-based line of the first line containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("`{needle}` not in text"))
        + 1
}

/// Asserts `text` is rejected with `FILE:LINE:COL: FIELD: ...message...`, LINE the line holding `needle`.
fn rejects(text: &str, field: &str, needle: &str, message: &str) -> String {
    let file = Path::new("scenes/bad.toml");
    let err = match Scene::from_str(text, file) {
        Ok(_) => panic!("accepted a scene that should fail at {field}:\n{text}"),
        Err(e) => e,
    };
    let s = err.to_string();
    let line = line_of(text, needle);
    let prefix = format!("{}:{line}:", file.display());
    assert!(
        s.starts_with(&prefix),
        "expected prefix `{prefix}` in `{s}`"
    );
    assert!(
        s.contains(&format!(": {field}: ")),
        "expected field `{field}` in `{s}`"
    );
    assert!(s.contains(message), "expected `{message}` in `{s}`");
    assert_eq!(err.field(), Some(field));
    assert_eq!(err.line(), Some(line));
    s
}

fn manifest(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

// ---------------------------------------------------------------- canonical scenes

#[test]
fn every_canonical_scene_loads() {
    let names = [
        "still_life",
        "light_shaft",
        "ball_lens",
        "ring",
        "gemstone",
        "volume_cone",
        "smoke",
        "mesh_glass",
        "diffuse_room",
        "water_pool",
        "pool_tiles",
        "ocean_large",
    ];
    for name in names {
        let path = manifest(&format!("assets/scenes/{name}.toml"));
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            !scene.lights.is_empty() && !scene.objects.is_empty(),
            "{name}"
        );
        let tris = scene.triangles(0.0);
        assert!(!tris.is_empty(), "{name}");
        for t in &tris {
            assert!(
                t.positions.iter().chain(&t.normals).all(|v| v.is_finite()),
                "{name}"
            );
            assert!((t.material as usize) < scene.materials.len(), "{name}");
            // Counter-clockwise about the shading normals.
            let n = (t.positions[1] - t.positions[0]).cross(t.positions[2] - t.positions[0]);
            let avg = t.normals[0] + t.normals[1] + t.normals[2];
            assert!(
                n.dot(avg) > 0.0,
                "{name}: triangle winds against its normals: {t:?}"
            );
        }
        let (c, r) = scene.bounding_sphere(0.0);
        assert!(c.is_finite() && r > 0.0, "{name}");
    }
    let found: Vec<String> = std::fs::read_dir(manifest("assets/scenes"))
        .expect("assets/scenes")
        .filter_map(|e| e.ok()?.path().file_stem()?.to_str().map(str::to_owned))
        .collect();
    for name in names {
        assert!(found.iter().any(|f| f == name), "{name} missing");
    }
}

/// The default scene is a showcase: tinted glass (absorption) on coloured
/// surfaces under a spot light, at an exposure of its own.
#[test]
fn default_scene_is_the_still_life_showcase() {
    assert_eq!(DEFAULT_SCENE, "assets/scenes/still_life.toml");
    let scene = Scene::load(&manifest(DEFAULT_SCENE)).expect("default scene");
    let tinted = scene
        .materials
        .iter()
        .filter(|m| m.kind == MaterialKind::Dielectric && m.absorption.max_element() > 0.0)
        .count();
    assert_eq!(tinted, 2, "two tinted glasses");
    let coloured = scene
        .materials
        .iter()
        .filter(|m| {
            m.kind == MaterialKind::Diffuse && m.color.max_element() > 1.4 * m.color.min_element()
        })
        .count();
    assert_eq!(coloured, 2, "a coloured floor and wall");
    assert_eq!(scene.lights[0].kind, LightKind::Spot);
    assert_ne!(scene.output.exposure, 1.0);
}

#[test]
fn ball_lens_contents() {
    let scene = Scene::load(&manifest("assets/scenes/ball_lens.toml")).expect("ball_lens");
    let glass = scene.material_index("glass").expect("glass") as usize;
    assert_eq!(scene.materials[glass].kind, MaterialKind::Dielectric);
    assert_eq!(scene.materials[glass].ior, 1.5);
    assert_eq!(scene.lights[0].kind, LightKind::Point);
    assert!((scene.lights[0].position.y - 8.0).abs() < 0.5);
    let (lo, hi) = scene.bounds(0.0);
    assert!((lo - Vec3::new(-5.0, 0.0, -5.0)).length() < 1e-4, "{lo}");
    assert!((hi - Vec3::new(5.0, 2.6, 5.0)).length() < 1e-4, "{hi}");
}

#[test]
fn canonical_scene_contents() {
    let ring = Scene::load(&manifest("assets/scenes/ring.toml")).expect("ring");
    let r = &ring.objects[0].mesh;
    // Open cylinder: every vertex on the side at radius 1, no cap centres.
    assert!(r
        .positions
        .iter()
        .all(|p| (Vec3::new(p.x, 0.0, p.z).length() - 1.0).abs() < 1e-4));
    assert_eq!(
        ring.materials[r.materials[0] as usize].kind,
        MaterialKind::Mirror
    );

    let glass = Scene::load(&manifest("assets/scenes/mesh_glass.toml")).expect("mesh_glass");
    let m = glass
        .material_index("glass.obj:glass")
        .expect("MTL material") as usize;
    assert_eq!(glass.materials[m].kind, MaterialKind::Dielectric);
    assert_eq!(glass.materials[m].ior, 1.5);

    assert!(
        signed_volume(&glass.objects[0].mesh) > 0.0,
        "goblet winds inward"
    );

    let gem = Scene::load(&manifest("assets/scenes/gemstone.toml")).expect("gemstone");
    assert!(
        signed_volume(&gem.objects[0].mesh) > 0.0,
        "gem winds inward"
    );
    assert!(gem.is_animated());
    assert!(gem.objects[0].mesh.indices.len() >= 24);

    let smoke = Scene::load(&manifest("assets/scenes/smoke.toml")).expect("smoke");
    assert!(matches!(
        smoke.medium.as_ref().map(|m| &m.density),
        Some(Density::Noise { octaves: 4, .. })
    ));
    let cone = Scene::load(&manifest("assets/scenes/volume_cone.toml")).expect("volume_cone");
    assert_eq!(
        cone.medium.as_ref().map(|m| m.density.clone()),
        Some(Density::Constant(1.0))
    );

    for (name, ior_of_water, min_extent) in
        [("water_pool", 1.33, 6.0), ("ocean_large", 1.33, 400.0)]
    {
        let scene = Scene::load(&manifest(&format!("assets/scenes/{name}.toml"))).expect(name);
        let water = scene
            .objects
            .iter()
            .find_map(|o| o.water.as_ref())
            .unwrap_or_else(|| panic!("{name}: no water"));
        let m = &scene.materials[water.material as usize];
        assert_eq!(
            (m.kind, m.ior),
            (MaterialKind::Dielectric, ior_of_water),
            "{name}"
        );
        assert!(water.size.min_element() >= min_extent, "{name}");
        assert!(water.waves.len() >= 3 && scene.is_animated(), "{name}");
        assert_eq!(scene.lights[0].kind, LightKind::Directional, "{name}");
    }

    let room = Scene::load(&manifest("assets/scenes/diffuse_room.toml")).expect("diffuse_room");
    assert!(room
        .materials
        .iter()
        .all(|m| m.kind == MaterialKind::Diffuse));
}

/// Signed volume enclosed by a mesh: positive when closed and wound outward.
fn signed_volume(m: &Mesh) -> f32 {
    m.indices
        .iter()
        .map(|t| {
            let p = t.map(|i| m.positions[i as usize]);
            p[0].dot(p[1].cross(p[2])) / 6.0
        })
        .sum()
}

// ---------------------------------------------------------------- rejections

#[test]
fn missing_scene_file_names_the_path() {
    let path = temp_dir("missing").join("nope.toml");
    let e = Scene::load(&path).expect_err("missing file");
    let s = e.to_string();
    assert!(
        s.contains(&path.display().to_string()) && s.contains("cannot read scene file"),
        "{s}"
    );
}

#[test]
fn syntax_errors_carry_line_and_column() {
    let text = base("[output]\nexposure = = 2\n");
    rejects(&text, "syntax", "exposure = = 2", "");
    let text = base("[[material]]\nname = \"x\"\nname = \"y\"\nkind = \"diffuse\"\n");
    rejects(&text, "syntax", "name = \"y\"", "duplicate key");
}

#[test]
fn unknown_keys_are_rejected() {
    rejects(
        &base("[[object]]\nshape = \"sphere\"\nradius = 1.0\nraduis = 2.0\nmaterial = \"white\"\n"),
        "object[1].raduis",
        "raduis",
        "unknown field",
    );
    rejects(
        &base("[outptu]\nexposure = 1.0\n"),
        "outptu",
        "[outptu]",
        "unknown field",
    );
    rejects(
        &with_camera("eye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 40.0"),
        "camera.fov",
        "fov = 40",
        "unknown field",
    );
    // A field of another light kind.
    rejects(&base("[[light]]\nkind = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = 1.0\ncone_angle = 10.0\n"), "light[1].cone_angle", "cone_angle", "unknown field");
    rejects(&base("[medium]\nsigma_s = 0.1\nbounds = { min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0], mx = 1 }\n"), "medium.bounds.mx", "bounds =", "unknown field");
}

#[test]
fn wrong_types_are_rejected() {
    rejects(
        &base("[[object]]\nshape = \"sphere\"\nradius = \"one\"\nmaterial = \"white\"\n"),
        "object[1].radius",
        "radius = \"one\"",
        "expected a number, got a string",
    );
    rejects(
        &with_camera("eye = [0.0, 2.0]\ntarget = [0.0, 0.0, 0.0]"),
        "camera.eye",
        "eye = [0.0, 2.0]",
        "3 numbers",
    );
    rejects(
        &with_camera("eye = [0.0, true, 5.0]\ntarget = [0.0, 0.0, 0.0]"),
        "camera.eye[1]",
        "eye = [0.0, true",
        "boolean",
    );
    rejects(
        &base(
            "[[object]]\nshape = \"sphere\"\nradius = 1.0\nsegments = 12.5\nmaterial = \"white\"\n",
        ),
        "object[1].segments",
        "segments",
        "integer",
    );
    rejects(
        &base("[camera2]\n"),
        "camera2",
        "[camera2]",
        "unknown field",
    );
    let text = format!("{CAMERA}\n[light]\nkind = \"point\"\n\n{MATERIAL}\n{OBJECT}");
    rejects(&text, "light", "[light]", "array of tables");
}

#[test]
fn missing_required_fields_are_rejected() {
    rejects(
        &base("[[object]] # two\nshape = \"sphere\"\nmaterial = \"white\"\n"),
        "object[1].radius",
        "# two",
        "missing required field",
    );
    rejects(
        &with_camera("eye = [0.0, 2.0, 5.0]"),
        "camera.target",
        "[camera]",
        "missing required field",
    );
    let no_camera = format!("{LIGHT}\n{MATERIAL}\n{OBJECT}");
    rejects(
        &no_camera,
        "camera",
        "[[light]]",
        "missing required table [camera]",
    );
    let no_light = format!("{CAMERA}\n{MATERIAL}\n{OBJECT}");
    rejects(&no_light, "light", "[camera]", "at least one [[light]]");
    let no_object = format!("{CAMERA}\n{LIGHT}\n{MATERIAL}");
    rejects(&no_object, "object", "[camera]", "at least one [[object]]");
    rejects(
        &base("[[object]] # nomat\nshape = \"sphere\"\nradius = 1.0\n"),
        "object[1].material",
        "# nomat",
        "missing required field",
    );
}

#[test]
fn missing_required_field_points_at_its_table() {
    // The object table's header is the located line.
    let text =
        base("[[object]] # second\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmaterial = \"white\"\n");
    rejects(&text, "object[1].max", "# second", "missing required field");
}

#[test]
fn material_references_and_names() {
    rejects(
        &base("[[object]]\nshape = \"sphere\"\nradius = 1.0\nmaterial = \"gold\"\n"),
        "object[1].material",
        "\"gold\"",
        "unknown material `gold`; defined: white",
    );
    rejects(
        &base("[[material]]\nname = \"white\" # again\nkind = \"mirror\"\n"),
        "material[1].name",
        "# again",
        "duplicate material name `white`",
    );
    rejects(
        &base("[[material]]\nname = \"x\"\nkind = \"metal\"\n"),
        "material[1].kind",
        "\"metal\"",
        "unknown material kind",
    );
}

#[test]
fn non_finite_numbers_are_rejected() {
    rejects(
        &base("[[object]]\nshape = \"sphere\"\nradius = nan\nmaterial = \"white\"\n"),
        "object[1].radius",
        "nan",
        "finite",
    );
    rejects(&base("[[object]]\nshape = \"sphere\"\ncenter = [0.0, inf, 0.0]\nradius = 1.0\nmaterial = \"white\"\n"), "object[1].center[1]", "inf", "finite");
    rejects(
        &base("[output]\nexposure = -inf\n"),
        "output.exposure",
        "-inf",
        "finite",
    );
    rejects(
        &base("[output]\nexposure = 1e300\n"),
        "output.exposure",
        "1e300",
        "finite",
    );
}

#[test]
fn sizes_must_be_positive() {
    let s = rejects(
        &base("[[object]]\nshape = \"sphere\"\nradius = -1\nmaterial = \"white\"\n"),
        "object[1].radius",
        "radius = -1",
        "must be positive, got -1",
    );
    assert!(
        s.contains("bad.toml:") && s.contains(":10: object[1].radius"),
        "column of the value: {s}"
    );
    rejects(
        &base("[[object]]\nshape = \"sphere\"\nradius = 0\nmaterial = \"white\"\n"),
        "object[1].radius",
        "radius = 0",
        "must be positive",
    );
    rejects(
        &base("[[object]]\nshape = \"plane\"\nsize = [1.0, 0.0]\nmaterial = \"white\"\n"),
        "object[1].size[1]",
        "size =",
        "must be positive",
    );
    rejects(&base("[[object]]\nshape = \"cylinder\"\np0 = [0.0, 0.0, 0.0]\np1 = [0.0, 1.0, 0.0]\nradius = -0.5\nmaterial = \"white\"\n"), "object[1].radius", "radius = -0.5", "must be positive");
    rejects(
        &base("[[object]]\nshape = \"torus\"\nradii = [1.0, 2.0]\nmaterial = \"white\"\n"),
        "object[1].radii",
        "radii",
        "minor radius",
    );
    rejects(&base("[[object]]\nshape = \"sphere\"\nradius = 1.0\nscale = [1.0, 0.0, 1.0]\nmaterial = \"white\"\n"), "object[1].scale", "scale", "zero");
    rejects(
        &base("[[object]]\nshape = \"sphere\"\nradius = 1.0\nsegments = 2\nmaterial = \"white\"\n"),
        "object[1].segments",
        "segments",
        "within",
    );
}

#[test]
fn degenerate_boxes_and_cylinders_are_rejected() {
    rejects(&base("[[object]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 0.0, 1.0]\nmaterial = \"white\"\n"), "object[1].max", "max = [1.0, 0.0", "must exceed min");
    rejects(&base("[[object]]\nshape = \"cylinder\"\np0 = [0.0, 1.0, 0.0]\np1 = [0.0, 1.0, 0.0]\nradius = 1.0\nmaterial = \"white\"\n"), "object[1].p1", "p1 =", "must differ from p0");
    rejects(
        &base(
            "[medium]\nsigma_s = 0.1\nbounds = { min = [0.0, 0.0, 0.0], max = [1.0, -1.0, 1.0] }\n",
        ),
        "medium.bounds.max",
        "bounds =",
        "must exceed min",
    );
}

#[test]
fn material_values_are_checked() {
    // A medium inside a dielectric (docs/SCENES.md).
    let water = |medium: &str, extra: &str| {
        base(&format!(
            "[[material]]\nname = \"w\"\nkind = \"dielectric\"\nior = 1.33\n{extra}medium = {medium}\n"
        ))
    };
    let scene = Scene::from_str(
        &water(
            "{ sigma_s = [0.1, 0.2, 0.3], sigma_a = 0.5, g = 0.8, density = 2.0 }",
            "",
        ),
        Path::new("scenes/ok.toml"),
    )
    .unwrap();
    let w = &scene.materials[1];
    assert!(w.holds_medium());
    assert_eq!(w.extinction(), glam::Vec3::new(1.2, 1.4, 1.6));
    assert_eq!(w.scattering.unwrap().g, 0.8);
    rejects(
        &water("{ sigma_s = 0.1 }", "absorption = 0.2\n"),
        "material[1].absorption",
        "absorption = 0.2",
        "medium.sigma_a",
    );
    rejects(
        &water("{ sigma_s = 0.1, density = { noise = { scale = 1 } } }", ""),
        "material[1].medium.density",
        "medium =",
        "constant density",
    );
    rejects(
        &water("{ sigma_s = 0.1, g = 1.0 }", ""),
        "material[1].medium.g",
        "medium =",
        "(-1, 1)",
    );
    rejects(
        &water("{ g = 0.5 }", ""),
        "material[1].medium.sigma_s",
        "medium =",
        "missing required field",
    );
    rejects(
        &base("[[material]]\nname = \"d\"\nkind = \"diffuse\"\nmedium = { sigma_s = 0.1 }\n"),
        "material[1].medium",
        "medium =",
        "unknown field",
    );
    rejects(
        &base("[[material]]\nname = \"g\"\nkind = \"dielectric\"\nior = 0.9\n"),
        "material[1].ior",
        "ior = 0.9",
        "at least 1",
    );
    rejects(
        &base("[[material]]\nname = \"d\"\nkind = \"diffuse\"\nalbedo = [0.5, 1.2, 0.5]\n"),
        "material[1].albedo",
        "albedo = [0.5, 1.2",
        "within [0, 1]",
    );
    rejects(
        &base("[[material]]\nname = \"m\"\nkind = \"mirror\"\nreflectance = -0.1\n"),
        "material[1].reflectance",
        "reflectance",
        "negative",
    );
    rejects(
        &base("[[material]]\nname = \"g\"\nkind = \"dielectric\"\nabsorption = [0.0, -1.0, 0.0]\n"),
        "material[1].absorption",
        "absorption",
        "negative",
    );
}

#[test]
fn medium_values_are_checked() {
    let bounds = "bounds = { min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }\n";
    rejects(
        &base(&format!("[medium]\nsigma_s = [0.1, -0.1, 0.1]\n{bounds}")),
        "medium.sigma_s",
        "sigma_s",
        "negative",
    );
    rejects(
        &base(&format!("[medium]\nsigma_s = 0.1\nsigma_a = -1\n{bounds}")),
        "medium.sigma_a",
        "sigma_a",
        "negative",
    );
    rejects(
        &base(&format!("[medium]\nsigma_s = 0.1\ng = 1.0\n{bounds}")),
        "medium.g",
        "g = 1.0",
        "(-1, 1)",
    );
    rejects(
        &base(&format!("[medium]\nsigma_s = 0.1\ng = -1.5\n{bounds}")),
        "medium.g",
        "g = -1.5",
        "(-1, 1)",
    );
    rejects(
        &base(&format!(
            "[medium]\nsigma_s = 0.1\n{bounds}density = {{ noise = {{ scale = 1 }} }}\nmultiple_scattering = true\n"
        )),
        "medium.multiple_scattering",
        "multiple_scattering = true",
        "constant density",
    );
    rejects(
        &base(&format!(
            "[medium]\nsigma_s = 0.1\n{bounds}multiple_scattering = 1\n"
        )),
        "medium.multiple_scattering",
        "multiple_scattering = 1",
        "",
    );
    rejects(
        &base("[medium]\nsigma_s = 0.1\n"),
        "medium.bounds",
        "[medium]",
        "missing required field",
    );
    rejects(
        &base(&format!(
            "[medium]\nsigma_s = 0.1\n{bounds}density = -2.0\n"
        )),
        "medium.density",
        "density",
        "negative",
    );
    rejects(
        &base(&format!(
            "[medium]\nsigma_s = 0.1\n{bounds}density = {{ noise = {{ octaves = 0 }} }}\n"
        )),
        "medium.density.noise.octaves",
        "density",
        "[1, 16]",
    );
    rejects(
        &base(&format!(
            "[medium]\nsigma_s = 0.1\n{bounds}density = {{ fog = 1 }}\n"
        )),
        "medium.density.fog",
        "density",
        "unknown field",
    );
}

#[test]
fn zero_directions_are_rejected() {
    rejects(
        &base("[[light]]\nkind = \"directional\"\ndirection = [0.0, 0.0, 0.0]\nirradiance = 1.0\n"),
        "light[1].direction",
        "direction = [0.0, 0.0, 0.0]",
        "non-zero",
    );
    rejects(&base("[[object]]\nshape = \"plane\"\nnormal = [0, 0, 0]\nsize = [1.0, 1.0]\nmaterial = \"white\"\n"), "object[1].normal", "normal", "non-zero");
    rejects(&base("[[object]]\nshape = \"torus\"\naxis = [0.0, 0.0, 0.0]\nradii = [1.0, 0.2]\nmaterial = \"white\"\n"), "object[1].axis", "axis", "non-zero");
    rejects(&base("[[object]]\nshape = \"plane\"\nnormal = [0, 1, 0]\ntangent = [0, 2, 0]\nsize = [1.0, 1.0]\nmaterial = \"white\"\n"), "object[1].tangent", "tangent", "parallel");
    rejects(&base("[[object]]\nshape = \"sphere\"\nradius = 1.0\nmaterial = \"white\"\nanimate = { spin = 1.0, spin_axis = [0.0, 0.0, 0.0] }\n"), "object[1].animate.spin_axis", "animate", "non-zero");
}

#[test]
fn camera_is_validated() {
    rejects(
        &with_camera("eye = [1.0, 1.0, 1.0]\ntarget = [1.0, 1.0, 1.0]"),
        "camera.target",
        "target",
        "must differ",
    );
    rejects(
        &with_camera("eye = [0.0, 5.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]"),
        "camera.up",
        "up =",
        "parallel",
    );
    rejects(
        &with_camera("eye = [0.0, 5.0, 1.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 180.0"),
        "camera.fov_y",
        "fov_y",
        "(0, 180)",
    );
    rejects(
        &with_camera("eye = [0.0, 5.0, 1.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 0"),
        "camera.fov_y",
        "fov_y",
        "(0, 180)",
    );
}

#[test]
fn lights_are_validated() {
    let spot = |angle: &str, falloff: &str| {
        base(&format!("[[light]]\nkind = \"spot\"\nposition = [0.0, 4.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\nintensity = 5.0\ncone_angle = {angle}\ncone_falloff = {falloff}\n"))
    };
    rejects(
        &spot("20.0", "25.0"),
        "light[1].cone_falloff",
        "cone_falloff",
        "must not exceed cone_angle",
    );
    rejects(
        &spot("0.0", "0.0"),
        "light[1].cone_angle",
        "cone_angle",
        "(0, 90]",
    );
    rejects(
        &base("[[light]]\nkind = \"area\"\n"),
        "light[1].kind",
        "\"area\"",
        "unknown light kind",
    );
    rejects(&base("[[light]]\nkind = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [1.0, -1.0, 1.0]\n"), "light[1].intensity", "[1.0, -1.0", "negative");
    let ok = Scene::from_str(&spot("20.0", "5.0"), Path::new("ok.toml")).expect("valid spot");
    let l = ok.lights[1];
    assert_eq!(
        (l.kind, l.cone_angle_deg, l.cone_falloff_deg),
        (LightKind::Spot, 20.0, 5.0)
    );
    assert_eq!(l.direction, Vec3::NEG_Y);
}

#[test]
fn at_most_eight_lights() {
    let max = caustics::shader_bindings::MAX_LIGHTS as usize;
    let lights: String = (0..max)
        .map(|i| LIGHT.replace("5.0, 0.0]", &format!("5.0, {i}.0]")))
        .collect::<Vec<_>>()
        .join("\n");
    let ok = format!("{CAMERA}\n{lights}\n{MATERIAL}\n{OBJECT}");
    assert_eq!(
        Scene::from_str(&ok, Path::new("ok.toml"))
            .expect("8 lights")
            .lights
            .len(),
        max
    );
    let too_many = format!("{CAMERA}\n{lights}\n[[light]] # ninth\nkind = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = 1.0\n\n{MATERIAL}\n{OBJECT}");
    rejects(
        &too_many,
        &format!("light[{max}]"),
        "# ninth",
        "too many lights",
    );
}

const WATER: &str = "[[object]]\nshape = \"water\"\nmaterial = \"white\"\ncenter = [1.0, 2.0]\nsize = [4.0, 3.0]\nresolution = [8, 6]\nbase_height = 0.25\n";

/// A scene with a water object whose table ends with `extra` (its waves, or a bad field).
fn with_water(extra: &str) -> String {
    base(&format!("{WATER}{extra}"))
}

#[test]
fn water_loads_with_waves_and_defaults() {
    let text = with_water(
        "[[object.wave]]\namplitude = 0.1\nwavelength = 2.0\ndirection = 30\nsteepness = 0.5\nspeed = 1.5\nphase = 0.2\n[[object.wave]]\namplitude = 0.05\nwavelength = 1.0\n",
    );
    let scene = Scene::from_str(&text, Path::new("water.toml")).expect("water scene");
    let o = &scene.objects[1];
    let w = o.water.as_ref().expect("a water surface");
    assert_eq!(w.center, glam::Vec2::new(1.0, 2.0));
    assert_eq!(w.size, glam::Vec2::new(4.0, 3.0));
    assert_eq!(w.resolution, [8, 6]);
    assert_eq!(w.base_height, 0.25);
    assert_eq!(w.waves.len(), 2);
    assert_eq!(
        w.waves[0],
        Wave {
            amplitude: 0.1,
            wavelength: 2.0,
            direction_deg: 30.0,
            steepness: 0.5,
            speed: 1.5,
            phase: 0.2
        }
    );
    // Defaults: direction 0, steepness 0, phase 0, deep-water speed sqrt(g λ / 2π).
    let d = w.waves[1];
    assert_eq!((d.direction_deg, d.steepness, d.phase), (0.0, 0.0, 0.0));
    assert!((d.speed - (9.81f32 / std::f32::consts::TAU).sqrt()).abs() < 1e-6);
    assert_eq!(o.mesh.indices.len(), 2 * 8 * 6);
    assert_eq!(
        scene.triangle_count(),
        2 * 8 * 6 + scene.objects[0].mesh.indices.len()
    );
    // Animated: the triangles move with time, their count does not.
    assert!(scene.is_animated());
    let (a, b) = (scene.triangles(0.0), scene.triangles(0.8));
    assert_eq!(a.len(), b.len());
    assert_ne!(a.last().unwrap().positions, b.last().unwrap().positions);
    // Heights stay within base_height ± the summed amplitudes.
    for p in &o.mesh_at(0.8).positions {
        assert!((p.y - 0.25).abs() <= 0.15 + 1e-5, "{p}");
    }
    // The bounds follow the moving surface (its far x edge, about 3 m).
    let (_, hi) = scene.bounds(0.8);
    assert!(hi.x > 2.9, "{hi}");

    // Inline array of tables, no waves at all, and waves without speed are still water.
    let inline = with_water(
        "wave = [{ amplitude = 0.1, wavelength = 2.0 }, { amplitude = 0.0, wavelength = 1.0 }]\n",
    );
    let scene = Scene::from_str(&inline, Path::new("water.toml")).expect("inline waves");
    assert_eq!(scene.objects[1].water.as_ref().unwrap().waves.len(), 2);
    let calm = Scene::from_str(&with_water(""), Path::new("water.toml")).expect("flat water");
    assert!(!calm.is_animated());
    assert!(calm.objects[1].mesh.positions.iter().all(|p| p.y == 0.25));
    let frozen = with_water("[[object.wave]]\namplitude = 0.1\nwavelength = 2.0\nspeed = 0\n");
    assert!(!Scene::from_str(&frozen, Path::new("water.toml"))
        .unwrap()
        .is_animated());
}

#[test]
fn water_values_are_checked() {
    let wave = "[[object.wave]]\n";
    for (extra, field, needle, message) in [
        (
            "size = [0.0, 1.0]\n",
            "object[1].size[0]",
            "size = [0.0",
            "must be positive",
        ),
        (
            "size = [2.0, -1.0]\n",
            "object[1].size[1]",
            "size = [2.0",
            "must be positive",
        ),
        (
            "resolution = [0, 4]\n",
            "object[1].resolution[0]",
            "resolution = [0",
            "within [1, 4096], got 0",
        ),
        (
            "resolution = [4, 5000]\n",
            "object[1].resolution[1]",
            "resolution = [4, 5000",
            "within [1, 4096], got 5000",
        ),
        (
            "resolution = [4096, 4096]\n",
            "object[1].resolution",
            "resolution = [4096",
            "cells, at most 2097152",
        ),
        (
            "resolution = [4.5, 4]\n",
            "object[1].resolution[0]",
            "resolution = [4.5",
            "got 4.5",
        ),
        (
            "resolution = 8\n",
            "object[1].resolution",
            "resolution = 8",
            "array of 2 integers",
        ),
        (
            "center = [1.0, nan]\n",
            "object[1].center[1]",
            "center = [1.0, nan",
            "finite",
        ),
        (
            "base_height = inf\n",
            "object[1].base_height",
            "base_height = inf",
            "finite",
        ),
        (
            "translate = [0.0, 1.0, 0.0]\n",
            "object[1].translate",
            "translate",
            "unknown field `translate` in a water object",
        ),
        (
            "animate = { spin = 1.0 }\n",
            "object[1].animate",
            "animate",
            "unknown field `animate`",
        ),
        (
            "waves = []\n",
            "object[1].waves",
            "waves",
            "unknown field `waves`",
        ),
    ] {
        // A later key of the same table overrides nothing in TOML: rebuild the table.
        let text = base(&format!(
            "[[object]]\nshape = \"water\"\nmaterial = \"white\"\n{}{extra}",
            [
                "center = [1.0, 2.0]\n",
                "size = [4.0, 3.0]\n",
                "resolution = [8, 6]\n"
            ]
            .iter()
            .filter(|l| !extra.starts_with(&l[..l.find(' ').unwrap()]))
            .copied()
            .collect::<String>()
        ));
        rejects(&text, field, needle, message);
    }
    rejects(
        &base("[[object]] # water\nshape = \"water\"\nmaterial = \"white\"\nsize = [1.0, 1.0]\n"),
        "object[1].resolution",
        "# water",
        "missing required field",
    );
    for (body, field, needle, message) in [
        (
            "amplitude = -0.1\nwavelength = 1.0\n",
            "object[1].wave[0].amplitude",
            "amplitude = -0.1",
            "must not be negative",
        ),
        (
            "amplitude = 0.1\nwavelength = 0.0\n",
            "object[1].wave[0].wavelength",
            "wavelength = 0.0",
            "must be positive",
        ),
        (
            "amplitude = 0.1\nwavelength = -2.0\n",
            "object[1].wave[0].wavelength",
            "wavelength = -2.0",
            "must be positive",
        ),
        (
            "amplitude = 0.1\n",
            "object[1].wave[0].wavelength",
            "[[object.wave]]",
            "missing required field",
        ),
        (
            "amplitude = 0.1\nwavelength = 1.0\nsteepness = 1.5\n",
            "object[1].wave[0].steepness",
            "steepness = 1.5",
            "within [0, 1], got 1.5",
        ),
        (
            "amplitude = 0.1\nwavelength = 1.0\nsteepness = -0.1\n",
            "object[1].wave[0].steepness",
            "steepness = -0.1",
            "within [0, 1]",
        ),
        (
            "amplitude = 0.1\nwavelength = 1.0\nspeed = -1\n",
            "object[1].wave[0].speed",
            "speed = -1",
            "must not be negative",
        ),
        (
            "amplitude = 0.1\nwavelength = 1.0\nphase = nan\n",
            "object[1].wave[0].phase",
            "phase = nan",
            "finite",
        ),
        (
            "amplitude = 0.1\nwavelength = 1.0\ndirection = \"north\"\n",
            "object[1].wave[0].direction",
            "direction = \"north\"",
            "expected a number",
        ),
        (
            "amplitude = 0.1\nwavelength = 1.0\nheight = 2\n",
            "object[1].wave[0].height",
            "height = 2",
            "unknown field `height` in a wave",
        ),
    ] {
        rejects(
            &with_water(&format!("{wave}{body}")),
            field,
            needle,
            message,
        );
    }
    // Steep, high, short waves fold over: Σ Q k A = 1 · 2π · 0.4 / 2 > 1.
    rejects(
        &with_water("[[object.wave]]\namplitude = 0.4\nwavelength = 2.0\nsteepness = 1.0\n"),
        "object[1].wave",
        "[[object.wave]]",
        "fold over themselves",
    );
    let many = (0..17)
        .map(|i| format!("[[object.wave]] # wave {i}\namplitude = 0.001\nwavelength = 1.0\n"))
        .collect::<String>();
    rejects(
        &with_water(&many),
        "object[1].wave[16]",
        "# wave 16",
        "too many waves: 17, at most 16",
    );
    rejects(
        &base("[[object]]\nshape = \"cone\"\nmaterial = \"white\"\n"),
        "object[1].shape",
        "\"cone\"",
        "unknown shape `cone`; expected sphere, plane, box, torus, cylinder, mesh, gltf or water",
    );
}

#[test]
fn density_grids_load_and_wrong_sizes_are_rejected() {
    let dir = temp_dir("grid");
    let values: Vec<u8> = (0..2 * 3 * 4)
        .flat_map(|i| (i as f32 * 0.5).to_le_bytes())
        .collect();
    write(&dir.join("vol/d.raw"), &values);
    let scene = |dims: &str| {
        base(&format!("[medium]\nsigma_s = 0.1\nbounds = {{ min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }}\ndensity = {{ grid = \"vol/d.raw\", dims = {dims} }}\n"))
    };
    let path = dir.join("s.toml");
    write(&path, scene("[2, 3, 4]"));
    let s = Scene::load(&path).expect("grid scene");
    let m = s.medium.expect("medium");
    assert_eq!(m.max_density(), 11.5);
    assert!(matches!(&m.density, Density::Grid { dims: [2, 3, 4], values } if values[3] == 1.5));

    let text = scene("[2, 3, 5]");
    write(&path, &text);
    let e = Scene::load(&path).expect_err("wrong size").to_string();
    let line = line_of(&text, "density =");
    assert!(e.starts_with(&format!("{}:{line}:", path.display())), "{e}");
    assert!(
        e.contains("medium.density.grid") && e.contains("96 bytes") && e.contains("need 120"),
        "{e}"
    );

    let text = scene("[2, 3, 4]").replace("vol/d.raw", "vol/missing.raw");
    write(&path, &text);
    let e = Scene::load(&path).expect_err("missing grid").to_string();
    assert!(
        e.contains("medium.density.grid") && e.contains("missing.raw"),
        "{e}"
    );
}

// ---------------------------------------------------------------- OBJ meshes

/// Writes `obj` (and `files`) next to a scene whose only extra object is the mesh
/// with `object_fields`; returns the scene path.
fn mesh_scene(name: &str, obj: &str, object_fields: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = temp_dir(name);
    write(&dir.join("m.obj"), obj);
    for (f, text) in files {
        write(&dir.join(f), text);
    }
    let path = dir.join("scene.toml");
    write(
        &path,
        base(&format!(
            "[[object]]\nshape = \"mesh\"\npath = \"m.obj\"\n{object_fields}\n"
        )),
    );
    path
}

fn mesh_of(scene: &Scene) -> &Mesh {
    &scene.objects[1].mesh
}

#[test]
fn obj_without_normals_gets_smooth_area_weighted_normals() {
    // A tent: two triangles of different areas sharing the edge 1-2.
    let obj = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nv 3 3 -3\nf 1 2 3\nf 2 4 3\n";
    let s = Scene::load(&mesh_scene("nonormals", obj, "material = \"white\"", &[])).expect("loads");
    let m = mesh_of(&s);
    assert_eq!(m.indices.len(), 2);
    let p = &m.positions;
    let face = |t: [u32; 3]| {
        (p[t[1] as usize] - p[t[0] as usize]).cross(p[t[2] as usize] - p[t[0] as usize])
    };
    let (a, b) = (face(m.indices[0]), face(m.indices[1]));
    // Vertex 0 belongs to the first face only; the shared vertices average by area.
    let shared = m.indices[0][1] as usize;
    assert!((m.normals[m.indices[0][0] as usize] - a.normalize()).length() < 1e-5);
    assert!((m.normals[shared] - (a + b).normalize()).length() < 1e-5);
    assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
}

#[test]
fn obj_normals_are_used_when_present() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nvn 0 0.6 0.8\nf 1//1 2//1 3//2\n";
    let s = Scene::load(&mesh_scene("normals", obj, "material = \"white\"", &[])).expect("loads");
    let m = mesh_of(&s);
    let n: Vec<Vec3> = m.indices[0]
        .iter()
        .map(|&i| m.normals[i as usize])
        .collect();
    assert_eq!(n[0], Vec3::Z);
    assert!((n[2] - Vec3::new(0.0, 0.6, 0.8)).length() < 1e-6);
}

#[test]
fn obj_quads_ngons_and_negative_indices() {
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n\
               v 0 0 1\nv 1 0 1\nv 1.5 0.5 1\nv 1 1 1\nv 0 1 1\nf -5 -4 -3 -2 -1\n\
               v 0 0 2\nv 1 0 2\nv 0 1 2\nf -3 -2 -1\n";
    let s = Scene::load(&mesh_scene("ngons", obj, "material = \"white\"", &[])).expect("loads");
    let m = mesh_of(&s);
    assert_eq!(m.indices.len(), 2 + 3 + 1);
    // Everything faces +z and lies where the file put it.
    for t in &m.indices {
        let p = t.map(|i| m.positions[i as usize]);
        assert!((p[1] - p[0]).cross(p[2] - p[0]).z > 0.0);
    }
    let last = m.indices[5].map(|i| m.positions[i as usize]);
    assert_eq!(
        last,
        [
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(1.0, 0.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0)
        ]
    );
}

#[test]
fn obj_open_surface_loads() {
    // A box without its top: unclosed, loads as-is.
    let obj = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\n\
               f 1 2 3 4\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n";
    let s = Scene::load(&mesh_scene("open", obj, "material = \"white\"", &[])).expect("loads");
    assert_eq!(mesh_of(&s).indices.len(), 10);
}

#[test]
fn obj_without_mtl_needs_a_material() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let path = mesh_scene("nomtl", obj, "", &[]);
    let e = Scene::load(&path).expect_err("no material").to_string();
    assert!(
        e.contains("object[1].material") && e.contains("m.obj"),
        "{e}"
    );
    let path = mesh_scene("nomtl-ok", obj, "material = \"white\"", &[]);
    let s = Scene::load(&path).expect("material applies");
    assert_eq!(
        mesh_of(&s).materials,
        vec![s.material_index("white").expect("white")]
    );
}

const MTL: &str = "newmtl clear\nNi 1.45\nd 0.2\nillum 2\n\
                   newmtl chrome\nKs 0.9 0.8 0.7\nillum 3\n\
                   newmtl paint\nKd 0.2 0.3 0.4\nillum 2\n\
                   newmtl crystal\nNi 1.7\nillum 7\n";
const MTL_OBJ: &str = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
                       usemtl clear\nf 1 2 3\nusemtl chrome\nf 2 4 3\nusemtl paint\nf 1 3 4\nusemtl crystal\nf 1 4 2\n";

#[test]
fn mtl_materials_become_scene_materials() {
    let s = Scene::load(&mesh_scene("mtl", MTL_OBJ, "", &[("m.mtl", MTL)])).expect("loads");
    let m = mesh_of(&s);
    let mat = |i: usize| &s.materials[m.materials[i] as usize];
    assert_eq!(
        (mat(0).name.as_str(), mat(0).kind, mat(0).ior),
        ("m.obj:clear", MaterialKind::Dielectric, 1.45)
    );
    assert_eq!(
        (mat(1).name.as_str(), mat(1).kind),
        ("m.obj:chrome", MaterialKind::Mirror)
    );
    assert_eq!(mat(1).color, Vec3::new(0.9, 0.8, 0.7));
    assert_eq!(
        (mat(2).kind, mat(2).color),
        (MaterialKind::Diffuse, Vec3::new(0.2, 0.3, 0.4))
    );
    assert_eq!((mat(3).kind, mat(3).ior), (MaterialKind::Dielectric, 1.7));
    // The object's material overrides the MTL.
    let s = Scene::load(&mesh_scene(
        "mtl-override",
        MTL_OBJ,
        "material = \"white\"",
        &[("m.mtl", MTL)],
    ))
    .expect("loads");
    assert!(mesh_of(&s)
        .materials
        .iter()
        .all(|&i| s.materials[i as usize].name == "white"));
    assert_eq!(s.materials.len(), 1);
}

#[test]
fn same_obj_twice_shares_its_materials() {
    let dir = temp_dir("twice");
    write(&dir.join("m.obj"), MTL_OBJ);
    write(&dir.join("m.mtl"), MTL);
    let path = dir.join("s.toml");
    write(&path, base("[[object]]\nshape = \"mesh\"\npath = \"m.obj\"\n\n[[object]]\nshape = \"mesh\"\npath = \"m.obj\"\ntranslate = [2.0, 0.0, 0.0]\n"));
    let s = Scene::load(&path).expect("loads");
    assert_eq!(s.materials.len(), 1 + 4);
    assert_eq!(s.objects[1].mesh.materials, s.objects[2].mesh.materials);
}

#[test]
fn missing_mtl_is_an_error_unless_material_is_set() {
    let path = mesh_scene("missing-mtl", MTL_OBJ, "", &[]);
    let e = Scene::load(&path).expect_err("missing mtl").to_string();
    assert!(
        e.contains("object[1].path") && e.contains("m.mtl") && e.contains("MTL"),
        "{e}"
    );
    let text = std::fs::read_to_string(&path).expect("scene");
    assert!(
        e.contains(&format!(":{}:", line_of(&text, "path = \"m.obj\""))),
        "{e}"
    );
    let path = mesh_scene("missing-mtl-ok", MTL_OBJ, "material = \"white\"", &[]);
    Scene::load(&path).expect("falls back to the object's material");
}

#[test]
fn missing_broken_and_empty_objs_are_rejected() {
    let dir = temp_dir("broken");
    let path = dir.join("s.toml");
    let text =
        base("[[object]]\nshape = \"mesh\"\npath = \"nowhere/gone.obj\"\nmaterial = \"white\"\n");
    write(&path, &text);
    let e = Scene::load(&path).expect_err("missing obj").to_string();
    let line = line_of(&text, "gone.obj");
    assert!(e.starts_with(&format!("{}:{line}:", path.display())), "{e}");
    assert!(
        e.contains("object[1].path") && e.contains("gone.obj"),
        "{e}"
    );

    for (name, obj, why) in [
        (
            "oob",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
            "out of bounds",
        ),
        ("zero", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "m.obj"),
        ("garbage", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "m.obj"),
        ("badpos", "v 0 zero 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "m.obj"),
        (
            "nanpos",
            "v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "not finite",
        ),
        ("empty", "# nothing here\nv 0 0 0\nv 1 0 0\n", "no faces"),
        ("lines-only", "v 0 0 0\nv 1 0 0\nl 1 2\n", "no faces"),
    ] {
        let e = Scene::load(&mesh_scene(name, obj, "material = \"white\"", &[]))
            .expect_err(name)
            .to_string();
        assert!(
            e.contains("object[1].path") && e.contains("m.obj") && e.contains(why),
            "{name}: {e}"
        );
    }
}

#[test]
fn obj_path_is_relative_to_the_scene_file() {
    let dir = temp_dir("relative");
    write(
        &dir.join("meshes/tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let path = dir.join("scenes/deep/s.toml");
    write(
        &path,
        base(
            "[[object]]\nshape = \"mesh\"\npath = \"../../meshes/tri.obj\"\nmaterial = \"white\"\n",
        ),
    );
    // The mesh is outside the scene's folder tree: allowed by its folder.
    let allowed = AllowedPaths::new(&[dir.join("meshes")]).unwrap();
    let s = Scene::load_allowing(&path, &allowed).expect("relative to the scene file, not the cwd");
    assert_eq!(mesh_of(&s).indices.len(), 1);
}

#[test]
fn large_obj_loads_quickly() {
    // 317 x 317 quads = 200,978 triangles, no normals.
    let n = 317;
    let mut obj = String::with_capacity(12_000_000);
    for j in 0..=n {
        for i in 0..=n {
            obj.push_str(&format!(
                "v {} {} {}\n",
                i as f32 * 0.01,
                ((i * j) % 7) as f32 * 0.001,
                j as f32 * -0.01
            ));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i + 1;
            obj.push_str(&format!("f {} {} {} {}\n", a, a + 1, a + n + 2, a + n + 1));
        }
    }
    let path = mesh_scene("large", &obj, "material = \"white\"", &[]);
    let start = Instant::now();
    let s = Scene::load(&path).expect("large mesh");
    let load = start.elapsed();
    let tris = s.triangles(0.0);
    let total = start.elapsed();
    assert_eq!(mesh_of(&s).indices.len(), 2 * n * n);
    assert!(tris.len() > 200_000);
    eprintln!("200k-triangle OBJ: load {load:?}, load + triangles {total:?}");
    assert!(total.as_secs_f32() < 4.0, "took {total:?}");
}

// ---------------------------------------------------------------- transforms and animation

#[test]
fn translated_sphere_bounds_move() {
    let s = Scene::from_str(
        &with_camera("eye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]").replace(
            "radius = 1.0\n",
            "radius = 1.0\ntranslate = [3.0, -1.0, 2.0]\n",
        ),
        Path::new("t.toml"),
    )
    .expect("loads");
    let (lo, hi) = s.bounds(0.0);
    assert!((lo - Vec3::new(2.0, -2.0, 1.0)).length() < 1e-5, "{lo}");
    assert!((hi - Vec3::new(4.0, 0.0, 3.0)).length() < 1e-5, "{hi}");
    let (c, r) = s.bounding_sphere(0.0);
    assert!((c - Vec3::new(3.0, -1.0, 2.0)).length() < 1e-5);
    assert!((r - 3f32.sqrt()).abs() < 1e-5);
    assert!(!s.is_animated());
}

#[test]
fn rotate_scale_and_mirroring_transforms() {
    let text = base("[[object]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 2.0, 3.0]\nrotate = [90.0, 0.0, 0.0]\nscale = 2\nmaterial = \"white\"\n\n\
                     [[object]]\nshape = \"box\"\nmin = [-1.0, -1.0, -1.0]\nmax = [1.0, 1.0, 1.0]\nscale = [-1.0, 1.0, 1.0]\ntranslate = [10.0, 0.0, 0.0]\nmaterial = \"white\"\n");
    let s = Scene::from_str(&text, Path::new("t.toml")).expect("loads");
    // Scale 2 then +90 degrees about X: y -> z, z -> -y.
    let m = s.object_transform(1, 0.0);
    assert!(
        (m.transform_point3(Vec3::new(1.0, 2.0, 3.0)) - Vec3::new(2.0, -6.0, 4.0)).length() < 1e-5
    );
    let tris = s.triangles(0.0);
    for t in tris.iter().filter(|t| t.object >= 1) {
        let n = (t.positions[1] - t.positions[0]).cross(t.positions[2] - t.positions[0]);
        let centre = if t.object == 1 {
            Vec3::new(1.0, -3.0, 2.0)
        } else {
            Vec3::new(10.0, 0.0, 0.0)
        };
        let centroid = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0;
        assert!(
            n.dot(centroid - centre) > 0.0,
            "object {} winds inward",
            t.object
        );
        for v in t.normals {
            assert!((v.length() - 1.0).abs() < 1e-5 && v.dot(n) > 0.0);
        }
    }
}

#[test]
fn rotations_apply_x_then_y_then_z() {
    let text = base("[[object]]\nshape = \"sphere\"\nradius = 1.0\nrotate = [90.0, 90.0, 0.0]\nmaterial = \"white\"\n");
    let s = Scene::from_str(&text, Path::new("t.toml")).expect("loads");
    // +y --Rx(90)--> +z --Ry(90)--> +x.
    let v = s.object_transform(1, 0.0).transform_vector3(Vec3::Y);
    assert!((v - Vec3::X).length() < 1e-5, "{v}");
}

#[test]
fn animation_moves_objects_with_time() {
    let text = base("[[object]]\nshape = \"sphere\"\nradius = 0.5\ntranslate = [0.0, 1.0, 0.0]\nmaterial = \"white\"\n\
                     animate = { orbit_radius = 2.0, orbit_speed = 90.0, bob_amplitude = 0.5, bob_frequency = 0.25 }\n\n\
                     [[object]]\nshape = \"box\"\nmin = [-1.0, -0.1, -0.1]\nmax = [1.0, 0.1, 0.1]\ntranslate = [5.0, 0.0, 0.0]\nmaterial = \"white\"\n\
                     animate = { spin = 90.0 }\n");
    let s = Scene::from_str(&text, Path::new("t.toml")).expect("loads");
    assert!(s.is_animated());
    // Orbit: +x at t = 0, a quarter turn counter-clockwise (seen from +y) at t = 1 -> -z; bob at its peak at t = 1.
    let origin = |t: f32| s.object_transform(1, t).transform_point3(Vec3::ZERO);
    assert!(
        (origin(0.0) - Vec3::new(2.0, 1.0, 0.0)).length() < 1e-5,
        "{}",
        origin(0.0)
    );
    assert!(
        (origin(1.0) - Vec3::new(0.0, 1.5, -2.0)).length() < 1e-5,
        "{}",
        origin(1.0)
    );
    // Spin about the object's own origin (its translate stays put).
    let spin = |t: f32, p: Vec3| s.object_transform(2, t).transform_point3(p);
    assert!((spin(1.0, Vec3::ZERO) - Vec3::new(5.0, 0.0, 0.0)).length() < 1e-5);
    assert!(
        (spin(1.0, Vec3::X) - Vec3::new(5.0, 0.0, -1.0)).length() < 1e-5,
        "{}",
        spin(1.0, Vec3::X)
    );
    // Triangles and bounds follow.
    let (lo0, _) = s.bounds(0.0);
    let (lo1, _) = s.bounds(1.0);
    assert_ne!(lo0, lo1);
    assert_ne!(s.triangles(0.0), s.triangles(1.0));
    // The static object does not move.
    assert_eq!(s.object_transform(0, 0.0), s.object_transform(0, 3.0));
}

// ------------------------------------------- issue 31: confined paths, limits

/// `dir/outside/`: a valid file of every kind a scene names (a triangle
/// OBJ, an MTL, an 8-bit PNG, the canonical sky, a 2³ density grid, a glTF
/// with its buffer beside it), and `dir/scene/` for scenes naming them.
fn outside_files(dir: &Path) -> PathBuf {
    let outside = dir.join("outside");
    write(
        &outside.join("tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    write(&outside.join("x.mtl"), "newmtl m\nKd 0.5 0.5 0.5\n");
    caustics::output::write_png(&outside.join("t.png"), 2, 2, &[128; 16]).unwrap();
    std::fs::copy(
        manifest("assets/scenes/environments/sky.hdr"),
        outside.join("sky.hdr"),
    )
    .unwrap();
    write(&outside.join("g.raw"), [0u8; 8 * 4]);
    let positions: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    write(&outside.join("m.bin"), &positions);
    write(
        &outside.join("m.gltf"),
        r#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "m.bin", "byteLength": 36}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}"#,
    );
    std::fs::create_dir_all(dir.join("scene")).unwrap();
    outside
}

/// (field, the scene's lines naming a file outside its tree, the rule's
/// words) for every kind of file a TOML scene names. `outside` is the
/// folder of [`outside_files`], `scene_dir` the scene's.
fn escaping_references(
    outside: &Path,
    scene_dir: &Path,
) -> Vec<(&'static str, String, &'static str)> {
    let mesh = |path: &str| {
        format!("[[object]]\nshape = \"mesh\"\npath = \"{path}\"\nmaterial = \"white\"\n")
    };
    // A link inside the scene's folder to the OBJ outside it.
    let link = scene_dir.join("link.obj");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(outside.join("tri.obj"), &link).unwrap();
    // An OBJ inside whose MTL is outside.
    write(
        &scene_dir.join("inside.obj"),
        "mtllib ../outside/x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
    );
    let absolute = outside.join("tri.obj");
    vec![
        ("object[1].path", mesh("../outside/tri.obj"), "climbs above the folder"),
        ("object[1].path", mesh(absolute.to_str().unwrap()), "an absolute path"),
        ("object[1].path", mesh("link.obj"), "a link that resolves outside"),
        (
            "object[1].path",
            "[[object]]\nshape = \"mesh\"\npath = \"inside.obj\"\n".into(),
            "mtllib `../outside/x.mtl`: it climbs above",
        ),
        (
            "material[1].albedo_texture",
            "[[material]]\nname = \"t\"\nkind = \"diffuse\"\nalbedo_texture = \"../outside/t.png\"\n".into(),
            "climbs above the folder",
        ),
        (
            "light[1].path",
            "[[light]]\nkind = \"environment\"\npath = \"../outside/sky.hdr\"\n".into(),
            "climbs above the folder",
        ),
        (
            "medium.density.grid",
            "[medium]\nsigma_s = 0.1\nbounds = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 1.0] }\n\
             density = { grid = \"../outside/g.raw\", dims = [2, 2, 2] }\n"
                .into(),
            "climbs above the folder",
        ),
        (
            "object[1].path",
            "[[object]]\nshape = \"gltf\"\npath = \"../outside/m.gltf\"\n".into(),
            "climbs above the folder",
        ),
    ]
}

/// Issue 31: a TOML scene read any file its paths named (`../`, absolute
/// paths, links out of its folder, an OBJ's `mtllib`). Each is now refused,
/// naming the scene file, the line, the field and the rule, before the
/// file is read.
#[test]
fn files_outside_the_scene_folder_tree_are_refused() {
    let dir = temp_dir("confined");
    let outside = outside_files(&dir);
    let scene_dir = dir.join("scene");
    for (field, lines, rule) in escaping_references(&outside, &scene_dir) {
        let path = scene_dir.join("s.toml");
        let text = base(&lines);
        write(&path, &text);
        let e = Scene::load(&path)
            .err()
            .unwrap_or_else(|| panic!("accepted a file outside the tree:\n{lines}"))
            .to_string();
        // The line of the value that names the file.
        let key = field.rsplit('.').next().unwrap();
        let at = format!(
            "{}:{}:",
            path.display(),
            line_of(&text, &format!("{key} = "))
        );
        assert!(e.starts_with(&at), "{at} in {e}");
        assert!(e.contains(&format!(": {field}: ")), "{field} in {e}");
        assert!(
            e.contains(rule) && e.contains("scene file's folder") && e.contains("--allow-paths"),
            "{rule} in {e}"
        );
        assert!(!e.contains('\n'), "{e}");
    }
}

/// The same files load when their folder is allowed (`--allow-paths`,
/// `Scene::load_allowing`), and a glTF file's URIs are widened the same way.
#[test]
fn allowed_folders_open_the_same_files() {
    let dir = temp_dir("allowed");
    let outside = outside_files(&dir);
    let scene_dir = dir.join("scene");
    let allowed = AllowedPaths::new(std::slice::from_ref(&outside)).unwrap();
    for (field, lines, _) in escaping_references(&outside, &scene_dir) {
        let path = scene_dir.join("s.toml");
        write(&path, base(&lines));
        if let Err(e) = Scene::load_allowing(&path, &allowed) {
            panic!("{field}: refused with its folder allowed: {e}");
        }
    }
    // A glTF scene whose buffer is in an allowed folder.
    write(
        &scene_dir.join("up.gltf"),
        std::fs::read_to_string(outside.join("m.gltf"))
            .unwrap()
            .replace("\"m.bin\"", "\"../outside/m.bin\""),
    );
    let e = Scene::load(&scene_dir.join("up.gltf"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("buffers[0].uri") && e.contains("climbs above"),
        "{e}"
    );
    Scene::load_allowing(&scene_dir.join("up.gltf"), &allowed).expect("allowed buffer");
    // An absolute URI is refused even when it names a file inside the tree
    // or an allowed folder (issue 31: glTF URIs are relative references).
    let absolute = std::path::absolute(outside.join("m.bin")).unwrap();
    write(
        &scene_dir.join("abs.gltf"),
        std::fs::read_to_string(outside.join("m.gltf"))
            .unwrap()
            .replace("\"m.bin\"", &format!("\"{}\"", absolute.display())),
    );
    let e = Scene::load_allowing(&scene_dir.join("abs.gltf"), &allowed)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("buffers[0].uri") && e.contains("an absolute path"),
        "{e}"
    );
    let e = AllowedPaths::new(&[dir.join("missing")]).unwrap_err();
    assert!(
        e.starts_with("--allow-paths ") && e.contains("missing"),
        "{e}"
    );
}

/// A PNG of `width` x `height` RGB8 (colour type 2) or RGBA16 (colour
/// type 6, depth 16) that holds only its header and an empty IDAT: a few
/// dozen bytes that declare a huge image.
fn png_header(width: u32, height: u32, depth: u8, colour: u8) -> Vec<u8> {
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &b in bytes {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xEDB8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }
    let chunk = |kind: &[u8], data: &[u8]| {
        let mut c = (data.len() as u32).to_be_bytes().to_vec();
        let body = [kind, data].concat();
        c.extend(&body);
        c.extend(crc32(&body).to_be_bytes());
        c
    };
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([depth, colour, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    png.extend(chunk(
        b"IDAT",
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    ));
    png.extend(chunk(b"IEND", &[]));
    png
}

/// Issue 31: small files that declare huge images were decoded with the
/// decoder's default limits only (or none: the HDR reader), the message
/// naming neither the size nor a limit. Now the header is checked against
/// the documented limits (docs/SCENES.md, "Limits") before anything is
/// allocated: one line naming the file, its size and the limit.
#[test]
fn images_over_the_decoder_limits_are_refused_naming_size_and_limit() {
    let dir = temp_dir("decoder-limits");
    let cases = [
        // Over 16384 per side.
        (
            "wide.png",
            png_header(20000, 16, 8, 2),
            "20000x16",
            "16384 texels per side",
        ),
        // Within the sides, 2 GiB of 16-bit RGBA: over 1024 MiB.
        (
            "deep.png",
            png_header(16384, 16384, 16, 6),
            "16384x16384",
            "1024 MiB",
        ),
    ];
    for (name, bytes, size, limit) in &cases {
        write(&dir.join(name), bytes);
        let text = base(&format!(
            "[[material]]\nname = \"t\"\nkind = \"diffuse\"\nalbedo_texture = \"{name}\"\n"
        ));
        let path = dir.join("s.toml");
        write(&path, &text);
        let e = Scene::load(&path).unwrap_err().to_string();
        assert!(e.contains(": material[1].albedo_texture: "), "{e}");
        assert!(
            e.contains(name) && e.contains(size) && e.contains(limit),
            "{e}"
        );
    }
    // A Radiance header declaring 18000 x 9000 texels and no data.
    write(
        &dir.join("huge.hdr"),
        "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 9000 +X 18000\n",
    );
    let path = dir.join("env.toml");
    write(
        &path,
        base("[[light]]\nkind = \"environment\"\npath = \"huge.hdr\"\n"),
    );
    let e = Scene::load(&path).unwrap_err().to_string();
    assert!(
        e.contains(": light[1].path: ")
            && e.contains("environment image")
            && e.contains("18000x9000")
            && e.contains("8192 texels per side"),
        "{e}"
    );
    // A float EXR environment one texel wider than the limit.
    image::Rgb32FImage::new(8193, 2)
        .save(dir.join("wide.exr"))
        .expect("write the EXR");
    write(
        &path,
        base("[[light]]\nkind = \"environment\"\npath = \"wide.exr\"\n"),
    );
    let e = Scene::load(&path).unwrap_err().to_string();
    assert!(
        e.contains(": light[1].path: ")
            && e.contains("8193x2")
            && e.contains("8192 texels per side"),
        "{e}"
    );
}
