//! Undo and redo, scoped to strokes: copy-on-first-touch per brick, bounded by bytes.
//!
//! ```text
//!  begin_stroke ─► edits: the first touch of a brick copies it (or notes "absent") ─► end_stroke
//!                                                                                      │
//!   undo stack (oldest … newest)  ◄────────────────────────────────────────────────────┘
//!   [disk][disk][mem][mem][mem]          undo: swap each saved brick with the live one,
//!      ▲ spilled when the memory               the live ones become the redo step
//!        budget is exceeded              redo: the same swap back; a new stroke clears redo
//! ```
//!
//! - A step holds, for every brick its stroke touched, the brick as it was before (or that it
//!   was absent). Undo restores exactly those bricks, so undo is bit-exact and costs what the
//!   stroke touched, never the whole field.
//! - The budget counts the bytes of saved bricks in memory (undo and redo steps). Over it, the
//!   oldest undo steps are written to the spill folder (when one is set) and read back when
//!   undo reaches them; over the disk budget, or with no spill folder, the oldest steps are
//!   dropped, and undo stops there.
//! - A spilled step is one file: a header (`ARGH`, version, entry count), the entries (brick
//!   key, flags (bit 0: present, bits 1–3: the level), densities and colours as little-endian `f32`), and a CRC-32 of all
//!   that. A file that does not read back whole and intact is refused with its path.
//! - Edits outside a stroke (building a scene's initial clay) are not journaled.

use std::collections::{HashMap, HashSet, VecDeque};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::brick::{Brick, BrickColours, BrickKey, LevelKey, BRICK_VOLUME, LEVELS};

/// Bytes one brick's samples take written out in full (spill files, sculpt files, the
/// journal): densities and RGBA colours as `f32`. In memory a brick takes
/// [`Brick::heap_bytes`], less when its colours are uniform.
pub const BRICK_BYTES: usize = BRICK_VOLUME * (4 + 16);

/// Bytes the history counts for one saved entry: its key and flag, and the brick's samples.
fn entry_bytes(brick: &Option<Arc<Brick>>) -> usize {
    12 + brick.as_ref().map_or(0, |b| b.heap_bytes())
}

/// Limits and place of the undo history.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HistoryConfig {
    /// Bytes of saved bricks kept in memory (default 256 MiB).
    pub memory_budget_bytes: usize,
    /// Folder for steps spilled out of memory (a session folder is made inside it and removed
    /// when the field is dropped); `None` drops the oldest steps instead.
    pub spill_dir: Option<PathBuf>,
    /// Bytes of spilled steps kept on disk (default 4 GiB); beyond, the oldest are dropped.
    pub disk_budget_bytes: u64,
}

impl Default for HistoryConfig {
    fn default() -> Self {
        Self { memory_budget_bytes: 256 << 20, spill_dir: None, disk_budget_bytes: 4 << 30 }
    }
}

/// A problem with the undo history's spill files; names the file.
#[derive(Debug, thiserror::Error)]
#[error("undo history file {path}: {reason}")]
pub struct HistoryError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong.
    pub reason: String,
}

/// Counts describing the history, for the user interface and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HistoryStats {
    /// Undo steps held in memory.
    pub undo_in_memory: usize,
    /// Undo steps spilled to disk.
    pub undo_on_disk: usize,
    /// Redo steps.
    pub redo: usize,
    /// Bytes of saved bricks in memory.
    pub memory_bytes: usize,
    /// Bytes of spill files on disk.
    pub disk_bytes: u64,
    /// Steps dropped for lack of room (undo cannot reach past them).
    pub dropped: usize,
}

/// The bricks one step saved: each key once, with its content before the step.
#[derive(Debug, Default)]
pub(crate) struct Step {
    pub(crate) bricks: Vec<(LevelKey, Option<Arc<Brick>>)>,
}

impl Step {
    fn bytes(&self) -> usize {
        self.bricks.iter().map(|(_, b)| entry_bytes(b)).sum()
    }
}

enum Stored {
    Memory(Step),
    Disk { path: PathBuf, bytes: u64 },
}

/// The undo/redo journal of one field.
pub(crate) struct History {
    config: HistoryConfig,
    undo: VecDeque<Stored>,
    redo: Vec<Step>,
    open: Option<(Step, HashSet<LevelKey>)>,
    memory_bytes: usize,
    disk_bytes: u64,
    dropped: usize,
    session_dir: Option<PathBuf>,
    next_file: u64,
    /// Bricks changed by closed strokes, undo and redo since the journal last took them.
    changed: HashSet<LevelKey>,
}

impl std::fmt::Debug for History {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("History").field("stats", &self.stats()).finish_non_exhaustive()
    }
}

impl History {
    pub(crate) fn new(config: HistoryConfig) -> Self {
        Self {
            config,
            undo: VecDeque::new(),
            redo: Vec::new(),
            open: None,
            memory_bytes: 0,
            disk_bytes: 0,
            dropped: 0,
            session_dir: None,
            next_file: 0,
            changed: HashSet::new(),
        }
    }

    pub(crate) fn config(&self) -> &HistoryConfig {
        &self.config
    }

    pub(crate) fn stats(&self) -> HistoryStats {
        let on_disk = self.undo.iter().filter(|s| matches!(s, Stored::Disk { .. })).count();
        HistoryStats {
            undo_in_memory: self.undo.len() - on_disk,
            undo_on_disk: on_disk,
            redo: self.redo.len(),
            memory_bytes: self.memory_bytes,
            disk_bytes: self.disk_bytes,
            dropped: self.dropped,
        }
    }

    /// The undo steps held in memory (oldest first; spilled ones are left out) and the redo
    /// steps (the next redo last), sharing their bricks.
    pub(crate) fn in_memory(&self) -> (Vec<&Step>, Vec<&Step>) {
        let undo = self
            .undo
            .iter()
            .filter_map(|s| match s {
                Stored::Memory(step) => Some(step),
                Stored::Disk { .. } => None,
            })
            .collect();
        (undo, self.redo.iter().collect())
    }

    /// Replaces every step (an open stroke is closed first) with `undo` (oldest first) and
    /// `redo` (the next redo last), within the memory budget.
    pub(crate) fn restore(&mut self, undo: Vec<Step>, redo: Vec<Step>) {
        self.end();
        for stored in std::mem::take(&mut self.undo) {
            self.forget(stored);
        }
        for step in std::mem::take(&mut self.redo) {
            self.memory_bytes -= step.bytes();
        }
        self.redo = redo;
        self.memory_bytes += self.redo.iter().map(Step::bytes).sum::<usize>();
        for step in undo {
            self.memory_bytes += step.bytes();
            self.undo.push_back(Stored::Memory(step));
        }
        self.enforce_budget();
    }

    /// Whether a stroke is open.
    pub(crate) fn recording(&self) -> bool {
        self.open.is_some()
    }

    /// Opens a stroke (closing one still open); clears redo.
    pub(crate) fn begin(&mut self) {
        self.end();
        for step in self.redo.drain(..) {
            self.memory_bytes -= step.bytes();
        }
        self.open = Some((Step::default(), HashSet::new()));
    }

    /// Takes the open stroke away unrecorded: its step (each brick it touched as it was before
    /// the stroke), the memory it held given back; the keys it saw come with it.
    pub(crate) fn take_open(&mut self) -> Option<(Step, HashSet<LevelKey>)> {
        let (step, seen) = self.open.take()?;
        self.memory_bytes -= step.bytes();
        Some((step, seen))
    }

    /// Puts back, as the open stroke, what [`History::take_open`] took.
    pub(crate) fn put_open(&mut self, (step, seen): (Step, HashSet<LevelKey>)) {
        self.memory_bytes += step.bytes();
        self.open = Some((step, seen));
    }

    /// Saves `current` as the state of `key` before the open stroke, on its first touch (by
    /// sharing it: the field copies it when it writes).
    pub(crate) fn touch(&mut self, key: LevelKey, current: Option<&Arc<Brick>>) {
        if let Some((step, seen)) = &mut self.open {
            if seen.insert(key) {
                let saved = current.cloned();
                self.memory_bytes += entry_bytes(&saved);
                step.bricks.push((key, saved));
            }
        }
    }

    /// Closes the open stroke; a stroke that touched nothing leaves no step.
    pub(crate) fn end(&mut self) {
        if let Some((step, _)) = self.open.take() {
            if !step.bricks.is_empty() {
                self.changed.extend(step.bricks.iter().map(|(k, _)| *k));
                self.undo.push_back(Stored::Memory(step));
                self.enforce_budget();
            }
        }
    }

    /// The newest undo step, loaded from disk if it was spilled.
    pub(crate) fn pop_undo(&mut self) -> Result<Option<Step>, HistoryError> {
        self.end();
        match self.undo.pop_back() {
            None => Ok(None),
            Some(Stored::Memory(step)) => {
                self.memory_bytes -= step.bytes();
                Ok(Some(step))
            }
            Some(Stored::Disk { path, bytes }) => {
                self.disk_bytes -= bytes;
                let step = read_step(&path);
                let _ = std::fs::remove_file(&path);
                step.map(Some)
            }
        }
    }

    /// Notes that undo or redo replaced the brick at `key`.
    pub(crate) fn note_changed(&mut self, key: LevelKey) {
        self.changed.insert(key);
    }

    /// The keys changed since the last call (see [`History::note_changed`]).
    pub(crate) fn take_changed(&mut self) -> Vec<LevelKey> {
        self.changed.drain().collect()
    }

    pub(crate) fn pop_redo(&mut self) -> Option<Step> {
        self.end();
        let step = self.redo.pop()?;
        self.memory_bytes -= step.bytes();
        Some(step)
    }

    pub(crate) fn push_redo(&mut self, step: Step) {
        self.memory_bytes += step.bytes();
        self.redo.push(step);
    }

    /// Pushes a step undone by redo back on the undo stack (redo does not clear redo).
    pub(crate) fn push_undo(&mut self, step: Step) {
        self.memory_bytes += step.bytes();
        self.undo.push_back(Stored::Memory(step));
        self.enforce_budget();
    }

    /// Spills or drops the oldest in-memory undo steps until memory fits the budget. The
    /// newest step always stays in memory.
    fn enforce_budget(&mut self) {
        while self.memory_bytes > self.config.memory_budget_bytes {
            let newest = self.undo.len().saturating_sub(1);
            let Some(i) = self.undo.iter().take(newest).position(|s| matches!(s, Stored::Memory(_))) else {
                return;
            };
            let Some(Stored::Memory(step)) = self.undo.remove(i) else {
                unreachable!("position found a memory step")
            };
            self.memory_bytes -= step.bytes();
            match self.spill(&step) {
                Ok(Some((path, bytes))) => {
                    self.disk_bytes += bytes;
                    self.undo.insert(i, Stored::Disk { path, bytes });
                    self.enforce_disk_budget();
                }
                Ok(None) => self.drop_oldest_through(i),
                Err(e) => {
                    tracing::warn!("{e}; the oldest undo step is dropped instead");
                    self.drop_oldest_through(i);
                }
            }
        }
    }

    /// Drops the steps older than position `i` and the one at `i` (already removed): undo
    /// cannot step over a missing step.
    fn drop_oldest_through(&mut self, i: usize) {
        let older: Vec<Stored> = self.undo.drain(..i).collect();
        for stored in older {
            self.forget(stored);
        }
        self.dropped += i + 1;
    }

    fn forget(&mut self, stored: Stored) {
        match stored {
            Stored::Memory(step) => self.memory_bytes -= step.bytes(),
            Stored::Disk { path, bytes } => {
                self.disk_bytes -= bytes;
                let _ = std::fs::remove_file(path);
            }
        }
    }

    fn enforce_disk_budget(&mut self) {
        while self.disk_bytes > self.config.disk_budget_bytes {
            let Some(oldest) = self.undo.pop_front() else { return };
            self.forget(oldest);
            self.dropped += 1;
        }
    }

    /// Writes a step to a new file in the session folder; `None` when no spill folder is set.
    fn spill(&mut self, step: &Step) -> Result<Option<(PathBuf, u64)>, HistoryError> {
        let Some(root) = &self.config.spill_dir else { return Ok(None) };
        let dir = match &self.session_dir {
            Some(d) => d.clone(),
            None => {
                let nanos = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_nanos());
                let d = root.join(format!("history-{}-{nanos}", std::process::id()));
                std::fs::create_dir_all(&d).map_err(|e| HistoryError {
                    path: d.clone(),
                    reason: format!("cannot create the folder: {e}"),
                })?;
                self.session_dir = Some(d.clone());
                d
            }
        };
        let path = dir.join(format!("step-{:08}.bin", self.next_file));
        self.next_file += 1;
        let bytes = encode_step(step);
        let fail =
            |e: std::io::Error| HistoryError { path: path.clone(), reason: format!("cannot write it: {e}") };
        let mut file = std::fs::File::create(&path).map_err(fail)?;
        file.write_all(&bytes).map_err(fail)?;
        Ok(Some((path, bytes.len() as u64)))
    }
}

impl Drop for History {
    fn drop(&mut self) {
        if let Some(dir) = &self.session_dir {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

const MAGIC: &[u8; 4] = b"ARGH";
const VERSION: u32 = 2;

fn encode_step(step: &Step) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + step.bricks.len() * (13 + BRICK_BYTES) + 4);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(step.bricks.len() as u64).to_le_bytes());
    for (key, brick) in &step.bricks {
        for c in key.key.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
        match brick {
            None => out.push(key.level << 1),
            Some(b) => {
                out.push(1 | key.level << 1);
                for d in b.densities() {
                    out.extend_from_slice(&d.to_le_bytes());
                }
                for c in b.colour.iter().flatten() {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
    }
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

fn read_step(path: &Path) -> Result<Step, HistoryError> {
    let fail = |reason: String| HistoryError { path: path.to_path_buf(), reason };
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(|e| fail(format!("cannot read it back: {e}")))?;
    decode_step(&bytes).map_err(fail)
}

/// Reads a spilled step, refusing anything not written whole by [`encode_step`].
fn decode_step(bytes: &[u8]) -> Result<Step, String> {
    if bytes.len() < 20 {
        return Err(format!("{} bytes is too short for a step", bytes.len()));
    }
    let (body, crc) = bytes.split_at(bytes.len() - 4);
    if crc32fast::hash(body) != u32::from_le_bytes(crc.try_into().expect("4 bytes")) {
        return Err("its checksum does not match: the file is damaged".into());
    }
    if &body[..4] != MAGIC {
        return Err("it is not an undo history step".into());
    }
    let version = u32::from_le_bytes(body[4..8].try_into().expect("4 bytes"));
    if version != VERSION {
        return Err(format!("format version {version}, this build reads {VERSION}"));
    }
    let count = u64::from_le_bytes(body[8..16].try_into().expect("8 bytes"));
    // Each entry takes at least 13 bytes: refuse counts the file cannot hold before
    // allocating for them.
    if count > (body.len() as u64 - 16) / 13 {
        return Err(format!("it claims {count} bricks, more than its size can hold"));
    }
    let mut rest = &body[16..];
    let mut take = |n: usize| -> Result<&[u8], String> {
        if rest.len() < n {
            return Err("it ends in the middle of a brick".into());
        }
        let (head, tail) = rest.split_at(n);
        rest = tail;
        Ok(head)
    };
    let f32_at = |b: &[u8], i: usize| f32::from_le_bytes(b[4 * i..4 * i + 4].try_into().expect("4 bytes"));
    let mut step = Step { bricks: Vec::with_capacity(count as usize) };
    let mut seen = HashMap::new();
    for _ in 0..count {
        let k = take(12)?;
        let key = BrickKey::new(
            i32::from_le_bytes(k[0..4].try_into().expect("4 bytes")),
            i32::from_le_bytes(k[4..8].try_into().expect("4 bytes")),
            i32::from_le_bytes(k[8..12].try_into().expect("4 bytes")),
        );
        let flags = take(1)?[0];
        let level = usize::from(flags >> 1);
        if level >= LEVELS {
            return Err(format!("brick {key} has an unknown level {level}"));
        }
        let key = LevelKey::new(level, key);
        if seen.insert(key, ()).is_some() {
            return Err(format!("brick {key} appears twice"));
        }
        let brick = match flags & 1 {
            0 => None,
            _ => {
                let d = take(BRICK_VOLUME * 4)?;
                let c = take(BRICK_VOLUME * 16)?;
                let mut b = Brick::default();
                for i in 0..BRICK_VOLUME {
                    b.set_density(i, f32_at(d, i));
                }
                b.colour = BrickColours::from_samples(|i| std::array::from_fn(|j| f32_at(c, 4 * i + j)));
                Some(Arc::new(b))
            }
        };
        step.bricks.push((key, brick));
    }
    if !rest.is_empty() {
        return Err(format!("{} bytes follow the last brick", rest.len()));
    }
    Ok(step)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::IVec3;

    fn sample_step() -> Step {
        let mut b = Brick::default();
        b.set_density(3, 0.25);
        b.colour[7] = [0.1, 0.2, 0.3, 1.0];
        Step {
            bricks: vec![
                (IVec3::new(-1, 2, 3).into(), Some(Arc::new(b))),
                (LevelKey::new(3, IVec3::new(4, -5, 6)), None),
            ],
        }
    }

    #[test]
    fn a_spilled_step_reads_back_exactly() {
        let step = sample_step();
        let back = decode_step(&encode_step(&step)).unwrap();
        assert_eq!(back.bricks, step.bricks);
    }

    #[test]
    fn every_truncation_and_a_flipped_byte_are_refused() {
        let bytes = encode_step(&sample_step());
        for n in 0..bytes.len() {
            assert!(decode_step(&bytes[..n]).is_err(), "a file cut at {n} bytes is refused");
        }
        for i in (0..bytes.len()).step_by(97) {
            let mut bad = bytes.clone();
            bad[i] ^= 0x10;
            let e = decode_step(&bad).unwrap_err();
            assert!(e.contains("checksum"), "byte {i}: {e}");
        }
    }

    #[test]
    fn absurd_counts_are_refused_before_allocating() {
        let mut body = Vec::new();
        body.extend_from_slice(MAGIC);
        body.extend_from_slice(&VERSION.to_le_bytes());
        body.extend_from_slice(&u64::MAX.to_le_bytes());
        body.extend_from_slice(&[0; 13]);
        let crc = crc32fast::hash(&body);
        body.extend_from_slice(&crc.to_le_bytes());
        let e = decode_step(&body).unwrap_err();
        assert!(e.contains("more than its size can hold"), "{e}");
    }
}
