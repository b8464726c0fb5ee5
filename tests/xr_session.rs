//! The headset session end to end, without a headset: `argile run --xr` against the repository's
//! OpenXR test runtime (`tests/xr-runtime`), loaded by the real Khronos loader through
//! `XR_RUNTIME_JSON`, with the Vulkan validation layer and the OpenXR core validation layer
//! (`XR_APILAYER_LUNARG_core_validation`, Debian package `openxr-layer-corevalidation`) on: a
//! message from either fails the test. The runtime plays a scripted head and hands, writes the
//! images submitted in the projection layer and logs every frame, state, haptic pulse and spec
//! violation (`log.jsonl`).
//!
//! Needs the loader (Debian package `libopenxr-loader1`), the core validation layer and a
//! Vulkan device; fails, never skips, without them.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use argile::math::{Pose, Quat, Vec3};
use argile::render::{Renderer, RendererDesc};
use argile::scene::Scene;
use argile::xr::{recentred, stereo_views, Fov, XrView};

mod common;
use common::{check_against_golden, out_dir, root};

const SCENE: &str = "scenes/tests/xr-session.toml";

/// A fresh folder for a case's files.
fn case_dir(case: &str) -> PathBuf {
    common::xr::pin_lavapipe();
    let dir = out_dir(case);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("test output folder");
    dir
}

/// `argile run --xr SCENE` with `args`, the runtime's manifest and script, in `dir`.
fn run_xr(dir: &Path, manifest: &Path, script: &str, args: &[&str], env: &[(&str, &str)]) -> Output {
    run_scene(SCENE, dir, manifest, script, args, env)
}

/// `argile run --xr scene` with `args`, the runtime's manifest and script, in `dir`.
fn run_scene(
    scene: &str,
    dir: &Path,
    manifest: &Path,
    script: &str,
    args: &[&str],
    env: &[(&str, &str)],
) -> Output {
    let script_path = dir.join("script.toml");
    std::fs::write(&script_path, script).expect("script written");
    let mut c = argile_in(dir, manifest, &script_path);
    c.arg("run")
        .arg("--xr")
        .arg(root().join(scene))
        .args(["--validation", "--save-to"])
        .arg(dir.join("sculpt.argile"))
        .args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("argile runs")
}

/// `argile` run in `dir` against the test runtime of `manifest` playing `script`, without a
/// display, its state (recovery journal) in `dir`.
fn argile_in(dir: &Path, manifest: &Path, script: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_argile"));
    c.current_dir(dir)
        .env("XR_ENABLE_API_LAYERS", CORE_VALIDATION)
        .env("XR_CORE_VALIDATION_EXPORT_TYPE", "text")
        .env("XR_CORE_VALIDATION_FILE_NAME", dir.join(XR_VALIDATION_FILE))
        .env("XR_RUNTIME_JSON", manifest)
        .env("ARGILE_XR_TEST_SCRIPT", script)
        .env("ARGILE_XR_TEST_OUT", dir.join("runtime"))
        .env("XDG_STATE_HOME", dir.join("state"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("RUST_LOG", "warn");
    c
}

/// The OpenXR core validation layer.
const CORE_VALIDATION: &str = "XR_APILAYER_LUNARG_core_validation";
/// Where the core validation layer writes its messages, in a case's folder.
const XR_VALIDATION_FILE: &str = "xr-validation.txt";

/// The core validation layer ran (it says so on standard output when it starts) and reported
/// nothing.
fn xr_validation_clean(dir: &Path, said: &str) {
    assert!(
        said.contains("Core Validation output type: text"),
        "the OpenXR core validation layer did not run (package openxr-layer-corevalidation):\n{said}"
    );
    let messages = std::fs::read_to_string(dir.join(XR_VALIDATION_FILE)).unwrap_or_default();
    assert!(messages.trim().is_empty(), "the OpenXR core validation layer reported:\n{messages}");
}

/// A run that succeeded, with nothing from either validation layer and no warning (a real
/// runtime's ordinary behaviour, such as its first IDLE event, warns of nothing); what it said.
fn succeeded(dir: &Path, out: &Output) -> String {
    let said = text(out);
    assert!(out.status.success(), "argile failed:\n{said}");
    assert!(!said.contains("WARN"), "argile warned:\n{said}");
    xr_validation_clean(dir, &said);
    said
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// The runtime's log, one JSON object per line.
fn log(dir: &Path) -> Vec<serde_json::Value> {
    let path = dir.join("runtime/log.jsonl");
    let text =
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    text.lines().map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}"))).collect()
}

fn kind<'a>(log: &'a [serde_json::Value], kind: &str) -> Vec<&'a serde_json::Value> {
    log.iter().filter(|e| e["kind"] == kind).collect()
}

fn no_violations(log: &[serde_json::Value]) {
    let v = kind(log, "violation");
    assert!(v.is_empty(), "the runtime saw spec violations: {v:#?}");
}

fn floats(v: &serde_json::Value) -> Vec<f32> {
    v.as_array().expect("an array").iter().map(|x| x.as_f64().expect("a number") as f32).collect()
}

/// The views the app submitted in frame `frame`.
fn submitted_views(log: &[serde_json::Value], frame: u64) -> [XrView; 2] {
    let end = kind(log, "end_frame")
        .into_iter()
        .find(|e| e["frame"] == frame)
        .unwrap_or_else(|| panic!("no end_frame {frame} in the log"));
    let view = |v: &serde_json::Value| {
        let p = floats(&v["pose"]["position"]);
        let o = floats(&v["pose"]["orientation"]);
        let f = &v["fov"];
        let angle = |k: &str| f[k].as_f64().expect("an angle") as f32;
        XrView {
            pose: Pose {
                position_m: Vec3::new(p[0], p[1], p[2]),
                rotation: Quat::from_xyzw(o[0], o[1], o[2], o[3]),
            },
            fov: Fov { left: angle("left"), right: angle("right"), up: angle("up"), down: angle("down") },
        }
    };
    let views = end["views"].as_array().expect("views");
    assert_eq!(views.len(), 2, "a projection layer of two views");
    [view(&views[0]), view(&views[1])]
}

/// Largest and mean per-pixel channel difference.
fn difference(a: &image::RgbaImage, b: &image::RgbaImage) -> (u8, f64) {
    assert_eq!(a.dimensions(), b.dimensions());
    let errors: Vec<u8> = a
        .pixels()
        .zip(b.pixels())
        .map(|(p, q)| (0..4).map(|i| p[i].abs_diff(q[i])).max().unwrap_or(0))
        .collect();
    let max = errors.iter().copied().max().unwrap_or(0);
    (max, errors.iter().map(|&e| f64::from(e)).sum::<f64>() / errors.len() as f64)
}

/// The head standing at the stage origin, looking down at the work point.
const HEAD: &str = "head = { position = [0.0, 1.6, 0.0], orientation = [-0.2898, 0.0, 0.0, 0.9571] }";

/// The right hand carves a groove across the slab's front face (frames 4 to 12) while the left
/// hand holds its palette up beside the slab (captured at frame 8), then both hands go behind
/// the viewer (out of view) before the frame captured at 24.
fn carving_script() -> String {
    format!(
        r#"
display_hz = 90.0
interaction_profile = "/interaction_profiles/oculus/touch_controller"
recommended_size = [128, 128]
fov_deg = [-25.0, 25.0, 25.0, -25.0]
ipd_m = 0.064
capture = [8, 24]
[[key]]
frame = 0
{HEAD}
left = {{ grip = {{ position = [-0.3, 1.9, 0.6], orientation = [0, 0, 0, 1] }} }}
right = {{ grip = {{ position = [0.05, 1.33, -0.40], orientation = [0, 0, 0, 1] }}, trigger = 0.0 }}
[[key]]
frame = 3
right = {{ grip = {{ position = [0.05, 1.33, -0.43] }}, trigger = 0.0 }}
[[key]]
frame = 4
left = {{ grip = {{ position = [-0.16, 1.34, -0.36] }} }}
right = {{ trigger = 1.0 }}
[[key]]
frame = 12
left = {{ grip = {{ position = [-0.16, 1.34, -0.36] }} }}
right = {{ grip = {{ position = [-0.05, 1.33, -0.43] }}, trigger = 1.0 }}
[[key]]
frame = 13
right = {{ trigger = 0.0 }}
[[key]]
frame = 16
left = {{ grip = {{ position = [-0.3, 1.9, 0.6] }} }}
right = {{ grip = {{ position = [0.3, 1.9, 0.6] }} }}
"#
    )
}

#[test]
fn a_headset_session_submits_what_the_offscreen_renderer_draws_of_the_same_views() {
    let dir = case_dir("xr-session");
    let manifest = common::xr::test_runtime_manifest(&dir);
    let out = run_xr(&dir, &manifest, &carving_script(), &["--frames", "28"], &[]);
    let said = succeeded(&dir, &out);
    assert!(said.contains("headset session on") && said.contains("(with depth)"), "{said}");
    // Scripted runs print the median of each stage of the frame, as the desk does.
    assert!(said.contains("frame stages, median ms over 28 frames (128×128 per eye)"), "{said}");
    assert!(said.contains("controller poses drawn"), "{said}");
    let log = log(&dir);
    no_violations(&log);
    let states: Vec<&str> = kind(&log, "state").iter().filter_map(|s| s["state"].as_str()).collect();
    for s in ["READY", "SYNCHRONIZED", "VISIBLE", "FOCUSED", "STOPPING", "EXITING"] {
        assert!(states.contains(&s), "the session never was {s}: {states:?}");
    }
    let drawn: Vec<_> = kind(&log, "end_frame").into_iter().filter(|e| e["layers"] != 0).collect();
    assert!(drawn.len() >= 25, "{} frames drawn", drawn.len());
    assert!(drawn.iter().all(|e| e["depth"] == true), "every drawn frame submits its depth");

    // The offscreen renderer draws the saved clay from the views submitted in frame 24.
    let scene_text = std::fs::read_to_string(root().join(SCENE)).unwrap();
    let scene = Scene::parse(&scene_text, SCENE, None).unwrap();
    let sculpt = argile::app::load_sculpt(&dir.join("sculpt.argile")).expect("the sculpt was saved");
    let mut field = sculpt.field;
    // The trigger carved a groove into the slab's front face where the hand went.
    {
        let mut reader = argile::field::FieldReader::new(&field);
        let mut at = |p: Vec3| reader.density_at(field.transform().world_to_index(p));
        assert!(at(Vec3::new(0.0, 0.03, 0.012)) < 0.5, "the groove is cut");
        assert!(at(Vec3::new(0.0, -0.03, 0.012)) > 0.5, "the slab is whole below it");
    }
    // A loaded field has nothing dirty: mesh every brick.
    let size = argile::field::BRICK_SIZE;
    let keys: Vec<_> = field.brick_keys().collect();
    for k in keys {
        field.mark_dirty(k * size, k * size + (size - 1));
    }
    let diff = argile::mesh::remesh_dirty(&mut field);
    let desc = RendererDesc { width: 128, height: 128, samples: 1, validation: true, view_passes: None };
    let environment = argile::render::Environment::Studio;
    let mut renderer =
        Renderer::new(&desc, &environment, scene.environment.intensity).expect("a Vulkan device");
    let validation = renderer.validation_log();
    renderer.apply(&diff).unwrap();
    let mut frame = argile::app::build_frame(&scene, &[], true);
    frame.views = stereo_views(&submitted_views(&log, 24), &recentred(scene.rig.target_m, None));
    renderer.draw(&frame).unwrap();
    let expected = renderer.read_back().unwrap();
    drop(renderer);
    assert!(validation.take().is_empty());

    for (eye, expected) in [("left", &expected.left), ("right", &expected.right)] {
        let path = dir.join(format!("runtime/frame-0024-{eye}.png"));
        let captured = image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8();
        expected.save(dir.join(format!("offscreen-{eye}.png"))).unwrap();
        // Same device, same pipelines, same views: lavapipe (Mesa 22.3.6) gives the same
        // bytes; allow a unit of rounding per channel and nothing more.
        let (max, mean) = difference(&captured, expected);
        assert!(max <= 1 && mean <= 0.01, "{eye} eye: submitted image differs from the offscreen render (max {max}, mean {mean:.4}); see {}", dir.display());
        check_against_golden("xr-session", eye, &captured);
    }
    // Mid-groove, the gouge is drawn in the right hand, a handle in each, the palette in
    // front of the left controller.
    for eye in ["left", "right"] {
        let path = dir.join(format!("runtime/frame-0008-{eye}.png"));
        let captured = image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8();
        check_against_golden("xr-session-hands", eye, &captured);
    }
}

/// Missing pieces each give their sentence, then the desktop station (here headless: no
/// display) renders the scene.
fn falls_back(dir: &Path, manifest: &Path, env: &[(&str, &str)], sentence: &str) {
    let out = run_xr(dir, manifest, &carving_script(), &["--frames", "5"], env);
    let said = text(&out);
    assert!(out.status.success(), "the fallback failed:\n{said}");
    assert!(said.contains("No headset session: ") && said.contains(sentence), "{said}");
    assert!(said.contains("Using the desktop stereo station."), "{said}");
    assert!(said.contains("Rendering the xr-session scene headless"), "{said}");
    assert!(dir.join("argile-out").is_dir(), "the headless station wrote its images: {said}");
}

#[test]
fn without_a_runtime_the_station_says_so_and_falls_back_to_the_desktop() {
    let dir = case_dir("xr-no-runtime");
    falls_back(&dir, &dir.join("nowhere/runtime.json"), &[], "no runtime is active");
}

#[test]
fn without_a_loader_the_station_says_which_package_to_install_and_falls_back() {
    let dir = case_dir("xr-no-loader");
    let missing = dir.join("nowhere/libopenxr_loader.so.1");
    falls_back(
        &dir,
        &dir.join("nowhere.json"),
        &[("ARGILE_XR_LOADER", missing.to_str().unwrap())],
        "libopenxr-loader1",
    );
}

#[test]
fn a_runtime_without_vulkan_or_headset_is_named_and_the_station_falls_back() {
    let dir = case_dir("xr-no-vulkan");
    let manifest = common::xr::test_runtime_manifest(&dir);
    falls_back(&dir, &manifest, &[("ARGILE_XR_TEST_NO_VULKAN", "1")], "does not offer XR_KHR_vulkan_enable2");
    let dir = case_dir("xr-no-hmd");
    falls_back(&dir, &manifest, &[("ARGILE_XR_TEST_NO_HMD", "1")], "finds no headset");
}

/// The clay's density at a scene point of a saved sculpt.
fn density(field: &argile::field::Field, p: Vec3) -> f32 {
    argile::field::FieldReader::new(field).density_at(field.transform().world_to_index(p))
}

/// The two-handed bend (Dewaele–Cani): the left hand's trigger holds the block under the bar
/// as a support, the right hand's trigger pushes the ball down on the bar's free end; the bar
/// bends over the block's edge. Scene points sit in the room at `recentred`'s placement
/// (the scene's target, (0, −0.02, 0), at the work point (0, 1.3, −0.45)).
#[test]
fn the_support_hand_holds_and_the_dominant_hand_bends_the_clay() {
    let dir = case_dir("xr-bend");
    let manifest = common::xr::test_runtime_manifest(&dir);
    // Scene → room: +(0, 1.32, −0.45).
    let script = r#"
display_hz = 30.0
recommended_size = [64, 64]
[[key]]
frame = 0
head = { position = [0.0, 1.6, 0.2], orientation = [-0.2898, 0.0, 0.0, 0.9571] }
left = { grip = { position = [-0.056, 1.296, -0.45], orientation = [0, 0, 0, 1] }, trigger = 1.0 }
right = { grip = { position = [0.075, 1.348, -0.45], orientation = [0, 0, 0, 1] }, trigger = 0.0 }
[[key]]
frame = 3
right = { trigger = 1.0 }
[[key]]
frame = 33
right = { grip = { position = [0.075, 1.318, -0.45] }, trigger = 1.0 }
[[key]]
frame = 36
left = { trigger = 0.0 }
right = { trigger = 0.0 }
"#;
    let out = run_scene("scenes/tests/xr-bend.toml", &dir, &manifest, script, &["--frames", "40"], &[]);
    succeeded(&dir, &out);
    no_violations(&log(&dir));
    let bent = argile::app::load_sculpt(&dir.join("sculpt.argile")).expect("the sculpt was saved").field;
    let scene = Scene::load(&root().join("scenes/tests/xr-bend.toml")).unwrap();
    let straight = argile::app::Playback::new(&scene).into_field();
    // The free end went down with the ball (3 cm): clay left the bar's axis there and came
    // below it; under the support the bar did not move; the matter is kept.
    let (end, below) = (Vec3::new(0.085, 0.0, 0.0), Vec3::new(0.085, -0.022, 0.0));
    assert!(density(&straight, end) > 0.5 && density(&straight, below) < 0.5);
    assert!(density(&bent, end) < 0.5, "the free end moved: {}", density(&bent, end));
    assert!(density(&bent, below) > 0.5, "the free end came down: {}", density(&bent, below));
    let held = Vec3::new(-0.056, 0.0, 0.0);
    assert!(density(&bent, held) > 0.5, "the bar stays on the support");
}

/// The script's contacts: the right hand's tool (the gouge, radius 1.5 cm) rests against the
/// slab's front face over frames 10–15 and 20–27 (its trigger held over 22–25) and is 5 cm
/// away otherwise.
fn touching_script() -> String {
    let (away, touch) = ("[0.0, 1.30, -0.38]", "[0.0, 1.30, -0.43]");
    let mut s = format!(
        "display_hz = 90.0\nrecommended_size = [64, 64]\n[[key]]\nframe = 0\n{HEAD}\n\
         left = {{ grip = {{ position = [-0.3, 1.9, 0.6] }} }}\n\
         right = {{ grip = {{ position = {away}, orientation = [0, 0, 0, 1] }}, trigger = 0.0 }}\n"
    );
    for (frame, at, trigger) in [
        (9, away, 0.0),
        (10, touch, 0.0),
        (15, touch, 0.0),
        (16, away, 0.0),
        (19, away, 0.0),
        (20, touch, 0.0),
        (21, touch, 0.0),
        (22, touch, 1.0),
        (25, touch, 1.0),
        (26, touch, 0.0),
        (27, touch, 0.0),
        (28, away, 0.0),
    ] {
        s += &format!(
            "[[key]]\nframe = {frame}\nright = {{ grip = {{ position = {at} }}, trigger = {trigger:.1} }}\n"
        );
    }
    s
}

#[test]
fn a_pulse_marks_each_touch_and_the_vibration_follows_the_clay_while_sculpting() {
    let dir = case_dir("xr-haptics");
    let manifest = common::xr::test_runtime_manifest(&dir);
    let out = run_xr(&dir, &manifest, &touching_script(), &["--frames", "32"], &[]);
    succeeded(&dir, &out);
    let log = log(&dir);
    no_violations(&log);
    let haptics = kind(&log, "haptic");
    assert!(haptics.iter().all(|h| h["hand"] == "right"), "{haptics:#?}");
    let frames_of = |duration: i64| -> Vec<u64> {
        haptics.iter().filter(|h| h["duration_ns"] == duration).filter_map(|h| h["frame"].as_u64()).collect()
    };
    let (pulse_amplitude, pulse_ns) = argile::app::TOUCH_PULSE;
    assert_eq!(frames_of(pulse_ns), [10, 20], "one pulse as each contact begins: {haptics:#?}");
    let vibration = frames_of(argile::app::CONTACT_NS);
    assert!(
        !vibration.is_empty() && vibration.iter().all(|f| (22..=25).contains(f)),
        "the contact vibrates only while the trigger sculpts: {vibration:?}"
    );
    for h in &haptics {
        let a = h["amplitude"].as_f64().unwrap() as f32;
        if h["duration_ns"] == pulse_ns {
            assert!((a - pulse_amplitude).abs() < 1e-6);
        } else {
            assert!(a > 0.5 && a <= 1.0, "the vibration follows the density under the tool: {a}");
        }
    }
}

/// The carving script with a runtime event at frame 8, halfway through the stroke.
fn carving_with(event: &str) -> String {
    format!("{}\n[[event]]\nframe = 8\nkind = \"{event}\"\n", carving_script())
}

/// The sculpt saved in `dir` holds the half of the groove carved before frame 8.
fn half_a_groove_is_saved(dir: &Path) {
    let field = argile::app::load_sculpt(&dir.join("sculpt.argile")).expect("the sculpt was saved").field;
    assert!(density(&field, Vec3::new(0.035, 0.03, 0.012)) < 0.5, "the groove's start is kept");
    assert!(density(&field, Vec3::new(-0.045, 0.03, 0.012)) > 0.5, "the groove was not finished");
}

#[test]
fn the_runtime_asking_to_quit_mid_stroke_loses_no_work() {
    let dir = case_dir("xr-exit");
    let manifest = common::xr::test_runtime_manifest(&dir);
    let out = run_xr(&dir, &manifest, &carving_with("exit"), &[], &[]);
    succeeded(&dir, &out);
    let log = log(&dir);
    no_violations(&log);
    let states: Vec<&str> = kind(&log, "state").iter().filter_map(|s| s["state"].as_str()).collect();
    assert!(states.ends_with(&["STOPPING", "IDLE", "EXITING"]), "{states:?}");
    half_a_groove_is_saved(&dir);
}

#[test]
fn a_lost_session_mid_stroke_is_saved_and_made_again() {
    let dir = case_dir("xr-loss");
    let manifest = common::xr::test_runtime_manifest(&dir);
    let out = run_xr(&dir, &manifest, &carving_with("session_loss"), &["--frames", "20"], &[]);
    let said = text(&out);
    assert!(out.status.success(), "argile failed:\n{said}");
    xr_validation_clean(&dir, &said);
    assert!(said.contains("made again 1 time"), "{said}");
    let log = log(&dir);
    no_violations(&log);
    let states: Vec<&str> = kind(&log, "state").iter().filter_map(|s| s["state"].as_str()).collect();
    let lost = states.iter().position(|s| *s == "LOSS_PENDING").expect("the session was lost");
    assert!(states[lost..].contains(&"FOCUSED"), "a new session ran: {states:?}");
    assert_eq!(states.last(), Some(&"EXITING"));
}

/// `argile recover` in `dir`'s state folder: nothing is left to recover (every session that
/// saved its sculpt closed its journal).
fn nothing_to_recover(dir: &Path) {
    let out = Command::new(env!("CARGO_BIN_EXE_argile"))
        .arg("recover")
        .current_dir(dir)
        .env("XDG_STATE_HOME", dir.join("state"))
        .output()
        .expect("argile recover runs");
    let said = text(&out);
    assert!(out.status.success() && said.contains("No session is left to recover"), "{said}");
}

/// The carving script with the runtime going away at frame 8 (`kind`: `instance_loss` with its
/// loss-pending event, `runtime_gone` without a word), back after `back_after_s` if given.
fn carving_until_gone(kind: &str, back_after_s: Option<f64>) -> String {
    let back = back_after_s.map_or(String::new(), |s| format!("back_after_s = {s}\n"));
    format!("{}\n[[event]]\nframe = 8\nkind = \"{kind}\"\n{back}", carving_script())
}

#[test]
fn a_lost_instance_mid_stroke_is_saved_and_when_the_runtime_stays_away_the_desk_goes_on() {
    for kind in ["instance_loss", "runtime_gone"] {
        let dir = case_dir(&format!("xr-{kind}"));
        let manifest = common::xr::test_runtime_manifest(&dir);
        let out = run_xr(&dir, &manifest, &carving_until_gone(kind, None), &["--xr-wait-s", "0.6"], &[]);
        let said = text(&out);
        assert!(out.status.success(), "argile failed:\n{said}");
        xr_validation_clean(&dir, &said);
        no_violations(&log(&dir));
        half_a_groove_is_saved(&dir);
        assert!(said.contains("The OpenXR runtime went away; the sculpt is saved in"), "{kind}: {said}");
        assert!(said.contains("did not come back within 0.6 s"), "{kind}: {said}");
        // The desk goes on with the saved sculpt (here headless: no display).
        assert!(said.contains("Going on at the desktop stereo station with"), "{kind}: {said}");
        assert!(dir.join("argile-out").is_dir(), "{kind}: the headless station rendered: {said}");
        // The sculpt is safe: the autosave session was closed, nothing is recovered twice.
        nothing_to_recover(&dir);
    }
}

#[test]
fn a_runtime_that_goes_away_and_comes_back_gets_a_new_session_with_the_same_sculpt() {
    let dir = case_dir("xr-runtime-back");
    let manifest = common::xr::test_runtime_manifest(&dir);
    let out =
        run_xr(&dir, &manifest, &carving_until_gone("runtime_gone", Some(0.5)), &["--frames", "24"], &[]);
    let said = text(&out);
    assert!(out.status.success(), "argile failed:\n{said}");
    xr_validation_clean(&dir, &said);
    assert!(said.contains("The OpenXR runtime went away"), "{said}");
    assert!(said.contains("is back: a new headset session goes on with the sculpt"), "{said}");
    let log = log(&dir);
    no_violations(&log);
    let back = kind(&log, "runtime_back");
    assert_eq!(back.len(), 1, "one new instance: {back:#?}");
    assert_eq!(back[0]["frame"], 9, "it resumes after the lost frame");
    let states: Vec<&str> = kind(&log, "state").iter().filter_map(|s| s["state"].as_str()).collect();
    assert_eq!(states.iter().filter(|s| **s == "FOCUSED").count(), 2, "{states:?}");
    assert_eq!(states.last(), Some(&"EXITING"));
    // The stroke went on in the new session: the whole groove is cut.
    let field = argile::app::load_sculpt(&dir.join("sculpt.argile")).expect("the sculpt was saved").field;
    assert!(density(&field, Vec3::new(0.035, 0.03, 0.012)) < 0.5, "the groove's start");
    assert!(
        density(&field, Vec3::new(-0.045, 0.03, 0.012)) < 0.5,
        "the groove's end, carved after the return"
    );
    nothing_to_recover(&dir);
}

#[test]
fn the_runtimes_view_size_and_pace_are_taken_as_it_chooses() {
    let dir = case_dir("xr-runtime-choice");
    let manifest = common::xr::test_runtime_manifest(&dir);
    // A headless runtime: 320×240 views whatever the script recommends, frames paced at 20 Hz.
    let script = format!("display_hz = 20.0\npace = true\ncapture = [3]\n[[key]]\nframe = 0\n{HEAD}\n");
    let started = std::time::Instant::now();
    let out =
        run_xr(&dir, &manifest, &script, &["--frames", "8"], &[("ARGILE_XR_TEST_VIEW_SIZE", "320x240")]);
    let took = started.elapsed();
    let said = succeeded(&dir, &out);
    assert!(said.contains("(320×240 per eye)"), "{said}");
    let captured = image::open(dir.join("runtime/frame-0003-left.png")).expect("frame 3 captured");
    assert_eq!((captured.width(), captured.height()), (320, 240));
    // Eight frames at 20 Hz take at least 0.35 s of waiting.
    assert!(took.as_secs_f64() > 0.35, "{took:?}");
    no_violations(&log(&dir));
}

/// The right hand carves across the slab's front (frames 2 to 6), then presses its primary
/// button (A; a Windows Mixed Reality controller's trackpad) at frame 9, on `profile`.
fn profile_script(profile: &str) -> String {
    format!(
        r#"
interaction_profile = "{profile}"
recommended_size = [64, 64]
[[key]]
frame = 0
{HEAD}
right = {{ grip = {{ position = [0.05, 1.33, -0.43], orientation = [0, 0, 0, 1] }}, trigger = 0.0 }}
[[key]]
frame = 2
right = {{ trigger = 1.0 }}
[[key]]
frame = 6
right = {{ grip = {{ position = [-0.05, 1.33, -0.43] }}, trigger = 1.0 }}
[[key]]
frame = 7
right = {{ trigger = 0.0 }}
[[key]]
frame = 9
right = {{ a = true }}
[[key]]
frame = 10
right = {{ a = false }}
"#
    )
}

#[test]
fn every_suggested_controller_profile_is_used_and_its_buttons_act() {
    for p in argile::xr::PROFILES {
        let name = p.path.rsplit('/').next().unwrap();
        let dir = case_dir(&format!("xr-profile-{name}"));
        let manifest = common::xr::test_runtime_manifest(&dir);
        let out = run_xr(&dir, &manifest, &profile_script(p.path), &["--frames", "14"], &[]);
        succeeded(&dir, &out);
        let log = log(&dir);
        no_violations(&log);
        let chosen: Vec<_> = kind(&log, "interaction_profile").iter().map(|e| e["profile"].clone()).collect();
        assert_eq!(chosen, [serde_json::json!(p.path)], "{name}: the runtime fell back instead");
        let field = argile::app::load_sculpt(&dir.join("sculpt.argile")).expect("saved").field;
        let groove = density(&field, Vec3::new(0.0, 0.03, 0.012));
        // The primary button undoes the groove where the controller has one.
        if p.bindings.primary.0.is_some() {
            assert!(groove > 0.5, "{name}: the primary button undid the groove ({groove})");
        } else {
            assert!(groove < 0.5, "{name}: the trigger carved ({groove})");
        }
    }
}

#[test]
fn sigterm_in_the_headset_saves_closes_the_session_and_exits_143() {
    let dir = case_dir("xr-sigterm");
    let manifest = common::xr::test_runtime_manifest(&dir);
    // The runtime never asks to quit; frames are paced at 90 Hz.
    let script = format!("pace = true\n{}", carving_script());
    let script_path = dir.join("script.toml");
    std::fs::write(&script_path, script).unwrap();
    let child = argile_in(&dir, &manifest, &script_path)
        .args(["run", "--xr", "--validation", "--save-to"])
        .arg(dir.join("sculpt.argile"))
        .arg(root().join(SCENE))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("argile starts");
    // Wait until the stroke is over (frame 16 ended), then ask it to stop.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    loop {
        let ended = std::fs::read_to_string(dir.join("runtime/log.jsonl"))
            .map(|t| t.lines().filter(|l| l.contains("\"end_frame\"")).count())
            .unwrap_or(0);
        if ended >= 16 {
            break;
        }
        assert!(std::time::Instant::now() < deadline, "the session never reached frame 16");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let status = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let out = child.wait_with_output().expect("argile ends");
    let said = text(&out);
    assert_eq!(out.status.code(), Some(143), "{said}");
    assert!(
        said.contains("SIGTERM received: saving the sculpt") && said.contains("stopped by SIGTERM"),
        "{said}"
    );
    xr_validation_clean(&dir, &said);
    let log = log(&dir);
    no_violations(&log);
    let states: Vec<&str> = kind(&log, "state").iter().filter_map(|s| s["state"].as_str()).collect();
    assert!(states.ends_with(&["STOPPING", "IDLE", "EXITING"]), "the session was ended properly: {states:?}");
    let field = argile::app::load_sculpt(&dir.join("sculpt.argile")).expect("the sculpt was saved").field;
    assert!(density(&field, Vec3::new(-0.045, 0.03, 0.012)) < 0.5, "the whole groove is saved");
    nothing_to_recover(&dir);
}

/// The panel in the headset: the left hand holds its palette up in front of the head, the
/// right hand presses the palette's panel button (the eighth, 12.25 cm to the right of the
/// left grip, 12.5 cm ahead of it, 3 cm above it), then points its aim at the panel's pixel
/// `px` from below and to the right, and pulls the trigger at frame 8 where `click`. Captured
/// at frame 10 at 512 × 512 per eye over 50°, about the panel's share of a headset's view at
/// its recommended resolution.
fn panel_script(px: [f32; 2], click: bool) -> String {
    let grip = Vec3::new(-0.03, 1.153, -0.214);
    let button = grip + Vec3::new(0.1225, 0.03, -0.125);
    // The panel (512 × 832 pixels, 0.18 m wide): its lower edge 6 cm above and 11 cm ahead of
    // the grip, the board leaning back by 0.35 rad.
    let (lean, m_per_px) = (0.35_f32, 0.18 / 512.0);
    let up = (832.0 - px[1]) * m_per_px;
    let target = grip
        + Vec3::new((px[0] - 256.0) * m_per_px, 0.06, -0.11)
        + up * Vec3::new(0.0, lean.cos(), -lean.sin());
    let from = Vec3::new(0.12, 1.25, -0.12);
    let turn = Quat::from_rotation_arc(Vec3::NEG_Z, (target - from).normalize());
    let pose = |p: Vec3, q: Quat| {
        format!(
            "{{ position = [{}, {}, {}], orientation = [{}, {}, {}, {}] }}",
            p.x, p.y, p.z, q.x, q.y, q.z, q.w
        )
    };
    let still = pose(Vec3::new(0.25, 1.2, -0.2), Quat::IDENTITY);
    let on_button = pose(button, Quat::IDENTITY);
    let aiming = pose(from, turn);
    let left = pose(grip, Quat::IDENTITY);
    let trigger = if click { 1.0 } else { 0.0 };
    format!(
        r#"
display_hz = 90.0
interaction_profile = "/interaction_profiles/oculus/touch_controller"
recommended_size = [512, 512]
fov_deg = [-25.0, 25.0, 25.0, -25.0]
ipd_m = 0.064
capture = [10]
[[key]]
frame = 0
{HEAD}
left = {{ grip = {left}, aim = {left} }}
right = {{ grip = {still}, aim = {still}, trigger = 0.0 }}
[[key]]
frame = 2
right = {{ grip = {on_button}, aim = {on_button}, trigger = 0.0 }}
[[key]]
frame = 3
right = {{ trigger = 1.0 }}
[[key]]
frame = 4
right = {{ trigger = 0.0 }}
[[key]]
frame = 6
right = {{ grip = {aiming}, aim = {aiming}, trigger = 0.0 }}
[[key]]
frame = 8
right = {{ trigger = {trigger} }}
[[key]]
frame = 9
right = {{ trigger = 0.0 }}
"#
    )
}

#[test]
fn the_headset_panel_shows_on_the_palette_with_the_hands_ray_on_it() {
    let dir = case_dir("xr-panel");
    let manifest = common::xr::test_runtime_manifest(&dir);
    let out = run_xr(&dir, &manifest, &panel_script([256.0, 300.0], false), &["--frames", "12"], &[]);
    succeeded(&dir, &out);
    no_violations(&log(&dir));
    for eye in ["left", "right"] {
        let path = dir.join(format!("runtime/frame-0010-{eye}.png"));
        let captured = image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8();
        check_against_golden("xr-panel", eye, &captured);
    }
}

#[test]
fn the_headset_panels_quit_saves_and_ends_the_session() {
    let dir = case_dir("xr-panel-quit");
    let manifest = common::xr::test_runtime_manifest(&dir);
    // The first row's Quit, 264 pixels from the panel's left edge.
    let out = run_xr(&dir, &manifest, &panel_script([264.0, 16.0], true), &["--frames", "60"], &[]);
    let said = succeeded(&dir, &out);
    let log = log(&dir);
    let states: Vec<&str> = kind(&log, "state").iter().filter_map(|s| s["state"].as_str()).collect();
    assert!(states.ends_with(&["STOPPING", "IDLE", "EXITING"]), "{states:?}");
    let frames = kind(&log, "end_frame").len();
    assert!(frames < 20, "the session ended soon after the click at frame 8: {frames} frames");
    assert!(said.contains("saved the sculpt to"), "{said}");
    assert!(argile::app::load_sculpt(&dir.join("sculpt.argile")).is_ok());
    nothing_to_recover(&dir);
}

#[test]
fn the_palettes_quit_button_saves_and_ends_the_session() {
    let dir = case_dir("xr-quit-button");
    let manifest = common::xr::test_runtime_manifest(&dir);
    // The left hand holds its palette still, facing forward; the right hand's grip goes onto
    // the quit button (the sixth of eight, 5.25 cm to the right of the palette, 12.5 cm ahead
    // of the left grip, 3 cm above it) and pulls the trigger.
    let script = format!(
        r#"
recommended_size = [64, 64]
[[key]]
frame = 0
{HEAD}
left = {{ grip = {{ position = [-0.1, 1.2, -0.1], orientation = [0, 0, 0, 1] }} }}
right = {{ grip = {{ position = [0.2, 1.2, -0.1], orientation = [0, 0, 0, 1] }} }}
[[key]]
frame = 3
right = {{ grip = {{ position = [-0.0475, 1.23, -0.225] }}, trigger = 0.0 }}
[[key]]
frame = 5
right = {{ trigger = 1.0 }}
"#
    );
    let out = run_xr(&dir, &manifest, &script, &[], &[]);
    let said = succeeded(&dir, &out);
    let log = log(&dir);
    no_violations(&log);
    let states: Vec<&str> = kind(&log, "state").iter().filter_map(|s| s["state"].as_str()).collect();
    assert!(states.ends_with(&["STOPPING", "IDLE", "EXITING"]), "{states:?}");
    let last = kind(&log, "end_frame").len();
    assert!(last < 12, "the session ended soon after the press: {last} frames");
    assert!(said.contains("saved the sculpt to"), "{said}");
    // The button's tick on arrival.
    let ticks =
        kind(&log, "haptic").into_iter().filter(|h| h["duration_ns"] == argile::app::BUTTON_PULSE.1).count();
    assert_eq!(ticks, 1, "one tick as the hand came onto the button");
    nothing_to_recover(&dir);
}

#[test]
fn with_no_command_a_ready_headset_is_chosen() {
    let dir = case_dir("xr-automatic");
    let manifest = common::xr::test_runtime_manifest(&dir);
    let script = dir.join("script.toml");
    let text_ = format!(
        "recommended_size = [64, 64]\n[[key]]\nframe = 0\n{HEAD}\n[[event]]\nframe = 6\nkind = \"exit\"\n"
    );
    std::fs::write(&script, text_).unwrap();
    let out = argile_in(&dir, &manifest, &script).output().expect("argile runs");
    let said = succeeded(&dir, &out);
    assert!(said.contains("headset session on Argile XR test runtime"), "{said}");
    assert!(dir.join("default.argile").is_file(), "the sculpt is saved where the station saves it: {said}");
    no_violations(&log(&dir));
}

#[test]
fn a_sculpt_file_opened_in_the_headset_is_sculpted_and_saved_back_to_itself() {
    let dir = case_dir("xr-open-sculpt");
    let manifest = common::xr::test_runtime_manifest(&dir);
    // Half a groove, saved by a session the runtime ends mid-stroke.
    let out = run_xr(&dir, &manifest, &carving_with("exit"), &[], &[]);
    assert!(out.status.success(), "argile failed:\n{}", text(&out));
    half_a_groove_is_saved(&dir);
    let sculpt = dir.join("kept/sculpt.argile");
    std::fs::create_dir_all(sculpt.parent().unwrap()).unwrap();
    std::fs::rename(dir.join("sculpt.argile"), &sculpt).unwrap();
    std::fs::remove_dir_all(dir.join("runtime")).unwrap();

    // Opened again in the headset, without --save-to: its clay is the file's, and it goes back
    // to the file when the runtime ends the session.
    let script = dir.join("open.toml");
    std::fs::write(
        &script,
        format!("recommended_size = [64, 64]\n[[key]]\nframe = 0\n{HEAD}\n[[event]]\nframe = 6\nkind = \"exit\"\n"),
    )
    .unwrap();
    let saved_before = std::fs::metadata(&sculpt).unwrap().modified().unwrap();
    let out = argile_in(&dir, &manifest, &script)
        .args(["run", "--xr", "--validation"])
        .arg(&sculpt)
        .output()
        .expect("argile runs");
    let said = text(&out);
    assert!(out.status.success(), "{said}");
    assert!(said.contains(&format!("saved the sculpt to {}", sculpt.display())), "{said}");
    assert!(!dir.join("sculpt.argile").exists(), "nothing is written beside it: {said}");
    assert!(std::fs::metadata(&sculpt).unwrap().modified().unwrap() >= saved_before);
    no_violations(&log(&dir));
    let field = argile::app::load_sculpt(&sculpt).expect("the sculpt was saved").field;
    assert!(density(&field, Vec3::new(0.035, 0.03, 0.012)) < 0.5, "the file's groove, not the scene's clay");
    assert!(density(&field, Vec3::new(-0.045, 0.03, 0.012)) > 0.5);
}

#[test]
fn bench_frame_xr_reports_the_view_size_the_runtime_chose_and_the_poses_age() {
    let dir = case_dir("xr-bench-frame");
    let out = Command::new(env!("CARGO_BIN_EXE_argile"))
        .args(["bench", "--json", "--quick", "frame-xr"])
        .current_dir(&dir)
        .env("ARGILE_XR_TEST_RUNTIME", common::xr::runtime_library())
        .env("ARGILE_XR_TEST_VIEW_SIZE", "320x240")
        .env("XDG_STATE_HOME", dir.join("state"))
        .env("RUST_LOG", "warn")
        .output()
        .expect("argile bench runs");
    let said = text(&out);
    assert!(out.status.success(), "{said}");
    let line = String::from_utf8_lossy(&out.stdout)
        .lines()
        .find(|l| l.contains("\"frame-xr\""))
        .map(str::to_owned)
        .unwrap_or_else(|| panic!("no frame-xr line:\n{said}"));
    let v: serde_json::Value = serde_json::from_str(&line).unwrap();
    assert_eq!(v["eye_px"], serde_json::json!([320, 240]), "{line}");
    for key in ["median_pose_age_ms", "median_input_pose_age_ms"] {
        let age = v[key].as_f64().unwrap_or_else(|| panic!("{key} missing: {line}"));
        assert!(age.is_finite() && age >= 0.0, "{key} = {age}");
    }
    // The poses the glyphs are drawn at are located after the step: never older.
    assert!(v["median_pose_age_ms"].as_f64() <= v["median_input_pose_age_ms"].as_f64(), "{line}");
}
