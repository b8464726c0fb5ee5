//! The desktop screen calibration (`calibration/screen.toml`): the physical screen, the default
//! eye position, the interpupillary distance, the head tracker's place and conventions, and the
//! comfort budget. `calibration/README.md` documents the procedure and every key.
//!
//! A file is layered over the shipped calibration (embedded in the binary): it names only the
//! keys it changes. Unknown keys are refused; every error names the file, line and column.

use std::fmt;
use std::ops::Range;
use std::path::Path;

use serde::Deserialize;

use crate::stereo::display::{DisplayMode, Parity};
use toml::Spanned;

use super::{line_column, FileError};
use crate::math::{Pose, Quat, Vec3};
use crate::stereo::{BudgetMode, ParallaxBudget, Screen};

/// The shipped screen calibration: a 24" 16:9 monitor seen from 60 cm.
pub const SHIPPED_SCREEN_TOML: &str = include_str!("../../calibration/screen.toml");

/// Where the head tracker is and how its numbers read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerCalibration {
    /// UDP port the opentrack receiver listens on.
    pub port: u16,
    /// Where the tracker's zero is: the viewer's centred head, or the tracker's own origin.
    pub zero: TrackerZero,
    /// The tracker's frame in screen space (tracker → screen): its axes, and with
    /// [`TrackerZero::Origin`] its origin.
    pub to_screen: Pose,
    /// Signs applied to the tracker's x, y, z before `to_screen` (±1; mirrors a tracker whose
    /// axes are left-handed).
    pub position_signs: Vec3,
    /// Signs applied to yaw, pitch, roll (±1).
    pub angle_signs: Vec3,
    /// How long a lost tracker's last pose is held, seconds.
    pub hold_s: f32,
    /// How long the view then takes to ease back to the default eye position, seconds.
    pub ease_s: f32,
}

/// What a tracker's zero position stands for (`[tracker] zero`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TrackerZero {
    /// The head where the viewer centred the tracker (opentrack's "center"): the station maps
    /// it to `[viewer] default_eye_m`, looking at the screen. The default.
    Centred,
    /// The tracker's own origin, at `[tracker] position_m` in screen space (a tracker that
    /// reports absolute positions).
    Origin,
}

/// A validated screen calibration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenCalibration {
    /// The physical screen, screen space (metres).
    pub screen: Screen,
    /// Where the point between the eyes is when nobody is tracked, screen space.
    pub default_eye_m: Vec3,
    /// Interpupillary distance, metres.
    pub ipd_m: f32,
    /// Near clipping distance, metres (physical, before the scene's scale).
    pub near_m: f32,
    /// Far clipping distance, metres.
    pub far_m: f32,
    /// The head tracker.
    pub tracker: TrackerCalibration,
    /// The parallax budget.
    pub budget: ParallaxBudget,
    /// How the display shows stereo pairs.
    pub display: DisplayCalibration,
    /// The screen's resolution, pixels (`[screen] resolution_px`): how much of the screen a
    /// window of so many pixels covers. `None`: the window system's word for it, where there
    /// is one.
    pub resolution_px: Option<(u32, u32)>,
}

/// What the display does with a stereo pair: the mode it needs (a passive 3D monitor needs an
/// interlaced one, a 3D TV side-by-side-half, ...) and which rows or columns its polariser gives
/// the left eye.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DisplayCalibration {
    /// The display mode for this display (the station's default when absent).
    pub mode: Option<DisplayMode>,
    /// The screen rows (columns) of the left eye, counted from the screen's top left.
    pub parity: Parity,
    /// The monitor this display is (its index or a part of its name), for the station's window.
    pub monitor: Option<MonitorName>,
    /// The station's window fills the monitor.
    pub fullscreen: bool,
}

/// How a monitor is named for the station's window: its index in the window system's list or
/// (a part of) its name, such as `DP-1`; at most [`MonitorName::MOST_BYTES`] bytes, kept inline
/// so that a calibration stays a plain value.
#[derive(Clone, Copy, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(try_from = "String")]
pub struct MonitorName {
    bytes: [u8; MonitorName::MOST_BYTES],
    len: u8,
}

impl MonitorName {
    /// The longest name kept (window systems' output names are a few characters).
    pub const MOST_BYTES: usize = 48;

    /// The name as written.
    pub fn as_str(&self) -> &str {
        std::str::from_utf8(&self.bytes[..usize::from(self.len)]).expect("made from a str (checked)")
    }
}

impl std::str::FromStr for MonitorName {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        if s.is_empty() || s.len() > Self::MOST_BYTES {
            return Err(format!(
                "a monitor is named by its index or (a part of) its name, of 1 to {} bytes, not {:?}",
                Self::MOST_BYTES,
                s.chars().take(60).collect::<String>()
            ));
        }
        let mut bytes = [0; Self::MOST_BYTES];
        bytes[..s.len()].copy_from_slice(s.as_bytes());
        Ok(Self { bytes, len: s.len() as u8 })
    }
}

impl TryFrom<String> for MonitorName {
    type Error = String;

    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl fmt::Debug for MonitorName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}

impl fmt::Display for MonitorName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl ScreenCalibration {
    /// The shipped calibration.
    pub fn shipped() -> Self {
        Self::parse_layer(SHIPPED_SCREEN_TOML, "calibration/screen.toml", None)
            .expect("the shipped screen calibration is valid (tested)")
    }

    /// Loads a calibration file, layered over the shipped one.
    pub fn load(path: &Path) -> Result<Self, FileError> {
        let text = crate::io::text::read_text(path, crate::io::text::SETTINGS_LIMIT).map_err(|reason| {
            FileError::Read { kind: "screen calibration", path: path.to_owned(), reason }
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses calibration text layered over the shipped calibration; `name` is used in
    /// messages.
    pub fn parse(text: &str, name: &str) -> Result<Self, FileError> {
        Self::parse_layer(text, name, Some(&Self::shipped()))
    }

    /// The default head pose: at the default eye, looking straight at the screen.
    pub fn default_head(&self) -> Pose {
        let (vr, vu, vn) = self.screen.basis();
        Pose {
            position_m: self.default_eye_m,
            rotation: Quat::from_mat3(&crate::math::Mat3::from_cols(vr, vu, vn)),
        }
    }

    /// Distance from the default eye to the screen plane.
    pub fn viewing_distance_m(&self) -> f32 {
        self.screen.signed_distance_m(self.default_eye_m)
    }

    fn parse_layer(text: &str, name: &str, base: Option<&Self>) -> Result<Self, FileError> {
        let at = |span: Option<Range<usize>>, message: String| {
            let (line, column) = span.map_or((1, 1), |s| line_column(text, s.start));
            FileError::Invalid { path: name.to_owned(), line, column, message }
        };
        let missing =
            |key: &str| at(None, format!("`{key}` is missing (a complete screen calibration needs it)"));
        let file: File = super::parse_toml(text).map_err(|(span, message)| at(span, message))?;
        let number = |v: Option<Spanned<f32>>, key: &str, range: Range<f32>, fallback: Option<f32>| match v {
            Some(v) if range.contains(v.get_ref()) => Ok(*v.get_ref()),
            Some(v) => Err(at(
                Some(v.span()),
                format!(
                    "`{key}` must be at least {} and below {}, not {}",
                    range.start,
                    range.end,
                    v.get_ref()
                ),
            )),
            None => fallback.ok_or_else(|| missing(key)),
        };
        let vector = |v: Option<Spanned<[f32; 3]>>, key: &str, fallback: Option<Vec3>| match v {
            Some(v) if v.get_ref().iter().all(|c| c.is_finite() && c.abs() <= 100.0) => {
                Ok(Vec3::from(*v.get_ref()))
            }
            Some(v) => Err(at(Some(v.span()), format!("`{key}` must be three numbers within ±100"))),
            None => fallback.ok_or_else(|| missing(key)),
        };
        let signs = |v: Option<Spanned<[f32; 3]>>, key: &str, fallback: Option<Vec3>| match v {
            Some(v) if v.get_ref().iter().all(|c| *c == 1.0 || *c == -1.0) => Ok(Vec3::from(*v.get_ref())),
            Some(v) => Err(at(Some(v.span()), format!("`{key}` must be three signs, each 1 or -1"))),
            None => fallback.ok_or_else(|| missing(key)),
        };

        // The screen: three corners, or size and pose; a layer gives one form or the other.
        let s = file.screen;
        let screen_span = s.span();
        let corners = [s.lower_left_m, s.lower_right_m, s.upper_left_m];
        let sized =
            [s.width_m.is_some(), s.height_m.is_some(), s.centre_m.is_some(), s.rotation_deg.is_some()];
        let screen = if corners.iter().any(Option::is_some) {
            if sized.iter().any(|&b| b) {
                return Err(at(
                    screen_span,
                    "[screen] gives corners and size together; give either the three corners or width_m, height_m, centre_m and rotation_deg".to_owned(),
                ));
            }
            let names = ["lower_left_m", "lower_right_m", "upper_left_m"];
            let mut spans = None;
            let mut points = [Vec3::ZERO; 3];
            for ((c, name), out) in corners.into_iter().zip(names).zip(&mut points) {
                let Some(c) = c else {
                    return Err(at(screen_span, format!("[screen] `{name}` is missing: corners need all three of lower_left_m, lower_right_m and upper_left_m")));
                };
                spans.get_or_insert(c.span());
                *out = vector(Some(c), &format!("screen.{name}"), None)?;
            }
            let screen =
                Screen { lower_left_m: points[0], lower_right_m: points[1], upper_left_m: points[2] };
            if let Some(problem) = screen.problem() {
                return Err(at(spans, format!("[screen] {problem}")));
            }
            screen
        } else if sized.iter().any(|&b| b) || base.is_none() {
            let base_size = base.map(|b| (b.screen.width_m(), b.screen.height_m()));
            let width = number(s.width_m, "screen.width_m", 0.01..100.0, base_size.map(|b| b.0))?;
            let height = number(s.height_m, "screen.height_m", 0.01..100.0, base_size.map(|b| b.1))?;
            let centre = vector(s.centre_m, "screen.centre_m", base.map(|b| b.screen.centre_m()))?;
            let rotation = match s.rotation_deg {
                Some(r) => {
                    let [x, y, z] = *r.get_ref();
                    if ![x, y, z].iter().all(|a| a.is_finite()) {
                        return Err(at(Some(r.span()), "`screen.rotation_deg` must be finite".to_owned()));
                    }
                    Quat::from_euler(glam::EulerRot::XYZ, x.to_radians(), y.to_radians(), z.to_radians())
                }
                None => base.map_or(Quat::IDENTITY, |b| {
                    let (vr, vu, vn) = b.screen.basis();
                    Quat::from_mat3(&crate::math::Mat3::from_cols(vr, vu, vn))
                }),
            };
            Screen::from_size(width, height, Pose { position_m: centre, rotation })
        } else {
            base.map(|b| b.screen).ok_or_else(|| missing("screen"))?
        };

        let resolution_px = match s.resolution_px {
            Some(r) if r.get_ref().iter().all(|p| (16..=65_536).contains(p)) => {
                let [w, h] = *r.get_ref();
                Some((w, h))
            }
            Some(r) => {
                return Err(at(
                    Some(r.span()),
                    format!(
                        "`screen.resolution_px` must be two pixel counts from 16 to 65536, not {:?}",
                        r.get_ref()
                    ),
                ))
            }
            None => base.and_then(|b| b.resolution_px),
        };
        let v = file.viewer;
        let default_eye_m =
            vector(v.default_eye_m.clone(), "viewer.default_eye_m", base.map(|b| b.default_eye_m))?;
        let distance = screen.signed_distance_m(default_eye_m);
        if distance < 0.05 {
            let span = v.default_eye_m.map(|s| s.span()).or(screen_span);
            return Err(at(
                span,
                format!("`viewer.default_eye_m` must be at least 5 cm in front of the screen, not {distance:.3} m"),
            ));
        }
        let ipd_m = number(v.ipd_m, "viewer.ipd_m", 0.04..0.085, base.map(|b| b.ipd_m))?;
        let near_m = number(v.near_m.clone(), "viewer.near_m", 0.001..10.0, base.map(|b| b.near_m))?;
        let far_m = number(v.far_m.clone(), "viewer.far_m", 0.01..100_000.0, base.map(|b| b.far_m))?;
        if far_m <= near_m {
            let span = v.far_m.or(v.near_m).map(|s| s.span());
            return Err(at(span, format!("`viewer.far_m` ({far_m}) must exceed `viewer.near_m` ({near_m})")));
        }

        let t = file.tracker;
        let bt = base.map(|b| b.tracker);
        let port = match t.port {
            Some(p) if *p.get_ref() >= 1 && *p.get_ref() <= 65535 => *p.get_ref() as u16,
            Some(p) => {
                return Err(at(
                    Some(p.span()),
                    format!("`tracker.port` must be 1 to 65535, not {}", p.get_ref()),
                ))
            }
            None => bt.map(|b| b.port).ok_or_else(|| missing("tracker.port"))?,
        };
        let position_m = vector(t.position_m, "tracker.position_m", bt.map(|b| b.to_screen.position_m))?;
        let rotation = match t.rotation_deg {
            Some(r) if r.get_ref().iter().all(|a| a.is_finite()) => {
                let [x, y, z] = r.get_ref().map(f32::to_radians);
                Quat::from_euler(glam::EulerRot::XYZ, x, y, z)
            }
            Some(r) => return Err(at(Some(r.span()), "`tracker.rotation_deg` must be finite".to_owned())),
            None => bt.map(|b| b.to_screen.rotation).ok_or_else(|| missing("tracker.rotation_deg"))?,
        };
        let tracker = TrackerCalibration {
            port,
            zero: t.zero.or(bt.map(|b| b.zero)).unwrap_or(TrackerZero::Centred),
            to_screen: Pose { position_m, rotation },
            position_signs: signs(t.position_signs, "tracker.position_signs", bt.map(|b| b.position_signs))?,
            angle_signs: signs(t.angle_signs, "tracker.angle_signs", bt.map(|b| b.angle_signs))?,
            hold_s: number(t.hold_s, "tracker.hold_s", 0.0..60.0, bt.map(|b| b.hold_s))?,
            ease_s: number(t.ease_s, "tracker.ease_s", 0.0..60.0, bt.map(|b| b.ease_s))?,
        };

        let c = file.comfort;
        let bb = base.map(|b| b.budget);
        let budget = ParallaxBudget {
            max_disparity_deg: number(
                c.max_disparity_deg,
                "comfort.max_disparity_deg",
                0.1..10.0,
                bb.map(|b| b.max_disparity_deg),
            )?,
            mode: match (c.limit, bb) {
                (Some(true), _) => BudgetMode::Limit,
                (Some(false), _) => BudgetMode::Warn,
                (None, Some(b)) => b.mode,
                (None, None) => return Err(missing("comfort.limit")),
            },
        };
        let bd = base.map(|b| b.display).unwrap_or_default();
        let display = DisplayCalibration {
            mode: file.display.mode.or(bd.mode),
            parity: file.display.parity.unwrap_or(bd.parity),
            monitor: file.display.monitor.or(bd.monitor),
            fullscreen: file.display.fullscreen.unwrap_or(bd.fullscreen),
        };
        Ok(Self { screen, default_eye_m, ipd_m, near_m, far_m, tracker, budget, display, resolution_px })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    screen: ScreenFile,
    #[serde(default)]
    viewer: ViewerFile,
    #[serde(default)]
    tracker: TrackerFile,
    #[serde(default)]
    comfort: ComfortFile,
    #[serde(default)]
    display: DisplayFile,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct DisplayFile {
    mode: Option<DisplayMode>,
    parity: Option<Parity>,
    monitor: Option<MonitorName>,
    fullscreen: Option<bool>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct ScreenFile {
    lower_left_m: Option<Spanned<[f32; 3]>>,
    lower_right_m: Option<Spanned<[f32; 3]>>,
    upper_left_m: Option<Spanned<[f32; 3]>>,
    width_m: Option<Spanned<f32>>,
    height_m: Option<Spanned<f32>>,
    centre_m: Option<Spanned<[f32; 3]>>,
    rotation_deg: Option<Spanned<[f32; 3]>>,
    resolution_px: Option<Spanned<[u32; 2]>>,
}

impl ScreenFile {
    /// Where the earliest key of the table is: errors about the table as a whole point there.
    fn span(&self) -> Option<Range<usize>> {
        let vectors =
            [&self.lower_left_m, &self.lower_right_m, &self.upper_left_m, &self.centre_m, &self.rotation_deg];
        let numbers = [&self.width_m, &self.height_m];
        let spans = vectors.iter().filter_map(|v| v.as_ref().map(Spanned::span));
        spans.chain(numbers.iter().filter_map(|v| v.as_ref().map(Spanned::span))).min_by_key(|s| s.start)
    }
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct ViewerFile {
    default_eye_m: Option<Spanned<[f32; 3]>>,
    ipd_m: Option<Spanned<f32>>,
    near_m: Option<Spanned<f32>>,
    far_m: Option<Spanned<f32>>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct TrackerFile {
    port: Option<Spanned<i64>>,
    zero: Option<TrackerZero>,
    position_m: Option<Spanned<[f32; 3]>>,
    rotation_deg: Option<Spanned<[f32; 3]>>,
    position_signs: Option<Spanned<[f32; 3]>>,
    angle_signs: Option<Spanned<[f32; 3]>>,
    hold_s: Option<Spanned<f32>>,
    ease_s: Option<Spanned<f32>>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct ComfortFile {
    max_disparity_deg: Option<Spanned<f32>>,
    limit: Option<bool>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_calibration_is_a_24_inch_monitor_at_60_cm() {
        let c = ScreenCalibration::shipped();
        let diagonal_in = c.screen.width_m().hypot(c.screen.height_m()) / 0.0254;
        assert!((diagonal_in - 24.0).abs() < 0.05, "{diagonal_in}");
        assert!((c.screen.aspect() - 16.0 / 9.0).abs() < 1e-3);
        assert!((c.viewing_distance_m() - 0.6).abs() < 1e-6);
        assert_eq!(c.tracker.port, 4242);
        assert_eq!(c.budget.max_disparity_deg, 1.0);
    }

    #[test]
    fn a_layer_changes_only_its_keys_and_corners_replace_the_size() {
        let c = ScreenCalibration::parse("[viewer]\nipd_m = 0.06\n", "mine.toml").unwrap();
        assert_eq!(c.ipd_m, 0.06);
        assert_eq!(c.screen, ScreenCalibration::shipped().screen);
        let c = ScreenCalibration::parse(
            "[screen]\nlower_left_m = [-0.3, -0.2, 0.0]\nlower_right_m = [0.3, -0.2, 0.0]\nupper_left_m = [-0.3, 0.2, 0.0]\n",
            "mine.toml",
        )
        .unwrap();
        assert!((c.screen.width_m() - 0.6).abs() < 1e-6 && (c.screen.height_m() - 0.4).abs() < 1e-6);
        let tilted =
            ScreenCalibration::parse("[screen]\nrotation_deg = [-20.0, 0.0, 0.0]\n", "t.toml").unwrap();
        assert!((tilted.screen.basis().2.y - 20f32.to_radians().sin()).abs() < 1e-5);
    }

    #[test]
    fn errors_name_the_file_line_and_column() {
        let cases = [
            ("[viewer]\nipd_mm = 63\n", "mine.toml:2:1", "unknown field"),
            ("[viewer]\nipd_m = 0.63\n", "mine.toml:2:9", "viewer.ipd_m"),
            ("[viewer]\ndefault_eye_m = [0.0, 0.0, -0.5]\n", "mine.toml:2:17", "in front of the screen"),
            (
                "[screen]\nlower_left_m = [-0.3, -0.2, 0.0]\nlower_right_m = [0.3, -0.2, 0.0]\nupper_left_m = [-0.2, 0.2, 0.0]\n",
                "mine.toml:2:16",
                "90°",
            ),
            ("[screen]\nlower_left_m = [-0.3, -0.2, 0.0]\n", "mine.toml:2:16", "upper_left_m"),
            ("[screen]\nwidth_m = 0.5\nlower_left_m = [-0.3, -0.2, 0.0]\n", "mine.toml:2:11", "either"),
            ("[tracker]\nport = 70000\n", "mine.toml:2:8", "tracker.port"),
            ("[tracker]\nangle_signs = [1.0, 0.5, 1.0]\n", "mine.toml:2:15", "signs"),
            ("[viewer]\nnear_m = 2.0\nfar_m = 1.0\n", "mine.toml:3:9", "far_m"),
        ];
        super::super::tests::assert_refused(&cases, |t| ScreenCalibration::parse(t, "mine.toml"));
    }

    #[test]
    fn the_display_table_names_the_mode_and_the_screen_parity() {
        let shipped = ScreenCalibration::shipped();
        assert_eq!(
            shipped.display,
            DisplayCalibration { mode: None, parity: Parity::LeftEven, monitor: None, fullscreen: false }
        );
        let passive = ScreenCalibration::parse_layer(
            "[display]\nmode = \"row-interlaced\"\nparity = \"left-odd\"\n",
            "passive.toml",
            Some(&shipped),
        )
        .unwrap();
        assert_eq!(passive.display.mode, Some(DisplayMode::RowInterlaced));
        assert_eq!(passive.display.parity, Parity::LeftOdd);
        assert_eq!(passive.screen, shipped.screen, "the rest comes from the base");
        let projector = ScreenCalibration::parse_layer(
            "[display]\nmode = \"frame-sequential\"\nmonitor = \"HDMI\"\nfullscreen = true\n",
            "projector.toml",
            Some(&passive),
        )
        .unwrap();
        assert_eq!(
            projector.display,
            DisplayCalibration {
                mode: Some(DisplayMode::FrameSequential),
                parity: Parity::LeftOdd,
                monitor: Some("HDMI".parse().unwrap()),
                fullscreen: true
            },
            "the phase from the base layer"
        );
        let e =
            ScreenCalibration::parse_layer("[display]\nmode = \"holographic\"\n", "bad.toml", Some(&shipped))
                .unwrap_err()
                .to_string();
        assert!(e.starts_with("bad.toml:2:") && e.contains("holographic"), "{e}");
    }
}
