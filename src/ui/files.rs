//! The panel's file browser: the folders and sculpts (or meshes) of one folder, read with
//! `std::fs` when the folder changes (never each frame), and a name to save or export as. A
//! folder that cannot be read says so in the browser and nothing else happens: the browser
//! can still go up or close.

use std::path::{Path, PathBuf};

use egui::Color32;

use super::{PanelCommand, PanelView};

/// What the browser is open for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileTask {
    /// Open a sculpt.
    Open,
    /// Save the sculpt under a new name.
    SaveAs,
    /// Export the surface as a mesh.
    Export,
}

impl FileTask {
    fn title(self) -> &'static str {
        match self {
            FileTask::Open => "Open a sculpt",
            FileTask::SaveAs => "Save the sculpt as",
            FileTask::Export => "Export the surface as",
        }
    }
}

/// The most entries of a folder listed: a folder of more shows these and says so.
pub const MOST_ENTRIES: usize = 4096;

/// One entry of a listed folder.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Entry {
    name: String,
    dir: bool,
}

/// A folder as listed: its folders then its files of the wanted kind, each sorted by name;
/// whether there were more than [`MOST_ENTRIES`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Listing {
    entries: Vec<Entry>,
    cut: bool,
}

/// The browser's state, kept by the panel between frames.
#[derive(Debug, Default)]
pub(super) struct Browser {
    task: Option<FileTask>,
    pub(super) folder: PathBuf,
    /// The folder's listing, or why it cannot be read.
    pub(super) listing: Option<Result<Listing, String>>,
    /// The file name typed or picked (save as, export).
    pub(super) name: String,
    /// The export format: an index of [`PanelView::export_formats`].
    format: usize,
    /// The name field takes the keyboard at the next frame (the browser just opened).
    focus_name: bool,
}

impl Browser {
    /// What the browser is open for, if it is.
    pub(super) fn task(&self) -> Option<FileTask> {
        self.task
    }

    /// Opens the browser for `task` in `folder` (the sculpt file's folder), the name field
    /// holding `name`.
    fn open(&mut self, task: FileTask, folder: &Path, name: &str, view: &PanelView) {
        self.task = Some(task);
        self.focus_name = task != FileTask::Open;
        self.name = match task {
            FileTask::Open => String::new(),
            FileTask::SaveAs => name.to_owned(),
            FileTask::Export => {
                let stem = Path::new(name).file_stem().map_or("sculpt".into(), |s| s.to_string_lossy());
                let ext = view.export_formats.get(self.format).copied().unwrap_or("obj");
                format!("{stem}.{ext}")
            }
        };
        self.go(folder.to_path_buf(), view);
    }

    /// Lists `folder` for the task.
    fn go(&mut self, folder: PathBuf, view: &PanelView) {
        // Made whole where it can be, so that "up" from a relative folder goes somewhere.
        self.folder = std::fs::canonicalize(&folder).unwrap_or(folder);
        let wanted: Vec<&str> = match self.task {
            Some(FileTask::Export) => view.export_formats.clone(),
            _ => vec![view.sculpt_extension],
        };
        self.listing = Some(list(&self.folder, &wanted));
    }

    /// The browser, in the panel's file section.
    pub(super) fn ui(&mut self, ui: &mut egui::Ui, view: &PanelView, commands: &mut Vec<PanelCommand>) {
        let folder = Path::new(&view.save_to).parent().filter(|p| !p.as_os_str().is_empty());
        let folder = folder.unwrap_or(Path::new(".")).to_path_buf();
        ui.horizontal_wrapped(|ui| {
            let label = match view.unsaved {
                0 => "Save".to_owned(),
                n => format!("Save ({n} unsaved)"),
            };
            if ui.button(label).on_hover_text(&view.save_to).clicked() {
                commands.push(PanelCommand::Save);
            }
            for task in [FileTask::SaveAs, FileTask::Open, FileTask::Export] {
                let label = match task {
                    FileTask::Open => "Open…",
                    FileTask::SaveAs => "Save as…",
                    FileTask::Export => "Export…",
                };
                if ui.selectable_label(self.task == Some(task), label).clicked() {
                    match self.task == Some(task) {
                        true => self.task = None,
                        false => self.open(task, &folder, &view.save_name, view),
                    }
                }
            }
        });
        ui.label(egui::RichText::new(&view.save_name).small()).on_hover_text(&view.save_to);
        if let Some(task) = self.task {
            ui.group(|ui| self.browse(ui, task, view, commands));
        }
        if !view.recent.is_empty() {
            ui.label(egui::RichText::new("recent sculpts").small());
            for path in &view.recent {
                let name = path
                    .file_name()
                    .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into());
                if ui.selectable_label(false, name).on_hover_text(path.display().to_string()).clicked() {
                    commands.push(PanelCommand::Open(path.clone()));
                }
            }
        }
    }

    /// The open browser: the folder, its entries, the name and the button that does the task.
    fn browse(
        &mut self,
        ui: &mut egui::Ui,
        task: FileTask,
        view: &PanelView,
        commands: &mut Vec<PanelCommand>,
    ) {
        ui.label(egui::RichText::new(task.title()).strong());
        ui.horizontal(|ui| {
            let parent = self.folder.parent().map(Path::to_path_buf);
            if ui.add_enabled(parent.is_some(), egui::Button::new("up")).clicked() {
                self.go(parent.unwrap_or_default(), view);
            }
            if ui.button("refresh").clicked() {
                self.go(self.folder.clone(), view);
            }
            if ui.button("close").clicked() {
                self.task = None;
            }
        });
        ui.label(egui::RichText::new(self.folder.display().to_string()).small().monospace());
        let mut picked: Option<Entry> = None;
        match &self.listing {
            Some(Ok(listing)) => {
                egui::ScrollArea::vertical().id_salt("file-browser").max_height(150.0).show(ui, |ui| {
                    if listing.entries.is_empty() {
                        ui.label(egui::RichText::new("nothing to show here").small().weak());
                    }
                    for entry in &listing.entries {
                        let text = match entry.dir {
                            true => format!("{}/", entry.name),
                            false => entry.name.clone(),
                        };
                        if ui.selectable_label(!entry.dir && entry.name == self.name, text).clicked() {
                            picked = Some(entry.clone());
                        }
                    }
                    if listing.cut {
                        ui.label(egui::RichText::new(format!("(the first {MOST_ENTRIES} only)")).small());
                    }
                });
            }
            Some(Err(why)) => {
                ui.label(egui::RichText::new(why).small().color(Color32::from_rgb(240, 90, 70)));
            }
            None => {}
        }
        if let Some(entry) = picked {
            match (entry.dir, task) {
                (true, _) => self.go(self.folder.join(&entry.name), view),
                (false, FileTask::Open) => {
                    commands.push(PanelCommand::Open(self.folder.join(&entry.name)));
                    self.task = None;
                }
                (false, _) => self.name = entry.name,
            }
        }
        if task == FileTask::Open {
            if view.unsaved > 0 {
                let said = format!(
                    "{} unsaved change(s): opening another sculpt leaves them ({})",
                    view.unsaved, view.unsaved_fate
                );
                ui.label(egui::RichText::new(said).small().color(Color32::from_rgb(240, 190, 90)));
            }
            return;
        }
        if task == FileTask::Export {
            ui.horizontal_wrapped(|ui| {
                for (i, ext) in view.export_formats.iter().enumerate() {
                    if ui.radio(self.format == i, *ext).clicked() && self.format != i {
                        self.format = i;
                        self.name = with_extension(&self.name, ext);
                        self.go(self.folder.clone(), view);
                    }
                }
            });
        }
        let field = ui.add(egui::TextEdit::singleline(&mut self.name).hint_text("file name"));
        if std::mem::take(&mut self.focus_name) {
            field.request_focus();
        }
        let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        let ext = match task {
            FileTask::Export => view.export_formats.get(self.format).copied().unwrap_or("obj"),
            _ => view.sculpt_extension,
        };
        let name = with_extension(self.name.trim(), ext);
        let usable = file_name_ok(&name, ext);
        let target = self.folder.join(&name);
        let verb = if task == FileTask::SaveAs { "Save" } else { "Export" };
        let label = match target.exists() {
            true => format!("{verb}, replacing {name}"),
            false => verb.to_owned(),
        };
        let clicked = ui.add_enabled(usable, egui::Button::new(label)).clicked();
        if usable && (clicked || entered) {
            commands.push(match task {
                FileTask::SaveAs => PanelCommand::SaveAs(target),
                _ => PanelCommand::Export(target),
            });
            self.task = None;
        } else if !usable && !self.name.trim().is_empty() {
            let said = "a file name: no folder separators, not only dots";
            ui.label(egui::RichText::new(said).small().weak());
        }
    }
}

/// `name` ending in `.ext` (the extension added if it has another one, or none).
fn with_extension(name: &str, ext: &str) -> String {
    let path = Path::new(name);
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case(ext) => name.to_owned(),
        _ if name.is_empty() => String::new(),
        _ => format!("{}.{ext}", path.file_stem().map_or(name.into(), |s| s.to_string_lossy())),
    }
}

/// Whether `name` names a file ending in `.ext` in the folder: no separator, and more than
/// its extension.
fn file_name_ok(name: &str, ext: &str) -> bool {
    let path = Path::new(name);
    let ends = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case(ext));
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    ends && !stem.is_empty() && !stem.chars().all(|c| c == '.') && !name.contains(['/', '\\', '\0'])
}

/// The folders and the files ending in one of `extensions` in `folder`, hidden ones (a leading
/// dot) left out; an error names the folder.
fn list(folder: &Path, extensions: &[&str]) -> Result<Listing, String> {
    let read =
        std::fs::read_dir(folder).map_err(|e| format!("cannot read the folder {}: {e}", folder.display()))?;
    let mut entries = Vec::new();
    let mut cut = false;
    for entry in read.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        // A link is followed; an entry whose kind cannot be read is left out.
        let Ok(meta) = std::fs::metadata(entry.path()) else { continue };
        let wanted = Path::new(&name)
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| extensions.iter().any(|x| x.eq_ignore_ascii_case(e)));
        if meta.is_dir() || (meta.is_file() && wanted) {
            if entries.len() == MOST_ENTRIES {
                cut = true;
                break;
            }
            entries.push(Entry { name, dir: meta.is_dir() });
        }
    }
    entries.sort_by(|a, b| b.dir.cmp(&a.dir).then_with(|| a.name.to_lowercase().cmp(&b.name.to_lowercase())));
    Ok(Listing { entries, cut })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_lists_its_folders_first_then_its_sculpts_and_an_unreadable_one_says_why() {
        let dir = std::env::temp_dir().join(format!("argile-browser-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for f in ["b.argile", "A.argile", "notes.txt", ".hidden.argile"] {
            std::fs::write(dir.as_path().join(f), b"x").unwrap();
        }
        std::fs::create_dir(dir.as_path().join("zeta")).unwrap();
        let listing = list(dir.as_path(), &["argile"]).unwrap();
        let names: Vec<&str> = listing.entries.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["zeta", "A.argile", "b.argile"]);
        assert!(!listing.cut);
        let gone = dir.as_path().join("gone");
        let e = list(&gone, &["argile"]).unwrap_err();
        assert!(e.contains("cannot read the folder") && e.contains("gone"), "{e}");
        let file = list(&dir.as_path().join("b.argile"), &["argile"]).unwrap_err();
        assert!(file.contains("b.argile"), "{file}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn names_gain_the_extension_and_paths_are_refused() {
        assert_eq!(with_extension("bust", "argile"), "bust.argile");
        assert_eq!(with_extension("bust.ARGILE", "argile"), "bust.ARGILE");
        assert_eq!(with_extension("bust.obj", "ply"), "bust.ply");
        assert_eq!(with_extension("", "ply"), "");
        assert!(file_name_ok("bust.argile", "argile") && file_name_ok("bust.ARGILE", "argile"));
        assert!(!file_name_ok(".argile", "argile"));
        assert!(!file_name_ok("...argile", "argile"));
        assert!(!file_name_ok("../x.argile", "argile"));
        assert!(!file_name_ok("a/b.argile", "argile"));
    }
}
