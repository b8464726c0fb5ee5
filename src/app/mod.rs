//! The station: wires scene, field, tools, mesher, stereo rig and renderer together.
//!
//! The only module that knows every other; the CLI in `main.rs` is a thin shell over it.

mod assembly;
mod autosave;
pub mod budget;
mod calibrate;
mod capture;
mod comfort;
mod document;
mod environment;
mod export;
mod frame;
mod glyphs;
mod held_lattice;
mod held_region;
mod monitor;
mod panel_rows;
mod playback;
mod recent;
mod sculpt;
pub mod signals;
mod station;
mod xr_station;

pub use crate::io::write_atomically;
pub use assembly::Assembly;
pub use autosave::{
    autosave_root, close_session, recover_and_report, recover_sessions, recovered_dir,
    remove_stale_spill_folders, start_autosave, RecoveredSculpt, RecoveryCount,
};
pub use calibrate::{
    adjust_calibration, adjusted, calibrate, describe, test_pattern, write_calibration, AdjustOptions,
    Adjustment, CalibrateOptions, Calibrated, Marker, TestPattern,
};
pub use capture::{
    render_scene, render_scene_autosaved, render_sculpt, renderer_for, save_png_atomically, RenderOptions,
    WrittenCapture,
};
pub use comfort::{apply_parallax_budget, judge_parallax_budget, BudgetVerdict};
pub use environment::{load_environment, EnvironmentError};
pub use export::{
    export, export_as, export_surface, final_field, final_mesh, welded_surface, ExportSummary, PartsExport,
};
pub use frame::{build_frame, world_lights};
pub use playback::Playback;
pub use recent::{RecentSculpts, MOST_RECENT};
pub use sculpt::{
    convert_sculpt, describe_sculpt, is_sculpt, load_sculpt, load_sculpt_with_progress, open_sculpt,
    save_scene_sculpt, with_lattice_applied, SavedSculpt, SCULPT_EXTENSION,
};
pub use station::{
    no_display_reason, run_station, AdjustTarget, InputScript, ScriptEvent, Station, StationOptions,
    StationReport, StepTimes, SCRIPTED_STEP_S,
};
pub use xr_station::{
    run_xr, xr_absent, XrReport, XrRunOptions, XrSculptor, BUTTON_PULSE, CONTACT_NS, TOUCH_PULSE,
    WAIT_FOR_RUNTIME_S,
};

use crate::field::HistoryConfig;

/// Where the station keeps its state between runs (undo spill files, recovery journals):
/// `$XDG_STATE_HOME/argile` on Linux (else the platform's local data folder).
pub fn state_dir() -> Option<std::path::PathBuf> {
    dirs::state_dir().or_else(dirs::data_local_dir).map(|d| d.join("argile"))
}

/// The undo history's settings: the default budgets, spilling into the state folder.
pub fn history_config() -> HistoryConfig {
    HistoryConfig { spill_dir: state_dir().map(|d| d.join("undo")), ..HistoryConfig::default() }
}
