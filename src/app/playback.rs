//! Playing a scene's timeline on the CPU side: the initial clay, then the scripted hands
//! sculpting it, step by step at the scene's fixed step rate.

use anyhow::{bail, Result};

use crate::field::Field;
use crate::io::autosave::{Autosave, Besides};
use crate::io::StoredTool;
use crate::math::Pose;
use std::sync::Arc;

use super::assembly::{image_in_part, Assembly};
use super::held_lattice::HeldLattice;
use super::held_region::{box_between, HeldRegion, MIN_BOX_VOXELS};
use crate::clay::{window_around, Clay, ClayParams, ClayTool};
use crate::lattice::{volume_at, Lattice, LatticeError};
use crate::math::{Aabb, Isometry, Vec3};
use crate::parts::Placement;
use crate::parts::{copy_repeated, inflate, Region, RegionDrag, RegionOp, Symmetry};
use crate::scene::{
    Hand, HandState, Key, RegionAction, Scene, SceneLattice, SceneRegion, SceneTool, SceneToolShape,
};
use crate::tool::{
    rasterize_solid, rasterize_solid_in_slabs, Action, Freeform, Stroke, Tool, ToolFrame, ToolShape,
};

/// What a scene's region tool is called in messages.
fn region_name(r: &SceneRegion) -> &'static str {
    match r.action {
        RegionAction::Drag(op) => op.name(),
        RegionAction::Inflate(d) if d > 0.0 => "inflate",
        RegionAction::Inflate(_) => "deflate",
        RegionAction::CopyToPart => "copy to part",
    }
}

/// Lattice points of room the virtual clay's window keeps around the tools' paths and the
/// clay they touch.
const CLAY_MARGIN_VOXELS: i32 = 12;

/// A push in progress: the virtual clay, and which hand drives which of its tools.
#[derive(Debug)]
struct Push {
    clay: Clay,
    /// Per clay tool: the hand holding it (`None`: the table), the scene tool index, and the
    /// symmetry's image of the hand it is (the identity for the hand's own tool).
    bodies: Vec<(Option<Hand>, usize, Isometry)>,
}

/// The clay and the hands' strokes at the current time of a scene's timeline.
#[derive(Debug)]
pub struct Playback<'s> {
    scene: &'s Scene,
    /// The first part's clay: the one pushes act on (the desk's and the headset's tools, the
    /// lattices and the region tools act on the part they name, or the active one).
    field: Field,
    /// The other parts, every part's layout and their composition.
    assembly: Assembly,
    /// The scene's tools, built once the initial clay is laid (freeform tools copy it).
    tools: Vec<Tool>,
    /// The stroke each hand is drawing (left, right), with its tool index and the part it acts
    /// on.
    strokes: [Option<(usize, usize, Stroke)>; 2],
    /// Whether the field's open stroke is the hands' (opened here).
    owns_stroke: bool,
    /// The parts after the first whose open strokes the timeline opened; a stroke someone else
    /// opened on a part (the desk's or the headset's tool, a region held) is theirs to close.
    opened: std::collections::BTreeSet<usize>,
    /// The push the hands' push and support tools drive, while one pushes.
    push: Option<Push>,
    time_s: f32,
    /// Journals every stroke that ends.
    autosave: Option<Autosave>,
    /// The hands' states given live (a headset's controllers) instead of the timeline's.
    live: Option<[Option<HandState>; 2]>,
    /// Per scene lattice: still to open, open, or applied.
    lattices: Vec<LatticeState>,
    /// Per scene region tool: still to act, moving, or done.
    regions: Vec<RegionState>,
    /// The symmetry strokes and pushes act through, and its images.
    symmetry: Symmetry,
    /// The form of the lattices the desk and the headset open.
    lattice_form: crate::lattice::LatticeForm,
    images: Vec<Isometry>,
    /// The lattice the desk or the headset holds open over a part's clay: its part's stroke
    /// stays open until it is applied (one undo step) or put back.
    held: Option<HeldLattice>,
    /// The held lattice as autosave last stored it, and as it was at the last
    /// [`Playback::keep_lattice`] (stored once it stays the same from one frame to the next).
    lattice_kept: Option<crate::io::StoredLattice>,
    lattice_seen: Option<crate::io::StoredLattice>,
    /// The region the desk or the headset carries: its part's stroke stays open until the
    /// hand lets it go (one undo step).
    held_region: Option<HeldRegion>,
    /// The box the region tools act on instead of the tool's shape: the part it lies in, and
    /// the box in that part's frame.
    selection: Option<(usize, Region)>,
}

/// Where a scene's region tool stands on the timeline.
#[derive(Debug)]
enum RegionState {
    Waiting,
    /// Carried along its motion over its duration.
    Moving(Box<RegionDrag>),
    Done,
}

/// Where a scene's lattice stands on the timeline.
#[derive(Debug)]
enum LatticeState {
    /// Its `open_s` has not come.
    Waiting,
    /// Open over the clay, with the world box its last changes have not been written to yet.
    Open(Box<Lattice>, Aabb),
    /// Applied (or refused): the clay keeps what it did.
    Closed,
}

/// How far a live hand may move during one push and stay in the clay's window, metres.
const LIVE_REACH_M: f32 = 0.08;

fn slot(hand: Hand) -> usize {
    match hand {
        Hand::Left => 0,
        Hand::Right => 1,
    }
}

impl<'s> Playback<'s> {
    /// The scene at time 0: its initial clay, rasterised into a new field, whatever it costs
    /// (for scenes known to be small; a user's scene goes through [`Playback::build`]).
    pub fn new(scene: &'s Scene) -> Self {
        Self::on_parts(scene, scene_parts(scene, |_| true), &[], |_, _| None)
    }

    /// The scene at time 0, its initial clay built by [`initial_parts`]: refused over the
    /// memory budget, with progress, and broken off by a stopping signal.
    pub fn build(scene: &'s Scene) -> Result<Self> {
        Self::new_autosaved(scene, |_, _| None)
    }

    /// The scene's freeform tools as a sculpt stores them (each with its index in the scene).
    pub fn stored_tools(&self) -> Vec<StoredTool> {
        stored_tools(&self.tools)
    }

    /// Puts the freeform tools a sculpt stored (see [`Playback::stored_tools`]) in place of the
    /// scene's copies of its clay; one whose index is not a freeform tool of the scene is left
    /// out. Returns how many it put. An autosave session started before keeps the tools it was
    /// started with: open a sculpt with [`Playback::on_field`] or [`Playback::replace_field`].
    pub fn restore_tools(&mut self, stored: &[StoredTool]) -> usize {
        restore_tools(&mut self.tools, stored)
    }

    /// The scene at time 0, its initial clay built by [`initial_parts`], with autosave started
    /// by `start` on it, before the first stroke; every stroke that ends is then journaled.
    pub fn new_autosaved(
        scene: &'s Scene,
        start: impl FnOnce(&mut Field, Besides<'_>) -> Option<Autosave>,
    ) -> Result<Self> {
        Ok(Self::on_parts(scene, initial_parts(scene)?, &[], start))
    }

    /// The scene at time 0 over `field` (a sculpt opened from a file) instead of its initial
    /// clay, with the freeform tools the sculpt stored (see [`Playback::restore_tools`]) and
    /// autosave started by `start` on it (given the scene's freeform tools, for its snapshots).
    pub fn on_field(
        scene: &'s Scene,
        field: Field,
        stored: &[StoredTool],
        start: impl FnOnce(&mut Field, Besides<'_>) -> Option<Autosave>,
    ) -> Self {
        Self::on_sculpt(scene, field, Vec::new(), stored, start)
    }

    /// [`Playback::on_field`] over a sculpt of parts: `field` the first part's clay, `others`
    /// the clay of the scene's other parts (a field each; the scene's own initial clay of them
    /// when `others` does not hold one per part).
    pub fn on_sculpt(
        scene: &'s Scene,
        field: Field,
        others: Vec<Field>,
        stored: &[StoredTool],
        start: impl FnOnce(&mut Field, Besides<'_>) -> Option<Autosave>,
    ) -> Self {
        let fields = if others.len() + 1 == scene.parts.len() {
            std::iter::once(field).chain(others).collect()
        } else {
            let mut fields = scene_parts(scene, |part| part > 0);
            fields[0] = field;
            fields
        };
        Self::on_parts(scene, fields, stored, start)
    }

    /// The scene at time 0 over `fields`, one per part of the scene, as [`Playback::on_field`]
    /// does over the first.
    fn on_parts(
        scene: &'s Scene,
        mut fields: Vec<Field>,
        stored: &[StoredTool],
        start: impl FnOnce(&mut Field, Besides<'_>) -> Option<Autosave>,
    ) -> Self {
        assert_eq!(fields.len(), scene.parts.len(), "a field per part");
        let others = fields.split_off(1);
        let mut field = fields.pop().expect("the first part");
        let mut assembly = Assembly::new(scene.parts.clone(), others, &field);
        let mut tools: Vec<Tool> = scene.tools.iter().map(|t| build_tool(t, &field)).collect();
        restore_tools(&mut tools, stored);
        let (stored_now, layouts) = (stored_tools(&tools), assembly.layouts());
        let besides = Besides { symmetry: Some(scene.symmetry), ..assembly.besides(&stored_now, &layouts) };
        let autosave = start(&mut field, besides);
        let mut playback = Self {
            scene,
            field,
            assembly,
            tools,
            strokes: [None, None],
            owns_stroke: false,
            opened: Default::default(),
            push: None,
            time_s: 0.0,
            autosave,
            live: None,
            lattices: scene.lattices.iter().map(|_| LatticeState::Waiting).collect(),
            regions: scene.regions.iter().map(|_| RegionState::Waiting).collect(),
            symmetry: scene.symmetry,
            lattice_form: crate::lattice::LatticeForm::default(),
            images: scene.symmetry.images(),
            held: None,
            held_region: None,
            selection: None,
            lattice_kept: None,
            lattice_seen: None,
        };
        // Keys at time 0 with their action on stamp at once.
        playback.step_to(0.0);
        playback
    }

    /// Puts `field` (a sculpt opened from a file) in place of the clay: the hands' strokes end,
    /// every brick of the old and the new clay is marked dirty so the next re-mesh redraws it
    /// all, and autosave starts again with `start` on the new clay. Returns the old autosave
    /// session: the caller closes it, or drops it to leave it for recovery.
    pub fn replace_field(
        &mut self,
        field: Field,
        start: impl FnOnce(&mut Field, Besides<'_>) -> Option<Autosave>,
    ) -> Option<Autosave> {
        let whole = vec![crate::scene::ScenePart::whole(field.transform().voxel_size_m)];
        self.replace_sculpt(field, whole, Vec::new(), start)
    }

    /// [`Playback::replace_field`] for a sculpt of parts: `parts` their layouts, `field` the
    /// first one's clay and `others` the clay of the rest.
    pub fn replace_sculpt(
        &mut self,
        mut field: Field,
        parts: Vec<crate::scene::ScenePart>,
        others: Vec<Field>,
        start: impl FnOnce(&mut Field, Besides<'_>) -> Option<Autosave>,
    ) -> Option<Autosave> {
        use crate::field::BRICK_SIZE;
        self.strokes = [None, None];
        self.owns_stroke = false;
        self.opened.clear();
        self.push = None;
        // An open lattice resamples the clay it opened over, a held region carries it: each
        // ends with that clay.
        self.held = None;
        self.held_region = None;
        self.selection = None;
        (self.lattice_kept, self.lattice_seen) = (None, None);
        for state in &mut self.lattices {
            if matches!(state, LatticeState::Open(..)) {
                *state = LatticeState::Closed;
            }
        }
        for state in &mut self.regions {
            if matches!(state, RegionState::Moving(..)) {
                *state = RegionState::Done;
            }
        }
        let keys: Vec<_> =
            self.surface_now().covered_keys().into_iter().chain(field.covered_keys()).collect();
        for key in keys {
            let lo = key * BRICK_SIZE;
            field.mark_dirty(lo, lo + crate::math::IVec3::splat(BRICK_SIZE - 1));
        }
        self.assembly = Assembly::new(parts, others, &field);
        self.field = field;
        let old = self.autosave.take();
        let (stored_now, layouts) = (stored_tools(&self.tools), self.assembly.layouts());
        let besides =
            Besides { symmetry: Some(self.symmetry), ..self.assembly.besides(&stored_now, &layouts) };
        self.autosave = start(&mut self.field, besides);
        old
    }

    /// The scene it plays.
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// The clay.
    pub fn field(&self) -> &Field {
        &self.field
    }

    /// The clay, ending the playback.
    pub fn into_field(self) -> Field {
        self.field
    }

    /// The clay of every part, ending the playback: the first part's, the parts' layouts as a
    /// sculpt file stores them (none for one part at rest) and the clay of the others.
    pub fn into_parts(self) -> (Field, Vec<crate::io::PartLayout>, Vec<Field>) {
        let layouts = self.assembly.layouts();
        (self.field, layouts, self.assembly.into_others())
    }

    /// The active part's clay, for the desk's and the headset's tools, and its placement in the
    /// world when it is not at rest there (a tool's pose and size go into its frame through it),
    /// or why no tool may act on it.
    pub fn active_target(&mut self) -> Result<(&mut Field, Option<Placement>), String> {
        let part = self.assembly.active();
        let layout = &self.assembly.parts()[part];
        if layout.locked {
            return Err(format!("part \"{}\" is locked: no tool acts on it", layout.name));
        }
        let frame = self.assembly.frame_of(part);
        Ok((self.assembly.field_mut(&mut self.field, part), frame))
    }

    /// A tool at `pose` (world), acting through the symmetry's `images`, as it acts on the
    /// active part: in the part's frame and at its scale when the part is placed in the world.
    /// The desk's and the headset's tools go through it.
    pub fn in_active_part(&self, tool: Tool, pose: Pose, images: &[Isometry]) -> (Tool, Pose, Vec<Isometry>) {
        in_part(self.assembly.frame_of(self.assembly.active()), tool, pose, images)
    }

    /// Makes part `part` (wrapped) the one the desk's and the headset's tools act on, closing the
    /// strokes open; returns it.
    pub fn set_active_part(&mut self, part: usize) -> usize {
        self.close_steps();
        let active = self.assembly.set_active(part);
        if self.selection.as_ref().is_some_and(|(on, _)| *on != active) {
            self.selection = None;
        }
        active
    }

    /// Places part `part` at `placement` in the world (the composition follows); the autosave
    /// session's snapshots store where it is from the next [`Playback::keep_layouts`].
    pub fn set_part_placement(&mut self, part: usize, placement: Placement) {
        self.assembly.set_placement(part, placement);
    }

    /// Has the autosave session store the parts' layouts as they are now (after a part was
    /// moved): written before this returns, so no recovery puts a part back where it was.
    pub fn keep_layouts(&mut self) {
        let layouts = self.assembly.layouts();
        if let Some(a) = &mut self.autosave {
            a.set_layouts(layouts);
        }
    }

    /// The sculpt's parts: their layouts and the fields of all but the first.
    pub fn assembly(&self) -> &Assembly {
        &self.assembly
    }

    /// The surface drawn, measured and exported, brought up to date: the first part's clay
    /// where it is the whole sculpt, else the composition of every part (see [`Assembly`]).
    /// Its dirty set says what to re-mesh.
    pub fn surface(&mut self) -> &mut Field {
        self.assembly.surface(&mut self.field)
    }

    /// The surface as it was last brought up to date by [`Playback::surface`].
    pub fn surface_now(&self) -> &Field {
        self.assembly.surface_now(&self.field)
    }

    /// The surface, up to date, ending the playback.
    pub fn into_surface(mut self) -> Field {
        let _ = self.surface();
        let Playback { field, assembly, .. } = self;
        assembly.into_surface(field)
    }

    /// Takes back the newest step of the sculpt, in every part it changed; returns whether
    /// there was one.
    /// A lattice held open is the newest step: undo puts its clay back and closes it.
    pub fn undo(&mut self) -> Result<bool, crate::field::HistoryError> {
        if self.cancel_lattice() {
            return Ok(true);
        }
        self.close_steps();
        let placed = self.placements();
        let autosave = &mut self.autosave;
        let undone = self.assembly.undo(&mut self.field, &mut |first, others| {
            if let Some(a) = autosave.as_mut() {
                a.record_parts(first, others);
            }
        })?;
        // A box selected on a part taken away goes with it.
        self.selection = self.selection.take().filter(|(p, _)| *p < self.assembly.parts().len());
        self.keep_placements(placed);
        Ok(undone)
    }

    /// Every part's placement.
    fn placements(&self) -> Vec<Placement> {
        self.assembly.parts().iter().map(|p| p.placement).collect()
    }

    /// Has the autosave session store the layouts when the parts are no longer as `before`
    /// placed them (an undo or a redo moved one, or added or took one away).
    fn keep_placements(&mut self, before: Vec<Placement>) {
        if self.placements() != before {
            self.keep_layouts();
        }
    }

    /// Logs part `part`'s move from `from` to where it is now (the desk's device or the
    /// headset's support hand let it go) as one undo step, and has the autosave session store
    /// where it is.
    pub fn keep_part_moved(&mut self, part: usize, from: Placement) {
        self.assembly.note_placement(&self.field, part, from);
        self.keep_layouts();
    }

    /// Puts back the newest step undone; returns whether there was one (none while a lattice
    /// is held open: opening it cleared what could be redone).
    pub fn redo(&mut self) -> bool {
        if self.held.is_some() {
            return false;
        }
        self.close_steps();
        let placed = self.placements();
        let redone = self.assembly.redo(&mut self.field);
        self.keep_placements(placed);
        redone
    }

    /// Ends the hands' strokes and closes the steps they hold open on every part (as undo does
    /// before taking back the newest), journaling them; a lattice held open is applied.
    pub fn close_steps(&mut self) {
        self.apply_held();
        self.let_go_held_region();
        self.strokes = [None, None];
        if self.owns_stroke {
            self.field.end_stroke();
            self.owns_stroke = false;
        }
        self.opened.clear();
        self.assembly.end_strokes();
        self.journal();
    }

    /// The tools let go: a push in progress ends as it does when its tool stops (the motion
    /// not yet passed on is, the crumbs the tools held are eaten back into the clay, the
    /// excess is settled into the field), then the steps close. The clay "at the end of the
    /// timeline" is the clay once its tools let go.
    pub fn let_go(&mut self) {
        if let Some(push) = self.push.take() {
            push.clay.finish(&mut self.field);
        }
        self.close_steps();
    }

    /// The clay's matter: the field's mass, plus what a push in progress holds beyond the
    /// densities of 1 the field can show (the excess its conservation layer still carries).
    pub fn matter(&self) -> f64 {
        self.field.mass() + self.push.as_ref().map_or(0.0, |p| p.clay.excess_mass())
    }

    /// The clay, mutably (to drain its dirty set).
    pub fn field_mut(&mut self) -> &mut Field {
        &mut self.field
    }

    /// Current time on the timeline, seconds.
    pub fn time_s(&self) -> f32 {
        self.time_s
    }

    /// From now on the hands are `hands` (left, right; `None`: no tool held), as a headset's
    /// controllers give them, instead of the timeline's keys: their tools (indices into
    /// [`Playback::tools`]) act while `active`, pushes and supports included.
    pub fn set_live_hands(&mut self, hands: [Option<HandState>; 2]) {
        self.live = Some(hands);
    }

    /// What `hand` does at `t`: the live state when hands are live, else the timeline's.
    fn state_at(&self, hand: Hand, t: f32) -> Option<HandState> {
        match &self.live {
            Some(live) => live[slot(hand)],
            None => self.scene.timeline.state_at(hand, t),
        }
    }

    /// The keys of `hand` (none when hands are live).
    fn keys(&self, hand: Hand) -> &'s [Key] {
        match self.live {
            Some(_) => &[],
            None => self.scene.timeline.keys(hand),
        }
    }

    /// Plays the timeline up to `t` in fixed steps; key times are always step boundaries, so
    /// strokes follow the keyed path exactly. Calls `progress(time)` after each step.
    pub fn advance_to(&mut self, t: f32, progress: impl FnMut(f32)) {
        self.advance_until(t, progress, || false);
    }

    /// [`Playback::advance_to`], stopping between two steps once `stop` says so; returns
    /// whether `t` was reached.
    pub fn advance_until(&mut self, t: f32, mut progress: impl FnMut(f32), stop: impl Fn() -> bool) -> bool {
        while self.time_s < t {
            if stop() {
                return false;
            }
            progress(self.step_towards(t));
        }
        true
    }

    /// Plays one fixed step towards `t` (shorter where a key or `t` comes first), as
    /// [`Playback::advance_to`] does; returns the new time.
    pub fn step_towards(&mut self, t: f32) -> f32 {
        let mut next = (self.time_s + self.scene.timeline.step_s()).min(t);
        for hand in Hand::BOTH {
            if let Some(k) = self.keys(hand).iter().find(|k| k.time_s > self.time_s) {
                next = next.min(k.time_s);
            }
        }
        for l in &self.scene.lattices {
            let times = [l.open_s, l.apply_s].into_iter().chain(l.edits.iter().map(|e| e.time_s));
            if let Some(t) = times.filter(|&t| t > self.time_s).reduce(f32::min) {
                next = next.min(t);
            }
        }
        for r in &self.scene.regions {
            if let Some(t) = [r.time_s, r.end_s()].into_iter().filter(|&t| t > self.time_s).reduce(f32::min) {
                next = next.min(t);
            }
        }
        self.step_to(next);
        next
    }

    fn step_to(&mut self, t: f32) {
        let previous = self.time_s;
        for hand in Hand::BOTH {
            // The interval's midpoint tells which key interval (and so which action) it is in.
            let during = self.state_at(hand, 0.5 * (previous + t));
            let (Some(during), Some(at_start), Some(at_end)) =
                (during, self.state_at(hand, previous), self.state_at(hand, t))
            else {
                continue;
            };
            let stroke = &mut self.strokes[slot(hand)];
            let active = during.active || (t == previous && at_end.active);
            let part = during.part.min(self.assembly.parts().len() - 1);
            if !active || self.tools[during.tool].action.is_clay_body() || self.assembly.parts()[part].locked
            {
                *stroke = None;
                continue;
            }
            // In a part placed in the world, the tool acts in the part's frame.
            let frame = self.assembly.frame_of(part);
            let local = |pose: Pose| frame.map_or(pose, |f| f.local_pose(pose));
            if stroke.as_ref().is_none_or(|(tool, on, _)| (*tool, *on) != (during.tool, part)) {
                let field = self.assembly.field_mut(&mut self.field, part);
                if !field.in_stroke() {
                    field.begin_stroke();
                    own(&mut self.owns_stroke, &mut self.opened, part);
                }
                let (tool, _, images) =
                    in_part(frame, self.tools[during.tool].clone(), Pose::default(), &self.images);
                let mut s = Stroke::with_images(tool, &images);
                s.advance(field, local(at_start.pose), 0.0);
                *stroke = Some((during.tool, part, s));
            }
            if let Some((_, part, s)) = stroke {
                s.advance(self.assembly.field_mut(&mut self.field, *part), local(at_end.pose), t - previous);
            }
        }
        self.step_clay(previous, t);
        self.step_lattices(t);
        self.step_regions(t);
        // The hands' strokes, pushes, open lattices and moving regions form one undo step while
        // any of them acts. A stroke someone else opened on the field (the station's desk
        // tool) is theirs to close.
        let drawing = self.strokes.iter().any(Option::is_some)
            || self.push.is_some()
            || self.held.is_some()
            || self.lattices.iter().any(|l| matches!(l, LatticeState::Open(..)))
            || self.regions.iter().any(|r| matches!(r, RegionState::Moving(..)));
        // The step's strokes on the other parts close with it, before it is journaled.
        if drawing && !self.field.in_stroke() {
            self.field.begin_stroke();
            self.owns_stroke = true;
        } else if !drawing && self.owns_stroke {
            self.end_opened_strokes();
            self.field.end_stroke();
            self.owns_stroke = false;
            if let Some(a) = &mut self.autosave {
                a.record_parts(&mut self.field, self.assembly.others_mut());
            }
        }
        if !drawing {
            self.end_opened_strokes();
            self.assembly.note_steps(&self.field);
        }
        self.time_s = t;
    }

    /// Closes the strokes the timeline opened on the parts after the first.
    fn end_opened_strokes(&mut self) {
        for part in std::mem::take(&mut self.opened) {
            let field = self.assembly.field_mut(&mut self.field, part);
            if field.in_stroke() {
                field.end_stroke();
            }
        }
    }

    /// Journals the strokes finished on the field since the last record (a stroke drawn on
    /// the field by someone else, an undo, a redo), if autosave runs.
    pub fn journal(&mut self) {
        self.assembly.note_steps(&self.field);
        if let Some(a) = &mut self.autosave {
            a.record_parts(&mut self.field, self.assembly.others_mut());
        }
    }

    /// The autosave session, if one runs.
    pub fn autosave(&self) -> Option<&Autosave> {
        self.autosave.as_ref()
    }

    /// Ends the stroke still open (journaling it; a lattice held open is applied) and hands
    /// the autosave session over, to be closed once the sculpt is safe.
    pub fn finish_autosave(&mut self) -> Option<Autosave> {
        // A lattice held open ends applied: its step is journaled with its last change, so a
        // session left unclosed keeps what the lattice did.
        self.apply_held();
        let mut autosave = self.autosave.take()?;
        if self.field.in_stroke() {
            self.field.end_stroke();
            self.strokes = [None, None];
        }
        self.assembly.end_strokes();
        autosave.record_parts(&mut self.field, self.assembly.others_mut());
        Some(autosave)
    }

    /// Runs the virtual clay over `previous ..= t`: a push starts when a hand's push tool turns
    /// active (with the supports held still and active at that moment, the table and the fixed
    /// boxes; a support whose hand moves it or turns it off later is let go), follows
    /// the hands at the clay's own step rate, is written back into the field after each
    /// interval, and ends, settled, when no hand pushes any more.
    fn step_clay(&mut self, previous: f32, t: f32) {
        let mid = 0.5 * (previous + t);
        let acting = |hand: Hand, action: Action| {
            self.state_at(hand, mid).filter(|s| {
                (s.active || (t == previous && self.state_at(hand, t).is_some_and(|e| e.active)))
                    && self.tools[s.tool].action == action
            })
        };
        let pushing: Vec<(Hand, usize)> =
            Hand::BOTH.iter().filter_map(|&h| acting(h, Action::Push).map(|s| (h, s.tool))).collect();
        if pushing.is_empty() {
            if let Some(push) = self.push.take() {
                push.clay.finish(&mut self.field);
            }
            return;
        }
        if self.push.is_none() {
            if !self.field.in_stroke() {
                self.field.begin_stroke();
                self.owns_stroke = true;
            }
            self.push = Some(self.start_push(&pushing, previous, t - previous));
        }
        let Some(bodies) = self.push.as_ref().map(|p| p.bodies.clone()) else { return };
        let now = self.push.as_ref().map(|p| p.clay.poses()).unwrap_or_default();
        // A scripted support holds while its hand holds it still; once the hand moves it or
        // lets go, it holds no more. A live hand (a controller) is never perfectly still: its
        // support stays where it was put for as long as the hand keeps it on.
        let let_go: Vec<(Hand, usize)> = bodies
            .iter()
            .enumerate()
            .filter_map(|(i, &(hand, tool, image))| {
                let hand = hand?;
                (image == Isometry::IDENTITY
                    && self.tools[tool].action == Action::Support
                    && !self.held_still(hand, tool, now[i], previous, t))
                .then_some((hand, tool))
            })
            .collect();
        // A support's images go with it.
        let released: Vec<usize> = bodies
            .iter()
            .enumerate()
            .filter_map(|(i, &(hand, tool, _))| let_go.contains(&(hand?, tool)).then_some(i))
            .collect();
        let poses: Vec<Pose> = bodies
            .iter()
            .zip(now)
            .map(|(&(hand, tool, image), now)| {
                let placed = self.live.is_some() && self.tools[tool].action == Action::Support;
                hand.filter(|_| !placed).and_then(|h| self.state_at(h, t)).map_or(now, |s| {
                    if image == Isometry::IDENTITY {
                        s.pose
                    } else {
                        image.pose(&s.pose).0
                    }
                })
            })
            .collect();
        let Some(push) = self.push.as_mut() else { return };
        for i in released {
            push.clay.release(i);
        }
        push.clay.advance(&poses, t - previous);
        push.clay.write_to(&mut self.field);
    }

    /// Opens the scene's lattices whose time has come, shapes the open ones as their keys say
    /// at `t`, and applies those whose `apply_s` it is. The clay is re-evaluated where a
    /// control changed when a key is reached, when the lattice is applied, and whenever
    /// [`Playback::sync_lattices`] asks (before a frame is drawn): a ramp's steps in between
    /// need no clay. A lattice that cannot open or follow its keys (its copy of the clay would
    /// grow over its limit) is closed with a warning, the clay left as it last was.
    fn step_lattices(&mut self, t: f32) {
        let scene = self.scene;
        for (state, sl) in self.lattices.iter_mut().zip(&scene.lattices) {
            // It deforms its part's clay, in that part's frame.
            let field = self.assembly.field_mut(&mut self.field, sl.part);
            if matches!(state, LatticeState::Waiting) && t >= sl.open_s {
                if !field.in_stroke() {
                    field.begin_stroke();
                    own(&mut self.owns_stroke, &mut self.opened, sl.part);
                }
                *state = match Lattice::open(field, &sl.spec) {
                    Ok(l) => LatticeState::Open(Box::new(l), Aabb::EMPTY),
                    Err(e) => {
                        eprintln!("warning: {}: lattice `{}` cannot open: {e}", scene.source, sl.name);
                        LatticeState::Closed
                    }
                };
            }
            let LatticeState::Open(lattice, pending) = state else { continue };
            let shaped = volume_at(lattice.fitted(), &sl.edits, t).map_err(LatticeError::from);
            let keyed = t >= sl.apply_s || sl.edits.iter().any(|e| e.time_s == t);
            let written = shaped.and_then(|v| lattice.set_controls(&v)).and_then(|changed| {
                if let Some(b) = changed {
                    *pending = pending.union(&b);
                }
                if keyed && !pending.is_empty() {
                    lattice.write(field, std::mem::replace(pending, Aabb::EMPTY))?;
                }
                Ok(())
            });
            if let Err(e) = written {
                eprintln!("warning: {}: lattice `{}` stops at {t} s: {e}", scene.source, sl.name);
                *state = LatticeState::Closed;
            } else if t >= sl.apply_s {
                *state = LatticeState::Closed;
            }
        }
    }

    /// Starts the scene's region tools whose time has come and carries the moving ones along
    /// their motions. Each is part of the undo step the timeline draws then (its own, unless
    /// the hands are drawing or another region is moving). A region tool that cannot act (its
    /// copy of the clay would be too large) stops with a warning.
    fn step_regions(&mut self, t: f32) {
        let scene = self.scene;
        let mut new_parts: Vec<(&SceneRegion, Vec<Isometry>)> = Vec::new();
        for (state, sr) in self.regions.iter_mut().zip(&scene.regions) {
            let warn = |e: crate::parts::RegionError| {
                eprintln!(
                    "warning: {}: the {} at {} s stops at {t} s: {e}",
                    scene.source,
                    region_name(sr),
                    sr.time_s
                );
                RegionState::Done
            };
            // It acts on its part's clay, in that part's frame, through the symmetry's images
            // there.
            let frame = self.assembly.frame_of(sr.part);
            let field = self.assembly.field_mut(&mut self.field, sr.part);
            if matches!(state, RegionState::Waiting) && t >= sr.time_s {
                if !field.in_stroke() {
                    field.begin_stroke();
                    own(&mut self.owns_stroke, &mut self.opened, sr.part);
                }
                let images: Vec<Isometry> = match frame {
                    Some(frame) => self.images.iter().map(|i| image_in_part(i, &frame)).collect(),
                    None => self.images.clone(),
                };
                *state = match sr.action {
                    RegionAction::Inflate(distance_m) => {
                        inflate(field, &sr.region, distance_m, &images);
                        RegionState::Done
                    }
                    RegionAction::Drag(RegionOp::Copy) if sr.count > 1 => {
                        copy_repeated(field, &sr.region, sr.motion, sr.count, &images)
                            .map_or_else(warn, |_| RegionState::Done)
                    }
                    RegionAction::Drag(op) => RegionDrag::start(field, sr.region.clone(), op, &images)
                        .map_or_else(warn, |d| RegionState::Moving(Box::new(d))),
                    // Made once the loop lets go of the part's field.
                    RegionAction::CopyToPart => {
                        new_parts.push((sr, images));
                        RegionState::Done
                    }
                };
            }
            let RegionState::Moving(drag) = state else { continue };
            let s = if sr.duration_s > 0.0 { ((t - sr.time_s) / sr.duration_s).clamp(0.0, 1.0) } else { 1.0 };
            match drag.update(field, sr.motion.fraction(s)) {
                Ok(_) if s < 1.0 => {}
                Ok(_) => *state = RegionState::Done,
                Err(e) => *state = warn(e),
            }
        }
        for (sr, images) in new_parts {
            if let Err(e) = self.add_copied_part(sr.part, &sr.region, &images, sr.name.as_deref()) {
                eprintln!("warning: {}: the copy to part at {} s is not made: {e}", scene.source, sr.time_s);
            }
        }
    }

    /// The scene's region tools moving now, with their scene entries.
    pub fn moving_regions(&self) -> impl Iterator<Item = (&'s SceneRegion, &RegionDrag)> + '_ {
        self.regions.iter().zip(&self.scene.regions).filter_map(|(state, sr)| match state {
            RegionState::Moving(d) => Some((sr, &**d)),
            _ => None,
        })
    }

    /// Writes into the clay what the open lattices changed since they last wrote: call before
    /// the clay is meshed, measured or saved while a lattice is open.
    pub fn sync_lattices(&mut self) {
        if let Some(held) = &mut self.held {
            if let Err(e) = held.sync(self.assembly.field_mut(&mut self.field, held.part())) {
                eprintln!("warning: the lattice held open stops, its clay put back: {e}");
                self.cancel_lattice();
            }
        }
        let scene = self.scene;
        for (state, sl) in self.lattices.iter_mut().zip(&scene.lattices) {
            let LatticeState::Open(lattice, pending) = state else { continue };
            if pending.is_empty() {
                continue;
            }
            let field = self.assembly.field_mut(&mut self.field, sl.part);
            if let Err(e) = lattice.write(field, std::mem::replace(pending, Aabb::EMPTY)) {
                eprintln!("warning: {}: lattice `{}` stops: {e}", scene.source, sl.name);
                *state = LatticeState::Closed;
            }
        }
    }

    /// Opens a lattice of `spec` (the active part's frame) over the active part's clay, held
    /// until [`Playback::apply_lattice`] or [`Playback::cancel_lattice`]: the steps open are
    /// closed first, and the part's stroke stays open while it is held, so that its whole
    /// session is one undo step. Refused, with a sentence, while one is held, on a locked part,
    /// or when the lattice cannot open.
    pub fn open_lattice(&mut self, spec: &crate::lattice::LatticeSpec) -> Result<(), String> {
        if self.held.is_some() {
            return Err("a lattice is open already: apply it or put the clay back first".into());
        }
        self.active_target()?;
        self.close_steps();
        let part = self.assembly.active();
        let field = self.assembly.field_mut(&mut self.field, part);
        let held = HeldLattice::open(field, part, spec).map_err(|e| format!("cannot open a lattice: {e}"))?;
        field.begin_stroke();
        self.held = Some(held);
        Ok(())
    }

    /// Opens the lattice a sculpt file stored (see [`crate::io::StoredLattice`]) over its
    /// part's clay, which the file holds as it was when the lattice opened, shaped as it was
    /// saved and held open as [`Playback::open_lattice`] holds it; its part becomes the active
    /// one.
    pub fn reopen_lattice(&mut self, stored: &crate::io::StoredLattice) -> Result<(), String> {
        if self.held.is_some() {
            return Err("a lattice is open already: apply it or put the clay back first".into());
        }
        if stored.part >= self.assembly.parts().len() {
            return Err(format!("its lattice lies over part {}, which it has not", stored.part));
        }
        self.set_active_part(stored.part);
        let field = self.assembly.field_mut(&mut self.field, stored.part);
        let held = HeldLattice::reopen(field, stored).map_err(|e| format!("its lattice cannot open: {e}"))?;
        field.begin_stroke();
        self.held = Some(held);
        self.sync_lattices();
        Ok(())
    }

    /// Calls `f` with the sculpt as a file stores it: the held lattice's part (if one is held)
    /// as it was when the lattice opened, beside its closed history, and the lattice
    /// ([`HeldLattice::stored`]); the lattice's work is back as it was when `f` returns.
    pub fn as_stored<R>(
        &mut self,
        f: impl FnOnce(&Playback<'s>, Option<&crate::io::StoredLattice>) -> R,
    ) -> R {
        self.sync_lattices();
        let Some(part) = self.held.as_ref().map(HeldLattice::part) else { return f(self, None) };
        let stored = self.held.as_ref().map(HeldLattice::stored);
        self.assembly.field_mut(&mut self.field, part).swap_open_stroke();
        let out = f(self, stored.as_ref());
        self.assembly.field_mut(&mut self.field, part).swap_open_stroke();
        out
    }

    /// Has the autosave session store the held lattice once it has stopped changing (it is the
    /// same as at the last call), and forget it as soon as it is applied or put back: call once
    /// a frame, after the hands have driven it. A crash then recovers the lattice as it was when
    /// it last stood still, over its clay as it was when it opened.
    pub fn keep_lattice(&mut self) {
        let now = self.held.as_ref().map(HeldLattice::stored);
        // A lattice closed is forgotten at once; one held is stored once it stands still.
        let settled = now.is_none() || now == self.lattice_seen;
        if settled && now != self.lattice_kept {
            if let Some(a) = &mut self.autosave {
                a.set_lattice(now.clone());
            }
            self.lattice_kept = now.clone();
        }
        self.lattice_seen = now;
    }

    /// The lattice held open, if any.
    pub fn held_lattice(&self) -> Option<&HeldLattice> {
        self.held.as_ref()
    }

    /// The lattice held open, to pick, drag and shape its controls (written into the clay by
    /// [`Playback::sync_lattices`]).
    pub fn held_lattice_mut(&mut self) -> Option<&mut HeldLattice> {
        self.held.as_mut()
    }

    /// Applies the lattice held open: the clay keeps its deformation, one undo step, journaled.
    /// Returns whether one was open.
    pub fn apply_lattice(&mut self) -> bool {
        let applied = self.apply_held();
        if applied {
            self.close_steps();
        }
        applied
    }

    /// Ends the held lattice's step, its last changes written; the caller journals it.
    fn apply_held(&mut self) -> bool {
        let Some(mut held) = self.held.take() else { return false };
        let field = self.assembly.field_mut(&mut self.field, held.part());
        if let Err(e) = held.sync(field) {
            eprintln!("warning: the lattice's last change is left out: {e}");
        }
        field.end_stroke();
        true
    }

    /// Closes the lattice held open and puts its part's clay back bit for bit as it was when
    /// it opened, leaving no undo step. Returns whether one was open.
    pub fn cancel_lattice(&mut self) -> bool {
        let Some(held) = self.held.take() else { return false };
        self.assembly.field_mut(&mut self.field, held.part()).abandon_stroke();
        self.close_steps();
        true
    }

    /// The region the region tools act on with the tool at `pose` (world): the box selected on
    /// the active part, else `tool`'s shape there; with the part, the hand's pose and the
    /// symmetry's images in the part's frame. Refused, with a sentence, while a lattice or a
    /// region is held, or on a locked part.
    fn region_target(
        &mut self,
        tool: Tool,
        pose: Pose,
    ) -> Result<(usize, Region, Pose, Vec<Isometry>), String> {
        if self.held.is_some() {
            return Err("a lattice is open: apply it or put the clay back before a region tool acts".into());
        }
        if self.held_region.is_some() {
            return Err("a region is held already: let it go first".into());
        }
        self.active_target()?;
        let (tool, local, images) = self.in_active_part(tool, pose, &self.images);
        let part = self.assembly.active();
        let region = match &self.selection {
            Some((on, selected)) if *on == part => selected.clone(),
            _ => Region::of_tool(&tool, local),
        };
        Ok((part, region, local, images))
    }

    /// Takes the region the region tools act on (see [`Playback::selection`]; else `tool`'s
    /// shape at `pose`, world) from the active part's clay, and its images under the symmetry,
    /// for `op`: held (the part's stroke open) until [`Playback::let_go_region`], carried by
    /// [`Playback::carry_region`]. Refused, with a sentence, while a lattice or a region is
    /// held, while a stroke is drawn on the part, on a locked part, or when the region cannot
    /// be taken.
    pub fn grab_region(&mut self, op: RegionOp, tool: Tool, pose: Pose) -> Result<(), String> {
        let (part, region, local, images) = self.region_target(tool, pose)?;
        let field = self.assembly.field_mut(&mut self.field, part);
        self.held_region = Some(HeldRegion::grab(field, part, op, region, local, &images)?);
        Ok(())
    }

    /// Carries the held region to where the hand is now, at `pose` (world); `None` when no
    /// region is held.
    pub fn carry_region(&mut self, pose: Pose) -> Option<Result<crate::parts::RegionStats, String>> {
        let held = self.held_region.as_mut()?;
        let local = self.assembly.frame_of(held.part()).map_or(pose, |f| f.local_pose(pose));
        Some(held.carry(self.assembly.field_mut(&mut self.field, held.part()), local))
    }

    /// Lets the held region go where it was last carried: one undo step, journaled. Returns
    /// whether one was held.
    pub fn let_go_region(&mut self) -> bool {
        let held = self.let_go_held_region();
        if held {
            self.journal();
        }
        held
    }

    /// Ends the held region's step (a box selected follows the clay it carried); the caller
    /// journals it.
    fn let_go_held_region(&mut self) -> bool {
        let Some(held) = self.held_region.take() else { return false };
        let part = held.part();
        let landed = held.let_go(self.assembly.field_mut(&mut self.field, part));
        if let (Some(landed), Some((on, selected))) = (landed, &mut self.selection) {
            if *on == part {
                *selected = landed;
            }
        }
        true
    }

    /// The region the desk or the headset carries, if any.
    pub fn held_region(&self) -> Option<&HeldRegion> {
        self.held_region.as_ref()
    }

    /// Selects the box from corner `from_m` to corner `to_m` (world) on the active part,
    /// axis-aligned in its frame: the region tools act on it from then on instead of the
    /// tool's shape, until it is cleared, another part is made active or another sculpt is
    /// opened. A box thinner than [`MIN_BOX_VOXELS`] of the part on some axis clears the
    /// selection. Returns the box's size (the part's frame, metres), or none when cleared.
    pub fn select_box(&mut self, from_m: Vec3, to_m: Vec3) -> Option<Vec3> {
        let part = self.assembly.active();
        let local = |p: Vec3| self.assembly.frame_of(part).map_or(p, |f| f.local_point(p));
        let min_m = MIN_BOX_VOXELS * self.assembly.field(&self.field, part).transform().voxel_size_m;
        let region = box_between(local(from_m), local(to_m), min_m);
        let size = region.as_ref().map(|r| 2.0 * r.shape.half_extents_m());
        self.selection = region.map(|r| (part, r));
        size
    }

    /// The box selected: the part it lies in and the box in that part's frame.
    pub fn selection(&self) -> Option<(usize, &Region)> {
        self.selection.as_ref().map(|(part, r)| (*part, r))
    }

    /// Copies the clay of the active part within the region the region tools act on (see
    /// [`Playback::grab_region`]), and within its images, into a new part after the others:
    /// named after the active one, placed as it is, at its voxel size, united with the rest
    /// (Hua and Qin's copy and compose). The new part becomes the active one, so that the tools,
    /// the desk's part device and the headset's support grip move it. One undo step, which
    /// takes the part away again; journaled. Returns the new part's index. Refused, with a
    /// sentence, as [`Playback::grab_region`] is, past [`crate::io::MAX_PARTS`] parts, or where
    /// no clay lies within the region.
    pub fn copy_to_new_part(&mut self, tool: Tool, pose: Pose) -> Result<usize, String> {
        let (part, region, _, images) = self.region_target(tool, pose)?;
        self.close_steps();
        let added = self.add_copied_part(part, &region, &images, None)?;
        self.set_active_part(added);
        Ok(added)
    }

    /// Adds a part holding the clay of part `part` within `region` and its `images` (that
    /// part's frame), named `name` (else after that part), placed and sized as it is and
    /// united with the rest: one undo step, journaled. Returns its index.
    fn add_copied_part(
        &mut self,
        part: usize,
        region: &Region,
        images: &[Isometry],
        name: Option<&str>,
    ) -> Result<usize, String> {
        if self.assembly.parts().len() >= crate::io::MAX_PARTS {
            return Err(format!("a sculpt holds at most {} parts", crate::io::MAX_PARTS));
        }
        let source = self.assembly.field(&self.field, part);
        let mut copy = Field::new(source.transform().voxel_size_m, source.iso());
        copy.set_history_config(super::history_config());
        copy.begin_stroke();
        let copied = crate::parts::copy_into(source, region, images, &mut copy);
        copy.end_stroke();
        copied.map_err(|e| format!("cannot copy the region into a new part: {e}"))?;
        if copy.mass() <= 0.0 {
            return Err("no clay within the region to copy into a new part".into());
        }
        let layouts = self.assembly.parts();
        let base = name.map_or_else(|| format!("{} copy", layouts[part].name), str::to_owned);
        let name = (1..)
            .map(|i| if i == 1 { base.clone() } else { format!("{base} {i}") })
            .find(|n| layouts.iter().all(|p| &p.name != n))
            .expect("a free name");
        let layout = crate::scene::ScenePart {
            name,
            op: crate::parts::Csg::Union,
            visible: true,
            locked: false,
            ..layouts[part].clone()
        };
        let added = self.assembly.add_part(&self.field, layout, copy);
        // The snapshot lists the part before the journal holds its clay.
        self.keep_layouts();
        self.journal();
        Ok(added)
    }

    /// Moves the surface of the active part's clay within the region the region tools act on
    /// (see [`Playback::grab_region`]), and within its images, out (`distance_m` > 0) or in:
    /// one undo step, journaled. Refused, with a sentence, as [`Playback::grab_region`] is;
    /// says so where no surface lies within the region.
    pub fn swell_region(&mut self, tool: Tool, pose: Pose, distance_m: f32) -> Result<(), String> {
        let name = if distance_m > 0.0 { "inflate" } else { "deflate" };
        let (part, region, _, images) = self.region_target(tool, pose)?;
        let field = self.assembly.field_mut(&mut self.field, part);
        if field.in_stroke() {
            return Err(format!("cannot {name} the region while a stroke is drawn"));
        }
        field.begin_stroke();
        let counters = inflate(field, &region, distance_m, &images);
        field.end_stroke();
        self.journal();
        if counters.dirtied == 0 {
            return Err(format!("no clay surface within the region to {name}"));
        }
        Ok(())
    }

    /// The scene's lattices open now, with their scene entries.
    pub fn open_lattices(&self) -> impl Iterator<Item = (&'s SceneLattice, &Lattice)> + '_ {
        self.lattices.iter().zip(&self.scene.lattices).filter_map(|(state, sl)| match state {
            LatticeState::Open(l, _) => Some((sl, &**l)),
            _ => None,
        })
    }

    /// Whether `hand` holds `tool` active and still at `pose` over `from ..= to` (a support's
    /// hold: it holds nothing while its hand moves it or lets it go). A live hand holds its
    /// support while it keeps it on, wherever the hand is: the support stays where it was put.
    fn held_still(&self, hand: Hand, tool: usize, pose: Pose, from: f32, to: f32) -> bool {
        // Interpolating between equal keys may round the rotation by an ulp: still is within a
        // micrometre and three milliradians.
        let same = |p: Pose| {
            p.position_m.distance(pose.position_m) <= 1e-6
                && p.rotation.dot(pose.rotation).abs() >= 1.0 - 1e-6
        };
        if self.live.is_some() {
            return self.state_at(hand, to).is_some_and(|s| s.tool == tool && s.active);
        }
        let mid = 0.5 * (from + to);
        [from, mid, to]
            .iter()
            .all(|&t| self.state_at(hand, t).is_some_and(|s| s.tool == tool && same(s.pose)))
            && self.state_at(hand, mid).is_some_and(|s| s.active)
    }

    /// Starts a push over the interval `t ..= t + step_s`.
    fn start_push(&self, pushing: &[(Hand, usize)], t: f32, step_s: f32) -> Push {
        let scene = self.scene;
        let mut tools = Vec::new();
        let mut bodies = Vec::new();
        let mut reach = Vec::new();
        for hand in Hand::BOTH {
            let Some(state) = self.state_at(hand, t) else { continue };
            let tool = &self.tools[state.tool];
            let support = match tool.action {
                // A support holds the clay only if its hand holds it still as the push starts.
                Action::Support if self.held_still(hand, state.tool, state.pose, t, t + step_s) => true,
                Action::Push if pushing.contains(&(hand, state.tool)) => false,
                _ => continue,
            };
            let shape = crate::clay::ClayShape::Tool { shape: tool.shape.clone(), scale: tool.scale };
            let first = reach.len();
            for &image in &self.images {
                let (pose, mirrored) =
                    if image == Isometry::IDENTITY { (state.pose, false) } else { image.pose(&state.pose) };
                tools.push(ClayTool { shape: shape.clone(), pose, support, mirrored });
                bodies.push((Some(hand), state.tool, image));
            }
            // The window holds every pose this hand's keys give the tool.
            let half = tool.half_extents_m() / tool.scale + Vec3::splat(scene.voxel_size_m * 4.0);
            for key in self.keys(hand).iter().filter(|k| k.tool == state.tool) {
                reach.push(ToolFrame::new(key.pose, tool.scale).world_bounds(half));
            }
            if self.live.is_some() {
                // A live hand's path is unknown: room for it to move.
                let room = half + Vec3::splat(LIVE_REACH_M) / tool.scale;
                reach.push(ToolFrame::new(state.pose, tool.scale).world_bounds(room));
            }
            reach.push(ToolFrame::new(state.pose, tool.scale).world_bounds(half));
            // The images' paths are the images of the hand's.
            let own: Vec<Aabb> = reach[first..].to_vec();
            for image in self.images.iter().skip(1) {
                reach.extend(own.iter().map(|b| b.transformed(&image.to_matrix())));
            }
        }
        if let Some(y) = scene.virtual_clay.table_y_m {
            tools.push(ClayTool::table(Vec3::new(0.0, y, 0.0)));
            bodies.push((None, usize::MAX, Isometry::IDENTITY));
        }
        let (mut lo, mut hi) = window_around(&self.field, &reach, CLAY_MARGIN_VOXELS);
        if let Some(y) = scene.virtual_clay.table_y_m {
            // Room under the table's surface for its band.
            let table = self.field.transform().world_to_index(Vec3::new(0.0, y, 0.0)).y.floor() as i32 - 4;
            lo.y = lo.y.max(table);
            hi.y = hi.y.max(lo.y + 2);
        }
        let params = ClayParams {
            fluidity: scene.virtual_clay.fluidity,
            step_s: scene.virtual_clay.step_s,
            ..ClayParams::default()
        };
        let mut clay = Clay::new(&self.field, lo, hi, tools, params);
        if !scene.virtual_clay.fixed_boxes_m.is_empty() {
            let transform = *self.field.transform();
            let boxes: Vec<Aabb> =
                scene.virtual_clay.fixed_boxes_m.iter().map(|&(min, max)| Aabb { min, max }).collect();
            clay.fix_where(|p| {
                let w = transform.index_to_world(p.as_vec3());
                boxes.iter().any(|b| w.cmpge(b.min).all() && w.cmple(b.max).all())
            });
        }
        Push { clay, bodies }
    }

    /// The tools as built for this playback, in the scene's order.
    pub fn tools(&self) -> &[Tool] {
        &self.tools
    }

    /// The form of the lattices the desk and the headset open (a cubic NURBS 4³ at first).
    pub fn lattice_form(&self) -> crate::lattice::LatticeForm {
        self.lattice_form
    }

    /// Changes the form of the lattices opened from now on (brought within its limits).
    pub fn set_lattice_form(&mut self, form: crate::lattice::LatticeForm) {
        self.lattice_form = form.within_limits();
    }

    /// The symmetry the hands' strokes and pushes act through.
    pub fn symmetry(&self) -> &Symmetry {
        &self.symmetry
    }

    /// Changes the symmetry: the strokes and pushes that start from now on act through it.
    pub fn set_symmetry(&mut self, symmetry: Symmetry) {
        if symmetry != self.symmetry {
            if let Some(a) = &mut self.autosave {
                a.set_symmetry(symmetry);
            }
        }
        self.symmetry = symmetry;
        self.images = symmetry.images();
    }

    /// The images of the symmetry, the identity first.
    pub fn images(&self) -> &[Isometry] {
        &self.images
    }

    /// The stroke a hand is drawing, if its action is on.
    pub fn stroke(&self, hand: Hand) -> Option<&Stroke> {
        self.strokes[slot(hand)].as_ref().map(|(_, _, s)| s)
    }

    /// Where each hand holds which tool now: `(tool index, pose)` for the hands with keys (or
    /// live), as [`Playback::hand`] says.
    pub fn hands(&self) -> Vec<(usize, Pose)> {
        Hand::BOTH.iter().filter_map(|&h| self.hand(h)).collect()
    }

    /// Where `hand`'s tool is now: `(tool index, pose)`. A live hand's support that holds the
    /// clay in a push is where the hand put it, wherever the hand has gone since.
    pub fn hand(&self, hand: Hand) -> Option<(usize, Pose)> {
        let state = self.state_at(hand, self.time_s)?;
        let placed = self.live.is_some() && state.active && self.tools[state.tool].action == Action::Support;
        let put = self.push.as_ref().filter(|_| placed).and_then(|push| {
            let body = push.bodies.iter().position(|&b| b == (Some(hand), state.tool, Isometry::IDENTITY))?;
            push.clay.poses().get(body).copied()
        });
        Some((state.tool, put.unwrap_or(state.pose)))
    }
}

/// A tool at `pose` (world), acting through the symmetry's `images`, as it acts on a part
/// placed at `frame` (`None`: at rest in the world): in the part's frame and at its scale.
/// Notes that the timeline opened the stroke on part `part`: the first part's in `first`, the
/// others' in `others`.
fn own(first: &mut bool, others: &mut std::collections::BTreeSet<usize>, part: usize) {
    if part == 0 {
        *first = true;
    } else {
        others.insert(part);
    }
}

fn in_part(
    frame: Option<Placement>,
    mut tool: Tool,
    pose: Pose,
    images: &[Isometry],
) -> (Tool, Pose, Vec<Isometry>) {
    match frame {
        None => (tool, pose, images.to_vec()),
        Some(frame) => {
            tool.scale /= frame.scale;
            let images = images.iter().map(|i| image_in_part(i, &frame)).collect();
            (tool, frame.local_pose(pose), images)
        }
    }
}

/// A field per part of `scene`, holding the scene's initial clay of the parts `which` takes,
/// whatever it costs (for scenes known to be small; see [`initial_parts`]).
fn scene_parts(scene: &Scene, which: impl Fn(usize) -> bool) -> Vec<Field> {
    let mut fields: Vec<Field> = (0..scene.parts.len()).map(|p| empty_field(scene, p)).collect();
    for primitive in scene.clay.iter().filter(|c| which(c.part)) {
        rasterize_solid(&mut fields[primitive.part], &primitive.solid, primitive.op, primitive.colour);
    }
    fields
}

/// An empty field for the scene's part `part`: its voxel size, the scene's iso-level, the
/// station's history.
fn empty_field(scene: &Scene, part: usize) -> Field {
    let mut field = Field::new(scene.parts[part].voxel_size_m, scene.iso);
    field.set_history_config(super::history_config());
    field
}

/// Points of initial clay past which its build says what it builds and shows its progress:
/// about a second's work.
const LONG_BUILD_POINTS: f64 = 5e7;

/// The scene's initial clay, rasterised into a new field: refused before any of it is built
/// when its estimate is over the memory budget (see [`super::budget`]); a long build says what
/// it builds and shows its progress on the terminal; a stopping signal (SIGINT, SIGTERM or
/// SIGHUP, where the station handles them) breaks it off between two slabs of bricks, with an
/// error that says so (nothing has been sculpted yet: nothing is lost).
pub fn initial_parts(scene: &Scene) -> Result<Vec<Field>> {
    let cost = super::budget::scene_clay_cost(scene);
    super::budget::admit_scene(scene, &cost)?;
    let mut fields: Vec<Field> = (0..scene.parts.len()).map(|p| empty_field(scene, p)).collect();
    let long = cost.points > LONG_BUILD_POINTS;
    if long {
        eprintln!(
            "building the initial clay of {}: about {:.3e} bricks, {} of memory",
            scene.source,
            cost.keys,
            super::budget::size_text(super::budget::clay_bytes(&cost))
        );
    }
    let bar = if long { indicatif::ProgressBar::new(1000) } else { indicatif::ProgressBar::hidden() };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {percent}%")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message("building the clay");
    let count = scene.clay.len() as f64;
    for (i, primitive) in scene.clay.iter().enumerate() {
        let mut progress = |f: f64| {
            bar.set_position(((i as f64 + f) / count * 1000.0) as u64);
            match super::signals::received() {
                Some(_) => std::ops::ControlFlow::Break(()),
                None => std::ops::ControlFlow::Continue(()),
            }
        };
        let whole = rasterize_solid_in_slabs(
            &mut fields[primitive.part],
            &primitive.solid,
            primitive.op,
            primitive.colour,
            &mut progress,
        );
        // A signal during a solid's last slab is the station's to handle once it runs.
        if !whole {
            bar.abandon();
            let signal = super::signals::received().map_or("a signal", super::signals::name);
            bail!(
                "{signal} received while building the initial clay of {}: stopped before any sculpting",
                scene.source
            );
        }
    }
    bar.finish_and_clear();
    Ok(fields)
}

/// The freeform tools among `tools`, as a sculpt stores them (each with its index).
fn stored_tools(tools: &[Tool]) -> Vec<StoredTool> {
    let freeform = tools.iter().enumerate().filter_map(|(i, t)| match &t.shape {
        ToolShape::Freeform(f) => Some((i, f)),
        _ => None,
    });
    freeform
        .map(|(i, f)| StoredTool {
            index: i as u32,
            dims: f.dims().to_array(),
            spacing_m: f.spacing_m(),
            samples: f.samples().to_vec(),
        })
        .collect()
}

/// Puts `stored` freeform tools in place of those of `tools` at their indices (a stored tool
/// whose index is not a freeform tool is left out); returns how many it put.
fn restore_tools(tools: &mut [Tool], stored: &[StoredTool]) -> usize {
    let mut put = 0;
    for s in stored {
        let Some(tool) = tools.get_mut(s.index as usize) else { continue };
        if !matches!(tool.shape, ToolShape::Freeform(_)) {
            continue;
        }
        let dims = crate::math::UVec3::from_array(s.dims);
        if let Some(f) = Freeform::from_samples(s.samples.clone(), dims, s.spacing_m) {
            tool.shape = ToolShape::Freeform(Arc::new(f));
            put += 1;
        }
    }
    put
}

/// The tool a scene describes; a freeform one copies the clay in its region of `field`.
pub fn build_tool(t: &SceneTool, field: &Field) -> Tool {
    let shape = match &t.shape {
        SceneToolShape::Shape(s) => s.clone(),
        SceneToolShape::Freeform { min_m, max_m } => {
            crate::tool::ToolShape::Freeform(Arc::new(Freeform::from_world_box(field, *min_m, *max_m)))
        }
    };
    Tool {
        shape,
        scale: t.scale,
        action: t.action,
        colour: t.colour,
        spacing: t.spacing,
        level_samples: t.level_samples,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{IVec3, Vec3};

    const STROKE: &str = r#"
[field]
voxel_size_m = 0.002
[[tool]]
name = "t"
radius_m = 0.01
action = "add"
[[key]]
time_s = 0.0
tool = "t"
position_m = [0.0, 0.0, 0.0]
active = true
[[key]]
time_s = 1.0
tool = "t"
position_m = [0.1, 0.0, 0.0]
"#;

    #[test]
    fn a_stroke_deposits_along_its_path_whatever_the_step() {
        let fine = Scene::parse(&format!("[timeline]\nstep_s = 0.001\n{STROKE}"), "fine", None).unwrap();
        let coarse = Scene::parse(&format!("[timeline]\nstep_s = 0.3\n{STROKE}"), "coarse", None).unwrap();
        let mut a = Playback::new(&fine);
        let mut b = Playback::new(&coarse);
        a.advance_to(1.0, |_| {});
        b.advance_to(1.0, |_| {});
        assert!(a.field().mass() > 0.0);
        assert!((a.field().mass() - b.field().mass()).abs() < 1e-3 * a.field().mass());
        // Clay at both ends and the middle of the path, none beyond.
        for x in [0, 25, 50] {
            assert!(a.field().density(IVec3::new(x, 0, 0)) > 0.99, "x = {x}");
        }
        assert_eq!(a.field().density(IVec3::new(62, 0, 0)), 0.0);
        assert_eq!(a.hands()[0].1.position_m, Vec3::new(0.1, 0.0, 0.0));
    }

    #[test]
    fn each_scripted_stroke_is_one_undo_step() {
        let scene = Scene::default_scene();
        let mut p = Playback::new(&scene);
        let initial = p.field().clone();
        p.advance_to(scene.captures[0].time_s, |_| {});
        // The groove, then the toothpaste band.
        assert_eq!(p.field().history_stats().undo_in_memory + usize::from(p.field().in_stroke()), 2);
        let field = p.field_mut();
        assert!(field.undo().unwrap() && field.undo().unwrap());
        assert!(!field.undo().unwrap());
        assert!(field.same_samples(&initial), "undoing both strokes gives back the initial clay");
    }

    #[test]
    fn the_lattice_scene_applies_each_lattice_as_one_undo_step() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/lattice-bars.toml");
        let scene = Scene::load(&path).unwrap();
        let mut p = Playback::new(&scene);
        let initial = p.field().clone();
        assert_eq!(p.open_lattices().count(), 3, "the lattices open at 0 s");
        p.advance_to(1.0, |_| {});
        p.sync_lattices();
        assert!(!p.field().same_samples(&initial) && p.field().in_stroke());
        p.advance_to(2.0, |_| {});
        assert_eq!(p.open_lattices().count(), 0, "applied at 2 s");
        assert!(!p.field().in_stroke());
        // Swelled, twisted (its matter kept within a few per cent) and bent.
        let m = p.field().mass() / initial.mass();
        assert!(m > 1.01 && m < 1.2, "mass ratio {m}");
        let field = p.field_mut();
        assert_eq!(field.history_stats().undo_in_memory, 1, "the three lattices, applied together");
        assert!(field.undo().unwrap());
        assert!(field.same_samples(&initial), "the undo gives back the clay exactly");
    }

    #[test]
    fn the_pushing_scenes_keep_their_matter_and_make_one_undo_step() {
        for name in ["bend-bar", "push-print", "poke-hole"] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"));
            let scene = Scene::load(&path).unwrap();
            let mut p = Playback::new(&scene);
            let initial = p.field().clone();
            let end = scene.timeline.duration_s() + 0.1;
            // The mass the field holds after every step of the timeline, not only at its end.
            let m0 = initial.mass();
            let mut worst = 0.0f64;
            while p.time_s() < end {
                p.step_towards(end);
                worst = worst.max((p.matter() - m0).abs() / m0);
            }
            assert!(worst < 0.01, "{name}: the mass strayed by {:.3} % during the timeline", worst * 100.0);
            let m1 = p.field().mass();
            assert!((m1 - m0).abs() / m0 < 0.01, "{name}: mass {m1} from {m0}");
            assert!(!p.field().same_samples(&initial), "{name}: the push moved clay");
            assert_eq!(p.field().history_stats().undo_in_memory, 1, "{name}: one push, one undo step");
            assert!(p.field_mut().undo().unwrap());
            assert!(p.field().same_samples(&initial), "{name}: undo takes the push back");
        }
    }

    #[test]
    fn the_default_scene_plays_to_its_capture() {
        let scene = Scene::default_scene();
        let mut p = Playback::new(&scene);
        let initial = p.field().mass();
        let mut steps = 0;
        p.advance_to(scene.captures[0].time_s, |_| steps += 1);
        assert!(steps >= 200, "fixed steps of 1/90 s over 2.5 s, got {steps}");
        assert_ne!(p.field().mass(), initial);
        assert_eq!(p.hands().len(), 2);
    }

    /// A bar on a support block held by the left hand, its right end pushed down by the right
    /// hand's ball; `left_keys` are the left hand's keys. Returns how far (voxels) the bar's
    /// left part sank.
    fn left_end_sinks(left_keys: &str) -> f64 {
        let text = format!(
            r#"
[field]
voxel_size_m = 0.002
[virtual_clay]
fluidity = 1.0
[[clay]]
shape = "bar"
length_m = 0.1
radius_m = 0.008
[[tool]]
name = "block"
shape = "box"
size_m = [0.04, 0.016, 0.03]
action = "support"
[[tool]]
name = "ball"
radius_m = 0.008
action = "push"
[[key]]
time_s = 0.0
tool = "ball"
position_m = [0.036, 0.018, 0.0]
active = true
[[key]]
time_s = 0.8
tool = "ball"
position_m = [0.036, -0.014, 0.0]
{left_keys}
"#
        );
        let scene = Scene::parse(&text, "support.toml", None).unwrap();
        let mut p = Playback::new(&scene);
        // Mean height (voxels) of the matter over the left part of the bar.
        let left = |f: &Field| {
            let (mut m, mut my) = (0.0f64, 0.0f64);
            for z in -8..=8 {
                for y in -24..=12 {
                    for x in -22..=-12 {
                        let d = f64::from(f.density(IVec3::new(x, y, z)));
                        m += d;
                        my += d * f64::from(y);
                    }
                }
            }
            my / m
        };
        let before = left(p.field());
        p.advance_to(0.9, |_| {});
        before - left(p.field())
    }

    /// The left hand's keys for the block under the bar's left part: (time, height, active).
    fn block_keys(keys: &[(f32, f32, bool)]) -> String {
        keys.iter()
            .map(|&(t, y, active)| {
                format!("[[key]]\ntime_s = {t:?}\nhand = \"left\"\ntool = \"block\"\nposition_m = [-0.03, {y:?}, 0.0]\nactive = {active}\n")
            })
            .collect()
    }

    #[test]
    fn a_support_held_still_as_the_push_starts_holds_the_clay() {
        let held = left_end_sinks(&block_keys(&[(0.0, -0.016, true), (1.0, -0.016, false)]));
        assert!(held.abs() < 1.0, "the part on the held block moved {held:.2} voxels");
    }

    #[test]
    fn a_support_still_moving_as_the_push_starts_holds_nothing() {
        // The block, touching the bar, still slides up as the push starts: it is not held
        // still, so it holds nothing and the push carries the whole bar down.
        let sliding =
            left_end_sinks(&block_keys(&[(0.0, -0.017, true), (0.3, -0.016, true), (1.0, -0.016, false)]));
        assert!(sliding > 4.0, "the bar's left part sank {sliding:.2} voxels");
    }

    #[test]
    fn a_support_let_go_during_the_push_holds_no_more() {
        let held = left_end_sinks(&block_keys(&[(0.0, -0.016, true), (1.0, -0.016, false)]));
        let let_go =
            left_end_sinks(&block_keys(&[(0.0, -0.016, true), (0.3, -0.016, false), (1.0, -0.016, false)]));
        assert!(let_go > held + 2.0, "let go after 0.3 s: {let_go:.2} voxels; held: {held:.2}");
    }

    /// `scene` played with autosave (syncing fast) in `root`.
    fn autosaved_bar<'s>(scene: &'s Scene, root: &std::path::Path) -> Playback<'s> {
        let config = crate::io::autosave::AutosaveConfig {
            sync_interval: std::time::Duration::from_millis(5),
            ..Default::default()
        };
        Playback::new_autosaved(scene, |field, besides| {
            let disk = std::sync::Arc::new(crate::io::autosave::LocalDisk);
            Some(Autosave::start_with_tools(root, field, (None, besides), "test", config, disk).unwrap())
        })
        .unwrap()
    }

    fn bar_scene() -> Scene {
        let text = "[field]\nvoxel_size_m = 0.002\n[[clay]]\nshape = \"box\"\nsize_m = [0.08, 0.02, 0.02]\n";
        Scene::parse(text, "bar", None).unwrap()
    }

    fn temp_root(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("argile-playback-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    /// The only session folder under `root` (its owner, this process, still runs, so it is
    /// not listed as unclosed), and its sculpt recovered.
    fn recovered(root: &std::path::Path) -> crate::io::autosave::Recovered {
        let dirs: Vec<_> = std::fs::read_dir(root).unwrap().map(|e| e.unwrap().path()).collect();
        let [dir] = &dirs[..] else { panic!("one session folder, not {}", dirs.len()) };
        crate::io::autosave::recover(dir).unwrap()
    }

    #[test]
    fn a_crash_with_a_lattice_held_open_recovers_it_as_it_last_stood_over_its_clay_at_rest() {
        let root = temp_root("held-lattice");
        let scene = bar_scene();
        let mut p = autosaved_bar(&scene, &root);
        let at_rest = p.field().clone();
        let region = crate::parts::local_bounds(p.field()).expanded(0.005);
        p.open_lattice(&crate::lattice::LatticeForm::default().over(region)).unwrap();
        p.keep_lattice();
        let held = p.held_lattice_mut().unwrap();
        held.pick_nearest(Vec3::new(0.01, 0.0, 0.0));
        held.add_value(0.3).unwrap();
        // One frame with the edit, one with it standing still: then it is stored.
        p.sync_lattices();
        p.keep_lattice();
        p.sync_lattices();
        p.keep_lattice();
        let stored = p.held_lattice().unwrap().stored();
        assert!(!p.field().same_samples(&at_rest), "the raised value swells the clay");
        // Killed: the playback is gone without closing its session.
        drop(p);
        let r = recovered(&root);
        assert_eq!(r.sculpt.lattice.as_ref(), Some(&stored), "the lattice as it last stood still");
        assert!(r.sculpt.field.same_samples(&at_rest), "the clay as it was when the lattice opened");
        // Opened again, the lattice gives the swelled clay back.
        let again = HeldLattice::reopen(&r.sculpt.field, &stored).unwrap();
        assert_eq!(again.stored(), stored);
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn a_lattice_applied_or_put_back_is_not_recovered_open() {
        let scene = bar_scene();
        for apply in [true, false] {
            let root = temp_root(if apply { "applied-lattice" } else { "put-back-lattice" });
            let mut p = autosaved_bar(&scene, &root);
            let at_rest = p.field().clone();
            let region = crate::parts::local_bounds(p.field()).expanded(0.005);
            p.open_lattice(&crate::lattice::LatticeForm::default().over(region)).unwrap();
            p.held_lattice_mut().unwrap().add_value(0.3).unwrap();
            for _ in 0..2 {
                p.sync_lattices();
                p.keep_lattice();
            }
            match apply {
                true => assert!(p.apply_lattice()),
                false => assert!(p.cancel_lattice()),
            }
            p.keep_lattice();
            let field = p.field().clone();
            let strokes = p.autosave().unwrap().strokes();
            drop(p);
            let r = recovered(&root);
            assert!(r.sculpt.lattice.is_none(), "apply {apply}: no lattice comes back open");
            assert!(r.sculpt.field.same_samples(&field), "apply {apply}: the clay as it was left");
            assert_eq!(r.strokes, strokes);
            assert_eq!(r.sculpt.field.same_samples(&at_rest), !apply);
            std::fs::remove_dir_all(&root).unwrap();
        }
    }

    #[test]
    fn finishing_autosave_with_a_lattice_held_journals_it_applied() {
        let root = temp_root("finish-lattice");
        let scene = bar_scene();
        let mut p = autosaved_bar(&scene, &root);
        let region = crate::parts::local_bounds(p.field()).expanded(0.005);
        p.open_lattice(&crate::lattice::LatticeForm::default().over(region)).unwrap();
        p.held_lattice_mut().unwrap().add_value(0.3).unwrap();
        p.sync_lattices();
        p.keep_lattice();
        let session = p.finish_autosave().unwrap();
        assert!(p.held_lattice().is_none(), "the lattice is applied");
        let field = p.field().clone();
        drop(session);
        let r = recovered(&root);
        assert!(r.sculpt.lattice.is_none());
        assert!(r.sculpt.field.same_samples(&field), "the lattice's work is journaled, applied");
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn a_crash_recovers_the_symmetry_the_strokes_acted_through() {
        let root = temp_root("symmetry");
        let scene = bar_scene();
        let mut p = autosaved_bar(&scene, &root);
        drop(p);
        let r = recovered(&root);
        assert_eq!(r.sculpt.symmetry, Some(scene.symmetry), "the first snapshot holds the scene's");
        std::fs::remove_dir_all(&root).unwrap();
        p = autosaved_bar(&scene, &root);
        let mirrored = crate::parts::Symmetry::mirror(crate::parts::Axis::X);
        assert_ne!(mirrored, scene.symmetry);
        p.set_symmetry(mirrored);
        // Killed: the playback is gone without closing its session.
        drop(p);
        let r = recovered(&root);
        assert_eq!(r.sculpt.symmetry, Some(mirrored), "the symmetry set last");
        std::fs::remove_dir_all(&root).unwrap();
    }
}
