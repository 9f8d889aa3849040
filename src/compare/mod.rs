//! `caustics compare`'s library side: every technique judged against the
//! ground truth (`driver`, shared by the CLI and the demo's compare panel)
//! by the same metrics the tests use (`metrics`), the report
//! both write (`report`, the JSON schema `bench --json` shares), the
//! contact sheet (`sheet`, labelled with a bitmap `font`) and the key of
//! the reference cache (`cache_key`).

pub mod driver;
pub mod font;
pub mod metrics;
pub mod report;
pub mod sheet;

use crate::scene::Scene;
use std::fmt::Write as _;

/// FNV-1a, 64 bits: a stable hash for cache keys (std's `DefaultHasher`
/// may change between Rust releases).
struct Fnv1a(u64);

impl Fnv1a {
    fn new() -> Self {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

impl std::fmt::Write for Fnv1a {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.bytes(s.as_bytes());
        Ok(())
    }
}

/// A stable 64-bit hash (FNV-1a) of `parts`, each length-prefixed so that
/// moving bytes between parts changes it; the tests' reference cache keys
/// its code hash with it (tests/suite/common/reference_cache.rs).
pub fn stable_hash<'a>(parts: impl IntoIterator<Item = &'a [u8]>) -> u64 {
    let mut h = Fnv1a::new();
    for part in parts {
        h.bytes(&(part.len() as u64).to_le_bytes());
        h.bytes(part);
    }
    h.0
}

/// What a reference image depends on, besides the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceKey {
    pub width: u32,
    pub height: u32,
    pub time: f32,
    pub diffuse_bounces: u32,
    /// "photons N", or "seconds S on DEVICE" (what S seconds trace
    /// depends on the device).
    pub budget: String,
    /// The reference's settings (`ReferenceSettings`, Debug form).
    pub settings: String,
}

/// The reference cache's key: a hash of the loaded scene (every value the
/// scene file and the files it references resolve to: meshes, textures,
/// materials, lights, camera, so an edited OBJ or texture changes it even
/// though the TOML did not), the render settings, the program's version and
/// the compiled reference shaders (a changed estimator is traced anew even
/// within one version). Hashing the resolved scene streams its `Debug` form
/// through the hash without building the string.
pub fn cache_key(scene: &Scene, key: &ReferenceKey) -> String {
    let mut h = Fnv1a::new();
    let _ = write!(h, "{}|{scene:?}|{key:?}", env!("CARGO_PKG_VERSION"));
    for bytes in crate::shaders::compiled_under("reference/") {
        h.bytes(bytes);
    }
    format!("{:016x}", h.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_key_changes_with_the_scene_and_the_settings() {
        let text = "[camera]\neye = [0, 1, 3]\ntarget = [0, 0, 0]\n[[light]]\nkind = \"point\"\nposition = [0, 2, 0]\nintensity = 1.0\n[[material]]\nname = \"m\"\nkind = \"diffuse\"\n[[object]]\nshape = \"plane\"\nsize = [1, 1]\nmaterial = \"m\"\n";
        let path = std::path::Path::new("k.toml");
        let scene = Scene::from_str(text, path).unwrap();
        let brighter =
            Scene::from_str(&text.replace("intensity = 1.0", "intensity = 2.0"), path).unwrap();
        let key = ReferenceKey {
            width: 64,
            height: 64,
            time: 0.0,
            diffuse_bounces: 0,
            budget: "photons 1000".into(),
            settings: String::new(),
        };
        let k = cache_key(&scene, &key);
        assert_eq!(k, cache_key(&scene, &key), "stable");
        assert_ne!(k, cache_key(&brighter, &key));
        let wider = ReferenceKey {
            width: 65,
            ..key.clone()
        };
        assert_ne!(k, cache_key(&scene, &wider));
    }
}
