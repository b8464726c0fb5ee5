//! The interactive station: a window where the scene plays and the user sculpts, at the
//! display's rate.
//!
//! Each frame runs the stages in the order of the data flow: input (window events or a
//! scripted input file) → tools (the scene's scripted hands and the desk tool) → field →
//! incremental mesh of the dirty bricks → stereo render → present. Key bindings come from
//! `calibration/keys.toml` (see [`crate::config`]); the mouse turns the scene with a virtual
//! trackball or places the desk tool on a plane through it ([`MouseNavigator`]).
//!
//! With `frames` set, the station plays that many frames with a fixed time step of 1/60 s
//! (so a scripted run gives the same pictures on every machine), optionally writes a
//! screenshot of the last frame, and closes.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use serde::Deserialize;
use toml::Spanned;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalPosition;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::monitor::MonitorHandle;
use winit::window::{Fullscreen, Window, WindowId};

use super::monitor::{frame_sequential_notice, pick_monitor, Monitor};

mod calibrating;
mod desk_controls;
mod lattice;
mod stereo_view;

use desk_controls::DeskControls;
use stereo_view::{Budgeted, StereoView};

pub use calibrating::AdjustTarget;

use super::document::Document;
use super::environment::load_environment;
use super::frame::build_frame;
use super::glyphs::tool_glyph;
use super::held_region::{selection_said, RegionTool, SWELL_STEP_M};
use super::panel_rows::{self, action_cycle, shape_cycle, shape_name};
use super::playback::Playback;
use super::recent::RecentSculpts;
use crate::config::{Chord, KeyBindings, Modifiers, StationAction};
use crate::input::clutch::{Clutch, ClutchGains};
use crate::input::desk::{DeskInput, FrameInput};
use crate::input::gamepad::{Contact, ContactFeedback, GamepadMotion, Gamepads, Rumble};
use crate::input::motion::{ActionEvent, DeviceClass, InputAction, Rates, Target, TargetPoses};
use crate::input::mouse::{MouseButton, MouseEvent, MouseMode, MouseNavigator};
use crate::input::opentrack::OpentrackHead;
use crate::input::reader::{HidSource, Mailbox, ReaderConfig, ReaderHandle};
use crate::input::settings::InputSettings;
use crate::input::spacenav::{Protocol, SpacenavSource, DEFAULT_SOCKET};
use crate::io::autosave::{Autosave, AutosaveConfig};
use crate::io::StoredView;
use crate::math::{Pose, Quat, Vec2, Vec3, Vec4};
use crate::mesh::Mesher;
use crate::parts::{RegionOp, SymmetrySwitch};
use crate::render::{Light, Presented, Renderer, RendererDesc, ValidationLog};
use crate::scene::ScreenCalibration;
use crate::scene::{line_column, FileError, Scene};
use crate::stereo::comfort::AutoConvergence;
use crate::stereo::display::{choose_mode, DisplayMode, Parity};
use crate::stereo::floating::FloatingWindow;
use crate::stereo::{HeadTrackedRig, StereoRig};
use crate::tool::{Action, Stroke, Tool, ToolShape, HAND_SIZE_SAMPLES};
use crate::ui::{DeviceRow, Disparity, Panel, PanelCommand, PanelKey, PanelView, PointerEvent, StereoRow};

/// The time step of a scripted run, seconds.
pub const SCRIPTED_STEP_S: f32 = 1.0 / 60.0;
/// How fast held pointer keys move the desk tool, metres per second.
const POINTER_SPEED_M_PER_S: f32 = 0.1;
/// How much one press of bigger/smaller scales the desk tool.
const SIZE_STEP: f32 = 1.25;
/// How much one press moves the convergence plane or changes the interaxial distance.
const STEREO_STEP: f32 = 1.1;
/// The most step names the panel's history keeps.
const STEP_NAMES_KEPT: usize = 256;

/// How the station runs.
#[derive(Clone, Debug, Default)]
pub struct StationOptions {
    /// Close after this many frames, stepping time by [`SCRIPTED_STEP_S`] per frame.
    pub frames: Option<u64>,
    /// Write what the window shows in the last frame to this PNG.
    pub screenshot: Option<PathBuf>,
    /// Scripted input events (see [`InputScript`]).
    pub script: Option<PathBuf>,
    /// Key bindings read over the shipped ones.
    pub keys: Option<PathBuf>,
    /// Where `save` writes the sculpt.
    pub save_to: Option<PathBuf>,
    /// Window size in pixels (the scene's output size when absent).
    pub window_px: Option<(u32, u32)>,
    /// Run with the Vulkan validation layer; any message it reports fails the run.
    pub validation: bool,
    /// The display mode (the scene's `[display] mode` when absent, else anaglyph).
    pub display_mode: Option<DisplayMode>,
    /// Track the head with opentrack's UDP datagrams on this address (head-tracked views of the
    /// scene's screen calibration, else the shipped `calibration/screen.toml`).
    pub opentrack: Option<std::net::SocketAddr>,
    /// The screen calibration (layered over the shipped `calibration/screen.toml`); the
    /// scene's `[head] calibration` when absent, else the shipped one.
    pub calibration: Option<PathBuf>,
    /// Journal every finished stroke (crash recovery), with these settings.
    pub autosave: Option<AutosaveConfig>,
    /// The scene's text, kept in the autosave snapshots.
    pub scene_toml: Option<String>,
    /// The desk input settings (targets, calibration files), read over the shipped
    /// `calibration/input.toml`; the user's `input.toml` in the configuration folder when
    /// absent.
    pub input: Option<PathBuf>,
    /// A sculpt file (`.argile`) to open at start: its clay replaces the scene's, and saving
    /// writes back to it.
    pub open: Option<PathBuf>,
    /// The folder the open key looks for sculpts in (the save file's folder when absent).
    pub open_dir: Option<PathBuf>,
    /// The desk tool edits the finest level whatever its size (by default one spanning more
    /// than [`HAND_SIZE_SAMPLES`] voxels edits the level its size chooses, unless its scene
    /// tool says which).
    pub edit_finest: bool,
    /// Each eye gets the other's image (as the scene's `[display] swap_eyes`).
    pub swap_eyes: bool,
    /// The floating window masks the side edges (as the scene's `[display] floating_window`).
    pub floating_window: bool,
    /// The window fills its monitor (as `[display] fullscreen`).
    pub fullscreen: bool,
    /// The monitor the window opens on (over the scene's and the calibration's).
    pub monitor: Option<crate::scene::MonitorName>,
    /// The sculpts recovered at start, with what each holds: the panel offers to open them.
    pub recovered: Vec<(PathBuf, String)>,
    /// The scene is a calibration's test pattern, and the keys adjust that calibration
    /// (`argile calibrate --adjust`): no panel, no tools.
    pub adjust: Option<AdjustTarget>,
}

/// How a station run ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StationReport {
    /// Frames shown.
    pub frames: u64,
    /// Where the screenshot went, if one was asked for.
    pub screenshot: Option<PathBuf>,
    /// Where the sculpt was saved, if it was.
    pub saved: Option<PathBuf>,
}

/// Why no window can be opened here (no display server named in the environment), or `None`
/// when one may be.
pub fn no_display_reason() -> Option<String> {
    let named = |v: &str| std::env::var_os(v).is_some_and(|s| !s.is_empty());
    if named("DISPLAY") || named("WAYLAND_DISPLAY") {
        None
    } else {
        Some("no display (neither DISPLAY nor WAYLAND_DISPLAY is set)".into())
    }
}

/// The most characters a scripted `type` event holds.
const MOST_TYPED: usize = 1000;

/// The panel's name for `key`, where a text field reads it.
fn panel_key(key: KeyCode) -> Option<PanelKey> {
    Some(match key {
        KeyCode::Backspace => PanelKey::Backspace,
        KeyCode::Delete => PanelKey::Delete,
        KeyCode::Enter | KeyCode::NumpadEnter => PanelKey::Enter,
        KeyCode::Escape => PanelKey::Escape,
        KeyCode::ArrowLeft => PanelKey::Left,
        KeyCode::ArrowRight => PanelKey::Right,
        KeyCode::Home => PanelKey::Home,
        KeyCode::End => PanelKey::End,
        _ => return None,
    })
}

/// One scripted input event.
#[derive(Clone, Debug, PartialEq)]
pub enum ScriptEvent {
    /// A chord pressed and released.
    Press(Chord),
    /// A key pressed and held (until a `Release`).
    Hold(KeyCode),
    /// A held key released.
    Release(KeyCode),
    /// A mouse drag with `button` from one pixel to another, in `steps` moves.
    Drag {
        /// The button held.
        button: MouseButton,
        /// Where the drag starts, window pixels.
        from_px: Vec2,
        /// Where it ends.
        to_px: Vec2,
        /// Mouse moves between them.
        steps: u32,
    },
    /// Wheel steps (positive: away from the user).
    Wheel(f32),
    /// The pointer moved to a pixel of the window.
    Move(Vec2),
    /// The left button pressed and released at a pixel of the window (the pointer moves there
    /// first).
    Click(Vec2),
    /// Text typed (into the panel's text field that has the keyboard).
    Text(String),
}

/// Input events at given frames, from a TOML file:
///
/// ```toml
/// [[event]]
/// frame = 3
/// press = "Ctrl+KeyZ"          # or hold = "Space", release = "Space", wheel = 2.0,
///                              # or drag = { button = "left", from_px = [10, 10], to_px = [60, 10] },
///                              # or click = [40, 30], move = [40, 30] (window pixels),
///                              # or type = "bust" (text, into the panel's text field)
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InputScript {
    /// `(frame, event)` in frame order (stable for events of the same frame).
    pub events: Vec<(u64, ScriptEvent)>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScriptFile {
    #[serde(default)]
    event: Vec<Spanned<EventSpec>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EventSpec {
    frame: u64,
    press: Option<String>,
    hold: Option<String>,
    release: Option<String>,
    wheel: Option<f32>,
    drag: Option<DragSpec>,
    click: Option<[f32; 2]>,
    #[serde(rename = "move")]
    move_to: Option<[f32; 2]>,
    #[serde(rename = "type")]
    typed: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DragSpec {
    button: String,
    from_px: [f32; 2],
    to_px: [f32; 2],
    #[serde(default = "default_drag_steps")]
    steps: u32,
}

fn default_drag_steps() -> u32 {
    8
}

impl InputScript {
    /// Parses a script; errors name `name`, the line and the column.
    pub fn parse(text: &str, name: &str) -> Result<Self, FileError> {
        let at = |span: std::ops::Range<usize>, message: String| {
            let (line, column) = line_column(text, span.start);
            FileError::Invalid { path: name.to_owned(), line, column, message }
        };
        let file: ScriptFile =
            crate::scene::parse_toml(text).map_err(|(span, message)| at(span.unwrap_or(0..0), message))?;
        let mut events = Vec::new();
        for spanned in &file.event {
            let e = spanned.get_ref();
            let span = spanned.span();
            let key = |name: &str| Chord::parse(name).map_err(|m| at(span.clone(), m));
            let mut parsed = Vec::new();
            if let Some(k) = &e.press {
                parsed.push(ScriptEvent::Press(key(k)?));
            }
            if let Some(k) = &e.hold {
                parsed.push(ScriptEvent::Hold(key(k)?.key));
            }
            if let Some(k) = &e.release {
                parsed.push(ScriptEvent::Release(key(k)?.key));
            }
            if let Some(w) = e.wheel {
                // A wheel turn is zoomed step by step: a hundred steps is far beyond any use.
                if !(w.is_finite() && w.abs() <= 100.0) {
                    return Err(at(span, format!("`wheel` must be -100 to 100 steps, not {w}")));
                }
                parsed.push(ScriptEvent::Wheel(w));
            }
            if let Some(d) = &e.drag {
                let button = match d.button.as_str() {
                    "left" => MouseButton::Left,
                    "right" => MouseButton::Right,
                    "middle" => MouseButton::Middle,
                    other => {
                        return Err(at(span, format!("drag button `{other}` is not left, right or middle")))
                    }
                };
                if !(1..=1000).contains(&d.steps) {
                    return Err(at(span, format!("drag steps must be 1 to 1000, not {}", d.steps)));
                }
                parsed.push(ScriptEvent::Drag {
                    button,
                    from_px: Vec2::from(d.from_px),
                    to_px: Vec2::from(d.to_px),
                    steps: d.steps,
                });
            }
            let pixel = |p: [f32; 2], what: &str| {
                if p.iter().all(|c| c.is_finite() && c.abs() <= 1e5) {
                    Ok(Vec2::from(p))
                } else {
                    Err(at(span.clone(), format!("`{what}` must be a window pixel, not {p:?}")))
                }
            };
            if let Some(p) = e.click {
                parsed.push(ScriptEvent::Click(pixel(p, "click")?));
            }
            if let Some(p) = e.move_to {
                parsed.push(ScriptEvent::Move(pixel(p, "move")?));
            }
            if let Some(text) = &e.typed {
                if text.chars().count() > MOST_TYPED {
                    return Err(at(span, format!("`type` holds at most {MOST_TYPED} characters")));
                }
                parsed.push(ScriptEvent::Text(text.clone()));
            }
            if parsed.len() != 1 {
                return Err(at(
                    span,
                    "an event gives exactly one of press, hold, release, wheel, drag, click, move or type"
                        .into(),
                ));
            }
            events.push((e.frame, parsed.remove(0)));
        }
        events.sort_by_key(|(frame, _)| *frame);
        Ok(Self { events })
    }

    /// Reads and parses a script file.
    pub fn load(path: &Path) -> Result<Self, FileError> {
        let text = crate::io::text::read_text(path, crate::io::text::SCENE_LIMIT)
            .map_err(|reason| FileError::Read { kind: "input script", path: path.to_owned(), reason })?;
        Self::parse(&text, &path.display().to_string())
    }
}

/// Where a station step spent its time, milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepTimes {
    /// The panel: laid out, its commands done, tessellated.
    pub panel_ms: f64,
    /// Keys held, pointer and view.
    pub input_ms: f64,
    /// The scripted hands' and the desk tool's strokes into the field.
    pub tools_ms: f64,
    /// Re-meshing the dirty bricks and handing the diff to the renderer.
    pub mesh_ms: f64,
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Views `t` of the way from `a` to `b` (0 to 1): the eyes' positions moved and their
/// orientations turned (slerp), the projections' terms blended, so that a change of view
/// (tracking starting) is eased rather than cut.
fn blend_views(
    a: &crate::render::StereoViews,
    b: &crate::render::StereoViews,
    t: f32,
) -> crate::render::StereoViews {
    let mut out = *b;
    for (o, (x, y)) in out.eyes.iter_mut().zip(a.eyes.iter().zip(&b.eyes)) {
        let (rx, ry) = (Quat::from_mat4(&x.view.inverse()), Quat::from_mat4(&y.view.inverse()));
        let position = x.position_m.lerp(y.position_m, t);
        let world_from_eye =
            crate::math::Mat4::from_rotation_translation(rx.slerp(ry, t).normalize(), position);
        o.view = world_from_eye.inverse();
        o.position_m = position;
        o.projection = x.projection * (1.0 - t) + y.projection * t;
    }
    out
}

/// The sculpt files (`.argile`) in `dir`, newest first (by modification time, then name).
fn sculpts_in(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let path = entry.path();
        if super::is_sculpt(&path) && entry.file_type().is_ok_and(|t| t.is_file()) {
            let modified = entry.metadata().and_then(|m| m.modified()).unwrap_or(std::time::UNIX_EPOCH);
            found.push((modified, path));
        }
    }
    found.sort_by(|a, b| b.0.cmp(&a.0).then_with(|| a.1.cmp(&b.1)));
    Ok(found.into_iter().map(|(_, p)| p).collect())
}

/// The sculpt the open key opens: the one after `last` in `list`, wrapping round; the first
/// when `last` is not in it.
fn next_sculpt<'l>(list: &'l [PathBuf], last: Option<&Path>) -> Option<&'l Path> {
    let next = last.and_then(|l| list.iter().position(|p| p == l)).map_or(0, |i| (i + 1) % list.len().max(1));
    list.get(next).map(PathBuf::as_path)
}

/// Where the targets start: the desk tool at the scene's target, the second tool 5 cm to
/// its left, the light and the scene where [`TargetPoses::default`] puts them.
fn home_poses(target_m: Vec3) -> TargetPoses {
    let mut poses = TargetPoses::default();
    poses.get_mut(Target::Tool).position_m = target_m;
    poses.get_mut(Target::SecondTool).position_m = target_m - Vec3::X * 0.05;
    poses
}

/// Whether a tool at `pose` of `half_extents_m` touches the clay of `field`, and the mean
/// density under it: the field sampled at the tool's centre and at both ends of its three
/// axes; it touches where a sample reaches the iso-level.
fn contact_under(field: &crate::field::Field, pose: Pose, half_extents_m: Vec3) -> (bool, f32) {
    let mut reader = crate::field::FieldReader::new(field);
    let transform = field.transform();
    let h = half_extents_m;
    let points = [
        Vec3::ZERO,
        Vec3::X * h.x,
        Vec3::X * -h.x,
        Vec3::Y * h.y,
        Vec3::Y * -h.y,
        Vec3::Z * h.z,
        Vec3::Z * -h.z,
    ];
    let (mut sum, mut max) = (0.0f32, 0.0f32);
    for p in points {
        let d = reader.density_at(transform.world_to_index(pose.position_m + pose.rotation * p));
        sum += d;
        max = max.max(d);
    }
    (max >= field.iso(), sum / points.len() as f32)
}

/// The station's state between frames, without the window and renderer.
#[derive(Debug)]
pub struct Station<'s> {
    scene: &'s Scene,
    /// The scene as drawn: its rig follows the mouse and the stereo keys.
    view: Scene,
    /// The sculpt: its clay, history, file and autosave session.
    doc: Document<'s>,
    /// The desk's controls: keys, mouse, 3D cursor and clutch, SpaceMice, pads, rumble.
    controls: DeskControls,
    /// The stereo view: calibration, head, convergence, parallax budget, display mode.
    stereo: StereoView,
    /// Seconds since the station started (the devices' filters run on it).
    clock_s: f64,
    desk_tool: Tool,
    /// The most voxels across the desk tool's size on the level it edits, where its scene
    /// tool sets none (`None`: the finest level whatever its size).
    hand_samples: Option<f32>,
    /// Index of the scene tool the desk tool started from (`next-tool`).
    tool_index: usize,
    action_index: usize,
    stroke: Option<Stroke>,
    /// The clay's bounds: those of the surface the renderer draws, updated as it changes.
    clay_bounds: crate::math::Aabb,
    /// That surface's chunks' bounds and a few of their vertices.
    surface: crate::mesh::SurfaceSketch,
    /// The surface as the renderer holds it, for the panel's exports, and the one under way.
    exports: super::export::Exports,
    /// The symmetry the desk tool and the scene's hands act through.
    symmetry: SymmetrySwitch,
    /// The active part's placement when the device driving the `part` target was last at home.
    part_base: crate::parts::Placement,
    /// While that device moves the part: where the part was when it began (one undo step
    /// once it stops).
    part_moving: Option<crate::parts::Placement>,
    /// While the box selection's key is held: where the tool was when it went down (world).
    box_from: Option<Vec3>,
    /// Seconds the active part's box is still drawn (after it was picked or moved).
    part_shown_s: f32,
    /// Whether the window fills its monitor, and a change the window has yet to make.
    fullscreen: bool,
    fullscreen_asked: Option<bool>,
    /// Where the open key looks for sculpts, and the sculpt it will open at the next press
    /// despite unsaved work (the user was warned).
    open_dir: PathBuf,
    confirm_open: Option<PathBuf>,
    /// The sculpts saved or opened last (the panel lists them).
    recent: RecentSculpts,
    /// The sculpts recovered at start, with what each holds, until the panel dismisses them.
    recovered: Vec<(PathBuf, String)>,
    quit: bool,
    frame_ms: f32,
    times: StepTimes,
    /// Messages for the user (saved, undo had nothing, ...).
    pub messages: Vec<String>,
    /// Re-meshes what each frame's edits dirtied, reusing its buffers from frame to frame.
    mesher: Mesher,
    /// The desk panel, and whether the left button went down on it (its release is then the
    /// panel's too).
    panel: Panel,
    panel_press: bool,
    /// Names of the desk's undo steps, oldest first, and of those undone, next last (the
    /// panel's history; steps it did not see, a scene's, are numbered instead).
    step_names: Vec<String>,
    redo_names: Vec<String>,
    /// The screen calibration being adjusted on its test pattern (`argile calibrate --adjust`).
    adjusting: Option<calibrating::Adjusting>,
}

impl<'s> Station<'s> {
    /// The station on `scene` at time 0, for a window of `window_px`.
    pub fn new(scene: &'s Scene, bindings: KeyBindings, window_px: (u32, u32), save_to: PathBuf) -> Self {
        Self::on_playback(scene, Playback::new(scene), bindings, window_px, save_to)
    }

    /// As [`Station::new`], its initial clay built as [`Playback::new_autosaved`] builds it
    /// (within the memory budget, with progress, stopped by a signal), journaling every
    /// finished stroke with the autosave session `start` opens on it (given the scene's
    /// freeform tools).
    pub fn new_autosaved(
        scene: &'s Scene,
        bindings: KeyBindings,
        window_px: (u32, u32),
        save_to: PathBuf,
        start: impl FnOnce(&mut crate::field::Field, crate::io::autosave::Besides<'_>) -> Option<Autosave>,
    ) -> anyhow::Result<Self> {
        let playback = Playback::new_autosaved(scene, start)?;
        Ok(Self::on_playback(scene, playback, bindings, window_px, save_to))
    }

    /// The station on `playback` of `scene`, for a window of `window_px`.
    fn on_playback(
        scene: &'s Scene,
        playback: Playback<'s>,
        bindings: KeyBindings,
        window_px: (u32, u32),
        save_to: PathBuf,
    ) -> Self {
        let rig = scene.rig;
        let distance = (rig.eye_m - rig.target_m).length();
        let settings = InputSettings::shipped();
        let mut mouse = MouseNavigator::new(
            settings.mouse.0,
            Vec2::new(window_px.0 as f32, window_px.1 as f32),
            distance,
        );
        mouse.tool_position_m = rig.target_m;
        let home = home_poses(rig.target_m);
        let mut desk = DeskInput::new(settings.spacemouse.0, settings.mapping, Rates::default());
        desk.poses = home;
        let desk_tool = playback
            .tools()
            .first()
            .cloned()
            .unwrap_or_else(|| Tool::new(ToolShape::sphere(0.02), Action::Add, [0.8, 0.5, 0.35, 1.0]));
        let action_index = action_cycle().iter().position(|a| *a == desk_tool.action).unwrap_or(0);
        let open_dir = save_to
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .map_or_else(|| PathBuf::from("."), Path::to_owned);
        let mut station = Self {
            scene,
            view: scene.clone(),
            doc: Document::new(playback, save_to),
            controls: DeskControls {
                bindings,
                mouse,
                desk,
                mailbox: None,
                device_apply: false,
                device_clutch: false,
                cursor_clutch: None,
                home,
                mouse_turn: Quat::IDENTITY,
                feedback: None,
                rumble: None,
                modifiers: Modifiers::default(),
                held: HashSet::new(),
                pointer_px: Vec2::ZERO,
                gamepad_names: Vec::new(),
            },
            stereo: StereoView::new(scene, window_px),
            clock_s: 0.0,
            desk_tool,
            hand_samples: Some(HAND_SIZE_SAMPLES),
            tool_index: 0,
            action_index,
            stroke: None,
            symmetry: SymmetrySwitch::new(scene.symmetry),
            part_base: scene.parts[0].placement,
            box_from: None,
            part_moving: None,
            part_shown_s: 0.0,
            fullscreen: false,
            fullscreen_asked: None,
            clay_bounds: crate::math::Aabb::EMPTY,
            surface: crate::mesh::SurfaceSketch::default(),
            exports: super::export::Exports::default(),
            open_dir,
            confirm_open: None,
            recent: RecentSculpts::default(),
            recovered: Vec::new(),
            quit: false,
            frame_ms: 0.0,
            times: StepTimes::default(),
            messages: Vec::new(),
            mesher: Mesher::default(),
            // Hidden until the window shows it (`run_station`): a station without one has no use
            // for it.
            panel: Panel::hidden(),
            panel_press: false,
            step_names: Vec::new(),
            redo_names: Vec::new(),
            adjusting: None,
        };
        station.set_calibration(station.stereo.calibration);
        station.resize(window_px);
        station
    }

    /// Lets the desk tool edit by its size with at most `samples` voxels across it where its
    /// scene tool does not say which level it edits (`None`: always the finest level). The
    /// default is [`HAND_SIZE_SAMPLES`].
    pub fn set_hand_samples(&mut self, samples: Option<f32>) {
        self.hand_samples = samples;
    }

    /// The desk tool as it acts on the clay (see [`Station::set_hand_samples`]).
    fn acting_tool(&self) -> Tool {
        self.desk_tool.clone().by_size_unless_set(self.hand_samples)
    }

    /// Uses `calibration` for the display, the screen and the viewer: its display mode unless
    /// the scene names one, and its interlace parity.
    pub fn set_calibration(&mut self, calibration: ScreenCalibration) {
        self.stereo.calibration = calibration;
        self.stereo.tracked_interaxial_m = calibration.ipd_m;
        self.stereo.display_mode =
            self.scene.display.mode.or(calibration.display.mode).unwrap_or(DisplayMode::Anaglyph);
        self.fit_views();
    }

    /// Uses the desk input settings: the targets each device family drives, the SpaceMouse
    /// calibration and the mouse settings (the gamepads' mapping goes to [`Gamepads`]). A mouse
    /// that drives the tool starts as its 3D cursor.
    pub fn set_input_settings(&mut self, settings: &InputSettings) {
        self.controls.desk.mapping = settings.mapping;
        self.controls.desk.calibration = settings.spacemouse.0;
        let mouse = settings.mouse.0;
        self.controls.mouse.settings = mouse;
        self.controls.mouse.distance_m =
            self.controls.mouse.distance_m.clamp(mouse.min_distance_m, mouse.max_distance_m);
        if settings.mapping.target(DeviceClass::Mouse) == Target::Tool {
            self.controls.mouse.mode = MouseMode::Cursor;
        }
    }

    /// Device family `class` drives `target` from now on; a mouse set to the tool becomes its
    /// 3D cursor, one set to the scene turns it again.
    fn set_device_target(&mut self, class: DeviceClass, target: Target) {
        self.controls.desk.mapping.set(class, target);
        if class == DeviceClass::Mouse {
            self.controls.mouse.mode =
                if target == Target::Tool { MouseMode::Cursor } else { MouseMode::Scene };
            self.controls.cursor_clutch = None;
        }
        self.messages.push(format!(
            "the {} drives the {} now",
            class.name(),
            target.name().replace('_', " ")
        ));
    }

    /// The names of the gamepads connected now (the window's gamepad library lists them).
    pub fn set_gamepad_names(&mut self, names: Vec<String>) {
        self.controls.gamepad_names = names;
    }

    /// The 3D cursor's clutch (Galyean–Hughes §2.2.2) after a mouse event that moved the tool
    /// from `tool_before`, `placed` under the pointer or not (the wheel moves it in depth):
    /// while the clutch is held the tool stays; once it has been held, the tool follows the
    /// pointer's motion from where it is, scaled by the mouse's clutch gain, instead of jumping
    /// under the pointer.
    fn clutch_cursor(&mut self, tool_before: Vec3, placed: bool) {
        if self.controls.mouse.mode != MouseMode::Cursor {
            return;
        }
        let held = self.controls.device_clutch || self.holding(StationAction::Clutch);
        let gains = ClutchGains { translation: self.controls.mouse.settings.clutch_gain, rotation: 1.0 };
        let at = |position_m: Vec3| Pose { position_m, rotation: Quat::IDENTITY };
        let clutch = match &mut self.controls.cursor_clutch {
            Some(c) => c,
            None if held => self.controls.cursor_clutch.insert(Clutch::new(at(tool_before), gains)),
            None => return,
        };
        if !placed {
            // Not a pointer sample: the tool stays where the event put it.
            if clutch.tool().position_m != self.controls.mouse.tool_position_m {
                clutch.set_tool(at(self.controls.mouse.tool_position_m));
            }
            return;
        }
        if clutch.tool().position_m != tool_before {
            // Another device moved the tool since: carry on from there.
            clutch.set_tool(at(tool_before));
        }
        clutch.set_gains(gains);
        self.controls.mouse.tool_position_m =
            clutch.update(at(self.controls.mouse.tool_position_m), held).position_m;
    }

    /// The rumble contact feedback asked for since the last call, if any (see
    /// [`ContactFeedback`]): the window plays it on the pads that have force feedback.
    pub fn take_rumble(&mut self) -> Option<Rumble> {
        self.controls.rumble.take()
    }

    /// The clay.
    pub fn field(&self) -> &crate::field::Field {
        self.doc.playback.field()
    }

    /// Whether the user asked to close.
    pub fn wants_quit(&self) -> bool {
        self.quit
    }

    /// The window fills its monitor (as it opened), or not.
    pub fn set_fullscreen(&mut self, on: bool) {
        self.fullscreen = on;
    }

    /// Whether the window is to fill its monitor, once, after the user asked for a change.
    pub fn take_fullscreen_request(&mut self) -> Option<bool> {
        self.fullscreen_asked.take()
    }

    /// The window changed size.
    pub fn resize(&mut self, window_px: (u32, u32)) {
        self.stereo.window_px = window_px;
        self.fit_views();
    }

    /// The frame's views take their aspect from the output size: each eye's part of the window
    /// in the display mode; the mouse reads the pointer in that eye's picture.
    fn fit_views(&mut self) {
        let ((w, h), picture) = self.stereo.eye_pictures();
        (self.view.output.width_px, self.view.output.height_px) = (w, h);
        self.controls.mouse.resize(picture);
    }

    /// The modifiers held now.
    pub fn set_modifiers(&mut self, modifiers: Modifiers) {
        self.controls.modifiers = modifiers;
    }

    /// A key went down or up.
    pub fn key(&mut self, key: KeyCode, pressed: bool) {
        if !pressed {
            self.controls.held.remove(&key);
        }
        if self.panel.wants_keyboard() {
            // A text field of the panel has the keyboard: keys edit it, none is a binding.
            if let Some(key) = panel_key(key) {
                self.panel.key(key, pressed);
            }
            return;
        }
        if !pressed {
            return;
        }
        if !self.controls.held.insert(key) {
            return; // auto-repeat
        }
        if let Some(action) = self
            .controls
            .bindings
            .action(key, self.controls.modifiers)
            .or_else(|| self.adjusting_step_key(key))
        {
            self.act(action);
        }
    }

    /// Text typed: it goes to the panel's text field that has the keyboard, if one has.
    pub fn text(&mut self, text: &str) {
        if self.panel.wants_keyboard() {
            self.panel.text(text);
        }
    }

    /// A mouse event, in window pixels: read in the picture of the eye the pointer is over.
    pub fn mouse(&mut self, event: MouseEvent) {
        if let MouseEvent::Move(at) = event {
            self.controls.pointer_px = at;
        }
        if self.panel_takes(event) {
            return;
        }
        let in_eye = |p: Vec2| self.stereo.in_eye(p);
        let event = match event {
            MouseEvent::Press(button, at) => MouseEvent::Press(button, in_eye(at)),
            MouseEvent::Move(at) => MouseEvent::Move(in_eye(at)),
            other => other,
        };
        let aspect = self.view.output.width_px as f32 / self.view.output.height_px as f32;
        let views = self.view.rig.views(aspect);
        let eye = &views.eyes[0];
        let inverse = (eye.projection * eye.view).inverse();
        let before = self.controls.mouse.scene_rotation;
        let tool_before = self.controls.mouse.tool_position_m;
        self.controls.mouse.handle(event, &inverse, self.view.rig.forward());
        let placed = match event {
            MouseEvent::Press(MouseButton::Left, _) => true,
            MouseEvent::Move(_) => self.controls.mouse.left_held(),
            _ => false,
        };
        self.clutch_cursor(tool_before, placed);
        if self.controls.mouse.mode == MouseMode::Scene
            && self.controls.desk.mapping.target(DeviceClass::Mouse) != Target::Scene
        {
            // The trackball turns the mouse's own target instead: its turn, from the view's
            // frame to the world's, goes to the desk with the other devices' motion.
            let turn = self.controls.mouse.scene_rotation * before.inverse();
            self.controls.mouse.scene_rotation = before;
            let view = Quat::from_mat4(&self.view.rig.centre_view().inverse());
            self.controls.mouse_turn = (view * turn * view.inverse() * self.controls.mouse_turn).normalize();
        }
        self.controls.desk.poses.get_mut(Target::Tool).position_m = self.controls.mouse.tool_position_m;
    }

    /// Where the pointer was last seen, window pixels.
    pub fn pointer_px(&self) -> Vec2 {
        self.controls.pointer_px
    }

    /// Tracks the viewer's head with `head` (opentrack): the views become head-tracked
    /// through the screen calibration's screen.
    pub fn attach_head(&mut self, head: OpentrackHead) {
        self.stereo.head = Some(head);
    }

    /// The screen calibration in use.
    fn screen_calibration(&self) -> ScreenCalibration {
        self.stereo.calibration
    }

    /// Reads SpaceMouse events and states from `mailbox` (filled by a reader thread).
    pub fn attach_spacemice(&mut self, mailbox: Arc<Mailbox>) {
        self.controls.mailbox = Some(mailbox);
    }

    /// One frame of the 6-DoF devices: drains the SpaceMice, integrates their motion and the
    /// gamepads' into the targets they drive, and acts on their buttons (`actions` holds what
    /// the gamepads' buttons did this frame).
    pub fn devices(&mut self, dt_s: f32, gamepads: &[GamepadMotion], mut actions: Vec<ActionEvent>) {
        self.clock_s += f64::from(dt_s);
        let view_rotation = Quat::from_mat4(&self.view.rig.centre_view().inverse());
        let mouse_turn = std::mem::replace(&mut self.controls.mouse_turn, Quat::IDENTITY);
        let input = FrameInput { t_s: self.clock_s, dt_s, view_rotation, gamepads, mouse_turn };
        let first_new = actions.len();
        self.controls.desk.update(self.controls.mailbox.as_deref(), &input, &mut actions);
        for (i, a) in actions.iter().enumerate() {
            // The desk already applied its own devices' actions to itself; the gamepads' go
            // through it here (a gamepad's CycleTarget switches the gamepad's target).
            if i < first_new {
                self.controls.desk.apply_action(*a);
            }
            let station_action = match a.action {
                InputAction::Stroke => {
                    self.controls.device_apply = a.pressed;
                    None
                }
                InputAction::Undo => Some(StationAction::Undo),
                InputAction::Redo => Some(StationAction::Redo),
                InputAction::ResetView => Some(StationAction::ResetView),
                InputAction::NextTool => Some(StationAction::NextTool),
                InputAction::Clutch => {
                    self.controls.device_clutch = a.pressed;
                    None
                }
                InputAction::CycleTarget | InputAction::None => None,
            };
            if let (Some(action), true) = (station_action, a.pressed) {
                self.act(action);
            }
        }
        self.controls.mouse.tool_position_m = self.controls.desk.poses.get(Target::Tool).position_m;
    }

    /// A scripted event.
    pub fn script(&mut self, event: &ScriptEvent) {
        match *event {
            ScriptEvent::Text(ref text) => self.text(text),
            ScriptEvent::Press(chord) => {
                let saved = self.controls.modifiers;
                self.controls.modifiers = chord.modifiers;
                self.key(chord.key, true);
                self.key(chord.key, false);
                self.controls.modifiers = saved;
            }
            ScriptEvent::Hold(key) => self.key(key, true),
            ScriptEvent::Release(key) => self.key(key, false),
            ScriptEvent::Wheel(steps) => self.mouse(MouseEvent::Wheel(steps)),
            ScriptEvent::Move(at) => self.mouse(MouseEvent::Move(at)),
            ScriptEvent::Click(at) => {
                self.mouse(MouseEvent::Move(at));
                self.mouse(MouseEvent::Press(MouseButton::Left, at));
                self.mouse(MouseEvent::Release(MouseButton::Left));
            }
            ScriptEvent::Drag { button, from_px, to_px, steps } => {
                self.mouse(MouseEvent::Press(button, from_px));
                for i in 1..=steps {
                    self.mouse(MouseEvent::Move(from_px.lerp(to_px, i as f32 / steps as f32)));
                }
                self.mouse(MouseEvent::Release(button));
            }
        }
    }

    fn act(&mut self, action: StationAction) {
        if self.act_adjusting(action) || self.act_lattice(action) {
            return;
        }
        match action {
            StationAction::Quit => self.quit = true,
            StationAction::Undo => {
                self.stroke = None;
                match self.doc.playback.undo() {
                    Ok(true) => {
                        self.doc.journal();
                        self.rebase_part();
                        if let Some(name) = self.step_names.pop() {
                            self.redo_names.push(name);
                        }
                    }
                    Ok(false) => self.messages.push("nothing to undo".into()),
                    Err(e) => self.messages.push(format!("undo failed: {e}")),
                }
            }
            StationAction::Redo => {
                if self.doc.playback.redo() {
                    self.doc.journal();
                    self.rebase_part();
                    if let Some(name) = self.redo_names.pop() {
                        self.step_names.push(name);
                    }
                } else {
                    self.messages.push("nothing to redo".into());
                }
            }
            StationAction::Open => self.open_next(),
            StationAction::Save => match self.save() {
                Ok(path) => self.messages.push(format!("saved the sculpt to {}", path.display())),
                Err(e) => self.messages.push(format!("{e:#}")),
            },
            StationAction::NextTool => {
                let tools = self.doc.playback.tools();
                if !tools.is_empty() {
                    self.tool_index = (self.tool_index + 1) % tools.len();
                    let scale = self.desk_tool.scale;
                    self.desk_tool = Tool { scale, ..tools[self.tool_index].clone() };
                }
            }
            StationAction::NextShape => {
                let size = self.desk_tool.shape.half_extents_m().min_element();
                let cycle = shape_cycle(size);
                let at = cycle.iter().position(|(_, n)| *n == shape_name(&self.desk_tool.shape));
                let next = at.map_or(0, |i| (i + 1) % cycle.len());
                self.desk_tool.shape = cycle[next].0.clone();
            }
            StationAction::NextAction => {
                let cycle = action_cycle();
                self.action_index = (self.action_index + 1) % cycle.len();
                self.desk_tool.action = cycle[self.action_index];
            }
            StationAction::Bigger => self.desk_tool.scale *= SIZE_STEP,
            StationAction::Smaller => self.desk_tool.scale /= SIZE_STEP,
            StationAction::ConvergenceFarther => self.step_convergence(STEREO_STEP),
            StationAction::ConvergenceNearer => self.step_convergence(1.0 / STEREO_STEP),
            StationAction::InteraxialWider => self.step_interaxial(STEREO_STEP),
            StationAction::InteraxialNarrower => self.step_interaxial(1.0 / STEREO_STEP),
            StationAction::ToggleMouseMode => {
                self.controls.cursor_clutch = None;
                self.controls.mouse.mode = match self.controls.mouse.mode {
                    MouseMode::Scene => MouseMode::Cursor,
                    MouseMode::Cursor => MouseMode::Scene,
                }
            }
            StationAction::ToggleLights => {
                self.stereo.lights_follow_viewer = !self.stereo.lights_follow_viewer
            }
            StationAction::ToggleAutoConvergence => {
                self.stereo.auto_convergence = match self.stereo.auto_convergence {
                    Some(_) => None,
                    None => Some(AutoConvergence::new(
                        self.view.rig.convergence_m,
                        AutoConvergence::DEFAULT_TIME_CONSTANT_S,
                        (self.view.rig.near_m * 2.0, self.view.rig.far_m * 0.5),
                    )),
                };
            }
            StationAction::SwapEyes => {
                self.stereo.swap_eyes = !self.stereo.swap_eyes;
                self.messages.push(match self.stereo.swap_eyes {
                    true => "eyes swapped: the left eye's image goes to the right eye".to_owned(),
                    false => "eyes as rendered: the left eye's image goes to the left eye".to_owned(),
                });
            }
            StationAction::ToggleFloatingWindow => {
                self.stereo.floating_window.0 = !self.stereo.floating_window.0;
                self.messages.push(match self.stereo.floating_window.0 {
                    true => "floating window: the side edges are masked where clay in front of the screen touches them"
                        .to_owned(),
                    false => "floating window off: the pictures are shown whole".to_owned(),
                });
            }
            StationAction::InflateRegion | StationAction::DeflateRegion => {
                let out = action == StationAction::InflateRegion;
                let distance = if out { SWELL_STEP_M } else { -SWELL_STEP_M };
                let pose = self.controls.desk.poses.get(Target::Tool);
                match self.doc.playback.swell_region(self.desk_tool.clone(), pose, distance) {
                    Ok(()) => {
                        self.doc.edited();
                        self.stepped(RegionTool::Swell { out }.name().into());
                    }
                    Err(why) => self.messages.push(why),
                }
            }
            StationAction::CopyToPart => {
                let pose = self.controls.desk.poses.get(Target::Tool);
                match self.doc.playback.copy_to_new_part(self.desk_tool.clone(), pose) {
                    Ok(part) => {
                        self.doc.edited();
                        self.stepped("copy to part".into());
                        self.rebase_part();
                        self.part_shown_s = PART_SHOWN_S;
                        self.messages.push(format!(
                            "the region is copied into a new part: {}",
                            describe_part(self.doc.playback.assembly(), part)
                        ));
                    }
                    Err(why) => self.messages.push(why),
                }
            }
            StationAction::NextPart | StationAction::PreviousPart => {
                let count = self.doc.playback.assembly().parts().len();
                let now = self.doc.playback.assembly().active();
                let next = if action == StationAction::NextPart { now + 1 } else { now + count - 1 };
                self.pick_part(next);
            }
            StationAction::ToggleSymmetry | StationAction::NextSymmetry => {
                let symmetry = match action {
                    StationAction::ToggleSymmetry => self.symmetry.toggle(),
                    _ => self.symmetry.next_choice(),
                };
                self.doc.playback.set_symmetry(symmetry);
                self.messages.push(format!("symmetry {}", symmetry.describe()));
            }
            StationAction::FlipParity => {
                self.stereo.parity_flipped = !self.stereo.parity_flipped;
                self.messages.push(match self.stereo.display_mode {
                    DisplayMode::FrameSequential => format!(
                        "frame-sequential phase {}: the frames that showed the right eye show the left",
                        self.stereo.display_phase().name()
                    ),
                    _ => format!(
                        "interlace parity {}: the other rows (columns) carry the left eye",
                        self.display().1.name()
                    ),
                });
            }
            StationAction::RecentreHead => {
                let said = match self.stereo.head.as_mut().map(OpentrackHead::recentre) {
                    Some(true) => "head tracking: recentred, your head is now the centred head",
                    Some(false) => "head tracking: nothing received from the tracker yet to recentre on",
                    None => "head tracking is off (--opentrack ADDR turns it on)",
                };
                let said = said.to_owned();
                self.messages.push(said);
            }
            StationAction::ResetView => {
                let distance = (self.scene.rig.eye_m - self.scene.rig.target_m).length();
                self.controls.mouse.scene_rotation = Quat::IDENTITY;
                self.controls.mouse.distance_m = distance;
                self.controls.mouse.tool_position_m = self.scene.rig.target_m;
                self.controls.desk.poses = self.controls.home;
                self.controls.cursor_clutch = None;
                self.view.rig = self.scene.rig;
                self.stereo.convergence_factor = self.scene.rig.convergence_m / distance.max(1e-6);
            }
            StationAction::NextDisplayMode => {
                let modes = DisplayMode::ALL;
                let at = modes.iter().position(|m| *m == self.stereo.display_mode).unwrap_or(0);
                let usable = |m: &DisplayMode| self.stereo.quad_buffer || m.layers() == 1;
                if let Some(next) = (1..=modes.len()).map(|i| modes[(at + i) % modes.len()]).find(usable) {
                    self.stereo.display_mode = next;
                    self.fit_views();
                }
            }
            StationAction::TogglePanel => self.set_panel_shown(!self.panel.shown()),
            StationAction::ToggleFullscreen => {
                self.fullscreen = !self.fullscreen;
                self.fullscreen_asked = Some(self.fullscreen);
                self.messages.push(
                    match self.fullscreen {
                        true => "fullscreen: the window fills its monitor",
                        false => "fullscreen off: back to a window",
                    }
                    .to_owned(),
                );
            }
            StationAction::Apply
            | StationAction::Clutch
            | StationAction::GrabRegion
            | StationAction::CopyRegion
            | StationAction::BendRegion
            | StationAction::SelectBox
            | StationAction::PointerLeft
            | StationAction::PointerRight
            | StationAction::PointerUp
            | StationAction::PointerDown
            | StationAction::PointerAway
            | StationAction::PointerToward
            | StationAction::OpenLattice
            | StationAction::OpenPartLattice
            | StationAction::ApplyLattice
            | StationAction::CancelLattice
            | StationAction::DragControl
            | StationAction::RaiseValue
            | StationAction::LowerValue
            | StationAction::HeavierWeight
            | StationAction::LighterWeight
            | StationAction::NextLatticeSlice
            | StationAction::NextLatticeKind => {}
        }
    }

    /// The tools act on part `next` (modulo the parts' count) from now on.
    fn pick_part(&mut self, next: usize) {
        self.end_desk_strokes();
        let part = self.doc.playback.set_active_part(next);
        // The device driving the part starts from home over the part as it is.
        *self.controls.desk.poses.get_mut(Target::Part) = self.controls.home.get(Target::Part);
        self.rebase_part();
        self.part_shown_s = PART_SHOWN_S;
        self.messages.push(describe_part(self.doc.playback.assembly(), part));
    }

    /// Shows or hides the desk panel (the `toggle-panel` key does too).
    pub fn set_panel_shown(&mut self, shown: bool) {
        self.panel.set_shown(shown);
        self.panel_press = false;
    }

    /// Hands `event` to the panel; returns whether it was the panel's: the pointer over the
    /// panel (and the view not being turned), or the left button that went down on it.
    fn panel_takes(&mut self, event: MouseEvent) -> bool {
        if !self.panel.shown() {
            return false;
        }
        let in_eye = |p: Vec2| self.stereo.in_eye(p).to_array();
        match event {
            MouseEvent::Move(at) => {
                self.panel.pointer(PointerEvent::Moved(in_eye(at)));
                self.panel_press || (self.panel.wants_pointer() && !self.controls.mouse.left_held())
            }
            MouseEvent::Press(button, at) => {
                self.panel.pointer(PointerEvent::Moved(in_eye(at)));
                let taken = self.panel.wants_pointer();
                if taken && button == MouseButton::Left {
                    self.panel.pointer(PointerEvent::Primary(true));
                    self.panel_press = true;
                }
                taken
            }
            MouseEvent::Release(MouseButton::Left) if self.panel_press => {
                self.panel.pointer(PointerEvent::Primary(false));
                self.panel_press = false;
                true
            }
            MouseEvent::Release(_) => false,
            MouseEvent::Wheel(steps) => {
                let taken = self.panel.wants_pointer();
                if taken {
                    self.panel.pointer(PointerEvent::Wheel(steps));
                }
                taken
            }
        }
    }

    /// What the panel shows now.
    fn panel_view(&self) -> PanelView {
        // The names kept for the newest steps; older ones (a scene's) by number alone.
        let history = self.doc.playback.assembly().history_len(self.doc.playback.field());
        let (undo_list, redo_list) = panel_rows::history_rows(history, &self.step_names, &self.redo_names);
        let modes: Vec<DisplayMode> =
            DisplayMode::ALL.iter().copied().filter(|m| self.stereo.quad_buffer || m.layers() == 1).collect();
        let mut status = self.hud_lines();
        status.extend(self.messages.iter().rev().take(3).rev().cloned());
        let assembly = self.doc.playback.assembly();
        let symmetry = self.doc.playback.symmetry();
        let rig = &self.view.rig;
        let stereo = StereoRow {
            convergence_m: rig.convergence_m,
            convergence_range_m: rig.convergence_range(),
            auto_convergence: self.stereo.auto_convergence.is_some(),
            interaxial_mm: self.stereo.interaxial_in_use_m(rig) * 1000.0,
            max_interaxial_mm: StereoRig::MAX_INTERAXIAL_M * 1000.0,
            disparity: self.stereo.budget.as_ref().and_then(|b| b.readout).map(|(check, bound_deg)| {
                Disparity {
                    nearest_deg: check.nearest_deg,
                    farthest_deg: check.farthest_deg,
                    bound_deg,
                    exceeded: check.exceeded,
                }
            }),
            lights_follow_viewer: self.stereo.lights_follow_viewer,
            swap_eyes: self.stereo.swap_eyes,
            floating_window: self.stereo.floating_window.0,
            head: self.stereo.head.as_ref().map(|h| !h.lost()),
        };
        let mut view = PanelView {
            level_samples: self.acting_tool().level_samples,
            level: self.edit_level(),
            parts: panel_rows::part_rows(&self.doc.playback),
            active_part: assembly.active(),
            symmetry: (symmetry.describe(), !symmetry.is_none()),
            lattice: panel_rows::lattice_row(&self.doc.playback),
            devices: DeviceClass::ALL
                .iter()
                .map(|&class| DeviceRow {
                    family: class.name(),
                    target: self.controls.desk.mapping.target(class).index(),
                    connected: match class {
                        DeviceClass::SpaceMouse => self.controls.desk.spacemouse_names(),
                        DeviceClass::Gamepad => self.controls.gamepad_names.clone(),
                        DeviceClass::Mouse => vec!["the system pointer".to_owned()],
                    },
                })
                .collect(),
            targets: Target::ALL.iter().map(|t| t.name()).collect(),
            head_tracker: self.stereo.head.as_ref().map(|h| {
                format!(
                    "head tracker: opentrack on UDP {}, {}",
                    h.receiver().local_addr(),
                    if h.lost() { "no head seen (lost)" } else { "tracking" }
                )
            }),
            stereo,
            undo: undo_list,
            redo: redo_list,
            display_mode: modes.iter().position(|m| *m == self.stereo.display_mode).unwrap_or(0),
            display_modes: modes.iter().map(|m| m.name()).collect(),
            save_to: self.doc.save_to().display().to_string(),
            save_name: self
                .doc
                .save_to()
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
            unsaved: self.unsaved_work(),
            unsaved_fate: self.unsaved_fate(),
            sculpt_extension: super::SCULPT_EXTENSION,
            export_formats: crate::mesh::export::ExportFormat::ALL.map(|f| f.extension()).to_vec(),
            recent: self.recent.list().to_vec(),
            recovered: self.recovered.clone(),
            status,
            ..PanelView::default()
        };
        panel_rows::fill_tool(&mut view, &self.desk_tool, self.action_index);
        view
    }

    /// Does what the panel asked.
    fn panel_command(&mut self, command: PanelCommand) {
        if panel_rows::apply_tool(
            &command,
            &mut self.desk_tool,
            &mut self.action_index,
            &mut self.hand_samples,
        ) {
            return;
        }
        if let Some(step) = panel_rows::LatticeStep::of(&command) {
            let said = panel_rows::lattice_step(&mut self.doc, step, lattice::LATTICE_OPENS);
            self.messages.push(said);
            return;
        }
        match command {
            // The tool's and the lattice's, taken above; the desk ends by closing its window.
            PanelCommand::Shape(_)
            | PanelCommand::Action(_)
            | PanelCommand::SizeMm(_)
            | PanelCommand::Rate(_)
            | PanelCommand::Spacing(_)
            | PanelCommand::Colour(_)
            | PanelCommand::LevelSamples(_)
            | PanelCommand::LevelBySize
            | PanelCommand::ApplyLattice
            | PanelCommand::CancelLattice
            | PanelCommand::NextLatticeSlice
            | PanelCommand::ControlValue(_)
            | PanelCommand::ControlWeight(_)
            | PanelCommand::Quit => {}
            PanelCommand::ActivePart(i) => self.pick_part(i),
            PanelCommand::CopyToPart => self.act(StationAction::CopyToPart),
            PanelCommand::ToggleSymmetry => self.act(StationAction::ToggleSymmetry),
            PanelCommand::NextSymmetry => self.act(StationAction::NextSymmetry),
            PanelCommand::ConvergenceM(m) => {
                if m.is_finite() && self.stereo.auto_convergence.is_none() {
                    self.stereo.set_convergence(m, &self.view.rig, self.controls.mouse.distance_m);
                }
            }
            PanelCommand::AutoConvergence(on) => {
                if on != self.stereo.auto_convergence.is_some() {
                    self.act(StationAction::ToggleAutoConvergence);
                }
            }
            PanelCommand::InteraxialMm(mm) => {
                if mm.is_finite() {
                    *self.stereo.interaxial_in_use(&mut self.view.rig) =
                        (mm * 1e-3).clamp(0.0, StereoRig::MAX_INTERAXIAL_M);
                }
            }
            PanelCommand::LightsFollowViewer(on) => self.stereo.lights_follow_viewer = on,
            PanelCommand::SwapEyes(on) => {
                if on != self.stereo.swap_eyes {
                    self.act(StationAction::SwapEyes);
                }
            }
            PanelCommand::FloatingWindow(on) => {
                if on != self.stereo.floating_window.0 {
                    self.act(StationAction::ToggleFloatingWindow);
                }
            }
            PanelCommand::RecentreHead => self.act(StationAction::RecentreHead),
            PanelCommand::Undo(n) => (0..n).for_each(|_| self.act(StationAction::Undo)),
            PanelCommand::Redo(n) => (0..n).for_each(|_| self.act(StationAction::Redo)),
            PanelCommand::DisplayMode(i) => {
                let usable = DisplayMode::ALL
                    .iter()
                    .copied()
                    .filter(|m| self.stereo.quad_buffer || m.layers() == 1)
                    .nth(i);
                if let Some(mode) = usable {
                    self.stereo.display_mode = mode;
                    self.fit_views();
                }
            }
            PanelCommand::Save => self.act(StationAction::Save),
            PanelCommand::DeviceTarget(device, target) => {
                if let (Some(&class), Some(&target)) = (DeviceClass::ALL.get(device), Target::ALL.get(target))
                {
                    self.set_device_target(class, target);
                }
            }
            PanelCommand::LatticeForm(form) => {
                let said = self.set_lattice_form(form);
                self.messages.push(said);
            }
            PanelCommand::OpenLattice(whole_part) => self.act(match whole_part {
                true => StationAction::OpenPartLattice,
                false => StationAction::OpenLattice,
            }),
            PanelCommand::SaveAs(path) => self.save_as(&path),
            PanelCommand::Open(path) => self.open_from_panel(&path),
            PanelCommand::Export(path) => self.export_to(&path),
            PanelCommand::DismissRecovered => self.recovered.clear(),
        }
    }

    /// A desk step (a stroke, a region moved) ended: its name goes to the panel's history, and
    /// what was undone can no longer be redone.
    fn stepped(&mut self, name: String) {
        self.step_names.push(name);
        self.redo_names.clear();
        if self.step_names.len() > STEP_NAMES_KEPT {
            self.step_names.drain(..self.step_names.len() - STEP_NAMES_KEPT);
        }
    }

    /// The desk tool's stroke as the history names it.
    fn stroke_name(&self) -> String {
        format!(
            "{} {} {} mm",
            self.desk_tool.action.name(),
            shape_name(&self.desk_tool.shape),
            (self.desk_tool.size_m() * 1000.0).round()
        )
    }

    /// Moves the convergence plane by `factor` (see [`StereoView::step_convergence`]).
    fn step_convergence(&mut self, factor: f32) {
        let said = self.stereo.step_convergence(factor, &self.view.rig, self.controls.mouse.distance_m);
        self.messages.extend(said);
    }

    /// Scales the interaxial distance in use by `factor` (see [`StereoView::step_interaxial`]).
    fn step_interaxial(&mut self, factor: f32) {
        let said = self.stereo.step_interaxial(factor, &mut self.view.rig);
        self.messages.extend(said);
    }

    /// The level the desk tool edits (its size chooses it) and its voxel size, millimetres.
    fn edit_level(&self) -> (u32, f32) {
        panel_rows::edit_level(&self.doc.playback, &self.acting_tool())
    }

    /// What the heads-up display shows: the desk tool, the stereo settings, the frame time.
    pub fn hud_lines(&self) -> Vec<String> {
        if let Some(lines) = self.adjusting_hud() {
            return lines;
        }
        let rig = &self.view.rig;
        let mouse = match self.controls.mouse.mode {
            MouseMode::Scene => "turns",
            MouseMode::Cursor => "places tool",
        };
        let voxel_mm = (self.edit_level().1 * 10.0).round() / 10.0;
        let mut lines = vec![
            format!(
                "tool {}: {} {} mm, {}, {} mm voxels{}",
                self.tool_index + 1,
                shape_name(&self.desk_tool.shape),
                (self.desk_tool.size_m() * 1000.0).round(),
                self.desk_tool.action.name(),
                voxel_mm,
                match self.doc.playback.symmetry() {
                    s if s.is_none() => String::new(),
                    s => format!(", {}", s.describe()),
                }
            ),
            format!(
                "{}: convergence {:.2} m, eyes {:.0} mm{}",
                self.stereo.display_mode,
                rig.convergence_m,
                self.stereo.interaxial_in_use_m(&self.view.rig) * 1000.0,
                if self.stereo.floating_window.0 { ", floating window" } else { "" },
            ),
            format!(
                "{:.1} ms/frame, mouse {mouse}{}{}",
                self.frame_ms,
                if self.stereo.auto_convergence.is_some() { ", auto-convergence" } else { "" },
                match &self.stereo.head {
                    Some(h) if h.lost() => ", head lost",
                    Some(_) => ", head tracked",
                    None => "",
                }
            ),
        ];
        let (parts, active) = (self.doc.playback.assembly().parts(), self.doc.playback.assembly().active());
        if parts.len() > 1 {
            let locked = if parts[active].locked { ", locked" } else { "" };
            lines
                .insert(1, format!("part {} of {}: {}{locked}", active + 1, parts.len(), parts[active].name));
        }
        lines.extend(self.exports.status());
        if let Some(Budgeted { over: Some((check, _)), .. }) = &self.stereo.budget {
            // Today's figures, not those of the first warning.
            // The HUD's font has no degree sign.
            lines.push(format!(
                "over the parallax budget: {:.2} to {:.2} deg",
                check.nearest_deg, check.farthest_deg
            ));
        }
        lines
    }

    /// The display mode and, for interlaced modes, the parity in window pixels (the
    /// calibration's parity is the screen's; a window on an odd row or column flips it).
    pub fn display(&self) -> (DisplayMode, Parity) {
        self.stereo.display()
    }

    /// Counts a frame the window has shown: a frame-sequential display shows the other eye in
    /// the next.
    pub fn frame_shown(&mut self) {
        self.stereo.frames_shown += 1;
    }

    /// Chooses the display mode for a surface of `max_layers` image layers on `device`:
    /// quad-buffer stereo falls back to the scene's fallback mode where the surface cannot show
    /// it. Returns the notice to show the user, if any.
    pub fn set_surface(
        &mut self,
        wanted: DisplayMode,
        device: &str,
        max_layers: u32,
    ) -> Result<Option<String>> {
        self.stereo.quad_buffer = max_layers >= 2;
        let choice = choose_mode(wanted, self.scene.display.fallback, device, max_layers)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        self.stereo.display_mode = choice.mode;
        self.fit_views();
        Ok(choice.notice)
    }

    /// The window moved to `origin` (its top-left corner on the screen, pixels).
    pub fn set_window_origin(&mut self, origin: (i32, i32)) {
        self.stereo.window_origin = origin;
    }

    /// The window's monitor, as the window system gives its resolution.
    pub fn set_monitor_px(&mut self, monitor_px: Option<(u32, u32)>) {
        self.stereo.monitor_px = monitor_px;
    }

    /// How the parallax budget sees the window: each eye's picture on the calibrated screen.
    pub fn describe_picture(&self) -> String {
        self.stereo.describe_picture()
    }

    /// The head-tracked views' rig, while tracked (the pattern's placement while adjusting).
    fn tracked_rig(&self) -> Option<HeadTrackedRig> {
        self.stereo.tracked_rig(&self.view.rig, self.adjusting_placement())
    }

    /// Where the last [`Station::step`] spent its time.
    pub fn times(&self) -> StepTimes {
        self.times
    }

    /// The last frame's duration, milliseconds (shown in the HUD).
    pub fn set_frame_time(&mut self, ms: f32) {
        self.frame_ms = ms;
    }

    /// Writes the sculpt to the save path, atomically. Where that fails (a full disk, a
    /// folder that cannot be written), nothing already there is damaged and the sculpt is
    /// written to the fallback folder instead (see [`Station::set_fallback_dir`]), where the
    /// save key writes from then on, and a message says so; without one, or when that fails
    /// too, the error says the sculpt stays in memory.
    pub fn save(&mut self) -> Result<PathBuf> {
        self.save_keeping("the sculpt stays in memory; `argile run --save-to FILE` saves it elsewhere")
    }

    /// [`Station::save`] as the station closes: where no file can be written, the error says
    /// the strokes stay in the autosave journal (the session is then left unclosed).
    fn save_at_exit(&mut self) -> Result<PathBuf> {
        self.save_keeping(
            "nothing could be saved as the station closed; its strokes stay in the autosave journal, \
             which `argile recover` gives back",
        )
    }

    /// Saves (see [`Station::save`]); `kept` says where the sculpt is when nothing can be written.
    fn save_keeping(&mut self, kept: &'static str) -> Result<PathBuf> {
        let view = self.stored_view();
        let saved = self.doc.save(Some(&view), kept)?;
        self.messages.extend(saved.moved);
        self.recent.remember(&saved.path);
        Ok(saved.path)
    }

    /// What the sculpt file lacks: the strokes (and undos, redos) since the last save or open,
    /// and one more for a lattice held open that is not as the last save stored it.
    pub fn unsaved_work(&self) -> u64 {
        self.doc.unsaved_work()
    }

    /// Where a save that cannot write its file writes the sculpt instead (the station uses
    /// `saved/` in the state folder).
    pub fn set_fallback_dir(&mut self, dir: Option<PathBuf>) {
        self.doc.set_fallback_dir(dir);
    }

    /// The view as a sculpt stores it: the camera's turn and distance, the scene's pose, the
    /// stereo settings and the display mode.
    pub fn stored_view(&self) -> StoredView {
        let scene = self.controls.desk.poses.get(Target::Scene);
        StoredView {
            turn: self.controls.mouse.scene_rotation.to_array(),
            distance_m: self.controls.mouse.distance_m,
            scene_position_m: scene.position_m.to_array(),
            scene_rotation: scene.rotation.to_array(),
            convergence_factor: self.stereo.convergence_factor,
            interaxial_m: self.view.rig.interaxial_m,
            lights_follow_viewer: self.stereo.lights_follow_viewer,
            auto_convergence: self.stereo.auto_convergence.is_some(),
            display_mode: self.stereo.display_mode.name().to_owned(),
        }
    }

    /// Puts the view a sculpt stored (see [`Station::stored_view`]) in place; a display mode
    /// this window cannot show is left as it is, and said.
    pub fn apply_view(&mut self, view: &StoredView) {
        self.controls.mouse.scene_rotation = Quat::from_array(view.turn).normalize();
        self.controls.mouse.distance_m = view.distance_m;
        *self.controls.desk.poses.get_mut(Target::Scene) = crate::math::Pose {
            position_m: Vec3::from_array(view.scene_position_m),
            rotation: Quat::from_array(view.scene_rotation).normalize(),
        };
        self.stereo.convergence_factor = view.convergence_factor;
        self.view.rig.interaxial_m = view.interaxial_m;
        self.stereo.lights_follow_viewer = view.lights_follow_viewer;
        self.stereo.auto_convergence = view.auto_convergence.then(|| {
            AutoConvergence::new(
                self.controls.mouse.distance_m * self.stereo.convergence_factor,
                AutoConvergence::DEFAULT_TIME_CONSTANT_S,
                (self.view.rig.near_m * 2.0, self.view.rig.far_m * 0.5),
            )
        });
        match view.display_mode.parse::<DisplayMode>() {
            Ok(mode) if self.stereo.quad_buffer || mode.layers() == 1 => {
                self.stereo.display_mode = mode;
                self.fit_views();
            }
            _ => self.messages.push(format!(
                "the sculpt was shown in the {} display mode, which this window cannot show; it stays {}",
                view.display_mode,
                self.stereo.display_mode.name()
            )),
        }
    }

    /// The text of the scene the station plays (a scene file's, or the one a sculpt file
    /// stores): saving stores it with the clay, and a sculpt opened later that was made in it
    /// brings back its freeform tools.
    pub fn set_scene_toml(&mut self, text: Option<String>) {
        self.doc.set_scene_toml(text);
    }

    /// The open key looks for sculpts in `dir`.
    pub fn set_open_dir(&mut self, dir: PathBuf) {
        self.open_dir = dir;
    }

    /// Autosave starts again with `config` on a sculpt opened later; its snapshots carry
    /// `scene_toml`.
    pub fn set_autosave_restart(&mut self, config: AutosaveConfig, scene_toml: Option<String>) {
        self.doc.set_autosave_restart(config, scene_toml);
    }

    /// Opens the sculpt file at `path`: its clay replaces the station's (the scene's tools,
    /// lights and view stay; when the file was made in the station's scene, its freeform
    /// tools and its view are the ones it stores), a stroke in progress ends, and saving
    /// writes back to it. The
    /// autosave session of the clay it replaces is closed, or left for recovery at the next
    /// start when it holds unsaved strokes. A file that cannot be read changes nothing and the
    /// error names it.
    pub fn open(&mut self, path: &Path) -> Result<()> {
        let opened = self.doc.open(path)?;
        self.stroke = None;
        if let Some(symmetry) = opened.symmetry {
            self.symmetry = SymmetrySwitch::new(symmetry);
        }
        if opened.tools_restored {
            let stored = self.doc.playback.tools().get(self.tool_index).map(|t| t.shape.clone());
            if let Some(shape @ ToolShape::Freeform(_)) = stored {
                if matches!(self.desk_tool.shape, ToolShape::Freeform(_)) {
                    self.desk_tool.shape = shape;
                }
            }
        }
        if let Some(view) = &opened.view {
            self.apply_view(view);
        }
        self.messages.extend(opened.notes);
        if self.doc.playback.held_lattice().is_some() {
            self.messages.push("Enter applies the lattice, Backspace puts the clay back".into());
        }
        self.rebase_part();
        self.clay_bounds = crate::math::Aabb::EMPTY;
        self.recent.remember(path);
        self.recovered.retain(|(p, _)| p != path);
        Ok(())
    }

    /// The sculpts saved and opened last, kept by `recent` (the window's station keeps them in
    /// the state folder).
    pub fn set_recent(&mut self, recent: RecentSculpts) {
        self.recent = recent;
    }

    /// The sculpts recovered at start, with what each holds: the panel offers to open them.
    pub fn set_recovered(&mut self, recovered: Vec<(PathBuf, String)>) {
        self.recovered = recovered;
    }

    /// What becomes of unsaved work when another sculpt is opened.
    fn unsaved_fate(&self) -> &'static str {
        self.doc.unsaved_fate()
    }

    /// The panel's open: the sculpt at `path`, whatever the unsaved work (the panel said what
    /// becomes of it).
    fn open_from_panel(&mut self, path: &Path) {
        let left = self.unsaved_work();
        let fate = self.unsaved_fate();
        match self.open(path) {
            Ok(()) => self.messages.push(panel_rows::opened_said(path, left, fate)),
            Err(e) => self.messages.push(format!("{e:#}")),
        }
    }

    /// The panel's save as: the sculpt to `path`, where saving writes from then on.
    fn save_as(&mut self, path: &Path) {
        let view = self.stored_view();
        let saved = self.doc.save_as(path, Some(&view));
        if let Ok(saved) = &saved {
            self.recent.remember(&saved.path);
        }
        let said = panel_rows::saved_as_said(&saved, self.doc.save_to());
        self.messages.push(said);
    }

    /// The panel's export: the surface as it stands to `path`, in the format its extension
    /// names.
    fn export_to(&mut self, path: &Path) {
        let said = self.exports.start(path);
        self.messages.push(said);
    }

    /// The open key: the sculpt after the one opened last in the open folder, newest first.
    fn open_next(&mut self) {
        let dir = self.open_dir.clone();
        let list = match sculpts_in(&dir) {
            Ok(list) => list,
            Err(e) => {
                self.messages.push(format!("cannot list the sculpts in {}: {e}", dir.display()));
                return;
            }
        };
        let Some(path) = next_sculpt(&list, self.doc.opened()).map(Path::to_owned) else {
            self.messages.push(format!(
                "no sculpt (.argile) in {} to open: the save key writes one there, and \
                 `argile run --open-dir DIR` names another folder",
                dir.display()
            ));
            return;
        };
        if self.unsaved_work() > 0 && self.confirm_open.as_ref() != Some(&path) {
            let fate = self.unsaved_fate();
            self.messages.push(format!(
                "{} unsaved stroke(s){}: the save key writes them to {}; the open key again opens {} \
                 anyway ({fate})",
                self.doc.unsaved_strokes(),
                if self.unsaved_work() > self.doc.unsaved_strokes() { " and an open lattice" } else { "" },
                self.doc.save_to().display(),
                path.display()
            ));
            self.confirm_open = Some(path);
            return;
        }
        self.confirm_open = None;
        match self.open(&path) {
            Ok(()) => self.messages.push(format!(
                "opened {} (the open key again: the next older sculpt in {})",
                path.display(),
                dir.display()
            )),
            Err(e) => {
                // Skipped at the next press.
                self.doc.skip(path);
                self.messages.push(format!("{e:#}"));
            }
        }
    }

    /// The region tools held at the desk: the region of the tool's shape at `pose` (world)
    /// grabbed when a region key goes down, carried (or copied, or bent) with the tool each
    /// frame, one undo step when the key comes up. Not while the tool is applied.
    fn carry_region(&mut self, pose: Pose, applying: bool) {
        let held = [
            (StationAction::GrabRegion, RegionOp::Move),
            (StationAction::CopyRegion, RegionOp::Copy),
            (StationAction::BendRegion, RegionOp::Bend),
        ]
        .into_iter()
        .find(|&(a, _)| self.holding(a))
        .map(|(_, op)| op)
        .filter(|_| !applying);
        let failed = match (held, self.doc.playback.held_region().is_some()) {
            (Some(op), false) => self.doc.playback.grab_region(op, self.desk_tool.clone(), pose).err(),
            (Some(_), true) => self.doc.playback.carry_region(pose).and_then(Result::err),
            (None, true) => {
                self.doc.playback.let_go_region();
                self.doc.edited();
                self.stepped("region".into());
                None
            }
            (None, false) => None,
        };
        if let Some(message) = failed {
            if self.messages.last() != Some(&message) {
                self.messages.push(message);
            }
        }
    }

    /// The box selection held at the desk: the key down takes the tool's position (`at`,
    /// world) as one corner, the box follows the tool while it is held, and the key up keeps
    /// it (a tap, a box without size, clears the selection).
    fn drag_out_box(&mut self, at: Vec3) {
        match (self.holding(StationAction::SelectBox), self.box_from) {
            (true, None) => self.box_from = Some(at),
            (true, Some(from)) => {
                self.doc.playback.select_box(from, at);
            }
            (false, Some(from)) => {
                self.box_from = None;
                let size = self.doc.playback.select_box(from, at);
                self.messages.push(selection_said(size, "a tap of U"));
            }
            (false, None) => {}
        }
    }

    /// Ends the desk tool's stroke and region drag on the active part, each one undo step.
    fn end_desk_strokes(&mut self) {
        let region = self.doc.playback.let_go_region();
        if self.stroke.take().is_some() || region {
            if let Ok((field, _)) = self.doc.playback.active_target() {
                field.end_stroke();
            }
            self.doc.journal();
            // The history names a region carried as the region keys do.
            let name = if region { "region".into() } else { self.stroke_name() };
            self.stepped(name);
        }
    }

    /// The device driving the part starts from home over the active part as it is now (picked,
    /// opened, or put back by undo).
    fn rebase_part(&mut self) {
        *self.controls.desk.poses.get_mut(Target::Part) = self.controls.home.get(Target::Part);
        let active = self.doc.playback.assembly().active();
        self.part_base = self.doc.playback.assembly().parts()[active].placement;
        self.part_moving = None;
    }

    /// The active part follows the device driving the `part` target: turned about its origin
    /// and moved as far as the device has moved that target from home. Once it stops, the
    /// move is one undo step and the autosave session keeps where it is.
    fn drive_active_part(&mut self) {
        let (pose, home) = (self.controls.desk.poses.get(Target::Part), self.controls.home.get(Target::Part));
        let base = self.part_base;
        let turn = (pose.rotation * home.rotation.inverse()).normalize();
        let placement = crate::parts::Placement {
            rotation: (turn * base.rotation).normalize(),
            translation_m: base.translation_m + (pose.position_m - home.position_m),
            scale: base.scale,
        };
        let part = self.doc.playback.assembly().active();
        let now = self.doc.playback.assembly().parts()[part].placement;
        if now != placement && pose != home {
            self.doc.playback.set_part_placement(part, placement);
            self.part_moving.get_or_insert(now);
            self.part_shown_s = PART_SHOWN_S;
        } else if let Some(from) = self.part_moving.take() {
            self.doc.playback.keep_part_moved(part, from);
            self.doc.edited();
            self.stepped("move part".into());
        }
    }

    fn holding(&self, action: StationAction) -> bool {
        self.controls.held.iter().any(|&k| self.controls.bindings.held_action(k) == Some(action))
    }

    /// Runs the tools and the field for `dt_s` seconds and returns the frame to draw; mesh
    /// changes go to `apply`.
    pub fn step(&mut self, dt_s: f32, mut apply: impl FnMut(&crate::mesh::MeshDiff)) -> crate::render::Frame {
        let started = Instant::now();
        self.messages.extend(self.exports.poll());
        // The panel first: what its controls ask for acts in this frame.
        let view = self.panel_view();
        let extent = (self.view.output.width_px, self.view.output.height_px);
        let (commands, panel_paint) = self.panel.run(&view, extent, self.clock_s);
        for command in commands {
            self.panel_command(command);
        }
        self.times.panel_ms = ms_since(started);
        let started = Instant::now();
        // The view first: the pointer moves in it.
        let rig = &mut self.view.rig;
        let base = self.scene.rig;
        let scene_pose = self.controls.desk.poses.get(Target::Scene);
        let rotation = (self.controls.mouse.scene_rotation * scene_pose.rotation).inverse();
        let offset = (base.eye_m - base.target_m).normalize_or(Vec3::Z) * self.controls.mouse.distance_m;
        rig.eye_m = base.target_m + rotation * offset;
        rig.up = rotation * base.up;
        self.stereo.converge(rig, self.controls.mouse.distance_m, self.controls.mouse.tool_position_m, dt_s);

        let step = POINTER_SPEED_M_PER_S * dt_s;
        let (right, up, forward) = (rig.right(), rig.right().cross(rig.forward()), rig.forward());
        for (action, direction) in [
            (StationAction::PointerLeft, -right),
            (StationAction::PointerRight, right),
            (StationAction::PointerUp, up),
            (StationAction::PointerDown, -up),
            (StationAction::PointerAway, forward),
            (StationAction::PointerToward, -forward),
        ] {
            if self.holding(action) {
                self.controls.mouse.tool_position_m += direction * step;
            }
        }
        let tool = self.controls.desk.poses.get_mut(Target::Tool);
        tool.position_m = self.controls.mouse.tool_position_m;
        let pose = *tool;

        let tools_started = Instant::now();
        self.times.input_ms = ms_since(started);

        // Tools: the scene's scripted hands, then the desk tool.
        let t = self.doc.playback.time_s() + dt_s;
        self.doc.playback.advance_to(t, |_| {});
        // While a calibration is adjusted, the pattern is not sculpted.
        let mut applying =
            (self.holding(StationAction::Apply) || self.controls.device_apply) && self.adjusting.is_none();
        self.drive_active_part();
        // The desk tool acts on the active part, in its frame.
        let images = self.doc.playback.images().to_vec();
        let (acting, local, images) = self.doc.playback.in_active_part(self.acting_tool(), pose, &images);
        let lattice_open = self.doc.playback.held_lattice().is_some();
        if lattice_open {
            self.drive_lattice(local.position_m);
            let region_keys =
                [StationAction::GrabRegion, StationAction::CopyRegion, StationAction::BendRegion];
            if applying || region_keys.into_iter().any(|a| self.holding(a)) {
                let why = "a lattice is open: the tools wait until Enter applies it or Backspace puts the clay back";
                if self.messages.last().map(String::as_str) != Some(why) {
                    self.messages.push(why.to_owned());
                }
            }
            applying = false;
        }
        match self.doc.playback.active_target() {
            Err(why) => {
                if applying && self.messages.last() != Some(&why) {
                    self.messages.push(why);
                }
            }
            Ok((field, _)) => {
                if applying {
                    if self.stroke.is_none() {
                        field.begin_stroke();
                        let mut s = Stroke::with_images(acting, &images);
                        s.advance(field, local, 0.0);
                        self.stroke = Some(s);
                    }
                    if let Some(s) = &mut self.stroke {
                        s.advance(field, local, dt_s);
                    }
                } else if self.stroke.take().is_some() {
                    field.end_stroke();
                    self.doc.journal();
                    self.confirm_open = None;
                    let name = self.stroke_name();
                    self.stepped(name);
                }
            }
        }
        if !lattice_open {
            self.drag_out_box(pose.position_m);
            self.carry_region(pose, applying);
        }

        self.times.tools_ms = ms_since(tools_started);
        self.feel_contact(pose, dt_s);

        // Field → mesh → renderer.
        let mesh_started = Instant::now();
        self.doc.playback.sync_lattices();
        self.doc.playback.keep_lattice();
        let diff = self.mesher.remesh_dirty(self.doc.playback.surface());
        if !diff.is_empty() {
            self.surface.apply(diff);
            self.exports.apply(diff);
            apply(diff);
            self.clay_bounds = self.surface.bounds();
        }
        self.times.mesh_ms = ms_since(mesh_started);

        let placement = self.adjusting_placement();
        let warning = self.stereo.judge_parallax(&self.view, self.clay_bounds, placement);
        self.messages.extend(warning);
        // Limit mode: this frame's eyes no farther apart than the budget allows.
        self.stereo.limit_interaxial(&mut self.view.rig);
        let mut frame = build_frame(&self.view, &self.doc.playback.hands(), true);
        frame.tools.extend(super::frame::lattice_glyphs(&self.doc.playback));
        frame.tools.extend(super::frame::symmetry_glyphs(&self.doc.playback));
        frame.tools.extend(super::frame::region_glyphs(&self.doc.playback));
        if self.stereo.lights_follow_viewer {
            // The scene's lights, carried along with the viewer's turn about the target.
            let pivot = self.scene.rig.target_m;
            for light in &mut frame.lights {
                match light {
                    Light::Directional { direction, .. } => *direction = rotation * *direction,
                    Light::Point { position_m, .. } => *position_m = pivot + rotation * (*position_m - pivot),
                }
            }
        }
        let head_pose = match (&mut self.stereo.head, &self.scene.head) {
            (Some(tracker), _) => Some(tracker.pose()),
            // The pattern is seen from the default eye of the calibration as it stands.
            (None, _) if self.adjusting.is_some() => Some(self.stereo.calibration.default_head()),
            (None, Some(path)) => Some(path.pose_at(self.doc.playback.time_s())),
            (None, None) => None,
        };
        if let (Some(head), Some(tracked)) = (head_pose, self.tracked_rig()) {
            // Fish-tank views: the scene's convergence plane on the calibrated screen, seen from
            // the tracked eyes; eased in from the camera rig's views as tracking starts.
            let views = tracked.views(&head);
            let since = match self.stereo.tracked_for_s {
                None => {
                    if self.adjusting.is_none() {
                        self.messages.push(self.stereo.tracking_notice(self.view.rig.fov_y_deg));
                    }
                    0.0
                }
                Some(t) => t + dt_s,
            };
            self.stereo.tracked_for_s = Some(since);
            let ease = self.stereo.calibration.tracker.ease_s;
            // A calibration's pattern is seen from the calibrated eye at once.
            frame.views = match ease > 0.0 && since < ease && self.adjusting.is_none() {
                true => {
                    let u = since / ease;
                    blend_views(&frame.views, &views, u * u * (3.0 - 2.0 * u))
                }
                false => views,
            };
        } else {
            self.stereo.tracked_for_s = None;
        }
        // The floating window, measured on the views as the eyes see them and carried with
        // the pictures when they are swapped.
        let measured = match self.stereo.floating_window.0 && self.stereo.display_mode != DisplayMode::Mono {
            true => FloatingWindow::measure(&frame.views, self.surface.points()),
            false => FloatingWindow::NONE,
        };
        let window = self.stereo.floating_window.1.eased(measured, dt_s);
        // Strips under a hundredth of a pixel are none (the easing never quite reaches 0).
        self.stereo.floating_window.1 = if window.widest() < 1e-5 { FloatingWindow::NONE } else { window };
        frame.floating_window = self.stereo.floating_window.1;
        if self.stereo.swap_eyes {
            frame.views.eyes.swap(0, 1);
            frame.floating_window = frame.floating_window.swapped();
        }
        self.place_key_light(&mut frame.lights);
        // The panel shows what the heads-up display would.
        frame.hud = if panel_paint.is_some() { Vec::new() } else { self.hud_lines() };
        frame.panel = panel_paint;
        if self.adjusting.is_some() {
            frame.eye_marks = self.adjusting_marks();
            return frame;
        }
        let tool = &self.desk_tool;
        let colour = Vec4::from(tool.colour).truncate().extend(0.35);
        frame.tools.push(tool_glyph(&tool.shape, pose, tool.scale, colour));
        // Its images under the symmetry, fainter.
        for image in self.doc.playback.images().iter().skip(1) {
            let ghost = colour.truncate().extend(0.5 * colour.w);
            frame.tools.push(tool_glyph(&tool.shape, image.pose(&pose).0, tool.scale, ghost));
        }
        // The active part's box, for a while after it was picked or moved.
        self.part_shown_s = (self.part_shown_s - dt_s).max(0.0);
        if self.part_shown_s > 0.0 {
            frame.tools.extend(super::frame::part_glyph(&self.doc.playback, super::frame::PART_COLOUR));
        }
        let second = self.controls.desk.poses.get(Target::SecondTool);
        if second != self.controls.home.get(Target::SecondTool) {
            // The second tool, once a device has moved it: the desk tool's shape and size, in blue.
            frame.tools.push(tool_glyph(&tool.shape, second, tool.scale, Vec4::new(0.3, 0.5, 1.0, 0.35)));
        }
        frame
    }

    /// The key light (the scene's first), turned and moved as far as the devices driving the
    /// light have moved its target from home; as the scene has it while they have not.
    fn place_key_light(&self, lights: &mut [Light]) {
        let (light, home) =
            (self.controls.desk.poses.get(Target::Light), self.controls.home.get(Target::Light));
        if light == home {
            return;
        }
        let turn = (light.rotation * home.rotation.inverse()).normalize();
        let pivot = self.scene.rig.target_m;
        match lights.first_mut() {
            Some(Light::Directional { direction, .. }) => *direction = turn * *direction,
            Some(Light::Point { position_m, .. }) => {
                *position_m = pivot + turn * (*position_m - pivot) + (light.position_m - home.position_m);
            }
            None => {}
        }
    }

    /// Contact feedback for the pads: the tool the gamepads drive (the desk tool at `tool`, or
    /// the second tool) against the clay this frame.
    fn feel_contact(&mut self, tool: Pose, dt_s: f32) {
        let driven = match self.controls.desk.mapping.target(DeviceClass::Gamepad) {
            Target::Tool => Some((tool, self.stroke.is_some())),
            Target::SecondTool => Some((self.controls.desk.poses.get(Target::SecondTool), false)),
            Target::Scene | Target::Light | Target::Part => None,
        };
        let contact = driven.map_or(Contact::default(), |(pose, stroking)| {
            let (touching, density) =
                contact_under(self.doc.playback.surface_now(), pose, self.desk_tool.half_extents_m());
            Contact { touching, density, stroking }
        });
        let feedback = self.controls.feedback.get_or_insert_with(|| {
            let mut silent = ContactFeedback::default();
            let _ = silent.update(Contact { stroking: false, ..contact }, 0.0);
            silent
        });
        if let Some(r) = feedback.update(contact, dt_s) {
            self.controls.rumble = Some(r);
        }
    }
}

/// How long the active part's box is drawn after it was picked or moved, seconds.
const PART_SHOWN_S: f32 = 2.0;

/// What the station says of part `part` when it becomes the active one.
fn describe_part(parts: &super::assembly::Assembly, part: usize) -> String {
    let p = &parts.parts()[part];
    let t = p.placement.translation_m;
    format!(
        "active part {} of {}: {} ({}, {} mm voxels, at {:.3}, {:.3}, {:.3} m, scale {}{}{})",
        part + 1,
        parts.parts().len(),
        p.name,
        p.op.name(),
        p.voxel_size_m * 1000.0,
        t.x,
        t.y,
        t.z,
        p.placement.scale,
        if p.visible { "" } else { ", hidden" },
        if p.locked { ", locked: no tool acts on it" } else { "" }
    )
}

/// Runs the station in a window on `scene` until the user closes it (or the frame count of
/// `options` is reached). `scene_name` names the window and the default save file.
pub fn run_station(scene: &Scene, scene_name: &str, options: &StationOptions) -> Result<StationReport> {
    if let Some(reason) = no_display_reason() {
        bail!("cannot open the station window: {reason}");
    }
    let (bindings, _) = KeyBindings::load(options.keys.as_deref())?;
    // The scene's input settings, then the command line's, over the user's.
    let layers: Vec<&Path> =
        scene.input_settings.iter().chain(&options.input).map(PathBuf::as_path).collect();
    let input = InputSettings::load(&layers, InputSettings::user_config_dir().as_deref())?;
    let calibration = options.calibration.as_deref().map(ScreenCalibration::load).transpose()?;
    let script = options.script.as_deref().map(InputScript::load).transpose()?;
    let event_loop = EventLoop::new().context("cannot connect to the display server")?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let window_px = options.window_px.unwrap_or((scene.output.width_px, scene.output.height_px));
    let save_to = options.save_to.clone().unwrap_or_else(|| PathBuf::from(format!("{scene_name}.argile")));
    let source = scene.source.clone();
    let start = |field: &mut crate::field::Field, tools: crate::io::autosave::Besides<'_>| {
        options.autosave.clone().and_then(|config| {
            super::autosave::start_autosave(field, (options.scene_toml.as_deref(), tools), &source, config)
        })
    };
    let mut app = WindowApp {
        station: {
            let mut station = Station::new_autosaved(scene, bindings, window_px, save_to, start)?;
            if let Some(c) = calibration {
                station.set_calibration(c);
            }
            station.set_input_settings(&input);
            match &options.adjust {
                Some(target) => station.start_adjusting(target.clone()),
                None => station.set_panel_shown(true),
            }
            if let Some(config) = &options.autosave {
                station.set_autosave_restart(config.clone(), options.scene_toml.clone());
            }
            station.set_scene_toml(options.scene_toml.clone());
            station.set_hand_samples((!options.edit_finest).then_some(HAND_SIZE_SAMPLES));
            station.set_fallback_dir(super::state_dir().map(|d| d.join("saved")));
            station.set_recent(RecentSculpts::in_state_folder());
            station.set_recovered(options.recovered.clone());
            if let Some(dir) = &options.open_dir {
                station.set_open_dir(dir.clone());
            }
            if let Some(path) = &options.open {
                station.open(path)?;
            }
            station
        },
        input,
        options,
        script: script.unwrap_or_default(),
        scene_name,
        window_px,
        window: None,
        monitor: None,
        renderer: None,
        spacemice: None,
        gamepads: None,
        validation: None,
        frames: 0,
        last: None,
        screenshot: None,
        error: None,
        stage_ms: Vec::new(),
    };
    event_loop.run_app(&mut app).context("the window's event loop failed")?;
    // Drop the renderer before its window, then read what the validation layer said of the
    // teardown too.
    drop(app.renderer.take());
    drop(app.window.take());
    if let Some(e) = app.error.take() {
        // A station that failed (to open its window, its head tracker, ...) before any stroke
        // closes its autosave session; strokes it did make stay in the journal.
        let unsaved = app.station.unsaved_work();
        if let Some(Err(dir)) = app.station.doc.end_session() {
            eprintln!(
                "{unsaved} stroke(s) of this run are not saved: the autosave journal in {} keeps them, \
                 and `argile recover` gives them back",
                dir.display()
            );
        }
        return Err(e);
    }
    if let Some(log) = &app.validation {
        let messages = log.take();
        if !messages.is_empty() {
            bail!(
                "the Vulkan validation layer reported {} problem(s):\n{}",
                messages.len(),
                messages.join("\n")
            );
        }
    }
    if options.frames.is_some() && !app.stage_ms.is_empty() {
        let median = |i: usize| crate::math::median(app.stage_ms.iter().map(|s| s[i]).collect());
        println!(
            "frame stages, median ms over {} frames: input {:.3}, tools {:.3}, mesh {:.3}, render + composition + present {:.2}",
            app.stage_ms.len(),
            median(0),
            median(1),
            median(2),
            median(3)
        );
    }
    let mut saved = app.station.doc.saved().map(Path::to_owned);
    let stats = app.station.doc.playback.field().history_stats();
    // Quitting saves unsaved strokes, and so do a stopping signal and a scripted run given a
    // place to save (`--save-to`).
    let quitting =
        options.frames.is_none() || super::signals::received().is_some() || options.save_to.is_some();
    // Strokes made after a save are saved again.
    let changed = stats.undo_in_memory + stats.undo_on_disk > 0 && saved.is_none();
    if quitting && (changed || app.station.unsaved_work() > 0) {
        saved = Some(app.station.save_at_exit()?);
    }
    if let Some(said) = app.station.unwritten_adjustments() {
        println!("{said}");
    }
    let unsaved = app.station.unsaved_work();
    // The sculpt is safe (saved when it changed): the session closes cleanly, so nothing is
    // recovered at the next start. A scripted run with nowhere to save leaves its strokes in
    // the journal, unclosed.
    if let Some(Err(dir)) = app.station.doc.end_session() {
        println!(
            "{unsaved} stroke(s) of this run are not saved (no --save-to): the autosave journal in {} keeps \
             them, and `argile recover` gives them back",
            dir.display()
        );
    }
    Ok(StationReport { frames: app.frames, screenshot: app.screenshot, saved })
}

/// Where the station's window opens.
struct WindowPlacement {
    monitor: Option<MonitorHandle>,
    fullscreen: bool,
}

/// A window system's monitor as [`Monitor`] describes it.
fn monitor_of(m: &MonitorHandle) -> Monitor {
    Monitor {
        name: m.name().unwrap_or_else(|| "(unnamed)".to_owned()),
        position_px: (m.position().x, m.position().y),
        size_px: (m.size().width, m.size().height),
        refresh_mhz: m.refresh_rate_millihertz(),
    }
}

struct WindowApp<'s, 'o> {
    station: Station<'s>,
    /// The monitor the window was opened on, when one was chosen or it fills one.
    monitor: Option<MonitorHandle>,
    options: &'o StationOptions,
    script: InputScript,
    scene_name: &'o str,
    window_px: (u32, u32),
    /// Dropped after the renderer (see `run_station`).
    window: Option<Arc<Window>>,
    renderer: Option<Renderer>,
    /// The SpaceMouse reader thread (stopped on drop) and the gamepads, when available.
    spacemice: Option<ReaderHandle>,
    gamepads: Option<Gamepads>,
    /// The desk input settings (how SpaceMice are read, the gamepads' mapping).
    input: InputSettings,
    validation: Option<ValidationLog>,
    frames: u64,
    last: Option<Instant>,
    screenshot: Option<PathBuf>,
    error: Option<anyhow::Error>,
    /// Per frame: input, tools, mesh, and render + composition + present (waited for), ms.
    stage_ms: Vec<[f64; 4]>,
}

impl WindowApp<'_, '_> {
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let mut attributes = Window::default_attributes()
            .with_title(format!("Argile — {}", self.scene_name))
            .with_inner_size(PhysicalSize::new(self.window_px.0, self.window_px.1));
        let placement = self.placement(event_loop)?;
        if let Some(monitor) = &placement.monitor {
            let (p, size) = (monitor.position(), monitor.size());
            attributes = match placement.fullscreen {
                // The size too, so that a display without a window manager (which would honour
                // the fullscreen hint) is filled as well.
                true => attributes
                    .with_fullscreen(Some(Fullscreen::Borderless(Some(monitor.clone()))))
                    .with_position(p)
                    .with_inner_size(size),
                false => attributes.with_position(PhysicalPosition::new(
                    p.x + (size.width.saturating_sub(self.window_px.0) / 2) as i32,
                    p.y + (size.height.saturating_sub(self.window_px.1) / 2) as i32,
                )),
            };
        }
        self.station.set_fullscreen(placement.fullscreen);
        let window =
            Arc::new(event_loop.create_window(attributes).context("cannot open the station window")?);
        self.monitor = placement.monitor;
        let size = window.inner_size();
        self.window_px = (size.width, size.height);
        self.station.resize(self.window_px);
        let scene = self.station.scene;
        let environment = load_environment(&scene.environment.choice)?;
        let desc = RendererDesc {
            width: size.width.max(1),
            height: size.height.max(1),
            samples: scene.output.samples,
            validation: self.options.validation,
            view_passes: None,
        };
        super::budget::admit_render(&scene.source, desc.width, desc.height, desc.samples)?;
        let renderer = Renderer::for_window(
            &desc,
            &environment,
            scene.environment.intensity,
            window.clone(),
            self.window_px,
        )?;
        tracing::info!("station window on {}", renderer.device_name());
        let wanted = self.options.display_mode.unwrap_or(self.station.stereo.display_mode);
        let layers = renderer.window_max_layers()?.unwrap_or(1);
        if let Some(notice) = self.station.set_surface(wanted, renderer.device_name(), layers)? {
            println!("{notice}");
        }
        if let Ok(p) = window.inner_position() {
            self.station.set_window_origin((p.x, p.y));
        }
        let monitor = window.current_monitor();
        self.station.set_monitor_px(monitor.as_ref().map(|m| (m.size().width, m.size().height)));
        if self.station.display().0 == DisplayMode::FrameSequential {
            println!(
                "{}",
                frame_sequential_notice(monitor.as_ref().and_then(|m| m.refresh_rate_millihertz()))
            );
        }
        println!("{}", self.station.describe_picture());
        self.validation = Some(renderer.validation_log());
        if let Some(addr) = self.options.opentrack {
            let head = OpentrackHead::start(&self.station.screen_calibration(), Some(addr))
                .with_context(|| format!("cannot listen for opentrack datagrams on {addr}"))?;
            println!("head tracking: listening for opentrack on {addr}");
            self.station.attach_head(head);
        }
        // The 6-DoF devices, unless the run is scripted (its input is the script alone).
        if self.options.frames.is_none() {
            let socket = PathBuf::from(DEFAULT_SOCKET);
            let spacenavd = self.input.spacemouse_via.use_spacenavd(SpacenavSource::socket_present(&socket));
            let reader = if spacenavd {
                println!("SpaceMouse: reading spacenavd's socket {}", socket.display());
                ReaderHandle::spawn(
                    move || Ok(SpacenavSource::new(socket, Protocol::V0)),
                    ReaderConfig::default(),
                )
            } else {
                ReaderHandle::spawn(HidSource::new, ReaderConfig::default())
            };
            match reader {
                Ok(reader) => {
                    self.station.attach_spacemice(reader.mailbox().clone());
                    self.spacemice = Some(reader);
                }
                Err(e) => tracing::warn!("no SpaceMouse reader: {e}"),
            }
            match Gamepads::new(self.input.gamepad.0) {
                Ok(g) => self.gamepads = Some(g),
                Err(e) => tracing::warn!("no gamepads: {e}"),
            }
        }
        self.renderer = Some(renderer);
        self.window = Some(window);
        Ok(())
    }

    fn frame(&mut self) -> Result<bool> {
        let dt = match self.options.frames {
            Some(_) => SCRIPTED_STEP_S,
            None => {
                let now = Instant::now();
                let dt = self.last.map_or(SCRIPTED_STEP_S, |l| (now - l).as_secs_f32().min(0.1));
                self.last = Some(now);
                dt
            }
        };
        let started = Instant::now();
        let index = self.frames;
        let due: Vec<ScriptEvent> =
            self.script.events.iter().filter(|(f, _)| *f == index).map(|(_, e)| e.clone()).collect();
        for event in &due {
            self.station.script(event);
        }
        let mut device_actions = Vec::new();
        let mut motions = Vec::new();
        if let Some(g) = &mut self.gamepads {
            g.poll(&mut device_actions);
            motions.extend(g.motions().map(|(_, m)| m));
            self.station.set_gamepad_names(g.names());
        }
        self.station.devices(dt, &motions, device_actions);
        self.follow_fullscreen();
        // Events may still arrive for a window whose opening failed: nothing is drawn then.
        let Some(renderer) = self.renderer.as_mut() else { return Ok(false) };
        let mut failed = None;
        let frame = self.station.step(dt, |diff| {
            if let Err(e) = renderer.apply(diff) {
                failed = Some(e);
            }
        });
        if let Some(e) = failed {
            return Err(e.into());
        }
        if let (Some(rumble), Some(pads)) = (self.station.take_rumble(), &mut self.gamepads) {
            let ids: Vec<_> = pads.pad_ids().collect();
            for id in ids {
                pads.play(id, rumble);
            }
        }
        for m in self.station.messages.drain(..) {
            println!("{m}");
        }
        let last = self.options.frames.is_some_and(|n| index + 1 >= n);
        let want_shot = last && self.options.screenshot.is_some();
        let present_started = Instant::now();
        let presented = renderer.present(&frame, self.station.display(), want_shot)?;
        let t = self.station.times();
        self.stage_ms.push([t.input_ms, t.tools_ms, t.mesh_ms, ms_since(present_started)]);
        // A scripted run shows its fixed step, so its pictures do not depend on the machine.
        self.station.set_frame_time(match self.options.frames {
            Some(_) => SCRIPTED_STEP_S * 1e3,
            None => started.elapsed().as_secs_f32() * 1e3,
        });
        match presented {
            Presented::Shown(shot) => {
                self.frames += 1;
                self.station.frame_shown();
                if let (Some(image), Some(path)) = (shot, &self.options.screenshot) {
                    super::capture::save_png_atomically(&image, path)?;
                    self.screenshot = Some(path.clone());
                }
            }
            Presented::Skipped => {}
        }
        if want_shot && self.screenshot.is_none() && self.frames > index {
            bail!("the window's swapchain cannot be read back, so no screenshot was taken");
        }
        Ok(self.station.wants_quit()
            || super::signals::received().is_some()
            || self.options.frames.is_some_and(|n| self.frames >= n))
    }

    /// The monitor the window opens on (the command line's, else the scene's, else the
    /// calibration's choice; none chosen: where the window system puts it) and whether it fills
    /// it. A choice that names no monitor is refused with the list.
    fn placement(&self, event_loop: &ActiveEventLoop) -> Result<WindowPlacement> {
        let scene = &self.station.scene.display;
        let calibration = self.station.screen_calibration().display;
        let fullscreen = self.options.fullscreen || scene.fullscreen || calibration.fullscreen;
        let handles: Vec<MonitorHandle> = event_loop.available_monitors().collect();
        let monitor = match self.options.monitor.or(scene.monitor).or(calibration.monitor) {
            Some(choice) => {
                let listed: Vec<Monitor> = handles.iter().map(monitor_of).collect();
                let i = pick_monitor(choice.as_str(), &listed).map_err(|e| {
                    anyhow::anyhow!("cannot open the station window on monitor `{choice}`: {e}")
                })?;
                println!(
                    "window on monitor {i}: {}{}",
                    listed[i],
                    if fullscreen { ", filling it" } else { "" }
                );
                Some(handles[i].clone())
            }
            None if fullscreen => {
                let m = event_loop.primary_monitor().or_else(|| handles.first().cloned());
                if let Some(m) = &m {
                    println!("window filling monitor {}", monitor_of(m));
                }
                m
            }
            None => None,
        };
        Ok(WindowPlacement { monitor, fullscreen })
    }

    /// Makes the fullscreen change the user asked for (F11), on the window's monitor.
    fn follow_fullscreen(&mut self) {
        let (Some(on), Some(window)) = (self.station.take_fullscreen_request(), &self.window) else { return };
        if on {
            let monitor = self.monitor.clone().or_else(|| window.current_monitor());
            if let Some(m) = &monitor {
                window.set_outer_position(m.position());
                let _ = window.request_inner_size(m.size());
            }
            window.set_fullscreen(Some(Fullscreen::Borderless(monitor)));
        } else {
            window.set_fullscreen(None);
            let _ = window.request_inner_size(PhysicalSize::new(
                self.station.scene.output.width_px,
                self.station.scene.output.height_px,
            ));
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error = Some(e);
        event_loop.exit();
    }
}

fn modifiers_of(state: winit::keyboard::ModifiersState) -> Modifiers {
    Modifiers {
        ctrl: state.control_key(),
        shift: state.shift_key(),
        alt: state.alt_key(),
        logo: state.super_key(),
    }
}

impl ApplicationHandler for WindowApp<'_, '_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() {
            if let Err(e) = self.open(event_loop) {
                self.fail(event_loop, e);
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Moved(_) => {
                if let Some(p) = self.window.as_ref().and_then(|w| w.inner_position().ok()) {
                    self.station.set_window_origin((p.x, p.y));
                }
            }
            WindowEvent::Resized(size) => {
                self.window_px = (size.width, size.height);
                self.station.resize(self.window_px);
                if let Some(r) = &mut self.renderer {
                    r.resize_window(size.width, size.height);
                }
            }
            WindowEvent::ModifiersChanged(m) => self.station.set_modifiers(modifiers_of(m.state())),
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    self.station.key(code, event.state == ElementState::Pressed);
                }
                if let (ElementState::Pressed, Some(text)) = (event.state, &event.text) {
                    self.station.text(text);
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.station.mouse(MouseEvent::Move(Vec2::new(position.x as f32, position.y as f32)));
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let button = match button {
                    winit::event::MouseButton::Left => MouseButton::Left,
                    winit::event::MouseButton::Right => MouseButton::Right,
                    winit::event::MouseButton::Middle => MouseButton::Middle,
                    _ => return,
                };
                let event = match state {
                    ElementState::Pressed => MouseEvent::Press(button, self.station.pointer_px()),
                    ElementState::Released => MouseEvent::Release(button),
                };
                self.station.mouse(event);
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.station.mouse(MouseEvent::Wheel(steps));
            }
            WindowEvent::RedrawRequested if self.error.is_some() => {}
            WindowEvent::RedrawRequested => match self.frame() {
                Ok(true) => event_loop.exit(),
                Ok(false) => {}
                Err(e) => self.fail(event_loop, e),
            },
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::FieldReader;
    use crate::math::IVec3;
    use crate::mesh::remesh_dirty;
    use crate::stereo::BudgetMode;

    #[test]
    fn a_wheel_turned_without_end_is_refused() {
        let e = InputScript::parse("[[event]]\nframe = 1\nwheel = 1e30\n", "s.toml").unwrap_err();
        assert_eq!(
            e.to_string(),
            "s.toml:1:1: `wheel` must be -100 to 100 steps, not 1000000000000000000000000000000"
        );
        assert!(InputScript::parse("[[event]]\nframe = 1\nwheel = -100.0\n", "s.toml").is_ok());
    }

    #[test]
    fn scripts_parse_every_event_and_name_the_line_of_a_mistake() {
        let s = InputScript::parse(
            "[[event]]\nframe = 4\npress = \"Ctrl+KeyZ\"\n\
             [[event]]\nframe = 1\nhold = \"Space\"\n\
             [[event]]\nframe = 2\ndrag = { button = \"left\", from_px = [0, 0], to_px = [10, 0], steps = 2 }\n\
             [[event]]\nframe = 3\nwheel = -1.5\n",
            "s.toml",
        )
        .unwrap();
        let frames: Vec<u64> = s.events.iter().map(|(f, _)| *f).collect();
        assert_eq!(frames, [1, 2, 3, 4], "sorted by frame");
        assert_eq!(s.events[0].1, ScriptEvent::Hold(KeyCode::Space));
        assert_eq!(s.events[2].1, ScriptEvent::Wheel(-1.5));
        let e = InputScript::parse("[[event]]\nframe = 1\npress = \"KeyA\"\nwheel = 1.0\n", "s.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("s.toml:1:1:") && e.contains("exactly one"), "{e}");
        let e = InputScript::parse("[[event]]\nframe = 1\npress = \"Banana\"\n", "s.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a key name"), "{e}");
        let s = InputScript::parse(
            "[[event]]\nframe = 1\nclick = [40, 30]\n[[event]]\nframe = 2\nmove = [41.5, 30]\n",
            "s.toml",
        )
        .unwrap();
        assert_eq!(s.events[0].1, ScriptEvent::Click(Vec2::new(40.0, 30.0)));
        assert_eq!(s.events[1].1, ScriptEvent::Move(Vec2::new(41.5, 30.0)));
        let e =
            InputScript::parse("[[event]]\nframe = 1\nclick = [1e9, 0]\n", "s.toml").unwrap_err().to_string();
        assert!(e.contains("window pixel"), "{e}");
        let s = InputScript::parse("[[event]]\nframe = 1\ntype = \"bust\"\n", "s.toml").unwrap();
        assert_eq!(s.events[0].1, ScriptEvent::Text("bust".into()));
        let long = format!("[[event]]\nframe = 1\ntype = \"{}\"\n", "a".repeat(MOST_TYPED + 1));
        let e = InputScript::parse(&long, "s.toml").unwrap_err().to_string();
        assert!(e.contains("at most 1000 characters"), "{e}");
    }

    /// Clicks the panel widget whose command is `wanted`, found by clicking down the panel's
    /// band of a fresh station on `scene` (the layout is the same in every station of a size).
    fn panel_point(scene: &Scene, wanted: impl Fn(&Station<'_>) -> bool) -> Option<Vec2> {
        for y in (6..540).step_by(6) {
            for x in (10..230).step_by(16) {
                let mut station =
                    Station::new(scene, KeyBindings::shipped(), (960, 540), "unused.argile".into());
                station.set_panel_shown(true);
                station.step(SCRIPTED_STEP_S, |_| {});
                let at = Vec2::new(x as f32, y as f32);
                station.script(&ScriptEvent::Click(at));
                station.step(SCRIPTED_STEP_S, |_| {});
                station.step(SCRIPTED_STEP_S, |_| {});
                if wanted(&station) {
                    return Some(at);
                }
            }
        }
        None
    }

    #[test]
    fn the_panel_picks_the_tool_its_size_and_colour_and_the_pointer_over_it_leaves_the_view_alone() {
        let scene = ball_scene();
        let shipped = Station::new(&scene, KeyBindings::shipped(), (960, 540), "unused.argile".into());
        let (size, colour) = (shipped.desk_tool.size_m(), shipped.desk_tool.colour);
        let boxed = panel_point(&scene, |s| shape_name(&s.desk_tool.shape) == "box").expect("a box button");
        let painting = panel_point(&scene, |s| s.desk_tool.action == Action::Paint).expect("a paint button");
        let sized =
            panel_point(&scene, |s| (s.desk_tool.size_m() - size).abs() > 1e-4).expect("a size slider");
        let coloured = panel_point(&scene, |s| s.desk_tool.colour != colour).expect("a swatch");
        // The controls lie in the panel's band, top to bottom as drawn: shapes, actions, size,
        // swatches.
        assert!(boxed.y < painting.y && painting.y < sized.y && sized.y < coloured.y);
        // The pointer over the panel does not turn the view; over the scene it does.
        let mut station = Station::new(&scene, KeyBindings::shipped(), (960, 540), "unused.argile".into());
        station.set_panel_shown(true);
        station.step(SCRIPTED_STEP_S, |_| {});
        let turn = station.controls.mouse.scene_rotation;
        let drag = |from: Vec2| ScriptEvent::Drag {
            button: MouseButton::Left,
            from_px: from,
            to_px: from + Vec2::new(40.0, 0.0),
            steps: 4,
        };
        station.script(&drag(Vec2::new(60.0, 400.0)));
        station.step(SCRIPTED_STEP_S, |_| {});
        assert_eq!(station.controls.mouse.scene_rotation, turn, "a drag on the panel leaves the view");
        station.script(&drag(Vec2::new(600.0, 300.0)));
        station.step(SCRIPTED_STEP_S, |_| {});
        assert_ne!(station.controls.mouse.scene_rotation, turn, "a drag on the scene turns it");
        // F1 hides it: the whole window is the view's again.
        station.key(KeyCode::F1, true);
        station.key(KeyCode::F1, false);
        let turn = station.controls.mouse.scene_rotation;
        station.script(&drag(Vec2::new(60.0, 400.0)));
        station.step(SCRIPTED_STEP_S, |_| {});
        assert_ne!(station.controls.mouse.scene_rotation, turn, "hidden, the panel takes nothing");
    }

    #[test]
    fn the_panels_history_names_the_desk_strokes_and_a_click_goes_back_to_one() {
        let scene = ball_scene();
        let mut station = Station::new(&scene, KeyBindings::shipped(), (960, 540), "unused.argile".into());
        station.set_panel_shown(true);
        sculpt_for(&mut station, 3);
        let one = station.field().clone();
        station.controls.mouse.tool_position_m += Vec3::new(0.05, 0.0, 0.0);
        sculpt_for(&mut station, 3);
        let view = station.panel_view();
        assert_eq!(view.undo.len(), 2, "{:?}", view.undo);
        assert!(
            view.undo[0].starts_with("1. add sphere") && view.undo[1].starts_with("2. add sphere"),
            "{:?}",
            view.undo
        );
        station.panel_command(PanelCommand::Undo(1));
        assert!(station.field().same_samples(&one), "back to after the first stroke");
        let view = station.panel_view();
        assert_eq!((view.undo.len(), view.redo.len()), (1, 1));
        assert!(view.redo[0].starts_with("2. add sphere"), "{:?}", view.redo);
        station.panel_command(PanelCommand::Undo(1));
        assert_eq!(station.field().mass(), 0.0, "back to the start");
        station.panel_command(PanelCommand::Redo(2));
        assert_eq!(station.panel_view().undo.len(), 2, "both redone");
        // A new stroke after an undo: nothing to redo any more.
        station.panel_command(PanelCommand::Undo(1));
        station.controls.mouse.tool_position_m -= Vec3::new(0.0, 0.05, 0.0);
        sculpt_for(&mut station, 2);
        let view = station.panel_view();
        assert_eq!((view.undo.len(), view.redo.len()), (2, 0));
    }

    #[test]
    fn the_panel_shows_and_sets_the_level_the_parts_the_symmetry_and_the_stereo_view() {
        let scene = two_part_scene();
        let mut station = Station::new(&scene, KeyBindings::shipped(), (960, 540), "unused.argile".into());
        station.step(SCRIPTED_STEP_S, |_| {});
        let view = station.panel_view();
        let names: Vec<&str> = view.parts.iter().map(|p| p.name.as_str()).collect();
        assert_eq!((names, view.active_part), (vec!["left", "right"], 0));
        assert_eq!(view.parts[1].voxel_mm, 2.0);
        station.panel_command(PanelCommand::ActivePart(1));
        assert_eq!(station.doc.playback.assembly().active(), 1, "the list picks the part");
        assert_eq!(station.panel_view().active_part, 1);
        // The level: by size, then the finest.
        station.panel_command(PanelCommand::LevelBySize);
        assert_eq!(station.panel_view().level_samples, Some(HAND_SIZE_SAMPLES));
        station.panel_command(PanelCommand::LevelSamples(None));
        let view = station.panel_view();
        assert_eq!(view.level_samples, None);
        assert_eq!(view.level.0, 0, "the finest level");
        assert_eq!(view.level.1, 2.0, "of the active part's 2 mm voxels");
        station.panel_command(PanelCommand::LevelSamples(Some(f32::NAN)));
        assert_eq!(station.panel_view().level_samples, None, "no NaN taken");
        // Symmetry on and off.
        assert!(!station.panel_view().symmetry.1);
        station.panel_command(PanelCommand::ToggleSymmetry);
        let (said, on) = station.panel_view().symmetry;
        assert!(on && said.starts_with("mirror"), "{said}");
        station.panel_command(PanelCommand::ToggleSymmetry);
        assert!(!station.panel_view().symmetry.1);
        // The stereo view: the sliders move the rig, within its range; the readout follows.
        let disparity = station.panel_view().stereo.disparity.expect("the clay's disparity after a frame");
        assert!(disparity.nearest_deg <= disparity.farthest_deg && disparity.bound_deg > 0.0);
        station.panel_command(PanelCommand::ConvergenceM(0.9));
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!((station.view.rig.convergence_m - 0.9).abs() < 1e-3, "{}", station.view.rig.convergence_m);
        station.panel_command(PanelCommand::ConvergenceM(1e9));
        station.step(SCRIPTED_STEP_S, |_| {});
        assert_eq!(
            station.view.rig.convergence_m,
            station.view.rig.convergence_range().1,
            "held at its far end"
        );
        station.panel_command(PanelCommand::InteraxialMm(40.0));
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!((station.panel_view().stereo.interaxial_mm - 40.0).abs() < 1e-3);
        let wider = station.panel_view().stereo.disparity.unwrap();
        station.panel_command(PanelCommand::InteraxialMm(120.0));
        station.step(SCRIPTED_STEP_S, |_| {});
        let widest = station.panel_view().stereo.disparity.unwrap();
        assert!(
            widest.farthest_deg - widest.nearest_deg > wider.farthest_deg - wider.nearest_deg,
            "eyes further apart, more disparity: {wider:?} then {widest:?}"
        );
        station.panel_command(PanelCommand::AutoConvergence(true));
        assert!(station.panel_view().stereo.auto_convergence);
        station.panel_command(PanelCommand::SwapEyes(true));
        assert!(station.panel_view().stereo.swap_eyes);
        station.panel_command(PanelCommand::LightsFollowViewer(true));
        assert!(station.panel_view().stereo.lights_follow_viewer);
        assert_eq!(station.panel_view().stereo.head, None, "no head tracker here");
    }

    /// An empty scene whose first tool adds clay with a 3 cm ball.
    fn ball_scene() -> Scene {
        let text = "[[tool]]\nname = \"ball\"\nshape = \"sphere\"\nradius_m = 0.03\naction = \"add\"\n";
        Scene::parse(text, "ball", None).unwrap()
    }

    /// Holds the sculpt key for `frames` frames, then one frame released.
    fn sculpt_for(station: &mut Station<'_>, frames: usize) {
        station.key(KeyCode::Space, true);
        for _ in 0..frames {
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        station.key(KeyCode::Space, false);
        station.step(SCRIPTED_STEP_S, |_| {});
    }

    fn small_station(scene: &Scene) -> Station<'_> {
        Station::new(scene, KeyBindings::shipped(), (64, 64), PathBuf::from("unused.argile"))
    }

    #[test]
    fn the_mouse_places_the_tool_in_the_eye_it_points_at_in_half_modes() {
        let scene = ball_scene();
        let place = |mode: DisplayMode, at: Vec2| {
            let mut station =
                Station::new(&scene, KeyBindings::shipped(), (480, 200), PathBuf::from("u.argile"));
            station.stereo.display_mode = mode;
            station.fit_views();
            station.act(StationAction::ToggleMouseMode);
            station.mouse(MouseEvent::Move(at));
            station.mouse(MouseEvent::Press(MouseButton::Left, station.pointer_px()));
            station.mouse(MouseEvent::Release(MouseButton::Left));
            station.controls.mouse.tool_position_m
        };
        // Pixel (280, 120) of each eye's 480 × 200 picture, off its centre.
        let mono = place(DisplayMode::Mono, Vec2::new(280.0, 120.0));
        for (mode, window_px) in [
            (DisplayMode::SideBySideHalf, Vec2::new(380.0, 120.0)),
            (DisplayMode::SideBySideHalf, Vec2::new(140.0, 120.0)),
            (DisplayMode::TopBottomHalf, Vec2::new(280.0, 160.0)),
        ] {
            let tool = place(mode, window_px);
            assert!(tool.distance(mono) < 1e-4, "{mode} at {window_px}: {tool}, where mono puts {mono}");
        }
    }

    #[test]
    fn the_floating_window_masks_the_edge_the_near_clay_touches_and_follows_the_swap() {
        // A ball 0.35 m from the eyes (the zero-parallax plane at 0.5 m) on the left edge.
        let text = "[camera]\neye_m = [0.0, 0.0, 0.5]\ntarget_m = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\n\
                    convergence_m = 0.5\ninteraxial_m = 0.063\n[stage]\nshow = false\n\
                    [[clay]]\nshape = \"sphere\"\nradius_m = 0.03\nposition_m = [-0.127, 0.0, 0.15]\n\
                    [[tool]]\nname = \"b\"\nradius_m = 0.01\naction = \"add\"\n";
        let scene = Scene::parse(text, "edge", None).unwrap();
        let mut station = small_station(&scene);
        let frames = |station: &mut Station<'_>, n: usize| {
            (0..n).map(|_| station.step(SCRIPTED_STEP_S, |_| {}).floating_window).last().unwrap()
        };
        assert_eq!(frames(&mut station, 3), FloatingWindow::NONE, "off unless asked");
        station.act(StationAction::ToggleFloatingWindow);
        assert!(station.messages.iter().any(|m| m.starts_with("floating window:")), "{:?}", station.messages);
        let first = frames(&mut station, 1);
        let settled = frames(&mut station, 60);
        // The crossed parallax of the ball's front at the edge: p = e (C − Z) / Z over the
        // plane's width, 2 C tan 20°; its nearest point (Z = 0.32 m) bounds it.
        let bound = 0.063 * (0.5 - 0.32) / 0.32 / (2.0 * 0.5 * 20f32.to_radians().tan());
        let strip = settled.strips[0].left;
        assert!(strip > 0.5 * bound && strip <= bound * 1.01, "{settled:?}, at most {bound}");
        assert!(first.strips[0].left > 0.0 && first.strips[0].left < strip, "it eases in: {first:?}");
        assert_eq!((settled.strips[0].right, settled.strips[1]), (0.0, Default::default()));
        assert!(station.hud_lines().iter().any(|l| l.contains("floating window")));
        // Swapped pictures carry their strips.
        station.act(StationAction::SwapEyes);
        let swapped = frames(&mut station, 1);
        assert!(
            (swapped.strips[1].left - strip).abs() < 1e-3 && swapped.strips[0].left == 0.0,
            "{swapped:?}"
        );
        station.act(StationAction::SwapEyes);
        // Mono shows one picture whole; turned off, the strips slide away.
        station.stereo.display_mode = DisplayMode::Mono;
        assert_eq!(frames(&mut station, 120), FloatingWindow::NONE);
        station.stereo.display_mode = DisplayMode::Anaglyph;
        frames(&mut station, 60);
        station.panel_command(PanelCommand::FloatingWindow(false));
        assert!(!station.panel_view().stereo.floating_window);
        assert_eq!(frames(&mut station, 120), FloatingWindow::NONE);
        // A scene may ask for it.
        let asked =
            Scene::parse(&format!("[display]\nfloating_window = true\n{text}"), "asked", None).unwrap();
        assert!(frames(&mut small_station(&asked), 60).strips[0].left > 0.0);
    }

    #[test]
    fn the_swap_key_gives_each_eye_the_others_image_and_the_parity_key_flips_the_rows() {
        let scene = ball_scene();
        let mut station = small_station(&scene);
        let before = station.step(SCRIPTED_STEP_S, |_| {}).views;
        station.act(StationAction::SwapEyes);
        let swapped = station.step(SCRIPTED_STEP_S, |_| {}).views;
        assert_eq!(swapped.eyes[0], before.eyes[1]);
        assert_eq!(swapped.eyes[1], before.eyes[0]);
        assert!(station.messages.iter().any(|m| m.starts_with("eyes swapped")), "{:?}", station.messages);
        station.act(StationAction::SwapEyes);
        assert_eq!(station.step(SCRIPTED_STEP_S, |_| {}).views, before);
        // A scene that asks for it starts swapped.
        let text = "[display]\nswap_eyes = true\n[[tool]]\nname = \"b\"\nradius_m = 0.03\naction = \"add\"\n";
        let swapped_scene = Scene::parse(text, "swapped", None).unwrap();
        let mut other = small_station(&swapped_scene);
        assert_eq!(other.step(SCRIPTED_STEP_S, |_| {}).views, swapped);
        let parity = station.display().1;
        station.act(StationAction::FlipParity);
        assert_eq!(station.display().1, parity.flipped());
        station.act(StationAction::FlipParity);
        assert_eq!(station.display().1, parity);
    }

    #[test]
    fn a_frame_sequential_window_shows_the_eyes_in_turn_and_the_parity_key_swaps_their_phase() {
        let scene = ball_scene();
        let mut station = small_station(&scene);
        station.set_surface(DisplayMode::FrameSequential, "llvmpipe", 1).unwrap();
        let eye = |s: &Station<'_>| {
            let (mode, parity) = s.display();
            assert_eq!(mode, DisplayMode::FrameSequential);
            parity.offset()
        };
        let mut shown = Vec::new();
        for _ in 0..4 {
            shown.push(eye(&station));
            station.frame_shown();
        }
        assert_eq!(shown, [0, 1, 0, 1], "left, right, left, right");
        // The window moving does not change the phase (rows are not what alternates).
        station.set_window_origin((1, 1));
        assert_eq!(eye(&station), 0);
        station.act(StationAction::FlipParity);
        assert_eq!(eye(&station), 1, "the frame that would have shown the left eye shows the right");
        assert!(
            station.messages.iter().any(|m| m.starts_with("frame-sequential phase left-odd")),
            "{:?}",
            station.messages
        );
        station.frame_shown();
        assert_eq!(eye(&station), 0);
    }

    #[test]
    fn the_stereo_keys_stop_at_their_limits_and_say_so() {
        let scene = ball_scene();
        let mut station = small_station(&scene);
        for _ in 0..20 {
            station.act(StationAction::InteraxialWider);
        }
        station.step(SCRIPTED_STEP_S, |_| {});
        assert_eq!(station.view.rig.interaxial_m, StereoRig::MAX_INTERAXIAL_M, "250 mm at most, not 437");
        assert!(
            station.messages.iter().any(|m| m.contains("250 mm apart: at the most")),
            "{:?}",
            station.messages
        );
        station.messages.clear();
        for _ in 0..40 {
            station.act(StationAction::ConvergenceNearer);
        }
        station.step(SCRIPTED_STEP_S, |_| {});
        let rig = station.view.rig;
        assert!(
            (rig.convergence_m - 2.0 * rig.near_m).abs() < 1e-6,
            "{} m, outside the near plane",
            rig.convergence_m
        );
        assert!(station.messages.iter().any(|m| m.contains("at its nearest")), "{:?}", station.messages);
        // One press back moves it at once: the keys did not pile up beyond the limit.
        station.act(StationAction::ConvergenceFarther);
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(station.view.rig.convergence_m > 2.0 * rig.near_m * 1.05);
        for _ in 0..80 {
            station.act(StationAction::ConvergenceFarther);
        }
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!((station.view.rig.convergence_m - 0.5 * rig.far_m).abs() < 1e-4);
    }

    #[test]
    fn the_symmetry_keys_mirror_the_desk_stroke_and_undo_takes_back_both_sides() {
        let scene = ball_scene();
        let mut station = small_station(&scene);
        station.key(KeyCode::KeyY, true);
        station.key(KeyCode::KeyY, false);
        assert!(station.messages.iter().any(|m| m == "symmetry mirror x"), "{:?}", station.messages);
        assert!(station.hud_lines()[0].ends_with(", mirror x"), "{:?}", station.hud_lines());
        // A stroke to the right of the plane x = 0 through the scene's centre.
        station.controls.mouse.tool_position_m = Vec3::new(0.06, 0.0, 0.0);
        let frame = station.step(SCRIPTED_STEP_S, |_| {});
        assert!(frame.tools.len() >= 3, "the tool, its mirror image and the plane are drawn");
        sculpt_for(&mut station, 3);
        let field = station.doc.playback.field();
        let t = *field.transform();
        let at = |x: f32| field.density(t.world_to_index(Vec3::new(x, 0.0, 0.0)).round().as_ivec3());
        assert!(at(0.06) > 0.9 && at(-0.06) > 0.9, "both sides: {} {}", at(0.06), at(-0.06));
        let reach = t.metres_to_voxels(0.1) as i32;
        for i in (1..reach).step_by(3) {
            for j in (-reach..reach).step_by(5) {
                let (p, q) = (IVec3::new(i, j, 0), IVec3::new(-i, j, 0));
                assert_eq!(field.density(p), field.density(q), "the sides differ at {p}");
            }
        }
        station.act(StationAction::Undo);
        assert_eq!(station.doc.playback.field().mass(), 0.0, "one undo takes back both sides");
        // Shift+Y steps on to mirror X and Z: four images of one stroke.
        station.set_modifiers(Modifiers { shift: true, ..Modifiers::default() });
        station.key(KeyCode::KeyY, true);
        station.key(KeyCode::KeyY, false);
        assert_eq!(station.doc.playback.images().len(), 4);
        station.set_modifiers(Modifiers::default());
        station.key(KeyCode::KeyY, true);
        assert_eq!(station.doc.playback.images().len(), 1, "Y switches it off");
    }

    #[test]
    fn the_region_keys_carry_copy_bend_and_inflate_the_clay_under_the_tool_each_one_undo_step() {
        let scene = ball_scene();
        let mut station = small_station(&scene);
        station.controls.mouse.tool_position_m = Vec3::ZERO;
        sculpt_for(&mut station, 2);
        let ball = station.doc.playback.field().clone();
        let mass = ball.mass();
        let at = |station: &Station<'_>, p: Vec3| {
            let f = station.doc.playback.field();
            f.density(f.transform().world_to_index(p).round().as_ivec3())
        };
        assert!(at(&station, Vec3::ZERO) > 0.9);
        // G held: the ball's region is carried 8 cm along X with the tool.
        let carry = |station: &mut Station<'_>, key: KeyCode| {
            station.controls.mouse.tool_position_m = Vec3::ZERO;
            station.key(key, true);
            station.step(SCRIPTED_STEP_S, |_| {});
            for x in [0.03, 0.06, 0.08] {
                station.controls.mouse.tool_position_m = Vec3::new(x, 0.0, 0.0);
                let frame = station.step(SCRIPTED_STEP_S, |_| {});
                assert!(!frame.tools.is_empty(), "the carried region is drawn");
            }
            station.key(key, false);
            station.step(SCRIPTED_STEP_S, |_| {});
        };
        carry(&mut station, KeyCode::KeyG);
        assert!(at(&station, Vec3::ZERO) < 0.1 && at(&station, Vec3::new(0.08, 0.0, 0.0)) > 0.9, "moved");
        let moved = station.doc.playback.field().mass();
        assert!((moved - mass).abs() < 1e-3 * mass, "{mass} → {moved}");
        station.act(StationAction::Undo);
        assert!(station.doc.playback.field().same_samples(&ball), "one undo takes the move back");
        // K held: a copy goes with the tool; the ball stays.
        carry(&mut station, KeyCode::KeyK);
        assert!(at(&station, Vec3::ZERO) > 0.9 && at(&station, Vec3::new(0.08, 0.0, 0.0)) > 0.9, "copied");
        station.act(StationAction::Undo);
        assert!(station.doc.playback.field().same_samples(&ball));
        // I and Shift+I: the surface within the tool grows, then shrinks.
        station.controls.mouse.tool_position_m = Vec3::new(0.03, 0.0, 0.0);
        station.step(SCRIPTED_STEP_S, |_| {});
        station.act(StationAction::InflateRegion);
        assert!(station.doc.playback.field().mass() > mass, "inflated");
        station.act(StationAction::DeflateRegion);
        station.act(StationAction::DeflateRegion);
        assert!(station.doc.playback.field().mass() < mass, "deflated");
        for _ in 0..3 {
            station.act(StationAction::Undo);
        }
        assert!(station.doc.playback.field().same_samples(&ball), "one undo step each");
        // B held at the ball's edge: the clay there follows the tool out.
        station.controls.mouse.tool_position_m = Vec3::new(0.03, 0.0, 0.0);
        station.key(KeyCode::KeyB, true);
        station.step(SCRIPTED_STEP_S, |_| {});
        station.controls.mouse.tool_position_m = Vec3::new(0.05, 0.0, 0.0);
        station.step(SCRIPTED_STEP_S, |_| {});
        station.key(KeyCode::KeyB, false);
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(at(&station, Vec3::new(0.045, 0.0, 0.0)) > 0.5, "the edge was pulled out");
        assert!(at(&station, Vec3::new(-0.025, 0.0, 0.0)) > 0.5, "the far side stays");
    }

    #[test]
    fn u_held_drags_out_a_box_the_region_keys_then_act_on_which_follows_the_clay_and_a_tap_clears() {
        let scene = ball_scene();
        let mut station = small_station(&scene);
        station.controls.mouse.tool_position_m = Vec3::ZERO;
        sculpt_for(&mut station, 2);
        let ball = station.doc.playback.field().clone();
        let at = |station: &Station<'_>, p: Vec3| {
            let f = station.doc.playback.field();
            f.density(f.transform().world_to_index(p).round().as_ivec3())
        };
        let tool_at = |station: &mut Station<'_>, p: Vec3| {
            station.controls.mouse.tool_position_m = p;
            station.step(SCRIPTED_STEP_S, |_| {})
        };
        // U held from one corner of the ball's box to the other.
        tool_at(&mut station, Vec3::splat(-0.045));
        station.key(KeyCode::KeyU, true);
        tool_at(&mut station, Vec3::splat(-0.045));
        tool_at(&mut station, Vec3::ZERO);
        let frame = tool_at(&mut station, Vec3::splat(0.045));
        assert!(frame.tools.iter().any(|g| g.colour == super::super::frame::SELECTION_COLOUR), "drawn");
        station.key(KeyCode::KeyU, false);
        tool_at(&mut station, Vec3::splat(0.045));
        assert!(
            station.messages.last().unwrap().contains("box of 90 × 90 × 90 mm selected"),
            "{:?}",
            station.messages
        );
        // G held with the tool 10 cm from the ball, out of its reach: the box carries the ball.
        tool_at(&mut station, Vec3::new(0.1, 0.0, 0.0));
        station.key(KeyCode::KeyG, true);
        tool_at(&mut station, Vec3::new(0.1, 0.0, 0.0));
        tool_at(&mut station, Vec3::new(0.15, 0.0, 0.0));
        tool_at(&mut station, Vec3::new(0.2, 0.0, 0.0));
        station.key(KeyCode::KeyG, false);
        tool_at(&mut station, Vec3::new(0.2, 0.0, 0.0));
        assert!(at(&station, Vec3::ZERO) < 0.1 && at(&station, Vec3::new(0.1, 0.0, 0.0)) > 0.9, "moved");
        let (_, selected) = station.doc.playback.selection().expect("still selected");
        assert!((selected.centre_m() - Vec3::new(0.1, 0.0, 0.0)).length() < 1e-5, "the box follows the clay");
        station.act(StationAction::Undo);
        assert!(station.doc.playback.field().same_samples(&ball), "one undo takes the move back");
        // A tap of U clears it: G with the tool out of reach moves nothing.
        station.key(KeyCode::KeyU, true);
        tool_at(&mut station, Vec3::new(0.1, 0.0, 0.0));
        station.key(KeyCode::KeyU, false);
        tool_at(&mut station, Vec3::new(0.1, 0.0, 0.0));
        assert!(station.doc.playback.selection().is_none());
        assert!(station.messages.last().unwrap().contains("selection cleared"));
        station.key(KeyCode::KeyG, true);
        tool_at(&mut station, Vec3::new(0.1, 0.0, 0.0));
        tool_at(&mut station, Vec3::new(0.2, 0.0, 0.0));
        station.key(KeyCode::KeyG, false);
        tool_at(&mut station, Vec3::new(0.2, 0.0, 0.0));
        assert!(at(&station, Vec3::ZERO) > 0.9, "the tool's own shape held nothing of the ball");
    }

    #[test]
    fn j_copies_the_region_into_a_new_active_part_which_the_part_device_carries_and_undo_takes_away() {
        let scene = ball_scene();
        let mut station = small_station(&scene);
        station.controls.mouse.tool_position_m = Vec3::ZERO;
        sculpt_for(&mut station, 2);
        let ball = station.doc.playback.field().clone();
        station.key(KeyCode::KeyJ, true);
        station.key(KeyCode::KeyJ, false);
        station.step(SCRIPTED_STEP_S, |_| {});
        let parts = station.doc.playback.assembly();
        assert_eq!((parts.parts().len(), parts.active()), (2, 1), "{:?}", station.messages);
        assert!(station
            .messages
            .iter()
            .any(|m| m.contains("copied into a new part") && m.contains("clay copy")));
        assert!(station.doc.playback.field().same_samples(&ball));
        // A gamepad on the part target carries the copy away along X; the ball stays.
        let moved = carry_part_along_x(&mut station);
        assert!(moved.x > 0.001, "{moved}");
        assert!(station.doc.playback.field().same_samples(&ball));
        // Undo takes back the carry, then the part.
        let_the_gamepad_go(&mut station);
        station.act(StationAction::Undo);
        station.act(StationAction::Undo);
        assert_eq!(station.doc.playback.assembly().parts().len(), 1);
        assert!(station.doc.playback.field().same_samples(&ball));
        // The panel's Parts section has the same copy.
        station.panel_command(PanelCommand::CopyToPart);
        assert_eq!(station.doc.playback.assembly().parts().len(), 2, "{:?}", station.messages);
    }

    #[test]
    fn the_lattice_keys_open_shape_apply_and_put_back_a_lattice_each_one_undo_step() {
        let scene = ball_scene();
        let mut station = small_station(&scene);
        station.controls.mouse.tool_position_m = Vec3::ZERO;
        sculpt_for(&mut station, 2);
        let ball = station.doc.playback.field().clone();
        let (mass, steps) = (ball.mass(), station.doc.playback.field().history_stats().undo_in_memory);
        let press = |station: &mut Station<'_>, chord: &str| {
            let chord = Chord::parse(chord).unwrap();
            station.controls.modifiers = chord.modifiers;
            station.key(chord.key, true);
            station.key(chord.key, false);
            station.controls.modifiers = Modifiers::default();
            station.step(SCRIPTED_STEP_S, |_| {})
        };
        // Shift+F: a lattice over the whole ball, drawn, the clay untouched.
        let frame = press(&mut station, "Shift+KeyF");
        let held = station.doc.playback.held_lattice().expect("a lattice is open");
        assert_eq!(held.lattice().volume().counts(), [4, 4, 4]);
        assert!(frame.tools.len() > 64, "its 64 controls, their lines and the picked one are drawn");
        assert!(station.doc.playback.field().same_samples(&ball));
        // The tool picks the control nearest it; R three times swells the clay there.
        station.controls.mouse.tool_position_m = Vec3::splat(0.012);
        station.step(SCRIPTED_STEP_S, |_| {});
        let picked = station.doc.playback.held_lattice().unwrap().picked();
        assert!(picked.iter().all(|&i| i == 2), "the interior control nearest the tool: {picked:?}");
        for _ in 0..3 {
            press(&mut station, "KeyR");
        }
        let swelled = station.doc.playback.field().mass();
        assert!(swelled > mass * 1.01, "raised values swell the clay: {mass} → {swelled}");
        // The tools wait while it is open.
        sculpt_for(&mut station, 2);
        assert_eq!(station.doc.playback.field().mass(), swelled, "no stroke while a lattice is open");
        assert!(station.messages.iter().any(|m| m.contains("a lattice is open")));
        // V shows a slice through the picked control's patch: its stems and a zero contour.
        let plain = station.step(SCRIPTED_STEP_S, |_| {}).tools.len();
        for _ in 0..3 {
            press(&mut station, "KeyV");
        }
        assert_eq!(station.doc.playback.held_lattice().unwrap().slice(), Some(2));
        let sliced = station.step(SCRIPTED_STEP_S, |_| {});
        let contour = sliced.tools.iter().filter(|g| g.colour == crate::app::glyphs::CONTOUR_COLOUR).count();
        assert!(contour > 8, "the ball's section drawn as a contour: {contour}");
        assert_eq!(sliced.tools.len(), plain + 16 + contour, "a stem per control of the patch");
        for _ in 0..2 {
            press(&mut station, "KeyV");
        }
        assert_eq!(station.doc.playback.held_lattice().unwrap().slice(), None, "after the last, none");
        // Enter applies it: one undo step, which takes it back bit for bit; redo puts it again.
        press(&mut station, "Enter");
        assert!(station.doc.playback.held_lattice().is_none());
        assert_eq!(station.doc.playback.field().history_stats().undo_in_memory, steps + 1);
        station.act(StationAction::Undo);
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(station.doc.playback.field().same_samples(&ball), "one undo takes the lattice back");
        station.act(StationAction::Redo);
        assert_eq!(station.doc.playback.field().mass(), swelled);
        station.act(StationAction::Undo);
        // F around the tool, D held drags the picked control 1 cm out, Backspace puts it all
        // back and leaves no step.
        station.controls.mouse.tool_position_m = Vec3::new(0.02, 0.0, 0.0);
        press(&mut station, "KeyF");
        let spec = *station.doc.playback.held_lattice().unwrap().lattice().spec();
        assert!((spec.region.size().x - 0.12).abs() < 1e-4, "twice the tool's size about it: {spec:?}");
        station.key(KeyCode::KeyD, true);
        station.step(SCRIPTED_STEP_S, |_| {});
        station.controls.mouse.tool_position_m = Vec3::new(0.03, 0.0, 0.0);
        station.step(SCRIPTED_STEP_S, |_| {});
        station.key(KeyCode::KeyD, false);
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(!station.doc.playback.field().same_samples(&ball), "the drag warped the clay");
        press(&mut station, "Backspace");
        assert!(station.doc.playback.held_lattice().is_none());
        assert!(station.doc.playback.field().same_samples(&ball), "put back bit for bit");
        assert_eq!(station.doc.playback.field().history_stats().undo_in_memory, steps, "no step left");
        // Undo while one is open closes it the same way.
        press(&mut station, "KeyF");
        press(&mut station, "KeyR");
        station.act(StationAction::Undo);
        assert!(station.doc.playback.held_lattice().is_none());
        assert!(station.doc.playback.field().same_samples(&ball));
        assert_eq!(station.doc.playback.field().history_stats().undo_in_memory, steps);
    }

    #[test]
    fn the_desk_opens_lattices_of_the_kind_counts_order_and_knots_chosen() {
        use crate::spline::SplineKind;
        let scene = ball_scene();
        let mut station = small_station(&scene);
        station.controls.mouse.tool_position_m = Vec3::ZERO;
        sculpt_for(&mut station, 2);
        let ball = station.doc.playback.field().clone();
        let chord = Chord::parse("Ctrl+KeyF").unwrap();
        station.controls.modifiers = chord.modifiers;
        station.key(chord.key, true);
        station.key(chord.key, false);
        station.controls.modifiers = Modifiers::default();
        assert_eq!(
            station.doc.playback.lattice_form().kind,
            SplineKind::Bezier,
            "Ctrl+F: NURBS, then Bézier"
        );
        assert!(station.messages.last().unwrap().starts_with("lattices open as: Bézier, 4 × 4 × 4"));
        // The panel sets a quadratic B-spline of 6 × 3 × 2 controls with uniform knots.
        let form = crate::lattice::LatticeForm {
            kind: SplineKind::BSpline,
            counts: [6, 3, 2],
            order: 3,
            knots: crate::spline::KnotStyle::Uniform,
        };
        station.panel_command(PanelCommand::LatticeForm(form));
        assert_eq!(station.panel_view().lattice.form, form);
        station.panel_command(PanelCommand::OpenLattice(true));
        let held = station.doc.playback.held_lattice().expect("the panel opened one over the part");
        let spec = *held.lattice().spec();
        assert_eq!((spec.kind, spec.counts, spec.order, spec.knots), (form.kind, form.counts, 3, form.knots));
        assert!(station
            .messages
            .last()
            .unwrap()
            .contains("quadratic B-spline, 6 × 3 × 2 controls, uniform knots"));
        let row = station.panel_view().lattice;
        assert!(
            row.open.as_deref().is_some_and(|o| o.starts_with("open: quadratic B-spline")) && !row.weighted
        );
        // A B-spline has no weights: the weight key says so and changes nothing.
        station.act(StationAction::HeavierWeight);
        assert!(
            station.messages.last().unwrap().starts_with("the control's weight stays"),
            "{:?}",
            station.messages
        );
        // The panel's buttons shape and apply it: one undo step.
        station.panel_command(PanelCommand::ControlValue(true));
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(!station.doc.playback.field().same_samples(&ball));
        station.panel_command(PanelCommand::ApplyLattice);
        assert!(station.doc.playback.held_lattice().is_none());
        station.act(StationAction::Undo);
        assert!(station.doc.playback.field().same_samples(&ball), "one undo takes it back");
        // Out of range counts and orders are brought within 2 to 16.
        station.panel_command(PanelCommand::LatticeForm(crate::lattice::LatticeForm {
            counts: [1, 40, 4],
            order: 0,
            ..form
        }));
        assert_eq!(station.doc.playback.lattice_form().counts, [2, 16, 4]);
        assert_eq!(station.doc.playback.lattice_form().order, 2);
    }

    #[test]
    fn a_lattice_left_open_is_saved_over_the_clay_it_opened_on_and_opens_again_as_it_was() {
        let dir = std::env::temp_dir().join(format!("argile-station-lattice-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("open-lattice.argile");
        let scene = ball_scene();
        let mut station = Station::new(&scene, KeyBindings::shipped(), (64, 64), path.clone());
        station.controls.mouse.tool_position_m = Vec3::ZERO;
        sculpt_for(&mut station, 2);
        let ball = station.doc.playback.field().clone();
        let steps = ball_steps(&station);
        station.act(StationAction::OpenPartLattice);
        station.controls.mouse.tool_position_m = Vec3::splat(0.012);
        station.step(SCRIPTED_STEP_S, |_| {});
        for _ in 0..3 {
            station.act(StationAction::RaiseValue);
        }
        station.act(StationAction::HeavierWeight);
        station.step(SCRIPTED_STEP_S, |_| {});
        let shaped = station.doc.playback.field().clone();
        assert!(!shaped.same_samples(&ball));
        station.save().unwrap();
        assert!(
            station.doc.playback.field().same_samples(&shaped),
            "saving leaves the lattice's work in place"
        );
        assert!(station.doc.playback.held_lattice().is_some(), "and the lattice open");
        // The file: the clay as the lattice found it, its history, and the lattice.
        let stored = crate::app::load_sculpt(&path).unwrap();
        assert!(stored.field.same_samples(&ball));
        assert_eq!(stored.field.history_stats().undo_in_memory, steps);
        let lattice = stored.lattice.clone().expect("the open lattice is stored");
        assert_eq!(lattice, station.doc.playback.held_lattice().unwrap().stored());
        // What only wants the shape gets it applied.
        let info = crate::app::describe_sculpt(&path).unwrap();
        assert!(
            info.contains("a lattice left open over part 0: 4 × 4 × 4 nurbs controls of order 4"),
            "{info}"
        );
        let applied = crate::app::with_lattice_applied(stored, &path).unwrap();
        assert!(applied.field.same_samples(&shaped) && applied.lattice.is_none());
        // Opened again, the lattice is open as it was left, and one undo step when applied.
        let mut again = Station::new(&scene, KeyBindings::shipped(), (64, 64), dir.join("other.argile"));
        again.open(&path).unwrap();
        let held = again.doc.playback.held_lattice().expect("open again");
        assert_eq!(held.stored(), lattice);
        assert!(again.doc.playback.field().same_samples(&shaped), "shaped as it was saved");
        again.act(StationAction::ApplyLattice);
        assert_eq!(ball_steps(&again), steps + 1);
        again.act(StationAction::Undo);
        assert!(again.doc.playback.field().same_samples(&ball));
        // A version that cannot keep it refuses rather than lose it.
        let old = dir.join("v5.argile");
        let options = crate::io::EncodeOptions { version: 5, history: true };
        let e = crate::app::convert_sculpt(&path, &old, options, false).unwrap_err();
        assert!(format!("{e:#}").contains("holds a lattice left open"), "{e:#}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    fn ball_steps(station: &Station<'_>) -> usize {
        station.doc.playback.field().history_stats().undo_in_memory
    }

    #[test]
    fn keys_sculpt_undo_and_redo_through_the_bindings() {
        let scene = ball_scene();
        let mut station = small_station(&scene);
        let mut applied = 0;
        station.step(SCRIPTED_STEP_S, |_| applied += 1);
        assert_eq!(station.doc.playback.field().mass(), 0.0, "nothing sculpted yet");
        // Sculpt while moving, over many frames: still one stroke, one undo step.
        station.key(KeyCode::Space, true);
        station.key(KeyCode::ArrowRight, true);
        for _ in 0..20 {
            station.step(SCRIPTED_STEP_S, |_| applied += 1);
        }
        station.key(KeyCode::Space, false);
        station.key(KeyCode::ArrowRight, false);
        station.step(SCRIPTED_STEP_S, |_| applied += 1);
        let sculpted = station.doc.playback.field().mass();
        assert!(sculpted > 0.0 && applied > 0, "holding apply adds clay and remeshes");

        station.set_modifiers(Modifiers { ctrl: true, ..Default::default() });
        station.key(KeyCode::KeyZ, true);
        station.key(KeyCode::KeyZ, false);
        assert_eq!(station.doc.playback.field().mass(), 0.0, "ctrl+z undoes the stroke");
        station.key(KeyCode::KeyY, true);
        station.key(KeyCode::KeyY, false);
        assert_eq!(station.doc.playback.field().mass(), sculpted, "ctrl+y redoes it");
        station.set_modifiers(Modifiers::default());
        station.key(KeyCode::KeyZ, true);
        assert_eq!(station.doc.playback.field().mass(), sculpted, "z alone is not undo");

        // S cycles the shapes at the same size, back to the sphere; ] grows the tool.
        let size = station.desk_tool.size_m();
        let mut names = Vec::new();
        for _ in 0..5 {
            station.key(KeyCode::KeyS, true);
            station.key(KeyCode::KeyS, false);
            names.push(shape_name(&station.desk_tool.shape));
            assert!((station.desk_tool.size_m() - size).abs() < 1e-6, "same size");
        }
        assert_eq!(names, ["box", "cylinder", "torus", "ellipsoid", "sphere"]);
        station.key(KeyCode::BracketRight, true);
        assert!((station.desk_tool.size_m() - size * SIZE_STEP).abs() < 1e-6);
        let shown = format!("sphere {} mm", (station.desk_tool.size_m() * 1000.0).round());
        assert!(station.hud_lines()[0].contains(&shown), "{:?}", station.hud_lines());
    }

    #[test]
    fn arrow_keys_move_the_tool_in_the_view_and_the_wheel_zooms() {
        let scene = Scene::default_scene();
        let mut station =
            Station::new(&scene, KeyBindings::shipped(), (64, 64), PathBuf::from("unused.argile"));
        let start = station.controls.mouse.tool_position_m;
        station.key(KeyCode::ArrowRight, true);
        for _ in 0..60 {
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        let moved = station.controls.mouse.tool_position_m - start;
        let right = station.view.rig.right();
        assert!((moved - right * POINTER_SPEED_M_PER_S).length() < 1e-4, "a second of ArrowRight: {moved}");
        let before = station.view.rig.eye_m.distance(station.view.rig.target_m);
        station.script(&ScriptEvent::Wheel(2.0));
        station.step(SCRIPTED_STEP_S, |_| {});
        let after = station.view.rig.eye_m.distance(station.view.rig.target_m);
        assert!(after < before, "wheel away zooms in: {before} → {after}");
        assert!(
            (station.view.rig.convergence_m / after - station.stereo.convergence_factor).abs() < 1e-5,
            "the zero-parallax plane follows the zoom"
        );
    }

    #[test]
    fn a_spacemouse_moves_the_desk_tool_and_its_button_sculpts() {
        use crate::input::reader::{DeviceId, DeviceInfo, ReaderEvent};
        use crate::input::spacemouse::{ButtonChange, RawAxes, SpaceMouseState};
        let scene = ball_scene();
        let mut station = small_station(&scene);
        let mailbox = Arc::new(Mailbox::new(16));
        station.attach_spacemice(mailbox.clone());
        let id = DeviceId(1);
        mailbox.push_event(ReaderEvent::Connected {
            id,
            info: DeviceInfo { path: "test".into(), name: "SpaceMouse".into() },
        });
        let start = station.controls.desk.poses.get(Target::Tool).position_m;
        // Half deflection to the right, button 1 (stroke) held.
        let state = SpaceMouseState { axes: RawAxes([175, 0, 0, 0, 0, 0]), buttons: 1, ..Default::default() };
        mailbox.push_event(ReaderEvent::Buttons {
            id,
            change: ButtonChange { pressed: 1, released: 0 },
            buttons: 1,
        });
        for _ in 0..30 {
            mailbox.publish_state(id, state);
            station.devices(SCRIPTED_STEP_S, &[], Vec::new());
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        let moved = station.controls.desk.poses.get(Target::Tool).position_m - start;
        assert!(moved.dot(station.view.rig.right()) > 0.01, "the tool went right: {moved}");
        assert_eq!(
            station.controls.mouse.tool_position_m,
            station.controls.desk.poses.get(Target::Tool).position_m
        );
        assert!(station.doc.playback.field().mass() > 0.0, "the stroke button sculpts");
        mailbox.push_event(ReaderEvent::Buttons {
            id,
            change: ButtonChange { pressed: 0, released: 1 },
            buttons: 0,
        });
        station.devices(SCRIPTED_STEP_S, &[], Vec::new());
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(
            station.stroke.is_none() && !station.doc.playback.field().in_stroke(),
            "release ends the stroke"
        );
    }

    #[test]
    fn the_display_mode_key_cycles_the_modes_the_surface_can_show_and_parity_follows_the_window() {
        let scene = Scene::default_scene();
        let mut station =
            Station::new(&scene, KeyBindings::shipped(), (200, 100), PathBuf::from("unused.argile"));
        let notice = station.set_surface(DisplayMode::QuadBuffer, "a flat display", 1).unwrap();
        assert!(notice.unwrap().contains("a flat display offers no stereo swapchain"));
        assert_eq!(station.display().0, DisplayMode::Anaglyph, "the scene's fallback");
        let mut seen = Vec::new();
        for _ in 0..DisplayMode::ALL.len() - 1 {
            station.key(KeyCode::KeyM, true);
            station.key(KeyCode::KeyM, false);
            seen.push(station.display().0);
        }
        assert!(!seen.contains(&DisplayMode::QuadBuffer), "quad-buffer is skipped here: {seen:?}");
        assert_eq!(seen.last(), Some(&DisplayMode::Anaglyph), "back to the start after every other mode");
        station.set_surface(DisplayMode::SideBySide, "a flat display", 1).unwrap();
        assert_eq!(
            (station.view.output.width_px, station.view.output.height_px),
            (100, 100),
            "each eye half the width"
        );
        station.set_surface(DisplayMode::RowInterlaced, "a flat display", 1).unwrap();
        let even = station.display().1;
        station.set_window_origin((0, 7));
        assert_eq!(station.display().1, even.flipped(), "a window on an odd row flips the rows' eyes");
        assert!(station.set_surface(DisplayMode::QuadBuffer, "a flat display", 2).unwrap().is_none());

        // A passive monitor's calibration names its mode and its polariser's parity.
        let passive = ScreenCalibration::parse(
            "[display]\nmode = \"row-interlaced\"\nparity = \"left-odd\"\n",
            "passive.toml",
        )
        .unwrap();
        let mut station =
            Station::new(&scene, KeyBindings::shipped(), (200, 100), PathBuf::from("unused.argile"));
        station.set_calibration(passive);
        assert_eq!(station.display(), (DisplayMode::RowInterlaced, Parity::LeftOdd));
        station.set_window_origin((0, 3));
        assert_eq!(station.display().1, Parity::LeftEven, "odd window row: flipped");
    }

    #[test]
    fn opentrack_datagrams_move_the_station_views_and_auto_convergence_follows_the_tool() {
        use crate::input::opentrack::encode_packet;
        let scene = Scene::default_scene();
        let mut station =
            Station::new(&scene, KeyBindings::shipped(), (160, 90), PathBuf::from("unused.argile"));
        let untracked = station.step(SCRIPTED_STEP_S, |_| {}).views;
        let mut calibration = station.screen_calibration();
        calibration.tracker.hold_s = 59.0; // no dropout between two steps on a slow machine
        calibration.tracker.ease_s = 0.0; // the tracked view at once (easing in is tested apart)
        station.set_calibration(calibration);
        let head = OpentrackHead::start(&calibration, Some("127.0.0.1:0".parse().unwrap())).unwrap();
        let to = head.receiver().local_addr();
        station.attach_head(head);
        let sender = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        // Nothing received yet: the default eye, seeing from the camera rig's centre (the eyes
        // the viewer's own distance apart, the calibration's IPD).
        let centred = station.step(SCRIPTED_STEP_S, |_| {}).views;
        let middle = |v: &crate::render::StereoViews| (v.eyes[0].position_m + v.eyes[1].position_m) * 0.5;
        assert!(
            (middle(&centred) - middle(&untracked)).length() < 1e-4,
            "{} vs {}",
            middle(&centred),
            middle(&untracked)
        );
        // The head 10 cm to the right: both eyes move right in the scene.
        let moved = loop {
            sender.send_to(&encode_packet([10.0, 0.0, 60.0], [0.0; 3]), to).unwrap();
            std::thread::sleep(std::time::Duration::from_millis(20));
            let views = station.step(SCRIPTED_STEP_S, |_| {}).views;
            if (views.eyes[0].position_m - centred.eyes[0].position_m).length() > 1e-3 {
                break views;
            }
        };
        let right = station.view.rig.right();
        for (m, c) in moved.eyes.iter().zip(&centred.eyes) {
            assert!((m.position_m - c.position_m).dot(right) > 0.01, "the eye went right");
        }
        assert!(station.hud_lines()[2].contains("head tracked"));

        // Auto-convergence: the tool 10 cm nearer than the target; the plane follows, smoothly.
        station.controls.mouse.tool_position_m = station.view.rig.target_m - station.view.rig.forward() * 0.1;
        station.key(KeyCode::KeyC, true);
        station.key(KeyCode::KeyC, false);
        let before = station.view.rig.convergence_m;
        station.step(SCRIPTED_STEP_S, |_| {});
        let first = station.view.rig.convergence_m;
        for _ in 0..120 {
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        let depth =
            (station.controls.mouse.tool_position_m - station.view.rig.eye_m).dot(station.view.rig.forward());
        assert!(first < before && first > depth, "one step moves part of the way: {before} → {first}");
        assert!((station.view.rig.convergence_m - depth).abs() < 1e-3, "two seconds later it is there");
    }

    #[test]
    fn the_default_scene_fits_the_parallax_budget() {
        // The first thing a user sees warns of nothing: neither the headless render (judged
        // on the mesh's bounds at the end of the timeline) nor the station (on the surface it
        // draws).
        let scene = Scene::default_scene();
        let mut playback = Playback::new(&scene);
        let end = scene.captures.last().map_or(0.0, |c| c.time_s);
        playback.advance_to(end, |_| {});
        let clay = crate::mesh::mesh_all(playback.field()).upserted_bounds();
        assert!(!clay.is_empty());
        use super::super::comfort::{judge_parallax_budget, scene_calibration, Seen};
        let seen = Seen::fitted(scene_calibration(&scene), (scene.output.width_px, scene.output.height_px));
        let verdict = judge_parallax_budget(&scene, &seen, clay);
        assert!(verdict.is_none(), "{:?}", verdict.map(|v| v.warning));
        let mut station =
            Station::new(&scene, KeyBindings::shipped(), (320, 240), PathBuf::from("unused.argile"));
        station.step(SCRIPTED_STEP_S, |_| {});
        // The station judges the surface it draws: the initial clay's, before the timeline.
        let drawn = crate::mesh::mesh_all(Playback::new(&scene).field()).upserted_bounds();
        assert_eq!(station.clay_bounds, drawn);
        assert!(!station.hud_lines().iter().any(|l| l.contains("over the parallax budget")));
        assert!(
            !station.messages.iter().any(|m| m.contains("beyond the comfortable")),
            "{:?}",
            station.messages
        );
    }

    #[test]
    fn tracking_eases_in_from_the_camera_view_and_says_why_the_view_changes() {
        // The scene's camera sees 50° where the shipped screen spans 28° from the default eye.
        let text = "[head]\n[camera]\nfov_y_deg = 50\n[[clay]]\nshape = \"sphere\"\nradius_m = 0.05\n";
        let scene = Scene::parse(text, "wide.toml", None).unwrap();
        let mut station = Station::new(&scene, KeyBindings::shipped(), (640, 360), PathBuf::from("u.argile"));
        let aspect = 640.0 / 360.0;
        let untracked = station.view.rig.views(aspect);
        let first = station.step(SCRIPTED_STEP_S, |_| {}).views;
        let said = station.messages.iter().find(|m| m.starts_with("head tracking:")).expect("said").clone();
        assert!(said.contains("the clay looks 1.87 times") && said.contains("easing in"), "{said}");
        let close = |a: &crate::render::StereoViews, b: &crate::render::StereoViews| {
            a.eyes.iter().zip(&b.eyes).all(|(x, y)| {
                x.projection.abs_diff_eq(y.projection, 1e-4) && x.view.abs_diff_eq(y.view, 1e-4)
            })
        };
        assert!(close(&first, &untracked), "the first frame is the camera's view");
        let frames = (station.stereo.calibration.tracker.ease_s / SCRIPTED_STEP_S).ceil() as usize + 1;
        let mut last = first;
        let mut steps = Vec::new();
        for _ in 0..frames {
            let v = station.step(SCRIPTED_STEP_S, |_| {}).views;
            steps.push((v.eyes[0].projection.x_axis.x - last.eyes[0].projection.x_axis.x).abs());
            last = v;
        }
        let head = scene.head.as_ref().unwrap().pose_at(station.doc.playback.time_s());
        let tracked = station.tracked_rig().unwrap().views(&head);
        assert!(close(&last, &tracked), "then the tracked view");
        let size = |v: &crate::render::StereoViews| {
            let m = v.eyes[0].projection * v.eyes[0].view;
            let ndc = |p: Vec3| {
                let c = m * p.extend(1.0);
                c.x / c.w
            };
            ndc(Vec3::new(0.05, 0.0, 0.0)) - ndc(Vec3::new(-0.05, 0.0, 0.0))
        };
        // As large as the notice says.
        assert!(
            (size(&tracked) / size(&untracked) - 1.87).abs() < 0.01,
            "{}",
            size(&tracked) / size(&untracked)
        );
        let total: f32 = steps.iter().sum();
        assert!(steps.iter().all(|s| *s < 0.1 * total), "no step is a jump: {steps:?}");
        assert_eq!(station.messages.iter().filter(|m| m.starts_with("head tracking:")).count(), 1);
    }

    #[test]
    fn head_tracked_views_take_the_interaxial_keys_and_the_budget_judges_them() {
        // A head-tracked scene with clay from 30 cm in front of the screen to 1 m behind it.
        let text = "[head]\n[stage]\nshow = false\n[[clay]]\nshape = \"box\"\nsize_m = [0.1, 0.1, 1.3]\nposition_m = [0, 0, -0.35]\n";
        let scene = Scene::parse(text, "deep.toml", None).unwrap();
        let mut station = Station::new(&scene, KeyBindings::shipped(), (640, 360), PathBuf::from("u.argile"));
        let apart = |v: &crate::render::StereoViews| (v.eyes[1].position_m - v.eyes[0].position_m).length();
        // Past the ease into the tracked views.
        for _ in 0..100 {
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        let first = station.step(SCRIPTED_STEP_S, |_| {}).views;
        let over =
            |s: &Station<'_>| s.hud_lines().into_iter().find(|l| l.contains("over the parallax budget"));
        let warned = over(&station).expect("the deep clay is over the budget");
        for _ in 0..3 {
            station.act(StationAction::InteraxialNarrower);
        }
        let narrowed = station.step(SCRIPTED_STEP_S, |_| {}).views;
        assert!(over(&station).is_some());
        let ratio = apart(&narrowed) / apart(&first);
        assert!((ratio - 1.1f32.powi(-3)).abs() < 1e-3, "the tracked eyes moved closer: {ratio}");
        assert!(station.hud_lines()[1].contains("eyes 47 mm"), "{:?}", station.hud_lines());
        // Still over the budget, with today's figures.
        let now = over(&station).expect("still over");
        assert_ne!(now, warned, "the figures follow the eyes");
        // Limit mode narrows the tracked eyes until it fits.
        let mut calibration = station.screen_calibration();
        calibration.budget.mode = BudgetMode::Limit;
        station.set_calibration(calibration);
        for _ in 0..3 {
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        assert!(over(&station).is_none(), "{:?}", station.hud_lines());
        assert!(station.stereo.tracked_interaxial_m < 0.063 * 0.7, "{}", station.stereo.tracked_interaxial_m);
    }

    #[test]
    fn the_hud_warns_while_the_clay_exceeds_the_parallax_budget() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/tests/station.toml");
        // Without its stage, whose back wall is over the budget on the shipped screen.
        let text = std::fs::read_to_string(&path).unwrap().replace("[stage]", "[stage]\nshow = false");
        let scene = Scene::parse(&text, "station.toml", None).unwrap();
        let mut station =
            Station::new(&scene, KeyBindings::shipped(), (320, 240), PathBuf::from("unused.argile"));
        // The first frame meshes the initial clay and judges it: within budget from afar.
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(!station.hud_lines().iter().any(|l| l.contains("over the parallax budget")));
        // Zoomed in, the slab's depth spans more than ±1° on the shipped display.
        station.script(&ScriptEvent::Wheel(7.0));
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(!station.clay_bounds.is_empty());
        assert!(
            station.hud_lines().iter().any(|l| l.contains("over the parallax budget")),
            "{:?}",
            station.hud_lines()
        );
        let said: Vec<&String> =
            station.messages.iter().filter(|m| m.contains("beyond the comfortable")).collect();
        assert_eq!(said.len(), 1, "said once: {:?}", station.messages);
        // Narrower eyes bring it within budget.
        for _ in 0..12 {
            station.key(KeyCode::Minus, true);
            station.key(KeyCode::Minus, false);
        }
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(
            !station.hud_lines().iter().any(|l| l.contains("over the parallax budget")),
            "{:?}",
            station.hud_lines()
        );
    }

    #[test]
    fn a_large_desk_tool_edits_the_level_its_size_chooses_unless_told_otherwise() {
        // A 40 mm ball, and the same ball that says which level it edits (8 voxels across), on
        // 1 mm voxels.
        let text = "[field]\nvoxel_size_m = 0.001\n[[tool]]\nname = \"large\"\nshape = \"sphere\"\nradius_m = 0.04\naction = \"add\"\n\
                    [[tool]]\nname = \"sized\"\nshape = \"sphere\"\nradius_m = 0.04\naction = \"add\"\n\
                    level_samples = 8\n";
        let scene = Scene::parse(text, "large tools", None).unwrap();
        // Strokes with the desk tool at `hand` and scene tool `tool`: the levels holding clay
        // after a short stroke, and what the display said of the tool before it.
        let stroke = |hand: Option<f32>, tool: usize| {
            let mut station = small_station(&scene);
            station.set_hand_samples(hand);
            for _ in 0..tool {
                station.key(KeyCode::KeyT, true);
                station.key(KeyCode::KeyT, false);
            }
            let shown = station.hud_lines()[0].clone();
            sculpt_for(&mut station, 3);
            let field = station.doc.playback.field();
            assert!(field.mass() > 0.0, "the stroke added clay");
            let levels: Vec<usize> =
                (0..crate::field::LEVELS).filter(|&l| field.level_brick_count(l) > 0).collect();
            (levels, shown)
        };
        // 40 voxels across: by default at most 32 across, level 1 (2 mm voxels).
        let (levels, shown) = stroke(Some(HAND_SIZE_SAMPLES), 0);
        assert_eq!(levels, [1], "{shown}");
        assert!(shown.contains("sphere 40 mm, add, 2 mm voxels"), "{shown}");
        // --edit-finest: the finest level.
        let (levels, shown) = stroke(None, 0);
        assert_eq!(levels, [0], "{shown}");
        assert!(shown.contains("1 mm voxels"), "{shown}");
        // A scene tool that says which level it edits keeps it either way (8 across: level 3).
        for hand in [Some(HAND_SIZE_SAMPLES), None] {
            let (levels, shown) = stroke(hand, 1);
            assert_eq!(levels, [3], "{shown}");
            assert!(shown.contains("8 mm voxels"), "{shown}");
        }
    }

    /// The ball scene with a ball of clay (5 cm radius) 12 cm right of the desk tool's start.
    fn clay_ball_scene() -> Scene {
        let text = "[[clay]]\nshape = \"sphere\"\nradius_m = 0.05\nposition_m = [0.12, 0, 0]\n\
                    [[tool]]\nname = \"ball\"\nshape = \"sphere\"\nradius_m = 0.02\naction = \"add\"\n";
        Scene::parse(text, "clay ball", None).unwrap()
    }

    fn gamepad_drives(station: &mut Station<'_>, target: Target) {
        let mut settings = InputSettings::shipped();
        settings.mapping.set(DeviceClass::Gamepad, target);
        station.set_input_settings(&settings);
    }

    /// A gamepad on the part target pushes the active part along X for ten frames; returns
    /// where the second part is then.
    fn carry_part_along_x(station: &mut Station<'_>) -> Vec3 {
        use crate::input::calibration::SixDof;
        gamepad_drives(station, Target::Part);
        let push = GamepadMotion {
            six: SixDof { translation: Vec3::X * 0.5, rotation: Vec3::ZERO },
            size_rate: 0.0,
        };
        for _ in 0..10 {
            station.devices(SCRIPTED_STEP_S, &[push], Vec::new());
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        station.doc.playback.assembly().parts()[1].placement.translation_m
    }

    /// The gamepad let go: a frame without motion.
    fn let_the_gamepad_go(station: &mut Station<'_>) {
        let still = GamepadMotion { six: crate::input::calibration::SixDof::default(), size_rate: 0.0 };
        station.devices(SCRIPTED_STEP_S, &[still], Vec::new());
        station.step(SCRIPTED_STEP_S, |_| {});
    }

    /// Two parts: a ball at rest and a ball of its own, 2 mm voxels, placed 8 cm along X at
    /// twice its size.
    fn two_part_scene() -> Scene {
        let text = "[[part]]\nname = \"left\"\n[[part]]\nname = \"right\"\nvoxel_size_m = 0.002\n\
                    position_m = [0.08, 0.0, 0.0]\nscale = 2.0\n\
                    [[clay]]\npart = \"left\"\nshape = \"sphere\"\nradius_m = 0.02\n\
                    [[clay]]\npart = \"right\"\nshape = \"sphere\"\nradius_m = 0.01\n\
                    [[tool]]\nname = \"ball\"\nshape = \"sphere\"\nradius_m = 0.01\naction = \"add\"\n";
        Scene::parse(text, "two parts", None).unwrap()
    }

    #[test]
    fn n_makes_the_next_part_active_the_desk_tool_acts_in_its_frame_and_a_device_moves_it() {
        let scene = two_part_scene();
        let mut station = small_station(&scene);
        let left = station.doc.playback.field().clone();
        let right = station.doc.playback.assembly().others()[0].clone();
        assert!(station.hud_lines().iter().any(|l| l == "part 1 of 2: left"));
        station.key(KeyCode::KeyN, true);
        station.key(KeyCode::KeyN, false);
        assert!(
            station.messages.last().unwrap().starts_with("active part 2 of 2: right"),
            "{:?}",
            station.messages
        );
        assert!(station.hud_lines().iter().any(|l| l == "part 2 of 2: right"));
        // Its box is drawn for a while, turned and scaled with it, then no more.
        let shown = station.step(SCRIPTED_STEP_S, |_| {});
        let part_box = |frame: &crate::render::Frame| {
            frame
                .tools
                .iter()
                .filter(|g| g.colour == super::super::frame::PART_COLOUR)
                .map(|g| g.model)
                .next()
        };
        let model = part_box(&shown).expect("the picked part's box is drawn");
        let centre = model.transform_point3(Vec3::ZERO);
        assert!((centre - Vec3::new(0.08, 0.0, 0.0)).length() < 0.01, "about the right ball: {centre}");
        assert!(model.transform_vector3(Vec3::X).x > 0.02, "as large as the ball scaled 2×");
        for _ in 0..(PART_SHOWN_S / SCRIPTED_STEP_S) as usize + 1 {
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        assert!(part_box(&station.step(SCRIPTED_STEP_S, |_| {})).is_none(), "gone after a while");
        // A stroke at the right ball's top (world): clay of the right part, in its frame.
        station.controls.mouse.tool_position_m = Vec3::new(0.08, 0.02, 0.0);
        sculpt_for(&mut station, 2);
        assert!(station.doc.playback.field().same_samples(&left), "the left part is untouched");
        let grown = &station.doc.playback.assembly().others()[0];
        assert!(grown.mass() > right.mass());
        let local = scene.parts[1].placement.local_point(Vec3::new(0.08, 0.026, 0.0));
        assert!(FieldReader::new(grown).density_at(grown.transform().world_to_index(local)) > 0.5);
        let surface = |station: &mut Station<'_>, p: Vec3| {
            let f = station.doc.playback.surface();
            FieldReader::new(f).density_world(p)
        };
        assert!(surface(&mut station, Vec3::new(0.08, 0.026, 0.0)) > 0.5, "drawn where it was laid");
        // A gamepad on the part target carries it along X.
        let moved = carry_part_along_x(&mut station);
        assert!(moved.x > 0.081 && moved.y.abs() < 1e-6, "the part moved along X: {moved}");
        assert!(station.doc.playback.field().same_samples(&left), "the left part stays");
        assert!(
            surface(&mut station, Vec3::new(0.08 - 0.0195, 0.0, 0.0)) < 0.5,
            "the right ball left its old place"
        );
        // The gamepad let go, the move is one undo step: undo puts the part back, redo carries it
        // again, and the next undo takes back the stroke on the right part.
        let_the_gamepad_go(&mut station);
        let carried = station.doc.playback.assembly().parts()[1].placement;
        station.act(StationAction::Undo);
        assert_eq!(station.doc.playback.assembly().parts()[1].placement, scene.parts[1].placement);
        station.step(SCRIPTED_STEP_S, |_| {});
        assert_eq!(
            station.doc.playback.assembly().parts()[1].placement,
            scene.parts[1].placement,
            "it stays back"
        );
        station.act(StationAction::Redo);
        assert_eq!(station.doc.playback.assembly().parts()[1].placement, carried);
        station.act(StationAction::Undo);
        station.act(StationAction::Undo);
        assert!(station.doc.playback.assembly().others()[0].same_samples(&right));
        // Back to the first part.
        station.key(KeyCode::KeyN, true);
        station.key(KeyCode::KeyN, false);
        assert_eq!(station.doc.playback.assembly().active(), 0);
    }

    #[test]
    fn a_gamepad_on_the_tool_feels_the_clay_a_tap_at_contact_then_the_density_while_stroking() {
        use crate::input::calibration::SixDof;
        let scene = clay_ball_scene();
        let mut station = small_station(&scene);
        gamepad_drives(&mut station, Target::Tool);
        let right = GamepadMotion {
            six: SixDof { translation: Vec3::X * 0.5, rotation: Vec3::ZERO },
            size_rate: 0.0,
        };
        let stroke = |pressed| {
            vec![ActionEvent { action: InputAction::Stroke, pressed, device: DeviceClass::Gamepad }]
        };
        // The injected sequence: push the stick right until the tool meets the ball, press
        // the stroke button for a quarter second while pushing on, release.
        let mut felt = Vec::new();
        let frame = |station: &mut Station<'_>, motion: &[GamepadMotion], actions, felt: &mut Vec<_>| {
            station.devices(SCRIPTED_STEP_S, motion, actions);
            station.step(SCRIPTED_STEP_S, |_| {});
            let (touching, density) = contact_under(
                station.field(),
                station.controls.desk.poses.get(Target::Tool),
                station.desk_tool.half_extents_m(),
            );
            felt.push((station.take_rumble(), touching, density));
        };
        let mut frames_to_contact = 0;
        while !felt.last().is_some_and(|f: &(Option<Rumble>, bool, f32)| f.1) {
            frame(&mut station, &[right], Vec::new(), &mut felt);
            frames_to_contact += 1;
            assert!(frames_to_contact < 120, "the tool reaches the ball");
        }
        assert!(felt[..felt.len() - 1].iter().all(|f| f.0.is_none()), "nothing in the air");
        assert_eq!(felt.last().unwrap().0, Some(ContactFeedback::TAP), "a tap at contact");
        frame(&mut station, &[right], stroke(true), &mut felt);
        for _ in 0..15 {
            frame(&mut station, &[right], Vec::new(), &mut felt);
        }
        let stroking = &felt[frames_to_contact..];
        let played: Vec<Rumble> = stroking.iter().filter_map(|f| f.0).collect();
        assert!(played.len() >= 3 && played.iter().all(|r| !r.is_stop()), "{played:?}");
        for (rumble, _, density) in stroking.iter().filter(|f| f.0.is_some()) {
            let expected = ContactFeedback::stroke_strength(*density);
            assert!((rumble.unwrap().strong - expected).abs() < 1e-5, "strength follows the density");
        }
        let densities: Vec<f32> = stroking.iter().map(|f| f.2).collect();
        assert!(densities.last() > densities.first(), "deeper into the clay: {densities:?}");
        frame(&mut station, &[], stroke(false), &mut felt);
        assert_eq!(felt.last().unwrap().0, Some(Rumble::STOP), "the stroke ends: the rumble stops");

        // A gamepad that turns the scene feels nothing, whatever the desk tool touches.
        let mut station = small_station(&scene);
        gamepad_drives(&mut station, Target::Scene);
        station.controls.desk.poses.get_mut(Target::Tool).position_m = Vec3::new(0.12, 0.0, 0.0);
        station.controls.mouse.tool_position_m = Vec3::new(0.12, 0.0, 0.0);
        station.devices(SCRIPTED_STEP_S, &[], stroke(true));
        station.step(SCRIPTED_STEP_S, |_| {});
        assert_eq!(station.take_rumble(), None);

        // A tool that starts in the clay does not tap at the first frame; it taps when it
        // comes back after leaving.
        let mut station = small_station(&scene);
        gamepad_drives(&mut station, Target::Tool);
        station.controls.desk.poses.get_mut(Target::Tool).position_m = Vec3::new(0.12, 0.0, 0.0);
        station.controls.mouse.tool_position_m = Vec3::new(0.12, 0.0, 0.0);
        station.step(SCRIPTED_STEP_S, |_| {});
        assert_eq!(station.take_rumble(), None, "no tap at start");
        station.controls.mouse.tool_position_m = Vec3::ZERO;
        station.step(SCRIPTED_STEP_S, |_| {});
        station.controls.mouse.tool_position_m = Vec3::new(0.12, 0.0, 0.0);
        station.step(SCRIPTED_STEP_S, |_| {});
        assert_eq!(station.take_rumble(), Some(ContactFeedback::TAP));
    }

    #[test]
    fn devices_drive_the_light_and_the_second_tool_and_a_mouse_can_turn_the_light() {
        use crate::input::calibration::SixDof;
        let scene = Scene::default_scene();
        let mut station = small_station(&scene);
        let before = station.step(SCRIPTED_STEP_S, |_| {});
        let glyphs = before.tools.len();
        gamepad_drives(&mut station, Target::Light);
        let twist = GamepadMotion {
            six: SixDof { translation: Vec3::ZERO, rotation: Vec3::Y * 0.5 },
            size_rate: 0.0,
        };
        for _ in 0..20 {
            station.devices(SCRIPTED_STEP_S, &[twist], Vec::new());
        }
        let lit = station.step(SCRIPTED_STEP_S, |_| {});
        assert_ne!(lit.lights[0], before.lights[0], "the key light turned");
        assert_eq!(lit.lights[1..], before.lights[1..], "the others stay");
        assert_eq!(lit.tools.len(), glyphs, "the second tool is not drawn until it moves");

        gamepad_drives(&mut station, Target::SecondTool);
        let push = GamepadMotion {
            six: SixDof { translation: Vec3::Y * 0.5, rotation: Vec3::ZERO },
            size_rate: 0.0,
        };
        for _ in 0..10 {
            station.devices(SCRIPTED_STEP_S, &[push], Vec::new());
        }
        let two = station.step(SCRIPTED_STEP_S, |_| {});
        assert_eq!(two.tools.len(), glyphs + 1, "the second tool is drawn once moved");
        let second = two.tools[glyphs].model.w_axis;
        assert!(second.y > 0.01, "it went up: {second:?}");

        // A mouse set to drive the light turns it with the trackball, not the scene.
        let mut station = small_station(&scene);
        let mut settings = InputSettings::shipped();
        settings.mapping.set(DeviceClass::Mouse, Target::Light);
        station.set_input_settings(&settings);
        let eye = station.view.rig.eye_m;
        station.script(&ScriptEvent::Drag {
            button: MouseButton::Left,
            from_px: Vec2::new(32.0, 32.0),
            to_px: Vec2::new(48.0, 32.0),
            steps: 4,
        });
        station.devices(SCRIPTED_STEP_S, &[], Vec::new());
        let turned = station.step(SCRIPTED_STEP_S, |_| {});
        assert!((station.view.rig.eye_m - eye).length() < 1e-6, "the view did not turn");
        assert_ne!(turned.lights[0], before.lights[0], "the light did");
        // Reset puts the light back.
        station.key(KeyCode::Home, true);
        assert_eq!(station.step(SCRIPTED_STEP_S, |_| {}).lights[0], before.lights[0]);

        // A mouse set to drive the tool starts as its 3D cursor.
        let mut station = small_station(&scene);
        assert_eq!(station.controls.mouse.mode, MouseMode::Scene);
        settings.mapping.set(DeviceClass::Mouse, Target::Tool);
        station.set_input_settings(&settings);
        assert_eq!(station.controls.mouse.mode, MouseMode::Cursor);
    }

    #[test]
    fn unplugging_the_spacemouse_mid_stroke_ends_the_stroke_and_a_replug_drives_again() {
        use crate::input::reader::{DeviceId, DeviceInfo, ReaderEvent};
        use crate::input::spacemouse::{ButtonChange, RawAxes, SpaceMouseState};
        let scene = ball_scene();
        let mut station = small_station(&scene);
        let mailbox = Arc::new(Mailbox::new(16));
        station.attach_spacemice(mailbox.clone());
        let info = DeviceInfo { path: "hid-a".into(), name: "SpaceMouse".into() };
        mailbox.push_event(ReaderEvent::Connected { id: DeviceId(1), info: info.clone() });
        mailbox.push_event(ReaderEvent::Buttons {
            id: DeviceId(1),
            change: ButtonChange { pressed: 1, released: 0 },
            buttons: 1,
        });
        let push = SpaceMouseState { axes: RawAxes([175, 0, 0, 0, 0, 0]), buttons: 1, ..Default::default() };
        for _ in 0..10 {
            mailbox.publish_state(DeviceId(1), push);
            station.devices(SCRIPTED_STEP_S, &[], Vec::new());
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        assert!(station.stroke.is_some() && station.doc.playback.field().in_stroke());
        let mass = station.doc.playback.field().mass();
        // Unplugged with the button held: the reader reports the loss, releasing it.
        mailbox.push_event(ReaderEvent::Lost { id: DeviceId(1), released: 1, reason: "unplugged".into() });
        station.devices(SCRIPTED_STEP_S, &[], Vec::new());
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(station.stroke.is_none() && !station.doc.playback.field().in_stroke(), "the stroke ended");
        let at = station.controls.desk.poses.get(Target::Tool).position_m;
        for _ in 0..5 {
            station.devices(SCRIPTED_STEP_S, &[], Vec::new());
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        assert_eq!(
            station.controls.desk.poses.get(Target::Tool).position_m,
            at,
            "a lost device moves nothing"
        );
        assert_eq!(station.doc.playback.field().mass(), mass, "nor sculpts");
        // Plugged back (a new id): it drives the tool again.
        mailbox.push_event(ReaderEvent::Connected { id: DeviceId(2), info });
        for _ in 0..10 {
            mailbox.publish_state(DeviceId(2), SpaceMouseState { buttons: 0, ..push });
            station.devices(SCRIPTED_STEP_S, &[], Vec::new());
            station.step(SCRIPTED_STEP_S, |_| {});
        }
        assert!((station.controls.desk.poses.get(Target::Tool).position_m - at).length() > 0.005);
        assert!(station.stroke.is_none());
    }

    #[test]
    fn the_panel_lists_the_devices_by_name_and_changes_what_each_family_drives() {
        use crate::input::reader::{DeviceId, DeviceInfo, ReaderEvent};
        let scene = ball_scene();
        let mut station = small_station(&scene);
        let mailbox = Arc::new(Mailbox::new(16));
        station.attach_spacemice(mailbox.clone());
        let info = DeviceInfo { path: "hid-a".into(), name: "SpaceMouse Compact".into() };
        mailbox.push_event(ReaderEvent::Connected { id: DeviceId(1), info });
        station.set_gamepad_names(vec!["Xbox Wireless Controller".into()]);
        station.devices(SCRIPTED_STEP_S, &[], Vec::new());
        let view = station.panel_view();
        let rows: Vec<(&str, &str, Vec<String>)> =
            view.devices.iter().map(|d| (d.family, view.targets[d.target], d.connected.clone())).collect();
        assert_eq!(rows[0], ("spacemouse", "tool", vec!["SpaceMouse Compact".to_owned()]));
        assert_eq!(rows[1], ("gamepad", "second_tool", vec!["Xbox Wireless Controller".to_owned()]));
        assert_eq!((rows[2].0, rows[2].1), ("mouse", "scene"));
        assert!(view.head_tracker.is_none());
        // The mouse set to the tool becomes its 3D cursor, and back to the scene turns it.
        let (mouse, tool, scene_target) = (2, Target::Tool.index(), Target::Scene.index());
        station.panel_command(PanelCommand::DeviceTarget(mouse, tool));
        assert_eq!(station.controls.desk.mapping.target(DeviceClass::Mouse), Target::Tool);
        assert_eq!(station.controls.mouse.mode, MouseMode::Cursor);
        assert_eq!(station.messages.last().unwrap(), "the mouse drives the tool now");
        station.panel_command(PanelCommand::DeviceTarget(mouse, scene_target));
        assert_eq!(station.controls.mouse.mode, MouseMode::Scene);
        // The SpaceMouse set to the light moves the light, not the tool.
        station.panel_command(PanelCommand::DeviceTarget(0, Target::Light.index()));
        assert_eq!(station.controls.desk.mapping.target(DeviceClass::SpaceMouse), Target::Light);
        assert_eq!(station.panel_view().devices[0].target, Target::Light.index());
        // Unplugged, it is listed no more.
        mailbox.push_event(ReaderEvent::Lost { id: DeviceId(1), released: 0, reason: "unplugged".into() });
        station.devices(SCRIPTED_STEP_S, &[], Vec::new());
        assert!(station.panel_view().devices[0].connected.is_empty());
        // Out of range indices change nothing.
        station.panel_command(PanelCommand::DeviceTarget(7, 0));
        station.panel_command(PanelCommand::DeviceTarget(0, 99));
        assert_eq!(station.controls.desk.mapping.target(DeviceClass::SpaceMouse), Target::Light);
    }

    #[test]
    fn saving_stores_the_scene_its_freeform_tools_and_the_view_and_opening_in_that_scene_brings_them_back() {
        let dir = std::env::temp_dir().join(format!("argile-station-tools-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let text = concat!(
            "[[clay]]\nshape = \"sphere\"\nradius_m = 0.02\n",
            "[[tool]]\nname = \"copy\"\nshape = \"freeform\"\n",
            "region_min_m = [-0.03, -0.03, -0.03]\nregion_max_m = [0.03, 0.0, 0.03]\naction = \"add\"\n",
        );
        let scene = Scene::parse(text, "copy", None).unwrap();
        let path = dir.join("copy.argile");
        let mut maker = Station::new(&scene, KeyBindings::shipped(), (64, 64), path.clone());
        maker.set_scene_toml(Some(text.to_owned()));
        let made = maker.desk_tool.shape.clone();
        // The view changed: turned, stereo keys, lights, the next display mode.
        maker.controls.mouse.scene_rotation = Quat::from_rotation_y(0.7) * Quat::from_rotation_x(-0.2);
        for action in [
            StationAction::InteraxialWider,
            StationAction::ConvergenceNearer,
            StationAction::ToggleLights,
            StationAction::NextDisplayMode,
            StationAction::ToggleAutoConvergence,
        ] {
            maker.act(action);
        }
        let view = maker.stored_view();
        let fresh =
            Station::new(&scene, KeyBindings::shipped(), (64, 64), dir.join("y.argile")).stored_view();
        assert_ne!(view, fresh);
        assert!(matches!(&made, ToolShape::Freeform(f) if f.mass() > 0.0));
        maker.save().unwrap();
        let saved = crate::io::read_file(&path, &mut |_| {}).unwrap();
        assert_eq!(saved.scene_toml.as_deref(), Some(text), "the scene is stored");
        assert_eq!(saved.tools.len(), 1);
        assert_eq!(saved.view.as_ref(), Some(&view), "the view is stored");

        // The scene as `open_sculpt` shows a sculpt: without its initial clay, so its freeform
        // tool, copied from no clay, is empty until the sculpt brings back the one it stores.
        let mut bare = scene.clone();
        bare.clay.clear();
        for (scene_text, restored) in [(Some(text), true), (Some("# another scene\n"), false), (None, false)]
        {
            let mut station = Station::new(&bare, KeyBindings::shipped(), (64, 64), dir.join("x.argile"));
            station.set_scene_toml(scene_text.map(str::to_owned));
            assert!(matches!(&station.desk_tool.shape, ToolShape::Freeform(f) if f.mass() == 0.0));
            station.open(&path).unwrap();
            let tools_made = station.doc.playback.tools()[0].shape == made && station.desk_tool.shape == made;
            assert_eq!(tools_made, restored, "in {scene_text:?}");
            assert_eq!(station.stored_view() == view, restored, "the view too, in {scene_text:?}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_sculpt_opens_with_the_symmetry_it_was_saved_with_and_an_older_file_keeps_the_one_in_force() {
        let dir = std::env::temp_dir().join(format!("argile-station-symmetry-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scene = ball_scene();
        let path = dir.join("mirrored.argile");
        let mut maker = Station::new(&scene, KeyBindings::shipped(), (64, 64), path.clone());
        // Y switches the mirror on, Shift+Y steps on to the next choice.
        maker.act(StationAction::ToggleSymmetry);
        maker.act(StationAction::NextSymmetry);
        let chosen = *maker.doc.playback.symmetry();
        assert!(!chosen.is_none());
        maker.save().unwrap();
        let saved = crate::io::read_file(&path, &mut |_| {}).unwrap();
        assert_eq!(saved.symmetry, Some(chosen), "the file stores it");
        let text = crate::app::describe_sculpt(&path).unwrap();
        assert!(text.contains(&format!("symmetry {}", chosen.describe())), "{text}");
        // Opened at another desk, the strokes act through it, and the keys go on from it.
        let mut desk = Station::new(&scene, KeyBindings::shipped(), (64, 64), dir.join("x.argile"));
        assert!(desk.doc.playback.symmetry().is_none());
        desk.open(&path).unwrap();
        assert_eq!(*desk.doc.playback.symmetry(), chosen);
        desk.act(StationAction::ToggleSymmetry);
        assert!(desk.doc.playback.symmetry().is_none(), "Y switches it off");
        desk.act(StationAction::ToggleSymmetry);
        assert_eq!(*desk.doc.playback.symmetry(), chosen, "and on again");
        // Saved with it off, it opens off.
        desk.act(StationAction::ToggleSymmetry);
        desk.save().unwrap();
        let mut other = Station::new(&scene, KeyBindings::shipped(), (64, 64), dir.join("y.argile"));
        other.act(StationAction::ToggleSymmetry);
        other.open(&path).unwrap();
        assert!(other.doc.playback.symmetry().is_none());
        // A version 6 file stores none: the desk keeps the symmetry in force.
        let older = dir.join("older.argile");
        let scene_parts = crate::io::SceneParts { symmetry: Some(&chosen), ..Default::default() };
        let options = crate::io::EncodeOptions { version: 6, history: true };
        let bytes = crate::io::encode_sculpt(&saved.field, scene_parts, options, &mut |_| {});
        std::fs::write(&older, bytes).unwrap();
        assert_eq!(crate::io::read_file(&older, &mut |_| {}).unwrap().symmetry, None);
        other.act(StationAction::ToggleSymmetry);
        let in_force = *other.doc.playback.symmetry();
        assert!(!in_force.is_none());
        other.open(&older).unwrap();
        assert_eq!(*other.doc.playback.symmetry(), in_force);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_save_that_cannot_write_its_file_saves_to_the_fallback_folder_or_keeps_the_sculpt() {
        let dir = std::env::temp_dir().join(format!("argile-station-fallback-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // A file where the save folder should be: no write there succeeds, even as root.
        std::fs::write(dir.join("not-a-folder"), "x").unwrap();
        let scene = ball_scene();
        let blocked = dir.join("not-a-folder").join("ball.argile");
        let mut station = Station::new(&scene, KeyBindings::shipped(), (64, 64), blocked.clone());
        sculpt_for(&mut station, 3);
        let mass = station.field().mass();
        assert!(mass > 0.0);

        let e = format!("{:#}", station.save().unwrap_err());
        assert!(e.contains("stays in memory") && e.contains("not-a-folder"), "{e}");
        assert_eq!(station.field().mass(), mass, "nothing lost");

        station.set_fallback_dir(Some(dir.join("saved")));
        let path = station.save().unwrap();
        assert!(path.starts_with(dir.join("saved")) && path.extension().unwrap() == "argile", "{path:?}");
        let said = station.messages.pop().unwrap();
        assert!(said.contains("cannot save to") && said.contains(&path.display().to_string()), "{said}");
        let saved = crate::io::read_file(&path, &mut |_| {}).unwrap();
        assert_eq!(saved.field.mass(), mass);
        assert_eq!(station.save().unwrap(), path, "the save key writes there from now on");
        assert!(std::fs::read_to_string(dir.join("not-a-folder")).unwrap() == "x", "nothing damaged");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_panel_saves_as_opens_and_exports_and_remembers_the_recent_sculpts() {
        let dir = std::env::temp_dir().join(format!("argile-station-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scene = ball_scene();
        let mut station = Station::new(&scene, KeyBindings::shipped(), (64, 64), dir.join("a.argile"));
        station.set_recent(RecentSculpts::load(dir.join("recent")));
        sculpt_for(&mut station, 3);
        let mass = station.field().mass();
        let b = dir.join("b.argile");
        station.panel_command(PanelCommand::SaveAs(b.clone()));
        assert_eq!(station.doc.save_to(), b, "saving writes there from now on");
        assert_eq!(station.unsaved_work(), 0);
        assert_eq!(crate::io::read_file(&b, &mut |_| {}).unwrap().field.mass(), mass);
        assert_eq!(station.panel_view().recent, [b.canonicalize().unwrap()]);
        // A folder that is a file: nothing changes, and the message says where saving writes.
        std::fs::write(dir.join("file"), "x").unwrap();
        station.panel_command(PanelCommand::SaveAs(dir.join("file/c.argile")));
        let said = station.messages.last().unwrap().clone();
        assert!(said.contains("file/c.argile") && said.contains("saving still writes to"), "{said}");
        assert_eq!(station.doc.save_to(), b);
        // Export: the surface as it stands, in the format of the extension, written away from
        // the frames, which say when it is done.
        station.panel_command(PanelCommand::Export(dir.join("b.obj")));
        assert!(station.messages.last().unwrap().starts_with("exporting"), "{:?}", station.messages);
        for _ in 0..2000 {
            if station.messages.last().unwrap().starts_with("exported") {
                break;
            }
            station.step(1.0 / 60.0, |_| {});
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        assert!(station.messages.last().unwrap().starts_with("exported"), "{:?}", station.messages);
        let obj = std::fs::read_to_string(dir.join("b.obj")).unwrap();
        assert!(obj.lines().filter(|l| l.starts_with("f ")).count() > 100);
        station.panel_command(PanelCommand::Export(dir.join("b.xyz")));
        assert!(station.messages.last().unwrap().contains("not an extension"));
        assert!(!dir.join("b.xyz").exists());
        // More clay, then open the saved sculpt: the panel said what becomes of the stroke.
        station.controls.mouse.tool_position_m += Vec3::new(0.05, 0.0, 0.0);
        sculpt_for(&mut station, 3);
        assert!(station.field().mass() > mass);
        station.set_recovered(vec![(b.clone(), "3 stroke(s) of ball".into())]);
        assert_eq!(station.panel_view().recovered.len(), 1);
        station.panel_command(PanelCommand::Open(b.clone()));
        let said = station.messages.last().unwrap();
        assert!(said.starts_with("opened") && said.contains("1 unsaved change(s) left behind"), "{said}");
        assert_eq!(station.field().mass(), mass);
        assert!(station.panel_view().recovered.is_empty(), "a recovered sculpt opened is no more offered");
        station.set_recovered(vec![(dir.join("gone.argile"), "1 stroke(s) of ball".into())]);
        station.panel_command(PanelCommand::DismissRecovered);
        assert!(station.panel_view().recovered.is_empty());
        // The list is kept in its file.
        assert_eq!(RecentSculpts::load(dir.join("recent")).list(), [b.canonicalize().unwrap()]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn while_the_panels_name_field_has_the_keyboard_keys_type_and_are_no_bindings() {
        let dir = std::env::temp_dir().join(format!("argile-station-typing-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scene = ball_scene();
        let save_to = dir.join("a.argile");
        let fresh = || {
            let mut station = Station::new(&scene, KeyBindings::shipped(), (960, 1200), save_to.clone());
            station.set_panel_shown(true);
            station
        };
        // "Save as…", found down the panel's band.
        let save_as = (6..1200)
            .step_by(6)
            .flat_map(|y| (10..250).step_by(20).map(move |x| Vec2::new(x as f32, y as f32)))
            .find(|&at| {
                let mut station = fresh();
                station.step(SCRIPTED_STEP_S, |_| {});
                station.script(&ScriptEvent::Click(at));
                station.step(SCRIPTED_STEP_S, |_| {});
                station.step(SCRIPTED_STEP_S, |_| {});
                station.panel.file_task() == Some(crate::ui::FileTask::SaveAs)
            })
            .expect("the save as button");
        let mut station = fresh();
        station.step(SCRIPTED_STEP_S, |_| {});
        station.script(&ScriptEvent::Click(save_as));
        station.step(SCRIPTED_STEP_S, |_| {});
        station.step(SCRIPTED_STEP_S, |_| {});
        assert!(station.panel.wants_keyboard());
        // Space sculpts no clay while typing, and Backspace deletes a character, not the lattice.
        station.script(&ScriptEvent::Hold(KeyCode::Space));
        station.step(SCRIPTED_STEP_S, |_| {});
        station.script(&ScriptEvent::Release(KeyCode::Space));
        assert_eq!(station.field().mass(), 0.0, "no stroke");
        for _ in 0.."a.argile".len() {
            station.script(&ScriptEvent::Press(Chord::parse("Backspace").unwrap()));
        }
        station.script(&ScriptEvent::Text("figure".into()));
        station.step(SCRIPTED_STEP_S, |_| {});
        station.script(&ScriptEvent::Press(Chord::parse("Enter").unwrap()));
        station.step(SCRIPTED_STEP_S, |_| {});
        let figure = dir.canonicalize().unwrap().join("figure.argile");
        assert!(figure.is_file(), "saved through the browser: {:?}", station.messages);
        assert_eq!(station.doc.save_to(), figure);
        assert!(!station.panel.wants_keyboard(), "the browser closed");
        // The keys are bindings again.
        sculpt_for(&mut station, 2);
        assert!(station.field().mass() > 0.0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_open_key_opens_the_newest_sculpt_then_older_ones_and_warns_of_unsaved_strokes() {
        use std::time::{Duration, SystemTime};
        let dir = std::env::temp_dir().join(format!("argile-station-open-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scene = ball_scene();
        // Two sculpts: one stroke in `older`, two in `newer`.
        let mut maker = Station::new(&scene, KeyBindings::shipped(), (64, 64), dir.join("older.argile"));
        let sculpt = |station: &mut Station<'_>| {
            station.key(KeyCode::Space, true);
            station.key(KeyCode::ArrowRight, true);
            for _ in 0..5 {
                station.step(SCRIPTED_STEP_S, |_| {});
            }
            station.key(KeyCode::Space, false);
            station.key(KeyCode::ArrowRight, false);
            station.step(SCRIPTED_STEP_S, |_| {});
        };
        sculpt(&mut maker);
        maker.save().unwrap();
        let older_mass = maker.field().mass();
        sculpt(&mut maker);
        maker.doc = Document::new(maker.doc.playback, dir.join("newer.argile"));
        maker.save().unwrap();
        let newer_mass = maker.field().mass();
        assert!(newer_mass > older_mass && older_mass > 0.0);
        let age = |name: &str, s: u64| {
            let f = std::fs::File::options().write(true).open(dir.join(name)).unwrap();
            f.set_modified(SystemTime::now() - Duration::from_secs(s)).unwrap();
        };
        age("older.argile", 100);
        age("newer.argile", 10);
        std::fs::write(dir.join("notes.txt"), "not a sculpt").unwrap();

        let mut station = Station::new(&scene, KeyBindings::shipped(), (64, 64), dir.join("fresh.argile"));
        let ctrl = Modifiers { ctrl: true, ..Default::default() };
        let open = |station: &mut Station<'_>| {
            station.set_modifiers(ctrl);
            station.key(KeyCode::KeyO, true);
            station.key(KeyCode::KeyO, false);
            station.set_modifiers(Modifiers::default());
            let diff = remesh_dirty(station.doc.playback.field_mut());
            // What the open key said (not the parallax budget's word on the clay).
            let said: Vec<String> =
                station.messages.drain(..).filter(|m| !m.contains("stereo disparity")).collect();
            (station.field().mass(), diff, said)
        };
        let (mass, diff, said) = open(&mut station);
        assert_eq!(mass, newer_mass, "the newest first: {said:?}");
        assert!(!diff.upserted.is_empty(), "its clay is meshed");
        assert!(said[0].starts_with("opened ") && said[0].contains("newer.argile"), "{said:?}");
        let (mass, _, _) = open(&mut station);
        assert_eq!(mass, older_mass, "then the next older");
        // The opened sculpt is where the save key writes.
        station.set_modifiers(ctrl);
        station.key(KeyCode::KeyS, true);
        station.key(KeyCode::KeyS, false);
        station.set_modifiers(Modifiers::default());
        assert!(station.messages.pop().unwrap().contains("older.argile"));

        // Unsaved strokes: the first press warns and opens nothing; the second opens.
        sculpt(&mut station);
        let sculpted = station.field().mass();
        let (mass, _, said) = open(&mut station);
        assert_eq!(mass, sculpted, "nothing opened yet");
        assert!(said[0].contains("1 unsaved stroke") && said[0].contains("newer.argile"), "{said:?}");
        let (mass, diff, _) = open(&mut station);
        assert_eq!(mass, newer_mass);
        assert!(!diff.removed.is_empty() || !diff.upserted.is_empty(), "the old clay's chunks are redrawn");

        // A damaged sculpt changes nothing and is named; the next press skips it.
        std::fs::write(dir.join("broken.argile"), b"ARGL but not really").unwrap();
        let (mass, _, said) = open(&mut station);
        assert_eq!(mass, newer_mass);
        assert!(said[0].contains("broken.argile"), "{said:?}");
        let (mass, _, said) = open(&mut station);
        // Saved a moment ago, `older` is now the newest after the damaged file.
        assert!(said[0].starts_with("opened ") && said[0].contains("older.argile"), "{said:?}");
        assert_eq!(mass, older_mass);

        // An empty folder says what to do.
        let empty = dir.join("empty");
        std::fs::create_dir_all(&empty).unwrap();
        station.set_open_dir(empty);
        let (_, _, said) = open(&mut station);
        assert!(said[0].starts_with("no sculpt (.argile) in") && said[0].contains("--open-dir"), "{said:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_clutch_holds_the_cursor_tool_then_it_follows_the_pointer_scaled_by_the_gain() {
        let scene = Scene::default_scene();
        let drag = |station: &mut Station<'_>, from: f32, to: f32| {
            station.script(&ScriptEvent::Drag {
                button: MouseButton::Left,
                from_px: Vec2::new(from, 32.0),
                to_px: Vec2::new(to, 32.0),
                steps: 4,
            });
            station.controls.mouse.tool_position_m
        };
        let cursor = |station: &mut Station<'_>| {
            station.key(KeyCode::Tab, true);
            station.key(KeyCode::Tab, false);
        };
        // Plain cursor: the tool lands under the pointer.
        let mut plain = small_station(&scene);
        cursor(&mut plain);
        let a = drag(&mut plain, 32.0, 32.0);
        let b = drag(&mut plain, 32.0, 48.0);
        let reach = b - a;
        assert!(reach.length() > 1e-3);

        let mut settings = InputSettings::shipped();
        settings.mouse.0.clutch_gain = 0.25;
        let mut station = small_station(&scene);
        station.set_input_settings(&settings);
        cursor(&mut station);
        let start = drag(&mut station, 32.0, 32.0);
        assert!((start - a).length() < 1e-6, "not clutched yet: under the pointer");
        // Clutch held: the pointer goes right, the tool stays.
        station.key(KeyCode::KeyX, true);
        let held = drag(&mut station, 32.0, 48.0);
        assert!((held - start).length() < 1e-6, "held: {held} vs {start}");
        station.key(KeyCode::KeyX, false);
        // Released: the same drag again moves the tool a quarter as far, from where it was.
        let after = drag(&mut station, 32.0, 48.0);
        assert!(((after - start) - reach * 0.25).length() < 1e-4, "{} vs {}", after - start, reach * 0.25);
        // A gamepad's clutch button lifts it too.
        let clutch = |pressed| {
            vec![ActionEvent { action: InputAction::Clutch, pressed, device: DeviceClass::Gamepad }]
        };
        station.devices(SCRIPTED_STEP_S, &[], clutch(true));
        assert!((drag(&mut station, 48.0, 16.0) - after).length() < 1e-6);
        station.devices(SCRIPTED_STEP_S, &[], clutch(false));
        // Tab twice: back to the plain cursor.
        cursor(&mut station);
        cursor(&mut station);
        assert!((drag(&mut station, 32.0, 48.0) - b).length() < 1e-3, "under the pointer again");
    }
}
