//! Scene files: the initial clay, lights, environment, camera, tools, a scripted timeline and
//! the capture times. Parsing, validation and defaults; the format is documented for users in
//! `scenes/README.md`.
//!
//! Every error names the file, and the line and column where the problem is. Knows nothing of
//! Vulkan; depends on `math`, `tool` (solids and tools) and `stereo` (the camera rig and the
//! display modes).

mod colour;
mod file;
mod finite;
mod head;
mod lattice;
mod part;
mod region;
mod screen;
mod symmetry;
mod timeline;
mod tool;

use std::path::{Path, PathBuf};

pub use colour::{parse_hex, SceneColour};
pub use head::{HeadKey, HeadPath};
pub use lattice::{SceneLattice, MAX_WEIGHT};
pub use part::{ScenePart, MAX_PARTS, MAX_PART_NAME};
pub use region::{RegionAction, SceneRegion, MAX_COPIES, MAX_INFLATION_M};
pub use screen::{
    DisplayCalibration, MonitorName, ScreenCalibration, TrackerCalibration, TrackerZero, SHIPPED_SCREEN_TOML,
};
pub use timeline::{Hand, HandState, Key, Timeline};
pub use tool::SceneToolShape;

use crate::field::Colour;
use crate::math::{Pose, Quat, Vec3};
use crate::parts::Symmetry;
use crate::stereo::display::{DisplayMode, Parity};
use crate::stereo::{HeadTrackedRig, Placement, StereoRig};
use crate::tool::{Action, CsgOp, PlacedSolid, Solid};
use file::{AttachSpec, ClaySpec, EnvironmentKind, LightKind, OpSpec, SceneFile, ShapeKind};

/// The scene `argile` renders when given none, embedded in the binary.
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../scenes/default.toml");

/// A problem with a TOML file the station reads (a scene, a calibration or mapping file): the
/// message names the file and, where it can, the line and column.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The file cannot be read.
    #[error("cannot read {kind} file {path}: {reason}")]
    Read {
        /// What the file is ("scene", "calibration", ...).
        kind: &'static str,
        /// The file.
        path: PathBuf,
        /// Why, said in the message (not an error source, whose text a chain of causes would
        /// repeat).
        reason: std::io::Error,
    },
    /// The file is not valid for its format (syntax, unknown key, bad value).
    #[error("{path}:{line}:{column}: {message}")]
    Invalid {
        /// The file.
        path: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong and what to do.
        message: String,
    },
}

/// A problem with a scene file.
pub type SceneError = FileError;

/// A solid of the initial clay.
#[derive(Clone, Debug, PartialEq)]
pub struct ClayPrimitive {
    /// The placed solid.
    pub solid: PlacedSolid,
    /// How it combines with the clay before it.
    pub op: CsgOp,
    /// Linear RGBA.
    pub colour: Colour,
    /// The part it is clay of (an index into [`Scene::parts`]); the solid is placed in that
    /// part's own frame.
    pub part: usize,
}

/// What a light is attached to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attachment {
    /// Fixed in the world: turns with the sculpture.
    Scene,
    /// Given in the viewer's frame (x right, y up, −z forward): moves with the viewer.
    Viewer,
}

/// A light as the scene places it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SceneLight {
    /// Light travelling along `direction`.
    Directional {
        /// Direction of travel (in the frame of `attached_to`).
        direction: Vec3,
        /// Colour × intensity, linear.
        radiance: Vec3,
        /// Frame.
        attached_to: Attachment,
    },
    /// A point light.
    Point {
        /// Position in metres (in the frame of `attached_to`).
        position_m: Vec3,
        /// Colour × intensity, linear.
        radiance: Vec3,
        /// Frame.
        attached_to: Attachment,
    },
}

/// The light surrounding the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvironmentChoice {
    /// The built-in procedural studio.
    Studio,
    /// An equirectangular PNG or Radiance HDR image (path resolved against the scene's folder).
    Image(PathBuf),
}

/// The environment settings.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentSettings {
    /// Which environment.
    pub choice: EnvironmentChoice,
    /// Scale of its radiance.
    pub intensity: f32,
    /// Whether it is drawn as the background.
    pub show: bool,
    /// Linear background colour when it is not.
    pub background: Vec3,
}

/// Clay material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialSettings {
    /// Blinn–Phong exponent.
    pub shininess: f32,
    /// Specular strength.
    pub specular: f32,
    /// Environment reflection at normal incidence.
    pub reflectivity: f32,
    /// Diffuse environment strength.
    pub ambient: f32,
}

/// The workspace stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StageSettings {
    /// Minimum corner, metres.
    pub min_m: Vec3,
    /// Maximum corner, metres.
    pub max_m: Vec3,
    /// Linear RGB.
    pub colour: Vec3,
}

/// Image size and multisampling of each eye.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OutputSettings {
    /// Width of each eye's image.
    pub width_px: u32,
    /// Height of each eye's image.
    pub height_px: u32,
    /// MSAA samples.
    pub samples: u32,
}

/// How the scene's stereo pairs are shown (`[display]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DisplaySettings {
    /// The display mode; `argile render` also writes the composed image when set.
    pub mode: Option<DisplayMode>,
    /// Which output rows or columns carry the left eye in interlaced modes.
    pub parity: Parity,
    /// The mode shown where quad-buffer stereo cannot be (`None`: refuse instead).
    pub fallback: Option<DisplayMode>,
    /// Each eye gets the other's image (glasses worn backwards, emitters that invert).
    pub swap_eyes: bool,
    /// The pictures' side edges are masked where clay in front of the screen touches them (a
    /// floating stereoscopic window, [`crate::stereo::floating`]).
    pub floating_window: bool,
    /// The station's window fills its monitor.
    pub fullscreen: bool,
    /// The monitor the station's window opens on: its index or (a part of) its name.
    pub monitor: Option<screen::MonitorName>,
}

impl Default for DisplaySettings {
    fn default() -> Self {
        Self {
            mode: None,
            parity: Parity::LeftEven,
            fallback: Some(DisplayMode::Anaglyph),
            swap_eyes: false,
            floating_window: false,
            fullscreen: false,
            monitor: None,
        }
    }
}

/// A named tool of the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneTool {
    /// Name keys refer to.
    pub name: String,
    /// Its shape (a freeform one is copied from the clay when playback starts).
    pub shape: SceneToolShape,
    /// Scale along the tool's local X, Y, Z axes.
    pub scale: Vec3,
    /// What it does.
    pub action: Action,
    /// Linear RGBA of the matter it adds or the paint it applies.
    pub colour: Colour,
    /// Distance between stamps, as a fraction of the tool's smallest half extent.
    pub spacing: f32,
    /// The level it edits: `None`, the finest; `Some(n)`, the finest on which its size spans at
    /// most `n` voxels (see `tool::Tool::level_samples`).
    pub level_samples: Option<f32>,
    /// Opacity of its glyph in renders.
    pub glyph_opacity: f32,
}

impl SceneTool {
    /// Half the size of the tool's influence box along its local axes, scaled, metres.
    pub fn half_extents_m(&self) -> Vec3 {
        self.shape.half_extents_m() * self.scale
    }
}

/// A moment at which a stereo pair is written.
#[derive(Clone, Debug, PartialEq)]
pub struct Capture {
    /// Base of the output file names (`NAME-left.png`, `NAME-right.png`).
    pub name: String,
    /// Time on the timeline, seconds.
    pub time_s: f32,
    /// Whether the tools' glyphs are drawn.
    pub show_tools: bool,
}

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Where it came from (a path, or `<built-in default scene>`).
    pub source: String,
    /// Field voxel size, metres.
    pub voxel_size_m: f32,
    /// Field iso-level.
    pub iso: f32,
    /// Output images.
    pub output: OutputSettings,
    /// The stereo camera.
    pub rig: StereoRig,
    /// Initial clay, in order.
    pub clay: Vec<ClayPrimitive>,
    /// Lights.
    pub lights: Vec<SceneLight>,
    /// Environment.
    pub environment: EnvironmentSettings,
    /// Clay material.
    pub material: MaterialSettings,
    /// The stage, if shown.
    pub stage: Option<StageSettings>,
    /// Tools.
    pub tools: Vec<SceneTool>,
    /// The scripted hands.
    pub timeline: Timeline,
    /// Captures, in time order.
    pub captures: Vec<Capture>,
    /// Display mode settings.
    pub display: DisplaySettings,
    /// The scripted head, for head-tracked views of a calibrated screen (`[head]`).
    pub head: Option<HeadPath>,
    /// How the clay behaves under tools that push (`[virtual_clay]`).
    pub virtual_clay: VirtualClaySettings,
    /// The desk input settings file the scene names (`[input] settings`, resolved against the
    /// scene's folder): which target each device drives and its calibration files, read over
    /// the user's settings and under the command line's.
    pub input_settings: Option<std::path::PathBuf>,
    /// The lattices opened over the clay, shaped by their keys and applied (`[[lattice]]`).
    pub lattices: Vec<SceneLattice>,
    /// The mirror planes and radial copies every tool acts through (`[symmetry]`).
    pub symmetry: Symmetry,
    /// Region tools on the timeline, in time order (`[[region]]`).
    pub regions: Vec<SceneRegion>,
    /// The parts the sculpt is built of, in composition order (`[[part]]`; one whole part
    /// without it). Region tools, lattices and pushed clay act on the first.
    pub parts: Vec<ScenePart>,
}

/// The virtual clay's settings: its fluidity, its step, and what holds it besides the tools.
#[derive(Clone, Debug, PartialEq)]
pub struct VirtualClaySettings {
    /// α in [0, 1]: 1 is dry clay that follows the tool, near 0 fluid clay that takes prints.
    pub fluidity: f32,
    /// Simulation step, seconds.
    pub step_s: f32,
    /// Height of a table under the clay (a support plane facing +Y), metres.
    pub table_y_m: Option<f32>,
    /// World boxes (min, max corners, metres) whose clay is held still.
    pub fixed_boxes_m: Vec<(Vec3, Vec3)>,
}

impl Scene {
    /// The end of the scene's timeline: its last key or capture, seconds.
    pub fn end_s(&self) -> f32 {
        self.captures.iter().map(|c| c.time_s).fold(self.timeline.duration_s(), f32::max)
    }

    /// Loads and validates a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = crate::io::text::read_text(path, crate::io::text::SCENE_LIMIT)
            .map_err(|reason| SceneError::Read { kind: "scene", path: path.to_owned(), reason })?;
        Scene::parse(&text, &path.display().to_string(), path.parent())
    }

    /// The head-tracked rig of a scene with a `[head]`: the calibrated screen placed so that
    /// from the default eye it shows what `[camera]` shows, its plane on the convergence plane.
    pub fn head_tracked_rig(&self) -> Option<HeadTrackedRig> {
        let c = &self.head.as_ref()?.calibration;
        Some(HeadTrackedRig {
            screen: c.screen,
            placement: Placement::from_rig(&c.screen, c.default_eye_m, &self.rig),
            interaxial_m: c.ipd_m,
            near_m: self.rig.near_m,
            far_m: self.rig.far_m,
        })
    }

    /// The built-in default scene.
    pub fn default_scene() -> Scene {
        Scene::parse(DEFAULT_SCENE_TOML, "<built-in default scene>", None)
            .expect("the embedded default scene is valid (tested)")
    }

    /// Parses and validates scene text. `name` is used in messages; relative image paths are
    /// resolved against `base_dir` (the current directory when `None`).
    pub fn parse(text: &str, name: &str, base_dir: Option<&Path>) -> Result<Scene, SceneError> {
        let at = |span: Option<std::ops::Range<usize>>, message: String| {
            let (line, column) = span.map_or((1, 1), |s| line_column(text, s.start));
            SceneError::Invalid { path: name.to_owned(), line, column, message: tidy(&message) }
        };
        let file: SceneFile = parse_toml(text).map_err(|(span, message)| at(span, message))?;
        let key = |path: &str| finite::span_of(text, path);
        resolve(file, name, base_dir, &at, &key)
    }
}

/// Parses TOML `text` into `T`, first refusing any value that is not a finite number
/// (`nan`, `inf`, or too large for an `f32`); an error gives the byte range it is at, when
/// known, and a sentence.
pub fn parse_toml<T: serde::de::DeserializeOwned>(
    text: &str,
) -> Result<T, (Option<std::ops::Range<usize>>, String)> {
    if let Err((span, key)) = finite::check_finite(text) {
        return Err((Some(span), format!("`{key}` must be a finite number")));
    }
    toml::from_str(text).map_err(|e| (e.span(), tidy(e.message())))
}

/// The longest message about a file's content, in characters: what a file says is quoted in
/// errors cut to this.
pub const MESSAGE_LIMIT: usize = 300;

/// A message that quotes a file's text, fit for a terminal: control characters escaped
/// (no escape sequence reaches it) and cut to [`MESSAGE_LIMIT`] characters.
pub fn tidy(message: &str) -> String {
    let mut out = String::with_capacity(message.len().min(4 * MESSAGE_LIMIT));
    let mut chars = message.chars();
    for c in chars.by_ref().take(MESSAGE_LIMIT) {
        if c.is_control() && c != '\n' {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    let rest = chars.count();
    if rest > 0 {
        out.push_str(&format!("… ({rest} more characters)"));
    }
    out
}

/// The largest length a scene gives (a radius, a size, a falloff), metres.
pub const MAX_LENGTH_M: f32 = 10.0;
/// The largest scale factor of a clay primitive or a tool.
pub const MAX_SCALE: f32 = 10.0;
/// The most finest-level samples a freeform tool's region may copy.
pub const MAX_FREEFORM_SAMPLES: u32 = 1 << 24;

/// The largest intensity of a light or of the environment.
pub const MAX_INTENSITY: f32 = 1000.0;

/// The shortest timeline step, seconds.
pub const MIN_STEP_S: f32 = 1e-4;
/// The most steps a timeline may take (its last key or capture over its step).
pub const MAX_STEPS: u32 = 1 << 20;
/// The latest time a key or capture may have, seconds (a day).
pub const MAX_TIME_S: f32 = 86_400.0;
/// The farthest a key may place a tool from the origin on each axis, metres.
pub const MAX_POSITION_M: f32 = 100.0;

/// 1-based line and column of a byte offset.
pub(crate) fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

pub(super) type At<'a> = dyn Fn(Option<std::ops::Range<usize>>, String) -> SceneError + 'a;

pub(super) fn positive(
    value: f32,
    what: &str,
    span: &std::ops::Range<usize>,
    at: &At<'_>,
) -> Result<f32, SceneError> {
    if value.is_finite() && value > 0.0 && value <= MAX_LENGTH_M {
        Ok(value)
    } else {
        Err(at(
            Some(span.clone()),
            format!("{what} must be a positive number of metres up to {MAX_LENGTH_M}, not {value}"),
        ))
    }
}

pub(super) fn rotation(deg: [f32; 3]) -> Quat {
    let [x, y, z] = deg.map(f32::to_radians);
    Quat::from_euler(glam::EulerRot::XYZ, x, y, z)
}

fn solid_of(spec: &ClaySpec, span: &std::ops::Range<usize>, at: &At<'_>) -> Result<Solid, SceneError> {
    let need = |v: Option<f32>, key: &str| -> Result<f32, SceneError> {
        let v = v.ok_or_else(|| {
            at(Some(span.clone()), format!("a {:?} needs `{key}`", spec.shape).to_lowercase())
        })?;
        positive(v, key, span, at)
    };
    let need3 = |v: Option<[f32; 3]>, key: &str| -> Result<Vec3, SceneError> {
        let v = v.ok_or_else(|| {
            at(Some(span.clone()), format!("a {:?} needs `{key}`", spec.shape).to_lowercase())
        })?;
        for c in v {
            positive(c, key, span, at)?;
        }
        Ok(Vec3::from(v))
    };
    // Keys that belong to other shapes are refused, so a typo'd shape is noticed.
    let allowed: &[&str] = match spec.shape {
        ShapeKind::Sphere => &["radius_m"],
        ShapeKind::Box => &["size_m"],
        ShapeKind::RoundedBox => &["size_m", "corner_radius_m"],
        ShapeKind::Cylinder => &["radius_m", "height_m"],
        ShapeKind::Torus => &["major_radius_m", "minor_radius_m"],
        ShapeKind::Bar => &["length_m", "radius_m"],
        ShapeKind::Slab => &["size_m", "thickness_m"],
    };
    let present = [
        ("radius_m", spec.radius_m.is_some()),
        ("size_m", spec.size_m.is_some()),
        ("corner_radius_m", spec.corner_radius_m.is_some()),
        ("height_m", spec.height_m.is_some()),
        ("major_radius_m", spec.major_radius_m.is_some()),
        ("minor_radius_m", spec.minor_radius_m.is_some()),
        ("length_m", spec.length_m.is_some()),
        ("thickness_m", spec.thickness_m.is_some()),
    ];
    if let Some((key, _)) = present.iter().find(|(k, p)| *p && !allowed.contains(k)) {
        return Err(at(
            Some(span.clone()),
            format!("`{key}` does not apply to shape {:?}; it takes {}", spec.shape, allowed.join(", "))
                .to_lowercase(),
        ));
    }
    Ok(match spec.shape {
        ShapeKind::Sphere => Solid::Sphere { radius_m: need(spec.radius_m, "radius_m")? },
        ShapeKind::Box => Solid::Box { half_m: need3(spec.size_m, "size_m")? * 0.5 },
        ShapeKind::RoundedBox => {
            let half_m = need3(spec.size_m, "size_m")? * 0.5;
            let corner_m = need(spec.corner_radius_m, "corner_radius_m")?;
            if corner_m > half_m.min_element() {
                return Err(at(
                    Some(span.clone()),
                    format!(
                        "corner_radius_m {corner_m} is more than half the smallest side {}",
                        half_m.min_element() * 2.0
                    ),
                ));
            }
            Solid::RoundedBox { half_m, corner_m }
        }
        ShapeKind::Cylinder => Solid::Cylinder {
            radius_m: need(spec.radius_m, "radius_m")?,
            half_height_m: need(spec.height_m, "height_m")? * 0.5,
        },
        ShapeKind::Torus => Solid::Torus {
            major_m: need(spec.major_radius_m, "major_radius_m")?,
            minor_m: need(spec.minor_radius_m, "minor_radius_m")?,
        },
        ShapeKind::Bar => {
            let half_length_m = need(spec.length_m, "length_m")? * 0.5;
            let radius_m = need(spec.radius_m, "radius_m")?;
            Solid::Bar { half_length_m: half_length_m.max(radius_m), radius_m }
        }
        ShapeKind::Slab => {
            let size = need3(spec.size_m.map(|[x, _, z]| [x, 1.0, z]), "size_m")?;
            let thickness = need(spec.thickness_m, "thickness_m")?;
            let half_m = Vec3::new(size.x, thickness, size.z) * 0.5;
            Solid::RoundedBox { half_m, corner_m: thickness * 0.25 }
        }
    })
}

/// Where a table's key is written (see [`finite::span_of`]): the place an error about its
/// value points at.
type KeyAt<'a> = dyn Fn(&str) -> Option<std::ops::Range<usize>> + 'a;

/// Whether every coordinate of `p` lies within ±[`MAX_POSITION_M`].
pub(super) fn within_reach(p: [f32; 3]) -> bool {
    p.iter().all(|c| c.is_finite() && c.abs() <= MAX_POSITION_M)
}

/// Refuses a number outside `range` at `span`: "`what` must be from … to …, not …".
fn in_range(
    value: f32,
    range: std::ops::RangeInclusive<f32>,
    what: &str,
    span: Option<std::ops::Range<usize>>,
    at: &At<'_>,
) -> Result<f32, SceneError> {
    if value.is_finite() && range.contains(&value) {
        Ok(value)
    } else {
        Err(at(span, format!("{what} must be from {} to {}, not {value}", range.start(), range.end())))
    }
}

fn resolve(
    file: SceneFile,
    name: &str,
    base_dir: Option<&Path>,
    at: &At<'_>,
    key: &KeyAt<'_>,
) -> Result<Scene, SceneError> {
    let field_voxel = file.field.voxel_size_m;
    if !(field_voxel.is_finite() && crate::field::VOXEL_SIZE_RANGE_M.contains(&field_voxel)) {
        return Err(at(
            key("field.voxel_size_m"),
            format!("[field] voxel_size_m must be between 0.0001 and 0.05 metres, not {field_voxel}"),
        ));
    }
    if !(file.field.iso > 0.0 && file.field.iso < 1.0) {
        return Err(at(
            key("field.iso"),
            format!("[field] iso must lie strictly between 0 and 1, not {}", file.field.iso),
        ));
    }
    let o = &file.output;
    if !(16..=8192).contains(&o.width_px) || !(16..=8192).contains(&o.height_px) {
        let wrong = if (16..=8192).contains(&o.width_px) { "output.height_px" } else { "output.width_px" };
        return Err(at(
            key(wrong),
            format!(
                "[output] image size must be 16..8192 pixels per side, not {}x{}",
                o.width_px, o.height_px
            ),
        ));
    }
    if !matches!(o.samples, 1 | 2 | 4 | 8) {
        return Err(at(
            key("output.samples"),
            format!("[output] samples must be 1, 2, 4 or 8, not {}", o.samples),
        ));
    }
    let c = &file.camera;
    for (k, p) in [("camera.eye_m", c.eye_m), ("camera.target_m", c.target_m)] {
        if !within_reach(p) {
            return Err(at(
                key(k),
                format!("[camera] {} must be within ±{MAX_POSITION_M} m on each axis, not {p:?}", &k[7..]),
            ));
        }
    }
    let eye = Vec3::from(c.eye_m);
    let target = Vec3::from(c.target_m);
    let distance = (target - eye).length();
    if distance < 1e-4 {
        return Err(at(key("camera.target_m"), "[camera] eye_m and target_m must differ".to_owned()));
    }
    if Vec3::from(c.up).cross(target - eye).length_squared() < 1e-12 {
        return Err(at(
            key("camera.up"),
            "[camera] up must not be parallel to the viewing direction".to_owned(),
        ));
    }
    if !(1.0..=170.0).contains(&c.fov_y_deg) {
        return Err(at(
            key("camera.fov_y_deg"),
            format!("[camera] fov_y_deg must be between 1 and 170, not {}", c.fov_y_deg),
        ));
    }
    if !(c.interaxial_m >= 0.0 && c.interaxial_m < 1.0) {
        return Err(at(
            key("camera.interaxial_m"),
            format!("[camera] interaxial_m must be between 0 and 1 metre, not {}", c.interaxial_m),
        ));
    }
    let convergence_m = c.convergence_m.unwrap_or(distance);
    let convergence_at = key("camera.convergence_m").or_else(|| key("camera.target_m")).unwrap_or(0..0);
    positive(convergence_m, "[camera] convergence_m", &convergence_at, at)?;
    in_range(c.near_m, 1e-4..=10.0, "[camera] near_m", key("camera.near_m"), at)?;
    in_range(c.far_m, 0.01..=10_000.0, "[camera] far_m", key("camera.far_m"), at)?;
    if c.far_m <= c.near_m {
        return Err(at(
            key("camera.far_m"),
            format!("[camera] need near_m < far_m, got {} and {}", c.near_m, c.far_m),
        ));
    }
    let rig = StereoRig {
        eye_m: eye,
        target_m: target,
        up: Vec3::from(c.up),
        fov_y_deg: c.fov_y_deg,
        interaxial_m: c.interaxial_m,
        convergence_m,
        near_m: c.near_m,
        far_m: c.far_m,
    };

    let parts = part::resolve_parts(&file.part, field_voxel, at)?;
    let mut clay = Vec::with_capacity(file.clay.len());
    for spanned in &file.clay {
        let span = spanned.span();
        let spec = spanned.get_ref();
        let solid = solid_of(spec, &span, at)?;
        if !(spec.scale.is_finite() && spec.scale > 0.0 && spec.scale <= MAX_SCALE) {
            return Err(at(
                Some(span),
                format!("scale must be a factor more than 0 and at most {MAX_SCALE}, not {}", spec.scale),
            ));
        }
        if !within_reach(spec.position_m) {
            return Err(at(
                Some(span),
                format!(
                    "position_m must be within ±{MAX_POSITION_M} m on each axis, not {:?}",
                    spec.position_m
                ),
            ));
        }
        if !spec.rotation_deg.iter().all(|a| a.is_finite() && a.abs() <= 3600.0) {
            return Err(at(
                Some(span),
                format!("rotation_deg must be finite angles within ±3600°, not {:?}", spec.rotation_deg),
            ));
        }
        let colour = spec.colour.unwrap_or(SceneColour([0.6, 0.6, 0.6])).with_alpha(1.0);
        let op = match spec.op {
            OpSpec::Union => CsgOp::Union,
            OpSpec::Difference => CsgOp::Difference,
        };
        let pose = Pose { position_m: Vec3::from(spec.position_m), rotation: rotation(spec.rotation_deg) };
        let part = part::part_index(&parts, spec.part.as_deref(), span, at)?;
        clay.push(ClayPrimitive { solid: PlacedSolid { solid, pose, scale: spec.scale }, op, colour, part });
    }

    let mut lights = Vec::new();
    for spanned in &file.light {
        let span = spanned.span();
        let l = spanned.get_ref();
        let radiance = Vec3::from(l.colour.0)
            * in_range(l.intensity, 0.0..=MAX_INTENSITY, "a light's intensity", Some(span.clone()), at)?;
        if !l.position_m.is_none_or(within_reach) {
            return Err(at(
                Some(span),
                format!(
                    "a light's position_m must be within ±{MAX_POSITION_M} m on each axis, not {:?}",
                    l.position_m
                ),
            ));
        }
        let attached_to = match l.attached_to {
            AttachSpec::Scene => Attachment::Scene,
            AttachSpec::Viewer => Attachment::Viewer,
        };
        lights.push(match (l.kind, l.direction, l.position_m) {
            (LightKind::Directional, Some(d), None) if Vec3::from(d).length_squared() > 1e-12 => {
                SceneLight::Directional { direction: Vec3::from(d).normalize(), radiance, attached_to }
            }
            (LightKind::Point, None, Some(p)) => {
                SceneLight::Point { position_m: Vec3::from(p), radiance, attached_to }
            }
            (LightKind::Directional, ..) => {
                return Err(at(
                    Some(span),
                    "a directional light needs a non-zero `direction` and no `position_m`".to_owned(),
                ))
            }
            (LightKind::Point, ..) => {
                return Err(at(Some(span), "a point light needs `position_m` and no `direction`".to_owned()))
            }
        });
    }

    let e = &file.environment;
    let choice = match (e.kind, &e.path) {
        (EnvironmentKind::Studio, None) => EnvironmentChoice::Studio,
        (EnvironmentKind::Image, Some(p)) => {
            let p = PathBuf::from(p);
            EnvironmentChoice::Image(match base_dir {
                Some(dir) if p.is_relative() => dir.join(p),
                _ => p,
            })
        }
        (EnvironmentKind::Studio, Some(_)) => {
            return Err(at(
                key("environment.path"),
                "[environment] `path` is only for kind = \"image\"".to_owned(),
            ))
        }
        (EnvironmentKind::Image, None) => {
            return Err(at(
                key("environment.kind"),
                "[environment] kind = \"image\" needs `path` (an equirectangular .png or .hdr)".to_owned(),
            ))
        }
    };
    let environment = EnvironmentSettings {
        choice,
        intensity: in_range(
            e.intensity,
            0.0..=MAX_INTENSITY,
            "[environment] intensity",
            key("environment.intensity"),
            at,
        )?,
        show: e.show,
        background: Vec3::from(e.background.0),
    };

    let m = &file.material;
    let of = |name: &str, value: f32, range| {
        in_range(value, range, &format!("[material] {name}"), key(&format!("material.{name}")), at)
    };
    let material = MaterialSettings {
        shininess: of("shininess", m.shininess, 1.0..=1024.0)?,
        specular: of("specular", m.specular, 0.0..=1.0)?,
        reflectivity: of("reflectivity", m.reflectivity, 0.0..=1.0)?,
        ambient: of("ambient", m.ambient, 0.0..=4.0)?,
    };

    let s = &file.stage;
    let stage = if s.show {
        for (k, p) in [("stage.min_m", s.min_m), ("stage.max_m", s.max_m)] {
            if !within_reach(p) {
                return Err(at(
                    key(k),
                    format!("[stage] {} must be within ±{MAX_POSITION_M} m on each axis, not {p:?}", &k[6..]),
                ));
            }
        }
        let (min_m, max_m) = (Vec3::from(s.min_m), Vec3::from(s.max_m));
        if min_m.cmpge(max_m).any() {
            return Err(at(key("stage.max_m"), "[stage] min_m must be below max_m on every axis".to_owned()));
        }
        Some(StageSettings { min_m, max_m, colour: Vec3::from(s.colour.0) })
    } else {
        None
    };

    let mut tools: Vec<SceneTool> = Vec::new();
    for spanned in &file.tool {
        let span = spanned.span();
        let t = spanned.get_ref();
        if tools.iter().any(|o| o.name == t.name) {
            return Err(at(Some(span), format!("a tool named `{}` is already defined", t.name)));
        }
        let shape = tool::shape_of(t, &span, at)?;
        if let SceneToolShape::Freeform { min_m, max_m } = &shape {
            // The region's clay is copied into a dense grid of the finest voxels.
            let samples = ((*max_m - *min_m) / field_voxel).ceil().max(Vec3::ONE);
            let count = f64::from(samples.x) * f64::from(samples.y) * f64::from(samples.z);
            if count > f64::from(MAX_FREEFORM_SAMPLES) {
                return Err(at(
                    Some(span),
                    format!(
                        "the freeform region spans {} × {} × {} voxels of {field_voxel} m: over the \
                         {MAX_FREEFORM_SAMPLES} samples a tool may copy; choose a smaller region",
                        samples.x, samples.y, samples.z
                    ),
                ));
            }
        }
        let scale = Vec3::from(t.scale);
        for c in t.scale {
            if !(c.is_finite() && c > 0.0 && c <= MAX_SCALE) {
                return Err(at(
                    Some(span),
                    format!(
                        "scale must be three factors more than 0 and at most {MAX_SCALE}, not {:?}",
                        t.scale
                    ),
                ));
            }
        }
        if !(0.05..=4.0).contains(&t.spacing) {
            return Err(at(
                Some(span),
                format!("spacing is a fraction of the tool's size between 0.05 and 4, not {}", t.spacing),
            ));
        }
        if let Some(n) = t.level_samples {
            if !(1.0..=64.0).contains(&n) {
                return Err(at(
                    Some(span),
                    format!("level_samples is the most voxels across the tool's size, 1 to 64, not {n}"),
                ));
            }
        }
        let size_m = (shape.half_extents_m() * scale).min_element();
        let action = tool::action_of(t, size_m, &span, at)?;
        tools.push(SceneTool {
            name: t.name.clone(),
            shape,
            scale,
            action,
            colour: t.colour.with_alpha(1.0),
            spacing: t.spacing,
            level_samples: t.level_samples,
            glyph_opacity: in_range(t.glyph_opacity, 0.0..=1.0, "glyph_opacity", Some(span.clone()), at)?,
        });
    }

    let mut keys = Vec::with_capacity(file.key.len());
    for spanned in &file.key {
        let span = spanned.span();
        let k = spanned.get_ref();
        let Some(tool) = tools.iter().position(|t| t.name == k.tool) else {
            let known: Vec<&str> = tools.iter().map(|t| t.name.as_str()).collect();
            return Err(at(Some(span), format!("no tool named `{}` (tools: {})", k.tool, known.join(", "))));
        };
        if !(k.time_s.is_finite() && (0.0..=MAX_TIME_S).contains(&k.time_s)) {
            return Err(at(Some(span), format!("time_s must be 0 to {MAX_TIME_S} s, not {}", k.time_s)));
        }
        if !k.position_m.iter().all(|c| c.is_finite() && c.abs() <= MAX_POSITION_M) {
            return Err(at(
                Some(span),
                format!("position_m must be within ±{MAX_POSITION_M} m on each axis, not {:?}", k.position_m),
            ));
        }
        if !k.rotation_deg.iter().all(|a| a.is_finite() && a.abs() <= 3600.0) {
            return Err(at(
                Some(span),
                format!("rotation_deg must be finite angles within ±3600°, not {:?}", k.rotation_deg),
            ));
        }
        let hand = match k.hand {
            file::HandSpec::Left => Hand::Left,
            file::HandSpec::Right => Hand::Right,
        };
        let part = part::part_index(&parts, k.part.as_deref(), span, at)?;
        if k.active && parts[part].locked {
            return Err(at(
                Some(file.key[keys.len()].span()),
                format!("part \"{}\" is locked: no tool acts on it", parts[part].name),
            ));
        }
        keys.push(Key {
            time_s: k.time_s,
            hand,
            tool,
            pose: Pose { position_m: Vec3::from(k.position_m), rotation: rotation(k.rotation_deg) },
            active: k.active,
            part,
        });
    }
    let step = &file.timeline.step_s;
    let step_s = *step.get_ref();
    // A step shorter than a tenth of a millisecond would only make the work endless.
    let step_at = (!step.span().is_empty()).then(|| step.span());
    if !(step_s.is_finite() && (MIN_STEP_S..=1.0).contains(&step_s)) {
        return Err(at(
            step_at,
            format!("[timeline] step_s must be {MIN_STEP_S} to 1 seconds, not {step_s}"),
        ));
    }
    let timeline = Timeline::new(keys, step_s).map_err(|(i, msg)| at(Some(file.key[i].span()), msg))?;
    let lattices = lattice::resolve_lattices(&file.lattice, &file.lattice_key, &parts, at)?;
    let symmetry = symmetry::resolve_symmetry(file.symmetry.as_ref(), at)?;
    let regions = region::resolve_regions(&file.region, &parts, at)?;
    // Pushes act on the first part in world coordinates: it must be at rest in the world.
    if !parts[0].placement.is_identity() && tools.iter().any(|t| t.action.is_clay_body()) {
        return Err(at(
            file.tool.first().map(|t| t.span()).or(file.part.first().map(|p| p.span())),
            format!(
                "a push or support tool acts on the first part (\"{}\") in world coordinates, but that part is placed by a position, turn or scale: leave the first part at rest",
                parts[0].name
            ),
        ));
    }
    // The timeline lasts until its last key, the lattices' and the region tools' included.
    let lattice_end = lattices
        .iter()
        .map(|l| l.apply_s)
        .chain(regions.iter().map(SceneRegion::end_s))
        .fold(0.0f32, f32::max);

    let mut captures: Vec<Capture> = Vec::new();
    for spanned in &file.capture {
        let span = spanned.span();
        let c = spanned.get_ref();
        let valid_name = !c.name.is_empty()
            && c.name.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '-' || ch == '_');
        if !valid_name {
            return Err(at(
                Some(span),
                format!("capture name `{}` must be letters, digits, '-' or '_'", c.name),
            ));
        }
        if captures.iter().any(|o| o.name == c.name) {
            return Err(at(Some(span), format!("two captures are named `{}`", c.name)));
        }
        if !(c.time_s.is_finite() && (0.0..=MAX_TIME_S).contains(&c.time_s)) {
            return Err(at(Some(span), format!("time_s must be 0 to {MAX_TIME_S} s, not {}", c.time_s)));
        }
        captures.push(Capture { name: c.name.clone(), time_s: c.time_s, show_tools: c.show_tools });
    }
    if captures.is_empty() {
        let end = timeline.duration_s().max(lattice_end);
        captures.push(Capture { name: "final".to_owned(), time_s: end, show_tools: true });
    }
    captures.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    // The timeline is played in steps of f32 seconds: at most MAX_STEPS of them, which also
    // keeps each step at least eight units of the last place of the time it advances.
    let last = captures.last().map_or(0.0, |c| c.time_s).max(timeline.duration_s()).max(lattice_end);
    if f64::from(last) / f64::from(step_s) > MAX_STEPS as f64 {
        return Err(at(
            step_at,
            format!(
                "the timeline runs to {last} s in steps of {step_s} s: over {MAX_STEPS} steps; \
                 lengthen [timeline] step_s to at least {} s or shorten the timeline",
                last / MAX_STEPS as f32
            ),
        ));
    }
    let head = file.head.as_ref().map(|h| head::resolve_head(h, base_dir, at)).transpose()?;

    let fallback = match &file.display.fallback {
        None => DisplaySettings::default().fallback,
        Some(spanned) => match spanned.get_ref().trim() {
            "none" => None,
            text => match text.parse::<DisplayMode>() {
                Ok(DisplayMode::QuadBuffer) => {
                    return Err(at(
                        Some(spanned.span()),
                        "[display] fallback cannot be quad-buffer: it is shown where quad-buffer \
                         cannot be"
                            .to_owned(),
                    ))
                }
                Ok(mode) => Some(mode),
                Err(e) => return Err(at(Some(spanned.span()), format!("[display] fallback: {e}, or none"))),
            },
        },
    };
    let display = DisplaySettings {
        mode: file.display.mode,
        parity: file.display.parity,
        fallback,
        swap_eyes: file.display.swap_eyes,
        floating_window: file.display.floating_window,
        fullscreen: file.display.fullscreen,
        monitor: file.display.monitor,
    };

    let vc = &file.virtual_clay;
    if !(0.0..=1.0).contains(&vc.fluidity) {
        return Err(at(
            key("virtual_clay.fluidity"),
            format!("[virtual_clay] fluidity must be in [0, 1], not {}", vc.fluidity),
        ));
    }
    if !(vc.step_s > 0.0 && vc.step_s <= 1.0) {
        return Err(at(
            key("virtual_clay.step_s"),
            format!("[virtual_clay] step_s must be in (0, 1] seconds, not {}", vc.step_s),
        ));
    }
    if !vc.table_y_m.is_none_or(|y| y.is_finite() && y.abs() <= MAX_POSITION_M)
        || !vc.fixed_boxes_m.iter().flatten().all(|p| within_reach(*p))
    {
        let k = if vc.table_y_m.is_some_and(|y| y.abs() > MAX_POSITION_M) {
            "table_y_m"
        } else {
            "fixed_boxes_m"
        };
        return Err(at(
            key(&format!("virtual_clay.{k}")),
            format!("[virtual_clay] {k} must lie within ±{MAX_POSITION_M} m"),
        ));
    }
    let virtual_clay = VirtualClaySettings {
        fluidity: vc.fluidity,
        step_s: vc.step_s,
        table_y_m: vc.table_y_m.filter(|y| y.is_finite()),
        fixed_boxes_m: vc
            .fixed_boxes_m
            .iter()
            .map(|[a, b]| (Vec3::from(*a).min(Vec3::from(*b)), Vec3::from(*a).max(Vec3::from(*b))))
            .collect(),
    };

    let input_settings = match &file.input {
        None => None,
        Some(spec) => {
            let p = Path::new(spec.settings.get_ref());
            let path = match base_dir {
                Some(dir) if p.is_relative() => dir.join(p),
                _ => p.to_owned(),
            };
            if !path.is_file() {
                return Err(at(
                    Some(spec.settings.span()),
                    format!("[input] settings: there is no file {}", path.display()),
                ));
            }
            Some(path)
        }
    };

    Ok(Scene {
        source: name.to_owned(),
        voxel_size_m: field_voxel,
        iso: file.field.iso,
        output: OutputSettings { width_px: o.width_px, height_px: o.height_px, samples: o.samples },
        rig,
        clay,
        lights,
        environment,
        material,
        stage,
        tools,
        timeline,
        captures,
        display,
        head,
        virtual_clay,
        input_settings,
        lattices,
        symmetry,
        regions,
        parts,
    })
}

#[cfg(test)]
mod tests;
