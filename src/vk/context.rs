//! Instance, physical-device choice, logical device, queue, allocator and the
//! validation messenger. One `Context` per process; everything else holds an
//! `Arc<Context>` so the device is destroyed last.

use super::device::{enumerate_devices, pick_device, query_device, DeviceInfo};
use super::instance::{create_instance, load_entry, Validation};
use super::limits::{MemoryHeaps, MemoryReport};
use super::pipeline_store::PipelineStore;
use super::{fault, VkError, VkResult};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::c_void;
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};

// Instance and device are created with these, so their host allocations
// are counted (`vk/host_memory.rs`).
use super::host_memory::HOST_CALLBACKS;

#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Turn on the Khronos validation layer and count its messages.
    pub validation: bool,
    /// With `validation`, also turn on the layer's synchronization
    /// validation (`VK_EXT_validation_features`,
    /// `SYNCHRONIZATION_VALIDATION`): missing or wrong barriers between
    /// commands are reported as errors (SYNC-HAZARD-*). Enabled only where
    /// the layer exposes the extension; `Context::sync_validation` says
    /// whether it is on.
    pub sync_validation: bool,
    /// Pick a device by index (as `caustics info` lists) or by a substring of its name.
    pub device: Option<String>,
}

/// Validation messages counted by the debug messenger since start-up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ValidationCounts {
    pub errors: u32,
    pub warnings: u32,
}

struct Counters {
    errors: AtomicU32,
    warnings: AtomicU32,
    /// The first error messages, kept so tests can show why they failed.
    first_errors: Mutex<Vec<String>>,
}

pub struct Context {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub info: DeviceInfo,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f64,
    /// Valid bits of a timestamp on the queue (for wrapping subtraction).
    pub timestamp_valid_bits: u32,
    pub limits: vk::PhysicalDeviceLimits,
    /// The memory heaps and what this process holds in each: every
    /// allocation is checked against them first (`limits.rs`).
    pub memory: MemoryHeaps,
    /// Synchronization validation is on (`ContextOptions::sync_validation`
    /// asked for it and the layer offers it).
    pub sync_validation: bool,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    debug_instance: Option<ash::ext::debug_utils::Instance>,
    debug_device: Option<ash::ext::debug_utils::Device>,
    messenger: vk::DebugUtilsMessengerEXT,
    counters: Box<Counters>,
    command_pool: vk::CommandPool,
    /// Pipelines shared across rebuilds, and the driver's pipeline cache.
    pipelines: PipelineStore,
    /// The serial of the frame being recorded (`Frames::begin_frame` counts
    /// it up); descriptor sets bound into a command buffer remember it.
    pub(super) frame_serial: std::sync::atomic::AtomicU64,
    /// Frames submitted through a `Frames` and not yet seen complete: a
    /// host write straight into a buffer the GPU may read is refused while
    /// any is (`Buffer::upload`).
    pub(super) frames_pending: std::sync::atomic::AtomicUsize,
    destroyed: bool,
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the messenger passes the `Counters` pointer we registered, alive until the messenger is destroyed.
    let counters = unsafe { &*(user as *const Counters) };
    let message = unsafe { (*data).message_as_c_str() }
        .map(|m| m.to_string_lossy().into_owned())
        .unwrap_or_default();
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        counters.errors.fetch_add(1, Ordering::SeqCst);
        log::error!("[vulkan {kind:?}] {message}");
        if let Ok(mut first) = counters.first_errors.lock() {
            if first.len() < 16 {
                first.push(message);
            }
        }
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        counters.warnings.fetch_add(1, Ordering::SeqCst);
        log::warn!("[vulkan {kind:?}] {message}");
    } else {
        log::debug!("[vulkan {kind:?}] {message}");
    }
    vk::FALSE
}

impl Context {
    pub fn list_devices() -> VkResult<Vec<DeviceInfo>> {
        enumerate_devices()
    }

    /// Headless context (no surface extensions).
    pub fn new(options: &ContextOptions) -> VkResult<Arc<Context>> {
        Self::with_instance_extensions(options, &[])
    }

    /// A context whose instance also enables `extensions` (e.g. surface extensions for the demo).
    pub fn with_instance_extensions(
        options: &ContextOptions,
        instance_extensions: &[*const std::ffi::c_char],
    ) -> VkResult<Arc<Context>> {
        let entry = load_entry()?;
        let validation = match (options.validation, options.sync_validation) {
            (false, _) => Validation::Off,
            (true, false) => Validation::On,
            (true, true) => Validation::Sync,
        };
        // Asked before the instance exists, so no early return leaves one.
        let has_debug_utils = unsafe { entry.enumerate_instance_extension_properties(None) }?
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::debug_utils::NAME));
        let (instance, sync_validation) = create_instance(&entry, validation, instance_extensions)?;
        let counters = Box::new(Counters {
            errors: AtomicU32::new(0),
            warnings: AtomicU32::new(0),
            first_errors: Mutex::new(Vec::new()),
        });
        let (debug_instance, messenger) = if has_debug_utils {
            let debug = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                        | vk::DebugUtilsMessageSeverityFlagsEXT::INFO,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback))
                .user_data(&*counters as *const Counters as *mut c_void);
            match unsafe { debug.create_debug_utils_messenger(&info, None) } {
                Ok(messenger) => (Some(debug), messenger),
                Err(e) => {
                    unsafe { instance.destroy_instance(HOST_CALLBACKS) };
                    return Err(e.into());
                }
            }
        } else {
            (None, vk::DebugUtilsMessengerEXT::null())
        };

        let cleanup = |instance: &ash::Instance| unsafe {
            if let Some(d) = &debug_instance {
                d.destroy_debug_utils_messenger(messenger, None);
            }
            instance.destroy_instance(HOST_CALLBACKS);
        };
        let devices = match unsafe { instance.enumerate_physical_devices() } {
            Ok(d) => d,
            Err(e) => {
                cleanup(&instance);
                return Err(e.into());
            }
        };
        let infos: Vec<DeviceInfo> = devices
            .iter()
            .enumerate()
            .map(|(i, &pd)| query_device(&instance, pd, i))
            .collect();
        let chosen = match pick_device(&infos, options.device.as_deref()) {
            Ok(i) => i,
            Err(e) => {
                cleanup(&instance);
                return Err(e);
            }
        };
        let info = infos[chosen].clone();
        let missing = info.missing();
        if !missing.is_empty() {
            cleanup(&instance);
            return Err(VkError::MissingFeatures {
                device: info.name.clone(),
                missing: missing
                    .iter()
                    .map(|f| f.name())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        let physical_device = devices[chosen];
        let props = unsafe { instance.get_physical_device_properties(physical_device) };
        let families =
            unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
        let Some(queue_family) = families.iter().position(|f| {
            f.queue_flags
                .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)
                && f.timestamp_valid_bits > 0
        }) else {
            cleanup(&instance);
            return Err(VkError::MissingFeatures {
                device: info.name.clone(),
                missing: "a graphics+compute queue with timestamps".into(),
            });
        };
        let timestamp_valid_bits = families[queue_family].timestamp_valid_bits;
        let queue_family = queue_family as u32;

        let priorities = [1.0f32];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let features = vk::PhysicalDeviceFeatures::default()
            .geometry_shader(true)
            .fragment_stores_and_atomics(true)
            .vertex_pipeline_stores_and_atomics(true)
            .multi_draw_indirect(true)
            // Point sprites wider than one pixel (caustic-map splats), where offered.
            .large_points(unsafe {
                instance
                    .get_physical_device_features(physical_device)
                    .large_points
                    == vk::TRUE
            })
            .wide_lines(
                props.limits.line_width_range[1] > 1.0
                    && unsafe {
                        instance
                            .get_physical_device_features(physical_device)
                            .wide_lines
                            == vk::TRUE
                    },
            );
        let mut v12 = vk::PhysicalDeviceVulkan12Features::default().host_query_reset(true);
        let mut v13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true);
        let mut atomic = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
            .shader_buffer_float32_atomics(true)
            .shader_buffer_float32_atomic_add(true);
        let extensions = [
            ash::ext::shader_atomic_float::NAME.as_ptr(),
            ash::khr::swapchain::NAME.as_ptr(),
        ];
        // Swapchains only when the instance has surface extensions (the demo):
        // VK_KHR_swapchain requires VK_KHR_surface on the instance.
        let extensions = if instance_extensions.is_empty() {
            &extensions[..1]
        } else {
            &extensions[..]
        };
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_features(&features)
            .enabled_extension_names(extensions)
            .push_next(&mut v12)
            .push_next(&mut v13)
            .push_next(&mut atomic);
        let device = match unsafe {
            instance.create_device(physical_device, &device_info, HOST_CALLBACKS)
        } {
            Ok(d) => d,
            Err(e) => {
                cleanup(&instance);
                return Err(e.into());
            }
        };
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let mut debug_settings = gpu_allocator::AllocatorDebugSettings::default();
        debug_settings.log_leaks_on_shutdown = true;
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings,
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        });
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let pool = unsafe { device.create_command_pool(&pool_info, None) };
        let (allocator, command_pool) = match (allocator, pool) {
            (Ok(a), Ok(p)) => (a, p),
            (allocator, pool) => {
                // Undo in reverse order so a failed start leaves nothing behind.
                unsafe {
                    if let Ok(p) = pool {
                        device.destroy_command_pool(p, None);
                    }
                    let error: VkError = match allocator {
                        Err(e) => e.into(),
                        Ok(a) => {
                            drop(a);
                            pool.err()
                                .map(VkError::from)
                                .unwrap_or(VkError::OutOfHostMemory)
                        }
                    };
                    device.destroy_device(HOST_CALLBACKS);
                    cleanup(&instance);
                    return Err(error);
                }
            }
        };
        let debug_device =
            has_debug_utils.then(|| ash::ext::debug_utils::Device::new(&instance, &device));
        log::info!(
            "device: {} ({:?}), driver {}",
            info.name,
            info.kind,
            info.driver
        );
        let pipelines = PipelineStore::new(&device, &props);
        let memory = MemoryHeaps::new(&unsafe {
            instance.get_physical_device_memory_properties(physical_device)
        });
        Ok(Arc::new(Context {
            entry,
            instance,
            physical_device,
            device,
            queue,
            queue_family,
            timestamp_period: props.limits.timestamp_period as f64,
            timestamp_valid_bits,
            limits: props.limits,
            memory,
            sync_validation,
            info,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            debug_instance,
            debug_device,
            messenger,
            counters,
            command_pool,
            pipelines,
            frame_serial: std::sync::atomic::AtomicU64::new(0),
            frames_pending: std::sync::atomic::AtomicUsize::new(0),
            destroyed: false,
        }))
    }

    pub fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        self.allocator
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    pub fn validation_counts(&self) -> ValidationCounts {
        ValidationCounts {
            errors: self.counters.errors.load(Ordering::SeqCst),
            warnings: self.counters.warnings.load(Ordering::SeqCst),
        }
    }

    /// The first validation error messages (at most 16).
    pub fn validation_errors(&self) -> Vec<String> {
        self.counters
            .first_errors
            .lock()
            .map(|v| v.clone())
            .unwrap_or_default()
    }

    /// True when the device is a CPU implementation (lavapipe), whose timestamps
    /// do not measure compute dispatches (GUIDE §8).
    pub fn is_cpu(&self) -> bool {
        self.info.kind == vk::PhysicalDeviceType::CPU
    }

    /// Opens a debug-utils label region (visible in RenderDoc and validation messages).
    pub fn begin_label(&self, cmd: vk::CommandBuffer, name: &str) {
        if let Some(d) = &self.debug_device {
            let name = std::ffi::CString::new(name).unwrap_or_default();
            let label = vk::DebugUtilsLabelEXT::default().label_name(&name);
            unsafe { d.cmd_begin_debug_utils_label(cmd, &label) };
        }
    }

    pub fn end_label(&self, cmd: vk::CommandBuffer) {
        if let Some(d) = &self.debug_device {
            unsafe { d.cmd_end_debug_utils_label(cmd) };
        }
    }

    /// Names a Vulkan object for validation messages and captures.
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(d) = &self.debug_device {
            let name = std::ffi::CString::new(name).unwrap_or_default();
            let info = vk::DebugUtilsObjectNameInfoEXT::default()
                .object_handle(handle)
                .object_name(&name);
            let _ = unsafe { d.set_debug_utils_object_name(&info) };
        }
    }

    pub fn allocate_command_buffer(&self) -> VkResult<vk::CommandBuffer> {
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        Ok(unsafe { self.device.allocate_command_buffers(&info) }?[0])
    }

    pub fn free_command_buffer(&self, cmd: vk::CommandBuffer) {
        unsafe { self.device.free_command_buffers(self.command_pool, &[cmd]) };
    }

    /// Records `record` into a fresh command buffer, submits it and waits for
    /// it to finish: the synchronisation point of headless rendering, after
    /// which the host may read results and drop what the commands used.
    pub fn submit_and_wait<R>(&self, record: impl FnOnce(vk::CommandBuffer) -> R) -> VkResult<R> {
        let cmd = self.allocate_command_buffer()?;
        let result = (|| {
            unsafe {
                self.device.begin_command_buffer(
                    cmd,
                    &vk::CommandBufferBeginInfo::default()
                        .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )?
            };
            let r = record(cmd);
            unsafe { self.device.end_command_buffer(cmd)? };
            let fence = unsafe {
                self.device
                    .create_fence(&vk::FenceCreateInfo::default(), None)
            }?;
            let cmd_infos = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
            let submit = vk::SubmitInfo2::default().command_buffer_infos(&cmd_infos);
            let waited = unsafe {
                self.device
                    .queue_submit2(self.queue, &[submit], fence)
                    .and_then(|_| self.device.wait_for_fences(&[fence], true, u64::MAX))
            }
            .and_then(|_| fault::queue_op());
            unsafe { self.device.destroy_fence(fence, None) };
            waited?;
            Ok(r)
        })();
        self.free_command_buffer(cmd);
        result
    }

    /// Device memory in use now, from gpu-allocator's report.
    pub fn memory_report(&self) -> MemoryReport {
        let report = self.allocator().generate_report();
        MemoryReport {
            allocated: report.total_allocated_bytes,
            capacity: report.total_capacity_bytes,
            allocations: report.allocations.len(),
        }
    }

    /// The pipeline store: reuse across rebuilds, counts, the disk cache.
    pub fn pipelines(&self) -> &PipelineStore {
        &self.pipelines
    }

    pub fn wait_idle(&self) {
        let _ = unsafe { self.device.device_wait_idle() };
    }
}

impl Context {
    /// Ends the context explicitly: fails if anything still holds it (a
    /// leaked resource keeps its `Arc<Context>`, which would otherwise keep
    /// the device alive silently), then destroys the device while the
    /// messenger still listens, so the validation layer's report of leaked
    /// objects is counted. Returns the final validation counts.
    pub fn shutdown(ctx: Arc<Context>) -> VkResult<ValidationCounts> {
        let mut ctx =
            Arc::try_unwrap(ctx).map_err(|still| VkError::Leaked(Arc::strong_count(&still) - 1))?;
        ctx.destroy();
        Ok(ctx.validation_counts())
    }

    fn destroy(&mut self) {
        if self.destroyed {
            return;
        }
        self.destroyed = true;
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_command_pool(self.command_pool, None);
            // The kept pipelines and the cache are made on the device.
            self.pipelines.destroy();
            // The allocator frees its memory blocks; it must go before the device.
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(HOST_CALLBACKS);
            if let Some(d) = &self.debug_instance {
                d.destroy_debug_utils_messenger(self.messenger, None);
            }
            self.instance.destroy_instance(HOST_CALLBACKS);
        }
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        self.destroy();
    }
}
