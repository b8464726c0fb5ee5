//! The station in a headset: the scene's clay floats in the room, the dominant hand's
//! controller holds the tool, the other hand grabs the sculpture; both grips turn, move and
//! scale it about the hands' midpoint.
//!
//! Each frame the headset session ([`XrStation::turn`]) hands over the hands, and
//! [`XrSculptor::step`] runs the stages of the data flow: controls (buttons, thumbstick,
//! grips) → tools (the scene's scripted hands, the dominant hand's stroke) → field →
//! incremental mesh → the frame to draw, with haptic pulses where the tool meets the clay.
//! The frame shows the dominant hand's tool (its own shape and size, in its action's colour),
//! the support where the other hand holds or put it, each tracked controller, and the palette
//! of the current shape, action and size in front of the other controller (see
//! `super::glyphs`); a hand that is not tracked shows nothing.
//!
//! Controls (right-handed; mirrored in left-handed mode):
//! - right trigger: apply the tool (its pressure sets the rate of soft actions);
//! - right thumbstick up/down: tool size; left/right flick: next shape; click: next action;
//! - A / B (X / Y on the left hand): undo / redo;
//! - left squeeze: grab the sculpture; both squeezes: turn, move and scale it;
//! - left menu: recentre the sculpture in front of the head;
//! - left thumbstick click: symmetry on or off; X: the next symmetry (mirror X, mirror X and
//!   Z, radial 6, a kaleidoscope); every stroke and push then acts at its images too;
//! - the palette's buttons (symmetry, undo, redo, recentre, save, quit, lattice, panel,
//!   region), in front of the left controller: touch one with the right controller and pull
//!   the trigger. Every profile has a trigger, so each of these is reachable on every
//!   controller.
//! - the palette's region button steps the right hand's region tool: move, copy, bend,
//!   inflate, deflate, copy to part, select box, then sculpting again. The tool is then drawn
//!   yellow and its shape is the region: the trigger takes the active part's clay within it and carries it (move: leaving
//!   empty space; copy: a copy), or bends the clay after the hand, one undo step when the
//!   trigger comes up; each pull of inflate or deflate moves the surface within it by 1 mm.
//!   Copy to part: each pull copies the clay within it into a new part, the active one.
//!   Select box: hold the trigger and drag out a box; the others act on it instead of the
//!   tool's shape (a move or a copy carries it along) until a pull without a drag clears it.
//! - the palette's panel button shows the panel (the desk's, less its view and devices
//!   sections, with a first row that saves, recentres and quits) on a board standing on the
//!   palette; a ray from the right controller's aim points at it (a dot where it meets it), the
//!   trigger clicks and drags there, and the right thumbstick scrolls it. Every tool setting,
//!   the parts, the history, the files (save, save as, open, export) and the lattice's form
//!   are reached from it. While the ray is on the panel the hand does not sculpt.
//! - with a lattice open (the palette's lattice button; pressed again it applies the lattice,
//!   one undo step, and A puts the clay back): the control nearest the right controller is
//!   picked and ringed, the right trigger pulled off the palette drags it with the hand, and
//!   the right thumbstick up/down raises or lowers its value (the clay near it swells or
//!   shrinks) instead of sizing the tool.

use std::path::PathBuf;

use anyhow::Result;

use super::document::Document;
use super::frame::build_frame;
use super::glyphs::{
    action_colour, buttons, controller_glyph, palette, panel_placement, ray_glyphs, ray_on_panel, tool_glyph,
    Button, REGION_RGB,
};
use super::held_region::{selection_said, RegionTool, SWELL_STEP_M};
use super::panel_rows::{self, action_cycle, shape_cycle, shape_name, LatticeStep};
use super::playback::Playback;
use crate::field::{Field, FieldReader};
use crate::io::autosave::AutosaveConfig;
use crate::io::Sculpt;
use crate::math::{Pose, Vec3};
use crate::mesh::{MeshDiff, Mesher};
use crate::parts::{Symmetry, SymmetrySwitch};
use crate::render::{Frame, ToolGlyph};
use crate::scene::{Hand, HandState as PlaybackHand, Scene};
use crate::tool::{Action, Stroke, Tool, ToolShape, HAND_SIZE_SAMPLES};
use crate::ui::{Panel, PanelCommand, PanelView, PointerEvent, HEADSET_PANEL_PX};
use crate::xr::{
    one_hand_grab, recentred, two_hand_grab, FrameInput, FrameOutput, HandState, Haptic, Held, Placement,
    Turn, XrError, XrOptions, XrStation,
};

/// Trigger travel below which the tool is not applied.
const TRIGGER_ON: f32 = 0.1;
/// Squeeze travel from which a hand grabs.
const SQUEEZE_ON: f32 = 0.5;
/// Thumbstick deflection that counts as a flick (next shape).
const FLICK: f32 = 0.8;
/// How fast a full thumbstick deflection resizes the tool: factor per second.
const RESIZE_PER_S: f32 = 2.0;
/// The short pulse when the tool starts touching the clay.
pub const TOUCH_PULSE: (f32, i64) = (0.8, 20_000_000);
/// Duration of each contact vibration while sculpting (renewed every frame), nanoseconds.
pub const CONTACT_NS: i64 = 30_000_000;
/// How far beyond the tool's half extents the contact is felt, as a factor.
const CONTACT_REACH: f32 = 1.3;
/// Density under the tool from which it touches the clay.
const TOUCH_DENSITY: f32 = 0.5;
/// How fast a full thumbstick deflection raises a lattice control's value, per second.
const VALUE_PER_S: f32 = 0.5;
/// The tick when the tool comes onto a palette button.
pub const BUTTON_PULSE: (f32, i64) = (0.3, 10_000_000);
/// How far the tool hand's ray reaches the panel, room metres.
const RAY_REACH_M: f32 = 1.5;
/// How fast a full thumbstick deflection scrolls the panel, lines per second.
const SCROLL_LINES_PER_S: f32 = 12.0;
/// How a lattice is opened in the headset, as the messages say it.
const LATTICE_OPENS: &str = "the palette's lattice button or the panel opens one";

/// How long a headset run waits for a runtime that went away to come back by default, seconds.
pub const WAIT_FOR_RUNTIME_S: f64 = 30.0;

/// How a headset run goes.
#[derive(Clone, Debug)]
pub struct XrRunOptions {
    /// The session's options (validation, samples, loader).
    pub session: XrOptions,
    /// Ask to quit after this many drawn frames (scripted runs, tests).
    pub frames: Option<u64>,
    /// Where the sculpt is saved (when the session ends, is lost, or the runtime quits).
    pub save_to: Option<PathBuf>,
    /// Journal strokes for crash recovery.
    pub autosave: Option<AutosaveConfig>,
    /// The scene file's text, for the recovery journal.
    pub scene_toml: Option<String>,
    /// The dominant hand is the left one.
    pub left_handed: bool,
    /// How long to wait for a runtime that went away to come back, seconds.
    pub wait_for_runtime_s: f64,
    /// The tool edits the finest level whatever its size (by default one spanning more than
    /// [`HAND_SIZE_SAMPLES`] voxels edits the level its size chooses, unless its scene tool
    /// says which).
    pub edit_finest: bool,
}

impl Default for XrRunOptions {
    fn default() -> Self {
        Self {
            session: XrOptions::default(),
            frames: None,
            save_to: None,
            autosave: None,
            scene_toml: None,
            left_handed: false,
            wait_for_runtime_s: WAIT_FOR_RUNTIME_S,
            edit_finest: false,
        }
    }
}

/// What a headset run did.
#[derive(Clone, Debug, PartialEq)]
pub struct XrReport {
    /// The runtime's name and version.
    pub runtime: String,
    /// The size of each eye's image, pixels, as the runtime chose it.
    pub eye_px: (u32, u32),
    /// Frames drawn.
    pub frames: u64,
    /// Sessions lost and made again.
    pub recreated: u32,
    /// Times the runtime went away (instance loss).
    pub instance_losses: u32,
    /// The runtime went away and did not come back in time: the caller goes on at the desk.
    pub runtime_gone: bool,
    /// Where the sculpt was saved, if it was.
    pub saved: Option<PathBuf>,
    /// Whether depth was submitted with the projection layer.
    pub depth: bool,
    /// Per drawn frame: (before the step, simulation, meshing, render submission), ms.
    pub stage_ms: Vec<[f64; 4]>,
    /// Per drawn frame, at `xrEndFrame`: the age of the controller poses the glyphs were
    /// drawn at, and of those the step acted on, ms.
    pub pose_age_ms: Vec<[f64; 2]>,
}

/// A grab of the sculpture in progress: the placement and the hands when it began.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Grab {
    One {
        hand: usize,
        start: Placement,
        hand_start: Pose,
    },
    Two {
        start: Placement,
        hands_start: (Vec3, Vec3),
    },
    /// The support hand alone, on a sculpt of several parts: it carries the active part (its
    /// placement at the grip and the hand's world pose then), its thumbstick scaling it.
    Part {
        start: crate::parts::Placement,
        hand_start: Pose,
        scale: f32,
    },
}

/// The headset station's state between frames, without the session and renderer.
#[derive(Debug)]
pub struct XrSculptor<'s> {
    scene: &'s Scene,
    /// The sculpt: its clay, history, file and autosave session (as the desk's).
    doc: Document<'s>,
    placement: Placement,
    /// Index of the dominant hand in `[left, right]`.
    dominant: usize,
    tool: Tool,
    /// The most voxels across the tool's size on the level it edits, where its scene tool
    /// sets none (`None`: the finest level whatever its size).
    hand_samples: Option<f32>,
    /// The scene tool the dominant hand's tool came from (a push tool pushes the virtual clay
    /// through the playback).
    tool_index: Option<usize>,
    /// The scene's support tool, which the other hand's trigger holds against the clay.
    support: Option<usize>,
    action_index: usize,
    stroke: Option<Stroke>,
    grab: Option<Grab>,
    previous: [HandState; 2],
    /// The tool touched the clay last frame.
    touching: bool,
    /// The scene's clock, seconds.
    time_s: f32,
    /// Time spent in the last step: tools and simulation, meshing (ms).
    times: (f64, f64),
    /// The palette button the tool hand points at.
    pointed: Option<Button>,
    /// The symmetry the strokes and pushes act through.
    symmetry: SymmetrySwitch,
    /// The quit button was pressed.
    quit: bool,
    /// Messages for the user.
    pub messages: Vec<String>,
    /// Re-meshes what each frame's edits dirtied, reusing its buffers from frame to frame.
    mesher: Mesher,
    /// The panel, shown and hidden by the palette's panel button.
    panel: Panel,
    /// Where the tool hand's ray meets the panel: the pixel, and the point in the room.
    panel_hit: Option<([f32; 2], Vec3)>,
    /// The trigger went down on the panel and is held: the panel keeps the hand.
    panel_held: bool,
    /// Where the tool was last (the scene), for a lattice opened around it.
    last_tool_pose: Option<Pose>,
    /// The surface as the renderer holds it, for the panel's exports, and the one under way.
    exports: super::export::Exports,
    /// The region tool the tool hand holds instead of sculpting (the palette's region button
    /// steps it), if any.
    region_tool: Option<RegionTool>,
    /// While a box is dragged out: where the trigger went down (the scene).
    box_from: Option<Vec3>,
}

impl<'s> XrSculptor<'s> {
    /// The scene at time 0, shown at the work point in front of the viewer.
    pub fn new(scene: &'s Scene, playback: Playback<'s>, save_to: PathBuf, left_handed: bool) -> Self {
        let tools = playback.tools();
        let tool_index = tools.iter().position(|t| t.action != Action::Support);
        let support = tools.iter().position(|t| t.action == Action::Support);
        let tool = tool_index
            .map(|i| tools[i].clone())
            .unwrap_or_else(|| Tool::new(ToolShape::sphere(0.01), Action::Add, [0.8, 0.5, 0.35, 1.0]));
        let action_index = action_cycle().iter().position(|a| *a == tool.action).unwrap_or(0);
        // The sculpt's symmetry (the scene's, or the one a sculpt file stored).
        let symmetry = *playback.symmetry();
        Self {
            scene,
            doc: Document::new(playback, save_to),
            placement: recentred(scene.rig.target_m, None),
            dominant: if left_handed { 0 } else { 1 },
            tool,
            hand_samples: Some(HAND_SIZE_SAMPLES),
            tool_index,
            support,
            action_index,
            stroke: None,
            grab: None,
            previous: Default::default(),
            touching: false,
            time_s: 0.0,
            times: (0.0, 0.0),
            pointed: None,
            symmetry: SymmetrySwitch::new(symmetry),
            quit: false,
            messages: Vec::new(),
            mesher: Mesher::default(),
            panel: {
                let mut panel = Panel::headset();
                panel.set_shown(false);
                panel
            },
            panel_hit: None,
            panel_held: false,
            last_tool_pose: None,
            exports: super::export::Exports::default(),
            region_tool: None,
            box_from: None,
        }
    }

    /// The text of the scene, stored with the clay when saving.
    pub fn set_scene_toml(&mut self, text: Option<String>) {
        self.doc.set_scene_toml(text);
    }

    /// Lets the tool edit by its size with at most `samples` voxels across it where its scene
    /// tool does not say which level it edits (`None`: always the finest level). The default
    /// is [`HAND_SIZE_SAMPLES`].
    pub fn set_hand_samples(&mut self, samples: Option<f32>) {
        self.hand_samples = samples;
    }

    /// The clay.
    pub fn field(&self) -> &crate::field::Field {
        self.doc.playback.field()
    }

    /// Where the sculpture is in the room.
    pub fn placement(&self) -> Placement {
        self.placement
    }

    /// The dominant hand's tool.
    pub fn tool(&self) -> &Tool {
        &self.tool
    }

    /// Whether the palette's quit button was pressed: the caller ends the session.
    pub fn wants_quit(&self) -> bool {
        self.quit
    }

    /// The palette button the tool hand points at, if any.
    pub fn pointed(&self) -> Option<Button> {
        self.pointed
    }

    /// Writes the sculpt to the save path, atomically, first closing a stroke in progress;
    /// where that cannot be written, to the fallback folder (see
    /// [`XrSculptor::set_fallback_dir`]), as the desk does.
    pub fn save(&mut self) -> Result<PathBuf> {
        self.end_stroke();
        let saved = self
            .doc
            .save(None, "the sculpt stays in memory; `argile xr --save-to FILE` saves it elsewhere")?;
        self.messages.extend(saved.moved);
        Ok(saved.path)
    }

    /// Where a save that cannot write its file writes the sculpt instead (the headset uses
    /// `saved/` in the state folder, as the desk does).
    pub fn set_fallback_dir(&mut self, dir: Option<PathBuf>) {
        self.doc.set_fallback_dir(dir);
    }

    /// What the sculpt file lacks: the strokes (and undos, redos) since the last save or open,
    /// and one more for a lattice held open that is not as the last save stored it.
    pub fn unsaved_work(&self) -> u64 {
        self.doc.unsaved_work()
    }

    /// The dominant hand's tool as it acts in the scene: its room size kept whatever the
    /// sculpture's scale, soft actions at the rate the trigger's pressure sets.
    /// The scene's push tool, when the tool hand holds it to push the virtual clay (through
    /// the playback) rather than a region tool.
    fn pushing_tool(&self) -> Option<usize> {
        self.tool_index.filter(|_| self.tool.action == Action::Push && self.region_tool.is_none())
    }

    fn acting_tool(&self, pressure: f32) -> Tool {
        let mut tool = self.tool.clone().by_size_unless_set(self.hand_samples);
        tool.scale /= self.placement.scale;
        tool.action = match tool.action {
            Action::Build { rate_per_s } => Action::Build { rate_per_s: rate_per_s * pressure },
            Action::SoftRemove { rate_per_s } => Action::SoftRemove { rate_per_s: rate_per_s * pressure },
            Action::SoftPaint { rate_per_s } => Action::SoftPaint { rate_per_s: rate_per_s * pressure },
            Action::Smooth { centre_weight, rate_per_s } => {
                Action::Smooth { centre_weight, rate_per_s: rate_per_s * pressure }
            }
            other => other,
        };
        tool
    }

    fn undo(&mut self) {
        self.end_stroke();
        match self.doc.playback.undo() {
            Ok(true) => self.doc.journal(),
            Ok(false) => self.messages.push("nothing to undo".into()),
            Err(e) => self.messages.push(format!("undo failed: {e}")),
        }
    }

    fn redo(&mut self) {
        self.end_stroke();
        if self.doc.playback.redo() {
            self.doc.journal();
        } else {
            self.messages.push("nothing to redo".into());
        }
    }

    /// Closes the stroke in progress, and lets a region carried go, journaling each.
    fn end_stroke(&mut self) {
        if self.stroke.take().is_some() {
            if let Ok((field, _)) = self.doc.playback.active_target() {
                field.end_stroke();
            }
            self.doc.journal();
        }
        if self.doc.playback.let_go_region() {
            self.doc.edited();
        }
    }

    /// The region tool the tool hand holds instead of sculpting, if any.
    pub fn region_tool(&self) -> Option<RegionTool> {
        self.region_tool
    }

    /// Copies the clay within the tool at `pose` (the scene), or the box selected, into a new
    /// part, the active one; says so.
    fn copy_to_part(&mut self, pose: Pose) -> Result<(), String> {
        let part = self.doc.playback.copy_to_new_part(self.acting_tool(1.0), pose)?;
        self.doc.edited();
        let count = self.doc.playback.assembly().parts().len();
        let name = &self.doc.playback.assembly().parts()[part].name;
        let said =
            format!("the region is copied into a new part: active part {} of {count}: {name}", part + 1);
        self.messages.push(said);
        Ok(())
    }

    /// The tool hand's region tool at `pose` (the scene), the trigger `pulling` it (`pulled`:
    /// this frame): a drag takes the region of the tool's shape as the trigger goes down,
    /// carries it with the hand and lets it go, one undo step, as the trigger comes up;
    /// inflate and deflate move the surface within the region by one step each pull.
    fn drive_region(&mut self, pose: Option<Pose>, pulling: bool, pulled: bool) {
        let Some(region_tool) = self.region_tool else { return };
        if region_tool == RegionTool::SelectBox {
            // The box is dragged out from where the trigger went down to where it comes up.
            match (pulling, self.box_from, pose) {
                (true, None, Some(p)) => self.box_from = Some(p.position_m),
                (true, Some(from), Some(p)) => {
                    self.doc.playback.select_box(from, p.position_m);
                }
                (false, Some(from), Some(p)) => {
                    self.box_from = None;
                    let size = self.doc.playback.select_box(from, p.position_m);
                    self.messages.push(selection_said(size, "a pull without a drag"));
                }
                (false, Some(_), None) => self.box_from = None,
                _ => {}
            }
            return;
        }
        let tool = self.acting_tool(1.0);
        let held = self.doc.playback.held_region().is_some();
        let failed = match (region_tool, pose.filter(|_| pulling), held) {
            (RegionTool::Drag(op), Some(pose), false) => self.doc.playback.grab_region(op, tool, pose).err(),
            (RegionTool::Drag(_), Some(pose), true) => {
                self.doc.playback.carry_region(pose).and_then(Result::err)
            }
            (RegionTool::CopyToPart, Some(pose), false) if pulled => self.copy_to_part(pose).err(),
            (RegionTool::Swell { out }, Some(pose), false) if pulled => {
                let distance = if out { SWELL_STEP_M } else { -SWELL_STEP_M };
                let swelled = self.doc.playback.swell_region(tool, pose, distance);
                if swelled.is_ok() {
                    self.doc.edited();
                }
                swelled.err()
            }
            (_, None, true) => {
                self.end_stroke();
                None
            }
            _ => None,
        };
        if let Some(message) = failed {
            if self.messages.last() != Some(&message) {
                self.messages.push(message);
            }
        }
    }

    /// The palette's buttons: the dominant hand's grip on one of them points at it (a tick on
    /// arrival), and its trigger pressed there presses it. Returns whether the tool hand is on
    /// the palette (it does not sculpt there).
    fn palette_buttons(&mut self, input: &FrameInput, haptics: &mut Vec<Haptic>) -> bool {
        let (d, o) = (self.dominant, 1 - self.dominant);
        let pointed = match (input.hands[d].grip, input.hands[o].grip) {
            (Some(tool), Some(palette)) => Button::at(palette, tool.position_m),
            _ => None,
        };
        if pointed.is_some() && pointed != self.pointed {
            let hand = if d == 0 { Hand::Left } else { Hand::Right };
            haptics.push(Haptic { hand, amplitude: BUTTON_PULSE.0, duration_ns: BUTTON_PULSE.1 });
        }
        self.pointed = pointed;
        let pressed = input.hands[d].trigger >= TRIGGER_ON && self.previous[d].trigger < TRIGGER_ON;
        match pointed.filter(|_| pressed) {
            Some(Button::Undo) => self.undo(),
            Some(Button::Redo) => self.redo(),
            Some(Button::Recentre) => self.placement = recentred(self.scene.rig.target_m, input.head),
            Some(Button::Save) => self.save_and_say(),
            Some(Button::Quit) => self.quit = true,
            Some(Button::Symmetry) => {
                let symmetry = self.symmetry.step();
                self.set_symmetry(symmetry);
            }
            Some(Button::Lattice) => self.lattice_button(),
            Some(Button::Region) => {
                self.end_stroke();
                self.box_from = None;
                self.region_tool = RegionTool::after(self.region_tool);
                self.messages.push(match self.region_tool {
                    Some(t) => t.describe(),
                    None => "region tools off: the trigger sculpts again".into(),
                });
            }
            Some(Button::Panel) => {
                let shown = !self.panel.shown();
                self.panel.set_shown(shown);
                if !shown {
                    self.panel_hit = None;
                    self.panel_held = false;
                }
            }
            None => {}
        }
        pointed.is_some()
    }

    /// Whether the panel is shown.
    pub fn panel_shown(&self) -> bool {
        self.panel.shown()
    }

    /// The pixel of the panel the tool hand's ray meets, if it does.
    pub fn panel_pointer(&self) -> Option<[f32; 2]> {
        self.panel_hit.map(|(px, _)| px)
    }

    /// The tool hand's ray on the panel: where it meets the panel is the panel's pointer, the
    /// trigger going down there presses (and the panel keeps the hand until it is let go), and
    /// the thumbstick scrolls (a press is taken only where `may_press`: the hand is not on a
    /// palette button). Returns whether the panel has the hand (it does not sculpt).
    fn point_at_panel(&mut self, input: &FrameInput, may_press: bool, dt_s: f32) -> bool {
        if !self.panel.shown() {
            return false;
        }
        let (d, o) = (self.dominant, 1 - self.dominant);
        let (now, before) = (input.hands[d], self.previous[d]);
        let hit = match (input.hands[o].grip, now.aim.or(now.grip)) {
            (Some(grip), Some(aim)) => ray_on_panel(
                panel_placement(grip, HEADSET_PANEL_PX),
                HEADSET_PANEL_PX,
                aim.position_m,
                aim.rotation * Vec3::NEG_Z,
                RAY_REACH_M,
            ),
            _ => None,
        };
        let down = now.trigger >= TRIGGER_ON;
        if let Some((px, _)) = hit {
            self.panel.pointer(PointerEvent::Moved(px));
            if down && before.trigger < TRIGGER_ON && may_press {
                self.panel.pointer(PointerEvent::Primary(true));
                self.panel_held = true;
            }
            let y = now.thumbstick.y;
            if y.abs() > 0.2 {
                self.panel.pointer(PointerEvent::Wheel(y * SCROLL_LINES_PER_S * dt_s));
            }
        }
        if self.panel_held && !down {
            self.panel.pointer(PointerEvent::Primary(false));
            self.panel_held = false;
        }
        // Off the panel, the pointer leaves it (a drag keeps it to the end).
        if hit.is_none() && self.panel_hit.is_some() && !self.panel_held {
            self.panel.pointer(PointerEvent::Left);
        }
        self.panel_hit = hit;
        hit.is_some() || self.panel_held
    }

    /// What the panel shows now.
    fn panel_view(&self) -> PanelView {
        let playback = &self.doc.playback;
        let history = playback.assembly().history_len(playback.field());
        let (undo, redo) = panel_rows::history_rows(history, &[], &[]);
        let symmetry = playback.symmetry();
        let save_to = self.doc.save_to();
        let acting = self.tool.clone().by_size_unless_set(self.hand_samples);
        let mut view = PanelView {
            headset: true,
            level_samples: acting.level_samples,
            level: panel_rows::edit_level(playback, &acting),
            parts: panel_rows::part_rows(playback),
            active_part: playback.assembly().active(),
            symmetry: (symmetry.describe(), !symmetry.is_none()),
            lattice: panel_rows::lattice_row(playback),
            undo,
            redo,
            save_to: save_to.display().to_string(),
            save_name: save_to.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
            unsaved: self.doc.unsaved_work(),
            unsaved_fate: self.doc.unsaved_fate(),
            sculpt_extension: super::SCULPT_EXTENSION,
            export_formats: crate::mesh::export::ExportFormat::ALL.map(|f| f.extension()).to_vec(),
            status: self
                .exports
                .status()
                .into_iter()
                .chain(self.messages.iter().rev().take(3).rev().cloned())
                .collect(),
            ..PanelView::default()
        };
        panel_rows::fill_tool(&mut view, &self.tool, self.action_index);
        view
    }

    /// Does what the panel asked; `head` is where the head is (for recentring).
    fn panel_command(&mut self, command: PanelCommand, head: Option<Pose>) {
        if panel_rows::apply_tool(&command, &mut self.tool, &mut self.action_index, &mut self.hand_samples) {
            return;
        }
        if let Some(step) = LatticeStep::of(&command) {
            self.end_stroke();
            let said = panel_rows::lattice_step(&mut self.doc, step, LATTICE_OPENS);
            self.messages.push(said);
            return;
        }
        match command {
            PanelCommand::ActivePart(i) => {
                self.end_stroke();
                let count = self.doc.playback.assembly().parts().len();
                let part = self.doc.playback.set_active_part(i);
                let name = &self.doc.playback.assembly().parts()[part].name;
                self.messages.push(format!("active part {} of {count}: {name}", part + 1));
            }
            PanelCommand::CopyToPart => {
                self.end_stroke();
                let copied = match self.last_tool_pose {
                    Some(pose) => self.copy_to_part(pose),
                    None => Err("the tool hand has not been seen: nothing to copy around it".into()),
                };
                if let Err(why) = copied {
                    self.messages.push(why);
                }
            }
            PanelCommand::ToggleSymmetry => {
                let symmetry = self.symmetry.toggle();
                self.set_symmetry(symmetry);
            }
            PanelCommand::NextSymmetry => {
                let symmetry = self.symmetry.next_choice();
                self.set_symmetry(symmetry);
            }
            PanelCommand::RecentreHead => self.placement = recentred(self.scene.rig.target_m, head),
            PanelCommand::Undo(n) => (0..n).for_each(|_| self.undo()),
            PanelCommand::Redo(n) => (0..n).for_each(|_| self.redo()),
            PanelCommand::LatticeForm(form) => {
                self.doc.playback.set_lattice_form(form);
                let form = self.doc.playback.lattice_form().describe();
                self.messages.push(format!("lattices open as: {form}"));
            }
            PanelCommand::OpenLattice(whole_part) => self.open_lattice(whole_part),
            PanelCommand::Save => self.save_and_say(),
            PanelCommand::SaveAs(path) => {
                self.end_stroke();
                let saved = self.doc.save_as(&path, None);
                let said = panel_rows::saved_as_said(&saved, self.doc.save_to());
                self.messages.push(said);
            }
            PanelCommand::Open(path) => self.open(&path),
            PanelCommand::Export(path) => {
                let said = self.exports.start(&path);
                self.messages.push(said);
            }
            PanelCommand::Quit => self.quit = true,
            // The tool's and the lattice's were taken above; the desk's view, devices and
            // recovered sculpts are not on the headset's panel.
            _ => {}
        }
    }

    /// Saves, and says where (or why not).
    fn save_and_say(&mut self) {
        match self.save() {
            Ok(p) => self.messages.push(format!("saved the sculpt to {}", p.display())),
            Err(e) => self.messages.push(format!("cannot save the sculpt: {e:#}")),
        }
    }

    /// Opens the sculpt at `path` in place of this one (its own file from then on); says so.
    fn open(&mut self, path: &std::path::Path) {
        self.end_stroke();
        let left = self.doc.unsaved_work();
        let fate = self.doc.unsaved_fate();
        match self.doc.open(path) {
            Ok(opened) => {
                self.messages.push(panel_rows::opened_said(path, left, fate));
                self.messages.extend(opened.notes);
                if let Some(symmetry) = opened.symmetry {
                    self.symmetry = SymmetrySwitch::new(symmetry);
                }
            }
            Err(e) => self.messages.push(format!("{e:#}")),
        }
    }

    /// Opens a lattice around the tool (where it was last) or over the active part's clay.
    fn open_lattice(&mut self, whole_part: bool) {
        self.end_stroke();
        if self.doc.playback.held_lattice().is_some() {
            self.messages.push("a lattice is open already: apply it or put the clay back first".into());
            return;
        }
        let around = self.last_tool_pose.filter(|_| !whole_part).map(|pose| (&self.tool, pose));
        let form = self.doc.playback.lattice_form();
        let said = match panel_rows::lattice_region(&self.doc.playback, around) {
            Ok(region) => match self.doc.playback.open_lattice(&form.over(region)) {
                Ok(()) => format!(
                    "lattice open ({}): the trigger drags the control nearest the tool, the thumbstick its \
                     value; the lattice button applies it, undo puts the clay back",
                    form.describe()
                ),
                Err(e) => e,
            },
            Err(why) => why,
        };
        self.messages.push(said);
    }

    /// The palette's lattice button: opens a lattice over the active part's whole clay, or
    /// applies the one open (one undo step).
    fn lattice_button(&mut self) {
        self.end_stroke();
        if self.doc.playback.apply_lattice() {
            self.doc.edited();
            self.messages.push("lattice applied (undo takes it back)".into());
            return;
        }
        self.open_lattice(true);
    }

    /// With a lattice open, the tool hand at `pose` (the scene): the control nearest it is
    /// picked, the trigger pulled off the palette drags it (a drag starts only as the trigger
    /// goes down), and the thumbstick raises or lowers its value. Returns whether a lattice is
    /// open (the hand then does not sculpt).
    fn drive_lattice(&mut self, input: &FrameInput, pose: Option<Pose>, on_palette: bool, dt_s: f32) -> bool {
        let d = self.dominant;
        let (now, before) = (input.hands[d], self.previous[d]);
        let local =
            pose.map(|pose| self.doc.playback.in_active_part(self.tool.clone(), pose, &[]).1.position_m);
        let Some(held) = self.doc.playback.held_lattice_mut() else { return false };
        let mut failed = None;
        if let Some(point) = local {
            held.pick_nearest(point);
            let pulling = now.trigger >= TRIGGER_ON && !on_palette && self.grab.is_none();
            let drag = pulling && (held.dragging() || before.trigger < TRIGGER_ON);
            failed = held.drag(point, drag).err().map(|e| format!("the control stays: {e}"));
        }
        let y = now.thumbstick.y;
        if y.abs() > 0.2 && failed.is_none() {
            failed = held
                .add_value((VALUE_PER_S * y * dt_s) as f64)
                .err()
                .map(|e| format!("the value stays: {e}"));
        }
        if let Some(message) = failed {
            if self.messages.last() != Some(&message) {
                self.messages.push(message);
            }
        }
        true
    }

    /// Buttons and thumbstick of the dominant hand (its thumbstick's up and down scroll the
    /// panel instead while the hand is `on_panel`); menu of the other.
    fn controls(&mut self, input: &FrameInput, on_panel: bool, dt_s: f32) {
        let (d, o) = (self.dominant, 1 - self.dominant);
        let (now, before) = (input.hands[d], self.previous[d]);
        if now.primary && !before.primary {
            self.undo();
        } else if now.secondary && !before.secondary {
            self.redo();
        }
        let y = now.thumbstick.y;
        // With a lattice open the thumbstick sets the picked control's value instead.
        if y.abs() > 0.2 && self.doc.playback.held_lattice().is_none() && !on_panel {
            self.tool.scale *= RESIZE_PER_S.powf(y * dt_s);
        }
        let flick = |x: f32| {
            if x > FLICK {
                1
            } else if x < -FLICK {
                -1
            } else {
                0
            }
        };
        if flick(now.thumbstick.x) != 0 && flick(before.thumbstick.x) == 0 {
            let size = self.tool.shape.half_extents_m().min_element();
            let cycle = shape_cycle(size);
            let at = cycle.iter().position(|(_, n)| *n == shape_name(&self.tool.shape)).unwrap_or(0);
            let step = if flick(now.thumbstick.x) > 0 { 1 } else { cycle.len() - 1 };
            self.tool.shape = cycle[(at + step) % cycle.len()].0.clone();
        }
        if now.thumbstick_click && !before.thumbstick_click {
            let cycle = action_cycle();
            self.action_index = (self.action_index + 1) % cycle.len();
            self.tool.action = cycle[self.action_index];
        }
        if input.hands[o].menu && !self.previous[o].menu {
            self.placement = recentred(self.scene.rig.target_m, input.head);
        }
        let (other, other_before) = (input.hands[o], self.previous[o]);
        if other.thumbstick_click && !other_before.thumbstick_click {
            let symmetry = self.symmetry.toggle();
            self.set_symmetry(symmetry);
        } else if other.primary && !other_before.primary {
            let symmetry = self.symmetry.next_choice();
            self.set_symmetry(symmetry);
        } else if other.secondary && !other_before.secondary {
            self.end_stroke();
            let count = self.doc.playback.assembly().parts().len();
            let part = self.doc.playback.set_active_part(self.doc.playback.assembly().active() + 1);
            let name = &self.doc.playback.assembly().parts()[part].name;
            self.messages.push(format!("active part {} of {count}: {name}", part + 1));
        }
    }

    /// Strokes and pushes from now on act through `symmetry`; the user is told.
    fn set_symmetry(&mut self, symmetry: Symmetry) {
        self.doc.playback.set_symmetry(symmetry);
        self.messages.push(format!("symmetry {}", symmetry.describe()));
    }

    /// The symmetry strokes act through now.
    pub fn symmetry(&self) -> &Symmetry {
        self.doc.playback.symmetry()
    }

    /// Grips: one hand drags and turns the sculpture, two also scale it; on a sculpt of several
    /// parts, the support hand alone carries and turns the active part, and its thumbstick
    /// scales it (as Medium's layers are grabbed).
    fn grabs(&mut self, hands: &[HandState; 2], dt_s: f32) {
        let gripping: Vec<(usize, Pose)> = (0..2)
            .filter_map(|i| hands[i].grip.filter(|_| hands[i].squeeze >= SQUEEZE_ON).map(|p| (i, p)))
            .collect();
        let support = 1 - self.dominant;
        let parted = self.doc.playback.assembly().parts().len() > 1;
        let was_part = match self.grab {
            Some(Grab::Part { start, .. }) => Some(start),
            _ => None,
        };
        self.grab = match (gripping.as_slice(), self.grab) {
            ([(i, p)], Some(Grab::Part { start, hand_start, scale })) if *i == support => {
                let y = hands[support].thumbstick.y;
                let scale = if y.abs() > 0.2 { scale * RESIZE_PER_S.powf(y * dt_s) } else { scale };
                let scale = (start.scale * scale)
                    .clamp(*crate::parts::SCALE_RANGE.start(), *crate::parts::SCALE_RANGE.end())
                    / start.scale;
                // Carried and turned as one grip carries the sculpture, scaled about its origin.
                let at =
                    Placement { scale: 1.0, rotation: start.rotation, translation_m: start.translation_m };
                let moved = one_hand_grab(&at, hand_start, self.placement.pose_to_world(*p));
                let placed = crate::parts::Placement {
                    rotation: moved.rotation,
                    translation_m: moved.translation_m,
                    scale: start.scale * scale,
                };
                self.doc.playback.set_part_placement(self.doc.playback.assembly().active(), placed);
                Some(Grab::Part { start, hand_start, scale })
            }
            ([(i, p)], _) if *i == support && parted => {
                let start =
                    self.doc.playback.assembly().parts()[self.doc.playback.assembly().active()].placement;
                Some(Grab::Part { start, hand_start: self.placement.pose_to_world(*p), scale: 1.0 })
            }
            ([(_, a), (_, b)], Some(Grab::Two { start, hands_start })) => {
                self.placement = two_hand_grab(&start, hands_start, (a.position_m, b.position_m));
                self.grab
            }
            ([(_, a), (_, b)], _) => {
                Some(Grab::Two { start: self.placement, hands_start: (a.position_m, b.position_m) })
            }
            ([(i, p)], Some(Grab::One { hand, start, hand_start })) if *i == hand => {
                self.placement = one_hand_grab(&start, hand_start, *p);
                self.grab
            }
            ([(i, p)], _) => Some(Grab::One { hand: *i, start: self.placement, hand_start: *p }),
            _ => None,
        };
        if let (Some(start), false) = (was_part, matches!(self.grab, Some(Grab::Part { .. }))) {
            // Let go: the move is one undo step, and the autosave session keeps where the part
            // is (the file does not yet).
            self.doc.playback.keep_part_moved(self.doc.playback.assembly().active(), start);
            self.doc.edited();
        }
    }

    /// Runs one headset frame: controls, grabs, the scene's timeline and the dominant hand's
    /// stroke, meshing (the mesh changes go to `apply`); returns the frame to draw and the
    /// haptic pulses.
    pub fn step(&mut self, input: &FrameInput, mut apply: impl FnMut(&MeshDiff)) -> FrameOutput {
        let started = std::time::Instant::now();
        let dt_s = input.period_s.clamp(1e-4, 0.1);
        let mut haptics = Vec::new();
        self.messages.extend(self.exports.poll());
        let on_palette = self.palette_buttons(input, &mut haptics);
        let on_panel = self.point_at_panel(input, !on_palette, dt_s);
        let mut panel_paint = None;
        if self.panel.shown() {
            let view = self.panel_view();
            let (commands, paint) = self.panel.run(&view, HEADSET_PANEL_PX, f64::from(self.time_s));
            for command in commands {
                self.panel_command(command, input.head);
            }
            panel_paint = paint;
        }
        let on_palette = on_palette || on_panel;
        self.controls(input, on_panel, dt_s);
        self.grabs(&input.hands, dt_s);
        let hand = input.hands[self.dominant];
        let tool_pose = hand.grip.map(|g| self.placement.pose_to_world(g));
        self.last_tool_pose = tool_pose.or(self.last_tool_pose);
        let lattice = self.drive_lattice(input, tool_pose, on_palette, dt_s);
        let pulling = hand.trigger >= TRIGGER_ON
            && tool_pose.is_some()
            && self.grab.is_none()
            && !on_palette
            && !lattice;
        let pulled = pulling && self.previous[self.dominant].trigger < TRIGGER_ON;
        // A region tool takes the trigger from the sculpting tools.
        let applying = pulling && self.region_tool.is_none();
        // The virtual clay: the dominant hand's push tool and the other hand's support act
        // through the playback, as the scene's scripted hands do.
        let pushing_tool = self.pushing_tool();
        let mut live = [None, None];
        if let (Some(tool), Some(pose)) = (pushing_tool, tool_pose) {
            live[self.dominant] = Some(PlaybackHand { tool, pose, active: applying, part: 0 });
        }
        let other = input.hands[1 - self.dominant];
        if let (Some(tool), Some(grip)) = (self.support, other.grip) {
            let active = other.trigger >= TRIGGER_ON && self.grab.is_none();
            let pose = self.placement.pose_to_world(grip);
            live[1 - self.dominant] = Some(PlaybackHand { tool, pose, active, part: 0 });
        }
        self.doc.playback.set_live_hands(live);
        self.time_s += dt_s;
        self.doc.playback.advance_to(self.time_s, |_| {});
        // The playback draws with the push tool; the stroke below is for the other actions.
        let applying_stroke = applying && pushing_tool.is_none();
        let tool = self.acting_tool(hand.trigger.clamp(0.0, 1.0));
        let side = if self.dominant == 0 { Hand::Left } else { Hand::Right };
        if let Some(pose) = tool_pose {
            let density = contact_density(self.doc.playback.surface_now(), pose, tool.half_extents_m());
            let touching = density >= TOUCH_DENSITY;
            if touching && !self.touching {
                haptics.push(Haptic { hand: side, amplitude: TOUCH_PULSE.0, duration_ns: TOUCH_PULSE.1 });
            } else if touching && applying {
                // While sculpting, the vibration follows the contact: the density under the tool.
                haptics.push(Haptic {
                    hand: side,
                    amplitude: density.clamp(0.0, 1.0),
                    duration_ns: CONTACT_NS,
                });
            }
            self.touching = touching;
        } else {
            self.touching = false;
        }
        // The tool acts on the active part, in its frame.
        let images = self.doc.playback.images().to_vec();
        let placed = tool_pose.map(|pose| self.doc.playback.in_active_part(tool.clone(), pose, &images));
        match (applying_stroke, placed, self.doc.playback.active_target()) {
            (true, Some((tool, pose, images)), Ok((field, _))) => {
                if self.stroke.is_none() {
                    field.begin_stroke();
                    let mut s = Stroke::with_images(tool.clone(), &images);
                    s.advance(field, pose, 0.0);
                    self.stroke = Some(s);
                }
                if let Some(s) = &mut self.stroke {
                    s.set_tool(tool);
                    s.advance(field, pose, dt_s);
                }
            }
            (true, Some(_), Err(why)) => {
                if self.messages.last() != Some(&why) {
                    self.messages.push(why);
                }
            }
            (_, _, target) => {
                if self.stroke.take().is_some() {
                    if let Ok((field, _)) = target {
                        field.end_stroke();
                    }
                    self.doc.journal();
                }
            }
        }
        self.drive_region(tool_pose, pulling, pulled);
        let tools_ms = started.elapsed().as_secs_f64() * 1e3;
        let meshing = std::time::Instant::now();
        self.doc.playback.sync_lattices();
        self.doc.playback.keep_lattice();
        let diff = self.mesher.remesh_dirty(self.doc.playback.surface());
        if !diff.is_empty() {
            self.exports.apply(diff);
            apply(diff);
        }
        self.times = (tools_ms, meshing.elapsed().as_secs_f64() * 1e3);
        let (mut frame, mut held) = self.frame(&input.hands, tool_pose.map(|pose| (pose, pulling)), &tool);
        // The panel on its board in the support hand; without that hand tracked, its textures
        // still go to the renderer (each is given once) and nothing is drawn.
        if let Some(mut paint) = panel_paint {
            let support = 1 - self.dominant;
            match input.hands[support].grip {
                Some(grip) => {
                    let room_to_scene = self.placement.matrix().inverse();
                    paint.placement = Some(room_to_scene * panel_placement(grip, HEADSET_PANEL_PX));
                    held[support].push(Held::Panel);
                }
                None => paint.batches.clear(),
            }
            frame.panel = Some(paint);
        }
        self.previous = input.hands;
        FrameOutput { frame, placement: self.placement, haptics, held }
    }
}

impl XrSculptor<'_> {
    /// The frame to draw, in scene metres: the clay; the dominant hand's tool at `dominant`
    /// (its pose, and whether it is applied) with its shape and size as it acts (`acting`, or
    /// the scene's push tool, which acts through the playback) in its action's colour; the
    /// support where the other hand holds or put it; and, room-sized, each tracked controller's
    /// handle and the palette of the current tool beside the other hand.
    ///
    /// Also returns the glyphs each hand holds (its controller, palette and tool), which the
    /// session draws where that hand is located last.
    fn frame(
        &self,
        hands: &[HandState; 2],
        dominant: Option<(Pose, bool)>,
        acting: &Tool,
    ) -> (Frame, [Vec<Held>; 2]) {
        let mut frame = build_frame(self.scene, &[], true);
        let mut held: [Vec<Held>; 2] = Default::default();
        let tools = self.doc.playback.tools();
        if let Some((pose, applying)) = dominant {
            held[self.dominant].push(Held::Tool(frame.tools.len()));
            let tool = match self.pushing_tool() {
                Some(i) => &tools[i],
                None => acting,
            };
            // A region tool is drawn in the colour of the regions it carries.
            let rgb = match self.region_tool {
                Some(_) => Vec3::from(REGION_RGB),
                None => action_colour(&tool.action),
            };
            let colour = rgb.extend(if applying { 0.6 } else { 0.35 });
            frame.tools.push(tool_glyph(&tool.shape, pose, tool.scale, colour));
            // Its images under the symmetry, fainter, with the planes and the axis.
            for image in self.doc.playback.images().iter().skip(1) {
                let ghost = colour.truncate().extend(0.5 * colour.w);
                frame.tools.push(tool_glyph(&tool.shape, image.pose(&pose).0, tool.scale, ghost));
            }
        }
        frame.tools.extend(super::frame::symmetry_glyphs(&self.doc.playback));
        frame.tools.extend(super::frame::lattice_glyphs(&self.doc.playback));
        frame.tools.extend(super::frame::region_glyphs(&self.doc.playback));
        // The active part's box while the support hand carries it.
        if matches!(self.grab, Some(Grab::Part { .. })) {
            frame.tools.extend(super::frame::part_glyph(&self.doc.playback, super::frame::PART_COLOUR));
        }
        let other = if self.dominant == 0 { Hand::Right } else { Hand::Left };
        if let Some((i, pose)) = self.doc.playback.hand(other) {
            let t = &tools[i];
            let colour = action_colour(&t.action).extend(self.scene.tools[i].glyph_opacity);
            frame.tools.push(tool_glyph(&t.shape, pose, t.scale, colour));
        }
        let room_to_scene = self.placement.matrix().inverse();
        let in_scene = |g: ToolGlyph| ToolGlyph { model: room_to_scene * g.model, ..g };
        for (i, hand) in hands.iter().enumerate() {
            let Some(grip) = hand.grip else { continue };
            let first = frame.controllers.len();
            frame.controllers.push(in_scene(controller_glyph(grip)));
            if i != self.dominant {
                frame.controllers.extend(palette(grip, &self.tool).map(in_scene));
                frame.controllers.extend(buttons(grip, self.pointed).map(in_scene));
            }
            held[i].extend((first..frame.controllers.len()).map(Held::Controller));
        }
        // The ray from the tool hand to where it meets the panel.
        let hand = hands[self.dominant];
        if let (Some((_, hit)), Some(aim)) = (self.panel_hit, hand.aim.or(hand.grip)) {
            let first = frame.controllers.len();
            frame.controllers.extend(ray_glyphs(aim.position_m, hit).map(in_scene));
            held[self.dominant].extend((first..frame.controllers.len()).map(Held::Controller));
        }
        (frame, held)
    }
}

/// The densest clay under a tool at `pose` with half extents `half_m`: sampled at its centre
/// and just beyond the ends of its three axes (a carving tool clears what it covers, so the
/// clay it works on lies at its rim).
pub fn contact_density(field: &crate::field::Field, pose: Pose, half_m: Vec3) -> f32 {
    let mut reader = FieldReader::new(field);
    let axes = [Vec3::ZERO, Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
    axes.iter()
        .map(|a| {
            let p = pose.position_m + pose.rotation * (*a * half_m * CONTACT_REACH);
            reader.density_at(field.transform().world_to_index(p))
        })
        .fold(0.0, f32::max)
}

/// Runs the station in the headset on `scene` until the runtime ends the session, the
/// palette's quit button or a stopping signal (SIGINT, SIGTERM, SIGHUP) ends it, or the frame
/// count of `options` is reached. The sculpt is then saved and the autosave session closed.
///
/// When the runtime goes away (the instance is lost, with its loss-pending event or with a
/// call answering `XR_ERROR_INSTANCE_LOST`), the sculpt is saved at once and Argile waits up
/// to [`XrRunOptions::wait_for_runtime_s`] for the runtime to come back, as the specification
/// allows after an instance loss; a new session then goes on with the same sculpt, undo
/// history and journal. If it does not come back, [`XrReport::runtime_gone`] says so and the
/// caller goes on at the desktop station with the saved sculpt.
///
/// Fails with an [`XrError`] that [`XrError::is_absent`] when there is no loader, runtime,
/// Vulkan support or headset at the start: the caller then falls back to the desktop stereo
/// modes.
pub fn run_xr(
    scene: &Scene,
    opened: Option<Sculpt>,
    scene_name: &str,
    options: &XrRunOptions,
) -> Result<XrReport> {
    let environment = super::environment::load_environment(&scene.environment.choice)?;
    let intensity = scene.environment.intensity;
    let first = XrStation::start(&options.session, &environment, intensity)?;
    let save_to = options.save_to.clone().unwrap_or_else(|| PathBuf::from(format!("{scene_name}.argile")));
    let source = scene.source.clone();
    let start = |field: &mut Field, tools: crate::io::autosave::Besides<'_>| {
        options.autosave.clone().and_then(|config| {
            super::autosave::start_autosave(field, (options.scene_toml.as_deref(), tools), &source, config)
        })
    };
    let playback = match opened {
        Some(sculpt) => {
            let mut playback = Playback::on_sculpt(scene, sculpt.field, sculpt.others, &sculpt.tools, start);
            if let Some(symmetry) = sculpt.symmetry {
                playback.set_symmetry(symmetry);
            }
            if let Some(stored) = &sculpt.lattice {
                if let Err(e) = playback.reopen_lattice(stored) {
                    eprintln!(
                        "warning: {}: {e}; the clay is as it was before the lattice",
                        save_to.display()
                    );
                }
            }
            playback
        }
        None => Playback::new_autosaved(scene, start)?,
    };
    let mut sculptor = XrSculptor::new(scene, playback, save_to, options.left_handed);
    sculptor.set_scene_toml(options.scene_toml.clone());
    sculptor.set_fallback_dir(super::state_dir().map(|d| d.join("saved")));
    sculptor.set_hand_samples((!options.edit_finest).then_some(HAND_SIZE_SAMPLES));
    let mut report = XrReport {
        runtime: first.runtime().to_owned(),
        eye_px: first.eye_size(),
        frames: 0,
        recreated: 0,
        instance_losses: 0,
        runtime_gone: false,
        saved: None,
        depth: first.submits_depth(),
        stage_ms: Vec::new(),
        pose_age_ms: Vec::new(),
    };
    let mut validation = first.renderer().validation_log();
    let mut problems = Vec::new();
    let mut station = Some(first);
    let mut exit_asked = false;
    let outcome: Result<()> = loop {
        let Some(live) = station.as_mut() else { break Ok(()) };
        // A stopping signal or the palette's quit button ends the session as the runtime's
        // own exit does: it walks down to EXITING, then the sculpt is saved below.
        let signalled = super::signals::received();
        if !exit_asked && (signalled.is_some() || sculptor.wants_quit()) {
            exit_asked = true;
            if let Some(signal) = signalled {
                println!(
                    "{} received: saving the sculpt and ending the headset session",
                    super::signals::name(signal)
                );
            }
            if let Err(e) = live.request_exit() {
                break Err(e.into());
            }
        }
        let mut upload = Ok(());
        let turn = live.turn(|input, renderer| {
            sculptor.step(input, |diff| {
                if upload.is_ok() {
                    upload = renderer.apply(diff);
                }
            })
        });
        let turn = match turn.and_then(|t| upload.map(|()| t).map_err(XrError::from)) {
            Ok(t) => t,
            Err(e) => break Err(e.into()),
        };
        match turn {
            Turn::Waiting => std::thread::sleep(std::time::Duration::from_millis(5)),
            Turn::Skipped => {}
            Turn::Drawn => {
                report.frames += 1;
                let t = live.times();
                report.stage_ms.push([t.before_ms, sculptor.times.0, sculptor.times.1, t.submit_ms]);
                report.pose_age_ms.push([t.pose_age_ms, t.input_pose_age_ms]);
                report.depth = live.submits_depth();
                if options.frames.is_some_and(|n| report.frames >= n) && !exit_asked {
                    exit_asked = true;
                    if let Err(e) = live.request_exit() {
                        break Err(e.into());
                    }
                }
            }
            Turn::Recreated => {
                report.recreated += 1;
                match sculptor.save() {
                    Ok(p) => report.saved = Some(p),
                    Err(e) => break Err(e.context("cannot save the sculpt after the session was lost")),
                }
                sculptor
                    .messages
                    .push("the headset session was lost and made again; the sculpt is saved".into());
            }
            Turn::Finished => break Ok(()),
            Turn::InstanceLost => {
                report.instance_losses += 1;
                let saved = match sculptor.save() {
                    Ok(p) => p,
                    Err(e) => {
                        break Err(e.context("the OpenXR runtime went away and the sculpt cannot be saved"))
                    }
                };
                report.saved = Some(saved.clone());
                // The lost instance's renderer goes; what the validation layer said of it stays.
                station = None;
                problems.extend(validation.take());
                if exit_asked {
                    break Ok(());
                }
                let wait = options.wait_for_runtime_s;
                println!(
                    "The OpenXR runtime went away; the sculpt is saved in {}. Waiting up to {wait} s for it to come back.",
                    saved.display()
                );
                match wait_for_runtime(options, &environment, intensity, wait) {
                    Ok(mut back) => {
                        println!(
                            "The OpenXR runtime {} is back: a new headset session goes on with the sculpt.",
                            back.runtime()
                        );
                        validation = back.renderer().validation_log();
                        let diff = sculptor.mesher.mesh_all(sculptor.doc.playback.surface());
                        // The new renderer holds none of the panel's textures yet.
                        sculptor.panel.renew_textures();
                        if let Err(e) = back.renderer_mut().apply(diff) {
                            break Err(
                                anyhow::Error::new(e).context("cannot draw the sculpt in the new session")
                            );
                        }
                        report.runtime = back.runtime().to_owned();
                        report.eye_px = back.eye_size();
                        station = Some(back);
                    }
                    Err(why) => {
                        println!("The OpenXR runtime did not come back within {wait} s ({why}).");
                        report.runtime_gone = true;
                    }
                }
            }
        }
    };
    if let Err(e) = outcome {
        // No sculpt is lost to a failing runtime or renderer: save, then report. The autosave
        // session is closed only once the sculpt is safe; otherwise the next start recovers it.
        drop(station);
        return Err(match sculptor.save() {
            Ok(p) => {
                sculptor.doc.end_session();
                e.context(format!("the headset session failed (the sculpt is saved in {})", p.display()))
            }
            Err(s) => e.context(format!(
                "the headset session failed, and saving failed too: {s:#} (the autosave journal keeps the strokes: `argile recover`)"
            )),
        });
    }
    for m in sculptor.messages.drain(..) {
        tracing::info!("{m}");
    }
    // A run that ends with its instance lost saved the sculpt as it went, and nothing
    // happened since; one that ends with a session saves it now.
    if station.is_some() {
        report.saved = Some(sculptor.save()?);
    }
    let unsaved = sculptor.unsaved_work();
    if let Some(Err(dir)) = sculptor.doc.end_session() {
        // Work done after the last save (the run ended with its instance lost): kept.
        println!(
            "{unsaved} change(s) of this run are not saved: the autosave journal in {} keeps them, and \
             `argile recover` gives them back",
            dir.display()
        );
    }
    // OpenXR and then Vulkan go (XrStation's drop order) before the report is returned, so
    // what the validation layer says of the teardown is read too.
    drop(station);
    problems.extend(validation.take());
    if !problems.is_empty() {
        anyhow::bail!(
            "the Vulkan validation layer reported {} problem(s):\n{}",
            problems.len(),
            problems.join("\n")
        );
    }
    if options.frames.is_some() && !report.stage_ms.is_empty() {
        println!("{}", report.stage_summary());
    }
    Ok(report)
}

/// Tries to start a headset session every quarter second for `wait_s` seconds; returns the
/// station, or why the last try failed. A stopping signal ends the wait.
fn wait_for_runtime(
    options: &XrRunOptions,
    environment: &crate::render::Environment,
    intensity: f32,
    wait_s: f64,
) -> Result<XrStation, String> {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs_f64(wait_s.max(0.0));
    loop {
        let why = match XrStation::start(&options.session, environment, intensity) {
            Ok(station) => return Ok(station),
            Err(e) => e.to_string(),
        };
        if let Some(signal) = super::signals::received() {
            return Err(format!("{} received", super::signals::name(signal)));
        }
        if std::time::Instant::now() >= deadline {
            return Err(why);
        }
        std::thread::sleep(std::time::Duration::from_millis(250));
    }
}

impl XrReport {
    /// The medians of the frame's stages and of the poses' ages, one line.
    pub fn stage_summary(&self) -> String {
        let median = crate::math::median;
        let stage = |i: usize| median(self.stage_ms.iter().map(|s| s[i]).collect());
        let age = |i: usize| median(self.pose_age_ms.iter().map(|s| s[i]).collect());
        format!(
            "frame stages, median ms over {} frames ({}×{} per eye): frame start {:.3}, tools {:.3}, mesh {:.3}, \
             render submission {:.2}; controller poses drawn {:.2} ms old at submission (the step's {:.2} ms)",
            self.stage_ms.len(),
            self.eye_px.0,
            self.eye_px.1,
            stage(0),
            stage(1),
            stage(2),
            stage(3),
            age(0),
            age(1),
        )
    }
}

/// Whether `e` says there is no headset here (no loader, runtime, Vulkan support or headset).
pub fn xr_absent(e: &anyhow::Error) -> Option<&XrError> {
    e.downcast_ref::<XrError>().filter(|x| x.is_absent())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Quat, Vec2};
    use crate::parts::RegionOp;

    /// A ball of clay (radius 5 cm) at the scene's origin and a gouge; shown at the work
    /// point, so its front is at room (0, 1.3, −0.40).
    fn ball() -> Scene {
        Scene::parse(
            "[field]\nvoxel_size_m = 0.004\n[camera]\neye_m = [0.0, 0.0, 0.5]\ntarget_m = [0.0, 0.0, 0.0]\n\
             [[clay]]\nshape = \"sphere\"\nradius_m = 0.05\n\
             [[tool]]\nname = \"gouge\"\nradius_m = 0.012\naction = \"remove\"\n",
            "ball",
            None,
        )
        .unwrap()
    }

    #[test]
    fn the_hand_tool_edits_by_its_size_unless_its_scene_tool_or_the_options_say_otherwise() {
        let scene = ball();
        let mut s = sculptor(&scene, false);
        assert_eq!(s.acting_tool(1.0).level_samples, Some(HAND_SIZE_SAMPLES));
        s.set_hand_samples(None);
        assert_eq!(s.acting_tool(1.0).level_samples, None, "--edit-finest");
        let sized = Scene::parse(
            "[[tool]]\nname = \"gouge\"\nradius_m = 0.012\naction = \"remove\"\nlevel_samples = 8\n",
            "sized",
            None,
        )
        .unwrap();
        for hand in [Some(HAND_SIZE_SAMPLES), None] {
            let mut s = sculptor(&sized, false);
            s.set_hand_samples(hand);
            assert_eq!(s.acting_tool(1.0).level_samples, Some(8.0), "the scene tool's own");
        }
    }

    fn sculptor(scene: &Scene, left_handed: bool) -> XrSculptor<'_> {
        XrSculptor::new(scene, Playback::new(scene), "unused.argile".into(), left_handed)
    }

    #[test]
    fn a_headset_save_that_cannot_write_its_file_saves_to_the_fallback_folder() {
        let dir = std::env::temp_dir().join(format!("argile-xr-fallback-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // A file where the save folder should be: no write there succeeds, even as root.
        std::fs::write(dir.join("not-a-folder"), "x").unwrap();
        let scene = ball();
        let blocked = dir.join("not-a-folder").join("ball.argile");
        let mut s = XrSculptor::new(&scene, Playback::new(&scene), blocked, false);
        let e = format!("{:#}", s.save().unwrap_err());
        assert!(e.contains("stays in memory") && e.contains("not-a-folder"), "{e}");
        s.set_fallback_dir(Some(dir.join("saved")));
        let path = s.save().unwrap();
        assert!(path.starts_with(dir.join("saved")), "{path:?}");
        let said = s.messages.pop().unwrap();
        assert!(said.contains("cannot save to") && said.contains(&path.display().to_string()), "{said}");
        let saved = crate::io::read_file(&path, &mut |_| {}).unwrap();
        assert!(saved.field.same_samples(s.field()));
        assert_eq!(s.save().unwrap(), path, "saves go there from now on");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn at(x: f32, y: f32, z: f32) -> Option<Pose> {
        Some(Pose { position_m: Vec3::new(x, y, z), rotation: Quat::IDENTITY })
    }

    /// One frame of 1/90 s with `hands` (left, right).
    fn frame(s: &mut XrSculptor<'_>, hands: [HandState; 2]) -> FrameOutput {
        let input = FrameInput {
            index: 0,
            display_time_ns: 0,
            period_s: 1.0 / 90.0,
            focused: true,
            head: None,
            hands,
        };
        s.step(&input, |_| {})
    }

    /// Where the palette's (left) hand is held in the palette tests.
    const PALETTE: Pose = Pose { position_m: Vec3::new(-0.1, 1.6, -0.1), rotation: Quat::IDENTITY };

    /// The palette's hand at [`PALETTE`].
    fn palette_hand() -> HandState {
        HandState { grip: Some(PALETTE), ..HandState::default() }
    }

    /// The tool hand at `p`, its trigger pulled by `trigger`.
    fn tool_hand(p: Vec3, trigger: f32) -> HandState {
        HandState {
            grip: Some(Pose { position_m: p, rotation: Quat::IDENTITY }),
            trigger,
            ..HandState::default()
        }
    }

    /// The tool hand presses palette button `b` (three frames: onto it, the trigger pulled, let
    /// go); returns the last frame.
    fn press(s: &mut XrSculptor<'_>, b: Button) -> FrameOutput {
        frame(s, [palette_hand(), tool_hand(b.centre(PALETTE), 0.0)]);
        frame(s, [palette_hand(), tool_hand(b.centre(PALETTE), 1.0)]);
        frame(s, [palette_hand(), tool_hand(b.centre(PALETTE), 0.0)])
    }

    fn density(s: &XrSculptor<'_>, p: Vec3) -> f32 {
        let field = s.field();
        FieldReader::new(field).density_at(field.transform().world_to_index(p))
    }

    /// The tool hand 30 cm in front of the panel's pixel `px` (for the left hand at `palette`),
    /// its aim (and grip) pointing at it, its trigger at `trigger`.
    fn aiming(palette: Pose, px: [f32; 2], trigger: f32) -> HandState {
        let on = panel_placement(palette, HEADSET_PANEL_PX).transform_point3(Vec3::new(px[0], px[1], 0.0));
        let from = on + Vec3::new(0.05, 0.1, 0.3);
        let pose = Pose {
            position_m: from,
            rotation: Quat::from_rotation_arc(Vec3::NEG_Z, (on - from).normalize()),
        };
        HandState { grip: Some(pose), aim: Some(pose), trigger, ..HandState::default() }
    }

    #[test]
    fn the_panel_button_shows_the_panel_whose_ray_points_clicks_scrolls_saves_and_quits_without_sculpting() {
        let scene = ball();
        let dir = std::env::temp_dir().join(format!("argile-xr-panel-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("panel.argile");
        let _ = std::fs::remove_file(&path);
        let mut s = XrSculptor::new(&scene, Playback::new(&scene), path.clone(), false);
        let palette = Pose { position_m: Vec3::new(-0.1, 1.3, -0.3), rotation: Quat::IDENTITY };
        let left = HandState { grip: Some(palette), ..HandState::default() };
        let out = frame(&mut s, [left, aiming(palette, [256.0, 400.0], 0.0)]);
        assert!(!s.panel_shown() && out.frame.panel.is_none(), "hidden at first");
        assert_eq!(s.panel_pointer(), None, "a hidden panel is not pointed at");
        // The palette's panel button shows it, on its board in the left hand.
        let on = |trigger: f32| HandState {
            grip: Some(Pose { position_m: Button::Panel.centre(palette), rotation: Quat::IDENTITY }),
            trigger,
            ..HandState::default()
        };
        for trigger in [0.0, 1.0, 0.0] {
            frame(&mut s, [left, on(trigger)]);
        }
        assert!(s.panel_shown());
        // The ray meets the panel where it is aimed; the frame draws the panel where the left
        // hand holds it, with the ray and its dot.
        let out = frame(&mut s, [left, aiming(palette, [256.0, 400.0], 0.0)]);
        let [x, y] = s.panel_pointer().expect("the ray meets the panel");
        assert!((x - 256.0).abs() < 0.05 && (y - 400.0).abs() < 0.05, "{x}, {y}");
        let paint = out.frame.panel.as_ref().expect("the panel is drawn");
        let placed = paint.placement.expect("on its board");
        let expected = s.placement().matrix().inverse() * panel_placement(palette, HEADSET_PANEL_PX);
        assert!(placed.abs_diff_eq(expected, 1e-5));
        assert!(!paint.batches.is_empty());
        assert!(out.held[0].contains(&Held::Panel), "the left hand carries it to its last pose");
        let dot = out.frame.controllers.last().expect("the ray's dot");
        let hit = s.placement().matrix().transform_point3(dot.model.w_axis.truncate());
        let aimed = panel_placement(palette, HEADSET_PANEL_PX).transform_point3(Vec3::new(256.0, 400.0, 0.0));
        assert!(hit.distance(aimed) < 1e-4, "the dot is where the ray meets the panel");
        // The trigger on the panel presses its controls and sculpts nothing; the thumbstick
        // scrolls it and leaves the tool's size.
        let before = s.field().history_stats();
        let scale = s.tool().scale;
        for trigger in [1.0, 1.0, 0.0] {
            frame(&mut s, [left, aiming(palette, [256.0, 400.0], trigger)]);
        }
        let mut scroll = aiming(palette, [256.0, 400.0], 0.0);
        scroll.thumbstick = Vec2::new(0.0, -1.0);
        frame(&mut s, [left, scroll]);
        assert_eq!(s.field().history_stats(), before, "no stroke from the panel");
        assert_eq!(s.tool().scale, scale, "the thumbstick scrolled the panel");
        // Back at the top, the first row: Save writes the sculpt, Quit asks to end.
        scroll.thumbstick = Vec2::new(0.0, 1.0);
        for _ in 0..30 {
            frame(&mut s, [left, scroll]);
        }
        let mut x = 16.0;
        while !s.wants_quit() && x < HEADSET_PANEL_PX.0 as f32 {
            for trigger in [0.0, 1.0, 0.0, 0.0] {
                frame(&mut s, [left, aiming(palette, [x, 20.0], trigger)]);
            }
            x += 16.0;
        }
        assert!(s.wants_quit(), "the first row's Quit");
        assert!(crate::app::load_sculpt(&path).is_ok(), "the first row's Save wrote the sculpt");
        assert!(s.messages.iter().any(|m| m.starts_with("saved the sculpt to")), "{:?}", s.messages);
        // Pressed again, the panel button hides it: no ray, nothing drawn.
        for trigger in [0.0, 1.0, 0.0] {
            frame(&mut s, [left, on(trigger)]);
        }
        let out = frame(&mut s, [left, aiming(palette, [256.0, 400.0], 0.0)]);
        assert!(!s.panel_shown() && out.frame.panel.is_none() && s.panel_pointer().is_none());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_panels_save_as_and_open_move_the_sculpt_between_files() {
        let scene = ball();
        let dir = std::env::temp_dir().join(format!("argile-xr-open-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let front = Vec3::new(0.0, 0.0, 0.045);
        let mut s = XrSculptor::new(&scene, Playback::new(&scene), dir.join("a.argile"), false);
        let carve = HandState { grip: at(0.0, 1.3, -0.40), trigger: 1.0, ..HandState::default() };
        frame(&mut s, [HandState::default(), carve]);
        frame(&mut s, [HandState::default(), HandState { trigger: 0.0, ..carve }]);
        assert!(density(&s, front) < 0.5, "carved");
        let b = dir.join("b.argile");
        s.panel_command(PanelCommand::SaveAs(b.clone()), None);
        assert_eq!(s.doc.save_to(), b, "saving writes there from now on");
        // Another headset session opens it from its panel: the carved clay, saved back to it.
        let mut t = XrSculptor::new(&scene, Playback::new(&scene), dir.join("c.argile"), false);
        assert!(density(&t, front) > 0.5);
        t.panel_command(PanelCommand::Open(b.clone()), None);
        assert!(t.messages.last().unwrap().starts_with("opened"), "{:?}", t.messages);
        assert!(density(&t, front) < 0.5, "the opened sculpt's clay");
        assert_eq!(t.doc.save_to(), b);
        // A file that is not there changes nothing, and the message names it.
        t.panel_command(PanelCommand::Open(dir.join("missing.argile")), None);
        assert!(t.messages.last().unwrap().contains("missing.argile"), "{:?}", t.messages);
        assert_eq!(t.doc.save_to(), b);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_panels_export_writes_the_surface_as_drawn_away_from_the_frame() {
        let scene = ball();
        let dir = std::env::temp_dir().join(format!("argile-xr-export-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut s = XrSculptor::new(&scene, Playback::new(&scene), dir.join("ball.argile"), false);
        // A groove, meshed frame by frame as the headset draws it.
        let carve =
            |x: f32, trigger: f32| HandState { grip: at(x, 1.3, -0.40), trigger, ..HandState::default() };
        for i in 0..6 {
            frame(&mut s, [HandState::default(), carve(-0.02 + 0.008 * i as f32, 1.0)]);
        }
        frame(&mut s, [HandState::default(), carve(0.03, 0.0)]);
        // What the export holds is what the whole clay meshes to, chunk for chunk.
        let whole = crate::app::welded_surface(s.doc.playback.surface());
        assert_eq!(s.exports.surface().weld(), whole);
        let out = dir.join("ball.ply");
        let _ = std::fs::remove_file(&out);
        s.panel_command(PanelCommand::Export(out.clone()), None);
        assert!(s.messages.last().unwrap().starts_with("exporting"), "{:?}", s.messages);
        s.panel_command(PanelCommand::Export(dir.join("again.obj")), None);
        assert!(s.messages.last().unwrap().contains("one at a time"), "{:?}", s.messages);
        let mut said = None;
        for _ in 0..2000 {
            frame(&mut s, [HandState::default(), HandState::default()]);
            if let Some(m) = s.messages.iter().find(|m| m.starts_with("exported")) {
                said = Some(m.clone());
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        let said = said.expect("the export finished");
        assert!(said.contains(&format!("{} triangles", whole.triangle_count())), "{said}");
        assert!(std::fs::metadata(&out).unwrap().len() > 0);
        // A name the export does not know is refused with the file's name.
        s.panel_command(PanelCommand::Export(dir.join("ball.xyz")), None);
        assert!(s.messages.last().unwrap().contains("ball.xyz"), "{:?}", s.messages);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_palettes_buttons_undo_redo_recentre_save_and_quit_under_the_tool_hands_trigger() {
        let scene = ball();
        let dir = std::env::temp_dir().join(format!("argile-palette-buttons-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("palette.argile");
        let mut s = XrSculptor::new(&scene, Playback::new(&scene), path.clone(), false);
        let front = Vec3::new(0.0, 0.0, 0.045);
        // A stroke on the ball's front, the left hand away.
        let carve = HandState { grip: at(0.0, 1.3, -0.40), trigger: 1.0, ..HandState::default() };
        frame(&mut s, [HandState::default(), carve]);
        frame(&mut s, [HandState::default(), HandState { trigger: 0.0, ..carve }]);
        assert!(density(&s, front) < 0.5, "carved");
        let palette = Pose { position_m: Vec3::new(-0.1, 1.6, -0.1), rotation: Quat::from_rotation_y(0.3) };
        let left = HandState { grip: Some(palette), ..HandState::default() };
        let on = |b: Button, trigger: f32| HandState {
            grip: Some(Pose { position_m: b.centre(palette), rotation: Quat::IDENTITY }),
            trigger,
            ..HandState::default()
        };
        let press = |s: &mut XrSculptor<'_>, b: Button| {
            let out = frame(s, [left, on(b, 0.0)]);
            assert_eq!(s.pointed(), Some(b));
            assert!(
                out.haptics
                    .iter()
                    .any(|h| (h.amplitude, h.duration_ns) == BUTTON_PULSE && h.hand == Hand::Right),
                "a tick on arrival at {}",
                b.name()
            );
            // The pointed button is drawn opaque, the others not.
            let opaque = out.frame.controllers.iter().filter(|g| g.colour.w == 1.0).count();
            assert_eq!(opaque, 1, "{}", b.name());
            let out = frame(s, [left, on(b, 1.0)]);
            frame(s, [left, on(b, 0.0)]);
            out
        };
        press(&mut s, Button::Undo);
        assert!(density(&s, front) > 0.5, "undone");
        press(&mut s, Button::Redo);
        assert!(density(&s, front) < 0.5, "redone");
        // Holding the trigger on a button presses it once and sculpts nothing.
        let before = s.field().history_stats();
        for _ in 0..5 {
            frame(&mut s, [left, on(Button::Undo, 1.0)]);
        }
        assert!(density(&s, front) > 0.5);
        frame(&mut s, [left, on(Button::Undo, 0.0)]);
        assert_ne!(s.field().history_stats(), before, "one undo");
        press(&mut s, Button::Redo);
        // Dragged away, the sculpture comes back with the recentre button.
        let grip = |x: f32, y: f32| HandState { grip: at(x, y, -0.4), squeeze: 1.0, ..HandState::default() };
        frame(&mut s, [grip(-0.1, 1.3), grip(0.1, 1.3)]);
        frame(&mut s, [grip(-0.3, 1.5), grip(0.3, 1.5)]);
        frame(&mut s, [HandState::default(), HandState::default()]);
        assert!(s.placement().scale > 2.0);
        press(&mut s, Button::Recentre);
        assert_eq!(s.placement(), recentred(scene.rig.target_m, None));
        press(&mut s, Button::Save);
        let saved = crate::app::load_sculpt(&path).expect("the save button wrote the sculpt");
        let mut reader = FieldReader::new(&saved.field);
        assert!(reader.density_at(saved.field.transform().world_to_index(front)) < 0.5, "with the stroke");
        assert!(!s.wants_quit());
        press(&mut s, Button::Quit);
        assert!(s.wants_quit());
        // A hand away from the palette points at nothing.
        frame(&mut s, [left, HandState { grip: at(0.3, 1.0, 0.0), ..HandState::default() }]);
        assert_eq!(s.pointed(), None);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn what_a_hand_holds_is_drawn_where_the_hand_is_located_last() {
        let scene = ball();
        let mut s = sculptor(&scene, false);
        let (l, r) = (at(-0.1, 1.3, -0.2), at(0.1, 1.3, -0.2));
        let hold = |p: Option<Pose>| HandState { grip: p, ..HandState::default() };
        let mut out = frame(&mut s, [hold(l), hold(r)]);
        // The right hand's tool and handle, the left hand's handle, palette and buttons.
        assert_eq!(out.held[1].len(), 2);
        assert_eq!(out.held[0].len(), 1 + 3 + Button::ALL.len());
        let before = out.frame.clone();
        let moved = Pose { position_m: Vec3::new(0.12, 1.31, -0.2), rotation: Quat::from_rotation_z(0.2) };
        crate::xr::carry_held(&mut out.frame, &out.held, &out.placement, [l, r], [l, Some(moved)]);
        let tool = out.frame.tools[0];
        let centre = s.placement().to_stage(tool.model.w_axis.truncate());
        assert!((centre - moved.position_m).length() < 1e-5, "the tool follows the late pose: {centre}");
        // The left hand did not move: its glyphs are where they were.
        for g in &out.held[0] {
            let Held::Controller(i) = *g else { panic!("the left hand holds controllers only") };
            assert_eq!(out.frame.controllers[i], before.controllers[i]);
        }
        // A hand lost at the late location keeps its glyphs.
        let mut again = before.clone();
        crate::xr::carry_held(&mut again, &out.held, &out.placement, [l, r], [None, None]);
        assert_eq!(again, before);
    }

    #[test]
    fn the_other_hands_thumbstick_and_the_palette_switch_the_symmetry_and_strokes_follow_it() {
        let scene = ball();
        let mut s = sculptor(&scene, false);
        let rest = HandState::default();
        let click = HandState { thumbstick_click: true, ..rest };
        frame(&mut s, [click, rest]);
        assert_eq!(s.symmetry().describe(), "mirror x");
        assert!(s.messages.iter().any(|m| m == "symmetry mirror x"), "{:?}", s.messages);
        // Carve right of the mirror plane: the left side is carved too.
        let room = Vec3::new(0.02, 1.3, -0.41);
        let p = s.placement.matrix().inverse().transform_point3(room);
        let mirrored = Vec3::new(-p.x, p.y, p.z);
        assert!(p.x > 0.01 && density(&s, p) > 0.5 && density(&s, mirrored) > 0.5, "{p}");
        let carving = HandState { grip: at(room.x, room.y, room.z), trigger: 1.0, ..rest };
        for _ in 0..3 {
            frame(&mut s, [rest, carving]);
        }
        assert!(density(&s, p) < 0.5 && density(&s, mirrored) < 0.5, "both sides carved");
        frame(&mut s, [rest, HandState { grip: at(0.0, 1.3, -0.2), ..rest }]);
        frame(&mut s, [rest, HandState { grip: at(0.0, 1.3, -0.2), primary: true, ..rest }]);
        assert!(density(&s, p) > 0.5 && density(&s, mirrored) > 0.5, "one undo restores both");
        // X steps to the next symmetry; the palette's symmetry button steps on from there.
        frame(&mut s, [HandState { primary: true, ..rest }, rest]);
        assert_eq!(s.symmetry().describe(), "mirror x+z");
        let palette = Pose { position_m: Vec3::new(-0.1, 1.6, -0.1), rotation: Quat::IDENTITY };
        let on = HandState {
            grip: Some(Pose { position_m: Button::Symmetry.centre(palette), ..palette }),
            ..rest
        };
        let left = HandState { grip: Some(palette), ..rest };
        frame(&mut s, [left, on]);
        frame(&mut s, [left, HandState { trigger: 1.0, ..on }]);
        assert_eq!(s.symmetry().describe(), "radial 6 about y");
        // The mirror planes and the ghost tools are drawn while it is on.
        let (f, _) = s.frame(&[left, rest], Some((Pose::default(), false)), &s.tool().clone());
        assert_eq!(f.tools.len(), 1 + 5 + 1, "the tool, five images and the axis");
    }

    #[test]
    fn the_dominant_thumbstick_sizes_and_cycles_and_its_buttons_undo_and_redo() {
        let scene = ball();
        let mut s = sculptor(&scene, false);
        let scale = s.tool().scale;
        let up = HandState { thumbstick: Vec2::new(0.0, 1.0), ..HandState::default() };
        for _ in 0..90 {
            frame(&mut s, [HandState::default(), up]);
        }
        assert!(
            (s.tool().scale / scale - Vec3::splat(RESIZE_PER_S)).abs().max_element() < 0.02,
            "{}",
            s.tool().scale
        );
        assert_eq!(shape_name(&s.tool().shape), "sphere");
        let flick = HandState { thumbstick: Vec2::new(1.0, 0.0), ..HandState::default() };
        frame(&mut s, [HandState::default(), flick]);
        frame(&mut s, [HandState::default(), flick]);
        assert_eq!(shape_name(&s.tool().shape), "box", "one flick, one step");
        let rest = HandState::default();
        let mut names = Vec::new();
        for _ in 0..4 {
            frame(&mut s, [rest, rest]);
            frame(&mut s, [rest, flick]);
            names.push(shape_name(&s.tool().shape));
        }
        assert_eq!(names, ["cylinder", "torus", "ellipsoid", "sphere"], "round the cycle");
        let action = s.tool().action;
        let click = HandState { thumbstick_click: true, ..HandState::default() };
        frame(&mut s, [HandState::default(), click]);
        assert_ne!(s.tool().action, action);

        // Carve, undo with A, redo with B.
        let mut s = sculptor(&scene, false);
        let inside = Vec3::new(0.0, 0.0, 0.045);
        assert!(density(&s, inside) > 0.5);
        let carving = HandState { grip: at(0.0, 1.3, -0.40), trigger: 1.0, ..HandState::default() };
        for _ in 0..3 {
            frame(&mut s, [HandState::default(), carving]);
        }
        assert!(density(&s, inside) < 0.5, "the trigger carves");
        let rest = HandState { grip: at(0.0, 1.3, -0.2), ..HandState::default() };
        frame(&mut s, [HandState::default(), rest]);
        frame(&mut s, [HandState::default(), HandState { primary: true, ..rest }]);
        assert!(density(&s, inside) > 0.5, "A undoes the stroke");
        frame(&mut s, [HandState::default(), rest]);
        frame(&mut s, [HandState::default(), HandState { secondary: true, ..rest }]);
        assert!(density(&s, inside) < 0.5, "B redoes it");
    }

    #[test]
    fn the_lattice_button_opens_a_lattice_whose_controls_the_tool_hand_drags_and_values_then_applies_it() {
        let scene = ball();
        let mut s = sculptor(&scene, false);
        let ball = s.field().clone();
        let steps = ball.history_stats().undo_in_memory;
        let palette = Pose { position_m: Vec3::new(-0.1, 1.6, -0.1), rotation: Quat::IDENTITY };
        let left = HandState { grip: Some(palette), ..HandState::default() };
        let hand = |p: Vec3, trigger: f32, stick: f32| HandState {
            grip: Some(Pose { position_m: p, rotation: Quat::IDENTITY }),
            trigger,
            thumbstick: Vec2::new(0.0, stick),
            ..HandState::default()
        };
        let out = press(&mut s, Button::Lattice);
        assert!(s.doc.playback.held_lattice().is_some(), "{:?}", s.messages);
        assert!(out.frame.tools.len() > 64, "the lattice's controls and lines are drawn");
        // The hand goes to the control at (2, 2, 2): picked; the trigger drags it 2 cm (room).
        let control =
            s.doc.playback.held_lattice().unwrap().lattice().volume().control(2, 2, 2).unwrap().position_m;
        let room = s.placement().matrix().transform_point3(control);
        frame(&mut s, [left, hand(room, 0.0, 0.0)]);
        assert_eq!(s.doc.playback.held_lattice().unwrap().picked(), [2, 2, 2]);
        frame(&mut s, [left, hand(room, 1.0, 0.0)]);
        frame(&mut s, [left, hand(room + Vec3::new(0.02, 0.0, 0.0), 1.0, 0.0)]);
        frame(&mut s, [left, hand(room + Vec3::new(0.02, 0.0, 0.0), 0.0, 0.0)]);
        let held = s.doc.playback.held_lattice().unwrap();
        let moved = held.lattice().volume().control(2, 2, 2).unwrap().position_m - control;
        let expected = 0.02 / s.placement().scale;
        assert!((moved.x - expected).abs() < 1e-5 && moved.y.abs() < 1e-6, "{moved} vs {expected}");
        assert!(!s.field().same_samples(&ball), "the drag warped the clay, not a stroke");
        assert_eq!(s.field().history_stats().undo_in_memory, steps);
        // The thumbstick raises its value (half a unit a second), not the tool's size.
        let (value, size) = (held.lattice().volume().control(2, 2, 2).unwrap().value, s.tool().scale);
        for _ in 0..30 {
            frame(&mut s, [left, hand(room, 0.0, 1.0)]);
        }
        let raised =
            s.doc.playback.held_lattice().unwrap().lattice().volume().control(2, 2, 2).unwrap().value;
        assert!((raised - value - 30.0 * 0.5 / 90.0).abs() < 1e-4, "{value} → {raised}");
        assert_eq!(s.tool().scale, size);
        let shaped = s.field().clone();
        // Pressed again, the button applies it: one undo step, taken back exactly.
        press(&mut s, Button::Lattice);
        assert!(s.doc.playback.held_lattice().is_none());
        assert!(s.field().same_samples(&shaped));
        assert_eq!(s.field().history_stats().undo_in_memory, steps + 1);
        press(&mut s, Button::Undo);
        assert!(s.field().same_samples(&ball));
        // Opened again and dragged, undo puts the clay back and leaves no step.
        press(&mut s, Button::Lattice);
        frame(&mut s, [left, hand(room, 1.0, 0.0)]);
        frame(&mut s, [left, hand(room + Vec3::new(0.0, 0.03, 0.0), 1.0, 0.0)]);
        frame(&mut s, [left, hand(room, 0.0, 0.0)]);
        assert!(!s.field().same_samples(&ball));
        press(&mut s, Button::Undo);
        assert!(s.doc.playback.held_lattice().is_none());
        assert!(s.field().same_samples(&ball));
        assert_eq!(s.field().history_stats().undo_in_memory, steps);
    }

    #[test]
    fn the_region_button_steps_region_tools_whose_trigger_carries_copies_bends_and_swells_the_clay() {
        let scene = ball();
        let mut s = sculptor(&scene, false);
        let ball = s.field().clone();
        let steps = ball.history_stats().undo_in_memory;
        let (left, hand) = (palette_hand(), tool_hand);
        // The tool's centre on the ball's top, and 3 cm (room) above it.
        let top = Vec3::new(0.0, 0.05, 0.0);
        let room = s.placement().matrix().transform_point3(top);
        let lift = Vec3::new(0.0, 0.03, 0.0);
        let above = top + lift / s.placement().scale;
        let region_glyphs = |out: &FrameOutput| {
            out.frame.tools.iter().filter(|g| g.colour == super::super::frame::REGION_COLOUR).count()
        };
        // Drags: the trigger takes the region as it goes down and lets it go as it comes up.
        let drag = |s: &mut XrSculptor<'_>| {
            frame(s, [left, hand(room, 0.0)]);
            frame(s, [left, hand(room, 1.0)]);
            assert!(s.doc.playback.held_region().is_some(), "{:?}", s.messages);
            let out = frame(s, [left, hand(room + 0.5 * lift, 1.0)]);
            assert_eq!(region_glyphs(&out), 1, "the region is drawn where the hand carries it");
            frame(s, [left, hand(room + lift, 1.0)]);
            let out = frame(s, [left, hand(room + lift, 0.0)]);
            assert!(s.doc.playback.held_region().is_none());
            assert_eq!(region_glyphs(&out), 0);
            assert_eq!(s.field().history_stats().undo_in_memory, steps + 1, "one undo step");
        };
        let undo_to_ball = |s: &mut XrSculptor<'_>| {
            press(s, Button::Undo);
            assert!(s.field().same_samples(&ball), "undo gives the ball back bit for bit");
            assert_eq!(s.field().history_stats().undo_in_memory, steps);
        };

        press(&mut s, Button::Region);
        assert_eq!(s.region_tool(), Some(RegionTool::Drag(RegionOp::Move)));
        assert!(s.messages.last().unwrap().contains("move"), "{:?}", s.messages);
        // The tool is drawn in the regions' colour.
        let out = frame(&mut s, [left, hand(room, 0.0)]);
        assert!(out.frame.tools.iter().any(|g| g.colour.truncate() == Vec3::from(REGION_RGB)));
        drag(&mut s);
        assert!(density(&s, above) > 0.5, "the clay is carried up: {}", density(&s, above));
        assert!(density(&s, top - Vec3::new(0.0, 0.004, 0.0)) < 0.5, "and leaves empty space");
        undo_to_ball(&mut s);

        press(&mut s, Button::Region);
        assert_eq!(s.region_tool(), Some(RegionTool::Drag(RegionOp::Copy)));
        drag(&mut s);
        assert!(density(&s, above) > 0.5, "a copy is carried up");
        assert!(density(&s, top - Vec3::new(0.0, 0.004, 0.0)) > 0.5, "and the clay stays");
        undo_to_ball(&mut s);

        press(&mut s, Button::Region);
        assert_eq!(s.region_tool(), Some(RegionTool::Drag(RegionOp::Bend)));
        drag(&mut s);
        assert!(!s.field().same_samples(&ball), "the clay is bent up");
        assert!(density(&s, top + 0.5 * lift / s.placement().scale) > 0.5, "{:?}", s.messages);
        undo_to_ball(&mut s);

        // Swells: each pull one step of 1 mm, one undo step.
        press(&mut s, Button::Region);
        assert_eq!(s.region_tool(), Some(RegionTool::Swell { out: true }));
        let mass = s.field().mass();
        for trigger in [0.0, 1.0, 1.0, 0.0] {
            frame(&mut s, [left, hand(room, trigger)]);
        }
        assert!(s.field().mass() > mass, "inflated: {mass} → {}", s.field().mass());
        assert_eq!(s.field().history_stats().undo_in_memory, steps + 1, "one pull, one step");
        undo_to_ball(&mut s);
        press(&mut s, Button::Region);
        assert_eq!(s.region_tool(), Some(RegionTool::Swell { out: false }));
        for trigger in [0.0, 1.0, 0.0] {
            frame(&mut s, [left, hand(room, trigger)]);
        }
        assert!(s.field().mass() < mass, "deflated: {mass} → {}", s.field().mass());
        undo_to_ball(&mut s);
        // Away from any clay, a swell says so and leaves no step.
        for trigger in [0.0, 1.0, 0.0] {
            frame(&mut s, [left, hand(room + Vec3::new(0.0, 0.3, 0.0), trigger)]);
        }
        assert!(s.messages.last().unwrap().contains("no clay surface"), "{:?}", s.messages);
        assert_eq!(s.field().history_stats().undo_in_memory, steps);

        // Copy to part: a pull makes a new part of the clay within the tool, the active one.
        press(&mut s, Button::Region);
        assert_eq!(s.region_tool(), Some(RegionTool::CopyToPart));
        for trigger in [0.0, 1.0, 1.0, 0.0] {
            frame(&mut s, [left, hand(room, trigger)]);
        }
        let parts = s.doc.playback.assembly();
        assert_eq!((parts.parts().len(), parts.active()), (2, 1), "{:?}", s.messages);
        assert!(s.messages.last().unwrap().contains("active part 2 of 2: clay copy"), "{:?}", s.messages);
        assert!(s.field().same_samples(&ball), "the ball stays");
        press(&mut s, Button::Undo);
        assert_eq!(s.doc.playback.assembly().parts().len(), 1, "undo takes the part away");

        // Past the box selection (its own test), the trigger sculpts again (the scene's gouge
        // removes clay).
        while s.region_tool() != Some(RegionTool::SelectBox) {
            press(&mut s, Button::Region);
        }
        press(&mut s, Button::Region);
        assert_eq!(s.region_tool(), None);
        assert!(s.messages.last().unwrap().contains("sculpts again"));
        for trigger in [0.0, 1.0, 1.0, 0.0] {
            frame(&mut s, [left, hand(room, trigger)]);
        }
        assert!(s.field().mass() < mass, "the gouge carved");
    }

    #[test]
    fn the_select_box_tool_drags_out_a_box_the_other_region_tools_then_act_on() {
        let scene = ball();
        let mut s = sculptor(&scene, false);
        let (left, hand) = (palette_hand(), tool_hand);
        let room = |s: &XrSculptor<'_>, p: Vec3| s.placement().matrix().transform_point3(p);
        while s.region_tool() != Some(RegionTool::SelectBox) {
            press(&mut s, Button::Region);
        }
        // The trigger held from one corner of the ball's box to the other.
        let (a, b) = (room(&s, Vec3::splat(-0.06)), room(&s, Vec3::splat(0.06)));
        frame(&mut s, [left, hand(a, 0.0)]);
        frame(&mut s, [left, hand(a, 1.0)]);
        let out = frame(&mut s, [left, hand(b, 1.0)]);
        assert!(out.frame.tools.iter().any(|g| g.colour == super::super::frame::SELECTION_COLOUR));
        frame(&mut s, [left, hand(b, 0.0)]);
        assert!(s.messages.last().unwrap().contains("mm selected"), "{:?}", s.messages);
        let (_, selected) = s.doc.playback.selection().expect("a box is selected");
        assert!((selected.shape.half_extents_m() - Vec3::splat(0.06)).abs().max_element() < 1e-4);
        // Two presses on: sculpting, then move. The trigger 10 cm beside the ball carries it.
        press(&mut s, Button::Region);
        press(&mut s, Button::Region);
        assert_eq!(s.region_tool(), Some(RegionTool::Drag(RegionOp::Move)));
        let beside = room(&s, Vec3::new(0.1, 0.0, 0.0));
        let lift = Vec3::new(0.0, 0.05, 0.0);
        for (p, trigger) in [(beside, 0.0), (beside, 1.0), (beside + lift, 1.0), (beside + lift, 0.0)] {
            frame(&mut s, [left, hand(p, trigger)]);
        }
        let up = lift / s.placement().scale;
        let below = Vec3::new(0.0, -0.04, 0.0);
        assert!(density(&s, below) < 0.1 && density(&s, up) > 0.9, "the ball went up {up}: {:?}", s.messages);
        // A pull without a drag clears the box.
        while s.region_tool() != Some(RegionTool::SelectBox) {
            press(&mut s, Button::Region);
        }
        for trigger in [0.0, 1.0, 0.0] {
            frame(&mut s, [left, hand(a, trigger)]);
        }
        assert!(s.doc.playback.selection().is_none());
        assert!(s.messages.last().unwrap().contains("selection cleared"));
    }

    #[test]
    fn on_a_locked_part_the_region_tools_say_so_and_change_nothing() {
        let scene = Scene::parse(
            "[field]\nvoxel_size_m = 0.004\n[camera]\neye_m = [0.0, 0.0, 0.5]\ntarget_m = [0.0, 0.0, 0.0]\n\
             [[part]]\nname = \"base\"\nlocked = true\n\
             [[clay]]\nshape = \"sphere\"\nradius_m = 0.05\n",
            "locked",
            None,
        )
        .unwrap();
        let mut s = sculptor(&scene, false);
        let ball = s.field().clone();
        let (left, hand) = (palette_hand(), tool_hand);
        let room = s.placement().matrix().transform_point3(Vec3::new(0.0, 0.05, 0.0));
        for region_tool in RegionTool::ALL.into_iter().filter(|t| *t != RegionTool::SelectBox) {
            for trigger in [0.0, 1.0, 0.0] {
                frame(&mut s, [left, hand(Button::Region.centre(PALETTE), trigger)]);
            }
            assert_eq!(s.region_tool(), Some(region_tool));
            for trigger in [0.0, 1.0, 1.0, 0.0] {
                frame(&mut s, [left, hand(room, trigger)]);
            }
            assert!(s.messages.last().unwrap().contains("locked"), "{:?}", s.messages);
            assert!(s.field().same_samples(&ball));
        }
    }

    #[test]
    fn the_other_hand_grabs_and_both_hands_turn_move_and_scale_the_sculpture() {
        let scene = ball();
        let mut s = sculptor(&scene, false);
        let start = s.placement();
        let grip = |x: f32, y: f32| HandState { grip: at(x, y, -0.4), squeeze: 1.0, ..HandState::default() };
        frame(&mut s, [grip(-0.1, 1.3), HandState::default()]);
        frame(&mut s, [grip(-0.1, 1.4), HandState::default()]);
        let moved = s.placement().translation_m - start.translation_m;
        assert!((moved - Vec3::new(0.0, 0.1, 0.0)).length() < 1e-5, "{moved}");
        // Both grips: pulling the hands apart doubles the sculpture about their midpoint.
        frame(&mut s, [grip(-0.1, 1.3), grip(0.1, 1.3)]);
        let before = s.placement();
        frame(&mut s, [grip(-0.2, 1.3), grip(0.2, 1.3)]);
        assert!((s.placement().scale / before.scale - 2.0).abs() < 1e-4);
        // Gripping with the dominant hand while the trigger is held does not sculpt.
        let whole = density(&s, Vec3::new(0.0, 0.0, 0.045));
        let pulling = HandState { trigger: 1.0, ..grip(0.2, 1.3) };
        frame(&mut s, [grip(-0.2, 1.3), pulling]);
        assert_eq!(density(&s, Vec3::new(0.0, 0.0, 0.045)), whole);
    }

    #[test]
    fn on_a_second_part_a_stroke_and_a_carried_region_are_each_one_undo_step_taken_back_exactly() {
        let scene = Scene::parse(
            "[field]\nvoxel_size_m = 0.004\n[camera]\neye_m = [0.0, 0.0, 0.5]\ntarget_m = [0.0, 0.0, 0.0]\n\
             [[part]]\nname = \"body\"\n[[part]]\nname = \"head\"\nposition_m = [0.0, 0.02, 0.0]\nscale = 2.0\n\
             [[clay]]\npart = \"body\"\nshape = \"sphere\"\nradius_m = 0.03\n\
             [[clay]]\npart = \"head\"\nshape = \"sphere\"\nradius_m = 0.015\n\
             [[tool]]\nname = \"gouge\"\nradius_m = 0.012\naction = \"remove\"\n",
            "parts",
            None,
        )
        .unwrap();
        let mut s = sculptor(&scene, false);
        frame(&mut s, [HandState { secondary: true, ..HandState::default() }, HandState::default()]);
        frame(&mut s, [HandState::default(), HandState::default()]);
        assert_eq!(s.doc.playback.assembly().active(), 1);
        let head = || s.doc.playback.assembly().field(s.doc.playback.field(), 1).clone();
        let (rest, steps) = (head(), head().history_stats().undo_in_memory);
        let (left, hand) = (palette_hand(), tool_hand);
        // The head's top (its clay is 3 cm across the world at scale 2).
        let room = s.placement().matrix().transform_point3(Vec3::new(0.0, 0.05, 0.0));
        let stroke = |s: &mut XrSculptor<'_>| {
            frame(s, [left, hand(room, 0.0)]);
            for i in 0..6 {
                frame(s, [left, hand(room + Vec3::new(0.002 * i as f32, 0.0, 0.0), 1.0)]);
            }
            frame(s, [left, hand(room, 0.0)]);
        };
        stroke(&mut s);
        let field = s.doc.playback.assembly().field(s.doc.playback.field(), 1);
        assert!(!field.same_samples(&rest), "the gouge carved the head");
        assert_eq!(field.history_stats().undo_in_memory, steps + 1, "six frames of a stroke, one step");
        frame(&mut s, [left, hand(room, 0.0)]);
        s.undo();
        let field = s.doc.playback.assembly().field(s.doc.playback.field(), 1);
        assert!(field.same_samples(&rest), "undo gives the head back bit for bit");
        // A region carried over several frames.
        for trigger in [0.0, 1.0, 0.0] {
            frame(&mut s, [left, hand(Button::Region.centre(PALETTE), trigger)]);
        }
        assert_eq!(s.region_tool(), Some(RegionTool::Drag(RegionOp::Move)));
        stroke(&mut s);
        let field = s.doc.playback.assembly().field(s.doc.playback.field(), 1);
        assert!(!field.same_samples(&rest), "the region moved: {:?}", s.messages);
        assert_eq!(field.history_stats().undo_in_memory, steps + 1, "a drag over six frames, one step");
        s.undo();
        let field = s.doc.playback.assembly().field(s.doc.playback.field(), 1);
        assert!(field.same_samples(&rest), "undo gives the head back bit for bit");
    }

    #[test]
    fn on_a_sculpt_of_parts_the_support_grip_carries_turns_and_scales_the_active_part() {
        let scene = Scene::parse(
            "[field]\nvoxel_size_m = 0.004\n[camera]\neye_m = [0.0, 0.0, 0.5]\ntarget_m = [0.0, 0.0, 0.0]\n\
             [[part]]\nname = \"body\"\n[[part]]\nname = \"head\"\nposition_m = [0.0, 0.08, 0.0]\n\
             [[clay]]\npart = \"body\"\nshape = \"sphere\"\nradius_m = 0.05\n\
             [[clay]]\npart = \"head\"\nshape = \"sphere\"\nradius_m = 0.02\n\
             [[tool]]\nname = \"gouge\"\nradius_m = 0.012\naction = \"remove\"\n",
            "parts",
            None,
        )
        .unwrap();
        let mut s = sculptor(&scene, false);
        let sculpture = s.placement();
        // The other hand's second button makes the head the active part.
        frame(&mut s, [HandState { secondary: true, ..HandState::default() }, HandState::default()]);
        frame(&mut s, [HandState::default(), HandState::default()]);
        assert_eq!(s.doc.playback.assembly().active(), 1);
        assert!(s.messages.last().unwrap().contains("active part 2 of 2: head"));
        // The support (left) grip carries the head up 10 cm of the room, the sculpture stays.
        let grip = |y: f32, stick: f32| HandState {
            grip: at(-0.1, y, -0.4),
            squeeze: 1.0,
            thumbstick: Vec2::new(0.0, stick),
            ..HandState::default()
        };
        frame(&mut s, [grip(1.3, 0.0), HandState::default()]);
        let out = frame(&mut s, [grip(1.4, 0.0), HandState::default()]);
        let carried = out.frame.tools.iter().filter(|g| g.colour == super::super::frame::PART_COLOUR).count();
        assert_eq!(carried, 1, "the carried part's box is drawn");
        assert_eq!(
            s.placement(),
            sculpture,
            "one grip of the support hand moves the part, not the sculpture"
        );
        let head = s.doc.playback.assembly().parts()[1].placement;
        let up = head.translation_m - Vec3::new(0.0, 0.08, 0.0);
        assert!((up - Vec3::Y * 0.1 / sculpture.scale).length() < 1e-4, "{up}");
        // Its thumbstick up, held for a second, doubles it.
        for _ in 0..90 {
            frame(&mut s, [grip(1.4, 1.0), HandState::default()]);
        }
        let grown = s.doc.playback.assembly().parts()[1].placement.scale;
        assert!((grown - 2.0).abs() < 0.05, "{grown}");
        frame(&mut s, [HandState::default(), HandState::default()]);
        // The composed surface shows the head where it was carried, the body where it was.
        let head_now = s.doc.playback.assembly().parts()[1].placement.translation_m;
        let _ = s.doc.playback.surface();
        let mut reader = FieldReader::new(s.doc.playback.surface_now());
        assert!(reader.density_world(head_now + Vec3::Y * 0.035) > 0.5, "the head, twice its size");
        assert!(reader.density_world(Vec3::ZERO) > 0.5, "the body stays");
        // The carry, from grip to letting go, is one undo step; redo carries it again.
        let (moved, rest) = (s.doc.playback.assembly().parts()[1].placement, scene.parts[1].placement);
        s.undo();
        assert_eq!(s.doc.playback.assembly().parts()[1].placement, rest, "undo puts the head back");
        let _ = s.doc.playback.surface();
        let mut reader = FieldReader::new(s.doc.playback.surface_now());
        assert!(reader.density_world(Vec3::new(0.0, 0.08, 0.0)) > 0.5, "drawn where it was");
        s.redo();
        assert_eq!(s.doc.playback.assembly().parts()[1].placement, moved);
        s.undo();
        s.undo();
        assert!(s.messages.last().unwrap().contains("nothing to undo"), "{:?}", s.messages);
    }

    #[test]
    fn the_other_hands_menu_button_recentres_the_sculpture_in_front_of_the_head() {
        let scene = ball();
        let mut s = sculptor(&scene, false);
        let grip = |x: f32, y: f32| HandState { grip: at(x, y, -0.4), squeeze: 1.0, ..HandState::default() };
        // Drag and scale the sculpture away.
        frame(&mut s, [grip(-0.1, 1.3), grip(0.1, 1.3)]);
        frame(&mut s, [grip(-0.3, 1.5), grip(0.3, 1.5)]);
        assert!(s.placement().scale > 2.0);
        // Facing +X, the other hand's menu button brings it back in front of the head, at
        // scale 1; holding the button does nothing more.
        let head = Pose {
            position_m: Vec3::new(0.5, 1.7, 0.2),
            rotation: Quat::from_rotation_y(-0.5 * std::f32::consts::PI),
        };
        let menu = HandState { menu: true, ..HandState::default() };
        let step = |s: &mut XrSculptor<'_>, hands| {
            let input = FrameInput {
                index: 0,
                display_time_ns: 0,
                period_s: 1.0 / 90.0,
                focused: true,
                head: Some(head),
                hands,
            };
            s.step(&input, |_| {})
        };
        step(&mut s, [menu, HandState::default()]);
        let centred = s.placement();
        assert_eq!(centred, recentred(scene.rig.target_m, Some(head)));
        assert_eq!(centred.scale, 1.0);
        let target = centred.to_stage(scene.rig.target_m);
        assert!(target.x > head.position_m.x + 0.2, "in front of a head facing +X: {target}");
        assert!((target.z - head.position_m.z).abs() < 1e-5, "{target}");
        // The dominant hand's menu button is not the recentre button.
        frame(&mut s, [grip(-0.1, 1.3), HandState::default()]);
        frame(&mut s, [grip(-0.1, 1.4), HandState::default()]);
        let moved = s.placement();
        step(&mut s, [HandState::default(), menu]);
        assert_eq!(s.placement(), moved);
    }

    #[test]
    fn left_handed_the_left_trigger_sculpts_and_a_touch_pulses_that_hand() {
        let scene = ball();
        let mut s = sculptor(&scene, true);
        let carving = HandState { grip: at(0.0, 1.3, -0.40), trigger: 1.0, ..HandState::default() };
        let out = frame(&mut s, [HandState::default(), carving]);
        assert!(density(&s, Vec3::new(0.0, 0.0, 0.045)) > 0.5, "the right hand does not sculpt");
        assert!(out.haptics.is_empty());
        let out = frame(&mut s, [carving, HandState::default()]);
        assert!(density(&s, Vec3::new(0.0, 0.0, 0.045)) < 0.5, "the left hand does");
        assert_eq!(out.haptics.len(), 1);
        assert_eq!(out.haptics[0].hand, Hand::Left);
        assert_eq!((out.haptics[0].amplitude, out.haptics[0].duration_ns), TOUCH_PULSE);
    }

    /// The ball with a support block the left hand holds (a box of 4 × 2 × 3 cm).
    fn ball_and_block() -> Scene {
        Scene::parse(
            "[field]\nvoxel_size_m = 0.004\n[camera]\neye_m = [0.0, 0.0, 0.5]\ntarget_m = [0.0, 0.0, 0.0]\n\
             [[clay]]\nshape = \"sphere\"\nradius_m = 0.05\n\
             [[tool]]\nname = \"gouge\"\nradius_m = 0.012\naction = \"remove\"\n\
             [[tool]]\nname = \"block\"\nshape = \"box\"\nsize_m = [0.04, 0.02, 0.03]\naction = \"support\"\n",
            "ball-and-block",
            None,
        )
        .unwrap()
    }

    /// A glyph's centre in the room.
    fn room_centre(s: &XrSculptor<'_>, g: &ToolGlyph) -> Vec3 {
        s.placement().to_stage(g.model.w_axis.truncate())
    }

    fn near(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    /// The controllers' handles, and the palette's items `[shape, action, size]` when drawn.
    fn split_controllers(frame: &Frame) -> (Vec<ToolGlyph>, Option<[ToolGlyph; 3]>) {
        use super::super::glyphs::HANDLE_COLOUR;
        let (handles, palette): (Vec<ToolGlyph>, Vec<ToolGlyph>) =
            frame.controllers.iter().copied().partition(|g| g.colour == HANDLE_COLOUR);
        // The palette's items, then its five buttons.
        let items = (palette.len() == 3 + Button::ALL.len()).then(|| [palette[0], palette[1], palette[2]]);
        (handles, items)
    }

    /// The size bar's length, room metres.
    fn bar_length_m(s: &XrSculptor<'_>, bar: &ToolGlyph) -> f32 {
        let (a, b) = (bar.model.transform_point3(-Vec3::Y), bar.model.transform_point3(Vec3::Y));
        s.placement().to_stage(a).distance(s.placement().to_stage(b))
    }

    #[test]
    fn the_headset_draws_the_tool_the_support_each_controller_and_the_palette() {
        use super::super::glyphs::{PALETTE_ABOVE_M, PALETTE_AHEAD_M};
        use crate::render::GlyphShape;
        let scene = ball_and_block();
        let mut s = sculptor(&scene, false);
        let (left, right) = (Vec3::new(-0.1, 1.3, -0.2), Vec3::new(0.1, 1.3, -0.2));
        let hold = |p: Vec3| HandState { grip: at(p.x, p.y, p.z), ..HandState::default() };
        let out = frame(&mut s, [hold(left), hold(right)]);
        let f = &out.frame;
        assert_eq!(f.tools.len(), 2, "the tool and the support");
        let (tool, support) = (f.tools[0], f.tools[1]);
        assert_eq!(tool.shape, GlyphShape::Sphere);
        assert!(near(room_centre(&s, &tool), right), "the tool is in the dominant hand");
        assert!((tool.model.x_axis.truncate().length() - 0.012).abs() < 1e-6, "its size");
        assert_eq!(tool.colour, action_colour(&Action::Remove).extend(0.35), "its action's colour");
        assert_eq!(support.shape, GlyphShape::Box, "the support block is drawn as a box");
        assert!(near(room_centre(&s, &support), left), "in the other hand");
        let half = Vec3::new(
            support.model.x_axis.length(),
            support.model.y_axis.length(),
            support.model.z_axis.length(),
        );
        assert!(near(half, Vec3::new(0.02, 0.01, 0.015)), "{half}");
        assert_eq!(support.colour.truncate(), action_colour(&Action::Support));

        let (handles, palette) = split_controllers(f);
        assert_eq!(handles.len(), 2, "a handle per controller");
        assert!(near(room_centre(&s, &handles[0]), left) && near(room_centre(&s, &handles[1]), right));
        assert!(handles.iter().all(|h| h.shape == GlyphShape::Cylinder));
        let [shape, action, size] = palette.expect("the palette is drawn");
        for g in [&shape, &action] {
            let p = room_centre(&s, g) - left;
            assert!((p.y - PALETTE_ABOVE_M).abs() < 1e-5 && (p.z + PALETTE_AHEAD_M).abs() < 1e-5, "{p}");
        }
        assert!(room_centre(&s, &size).x > room_centre(&s, &action).x, "beside the left hand, in a row");
        assert_eq!(shape.shape, GlyphShape::Sphere);
        assert_eq!(action.colour.truncate(), action_colour(&Action::Remove));
        assert!((bar_length_m(&s, &size) - 0.024).abs() < 1e-5, "the bar spans the tool's 2.4 cm");

        // The trigger makes the tool more opaque; an untracked hand draws nothing.
        let out = frame(&mut s, [HandState::default(), HandState { trigger: 1.0, ..hold(right) }]);
        assert_eq!(out.frame.tools.len(), 1, "no support without the left hand");
        assert_eq!(out.frame.tools[0].colour.w, 0.6);
        let (handles, palette) = split_controllers(&out.frame);
        assert!(handles.len() == 1 && palette.is_none(), "no handle nor palette for the untracked hand");
        let out = frame(&mut s, [hold(left), HandState::default()]);
        assert_eq!(out.frame.tools.len(), 1, "only the support");
        assert_eq!(out.frame.tools[0].shape, GlyphShape::Box);
        let (handles, palette) = split_controllers(&out.frame);
        assert!(handles.len() == 1 && palette.is_some());

        // Glyphs follow the sculpture's placement: scaled twice, the room-sized ones keep
        // their room size, the tool keeps its room size as it acts.
        let grip = |x: f32| HandState { grip: at(x, 1.3, -0.4), squeeze: 1.0, ..HandState::default() };
        frame(&mut s, [grip(-0.1), grip(0.1)]);
        let out = frame(&mut s, [grip(-0.2), grip(0.2)]);
        assert!((s.placement().scale - 2.0).abs() < 1e-4);
        let (handles, _) = split_controllers(&out.frame);
        let end = s.placement().to_stage(handles[1].model.transform_point3(Vec3::Y));
        assert!(
            (end.distance(Vec3::new(0.2, 1.3, -0.4)) - super::super::glyphs::HANDLE_HALF_LENGTH_M).abs()
                < 1e-5
        );
        let tool = out.frame.tools[0];
        let rim = s.placement().to_stage(tool.model.transform_point3(Vec3::X));
        assert!((rim.distance(Vec3::new(0.2, 1.3, -0.4)) - 0.012).abs() < 1e-5, "the tool's room size");
    }

    #[test]
    fn the_palette_follows_the_thumbstick_and_left_handed_it_is_on_the_right_hand() {
        use crate::render::GlyphShape;
        let scene = ball();
        let mut s = sculptor(&scene, false);
        let left = Vec3::new(-0.1, 1.3, -0.2);
        let hold = |stick: Vec2, click: bool| HandState {
            grip: at(0.1, 1.3, -0.2),
            thumbstick: stick,
            thumbstick_click: click,
            ..HandState::default()
        };
        let other = HandState { grip: at(left.x, left.y, left.z), ..HandState::default() };
        let palette = |out: &FrameOutput| split_controllers(&out.frame).1.expect("the palette");
        let first = palette(&frame(&mut s, [other, hold(Vec2::ZERO, false)]));
        let bar = bar_length_m(&s, &first[2]);
        // A flick: the next shape, on the palette and in the hand.
        frame(&mut s, [other, hold(Vec2::X, false)]);
        let out = frame(&mut s, [other, hold(Vec2::ZERO, false)]);
        assert_eq!(palette(&out)[0].shape, GlyphShape::Box);
        assert_eq!(out.frame.tools[0].shape, GlyphShape::Box);
        // Two flicks more: a cylinder, then a torus.
        for expected in [GlyphShape::Cylinder, GlyphShape::Torus { tube: 0.5 }] {
            frame(&mut s, [other, hold(Vec2::X, false)]);
            let out = frame(&mut s, [other, hold(Vec2::ZERO, false)]);
            assert_eq!(palette(&out)[0].shape, expected);
            assert_eq!(out.frame.tools[0].shape, expected);
        }
        // A click: the next action's colour.
        let out = frame(&mut s, [other, hold(Vec2::ZERO, true)]);
        let action = s.tool().action;
        assert_ne!(action, Action::Remove);
        assert_eq!(palette(&out)[1].colour.truncate(), action_colour(&action));
        assert_eq!(out.frame.tools[0].colour.truncate(), action_colour(&action));
        // A second of the stick pushed up doubles the tool, and the bar with it.
        let sized = s.tool().half_extents_m().max_element();
        for _ in 0..90 {
            frame(&mut s, [other, hold(Vec2::Y, false)]);
        }
        let out = frame(&mut s, [other, hold(Vec2::ZERO, false)]);
        let grown = s.tool().half_extents_m().max_element() / sized;
        assert!((grown - RESIZE_PER_S).abs() < 0.05, "{grown}");
        let now = bar_length_m(&s, &palette(&out)[2]);
        assert!((now - 2.0 * s.tool().half_extents_m().max_element()).abs() < 1e-5, "{now}");
        assert!(now > bar, "{now} > {bar}");

        // Left-handed: the palette is beside the right hand.
        let mut s = sculptor(&scene, true);
        let right = Vec3::new(0.1, 1.3, -0.2);
        let out =
            frame(&mut s, [other, HandState { grip: at(right.x, right.y, right.z), ..HandState::default() }]);
        let items = palette(&out);
        let ahead = room_centre(&s, &items[1]) - right;
        assert!(ahead.z < -0.05 && ahead.x.abs() < 1e-5, "in front of the right controller: {ahead}");
        assert!(near(room_centre(&s, &out.frame.tools[0]), left), "the tool is in the left hand");
    }

    #[test]
    fn a_support_holding_the_clay_is_drawn_where_it_was_put() {
        // The headset bend (scenes/tests/xr-bend.toml): scene → room is +(0, 1.32, −0.45).
        let scene = Scene::parse(
            "[field]\nvoxel_size_m = 0.003\n[camera]\neye_m = [0.0, 0.04, 0.32]\ntarget_m = [0.0, -0.02, 0.0]\n\
             [virtual_clay]\nfluidity = 1.0\n\
             [[clay]]\nshape = \"bar\"\nlength_m = 0.2\nradius_m = 0.012\n\
             [[tool]]\nname = \"ball\"\nshape = \"sphere\"\nradius_m = 0.012\naction = \"push\"\n\
             [[tool]]\nname = \"block\"\nshape = \"box\"\nsize_m = [0.08, 0.024, 0.04]\naction = \"support\"\n",
            "bend",
            None,
        )
        .unwrap();
        let mut s = sculptor(&scene, false);
        let put = Vec3::new(-0.056, 1.296, -0.45);
        let support = |p: Vec3| HandState { grip: at(p.x, p.y, p.z), trigger: 1.0, ..HandState::default() };
        let push = HandState { grip: at(0.075, 1.348, -0.45), trigger: 1.0, ..HandState::default() };
        let out = frame(&mut s, [support(put), push]);
        let block =
            *out.frame.tools.iter().find(|g| g.shape == crate::render::GlyphShape::Box).expect("the block");
        assert!(near(room_centre(&s, &block), put));
        assert_eq!(out.frame.tools[0].colour.truncate(), action_colour(&Action::Push), "the ball pushes");
        // The hand moves away with the trigger held: the block stays where it was put, the
        // controller goes with the hand.
        let away = put + Vec3::new(-0.03, 0.0, 0.0);
        let out = frame(&mut s, [support(away), push]);
        let block =
            *out.frame.tools.iter().find(|g| g.shape == crate::render::GlyphShape::Box).expect("the block");
        assert!(near(room_centre(&s, &block), put), "{}", room_centre(&s, &block));
        let (handles, _) = split_controllers(&out.frame);
        assert!(near(room_centre(&s, &handles[0]), away));
        // Let go: the block is in the hand again.
        let out = frame(&mut s, [HandState { trigger: 0.0, ..support(away) }, push]);
        let block =
            *out.frame.tools.iter().find(|g| g.shape == crate::render::GlyphShape::Box).expect("the block");
        assert!(near(room_centre(&s, &block), away));
    }
}
