//! `water_photons`' parameters and the uniform block its passes share.

use super::bindings;
use super::denoise::DenoiseParams;
use crate::passes::direct_light::DirectParams;
use crate::vk::Buffer;
use bytemuck::{Pod, Zeroable};
use std::mem::size_of;

crate::declare_params! {
    /// `water_photons`' parameters: `DirectLight`'s, the denoiser's, then the
    /// cascades', photons' and splats'.
    pub struct WaterPhotonsParams {
        @group direct: DirectParams;
        @group denoise: DenoiseParams;
        cascades: u32 [1, bindings::WP_MAX_CASCADES] = 2, rebuild,
            "N, the number of cascaded caustic maps (Eqs. 4-5)";
        cascade_scale: f32 [1.25, 8.0] = 2.0, rebuild,
            "s, each cascade covers s times the extent of the previous one (Eq. 2)";
        ccm_size: u32 [16, 2048] = 512, rebuild,
            "ccm_0, texels per side of every cascade (Eq. 3 picks 256-2048 from range / precision)";
        ccm_precision: f32 [0.0, 1000.0] = 0.0, rebuild,
            "p of Eq. 3 in metres per texel: ccm_0 is then the smallest of 256, 512, 1024, 2048 covering the range; 0: ccm_size decides";
        light_range: f32 [0.0, 100000.0] = 0.0, rebuild,
            "width (= height) r of the innermost cascade in metres; 0: the outermost cascade just covers the water";
        photon_capacity: u32 [0, 33554432] = 0, rebuild,
            "photon buffer size; 0: twice the threads of Eq. 5 (a reflected and a refracted photon each, never overflows)";
        splat_mode: u32 [0, 2] = 0, rebuild,
            "0: the photon differential's footprint (exact flux density); 1: Eqs. 16-19's quad sized by σ; 2: fixed splats (Eqs. 16-19 with σ = s^c, no differentials)";
        intensity_mode: u32 [0, 1] = 0, rebuild,
            "0: physical (exact Fresnel, photon flux = E x texel area, absorption); 1: the paper's Eqs. 12-15 (attenuation, stylised Fresnel)";
        quad_size: f32 [0.25, 16.0] = 1.0, rebuild,
            "q_0 of Eq. 16 in texel pitches (splat modes 1, 2); 1 makes the box splats tile a flat surface";
        fresnel_frac: f32 [0.0, 1.0] = 0.02, rebuild,
            "F_frac of Eq. 14 (intensity_mode 1)";
        fresnel_exp: f32 [0.1, 16.0] = 5.0, rebuild,
            "F_exp of Eq. 14 (intensity_mode 1)";
        attenuation_gamma: f32 [0.01, 0.99] = 0.95, rebuild,
            "γ of Eq. 13, the focus bias (intensity_mode 1)";
        attenuation_t_max: f32 [0.01, 100000.0] = 20.0, rebuild,
            "t_max of Eq. 13 in metres (intensity_mode 1)";
        depth_bias: f32 [0.0, 0.1] = 0.01, rebuild,
            "splats move toward the camera by this fraction of their distance before the depth test (along the view ray: the image does not move); 0.001 lets ocean_large's far seabed reject its own splats";
        shafts: u32 [0, 1] = 1, live,
            "1: the light a medium in the water scatters, as shafts seen from under the surface (shafts.rs); 0: off";
        shaft_stride: u32 [1, 16] = 1, live,
            "k: one shaft tube for each k x k block of caustic-map texels, k times as wide, with k^2 times the flux (the shafts' cost goes as 1/k; over a faceted surface k > 1 draws lines where the bend changes within a block)";
        search_steps: u32 [4, 256] = 32, live,
            "linear steps of the camera refraction's image-space search (image_space)";
    }
}

/// The uniform block `WpParams` of glsl/water_photons/common.glsl (std140).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuWpParams {
    pub light_view: [[f32; 4]; 4],
    pub light_dir: [f32; 4],
    pub irradiance: [f32; 4],
    pub range: [f32; 4],
    pub size: [u32; 4],
    pub modes: [u32; 4],
    pub cascade: [f32; 4],
    pub paper: [f32; 4],
    pub water: [u32; 4],
    /// x: the shafts' block stride k (`shaft_stride`); y: 1 while the eye
    /// is under the water (`Water::is_below_surface`, each frame); z, w: unused.
    pub shafts: [u32; 4],
}
const _: () = assert!(size_of::<GpuWpParams>() == 208);

/// The uniform buffer holding `GpuWpParams`, shared by the passes.
pub struct WpParamsBuffer(pub Buffer);
