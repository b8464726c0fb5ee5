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
//! where, and [`Lattice::write`] re-evaluates only there, brick by brick ([`BrickPlan`]):
//!
//! - Where the weights are equal, a point's read lies within the moved controls'
//!   displacements of the point (`A(u) = x − Σ N_i(u) d_i`): a brick whose every such read
//!   lies in empty clay is empty, one whose reads lie in full clay of one colour is full of it
//!   (when the cube's faces are at rest, so that every point has a preimage), with no inverse
//!   mapping found at all.
//! - For the other bricks the inverse mapping is found by Newton's method at the nodes of a
//!   grid every [`COARSE_STRIDE`] points (each search from its row's two nodes before it,
//!   extrapolated, to [`MAPPING_TOLERANCE_VOXELS`]) and interpolated between; the reads of a
//!   brick, or of a 4³ block of one, lie between its nodes' reads, which decide it whole
//!   where they can.
//! - Only the points of the blocks left mixed are evaluated one by one (the function
//!   mapping's shift, when a value or weight has changed, at each), on every thread; a brick
//!   that comes out as the last write left it is not written again.
//!
//! [`Lattice::evaluate`] is the same mapping point by point over any box (the reference the
//! tests hold the writes to).

mod edit;
#[cfg(test)]
mod tests;

pub use edit::{volume_at, ControlEdit, Selection, TimedEdit};

use rayon::prelude::*;

use crate::field::{
    bricks_over, Brick, BrickPlan, Colour, DenseCopy, Field, Fill, Holds, BRICK_SIZE, DEFAULT_COLOUR,
};
use crate::math::{floor_i32, Aabb, IVec3, Vec3, VoxelTransform};
use crate::spline::{
    unit_cube_function, FitReport, KnotStyle, SplineError, SplineKind, SplineVolume, Uvw,
    DEFAULT_SAMPLES_PER_SPAN, MAX_SAMPLES_PER_SPAN,
};

/// The most lattice points of the field a lattice may copy (its box, and the room its
/// control points may move into): 2²⁴, 256³, about 320 MiB with their colours.
pub const MAX_SOURCE_POINTS: u64 = 1 << 24;

/// How closely the inverse mapping is solved for, in voxels: the clay is read trilinearly, so
/// an error this small changes no density by more than it times the steepest ramp (about one
/// per voxel).
pub const MAPPING_TOLERANCE_VOXELS: f64 = 1e-5;

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

/// What an evaluation or a write did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LatticeStats {
    /// Samples evaluated one by one (a write's whole bricks and blocks filled or given back
    /// are not).
    pub points: usize,
    /// Samples whose inverse mapping ran Newton's method (the others were at rest, had no
    /// preimage in the cube, or were interpolated), the coarse grid's nodes included.
    pub searched: usize,
    /// Samples read elsewhere than where they are (the mapping moved them).
    pub moved: usize,
    /// Newton iterations, in all.
    pub newton_iterations: u64,
    /// Samples whose parameters were interpolated between the coarse grid's nodes.
    pub interpolated: usize,
    /// Samples written into the field (a write: every brick it changed).
    pub written: u64,
    /// Bricks written.
    pub bricks: usize,
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
            written: self.written + o.written,
            bricks: self.bricks + o.bricks,
        }
    }
}

/// The spacing, in lattice points, of the nodes where a deformed lattice's inverse mapping is
/// found by Newton's method; between them the parameters are interpolated trilinearly (the
/// mapping is a polynomial of the lattice's order over spans many voxels long: `tests` bound
/// the error it makes), and the function mapping's shift, which varies on the scale of the
/// clay's surface, is evaluated at every point. Nodes lie on multiples of it (and on the box's
/// faces), so that a brick's points lie between the nodes on its own corners, mid-points and
/// far faces.
pub const COARSE_STRIDE: i32 = 4;

/// The parameters at the nodes of a coarse grid over the lattice's box (within the points it
/// serves): `None` at nodes where the search found none (outside the control points' hull,
/// or not converged), around which points are mapped one by one.
#[derive(Debug)]
struct CoarseMap {
    /// Per axis, each node's lattice coordinate: the first point served in the box, every
    /// multiple of [`COARSE_STRIDE`] past it, and the last.
    at: [Vec<i32>; 3],
    /// Per axis, per lattice coordinate from the first node's to the last's: the cell holding
    /// it (between nodes `c` and `c + 1`) and where in it (0 to 1).
    cells: [Vec<(usize, f64)>; 3],
    /// The nodes' parameters, axis 0 fastest.
    nodes: Vec<Option<[f64; 3]>>,
}

impl CoarseMap {
    /// The nodes of a grid over the lattice points `lo ..= hi` (the box's, of those served),
    /// without parameters; `None` where it is too thin for one.
    fn laid_over(lo: IVec3, hi: IVec3) -> Option<Self> {
        if (hi - lo).min_element() < 2 * COARSE_STRIDE {
            return None;
        }
        let at: [Vec<i32>; 3] = std::array::from_fn(|a| {
            let mut at = vec![lo[a]];
            let mut next = (lo[a].div_euclid(COARSE_STRIDE) + 1) * COARSE_STRIDE;
            while next < hi[a] {
                at.push(next);
                next += COARSE_STRIDE;
            }
            at.push(hi[a]);
            at
        });
        let cells = std::array::from_fn(|a| {
            let nodes = &at[a];
            let mut cells = Vec::with_capacity((hi[a] - lo[a] + 1) as usize);
            for c in 0..nodes.len() - 1 {
                let (x0, x1) = (nodes[c], nodes[c + 1]);
                let last = c == nodes.len() - 2;
                for x in x0..if last { x1 + 1 } else { x1 } {
                    cells.push((c, (x - x0) as f64 / (x1 - x0) as f64));
                }
            }
            cells
        });
        let n = at.iter().map(Vec::len).product();
        Some(Self { at, cells, nodes: vec![None; n] })
    }

    /// Nodes per axis.
    #[inline]
    fn counts(&self) -> [usize; 3] {
        [self.at[0].len(), self.at[1].len(), self.at[2].len()]
    }

    /// The lattice point of node `n`.
    #[inline]
    fn point(&self, n: [usize; 3]) -> IVec3 {
        IVec3::new(self.at[0][n[0]], self.at[1][n[1]], self.at[2][n[2]])
    }

    #[inline]
    fn node(&self, n: [usize; 3]) -> Option<[f64; 3]> {
        let [cx, cy, _] = self.counts();
        self.nodes[n[0] + cx * (n[1] + cy * n[2])]
    }

    /// The cell holding coordinate `x` along `axis`, and where in it, when the grid covers it.
    #[inline]
    fn cell(&self, axis: usize, x: i32) -> Option<(usize, f64)> {
        usize::try_from(x - self.at[axis][0]).ok().and_then(|o| self.cells[axis].get(o).copied())
    }

    /// The parameters at lattice point `p`, interpolated from its cell's corners; `None`
    /// outside the grid or where a corner has none.
    #[inline]
    fn parameters(&self, p: IVec3) -> Option<[f64; 3]> {
        let (cx, tx) = self.cell(0, p.x)?;
        let (cy, ty) = self.cell(1, p.y)?;
        let (cz, tz) = self.cell(2, p.z)?;
        let mut out = [0.0; 3];
        for corner in 0..8 {
            let (i, j, k) = (corner & 1, (corner >> 1) & 1, corner >> 2);
            let u = self.node([cx + i, cy + j, cz + k])?;
            let w = (if i == 1 { tx } else { 1.0 - tx })
                * (if j == 1 { ty } else { 1.0 - ty })
                * (if k == 1 { tz } else { 1.0 - tz });
            for a in 0..3 {
                out[a] += w * u[a];
            }
        }
        Some(out)
    }

    /// The parameters at the points of the [`BLOCK`]³ block at `lo` (`x` fastest),
    /// interpolated axis by axis: `None` unless the block lies in one cell whose corners all
    /// have parameters.
    fn block(&self, lo: IVec3) -> Option<[[f64; 3]; BLOCK_POINTS]> {
        const N: usize = BLOCK as usize;
        let mut cell = [0usize; 3];
        let mut t = [[0.0f64; N]; 3];
        for a in 0..3 {
            for (o, t) in t[a].iter_mut().enumerate() {
                let (c, at) = self.cell(a, lo[a] + o as i32)?;
                if o == 0 {
                    cell[a] = c;
                } else if c != cell[a] {
                    return None;
                }
                *t = at;
            }
        }
        let corner = |i: usize, j: usize, k: usize| self.node([cell[0] + i, cell[1] + j, cell[2] + k]);
        let lerp = |a: [f64; 3], b: [f64; 3], t: f64| -> [f64; 3] {
            std::array::from_fn(|c| a[c] + (b[c] - a[c]) * t)
        };
        // Along x on the cell's four edges, then along y on its two faces, then along z.
        let mut edges = [[[0.0; 3]; N]; 4];
        for (e, edge) in edges.iter_mut().enumerate() {
            let (a, b) = (corner(0, e & 1, e >> 1)?, corner(1, e & 1, e >> 1)?);
            for (x, v) in edge.iter_mut().enumerate() {
                *v = lerp(a, b, t[0][x]);
            }
        }
        let mut faces = [[[[0.0; 3]; N]; N]; 2];
        for (k, face) in faces.iter_mut().enumerate() {
            for (y, row) in face.iter_mut().enumerate() {
                for (x, v) in row.iter_mut().enumerate() {
                    *v = lerp(edges[2 * k][x], edges[2 * k + 1][x], t[1][y]);
                }
            }
        }
        let mut out = [[0.0; 3]; BLOCK_POINTS];
        for (i, v) in out.iter_mut().enumerate() {
            let o = block_point(i);
            let (x, y, z) = (o.x as usize, o.y as usize, o.z as usize);
            *v = lerp(faces[0][y][x], faces[1][y][x], t[2][z]);
        }
        Some(out)
    }

    /// The nodes `first ..= last` whose cells hold the lattice points `lo ..= hi`, when the grid
    /// covers them.
    fn nodes_over(&self, lo: IVec3, hi: IVec3) -> Option<([usize; 3], [usize; 3])> {
        let mut first = [0; 3];
        let mut last = [0; 3];
        for a in 0..3 {
            first[a] = self.cell(a, lo[a])?.0;
            let (c, t) = self.cell(a, hi[a])?;
            last[a] = if t == 0.0 { c } else { c + 1 };
        }
        Some((first, last))
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
    /// What the writes left in each brick of the field.
    plan: BrickPlan,
    /// Every reach the writes have had (see [`Self::reach`]): only there is the field written,
    /// and there it is the lattice's, however the reach shrinks again.
    written: Aabb,
    /// The rest mapping onto the field's lattice: parameters `u` lie at index coordinates
    /// `to_index.0 + to_index.1 · u`.
    to_index: ([f64; 3], [f64; 3]),
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

/// What bounds the reads of a box of points when its fill is decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum By {
    /// The moved controls' displacements (no node needed): each point's read lies within the
    /// displacements' box of the point.
    Displacements,
    /// The coarse grid's nodes around the box: every point's parameters lie between theirs,
    /// so its read (the rest mapping being affine) lies in the box of the nodes' reads.
    Nodes,
}

/// What evaluating a box of lattice points needs, found once for it.
struct Context<'a> {
    lattice: &'a Lattice,
    state: State,
    /// The lattice points in the lattice's box.
    box_lo: IVec3,
    box_hi: IVec3,
    /// The lattice points around the control points' hull: beyond them nothing has a
    /// preimage in the cube.
    hull_lo: IVec3,
    hull_hi: IVec3,
    /// The longest shift, in lattice points (rounded up).
    shift_points: i32,
    /// Where the weights are equal: how far below and above a point its read may lie (the
    /// displacements' box, the shift, the trilinear read's corner and a point of slack), and
    /// whether every point of the box has a preimage in the cube.
    bound: Option<(IVec3, IVec3, bool)>,
    /// The nodes of the inverse mapping's coarse grid, when it has one.
    coarse: Option<CoarseMap>,
    /// What finding the nodes cost.
    stats: LatticeStats,
}

impl Context<'_> {
    /// What the lattice points `lo ..= hi` become, where they all become one thing; else
    /// [`Fill::Mixed`]. Outside the box and the hull nothing reaches them; inside the box, the
    /// reads lie within the bound `by` gives (see [`By`]), grown by the longest shift when
    /// values or weights changed: where the clay was empty there, or full of one colour, so
    /// are the points.
    fn fill(&self, lo: IVec3, hi: IVec3, by: By) -> Fill {
        self.as_it_was(lo, hi, self.fill_of(lo, hi, by))
    }

    /// `fill` of the points `lo ..= hi`, named [`Fill::Original`] where it is the clay as it
    /// was: empty where it was empty, or full of the colour it was full of (no brick made where
    /// there was none, none written again).
    fn as_it_was(&self, lo: IVec3, hi: IVec3, fill: Fill) -> Fill {
        match fill {
            Fill::Empty if self.lattice.source.holds(lo, hi) == Holds::Empty => Fill::Original,
            Fill::Full(colour) if self.lattice.source.holds(lo, hi) == Holds::Full(colour) => Fill::Original,
            fill => fill,
        }
    }

    /// [`Self::fill`], before a fill that is the clay as it was is named so.
    fn fill_of(&self, lo: IVec3, hi: IVec3, by: By) -> Fill {
        let outside = |a: IVec3, b: IVec3| lo.cmpgt(b).any() || hi.cmplt(a).any();
        let untouched = self.state.at_rest && !self.state.shifting;
        if untouched || (outside(self.box_lo, self.box_hi) && outside(self.hull_lo, self.hull_hi)) {
            return Fill::Original;
        }
        if lo.cmplt(self.box_lo).any() || hi.cmpgt(self.box_hi).any() {
            return Fill::Mixed;
        }
        if by == By::Displacements {
            return self.bounded_fill(lo, hi);
        }
        let Some(grid) = &self.coarse else { return Fill::Mixed };
        let Some((first, last)) = grid.nodes_over(lo, hi) else { return Fill::Mixed };
        // Every point's parameters are a convex combination of those of its cell's corners.
        let (mut a, mut b) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let mut moved = false;
        for k in first[2]..=last[2] {
            for j in first[1]..=last[1] {
                for i in first[0]..=last[0] {
                    let Some(u) = grid.node([i, j, k]) else { return Fill::Mixed };
                    if !Uvw(u).is_in_unit_cube() {
                        return Fill::Mixed;
                    }
                    let own = grid.point([i, j, k]);
                    let read = self.lattice.rest_index(u);
                    for x in 0..3 {
                        moved |= (read[x] - own[x] as f64).abs() > 1e-4;
                        a[x] = a[x].min(read[x]);
                        b[x] = b[x].max(read[x]);
                    }
                }
            }
        }
        self.fill_within(a, b, moved)
    }

    /// What points become whose parameters are each a convex combination of some lattice
    /// points' (the corners of a cell of the coarse grid, or of a box in one cell), every one
    /// of which lies in the cube, given the box `a ..= b` of those points' reads and whether
    /// any of them `moved`. The points' reads (the rest mapping being affine) lie in that box,
    /// grown by the longest shift when values or weights changed; and every point lies in the
    /// cube too, so has its preimage.
    #[inline]
    fn fill_within(&self, a: [f64; 3], b: [f64; 3], moved: bool) -> Fill {
        if !moved && !self.state.shifting {
            return Fill::Original;
        }
        let grow = if self.state.shifting { self.shift_points } else { 0 };
        let a = IVec3::new(floor_i32(a[0]), floor_i32(a[1]), floor_i32(a[2])) - IVec3::splat(grow);
        let b = IVec3::new(floor_i32(b[0]), floor_i32(b[1]), floor_i32(b[2])) + IVec3::splat(1 + grow);
        self.fill_reading(a, b, true)
    }

    /// What points become whose reads all lie in the clay as it was at `lo ..= hi`: empty
    /// where it was empty, full of its colour where it was full of one (and every point has a
    /// preimage in the cube, as `preimages` says), else mixed.
    fn fill_reading(&self, lo: IVec3, hi: IVec3, preimages: bool) -> Fill {
        match self.lattice.source.holds(lo, hi) {
            Holds::Empty => Fill::Empty,
            Holds::Full(colour) if preimages => Fill::Full(colour),
            _ => Fill::Mixed,
        }
    }

    /// [`Self::fill`] for points of the box, from the displacements' bound alone: empty where
    /// every read the bound allows lies in empty clay, full where it lies in full clay of one
    /// colour and every point has a preimage.
    fn bounded_fill(&self, lo: IVec3, hi: IVec3) -> Fill {
        let Some((below, above, preimages)) = self.bound else { return Fill::Mixed };
        self.fill_reading(lo - below, hi + above, preimages)
    }

    /// Brick `key`'s densities and colours into `out` ([`Brick::linear`] order), decided
    /// again block by block and the mixed blocks' points evaluated one by one.
    fn brick(&self, key: IVec3, out: &mut [(f32, Colour)]) -> LatticeStats {
        let base = key * IVec3::splat(BRICK_SIZE);
        let mut stats = LatticeStats::default();
        let blocks = BRICK_SIZE / BLOCK;
        for block in 0..blocks * blocks * blocks {
            let offset =
                IVec3::new(block % blocks, (block / blocks) % blocks, block / (blocks * blocks)) * BLOCK;
            let lo = base + offset;
            let fill = self.fill(lo, lo + IVec3::splat(BLOCK - 1), By::Nodes);
            if fill == Fill::Mixed && self.sub_blocks(lo, base, out, &mut stats) {
                continue;
            }
            let mut previous = [None; 2];
            for i in 0..BLOCK_POINTS {
                let local = offset + block_point(i);
                let p = base + local;
                if local.x == offset.x {
                    previous = [None; 2];
                }
                let source = &self.lattice.source;
                out[Brick::linear(local)] = fill
                    .value(|| (source.density(p), source.colour(p)))
                    .unwrap_or_else(|| self.point(p, &mut previous, true, &mut stats));
            }
        }
        stats
    }

    /// A mixed block `lo ..= lo + 3` of the brick at `base` into `out`, as 2³ sub-blocks, where
    /// the block lies in one cell of the coarse grid (the points' parameters interpolated
    /// between its corners): each sub-block decided from its own corners' parameters, only
    /// the undecided ones' points evaluated. `false`, and nothing written, where the block
    /// does not lie in one cell.
    fn sub_blocks(
        &self,
        lo: IVec3,
        base: IVec3,
        out: &mut [(f32, Colour)],
        stats: &mut LatticeStats,
    ) -> bool {
        // Every point's parameters, interpolated once, and where each reads at rest.
        let Some(parameters) = self.coarse.as_ref().and_then(|grid| grid.block(lo)) else { return false };
        let (mut reads, mut moved, mut in_cube) =
            ([[0.0; 3]; BLOCK_POINTS], [false; BLOCK_POINTS], [false; BLOCK_POINTS]);
        for (i, u) in parameters.iter().enumerate() {
            let own = lo + block_point(i);
            reads[i] = self.lattice.rest_index(*u);
            moved[i] = (0..3).any(|a| (reads[i][a] - own[a] as f64).abs() > 1e-4);
            in_cube[i] = Uvw(*u).is_in_unit_cube();
        }
        let source = &self.lattice.source;
        for sub in 0..8 {
            let s = IVec3::new(sub & 1, (sub >> 1) & 1, sub >> 2) * SUB_BLOCK;
            let points: [usize; 8] = std::array::from_fn(|c| {
                let o = s + IVec3::new(c as i32 & 1, (c as i32 >> 1) & 1, c as i32 >> 2);
                (o.x + BLOCK * (o.y + BLOCK * o.z)) as usize
            });
            let fill = if points.iter().all(|&i| in_cube[i]) {
                let (mut a, mut b) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
                for &i in &points {
                    for x in 0..3 {
                        a[x] = a[x].min(reads[i][x]);
                        b[x] = b[x].max(reads[i][x]);
                    }
                }
                self.fill_within(a, b, points.iter().any(|&i| moved[i]))
            } else {
                Fill::Mixed
            };
            let fill = self.as_it_was(lo + s, lo + s + IVec3::splat(SUB_BLOCK - 1), fill);
            for i in points {
                let p = lo + block_point(i);
                out[Brick::linear(p - base)] =
                    fill.value(|| (source.density(p), source.colour(p))).unwrap_or_else(|| {
                        let read = match in_cube[i] {
                            true => {
                                let own = [p.x as f64, p.y as f64, p.z as f64];
                                let uvw = Uvw(parameters[i]);
                                self.lattice.read_from_rest(own, uvw, reads[i], true, self.state.shifting)
                            }
                            false => Read::Empty,
                        };
                        self.counted_read(p, read, true, stats)
                    });
            }
        }
        true
    }

    /// The deformed clay at lattice point `p` whose parameters `uvw` were interpolated on the
    /// coarse grid (which lies in the box).
    #[inline]
    fn point_at(&self, p: IVec3, uvw: Uvw, colour: bool, stats: &mut LatticeStats) -> (f32, Colour) {
        let read = match uvw.is_in_unit_cube() {
            true => self.lattice.read_at_parameters(
                [p.x as f64, p.y as f64, p.z as f64],
                uvw,
                true,
                self.state.shifting,
            ),
            false => Read::Empty,
        };
        self.counted_read(p, read, colour, stats)
    }

    /// Point `p` read as `read` says, its parameters interpolated: counted in `stats`.
    #[inline]
    fn counted_read(&self, p: IVec3, read: Read, colour: bool, stats: &mut LatticeStats) -> (f32, Colour) {
        stats.points += 1;
        stats.interpolated += 1;
        stats.moved += usize::from(read != Read::Own);
        self.lattice.read(p, read, colour)
    }

    /// The deformed clay at lattice point `p` (its colour only when asked): the parameters
    /// interpolated on the coarse grid where it covers `p`, else found by Newton's method from
    /// the row's `previous` two points' extrapolated.
    #[inline]
    fn point(
        &self,
        p: IVec3,
        previous: &mut [Option<Uvw>; 2],
        colour: bool,
        stats: &mut LatticeStats,
    ) -> (f32, Colour) {
        if let Some(uvw) = self.coarse.as_ref().and_then(|c| c.parameters(p)) {
            return self.point_at(p, Uvw(uvw), colour, stats);
        }
        let lattice = self.lattice;
        stats.points += 1;
        let m = lattice.map_index([p.x as f64, p.y as f64, p.z as f64], extrapolated(*previous), &self.state);
        *previous = [previous[1], m.uvw];
        stats.searched += usize::from(m.iterations > 0);
        stats.newton_iterations += m.iterations as u64;
        let read = m.read;
        stats.moved += usize::from(read != Read::Own);
        lattice.read(p, read, colour)
    }
}

/// A start for the inverse mapping of the next point of a row (evenly spaced) from the
/// parameters of the two before it: extrapolated linearly.
#[inline]
fn extrapolated(previous: [Option<Uvw>; 2]) -> Option<Uvw> {
    match previous {
        [Some(a), Some(b)] => Some(Uvw(std::array::from_fn(|i| 2.0 * b.0[i] - a.0[i]))),
        [_, b] => b,
    }
}

/// Lattice points along a side of the blocks a mixed brick is decided in, block by block,
/// before its points are evaluated one by one.
const BLOCK: i32 = 4;

/// Lattice points in a block.
const BLOCK_POINTS: usize = (BLOCK * BLOCK * BLOCK) as usize;

/// The offset of a block's `i`-th point from its first (`x` fastest).
#[inline]
fn block_point(i: usize) -> IVec3 {
    const N: usize = BLOCK as usize;
    IVec3::new((i % N) as i32, (i / N % N) as i32, (i / (N * N)) as i32)
}

/// Lattice points along a side of the sub-blocks a mixed block is decided in.
const SUB_BLOCK: i32 = 2;

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
            plan: BrickPlan::new(),
            written: Aabb::EMPTY,
            to_index: {
                let (min, size) = (spec.region.min, spec.region.size());
                let (h, o) = (transform.voxel_size_m as f64, transform.origin_m);
                (
                    std::array::from_fn(|a| (min[a] as f64 - o[a] as f64) / h),
                    std::array::from_fn(|a| size[a] as f64 / h),
                )
            },
        };
        let (lo, hi) = lattice.source_box(volume.hull())?;
        let start = std::time::Instant::now();
        lattice.source = DenseCopy::read(field, lo, hi).counted();
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
            let tolerance = MAPPING_TOLERANCE_VOXELS * t.voxel_size_m as f64
                / self.spec.region.size().max_element() as f64;
            let (mut m, _) = self.volume.inverse_map_within(x, start, Vec3::ZERO, false, tolerance);
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
        self.read_from_rest(own, uvw, self.rest_index(uvw.0), in_box, shifting)
    }

    /// [`Self::read_at_parameters`], where the rest lattice places `uvw` at `rest` (index
    /// coordinates, [`Self::rest_index`]) already.
    #[inline]
    fn read_from_rest(&self, own: [f64; 3], uvw: Uvw, rest: [f64; 3], in_box: bool, shifting: bool) -> Read {
        let mut read_at = rest;
        // The function mapping's shift, faded out on the faces so that it meets the clay
        // outside without a step.
        if shifting {
            let kappa = smoothstep(self.window_scale * unit_cube_function(uvw));
            if kappa > 0.0 {
                let shift = self.shift(uvw);
                let h = self.transform.voxel_size_m as f64;
                for a in 0..3 {
                    read_at[a] += kappa * shift[a] / h;
                }
            }
        }
        let moved = (0..3).any(|a| (read_at[a] - own[a]).abs() > 1e-4);
        match (moved, in_box) {
            (false, true) => Read::Own,
            (true, true) => Read::At(read_at),
            (_, false) => Read::AtOrOwn(read_at),
        }
    }

    /// The index coordinates where the rest lattice places parameters `u`.
    #[inline]
    fn rest_index(&self, u: [f64; 3]) -> [f64; 3] {
        let (offset, scale) = &self.to_index;
        std::array::from_fn(|a| offset[a] + scale[a] * u[a])
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
    /// `lo ..= hi`, `x` fastest, point by point (the inverse mapping interpolated between the
    /// nodes of a coarse grid); rows in parallel.
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
        let mut context = self.context(lo, hi, coarse);
        let all = vec![true; context.coarse.as_ref().map_or(0, |c| c.nodes.len())];
        self.find_nodes(&mut context, &all);
        let eval_row = |row: usize, out: &mut [f32], mut colour: Option<&mut [Colour]>| {
            let start = row_of(row);
            let mut stats = LatticeStats::default();
            let mut previous = [None; 2];
            for (x, d) in out.iter_mut().enumerate() {
                let p = start + IVec3::new(x as i32, 0, 0);
                let (density, c) = context.point(p, &mut previous, colour.is_some(), &mut stats);
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
        stats + context.stats
    }

    /// What evaluating the lattice points `lo ..= hi` needs: the lattice's state, its box and
    /// hull on the field's lattice, and (with `coarse`, where the lattice is deformed and the
    /// box thick enough) the coarse grid's nodes over the box within them, found in parallel.
    fn context(&self, lo: IVec3, hi: IVec3, coarse: bool) -> Context<'_> {
        let state = self.state();
        let t = &self.transform;
        let region = self.spec.region;
        // A face on the lattice (within rounding) holds its points.
        let box_lo = (t.world_to_index(region.min) - Vec3::splat(1e-3)).ceil().as_ivec3();
        let box_hi = (t.world_to_index(region.max) + Vec3::splat(1e-3)).floor().as_ivec3();
        let hull = self.volume.hull();
        let hull_lo = t.world_to_index(hull.min).floor().as_ivec3();
        let hull_hi = t.world_to_index(hull.max).ceil().as_ivec3();
        let mut context = Context {
            lattice: self,
            state,
            box_lo,
            box_hi,
            hull_lo,
            hull_hi,
            shift_points: (self.max_shift_m / t.voxel_size_m as f64).ceil() as i32,
            bound: None,
            coarse: None,
            stats: LatticeStats::default(),
        };
        if let Some(d) = self.volume.displacement_box() {
            let grow = 1 + if state.shifting { context.shift_points } else { 0 };
            let h = t.voxel_size_m;
            let below = (d.max / h).ceil().as_ivec3() + IVec3::splat(grow);
            let above = (-d.min / h).ceil().as_ivec3() + IVec3::splat(grow + 1);
            context.bound = Some((below, above, self.volume.faces_at_rest()));
        }
        if coarse && !state.at_rest {
            context.coarse = CoarseMap::laid_over(lo.max(box_lo), hi.min(box_hi));
        }
        context
    }

    /// Finds the coarse grid's nodes where `needed` says, by Newton's method, rows in parallel;
    /// each search starts from the row's two nodes before it, extrapolated.
    fn find_nodes(&self, context: &mut Context<'_>, needed: &[bool]) {
        let Some(grid) = context.coarse.as_mut() else { return };
        let state = context.state;
        let [cx, cy, _] = grid.counts();
        let at = &grid.at;
        context.stats = grid
            .nodes
            .par_chunks_mut(cx)
            .zip(needed.par_chunks(cx))
            .enumerate()
            .map(|(row, (out, needed))| {
                let (y, z) = (at[1][row % cy], at[2][row / cy]);
                let mut stats = LatticeStats::default();
                let mut previous = [None; 2];
                for (x, (node, &needed)) in out.iter_mut().zip(needed).enumerate() {
                    if !needed {
                        previous = [None; 2];
                        continue;
                    }
                    let own = [at[0][x] as f64, y as f64, z as f64];
                    let m = self.map_index(own, extrapolated(previous), &state);
                    previous = [previous[1], m.uvw];
                    stats.searched += usize::from(m.iterations > 0);
                    stats.newton_iterations += m.iterations as u64;
                    // Its parameters wherever the search converged, in the cube or not.
                    *node = m.uvw.map(|u| u.0);
                }
                stats
            })
            .reduce(LatticeStats::default, |a, b| a + b);
    }

    /// The density and colour of sample `p` read as `read` says (the colour only when asked).
    #[inline]
    fn read(&self, p: IVec3, read: Read, colour: bool) -> (f32, Colour) {
        let own = || (self.source.density(p), self.source.colour(p));
        let at = |q: [f64; 3]| {
            let d = self.source.density_f64(q).clamp(0.0, 1.0);
            // No clay has no colour (none around to take one from).
            (d, if colour && d > 0.0 { self.source.colour_near(q) } else { DEFAULT_COLOUR })
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

    /// Evaluates the deformed clay over `world` and writes it into `field`, growing the copy
    /// of the clay first where the control points now reach beyond it. The caller holds
    /// `field`'s stroke open (the lattice's whole session is one undo step), and nothing else
    /// writes the field while the lattice is open.
    ///
    /// Written brick by brick ([`BrickPlan`]): a brick (or a 4³ block of one) whose points all
    /// read clay as it was, or read only where the clay was empty, or full of one colour, is
    /// filled whole (its reads lie between those of the coarse grid's nodes around it, grown
    /// by the longest shift); only the rest are evaluated point by point, and a brick left as
    /// the last write left it is not written again.
    pub fn write(&mut self, field: &mut Field, world: Aabb) -> Result<LatticeStats, LatticeError> {
        let (slo, shi) = self.source_box(self.volume.hull())?;
        if !self.source.contains(slo, shi) {
            let lo = slo.min(self.source.lo());
            let hi = shi.max(self.source.hi());
            self.source = self.source.grown(field, lo, hi).counted();
        }
        // The clay of a reach left behind goes back as it was (its points read their own).
        self.written = self.written.union(&self.reach());
        let reach = self.written;
        let world = Aabb { min: world.min.max(reach.min), max: world.max.min(reach.max) };
        if world.is_empty() {
            return Ok(LatticeStats::default());
        }
        let (lo, hi) = self.points_of(world);
        let within = self.points_of(reach);
        // Whole bricks: the grid over every brick the box touches.
        let size = IVec3::splat(BRICK_SIZE);
        let (blo, bhi) = (lo.div_euclid(size) * size, hi.div_euclid(size) * size + size - IVec3::ONE);
        let mut plan = std::mem::take(&mut self.plan);
        // Its far nodes on the next bricks' first points, where every brick's are.
        let mut context = self.context(blo, bhi + IVec3::ONE, true);
        // Each brick decided by the displacements' bound, then the nodes of those it leaves
        // undecided found, alone, and those decided by them.
        let keys: Vec<IVec3> = bricks_over(lo, hi).collect();
        let bounds = |key: IVec3| (key * size, key * size + size - IVec3::ONE);
        let mut fills: Vec<Fill> = keys
            .par_iter()
            .map(|&key| {
                let (a, b) = bounds(key);
                context.fill(a, b, By::Displacements)
            })
            .collect();
        if let Some(grid) = &context.coarse {
            let mut needed = vec![false; grid.nodes.len()];
            let [cx, cy, _] = grid.counts();
            let undecided: Vec<([usize; 3], [usize; 3])> = keys
                .iter()
                .zip(&fills)
                .filter(|&(_, &fill)| fill == Fill::Mixed)
                .filter_map(|(&key, _)| {
                    // The brick's points the grid covers (a brick across a face has some).
                    let (a, b) = bounds(key);
                    let (first, last) = (grid.point([0; 3]), grid.point(grid.counts().map(|n| n - 1)));
                    let (a, b) = (a.max(first), b.min(last));
                    a.cmple(b).all().then(|| grid.nodes_over(a, b)).flatten()
                })
                .collect();
            for (first, last) in undecided {
                for k in first[2]..=last[2] {
                    for j in first[1]..=last[1] {
                        for i in first[0]..=last[0] {
                            needed[i + cx * (j + cy * k)] = true;
                        }
                    }
                }
            }
            self.find_nodes(&mut context, &needed);
            keys.par_iter().zip(&mut fills).filter(|(_, fill)| **fill == Fill::Mixed).for_each(
                |(&key, fill)| {
                    let (a, b) = bounds(key);
                    *fill = context.fill(a, b, By::Nodes);
                },
            );
        }
        let decided: rustc_hash::FxHashMap<IVec3, Fill> = keys.iter().copied().zip(fills).collect();
        let counted = std::sync::Mutex::new(LatticeStats::default());
        let written = plan.write(
            field,
            Some(within),
            keys,
            |key| decided[&key],
            || (),
            |key, _, out| {
                let stats = context.brick(key, out);
                let mut all = counted.lock().unwrap_or_else(|e| e.into_inner());
                *all = *all + stats;
                stats.points
            },
            |_, p| (self.source.density(p), self.source.colour(p)),
        );
        let stats = counted.into_inner().unwrap_or_else(|e| e.into_inner()) + context.stats;
        drop(context);
        self.plan = plan;
        Ok(LatticeStats { written: written.written, bricks: written.bricks, ..stats })
    }

    /// Puts the clay back as it was over everything the lattice reaches, and the lattice at
    /// rest with its fitted values.
    pub fn reset(&mut self, field: &mut Field) -> Result<LatticeStats, LatticeError> {
        let before = self.reach();
        self.volume = self.fitted.clone();
        self.write(field, before.union(&self.reach()))
    }
}
