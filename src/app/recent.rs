//! The sculpts saved or opened last, newest first, kept in `recent` in the state folder: one
//! path a line. The list is read once at start and written (atomically) when it changes; a
//! list that cannot be read is empty, one that cannot be written stays in memory, each with a
//! warning that names the file.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::io::text::{read_text, SETTINGS_LIMIT};
use crate::io::write_atomically;

/// The most sculpts the list keeps.
pub const MOST_RECENT: usize = 10;

/// The recent sculpts and the file that keeps them.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RecentSculpts {
    /// Where the list is kept; `None`: in memory only.
    file: Option<PathBuf>,
    list: Vec<PathBuf>,
}

impl RecentSculpts {
    /// The list kept in `recent` in the state folder.
    pub fn in_state_folder() -> Self {
        super::state_dir().map_or_else(Self::default, |d| Self::load(d.join("recent")))
    }

    /// The list kept in `file`: the sculpts it names that are still there.
    pub fn load(file: PathBuf) -> Self {
        let list = match read_text(&file, SETTINGS_LIMIT) {
            Ok(text) => text
                .lines()
                .map(str::trim)
                .filter(|l| !l.is_empty())
                .map(PathBuf::from)
                .filter(|p| p.is_file())
                .take(MOST_RECENT)
                .collect(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
            Err(e) => {
                tracing::warn!("cannot read the recent sculpts from {}: {e}", file.display());
                Vec::new()
            }
        };
        Self { file: Some(file), list }
    }

    /// The sculpts, newest first.
    pub fn list(&self) -> &[PathBuf] {
        &self.list
    }

    /// `path` was saved or opened: it goes first (made whole where it can be), the oldest past
    /// [`MOST_RECENT`] drops off, and the list is written.
    pub fn remember(&mut self, path: &Path) {
        let path = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        self.list.retain(|p| *p != path);
        self.list.insert(0, path);
        self.list.truncate(MOST_RECENT);
        let Some(file) = &self.file else { return };
        let written =
            file.parent().map_or(Ok(()), std::fs::create_dir_all).map_err(anyhow::Error::from).and_then(
                |()| {
                    write_atomically(file, true, |w| {
                        self.list.iter().try_for_each(|p| writeln!(w, "{}", p.display())).map_err(Into::into)
                    })
                },
            );
        if let Err(e) = written {
            tracing::warn!("cannot keep the recent sculpts in {}: {e:#}", file.display());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_newest_goes_first_once_the_list_holds_ten_and_survives_a_restart() {
        let dir = std::env::temp_dir().join(format!("argile-recent-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("state/recent");
        let mut recent = RecentSculpts::load(file.clone());
        assert!(recent.list().is_empty(), "no file yet: an empty list");
        let sculpt = |i: usize| {
            let p = dir.join(format!("s{i}.argile"));
            std::fs::write(&p, b"x").unwrap();
            p
        };
        for i in 0..12 {
            recent.remember(&sculpt(i));
        }
        recent.remember(&sculpt(5));
        let names: Vec<String> =
            recent.list().iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
        assert_eq!(names[..3], ["s5.argile", "s11.argile", "s10.argile"]);
        assert_eq!(names.len(), MOST_RECENT);
        assert_eq!(names.iter().filter(|n| *n == "s5.argile").count(), 1);
        // Read again, less the one removed since.
        std::fs::remove_file(dir.join("s11.argile")).unwrap();
        let again = RecentSculpts::load(file.clone());
        assert_eq!(again.list().len(), MOST_RECENT - 1);
        assert_eq!(again.list()[0], recent.list()[0]);
        // A list that is a folder cannot be read: empty, and remembering does not panic.
        let folder = dir.join("folder");
        std::fs::create_dir_all(&folder).unwrap();
        let mut broken = RecentSculpts::load(folder);
        assert!(broken.list().is_empty());
        broken.remember(&sculpt(1));
        assert_eq!(broken.list().len(), 1, "kept in memory");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
