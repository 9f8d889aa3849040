//! The scene's albedo textures on the GPU: one RGBA16F 2D array image with
//! a full mip chain, a layer per `Scene::textures` entry (material records
//! hold the layer, `GpuMaterial::texture`), and its trilinear repeat-wrap
//! sampler, bound in set 0 at BINDING_ALBEDO_TEXTURES.
//!
//! Why one array: lavapipe 22.3 has no descriptor indexing, so shaders
//! cannot pick among separately bound textures by a material's index. Every
//! layer has one size (`texture::layer_size`: the largest texture's side
//! rounded up to a power of two, at most `texture::MAX_LAYER_SIZE`), so
//! smaller or non-square files are resampled to it. RGBA16F: filterable
//! everywhere, and its 11-bit mantissa is finer than an 8-bit sRGB step.
//! A scene without textures gets one 1x1 white layer, so the binding is
//! always valid.

use crate::scene::{texture, Texture};
use crate::vk::{Context, Image, ImageDesc, Sampler, VkResult};
use ash::vk;
use std::path::PathBuf;
use std::sync::Arc;

pub struct AlbedoTextures {
    pub image: Image,
    pub sampler: Sampler,
}

impl AlbedoTextures {
    pub fn new(ctx: &Arc<Context>, textures: &[Texture]) -> VkResult<Self> {
        let white = [Texture {
            path: PathBuf::new(),
            width: 1,
            height: 1,
            texels: vec![[1.0; 3]],
            alpha: Vec::new(),
        }];
        let textures = if textures.is_empty() {
            &white[..]
        } else {
            textures
        };
        let size = texture::layer_size(textures);
        let chains: Vec<Vec<Vec<[f32; 4]>>> = textures
            .iter()
            .map(|t| texture::mip_chain(t, size))
            .collect();
        // Level l holds every layer's texels, layer after layer.
        let levels: Vec<Vec<u8>> = (0..chains[0].len())
            .map(|l| {
                let halfs: Vec<u16> = chains
                    .iter()
                    .flat_map(|c| c[l].iter().flatten())
                    .map(|&x| half::f16::from_f32(x).to_bits())
                    .collect();
                bytemuck::cast_slice(&halfs).to_vec()
            })
            .collect();
        let level_refs: Vec<&[u8]> = levels.iter().map(Vec::as_slice).collect();
        let desc = ImageDesc {
            layers: textures.len() as u32,
            ..ImageDesc::new_2d(
                size,
                size,
                vk::Format::R16G16B16A16_SFLOAT,
                vk::ImageUsageFlags::SAMPLED,
            )
        };
        let image = Image::sampled_with_levels(ctx, "albedo textures", desc, &level_refs)?;
        Ok(Self {
            image,
            sampler: Sampler::repeat_mipmapped(ctx)?,
        })
    }
}
