//! `volume_lines`: line-based volume caustics in single-scattering media
//! (Hu, Dong, Ihrke, Grosch, Yuan, Seidel 2010, "Interactive Volume Caustics in
//! Single-Scattering Media"), on top of `image_space`.
//!
//! The frame is Hu's Fig. 2 sum: C (surface radiance with surface caustics
//! and what the camera sees through glass) is `image_space::ImageSpace` as
//! it is; B (light scattered once in the medium after one or more specular
//! events, the reference's L S+ V) is added by this module's passes, per
//! light:
//! 1. "volume light view": `passes::specular_gbuffer` from the light's
//!    photon view (`caustic_map::photon_view`, the frustum fitted to the
//!    specular objects; orthographic for directional light): front and
//!    back faces of the specular objects (Sect. 5.1, step 1).
//! 2. "volume segments" (glsl/volume_lines/segments.comp): per texel of that
//!    view, one-bounce reflection (mirrors) or two-bounce refraction
//!    (Wyman's two-sided refraction, shared with `image_space`) gives the
//!    exit point p1 and direction w'_l; p2 is the first diffuse surface
//!    along it (BVH; the scene's bounding sphere where it leaves). Stored
//!    with its flux Phi = I Omega_texel T0 T1 tau_glass tau(s, p0) in the
//!    volume caustic buffer (`GpuSegment`, one per texel, invalid ones
//!    flagged), followed by a second N x N half holding the Fresnel
//!    reflection F0 off a dielectric's front face (a one-bounce
//!    reflection; both are L S+ V; `front_reflection` = 0 leaves it
//!    undrawn). Each ray is clipped to the medium's bounds, with a margin
//!    of two pixels' footprint plus r so the line's rasterised end cuts
//!    nothing that scatters.
//! 3. "volume lines": one point per buffer entry (`vkCmdDraw`, vertex pulling); the
//!    geometry shader emits the camera-space line p1 -> p2; the fragment
//!    shader evaluates Eq. 3 with the regular-step resampling of Fig. 5 and
//!    blends additively into `volume` (RGBA32F; alpha counts fragments).
//!    Radiometry (glsl/volume_lines/lines.glsl has the derivation): a line
//!    is a beam x beam kernel, L = sigma_s p tau Phi / (w_world sin theta),
//!    w_world the width in metres, perpendicular to both rays, of the
//!    line's rasterised footprint (1 px wide, rectangular or parallelogram
//!    depending on the device's `strictLines`), redistributed over the
//!    ray-marching points k Delta_x within the filter support r of x_l
//!    with normalised Gaussian weights. No scale factor. This is how Eq. 3's
//!    L_in Delta_omega Delta_x is made radiometric (the issue's "Delta_omega
//!    from the light's radiometry"): L_in Delta_omega is the irradiance of
//!    the light tube, Phi over its cross-section, and the line's kernel
//!    over the beam-to-ray distance integrates the tube along the viewing
//!    ray; Delta_x then only picks where along the ray the contribution
//!    lands (Fig. 5's resampling), not how much, so the energy does not
//!    depend on Delta_x (as long as r >= Delta_x / 2, so that every line
//!    reaches a step point).
//!
//! Once per frame: "volume visibility" (the distance to the first surface,
//! diffuse or specular, per pixel: Sect. 5.3's culling; refractors hide the
//! volume caustic behind them) before the lines, "volume composite" (adds B
//! to the frame) after them.
//!
//! Homogeneous media use exact transmittance, with fragments compiled
//! without the density field (lines.frag; on a CPU rasteriser that code
//! made them 2.4x slower); inhomogeneous ones (noise, grid) a
//! `transmittance_steps`-point midpoint rule (lines_heterogeneous.frag,
//! Sect. 5.4).
//!
//! Cost: the lines pass is fragment-bound; fragments grow with buffer
//! texels x screen side (BENCHMARKS.md). The front-face reflections cross
//! the whole medium and make most of the fragments.
//!
//! Checked (tests/volume_lines.rs): the image's energy against a CPU
//! integral of the same light rays within 0.3%, HG's g = +-0.7 ratio
//! within 1e-4, and against the reference's L S+ V on volume_cone and
//! smoke (+1.4% to +3.2% energy; +16% at g = -0.7, see below).
//!
//! Limits: two interfaces (light reflected inside the glass is not
//! drawn); near a sphere's rim Eq. 6.3.1's exit meets a total internal
//! reflection the sphere does not have, and the default remedy (clamp)
//! sends those rays out tangentially (the main excess at g = -0.7); one
//! segment per texel (no chains of several objects); p2 comes from the
//! BVH, not from a light-space depth map as in Hu; lines with a
//! parallelogram rasteriser (no `strictLines`) assume the one-fragment-
//! per-column rule, not verified here (lavapipe has strict lines); the camera sees no volume caustic through glass or
//! in mirrors (Sect. 5.3; the reference cannot show those paths either);
//! a point light inside the specular objects' bounding sphere gets no
//! volume caustic (logged).
//!
//! A (airlight and volumetric shadows, the reference's L V) is
//! `passes::airlight`, recorded last ("airlight"): a ray march along each
//! camera ray with the shadow maps of C (every caster, glass included),
//! added to the frame. So the whole frame is Hu's D = A + B + C, and
//! `--component` writes each alone (direct and surface_caustics are C's
//! two parts, airlight is A, volume_caustics is B).

use super::image_space::{ImageSpace, ImageSpaceParams};
use super::{Technique, TechniqueBuild};
use crate::frame::{FrameTargets, SceneGpu};
use crate::params::{ParamSet, Params};
use crate::passes::airlight::{Airlight, AirlightParams};
use crate::passes::caustic_map::{photon_view, photon_view_proj, specular_bounds, PhotonViewPush};
use crate::passes::specular_gbuffer::{SpecularGBuffer, Viewpoint};
use crate::radiometry::Component;
use crate::scene::{Density, Light, Scene};
use crate::shader_bindings as b;
use crate::vk::{
    barrier, begin_rendering, end_rendering, Access, BindingKind, Buffer, BufferAccess,
    BufferUsage, ComputePipeline, Context, DescriptorSet, DescriptorSetLayout, FrameRecorder,
    GraphicsPipeline, GraphicsPipelineDesc, Image, ImageAccess, ImageDesc,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::mem::size_of;
use std::sync::Arc;

crate::declare_params! {
    /// `volume_lines`' parameters: image_space's (passed through to C,
    /// whatever they are) and the airlight's (A), then B's own.
    pub struct VolumeLinesParams {
        @group image_space: ImageSpaceParams;
        @group airlight: AirlightParams;
        volume_buffer_size: u32 [64, 2048] = 512, rebuild,
            "volume caustic buffer resolution (light rays per side of the light's view of the specular objects)";
        ray_step: f32 [0.005, 5.0] = 0.2, rebuild,
            "Delta_x (m): the regular ray-marching step the line contributions are redistributed to (Hu Eq. 3, Fig. 5)";
        filter_radius: f32 [0.005, 5.0] = 0.2, rebuild,
            "r (m): support of the normalised Gaussian that spreads a line's contribution over the step points (Hu uses r = Delta_x; at most 16 Delta_x; below Delta_x / 2 some lines reach no step point and are lost)";
        transmittance_steps: u32 [1, 64] = 4, rebuild,
            "midpoint-rule samples per transmittance integral in inhomogeneous media (Hu Sect. 5.4; homogeneous media are exact)";
        front_reflection: bool [0, 1] = 1, rebuild,
            "1: also draw the light reflected off a dielectric's front face (Fresnel F0; part of L S+ V, 14% of volume_cone's volume caustic at g = 0, but long lines across the whole medium: most of the fragments); 0: Hu's two-bounce refraction only";
    }
}

/// Most regular step points a fragment visits (glsl/volume_lines/lines.frag).
const MAX_RADIUS_IN_STEPS: f32 = 16.0;

/// One entry of the volume caustic buffer, mirrored by `Segment` in
/// glsl/volume_lines/volume_lines.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuSegment {
    /// xyz exit point p1; w = 1 for a light ray, 0 for none.
    pub p1: [f32; 4],
    /// xyz end point p2.
    pub p2: [f32; 4],
    /// rgb flux (W) after the specular object; w: the texel's solid angle
    /// (sr) or area (m^2).
    pub flux: [f32; 4],
}
const _: () = assert!(size_of::<GpuSegment>() == 48);

/// Push constants of segments.comp: the photon view and its parameters.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SegmentPush {
    origin: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    forward: [f32; 4],
    /// x: TIR remedy; y: Eq. 6.3.2 on; z: transmittance steps; w: the
    /// filter radius (f32 bits; the clipping margin).
    params: [u32; 4],
}

/// Push constants of lines.frag.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct LinePush {
    step: f32,
    radius: f32,
    line_raster: u32,
    transmittance_steps: u32,
}

pub struct VolumeLines {
    /// C: direct light, surface caustics, refraction seen by the camera.
    pub image_space: ImageSpace,
    /// A: airlight with volumetric shadows from C's shadow maps.
    pub airlight: Airlight,
    /// The volume caustic buffer of the last light recorded: N x N
    /// transmitted (or mirror-reflected) light rays, then N x N rays
    /// reflected off a dielectric's front face.
    pub segments: Buffer,
    /// B alone: radiance (rgb) and fragments per pixel (a).
    pub volume: Image,
    /// Light-space front/back G-buffer of the specular objects.
    pub light_view: SpecularGBuffer,
    pub buffer_size: u32,
    /// Buffer entries drawn: the transmitted half, or both halves with
    /// `front_reflection`.
    draw_count: u32,
    /// Distance to the first surface per pixel (floats).
    visibility: Buffer,
    lights: Vec<Light>,
    specular: Option<(Vec3, f32)>,
    segment_params: [u32; 4],
    line_push: LinePush,
    segment_pipeline: ComputePipeline,
    visibility_pipeline: ComputePipeline,
    line_pipeline: GraphicsPipeline,
    composite_pipeline: ComputePipeline,
    set: DescriptorSet,
    bound_radiance: vk::ImageView,
    _layout: DescriptorSetLayout,
}

impl VolumeLines {
    pub fn new(
        ctx: &Arc<Context>,
        params: &VolumeLinesParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        let step = params.ray_step;
        let radius = params.filter_radius;
        if radius > MAX_RADIUS_IN_STEPS * step {
            anyhow::bail!(
                "--param filter_radius={radius}: must be at most {MAX_RADIUS_IN_STEPS} x ray_step ({})",
                MAX_RADIUS_IN_STEPS * step
            );
        }
        let image_space =
            ImageSpace::new(ctx, &params.image_space, scene, scene_gpu, width, height)?;
        let airlight = Airlight::new(
            ctx,
            &params.airlight,
            params.image_space.direct.medium_steps,
            scene,
            scene_gpu,
            &image_space.direct.shadows,
        )?;
        let n = params.volume_buffer_size;
        let segments = Buffer::new(
            ctx,
            "volume caustic buffer",
            2 * (n as u64 * n as u64) * size_of::<GpuSegment>() as u64,
            BufferUsage::Storage,
        )?;
        let visibility = Buffer::new(
            ctx,
            "volume visibility",
            width as u64 * height as u64 * 4,
            BufferUsage::Storage,
        )?;
        let volume = Image::new(
            ctx,
            "volume caustic radiance",
            ImageDesc::new_2d(
                width,
                height,
                vk::Format::R32G32B32A32_SFLOAT,
                vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::STORAGE
                    | vk::ImageUsageFlags::TRANSFER_SRC,
            ),
        )?;
        let light_view = SpecularGBuffer::new(ctx, &scene_gpu.layout, n, n)?;
        let layout = DescriptorSetLayout::new(
            ctx,
            &[
                (b::VOLUME_LINES_BINDING_SEGMENTS, BindingKind::Storage),
                (
                    b::VOLUME_LINES_BINDING_FRONT_POSITION,
                    BindingKind::StorageImage,
                ),
                (
                    b::VOLUME_LINES_BINDING_FRONT_NORMAL,
                    BindingKind::StorageImage,
                ),
                (
                    b::VOLUME_LINES_BINDING_BACK_POSITION,
                    BindingKind::StorageImage,
                ),
                (
                    b::VOLUME_LINES_BINDING_BACK_NORMAL,
                    BindingKind::StorageImage,
                ),
                (b::VOLUME_LINES_BINDING_VISIBILITY, BindingKind::Storage),
                (
                    b::VOLUME_LINES_BINDING_OPAQUE_POSITION,
                    BindingKind::StorageImage,
                ),
                (
                    b::VOLUME_LINES_BINDING_SPECULAR_POSITION,
                    BindingKind::StorageImage,
                ),
                (b::VOLUME_LINES_BINDING_VOLUME, BindingKind::StorageImage),
                (b::VOLUME_LINES_BINDING_RADIANCE, BindingKind::StorageImage),
            ],
        )?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(b::VOLUME_LINES_BINDING_SEGMENTS, &segments)
            .write_storage_image(
                b::VOLUME_LINES_BINDING_FRONT_POSITION,
                &light_view.front_position,
            )
            .write_storage_image(
                b::VOLUME_LINES_BINDING_FRONT_NORMAL,
                &light_view.front_normal,
            )
            .write_storage_image(
                b::VOLUME_LINES_BINDING_BACK_POSITION,
                &light_view.back_position,
            )
            .write_storage_image(b::VOLUME_LINES_BINDING_BACK_NORMAL, &light_view.back_normal)
            .write_buffer(b::VOLUME_LINES_BINDING_VISIBILITY, &visibility)
            .write_storage_image(
                b::VOLUME_LINES_BINDING_OPAQUE_POSITION,
                &image_space.direct.gbuffer.position,
            )
            .write_storage_image(
                b::VOLUME_LINES_BINDING_SPECULAR_POSITION,
                &image_space.refraction.gbuffer.front_position,
            )
            .write_storage_image(b::VOLUME_LINES_BINDING_VOLUME, &volume);
        let sets = [&scene_gpu.layout, &layout];
        let segment_pipeline = ComputePipeline::new(
            ctx,
            "volume_lines/segments.comp",
            &sets,
            size_of::<SegmentPush>() as u32,
        )?;
        let visibility_pipeline =
            ComputePipeline::new(ctx, "volume_lines/visibility.comp", &sets, 0)?;
        let composite_pipeline =
            ComputePipeline::new(ctx, "volume_lines/composite.comp", &sets, 0)?;
        // A constant density (or none) gets fragments compiled without the
        // density field's code.
        let homogeneous = scene
            .medium
            .as_ref()
            .is_none_or(|m| matches!(m.density, Density::Constant(_)));
        let fragment = if homogeneous {
            "volume_lines/lines.frag"
        } else {
            "volume_lines/lines_heterogeneous.frag"
        };
        let mut desc = GraphicsPipelineDesc::new("volume_lines/lines.vert", fragment);
        desc.geometry = Some("volume_lines/lines.geom");
        desc.color_formats = vec![vk::Format::R32G32B32A32_SFLOAT];
        desc.additive = true;
        desc.topology = vk::PrimitiveTopology::POINT_LIST;
        desc.push_size = size_of::<LinePush>() as u32;
        let line_pipeline = GraphicsPipeline::new(ctx, &desc, &sets)?;
        let transmittance_steps = params.transmittance_steps;
        Ok(Self {
            image_space,
            airlight,
            segments,
            volume,
            light_view,
            buffer_size: n,
            draw_count: if params.front_reflection {
                2 * n * n
            } else {
                n * n
            },
            visibility,
            lights: scene
                .lights
                .iter()
                .take(b::MAX_LIGHTS as usize)
                .copied()
                .collect(),
            specular: specular_bounds(scene),
            segment_params: [
                params.image_space.tir_remedy,
                params.image_space.eq_6_3_2,
                transmittance_steps,
                radius.to_bits(),
            ],
            line_push: LinePush {
                step,
                radius,
                // Strict lines are 1-px rectangles about the line; otherwise
                // implementations rasterise a parallelogram (one fragment per
                // major-axis column, the Bresenham-like rule).
                line_raster: if ctx.limits.strict_lines == vk::TRUE {
                    b::LINE_RASTER_RECTANGULAR
                } else {
                    b::LINE_RASTER_PARALLELOGRAM
                },
                transmittance_steps,
            },
            segment_pipeline,
            visibility_pipeline,
            line_pipeline,
            composite_pipeline,
            set,
            bound_radiance: vk::ImageView::null(),
            _layout: layout,
        })
    }

    /// The photon view of light `l` (None: no specular objects, or a point
    /// light inside their bounding sphere).
    fn view(&self, l: usize) -> Option<PhotonViewPush> {
        photon_view(&self.lights[l], l as u32, self.specular?, self.buffer_size)
    }
}

impl TechniqueBuild for VolumeLines {
    const NAME: &'static str = "volume_lines";
    const DESCRIPTION: &'static str = "Hu et al. 2010: volume caustics as lines (light rays after one reflection or two refractions, drawn by a geometry shader, Eq. 3 per fragment), plus ray-marched airlight with volumetric shadows, over image_space's surface radiance attenuated by the medium";
    const COMPONENTS: &'static [Component] = &[
        Component::Direct,
        Component::SurfaceCaustics,
        Component::Airlight,
        Component::VolumeCaustics,
    ];
    type Params = VolumeLinesParams;

    fn build(
        ctx: &Arc<Context>,
        params: &VolumeLinesParams,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        Self::new(ctx, params, scene, scene_gpu, width, height)
    }
}

impl Technique for VolumeLines {
    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn update_live(&mut self, params: &Params) -> anyhow::Result<bool> {
        let params = VolumeLinesParams::from_params(params)?;
        self.image_space.set_live(&params.image_space);
        self.airlight.set_live(&params.airlight);
        Ok(true)
    }

    fn record(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        targets: &FrameTargets,
    ) -> crate::vk::VkResult<()> {
        self.image_space.record(rec, scene, targets)?;
        if self.bound_radiance != targets.radiance.view {
            // A set may not be updated while a submitted frame can use it.
            rec.wait_for_other_frames();
            self.set
                .write_storage_image(b::VOLUME_LINES_BINDING_RADIANCE, &targets.radiance);
            self.bound_radiance = targets.radiance.view;
        }
        let ctx = rec.ctx().clone();
        rec.pass("volume visibility", |cmd| {
            // The camera G-buffers were written by rasterisation; the
            // distances are overwritten after last frame's line fragments.
            barrier(
                &ctx,
                cmd,
                &[
                    ImageAccess::new(
                        &self.image_space.direct.gbuffer.position,
                        Access::ComputeRead,
                    ),
                    ImageAccess::new(
                        &self.image_space.refraction.gbuffer.front_position,
                        Access::ComputeRead,
                    ),
                ],
                &[BufferAccess::new(&self.visibility, Access::ComputeWrite)],
            );
            let groups = [targets.width.div_ceil(8), targets.height.div_ceil(8), 1];
            self.visibility_pipeline
                .dispatch(cmd, &[&scene.set, &self.set], &[], groups);
        });
        rec.pass("volume clear", |cmd| {
            barrier(
                &ctx,
                cmd,
                &[ImageAccess::discard(&self.volume, Access::ColorAttachment)],
                &[],
            );
            begin_rendering(
                &ctx,
                cmd,
                self.volume.extent(),
                &[(self.volume.view, Some([0.0; 4]))],
                None,
            );
            end_rendering(&ctx, cmd);
        });
        for l in 0..self.lights.len() {
            let Some(view) = self.view(l) else {
                if self.specular.is_some() {
                    log::warn!(
                        "light {l} lies inside the specular objects' bounds: no volume caustic"
                    );
                }
                continue;
            };
            let specular = self.specular.unwrap_or_default();
            let viewpoint = Viewpoint::Light {
                view_proj: photon_view_proj(&view, specular),
                origin: Vec3::from_slice(&view.origin[..3]),
                forward: Vec3::from_slice(&view.forward[..3]),
                orthographic: view.forward[3].to_bits() == b::SHADOW_PLANAR,
            };
            rec.pass("volume light view", |cmd| {
                // Overwritten entirely; its barriers wait for the previous
                // light's segment pass.
                self.light_view.draw(&ctx, cmd, scene, &viewpoint);
            });
            let push = SegmentPush {
                origin: view.origin,
                right: view.right,
                up: view.up,
                forward: view.forward,
                params: self.segment_params,
            };
            rec.pass("volume segments", |cmd| {
                // The light view's attachment writes become storage reads;
                // the buffer is rewritten after the previous light's lines
                // (or last frame's) pulled it.
                barrier(
                    &ctx,
                    cmd,
                    &self.light_view.compute_reads(),
                    &[
                        BufferAccess::new(&self.segments, Access::ComputeWrite),
                        BufferAccess::new(&scene.triangles, Access::ComputeRead),
                    ],
                );
                let groups = [
                    self.buffer_size.div_ceil(8),
                    self.buffer_size.div_ceil(8),
                    1,
                ];
                self.segment_pipeline.dispatch(
                    cmd,
                    &[&scene.set, &self.set],
                    bytemuck::bytes_of(&push),
                    groups,
                );
            });
            rec.pass("volume lines", |cmd| {
                // Segments pulled by the geometry shader and read again by
                // the fragments (so the next light's segment pass waits for
                // both); the distances read by the fragments.
                barrier(
                    &ctx,
                    cmd,
                    &[ImageAccess::new(&self.volume, Access::ColorAttachment)],
                    &[
                        BufferAccess::new(&self.segments, Access::GraphicsRead),
                        BufferAccess::new(&self.visibility, Access::FragmentRead),
                    ],
                );
                let extent = self.volume.extent();
                begin_rendering(&ctx, cmd, extent, &[(self.volume.view, None)], None);
                self.line_pipeline.bind(
                    cmd,
                    &[&scene.set, &self.set],
                    bytemuck::bytes_of(&self.line_push),
                    extent,
                );
                unsafe { ctx.device.cmd_draw(cmd, self.draw_count, 1, 0, 0) };
                end_rendering(&ctx, cmd);
            });
        }
        rec.pass("volume composite", |cmd| {
            // The lines' blended writes are read; the frame's radiance was
            // written by image_space's refraction pass.
            barrier(
                &ctx,
                cmd,
                &[
                    ImageAccess::new(&self.volume, Access::ComputeRead),
                    ImageAccess::new(&targets.radiance, Access::ComputeWrite),
                ],
                &[],
            );
            let groups = [targets.width.div_ceil(8), targets.height.div_ceil(8), 1];
            self.composite_pipeline
                .dispatch(cmd, &[&scene.set, &self.set], &[], groups);
        });
        // A: single scattering straight from the lights, shadowed by every
        // object (the shadow maps C recorded this frame).
        self.airlight.record(
            rec,
            scene,
            &self.image_space.direct.shadows,
            &targets.radiance,
        );
        Ok(())
    }

    fn set_lights(&mut self, lights: &[Light]) -> bool {
        if lights.len() != self.lights.len()
            || lights
                .iter()
                .zip(&self.lights)
                .any(|(a, b)| a.kind != b.kind)
        {
            return false;
        }
        if !self.image_space.set_lights(lights) {
            return false;
        }
        self.lights.copy_from_slice(lights);
        true
    }
}
