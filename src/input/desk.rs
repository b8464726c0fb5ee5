//! The per-frame input step at the desk: drain the SpaceMouse mailbox, calibrate, smooth,
//! integrate every device's motion into the target it drives, and turn buttons into actions.
//!
//! ```text
//!  Mailbox ──drain──► events ──► Connected / Lost / Buttons ──► ActionEvent (stroke, cycle…)
//!                     states ──► apply_calibration ──► One Euro (per device) ─┐
//!  gamepads: GamepadMotion ─────────────────────────────────────────────────────┼─► integrate
//!  mouse: trackball turn of this frame ──────────────────────────────────────────┘   into the
//!                                                                          mapped Target's pose
//! ```
//!
//! Contract: [`DeskInput::update`] never blocks (the mailbox drain gives up if the reader
//! holds the lock) and allocates nothing once warm. A lost SpaceMouse releases its buttons, so
//! a stroke in progress ends with a `Stroke` release in the same frame. `CycleTarget` presses
//! switch the pressing device's target in the [`MappingTable`].

use super::calibration::{apply_calibration, SixDof, SpaceMouseCalibration};
use super::gamepad::GamepadMotion;
use super::motion::{
    integrate, ActionEvent, DeviceClass, InputAction, MappingTable, MotionFrame, Rates, TargetPoses,
};
use super::reader::{DeviceId, Drained, Mailbox, ReaderEvent};
use super::smoothing::{OneEuroFilter, PositionFilter};
use crate::math::Quat;

/// What each SpaceMouse button does, by button index (button 1 first); later buttons do
/// nothing.
pub const SPACEMOUSE_BUTTON_ACTIONS: [InputAction; 2] = [InputAction::Stroke, InputAction::CycleTarget];

/// One frame's inputs besides the mailbox.
#[derive(Clone, Copy, Debug)]
pub struct FrameInput<'a> {
    /// Time of the frame, seconds.
    pub t_s: f64,
    /// Time since the previous frame, seconds.
    pub dt_s: f32,
    /// The viewer's orientation (view to world), for view-relative devices.
    pub view_rotation: Quat,
    /// Every gamepad's motion this frame.
    pub gamepads: &'a [GamepadMotion],
    /// The mouse trackball's turn since the previous frame (identity when still).
    pub mouse_turn: Quat,
}

#[derive(Clone, Debug)]
struct SpaceMouseSlot {
    id: DeviceId,
    /// Its name, for the user.
    name: String,
    translation: OneEuroFilter,
    rotation: OneEuroFilter,
    buttons: u64,
}

/// The desk's input state between frames.
#[derive(Debug)]
pub struct DeskInput {
    /// SpaceMouse calibration.
    pub calibration: SpaceMouseCalibration,
    /// Which device drives which target.
    pub mapping: MappingTable,
    /// Full-deflection speeds.
    pub rates: Rates,
    /// The target poses.
    pub poses: TargetPoses,
    /// Accumulated tool size rate from gamepads (signed fraction of full speed × seconds).
    pub size_change: f32,
    drained: Drained,
    spacemice: Vec<SpaceMouseSlot>,
}

/// Smoothing of a SpaceMouse's calibrated deflection: a cap held still reads steady, a quick
/// push passes (deflection units are fractions of full scale, so the cutoffs are in Hz of a
/// hand's motion, not of metres).
fn deflection_filter() -> OneEuroFilter {
    OneEuroFilter::new(4.0, 2.0, 1.0)
}

impl DeskInput {
    /// A desk with the given calibration and mapping, targets at their defaults.
    pub fn new(calibration: SpaceMouseCalibration, mapping: MappingTable, rates: Rates) -> Self {
        Self {
            calibration,
            mapping,
            rates,
            poses: TargetPoses::default(),
            size_change: 0.0,
            drained: Drained::default(),
            spacemice: Vec::new(),
        }
    }

    /// The SpaceMice known now.
    pub fn spacemice(&self) -> impl Iterator<Item = DeviceId> + '_ {
        self.spacemice.iter().map(|s| s.id)
    }

    /// One frame: drains `mailbox` (if any), then moves the targets; appends actions.
    pub fn update(
        &mut self,
        mailbox: Option<&Mailbox>,
        input: &FrameInput<'_>,
        actions: &mut Vec<ActionEvent>,
    ) {
        let drained = mailbox.is_some_and(|m| m.drain(&mut self.drained));
        if drained {
            for i in 0..self.drained.events.len() {
                let first = actions.len();
                self.on_event(i, actions);
                for &a in &actions[first..] {
                    self.on_action(a);
                }
            }
        }

        let target = self.mapping.target(DeviceClass::SpaceMouse);
        if drained {
            for (id, state) in &self.drained.states {
                let Some(slot) = self.spacemice.iter_mut().find(|s| s.id == *id) else { continue };
                let raw = apply_calibration(state.axes, &self.calibration);
                let smoothed = SixDof {
                    translation: slot.translation.filter(input.t_s, raw.translation),
                    rotation: slot.rotation.filter(input.t_s, raw.rotation),
                };
                let pose = self.poses.get_mut(target);
                *pose = integrate(
                    *pose,
                    smoothed,
                    self.rates,
                    MotionFrame::View,
                    input.view_rotation,
                    input.dt_s,
                );
            }
        }

        let target = self.mapping.target(DeviceClass::Gamepad);
        for g in input.gamepads {
            let pose = self.poses.get_mut(target);
            *pose = integrate(*pose, g.six, self.rates, MotionFrame::View, input.view_rotation, input.dt_s);
            if g.size_rate.is_finite() && input.dt_s.is_finite() && input.dt_s > 0.0 {
                self.size_change += g.size_rate * input.dt_s.min(super::motion::MAX_STEP_S);
            }
        }

        if input.mouse_turn.is_finite() && input.mouse_turn != Quat::IDENTITY {
            let pose = self.poses.get_mut(self.mapping.target(DeviceClass::Mouse));
            pose.rotation = (input.mouse_turn * pose.rotation).normalize();
        }
    }

    fn on_event(&mut self, index: usize, actions: &mut Vec<ActionEvent>) {
        let action_of =
            |bit: u32| SPACEMOUSE_BUTTON_ACTIONS.get(bit as usize).copied().unwrap_or(InputAction::None);
        let push_edges = |bits: u64, pressed: bool, actions: &mut Vec<ActionEvent>| {
            let mut rest = bits;
            while rest != 0 {
                let bit = rest.trailing_zeros();
                rest &= rest - 1;
                let action = action_of(bit);
                if action != InputAction::None {
                    actions.push(ActionEvent { action, pressed, device: DeviceClass::SpaceMouse });
                }
            }
        };
        match &self.drained.events[index] {
            ReaderEvent::Connected { id, info } => {
                if self.spacemice.iter().all(|s| s.id != *id) {
                    self.spacemice.push(SpaceMouseSlot {
                        id: *id,
                        name: info.name.clone(),
                        translation: deflection_filter(),
                        rotation: deflection_filter(),
                        buttons: 0,
                    });
                }
            }
            ReaderEvent::Buttons { id, change, buttons } => {
                if let Some(slot) = self.spacemice.iter_mut().find(|s| s.id == *id) {
                    slot.buttons = *buttons;
                }
                push_edges(change.released, false, actions);
                push_edges(change.pressed, true, actions);
            }
            ReaderEvent::Lost { id, released, .. } => {
                self.spacemice.retain(|s| s.id != *id);
                push_edges(*released, false, actions);
            }
            ReaderEvent::OpenFailed { .. } => {}
        }
    }

    fn on_action(&mut self, action: ActionEvent) {
        if action.action == InputAction::CycleTarget && action.pressed {
            self.mapping.cycle(action.device);
        }
    }

    /// The names of the SpaceMice connected now, in the order they came.
    pub fn spacemouse_names(&self) -> Vec<String> {
        self.spacemice.iter().map(|s| s.name.clone()).collect()
    }

    /// Applies an action that came from elsewhere (a gamepad, keys) to the desk's own state:
    /// `CycleTarget` switches that device's target.
    pub fn apply_action(&mut self, action: ActionEvent) {
        self.on_action(action);
    }
}
