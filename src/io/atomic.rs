//! Writing files so that a crash or a full disk never leaves a half-written one in place.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{bail, Context, Result};

/// Writes `path` atomically: into a temporary file beside it, flushed and synced, then renamed
/// over it, then the folder synced. With `overwrite` false an existing file is refused. On any
/// failure the temporary file is removed and `path` is left as it was.
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
