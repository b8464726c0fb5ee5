//! Argile's OpenXR test runtime: a shared library the Khronos loader loads (through a runtime
//! manifest named by `XR_RUNTIME_JSON`) that simulates a head-mounted display and two
//! controllers from a scripted timeline, so Argile's real OpenXR code path runs in tests
//! without a headset.
//!
//! It implements the loader–runtime interface (`xrNegotiateLoaderRuntimeInterface`) and the
//! OpenXR 1.0 subset Argile uses: instance, system, `XR_KHR_vulkan_enable2` (the runtime creates
//! the application's Vulkan instance and device), sessions and their state machine, reference
//! and action spaces, swapchains of Vulkan images on the application's device, frame timing,
//! views, actions with suggested bindings for eight controller profiles, and haptics. It keeps to
//! the specification's rules: calls out of order, on unknown or destroyed handles, or with
//! wrong structure types are refused with the result a conformant runtime gives, and logged.
//!
//! Environment:
//! - `ARGILE_XR_TEST_SCRIPT`: the timeline (TOML, see [`script`]); without it the headset and
//!   hands hold still.
//! - `ARGILE_XR_TEST_OUT`: a folder for `log.jsonl` (one JSON object a line, each with a
//!   `kind`: `instance`, `state`, `end_frame`, `capture`, `haptic`, `haptic_stop`,
//!   `interaction_profile`, `instance_loss`, `runtime_gone`, `runtime_back`, `violation`,
//!   `refused`, `error`), the captured images `frame-NNNN-left.png` / `frame-NNNN-right.png`,
//!   and `runtime-gone.json` while the scripted runtime is away (instances are refused with
//!   `XR_ERROR_RUNTIME_UNAVAILABLE` until it is back; the loader unloads the runtime with its
//!   last instance, so this is kept on disk).
//! - `ARGILE_XR_TEST_NO_VULKAN=1`: offer no Vulkan extension; `ARGILE_XR_TEST_NO_HMD=1`: no
//!   headset connected (`xrGetSystem` answers `XR_ERROR_FORM_FACTOR_UNAVAILABLE`).
//! - `ARGILE_XR_TEST_VIEW_SIZE=WxH`: the view size the runtime recommends, over the script's
//!   (a real runtime chooses its own, e.g. 320×240 on a headless one).
//!
//! Like real runtimes, it sends a new session's first state event (IDLE) before READY, falls
//! back to `khr/simple_controller` when the application suggested nothing for the simulated
//! controllers' own profile, offers the controller extensions `XR_EXT_hp_mixed_reality_controller`,
//! `XR_BD_controller_interaction` and `XR_META_touch_controller_plus` (their profiles are
//! refused unless the extension is enabled), can pace frames at the display's rate, and can go
//! away mid-frame (`runtime_gone`: calls answer `XR_ERROR_INSTANCE_LOST` without warning).
//!
//! Time is virtual: the frame waited for `k`-th in the instance's life is displayed at
//! `1 s + (k + 1) × period`, and every pose is the script's at the frame a time falls on, so
//! runs are deterministic. Frames are numbered by `xrEndFrame` calls from 0; `state` lines carry
//! the number of frames ended when the state was entered, `haptic` lines the frame in flight.
//! `end_frame` lines carry the first projection layer's views in stage space.

pub mod actions;
pub mod api;
pub mod log;
pub mod profiles;
pub mod script;
pub mod state;
pub mod vk;

use openxr_sys as xr;
use std::ffi::{c_char, CStr};

macro_rules! commands {
    ($($name:literal => $pfn:ident = $f:path),* $(,)?) => {
        /// The OpenXR commands the runtime answers, by name.
        fn command(name: &[u8]) -> Option<xr::pfn::VoidFunction> {
            $(
                if name == $name.as_bytes() {
                    // SAFETY: a function pointer cast to the generic type the loader expects;
                    // the caller casts it back to the command's own type.
                    return Some(unsafe { std::mem::transmute::<xr::pfn::$pfn, xr::pfn::VoidFunction>($f as xr::pfn::$pfn) });
                }
            )*
            None
        }
    };
}

commands! {
    "xrGetInstanceProcAddr" => GetInstanceProcAddr = get_instance_proc_addr,
    "xrEnumerateApiLayerProperties" => EnumerateApiLayerProperties = api::enumerate_api_layer_properties,
    "xrEnumerateInstanceExtensionProperties" => EnumerateInstanceExtensionProperties = api::enumerate_instance_extension_properties,
    "xrCreateInstance" => CreateInstance = api::create_instance,
    "xrDestroyInstance" => DestroyInstance = api::destroy_instance,
    "xrGetInstanceProperties" => GetInstanceProperties = api::get_instance_properties,
    "xrPollEvent" => PollEvent = api::poll_event,
    "xrResultToString" => ResultToString = api::result_to_string,
    "xrStructureTypeToString" => StructureTypeToString = api::structure_type_to_string,
    "xrGetSystem" => GetSystem = api::get_system,
    "xrGetSystemProperties" => GetSystemProperties = api::get_system_properties,
    "xrEnumerateEnvironmentBlendModes" => EnumerateEnvironmentBlendModes = api::enumerate_environment_blend_modes,
    "xrCreateSession" => CreateSession = api::create_session,
    "xrDestroySession" => DestroySession = api::destroy_session,
    "xrEnumerateReferenceSpaces" => EnumerateReferenceSpaces = api::enumerate_reference_spaces,
    "xrCreateReferenceSpace" => CreateReferenceSpace = api::create_reference_space,
    "xrGetReferenceSpaceBoundsRect" => GetReferenceSpaceBoundsRect = api::get_reference_space_bounds_rect,
    "xrCreateActionSpace" => CreateActionSpace = api::create_action_space,
    "xrLocateSpace" => LocateSpace = api::locate_space,
    "xrDestroySpace" => DestroySpace = api::destroy_space,
    "xrEnumerateViewConfigurations" => EnumerateViewConfigurations = api::enumerate_view_configurations,
    "xrGetViewConfigurationProperties" => GetViewConfigurationProperties = api::get_view_configuration_properties,
    "xrEnumerateViewConfigurationViews" => EnumerateViewConfigurationViews = api::enumerate_view_configuration_views,
    "xrEnumerateSwapchainFormats" => EnumerateSwapchainFormats = api::enumerate_swapchain_formats,
    "xrCreateSwapchain" => CreateSwapchain = api::create_swapchain,
    "xrDestroySwapchain" => DestroySwapchain = api::destroy_swapchain,
    "xrEnumerateSwapchainImages" => EnumerateSwapchainImages = api::enumerate_swapchain_images,
    "xrAcquireSwapchainImage" => AcquireSwapchainImage = api::acquire_swapchain_image,
    "xrWaitSwapchainImage" => WaitSwapchainImage = api::wait_swapchain_image,
    "xrReleaseSwapchainImage" => ReleaseSwapchainImage = api::release_swapchain_image,
    "xrBeginSession" => BeginSession = api::begin_session,
    "xrEndSession" => EndSession = api::end_session,
    "xrRequestExitSession" => RequestExitSession = api::request_exit_session,
    "xrWaitFrame" => WaitFrame = api::wait_frame,
    "xrBeginFrame" => BeginFrame = api::begin_frame,
    "xrEndFrame" => EndFrame = api::end_frame,
    "xrLocateViews" => LocateViews = api::locate_views,
    "xrStringToPath" => StringToPath = actions::string_to_path,
    "xrPathToString" => PathToString = actions::path_to_string,
    "xrCreateActionSet" => CreateActionSet = actions::create_action_set,
    "xrDestroyActionSet" => DestroyActionSet = actions::destroy_action_set,
    "xrCreateAction" => CreateAction = actions::create_action,
    "xrDestroyAction" => DestroyAction = actions::destroy_action,
    "xrSuggestInteractionProfileBindings" => SuggestInteractionProfileBindings = actions::suggest_interaction_profile_bindings,
    "xrAttachSessionActionSets" => AttachSessionActionSets = actions::attach_session_action_sets,
    "xrGetCurrentInteractionProfile" => GetCurrentInteractionProfile = actions::get_current_interaction_profile,
    "xrGetActionStateBoolean" => GetActionStateBoolean = actions::get_action_state_boolean,
    "xrGetActionStateFloat" => GetActionStateFloat = actions::get_action_state_float,
    "xrGetActionStateVector2f" => GetActionStateVector2f = actions::get_action_state_vector2f,
    "xrGetActionStatePose" => GetActionStatePose = actions::get_action_state_pose,
    "xrSyncActions" => SyncActions = actions::sync_actions,
    "xrEnumerateBoundSourcesForAction" => EnumerateBoundSourcesForAction = actions::enumerate_bound_sources_for_action,
    "xrGetInputSourceLocalizedName" => GetInputSourceLocalizedName = actions::get_input_source_localized_name,
    "xrApplyHapticFeedback" => ApplyHapticFeedback = actions::apply_haptic_feedback,
    "xrStopHapticFeedback" => StopHapticFeedback = actions::stop_haptic_feedback,
    "xrGetVulkanGraphicsRequirements2KHR" => GetVulkanGraphicsRequirements2KHR = api::get_vulkan_graphics_requirements2,
    "xrCreateVulkanInstanceKHR" => CreateVulkanInstanceKHR = api::create_vulkan_instance,
    "xrCreateVulkanDeviceKHR" => CreateVulkanDeviceKHR = api::create_vulkan_device,
    "xrGetVulkanGraphicsDevice2KHR" => GetVulkanGraphicsDevice2KHR = api::get_vulkan_graphics_device2,
}

/// Commands of XR_KHR_vulkan_enable2, answered only when the instance enabled it.
const VULKAN_COMMANDS: [&[u8]; 4] = [
    b"xrGetVulkanGraphicsRequirements2KHR",
    b"xrCreateVulkanInstanceKHR",
    b"xrCreateVulkanDeviceKHR",
    b"xrGetVulkanGraphicsDevice2KHR",
];

/// Commands callable without an instance.
const GLOBAL_COMMANDS: [&[u8]; 3] =
    [b"xrEnumerateInstanceExtensionProperties", b"xrEnumerateApiLayerProperties", b"xrCreateInstance"];

/// `xrGetInstanceProcAddr`.
///
/// # Safety
/// `name` must be a NUL-terminated string and `function` writable, as OpenXR requires.
pub unsafe extern "system" fn get_instance_proc_addr(
    instance: xr::Instance,
    name: *const c_char,
    function: *mut Option<xr::pfn::VoidFunction>,
) -> xr::Result {
    api::run_global("xrGetInstanceProcAddr", |rt| {
        if function.is_null() || name.is_null() {
            return state::refuse(xr::Result::ERROR_VALIDATION_FAILURE, "name or function is null");
        }
        *function = None;
        let name = CStr::from_ptr(name).to_bytes();
        if instance == xr::Instance::NULL {
            if !GLOBAL_COMMANDS.contains(&name) {
                return state::refuse(
                    xr::Result::ERROR_HANDLE_INVALID,
                    format!("{} needs an instance", String::from_utf8_lossy(name)),
                );
            }
        } else {
            let Some(inst) = rt.instance.as_ref().filter(|i| i.handle == instance.into_raw()) else {
                return state::refuse(
                    xr::Result::ERROR_HANDLE_INVALID,
                    format!("XrInstance {:#x} is not a live instance", instance.into_raw()),
                );
            };
            if VULKAN_COMMANDS.contains(&name) && !inst.vulkan {
                return Ok(xr::Result::ERROR_FUNCTION_UNSUPPORTED);
            }
        }
        match command(name) {
            Some(f) => {
                *function = Some(f);
                Ok(xr::Result::SUCCESS)
            }
            None => Ok(xr::Result::ERROR_FUNCTION_UNSUPPORTED),
        }
    })
}

/// The loader–runtime interface: agrees on interface version 1 and OpenXR 1.0, and hands the
/// loader `xrGetInstanceProcAddr`.
///
/// # Safety
/// Both pointers must be the loader's structures, as the loader interface requires.
#[no_mangle]
pub unsafe extern "system" fn xrNegotiateLoaderRuntimeInterface(
    loader_info: *const xr::loader::XrNegotiateLoaderInfo,
    request: *mut xr::loader::XrNegotiateRuntimeRequest,
) -> xr::Result {
    use xr::loader::{XrNegotiateLoaderInfo as Info, XrNegotiateRuntimeRequest as Request};
    if loader_info.is_null() || request.is_null() {
        return xr::Result::ERROR_INITIALIZATION_FAILED;
    }
    let info = &*loader_info;
    let req = &mut *request;
    let api = xr::Version::new(1, 0, 0);
    let info_ok = info.ty == Info::TYPE
        && info.struct_version == Info::VERSION
        && info.struct_size == size_of::<Info>();
    let req_ok = req.ty == Request::TYPE
        && req.struct_version == Request::VERSION
        && req.struct_size == size_of::<Request>();
    let versions_ok = info.min_interface_version <= xr::loader::CURRENT_LOADER_RUNTIME_VERSION
        && info.max_interface_version >= xr::loader::CURRENT_LOADER_RUNTIME_VERSION
        && info.min_api_version.into_raw() <= api.into_raw()
        && info.max_api_version.into_raw() >= api.into_raw();
    if !(info_ok && req_ok && versions_ok) {
        eprintln!("argile XR test runtime: the loader's negotiation structures or versions do not match interface 1 and OpenXR 1.0");
        return xr::Result::ERROR_INITIALIZATION_FAILED;
    }
    req.runtime_interface_version = xr::loader::CURRENT_LOADER_RUNTIME_VERSION;
    req.runtime_api_version = api;
    req.get_instance_proc_addr = Some(get_instance_proc_addr);
    xr::Result::SUCCESS
}
