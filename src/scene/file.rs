//! The TOML layout of a scene file, as serde reads it. Every table refuses unknown keys.
//! `scenes/README.md` documents the format for users.

use serde::Deserialize;
use toml::Spanned;

use super::colour::SceneColour;

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    #[serde(default)]
    pub field: FieldSpec,
    #[serde(default)]
    pub output: OutputSpec,
    #[serde(default)]
    pub camera: CameraSpec,
    #[serde(default)]
    pub environment: EnvironmentSpec,
    #[serde(default)]
    pub material: MaterialSpec,
    #[serde(default)]
    pub stage: StageSpec,
    #[serde(default)]
    pub timeline: TimelineSpec,
    #[serde(default)]
    pub clay: Vec<Spanned<ClaySpec>>,
    #[serde(default)]
    pub light: Vec<Spanned<LightSpec>>,
    #[serde(default)]
    pub tool: Vec<Spanned<ToolSpec>>,
    #[serde(default)]
    pub key: Vec<Spanned<KeySpec>>,
    #[serde(default)]
    pub capture: Vec<Spanned<CaptureSpec>>,
    #[serde(default)]
    pub display: DisplaySpec,
    pub head: Option<super::head::HeadSpec>,
    #[serde(default)]
    pub virtual_clay: VirtualClaySpec,
    pub input: Option<InputSpec>,
    #[serde(default)]
    pub lattice: Vec<Spanned<super::lattice::LatticeFile>>,
    #[serde(default)]
    pub lattice_key: Vec<Spanned<super::lattice::LatticeKeyFile>>,
    pub symmetry: Option<Spanned<super::symmetry::SymmetryFile>>,
    #[serde(default)]
    pub region: Vec<Spanned<super::region::RegionFile>>,
    #[serde(default)]
    pub part: Vec<Spanned<super::part::PartFile>>,
}

/// `[input]`: the desk input settings file the scene asks for.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct InputSpec {
    pub settings: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct VirtualClaySpec {
    #[serde(default = "one")]
    pub fluidity: f32,
    #[serde(default = "clay_step")]
    pub step_s: f32,
    pub table_y_m: Option<f32>,
    #[serde(default)]
    pub fixed_boxes_m: Vec<[[f32; 3]; 2]>,
}

impl Default for VirtualClaySpec {
    fn default() -> Self {
        Self { fluidity: 1.0, step_s: clay_step(), table_y_m: None, fixed_boxes_m: Vec::new() }
    }
}

fn clay_step() -> f32 {
    1.0 / 60.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FieldSpec {
    #[serde(default = "default_voxel")]
    pub voxel_size_m: f32,
    #[serde(default = "default_iso")]
    pub iso: f32,
}

impl Default for FieldSpec {
    fn default() -> Self {
        Self { voxel_size_m: default_voxel(), iso: default_iso() }
    }
}

fn default_voxel() -> f32 {
    0.002
}
fn default_iso() -> f32 {
    0.5
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct OutputSpec {
    #[serde(default = "default_size")]
    pub width_px: u32,
    #[serde(default = "default_size")]
    pub height_px: u32,
    #[serde(default = "default_samples")]
    pub samples: u32,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self { width_px: default_size(), height_px: default_size(), samples: default_samples() }
    }
}

fn default_size() -> u32 {
    1024
}
fn default_samples() -> u32 {
    4
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraSpec {
    #[serde(default = "default_eye")]
    pub eye_m: [f32; 3],
    #[serde(default)]
    pub target_m: [f32; 3],
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    #[serde(default = "default_fov")]
    pub fov_y_deg: f32,
    #[serde(default = "default_interaxial")]
    pub interaxial_m: f32,
    /// Defaults to the distance from the eye to the target.
    pub convergence_m: Option<f32>,
    #[serde(default = "default_near")]
    pub near_m: f32,
    #[serde(default = "default_far")]
    pub far_m: f32,
}

impl Default for CameraSpec {
    fn default() -> Self {
        Self {
            eye_m: default_eye(),
            target_m: [0.0; 3],
            up: default_up(),
            fov_y_deg: default_fov(),
            interaxial_m: default_interaxial(),
            convergence_m: None,
            near_m: default_near(),
            far_m: default_far(),
        }
    }
}

fn default_eye() -> [f32; 3] {
    [0.0, 0.0, 0.6]
}
fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn default_fov() -> f32 {
    35.0
}
fn default_interaxial() -> f32 {
    0.063
}
fn default_near() -> f32 {
    0.05
}
fn default_far() -> f32 {
    20.0
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug, Default)]
#[serde(rename_all = "snake_case")]
pub(super) enum EnvironmentKind {
    #[default]
    Studio,
    Image,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct EnvironmentSpec {
    #[serde(default)]
    pub kind: EnvironmentKind,
    pub path: Option<String>,
    #[serde(default = "one")]
    pub intensity: f32,
    #[serde(default = "yes")]
    pub show: bool,
    #[serde(default = "default_background")]
    pub background: SceneColour,
}

impl Default for EnvironmentSpec {
    fn default() -> Self {
        Self {
            kind: EnvironmentKind::Studio,
            path: None,
            intensity: 1.0,
            show: true,
            background: default_background(),
        }
    }
}

fn one() -> f32 {
    1.0
}
fn yes() -> bool {
    true
}
fn default_background() -> SceneColour {
    SceneColour([0.02, 0.02, 0.025])
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialSpec {
    #[serde(default = "default_shininess")]
    pub shininess: f32,
    #[serde(default = "default_specular")]
    pub specular: f32,
    #[serde(default = "default_reflectivity")]
    pub reflectivity: f32,
    #[serde(default = "default_ambient")]
    pub ambient: f32,
}

impl Default for MaterialSpec {
    fn default() -> Self {
        Self {
            shininess: default_shininess(),
            specular: default_specular(),
            reflectivity: default_reflectivity(),
            ambient: default_ambient(),
        }
    }
}

fn default_shininess() -> f32 {
    48.0
}
fn default_specular() -> f32 {
    0.35
}
fn default_reflectivity() -> f32 {
    0.08
}
fn default_ambient() -> f32 {
    0.35
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct StageSpec {
    #[serde(default = "yes")]
    pub show: bool,
    #[serde(default = "default_stage_min")]
    pub min_m: [f32; 3],
    #[serde(default = "default_stage_max")]
    pub max_m: [f32; 3],
    #[serde(default = "default_stage_colour")]
    pub colour: SceneColour,
}

impl Default for StageSpec {
    fn default() -> Self {
        Self {
            show: true,
            min_m: default_stage_min(),
            max_m: default_stage_max(),
            colour: default_stage_colour(),
        }
    }
}

fn default_stage_min() -> [f32; 3] {
    [-0.3, -0.15, -0.3]
}
fn default_stage_max() -> [f32; 3] {
    [0.3, 0.35, 0.3]
}
fn default_stage_colour() -> SceneColour {
    SceneColour([0.18, 0.18, 0.2])
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TimelineSpec {
    #[serde(default = "default_step")]
    pub step_s: Spanned<f32>,
}

impl Default for TimelineSpec {
    fn default() -> Self {
        Self { step_s: default_step() }
    }
}

fn default_step() -> Spanned<f32> {
    Spanned::new(0..0, 1.0 / 90.0)
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub(super) enum ShapeKind {
    Sphere,
    Box,
    RoundedBox,
    Cylinder,
    Torus,
    Bar,
    Slab,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug, Default)]
#[serde(rename_all = "snake_case")]
pub(super) enum OpSpec {
    #[default]
    Union,
    Difference,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ClaySpec {
    pub shape: ShapeKind,
    #[serde(default)]
    pub op: OpSpec,
    #[serde(default)]
    pub position_m: [f32; 3],
    #[serde(default)]
    pub rotation_deg: [f32; 3],
    #[serde(default = "one")]
    pub scale: f32,
    pub colour: Option<SceneColour>,
    pub radius_m: Option<f32>,
    pub size_m: Option<[f32; 3]>,
    pub corner_radius_m: Option<f32>,
    pub height_m: Option<f32>,
    pub major_radius_m: Option<f32>,
    pub minor_radius_m: Option<f32>,
    pub length_m: Option<f32>,
    pub thickness_m: Option<f32>,
    pub part: Option<String>,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub(super) enum LightKind {
    Directional,
    Point,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug, Default)]
#[serde(rename_all = "snake_case")]
pub(super) enum AttachSpec {
    #[default]
    Scene,
    Viewer,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LightSpec {
    pub kind: LightKind,
    pub direction: Option<[f32; 3]>,
    pub position_m: Option<[f32; 3]>,
    #[serde(default = "white")]
    pub colour: SceneColour,
    #[serde(default = "one")]
    pub intensity: f32,
    #[serde(default)]
    pub attached_to: AttachSpec,
}

fn white() -> SceneColour {
    SceneColour([1.0; 3])
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub(super) enum ToolShapeSpec {
    Sphere,
    Ellipsoid,
    Box,
    Cylinder,
    Torus,
    Freeform,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub(super) enum FalloffSpec {
    Wyvill,
    Box,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub(super) enum ActionSpec {
    #[serde(alias = "toothpaste")]
    Add,
    #[serde(alias = "eraser")]
    Remove,
    #[serde(alias = "heat_gun", alias = "soft_eraser")]
    SoftRemove,
    Build,
    Paint,
    SoftPaint,
    #[serde(alias = "sandpaper")]
    Smooth,
    #[serde(alias = "print")]
    Stamp,
    Inflate,
    Deflate,
    Push,
    Support,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ToolSpec {
    pub name: String,
    #[serde(default = "sphere")]
    pub shape: ToolShapeSpec,
    pub radius_m: Option<f32>,
    pub radii_m: Option<[f32; 3]>,
    pub falloff: Option<FalloffSpec>,
    pub size_m: Option<[f32; 3]>,
    pub height_m: Option<f32>,
    pub major_radius_m: Option<f32>,
    pub minor_radius_m: Option<f32>,
    pub region_min_m: Option<[f32; 3]>,
    pub region_max_m: Option<[f32; 3]>,
    #[serde(default = "unit_scale")]
    pub scale: [f32; 3],
    pub action: ActionSpec,
    pub rate_per_s: Option<f32>,
    pub centre_weight: Option<f32>,
    pub speed_m_per_s: Option<f32>,
    pub s: Option<f32>,
    pub m: Option<f32>,
    pub r: Option<f32>,
    pub k: Option<f32>,
    pub n: Option<f32>,
    pub falloff_m: Option<f32>,
    #[serde(default = "default_tool_colour")]
    pub colour: SceneColour,
    #[serde(default = "default_spacing")]
    pub spacing: f32,
    pub level_samples: Option<f32>,
    #[serde(default = "default_opacity")]
    pub glyph_opacity: f32,
}

fn sphere() -> ToolShapeSpec {
    ToolShapeSpec::Sphere
}
fn unit_scale() -> [f32; 3] {
    [1.0; 3]
}
fn default_tool_colour() -> SceneColour {
    SceneColour([0.5, 0.5, 0.5])
}
fn default_spacing() -> f32 {
    0.25
}
fn default_opacity() -> f32 {
    0.3
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug, Hash)]
#[serde(rename_all = "snake_case")]
pub(super) enum HandSpec {
    Left,
    Right,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct KeySpec {
    pub time_s: f32,
    #[serde(default = "right")]
    pub hand: HandSpec,
    pub tool: String,
    pub position_m: [f32; 3],
    #[serde(default)]
    pub rotation_deg: [f32; 3],
    #[serde(default)]
    pub active: bool,
    pub part: Option<String>,
}

fn right() -> HandSpec {
    HandSpec::Right
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CaptureSpec {
    pub name: String,
    pub time_s: f32,
    #[serde(default = "yes")]
    pub show_tools: bool,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct DisplaySpec {
    pub mode: Option<crate::stereo::display::DisplayMode>,
    #[serde(default)]
    pub parity: crate::stereo::display::Parity,
    #[serde(default)]
    pub swap_eyes: bool,
    #[serde(default)]
    pub floating_window: bool,
    pub fallback: Option<Spanned<String>>,
    #[serde(default)]
    pub fullscreen: bool,
    pub monitor: Option<crate::scene::screen::MonitorName>,
}
