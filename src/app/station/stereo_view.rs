//! The stereo view, one part of the station: how the pair is seen (the display's calibration,
//! the viewer's head, convergence and interaxial, the parallax budget) and shown (the display
//! mode, its parity and what masks its edges).

use super::Budgeted;
use crate::input::opentrack::OpentrackHead;
use crate::scene::ScreenCalibration;
use crate::stereo::comfort::AutoConvergence;
use crate::stereo::display::{DisplayMode, Parity};
use crate::stereo::floating::FloatingWindow;

/// The stereo view: the display's calibration, the viewer's head, the convergence and the
/// distance between the eyes, the parallax budget, the display mode and what it shows.
#[derive(Debug)]
pub(super) struct StereoView {
    /// The convergence plane's distance as a share of the mouse's viewing distance (the
    /// convergence keys and the panel's slider change it; the view zoom keeps it).
    pub(super) convergence_factor: f32,
    /// The lights turn with the viewer instead of staying with the scene.
    pub(super) lights_follow_viewer: bool,
    /// The display, its screen and the viewer.
    pub(super) calibration: ScreenCalibration,
    /// Where the viewer's head is, for head-tracked views: opentrack, else the scene's
    /// scripted head, else none (the scene's camera rig).
    pub(super) head: Option<OpentrackHead>,
    /// Keeps the desk tool at zero parallax while on.
    pub(super) auto_convergence: Option<AutoConvergence>,
    /// The parallax budget's verdict for what is shown now: what it was judged on, the check
    /// and warning when over budget, and the interaxial it allows in limit mode (of the
    /// head-tracked eyes when the views are head-tracked).
    pub(super) budget: Option<Budgeted>,
    /// The distance between the eyes of head-tracked views, physical metres: the calibrated
    /// viewer's, until the interaxial keys or the budget's limit change it.
    pub(super) tracked_interaxial_m: f32,
    /// Seconds since the views became head-tracked (they ease in from the untracked views).
    pub(super) tracked_for_s: Option<f32>,
    /// Each eye gets the other's image.
    pub(super) swap_eyes: bool,
    /// Whether the floating window masks the pictures' edges, and the strips it masks now
    /// (eased towards the measured ones).
    pub(super) floating_window: (bool, FloatingWindow),
    /// The interlace parity (a frame-sequential display's phase) is the calibration's flipped.
    pub(super) parity_flipped: bool,
    /// Frames the window has shown (a frame-sequential display alternates eyes by it).
    pub(super) frames_shown: u64,
    /// How the window shows the stereo pair.
    pub(super) display_mode: DisplayMode,
    /// Whether the window's surface can show quad-buffer stereo.
    pub(super) quad_buffer: bool,
    /// The window's top-left corner on the screen, pixels (interlace parity follows it).
    pub(super) window_origin: (i32, i32),
}

impl StereoView {
    /// The display mode and, for interlaced modes, the parity in window pixels (the
    /// calibration's parity is the screen's; a window on an odd row or column flips it).
    pub(super) fn display(&self) -> (DisplayMode, Parity) {
        let screen = self.display_phase();
        let parity = match self.display_mode {
            DisplayMode::ColumnInterlaced => screen.for_origin(self.window_origin.0),
            DisplayMode::FrameSequential => screen.for_frame(self.frames_shown),
            _ => screen.for_origin(self.window_origin.1),
        };
        (self.display_mode, parity)
    }

    /// The display's parity in screen rows (columns), or a frame-sequential display's phase:
    /// the calibration's, flipped by P.
    pub(super) fn display_phase(&self) -> Parity {
        match self.parity_flipped {
            true => self.calibration.display.parity.flipped(),
            false => self.calibration.display.parity,
        }
    }
}
