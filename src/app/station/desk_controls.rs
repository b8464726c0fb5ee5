//! The desk's controls, one part of the station: what the keys, the mouse and the 6-DoF
//! devices hold between frames.

use std::collections::HashSet;
use std::sync::Arc;

use winit::keyboard::KeyCode;

use crate::config::{KeyBindings, Modifiers};
use crate::input::clutch::Clutch;
use crate::input::desk::DeskInput;
use crate::input::gamepad::{ContactFeedback, Rumble};
use crate::input::motion::TargetPoses;
use crate::input::mouse::MouseNavigator;
use crate::input::reader::Mailbox;
use crate::math::{Quat, Vec2};

/// The desk's controls: the key bindings and keys held, the mouse and its 3D cursor's clutch,
/// the 6-DoF devices (SpaceMice, gamepads) and their buttons, the pads' rumble.
#[derive(Debug)]
pub(super) struct DeskControls {
    pub(super) bindings: KeyBindings,
    pub(super) mouse: MouseNavigator,
    /// The 6-DoF devices' state (SpaceMice through `mailbox`, gamepads): the desk tool's pose
    /// is its `Target::Tool` pose.
    pub(super) desk: DeskInput,
    pub(super) mailbox: Option<Arc<Mailbox>>,
    /// A device's stroke button is down.
    pub(super) device_apply: bool,
    /// A device's clutch button is down.
    pub(super) device_clutch: bool,
    /// The 3D cursor's clutch (relative) mode, from the first time the clutch is lifted in
    /// cursor mode until the mouse mode changes or the view is reset; absent: the tool is
    /// placed under the pointer.
    pub(super) cursor_clutch: Option<Clutch>,
    /// Where the targets start (and `reset-view` puts them back).
    pub(super) home: TargetPoses,
    /// The trackball's turn for a mouse that drives another target than the scene, world
    /// frame, until the next [`Station::devices`].
    pub(super) mouse_turn: Quat,
    /// Contact feedback for the pads (`None` before the first frame, whose contact is taken
    /// silently: a tool that starts in the clay does not tap), and the rumble it asked for last.
    pub(super) feedback: Option<ContactFeedback>,
    pub(super) rumble: Option<Rumble>,
    pub(super) modifiers: Modifiers,
    pub(super) held: HashSet<KeyCode>,
    /// Where the pointer was last seen, window pixels.
    pub(super) pointer_px: Vec2,
    /// The gamepads connected, by name (the panel lists them).
    pub(super) gamepad_names: Vec<String>,
}
