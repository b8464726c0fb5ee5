//! The desk's input settings: which target each device family drives, how SpaceMice are read,
//! and where each device's calibration comes from.
//!
//! ```text
//!  calibration/input.toml (shipped, embedded)
//!    < $XDG_CONFIG_HOME/argile/input.toml (the user's, when it exists)
//!    < the scene's `[input] settings` file < `--input FILE`      (each names only what it changes)
//!  per device (spacemouse, gamepad, mouse):
//!    calibration/DEVICE.toml (shipped)
//!      < the file the last settings layer naming one gives in [calibration] (relative to
//!        that file's folder), else $XDG_CONFIG_HOME/argile/DEVICE.toml when it exists
//! ```
//!
//! Every file refuses unknown keys and reports errors with file, line and column. The settings
//! give the station's starting [`MappingTable`]; a device's `cycle_target` button changes it at
//! run time. `argile info` prints the result ([`InputSettings::describe`]).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::calibration::{read_text, CalibrationError, Layer, SpaceMouseCalibration};
use super::gamepad::GamepadCalibration;
use super::motion::{DeviceClass, MappingTable, TargetsFile};
use super::mouse::MouseSettings;

/// The shipped settings, embedded in the binary; `calibration/input.toml` documents every key.
pub const SHIPPED_INPUT_TOML: &str = include_str!("../../calibration/input.toml");

/// How SpaceMice are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpaceMouseVia {
    /// Through spacenavd's socket when the daemon runs, else over HID.
    Auto,
    /// The devices themselves, over HID (hidraw).
    Hid,
    /// spacenavd's socket only.
    Spacenavd,
}

impl SpaceMouseVia {
    /// Whether to read spacenavd's socket rather than HID, given whether the socket is there.
    pub fn use_spacenavd(self, socket_present: bool) -> bool {
        match self {
            SpaceMouseVia::Auto => socket_present,
            SpaceMouseVia::Hid => false,
            SpaceMouseVia::Spacenavd => true,
        }
    }
}

/// Where a device's calibration came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CalibrationSource {
    /// The shipped file alone (its repository path).
    Shipped(&'static str),
    /// A file read over the shipped one.
    File(PathBuf),
}

impl std::fmt::Display for CalibrationSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CalibrationSource::Shipped(name) => write!(f, "shipped {name}"),
            CalibrationSource::File(path) => write!(f, "{} (over the shipped file)", path.display()),
        }
    }
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct InputFile {
    #[serde(default)]
    targets: TargetsFile,
    #[serde(default)]
    devices: DevicesFile,
    #[serde(default)]
    calibration: CalibrationPaths,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct DevicesFile {
    spacemouse_via: Option<SpaceMouseVia>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct CalibrationPaths {
    spacemouse: Option<PathBuf>,
    gamepad: Option<PathBuf>,
    mouse: Option<PathBuf>,
}

/// What one settings file gives: the mapping over its base, the SpaceMouse reading if named,
/// and the calibration files it names (SpaceMouse, gamepad, mouse).
type SettingsLayer = (MappingTable, Option<SpaceMouseVia>, [Option<PathBuf>; 3]);

/// The desk's input settings, with every device's calibration loaded.
#[derive(Clone, Debug, PartialEq)]
pub struct InputSettings {
    /// Which target each device family drives at start.
    pub mapping: MappingTable,
    /// How SpaceMice are read.
    pub spacemouse_via: SpaceMouseVia,
    /// The SpaceMouse calibration, and where it came from.
    pub spacemouse: (SpaceMouseCalibration, CalibrationSource),
    /// The gamepad mapping, and where it came from.
    pub gamepad: (GamepadCalibration, CalibrationSource),
    /// The mouse settings, and where they came from.
    pub mouse: (MouseSettings, CalibrationSource),
    /// The settings files read over the shipped one, in order.
    pub files: Vec<PathBuf>,
}

impl InputSettings {
    /// The shipped settings and calibrations alone.
    pub fn shipped() -> Self {
        let (mapping, spacemouse_via, _) =
            Self::parse_over(SHIPPED_INPUT_TOML, "calibration/input.toml", MappingTable::default(), None)
                .expect("the shipped input settings are valid (tested)");
        Self {
            mapping,
            spacemouse_via: spacemouse_via.unwrap_or(SpaceMouseVia::Auto),
            spacemouse: (
                SpaceMouseCalibration::shipped(),
                CalibrationSource::Shipped("calibration/spacemouse.toml"),
            ),
            gamepad: (GamepadCalibration::shipped(), CalibrationSource::Shipped("calibration/gamepad.toml")),
            mouse: (MouseSettings::shipped(), CalibrationSource::Shipped("calibration/mouse.toml")),
            files: Vec::new(),
        }
    }

    /// Reads settings text over `mapping`: the mapping, the SpaceMouse reading (if named) and
    /// the calibration paths it names (relative ones taken from `folder`).
    fn parse_over(
        text: &str,
        name: &str,
        mapping: MappingTable,
        folder: Option<&Path>,
    ) -> Result<SettingsLayer, CalibrationError> {
        let layer = Layer { text, name, what: "input settings file" };
        let file: InputFile =
            crate::scene::parse_toml(text).map_err(|(span, message)| layer.at(span, message))?;
        let place = |p: Option<PathBuf>| match (p, folder) {
            (Some(p), Some(dir)) if p.is_relative() => Some(dir.join(p)),
            (p, _) => p,
        };
        let c = file.calibration;
        Ok((
            file.targets.over(mapping),
            file.devices.spacemouse_via,
            [place(c.spacemouse), place(c.gamepad), place(c.mouse)],
        ))
    }

    /// The settings: the shipped ones, with `input.toml` in `config_dir` (the user's
    /// `$XDG_CONFIG_HOME/argile`) read over them if it exists, then each of `layers` in order
    /// (they must exist: a scene's, then the command line's); then each device's calibration as
    /// the module docs say.
    pub fn load(layers: &[&Path], config_dir: Option<&Path>) -> Result<Self, CalibrationError> {
        let mut settings = Self::shipped();
        let user_file = |name: &str| config_dir.map(|d| d.join(name)).filter(|p| p.is_file());
        let paths = user_file("input.toml").into_iter().chain(layers.iter().map(|p| p.to_path_buf()));
        let mut named: [Option<PathBuf>; 3] = [None, None, None];
        for path in paths {
            let text = read_text(&path, "input settings")?;
            let (mapping, via, given) =
                Self::parse_over(&text, &path.display().to_string(), settings.mapping, path.parent())?;
            settings.mapping = mapping;
            settings.spacemouse_via = via.unwrap_or(settings.spacemouse_via);
            for (slot, file) in named.iter_mut().zip(given) {
                if file.is_some() {
                    *slot = file;
                }
            }
            settings.files.push(path);
        }
        let [spacemouse, gamepad, mouse] = named;
        if let Some(p) = spacemouse.or_else(|| user_file("spacemouse.toml")) {
            settings.spacemouse = (SpaceMouseCalibration::load(&p)?, CalibrationSource::File(p));
        }
        if let Some(p) = gamepad.or_else(|| user_file("gamepad.toml")) {
            settings.gamepad = (GamepadCalibration::load(&p)?, CalibrationSource::File(p));
        }
        if let Some(p) = mouse.or_else(|| user_file("mouse.toml")) {
            settings.mouse = (MouseSettings::load(&p)?, CalibrationSource::File(p));
        }
        Ok(settings)
    }

    /// The user's configuration folder for Argile (`$XDG_CONFIG_HOME/argile`), if the platform
    /// has one.
    pub fn user_config_dir() -> Option<PathBuf> {
        dirs::config_dir().map(|d| d.join("argile"))
    }

    /// Where `class`'s calibration came from.
    pub fn source(&self, class: DeviceClass) -> &CalibrationSource {
        match class {
            DeviceClass::SpaceMouse => &self.spacemouse.1,
            DeviceClass::Gamepad => &self.gamepad.1,
            DeviceClass::Mouse => &self.mouse.1,
        }
    }

    /// One line per device family: what it drives and where its calibration comes from.
    pub fn describe(&self, mapping: &MappingTable) -> Vec<String> {
        DeviceClass::ALL
            .into_iter()
            .map(|class| {
                format!(
                    "{} drives the {}; calibration: {}",
                    class.name(),
                    mapping.target(class).name(),
                    self.source(class)
                )
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::motion::Target;

    /// A scratch folder removed when dropped.
    struct Scratch(PathBuf);

    impl Scratch {
        fn new(name: &str) -> Self {
            let dir = std::env::temp_dir().join(format!("argile-input-{name}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            Self(dir)
        }

        fn path(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    #[test]
    fn the_shipped_settings_match_the_built_in_mapping() {
        let s = InputSettings::shipped();
        assert_eq!(s.mapping, MappingTable::default());
        assert_eq!(s.spacemouse_via, SpaceMouseVia::Auto);
        assert!(SpaceMouseVia::Auto.use_spacenavd(true) && !SpaceMouseVia::Auto.use_spacenavd(false));
        assert!(!SpaceMouseVia::Hid.use_spacenavd(true) && SpaceMouseVia::Spacenavd.use_spacenavd(false));
        let lines = s.describe(&s.mapping);
        assert_eq!(lines[0], "spacemouse drives the tool; calibration: shipped calibration/spacemouse.toml");
        assert_eq!(lines[2], "mouse drives the scene; calibration: shipped calibration/mouse.toml");
    }

    #[test]
    fn a_settings_file_names_targets_and_calibration_files_and_the_config_folder_fills_in() {
        let dir = Scratch::new("layers");
        let config = dir.path().join("config");
        let mine = dir.path().join("mine");
        std::fs::create_dir_all(&config).unwrap();
        std::fs::create_dir_all(&mine).unwrap();
        std::fs::write(
            mine.join("input.toml"),
            "[targets]\nspacemouse = \"scene\"\nmouse = \"tool\"\n[devices]\nspacemouse_via = \"hid\"\n\
             [calibration]\nspacemouse = \"sm.toml\"\n",
        )
        .unwrap();
        std::fs::write(mine.join("sm.toml"), "dead_zone = 0.4\n").unwrap();
        std::fs::write(config.join("mouse.toml"), "trackball = \"bell\"\n").unwrap();
        // The user's own input.toml in the config folder comes first; a named file over it.
        std::fs::write(config.join("input.toml"), "[targets]\ngamepad = \"light\"\nmouse = \"light\"\n")
            .unwrap();

        let s = InputSettings::load(&[&mine.join("input.toml")], Some(&config)).unwrap();
        assert_eq!(s.mapping.target(DeviceClass::SpaceMouse), Target::Scene);
        assert_eq!(s.mapping.target(DeviceClass::Mouse), Target::Tool, "the named file wins");
        assert_eq!(s.mapping.target(DeviceClass::Gamepad), Target::Light, "the user's file fills in");
        assert_eq!(s.files, [config.join("input.toml"), mine.join("input.toml")]);
        assert_eq!(s.spacemouse_via, SpaceMouseVia::Hid);
        assert_eq!(s.spacemouse.0.dead_zone, 0.4);
        assert_eq!(s.spacemouse.1, CalibrationSource::File(mine.join("sm.toml")));
        assert_eq!(s.mouse.0.trackball, crate::input::mouse::TrackballKind::Bell);
        assert_eq!(s.mouse.1, CalibrationSource::File(config.join("mouse.toml")));
        assert_eq!(s.gamepad.1, CalibrationSource::Shipped("calibration/gamepad.toml"));
        let lines = s.describe(&s.mapping);
        assert!(
            lines[0].starts_with("spacemouse drives the scene; calibration: ")
                && lines[0].contains("sm.toml")
        );

        // Without a named file, the config folder's input.toml alone.
        let s = InputSettings::load(&[], Some(&config)).unwrap();
        assert_eq!(s.mapping.target(DeviceClass::Gamepad), Target::Light);
        assert_eq!(s.files, [config.join("input.toml")]);
        // A later layer's calibration file replaces an earlier one's, device by device.
        std::fs::write(mine.join("later.toml"), "[calibration]\nspacemouse = \"sm2.toml\"\n").unwrap();
        std::fs::write(mine.join("sm2.toml"), "dead_zone = 0.2\n").unwrap();
        let s = InputSettings::load(&[&mine.join("input.toml"), &mine.join("later.toml")], None).unwrap();
        assert_eq!(s.spacemouse.0.dead_zone, 0.2);
        assert_eq!(s.mapping.target(DeviceClass::SpaceMouse), Target::Scene, "earlier targets stay");
    }

    #[test]
    fn mistakes_in_settings_and_named_files_say_where() {
        let dir = Scratch::new("mistakes");
        let path = dir.path().join("input.toml");
        std::fs::write(&path, "[targets]\nspacemouse = \"tool\"\ngamepad = \"lamp\"\n").unwrap();
        let e = InputSettings::load(&[&path], None).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}:3:11:", path.display())) && e.contains("lamp"), "{e}");
        std::fs::write(&path, "[calibration]\nmouse = \"missing.toml\"\n").unwrap();
        let e = InputSettings::load(&[&path], None).unwrap_err().to_string();
        assert!(e.contains("missing.toml"), "{e}");
        std::fs::write(&path, "[calibration]\nmouse = \"m.toml\"\n").unwrap();
        std::fs::write(dir.path().join("m.toml"), "\n\ninvert_wheel = 3\n").unwrap();
        let e = InputSettings::load(&[&path], None).unwrap_err().to_string();
        assert!(e.contains("m.toml:3:16:"), "{e}");
        let e = InputSettings::load(&[&dir.path().join("absent.toml")], None).unwrap_err().to_string();
        assert!(e.contains("absent.toml"), "{e}");
    }
}
