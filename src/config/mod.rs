//! Settings that are neither scene nor device calibration: the station's key bindings.
//!
//! The shipped bindings are `calibration/keys.toml`, embedded in the binary; a user's
//! `keys.toml` in the configuration folder (`$XDG_CONFIG_HOME/argile/`, usually
//! `~/.config/argile/`) or a file named on the command line is read over them: each action it
//! names gets the keys it gives, the others keep the shipped ones. Keys are chords of
//! modifiers and one key named as on a US keyboard by its physical position (winit's
//! `KeyCode` names: `KeyZ`, `Digit1`, `Space`, `ArrowLeft`, `BracketLeft`, `F5`, ...), for
//! example `"Ctrl+Shift+KeyZ"`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;
use winit::keyboard::KeyCode;

use crate::scene::{line_column, FileError};

/// The shipped key bindings; `calibration/keys.toml` documents every action.
pub const SHIPPED_KEYS_TOML: &str = include_str!("../../calibration/keys.toml");

/// What a key does in the station.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StationAction {
    /// Close the station (the sculpt is saved first when it has changed).
    Quit,
    /// Undo the last stroke.
    Undo,
    /// Redo the stroke undone last.
    Redo,
    /// Save the sculpt.
    Save,
    /// Held: the desk tool acts on the clay.
    Apply,
    /// Next tool of the scene.
    NextTool,
    /// Next shape for the desk tool (sphere, box, cylinder, torus, soft ellipsoid), same size.
    NextShape,
    /// Next action for the tool (add, remove, paint, smooth, ...).
    NextAction,
    /// Grow the tool.
    Bigger,
    /// Shrink the tool.
    Smaller,
    /// Next display mode.
    NextDisplayMode,
    /// Move the zero-parallax plane away.
    ConvergenceFarther,
    /// Move the zero-parallax plane nearer.
    ConvergenceNearer,
    /// Widen the distance between the eyes.
    InteraxialWider,
    /// Narrow the distance between the eyes.
    InteraxialNarrower,
    /// Switch the mouse between turning the scene and placing the tool.
    ToggleMouseMode,
    /// Switch the lights between following the sculpture and following the viewer.
    ToggleLights,
    /// Keep the desk tool at zero parallax (smoothly), or stop.
    ToggleAutoConvergence,
    /// Take the head tracker's pose of now as the viewer's centred head (the default eye).
    RecentreHead,
    /// Give each eye the other's image (glasses worn backwards), or back.
    SwapEyes,
    /// Mask the pictures' side edges where clay in front of the screen touches them (a
    /// floating stereoscopic window), or stop.
    ToggleFloatingWindow,
    /// Flip the interlace parity: the other rows (columns) carry the left eye (a
    /// frame-sequential display: the other frames).
    FlipParity,
    /// Fill the window's monitor, or go back to a window.
    ToggleFullscreen,
    /// Put the view and the tool back where the scene starts them.
    ResetView,
    /// Held: move the desk tool left (in the view).
    PointerLeft,
    /// Held: move the desk tool right.
    PointerRight,
    /// Held: move the desk tool up.
    PointerUp,
    /// Held: move the desk tool down.
    PointerDown,
    /// Held: move the desk tool away from the viewer.
    PointerAway,
    /// Held: move the desk tool towards the viewer.
    PointerToward,
    /// Open a sculpt file: the newest in the open folder, then each older one in turn.
    Open,
    /// Switch the symmetry (the scene's, or a mirror across X) on or off.
    ToggleSymmetry,
    /// Step to the next symmetry: mirror X, mirror X and Z, radial 6, a kaleidoscope.
    NextSymmetry,
    /// Held: the region of the tool's shape, grabbed where the tool is, is carried and turned
    /// with it; what it leaves is empty, what it lands on unites with it.
    GrabRegion,
    /// Held: a copy of the region of the tool's shape is carried with the tool.
    CopyRegion,
    /// Held: the clay within the tool's size of where it grabbed follows it with a smooth
    /// falloff (a bend).
    BendRegion,
    /// Grow the clay's surface within the tool's shape by a millimetre.
    InflateRegion,
    /// Shrink the clay's surface within the tool's shape by a millimetre.
    DeflateRegion,
    /// Copy the region of the tool's shape (or the box selected) into a new part, which becomes
    /// the active one.
    CopyToPart,
    /// Held: a box is dragged out from where the tool was when the key went down to where it
    /// is; the region keys act on it from then on (a tap clears it).
    SelectBox,
    /// Held: the clutch is lifted: the mouse's 3D cursor moves without the tool; released, the
    /// tool follows the pointer's motion from where it is, scaled by the mouse's clutch gain.
    Clutch,
    /// Make the next part of the sculpt the active one (the tools act on it; a device driving
    /// the `part` target moves and turns it).
    NextPart,
    /// Make the previous part the active one.
    PreviousPart,
    /// Open a lattice over the clay around the tool (a box twice the tool's size), held open
    /// until it is applied or put back.
    OpenLattice,
    /// Open a lattice over the active part's whole clay.
    OpenPartLattice,
    /// Apply the open lattice: the clay keeps its deformation, one undo step.
    ApplyLattice,
    /// Close the open lattice and put the clay back as it was when it opened.
    CancelLattice,
    /// Held: the open lattice's picked control (the one nearest the tool) follows the tool.
    DragControl,
    /// Raise the picked control's function value: the clay near it swells.
    RaiseValue,
    /// Lower the picked control's function value: the clay near it shrinks.
    LowerValue,
    /// Make the picked control's NURBS weight heavier: the volume is drawn towards it.
    HeavierWeight,
    /// Make the picked control's NURBS weight lighter.
    LighterWeight,
    /// Show the open lattice's next slice (ESM §4.2): a patch of controls with stems for their
    /// values and the function's zero contour on it; after the last, none.
    NextLatticeSlice,
    /// The lattices opened from now on are of the next kind: Bézier, B-spline, NURBS.
    NextLatticeKind,
    /// Show or hide the desk panel (tool, history, view, file).
    TogglePanel,
}

/// Every action with its name in the bindings file.
pub const ACTIONS: &[(&str, StationAction)] = &[
    ("quit", StationAction::Quit),
    ("undo", StationAction::Undo),
    ("redo", StationAction::Redo),
    ("save", StationAction::Save),
    ("apply", StationAction::Apply),
    ("next-tool", StationAction::NextTool),
    ("next-shape", StationAction::NextShape),
    ("next-action", StationAction::NextAction),
    ("bigger", StationAction::Bigger),
    ("smaller", StationAction::Smaller),
    ("next-display-mode", StationAction::NextDisplayMode),
    ("convergence-farther", StationAction::ConvergenceFarther),
    ("convergence-nearer", StationAction::ConvergenceNearer),
    ("interaxial-wider", StationAction::InteraxialWider),
    ("interaxial-narrower", StationAction::InteraxialNarrower),
    ("toggle-mouse-mode", StationAction::ToggleMouseMode),
    ("toggle-lights", StationAction::ToggleLights),
    ("toggle-auto-convergence", StationAction::ToggleAutoConvergence),
    ("recentre-head", StationAction::RecentreHead),
    ("swap-eyes", StationAction::SwapEyes),
    ("toggle-floating-window", StationAction::ToggleFloatingWindow),
    ("flip-parity", StationAction::FlipParity),
    ("toggle-fullscreen", StationAction::ToggleFullscreen),
    ("reset-view", StationAction::ResetView),
    ("pointer-left", StationAction::PointerLeft),
    ("pointer-right", StationAction::PointerRight),
    ("pointer-up", StationAction::PointerUp),
    ("pointer-down", StationAction::PointerDown),
    ("pointer-away", StationAction::PointerAway),
    ("pointer-toward", StationAction::PointerToward),
    ("open", StationAction::Open),
    ("clutch", StationAction::Clutch),
    ("toggle-symmetry", StationAction::ToggleSymmetry),
    ("next-symmetry", StationAction::NextSymmetry),
    ("grab-region", StationAction::GrabRegion),
    ("copy-region", StationAction::CopyRegion),
    ("bend-region", StationAction::BendRegion),
    ("inflate-region", StationAction::InflateRegion),
    ("deflate-region", StationAction::DeflateRegion),
    ("select-box", StationAction::SelectBox),
    ("copy-to-part", StationAction::CopyToPart),
    ("next-part", StationAction::NextPart),
    ("previous-part", StationAction::PreviousPart),
    ("open-lattice", StationAction::OpenLattice),
    ("open-part-lattice", StationAction::OpenPartLattice),
    ("apply-lattice", StationAction::ApplyLattice),
    ("cancel-lattice", StationAction::CancelLattice),
    ("drag-control", StationAction::DragControl),
    ("raise-value", StationAction::RaiseValue),
    ("lower-value", StationAction::LowerValue),
    ("heavier-weight", StationAction::HeavierWeight),
    ("lighter-weight", StationAction::LighterWeight),
    ("next-lattice-slice", StationAction::NextLatticeSlice),
    ("next-lattice-kind", StationAction::NextLatticeKind),
    ("toggle-panel", StationAction::TogglePanel),
];

impl StationAction {
    /// The action's name in the bindings file.
    pub fn name(self) -> &'static str {
        ACTIONS.iter().find(|(_, a)| *a == self).map_or("?", |(n, _)| n)
    }

    /// The action a bindings-file name stands for.
    pub fn from_name(name: &str) -> Option<Self> {
        ACTIONS.iter().find(|(n, _)| *n == name).map(|(_, a)| *a)
    }
}

/// Modifier keys held with a key.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Modifiers {
    /// Either Control key.
    pub ctrl: bool,
    /// Either Shift key.
    pub shift: bool,
    /// Either Alt key.
    pub alt: bool,
    /// Either Super (logo) key.
    pub logo: bool,
}

/// A key with the modifiers that must be held with it (exactly those).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Chord {
    /// The modifiers.
    pub modifiers: Modifiers,
    /// The key, by physical position.
    pub key: KeyCode,
}

impl std::fmt::Display for Chord {
    /// As the bindings file writes it, without its `Key` and `Digit` prefixes: `Ctrl+S`,
    /// `ArrowLeft`, `Shift+7`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let m = self.modifiers;
        for (held, name) in [(m.ctrl, "Ctrl+"), (m.shift, "Shift+"), (m.alt, "Alt+"), (m.logo, "Super+")] {
            if held {
                f.write_str(name)?;
            }
        }
        let key = format!("{:?}", self.key);
        let key = key.strip_prefix("Key").or_else(|| key.strip_prefix("Digit")).unwrap_or(&key);
        f.write_str(key)
    }
}

impl Chord {
    /// Parses `"Ctrl+Shift+KeyZ"`; the error says what is wrong.
    pub fn parse(text: &str) -> Result<Self, String> {
        let parts: Vec<&str> = text.split('+').map(str::trim).collect();
        let (key, modifier_names) = parts
            .split_last()
            .filter(|(k, _)| !k.is_empty())
            .ok_or_else(|| format!("`{text}` names no key (write e.g. \"KeyZ\" or \"Ctrl+KeyZ\")"))?;
        let mut modifiers = Modifiers::default();
        for m in modifier_names {
            let slot = match m.to_ascii_lowercase().as_str() {
                "ctrl" | "control" => &mut modifiers.ctrl,
                "shift" => &mut modifiers.shift,
                "alt" => &mut modifiers.alt,
                "super" | "logo" | "meta" => &mut modifiers.logo,
                _ => return Err(format!("`{m}` in `{text}` is not a modifier (Ctrl, Shift, Alt or Super)")),
            };
            if std::mem::replace(slot, true) {
                return Err(format!("`{text}` names the modifier {m} twice"));
            }
        }
        let key =
            KeyCode::deserialize(serde::de::value::StrDeserializer::<serde::de::value::Error>::new(key))
                .map_err(|_| {
                    format!(
                        "`{key}` is not a key name; keys are named by their place on a US keyboard, e.g. \
                     KeyZ, Digit1, Space, Enter, Escape, ArrowLeft, BracketLeft, Equal, Minus, F5"
                    )
                })?;
        Ok(Self { modifiers, key })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeysFile {
    #[serde(default)]
    keys: BTreeMap<Spanned<String>, Spanned<Vec<Spanned<String>>>>,
}

/// Which chords trigger which actions.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyBindings {
    bindings: BTreeMap<StationAction, Vec<Chord>>,
}

impl KeyBindings {
    /// The shipped bindings.
    pub fn shipped() -> Self {
        Self::parse_over(SHIPPED_KEYS_TOML, "calibration/keys.toml", None)
            .expect("the shipped calibration/keys.toml is valid (checked by a test)")
    }

    /// Reads `text` (named `name` in messages) over `base`: the actions it names get its
    /// chords. Without a base, every action must be bound.
    pub fn parse_over(text: &str, name: &str, base: Option<&KeyBindings>) -> Result<Self, FileError> {
        let at = |span: std::ops::Range<usize>, message: String| {
            let (line, column) = line_column(text, span.start);
            FileError::Invalid { path: name.to_owned(), line, column, message }
        };
        let file: KeysFile = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map_or((1, 1), |s| line_column(text, s.start));
            FileError::Invalid { path: name.to_owned(), line, column, message: e.message().to_owned() }
        })?;
        let mut bindings = base.map(|b| b.bindings.clone()).unwrap_or_default();
        let mut owner: BTreeMap<(Modifiers, u32), StationAction> = BTreeMap::new();
        for (action_name, chords) in &file.keys {
            let action = StationAction::from_name(action_name.get_ref()).ok_or_else(|| {
                at(
                    action_name.span(),
                    format!(
                        "unknown action `{}`; the actions are {}",
                        action_name.get_ref(),
                        ACTIONS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                    ),
                )
            })?;
            let mut parsed = Vec::new();
            for chord in chords.get_ref() {
                parsed.push(Chord::parse(chord.get_ref()).map_err(|m| at(chord.span(), m))?);
            }
            bindings.insert(action, parsed);
        }
        // One chord, one action: a chord bound twice would do two things at once.
        for (&action, chords) in &bindings {
            for chord in chords {
                let id = (chord.modifiers, chord.key as u32);
                if let Some(other) = owner.insert(id, action) {
                    let span = file
                        .keys
                        .iter()
                        .find(|(n, _)| n.get_ref() == action.name())
                        .map_or(0..0, |(_, v)| v.span());
                    return Err(at(
                        span,
                        format!("{chord:?} is bound to both `{}` and `{}`", other.name(), action.name()),
                    ));
                }
            }
        }
        if base.is_none() {
            if let Some((missing, _)) = ACTIONS.iter().find(|(_, a)| !bindings.contains_key(a)) {
                return Err(at(0..0, format!("the action `{missing}` has no keys")));
            }
        }
        Ok(Self { bindings })
    }

    /// The shipped bindings with the user's file read over them: `explicit` if given (it must
    /// exist), else `keys.toml` in the configuration folder if there is one.
    pub fn load(explicit: Option<&Path>) -> Result<(Self, Option<PathBuf>), FileError> {
        let shipped = Self::shipped();
        let path = match explicit {
            Some(p) => Some(p.to_owned()),
            None => dirs::config_dir().map(|d| d.join("argile").join("keys.toml")).filter(|p| p.is_file()),
        };
        let Some(path) = path else { return Ok((shipped, None)) };
        let text = crate::io::text::read_text(&path, crate::io::text::SETTINGS_LIMIT)
            .map_err(|reason| FileError::Read { kind: "key bindings", path: path.clone(), reason })?;
        let bindings = Self::parse_over(&text, &path.display().to_string(), Some(&shipped))?;
        Ok((bindings, Some(path)))
    }

    /// The action `key` pressed with `modifiers` triggers, if any.
    pub fn action(&self, key: KeyCode, modifiers: Modifiers) -> Option<StationAction> {
        self.bindings
            .iter()
            .find(|(_, chords)| chords.iter().any(|c| c.key == key && c.modifiers == modifiers))
            .map(|(a, _)| *a)
    }

    /// The actions held keys keep doing whatever the modifiers (pointer moves, apply):
    /// `key` with any modifiers.
    pub fn held_action(&self, key: KeyCode) -> Option<StationAction> {
        self.bindings.iter().find(|(_, chords)| chords.iter().any(|c| c.key == key)).map(|(a, _)| *a)
    }

    /// The chords bound to `action`.
    pub fn chords(&self, action: StationAction) -> &[Chord] {
        self.bindings.get(&action).map_or(&[], Vec::as_slice)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chords_are_written_as_the_bindings_file_names_them_without_prefixes() {
        for (text, shown) in
            [("Ctrl+KeyS", "Ctrl+S"), ("ArrowLeft", "ArrowLeft"), ("Shift+Digit7", "Shift+7")]
        {
            assert_eq!(Chord::parse(text).unwrap().to_string(), shown);
        }
    }

    #[test]
    fn the_shipped_bindings_bind_every_action_once() {
        let b = KeyBindings::shipped();
        for (_, action) in ACTIONS {
            assert!(!b.chords(*action).is_empty(), "{action:?} has keys");
        }
        let ctrl = Modifiers { ctrl: true, ..Default::default() };
        assert_eq!(b.action(KeyCode::KeyZ, ctrl), Some(StationAction::Undo));
        assert_eq!(b.action(KeyCode::KeyZ, Modifiers::default()), None, "modifiers must match exactly");
    }

    #[test]
    fn chords_parse_modifiers_and_key_names() {
        let c = Chord::parse("Ctrl+Shift+KeyZ").unwrap();
        assert_eq!(c.key, KeyCode::KeyZ);
        assert!(c.modifiers.ctrl && c.modifiers.shift && !c.modifiers.alt);
        assert_eq!(Chord::parse("F5").unwrap().key, KeyCode::F5);
        assert!(Chord::parse("Ctrl+").unwrap_err().contains("names no key"));
        assert!(Chord::parse("Hyper+KeyA").unwrap_err().contains("not a modifier"));
        assert!(Chord::parse("Ctrl+Ctrl+KeyA").unwrap_err().contains("twice"));
        assert!(Chord::parse("Z").unwrap_err().contains("not a key name"));
    }

    #[test]
    fn a_user_file_overrides_only_what_it_names_and_errors_say_where() {
        let shipped = KeyBindings::shipped();
        let mine = KeyBindings::parse_over("[keys]\nundo = [\"F5\"]\n", "mine.toml", Some(&shipped)).unwrap();
        assert_eq!(mine.action(KeyCode::F5, Modifiers::default()), Some(StationAction::Undo));
        assert_eq!(mine.chords(StationAction::Redo), shipped.chords(StationAction::Redo));

        let e = KeyBindings::parse_over(
            "[keys]\nundo = [\"F5\"]\nfly = [\"KeyF\"]\n",
            "mine.toml",
            Some(&shipped),
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("mine.toml:3:1: unknown action `fly`"), "{e}");
        let e = KeyBindings::parse_over("[keys]\nundo = [\"Ctrl+Q\"]\n", "mine.toml", Some(&shipped))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("mine.toml:2:9:") && e.contains("not a key name"), "{e}");
        let e = KeyBindings::parse_over("[keys]\nundo = [\"Ctrl+KeyY\"]\n", "mine.toml", Some(&shipped))
            .unwrap_err()
            .to_string();
        assert!(e.contains("bound to both"), "{e}");
        let e =
            KeyBindings::parse_over("[keys]\nundo = [\"KeyU\"]\n", "all.toml", None).unwrap_err().to_string();
        assert!(e.contains("has no keys"), "{e}");
    }
}
