//! The runtime's outputs: `log.jsonl` (one JSON object a line, each with a `kind`) and the
//! captured layer images, in the folder `ARGILE_XR_TEST_OUT` names.

use serde_json::Value;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Where the runtime writes; without an output folder it writes nothing but still says
/// violations on standard error.
pub struct Log {
    out: Option<PathBuf>,
    file: Option<File>,
}

impl Log {
    /// Opens (appends to) `log.jsonl` in `out`, creating the folder.
    pub fn open(out: Option<PathBuf>) -> Result<Log, String> {
        let file = match &out {
            None => None,
            Some(dir) => {
                std::fs::create_dir_all(dir)
                    .map_err(|e| format!("cannot create the XR test output folder {}: {e}", dir.display()))?;
                let path = dir.join("log.jsonl");
                Some(
                    std::fs::OpenOptions::new()
                        .create(true)
                        .append(true)
                        .open(&path)
                        .map_err(|e| format!("cannot open {}: {e}", path.display()))?,
                )
            }
        };
        Ok(Log { out, file })
    }

    pub fn out_dir(&self) -> Option<&Path> {
        self.out.as_deref()
    }

    /// Appends one line; a line that cannot be written is said on standard error.
    pub fn write(&mut self, line: Value) {
        if let Some(f) = &mut self.file {
            if let Err(e) = writeln!(f, "{line}") {
                eprintln!("argile XR test runtime: cannot write log.jsonl: {e}");
            }
        }
    }

    /// Logs a call the runtime refused as a specification violation, and says it on stderr.
    pub fn violation(&mut self, function: &str, result: &str, why: &str) {
        eprintln!("argile XR test runtime: {function} refused with {result}: {why}");
        self.write(
            serde_json::json!({"kind": "violation", "function": function, "result": result, "why": why}),
        );
    }
}
