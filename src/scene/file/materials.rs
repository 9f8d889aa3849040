//! The scene's materials with an index by name, so every name check
//! (duplicate `[[material]]`, an object's `material`, an MTL material met
//! again) is one hash lookup: a scene or MTL file with thousands of
//! materials loads in linear time. It also holds the albedo textures the
//! materials use, each file decoded once however many materials name it.

use crate::scene::texture;
use crate::scene::types::{Material, Texture};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

#[derive(Default)]
pub(super) struct Materials {
    list: Vec<Material>,
    by_name: HashMap<String, usize>,
    /// The first `defined` come from `[[material]]`; materials that OBJ
    /// files bring through their MTL follow.
    defined: usize,
    textures: Vec<Texture>,
    texture_by_path: HashMap<PathBuf, u32>,
}

impl Materials {
    /// Adds a `[[material]]`; `Err(i)` if material `i` has the same name.
    pub(super) fn define(&mut self, m: Material) -> Result<(), usize> {
        debug_assert_eq!(
            self.defined,
            self.list.len(),
            "defined after an MTL material"
        );
        if let Some(&first) = self.by_name.get(&m.name) {
            return Err(first);
        }
        self.push(m);
        self.defined = self.list.len();
        Ok(())
    }

    /// The index of the `[[material]]` called `name` (MTL materials are not
    /// names an object can use).
    pub(super) fn defined_index(&self, name: &str) -> Option<usize> {
        self.by_name
            .get(name)
            .copied()
            .filter(|&i| i < self.defined)
    }

    /// The names of the `[[material]]`s, in file order.
    pub(super) fn defined_names(&self) -> Vec<&str> {
        self.list[..self.defined]
            .iter()
            .map(|m| m.name.as_str())
            .collect()
    }

    /// The index of an MTL material: the one already added if an identical
    /// material of that name came from an earlier OBJ (the same file used
    /// twice), else a new one. `None` when the name is taken by a different
    /// material or by a `[[material]]`.
    pub(super) fn add_mtl(&mut self, m: &Material) -> Option<usize> {
        match self.by_name.get(&m.name) {
            Some(&i) if i >= self.defined && self.list[i] == *m => Some(i),
            Some(_) => None,
            None => Some(self.push(m.clone())),
        }
    }

    fn push(&mut self, m: Material) -> usize {
        let i = self.list.len();
        self.by_name.insert(m.name.clone(), i);
        self.list.push(m);
        i
    }

    /// The index in `Scene::textures` of the texture file `path`, decoding
    /// it on first use. The error says why (without a scene location).
    pub(super) fn texture(&mut self, path: &Path) -> Result<u32, String> {
        match self.texture_by_path.get(path) {
            Some(&i) => Ok(i),
            None => Ok(self.add_texture(texture::load(path)?)),
        }
    }

    /// The index in `Scene::textures` of a decoded texture: the one of the
    /// same `path` if already added (the same image named twice).
    pub(super) fn add_texture(&mut self, t: Texture) -> u32 {
        if let Some(&i) = self.texture_by_path.get(&t.path) {
            return i;
        }
        let i = self.textures.len() as u32;
        self.texture_by_path.insert(t.path.clone(), i);
        self.textures.push(t);
        i
    }

    /// The materials and the textures they index.
    pub(super) fn into_parts(self) -> (Vec<Material>, Vec<Texture>) {
        (self.list, self.textures)
    }
}
