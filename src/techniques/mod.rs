//! Techniques: each one owns its resources and records its passes into the
//! frame, writing linear radiance (W m^-2 sr^-1) into the frame's radiance
//! image. Each declares its parameters once, as a typed struct
//! (`crate::declare_params!`), and its name, description and components once
//! (`TechniqueBuild`); the registry (`registry!` below) lists one line per
//! technique: its module and type. A technique composes passes
//! (`crate::passes`: surface frame, light views, caustic map, airlight) and
//! never imports another technique.

use crate::frame::{FrameTargets, SceneGpu};
use crate::params::{ParamSet, ParamSpec, Params};
use crate::radiometry::Component;
use crate::scene::Scene;
use crate::vk::{Context, FrameRecorder, VkResult};
use std::sync::Arc;

/// A technique as the renderer holds it (`Box<dyn Technique>`); its typed
/// side (parameters, constructor) is `TechniqueBuild`.
pub trait Technique: AsAny {
    fn name(&self) -> &'static str;
    /// Records this frame's passes; every pass goes through `rec.pass`.
    fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) -> VkResult<()>;

    /// The scene's lights moved (same count and kinds). Returns true when the
    /// technique updated itself; false (the default) makes the renderer
    /// rebuild it. Called with no frame in flight.
    fn set_lights(&mut self, _lights: &[crate::scene::Light]) -> bool {
        false
    }

    /// The environment's `rotate` changed (`Renderer::set_environment_rotation`);
    /// the scene's GPU copy (environment constants, lights) is updated
    /// already. Returns true when the technique updated what it derived
    /// from the environment in place (`direct`'s irradiance SH, recomputed
    /// on the next frame); false (the default) makes the renderer rebuild
    /// it. Called with no frame in flight.
    fn environment_changed(&mut self) -> bool {
        false
    }

    /// Called once a frame recorded by `record` has completed (its fence
    /// has signalled), with the slot it ran in (`FrameRecorder::slot`):
    /// host-visible results written per slot are that frame's, so this is
    /// where a technique reads them back and reports. Frames complete in order.
    fn after_frame(&mut self, _slot: usize) -> VkResult<()> {
        Ok(())
    }

    /// Named counts of the last completed frame (`caustics bench --json`
    /// writes them); none by default.
    fn counters(&self) -> Vec<(&'static str, u64)> {
        Vec::new()
    }
}

/// What the registry needs of a technique type: its name, description and
/// components, its typed parameters, and its constructor. Written once, in
/// the technique's own module.
pub trait TechniqueBuild: Technique + Sized + 'static {
    const NAME: &'static str;
    /// One line: the paper and what it renders (`caustics info`).
    const DESCRIPTION: &'static str;
    /// The path-type components it renders (the demo's C key and
    /// `caustics render --component` pick among them).
    const COMPONENTS: &'static [Component];
    /// Which specular objects' caustics it renders (`caustics compare`
    /// marks its caustic components "not applicable" on a scene with others).
    const CAUSTIC_SOURCES: CausticSources;
    type Params: ParamSet;

    fn build(
        ctx: &Arc<Context>,
        params: &Self::Params,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self>;

    /// What the technique needs of the scene (a water object, a sun),
    /// checked before any device work so that the error comes first and
    /// alone; `build` may assume it.
    fn check_scene(_scene: &Scene) -> anyhow::Result<()> {
        Ok(())
    }

    /// Takes new values of its `Live` parameters (`params::Apply`) in
    /// place, typed: push constants and switches read at record time.
    /// Called (through `TechniqueInfo::update_live`) by
    /// `Renderer::set_params` only when every changed parameter is live,
    /// possibly with frames in flight: change only host state read at
    /// record time, never a buffer or descriptor set a submitted frame may
    /// read. Returns false (the default) when the technique cannot, and the
    /// renderer rebuilds it.
    fn update_live(&mut self, _params: &Self::Params) -> bool {
        false
    }
}

/// The concrete type behind a `dyn Technique`, for the registry's typed
/// calls (`TechniqueInfo::update_live`).
pub trait AsAny: std::any::Any {
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any;
}

impl<T: std::any::Any> AsAny for T {
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// Builds a `T` from validated values (`TechniqueInfo::create`).
fn create<T: TechniqueBuild>(
    ctx: &Arc<Context>,
    params: &Params,
    scene: &Scene,
    scene_gpu: &SceneGpu,
    width: u32,
    height: u32,
) -> anyhow::Result<Box<dyn Technique>> {
    let params = T::Params::from_params(params)?;
    T::check_scene(scene)?;
    Ok(Box::new(T::build(
        ctx, &params, scene, scene_gpu, width, height,
    )?))
}

/// Hands `T` its typed live parameters (`TechniqueBuild::update_live`):
/// the values become `T::Params` here, once, by position.
fn update_live<T: TechniqueBuild>(
    technique: &mut dyn Technique,
    params: &Params,
) -> anyhow::Result<bool> {
    let name = technique.name();
    let typed = T::Params::from_params(params)?;
    let Some(technique) = technique.as_any_mut().downcast_mut::<T>() else {
        anyhow::bail!("live parameters of `{}` given to `{name}`", T::NAME);
    };
    Ok(technique.update_live(&typed))
}

/// The constructor of a registered technique.
pub type CreateFn =
    fn(&Arc<Context>, &Params, &Scene, &SceneGpu, u32, u32) -> anyhow::Result<Box<dyn Technique>>;

/// Which specular objects' caustics (L S+ D, L S+ V) a technique renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CausticSources {
    /// It draws no caustics.
    None,
    /// Reflections only: mirrors and the outer Fresnel reflection of
    /// dielectrics (Wand & Straßer's reflectors).
    Reflection,
    /// The surfaces of `water` objects only.
    Water,
    /// Mirrors and closed dielectrics, reflected and refracted; not the
    /// single interface of an open water surface.
    Solids,
    /// Every mirror and dielectric, reflected and refracted.
    All,
}

/// A real-time technique in the registry.
pub struct TechniqueInfo {
    pub name: &'static str,
    pub description: &'static str,
    /// The path-type components it renders.
    pub components: &'static [Component],
    pub caustic_sources: CausticSources,
    specs: fn() -> &'static [ParamSpec],
    /// Builds it for frames of `width` x `height` from values validated
    /// against `params()`.
    pub create: CreateFn,
    /// What it needs of the scene, checked without a device
    /// (`TechniqueBuild::check_scene`).
    pub check_scene: fn(&Scene) -> anyhow::Result<()>,
    /// Gives a technique built by `create` new values of its live
    /// parameters (`TechniqueBuild::update_live`); Ok(false) when it
    /// cannot take them in place.
    pub update_live: fn(&mut dyn Technique, &Params) -> anyhow::Result<bool>,
}

impl TechniqueInfo {
    pub const fn of<T: TechniqueBuild>() -> TechniqueInfo {
        TechniqueInfo {
            name: T::NAME,
            description: T::DESCRIPTION,
            components: T::COMPONENTS,
            caustic_sources: T::CAUSTIC_SOURCES,
            specs: <T::Params as ParamSet>::specs,
            create: create::<T>,
            check_scene: T::check_scene,
            update_live: update_live::<T>,
        }
    }

    /// Its parameters (`--param`, the overlay, `caustics info`).
    pub fn params(&self) -> &'static [ParamSpec] {
        (self.specs)()
    }

    /// Why `component` of `scene` is beyond what the technique models
    /// (caustics of a specular object its `caustic_sources` leave out), or
    /// None when the technique models all of it. A comparison reports such
    /// a component as not applicable instead of scoring it.
    pub fn not_modelled(&self, scene: &Scene, component: Component) -> Option<String> {
        use crate::scene::MaterialKind;
        // `other` holds multiple scattering, which the volume techniques
        // approximate where the medium asks for it (passes::scattered_lights),
        // and diffuse interreflection, which none draws.
        if component == Component::Other
            && !scene.medium.as_ref().is_some_and(|m| m.multiple_scattering)
        {
            return Some(format!(
                "{} draws multiple scattering only in a medium with `multiple_scattering = true`",
                self.name
            ));
        }
        if !matches!(
            component,
            Component::SurfaceCaustics | Component::VolumeCaustics
        ) {
            return None;
        }
        let name = self.name;
        for o in &scene.objects {
            for &m in &o.mesh.materials {
                let Some(mat) = scene.materials.get(m as usize) else {
                    continue;
                };
                let refracts = matches!(
                    mat.kind,
                    MaterialKind::Dielectric | MaterialKind::ThinDielectric
                );
                let specular = refracts || mat.kind == MaterialKind::Mirror || mat.is_mixed();
                let why = match self.caustic_sources {
                    CausticSources::All => None,
                    CausticSources::None if specular => Some("draws no caustics".to_string()),
                    CausticSources::Reflection if refracts => {
                        Some("renders reflection caustics only".to_string())
                    }
                    CausticSources::Water if specular && o.water.is_none() => {
                        Some("renders the water's caustics only".to_string())
                    }
                    CausticSources::Solids if o.water.is_some() => {
                        Some("renders no caustics of open water surfaces".to_string())
                    }
                    _ => None,
                };
                if let Some(why) = why {
                    return Some(format!(
                        "{name} {why}; object `{}` (material `{}`) makes caustics it does not",
                        o.name, mat.name
                    ));
                }
            }
        }
        None
    }
}

// Each technique's module, declared here where rustfmt and other tools
// follow it (a macro-declared module is invisible to `cargo fmt`).
pub mod beams;
pub mod direct;
pub mod image_space;
pub mod pinhole;
pub mod volume_lines;
pub mod water_photons;

/// Lists each technique in `TECHNIQUES`: adding one is its `mod` line above
/// and one line in `registry!` below.
macro_rules! registry {
    ($($module:ident :: $ty:ident),* $(,)?) => {
        /// Every real-time technique, one line each (the demo's number keys
        /// follow this order).
        pub const TECHNIQUES: &[TechniqueInfo] = &[$(TechniqueInfo::of::<$module::$ty>()),*];
    };
}

registry! {
    direct::Direct,
    image_space::ImageSpace,
    volume_lines::VolumeLines,
    water_photons::WaterPhotons,
    beams::Beams,
    pinhole::Pinhole,
}

/// Refuses, naming the first such material, what only `direct` and the
/// reference render: a thin dielectric sheet (`thin_dielectric`; the other
/// techniques model mirrors and solid dielectrics, and would refract
/// through it into a solid that is not there) and an emissive surface
/// that is not a scene area light (a glTF `emissiveFactor`: their light
/// reaches receivers only through `direct`'s and the reference's area
/// light sampling). Every technique but `direct` calls it from its
/// `check_scene`.
pub fn check_materials(scene: &Scene, technique: &str) -> anyhow::Result<()> {
    let file = scene.source.display();
    for (i, m) in used_materials(scene) {
        if m.kind == crate::scene::MaterialKind::ThinDielectric {
            anyhow::bail!(
                "{file}: material `{}`: {technique} does not render thin dielectric sheets (kind = \"thin_dielectric\", glTF transmission without a volume); use `direct` or `reference`",
                m.name
            );
        }
        let area_light = scene.emitters.iter().any(|e| e.material as usize == i);
        if m.emission.max_element() > 0.0 && !area_light {
            anyhow::bail!(
                "{file}: material `{}`: {technique} does not render emissive surfaces other than area lights (glTF emissiveFactor); use `direct` or `reference`",
                m.name
            );
        }
    }
    Ok(())
}

/// The materials some object uses, with their indices.
fn used_materials(scene: &Scene) -> impl Iterator<Item = (usize, &crate::scene::Material)> {
    let mut used = vec![false; scene.materials.len()];
    for o in &scene.objects {
        for &m in &o.mesh.materials {
            if let Some(u) = used.get_mut(m as usize) {
                *u = true;
            }
        }
    }
    scene
        .materials
        .iter()
        .enumerate()
        .filter(move |&(i, _)| used[i])
}

/// Whether an object uses a `mixed` material (a diffuse surface with a
/// mirror part, `Material::specular`).
pub fn has_mixed(scene: &Scene) -> bool {
    used_materials(scene).any(|(_, m)| m.is_mixed())
}

/// Refuses, naming the first one, a `mixed` material: its mirror part
/// would be dropped silently by the techniques that trace caustics from
/// mirrors and glass only (image_space, volume_lines, water_photons,
/// beams: their G-buffers and light views see a diffuse surface). `pinhole`
/// renders both parts, the reference exactly; `direct` draws no specular
/// light at all.
pub fn check_no_mixed(scene: &Scene, technique: &str) -> anyhow::Result<()> {
    if let Some((_, m)) = used_materials(scene).find(|(_, m)| m.is_mixed()) {
        anyhow::bail!(
            "{}: material `{}`: {technique} does not render the mirror part of a mixed material (kind = \"mixed\"); use `pinhole` or `reference`",
            scene.source.display(),
            m.name
        );
    }
    Ok(())
}

/// `--technique auto`: the technique that renders every component `scene`
/// has, among those that accept it (`check_scene`: e.g. image_space and
/// volume_lines refuse sphere lights and mixed materials). A participating
/// medium needs airlight and volume caustics: `volume_lines` (`beams`
/// renders them too; volume_lines is the closer to the reference on
/// volume_cone, BENCHMARKS.md). Water lit by a sun: `water_photons`.
/// Reflectors (mirrors, mixed surfaces) and no refractors, lit by what
/// image_space cannot map: `pinhole`, whose light cube maps hold every
/// emitter. That is an environment (image_space maps its sun alone: the
/// sky in the mirrors would cast nothing) or any scene image_space refuses
/// (sphere lights, a rect too large for a point stand-in, a mixed
/// material: `ring_sky`, `moving_lights`, `cup`). Otherwise `image_space`,
/// the surface caustics of mirrors and glass under point, spot,
/// directional and small rect lights, which it maps without pinhole's
/// distant-light error (Wand & Straßer Sect. 5); then `pinhole` where
/// image_space refuses a scene with specular surfaces (glass under sphere
/// lights: it still shows the glass and its reflections); `direct` when
/// none of them accepts the scene.
pub fn auto(scene: &Scene) -> &'static str {
    let accepts = |name: &str| find(name).is_ok_and(|t| (t.check_scene)(scene).is_ok());
    let candidates: Vec<&'static str> = if scene.medium.is_some() {
        vec!["volume_lines", "beams"]
    } else {
        use crate::scene::MaterialKind;
        let kind = |k: MaterialKind| used_materials(scene).any(|(_, m)| m.kind == k);
        let reflectors = kind(MaterialKind::Mirror) || has_mixed(scene);
        let refractors = kind(MaterialKind::Dielectric);
        let pinhole_first =
            reflectors && !refractors && (scene.environment.is_some() || !accepts("image_space"));
        if pinhole_first {
            vec!["water_photons", "pinhole"]
        } else if reflectors || refractors {
            vec!["water_photons", "image_space", "pinhole"]
        } else {
            vec!["water_photons", "image_space"]
        }
    };
    candidates
        .into_iter()
        .find(|name| accepts(name))
        .unwrap_or("direct")
}

pub fn find(name: &str) -> anyhow::Result<&'static TechniqueInfo> {
    TECHNIQUES.iter().find(|t| t.name == name).ok_or_else(|| {
        let names: Vec<_> = TECHNIQUES.iter().map(|t| t.name).collect();
        anyhow::anyhow!("unknown technique `{name}`; available: {} (and `caustics reference` for the ground truth)", names.join(", "))
    })
}

impl TechniqueInfo {
    /// The component mask (`Component::mask`) that draws only `component`
    /// of this technique, or everything for `all`; an error names the
    /// components it has.
    pub fn component_mask(&self, component: &str) -> anyhow::Result<u32> {
        let c = Component::parse(component)?;
        if c == Component::All || self.components.contains(&c) {
            return Ok(c.mask());
        }
        let names: Vec<_> = self.components.iter().map(|c| c.name()).collect();
        anyhow::bail!(
            "technique `{}` does not render component `{component}`; it renders: {}, all",
            self.name,
            names.join(", ")
        )
    }
}

/// Builds the technique `name` for frames of `width` x `height`.
pub fn create_named(
    ctx: &Arc<Context>,
    name: &str,
    params: &Params,
    scene: &Scene,
    scene_gpu: &SceneGpu,
    width: u32,
    height: u32,
) -> anyhow::Result<Box<dyn Technique>> {
    (find(name)?.create)(ctx, params, scene, scene_gpu, width, height)
}

#[cfg(test)]
mod auto_tests {
    use super::*;

    /// A canonical scene of assets/scenes by file name.
    fn load(name: &str) -> Scene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/scenes")
            .join(name);
        Scene::load(&path).unwrap()
    }

    /// `--technique auto` on the canonical scenes: a medium, sunlit water,
    /// glass over a floor, reflectors under what only pinhole maps.
    #[test]
    fn auto_picks_by_what_the_scene_has() {
        assert_eq!(auto(&load("smoke.toml")), "volume_lines");
        assert_eq!(auto(&load("volume_cone.toml")), "volume_lines");
        assert_eq!(auto(&load("water_pool.toml")), "water_photons");
        assert_eq!(auto(&load("ball_lens.toml")), "image_space");
        assert_eq!(auto(&load("ring.toml")), "image_space");
        // Reflectors under an environment, sphere lights, a mixed material.
        assert_eq!(auto(&load("ring_sky.toml")), "pinhole");
        assert_eq!(auto(&load("moving_lights.toml")), "pinhole");
        assert_eq!(auto(&load("cup.toml")), "pinhole");
        // A rect light in a medium: its stand-in serves volume_lines.
        assert_eq!(auto(&load("volume_box.toml")), "volume_lines");
        // Glass under a sphere light: image_space refuses it, pinhole
        // still shows the glass; no specular surface at all: image_space.
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/ball_lens.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        let point =
            "kind = \"point\"\nposition = [0.0, 8.0, 0.0]\nintensity = [60.0, 60.0, 60.0]\n";
        assert!(text.contains(point));
        let sphere =
            "kind = \"sphere\"\ncenter = [0.0, 8.0, 0.0]\nradius = 0.2\nradiance = 100.0\n";
        let glass = Scene::from_str(&text.replace(point, sphere), &path).unwrap();
        assert_eq!(auto(&glass), "pinhole");
        let mut plain = load("ring.toml");
        for m in &mut plain.materials {
            m.kind = crate::scene::MaterialKind::Diffuse;
        }
        assert_eq!(auto(&plain), "image_space");
    }

    /// What each technique's caustics leave out: pinhole the glass ball's
    /// refraction, water_photons every specular object but the water.
    #[test]
    fn caustic_components_a_technique_does_not_model() {
        let info = |name| find(name).unwrap();
        // `name` leaves out `component` of `scene` for a reason naming
        // each of `words`.
        let leaves_out = |name, scene: &Scene, component, words: &[&str]| {
            let reason = info(name).not_modelled(scene, component);
            assert!(
                reason
                    .as_deref()
                    .is_some_and(|r| words.iter().all(|w| r.contains(w))),
                "{name}: {reason:?}"
            );
        };
        let ball = load("ball_lens.toml");
        let surface = Component::SurfaceCaustics;
        leaves_out(
            "pinhole",
            &ball,
            surface,
            &["reflection caustics only", "`lens`"],
        );
        assert_eq!(info("pinhole").not_modelled(&ball, Component::Direct), None);
        for name in ["image_space", "volume_lines", "beams"] {
            assert_eq!(
                info(name).not_modelled(&ball, Component::SurfaceCaustics),
                None,
                "{name}"
            );
        }
        // Mirrors only: every reflector technique models them.
        let ring = load("ring.toml");
        assert_eq!(
            info("pinhole").not_modelled(&ring, Component::SurfaceCaustics),
            None
        );
        // The pool's water is water_photons' own; a glass ball beside it is
        // not. beams' two-sided beams have no open surface's caustics.
        let pool = load("water_pool.toml");
        leaves_out("beams", &pool, surface, &["open water", "`water`"]);
        assert_eq!(
            info("water_photons").not_modelled(&pool, Component::SurfaceCaustics),
            None
        );
        let mut with_ball = pool.clone();
        with_ball.materials.push(ball.materials[0].clone());
        let mut lens = ball.objects[0].clone();
        lens.mesh
            .materials
            .iter_mut()
            .for_each(|m| *m = with_ball.materials.len() as u32 - 1);
        with_ball.objects.push(lens);
        leaves_out(
            "water_photons",
            &with_ball,
            Component::VolumeCaustics,
            &["the water's caustics only"],
        );
    }
}
