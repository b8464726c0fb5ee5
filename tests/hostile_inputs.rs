//! Hostile and mistaken inputs, walked in one place, through the real binary: every one is
//! refused at once (well within a bound of seconds, never hanging or growing without bound),
//! with an exit status of 1, a sentence that names the file (and the line of the key at
//! fault, for TOML files), nothing of the file echoed raw or whole, and no panic.
//!
//! The items of the crash-window and autosave faults are held by the tests that kill or
//! starve the real binary: `tests/autosave_crash.rs` (SIGKILL at random points, before the
//! first snapshot included), `tests/autosave.rs` (full disks, failed recoveries, scripted
//! runs, leftovers of killed saves and undo spills). Paths that are devices, FIFOs, folders or
//! oversized files: `tests/cli.rs` (`devices_fifos_folders_and_oversized_files_...`).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("argile-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// What a refusal must look like.
struct Refusal<'a> {
    /// A phrase of the message.
    says: &'a str,
    /// `file:line:` where the message must point, when it is about a TOML key.
    at_line: Option<usize>,
}

/// Runs `argile ARGS` in `dir` and checks it is refused as the module says, within `limit`.
fn refused(dir: &Path, args: &[&str], file: &Path, refusal: Refusal<'_>, limit: Duration) -> String {
    let started = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_argile"))
        .args(args)
        .current_dir(dir)
        .env("XDG_STATE_HOME", dir.join("state"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?} ran past {limit:?}: a runaway input");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    let said = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{args:?} exits 1: {said}");
    assert!(said.contains(refusal.says), "{args:?} says `{}`: {said}", refusal.says);
    let name = file.display().to_string();
    match refusal.at_line {
        Some(line) => {
            assert!(said.contains(&format!("{name}:{line}:")), "{args:?} points at line {line}: {said}")
        }
        None => assert!(said.contains(&name), "{args:?} names {name}: {said}"),
    }
    assert!(!said.contains("panicked"), "{args:?}: {said}");
    assert!(said.len() < 4000, "{args:?} says {} bytes: what a file says is cut", said.len());
    assert!(!said.contains('\u{1b}'), "{args:?}: no raw escape byte reaches the terminal");
    said
}

/// Scenes that ask for endless work or memory, or hold values no work can use: each is
/// refused by `save` (which plays the timeline and needs no GPU) at the key's line.
#[test]
fn scenes_whose_values_run_away_are_refused_at_their_line() {
    let dir = temp_dir("scenes");
    let freeform = |half: f32| {
        format!(
            "[[tool]]\nname = \"copy\"\nshape = \"freeform\"\nregion_min_m = [{m}, {m}, {m}]\n\
             region_max_m = [{half}, {half}, {half}]\naction = \"add\"\n",
            m = -half
        )
    };
    let key = "[[tool]]\nname = \"t\"\nradius_m = 0.01\naction = \"add\"\n";
    // A key of that tool, then its time or position.
    let keyed = |rest: &str| format!("{key}[[key]]\ntool = \"t\"\n{rest}\n");
    let cases: Vec<(&str, String, &str, Option<usize>)> = vec![
        // Item 3: hang at flat memory.
        ("step", "[timeline]\nstep_s = 1e-12\n".into(), "step_s must be", Some(2)),
        (
            "key-time",
            keyed("position_m = [0, 0, 0]\ntime_s = 1e12"),
            "time_s must be 0 to",
            Some(5),
        ),
        (
            "key-far",
            keyed("time_s = 0\nposition_m = [1e30, 0, 0]"),
            "position_m must be within",
            Some(5),
        ),
        ("clay-radius", "[[clay]]\nshape = \"sphere\"\nradius_m = 1e6\n".into(), "radius_m must be", Some(1)),
        ("tool-radius", "[[tool]]\nname = \"t\"\nradius_m = 1e6\naction = \"add\"\n".into(), "radius_m", Some(1)),
        // Item 3: grow without bound.
        ("freeform-100", freeform(100.0), "freeform region", Some(1)),
        ("clay-scale", "[[clay]]\nshape = \"sphere\"\nradius_m = 0.1\nscale = 1e9\n".into(), "scale must be", Some(1)),
        (
            "box-50m",
            "[field]\nvoxel_size_m = 0.002\n[[clay]]\nshape = \"box\"\nsize_m = [50, 50, 50]\n".into(),
            "size_m must be",
            Some(3),
        ),
        // Within every length limit, over the memory budget: refused with the estimate.
        (
            "box-10m",
            "[field]\nvoxel_size_m = 0.002\n[[clay]]\nshape = \"box\"\nsize_m = [10, 10, 10]\n".into(),
            "would need about",
            None,
        ),
        (
            "sphere-fine",
            "[field]\nvoxel_size_m = 0.0001\n[[clay]]\nshape = \"sphere\"\nradius_m = 0.5\n".into(),
            "over the memory budget",
            None,
        ),
        // Item 3 and 8: NaN and infinities, wherever they are written.
        ("nan-key", keyed("time_s = 0\nposition_m = [nan, 0, 0]"), "finite number", Some(8)),
        ("nan-rotation", "[[clay]]\nshape = \"sphere\"\nradius_m = 0.1\nrotation_deg = [0, inf, 0]\n".into(), "finite number", Some(4)),
        ("nan-environment", "[environment]\nintensity = nan\n".into(), "finite number", Some(2)),
        ("nan-up", "[camera]\nup = [0, nan, 0]\n".into(), "finite number", Some(2)),
        ("nan-stage", "[stage]\nmin_m = [-1, -1, nan]\n".into(), "finite number", Some(2)),
        ("nan-material", "[material]\nspecular = nan\n".into(), "finite number", Some(2)),
        ("nan-light", "[[light]]\nkind = \"point\"\nposition_m = [0, -inf, 0]\n".into(), "finite number", Some(3)),
        ("nan-glyph", format!("{key}glyph_opacity = nan\n"), "finite number", Some(5)),
        ("nan-boxes", "[virtual_clay]\nfixed_boxes_m = [[[0, 0, 0], [1, nan, 1]]]\n".into(), "finite number", Some(2)),
        // Item 8: more runaway values.
        ("time-2-18", format!("{key}[[capture]]\nname = \"late\"\ntime_s = 262144\n"), "time_s must be 0 to", Some(5)),
        (
            "falloff",
            "[[tool]]\nname = \"s\"\nshape = \"sphere\"\nradius_m = 0.01\naction = \"stamp\"\nfalloff_m = 1e9\n".into(),
            "falloff_m",
            Some(1),
        ),
        ("tool-scale", "[[tool]]\nname = \"t\"\nradius_m = 0.01\naction = \"add\"\nscale = [1e9, 1, 1]\n".into(), "scale must be", Some(1)),
        ("freeform-1000", freeform(1000.0), "region", Some(1)),
        // Values beyond NaN that keep the work finite: light, stage, material, camera.
        ("light-intensity", "[[light]]\nkind = \"point\"\nposition_m = [0, 1, 0]\nintensity = 1e30\n".into(), "intensity must be from 0 to 1000", Some(1)),
        ("light-far", "[[light]]\nkind = \"point\"\nposition_m = [0, 1e9, 0]\n".into(), "position_m must be within", Some(1)),
        ("stage-far", "[stage]\nmax_m = [1e7, 1, 1]\n".into(), "[stage] max_m must be within", Some(2)),
        ("shininess", "[output]\nsamples = 4\n\n[material]\nshininess = 5000\n".into(), "shininess must be from 1 to 1024", Some(5)),
        ("far-plane", "[camera]\nfar_m = 1e9\n".into(), "far_m must be from", Some(2)),
        ("table-far", "[virtual_clay]\ntable_y_m = -1e9\n".into(), "table_y_m must lie within", Some(2)),
        // Item 10: a range error points at its key's line, not at 1:1.
        ("fov", "# a comment\n[camera]\neye_m = [0, 0, 1]\nfov_y_deg = 400\n".into(), "fov_y_deg must be between", Some(4)),
        ("voxel", "\n\n[field]\nvoxel_size_m = 1\n".into(), "voxel_size_m must be between", Some(4)),
        ("samples", "[output]\nwidth_px = 256\nsamples = 3\n".into(), "samples must be 1, 2, 4 or 8", Some(3)),
        // Item 9: what the file says is quoted cut and escaped.
        (
            "long-name",
            format!("{key}[[key]]\ntool = \"{}\"\ntime_s = 0\nposition_m = [0, 0, 0]\n", "x".repeat(10 << 20)),
            "more characters",
            Some(5),
        ),
        ("escape", format!("{key}[[key]]\ntool = \"\\u001b[2J\"\ntime_s = 0\nposition_m = [0, 0, 0]\n"), "\\u{1b}[2J", Some(5)),
    ];
    for (name, text, says, at_line) in &cases {
        let scene = dir.join(format!("{name}.toml"));
        std::fs::write(&scene, text).unwrap();
        let out = dir.join(format!("{name}.argile"));
        // A budget of its own, so that the refusals over it do not depend on the machine.
        let args =
            ["--memory-budget", "16G", "save", scene.to_str().unwrap(), "--out", out.to_str().unwrap()];
        refused(&dir, &args, &scene, Refusal { says, at_line: *at_line }, Duration::from_secs(20));
        assert!(!out.exists(), "{name}: nothing is written");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Sizes a sculpt file claims, a budget set low, renders larger than it, environment images
/// too large to hold: refused before the memory is taken.
#[test]
fn sizes_claimed_and_work_over_the_budget_are_refused_before_allocating() {
    let dir = temp_dir("sizes");
    let sculpt = dir.join("default.argile");
    let made = Command::new(env!("CARGO_BIN_EXE_argile"))
        .args(["save", "scenes/default.toml", "--out"])
        .arg(&sculpt)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("XDG_STATE_HOME", dir.join("state"))
        .output()
        .unwrap();
    assert!(made.status.success(), "{}", String::from_utf8_lossy(&made.stderr));
    let s = sculpt.to_str().unwrap();
    let limit = Duration::from_secs(20);
    // Item 2: a chunk header that claims 0xFFFFFFF0 bytes (the first chunk's raw length, after
    // the 12-byte file header and the 4-byte tag).
    let mut bytes = std::fs::read(&sculpt).unwrap();
    bytes[16..20].copy_from_slice(&0xFFFF_FFF0u32.to_le_bytes());
    let claims = dir.join("claims.argile");
    std::fs::write(&claims, &bytes).unwrap();
    let c = claims.to_str().unwrap();
    refused(
        &dir,
        &["export", c, "--format", "stl", "--out", "x.stl"],
        &claims,
        Refusal { says: "chunk 0", at_line: None },
        limit,
    );
    // A budget below what the sculpt's clay takes: refused as it is read, with what was read.
    let said = refused(
        &dir,
        &["--memory-budget", "2M", "export", s, "--format", "stl", "--out", "y.stl"],
        &sculpt,
        Refusal { says: "over the memory budget of 2.0 MiB", at_line: None },
        limit,
    );
    assert!(said.contains("bricks read"), "{said}");
    assert!(!dir.join("y.stl").exists());
    // A scene whose clay fits the machine but not the budget: refused with the estimate.
    let scene = dir.join("ball.toml");
    std::fs::write(&scene, "[field]\nvoxel_size_m = 0.001\n[[clay]]\nshape = \"sphere\"\nradius_m = 0.2\n")
        .unwrap();
    let said = refused(
        &dir,
        &["--memory-budget", "64M", "save", scene.to_str().unwrap(), "--out", "ball.argile"],
        &scene,
        Refusal { says: "would need about", at_line: None },
        limit,
    );
    assert!(
        said.contains("bricks of 1 mm voxels") && said.contains("raise the budget with --memory-budget"),
        "{said}"
    );
    // Item 8: an 8192² stereo render within a budget that cannot hold its targets.
    let said = refused(
        &dir,
        &["--memory-budget", "4G", "render", s, "--out", "r", "--size", "8192x8192"],
        &sculpt,
        Refusal { says: "a stereo render of 8192x8192 pixels per eye", at_line: None },
        limit,
    );
    assert!(said.contains("would need about 7.5 GiB"), "{said}");
    // Item 8: a 16384 × 8192 environment (its header says so; it is never decoded).
    let png = dir.join("huge.png");
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend_from_slice(&16384u32.to_be_bytes());
    ihdr.extend_from_slice(&8192u32.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    let mut header = b"\x89PNG\r\n\x1a\n\0\0\0\x0d".to_vec();
    header.extend_from_slice(&ihdr);
    header.extend_from_slice(&crc32fast::hash(&ihdr).to_be_bytes());
    // An empty IDAT and the end: the header is all a reader reads before the image data.
    for tag in [b"IDAT", b"IEND"] {
        header.extend_from_slice(&[0, 0, 0, 0]);
        header.extend_from_slice(tag);
        header.extend_from_slice(&crc32fast::hash(tag).to_be_bytes());
    }
    std::fs::write(&png, &header).unwrap();
    let lit = dir.join("lit.toml");
    std::fs::write(&lit, "[environment]\nkind = \"image\"\npath = \"huge.png\"\n").unwrap();
    refused(
        &dir,
        &["render", lit.to_str().unwrap(), "--out", "r"],
        &png,
        Refusal { says: "16384x8192 texels", at_line: None },
        limit,
    );
    // Item 10: a missing path says the system's reason once; a folder says it is one.
    let missing = dir.join("missing.toml");
    let said = refused(
        &dir,
        &["export", missing.to_str().unwrap(), "--format", "stl", "--out", "m.stl"],
        &missing,
        Refusal { says: "No such file", at_line: None },
        limit,
    );
    assert_eq!(said.matches("No such file").count(), 1, "{said}");
    let said = refused(
        &dir,
        &["run", "--calibration", missing.to_str().unwrap(), "--frames", "1"],
        &missing,
        Refusal { says: "cannot read screen calibration file", at_line: None },
        limit,
    );
    assert_eq!(said.matches("No such file").count(), 1, "{said}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A long build says what it builds, and a stopping signal breaks it off: the station and
/// autosaved commands handle SIGINT, SIGTERM and SIGHUP, and stop between two slabs of bricks.
#[test]
fn a_long_build_shows_what_it_builds_and_stops_on_a_signal() {
    let dir = temp_dir("long");
    let scene = dir.join("long.toml");
    // About 4 million bricks, 2 GiB: many seconds of work.
    std::fs::write(&scene, "[field]\nvoxel_size_m = 0.0005\n[[clay]]\nshape = \"sphere\"\nradius_m = 0.4\n")
        .unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_argile"))
        .args(["save", scene.to_str().unwrap(), "--out", "long.argile", "--autosave"])
        .current_dir(&dir)
        .env("XDG_STATE_HOME", dir.join("state"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let started = Instant::now();
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    while child.try_wait().unwrap().is_none() {
        assert!(started.elapsed() < Duration::from_secs(10), "the build stops within seconds of SIGINT");
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    let said = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{said}");
    assert!(said.contains("building the initial clay of") && said.contains("bricks"), "{said}");
    assert!(said.contains("SIGINT received while building the initial clay"), "{said}");
    assert!(!dir.join("long.argile").exists(), "nothing half-built is saved");
    std::fs::remove_dir_all(&dir).unwrap();
}
