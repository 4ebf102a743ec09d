//! The Vulkan device of the previewer (docs/design.md §3, §8).
//!
//! - The instance asks for Vulkan 1.1 and, where the loader has it, `VK_EXT_debug_utils`, so
//!   that every GPU resource can carry a name ([`Gpu::name`]).
//! - The physical device is the first discrete GPU, else the first integrated one, else any
//!   device with a graphics queue: lavapipe (Mesa's software Vulkan) on a machine without a
//!   GPU, as in CI.
//! - With `WPBGI_VALIDATE=1` the Khronos validation layer is enabled and a messenger collects
//!   its warnings and errors ([`Gpu::validation_messages`]); asking for it where it is not
//!   installed is an error, not a silent run without it.
//! - Every Vulkan call's failure is a typed [`VulkanError`]; no loader or no device is one
//!   sentence that says what to install.

use ash::vk;
use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::Mutex;
use thiserror::Error;

/// What can go wrong setting up or using Vulkan.
/// Why the previewer has no Vulkan device, or what a Vulkan call refused.
#[derive(Debug, Error)]
pub enum VulkanError {
    /// No Vulkan loader library (the loader's own message).
    #[error(
        "no Vulkan loader was found ({0}); install a loader and a driver, e.g. \
         `apt install libvulkan1 mesa-vulkan-drivers` for lavapipe (software Vulkan)"
    )]
    NoLoader(String),
    /// No device with a graphics queue.
    #[error(
        "no Vulkan device with a graphics queue was found; install a driver, e.g. \
         `apt install mesa-vulkan-drivers` for lavapipe (software Vulkan)"
    )]
    NoDevice,
    /// `WPBGI_VALIDATE=1` without the validation layer.
    #[error(
        "WPBGI_VALIDATE=1 asks for the Vulkan validation layer, which is not installed \
         (e.g. `apt install vulkan-validationlayers`)"
    )]
    NoValidationLayer,
    /// A Vulkan call that failed.
    #[error("the Vulkan call {call} failed: {result}")]
    Call {
        /// The call's name.
        call: &'static str,
        /// What it returned.
        result: vk::Result,
    },
}

/// The name of the Khronos validation layer.
const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// A Vulkan call's result with the call's name on failure.
pub(super) fn check<T>(call: &'static str, r: Result<T, vk::Result>) -> Result<T, VulkanError> {
    r.map_err(|result| VulkanError::Call { call, result })
}

/// The device the previewer draws with.
pub struct Gpu {
    /// The device's name and kind, as the driver reports them.
    pub name: String,
    /// See `name`.
    pub kind: vk::PhysicalDeviceType,
    /// The queue family (graphics and compute) and its first queue.
    pub queue_family: u32,
    /// See `queue_family`.
    pub queue: vk::Queue,
    /// The logical device.
    pub device: ash::Device,
    /// The physical device it runs on.
    pub physical: vk::PhysicalDevice,
    /// The Vulkan instance.
    pub instance: ash::Instance,
    naming: Option<ash::ext::debug_utils::Device>,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// The validation layer's messages (boxed: the messenger holds its address).
    messages: Box<Mutex<Vec<String>>>,
    _entry: ash::Entry,
}

/// The validation messenger's callback: keeps warnings and errors in the `Mutex<Vec<String>>`
/// that `user_data` points to.
unsafe extern "system" fn collect(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the loader passes valid callback data for the call's duration, and `user_data`
    // is the `Gpu`'s boxed mutex, which outlives the messenger.
    let (data, messages) = unsafe { (&*data, &*(user_data as *const Mutex<Vec<String>>)) };
    let text = if data.p_message.is_null() {
        String::from("(no message)")
    } else {
        // SAFETY: a non-null message is a NUL-terminated string (Vulkan spec).
        unsafe { CStr::from_ptr(data.p_message) }
            .to_string_lossy()
            .into_owned()
    };
    if let Ok(mut m) = messages.lock() {
        m.push(format!("{severity:?}: {text}"));
    }
    vk::FALSE
}

/// How much a device kind is preferred (lower first).
fn preference(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

impl Gpu {
    /// The device, with validation if the environment has `WPBGI_VALIDATE=1`.
    pub fn from_env() -> Result<Gpu, VulkanError> {
        Gpu::new(std::env::var("WPBGI_VALIDATE").is_ok_and(|v| v == "1"))
    }

    /// Set up Vulkan: instance, the preferred device, one graphics queue; with `validate`, the
    /// validation layer and its messenger.
    pub fn new(validate: bool) -> Result<Gpu, VulkanError> {
        Gpu::with_extensions(validate, &[], &[])
    }

    /// [`Gpu::new`] for a window: the instance extensions of its display's surfaces and the
    /// device's `VK_KHR_swapchain`.
    pub(crate) fn for_window(
        validate: bool,
        display: raw_window_handle::RawDisplayHandle,
    ) -> Result<Gpu, VulkanError> {
        let surface = check(
            "vkEnumerateInstanceExtensionProperties (surface extensions)",
            ash_window::enumerate_required_extensions(display),
        )?;
        Gpu::with_extensions(validate, surface, &[ash::khr::swapchain::NAME.as_ptr()])
    }

    /// The loader's entry points.
    pub(super) fn entry(&self) -> &ash::Entry {
        &self._entry
    }

    fn with_extensions(
        validate: bool,
        instance_extensions: &[*const c_char],
        device_extensions: &[*const c_char],
    ) -> Result<Gpu, VulkanError> {
        // SAFETY: loading the system's Vulkan loader runs its initialisation; nothing else of
        // ours runs meanwhile.
        let entry =
            unsafe { ash::Entry::load() }.map_err(|e| VulkanError::NoLoader(e.to_string()))?;
        // SAFETY: plain queries of the loader.
        let layers = check("vkEnumerateInstanceLayerProperties", unsafe {
            entry.enumerate_instance_layer_properties()
        })?;
        let extensions = check("vkEnumerateInstanceExtensionProperties", unsafe {
            entry.enumerate_instance_extension_properties(None)
        })?;
        let has_layer = layers
            .iter()
            .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
        if validate && !has_layer {
            return Err(VulkanError::NoValidationLayer);
        }
        let debug_utils = extensions
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::debug_utils::NAME));
        let layer_names: Vec<*const c_char> = if validate {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };
        let mut extension_names: Vec<*const c_char> = instance_extensions.to_vec();
        if debug_utils {
            extension_names.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let app = vk::ApplicationInfo::default()
            .application_name(c"wpbgi preview")
            .engine_name(c"wpbgi")
            .api_version(vk::API_VERSION_1_1);
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layer_names)
            .enabled_extension_names(&extension_names);
        // SAFETY: the create info and everything it points to live through the call.
        let instance = match unsafe { entry.create_instance(&info, None) } {
            Ok(i) => i,
            // The loader's answer when it has no driver at all.
            Err(vk::Result::ERROR_INCOMPATIBLE_DRIVER) => return Err(VulkanError::NoDevice),
            Err(result) => {
                return Err(VulkanError::Call {
                    call: "vkCreateInstance",
                    result,
                })
            }
        };
        let messages: Box<Mutex<Vec<String>>> = Box::default();
        let mut gpu_messenger = None;
        if validate && debug_utils {
            let utils = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                        | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(collect))
                .user_data(&*messages as *const Mutex<Vec<String>> as *mut c_void);
            // SAFETY: the callback's user data is the boxed mutex, kept until the messenger is
            // destroyed in `drop`.
            match unsafe { utils.create_debug_utils_messenger(&info, None) } {
                Ok(m) => gpu_messenger = Some((utils, m)),
                Err(result) => {
                    // SAFETY: nothing else was created from the instance yet.
                    unsafe { instance.destroy_instance(None) };
                    return Err(VulkanError::Call {
                        call: "vkCreateDebugUtilsMessengerEXT",
                        result,
                    });
                }
            }
        }
        let destroy =
            |messenger: &Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>| {
                // SAFETY: the messenger and the instance are ours, and nothing uses them after this.
                unsafe {
                    if let Some((utils, m)) = messenger {
                        utils.destroy_debug_utils_messenger(*m, None);
                    }
                    instance.destroy_instance(None);
                }
            };
        let picked = Self::pick(&instance);
        let (physical, queue_family, name, kind) = match picked {
            Ok(Some(p)) => p,
            Ok(None) => {
                destroy(&gpu_messenger);
                return Err(VulkanError::NoDevice);
            }
            Err(e) => {
                destroy(&gpu_messenger);
                return Err(e);
            }
        };
        let priorities = [1.0f32];
        let queue_info = vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities);
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(std::slice::from_ref(&queue_info))
            .enabled_extension_names(device_extensions);
        // SAFETY: the physical device and queue family come from this instance.
        let device = match unsafe { instance.create_device(physical, &device_info, None) } {
            Ok(d) => d,
            Err(result) => {
                destroy(&gpu_messenger);
                return Err(VulkanError::Call {
                    call: "vkCreateDevice",
                    result,
                });
            }
        };
        // SAFETY: queue 0 of a family the device was created with.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let naming = debug_utils.then(|| ash::ext::debug_utils::Device::new(&instance, &device));
        let gpu = Gpu {
            name,
            kind,
            queue_family,
            queue,
            device,
            physical,
            instance,
            naming,
            messenger: gpu_messenger,
            messages,
            _entry: entry,
        };
        gpu.name(gpu.queue, "wpbgi main queue")?;
        Ok(gpu)
    }

    /// The preferred physical device with a graphics queue: its handle, queue family, name and
    /// kind.
    #[allow(clippy::type_complexity)]
    fn pick(
        instance: &ash::Instance,
    ) -> Result<Option<(vk::PhysicalDevice, u32, String, vk::PhysicalDeviceType)>, VulkanError>
    {
        // SAFETY: plain queries of a live instance.
        let devices = check("vkEnumeratePhysicalDevices", unsafe {
            instance.enumerate_physical_devices()
        })?;
        let mut best = None;
        for (index, &pd) in devices.iter().enumerate() {
            // SAFETY: `pd` comes from this instance.
            let (props, families) = unsafe {
                (
                    instance.get_physical_device_properties(pd),
                    instance.get_physical_device_queue_family_properties(pd),
                )
            };
            let Some(family) = families
                .iter()
                .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS))
            else {
                continue;
            };
            let rank = (preference(props.device_type), index);
            let name = props.device_name_as_c_str().map_or_else(
                |_| String::from("(unnamed)"),
                |n| n.to_string_lossy().into_owned(),
            );
            if best.as_ref().is_none_or(|(r, _)| rank < *r) {
                best = Some((rank, (pd, family as u32, name, props.device_type)));
            }
        }
        Ok(best.map(|(_, d)| d))
    }

    /// Give a Vulkan object a name that validation messages and GPU debuggers show (a no-op
    /// where the loader lacks `VK_EXT_debug_utils`).
    pub fn name<H: vk::Handle>(&self, handle: H, name: &str) -> Result<(), VulkanError> {
        let Some(naming) = &self.naming else {
            return Ok(());
        };
        let name = CString::new(name.replace('\0', " ")).unwrap_or_default();
        let info = vk::DebugUtilsObjectNameInfoEXT::default()
            .object_handle(handle)
            .object_name(&name);
        // SAFETY: the handle belongs to this device, and the info lives through the call.
        check("vkSetDebugUtilsObjectNameEXT", unsafe {
            naming.set_debug_utils_object_name(&info)
        })
    }

    /// The validation layer's warnings and errors so far (empty without validation).
    pub fn validation_messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // SAFETY: everything here was created by `Gpu::new` and is destroyed once, children
        // before their parents, after the device is idle.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_device(None);
            if let Some((utils, m)) = &self.messenger {
                utils.destroy_debug_utils_messenger(*m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}
