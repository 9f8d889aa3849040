//! The demo's orbit camera: yaw/pitch/distance around a target, with pan and
//! WASD fly. It writes a plain `scene::Camera` each frame.

use crate::scene::Camera;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct OrbitCamera {
    pub target: Vec3,
    /// Radians about +Y; 0 looks down -Z (eye on +Z).
    pub yaw: f32,
    /// Radians above the horizontal plane through the target.
    pub pitch: f32,
    pub distance: f32,
    pub fov_y_deg: f32,
}

const PITCH_LIMIT: f32 = 1.55;

impl OrbitCamera {
    pub fn from_camera(c: &Camera) -> Self {
        let offset = c.eye - c.target;
        let distance = offset.length().max(1e-3);
        Self {
            target: c.target,
            yaw: offset.x.atan2(offset.z),
            pitch: (offset.y / distance).clamp(-1.0, 1.0).asin(),
            distance,
            fov_y_deg: c.fov_y_deg,
        }
    }

    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy)
    }

    pub fn camera(&self) -> Camera {
        Camera {
            eye: self.eye(),
            target: self.target,
            up: Vec3::Y,
            fov_y_deg: self.fov_y_deg,
        }
    }

    /// Unit vector from the eye to the target.
    pub fn forward(&self) -> Vec3 {
        (self.target - self.eye()).normalize_or(Vec3::NEG_Z)
    }

    pub fn right(&self) -> Vec3 {
        self.forward().cross(Vec3::Y).normalize_or(Vec3::X)
    }

    /// Left drag: `dx`, `dy` in pixels.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.005;
        self.pitch = (self.pitch + dy * 0.005).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Wheel: positive `steps` zoom in.
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.9f32.powf(steps)).clamp(0.05, 1e4);
    }

    /// Right drag: moves the target (and eye) in the view plane.
    pub fn pan(&mut self, dx: f32, dy: f32) {
        let right = self.right();
        let up = right.cross(self.forward());
        self.target += (-dx * right + dy * up) * self.distance * 0.0015;
    }

    /// WASD: `forward` and `strafe` in -1..1, for `dt` seconds.
    pub fn fly(&mut self, forward: f32, strafe: f32, dt: f32) {
        let speed = self.distance * 0.8 * dt;
        self.target += (self.forward() * forward + self.right() * strafe) * speed;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_a_camera() {
        let c = Camera {
            eye: Vec3::new(0.0, 5.0, 7.0),
            target: Vec3::new(0.0, 0.8, 0.0),
            up: Vec3::Y,
            fov_y_deg: 40.0,
        };
        let o = OrbitCamera::from_camera(&c);
        assert!((o.eye() - c.eye).length() < 1e-4, "{:?}", o.eye());
        let mut z = o;
        z.zoom(1.0);
        assert!(z.distance < o.distance);
    }
}
