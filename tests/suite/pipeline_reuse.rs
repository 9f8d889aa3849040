//! Pipeline reuse across rebuilds (`vk::PipelineStore`): a rebuild that
//! changes no shader creates no pipeline and renders what a fresh build
//! renders; a changed specialisation constant creates exactly the pipelines
//! that use it; the on-disk pipeline cache loader ignores a corrupt or
//! foreign file without failing.

use crate::common;

use caustics::params::Params;
use caustics::renderer::Renderer;
use caustics::scene::Scene;
use caustics::shader_bindings as b;
use caustics::techniques;
use caustics::vk::{
    Buffer, BufferUsage, CacheLoad, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    Specialization,
};
use std::path::Path;
use std::sync::Arc;

const SIZE: u32 = 32;

/// `technique`'s parameters with `overrides`. pinhole runs with its
/// footprint filter off: its normal gradients sum their neighbours in the
/// order of hash-grid lists that atomics build, so their last bits vary
/// from run to run, and lavapipe's quantised LOD turns that into
/// differences of up to 1.6e-3 of the peak (measured; filter off, runs are
/// bit-identical). Pipeline reuse is what this file tests.
fn params(technique: &str, overrides: &[&str]) -> Params {
    let specs = techniques::find(technique).unwrap().params();
    let mut o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    if technique == "pinhole" {
        o.insert(0, "filter=0".into());
    }
    Params::resolve(technique, specs, &o).unwrap()
}

fn frame(r: &mut Renderer) -> Vec<f32> {
    r.render_frame(0.0).unwrap();
    r.radiance().unwrap()
}

/// Changes `change` (a rebuild parameter that sizes resources only) on a
/// running `technique`: the rebuild reuses every pipeline, and its frame
/// equals that of a technique built with the new value from new pipelines.
fn rebuild_reuses_every_pipeline(technique: &str, scene: &str, change: &str) {
    let ctx = common::validated_context();
    let scene = Scene::load(Path::new(scene)).unwrap();
    let mut renderer = Renderer::new(
        &ctx,
        scene.clone(),
        technique,
        &params(technique, &[]),
        SIZE,
        SIZE,
        0.0,
    )
    .unwrap();
    frame(&mut renderer);
    let before = ctx.pipelines().counts();
    assert!(before.created > 0);
    assert!(
        renderer.set_params(&params(technique, &[change])).unwrap(),
        "{technique}: {change} is a rebuild parameter"
    );
    let after = ctx.pipelines().counts();
    assert_eq!(
        after.created, before.created,
        "{technique}: the rebuild for {change} created pipelines"
    );
    assert!(
        after.reused > before.reused,
        "{technique}: the rebuild asked for no pipeline"
    );
    let reused_image = frame(&mut renderer);

    // The same technique from pipelines created anew.
    ctx.pipelines().set_reuse(false);
    let mut fresh = Renderer::new(
        &ctx,
        scene,
        technique,
        &params(technique, &[change]),
        SIZE,
        SIZE,
        0.0,
    )
    .unwrap();
    assert!(ctx.pipelines().counts().created > after.created);
    // The second frame of each, as frames may depend on their index
    // (jittered sampling).
    frame(&mut fresh);
    let fresh_image = frame(&mut fresh);
    let what = format!("{technique}: reused pipelines render another image");
    // Photons and beams are appended through atomic counters; pinhole sums
    // its light maps' coverage with float atomics: all agree up to the
    // order of float sums.
    if technique == "water_photons" || technique == "beams" || technique == "pinhole" {
        common::assert_equal_up_to_splat_order(&fresh_image, &reused_image, &what);
    } else {
        assert_eq!(reused_image, fresh_image, "{what}");
    }
    drop((renderer, fresh));
    common::assert_validation_clean(&ctx);
}

#[test]
fn direct_rebuild_reuses_every_pipeline() {
    rebuild_reuses_every_pipeline(
        "direct",
        "assets/scenes/ball_lens.toml",
        "shadow_map_size=512",
    );
}

#[test]
fn image_space_rebuild_reuses_every_pipeline() {
    rebuild_reuses_every_pipeline(
        "image_space",
        "assets/scenes/ball_lens.toml",
        "caustic_map_size=256",
    );
}

#[test]
fn volume_lines_rebuild_reuses_every_pipeline() {
    rebuild_reuses_every_pipeline(
        "volume_lines",
        "assets/scenes/volume_cone.toml",
        "volume_buffer_size=256",
    );
}

#[test]
fn beams_rebuild_reuses_every_pipeline() {
    rebuild_reuses_every_pipeline(
        "beams",
        "assets/scenes/volume_cone.toml",
        "beam_capacity=65536",
    );
}

#[test]
fn pinhole_rebuild_reuses_every_pipeline() {
    rebuild_reuses_every_pipeline("pinhole", "assets/scenes/ring.toml", "cube_size=64");
}

#[test]
fn water_photons_rebuild_reuses_every_pipeline() {
    rebuild_reuses_every_pipeline(
        "water_photons",
        "assets/scenes/water_pool.toml",
        "ccm_size=256",
    );
}

/// A "technique" of two pipelines, one specialised by `factor`.
struct Probe {
    scaled: ComputePipeline,
    _other: ComputePipeline,
    layout: DescriptorSetLayout,
}

impl Probe {
    fn new(ctx: &Arc<Context>, factor: u32) -> Probe {
        // A new set layout each time, as a rebuilt technique makes.
        let layout = DescriptorSetLayout::of_shaders(
            ctx,
            0,
            &["tests/specialization.comp", "tests/ccm_distribution.comp"],
        )
        .unwrap();
        let scaled = ComputePipeline::specialized(
            ctx,
            "tests/specialization.comp",
            &Specialization::new().u32(0, factor),
            &[&layout],
            4,
        )
        .unwrap();
        let other =
            ComputePipeline::new(ctx, "tests/ccm_distribution.comp", &[&layout], 32).unwrap();
        Probe {
            scaled,
            _other: other,
            layout,
        }
    }

    /// Runs the specialised pipeline on `value`.
    fn run(&self, ctx: &Arc<Context>, value: u32) -> u32 {
        let out = Buffer::new(ctx, "probe", 16, BufferUsage::Storage).unwrap();
        let set = DescriptorSet::new(ctx, &self.layout).unwrap();
        set.write_buffer(b::PROBE_BINDING_RESULTS, &out);
        ctx.submit_commands_and_wait(|c| {
            c.dispatch(&self.scaled, &[&set], bytemuck::bytes_of(&value), [1, 1, 1])
        })
        .unwrap();
        out.download_pod::<u32>().unwrap()[0]
    }
}

#[test]
fn a_changed_specialisation_constant_creates_only_its_pipeline() {
    let ctx = common::validated_context();
    let counts = || ctx.pipelines().counts();
    let old = Probe::new(&ctx, 3);
    assert_eq!((counts().created, counts().reused), (2, 0));
    assert_eq!(old.run(&ctx, 7), 21, "FACTOR = 3 specialises the shader");

    // Rebuilt with another factor while the old one lives (as
    // `Renderer::set_params` does): only the specialised pipeline is new.
    let new = Probe::new(&ctx, 5);
    assert_eq!((counts().created, counts().reused), (3, 1));
    assert_eq!(new.run(&ctx, 7), 35);
    assert_eq!(old.run(&ctx, 7), 21, "the old pipeline is not replaced");

    // Dropped first and rebuilt (as a resize does): the store kept them.
    drop((old, new));
    let again = Probe::new(&ctx, 3);
    assert_eq!((counts().created, counts().reused), (3, 3));
    assert_eq!(again.run(&ctx, 2), 6);

    // With reuse off every request creates a pipeline.
    ctx.pipelines().set_reuse(false);
    let unshared = Probe::new(&ctx, 3);
    assert_eq!((counts().created, counts().reused), (5, 3));
    assert_eq!(unshared.run(&ctx, 2), 6);
    drop((again, unshared));
    common::assert_validation_clean(&ctx);
}

/// A fresh folder for this test's files.
fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("caustics-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn the_disk_cache_loader_ignores_corrupt_and_foreign_files() {
    let ctx = common::validated_context();
    let store = ctx.pipelines();
    let dir = temp_dir("pipeline-cache");
    let path = dir.join("sub/pipelines.bin");
    assert_eq!(store.load(&path), CacheLoad::Missing);

    // A pipeline in the cache, then a round trip through the file.
    let probe = Probe::new(&ctx, 2);
    let written = store.save(&path).unwrap();
    assert!(written >= 32, "a cache file holds at least its header");
    let good = std::fs::read(&path).unwrap();
    assert_eq!(good.len(), written);
    assert_eq!(store.load(&path), CacheLoad::Loaded(written));

    let ignored = |bytes: &[u8], why: &str| {
        std::fs::write(&path, bytes).unwrap();
        match store.load(&path) {
            CacheLoad::Ignored(reason) => assert!(
                reason.contains(why),
                "expected a reason with {why:?}, got {reason:?}"
            ),
            other => panic!("a file that is {why} was not ignored: {other:?}"),
        }
    };
    ignored(b"not a pipeline cache", "shorter than");
    let edit = |at: usize, value: u8, why: &str| {
        let mut bytes = good.clone();
        bytes[at] ^= value;
        ignored(&bytes, why);
    };
    edit(0, 0xff, "header size");
    edit(4, 0x02, "version");
    edit(8, 0x01, "vendor");
    edit(12, 0x01, "device");
    edit(20, 0x01, "UUID");

    // The store still works after refusing them.
    assert_eq!(probe.run(&ctx, 4), 8);
    drop(probe);
    std::fs::remove_dir_all(&dir).unwrap();
    common::assert_validation_clean(&ctx);
}
