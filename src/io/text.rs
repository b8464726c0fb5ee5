//! Reading the text files Argile is given (scenes, calibrations, settings, scripts) with the
//! bounds a hostile or mistaken path needs: only regular files (a FIFO would block forever,
//! `/dev/zero` would never end), and no more than a stated size, named in the error.

use std::io::Read;
use std::path::Path;

/// The most bytes a scene or a scripted input may hold.
pub const SCENE_LIMIT: u64 = 16 << 20;
/// The most bytes a calibration, settings or key bindings file may hold.
pub const SETTINGS_LIMIT: u64 = 1 << 20;

/// Checks that `path` names a regular file (following links) before anything opens it, and
/// returns its length. The error says what the path is instead.
pub fn regular_file(path: &Path) -> std::io::Result<u64> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        return Ok(meta.len());
    }
    let what = if meta.is_dir() {
        "a folder"
    } else {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            "a FIFO (named pipe)"
        } else if t.is_char_device() || t.is_block_device() {
            "a device"
        } else if t.is_socket() {
            "a socket"
        } else {
            "not a regular file"
        }
    };
    Err(std::io::Error::new(std::io::ErrorKind::InvalidInput, format!("it is {what}, not a file")))
}

/// Reads the text file `path` of at most `limit` bytes: refuses what is not a regular file,
/// a file over the limit (before reading it, and again if it grows while read) and text that
/// is not UTF-8, each with an error that says so.
pub fn read_text(path: &Path, limit: u64) -> std::io::Result<String> {
    let too_large = |len: u64| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("it is {len} bytes, over the {limit}-byte limit for such a file"),
        )
    };
    let len = regular_file(path)?;
    if len > limit {
        return Err(too_large(len));
    }
    let mut text = String::with_capacity(len as usize);
    std::fs::File::open(path)?.take(limit + 1).read_to_string(&mut text)?;
    if text.len() as u64 > limit {
        return Err(too_large(text.len() as u64));
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_devices_fifos_and_large_files_are_refused_by_name() {
        let dir = std::env::temp_dir().join(format!("argile-text-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let said = |p: &Path, limit| read_text(p, limit).unwrap_err().to_string();
        assert!(said(&dir, 10).contains("it is a folder"), "{}", said(&dir, 10));
        assert!(said(Path::new("/dev/zero"), 10).contains("a device"));
        let fifo = dir.join("fifo");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        // Refused without opening it (opening a FIFO would wait for a writer).
        assert!(said(&fifo, 10).contains("FIFO"));
        let big = dir.join("big.toml");
        std::fs::write(&big, "x".repeat(11)).unwrap();
        assert!(said(&big, 10).contains("11 bytes, over the 10-byte limit"), "{}", said(&big, 10));
        std::fs::write(&big, "[a]\nb = 1\n").unwrap();
        assert_eq!(read_text(&big, 10).unwrap(), "[a]\nb = 1\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
