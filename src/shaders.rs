//! SPIR-V compiled by build.rs from `glsl/`, embedded in the binary.

static SHADERS: &[(&str, &[u8])] = include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// The SPIR-V words of a shader by its path under `glsl/`, e.g. "reference/trace.comp".
pub fn spirv(name: &str) -> Vec<u32> {
    let bytes = SHADERS
        .iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("shader {name} was not compiled by build.rs"))
        .1;
    ash::util::read_spv(&mut std::io::Cursor::new(bytes)).expect("valid SPIR-V from build.rs")
}
