//! glTF 2.0 scenes (docs/SCENES.md, "glTF 2.0"): the tests write their own
//! small files with [`Gltf`] (JSON + .bin, or .glb) and check the material
//! mapping, node transforms against an equivalent TOML scene (the same
//! `direct` image), a file as a whole scene (`--scene model.glb`), every
//! rejection through the CLI (exit code 1, one line naming the file and the
//! glTF path), and the loader's linear scaling.

use crate::common;

use caustics::params::{ParamSet, Params};
use caustics::renderer::Renderer;
use caustics::scene::gltf::{self as loader, LUMENS_PER_WATT};
use caustics::scene::{shapes, LightKind, MaterialKind, Mesh, Scene, Wrap};
use caustics::techniques;
use common::gltf_builder::Gltf;
use common::*;
use glam::{Mat4, Quat, Vec2, Vec3};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::SeqCst);
    let dir = std::env::temp_dir().join(format!("caustics-gltf-{}-{name}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn quad() -> Mesh {
    shapes::plane(Vec3::ZERO, Vec3::Y, None, [4.0, 4.0])
}

// ------------------------------------------------------------ materials

#[test]
fn materials_map_to_the_projects_radiometry() {
    let dir = temp_dir("materials");
    let mut g = Gltf::new();
    let glass = g.material(json!({
        "name": "glass",
        "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.0},
        "extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_volume": {"thicknessFactor": 0.5, "attenuationDistance": 2.0,
                                     "attenuationColor": [0.5, 0.8, 1.0]},
            "KHR_materials_ior": {"ior": 1.45}
        }
    }));
    let mirror = g.material(json!({
        "name": "mirror",
        "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.8, 0.7, 1.0],
                                 "metallicFactor": 1.0, "roughnessFactor": 0.0}
    }));
    let floor = g.material(json!({
        "name": "floor",
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.6, 0.7, 1.0], "metallicFactor": 0.0}
    }));
    let thin = g.material(json!({
        "name": "thin",
        "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                       "KHR_materials_ior": {"ior": 1.4}}
    }));
    let brushed = g.material(json!({
        "name": "brushed",
        "pbrMetallicRoughness": {"metallicFactor": 1.0, "roughnessFactor": 0.3}
    }));
    let lamp = g.material(json!({
        "name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0],
        "pbrMetallicRoughness": {"metallicFactor": 0.0}
    }));
    let hidden = g.material(json!({
        "name": "hidden", "alphaMode": "MASK",
        "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 0.2], "metallicFactor": 0.0}
    }));
    // The glass sphere has no NORMAL: smooth normals are computed.
    let sphere = sphere_mesh(Vec3::new(0.0, 1.0, 0.0), 0.5, 0, 24);
    for (m, mat, normals) in [
        (&sphere, glass, false),
        (&quad(), mirror, true),
        (&quad(), floor, true),
        (&quad(), thin, true),
        (&quad(), brushed, true),
        (&quad(), lamp, true),
        (&quad(), hidden, true),
    ] {
        let mesh = g.mesh(m, normals, Some(mat));
        g.root_node(json!({"mesh": mesh}));
    }
    g.root["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_clearcoat"]);
    let path = g.write_gltf(&dir, "materials");
    let a = loader::load(&path).unwrap();

    let by_name = |n: &str| {
        a.materials
            .iter()
            .find(|m| m.name == format!("materials.gltf:{n}"))
            .unwrap_or_else(|| panic!("material {n} in {:?}", a.materials))
    };
    let glass = by_name("glass");
    assert_eq!(glass.kind, MaterialKind::Dielectric);
    assert_eq!(glass.ior, 1.45);
    // σa = -ln(attenuationColor) / attenuationDistance per channel.
    let expect = Vec3::new(-(0.5f32.ln()), -(0.8f32.ln()), 0.0) / 2.0;
    assert!(
        (glass.absorption - expect).abs().max_element() < 1e-6,
        "{}",
        glass.absorption
    );
    let mirror = by_name("mirror");
    assert_eq!(mirror.kind, MaterialKind::Mirror);
    assert_eq!(mirror.color, Vec3::new(0.9, 0.8, 0.7));
    let floor = by_name("floor");
    assert_eq!(floor.kind, MaterialKind::Diffuse);
    assert_eq!(floor.color, Vec3::new(0.5, 0.6, 0.7));
    // Transmission without KHR_materials_volume: thin-walled, a sheet.
    let thin = by_name("thin");
    assert_eq!((thin.kind, thin.ior), (MaterialKind::ThinDielectric, 1.4));
    assert_eq!(by_name("brushed").kind, MaterialKind::Mirror);
    // Emission in cd/m² becomes radiance at the lights' 683 lm/W.
    let lamp = by_name("lamp");
    assert_eq!(lamp.kind, MaterialKind::Diffuse);
    assert_eq!(lamp.emission, Vec3::splat(1.0 / LUMENS_PER_WATT));
    // alphaMode MASK with a constant alpha below the cutoff: cut out.
    assert!(a.materials.iter().all(|m| !m.name.ends_with(":hidden")));
    assert_eq!(a.mesh.indices.len(), sphere.indices.len() + 5 * 2);

    // One warning per material that is not rendered as written, naming
    // it; none for the ones that map exactly.
    for name in ["brushed", "hidden"] {
        let n = a
            .warnings
            .iter()
            .filter(|w| w.contains(&format!("materials.gltf:{name}`")))
            .count();
        assert_eq!(n, 1, "{name}: {:#?}", a.warnings);
    }
    assert!(a.warnings[0]
        .ends_with("extension KHR_materials_clearcoat is used by the file but ignored"));
    assert_eq!(a.warnings.len(), 3, "{:#?}", a.warnings);
    assert!(!a.warnings.iter().any(|w| w.contains("thin")));

    // Computed normals of the sphere point away from its centre (at every
    // vertex a triangle uses: the UV sphere leaves one pole copy unused).
    assert!(!a.had_normals);
    for t in &a.mesh.indices[..sphere.indices.len()] {
        for &i in t {
            let (p, n) = (a.mesh.positions[i as usize], a.mesh.normals[i as usize]);
            let radial = (p - Vec3::new(0.0, 1.0, 0.0)).normalize();
            assert!(n.dot(radial) > 0.99, "normal {n} at {p}");
        }
    }
}

#[test]
fn texture_coordinates_and_base_color_texture_are_read() {
    let dir = temp_dir("texture");
    image::RgbImage::from_pixel(2, 2, image::Rgb([255, 255, 255]))
        .save(dir.join("tiles.png"))
        .unwrap();
    let mut g = Gltf::new();
    g.root["images"] = json!([{"uri": "tiles.png"}]);
    g.root["textures"] = json!([{"source": 0}]);
    let mat = g.material(json!({
        "name": "tiles",
        "pbrMetallicRoughness": {
            "metallicFactor": 0.0,
            "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform":
                {"offset": [0.25, 0.5], "rotation": 0.5, "scale": [2.0, 3.0]}}}
        }
    }));
    let q = quad();
    let uv = [
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ];
    let mesh = g.mesh(&q, true, Some(mat));
    let uv_acc = g.vec2s(&uv);
    g.root["meshes"][mesh]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv_acc);
    g.root_node(json!({"mesh": mesh}));
    let mut a = loader::load(&g.write_gltf(&dir, "textured")).unwrap();
    assert_eq!(a.mesh.uvs, uv);
    let t = a.base_color_textures[0].clone().expect("texture reference");
    assert_eq!((t.texture, t.image, t.tex_coord), (0, 0, 0));
    assert_eq!(t.pixels.path, dir.join("tiles.png"));
    assert_eq!((t.pixels.width, t.pixels.height), (2, 2));
    assert_eq!(
        (t.offset, t.rotation, t.scale),
        (Vec2::new(0.25, 0.5), 0.5, Vec2::new(2.0, 3.0))
    );
    assert!(a.warnings.is_empty(), "{:#?}", a.warnings);
    // The extension's `T * R * S` (GLSL column-major): scale, then rotate
    // counter-clockwise in uv, then offset.
    let (sin, cos) = 0.5f32.sin_cos();
    let expect = |p: Vec2| {
        let q = p * Vec2::new(2.0, 3.0);
        Vec2::new(cos * q.x - sin * q.y, sin * q.x + cos * q.y) + Vec2::new(0.25, 0.5)
    };
    assert_eq!(
        t.transform(Vec2::new(1.0, 0.0)),
        expect(Vec2::new(1.0, 0.0))
    );
    let quarter = loader::TextureRef {
        rotation: std::f32::consts::FRAC_PI_2,
        offset: Vec2::ZERO,
        scale: Vec2::ONE,
        ..t.clone()
    };
    assert!((quarter.transform(Vec2::X) - Vec2::Y).length() < 1e-6);
    a.transform_uvs();
    for (got, &p) in a.mesh.uvs.iter().zip(&uv) {
        assert!((*got - expect(p)).length() < 1e-6, "{got} vs {}", expect(p));
    }
}

/// `alphaMode = MASK` with a base colour texture: the texture's alpha is
/// compared with alphaCutoff / the factor's alpha (the spec compares their
/// product), kept with no warning on a diffuse material; on a mirror
/// (cut-outs are diffuse-only) it renders opaque with one warning. The
/// rendering of a cut-out is tested in tests/textures.rs.
#[test]
fn mask_with_a_texture_keeps_the_cutoff_over_the_factor_alpha() {
    let dir = temp_dir("mask");
    image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 255, 255, 128]))
        .save(dir.join("leaf.png"))
        .unwrap();
    let mut g = Gltf::new();
    g.root["images"] = json!([{"uri": "leaf.png"}]);
    g.root["textures"] = json!([{"source": 0}]);
    let leaf = g.material(json!({
        "name": "leaf", "alphaMode": "MASK", "alphaCutoff": 0.4,
        "pbrMetallicRoughness": {"metallicFactor": 0.0,
            "baseColorFactor": [1.0, 1.0, 1.0, 0.8], "baseColorTexture": {"index": 0}}
    }));
    let chrome = g.material(json!({
        "name": "chrome", "alphaMode": "MASK",
        "pbrMetallicRoughness": {"metallicFactor": 1.0, "roughnessFactor": 0.0,
            "baseColorTexture": {"index": 0}}
    }));
    for mat in [leaf, chrome] {
        let mesh = g.mesh(&quad(), true, Some(mat));
        g.root_node(json!({"mesh": mesh}));
    }
    let a = loader::load(&g.write_gltf(&dir, "mask")).unwrap();
    let t = a.base_color_textures[0].as_ref().expect("leaf texture");
    assert!((t.alpha_cutoff - 0.5).abs() < 1e-6, "{}", t.alpha_cutoff);
    assert_eq!(t.pixels.alpha.len(), 4);
    assert!(
        (t.pixels.alpha[0] - 128.0 / 255.0).abs() < 1e-6,
        "alpha is not sRGB-decoded"
    );
    let chrome = a.base_color_textures[1].as_ref().expect("chrome texture");
    assert_eq!(chrome.alpha_cutoff, 0.0);
    assert_eq!(a.warnings.len(), 1, "{:#?}", a.warnings);
    assert!(
        a.warnings[0].contains("chrome") && a.warnings[0].contains("diffuse materials only"),
        "{}",
        a.warnings[0]
    );
}

/// A 16 x 16 checker of sRGB 40 and 220 (linear ≈ 0.02 and 0.72).
fn checker_png() -> Vec<u8> {
    let img = image::RgbImage::from_fn(16, 16, |x, y| {
        let c = if (x / 4 + y / 4) % 2 == 0 { 40 } else { 220 };
        image::Rgb([c, c, c])
    });
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
    bytes.into_inner()
}

/// A floor whose glTF material has a base colour texture (a file beside
/// the .gltf, a buffer view of a .glb, a data: URI) and a
/// `KHR_texture_transform` scale renders the same `direct` image as the
/// TOML floor with that `albedo_texture` and `uv_scale`.
#[test]
fn textured_gltf_floor_matches_the_toml_albedo_texture() {
    let dir = temp_dir("textured_floor");
    let png = checker_png();
    std::fs::write(dir.join("checker.png"), &png).unwrap();
    let floor = shapes::plane(Vec3::ZERO, Vec3::Y, None, [6.0, 6.0]);
    // The camera, the light and the "white" material, without the floor.
    let head = SCENE_HEAD.split("\n[[object]]").next().unwrap();
    // image: the glTF `images[0]` (JSON), given the writer for buffer views.
    let write = |name: &str, glb: bool, image: &dyn Fn(&mut Gltf) -> Value| {
        let mut g = Gltf::new();
        g.root["images"] = json!([image(&mut g)]);
        g.root["textures"] = json!([{"source": 0}]);
        g.root["extensionsUsed"] = json!(["KHR_texture_transform"]);
        let mat = g.material(json!({"name": "tiles", "pbrMetallicRoughness": {
            "metallicFactor": 0.0,
            "baseColorTexture": {"index": 0, "extensions":
                {"KHR_texture_transform": {"scale": [3.0, 2.0]}}}}}));
        let mesh = g.mesh(&floor, true, Some(mat));
        let uvs = g.vec2s(&floor.uvs);
        g.root["meshes"][mesh]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uvs);
        g.root_node(json!({"mesh": mesh}));
        let path = if glb {
            g.write_glb(&dir, name)
        } else {
            g.write_gltf(&dir, name)
        };
        path.file_name().unwrap().to_str().unwrap().to_owned()
    };
    let file = write("file", false, &|_| json!({"uri": "checker.png"}));
    let view = write(
        "view",
        true,
        &|g| json!({"bufferView": g.view(&png), "mimeType": "image/png"}),
    );
    let data = write(
        "data",
        false,
        &|_| json!({"uri": format!("data:image/png;base64,{}", base64(&png))}),
    );

    let toml = format!(
        r#"{head}
[[material]]
name = "tiles"
kind = "diffuse"
albedo = 1.0
albedo_texture = "checker.png"
uv_scale = [3.0, 2.0]

[[object]]
shape = "plane"
material = "tiles"
size = [6.0, 6.0]
"#
    );
    let reference = render_direct(Scene::from_str(&toml, &dir.join("toml.toml")).unwrap());
    let untextured = render_direct(
        Scene::from_str(
            &toml.replace(
                "albedo_texture = \"checker.png\"\nuv_scale = [3.0, 2.0]\n",
                "",
            ),
            &dir.join("plain.toml"),
        )
        .unwrap(),
    );
    let peak = reference.iter().copied().fold(0.0f32, f32::max);
    // The texture shows (the comparisons below can fail).
    assert!(max_diff(&reference, &untextured) > 0.2 * peak);
    for name in [&file, &view, &data] {
        let text = format!("{head}\n[[object]]\nshape = \"gltf\"\npath = \"{name}\"\n");
        let scene = Scene::from_str(&text, &dir.join(format!("{name}.toml"))).unwrap();
        assert_eq!(scene.textures.len(), 1, "{name}");
        let m = scene.materials[1].texture.expect("textured material");
        assert_eq!(m.uv_scale, Vec2::ONE, "{name}: the transform is in the UVs");
        let worst = max_diff(&reference, &render_direct(scene));
        eprintln!("{name}: direct 32², max difference {worst}, peak {peak}");
        assert!(worst <= 1e-5, "{name}: max difference {worst}, peak {peak}");
    }
}

/// An 8 x 8 PNG of distinct, asymmetric grey codes, and its texel `(x, y)`
/// as a code.
fn asymmetric_code(x: u32, y: u32) -> u8 {
    ((37 * x + 91 * y * y + 13) % 200 + 30) as u8
}

fn png_of(side: u32, code: impl Fn(u32, u32) -> u8) -> Vec<u8> {
    let img = image::RgbImage::from_fn(side, side, |x, y| {
        let c = code(x, y);
        image::Rgb([c, c, c])
    });
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
    bytes.into_inner()
}

/// glTF sampler wrap modes: a floor whose 8² texture is read over UVs
/// beyond [0, 1] with MIRRORED_REPEAT (or CLAMP_TO_EDGE) renders the same
/// `direct` image as a floor reading, inside (0, 1) with REPEAT, a 32²
/// texture that holds those mirrored (or edge-extended) texels explicitly,
/// texel for texel (the UV maps line the two texel grids up; the camera
/// looks straight down so every lookup magnifies, level 0). The same file
/// with REPEAT differs, so the comparison can fail.
#[test]
fn sampler_wrap_modes_match_explicitly_wrapped_textures() {
    let dir = temp_dir("wrap");
    let floor = shapes::plane(Vec3::ZERO, Vec3::Y, None, [6.0, 6.0]);
    // Each file: one image, one sampler, a KHR_texture_transform on the
    // floor's [0, 1]² UVs (uv' = scale uv + offset).
    let write = |name: &str, png: &[u8], wrap: u32, scale: f32, offset: f32| {
        let mut g = Gltf::new();
        g.root["images"] = json!([{"bufferView": g.view(png), "mimeType": "image/png"}]);
        g.root["samplers"] = json!([{"wrapS": wrap, "wrapT": wrap, "magFilter": 9729}]);
        g.root["textures"] = json!([{"source": 0, "sampler": 0}]);
        g.root["extensionsUsed"] = json!(["KHR_texture_transform"]);
        let mat = g.material(json!({"name": "floor", "pbrMetallicRoughness": {
            "metallicFactor": 0.0,
            "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform":
                {"scale": [scale, scale], "offset": [offset, offset]}}}}}));
        let mesh = g.mesh(&floor, true, Some(mat));
        let uvs = g.vec2s(&floor.uvs);
        g.root["meshes"][mesh]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uvs);
        g.root_node(json!({"mesh": mesh}));
        let path = g.write_glb(&dir, name);
        let text = format!(
            "[camera]\neye = [0.0, 8.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\n\
             [[light]]\nkind = \"point\"\nposition = [1.0, 4.0, 2.0]\nintensity = 30.0\n\
             [[object]]\nshape = \"gltf\"\npath = \"{}\"\n",
            path.file_name().unwrap().to_str().unwrap()
        );
        Scene::from_str(&text, &dir.join(format!("{name}.toml"))).unwrap()
    };
    let small = png_of(8, asymmetric_code);
    const REPEAT: u32 = 10497;
    const CLAMP: u32 = 33071;
    const MIRROR: u32 = 33648;
    // Floor UV w in [0, 1]. Small texture: uv = 2 w + o, texel coordinate
    // 8 uv; big one (32²): uv = w / 2 + 1/4, texel coordinate 32 uv, which
    // is the small one's plus `shift` texels, away from its own seams.
    let mirrored = |i: u32| {
        let m = (i + 16 - 8) % 16;
        if m < 8 {
            m
        } else {
            15 - m
        }
    };
    let clamped = |i: u32| (i as i32 - 12).clamp(0, 7) as u32;
    // Name, wrap mode, UV offset, the big texture's texel -> the small one's.
    type Case = (&'static str, u32, f32, fn(u32) -> u32);
    let cases: [Case; 2] = [
        ("mirrored", MIRROR, 0.0, mirrored),
        ("clamped", CLAMP, -0.5, clamped),
    ];
    for (name, wrap, offset, explicit) in cases {
        let wrapped = write(name, &small, wrap, 2.0, offset);
        let t = wrapped.materials[0].texture.expect("textured");
        assert_eq!(
            t.wrap,
            [if wrap == MIRROR {
                Wrap::MirroredRepeat
            } else {
                Wrap::ClampToEdge
            }; 2]
        );
        let big = png_of(32, |x, y| asymmetric_code(explicit(x), explicit(y)));
        let expected = render_direct(write(&format!("{name}_explicit"), &big, REPEAT, 0.5, 0.25));
        let repeated = render_direct(write(
            &format!("{name}_repeat"),
            &small,
            REPEAT,
            2.0,
            offset,
        ));
        let peak = expected.iter().copied().fold(0.0f32, f32::max);
        let worst = max_diff(&expected, &render_direct(wrapped));
        let repeat_diff = max_diff(&expected, &repeated);
        eprintln!("{name}: max difference {worst} (repeat instead: {repeat_diff}), peak {peak}");
        assert!(repeat_diff > 0.1 * peak, "{name}: repeat should differ");
        assert!(worst <= 1e-5, "{name}: max difference {worst}, peak {peak}");
    }
}

/// An emissive glTF quad (emissiveFactor × KHR_materials_emissive_strength
/// in cd/m², black base colour) is the area light a TOML `rect` of that
/// size and radiance (cd/m² / 683) is: the same floor irradiance and the
/// same lamp seen directly, in `direct` (its two triangles' exact polygon
/// irradiance sums to the rect's) and in the reference (photons uniform
/// over its area, cosine-weighted). Measured: `direct` max difference
/// 2.4e-7 at peak 20; reference at 2 M photons, 48²: direct component
/// energy +0.07%, emitted 0.00%.
#[test]
fn emissive_gltf_quad_equals_the_toml_rect_light() {
    let dir = temp_dir("emissive");
    let radiance = 20.0f32;
    let lamp = shapes::plane(Vec3::new(0.0, 1.5, 0.0), Vec3::NEG_Y, None, [0.6, 0.4]);
    let mut g = Gltf::new();
    g.root["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]);
    let mat = g.material(json!({"name": "lamp", "emissiveFactor": [1.0, 0.5, 0.25],
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0},
        "extensions": {"KHR_materials_emissive_strength":
            {"emissiveStrength": radiance * LUMENS_PER_WATT}}}));
    let mesh = g.mesh(&lamp, true, Some(mat));
    g.root_node(json!({"mesh": mesh}));
    g.write_glb(&dir, "lamp");
    // SCENE_HEAD's floor, seen from below the lamp (its emitting side),
    // with the point light off.
    let head = SCENE_HEAD
        .replace("eye = [2.5, 3.0, 4.0]", "eye = [0.0, 0.8, 3.0]")
        .replace("intensity = 30.0", "intensity = 0.0");
    let rect = format!(
        "{head}\n[[light]]\nkind = \"rect\"\ncenter = [0.0, 1.5, 0.0]\nnormal = [0.0, -1.0, 0.0]\n\
         tangent = [1.0, 0.0, 0.0]\nsize = [0.6, 0.4]\nradiance = [{radiance}, {}, {}]\n",
        radiance * 0.5,
        radiance * 0.25
    );
    let gltf = format!("{head}\n[[object]]\nshape = \"gltf\"\npath = \"lamp.glb\"\n");
    let rect = Scene::from_str(&rect, &dir.join("rect.toml")).unwrap();
    let gltf = Scene::from_str(&gltf, &dir.join("gltf.toml")).unwrap();
    let m = &gltf.materials[1];
    assert!(
        (m.emission - Vec3::new(1.0, 0.5, 0.25) * radiance)
            .abs()
            .max_element()
            < 1e-4
    );

    // direct: the polygon formula is additive, so two triangles give the
    // rect's irradiance up to rounding.
    let (a, b) = (render_direct(rect.clone()), render_direct(gltf.clone()));
    let peak = a.iter().copied().fold(0.0f32, f32::max);
    let worst = max_diff(&a, &b);
    eprintln!("emissive quad, direct 32²: max difference {worst}, peak {peak}");
    assert!(peak > 1.0, "the lamp shows");
    assert!(worst <= 1e-5 * peak, "max difference {worst}, peak {peak}");

    // The reference: the floor's direct light and the lamp seen directly.
    use caustics::reference::Component;
    let render = |scene: Scene| {
        let ctx = validated_context();
        let r = traced_reference(&ctx, &scene, 48, 2_000_000);
        let out = [Component::Direct, Component::Emitted].map(|c| energy(r.whole(c)));
        assert_validation_clean(&ctx);
        out
    };
    let (a, b) = (render(rect), render(gltf));
    for (name, x, y) in [("direct", a[0], b[0]), ("emitted", a[1], b[1])] {
        let rel = (y - x) / x;
        eprintln!(
            "emissive quad, reference 48², {name}: rect {x:.4}, glTF {y:.4}, {:+.2}%",
            100.0 * rel
        );
        assert!(x > 0.0 && rel.abs() < 0.03, "{name}: {rel}");
    }
}

/// Only `direct` and the reference render a thin dielectric sheet and an
/// emissive glTF surface; every other technique refuses the scene in its
/// `check_scene`, naming the material, and `--technique auto` falls back
/// to `direct`. A bad `thin_dielectric` is one error naming the field.
#[test]
fn other_techniques_refuse_sheets_and_emissive_surfaces() {
    let dir = temp_dir("refuse");
    let mut g = Gltf::new();
    let mat = g.material(json!({"name": "glow", "emissiveFactor": [1.0, 1.0, 1.0],
        "pbrMetallicRoughness": {"metallicFactor": 0.0}}));
    let mesh = g.mesh(&quad(), true, Some(mat));
    g.root_node(json!({"mesh": mesh}));
    g.write_glb(&dir, "glow");
    let head = SCENE_HEAD;
    let sheet = format!(
        "{head}\n[[material]]\nname = \"pane\"\nkind = \"thin_dielectric\"\nior = 1.5\n\
         [[object]]\nshape = \"plane\"\nmaterial = \"pane\"\ncenter = [0.0, 1.0, 0.0]\nsize = [1.0, 1.0]\n"
    );
    let glow = format!("{head}\n[[object]]\nshape = \"gltf\"\npath = \"glow.glb\"\n");
    for (text, material) in [(sheet, "pane"), (glow, "glow.glb:glow")] {
        let scene = Scene::from_str(&text, &dir.join("s.toml")).unwrap();
        for t in techniques::TECHNIQUES {
            let result = (t.check_scene)(&scene);
            if t.name == "direct" {
                assert!(result.is_ok(), "direct: {result:?}");
                continue;
            }
            let e = result.expect_err(t.name).to_string();
            assert!(
                e.contains(&format!("`{material}`"))
                    && e.contains(t.name)
                    && e.contains("use `direct` or `reference`"),
                "{}: {e}",
                t.name
            );
        }
        assert_eq!(techniques::auto(&scene), "direct");
    }
    for (bad, field) in [
        ("ior = 0.5", "material[1].ior"),
        ("absorption = 1.0", "material[1]"),
    ] {
        let text = format!(
            "{SCENE_HEAD}\n[[material]]\nname = \"pane\"\nkind = \"thin_dielectric\"\n{bad}\n"
        );
        let e = Scene::from_str(&text, &dir.join("bad.toml")).unwrap_err();
        assert_eq!(e.to_string().lines().count(), 1, "{e}");
        assert!(e.to_string().contains(field), "{e}");
    }
}

// ------------------------------------------------------------ transforms

const SIZE: u32 = 32;

/// Largest absolute difference between two images.
fn max_diff(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f32, f32::max)
}

/// The `direct` image of `scene` at 32², after two frames: rgb per pixel.
fn render_direct(scene: Scene) -> Vec<f32> {
    let ctx = validated_context();
    let params = Params::resolve("direct", techniques::direct::DirectParams::specs(), &[]).unwrap();
    let image = {
        let mut r = Renderer::new(&ctx, scene, "direct", &params, SIZE, SIZE, 0.0).unwrap();
        r.render_frame(0.0).unwrap();
        r.render_frame(0.0).unwrap();
        r.radiance().unwrap()
    };
    assert_validation_clean(&ctx);
    assert_finite(&image);
    image.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect()
}

const SCENE_HEAD: &str = r#"
[camera]
eye = [2.5, 3.0, 4.0]
target = [0.0, 0.4, 0.0]
fov_y = 45.0

[[light]]
kind = "point"
position = [1.0, 4.0, 2.0]
intensity = 30.0

[[material]]
name = "white"
kind = "diffuse"
albedo = 0.8

[[object]]
shape = "plane"
material = "white"
size = [6.0, 6.0]
"#;

/// A node hierarchy (a root `matrix`, a parent's translation + rotation, a
/// child's translation + mirroring scale) against one TOML transform: the
/// same triangles and the same `direct` image.
#[test]
fn node_hierarchy_matches_the_equivalent_toml_transform() {
    let dir = temp_dir("hierarchy");
    let (m0, t1, c) = (
        Vec3::new(0.1, 0.0, -0.2),
        Vec3::new(-0.3, 0.2, 0.1),
        Vec3::new(0.4, 0.0, 0.2),
    );
    let r = Quat::from_rotation_y(30f32.to_radians());
    let s = Vec3::new(-0.6, 0.8, 0.5);
    let (lo, hi) = (Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 1.0, 0.5));
    let cube = shapes::cuboid(lo, hi);

    let mut g = Gltf::new();
    let mat = g.material(json!({"name": "white", "pbrMetallicRoughness":
        {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0}}));
    let mesh = g.mesh(&cube, true, Some(mat));
    let child = g.node(json!({"mesh": mesh, "translation": c.to_array(), "scale": s.to_array()}));
    let parent = g.node(json!({"children": [child], "translation": t1.to_array(),
                               "rotation": r.to_array()}));
    g.root_node(json!({"children": [parent],
        "matrix": Mat4::from_translation(m0).to_cols_array()}));
    g.write_gltf(&dir, "model");

    let translate = m0 + t1 + r * c;
    let toml = format!(
        "{SCENE_HEAD}\n[[object]]\nshape = \"box\"\nmaterial = \"white\"\nmin = {:?}\nmax = {:?}\ntranslate = {:?}\nrotate = [0.0, 30.0, 0.0]\nscale = {:?}\n",
        lo.to_array(),
        hi.to_array(),
        translate.to_array(),
        s.to_array()
    );
    let reference = Scene::from_str(&toml, &dir.join("box.toml")).unwrap();
    let gltf_toml = format!("{SCENE_HEAD}\n[[object]]\nshape = \"gltf\"\npath = \"model.gltf\"\n");
    let via_gltf = Scene::from_str(&gltf_toml, &dir.join("gltf.toml")).unwrap();
    assert_eq!(
        via_gltf.materials[1].name, "model.gltf:white",
        "the file's material joins the scene's"
    );
    // `material` on the object replaces the file's.
    let replaced = Scene::from_str(
        &format!("{gltf_toml}material = \"white\"\n"),
        &dir.join("replaced.toml"),
    )
    .unwrap();
    assert_eq!(replaced.materials.len(), 1);
    assert!(replaced.objects[1].mesh.materials.iter().all(|&m| m == 0));

    let (a, b) = (reference.triangles(0.0), via_gltf.triangles(0.0));
    assert_eq!(a.len(), b.len());
    for (ta, tb) in a.iter().zip(&b) {
        for k in 0..3 {
            assert!(
                (ta.positions[k] - tb.positions[k]).abs().max_element() < 1e-5,
                "{ta:?} vs {tb:?}"
            );
            assert!((ta.normals[k] - tb.normals[k]).abs().max_element() < 1e-5);
        }
    }
    let (ia, ib) = (render_direct(reference), render_direct(via_gltf));
    let floor_only = render_direct(Scene::from_str(SCENE_HEAD, &dir.join("floor.toml")).unwrap());
    let peak = ia.iter().copied().fold(0.0f32, f32::max);
    // The box is in view (the comparison below can fail).
    assert!(max_diff(&ia, &floor_only) > 0.1 * peak);
    let worst = max_diff(&ia, &ib);
    eprintln!("direct 32²: max difference {worst}, peak radiance {peak}");
    assert!(worst <= 1e-4 * peak, "max difference {worst}, peak {peak}");
}

// ------------------------------------------------------------ whole scenes

#[test]
fn a_glb_is_a_scene_with_its_camera_lights_and_a_floor() {
    let dir = temp_dir("whole");
    let mut g = Gltf::new();
    let mat = g.material(json!({"name": "white", "pbrMetallicRoughness": {"metallicFactor": 0.0}}));
    let mesh = g.mesh(&shapes::cuboid(Vec3::ZERO, Vec3::ONE), true, Some(mat));
    g.root_node(json!({"mesh": mesh}));
    g.root["cameras"] =
        json!([{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}]);
    // A camera 5 m up +z looking down -z (its node's -z).
    g.root_node(json!({"camera": 0, "translation": [0.5, 0.5, 5.0]}));
    g.root["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    g.root["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "point", "intensity": 20.0 * LUMENS_PER_WATT, "color": [1.0, 0.5, 0.25]},
        {"type": "spot", "intensity": 683.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
        {"type": "directional", "intensity": 1000.0 * LUMENS_PER_WATT}
    ]}});
    g.root_node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}},
                       "translation": [0.0, 3.0, 0.0]}));
    // Rotated -90° about x: its -z turns to -y.
    let down = Quat::from_rotation_x(-90f32.to_radians());
    g.root_node(json!({"extensions": {"KHR_lights_punctual": {"light": 1}},
                       "translation": [1.0, 4.0, 0.0], "rotation": down.to_array()}));
    g.root_node(json!({"extensions": {"KHR_lights_punctual": {"light": 2}},
                       "rotation": down.to_array()}));
    let path = g.write_glb(&dir, "whole");
    let s = Scene::load(&path).unwrap();

    assert!((s.camera.eye - Vec3::new(0.5, 0.5, 5.0)).length() < 1e-6);
    let forward = (s.camera.target - s.camera.eye).normalize();
    assert!((forward - Vec3::NEG_Z).length() < 1e-6);
    assert!((s.camera.fov_y_deg - 0.8f32.to_degrees()).abs() < 1e-4);

    assert_eq!(s.lights.len(), 3);
    let (p, sp, d) = (&s.lights[0], &s.lights[1], &s.lights[2]);
    assert_eq!(p.kind, LightKind::Point);
    assert!(
        (p.intensity - Vec3::new(20.0, 10.0, 5.0))
            .abs()
            .max_element()
            < 1e-4
    );
    assert!((p.position - Vec3::new(0.0, 3.0, 0.0)).length() < 1e-6);
    assert_eq!(sp.kind, LightKind::Spot);
    assert!((sp.intensity - Vec3::ONE).abs().max_element() < 1e-6);
    assert!((sp.direction - Vec3::NEG_Y).length() < 1e-5);
    assert!((sp.cone_angle_deg - 0.6f32.to_degrees()).abs() < 1e-4);
    assert!((sp.cone_falloff_deg - 0.4f32.to_degrees()).abs() < 1e-4);
    assert_eq!(d.kind, LightKind::Directional);
    assert!((d.intensity - Vec3::splat(1000.0)).abs().max_element() < 1e-2);
    assert!((d.direction - Vec3::NEG_Y).length() < 1e-5);

    // The default floor: diffuse, just below the model.
    assert_eq!(s.objects.len(), 2);
    let floor = &s.objects[1];
    let fm = &s.materials[floor.mesh.materials[0] as usize];
    assert_eq!(
        (fm.kind, fm.color),
        (MaterialKind::Diffuse, Vec3::splat(loader::FLOOR_ALBEDO))
    );
    assert!(floor
        .mesh
        .positions
        .iter()
        .all(|p| p.y < 0.0 && p.y > -0.01));
}

/// A GLB's header length is the file's (issue 31: a file longer than its
/// header said was accepted); a shorter one was already refused.
#[test]
fn a_glb_longer_or_shorter_than_its_header_is_refused() {
    let dir = temp_dir("glb-length");
    let mut g = Gltf::new();
    let mesh = g.mesh(&shapes::cuboid(Vec3::splat(-1.0), Vec3::ONE), true, None);
    g.root_node(json!({"mesh": mesh}));
    let path = g.write_glb(&dir, "sized");
    let bytes = std::fs::read(&path).unwrap();
    assert!(Scene::load(&path).is_ok());
    for (name, edited) in [
        ("longer", [&bytes[..], &[0u8; 16]].concat()),
        ("shorter", bytes[..bytes.len() - 4].to_vec()),
    ] {
        let p = dir.join(format!("{name}.glb"));
        std::fs::write(&p, edited).unwrap();
        let e = format!("{:#}", Scene::load(&p).expect_err(name));
        assert!(e.contains(p.to_str().unwrap()) && e.contains("GLB"), "{e}");
        assert_eq!(e.lines().count(), 1, "{e}");
    }
}

#[test]
fn a_file_without_camera_or_lights_gets_a_framing_camera_and_a_sun() {
    let dir = temp_dir("defaults");
    let mut g = Gltf::new();
    let mesh = g.mesh(&shapes::cuboid(Vec3::splat(-1.0), Vec3::ONE), true, None);
    g.root_node(json!({"mesh": mesh, "translation": [2.0, 1.0, 0.0]}));
    let s = Scene::load(&g.write_glb(&dir, "bare")).unwrap();
    assert_eq!(s.lights.len(), 1);
    assert_eq!(s.lights[0].kind, LightKind::Directional);
    assert_eq!(
        s.lights[0].intensity,
        Vec3::splat(loader::DEFAULT_SUN_IRRADIANCE)
    );
    assert!((s.camera.target - Vec3::new(2.0, 1.0, 0.0)).length() < 1e-5);
    // Every corner of the model is inside the view.
    let (view, proj) = caustics::frame::camera_matrices(&s.camera, 1.0);
    for p in &s.objects[0].mesh.positions {
        let c = (proj * view).project_point3(*p);
        assert!(c.x.abs() < 1.0 && c.y.abs() < 1.0, "{p} -> {c}");
    }
}

/// Standard base64 with padding (RFC 4648), for `data:` URIs.
fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                out.push(ABC[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[test]
fn buffers_in_data_uris_load_like_files() {
    let dir = temp_dir("data_uri");
    let mut g = Gltf::new();
    let cube = shapes::cuboid(Vec3::ZERO, Vec3::ONE);
    let mesh = g.mesh(&cube, true, None);
    g.root_node(json!({"mesh": mesh}));
    let from_file = loader::load(&g.write_gltf(&dir, "file")).unwrap();
    let uri = format!("data:application/octet-stream;base64,{}", base64(&g.bin));
    let path = dir.join("embedded.gltf");
    std::fs::write(&path, serde_json::to_vec(&g.finish(Some(&uri))).unwrap()).unwrap();
    let embedded = loader::load(&path).unwrap();
    assert_eq!(embedded.mesh.positions, from_file.mesh.positions);
    assert_eq!(embedded.mesh.indices, cube.indices);
}

// ------------------------------------------------------------ the CLI

fn caustics(args: &[&str]) -> (Option<i32>, String, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_caustics"));
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        c.env(
            "VK_DRIVER_FILES",
            "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json",
        );
    }
    let out = c.args(args).env_remove("RUST_BACKTRACE").output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn render_takes_a_glb_as_the_scene() {
    let dir = temp_dir("cli");
    let mut g = Gltf::new();
    let mat = g.material(json!({"name": "white", "pbrMetallicRoughness": {"metallicFactor": 0.0}}));
    let mesh = g.mesh(&shapes::sphere(Vec3::ZERO, 0.5, 16), true, Some(mat));
    g.root_node(json!({"mesh": mesh}));
    let path = g.write_glb(&dir, "ball");
    let out = dir.join("ball.exr");
    let (code, stdout, stderr) = caustics(&[
        "render",
        "--scene",
        path.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "32",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{stdout}\n{stderr}");
    assert!(out.exists() && dir.join("ball.png").exists());
}

/// A file that is bad at `at`: `edit` breaks an otherwise valid one.
struct Bad {
    name: &'static str,
    at: &'static str,
    says: &'static str,
    edit: fn(&mut Gltf, &Path),
}

fn bad_files() -> Vec<Bad> {
    vec![
        Bad {
            name: "missing_buffer",
            at: "buffers[0].uri",
            says: "cannot read",
            edit: |g, _| g.root["buffers_uri_override"] = json!("gone.bin"),
        },
        // Issue 31: URIs are confined to the glTF file's folder.
        Bad {
            name: "file_scheme_buffer",
            at: "buffers[0].uri",
            says: "a scheme",
            edit: |g, _| g.root["buffers_uri_override"] = json!("file:///etc/passwd"),
        },
        Bad {
            name: "absolute_buffer",
            at: "buffers[0].uri",
            says: "an absolute path",
            edit: |g, _| g.root["buffers_uri_override"] = json!("/etc/passwd"),
        },
        Bad {
            name: "encoded_parent_buffer",
            at: "buffers[0].uri",
            says: "climbs above the folder",
            edit: |g, _| g.root["buffers_uri_override"] = json!("sub/%2e%2e/%2E%2E/passwd"),
        },
        Bad {
            name: "link_outside",
            at: "buffers[0].uri",
            says: "a link that resolves outside the folder",
            edit: |g, dir| {
                let link = dir.join("outside.bin");
                let _ = std::fs::remove_file(&link);
                std::os::unix::fs::symlink("/etc/hostname", &link).unwrap();
                g.root["buffers_uri_override"] = json!("outside.bin");
            },
        },
        Bad {
            name: "parent_image",
            at: "images[0].uri",
            says: "climbs above the folder",
            edit: |g, _| g.root["images"] = json!([{"uri": "../secret.png"}]),
        },
        Bad {
            name: "missing_image",
            at: "images[0].uri",
            says: "not found",
            edit: |g, _| g.root["images"] = json!([{"uri": "missing.png"}]),
        },
        Bad {
            name: "undecodable_image",
            at: "images[0].bufferView",
            says: "cannot decode",
            edit: |g, _| {
                let view = g.view(b"not an image");
                g.root["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
                g.root["textures"] = json!([{"source": 0}]);
                g.root["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
                g.root["meshes"][0]["primitives"][0]["material"] = json!(0);
            },
        },
        Bad {
            name: "accessor_index",
            at: "meshes[0].primitives[0].attributes",
            says: "",
            edit: |g, _| g.root["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(99),
        },
        Bad {
            name: "accessor_past_view",
            at: "meshes[0].primitives[0].attributes.NORMAL",
            says: "bufferView",
            edit: |g, _| {
                let n = g.root["meshes"][0]["primitives"][0]["attributes"]["NORMAL"].clone();
                g.root["accessors"][n.as_u64().unwrap() as usize]["count"] = json!(1000);
            },
        },
        // Issue 31: stride x count wrapped to a small size and passed the
        // bounds check ("POSITION has 0", or the primitive dropped).
        Bad {
            name: "accessor_count_overflow",
            at: "meshes[0].primitives[0].attributes.POSITION",
            says: "bufferView",
            edit: |g, _| {
                let n = g.root["meshes"][0]["primitives"][0]["attributes"]["POSITION"].clone();
                g.root["accessors"][n.as_u64().unwrap() as usize]["count"] = json!(1u64 << 62);
            },
        },
        Bad {
            name: "normal_type",
            at: "meshes[0].primitives[0].attributes.NORMAL",
            says: "expected Vec3",
            edit: |g, _| {
                let n = g.root["meshes"][0]["primitives"][0]["attributes"]["NORMAL"].clone();
                g.root["accessors"][n.as_u64().unwrap() as usize]["type"] = json!("VEC2");
            },
        },
        Bad {
            name: "index_range",
            at: "meshes[0].primitives[0].indices",
            says: "out of range",
            edit: |g, _| {
                let n = g.root["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap();
                let view = g.root["accessors"][n as usize]["bufferView"].as_u64().unwrap();
                let off = g.root["bufferViews"][view as usize]["byteOffset"].as_u64().unwrap();
                g.bin[off as usize..off as usize + 4].copy_from_slice(&1000u32.to_le_bytes());
            },
        },
        Bad {
            name: "lines",
            at: "meshes[0].primitives[0].mode",
            says: "only TRIANGLES",
            edit: |g, _| g.root["meshes"][0]["primitives"][0]["mode"] = json!(1),
        },
        Bad {
            name: "nan_position",
            at: "meshes[0].primitives[0].attributes.POSITION",
            says: "not finite",
            edit: |g, _| {
                let n = g.root["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
                    .as_u64()
                    .unwrap();
                let view = g.root["accessors"][n as usize]["bufferView"].as_u64().unwrap();
                let off = g.root["bufferViews"][view as usize]["byteOffset"].as_u64().unwrap();
                let o = off as usize + 12 * 2 + 4;
                g.bin[o..o + 4].copy_from_slice(&f32::NAN.to_le_bytes());
            },
        },
        Bad {
            name: "cycle",
            at: "nodes[0]",
            says: "strict trees",
            edit: |g, _| g.root["nodes"][0]["children"] = json!([0]),
        },
        Bad {
            name: "too_many_lights",
            at: "extensions.KHR_lights_punctual",
            says: "at most 8",
            edit: |g, _| {
                g.root["extensions"] = json!({"KHR_lights_punctual": {"lights": [
                    {"type": "point", "intensity": 1.0}]}});
                for _ in 0..9 {
                    g.root_node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}}));
                }
            },
        },
        // Issue 31: values outside the extensions' schemas and the scene
        // bounds were accepted (clamped, or an all-black image).
        Bad {
            name: "negative_light",
            at: "extensions.KHR_lights_punctual.lights[0]",
            says: "must be 0 or more",
            edit: |g, _| {
                g.root["extensions"] = json!({"KHR_lights_punctual": {"lights": [
                    {"type": "point", "intensity": -5.0}]}});
                g.root_node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}}));
            },
        },
        Bad {
            name: "light_far_away",
            at: "light[0]",
            says: "beyond",
            edit: |g, _| {
                // A diffuse material: the default one's warning is a line of its own.
                g.root["materials"] = json!([{"pbrMetallicRoughness": {"metallicFactor": 0.0}}]);
                g.root["meshes"][0]["primitives"][0]["material"] = json!(0);
                g.root["extensions"] = json!({"KHR_lights_punctual": {"lights": [
                    {"type": "point", "intensity": 5.0}]}});
                g.root_node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}},
                                   "translation": [1e20, 0.0, 0.0]}));
            },
        },
        Bad {
            name: "camera_far_away",
            at: "camera",
            says: "beyond",
            edit: |g, _| {
                // A diffuse material: the default one's warning is a line of its own.
                g.root["materials"] = json!([{"pbrMetallicRoughness": {"metallicFactor": 0.0}}]);
                g.root["meshes"][0]["primitives"][0]["material"] = json!(0);
                g.root["cameras"] =
                    json!([{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}]);
                g.root_node(json!({"camera": 0, "translation": [0.0, 0.0, 1e20]}));
            },
        },
        Bad {
            name: "attenuation_distance_zero",
            at: "materials[0].extensions.KHR_materials_volume.attenuationDistance",
            says: "must be above 0",
            edit: |g, _| {
                g.root["materials"] = json!([{"extensions": {
                    "KHR_materials_transmission": {"transmissionFactor": 1.0},
                    "KHR_materials_volume": {"thicknessFactor": 0.5, "attenuationDistance": 0.0}}}]);
                g.root["meshes"][0]["primitives"][0]["material"] = json!(0);
            },
        },
        Bad {
            name: "draco",
            at: "extensionsRequired[0]",
            says: "KHR_draco_mesh_compression (compressed geometry) is not supported: the file must be decompressed",
            edit: |g, _| {
                g.root["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
                g.root["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
            },
        },
        Bad {
            name: "meshopt",
            at: "extensionsRequired[1]",
            says: "EXT_meshopt_compression (compressed geometry) is not supported: the file must be decompressed",
            edit: |g, _| {
                g.root["extensionsUsed"] = json!(["KHR_lights_punctual", "EXT_meshopt_compression"]);
                g.root["extensionsRequired"] = json!(["KHR_lights_punctual", "EXT_meshopt_compression"]);
            },
        },
    ]
}

/// Writes the cube file with `bad` applied.
fn write_bad(dir: &Path, bad: &Bad) -> PathBuf {
    let mut g = Gltf::new();
    let mesh = g.mesh(&shapes::cuboid(Vec3::ZERO, Vec3::ONE), true, None);
    g.root_node(json!({"mesh": mesh}));
    (bad.edit)(&mut g, dir);
    let uri = g
        .root
        .as_object_mut()
        .unwrap()
        .remove("buffers_uri_override");
    let path = g.write_gltf(dir, bad.name);
    if let Some(uri) = uri {
        let mut root: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        root["buffers"][0]["uri"] = uri;
        std::fs::write(&path, serde_json::to_vec(&root).unwrap()).unwrap();
    }
    path
}

fn assert_one_line_failure(code: Option<i32>, stdout: &str, stderr: &str, needles: &[&str]) {
    let what = format!("exit {code:?}\n--- stdout\n{stdout}\n--- stderr\n{stderr}");
    assert_eq!(code, Some(1), "{what}");
    assert!(stderr.starts_with("error: "), "{what}");
    assert_eq!(stderr.lines().count(), 1, "{what}");
    assert!(!stderr.contains("panicked"), "{what}");
    for n in needles {
        assert!(stderr.contains(n), "expected `{n}`: {what}");
    }
}

#[test]
fn bad_files_fail_with_one_line_naming_the_file_and_the_gltf_path() {
    let dir = temp_dir("bad");
    for bad in bad_files() {
        let path = write_bad(&dir, &bad);
        let p = path.to_str().unwrap();
        let out = dir.join(format!("{}.png", bad.name));
        let (code, stdout, stderr) =
            caustics(&["render", "--scene", p, "--out", out.to_str().unwrap()]);
        let mut needles = vec![p, bad.at];
        if !bad.says.is_empty() {
            needles.push(bad.says);
        }
        assert_one_line_failure(code, &stdout, &stderr, &needles);
        assert!(!out.exists(), "{}", bad.name);
    }

    // The same through a TOML scene's `shape = "gltf"`: located at the
    // object's `path`, then the file and the glTF path.
    let bad = &bad_files()[13];
    write_bad(&dir, bad);
    let scene = dir.join("scene.toml");
    let text = format!(
        "{SCENE_HEAD}\n[[object]]\nshape = \"gltf\"\npath = \"{}.gltf\"\n",
        bad.name
    );
    let line = text.lines().position(|l| l.starts_with("path =")).unwrap() + 1;
    std::fs::write(&scene, text).unwrap();
    let (code, stdout, stderr) = caustics(&["render", "--scene", scene.to_str().unwrap()]);
    let file = dir.join(format!("{}.gltf", bad.name));
    assert_one_line_failure(
        code,
        &stdout,
        &stderr,
        &[
            &format!("{}:{line}:", scene.display()),
            "object[1].path",
            file.to_str().unwrap(),
            bad.at,
        ],
    );
}
