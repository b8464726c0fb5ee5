//! Crash recovery end to end: `argile save --autosave` sculpting a scripted session is killed
//! with SIGKILL at random points; the next `argile recover` must give back exactly the clay
//! after some completed stroke (bit for bit), never a torn stroke, and never fewer strokes
//! than the session had reported on disk before it was killed.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use argile::app::{load_sculpt, Playback};
use argile::field::Field;
use argile::scene::Scene;

const STROKES: usize = 48;

/// A session of short strokes, alternately adding, carving and painting, spread over a slab.
fn scene_text() -> String {
    let mut text = String::from(
        "[field]\nvoxel_size_m = 0.001\n[timeline]\nstep_s = 0.01\n\
         [[clay]]\nshape = \"box\"\nposition_m = [0.0, -0.01, 0.0]\nsize_m = [0.12, 0.02, 0.12]\n\
         [[tool]]\nname = \"add\"\nradius_m = 0.012\naction = \"add\"\ncolour = \"#c04020\"\n\
         [[tool]]\nname = \"carve\"\nradius_m = 0.009\naction = \"remove\"\n\
         [[tool]]\nname = \"paint\"\nradius_m = 0.01\naction = \"paint\"\ncolour = \"#2040c0\"\n",
    );
    for i in 0..STROKES {
        let t0 = i as f32 * 0.1;
        let tool = ["add", "carve", "paint"][i % 3];
        let x = -0.05 + 0.1 * ((i * 7) % STROKES) as f32 / STROKES as f32;
        let z = -0.05 + 0.1 * ((i * 11) % STROKES) as f32 / STROKES as f32;
        text += &format!(
            "[[key]]\ntime_s = {t0:.2}\ntool = \"{tool}\"\nposition_m = [{x:.4}, 0.0, {z:.4}]\nactive = true\n\
             [[key]]\ntime_s = {:.2}\ntool = \"{tool}\"\nposition_m = [{:.4}, 0.0, {:.4}]\n",
            t0 + 0.06,
            x + 0.02,
            z + 0.01
        );
    }
    text
}

/// The clay after 0, 1, 2, … completed strokes (strokes that changed something, as the
/// journal counts them).
fn reference_states(scene: &Scene) -> Vec<Field> {
    let mut playback = Playback::new(scene);
    let steps = |f: &Field| {
        let s = f.history_stats();
        s.undo_in_memory + s.undo_on_disk + s.dropped
    };
    let mut states = vec![playback.field().clone()];
    assert_eq!(steps(playback.field()), 0, "the first key starts a stroke, none has ended");
    // Step by step exactly as `argile save` plays to the end of the timeline.
    let end = scene.timeline.duration_s();
    while playback.time_s() < end {
        playback.step_towards(end);
        if steps(playback.field()) == states.len() {
            states.push(playback.field().clone());
        }
        assert!(steps(playback.field()) < states.len(), "one stroke ends per step at most");
    }
    let field = playback.field_mut();
    if field.in_stroke() {
        field.end_stroke();
        if steps(field) == states.len() {
            states.push(field.clone());
        }
    }
    states
}

fn argile(state: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_argile"));
    c.env("XDG_STATE_HOME", state).env("RUST_LOG", "warn,argile=debug");
    c
}

/// `argile save --autosave` of `scene`, killed after `kill_after` (if it runs that long).
/// Returns the highest stroke count it reported on disk before the kill, and whether it ran
/// to its end.
fn run_and_kill(scene: &Path, state: &Path, out: &Path, kill_after: Duration) -> (u64, bool) {
    let mut child = argile(state)
        .args(["save", "--autosave", "--sync-s", "0.05", "--checkpoint-s", "0.15", "--force"])
        .arg(scene)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    let start = Instant::now();
    let mut durable = 0;
    let mut finished = false;
    let mut lines = Vec::new();
    loop {
        while let Ok(line) = rx.try_recv() {
            if let Some(n) = line.split("strokes up to ").nth(1).and_then(|r| r.split(' ').next()) {
                durable = durable.max(n.parse::<u64>().unwrap());
            }
            lines.push(line);
        }
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "the session failed:\n{}", lines.join("\n"));
            finished = true;
            break;
        }
        if start.elapsed() >= kill_after {
            // Read what it reported before the kill: lines still in the pipe were written
            // before it.
            child.kill().unwrap();
            child.wait().unwrap();
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    reader.join().unwrap();
    for line in rx.try_iter() {
        if let Some(n) = line.split("strokes up to ").nth(1).and_then(|r| r.split(' ').next()) {
            durable = durable.max(n.parse::<u64>().unwrap());
        }
    }
    (durable, finished)
}

/// The recovered sculpt's path and stroke count, from `argile recover`'s sentence.
fn recover(state: &Path) -> Option<(PathBuf, usize)> {
    let out = argile(state).arg("recover").output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        !String::from_utf8_lossy(&out.stderr).contains("warning"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    if text.contains("No session is left to recover") {
        return None;
    }
    let stroke = text.split("(stroke ").nth(1)?.split(')').next()?.parse().ok()?;
    let path = text.split(") in ").nth(1)?.trim();
    Some((PathBuf::from(path), stroke))
}

/// A simple deterministic generator (xorshift), so each seed kills at the same point.
fn uniform(seed: u64) -> f64 {
    let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    for _ in 0..4 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
    }
    (x >> 11) as f64 / (1u64 << 53) as f64
}

#[test]
fn sigkill_at_random_points_recovers_exactly_a_completed_stroke() {
    let dir = std::env::temp_dir().join(format!("argile-crash-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = dir.join("strokes.toml");
    std::fs::write(&scene_path, scene_text()).unwrap();
    let scene = Scene::load(&scene_path).unwrap();
    let states = reference_states(&scene);
    assert_eq!(states.len(), STROKES + 1, "every stroke changes the clay");

    // A whole run: it closes its session, so nothing is left to recover.
    let state = dir.join("clean");
    let start = Instant::now();
    let (durable, finished) =
        run_and_kill(&scene_path, &state, &dir.join("clean.argile"), Duration::from_secs(60));
    let whole = start.elapsed();
    assert!(finished && durable >= 1, "the clean run reported strokes on disk");
    assert!(recover(&state).is_none(), "a session that closed is not recovered");
    assert!(load_sculpt(&dir.join("clean.argile")).unwrap().field.same_samples(&states[STROKES]));

    let mut recovered_strokes = Vec::new();
    for seed in 0..14 {
        let state = dir.join(format!("seed-{seed}"));
        let kill_after = whole.mul_f64(uniform(seed));
        let out = dir.join(format!("out-{seed}.argile"));
        let (durable, finished) = run_and_kill(&scene_path, &state, &out, kill_after);
        let recovered = recover(&state);
        eprintln!(
            "seed {seed}: killed after {kill_after:?} of {whole:?}, strokes up to {durable} on disk, recovered {:?}",
            recovered.as_ref().map(|r| r.1)
        );
        match recovered {
            None if durable > 0 => {
                // Killed after its clean close: the sculpt is saved, and the session closed.
                let saved = load_sculpt(&out)
                    .unwrap_or_else(|e| panic!("seed {seed}: nothing recovered, nothing saved: {e}"));
                assert!(saved.field.same_samples(&states[STROKES]), "seed {seed}");
            }
            None => assert!(!out.exists(), "seed {seed}: killed before any stroke was on disk"),
            Some((path, n)) => {
                assert!(!finished, "seed {seed}: a finished session is closed");
                assert!(
                    n >= durable as usize,
                    "seed {seed}: recovered stroke {n}, stroke {durable} was on disk"
                );
                assert!(n <= STROKES);
                let sculpt = load_sculpt(&path).unwrap();
                assert!(
                    sculpt.field.same_samples(&states[n]),
                    "seed {seed}: the recovered clay is not the clay after stroke {n}"
                );
                assert!(recover(&state).is_none(), "seed {seed}: a recovered session is removed");
                recovered_strokes.push(n);
            }
        }
    }
    recovered_strokes.sort_unstable();
    recovered_strokes.dedup();
    assert!(
        recovered_strokes.len() >= 4,
        "kills landed at several points of the session: strokes {recovered_strokes:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
