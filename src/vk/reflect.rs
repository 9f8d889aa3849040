//! The descriptor bindings a compiled shader uses, read from its SPIR-V
//! (SPIR-V 1.5 spec, sect. 2.3 "Physical Layout", 3.32 instructions): a
//! set's layout is the union of what its shaders use
//! (`DescriptorSetLayout::of_shaders`), so a binding is declared by the
//! shader that reads it and by the one Rust line that writes it, never in a
//! third list.
//!
//! Only variables in the entry point's interface count: from SPIR-V 1.4 on
//! it lists every global the entry point uses, so a binding that a shared
//! header declares and the shader never touches is not part of its layout.

use ash::vk;
use std::collections::{BTreeMap, HashMap, HashSet};

const MAGIC: u32 = 0x0723_0203;
const OP_ENTRY_POINT: u16 = 15;
const OP_TYPE_IMAGE: u16 = 25;
const OP_TYPE_SAMPLED_IMAGE: u16 = 27;
const OP_TYPE_ARRAY: u16 = 28;
const OP_TYPE_RUNTIME_ARRAY: u16 = 29;
const OP_TYPE_STRUCT: u16 = 30;
const OP_TYPE_POINTER: u16 = 32;
const OP_VARIABLE: u16 = 59;
const OP_DECORATE: u16 = 71;
const DECORATION_BLOCK: u32 = 2;
const DECORATION_BUFFER_BLOCK: u32 = 3;
const DECORATION_BINDING: u32 = 33;
const DECORATION_DESCRIPTOR_SET: u32 = 34;
const STORAGE_UNIFORM_CONSTANT: u32 = 0;
const STORAGE_UNIFORM: u32 = 2;
const STORAGE_STORAGE_BUFFER: u32 = 12;

/// What a binding holds (one descriptor each).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    Uniform,
    Storage,
    StorageImage,
    /// Combined image sampler.
    Sampled,
}

impl BindingKind {
    pub(super) fn descriptor_type(self) -> vk::DescriptorType {
        match self {
            BindingKind::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
            BindingKind::Storage => vk::DescriptorType::STORAGE_BUFFER,
            BindingKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
            BindingKind::Sampled => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        }
    }
}

/// One descriptor a shader uses: its set, binding and kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReflectedBinding {
    pub set: u32,
    pub binding: u32,
    pub kind: BindingKind,
}

/// The descriptors `words` (one shader module) uses, sorted by set and
/// binding; an error naming what it cannot map to a `BindingKind`.
pub fn bindings(words: &[u32]) -> Result<Vec<ReflectedBinding>, String> {
    if words.len() < 5 || words[0] != MAGIC {
        return Err("not SPIR-V (bad magic number)".into());
    }
    let mut interface: HashSet<u32> = HashSet::new();
    let mut decorations: HashMap<(u32, u32), u32> = HashMap::new();
    let mut images: HashMap<u32, u32> = HashMap::new(); // id -> Sampled operand
    let mut sampled_images: HashSet<u32> = HashSet::new();
    let mut arrays: HashMap<u32, u32> = HashMap::new(); // id -> element type
    let mut structs: HashSet<u32> = HashSet::new();
    let mut pointers: HashMap<u32, (u32, u32)> = HashMap::new(); // id -> (class, pointee)
    let mut variables: Vec<(u32, u32, u32)> = Vec::new(); // (id, pointer type, class)
    let mut at = 5;
    while at < words.len() {
        let count = (words[at] >> 16) as usize;
        let op = (words[at] & 0xffff) as u16;
        if count == 0 || at + count > words.len() {
            return Err(format!("truncated instruction at word {at}"));
        }
        let w = &words[at + 1..at + count];
        match op {
            OP_ENTRY_POINT => {
                // Execution model, id, a nul-terminated name packed in
                // words, then the interface ids.
                let name_words = w[2..]
                    .iter()
                    .position(|x| x.to_le_bytes().contains(&0))
                    .map_or(w.len(), |i| i + 1);
                interface.extend(&w[2 + name_words..]);
            }
            OP_DECORATE if w.len() >= 2 => {
                decorations.insert((w[0], w[1]), w.get(2).copied().unwrap_or(0));
            }
            OP_TYPE_IMAGE => {
                images.insert(w[0], w[6]);
            }
            OP_TYPE_SAMPLED_IMAGE => {
                sampled_images.insert(w[0]);
            }
            OP_TYPE_ARRAY | OP_TYPE_RUNTIME_ARRAY => {
                arrays.insert(w[0], w[1]);
            }
            OP_TYPE_STRUCT => {
                structs.insert(w[0]);
            }
            OP_TYPE_POINTER => {
                pointers.insert(w[0], (w[1], w[2]));
            }
            OP_VARIABLE => variables.push((w[1], w[0], w[2])),
            _ => {}
        }
        at += count;
    }
    let mut found: BTreeMap<(u32, u32), BindingKind> = BTreeMap::new();
    for (id, pointer, class) in variables {
        let (Some(&set), Some(&binding)) = (
            decorations.get(&(id, DECORATION_DESCRIPTOR_SET)),
            decorations.get(&(id, DECORATION_BINDING)),
        ) else {
            continue;
        };
        if !interface.contains(&id) {
            continue;
        }
        let ty = pointers.get(&pointer).map_or(0, |p| p.1);
        if let Some(&element) = arrays.get(&ty) {
            return Err(format!(
                "set {set} binding {binding}: an array of descriptors (type {element}) is not supported"
            ));
        }
        let kind = match class {
            STORAGE_STORAGE_BUFFER => BindingKind::Storage,
            STORAGE_UNIFORM if decorations.contains_key(&(ty, DECORATION_BUFFER_BLOCK)) => {
                BindingKind::Storage
            }
            STORAGE_UNIFORM if decorations.contains_key(&(ty, DECORATION_BLOCK)) => {
                BindingKind::Uniform
            }
            STORAGE_UNIFORM_CONSTANT if sampled_images.contains(&ty) => BindingKind::Sampled,
            STORAGE_UNIFORM_CONSTANT if images.get(&ty) == Some(&2) => BindingKind::StorageImage,
            _ => {
                return Err(format!(
                    "set {set} binding {binding}: storage class {class}, type {ty}{} is not a uniform or storage buffer, storage image or combined image sampler",
                    if structs.contains(&ty) { " (a struct)" } else { "" }
                ));
            }
        };
        found.insert((set, binding), kind);
    }
    Ok(found
        .into_iter()
        .map(|((set, binding), kind)| ReflectedBinding { set, binding, kind })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Instruction words: `op` with its operands.
    fn inst(op: u16, operands: &[u32]) -> Vec<u32> {
        let mut v = vec![((operands.len() as u32 + 1) << 16) | op as u32];
        v.extend_from_slice(operands);
        v
    }

    /// A hand-assembled module: a storage buffer at (1, 3), a storage
    /// image at (0, 2), a combined sampler at (1, 0) and a uniform block
    /// at (1, 5) that the entry point does not use.
    #[test]
    fn reads_sets_bindings_and_kinds_of_the_entry_points_variables() {
        let mut m = vec![MAGIC, 0x0001_0500, 0, 100, 0];
        // OpEntryPoint GLCompute %1 "main" %10 %11 %12
        m.extend(inst(
            OP_ENTRY_POINT,
            &[5, 1, u32::from_le_bytes(*b"main"), 0, 10, 11, 12],
        ));
        for (var, set, binding) in [(10, 1, 3), (11, 0, 2), (12, 1, 0), (13, 1, 5)] {
            m.extend(inst(OP_DECORATE, &[var, DECORATION_DESCRIPTOR_SET, set]));
            m.extend(inst(OP_DECORATE, &[var, DECORATION_BINDING, binding]));
        }
        m.extend(inst(OP_DECORATE, &[20, DECORATION_BLOCK]));
        m.extend(inst(OP_DECORATE, &[21, DECORATION_BLOCK]));
        m.extend(inst(OP_TYPE_STRUCT, &[20]));
        m.extend(inst(OP_TYPE_STRUCT, &[21]));
        // %22 = 2D storage image, %23 = sampled image of a sampled %24.
        m.extend(inst(OP_TYPE_IMAGE, &[22, 99, 1, 0, 0, 0, 2, 1]));
        m.extend(inst(OP_TYPE_IMAGE, &[24, 99, 1, 0, 0, 0, 1, 0]));
        m.extend(inst(OP_TYPE_SAMPLED_IMAGE, &[23, 24]));
        m.extend(inst(OP_TYPE_POINTER, &[30, STORAGE_STORAGE_BUFFER, 20]));
        m.extend(inst(OP_TYPE_POINTER, &[31, STORAGE_UNIFORM_CONSTANT, 22]));
        m.extend(inst(OP_TYPE_POINTER, &[32, STORAGE_UNIFORM_CONSTANT, 23]));
        m.extend(inst(OP_TYPE_POINTER, &[33, STORAGE_UNIFORM, 21]));
        m.extend(inst(OP_VARIABLE, &[30, 10, STORAGE_STORAGE_BUFFER]));
        m.extend(inst(OP_VARIABLE, &[31, 11, STORAGE_UNIFORM_CONSTANT]));
        m.extend(inst(OP_VARIABLE, &[32, 12, STORAGE_UNIFORM_CONSTANT]));
        m.extend(inst(OP_VARIABLE, &[33, 13, STORAGE_UNIFORM]));
        let b = |set, binding, kind| ReflectedBinding { set, binding, kind };
        assert_eq!(
            bindings(&m).unwrap(),
            [
                b(0, 2, BindingKind::StorageImage),
                b(1, 0, BindingKind::Sampled),
                b(1, 3, BindingKind::Storage),
            ]
        );
        assert!(bindings(&m[1..]).is_err());
        assert!(bindings(&m[..m.len() - 1]).is_err());
    }

    /// Every shader build.rs compiled maps to kinds a layout can hold, and
    /// a shader that binds through a shared header keeps only what it uses
    /// (the tonemap's two images, not the scene's set).
    #[test]
    fn every_compiled_shader_reflects() {
        for bytes in crate::shaders::compiled_under("") {
            let words = ash::util::read_spv(&mut std::io::Cursor::new(bytes)).unwrap();
            bindings(&words).unwrap();
        }
        let tonemap = bindings(&crate::shaders::spirv("passes/tonemap.comp")).unwrap();
        let kinds: Vec<_> = tonemap.iter().map(|b| (b.set, b.binding, b.kind)).collect();
        assert_eq!(
            kinds,
            [
                (0, 0, BindingKind::StorageImage),
                (0, 1, BindingKind::StorageImage)
            ]
        );
    }
}
