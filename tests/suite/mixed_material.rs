//! The `mixed` material (docs/SCENES.md): a Lambertian part of albedo `a`
//! plus a perfect mirror of reflectance `ρ`, a + ρ <= 1 per channel. Its
//! scene-file validation, and the reference against analytic answers for
//! each of its lobes, on the camera side and on the light side; `direct`
//! renders its diffuse part. Measurements (lavapipe, Mesa 22.3.6, 32²):
//! - mixed_floor_under_a_constant_sky (a = 0.3, ρ = 0.5, L = 1, 2M photons):
//!   the whole frame (a + ρ) L: +0.02% (bound 1.5%); the emitted component
//!   (the sky in the mirror part) ρ L: exact (bound 1e-4); `direct` a L:
//!   +0.003% (bound 1%).
//! - mixed_plate_reflects_its_mirror_part (a 45° plate, a = 0.3, ρ = 0.6,
//!   the sun straight down, E = 10, onto a wall of albedo 0.5; 4M photons):
//!   the wall's L S+ D over the patch's centre against albedo/π ρ E: -0.35%
//!   (bound 3%).

use crate::common;

use caustics::params::{ParamSet, Params};
use caustics::reference::Component;
use caustics::renderer::Renderer;
use caustics::scene::{MaterialKind, Scene};
use caustics::techniques;
use common::*;
use glam::Vec3;
use std::path::Path;

const SIZE: u32 = 32;

fn load(text: &str) -> Scene {
    Scene::from_str(text, Path::new("mixed.toml")).unwrap()
}

/// Mean of rgb over the pixels `keep` selects, per channel averaged.
fn mean(img: &[f32], keep: impl Fn(usize, usize) -> bool) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for y in 0..SIZE as usize {
        for x in 0..SIZE as usize {
            if keep(x, y) {
                sum += sum_rgb(img, y * SIZE as usize + x) / 3.0;
                n += 1;
            }
        }
    }
    assert!(n > 0);
    sum / n as f64
}

#[test]
fn mixed_materials_parse_and_bad_ones_are_refused() {
    let head = "[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n\
                [[light]]\nkind = \"point\"\nposition = [0.0, 5.0, 0.0]\nintensity = 10.0\n";
    let body = |material: &str| {
        format!(
            "{head}[[material]]\nname = \"cup\"\nkind = \"mixed\"\n{material}\n\
             [[object]]\nshape = \"plane\"\nsize = [1.0, 1.0]\nmaterial = \"cup\"\n"
        )
    };
    let s = load(&body("reflectance = [0.6, 0.5, 0.4]\nalbedo = 0.3"));
    let m = &s.materials[0];
    assert_eq!(m.kind, MaterialKind::Diffuse);
    assert_eq!(m.specular, Vec3::new(0.6, 0.5, 0.4));
    assert_eq!(m.color, Vec3::splat(0.3));
    // (material text, field, words in the message)
    let cases = [
        (
            "reflectance = 0.8\nalbedo = [0.1, 0.3, 0.1]",
            "albedo",
            "reflectance + albedo must be at most 1",
        ),
        (
            "reflectance = 1.2\nalbedo = 0.0",
            "reflectance",
            "within [0, 1]",
        ),
        ("reflectance = 0.5\nalbedo = -0.1", "albedo", "negative"),
        ("reflectance = 0.5\nior = 1.5", "ior", "mixed material"),
    ];
    for (material, field, words) in cases {
        let text = body(material);
        let e = Scene::from_str(&text, Path::new("mixed.toml")).expect_err(material);
        let msg = e.to_string();
        println!("{msg}");
        assert!(e.field().is_some_and(|f| f.ends_with(field)), "{msg}");
        assert!(e.line().is_some(), "{msg}");
        assert!(msg.contains("mixed.toml"), "{msg}");
        assert!(msg.contains(words), "expected `{words}` in `{msg}`");
        assert_eq!(msg.lines().count(), 1, "{msg}");
    }
}

/// A mixed floor under a constant sky (L = 1, no sun), seen from above: its
/// diffuse part receives E = π L and sends a L, its mirror part shows the
/// sky, ρ L: every pixel is (a + ρ) L. The camera side follows the mirror
/// part from the first hit (the emitted component); the light tracer
/// connects the diffuse part. `direct` renders the diffuse part, a L (its
/// order-2 SH irradiance is exact for a constant sky).
#[test]
fn mixed_floor_under_a_constant_sky() {
    let (a, rho) = (0.3, 0.5);
    let text = format!(
        "[camera]\neye = [0.0, 2.0, 2.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40\n\
         [[light]]\nkind = \"environment\"\nsky = {{ sun_direction = [0.0, 1.0, 0.0], sun_radius = 1.0, sun_radiance = 0.0, zenith = 1.0, horizon = 1.0 }}\n\
         [[material]]\nname = \"floor\"\nkind = \"mixed\"\nreflectance = {rho}\nalbedo = {a}\n\
         [[object]]\nshape = \"plane\"\nsize = [20.0, 20.0]\nmaterial = \"floor\"\n"
    );
    let ctx = validated_context();
    let reference = traced_reference(&ctx, &load(&text), SIZE, 2_000_000);
    let all = reference.whole(Component::All);
    let emitted = reference.whole(Component::Emitted);
    assert_finite(all);
    let every = |_, _| true;
    let rel_all = mean(all, every) / (a + rho) - 1.0;
    let rel_emitted = mean(emitted, every) / rho - 1.0;
    let params = Params::resolve("direct", techniques::direct::DirectParams::specs(), &[]).unwrap();
    let direct = {
        let mut r = Renderer::new(&ctx, load(&text), "direct", &params, SIZE, SIZE, 0.0).unwrap();
        r.render_frame(0.0).unwrap();
        r.radiance().unwrap()
    };
    let rel_direct = mean(&direct, every) / a - 1.0;
    println!(
        "reference all {rel_all:+.5} of (a + ρ) L, emitted {rel_emitted:+.6} of ρ L; direct {rel_direct:+.5} of a L"
    );
    assert!(
        rel_all.abs() < 0.015,
        "reference: (a + ρ) L off by {rel_all:+.5}"
    );
    assert!(
        rel_emitted.abs() < 1e-4,
        "reference: ρ L off by {rel_emitted:+.6}"
    );
    assert!(
        rel_direct.abs() < 0.01,
        "direct: a L off by {rel_direct:+.5}"
    );
    assert_validation_clean(&ctx);
}

/// A 1 m² mixed plate tilted 45° under the sun (straight down, E = 10)
/// reflects its mirror part along +x onto a wall 2 m away (albedo 0.5)
/// seen squarely by a camera at x = 1 (pinhole's flat-mirror scene): inside
/// the reflected patch the wall's L S+ D radiance is albedo/π ρ E. The
/// light tracer continues by the mirror part with probability lum(ρ) and
/// weight ρ / lum(ρ).
#[test]
fn mixed_plate_reflects_its_mirror_part() {
    let (a, rho, e, wall) = (0.3, 0.6, 10.0, 0.5);
    let text = format!(
        "[camera]\neye = [1.0, 0.0, 0.0]\ntarget = [2.0, 0.0, 0.0]\nfov_y = 90\n\
         [[light]]\nkind = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = {e}\n\
         [[material]]\nname = \"plate\"\nkind = \"mixed\"\nreflectance = {rho}\nalbedo = {a}\n\
         [[material]]\nname = \"wall\"\nkind = \"diffuse\"\nalbedo = {wall}\n\
         [[object]]\nshape = \"plane\"\nnormal = [1.0, 1.0, 0.0]\nsize = [1.0, 1.0]\ntangent = [0.0, 0.0, 1.0]\nmaterial = \"plate\"\n\
         [[object]]\nshape = \"plane\"\ncenter = [2.0, 0.0, 0.0]\nnormal = [-1.0, 0.0, 0.0]\nsize = [4.0, 4.0]\nmaterial = \"wall\"\n"
    );
    let ctx = validated_context();
    let reference = traced_reference(&ctx, &load(&text), SIZE, 4_000_000);
    let caustic = reference.whole(Component::SurfaceCaustics);
    assert_finite(caustic);
    // Pixel (x, y) sees the wall at (y, z) = (1 - (y + 1/2) 2 / size,
    // (x + 1/2) 2 / size - 1); the patch is |y| < 0.354, |z| < 0.5.
    let centre = |x: usize, y: usize| {
        let wy = 1.0 - (y as f64 + 0.5) * 2.0 / SIZE as f64;
        let wz = (x as f64 + 0.5) * 2.0 / SIZE as f64 - 1.0;
        wy.abs() < 0.15 && wz.abs() < 0.25
    };
    let expected = wall / std::f64::consts::PI * rho * e;
    let rel = mean(caustic, centre) / expected - 1.0;
    println!("wall's L S+ D over the patch's centre: {rel:+.4} of albedo/π ρ E");
    assert!(rel.abs() < 0.03, "mirror part off by {rel:+.4}");
    assert_validation_clean(&ctx);
}

/// No technique drops a mixed surface's mirror part silently: those that
/// trace caustics from mirrors and glass only refuse the scene (one line
/// naming the file and the material); pinhole, which renders both parts,
/// and direct, which renders no specular light, accept it. The same scene
/// with the material plain diffuse is accepted by all (the refusal is the
/// mirror part's).
#[test]
fn techniques_without_a_mirror_part_refuse_mixed_materials() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cup.toml");
    let cup = Scene::load(&path).unwrap();
    assert!(techniques::has_mixed(&cup));
    let mut plain = cup.clone();
    for m in &mut plain.materials {
        m.specular = Vec3::ZERO;
    }
    assert!(!techniques::has_mixed(&plain));
    for name in ["image_space", "volume_lines", "water_photons", "beams"] {
        let info = techniques::find(name).unwrap();
        let e = (info.check_scene)(&cup).expect_err(name).to_string();
        assert!(
            e.starts_with(&path.display().to_string())
                && e.contains("material `metal`")
                && e.contains("mixed")
                && e.contains(name),
            "{e}"
        );
        assert_eq!(e.lines().count(), 1, "{e}");
        if name != "water_photons" {
            // (water_photons refuses the cup anyway: it has no water.)
            (info.check_scene)(&plain).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
    for name in ["pinhole", "direct"] {
        (techniques::find(name).unwrap().check_scene)(&cup).unwrap();
    }
}
