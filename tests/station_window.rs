//! The station in a real window: an X server (Xvfb) per test, the `argile run` binary with
//! scripted input on a test scene, the Vulkan validation layer on. The screenshot of the last
//! frame is compared with `tests/golden/station-window.png` (`BLESS=1` regenerates it).
//!
//! Needs `Xvfb` (Debian package `xvfb`, installed by `scripts/setup test`) and a Vulkan device;
//! fails, never skips, without them.

use std::path::Path;
use std::process::Command;

use image::GenericImageView;

mod common;
use common::{check_against_golden, out_dir, root, Xvfb};

/// Runs the station on `x` with `args`, its state folder (autosave, recent sculpts) `state`.
fn run_station(x: &Xvfb, state: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_argile"))
        .arg("run")
        .args(args)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .env("XDG_STATE_HOME", state)
        .output()
        .expect("the argile binary runs")
}

/// Runs the station like `run_station` and returns what it printed, failing the test with its
/// output when it does not exit cleanly.
fn run_station_ok(x: &Xvfb, state: &Path, args: &[&str]) -> String {
    let out = run_station(x, state, args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    stdout
}

/// A fresh X server and the test's output folder, with the paths of its screenshot and saved
/// sculpt cleared of any earlier run's files.
struct Run {
    x: Xvfb,
    dir: std::path::PathBuf,
    shot: std::path::PathBuf,
    saved: std::path::PathBuf,
    /// Its state folder.
    state: std::path::PathBuf,
}

fn start(name: &str) -> Run {
    let x = Xvfb::start();
    let dir = out_dir(name);
    std::fs::create_dir_all(&dir).unwrap();
    let (shot, saved) = (dir.join(format!("{name}-screenshot.png")), dir.join(format!("{name}.argile")));
    let _ = std::fs::remove_file(&shot);
    let _ = std::fs::remove_file(&saved);
    // A state folder of its own, empty: no other run's recent sculpts or sessions to recover.
    let state = dir.join("state");
    let _ = std::fs::remove_dir_all(&state);
    Run { x, dir, shot, saved, state }
}

impl Run {
    /// `argile run` on `scene` with the validation layer, the input `script`, a screenshot
    /// and a save at the end, and `args` (frames, size, mode).
    fn scripted(&self, scene: &Path, script: &Path, args: &[&str]) -> std::process::Output {
        let (scene, script) = (scene.to_str().unwrap(), script.to_str().unwrap());
        let (shot, saved) = (self.shot.to_str().unwrap(), self.saved.to_str().unwrap());
        let fixed =
            [scene, "--validation", "--input-script", script, "--screenshot", shot, "--save-to", saved];
        run_station(&self.x, &self.state, &[&fixed[..], args].concat())
    }
}

#[test]
fn a_scripted_session_in_a_window_matches_its_golden_and_saves_the_sculpt() {
    let run = start("station");
    let (shot, saved) = (&run.shot, &run.saved);
    let scene = root().join("scenes/tests/station.toml");
    let script = root().join("tests/fixtures/station-input.toml");
    let out = run.scripted(&scene, &script, &["--frames", "16", "--size", "320x240"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    // Any validation message (leaked objects at teardown included) makes the run fail.
    assert!(out.status.success(), "the station failed:\n{stdout}\n{stderr}");
    assert!(stdout.contains("station closed after 16 frames"), "{stdout}");
    assert!(stdout.contains("frame stages, median ms over 16 frames: input"), "{stdout}");
    assert!(stdout.contains(&format!("saved the sculpt to {}", saved.display())), "{stdout}");

    let image = image::open(shot).expect("the screenshot was written").to_rgba8();
    assert_eq!(image.dimensions(), (320, 240));
    check_against_golden("station", "window", &image);

    // The saved sculpt is the slab with one groove through it (about 18% of its clay: a 4 cm
    // wide, 15 cm long cut through 4 cm); the second groove, undone, would take as much again.
    let sculpt = argile::app::load_sculpt(saved).expect("the saved sculpt loads");
    let slab = argile::app::final_field(&argile::scene::Scene::load(&scene).unwrap());
    let (carved, whole) = (sculpt.field.mass(), slab.mass());
    assert!(carved < 0.9 * whole && carved > 0.74 * whole, "one groove's worth carved: {carved} of {whole}");
}

#[test]
fn a_bad_input_script_is_refused_by_name_before_any_window_opens() {
    let x = Xvfb::start();
    let dir = out_dir("station");
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("bad-input.toml");
    std::fs::write(&script, "[[event]]\nframe = 1\npress = \"Ctrl+Banana\"\n").unwrap();
    let out =
        run_station(&x, &dir.join("state"), &["--frames", "1", "--input-script", script.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains(&format!("{}:1:1", script.display())) && stderr.contains("not a key name"),
        "{stderr}"
    );
    assert!(Path::new(&script).exists());
}

#[test]
fn quad_buffer_stereo_falls_back_with_a_notice_where_the_surface_has_one_layer() {
    // Xvfb's surfaces offer a single image layer: quad-buffer cannot be shown there.
    let x = Xvfb::start();
    let scene = root().join("scenes/tests/station.toml");
    let stdout = run_station_ok(
        &x,
        &out_dir("station").join("state"),
        &[
            scene.to_str().unwrap(),
            "--frames",
            "2",
            "--size",
            "64x48",
            "--display-mode",
            "quad-buffer",
            "--validation",
        ],
    );
    assert!(
        stdout.contains("offers no stereo swapchain (maxImageArrayLayers is 1)")
            && stdout.contains("showing anaglyph (the display fallback)"),
        "{stdout}"
    );
}

#[test]
fn a_station_that_cannot_start_says_why_exits_1_and_closes_its_session() {
    let x = Xvfb::start();
    let dir = out_dir("station-cannot-start");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // Quad-buffer asked of a one-layer surface, with no fallback.
    let scene = dir.join("no-fallback.toml");
    let plain = root().join("scenes/tests/station.toml");
    let station = std::fs::read_to_string(&plain).unwrap();
    std::fs::write(&scene, format!("{station}\n[display]\nfallback = \"none\"\n")).unwrap();
    // A UDP port already taken.
    let taken = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().to_string();
    let cases: [(Vec<&str>, &str); 3] = [
        (
            vec![scene.to_str().unwrap(), "--display-mode", "quad-buffer"],
            "quad-buffer stereo cannot be shown",
        ),
        (vec![plain.to_str().unwrap(), "--opentrack", &port], "cannot listen for opentrack datagrams"),
        // A monitor Xvfb has not.
        (
            vec![plain.to_str().unwrap(), "--monitor", "5"],
            "cannot open the station window on monitor `5`: there is no monitor 5; the monitors are 0: `",
        ),
    ];
    for (i, (args, says)) in cases.iter().enumerate() {
        let state = dir.join(format!("state-{i}"));
        let out = Command::new(env!("CARGO_BIN_EXE_argile"))
            .arg("run")
            .args(args)
            .args(["--frames", "2", "--size", "64x48"])
            .env("DISPLAY", &x.display)
            .env_remove("WAYLAND_DISPLAY")
            .env("XDG_STATE_HOME", &state)
            .output()
            .expect("the argile binary runs");
        let said =
            format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        assert_eq!(out.status.code(), Some(1), "{args:?}: {said}");
        assert!(said.contains(says) && !said.contains("panicked"), "{args:?}: {said}");
        let recover = recover_in(&state);
        let told = String::from_utf8_lossy(&recover.stdout);
        assert!(told.contains("No session is left to recover"), "{args:?}: the session was closed: {told}");
    }
    drop(taken);
}

#[test]
fn the_window_fills_its_monitor_when_asked_and_f11_switches_at_run_time() {
    let x = Xvfb::start();
    let dir = out_dir("station-fullscreen");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = root().join("scenes/tests/station.toml");
    let size = |png: &Path| image::image_dimensions(png).expect("the screenshot is written");
    // Asked at start, on the monitor named by its index: Xvfb's one screen is 800x600.
    let filled = dir.join("filled.png");
    let stdout = run_station_ok(
        &x,
        &dir.join("state-0"),
        &[
            scene.to_str().unwrap(),
            "--frames",
            "4",
            "--size",
            "64x48",
            "--fullscreen",
            "--monitor",
            "0",
            "--screenshot",
            filled.to_str().unwrap(),
            "--validation",
        ],
    );
    assert!(stdout.contains("window on monitor 0: `") && stdout.contains("800x600 at (0, 0)"), "{stdout}");
    assert!(stdout.contains(", filling it"), "{stdout}");
    assert_eq!(size(&filled), (800, 600));
    // F11 at run time fills it; the window opened small.
    let script = dir.join("f11.toml");
    std::fs::write(&script, "[[event]]\nframe = 1\npress = \"F11\"\n").unwrap();
    let switched = dir.join("switched.png");
    let stdout = run_station_ok(
        &x,
        &dir.join("state-1"),
        &[
            scene.to_str().unwrap(),
            "--frames",
            "12",
            "--size",
            "64x48",
            "--input-script",
            script.to_str().unwrap(),
            "--screenshot",
            switched.to_str().unwrap(),
        ],
    );
    assert!(stdout.contains("fullscreen: the window fills its monitor"), "{stdout}");
    assert_eq!(size(&switched), (800, 600));
}

#[test]
fn a_frame_sequential_window_shows_the_left_eye_then_the_right() {
    let x = Xvfb::start();
    let dir = out_dir("station-frame-sequential");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = root().join("scenes/tests/station.toml");
    // The panel hidden, so that the clay fills the picture.
    let script = dir.join("no-panel.toml");
    std::fs::write(&script, "[[event]]\nframe = 0\npress = \"F1\"\n").unwrap();
    // The last frame's picture of a run of 2, 3 and 4 frames: the eyes in turn (the HUD's frame
    // time is the same from the second frame on).
    let shots: Vec<image::RgbaImage> = (2..=4)
        .map(|frames| {
            let shot = dir.join(format!("frame-{frames}.png"));
            let stdout = run_station_ok(
                &x,
                &dir.join(format!("state-{frames}")),
                &[
                    scene.to_str().unwrap(),
                    "--frames",
                    &frames.to_string(),
                    "--size",
                    "160x120",
                    "--display-mode",
                    "frame-sequential",
                    "--input-script",
                    script.to_str().unwrap(),
                    "--screenshot",
                    shot.to_str().unwrap(),
                ],
            );
            assert!(stdout.contains("frame-sequential"), "the refresh is said: {stdout}");
            image::open(&shot).expect("the screenshot").to_rgba8()
        })
        .collect();
    let differing = |a: &image::RgbaImage, b: &image::RgbaImage| {
        a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count()
    };
    let (next, after) = (differing(&shots[0], &shots[1]), differing(&shots[0], &shots[2]));
    assert!(next > 500, "the third frame shows the other eye than the second: {next} pixels differ");
    assert!(
        after * 10 < next,
        "the fourth shows the second's eye again: {after} pixels differ, against {next}"
    );
}

/// The journal files of the autosave sessions under `state`.
fn journals(state: &std::path::Path) -> Vec<std::path::PathBuf> {
    let Ok(sessions) = std::fs::read_dir(state.join("argile/autosave")) else { return Vec::new() };
    sessions
        .filter_map(|s| std::fs::read_dir(s.ok()?.path()).ok())
        .flatten()
        .filter_map(|f| f.ok().map(|f| f.path()))
        .filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("journal-")))
        .collect()
}

/// `argile recover` with the state folder `state`.
fn recover_in(state: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_argile"))
        .arg("recover")
        .env("XDG_STATE_HOME", state)
        .output()
        .expect("argile recover runs")
}

/// A fresh folder for a case: (the folder, the carving scene, its input script, the state
/// folder).
fn carving_case(
    case: &str,
) -> (std::path::PathBuf, std::path::PathBuf, std::path::PathBuf, std::path::PathBuf) {
    let dir = out_dir(case);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let state = dir.join("state");
    (dir, root().join("scenes/tests/station.toml"), root().join("tests/fixtures/station-input.toml"), state)
}

#[test]
fn sigint_at_the_desk_saves_the_strokes_closes_the_session_and_exits_130() {
    let x = Xvfb::start();
    let (dir, scene, script, state) = carving_case("station-sigint");
    let saved = dir.join("sigint.argile");
    // A scripted session that would run for an hour: the groove is carved in its first frames.
    let child = Command::new(env!("CARGO_BIN_EXE_argile"))
        .arg("run")
        .arg(&scene)
        .args(["--frames", "200000", "--size", "320x240", "--input-script"])
        .arg(&script)
        .arg("--save-to")
        .arg(&saved)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .env("XDG_STATE_HOME", &state)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the argile binary runs");
    // The journal starts with the session's header; the stroke is journaled once it ends.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    let journaled =
        || journals(&state).iter().filter_map(|j| std::fs::metadata(j).ok()).map(|m| m.len()).sum::<u64>();
    let mut header = 0;
    while header == 0 || journaled() <= header {
        if header == 0 {
            header = journaled();
        }
        assert!(std::time::Instant::now() < deadline, "no stroke was journaled within 60 s");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    let out = child.wait_with_output().expect("argile ends");
    let said = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert_eq!(out.status.code(), Some(130), "{said}");
    assert!(said.contains("stopped by SIGINT"), "{said}");
    assert!(said.contains(&format!("saved the sculpt to {}", saved.display())), "{said}");
    let sculpt = argile::app::load_sculpt(&saved).expect("the saved sculpt loads");
    let slab = argile::app::final_field(&argile::scene::Scene::load(&scene).unwrap());
    assert!(sculpt.field.mass() < 0.9 * slab.mass(), "the groove is saved");
    // The session closed: nothing is left to recover.
    let recover = recover_in(&state);
    let said = String::from_utf8_lossy(&recover.stdout);
    assert!(said.contains("No session is left to recover"), "{said}");
}

#[test]
fn a_scripted_run_with_nowhere_to_save_leaves_its_strokes_to_recover() {
    let x = Xvfb::start();
    let (dir, scene, script, state) = carving_case("station-unsaved");
    let out = Command::new(env!("CARGO_BIN_EXE_argile"))
        .arg("run")
        .arg(&scene)
        .args(["--frames", "8", "--size", "320x240", "--input-script"])
        .arg(&script)
        .current_dir(&dir)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .env("XDG_STATE_HOME", &state)
        .output()
        .expect("the argile binary runs");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{said}{}", String::from_utf8_lossy(&out.stderr));
    assert!(said.contains("stroke(s) of this run are not saved (no --save-to)"), "{said}");
    let recover = recover_in(&state);
    let said = String::from_utf8_lossy(&recover.stdout);
    assert!(recover.status.success() && said.contains("its sculpt is recovered"), "{said}");
    let path = said.split(") in ").nth(1).expect("the recovered file is named").trim();
    let sculpt = argile::app::load_sculpt(std::path::Path::new(path)).expect("the recovered sculpt loads");
    let slab = argile::app::final_field(&argile::scene::Scene::load(&scene).unwrap());
    assert!(sculpt.field.mass() < 0.95 * slab.mass(), "the groove is recovered");
}

#[test]
fn a_scripted_run_that_can_save_nowhere_fails_and_its_journal_keeps_the_strokes() {
    let x = Xvfb::start();
    let (dir, scene, script, state) = carving_case("station-save-nowhere");
    // Neither the place asked for (under a file) nor the fallback folder can be written; the
    // autosave journal can.
    std::fs::write(dir.join("a-file"), "in the way").unwrap();
    std::fs::create_dir_all(state.join("argile")).unwrap();
    std::fs::write(state.join("argile/saved"), "in the way").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_argile"))
        .arg("run")
        .arg(&scene)
        .args(["--frames", "8", "--size", "320x240", "--input-script"])
        .arg(&script)
        .arg("--save-to")
        .arg(dir.join("a-file/sculpt.argile"))
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .env("XDG_STATE_HOME", &state)
        .output()
        .expect("the argile binary runs");
    let said = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(!out.status.success(), "{said}");
    assert!(said.contains("nothing could be saved as the station closed"), "{said}");
    assert!(!said.contains("stays in memory"), "the process ends: {said}");
    std::fs::remove_file(state.join("argile/saved")).unwrap();
    let recover = recover_in(&state);
    let said = String::from_utf8_lossy(&recover.stdout);
    assert!(recover.status.success() && said.contains("its sculpt is recovered"), "{said}");
}

/// The density and colour of `field` at `p` (metres).
fn sample(field: &argile::field::Field, p: [f32; 3]) -> (f32, [f32; 4]) {
    let mut reader = argile::field::FieldReader::new(field);
    let index = field.transform().world_to_index(argile::math::Vec3::from(p));
    (reader.density_at(index), reader.colour_at(index))
}

#[test]
fn the_desk_panel_picks_the_tool_its_size_and_colour_undoes_from_its_history_saves_through_its_browser_and_matches_its_goldens(
) {
    let run = start("panel");
    let (x, dir, shot, saved) = (&run.x, &run.dir, &run.shot, &run.saved);
    let browsed = dir.join("bust-panel.argile");
    let _ = std::fs::remove_file(&browsed);
    let scene = root().join("scenes/tests/station.toml");
    let script = root().join("tests/fixtures/panel-input.toml");
    let out =
        run.scripted(&scene, &script, &["--frames", "38", "--size", "960x540", "--display-mode", "mono"]);
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "the station failed:\n{stdout}\n{stderr}");
    let image = image::open(shot).expect("the screenshot was written").to_rgba8();
    check_against_golden("panel", "mono", &image);

    // The first stroke painted a 50 mm box's band moss green across the slab's upper half
    // (a 20 mm box would not reach its middle); the second, lower one was taken back from
    // the history, so the slab's lower edge keeps its colour.
    // The file browser saved it under the name typed, where saving wrote from then on (the
    // station's save at its end too): the file named on the command line was never written.
    assert!(!saved.exists(), "saving moved to the name the browser gave");
    assert!(stdout.contains(&format!("saved the sculpt to {}", browsed.display())), "{stdout}");
    let sculpt = argile::app::load_sculpt(&browsed).expect("the sculpt saved through the browser loads");
    let field = &sculpt.field;
    let front = 0.018;
    for p in [[0.06, 0.045, front], [0.06, 0.0, front]] {
        let (density, [r, g, b, _]) = sample(field, p);
        assert!(density > 0.5 && g > r && g > 2.0 * b, "moss green at {p:?}: {r} {g} {b}");
    }
    let (density, [r, g, _, _]) = sample(field, [0.06, -0.06, front]);
    assert!(density > 0.5 && r > 2.0 * g, "the slab's own colour where the undone stroke was: {r} {g}");
    let slab = argile::app::final_field(&argile::scene::Scene::load(&scene).unwrap());
    assert!((field.mass() - slab.mass()).abs() < 1e-3 * slab.mass(), "paint moves no clay");
    let history = field.history_stats();
    assert_eq!((history.undo_in_memory + history.undo_on_disk, history.redo), (1, 1), "{history:?}");

    // A stereo mode: the same panel in each eye's half, at zero parallax.
    let shot = dir.join("panel-side-by-side.png");
    let out = run_station(
        x,
        &run.state,
        &[
            scene.to_str().unwrap(),
            "--frames",
            "3",
            "--size",
            "960x540",
            "--display-mode",
            "side-by-side",
            "--validation",
            "--screenshot",
            shot.to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "the station failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let image = image::open(&shot).unwrap().to_rgba8();
    let (left, right) = (image.view(0, 0, 480, 540).to_image(), image.view(480, 0, 480, 540).to_image());
    // Zero parallax: the panel's pixels are the same in both eyes.
    let panel_differs = (0..540)
        .flat_map(|y| (0..200).map(move |x| (x, y)))
        .filter(|&(x, y)| left.get_pixel(x, y) != right.get_pixel(x, y))
        .count();
    assert_eq!(panel_differs, 0, "pixels of the panel that differ between the eyes");
    check_against_golden("panel", "side-by-side", &image);
}

/// `argile calibrate --adjust` in a window: keys size the screen and move the eye while the
/// pattern shows, Enter writes them into the calibration file keeping its comments, and a run
/// that leaves without writing says the values and leaves the file as it was.
#[test]
fn calibrate_adjust_writes_the_keys_changes_into_the_calibration_file() {
    let x = Xvfb::start();
    let dir = out_dir("calibrate-adjust");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("mine.toml");
    std::fs::write(&file, "# the desk monitor\n[screen]\nwidth_m = 0.5   # guessed\nheight_m = 0.28125\n")
        .unwrap();
    let calibrate = |script: &str, shot: &Path| {
        let script_path = dir.join("script.toml");
        std::fs::write(&script_path, script).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_argile"))
            .args(["calibrate", "--adjust", "--calibration", file.to_str().unwrap(), "--width", "256"])
            .args(["--size", "640x360", "--display-mode", "mono", "--frames", "8", "--validation"])
            .args(["--input-script", script_path.to_str().unwrap(), "--screenshot", shot.to_str().unwrap()])
            .env("DISPLAY", &x.display)
            .env_remove("WAYLAND_DISPLAY")
            .env("XDG_STATE_HOME", dir.join("state"))
            .output()
            .expect("the argile binary runs");
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(out.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
        stdout
    };
    let event = |frame: u32, key: &str| format!("[[event]]\nframe = {frame}\npress = \"{key}\"\n");
    let shot = dir.join("adjusted.png");
    let script =
        [event(2, "Shift+ArrowRight"), event(3, "Shift+ArrowRight"), event(4, "PageDown"), event(5, "Enter")];
    let stdout = calibrate(&script.concat(), &shot);
    assert!(stdout.contains("wrote the screen's size, the viewing distance and the IPD to"), "{stdout}");
    let written = std::fs::read_to_string(&file).unwrap();
    assert!(written.starts_with("# the desk monitor\n[screen]\nwidth_m = 0.52   # guessed\n"), "{written}");
    assert!(
        written.contains("height_m = 0.2925") && written.contains("default_eye_m = [0.0, 0.0, 0.595]"),
        "{written}"
    );
    // The left eye's picture (mono) with the L, not the R, and the ruler's ticks along the bottom
    // row, one each 10 mm of the picture: 640 pixels of Xvfb's 800-pixel screen, now 520 mm
    // wide, are 416 mm.
    let image = image::open(&shot).expect("the screenshot is written").to_rgba8();
    let (w, h) = image.dimensions();
    let white = |x: u32, y: u32| image.get_pixel(x, y).0[..3].iter().all(|&c| c > 200);
    let count = |x0: u32, x1: u32, y0: u32, y1: u32| {
        (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y))).filter(|&(x, y)| white(x, y)).count()
    };
    // Below the heads-up display's four lines, clear of the grid's bars' highlights.
    let (top, bottom) = (h * 3 / 20, h / 4);
    assert!(count(w / 40, w / 5, top, bottom) > 20, "the L is in the left eye's picture");
    assert_eq!(count(w * 177 / 200, w - w / 40, top, bottom), 0, "the R is not");
    let mut runs = 0;
    let mut last = false;
    for x in 0..w {
        let now = white(x, h - 1);
        runs += usize::from(now && !last);
        last = now;
    }
    assert_eq!(runs, 42, "ticks along the bottom edge, at 0 to 410 mm");

    // Changed and not written: the run says the values and the file stays.
    let stdout = calibrate(&event(2, "ArrowLeft"), &dir.join("unwritten.png"));
    assert!(
        stdout.contains("the adjustments were not written to") && stdout.contains("width_m = 0.51900"),
        "{stdout}"
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), written);
}

/// The recovered-sessions prompt, end to end: a run that could save nowhere leaves its stroke
/// in an unclosed session; the next start recovers it and its panel offers the sculpt; a click
/// on "open" opens it, and a save writes the groove back to that sculpt.
#[test]
fn the_next_start_offers_the_recovered_sculpt_and_a_click_opens_it() {
    let x = Xvfb::start();
    let (dir, scene, script, state) = carving_case("station-recovered-prompt");
    let run = |args: &[&str]| run_station_ok(&x, &state, &[&[scene.to_str().unwrap()], args].concat());
    let said = run(&["--frames", "8", "--size", "320x240", "--input-script", script.to_str().unwrap()]);
    assert!(said.contains("stroke(s) of this run are not saved"), "{said}");
    // The next start: the prompt heads the panel; its "open" button, then Ctrl+S.
    let clicks = dir.join("open-recovered.toml");
    std::fs::write(
        &clicks,
        "[[event]]\nframe = 2\nclick = [32, 48]\n[[event]]\nframe = 5\npress = \"Ctrl+KeyS\"\n",
    )
    .unwrap();
    let elsewhere = dir.join("elsewhere.argile");
    let said = run(&[
        "--frames",
        "8",
        "--size",
        "960x540",
        "--display-mode",
        "mono",
        "--validation",
        "--input-script",
        clicks.to_str().unwrap(),
        "--save-to",
        elsewhere.to_str().unwrap(),
    ]);
    assert!(said.contains("its sculpt is recovered"), "recovered at start: {said}");
    let opened =
        said.lines().find(|l| l.starts_with("opened ")).unwrap_or_else(|| panic!("nothing opened: {said}"));
    assert!(opened.contains("sculpt-"), "the recovered sculpt is what opened: {opened}");
    let saved = said
        .lines()
        .find_map(|l| l.strip_prefix("saved the sculpt to "))
        .unwrap_or_else(|| panic!("no save: {said}"));
    assert!(
        !elsewhere.exists() && saved.contains("sculpt-"),
        "saving writes back to the opened sculpt: {saved}"
    );
    let sculpt = argile::app::load_sculpt(Path::new(saved.trim())).expect("the saved sculpt loads");
    let slab = argile::app::final_field(&argile::scene::Scene::load(&scene).unwrap());
    assert!(sculpt.field.mass() < 0.95 * slab.mass(), "the station held the recovered groove");
}
