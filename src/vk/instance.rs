//! The Vulkan loader and instance: the validation layer and its
//! synchronization validation when asked for, debug utils when offered.
//! Used by `Context` (its instance) and by device enumeration (a
//! throwaway instance).

use super::host_memory::HOST_CALLBACKS;
use super::{VkError, VkResult};
use ash::vk;
use std::ffi::CStr;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

pub(super) fn load_entry() -> VkResult<ash::Entry> {
    // SAFETY: loading the system Vulkan loader; its symbols are trusted.
    unsafe { ash::Entry::load() }.map_err(|e| VkError::Loader(e.to_string()))
}

/// The validation features an instance is created with.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Validation {
    Off,
    On,
    /// On, with synchronization validation.
    Sync,
}

/// Creates the instance; returns it and whether synchronization validation
/// is on (asked for and offered by the layer).
pub(super) fn create_instance(
    entry: &ash::Entry,
    validation: Validation,
    extra_extensions: &[*const std::ffi::c_char],
) -> VkResult<(ash::Instance, bool)> {
    let app = vk::ApplicationInfo::default()
        .application_name(c"caustics")
        .engine_name(c"caustics")
        .api_version(vk::API_VERSION_1_3);
    let mut extensions: Vec<*const std::ffi::c_char> = extra_extensions.to_vec();
    let mut layers = Vec::new();
    let mut sync_validation = false;
    if validation != Validation::Off {
        let available = unsafe { entry.enumerate_instance_layer_properties() }?;
        if !available
            .iter()
            .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER))
        {
            return Err(VkError::NoValidationLayer);
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        if validation == Validation::Sync {
            // The layer itself provides VK_EXT_validation_features.
            sync_validation =
                unsafe { entry.enumerate_instance_extension_properties(Some(VALIDATION_LAYER)) }?
                    .iter()
                    .any(|e| {
                        e.extension_name_as_c_str() == Ok(ash::ext::validation_features::NAME)
                    });
            if sync_validation {
                extensions.push(ash::ext::validation_features::NAME.as_ptr());
            } else {
                log::warn!(
                    "the validation layer does not offer VK_EXT_validation_features: \
                     synchronization validation stays off"
                );
            }
        }
    }
    let has_debug_utils = unsafe { entry.enumerate_instance_extension_properties(None) }?
        .iter()
        .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::debug_utils::NAME));
    if has_debug_utils {
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let enabled = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    if sync_validation {
        info = info.push_next(&mut features);
    }
    let instance = unsafe { entry.create_instance(&info, HOST_CALLBACKS) }?;
    Ok((instance, sync_validation))
}
