//! The spline volume: a lattice of control points with positions, weights and function values,
//! and its evaluation (ESM §3: the solid `f(x) = S(u, v, w)`; §4.4: Bézier, B-spline, NURBS).
//!
//! ```text
//!   region (world box)                 control (i, j, k), linear index i + l·(j + m·k)
//!    w                                    rest_m      where the lattice places it
//!    │  v                                 position_m  where it is now (space mapping)
//!    │ ╱                                  weight      NURBS homogeneous coordinate (> 0)
//!    o───── u       P(0,0,0) = min        value       its function value f, a density
//!                   P(1,1,1) = max        (function mapping)
//! ```
//!
//! Evaluation works in homogeneous form: with `B = N_i(u) N_j(v) N_k(w)`,
//! `A = Σ B w p`, `W = Σ B w`, `Φ = Σ B w f`, the point is `P = A / W` and the function
//! `F = Φ / W` (ESM: the function coordinate is rational in the same weights as the space
//! coordinates). Derivatives follow the quotient rule, `∂P = (∂A − P ∂W) / W`. Only the
//! `k_u·k_v·k_w` controls of the parameter's span take part.
//!
//! A control at rest counts at its exact Greville point (in `f64`, not its `f32` copy), so
//! the rest lattice maps the cube exactly affinely. Where the weights are equal, the inverse
//! mapping's searches locate points by that: `P(u) = A(u) + Σ N_i(u) d_i` over the controls
//! moved by `d_i` from rest (`A` the box's affine map, by linear precision), which for a drag of
//! a few controls costs three bases and a few products rather than the span's full sum
//! ([`SplineVolume::locate`]).

use crate::math::{Aabb, Mat3, Vec3};

use super::knots::{check_count_and_order, KnotStyle, KnotVector, MAX_ORDER};
use super::{SplineError, AXES};

/// Normalised parameters `(u, v, w)`; the unit cube [0, 1]³ is the spline's domain.
///
/// Evaluation takes finite parameters. Outside the cube the end spans' polynomials continue
/// (finite for the parameters any search here produces, within [−1, 2]³); non-finite
/// parameters give non-finite results.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Uvw(pub [f64; 3]);

impl Uvw {
    /// Parameters from their three values.
    pub const fn new(u: f64, v: f64, w: f64) -> Self {
        Self([u, v, w])
    }

    /// Parameters from a `Vec3` (widened to `f64`).
    pub fn from_vec3(p: Vec3) -> Self {
        Self([p.x as f64, p.y as f64, p.z as f64])
    }

    /// The parameters as a `Vec3` (narrowed to `f32`).
    pub fn to_vec3(self) -> Vec3 {
        Vec3::new(self.0[0] as f32, self.0[1] as f32, self.0[2] as f32)
    }

    /// Whether every parameter lies in [0, 1].
    pub fn is_in_unit_cube(self) -> bool {
        self.0.iter().all(|t| (0.0..=1.0).contains(t))
    }

    /// The parameters clamped to [0, 1].
    pub fn clamped_to_unit_cube(self) -> Self {
        Self(self.0.map(|t| t.clamp(0.0, 1.0)))
    }

    /// Whether every parameter is finite.
    pub fn is_finite(self) -> bool {
        self.0.iter().all(|t| t.is_finite())
    }
}

/// Which family of spline a volume belongs to (ESM §4.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SplineKind {
    /// Bernstein basis of full order on each axis: every control point influences the whole
    /// volume.
    Bezier,
    /// Polynomial B-spline of a chosen order: a control point influences `order` spans per
    /// axis.
    BSpline,
    /// Rational B-spline: a B-spline whose control points carry weights.
    Nurbs,
}

impl SplineKind {
    /// The kind's name, for messages.
    pub fn name(self) -> &'static str {
        match self {
            SplineKind::Bezier => "Bézier",
            SplineKind::BSpline => "B-spline",
            SplineKind::Nurbs => "NURBS",
        }
    }
}

/// One control point of the lattice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlPoint {
    /// Where the undeformed lattice places it (a Greville point of the box), metres.
    pub rest_m: Vec3,
    /// Where it is now, metres. Moving it warps space (ESM's space mapping).
    pub position_m: Vec3,
    /// Its NURBS weight, positive; 1 for Bézier and B-spline volumes.
    pub weight: f64,
    /// Its function value `f` (ESM's fourth coordinate): a density, [0, 1] by convention.
    pub value: f64,
}

/// A trivariate spline volume: `l × m × n` control points over a box, with per-axis knots.
#[derive(Clone, Debug, PartialEq)]
pub struct SplineVolume {
    kind: SplineKind,
    region: Aabb,
    knots: [KnotVector; 3],
    counts: [usize; 3],
    controls: Vec<ControlPoint>,
    /// The bounding box of the current positions: it holds the image of the unit cube.
    hull: Aabb,
    /// Whether all weights are equal (then the volume is polynomial).
    uniform_weights: bool,
    /// The smallest weight, which bounds the rational denominator from below in the domain.
    min_weight: f64,
    /// Per control, the homogeneous coordinates `(w·x, w·y, w·z, w, w·f)` in `f64`, kept in
    /// step with `controls`: what evaluation sums.
    homogeneous: Vec<[f64; 5]>,
    /// Per control, its rest point in `f64`: the Greville point of the box.
    rest: Vec<[f64; 3]>,
    /// The controls away from rest, kept in step with `controls`.
    displaced: Vec<Displaced>,
}

/// The position and its derivatives at one parameter: what the inverse mapping needs.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Located {
    /// `P(u, v, w)`.
    pub position: [f64; 3],
    /// `∂P/∂u`, `∂P/∂v`, `∂P/∂w` (when derivatives were asked for).
    pub jacobian: [[f64; 3]; 3],
}

/// A control away from its rest point: its indices and how far it moved, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Displaced {
    ijk: [usize; 3],
    by: [f64; 3],
}

/// Up to this many moved controls, [`SplineVolume::locate`] sums their displacements over the
/// affine map; past it, the span's full sum is cheaper.
const SPARSE_LIMIT: usize = 64;

/// The homogeneous sums at one parameter and what follows from them.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Eval {
    /// `P(u, v, w)`.
    pub position: [f64; 3],
    /// `F(u, v, w)`.
    pub value: f64,
    /// `∂P/∂u`, `∂P/∂v`, `∂P/∂w` (when derivatives were asked for).
    pub jacobian: [[f64; 3]; 3],
    /// `∂F/∂u`, `∂F/∂v`, `∂F/∂w` (when derivatives were asked for).
    pub gradient: [f64; 3],
}

/// The homogeneous coordinates of `c`, whose exact rest point is `rest`.
fn homogeneous(c: &ControlPoint, rest: [f64; 3]) -> [f64; 5] {
    let [x, y, z] = if c.position_m == c.rest_m { rest } else { to_f64(c.position_m) };
    let w = c.weight;
    [w * x, w * y, w * z, w, w * c.value]
}

pub(crate) fn to_f64(p: Vec3) -> [f64; 3] {
    [p.x as f64, p.y as f64, p.z as f64]
}

pub(crate) fn to_vec3(p: [f64; 3]) -> Vec3 {
    Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
}

fn check_region(region: Aabb) -> Result<(), SplineError> {
    let size = region.size();
    if !(region.min.is_finite() && region.max.is_finite() && size.cmpgt(Vec3::ZERO).all()) {
        return Err(SplineError::Region { min: region.min.to_array(), max: region.max.to_array() });
    }
    Ok(())
}

fn check_finite_vec(what: &'static str, p: Vec3) -> Result<(), SplineError> {
    match p.to_array().into_iter().find(|c| !c.is_finite()) {
        Some(c) => Err(SplineError::NotFinite { what, value: c as f64 }),
        None => Ok(()),
    }
}

impl SplineVolume {
    /// A lattice over `region` with the given knots per axis, every control point at its
    /// rest position, weight 1 and value 0 (no clay).
    ///
    /// Rest positions are the Greville abscissae of each axis's knots mapped onto the box,
    /// `rest_ijk = min + size · (g_i, g_j, g_k)`, so that the rest mapping is exactly the affine
    /// map of [0, 1]³ onto the box, `P(u, v, w) = min + size · (u, v, w)` (linear precision:
    /// `Σ g_i N_i(u) = u` for every knot vector of order ≥ 2). For uniform knots the outer rest
    /// points lie outside the box. A [`SplineKind::Bezier`] volume needs the Bézier knots on
    /// every axis ([`KnotVector::bezier`]).
    pub fn over_box(region: Aabb, kind: SplineKind, knots: [KnotVector; 3]) -> Result<Self, SplineError> {
        check_region(region)?;
        for (axis, kv) in knots.iter().enumerate() {
            check_count_and_order(axis, kv.count(), kv.order())?;
            if kind == SplineKind::Bezier && !kv.is_bezier() {
                return Err(SplineError::NotBezier {
                    axis: AXES[axis],
                    order: kv.order(),
                    count: kv.count(),
                });
            }
        }
        let counts = [knots[0].count(), knots[1].count(), knots[2].count()];
        let (min, max) = (to_f64(region.min), to_f64(region.max));
        let mut controls = Vec::with_capacity(counts.iter().product());
        let mut rests = Vec::with_capacity(counts.iter().product());
        for k in 0..counts[2] {
            for j in 0..counts[1] {
                for i in 0..counts[0] {
                    let g = [knots[0].greville(i), knots[1].greville(j), knots[2].greville(k)];
                    // As a blend of the corners, so that the corner abscissae 0 and 1 give the
                    // box's corners exactly.
                    let exact: [f64; 3] = std::array::from_fn(|a| min[a] * (1.0 - g[a]) + max[a] * g[a]);
                    let rest = to_vec3(exact);
                    controls.push(ControlPoint { rest_m: rest, position_m: rest, weight: 1.0, value: 0.0 });
                    rests.push(exact);
                }
            }
        }
        let mut out = Self {
            kind,
            region,
            knots,
            counts,
            controls,
            hull: Aabb::EMPTY,
            uniform_weights: true,
            min_weight: 1.0,
            homogeneous: Vec::new(),
            rest: rests,
            displaced: Vec::new(),
        };
        out.refresh_derived();
        Ok(out)
    }

    /// A Bézier volume of `counts` control points per axis over `region` (order = count).
    pub fn bezier(region: Aabb, counts: [usize; 3]) -> Result<Self, SplineError> {
        let orders = counts.map(|n| n.clamp(super::MIN_ORDER, MAX_ORDER));
        Self::styled(region, SplineKind::Bezier, counts, orders, KnotStyle::Clamped)
    }

    /// A B-spline volume of `counts` control points and `orders` per axis, with knots of
    /// `style`.
    pub fn bspline(
        region: Aabb,
        counts: [usize; 3],
        orders: [usize; 3],
        style: KnotStyle,
    ) -> Result<Self, SplineError> {
        Self::styled(region, SplineKind::BSpline, counts, orders, style)
    }

    /// A NURBS volume, as [`Self::bspline`], with every weight 1 until set.
    pub fn nurbs(
        region: Aabb,
        counts: [usize; 3],
        orders: [usize; 3],
        style: KnotStyle,
    ) -> Result<Self, SplineError> {
        Self::styled(region, SplineKind::Nurbs, counts, orders, style)
    }

    /// A volume of `kind` over `region` with knots of `style` on every axis.
    fn styled(
        region: Aabb,
        kind: SplineKind,
        counts: [usize; 3],
        orders: [usize; 3],
        style: KnotStyle,
    ) -> Result<Self, SplineError> {
        let [u, v, w] = [0, 1, 2].map(|a| KnotVector::styled(style, counts[a], orders[a], a));
        Self::over_box(region, kind, [u?, v?, w?])
    }

    /// The volume's kind.
    pub fn kind(&self) -> SplineKind {
        self.kind
    }

    /// The box the rest lattice maps the unit cube onto.
    pub fn region(&self) -> Aabb {
        self.region
    }

    /// The knot vector of axis 0 (u), 1 (v) or 2 (w); other axes read as w.
    pub fn knots(&self, axis: usize) -> &KnotVector {
        &self.knots[axis.min(2)]
    }

    /// The orders per axis.
    pub fn orders(&self) -> [usize; 3] {
        [self.knots[0].order(), self.knots[1].order(), self.knots[2].order()]
    }

    /// The control counts `[l, m, n]`.
    pub fn counts(&self) -> [usize; 3] {
        self.counts
    }

    /// All control points, index `i + l·(j + m·k)`.
    pub fn controls(&self) -> &[ControlPoint] {
        &self.controls
    }

    /// The bounding box of the current control positions, which holds `P([0, 1]³)` (convex
    /// hull property, weights being positive).
    pub fn hull(&self) -> Aabb {
        self.hull
    }

    /// Where the weights are equal: the box of the moved controls' displacements from rest, and
    /// the origin, metres. In the cube `P(u) − A(u) = Σ N_i(u) d_i` lies in it (the basis
    /// functions being non-negative and summing to 1), so a point's preimage `u` maps back to
    /// rest within it: `A(u) ∈ x − box`. `None` for unequal weights (no such bound).
    pub fn displacement_box(&self) -> Option<Aabb> {
        self.uniform_weights.then(|| {
            self.displaced
                .iter()
                .fold(Aabb { min: Vec3::ZERO, max: Vec3::ZERO }, |b, c| b.grown_by_point(to_vec3(c.by)))
        })
    }

    /// Whether every control that shapes the cube's faces is at rest and the knots are
    /// clamped (or Bézier) on every axis, so that each face maps onto itself as at rest and the
    /// deformed cube's image is the box itself: every point of the box has a preimage in the
    /// cube (the boundary fixed, the mapping has degree 1 over the box).
    pub fn faces_at_rest(&self) -> bool {
        let clamped = self.knots.iter().all(|k| k.is_clamped());
        let [l, m, n] = self.counts;
        clamped
            && self.uniform_weights
            && self.displaced.iter().all(|c| {
                let [i, j, k] = c.ijk;
                i > 0 && j > 0 && k > 0 && i + 1 < l && j + 1 < m && k + 1 < n
            })
    }

    /// The linear index of control `(i, j, k)`, if it lies in the lattice.
    pub fn index(&self, i: usize, j: usize, k: usize) -> Option<usize> {
        let [l, m, n] = self.counts;
        (i < l && j < m && k < n).then(|| i + l * (j + m * k))
    }

    fn checked_index(&self, i: usize, j: usize, k: usize) -> Result<usize, SplineError> {
        let [l, m, n] = self.counts;
        self.index(i, j, k).ok_or(SplineError::Index { i, j, k, l, m, n })
    }

    /// Control point `(i, j, k)`.
    pub fn control(&self, i: usize, j: usize, k: usize) -> Result<&ControlPoint, SplineError> {
        Ok(&self.controls[self.checked_index(i, j, k)?])
    }

    /// Moves control `(i, j, k)` to `position_m` (space mapping).
    pub fn set_position(
        &mut self,
        i: usize,
        j: usize,
        k: usize,
        position_m: Vec3,
    ) -> Result<(), SplineError> {
        check_finite_vec("a control position", position_m)?;
        let index = self.checked_index(i, j, k)?;
        let old = self.controls[index].position_m;
        self.controls[index].position_m = position_m;
        let on_hull_boundary = old.cmpeq(self.hull.min).any() || old.cmpeq(self.hull.max).any();
        if on_hull_boundary {
            self.refresh_derived();
        } else {
            self.hull = self.hull.grown_by_point(position_m);
        }
        self.refresh_homogeneous_at(index);
        self.refresh_displaced();
        Ok(())
    }

    /// Sets control `(i, j, k)`'s function value (function mapping).
    pub fn set_value(&mut self, i: usize, j: usize, k: usize, value: f64) -> Result<(), SplineError> {
        if !value.is_finite() {
            return Err(SplineError::NotFinite { what: "a control value", value });
        }
        let index = self.checked_index(i, j, k)?;
        self.controls[index].value = value;
        self.refresh_homogeneous_at(index);
        Ok(())
    }

    /// Sets control `(i, j, k)`'s weight; NURBS volumes only, and the weight must be positive.
    pub fn set_weight(&mut self, i: usize, j: usize, k: usize, weight: f64) -> Result<(), SplineError> {
        if self.kind != SplineKind::Nurbs {
            return Err(SplineError::NotRational { kind: self.kind.name() });
        }
        if !(weight.is_finite() && weight > 0.0) {
            return Err(SplineError::Weight { value: weight });
        }
        let index = self.checked_index(i, j, k)?;
        self.controls[index].weight = weight;
        self.refresh_weights();
        self.refresh_homogeneous_at(index);
        Ok(())
    }

    /// Moves every control point to `position([i, j, k], &control)`, all or none: on an error
    /// nothing changes.
    pub fn update_positions(
        &mut self,
        mut position: impl FnMut([usize; 3], &ControlPoint) -> Vec3,
    ) -> Result<(), SplineError> {
        let mut next = Vec::with_capacity(self.controls.len());
        for (index, cp) in self.controls.iter().enumerate() {
            let p = position(self.ijk(index), cp);
            check_finite_vec("a control position", p)?;
            next.push(p);
        }
        for (cp, p) in self.controls.iter_mut().zip(next) {
            cp.position_m = p;
        }
        self.refresh_derived();
        Ok(())
    }

    /// Sets every control value to `value([i, j, k], &control)`, all or none.
    pub fn update_values(
        &mut self,
        mut value: impl FnMut([usize; 3], &ControlPoint) -> f64,
    ) -> Result<(), SplineError> {
        let next: Vec<f64> =
            (0..self.controls.len()).map(|i| value(self.ijk(i), &self.controls[i])).collect();
        if let Some(&bad) = next.iter().find(|v| !v.is_finite()) {
            return Err(SplineError::NotFinite { what: "a control value", value: bad });
        }
        for (cp, v) in self.controls.iter_mut().zip(next) {
            cp.value = v;
        }
        self.refresh_derived();
        Ok(())
    }

    /// Sets all control values from a slice in index order `i + l·(j + m·k)`.
    pub fn set_values(&mut self, values: &[f64]) -> Result<(), SplineError> {
        if values.len() != self.controls.len() {
            return Err(SplineError::Length {
                what: "the control values",
                expected: self.controls.len(),
                given: values.len(),
            });
        }
        let [l, m, _] = self.counts;
        self.update_values(|[i, j, k], _| values[i + l * (j + m * k)])
    }

    /// Puts every control point back at its rest position.
    pub fn reset_positions(&mut self) {
        for cp in &mut self.controls {
            cp.position_m = cp.rest_m;
        }
        self.refresh_derived();
    }

    /// Whether the lattice is undeformed: every control at rest and all weights equal, so that
    /// `P` is the box's affine map.
    pub fn is_at_rest(&self) -> bool {
        self.uniform_weights && self.controls.iter().all(|c| c.position_m == c.rest_m)
    }

    /// The smallest weight.
    pub(crate) fn min_weight_value(&self) -> f64 {
        self.min_weight
    }

    /// Whether all weights are equal (the volume is then polynomial, even if NURBS).
    pub fn has_uniform_weights(&self) -> bool {
        self.uniform_weights
    }

    /// `(i, j, k)` of a linear index.
    pub(crate) fn ijk(&self, index: usize) -> [usize; 3] {
        let [l, m, _] = self.counts;
        [index % l, (index / l) % m, index / (l * m)]
    }

    /// Recomputes what follows from every control: the hull and the homogeneous coordinates.
    fn refresh_derived(&mut self) {
        self.hull = self.controls.iter().fold(Aabb::EMPTY, |b, c| b.grown_by_point(c.position_m));
        self.homogeneous = self.controls.iter().zip(&self.rest).map(|(c, &r)| homogeneous(c, r)).collect();
        self.refresh_displaced();
    }

    fn refresh_homogeneous_at(&mut self, index: usize) {
        self.homogeneous[index] = homogeneous(&self.controls[index], self.rest[index]);
    }

    /// Recomputes the list of moved controls (after a position changed).
    fn refresh_displaced(&mut self) {
        self.displaced = (self.controls.iter().zip(&self.rest).enumerate())
            .filter(|(_, (c, _))| c.position_m != c.rest_m)
            .map(|(index, (c, r))| {
                let p = to_f64(c.position_m);
                Displaced { ijk: self.ijk(index), by: std::array::from_fn(|a| p[a] - r[a]) }
            })
            .collect();
    }

    fn refresh_weights(&mut self) {
        let first = self.controls[0].weight;
        self.uniform_weights = self.controls.iter().all(|c| c.weight == first);
        self.min_weight = self.controls.iter().map(|c| c.weight).fold(f64::INFINITY, f64::min);
    }

    /// The rest (affine) mapping: `min + size · uvw`.
    pub fn rest_point(&self, uvw: Uvw) -> Vec3 {
        let (min, max) = (to_f64(self.region.min), to_f64(self.region.max));
        to_vec3(std::array::from_fn(|a| min[a] * (1.0 - uvw.0[a]) + max[a] * uvw.0[a]))
    }

    /// The inverse of the rest mapping: `(x − min) / size`.
    pub fn rest_parameters(&self, x: Vec3) -> Uvw {
        let (min, max, x) = (to_f64(self.region.min), to_f64(self.region.max), to_f64(x));
        Uvw(std::array::from_fn(|a| (x[a] - min[a]) / (max[a] - min[a])))
    }

    /// `P(u, v, w)`, the mapped point (rational for weighted volumes).
    pub fn position(&self, uvw: Uvw) -> Vec3 {
        to_vec3(self.eval::<false>(uvw).position)
    }

    /// The Jacobian `∂P/∂(u, v, w)`: column `a` is the derivative along parameter `a`.
    pub fn jacobian(&self, uvw: Uvw) -> Mat3 {
        let e = self.eval::<true>(uvw);
        Mat3::from_cols(to_vec3(e.jacobian[0]), to_vec3(e.jacobian[1]), to_vec3(e.jacobian[2]))
    }

    /// `F(u, v, w)`, the function value (rational in the same weights), unclipped.
    pub fn value(&self, uvw: Uvw) -> f64 {
        self.eval::<false>(uvw).value
    }

    /// `F(u, v, w)` and its gradient with respect to the parameters.
    pub fn value_and_gradient(&self, uvw: Uvw) -> (f64, [f64; 3]) {
        let e = self.eval::<true>(uvw);
        (e.value, e.gradient)
    }

    /// `P(u, v, w)` in `f64`.
    pub fn position_f64(&self, uvw: Uvw) -> [f64; 3] {
        self.eval::<false>(uvw).position
    }

    /// Each axis's non-zero basis functions at `uvw`, and with `D` their derivatives (else
    /// zeros).
    #[inline]
    fn bases<const D: bool>(&self, uvw: Uvw) -> [super::BasisDerivatives; 3] {
        std::array::from_fn(|a| {
            if D {
                self.knots[a].basis_with_derivatives(uvw.0[a])
            } else {
                let b = self.knots[a].basis(uvw.0[a]);
                super::BasisDerivatives {
                    first: b.first,
                    order: b.order,
                    values: b.values,
                    derivatives: [0.0; MAX_ORDER],
                }
            }
        })
    }

    /// The position at one parameter, and with `D` its Jacobian: [`Self::eval`]'s, found as
    /// the box's affine map plus the moved controls' displacements where the weights are equal
    /// and few controls moved (see the module documentation).
    #[inline]
    pub(crate) fn locate<const D: bool>(&self, uvw: Uvw) -> Located {
        if !self.uniform_weights || self.displaced.len() > SPARSE_LIMIT {
            let e = self.eval::<D>(uvw);
            return Located { position: e.position, jacobian: e.jacobian };
        }
        if self.knots.iter().all(|k| k.order() <= 4) {
            self.locate_displaced::<4, D>(uvw)
        } else {
            self.locate_displaced::<MAX_ORDER, D>(uvw)
        }
    }

    /// [`Self::locate`] as the affine map plus the displacements, bases in arrays of `N`.
    #[inline]
    fn locate_displaced<const N: usize, const D: bool>(&self, uvw: Uvw) -> Located {
        let (min, max) = (to_f64(self.region.min), to_f64(self.region.max));
        let u = uvw.0;
        let mut out = Located {
            position: std::array::from_fn(|a| min[a] * (1.0 - u[a]) + max[a] * u[a]),
            jacobian: [[0.0; 3]; 3],
        };
        if D {
            for a in 0..3 {
                out.jacobian[a][a] = max[a] - min[a];
            }
        }
        if self.displaced.is_empty() {
            return out;
        }
        let bases: [(usize, [f64; N], [f64; N]); 3] =
            std::array::from_fn(|a| self.knots[a].basis_sized::<N, D>(u[a]));
        let orders: [usize; 3] = std::array::from_fn(|a| self.knots[a].order());
        for c in &self.displaced {
            // The control's place among each axis's non-zero functions, if it has one.
            let r: [usize; 3] = std::array::from_fn(|a| c.ijk[a].wrapping_sub(bases[a].0));
            if (0..3).any(|a| r[a] >= orders[a]) {
                continue;
            }
            let n: [f64; 3] = std::array::from_fn(|a| bases[a].1[r[a]]);
            let weight = n[0] * n[1] * n[2];
            for x in 0..3 {
                out.position[x] += weight * c.by[x];
            }
            if D {
                let dn: [f64; 3] = std::array::from_fn(|a| bases[a].2[r[a]]);
                let along = [dn[0] * n[1] * n[2], n[0] * dn[1] * n[2], n[0] * n[1] * dn[2]];
                for (column, along) in out.jacobian.iter_mut().zip(along) {
                    for (entry, by) in column.iter_mut().zip(c.by) {
                        *entry += along * by;
                    }
                }
            }
        }
        out
    }

    /// Everything at one parameter: position and value, and with `D` their derivatives.
    /// Allocates nothing.
    #[inline]
    pub(crate) fn eval<const D: bool>(&self, uvw: Uvw) -> Eval {
        let bases = self.bases::<D>(uvw);
        let [bu, bv, bw] = &bases;
        let [l, m, _] = self.counts;
        // Sums of (w·p, w, w·f): t, and its derivatives along u, v, w.
        let mut t = [0.0f64; 5];
        let mut dt = [[0.0f64; 5]; 3];
        for c in 0..bw.order {
            let (nw, dnw) = (bw.values[c], bw.derivatives[c]);
            for b in 0..bv.order {
                let (nv, dnv) = (bv.values[b], bv.derivatives[b]);
                let row = l * (bv.first + b + m * (bw.first + c)) + bu.first;
                // Along u first: the row's sums with N_u and with N_u′.
                let mut s0 = [0.0f64; 5];
                let mut s1 = [0.0f64; 5];
                for (r, q) in self.homogeneous[row..row + bu.order].iter().enumerate() {
                    let (nu, dnu) = (bu.values[r], bu.derivatives[r]);
                    for x in 0..5 {
                        s0[x] += nu * q[x];
                        if D {
                            s1[x] += dnu * q[x];
                        }
                    }
                }
                let nvw = nv * nw;
                for x in 0..5 {
                    t[x] += nvw * s0[x];
                    if D {
                        dt[0][x] += nvw * s1[x];
                        dt[1][x] += dnv * nw * s0[x];
                        dt[2][x] += nv * dnw * s0[x];
                    }
                }
            }
        }
        let (a, mut wsum, phi) = ([t[0], t[1], t[2]], t[3], t[4]);
        let da: [[f64; 3]; 3] = std::array::from_fn(|ax| [dt[ax][0], dt[ax][1], dt[ax][2]]);
        let dw = [dt[0][3], dt[1][3], dt[2][3]];
        let dphi = [dt[0][4], dt[1][4], dt[2][4]];
        // In the domain W ≥ the smallest weight (non-negative basis summing to 1). Outside
        // it the extended basis can be negative and unequal weights could send W through 0;
        // the floor keeps the continuation finite (it never acts with equal weights, where
        // W is exactly the weight).
        let floor = 1e-3 * self.min_weight;
        let clamped = wsum < floor;
        if clamped {
            wsum = floor;
        }
        let inv = 1.0 / wsum;
        let position = a.map(|x| x * inv);
        let value = phi * inv;
        let mut out = Eval { position, value, ..Eval::default() };
        if D {
            let dw = if clamped { [0.0; 3] } else { dw };
            for ax in 0..3 {
                for x in 0..3 {
                    out.jacobian[ax][x] = (da[ax][x] - position[x] * dw[ax]) * inv;
                }
                out.gradient[ax] = (dphi[ax] - value * dw[ax]) * inv;
            }
        }
        out
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn unit_box() -> Aabb {
        Aabb { min: Vec3::new(-0.1, 0.05, 0.2), max: Vec3::new(0.2, 0.25, 0.6) }
    }

    /// A small deterministic generator (xorshift), for test parameters.
    pub(crate) struct Rng(pub u64);

    impl Rng {
        pub(crate) fn next_f64(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }

        pub(crate) fn uvw(&mut self, lo: f64, hi: f64) -> Uvw {
            Uvw(std::array::from_fn(|_| lo + (hi - lo) * self.next_f64()))
        }
    }

    /// A variety of volumes: Bézier, uniform and clamped B-splines of several orders, NURBS
    /// and non-uniform knots.
    pub(crate) fn volumes() -> Vec<SplineVolume> {
        let b = unit_box();
        let mut out = vec![
            SplineVolume::bezier(b, [4, 3, 5]).unwrap(),
            SplineVolume::bezier(b, [2, 2, 2]).unwrap(),
            SplineVolume::bspline(b, [6, 5, 4], [4, 3, 2], KnotStyle::Uniform).unwrap(),
            SplineVolume::bspline(b, [8, 8, 8], [4, 4, 4], KnotStyle::Clamped).unwrap(),
            SplineVolume::bspline(b, [16, 7, 9], [4, 5, 3], KnotStyle::Uniform).unwrap(),
            SplineVolume::nurbs(b, [5, 5, 5], [3, 3, 3], KnotStyle::Clamped).unwrap(),
        ];
        let nonuniform = [
            KnotVector::new(6, 3, vec![0.0, 0.0, 0.0, 0.1, 0.5, 0.5, 2.0, 2.0, 2.0]).unwrap(),
            KnotVector::new(5, 4, vec![-1.0, -0.5, 0.0, 0.2, 0.3, 1.5, 1.6, 4.0, 4.0]).unwrap(),
            KnotVector::uniform(4, 2).unwrap(),
        ];
        out.push(SplineVolume::over_box(b, SplineKind::BSpline, nonuniform).unwrap());
        out
    }

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol
    }

    #[test]
    fn the_rest_mapping_is_the_affine_map_of_the_box() {
        let mut rng = Rng(7);
        for vol in volumes() {
            assert!(vol.is_at_rest());
            for _ in 0..200 {
                let uvw = rng.uvw(-0.2, 1.2);
                let p = vol.position(uvw);
                let want = vol.rest_point(uvw);
                assert!(close(p, want, 1e-6), "{:?}: {p} vs {want}", vol.kind());
                // Its Jacobian is the box's size on the diagonal.
                let j = vol.jacobian(uvw);
                let size = Mat3::from_diagonal(vol.region().size());
                assert!(j.abs_diff_eq(size, 1e-5), "{j} vs {size}");
            }
            let corner = vol.position(Uvw::new(1.0, 1.0, 1.0));
            assert!(close(corner, vol.region().max, 1e-6));
            assert!(close(vol.position(Uvw::new(0.0, 0.0, 0.0)), vol.region().min, 1e-6));
        }
    }

    #[test]
    fn equal_weights_and_unit_weights_give_the_b_spline() {
        let b = unit_box();
        let mut spline = SplineVolume::bspline(b, [5, 6, 4], [3, 4, 2], KnotStyle::Clamped).unwrap();
        let mut nurbs = SplineVolume::nurbs(b, [5, 6, 4], [3, 4, 2], KnotStyle::Clamped).unwrap();
        let mut rng = Rng(3);
        let offsets: Vec<(Vec3, f64)> =
            (0..spline.controls().len()).map(|_| (rng.uvw(-0.01, 0.01).to_vec3(), rng.next_f64())).collect();
        for vol in [&mut spline, &mut nurbs] {
            vol.update_positions(|[i, j, k], c| c.rest_m + offsets[i + 5 * (j + 6 * k)].0).unwrap();
            vol.update_values(|[i, j, k], _| offsets[i + 5 * (j + 6 * k)].1).unwrap();
        }
        let check = |nurbs: &SplineVolume, tol: f64| {
            let mut rng = Rng(11);
            for _ in 0..100 {
                let uvw = rng.uvw(0.0, 1.0);
                let (a, b) = (spline.eval::<true>(uvw), nurbs.eval::<true>(uvw));
                assert!((a.value - b.value).abs() < tol);
                for x in 0..3 {
                    assert!((a.position[x] - b.position[x]).abs() < tol);
                    assert!((a.gradient[x] - b.gradient[x]).abs() < tol * 10.0);
                    for y in 0..3 {
                        assert!((a.jacobian[x][y] - b.jacobian[x][y]).abs() < tol * 10.0);
                    }
                }
            }
        };
        check(&nurbs, 1e-14);
        for k in 0..4 {
            for j in 0..6 {
                for i in 0..5 {
                    nurbs.set_weight(i, j, k, 2.5).unwrap();
                }
            }
        }
        assert!(nurbs.has_uniform_weights());
        check(&nurbs, 1e-12);
    }

    #[test]
    fn a_bezier_volume_is_the_bernstein_triple_sum() {
        let b = unit_box();
        let mut vol = SplineVolume::bezier(b, [4, 3, 5]).unwrap();
        let mut rng = Rng(5);
        vol.update_values(|_, _| rng.next_f64()).unwrap();
        vol.update_positions(|_, c| c.rest_m + Vec3::splat(0.02 * rng.next_f64() as f32)).unwrap();
        let bern = |n: usize, i: usize, t: f64| {
            let c = (0..i).fold(1.0, |acc, j| acc * (n - j) as f64 / (j + 1) as f64);
            c * t.powi(i as i32) * (1.0 - t).powi((n - i) as i32)
        };
        for _ in 0..50 {
            let uvw = rng.uvw(0.0, 1.0);
            let [u, v, w] = uvw.0;
            let (mut f, mut p) = (0.0, [0.0; 3]);
            for k in 0..5 {
                for j in 0..3 {
                    for i in 0..4 {
                        let c = vol.control(i, j, k).unwrap();
                        let n = bern(3, i, u) * bern(2, j, v) * bern(4, k, w);
                        f += n * c.value;
                        let q = to_f64(c.position_m);
                        for x in 0..3 {
                            p[x] += n * q[x];
                        }
                    }
                }
            }
            assert!((vol.value(uvw) - f).abs() < 1e-12);
            let got = vol.position_f64(uvw);
            assert!((0..3).all(|x| (got[x] - p[x]).abs() < 1e-12));
        }
    }

    #[test]
    fn a_bezier_volume_is_the_clamped_b_spline_of_full_order() {
        let b = unit_box();
        let mut bezier = SplineVolume::bezier(b, [5, 3, 7]).unwrap();
        let mut spline = SplineVolume::bspline(b, [5, 3, 7], [5, 3, 7], KnotStyle::Clamped).unwrap();
        assert!((0..3).all(|a| bezier.knots(a) == spline.knots(a)));
        let mut rng = Rng(13);
        let moves: Vec<(Vec3, f64)> =
            (0..bezier.controls().len()).map(|_| (rng.uvw(-0.02, 0.02).to_vec3(), rng.next_f64())).collect();
        for vol in [&mut bezier, &mut spline] {
            vol.update_positions(|[i, j, k], c| c.rest_m + moves[i + 5 * (j + 3 * k)].0).unwrap();
            vol.update_values(|[i, j, k], _| moves[i + 5 * (j + 3 * k)].1).unwrap();
        }
        for _ in 0..100 {
            let uvw = rng.uvw(-0.1, 1.1);
            assert_eq!(bezier.value(uvw), spline.value(uvw));
            assert_eq!(bezier.position(uvw), spline.position(uvw));
        }
        // A clamped spline of lower order is no Bézier volume.
        let lower = [0, 1, 2].map(|_| KnotVector::clamped(5, 4).unwrap());
        assert!(SplineVolume::over_box(b, SplineKind::Bezier, lower).is_err());
    }

    #[test]
    fn jacobian_and_gradient_match_finite_differences() {
        let mut rng = Rng(19);
        for mut vol in volumes() {
            let size = vol.region().size().max_element();
            vol.update_positions(|_, c| c.rest_m + rng.uvw(-0.05, 0.05).to_vec3() * size).unwrap();
            vol.update_values(|_, _| rng.next_f64()).unwrap();
            if vol.kind() == SplineKind::Nurbs {
                vol.set_weight(1, 2, 3, 4.0).unwrap();
                vol.set_weight(2, 2, 2, 0.3).unwrap();
            }
            for _ in 0..40 {
                let uvw = rng.uvw(0.01, 0.99);
                let e = vol.eval::<true>(uvw);
                let h = 1e-6;
                for ax in 0..3 {
                    let (mut up, mut dn) = (uvw, uvw);
                    up.0[ax] += h;
                    dn.0[ax] -= h;
                    let (ep, em) = (vol.eval::<false>(up), vol.eval::<false>(dn));
                    let fd = (ep.value - em.value) / (2.0 * h);
                    assert!((fd - e.gradient[ax]).abs() < 1e-4 * (1.0 + fd.abs()), "{:?}", vol.kind());
                    for x in 0..3 {
                        let fd = (ep.position[x] - em.position[x]) / (2.0 * h);
                        assert!((fd - e.jacobian[ax][x]).abs() < 1e-5 * (size as f64 + fd.abs()));
                    }
                }
            }
        }
    }

    #[test]
    fn locating_by_displacements_gives_the_full_sum() {
        let mut rng = Rng(23);
        for mut vol in volumes() {
            let size = vol.region().size().max_element() as f64;
            let n = vol.controls().len();
            // At rest, then a few controls moved (the displacements' sum), then every one
            // (the full sum, past the sparse limit for the larger lattices).
            for moved in [0, 1, 3, n] {
                vol.reset_positions();
                for _ in 0..moved {
                    let index = (rng.next_f64() * n as f64) as usize % n;
                    let [i, j, k] = vol.ijk(index);
                    let p = vol.controls()[index].rest_m + rng.uvw(-0.1, 0.1).to_vec3() * size as f32;
                    vol.set_position(i, j, k, p).unwrap();
                }
                for _ in 0..50 {
                    // In the cube and beyond it, where the end spans' polynomials continue.
                    let uvw = rng.uvw(-0.3, 1.3);
                    let (full, located) = (vol.eval::<true>(uvw), vol.locate::<true>(uvw));
                    for x in 0..3 {
                        assert!(
                            (full.position[x] - located.position[x]).abs() < 1e-12 * size,
                            "{moved} moved"
                        );
                        for a in 0..3 {
                            assert!(
                                (full.jacobian[a][x] - located.jacobian[a][x]).abs() < 1e-11 * size,
                                "{moved} moved: {:?} against {:?}",
                                full.jacobian,
                                located.jacobian
                            );
                        }
                    }
                    let plain = vol.locate::<false>(uvw).position;
                    assert!((0..3).all(|x| (plain[x] - located.position[x]).abs() < 1e-12 * size));
                }
            }
        }
    }

    #[test]
    fn a_point_maps_back_to_rest_within_the_displacements_box() {
        let mut rng = Rng(29);
        for mut vol in volumes() {
            let size = vol.region().size().max_element();
            let n = vol.controls().len();
            for _ in 0..4 {
                let index = (rng.next_f64() * n as f64) as usize % n;
                let [i, j, k] = vol.ijk(index);
                let p = vol.controls()[index].rest_m + rng.uvw(-0.2, 0.2).to_vec3() * size;
                vol.set_position(i, j, k, p).unwrap();
            }
            let d = vol.displacement_box().expect("equal weights");
            for _ in 0..200 {
                let uvw = rng.uvw(0.0, 1.0);
                let off = vol.position(uvw) - vol.rest_point(uvw);
                let slack = Vec3::splat(1e-6 * size);
                assert!(
                    off.cmpge(d.min - slack).all() && off.cmple(d.max + slack).all(),
                    "{off} not in {d:?}"
                );
            }
            // Interior controls alone moved keep a clamped lattice's faces where they were.
            let interior = vol.counts().iter().all(|&c| c > 2)
                && vol.controls().iter().enumerate().all(|(index, c)| {
                    let [i, j, k] = vol.ijk(index);
                    let [l, m, n] = vol.counts();
                    c.position_m == c.rest_m
                        || (i > 0 && j > 0 && k > 0 && i + 1 < l && j + 1 < m && k + 1 < n)
                });
            let clamped = (0..3).all(|a| vol.knots(a).is_clamped());
            assert_eq!(vol.faces_at_rest(), interior && clamped);
            if vol.kind() == SplineKind::Nurbs {
                vol.set_weight(1, 1, 1, 2.0).unwrap();
                assert!(vol.displacement_box().is_none() && !vol.faces_at_rest());
            }
        }
    }

    #[test]
    fn bad_parameters_are_refused_not_panicked_on() {
        let b = unit_box();
        let e = SplineVolume::bspline(b, [4, 17, 4], [3, 3, 3], KnotStyle::Uniform).unwrap_err();
        assert_eq!(e.to_string(), "a lattice needs 2 to 16 control points per axis, not 17 (axis v)");
        assert!(matches!(
            SplineVolume::bspline(b, [4, 4, 4], [3, 5, 3], KnotStyle::Uniform),
            Err(SplineError::Order { axis: 'v', .. })
        ));
        assert!(matches!(SplineVolume::bezier(b, [1, 4, 4]), Err(SplineError::ControlCount { .. })));
        let flat = Aabb { min: Vec3::ZERO, max: Vec3::new(1.0, 0.0, 1.0) };
        assert!(matches!(SplineVolume::bezier(flat, [3, 3, 3]), Err(SplineError::Region { .. })));
        let nan = Aabb { min: Vec3::ZERO, max: Vec3::new(1.0, f32::NAN, 1.0) };
        assert!(matches!(SplineVolume::bezier(nan, [3, 3, 3]), Err(SplineError::Region { .. })));
        let not_bezier = [0, 1, 2].map(|_| KnotVector::uniform(4, 4).unwrap());
        assert!(matches!(
            SplineVolume::over_box(b, SplineKind::Bezier, not_bezier),
            Err(SplineError::NotBezier { .. })
        ));

        let mut vol = SplineVolume::bspline(b, [4, 4, 4], [3, 3, 3], KnotStyle::Uniform).unwrap();
        assert!(matches!(vol.set_weight(0, 0, 0, 2.0), Err(SplineError::NotRational { .. })));
        assert!(matches!(vol.set_position(4, 0, 0, Vec3::ZERO), Err(SplineError::Index { i: 4, .. })));
        assert!(matches!(vol.set_position(0, 0, 0, Vec3::NAN), Err(SplineError::NotFinite { .. })));
        assert!(matches!(vol.set_value(0, 0, 0, f64::INFINITY), Err(SplineError::NotFinite { .. })));
        assert!(matches!(vol.set_values(&[0.0; 3]), Err(SplineError::Length { .. })));
        assert!(vol.update_positions(|_, _| Vec3::INFINITY).is_err());
        assert!(vol.is_at_rest(), "a refused update changes nothing");
        let mut nurbs = SplineVolume::nurbs(b, [4, 4, 4], [3, 3, 3], KnotStyle::Uniform).unwrap();
        for w in [0.0, -1.0, f64::NAN] {
            assert!(matches!(nurbs.set_weight(1, 1, 1, w), Err(SplineError::Weight { .. })));
        }
    }

    #[test]
    fn the_hull_follows_moved_control_points() {
        let mut vol = SplineVolume::bezier(unit_box(), [3, 3, 3]).unwrap();
        assert_eq!(vol.hull(), unit_box());
        vol.set_position(1, 1, 1, Vec3::new(5.0, 0.1, 0.3)).unwrap();
        assert_eq!(vol.hull().max.x, 5.0);
        vol.set_position(1, 1, 1, vol.control(1, 1, 1).unwrap().rest_m).unwrap();
        assert_eq!(vol.hull(), unit_box());
        vol.set_position(0, 0, 0, Vec3::new(-1.0, 0.1, 0.3)).unwrap();
        assert_eq!(vol.hull().min.x, -1.0);
        assert_eq!(vol.hull().min.y, unit_box().min.y);
    }
}
