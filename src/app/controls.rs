//! What keys and the mouse do to the open window's state: fly and orbit,
//! move the light, turn the environment, screenshots, reload, technique and
//! component switches.

use super::camera::OrbitCamera;
use crate::output;
use crate::params::Params;
use crate::radiometry::Component;
use crate::scene::Scene;
use crate::techniques;
use std::path::PathBuf;
use winit::keyboard::KeyCode;

use super::state::State;

impl State {
    pub(super) fn apply_fly(&mut self, dt: f32) {
        let k = &self.input.keys;
        let axis =
            |pos: KeyCode, neg: KeyCode| (k.contains(&pos) as i32 - k.contains(&neg) as i32) as f32;
        let forward = axis(KeyCode::KeyW, KeyCode::KeyS);
        let strafe = axis(KeyCode::KeyD, KeyCode::KeyA);
        if forward != 0.0 || strafe != 0.0 {
            self.camera.fly(forward, strafe, dt);
        }
    }

    pub(super) fn mouse_moved(&mut self, x: f64, y: f64) {
        let Some((px, py)) = self.input.cursor.replace((x, y)) else {
            return;
        };
        let (dx, dy) = ((x - px) as f32, (y - py) as f32);
        if self.input.left && self.input.keys.contains(&KeyCode::KeyL) {
            self.move_light(dx, dy);
        } else if self.input.left {
            self.camera.orbit(dx, dy);
        } else if self.input.right {
            self.camera.pan(dx, dy);
        }
    }

    /// L + left drag: moves the first light across the ground plane, along
    /// the camera's right and (flattened) forward directions.
    pub(super) fn move_light(&mut self, dx: f32, dy: f32) {
        let right = self.camera.right();
        let mut ahead = self.camera.forward();
        ahead.y = 0.0;
        let ahead = ahead.normalize_or(glam::Vec3::NEG_Z);
        let step = self.camera.distance * 0.003;
        if let Some(light) = self.renderer.scene.lights.first_mut() {
            light.position += (right * dx - ahead * dy) * step;
            self.lights_changed = true;
        }
    }

    /// `[` / `]`: turns the environment by `delta_deg` about +y.
    pub(super) fn rotate_environment(&mut self, delta_deg: f32) {
        let Some(env) = self.renderer.scene.environment.as_ref() else {
            println!("environment rotation: the scene has no environment");
            return;
        };
        let turned = (env.rotate_deg + delta_deg + 180.0).rem_euclid(360.0) - 180.0;
        self.set_environment_rotation(turned);
    }

    /// The environment's `rotate` (degrees about +y), live
    /// (`Renderer::set_environment_rotation`); the overlay's slider and the
    /// bracket keys call it. On an error the old rotation is kept.
    pub(super) fn set_environment_rotation(&mut self, rotate_deg: f32) {
        let start = std::time::Instant::now();
        match self.renderer.set_environment_rotation(rotate_deg) {
            Ok(()) => {
                self.scene_edits += 1;
                println!(
                    "environment rotate = {rotate_deg:.1} degrees ({:.1} ms)",
                    start.elapsed().as_secs_f64() * 1e3
                )
            }
            Err(e) => eprintln!("environment rotation: {e:#}"),
        }
    }

    pub(super) fn screenshot(&mut self) -> anyhow::Result<()> {
        self.ctx().wait_idle();
        let (w, h) = (self.renderer.targets.width, self.renderer.targets.height);
        let radiance = self.renderer.radiance()?;
        let display = self.renderer.display()?;
        self.screenshots += 1;
        let stamp = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs())
            .unwrap_or(0);
        let base = PathBuf::from(format!("out/demo-{stamp}-{}", self.screenshots));
        let (exr, png) = output::prepare(&base.with_extension("png"))?;
        output::write_files(vec![
            output::exr_file(&exr, w, h, &radiance),
            output::png_file(&png, w, h, &display),
        ])?;
        println!("wrote {} and {}", png.display(), exr.display());
        Ok(())
    }

    pub(super) fn reload(&mut self) {
        let path = self.renderer.scene.source.clone();
        match Scene::load_allowing(&path, &self.allowed) {
            Err(e) => eprintln!("reload: {e} (keeping the old scene)"),
            Ok(scene) => {
                let camera = OrbitCamera::from_camera(&scene.camera);
                match self.renderer.set_scene(scene, self.time) {
                    Ok(()) => {
                        self.camera = camera;
                        self.scene_edits += 1;
                        println!("reloaded {}", path.display());
                    }
                    Err(e) => eprintln!("reload: {e:#} (keeping the old scene)"),
                }
            }
        }
    }

    pub(super) fn switch_technique(&mut self, n: usize) -> anyhow::Result<()> {
        let Some(info) = techniques::TECHNIQUES.get(n - 1) else {
            println!(
                "key {n}: no technique {n} (there are {}); ignored",
                techniques::TECHNIQUES.len()
            );
            return Ok(());
        };
        self.switch_technique_named(info.name)
    }

    pub(super) fn switch_technique_named(&mut self, name: &str) -> anyhow::Result<()> {
        let info = techniques::find(name)?;
        if info.name == self.renderer.technique_name() {
            return Ok(());
        }
        let params = Params::resolve(info.name, info.params(), &[])?;
        self.renderer.set_technique(info.name, &params)?;
        self.renderer.scene_gpu.components = Component::All.mask();
        println!("technique: {}", info.name);
        Ok(())
    }

    /// C: all components, then each one the technique renders alone, then
    /// all again.
    pub(super) fn cycle_components(&mut self) {
        let all = Component::All.mask();
        let own = self.renderer.technique_info().components;
        let current = self.renderer.scene_gpu.components;
        let position = own.iter().position(|c| c.mask() == current);
        let next = match position {
            None if current == all => own.first(),
            Some(i) => own.get(i + 1),
            None => None,
        };
        self.renderer.scene_gpu.components = next.map_or(all, |c| c.mask());
        println!("components: {}", next.map_or("all", |c| c.name()));
    }
}
