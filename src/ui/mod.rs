//! The panels' model: what the desk panel shows and the commands it emits, laid out with egui
//! and tessellated into a [`PanelPaint`] that `render` draws in both eyes at zero parallax.
//!
//! The station hands the panel a [`PanelView`] each frame (a plain snapshot: the tool, the
//! history, the view, the file) and the pointer's events in the eye image's pixels; the panel
//! answers with [`PanelCommand`]s, which the station applies as it applies its keys, and with
//! the paint. The panel knows nothing of the field or the devices. Input goes in as egui
//! events built here, from real and scripted pointer events alike, so a scripted session
//! drives the panel exactly as a hand does.

mod files;

use std::path::PathBuf;

use egui::{Color32, Pos2, Rect, Vec2};

pub use files::{FileTask, MOST_ENTRIES};

use crate::render::{PanelBatch, PanelPaint, PanelTexture, PanelVertex, MAX_TEXTURE_SIDE};

/// What the desk panel shows: a plain snapshot the station makes each frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PanelView {
    /// The tool's shapes.
    pub shapes: Vec<&'static str>,
    /// Which of them the tool has (none: a shape not in the list, a scene's freeform one).
    pub shape: Option<usize>,
    /// The tool's actions.
    pub actions: Vec<&'static str>,
    /// Which of them it does.
    pub action: usize,
    /// The tool's size (its smallest extent), millimetres.
    pub size_mm: f32,
    /// The range the size slider spans, millimetres.
    pub size_range_mm: (f32, f32),
    /// The action's rate per second, where it has one (build, soft remove, paint, smooth).
    pub rate_per_s: Option<f32>,
    /// Stamps along a stroke, as a fraction of the tool's size.
    pub spacing: f32,
    /// The colour the tool adds or paints, linear RGB.
    pub colour: [f32; 3],
    /// The level the tool edits: `None`, always the finest; `Some(n)`, the finest on which
    /// its size spans at most `n` voxels.
    pub level_samples: Option<f32>,
    /// The level it edits now (0: the finest) and that level's voxel size, millimetres.
    pub level: (u32, f32),
    /// The sculpt's parts, in composition order, and which one the tools act on.
    pub parts: Vec<PartRow>,
    /// Which of them the tools act on.
    pub active_part: usize,
    /// The symmetry the tools act through, as a phrase, and whether it is on.
    pub symmetry: (String, bool),
    /// The lattices the tools open, and the one open.
    pub lattice: LatticeRow,
    /// The desk's device families, each with the target it drives and what is connected.
    pub devices: Vec<DeviceRow>,
    /// The targets a device family can drive, by name.
    pub targets: Vec<&'static str>,
    /// The head tracker in words (where it listens and whether a head is seen), if one runs.
    pub head_tracker: Option<String>,
    /// The stereo view.
    pub stereo: StereoRow,
    /// The undo history: the steps that can be undone, oldest first.
    pub undo: Vec<String>,
    /// The steps that can be redone, next first.
    pub redo: Vec<String>,
    /// The display modes the window can show.
    pub display_modes: Vec<&'static str>,
    /// Which of them it shows.
    pub display_mode: usize,
    /// Where saving writes.
    pub save_to: String,
    /// The name of that file (shown; the whole path on hover).
    pub save_name: String,
    /// The changes the file lacks.
    pub unsaved: u64,
    /// What becomes of them if another sculpt is opened (kept for recovery, or lost).
    pub unsaved_fate: &'static str,
    /// The sculpt file's extension.
    pub sculpt_extension: &'static str,
    /// The mesh formats the surface exports to, by extension.
    pub export_formats: Vec<&'static str>,
    /// The sculpts saved or opened last, newest first.
    pub recent: Vec<PathBuf>,
    /// The sculpts recovered at start from sessions that did not close, with what each holds;
    /// shown at the top of the panel until dismissed.
    pub recovered: Vec<(PathBuf, String)>,
    /// Status lines (what the heads-up display shows while the panel is hidden) and the
    /// latest messages.
    pub status: Vec<String>,
    /// The panel is the headset's: a first row saves, recentres the sculpture and quits, and
    /// the desk's view and devices sections are left out.
    pub headset: bool,
}

/// A part as the panel lists it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PartRow {
    /// Its name.
    pub name: String,
    /// How it composes with the parts before it (union, difference, intersection).
    pub op: &'static str,
    /// Its finest voxel size, millimetres.
    pub voxel_mm: f32,
    /// Whether it is drawn.
    pub visible: bool,
    /// Whether the tools leave it alone.
    pub locked: bool,
}

/// A device family as the panel lists it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DeviceRow {
    /// The family: "spacemouse", "gamepad", "mouse".
    pub family: &'static str,
    /// The index in [`PanelView::targets`] of the target it drives.
    pub target: usize,
    /// The devices of the family connected now, by name.
    pub connected: Vec<String>,
}

/// The lattice tool as the panel shows it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LatticeRow {
    /// The form the next lattice opens with.
    pub form: crate::lattice::LatticeForm,
    /// The open lattice in words (its form, the picked control's value and weight), if one is.
    pub open: Option<String>,
    /// Whether the open lattice's controls carry weights (NURBS).
    pub weighted: bool,
}

/// The stereo view as the panel shows it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StereoRow {
    /// The convergence plane's distance, metres, and the range it may take.
    pub convergence_m: f32,
    /// The range of the convergence plane, metres.
    pub convergence_range_m: (f32, f32),
    /// The convergence follows the clay by itself (its slider is then disabled).
    pub auto_convergence: bool,
    /// The distance between the eyes in use, millimetres, and the most allowed.
    pub interaxial_mm: f32,
    /// The most the eyes may be apart, millimetres.
    pub max_interaxial_mm: f32,
    /// The nearest and farthest disparity of what is shown, degrees (negative: crossed), the
    /// comfort bound, degrees, and whether the range is over it; `None` with nothing in view.
    pub disparity: Option<Disparity>,
    /// The lights turn with the viewer (else they stay with the scene).
    pub lights_follow_viewer: bool,
    /// Each eye gets the other's image.
    pub swap_eyes: bool,
    /// The pictures' side edges are masked where clay in front of the screen touches them.
    pub floating_window: bool,
    /// Head tracking: `None` off; `Some(true)` tracked; `Some(false)` the tracker is lost.
    pub head: Option<bool>,
}

/// The parallax budget's readout.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Disparity {
    /// The nearest point's disparity, degrees (negative: crossed).
    pub nearest_deg: f32,
    /// The farthest point's, degrees.
    pub farthest_deg: f32,
    /// The comfortable bound either way, degrees.
    pub bound_deg: f32,
    /// The range is over the budget.
    pub exceeded: bool,
}

/// What the panel asks of the station.
#[derive(Clone, Debug, PartialEq)]
pub enum PanelCommand {
    /// The tool takes the shape of this index of [`PanelView::shapes`].
    Shape(usize),
    /// The tool does the action of this index of [`PanelView::actions`].
    Action(usize),
    /// The tool's size, millimetres.
    SizeMm(f32),
    /// The action's rate per second.
    Rate(f32),
    /// The stamp spacing, a fraction of the size.
    Spacing(f32),
    /// The tool's colour, linear RGB.
    Colour([f32; 3]),
    /// The level the tool edits (see [`PanelView::level_samples`]).
    LevelSamples(Option<f32>),
    /// The tool edits the level its size chooses, with the station's default voxels across it.
    LevelBySize,
    /// The tools act on the part of this index of [`PanelView::parts`].
    ActivePart(usize),
    /// Copy the clay within the tool (or the box selected) into a new part, the active one.
    CopyToPart,
    /// Symmetry on or off.
    ToggleSymmetry,
    /// The next symmetry (one plane, two, three, radial).
    NextSymmetry,
    /// The convergence plane's distance, metres.
    ConvergenceM(f32),
    /// The convergence follows the clay, or not.
    AutoConvergence(bool),
    /// The distance between the eyes, millimetres.
    InteraxialMm(f32),
    /// The lights turn with the viewer, or stay with the scene.
    LightsFollowViewer(bool),
    /// Each eye gets the other's image, or its own.
    SwapEyes(bool),
    /// The floating window masks the pictures' edges, or not.
    FloatingWindow(bool),
    /// The viewer's head as it is now is the centred head.
    RecentreHead,
    /// Undo this many steps.
    Undo(usize),
    /// Redo this many steps.
    Redo(usize),
    /// The device family of this index of [`PanelView::devices`] drives the target of this
    /// index of [`PanelView::targets`].
    DeviceTarget(usize, usize),
    /// The lattices opened from now on have this form.
    LatticeForm(crate::lattice::LatticeForm),
    /// Open a lattice around the tool (`false`) or over the active part's clay (`true`).
    OpenLattice(bool),
    /// Apply the open lattice (one undo step).
    ApplyLattice,
    /// Close the open lattice, the clay as it was.
    CancelLattice,
    /// Show the open lattice's next slice.
    NextLatticeSlice,
    /// Raise (`true`) or lower the picked control's value.
    ControlValue(bool),
    /// Make the picked control's weight heavier (`true`) or lighter.
    ControlWeight(bool),
    /// Show the display mode of this index of [`PanelView::display_modes`].
    DisplayMode(usize),
    /// Save the sculpt.
    Save,
    /// Save the sculpt to this file, where saving writes from then on.
    SaveAs(PathBuf),
    /// Open this sculpt.
    Open(PathBuf),
    /// Export the surface to this file (its extension names the format), replacing it.
    Export(PathBuf),
    /// The recovered sculpts need no more showing.
    DismissRecovered,
    /// End the session, saving the sculpt (the headset's panel).
    Quit,
}

/// A key a text field of the panel reads (typed characters come as text, see
/// [`Panel::text`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PanelKey {
    /// Deletes before the cursor.
    Backspace,
    /// Deletes after the cursor.
    Delete,
    /// Confirms the field.
    Enter,
    /// Leaves the field.
    Escape,
    /// The cursor one character left.
    Left,
    /// One right.
    Right,
    /// To the start.
    Home,
    /// To the end.
    End,
}

/// A pointer event on the panel, in the eye image's pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PointerEvent {
    /// The pointer is at this pixel.
    Moved([f32; 2]),
    /// The primary button went down (`true`) or up, where the pointer is.
    Primary(bool),
    /// The wheel turned, lines (positive: away from the user).
    Wheel(f32),
    /// The pointer left the window.
    Left,
}

/// The panel's width, points.
const PANEL_WIDTH_PT: f32 = 256.0;

/// Pixels per point of the headset's panel: its text is drawn twice as finely as a desk
/// monitor's, as the eye comes close to it.
pub const HEADSET_PIXELS_PER_POINT: f32 = 2.0;

/// The size of the headset's panel, pixels: the desk panel's width, and tall enough for the
/// tool and history sections without scrolling (the thumbstick scrolls the rest).
pub const HEADSET_PANEL_PX: (u32, u32) = (512, 832);

/// How far a section's controls sit in from its heading, points.
const SECTION_INDENT_PT: f32 = 6.0;

/// The desk panel: see the module docs.
pub struct Panel {
    ctx: egui::Context,
    shown: bool,
    events: Vec<egui::Event>,
    /// Events held for the frame after next: a release that came in the same frame as its
    /// press (a quick click, a scripted one), so that controls that follow a held button (a
    /// slider) see it down for a frame.
    deferred: Vec<egui::Event>,
    pointer: Option<Pos2>,
    /// The pointer is over the panel (or a popup of it) or held by one of its controls.
    wants_pointer: bool,
    /// One of its controls held the pointer at the end of the last frame run (a drag).
    using_pointer: bool,
    /// The right edge of the panel as last laid out, points.
    right_pt: f32,
    /// The primary button is down (as the pointer events given so far say).
    primary_down: bool,
    wants_keyboard: bool,
    /// The file browser's folder, listing and name field.
    browser: files::Browser,
    /// The pixels per point the textures were made for.
    pixels_per_point: f32,
    /// The pixels per point it is drawn at whatever its image's width (the headset's);
    /// `None`, by the width ([`pixels_per_point`]).
    fixed_pixels_per_point: Option<f32>,
    /// The time of the last frame run, seconds.
    time_s: f64,
}

impl std::fmt::Debug for Panel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Panel").field("shown", &self.shown).finish_non_exhaustive()
    }
}

impl Default for Panel {
    fn default() -> Self {
        Self::new()
    }
}

/// The panel's egui context: dark, with a narrow indent under the sections' headings (it keeps
/// the sliders' names whole).
fn context() -> egui::Context {
    let ctx = egui::Context::default();
    ctx.set_theme(egui::Theme::Dark);
    ctx.style_mut(|style| style.spacing.indent = SECTION_INDENT_PT);
    ctx
}

/// Pixels per point for an image `width` pixels wide: 1 below 1280 pixels, then in steps of a
/// half up to 3, so the panel keeps about the same share of a wide window.
pub fn pixels_per_point(width: u32) -> f32 {
    ((width as f32 / 1280.0 * 2.0).floor() / 2.0).clamp(1.0, 3.0)
}

impl Panel {
    /// A panel, shown.
    pub fn new() -> Self {
        Self {
            ctx: context(),
            shown: true,
            events: Vec::new(),
            deferred: Vec::new(),
            pointer: None,
            wants_pointer: false,
            using_pointer: false,
            right_pt: PANEL_WIDTH_PT,
            primary_down: false,
            wants_keyboard: false,
            browser: files::Browser::default(),
            pixels_per_point: 1.0,
            fixed_pixels_per_point: None,
            time_s: 0.0,
        }
    }

    /// The headset's panel, shown: drawn at [`HEADSET_PIXELS_PER_POINT`] into an image of
    /// [`HEADSET_PANEL_PX`], which it fills.
    pub fn headset() -> Self {
        let mut panel = Self::new();
        panel.fixed_pixels_per_point = Some(HEADSET_PIXELS_PER_POINT);
        panel.pixels_per_point = HEADSET_PIXELS_PER_POINT;
        panel
    }

    /// Paints every texture anew from the next frame (for a renderer that holds none of
    /// them: one made again after its device was lost). What the panel shows stays.
    pub fn renew_textures(&mut self) {
        self.ctx = context();
    }

    /// A panel, hidden.
    pub fn hidden() -> Self {
        let mut panel = Self::new();
        panel.set_shown(false);
        panel
    }

    /// Whether the panel is shown.
    pub fn shown(&self) -> bool {
        self.shown
    }

    /// Shows or hides the panel.
    pub fn set_shown(&mut self, shown: bool) {
        self.shown = shown;
        if !shown {
            self.wants_pointer = false;
            self.wants_keyboard = false;
        }
    }

    /// Whether the pointer's events are the panel's (it is over the panel or dragging one of
    /// its controls): then they do not turn the view or place the tool.
    pub fn wants_pointer(&self) -> bool {
        self.shown && self.wants_pointer
    }

    /// Whether a text field of the panel has the keyboard.
    pub fn wants_keyboard(&self) -> bool {
        self.shown && self.wants_keyboard
    }

    /// What the file browser is open for, if it is.
    pub fn file_task(&self) -> Option<FileTask> {
        self.browser.task()
    }

    /// Takes typed text for the next frame: it goes to the text field with the keyboard.
    /// Control characters are left out (their keys come through [`Panel::key`]).
    pub fn text(&mut self, text: &str) {
        let text: String = text.chars().filter(|c| !c.is_control()).collect();
        if !text.is_empty() {
            self.push(egui::Event::Text(text));
        }
    }

    /// Takes a key for the next frame, for the text field with the keyboard.
    pub fn key(&mut self, key: PanelKey, pressed: bool) {
        let key = match key {
            PanelKey::Backspace => egui::Key::Backspace,
            PanelKey::Delete => egui::Key::Delete,
            PanelKey::Enter => egui::Key::Enter,
            PanelKey::Escape => egui::Key::Escape,
            PanelKey::Left => egui::Key::ArrowLeft,
            PanelKey::Right => egui::Key::ArrowRight,
            PanelKey::Home => egui::Key::Home,
            PanelKey::End => egui::Key::End,
        };
        self.push(egui::Event::Key {
            key,
            physical_key: None,
            pressed,
            repeat: false,
            modifiers: egui::Modifiers::NONE,
        });
    }

    /// Takes a pointer event for the next frame.
    pub fn pointer(&mut self, event: PointerEvent) {
        let ppp = self.pixels_per_point;
        match event {
            PointerEvent::Moved([x, y]) => {
                let at = Pos2::new(x / ppp, y / ppp);
                self.pointer = Some(at);
                self.push(egui::Event::PointerMoved(at));
                // Over the panel (as it was last laid out) or one of its popups, or dragging
                // one of its controls (egui still calls a drag released since the last frame
                // in use: it is not).
                let popup = self.ctx.layer_id_at(at).is_some_and(|l| l.order != egui::Order::Background);
                let dragging = self.using_pointer && self.primary_down;
                self.wants_pointer = self.shown && (dragging || at.x <= self.right_pt || popup);
            }
            PointerEvent::Primary(pressed) => {
                self.primary_down = pressed;
                if let Some(pos) = self.pointer {
                    let event = egui::Event::PointerButton {
                        pos,
                        button: egui::PointerButton::Primary,
                        pressed,
                        modifiers: egui::Modifiers::NONE,
                    };
                    let pressed_now = self
                        .events
                        .iter()
                        .any(|e| matches!(e, egui::Event::PointerButton { pressed: true, .. }));
                    match !pressed && pressed_now {
                        true => self.deferred.push(event),
                        false => self.push(event),
                    }
                }
            }
            PointerEvent::Wheel(lines) => self.push(egui::Event::MouseWheel {
                unit: egui::MouseWheelUnit::Line,
                delta: Vec2::new(0.0, lines),
                modifiers: egui::Modifiers::NONE,
            }),
            PointerEvent::Left => {
                self.pointer = None;
                self.push(egui::Event::PointerGone);
            }
        }
    }

    /// Queues `event` for the next frame, or after the events deferred to the frame after.
    fn push(&mut self, event: egui::Event) {
        match self.deferred.is_empty() {
            true => self.events.push(event),
            false => self.deferred.push(event),
        }
    }

    /// Runs one frame of the panel over `view` in an eye image of `extent_px` at `time_s`:
    /// returns the commands its controls gave and what to paint (`None` while hidden).
    pub fn run(
        &mut self,
        view: &PanelView,
        extent_px: (u32, u32),
        time_s: f64,
    ) -> (Vec<PanelCommand>, Option<PanelPaint>) {
        let events = std::mem::replace(&mut self.events, std::mem::take(&mut self.deferred));
        if !self.shown || extent_px.0 == 0 || extent_px.1 == 0 {
            return (Vec::new(), None);
        }
        let ppp = self.fixed_pixels_per_point.unwrap_or_else(|| pixels_per_point(extent_px.0));
        self.pixels_per_point = ppp;
        // egui's time never goes back (a clock that does, or NaN, holds it where it was).
        let time_s = if time_s >= self.time_s { time_s } else { self.time_s };
        self.time_s = time_s;
        let size = Vec2::new(extent_px.0 as f32 / ppp, extent_px.1 as f32 / ppp);
        let mut input = egui::RawInput {
            screen_rect: Some(Rect::from_min_size(Pos2::ZERO, size)),
            max_texture_side: Some(MAX_TEXTURE_SIDE as usize),
            time: Some(time_s),
            events,
            focused: true,
            ..Default::default()
        };
        input.viewports.entry(egui::ViewportId::ROOT).or_default().native_pixels_per_point = Some(ppp);
        let mut commands = Vec::new();
        let mut right_pt = PANEL_WIDTH_PT;
        let browser = &mut self.browser;
        let output = self.ctx.run(input, |ctx| right_pt = panel_ui(ctx, view, browser, &mut commands));
        self.right_pt = right_pt;
        self.using_pointer = self.ctx.is_using_pointer();
        self.wants_pointer = self.ctx.is_pointer_over_area() || self.using_pointer;
        self.wants_keyboard = self.ctx.wants_keyboard_input();
        let primitives = self.ctx.tessellate(output.shapes, output.pixels_per_point);
        let paint = paint_of(&primitives, &output.textures_delta, output.pixels_per_point, extent_px);
        (commands, Some(paint))
    }
}

/// The panel's contents; returns its right edge, points.
fn panel_ui(
    ctx: &egui::Context,
    view: &PanelView,
    browser: &mut files::Browser,
    commands: &mut Vec<PanelCommand>,
) -> f32 {
    let panel = egui::SidePanel::left("argile-panel").exact_width(PANEL_WIDTH_PT).resizable(false);
    let shown = panel.show(ctx, |ui| {
        // Scrolled by the wheel alone: a press on the panel is a press on one of its controls.
        let sources =
            egui::scroll_area::ScrollSource::SCROLL_BAR | egui::scroll_area::ScrollSource::MOUSE_WHEEL;
        egui::ScrollArea::vertical().scroll_source(sources).show(ui, |ui| {
            if view.headset {
                headset_ui(ui, view, commands);
            }
            if !view.recovered.is_empty() {
                recovered_ui(ui, view, commands);
            }
            section(ui, "Tool", |ui| tool_ui(ui, view, commands));
            section(ui, "Parts", |ui| parts_ui(ui, view, commands));
            section(ui, "History", |ui| history_ui(ui, view, commands));
            if !view.headset {
                section(ui, "View", |ui| {
                    ui.horizontal_wrapped(|ui| {
                        for (i, name) in view.display_modes.iter().enumerate() {
                            if ui.radio(view.display_mode == i, *name).clicked() && view.display_mode != i {
                                commands.push(PanelCommand::DisplayMode(i));
                            }
                        }
                    });
                    stereo_ui(ui, &view.stereo, commands);
                });
            }
            section(ui, "File", |ui| browser.ui(ui, view, commands));
            section(ui, "Lattice", |ui| lattice_ui(ui, &view.lattice, commands));
            if !view.headset {
                section(ui, "Devices", |ui| devices_ui(ui, view, commands));
            }
            if !view.status.is_empty() {
                ui.separator();
                for line in &view.status {
                    ui.label(egui::RichText::new(line).small());
                }
            }
        });
    });
    shown.response.rect.max.x
}

/// The level the tool edits: always the finest, or by its size.
fn level_ui(ui: &mut egui::Ui, view: &PanelView, commands: &mut Vec<PanelCommand>) {
    let (level, voxel_mm) = view.level;
    let mut finest = view.level_samples.is_none();
    let said = format!("finest level only (edits level {level}, {voxel_mm:.1} mm voxels)");
    if ui.checkbox(&mut finest, said).changed() {
        commands.push(if finest { PanelCommand::LevelSamples(None) } else { PanelCommand::LevelBySize });
    }
    if let Some(samples) = view.level_samples {
        let mut samples = samples;
        let slider = egui::Slider::new(&mut samples, 2.0..=256.0).logarithmic(true).text("voxels across");
        if ui
            .add(slider)
            .on_hover_text("the tool edits the finest level it spans at most this many voxels of")
            .changed()
        {
            commands.push(PanelCommand::LevelSamples(Some(samples)));
        }
    }
}

/// The headset's first row: save, bring the sculpture in front of the head, save and quit.
fn headset_ui(ui: &mut egui::Ui, view: &PanelView, commands: &mut Vec<PanelCommand>) {
    ui.horizontal(|ui| {
        let save = match view.unsaved {
            0 => "Save".to_owned(),
            n => format!("Save ({n})"),
        };
        for (label, command, hint) in [
            (save.as_str(), PanelCommand::Save, view.save_to.as_str()),
            ("Recentre", PanelCommand::RecentreHead, "the sculpture in front of the head"),
            ("Quit", PanelCommand::Quit, "save the sculpt and end the session"),
        ] {
            if ui.button(label).on_hover_text(hint).clicked() {
                commands.push(command);
            }
        }
    });
    ui.separator();
}

/// The sculpts recovered at start, each opened by a click, until dismissed.
fn recovered_ui(ui: &mut egui::Ui, view: &PanelView, commands: &mut Vec<PanelCommand>) {
    ui.group(|ui| {
        let said = "Recovered at start, from sessions that did not close:";
        ui.label(egui::RichText::new(said).color(Color32::from_rgb(240, 190, 90)));
        for (path, what) in &view.recovered {
            let name =
                path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into());
            ui.horizontal_wrapped(|ui| {
                if ui.button("open").on_hover_text(path.display().to_string()).clicked() {
                    commands.push(PanelCommand::Open(path.clone()));
                }
                ui.label(egui::RichText::new(format!("{name}: {what}")).small());
            });
        }
        if ui.button("dismiss").clicked() {
            commands.push(PanelCommand::DismissRecovered);
        }
    });
}

/// The desk's devices: each family's target, changeable, and what of it is connected; the head
/// tracker.
fn devices_ui(ui: &mut egui::Ui, view: &PanelView, commands: &mut Vec<PanelCommand>) {
    for (i, row) in view.devices.iter().enumerate() {
        ui.horizontal_wrapped(|ui| {
            ui.label(egui::RichText::new(row.family).strong());
            for (t, name) in view.targets.iter().enumerate() {
                let shown = name.replace('_', " ");
                if ui.selectable_label(t == row.target, shown).clicked() && t != row.target {
                    commands.push(PanelCommand::DeviceTarget(i, t));
                }
            }
        });
        let connected = match row.connected.is_empty() {
            true => "none connected".to_owned(),
            false => row.connected.join(", "),
        };
        ui.label(egui::RichText::new(connected).small());
    }
    let head = view.head_tracker.as_deref().unwrap_or("head tracker: none (--opentrack ADDRESS starts one)");
    ui.label(egui::RichText::new(head).small());
}

/// The lattice tool: the form the next one opens with, and the open one's keys as buttons.
fn lattice_ui(ui: &mut egui::Ui, row: &LatticeRow, commands: &mut Vec<PanelCommand>) {
    use crate::spline::{KnotStyle, SplineKind};
    if let Some(open) = &row.open {
        ui.label(egui::RichText::new(open).small());
        ui.horizontal_wrapped(|ui| {
            for (label, command) in [
                ("value +", PanelCommand::ControlValue(true)),
                ("value −", PanelCommand::ControlValue(false)),
                ("next slice", PanelCommand::NextLatticeSlice),
            ] {
                if ui.button(label).clicked() {
                    commands.push(command);
                }
            }
        });
        if row.weighted {
            ui.horizontal(|ui| {
                for (label, heavier) in [("weight +", true), ("weight −", false)] {
                    if ui.button(label).clicked() {
                        commands.push(PanelCommand::ControlWeight(heavier));
                    }
                }
            });
        }
        ui.horizontal(|ui| {
            if ui.button("apply").on_hover_text("one undo step").clicked() {
                commands.push(PanelCommand::ApplyLattice);
            }
            if ui.button("put the clay back").clicked() {
                commands.push(PanelCommand::CancelLattice);
            }
        });
        return;
    }
    let mut form = row.form;
    ui.horizontal(|ui| {
        for (kind, name) in
            [(SplineKind::Bezier, "Bézier"), (SplineKind::BSpline, "B-spline"), (SplineKind::Nurbs, "NURBS")]
        {
            ui.radio_value(&mut form.kind, kind, name);
        }
    });
    for (axis, name) in ["X", "Y", "Z"].iter().enumerate() {
        ui.add(egui::Slider::new(&mut form.counts[axis], 2..=16).text(format!("controls, {name}")));
    }
    ui.add_enabled_ui(form.kind != SplineKind::Bezier, |ui| {
        ui.add(egui::Slider::new(&mut form.order, 2..=16).text("order"))
            .on_hover_text("degree + 1 (4: cubic); on an axis of fewer controls, their count");
        ui.horizontal(|ui| {
            ui.radio_value(&mut form.knots, KnotStyle::Clamped, "clamped knots")
                .on_hover_text("the box's faces stay where they are: no seam with the clay outside");
            ui.radio_value(&mut form.knots, KnotStyle::Uniform, "uniform knots");
        });
    });
    if form != row.form {
        commands.push(PanelCommand::LatticeForm(form));
    }
    ui.horizontal(|ui| {
        ui.label("open");
        if ui.button("around the tool").on_hover_text("F: a box twice the tool's size").clicked() {
            commands.push(PanelCommand::OpenLattice(false));
        }
        if ui.button("over the part").on_hover_text("Shift+F: the active part's clay").clicked() {
            commands.push(PanelCommand::OpenLattice(true));
        }
    });
}

/// A section of the panel under a heading that folds it away; open at first.
fn section(ui: &mut egui::Ui, title: &str, body: impl FnOnce(&mut egui::Ui)) {
    egui::CollapsingHeader::new(egui::RichText::new(title).heading()).default_open(true).show(ui, body);
}

/// The tool: shape, action, size, strength, spacing, colour and the level it edits.
fn tool_ui(ui: &mut egui::Ui, view: &PanelView, commands: &mut Vec<PanelCommand>) {
    ui.horizontal_wrapped(|ui| {
        for (i, name) in view.shapes.iter().enumerate() {
            if ui.selectable_label(view.shape == Some(i), *name).clicked() && view.shape != Some(i) {
                commands.push(PanelCommand::Shape(i));
            }
        }
    });
    ui.horizontal_wrapped(|ui| {
        for (i, name) in view.actions.iter().enumerate() {
            if ui.selectable_label(view.action == i, *name).clicked() && view.action != i {
                commands.push(PanelCommand::Action(i));
            }
        }
    });
    let mut size = view.size_mm;
    let (lo, hi) = view.size_range_mm;
    let slider = egui::Slider::new(&mut size, lo..=hi).logarithmic(true).text("size mm");
    if ui.add(slider).changed() {
        commands.push(PanelCommand::SizeMm(size));
    }
    if let Some(rate) = view.rate_per_s {
        let mut rate = rate;
        let slider = egui::Slider::new(&mut rate, 0.1..=50.0).logarithmic(true).text("strength /s");
        if ui.add(slider).changed() {
            commands.push(PanelCommand::Rate(rate));
        }
    }
    let mut spacing = view.spacing;
    if ui.add(egui::Slider::new(&mut spacing, 0.05..=1.0).text("spacing")).changed() {
        commands.push(PanelCommand::Spacing(spacing));
    }
    ui.horizontal(|ui| {
        let mut rgb = view.colour;
        if ui.color_edit_button_rgb(&mut rgb).changed() {
            commands.push(PanelCommand::Colour(rgb));
        }
        ui.label("colour");
    });
    ui.horizontal_wrapped(|ui| {
        for (name, rgb) in SWATCHES {
            let colour = egui::Rgba::from_rgb(rgb[0], rgb[1], rgb[2]);
            let swatch = egui::Button::new("").fill(Color32::from(colour)).min_size(Vec2::splat(18.0));
            if ui.add(swatch).on_hover_text(name).clicked() {
                commands.push(PanelCommand::Colour(rgb));
            }
        }
    });
    level_ui(ui, view, commands);
}

/// The history: undo and redo, and every step kept, a click going back (or on) to it.
fn history_ui(ui: &mut egui::Ui, view: &PanelView, commands: &mut Vec<PanelCommand>) {
    ui.horizontal(|ui| {
        if ui.add_enabled(!view.undo.is_empty(), egui::Button::new("Undo")).clicked() {
            commands.push(PanelCommand::Undo(1));
        }
        if ui.add_enabled(!view.redo.is_empty(), egui::Button::new("Redo")).clicked() {
            commands.push(PanelCommand::Redo(1));
        }
    });
    let n = view.undo.len();
    if ui.selectable_label(n == 0, "the start").clicked() && n > 0 {
        commands.push(PanelCommand::Undo(n));
    }
    for (i, step) in view.undo.iter().enumerate() {
        if ui.selectable_label(i + 1 == n, step).clicked() && i + 1 < n {
            commands.push(PanelCommand::Undo(n - 1 - i));
        }
    }
    for (i, step) in view.redo.iter().enumerate() {
        let text = egui::RichText::new(step).weak();
        if ui.selectable_label(false, text).clicked() {
            commands.push(PanelCommand::Redo(i + 1));
        }
    }
}

/// The parts (click one for the tools to act on) and the symmetry.
fn parts_ui(ui: &mut egui::Ui, view: &PanelView, commands: &mut Vec<PanelCommand>) {
    for (i, part) in view.parts.iter().enumerate() {
        let mut text = format!("{} {} · {} · {:.1} mm", i + 1, part.name, part.op, part.voxel_mm);
        if !part.visible {
            text.push_str(" · hidden");
        }
        if part.locked {
            text.push_str(" · locked");
        }
        if ui.selectable_label(view.active_part == i, text).clicked() && view.active_part != i {
            commands.push(PanelCommand::ActivePart(i));
        }
    }
    let copy = ui.button("copy to new part");
    if copy
        .on_hover_text("the clay within the tool (or the box selected) becomes a part of its own")
        .clicked()
    {
        commands.push(PanelCommand::CopyToPart);
    }
    ui.horizontal(|ui| {
        let (said, on) = &view.symmetry;
        let mut on = *on;
        if ui.checkbox(&mut on, "symmetry").changed() {
            commands.push(PanelCommand::ToggleSymmetry);
        }
        if ui.button("next").on_hover_text("one plane, two, three, radial").clicked() {
            commands.push(PanelCommand::NextSymmetry);
        }
        ui.label(egui::RichText::new(said).small());
    });
}

/// Convergence and interaxial, the parallax budget's readout, lights, eyes, head tracking.
fn stereo_ui(ui: &mut egui::Ui, stereo: &StereoRow, commands: &mut Vec<PanelCommand>) {
    let (lo, hi) = stereo.convergence_range_m;
    let mut convergence = stereo.convergence_m;
    let slider = egui::Slider::new(&mut convergence, lo..=hi.max(lo)).logarithmic(true).text("converge m");
    if ui.add_enabled(!stereo.auto_convergence, slider).changed() {
        commands.push(PanelCommand::ConvergenceM(convergence));
    }
    let mut auto = stereo.auto_convergence;
    if ui.checkbox(&mut auto, "convergence follows the clay").changed() {
        commands.push(PanelCommand::AutoConvergence(auto));
    }
    let mut interaxial = stereo.interaxial_mm;
    let slider = egui::Slider::new(&mut interaxial, 0.0..=stereo.max_interaxial_mm).text("eyes apart mm");
    if ui.add(slider).changed() {
        commands.push(PanelCommand::InteraxialMm(interaxial));
    }
    match stereo.disparity {
        Some(d) => disparity_ui(ui, d),
        None => {
            ui.label(egui::RichText::new("disparity: nothing in view").small());
        }
    }
    let mut lights = stereo.lights_follow_viewer;
    if ui.checkbox(&mut lights, "lights turn with the viewer").changed() {
        commands.push(PanelCommand::LightsFollowViewer(lights));
    }
    let mut swap = stereo.swap_eyes;
    if ui.checkbox(&mut swap, "swap eyes").changed() {
        commands.push(PanelCommand::SwapEyes(swap));
    }
    let mut floating = stereo.floating_window;
    if ui
        .checkbox(&mut floating, "floating window")
        .on_hover_text("mask the side edges where clay in front of the screen touches them")
        .changed()
    {
        commands.push(PanelCommand::FloatingWindow(floating));
    }
    ui.horizontal(|ui| {
        let said = match stereo.head {
            None => "head tracking off",
            Some(true) => "head tracked",
            Some(false) => "head lost",
        };
        ui.label(said);
        if stereo.head.is_some() && ui.button("recentre").clicked() {
            commands.push(PanelCommand::RecentreHead);
        }
    });
}

/// The disparity range as numbers and as a bar against the comfort bounds (the bar spans
/// twice the bound either way; the bounds are the two white ticks).
fn disparity_ui(ui: &mut egui::Ui, d: Disparity) {
    let colour = if d.exceeded { Color32::from_rgb(240, 90, 70) } else { Color32::from_rgb(120, 200, 120) };
    let text =
        format!("disparity {:+.2}° to {:+.2}° (comfort ±{:.2}°)", d.nearest_deg, d.farthest_deg, d.bound_deg);
    ui.label(egui::RichText::new(text).small().color(colour));
    let (rect, _) = ui.allocate_exact_size(Vec2::new(ui.available_width(), 10.0), egui::Sense::hover());
    let span = 2.0 * d.bound_deg.max(1e-3);
    let x = |deg: f32| rect.center().x + (deg / span).clamp(-1.0, 1.0) * rect.width() * 0.5;
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
    let bar = Rect::from_x_y_ranges(
        x(d.nearest_deg)..=x(d.farthest_deg).max(x(d.nearest_deg) + 1.0),
        rect.y_range(),
    );
    painter.rect_filled(bar.shrink2(Vec2::new(0.0, 2.0)), 1.0, colour);
    for bound in [-d.bound_deg, d.bound_deg] {
        painter.vline(x(bound), rect.y_range(), egui::Stroke::new(1.5, Color32::WHITE));
    }
}

/// Colours one click away, linear RGB: the clay's own and a few a sculptor paints with.
const SWATCHES: [(&str, [f32; 3]); 6] = [
    ("clay", [0.8, 0.5, 0.35]),
    ("bone", [0.85, 0.8, 0.7]),
    ("brick", [0.6, 0.12, 0.06]),
    ("moss", [0.2, 0.35, 0.08]),
    ("slate", [0.1, 0.15, 0.25]),
    ("ink", [0.02, 0.02, 0.03]),
];

/// egui's tessellated meshes and texture updates as the renderer's plain paint.
fn paint_of(
    primitives: &[egui::ClippedPrimitive],
    textures: &egui::TexturesDelta,
    pixels_per_point: f32,
    extent_px: (u32, u32),
) -> PanelPaint {
    let mut paint = PanelPaint { extent_px, ..PanelPaint::default() };
    for (id, delta) in &textures.set {
        let egui::ImageData::Color(image) = &delta.image;
        let srgba: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
        paint.textures.push(PanelTexture {
            id: texture_key(*id),
            offset_px: delta.pos.map(|[x, y]| [x as u32, y as u32]),
            size_px: [image.size[0] as u32, image.size[1] as u32],
            srgba,
        });
    }
    paint.freed = textures.free.iter().map(|id| texture_key(*id)).collect();
    let (w, h) = (extent_px.0 as f32, extent_px.1 as f32);
    for clipped in primitives {
        let egui::epaint::Primitive::Mesh(mesh) = &clipped.primitive else { continue };
        if mesh.indices.is_empty() {
            continue;
        }
        let clip = clipped.clip_rect;
        let px = |v: f32, max: f32| (v * pixels_per_point).round().clamp(0.0, max) as u32;
        let clip_px = [px(clip.min.x, w), px(clip.min.y, h), px(clip.max.x, w), px(clip.max.y, h)];
        let base = paint.vertices.len() as u32;
        paint.vertices.extend(mesh.vertices.iter().map(|v| {
            let c = egui::Rgba::from(v.color);
            PanelVertex {
                position_px: [v.pos.x * pixels_per_point, v.pos.y * pixels_per_point],
                uv: [v.uv.x, v.uv.y],
                colour: [c.r(), c.g(), c.b(), c.a()],
            }
        }));
        let first_index = paint.indices.len() as u32;
        paint.indices.extend(mesh.indices.iter().map(|i| i + base));
        paint.batches.push(PanelBatch {
            clip_px,
            first_index,
            index_count: mesh.indices.len() as u32,
            texture: texture_key(mesh.texture_id),
        });
    }
    paint
}

/// One number for egui's texture ids: managed ones even, user ones odd.
fn texture_key(id: egui::TextureId) -> u64 {
    match id {
        egui::TextureId::Managed(n) => n << 1,
        egui::TextureId::User(n) => (n << 1) | 1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> PanelView {
        PanelView {
            headset: false,
            shapes: vec!["sphere", "box"],
            shape: Some(0),
            actions: vec!["add", "remove", "paint"],
            action: 0,
            size_mm: 20.0,
            size_range_mm: (1.0, 200.0),
            rate_per_s: None,
            spacing: 0.25,
            colour: [0.8, 0.5, 0.35],
            undo: vec!["add sphere 20 mm".into(), "remove sphere 20 mm".into()],
            redo: vec!["paint box 10 mm".into()],
            display_modes: vec!["mono", "anaglyph"],
            display_mode: 1,
            save_to: "sculpts/bust.argile".into(),
            save_name: "bust.argile".into(),
            unsaved: 2,
            unsaved_fate: "they are kept for recovery at the next start",
            sculpt_extension: "argile",
            export_formats: vec!["obj", "ply", "stl", "glb"],
            recent: Vec::new(),
            recovered: Vec::new(),
            status: vec!["tool 1: sphere 20 mm, add".into()],
            level_samples: Some(32.0),
            level: (1, 4.0),
            parts: vec![
                PartRow { name: "body".into(), op: "union", voxel_mm: 2.0, visible: true, locked: false },
                PartRow { name: "hole".into(), op: "difference", voxel_mm: 1.0, visible: true, locked: true },
            ],
            active_part: 0,
            symmetry: ("off".into(), false),
            lattice: LatticeRow::default(),
            devices: vec![
                DeviceRow { family: "spacemouse", target: 0, connected: vec!["SpaceMouse Compact".into()] },
                DeviceRow { family: "mouse", target: 1, connected: Vec::new() },
            ],
            targets: vec!["tool", "scene", "light"],
            head_tracker: None,
            stereo: StereoRow {
                convergence_m: 0.6,
                convergence_range_m: (0.1, 5.0),
                auto_convergence: false,
                interaxial_mm: 63.0,
                max_interaxial_mm: 250.0,
                disparity: Some(Disparity {
                    nearest_deg: -0.4,
                    farthest_deg: 1.3,
                    bound_deg: 1.0,
                    exceeded: true,
                }),
                lights_follow_viewer: false,
                swap_eyes: false,
                floating_window: false,
                head: Some(true),
            },
        }
    }

    /// The height of the test's eye image, pixels: the whole panel fits.
    const TALL: u32 = 1500;

    /// Runs frames until the panel has laid out, then clicks at `at` (points = pixels here).
    fn click(panel: &mut Panel, view: &PanelView, at: [f32; 2]) -> Vec<PanelCommand> {
        click_in(panel, view, (800, TALL), at)
    }

    /// [`click`] on a panel laid out in an image of `extent` pixels, at the pixel `at`.
    fn click_in(panel: &mut Panel, view: &PanelView, extent: (u32, u32), at: [f32; 2]) -> Vec<PanelCommand> {
        let mut t = 0.0;
        let mut frame = |panel: &mut Panel| {
            t += 1.0 / 60.0;
            panel.run(view, extent, t).0
        };
        frame(panel);
        panel.pointer(PointerEvent::Moved(at));
        frame(panel);
        panel.pointer(PointerEvent::Primary(true));
        let mut commands = frame(panel);
        panel.pointer(PointerEvent::Primary(false));
        commands.extend(frame(panel));
        commands
    }

    /// Every command a click down the panel's band gives, once each, with where it was.
    fn sweep(view: &PanelView) -> Vec<(PanelCommand, [f32; 2])> {
        let mut found: Vec<(PanelCommand, [f32; 2])> = Vec::new();
        for y in (4..TALL).step_by(4) {
            for x in [20.0, 60.0, 100.0, 140.0, 180.0] {
                for command in click(&mut Panel::new(), view, [x, y as f32]) {
                    if !found.iter().any(|(c, _)| *c == command) {
                        found.push((command, [x, y as f32]));
                    }
                }
            }
        }
        found
    }

    /// Where a click gives `wanted`, in a sweep.
    fn find(swept: &[(PanelCommand, [f32; 2])], wanted: &PanelCommand) -> Option<[f32; 2]> {
        swept.iter().find(|(c, _)| c == wanted).map(|(_, at)| *at)
    }

    #[test]
    fn the_headset_panel_fills_its_image_saves_recentres_and_quits_from_its_first_row_without_the_desks_sections(
    ) {
        let view = PanelView { headset: true, ..view() };
        let (_, paint) = Panel::headset().run(&view, HEADSET_PANEL_PX, 0.0);
        let paint = paint.expect("shown");
        assert_eq!(paint.extent_px, HEADSET_PANEL_PX);
        let right = paint.vertices.iter().map(|v| v.position_px[0]).fold(0.0, f32::max);
        assert!((right - HEADSET_PANEL_PX.0 as f32).abs() <= 1.0, "the panel spans its image: {right}");
        let mut found: Vec<(PanelCommand, [f32; 2])> = Vec::new();
        for y in (4..HEADSET_PANEL_PX.1).step_by(8) {
            for x in (24..HEADSET_PANEL_PX.0).step_by(80) {
                let at = [x as f32, y as f32];
                for command in click_in(&mut Panel::headset(), &view, HEADSET_PANEL_PX, at) {
                    if !found.iter().any(|(c, _)| *c == command) {
                        found.push((command, at));
                    }
                }
            }
        }
        for wanted in [PanelCommand::Save, PanelCommand::RecentreHead, PanelCommand::Quit] {
            let at = find(&found, &wanted).unwrap_or_else(|| panic!("{wanted:?} in {found:?}"));
            assert!(at[1] < 64.0, "{wanted:?} is on the first row: {at:?}");
        }
        let at = |c: &PanelCommand| find(&found, c).unwrap()[0];
        assert!(at(&PanelCommand::Save) < at(&PanelCommand::RecentreHead));
        assert!(at(&PanelCommand::RecentreHead) < at(&PanelCommand::Quit));
        // The tool, the history and the parts are there; the desk's view and devices are not.
        for wanted in [
            PanelCommand::Shape(1),
            PanelCommand::Action(2),
            PanelCommand::Undo(2),
            PanelCommand::ActivePart(1),
        ] {
            assert!(find(&found, &wanted).is_some(), "{wanted:?} in {found:?}");
        }
        assert!(
            !found.iter().any(|(c, _)| matches!(
                c,
                PanelCommand::DisplayMode(_) | PanelCommand::DeviceTarget(..) | PanelCommand::SwapEyes(_)
            )),
            "{found:?}"
        );
    }

    #[test]
    fn clicks_on_the_panel_give_its_commands_and_the_panel_holds_the_pointer() {
        let view = view();
        let swept = sweep(&view);
        // The history: "the start" undoes both steps; the redo entry redoes one.
        assert!(find(&swept, &PanelCommand::Undo(2)).is_some(), "the start of the history");
        assert!(find(&swept, &PanelCommand::Redo(1)).is_some(), "a redo entry");
        assert!(find(&swept, &PanelCommand::Shape(1)).is_some(), "the box shape");
        assert!(find(&swept, &PanelCommand::Action(2)).is_some(), "the paint action");
        assert!(find(&swept, &PanelCommand::DisplayMode(0)).is_some(), "mono");
        assert!(find(&swept, &PanelCommand::ActivePart(1)).is_some(), "the second part");
        assert!(find(&swept, &PanelCommand::ToggleSymmetry).is_some(), "the symmetry box");
        assert!(find(&swept, &PanelCommand::LevelSamples(None)).is_some(), "the finest level box");
        assert!(find(&swept, &PanelCommand::SwapEyes(true)).is_some(), "the swap eyes box");
        assert!(find(&swept, &PanelCommand::FloatingWindow(true)).is_some(), "the floating window box");
        assert!(find(&swept, &PanelCommand::AutoConvergence(true)).is_some(), "auto-convergence");
        assert!(find(&swept, &PanelCommand::RecentreHead).is_some(), "recentre");
        // The devices: the mouse set to drive the light; the one driving the tool already
        // offers no click on the tool.
        assert!(find(&swept, &PanelCommand::DeviceTarget(1, 2)).is_some(), "the mouse to the light");
        assert!(find(&swept, &PanelCommand::DeviceTarget(0, 0)).is_none(), "the SpaceMouse drives the tool");
        // The lattice: its kind (NURBS at first) and its opening buttons; once open, its own.
        let bezier =
            crate::lattice::LatticeForm { kind: crate::spline::SplineKind::Bezier, ..Default::default() };
        assert!(find(&swept, &PanelCommand::LatticeForm(bezier)).is_some(), "the Bézier kind");
        assert!(find(&swept, &PanelCommand::OpenLattice(true)).is_some(), "open over the part");
        let open = PanelView {
            lattice: LatticeRow {
                open: Some("open: cubic NURBS".into()),
                weighted: true,
                ..Default::default()
            },
            ..view.clone()
        };
        let open_swept = sweep(&open);
        for wanted in
            [PanelCommand::ApplyLattice, PanelCommand::CancelLattice, PanelCommand::ControlWeight(true)]
        {
            assert!(find(&open_swept, &wanted).is_some(), "{wanted:?} with a lattice open");
        }
        assert!(find(&open_swept, &PanelCommand::OpenLattice(true)).is_none(), "one lattice at a time");
        let sliders = |swept: &[(PanelCommand, [f32; 2])]| {
            let any = |f: fn(&PanelCommand) -> bool| swept.iter().any(|(c, _)| f(c));
            (
                any(|c| matches!(c, PanelCommand::ConvergenceM(_))),
                any(|c| matches!(c, PanelCommand::InteraxialMm(_))),
            )
        };
        assert_eq!(sliders(&swept), (true, true), "the convergence and interaxial sliders");
        // The convergence slider is off while it follows the clay, and with no head tracked
        // there is nothing to recentre.
        let other = PanelView {
            stereo: StereoRow { auto_convergence: true, head: None, ..view.stereo.clone() },
            ..view.clone()
        };
        let other_swept = sweep(&other);
        assert_eq!(
            sliders(&other_swept),
            (false, true),
            "the convergence slider is off while it follows the clay"
        );
        assert!(find(&other_swept, &PanelCommand::RecentreHead).is_none(), "nothing to recentre");
        let mut panel = Panel::new();
        panel.run(&view, (800, 600), 0.0);
        panel.pointer(PointerEvent::Moved([100.0, 100.0]));
        panel.run(&view, (800, 600), 0.1);
        assert!(panel.wants_pointer(), "over the panel");
        panel.pointer(PointerEvent::Moved([600.0, 300.0]));
        panel.run(&view, (800, 600), 0.2);
        assert!(!panel.wants_pointer(), "over the scene");
        panel.set_shown(false);
        assert!(panel.run(&view, (800, 600), 0.3).1.is_none(), "hidden: nothing painted");
    }

    #[test]
    fn the_paint_holds_the_font_texture_and_batches_inside_the_image() {
        let mut panel = Panel::new();
        let (_, paint) = panel.run(&view(), (800, 600), 0.0);
        let paint = paint.unwrap();
        assert!(!paint.textures.is_empty() && paint.textures[0].offset_px.is_none(), "the font atlas first");
        let t = &paint.textures[0];
        assert_eq!(t.srgba.len() as u32, t.size_px[0] * t.size_px[1] * 4);
        assert!(!paint.batches.is_empty());
        for b in &paint.batches {
            assert!(b.clip_px[2] <= 800 && b.clip_px[3] <= 600);
            let end = (b.first_index + b.index_count) as usize;
            assert!(paint.indices[b.first_index as usize..end]
                .iter()
                .all(|&i| (i as usize) < paint.vertices.len()));
        }
        assert!(paint.vertices.iter().all(|v| v.colour.iter().chain(&v.position_px).all(|c| c.is_finite())));
        // The panel lies in its band on the left.
        let right = paint.vertices.iter().map(|v| v.position_px[0]).fold(0.0, f32::max);
        assert!(right <= PANEL_WIDTH_PT + 20.0, "{right}");
    }

    /// Where a click leaves `wanted` true, on a fresh panel that was first clicked at each of
    /// `before`; searched down the panel's band.
    fn find_after(
        view: &PanelView,
        before: &[[f32; 2]],
        wanted: impl Fn(&Panel, &[PanelCommand]) -> bool,
    ) -> Option<[f32; 2]> {
        for y in (4..TALL).step_by(6) {
            for x in [20.0, 60.0, 100.0, 140.0, 180.0, 220.0] {
                let mut panel = Panel::new();
                before.iter().for_each(|&at| drop(click(&mut panel, view, at)));
                let commands = click(&mut panel, view, [x, y as f32]);
                if wanted(&panel, &commands) {
                    return Some([x, y as f32]);
                }
            }
        }
        None
    }

    /// A folder of its own for a test, empty.
    fn test_folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("argile-panel-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A short view (one shape, one action, no history, one display mode) saving in `dir`.
    fn files_view(dir: &std::path::Path) -> PanelView {
        PanelView {
            shapes: vec!["sphere"],
            actions: vec!["add"],
            undo: Vec::new(),
            redo: Vec::new(),
            display_modes: vec!["mono"],
            save_to: dir.join("bust.argile").display().to_string(),
            ..view()
        }
    }

    #[test]
    fn the_file_browser_saves_as_a_typed_name_and_opens_a_sculpt_of_its_folder() {
        let dir = test_folder("browser");
        std::fs::write(dir.join("older.argile"), b"x").unwrap();
        std::fs::write(dir.join("notes.txt"), b"x").unwrap();
        std::fs::create_dir(dir.join("studies")).unwrap();
        let view = files_view(&dir);
        // Save as: the name field has the keyboard at once; typed, Enter saves.
        let save_as =
            find_after(&view, &[], |p, _| p.file_task() == Some(FileTask::SaveAs)).expect("save as");
        let mut panel = Panel::new();
        click(&mut panel, &view, save_as);
        panel.run(&view, (800, TALL), 1.0);
        assert!(panel.wants_keyboard(), "the name field has the keyboard");
        for _ in 0.."bust.argile".len() {
            panel.key(PanelKey::Backspace, true);
            panel.key(PanelKey::Backspace, false);
        }
        panel.run(&view, (800, TALL), 1.1);
        panel.text("head\u{8}");
        panel.run(&view, (800, TALL), 1.2);
        panel.key(PanelKey::Enter, true);
        panel.key(PanelKey::Enter, false);
        let (commands, _) = panel.run(&view, (800, TALL), 1.3);
        // The name cleared, "head" typed (the control character left out) gains the extension.
        assert_eq!(commands, [PanelCommand::SaveAs(dir.canonicalize().unwrap().join("head.argile"))]);
        assert_eq!(panel.file_task(), None, "the browser closes");
        // Open: the folder lists the sculpt and the subfolder, not the text file; a click on
        // the sculpt opens it.
        let open = find_after(&view, &[], |p, _| p.file_task() == Some(FileTask::Open)).expect("open");
        let older = dir.canonicalize().unwrap().join("older.argile");
        let wanted = PanelCommand::Open(older.clone());
        let at = find_after(&view, &[open], |_, c| c.contains(&wanted)).expect("the sculpt listed");
        // Into the subfolder, then up again: the sculpt is where it was.
        let into = find_after(&view, &[open], |p, _| {
            p.browser.folder.ends_with("studies") && p.file_task() == Some(FileTask::Open)
        })
        .expect("the subfolder listed");
        let up = find_after(&view, &[open, into], |p, _| p.browser.folder == dir.canonicalize().unwrap())
            .expect("up");
        assert!(up[1] < at[1], "the browser's buttons above its entries");
        // The recent sculpts and the recovered ones open by a click; the recovered are dismissed.
        let recent = PanelView { recent: vec![older.clone()], ..view.clone() };
        assert!(find_after(&recent, &[], |_, c| c.contains(&wanted)).is_some(), "a recent sculpt");
        let recovered =
            PanelView { recovered: vec![(older.clone(), "3 stroke(s) of bust".into())], ..view.clone() };
        assert!(find_after(&recovered, &[], |_, c| c.contains(&wanted)).is_some(), "a recovered sculpt");
        let dismissed = find_after(&recovered, &[], |_, c| c.contains(&PanelCommand::DismissRecovered));
        assert!(dismissed.is_some(), "dismiss");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_file_browser_exports_in_the_format_picked_and_an_unreadable_folder_only_says_so() {
        let dir = test_folder("export");
        let view = files_view(&dir);
        let export = find_after(&view, &[], |p, _| p.file_task() == Some(FileTask::Export)).expect("export");
        let mut panel = Panel::new();
        click(&mut panel, &view, export);
        panel.key(PanelKey::Enter, true);
        panel.key(PanelKey::Enter, false);
        let (commands, _) = panel.run(&view, (800, TALL), 1.0);
        assert_eq!(commands, [PanelCommand::Export(dir.canonicalize().unwrap().join("bust.obj"))]);
        // The STL button renames the file.
        let stl = find_after(&view, &[export], |p, _| p.browser.name == "bust.stl").expect("the stl button");
        let mut panel = Panel::new();
        click(&mut panel, &view, export);
        click(&mut panel, &view, stl);
        let wanted = PanelCommand::Export(dir.canonicalize().unwrap().join("bust.stl"));
        assert!(find_after(&view, &[export, stl], |_, c| c.contains(&wanted)).is_some(), "export as stl");
        // A folder that is not there, and one that is a file: the browser says so, every click
        // on it gives nothing but its own buttons' work, and nothing panics.
        std::fs::write(dir.join("file"), b"x").unwrap();
        for folder in [dir.join("gone"), dir.join("file")] {
            let view =
                PanelView { save_to: folder.join("bust.argile").display().to_string(), ..view.clone() };
            let open = find_after(&view, &[], |p, _| p.file_task() == Some(FileTask::Open)).expect("open");
            let mut panel = Panel::new();
            click(&mut panel, &view, open);
            match &panel.browser.listing {
                Some(Err(why)) => assert!(why.contains("cannot read the folder"), "{why}"),
                other => panic!("{folder:?} listed: {other:?}"),
            }
            let opened =
                find_after(&view, &[open], |_, c| c.iter().any(|c| matches!(c, PanelCommand::Open(_))));
            assert_eq!(opened, None, "nothing to open in {folder:?}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn names_in_scripts_the_built_in_fonts_lack_are_listed_drawn_and_opened() {
        // The panel's fonts are built into the program (egui's), so no font file can be
        // missing; the glyphs of a file or part name can be. Such names still list, draw (as
        // the font's replacement glyph) and open the file they name.
        let dir = test_folder("glyphs");
        let names = ["頭部.argile", "🗿 statue.argile", "גוף.argile", "a\u{301}\u{200b}b.argile"];
        for name in names {
            std::fs::write(dir.join(name), b"x").unwrap();
        }
        let part =
            PartRow { name: "腕 💪".into(), op: "union", voxel_mm: 2.0, visible: true, locked: false };
        let view = PanelView {
            status: vec!["opened 頭部.argile 🗿".into()],
            parts: vec![part],
            save_name: "頭部 🗿.argile".into(),
            ..files_view(&dir)
        };
        let open = find_after(&view, &[], |p, _| p.file_task() == Some(FileTask::Open)).expect("open");
        let mut opened = Vec::new();
        for y in (4..TALL).step_by(6) {
            let mut panel = Panel::new();
            click(&mut panel, &view, open);
            for command in click(&mut panel, &view, [60.0, y as f32]) {
                if let PanelCommand::Open(path) = command {
                    opened.push(path);
                }
            }
        }
        for name in names {
            let path = dir.canonicalize().unwrap().join(name);
            assert!(opened.contains(&path), "{name} listed and opened: {opened:?}");
        }
        // Drawn at the desk and in the headset (the font's textures came with the first frames).
        for mut panel in [Panel::new(), Panel::headset()] {
            click(&mut panel, &view, open);
            let (_, paint) = panel.run(&view, (800, TALL), 2.0);
            let paint = paint.expect("a frame's paint");
            assert!(!paint.batches.is_empty() && !paint.vertices.is_empty());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_tiny_or_a_huge_image_never_panics() {
        for extent in [(1, 1), (2, 1), (8192, 8192), (0, 0), (1, 8192)] {
            let mut panel = Panel::new();
            for t in 0..3 {
                panel.pointer(PointerEvent::Moved([0.5, 0.5]));
                panel.pointer(PointerEvent::Primary(t % 2 == 0));
                let (_, paint) = panel.run(&view(), extent, f64::from(t));
                if let Some(paint) = paint {
                    assert!(paint.textures.iter().all(|t| t.size_px[0] <= MAX_TEXTURE_SIDE));
                }
            }
        }
    }
}
