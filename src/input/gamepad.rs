//! Gamepads over gilrs: sticks and triggers as rate controls for a target (translation,
//! rotation, tool size), buttons as actions, rumble as contact feedback.
//!
//! ```text
//!  gilrs::EventType ──► GamepadMapper::handle ──► source values (sticks, triggers, d-pad)
//!                                            └──► ActionEvent (button → action, from the file)
//!  source values ──► GamepadMapper::motion(calibration) ──► GamepadMotion { SixDof, size rate }
//! ```
//!
//! The mapping is data (`calibration/gamepad.toml`, layered like the SpaceMouse file: a user
//! file names only what it changes; unknown keys are refused with file, line and column).
//! [`GamepadMapper`] is a pure state machine over `gilrs::EventType` values; [`Gamepads`] only
//! drains gilrs' queue into one mapper per pad (tests insert events into that queue).
//! A pad that disconnects releases its held actions, so a stroke in progress ends cleanly.

use std::path::Path;

use gilrs::{Axis, Button, EventType, GamepadId, Gilrs};
use serde::Deserialize;
use toml::Spanned;

use super::calibration::{read_text, CalibrationError, Layer, SixDof};
use super::motion::{ActionEvent, DeviceClass, InputAction};
use crate::math::Vec3;

/// The shipped mapping, embedded in the binary; `calibration/gamepad.toml` documents every key.
pub const SHIPPED_GAMEPAD_TOML: &str = include_str!("../../calibration/gamepad.toml");

/// A value a pad reports, as named in the mapping file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// Left stick, right positive.
    LeftStickX,
    /// Left stick, up positive.
    LeftStickY,
    /// Right stick, right positive.
    RightStickX,
    /// Right stick, up positive.
    RightStickY,
    /// Left analog trigger, 0 to 1.
    LeftTrigger,
    /// Right analog trigger, 0 to 1.
    RightTrigger,
    /// Right trigger minus left trigger.
    Triggers,
    /// D-pad, right positive (−1, 0 or 1).
    DpadX,
    /// D-pad, up positive.
    DpadY,
    /// Drives nothing.
    None,
}

/// Names of the outputs, in [`GamepadCalibration::axes`] order.
pub const GAMEPAD_OUTPUTS: [&str; 7] = ["tx", "ty", "tz", "rx", "ry", "rz", "size"];

/// Names of the mappable buttons, in [`GamepadCalibration::buttons`] order.
pub const GAMEPAD_BUTTONS: [&str; 15] = [
    "south",
    "east",
    "west",
    "north",
    "left_bumper",
    "right_bumper",
    "select",
    "start",
    "mode",
    "left_thumb",
    "right_thumb",
    "dpad_up",
    "dpad_down",
    "dpad_left",
    "dpad_right",
];

const BUTTONS: [Button; 15] = [
    Button::South,
    Button::East,
    Button::West,
    Button::North,
    Button::LeftTrigger,
    Button::RightTrigger,
    Button::Select,
    Button::Start,
    Button::Mode,
    Button::LeftThumb,
    Button::RightThumb,
    Button::DPadUp,
    Button::DPadDown,
    Button::DPadLeft,
    Button::DPadRight,
];

/// How one output is driven.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GamepadAxis {
    /// The source value.
    pub from: Source,
    /// Flip the sign.
    pub invert: bool,
    /// The output's own gain.
    pub sensitivity: f32,
}

/// A validated gamepad mapping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GamepadCalibration {
    /// Fraction of the travel that reads as zero.
    pub dead_zone: f32,
    /// Response curve exponent.
    pub curve_exponent: f32,
    /// Gain of every output.
    pub sensitivity: f32,
    /// `tx ty tz rx ry rz size`, see [`GAMEPAD_OUTPUTS`].
    pub axes: [GamepadAxis; 7],
    /// Action of each button, see [`GAMEPAD_BUTTONS`].
    pub buttons: [InputAction; 15],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GamepadFile {
    dead_zone: Option<Spanned<f32>>,
    curve_exponent: Option<Spanned<f32>>,
    sensitivity: Option<Spanned<f32>>,
    axes: Option<AxesFile>,
    buttons: Option<ButtonsFile>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct AxesFile {
    tx: Option<AxisFile>,
    ty: Option<AxisFile>,
    tz: Option<AxisFile>,
    rx: Option<AxisFile>,
    ry: Option<AxisFile>,
    rz: Option<AxisFile>,
    size: Option<AxisFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AxisFile {
    from: Source,
    #[serde(default)]
    invert: bool,
    sensitivity: Option<Spanned<f32>>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct ButtonsFile {
    south: Option<InputAction>,
    east: Option<InputAction>,
    west: Option<InputAction>,
    north: Option<InputAction>,
    left_bumper: Option<InputAction>,
    right_bumper: Option<InputAction>,
    select: Option<InputAction>,
    start: Option<InputAction>,
    mode: Option<InputAction>,
    left_thumb: Option<InputAction>,
    right_thumb: Option<InputAction>,
    dpad_up: Option<InputAction>,
    dpad_down: Option<InputAction>,
    dpad_left: Option<InputAction>,
    dpad_right: Option<InputAction>,
}

impl GamepadCalibration {
    /// The shipped mapping (`calibration/gamepad.toml`, embedded).
    pub fn shipped() -> Self {
        Self::parse_layer(SHIPPED_GAMEPAD_TOML, "calibration/gamepad.toml", None)
            .expect("the shipped gamepad mapping is valid (tested)")
    }

    /// Loads a mapping file, layered over the shipped defaults.
    pub fn load(path: &Path) -> Result<Self, CalibrationError> {
        let text = read_text(path, "gamepad mapping")?;
        Self::parse_layer(&text, &path.display().to_string(), Some(&Self::shipped()))
    }

    /// Parses mapping text over `base`; without a base every key must be present. `name` is
    /// used in messages.
    pub fn parse_layer(text: &str, name: &str, base: Option<&Self>) -> Result<Self, CalibrationError> {
        let layer = Layer { text, name, what: "mapping" };
        let file: GamepadFile =
            crate::scene::parse_toml(text).map_err(|(span, message)| layer.at(span, message))?;
        let dead_zone = layer.number(file.dead_zone, "dead_zone", 0.0..=0.95, base.map(|b| b.dead_zone))?;
        let curve_exponent =
            layer.number(file.curve_exponent, "curve_exponent", 0.2..=5.0, base.map(|b| b.curve_exponent))?;
        let sensitivity =
            layer.number(file.sensitivity, "sensitivity", 0.0..=100.0, base.map(|b| b.sensitivity))?;

        let a = file.axes.unwrap_or_default();
        let given = [a.tx, a.ty, a.tz, a.rx, a.ry, a.rz, a.size];
        let mut axes = [GamepadAxis { from: Source::None, invert: false, sensitivity: 1.0 }; 7];
        for (i, entry) in given.into_iter().enumerate() {
            let out = GAMEPAD_OUTPUTS[i];
            axes[i] = match entry {
                Some(e) => GamepadAxis {
                    from: e.from,
                    invert: e.invert,
                    sensitivity: layer.number(
                        e.sensitivity,
                        &format!("axes.{out}.sensitivity"),
                        0.0..=100.0,
                        Some(1.0),
                    )?,
                },
                None => base.map(|b| b.axes[i]).ok_or_else(|| layer.missing(&format!("axes.{out}")))?,
            };
        }

        let b = file.buttons.unwrap_or_default();
        let given = [
            b.south,
            b.east,
            b.west,
            b.north,
            b.left_bumper,
            b.right_bumper,
            b.select,
            b.start,
            b.mode,
            b.left_thumb,
            b.right_thumb,
            b.dpad_up,
            b.dpad_down,
            b.dpad_left,
            b.dpad_right,
        ];
        let mut buttons = [InputAction::None; 15];
        for (i, entry) in given.into_iter().enumerate() {
            buttons[i] = match entry {
                Some(action) => action,
                None => base
                    .map(|b| b.buttons[i])
                    .ok_or_else(|| layer.missing(&format!("buttons.{}", GAMEPAD_BUTTONS[i])))?,
            };
        }
        Ok(Self { dead_zone, curve_exponent, sensitivity, axes, buttons })
    }

    /// The action bound to `button`, if it is mappable.
    pub fn action(&self, button: Button) -> Option<InputAction> {
        BUTTONS.iter().position(|&b| b == button).map(|i| self.buttons[i])
    }
}

/// What a pad's sticks and triggers ask for this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GamepadMotion {
    /// Translation and rotation rates (view frame), as a SpaceMouse's [`SixDof`].
    pub six: SixDof,
    /// Tool size rate: a signed fraction of full speed.
    pub size_rate: f32,
}

/// The pure gamepad mapping: folds gilrs events into source values and actions.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GamepadMapper {
    /// Source values, indexed like [`Source`] up to `DpadY` (`Triggers` is derived).
    values: [f32; 9],
    dpad: [bool; 4],
    held: u32,
    /// Events ignored as not mappable or out of range.
    pub ignored_events: u64,
}

const LSX: usize = 0;
const LSY: usize = 1;
const RSX: usize = 2;
const RSY: usize = 3;
const LT: usize = 4;
const RT: usize = 5;
const DX: usize = 7;
const DY: usize = 8;

impl GamepadMapper {
    /// Folds one event in, appending the actions it causes to `actions`.
    pub fn handle(
        &mut self,
        event: &EventType,
        calibration: &GamepadCalibration,
        actions: &mut Vec<ActionEvent>,
    ) {
        match *event {
            EventType::AxisChanged(axis, value, _) => {
                if !value.is_finite() {
                    self.ignored_events += 1;
                    return;
                }
                let value = value.clamp(-1.0, 1.0);
                let slot = match axis {
                    Axis::LeftStickX => LSX,
                    Axis::LeftStickY => LSY,
                    Axis::RightStickX => RSX,
                    Axis::RightStickY => RSY,
                    // Pads that report triggers as axes.
                    Axis::LeftZ => LT,
                    Axis::RightZ => RT,
                    Axis::DPadX => DX,
                    Axis::DPadY => DY,
                    Axis::Unknown => {
                        self.ignored_events += 1;
                        return;
                    }
                };
                self.values[slot] = if slot == LT || slot == RT { value.max(0.0) } else { value };
            }
            EventType::ButtonChanged(button, value, _) => {
                let slot = match button {
                    Button::LeftTrigger2 => LT,
                    Button::RightTrigger2 => RT,
                    // Digital buttons report their value too; their press/release is what counts.
                    _ => return,
                };
                if value.is_finite() {
                    self.values[slot] = value.clamp(0.0, 1.0);
                } else {
                    self.ignored_events += 1;
                }
            }
            EventType::ButtonPressed(button, _) => self.button(button, true, calibration, actions),
            EventType::ButtonReleased(button, _) => self.button(button, false, calibration, actions),
            EventType::Disconnected => self.release_all(calibration, actions),
            // Connection, repeats, dropped and effect events carry no control value.
            _ => {}
        }
    }

    fn button(
        &mut self,
        button: Button,
        down: bool,
        calibration: &GamepadCalibration,
        actions: &mut Vec<ActionEvent>,
    ) {
        if let Some(d) = [Button::DPadUp, Button::DPadDown, Button::DPadLeft, Button::DPadRight]
            .iter()
            .position(|&b| b == button)
        {
            self.dpad[d] = down;
            let v = |on: bool| if on { 1.0 } else { 0.0 };
            self.values[DY] = v(self.dpad[0]) - v(self.dpad[1]);
            self.values[DX] = v(self.dpad[3]) - v(self.dpad[2]);
        }
        let Some(index) = BUTTONS.iter().position(|&b| b == button) else {
            self.ignored_events += 1;
            return;
        };
        let bit = 1u32 << index;
        // Only edges count: a repeated press or a release without a press does nothing.
        if down == (self.held & bit != 0) {
            return;
        }
        self.held ^= bit;
        let action = calibration.buttons[index];
        if action != InputAction::None {
            actions.push(ActionEvent { action, pressed: down, device: DeviceClass::Gamepad });
        }
    }

    /// Releases every held button and centres every control (the pad went away).
    pub fn release_all(&mut self, calibration: &GamepadCalibration, actions: &mut Vec<ActionEvent>) {
        for (index, &action) in calibration.buttons.iter().enumerate() {
            if self.held & (1 << index) != 0 && action != InputAction::None {
                actions.push(ActionEvent { action, pressed: false, device: DeviceClass::Gamepad });
            }
        }
        *self = Self { ignored_events: self.ignored_events, ..Self::default() };
    }

    /// Sets a control directly, as a replay or a scripted pad does (`Triggers` and `None`
    /// cannot be set: the first is derived, the second is nothing). Values are clamped to the
    /// control's range; a value that is not finite is ignored.
    pub fn set_value(&mut self, source: Source, value: f32) {
        if !value.is_finite() {
            return;
        }
        let (slot, low) = match source {
            Source::LeftStickX => (LSX, -1.0),
            Source::LeftStickY => (LSY, -1.0),
            Source::RightStickX => (RSX, -1.0),
            Source::RightStickY => (RSY, -1.0),
            Source::LeftTrigger => (LT, 0.0),
            Source::RightTrigger => (RT, 0.0),
            Source::DpadX => (DX, -1.0),
            Source::DpadY => (DY, -1.0),
            Source::Triggers | Source::None => return,
        };
        self.values[slot] = value.clamp(low, 1.0);
    }

    /// The value of a source now.
    pub fn value(&self, source: Source) -> f32 {
        match source {
            Source::LeftStickX => self.values[LSX],
            Source::LeftStickY => self.values[LSY],
            Source::RightStickX => self.values[RSX],
            Source::RightStickY => self.values[RSY],
            Source::LeftTrigger => self.values[LT],
            Source::RightTrigger => self.values[RT],
            Source::Triggers => self.values[RT] - self.values[LT],
            Source::DpadX => self.values[DX],
            Source::DpadY => self.values[DY],
            Source::None => 0.0,
        }
    }

    /// The motion the controls ask for, through the calibration's dead zone, curve and gains.
    pub fn motion(&self, calibration: &GamepadCalibration) -> GamepadMotion {
        let mut out = [0.0f32; 7];
        for (o, axis) in out.iter_mut().zip(&calibration.axes) {
            let v = self.value(axis.from).clamp(-1.0, 1.0);
            let dz = calibration.dead_zone;
            let m = if v.abs() <= dz { 0.0 } else { (v.abs() - dz) / (1.0 - dz) };
            let shaped = m.powf(calibration.curve_exponent) * calibration.sensitivity * axis.sensitivity;
            let signed = shaped.copysign(v);
            *o = if axis.invert { -signed } else { signed };
            if m == 0.0 {
                *o = 0.0;
            }
        }
        GamepadMotion {
            six: SixDof {
                translation: Vec3::new(out[0], out[1], out[2]),
                rotation: Vec3::new(out[3], out[4], out[5]),
            },
            size_rate: out[6],
        }
    }
}

/// What the tool a pad drives is doing to the clay this frame, as the station samples it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Contact {
    /// Whether the tool touches the clay (the density somewhere in it reaches the iso-level).
    pub touching: bool,
    /// Mean density under the tool, 0 (air) to 1 (full clay).
    pub density: f32,
    /// Whether the tool is acting on the clay (a stroke is in progress).
    pub stroking: bool,
}

/// A rumble to play on a pad: the strong (low-frequency) and weak (high-frequency) motors'
/// magnitudes, 0 to 1, for `duration_ms`. Zero magnitudes stop the pad's rumble.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rumble {
    /// Strong motor, 0 to 1.
    pub strong: f32,
    /// Weak motor, 0 to 1.
    pub weak: f32,
    /// How long it plays, milliseconds.
    pub duration_ms: u32,
}

impl Rumble {
    /// Stops the rumble.
    pub const STOP: Rumble = Rumble { strong: 0.0, weak: 0.0, duration_ms: 0 };

    /// Whether this stops the rumble rather than playing one.
    pub fn is_stop(&self) -> bool {
        self.strong <= 0.0 && self.weak <= 0.0
    }
}

/// Contact feedback: which rumble to start, frame by frame, from the tool's [`Contact`].
///
/// ```text
///  touch onset (not touching → touching) ──► a tap: strong 0.6, weak 0.3, 40 ms
///  touching and stroking ──► strength s = 0.15 + 0.85 · density (density under the tool):
///                            strong s, weak s/2, 120 ms; started again when s changes by a
///                            sixteenth or every 80 ms, so it never lapses mid-stroke
///  stroke or contact ends while the stroke rumble plays ──► STOP
/// ```
///
/// A pure state machine (no device): [`ContactFeedback::update`] returns the effect to start,
/// if any; the station plays it on every pad that drives the tool and has force feedback.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactFeedback {
    touching: bool,
    /// The stroke rumble's level (sixteenths) and the seconds since it was started.
    holding: Option<(u8, f32)>,
}

impl ContactFeedback {
    /// The tap at touch onset.
    pub const TAP: Rumble = Rumble { strong: 0.6, weak: 0.3, duration_ms: 40 };
    /// How long a stroke rumble plays if not started again.
    pub const HOLD_MS: u32 = 120;
    /// A stroke rumble is started again at least this often, seconds.
    pub const REFRESH_S: f32 = 0.08;

    /// The strength of the stroke rumble at `density` under the tool (0 to 1, clamped): light
    /// contact is felt, full clay is full strength.
    pub fn stroke_strength(density: f32) -> f32 {
        let d = if density.is_finite() { density.clamp(0.0, 1.0) } else { 0.0 };
        0.15 + 0.85 * d
    }

    /// One frame `dt_s` long with `contact`: the rumble to start now, if any.
    pub fn update(&mut self, contact: Contact, dt_s: f32) -> Option<Rumble> {
        let dt_s = if dt_s.is_finite() { dt_s.max(0.0) } else { 0.0 };
        let onset = contact.touching && !self.touching;
        self.touching = contact.touching;
        if !(contact.touching && contact.stroking) {
            let was_holding = self.holding.take().is_some();
            return if onset { Some(Self::TAP) } else { was_holding.then_some(Rumble::STOP) };
        }
        let strength = Self::stroke_strength(contact.density);
        let level = (strength * 16.0).round() as u8;
        let due = match &mut self.holding {
            Some((held, since)) => {
                *since += dt_s;
                *held != level || *since >= Self::REFRESH_S
            }
            None => true,
        };
        if onset {
            // The tap first; the stroke rumble starts on the next frame.
            self.holding = None;
            return Some(Self::TAP);
        }
        if !due {
            return None;
        }
        self.holding = Some((level, 0.0));
        Some(Rumble { strong: strength, weak: strength * 0.5, duration_ms: Self::HOLD_MS })
    }
}

/// Every connected gamepad, through gilrs.
pub struct Gamepads {
    gilrs: Gilrs,
    calibration: GamepadCalibration,
    pads: Vec<(GamepadId, GamepadMapper)>,
    /// The last rumble of each pad: gilrs stops an effect when it is dropped.
    effects: Vec<(GamepadId, gilrs::ff::Effect)>,
}

impl std::fmt::Debug for Gamepads {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gamepads").field("pads", &self.pads).finish_non_exhaustive()
    }
}

impl Gamepads {
    /// Opens gilrs. Where the platform has no gamepad support, gilrs still gives a context
    /// that sees no pad; that is used.
    pub fn new(calibration: GamepadCalibration) -> Result<Self, String> {
        let gilrs = match gilrs::GilrsBuilder::new().build() {
            Ok(g) => g,
            Err(gilrs::Error::NotImplemented(g)) => g,
            Err(e) => return Err(format!("cannot open the gamepad library: {e}")),
        };
        Ok(Self::with_gilrs(gilrs, calibration))
    }

    /// Wraps an existing gilrs context.
    pub fn with_gilrs(gilrs: Gilrs, calibration: GamepadCalibration) -> Self {
        Self { gilrs, calibration, pads: Vec::new(), effects: Vec::new() }
    }

    /// The gilrs context (to insert events, or to list pads).
    pub fn gilrs_mut(&mut self) -> &mut Gilrs {
        &mut self.gilrs
    }

    /// Drains gilrs' queue into the pads' mappers; appends the actions caused.
    pub fn poll(&mut self, actions: &mut Vec<ActionEvent>) {
        while let Some(event) = self.gilrs.next_event() {
            let index = match self.pads.iter().position(|(id, _)| *id == event.id) {
                Some(i) => i,
                None => {
                    self.pads.push((event.id, GamepadMapper::default()));
                    self.pads.len() - 1
                }
            };
            self.pads[index].1.handle(&event.event, &self.calibration, actions);
            if event.event == EventType::Disconnected {
                self.pads.swap_remove(index);
                self.effects.retain(|(id, _)| *id != event.id);
            }
        }
    }

    /// The motion of every pad that has sent events.
    pub fn motions(&self) -> impl Iterator<Item = (GamepadId, GamepadMotion)> + '_ {
        self.pads.iter().map(|(id, m)| (*id, m.motion(&self.calibration)))
    }

    /// The mapper of pad `id`.
    pub fn mapper(&self, id: GamepadId) -> Option<&GamepadMapper> {
        self.pads.iter().find(|(p, _)| *p == id).map(|(_, m)| m)
    }

    /// The names of the pads that have sent events, as their drivers give them.
    pub fn names(&self) -> Vec<String> {
        self.pads.iter().map(|(id, _)| self.gilrs.gamepad(*id).name().to_owned()).collect()
    }

    /// The pads that have sent events (connected ones).
    pub fn pad_ids(&self) -> impl Iterator<Item = GamepadId> + '_ {
        self.pads.iter().map(|(id, _)| *id)
    }

    /// Plays `rumble` on pad `id` as contact feedback (see [`ContactFeedback`]); a stop
    /// rumble ends the pad's effect. Returns whether an effect was started: `false`, doing
    /// nothing, when the pad is not connected or has no force feedback, or for a stop.
    pub fn play(&mut self, id: GamepadId, rumble: Rumble) -> bool {
        use gilrs::ff::{BaseEffect, BaseEffectType, EffectBuilder, Repeat, Replay, Ticks};
        if rumble.is_stop() || !(rumble.strong.is_finite() && rumble.weak.is_finite()) {
            // gilrs stops an effect when it is dropped.
            self.effects.retain(|(p, _)| *p != id);
            return false;
        }
        let supported = self.gilrs.connected_gamepad(id).is_some_and(|p| p.is_ff_supported());
        if !supported {
            return false;
        }
        let ticks = Ticks::from_ms(rumble.duration_ms);
        let magnitude = |v: f32| (v.clamp(0.0, 1.0) * f32::from(u16::MAX)) as u16;
        let scheduling = Replay { play_for: ticks, ..Default::default() };
        let effect = EffectBuilder::new()
            .add_effect(BaseEffect {
                kind: BaseEffectType::Strong { magnitude: magnitude(rumble.strong) },
                scheduling,
                envelope: Default::default(),
            })
            .add_effect(BaseEffect {
                kind: BaseEffectType::Weak { magnitude: magnitude(rumble.weak) },
                scheduling,
                envelope: Default::default(),
            })
            .repeat(Repeat::For(ticks))
            .gamepads(&[id])
            .finish(&mut self.gilrs);
        match effect.and_then(|e| e.play().map(|()| e)) {
            Ok(e) => {
                self.effects.retain(|(p, _)| *p != id);
                self.effects.push((id, e));
                true
            }
            Err(e) => {
                tracing::debug!("rumble on gamepad {id} refused: {e}");
                false
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_mapping_is_complete() {
        let c = GamepadCalibration::shipped();
        assert_eq!(c.action(Button::South), Some(InputAction::Stroke));
        assert_eq!(c.action(Button::LeftTrigger2), None, "analog triggers are axes, not actions");
        assert_eq!(c.axes[6].from, Source::DpadY);
        assert!(c.dead_zone > 0.0);
    }

    #[test]
    fn user_files_layer_and_errors_name_the_place() {
        let base = GamepadCalibration::shipped();
        let c = GamepadCalibration::parse_layer(
            "dead_zone = 0.3\n[buttons]\nsouth = \"clutch\"\n",
            "mine.toml",
            Some(&base),
        )
        .unwrap();
        assert_eq!(c.dead_zone, 0.3);
        assert_eq!(c.action(Button::South), Some(InputAction::Clutch));
        assert_eq!(c.action(Button::East), base.action(Button::East));

        let err = |text: &str| {
            GamepadCalibration::parse_layer(text, "mine.toml", Some(&base)).unwrap_err().to_string()
        };
        let e = err("dead_zone = 0.1\n[axes]\ntx = { from = \"left_stik_x\" }\n");
        assert!(e.starts_with("mine.toml:3:15:") && e.contains("left_stik_x"), "{e}");
        let e = err("[buttons]\nsouth = \"stroke\"\nsouht = \"undo\"\n");
        assert!(e.starts_with("mine.toml:3:1:") && e.contains("souht"), "{e}");
        let e = err("curve_exponent = 9.0\n");
        assert!(e.starts_with("mine.toml:1:18:") && e.contains("between 0.2 and 5"), "{e}");
        let e =
            GamepadCalibration::parse_layer("dead_zone = 0.1\n", "alone.toml", None).unwrap_err().to_string();
        assert!(e.contains("curve_exponent") && e.contains("missing"), "{e}");
    }

    #[test]
    fn contact_feedback_taps_on_touch_follows_density_while_stroking_and_stops() {
        let mut f = ContactFeedback::default();
        let air = Contact { touching: false, density: 0.0, stroking: false };
        let dt = 1.0 / 60.0;
        assert_eq!(f.update(air, dt), None, "nothing in the air");
        let touch = Contact { touching: true, density: 0.3, stroking: false };
        assert_eq!(f.update(touch, dt), Some(ContactFeedback::TAP), "a tap at contact");
        assert_eq!(f.update(touch, dt), None, "resting in contact without a stroke: quiet");
        let stroke = |density: f32| Contact { touching: true, density, stroking: true };
        let first = f.update(stroke(0.3), dt).unwrap();
        assert!((first.strong - ContactFeedback::stroke_strength(0.3)).abs() < 1e-6);
        assert_eq!(first.duration_ms, ContactFeedback::HOLD_MS);
        assert_eq!(f.update(stroke(0.3), dt), None, "same density, not yet due");
        let deeper = f.update(stroke(0.9), dt).unwrap();
        assert!(deeper.strong > first.strong && deeper.weak > first.weak, "deeper clay, stronger");
        // Held at one density, it is started again before it lapses.
        let mut again = 0;
        for _ in 0..30 {
            again += usize::from(f.update(stroke(0.9), dt).is_some());
        }
        assert!((5..=7).contains(&again), "every 80 ms over half a second: {again}");
        assert!(ContactFeedback::REFRESH_S * 1000.0 < ContactFeedback::HOLD_MS as f32);
        assert_eq!(f.update(touch, dt), Some(Rumble::STOP), "the stroke ends: stop");
        assert_eq!(f.update(air, dt), None);
        // Touching while already stroking (the button held in the air): the tap first.
        assert_eq!(f.update(Contact { touching: false, density: 0.0, stroking: true }, dt), None);
        assert_eq!(f.update(stroke(0.5), dt), Some(ContactFeedback::TAP));
        assert!(f.update(stroke(0.5), dt).is_some_and(|r| !r.is_stop()));
        assert_eq!(f.update(air, dt), Some(Rumble::STOP));
        assert_eq!(ContactFeedback::stroke_strength(f32::NAN), ContactFeedback::stroke_strength(0.0));
        assert_eq!(ContactFeedback::stroke_strength(7.0), 1.0);
    }
}
