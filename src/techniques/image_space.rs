//! `image_space`: Wyman 2005-06 surface caustics on top of the `direct`
//! frame. The frame is direct light with shadow maps (every caster, the
//! glass too) plus, on diffuse receivers, L = albedo / pi * E_caustic from
//! the caustic map (`passes::caustic_map`): the light the specular objects
//! redirect, which includes the light their shadow removed, so with IOR 1
//! the shadow is filled back in.
//!
//! Passes: the `direct` passes; "caustic map clear", per light "caustic
//! photons" and "caustic splat"; "caustic apply" (glsl/caustic_map/apply.comp).
//! With `caustics_on_change` = 1 the clear, photon and splat passes run only
//! when a light moved (`set_lights`) or the geometry's animation time
//! changed; other frames reuse the last caustic map.
//! Glass objects seen directly stay black (two-sided image-space refraction
//! toward the camera is not implemented yet).

use super::direct::Direct;
use super::{ParamSpec, Params, Technique};
use crate::passes::caustic_map::CausticMap;
use crate::renderer::{FrameTargets, SceneGpu};
use crate::scene::Scene;
use crate::shader_bindings as b;
use crate::vk::{
    barrier, Access, BindingKind, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout,
    FrameRecorder, ImageAccess, Sampler, VkResult,
};
use ash::vk;
use std::sync::Arc;

pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "shadow_map_size",
        description: "shadow map resolution per view (texels per side)",
        min: 64.0,
        max: 4096.0,
        default: 1024.0,
        integer: true,
    },
    ParamSpec {
        name: "pcf_radius",
        description: "percentage-closer filter half-width in shadow texels (0: one tap)",
        min: 0.0,
        max: 4.0,
        default: 1.0,
        integer: true,
    },
    ParamSpec {
        name: "photon_buffer_size",
        description: "photon buffer resolution (photons per side of the light view)",
        min: 64.0,
        max: 1024.0,
        default: 512.0,
        integer: true,
    },
    ParamSpec {
        name: "caustic_map_size",
        description: "caustic map resolution per light view (texels per side)",
        min: 64.0,
        max: 1024.0,
        default: 512.0,
        integer: true,
    },
    ParamSpec {
        name: "splat_size",
        description: "photon splat width in caustic-map texels (odd; an even value is raised by 1)",
        min: 1.0,
        max: 15.0,
        default: 7.0,
        integer: true,
    },
    ParamSpec {
        name: "photon_mode",
        description: "0: photon paths traced exactly through the BVH; 1: Wyman's two-sided image-space refraction from light-space front/back G-buffers (Eq. 6.3.1 distance); 2: the same G-buffers, the refracted ray marched against the back-face map (exact for convex objects)",
        min: 0.0,
        max: 2.0,
        default: 0.0,
        integer: true,
    },
    ParamSpec {
        name: "caustics_on_change",
        description: "1: recompute the caustic map only when a light moved or animated geometry changed, reusing the last one otherwise; 0: every frame (benchmarks)",
        min: 0.0,
        max: 1.0,
        default: 0.0,
        integer: true,
    },
];

pub struct ImageSpace {
    pub direct: Direct,
    pub caustics: CausticMap,
    apply: ComputePipeline,
    set: DescriptorSet,
    bound_radiance: vk::ImageView,
    /// `caustics_on_change`: reuse the caustic map while nothing it depends
    /// on moved (Wyman 2006, "Putting it Together": "we only update the
    /// caustic map after changes to the light or scene geometry").
    caustics_on_change: bool,
    /// Geometry time the caustic map was computed for; `None` when it must
    /// be recomputed (never computed, or a light moved).
    caustics_geometry_time: Option<f32>,
    _layout: DescriptorSetLayout,
    _sampler: Sampler,
}

impl ImageSpace {
    pub fn new(
        ctx: &Arc<Context>,
        params: &Params,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> VkResult<Self> {
        let direct = Direct::new(ctx, params, scene, scene_gpu, width, height)?;
        let caustics = CausticMap::new(
            ctx,
            scene,
            scene_gpu,
            params.get("photon_buffer_size") as u32,
            params.get("caustic_map_size") as u32,
            params.get("splat_size") as u32,
            params.get("photon_mode") as u32,
        )?;
        let layout = DescriptorSetLayout::new(
            ctx,
            &[
                (b::CAUSTIC_BINDING_VIEWS, BindingKind::Uniform),
                (b::CAUSTIC_BINDING_MAP, BindingKind::Sampled),
                (b::CAUSTIC_BINDING_POSITION, BindingKind::StorageImage),
                (b::CAUSTIC_BINDING_NORMAL, BindingKind::StorageImage),
                (b::CAUSTIC_BINDING_RADIANCE, BindingKind::StorageImage),
            ],
        )?;
        let sampler = Sampler::new(ctx, vk::Filter::NEAREST)?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(b::CAUSTIC_BINDING_VIEWS, &caustics.views)
            .write_sampled_image(
                b::CAUSTIC_BINDING_MAP,
                &caustics.map,
                &sampler,
                vk::ImageLayout::GENERAL,
            )
            .write_storage_image(b::CAUSTIC_BINDING_POSITION, &direct.gbuffer.position)
            .write_storage_image(b::CAUSTIC_BINDING_NORMAL, &direct.gbuffer.normal);
        let apply = ComputePipeline::new(
            ctx,
            "caustic_map/apply.comp",
            &[&scene_gpu.layout, &layout],
            4,
        )?;
        Ok(Self {
            direct,
            caustics,
            apply,
            set,
            bound_radiance: vk::ImageView::null(),
            caustics_on_change: params.get("caustics_on_change") != 0.0,
            caustics_geometry_time: None,
            _layout: layout,
            _sampler: sampler,
        })
    }
}

impl Technique for ImageSpace {
    fn name(&self) -> &'static str {
        "image_space"
    }

    fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) -> VkResult<()> {
        if self.bound_radiance != targets.radiance.view {
            // Legal: the renderer waits for every frame before the next.
            self.set
                .write_storage_image(b::CAUSTIC_BINDING_RADIANCE, &targets.radiance);
            self.bound_radiance = targets.radiance.view;
        }
        self.direct.record(rec, scene, targets)?;
        if !self.caustics_on_change || self.caustics_geometry_time != Some(scene.geometry_time) {
            self.caustics.record(rec, scene)?;
            self.caustics_geometry_time = Some(scene.geometry_time);
        }
        let ctx = rec.ctx().clone();
        let light_count = self.caustics.light_count();
        rec.pass("caustic apply", |cmd| {
            // The splats' attachment writes and the direct pass's radiance
            // writes must be visible to this read-modify-write.
            barrier(
                &ctx,
                cmd,
                &[
                    ImageAccess::new(&self.caustics.map, Access::ComputeRead),
                    ImageAccess::new(&self.direct.gbuffer.position, Access::ComputeRead),
                    ImageAccess::new(&self.direct.gbuffer.normal, Access::ComputeRead),
                    ImageAccess::new(&targets.radiance, Access::ComputeWrite),
                ],
                &[],
            );
            let groups = [targets.width.div_ceil(8), targets.height.div_ceil(8), 1];
            self.apply.dispatch(
                cmd,
                &[&scene.set, &self.set],
                bytemuck::bytes_of(&light_count),
                groups,
            );
        });
        Ok(())
    }

    fn set_lights(&mut self, lights: &[crate::scene::Light]) -> bool {
        self.caustics_geometry_time = None;
        self.direct.set_lights(lights) && self.caustics.set_lights(lights)
    }
}
