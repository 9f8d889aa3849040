//! Sphere lights with `animate` (docs/SCENES.md, "Area lights"): the
//! emitter moves with its geometry, on the host (`Scene::emitter_at`) and
//! on the GPU (the area-light buffer re-uploaded with the triangles each
//! frame), so a frame at time t equals the frame of the same scene with the
//! light placed where the motion puts it. `assets/scenes/moving_lights.toml`
//! is the paper's dynamic-lighting scene (Wand & Straßer 2003, Fig. 7c).

use crate::common;

use caustics::params::Params;
use caustics::renderer::Renderer;
use caustics::scene::{EmitterShape, Scene};
use caustics::techniques;
use common::*;
use glam::Vec3;
use std::path::Path;

fn centre(s: &Scene, i: usize, t: f32) -> Vec3 {
    match s.emitter_at(i, t).shape {
        EmitterShape::Sphere { center, .. } => center,
        EmitterShape::Rect { .. } => panic!("light {i} is a rect"),
    }
}

#[test]
fn sphere_lights_follow_their_motion() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/moving_lights.toml");
    let s = Scene::load(&path).unwrap();
    assert!(s.is_animated());
    // The orbit: orbit_center + 3.5 (cos a, 0, -sin a), a = 30°/s · t.
    assert!(centre(&s, 0, 0.0).distance(Vec3::new(3.5, 1.0, 0.0)) < 1e-5);
    assert!(centre(&s, 0, 3.0).distance(Vec3::new(0.0, 1.0, -3.5)) < 1e-5);
    // The bob: 0.6 sin(2π 0.25 t), a quarter period at t = 1.
    assert!(centre(&s, 1, 1.0).distance(Vec3::new(-2.5, 2.2, -1.5)) < 1e-5);
    // Its geometry goes along: the light's triangles are centred on it.
    let object = s.emitters[0].object;
    let tris: Vec<_> = s
        .triangles(3.0)
        .into_iter()
        .filter(|t| t.object == object)
        .collect();
    let mean = tris.iter().flat_map(|t| t.positions).sum::<Vec3>() / (3 * tris.len()) as f32;
    assert!(mean.distance(centre(&s, 0, 3.0)) < 1e-3, "{mean}");
    // A rect light takes no `animate`: one line naming the field.
    let text = "[camera]\neye = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n\
                [[light]]\nkind = \"rect\"\ncenter = [0.0, 1.0, 0.0]\nnormal = [0.0, -1.0, 0.0]\nsize = [0.2, 0.2]\nradiance = 10.0\nanimate = { bob_amplitude = 0.1, bob_frequency = 1.0 }\n";
    let e = Scene::from_str(text, Path::new("rect.toml")).expect_err("animated rect");
    let msg = e.to_string();
    assert!(
        msg.starts_with("rect.toml:") && msg.contains("animate"),
        "{msg}"
    );
    assert_eq!(msg.lines().count(), 1, "{msg}");
}

const GEOMETRY: &str = "[camera]\neye = [0.0, 4.0, 2.5]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40\n\
[[material]]\nname = \"chrome\"\nkind = \"mirror\"\nreflectance = 0.95\n\
[[material]]\nname = \"floor\"\nkind = \"diffuse\"\nalbedo = 0.8\n\
[[object]]\nshape = \"cylinder\"\np0 = [0.0, 0.0, 0.0]\np1 = [0.0, 0.5, 0.0]\nradius = 1.0\ncaps = false\nsegments = 64\nmaterial = \"chrome\"\n\
[[object]]\nshape = \"plane\"\nsize = [10.0, 10.0]\nmaterial = \"floor\"\n";

/// `direct` and `pinhole` (whose light cube maps are rendered from the
/// area-light buffer every frame) of a sphere light orbiting the ring,
/// built at time 0 and rendered at t = 3 s, against the same scene with
/// the light standing where the orbit puts it then, (0, 1, -3.5). `direct`
/// agrees to float noise (measured 1.8e-7 of the peak). pinhole draws its
/// sample points from the triangles in BVH leaf order, which differs
/// between the refitted tree and one built with the light standing, so its
/// two frames are two samplings of the same caustic: compared by relative
/// energy (measured -0.01%, bound 2%) and FLIP (measured 0.040, bound 0.06).
/// The frame at t = 0 differs from them by far more.
#[test]
fn a_moving_sphere_light_renders_where_it_is() {
    let ctx = validated_context();
    let size = 32;
    let light = |fields: &str| {
        format!(
            "{GEOMETRY}[[light]]\nkind = \"sphere\"\nradius = 0.15\nradiance = 150.0\n{fields}\n"
        )
    };
    let moving = light(
        "center = [0.0, 0.0, 0.0]\nanimate = { orbit_center = [0.0, 1.0, 0.0], orbit_radius = 3.5, orbit_speed = 30.0 }",
    );
    let standing = light("center = [0.0, 1.0, -3.5]");
    for technique in ["direct", "pinhole"] {
        let specs = techniques::find(technique).unwrap().params();
        let params = Params::resolve(technique, specs, &[]).unwrap();
        let frame = |text: &str, t: f32| {
            let scene = Scene::from_str(text, Path::new("moving.toml")).unwrap();
            let mut r = Renderer::new(&ctx, scene, technique, &params, size, size, 0.0).unwrap();
            r.render_frame(t).unwrap();
            r.radiance().unwrap()
        };
        let (at_3, there, at_0) = (
            frame(&moving, 3.0),
            frame(&standing, 0.0),
            frame(&moving, 0.0),
        );
        assert_finite(&at_3);
        let peak = there.iter().cloned().fold(0.0f32, f32::max);
        let same = max_difference(&at_3, &there) / peak;
        let moved = max_difference(&at_0, &there) / peak;
        let energy_error = energy(&at_3) / energy(&there) - 1.0;
        let (flip_mean, _) = flip(&tonemap(&at_3), &tonemap(&there), size);
        let (flip_moved, _) = flip(&tonemap(&at_0), &tonemap(&there), size);
        println!(
            "{technique}: frame(t = 3) vs frame(light placed): max difference {same:.2e} of the peak, energy {energy_error:+.4}, FLIP {flip_mean:.4}; frame(t = 0): {moved:.2e}, FLIP {flip_moved:.4}"
        );
        if technique == "direct" {
            assert!(same < 1e-4, "{technique}: {same:e}");
        } else {
            assert!(
                energy_error.abs() < 0.02,
                "{technique}: energy {energy_error:+.4}"
            );
            assert!(flip_mean < 0.06, "{technique}: FLIP {flip_mean:.4}");
        }
        assert!(
            moved > 0.1 && flip_moved > 2.0 * flip_mean.max(0.01),
            "{technique}: the light did not matter ({moved:e}, FLIP {flip_moved})"
        );
    }
    assert_validation_clean(&ctx);
}
