//! glTF materials mapped to the project's radiometry (docs/SCENES.md).

use super::*;

/// What `alphaMode` leaves of a material's surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Coverage {
    Opaque,
    /// Every triangle cut out (a constant alpha below the cutoff).
    CutOut,
    /// Cut out where the base colour texture's alpha is below this.
    Mask(f32),
}

/// glTF material -> project material (docs/SCENES.md, "glTF materials"):
/// the material, what `alphaMode = MASK` leaves of it, and the ways it
/// differs from the file (one warning line per material).
pub(super) fn convert_material(
    name: String,
    m: &::gltf::Material,
) -> (Material, Coverage, Vec<String>) {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, alpha] = pbr.base_color_factor();
    let base = Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE);
    let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
    let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
    let mut notes = Vec::new();
    let mut coverage = Coverage::Opaque;
    match m.alpha_mode() {
        ::gltf::material::AlphaMode::Opaque => {}
        ::gltf::material::AlphaMode::Mask => {
            // The spec compares alpha = factor × texture alpha with the
            // cutoff: kept where factor · t >= cutoff, i.e. t >= cutoff /
            // factor. A texture alpha is at most 1, so a threshold above 1
            // cuts every triangle (as does a constant alpha below the
            // cutoff without a texture).
            let cutoff = m.alpha_cutoff().unwrap_or(0.5).max(0.0);
            let threshold = if alpha > 0.0 {
                cutoff / alpha
            } else {
                f32::INFINITY
            };
            coverage = if threshold > 1.0 {
                notes.push(format!(
                    "alphaMode MASK with alpha {alpha} below alphaCutoff {cutoff}: its triangles are cut out"
                ));
                Coverage::CutOut
            } else if threshold > 0.0 && pbr.base_color_texture().is_some() {
                Coverage::Mask(threshold)
            } else {
                Coverage::Opaque
            };
        }
        ::gltf::material::AlphaMode::Blend => {
            notes.push("alphaMode BLEND is not supported: rendered opaque".to_owned())
        }
    }
    // Emission: emissiveFactor × emissiveStrength is a luminance in cd/m²
    // (KHR_materials_emissive_strength); the lights' luminous efficacy
    // turns it into radiance, W m^-2 sr^-1 = (cd/m²) / LUMENS_PER_WATT.
    let mut emission = Vec3::from(m.emissive_factor()).max(Vec3::ZERO)
        * m.emissive_strength().unwrap_or(1.0).max(0.0)
        / LUMENS_PER_WATT;
    if emission.max_element() > 0.0 && m.emissive_texture().is_some() {
        notes.push("emissiveTexture is not applied: the factor emits uniformly".to_owned());
    }
    let mut out = Material {
        texture: None,
        emission: Vec3::ZERO,
        specular: Vec3::ZERO,
        scattering: None,
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
        let ior = m.ior().unwrap_or(1.5);
        out.ior = if ior >= 1.0 {
            ior
        } else {
            notes.push(format!("ior {ior} below 1 rendered as 1.5"));
            1.5
        };
        match m.volume().filter(|v| v.thickness_factor() > 0.0) {
            Some(v) => {
                // KHR_materials_volume: transmittance over attenuationDistance
                // d is attenuationColor c, so Beer-Lambert σa = -ln(c)/d
                // (an infinite distance, the default, absorbs nothing).
                let d = v.attenuation_distance();
                if d.is_finite() && d > 0.0 {
                    let c = Vec3::from(v.attenuation_color()).clamp(Vec3::splat(1e-6), Vec3::ONE);
                    out.absorption = Vec3::new(-c.x.ln(), -c.y.ln(), -c.z.ln()) / d;
                }
            }
            // Thin-walled (the glTF default without a volume): a sheet with
            // Fresnel at both faces and no net deflection.
            None => out.kind = MaterialKind::ThinDielectric,
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
    if emission.max_element() > 0.0 && out.kind != MaterialKind::Diffuse {
        notes.push(format!(
            "emission {emission} W m^-2 sr^-1 on a specular material is not rendered (only diffuse surfaces emit)"
        ));
        emission = Vec3::ZERO;
    }
    out.emission = emission;
    if matches!(coverage, Coverage::Mask(_)) && out.kind != MaterialKind::Diffuse {
        notes.push(
            "alphaMode MASK cut-outs apply to diffuse materials only: rendered opaque".to_owned(),
        );
        coverage = Coverage::Opaque;
    }
    (out, coverage, notes)
}
