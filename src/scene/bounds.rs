//! Derived quantities checked before rendering (issue 18; docs/SCENES.md,
//! "Bounds"): a scene whose every field is within its bounds can still be
//! placed out of reach by its transforms at the requested time (a glTF
//! node's matrix, an OBJ's raw coordinates, an orbit), or carry lights from
//! a glTF file beyond the radiometric bound. [`Scene::check_at`] names the
//! object or light at fault.

use super::node::MAX_RADIOMETRIC;
use super::Scene;

/// The farthest a world-space vertex may lie from the origin, in metres:
/// ten times the largest coordinate a scene file may hold, leaving room
/// for a translation plus an orbit plus a bob.
pub const MAX_WORLD_EXTENT: f32 = 1e7;

/// Most point, spot and directional lights a scene may hold (the renderer's
/// light buffers and shadow maps are sized for them: `frame/stand_ins.rs`
/// checks that its GPU constant agrees).
pub const MAX_LIGHTS: usize = 8;

/// Most emissive triangles (glTF `emissiveFactor`) one object may hold: each
/// is an area light of its own, which `direct` gives a shadow ray per pixel
/// and the reference's light selection scans.
pub const MAX_EMISSIVE_TRIANGLES: usize = 1024;

impl Scene {
    /// Checks the scene at `time` (seconds): every object's transform
    /// finite and its vertices within [`MAX_WORLD_EXTENT`] of the origin,
    /// so too the camera's eye and target and every point and spot light,
    /// every light's intensity within 0 and the radiometric bound and its
    /// power finite. The error is one line naming the scene file and the field.
    pub fn check_at(&self, time: f32) -> Result<(), String> {
        let at = |field: String, why: String| {
            format!(
                "{}: {field}: {why} (docs/SCENES.md, Bounds)",
                self.source.display()
            )
        };
        if !time.is_finite() {
            return Err(at("--time".into(), format!("must be finite, got {time}")));
        }
        for (i, o) in self.objects.iter().enumerate() {
            let field = if o.animation.is_some() {
                format!("object[{i}].animate")
            } else {
                format!("object[{i}]")
            };
            let m = self.object_transform(i, time);
            if !m.is_finite() {
                return Err(at(
                    field,
                    format!("`{}`: its transform at time {time} s is not finite", o.name),
                ));
            }
            let mesh = o.mesh_at(time);
            let far = mesh
                .positions
                .iter()
                .map(|&p| m.transform_point3(p).abs().max_element())
                .fold(
                    0.0f32,
                    |a, b| if b.is_nan() { f32::INFINITY } else { a.max(b) },
                );
            if far > MAX_WORLD_EXTENT {
                return Err(at(
                    field,
                    format!(
                        "`{}` reaches {far:e} m from the origin at time {time} s, beyond {MAX_WORLD_EXTENT:e} m",
                        o.name
                    ),
                ));
            }
            let emissive = mesh
                .materials
                .iter()
                .filter(|&&m| self.materials[m as usize].emission.max_element() > 0.0)
                .count();
            let area_light = self.emitters.iter().any(|e| e.object as usize == i);
            if !area_light && emissive > MAX_EMISSIVE_TRIANGLES {
                return Err(at(
                    format!("object[{i}]"),
                    format!(
                        "`{}` has {emissive} emissive triangles, at most {MAX_EMISSIVE_TRIANGLES} (each is an area light)",
                        o.name
                    ),
                ));
            }
        }
        let camera_far = self
            .camera
            .eye
            .abs()
            .max(self.camera.target.abs())
            .max_element();
        if camera_far.is_nan() || camera_far > MAX_WORLD_EXTENT {
            return Err(at(
                "camera".into(),
                format!("the eye or the target lies {camera_far:e} m from the origin, beyond {MAX_WORLD_EXTENT:e} m"),
            ));
        }
        let (_, radius) = self.bounding_sphere(time);
        for (i, l) in self.lights.iter().enumerate() {
            let largest = l.intensity.max_element();
            if largest.is_nan() || largest as f64 > MAX_RADIOMETRIC {
                return Err(at(
                    format!("light[{i}]"),
                    format!("intensity {largest:e} is beyond {MAX_RADIOMETRIC:e}"),
                ));
            }
            if l.intensity.min_element() < 0.0 {
                return Err(at(
                    format!("light[{i}]"),
                    format!("intensity {} is negative", l.intensity),
                ));
            }
            let far = l.position.abs().max_element();
            if l.kind != super::LightKind::Directional && (far.is_nan() || far > MAX_WORLD_EXTENT) {
                return Err(at(
                    format!("light[{i}]"),
                    format!("its position lies {far:e} m from the origin, beyond {MAX_WORLD_EXTENT:e} m"),
                ));
            }
            // Above every kind's power (radiometry::light_power: 4π I at
            // most for point and spot lights, E π R² for a directional one).
            let power =
                largest * (4.0 * std::f32::consts::PI).max(std::f32::consts::PI * radius * radius);
            if !power.is_finite() {
                return Err(at(
                    format!("light[{i}]"),
                    format!("its power (up to {power} W) is not finite"),
                ));
            }
        }
        Ok(())
    }
}
