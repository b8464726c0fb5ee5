//! The `argile` command as a user runs it.

use std::process::Command;

fn argile() -> Command {
    Command::new(env!("CARGO_BIN_EXE_argile"))
}

/// The station run in `dir` without a display, its state (recovery journal) in `dir`.
fn headless_in(dir: &std::path::Path) -> Command {
    let mut c = argile();
    c.current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("XDG_STATE_HOME", dir.join("state"));
    c
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("argile-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn info_lists_vulkan_openxr_and_input_without_a_display() {
    let out = argile().arg("info").env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY").output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        text.contains("Vulkan:") && text.contains("OpenXR:") && text.contains("Input devices:"),
        "{text}"
    );
    assert!(text.contains("multiview"), "the Vulkan section names the multiview capability: {text}");
    assert!(
        text.contains("mouse: the window's pointer, drives the scene"),
        "each input names its target: {text}"
    );
}

#[test]
fn bench_json_prints_one_object_per_line() {
    let out = argile().args(["bench", "--json", "--quick", "stamp"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<serde_json::Value> =
        text.lines().map(|l| serde_json::from_str(l).expect("a JSON object per line")).collect();
    assert_eq!(lines.len(), 4, "one line per radius");
    assert!(lines.iter().all(|l| l["workload"] == "stamp"));
}

#[test]
fn bench_render_stereo_runs_on_the_vulkan_device() {
    let out = argile().args(["bench", "--json", "--quick", "render-stereo"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(lines.len(), 4, "two scenes, each with joint and split view passes");
    assert!(lines[1]["triangles"].as_u64().unwrap() >= 100_000);
    let passes: Vec<&str> = lines.iter().map(|l| l["view_passes"].as_str().unwrap()).collect();
    assert_eq!(passes, ["joint", "joint", "split", "split"]);
    assert!(lines.iter().all(|l| l["median_frame_ms"].as_f64().unwrap() > 0.0 && l["device"].is_string()));
}

#[test]
fn bench_compose_times_every_display_mode() {
    let out = argile().args(["bench", "--json", "--quick", "compose"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let modes: Vec<&str> = lines.iter().map(|l| l["mode"].as_str().unwrap()).collect();
    assert_eq!(
        modes.len(),
        argile::stereo::display::DisplayMode::ALL.len(),
        "one line per display mode: {modes:?}"
    );
    assert!(modes.contains(&"frame-sequential") && modes.contains(&"anaglyph-amber-blue"));
    assert!(modes.contains(&"anaglyph") && modes.contains(&"quad-buffer"));
    let side_by_side = lines.iter().find(|l| l["mode"] == "side-by-side").unwrap();
    assert_eq!(side_by_side["output_width_px"], 2 * side_by_side["eye_width_px"].as_u64().unwrap());
    assert!(lines.iter().all(|l| l["median_compose_ms"].as_f64().unwrap() > 0.0));
}

#[test]
fn render_writes_the_pair_and_the_composed_images_and_says_where() {
    let dir = temp_dir("render");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tests/parallax.toml");
    let out = argile()
        .args(["render", scene, "--out"])
        .arg(&dir)
        .args(["--display-mode", "side-by-side", "--display-mode", "quad-buffer", "--size", "64x48"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    let names = [
        "parallax-left.png",
        "parallax-right.png",
        "parallax-side-by-side.png",
        "parallax-quad-buffer-left.png",
        "parallax-quad-buffer-right.png",
    ];
    for name in names {
        assert!(text.contains(name), "says where {name} is: {text}");
        let img = image::open(dir.join(name)).unwrap();
        assert_eq!(img.height(), 48);
    }
    assert_eq!(image::open(dir.join("parallax-side-by-side.png")).unwrap().width(), 128);
    let read = |name: &str| image::open(dir.join(name)).unwrap().to_rgba8();
    assert_eq!(read("parallax-quad-buffer-left.png"), read("parallax-left.png"));
    assert_eq!(read("parallax-quad-buffer-right.png"), read("parallax-right.png"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_scene_display_mode_writes_the_composed_image_unless_the_command_line_names_others() {
    let dir = temp_dir("display");
    let scene = dir.join("display.toml");
    std::fs::write(
        &scene,
        "[output]\nwidth_px = 32\nheight_px = 24\nsamples = 1\n[display]\nmode = \"top-bottom\"\n",
    )
    .unwrap();
    let out = argile().arg("render").arg(&scene).arg("--out").arg(dir.join("a")).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(image::open(dir.join("a/final-top-bottom.png")).unwrap().height(), 48);
    let out = argile()
        .arg("render")
        .arg(&scene)
        .arg("--out")
        .arg(dir.join("b"))
        .args(["--display-mode", "mono"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(dir.join("b/final-mono.png").exists() && !dir.join("b/final-top-bottom.png").exists());
    let out =
        argile().arg("render").arg(&scene).args(["--out", "o", "--display-mode", "3d"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("side-by-side-half"), "the modes are listed");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn scene_errors_name_the_file_line_and_column() {
    let dir = temp_dir("bad-scene");
    let scene = dir.join("bad.toml");
    std::fs::write(&scene, "[camera]\nfov_y_deg = 30.0\nfov = 3\n").unwrap();
    let out = argile().arg("render").arg(&scene).arg("--out").arg(dir.join("out")).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("{}:3:1: unknown field `fov`", scene.display())), "{err}");
    assert!(!dir.join("out").exists(), "nothing is written for a bad scene");

    let out = argile().args(["render", "no/such/scene.toml", "--out"]).arg(dir.join("out")).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read scene file no/such/scene.toml"));

    let out = argile().args(["render", "x.toml", "--out", "o", "--size", "12x9000"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("from 16 to 8192"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn calibrate_prints_the_frusta_and_writes_the_test_pattern() {
    let dir = temp_dir("calibrate");
    let calibration = dir.join("screen.toml");
    std::fs::write(&calibration, "[viewer]\ndefault_eye_m = [0.0, 0.0, 0.7]\nipd_m = 0.065\n").unwrap();
    let out = argile()
        .args(["calibrate", "--calibration"])
        .arg(&calibration)
        .arg("--out")
        .arg(&dir)
        .args(["--width", "128"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    for words in [
        "700.0 mm from the screen",
        "IPD 65.0 mm",
        "left eye at (-32.5, 0.0, 700.0) mm",
        "right eye",
        "crossed",
    ] {
        assert!(text.contains(words), "says {words:?}: {text}");
    }
    for name in ["calibration-left.png", "calibration-right.png"] {
        assert!(text.contains(name), "says where {name} is: {text}");
        assert_eq!(image::open(dir.join(name)).unwrap().width(), 128);
    }

    std::fs::write(&calibration, "[viewer]\nipd_m = 63\n").unwrap();
    let out = argile()
        .args(["calibrate", "--calibration"])
        .arg(&calibration)
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("{}:2:9: `viewer.ipd_m`", calibration.display())), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_station_without_a_display_renders_the_default_scene_headless_and_says_where() {
    let dir = temp_dir("headless-station");
    let out = headless_in(&dir).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("No window can open here: no display"), "{stdout}");
    for name in ["default-left.png", "default-right.png", "default-anaglyph.png"] {
        let path = dir.join("argile-out").join(name);
        assert!(stdout.contains(&format!("argile-out/{name}")), "says where {name} is: {stdout}");
        let image = image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(image.width(), 1024);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn info_says_what_each_device_drives_and_where_its_calibration_comes_from() {
    let dir = temp_dir("input-settings");
    let config = dir.join("config");
    std::fs::create_dir_all(&config).unwrap();
    std::fs::write(
        dir.join("input.toml"),
        "[targets]\nmouse = \"light\"\n[calibration]\nmouse = \"m.toml\"\n",
    )
    .unwrap();
    std::fs::write(dir.join("m.toml"), "trackball = \"bell\"\n").unwrap();
    let out = argile()
        .args(["info", "--input"])
        .arg(dir.join("input.toml"))
        .env("XDG_CONFIG_HOME", &config)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    let m = dir.join("m.toml");
    assert!(
        text.contains(&format!("mouse: the window's pointer, drives the light (settings: {}", m.display())),
        "{text}"
    );
    assert!(
        text.contains("spacemouse drives the tool; calibration: shipped calibration/spacemouse.toml"),
        "{text}"
    );
    assert!(
        text.contains("gamepad drives the second_tool; calibration: shipped calibration/gamepad.toml"),
        "{text}"
    );
    assert!(text
        .contains(&format!("mouse drives the light; calibration: {} (over the shipped file)", m.display())));

    std::fs::write(dir.join("input.toml"), "[targets]\nmouse = \"lamp\"\n").unwrap();
    let out = argile().args(["info", "--input"]).arg(dir.join("input.toml")).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("input.toml:2:9:") && err.contains("lamp"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn render_and_save_take_a_sculpt_file_where_they_take_a_scene() {
    let dir = temp_dir("sculpt-as-scene");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tests/parallax.toml");
    let sculpt = dir.join("parallax.argile");
    let run = |args: &[&std::ffi::OsStr]| {
        let out = argile().args(args).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
        text
    };
    let os = |s: &str| std::ffi::OsString::from(s);
    run(&[&os("save"), &os(scene), &os("--out"), sculpt.as_os_str()]);
    let copy = dir.join("copy.argile");
    run(&[&os("save"), sculpt.as_os_str(), &os("--out"), copy.as_os_str()]);
    let (a, b) = (argile::app::load_sculpt(&sculpt).unwrap(), argile::app::load_sculpt(&copy).unwrap());
    assert!(a.field.same_samples(&b.field) && a.scene_toml == b.scene_toml, "saving a sculpt copies it");

    // The sculpt, rendered in the scene stored in it, looks as the scene itself does.
    let (from_scene, from_sculpt) = (dir.join("scene"), dir.join("sculpt"));
    run(&[&os("render"), &os(scene), &os("--out"), from_scene.as_os_str(), &os("--size"), &os("64x48")]);
    let text = run(&[
        &os("render"),
        copy.as_os_str(),
        &os("--out"),
        from_sculpt.as_os_str(),
        &os("--size"),
        &os("64x48"),
    ]);
    assert!(text.contains("parallax-left.png"), "{text}");
    for eye in ["left", "right"] {
        let read =
            |d: &std::path::Path| image::open(d.join(format!("parallax-{eye}.png"))).unwrap().to_rgba8();
        assert_eq!(read(&from_scene), read(&from_sculpt), "{eye} eye");
    }
    // The station without a display renders the sculpt headless, at the scene's size.
    let out = headless_in(&dir).arg("run").arg(&copy).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("Rendering the copy scene headless"), "{stdout}");
    let left = image::open(dir.join("argile-out/parallax-left.png")).unwrap();
    assert_eq!((left.width(), left.height()), (256, 192));
    let missing = dir.join("missing.argile");
    let out = argile().args(["render"]).arg(&missing).args(["--out"]).arg(&dir).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("missing.argile"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn without_a_headset_run_xr_goes_on_with_the_sculpt_it_was_given() {
    let dir = temp_dir("xr-fallback");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tests/toothpaste.toml");
    let sculpt = dir.join("paste.argile");
    assert!(argile().args(["save", scene, "--out"]).arg(&sculpt).output().unwrap().status.success());
    let reference = argile().arg("render").arg(&sculpt).arg("--out").arg(dir.join("ref")).output().unwrap();
    assert!(reference.status.success(), "{}", String::from_utf8_lossy(&reference.stderr));
    // No runtime: the desktop station takes over, here headless, on the same sculpt.
    let out = headless_in(&dir)
        .env("XR_RUNTIME_JSON", dir.join("no-runtime.json"))
        .args(["run", "--xr"])
        .arg(&sculpt)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{said}{}", String::from_utf8_lossy(&out.stderr));
    assert!(said.contains("No headset session") && said.contains("headless"), "{said}");
    let png = |d: &str| std::fs::read(dir.join(d).join("toothpaste-left.png")).unwrap();
    assert!(png("argile-out") == png("ref"), "the sculpt's clay, not the empty scene: {said}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn devices_fifos_folders_and_oversized_files_are_refused_by_name_at_once() {
    let dir = temp_dir("hostile-paths");
    let fifo = dir.join("pipe.argile");
    let scene_fifo = dir.join("pipe.toml");
    for f in [&fifo, &scene_fifo] {
        assert!(Command::new("mkfifo").arg(f).status().unwrap().success());
    }
    let huge = dir.join("huge.toml");
    std::fs::write(&huge, vec![b'#'; (16 << 20) + 1]).unwrap();
    let calibration = dir.join("screen.toml");
    std::fs::write(&calibration, vec![b'#'; (1 << 20) + 1]).unwrap();
    let cases: [(Vec<std::ffi::OsString>, &str); 6] = [
        (
            vec!["save".into(), "/dev/zero".into(), "--out".into(), dir.join("a.argile").into()],
            "it is a device",
        ),
        (vec!["save".into(), fifo.clone().into(), "--out".into(), dir.join("b.argile").into()], "FIFO"),
        (vec!["info".into(), fifo.clone().into()], "FIFO"),
        (vec!["render".into(), scene_fifo.clone().into(), "--out".into(), dir.join("r").into()], "FIFO"),
        (
            vec!["save".into(), dir.clone().join(".").into(), "--out".into(), dir.join("c.argile").into()],
            "folder",
        ),
        (
            vec!["save".into(), huge.clone().into(), "--out".into(), dir.join("d.argile").into()],
            "over the 16777216-byte limit",
        ),
    ];
    for (args, expected) in cases {
        let started = std::time::Instant::now();
        let out = argile().args(&args).env("XDG_STATE_HOME", dir.join("state")).output().unwrap();
        let said = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}: {said}");
        assert!(said.contains(expected), "{args:?}: {said}");
        assert!(
            started.elapsed() < std::time::Duration::from_secs(20),
            "{args:?} took {:?}",
            started.elapsed()
        );
    }
    let out = argile()
        .args(["calibrate", "--calibration"])
        .arg(&calibration)
        .arg("--out")
        .arg(dir.join("cal"))
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && said.contains("over the 1048576-byte limit"), "{said}");
    assert!(said.contains(&calibration.display().to_string()), "the file is named: {said}");
    std::fs::remove_dir_all(&dir).unwrap();
}
