//! OpenXR: the headset session, its state machine, the reference space, the two-hand action
//! set, haptics, and what the station learns about the OpenXR loader and runtime.
//!
//! The Khronos loader is loaded at run time (`libopenxr_loader.so.1`, Debian/Ubuntu package
//! `libopenxr-loader1`), so Argile runs where there is none. Debian's loader (1.0.20) speaks
//! API 1.0 only, so instances ask for 1.0. The runtime makes the renderer's Vulkan instance
//! and device (XR_KHR_vulkan_enable2); both eyes are drawn in one multiview pass into the
//! runtime's 2-layer swapchain images, which stay the runtime's.
//!
//! Knows nothing of the field, meshes, tools or clay: the caller's step gets the hands and
//! returns the frame to draw (see [`XrStation::turn`]).
//!
//! - `lifecycle`: the session states and what each asks of Argile (pure).
//! - `views`: the runtime's views as the renderer's eye cameras (pure).
//! - `grab`: where the sculpture is in the room and how one or two grips move it (pure).
//! - `actions`: the action set, bindings per controller, haptics.
//! - `session`: the instance, system, renderer, session, swapchains and frame loop.

mod actions;
mod grab;
mod lifecycle;
mod session;
mod views;

pub use actions::{Bindings, HandState, Haptic, Profile, PROFILES};
pub use grab::{one_hand_grab, two_hand_grab, Placement, SCALE_RANGE};
pub use lifecycle::{Command, Lifecycle, SessionState};
pub use session::{carry_held, FrameInput, FrameOutput, FrameTimes, Held, Turn, XrOptions, XrStation};
pub use views::{eye_view, recentred, stereo_views, Fov, XrView, FAR_M, NEAR_M, WORK_POINT_M};

/// The environment variable naming the OpenXR loader library to use instead of the system's.
pub const LOADER_VARIABLE: &str = "ARGILE_XR_LOADER";

/// Why a headset session could not start or went wrong. The first four are "no headset
/// here" cases, after which the station falls back to the desktop stereo modes.
#[derive(Debug, thiserror::Error)]
pub enum XrError {
    /// No loader library could be opened.
    #[error("no OpenXR loader ({0}); install the package libopenxr-loader1 to use a headset")]
    NoLoader(String),
    /// The loader is there but no runtime answered.
    #[error(
        "OpenXR loader present, but no runtime is active ({0}); install and start an OpenXR runtime \
         (for example Monado) or point XR_RUNTIME_JSON at its manifest"
    )]
    NoRuntime(String),
    /// The runtime cannot make Vulkan instances and devices.
    #[error(
        "the OpenXR runtime {runtime} does not offer XR_KHR_vulkan_enable2, so Argile cannot render to it"
    )]
    NoVulkan {
        /// The runtime's name and version.
        runtime: String,
    },
    /// The runtime has no head-mounted display.
    #[error("the OpenXR runtime {runtime} finds no headset ({reason}); connect and switch on a headset")]
    NoHeadset {
        /// The runtime's name and version.
        runtime: String,
        /// Its answer.
        reason: String,
    },
    /// The runtime or headset lacks something Argile needs.
    #[error("{0}")]
    Unsupported(String),
    /// An OpenXR call failed.
    #[error("the OpenXR call {call} failed: {result}")]
    Call {
        /// The call.
        call: &'static str,
        /// What it returned.
        result: openxr::sys::Result,
    },
    /// Rendering failed.
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
}

impl XrError {
    /// Whether a call found the instance lost (`XR_ERROR_INSTANCE_LOST`): the runtime went
    /// away, with or without the loss-pending event first.
    pub fn is_instance_lost(&self) -> bool {
        matches!(self, XrError::Call { result, .. } if *result == openxr::sys::Result::ERROR_INSTANCE_LOST)
    }

    /// Whether this means "no headset here" (no loader, runtime, Vulkan support or headset),
    /// after which the station uses the desktop stereo modes.
    pub fn is_absent(&self) -> bool {
        matches!(
            self,
            XrError::NoLoader(_)
                | XrError::NoRuntime(_)
                | XrError::NoVulkan { .. }
                | XrError::NoHeadset { .. }
        )
    }
}

/// The loader at `path` (else `ARGILE_XR_LOADER`, else the system's), or why none loads.
pub fn load_entry(path: Option<&std::path::Path>) -> Result<openxr::Entry, XrError> {
    let from_env = std::env::var_os(LOADER_VARIABLE).map(std::path::PathBuf::from);
    session::load_from(path.or(from_env.as_deref())).map_err(XrError::NoLoader)
}

fn app_info() -> openxr::ApplicationInfo<'static> {
    openxr::ApplicationInfo {
        application_name: "argile",
        application_version: 1,
        engine_name: "argile",
        engine_version: 1,
        api_version: openxr::Version::new(1, 0, 0),
    }
}

/// What was found of OpenXR on this machine.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum XrState {
    /// No loader library could be opened.
    NoLoader {
        /// The loader's error.
        reason: String,
    },
    /// The loader is there but no runtime answered (none installed or none active).
    NoRuntime {
        /// The loader's error.
        reason: String,
    },
    /// A runtime answered.
    Runtime {
        /// Runtime name.
        name: String,
        /// Runtime version.
        version: String,
        /// Whether it offers `XR_KHR_vulkan_enable2`, which Argile needs.
        vulkan_enable2: bool,
        /// The head-mounted display found, or why none was.
        headset: Result<String, String>,
    },
}

impl std::fmt::Display for XrState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            XrState::NoLoader { reason } => write!(
                f,
                "no OpenXR loader ({reason}); install the package libopenxr-loader1 to use a headset"
            ),
            XrState::NoRuntime { reason } => write!(
                f,
                "OpenXR loader present, but no runtime is active ({reason}); install and start an OpenXR \
                 runtime (for example Monado) or point XR_RUNTIME_JSON at its manifest"
            ),
            XrState::Runtime { name, version, vulkan_enable2, headset } => {
                write!(f, "OpenXR runtime {name} {version}")?;
                if !vulkan_enable2 {
                    write!(f, ", WITHOUT XR_KHR_vulkan_enable2 (Argile cannot render to it)")?;
                }
                match headset {
                    Ok(h) => write!(f, ", headset: {h}"),
                    Err(e) => write!(f, ", no headset ({e})"),
                }
            }
        }
    }
}

impl XrState {
    /// Whether a headset session can start: a runtime with `XR_KHR_vulkan_enable2` and a
    /// headset.
    pub fn ready(&self) -> bool {
        matches!(self, XrState::Runtime { vulkan_enable2: true, headset: Ok(_), .. })
    }
}

/// Whether an OpenXR runtime is configured at all (`XR_RUNTIME_JSON`, or an active runtime
/// manifest where the loader looks on Linux), so that starting without one probes nothing
/// (the loader would print its errors).
pub fn runtime_configured() -> bool {
    if std::env::var_os("XR_RUNTIME_JSON").is_some() {
        return true;
    }
    let config_home = std::env::var_os("XDG_CONFIG_HOME")
        .map(std::path::PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| std::path::Path::new(&h).join(".config")));
    let config_dirs = std::env::var("XDG_CONFIG_DIRS").unwrap_or_else(|_| "/etc/xdg".into());
    config_home
        .into_iter()
        .chain(config_dirs.split(':').filter(|d| !d.is_empty()).map(std::path::PathBuf::from))
        .chain([std::path::PathBuf::from("/etc")])
        .any(|d| d.join("openxr/1/active_runtime.json").is_file())
}

/// Looks for the OpenXR loader, a runtime and a headset, without creating a session.
pub fn probe() -> XrState {
    let entry = match load_entry(None) {
        Ok(entry) => entry,
        Err(e) => return XrState::NoLoader { reason: e.to_string() },
    };
    let extensions = match entry.enumerate_extensions() {
        Ok(x) => x,
        Err(e) => return XrState::NoRuntime { reason: e.to_string() },
    };
    let instance = match entry.create_instance(&app_info(), &openxr::ExtensionSet::default(), &[]) {
        Ok(i) => i,
        Err(e) => return XrState::NoRuntime { reason: e.to_string() },
    };
    let (name, version) = match instance.properties() {
        Ok(p) => (p.runtime_name, p.runtime_version.to_string()),
        Err(e) => (format!("(unnamed: {e})"), String::new()),
    };
    let headset = instance
        .system(openxr::FormFactor::HEAD_MOUNTED_DISPLAY)
        .and_then(|s| instance.system_properties(s))
        .map(|p| p.system_name)
        .map_err(|e| e.to_string());
    XrState::Runtime { name, version, vulkan_enable2: extensions.khr_vulkan_enable2, headset }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_state_reads_as_one_sentence_saying_what_to_do() {
        let s = XrState::NoLoader { reason: "libopenxr_loader.so: not found".into() }.to_string();
        assert!(s.contains("libopenxr-loader1"));
        let s = XrState::NoRuntime { reason: "XR_ERROR_RUNTIME_UNAVAILABLE".into() }.to_string();
        assert!(s.contains("XR_RUNTIME_JSON"));
        let s = XrState::Runtime {
            name: "Monado".into(),
            version: "21.0.0".into(),
            vulkan_enable2: true,
            headset: Err("XR_ERROR_FORM_FACTOR_UNAVAILABLE".into()),
        }
        .to_string();
        assert!(s.contains("Monado") && s.contains("no headset"));
    }

    #[test]
    fn a_loader_that_does_not_load_says_which_package_to_install() {
        let missing = std::path::Path::new("no-such-dir/libopenxr_loader.so.1");
        let Err(e) = load_entry(Some(missing)) else { panic!("a loader loaded from {}", missing.display()) };
        assert!(e.is_absent());
        let s = e.to_string();
        assert!(s.starts_with("no OpenXR loader (") && s.contains("libopenxr-loader1"), "{s}");
        assert!(s.contains("no-such-dir"), "the loader's own error names the file: {s}");
        // The other "absent" cases read as one sentence each and name the runtime.
        let v = XrError::NoVulkan { runtime: "Test 1.0".into() }.to_string();
        assert!(v.contains("Test 1.0") && v.contains("XR_KHR_vulkan_enable2"), "{v}");
        let h = XrError::NoHeadset {
            runtime: "Test 1.0".into(),
            reason: "XR_ERROR_FORM_FACTOR_UNAVAILABLE".into(),
        };
        assert!(h.is_absent() && h.to_string().contains("no headset"));
        assert!(!XrError::Unsupported("x".into()).is_absent());
    }

    #[test]
    fn only_a_runtime_with_vulkan_and_a_headset_is_ready() {
        let runtime = |vulkan_enable2, headset: Result<&str, &str>| XrState::Runtime {
            name: "Test".into(),
            version: "1".into(),
            vulkan_enable2,
            headset: headset.map(Into::into).map_err(Into::into),
        };
        assert!(runtime(true, Ok("HMD")).ready());
        assert!(!runtime(false, Ok("HMD")).ready());
        assert!(!runtime(true, Err("XR_ERROR_FORM_FACTOR_UNAVAILABLE")).ready());
        assert!(!XrState::NoRuntime { reason: String::new() }.ready());
    }

    #[test]
    fn probing_never_panics() {
        // Whatever this machine has, probing answers with a state.
        let _ = probe().to_string();
    }
}
