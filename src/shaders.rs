//! SPIR-V compiled by build.rs from `glsl/`, embedded in the binary.

static SHADERS: &[(&str, &[u8])] = include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// The compiled bytes of every shader whose path under `glsl/` starts with
/// `prefix`, in build order (a fingerprint of, e.g., the reference's code).
pub fn compiled_under(prefix: &str) -> impl Iterator<Item = &'static [u8]> + '_ {
    SHADERS
        .iter()
        .filter(move |(n, _)| n.starts_with(prefix))
        .map(|(_, bytes)| *bytes)
}

/// The SPIR-V words of a shader by its path under `glsl/`, e.g. "reference/trace.comp".
pub fn spirv(name: &str) -> Vec<u32> {
    let bytes = SHADERS
        .iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("shader {name} was not compiled by build.rs"))
        .1;
    ash::util::read_spv(&mut std::io::Cursor::new(bytes)).expect("valid SPIR-V from build.rs")
}
