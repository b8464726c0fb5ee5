//! The sculpt document: the clay and its undo history (through the [`Playback`]), the file it
//! is saved to and what it holds that the file does not, its autosave session. One type, shared
//! by the desk station and the headset, so that both save, open and close the same way: a save
//! that cannot write its file writes to the fallback folder, a lattice held open counts as
//! unsaved work, and a session with unsaved work is left for recovery, never closed.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::held_lattice::HeldLattice;
use super::playback::Playback;
use crate::io::autosave::AutosaveConfig;
use crate::io::{StoredLattice, StoredTool, StoredView};

/// A sculpt being worked on: see the module docs.
#[derive(Debug)]
pub struct Document<'s> {
    /// The clay, its parts, its history and its autosave session.
    pub(super) playback: Playback<'s>,
    save_to: PathBuf,
    saved: Option<PathBuf>,
    /// Strokes (and undos, redos, region moves, applied lattices) since the last save or open.
    unsaved_strokes: u64,
    /// The lattice held open as the last save or open stored it (see [`Document::unsaved_work`]).
    saved_lattice: Option<StoredLattice>,
    /// The sculpt file opened last.
    opened: Option<PathBuf>,
    /// The text of the scene played, stored in the sculpts saved.
    scene_toml: Option<String>,
    /// Where a save that cannot write its file writes instead.
    fallback_dir: Option<PathBuf>,
    /// How autosave starts again on a sculpt opened later, with the scene text its snapshots
    /// carry.
    autosave_restart: Option<(AutosaveConfig, Option<String>)>,
}

/// What a sculpt file opened by [`Document::open`] brings beside its clay.
#[derive(Debug, Default)]
pub struct Opened {
    /// The view it stores, when it was made in the document's scene.
    pub view: Option<StoredView>,
    /// Whether the scene's freeform tools were replaced by those it stores.
    pub tools_restored: bool,
    /// What the user should read (the lattice it left open is open again, or cannot be).
    pub notes: Vec<String>,
    /// The symmetry it was saved with, now in force (none stored in files before version 7:
    /// the one in force stays).
    pub symmetry: Option<crate::parts::Symmetry>,
}

/// Where [`Document::save`] wrote the sculpt.
#[derive(Debug)]
pub struct Saved {
    pub path: PathBuf,
    /// Set when the save file could not be written and the fallback folder took the sculpt:
    /// says why and where (saves go there from then on).
    pub moved: Option<String>,
}

impl<'s> Document<'s> {
    /// The sculpt `playback` holds, saved to `save_to`.
    pub fn new(playback: Playback<'s>, save_to: PathBuf) -> Self {
        Self {
            playback,
            save_to,
            saved: None,
            unsaved_strokes: 0,
            saved_lattice: None,
            opened: None,
            scene_toml: None,
            fallback_dir: None,
            autosave_restart: None,
        }
    }

    /// One more change the file lacks (a stroke, an undo or redo, a region moved, a lattice
    /// applied).
    pub fn edited(&mut self) {
        self.unsaved_strokes += 1;
    }

    /// Journals what the field finished since the last record (a stroke, an undo, a redo, a
    /// region moved), if autosave runs, and counts it as one change the file lacks.
    pub fn journal(&mut self) {
        self.playback.journal();
        self.edited();
    }

    /// The strokes (and undos, redos) since the last save or open.
    pub fn unsaved_strokes(&self) -> u64 {
        self.unsaved_strokes
    }

    /// What the sculpt file lacks: the strokes since the last save or open, and one more for a
    /// lattice held open that is not as the last save stored it (its work is no stroke until it
    /// is applied, and would be lost with the session).
    pub fn unsaved_work(&self) -> u64 {
        let lattice = self.playback.held_lattice().map(HeldLattice::stored);
        self.unsaved_strokes + u64::from(lattice.is_some() && lattice != self.saved_lattice)
    }

    /// What becomes of the unsaved work if another sculpt is opened, as a clause.
    pub fn unsaved_fate(&self) -> &'static str {
        if self.playback.autosave().is_some() {
            "they are kept for recovery at the next start"
        } else {
            "they will be lost"
        }
    }

    /// Where saving writes.
    pub fn save_to(&self) -> &Path {
        &self.save_to
    }

    /// Where the last save wrote, if one did.
    pub fn saved(&self) -> Option<&Path> {
        self.saved.as_deref()
    }

    /// The sculpt file opened last, if any.
    pub fn opened(&self) -> Option<&Path> {
        self.opened.as_deref()
    }

    /// The text of the scene played (a scene file's, or the one a sculpt file stores): saving
    /// stores it with the clay, and a sculpt opened later that was made in it brings back its
    /// freeform tools and its view.
    pub fn set_scene_toml(&mut self, text: Option<String>) {
        self.scene_toml = text;
    }

    /// Where a save that cannot write its file writes the sculpt instead (the stations use
    /// `saved/` in the state folder).
    pub fn set_fallback_dir(&mut self, dir: Option<PathBuf>) {
        self.fallback_dir = dir;
    }

    /// Autosave starts again with `config` on a sculpt opened later; its snapshots carry
    /// `scene_toml`.
    pub fn set_autosave_restart(&mut self, config: AutosaveConfig, scene_toml: Option<String>) {
        self.autosave_restart = Some((config, scene_toml));
    }

    /// Writes the sculpt (with `view`, and a lattice held open as it stands) to the save path,
    /// atomically. Where that fails (a full disk, a folder that cannot be written), nothing
    /// already there is damaged and the sculpt is written to the fallback folder instead, where
    /// saves write from then on ([`Saved::moved`] says so); without one, or when that fails too,
    /// the error says `kept`: where the sculpt is now.
    pub fn save(&mut self, view: Option<&StoredView>, kept: &str) -> Result<Saved> {
        let bytes = super::sculpt::encode_playback(&mut self.playback, self.scene_toml.as_deref(), view);
        let write = |path: &Path| super::sculpt::write_sculpt(&bytes, path);
        let saved = match write(&self.save_to) {
            Ok(()) => Saved { path: self.save_to.clone(), moved: None },
            Err(e) => {
                let Some(dir) = &self.fallback_dir else { return Err(e.context(kept.to_owned())) };
                let stem = self.save_to.file_stem().map_or("sculpt".into(), |s| s.to_string_lossy());
                let stamp = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_secs());
                let other = dir.join(format!("{stem}-{stamp}.{}", super::SCULPT_EXTENSION));
                let written = std::fs::create_dir_all(dir)
                    .with_context(|| format!("cannot create {}", dir.display()))
                    .and_then(|()| write(&other));
                if let Err(again) = written {
                    return Err(e.context(format!(
                        "{kept} (nor could it be saved to {}: {again:#})",
                        other.display()
                    )));
                }
                let moved = format!(
                    "cannot save to {}: {e:#}; saved the sculpt to {} instead, where saving writes from now on",
                    self.save_to.display(),
                    other.display()
                );
                self.save_to = other.clone();
                Saved { path: other, moved: Some(moved) }
            }
        };
        self.written(&saved.path);
        Ok(saved)
    }

    /// Writes the sculpt (as [`Document::save`]) to `path`, where saving writes from then on.
    /// Where `path` cannot be written nothing changes: the error names it, and saving still
    /// writes where it did.
    pub fn save_as(&mut self, path: &Path, view: Option<&StoredView>) -> Result<Saved> {
        let bytes = super::sculpt::encode_playback(&mut self.playback, self.scene_toml.as_deref(), view);
        super::sculpt::write_sculpt(&bytes, path)
            .with_context(|| format!("cannot save the sculpt to {}", path.display()))?;
        self.save_to = path.to_path_buf();
        self.written(path);
        Ok(Saved { path: path.to_path_buf(), moved: None })
    }

    /// The sculpt as it is now is in the file at `path`.
    fn written(&mut self, path: &Path) {
        self.saved = Some(path.to_path_buf());
        self.unsaved_strokes = 0;
        self.saved_lattice = self.playback.held_lattice().map(HeldLattice::stored);
    }

    /// Opens the sculpt file at `path`: its clay and parts replace the document's, saving
    /// writes back to it, and a lattice it left open is open again. When it was made in the
    /// document's scene, its freeform tools replace the scene's and its view is returned. The
    /// autosave session of the clay it replaces is closed, or left for recovery at the next
    /// start when it holds unsaved work; a new one starts on the opened clay. A file that
    /// cannot be read changes nothing, and the error names it.
    pub fn open(&mut self, path: &Path) -> Result<Opened> {
        let sculpt = crate::io::read_file_within(path, &super::budget::sculpt_limit(), &mut |_| {})?;
        let parts = super::assembly::parts_of(&sculpt)
            .with_context(|| format!("{}: a part's layout cannot be placed", path.display()))?;
        let same_scene = sculpt.scene_toml.is_some() && sculpt.scene_toml == self.scene_toml;
        // The tools first: the autosave session started on the new clay stores them.
        let tools: &[StoredTool] = if same_scene { &sculpt.tools } else { &[] };
        let tools_restored = self.playback.restore_tools(tools) > 0;
        let restart = self.autosave_restart.clone();
        let source = path.display().to_string();
        let unsaved = self.unsaved_work();
        let old = self.playback.replace_sculpt(sculpt.field, parts, sculpt.others, |field, tools| {
            restart.and_then(|(config, toml)| {
                super::autosave::start_autosave(field, (toml.as_deref(), tools), &source, config)
            })
        });
        let mut notes = Vec::new();
        if let Some(session) = old {
            if unsaved == 0 {
                if let Err(e) = session.close() {
                    notes.push(format!("{e:#}"));
                }
            }
            // Else dropped unclosed: the next start recovers its work.
        }
        if let Some(stored) = &sculpt.lattice {
            notes.push(match self.playback.reopen_lattice(stored) {
                Ok(()) => "the lattice left open is open again: applying it or putting the clay back \
                           is one undo step"
                    .into(),
                Err(e) => format!("{}: {e}; the clay is as it was before the lattice", path.display()),
            });
        }
        if let Some(symmetry) = sculpt.symmetry {
            self.playback.set_symmetry(symmetry);
        }
        self.save_to = path.to_owned();
        self.opened = Some(path.to_owned());
        self.unsaved_strokes = 0;
        self.saved_lattice = self.playback.held_lattice().map(HeldLattice::stored);
        Ok(Opened {
            view: sculpt.view.filter(|_| same_scene),
            tools_restored,
            notes,
            symmetry: sculpt.symmetry,
        })
    }

    /// Remembers `path` as the sculpt opened last without opening it (one that could not be
    /// read, skipped by the next look for one).
    pub fn skip(&mut self, path: PathBuf) {
        self.opened = Some(path);
    }

    /// Ends the document's autosave session, applying a lattice held open first (its work is
    /// journaled): closed when the document holds no unsaved work, so nothing is recovered at
    /// the next start; else left unclosed for `argile recover`, and its folder returned. `None`
    /// without a session.
    pub fn end_session(&mut self) -> Option<Result<(), PathBuf>> {
        let unsaved = self.unsaved_work();
        let session = self.playback.finish_autosave()?;
        Some(match unsaved {
            0 => {
                super::autosave::close_session(session);
                Ok(())
            }
            _ => Err(session.dir().to_owned()),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    fn bar_scene() -> Scene {
        let text = "[field]\nvoxel_size_m = 0.002\n[[clay]]\nshape = \"box\"\nsize_m = [0.08, 0.02, 0.02]\n";
        Scene::parse(text, "bar", None).unwrap()
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("argile-document-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A document over `scene` with autosave (its sessions under `root`), saved to `save_to`.
    fn autosaved<'s>(scene: &'s Scene, root: &Path, save_to: PathBuf) -> Document<'s> {
        let playback = Playback::new_autosaved(scene, |field, besides| {
            let disk = std::sync::Arc::new(crate::io::autosave::LocalDisk);
            let config = AutosaveConfig::default();
            Some(
                crate::io::autosave::Autosave::start_with_tools(
                    root,
                    field,
                    (None, besides),
                    "t",
                    config,
                    disk,
                )
                .unwrap(),
            )
        })
        .unwrap();
        Document::new(playback, save_to)
    }

    fn open_lattice(doc: &mut Document<'_>) {
        let region = crate::parts::local_bounds(doc.playback.field()).expanded(0.005);
        doc.playback.open_lattice(&crate::lattice::LatticeForm::default().over(region)).unwrap();
        doc.playback.held_lattice_mut().unwrap().add_value(0.3).unwrap();
        doc.playback.sync_lattices();
    }

    #[test]
    fn a_session_with_unsaved_work_is_left_for_recovery_and_a_saved_one_is_closed() {
        let dir = temp_dir("sessions");
        let scene = bar_scene();
        for save in [false, true] {
            let root = dir.join(format!("autosave-{save}"));
            let mut doc = autosaved(&scene, &root, dir.join("bar.argile"));
            doc.edited();
            assert_eq!(doc.unsaved_work(), 1);
            if save {
                doc.save(None, "kept").unwrap();
                assert_eq!(doc.unsaved_work(), 0);
            }
            let session = doc.end_session().expect("a session ran");
            let folders = std::fs::read_dir(&root).unwrap().count();
            match save {
                true => assert!(session.is_ok() && folders == 0, "closed and removed: {session:?}"),
                false => {
                    let kept = session.unwrap_err();
                    assert!(kept.starts_with(&root) && kept.exists(), "left for recovery: {kept:?}");
                }
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_lattice_held_open_is_unsaved_work_until_saved_as_it_stands_then_again_once_changed() {
        let dir = temp_dir("lattice");
        let scene = bar_scene();
        let mut doc = Document::new(Playback::new(&scene), dir.join("bar.argile"));
        open_lattice(&mut doc);
        assert_eq!((doc.unsaved_strokes(), doc.unsaved_work()), (0, 1));
        let saved = doc.save(None, "kept").unwrap();
        assert_eq!((saved.path.as_path(), saved.moved), (dir.join("bar.argile").as_path(), None));
        assert_eq!(doc.unsaved_work(), 0, "the file holds the lattice as it stands");
        doc.playback.held_lattice_mut().unwrap().add_value(0.1).unwrap();
        assert_eq!(doc.unsaved_work(), 1);
        // Opened again, the file gives back the lattice as it was saved, and nothing is unsaved.
        let mut again = Document::new(Playback::new(&scene), dir.join("other.argile"));
        let opened = again.open(&dir.join("bar.argile")).unwrap();
        assert!(again.playback.held_lattice().is_some(), "{:?}", opened.notes);
        assert_eq!((again.unsaved_work(), again.save_to()), (0, dir.join("bar.argile").as_path()));
        assert_eq!(again.opened(), Some(dir.join("bar.argile").as_path()));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_file_that_cannot_be_opened_changes_nothing_and_is_named() {
        let dir = temp_dir("bad-open");
        let scene = bar_scene();
        let mut doc = Document::new(Playback::new(&scene), dir.join("bar.argile"));
        doc.edited();
        let before = doc.playback.field().clone();
        let bad = dir.join("broken.argile");
        std::fs::write(&bad, b"not a sculpt").unwrap();
        let e = format!("{:#}", doc.open(&bad).unwrap_err());
        assert!(e.contains("broken.argile"), "{e}");
        assert!(doc.playback.field().same_samples(&before));
        assert_eq!(
            (doc.unsaved_work(), doc.save_to(), doc.opened()),
            (1, dir.join("bar.argile").as_path(), None)
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
