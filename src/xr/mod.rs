//! OpenXR: for now, what the station learns about the OpenXR loader and runtime.
//!
//! The Khronos loader is loaded at run time (`libopenxr_loader.so.1`, Debian/Ubuntu package
//! `libopenxr-loader1`), so Argile runs where there is none. Debian's loader (1.0.20) speaks
//! API 1.0 only, so instances ask for 1.0. Knows nothing of the field or meshes.

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

/// Looks for the OpenXR loader, a runtime and a headset, without creating a session.
pub fn probe() -> XrState {
    // SAFETY: loading the system's OpenXR loader runs its initialisers; the library named by
    // the OpenXR loader specification is trusted to conform to it, as for any OpenXR app.
    let entry = match unsafe { openxr::Entry::load() } {
        Ok(entry) => entry,
        Err(e) => return XrState::NoLoader { reason: e.to_string() },
    };
    let extensions = match entry.enumerate_extensions() {
        Ok(x) => x,
        Err(e) => return XrState::NoRuntime { reason: e.to_string() },
    };
    let app = openxr::ApplicationInfo {
        application_name: "argile",
        application_version: 1,
        engine_name: "argile",
        engine_version: 1,
        api_version: openxr::Version::new(1, 0, 0),
    };
    let instance = match entry.create_instance(&app, &openxr::ExtensionSet::default(), &[]) {
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
    fn probing_never_panics() {
        // Whatever this machine has, probing answers with a state.
        let _ = probe().to_string();
    }
}
