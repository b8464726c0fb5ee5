//! A lattice the user holds open over a part's clay, at the desk or in the headset: opened over
//! a box, shaped control by control (picked nearest the tool, dragged with it, its value raised
//! or lowered, its NURBS weight made heavier or lighter), then applied as one undo step or put
//! back. The scene's scripted lattices are [`super::playback`]'s; this is the hand-held one,
//! one at a time, shared by the desk and the headset through [`super::playback::Playback`].

use crate::field::Field;
use crate::io::{StoredControl, StoredLattice};
use crate::lattice::{Lattice, LatticeError, LatticeSpec};
use crate::math::{Aabb, Mat4, Vec3, Vec4};
use crate::render::ToolGlyph;
use crate::spline::{KnotStyle, SplineKind};

/// How much one press raises or lowers the picked control's function value (a density).
pub const VALUE_STEP: f64 = 0.1;

/// How far a held lattice's values may be taken from the values fitted to the clay (a density
/// spans 1): room to push the surface through the whole lattice cell either way.
pub const VALUE_REACH: f64 = 2.0;

/// The factor one press makes the picked control's NURBS weight heavier (or lighter, by its
/// inverse).
pub const WEIGHT_STEP: f64 = 1.25;

/// The range a held lattice's weights are kept in.
pub const WEIGHT_RANGE: (f64, f64) = (0.05, 20.0);

/// A lattice opened over a whole part reaches this fraction of the clay's size beyond it.
pub const PART_MARGIN: f32 = 0.05;

/// The colour of the picked control's marker: a bright ring yellow.
pub const PICKED_COLOUR: Vec4 = Vec4::new(1.0, 0.85, 0.2, 0.35);

/// A lattice held open over part `part`'s clay, with the control picked and the drag under way.
#[derive(Clone, Debug)]
pub struct HeldLattice {
    lattice: Lattice,
    part: usize,
    picked: [usize; 3],
    /// While a drag is under way: the picked control's position and the hand's point when it
    /// began (the part's frame).
    drag: Option<(Vec3, Vec3)>,
    /// The box of the part's clay the last changes have not been written to yet.
    pending: Aabb,
    /// The slice shown (ESM §4.2): the patch of controls `k` and its zero contour.
    slice: Option<usize>,
}

impl HeldLattice {
    /// Opens a lattice of `spec` over `field` (part `part`'s clay), at rest, the control
    /// nearest the box's centre picked.
    pub fn open(field: &Field, part: usize, spec: &LatticeSpec) -> Result<Self, LatticeError> {
        let lattice = Lattice::open(field, spec)?;
        let mut held = Self { lattice, part, picked: [0; 3], drag: None, pending: Aabb::EMPTY, slice: None };
        held.pick_nearest(spec.region.centre());
        Ok(held)
    }

    /// The lattice.
    pub fn lattice(&self) -> &Lattice {
        &self.lattice
    }

    /// The part whose clay it deforms.
    pub fn part(&self) -> usize {
        self.part
    }

    /// The picked control's indices.
    pub fn picked(&self) -> [usize; 3] {
        self.picked
    }

    /// The slice shown, if any: the index `k` of its patch of controls.
    pub fn slice(&self) -> Option<usize> {
        self.slice
    }

    /// Shows the next slice (none, then `k` = 0, 1, … up the lattice's third axis, then none
    /// again); returns the one shown.
    pub fn next_slice(&mut self) -> Option<usize> {
        let n = self.lattice.volume().counts()[2];
        self.slice = match self.slice {
            None => Some(0),
            Some(k) if k + 1 < n => Some(k + 1),
            Some(_) => None,
        };
        self.slice
    }

    /// Whether the picked control is being dragged.
    pub fn dragging(&self) -> bool {
        self.drag.is_some()
    }

    /// Picks the control nearest `point` (the part's frame), unless a drag is under way.
    pub fn pick_nearest(&mut self, point: Vec3) {
        if self.drag.is_some() {
            return;
        }
        let volume = self.lattice.volume();
        let [l, m, _] = volume.counts();
        let nearest = volume
            .controls()
            .iter()
            .enumerate()
            .min_by(|(_, a), (_, b)| {
                a.position_m.distance_squared(point).total_cmp(&b.position_m.distance_squared(point))
            })
            .map_or(0, |(n, _)| n);
        self.picked = [nearest % l, (nearest / l) % m, nearest / (l * m)];
    }

    /// The hand at `point` (the part's frame), `held` while the drag button or key is down:
    /// the picked control follows the hand's motion since the drag began. A move that would
    /// reach too far is refused (the control stays where it was) and the error returned.
    pub fn drag(&mut self, point: Vec3, held: bool) -> Result<(), LatticeError> {
        let Some((from, grabbed)) = self.drag else {
            if held {
                let c = self.lattice.volume().control(self.picked[0], self.picked[1], self.picked[2])?;
                self.drag = Some((c.position_m, point));
            }
            return Ok(());
        };
        if !held {
            self.drag = None;
            return Ok(());
        }
        let to = from + (point - grabbed);
        let c = self.lattice.volume().control(self.picked[0], self.picked[1], self.picked[2])?;
        if c.position_m != to {
            let changed = self.lattice.move_control(self.picked, to)?;
            self.pending = self.pending.union(&changed);
        }
        Ok(())
    }

    /// Raises (or, negative, lowers) the picked control's function value by `delta`, kept
    /// within [`VALUE_REACH`] of the value the fit gave it: the clay near it swells (shrinks).
    /// Returns the new value.
    pub fn add_value(&mut self, delta: f64) -> Result<f64, LatticeError> {
        let [i, j, k] = self.picked;
        let now = self.lattice.volume().control(i, j, k)?.value;
        let fitted = self.lattice.fitted().control(i, j, k)?.value;
        let value = (now + delta).clamp(fitted - VALUE_REACH, fitted + VALUE_REACH);
        let changed = self.lattice.set_value(self.picked, value)?;
        self.pending = self.pending.union(&changed);
        Ok(value)
    }

    /// Multiplies the picked control's NURBS weight by `factor`, kept in [`WEIGHT_RANGE`].
    /// Returns the new weight.
    pub fn scale_weight(&mut self, factor: f64) -> Result<f64, LatticeError> {
        let [i, j, k] = self.picked;
        let now = self.lattice.volume().control(i, j, k)?.weight;
        let weight = (now * factor).clamp(WEIGHT_RANGE.0, WEIGHT_RANGE.1);
        let changed = self.lattice.set_weight(self.picked, weight)?;
        self.pending = self.pending.union(&changed);
        Ok(weight)
    }

    /// The lattice as a sculpt file stores it.
    pub fn stored(&self) -> StoredLattice {
        let spec = self.lattice.spec();
        StoredLattice {
            part: self.part,
            min_m: spec.region.min.to_array(),
            max_m: spec.region.max.to_array(),
            counts: spec.counts,
            kind: match spec.kind {
                SplineKind::Bezier => "bezier",
                SplineKind::BSpline => "bspline",
                SplineKind::Nurbs => "nurbs",
            }
            .to_owned(),
            order: spec.order,
            knots: match spec.knots {
                KnotStyle::Clamped => "clamped",
                KnotStyle::Uniform => "uniform",
            }
            .to_owned(),
            samples_per_span: spec.samples_per_span,
            controls: self
                .lattice
                .volume()
                .controls()
                .iter()
                .map(|c| StoredControl {
                    position_m: c.position_m.to_array(),
                    value: c.value,
                    weight: c.weight,
                })
                .collect(),
            picked: self.picked,
        }
    }

    /// Opens the lattice a sculpt file stored over `field` (its part's clay as it was when the
    /// lattice opened) and shapes it as it was saved.
    pub fn reopen(field: &Field, stored: &StoredLattice) -> Result<Self, LatticeError> {
        let spec = LatticeSpec {
            region: Aabb { min: Vec3::from_array(stored.min_m), max: Vec3::from_array(stored.max_m) },
            counts: stored.counts,
            kind: match stored.kind.as_str() {
                "bezier" => SplineKind::Bezier,
                "bspline" => SplineKind::BSpline,
                _ => SplineKind::Nurbs,
            },
            order: stored.order,
            knots: if stored.knots == "uniform" { KnotStyle::Uniform } else { KnotStyle::Clamped },
            samples_per_span: stored.samples_per_span,
        };
        let mut held = Self::open(field, stored.part, &spec)?;
        let mut volume = held.lattice.volume().clone();
        let [l, m, _] = stored.counts;
        for (n, c) in stored.controls.iter().enumerate() {
            let (i, j, k) = (n % l, (n / l) % m, n / (l * m));
            volume.set_position(i, j, k, Vec3::from_array(c.position_m))?;
            volume.set_value(i, j, k, c.value)?;
            if c.weight != volume.control(i, j, k)?.weight {
                volume.set_weight(i, j, k, c.weight)?;
            }
        }
        if let Some(changed) = held.lattice.set_controls(&volume)? {
            held.pending = changed;
        }
        held.picked = stored.picked;
        Ok(held)
    }

    /// Writes what the changes since the last write did into `field` (the part's clay).
    pub fn sync(&mut self, field: &mut Field) -> Result<(), LatticeError> {
        let pending = std::mem::replace(&mut self.pending, Aabb::EMPTY);
        if !pending.is_empty() {
            self.lattice.write(field, pending)?;
        }
        Ok(())
    }

    /// The lattice's glyphs (ESM §4.1: each control a sphere coloured by its value, sized by its
    /// weight, the lines between them) and a ring marker on the picked control, placed in the
    /// world by `frame` (the part's frame → world).
    pub fn glyphs(&self, iso: f64, frame: Mat4) -> Vec<ToolGlyph> {
        let volume = self.lattice.volume();
        let mut glyphs = super::glyphs::lattice_glyphs(volume, iso);
        if let Some(k) = self.slice {
            glyphs.extend(super::glyphs::lattice_slice_glyphs(volume, k, iso));
        }
        let [i, j, k] = self.picked;
        if let Ok(c) = volume.control(i, j, k) {
            let r = 1.8 * super::glyphs::control_radius(volume) * super::glyphs::weight_size(c.weight);
            glyphs.push(ToolGlyph::sphere(
                Mat4::from_translation(c.position_m) * Mat4::from_scale(Vec3::splat(r)),
                PICKED_COLOUR,
            ));
        }
        for g in &mut glyphs {
            g.model = frame * g.model;
        }
        glyphs
    }
}
