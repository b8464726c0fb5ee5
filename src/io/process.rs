//! Whether another process is alive, from `/proc`: what autosave and atomic writes need to
//! tell the files of a process that was killed from those of one still writing them.

use std::path::Path;

/// The start time field of `/proc/PID/stat` (after the command name, which may hold spaces)
/// of a live process; `None` for a process that is gone.
pub(crate) fn start_token(pid: u32) -> Option<String> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let mut fields = stat[stat.rfind(')')? + 1..].split_whitespace();
    // Fields after the name start at field 3, the state: a dead process (a zombie not yet
    // reaped) owns nothing. The start time is field 22.
    if matches!(fields.next(), Some("Z" | "X" | "x")) {
        return None;
    }
    fields.nth(18).map(str::to_owned)
}

/// Whether the process `pid` is alive (not a zombie). Where there is no `/proc`, every
/// process counts as alive, so nothing of another process is ever removed.
pub fn process_alive(pid: u32) -> bool {
    !Path::new("/proc/self").exists() || start_token(pid).is_some()
}
