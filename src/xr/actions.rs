//! The controllers: one action set with both hands' poses (grip and aim), trigger, squeeze,
//! thumbstick and buttons, suggested bindings for the common controllers, and haptic output.
//!
//! Every action has the subaction paths `/user/hand/left` and `/user/hand/right`, so each
//! hand is read on its own. The buttons are named by role: *primary* is A on the right hand
//! and X on the left (Touch), *secondary* B or Y. Controllers without an analogue trigger or
//! squeeze give 0 or 1; without a thumbstick, the trackpad stands in (Vive).

use openxr as xr;

use super::session::failed;
use super::XrError;
use crate::math::{Pose, Quat, Vec2, Vec3};
use crate::scene::Hand;

/// One hand's controller as read this frame, in the room (reference space).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HandState {
    /// The grip pose (where the hand holds the controller), when tracked.
    pub grip: Option<Pose>,
    /// The aim pose (pointing along its −Z), when tracked.
    pub aim: Option<Pose>,
    /// Trigger, 0 to 1.
    pub trigger: f32,
    /// Squeeze (grip button), 0 to 1.
    pub squeeze: f32,
    /// Thumbstick (or trackpad), −1 to 1 on each axis, +Y forward.
    pub thumbstick: Vec2,
    /// Thumbstick (or trackpad) pressed.
    pub thumbstick_click: bool,
    /// A (right) or X (left).
    pub primary: bool,
    /// B (right) or Y (left).
    pub secondary: bool,
    /// Menu button.
    pub menu: bool,
}

/// A vibration to play on one hand.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Haptic {
    /// Which hand.
    pub hand: Hand,
    /// Amplitude, 0 to 1.
    pub amplitude: f32,
    /// Duration, nanoseconds.
    pub duration_ns: i64,
}

/// An interaction profile Argile suggests bindings for: its path, the extension that adds it
/// (its bindings are suggested only where the runtime offers that extension), and which input
/// each action reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Profile {
    /// `/interaction_profiles/...`.
    pub path: &'static str,
    /// The extension that adds the profile, `None` for the core ones.
    pub extension: Option<&'static str>,
    /// The inputs of Argile's actions.
    pub bindings: Bindings,
}

/// Touch-like controllers: A/B on the right, X/Y and menu on the left (the right one's system
/// button is the runtime's).
const TOUCH_LIKE: Bindings = Bindings {
    trigger: Some("input/trigger/value"),
    squeeze: Some("input/squeeze/value"),
    thumbstick: Some("input/thumbstick"),
    thumbstick_click: Some("input/thumbstick/click"),
    primary: (Some("input/a/click"), Some("input/x/click")),
    secondary: (Some("input/b/click"), Some("input/y/click")),
    menu: (None, Some("input/menu/click")),
};

/// The profiles Argile suggests bindings for, and for each the input paths (under
/// `/user/hand/{left,right}`) of: trigger, squeeze, thumbstick, thumbstick click, primary
/// (right, left), secondary (right, left), menu (right, left); poses and haptics are the same
/// on every profile. The palette's buttons (undo, redo, recentre, save, quit) need only the
/// trigger, so every action is reachable on every profile.
pub const PROFILES: [Profile; 8] = [
    Profile {
        path: "/interaction_profiles/khr/simple_controller",
        extension: None,
        bindings: Bindings {
            trigger: Some("input/select/click"),
            squeeze: None,
            thumbstick: None,
            thumbstick_click: None,
            primary: (None, None),
            secondary: (None, None),
            menu: (Some("input/menu/click"), Some("input/menu/click")),
        },
    },
    Profile { path: "/interaction_profiles/oculus/touch_controller", extension: None, bindings: TOUCH_LIKE },
    Profile {
        path: "/interaction_profiles/valve/index_controller",
        extension: None,
        bindings: Bindings {
            primary: (Some("input/a/click"), Some("input/a/click")),
            secondary: (Some("input/b/click"), Some("input/b/click")),
            // The system button is the runtime's: a firm press on the trackpad is the menu.
            menu: (Some("input/trackpad/force"), Some("input/trackpad/force")),
            ..TOUCH_LIKE
        },
    },
    Profile {
        path: "/interaction_profiles/htc/vive_controller",
        extension: None,
        bindings: Bindings {
            trigger: Some("input/trigger/value"),
            squeeze: Some("input/squeeze/click"),
            thumbstick: Some("input/trackpad"),
            thumbstick_click: Some("input/trackpad/click"),
            primary: (None, None),
            secondary: (None, None),
            menu: (Some("input/menu/click"), Some("input/menu/click")),
        },
    },
    Profile {
        path: "/interaction_profiles/microsoft/motion_controller",
        extension: None,
        bindings: Bindings {
            trigger: Some("input/trigger/value"),
            squeeze: Some("input/squeeze/click"),
            thumbstick: Some("input/thumbstick"),
            thumbstick_click: Some("input/thumbstick/click"),
            // No face buttons: the trackpad's click undoes (redo is on the palette).
            primary: (Some("input/trackpad/click"), Some("input/trackpad/click")),
            secondary: (None, None),
            menu: (Some("input/menu/click"), Some("input/menu/click")),
        },
    },
    Profile {
        path: "/interaction_profiles/hp/mixed_reality_controller",
        extension: Some("XR_EXT_hp_mixed_reality_controller"),
        bindings: Bindings { menu: (Some("input/menu/click"), Some("input/menu/click")), ..TOUCH_LIKE },
    },
    Profile {
        path: "/interaction_profiles/bytedance/pico4_controller",
        extension: Some("XR_BD_controller_interaction"),
        bindings: TOUCH_LIKE,
    },
    Profile {
        path: "/interaction_profiles/meta/touch_controller_plus",
        extension: Some("XR_META_touch_controller_plus"),
        bindings: TOUCH_LIKE,
    },
];

/// The extensions of [`PROFILES`] the runtime offers, enabled in `enabled`.
pub(super) fn enable_profile_extensions(available: &xr::ExtensionSet, enabled: &mut xr::ExtensionSet) {
    enabled.ext_hp_mixed_reality_controller = available.ext_hp_mixed_reality_controller;
    enabled.bd_controller_interaction = available.bd_controller_interaction;
    enabled.meta_touch_controller_plus = available.meta_touch_controller_plus;
}

/// Whether the extension `name` (one of [`PROFILES`]') is enabled in `enabled`.
fn profile_extension_enabled(name: &str, enabled: &xr::ExtensionSet) -> bool {
    match name {
        "XR_EXT_hp_mixed_reality_controller" => enabled.ext_hp_mixed_reality_controller,
        "XR_BD_controller_interaction" => enabled.bd_controller_interaction,
        "XR_META_touch_controller_plus" => enabled.meta_touch_controller_plus,
        _ => false,
    }
}

/// Which input of a profile each action reads (paths under `/user/hand/<side>/`); `None`
/// where the controller has no such input. Poses and haptics are the same on every profile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bindings {
    /// Trigger (a click where there is no analogue trigger).
    pub trigger: Option<&'static str>,
    /// Squeeze.
    pub squeeze: Option<&'static str>,
    /// Thumbstick or trackpad.
    pub thumbstick: Option<&'static str>,
    /// Its click.
    pub thumbstick_click: Option<&'static str>,
    /// Primary button: (right hand, left hand).
    pub primary: (Option<&'static str>, Option<&'static str>),
    /// Secondary button: (right hand, left hand).
    pub secondary: (Option<&'static str>, Option<&'static str>),
    /// Menu button: (right hand, left hand).
    pub menu: (Option<&'static str>, Option<&'static str>),
}

impl Bindings {
    /// Every binding of the profile as (action name, full input path), both hands.
    pub fn paths(&self) -> Vec<(&'static str, String)> {
        let mut out = Vec::new();
        for side in ["left", "right"] {
            let hand = |p: &str| format!("/user/hand/{side}/{p}");
            out.push(("grip_pose", hand("input/grip/pose")));
            out.push(("aim_pose", hand("input/aim/pose")));
            out.push(("haptic", hand("output/haptic")));
            let (primary, secondary, menu) = match side {
                "right" => (self.primary.0, self.secondary.0, self.menu.0),
                _ => (self.primary.1, self.secondary.1, self.menu.1),
            };
            let optional = [
                ("trigger", self.trigger),
                ("squeeze", self.squeeze),
                ("thumbstick", self.thumbstick),
                ("thumbstick_click", self.thumbstick_click),
                ("primary", primary),
                ("secondary", secondary),
                ("menu", menu),
            ];
            out.extend(optional.into_iter().filter_map(|(action, p)| p.map(|p| (action, hand(p)))));
        }
        out
    }
}

/// The action set, its actions and the hands' pose spaces. Field order is drop order: the
/// spaces before the actions, the actions before the set.
pub(super) struct Hands {
    spaces: [(xr::Space, xr::Space); 2],
    /// The pose actions, read through `spaces`; kept as long as the set.
    _grip_pose: xr::Action<xr::Posef>,
    _aim_pose: xr::Action<xr::Posef>,
    trigger: xr::Action<f32>,
    squeeze: xr::Action<f32>,
    thumbstick: xr::Action<xr::Vector2f>,
    thumbstick_click: xr::Action<bool>,
    primary: xr::Action<bool>,
    secondary: xr::Action<bool>,
    menu: xr::Action<bool>,
    haptic: xr::Action<xr::Haptic>,
    set: xr::ActionSet,
    /// `/user/hand/left`, `/user/hand/right`.
    paths: [xr::Path; 2],
}

/// Where `s` is in `base` at `time`, when the runtime tracks both its position and orientation.
fn located(s: &xr::Space, base: &xr::Space, time: xr::Time) -> Result<Option<Pose>, XrError> {
    let l = s.locate(base, time).map_err(failed("xrLocateSpace"))?;
    let valid = xr::SpaceLocationFlags::POSITION_VALID | xr::SpaceLocationFlags::ORIENTATION_VALID;
    Ok(l.location_flags.contains(valid).then(|| pose_of(l.pose)))
}

/// A pose as OpenXR gives it, in Argile's types.
pub(super) fn pose_of(p: xr::Posef) -> Pose {
    let o = p.orientation;
    Pose {
        position_m: Vec3::new(p.position.x, p.position.y, p.position.z),
        rotation: Quat::from_xyzw(o.x, o.y, o.z, o.w).normalize(),
    }
}

impl Hands {
    /// Creates the action set with its suggested bindings (for the profiles of extensions
    /// `enabled` holds) and attaches it to `session`.
    pub(super) fn new(
        instance: &xr::Instance,
        session: &xr::Session<xr::Vulkan>,
        enabled: &xr::ExtensionSet,
    ) -> Result<Self, XrError> {
        let path = |p: &str| instance.string_to_path(p).map_err(failed("xrStringToPath"));
        let paths = [path("/user/hand/left")?, path("/user/hand/right")?];
        let set =
            instance.create_action_set("sculpting", "Sculpting", 0).map_err(failed("xrCreateActionSet"))?;
        macro_rules! action {
            ($name:literal, $label:literal) => {
                set.create_action($name, $label, &paths).map_err(failed("xrCreateAction"))?
            };
        }
        let grip_pose: xr::Action<xr::Posef> = action!("grip_pose", "Hand grip");
        let aim_pose: xr::Action<xr::Posef> = action!("aim_pose", "Hand aim");
        let trigger: xr::Action<f32> = action!("trigger", "Apply the tool");
        let squeeze: xr::Action<f32> = action!("squeeze", "Grab");
        let thumbstick: xr::Action<xr::Vector2f> = action!("thumbstick", "Tool size and shape");
        let thumbstick_click: xr::Action<bool> = action!("thumbstick_click", "Next action");
        let primary: xr::Action<bool> = action!("primary", "Undo");
        let secondary: xr::Action<bool> = action!("secondary", "Redo");
        let menu: xr::Action<bool> = action!("menu", "Recentre");
        let haptic: xr::Action<xr::Haptic> = action!("haptic", "Contact");
        for profile in PROFILES {
            if profile.extension.is_some_and(|e| !profile_extension_enabled(e, enabled)) {
                continue;
            }
            let mut suggested = Vec::new();
            for (action, input) in profile.bindings.paths() {
                let at = path(&input)?;
                suggested.push(match action {
                    "grip_pose" => xr::Binding::new(&grip_pose, at),
                    "aim_pose" => xr::Binding::new(&aim_pose, at),
                    "trigger" => xr::Binding::new(&trigger, at),
                    "squeeze" => xr::Binding::new(&squeeze, at),
                    "thumbstick" => xr::Binding::new(&thumbstick, at),
                    "thumbstick_click" => xr::Binding::new(&thumbstick_click, at),
                    "primary" => xr::Binding::new(&primary, at),
                    "secondary" => xr::Binding::new(&secondary, at),
                    "menu" => xr::Binding::new(&menu, at),
                    _ => xr::Binding::new(&haptic, at),
                });
            }
            instance
                .suggest_interaction_profile_bindings(path(profile.path)?, &suggested)
                .map_err(failed("xrSuggestInteractionProfileBindings"))?;
        }
        session.attach_action_sets(&[&set]).map_err(failed("xrAttachSessionActionSets"))?;
        let space = |action: &xr::Action<xr::Posef>, hand: xr::Path| {
            action
                .create_space(session.clone(), hand, xr::Posef::IDENTITY)
                .map_err(failed("xrCreateActionSpace"))
        };
        let spaces = [
            (space(&grip_pose, paths[0])?, space(&aim_pose, paths[0])?),
            (space(&grip_pose, paths[1])?, space(&aim_pose, paths[1])?),
        ];
        Ok(Self {
            spaces,
            _grip_pose: grip_pose,
            _aim_pose: aim_pose,
            trigger,
            squeeze,
            thumbstick,
            thumbstick_click,
            primary,
            secondary,
            menu,
            haptic,
            set,
            paths,
        })
    }

    /// Syncs the actions and reads both hands (`[left, right]`) located in `space` at `time`.
    /// Without the input focus the runtime gives nothing, so both hands read as idle.
    pub(super) fn read(
        &self,
        session: &xr::Session<xr::Vulkan>,
        space: &xr::Space,
        time: xr::Time,
        focused: bool,
    ) -> Result<[HandState; 2], XrError> {
        if !focused {
            return Ok(Default::default());
        }
        session.sync_actions(&[(&self.set).into()]).map_err(failed("xrSyncActions"))?;
        let mut out = [HandState::default(); 2];
        for (i, hand) in out.iter_mut().enumerate() {
            let sub = self.paths[i];
            let float = |a: &xr::Action<f32>| {
                a.state(session, sub).map(|s| s.current_state).map_err(failed("xrGetActionStateFloat"))
            };
            let button = |a: &xr::Action<bool>| {
                a.state(session, sub).map(|s| s.current_state).map_err(failed("xrGetActionStateBoolean"))
            };
            let stick = self
                .thumbstick
                .state(session, sub)
                .map_err(failed("xrGetActionStateVector2f"))?
                .current_state;
            *hand = HandState {
                grip: located(&self.spaces[i].0, space, time)?,
                aim: located(&self.spaces[i].1, space, time)?,
                trigger: float(&self.trigger)?,
                squeeze: float(&self.squeeze)?,
                thumbstick: Vec2::new(stick.x, stick.y),
                thumbstick_click: button(&self.thumbstick_click)?,
                primary: button(&self.primary)?,
                secondary: button(&self.secondary)?,
                menu: button(&self.menu)?,
            };
        }
        Ok(out)
    }

    /// Both grips (`[left, right]`) located in `space` at `time` again, without syncing the
    /// actions: the runtime's latest prediction of where the hands will be when the frame is
    /// shown.
    pub(super) fn locate_grips(
        &self,
        space: &xr::Space,
        time: xr::Time,
    ) -> Result<[Option<Pose>; 2], XrError> {
        Ok([located(&self.spaces[0].0, space, time)?, located(&self.spaces[1].0, space, time)?])
    }

    /// Plays `pulse` on its hand.
    pub(super) fn play(&self, session: &xr::Session<xr::Vulkan>, pulse: &Haptic) -> Result<(), XrError> {
        let sub = self.paths[usize::from(pulse.hand == Hand::Right)];
        let vibration = xr::HapticVibration::new()
            .amplitude(pulse.amplitude.clamp(0.0, 1.0))
            .duration(xr::Duration::from_nanos(pulse.duration_ns.max(1)))
            .frequency(xr::FREQUENCY_UNSPECIFIED);
        self.haptic.apply_feedback(session, sub, &vibration).map_err(failed("xrApplyHapticFeedback"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_profile_binds_both_hands_poses_haptics_and_a_trigger() {
        for Profile { path: profile, bindings, extension } in PROFILES {
            let paths = bindings.paths();
            if let Some(e) = extension {
                let mut offered = xr::ExtensionSet::default();
                offered.ext_hp_mixed_reality_controller = true;
                offered.bd_controller_interaction = true;
                offered.meta_touch_controller_plus = true;
                let mut all = xr::ExtensionSet::default();
                enable_profile_extensions(&offered, &mut all);
                assert!(profile_extension_enabled(e, &all), "{profile}: {e} is not enabled when offered");
                assert!(!profile_extension_enabled(e, &xr::ExtensionSet::default()));
            }
            for side in ["left", "right"] {
                for needed in ["input/grip/pose", "input/aim/pose", "output/haptic"] {
                    let p = format!("/user/hand/{side}/{needed}");
                    assert!(paths.iter().any(|(_, q)| *q == p), "{profile} lacks {p}");
                }
                assert!(
                    paths
                        .iter()
                        .any(|(a, q)| *a == "trigger" && q.starts_with(&format!("/user/hand/{side}/"))),
                    "{profile}: no trigger on the {side} hand"
                );
            }
            // No input path is bound twice to different actions.
            let mut seen = std::collections::HashMap::new();
            for (action, p) in &paths {
                if let Some(other) = seen.insert(p.clone(), *action) {
                    assert_eq!(other, *action, "{profile}: {p}");
                }
            }
        }
    }

    #[test]
    fn touch_buttons_follow_the_hand() {
        let paths = PROFILES[1].bindings.paths();
        let find = |action: &str, side: &str| {
            paths
                .iter()
                .filter(|(a, p)| *a == action && p.starts_with(&format!("/user/hand/{side}/")))
                .map(|(_, p)| p.clone())
                .collect::<Vec<_>>()
        };
        assert_eq!(find("primary", "right"), ["/user/hand/right/input/a/click"]);
        assert_eq!(find("primary", "left"), ["/user/hand/left/input/x/click"]);
        assert_eq!(find("secondary", "left"), ["/user/hand/left/input/y/click"]);
        assert_eq!(find("squeeze", "left"), ["/user/hand/left/input/squeeze/value"]);
        assert!(find("menu", "right").is_empty());
        assert_eq!(find("menu", "left"), ["/user/hand/left/input/menu/click"]);
    }

    #[test]
    fn every_controller_with_a_menu_button_reaches_the_menu_and_each_profile_is_named_once() {
        for p in PROFILES {
            assert_eq!(PROFILES.iter().filter(|q| q.path == p.path).count(), 1, "{}", p.path);
            let simple = p.path.ends_with("simple_controller");
            let menu = p.bindings.menu;
            assert!(menu.0.is_some() || menu.1.is_some(), "{}: no menu binding", p.path);
            if !simple {
                assert!(p.bindings.squeeze.is_some() && p.bindings.thumbstick.is_some(), "{}", p.path);
            }
        }
        let index = PROFILES.iter().find(|p| p.path.ends_with("valve/index_controller")).unwrap();
        assert_eq!(index.bindings.menu.1, Some("input/trackpad/force"));
        let wmr = PROFILES.iter().find(|p| p.path.ends_with("microsoft/motion_controller")).unwrap();
        assert_eq!(wmr.bindings.primary.0, Some("input/trackpad/click"), "undo on the trackpad");
    }
}
