//! Environment and area lights in scene files: what they load into, and
//! every rejection (one line naming file, line and field).

use caustics::scene::*;
use glam::Vec3;
use std::path::{Path, PathBuf};

const CAMERA: &str = "[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n";
const REST: &str = "[[material]]\nname = \"white\"\nkind = \"diffuse\"\n\n[[object]]\nshape = \"sphere\"\nradius = 1.0\nmaterial = \"white\"\n";
const SKY: &str = "[[light]]\nkind = \"environment\"\nsky = { sun_direction = [0.0, 2.0, 0.0], sun_radius = 0.5, sun_radiance = 1000.0, zenith = [0.1, 0.2, 0.4], horizon = 0.3 }\n";

fn scene(lights: &str) -> String {
    format!("{CAMERA}\n{lights}\n{REST}")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caustics-lights-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Asserts `text` (as `file`) is rejected at `field` on the line holding `needle`.
fn rejects(text: &str, file: &Path, field: &str, needle: &str, message: &str) {
    let err =
        Scene::from_str(text, file).expect_err(&format!("should be rejected: {field} {message}"));
    let s = err.to_string();
    let line = text.lines().position(|l| l.contains(needle)).unwrap() + 1;
    assert!(
        s.starts_with(&format!("{}:{line}:", file.display())),
        "`{s}` should start with the file and line {line}"
    );
    assert_eq!(err.field(), Some(field), "{s}");
    assert!(s.contains(message), "expected `{message}` in `{s}`");
    assert_eq!(s.lines().count(), 1);
}

fn bad(text: &str, field: &str, needle: &str, message: &str) {
    rejects(text, Path::new("scenes/bad.toml"), field, needle, message);
}

#[test]
fn sky_environment_loads() {
    let s = Scene::from_str(&scene(SKY), Path::new("sky.toml")).expect("sky");
    assert!(
        s.lights.is_empty(),
        "an environment is not a punctual light"
    );
    let env = s.environment.expect("environment");
    assert_eq!((env.scale, env.rotate_deg), (1.0, 0.0));
    let EnvironmentKind::Sky(sky) = env.kind else {
        panic!("a sky")
    };
    assert_eq!(sky.sun_direction, Vec3::Y);
    assert_eq!(sky.horizon, Vec3::splat(0.3));
    // E = L 2π(1 − cos α).
    let (dir, e) = caustics::emitters::sun_irradiance(&env).expect("a sun");
    assert_eq!(dir, Vec3::NEG_Y);
    let expected = 1000.0 * 2.0 * std::f32::consts::PI * (1.0 - 0.5f32.to_radians().cos());
    assert!((e.x - expected).abs() < 1e-3 * expected);
    // `rotate` turns the sun about +y.
    let rotated = SKY.replace(
        "sun_direction = [0.0, 2.0, 0.0]",
        "sun_direction = [1.0, 0.0, 0.0]",
    ) + "rotate = 90.0\nscale = 2.0\n";
    let s = Scene::from_str(&scene(&rotated), Path::new("sky.toml")).expect("rotated");
    let env = s.environment.unwrap();
    let EnvironmentKind::Sky(sky) = env.kind else {
        panic!()
    };
    assert!(
        (sky.sun_direction - Vec3::NEG_Z).length() < 1e-6,
        "{}",
        sky.sun_direction
    );
    assert_eq!(env.scale, 2.0);
}

#[test]
fn hdr_image_environment_loads_relative_to_the_scene() {
    let dir = temp_dir("hdr");
    let pixels: Vec<image::Rgb<f32>> = (0..8).map(|i| image::Rgb([i as f32, 0.5, 2.0])).collect();
    let file = std::fs::File::create(dir.join("env.hdr")).unwrap();
    image::codecs::hdr::HdrEncoder::new(file)
        .encode(&pixels, 4, 2)
        .unwrap();
    let text =
        scene("[[light]]\nkind = \"environment\"\npath = \"env.hdr\"\nscale = 0.5\nrotate = 30\n");
    let s = Scene::from_str(&text, &dir.join("scene.toml")).expect("hdr environment");
    let env = s.environment.unwrap();
    let EnvironmentKind::Image(t) = &env.kind else {
        panic!("an image")
    };
    assert_eq!((t.width, t.height), (4, 2));
    assert!((t.texels[3][0] - 3.0).abs() < 0.05 && (t.texels[3][2] - 2.0).abs() < 0.02);
    assert_eq!((env.scale, env.rotate_deg), (0.5, 30.0));

    // Missing, not HDR, truncated: one line at `light[0].path` naming the file.
    let file = dir.join("scene.toml");
    let with = |p: &str| text.replace("env.hdr", p);
    rejects(
        &with("missing.hdr"),
        &file,
        "light[0].path",
        "path =",
        "missing.hdr",
    );
    image::RgbImage::new(4, 2)
        .save(dir.join("ldr.png"))
        .unwrap();
    rejects(
        &with("ldr.png"),
        &file,
        "light[0].path",
        "path =",
        "not an HDR image",
    );
    // Issue 31: texels far above the radiometric bound (1e10) loaded and
    // the render failed at its end with a NaN naming no file.
    let mut texels = vec![1.0f32; 4 * 2 * 4];
    texels[4 * 5] = 1.5e20;
    caustics::output::write_exr(&dir.join("hot.exr"), 4, 2, &texels).unwrap();
    rejects(
        &with("hot.exr"),
        &file,
        "light[0].path",
        "path =",
        "texel (1, 1) is [1.5e20",
    );
    let bytes = std::fs::read(dir.join("env.hdr")).unwrap();
    std::fs::write(dir.join("cut.hdr"), &bytes[..bytes.len() / 2]).unwrap();
    rejects(
        &with("cut.hdr"),
        &file,
        "light[0].path",
        "path =",
        "cut.hdr",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn area_lights_load_with_their_geometry() {
    let text = scene(
        "[[light]]\nkind = \"rect\"\ncenter = [0.0, 3.0, 0.0]\nnormal = [0.0, -2.0, 0.0]\nsize = [0.5, 0.25]\ntangent = [1.0, 0.5, 0.0]\nradiance = [10.0, 20.0, 30.0]\n\n[[light]]\nkind = \"sphere\"\ncenter = [2.0, 1.0, 0.0]\nradius = 0.1\nradiance = 5.0\n",
    );
    let s = Scene::from_str(&text, Path::new("area.toml")).expect("area lights");
    assert_eq!(s.emitters.len(), 2);
    let EmitterShape::Rect {
        normal,
        tangent,
        size,
        ..
    } = s.emitters[0].shape
    else {
        panic!("a rect")
    };
    assert_eq!(normal, Vec3::NEG_Y);
    assert_eq!(tangent, Vec3::X, "projected onto the plane");
    assert_eq!(size, [0.5, 0.25]);
    for e in &s.emitters {
        let m = &s.materials[e.material as usize];
        assert_eq!(
            (m.kind, m.color, m.emission),
            (MaterialKind::Diffuse, Vec3::ZERO, e.radiance)
        );
        let o = &s.objects[e.object as usize];
        assert!(o.mesh.materials.iter().all(|&i| i == e.material));
    }
    // The rect's triangles face the side it emits to.
    let tris = s.triangles(0.0);
    let rect: Vec<_> = tris
        .iter()
        .filter(|t| t.object == s.emitters[0].object)
        .collect();
    assert_eq!(rect.len(), 2);
    for t in rect {
        let [a, b, c] = t.positions;
        assert!((b - a).cross(c - a).normalize().dot(Vec3::NEG_Y) > 0.999);
    }
    let power = caustics::emitters::emitter_power(&s.emitters[0]);
    assert!((power.x - std::f32::consts::PI * 10.0 * 0.125).abs() < 1e-4);
}

#[test]
fn bad_lights_are_rejected() {
    let rect = "[[light]]\nkind = \"rect\"\ncenter = [0.0, 3.0, 0.0]\nnormal = [0.0, -1.0, 0.0]\nsize = [0.5, 0.25]\nradiance = 1.0\n";
    bad(
        &scene(&rect.replace("radiance = 1.0", "radiance = [1.0, -2.0, 1.0]")),
        "light[0].radiance",
        "radiance",
        "negative",
    );
    bad(
        &scene(&rect.replace("size = [0.5, 0.25]", "size = [0.0, 0.25]")),
        "light[0].size[0]",
        "size",
        "positive",
    );
    bad(
        &scene(&rect.replace("normal = [0.0, -1.0, 0.0]", "normal = [0.0, 0.0, 0.0]")),
        "light[0].normal",
        "normal",
        "non-zero",
    );
    bad(
        &scene(&(rect.to_owned() + "tangent = [0.0, 2.0, 0.0]\n")),
        "light[0].tangent",
        "tangent",
        "parallel",
    );
    bad(
        &scene(&(rect.to_owned() + "radius = 1.0\n")),
        "light[0].radius",
        "radius = 1",
        "unknown",
    );
    let sphere =
        "[[light]]\nkind = \"sphere\"\ncenter = [0.0, 3.0, 0.0]\nradius = 0.0\nradiance = 1.0\n";
    bad(&scene(sphere), "light[0].radius", "radius", "positive");
    bad(
        &scene(
            &sphere
                .replace("radiance = 1.0", "radiance = -1.0")
                .replace("radius = 0.0", "radius = 1.0"),
        ),
        "light[0].radiance",
        "radiance",
        "negative",
    );
    bad(
        &scene(&SKY.replace("sun_radius = 0.5", "sun_radius = 0.0")),
        "light[0].sky.sun_radius",
        "sky",
        "positive",
    );
    bad(
        &scene(&SKY.replace("zenith = [0.1, 0.2, 0.4]", "zenith = [0.1, -0.2, 0.4]")),
        "light[0].sky.zenith",
        "sky",
        "negative",
    );
    bad(
        &scene(&SKY.replace(
            "sun_direction = [0.0, 2.0, 0.0]",
            "sun_direction = [0.0, 0.0, 0.0]",
        )),
        "light[0].sky.sun_direction",
        "sky",
        "non-zero",
    );
    bad(
        &scene(&(SKY.to_owned() + "scale = -1.0\n")),
        "light[0].scale",
        "scale",
        "negative",
    );
    bad(
        &scene("[[light]]\nkind = \"environment\"\n"),
        "light[0].path",
        "[[light]]",
        "needs `path`",
    );
    bad(
        &scene(&(SKY.to_owned() + "path = \"x.hdr\"\n")),
        "light[0].sky",
        "sky",
        "not both",
    );
    let second = SKY.replace("\"environment\"", "\"environment\" # second");
    bad(
        &scene(&format!("{SKY}\n{second}")),
        "light[1].kind",
        "# second",
        "at most one",
    );
}

#[test]
fn canonical_light_scenes_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let s = Scene::load(&dir.join("ring_sky.toml")).expect("ring_sky");
    let env = s.environment.expect("an environment");
    let EnvironmentKind::Image(t) = &env.kind else {
        panic!("an image")
    };
    assert_eq!((t.width, t.height), (256, 128));
    // Brighter toward the sun (-x, 25 degrees up) than straight up.
    let texel = |d: Vec3| {
        let (u, v) = caustics::emitters::equirect_uv(d);
        let (i, j) = ((u * 256.0) as usize, (v * 128.0) as usize);
        Vec3::from(t.texels[j * 256 + i])
    };
    let to_sun = Vec3::new(-25f32.to_radians().cos(), 25f32.to_radians().sin(), 0.0);
    assert!(texel(to_sun).x > 100.0 * texel(Vec3::Y).x);
    // The sun `direct` extracts from the image: the script's 700 W/m² red
    // (less the faint rim texels left to the sky), from -x at 25 degrees.
    let (travel, e) = caustics::emitters::sun_irradiance(&env).expect("a sun in the image");
    eprintln!("extracted sun: E {e}, toward {}", -travel);
    assert!((-travel).dot(to_sun) > 0.9995, "{travel}");
    assert!((e.x / 700.0 - 1.0).abs() < 0.05, "{e}");
    let s = Scene::load(&dir.join("volume_box.toml")).expect("volume_box");
    assert_eq!(s.emitters.len(), 1);
    assert!(s.medium.is_some());
}
