//! Edits of a lattice's control points as scripts and panels give them: a block of controls
//! moved, turned, scaled, re-valued or re-weighted, applied in part while it ramps in.

use crate::math::{Quat, Vec3};
use crate::spline::{SplineError, SplineKind, SplineVolume};

/// A block of control points: inclusive index ranges per axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Selection {
    /// First and last index along u, v and w.
    pub ranges: [(usize, usize); 3],
}

impl Selection {
    /// Every control point of a lattice of `counts`.
    pub fn all(counts: [usize; 3]) -> Self {
        Self { ranges: counts.map(|n| (0, n.saturating_sub(1))) }
    }

    /// Whether control `ijk` is selected.
    pub fn contains(&self, ijk: [usize; 3]) -> bool {
        (0..3).all(|a| (self.ranges[a].0..=self.ranges[a].1).contains(&ijk[a]))
    }

    /// Whether every range is ordered and within a lattice of `counts`.
    pub fn fits(&self, counts: [usize; 3]) -> bool {
        (0..3).all(|a| self.ranges[a].0 <= self.ranges[a].1 && self.ranges[a].1 < counts[a])
    }
}

/// What an edit does to the selected control points, in this order: scale and turn about the
/// pivot, move, add to the value, set the weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlEdit {
    /// Which control points.
    pub select: Selection,
    /// Added to their positions, metres.
    pub offset_m: Vec3,
    /// Turns them about the pivot.
    pub rotation: Quat,
    /// Scales their distances from the pivot.
    pub scale: f32,
    /// Where they turn and scale about; `None`: the centre of their positions before the edit.
    pub pivot_m: Option<Vec3>,
    /// Added to their function values (densities: swells above 0, shrinks below).
    pub value_offset: f64,
    /// Their NURBS weight (NURBS lattices only).
    pub weight: Option<f64>,
}

impl ControlEdit {
    /// An edit of `select` that changes nothing yet.
    pub fn none(select: Selection) -> Self {
        Self {
            select,
            offset_m: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            scale: 1.0,
            pivot_m: None,
            value_offset: 0.0,
            weight: None,
        }
    }

    /// Applies `fraction` (0 to 1) of the edit to `volume`: the rotation slerped, the offset,
    /// the scale and the value scaled, the weight blended from each control's own. All or
    /// nothing: on an error (a selection outside the lattice, a weight on a non-NURBS lattice)
    /// the volume is unchanged.
    pub fn apply(&self, volume: &mut SplineVolume, fraction: f64) -> Result<(), SplineError> {
        let counts = volume.counts();
        if !self.select.fits(counts) {
            let [(_, i), (_, j), (_, k)] = self.select.ranges;
            let [l, m, n] = counts;
            return Err(SplineError::Index { i, j, k, l, m, n });
        }
        if self.weight.is_some() && volume.kind() != SplineKind::Nurbs {
            return Err(SplineError::NotRational { kind: volume.kind().name() });
        }
        let f = fraction.clamp(0.0, 1.0);
        let selected: Vec<[usize; 3]> = (0..counts[2])
            .flat_map(|k| (0..counts[1]).flat_map(move |j| (0..counts[0]).map(move |i| [i, j, k])))
            .filter(|&ijk| self.select.contains(ijk))
            .collect();
        let pivot = self.pivot_m.unwrap_or_else(|| {
            let sum: Vec3 = selected
                .iter()
                .map(|&[i, j, k]| volume.control(i, j, k).map_or(Vec3::ZERO, |c| c.position_m))
                .sum();
            sum / selected.len().max(1) as f32
        });
        let turn = Quat::IDENTITY.slerp(self.rotation, f as f32);
        let scale = 1.0 + (self.scale - 1.0) * f as f32;
        let moves = self.offset_m != Vec3::ZERO || self.rotation != Quat::IDENTITY || self.scale != 1.0;
        let mut next = volume.clone();
        if moves {
            next.update_positions(|ijk, c| {
                if self.select.contains(ijk) {
                    pivot + turn * ((c.position_m - pivot) * scale) + self.offset_m * f as f32
                } else {
                    c.position_m
                }
            })?;
        }
        if self.value_offset != 0.0 {
            next.update_values(|ijk, c| {
                c.value + if self.select.contains(ijk) { self.value_offset * f } else { 0.0 }
            })?;
        }
        if let Some(w) = self.weight {
            for &[i, j, k] in &selected {
                let own = next.control(i, j, k)?.weight;
                next.set_weight(i, j, k, own + (w - own) * f)?;
            }
        }
        *volume = next;
        Ok(())
    }
}

/// An edit that ramps in over `from_s ..= time_s` of a timeline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimedEdit {
    /// When it starts ramping in, seconds.
    pub from_s: f32,
    /// When it is whole, seconds.
    pub time_s: f32,
    /// What it does.
    pub edit: ControlEdit,
}

impl TimedEdit {
    /// How much of it applies at `t`: 0 before `from_s`, 1 from `time_s`, linear between.
    pub fn fraction_at(&self, t: f32) -> f64 {
        if t >= self.time_s {
            1.0
        } else if t <= self.from_s {
            0.0
        } else {
            ((t - self.from_s) / (self.time_s - self.from_s)) as f64
        }
    }
}

/// The lattice `fitted` (as opened) shaped by `edits` (in time order) at time `t`: every
/// edit whole by then, those ramping in in part, the later ones not at all.
pub fn volume_at(fitted: &SplineVolume, edits: &[TimedEdit], t: f32) -> Result<SplineVolume, SplineError> {
    let mut volume = fitted.clone();
    for e in edits {
        let f = e.fraction_at(t);
        if f > 0.0 {
            e.edit.apply(&mut volume, f)?;
        }
    }
    Ok(volume)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Aabb;
    use crate::spline::KnotStyle;

    fn cube() -> SplineVolume {
        let b = Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
        SplineVolume::nurbs(b, [4, 4, 4], [3, 3, 3], KnotStyle::Clamped).unwrap()
    }

    #[test]
    fn a_layer_turned_about_its_centre_keeps_its_centre_and_ramps_in() {
        let fitted = cube();
        let layer = Selection { ranges: [(3, 3), (0, 3), (0, 3)] };
        let edit = ControlEdit {
            rotation: Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
            ..ControlEdit::none(layer)
        };
        let timed = [TimedEdit { from_s: 1.0, time_s: 3.0, edit }];
        assert_eq!(volume_at(&fitted, &timed, 0.5).unwrap(), fitted);
        let half = volume_at(&fitted, &timed, 2.0).unwrap();
        let whole = volume_at(&fitted, &timed, 3.0).unwrap();
        let c = |v: &SplineVolume, j, k| v.control(3, j, k).unwrap().position_m;
        // A quarter turn about X: (y, z) → (−z, y); half way, an eighth.
        let p = c(&fitted, 0, 0);
        assert!((c(&whole, 0, 0) - Vec3::new(p.x, -p.z, p.y)).length() < 1e-5);
        let r = c(&half, 0, 0);
        assert!((r.y.atan2(r.z) - p.y.atan2(p.z)).abs() > 0.7 && (r.length() - p.length()).abs() < 1e-5);
        // The other layers did not move.
        assert_eq!(whole.control(0, 1, 1), fitted.control(0, 1, 1));
    }

    #[test]
    fn values_weights_and_bad_selections() {
        let fitted = cube();
        let one = Selection { ranges: [(1, 1), (1, 1), (1, 1)] };
        let mut v = fitted.clone();
        ControlEdit { value_offset: 0.4, weight: Some(3.0), ..ControlEdit::none(one) }
            .apply(&mut v, 0.5)
            .unwrap();
        let c = v.control(1, 1, 1).unwrap();
        assert!((c.value - 0.2).abs() < 1e-12 && (c.weight - 2.0).abs() < 1e-12);
        let outside = Selection { ranges: [(0, 4), (0, 0), (0, 0)] };
        assert!(ControlEdit { offset_m: Vec3::X, ..ControlEdit::none(outside) }.apply(&mut v, 1.0).is_err());
        let mut b = SplineVolume::bspline(fitted.region(), [4, 4, 4], [3, 3, 3], KnotStyle::Clamped).unwrap();
        let before = b.clone();
        assert!(ControlEdit { offset_m: Vec3::X, weight: Some(2.0), ..ControlEdit::none(one) }
            .apply(&mut b, 1.0)
            .is_err());
        assert_eq!(b, before, "a refused edit changed the lattice");
    }
}
