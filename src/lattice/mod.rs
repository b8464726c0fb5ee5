//! The lattice tool: global deformation of a box of clay by a spline volume (the extended space
//! mapping of the spline-volume sculpting paper, "ESM"), with the control values fitted to the
//! clay by least squares (Hua and Qin's eq. 13, "HQ").
//!
//! Owns a [`Lattice`]: the spline volume placed over a box of the field, the least-squares fit
//! of its function values to the clay there, a dense copy of the clay as it was when the
//! lattice was opened, and the evaluation of the deformed clay over any box of lattice points
//! after a control point was dragged, moved or re-weighted. Depends on `math`, `field` (its
//! public API) and `spline`; knows nothing of meshes, devices or Vulkan.
//!
//! ## What the deformed clay is
//!
//! The lattice never replaces the clay by its spline function: it resamples the clay as it
//! was when the lattice opened. For a sample `x` of the result,
//!
//! ```text
//!   u      = P⁻¹(x)                          the inverse space mapping (ESM §2–3): Newton
//!                                             iteration from the rest lattice's affine inverse
//!   ΔF     = F(u) − F₀(u)                     what the function mapping changed: the current
//!                                             function against the one fitted at opening
//!   g      = ∇ₓF₀(u)                          the fitted function's gradient (per metre)
//!   v      = φ(F) · ΔF · g / (|g|² + ε²)      the shift that moves F₀'s iso-surface by ΔF (the
//!                                             first-order step of ESM's function mapping),
//!                                             φ fading it out away from the new surface
//!   κ      = s(λ · F_c(u))                    ESM's cube function (§3.1) as a window: 0 on
//!                                             the lattice's faces, 1 inside
//!   y      = P_rest(u) + κ · v                where the clay is read
//!
//!   clay'(x) = clay₀(y)                       x in the box, u in the cube
//!            = 0                              x in the box, no preimage in the cube (the
//!                                             deformed lattice has left it)
//!            = max(clay₀(y), clay₀(x))        x outside the box, u in the cube (it has
//!                                             reached out there)
//!            = clay₀(x)                       x outside the box, no preimage in the cube
//! ```
//!
//! read trilinearly, the colour from the nearest sample holding matter. So:
//!
//! - an untouched lattice leaves the clay bit for bit as it was (`y = x`, read at the lattice
//!   point itself), whatever the fit's error;
//! - moving control points warps the clay (ESM's space mapping), its detail carried along;
//! - raising a control's value swells the clay near it, lowering it shrinks it, by as much as
//!   the fitted function's iso-surface would move (ESM's function mapping, to first order),
//!   with the clay's own detail and sharpness kept; raising a value never removes matter
//!   (`v` points up `F₀`'s gradient as `ΔF` grows);
//! - nothing changes outside the deformed lattice and its box, and no ghost solid appears
//!   there: no polynomial is ever evaluated outside the unit cube (the role of ESM §3.1's
//!   R-function clipping), and the function mapping's shift vanishes on the faces;
//! - with clamped knots (the default) a face of the cube maps by its own control points
//!   only: while the outer layer of control points stays where it is, the deformed clay
//!   meets the clay outside without a seam. Moving the outer layer moves the box's face
//!   through the clay and cuts it there, as a sculptor moving the lattice's edge expects.
//!
//! ## Where this departs from the papers, and why
//!
//! ESM's solid is the spline's clipped function itself, `F(P⁻¹(x)) & F_c` (implemented
//! faithfully in `spline`, [`SplineVolume::density_grid`]). Applied to sculpted clay that
//! replaces every detail finer than the lattice by the fit's smooth approximation (the
//! fit's error on a 1 mm bar under an 8³ lattice is about 0.3 in density): an untouched
//! lattice would already blur the sculpt. Resampling the original clay through the same
//! mapping keeps the detail, makes the untouched lattice exact, and moves the surface by the
//! function mapping as far as the paper's solid would move it (`tests`:
//! `a_raised_value_moves_the_surface_as_the_fitted_function_does`).
//!
//! ## Cost
//!
//! A drag changes the mapping only on the dragged control's support
//! ([`SplineVolume::support_world_bounds`] before and after); [`Lattice::changed_box`] says
//! where, and callers re-evaluate only there. The inverse mapping is found by Newton's method
//! at every [`COARSE_STRIDE`]-th point of that box and interpolated between (the points near
//! the box's faces and outside it are mapped one by one); the function mapping's shift, when a
//! value or weight has changed, is evaluated at every point. Rows are evaluated in parallel;
//! each Newton search starts from its neighbour's parameters, extrapolated.

mod edit;
#[cfg(test)]
mod tests;

pub use edit::{volume_at, ControlEdit, Selection, TimedEdit};

use rayon::prelude::*;

use crate::field::{Colour, DenseCopy, Field, DEFAULT_COLOUR};
use crate::math::{Aabb, IVec3, Vec3, VoxelTransform};
use crate::spline::{
    unit_cube_function, FitReport, KnotStyle, SplineError, SplineKind, SplineVolume, Uvw,
    DEFAULT_SAMPLES_PER_SPAN, MAX_SAMPLES_PER_SPAN,
};

/// The most lattice points of the field a lattice may copy (its box, and the room its
/// control points may move into): 2²⁴, 256³, about 320 MiB with their colours.
pub const MAX_SOURCE_POINTS: u64 = 1 << 24;

/// The width of the window `κ` on each face, as a fraction of the box: the clay within it is
/// blended from the mapping to itself.
pub const FACE_BLEND: f64 = 0.05;

/// How far a point may be read from where it is sampled, in units of the finest lattice
/// spacing of the control points: the function mapping's shift is capped there.
pub const MAX_SHIFT_SPACINGS: f64 = 1.0;

/// The fit samples the clay about this often, in voxels, unless told otherwise (see
/// [`LatticeSpec::samples_per_span`]): finer than the clay's surface band, so that the fit
/// sees every surface rather than aliasing it.
pub const FIT_SPACING_VOXELS: f32 = 2.0;

/// A lattice without its box: its kind, its control points per axis, its order and its knots,
/// as the desk and the headset open one over the clay.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LatticeForm {
    /// Bézier, B-spline or NURBS.
    pub kind: SplineKind,
    /// Control points per axis, 2 to 16.
    pub counts: [usize; 3],
    /// The B-spline or NURBS order (degree + 1), 2 to 16; on an axis of fewer controls, their
    /// count. A Bézier lattice's order is its counts.
    pub order: usize,
    /// The knots' spacing (B-spline and NURBS).
    pub knots: KnotStyle,
}

impl Default for LatticeForm {
    /// A cubic NURBS lattice of 4 × 4 × 4 controls with clamped knots: while its weights are
    /// all 1 it is the cubic B-spline, and its weights can be changed too.
    fn default() -> Self {
        Self { kind: SplineKind::Nurbs, counts: [4; 3], order: 4, knots: KnotStyle::Clamped }
    }
}

impl LatticeForm {
    /// The kinds in the order the desk steps through them.
    pub const KINDS: [SplineKind; 3] = [SplineKind::Bezier, SplineKind::BSpline, SplineKind::Nurbs];

    /// The form with its counts and order brought within 2 to 16.
    pub fn within_limits(self) -> Self {
        Self { counts: self.counts.map(|n| n.clamp(2, 16)), order: self.order.clamp(2, 16), ..self }
    }

    /// The lattice of this form over `region` (the part's own frame).
    pub fn over(&self, region: Aabb) -> LatticeSpec {
        let f = self.within_limits();
        LatticeSpec {
            region,
            counts: f.counts,
            kind: f.kind,
            order: f.order,
            knots: f.knots,
            samples_per_span: None,
        }
    }

    /// The next kind: Bézier, B-spline, NURBS, Bézier, …
    pub fn next_kind(self) -> Self {
        let at = Self::KINDS.iter().position(|k| *k == self.kind).unwrap_or(0);
        Self { kind: Self::KINDS[(at + 1) % Self::KINDS.len()], ..self }
    }

    /// In words: "cubic NURBS, 4 × 4 × 4 controls, clamped knots".
    pub fn describe(&self) -> String {
        let [l, m, n] = self.counts;
        let degree = match self.order {
            2 => "linear".to_owned(),
            3 => "quadratic".to_owned(),
            4 => "cubic".to_owned(),
            k => format!("order-{k}"),
        };
        let knots = match self.knots {
            KnotStyle::Clamped => "clamped",
            KnotStyle::Uniform => "uniform",
        };
        match self.kind {
            SplineKind::Bezier => format!("Bézier, {l} × {m} × {n} controls"),
            SplineKind::BSpline => format!("{degree} B-spline, {l} × {m} × {n} controls, {knots} knots"),
            SplineKind::Nurbs => format!("{degree} NURBS, {l} × {m} × {n} controls, {knots} knots"),
        }
    }
}

/// What a lattice is made of: where, how many control points, which kind of spline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatticeSpec {
    /// The world box the rest lattice spans, metres.
    pub region: Aabb,
    /// Control points per axis, 2 to 16.
    pub counts: [usize; 3],
    /// Bézier, B-spline or NURBS.
    pub kind: SplineKind,
    /// The B-spline or NURBS order on every axis (degree + 1; 4 is cubic), at most the axis's
    /// count (a Bézier volume's order is its count).
    pub order: usize,
    /// The knots' spacing (B-spline and NURBS).
    pub knots: KnotStyle,
    /// Samples per knot span and axis for the least-squares fit; `None`: enough for a sample
    /// every [`FIT_SPACING_VOXELS`] voxels along the longest span (3 to 16).
    pub samples_per_span: Option<usize>,
}

impl LatticeSpec {
    /// A cubic B-spline lattice with clamped knots over `region`.
    pub fn cubic(region: Aabb, counts: [usize; 3]) -> Self {
        Self {
            region,
            counts,
            kind: SplineKind::BSpline,
            order: 4,
            knots: KnotStyle::Clamped,
            samples_per_span: None,
        }
    }

    /// The smallest distance between neighbouring rest control points, metres (over the
    /// counts, not the Greville points: a lower bound of theirs for clamped knots).
    pub fn spacing_m(&self) -> f64 {
        (0..3)
            .map(|a| (self.region.size()[a] as f64) / (self.counts[a].max(2) - 1) as f64)
            .fold(f64::INFINITY, f64::min)
    }

    /// The longest shift the function mapping reads the clay at, metres.
    pub fn max_shift_m(&self) -> f64 {
        MAX_SHIFT_SPACINGS * self.spacing_m()
    }

    /// The fit's samples per span for clay of `voxel_m` voxels.
    pub fn fit_samples_per_span(&self, voxel_m: f32) -> usize {
        self.samples_per_span.unwrap_or_else(|| {
            let longest = (0..3)
                .map(|a| {
                    let spans = match self.kind {
                        SplineKind::Bezier => 1,
                        _ => self.counts[a].saturating_sub(self.order.min(self.counts[a])) + 1,
                    };
                    self.region.size()[a] / spans as f32
                })
                .fold(0.0f32, f32::max);
            let wanted = (longest / (FIT_SPACING_VOXELS * voxel_m)).ceil();
            (wanted as usize).clamp(DEFAULT_SAMPLES_PER_SPAN, MAX_SAMPLES_PER_SPAN)
        })
    }

    /// The spline volume at rest, values 0.
    pub fn volume(&self) -> Result<SplineVolume, SplineError> {
        let orders = self.counts.map(|n| self.order.min(n));
        match self.kind {
            SplineKind::Bezier => SplineVolume::bezier(self.region, self.counts),
            SplineKind::BSpline => SplineVolume::bspline(self.region, self.counts, orders, self.knots),
            SplineKind::Nurbs => SplineVolume::nurbs(self.region, self.counts, orders, self.knots),
        }
    }
}

/// Why a lattice cannot be opened, or a change to it is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LatticeError {
    /// The spline refuses the lattice or the change.
    #[error(transparent)]
    Spline(#[from] SplineError),
    /// The box, with the room its control points reach, holds too many samples.
    #[error(
        "the lattice's box and the room its control points reach hold {points} samples of the \
         clay ({size_m:?} m at {voxel_m} m voxels), over the limit of {limit}; make the box \
         smaller, move its control points less far, or use a coarser [field] voxel_size_m"
    )]
    TooLarge {
        /// The samples it would copy.
        points: u64,
        /// [`MAX_SOURCE_POINTS`].
        limit: u64,
        /// The size of the box to copy, metres.
        size_m: [f32; 3],
        /// The field's voxel size.
        voxel_m: f32,
    },
}

/// What an evaluation did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LatticeStats {
    /// Samples evaluated.
    pub points: usize,
    /// Samples whose inverse mapping ran Newton's method (the others were at rest, or had no
    /// preimage in the cube).
    pub searched: usize,
    /// Samples read elsewhere than where they are (the mapping moved them).
    pub moved: usize,
    /// Newton iterations, in all.
    pub newton_iterations: u64,
    /// Samples whose parameters were interpolated between the coarse grid's nodes, or whose
    /// cell of constant clay needed none.
    pub interpolated: usize,
}

impl std::ops::Add for LatticeStats {
    type Output = LatticeStats;

    fn add(self, o: LatticeStats) -> LatticeStats {
        LatticeStats {
            points: self.points + o.points,
            searched: self.searched + o.searched,
            moved: self.moved + o.moved,
            newton_iterations: self.newton_iterations + o.newton_iterations,
            interpolated: self.interpolated + o.interpolated,
        }
    }
}

/// The spacing, in lattice points, of the nodes where a deformed lattice's inverse mapping is
/// found by Newton's method; between them the parameters are interpolated trilinearly (the
/// mapping is a polynomial of the lattice's order over spans many voxels long: `tests` bound
/// the error it makes), and the function mapping's shift, which varies on the scale of the
/// clay's surface, is evaluated at every point.
pub const COARSE_STRIDE: i32 = 4;

/// The parameters at the nodes of a coarse grid over a box of lattice points (in the cube or
/// not): `None` at nodes where the search found none (outside the control points' hull, or
/// not converged), around which points are mapped one by one.
#[derive(Debug)]
struct CoarseMap {
    counts: IVec3,
    /// The lattice point of the first node: the grid covers the lattice's box (where the
    /// mapping is smooth) within the box of points evaluated.
    origin: IVec3,
    /// The offset of the grid's last point from its first: node `n` lies at
    /// `origin + min(n · COARSE_STRIDE, last)`, so that the last nodes lie on its far faces.
    last: IVec3,
    nodes: Vec<Option<[f64; 3]>>,
    /// Per cell (`counts − 1` per axis): the density of every point in it, when every read
    /// its points make lies where the clay is constant (the rest mapping is affine, so
    /// their reads lie in the box of its corners' reads), and no shift applies.
    constant: Vec<Option<f32>>,
}

impl CoarseMap {
    /// For the row of lattice points `(·, y, z)` of `p`: per node column, the parameters
    /// interpolated in `y` and `z` from the four nodes around the row (`None` where one of
    /// them has none); `None` for a row outside the grid.
    fn row_edges(&self, p: IVec3) -> Option<Vec<Option<[f64; 3]>>> {
        let q = p - self.origin;
        if q.y < 0 || q.z < 0 || q.y > self.last.y || q.z > self.last.z {
            return None;
        }
        let (cy, ty) = self.cell(1, q.y);
        let (cz, tz) = self.cell(2, q.z);
        let (nx, ny) = (self.counts.x as usize, self.counts.y as usize);
        let node = |x: usize, y: i32, z: i32| self.nodes[x + nx * (y as usize + ny * z as usize)];
        Some(
            (0..nx)
                .map(|x| {
                    let corners =
                        [node(x, cy, cz), node(x, cy + 1, cz), node(x, cy, cz + 1), node(x, cy + 1, cz + 1)];
                    let [a, b, c, d] = [corners[0]?, corners[1]?, corners[2]?, corners[3]?];
                    Some(std::array::from_fn(|i| {
                        let low = a[i] + (b[i] - a[i]) * ty;
                        let high = c[i] + (d[i] - c[i]) * ty;
                        low + (high - low) * tz
                    }))
                })
                .collect(),
        )
    }

    /// The offset of node `n` along `axis`.
    #[inline]
    fn node_offset(&self, axis: usize, n: i32) -> i32 {
        (n * COARSE_STRIDE).min(self.last[axis])
    }

    /// The cell holding offset `o` along `axis`, and where in it `o` lies (0 to 1).
    #[inline]
    fn cell(&self, axis: usize, o: i32) -> (i32, f64) {
        let c = (o / COARSE_STRIDE).min(self.counts[axis] - 2);
        let (a, b) = (self.node_offset(axis, c), self.node_offset(axis, c + 1));
        (c, (o - a) as f64 / (b - a).max(1) as f64)
    }

    /// The constant density of the cell holding lattice point `p`, if it has one.
    #[inline]
    fn constant_at(&self, p: IVec3) -> Option<f32> {
        let q = p - self.origin;
        if q.cmplt(IVec3::ZERO).any() || q.cmpgt(self.last).any() {
            return None;
        }
        let c = IVec3::new(self.cell(0, q.x).0, self.cell(1, q.y).0, self.cell(2, q.z).0);
        let cells = self.counts - IVec3::ONE;
        self.constant[(c.x + cells.x * (c.y + cells.y * c.z)) as usize]
    }

    /// The parameters at lattice point `(x, ·, ·)` of the row whose `edges` are given.
    #[inline]
    fn interpolate(&self, edges: &[Option<[f64; 3]>], x: i32) -> Option<[f64; 3]> {
        let q = x - self.origin.x;
        if q < 0 || q > self.last.x {
            return None;
        }
        let (c, t) = self.cell(0, q);
        let (a, b) = (edges[c as usize]?, edges[c as usize + 1]?);
        Some(std::array::from_fn(|i| a[i] + (b[i] - a[i]) * t))
    }
}

/// The lattice points a lattice of `spec` copies when its control points span `hull`: the box
/// and the hull, grown by the longest shift and two voxels; and how many they are.
fn source_bounds(spec: &LatticeSpec, t: &VoxelTransform, hull: Aabb) -> (IVec3, IVec3, u64) {
    let room = spec.max_shift_m() as f32 + 2.0 * t.voxel_size_m;
    let world = spec.region.union(&hull).expanded(room);
    let lo = t.world_to_index(world.min).floor().as_ivec3();
    let hi = t.world_to_index(world.max).ceil().as_ivec3();
    let dims = (hi - lo + IVec3::ONE).as_i64vec3();
    (lo, hi, (dims.x * dims.y * dims.z).max(0) as u64)
}

/// How many samples of clay of `voxel_m` voxels a lattice of `spec` copies when its control
/// points span `hull` (refused over [`MAX_SOURCE_POINTS`]).
pub fn source_points(spec: &LatticeSpec, voxel_m: f32, hull: Aabb) -> u64 {
    source_bounds(spec, &VoxelTransform::new(voxel_m), hull).2
}

/// A lattice open over a box of clay: the spline volume as the user shapes it, the function
/// it was fitted with, and the clay as it was.
#[derive(Clone, Debug)]
pub struct Lattice {
    spec: LatticeSpec,
    volume: SplineVolume,
    /// The volume as opened: control values fitted to the clay, weights 1, at rest.
    fitted: SplineVolume,
    fit: FitReport,
    transform: VoxelTransform,
    source: DenseCopy,
    /// The field's iso-level: the surface the function mapping moves.
    iso: f64,
    /// `ε` of the shift, per metre.
    epsilon: f64,
    /// The longest shift, metres.
    max_shift_m: f64,
    /// `λ` of the window: `λ F_c = 1` at [`FACE_BLEND`] inside a face.
    window_scale: f64,
    /// What opening it cost.
    opened: OpenTimes,
}

/// What opening a lattice cost, seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OpenTimes {
    /// Copying the clay of its box.
    pub copy_s: f64,
    /// Fitting its control values.
    pub fit_s: f64,
}

/// How one sample of the result reads the clay as it was.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Read {
    /// Its own lattice point: nothing moved it (the lattice at rest there, or outside it).
    Own,
    /// The clay at these index coordinates (the mapping's source), alone: the sample lies in
    /// the lattice's box.
    At([f64; 3]),
    /// The densest of the clay there and of its own: the sample lies outside the box, where
    /// the deformed lattice has reached.
    AtOrOwn([f64; 3]),
    /// Nothing: the sample lies in the box, but the deformed lattice has left it.
    Empty,
}

/// What the lattice is, as every point's mapping needs it: found once per evaluation.
#[derive(Clone, Copy, Debug)]
struct State {
    /// [`SplineVolume::is_at_rest`].
    at_rest: bool,
    /// [`Lattice::shifts`].
    shifting: bool,
}

/// One sample of the result: how it reads the clay, and its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mapped {
    /// Where the clay is read.
    pub read: Read,
    /// Its parameters, when it has a preimage.
    pub uvw: Option<Uvw>,
    /// Whether the sample lies in the lattice's box.
    pub in_box: bool,
    /// Newton iterations spent.
    pub iterations: u32,
}

fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl Lattice {
    /// Opens a lattice over `spec.region` of `field`: copies the clay there (and the margin
    /// its function mapping may read), fits the control values to it (HQ eq. 13, one solve
    /// per axis) and leaves the lattice at rest.
    pub fn open(field: &Field, spec: &LatticeSpec) -> Result<Self, LatticeError> {
        let mut volume = spec.volume()?;
        let transform = *field.transform();
        let spacing = spec.spacing_m();
        let mut lattice = Self {
            spec: *spec,
            fitted: volume.clone(),
            volume: volume.clone(),
            fit: FitReport { max_error: 0.0, rms_error: 0.0, samples: 0 },
            transform,
            source: DenseCopy::default(),
            iso: field.iso() as f64,
            epsilon: 0.25 / spacing,
            max_shift_m: spec.max_shift_m(),
            window_scale: 1.0 / (FACE_BLEND * (1.0 - FACE_BLEND)),
            opened: OpenTimes::default(),
        };
        let (lo, hi) = lattice.source_box(volume.hull())?;
        let start = std::time::Instant::now();
        lattice.source = DenseCopy::read(field, lo, hi);
        lattice.opened.copy_s = start.elapsed().as_secs_f64();
        let start = std::time::Instant::now();
        let source = &lattice.source;
        let to_index = |x: Vec3| {
            let p = transform.world_to_index(x);
            [p.x as f64, p.y as f64, p.z as f64]
        };
        let per_span = spec.fit_samples_per_span(transform.voxel_size_m);
        lattice.fit = volume.fit_field(|x| source.density_f64(to_index(x)), per_span)?;
        lattice.opened.fit_s = start.elapsed().as_secs_f64();
        lattice.fitted = volume.clone();
        lattice.volume = volume;
        Ok(lattice)
    }

    /// The lattice points to copy so that every read of the result over `hull` (the control
    /// points' box) lies in the copy; refused over [`MAX_SOURCE_POINTS`].
    fn source_box(&self, hull: Aabb) -> Result<(IVec3, IVec3), LatticeError> {
        let (lo, hi, points) = source_bounds(&self.spec, &self.transform, hull);
        if points > MAX_SOURCE_POINTS {
            let t = &self.transform;
            return Err(LatticeError::TooLarge {
                points,
                limit: MAX_SOURCE_POINTS,
                size_m: ((hi - lo).as_vec3() * t.voxel_size_m).to_array(),
                voxel_m: t.voxel_size_m,
            });
        }
        Ok((lo, hi))
    }

    /// What the lattice was made from.
    pub fn spec(&self) -> &LatticeSpec {
        &self.spec
    }

    /// The spline volume as it is now.
    pub fn volume(&self) -> &SplineVolume {
        &self.volume
    }

    /// The volume as it was opened: at rest, the control values fitted to the clay.
    pub fn fitted(&self) -> &SplineVolume {
        &self.fitted
    }

    /// What opening it cost.
    pub fn open_times(&self) -> OpenTimes {
        self.opened
    }

    /// How well the fitted values match the clay at the fit's samples.
    pub fn fit_report(&self) -> FitReport {
        self.fit
    }

    /// The bytes the copy of the clay holds.
    pub fn source_bytes(&self) -> usize {
        self.source.bytes()
    }

    /// The world box where the result can differ from the clay: the box and the control
    /// points' hull, with the room the shift may read.
    pub fn reach(&self) -> Aabb {
        self.spec.region.union(&self.volume.hull()).expanded(self.transform.voxel_size_m)
    }

    /// The world box where moving, re-valuing or re-weighting control `(i, j, k)` changes the
    /// result, for its current positions: its support's image (see
    /// [`SplineVolume::support_world_bounds`]), cut to the reach.
    pub fn changed_box(&self, ijk: [usize; 3]) -> Result<Aabb, LatticeError> {
        let [i, j, k] = ijk;
        // The window is 0 outside the cube: no band beyond the faces.
        let clip = crate::spline::Clipping::with_band(0.5, 1e-3)?;
        let b = self.volume.support_world_bounds(i, j, k, &clip)?;
        let reach = self.reach();
        Ok(Aabb { min: b.min.max(reach.min), max: b.max.min(reach.max) }
            .expanded(self.transform.voxel_size_m))
    }

    /// Moves control `(i, j, k)` to `position_m`; returns the world box to re-evaluate
    /// (the changed box before and after). Refused, and nothing changes, when the control
    /// points would reach so far that the copy of the clay grows over its limit.
    pub fn move_control(&mut self, ijk: [usize; 3], position_m: Vec3) -> Result<Aabb, LatticeError> {
        let before = self.changed_box(ijk)?;
        let [i, j, k] = ijk;
        let old = self.volume.control(i, j, k)?.position_m;
        self.volume.set_position(i, j, k, position_m)?;
        if let Err(e) = self.source_box(self.volume.hull()) {
            self.volume.set_position(i, j, k, old)?;
            return Err(e);
        }
        Ok(before.union(&self.changed_box(ijk)?))
    }

    /// Sets control `(i, j, k)`'s function value; returns the world box to re-evaluate.
    pub fn set_value(&mut self, ijk: [usize; 3], value: f64) -> Result<Aabb, LatticeError> {
        let [i, j, k] = ijk;
        self.volume.set_value(i, j, k, value)?;
        self.changed_box(ijk)
    }

    /// Sets control `(i, j, k)`'s NURBS weight; returns the world box to re-evaluate.
    pub fn set_weight(&mut self, ijk: [usize; 3], weight: f64) -> Result<Aabb, LatticeError> {
        let [i, j, k] = ijk;
        self.volume.set_weight(i, j, k, weight)?;
        self.changed_box(ijk)
    }

    /// Replaces the volume's control positions, values and weights by those of `volume`
    /// (the same lattice, shaped elsewhere: a scripted key, a sculpt file); returns the world
    /// box to re-evaluate (the changed boxes of the controls that changed, before and after),
    /// or `None` when nothing changed. Refused, and nothing changes, when `volume` is not the
    /// same lattice or reaches too far.
    pub fn set_controls(&mut self, volume: &SplineVolume) -> Result<Option<Aabb>, LatticeError> {
        let same = volume.counts() == self.volume.counts()
            && volume.kind() == self.volume.kind()
            && volume.region() == self.volume.region()
            && (0..3).all(|a| volume.knots(a) == self.volume.knots(a));
        if !same {
            return Err(SplineError::Parameter {
                name: "the lattice's controls",
                what: "those of a lattice of the same kind, counts, knots and box",
                value: f64::NAN,
            }
            .into());
        }
        self.source_box(volume.hull())?;
        let [l, m, _] = self.volume.counts();
        let changed: Vec<[usize; 3]> = self
            .volume
            .controls()
            .iter()
            .zip(volume.controls())
            .enumerate()
            .filter(|(_, (a, b))| a != b)
            .map(|(n, _)| [n % l, (n / l) % m, n / (l * m)])
            .collect();
        if changed.is_empty() {
            return Ok(None);
        }
        let mut region = Aabb::EMPTY;
        for &ijk in &changed {
            region = region.union(&self.changed_box(ijk)?);
        }
        self.volume = volume.clone();
        for &ijk in &changed {
            region = region.union(&self.changed_box(ijk)?);
        }
        Ok(Some(region))
    }

    /// Where the clay is read for the world point `x` (see the module documentation); the
    /// inverse mapping starts from `start` when given.
    pub fn map_point(&self, x: Vec3, start: Option<Uvw>) -> Mapped {
        let xi = self.transform.world_to_index(x);
        self.map_index([xi.x as f64, xi.y as f64, xi.z as f64], start, &self.state())
    }

    /// [`Self::map_point`] for the point at index coordinates `own` of the field's lattice.
    fn map_index(&self, own: [f64; 3], start: Option<Uvw>, state: &State) -> Mapped {
        let t = &self.transform;
        let voxel = t.voxel_size_m as f64;
        let origin = t.origin_m;
        let x = Vec3::new(
            (origin.x as f64 + own[0] * voxel) as f32,
            (origin.y as f64 + own[1] * voxel) as f32,
            (origin.z as f64 + own[2] * voxel) as f32,
        );
        let in_box = self.volume.rest_parameters(x).is_in_unit_cube();
        // Where no preimage lies in the cube: the clay as it was outside the box, none inside.
        let left = |uvw: Option<Uvw>, iterations: u32| Mapped {
            read: if in_box { Read::Empty } else { Read::Own },
            uvw,
            in_box,
            iterations,
        };
        let (uvw, iterations) = if state.at_rest {
            (self.volume.rest_parameters(x), 0)
        } else {
            // Outside the control points' hull nothing has a preimage in the cube (convex
            // hull property); inside it, the neighbour's parameters first, the searches with
            // fallback starts only where that fails.
            let hull = self.volume.hull();
            if !(x.cmpge(hull.min).all() && x.cmple(hull.max).all()) {
                return left(None, 0);
            }
            let (mut m, _) = self.volume.inverse_map_within(x, start, Vec3::ZERO, false);
            if !m.converged {
                let spent = m.iterations;
                m = self.volume.inverse_map_from(x, start);
                m.iterations += spent;
            }
            if !m.converged {
                return left(None, m.iterations);
            }
            (m.uvw, m.iterations)
        };
        if !uvw.is_in_unit_cube() {
            return left(Some(uvw), iterations);
        }
        let read = self.read_at_parameters(own, uvw, in_box, state.shifting);
        Mapped { read, uvw: Some(uvw), in_box, iterations }
    }

    /// What every point's mapping asks of the whole lattice, found once per evaluation.
    fn state(&self) -> State {
        State { at_rest: self.volume.is_at_rest(), shifting: self.shifts() }
    }

    /// Whether the function mapping shifts anything: some control's value or weight differs
    /// from the fitted lattice's.
    fn shifts(&self) -> bool {
        self.volume
            .controls()
            .iter()
            .zip(self.fitted.controls())
            .any(|(a, b)| a.value != b.value || a.weight != b.weight)
    }

    /// How the point at index coordinates `own`, whose parameters `uvw` lie in the cube,
    /// reads the clay (`shifting`: [`Self::shifts`]).
    #[inline]
    fn read_at_parameters(&self, own: [f64; 3], uvw: Uvw, in_box: bool, shifting: bool) -> Read {
        let t = &self.transform;
        let (voxel, origin) = (t.voxel_size_m as f64, t.origin_m);
        let region = self.spec.region;
        let (min, size) = (region.min, region.size());
        let mut rest: [f64; 3] = std::array::from_fn(|a| min[a] as f64 + size[a] as f64 * uvw.0[a]);
        // The function mapping's shift, faded out on the faces so that it meets the clay
        // outside without a step.
        if shifting {
            let kappa = smoothstep(self.window_scale * unit_cube_function(uvw));
            if kappa > 0.0 {
                let shift = self.shift(uvw);
                for a in 0..3 {
                    rest[a] += kappa * shift[a];
                }
            }
        }
        let read_at: [f64; 3] = std::array::from_fn(|a| (rest[a] - origin[a] as f64) / voxel);
        let moved = (0..3).any(|a| (read_at[a] - own[a]).abs() > 1e-4);
        match (moved, in_box) {
            (false, true) => Read::Own,
            (true, true) => Read::At(read_at),
            (_, false) => Read::AtOrOwn(read_at),
        }
    }

    /// The function mapping's shift at `uvw`, metres: `ΔF g / (|g|² + ε²)`, capped.
    fn shift(&self, uvw: Uvw) -> [f64; 3] {
        let f = self.volume.value(uvw);
        let (f0, grad) = self.fitted.value_and_gradient(uvw);
        let delta = f - f0;
        // The first-order step holds near the new surface (F = iso); away from it, deep in
        // the clay or far out in the air, reading elsewhere changes nothing but could reach
        // through a thin wall: the shift fades out.
        let t = (2.0 * (f - self.iso)).abs().min(1.0);
        let fade = 1.0 - t * t;
        if delta == 0.0 || fade == 0.0 || !delta.is_finite() {
            return [0.0; 3];
        }
        let size = self.spec.region.size();
        let g: [f64; 3] = std::array::from_fn(|a| grad[a] / size[a] as f64);
        let g2 = g.iter().map(|c| c * c).sum::<f64>();
        let scale = fade * delta / (g2 + self.epsilon * self.epsilon);
        let mut v = g.map(|c| c * scale);
        let len = v.iter().map(|c| c * c).sum::<f64>().sqrt();
        if len > self.max_shift_m {
            v = v.map(|c| c * self.max_shift_m / len);
        }
        v
    }

    /// The lattice points of the field covering a world box.
    pub fn points_of(&self, world: Aabb) -> (IVec3, IVec3) {
        let t = &self.transform;
        (t.world_to_index(world.min).floor().as_ivec3(), t.world_to_index(world.max).ceil().as_ivec3())
    }

    /// The deformed clay's densities (and with `colours`, colours) at the lattice points
    /// `lo ..= hi`, `x` fastest; rows in parallel.
    pub fn evaluate(
        &self,
        lo: IVec3,
        hi: IVec3,
        densities: &mut Vec<f32>,
        colours: Option<&mut Vec<Colour>>,
    ) -> LatticeStats {
        self.evaluate_with(lo, hi, densities, colours, true)
    }

    /// [`Self::evaluate`], the mapping interpolated between the nodes of a coarse grid when
    /// `coarse`, found at every point otherwise.
    fn evaluate_with(
        &self,
        lo: IVec3,
        hi: IVec3,
        densities: &mut Vec<f32>,
        mut colours: Option<&mut Vec<Colour>>,
        coarse: bool,
    ) -> LatticeStats {
        let dims = (hi - lo + IVec3::ONE).max(IVec3::ZERO);
        let n = (dims.x as usize) * (dims.y as usize) * (dims.z as usize);
        densities.clear();
        densities.resize(n, 0.0);
        if let Some(c) = colours.as_deref_mut() {
            c.clear();
            c.resize(n, DEFAULT_COLOUR);
        }
        if n == 0 {
            return LatticeStats::default();
        }
        let nx = dims.x as usize;
        let row_of = |row: usize| {
            IVec3::new(lo.x, lo.y + (row % dims.y as usize) as i32, lo.z + (row / dims.y as usize) as i32)
        };
        let (coarse, coarse_stats) =
            if coarse { self.coarse_map(lo, dims) } else { (None, LatticeStats::default()) };
        let state = self.state();
        let shifting = state.shifting;
        let t = self.transform;
        let eval_row = |row: usize, out: &mut [f32], mut colour: Option<&mut [Colour]>| {
            let start = row_of(row);
            let mut stats = LatticeStats { points: nx, ..LatticeStats::default() };
            let edges = coarse.as_ref().and_then(|c| c.row_edges(start));
            let mut previous: [Option<Uvw>; 2] = [None, None];
            for (x, d) in out.iter_mut().enumerate() {
                let p = start + IVec3::new(x as i32, 0, 0);
                let own = [p.x as f64, p.y as f64, p.z as f64];
                // A cell of constant clay: its value, and no colour to find but the default.
                if let Some(v) = coarse.as_ref().and_then(|c| c.constant_at(p)) {
                    if v == 0.0 || colour.is_none() {
                        stats.interpolated += 1;
                        *d = v;
                        if let Some(out) = colour.as_deref_mut() {
                            out[x] = DEFAULT_COLOUR;
                        }
                        continue;
                    }
                }
                let interpolated = match (&coarse, &edges) {
                    (Some(c), Some(e)) => c.interpolate(e, p.x).map(Uvw),
                    _ => None,
                };
                stats.interpolated += usize::from(interpolated.is_some());
                let read = match interpolated {
                    Some(uvw) => {
                        let x = t.index_to_world(p.as_vec3());
                        let in_box = self.volume.rest_parameters(x).is_in_unit_cube();
                        match (uvw.is_in_unit_cube(), in_box) {
                            (true, _) => self.read_at_parameters(own, uvw, in_box, shifting),
                            (false, true) => Read::Empty,
                            (false, false) => Read::Own,
                        }
                    }
                    None => {
                        let guess = match previous {
                            [Some(a), Some(b)] => Some(Uvw(std::array::from_fn(|i| 2.0 * b.0[i] - a.0[i]))),
                            [_, b] => b,
                        };
                        let m = self.map_index(own, guess, &state);
                        previous = [previous[1], m.uvw];
                        stats.searched += usize::from(m.iterations > 0);
                        stats.newton_iterations += m.iterations as u64;
                        m.read
                    }
                };
                stats.moved += usize::from(read != Read::Own);
                let (density, c) = self.read(p, read, colour.is_some());
                *d = density;
                if let Some(out) = colour.as_deref_mut() {
                    out[x] = c;
                }
            }
            stats
        };
        let stats = match colours {
            Some(c) => densities
                .par_chunks_mut(nx)
                .zip(c.par_chunks_mut(nx))
                .enumerate()
                .map(|(row, (out, colour))| eval_row(row, out, Some(colour)))
                .reduce(LatticeStats::default, |a, b| a + b),
            None => densities
                .par_chunks_mut(nx)
                .enumerate()
                .map(|(row, out)| eval_row(row, out, None))
                .reduce(LatticeStats::default, |a, b| a + b),
        };
        let LatticeStats { searched, newton_iterations, .. } = coarse_stats;
        LatticeStats {
            searched: stats.searched + searched,
            newton_iterations: stats.newton_iterations + newton_iterations,
            ..stats
        }
    }

    /// The density and colour of sample `p` read as `read` says (the colour only when asked).
    #[inline]
    fn read(&self, p: IVec3, read: Read, colour: bool) -> (f32, Colour) {
        let own = || (self.source.density(p), self.source.colour(p));
        let at = |q: [f64; 3]| {
            let d = self.source.density_f64(q).clamp(0.0, 1.0);
            (d, if colour { self.source.colour_near(q) } else { DEFAULT_COLOUR })
        };
        match read {
            Read::Own => own(),
            Read::Empty => (0.0, DEFAULT_COLOUR),
            Read::At(q) => at(q),
            Read::AtOrOwn(q) => {
                let (o, a) = (own(), at(q));
                if o.0 >= a.0 {
                    o
                } else {
                    a
                }
            }
        }
    }

    /// The mapping at every [`COARSE_STRIDE`]-th lattice point of the box of `dims` points from
    /// `lo` (and one node past its far end), node rows in parallel; `None` when the lattice
    /// is at rest (every point's own read is cheaper) or the box too thin.
    fn coarse_map(&self, lo: IVec3, dims: IVec3) -> (Option<CoarseMap>, LatticeStats) {
        let s = COARSE_STRIDE;
        let state = self.state();
        // The grid covers the lattice's box within the points evaluated: outside the box the
        // mapping has no preimage or meets the clay outside, and is found point by point.
        let t = &self.transform;
        let region = self.spec.region;
        let box_lo = t.world_to_index(region.min).ceil().as_ivec3();
        let box_hi = t.world_to_index(region.max).floor().as_ivec3();
        let lo = lo.max(box_lo);
        let last = (lo + dims - IVec3::ONE).min(box_hi) - lo;
        if state.at_rest || last.min_element() < 2 * s {
            return (None, LatticeStats::default());
        }
        let counts = (last + IVec3::splat(s - 1)) / s + IVec3::ONE;
        let (cx, cy) = (counts.x as usize, counts.y as usize);
        let mut nodes = vec![None; cx * cy * counts.z as usize];
        let stats = nodes
            .par_chunks_mut(cx)
            .enumerate()
            .map(|(row, out)| {
                let (y, z) = ((row % cy) as i32, (row / cy) as i32);
                let mut stats = LatticeStats::default();
                let mut previous: Option<Uvw> = None;
                for (x, node) in out.iter_mut().enumerate() {
                    let p = lo + (s * IVec3::new(x as i32, y, z)).min(last);
                    let m = self.map_index([p.x as f64, p.y as f64, p.z as f64], previous, &state);
                    previous = m.uvw;
                    stats.searched += usize::from(m.iterations > 0);
                    stats.newton_iterations += m.iterations as u64;
                    // Its parameters wherever the search converged, in the cube or not.
                    *node = m.uvw.map(|u| u.0);
                }
                stats
            })
            .reduce(LatticeStats::default, |a, b| a + b);
        let cells = counts - IVec3::ONE;
        let read_of = |u: [f64; 3]| -> [f64; 3] {
            std::array::from_fn(|a| {
                let world = region.min[a] as f64 + region.size()[a] as f64 * u[a];
                (world - t.origin_m[a] as f64) / t.voxel_size_m as f64
            })
        };
        let node = |x: i32, y: i32, z: i32| nodes[(x + counts.x * (y + counts.y * z)) as usize];
        let constant = (0..cells.x * cells.y * cells.z)
            .into_par_iter()
            .map(|c| {
                if state.shifting {
                    return None;
                }
                let (x, y, z) = (c % cells.x, (c / cells.x) % cells.y, c / (cells.x * cells.y));
                let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
                for n in 0..8 {
                    let u = node(x + (n & 1), y + ((n >> 1) & 1), z + ((n >> 2) & 1))?;
                    let r = read_of(u);
                    for a in 0..3 {
                        lo[a] = lo[a].min(r[a]);
                        hi[a] = hi[a].max(r[a]);
                    }
                }
                let lo = IVec3::new(lo[0].floor() as i32, lo[1].floor() as i32, lo[2].floor() as i32);
                let hi =
                    IVec3::new(hi[0].floor() as i32, hi[1].floor() as i32, hi[2].floor() as i32) + IVec3::ONE;
                self.source.constant_density(lo, hi)
            })
            .collect();
        (Some(CoarseMap { counts, origin: lo, last, nodes, constant }), stats)
    }

    /// Evaluates the deformed clay over `world` and writes it into `field`, growing the copy
    /// of the clay first where the control points now reach beyond it. The caller holds
    /// `field`'s stroke open (the lattice's whole session is one undo step).
    pub fn write(&mut self, field: &mut Field, world: Aabb) -> Result<LatticeStats, LatticeError> {
        let (slo, shi) = self.source_box(self.volume.hull())?;
        if !self.source.contains(slo, shi) {
            let lo = slo.min(self.source.lo());
            let hi = shi.max(self.source.hi());
            self.source = self.source.grown(field, lo, hi);
        }
        let reach = self.reach();
        let world = Aabb { min: world.min.max(reach.min), max: world.max.min(reach.max) };
        if world.is_empty() {
            return Ok(LatticeStats::default());
        }
        let (lo, hi) = self.points_of(world);
        let (mut d, mut c) = (Vec::new(), Vec::new());
        let stats = self.evaluate(lo, hi, &mut d, Some(&mut c));
        let dims = hi - lo + IVec3::ONE;
        let at = |p: IVec3| {
            let q = p - lo;
            (q.x + dims.x * (q.y + dims.y * q.z)) as usize
        };
        field.edit_box(lo, hi, true, |p, density, colour| {
            let i = at(p);
            *density = d[i];
            if d[i] > 0.0 {
                *colour = c[i];
            }
        });
        Ok(stats)
    }

    /// Puts the clay back as it was over everything the lattice reaches, and the lattice at
    /// rest with its fitted values.
    pub fn reset(&mut self, field: &mut Field) -> Result<LatticeStats, LatticeError> {
        let before = self.reach();
        self.volume = self.fitted.clone();
        self.write(field, before.union(&self.reach()))
    }
}
