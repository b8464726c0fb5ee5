//! From calibrated device motion to target poses: which device drives what (the mapping
//! table), and rate control (deflection × speed × time).
//!
//! A SpaceMouse or a gamepad stick is a *rate* device: holding the cap deflected keeps the
//! target moving. [`integrate`] turns a calibrated [`SixDof`] (each component a signed
//! fraction of full deflection, times the calibration's gains) into a pose increment:
//!
//! ```text
//!  translation  Δp = speed_m_s   · dt_s · R_frame · t        (t: SixDof translation)
//!  rotation     Δq = exp(speed_rad_s · dt_s · R_frame · r)   (r: SixDof rotation, an axis·angle rate)
//!  pose         p ← p + Δp,  q ← Δq · q          (View, World: about the target's own position)
//!               q ← q · Δq' with Δq' in the target's frame (Target)
//! ```
//!
//! `R_frame` is the frame the user expects ([`MotionFrame`]): for a SpaceMouse on a desk the
//! view (pushing the cap away moves the tool away from the viewer, whichever way the scene is
//! turned), as 3D applications do.
//!
//! The [`MappingTable`] says which [`Target`] each [`DeviceClass`] drives (Ferley et al. §2:
//! "the mouse rotates the scene while the SpaceMouse controls the tool, or the opposite"). It is
//! plain data: switchable at runtime ([`MappingTable::set`], [`MappingTable::cycle`]) and read
//! from a settings table (`[targets]`, [`MappingTable::parse`]).

use serde::Deserialize;

use super::calibration::{CalibrationError, SixDof};
use crate::math::{Pose, Quat, Vec3};
use crate::scene::line_column;

/// What a device moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Target {
    /// The tool in the dominant hand.
    Tool,
    /// The scene (the clay and its stage), turned and moved as a whole.
    Scene,
    /// The key light.
    Light,
    /// The second tool, for the other hand (a support, or a second brush).
    SecondTool,
    /// The sculpt's active part, moved and turned about its origin.
    Part,
}

impl Target {
    /// Every target, in [`MappingTable::cycle`] order.
    pub const ALL: [Target; 5] =
        [Target::Tool, Target::Scene, Target::Light, Target::SecondTool, Target::Part];

    /// The name used in settings files and messages.
    pub fn name(self) -> &'static str {
        match self {
            Target::Tool => "tool",
            Target::Scene => "scene",
            Target::Light => "light",
            Target::SecondTool => "second_tool",
            Target::Part => "part",
        }
    }

    /// Index into [`Target::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// A family of desktop input devices; each family drives one target.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DeviceClass {
    /// 3Dconnexion six-axis devices, read over HID or through spacenavd.
    SpaceMouse,
    /// Gamepads (gilrs).
    Gamepad,
    /// The system mouse (trackball, drag and wheel, 3D cursor).
    Mouse,
}

impl DeviceClass {
    /// Every class, in table order.
    pub const ALL: [DeviceClass; 3] = [DeviceClass::SpaceMouse, DeviceClass::Gamepad, DeviceClass::Mouse];

    /// The name used in settings files and messages.
    pub fn name(self) -> &'static str {
        match self {
            DeviceClass::SpaceMouse => "spacemouse",
            DeviceClass::Gamepad => "gamepad",
            DeviceClass::Mouse => "mouse",
        }
    }
}

/// Which target each device class drives.
///
/// The default is the desk set-up of Ferley et al.: the SpaceMouse moves the tool, the mouse
/// turns the scene, and a gamepad drives the second tool.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MappingTable {
    targets: [Target; 3],
}

impl Default for MappingTable {
    fn default() -> Self {
        Self { targets: [Target::Tool, Target::SecondTool, Target::Scene] }
    }
}

/// The `[targets]` settings table; every key is optional and unknown keys are refused.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct TargetsFile {
    spacemouse: Option<Target>,
    gamepad: Option<Target>,
    mouse: Option<Target>,
}

impl TargetsFile {
    /// `base` with the targets this table names.
    pub(crate) fn over(&self, base: MappingTable) -> MappingTable {
        let mut out = base;
        for (device, target) in [
            (DeviceClass::SpaceMouse, self.spacemouse),
            (DeviceClass::Gamepad, self.gamepad),
            (DeviceClass::Mouse, self.mouse),
        ] {
            if let Some(t) = target {
                out.set(device, t);
            }
        }
        out
    }
}

impl MappingTable {
    /// The target `device` drives.
    pub fn target(&self, device: DeviceClass) -> Target {
        self.targets[device as usize]
    }

    /// Makes `device` drive `target` (several devices may drive one target; their motions add).
    pub fn set(&mut self, device: DeviceClass, target: Target) {
        self.targets[device as usize] = target;
    }

    /// Switches `device` to the next target in [`Target::ALL`] order; returns it.
    pub fn cycle(&mut self, device: DeviceClass) -> Target {
        let next = Target::ALL[(self.target(device).index() + 1) % Target::ALL.len()];
        self.set(device, next);
        next
    }

    /// The devices driving `target`.
    pub fn devices_driving(&self, target: Target) -> impl Iterator<Item = DeviceClass> + '_ {
        DeviceClass::ALL.into_iter().filter(move |&d| self.target(d) == target)
    }

    /// Reads a `[targets]` table (for example `spacemouse = "scene"`) layered over `self`;
    /// `name` is used in messages, which give line and column.
    pub fn parse(&self, text: &str, name: &str) -> Result<Self, CalibrationError> {
        let file: TargetsFile = crate::scene::parse_toml(text).map_err(|(span, message)| {
            let (line, column) = span.map_or((1, 1), |s| line_column(text, s.start));
            CalibrationError::Invalid { path: name.to_owned(), line, column, message }
        })?;
        Ok(file.over(*self))
    }
}

/// What a button does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InputAction {
    /// Held: the tool acts (a stroke lasts from press to release).
    Stroke,
    /// Held: the clutch is lifted (relative mode, Galyean–Hughes §2.2.2).
    Clutch,
    /// Pressed: the device switches to its next target.
    CycleTarget,
    /// Pressed: undo the last stroke.
    Undo,
    /// Pressed: redo.
    Redo,
    /// Pressed: the scene returns to its initial view.
    ResetView,
    /// Pressed: the next tool shape.
    NextTool,
    /// Nothing (a button left unbound).
    None,
}

/// A button going down or up, with what it does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ActionEvent {
    /// What the button does.
    pub action: InputAction,
    /// Down (`true`) or up.
    pub pressed: bool,
    /// The device family it came from.
    pub device: DeviceClass,
}

/// The frame in which a device's axes are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotionFrame {
    /// The viewer's frame: x right on the screen, y up, z towards the viewer (SpaceMouse,
    /// gamepad sticks).
    View,
    /// World axes, whatever the view.
    World,
    /// The target's own axes (fly-through style).
    Target,
}

/// Full-deflection speeds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates {
    /// Metres per second at a deflection of 1.
    pub translation_m_s: f32,
    /// Radians per second at a deflection of 1.
    pub rotation_rad_s: f32,
}

impl Default for Rates {
    /// 0.25 m/s and half a turn per second: a full deflection crosses a 50 cm stage in two
    /// seconds; the dead zone and response curve leave fine control near rest.
    fn default() -> Self {
        Self { translation_m_s: 0.25, rotation_rad_s: std::f32::consts::PI }
    }
}

/// Longest time step integrated at once: after a hitch the target moves as if 0.1 s had
/// passed, so a stalled frame never throws it across the scene.
pub const MAX_STEP_S: f32 = 0.1;

/// Moves `pose` by the rate `motion` held for `dt_s` seconds. `view_rotation` is the viewer's
/// orientation (view to world), used by [`MotionFrame::View`]. A motion or a time step that is
/// not finite, or a negative time step, leaves the pose as it was.
pub fn integrate(
    pose: Pose,
    motion: SixDof,
    rates: Rates,
    frame: MotionFrame,
    view_rotation: Quat,
    dt_s: f32,
) -> Pose {
    if !(dt_s.is_finite() && dt_s > 0.0 && motion.translation.is_finite() && motion.rotation.is_finite()) {
        return pose;
    }
    let dt_s = dt_s.min(MAX_STEP_S);
    let step = motion.translation * (rates.translation_m_s * dt_s);
    let turn = motion.rotation * (rates.rotation_rad_s * dt_s);
    let (step, turn) = match frame {
        MotionFrame::View => (view_rotation * step, view_rotation * turn),
        MotionFrame::World => (step, turn),
        MotionFrame::Target => {
            let local = Quat::from_scaled_axis(turn);
            return Pose {
                position_m: pose.position_m + pose.rotation * step,
                rotation: (pose.rotation * local).normalize(),
            };
        }
    };
    Pose {
        position_m: pose.position_m + step,
        rotation: (Quat::from_scaled_axis(turn) * pose.rotation).normalize(),
    }
}

/// The target poses, indexed by [`Target`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetPoses(pub [Pose; 5]);

impl Default for TargetPoses {
    /// Tool and second tool half a decimetre either side of the origin, the light up and to the
    /// left, the scene and the part at the origin.
    fn default() -> Self {
        let at = |x: f32, y: f32, z: f32| Pose { position_m: Vec3::new(x, y, z), rotation: Quat::IDENTITY };
        Self([
            at(0.05, 0.0, 0.0),
            at(0.0, 0.0, 0.0),
            at(-0.5, 0.8, 0.5),
            at(-0.05, 0.0, 0.0),
            at(0.0, 0.0, 0.0),
        ])
    }
}

impl TargetPoses {
    /// The pose of `target`.
    pub fn get(&self, target: Target) -> Pose {
        self.0[target.index()]
    }

    /// Mutable access to the pose of `target`.
    pub fn get_mut(&mut self, target: Target) -> &mut Pose {
        &mut self.0[target.index()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_2;

    fn six(t: [f32; 3], r: [f32; 3]) -> SixDof {
        SixDof { translation: Vec3::from(t), rotation: Vec3::from(r) }
    }

    const RATES: Rates = Rates { translation_m_s: 0.2, rotation_rad_s: 1.0 };

    #[test]
    fn full_deflection_for_one_second_moves_by_the_rate() {
        let mut p = Pose::default();
        for _ in 0..100 {
            p = integrate(
                p,
                six([1.0, 0.0, -0.5], [0.0; 3]),
                RATES,
                MotionFrame::World,
                Quat::IDENTITY,
                0.01,
            );
        }
        assert!((p.position_m - Vec3::new(0.2, 0.0, -0.1)).length() < 1e-5, "{:?}", p.position_m);
        for _ in 0..100 {
            p = integrate(
                p,
                six([0.0; 3], [0.0, FRAC_PI_2, 0.0]),
                RATES,
                MotionFrame::World,
                Quat::IDENTITY,
                0.01,
            );
        }
        assert!((p.rotation * Vec3::X - Vec3::NEG_Z).length() < 1e-4, "a quarter turn about +y");
        assert!((p.position_m - Vec3::new(0.2, 0.0, -0.1)).length() < 1e-5, "rotation keeps the position");
    }

    #[test]
    fn view_relative_motion_follows_the_viewer() {
        // The viewer has walked round to look along −x (turned a quarter turn left about +y):
        // "push right" on the cap is then world −z.
        let view = Quat::from_rotation_y(FRAC_PI_2);
        let p =
            integrate(Pose::default(), six([1.0, 0.0, 0.0], [0.0; 3]), RATES, MotionFrame::View, view, 0.1);
        assert!((p.position_m - Vec3::new(0.0, 0.0, -0.02)).length() < 1e-6, "{:?}", p.position_m);
        // And the twist about the view's z (towards the viewer) turns about world +x.
        let p =
            integrate(Pose::default(), six([0.0; 3], [0.0, 0.0, 1.0]), RATES, MotionFrame::View, view, 0.1);
        let (axis, angle) = p.rotation.to_axis_angle();
        assert!((axis - Vec3::X).length() < 1e-5 && (angle - 0.1).abs() < 1e-5, "{axis:?} {angle}");
    }

    #[test]
    fn target_frame_moves_along_the_targets_axes() {
        let start = Pose { position_m: Vec3::ZERO, rotation: Quat::from_rotation_y(FRAC_PI_2) };
        let p = integrate(
            start,
            six([0.0, 0.0, -1.0], [0.0; 3]),
            RATES,
            MotionFrame::Target,
            Quat::IDENTITY,
            0.5,
        );
        // The target's −z is world −x after its quarter turn.
        assert!((p.position_m - Vec3::new(-0.02, 0.0, 0.0)).length() < 1e-6, "{:?}", p.position_m);
    }

    #[test]
    fn bad_steps_leave_the_pose_and_hitches_are_capped() {
        let p = Pose { position_m: Vec3::ONE, rotation: Quat::IDENTITY };
        let m = six([1.0, 0.0, 0.0], [0.0; 3]);
        for dt in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert_eq!(integrate(p, m, RATES, MotionFrame::World, Quat::IDENTITY, dt), p, "dt {dt}");
        }
        let nan = six([f32::NAN, 0.0, 0.0], [0.0; 3]);
        assert_eq!(integrate(p, nan, RATES, MotionFrame::World, Quat::IDENTITY, 0.01), p);
        let hitch = integrate(p, m, RATES, MotionFrame::World, Quat::IDENTITY, 5.0);
        assert!((hitch.position_m.x - (1.0 + 0.2 * MAX_STEP_S)).abs() < 1e-6);
    }

    #[test]
    fn mapping_table_switches_at_runtime_and_reads_settings() {
        let mut m = MappingTable::default();
        assert_eq!(m.target(DeviceClass::SpaceMouse), Target::Tool);
        assert_eq!(m.target(DeviceClass::Mouse), Target::Scene);
        // The opposite set-up of Ferley et al.: mouse on the tool, SpaceMouse on the scene.
        m.set(DeviceClass::SpaceMouse, Target::Scene);
        m.set(DeviceClass::Mouse, Target::Tool);
        assert_eq!(m.devices_driving(Target::Scene).collect::<Vec<_>>(), [DeviceClass::SpaceMouse]);
        let order: Vec<Target> = (0..5).map(|_| m.cycle(DeviceClass::Gamepad)).collect();
        assert_eq!(order, [Target::Part, Target::Tool, Target::Scene, Target::Light, Target::SecondTool]);

        let read = MappingTable::default()
            .parse("spacemouse = \"light\"\nmouse = \"tool\"\n", "settings.toml")
            .unwrap();
        assert_eq!(read.target(DeviceClass::SpaceMouse), Target::Light);
        assert_eq!(read.target(DeviceClass::Mouse), Target::Tool);
        assert_eq!(read.target(DeviceClass::Gamepad), Target::SecondTool, "unnamed keys keep their value");
    }

    #[test]
    fn mapping_settings_errors_name_the_place() {
        let base = MappingTable::default();
        let e =
            base.parse("mouse = \"tool\"\nspacemose = \"scene\"\n", "settings.toml").unwrap_err().to_string();
        assert!(e.starts_with("settings.toml:2:1:") && e.contains("spacemose"), "{e}");
        let e = base.parse("gamepad = \"head\"\n", "settings.toml").unwrap_err().to_string();
        assert!(e.starts_with("settings.toml:1:11:") && e.contains("head"), "{e}");
    }
}
