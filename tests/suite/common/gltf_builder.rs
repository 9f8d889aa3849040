//! A glTF 2.0 writer for tests: scenes built in code as .gltf or .glb
//! files. Shared by tests/suite/gltf.rs and tests/scene_scaling.rs (which
//! includes this file by path).

use caustics::scene::Mesh;
use glam::{Vec2, Vec3};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// A glTF document being written: one binary buffer, accessors appended.
pub struct Gltf {
    pub bin: Vec<u8>,
    pub root: Value,
}

impl Gltf {
    pub fn new() -> Self {
        Gltf {
            bin: Vec::new(),
            root: json!({
                "asset": {"version": "2.0"},
                "scene": 0,
                "scenes": [{"nodes": []}],
                "nodes": [], "meshes": [], "materials": [],
                "accessors": [], "bufferViews": [],
            }),
        }
    }

    pub fn push(&mut self, key: &str, v: Value) -> usize {
        let a = self.root[key].as_array_mut().unwrap();
        a.push(v);
        a.len() - 1
    }

    /// Raw bytes as a new buffer view.
    pub fn view(&mut self, bytes: &[u8]) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let view = self.push(
            "bufferViews",
            json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}),
        );
        self.bin.extend_from_slice(bytes);
        view
    }

    /// Raw bytes as a new buffer view + accessor.
    pub fn accessor(&mut self, bytes: &[u8], count: usize, ty: &str, component: u32) -> usize {
        let view = self.view(bytes);
        self.push(
            "accessors",
            json!({"bufferView": view, "count": count, "type": ty, "componentType": component}),
        )
    }

    pub fn vec3s(&mut self, v: &[Vec3]) -> usize {
        let i = self.accessor(bytemuck::cast_slice(v), v.len(), "VEC3", 5126);
        // POSITION accessors need min and max (any VEC3 may carry them).
        let finite = v.iter().filter(|p| p.is_finite());
        let lo = finite.clone().fold(Vec3::INFINITY, |a, &b| a.min(b));
        let hi = finite.fold(Vec3::NEG_INFINITY, |a, &b| a.max(b));
        let (lo, hi) = if lo.x <= hi.x {
            (lo, hi)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        self.root["accessors"][i]["min"] = json!(lo.to_array());
        self.root["accessors"][i]["max"] = json!(hi.to_array());
        i
    }

    pub fn vec2s(&mut self, v: &[Vec2]) -> usize {
        self.accessor(bytemuck::cast_slice(v), v.len(), "VEC2", 5126)
    }

    pub fn indices(&mut self, t: &[[u32; 3]]) -> usize {
        self.accessor(bytemuck::cast_slice(t), t.len() * 3, "SCALAR", 5125)
    }

    /// A mesh of one primitive (`normals`: write the mesh's NORMAL).
    pub fn mesh(&mut self, m: &Mesh, normals: bool, material: Option<usize>) -> usize {
        let pos = self.vec3s(&m.positions);
        let idx = self.indices(&m.indices);
        let mut prim = json!({"attributes": {"POSITION": pos}, "indices": idx});
        if normals {
            prim["attributes"]["NORMAL"] = json!(self.vec3s(&m.normals));
        }
        if let Some(mat) = material {
            prim["material"] = json!(mat);
        }
        self.push("meshes", json!({"primitives": [prim]}))
    }

    pub fn material(&mut self, m: Value) -> usize {
        self.push("materials", m)
    }

    pub fn node(&mut self, n: Value) -> usize {
        self.push("nodes", n)
    }

    /// Puts a node at the scene root.
    pub fn root_node(&mut self, n: Value) -> usize {
        let i = self.node(n);
        self.root["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(i));
        i
    }

    pub fn finish(&mut self, uri: Option<&str>) -> Value {
        let mut root = self.root.clone();
        let mut buffer = json!({"byteLength": self.bin.len()});
        if let Some(u) = uri {
            buffer["uri"] = json!(u);
        }
        root["buffers"] = json!([buffer]);
        root
    }

    /// `name.gltf` and `name.bin` in `dir`.
    pub fn write_gltf(&mut self, dir: &Path, name: &str) -> PathBuf {
        let bin = format!("{name}.bin");
        let root = self.finish(Some(&bin));
        std::fs::write(dir.join(&bin), &self.bin).unwrap();
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_vec_pretty(&root).unwrap()).unwrap();
        path
    }

    /// `name.glb`: the JSON and BIN chunks, each padded to 4 bytes.
    pub fn write_glb(&mut self, dir: &Path, name: &str) -> PathBuf {
        let mut json = serde_json::to_vec(&self.finish(None)).unwrap();
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        let path = dir.join(format!("{name}.glb"));
        std::fs::write(&path, out).unwrap();
        path
    }
}
