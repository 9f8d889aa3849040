//! Techniques: each one owns its resources and records its passes into the
//! frame, writing linear radiance (W m^-2 sr^-1) into the frame's radiance
//! image. Parameters are declared once (`ParamSpec`) so the CLI, the demo
//! overlay and the benchmarks read the same list.

pub mod direct;
pub mod image_space;
pub mod volume_lines;
pub mod water_photons;

use crate::frame::{FrameTargets, SceneGpu};
use crate::params::{ParamSpec, Params};
use crate::radiometry::Component;
use crate::scene::Scene;
use crate::vk::{Context, FrameRecorder, VkResult};
use std::sync::Arc;

pub trait Technique {
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

    /// Called once the frame recorded by `record` has completed (after the
    /// renderer's fence wait): host-visible results of that frame are
    /// current, so this is where a technique reads them back and reports.
    fn after_frame(&mut self) -> VkResult<()> {
        Ok(())
    }

    /// Named counts of the last completed frame (`caustics bench --json`
    /// writes them); none by default.
    fn counters(&self) -> Vec<(&'static str, u64)> {
        Vec::new()
    }
}

/// Every real-time technique: name, one-line description, parameters.
pub struct TechniqueInfo {
    pub name: &'static str,
    pub description: &'static str,
    pub params: &'static [ParamSpec],
    /// The path-type components it renders (the demo's C key and
    /// `caustics render --component` pick among them).
    pub components: &'static [Component],
}

pub const TECHNIQUES: &[TechniqueInfo] = &[TechniqueInfo {
    name: "direct",
    description: "direct light with shadow maps (the base frame every technique adds to)",
    params: direct::PARAMS,
    components: &[Component::Direct],
}, TechniqueInfo {
    name: "image_space",
    description: "Wyman 2005-06: two-sided image-space refraction of what the camera sees through glass (and in mirrors), and caustic maps (photons through the specular objects, Gaussian splats, projected onto diffuse receivers)",
    params: image_space::PARAMS,
    components: &[Component::Direct, Component::SurfaceCaustics],
}, TechniqueInfo {
    name: "volume_lines",
    description: "Hu et al. 2010: volume caustics as lines (light rays after one reflection or two refractions, drawn by a geometry shader, Eq. 3 per fragment), plus ray-marched airlight with volumetric shadows, over image_space's surface radiance attenuated by the medium",
    params: volume_lines::PARAMS,
    components: &[
        Component::Direct,
        Component::SurfaceCaustics,
        Component::Airlight,
        Component::VolumeCaustics,
    ],
}, TechniqueInfo {
    name: "water_photons",
    description: "Kougianos & Moustakas 2021: cascaded caustic maps of the water from the sun, photon differentials traced through the BVH, splats drawn indirect into a screen-space caustic buffer",
    params: water_photons::PARAMS,
    components: &[Component::Direct, Component::SurfaceCaustics],
}];

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
pub fn create(
    ctx: &Arc<Context>,
    name: &str,
    params: &Params,
    scene: &Scene,
    scene_gpu: &SceneGpu,
    width: u32,
    height: u32,
) -> anyhow::Result<Box<dyn Technique>> {
    Ok(match name {
        "direct" => Box::new(direct::Direct::new(
            ctx, params, scene, scene_gpu, width, height,
        )?),
        "image_space" => Box::new(image_space::ImageSpace::new(
            ctx, params, scene, scene_gpu, width, height,
        )?),
        "volume_lines" => Box::new(volume_lines::VolumeLines::new(
            ctx, params, scene, scene_gpu, width, height,
        )?),
        "water_photons" => Box::new(water_photons::WaterPhotons::new(
            ctx, params, scene, scene_gpu, width, height,
        )?),
        other => {
            return Err(find(other)
                .err()
                .unwrap_or_else(|| anyhow::anyhow!("technique `{other}` not built")))
        }
    })
}
