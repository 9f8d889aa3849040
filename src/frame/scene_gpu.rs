//! The scene on the GPU: world-space triangles in BVH leaf order, the BVH,
//! materials, lights, medium and the per-frame uniform block, bound as
//! descriptor set 0 (glsl/common/scene.glsl) by every pass that reads them.

use super::{AlbedoTextures, EnvironmentGpu};
use crate::bvh::Bvh;
use crate::gpu::{
    GpuEmitter, GpuFrame, GpuLight, GpuMaterial, GpuMedium, GpuTriangle, GpuTriangleUv,
};
use crate::radiometry::Component;
use crate::scene::{Camera, Density, MaterialKind, Scene, Triangle};
use crate::shader_bindings as b;
use crate::vk::{
    Buffer, BufferUsage, Context, DescriptorSet, DescriptorSetLayout, FrameRecorder, SetResource,
    VkError, VkResult,
};
use glam::{Mat4, Vec3};
use std::cell::Cell;
use std::sync::Arc;

/// Statistics of the uploaded geometry (printed by `render`, recorded in BENCHMARKS.md).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct GeometryStats {
    pub triangles: usize,
    pub bvh_nodes: usize,
    pub bvh_leaves: usize,
    pub bvh_depth: u32,
    pub bvh_build_ms: f64,
}

pub struct SceneGpu {
    pub triangles: Buffer,
    /// UVs per triangle, leaf order (`GpuTriangleUv`). Never re-uploaded:
    /// the motions keep every triangle's UVs.
    pub triangle_uvs: Buffer,
    pub albedo_textures: AlbedoTextures,
    /// Area lights (`GpuEmitter`; one zeroed record when there are none).
    pub emitters: Buffer,
    emitter_count: u32,
    pub environment: EnvironmentGpu,
    pub bvh_nodes: Buffer,
    pub materials: Buffer,
    pub lights: Buffer,
    pub medium: Buffer,
    pub density_grid: Buffer,
    /// The frame constants (device-local; written by a copy in each frame's
    /// command buffer, so frames in flight never share host-written memory).
    pub frame: Buffer,
    /// The host's copy of the constants last written (`upload_frame`).
    frame_constants: Cell<GpuFrame>,
    pub layout: DescriptorSetLayout,
    pub set: DescriptorSet,
    pub stats: GeometryStats,
    /// Bounding sphere (centre, radius) of the scene at the uploaded time.
    pub sphere: (Vec3, f32),
    /// Animation time of the uploaded geometry: techniques that cache
    /// light-space results (`image_space` with `caustics_on_change`) compare it.
    pub geometry_time: f32,
    pub triangle_count: u32,
    /// The path-type components techniques draw (`Component::mask` bits),
    /// written into the frame constants; all of them unless a caller narrows it.
    pub components: u32,
    /// Frames of the same still view accumulated before this one
    /// (`Renderer::set_accumulation`; 0 in motion or without accumulation):
    /// the frame constants' `components.z`, which stochastic passes mix
    /// into their seeds so that each still frame draws new samples.
    pub still_frames: u32,
    /// Per uploaded triangle, the d_N of its three vertices (kept across
    /// refits, see `update_geometry`).
    normal_thickness: Vec<[f32; 3]>,
    bvh: Bvh,
}

/// The area lights at `time` (`Scene::emitter_at`), one zeroed entry when
/// there are none (a buffer is never empty).
/// The area lights' records at `time` (the first records of the emitter
/// buffer; the emissive triangles follow them).
fn gpu_area_lights(scene: &Scene, time: f32) -> Vec<GpuEmitter> {
    (0..scene.emitters.len())
        .map(|i| GpuEmitter::new(&scene.emitter_at(i, time)))
        .collect()
}

fn gpu_medium(scene: &Scene) -> GpuMedium {
    scene
        .medium
        .as_ref()
        .map(GpuMedium::new)
        .unwrap_or_else(GpuMedium::none)
}

/// Closed dielectric objects get Wyman's per-vertex d_N
/// (`Bvh::set_normal_thickness`). Water is an open sheet: it has no far
/// side, so its d_N stays 0 (the shaders then use d_V).
fn is_refractor(scene: &Scene, material: u32, object: u32) -> bool {
    let dielectric = scene
        .materials
        .get(material as usize)
        .is_some_and(|m| m.kind == MaterialKind::Dielectric);
    let water = scene
        .objects
        .get(object as usize)
        .is_some_and(|o| o.water.is_some());
    dielectric && !water
}

/// View and projection for Vulkan: right-handed view, depth 0..1, y down in
/// clip space so image row 0 is the top.
pub fn camera_matrices(camera: &Camera, aspect: f32) -> (Mat4, Mat4) {
    let view = Mat4::look_at_rh(camera.eye, camera.target, camera.up);
    let mut proj = Mat4::perspective_rh(camera.fov_y_deg.to_radians(), aspect, 0.01, 1000.0);
    proj.y_axis.y *= -1.0;
    (view, proj)
}

impl SceneGpu {
    pub fn new(ctx: &Arc<Context>, scene: &Scene, time: f32) -> VkResult<SceneGpu> {
        let start = std::time::Instant::now();
        let triangles = scene.triangles(time);
        // Every shader binds the triangle buffer whole: a scene it cannot
        // hold is refused here, before the BVH build (seconds at millions).
        let size = std::mem::size_of::<GpuTriangle>() as u64;
        let most = ctx.limits.max_storage_buffer_range as u64 / size;
        if triangles.len() as u64 > most {
            return Err(VkError::OverLimit(format!(
                "{} triangles: the device holds at most {most} ({size} bytes each in one storage buffer, maxStorageBufferRange {})",
                triangles.len(),
                crate::vk::bytes(ctx.limits.max_storage_buffer_range as u64)
            )));
        }
        let world_ms = start.elapsed().as_secs_f64() * 1e3;
        let bvh = Bvh::build(&triangles);
        let gpu_triangles = Self::gpu_triangles(scene, &bvh, &triangles);
        let normal_thickness = gpu_triangles
            .iter()
            .map(|t| [t.n0[3], t.n1[3], t.n2[3]])
            .collect();
        let stats = GeometryStats {
            triangles: triangles.len(),
            bvh_nodes: bvh.nodes.len(),
            bvh_leaves: bvh.leaf_count,
            bvh_depth: bvh.depth,
            bvh_build_ms: bvh.build_ms,
        };
        let sphere = scene.bounding_sphere(time);
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(GpuMaterial::new).collect();
        // The scene's lights, then the stand-ins of its sun and rect lights
        // (`frame::caustic_lights`): the reference and `direct` use
        // only the first `frame.counts.x`, the caustic techniques all.
        let mut lights: Vec<GpuLight> = crate::frame::caustic_lights(scene)
            .iter()
            .map(|l| GpuLight::new(l, sphere.1))
            .collect();
        if lights.is_empty() {
            lights.push(bytemuck::Zeroable::zeroed());
        }
        let medium = gpu_medium(scene);
        let grid: Vec<f32> = match scene.medium.as_ref().map(|m| &m.density) {
            Some(Density::Grid { values, .. }) => values.clone(),
            _ => vec![0.0],
        };
        let storage = BufferUsage::Storage;
        let upload = std::time::Instant::now();
        let tri_data = if gpu_triangles.is_empty() {
            vec![bytemuck::Zeroable::zeroed()]
        } else {
            gpu_triangles
        };
        let triangles_buf = Buffer::with_data::<GpuTriangle>(ctx, "triangles", &tri_data, storage)?;
        let mut uvs: Vec<GpuTriangleUv> = bvh
            .triangle_order
            .iter()
            .map(|&i| GpuTriangleUv::new(&triangles[i as usize]))
            .collect();
        if uvs.is_empty() {
            uvs.push(bytemuck::Zeroable::zeroed());
        }
        let uvs_buf = Buffer::with_data(ctx, "triangle uvs", &uvs, storage)?;
        let albedo_textures = AlbedoTextures::new(ctx, &scene.textures)?;
        let nodes_buf = Buffer::with_data(ctx, "bvh nodes", &bvh.nodes, storage)?;
        let materials_buf = Buffer::with_data(ctx, "materials", &materials, storage)?;
        // The area lights, then the emissive triangles (at `time`: an
        // animated one's records stay where it was then).
        let mut emitters = gpu_area_lights(scene, time);
        emitters.extend(GpuEmitter::emissive_triangles(scene, &triangles));
        let emitter_count = emitters.len() as u32;
        if emitters.is_empty() {
            emitters.push(bytemuck::Zeroable::zeroed());
        }
        let emitters_buf = Buffer::with_data(ctx, "area lights", &emitters, storage)?;
        let environment = EnvironmentGpu::new(ctx, scene.environment.as_ref(), sphere.1)?;
        let lights_buf = Buffer::with_data(ctx, "lights", &lights, storage)?;
        let medium_buf = Buffer::with_data(ctx, "medium", &[medium], storage)?;
        let grid_buf = Buffer::with_data(ctx, "density grid", &grid, storage)?;
        let frame_buf = Buffer::new(
            ctx,
            "frame constants",
            std::mem::size_of::<GpuFrame>() as u64,
            BufferUsage::Uniform,
        )?;
        use SetResource::{Buffer as Buf, Texture};
        let (layout, set) = DescriptorSet::of_resources(
            ctx,
            &[
                (b::BINDING_FRAME, Buf(&frame_buf)),
                (b::BINDING_TRIANGLES, Buf(&triangles_buf)),
                (b::BINDING_BVH_NODES, Buf(&nodes_buf)),
                (b::BINDING_MATERIALS, Buf(&materials_buf)),
                (b::BINDING_LIGHTS, Buf(&lights_buf)),
                (b::BINDING_MEDIUM, Buf(&medium_buf)),
                (b::BINDING_DENSITY_GRID, Buf(&grid_buf)),
                (b::BINDING_TRIANGLE_UVS, Buf(&uvs_buf)),
                (
                    b::BINDING_ALBEDO_TEXTURES,
                    Texture(&albedo_textures.image, &albedo_textures.sampler),
                ),
                (b::BINDING_EMITTERS, Buf(&emitters_buf)),
                (
                    b::BINDING_ENVIRONMENT,
                    Texture(&environment.image, &environment.sampler),
                ),
                (b::BINDING_ENVIRONMENT_DATA, Buf(&environment.data)),
            ],
        )?;
        // The load phases' costs (RUST_LOG=info): scripts/gltf-bench.sh reads them.
        log::info!(
            "scene on the device: world-space triangles {world_ms:.1} ms, BVH build {:.1} ms, upload {:.1} ms",
            bvh.build_ms,
            upload.elapsed().as_secs_f64() * 1e3
        );
        Ok(SceneGpu {
            triangle_count: triangles.len() as u32,
            triangles: triangles_buf,
            triangle_uvs: uvs_buf,
            albedo_textures,
            emitters: emitters_buf,
            emitter_count,
            environment,
            bvh_nodes: nodes_buf,
            materials: materials_buf,
            lights: lights_buf,
            medium: medium_buf,
            density_grid: grid_buf,
            frame: frame_buf,
            frame_constants: Cell::new(bytemuck::Zeroable::zeroed()),
            layout,
            set,
            stats,
            sphere,
            components: Component::All.mask(),
            still_frames: 0,
            geometry_time: time,
            normal_thickness,
            bvh,
        })
    }

    /// The triangle buffer's contents: `triangles` (of `scene`) in `bvh`'s
    /// leaf order, with Wyman's per-vertex d_N on the dielectric ones.
    pub fn gpu_triangles(scene: &Scene, bvh: &Bvh, triangles: &[Triangle]) -> Vec<GpuTriangle> {
        let mut gpu = bvh.gpu_triangles(triangles);
        bvh.set_normal_thickness(&mut gpu, |m, o| is_refractor(scene, m, o));
        gpu
    }

    /// The BVH the GPU traverses (its `nodes` are the uploaded `bvh_nodes`;
    /// `triangle_order` maps the uploaded leaf-order triangles to the scene's).
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Whether this frame draws component `c` (`components` has its bit).
    /// A technique skips the passes whose only output is a component not
    /// drawn: the shaders would multiply it by `component_weight` = 0, so
    /// the image is the same, and a component's frame (the demo's C key,
    /// `render --component`, `compare`) costs only what it draws.
    pub fn draws(&self, c: Component) -> bool {
        self.components & c.mask() != 0
    }

    /// Refits the BVH to the triangles at `time` (animated scenes) and
    /// writes both through this frame's upload ring: earlier frames in
    /// flight still read the old geometry, which the frame's copy replaces
    /// only after their reads (queue order and the copy's barrier).
    pub fn update_geometry(&mut self, rec: &mut FrameRecorder, scene: &Scene, time: f32) {
        let triangles = scene.triangles(time);
        self.bvh.refit(&triangles);
        // d_N is kept from the upload: the `animate` motions are rigid, which
        // leaves every thickness unchanged, and water, the only geometry that
        // deforms, has none. (A refit keeps the leaf order.)
        let mut gpu_triangles = self.bvh.gpu_triangles(&triangles);
        for (t, d) in gpu_triangles.iter_mut().zip(&self.normal_thickness) {
            (t.n0[3], t.n1[3], t.n2[3]) = (d[0], d[1], d[2]);
        }
        rec.upload(&self.triangles, bytemuck::cast_slice(&gpu_triangles));
        rec.upload(&self.bvh_nodes, bytemuck::cast_slice(&self.bvh.nodes));
        // Sphere lights with `animate` move with their geometry (the
        // buffer's first records; the emissive triangles' stay).
        rec.upload(
            &self.emitters,
            bytemuck::cast_slice(&gpu_area_lights(scene, time)),
        );
        self.sphere = scene.bounding_sphere(time);
        self.geometry_time = time;
    }

    /// The environment's `rotate` changed (`Scene::set_environment_rotation`):
    /// re-uploads its constants and the lights, whose stand-in for the
    /// environment's sun turned with it. The caller has waited for every
    /// frame that read the old ones.
    pub fn update_environment(&mut self, scene: &Scene) -> VkResult<()> {
        self.environment
            .update(scene.environment.as_ref(), self.sphere.1)?;
        self.update_lights(scene)
    }

    /// Re-uploads moved lights (same count). The caller has waited for every
    /// frame that read the old ones.
    pub fn update_lights(&self, scene: &Scene) -> VkResult<()> {
        let lights: Vec<GpuLight> = crate::frame::caustic_lights(scene)
            .iter()
            .map(|l| GpuLight::new(l, self.sphere.1))
            .collect();
        self.lights.upload(bytemuck::cast_slice(&lights))
    }

    /// Re-uploads the medium's coefficients after `scene.medium` was edited
    /// in place (the demo's sliders; same density kind and grid). The caller
    /// has waited for every frame that read the old ones.
    pub fn update_medium(&self, scene: &Scene) -> VkResult<()> {
        let medium = gpu_medium(scene);
        self.medium.upload(bytemuck::bytes_of(&medium))
    }

    /// Writes the per-frame constants for an image of `width` x `height`
    /// now, waiting for the copy (tests and the reference, between frames).
    pub fn update_frame(
        &self,
        scene: &Scene,
        width: u32,
        height: u32,
        time: f32,
        frame_index: u32,
    ) -> VkResult<()> {
        let data = self.constants(scene, (width, height), time, frame_index);
        self.frame.upload(bytemuck::bytes_of(&data))
    }

    /// Writes this frame's constants through its upload ring.
    pub fn upload_frame(
        &self,
        rec: &mut FrameRecorder,
        scene: &Scene,
        size: (u32, u32),
        time: f32,
        frame_index: u32,
    ) {
        let data = self.constants(scene, size, time, frame_index);
        rec.upload(&self.frame, bytemuck::bytes_of(&data));
    }

    /// The constants last written, as the host computed them.
    pub fn frame_constants(&self) -> GpuFrame {
        self.frame_constants.get()
    }

    fn constants(
        &self,
        scene: &Scene,
        (width, height): (u32, u32),
        time: f32,
        frame_index: u32,
    ) -> GpuFrame {
        let aspect = width as f32 / height as f32;
        let (view, proj) = camera_matrices(&scene.camera, aspect);
        let view_proj = proj * view;
        let data = GpuFrame {
            view: GpuFrame::mat(view),
            proj: GpuFrame::mat(proj),
            view_proj: GpuFrame::mat(view_proj),
            inv_view_proj: GpuFrame::mat(view_proj.inverse()),
            eye: scene
                .camera
                .eye
                .extend((scene.camera.fov_y_deg.to_radians() * 0.5).tan())
                .to_array(),
            viewport: [width as f32, height as f32, aspect, time],
            scene_sphere: self.sphere.0.extend(self.sphere.1).to_array(),
            counts: [
                scene.lights.len() as u32,
                self.triangle_count,
                scene.materials.len() as u32,
                frame_index,
            ],
            components: [self.components, self.emitter_count, self.still_frames, 0],
        };
        self.frame_constants.set(data);
        data
    }
}
