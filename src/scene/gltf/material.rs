//! glTF materials mapped to the project's radiometry (docs/SCENES.md).

use super::*;

/// glTF material -> project material (docs/SCENES.md, "glTF materials"):
/// the material, whether `alphaMode = MASK` cuts it out entirely, and the
/// ways it differs from the file (one warning line per material).
pub(super) fn convert_material(
    name: String,
    m: &::gltf::Material,
) -> (Material, bool, Vec<String>) {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, alpha] = pbr.base_color_factor();
    let base = Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE);
    let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
    let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
    let mut notes = Vec::new();
    let mut cut_out = false;
    match m.alpha_mode() {
        ::gltf::material::AlphaMode::Opaque => {}
        ::gltf::material::AlphaMode::Mask => {
            let cutoff = m.alpha_cutoff().unwrap_or(0.5);
            if pbr.base_color_texture().is_some() {
                notes.push("alphaMode MASK with a baseColorTexture: the cut-out is not applied (rendered opaque)".to_owned());
            } else if alpha < cutoff {
                // Without a texture alpha is one constant: the whole surface
                // is either kept or cut out.
                cut_out = true;
                notes.push(format!(
                    "alphaMode MASK with alpha {alpha} below alphaCutoff {cutoff}: its triangles are cut out"
                ));
            }
        }
        ::gltf::material::AlphaMode::Blend => {
            notes.push("alphaMode BLEND is not supported: rendered opaque".to_owned())
        }
    }
    let emission = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
    if emission.max_element() > 0.0 {
        notes.push(format!(
            "emissive {emission} is not rendered (no area emitters yet)"
        ));
    }
    let mut out = Material {
        texture: None,
        emission: Vec3::ZERO,
        name,
        kind: MaterialKind::Diffuse,
        color: base,
        ior: 1.0,
        absorption: Vec3::ZERO,
    };
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    if transmission > 0.0 {
        out.kind = MaterialKind::Dielectric;
        out.color = Vec3::ONE;
        if transmission < 1.0 {
            notes.push(format!(
                "transmission {transmission} rendered as 1 (a clear dielectric)"
            ));
        }
        if roughness > SMOOTH_ROUGHNESS {
            notes.push(format!(
                "rough transmission (roughness {roughness}) rendered smooth"
            ));
        }
        if base != Vec3::ONE {
            notes.push(format!(
                "the base colour {base} tinting the transmission is not applied"
            ));
        }
        match m.volume().filter(|v| v.thickness_factor() > 0.0) {
            Some(v) => {
                let ior = m.ior().unwrap_or(1.5);
                out.ior = if ior >= 1.0 {
                    ior
                } else {
                    notes.push(format!("ior {ior} below 1 rendered as 1.5"));
                    1.5
                };
                // KHR_materials_volume: transmittance over attenuationDistance
                // d is attenuationColor c, so Beer-Lambert σa = -ln(c)/d
                // (an infinite distance, the default, absorbs nothing).
                let d = v.attenuation_distance();
                if d.is_finite() && d > 0.0 {
                    let c = Vec3::from(v.attenuation_color()).clamp(Vec3::splat(1e-6), Vec3::ONE);
                    out.absorption = Vec3::new(-c.x.ln(), -c.y.ln(), -c.z.ln()) / d;
                }
            }
            None => {
                // Thin-walled (the glTF default without a volume): a sheet
                // with Fresnel at both faces and no net deflection. The
                // nearest supported material keeps its geometry optics: a
                // dielectric of ior 1 lets light through undeflected (it
                // drops the sheet's ~8% Fresnel reflection).
                out.ior = 1.0;
                notes.push("thin-walled transmission (no KHR_materials_volume) rendered as a dielectric of ior 1: undeflected, without the sheet's Fresnel reflection".to_owned());
            }
        }
    } else if metallic >= 0.5 {
        if metallic < 1.0 {
            notes.push(format!("metallic {metallic} rendered as a metal"));
        }
        if roughness <= ROUGH_METAL_LIMIT {
            out.kind = MaterialKind::Mirror;
            if roughness > SMOOTH_ROUGHNESS {
                notes.push(format!(
                    "rough metal (roughness {roughness}) rendered as a smooth mirror"
                ));
            }
        } else {
            notes.push(format!(
                "rough metal (roughness {roughness}) rendered diffuse with albedo = base colour"
            ));
        }
    } else if metallic > 0.0 {
        notes.push(format!(
            "metallic {metallic} rendered as a non-metal (diffuse)"
        ));
    }
    (out, cut_out, notes)
}
