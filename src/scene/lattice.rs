//! `[[lattice]]` and `[[lattice_key]]`: spline-volume lattices opened over the clay, shaped
//! by scripted keys, applied as one undo step (`scenes/README.md`).

use serde::Deserialize;
use toml::Spanned;

use super::{rotation, within_reach, At, SceneError, MAX_LENGTH_M, MAX_POSITION_M, MAX_SCALE, MAX_TIME_S};
use crate::lattice::{
    source_points, volume_at, ControlEdit, LatticeSpec, Selection, TimedEdit, MAX_SOURCE_POINTS,
};
use crate::math::{Aabb, Vec3};
use crate::spline::{KnotStyle, SplineKind, MAX_SAMPLES_PER_SPAN};

/// The largest NURBS weight a key may set.
pub const MAX_WEIGHT: f64 = 1000.0;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LatticeFile {
    pub name: String,
    pub min_m: [f32; 3],
    pub max_m: [f32; 3],
    #[serde(default = "four_each")]
    pub controls: [usize; 3],
    #[serde(default)]
    pub kind: KindSpec,
    #[serde(default = "four")]
    pub order: usize,
    #[serde(default)]
    pub knots: KnotsSpec,
    pub samples_per_span: Option<usize>,
    #[serde(default)]
    pub open_s: f32,
    pub apply_s: Option<f32>,
    #[serde(default = "yes")]
    pub show: bool,
    pub slice: Option<usize>,
    pub part: Option<String>,
}

fn four_each() -> [usize; 3] {
    [4, 4, 4]
}

fn four() -> usize {
    4
}

fn yes() -> bool {
    true
}

fn one() -> f32 {
    1.0
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "snake_case")]
pub(super) enum KindSpec {
    Bezier,
    #[default]
    Bspline,
    Nurbs,
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "snake_case")]
pub(super) enum KnotsSpec {
    #[default]
    Clamped,
    Uniform,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LatticeKeyFile {
    pub time_s: f32,
    pub lattice: String,
    pub i: Option<[usize; 2]>,
    pub j: Option<[usize; 2]>,
    pub k: Option<[usize; 2]>,
    #[serde(default)]
    pub offset_m: [f32; 3],
    #[serde(default)]
    pub rotation_deg: [f32; 3],
    #[serde(default = "one")]
    pub scale: f32,
    pub pivot_m: Option<[f32; 3]>,
    #[serde(default)]
    pub value_offset: f64,
    pub weight: Option<f64>,
}

/// A lattice of the scene: opened over the clay at `open_s`, shaped by its keys, applied at
/// `apply_s`.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneLattice {
    /// What keys call it.
    pub name: String,
    /// Its box, control points and kind of spline.
    pub spec: LatticeSpec,
    /// When it is opened over the clay (the clay as it is then is what it deforms), seconds.
    pub open_s: f32,
    /// When it is applied (it closes; the sculpt keeps what it did as one undo step), seconds.
    pub apply_s: f32,
    /// Whether captures draw its control points and lines while it is open.
    pub show: bool,
    /// The slice drawn with it (ESM §4.2): the patch of controls `k` along Z, with its values'
    /// stems and the function's zero contour.
    pub slice: Option<usize>,
    /// Its keys' edits, in time order, each ramping in from the key before it.
    pub edits: Vec<TimedEdit>,
    /// The part whose clay it deforms; its box and its keys are in that part's own frame.
    pub part: usize,
}

/// The scene's lattices, validated.
pub(super) fn resolve_lattices(
    lattices: &[Spanned<LatticeFile>],
    keys: &[Spanned<LatticeKeyFile>],
    parts: &[super::ScenePart],
    at: &At<'_>,
) -> Result<Vec<SceneLattice>, SceneError> {
    let mut out: Vec<SceneLattice> = Vec::with_capacity(lattices.len());
    for spanned in lattices {
        let span = Some(spanned.span());
        let l = spanned.get_ref();
        let err = |message: String| at(span.clone(), format!("lattice `{}`: {message}", l.name));
        let fail = |message: String| Err(err(message));
        if l.name.is_empty() || out.iter().any(|o| o.name == l.name) {
            return Err(at(span, format!("lattice names must be non-empty and distinct: `{}`", l.name)));
        }
        let part = super::part::part_index(parts, l.part.as_deref(), spanned.span(), at)?;
        if parts[part].locked {
            return fail(format!("part \"{}\" is locked: no lattice acts on it", parts[part].name));
        }
        // The part's finest voxel, in its own frame.
        let voxel_size_m = parts[part].voxel_size_m;
        let (min, max) = (Vec3::from(l.min_m), Vec3::from(l.max_m));
        if !within_reach(l.min_m) || !within_reach(l.max_m) {
            return fail(format!("min_m and max_m must lie within ±{MAX_POSITION_M} m on each axis"));
        }
        let size = max - min;
        if !(size.cmpgt(Vec3::ZERO).all() && size.max_element() <= MAX_LENGTH_M) {
            return fail(format!(
                "max_m must exceed min_m on every axis, by at most {MAX_LENGTH_M} m: {:?} to {:?}",
                l.min_m, l.max_m
            ));
        }
        if l.samples_per_span.is_some_and(|s| !(1..=MAX_SAMPLES_PER_SPAN).contains(&s)) {
            return fail(format!("samples_per_span must be 1 to {MAX_SAMPLES_PER_SPAN}"));
        }
        let kind = match l.kind {
            KindSpec::Bezier => SplineKind::Bezier,
            KindSpec::Bspline => SplineKind::BSpline,
            KindSpec::Nurbs => SplineKind::Nurbs,
        };
        let knots = match l.knots {
            KnotsSpec::Clamped => KnotStyle::Clamped,
            KnotsSpec::Uniform => KnotStyle::Uniform,
        };
        let spec = LatticeSpec {
            region: Aabb { min, max },
            counts: l.controls,
            kind,
            order: l.order,
            knots,
            samples_per_span: l.samples_per_span,
        };
        // The spline's own checks: counts 2 to 16, the order 2 to 16.
        if l.order < 2 || l.order > 16 {
            return fail(format!("order must be 2 to 16 (4 is cubic), not {}", l.order));
        }
        let rest = spec.volume().map_err(|e| err(e.to_string()))?;
        if let Some(k) = l.slice.filter(|&k| k >= l.controls[2]) {
            return fail(format!(
                "slice must be a layer of control points along Z, 0 to {}, not {k}",
                l.controls[2] - 1
            ));
        }
        if !(l.open_s.is_finite() && (0.0..=MAX_TIME_S).contains(&l.open_s)) {
            return fail(format!("open_s must be 0 to {MAX_TIME_S} s, not {}", l.open_s));
        }
        let mut edits: Vec<(f32, ControlEdit, std::ops::Range<usize>)> = Vec::new();
        for key in keys.iter().filter(|k| k.get_ref().lattice == l.name) {
            let kspan = key.span();
            let k = key.get_ref();
            let bad = |message: String| at(Some(kspan.clone()), message);
            if !(k.time_s.is_finite() && (l.open_s..=MAX_TIME_S).contains(&k.time_s)) {
                return Err(bad(format!(
                    "time_s must be from the lattice's open_s ({} s) to {MAX_TIME_S} s, not {}",
                    l.open_s, k.time_s
                )));
            }
            let range = |r: Option<[usize; 2]>, n: usize| r.map_or((0, n - 1), |[a, b]| (a, b));
            let select = Selection {
                ranges: [range(k.i, l.controls[0]), range(k.j, l.controls[1]), range(k.k, l.controls[2])],
            };
            if !select.fits(l.controls) {
                return Err(bad(format!(
                    "i, j and k must be [first, last] index ranges within the lattice's {} × {} × {} \
                     control points (from 0), not {:?}",
                    l.controls[0], l.controls[1], l.controls[2], select.ranges
                )));
            }
            if !k.offset_m.iter().all(|c| c.is_finite() && c.abs() <= MAX_LENGTH_M) {
                return Err(bad(format!("offset_m must be within ±{MAX_LENGTH_M} m on each axis")));
            }
            if !k.rotation_deg.iter().all(|a| a.is_finite() && a.abs() <= 3600.0) {
                return Err(bad("rotation_deg must be finite angles within ±3600°".to_owned()));
            }
            if !(k.scale.is_finite() && k.scale > 0.0 && k.scale <= MAX_SCALE) {
                return Err(bad(format!("scale must be above 0 and at most {MAX_SCALE}, not {}", k.scale)));
            }
            if k.pivot_m.is_some_and(|p| !within_reach(p)) {
                return Err(bad(format!("pivot_m must lie within ±{MAX_POSITION_M} m on each axis")));
            }
            if !(k.value_offset.is_finite() && k.value_offset.abs() <= 1.0) {
                return Err(bad(format!(
                    "value_offset is a change of density, from -1 to 1, not {}",
                    k.value_offset
                )));
            }
            if let Some(w) = k.weight {
                if kind != SplineKind::Nurbs {
                    return Err(bad(format!(
                        "weight belongs to NURBS lattices; lattice `{}` is not one (kind = \"nurbs\")",
                        l.name
                    )));
                }
                if !(w.is_finite() && w > 0.0 && w <= MAX_WEIGHT) {
                    return Err(bad(format!("weight must be above 0 and at most {MAX_WEIGHT}, not {w}")));
                }
            }
            let edit = ControlEdit {
                select,
                offset_m: Vec3::from(k.offset_m),
                rotation: rotation(k.rotation_deg),
                scale: k.scale,
                pivot_m: k.pivot_m.map(Vec3::from),
                value_offset: k.value_offset,
                weight: k.weight,
            };
            edits.push((k.time_s, edit, kspan));
        }
        edits.sort_by(|a, b| a.0.total_cmp(&b.0));
        let last = edits.last().map_or(l.open_s, |e| e.0);
        let apply_s = l.apply_s.unwrap_or(last);
        if !(apply_s.is_finite() && apply_s >= last && apply_s <= MAX_TIME_S) {
            return fail(format!(
                "apply_s must be at or after its open_s and its last key ({last} s), and at most \
                 {MAX_TIME_S} s, not {apply_s}"
            ));
        }
        // Each key ramps in from the time of the key before it (or the opening).
        let mut timed = Vec::with_capacity(edits.len());
        for (n, (time_s, edit, _)) in edits.iter().enumerate() {
            let from_s = edits[..n].iter().rev().map(|e| e.0).find(|&t| t < *time_s).unwrap_or(l.open_s);
            timed.push(TimedEdit { from_s, time_s: *time_s, edit: *edit });
        }
        // The copy of the clay it needs, wherever its keys take its control points.
        let mut times: Vec<f32> =
            timed.iter().flat_map(|e| [0.5 * (e.from_s + e.time_s), e.time_s]).collect();
        times.push(l.open_s);
        for t in times {
            let shaped = volume_at(&rest, &timed, t).map_err(|e| err(e.to_string()))?;
            let points = source_points(&spec, voxel_size_m, shaped.hull());
            if points > MAX_SOURCE_POINTS {
                return fail(format!(
                    "its box and the room its keys move its control points into hold {points} \
                     samples of the clay at {t} s, over the limit of {MAX_SOURCE_POINTS}; make \
                     the box smaller, move its control points less far, or use a coarser voxel_size_m \
                     for its part"
                ));
            }
        }
        out.push(SceneLattice {
            name: l.name.clone(),
            spec,
            open_s: l.open_s,
            apply_s,
            show: l.show,
            slice: l.slice,
            edits: timed,
            part,
        });
    }
    if let Some(key) = keys.iter().find(|k| !out.iter().any(|l| l.name == k.get_ref().lattice)) {
        let known: Vec<&str> = out.iter().map(|l| l.name.as_str()).collect();
        return Err(at(
            Some(key.span()),
            format!("no lattice named `{}` (lattices: {})", key.get_ref().lattice, known.join(", ")),
        ));
    }
    Ok(out)
}
