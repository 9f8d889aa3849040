//! Where the files a scene names may be (issue 31, docs/SCENES.md
//! "Paths"). A scene downloaded with its assets must not make the program
//! read `/etc/passwd` or `~/.ssh`: every file a TOML scene names (meshes,
//! the MTL files and textures an OBJ names, textures, environment images,
//! density grids, glTF files) resolves inside the scene file's folder tree,
//! and every file a glTF file names inside the glTF file's folder tree,
//! unless the user allows more folders (`--allow-paths DIR`). One rule,
//! [`Confinement::resolve`], serves both.

use std::path::{Component, Path, PathBuf};

/// Folders the user allows besides a scene's own tree (`--allow-paths`),
/// canonical: a file inside one of their trees may be named from anywhere.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AllowedPaths {
    roots: Vec<PathBuf>,
}

impl AllowedPaths {
    /// `folders` canonicalised (a link to a folder allows the folder it
    /// names); the error names the one that is missing or not a folder.
    pub fn new(folders: &[PathBuf]) -> Result<AllowedPaths, String> {
        let roots = folders
            .iter()
            .map(|folder| {
                let root = folder
                    .canonicalize()
                    .map_err(|e| format!("--allow-paths {}: {e}", folder.display()))?;
                if !root.is_dir() {
                    return Err(format!("--allow-paths {}: not a folder", folder.display()));
                }
                Ok(root)
            })
            .collect::<Result<_, _>>()?;
        Ok(AllowedPaths { roots })
    }
}

/// The trees a file named by a scene may be in: the folder of the scene
/// file (or of the glTF file, for its URIs) and the allowed folders.
#[derive(Clone, Copy, Debug)]
pub struct Confinement<'a> {
    folder: &'a Path,
    /// What `folder` is, in messages ("the scene file's folder").
    owner: &'static str,
    allowed: &'a AllowedPaths,
}

impl<'a> Confinement<'a> {
    /// The files TOML scene `scene_file` names: inside its folder's tree.
    pub fn scene(scene_file: &'a Path, allowed: &'a AllowedPaths) -> Confinement<'a> {
        Confinement {
            folder: folder_of(scene_file),
            owner: "the scene file's folder",
            allowed,
        }
    }

    /// The files glTF file `gltf_file` names by URI: inside its folder's tree.
    pub fn gltf(gltf_file: &'a Path, allowed: &'a AllowedPaths) -> Confinement<'a> {
        Confinement {
            folder: folder_of(gltf_file),
            owner: "the glTF file's folder",
            allowed,
        }
    }

    /// The folder whose tree this confines to (relative references of the
    /// scene or glTF file itself resolve against it).
    pub fn folder(&self) -> &'a Path {
        self.folder
    }

    /// The folders allowed besides [`Self::folder`]'s tree.
    pub fn allowed(&self) -> &'a AllowedPaths {
        self.allowed
    }

    /// The file `reference` names, relative to folder `base` (the folder
    /// of the file naming it: the scene's, or an OBJ's for its `mtllib`),
    /// as `base.join(reference)`. Refused unless it lies inside the tree of
    /// [`Self::folder`] or of an allowed folder, `..` and symbolic links
    /// resolved (the file canonicalised, or, when it does not exist yet,
    /// its path made absolute and `..` taken lexically: reading it then
    /// fails as not found). The error names the reference and the rule.
    pub fn resolve(&self, base: &Path, reference: &Path) -> Result<PathBuf, String> {
        let file = base.join(reference);
        let folder = if self.folder.as_os_str().is_empty() {
            Path::new(".")
        } else {
            self.folder
        };
        let tree = canonical_or_lexical(folder);
        let resolved = canonical_or_lexical(&file);
        if resolved.starts_with(&tree) || self.allowed.roots.iter().any(|r| resolved.starts_with(r))
        {
            return Ok(file);
        }
        let why = if reference.has_root() {
            "an absolute path outside the folder"
        } else if !lexical(&file).starts_with(lexical(folder)) {
            "it climbs above the folder"
        } else {
            "a link that resolves outside the folder"
        };
        Err(format!(
            "`{}`: {why}; only files inside {}'s tree, or the tree of a folder given with --allow-paths, are read (docs/SCENES.md, \"Paths\")",
            reference.display(),
            self.owner
        ))
    }

    /// [`Self::resolve`] relative to [`Self::folder`].
    pub fn file(&self, reference: impl AsRef<Path>) -> Result<PathBuf, String> {
        self.resolve(self.folder, reference.as_ref())
    }
}

/// The folder holding `file` (empty for a bare file name: the working
/// directory, and references keep their own spelling in messages).
fn folder_of(file: &Path) -> &Path {
    file.parent().unwrap_or(Path::new(""))
}

/// `path` canonicalised; when it does not exist, its nearest existing
/// ancestor canonicalised with the rest of [`lexical`]'s path after it.
fn canonical_or_lexical(path: &Path) -> PathBuf {
    if let Ok(canonical) = path.canonicalize() {
        return canonical;
    }
    let lexical = lexical(path);
    for ancestor in lexical.ancestors().skip(1) {
        if let Ok(canonical) = ancestor.canonicalize() {
            let rest = lexical.strip_prefix(ancestor).unwrap_or(&lexical);
            return canonical.join(rest);
        }
    }
    lexical
}

/// `path` made absolute (against the working directory), `.` dropped and
/// each `..` taking off the component before it, without touching the
/// file system.
fn lexical(path: &Path) -> PathBuf {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut out = PathBuf::new();
    for c in absolute.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_resolve_inside_the_tree_or_an_allowed_folder() {
        let dir = std::env::temp_dir().join(format!("caustics-paths-{}", std::process::id()));
        let scene = dir.join("scenes/s.toml");
        std::fs::create_dir_all(dir.join("scenes/meshes")).unwrap();
        std::fs::create_dir_all(dir.join("other")).unwrap();
        std::fs::write(dir.join("other/m.obj"), "").unwrap();
        let none = AllowedPaths::default();
        let within = Confinement::scene(&scene, &none);
        let meshes = dir.join("scenes/meshes");
        assert!(within.file("meshes/m.obj").is_ok());
        assert!(within.file("missing/m.obj").is_ok(), "not found later");
        assert!(within.resolve(&meshes, Path::new("../x.mtl")).is_ok());
        let e = within.file("../other/m.obj").unwrap_err();
        assert!(
            e.contains("climbs above") && e.contains("scene file's folder"),
            "{e}"
        );
        let e = within
            .resolve(&meshes, Path::new("../../x.mtl"))
            .unwrap_err();
        assert!(e.contains("climbs above"), "{e}");
        let e = within.file(dir.join("other/m.obj")).unwrap_err();
        assert!(e.contains("an absolute path"), "{e}");
        let link = dir.join("scenes/link.obj");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(dir.join("other/m.obj"), &link).unwrap();
        let e = within.file("link.obj").unwrap_err();
        assert!(e.contains("a link that resolves outside"), "{e}");
        let allowed = AllowedPaths::new(&[dir.join("other")]).unwrap();
        let wider = Confinement::scene(&scene, &allowed);
        for reference in ["../other/m.obj", "link.obj"] {
            assert!(wider.file(reference).is_ok(), "{reference}");
        }
        assert!(wider.file(dir.join("other/m.obj")).is_ok());
        assert!(wider.file("../elsewhere.obj").is_err());
        let e = AllowedPaths::new(&[dir.join("other/m.obj")]).unwrap_err();
        assert!(e.contains("not a folder"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
