//! Instance, device, queue, debug messenger and the memory allocator, owned by one `Context`
//! that frees them in reverse order of creation.

use super::{Check, VkError, VkResult};
use ash::{ext, vk};
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use gpu_allocator::AllocatorDebugSettings;
use std::ffi::{c_void, CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// What the caller asks of the context.
#[derive(Clone, Debug, Default)]
pub struct ContextDesc {
    /// Enable VK_LAYER_KHRONOS_validation with synchronization validation.
    pub validate: bool,
    /// Pick the device whose name contains this (case-insensitive).
    pub device: Option<String>,
    /// Extra instance extensions (e.g. the window system's surface extensions).
    pub instance_extensions: Vec<CString>,
    /// Extra device extensions (e.g. VK_KHR_swapchain).
    pub device_extensions: Vec<CString>,
    /// Refuse allocations that would take the bytes in use past this, as a device out of
    /// memory would (`--memory-budget`: a share of a machine, or running out on purpose).
    pub memory_budget: Option<u64>,
    /// Testing only: the submission after this many fails as on a lost device
    /// (VOXGI_TEST_LOSE_DEVICE_AFTER, since lavapipe cannot lose its device).
    pub lose_device_after: Option<u32>,
}

/// Validation messages seen by the debug messenger.
#[derive(Default, Debug)]
pub struct MessageStats {
    pub errors: AtomicUsize,
    pub warnings: AtomicUsize,
    /// Every counted message, as printed.
    pub log: Mutex<Vec<String>>,
    /// The pass being recorded, named in messages the layer reports while recording.
    pub recording: Mutex<Option<String>>,
}

impl MessageStats {
    /// Validation errors and warnings seen so far.
    pub fn count(&self) -> usize {
        self.errors.load(Ordering::SeqCst) + self.warnings.load(Ordering::SeqCst)
    }
    pub fn messages(&self) -> Vec<String> {
        self.log.lock().unwrap().clone()
    }
}

/// The device the context runs on, for `voxgi info` and error messages.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    pub api_version: u32,
    pub driver: String,
}

impl std::fmt::Display for DeviceInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match self.kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
            vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
            vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
            vk::PhysicalDeviceType::CPU => "CPU",
            _ => "other",
        };
        write!(
            f,
            "{} ({kind}, Vulkan {}.{}.{}, {})",
            self.name,
            vk::api_version_major(self.api_version),
            vk::api_version_minor(self.api_version),
            vk::api_version_patch(self.api_version),
            self.driver
        )
    }
}

pub struct Context {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    debug_instance: Option<ext::debug_utils::Instance>,
    messenger: vk::DebugUtilsMessengerEXT,
    /// Owned by the messenger callback; freed after the messenger.
    stats_ptr: *const MessageStats,
    pub stats: Arc<MessageStats>,
    pub physical_device: vk::PhysicalDevice,
    pub device_info: DeviceInfo,
    pub properties: vk::PhysicalDeviceProperties,
    /// The largest single allocation (VkPhysicalDeviceMaintenance3Properties).
    pub max_allocation: u64,
    pub device: ash::Device,
    /// Labels and object names; None where VK_EXT_debug_utils is absent.
    pub debug_device: Option<ext::debug_utils::Device>,
    pub queue_family: u32,
    pub queue: vk::Queue,
    pub timestamp_valid_bits: u32,
    pub validating: bool,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    memory_budget: Option<u64>,
    /// Submissions left before a simulated device loss (ContextDesc::lose_device_after).
    submits_left: Mutex<Option<u32>>,
    /// Command pool of the one-shot helper.
    one_shot_pool: vk::CommandPool,
}

// The raw pointer is only read by the messenger callback, which the driver may call from any
// thread; MessageStats is itself Sync.
unsafe impl Send for Context {}
unsafe impl Sync for Context {}

/// A validation message or a leak: through the logger as an error when one is installed
/// (the command line's), else straight to stderr (tests and library users see it either way).
fn report_error(line: &str) {
    if log::max_level() == log::LevelFilter::Off {
        eprintln!("{line}");
    } else {
        log::error!(target: "vulkan", "{line}");
    }
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    ty: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    let stats = &*(user as *const MessageStats);
    let data = &*data;
    let message = data
        .message_as_c_str()
        .map(|m| m.to_string_lossy().into_owned())
        .unwrap_or_default();
    // The innermost command-buffer label is the pass that was recording.
    let mut labels = Vec::new();
    if data.cmd_buf_label_count > 0 && !data.p_cmd_buf_labels.is_null() {
        let slice =
            std::slice::from_raw_parts(data.p_cmd_buf_labels, data.cmd_buf_label_count as usize);
        for l in slice {
            if let Some(name) = l.label_name_as_c_str() {
                labels.push(name.to_string_lossy().into_owned());
            }
        }
    }
    let pass = if !labels.is_empty() {
        format!(" [pass {}]", labels.join(" > "))
    } else if let Some(p) = stats.recording.lock().unwrap().as_ref() {
        format!(" [recording pass {p}]")
    } else {
        String::new()
    };
    let level = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        stats.errors.fetch_add(1, Ordering::SeqCst);
        "error"
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        stats.warnings.fetch_add(1, Ordering::SeqCst);
        "warning"
    } else {
        return vk::FALSE;
    };
    let line = format!("vulkan {level} ({ty:?}){pass}: {message}");
    report_error(&line);
    stats.log.lock().unwrap().push(line);
    vk::FALSE
}

fn device_name(props: &vk::PhysicalDeviceProperties) -> String {
    props
        .device_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "unnamed device".into())
}

fn device_rank(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Formats and the usages the renderer needs of them.
const REQUIRED_FORMATS: &[(vk::Format, vk::FormatFeatureFlags, &str)] = &[
    (
        vk::Format::R32_UINT,
        vk::FormatFeatureFlags::STORAGE_IMAGE_ATOMIC,
        "R32_UINT storage-image atomics",
    ),
    (
        vk::Format::R32G32B32A32_SFLOAT,
        vk::FormatFeatureFlags::from_raw(
            vk::FormatFeatureFlags::COLOR_ATTACHMENT.as_raw()
                | vk::FormatFeatureFlags::STORAGE_IMAGE.as_raw()
                | vk::FormatFeatureFlags::SAMPLED_IMAGE.as_raw(),
        ),
        "R32G32B32A32_SFLOAT colour attachment + storage + sampled",
    ),
    (
        vk::Format::R16G16B16A16_SFLOAT,
        vk::FormatFeatureFlags::from_raw(
            vk::FormatFeatureFlags::COLOR_ATTACHMENT.as_raw()
                | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR.as_raw()
                | vk::FormatFeatureFlags::STORAGE_IMAGE.as_raw(),
        ),
        "R16G16B16A16_SFLOAT colour attachment + linear filtering + storage",
    ),
    (
        vk::Format::D32_SFLOAT,
        vk::FormatFeatureFlags::from_raw(
            vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT.as_raw()
                | vk::FormatFeatureFlags::SAMPLED_IMAGE.as_raw(),
        ),
        "D32_SFLOAT depth attachment + sampled",
    ),
    (
        vk::Format::R8G8B8A8_SRGB,
        vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR,
        "R8G8B8A8_SRGB linear filtering",
    ),
    (
        vk::Format::R8G8B8A8_UNORM,
        vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR,
        "R8G8B8A8_UNORM linear filtering",
    ),
];

/// The largest uniform block the shaders declare.
pub const UNIFORM_BLOCK_BYTES: u32 = 65536;

/// Lists what the device lacks of the renderer's needs (empty when it has everything).
fn missing_requirements(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    props: &vk::PhysicalDeviceProperties,
    needed_extensions: &[CString],
) -> Vec<String> {
    let mut missing = Vec::new();
    if props.api_version < vk::API_VERSION_1_3 {
        missing.push(format!(
            "Vulkan 1.3 (it has {}.{})",
            vk::api_version_major(props.api_version),
            vk::api_version_minor(props.api_version)
        ));
        return missing;
    }
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut f13)
        .push_next(&mut f12);
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let f = f2.features;
    let checks = [
        (f.geometry_shader, "geometryShader"),
        (f.fragment_stores_and_atomics, "fragmentStoresAndAtomics"),
        (f.sampler_anisotropy, "samplerAnisotropy"),
        (f.depth_clamp, "depthClamp"),
        (f13.dynamic_rendering, "dynamicRendering"),
        (f13.synchronization2, "synchronization2"),
        (f12.host_query_reset, "hostQueryReset"),
        (f12.scalar_block_layout, "scalarBlockLayout"),
        (f12.buffer_device_address, "bufferDeviceAddress"),
    ];
    for (have, name) in checks {
        if have == vk::FALSE {
            missing.push(format!("the {name} feature"));
        }
    }
    // The shadow views' uniform block (glsl/common.glsl: MAX_SHADOW_VIEWS); desktop GPUs and
    // lavapipe allow 64 KiB or more, the specification's minimum is 16.
    if props.limits.max_uniform_buffer_range < UNIFORM_BLOCK_BYTES {
        missing.push(format!(
            "a maxUniformBufferRange of {UNIFORM_BLOCK_BYTES} bytes (it has {})",
            props.limits.max_uniform_buffer_range
        ));
    }
    for &(format, usage, what) in REQUIRED_FORMATS {
        let fp = unsafe { instance.get_physical_device_format_properties(pd, format) };
        if !fp.optimal_tiling_features.contains(usage) {
            missing.push(what.to_string());
        }
    }
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    for need in needed_extensions {
        if !exts
            .iter()
            .any(|e| e.extension_name_as_c_str().ok() == Some(need.as_c_str()))
        {
            missing.push(format!("the {} extension", need.to_string_lossy()));
        }
    }
    missing
}

/// The physical device chosen and what the context keeps of it.
struct Chosen {
    physical_device: vk::PhysicalDevice,
    properties: vk::PhysicalDeviceProperties,
    queue_family: u32,
    timestamp_valid_bits: u32,
}

/// The instance, with the validation layer (and synchronization validation) when asked, and
/// whether VK_EXT_debug_utils is on.
fn create_instance(entry: &ash::Entry, desc: &ContextDesc) -> VkResult<(ash::Instance, bool)> {
    let layers = unsafe { entry.enumerate_instance_layer_properties() }.unwrap_or_default();
    let has_validation = layers
        .iter()
        .any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER));
    if desc.validate && !has_validation {
        return Err(VkError::NoValidationLayer);
    }
    let inst_exts =
        unsafe { entry.enumerate_instance_extension_properties(None) }.unwrap_or_default();
    let has_debug_utils = inst_exts
        .iter()
        .any(|e| e.extension_name_as_c_str().ok() == Some(ext::debug_utils::NAME));

    let mut ext_names: Vec<*const i8> = desc
        .instance_extensions
        .iter()
        .map(|e| e.as_ptr())
        .collect();
    if has_debug_utils {
        ext_names.push(ext::debug_utils::NAME.as_ptr());
    }
    let layer_names: Vec<*const i8> = if desc.validate {
        vec![VALIDATION_LAYER.as_ptr()]
    } else {
        vec![]
    };
    let app_info = vk::ApplicationInfo::default()
        .application_name(c"voxgi")
        .engine_name(c"voxgi")
        .api_version(vk::API_VERSION_1_3);
    let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut validation_features =
        vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app_info)
        .enabled_extension_names(&ext_names)
        .enabled_layer_names(&layer_names);
    if desc.validate {
        info = info.push_next(&mut validation_features);
    }
    let instance = unsafe { entry.create_instance(&info, None) }.check("vkCreateInstance")?;
    Ok((instance, has_debug_utils))
}

/// The messenger that counts and prints validation messages into `stats` (none without
/// VK_EXT_debug_utils).
fn create_messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
    has_debug_utils: bool,
    stats: *const MessageStats,
) -> VkResult<(
    Option<ext::debug_utils::Instance>,
    vk::DebugUtilsMessengerEXT,
)> {
    if !has_debug_utils {
        return Ok((None, vk::DebugUtilsMessengerEXT::null()));
    }
    let di = ext::debug_utils::Instance::new(entry, instance);
    let minfo = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(stats as *mut c_void);
    let m = unsafe { di.create_debug_utils_messenger(&minfo, None) }
        .check("vkCreateDebugUtilsMessengerEXT")?;
    Ok((Some(di), m))
}

/// The device named by `desc.device` (or any), a GPU before a CPU implementation, that has
/// everything the renderer needs; otherwise an error naming what the best one lacks.
fn choose_physical_device(instance: &ash::Instance, desc: &ContextDesc) -> VkResult<Chosen> {
    let pds = match unsafe { instance.enumerate_physical_devices() } {
        Ok(p) if !p.is_empty() => p,
        Ok(_) => {
            return Err(VkError::NoDevice(
                "the Vulkan loader found no device (is mesa-vulkan-drivers installed?)".into(),
            ))
        }
        Err(r) => {
            return Err(VkError::Call {
                call: "vkEnumeratePhysicalDevices",
                result: r,
            })
        }
    };
    let mut candidates: Vec<(vk::PhysicalDevice, vk::PhysicalDeviceProperties)> = pds
        .iter()
        .map(|&pd| (pd, unsafe { instance.get_physical_device_properties(pd) }))
        .collect();
    if let Some(want) = &desc.device {
        let want_l = want.to_lowercase();
        let names: Vec<String> = candidates.iter().map(|(_, p)| device_name(p)).collect();
        candidates.retain(|(_, p)| device_name(p).to_lowercase().contains(&want_l));
        if candidates.is_empty() {
            return Err(VkError::NoDevice(format!(
                "no device name contains {want:?}; the devices are: {}",
                names.join(", ")
            )));
        }
    }
    // Prefer a real GPU over a CPU implementation.
    candidates.sort_by_key(|(_, p)| device_rank(p.device_type));

    let mut rejected = Vec::new();
    for (pd, props) in &candidates {
        let missing = missing_requirements(instance, *pd, props, &desc.device_extensions);
        let families = unsafe { instance.get_physical_device_queue_family_properties(*pd) };
        let family = families.iter().position(|q| {
            q.queue_flags
                .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)
        });
        match (missing.is_empty(), family) {
            (true, Some(fam)) => {
                return Ok(Chosen {
                    physical_device: *pd,
                    properties: *props,
                    queue_family: fam as u32,
                    timestamp_valid_bits: families[fam].timestamp_valid_bits,
                })
            }
            (_, None) => rejected.push((device_name(props), "a graphics+compute queue".into())),
            (false, _) => rejected.push((device_name(props), missing.join(", "))),
        }
    }
    let (device, missing) = rejected.remove(0);
    Err(VkError::Missing { device, missing })
}

/// The driver's name and version, and the largest single allocation.
fn driver_and_max_allocation(instance: &ash::Instance, pd: vk::PhysicalDevice) -> (String, u64) {
    let mut drv = vk::PhysicalDeviceDriverProperties::default();
    let mut m3 = vk::PhysicalDeviceMaintenance3Properties::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut drv)
        .push_next(&mut m3);
    unsafe { instance.get_physical_device_properties2(pd, &mut p2) };
    let name = drv
        .driver_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let info = drv
        .driver_info_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    (
        format!("{name} {info}").trim().to_string(),
        m3.max_memory_allocation_size,
    )
}

/// The logical device with the features the passes use and one graphics+compute queue.
fn create_logical_device(
    instance: &ash::Instance,
    chosen: &Chosen,
    extensions: &[CString],
) -> VkResult<ash::Device> {
    let priorities = [1.0f32];
    let queue_infos = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(chosen.queue_family)
        .queue_priorities(&priorities)];
    let features = vk::PhysicalDeviceFeatures::default()
        .geometry_shader(true)
        .fragment_stores_and_atomics(true)
        .sampler_anisotropy(true)
        .depth_clamp(true);
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
        .host_query_reset(true)
        .scalar_block_layout(true)
        .buffer_device_address(true);
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(true)
        .synchronization2(true);
    let dev_ext_ptrs: Vec<*const i8> = extensions.iter().map(|e| e.as_ptr()).collect();
    let dinfo = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_infos)
        .enabled_features(&features)
        .enabled_extension_names(&dev_ext_ptrs)
        .push_next(&mut f12)
        .push_next(&mut f13);
    unsafe { instance.create_device(chosen.physical_device, &dinfo, None) }.check("vkCreateDevice")
}

/// The GPU allocator (leaks are reported by Context::drop, not by it).
fn create_allocator(
    instance: &ash::Instance,
    device: &ash::Device,
    physical_device: vk::PhysicalDevice,
) -> VkResult<Allocator> {
    Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device,
        debug_settings: AllocatorDebugSettings {
            log_leaks_on_shutdown: false,
            ..Default::default()
        },
        // The voxel sums are reached by address (glsl/voxel_common.glsl).
        buffer_device_address: true,
        allocation_sizes: Default::default(),
    })
    .map_err(|e| VkError::Alloc {
        name: "allocator".into(),
        size: 0,
        in_use: 0,
        budget: None,
        error: e,
    })
}

/// The command pool of the one-shot helper.
fn create_one_shot_pool(device: &ash::Device, queue_family: u32) -> VkResult<vk::CommandPool> {
    let pool_info = vk::CommandPoolCreateInfo::default()
        .queue_family_index(queue_family)
        .flags(vk::CommandPoolCreateFlags::TRANSIENT);
    unsafe { device.create_command_pool(&pool_info, None) }.check("vkCreateCommandPool")
}

impl Context {
    /// The instance, the messenger, the device and its queue, the allocator and the one-shot
    /// command pool, in that order; a step that fails frees the ones before it.
    pub fn new(desc: &ContextDesc) -> VkResult<Arc<Context>> {
        let entry = unsafe { ash::Entry::load() }.map_err(|e| VkError::Loader(e.to_string()))?;
        let (instance, has_debug_utils) = create_instance(&entry, desc)?;
        let stats = Arc::new(MessageStats::default());
        let stats_ptr = Arc::into_raw(stats.clone());
        let (debug_instance, messenger) =
            match create_messenger(&entry, &instance, has_debug_utils, stats_ptr) {
                Ok(m) => m,
                Err(e) => {
                    unsafe {
                        drop(Arc::from_raw(stats_ptr));
                        instance.destroy_instance(None);
                    }
                    return Err(e);
                }
            };
        // From here on, a failure frees what was made.
        let fail = |e: VkError| -> VkError {
            unsafe {
                if let Some(di) = &debug_instance {
                    di.destroy_debug_utils_messenger(messenger, None);
                }
                drop(Arc::from_raw(stats_ptr));
                instance.destroy_instance(None);
            }
            e
        };
        let chosen = choose_physical_device(&instance, desc).map_err(fail)?;
        let (driver, max_allocation) = driver_and_max_allocation(&instance, chosen.physical_device);
        let device_info = DeviceInfo {
            name: device_name(&chosen.properties),
            kind: chosen.properties.device_type,
            api_version: chosen.properties.api_version,
            driver,
        };
        let device =
            create_logical_device(&instance, &chosen, &desc.device_extensions).map_err(fail)?;
        let allocator = match create_allocator(&instance, &device, chosen.physical_device) {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_device(None) };
                return Err(fail(e));
            }
        };
        let one_shot_pool = match create_one_shot_pool(&device, chosen.queue_family) {
            Ok(p) => p,
            Err(e) => {
                drop(allocator);
                unsafe { device.destroy_device(None) };
                return Err(fail(e));
            }
        };
        let queue = unsafe { device.get_device_queue(chosen.queue_family, 0) };
        let debug_device = debug_instance
            .as_ref()
            .map(|_| ext::debug_utils::Device::new(&instance, &device));

        Ok(Arc::new(Context {
            entry,
            instance,
            debug_instance,
            messenger,
            stats_ptr,
            stats,
            physical_device: chosen.physical_device,
            device_info,
            properties: chosen.properties,
            max_allocation,
            device,
            debug_device,
            queue_family: chosen.queue_family,
            queue,
            timestamp_valid_bits: chosen.timestamp_valid_bits,
            validating: desc.validate,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            memory_budget: desc.memory_budget,
            submits_left: Mutex::new(desc.lose_device_after),
            one_shot_pool,
        }))
    }

    pub fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap()
    }

    /// Allocates device memory for a resource named `desc.name`, within the memory budget.
    pub fn allocate(
        &self,
        desc: &gpu_allocator::vulkan::AllocationCreateDesc<'_>,
    ) -> VkResult<gpu_allocator::vulkan::Allocation> {
        let mut allocator = self.allocator();
        // The report lists every allocation by name: made only for a budget or a failure.
        let in_use = |a: &Allocator| a.generate_report().total_allocated_bytes;
        let size = desc.requirements.size;
        let over_budget = self
            .memory_budget
            .is_some_and(|b| in_use(&allocator) + size > b);
        let result = if over_budget {
            Err(gpu_allocator::AllocationError::OutOfMemory)
        } else {
            allocator.allocate(desc)
        };
        let in_use = if result.is_err() {
            in_use(&allocator)
        } else {
            0
        };
        result.map_err(|error| VkError::Alloc {
            name: desc.name.into(),
            size,
            in_use,
            budget: self.memory_budget,
            error,
        })
    }

    /// Gives a Vulkan object a name that validation messages and tools show.
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(dd) = &self.debug_device {
            let cname = CString::new(name.replace('\0', " ")).unwrap();
            let info = vk::DebugUtilsObjectNameInfoEXT::default()
                .object_handle(handle)
                .object_name(&cname);
            unsafe {
                let _ = dd.set_debug_utils_object_name(&info);
            }
        }
    }

    /// Records commands into a fresh command buffer, submits it and waits for it.
    pub fn one_shot<R>(&self, record: impl FnOnce(vk::CommandBuffer) -> R) -> VkResult<R> {
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.one_shot_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd = unsafe { self.device.allocate_command_buffers(&info) }
            .check("vkAllocateCommandBuffers")?[0];
        let result = (|| {
            let begin = vk::CommandBufferBeginInfo::default()
                .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            unsafe { self.device.begin_command_buffer(cmd, &begin) }
                .check("vkBeginCommandBuffer")?;
            let r = record(cmd);
            unsafe { self.device.end_command_buffer(cmd) }.check("vkEndCommandBuffer")?;
            self.submit_and_wait(cmd)?;
            Ok(r)
        })();
        unsafe { self.device.free_command_buffers(self.one_shot_pool, &[cmd]) };
        result
    }

    /// Submits one command buffer and blocks until the GPU has finished it.
    pub fn submit_and_wait(&self, cmd: vk::CommandBuffer) -> VkResult<()> {
        self.submit_and_wait_with(cmd, &[], &[])
    }

    /// Submits `cmd` after `waits` (e.g. a swapchain image's acquire), signalling `signals`
    /// (e.g. its present), and waits for it on the host.
    pub fn submit_and_wait_with(
        &self,
        cmd: vk::CommandBuffer,
        waits: &[vk::SemaphoreSubmitInfo],
        signals: &[vk::SemaphoreSubmitInfo],
    ) -> VkResult<()> {
        let fence = unsafe {
            self.device
                .create_fence(&vk::FenceCreateInfo::default(), None)
        }
        .check("vkCreateFence")?;
        if let Some(left) = self.submits_left.lock().unwrap().as_mut() {
            if *left == 0 {
                unsafe { self.device.destroy_fence(fence, None) };
                return Err(VkError::DeviceLost {
                    call: "vkQueueSubmit2",
                });
            }
            *left -= 1;
        }
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = vk::SubmitInfo2::default()
            .command_buffer_infos(&cmds)
            .wait_semaphore_infos(waits)
            .signal_semaphore_infos(signals);
        let r = unsafe {
            self.device
                .queue_submit2(self.queue, &[submit], fence)
                .check("vkQueueSubmit2")
                .and_then(|_| {
                    self.device
                        .wait_for_fences(&[fence], true, u64::MAX)
                        .check("vkWaitForFences")
                })
        };
        unsafe { self.device.destroy_fence(fence, None) };
        r
    }

    /// Bytes the allocator has handed out and not yet taken back.
    pub fn allocated_bytes(&self) -> u64 {
        self.allocator().generate_report().total_allocated_bytes
    }

    /// Names of the allocations still alive (a leak report when called at shutdown).
    pub fn live_allocations(&self) -> Vec<String> {
        self.allocator()
            .generate_report()
            .allocations
            .into_iter()
            .map(|a| format!("{} ({} bytes)", a.name, a.size))
            .collect()
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_command_pool(self.one_shot_pool, None);
            let leaks = self.live_allocations();
            if !leaks.is_empty() {
                // Counted as an error so that tests fail on leaks.
                let line = format!("GPU memory leaked at shutdown: {}", leaks.join(", "));
                report_error(&line);
                self.stats.errors.fetch_add(1, Ordering::SeqCst);
                self.stats.log.lock().unwrap().push(line);
            }
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some(di) = &self.debug_instance {
                di.destroy_debug_utils_messenger(self.messenger, None);
            }
            drop(Arc::from_raw(self.stats_ptr));
            self.instance.destroy_instance(None);
        }
    }
}
