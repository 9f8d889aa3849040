//! Live parameters (`params::Apply::Live`) of every registered technique
//! reach it typed and in place (`TechniqueBuild::update_live` through
//! `Renderer::set_params`): no rebuild, and the next frame is the frame of
//! a technique built with the new values.

use crate::common;

use caustics::params::{Apply, Params};
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::techniques::TECHNIQUES;
use std::path::Path;

const SIZE: u32 = 32;

/// Techniques whose frames vary in their last bits from run to run: their
/// splats' sums come in no fixed order (float atomics in beams and
/// pinhole, photons appended by atomics in water_photons, whose order
/// follows lavapipe's worker threads on a loaded machine), so they agree
/// up to that order (`common::assert_equal_up_to_splat_order`).
const SPLAT_ORDER: &[&str] = &["beams", "pinhole", "water_photons"];

/// A value of `spec` other than its default: one step up (or down at the
/// top of its range) for whole numbers, halfway to the far end for reals.
fn other_value(spec: &caustics::params::ParamSpec) -> f32 {
    let v = if spec.integer {
        if spec.default + 1.0 <= spec.max {
            spec.default + 1.0
        } else {
            spec.default - 1.0
        }
    } else if spec.max - spec.default >= spec.default - spec.min {
        0.5 * (spec.default + spec.max)
    } else {
        0.5 * (spec.default + spec.min)
    };
    assert!(spec.accepts(v) && v != spec.default, "{}", spec.name);
    v
}

fn frame(r: &mut Renderer) -> Vec<f32> {
    r.render_frame(0.0).unwrap();
    r.radiance().unwrap()
}

#[test]
fn every_live_parameter_is_taken_in_place() {
    let ctx = common::validated_context();
    for info in TECHNIQUES {
        let scene = match info.name {
            "water_photons" => "assets/scenes/water_pool.toml",
            "pinhole" => "assets/scenes/ring.toml",
            _ => "assets/scenes/ball_lens.toml",
        };
        let scene = Scene::load(Path::new(scene)).unwrap();
        let defaults = Params::resolve(info.name, info.params(), &[]).unwrap();
        let mut changed = defaults.clone();
        let mut live = Vec::new();
        for (index, spec) in info.params().iter().enumerate() {
            if spec.apply == Apply::Live {
                changed.set(index, other_value(spec)).unwrap();
                live.push(spec.name);
            }
        }
        if live.is_empty() {
            continue;
        }
        let mut renderer =
            Renderer::new(&ctx, scene.clone(), info.name, &defaults, SIZE, SIZE, 0.0).unwrap();
        frame(&mut renderer);
        assert!(
            !renderer.set_params(&changed).unwrap(),
            "{}: changing {live:?} rebuilt the technique",
            info.name
        );
        assert_eq!(renderer.params(), &changed);
        let taken = frame(&mut renderer);
        let mut built = Renderer::new(&ctx, scene, info.name, &changed, SIZE, SIZE, 0.0).unwrap();
        let fresh = frame(&mut built);
        assert_eq!(taken.len(), fresh.len());
        if SPLAT_ORDER.contains(&info.name) {
            common::assert_equal_up_to_splat_order(
                &taken,
                &fresh,
                &format!(
                    "{}: {live:?} changed in place against a technique built with them",
                    info.name
                ),
            );
        } else {
            assert!(
                taken == fresh,
                "{}: with {live:?} changed in place the frame is not, bit for bit, the frame of a technique built with them",
                info.name
            );
        }
        drop((renderer, built));
    }
    common::assert_validation_clean(&ctx);
}
