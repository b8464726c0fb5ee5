//! Crash recovery end to end: `argile save --autosave` sculpting a scripted session is killed
//! with SIGKILL at random points of its whole run (while it starts, before and during
//! checkpoints, during its final save); the next `argile recover` must give back exactly the
//! clay after some completed stroke (bit for bit), never a torn stroke, and never fewer strokes
//! than the session had reported on disk before it was killed. A kill during the final save
//! leaves no temporary file for long: the next save of the same file removes it.
//!
//! 100 kills by default (about half a minute); more with `ARGILE_CRASH_KILLS`:
//!
//! ```sh
//! ARGILE_CRASH_KILLS=1000 cargo test --release --test autosave_crash
//! ```

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use argile::app::{load_sculpt, Playback};
use argile::field::Field;
use argile::scene::Scene;

mod common;

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
    // The clay before any stroke is what the session's first snapshot holds: the scene's clay
    // as autosave starts on it, before the keys at time 0 begin their strokes.
    let mut initial = None;
    let mut playback = Playback::new_autosaved(scene, |field, _| {
        initial = Some(field.clone());
        None
    })
    .unwrap();
    let steps = |f: &Field| {
        let s = f.history_stats();
        s.undo_in_memory + s.undo_on_disk + s.dropped
    };
    let mut states = vec![initial.expect("autosave is started on the scene's clay")];
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
    c.env("XDG_STATE_HOME", state).env("RUST_LOG", "warn,argile=trace");
    c
}

/// When a watched run is killed (if it runs that long): a time after its start, or after it
/// says a stroke is in its journal. Kills timed from a stroke land among the strokes however
/// fast the machine plays them.
#[derive(Clone, Copy, Debug)]
enum Kill {
    After(Duration),
    Journaled(u64, Duration),
}

/// What `argile save --autosave` says as each stroke reaches the disk.
const ON_DISK: &str = "strokes up to ";

/// What `argile save --autosave` says (at the trace level) as it appends a stroke to its journal.
const JOURNALED: (&str, &str) = ("autosave: stroke ", " is in the journal");

/// The stroke count a line of `argile save --autosave` says is on disk, if it says so.
fn on_disk(line: &str) -> Option<u64> {
    line.split(ON_DISK).nth(1).and_then(|r| r.split(' ').next()).map(|n| n.parse().unwrap())
}

/// The stroke a line says was appended to the journal, if it says so.
fn journaled(line: &str) -> Option<u64> {
    let rest = line.split(JOURNALED.0).nth(1)?;
    rest.split_once(JOURNALED.1).map(|(n, _)| n.parse().unwrap())
}

/// What a watched run of `argile save --autosave` reported: the highest stroke count on disk
/// before the kill and whether it ran to its end.
struct Watched {
    durable: u64,
    finished: bool,
}

/// When to kill run `seed` of a session of `strokes` strokes whose clean run took `whole`:
/// one in four at a time spread over the whole run (its start and its final save included),
/// the others within half a millisecond of a stroke entering the journal, the strokes taken in
/// turn.
fn kill_time(seed: u64, whole: Duration, strokes: u64) -> Kill {
    match seed % 4 {
        0 => Kill::After(whole.mul_f64(1.05 * uniform(seed))),
        _ => Kill::Journaled(1 + seed % strokes, Duration::from_secs_f64(0.0005 * uniform(seed))),
    }
}

/// `argile save --autosave` of `scene`, killed as `kill` says.
fn run_and_kill(scene: &Path, state: &Path, out: &Path, kill: Kill) -> Watched {
    let child = argile(state)
        .args(["save", "--autosave", "--sync-s", "0.05", "--checkpoint-s", "0.15", "--force"])
        .arg(scene)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut durable = 0;
    let finished = watch_and_kill(child, kill, |line| durable = durable.max(on_disk(line).unwrap_or(0)));
    Watched { durable, finished }
}

/// Run `seed` of `argile save --autosave` of `scene`, killed as `kill` says (its sculpt file
/// `out` removed first), then recovered: what it reported and what `argile recover` found.
fn killed_run(
    scene: &Path,
    state: &Path,
    out: &Path,
    (seed, kill): (u64, Kill),
) -> (Watched, Option<(PathBuf, usize)>) {
    let _ = std::fs::remove_file(out);
    let watched = run_and_kill(scene, state, out, kill);
    let recovered = recover(state);
    eprintln!(
        "seed {seed}: killed {kill:?}, strokes up to {} on disk, recovered {:?}",
        watched.durable,
        recovered.as_ref().map(|r| r.1)
    );
    (watched, recovered)
}

/// Reads `child`'s standard error line by line into `seen` until it exits (it must succeed)
/// or `kill` says, when it is killed; then reads the lines still in the pipe, which were
/// written before the kill. Returns whether it ran to its end.
fn watch_and_kill(mut child: std::process::Child, kill: Kill, mut seen: impl FnMut(&str)) -> bool {
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    let (mut start, kill_after) = match kill {
        Kill::After(after) => (Some(Instant::now()), after),
        Kill::Journaled(_, after) => (None, after),
    };
    let mut lines = Vec::new();
    let killed = |child: &mut std::process::Child, start: Option<Instant>| {
        let due = start.is_some_and(|s| s.elapsed() >= kill_after);
        if due {
            child.kill().unwrap();
            child.wait().unwrap();
        }
        due
    };
    let finished = 'watch: loop {
        // Each line as it comes, so that a kill due at a line lands while the run is there.
        while let Ok(line) = rx.recv_timeout(Duration::from_micros(200)) {
            if let Kill::Journaled(stroke, _) = kill {
                if start.is_none() && journaled(&line).is_some_and(|n| n >= stroke) {
                    start = Some(Instant::now());
                }
            }
            seen(&line);
            lines.push(line);
            if killed(&mut child, start) {
                break 'watch false;
            }
        }
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "the run failed:\n{}", lines.join("\n"));
            break true;
        }
        if killed(&mut child, start) {
            break false;
        }
    };
    reader.join().unwrap();
    rx.try_iter().for_each(|line| seen(&line));
    finished
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
    let path = text.split(") in ").nth(1)?.lines().next()?.trim();
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
    let clean =
        run_and_kill(&scene_path, &state, &dir.join("clean.argile"), Kill::After(Duration::from_secs(60)));
    let whole = start.elapsed();
    assert!(clean.finished && clean.durable >= 1, "the clean run reported strokes on disk");
    assert!(recover(&state).is_none(), "a session that closed is not recovered");
    assert!(load_sculpt(&dir.join("clean.argile")).unwrap().field.same_samples(&states[STROKES]));

    let kills: u64 = std::env::var("ARGILE_CRASH_KILLS").ok().and_then(|k| k.parse().ok()).unwrap_or(100);
    let mut recovered_strokes = Vec::new();
    // Every run writes the same file, as a user saving again would.
    let out = dir.join("out.argile");
    for seed in 0..kills {
        let state = dir.join(format!("seed-{seed}"));
        let kill = kill_time(seed, whole, STROKES as u64);
        let (Watched { durable, finished }, recovered) = killed_run(&scene_path, &state, &out, (seed, kill));
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
        let _ = std::fs::remove_dir_all(&state);
    }
    // A last, whole run of the same file leaves no temporary file of the killed ones.
    let last = run_and_kill(&scene_path, &dir.join("last"), &out, Kill::After(Duration::from_secs(60)));
    assert!(last.finished);
    let temporaries: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(temporaries.is_empty(), "temporary files left beside the sculpt: {temporaries:?}");
    recovered_strokes.sort_unstable();
    recovered_strokes.dedup();
    assert!(
        recovered_strokes.len() >= 4.min(kills as usize / 4),
        "kills landed at several points of the session: strokes {recovered_strokes:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Starts `argile save --autosave` of `scene` and waits until it reports a stroke on disk;
/// returns the running child and a thread reading the rest of what it says on standard error
/// (a closed pipe would fail its writes), which gives every line.
fn started_with_a_stroke_on_disk(
    scene: &Path,
    state: &Path,
    out: &Path,
) -> (std::process::Child, std::thread::JoinHandle<Vec<String>>) {
    let mut child = argile(state)
        .args(["save", "--autosave", "--sync-s", "0.02", "--checkpoint-s", "0.15", "--force"])
        .arg(scene)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let stderr = BufReader::new(child.stderr.take().unwrap());
    let reader = std::thread::spawn(move || {
        let mut lines = Vec::new();
        for line in stderr.lines().map_while(Result::ok) {
            if line.contains("strokes up to ") && !line.contains("strokes up to 0 ") {
                let _ = tx.send(());
            }
            lines.push(line);
        }
        lines
    });
    rx.recv_timeout(Duration::from_secs(60)).expect("a stroke reported on disk");
    (child, reader)
}

#[test]
fn a_stopping_signal_during_save_autosave_saves_what_was_done_closes_and_exits_143() {
    let dir = std::env::temp_dir().join(format!("argile-sigterm-save-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = dir.join("strokes.toml");
    std::fs::write(&scene_path, scene_text()).unwrap();
    let (state, out) = (dir.join("state"), dir.join("stopped.argile"));
    let (child, reader) = started_with_a_stroke_on_disk(&scene_path, &state, &out);
    assert!(Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap().success());
    let output = child.wait_with_output().unwrap();
    let said = format!("{}\n{}", reader.join().unwrap().join("\n"), String::from_utf8_lossy(&output.stdout));
    assert_eq!(output.status.code(), Some(143), "{said}");
    assert!(said.contains("SIGTERM received at") && said.contains("stopped by SIGTERM"), "{said}");
    let saved =
        load_sculpt(&out).unwrap_or_else(|e| panic!("the sculpt as far as it got is saved: {e}\n{said}"));
    let whole = reference_states(&Scene::load(&scene_path).unwrap());
    assert!(!saved.field.same_samples(&whole[0]), "strokes were saved");
    assert!(recover(&state).is_none(), "the session was closed");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_recovery_that_cannot_save_says_so_fails_and_keeps_the_session() {
    let dir = std::env::temp_dir().join(format!("argile-recover-fails-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = dir.join("strokes.toml");
    std::fs::write(&scene_path, scene_text()).unwrap();
    let state = dir.join("state");
    let (mut child, reader) = started_with_a_stroke_on_disk(&scene_path, &state, &dir.join("killed.argile"));
    child.kill().unwrap();
    child.wait().unwrap();
    reader.join().unwrap();
    // A file where the recovered folder should be.
    std::fs::write(state.join("argile/recovered"), "in the way").unwrap();
    let out = argile(&state).arg("recover").output().unwrap();
    let said = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(!out.status.success(), "{said}");
    assert!(
        said.contains("cannot recover an unclosed session") && said.contains("could not be recovered"),
        "{said}"
    );
    assert!(!said.contains("No session is left to recover"), "{said}");
    // Out of the way, the session is still there to recover.
    std::fs::remove_file(state.join("argile/recovered")).unwrap();
    let (path, strokes) = recover(&state).expect("the session was kept");
    assert!(strokes >= 1 && load_sculpt(&path).is_ok());
    std::fs::remove_dir_all(&dir).unwrap();
}

const PART_STROKES: usize = 16;

/// A sculpt of two parts — a slab at rest at 1 mm, a ball at 2 mm placed turned and scaled —
/// with strokes alternately on each.
fn parts_scene_text() -> String {
    let mut text = String::from(
        "[field]\nvoxel_size_m = 0.001\n[timeline]\nstep_s = 0.01\n\
         [[part]]\nname = \"slab\"\n\
         [[part]]\nname = \"ball\"\nvoxel_size_m = 0.002\nposition_m = [0.0, 0.03, 0.0]\nrotation_deg = [0.0, 30.0, 0.0]\nscale = 1.5\n\
         [[clay]]\npart = \"slab\"\nshape = \"box\"\nposition_m = [0.0, -0.01, 0.0]\nsize_m = [0.12, 0.02, 0.12]\n\
         [[clay]]\npart = \"ball\"\nshape = \"sphere\"\nradius_m = 0.015\n\
         [[tool]]\nname = \"add\"\nradius_m = 0.008\naction = \"add\"\ncolour = \"#c04020\"\n\
         [[tool]]\nname = \"carve\"\nradius_m = 0.006\naction = \"remove\"\n",
    );
    for i in 0..PART_STROKES {
        let t0 = i as f32 * 0.1;
        let (part, y) = if i % 2 == 0 { ("slab", 0.0) } else { ("ball", 0.03) };
        let tool = ["add", "add", "carve", "carve"][i % 4];
        let a = i as f32 * 0.7;
        let (x, z) = (0.02 * a.cos(), 0.02 * a.sin());
        text += &format!(
            "[[key]]\ntime_s = {t0:.2}\npart = \"{part}\"\ntool = \"{tool}\"\nposition_m = [{x:.4}, {y}, {z:.4}]\nactive = true\n\
             [[key]]\ntime_s = {:.2}\npart = \"{part}\"\ntool = \"{tool}\"\nposition_m = [{:.4}, {y}, {:.4}]\n",
            t0 + 0.06,
            x + 0.005,
            z + 0.005
        );
    }
    text
}

/// The parts' clay (the first, then the others) after 0, 1, 2, … completed strokes.
fn parts_reference_states(scene: &Scene) -> Vec<(Field, Vec<Field>)> {
    // Before any stroke: the first part as autosave starts on it, the others as the scene
    // makes them.
    let mut first = None;
    let mut playback = Playback::new_autosaved(scene, |field, _| {
        first = Some(field.clone());
        None
    })
    .unwrap();
    let mut bare = scene.clone();
    bare.timeline = argile::scene::Timeline::new(Vec::new(), scene.timeline.step_s()).unwrap();
    let others = Playback::new(&bare).assembly().others().to_vec();
    let steps = |p: &Playback<'_>| {
        let count = |f: &Field| {
            let s = f.history_stats();
            s.undo_in_memory + s.undo_on_disk + s.dropped
        };
        count(p.field()) + p.assembly().others().iter().map(count).sum::<usize>()
    };
    let state = |p: &Playback<'_>| (p.field().clone(), p.assembly().others().to_vec());
    let mut states = vec![(first.expect("autosave is started on the first part"), others)];
    let end = scene.timeline.duration_s();
    while playback.time_s() < end {
        playback.step_towards(end);
        if steps(&playback) == states.len() {
            states.push(state(&playback));
        }
        assert!(steps(&playback) < states.len(), "one stroke ends per step at most");
    }
    // The last stroke closes as the save ends it.
    playback.close_steps();
    if steps(&playback) == states.len() {
        states.push(state(&playback));
    }
    states
}

fn same_parts(a: &argile::io::Sculpt, (field, others): &(Field, Vec<Field>)) -> bool {
    a.field.same_samples(field)
        && a.others.len() == others.len()
        && a.others.iter().zip(others).all(|(x, y)| x.same_samples(y))
}

/// The same as `sigkill_at_random_points_recovers_exactly_a_completed_stroke`, for a sculpt of
/// parts whose strokes change one part or the other: the recovered sculpt holds every part as
/// it was after some completed stroke, never fewer than were on disk.
#[test]
fn sigkill_of_a_sculpt_of_parts_recovers_every_part_after_a_completed_stroke() {
    let dir = std::env::temp_dir().join(format!("argile-crash-parts-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = dir.join("parts.toml");
    std::fs::write(&scene_path, parts_scene_text()).unwrap();
    let scene = Scene::load(&scene_path).unwrap();
    let states = parts_reference_states(&scene);
    assert_eq!(states.len(), PART_STROKES + 1, "every stroke changes its part");

    let start = Instant::now();
    let clean = run_and_kill(
        &scene_path,
        &dir.join("clean"),
        &dir.join("clean.argile"),
        Kill::After(Duration::from_secs(60)),
    );
    let whole = start.elapsed();
    assert!(clean.finished && clean.durable >= 1, "the clean run reported strokes on disk");
    let saved = load_sculpt(&dir.join("clean.argile")).unwrap();
    assert_eq!(saved.parts.len(), 2, "the sculpt file keeps both parts");
    assert!(same_parts(&saved, &states[PART_STROKES]), "the saved parts are the played ones");

    let kills: u64 = std::env::var("ARGILE_CRASH_KILLS").ok().and_then(|k| k.parse().ok()).unwrap_or(40);
    let mut recovered_strokes = Vec::new();
    let out = dir.join("out.argile");
    for seed in 0..kills {
        let state = dir.join(format!("seed-{seed}"));
        let kill = kill_time(seed + 1000, whole, PART_STROKES as u64);
        let (Watched { durable, finished }, recovered) = killed_run(&scene_path, &state, &out, (seed, kill));
        match recovered {
            None if durable > 0 => {
                let saved = load_sculpt(&out)
                    .unwrap_or_else(|e| panic!("seed {seed}: nothing recovered, nothing saved: {e}"));
                assert!(same_parts(&saved, &states[PART_STROKES]), "seed {seed}");
            }
            None => assert!(!out.exists(), "seed {seed}: killed before any stroke was on disk"),
            Some((path, n)) => {
                assert!(!finished, "seed {seed}: a finished session is closed");
                assert!(
                    n >= durable as usize && n <= PART_STROKES,
                    "seed {seed}: recovered stroke {n}, {durable} on disk"
                );
                let sculpt = load_sculpt(&path).unwrap();
                assert!(
                    same_parts(&sculpt, &states[n]),
                    "seed {seed}: the recovered parts are not those after stroke {n}"
                );
                recovered_strokes.push(n);
            }
        }
        let _ = std::fs::remove_dir_all(&state);
    }
    recovered_strokes.sort_unstable();
    recovered_strokes.dedup();
    assert!(
        recovered_strokes.len() >= 3.min(kills as usize / 4),
        "kills landed at several points of the session: strokes {recovered_strokes:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The raises of the desk lattice's value the station script presses (`R`), one every
/// `RAISE_EVERY` frames after the lattice opens.
const RAISES: u64 = 8;
const RAISE_EVERY: u64 = 6;

/// The desk session killed: Shift+F opens a lattice over the slab, R raises the picked
/// control's value `RAISES` times, then the station idles until its last frame.
fn lattice_script() -> String {
    let mut text = String::from("[[event]]\nframe = 2\npress = \"Shift+KeyF\"\n");
    for i in 1..=RAISES {
        text += &format!("[[event]]\nframe = {}\npress = \"KeyR\"\n", 2 + i * RAISE_EVERY);
    }
    text
}

/// `argile run` of the station scene in `x`'s window playing `script` for `frames` frames,
/// saving to `out`, killed after `kill_after` (if it runs that long). Returns how many states
/// of the open lattice it reported on disk before the kill, and whether it ran to its end.
fn run_station_and_kill(
    x: &common::Xvfb,
    (script, frames): (&Path, u64),
    state: &Path,
    out: &Path,
    kill_after: Duration,
) -> (usize, bool) {
    let scene = common::root().join("scenes/tests/station.toml");
    let child = argile(state)
        .arg("run")
        .arg(&scene)
        .args(["--frames", &frames.to_string(), "--size", "160x120", "--input-script"])
        .arg(script)
        .arg("--save-to")
        .arg(out)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stored = 0;
    let finished = watch_and_kill(child, Kill::After(kill_after), |line| {
        stored += usize::from(line.contains("the open lattice is on disk"));
    });
    (stored, finished)
}

/// How many raises `lattice` holds over `last` (the lattice after all `RAISES`): every control
/// as in `last` but one, whose value is `RAISES − k` steps below it.
fn raises_in(lattice: &argile::io::StoredLattice, last: &argile::io::StoredLattice) -> u64 {
    assert_eq!((lattice.counts, lattice.min_m, lattice.max_m), (last.counts, last.min_m, last.max_m));
    let mut raises = RAISES;
    for (c, l) in lattice.controls.iter().zip(&last.controls) {
        assert_eq!((c.position_m, c.weight), (l.position_m, l.weight), "only values are raised");
        if c.value != l.value {
            let below = (l.value - c.value) / 0.1;
            assert!((below - below.round()).abs() < 1e-6 && below > 0.5, "{} against {}", c.value, l.value);
            assert_eq!(raises, RAISES, "one control is raised");
            raises = RAISES - below.round() as u64;
        }
    }
    raises
}

#[test]
fn sigkill_of_the_desk_with_a_lattice_open_recovers_the_lattice_as_it_last_stood() {
    let dir = std::env::temp_dir().join(format!("argile-crash-lattice-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("lattice-input.toml");
    std::fs::write(&script, lattice_script()).unwrap();
    let frames = 2 + (RAISES + 4) * RAISE_EVERY;
    let x = common::Xvfb::start();

    // A whole run saves the sculpt with its lattice open (the clay as it was when the lattice
    // opened, the lattice raised `RAISES` times) and closes its session.
    let clean = dir.join("clean.argile");
    let start = Instant::now();
    let (stored, finished) =
        run_station_and_kill(&x, (&script, frames), &dir.join("clean"), &clean, Duration::from_secs(120));
    let whole = start.elapsed();
    assert!(finished && stored >= 2, "the lattice was stored as it opened and as it was raised ({stored})");
    assert!(recover(&dir.join("clean")).is_none(), "a session that closed is not recovered");
    let saved = load_sculpt(&clean).unwrap();
    let last = saved.lattice.clone().expect("quitting with a lattice open saves it open");
    let at_rest = saved.field;

    let kills: u64 =
        std::env::var("ARGILE_CRASH_KILLS").ok().and_then(|k| k.parse::<u64>().ok()).map_or(12, |k| k / 8);
    let mut seen = Vec::new();
    for seed in 0..kills.max(1) {
        let state = dir.join(format!("seed-{seed}"));
        let out = dir.join(format!("seed-{seed}.argile"));
        let kill_after = whole.mul_f64(0.2 + 0.85 * uniform(seed + 1000));
        let (stored, finished) = run_station_and_kill(&x, (&script, frames), &state, &out, kill_after);
        let recovered = recover(&state);
        eprintln!(
            "seed {seed}: killed after {kill_after:?} of {whole:?}, {stored} lattice state(s) on disk, recovered {:?}",
            recovered.as_ref().map(|r| &r.0)
        );
        let Some((path, _)) = recovered else {
            assert!(finished || stored == 0, "seed {seed}: a lattice on disk is recovered");
            continue;
        };
        assert!(!finished, "seed {seed}: a finished session is closed");
        let sculpt = load_sculpt(&path).unwrap();
        assert!(
            sculpt.field.same_samples(&at_rest),
            "seed {seed}: the clay as it was when the lattice opened"
        );
        match &sculpt.lattice {
            None => assert_eq!(stored, 0, "seed {seed}: a lattice was on disk and is not recovered"),
            Some(lattice) => {
                let raises = raises_in(lattice, &last);
                assert!(
                    raises as usize + 1 >= stored,
                    "seed {seed}: {raises} raise(s) recovered, {stored} lattice state(s) were on disk"
                );
                seen.push(raises);
            }
        }
        let _ = std::fs::remove_dir_all(&state);
    }
    seen.sort_unstable();
    seen.dedup();
    assert!(
        seen.len() >= 2.min(kills as usize / 4),
        "kills landed at several of the lattice's states: {seen:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
