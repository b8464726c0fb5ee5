//! The OpenXR entry points: the instance and its objects, kept in one lock, and the checks a
//! conformant runtime makes of every call (handles, structure types, order).

use crate::log::Log;
use crate::profiles::{ActionKind, Reading};
use crate::script::{EventKind, Pose, Script};
use crate::state::{refuse, state_name, FrameLoop, Lifecycle, Refusal, Ring};
use crate::vk as gvk;
use ash::vk;
use glam::{Quat, Vec3};
use openxr_sys as xr;
use serde_json::json;
use std::collections::{HashMap, VecDeque};
use std::ffi::{c_char, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

pub const RUNTIME_NAME: &str = "Argile XR test runtime";
pub const SYSTEM_ID: u64 = 1;
const SYSTEM_NAME: &str = "Argile simulated headset";
/// The virtual clock's origin; frame `f` is displayed at `T0 + (f + 1) * period`.
const T0: i64 = 1_000_000_000;
const MAX_LAYERS: u32 = 16;
const MAX_IMAGE_SIZE: u32 = 4096;
const SWAPCHAIN_IMAGES: u32 = 3;
pub const FORMATS: [vk::Format; 3] =
    [vk::Format::R8G8B8A8_SRGB, vk::Format::B8G8R8A8_SRGB, vk::Format::D32_SFLOAT];

pub type Outcome = Result<xr::Result, Refusal>;

static NEXT_HANDLE: AtomicU64 = AtomicU64::new(0);

/// A fresh handle value. The loader may unload and reload the runtime between instances, which
/// restarts this counter, so it starts from the clock: a handle kept from an earlier instance
/// does not name an object of a later one.
pub fn new_handle() -> u64 {
    if NEXT_HANDLE.load(Ordering::Relaxed) == 0 {
        let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
        let seed = (now.as_micros() as u64 & 0xffff_ffff_ffff) << 12 | 1;
        let _ = NEXT_HANDLE.compare_exchange(0, seed, Ordering::Relaxed, Ordering::Relaxed);
    }
    NEXT_HANDLE.fetch_add(1, Ordering::Relaxed)
}

/// Everything the runtime holds; one instance at a time, as the loader allows.
pub struct Runtime {
    pub instance: Option<Instance>,
    /// The log of the last instance, for calls made after it was destroyed.
    pub orphan_log: Option<Log>,
}

pub static RUNTIME: Mutex<Runtime> = Mutex::new(Runtime { instance: None, orphan_log: None });

pub enum Event {
    State { session: u64, state: xr::SessionState, time: i64 },
    InstanceLoss { time: i64 },
    ProfileChanged { session: u64 },
}

pub struct Instance {
    pub handle: u64,
    pub vulkan: bool,
    pub depth: bool,
    pub script: Script,
    pub log: Log,
    pub paths: Vec<String>,
    pub events: VecDeque<Event>,
    /// Instance loss has happened: calls answer XR_ERROR_INSTANCE_LOST.
    pub lost: bool,
    pub requirements_queried: bool,
    pub vk_instances: Vec<gvk::Instance>,
    pub vk_devices: Vec<gvk::Device>,
    /// Suggested bindings by interaction profile path: (action, binding path).
    pub suggested: HashMap<&'static str, Vec<(u64, String)>>,
    /// Enabled extensions that add interaction profiles.
    pub profile_extensions: Vec<&'static str>,
    /// When frame 0 of this instance's pace was waited for (`pace = true`).
    pub paced_from: Option<(std::time::Instant, u64)>,
    /// Frames ended and waited for over the instance's life (the script's timeline; an
    /// instance made after the runtime came back resumes it after the lost frame).
    pub frames_ended: u64,
    pub frames_waited: u64,
    pub events_fired: usize,
    pub session: Option<Session>,
    pub spaces: HashMap<u64, Space>,
    pub swapchains: HashMap<u64, Swapchain>,
    pub action_sets: HashMap<u64, crate::actions::ActionSet>,
    pub actions: HashMap<u64, crate::actions::Action>,
}

pub struct Session {
    pub handle: u64,
    pub lifecycle: Lifecycle,
    pub frames: FrameLoop,
    pub gpu: gvk::Gpu,
    pub actions: crate::actions::SessionActions,
}

#[derive(Clone, Copy)]
pub enum SpaceKind {
    Reference(xr::ReferenceSpaceType),
    Action { action: u64, sub: u64 },
}

pub struct Space {
    pub session: u64,
    pub kind: SpaceKind,
    pub offset: Pose,
}

pub struct Swapchain {
    pub session: u64,
    pub ring: Ring,
    pub images: gvk::Images,
}

pub fn result_name(r: xr::Result) -> String {
    format!("XR_{r:?}")
}

/// Results that say the application broke a rule, as opposed to the runtime's or the
/// system's conditions (loss, missing features).
fn is_violation(r: xr::Result) -> bool {
    use xr::Result as R;
    r.into_raw() < 0
        && ![
            R::ERROR_SESSION_LOST,
            R::ERROR_INSTANCE_LOST,
            R::ERROR_FORM_FACTOR_UNAVAILABLE,
            R::ERROR_FORM_FACTOR_UNSUPPORTED,
            R::ERROR_FUNCTION_UNSUPPORTED,
            R::ERROR_EXTENSION_NOT_PRESENT,
            R::ERROR_API_LAYER_NOT_PRESENT,
            R::ERROR_API_VERSION_UNSUPPORTED,
            R::ERROR_RUNTIME_FAILURE,
            R::ERROR_LIMIT_REACHED,
            R::ERROR_FEATURE_UNSUPPORTED,
            R::ERROR_INITIALIZATION_FAILED,
            R::ERROR_RUNTIME_UNAVAILABLE,
        ]
        .contains(&r)
}

pub fn report(log: &mut Log, function: &str, r: &Refusal) {
    if is_violation(r.result) {
        log.violation(function, &result_name(r.result), &r.why);
    } else {
        log.write(
            json!({"kind": "refused", "function": function, "result": result_name(r.result), "why": r.why}),
        );
    }
}

/// Runs an entry point: under the runtime's lock, never unwinding into the caller; refusals
/// are logged.
pub fn run(function: &'static str, f: impl FnOnce(&mut Instance) -> Outcome) -> xr::Result {
    run_global(function, |rt| match rt.instance.as_mut() {
        Some(inst) => match f(inst) {
            Ok(r) => Ok(r),
            Err(refusal) => {
                report(&mut inst.log, function, &refusal);
                Ok(refusal.result)
            }
        },
        None => {
            refuse(xr::Result::ERROR_HANDLE_INVALID, "there is no instance (never created, or destroyed)")
        }
    })
}

/// Like `run`, with the whole runtime (for creating and destroying the instance).
pub fn run_global(function: &'static str, f: impl FnOnce(&mut Runtime) -> Outcome) -> xr::Result {
    let r = catch_unwind(AssertUnwindSafe(|| {
        let mut rt = RUNTIME.lock().unwrap_or_else(PoisonError::into_inner);
        match f(&mut rt) {
            Ok(r) => r,
            Err(refusal) => {
                match rt.orphan_log.as_mut() {
                    Some(log) => report(log, function, &refusal),
                    None => eprintln!(
                        "argile XR test runtime: {function} refused with {}: {}",
                        result_name(refusal.result),
                        refusal.why
                    ),
                }
                refusal.result
            }
        }
    }));
    r.unwrap_or_else(|_| {
        eprintln!("argile XR test runtime: {function} failed inside the runtime (a bug in the runtime)");
        xr::Result::ERROR_RUNTIME_FAILURE
    })
}

// ---------------------------------------------------------------------------------------------
// Pointer and structure checks.

/// Reads an input structure after checking it is there and of the right type.
///
/// # Safety
/// A non-null `p` must point to a structure that starts with an `XrStructureType`.
pub unsafe fn input<'a, T>(p: *const T, ty: xr::StructureType, what: &str) -> Result<&'a T, Refusal> {
    if p.is_null() {
        return refuse(xr::Result::ERROR_VALIDATION_FAILURE, format!("{what} is null"));
    }
    let found = *(p as *const xr::StructureType);
    if found != ty {
        return refuse(
            xr::Result::ERROR_VALIDATION_FAILURE,
            format!("{what} has type {found:?}, not {ty:?}"),
        );
    }
    Ok(&*p)
}

/// Checks an output structure is there and of the right type.
///
/// # Safety
/// As `input`.
pub unsafe fn output<'a, T>(p: *mut T, ty: xr::StructureType, what: &str) -> Result<&'a mut T, Refusal> {
    input(p as *const T, ty, what)?;
    Ok(&mut *p)
}

/// Checks an output pointer to a plain value is there.
pub fn out_ptr<T>(p: *mut T, what: &str) -> Result<(), Refusal> {
    if p.is_null() {
        return refuse(xr::Result::ERROR_VALIDATION_FAILURE, format!("{what} is null"));
    }
    Ok(())
}

/// Finds a structure of type `ty` in a `next` chain.
///
/// # Safety
/// The chain must be made of valid OpenXR structures.
pub unsafe fn find_in_chain(
    mut next: *const std::ffi::c_void,
    ty: xr::StructureType,
) -> Option<*const std::ffi::c_void> {
    while !next.is_null() {
        let base = &*(next as *const xr::BaseInStructure);
        if base.ty == ty {
            return Some(next);
        }
        next = base.next as *const std::ffi::c_void;
    }
    None
}

/// The two-call idiom: writes the count, and the items when there is room.
///
/// # Safety
/// `items` must have room for `capacity` elements when `capacity` is not zero.
pub unsafe fn enumerate<T>(
    capacity: u32,
    count: *mut u32,
    items: *mut T,
    len: usize,
    mut write: impl FnMut(*mut T, usize) -> Result<(), Refusal>,
) -> Outcome {
    out_ptr(count, "the count output")?;
    *count = len as u32;
    if capacity == 0 {
        return Ok(xr::Result::SUCCESS);
    }
    if (capacity as usize) < len {
        return refuse(
            xr::Result::ERROR_SIZE_INSUFFICIENT,
            format!("capacity {capacity} is less than the {len} elements to return"),
        );
    }
    out_ptr(items, "the output array")?;
    for i in 0..len {
        write(items.add(i), i)?;
    }
    Ok(xr::Result::SUCCESS)
}

/// The two-call idiom for plain values.
///
/// # Safety
/// As `enumerate`.
pub unsafe fn enumerate_values<T: Copy>(
    capacity: u32,
    count: *mut u32,
    items: *mut T,
    values: &[T],
) -> Outcome {
    enumerate(capacity, count, items, values.len(), |p, i| {
        *p = values[i];
        Ok(())
    })
}

/// The two-call idiom for a string (with its terminating NUL).
///
/// # Safety
/// As `enumerate`.
pub unsafe fn enumerate_string(capacity: u32, count: *mut u32, buffer: *mut c_char, s: &str) -> Outcome {
    let bytes: Vec<c_char> = s.bytes().chain(std::iter::once(0)).map(|b| b as c_char).collect();
    enumerate_values(capacity, count, buffer, &bytes)
}

/// Copies a string into a fixed-size C array, cut to fit.
pub fn put_str(dst: &mut [c_char], s: &str) {
    let n = s.len().min(dst.len() - 1);
    for (d, b) in dst.iter_mut().zip(s.bytes().take(n)) {
        *d = b as c_char;
    }
    dst[n] = 0;
}

/// Reads a fixed-size C string array.
pub fn get_str(src: &[c_char]) -> Result<String, Refusal> {
    let bytes: Vec<u8> = src.iter().take_while(|&&c| c != 0).map(|&c| c as u8).collect();
    if bytes.len() == src.len() {
        return refuse(xr::Result::ERROR_VALIDATION_FAILURE, "a name is not NUL-terminated");
    }
    String::from_utf8(bytes).map_err(|_| Refusal {
        result: xr::Result::ERROR_VALIDATION_FAILURE,
        why: "a name is not UTF-8".into(),
    })
}

pub fn to_pose(p: &xr::Posef) -> Pose {
    let o = p.orientation;
    Pose::new(Vec3::new(p.position.x, p.position.y, p.position.z), Quat::from_xyzw(o.x, o.y, o.z, o.w))
}

pub fn from_pose(p: &Pose) -> xr::Posef {
    xr::Posef {
        orientation: xr::Quaternionf {
            x: p.orientation.x,
            y: p.orientation.y,
            z: p.orientation.z,
            w: p.orientation.w,
        },
        position: xr::Vector3f { x: p.position.x, y: p.position.y, z: p.position.z },
    }
}

/// A pose the application gives: its orientation must be a unit quaternion.
pub fn checked_pose(p: &xr::Posef, what: &str) -> Result<Pose, Refusal> {
    let pose = to_pose(p);
    let len = pose.orientation.length();
    if !pose.position.is_finite() || !(len - 1.0).abs().lt(&0.01) {
        return refuse(
            xr::Result::ERROR_POSE_INVALID,
            format!(
                "{what} has orientation {:?} of length {len}, not a unit quaternion",
                pose.orientation.to_array()
            ),
        );
    }
    Ok(Pose::new(pose.position, pose.orientation.normalize()))
}

pub fn pose_json(p: &Pose) -> serde_json::Value {
    json!({"position": p.position.to_array(), "orientation": p.orientation.to_array()})
}

// ---------------------------------------------------------------------------------------------
// The instance's helpers.

impl Instance {
    pub fn new(handle: u64, vulkan: bool, depth: bool, script: Script, log: Log) -> Instance {
        Instance {
            handle,
            vulkan,
            depth,
            script,
            log,
            paths: Vec::new(),
            events: VecDeque::new(),
            lost: false,
            requirements_queried: false,
            vk_instances: Vec::new(),
            vk_devices: Vec::new(),
            suggested: HashMap::new(),
            profile_extensions: Vec::new(),
            paced_from: None,
            frames_ended: 0,
            frames_waited: 0,
            events_fired: 0,
            session: None,
            spaces: HashMap::new(),
            swapchains: HashMap::new(),
            action_sets: HashMap::new(),
            actions: HashMap::new(),
        }
    }

    pub fn check(&self, h: xr::Instance) -> Result<(), Refusal> {
        if h.into_raw() != self.handle {
            return refuse(
                xr::Result::ERROR_HANDLE_INVALID,
                format!("XrInstance {:#x} is not a live instance", h.into_raw()),
            );
        }
        if self.lost {
            return refuse(xr::Result::ERROR_INSTANCE_LOST, "the instance was lost; destroy it");
        }
        Ok(())
    }

    pub fn check_system(&self, id: xr::SystemId) -> Result<(), Refusal> {
        if id.into_raw() != SYSTEM_ID {
            return refuse(
                xr::Result::ERROR_SYSTEM_INVALID,
                format!("system {} is not the one xrGetSystem gave", id.into_raw()),
            );
        }
        Ok(())
    }

    /// The session behind a handle (lost sessions included: the caller decides).
    pub fn session_any(&mut self, h: xr::Session) -> Result<&mut Session, Refusal> {
        if self.lost {
            return refuse(xr::Result::ERROR_INSTANCE_LOST, "the instance was lost; destroy it");
        }
        match self.session.as_mut() {
            Some(s) if s.handle == h.into_raw() => Ok(s),
            _ => refuse(
                xr::Result::ERROR_HANDLE_INVALID,
                format!("XrSession {:#x} is not a live session", h.into_raw()),
            ),
        }
    }

    /// The session behind a handle, refusing a lost one.
    pub fn session(&mut self, h: xr::Session) -> Result<&mut Session, Refusal> {
        let s = self.session_any(h)?;
        if s.lifecycle.lost() {
            return refuse(xr::Result::ERROR_SESSION_LOST, "the session was lost; destroy it");
        }
        Ok(s)
    }

    pub fn now(&self) -> i64 {
        self.frame_time(self.frames_ended as f64)
    }

    /// The display time of a (fractional) frame index.
    pub fn frame_time(&self, frame: f64) -> i64 {
        T0 + ((frame + 1.0) * self.script.display_period_ns as f64).round() as i64
    }

    /// The frame index displayed at a time.
    pub fn time_frame(&self, time: i64) -> f64 {
        (time - T0) as f64 / self.script.display_period_ns as f64 - 1.0
    }

    /// The frame in flight: the last one waited for.
    pub fn current_frame(&self) -> u64 {
        self.frames_waited.saturating_sub(1)
    }

    pub fn push_states(&mut self, session: u64, states: Vec<xr::SessionState>) {
        let time = self.now();
        for state in states {
            self.log.write(json!({"kind": "state", "frame": self.frames_ended, "state": state_name(state)}));
            self.events.push_back(Event::State { session, state, time });
        }
    }

    pub fn path_string(&self, p: xr::Path) -> Result<&str, Refusal> {
        let i = p.into_raw();
        if i == 0 || i as usize > self.paths.len() {
            return refuse(
                xr::Result::ERROR_PATH_INVALID,
                format!("XrPath {i} is not a path of this instance"),
            );
        }
        Ok(&self.paths[i as usize - 1])
    }

    pub fn intern(&mut self, s: &str) -> xr::Path {
        let i = match self.paths.iter().position(|p| p == s) {
            Some(i) => i,
            None => {
                self.paths.push(s.to_string());
                self.paths.len() - 1
            }
        };
        xr::Path::from_raw(i as u64 + 1)
    }

    /// The pose of a space in stage space at a time, or `None` where it cannot be located.
    pub fn locate(&self, space: &Space, time: i64) -> Option<Pose> {
        let frame = self.time_frame(time);
        let sample = self.script.sample(frame);
        let base = match space.kind {
            SpaceKind::Reference(xr::ReferenceSpaceType::STAGE) => Pose::IDENTITY,
            SpaceKind::Reference(xr::ReferenceSpaceType::LOCAL) => self.local_origin(),
            SpaceKind::Reference(_) => sample.head,
            SpaceKind::Action { action, sub } => {
                let session = self.session.as_ref()?;
                let source = session.actions.pose_source(action, sub)?;
                match source.input.read(&sample.hands[source.hand.index()]) {
                    Reading::Pose(p) => p,
                    _ => return None,
                }
            }
        };
        Some(base.mul(&space.offset))
    }

    /// LOCAL space: where the head was at the timeline's start, turned only about the vertical.
    pub fn local_origin(&self) -> Pose {
        let head = self.script.sample(0.0).head;
        let forward = head.orientation * Vec3::NEG_Z;
        let yaw = (-forward.x).atan2(-forward.z);
        Pose::new(head.position, Quat::from_rotation_y(yaw))
    }

    /// A space of a live, not lost session.
    pub fn space(&self, h: xr::Space) -> Result<&Space, Refusal> {
        if self.lost {
            return refuse(xr::Result::ERROR_INSTANCE_LOST, "the instance was lost; destroy it");
        }
        let s = self.spaces.get(&h.into_raw()).ok_or_else(|| Refusal {
            result: xr::Result::ERROR_HANDLE_INVALID,
            why: format!("XrSpace {:#x} is not a live space", h.into_raw()),
        })?;
        if self.session.as_ref().is_some_and(|x| x.lifecycle.lost()) {
            return refuse(xr::Result::ERROR_SESSION_LOST, "the space's session was lost");
        }
        Ok(s)
    }

    pub fn swapchain(&mut self, h: xr::Swapchain) -> Result<(&mut Swapchain, &mut Session), Refusal> {
        if self.lost {
            return refuse(xr::Result::ERROR_INSTANCE_LOST, "the instance was lost; destroy it");
        }
        let sc = self.swapchains.get_mut(&h.into_raw()).ok_or_else(|| Refusal {
            result: xr::Result::ERROR_HANDLE_INVALID,
            why: format!("XrSwapchain {:#x} is not a live swapchain", h.into_raw()),
        })?;
        let session = self.session.as_mut().expect("swapchains die with their session");
        if session.lifecycle.lost() {
            return refuse(xr::Result::ERROR_SESSION_LOST, "the swapchain's session was lost");
        }
        Ok((sc, session))
    }

    /// Destroys the session and everything made from it.
    pub fn destroy_session(&mut self) {
        if let Some(s) = self.session.take() {
            for (_, sc) in self.swapchains.drain() {
                sc.images.destroy(&s.gpu);
            }
            self.spaces.clear();
            s.gpu.destroy();
        }
    }

    /// The runtime goes away after the frames ended so far: until `back_after_s` has passed
    /// (never, for `None`) new instances are refused with `XR_ERROR_RUNTIME_UNAVAILABLE`; then
    /// they resume the timeline after this frame. Kept in the output folder, since the
    /// loader unloads the runtime with its last instance.
    fn leave(&mut self, back_after_s: Option<f64>) {
        let back_at_ms = back_after_s.map(|s| unix_ms() + (s * 1e3) as u64);
        let gone = Gone { back_at_ms, resume_frame: self.frames_ended };
        if let Some(path) = gone_path() {
            if let Err(e) = std::fs::write(&path, serde_json::to_string(&gone).unwrap_or_default()) {
                self.log
                    .write(json!({"kind": "error", "why": format!("cannot write {}: {e}", path.display())}));
            }
        }
    }

    /// Runs the script's events due at the end of frame `frame`.
    fn fire_events(&mut self, frame: u64) {
        while let Some(e) = self.script.events.get(self.events_fired).copied() {
            if e.frame > frame {
                break;
            }
            self.events_fired += 1;
            let Some(session) = self.session.as_mut() else { continue };
            let handle = session.handle;
            let states = match e.kind {
                EventKind::SessionLoss => session.lifecycle.lose(),
                EventKind::Exit => session.lifecycle.request_exit(false).unwrap_or_default(),
                EventKind::FocusLost => session.lifecycle.set_focus(false),
                EventKind::FocusGained => session.lifecycle.set_focus(true),
                EventKind::InstanceLoss => {
                    let time = self.now();
                    self.log.write(json!({"kind": "instance_loss", "frame": self.frames_ended}));
                    self.events.push_back(Event::InstanceLoss { time });
                    self.lost = true;
                    self.leave(e.back_after_s);
                    Vec::new()
                }
                EventKind::RuntimeGone => {
                    self.log.write(json!({"kind": "runtime_gone", "frame": self.frames_ended}));
                    self.lost = true;
                    self.leave(e.back_after_s);
                    Vec::new()
                }
            };
            self.push_states(handle, states);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Global commands and the instance.

/// A runtime that went away: when it comes back, and the frame its next instance resumes at.
#[derive(serde::Serialize, serde::Deserialize)]
struct Gone {
    back_at_ms: Option<u64>,
    resume_frame: u64,
}

fn gone_path() -> Option<std::path::PathBuf> {
    std::env::var_os("ARGILE_XR_TEST_OUT").map(|d| std::path::PathBuf::from(d).join("runtime-gone.json"))
}

fn unix_ms() -> u64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_millis() as u64)
}

/// Whether the runtime is away (`Err`), else the frame a new instance starts at.
fn runtime_back() -> Result<u64, Refusal> {
    let Some(text) = gone_path().and_then(|p| std::fs::read_to_string(p).ok()) else { return Ok(0) };
    let Ok(gone) = serde_json::from_str::<Gone>(&text) else { return Ok(0) };
    match gone.back_at_ms {
        Some(at) if unix_ms() >= at => Ok(gone.resume_frame),
        _ => refuse(xr::Result::ERROR_RUNTIME_UNAVAILABLE, "the runtime went away and is not back"),
    }
}

/// The extensions that add interaction profiles, with the profile each adds.
pub const PROFILE_EXTENSIONS: [(&[u8], &str); 3] = [
    (xr::EXT_HP_MIXED_REALITY_CONTROLLER_EXTENSION_NAME, "/interaction_profiles/hp/mixed_reality_controller"),
    (xr::BD_CONTROLLER_INTERACTION_EXTENSION_NAME, "/interaction_profiles/bytedance/pico4_controller"),
    (xr::META_TOUCH_CONTROLLER_PLUS_EXTENSION_NAME, "/interaction_profiles/meta/touch_controller_plus"),
];

fn extensions() -> Vec<(&'static [u8], u32)> {
    let mut v = Vec::new();
    if std::env::var_os("ARGILE_XR_TEST_NO_VULKAN").is_none() {
        v.push((xr::KHR_VULKAN_ENABLE2_EXTENSION_NAME, 2));
    }
    v.push((xr::KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME, 6));
    v.extend(PROFILE_EXTENSIONS.iter().map(|(name, _)| (*name, 1)));
    v
}

fn ext_name(e: &[u8]) -> &str {
    std::str::from_utf8(&e[..e.len() - 1]).expect("extension names are ASCII")
}

pub(crate) unsafe extern "system" fn enumerate_api_layer_properties(
    capacity: u32,
    count: *mut u32,
    props: *mut xr::ApiLayerProperties,
) -> xr::Result {
    run_global("xrEnumerateApiLayerProperties", |_| enumerate(capacity, count, props, 0, |_, _| Ok(())))
}

pub(crate) unsafe extern "system" fn enumerate_instance_extension_properties(
    layer: *const c_char,
    capacity: u32,
    count: *mut u32,
    props: *mut xr::ExtensionProperties,
) -> xr::Result {
    run_global("xrEnumerateInstanceExtensionProperties", |_| {
        if !layer.is_null() {
            return refuse(xr::Result::ERROR_API_LAYER_NOT_PRESENT, "the runtime has no API layers");
        }
        let exts = extensions();
        enumerate(capacity, count, props, exts.len(), |p, i| {
            let p = output(p, xr::StructureType::EXTENSION_PROPERTIES, "XrExtensionProperties")?;
            put_str(&mut p.extension_name, ext_name(exts[i].0));
            p.extension_version = exts[i].1;
            Ok(())
        })
    })
}

pub(crate) unsafe extern "system" fn create_instance(
    info: *const xr::InstanceCreateInfo,
    out: *mut xr::Instance,
) -> xr::Result {
    run_global("xrCreateInstance", |rt| {
        let info = input(info, xr::StructureType::INSTANCE_CREATE_INFO, "XrInstanceCreateInfo")?;
        out_ptr(out, "the instance output")?;
        if rt.instance.is_some() {
            return refuse(xr::Result::ERROR_LIMIT_REACHED, "the runtime serves one instance at a time");
        }
        let v = info.application_info.api_version;
        if v.major() != 1 || v.minor() != 0 {
            return refuse(
                xr::Result::ERROR_API_VERSION_UNSUPPORTED,
                format!(
                    "the application asks for OpenXR {}.{}; the runtime implements 1.0",
                    v.major(),
                    v.minor()
                ),
            );
        }
        if info.enabled_api_layer_count > 0 {
            return refuse(xr::Result::ERROR_API_LAYER_NOT_PRESENT, "the runtime has no API layers");
        }
        let resume_frame = runtime_back()?;
        let offered = extensions();
        let (mut vulkan, mut depth) = (false, false);
        let mut profile_extensions = Vec::new();
        for i in 0..info.enabled_extension_count as usize {
            let name = CStr::from_ptr(*info.enabled_extension_names.add(i)).to_bytes_with_nul();
            if !offered.iter().any(|(e, _)| *e == name) {
                return refuse(
                    xr::Result::ERROR_EXTENSION_NOT_PRESENT,
                    format!("extension {} is not offered", String::from_utf8_lossy(&name[..name.len() - 1])),
                );
            }
            vulkan |= name == xr::KHR_VULKAN_ENABLE2_EXTENSION_NAME;
            depth |= name == xr::KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME;
            profile_extensions.extend(PROFILE_EXTENSIONS.iter().filter(|(e, _)| *e == name).map(|(_, p)| *p));
        }
        let script = match std::env::var_os("ARGILE_XR_TEST_SCRIPT") {
            Some(p) => Script::load(std::path::Path::new(&p)),
            None => Ok(Script::default()),
        };
        let out_dir = std::env::var_os("ARGILE_XR_TEST_OUT").map(std::path::PathBuf::from);
        let mut log =
            Log::open(out_dir).map_err(|why| Refusal { result: xr::Result::ERROR_RUNTIME_FAILURE, why })?;
        let script = match script {
            Ok(s) => s,
            Err(why) => {
                log.write(json!({"kind": "error", "why": why}));
                return refuse(xr::Result::ERROR_RUNTIME_FAILURE, why);
            }
        };
        let handle = new_handle();
        log.write(json!({"kind": "instance", "application": get_str(&info.application_info.application_name)?, "vulkan_enable2": vulkan, "depth": depth}));
        rt.orphan_log = None;
        let mut instance = Instance::new(handle, vulkan, depth, script, log);
        instance.profile_extensions = profile_extensions;
        if resume_frame > 0 {
            instance.log.write(json!({"kind": "runtime_back", "frame": resume_frame}));
            instance.frames_ended = resume_frame;
            instance.frames_waited = resume_frame;
            instance.events_fired = instance.script.events.iter().filter(|e| e.frame < resume_frame).count();
        }
        rt.instance = Some(instance);
        *out = xr::Instance::from_raw(handle);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn destroy_instance(instance: xr::Instance) -> xr::Result {
    run_global("xrDestroyInstance", |rt| {
        match rt.instance.as_ref() {
            Some(i) if i.handle == instance.into_raw() => {}
            _ => {
                return refuse(
                    xr::Result::ERROR_HANDLE_INVALID,
                    format!("XrInstance {:#x} is not a live instance", instance.into_raw()),
                )
            }
        }
        let mut inst = rt.instance.take().expect("checked above");
        inst.destroy_session();
        inst.log.write(json!({"kind": "instance_destroyed"}));
        rt.orphan_log = Some(inst.log);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn get_instance_properties(
    instance: xr::Instance,
    props: *mut xr::InstanceProperties,
) -> xr::Result {
    run("xrGetInstanceProperties", |inst| {
        inst.check(instance)?;
        let p = output(props, xr::StructureType::INSTANCE_PROPERTIES, "XrInstanceProperties")?;
        p.runtime_version = xr::Version::new(0, 1, 0);
        put_str(&mut p.runtime_name, RUNTIME_NAME);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn poll_event(
    instance: xr::Instance,
    buffer: *mut xr::EventDataBuffer,
) -> xr::Result {
    run("xrPollEvent", |inst| {
        if instance.into_raw() != inst.handle {
            return refuse(
                xr::Result::ERROR_HANDLE_INVALID,
                format!("XrInstance {:#x} is not a live instance", instance.into_raw()),
            );
        }
        let buffer = output(buffer, xr::StructureType::EVENT_DATA_BUFFER, "XrEventDataBuffer")?;
        // Polling keeps working after an instance loss, so the application is sure to see the
        // loss event; every other call then answers XR_ERROR_INSTANCE_LOST.
        let Some(event) = inst.events.pop_front() else { return Ok(xr::Result::EVENT_UNAVAILABLE) };
        let p = buffer as *mut xr::EventDataBuffer;
        match event {
            Event::State { session, state, time } => {
                (p as *mut xr::EventDataSessionStateChanged).write(xr::EventDataSessionStateChanged {
                    ty: xr::StructureType::EVENT_DATA_SESSION_STATE_CHANGED,
                    next: std::ptr::null(),
                    session: xr::Session::from_raw(session),
                    state,
                    time: xr::Time::from_nanos(time),
                })
            }
            Event::InstanceLoss { time } => {
                (p as *mut xr::EventDataInstanceLossPending).write(xr::EventDataInstanceLossPending {
                    ty: xr::StructureType::EVENT_DATA_INSTANCE_LOSS_PENDING,
                    next: std::ptr::null(),
                    loss_time: xr::Time::from_nanos(time),
                })
            }
            Event::ProfileChanged { session } => (p as *mut xr::EventDataInteractionProfileChanged).write(
                xr::EventDataInteractionProfileChanged {
                    ty: xr::StructureType::EVENT_DATA_INTERACTION_PROFILE_CHANGED,
                    next: std::ptr::null(),
                    session: xr::Session::from_raw(session),
                },
            ),
        }
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn result_to_string(
    instance: xr::Instance,
    value: xr::Result,
    buffer: *mut c_char,
) -> xr::Result {
    run("xrResultToString", |inst| {
        inst.check(instance)?;
        out_ptr(buffer, "the string buffer")?;
        put_str(std::slice::from_raw_parts_mut(buffer, xr::MAX_RESULT_STRING_SIZE), &result_name(value));
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn structure_type_to_string(
    instance: xr::Instance,
    value: xr::StructureType,
    buffer: *mut c_char,
) -> xr::Result {
    run("xrStructureTypeToString", |inst| {
        inst.check(instance)?;
        out_ptr(buffer, "the string buffer")?;
        put_str(
            std::slice::from_raw_parts_mut(buffer, xr::MAX_STRUCTURE_NAME_SIZE),
            &format!("XR_TYPE_{value:?}"),
        );
        Ok(xr::Result::SUCCESS)
    })
}

// ---------------------------------------------------------------------------------------------
// System and view configuration.

pub(crate) unsafe extern "system" fn get_system(
    instance: xr::Instance,
    info: *const xr::SystemGetInfo,
    id: *mut xr::SystemId,
) -> xr::Result {
    run("xrGetSystem", |inst| {
        inst.check(instance)?;
        let info = input(info, xr::StructureType::SYSTEM_GET_INFO, "XrSystemGetInfo")?;
        out_ptr(id, "the system id output")?;
        if info.form_factor != xr::FormFactor::HEAD_MOUNTED_DISPLAY {
            return refuse(
                xr::Result::ERROR_FORM_FACTOR_UNSUPPORTED,
                "the runtime simulates a head-mounted display only",
            );
        }
        if std::env::var_os("ARGILE_XR_TEST_NO_HMD").is_some() {
            return refuse(
                xr::Result::ERROR_FORM_FACTOR_UNAVAILABLE,
                "no headset is connected (ARGILE_XR_TEST_NO_HMD)",
            );
        }
        *id = xr::SystemId::from_raw(SYSTEM_ID);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn get_system_properties(
    instance: xr::Instance,
    id: xr::SystemId,
    props: *mut xr::SystemProperties,
) -> xr::Result {
    run("xrGetSystemProperties", |inst| {
        inst.check(instance)?;
        inst.check_system(id)?;
        let p = output(props, xr::StructureType::SYSTEM_PROPERTIES, "XrSystemProperties")?;
        p.system_id = id;
        p.vendor_id = 0x4172;
        put_str(&mut p.system_name, SYSTEM_NAME);
        p.graphics_properties = xr::SystemGraphicsProperties {
            max_swapchain_image_height: MAX_IMAGE_SIZE,
            max_swapchain_image_width: MAX_IMAGE_SIZE,
            max_layer_count: MAX_LAYERS,
        };
        p.tracking_properties =
            xr::SystemTrackingProperties { orientation_tracking: xr::TRUE, position_tracking: xr::TRUE };
        Ok(xr::Result::SUCCESS)
    })
}

fn check_view_configuration(ty: xr::ViewConfigurationType) -> Result<(), Refusal> {
    if ty != xr::ViewConfigurationType::PRIMARY_STEREO {
        return refuse(
            xr::Result::ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED,
            format!("{ty:?} is not offered; only PRIMARY_STEREO"),
        );
    }
    Ok(())
}

pub(crate) unsafe extern "system" fn enumerate_environment_blend_modes(
    instance: xr::Instance,
    id: xr::SystemId,
    view: xr::ViewConfigurationType,
    capacity: u32,
    count: *mut u32,
    modes: *mut xr::EnvironmentBlendMode,
) -> xr::Result {
    run("xrEnumerateEnvironmentBlendModes", |inst| {
        inst.check(instance)?;
        inst.check_system(id)?;
        check_view_configuration(view)?;
        enumerate_values(capacity, count, modes, &[xr::EnvironmentBlendMode::OPAQUE])
    })
}

pub(crate) unsafe extern "system" fn enumerate_view_configurations(
    instance: xr::Instance,
    id: xr::SystemId,
    capacity: u32,
    count: *mut u32,
    types: *mut xr::ViewConfigurationType,
) -> xr::Result {
    run("xrEnumerateViewConfigurations", |inst| {
        inst.check(instance)?;
        inst.check_system(id)?;
        enumerate_values(capacity, count, types, &[xr::ViewConfigurationType::PRIMARY_STEREO])
    })
}

pub(crate) unsafe extern "system" fn get_view_configuration_properties(
    instance: xr::Instance,
    id: xr::SystemId,
    view: xr::ViewConfigurationType,
    props: *mut xr::ViewConfigurationProperties,
) -> xr::Result {
    run("xrGetViewConfigurationProperties", |inst| {
        inst.check(instance)?;
        inst.check_system(id)?;
        check_view_configuration(view)?;
        let p =
            output(props, xr::StructureType::VIEW_CONFIGURATION_PROPERTIES, "XrViewConfigurationProperties")?;
        p.view_configuration_type = view;
        p.fov_mutable = xr::FALSE;
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn enumerate_view_configuration_views(
    instance: xr::Instance,
    id: xr::SystemId,
    view: xr::ViewConfigurationType,
    capacity: u32,
    count: *mut u32,
    views: *mut xr::ViewConfigurationView,
) -> xr::Result {
    run("xrEnumerateViewConfigurationViews", |inst| {
        inst.check(instance)?;
        inst.check_system(id)?;
        check_view_configuration(view)?;
        // The runtime's own choice wins over the script's, as a real headset's does.
        let [w, h] = view_size_override().unwrap_or(inst.script.recommended_size);
        enumerate(capacity, count, views, 2, |p, _| {
            let p = output(p, xr::StructureType::VIEW_CONFIGURATION_VIEW, "XrViewConfigurationView")?;
            p.recommended_image_rect_width = w;
            p.recommended_image_rect_height = h;
            p.max_image_rect_width = MAX_IMAGE_SIZE;
            p.max_image_rect_height = MAX_IMAGE_SIZE;
            p.recommended_swapchain_sample_count = 1;
            p.max_swapchain_sample_count = 1;
            Ok(())
        })
    })
}

/// `ARGILE_XR_TEST_VIEW_SIZE=WxH`: the view size the runtime recommends whatever the script says.
fn view_size_override() -> Option<[u32; 2]> {
    let v = std::env::var("ARGILE_XR_TEST_VIEW_SIZE").ok()?;
    let (w, h) = v.split_once('x')?;
    let size = [w.parse().ok()?, h.parse().ok()?];
    size.iter().all(|s| (1..=4096).contains(s)).then_some(size)
}

// ---------------------------------------------------------------------------------------------
// XR_KHR_vulkan_enable2.

fn check_vulkan(inst: &Instance) -> Result<(), Refusal> {
    if !inst.vulkan {
        return refuse(xr::Result::ERROR_FUNCTION_UNSUPPORTED, "XR_KHR_vulkan_enable2 was not enabled");
    }
    Ok(())
}

pub(crate) unsafe extern "system" fn get_vulkan_graphics_requirements2(
    instance: xr::Instance,
    id: xr::SystemId,
    reqs: *mut xr::GraphicsRequirementsVulkanKHR,
) -> xr::Result {
    run("xrGetVulkanGraphicsRequirements2KHR", |inst| {
        inst.check(instance)?;
        check_vulkan(inst)?;
        inst.check_system(id)?;
        let r = output(
            reqs,
            xr::StructureType::GRAPHICS_REQUIREMENTS_VULKAN_KHR,
            "XrGraphicsRequirementsVulkanKHR",
        )?;
        r.min_api_version_supported = xr::Version::new(1, 1, 0);
        r.max_api_version_supported = xr::Version::new(1, 3, 0);
        inst.requirements_queried = true;
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn create_vulkan_instance(
    instance: xr::Instance,
    info: *const xr::VulkanInstanceCreateInfoKHR,
    vk_instance: *mut xr::platform::VkInstance,
    vk_result: *mut xr::platform::VkResult,
) -> xr::Result {
    run("xrCreateVulkanInstanceKHR", |inst| {
        inst.check(instance)?;
        check_vulkan(inst)?;
        let info =
            input(info, xr::StructureType::VULKAN_INSTANCE_CREATE_INFO_KHR, "XrVulkanInstanceCreateInfoKHR")?;
        inst.check_system(info.system_id)?;
        out_ptr(vk_instance, "the VkInstance output")?;
        out_ptr(vk_result, "the VkResult output")?;
        let Some(gipa) = info.pfn_get_instance_proc_addr else {
            return refuse(xr::Result::ERROR_VALIDATION_FAILURE, "pfnGetInstanceProcAddr is null");
        };
        if info.vulkan_create_info.is_null() {
            return refuse(xr::Result::ERROR_VALIDATION_FAILURE, "vulkanCreateInfo is null");
        }
        if (*(info.vulkan_create_info as *const vk::InstanceCreateInfo)).s_type
            != vk::StructureType::INSTANCE_CREATE_INFO
        {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                "vulkanCreateInfo is not a VkInstanceCreateInfo",
            );
        }
        if info.create_flags != xr::VulkanInstanceCreateFlagsKHR::EMPTY {
            return refuse(xr::Result::ERROR_VALIDATION_FAILURE, "createFlags must be 0");
        }
        // SAFETY: both signatures are vkGetInstanceProcAddr's.
        let gipa: vk::PFN_vkGetInstanceProcAddr = std::mem::transmute(gipa);
        match gvk::create_instance(
            gipa,
            info.vulkan_create_info as *const _,
            info.vulkan_allocator as *const _,
        ) {
            Ok(made) => {
                *vk_instance =
                    vk::Handle::as_raw(made.instance.handle()) as usize as xr::platform::VkInstance;
                *vk_result = 0;
                inst.vk_instances.push(made);
            }
            Err(e) => *vk_result = e.as_raw(),
        }
        Ok(xr::Result::SUCCESS)
    })
}

fn raw<T: vk::Handle>(h: T) -> u64 {
    h.as_raw()
}

pub(crate) unsafe extern "system" fn get_vulkan_graphics_device2(
    instance: xr::Instance,
    info: *const xr::VulkanGraphicsDeviceGetInfoKHR,
    physical: *mut xr::platform::VkPhysicalDevice,
) -> xr::Result {
    run("xrGetVulkanGraphicsDevice2KHR", |inst| {
        inst.check(instance)?;
        check_vulkan(inst)?;
        let info = input(
            info,
            xr::StructureType::VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR,
            "XrVulkanGraphicsDeviceGetInfoKHR",
        )?;
        inst.check_system(info.system_id)?;
        out_ptr(physical, "the VkPhysicalDevice output")?;
        let wanted = info.vulkan_instance as usize as u64;
        let Some(made) = inst.vk_instances.iter_mut().find(|i| raw(i.instance.handle()) == wanted) else {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                "vulkanInstance was not created with xrCreateVulkanInstanceKHR",
            );
        };
        let device = gvk::physical_device(&made.instance)
            .map_err(|why| Refusal { result: xr::Result::ERROR_RUNTIME_FAILURE, why })?;
        made.physical = Some(device);
        *physical = raw(device) as usize as xr::platform::VkPhysicalDevice;
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn create_vulkan_device(
    instance: xr::Instance,
    info: *const xr::VulkanDeviceCreateInfoKHR,
    vk_device: *mut xr::platform::VkDevice,
    vk_result: *mut xr::platform::VkResult,
) -> xr::Result {
    run("xrCreateVulkanDeviceKHR", |inst| {
        inst.check(instance)?;
        check_vulkan(inst)?;
        let info =
            input(info, xr::StructureType::VULKAN_DEVICE_CREATE_INFO_KHR, "XrVulkanDeviceCreateInfoKHR")?;
        inst.check_system(info.system_id)?;
        out_ptr(vk_device, "the VkDevice output")?;
        out_ptr(vk_result, "the VkResult output")?;
        if info.pfn_get_instance_proc_addr.is_none() || info.vulkan_create_info.is_null() {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                "pfnGetInstanceProcAddr or vulkanCreateInfo is null",
            );
        }
        if (*(info.vulkan_create_info as *const vk::DeviceCreateInfo)).s_type
            != vk::StructureType::DEVICE_CREATE_INFO
        {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                "vulkanCreateInfo is not a VkDeviceCreateInfo",
            );
        }
        if info.create_flags != xr::VulkanDeviceCreateFlagsKHR::EMPTY {
            return refuse(xr::Result::ERROR_VALIDATION_FAILURE, "createFlags must be 0");
        }
        let wanted = info.vulkan_physical_device as usize as u64;
        let Some(made) = inst.vk_instances.iter().find(|i| i.physical.is_some_and(|p| raw(p) == wanted))
        else {
            return refuse(
                xr::Result::ERROR_HANDLE_INVALID,
                "vulkanPhysicalDevice is not the one xrGetVulkanGraphicsDevice2KHR returned",
            );
        };
        let physical = made.physical.expect("found by it");
        match gvk::create_device(
            made,
            physical,
            info.vulkan_create_info as *const _,
            info.vulkan_allocator as *const _,
        ) {
            Ok(device) => {
                *vk_device = raw(device.device.handle()) as usize as xr::platform::VkDevice;
                *vk_result = 0;
                inst.vk_devices.push(device);
            }
            Err(e) => *vk_result = e.as_raw(),
        }
        Ok(xr::Result::SUCCESS)
    })
}

// ---------------------------------------------------------------------------------------------
// Sessions.

pub(crate) unsafe extern "system" fn create_session(
    instance: xr::Instance,
    info: *const xr::SessionCreateInfo,
    out: *mut xr::Session,
) -> xr::Result {
    run("xrCreateSession", |inst| {
        inst.check(instance)?;
        let info = input(info, xr::StructureType::SESSION_CREATE_INFO, "XrSessionCreateInfo")?;
        inst.check_system(info.system_id)?;
        out_ptr(out, "the session output")?;
        if inst.session.is_some() {
            return refuse(xr::Result::ERROR_LIMIT_REACHED, "the runtime serves one session at a time");
        }
        let binding = find_in_chain(info.next, xr::StructureType::GRAPHICS_BINDING_VULKAN_KHR);
        let (true, Some(binding)) = (inst.vulkan, binding) else {
            return refuse(
                xr::Result::ERROR_GRAPHICS_DEVICE_INVALID,
                "no XrGraphicsBindingVulkan2KHR in the next chain (with XR_KHR_vulkan_enable2 enabled); the runtime offers no headless sessions",
            );
        };
        if !inst.requirements_queried {
            return refuse(
                xr::Result::ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING,
                "xrGetVulkanGraphicsRequirements2KHR was not called before xrCreateSession",
            );
        }
        let b = &*(binding as *const xr::GraphicsBindingVulkanKHR);
        let device = b.device as usize as u64;
        let Some(d) = inst.vk_devices.iter().find(|d| raw(d.device.handle()) == device) else {
            return refuse(
                xr::Result::ERROR_GRAPHICS_DEVICE_INVALID,
                "the binding's device was not created with xrCreateVulkanDeviceKHR",
            );
        };
        if raw(d.physical) != b.physical_device as usize as u64
            || raw(d.instance.handle()) != b.instance as usize as u64
        {
            return refuse(
                xr::Result::ERROR_GRAPHICS_DEVICE_INVALID,
                "the binding's instance or physical device is not the one its device was made from",
            );
        }
        let families = d.instance.get_physical_device_queue_family_properties(d.physical);
        if families.get(b.queue_family_index as usize).is_none_or(|f| b.queue_index >= f.queue_count) {
            return refuse(
                xr::Result::ERROR_GRAPHICS_DEVICE_INVALID,
                format!(
                    "queue {} of family {} does not exist on the device",
                    b.queue_index, b.queue_family_index
                ),
            );
        }
        let gpu = gvk::Gpu::new(d, b.queue_family_index, b.queue_index)
            .map_err(|why| Refusal { result: xr::Result::ERROR_RUNTIME_FAILURE, why })?;
        let handle = new_handle();
        let (lifecycle, states) = Lifecycle::new();
        inst.session = Some(Session {
            handle,
            lifecycle,
            frames: FrameLoop::default(),
            gpu,
            actions: Default::default(),
        });
        inst.push_states(handle, states);
        *out = xr::Session::from_raw(handle);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn destroy_session(session: xr::Session) -> xr::Result {
    run("xrDestroySession", |inst| {
        match inst.session.as_ref() {
            Some(s) if s.handle == session.into_raw() => {}
            _ => {
                return refuse(
                    xr::Result::ERROR_HANDLE_INVALID,
                    format!("XrSession {:#x} is not a live session", session.into_raw()),
                )
            }
        }
        inst.destroy_session();
        // Queued events about the destroyed session are not delivered.
        inst.events.retain(|e| match e {
            Event::State { session: s, .. } | Event::ProfileChanged { session: s } => {
                *s != session.into_raw()
            }
            Event::InstanceLoss { .. } => true,
        });
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn begin_session(
    session: xr::Session,
    info: *const xr::SessionBeginInfo,
) -> xr::Result {
    run("xrBeginSession", |inst| {
        let s = inst.session(session)?;
        let info = input(info, xr::StructureType::SESSION_BEGIN_INFO, "XrSessionBeginInfo")?;
        check_view_configuration(info.primary_view_configuration_type)?;
        s.lifecycle.begin()?;
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn end_session(session: xr::Session) -> xr::Result {
    run("xrEndSession", |inst| {
        let s = inst.session(session)?;
        let states = s.lifecycle.end()?;
        s.frames = FrameLoop::default();
        inst.push_states(session.into_raw(), states);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn request_exit_session(session: xr::Session) -> xr::Result {
    run("xrRequestExitSession", |inst| {
        let s = inst.session(session)?;
        let states = s.lifecycle.request_exit(true)?;
        inst.push_states(session.into_raw(), states);
        Ok(xr::Result::SUCCESS)
    })
}

// ---------------------------------------------------------------------------------------------
// Spaces.

const REFERENCE_SPACES: [xr::ReferenceSpaceType; 3] =
    [xr::ReferenceSpaceType::VIEW, xr::ReferenceSpaceType::LOCAL, xr::ReferenceSpaceType::STAGE];

pub(crate) unsafe extern "system" fn enumerate_reference_spaces(
    session: xr::Session,
    capacity: u32,
    count: *mut u32,
    spaces: *mut xr::ReferenceSpaceType,
) -> xr::Result {
    run("xrEnumerateReferenceSpaces", |inst| {
        inst.session(session)?;
        enumerate_values(capacity, count, spaces, &REFERENCE_SPACES)
    })
}

fn check_reference_space(ty: xr::ReferenceSpaceType) -> Result<(), Refusal> {
    if !REFERENCE_SPACES.contains(&ty) {
        return refuse(
            xr::Result::ERROR_REFERENCE_SPACE_UNSUPPORTED,
            format!("reference space {ty:?} is not offered"),
        );
    }
    Ok(())
}

pub(crate) unsafe extern "system" fn create_reference_space(
    session: xr::Session,
    info: *const xr::ReferenceSpaceCreateInfo,
    out: *mut xr::Space,
) -> xr::Result {
    run("xrCreateReferenceSpace", |inst| {
        inst.session(session)?;
        let info = input(info, xr::StructureType::REFERENCE_SPACE_CREATE_INFO, "XrReferenceSpaceCreateInfo")?;
        out_ptr(out, "the space output")?;
        check_reference_space(info.reference_space_type)?;
        let offset = checked_pose(&info.pose_in_reference_space, "poseInReferenceSpace")?;
        let handle = new_handle();
        inst.spaces.insert(
            handle,
            Space {
                session: session.into_raw(),
                kind: SpaceKind::Reference(info.reference_space_type),
                offset,
            },
        );
        *out = xr::Space::from_raw(handle);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn get_reference_space_bounds_rect(
    session: xr::Session,
    ty: xr::ReferenceSpaceType,
    bounds: *mut xr::Extent2Df,
) -> xr::Result {
    run("xrGetReferenceSpaceBoundsRect", |inst| {
        inst.session(session)?;
        check_reference_space(ty)?;
        out_ptr(bounds, "the bounds output")?;
        if ty == xr::ReferenceSpaceType::STAGE {
            *bounds = xr::Extent2Df { width: 2.5, height: 2.5 };
            Ok(xr::Result::SUCCESS)
        } else {
            *bounds = xr::Extent2Df { width: 0.0, height: 0.0 };
            Ok(xr::Result::SPACE_BOUNDS_UNAVAILABLE)
        }
    })
}

pub(crate) unsafe extern "system" fn create_action_space(
    session: xr::Session,
    info: *const xr::ActionSpaceCreateInfo,
    out: *mut xr::Space,
) -> xr::Result {
    run("xrCreateActionSpace", |inst| {
        inst.session(session)?;
        let info = input(info, xr::StructureType::ACTION_SPACE_CREATE_INFO, "XrActionSpaceCreateInfo")?;
        out_ptr(out, "the space output")?;
        crate::actions::check_action_of_kind(
            inst,
            session,
            info.action,
            info.subaction_path,
            ActionKind::Pose,
            false,
        )?;
        let offset = checked_pose(&info.pose_in_action_space, "poseInActionSpace")?;
        let handle = new_handle();
        inst.spaces.insert(
            handle,
            Space {
                session: session.into_raw(),
                kind: SpaceKind::Action {
                    action: info.action.into_raw(),
                    sub: info.subaction_path.into_raw(),
                },
                offset,
            },
        );
        *out = xr::Space::from_raw(handle);
        Ok(xr::Result::SUCCESS)
    })
}

fn check_time(time: i64) -> Result<(), Refusal> {
    if time <= 0 {
        return refuse(xr::Result::ERROR_TIME_INVALID, format!("time {time} is not a valid XrTime"));
    }
    Ok(())
}

pub(crate) unsafe extern "system" fn locate_space(
    space: xr::Space,
    base: xr::Space,
    time: xr::Time,
    location: *mut xr::SpaceLocation,
) -> xr::Result {
    run("xrLocateSpace", |inst| {
        let s = inst.space(space)?;
        let b = inst.space(base)?;
        check_time(time.as_nanos())?;
        let loc = output(location, xr::StructureType::SPACE_LOCATION, "XrSpaceLocation")?;
        let t = time.as_nanos();
        let located = inst.locate(s, t).zip(inst.locate(b, t)).map(|(sp, bp)| bp.inverse().mul(&sp));
        let velocity =
            find_in_chain(loc.next, xr::StructureType::SPACE_VELOCITY).map(|v| v as *mut xr::SpaceVelocity);
        match located {
            Some(pose) => {
                loc.pose = from_pose(&pose);
                loc.location_flags = xr::SpaceLocationFlags::ORIENTATION_VALID
                    | xr::SpaceLocationFlags::POSITION_VALID
                    | xr::SpaceLocationFlags::ORIENTATION_TRACKED
                    | xr::SpaceLocationFlags::POSITION_TRACKED;
                if let Some(v) = velocity {
                    // Linear velocity by the change over one display period; angular not given.
                    let dt = inst.script.display_period_ns;
                    let before = inst
                        .locate(s, t - dt)
                        .zip(inst.locate(b, t - dt))
                        .map(|(sp, bp)| bp.inverse().mul(&sp));
                    let lin = before
                        .map(|p| (pose.position - p.position) / (dt as f32 * 1e-9))
                        .unwrap_or(Vec3::ZERO);
                    (*v).linear_velocity = xr::Vector3f { x: lin.x, y: lin.y, z: lin.z };
                    (*v).angular_velocity = xr::Vector3f::default();
                    (*v).velocity_flags = xr::SpaceVelocityFlags::LINEAR_VALID;
                }
            }
            None => {
                loc.location_flags = xr::SpaceLocationFlags::EMPTY;
                if let Some(v) = velocity {
                    (*v).velocity_flags = xr::SpaceVelocityFlags::EMPTY;
                }
            }
        }
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn destroy_space(space: xr::Space) -> xr::Result {
    run("xrDestroySpace", |inst| match inst.spaces.remove(&space.into_raw()) {
        Some(_) => Ok(xr::Result::SUCCESS),
        None => refuse(
            xr::Result::ERROR_HANDLE_INVALID,
            format!("XrSpace {:#x} is not a live space", space.into_raw()),
        ),
    })
}

pub(crate) unsafe extern "system" fn locate_views(
    session: xr::Session,
    info: *const xr::ViewLocateInfo,
    state: *mut xr::ViewState,
    capacity: u32,
    count: *mut u32,
    views: *mut xr::View,
) -> xr::Result {
    run("xrLocateViews", |inst| {
        inst.session(session)?;
        let info = input(info, xr::StructureType::VIEW_LOCATE_INFO, "XrViewLocateInfo")?;
        check_view_configuration(info.view_configuration_type)?;
        check_time(info.display_time.as_nanos())?;
        let base = inst.space(info.space)?;
        let state = output(state, xr::StructureType::VIEW_STATE, "XrViewState")?;
        let t = info.display_time.as_nanos();
        let head = inst.script.sample(inst.time_frame(t)).head;
        let base_pose = inst.locate(base, t);
        state.view_state_flags = if base_pose.is_some() {
            xr::ViewStateFlags::ORIENTATION_VALID
                | xr::ViewStateFlags::POSITION_VALID
                | xr::ViewStateFlags::ORIENTATION_TRACKED
                | xr::ViewStateFlags::POSITION_TRACKED
        } else {
            xr::ViewStateFlags::EMPTY
        };
        let base_pose = base_pose.unwrap_or(Pose::IDENTITY);
        let script = &inst.script;
        enumerate(capacity, count, views, 2, |p, eye| {
            let v = output(p, xr::StructureType::VIEW, "XrView")?;
            v.pose = from_pose(&base_pose.inverse().mul(&script.eye_pose(&head, eye)));
            let [l, r, u, d] = script.eye_fov(eye);
            v.fov = xr::Fovf { angle_left: l, angle_right: r, angle_up: u, angle_down: d };
            Ok(())
        })
    })
}

// ---------------------------------------------------------------------------------------------
// Swapchains.

pub(crate) unsafe extern "system" fn enumerate_swapchain_formats(
    session: xr::Session,
    capacity: u32,
    count: *mut u32,
    formats: *mut i64,
) -> xr::Result {
    run("xrEnumerateSwapchainFormats", |inst| {
        inst.session(session)?;
        let values: Vec<i64> = FORMATS.iter().map(|f| i64::from(f.as_raw())).collect();
        enumerate_values(capacity, count, formats, &values)
    })
}

fn image_usage(u: xr::SwapchainUsageFlags) -> vk::ImageUsageFlags {
    use xr::SwapchainUsageFlags as X;
    let mut v = vk::ImageUsageFlags::empty();
    for (x, f) in [
        (X::COLOR_ATTACHMENT, vk::ImageUsageFlags::COLOR_ATTACHMENT),
        (X::DEPTH_STENCIL_ATTACHMENT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        (X::UNORDERED_ACCESS, vk::ImageUsageFlags::STORAGE),
        (X::TRANSFER_SRC, vk::ImageUsageFlags::TRANSFER_SRC),
        (X::TRANSFER_DST, vk::ImageUsageFlags::TRANSFER_DST),
        (X::SAMPLED, vk::ImageUsageFlags::SAMPLED),
        (X::INPUT_ATTACHMENT, vk::ImageUsageFlags::INPUT_ATTACHMENT),
    ] {
        if u.contains(x) {
            v |= f;
        }
    }
    v
}

pub(crate) unsafe extern "system" fn create_swapchain(
    session: xr::Session,
    info: *const xr::SwapchainCreateInfo,
    out: *mut xr::Swapchain,
) -> xr::Result {
    run("xrCreateSwapchain", |inst| {
        let s = inst.session(session)?;
        let info = input(info, xr::StructureType::SWAPCHAIN_CREATE_INFO, "XrSwapchainCreateInfo")?;
        out_ptr(out, "the swapchain output")?;
        if info.create_flags.contains(xr::SwapchainCreateFlags::PROTECTED_CONTENT) {
            return refuse(xr::Result::ERROR_FEATURE_UNSUPPORTED, "protected content is not supported");
        }
        let Some(&format) = FORMATS.iter().find(|f| i64::from(f.as_raw()) == info.format) else {
            return refuse(
                xr::Result::ERROR_SWAPCHAIN_FORMAT_UNSUPPORTED,
                format!("format {} is not one xrEnumerateSwapchainFormats offers", info.format),
            );
        };
        let usage = image_usage(info.usage_flags);
        let depth = format == vk::Format::D32_SFLOAT;
        if (depth && usage.contains(vk::ImageUsageFlags::COLOR_ATTACHMENT))
            || (!depth && usage.contains(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT))
        {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                format!("usage {:?} does not suit format {format:?}", info.usage_flags),
            );
        }
        if info.sample_count != 1 {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                format!("sampleCount {} exceeds the maximum of 1", info.sample_count),
            );
        }
        if info.width == 0 || info.height == 0 || info.width > MAX_IMAGE_SIZE || info.height > MAX_IMAGE_SIZE
        {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                format!("size {}×{} is outside 1..={MAX_IMAGE_SIZE}", info.width, info.height),
            );
        }
        if info.face_count != 1 {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                format!("faceCount {} (only 1 is offered)", info.face_count),
            );
        }
        if info.array_size == 0 || info.array_size > 16 {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                format!("arraySize {} is outside 1..=16", info.array_size),
            );
        }
        let max_mips = 32 - info.width.max(info.height).leading_zeros();
        if info.mip_count == 0 || info.mip_count > max_mips {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                format!("mipCount {} is outside 1..={max_mips}", info.mip_count),
            );
        }
        let static_image = info.create_flags.contains(xr::SwapchainCreateFlags::STATIC_IMAGE);
        let count = if static_image { 1 } else { SWAPCHAIN_IMAGES };
        let desc = gvk::ImageDesc {
            format,
            width: info.width,
            height: info.height,
            layers: info.array_size,
            mips: info.mip_count,
            samples: vk::SampleCountFlags::TYPE_1,
            usage,
            mutable: info.usage_flags.contains(xr::SwapchainUsageFlags::MUTABLE_FORMAT),
        };
        let images = gvk::Images::new(&s.gpu, desc, count)
            .map_err(|why| Refusal { result: xr::Result::ERROR_RUNTIME_FAILURE, why })?;
        let handle = new_handle();
        inst.swapchains.insert(
            handle,
            Swapchain { session: session.into_raw(), ring: Ring::new(count, static_image), images },
        );
        *out = xr::Swapchain::from_raw(handle);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn destroy_swapchain(swapchain: xr::Swapchain) -> xr::Result {
    run("xrDestroySwapchain", |inst| match inst.swapchains.remove(&swapchain.into_raw()) {
        Some(sc) => {
            if let Some(s) = inst.session.as_ref() {
                sc.images.destroy(&s.gpu);
            }
            Ok(xr::Result::SUCCESS)
        }
        None => refuse(
            xr::Result::ERROR_HANDLE_INVALID,
            format!("XrSwapchain {:#x} is not a live swapchain", swapchain.into_raw()),
        ),
    })
}

pub(crate) unsafe extern "system" fn enumerate_swapchain_images(
    swapchain: xr::Swapchain,
    capacity: u32,
    count: *mut u32,
    images: *mut xr::SwapchainImageBaseHeader,
) -> xr::Result {
    run("xrEnumerateSwapchainImages", |inst| {
        let (sc, _) = inst.swapchain(swapchain)?;
        let list = &sc.images.images;
        let images = images as *mut xr::SwapchainImageVulkanKHR;
        enumerate(capacity, count, images, list.len(), |p, i| {
            let p = output(p, xr::StructureType::SWAPCHAIN_IMAGE_VULKAN_KHR, "XrSwapchainImageVulkan2KHR")?;
            p.image = raw(list[i]);
            Ok(())
        })
    })
}

pub(crate) unsafe extern "system" fn acquire_swapchain_image(
    swapchain: xr::Swapchain,
    info: *const xr::SwapchainImageAcquireInfo,
    index: *mut u32,
) -> xr::Result {
    run("xrAcquireSwapchainImage", |inst| {
        let (sc, _) = inst.swapchain(swapchain)?;
        if !info.is_null() {
            input(info, xr::StructureType::SWAPCHAIN_IMAGE_ACQUIRE_INFO, "XrSwapchainImageAcquireInfo")?;
        }
        out_ptr(index, "the index output")?;
        *index = sc.ring.acquire()?;
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn wait_swapchain_image(
    swapchain: xr::Swapchain,
    info: *const xr::SwapchainImageWaitInfo,
) -> xr::Result {
    run("xrWaitSwapchainImage", |inst| {
        let (sc, _) = inst.swapchain(swapchain)?;
        input(info, xr::StructureType::SWAPCHAIN_IMAGE_WAIT_INFO, "XrSwapchainImageWaitInfo")?;
        sc.ring.wait()?;
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn release_swapchain_image(
    swapchain: xr::Swapchain,
    info: *const xr::SwapchainImageReleaseInfo,
) -> xr::Result {
    run("xrReleaseSwapchainImage", |inst| {
        let (sc, _) = inst.swapchain(swapchain)?;
        if !info.is_null() {
            input(info, xr::StructureType::SWAPCHAIN_IMAGE_RELEASE_INFO, "XrSwapchainImageReleaseInfo")?;
        }
        sc.ring.release()?;
        Ok(xr::Result::SUCCESS)
    })
}

// ---------------------------------------------------------------------------------------------
// Frames.

pub(crate) unsafe extern "system" fn wait_frame(
    session: xr::Session,
    info: *const xr::FrameWaitInfo,
    state: *mut xr::FrameState,
) -> xr::Result {
    run("xrWaitFrame", |inst| {
        let s = inst.session(session)?;
        s.lifecycle.check_running()?;
        if !info.is_null() {
            input(info, xr::StructureType::FRAME_WAIT_INFO, "XrFrameWaitInfo")?;
        }
        let state = output(state, xr::StructureType::FRAME_STATE, "XrFrameState")?;
        s.frames.wait()?;
        let should_render = s.lifecycle.should_render();
        let k = inst.frames_waited;
        if inst.script.pace {
            // A compositor's pace: frame k is released at its wall-clock time.
            let (start, first) = *inst.paced_from.get_or_insert((std::time::Instant::now(), k));
            let due =
                start + std::time::Duration::from_nanos((k - first) * inst.script.display_period_ns as u64);
            std::thread::sleep(due.saturating_duration_since(std::time::Instant::now()));
        }
        inst.frames_waited += 1;
        state.predicted_display_time = xr::Time::from_nanos(inst.frame_time(k as f64));
        state.predicted_display_period = xr::Duration::from_nanos(inst.script.display_period_ns);
        state.should_render = should_render.into();
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn begin_frame(
    session: xr::Session,
    info: *const xr::FrameBeginInfo,
) -> xr::Result {
    run("xrBeginFrame", |inst| {
        let s = inst.session(session)?;
        s.lifecycle.check_running()?;
        if !info.is_null() {
            input(info, xr::StructureType::FRAME_BEGIN_INFO, "XrFrameBeginInfo")?;
        }
        Ok(if s.frames.begin()? { xr::Result::FRAME_DISCARDED } else { xr::Result::SUCCESS })
    })
}

/// A projection view the application submitted, checked.
struct SubmittedView {
    pose: Pose,
    fov: xr::Fovf,
    swapchain: u64,
    layer: u32,
    rect: xr::Rect2Di,
}

fn check_sub_image(
    inst: &Instance,
    session: u64,
    sub: &xr::SwapchainSubImage,
    what: &str,
) -> Result<(), Refusal> {
    let Some(sc) = inst.swapchains.get(&sub.swapchain.into_raw()).filter(|sc| sc.session == session) else {
        return refuse(
            xr::Result::ERROR_HANDLE_INVALID,
            format!(
                "{what}: XrSwapchain {:#x} is not a live swapchain of the session",
                sub.swapchain.into_raw()
            ),
        );
    };
    if sc.ring.last_released().is_none() {
        return refuse(
            xr::Result::ERROR_LAYER_INVALID,
            format!("{what}: its swapchain has no released image"),
        );
    }
    let d = &sc.images.desc;
    if sub.image_array_index >= d.layers {
        return refuse(
            xr::Result::ERROR_VALIDATION_FAILURE,
            format!(
                "{what}: imageArrayIndex {} but the swapchain has {} layers",
                sub.image_array_index, d.layers
            ),
        );
    }
    let r = sub.image_rect;
    let inside = r.offset.x >= 0
        && r.offset.y >= 0
        && r.extent.width > 0
        && r.extent.height > 0
        && (r.offset.x as i64 + r.extent.width as i64) <= d.width as i64
        && (r.offset.y as i64 + r.extent.height as i64) <= d.height as i64;
    if !inside {
        return refuse(
            xr::Result::ERROR_SWAPCHAIN_RECT_INVALID,
            format!(
                "{what}: imageRect {}×{} at ({}, {}) is not inside the {}×{} swapchain",
                r.extent.width, r.extent.height, r.offset.x, r.offset.y, d.width, d.height
            ),
        );
    }
    Ok(())
}

/// Checks a quad layer (accepted and counted, not captured).
fn check_quad(inst: &Instance, session: u64, q: &xr::CompositionLayerQuad, i: usize) -> Result<(), Refusal> {
    let what = format!("layer {i} (quad)");
    let space = inst.space(q.space)?;
    if space.session != session {
        return refuse(
            xr::Result::ERROR_HANDLE_INVALID,
            format!("{what}: its space belongs to another session"),
        );
    }
    checked_pose(&q.pose, &what)?;
    if !(q.size.width > 0.0 && q.size.height > 0.0) {
        return refuse(
            xr::Result::ERROR_VALIDATION_FAILURE,
            format!("{what}: size {}×{} is not positive", q.size.width, q.size.height),
        );
    }
    if !(0..=2).contains(&q.eye_visibility.into_raw()) {
        return refuse(
            xr::Result::ERROR_VALIDATION_FAILURE,
            format!("{what}: eyeVisibility {:?}", q.eye_visibility),
        );
    }
    check_sub_image(inst, session, &q.sub_image, &what)
}

/// Checks the layers of xrEndFrame; returns the projection views of the first projection layer
/// (in stage space) and whether depth came with them.
unsafe fn check_layers(
    inst: &Instance,
    session: u64,
    info: &xr::FrameEndInfo,
) -> Result<(Vec<SubmittedView>, bool), Refusal> {
    check_time(info.display_time.as_nanos())?;
    if info.environment_blend_mode != xr::EnvironmentBlendMode::OPAQUE {
        return refuse(
            xr::Result::ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED,
            format!("blend mode {:?}; only OPAQUE is offered", info.environment_blend_mode),
        );
    }
    if info.layer_count > MAX_LAYERS {
        return refuse(
            xr::Result::ERROR_LAYER_LIMIT_EXCEEDED,
            format!("{} layers; at most {MAX_LAYERS}", info.layer_count),
        );
    }
    if info.layer_count > 0 && info.layers.is_null() {
        return refuse(xr::Result::ERROR_LAYER_INVALID, "layerCount is not 0 but layers is null");
    }
    let mut first: Option<(Vec<SubmittedView>, bool)> = None;
    for i in 0..info.layer_count as usize {
        let layer = *info.layers.add(i);
        if layer.is_null() {
            return refuse(xr::Result::ERROR_LAYER_INVALID, format!("layer {i} is null"));
        }
        if (*layer).ty == xr::StructureType::COMPOSITION_LAYER_QUAD {
            check_quad(inst, session, &*(layer as *const xr::CompositionLayerQuad), i)?;
            continue;
        }
        if (*layer).ty != xr::StructureType::COMPOSITION_LAYER_PROJECTION {
            return refuse(
                xr::Result::ERROR_LAYER_INVALID,
                format!(
                    "layer {i} has type {:?}; the runtime composes projection and quad layers",
                    (*layer).ty
                ),
            );
        }
        let layer = &*(layer as *const xr::CompositionLayerProjection);
        let space = inst.space(layer.space)?;
        if space.session != session {
            return refuse(
                xr::Result::ERROR_HANDLE_INVALID,
                format!("layer {i}'s space belongs to another session"),
            );
        }
        if layer.view_count != 2 || layer.views.is_null() {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                format!("layer {i} has {} views; PRIMARY_STEREO needs 2", layer.view_count),
            );
        }
        let space_pose = inst.locate(space, info.display_time.as_nanos()).unwrap_or(Pose::IDENTITY);
        let mut views = Vec::with_capacity(2);
        let mut depth = false;
        for v in 0..2 {
            let what = format!("layer {i} view {v}");
            let view =
                input(layer.views.add(v), xr::StructureType::COMPOSITION_LAYER_PROJECTION_VIEW, &what)?;
            let pose = checked_pose(&view.pose, &what)?;
            check_sub_image(inst, session, &view.sub_image, &what)?;
            if let Some(d) = find_in_chain(view.next, xr::StructureType::COMPOSITION_LAYER_DEPTH_INFO_KHR) {
                if !inst.depth {
                    return refuse(
                        xr::Result::ERROR_VALIDATION_FAILURE,
                        format!("{what}: depth info without XR_KHR_composition_layer_depth enabled"),
                    );
                }
                let d = &*(d as *const xr::CompositionLayerDepthInfoKHR);
                check_sub_image(inst, session, &d.sub_image, &format!("{what} depth"))?;
                let in01 = |x: f32| (0.0..=1.0).contains(&x);
                if !(in01(d.min_depth)
                    && in01(d.max_depth)
                    && d.min_depth <= d.max_depth
                    && d.near_z != d.far_z)
                {
                    return refuse(
                        xr::Result::ERROR_VALIDATION_FAILURE,
                        format!(
                            "{what} depth: minDepth {} maxDepth {} nearZ {} farZ {}",
                            d.min_depth, d.max_depth, d.near_z, d.far_z
                        ),
                    );
                }
                depth = true;
            }
            views.push(SubmittedView {
                pose: space_pose.mul(&pose),
                fov: view.fov,
                swapchain: view.sub_image.swapchain.into_raw(),
                layer: view.sub_image.image_array_index,
                rect: view.sub_image.image_rect,
            });
        }
        if first.is_none() {
            first = Some((views, depth));
        }
    }
    Ok(first.unwrap_or_default())
}

pub(crate) unsafe extern "system" fn end_frame(
    session: xr::Session,
    info: *const xr::FrameEndInfo,
) -> xr::Result {
    run("xrEndFrame", |inst| {
        let s = inst.session(session)?;
        s.lifecycle.check_running()?;
        let info = input(info, xr::StructureType::FRAME_END_INFO, "XrFrameEndInfo")?;
        if !s.frames.in_frame() {
            return refuse(
                xr::Result::ERROR_CALL_ORDER_INVALID,
                "xrEndFrame without a matching xrBeginFrame",
            );
        }
        let (views, depth) = check_layers(inst, session.into_raw(), info)?;
        let frame = inst.frames_ended;
        let views_json: Vec<_> = views
            .iter()
            .map(|v| {
                json!({"pose": pose_json(&v.pose), "fov": {"left": v.fov.angle_left, "right": v.fov.angle_right, "up": v.fov.angle_up, "down": v.fov.angle_down}})
            })
            .collect();
        inst.log.write(json!({"kind": "end_frame", "frame": frame, "display_time": info.display_time.as_nanos(), "layers": info.layer_count, "views": views_json, "depth": depth}));
        if inst.script.capture.contains(&frame) {
            capture(inst, frame, &views)?;
        }
        let s = inst.session.as_mut().expect("checked above");
        s.frames.end()?;
        let states = s.lifecycle.frame_ended();
        inst.frames_ended += 1;
        inst.push_states(session.into_raw(), states);
        inst.fire_events(frame);
        Ok(xr::Result::SUCCESS)
    })
}

/// Writes the images of a captured frame's projection views to PNG.
fn capture(inst: &mut Instance, frame: u64, views: &[SubmittedView]) -> Result<(), Refusal> {
    let Some(dir) = inst.log.out_dir().map(|d| d.to_path_buf()) else { return Ok(()) };
    if views.is_empty() {
        inst.log.write(
            json!({"kind": "capture", "frame": frame, "missing": "the frame has no projection layer"}),
        );
        return Ok(());
    }
    let gpu = &inst.session.as_ref().expect("a frame has a session").gpu;
    let mut lines = Vec::new();
    for (eye, v) in ["left", "right"].iter().zip(views) {
        let sc = &inst.swapchains[&v.swapchain];
        let index = sc.ring.last_released().expect("checked by check_sub_image") as usize;
        let (w, h) = (v.rect.extent.width as u32, v.rect.extent.height as u32);
        let fail = |why: String| Refusal { result: xr::Result::ERROR_RUNTIME_FAILURE, why };
        let bytes =
            sc.images.read(gpu, index, v.layer, [v.rect.offset.x, v.rect.offset.y], [w, h]).map_err(fail)?;
        let file = format!("frame-{frame:04}-{eye}.png");
        let img = image::RgbaImage::from_raw(w, h, bytes).expect("the readback has w×h pixels");
        img.save(dir.join(&file))
            .map_err(|e| fail(format!("cannot write {}: {e}", dir.join(&file).display())))?;
        lines.push(json!({"kind": "capture", "frame": frame, "eye": eye, "file": file, "width": w, "height": h, "image_index": index, "array_index": v.layer}));
    }
    for l in lines {
        inst.log.write(l);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn instance(script: &str) -> Instance {
        Instance::new(1, true, true, Script::parse(script).unwrap(), Log::open(None).unwrap())
    }

    #[test]
    fn frames_and_display_times_map_both_ways() {
        let inst = instance("display_hz = 50.0");
        assert_eq!(inst.frame_time(0.0), T0 + 20_000_000);
        assert_eq!(inst.frame_time(3.0), T0 + 80_000_000);
        assert!((inst.time_frame(inst.frame_time(7.5)) - 7.5).abs() < 1e-9);
    }

    #[test]
    fn reference_spaces_sit_where_the_specification_puts_them() {
        // The head starts 1.7 m up, turned 90° left; it then walks 1 m along x.
        let inst = instance(
            "[[key]]\nframe = 0\nhead = { position = [0.5, 1.7, 0.0], orientation = [0, 0.70710677, 0, 0.70710677] }\n\
             [[key]]\nframe = 10\nhead = { position = [1.5, 1.7, 0.0] }",
        );
        let space = |kind| Space { session: 0, kind, offset: Pose::IDENTITY };
        let t = inst.frame_time(10.0);
        let stage = inst.locate(&space(SpaceKind::Reference(xr::ReferenceSpaceType::STAGE)), t).unwrap();
        assert_eq!(stage, Pose::IDENTITY);
        // LOCAL stays where the head started, turned with it about the vertical only.
        let local = inst.locate(&space(SpaceKind::Reference(xr::ReferenceSpaceType::LOCAL)), t).unwrap();
        assert!((local.position - Vec3::new(0.5, 1.7, 0.0)).length() < 1e-5);
        assert!((local.orientation * Vec3::NEG_Z - Vec3::NEG_X).length() < 1e-5);
        // VIEW follows the head.
        let view = inst.locate(&space(SpaceKind::Reference(xr::ReferenceSpaceType::VIEW)), t).unwrap();
        assert!((view.position - Vec3::new(1.5, 1.7, 0.0)).length() < 1e-5);
        // An offset is applied in the space's own frame.
        let offset = Space {
            session: 0,
            kind: SpaceKind::Reference(xr::ReferenceSpaceType::STAGE),
            offset: Pose::new(Vec3::new(0.0, 0.0, -1.0), Quat::IDENTITY),
        };
        assert!((inst.locate(&offset, t).unwrap().position - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        // An action space with no session cannot be located.
        assert!(inst.locate(&space(SpaceKind::Action { action: 9, sub: 0 }), t).is_none());
    }

    #[test]
    fn poses_given_by_the_application_must_be_rotations() {
        let mut p = xr::Posef::IDENTITY;
        assert!(checked_pose(&p, "pose").is_ok());
        p.orientation.w = 0.5;
        assert_eq!(checked_pose(&p, "pose").unwrap_err().result, xr::Result::ERROR_POSE_INVALID);
    }

    #[test]
    fn violations_are_the_applications_mistakes_only() {
        assert!(is_violation(xr::Result::ERROR_CALL_ORDER_INVALID));
        assert!(is_violation(xr::Result::ERROR_HANDLE_INVALID));
        assert!(!is_violation(xr::Result::ERROR_SESSION_LOST));
        assert!(!is_violation(xr::Result::ERROR_FORM_FACTOR_UNAVAILABLE));
        assert!(!is_violation(xr::Result::SESSION_NOT_FOCUSED));
        assert_eq!(result_name(xr::Result::ERROR_VALIDATION_FAILURE), "XR_ERROR_VALIDATION_FAILURE");
    }
}
