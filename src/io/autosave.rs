//! Autosave and crash recovery: a write-ahead journal of finished strokes, folded into
//! snapshots by checkpoints, in a session folder (layout in the module docs of `io`).
//!
//! ```text
//!  start: snapshot-0 written (before any stroke can be journaled)
//!  sculpting thread              writer thread                        checkpoint thread
//!  stroke ends ──record()──────► appends the stroke's record;
//!  (hands over shared bricks:    syncs at most `sync_interval` later;
//!   no copy, no disk)            keeps a mirror of the sculpt ──job──► encodes the mirror,
//!                                                                       writes snapshot-N
//!                                starts a new journal, removes ◄─done── atomically
//!                                the files snapshot-N covers
//! ```
//!
//! - The first snapshot is written by [`Autosave::start`] itself, so every journaled stroke
//!   has a snapshot to apply to: no crash after the start loses a stroke that was synced.
//!   This costs the start one encoding of the sculpt (measured in the docs of
//!   [`Autosave::start_with_tools`]); recovering instead from the scene text or the opened
//!   file would depend on rebuilding them bit for bit, which a later build may not do.
//! - The sculpting thread never waits on the disk: [`Autosave::record`] takes the bricks the
//!   stroke changed from the field (shared, copy-on-write) and sends them to the writer.
//! - A failing disk (full, read-only, no permission) is reported once by a warning that
//!   names the path ([`Autosave::problem`] holds it); the sculpt stays in memory, the files
//!   already written stay as they are, and a checkpoint is retried every `retry_interval`
//!   until one succeeds.
//! - [`Autosave::close`] marks the session closed and removes its files; a session folder
//!   that is neither closed nor owned by a live process is what [`unclosed_sessions`] finds
//!   and [`recover`] reads.
//! - A lattice held open ([`Autosave::set_lattice`]), the parts' layouts and the symmetry the
//!   strokes act through ([`Autosave::set_symmetry`]) live only in snapshots: a change of any
//!   rewrites the newest snapshot (on the writer thread), with the clay the lattice rests on,
//!   so a crash recovers it open as it last stood, and the symmetry in force; a stroke
//!   journaled later on the lattice's part is the lattice applied, and recovery then drops it.
//! - File operations go through [`Disk`], so that tests can make them fail.

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use super::journal::{self, Reader};
use super::process::start_token;
use super::{
    decode, encode_bricks, write_atomically, PartBrick, PartLayout, SceneParts, Sculpt, StoredLattice,
    StoredTool,
};
use crate::field::{Brick, Field, LevelKey};
use crate::parts::Symmetry;

/// When autosave syncs and checkpoints.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AutosaveConfig {
    /// The longest a written record waits for its sync (at most one second: longer is
    /// shortened to one second).
    pub sync_interval: Duration,
    /// How old the oldest stroke not yet in a snapshot may grow before a checkpoint folds the
    /// journal into a new snapshot (default 60 s): idle time does not count.
    pub checkpoint_interval: Duration,
    /// A journal this large is folded at once, whatever its age (default 256 MiB).
    pub checkpoint_journal_bytes: u64,
    /// After a failure, how long autosave waits before it tries again (default 10 s).
    pub retry_interval: Duration,
}

impl Default for AutosaveConfig {
    fn default() -> Self {
        Self {
            sync_interval: Duration::from_secs(1),
            checkpoint_interval: Duration::from_secs(60),
            checkpoint_journal_bytes: 256 << 20,
            retry_interval: Duration::from_secs(10),
        }
    }
}

/// A file autosave appends to.
pub trait AppendFile: Send {
    /// Appends `bytes` (all of them, or an error).
    fn append(&mut self, bytes: &[u8]) -> Result<()>;
    /// Makes what was appended durable.
    fn sync(&mut self) -> Result<()>;
}

/// The file operations autosave uses; errors name the path.
pub trait Disk: Send + Sync + std::fmt::Debug {
    /// Creates a folder and its parents.
    fn create_dir(&self, path: &Path) -> Result<()>;
    /// Writes a whole file atomically: a failure leaves what was at `path` as it was.
    fn write_whole(&self, path: &Path, bytes: &[u8]) -> Result<()>;
    /// Creates a new, empty file to append to (its folder entry made durable).
    fn create_append(&self, path: &Path) -> Result<Box<dyn AppendFile>>;
    /// Removes a file.
    fn remove(&self, path: &Path) -> Result<()>;
}

/// The local file system.
#[derive(Clone, Copy, Debug, Default)]
pub struct LocalDisk;

struct LocalFile {
    file: std::fs::File,
    path: PathBuf,
}

impl AppendFile for LocalFile {
    fn append(&mut self, bytes: &[u8]) -> Result<()> {
        self.file.write_all(bytes).with_context(|| format!("cannot write {}", self.path.display()))
    }

    fn sync(&mut self) -> Result<()> {
        self.file.sync_data().with_context(|| format!("cannot flush {} to disk", self.path.display()))
    }
}

fn sync_folder(path: &Path) {
    // Makes a new folder entry durable; folders cannot be synced on every platform.
    if let Some(Ok(d)) = path.parent().map(std::fs::File::open) {
        let _ = d.sync_all();
    }
}

impl Disk for LocalDisk {
    fn create_dir(&self, path: &Path) -> Result<()> {
        std::fs::create_dir_all(path).with_context(|| format!("cannot create the folder {}", path.display()))
    }

    fn write_whole(&self, path: &Path, bytes: &[u8]) -> Result<()> {
        write_atomically(path, true, |w| {
            w.write_all(bytes).with_context(|| format!("cannot write {}", path.display()))
        })
    }

    fn create_append(&self, path: &Path) -> Result<Box<dyn AppendFile>> {
        let file =
            std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
        sync_folder(path);
        Ok(Box::new(LocalFile { file, path: path.to_path_buf() }))
    }

    fn remove(&self, path: &Path) -> Result<()> {
        std::fs::remove_file(path).with_context(|| format!("cannot remove {}", path.display()))
    }
}

/// Who owns a session folder (its `session.json`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SessionInfo {
    /// The owning process.
    pub pid: u32,
    /// The process's start time as the system reports it (Linux: `/proc/PID/stat`), so that
    /// a later process given the same id is not taken for the owner.
    pub start_token: Option<String>,
    /// When the session started, seconds since the Unix epoch.
    pub started_unix_s: u64,
    /// What was being sculpted (a scene file, or a description).
    pub source: String,
}

impl SessionInfo {
    fn of_this_process(source: &str) -> Self {
        let pid = std::process::id();
        Self {
            pid,
            start_token: start_token(pid),
            started_unix_s: SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs()),
            source: source.to_owned(),
        }
    }

    /// Whether the process that owns the session still runs. Exact on Linux; elsewhere a
    /// session is taken as orphaned once its owner's id is not this process's.
    pub fn owner_alive(&self) -> bool {
        if self.pid == std::process::id() {
            return true;
        }
        match (&self.start_token, start_token(self.pid)) {
            (Some(mine), Some(now)) => *mine == now,
            _ => false,
        }
    }
}

const SESSION_FILE: &str = "session.json";
const CLOSED_FILE: &str = "closed";

fn numbered(dir: &Path, prefix: &str, ext: &str) -> Vec<(u64, PathBuf)> {
    let mut found: Vec<(u64, PathBuf)> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let n = name.strip_prefix(prefix)?.strip_suffix(ext)?.parse().ok()?;
            Some((n, e.path()))
        })
        .collect();
    found.sort();
    found
}

fn snapshot_path(dir: &Path, n: u64) -> PathBuf {
    dir.join(format!("snapshot-{n}.argile"))
}

fn journal_path(dir: &Path, base: u64) -> PathBuf {
    dir.join(format!("journal-{base}.argj"))
}

/// Why autosave could not start; names the folder or file.
#[derive(Debug, thiserror::Error)]
#[error("autosave cannot start: {0:#}")]
pub struct AutosaveError(anyhow::Error);

#[derive(Debug, Default)]
struct Shared {
    durable: AtomicU64,
    problem: Mutex<Option<String>>,
}

type Changes = Vec<PartBrick>;

/// What a session's snapshots store besides the first part's clay: the scene's freeform tools
/// as they were copied, and for a sculpt of parts their layouts and the clay of the parts after
/// the first (whose changes [`Autosave::record_parts`] then journals).
#[derive(Debug, Default)]
pub struct Besides<'a> {
    /// The scene's freeform tools.
    pub tools: &'a [StoredTool],
    /// The parts' layouts (none: one part at rest).
    pub layouts: &'a [PartLayout],
    /// The clay of the parts after the first.
    pub others: &'a mut [Field],
    /// The symmetry the strokes act through (none: the scene's, never stored).
    pub symmetry: Option<Symmetry>,
}

impl<'a> Besides<'a> {
    /// The scene's freeform tools alone: a sculpt of one part.
    pub fn tools(tools: &'a [StoredTool]) -> Self {
        Self { tools, ..Self::default() }
    }
}

/// A brick of the sculpt: its part's index (0 the first) and its key.
type PartKey = (u16, LevelKey);

enum Msg {
    Stroke(u64, Changes),
    /// The parts' layouts as they are now; the reply comes once a snapshot holds them.
    Layouts(Vec<PartLayout>, Sender<()>),
    /// The lattice held open as it is now (`None`: none is held).
    Lattice(Option<StoredLattice>),
    /// The symmetry the strokes act through now.
    Symmetry(Symmetry),
    Checkpointed(u64, Result<(), String>),
    Close(Sender<Result<()>>),
    /// Stop without closing: the session stays open for recovery.
    Stop,
}

/// A running autosave session: see the module docs.
#[derive(Debug)]
pub struct Autosave {
    dir: PathBuf,
    strokes: u64,
    tx: Sender<Msg>,
    shared: Arc<Shared>,
    writer: Option<JoinHandle<()>>,
}

impl Autosave {
    /// Starts a session in a new folder inside `root` for `field` as it is now (between
    /// strokes), made from `scene_toml` (stored in snapshots); `source` says what is sculpted.
    /// Fails, naming the path, when the folder or its session file cannot be written.
    pub fn start(
        root: &Path,
        field: &mut Field,
        scene_toml: Option<&str>,
        source: &str,
        config: AutosaveConfig,
        disk: Arc<dyn Disk>,
    ) -> Result<Self, AutosaveError> {
        Self::start_with_tools(root, field, (scene_toml, Besides::default()), source, config, disk)
    }

    /// [`Autosave::start`] for a scene with freeform tools (`scene`: its text and its tools as
    /// they were copied), which the snapshots store, so that a recovered sculpt keeps them.
    ///
    /// Writes the first snapshot before returning (release build, 2-core development machine,
    /// three runs: the default scene's 1.0 MB, 23 to 36 ms; a 20 cm sphere at 1 mm, 2.2 MB,
    /// 52 to 116 ms; see BENCHMARKS.md). Where it cannot be written, the
    /// problem is reported and retried as any checkpoint's; strokes are journaled from the
    /// first snapshot that succeeds.
    pub fn start_with_tools(
        root: &Path,
        field: &mut Field,
        (scene_toml, Besides { tools, layouts, others, symmetry }): (Option<&str>, Besides<'_>),
        source: &str,
        config: AutosaveConfig,
        disk: Arc<dyn Disk>,
    ) -> Result<Self, AutosaveError> {
        debug_assert!(!field.in_stroke(), "autosave starts between strokes");
        let info = SessionInfo::of_this_process(source);
        let nanos = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.subsec_nanos());
        let dir = root.join(format!("{}-{}-{nanos:09}", info.started_unix_s, info.pid));
        disk.create_dir(&dir).map_err(AutosaveError)?;
        let json = serde_json::to_vec_pretty(&info).expect("plain values serialise");
        disk.write_whole(&dir.join(SESSION_FILE), &json).map_err(AutosaveError)?;
        // What strokes changed before now is in the first snapshot.
        drop(field.take_changed_bricks());
        let mut mirror: HashMap<PartKey, Arc<Brick>> =
            field.shared_bricks().map(|(k, b)| ((0, k), Arc::clone(b))).collect();
        for (i, other) in others.iter_mut().enumerate() {
            drop(other.take_changed_bricks());
            mirror.extend(other.shared_bricks().map(|(k, b)| ((i as u16 + 1, k), Arc::clone(b))));
        }
        let layouts = layouts.to_vec();
        let tools: Arc<[StoredTool]> = Arc::from(tools);
        let first = snapshot_path(&dir, 0);
        let encoding = Instant::now();
        let (voxel_size_m, iso) = (field.transform().voxel_size_m, field.iso());
        let bytes = snapshot_bytes(
            (voxel_size_m, iso),
            mirror.iter(),
            (scene_toml, &tools),
            (&layouts, None, symmetry.as_ref()),
        );
        let first_written = disk.write_whole(&first, &bytes).map_err(|e| format!("{e:#}"));
        tracing::debug!(
            "autosave: the first snapshot ({} bytes) took {:.1} ms",
            bytes.len(),
            encoding.elapsed().as_secs_f64() * 1e3
        );
        drop(bytes);
        let shared = Arc::new(Shared::default());
        let (tx, rx) = mpsc::channel();
        let writer = Writer {
            dir: dir.clone(),
            disk,
            config,
            shared: Arc::clone(&shared),
            mirror,
            voxel_size_m,
            iso,
            scene_toml: scene_toml.map(Arc::from),
            tools,
            layouts,
            lattice: None,
            symmetry,
            journal: None,
            journals: Vec::new(),
            snapshots: if first_written.is_ok() { vec![(0, first)] } else { Vec::new() },
            written: 0,
            gap: false,
            sync_due: None,
            unfolded_since: None,
            checkpoint: None,
            retry_at: None,
            tx: tx.clone(),
        };
        let writer = std::thread::Builder::new()
            .name("autosave".into())
            .spawn(move || writer.run(rx, first_written.err()))
            .map_err(|e| AutosaveError(anyhow::anyhow!("cannot start its thread: {e}")))?;
        Ok(Self { dir, strokes: 0, tx, shared, writer: Some(writer) })
    }

    /// Journals the stroke that just ended (or the undo or redo just done): hands the bricks
    /// it changed to the writer thread. Costs a map lookup per changed brick and no copy; does
    /// nothing when nothing changed.
    pub fn record(&mut self, field: &mut Field) {
        self.record_parts(field, &mut []);
    }

    /// [`Autosave::record`] for a sculpt of parts: `first` the first part's clay, `others` the
    /// clay of the parts after it (as the session was started with them).
    pub fn record_parts(&mut self, first: &mut Field, others: &mut [Field]) {
        let mut changes: Changes = first.take_changed_bricks().into_iter().map(|(k, b)| (0, k, b)).collect();
        for (i, field) in others.iter_mut().enumerate() {
            changes.extend(field.take_changed_bricks().into_iter().map(|(k, b)| (i as u16 + 1, k, b)));
        }
        if changes.is_empty() {
            return;
        }
        self.strokes += 1;
        // A writer that has stopped has reported why; the sculpt stays in memory.
        let _ = self.tx.send(Msg::Stroke(self.strokes, changes));
    }

    /// Stores the parts' layouts as they are now (a part moved, hidden, locked): the writer
    /// writes the snapshot of the strokes so far again with them (atomically, in place of the
    /// one of that number) before this returns, so that no recovery puts a part back.
    pub fn set_layouts(&mut self, layouts: Vec<PartLayout>) {
        let (done, wait) = mpsc::channel();
        if self.tx.send(Msg::Layouts(layouts, done)).is_ok() {
            // A writer that has stopped has reported why.
            let _ = wait.recv();
        }
    }

    /// Stores the lattice held open as it is now (`None` once it is applied or its clay put
    /// back): the writer writes the snapshot of the strokes so far again with it, so that a
    /// crash while a lattice is open recovers the clay as it was when the lattice opened with
    /// the lattice over it, shaped as it was stored. Does not wait for the disk; send it when an
    /// edit of the lattice stops, not on every frame of a drag. A stroke journaled later on the
    /// lattice's part (the lattice applied) ends it, on disk as in recovery.
    pub fn set_lattice(&mut self, lattice: Option<StoredLattice>) {
        // A writer that has stopped has reported why.
        let _ = self.tx.send(Msg::Lattice(lattice));
    }

    /// Stores the symmetry the strokes act through from now on: the writer writes the snapshot
    /// of the strokes so far again with it, so that a crash recovers the sculpt with the
    /// symmetry in force. Does not wait for the disk.
    pub fn set_symmetry(&mut self, symmetry: Symmetry) {
        let _ = self.tx.send(Msg::Symmetry(symmetry));
    }

    /// The session folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Strokes recorded so far.
    pub fn strokes(&self) -> u64 {
        self.strokes
    }

    /// Strokes that a crash from now on cannot lose (synced to disk).
    pub fn durable_strokes(&self) -> u64 {
        self.shared.durable.load(Ordering::Acquire)
    }

    /// What keeps autosave from writing, if anything: one sentence naming the path.
    pub fn problem(&self) -> Option<String> {
        self.shared.problem.lock().map(|p| p.clone()).unwrap_or(None)
    }

    /// Ends the session cleanly: syncs, marks the session closed and removes its files.
    /// Fails (naming the path) if the session cannot be marked closed; then the next start
    /// recovers it.
    pub fn close(mut self) -> Result<()> {
        let (tx, rx) = mpsc::channel();
        self.tx.send(Msg::Close(tx)).map_err(|_| anyhow::anyhow!("the autosave thread has stopped"))?;
        let result = rx.recv().unwrap_or_else(|_| Err(anyhow::anyhow!("the autosave thread has stopped")));
        if let Some(w) = self.writer.take() {
            let _ = w.join();
        }
        result
    }
}

impl Drop for Autosave {
    /// Without [`Autosave::close`], the session stays open: the writer syncs what it has and
    /// stops, and the next start recovers the session.
    fn drop(&mut self) {
        if let Some(w) = self.writer.take() {
            let _ = self.tx.send(Msg::Stop);
            let _ = w.join();
        }
    }
}

struct Journal {
    file: Box<dyn AppendFile>,
    base: u64,
    /// The newest stroke appended.
    last: u64,
    unsynced: bool,
    bytes: u64,
}

struct Job {
    stroke: u64,
    bricks: Vec<(PartKey, Arc<Brick>)>,
    layouts: Vec<PartLayout>,
    lattice: Option<StoredLattice>,
    symmetry: Option<Symmetry>,
}

struct Writer {
    dir: PathBuf,
    disk: Arc<dyn Disk>,
    config: AutosaveConfig,
    shared: Arc<Shared>,
    mirror: HashMap<PartKey, Arc<Brick>>,
    voxel_size_m: f32,
    iso: f32,
    scene_toml: Option<Arc<str>>,
    tools: Arc<[StoredTool]>,
    /// The parts' layouts (none: one part at rest).
    layouts: Vec<PartLayout>,
    /// The lattice held open over the clay of `mirror` (which is its part's clay as it was when
    /// the lattice opened: its stroke is journaled when it is applied).
    lattice: Option<StoredLattice>,
    /// The symmetry the strokes act through (none: the scene's, never set).
    symmetry: Option<Symmetry>,
    journal: Option<Journal>,
    /// Journal files on disk (base, path), oldest first; the last one is `journal`'s.
    journals: Vec<(u64, PathBuf)>,
    /// Snapshots on disk (stroke, path), oldest first.
    snapshots: Vec<(u64, PathBuf)>,
    /// The newest stroke received.
    written: u64,
    /// Whether strokes are missing between the newest snapshot and the current journal (after
    /// a failure): until a checkpoint covers them, the journal does not extend what a
    /// recovery gets.
    gap: bool,
    sync_due: Option<Instant>,
    unfolded_since: Option<Instant>,
    /// The checkpoint being written: its stroke and thread.
    checkpoint: Option<(u64, JoinHandle<()>)>,
    retry_at: Option<Instant>,
    tx: Sender<Msg>,
}

impl Writer {
    /// Runs until closed or dropped; `first_failed` says why the first snapshot could not be
    /// written (then it is retried, and strokes are journaled once one is).
    fn run(mut self, rx: mpsc::Receiver<Msg>, first_failed: Option<String>) {
        match first_failed {
            None => self.open_journal(),
            Some(problem) => self.fail(problem),
        }
        loop {
            let wait = self.next_deadline().map(|d| d.saturating_duration_since(Instant::now()));
            let msg = match wait {
                Some(w) => rx.recv_timeout(w),
                None => rx.recv().map_err(|_| RecvTimeoutError::Disconnected),
            };
            match msg {
                Ok(Msg::Stroke(n, changes)) => self.stroke(n, changes),
                Ok(Msg::Layouts(layouts, done)) => {
                    if layouts != self.layouts {
                        self.layouts = layouts;
                        self.rewrite_snapshot();
                    }
                    let _ = done.send(());
                }
                Ok(Msg::Lattice(lattice)) => {
                    if lattice != self.lattice {
                        let open = lattice.is_some();
                        self.lattice = lattice;
                        if self.rewrite_snapshot() {
                            let n = self.written;
                            match open {
                                true => {
                                    tracing::debug!("autosave: the open lattice is on disk (snapshot {n})")
                                }
                                false => tracing::debug!("autosave: no open lattice on disk (snapshot {n})"),
                            }
                        }
                    }
                }
                Ok(Msg::Symmetry(symmetry)) => {
                    if self.symmetry != Some(symmetry) {
                        self.symmetry = Some(symmetry);
                        if self.rewrite_snapshot() {
                            tracing::debug!(
                                "autosave: the symmetry in force is on disk (snapshot {})",
                                self.written
                            );
                        }
                    }
                }
                Ok(Msg::Checkpointed(n, result)) => self.checkpointed(n, result),
                Ok(Msg::Close(reply)) => {
                    let _ = reply.send(self.close());
                    return;
                }
                Err(RecvTimeoutError::Timeout) => {}
                Ok(Msg::Stop) | Err(RecvTimeoutError::Disconnected) => {
                    // Dropped without closing: keep what was written, leave the session open.
                    self.finish_checkpoint();
                    self.sync();
                    return;
                }
            }
            self.tick();
        }
    }

    fn sync_interval(&self) -> Duration {
        self.config.sync_interval.min(Duration::from_secs(1))
    }

    fn next_deadline(&self) -> Option<Instant> {
        if self.checkpoint.is_some() {
            // Folding waits for the checkpoint being written.
            return self.sync_due;
        }
        let fold = self.unfolded_since.map(|t| t + self.config.checkpoint_interval);
        [self.sync_due, fold, self.retry_at].into_iter().flatten().min()
    }

    fn report(&self, problem: String) {
        let mut slot = self.shared.problem.lock().unwrap_or_else(|e| e.into_inner());
        if slot.is_none() {
            tracing::warn!(
                "autosave: {problem}; the sculpt stays in memory but a crash would lose the strokes from now on: \
                 free space or fix the folder's permissions, or save the sculpt to another place"
            );
        }
        *slot = Some(problem);
    }

    fn clear_problem(&self) {
        let mut slot = self.shared.problem.lock().unwrap_or_else(|e| e.into_inner());
        if slot.take().is_some() {
            tracing::info!("autosave: writing to {} again", self.dir.display());
        }
    }

    fn fail(&mut self, problem: String) {
        // A journal that failed may end in a torn record: nothing more goes into it.
        self.journal = None;
        self.report(problem);
        self.retry_at.get_or_insert(Instant::now() + self.config.retry_interval);
    }

    fn open_journal(&mut self) {
        let base = self.written;
        let path = journal_path(&self.dir, base);
        let result = self.disk.create_append(&path).and_then(|mut file| {
            file.append(&journal::header(base))?;
            file.sync()?;
            Ok(file)
        });
        match result {
            Ok(file) => {
                self.journal =
                    Some(Journal { file, base, last: base, unsynced: false, bytes: journal::HEADER as u64 });
                self.journals.push((base, path));
            }
            Err(e) => {
                // Leave no journal without a whole header behind, where the disk allows.
                let _ = self.disk.remove(&path);
                self.fail(format!("{e:#}"));
            }
        }
    }

    /// Writes the snapshot of the strokes so far again (atomically, in place of the one of that
    /// number) with the layouts and the lattice as they are now; returns whether it was written.
    fn rewrite_snapshot(&mut self) -> bool {
        self.finish_checkpoint();
        let n = self.written;
        let bytes = snapshot_bytes(
            (self.voxel_size_m, self.iso),
            self.mirror.iter(),
            (self.scene_toml.as_deref(), &self.tools),
            (&self.layouts, self.lattice.as_ref(), self.symmetry.as_ref()),
        );
        let path = snapshot_path(&self.dir, n);
        match self.disk.write_whole(&path, &bytes) {
            Ok(()) => {
                if !self.snapshots.iter().any(|(s, _)| *s == n) {
                    self.snapshots.push((n, path));
                }
                true
            }
            Err(e) => {
                self.fail(format!("{e:#}"));
                false
            }
        }
    }

    fn stroke(&mut self, n: u64, mut changes: Changes) {
        // Sorted here, not on the sculpting thread: the same strokes give the same bytes.
        changes.sort_unstable_by_key(|(p, k, _)| (*p, k.sort_key()));
        // A step closed on the lattice's part is the lattice applied: its clay is journaled.
        if self.lattice.as_ref().is_some_and(|l| changes.iter().any(|(p, ..)| usize::from(*p) == l.part)) {
            self.lattice = None;
        }
        let bytes = (self.journal.is_some()).then(|| journal::record(n, &changes));
        for (part, key, brick) in changes {
            match brick {
                Some(b) => self.mirror.insert((part, key), b),
                None => self.mirror.remove(&(part, key)),
            };
        }
        self.written = n;
        self.unfolded_since.get_or_insert_with(Instant::now);
        let (Some(bytes), Some(journal)) = (bytes, self.journal.as_mut()) else { return };
        match journal.file.append(&bytes) {
            Ok(()) => {
                tracing::trace!("autosave: stroke {n} is in the journal, not yet synced");
                journal.last = n;
                journal.unsynced = true;
                journal.bytes += bytes.len() as u64;
                let interval = self.sync_interval();
                self.sync_due.get_or_insert_with(|| Instant::now() + interval);
            }
            Err(e) => self.fail(format!("{e:#}")),
        }
    }

    fn sync(&mut self) {
        self.sync_due = None;
        let Some(journal) = self.journal.as_mut() else { return };
        if !journal.unsynced {
            return;
        }
        match journal.file.sync() {
            Ok(()) => {
                journal.unsynced = false;
                if !self.gap && !self.snapshots.is_empty() {
                    self.shared.durable.fetch_max(journal.last, Ordering::AcqRel);
                    tracing::debug!("autosave: strokes up to {} are on disk", journal.last);
                }
            }
            Err(e) => self.fail(format!("{e:#}")),
        }
    }

    fn tick(&mut self) {
        let now = Instant::now();
        if self.sync_due.is_some_and(|d| d <= now) {
            self.sync();
        }
        if self.checkpoint.is_some() {
            return;
        }
        let retry = self.retry_at.is_some_and(|t| t <= now);
        let old =
            self.unfolded_since.is_some_and(|t| now.duration_since(t) >= self.config.checkpoint_interval);
        let large = self.journal.as_ref().is_some_and(|j| j.bytes >= self.config.checkpoint_journal_bytes);
        if retry || old || large {
            self.retry_at = None;
            self.start_checkpoint();
        }
    }

    fn start_checkpoint(&mut self) {
        let job = Job {
            stroke: self.written,
            bricks: self.mirror.iter().map(|(k, b)| (*k, Arc::clone(b))).collect(),
            layouts: self.layouts.clone(),
            lattice: self.lattice.clone(),
            symmetry: self.symmetry,
        };
        let (dir, disk, tx) = (self.dir.clone(), Arc::clone(&self.disk), self.tx.clone());
        let (voxel, iso, scene, tools) =
            (self.voxel_size_m, self.iso, self.scene_toml.clone(), Arc::clone(&self.tools));
        let n = job.stroke;
        let spawned = std::thread::Builder::new().name("autosave-checkpoint".into()).spawn(move || {
            let bricks = job.bricks.iter().map(|(k, b)| (k, b));
            let bytes = snapshot_bytes(
                (voxel, iso),
                bricks,
                (scene.as_deref(), &tools),
                (&job.layouts, job.lattice.as_ref(), job.symmetry.as_ref()),
            );
            let result =
                disk.write_whole(&snapshot_path(&dir, job.stroke), &bytes).map_err(|e| format!("{e:#}"));
            let _ = tx.send(Msg::Checkpointed(job.stroke, result));
        });
        match spawned {
            Ok(handle) => {
                self.checkpoint = Some((n, handle));
                self.unfolded_since = None;
            }
            Err(e) => self.fail(format!("cannot start the checkpoint thread: {e}")),
        }
    }

    fn checkpointed(&mut self, n: u64, result: Result<(), String>) {
        if let Some((_, handle)) = self.checkpoint.take() {
            let _ = handle.join();
        }
        if self.written > n {
            self.unfolded_since.get_or_insert_with(Instant::now);
        }
        if let Err(e) = result {
            self.fail(e);
            return;
        }
        self.snapshots.push((n, snapshot_path(&self.dir, n)));
        self.shared.durable.fetch_max(n, Ordering::AcqRel);
        tracing::debug!("autosave: strokes up to {n} are on disk (snapshot)");
        if self.gap && self.journal.as_ref().is_some_and(|j| n >= j.base) {
            self.gap = false;
        }
        let roll = self.journal.as_ref().is_some_and(|j| j.last > j.base);
        if self.journal.is_none() || (roll && !self.gap) {
            // The old journal holds the strokes after `n` received meanwhile: sync it before
            // the next one takes over.
            self.sync();
            let intact = self.journal.is_some();
            self.open_journal();
            // The new journal starts after `written`: strokes n + 1 ..= written are in the
            // old journal if it was intact, else in none, and then are folded at once.
            self.gap = !intact && self.written > n;
            if self.gap {
                self.retry_at = Some(Instant::now());
            }
        }
        if let Some(journal) = self.journal.as_ref().filter(|_| !self.gap) {
            // Strokes synced before the first snapshot existed count from now.
            if !journal.unsynced {
                self.shared.durable.fetch_max(journal.last, Ordering::AcqRel);
            }
            self.clear_problem();
        }
        self.remove_covered(n);
    }

    /// Removes the snapshots older than `n` and the journals whose strokes are all ≤ `n`.
    fn remove_covered(&mut self, n: u64) {
        let (old, keep): (Vec<_>, Vec<_>) = self.snapshots.drain(..).partition(|(s, _)| *s < n);
        self.snapshots = keep;
        let mut gone: Vec<PathBuf> = old.into_iter().map(|(_, p)| p).collect();
        let mut i = 0;
        while i + 1 < self.journals.len() && self.journals[i + 1].0 <= n {
            i += 1;
        }
        gone.extend(self.journals.drain(..i).map(|(_, p)| p));
        for path in gone {
            if let Err(e) = self.disk.remove(&path) {
                tracing::debug!("autosave: {e:#}");
            }
        }
    }

    fn finish_checkpoint(&mut self) {
        if let Some((_, handle)) = self.checkpoint.take() {
            let _ = handle.join();
        }
    }

    /// Marks the session closed, then removes its files: journals first, so that a crash in
    /// between never leaves strokes without their snapshot. A full disk may refuse the mark
    /// but not the removals: the session is closed all the same once its files are gone.
    fn close(&mut self) -> Result<()> {
        self.finish_checkpoint();
        self.sync();
        let marked = self.disk.write_whole(&self.dir.join(CLOSED_FILE), b"closed\n");
        // Listed from the folder: a checkpoint that finished just now is not in `snapshots`.
        let journals = numbered(&self.dir, "journal-", ".argj");
        let snapshots = numbered(&self.dir, "snapshot-", ".argile");
        let files = journals.into_iter().chain(snapshots).map(|(_, p)| p);
        let mut left = Vec::new();
        for path in files.chain([self.dir.join(SESSION_FILE)]) {
            if let Err(e) = self.disk.remove(&path) {
                left.push(format!("{e:#}"));
            }
        }
        // The mark stays with files that could not be removed, so no start recovers them.
        if marked.is_ok() && left.is_empty() {
            let _ = self.disk.remove(&self.dir.join(CLOSED_FILE));
        }
        let _ = std::fs::remove_dir(&self.dir);
        match (marked, left.is_empty()) {
            (_, true) => Ok(()),
            (Ok(()), false) => {
                tracing::debug!("autosave: the closed session {} keeps files: {}", self.dir.display(), left.join("; "));
                Ok(())
            }
            (Err(e), false) => Err(e.context(format!(
                "cannot mark the autosave session {} closed nor remove its files ({}); the next start recovers it",
                self.dir.display(),
                left.join("; ")
            ))),
        }
    }
}

/// A snapshot of the sculpt: `bricks` of its parts, the first in a field of `(voxel size,
/// iso-level)`, with the scene's text and tools, the parts' `layouts`, the lattice held open and
/// the symmetry in force.
fn snapshot_bytes<'b>(
    (voxel_size_m, iso): (f32, f32),
    bricks: impl Iterator<Item = (&'b PartKey, &'b Arc<Brick>)>,
    (scene_toml, tools): (Option<&str>, &[StoredTool]),
    (layouts, lattice, symmetry): (&[PartLayout], Option<&StoredLattice>, Option<&Symmetry>),
) -> Vec<u8> {
    let (mut first, mut others) = (Vec::new(), Vec::new());
    for ((part, key), brick) in bricks {
        match part {
            0 => first.push((*key, &**brick)),
            p => others.push((u32::from(*p), *key, &**brick)),
        }
    }
    let scene = SceneParts { toml: scene_toml, tools, layouts, lattice, symmetry, ..SceneParts::default() };
    encode_bricks(voxel_size_m, iso, first, scene, others, &mut |_| {})
}

/// A session folder found at start.
#[derive(Clone, Debug)]
pub struct Session {
    /// The folder.
    pub dir: PathBuf,
    /// Its owner.
    pub info: SessionInfo,
}

/// The sessions under `root` that did not close and whose process is gone, oldest first.
/// Folders of sessions that closed (but whose files were not all removed) are removed.
pub fn unclosed_sessions(root: &Path) -> Vec<Session> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(root).into_iter().flatten().flatten() {
        let dir = entry.path();
        if dir.join(CLOSED_FILE).exists() {
            let _ = std::fs::remove_dir_all(&dir);
            continue;
        }
        let Ok(text) = std::fs::read(dir.join(SESSION_FILE)) else {
            remove_if_stillborn(&dir);
            continue;
        };
        let Ok(info) = serde_json::from_slice::<SessionInfo>(&text) else {
            tracing::warn!(
                "autosave: {} is not a session file; the folder is left alone",
                dir.join(SESSION_FILE).display()
            );
            continue;
        };
        if !info.owner_alive() {
            found.push(Session { dir, info });
        }
    }
    found.sort_by_key(|s| (s.info.started_unix_s, s.dir.clone()));
    found
}

/// Removes a session folder that has no session file (its process ended while starting it,
/// before any sculpt was written), once the process named in the folder's name is gone.
fn remove_if_stillborn(dir: &Path) {
    let Some(name) = dir.file_name().and_then(|n| n.to_str()) else { return };
    let mut parts = name.split('-');
    let (Some(_), Some(Ok(pid)), Some(_), None) =
        (parts.next(), parts.next().map(str::parse::<u32>), parts.next(), parts.next())
    else {
        return;
    };
    let has_data =
        !numbered(dir, "snapshot-", ".argile").is_empty() || !numbered(dir, "journal-", ".argj").is_empty();
    if !has_data && pid != std::process::id() && start_token(pid).is_none() {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// A session's sculpt as recovered.
#[derive(Debug)]
pub struct Recovered {
    /// The sculpt after its last complete stroke.
    pub sculpt: Sculpt,
    /// Strokes the sculpt holds (the session's stroke count at that point).
    pub strokes: u64,
    /// Strokes in the snapshot recovery started from.
    pub snapshot_strokes: u64,
    /// Why the journal's end was discarded, if it was (a stroke cut short by the crash): the
    /// first reason found.
    pub discarded: Option<String>,
}

/// Why a session cannot be recovered; names the folder.
#[derive(Debug, thiserror::Error)]
#[error("autosave session {dir}: {reason}")]
pub struct RecoveryError {
    /// The session folder.
    pub dir: PathBuf,
    /// What is missing or damaged.
    pub reason: String,
    /// Whether the session holds no snapshot at all: it ended before its first was written,
    /// so it holds nothing to recover.
    pub empty: bool,
}

/// Recovers a session's sculpt to its last complete stroke: the newest snapshot that reads
/// whole, then the journal records that follow it (see the module docs of `io`).
pub fn recover(dir: &Path) -> Result<Recovered, RecoveryError> {
    let fail = |reason: String| RecoveryError { dir: dir.to_path_buf(), reason, empty: false };
    let mut problems = Vec::new();
    let mut base = None;
    for (n, path) in numbered(dir, "snapshot-", ".argile").into_iter().rev() {
        let read = std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()));
        match read
            .and_then(|b| decode(&b, &path.display().to_string(), &mut |_| {}).map_err(|e| e.to_string()))
        {
            Ok(sculpt) => {
                base = Some((n, sculpt));
                break;
            }
            Err(e) => problems.push(e),
        }
    }
    let Some((snapshot_strokes, mut sculpt)) = base else {
        let journaled = journaled_strokes(dir);
        if problems.is_empty() && journaled == 0 {
            let reason = "it holds no snapshot and no stroke (the session ended before its first snapshot was written)".into();
            return Err(RecoveryError { empty: true, ..fail(reason) });
        }
        if journaled > 0 {
            problems.push(format!(
                "its journal holds {journaled} stroke(s) but no snapshot reads whole to apply them to; \
                 the folder is kept as it is"
            ));
        }
        return Err(fail(problems.join("; ")));
    };
    let mut strokes = snapshot_strokes;
    let mut discarded = None;
    for (_, path) in numbered(dir, "journal-", ".argj") {
        let bytes = std::fs::read(&path).map_err(|e| fail(format!("cannot read {}: {e}", path.display())))?;
        // A journal that cannot be read is skipped: the next one tells, by its base, whether
        // strokes are missing.
        let mut reader = match Reader::new(&bytes) {
            Ok(r) => r,
            Err(e) => {
                discarded.get_or_insert(format!("{}: {e}", path.display()));
                continue;
            }
        };
        if reader.base() > strokes {
            discarded.get_or_insert(format!(
                "{} starts after stroke {}: strokes {} to {} are missing",
                path.display(),
                reader.base(),
                strokes + 1,
                reader.base()
            ));
            break;
        }
        for record in reader.by_ref() {
            if record.stroke <= strokes {
                continue;
            }
            // A stroke of a part the snapshot does not hold ends what can be recovered.
            if let Some((part, ..)) =
                record.bricks.iter().find(|(p, ..)| usize::from(*p) > sculpt.others.len())
            {
                discarded.get_or_insert(format!(
                    "{}: stroke {} changes part {part}, which its snapshot does not hold",
                    path.display(),
                    record.stroke
                ));
                break;
            }
            // A step on the lattice's part after the snapshot is the lattice applied.
            if sculpt
                .lattice
                .as_ref()
                .is_some_and(|l| record.bricks.iter().any(|(p, ..)| usize::from(*p) == l.part))
            {
                sculpt.lattice = None;
            }
            for (part, key, brick) in record.bricks {
                let field = match part {
                    0 => &mut sculpt.field,
                    p => &mut sculpt.others[usize::from(p) - 1],
                };
                match brick {
                    Some(brick) => field.insert_brick(key, brick),
                    None => field.remove_brick(key),
                }
            }
            strokes = record.stroke;
        }
        if let Some(why) = reader.torn {
            discarded.get_or_insert(format!("{}: {why}", path.display()));
        }
    }
    sculpt.field.take_dirty();
    for field in &mut sculpt.others {
        field.take_dirty();
    }
    Ok(Recovered { sculpt, strokes, snapshot_strokes, discarded })
}

/// How many stroke records the session's journals hold (whole ones).
fn journaled_strokes(dir: &Path) -> usize {
    numbered(dir, "journal-", ".argj")
        .into_iter()
        .filter_map(|(_, path)| std::fs::read(path).ok())
        .map(|bytes| Reader::new(&bytes).map_or(0, |r| r.count()))
        .sum()
}

/// Removes a session folder (once its sculpt is recovered and saved elsewhere).
pub fn remove_session(dir: &Path) -> std::io::Result<()> {
    std::fs::remove_dir_all(dir)
}
