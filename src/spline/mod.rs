//! Trivariate spline volumes for global deformation: extended space mapping with a 4D spline
//! volume whose control points carry a function value (the spline-volume sculpting paper,
//! "ESM" below, `papers/extended-space-mapping-spline-volume-sculpting.txt`) and the
//! least-squares fit of trivariate B-spline functions to a density field (Hua and Qin,
//! "Haptic sculpting of volumetric implicit functions", "HQ" below).
//!
//! Owns knot vectors and their Cox–de Boor basis, the lattice of control points (Bézier,
//! B-spline or NURBS), its forward and inverse space mapping, function mapping with
//! functional clipping, the fit of the control values to a field, and fast evaluation over
//! regular grids. Depends on `math` only: the field reaches it as a closure, the app as plain
//! values; it knows nothing of fields, meshes, tools, devices or Vulkan.
//!
//! ## The method
//!
//! A lattice of `l × m × n` control points spans a box of the world. Each control point
//! `P_ijk` has a position (3 coordinates), a function value `f_ijk` (ESM's 4th, "function"
//! coordinate: here a density) and, for NURBS, a weight `w_ijk` (ESM §4.1's homogeneous
//! coordinate). With per-axis bases `N_i(u)`, `N_j(v)`, `N_k(w)` (order `k_u`, `k_v`, `k_w`,
//! see [`KnotVector`]) the volume is the 4D map of the unit parameter cube
//!
//! ```text
//!   (P, F)(u, v, w) = Σ N_i(u) N_j(v) N_k(w) w_ijk (P_ijk, f_ijk) / Σ N_i(u) N_j(v) N_k(w) w_ijk
//! ```
//!
//! (ESM §3 with the rational weights of §4.4; HQ eq. 2 is the non-rational value part). The
//! parameters are always normalised: `(u, v, w) ∈ [0, 1]³` is the spline's domain on every
//! axis, whatever the knots.
//!
//! - *Space mapping* (ESM §2–3): moving control points warps space. The density at a world
//!   point `x` of the deformed lattice is `F(P⁻¹(x))`; [`SplineVolume::inverse_map`] finds
//!   `P⁻¹(x)` by damped Newton iteration from the undeformed lattice's affine inverse.
//! - *Function mapping* (ESM §2, §3): changing the `f_ijk` changes the solid without moving
//!   space.
//! - *Functional clipping* (ESM §3.1): outside the unit cube a spline's pieces extend as
//!   polynomials and can rise above the iso-level, giving "ghost" solids. [`Clipping`]
//!   intersects the mapped function with the unit cube's defining function by the R-function
//!   `a & b = a + b − √(a² + b²)`.
//! - *Fit* (HQ §4.2.2, eq. 9–13): the control values least-squares fitted to samples of a field
//!   on a full tensor grid of parameters separate into one small solve per axis
//!   ([`SplineVolume::fit_field`]).
//!
//! ```text
//!   rest lattice (over the box)            dragged lattice
//!    o───o───o───o                          o───o───o───o
//!    │   │   │   │      move control         │   │    \   \
//!    o───o───o───o   ───points (space──►     o───o─────o───o      density at x:
//!    │   │   │   │      mapping)             │   │    /   /        F(P⁻¹(x)) clipped
//!    o───o───o───o                          o───o───o───o        to the unit cube
//!   P(u) = box.min + u · box.size           P(u) from the moved points
//! ```
//!
//! ## Conventions and invariants
//!
//! - World space in metres. Control point `(i, j, k)` has linear index `i + l·(j + m·k)`
//!   (`u` fastest), like a brick's samples; grids of samples are `x` fastest.
//! - Density in [0, 1], 1 full clay, surface at the iso-level (0.5 by default). The spline's
//!   function values `f_ijk` are densities; ESM's defining functions are signed (positive
//!   inside, zero on the surface), so clipping works on `f − iso` and maps back by adding
//!   `iso` and clamping to [0, 1] (see [`Clipping`]).
//! - The rest lattice maps the unit cube exactly onto the box ([`SplineVolume::over_box`]
//!   places the rest control points at the Greville abscissae, for every kind and order), so
//!   an untouched lattice maps every point to itself.
//! - Weights are positive: the rational denominator never vanishes in the cube, and the image
//!   of the unit cube lies in the control points' convex hull. Nothing that takes a world
//!   point returns NaN or an infinity, whatever the point or the lattice (coincident control
//!   points included): the searches keep their parameters in [−1, 2]³.
//! - Nothing panics on bad parameters: constructors and setters return [`SplineError`].
//! - Evaluation of one point (basis, position, Jacobian, value, inverse map) allocates
//!   nothing; the arithmetic is in `f64` (positions are stored as `Vec3`, values and weights
//!   as `f64`).
//!
//! ## Where this departs from the papers, and why
//!
//! - ESM §3 places the rest control points on a regular grid (printed as `i / l`). Equally
//!   spaced control points map the cube onto the box by the identity only for Bézier volumes;
//!   for B-splines of order > 2 they give a non-linear reparameterisation. We place them at
//!   the Greville abscissae of the knots, which makes the rest mapping exactly affine for
//!   every order and knot vector (linear precision of B-splines), so the inverse of the rest
//!   mapping is the box's affine inverse and the Newton iteration starts at the answer.
//! - Weights act on all four coordinates, as in a NURBS hypersurface of the 4D extended
//!   space: a heavier control point pulls space towards its position as well as the function
//!   towards its value. ESM §4.4's observations hold (no effect inside the solid, a local
//!   effect at its boundary that widens with the order; `grid::tests`), but in the world the
//!   boundary moves much less than in the parameters (a weight of 4 on the last positive
//!   control of an order-3 slab moves it by 0.046 of the box in `u`, by 1.6 mm of 300 mm in
//!   the world), which agrees with ESM's remark that every NURBS result could also be had
//!   with B-splines.
//! - ESM draws negative weights as "−" spheres (§4.1). We refuse them: a weight of either sign
//!   can make the denominator vanish inside the cube (a pole), which turns the mapping and the
//!   function into infinities. With positive weights both are convex combinations.
//! - The clipped function keeps the paper's R-function but scales the cube's function by
//!   [`Clipping::cube_scale`]. With the paper's scale (1) the surface and its normals are
//!   exactly those of the unclipped function inside the cube, but the interior density is
//!   compressed (full clay at the centre of the cube reads 0.6); a larger scale keeps the
//!   same surface and leaves the interior within `(f − iso)² / (2·scale·c)` of the unclipped
//!   density, so matter is kept (`clip::tests`).
//! - HQ fits with the inverse of the full Kronecker normal matrix (eq. 13). On a full grid of
//!   samples that inverse factors per axis, `(B ⊗ C ⊗ D)⁺ = B⁺ ⊗ C⁺ ⊗ D⁺`: three solves with
//!   matrices of at most 16 × 16 instead of one of 4096 × 4096. For NURBS the fit solves for
//!   the homogeneous values `w·f` against `d·W` (W the weights' spline), which keeps that
//!   separation and minimises the error weighted by `W²`.
//!
//! And what the papers leave open: ESM defers the inverse mapping to another paper ([8]); ours
//! is damped Newton with Levenberg–Marquardt steps where the Jacobian is singular, fallback
//! starts, and a refusal of points that cannot have a preimage (outside the control hull,
//! convex hull property), so coincident control points or far points cost little and give no
//! NaN (`inverse`). Grids of a deformed lattice start each point's search from its
//! neighbour's parameters moved through the inverse Jacobian, about one Newton iteration a
//! point (`grid`).

mod clip;
mod fit;
mod grid;
mod inverse;
mod knots;
mod slice;
mod tensor;
mod volume;

pub use clip::{r_intersection, unit_cube_function, unit_strip, Clipping};
pub use fit::{FitReport, FitSamples, DEFAULT_SAMPLES_PER_SPAN, MAX_SAMPLES_PER_SPAN};
pub use grid::{GridStats, ParamBox, SampleGrid, MAX_GRID_SAMPLES};
pub use inverse::InverseMap;
pub use knots::{
    Basis, BasisDerivatives, KnotStyle, KnotVector, MAX_CONTROLS, MAX_ORDER, MIN_CONTROLS, MIN_ORDER,
};
pub use slice::SLICE_SAMPLES;
pub use volume::{ControlPoint, SplineKind, SplineVolume, Uvw};

/// Why a spline volume, a knot vector, a fit or an evaluation request is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SplineError {
    /// An axis has too few or too many control points.
    #[error(
        "a lattice needs {MIN_CONTROLS} to {MAX_CONTROLS} control points per axis, not {count} \
         (axis {axis})"
    )]
    ControlCount {
        /// The axis, `u`, `v` or `w`.
        axis: char,
        /// The count given.
        count: usize,
    },
    /// An order outside 2..=min(controls, 16).
    #[error(
        "a spline's order must be {MIN_ORDER} to {MAX_ORDER} and at most its number of control \
         points ({count}), not {order} (axis {axis})"
    )]
    Order {
        /// The axis.
        axis: char,
        /// The order given.
        order: usize,
        /// The control count on that axis.
        count: usize,
    },
    /// A knot vector whose length is not controls + order.
    #[error(
        "a knot vector for {count} control points of order {order} needs {expected} knots, \
         not {given} (axis {axis})"
    )]
    KnotCount {
        /// The axis.
        axis: char,
        /// Control count.
        count: usize,
        /// Order.
        order: usize,
        /// `count + order`.
        expected: usize,
        /// The length given.
        given: usize,
    },
    /// A knot that is not finite or smaller than its predecessor.
    #[error("knots must be finite and non-decreasing; knot {index} is {value} (axis {axis})")]
    KnotOrder {
        /// The axis.
        axis: char,
        /// Index of the offending knot.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A knot repeated so often that the spline breaks apart or a basis function vanishes.
    #[error(
        "knot {value} is repeated {multiplicity} times; at most {allowed} are allowed there \
         (interior knots: order − 1, end knots: the order) (axis {axis})"
    )]
    KnotMultiplicity {
        /// The axis.
        axis: char,
        /// The knot's value.
        value: f64,
        /// How often it appears.
        multiplicity: usize,
        /// How often it may appear there.
        allowed: usize,
    },
    /// The knots leave no parameter interval for the spline.
    #[error(
        "the knots leave an empty domain: knot {first} ({lo}) must be smaller than knot {last} \
         ({hi}) (axis {axis})"
    )]
    EmptyDomain {
        /// The axis.
        axis: char,
        /// Index of the domain's first knot (order − 1).
        first: usize,
        /// Index of the domain's last knot (count).
        last: usize,
        /// Its first knot's value.
        lo: f64,
        /// Its last knot's value.
        hi: f64,
    },
    /// A Bézier volume whose knots are not clamped of full order.
    #[error(
        "a Bézier volume has order equal to its control count and clamped knots on every axis; \
         axis {axis} has order {order} for {count} control points"
    )]
    NotBezier {
        /// The axis.
        axis: char,
        /// Its order.
        order: usize,
        /// Its control count.
        count: usize,
    },
    /// The lattice's region is not a finite box with positive size.
    #[error(
        "a lattice needs a finite box with a positive size on every axis, not min {min:?} max \
         {max:?}"
    )]
    Region {
        /// The box's minimum corner given.
        min: [f32; 3],
        /// The box's maximum corner given.
        max: [f32; 3],
    },
    /// A non-finite number where a finite one is needed.
    #[error("{what} must be finite, not {value}")]
    NotFinite {
        /// What the number is.
        what: &'static str,
        /// The value given (the first non-finite component).
        value: f64,
    },
    /// A weight that is not positive and finite.
    #[error("a NURBS weight must be positive and finite, not {value}")]
    Weight {
        /// The value given.
        value: f64,
    },
    /// A weight set on a non-rational volume.
    #[error(
        "weights belong to NURBS volumes; this is a {kind} volume (make it with \
         SplineVolume::nurbs)"
    )]
    NotRational {
        /// The volume's kind.
        kind: &'static str,
    },
    /// A control point index outside the lattice.
    #[error("control point ({i}, {j}, {k}) lies outside the {l} × {m} × {n} lattice")]
    Index {
        /// Index along u.
        i: usize,
        /// Index along v.
        j: usize,
        /// Index along w.
        k: usize,
        /// Count along u.
        l: usize,
        /// Count along v.
        m: usize,
        /// Count along w.
        n: usize,
    },
    /// A parameter outside its accepted range.
    #[error("{name} must be {what}, not {value}")]
    Parameter {
        /// Which parameter.
        name: &'static str,
        /// What it must be.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// A number of fit samples per knot span outside the accepted range.
    #[error("a fit takes 1 to {MAX_SAMPLES_PER_SPAN} samples per knot span, not {value}")]
    SamplesPerSpan {
        /// The value given.
        value: usize,
    },
    /// A buffer whose length does not match the grid it stands for.
    #[error("{what} holds {given} values; its grid has {expected}")]
    Length {
        /// What the buffer is.
        what: &'static str,
        /// The grid's number of points.
        expected: usize,
        /// The buffer's length.
        given: usize,
    },
    /// A sample grid that is empty, too large or badly placed.
    #[error("a sample grid needs 1 to {MAX_GRID_SAMPLES} points and a positive finite spacing: {reason}")]
    Grid {
        /// What is wrong with it.
        reason: String,
    },
    /// The fit's normal equations are singular (samples that miss a basis function).
    #[error(
        "the fit's samples along axis {axis} do not determine every control value (the normal \
         matrix is singular at row {row}); use more samples per span"
    )]
    Singular {
        /// The axis.
        axis: char,
        /// The row whose pivot vanished.
        row: usize,
    },
}

/// The names of the three parameter axes, for messages.
pub(crate) const AXES: [char; 3] = ['u', 'v', 'w'];
