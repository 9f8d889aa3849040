//! The environment light on the GPU (set 0): its equirectangular radiance
//! table as an RGBA32F image with a bilinear sampler (BINDING_ENVIRONMENT),
//! and its constants followed by the luminance sampling tables
//! (BINDING_ENVIRONMENT_DATA; `emitters::sampling_tables`). A scene
//! without an environment binds a 2x1 black table and `params.x` = 0.
//! Both are written at `SceneGpu::new` (a blocking upload before any frame
//! reads them); the constants again when the environment's `rotate`
//! changes (`EnvironmentGpu::update`, the demo's live rotation).

use crate::emitters;
use crate::gpu::GpuEnvironment;
use crate::radiometry::LUMINANCE;
use crate::scene::{Environment, EnvironmentKind};
use crate::vk::{Buffer, BufferUsage, Context, Image, ImageDesc, Sampler, VkResult};
use ash::vk;
use std::f32::consts::PI;
use std::sync::Arc;

pub struct EnvironmentGpu {
    pub image: Image,
    pub sampler: Sampler,
    /// `GpuEnvironment` then the sampling tables (f32).
    pub data: Buffer,
    pub constants: GpuEnvironment,
}

impl EnvironmentGpu {
    /// `scene_radius`: the bounding sphere's radius R; the environment's
    /// photons leave a disc of that radius, so its power is π R² ∫ L dω.
    pub fn new(ctx: &Arc<Context>, env: Option<&Environment>, scene_radius: f32) -> VkResult<Self> {
        let (w, h, texels) = env.map_or((2, 1, vec![[0.0; 3]; 2]), emitters::table);
        let (constants, bytes) = data(env, scene_radius, w, h, &texels);
        let data = Buffer::with_data::<u8>(ctx, "environment data", &bytes, BufferUsage::Storage)?;
        let rgba: Vec<f32> = texels
            .iter()
            .flat_map(|t| [t[0], t[1], t[2], 1.0])
            .collect();
        let image = Image::sampled_with_levels(
            ctx,
            "environment",
            ImageDesc::new_2d(
                w,
                h,
                vk::Format::R32G32B32A32_SFLOAT,
                vk::ImageUsageFlags::SAMPLED,
            ),
            &[bytemuck::cast_slice(&rgba)],
        )?;
        Ok(Self {
            image,
            sampler: Sampler::repeat_mipmapped(ctx)?,
            data,
            constants,
        })
    }

    /// The environment's `rotate` changed (`Scene::set_environment_rotation`):
    /// rewrites the constants (the rotation, a sky's sun, an image's sun
    /// rotated into the world) with the sampling tables, which are in the
    /// image's frame and do not change. The table image stays: an image's
    /// is in its own frame, a sky's gradient depends on elevation alone.
    /// The caller has waited for every frame that read the old data.
    pub fn update(&mut self, env: Option<&Environment>, scene_radius: f32) -> VkResult<()> {
        let (w, h, texels) = env.map_or((2, 1, vec![[0.0; 3]; 2]), emitters::table);
        let (constants, bytes) = data(env, scene_radius, w, h, &texels);
        self.data.upload(&bytes)?;
        self.constants = constants;
        Ok(())
    }
}

/// The constants of `env` and the data buffer's bytes (the constants, then
/// the sampling tables of its `w` x `h` table `texels`).
fn data(
    env: Option<&Environment>,
    scene_radius: f32,
    w: u32,
    h: u32,
    texels: &[[f32; 3]],
) -> (GpuEnvironment, Vec<u8>) {
    let (cdf, integral) = emitters::sampling_tables(w, h, texels);
    let disc = PI * scene_radius * scene_radius;
    let mut constants = GpuEnvironment {
        params: [0.0, 0.0, 1.0, 0.0],
        sun: [0.0, 1.0, 0.0, 2.0],
        sun_radiance: [0.0; 4],
        table: [w as f32, h as f32, 0.0, 0.0],
        image_sun_peak: [0.0, 1.0, 0.0, 2.0],
        image_sun_direction: [0.0, 1.0, 0.0, f32::MAX],
        image_sun_irradiance: [0.0; 4],
    };
    if let Some(env) = env {
        let (s, c) = env.rotate_deg.to_radians().sin_cos();
        constants.params = [1.0, 0.0, c, s];
        constants.table[2] = integral * disc;
        if let EnvironmentKind::Image(_) = &env.kind {
            if let Some(sun) = emitters::extract_sun(w, h, texels) {
                let rot = emitters::rotation(env);
                let (p, d) = (rot * sun.peak, rot * sun.direction);
                constants.image_sun_peak = [p.x, p.y, p.z, sun.cos_search];
                constants.image_sun_direction = [d.x, d.y, d.z, sun.threshold];
                constants.image_sun_irradiance = sun.irradiance.extend(0.0).to_array();
            }
        }
        if let EnvironmentKind::Sky(sky) = &env.kind {
            let l = sky.sun_radiance * env.scale;
            let d = sky.sun_direction;
            constants.sun = [d.x, d.y, d.z, sky.sun_radius_deg.to_radians().cos()];
            let power = l.dot(LUMINANCE) * emitters::sun_solid_angle(sky) * disc;
            constants.sun_radiance = [l.x, l.y, l.z, power];
        }
    }
    let mut bytes = bytemuck::bytes_of(&constants).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(&cdf));
    (constants, bytes)
}
