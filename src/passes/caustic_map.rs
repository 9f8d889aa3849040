//! Caustic maps (Wyman & Davis 2006, "Approximate, Image-Space Caustics"):
//! photons shot from each light through the specular objects, splatted into
//! a light-space map, projected onto the diffuse receivers.
//!
//! Each frame "caustic map clear" (`begin`), then per light (the light
//! views' loop, `LightViewConsumer::record_light`):
//! 1. "caustic photons" (glsl/caustic_map/photons.comp): one photon per texel
//!    of an N x N light view fitted to the specular objects' bounding sphere
//!    (perspective for point and spot lights, orthographic for directional
//!    ones). Flux I * Omega_texel (exact per-texel solid angle) or
//!    E * A_texel, times Fresnel and Beer-Lambert. At the first interface
//!    the photon splits into a reflected (F) and a refracted (1 - F) photon;
//!    traced chains then reflect with probability F at each further
//!    interface, weight unchanged, up to 128 bounces (unbiased, as the
//!    reference). `mode` picks how the
//!    refracted path is found: traced through the BVH (exact, default), or
//!    from light-space front/back G-buffers of the specular objects
//!    ("light view", `passes::light_views` (this map is one of its consumers):
//!    Wyman's two-sided refraction, shared with the camera) with the back
//!    interface by Eq. 6.3.1 or by marching the back-face map; the exit ray
//!    lands through the BVH. Buffer: `2 N^2` `GpuPhoton`s, refracted photons
//!    first, reflected ones second (reflected photons are always traced).
//! 2. "caustic splat" (glsl/caustic_map/splat.*): one point sprite per photon,
//!    S x S discrete Gaussian weights summing to 1, additive, into the
//!    caustic map: a 2D array with the light's shadow-map views
//!    (`passes::shadow::shadow_views`; a spot light gets a point light's
//!    cube faces, since caustics land outside its cone) at M x M texels,
//!    storing flux per texel (W) in rgb and, by min blending, the nearest
//!    depth along the light's view at which a photon in the texel landed
//!    in a.
//! 3. "caustic apply" (glsl/caustic_map/apply.comp, `CausticMap::apply`):
//!    E = Phi_texel / A_texel(x) on each diffuse receiver where the texel's
//!    photons landed: not nearer the light than their nearest depth (the
//!    top of a wall above the floor the refracted light reaches behind
//!    it), and with no diffuse surface between the receiver and that depth
//!    (the floor behind a column the photons landed on).
//!
//! In a participating medium (Hu et al. 2010 Sect. 5.3) the photons' flux
//! is attenuated by the medium's transmittance along every segment through
//! air (light -> first specular surface, between interfaces outside the
//! objects, exit -> receiver; solids hold no medium), and `apply`
//! multiplies the caustic radiance by the transmittance to the eye; both
//! deterministic (`medium_transmittance_steps`, `PhotonPaths::medium_steps`
//! midpoint steps for noise/grid densities), exactly 1 without a medium.
//!
//! Limits: the specular bounds are taken once at construction (animated
//! specular objects would need them per frame); a point light inside the
//! specular bounding sphere gets no caustics (logged); sprites crossing a
//! map edge or a cube-face edge lose their clipped part. The splat draws
//! every photon once per view of the light (6x for a point or spot light,
//! culled in the vertex shader): 0.6 s of a 1.05 s frame at 512² on
//! lavapipe.
//! Mode 1 runs the camera's two-sided refraction code
//! (glsl/common/image_space_refraction.glsl) with the per-vertex d_N. On
//! the ball lens it still shows a faint halo outside the shadow with the
//! default `tir_remedy` 1: about 21% of the entering photons meet total
//! internal reflection at the approximated exit (Eq. 6.3.1's d~ falls
//! short near the rim, whatever d_N) and, clamped to the critical angle,
//! leave tangent to the sphere. `tir_remedy` 0 (T2 = T1) or 2 (reflect,
//! losing that flux upward) show no halo. The small dark spots in the
//! caustic (four, symmetric about the light view's axes; three visible from
//! the ball_lens camera) remain with every remedy, so the per-photon BVH
//! cast for d_N was not their cause; still unexplained. On the gemstone
//! (diamond) 99.2% of mode 1's photons meet total internal reflection at
//! the approximated exit, a real one there, and every remedy sends the
//! trapped light on towards the floor (85% of the landing flux within 1 m
//! of the gem, 8.9 W where the traced photons land 2.2 W): no energy is
//! created (tests/suite/image_space.rs checks that every mode lands at most the
//! flux that entered), but two interfaces cannot tell where a diamond
//! lets its light out (mostly upwards). The default stays mode 0 (exact)
//! for these reasons; mode 2 shows neither artefact on the ball lens but
//! lands only 5% of the gem's flux (it drops the photons that meet total
//! internal reflection or no back face).

use crate::frame::SceneGpu;
use crate::passes::camera_refraction::RefractionPush;
use crate::passes::direct_light::DirectParams;
use crate::passes::gbuffer::GBuffer;
use crate::passes::light_views::{LightView, LightViewConsumer, LightViews};
use crate::passes::shadow::{shadow_views, GpuShadowLight};
use crate::passes::specular_gbuffer::SpecularGBuffer;
use crate::scene::{Light, LightKind};
use crate::shader_bindings as b;
use crate::vk::{
    groups_8x8, Access, Buffer, BufferUsage, ComputePipeline, Context, DescriptorSet,
    DescriptorSetLayout, FrameRecorder, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc,
    Sampler, Specialization, VkResult,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::mem::size_of;
use std::sync::Arc;

pub const CAUSTIC_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// One photon, mirrored by `Photon` in glsl/caustic_map/photon.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuPhoton {
    /// xyz landing point p3; w = 1 if it landed on a diffuse surface.
    pub position: [f32; 4],
    /// rgb flux (W); w: the texel's solid angle (sr) or area (m^2).
    pub flux: [f32; 4],
    /// xyz arrival direction.
    pub dir: [f32; 4],
}
const _: () = assert!(size_of::<GpuPhoton>() == 48);

/// Push constants of photons.comp: the light's view (`LightView`) and how
/// its photons find their paths.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct PhotonViewPush {
    pub origin: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub forward: [f32; 4],
    /// x: midpoint steps of the medium transmittance along the photon's
    /// paths through air (`medium_steps`). The path mode, TIR remedy and
    /// Eq. 6.3.2 switch are specialisation constants of the pipeline.
    pub steps: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SplatPush {
    light: u32,
    view: u32,
    size: u32,
    splat_size: u32,
}

crate::declare_params! {
    /// Wyman's image-space parameters: `DirectLight`'s, then the caustic
    /// map's and the camera refraction's (the `image_space` technique's
    /// parameters, and a group of `volume_lines'`).
    pub struct ImageSpaceParams {
        @group direct: DirectParams;
        photon_buffer_size: u32 [64, 1024] = 512, rebuild,
            "photon buffer resolution (photons per side of the light view)";
        caustic_map_size: u32 [64, 1024] = 512, rebuild,
            "caustic map resolution per light view (texels per side)";
        splat_size: u32 [1, 15] = 7, rebuild,
            "photon splat width in caustic-map texels (odd; an even value is raised by 1)";
        photon_mode: u32 [0, 2] = 0, rebuild,
            "0: photon paths traced exactly through the BVH; 1: Wyman's two-sided image-space refraction from light-space front/back G-buffers (Eq. 6.3.1 distance); 2: the same G-buffers, the refracted ray marched against the back-face map (exact for convex objects)";
        tir_remedy: u32 [0, 2] = 1, rebuild,
            "total internal reflection at the approximated exit (Wyman 2006's ad hoc remedies; camera and photon_mode 1): 0 single refraction (T2 = T1), 1 clamp to the critical angle (T2 tangent to the back face), 2 reflect and ignore the refractor. Default 1, of the two Wyman recommends (the first 'behaves poorly in dynamic scenes'): a reflected ray heads back toward the camera or the light, where the image-space search has no data and photons fly up past the light, while the clamped ray goes on through, as the light does on average";
        eq_6_3_2: u32 [0, 1] = 1, rebuild,
            "1: where d~ overshoots and the back-face texel holds no normal, use Wyman's Eq. 6.3.2 (N2 = T1 - (V.T1) V, the exit through the side); 0: drop the transmitted light there";
        camera_exit: u32 [0, 1] = 0, rebuild,
            "what the camera sees through closed glass: 0 the refracted ray traced through the BVH to its exit (exact, total internal reflections followed); 1 Wyman's two-sided image-space exit (Eq. 6.3.1 distance, back-face normals; approximate, it sends rays near the silhouette to the wrong place)";
        search_steps: u32 [4, 256] = 32, live,
            "linear steps of the image-space search of refracted and reflected camera rays against the opaque frame (then 10 bisections)";
        caustics_on_change: bool [0, 1] = 0, live,
            "1: recompute the caustic map only when a light moved or animated geometry changed, reusing the last one otherwise; 0: every frame (benchmarks)";
    }
}

impl ImageSpaceParams {
    /// The camera refraction's push constants.
    pub fn refraction(&self) -> RefractionPush {
        RefractionPush {
            tir_remedy: self.tir_remedy,
            use_eq632: self.eq_6_3_2,
            search_steps: self.search_steps,
            exit: self.camera_exit,
        }
    }

    /// The caustic map of these parameters, its photons from `light_views`.
    pub fn caustic_map(
        &self,
        ctx: &Arc<Context>,
        scene_gpu: &SceneGpu,
        light_views: &LightViews,
    ) -> VkResult<CausticMap> {
        CausticMap::new(
            ctx,
            scene_gpu,
            light_views,
            self.caustic_map_size,
            self.splat_size,
            PhotonPaths {
                mode: self.photon_mode,
                tir_remedy: self.tir_remedy,
                use_eq632: self.eq_6_3_2 != 0,
                medium_steps: self.direct.medium_steps,
                on_change: self.caustics_on_change,
            },
        )
    }
}

/// How photons find their refracted paths.
#[derive(Clone, Copy, Debug)]
pub struct PhotonPaths {
    /// `PHOTON_MODE_*`.
    pub mode: u32,
    /// `TIR_*` (photon mode 1).
    pub tir_remedy: u32,
    /// Eq. 6.3.2 where the back-face texel holds no normal (photon mode 1).
    pub use_eq632: bool,
    /// Midpoint steps of the transmittance through inhomogeneous media
    /// along the photons' air segments (`medium_steps`).
    pub medium_steps: u32,
    /// `caustics_on_change`: recompute only when a light or the geometry moved.
    pub on_change: bool,
}

pub struct CausticMap {
    /// `2 N^2` photons (refracted, then reflected), storage, reused per light.
    pub photons: Buffer,
    /// Flux per texel (rgb, W) and splat weight sum (a); 6 layers per light.
    pub map: Image,
    /// The caustic views, `GpuShadowLight[MAX_LIGHTS]` (uniform).
    pub views: Buffer,
    pub photon_size: u32,
    pub map_size: u32,
    pub splat_size: u32,
    /// `PHOTON_MODE_TRACED` or `PHOTON_MODE_IMAGE_SPACE`.
    pub mode: u32,
    /// `[TIR_*, 1 if Eq. 6.3.2 is on]` for the image-space photon mode.
    pub refraction: [u32; 2],
    /// Midpoint steps of the medium transmittance (`PhotonPaths::medium_steps`).
    pub medium_steps: u32,
    /// Lights with caustic views (`MAX_LIGHTS` at most).
    pub light_count: u32,
    /// This frame's caustic views (`begin`), read by each light's splat.
    frame_views: Vec<GpuShadowLight>,
    photon_pipeline: ComputePipeline,
    splat_pipeline: GraphicsPipeline,
    pub set: DescriptorSet,
    _layout: DescriptorSetLayout,
    apply: ComputePipeline,
    apply_set: DescriptorSet,
    /// `caustics_on_change`: reuse the caustic map while nothing it depends
    /// on moved (Wyman 2006, "Putting it Together": "we only update the
    /// caustic map after changes to the light or scene geometry").
    on_change: bool,
    /// Geometry time the caustic map was computed for; `None` when it must
    /// be recomputed (never computed, or a light moved).
    geometry_time: Option<f32>,
    _apply_layout: DescriptorSetLayout,
    sampler: Sampler,
}

impl CausticMap {
    /// `light_views`' resolution of photon texels, `map_size`^2 caustic
    /// texels per view, sprites of `splat_size` (odd) texels; `apply` adds
    /// the caustic radiance on `gbuffer`'s diffuse receivers to `radiance`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Arc<Context>,
        scene_gpu: &SceneGpu,
        light_views: &LightViews,
        map_size: u32,
        splat_size: u32,
        paths: PhotonPaths,
    ) -> VkResult<Self> {
        let photon_size = light_views.size;
        let layers = b::SHADOW_LAYERS_PER_LIGHT * (light_views.lights().len() as u32).max(1);
        let map = Image::new(
            ctx,
            "caustic map (flux per texel)",
            ImageDesc {
                width: map_size,
                height: map_size,
                layers,
                format: CAUSTIC_FORMAT,
                usage: vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::STORAGE
                    | vk::ImageUsageFlags::TRANSFER_SRC,
            },
        )?;
        let photons = Buffer::new(
            ctx,
            "photon buffer",
            (2 * photon_size as u64 * photon_size as u64) * size_of::<GpuPhoton>() as u64,
            BufferUsage::Storage,
        )?;
        let views = Buffer::new(
            ctx,
            "caustic views",
            (size_of::<GpuShadowLight>() * b::MAX_LIGHTS as usize) as u64,
            BufferUsage::Uniform,
        )?;
        let layout = DescriptorSetLayout::of_shaders(
            ctx,
            1,
            &[
                "caustic_map/photons.comp",
                "caustic_map/splat.vert",
                "caustic_map/splat.frag",
            ],
        )?;
        let set = DescriptorSet::new(ctx, &layout)?;
        set.write_buffer(b::CAUSTIC_BINDING_VIEWS, &views);
        let photon_pipeline = ComputePipeline::specialized(
            ctx,
            "caustic_map/photons.comp",
            &Specialization::new()
                .u32(b::CAUSTIC_SPEC_PHOTON_MODE, paths.mode)
                .u32(b::CAUSTIC_SPEC_TIR_REMEDY, paths.tir_remedy)
                .bool(b::CAUSTIC_SPEC_EQ632, paths.use_eq632),
            &[&scene_gpu.layout, &layout],
            size_of::<PhotonViewPush>() as u32,
        )?;
        let mut desc =
            GraphicsPipelineDesc::new("caustic_map/splat.vert", "caustic_map/splat.frag");
        desc.color_formats = vec![CAUSTIC_FORMAT];
        desc.additive = true;
        // Alpha: the nearest landing depth of the texel's photons (apply.comp).
        desc.alpha_min = true;
        desc.topology = vk::PrimitiveTopology::POINT_LIST;
        desc.push_size = size_of::<SplatPush>() as u32;
        let splat_pipeline = GraphicsPipeline::new(ctx, &desc, &[&scene_gpu.layout, &layout])?;
        let apply_layout = DescriptorSetLayout::of_shaders(ctx, 1, &["caustic_map/apply.comp"])?;
        let sampler = Sampler::new(ctx, vk::Filter::NEAREST)?;
        let apply_set = DescriptorSet::new(ctx, &apply_layout)?;
        apply_set.write_buffer(b::CAUSTIC_BINDING_VIEWS, &views);
        let apply = ComputePipeline::new(
            ctx,
            "caustic_map/apply.comp",
            &[&scene_gpu.layout, &apply_layout],
            size_of::<[u32; 4]>() as u32,
        )?;
        Ok(Self {
            photons,
            map,
            views,
            photon_size,
            map_size,
            splat_size: splat_size | 1,
            mode: paths.mode,
            refraction: [paths.tir_remedy, u32::from(paths.use_eq632)],
            medium_steps: paths.medium_steps,
            light_count: light_views.lights().len() as u32,
            frame_views: Vec::new(),
            photon_pipeline,
            splat_pipeline,
            set,
            _layout: layout,
            apply,
            apply_set,
            on_change: paths.on_change,
            geometry_time: None,
            _apply_layout: apply_layout,
            sampler,
        })
    }

    /// The caustic views of every light: its shadow views at the map size,
    /// except that a spot light gets a point light's six cube faces.
    /// Specular objects send its light outside its cone (the gemstone's
    /// facets throw 23% of the landing flux there), and a photon outside
    /// every view is culled by the splat.
    pub fn views(&self, lights: &[Light], sphere: (Vec3, f32)) -> Vec<GpuShadowLight> {
        lights
            .iter()
            .enumerate()
            .map(|(l, light)| {
                let all_around = match light.kind {
                    LightKind::Spot => Light {
                        kind: LightKind::Point,
                        ..*light
                    },
                    _ => *light,
                };
                shadow_views(
                    &all_around,
                    sphere,
                    self.map_size,
                    l as u32 * b::SHADOW_LAYERS_PER_LIGHT,
                )
            })
            .collect()
    }

    /// `caustics_on_change` (live).
    pub fn set_on_change(&mut self, on_change: bool) {
        if on_change != self.on_change {
            self.on_change = on_change;
            self.geometry_time = None;
        }
    }

    /// A light moved: the next frame recomputes the map.
    pub fn invalidate(&mut self) {
        self.geometry_time = None;
    }

    /// Whether this frame recomputes the map (always, unless
    /// `caustics_on_change` and nothing moved since the last one); if so
    /// `begin` must be called and the map take part in the light loop.
    pub fn needs_update(&self, scene: &SceneGpu) -> bool {
        !self.on_change || self.geometry_time != Some(scene.geometry_time)
    }

    /// The photon push of `view`: the light view and the photon paths.
    pub fn photon_push(&self, view: &LightView) -> PhotonViewPush {
        PhotonViewPush {
            origin: view.origin,
            right: view.right,
            up: view.up,
            forward: view.forward,
            steps: [self.medium_steps, 0, 0, 0],
        }
    }

    /// Records "caustic map clear" and takes this frame's views of
    /// `light_views`' lights; the lights' passes follow in
    /// `LightViews::record` (this map as a consumer).
    pub fn begin(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        light_views: &LightViews,
    ) -> VkResult<()> {
        let views = self.views(light_views.lights(), scene.sphere);
        // Through the frame's upload ring: earlier frames may still read the buffer.
        rec.upload(&self.views, bytemuck::cast_slice(&views));
        self.frame_views = views;
        self.geometry_time = Some(scene.geometry_time);
        rec.pass("caustic map clear")
            .overwrite(&self.map, Access::ColorAttachment)
            .record(|c| {
                let extent = self.map.extent();
                for &view in &self.map.layer_views {
                    // No flux, and no photon landed nearer than anything.
                    c.render(
                        extent,
                        &[(view, Some([0.0, 0.0, 0.0, f32::MAX]))],
                        None,
                        |_| {},
                    );
                }
            });
        Ok(())
    }

    /// Records "caustic apply": E = Phi_texel / A_texel(x) on the diffuse
    /// receivers of `gbuffer`, added to `radiance` (the ones given to `new`).
    pub fn apply(
        &self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        gbuffer: &GBuffer,
        radiance: &Image,
    ) {
        // apply.comp's push constants: light count, medium steps, splat size.
        let push = [self.light_count, self.medium_steps, self.splat_size, 0];
        let extent = radiance.extent();
        // The splats' attachment writes and the direct pass's radiance
        // writes must be visible to this read-modify-write.
        let set = &self.apply_set;
        rec.pass("caustic apply")
            .sampled(
                set,
                b::CAUSTIC_BINDING_MAP,
                &self.map,
                &self.sampler,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                b::CAUSTIC_BINDING_POSITION,
                &gbuffer.position,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                b::CAUSTIC_BINDING_NORMAL,
                &gbuffer.normal,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                b::CAUSTIC_BINDING_ALBEDO,
                &gbuffer.albedo,
                Access::ComputeRead,
            )
            .storage_image(
                set,
                b::CAUSTIC_BINDING_RADIANCE,
                radiance,
                Access::ComputeWrite,
            )
            .record(|c| {
                let groups = groups_8x8(extent.width, extent.height);
                c.dispatch(
                    &self.apply,
                    &[&scene.set, &self.apply_set],
                    bytemuck::bytes_of(&push),
                    groups,
                );
            });
    }
}

impl LightViewConsumer for CausticMap {
    fn reads_gbuffer(&self) -> bool {
        self.mode != b::PHOTON_MODE_TRACED
    }

    /// Records "caustic photons" and "caustic splat" for light `l`; the
    /// photon buffer is reused, so each light's splat waits for its photons
    /// and the next light's photons wait for that splat.
    fn record_light(
        &mut self,
        rec: &mut FrameRecorder,
        scene: &SceneGpu,
        l: usize,
        view: &LightView,
        light_view: &SpecularGBuffer,
    ) {
        let push = self.photon_push(view);
        let v = self.frame_views[l];
        // Write-after-read against the previous light's splat (or last
        // frame's readers). The light-view attachments are read as storage
        // images (in GENERAL layout even in traced mode: the shader declares
        // them, so they must be in the bound layout).
        let set = &self.set;
        let pass = rec
            .pass("caustic photons")
            .buffer(
                set,
                b::CAUSTIC_BINDING_PHOTONS,
                &self.photons,
                Access::ComputeWrite,
            )
            .read(&scene.triangles, Access::ComputeRead);
        light_view
            .bind_reads(
                pass,
                set,
                [
                    b::CAUSTIC_BINDING_FRONT_POSITION,
                    b::CAUSTIC_BINDING_FRONT_NORMAL,
                    b::CAUSTIC_BINDING_BACK_POSITION,
                    b::CAUSTIC_BINDING_BACK_NORMAL,
                ],
            )
            .record(|c| {
                let groups = groups_8x8(self.photon_size, self.photon_size);
                c.dispatch(
                    &self.photon_pipeline,
                    &[&scene.set, &self.set],
                    bytemuck::bytes_of(&push),
                    groups,
                );
            });
        // The photons written by compute are pulled by the vertex shader.
        rec.pass("caustic splat")
            .write(&self.map, Access::ColorAttachment)
            .buffer(
                &self.set,
                b::CAUSTIC_BINDING_PHOTONS,
                &self.photons,
                Access::VertexRead,
            )
            .record(|c| {
                let extent = self.map.extent();
                let count = 2 * self.photon_size * self.photon_size;
                for face in 0..v.info[1] {
                    let layer = (v.info[2] + face) as usize;
                    let push = SplatPush {
                        light: l as u32,
                        view: face,
                        size: self.map_size,
                        splat_size: self.splat_size,
                    };
                    let colors = [(self.map.layer_views[layer], None)];
                    c.render(extent, &colors, None, |r| {
                        let sets = [&scene.set, &self.set];
                        r.bind(&self.splat_pipeline, &sets, bytemuck::bytes_of(&push));
                        r.draw(count);
                    });
                }
            });
    }
}
