//! The OpenXR test runtime (`tests/xr-runtime/`) for integration tests: its shared library and
//! a runtime manifest pointing at it, to be named by `XR_RUNTIME_JSON`, so the real Khronos
//! loader (`libopenxr_loader.so.1`, package libopenxr-loader1) loads it.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The Khronos loader's soname (Debian/Ubuntu ship no unversioned name without the -dev
/// package).
pub const LOADER: &str = "libopenxr_loader.so.1";

const LIBRARY: &str = "libargile_xr_test_runtime.so";

/// The runtime's shared library. The root package's dev-dependency on the runtime makes cargo
/// build it (into `deps/`) with the tests; a `cargo build -p argile-xr-test-runtime` puts one in
/// the profile folder. The newest is taken; with none, it is built here.
pub fn runtime_library() -> PathBuf {
    let exe = std::env::current_exe().expect("the test executable's path");
    let deps = exe.parent().expect("the test executable is in target/<profile>/deps");
    let profile_dir = deps.parent().expect("target/<profile>");
    let newest = || {
        [profile_dir.join(LIBRARY), deps.join(LIBRARY)]
            .into_iter()
            .filter_map(|p| std::fs::metadata(&p).and_then(|m| m.modified()).ok().map(|t| (t, p)))
            .max()
            .map(|(_, p)| p)
    };
    if let Some(p) = newest() {
        return p;
    }
    let mut cmd = Command::new(option_env!("CARGO").unwrap_or("cargo"));
    cmd.args(["build", "--quiet", "-p", "argile-xr-test-runtime"]);
    if profile_dir.file_name().is_some_and(|n| n == "release") {
        cmd.arg("--release");
    }
    let status = cmd.current_dir(super::root()).status().expect("cargo runs");
    assert!(
        status.success(),
        "building the OpenXR test runtime (cargo build -p argile-xr-test-runtime) failed"
    );
    newest().unwrap_or_else(|| panic!("no {LIBRARY} under {} after building it", profile_dir.display()))
}

/// Writes a runtime manifest (file format 1.0.0) for the test runtime into `dir` and returns
/// its path, for `XR_RUNTIME_JSON`.
pub fn test_runtime_manifest(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).expect("the manifest's folder");
    let manifest = serde_json::json!({
        "file_format_version": "1.0.0",
        "runtime": {
            "name": "Argile XR test runtime",
            "library_path": runtime_library(),
        }
    });
    let path = dir.join("argile_xr_test_runtime.json");
    std::fs::write(&path, serde_json::to_string_pretty(&manifest).expect("JSON"))
        .expect("the manifest is written");
    path
}

/// Pins Vulkan to Mesa's lavapipe unless the caller pinned a device (as `scripts/test` does),
/// so XR tests render where the goldens were made.
pub fn pin_lavapipe() {
    if std::env::var_os("VK_DRIVER_FILES").is_some() || std::env::var_os("VK_ICD_FILENAMES").is_some() {
        return;
    }
    let icd = std::fs::read_dir("/usr/share/vulkan/icd.d")
        .ok()
        .and_then(|d| {
            d.filter_map(|e| e.ok().map(|e| e.path()))
                .find(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("lvp_icd")))
        })
        .expect("Mesa's lavapipe ICD (package mesa-vulkan-drivers) is missing");
    std::env::set_var("VK_DRIVER_FILES", &icd);
    std::env::set_var("VK_ICD_FILENAMES", &icd);
}
