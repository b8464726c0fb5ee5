//! The interaction profiles the runtime simulates, their input and output paths, and how the
//! scripted hand state reads through a binding as an action's value.

use crate::script::{HandState, Pose};

/// Left or right hand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Hand {
    Left,
    Right,
}

impl Hand {
    pub const BOTH: [Hand; 2] = [Hand::Left, Hand::Right];

    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        match self {
            Hand::Left => "left",
            Hand::Right => "right",
        }
    }

    pub fn user_path(self) -> &'static str {
        match self {
            Hand::Left => "/user/hand/left",
            Hand::Right => "/user/hand/right",
        }
    }

    pub fn from_user_path(path: &str) -> Option<Hand> {
        Hand::BOTH.into_iter().find(|h| h.user_path() == path)
    }
}

/// The top-level user paths OpenXR 1.0 defines.
pub const TOP_LEVEL_PATHS: &[&str] =
    &["/user/hand/left", "/user/hand/right", "/user/head", "/user/gamepad", "/user/treadmill"];

/// A physical input or output of a simulated controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Input {
    TriggerValue,
    TriggerClick,
    TriggerTouch,
    SqueezeValue,
    SqueezeClick,
    Stick,
    StickX,
    StickY,
    StickClick,
    StickTouch,
    A,
    B,
    X,
    Y,
    ATouch,
    BTouch,
    XTouch,
    YTouch,
    Menu,
    /// A trackpad's click (Windows Mixed Reality): the script's primary button (A or X).
    TrackpadClick,
    GripPose,
    AimPose,
    Haptic,
}

/// An input's reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reading {
    Bool(bool),
    Float(f32),
    Vector2([f32; 2]),
    Pose(Pose),
    Haptic,
}

/// The OpenXR action types (`XrActionType` values).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ActionKind {
    Boolean,
    Float,
    Vector2,
    Pose,
    Vibration,
}

impl Input {
    /// What this input reads in a hand state.
    pub fn read(self, h: &HandState) -> Reading {
        use Input::*;
        match self {
            TriggerValue => Reading::Float(h.trigger),
            TriggerClick => Reading::Bool(h.trigger >= 0.5),
            TriggerTouch => Reading::Bool(h.trigger > 0.0),
            SqueezeValue => Reading::Float(h.squeeze),
            SqueezeClick => Reading::Bool(h.squeeze >= 0.5),
            Stick => Reading::Vector2(h.thumbstick),
            StickX => Reading::Float(h.thumbstick[0]),
            StickY => Reading::Float(h.thumbstick[1]),
            StickClick => Reading::Bool(h.thumbstick_click),
            StickTouch => Reading::Bool(h.thumbstick_click || h.thumbstick != [0.0, 0.0]),
            A | ATouch => Reading::Bool(h.a),
            B | BTouch => Reading::Bool(h.b),
            X | XTouch => Reading::Bool(h.x),
            Y | YTouch => Reading::Bool(h.y),
            Menu => Reading::Bool(h.menu),
            TrackpadClick => Reading::Bool(h.a || h.x),
            GripPose => Reading::Pose(h.grip),
            AimPose => Reading::Pose(h.aim),
            Haptic => Reading::Haptic,
        }
    }

    /// The reading converted to an action of `kind`, as OpenXR converts between input types
    /// (a float read as a boolean crosses at one half; a boolean read as a float is 0 or 1);
    /// `None` where no conversion exists, and such a binding is ignored.
    pub fn read_as(self, h: &HandState, kind: ActionKind) -> Option<Reading> {
        match (self.read(h), kind) {
            (Reading::Bool(b), ActionKind::Boolean) => Some(Reading::Bool(b)),
            (Reading::Float(f), ActionKind::Boolean) => Some(Reading::Bool(f >= 0.5)),
            (Reading::Bool(b), ActionKind::Float) => Some(Reading::Float(if b { 1.0 } else { 0.0 })),
            (Reading::Float(f), ActionKind::Float) => Some(Reading::Float(f)),
            (r @ Reading::Vector2(_), ActionKind::Vector2) => Some(r),
            (r @ Reading::Pose(_), ActionKind::Pose) => Some(r),
            (Reading::Haptic, ActionKind::Vibration) => Some(Reading::Haptic),
            _ => None,
        }
    }
}

type Table = &'static [(&'static str, Input)];

use Input::*;

const SIMPLE: Table = &[
    ("/input/select/click", TriggerClick),
    ("/input/menu/click", Menu),
    ("/input/grip/pose", GripPose),
    ("/input/aim/pose", AimPose),
    ("/output/haptic", Haptic),
];

const THUMBSTICK: Table = &[
    ("/input/thumbstick", Stick),
    ("/input/thumbstick/x", StickX),
    ("/input/thumbstick/y", StickY),
    ("/input/thumbstick/click", StickClick),
    ("/input/thumbstick/touch", StickTouch),
];

const POSES_AND_HAPTIC: Table =
    &[("/input/grip/pose", GripPose), ("/input/aim/pose", AimPose), ("/output/haptic", Haptic)];

const TOUCH_COMMON: Table = &[
    ("/input/squeeze/value", SqueezeValue),
    ("/input/trigger/value", TriggerValue),
    ("/input/trigger/touch", TriggerTouch),
    ("/input/thumbrest/touch", StickTouch),
];

const TOUCH_LEFT: Table = &[
    ("/input/x/click", X),
    ("/input/x/touch", XTouch),
    ("/input/y/click", Y),
    ("/input/y/touch", YTouch),
    ("/input/menu/click", Menu),
];

const TOUCH_RIGHT: Table =
    &[("/input/a/click", A), ("/input/a/touch", ATouch), ("/input/b/click", B), ("/input/b/touch", BTouch)];

const INDEX_COMMON: Table = &[
    ("/input/system/click", Menu),
    // Pressing the trackpad hard; the script's menu button stands for it.
    ("/input/trackpad/force", Menu),
    ("/input/squeeze/value", SqueezeValue),
    ("/input/squeeze/force", SqueezeValue),
    ("/input/trigger/click", TriggerClick),
    ("/input/trigger/value", TriggerValue),
    ("/input/trigger/touch", TriggerTouch),
];

// The Index's face buttons are A and B on both hands; the script's left hand names them X and Y.
const INDEX_LEFT: Table =
    &[("/input/a/click", X), ("/input/a/touch", XTouch), ("/input/b/click", Y), ("/input/b/touch", YTouch)];

const INDEX_RIGHT: Table = TOUCH_RIGHT;

const VIVE: Table = &[
    ("/input/system/click", Menu),
    ("/input/squeeze/click", SqueezeClick),
    ("/input/menu/click", Menu),
    ("/input/trigger/click", TriggerClick),
    ("/input/trigger/value", TriggerValue),
    ("/input/trackpad", Stick),
    ("/input/trackpad/x", StickX),
    ("/input/trackpad/y", StickY),
    ("/input/trackpad/click", StickClick),
    ("/input/trackpad/touch", StickTouch),
    ("/input/grip/pose", GripPose),
    ("/input/aim/pose", AimPose),
    ("/output/haptic", Haptic),
];

// Windows Mixed Reality: no face buttons; a thumbstick and a trackpad.
const MOTION: Table = &[
    ("/input/menu/click", Menu),
    ("/input/squeeze/click", SqueezeClick),
    ("/input/trigger/value", TriggerValue),
    ("/input/trackpad/x", StickX),
    ("/input/trackpad/y", StickY),
    ("/input/trackpad/click", TrackpadClick),
    ("/input/trackpad/touch", TrackpadClick),
];

const SQUEEZE_TRIGGER: Table =
    &[("/input/squeeze/value", SqueezeValue), ("/input/trigger/value", TriggerValue)];

const MENU: Table = &[("/input/menu/click", Menu)];

// Pico 4: the right controller's system button is reserved, as on Touch.
const PICO4_COMMON: Table = &[
    ("/input/squeeze/value", SqueezeValue),
    ("/input/squeeze/click", SqueezeClick),
    ("/input/trigger/value", TriggerValue),
    ("/input/trigger/click", TriggerClick),
    ("/input/trigger/touch", TriggerTouch),
];

const TOUCH_PLUS_COMMON: Table =
    &[("/input/trigger/force", TriggerValue), ("/input/trigger/curl_meta", TriggerValue)];

/// A simulated interaction profile: its path, whether an extension adds it (see
/// `api::PROFILE_EXTENSIONS`), and the component paths under `/user/hand/left` and
/// `/user/hand/right`.
pub struct Profile {
    pub path: &'static str,
    pub by_extension: bool,
    left: &'static [Table],
    right: &'static [Table],
}

const PROFILES: &[Profile] = &[
    Profile {
        path: "/interaction_profiles/khr/simple_controller",
        by_extension: false,
        left: &[SIMPLE],
        right: &[SIMPLE],
    },
    Profile {
        path: "/interaction_profiles/oculus/touch_controller",
        by_extension: false,
        left: &[TOUCH_COMMON, THUMBSTICK, POSES_AND_HAPTIC, TOUCH_LEFT],
        right: &[TOUCH_COMMON, THUMBSTICK, POSES_AND_HAPTIC, TOUCH_RIGHT],
    },
    Profile {
        path: "/interaction_profiles/valve/index_controller",
        by_extension: false,
        left: &[INDEX_COMMON, THUMBSTICK, POSES_AND_HAPTIC, INDEX_LEFT],
        right: &[INDEX_COMMON, THUMBSTICK, POSES_AND_HAPTIC, INDEX_RIGHT],
    },
    Profile {
        path: "/interaction_profiles/htc/vive_controller",
        by_extension: false,
        left: &[VIVE],
        right: &[VIVE],
    },
    Profile {
        path: "/interaction_profiles/microsoft/motion_controller",
        by_extension: false,
        left: &[MOTION, THUMBSTICK, POSES_AND_HAPTIC],
        right: &[MOTION, THUMBSTICK, POSES_AND_HAPTIC],
    },
    Profile {
        path: "/interaction_profiles/hp/mixed_reality_controller",
        by_extension: true,
        left: &[SQUEEZE_TRIGGER, MENU, THUMBSTICK, POSES_AND_HAPTIC, TOUCH_LEFT],
        right: &[SQUEEZE_TRIGGER, MENU, THUMBSTICK, POSES_AND_HAPTIC, TOUCH_RIGHT],
    },
    Profile {
        path: "/interaction_profiles/bytedance/pico4_controller",
        by_extension: true,
        left: &[PICO4_COMMON, THUMBSTICK, POSES_AND_HAPTIC, TOUCH_LEFT],
        right: &[PICO4_COMMON, THUMBSTICK, POSES_AND_HAPTIC, TOUCH_RIGHT],
    },
    Profile {
        path: "/interaction_profiles/meta/touch_controller_plus",
        by_extension: true,
        left: &[TOUCH_COMMON, TOUCH_PLUS_COMMON, THUMBSTICK, POSES_AND_HAPTIC, TOUCH_LEFT],
        right: &[TOUCH_COMMON, TOUCH_PLUS_COMMON, THUMBSTICK, POSES_AND_HAPTIC, TOUCH_RIGHT],
    },
];

/// A resolved binding: which hand's which input.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Source {
    pub hand: Hand,
    pub input: Input,
}

impl Profile {
    /// The profile with this path, if simulated.
    pub fn find(path: &str) -> Option<&'static Profile> {
        PROFILES.iter().find(|p| p.path == path)
    }

    fn entries(&self, hand: Hand) -> impl Iterator<Item = (&'static str, Input)> {
        let tables = if hand == Hand::Left { self.left } else { self.right };
        tables.iter().flat_map(|t| t.iter().copied())
    }

    /// Resolves a binding path (`/user/hand/right/input/trigger/value`) of this profile. A path
    /// naming only an identifier (`.../input/trigger`) resolves to its value, click or pose
    /// component, as the specification lets an application bind.
    pub fn lookup(&self, path: &str) -> Option<Source> {
        let hand = Hand::BOTH
            .into_iter()
            .find(|h| path.strip_prefix(h.user_path()).is_some_and(|rest| rest.starts_with('/')))?;
        let rest = &path[hand.user_path().len()..];
        let find =
            |p: &str| self.entries(hand).find(|(q, _)| *q == p).map(|(_, input)| Source { hand, input });
        find(rest)
            .or_else(|| find(&format!("{rest}/value")))
            .or_else(|| find(&format!("{rest}/click")))
            .or_else(|| find(&format!("{rest}/pose")))
    }

    /// Every path of this profile, for enumerating bound sources.
    pub fn all_paths(&self) -> Vec<String> {
        Hand::BOTH
            .into_iter()
            .flat_map(|h| self.entries(h).map(move |(p, _)| format!("{}{p}", h.user_path())))
            .collect()
    }
}

/// Combines the readings of an action's bound sources as OpenXR does: booleans OR, floats by
/// largest magnitude, vectors by longest.
pub fn combine(readings: impl IntoIterator<Item = Reading>) -> Option<Reading> {
    readings.into_iter().reduce(|a, b| match (a, b) {
        (Reading::Bool(x), Reading::Bool(y)) => Reading::Bool(x || y),
        (Reading::Float(x), Reading::Float(y)) => Reading::Float(if y.abs() > x.abs() { y } else { x }),
        (Reading::Vector2(x), Reading::Vector2(y)) => {
            let len = |v: [f32; 2]| v[0] * v[0] + v[1] * v[1];
            Reading::Vector2(if len(y) > len(x) { y } else { x })
        }
        (a, _) => a,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::script::Script;

    #[test]
    fn the_four_profiles_resolve_their_paths_per_hand() {
        let touch = Profile::find("/interaction_profiles/oculus/touch_controller").unwrap();
        assert_eq!(
            touch.lookup("/user/hand/right/input/trigger/value"),
            Some(Source { hand: Hand::Right, input: TriggerValue })
        );
        assert_eq!(
            touch.lookup("/user/hand/left/input/x/click"),
            Some(Source { hand: Hand::Left, input: X })
        );
        // The Touch's right controller has no X button, its left no A.
        assert_eq!(touch.lookup("/user/hand/right/input/x/click"), None);
        assert_eq!(touch.lookup("/user/hand/left/input/a/click"), None);
        // Identifier-only paths resolve to their component.
        assert_eq!(touch.lookup("/user/hand/left/input/trigger").map(|s| s.input), Some(TriggerValue));
        assert_eq!(touch.lookup("/user/hand/left/input/grip").map(|s| s.input), Some(GripPose));
        assert_eq!(touch.lookup("/user/hand/leftx/input/grip/pose"), None);
        let simple = Profile::find("/interaction_profiles/khr/simple_controller").unwrap();
        assert_eq!(simple.lookup("/user/hand/left/input/select/click").map(|s| s.input), Some(TriggerClick));
        assert_eq!(simple.lookup("/user/hand/left/input/trigger/value"), None);
        let index = Profile::find("/interaction_profiles/valve/index_controller").unwrap();
        assert_eq!(index.lookup("/user/hand/left/input/a/click").map(|s| s.input), Some(X));
        assert_eq!(index.lookup("/user/hand/right/input/b/click").map(|s| s.input), Some(B));
        let vive = Profile::find("/interaction_profiles/htc/vive_controller").unwrap();
        assert_eq!(vive.lookup("/user/hand/right/input/trackpad").map(|s| s.input), Some(Stick));
        assert_eq!(vive.lookup("/user/hand/right/input/thumbstick"), None);
        assert!(Profile::find("/interaction_profiles/acme/wand").is_none());
        assert!(vive.all_paths().contains(&"/user/hand/left/output/haptic".to_string()));
    }

    #[test]
    fn readings_convert_to_the_action_type_or_not_at_all() {
        let script =
            Script::parse("[[key]]\nframe = 0\nright = { trigger = 0.75, thumbstick = [0.5, -1.0] }")
                .unwrap();
        let right = script.sample(0.0).hands[1];
        assert_eq!(TriggerValue.read_as(&right, ActionKind::Float), Some(Reading::Float(0.75)));
        assert_eq!(TriggerValue.read_as(&right, ActionKind::Boolean), Some(Reading::Bool(true)));
        assert_eq!(A.read_as(&right, ActionKind::Float), Some(Reading::Float(0.0)));
        assert_eq!(Stick.read_as(&right, ActionKind::Vector2), Some(Reading::Vector2([0.5, -1.0])));
        assert_eq!(Stick.read_as(&right, ActionKind::Float), None);
        assert_eq!(GripPose.read_as(&right, ActionKind::Boolean), None);
        assert_eq!(Haptic.read_as(&right, ActionKind::Vibration), Some(Reading::Haptic));
    }

    #[test]
    fn several_sources_combine_as_openxr_says() {
        assert_eq!(combine([Reading::Bool(false), Reading::Bool(true)]), Some(Reading::Bool(true)));
        assert_eq!(combine([Reading::Float(0.3), Reading::Float(-0.8)]), Some(Reading::Float(-0.8)));
        assert_eq!(
            combine([Reading::Vector2([0.1, 0.0]), Reading::Vector2([0.0, 0.5])]),
            Some(Reading::Vector2([0.0, 0.5]))
        );
        assert_eq!(combine([]), None);
    }
}
