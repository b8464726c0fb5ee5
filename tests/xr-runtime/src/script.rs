//! The scripted timeline: the simulated headset and hands at each frame, the frames whose
//! layers are captured, and the runtime events (session loss, exit, focus, the runtime going
//! away) by frame.
//!
//! `pace = true` makes `xrWaitFrame` block until the frame's wall-clock time at `display_hz`,
//! as a real compositor does (a headless one may pace at 20 Hz); without it frames run as
//! fast as the application asks.
//!
//! Keyframes are given by frame index; fields a keyframe leaves out keep the previous
//! keyframe's values. Between keyframes positions and analogue inputs are interpolated
//! linearly, orientations spherically, and buttons keep the earlier keyframe's state.

use glam::{Quat, Vec3};
use serde::Deserialize;
use std::collections::BTreeSet;
use std::path::Path;

/// A rigid pose in stage space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub position: Vec3,
    pub orientation: Quat,
}

impl Pose {
    pub const IDENTITY: Pose = Pose { position: Vec3::ZERO, orientation: Quat::IDENTITY };

    pub fn new(position: Vec3, orientation: Quat) -> Pose {
        Pose { position, orientation }
    }

    /// `self` then `local`: the pose of something placed at `local` in this pose's frame.
    pub fn mul(&self, local: &Pose) -> Pose {
        Pose {
            position: self.position + self.orientation * local.position,
            orientation: (self.orientation * local.orientation).normalize(),
        }
    }

    pub fn inverse(&self) -> Pose {
        let inv = self.orientation.conjugate();
        Pose { position: inv * -self.position, orientation: inv }
    }

    fn lerp(&self, other: &Pose, t: f32) -> Pose {
        Pose {
            position: self.position.lerp(other.position, t),
            orientation: self.orientation.slerp(other.orientation, t).normalize(),
        }
    }
}

/// One hand's controller state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandState {
    pub grip: Pose,
    pub aim: Pose,
    pub trigger: f32,
    pub squeeze: f32,
    pub thumbstick: [f32; 2],
    pub a: bool,
    pub b: bool,
    pub x: bool,
    pub y: bool,
    pub menu: bool,
    pub thumbstick_click: bool,
}

impl HandState {
    fn at_rest(side: f32) -> HandState {
        let grip = Pose::new(Vec3::new(0.2 * side, 1.3, -0.3), Quat::IDENTITY);
        HandState {
            grip,
            aim: grip,
            trigger: 0.0,
            squeeze: 0.0,
            thumbstick: [0.0, 0.0],
            a: false,
            b: false,
            x: false,
            y: false,
            menu: false,
            thumbstick_click: false,
        }
    }

    fn lerp(&self, other: &HandState, t: f32) -> HandState {
        let l = |a: f32, b: f32| a + (b - a) * t;
        HandState {
            grip: self.grip.lerp(&other.grip, t),
            aim: self.aim.lerp(&other.aim, t),
            trigger: l(self.trigger, other.trigger),
            squeeze: l(self.squeeze, other.squeeze),
            thumbstick: [
                l(self.thumbstick[0], other.thumbstick[0]),
                l(self.thumbstick[1], other.thumbstick[1]),
            ],
            ..*self
        }
    }
}

/// Everything simulated at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub head: Pose,
    /// Left then right.
    pub hands: [HandState; 2],
}

/// A runtime event the script triggers at the end of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    SessionLoss,
    Exit,
    InstanceLoss,
    /// The runtime's service dies without a word: every call answers
    /// `XR_ERROR_INSTANCE_LOST`, no loss-pending event is sent.
    RuntimeGone,
    FocusLost,
    FocusGained,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    pub frame: u64,
    pub kind: EventKind,
    /// For `instance_loss` and `runtime_gone`: after how many seconds new instances can be
    /// made again (they resume the timeline after the lost frame); `None`: never.
    pub back_after_s: Option<f64>,
}

/// A parsed script.
#[derive(Clone, Debug, PartialEq)]
pub struct Script {
    pub display_period_ns: i64,
    /// `xrWaitFrame` blocks until the frame's wall-clock time.
    pub pace: bool,
    pub interaction_profile: String,
    pub recommended_size: [u32; 2],
    pub ipd_m: f32,
    pub capture: BTreeSet<u64>,
    /// The left eye's field of view in radians (left, right, up, down); the right eye mirrors it.
    pub fov: [f32; 4],
    keys: Vec<(u64, Sample)>,
    pub events: Vec<Event>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScript {
    display_hz: Option<f64>,
    pace: Option<bool>,
    interaction_profile: Option<String>,
    recommended_size: Option<[u32; 2]>,
    ipd_m: Option<f32>,
    #[serde(default)]
    capture: Vec<u64>,
    fov_deg: Option<[f32; 4]>,
    #[serde(default)]
    key: Vec<RawKey>,
    #[serde(default)]
    event: Vec<Event2>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Event2 {
    frame: u64,
    kind: EventKind,
    back_after_s: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawKey {
    frame: u64,
    head: Option<RawPose>,
    left: Option<RawHand>,
    right: Option<RawHand>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPose {
    position: Option<[f32; 3]>,
    orientation: Option<[f32; 4]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHand {
    grip: Option<RawPose>,
    aim: Option<RawPose>,
    trigger: Option<f32>,
    squeeze: Option<f32>,
    thumbstick: Option<[f32; 2]>,
    a: Option<bool>,
    b: Option<bool>,
    x: Option<bool>,
    y: Option<bool>,
    menu: Option<bool>,
    thumbstick_click: Option<bool>,
}

const DEFAULT_PROFILE: &str = "/interaction_profiles/oculus/touch_controller";
const DEFAULT_FOV_DEG: [f32; 4] = [-50.0, 42.0, 45.0, -48.0];

fn apply_pose(raw: &Option<RawPose>, pose: &mut Pose, what: &str) -> Result<(), String> {
    let Some(raw) = raw else { return Ok(()) };
    if let Some(p) = raw.position {
        if p.iter().any(|c| !c.is_finite()) {
            return Err(format!("{what}: position {p:?} is not finite"));
        }
        pose.position = Vec3::from(p);
    }
    if let Some(q) = raw.orientation {
        let q = Quat::from_array(q);
        if !q.is_finite() || q.length() < 1e-6 {
            return Err(format!("{what}: orientation {:?} is not a rotation quaternion", q.to_array()));
        }
        pose.orientation = q.normalize();
    }
    Ok(())
}

fn apply_hand(raw: &Option<RawHand>, hand: &mut HandState, what: &str) -> Result<(), String> {
    let Some(raw) = raw else { return Ok(()) };
    apply_pose(&raw.grip, &mut hand.grip, &format!("{what}.grip"))?;
    apply_pose(&raw.aim, &mut hand.aim, &format!("{what}.aim"))?;
    for (value, slot, name) in
        [(raw.trigger, &mut hand.trigger, "trigger"), (raw.squeeze, &mut hand.squeeze, "squeeze")]
    {
        if let Some(v) = value {
            if !(0.0..=1.0).contains(&v) {
                return Err(format!("{what}.{name} = {v} is outside 0..1"));
            }
            *slot = v;
        }
    }
    if let Some(s) = raw.thumbstick {
        if s.iter().any(|c| !(-1.0..=1.0).contains(c)) {
            return Err(format!("{what}.thumbstick = {s:?} is outside -1..1"));
        }
        hand.thumbstick = s;
    }
    for (value, slot) in [
        (raw.a, &mut hand.a),
        (raw.b, &mut hand.b),
        (raw.x, &mut hand.x),
        (raw.y, &mut hand.y),
        (raw.menu, &mut hand.menu),
        (raw.thumbstick_click, &mut hand.thumbstick_click),
    ] {
        if let Some(v) = value {
            *slot = v;
        }
    }
    Ok(())
}

impl Default for Script {
    fn default() -> Script {
        Script::parse("").expect("the empty script is valid")
    }
}

impl Script {
    /// Reads and parses a script file; errors name the file.
    pub fn load(path: &Path) -> Result<Script, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read the XR test script {}: {e}", path.display()))?;
        Script::parse(&text).map_err(|e| format!("the XR test script {} is invalid: {e}", path.display()))
    }

    /// Parses a script's TOML text.
    pub fn parse(text: &str) -> Result<Script, String> {
        let raw: RawScript = toml::from_str(text).map_err(|e| e.to_string())?;
        let hz = raw.display_hz.unwrap_or(90.0);
        if !(hz.is_finite() && (1.0..=1000.0).contains(&hz)) {
            return Err(format!("display_hz = {hz} is not a display rate (1 to 1000 Hz)"));
        }
        let recommended_size = raw.recommended_size.unwrap_or([256, 256]);
        if recommended_size.iter().any(|&s| s == 0 || s > 4096) {
            return Err(format!("recommended_size = {recommended_size:?} must be 1 to 4096 pixels each"));
        }
        let ipd_m = raw.ipd_m.unwrap_or(0.064);
        if !(0.0..=0.2).contains(&ipd_m) {
            return Err(format!("ipd_m = {ipd_m} is not an interpupillary distance (0 to 0.2 m)"));
        }
        let fov_deg = raw.fov_deg.unwrap_or(DEFAULT_FOV_DEG);
        if !(fov_deg[0] < fov_deg[1] && fov_deg[3] < fov_deg[2] && fov_deg.iter().all(|a| a.abs() < 89.0)) {
            return Err(format!("fov_deg = {fov_deg:?} must be [left, right, up, down] with left < right, down < up, each within ±89°"));
        }
        let interaction_profile = raw.interaction_profile.unwrap_or_else(|| DEFAULT_PROFILE.to_string());
        if crate::profiles::Profile::find(&interaction_profile).is_none() {
            return Err(format!(
                "interaction_profile {interaction_profile:?} is not one the runtime simulates"
            ));
        }
        let mut current = Sample {
            head: Pose::new(Vec3::new(0.0, 1.6, 0.0), Quat::IDENTITY),
            hands: [HandState::at_rest(-1.0), HandState::at_rest(1.0)],
        };
        let mut keys = Vec::with_capacity(raw.key.len().max(1));
        for (i, k) in raw.key.iter().enumerate() {
            if let Some(&(previous, _)) = keys.last() {
                if k.frame <= previous {
                    return Err(format!(
                        "key {} at frame {} does not follow frame {previous}",
                        i + 1,
                        k.frame
                    ));
                }
            }
            let what = format!("key {} (frame {})", i + 1, k.frame);
            apply_pose(&k.head, &mut current.head, &format!("{what} head"))?;
            apply_hand(&k.left, &mut current.hands[0], &format!("{what} left"))?;
            apply_hand(&k.right, &mut current.hands[1], &format!("{what} right"))?;
            keys.push((k.frame, current));
        }
        if keys.is_empty() {
            keys.push((0, current));
        }
        let mut events = Vec::with_capacity(raw.event.len());
        for e in &raw.event {
            if let Some(b) = e.back_after_s {
                if !(b.is_finite() && (0.0..=3600.0).contains(&b)) {
                    return Err(format!("event at frame {}: back_after_s = {b} is not 0 to 3600 s", e.frame));
                }
                if !matches!(e.kind, EventKind::InstanceLoss | EventKind::RuntimeGone) {
                    return Err(format!(
                        "event at frame {}: back_after_s is for instance_loss and runtime_gone",
                        e.frame
                    ));
                }
            }
            events.push(Event { frame: e.frame, kind: e.kind, back_after_s: e.back_after_s });
        }
        events.sort_by_key(|e| e.frame);
        Ok(Script {
            display_period_ns: (1e9 / hz).round() as i64,
            pace: raw.pace.unwrap_or(false),
            interaction_profile,
            recommended_size,
            ipd_m,
            capture: raw.capture.into_iter().collect(),
            fov: fov_deg.map(f32::to_radians),
            keys,
            events,
        })
    }

    /// The simulated state at a (fractional) frame index.
    pub fn sample(&self, frame: f64) -> Sample {
        let after = self.keys.partition_point(|(f, _)| (*f as f64) <= frame);
        if after == 0 {
            return self.keys[0].1;
        }
        let (f0, s0) = &self.keys[after - 1];
        let Some((f1, s1)) = self.keys.get(after) else { return *s0 };
        let t = ((frame - *f0 as f64) / (*f1 - *f0) as f64) as f32;
        Sample {
            head: s0.head.lerp(&s1.head, t),
            hands: [s0.hands[0].lerp(&s1.hands[0], t), s0.hands[1].lerp(&s1.hands[1], t)],
        }
    }

    /// The field of view of eye 0 (left) or 1 (right).
    pub fn eye_fov(&self, eye: usize) -> [f32; 4] {
        let [l, r, u, d] = self.fov;
        if eye == 0 {
            [l, r, u, d]
        } else {
            [-r, -l, u, d]
        }
    }

    /// The pose of eye 0 (left) or 1 (right) for a head pose.
    pub fn eye_pose(&self, head: &Pose, eye: usize) -> Pose {
        let side = if eye == 0 { -0.5 } else { 0.5 };
        head.mul(&Pose::new(Vec3::new(side * self.ipd_m, 0.0, 0.0), Quat::IDENTITY))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCRIPT: &str = r#"
display_hz = 72.0
interaction_profile = "/interaction_profiles/valve/index_controller"
recommended_size = [320, 200]
ipd_m = 0.06
capture = [3, 1]
[[key]]
frame = 0
head = { position = [0, 1.5, 0], orientation = [0, 0, 0, 1] }
right = { trigger = 0.0, a = true, grip = { position = [0.3, 1.2, -0.4] } }
[[key]]
frame = 10
head = { position = [1, 1.5, 0], orientation = [0, 0.70710677, 0, 0.70710677] }
right = { trigger = 1.0, a = false }
[[event]]
frame = 8
kind = "exit"
[[event]]
frame = 4
kind = "focus_lost"
"#;

    #[test]
    fn a_script_reads_its_settings_and_sorts_events() {
        let s = Script::parse(SCRIPT).unwrap();
        assert_eq!(s.display_period_ns, 13_888_889);
        assert_eq!(s.recommended_size, [320, 200]);
        assert_eq!(s.capture.iter().copied().collect::<Vec<_>>(), vec![1, 3]);
        assert_eq!(s.events[0], Event { frame: 4, kind: EventKind::FocusLost, back_after_s: None });
        assert_eq!(s.events[1].kind, EventKind::Exit);
    }

    #[test]
    fn keyframes_interpolate_positions_orientations_and_analogue_inputs() {
        let s = Script::parse(SCRIPT).unwrap();
        let mid = s.sample(5.0);
        assert!((mid.head.position - Vec3::new(0.5, 1.5, 0.0)).length() < 1e-5);
        let (axis, angle) = mid.head.orientation.to_axis_angle();
        assert!((angle - std::f32::consts::FRAC_PI_4).abs() < 1e-4 && (axis.y - 1.0).abs() < 1e-4);
        assert!((mid.hands[1].trigger - 0.5).abs() < 1e-6);
        // Buttons hold the earlier keyframe's state until the next keyframe.
        assert!(mid.hands[1].a);
        assert!(!s.sample(10.0).hands[1].a);
        // Fields a keyframe leaves out carry over: the grip stays where key 1 put it.
        assert!((s.sample(10.0).hands[1].grip.position - Vec3::new(0.3, 1.2, -0.4)).length() < 1e-6);
        // Before the first and after the last keyframe the timeline holds still.
        assert_eq!(s.sample(-3.0), s.sample(0.0));
        assert_eq!(s.sample(99.0), s.sample(10.0));
    }

    #[test]
    fn eyes_sit_half_the_ipd_either_side_of_the_head_and_mirror_their_fov() {
        let s = Script::parse(SCRIPT).unwrap();
        let head = Pose::new(Vec3::new(0.0, 1.5, 0.0), Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
        let left = s.eye_pose(&head, 0);
        // Turned 90° left (about +y), the head's left is +z.
        assert!((left.position - Vec3::new(0.0, 1.5, 0.03)).length() < 1e-5, "{:?}", left.position);
        let [l, r, u, d] = s.eye_fov(0);
        assert_eq!(s.eye_fov(1), [-r, -l, u, d]);
    }

    #[test]
    fn bad_scripts_are_refused_with_a_reason() {
        for (text, needle) in [
            ("display_hz = 0.0", "display_hz"),
            ("ipd_m = 1.0", "ipd_m"),
            ("interaction_profile = \"/interaction_profiles/acme/wand\"", "acme"),
            ("[[key]]\nframe = 5\n[[key]]\nframe = 5", "does not follow"),
            ("[[key]]\nframe = 0\nhead = { orientation = [0, 0, 0, 0] }", "quaternion"),
            ("[[key]]\nframe = 0\nright = { trigger = 2.0 }", "trigger"),
            ("[[event]]\nframe = 1\nkind = \"explode\"", "explode"),
            ("colour = 3", "colour"),
        ] {
            let e = Script::parse(text).unwrap_err();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
    }

    #[test]
    fn poses_compose_and_invert() {
        let a = Pose::new(Vec3::new(1.0, 2.0, 3.0), Quat::from_rotation_y(0.7));
        let b = Pose::new(Vec3::new(-0.5, 0.1, 0.2), Quat::from_rotation_x(-0.3));
        let ab = a.mul(&b);
        let back = a.inverse().mul(&ab);
        assert!((back.position - b.position).length() < 1e-5);
        assert!(back.orientation.dot(b.orientation).abs() > 0.99999);
    }
}
