//! `argile bench frame-xr`: headset frames against the OpenXR test runtime.

use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::math::median;
use crate::scene::Scene;

/// The OpenXR test runtime's library: `ARGILE_XR_TEST_RUNTIME`, else beside this executable
/// (or in its `deps/`), where `cargo build -p argile-xr-test-runtime` and the test build put it.
fn test_runtime_library() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("ARGILE_XR_TEST_RUNTIME") {
        return Some(PathBuf::from(p));
    }
    let exe = std::env::current_exe().ok()?;
    let dir = exe.parent()?;
    let name = "libargile_xr_test_runtime.so";
    [dir.join(name), dir.join("deps").join(name), dir.parent()?.join(name)].into_iter().find(|p| p.is_file())
}

/// `argile bench frame-xr`: `frames` headset frames of `eye_px`² per eye against the OpenXR
/// test runtime while the right controller carves across the default scene's bust, after two
/// frames of warm-up; medians of each part of the frame, from `xrWaitFrame` returning to
/// `xrEndFrame` returning.
pub(super) fn frame_xr(eye_px: u32, frames: usize, emit: &mut impl FnMut(serde_json::Value)) -> Result<()> {
    let Some(library) = test_runtime_library() else {
        anyhow::bail!(
            "frame-xr needs the OpenXR test runtime: build it with `cargo build --release -p \
             argile-xr-test-runtime` (or name its library with ARGILE_XR_TEST_RUNTIME)"
        );
    };
    let dir = std::env::temp_dir().join(format!("argile-bench-frame-xr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let _cleanup = scopeguard::guard(dir.clone(), |d| {
        let _ = std::fs::remove_dir_all(d);
    });
    let manifest = dir.join("runtime.json");
    let json = serde_json::json!({
        "file_format_version": "1.0.0",
        "runtime": { "name": "Argile XR test runtime", "library_path": library },
    });
    std::fs::write(&manifest, json.to_string())?;
    // The bust's front (scene z = 0.075 at the head's height) is at room (x, 1.335, −0.375);
    // the gouge crosses it, trigger held, from the first frame to the last.
    let last = frames + 8;
    let script = format!(
        "display_hz = 90.0\nrecommended_size = [{eye_px}, {eye_px}]\n\
         [[key]]\nframe = 0\nhead = {{ position = [0.0, 1.6, 0.0], orientation = [-0.2898, 0.0, 0.0, 0.9571] }}\n\
         right = {{ grip = {{ position = [0.04, 1.335, -0.378], orientation = [0, 0, 0, 1] }}, trigger = 1.0 }}\n\
         [[key]]\nframe = {last}\nright = {{ grip = {{ position = [-0.04, 1.335, -0.378] }}, trigger = 1.0 }}\n"
    );
    let script_path = dir.join("script.toml");
    std::fs::write(&script_path, script)?;
    std::env::set_var("XR_RUNTIME_JSON", &manifest);
    std::env::set_var("ARGILE_XR_TEST_SCRIPT", &script_path);
    std::env::set_var("ARGILE_XR_TEST_OUT", dir.join("out"));
    let scene = Scene::default_scene();
    let options = crate::app::XrRunOptions {
        frames: Some(frames as u64 + 2),
        save_to: Some(dir.join("bench.argile")),
        ..crate::app::XrRunOptions::default()
    };
    let report = crate::app::run_xr(&scene, None, "bench", &options)?;
    let timed = &report.stage_ms[2.min(report.stage_ms.len())..];
    let timed_ages = &report.pose_age_ms[2.min(report.pose_age_ms.len())..];
    let median_of = |i: usize| median(timed.iter().map(|s| s[i]).collect());
    let total = median(timed.iter().map(|s| s.iter().sum()).collect());
    emit(serde_json::json!({
        "workload": "frame-xr",
        "runtime": report.runtime,
        "eye_px": [report.eye_px.0, report.eye_px.1],
        "eye_px_asked": [eye_px, eye_px],
        "frames": timed.len(),
        "depth": report.depth,
        "median_frame_start_ms": median_of(0),
        "median_simulation_ms": median_of(1),
        "median_meshing_ms": median_of(2),
        "median_render_submission_ms": median_of(3),
        "median_frame_ms": total,
        "median_pose_age_ms": median(timed_ages.iter().map(|a| a[0]).collect()),
        "median_input_pose_age_ms": median(timed_ages.iter().map(|a| a[1]).collect()),
        "budget_ms_at_90_hz": 1000.0 / 90.0,
    }));
    Ok(())
}
