//! Autosave in process: checkpoints fold the journal and recovery still gives the last stroke;
//! a clean close leaves nothing; a full disk or a read-only folder is reported by path, the
//! sculpt stays in memory, nothing on disk is damaged, and autosave resumes when it can.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use argile::field::Field;
use argile::io::autosave::{
    recover, unclosed_sessions, AppendFile, Autosave, AutosaveConfig, Disk, LocalDisk, SessionInfo,
};
use argile::io::decode;
use argile::math::Vec3;
use argile::tool::{stamp_sphere, Action};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("argile-autosave-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn fast() -> AutosaveConfig {
    AutosaveConfig {
        sync_interval: Duration::from_millis(10),
        checkpoint_interval: Duration::from_millis(30),
        retry_interval: Duration::from_millis(20),
        ..AutosaveConfig::default()
    }
}

/// Stroke `i`: a few stamps, adding or carving, somewhere on a ring.
fn stroke(field: &mut Field, i: usize) {
    field.begin_stroke();
    let a = i as f32 * 0.7;
    for s in 0..4 {
        let p = Vec3::new(a.cos() * 0.02 + s as f32 * 0.002, 0.0, a.sin() * 0.02);
        let action = if i % 3 == 2 { Action::Remove } else { Action::Add };
        stamp_sphere(field, p, 0.006, action, [0.2 * (i % 5) as f32, 0.5, 0.7, 1.0]);
    }
    field.end_stroke();
}

fn wait_for(what: &str, mut ok: impl FnMut() -> bool) {
    let start = Instant::now();
    while !ok() {
        assert!(start.elapsed() < Duration::from_secs(20), "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn files(dir: &Path, prefix: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter_map(|e| e.file_name().into_string().ok())
        .filter(|n| n.starts_with(prefix))
        .collect();
    names.sort();
    names
}

#[test]
fn recovery_gives_the_last_stroke_across_checkpoints_and_undo() {
    let root = temp_dir("checkpoints");
    let mut field = Field::new(0.001, 0.5);
    stamp_sphere(&mut field, Vec3::ZERO, 0.01, Action::Add, [0.6, 0.6, 0.6, 1.0]);
    let mut autosave =
        Autosave::start(&root, &mut field, Some("[field]\n"), "test", fast(), Arc::new(LocalDisk)).unwrap();
    let dir = autosave.dir().to_path_buf();
    for i in 0..12 {
        stroke(&mut field, i);
        autosave.record(&mut field);
        if i % 4 == 3 {
            // Time for a checkpoint to fold what came before.
            std::thread::sleep(Duration::from_millis(40));
        }
    }
    assert!(field.undo().unwrap());
    autosave.record(&mut field);
    assert_eq!(autosave.strokes(), 13, "the undo is journaled as a step of its own");
    wait_for("every stroke on disk", || autosave.durable_strokes() == 13);
    wait_for("a checkpoint past the first strokes", || {
        files(&dir, "snapshot-").iter().any(|n| n != "snapshot-0.argile")
    });
    // The checkpoint after the last stroke folds every journal but the one it starts.
    wait_for("folded journals to be removed", || files(&dir, "journal-").len() == 1);
    // Dropped without closing, as a crash would leave it.
    drop(autosave);
    let recovered = recover(&dir).unwrap();
    assert_eq!(recovered.strokes, 13);
    assert!(recovered.snapshot_strokes > 0);
    assert!(recovered.sculpt.field.same_samples(&field), "bit for bit the clay after the undo");
    assert_eq!(recovered.sculpt.scene_toml.as_deref(), Some("[field]\n"));
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn recovery_gives_back_every_resolution_level() {
    use argile::math::Pose;
    use argile::tool::{apply_tool, Tool, ToolShape, MAX_SIZE_SAMPLES};
    let root = temp_dir("levels");
    let mut field = Field::new(0.001, 0.5);
    stamp_sphere(&mut field, Vec3::ZERO, 0.01, Action::Add, [0.6, 0.6, 0.6, 1.0]);
    let mut autosave = Autosave::start(&root, &mut field, None, "test", fast(), Arc::new(LocalDisk)).unwrap();
    let dir = autosave.dir().to_path_buf();
    for i in 0..6 {
        // Tools of 6 to 36 mm editing by their size: levels 0 to 3, over and beside the clay.
        let radius_m = 0.006 * (i + 1) as f32;
        let action = if i % 2 == 1 { Action::Remove } else { Action::Add };
        let tool = Tool {
            level_samples: Some(MAX_SIZE_SAMPLES),
            ..Tool::new(ToolShape::sphere(radius_m), action, [0.1 * i as f32, 0.5, 0.3, 1.0])
        };
        field.begin_stroke();
        let at = Vec3::new(0.01 * i as f32, 0.0, -0.01);
        apply_tool(&mut field, &tool, Pose { position_m: at, ..Default::default() }, 0.0);
        field.end_stroke();
        autosave.record(&mut field);
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(field.level_brick_count(3) > 0, "the largest tool wrote level 3");
    wait_for("every stroke on disk", || autosave.durable_strokes() == 6);
    drop(autosave);
    let recovered = recover(&dir).unwrap();
    assert_eq!(recovered.strokes, 6);
    assert!(recovered.sculpt.field.same_samples(&field), "bit for bit, every level");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_torn_journal_tail_is_discarded() {
    let root = temp_dir("torn");
    let mut field = Field::new(0.001, 0.5);
    let config = AutosaveConfig { checkpoint_interval: Duration::from_secs(3600), ..fast() };
    let mut autosave = Autosave::start(&root, &mut field, None, "test", config, Arc::new(LocalDisk)).unwrap();
    let dir = autosave.dir().to_path_buf();
    let mut states = vec![field.clone()];
    for i in 0..5 {
        stroke(&mut field, i);
        autosave.record(&mut field);
        states.push(field.clone());
    }
    wait_for("every stroke on disk", || autosave.durable_strokes() == 5);
    drop(autosave);
    let journal = dir.join(&files(&dir, "journal-")[0]);
    let bytes = std::fs::read(&journal).unwrap();
    for cut in [bytes.len() - 1, bytes.len() - 3000, bytes.len() / 2, 21] {
        std::fs::write(&journal, &bytes[..cut]).unwrap();
        let r = recover(&dir).unwrap();
        assert!(r.strokes < 5, "cut at {cut}");
        assert!(
            r.sculpt.field.same_samples(&states[r.strokes as usize]),
            "cut at {cut}: clay after stroke {}",
            r.strokes
        );
        assert!(r.discarded.unwrap().contains("discarded"), "cut at {cut}");
    }
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_clean_close_leaves_nothing_and_only_orphaned_sessions_are_found() {
    let root = temp_dir("close");
    let mut field = Field::new(0.001, 0.5);
    let mut autosave = Autosave::start(&root, &mut field, None, "test", fast(), Arc::new(LocalDisk)).unwrap();
    stroke(&mut field, 0);
    autosave.record(&mut field);
    let dir = autosave.dir().to_path_buf();
    // This process owns it: it is not an orphan.
    assert!(unclosed_sessions(&root).is_empty());
    autosave.close().unwrap();
    assert!(!dir.exists(), "a closed session removes its files");

    // A session whose process is gone (an id above any the system hands out).
    let orphan = root.join("1-4999999-000000000");
    std::fs::create_dir_all(&orphan).unwrap();
    let info =
        SessionInfo { pid: 4_999_999, start_token: Some("1".into()), started_unix_s: 1, source: "s".into() };
    std::fs::write(orphan.join("session.json"), serde_json::to_vec(&info).unwrap()).unwrap();
    let found = unclosed_sessions(&root);
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].dir, orphan);
    assert_eq!(found[0].info, info);
    let e = recover(&orphan).unwrap_err();
    assert!(e.empty && e.to_string().contains(&orphan.display().to_string()), "{e}");
    // A folder left without a session file by a process gone while starting is removed.
    let stillborn = root.join("1-4999998-000000000");
    std::fs::create_dir_all(&stillborn).unwrap();
    unclosed_sessions(&root);
    assert!(!stillborn.exists());
    std::fs::remove_dir_all(&root).unwrap();
}

/// The local disk, made to fail on demand: 0 works, 1 is full (ENOSPC; an append writes
/// half its bytes first, as a real full disk can), 2 is read-only (EROFS).
#[derive(Debug, Default)]
struct FlakyDisk {
    mode: Arc<AtomicU8>,
}

fn injected(mode: u8, path: &Path, what: &str) -> Result<()> {
    let code = match mode {
        0 => return Ok(()),
        1 => 28,
        _ => 30,
    };
    Err(std::io::Error::from_raw_os_error(code)).with_context(|| format!("cannot {what} {}", path.display()))
}

struct FlakyFile {
    inner: Box<dyn AppendFile>,
    mode: Arc<AtomicU8>,
    path: PathBuf,
}

impl AppendFile for FlakyFile {
    fn append(&mut self, bytes: &[u8]) -> Result<()> {
        let mode = self.mode.load(Ordering::SeqCst);
        if mode == 1 {
            self.inner.append(&bytes[..bytes.len() / 2])?;
        }
        injected(mode, &self.path, "write")?;
        self.inner.append(bytes)
    }

    fn sync(&mut self) -> Result<()> {
        injected(self.mode.load(Ordering::SeqCst), &self.path, "flush")?;
        self.inner.sync()
    }
}

impl Disk for FlakyDisk {
    fn create_dir(&self, path: &Path) -> Result<()> {
        injected(self.mode.load(Ordering::SeqCst), path, "create the folder")?;
        LocalDisk.create_dir(path)
    }

    fn write_whole(&self, path: &Path, bytes: &[u8]) -> Result<()> {
        injected(self.mode.load(Ordering::SeqCst), path, "write")?;
        LocalDisk.write_whole(path, bytes)
    }

    fn create_append(&self, path: &Path) -> Result<Box<dyn AppendFile>> {
        injected(self.mode.load(Ordering::SeqCst), path, "create")?;
        let inner = LocalDisk.create_append(path)?;
        Ok(Box::new(FlakyFile { inner, mode: Arc::clone(&self.mode), path: path.to_path_buf() }))
    }

    fn remove(&self, path: &Path) -> Result<()> {
        injected(self.mode.load(Ordering::SeqCst), path, "remove")?;
        LocalDisk.remove(path)
    }
}

/// Every file in `dir` and its bytes.
fn contents(dir: &Path) -> Vec<(String, Vec<u8>)> {
    files(dir, "").into_iter().map(|n| (n.clone(), std::fs::read(dir.join(&n)).unwrap())).collect()
}

fn failing_disk_mid_session(mode: u8, message: &str) {
    let root = temp_dir(&format!("failing-{mode}"));
    let disk = FlakyDisk::default();
    let switch = Arc::clone(&disk.mode);
    let mut field = Field::new(0.001, 0.5);
    let mut autosave = Autosave::start(&root, &mut field, None, "test", fast(), Arc::new(disk)).unwrap();
    let dir = autosave.dir().to_path_buf();
    let mut states = vec![field.clone()];
    for i in 0..4 {
        stroke(&mut field, i);
        autosave.record(&mut field);
        states.push(field.clone());
    }
    wait_for("the first strokes on disk", || autosave.durable_strokes() == 4);
    // Let checkpoints settle, then freeze the folder's content as it is.
    std::thread::sleep(Duration::from_millis(60));
    switch.store(mode, Ordering::SeqCst);
    let durable = autosave.durable_strokes();
    let before = contents(&dir);
    for i in 4..8 {
        stroke(&mut field, i);
        autosave.record(&mut field);
        states.push(field.clone());
    }
    wait_for("the failure to be reported", || autosave.problem().is_some());
    let problem = autosave.problem().unwrap();
    assert!(problem.contains(&dir.display().to_string()) && problem.contains(message), "{problem}");
    // Retries fail too; what was on disk reads as before.
    std::thread::sleep(Duration::from_millis(80));
    let r = recover(&dir).unwrap();
    assert!(r.strokes >= durable && r.strokes < 8, "recovered {} strokes", r.strokes);
    assert!(r.sculpt.field.same_samples(&states[r.strokes as usize]));
    for (name, bytes) in &before {
        if name.starts_with("snapshot-") || name == "session.json" {
            let now = std::fs::read(dir.join(name)).unwrap();
            assert_eq!(&now, bytes, "{name} is untouched while the disk fails");
            if name.starts_with("snapshot-") {
                decode(&now, name, &mut |_| {}).unwrap();
            }
        }
    }
    // The disk works again: the next retry folds everything, the warning clears.
    switch.store(0, Ordering::SeqCst);
    wait_for("autosave to resume", || autosave.problem().is_none() && autosave.durable_strokes() == 8);
    stroke(&mut field, 8);
    autosave.record(&mut field);
    wait_for("the new stroke on disk", || autosave.durable_strokes() == 9);
    drop(autosave);
    let r = recover(&dir).unwrap();
    assert_eq!(r.strokes, 9);
    assert!(r.sculpt.field.same_samples(&field), "the sculpt in memory was never lost");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_full_disk_is_reported_by_path_and_autosave_resumes_when_space_returns() {
    failing_disk_mid_session(1, "No space left on device");
}

#[test]
fn a_folder_turned_read_only_is_reported_by_path_and_autosave_resumes() {
    failing_disk_mid_session(2, "Read-only file system");
}

#[test]
fn autosave_that_cannot_start_says_which_folder() {
    let root = temp_dir("cannot-start");
    let mut field = Field::new(0.001, 0.5);
    let disk = FlakyDisk::default();
    disk.mode.store(2, Ordering::SeqCst);
    let e = Autosave::start(&root, &mut field, None, "test", fast(), Arc::new(disk)).unwrap_err().to_string();
    assert!(e.contains("cannot create the folder") && e.contains(&root.display().to_string()), "{e}");
    assert!(e.contains("Read-only file system"), "{e}");
    // A real failure, whatever the user's rights (root included): the state folder's place is
    // taken by a file.
    let blocked = root.join("blocked");
    std::fs::write(&blocked, "a file, not a folder").unwrap();
    let e = Autosave::start(&blocked, &mut field, None, "test", fast(), Arc::new(LocalDisk))
        .unwrap_err()
        .to_string();
    assert!(e.contains(&blocked.display().to_string()), "{e}");
    assert_eq!(std::fs::read_to_string(&blocked).unwrap(), "a file, not a folder", "nothing is damaged");
    std::fs::remove_dir_all(&root).unwrap();
}

/// The local disk with switches: snapshots held back until released, journal files failing
/// to be created or appended to (ENOSPC).
#[derive(Debug, Default)]
struct SwitchedDisk {
    hold_snapshots: Arc<std::sync::atomic::AtomicBool>,
    full: Arc<std::sync::atomic::AtomicBool>,
}

struct SwitchedFile {
    inner: Box<dyn AppendFile>,
    full: Arc<std::sync::atomic::AtomicBool>,
    path: PathBuf,
}

impl AppendFile for SwitchedFile {
    fn append(&mut self, bytes: &[u8]) -> Result<()> {
        injected(if self.full.load(Ordering::SeqCst) { 1 } else { 0 }, &self.path, "write")?;
        self.inner.append(bytes)
    }

    fn sync(&mut self) -> Result<()> {
        self.inner.sync()
    }
}

impl Disk for SwitchedDisk {
    fn create_dir(&self, path: &Path) -> Result<()> {
        LocalDisk.create_dir(path)
    }

    fn write_whole(&self, path: &Path, bytes: &[u8]) -> Result<()> {
        while self.hold_snapshots.load(Ordering::SeqCst) && path.to_string_lossy().contains("snapshot-") {
            std::thread::sleep(Duration::from_millis(1));
        }
        LocalDisk.write_whole(path, bytes)
    }

    fn create_append(&self, path: &Path) -> Result<Box<dyn AppendFile>> {
        injected(if self.full.load(Ordering::SeqCst) { 1 } else { 0 }, path, "create")?;
        let inner = LocalDisk.create_append(path)?;
        Ok(Box::new(SwitchedFile { inner, full: Arc::clone(&self.full), path: path.to_path_buf() }))
    }

    fn remove(&self, path: &Path) -> Result<()> {
        LocalDisk.remove(path)
    }
}

#[test]
fn strokes_lost_with_a_failed_journal_are_folded_before_the_journal_counts_again() {
    let root = temp_dir("gap");
    let disk = SwitchedDisk::default();
    let (hold, full) = (Arc::clone(&disk.hold_snapshots), Arc::clone(&disk.full));
    let mut field = Field::new(0.001, 0.5);
    // Every journal is large enough to fold: each stroke starts a checkpoint.
    let config = AutosaveConfig {
        checkpoint_interval: Duration::from_secs(3600),
        checkpoint_journal_bytes: 1,
        ..fast()
    };
    // The first snapshot is written by the start itself; the next ones are held.
    let mut autosave = Autosave::start(&root, &mut field, None, "test", config, Arc::new(disk)).unwrap();
    assert_eq!(files(autosave.dir(), "snapshot-"), ["snapshot-0.argile"], "the first snapshot is on disk");
    hold.store(true, Ordering::SeqCst);
    let dir = autosave.dir().to_path_buf();
    for i in 0..2 {
        stroke(&mut field, i);
        autosave.record(&mut field);
    }
    // The journal fails while a checkpoint is still being written: stroke 3 is in no
    // journal, and the next journal cannot even be created at first.
    full.store(true, Ordering::SeqCst);
    stroke(&mut field, 2);
    autosave.record(&mut field);
    wait_for("the failure to be reported", || autosave.problem().is_some());
    hold.store(false, Ordering::SeqCst);
    std::thread::sleep(Duration::from_millis(80));
    assert!(autosave.problem().is_some());
    full.store(false, Ordering::SeqCst);
    wait_for("autosave to resume", || autosave.problem().is_none() && autosave.durable_strokes() >= 3);
    stroke(&mut field, 3);
    autosave.record(&mut field);
    wait_for("stroke 4 on disk", || autosave.durable_strokes() == 4);
    drop(autosave);
    let listing = files(&dir, "");
    let r = recover(&dir).unwrap();
    assert_eq!(r.strokes, 4, "{:?} {listing:?}", r.discarded);
    assert!(r.sculpt.field.same_samples(&field));
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_session_whose_state_folder_cannot_be_written_warns_by_path_and_still_saves() {
    let root = temp_dir("cli-blocked");
    let state = root.join("state");
    std::fs::write(&state, "a file where the state folder should be").unwrap();
    let out = root.join("paste.argile");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tests/toothpaste.toml");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_argile"))
        .env("XDG_STATE_HOME", &state)
        .args(["save", scene, "--autosave", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("autosave cannot start") && stderr.contains(&state.display().to_string()),
        "{stderr}"
    );
    assert!(stderr.contains("the sculpt stays in memory"), "{stderr}");
    assert!(argile::app::load_sculpt(&out).is_ok(), "the sculpt is saved where asked");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_recovered_sculpt_keeps_the_scenes_freeform_tools() {
    let root = temp_dir("tools");
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tests/tool-freeform.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let scene = argile::scene::Scene::parse(&text, path, None).unwrap();
    let mut playback = argile::app::Playback::new_autosaved(&scene, |field, tools| {
        let disk = Arc::new(LocalDisk);
        Some(Autosave::start_with_tools(&root, field, (Some(&text), tools), "test", fast(), disk).unwrap())
    })
    .unwrap();
    let dir = playback.autosave().unwrap().dir().to_path_buf();
    playback.advance_to(10.0, |_| {});
    let strokes = playback.autosave().unwrap().strokes();
    assert!(strokes > 0, "the scene's stamps are strokes");
    wait_for("every stroke on disk", || playback.autosave().unwrap().durable_strokes() == strokes);
    wait_for("a snapshot", || !files(&dir, "snapshot-").is_empty());
    let tools = playback.stored_tools();
    assert_eq!(tools.len(), 1);
    // Dropped without closing, as a crash would leave it.
    let field = playback.into_field();
    let recovered = recover(&dir).unwrap();
    assert!(recovered.sculpt.field.same_samples(&field));
    assert!(recovered.sculpt.tools == tools, "the tool as the scene copied it from its first clay");
    std::fs::remove_dir_all(&root).unwrap();
}

/// A disk with no room left for new files: writing a whole file fails once `full` is set;
/// appends and removals still work (a full disk frees space by removing).
#[derive(Debug, Default)]
struct NoRoomForNewFiles {
    full: Arc<std::sync::atomic::AtomicBool>,
}

impl Disk for NoRoomForNewFiles {
    fn create_dir(&self, path: &Path) -> Result<()> {
        LocalDisk.create_dir(path)
    }

    fn write_whole(&self, path: &Path, bytes: &[u8]) -> Result<()> {
        injected(if self.full.load(Ordering::SeqCst) { 1 } else { 0 }, path, "write")?;
        LocalDisk.write_whole(path, bytes)
    }

    fn create_append(&self, path: &Path) -> Result<Box<dyn AppendFile>> {
        LocalDisk.create_append(path)
    }

    fn remove(&self, path: &Path) -> Result<()> {
        LocalDisk.remove(path)
    }
}

#[test]
fn a_session_closes_on_a_full_disk_by_removing_its_files() {
    let root = temp_dir("close-full");
    let disk = NoRoomForNewFiles::default();
    let full = Arc::clone(&disk.full);
    let mut field = Field::new(0.001, 0.5);
    let mut autosave = Autosave::start(&root, &mut field, None, "test", fast(), Arc::new(disk)).unwrap();
    let dir = autosave.dir().to_path_buf();
    stroke(&mut field, 0);
    autosave.record(&mut field);
    // The disk fills up: the session cannot be marked closed, but its files can go.
    full.store(true, Ordering::SeqCst);
    autosave.close().expect("closing needs no new file");
    assert!(!dir.exists(), "the session's folder is gone");
    assert!(unclosed_sessions(&root).is_empty(), "nothing is left to recover");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_session_folder_with_journaled_strokes_and_no_snapshot_is_kept_and_named() {
    let root = temp_dir("no-snapshot");
    let mut field = Field::new(0.001, 0.5);
    let mut autosave = Autosave::start(&root, &mut field, None, "test", fast(), Arc::new(LocalDisk)).unwrap();
    let dir = autosave.dir().to_path_buf();
    for i in 0..3 {
        stroke(&mut field, i);
        autosave.record(&mut field);
    }
    wait_for("the strokes on disk", || autosave.durable_strokes() == 3);
    drop(autosave);
    // The snapshot is lost (a disk that dropped it): the journal's strokes are not thrown away.
    for snapshot in files(&dir, "snapshot-") {
        std::fs::remove_file(dir.join(snapshot)).unwrap();
    }
    let e = recover(&dir).unwrap_err();
    assert!(!e.empty, "{e}");
    assert!(e.to_string().contains("its journal holds 3 stroke(s)"), "{e}");
    assert!(dir.exists());
    std::fs::remove_dir_all(&root).unwrap();
}
