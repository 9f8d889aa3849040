//! `direct` with environment and area lights against the ground truth on a
//! diffuse scene (floor, box, sphere), one light kind at a time: the sun and
//! sky, a rect lamp, a sphere lamp; and on `ring_sky`. `direct`'s approximations
//! (docs/ARCHITECTURE.md, "Environment and area lights in direct"): the sky
//! by order-2 SH irradiance times a visibility from `sky_rays` BVH rays, the sun and each lamp with
//! one hard shadow ray to its centre. Compared: the whole frame (direct +
//! emitted; the reference's `all`, no diffuse bounces) by relative total
//! energy and FLIP mean (nv-flip, 67 px/degree) of the tonemapped images.
//! Measurements and bounds in BENCHMARKS.md ("direct with environment and
//! area lights"); the images (actual, reference, FLIP map) are written to
//! `$CARGO_TARGET_TMPDIR/test-output/` every run. 64², 2 M photons each.

use crate::common;

use caustics::params::{ParamSet, Params};
use caustics::reference::Component;
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::techniques;
use common::*;
use std::path::Path;

const SIZE: u32 = 64;
const PHOTONS: u64 = 2_000_000;

const GEOMETRY: &str = "[camera]\neye = [0.0, 2.2, 3.2]\ntarget = [0.0, 0.4, 0.0]\nfov_y = 50\n\
[[material]]\nname = \"floor\"\nkind = \"diffuse\"\nalbedo = 0.7\n\
[[material]]\nname = \"grey\"\nkind = \"diffuse\"\nalbedo = 0.5\n\
[[object]]\nshape = \"plane\"\nsize = [4.0, 4.0]\nmaterial = \"floor\"\n\
[[object]]\nshape = \"box\"\nmin = [-0.9, 0.0, -0.6]\nmax = [-0.3, 0.8, 0.0]\nmaterial = \"grey\"\n\
[[object]]\nshape = \"sphere\"\ncenter = [0.6, 0.4, 0.2]\nradius = 0.4\nmaterial = \"grey\"\n";

/// `direct`'s frame of `scene` with parameter `overrides`.
fn render_direct(
    ctx: &std::sync::Arc<caustics::vk::Context>,
    scene: Scene,
    overrides: &[String],
    components: u32,
) -> Vec<f32> {
    let params = Params::resolve(
        "direct",
        techniques::direct::DirectParams::specs(),
        overrides,
    )
    .unwrap();
    let mut r = Renderer::new(ctx, scene, "direct", &params, SIZE, SIZE, 0.0).unwrap();
    r.scene_gpu.components = components;
    r.render_frame(0.0).unwrap();
    r.radiance().unwrap()
}

/// Renders `direct` and the reference for `light` over the geometry and
/// returns (relative energy error, FLIP mean); prints `direct`'s energy
/// error without sky occlusion (`sky_rays` = 0) too.
fn compare(name: &str, light: &str) -> (f64, f32) {
    let ctx = validated_context();
    let text = format!("{GEOMETRY}\n{light}");
    let load = || Scene::from_str(&text, Path::new("direct_lights.toml")).unwrap();
    let all = caustics::radiometry::Component::All.mask();
    let actual = render_direct(&ctx, load(), &[], all);
    let unoccluded = render_direct(&ctx, load(), &["sky_rays=0".to_string()], all);
    assert_finite(&actual);
    let reference = reference_images(&ctx, &ReferenceRequest::new(&load(), SIZE, PHOTONS));
    let truth = reference.whole(Component::All).to_vec();
    assert_finite(&truth);
    let energy_unoccluded = energy(&unoccluded) / energy(&truth) - 1.0;
    let energy = energy(&actual) / energy(&truth) - 1.0;
    eprintln!("{name}: without sky occlusion: energy {energy_unoccluded:+.4}");
    let (actual_ldr, truth_ldr) = (tonemap(&actual), tonemap(&truth));
    let (flip_mean, map) = flip(&actual_ldr, &truth_ldr, SIZE);
    eprintln!("{name}: energy {energy:+.4}, FLIP mean {flip_mean:.4}");
    assert_validation_clean(&ctx);
    let dir = write_comparison_pngs(
        &format!("direct_lights_{name}"),
        SIZE,
        &actual_ldr,
        &truth_ldr,
        &map,
    );
    eprintln!("actual, reference and FLIP map in {dir}");
    (energy, flip_mean)
}

#[test]
fn direct_with_sun_and_sky_against_the_reference() {
    let (energy, flip) = compare(
        "sky",
        "[[light]]\nkind = \"environment\"\nsky = { sun_direction = [0.5, 1.0, 0.3], sun_radius = 2.0, sun_radiance = 800.0, zenith = [0.15, 0.25, 0.45], horizon = [0.35, 0.35, 0.35] }\n",
    );
    // Measured +0.0045, 0.032 (without sky occlusion, `sky_rays` = 0:
    // +0.033, 0.055: the sky lit the floor next to the box and under the
    // sphere unoccluded).
    assert!(energy.abs() < 0.025, "energy {energy}");
    assert!(flip < 0.045, "FLIP {flip}");
}

#[test]
fn direct_with_a_rect_light_against_the_reference() {
    let (energy, flip) = compare(
        "rect",
        "[[light]]\nkind = \"rect\"\ncenter = [0.0, 1.6, 0.0]\nnormal = [0.0, -1.0, 0.0]\nsize = [0.4, 0.4]\nradiance = 30.0\n",
    );
    // Measured +0.009, 0.037: hard shadows from the lamp's centre.
    assert!(energy.abs() < 0.025, "energy {energy}");
    assert!(flip < 0.055, "FLIP {flip}");
}

#[test]
fn direct_with_a_sphere_light_against_the_reference() {
    let (energy, flip) = compare(
        "sphere",
        "[[light]]\nkind = \"sphere\"\ncenter = [0.0, 1.2, 0.6]\nradius = 0.15\nradiance = 40.0\n",
    );
    // Measured +0.036, 0.042: hard shadows, and the clamped irradiance
    // where the grey sphere's horizon cuts the lamp.
    assert!(energy.abs() < 0.06, "energy {energy}");
    assert!(flip < 0.06, "FLIP {flip}");
}

#[test]
fn direct_with_the_sky_image_against_the_reference() {
    // assets/scenes/environments/sky.hdr (relative to the scene's source,
    // `direct_lights.toml` in the working directory, the checkout): `direct`
    // takes the sun it finds in the image as a directional light and the
    // rest of the image by SH.
    let (energy, flip) = compare(
        "image",
        "[[light]]\nkind = \"environment\"\npath = \"assets/scenes/environments/sky.hdr\"\nscale = 0.005\n",
    );
    // Measured +0.0079, 0.053 (without sky occlusion +0.022, 0.057).
    assert!(energy.abs() < 0.03, "energy {energy}");
    assert!(flip < 0.07, "FLIP {flip}");
}

/// `ring_sky` (the mirror ring on a floor under sky.hdr): `direct`'s L D
/// on the floor against the reference's, with and without the sky's
/// occlusion (`sky_rays`): the ring hides part of the sky from the floor
/// inside and around it. Measurements in BENCHMARKS.md ("direct with
/// environment and area lights"); bounds from them.
#[test]
fn direct_on_ring_sky_with_sky_occlusion() {
    use caustics::radiometry::Component as C;
    let ctx = validated_context();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ring_sky.toml");
    let scene = Scene::load(&path).unwrap();
    let exposure = scene.output.exposure;
    let mask = first_hit_mask(&scene, SIZE, false, |k| {
        k == caustics::scene::MaterialKind::Diffuse
    });
    let reference = traced_reference(&ctx, &scene, SIZE, PHOTONS);
    let truth = masked(reference.whole(Component::Direct), &mask);
    let ldr = |img: &[f32]| caustics::compare::metrics::tonemap(img, exposure);
    let truth_ldr = ldr(&truth);
    let mut results = Vec::new();
    for rays in [0, 16] {
        let img = render_direct(
            &ctx,
            scene.clone(),
            &[format!("sky_rays={rays}")],
            C::Direct.mask(),
        );
        let img = masked(&img, &mask);
        assert_finite(&img);
        let e = energy(&img) / energy(&truth) - 1.0;
        let img_ldr = ldr(&img);
        let (f, map) = flip(&img_ldr, &truth_ldr, SIZE);
        eprintln!("ring_sky, sky_rays = {rays}: energy {e:+.4}, FLIP mean {f:.4}");
        write_comparison_pngs(
            &format!("direct_ring_sky_rays{rays}"),
            SIZE,
            &img_ldr,
            &truth_ldr,
            &map,
        );
        results.push((e, f));
    }
    // Measured: unoccluded +0.038, FLIP 0.162; 16 rays +0.0084, 0.130
    // (part of the FLIP is the reference's noise at 2M photons).
    let (e, f) = results[1];
    assert!(
        e.abs() < 0.03 && f < 0.16,
        "ring_sky with sky occlusion: energy {e:+.4} (bound 0.03), FLIP {f:.4} (bound 0.16)"
    );
    assert_validation_clean(&ctx);
}

/// A sky's sun stands for a directional light of E = L 2π(1 − cos α)
/// (docs/SCENES.md): `water_photons` on the pool lit by a black sky with a
/// sun of that E draws the same caustics as under the directional light.
#[test]
fn water_photons_takes_the_sky_sun_as_its_directional_light() {
    use caustics::radiometry::Component;
    let ctx = validated_context();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/water_pool.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let omega = 2.0 * std::f64::consts::PI * (1.0 - 0.5f64.to_radians().cos());
    let sky = format!(
        "[[light]]\nkind = \"environment\"\nsky = {{ sun_direction = [0.35, 1.0, 0.45], sun_radius = 0.5, sun_radiance = [{}, {}, {}], zenith = 0.0, horizon = 0.0 }}\n",
        1000.0 / omega,
        980.0 / omega,
        950.0 / omega
    );
    let directional = "[[light]]\nkind = \"directional\"\ndirection = [-0.35, -1.0, -0.45]\nirradiance = [1000.0, 980.0, 950.0]\n";
    assert!(text.contains(directional));
    let params = Params::resolve(
        "water_photons",
        techniques::water_photons::WaterPhotonsParams::specs(),
        &[],
    )
    .unwrap();
    let caustics = |text: &str| {
        let scene = Scene::from_str(text, &path).unwrap();
        let mut r = Renderer::new(&ctx, scene, "water_photons", &params, 48, 48, 0.0).unwrap();
        r.scene_gpu.components = Component::SurfaceCaustics.mask();
        r.render_frame(0.0).unwrap();
        energy(&r.radiance().unwrap())
    };
    let under_light = caustics(&text);
    let under_sky = caustics(&text.replace(directional, &sky));
    let rel = under_sky / under_light - 1.0;
    eprintln!("caustic energy: directional {under_light:.3}, sky sun {under_sky:.3} ({rel:+.2e})");
    assert!(under_light > 0.0 && rel.abs() < 1e-3, "{rel}");
    assert_validation_clean(&ctx);
}

/// `image_space` treats a small rect light as a spot at its centre with the
/// cosine profile (I = L A cos θ): on `ball_lens` with the point light
/// replaced by a 5 cm rect of the same I₀ = L A, its surface caustic
/// against the reference's L S+ D (64², 2 M photons), next to the same
/// comparison with the point light. Too large a rect, or a sphere light,
/// is refused.
#[test]
fn image_space_caustics_from_a_small_rect_light() {
    use caustics::radiometry::Component;
    let ctx = validated_context();
    let point = BALL_LENS_POINT_LIGHT;
    let rect = ball_lens_rect_light;
    let scene = ball_lens_with_light;
    let params = Params::resolve(
        "image_space",
        techniques::image_space::ImageSpaceParams::specs(),
        &[],
    )
    .unwrap();
    let measure = |light: &str| {
        let actual = {
            let mut r =
                Renderer::new(&ctx, scene(light), "image_space", &params, SIZE, SIZE, 0.0).unwrap();
            r.scene_gpu.components = Component::SurfaceCaustics.mask();
            r.render_frame(0.0).unwrap();
            r.radiance().unwrap()
        };
        let reference = traced_reference(&ctx, &scene(light), SIZE, 2_000_000);
        let truth = reference.whole(Component::SurfaceCaustics);
        let energy = energy(&actual) / energy(truth) - 1.0;
        let (flip_mean, _) = flip(&tonemap(&actual), &tonemap(truth), SIZE);
        (energy, flip_mean)
    };
    let (energy, flip_mean) = measure(&rect(0.05));
    let (point_energy, point_flip) = measure(point);
    eprintln!(
        "rect stand-in caustic: energy {energy:+.4}, FLIP mean {flip_mean:.4}; the point light itself: {point_energy:+.4}, {point_flip:.4}"
    );
    // Measured at 4 M photons: rect −0.143, FLIP 0.020; point −0.150,
    // 0.014; at 2 M (since 2026-12-03): −0.139, 0.023; −0.145, 0.016. At 64²
    // image_space itself is 15% under the reference with the point light
    // (−1.5% at 128², BENCHMARKS.md): the stand-in must match that.
    assert!(
        (energy - point_energy).abs() < 0.02,
        "{energy} vs {point_energy}"
    );
    assert!(flip_mean < 0.035, "FLIP {flip_mean}");

    // A rect of 2 m at 6.4 m from the lens: beyond the size limit.
    let err = Renderer::new(
        &ctx,
        scene(&rect(2.0)),
        "image_space",
        &params,
        SIZE,
        SIZE,
        0.0,
    )
    .err()
    .expect("refused");
    assert!(
        format!("{err:#}").contains("treats rect lights as points"),
        "{err:#}"
    );
    let sphere = "[[light]]\nkind = \"sphere\"\ncenter = [0.0, 8.0, 0.0]\nradius = 0.05\nradiance = 1000.0\n";
    let err = Renderer::new(&ctx, scene(sphere), "image_space", &params, SIZE, SIZE, 0.0)
        .err()
        .expect("refused");
    assert!(format!("{err:#}").contains("sphere lights"), "{err:#}");
    assert_validation_clean(&ctx);
}
