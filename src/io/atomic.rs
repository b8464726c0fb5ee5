//! Writing files so that a crash or a full disk never leaves a half-written one in place.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{bail, Context, Result};

use super::process::process_alive;

/// Removes the temporary files that writes of `name` in `dir` by processes now dead left
/// behind (a process killed while writing), so they never pile up beside the file.
fn remove_stale_temporaries(dir: &Path, name: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let prefix = format!(".{name}.");
    for entry in entries.flatten() {
        let file = entry.file_name();
        let Some(pid) = file
            .to_str()
            .and_then(|f| f.strip_prefix(&prefix))
            .and_then(|rest| rest.strip_suffix(".tmp"))
            .and_then(|pid| pid.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && !process_alive(pid) {
            match std::fs::remove_file(entry.path()) {
                Ok(()) => {
                    tracing::info!("removed {}, left by a write that did not finish", entry.path().display())
                }
                Err(e) => tracing::debug!("cannot remove {}: {e}", entry.path().display()),
            }
        }
    }
}

/// Writes `path` atomically: into a temporary file beside it, flushed and synced, then renamed
/// over it, then the folder synced. With `overwrite` false an existing file is refused. On any
/// failure the temporary file is removed and `path` is left as it was. Temporary files that
/// earlier writes of `path` left when their process was killed are removed first.
pub fn write_atomically(
    path: &Path,
    overwrite: bool,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
) -> Result<()> {
    if !overwrite && path.exists() {
        bail!("{} already exists; pass --force to replace it", path.display());
    }
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("file");
    remove_stale_temporaries(dir, name);
    let temp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let file = File::create(&temp).with_context(|| format!("cannot create {}", temp.display()))?;
        let mut writer = BufWriter::new(file);
        write(&mut writer)?;
        writer.flush().with_context(|| format!("cannot write {}", temp.display()))?;
        let file = writer
            .into_inner()
            .map_err(|e| e.into_error())
            .with_context(|| format!("cannot write {}", temp.display()))?;
        file.sync_all().with_context(|| format!("cannot flush {} to disk", temp.display()))?;
        std::fs::rename(&temp, path)
            .with_context(|| format!("cannot move {} to {}", temp.display(), path.display()))?;
        // Make the rename itself durable; folders cannot be synced on every platform.
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("argile-files-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = temp_dir("fail");
        let path = dir.join("a.txt");
        std::fs::write(&path, "good").unwrap();
        let e = write_atomically(&path, true, |w| {
            w.write_all(b"half")?;
            bail!("the disk is full")
        })
        .unwrap_err();
        assert!(e.to_string().contains("the disk is full"));
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "good");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "no temporary file is left");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn temporaries_of_dead_writers_are_removed_and_those_of_live_ones_kept() {
        let dir = temp_dir("stale");
        let path = dir.join("a.argile");
        // A process that has ended: a child that exited and was waited for.
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        assert!(!process_alive(dead) && process_alive(std::process::id()));
        let stale = dir.join(format!(".a.argile.{dead}.tmp"));
        let live = dir.join(format!(".a.argile.{}.tmp", std::os::unix::process::parent_id()));
        let other = dir.join(format!(".b.argile.{dead}.tmp"));
        for p in [&stale, &live, &other] {
            std::fs::write(p, "half").unwrap();
        }
        write_atomically(&path, true, |w| Ok(w.write_all(b"new")?)).unwrap();
        assert!(!stale.exists(), "the dead writer's temporary is gone");
        assert!(live.exists(), "a live writer's temporary is kept");
        assert!(other.exists(), "another file's temporary is not this write's business");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn existing_files_are_kept_unless_overwriting_is_asked() {
        let dir = temp_dir("exists");
        let path = dir.join("a.txt");
        std::fs::write(&path, "good").unwrap();
        let e = write_atomically(&path, false, |w| Ok(w.write_all(b"new")?)).unwrap_err();
        assert!(e.to_string().contains("already exists; pass --force"), "{e}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "good");
        write_atomically(&path, true, |w| Ok(w.write_all(b"new")?)).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
