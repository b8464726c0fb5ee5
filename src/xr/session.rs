//! The headset session: the OpenXR instance and system, the renderer on the Vulkan instance
//! and device the runtime makes (XR_KHR_vulkan_enable2), the session with its swapchains and
//! reference space, and the frame loop.
//!
//! A frame, in the order of the openxr crate's Vulkan example:
//! `xrWaitFrame` → `xrBeginFrame` → acquire and wait the swapchain images → sync the actions
//! and locate the hands → the caller simulates and meshes → locate the views (as late as
//! possible: just before the draw is recorded) → draw both eyes into the 2-layer images →
//! release → `xrEndFrame` with one projection layer (and its depth when the runtime offers
//! XR_KHR_composition_layer_depth).
//!
//! Teardown: every OpenXR handle (swapchains, spaces, actions, session, instance) goes before
//! the renderer, which destroys the Vulkan device and instance the runtime made for us; the
//! renderer forgets the runtime's swapchain images before their swapchains go.

use std::path::Path;
use std::time::Instant;

use ash::vk;
use ash::vk::Handle;
use openxr as xr;

use super::actions::{pose_of, HandState, Hands, Haptic};
use super::lifecycle::{Command, Lifecycle, SessionState};
use super::views::{stereo_views, Fov, XrView};
use super::{Placement, XrError};
use crate::math::Pose;
use crate::render::{Environment, Frame, RenderError, Renderer, RendererDesc, SwapchainImages, VulkanMaker};

const VIEW_TYPE: xr::ViewConfigurationType = xr::ViewConfigurationType::PRIMARY_STEREO;
/// The colour format of the swapchains: what the renderer draws (8-bit sRGB).
const COLOUR_FORMAT: vk::Format = vk::Format::R8G8B8A8_SRGB;

/// What the caller's step gets each rendered frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameInput {
    /// Frames ended so far in this session (the runtime's count, from 0).
    pub index: u64,
    /// When this frame will be shown, runtime nanoseconds.
    pub display_time_ns: i64,
    /// The time between two frames the runtime predicts, seconds.
    pub period_s: f32,
    /// Whether the controllers act (the session has the input focus).
    pub focused: bool,
    /// The head in the room, when tracked.
    pub head: Option<Pose>,
    /// Both hands, `[left, right]`, in the room.
    pub hands: [HandState; 2],
}

/// What the caller's step returns: the frame to draw (its views are replaced by the
/// headset's), where the scene is in the room, and the haptic feedback to play.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameOutput {
    /// The frame; its `views` are ignored.
    pub frame: Frame,
    /// Scene → room.
    pub placement: Placement,
    /// Pulses to play, per hand.
    pub haptics: Vec<Haptic>,
    /// The glyphs held by each hand (`[left, right]`), drawn where that hand's grip is
    /// located again just before the draw (its motion since the step's input carried over).
    pub held: [Vec<Held>; 2],
}

/// A glyph of a [`Frame`] that a hand holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Held {
    /// `frame.tools[i]`.
    Tool(usize),
    /// `frame.controllers[i]`.
    Controller(usize),
    /// The panel, on its surface (`frame.panel`'s placement).
    Panel,
}

/// Moves the glyphs of `frame` that a hand holds by that hand's motion from `read` (the grips
/// the step used) to `late` (located again), both in the room; `placement` takes the scene
/// into the room. A hand not tracked at either time keeps its glyphs where they were.
pub fn carry_held(
    frame: &mut Frame,
    held: &[Vec<Held>; 2],
    placement: &Placement,
    read: [Option<Pose>; 2],
    late: [Option<Pose>; 2],
) {
    let to_room = placement.matrix();
    let to_scene = to_room.inverse();
    for (hand, glyphs) in held.iter().enumerate() {
        let (Some(from), Some(to)) = (read[hand], late[hand]) else { continue };
        let motion = to_scene * to.to_matrix() * from.to_matrix().inverse() * to_room;
        for g in glyphs {
            let model = match *g {
                Held::Tool(i) => frame.tools.get_mut(i).map(|g| &mut g.model),
                Held::Controller(i) => frame.controllers.get_mut(i).map(|g| &mut g.model),
                Held::Panel => frame.panel.as_mut().and_then(|p| p.placement.as_mut()),
            };
            if let Some(model) = model {
                *model = motion * *model;
            }
        }
    }
}

/// What one turn of the loop did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Turn {
    /// The session is not running (waiting for the runtime): call again a little later.
    Waiting,
    /// A frame was ended without images (the runtime did not want them).
    Skipped,
    /// A frame was drawn and ended.
    Drawn,
    /// The session was lost and a new one made: save the sculpt now.
    Recreated,
    /// The runtime ended the session for good (it asked to quit, or Argile did): save and quit.
    Finished,
    /// The runtime went away: the instance is lost (announced by its loss-pending event, or
    /// found by a call answering `XR_ERROR_INSTANCE_LOST`). Every OpenXR handle of it is gone;
    /// save, then start a new [`XrStation`] when the runtime is back, or go on without it.
    InstanceLost,
}

/// Where the time of the last drawn frame went, from `xrWaitFrame` returning to `xrEndFrame`
/// returning, milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTimes {
    /// From `xrWaitFrame` returning to the caller's step (begin frame, images, input).
    pub before_ms: f64,
    /// The caller's step (simulation, meshing).
    pub step_ms: f64,
    /// Locating views, drawing (waited for), releasing and `xrEndFrame`.
    pub submit_ms: f64,
    /// The age at `xrEndFrame` of the controller poses the frame's glyphs were drawn at (they
    /// are located again after the step, just before the draw is recorded), ms.
    pub pose_age_ms: f64,
    /// The age at `xrEndFrame` of the poses the step acted on (read before it), ms.
    pub input_pose_age_ms: f64,
}

/// The renderer's instance and device, made by the runtime (XR_KHR_vulkan_enable2).
struct RuntimeVulkan<'a> {
    instance: &'a xr::Instance,
    system: xr::SystemId,
}

fn xr_failed(call: &'static str) -> impl Fn(xr::sys::Result) -> RenderError {
    move |result| RenderError::Unsupported(format!("{call} failed: {result}"))
}

/// The loader's `vkGetInstanceProcAddr` as OpenXR's headers type it.
fn xr_proc_addr(f: vk::PFN_vkGetInstanceProcAddr) -> xr::sys::platform::VkGetInstanceProcAddr {
    // SAFETY: both are the same C function pointer type, `PFN_vkGetInstanceProcAddr`, declared
    // by ash and by openxr-sys.
    unsafe {
        std::mem::transmute::<vk::PFN_vkGetInstanceProcAddr, xr::sys::platform::VkGetInstanceProcAddr>(f)
    }
}

/// What xrCreateVulkan{Instance,Device}KHR returned: the handle, or the OpenXR or Vulkan
/// failure, naming `xr_call` and `vk_call`.
fn made_by_runtime<T>(
    made: xr::Result<Result<T, xr::sys::platform::VkResult>>,
    (xr_call, vk_call): (&'static str, &'static str),
) -> Result<T, RenderError> {
    made.map_err(xr_failed(xr_call))?.map_err(|r| RenderError::vk(vk_call)(vk::Result::from_raw(r)))
}

impl VulkanMaker for RuntimeVulkan<'_> {
    unsafe fn create_instance(
        &mut self,
        get_instance_proc_addr: vk::PFN_vkGetInstanceProcAddr,
        info: &vk::InstanceCreateInfo<'_>,
    ) -> Result<vk::Instance, RenderError> {
        let gipa = xr_proc_addr(get_instance_proc_addr);
        // SAFETY: the caller guarantees `info` and the loader's entry point; the runtime calls
        // vkCreateInstance through them.
        let made = unsafe {
            self.instance.create_vulkan_instance(self.system, gipa, std::ptr::from_ref(info).cast())
        };
        let calls = ("xrCreateVulkanInstanceKHR", "vkCreateInstance (by the OpenXR runtime)");
        Ok(vk::Instance::from_raw(made_by_runtime(made, calls)? as u64))
    }

    fn physical_device(&mut self, instance: vk::Instance) -> Result<vk::PhysicalDevice, RenderError> {
        // SAFETY: `instance` is the live instance the runtime made for this system.
        let raw = unsafe { self.instance.vulkan_graphics_device(self.system, instance.as_raw() as _) }
            .map_err(xr_failed("xrGetVulkanGraphicsDevice2KHR"))?;
        Ok(vk::PhysicalDevice::from_raw(raw as u64))
    }

    unsafe fn create_device(
        &mut self,
        get_instance_proc_addr: vk::PFN_vkGetInstanceProcAddr,
        physical: vk::PhysicalDevice,
        info: &vk::DeviceCreateInfo<'_>,
    ) -> Result<vk::Device, RenderError> {
        let gipa = xr_proc_addr(get_instance_proc_addr);
        // SAFETY: as for the instance; `physical` is the runtime's choice.
        let made = unsafe {
            self.instance.create_vulkan_device(
                self.system,
                gipa,
                physical.as_raw() as _,
                std::ptr::from_ref(info).cast(),
            )
        };
        let calls = ("xrCreateVulkanDeviceKHR", "vkCreateDevice (by the OpenXR runtime)");
        Ok(vk::Device::from_raw(made_by_runtime(made, calls)? as u64))
    }
}

/// One swapchain and its images' handles.
struct Chain {
    handle: xr::Swapchain<xr::Vulkan>,
    images: SwapchainImages,
}

/// Everything that lives as long as one session. Field order is drop order: swapchains,
/// spaces, the frame stream and waiter, then the session.
struct Live {
    colour: Chain,
    /// The depth swapchain, when its images are the renderer's depth attachment.
    depth: Option<Chain>,
    hands: Option<Hands>,
    view_space: xr::Space,
    space: xr::Space,
    stream: xr::FrameStream<xr::Vulkan>,
    waiter: xr::FrameWaiter,
    session: xr::Session<xr::Vulkan>,
    lifecycle: Lifecycle,
    /// Frames ended in this session.
    frames: u64,
}

/// Options of a headset session.
#[derive(Clone, Debug, PartialEq)]
pub struct XrOptions {
    /// Turn the Vulkan validation layer on.
    pub validation: bool,
    /// MSAA samples (1 submits depth when the runtime takes it).
    pub samples: u32,
    /// The OpenXR loader library to use instead of the system's (tests).
    pub loader: Option<std::path::PathBuf>,
}

impl Default for XrOptions {
    fn default() -> Self {
        Self { validation: false, samples: 1, loader: None }
    }
}

/// A headset session and the renderer drawing into it.
///
/// Field order is drop order after `Drop::drop` has made the renderer forget the swapchain
/// images: the session's handles, the OpenXR instance, then the renderer (Vulkan) last.
pub struct XrStation {
    /// The instance's extensions.
    enabled: xr::ExtensionSet,
    live: Option<Live>,
    events: xr::EventDataBuffer,
    instance: xr::Instance,
    system: xr::SystemId,
    blend: xr::EnvironmentBlendMode,
    /// Per-eye image size, pixels.
    size: (u32, u32),
    /// The runtime offers XR_KHR_composition_layer_depth.
    depth_layers: bool,
    runtime: String,
    /// The session ended for good (the runtime or Argile asked to quit).
    finished: bool,
    /// The instance is lost.
    lost: bool,
    times: FrameTimes,
    renderer: Renderer,
}

impl std::fmt::Debug for XrStation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("XrStation")
            .field("runtime", &self.runtime)
            .field("size", &self.size)
            .finish_non_exhaustive()
    }
}

fn state_of(s: xr::SessionState) -> Option<SessionState> {
    Some(match s {
        xr::SessionState::IDLE => SessionState::Idle,
        xr::SessionState::READY => SessionState::Ready,
        xr::SessionState::SYNCHRONIZED => SessionState::Synchronized,
        xr::SessionState::VISIBLE => SessionState::Visible,
        xr::SessionState::FOCUSED => SessionState::Focused,
        xr::SessionState::STOPPING => SessionState::Stopping,
        xr::SessionState::LOSS_PENDING => SessionState::LossPending,
        xr::SessionState::EXITING => SessionState::Exiting,
        _ => return None,
    })
}

/// A failing OpenXR call, as an error naming it.
pub(super) fn failed(call: &'static str) -> impl Fn(xr::sys::Result) -> XrError {
    move |result| XrError::Call { call, result }
}

impl XrStation {
    /// Finds the loader, the runtime and the headset, has the runtime make the renderer's
    /// Vulkan instance and device, and creates the session. Each missing piece is its own
    /// [`XrError`] with one sentence saying what to do.
    pub fn start(options: &XrOptions, environment: &Environment, intensity: f32) -> Result<Self, XrError> {
        let entry = super::load_entry(options.loader.as_deref())?;
        let available = entry.enumerate_extensions().map_err(|e| XrError::NoRuntime(e.to_string()))?;
        let mut enabled = xr::ExtensionSet::default();
        enabled.khr_vulkan_enable2 = available.khr_vulkan_enable2;
        enabled.khr_composition_layer_depth = available.khr_composition_layer_depth;
        super::actions::enable_profile_extensions(&available, &mut enabled);
        let instance = entry
            .create_instance(&super::app_info(), &enabled, &[])
            .map_err(|e| XrError::NoRuntime(e.to_string()))?;
        let runtime = match instance.properties() {
            Ok(p) => format!("{} {}", p.runtime_name, p.runtime_version),
            Err(_) => "(unnamed)".to_owned(),
        };
        if !available.khr_vulkan_enable2 {
            return Err(XrError::NoVulkan { runtime });
        }
        let system = instance
            .system(xr::FormFactor::HEAD_MOUNTED_DISPLAY)
            .map_err(|e| XrError::NoHeadset { runtime: runtime.clone(), reason: e.to_string() })?;
        let requirements = instance
            .graphics_requirements::<xr::Vulkan>(system)
            .map_err(failed("xrGetVulkanGraphicsRequirements2KHR"))?;
        if requirements.min_api_version_supported > xr::Version::new(1, 1, 0) {
            return Err(XrError::Unsupported(format!(
                "the OpenXR runtime {runtime} needs Vulkan {} or newer; Argile uses 1.1",
                requirements.min_api_version_supported
            )));
        }
        let views = instance
            .enumerate_view_configuration_views(system, VIEW_TYPE)
            .map_err(failed("xrEnumerateViewConfigurationViews"))?;
        let [left, right] = views.as_slice() else {
            return Err(XrError::Unsupported(format!(
                "the headset has {} views; Argile draws two",
                views.len()
            )));
        };
        // One 2-layer image for both eyes: both eyes get the larger of the recommended sizes.
        let size = (
            left.recommended_image_rect_width.max(right.recommended_image_rect_width),
            left.recommended_image_rect_height.max(right.recommended_image_rect_height),
        );
        let blend = instance
            .enumerate_environment_blend_modes(system, VIEW_TYPE)
            .map_err(failed("xrEnumerateEnvironmentBlendModes"))?
            .into_iter()
            .next()
            .unwrap_or(xr::EnvironmentBlendMode::OPAQUE);
        let desc = RendererDesc {
            width: size.0,
            height: size.1,
            samples: options.samples,
            validation: options.validation,
            view_passes: None,
        };
        let mut maker = RuntimeVulkan { instance: &instance, system };
        let renderer = Renderer::for_external(&desc, environment, intensity, &mut maker)?;
        let mut station = Self {
            enabled,
            live: None,
            events: xr::EventDataBuffer::new(),
            depth_layers: available.khr_composition_layer_depth,
            instance,
            system,
            blend,
            size,
            runtime,
            finished: false,
            lost: false,
            times: FrameTimes::default(),
            renderer,
        };
        station.live = Some(station.create_session()?);
        tracing::info!("OpenXR session on {} ({}×{} per eye)", station.runtime, size.0, size.1);
        Ok(station)
    }

    /// The size of each eye's image, pixels: the runtime's recommendation.
    pub fn eye_size(&self) -> (u32, u32) {
        self.size
    }

    /// The runtime's name and version.
    pub fn runtime(&self) -> &str {
        &self.runtime
    }

    /// The renderer (upload mesh changes to it).
    pub fn renderer_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }

    /// The renderer.
    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    /// The time split of the last drawn frame.
    pub fn times(&self) -> FrameTimes {
        self.times
    }

    /// The session's state, if one exists.
    pub fn state(&self) -> Option<SessionState> {
        self.live.as_ref().map(|l| l.lifecycle.state())
    }

    /// Whether depth is submitted with the projection layer.
    pub fn submits_depth(&self) -> bool {
        self.live.as_ref().is_some_and(|l| l.depth.is_some())
    }

    fn create_session(&mut self) -> Result<Live, XrError> {
        let h = self.renderer.vulkan_handles();
        let info = xr::vulkan::SessionCreateInfo {
            instance: h.instance.as_raw() as _,
            physical_device: h.physical_device.as_raw() as _,
            device: h.device.as_raw() as _,
            queue_family_index: h.queue_family,
            queue_index: h.queue_index,
        };
        // SAFETY: the handles are the renderer's live instance and device, made by this
        // runtime for this system; the renderer outlives the session (field order, Drop).
        let (session, waiter, stream) =
            unsafe { self.instance.create_session::<xr::Vulkan>(self.system, &info) }
                .map_err(failed("xrCreateSession"))?;
        let spaces = session.enumerate_reference_spaces().map_err(failed("xrEnumerateReferenceSpaces"))?;
        let kind = if spaces.contains(&xr::ReferenceSpaceType::STAGE) {
            xr::ReferenceSpaceType::STAGE
        } else {
            xr::ReferenceSpaceType::LOCAL
        };
        let space = session
            .create_reference_space(kind, xr::Posef::IDENTITY)
            .map_err(failed("xrCreateReferenceSpace"))?;
        let view_space = session
            .create_reference_space(xr::ReferenceSpaceType::VIEW, xr::Posef::IDENTITY)
            .map_err(failed("xrCreateReferenceSpace"))?;
        let hands = Some(Hands::new(&self.instance, &session, &self.enabled)?);
        let formats = session.enumerate_swapchain_formats().map_err(failed("xrEnumerateSwapchainFormats"))?;
        if !formats.contains(&(COLOUR_FORMAT.as_raw() as u32)) {
            return Err(XrError::Unsupported(format!(
                "the OpenXR runtime {} offers no R8G8B8A8_SRGB swapchain, which Argile draws",
                self.runtime
            )));
        }
        let colour = self.chain(&session, COLOUR_FORMAT, xr::SwapchainUsageFlags::COLOR_ATTACHMENT)?;
        let depth_format = self.renderer.depth_format();
        let depth = if self.depth_layers && formats.contains(&(depth_format.as_raw() as u32)) {
            Some(self.chain(&session, depth_format, xr::SwapchainUsageFlags::DEPTH_STENCIL_ATTACHMENT)?)
        } else {
            None
        };
        let stored =
            self.renderer.attach_swapchains(self.size, &colour.images, depth.as_ref().map(|d| &d.images))?;
        // A depth swapchain the renderer cannot draw into (MSAA) is not kept.
        let depth = depth.filter(|_| stored);
        Ok(Live {
            colour,
            depth,
            hands,
            view_space,
            space,
            stream,
            waiter,
            session,
            lifecycle: Lifecycle::new(),
            frames: 0,
        })
    }

    fn chain(
        &self,
        session: &xr::Session<xr::Vulkan>,
        format: vk::Format,
        usage: xr::SwapchainUsageFlags,
    ) -> Result<Chain, XrError> {
        let handle = session
            .create_swapchain(&xr::SwapchainCreateInfo {
                create_flags: xr::SwapchainCreateFlags::EMPTY,
                usage_flags: usage,
                format: format.as_raw() as u32,
                sample_count: 1,
                width: self.size.0,
                height: self.size.1,
                face_count: 1,
                array_size: 2,
                mip_count: 1,
            })
            .map_err(failed("xrCreateSwapchain"))?;
        let images = handle.enumerate_images().map_err(failed("xrEnumerateSwapchainImages"))?;
        let images =
            SwapchainImages { images: images.into_iter().map(vk::Image::from_raw).collect(), format };
        Ok(Chain { handle, images })
    }

    /// Drops the session's handles, the renderer first forgetting their images.
    fn destroy_session(&mut self) {
        self.renderer.detach_swapchains();
        self.live = None;
    }

    /// Asks to quit: the runtime walks the session down (STOPPING, IDLE, EXITING) over the
    /// next turns, which end with [`Turn::Finished`].
    pub fn request_exit(&mut self) -> Result<(), XrError> {
        match &mut self.live {
            Some(live) => {
                if live.lifecycle.request_exit() {
                    live.session.request_exit().map_err(failed("xrRequestExitSession"))?;
                } else {
                    self.finished = true;
                }
                Ok(())
            }
            None => {
                self.finished = true;
                Ok(())
            }
        }
    }

    /// Reads the runtime's events; returns the turn they end with, if any.
    fn poll(&mut self) -> Result<Option<Turn>, XrError> {
        loop {
            let event = self.instance.poll_event(&mut self.events).map_err(failed("xrPollEvent"))?;
            let Some(event) = event else { return Ok(None) };
            let (command, state) = match event {
                xr::Event::SessionStateChanged(e) => {
                    let Some(live) = self.live.as_mut() else { continue };
                    if e.session() != live.session.as_raw() {
                        continue;
                    }
                    let Some(state) = state_of(e.state()) else { continue };
                    let (command, complaint) = live.lifecycle.on_state(state);
                    if let Some(c) = complaint {
                        tracing::warn!("OpenXR: {c}");
                    }
                    (command, Some(state))
                }
                xr::Event::InstanceLossPending(_) => {
                    tracing::warn!("OpenXR: the runtime is going away (instance loss pending)");
                    self.lose_instance();
                    return Ok(Some(Turn::InstanceLost));
                }
                xr::Event::EventsLost(e) => {
                    tracing::warn!("OpenXR: the runtime lost {} events", e.lost_event_count());
                    continue;
                }
                _ => continue,
            };
            tracing::debug!("OpenXR session state {state:?}: {command:?}");
            match command {
                Command::Nothing => {}
                Command::Begin => {
                    if let Some(live) = &self.live {
                        live.session.begin(VIEW_TYPE).map_err(failed("xrBeginSession"))?;
                    }
                }
                Command::End => {
                    if let Some(live) = &self.live {
                        live.session.end().map_err(failed("xrEndSession"))?;
                    }
                }
                Command::SaveAndQuit => {
                    self.destroy_session();
                    self.finished = true;
                    return Ok(Some(Turn::Finished));
                }
                Command::SaveAndRecreate => {
                    self.destroy_session();
                    self.live = Some(self.create_session()?);
                    return Ok(Some(Turn::Recreated));
                }
            }
        }
    }

    /// The instance is lost: the session's handles go (their destruction answers nothing
    /// useful now) and every later turn says so.
    fn lose_instance(&mut self) {
        self.destroy_session();
        self.lost = true;
    }

    /// One turn: reads the runtime's events, then, while the session runs, one frame in
    /// which `step` simulates (given the hands) and returns what to draw. A call answering
    /// `XR_ERROR_INSTANCE_LOST` (a runtime that went away without warning) ends in
    /// [`Turn::InstanceLost`], as the loss-pending event does.
    pub fn turn(
        &mut self,
        step: impl FnOnce(&FrameInput, &mut Renderer) -> FrameOutput,
    ) -> Result<Turn, XrError> {
        match self.turn_or_fail(step) {
            Err(e) if e.is_instance_lost() => {
                tracing::warn!("OpenXR: the runtime went away ({e})");
                self.lose_instance();
                Ok(Turn::InstanceLost)
            }
            other => other,
        }
    }

    fn turn_or_fail(
        &mut self,
        step: impl FnOnce(&FrameInput, &mut Renderer) -> FrameOutput,
    ) -> Result<Turn, XrError> {
        if self.lost {
            return Ok(Turn::InstanceLost);
        }
        if self.finished {
            return Ok(Turn::Finished);
        }
        if let Some(turn) = self.poll()? {
            return Ok(turn);
        }
        let Some(live) = self.live.as_mut() else { return Ok(Turn::Finished) };
        if !live.lifecycle.running() {
            return Ok(Turn::Waiting);
        }
        let state = live.waiter.wait().map_err(failed("xrWaitFrame"))?;
        let waited = Instant::now();
        live.stream.begin().map_err(failed("xrBeginFrame"))?;
        if !state.should_render {
            live.stream.end(state.predicted_display_time, self.blend, &[]).map_err(failed("xrEndFrame"))?;
            live.frames += 1;
            return Ok(Turn::Skipped);
        }
        let colour_index = live.colour.handle.acquire_image().map_err(failed("xrAcquireSwapchainImage"))?;
        live.colour.handle.wait_image(xr::Duration::INFINITE).map_err(failed("xrWaitSwapchainImage"))?;
        let depth_index = match &mut live.depth {
            Some(d) => {
                let i = d.handle.acquire_image().map_err(failed("xrAcquireSwapchainImage"))?;
                d.handle.wait_image(xr::Duration::INFINITE).map_err(failed("xrWaitSwapchainImage"))?;
                Some(i)
            }
            None => None,
        };
        let time = state.predicted_display_time;
        let focused = live.lifecycle.focused();
        let hands = match &live.hands {
            Some(h) => h.read(&live.session, &live.space, time, focused)?,
            None => Default::default(),
        };
        let input_read = Instant::now();
        let head = live
            .view_space
            .locate(&live.space, time)
            .ok()
            .filter(|l| {
                l.location_flags.contains(
                    xr::SpaceLocationFlags::POSITION_VALID | xr::SpaceLocationFlags::ORIENTATION_VALID,
                )
            })
            .map(|l| pose_of(l.pose));
        let input = FrameInput {
            index: live.frames,
            display_time_ns: time.as_nanos(),
            period_s: state.predicted_display_period.as_nanos() as f32 * 1e-9,
            focused,
            head,
            hands,
        };
        let stepped = Instant::now();
        let before_ms = (stepped - waited).as_secs_f64() * 1e3;
        let output = step(&input, &mut self.renderer);
        let step_ms = stepped.elapsed().as_secs_f64() * 1e3;
        let submitting = Instant::now();
        let live = self.live.as_mut().expect("present above");
        let mut frame = output.frame;
        // The hands are located again as late as possible, just before the draw is recorded,
        // and what they hold is drawn where they are now.
        let late = match &live.hands {
            Some(h) if focused => h.locate_grips(&live.space, time)?,
            _ => [None, None],
        };
        let late_located = Instant::now();
        let read = [hands[0].grip, hands[1].grip];
        carry_held(&mut frame, &output.held, &output.placement, read, late);
        if let Some(h) = &live.hands {
            for pulse in &output.haptics {
                h.play(&live.session, pulse)?;
            }
        }
        // Locate the views as late as possible: just before the draw is recorded.
        let (_, located) =
            live.session.locate_views(VIEW_TYPE, time, &live.space).map_err(failed("xrLocateViews"))?;
        let [l, r] = located.as_slice() else {
            return Err(XrError::Unsupported(format!(
                "the runtime located {} views; Argile draws two",
                located.len()
            )));
        };
        let view_of = |v: &xr::View| XrView {
            pose: pose_of(v.pose),
            fov: Fov {
                left: v.fov.angle_left,
                right: v.fov.angle_right,
                up: v.fov.angle_up,
                down: v.fov.angle_down,
            },
        };
        frame.views = stereo_views(&[view_of(l), view_of(r)], &output.placement);
        self.renderer.draw_to_swapchain(&frame, colour_index, depth_index)?;
        live.colour.handle.release_image().map_err(failed("xrReleaseSwapchainImage"))?;
        if let Some(d) = &mut live.depth {
            d.handle.release_image().map_err(failed("xrReleaseSwapchainImage"))?;
        }
        let rect = xr::Rect2Di {
            offset: xr::Offset2Di { x: 0, y: 0 },
            extent: xr::Extent2Di { width: self.size.0 as i32, height: self.size.1 as i32 },
        };
        let depth_infos: Vec<xr::sys::CompositionLayerDepthInfoKHR> = match &live.depth {
            Some(d) => (0..2)
                .map(|eye| xr::sys::CompositionLayerDepthInfoKHR {
                    ty: xr::sys::CompositionLayerDepthInfoKHR::TYPE,
                    next: std::ptr::null(),
                    sub_image: xr::sys::SwapchainSubImage {
                        swapchain: d.handle.as_raw(),
                        image_rect: rect,
                        image_array_index: eye,
                    },
                    min_depth: 0.0,
                    max_depth: 1.0,
                    near_z: super::views::NEAR_M,
                    far_z: super::views::FAR_M,
                })
                .collect(),
            None => Vec::new(),
        };
        let projection_views: Vec<xr::CompositionLayerProjectionView<'_, xr::Vulkan>> = [l, r]
            .iter()
            .enumerate()
            .map(|(eye, v)| {
                let view = xr::CompositionLayerProjectionView::new().pose(v.pose).fov(v.fov).sub_image(
                    xr::SwapchainSubImage::new()
                        .swapchain(&live.colour.handle)
                        .image_array_index(eye as u32)
                        .image_rect(rect),
                );
                match depth_infos.get(eye) {
                    Some(depth) => {
                        let mut raw = view.into_raw();
                        raw.next = std::ptr::from_ref(depth).cast();
                        // SAFETY: the chained depth info lives in `depth_infos` until after
                        // xrEndFrame; the rest is the builder's own valid structure.
                        unsafe { xr::CompositionLayerProjectionView::from_raw(raw) }
                    }
                    None => view,
                }
            })
            .collect();
        let layer = xr::CompositionLayerProjection::new().space(&live.space).views(&projection_views);
        let ending = Instant::now();
        live.stream.end(time, self.blend, &[&layer]).map_err(failed("xrEndFrame"))?;
        live.frames += 1;
        let age_ms = |since: Instant| (ending - since).as_secs_f64() * 1e3;
        self.times = FrameTimes {
            before_ms,
            step_ms,
            submit_ms: submitting.elapsed().as_secs_f64() * 1e3,
            pose_age_ms: age_ms(late_located),
            input_pose_age_ms: age_ms(input_read),
        };
        Ok(Turn::Drawn)
    }
}

impl Drop for XrStation {
    fn drop(&mut self) {
        // OpenXR before Vulkan: the renderer forgets the swapchain images, the session's
        // handles go, then (field order) the instance and the renderer.
        self.destroy_session();
    }
}

/// The loader library for `path`, else the system's (`libopenxr_loader.so.1`, the name the
/// Debian/Ubuntu package installs, then the unversioned name).
pub(super) fn load_from(path: Option<&Path>) -> Result<xr::Entry, String> {
    let candidates: Vec<&Path> = match path {
        Some(p) => vec![p],
        None => vec![Path::new("libopenxr_loader.so.1"), Path::new("libopenxr_loader.so")],
    };
    let mut last = String::new();
    for candidate in candidates {
        // SAFETY: loading an OpenXR loader runs its initialisers; the library named by the
        // OpenXR loader specification is trusted to conform to it, as for any OpenXR app.
        match unsafe { xr::Entry::load_from(candidate) } {
            Ok(entry) => return Ok(entry),
            Err(e) => last = e.to_string(),
        }
    }
    Err(last)
}
