//! The Vulkan loader, the instance and (when asked) the validation layer's messenger.

use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

use ash::vk;

use super::super::RenderError;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Messages the validation layer reported, shared with its callback.
type MessageLog = Mutex<Vec<String>>;

/// The validation layer's warnings and errors. A handle outlives the renderer, so problems
/// reported while Vulkan objects are destroyed (leaks, wrong order) are read too.
#[derive(Clone, Debug, Default)]
pub struct ValidationLog(Arc<MessageLog>);

impl ValidationLog {
    /// The messages reported since the last call.
    pub fn take(&self) -> Vec<String> {
        std::mem::take(&mut *self.0.lock().unwrap_or_else(|p| p.into_inner()))
    }
}

/// The loaded Vulkan library and an instance on it.
///
/// Owns the instance and the debug messenger; `Drop` destroys the messenger, then the
/// instance. Devices hold an `Arc<Instance>` so that it outlives them.
pub(crate) struct Instance {
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// The instance function table.
    pub(crate) raw: ash::Instance,
    /// The callback's user data points into this; dropped after the messenger.
    messages: ValidationLog,
    /// The loader; must outlive `raw`.
    pub(crate) entry: ash::Entry,
}

impl std::fmt::Debug for Instance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Instance").field("validation", &self.debug.is_some()).finish_non_exhaustive()
    }
}

/// Loads the Vulkan loader, with a sentence that says what to install when it is missing.
pub(crate) fn load_entry() -> Result<ash::Entry, RenderError> {
    // SAFETY: loading the system's Vulkan loader runs its initialisers; nothing else in this
    // process loads or unloads it concurrently.
    unsafe { ash::Entry::load() }.map_err(|e| RenderError::NoLoader(e.to_string()))
}

impl Instance {
    /// Creates a Vulkan 1.1 instance; with `validation`, enables the Khronos validation layer
    /// and records its warnings and errors (read them with [`Instance::take_messages`]).
    /// `window_extensions` are the surface extensions a window needs (none offscreen).
    pub(crate) fn new(
        validation: bool,
        window_extensions: &[*const std::ffi::c_char],
    ) -> Result<Self, RenderError> {
        Self::create_with(validation, window_extensions, |entry, create| {
            // SAFETY: every pointer in `create` refers to data that lives across the call.
            unsafe { entry.create_instance(create, None) }
                .map(|i| i.handle())
                .map_err(RenderError::vk("vkCreateInstance"))
        })
    }

    /// As [`Instance::new`], with the instance made by `create` from Argile's create info
    /// (an OpenXR runtime makes it through `xrCreateVulkanInstanceKHR`, adding what it needs).
    /// The instance belongs to this value all the same: `Drop` destroys it.
    pub(crate) fn create_with(
        validation: bool,
        window_extensions: &[*const std::ffi::c_char],
        create_instance: impl FnOnce(
            &ash::Entry,
            &vk::InstanceCreateInfo<'_>,
        ) -> Result<vk::Instance, RenderError>,
    ) -> Result<Self, RenderError> {
        let entry = load_entry()?;
        // SAFETY: a plain query on a loaded entry.
        let version = unsafe { entry.try_enumerate_instance_version() }
            .map_err(RenderError::vk("vkEnumerateInstanceVersion"))?
            .unwrap_or(vk::API_VERSION_1_0);
        if version < vk::API_VERSION_1_1 {
            return Err(RenderError::Unsupported(format!(
                "the Vulkan loader offers only Vulkan {}; Argile needs 1.1 (update libvulkan1)",
                version_string(version)
            )));
        }
        let mut layers = Vec::new();
        let mut extensions = window_extensions.to_vec();
        if validation {
            // SAFETY: a plain query on a loaded entry.
            let available = unsafe { entry.enumerate_instance_layer_properties() }
                .map_err(RenderError::vk("vkEnumerateInstanceLayerProperties"))?;
            if !available.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER)) {
                return Err(RenderError::Unsupported(
                    "the Vulkan validation layer VK_LAYER_KHRONOS_validation is not installed \
                     (Debian package vulkan-validationlayers; scripts/setup test installs it)"
                        .into(),
                ));
            }
            layers.push(VALIDATION_LAYER.as_ptr());
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let messages = ValidationLog::default();
        let app = vk::ApplicationInfo::default()
            .application_name(c"argile")
            .application_version(vk::make_api_version(0, 0, 1, 0))
            .engine_name(c"argile")
            .api_version(vk::API_VERSION_1_1);
        let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
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
            .pfn_user_callback(Some(on_debug_message))
            .user_data(Arc::as_ptr(&messages.0).cast_mut().cast());
        let mut create = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validation {
            // Also reports problems in vkCreateInstance/vkDestroyInstance themselves.
            create = create.push_next(&mut messenger_info);
        }
        // The user-data pointer refers to the shared log, which the instance keeps until after
        // the messenger and the instance are destroyed.
        let handle = create_instance(&entry, &create)?;
        // SAFETY: `handle` is a live instance just created from this entry's loader.
        let raw = unsafe { ash::Instance::load(entry.static_fn(), handle) };
        let debug = if validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &raw);
            // SAFETY: as above; the messenger is destroyed in Drop before the instance.
            match unsafe { loader.create_debug_utils_messenger(&messenger_info, None) } {
                Ok(m) => Some((loader, m)),
                Err(e) => {
                    // SAFETY: nothing was created from `raw` yet.
                    unsafe { raw.destroy_instance(None) };
                    return Err(RenderError::vk("vkCreateDebugUtilsMessengerEXT")(e));
                }
            }
        } else {
            None
        };
        Ok(Self { debug, raw, messages, entry })
    }

    /// Whether the validation layer is on.
    pub(crate) fn validation(&self) -> bool {
        self.debug.is_some()
    }

    /// The validation layer's log (empty for good when the layer is off).
    pub(crate) fn validation_log(&self) -> ValidationLog {
        self.messages.clone()
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: devices hold an Arc to this instance, so none is left; the messenger was
        // created from this instance and is destroyed before it.
        unsafe {
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.raw.destroy_instance(None);
        }
    }
}

/// `major.minor.patch` of a packed Vulkan version.
pub(crate) fn version_string(v: u32) -> String {
    format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v))
}

/// The messenger's callback: validation warnings and errors go to the log (and fail tests);
/// everything else goes to `tracing` at debug level.
unsafe extern "system" fn on_debug_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid callback data whose message, when not null, is a
    // NUL-terminated string valid for the duration of the call.
    let message = unsafe {
        data.as_ref()
            .filter(|d| !d.p_message.is_null())
            .map(|d| CStr::from_ptr(d.p_message).to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let counts = severity.intersects(
        vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
    ) && kind.intersects(
        vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
    );
    if counts {
        tracing::error!("Vulkan validation: {message}");
        // SAFETY: `user` points to the log in the instance's Arc (set in `Instance::new`),
        // which lives until after the messenger is destroyed.
        if let Some(log) = unsafe { user.cast::<MessageLog>().as_ref() } {
            log.lock().unwrap_or_else(|p| p.into_inner()).push(message);
        }
    } else {
        tracing::debug!("Vulkan ({severity:?}, {kind:?}): {message}");
    }
    vk::FALSE
}
