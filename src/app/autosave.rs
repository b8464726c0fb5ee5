//! Autosave in the station's state folder, and recovery at start of the sessions that did not
//! close (see [`crate::io::autosave`]).

use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Context, Result};

use super::state_dir;
use crate::field::Field;
use crate::io::autosave::{
    recover, remove_session, unclosed_sessions, Autosave, AutosaveConfig, Besides, LocalDisk,
};
use crate::io::{encode_sculpt, write_atomically, EncodeOptions};

/// The folder autosave sessions live in: `autosave/` in the state folder.
pub fn autosave_root() -> Option<PathBuf> {
    state_dir().map(|d| d.join("autosave"))
}

/// The folder recovered sculpts are saved to: `recovered/` in the state folder.
pub fn recovered_dir() -> Option<PathBuf> {
    state_dir().map(|d| d.join("recovered"))
}

/// Starts autosave of `field` (between strokes) in the state folder. When it cannot start,
/// warns with the reason (naming the folder) and returns `None`: the sculpt stays in memory.
pub fn start_autosave(
    field: &mut Field,
    (scene_toml, besides): (Option<&str>, Besides<'_>),
    source: &str,
    config: AutosaveConfig,
) -> Option<Autosave> {
    let Some(root) = autosave_root() else {
        tracing::warn!("autosave is off: this system names no state folder (set XDG_STATE_HOME)");
        return None;
    };
    match Autosave::start_with_tools(&root, field, (scene_toml, besides), source, config, Arc::new(LocalDisk))
    {
        Ok(a) => {
            tracing::debug!("autosave: session folder {}", a.dir().display());
            Some(a)
        }
        Err(e) => {
            tracing::warn!("{e}; the sculpt stays in memory but is not protected against a crash");
            None
        }
    }
}

/// Closes an autosave session once its sculpt is saved: a failure only warns (naming the
/// folder), since the sculpt is safe; the next start then recovers the session's copy too.
pub fn close_session(session: Autosave) {
    if let Err(e) = session.close() {
        tracing::warn!("{e:#}");
    }
}

/// A sculpt recovered from a session that did not close.
#[derive(Clone, Debug)]
pub struct RecoveredSculpt {
    /// Where the recovered sculpt was saved.
    pub path: PathBuf,
    /// The session's stroke count at the recovered point (its last complete stroke).
    pub strokes: u64,
    /// What the session sculpted.
    pub source: String,
    /// The session's process id.
    pub pid: u32,
    /// Why the journal's end was discarded, if it was.
    pub discarded: Option<String>,
    /// Whether a lattice was held open: the recovered sculpt keeps it open over its clay as it
    /// was when it opened, shaped as it last stood still.
    pub lattice: bool,
}

/// Recovers every session that did not close and whose process is gone, oldest first: each
/// sculpt, to its last complete stroke, is saved (atomically) in [`recovered_dir`], then the
/// session folder is removed. A session that cannot be recovered or saved is left in place and
/// its error returned.
pub fn recover_sessions() -> Vec<Result<RecoveredSculpt>> {
    let (Some(root), Some(out_dir)) = (autosave_root(), recovered_dir()) else { return Vec::new() };
    unclosed_sessions(&root)
        .into_iter()
        .map(|session| -> Result<Option<RecoveredSculpt>> {
            let recovered = match recover(&session.dir) {
                Ok(r) => r,
                Err(e) if e.empty => {
                    // Nothing was sculpted yet when it ended: nothing to save.
                    tracing::info!("{e}; the folder is removed");
                    let _ = remove_session(&session.dir);
                    return Ok(None);
                }
                Err(e) => return Err(e.into()),
            };
            std::fs::create_dir_all(&out_dir)
                .with_context(|| format!("cannot create the folder {}", out_dir.display()))?;
            let name = session.dir.file_name().and_then(|n| n.to_str()).unwrap_or("session");
            let path = out_dir.join(format!("sculpt-{name}.argile"));
            let sculpt = &recovered.sculpt;
            let bytes =
                encode_sculpt(&sculpt.field, sculpt.scene_parts(), EncodeOptions::default(), &mut |_| {});
            write_atomically(&path, true, |w| {
                w.write_all(&bytes).with_context(|| format!("cannot write {}", path.display()))
            })?;
            // The recovered sculpt is safe: the session's files can go.
            if let Err(e) = remove_session(&session.dir) {
                tracing::warn!("cannot remove the recovered session folder {}: {e}", session.dir.display());
            }
            Ok(Some(RecoveredSculpt {
                path,
                strokes: recovered.strokes,
                source: session.info.source,
                pid: session.info.pid,
                discarded: recovered.discarded,
                lattice: recovered.sculpt.lattice.is_some(),
            }))
        })
        .filter_map(Result::transpose)
        .collect()
}

/// What [`recover_and_report`] did.
#[derive(Clone, Debug, Default)]
pub struct RecoveryCount {
    /// Sessions recovered (each saved in the recovered folder).
    pub recovered: usize,
    /// Sessions that could not be recovered or saved (left in place).
    pub failed: usize,
    /// The sculpts recovered, oldest first.
    pub sculpts: Vec<RecoveredSculpt>,
}

impl RecoveredSculpt {
    /// What the recovered sculpt holds, in a few words (for the panel's prompt).
    pub fn described(&self) -> String {
        let lattice = if self.lattice { ", a lattice open" } else { "" };
        format!("{} stroke(s) of {}{lattice}", self.strokes, self.source)
    }
}

/// Removes the undo spill folders (`undo/history-PID-…` in the state folder) of processes
/// that ended without removing them (killed): nothing reads them once their process is gone.
pub fn remove_stale_spill_folders() {
    let Some(undo) = super::state_dir().map(|d| d.join("undo")) else { return };
    let Ok(entries) = std::fs::read_dir(&undo) else { return };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix("history-"))
            .and_then(|rest| rest.split('-').next())
            .and_then(|pid| pid.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && !crate::io::process_alive(pid) {
            match std::fs::remove_dir_all(entry.path()) {
                Ok(()) => tracing::info!(
                    "removed {}, the undo history of a process that was killed",
                    entry.path().display()
                ),
                Err(e) => tracing::warn!("cannot remove {}: {e}", entry.path().display()),
            }
        }
    }
}

/// Recovers the sessions that did not close (see [`recover_sessions`]) and says so on
/// standard output, one sentence per session; removes the undo spill folders of processes
/// that were killed. Returns how many sessions were recovered and how many could not be.
pub fn recover_and_report() -> RecoveryCount {
    remove_stale_spill_folders();
    let mut count = RecoveryCount::default();
    for result in recover_sessions() {
        match result {
            Ok(r) => {
                count.recovered += 1;
                println!(
                    "The session of process {} ({}) did not close cleanly: its sculpt is recovered to its last \
                     completed stroke (stroke {}) in {}",
                    r.pid,
                    r.source,
                    r.strokes,
                    r.path.display()
                );
                if r.lattice {
                    println!(
                        "It held a lattice open: opening {} opens the lattice again as it was last left, over the \
                         clay as it was when the lattice opened",
                        r.path.display()
                    );
                }
                if let Some(why) = &r.discarded {
                    tracing::info!("recovery discarded the stroke cut short by the crash: {why}");
                }
                count.sculpts.push(r);
            }
            Err(e) => {
                count.failed += 1;
                eprintln!("warning: cannot recover an unclosed session: {e:#}");
            }
        }
    }
    count
}
