//! Device discovery: what the renderer requires of a device
//! (`RequiredFeature`), what `caustics info` shows of each (`DeviceInfo`),
//! and the choice of one (`--device` by index or name).

use super::instance::{create_instance, load_entry, Validation};
use super::{VkError, VkResult};
use ash::vk;
use std::ffi::CStr;

/// Every device feature the renderer relies on, checked at start-up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RequiredFeature {
    Vulkan13,
    GeometryShader,
    FragmentStoresAndAtomics,
    VertexPipelineStoresAndAtomics,
    BufferFloat32AtomicAdd,
    TimestampQueries,
    MultiDrawIndirect,
    DynamicRendering,
    Synchronization2,
}

impl RequiredFeature {
    pub const ALL: [RequiredFeature; 9] = [
        RequiredFeature::Vulkan13,
        RequiredFeature::GeometryShader,
        RequiredFeature::FragmentStoresAndAtomics,
        RequiredFeature::VertexPipelineStoresAndAtomics,
        RequiredFeature::BufferFloat32AtomicAdd,
        RequiredFeature::TimestampQueries,
        RequiredFeature::MultiDrawIndirect,
        RequiredFeature::DynamicRendering,
        RequiredFeature::Synchronization2,
    ];

    pub fn name(self) -> &'static str {
        match self {
            RequiredFeature::Vulkan13 => "Vulkan 1.3",
            RequiredFeature::GeometryShader => "geometryShader",
            RequiredFeature::FragmentStoresAndAtomics => "fragmentStoresAndAtomics",
            RequiredFeature::VertexPipelineStoresAndAtomics => "vertexPipelineStoresAndAtomics",
            RequiredFeature::BufferFloat32AtomicAdd => {
                "shaderBufferFloat32AtomicAdd (VK_EXT_shader_atomic_float)"
            }
            RequiredFeature::TimestampQueries => "timestampComputeAndGraphics",
            RequiredFeature::MultiDrawIndirect => "multiDrawIndirect",
            RequiredFeature::DynamicRendering => "dynamicRendering",
            RequiredFeature::Synchronization2 => "synchronization2",
        }
    }
}

/// What `caustics info` prints for one device.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    pub api_version: (u32, u32, u32),
    pub driver: String,
    pub features: Vec<(RequiredFeature, bool)>,
}

impl DeviceInfo {
    pub fn missing(&self) -> Vec<RequiredFeature> {
        self.features
            .iter()
            .filter(|(_, ok)| !ok)
            .map(|(f, _)| *f)
            .collect()
    }
}

fn cstr_array(raw: &[std::ffi::c_char]) -> String {
    // SAFETY: Vulkan guarantees these fixed arrays are NUL-terminated.
    unsafe { CStr::from_ptr(raw.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

pub(super) fn query_device(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    index: usize,
) -> DeviceInfo {
    unsafe {
        let props = instance.get_physical_device_properties(pd);
        let mut atomic = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
        let has_atomic_ext = instance
            .enumerate_device_extension_properties(pd)
            .unwrap_or_default()
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::shader_atomic_float::NAME));
        let api = props.api_version;
        let is_13 = vk::api_version_major(api) > 1 || vk::api_version_minor(api) >= 3;
        let mut features2 = vk::PhysicalDeviceFeatures2::default();
        if is_13 {
            features2 = features2.push_next(&mut v13);
        }
        if has_atomic_ext {
            features2 = features2.push_next(&mut atomic);
        }
        instance.get_physical_device_features2(pd, &mut features2);
        let f = features2.features;
        let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver_props);
        instance.get_physical_device_properties2(pd, &mut props2);
        let features = RequiredFeature::ALL
            .iter()
            .map(|&r| {
                let ok = match r {
                    RequiredFeature::Vulkan13 => is_13,
                    RequiredFeature::GeometryShader => f.geometry_shader == vk::TRUE,
                    RequiredFeature::FragmentStoresAndAtomics => {
                        f.fragment_stores_and_atomics == vk::TRUE
                    }
                    RequiredFeature::VertexPipelineStoresAndAtomics => {
                        f.vertex_pipeline_stores_and_atomics == vk::TRUE
                    }
                    RequiredFeature::BufferFloat32AtomicAdd => {
                        has_atomic_ext && atomic.shader_buffer_float32_atomic_add == vk::TRUE
                    }
                    RequiredFeature::TimestampQueries => {
                        props.limits.timestamp_compute_and_graphics == vk::TRUE
                    }
                    RequiredFeature::MultiDrawIndirect => f.multi_draw_indirect == vk::TRUE,
                    RequiredFeature::DynamicRendering => v13.dynamic_rendering == vk::TRUE,
                    RequiredFeature::Synchronization2 => v13.synchronization2 == vk::TRUE,
                };
                (r, ok)
            })
            .collect();
        DeviceInfo {
            index,
            name: cstr_array(&props.device_name),
            kind: props.device_type,
            api_version: (
                vk::api_version_major(api),
                vk::api_version_minor(api),
                vk::api_version_patch(api),
            ),
            driver: format!(
                "{} {}",
                cstr_array(&driver_props.driver_name),
                cstr_array(&driver_props.driver_info)
            ),
            features,
        }
    }
}

/// Lists every device with the features the renderer needs (`caustics info`).
pub fn enumerate_devices() -> VkResult<Vec<DeviceInfo>> {
    let entry = load_entry()?;
    let (instance, _) = create_instance(&entry, Validation::Off, &[])?;
    let devices = unsafe { instance.enumerate_physical_devices() };
    let infos = devices.map(|devices| {
        devices
            .iter()
            .enumerate()
            .map(|(i, &pd)| query_device(&instance, pd, i))
            .collect()
    });
    unsafe { instance.destroy_instance(super::host_memory::HOST_CALLBACKS) };
    Ok(infos?)
}

pub(super) fn pick_device(infos: &[DeviceInfo], wanted: Option<&str>) -> VkResult<usize> {
    if infos.is_empty() {
        return Err(VkError::NoDevice);
    }
    if let Some(w) = wanted {
        if let Ok(i) = w.parse::<usize>() {
            return if i < infos.len() {
                Ok(i)
            } else {
                Err(VkError::DeviceNotFound(w.into()))
            };
        }
        let lw = w.to_lowercase();
        return infos
            .iter()
            .position(|d| d.name.to_lowercase().contains(&lw))
            .ok_or_else(|| VkError::DeviceNotFound(w.into()));
    }
    // Prefer a discrete GPU with every feature, then any complete device, then
    // whatever exists (the caller reports what it lacks).
    let rank = |d: &DeviceInfo| {
        let complete = d.missing().is_empty();
        let kind = match d.kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => 0,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
            vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
            vk::PhysicalDeviceType::CPU => 3,
            _ => 4,
        };
        (!complete, kind)
    };
    Ok(infos
        .iter()
        .min_by_key(|d| rank(d))
        .map(|d| d.index)
        .unwrap_or(0))
}
