//! The point lights that stand for the environment's sun and the rect
//! lights in the real-time techniques, which trace caustics from point,
//! spot and directional lights, and the check that refuses a scene whose
//! area lights they cannot represent. The radiometry they derive from is
//! `emitters.rs`; the GPU light buffer (`SceneGpu`) and the light views
//! hold [`caustic_lights`].

use crate::emitters::sun_irradiance;
use crate::scene::{EmitterShape, Light, LightKind, Scene};
use crate::shader_bindings::MAX_LIGHTS;
use glam::Vec3;

// The scene format's limit is what the GPU's light buffers hold.
const _: () = assert!(crate::scene::MAX_LIGHTS == MAX_LIGHTS as usize);

/// `cone_falloff_deg` of a spot light that stands for a rect light: the
/// cosine (Lambertian) profile I(θ) = I₀ max(cos θ, 0) over the hemisphere
/// (`radiometry::spot_falloff`, glsl/common/lights.glsl). Never parsed from
/// a file (a negative falloff is refused there).
pub const LAMBERTIAN_FALLOFF: f32 = -1.0;

/// Largest rect light a point stand-in may replace: its half-diagonal over
/// the distance from its centre to the nearest other surface. The point's
/// irradiance differs from the rect's by O((s/d)²): under 1% here.
pub const STAND_IN_MAX_SIZE_RATIO: f32 = 0.1;

/// The punctual lights that stand for the environment's sun and the rect
/// lights, for the techniques that trace caustics from point, spot and
/// directional lights (`image_space`, `volume_lines`): the sun as a
/// directional light of its irradiance, a rect as a spot at its centre
/// (2e-3 of its coordinates' magnitude in front) along its normal with the cosine profile, I₀ =
/// L A (power π L A). Sphere lights have none (see [`check_stand_ins`]).
pub fn stand_in_lights(scene: &Scene) -> Vec<Light> {
    let sun = scene.environment.as_ref().and_then(sun_irradiance);
    let sun = sun.map(|(direction, irradiance)| Light {
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction,
        intensity: irradiance,
        cone_angle_deg: 0.0,
        cone_falloff_deg: 0.0,
    });
    let rects = scene.emitters.iter().filter_map(|e| match e.shape {
        EmitterShape::Rect {
            center,
            normal,
            size,
            ..
        } => Some(Light {
            kind: LightKind::Spot,
            // In front of its own (black) geometry by more than the
            // shaders' ray offsets (1e-4 of the coordinates' magnitude per
            // surface crossed), else rays to the light would meet it.
            position: center + normal * (2e-3 * center.abs().max_element().max(1.0)),
            direction: normal,
            intensity: e.radiance * size[0] * size[1],
            cone_angle_deg: 90.0,
            cone_falloff_deg: LAMBERTIAN_FALLOFF,
        }),
        EmitterShape::Sphere { .. } => None,
    });
    sun.into_iter().chain(rects).collect()
}

/// The scene's lights followed by [`stand_in_lights`], at most `MAX_LIGHTS`:
/// the GPU light buffer (`SceneGpu::lights`) and the light views of the
/// caustic techniques. Without an environment or area lights, `scene.lights`.
pub fn caustic_lights(scene: &Scene) -> Vec<Light> {
    let mut lights = scene.lights.clone();
    lights.extend(stand_in_lights(scene));
    lights.truncate(MAX_LIGHTS as usize);
    lights
}

/// Refuses, for `technique`, a scene whose area lights its point-light
/// stand-ins cannot represent: a sphere light (a point at its centre lies
/// inside its own geometry), a rect larger than
/// [`STAND_IN_MAX_SIZE_RATIO`] of its distance to the nearest other
/// surface not entirely behind it, or more lights than `MAX_LIGHTS` with
/// the stand-ins.
pub fn check_stand_ins(scene: &Scene, technique: &str) -> Result<(), String> {
    let triangles = scene.triangles(0.0);
    for (i, e) in scene.emitters.iter().enumerate() {
        match e.shape {
            EmitterShape::Sphere { .. } => {
                return Err(format!(
                    "{technique} does not support sphere lights (area light {i}); use `direct` or `reference`"
                ))
            }
            EmitterShape::Rect {
                center,
                normal,
                size,
                ..
            } => {
                let half = 0.5 * (size[0] * size[0] + size[1] * size[1]).sqrt();
                // Surfaces entirely behind the rect receive none of its light.
                let nearest = triangles
                    .iter()
                    .filter(|t| t.object != e.object)
                    .filter(|t| t.positions.iter().any(|&p| (p - center).dot(normal) > 0.0))
                    .map(|t| point_triangle_distance(center, t.positions))
                    .fold(f32::INFINITY, f32::min);
                if half > STAND_IN_MAX_SIZE_RATIO * nearest {
                    return Err(format!(
                        "{technique} treats rect lights as points: area light {i} (half-diagonal {half} m) must be at most {STAND_IN_MAX_SIZE_RATIO} of its distance to the nearest surface ({nearest} m)"
                    ));
                }
            }
        }
    }
    let count = scene.lights.len() + stand_in_lights(scene).len();
    if count > MAX_LIGHTS as usize {
        return Err(format!(
            "{technique}: {count} lights with the environment's sun and the rect lights, at most {MAX_LIGHTS}"
        ));
    }
    Ok(())
}

/// Distance from `p` to the triangle `t` (closest point by regions).
fn point_triangle_distance(p: Vec3, t: [Vec3; 3]) -> f32 {
    let [a, b, c] = t;
    let n = (b - a).cross(c - a);
    let inside = |u: Vec3, v: Vec3| (v - u).cross(p - u).dot(n) >= 0.0;
    if n.length_squared() > 0.0 && inside(a, b) && inside(b, c) && inside(c, a) {
        return (p - a).dot(n).abs() / n.length();
    }
    let seg = |u: Vec3, v: Vec3| {
        let d = v - u;
        let s = ((p - u).dot(d) / d.length_squared().max(1e-30)).clamp(0.0, 1.0);
        (p - (u + d * s)).length()
    };
    seg(a, b).min(seg(b, c)).min(seg(c, a))
}
