//! The OpenXR test runtime (`tests/xr-runtime/`) through the real Khronos loader: negotiation,
//! instance and system, a Vulkan session made through XR_KHR_vulkan_enable2 (lavapipe, the
//! validation layer on) that reaches FOCUSED and submits a cleared two-layer swapchain image
//! which the runtime captures to PNG, scripted actions, haptics and session loss, and the
//! refusal (and logging) of calls a conformant runtime refuses.
//!
//! The loader serves one instance per process and the runtime reads its environment at
//! instance creation, so the tests here run one at a time.

mod common;

use argile_xr_test_runtime::vk::transition;
use ash::vk;
use ash::vk::Handle;
use openxr as xr;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Validation messages the Vulkan debug messenger received.
static VALIDATION: Mutex<Vec<String>> = Mutex::new(Vec::new());

unsafe extern "system" fn on_validation(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _: *mut std::ffi::c_void,
) -> vk::Bool32 {
    if severity.intersects(
        vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
    ) {
        let msg = std::ffi::CStr::from_ptr((*data).p_message).to_string_lossy().into_owned();
        VALIDATION.lock().unwrap_or_else(|p| p.into_inner()).push(msg);
    }
    vk::FALSE
}

fn app_info() -> xr::ApplicationInfo<'static> {
    xr::ApplicationInfo {
        application_name: "argile-xr-runtime-test",
        application_version: 1,
        engine_name: "argile",
        engine_version: 1,
        api_version: xr::Version::new(1, 0, 0),
    }
}

/// A test case's folder with a fresh output folder, the runtime's environment set, and the
/// loader opened.
struct Case {
    out: PathBuf,
    entry: xr::Entry,
    _guard: std::sync::MutexGuard<'static, ()>,
}

impl Case {
    fn new(name: &str, script: &str) -> Case {
        let guard = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
        common::xr::pin_lavapipe();
        let dir = common::out_dir("xr-runtime").join(name);
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("case folder");
        let manifest = common::xr::test_runtime_manifest(&dir);
        let script_path = dir.join("script.toml");
        std::fs::write(&script_path, script).expect("script written");
        let out = dir.join("out");
        std::env::set_var("XR_RUNTIME_JSON", &manifest);
        std::env::set_var("ARGILE_XR_TEST_SCRIPT", &script_path);
        std::env::set_var("ARGILE_XR_TEST_OUT", &out);
        std::env::remove_var("ARGILE_XR_TEST_NO_VULKAN");
        std::env::remove_var("ARGILE_XR_TEST_NO_HMD");
        VALIDATION.lock().unwrap_or_else(|p| p.into_inner()).clear();
        // SAFETY: the system's Khronos loader conforms to the OpenXR loader specification.
        let entry = unsafe { xr::Entry::load_from(Path::new(common::xr::LOADER)) }
            .expect("the OpenXR loader libopenxr_loader.so.1 (package libopenxr-loader1) loads");
        Case { out, entry, _guard: guard }
    }

    fn instance(&self) -> xr::Instance {
        let mut exts = xr::ExtensionSet::default();
        exts.khr_vulkan_enable2 = true;
        exts.khr_composition_layer_depth = true;
        let app = app_info();
        self.entry.create_instance(&app, &exts, &[]).expect("the test runtime creates an instance")
    }

    fn log(&self) -> Vec<Value> {
        let text = std::fs::read_to_string(self.out.join("log.jsonl")).expect("the runtime wrote log.jsonl");
        text.lines().map(|l| serde_json::from_str(l).expect("each log line is JSON")).collect()
    }

    fn kinds<'a>(log: &'a [Value], kind: &str) -> Vec<&'a Value> {
        log.iter().filter(|l| l["kind"] == kind).collect()
    }
}

/// A Vulkan instance and device the runtime made for us (XR_KHR_vulkan_enable2).
struct Gpu {
    _entry: ash::Entry,
    instance: ash::Instance,
    device: ash::Device,
    family: u32,
    queue: vk::Queue,
    pool: vk::CommandPool,
    debug: ash::ext::debug_utils::Instance,
    messenger: vk::DebugUtilsMessengerEXT,
}

impl Gpu {
    fn new(xri: &xr::Instance, system: xr::SystemId) -> Gpu {
        let reqs = xri.graphics_requirements::<xr::Vulkan>(system).expect("Vulkan requirements");
        assert!(reqs.min_api_version_supported <= xr::Version::new(1, 1, 0));
        // SAFETY: plain Vulkan setup through the runtime; every handle is destroyed in `drop`.
        unsafe {
            let entry = ash::Entry::load().expect("the Vulkan loader");
            let app = vk::ApplicationInfo::default().api_version(vk::make_api_version(0, 1, 1, 0));
            let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
            let exts = [ash::ext::debug_utils::NAME.as_ptr()];
            let info = vk::InstanceCreateInfo::default()
                .application_info(&app)
                .enabled_layer_names(&layers)
                .enabled_extension_names(&exts);
            // SAFETY: the same vkGetInstanceProcAddr signature, as ash and openxr spell it.
            let gipa = std::mem::transmute::<
                vk::PFN_vkGetInstanceProcAddr,
                xr::sys::platform::VkGetInstanceProcAddr,
            >(entry.static_fn().get_instance_proc_addr);
            let raw = xri
                .create_vulkan_instance(system, gipa, &info as *const _ as *const _)
                .expect("xrCreateVulkanInstanceKHR")
                .expect("vkCreateInstance through the runtime");
            let instance = ash::Instance::load(entry.static_fn(), vk::Instance::from_raw(raw as u64));
            let debug = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let messenger = debug
                .create_debug_utils_messenger(
                    &vk::DebugUtilsMessengerCreateInfoEXT::default()
                        .message_severity(
                            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                        )
                        .message_type(
                            vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                                | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
                        )
                        .pfn_user_callback(Some(on_validation)),
                    None,
                )
                .expect("debug messenger");
            let physical = xri.vulkan_graphics_device(system, raw).expect("xrGetVulkanGraphicsDevice2KHR");
            let physical = vk::PhysicalDevice::from_raw(physical as u64);
            let family = instance
                .get_physical_device_queue_family_properties(physical)
                .iter()
                .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS))
                .expect("a graphics queue") as u32;
            let prio = [1.0];
            let queues =
                [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&prio)];
            let dinfo = vk::DeviceCreateInfo::default().queue_create_infos(&queues);
            let raw_device = xri
                .create_vulkan_device(system, gipa, physical.as_raw() as _, &dinfo as *const _ as *const _)
                .expect("xrCreateVulkanDeviceKHR")
                .expect("vkCreateDevice through the runtime");
            let device = ash::Device::load(instance.fp_v1_0(), vk::Device::from_raw(raw_device as u64));
            let queue = device.get_device_queue(family, 0);
            let pool = device
                .create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(family), None)
                .expect("command pool");
            Gpu { _entry: entry, instance, device, family, queue, pool, debug, messenger }
        }
    }

    fn binding(&self) -> xr::vulkan::SessionCreateInfo {
        xr::vulkan::SessionCreateInfo {
            instance: self.instance.handle().as_raw() as _,
            physical_device: unsafe { self.instance.enumerate_physical_devices() }.expect("devices")[0]
                .as_raw() as _,
            device: self.device.handle().as_raw() as _,
            queue_family_index: self.family,
            queue_index: 0,
        }
    }

    /// Clears each array layer of an image (handed over in COLOR_ATTACHMENT_OPTIMAL) to its
    /// colour and gives it back in that layout, waiting for the work.
    fn clear_layers(&self, image: vk::Image, colours: &[[f32; 4]]) {
        // SAFETY: a one-time command buffer, waited for before returning.
        unsafe {
            let cmd = self
                .device
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default().command_pool(self.pool).command_buffer_count(1),
                )
                .expect("command buffer")[0];
            self.device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).expect("begin");
            let range = |layer: u32| {
                vk::ImageSubresourceRange::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .base_array_layer(layer)
                    .layer_count(1)
                    .level_count(1)
            };
            let all = vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .layer_count(colours.len() as u32)
                .level_count(1);
            let attachment = (
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE | vk::AccessFlags::COLOR_ATTACHMENT_READ,
            );
            let clearing = (
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
            );
            transition(&self.device, cmd, image, all, attachment, clearing);
            for (layer, c) in colours.iter().enumerate() {
                self.device.cmd_clear_color_image(
                    cmd,
                    image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &vk::ClearColorValue { float32: *c },
                    &[range(layer as u32)],
                );
            }
            transition(&self.device, cmd, image, all, clearing, attachment);
            self.device.end_command_buffer(cmd).expect("end");
            let cmds = [cmd];
            self.device
                .queue_submit(
                    self.queue,
                    &[vk::SubmitInfo::default().command_buffers(&cmds)],
                    vk::Fence::null(),
                )
                .expect("submit");
            self.device.queue_wait_idle(self.queue).expect("wait");
            self.device.free_command_buffers(self.pool, &cmds);
        }
    }

    fn assert_no_validation_messages(&self) {
        let msgs = VALIDATION.lock().unwrap_or_else(|p| p.into_inner());
        assert!(msgs.is_empty(), "Vulkan validation messages:\n{}", msgs.join("\n"));
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // SAFETY: OpenXR (and the runtime's use of the device) is gone before this runs.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_command_pool(self.pool, None);
            self.device.destroy_device(None);
            self.debug.destroy_debug_utils_messenger(self.messenger, None);
            self.instance.destroy_instance(None);
        }
    }
}

/// A swapchain of two-layer colour images the application clears, and its images.
fn two_layer_swapchain(
    session: &xr::Session<xr::Vulkan>,
    size: [u32; 2],
    format: vk::Format,
) -> (xr::Swapchain<xr::Vulkan>, Vec<vk::Image>) {
    let swapchain = session
        .create_swapchain(&xr::SwapchainCreateInfo {
            create_flags: xr::SwapchainCreateFlags::EMPTY,
            usage_flags: xr::SwapchainUsageFlags::COLOR_ATTACHMENT | xr::SwapchainUsageFlags::TRANSFER_DST,
            format: format.as_raw() as u32,
            sample_count: 1,
            width: size[0],
            height: size[1],
            face_count: 1,
            array_size: 2,
            mip_count: 1,
        })
        .expect("a two-layer swapchain");
    let images = swapchain.enumerate_images().expect("images").into_iter().map(vk::Image::from_raw).collect();
    (swapchain, images)
}

/// An application: instance, Vulkan, session, stage space and a two-layer swapchain.
struct App {
    // Fields drop in order: OpenXR objects before the instance, Vulkan last.
    swapchain: xr::Swapchain<xr::Vulkan>,
    images: Vec<vk::Image>,
    stage: xr::Space,
    waiter: xr::FrameWaiter,
    stream: xr::FrameStream<xr::Vulkan>,
    session: xr::Session<xr::Vulkan>,
    instance: xr::Instance,
    system: xr::SystemId,
    size: [u32; 2],
    gpu: Gpu,
}

impl App {
    fn new(case: &Case) -> App {
        let instance = case.instance();
        let system = instance.system(xr::FormFactor::HEAD_MOUNTED_DISPLAY).expect("a headset");
        let gpu = Gpu::new(&instance, system);
        // SAFETY: the binding names the instance and device the runtime made.
        let (session, waiter, stream) =
            unsafe { instance.create_session::<xr::Vulkan>(system, &gpu.binding()) }
                .expect("xrCreateSession");
        let stage = session
            .create_reference_space(xr::ReferenceSpaceType::STAGE, xr::Posef::IDENTITY)
            .expect("stage space");
        let views = instance
            .enumerate_view_configuration_views(system, xr::ViewConfigurationType::PRIMARY_STEREO)
            .expect("views");
        let size = [views[0].recommended_image_rect_width, views[0].recommended_image_rect_height];
        let (swapchain, images) = two_layer_swapchain(&session, size, vk::Format::R8G8B8A8_SRGB);
        App { swapchain, images, stage, waiter, stream, session, instance, system, size, gpu }
    }

    /// Polls every pending event; returns the session states entered.
    fn poll(&self) -> Vec<xr::SessionState> {
        let mut buffer = xr::EventDataBuffer::new();
        let mut states = Vec::new();
        while let Some(e) = self.instance.poll_event(&mut buffer).expect("xrPollEvent") {
            if let xr::Event::SessionStateChanged(s) = e {
                states.push(s.state());
            }
        }
        states
    }

    /// Clears the colour swapchain's next image (one colour per eye layer) and locates the
    /// views for the frame; returns them with the full-image rectangle.
    fn render_colour(
        &mut self,
        state: &xr::FrameState,
        colours: &[[f32; 4]; 2],
    ) -> (Vec<xr::View>, xr::Rect2Di) {
        let i = self.swapchain.acquire_image().expect("acquire") as usize;
        self.swapchain.wait_image(xr::Duration::INFINITE).expect("wait image");
        self.gpu.clear_layers(self.images[i], colours);
        self.swapchain.release_image().expect("release");
        let (_, views) = self
            .session
            .locate_views(
                xr::ViewConfigurationType::PRIMARY_STEREO,
                state.predicted_display_time,
                &self.stage,
            )
            .expect("xrLocateViews");
        let rect = xr::Rect2Di {
            offset: xr::Offset2Di { x: 0, y: 0 },
            extent: xr::Extent2Di { width: self.size[0] as i32, height: self.size[1] as i32 },
        };
        (views, rect)
    }

    /// One frame: wait, begin, locate the views, clear both layers, end with a projection layer
    /// (or no layer when the runtime says not to render).
    fn frame(&mut self, colours: &[[f32; 4]; 2]) -> xr::FrameState {
        let state = self.waiter.wait().expect("xrWaitFrame");
        self.stream.begin().expect("xrBeginFrame");
        if !state.should_render {
            self.stream
                .end(state.predicted_display_time, xr::EnvironmentBlendMode::OPAQUE, &[])
                .expect("xrEndFrame");
            return state;
        }
        let (views, rect) = self.render_colour(&state, colours);
        let proj: Vec<_> = views
            .iter()
            .enumerate()
            .map(|(eye, v)| {
                xr::CompositionLayerProjectionView::new().pose(v.pose).fov(v.fov).sub_image(
                    xr::SwapchainSubImage::new()
                        .swapchain(&self.swapchain)
                        .image_array_index(eye as u32)
                        .image_rect(rect),
                )
            })
            .collect();
        let layer = xr::CompositionLayerProjection::new().space(&self.stage).views(&proj);
        self.stream
            .end(state.predicted_display_time, xr::EnvironmentBlendMode::OPAQUE, &[&layer])
            .expect("xrEndFrame");
        state
    }
}

const LEFT_COLOUR: [f32; 4] = [1.0, 0.5, 0.0, 1.0];
const RIGHT_COLOUR: [f32; 4] = [0.0, 0.5, 1.0, 1.0];

const SCRIPT: &str = r#"
display_hz = 90.0
interaction_profile = "/interaction_profiles/oculus/touch_controller"
recommended_size = [64, 48]
ipd_m = 0.064
capture = [3]
[[key]]
frame = 0
head = { position = [0, 1.6, 0], orientation = [0, 0, 0, 1] }
right = { grip = { position = [0.2, 1.3, -0.3] }, trigger = 0.0, thumbstick = [0, 0] }
[[key]]
frame = 10
head = { position = [0.1, 1.6, 0], orientation = [0, 0, 0, 1] }
right = { grip = { position = [0.2, 1.1, -0.5] }, trigger = 1.0, a = true, thumbstick = [0.5, -0.5] }
"#;

#[test]
fn the_loader_negotiates_with_the_runtime_which_offers_a_stereo_headset() {
    let case = Case::new("negotiation", SCRIPT);
    let exts = case.entry.enumerate_extensions().expect("extensions");
    assert!(exts.khr_vulkan_enable2 && exts.khr_composition_layer_depth);
    let instance = case.instance();
    let props = instance.properties().expect("properties");
    assert_eq!(props.runtime_name, "Argile XR test runtime");
    let system = instance.system(xr::FormFactor::HEAD_MOUNTED_DISPLAY).expect("a headset");
    let sp = instance.system_properties(system).expect("system properties");
    assert!(sp.tracking_properties.position_tracking);
    assert_eq!(
        instance.enumerate_view_configurations(system).expect("view configurations"),
        vec![xr::ViewConfigurationType::PRIMARY_STEREO]
    );
    let views = instance
        .enumerate_view_configuration_views(system, xr::ViewConfigurationType::PRIMARY_STEREO)
        .expect("views");
    assert_eq!(views.len(), 2);
    assert_eq!((views[0].recommended_image_rect_width, views[0].recommended_image_rect_height), (64, 48));
    assert_eq!(
        instance
            .enumerate_environment_blend_modes(system, xr::ViewConfigurationType::PRIMARY_STEREO)
            .expect("blend"),
        vec![xr::EnvironmentBlendMode::OPAQUE]
    );
    // Other form factors are not simulated.
    assert_eq!(
        instance.system(xr::FormFactor::HANDHELD_DISPLAY).unwrap_err(),
        xr::sys::Result::ERROR_FORM_FACTOR_UNSUPPORTED
    );
    drop(instance);
    assert!(Case::kinds(&case.log(), "violation").is_empty());
}

#[test]
fn a_vulkan_session_reaches_focused_and_its_two_layer_image_is_captured() {
    let case = Case::new("session", SCRIPT);
    let mut app = App::new(&case);
    assert_eq!(app.poll(), vec![xr::SessionState::IDLE, xr::SessionState::READY]);
    app.session.begin(xr::ViewConfigurationType::PRIMARY_STEREO).expect("xrBeginSession");
    // The first frame is not rendered; it synchronises the session, which then gets focus.
    let first = app.frame(&[LEFT_COLOUR, RIGHT_COLOUR]);
    assert!(!first.should_render);
    assert_eq!(
        app.poll(),
        vec![xr::SessionState::SYNCHRONIZED, xr::SessionState::VISIBLE, xr::SessionState::FOCUSED]
    );
    let mut times = vec![first.predicted_display_time.as_nanos()];
    for _ in 0..4 {
        let s = app.frame(&[LEFT_COLOUR, RIGHT_COLOUR]);
        assert!(s.should_render);
        assert_eq!(s.predicted_display_period.as_nanos(), 11_111_111);
        times.push(s.predicted_display_time.as_nanos());
    }
    assert!(
        times.windows(2).all(|w| w[1] - w[0] == 11_111_111),
        "display times step by the period: {times:?}"
    );
    // The views follow the script: at frame 5 the head has moved half way to x = 0.1.
    let (_, views) = app
        .session
        .locate_views(
            xr::ViewConfigurationType::PRIMARY_STEREO,
            xr::Time::from_nanos(times[0] + 5 * 11_111_111),
            &app.stage,
        )
        .expect("views");
    let (l, r) = (views[0].pose.position, views[1].pose.position);
    assert!(((l.x + r.x) / 2.0 - 0.05).abs() < 1e-4 && (r.x - l.x - 0.064).abs() < 1e-4, "{l:?} {r:?}");
    assert!(views[0].fov.angle_left < 0.0 && views[0].fov.angle_right > 0.0);
    // Exit: the application asks, the runtime stops the session, the application ends it.
    app.session.request_exit().expect("xrRequestExitSession");
    assert_eq!(
        app.poll(),
        vec![xr::SessionState::VISIBLE, xr::SessionState::SYNCHRONIZED, xr::SessionState::STOPPING]
    );
    app.session.end().expect("xrEndSession");
    assert_eq!(app.poll(), vec![xr::SessionState::IDLE, xr::SessionState::EXITING]);
    app.gpu.assert_no_validation_messages();
    drop(app);

    let log = case.log();
    assert!(Case::kinds(&log, "violation").is_empty(), "{:?}", Case::kinds(&log, "violation"));
    let states: Vec<_> =
        Case::kinds(&log, "state").iter().map(|l| l["state"].as_str().unwrap().to_string()).collect();
    assert_eq!(
        states,
        [
            "IDLE",
            "READY",
            "SYNCHRONIZED",
            "VISIBLE",
            "FOCUSED",
            "VISIBLE",
            "SYNCHRONIZED",
            "STOPPING",
            "IDLE",
            "EXITING"
        ]
    );
    let ends = Case::kinds(&log, "end_frame");
    assert_eq!(ends.len(), 5);
    assert_eq!(ends[0]["layers"], 0);
    assert_eq!(ends[3]["views"].as_array().unwrap().len(), 2);
    assert_eq!(ends[3]["depth"], false);
    let captures = Case::kinds(&log, "capture");
    assert_eq!(captures.len(), 2, "{captures:?}");
    // Both eyes' PNGs hold their layer's clear colour, sRGB-encoded as on screen.
    for (eye, expected) in [("left", [255u8, 188, 0, 255]), ("right", [0, 188, 255, 255])] {
        let img =
            image::open(case.out.join(format!("frame-0003-{eye}.png"))).expect("captured PNG").to_rgba8();
        assert_eq!(img.dimensions(), (64, 48));
        for p in img.pixels() {
            assert!(
                p.0.iter().zip(expected).all(|(a, b)| a.abs_diff(b) <= 1),
                "{eye}: {:?} not {expected:?}",
                p.0
            );
        }
    }
}

const ACTIONS_SCRIPT: &str = r#"
interaction_profile = "/interaction_profiles/oculus/touch_controller"
recommended_size = [32, 32]
[[key]]
frame = 0
right = { grip = { position = [0.2, 1.3, -0.3] }, trigger = 0.0, thumbstick = [0, 0] }
[[key]]
frame = 4
right = { grip = { position = [0.2, 1.1, -0.7] }, trigger = 1.0, a = true, thumbstick = [0.5, -0.5] }
"#;

#[test]
fn actions_read_the_scripted_controllers_and_haptics_are_logged() {
    let case = Case::new("actions", ACTIONS_SCRIPT);
    let mut app = App::new(&case);
    let i = &app.instance.clone();
    let set = i.create_action_set("sculpt", "Sculpt", 0).expect("action set");
    let hands = [i.string_to_path("/user/hand/left").unwrap(), i.string_to_path("/user/hand/right").unwrap()];
    let trigger = set.create_action::<f32>("apply", "Apply", &hands).expect("float action");
    let undo = set.create_action::<bool>("undo", "Undo", &[]).expect("bool action");
    let size = set.create_action::<xr::Vector2f>("size", "Size", &hands).expect("vector action");
    let grip = set.create_action::<xr::Posef>("grip", "Grip", &hands).expect("pose action");
    let buzz = set.create_action::<xr::Haptic>("buzz", "Buzz", &hands).expect("haptic action");
    let p = |s: &str| i.string_to_path(s).unwrap();
    i.suggest_interaction_profile_bindings(
        p("/interaction_profiles/oculus/touch_controller"),
        &[
            xr::Binding::new(&trigger, p("/user/hand/right/input/trigger/value")),
            xr::Binding::new(&trigger, p("/user/hand/left/input/trigger/value")),
            xr::Binding::new(&undo, p("/user/hand/right/input/a/click")),
            xr::Binding::new(&size, p("/user/hand/right/input/thumbstick")),
            xr::Binding::new(&grip, p("/user/hand/right/input/grip/pose")),
            xr::Binding::new(&buzz, p("/user/hand/right/output/haptic")),
        ],
    )
    .expect("touch bindings");
    // A path the profile does not have is refused.
    assert_eq!(
        i.suggest_interaction_profile_bindings(
            p("/interaction_profiles/htc/vive_controller"),
            &[xr::Binding::new(&undo, p("/user/hand/right/input/a/click"))],
        )
        .unwrap_err(),
        xr::sys::Result::ERROR_PATH_UNSUPPORTED
    );
    // An action space may be made before its set is attached.
    let grip_space =
        grip.create_space(app.session.clone(), hands[1], xr::Posef::IDENTITY).expect("action space");
    app.session.attach_action_sets(&[&set]).expect("attach");
    app.poll();
    app.session.begin(xr::ViewConfigurationType::PRIMARY_STEREO).expect("begin");
    for _ in 0..5 {
        app.frame(&[LEFT_COLOUR, RIGHT_COLOUR]);
    }
    app.poll();
    // The frame in flight is frame 5 (after the last keyframe): trigger full, A down, stick set.
    let state = app.waiter.wait().expect("wait");
    app.stream.begin().expect("begin frame");
    app.session.sync_actions(&[xr::ActiveActionSet::new(&set)]).expect("sync");
    let t = trigger.state(&app.session, xr::Path::NULL).expect("float state");
    assert!(t.is_active && (t.current_state - 1.0).abs() < 1e-6, "trigger {}", t.current_state);
    assert!(t.changed_since_last_sync || t.last_change_time.as_nanos() > 0);
    assert_eq!(trigger.state(&app.session, hands[0]).expect("left").current_state, 0.0);
    let u = undo.state(&app.session, xr::Path::NULL).expect("bool state");
    assert!(u.is_active && u.current_state);
    let s = size.state(&app.session, hands[1]).expect("vector state");
    assert_eq!((s.current_state.x, s.current_state.y), (0.5, -0.5));
    assert!(grip.is_active(&app.session, hands[1]).expect("pose state"));
    let loc = grip_space.locate(&app.stage, state.predicted_display_time).expect("locate grip");
    assert!(loc.location_flags.contains(xr::SpaceLocationFlags::POSITION_VALID));
    assert!(
        (loc.pose.position.z + 0.7).abs() < 1e-5 && (loc.pose.position.y - 1.1).abs() < 1e-5,
        "{:?}",
        loc.pose.position
    );
    buzz.apply_feedback(
        &app.session,
        hands[1],
        &xr::HapticVibration::new()
            .amplitude(0.75)
            .duration(xr::Duration::from_nanos(20_000_000))
            .frequency(160.0),
    )
    .expect("haptic");
    buzz.stop_feedback(&app.session, hands[1]).expect("stop haptic");
    // The trigger action's bound sources are both triggers, named for people.
    let info = xr::sys::BoundSourcesForActionEnumerateInfo {
        ty: xr::sys::BoundSourcesForActionEnumerateInfo::TYPE,
        next: std::ptr::null(),
        action: trigger.as_raw(),
    };
    let mut sources = [xr::Path::NULL; 4];
    let mut count = 0;
    // SAFETY: valid structures and a large enough array.
    let r = unsafe {
        (i.fp().enumerate_bound_sources_for_action)(
            app.session.as_raw(),
            &info,
            4,
            &mut count,
            sources.as_mut_ptr(),
        )
    };
    assert_eq!((r, count), (xr::sys::Result::SUCCESS, 2));
    let names: Vec<String> = sources[..2].iter().map(|&p| i.path_to_string(p).expect("path")).collect();
    assert_eq!(names, ["/user/hand/left/input/trigger/value", "/user/hand/right/input/trigger/value"]);
    let name = app
        .session
        .input_source_localized_name(
            sources[1],
            xr::InputSourceLocalizedNameFlags::USER_PATH | xr::InputSourceLocalizedNameFlags::COMPONENT,
        )
        .expect("localized name");
    assert_eq!(name, "Right hand trigger value");
    // Asking a float action for a boolean state is a type mismatch.
    let wrong = xr::sys::ActionStateGetInfo {
        ty: xr::sys::ActionStateGetInfo::TYPE,
        next: std::ptr::null(),
        action: trigger.as_raw(),
        subaction_path: xr::Path::NULL,
    };
    let mut b = xr::sys::ActionStateBoolean {
        ty: xr::sys::ActionStateBoolean::TYPE,
        next: std::ptr::null_mut(),
        current_state: xr::sys::FALSE,
        changed_since_last_sync: xr::sys::FALSE,
        last_change_time: xr::Time::from_nanos(0),
        is_active: xr::sys::FALSE,
    };
    // SAFETY: valid structures for the runtime to refuse.
    let r = unsafe { (i.fp().get_action_state_boolean)(app.session.as_raw(), &wrong, &mut b) };
    assert_eq!(r, xr::sys::Result::ERROR_ACTION_TYPE_MISMATCH);
    app.stream.end(state.predicted_display_time, xr::EnvironmentBlendMode::OPAQUE, &[]).expect("end frame");
    app.gpu.assert_no_validation_messages();
    drop(grip_space);
    drop(app);
    let log = case.log();
    let haptics = Case::kinds(&log, "haptic");
    assert_eq!(haptics.len(), 1, "{haptics:?}");
    assert_eq!(haptics[0]["hand"], "right");
    assert_eq!(haptics[0]["frame"], 5);
    assert_eq!(haptics[0]["amplitude"], 0.75);
    assert_eq!(haptics[0]["duration_ns"], 20_000_000);
    assert_eq!(Case::kinds(&log, "haptic_stop").len(), 1);
    let violations = Case::kinds(&log, "violation");
    let functions: Vec<_> =
        violations.iter().map(|v| (v["function"].as_str().unwrap(), v["result"].as_str().unwrap())).collect();
    assert_eq!(
        functions,
        [
            ("xrSuggestInteractionProfileBindings", "XR_ERROR_PATH_UNSUPPORTED"),
            ("xrGetActionStateBoolean", "XR_ERROR_ACTION_TYPE_MISMATCH")
        ]
    );
}

#[test]
fn calls_out_of_order_on_dead_handles_or_with_wrong_types_are_refused_and_logged() {
    let case = Case::new("violations", SCRIPT);
    let mut app = App::new(&case);
    app.poll();
    let instance = app.instance.clone();
    let fp = instance.fp();
    // Frames before the session begins.
    assert_eq!(app.waiter.wait().unwrap_err(), xr::sys::Result::ERROR_SESSION_NOT_RUNNING);
    app.session.begin(xr::ViewConfigurationType::PRIMARY_STEREO).expect("begin");
    assert_eq!(
        app.session.begin(xr::ViewConfigurationType::PRIMARY_STEREO).unwrap_err(),
        xr::sys::Result::ERROR_SESSION_RUNNING
    );
    // Begin without wait, end without begin, wait twice.
    assert_eq!(app.stream.begin().unwrap_err(), xr::sys::Result::ERROR_CALL_ORDER_INVALID);
    let state = app.waiter.wait().expect("wait");
    assert_eq!(
        app.stream.end(state.predicted_display_time, xr::EnvironmentBlendMode::OPAQUE, &[]).unwrap_err(),
        xr::sys::Result::ERROR_CALL_ORDER_INVALID
    );
    assert_eq!(app.waiter.wait().unwrap_err(), xr::sys::Result::ERROR_CALL_ORDER_INVALID);
    app.stream.begin().expect("begin frame");
    // Swapchain order, through the raw commands (the openxr crate asserts part of it itself):
    // wait or release before acquire, more acquired than there are images, release unwaited.
    let sc = app.swapchain.as_raw();
    let wait_info = xr::sys::SwapchainImageWaitInfo {
        ty: xr::sys::SwapchainImageWaitInfo::TYPE,
        next: std::ptr::null(),
        timeout: xr::Duration::INFINITE,
    };
    // SAFETY: valid arguments; the order of the calls is what is tested.
    let acquire = || unsafe { (fp.acquire_swapchain_image)(sc, std::ptr::null(), &mut 0) };
    let wait = || unsafe { (fp.wait_swapchain_image)(sc, &wait_info) };
    let release = || unsafe { (fp.release_swapchain_image)(sc, std::ptr::null()) };
    assert_eq!(wait(), xr::sys::Result::ERROR_CALL_ORDER_INVALID);
    assert_eq!(release(), xr::sys::Result::ERROR_CALL_ORDER_INVALID);
    for _ in 0..app.images.len() {
        assert_eq!(acquire(), xr::sys::Result::SUCCESS);
    }
    assert_eq!(acquire(), xr::sys::Result::ERROR_CALL_ORDER_INVALID);
    assert_eq!(release(), xr::sys::Result::ERROR_CALL_ORDER_INVALID);
    for _ in 0..app.images.len() {
        assert_eq!(wait(), xr::sys::Result::SUCCESS);
        assert_eq!(release(), xr::sys::Result::SUCCESS);
    }
    // A layer whose image rectangle leaves the swapchain, and a blend mode not offered.
    let views = [0u32, 1].map(|eye| {
        xr::CompositionLayerProjectionView::new().pose(xr::Posef::IDENTITY).sub_image(
            xr::SwapchainSubImage::new().swapchain(&app.swapchain).image_array_index(eye).image_rect(
                xr::Rect2Di {
                    offset: xr::Offset2Di { x: 10, y: 0 },
                    extent: xr::Extent2Di { width: 64, height: 48 },
                },
            ),
        )
    });
    let layer = xr::CompositionLayerProjection::new().space(&app.stage).views(&views);
    assert_eq!(
        app.stream
            .end(state.predicted_display_time, xr::EnvironmentBlendMode::OPAQUE, &[&layer])
            .unwrap_err(),
        xr::sys::Result::ERROR_SWAPCHAIN_RECT_INVALID
    );
    assert_eq!(
        app.stream.end(state.predicted_display_time, xr::EnvironmentBlendMode::ADDITIVE, &[]).unwrap_err(),
        xr::sys::Result::ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED
    );
    app.stream.end(state.predicted_display_time, xr::EnvironmentBlendMode::OPAQUE, &[]).expect("a valid end");
    // A destroyed space, and a handle that never was.
    let view_space =
        app.session.create_reference_space(xr::ReferenceSpaceType::VIEW, xr::Posef::IDENTITY).expect("space");
    let raw_view = view_space.as_raw();
    drop(view_space);
    let mut loc = xr::sys::SpaceLocation {
        ty: xr::sys::SpaceLocation::TYPE,
        next: std::ptr::null_mut(),
        location_flags: xr::SpaceLocationFlags::EMPTY,
        pose: xr::Posef::IDENTITY,
    };
    // SAFETY: valid structures; the handles are what is being tested.
    unsafe {
        assert_eq!(
            (fp.locate_space)(raw_view, app.stage.as_raw(), state.predicted_display_time, &mut loc),
            xr::sys::Result::ERROR_HANDLE_INVALID
        );
        assert_eq!((fp.destroy_space)(raw_view), xr::sys::Result::ERROR_HANDLE_INVALID);
        assert_eq!(
            (fp.request_exit_session)(xr::sys::Session::from_raw(0xdead)),
            xr::sys::Result::ERROR_HANDLE_INVALID
        );
        // Wrong structure types.
        let info = xr::sys::SystemGetInfo {
            ty: xr::sys::StructureType::SESSION_CREATE_INFO,
            next: std::ptr::null(),
            form_factor: xr::FormFactor::HEAD_MOUNTED_DISPLAY,
        };
        let mut id = xr::SystemId::NULL;
        assert_eq!(
            (fp.get_system)(app.instance.as_raw(), &info, &mut id),
            xr::sys::Result::ERROR_VALIDATION_FAILURE
        );
        loc.ty = xr::sys::StructureType::VIEW;
        assert_eq!(
            (fp.locate_space)(app.stage.as_raw(), app.stage.as_raw(), state.predicted_display_time, &mut loc),
            xr::sys::Result::ERROR_VALIDATION_FAILURE
        );
        // A pose that is not a rotation.
        let bad = xr::sys::ReferenceSpaceCreateInfo {
            ty: xr::sys::ReferenceSpaceCreateInfo::TYPE,
            next: std::ptr::null(),
            reference_space_type: xr::ReferenceSpaceType::LOCAL,
            pose_in_reference_space: xr::Posef {
                orientation: xr::Quaternionf { x: 0.0, y: 0.0, z: 0.0, w: 2.0 },
                position: xr::Vector3f::default(),
            },
        };
        let mut space = xr::sys::Space::NULL;
        assert_eq!(
            (fp.create_reference_space)(app.session.as_raw(), &bad, &mut space),
            xr::sys::Result::ERROR_POSE_INVALID
        );
    }
    // Ending a session that is not stopping.
    assert_eq!(app.session.end().unwrap_err(), xr::sys::Result::ERROR_SESSION_NOT_STOPPING);
    app.gpu.assert_no_validation_messages();
    drop(app);
    let log = case.log();
    let got: Vec<(String, String)> = Case::kinds(&log, "violation")
        .iter()
        .map(|v| (v["function"].as_str().unwrap().to_string(), v["result"].as_str().unwrap().to_string()))
        .collect();
    let expected = [
        ("xrWaitFrame", "XR_ERROR_SESSION_NOT_RUNNING"),
        ("xrBeginSession", "XR_ERROR_SESSION_RUNNING"),
        ("xrBeginFrame", "XR_ERROR_CALL_ORDER_INVALID"),
        ("xrEndFrame", "XR_ERROR_CALL_ORDER_INVALID"),
        ("xrWaitFrame", "XR_ERROR_CALL_ORDER_INVALID"),
        ("xrWaitSwapchainImage", "XR_ERROR_CALL_ORDER_INVALID"),
        ("xrReleaseSwapchainImage", "XR_ERROR_CALL_ORDER_INVALID"),
        ("xrAcquireSwapchainImage", "XR_ERROR_CALL_ORDER_INVALID"),
        ("xrReleaseSwapchainImage", "XR_ERROR_CALL_ORDER_INVALID"),
        ("xrEndFrame", "XR_ERROR_SWAPCHAIN_RECT_INVALID"),
        ("xrEndFrame", "XR_ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED"),
        ("xrLocateSpace", "XR_ERROR_HANDLE_INVALID"),
        ("xrDestroySpace", "XR_ERROR_HANDLE_INVALID"),
        ("xrRequestExitSession", "XR_ERROR_HANDLE_INVALID"),
        ("xrGetSystem", "XR_ERROR_VALIDATION_FAILURE"),
        ("xrLocateSpace", "XR_ERROR_VALIDATION_FAILURE"),
        ("xrCreateReferenceSpace", "XR_ERROR_POSE_INVALID"),
        ("xrEndSession", "XR_ERROR_SESSION_NOT_STOPPING"),
    ];
    let expected: Vec<(String, String)> =
        expected.iter().map(|(f, r)| (f.to_string(), r.to_string())).collect();
    assert_eq!(got, expected);
    assert!(Case::kinds(&log, "violation").iter().all(|v| !v["why"].as_str().unwrap().is_empty()));
}

const LOSS_SCRIPT: &str = r#"
recommended_size = [32, 32]
[[event]]
frame = 2
kind = "session_loss"
[[event]]
frame = 5
kind = "exit"
"#;

#[test]
fn a_lost_session_refuses_frames_until_destroyed_and_a_new_one_runs_to_exit() {
    let case = Case::new("loss", LOSS_SCRIPT);
    let mut app = App::new(&case);
    app.poll();
    app.session.begin(xr::ViewConfigurationType::PRIMARY_STEREO).expect("begin");
    for _ in 0..3 {
        app.frame(&[LEFT_COLOUR, RIGHT_COLOUR]);
    }
    assert_eq!(
        app.poll(),
        vec![
            xr::SessionState::SYNCHRONIZED,
            xr::SessionState::VISIBLE,
            xr::SessionState::FOCUSED,
            xr::SessionState::LOSS_PENDING
        ]
    );
    assert_eq!(app.waiter.wait().unwrap_err(), xr::sys::Result::ERROR_SESSION_LOST);
    // Recreate the session (and its objects) on the same instance and device.
    let App { swapchain, stage, waiter, stream, session, instance, system, size, gpu, .. } = app;
    drop((swapchain, stage, waiter, stream, session));
    let (session, waiter, stream) = unsafe { instance.create_session::<xr::Vulkan>(system, &gpu.binding()) }
        .expect("a new session after the loss");
    let stage =
        session.create_reference_space(xr::ReferenceSpaceType::STAGE, xr::Posef::IDENTITY).expect("stage");
    let (swapchain, images) = two_layer_swapchain(&session, size, vk::Format::B8G8R8A8_SRGB);
    let mut app = App { swapchain, images, stage, waiter, stream, session, instance, system, size, gpu };
    assert_eq!(app.poll(), vec![xr::SessionState::IDLE, xr::SessionState::READY]);
    app.session.begin(xr::ViewConfigurationType::PRIMARY_STEREO).expect("begin again");
    let mut states = Vec::new();
    for _ in 0..3 {
        app.frame(&[LEFT_COLOUR, RIGHT_COLOUR]);
        states.extend(app.poll());
    }
    // Frame 5 (the timeline counts over the instance's life) carries the scripted exit.
    assert_eq!(
        states,
        vec![
            xr::SessionState::SYNCHRONIZED,
            xr::SessionState::VISIBLE,
            xr::SessionState::FOCUSED,
            xr::SessionState::VISIBLE,
            xr::SessionState::SYNCHRONIZED,
            xr::SessionState::STOPPING
        ]
    );
    app.session.end().expect("end");
    assert_eq!(app.poll(), vec![xr::SessionState::IDLE, xr::SessionState::EXITING]);
    app.gpu.assert_no_validation_messages();
    drop(app);
    let log = case.log();
    assert!(Case::kinds(&log, "violation").is_empty(), "{:?}", Case::kinds(&log, "violation"));
    assert_eq!(Case::kinds(&log, "refused").len(), 1, "the lost session's xrWaitFrame");
}

#[test]
fn a_runtime_without_vulkan_or_without_a_headset_says_so() {
    let case = Case::new("no-vulkan", SCRIPT);
    std::env::set_var("ARGILE_XR_TEST_NO_VULKAN", "1");
    std::env::set_var("ARGILE_XR_TEST_NO_HMD", "1");
    let exts = case.entry.enumerate_extensions().expect("extensions");
    assert!(!exts.khr_vulkan_enable2 && exts.khr_composition_layer_depth);
    let app = app_info();
    let mut vulkan = xr::ExtensionSet::default();
    vulkan.khr_vulkan_enable2 = true;
    assert_eq!(
        case.entry.create_instance(&app, &vulkan, &[]).err(),
        Some(xr::sys::Result::ERROR_EXTENSION_NOT_PRESENT)
    );
    let instance = case
        .entry
        .create_instance(&app, &xr::ExtensionSet::default(), &[])
        .expect("an instance without Vulkan");
    assert_eq!(
        instance.system(xr::FormFactor::HEAD_MOUNTED_DISPLAY).unwrap_err(),
        xr::sys::Result::ERROR_FORM_FACTOR_UNAVAILABLE
    );
    drop(instance);
    std::env::remove_var("ARGILE_XR_TEST_NO_VULKAN");
    std::env::remove_var("ARGILE_XR_TEST_NO_HMD");
    let log = case.log();
    assert!(Case::kinds(&log, "violation").is_empty(), "{:?}", Case::kinds(&log, "violation"));
    assert_eq!(Case::kinds(&log, "refused").len(), 1, "xrGetSystem's refusal is logged");
}

const FOCUS_SCRIPT: &str = r#"
recommended_size = [32, 32]
interaction_profile = "/interaction_profiles/valve/index_controller"
[[key]]
frame = 0
left = { trigger = 1.0 }
[[event]]
frame = 2
kind = "focus_lost"
[[event]]
frame = 4
kind = "focus_gained"
[[event]]
frame = 6
kind = "instance_loss"
"#;

#[test]
fn depth_layers_focus_changes_and_instance_loss_follow_the_script() {
    let case = Case::new("focus", FOCUS_SCRIPT);
    let mut app = App::new(&case);
    let instance = app.instance.clone();
    let fp = instance.fp();
    let set = instance.create_action_set("tools", "Tools", 0).expect("set");
    let select = set.create_action::<bool>("select", "Select", &[]).expect("action");
    let p = |s: &str| instance.string_to_path(s).unwrap();
    // Only simple-controller bindings: the Index controllers present themselves as simple ones.
    instance
        .suggest_interaction_profile_bindings(
            p("/interaction_profiles/khr/simple_controller"),
            &[xr::Binding::new(&select, p("/user/hand/left/input/select/click"))],
        )
        .expect("bindings");
    app.session.attach_action_sets(&[&set]).expect("attach");
    assert_eq!(
        app.session.current_interaction_profile(p("/user/hand/left")).expect("profile"),
        p("/interaction_profiles/khr/simple_controller")
    );
    let depth = app
        .session
        .create_swapchain(&xr::SwapchainCreateInfo {
            create_flags: xr::SwapchainCreateFlags::EMPTY,
            usage_flags: xr::SwapchainUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            format: vk::Format::D32_SFLOAT.as_raw() as u32,
            sample_count: 1,
            width: app.size[0],
            height: app.size[1],
            face_count: 1,
            array_size: 2,
            mip_count: 1,
        })
        .expect("a two-layer depth swapchain");
    app.poll();
    app.session.begin(xr::ViewConfigurationType::PRIMARY_STEREO).expect("begin");
    let sync = |session: &xr::Session<xr::Vulkan>| {
        let active = [xr::sys::ActiveActionSet { action_set: set.as_raw(), subaction_path: xr::Path::NULL }];
        let info = xr::sys::ActionsSyncInfo {
            ty: xr::sys::ActionsSyncInfo::TYPE,
            next: std::ptr::null(),
            count_active_action_sets: 1,
            active_action_sets: active.as_ptr(),
        };
        // SAFETY: valid structures.
        unsafe { (fp.sync_actions)(session.as_raw(), &info) }
    };
    let mut seen = Vec::new();
    let mut synced = Vec::new();
    for frame in 0..7 {
        let state = app.waiter.wait().expect("wait");
        app.stream.begin().expect("begin frame");
        synced
            .push((sync(&app.session), select.state(&app.session, xr::Path::NULL).expect("state").is_active));
        let result = if state.should_render {
            let (views, rect) = app.render_colour(&state, &[LEFT_COLOUR, RIGHT_COLOUR]);
            let d = depth.as_raw();
            // SAFETY: the depth images are not rendered; they stay in their layout.
            unsafe {
                (fp.acquire_swapchain_image)(d, std::ptr::null(), &mut 0);
                let wait = xr::sys::SwapchainImageWaitInfo {
                    ty: xr::sys::SwapchainImageWaitInfo::TYPE,
                    next: std::ptr::null(),
                    timeout: xr::Duration::INFINITE,
                };
                (fp.wait_swapchain_image)(d, &wait);
                (fp.release_swapchain_image)(d, std::ptr::null());
            }
            let sub = |sc: xr::sys::Swapchain, eye: u32| xr::sys::SwapchainSubImage {
                swapchain: sc,
                image_rect: rect,
                image_array_index: eye,
            };
            let depth_infos = [0, 1].map(|eye| xr::sys::CompositionLayerDepthInfoKHR {
                ty: xr::sys::CompositionLayerDepthInfoKHR::TYPE,
                next: std::ptr::null(),
                sub_image: sub(depth.as_raw(), eye),
                min_depth: 0.0,
                max_depth: 1.0,
                near_z: 0.05,
                far_z: 100.0,
            });
            let proj = [0usize, 1].map(|eye| xr::sys::CompositionLayerProjectionView {
                ty: xr::sys::CompositionLayerProjectionView::TYPE,
                next: &depth_infos[eye] as *const _ as *const _,
                pose: views[eye].pose,
                fov: views[eye].fov,
                sub_image: sub(app.swapchain.as_raw(), eye as u32),
            });
            let layer = xr::sys::CompositionLayerProjection {
                ty: xr::sys::CompositionLayerProjection::TYPE,
                next: std::ptr::null(),
                layer_flags: xr::CompositionLayerFlags::EMPTY,
                space: app.stage.as_raw(),
                view_count: 2,
                views: proj.as_ptr(),
            };
            // A quad (a palette, say) in front of the user, from the left eye's image.
            let quad = xr::sys::CompositionLayerQuad {
                ty: xr::sys::CompositionLayerQuad::TYPE,
                next: std::ptr::null(),
                layer_flags: xr::CompositionLayerFlags::EMPTY,
                space: app.stage.as_raw(),
                eye_visibility: xr::EyeVisibility::BOTH,
                sub_image: sub(app.swapchain.as_raw(), 0),
                pose: xr::Posef {
                    orientation: xr::Quaternionf::IDENTITY,
                    position: xr::Vector3f { x: 0.0, y: 1.4, z: -0.5 },
                },
                size: xr::Extent2Df { width: 0.2, height: 0.2 },
            };
            let layers = [
                &layer as *const _ as *const xr::sys::CompositionLayerBaseHeader,
                &quad as *const _ as *const xr::sys::CompositionLayerBaseHeader,
            ];
            let info = xr::sys::FrameEndInfo {
                ty: xr::sys::FrameEndInfo::TYPE,
                next: std::ptr::null(),
                display_time: state.predicted_display_time,
                environment_blend_mode: xr::EnvironmentBlendMode::OPAQUE,
                layer_count: 2,
                layers: layers.as_ptr(),
            };
            // SAFETY: valid structures that live across the call.
            unsafe { (fp.end_frame)(app.session.as_raw(), &info) }
        } else {
            let info = xr::sys::FrameEndInfo {
                ty: xr::sys::FrameEndInfo::TYPE,
                next: std::ptr::null(),
                display_time: state.predicted_display_time,
                environment_blend_mode: xr::EnvironmentBlendMode::OPAQUE,
                layer_count: 0,
                layers: std::ptr::null(),
            };
            // SAFETY: a valid structure.
            unsafe { (fp.end_frame)(app.session.as_raw(), &info) }
        };
        assert_eq!(result, xr::sys::Result::SUCCESS, "frame {frame}");
        let mut buffer = xr::EventDataBuffer::new();
        while let Some(e) = instance.poll_event(&mut buffer).expect("poll") {
            match e {
                xr::Event::SessionStateChanged(s) => seen.push(format!("{frame}:{:?}", s.state())),
                xr::Event::InstanceLossPending(_) => seen.push(format!("{frame}:instance loss")),
                _ => {}
            }
        }
    }
    assert_eq!(
        seen,
        ["0:SYNCHRONIZED", "0:VISIBLE", "0:FOCUSED", "2:VISIBLE", "4:FOCUSED", "6:instance loss"],
    );
    // Actions are active only while focused (frames 1, 2, 5, 6 are synced focused).
    let s = xr::sys::Result::SUCCESS;
    let nf = xr::sys::Result::SESSION_NOT_FOCUSED;
    assert_eq!(synced, [(nf, false), (s, true), (s, true), (nf, false), (nf, false), (s, true), (s, true)]);
    // After the loss every call but the destroy calls answers XR_ERROR_INSTANCE_LOST.
    assert_eq!(app.waiter.wait().unwrap_err(), xr::sys::Result::ERROR_INSTANCE_LOST);
    app.gpu.assert_no_validation_messages();
    drop((depth, select, set));
    drop(app);
    drop(instance);
    let log = case.log();
    assert!(Case::kinds(&log, "violation").is_empty(), "{:?}", Case::kinds(&log, "violation"));
    let ends = Case::kinds(&log, "end_frame");
    assert_eq!(ends.len(), 7);
    assert!(ends[1..].iter().all(|e| e["depth"] == true && e["layers"] == 2));
}

#[test]
fn a_bad_script_fails_the_instance_with_a_sentence_naming_the_file() {
    let case = Case::new("bad-script", "[[key]]\nframe = 0\nright = { trigger = 3.0 }\n");
    let app = app_info();
    let made = case.entry.create_instance(&app, &xr::ExtensionSet::default(), &[]);
    assert_eq!(made.err(), Some(xr::sys::Result::ERROR_RUNTIME_FAILURE));
    let log = case.log();
    let errors = Case::kinds(&log, "error");
    assert_eq!(errors.len(), 1, "{log:?}");
    let why = errors[0]["why"].as_str().unwrap();
    assert!(why.contains("script.toml") && why.contains("trigger"), "{why}");
}
