//! The sculpt's parts as a session holds them: the first part's field lives in the playback
//! (the desk's and the headset's tools, pushed clay, lattices and region tools act on it); the
//! other parts' fields, every part's placement, operator and visibility, the composition the
//! mesher reads, and the sculpt-wide undo order live here.
//!
//! Each part's field keeps its own undo history; a sculpt step (a stroke, a push, a region
//! tool) may change several parts at once, so the steps are logged in the order they close,
//! each with the parts it changed, and undo takes back the newest step in every part it
//! changed.

use crate::field::{Field, HistoryError, BRICK_SIZE};
use crate::io::autosave::Besides;
use crate::io::{PartLayout, Sculpt};
use crate::math::{IVec3, Isometry, Mat3, Quat, Vec3};
use crate::parts::{Composition, Csg, PartView, Placement};
use crate::scene::ScenePart;

/// The parts beyond the first, every part's layout, the composition and the undo order.
#[derive(Debug)]
pub struct Assembly {
    parts: Vec<ScenePart>,
    /// The fields of parts 1.. (part 0's is the playback's).
    others: Vec<Field>,
    composition: Option<Composition>,
    /// Closed sculpt steps, oldest first.
    undo: Vec<Step>,
    redo: Vec<Step>,
    /// Per part, the undo steps its field held when last looked at.
    seen: Vec<usize>,
    /// The part the desk's and the headset's tools act on.
    active: usize,
}

/// A closed sculpt step, as undo takes it back.
#[derive(Clone, Debug)]
enum Step {
    /// Strokes (pushes, region tools, lattices) closed on these parts' fields at once.
    Edits(Vec<usize>),
    /// A part carried, turned or scaled from one placement to another.
    Placed { part: usize, from: Placement, to: Placement },
    /// A part added last with its clay as its field's one step; undone, the part is taken away
    /// and kept here (its layout and its field, holding that step to redo).
    Added { part: usize, taken: Option<Box<(ScenePart, Field)>> },
}

/// [`steps`] of every part's field, the first's first.
fn counts(first: &Field, others: &[Field]) -> Vec<usize> {
    std::iter::once(first).chain(others).map(steps).collect()
}

/// Undo steps a field has recorded and not taken back (dropped ones included, so that the
/// count only grows with new steps).
fn steps(field: &Field) -> usize {
    let s = field.history_stats();
    s.undo_in_memory + s.undo_on_disk + s.dropped
}

impl Assembly {
    /// The parts `parts` describes, `others` holding the fields of all but the first.
    pub fn new(parts: Vec<ScenePart>, others: Vec<Field>, first: &Field) -> Self {
        debug_assert_eq!(parts.len(), others.len() + 1);
        let seen = counts(first, &others);
        Self { parts, others, composition: None, undo: Vec::new(), redo: Vec::new(), seen, active: 0 }
    }

    /// The parts' layouts, in composition order.
    pub fn parts(&self) -> &[ScenePart] {
        &self.parts
    }

    /// The part the desk's and the headset's tools act on.
    pub fn active(&self) -> usize {
        self.active
    }

    /// Makes part `part` (an index into [`Assembly::parts`], wrapped) the active one; returns it.
    pub fn set_active(&mut self, part: usize) -> usize {
        self.active = part % self.parts.len();
        self.active
    }

    /// Places part `part` at `placement`; the composition is made again at the next
    /// [`Assembly::surface`].
    pub fn set_placement(&mut self, part: usize, placement: Placement) {
        self.parts[part].placement = placement;
    }

    /// The parts' layouts as a sculpt file stores them: none for one part at rest (the file of
    /// a sculpt without parts).
    pub fn layouts(&self) -> Vec<PartLayout> {
        let rest = matches!(&self.parts[..], [p] if p.visible && !p.locked && p.op == Csg::Union && p.placement.is_identity());
        if rest {
            return Vec::new();
        }
        self.parts.iter().map(layout_of).collect()
    }

    /// The fields of the parts after the first.
    pub fn others(&self) -> &[Field] {
        &self.others
    }

    /// The fields of the parts after the first, mutably (for the journal to take what changed).
    pub fn others_mut(&mut self) -> &mut [Field] {
        &mut self.others
    }

    /// What an autosave session's snapshots store of the parts besides the first part's clay,
    /// with the scene's freeform `tools`.
    pub fn besides<'a>(
        &'a mut self,
        tools: &'a [crate::io::StoredTool],
        layouts: &'a [PartLayout],
    ) -> Besides<'a> {
        Besides {
            tools,
            layouts,
            others: if layouts.is_empty() { &mut [] } else { &mut self.others },
            symmetry: None,
        }
    }

    /// The fields of the parts after the first, ending the assembly.
    pub fn into_others(self) -> Vec<Field> {
        self.others
    }

    /// Part `part`'s field (`first` is part 0's).
    pub fn field<'a>(&'a self, first: &'a Field, part: usize) -> &'a Field {
        if part == 0 {
            first
        } else {
            &self.others[part - 1]
        }
    }

    /// Part `part`'s field, mutably (`first` is part 0's).
    pub fn field_mut<'a>(&'a mut self, first: &'a mut Field, part: usize) -> &'a mut Field {
        if part == 0 {
            first
        } else {
            &mut self.others[part - 1]
        }
    }

    /// Every part's field with its layout, as the composition reads them.
    fn views<'a>(&'a self, first: &'a Field) -> Vec<PartView<'a>> {
        views(&self.parts, &self.others, first)
    }

    /// Where a tool acting on part `part` acts, when that part is not at rest in the world: its
    /// placement (the tool's pose and size go into the part's frame through it).
    pub fn frame_of(&self, part: usize) -> Option<Placement> {
        let p = self.parts[part].placement;
        (!p.is_identity()).then_some(p)
    }

    /// The surface the mesher reads, brought up to date with every part's changes: the first
    /// part's field where it is the whole sculpt, else the composition (re-made where the
    /// parts changed, whole where their layout did). Its dirty set says what to re-mesh.
    pub fn surface<'a>(&'a mut self, first: &'a mut Field) -> &'a mut Field {
        let needed = Composition::needed(&self.views(first));
        if !needed {
            if let Some(old) = self.composition.take() {
                redraw_over(first, old.field());
            }
            return first;
        }
        let mut changed = Vec::new();
        for part in 0..self.parts.len() {
            let field = self.field_mut(first, part);
            changed.extend(
                field
                    .drain_dirty()
                    .map(|k| (part, k * BRICK_SIZE, k * BRICK_SIZE + IVec3::splat(BRICK_SIZE - 1))),
            );
        }
        let views = views(&self.parts, &self.others, first);
        match &mut self.composition {
            Some(c) if c.fits(&views) => c.update(&views, &changed),
            slot => {
                let mut fresh = Composition::build(&views);
                // What was drawn before (the first part alone, or an older layout) is drawn again.
                match slot.as_ref() {
                    Some(old) => redraw_over(fresh.field_mut(), old.field()),
                    None => redraw_over(fresh.field_mut(), first),
                }
                *slot = Some(fresh);
            }
        }
        self.composition.as_mut().map_or(first, Composition::field_mut)
    }

    /// The surface as last brought up to date by [`Assembly::surface`], ending the assembly.
    pub fn into_surface(self, first: Field) -> Field {
        match self.composition {
            Some(c) => c.into_field(),
            None => first,
        }
    }

    /// The surface as last brought up to date by [`Assembly::surface`].
    pub fn surface_now<'a>(&'a self, first: &'a Field) -> &'a Field {
        self.composition.as_ref().map_or(first, Composition::field)
    }

    /// Logs the sculpt step that has just closed on any part's field (the parts whose fields
    /// recorded a new step); a new step clears the redo order.
    pub fn note_steps(&mut self, first: &Field) {
        let now = counts(first, &self.others);
        let grown: Vec<usize> = (0..now.len()).filter(|&i| now[i] > self.seen[i]).collect();
        self.seen = now;
        if !grown.is_empty() {
            self.undo.push(Step::Edits(grown));
            self.redo.clear();
        }
    }

    /// Adds a part of `layout` after the others, holding `field` (empty but for one closed
    /// step, its clay): one sculpt step, which undo takes back by taking the part away and redo
    /// by bringing it back. Returns its index.
    pub fn add_part(&mut self, first: &Field, layout: ScenePart, field: Field) -> usize {
        self.note_steps(first);
        self.parts.push(layout);
        self.others.push(field);
        self.seen = counts(first, &self.others);
        let part = self.parts.len() - 1;
        self.undo.push(Step::Added { part, taken: None });
        self.redo.clear();
        part
    }

    /// Logs part `part`'s move from `from` to where it is now as one sculpt step (none when it
    /// is back where it was); a new step clears the redo order.
    pub fn note_placement(&mut self, first: &Field, part: usize, from: Placement) {
        self.note_steps(first);
        let to = self.parts[part].placement;
        if to != from {
            self.undo.push(Step::Placed { part, from, to });
            self.redo.clear();
        }
    }

    /// Takes back the newest sculpt step in every part it changed (the first part's newest step
    /// when none is logged). Returns whether there was one. A part added by that step is taken
    /// away once `journal` has been given every part's field with its clay taken back (so that
    /// a journal of the parts' bricks sees it emptied before it goes).
    pub fn undo(
        &mut self,
        first: &mut Field,
        journal: &mut dyn FnMut(&mut Field, &mut [Field]),
    ) -> Result<bool, HistoryError> {
        self.step_back(first, true, journal)
    }

    /// Puts back the newest step undone. Returns whether there was one.
    pub fn redo(&mut self, first: &mut Field) -> bool {
        self.step_back(first, false, &mut |_, _| {}).unwrap_or(false)
    }

    /// Undoes (or redoes) the newest logged step in every part it changed, and logs it on the
    /// other stack.
    fn step_back(
        &mut self,
        first: &mut Field,
        undo: bool,
        journal: &mut dyn FnMut(&mut Field, &mut [Field]),
    ) -> Result<bool, HistoryError> {
        self.note_steps(first);
        let from = if undo { &mut self.undo } else { &mut self.redo };
        // Undo with nothing logged takes back the first part's newest step (a history read from
        // a file); redo only puts back what undo logged.
        let step = match from.pop() {
            Some(step) => step,
            None if undo => Step::Edits(vec![0]),
            None => return Ok(false),
        };
        let mut any = false;
        let mut step = step;
        match &mut step {
            Step::Added { part, taken } => {
                if undo && *part + 1 == self.parts.len() && *part > 0 {
                    self.others[*part - 1].undo()?;
                    journal(first, &mut self.others);
                    let field = self.others.pop().expect("the part added last");
                    let layout = self.parts.pop().expect("its layout");
                    *taken = Some(Box::new((layout, field)));
                    self.active = self.active.min(self.parts.len() - 1);
                    any = true;
                } else if let (false, Some(back)) = (undo, taken.take()) {
                    let (layout, mut field) = *back;
                    field.redo();
                    self.parts.push(layout);
                    self.others.push(field);
                    any = true;
                }
            }
            Step::Edits(parts) => {
                for &part in parts.iter() {
                    let field = self.field_mut(first, part);
                    any |= if undo { field.undo()? } else { field.redo() };
                }
            }
            Step::Placed { part, from, to } => {
                self.parts[*part].placement = if undo { *from } else { *to };
                any = true;
            }
        }
        if any {
            let to = if undo { &mut self.redo } else { &mut self.undo };
            to.push(step);
        }
        self.seen = counts(first, &self.others);
        Ok(any)
    }

    /// How many steps of the sculpt undo can take back and redo can put back.
    pub fn history_len(&self, first: &Field) -> (usize, usize) {
        let placed = self.undo.iter().chain(&self.redo).any(|s| matches!(s, Step::Placed { .. }));
        if self.others.is_empty() && !placed {
            let s = first.history_stats();
            return (s.undo_in_memory + s.undo_on_disk, s.redo);
        }
        (self.undo.len(), self.redo.len())
    }

    /// Closes the strokes open on the parts after the first.
    pub fn end_strokes(&mut self) {
        for field in &mut self.others {
            if field.in_stroke() {
                field.end_stroke();
            }
        }
    }
}

/// Every part's field with its layout, as the composition reads them.
fn views<'a>(parts: &'a [ScenePart], others: &'a [Field], first: &'a Field) -> Vec<PartView<'a>> {
    parts
        .iter()
        .enumerate()
        .map(|(i, p)| PartView {
            field: if i == 0 { first } else { &others[i - 1] },
            placement: p.placement,
            op: p.op,
            visible: p.visible,
        })
        .collect()
}

/// Marks dirty in `field` every brick `drawn` holds, so that what was drawn of it is re-meshed
/// (and removed where `field` holds nothing there).
fn redraw_over(field: &mut Field, drawn: &Field) {
    for key in drawn.covered_keys() {
        let lo = key * BRICK_SIZE;
        field.mark_dirty(lo, lo + IVec3::splat(BRICK_SIZE - 1));
    }
}

/// A world symmetry image as it acts in the frame of a part placed at `placement`:
/// `placement⁻¹ ∘ image ∘ placement`.
pub fn image_in_part(image: &Isometry, placement: &Placement) -> Isometry {
    let r = Mat3::from_quat(placement.rotation);
    let r_inv = r.transpose();
    let t = placement.translation_m;
    Isometry {
        linear: r_inv * image.linear * r,
        translation: r_inv * (image.linear * t + image.translation - t) / placement.scale,
    }
}

/// A part's layout as a sculpt file stores it.
pub fn layout_of(p: &ScenePart) -> PartLayout {
    PartLayout {
        name: p.name.clone(),
        voxel_size_m: p.voxel_size_m,
        rotation: p.placement.rotation.to_array(),
        translation_m: p.placement.translation_m.to_array(),
        scale: p.placement.scale,
        op: p.op.name().to_owned(),
        visible: p.visible,
        locked: p.locked,
    }
}

/// The parts a sculpt stores (one whole part at rest, of its clay's voxel, when it stores none);
/// `None` when a stored layout is not one a part can have (the reader refuses those).
pub fn parts_of(sculpt: &Sculpt) -> Option<Vec<ScenePart>> {
    if sculpt.parts.is_empty() {
        return Some(vec![ScenePart::whole(sculpt.field.transform().voxel_size_m)]);
    }
    sculpt
        .parts
        .iter()
        .map(|l| {
            let placement =
                Placement::new(Quat::from_array(l.rotation), Vec3::from(l.translation_m), l.scale).ok()?;
            Some(ScenePart {
                name: l.name.clone(),
                voxel_size_m: l.voxel_size_m,
                placement,
                op: Csg::from_name(&l.op)?,
                visible: l.visible,
                locked: l.locked,
            })
        })
        .collect()
}

/// The surface of a sculpt read from a file: its clay, or the composition of its parts; `None`
/// when a stored layout is not one a part can have.
pub fn sculpt_surface(sculpt: Sculpt) -> Option<Field> {
    let parts = parts_of(&sculpt)?;
    let mut assembly = Assembly::new(parts, sculpt.others, &sculpt.field);
    let mut first = sculpt.field;
    let _ = assembly.surface(&mut first);
    Some(assembly.into_surface(first))
}
