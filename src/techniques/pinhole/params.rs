//! `pinhole`'s parameters and the push constants its passes share.

use super::bindings as b;
use crate::passes::direct_light::DirectParams;
use bytemuck::{Pod, Zeroable};
use std::mem::size_of;

crate::declare_params! {
    /// `pinhole`'s parameters: `DirectLight`'s, then the sample points',
    /// the light cube maps' and the receivers'.
    pub struct PinholeParams {
        @group direct: DirectParams;
        samples: u32 [60, 10000] = 1000, rebuild,
            "N, reflector sample points (pinhole cameras) per frame (Sect. 3.2; the paper uses 60-10,000)";
        strategy: u32 [0, 3] = 3, live,
            "sampling strategy of Sect. 3.2: 0 random, 1 grid stratification, 2 quantized-grid stratification, 3 neighbourhood-based removal (the paper's choice)";
        oversample: u32 [2, 32] = 8, rebuild,
            "dense random candidates per sample point, from which the strategies select and the normal gradient is fitted (Sect. 3.3)";
        clusters: u32 [1, 16] = 8, rebuild,
            "K, clusters of sample points, each with its own light cube maps centred on it (Sect. 5, for lights near the reflector); 1: the paper's single map";
        cube_size: u32 [16, 512] = 128, rebuild,
            "texels per side of each light cube-map face";
        light_radius: f32 [0.001, 10.0] = 0.05, live,
            "r in metres of the sphere a point or spot light is drawn as in the cube maps, radiance I / (pi r^2)";
        sun_radius: f32 [0.01, 20.0] = 0.5, live,
            "angular radius in degrees of the disc a directional light is drawn as, radiance E / (pi sin^2)";
        epsilon: f32 [0.0, 16.0] = 1.0, live,
            "the paper's constant added to the squared distance, in units of a sample region's diameter squared (4 A / (pi N))";
        filter: bool [0, 1] = 1, live,
            "1: anisotropic filtering of each cube-map lookup over the footprint from the normal gradient (Sect. 3.3, textureGrad); 0: point lookups";
        visibility: bool [0, 1] = 1, live,
            "1: a shadow ray from the receiver to each contributing sample point (beyond the paper); 0: none, as in the paper";
        light_visibility: bool [0, 1] = 1, live,
            "1: one shadow ray per sample point and light gates that light's map (beyond the paper); 0: every light reaches every sample point";
        dielectrics: bool [0, 1] = 1, live,
            "1: dielectric surfaces are reflectors too, with the Fresnel reflectance of their outer side (Sect. 5); 0: mirrors only";
        search_steps: u32 [4, 256] = 32, live,
            "linear steps of the camera refraction's image-space search (what the camera sees in mirrors and glass)";
    }
}

/// The push constants of every pinhole pass but the mips (`Push` in
/// glsl/pinhole/common.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct PinholePush {
    pub target: u32,
    pub strategy: u32,
    pub candidates: u32,
    pub clusters: u32,
    pub slots: u32,
    pub cube_size: u32,
    pub flags: u32,
    pub hash_size: u32,
    pub light_radius: f32,
    pub sun_cos: f32,
    pub epsilon: f32,
    pub medium_steps: u32,
    /// select.comp: the first candidate of this dispatch.
    pub first_candidate: u32,
    pub pad: [u32; 3],
}
const _: () = assert!(size_of::<PinholePush>() == 64);

impl PinholeParams {
    /// The live part of the push constants.
    pub fn apply_live(&self, push: &mut PinholePush) {
        push.strategy = self.strategy;
        push.light_radius = self.light_radius;
        push.sun_cos = self.sun_radius.to_radians().cos();
        push.epsilon = self.epsilon;
        push.flags = (if self.filter {
            b::PINHOLE_FLAG_FILTER
        } else {
            0
        }) | (if self.visibility {
            b::PINHOLE_FLAG_VISIBILITY
        } else {
            0
        }) | (if self.light_visibility {
            b::PINHOLE_FLAG_LIGHT_VISIBILITY
        } else {
            0
        }) | (if self.dielectrics {
            b::PINHOLE_FLAG_DIELECTRICS
        } else {
            0
        });
    }
}
