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
//!   v      = ΔF · g / (|g|² + ε²)             the shift that moves F₀'s iso-surface by ΔF:
//!                                             the first-order step of ESM's function mapping
//!   κ      = s(λ · F_c(u))                    ESM's cube function (§3.1) as a window: 0 on
//!                                             the lattice's faces and outside, 1 inside
//!   y      = x + κ · (P_rest(u) + v − x)      where the clay is read
//!   clay'(x) = clay₀(y)                       trilinear, colour from the nearest sample
//! ```
//!
//! so that:
//!
//! - an untouched lattice leaves the clay bit for bit as it was (`y = x`, read at the lattice
//!   point itself), whatever the fit's error;
//! - moving control points warps the clay (ESM's space mapping), its detail carried along;
//! - raising a control's value swells the clay near it, lowering it shrinks it, by as much as
//!   the fitted function's iso-surface would move (ESM's function mapping, to first order),
//!   with the clay's own detail and sharpness kept; raising a value never removes matter
//!   (`v` points up `F₀`'s gradient as `ΔF` grows);
//! - nothing changes outside the lattice, and the clay inside joins the clay outside without
//!   a seam: the window `κ` goes to 0 continuously on the faces (ESM §3.1's role for the
//!   R-function clipping: no ghost solid appears outside the lattice, since no polynomial is
//!   ever evaluated outside the unit cube).
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
//! where, and callers re-evaluate only there. Rows of the box are evaluated in parallel; each
//! point's Newton search starts from its neighbour's parameters, extrapolated.

#[cfg(test)]
mod tests;

use rayon::prelude::*;

use crate::field::{Colour, Field, FieldReader, DEFAULT_COLOUR};
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
}

impl std::ops::Add for LatticeStats {
    type Output = LatticeStats;

    fn add(self, o: LatticeStats) -> LatticeStats {
        LatticeStats {
            points: self.points + o.points,
            searched: self.searched + o.searched,
            moved: self.moved + o.moved,
            newton_iterations: self.newton_iterations + o.newton_iterations,
        }
    }
}

/// The clay as it was, over a box of lattice points: densities and colours, `x` fastest.
#[derive(Clone, Debug)]
struct Source {
    lo: IVec3,
    dims: IVec3,
    density: Vec<f32>,
    colour: Vec<Colour>,
}

impl Source {
    fn empty() -> Self {
        Self { lo: IVec3::ZERO, dims: IVec3::ZERO, density: Vec::new(), colour: Vec::new() }
    }

    fn contains(&self, lo: IVec3, hi: IVec3) -> bool {
        lo.cmpge(self.lo).all() && (hi - self.lo).cmplt(self.dims).all()
    }

    #[inline]
    fn index(&self, p: IVec3) -> Option<usize> {
        let c = p - self.lo;
        (c.cmpge(IVec3::ZERO).all() && c.cmplt(self.dims).all())
            .then(|| (c.x + self.dims.x * (c.y + self.dims.y * c.z)) as usize)
    }

    /// The source over `lo ..= hi`: what this one holds is kept, the rest read from `field`
    /// (which, outside this source's box, still holds the clay as it was).
    fn grown(&self, field: &Field, lo: IVec3, hi: IVec3) -> Self {
        let dims = hi - lo + IVec3::ONE;
        let n = (dims.x as usize) * (dims.y as usize) * (dims.z as usize);
        let mut density = Vec::with_capacity(n);
        let mut colour = Vec::with_capacity(n);
        let mut reader = FieldReader::new(field);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let p = IVec3::new(x, y, z);
                    match self.index(p) {
                        Some(i) => {
                            density.push(self.density[i]);
                            colour.push(self.colour[i]);
                        }
                        None => {
                            let d = reader.density(p);
                            density.push(if d.is_finite() { d.clamp(0.0, 1.0) } else { 0.0 });
                            colour.push(if d > 0.0 { reader.colour(p) } else { DEFAULT_COLOUR });
                        }
                    }
                }
            }
        }
        Self { lo, dims, density, colour }
    }

    /// The density at a lattice point (0 outside).
    #[inline]
    fn at(&self, p: IVec3) -> f32 {
        self.index(p).map_or(0.0, |i| self.density[i])
    }

    /// The trilinear density at index coordinates `p`.
    #[inline]
    fn density_at(&self, p: [f64; 3]) -> f32 {
        let base = p.map(f64::floor);
        let f = [p[0] - base[0], p[1] - base[1], p[2] - base[2]];
        let b = IVec3::new(base[0] as i32, base[1] as i32, base[2] as i32);
        let mut acc = 0.0f64;
        for c in 0..8 {
            let o = IVec3::new(c & 1, (c >> 1) & 1, (c >> 2) & 1);
            let w = (if o.x == 1 { f[0] } else { 1.0 - f[0] })
                * (if o.y == 1 { f[1] } else { 1.0 - f[1] })
                * (if o.z == 1 { f[2] } else { 1.0 - f[2] });
            if w != 0.0 {
                acc += w * self.at(b + o) as f64;
            }
        }
        acc as f32
    }

    /// The colour of the nearest lattice point holding matter around `p`, else the default.
    fn colour_near(&self, p: [f64; 3]) -> Colour {
        let near = IVec3::new(p[0].round() as i32, p[1].round() as i32, p[2].round() as i32);
        if let Some(i) = self.index(near).filter(|&i| self.density[i] > 0.0) {
            return self.colour[i];
        }
        let base = IVec3::new(p[0].floor() as i32, p[1].floor() as i32, p[2].floor() as i32);
        (0..8)
            .map(|c| base + IVec3::new(c & 1, (c >> 1) & 1, (c >> 2) & 1))
            .filter_map(|q| self.index(q))
            .filter(|&i| self.density[i] > 0.0)
            .max_by(|&a, &b| self.density[a].total_cmp(&self.density[b]))
            .map_or(DEFAULT_COLOUR, |i| self.colour[i])
    }

    fn bytes(&self) -> usize {
        self.density.len() * (std::mem::size_of::<f32>() + std::mem::size_of::<Colour>())
    }
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
    source: Source,
    /// The field's iso-level: the surface the function mapping moves.
    iso: f64,
    /// `ε` of the shift, per metre.
    epsilon: f64,
    /// The longest shift, metres.
    max_shift_m: f64,
    /// `λ` of the window: `λ F_c = 1` at [`FACE_BLEND`] inside a face.
    window_scale: f64,
}

/// One sample of the result: where the clay is read for it, and its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mapped {
    /// Where the clay is read, in index coordinates of the field's lattice.
    pub read_at: [f64; 3],
    /// Whether that is the sample's own lattice point (nothing moved it).
    pub unmoved: bool,
    /// Its parameters, when it has a preimage.
    pub uvw: Option<Uvw>,
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
        let spacing = (0..3)
            .map(|a| (spec.region.size()[a] as f64) / (spec.counts[a].max(2) - 1) as f64)
            .fold(f64::INFINITY, f64::min);
        let mut lattice = Self {
            spec: *spec,
            fitted: volume.clone(),
            volume: volume.clone(),
            fit: FitReport { max_error: 0.0, rms_error: 0.0, samples: 0 },
            transform,
            source: Source::empty(),
            iso: field.iso() as f64,
            epsilon: 0.25 / spacing,
            max_shift_m: MAX_SHIFT_SPACINGS * spacing,
            window_scale: 1.0 / (FACE_BLEND * (1.0 - FACE_BLEND)),
        };
        let (lo, hi) = lattice.source_box(volume.hull())?;
        lattice.source = Source::empty().grown(field, lo, hi);
        let source = &lattice.source;
        let to_index = |x: Vec3| {
            let p = transform.world_to_index(x);
            [p.x as f64, p.y as f64, p.z as f64]
        };
        let per_span = spec.fit_samples_per_span(transform.voxel_size_m);
        lattice.fit = volume.fit_field(|x| source.density_at(to_index(x)), per_span)?;
        lattice.fitted = volume.clone();
        lattice.volume = volume;
        Ok(lattice)
    }

    /// The lattice points to copy so that every read of the result over `hull` (the control
    /// points' box) lies in the copy: the box and the hull, grown by the longest shift and a
    /// voxel; refused over [`MAX_SOURCE_POINTS`].
    fn source_box(&self, hull: Aabb) -> Result<(IVec3, IVec3), LatticeError> {
        let t = &self.transform;
        let room = self.max_shift_m as f32 + 2.0 * t.voxel_size_m;
        let world = self.spec.region.union(&hull).expanded(room);
        let lo = t.world_to_index(world.min).floor().as_ivec3();
        let hi = t.world_to_index(world.max).ceil().as_ivec3();
        let dims = (hi - lo + IVec3::ONE).as_i64vec3();
        let points = (dims.x * dims.y * dims.z) as u64;
        if points > MAX_SOURCE_POINTS {
            return Err(LatticeError::TooLarge {
                points,
                limit: MAX_SOURCE_POINTS,
                size_m: world.size().to_array(),
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
    /// box to re-evaluate (everything the lattice reaches before and after).
    pub fn set_controls(&mut self, volume: &SplineVolume) -> Result<Aabb, LatticeError> {
        let before = self.reach();
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
        self.volume = volume.clone();
        Ok(before.union(&self.reach()))
    }

    /// Where the clay is read for the world point `x` (see the module documentation); the
    /// inverse mapping starts from `start` when given.
    pub fn map_point(&self, x: Vec3, start: Option<Uvw>) -> Mapped {
        let xi = self.transform.world_to_index(x);
        self.map_index([xi.x as f64, xi.y as f64, xi.z as f64], start)
    }

    /// [`Self::map_point`] for the point at index coordinates `own` of the field's lattice.
    fn map_index(&self, own: [f64; 3], start: Option<Uvw>) -> Mapped {
        let t = &self.transform;
        let voxel = t.voxel_size_m as f64;
        let origin = t.origin_m;
        let x = Vec3::new(
            (origin.x as f64 + own[0] * voxel) as f32,
            (origin.y as f64 + own[1] * voxel) as f32,
            (origin.z as f64 + own[2] * voxel) as f32,
        );
        let unmoved = Mapped { read_at: own, unmoved: true, uvw: None, iterations: 0 };
        let (uvw, iterations) = if self.volume.is_at_rest() {
            (self.volume.rest_parameters(x), 0)
        } else {
            let m = self.volume.inverse_map_from(x, start);
            if !m.converged {
                return Mapped { iterations: m.iterations, ..unmoved };
            }
            (m.uvw, m.iterations)
        };
        let cube = unit_cube_function(uvw);
        if cube <= 0.0 {
            return Mapped { uvw: Some(uvw), iterations, ..unmoved };
        }
        let kappa = smoothstep(self.window_scale * cube);
        let region = self.spec.region;
        let (min, size) = (region.min, region.size());
        let mut rest: [f64; 3] = std::array::from_fn(|a| min[a] as f64 + size[a] as f64 * uvw.0[a]);
        let shift = self.shift(uvw);
        for a in 0..3 {
            rest[a] += shift[a];
        }
        let read_at: [f64; 3] = std::array::from_fn(|a| {
            let target = (rest[a] - origin[a] as f64) / voxel;
            own[a] + kappa * (target - own[a])
        });
        let moved = (0..3).any(|a| (read_at[a] - own[a]).abs() > 1e-4);
        if moved {
            Mapped { read_at, unmoved: false, uvw: Some(uvw), iterations }
        } else {
            Mapped { uvw: Some(uvw), iterations, ..unmoved }
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
        mut colours: Option<&mut Vec<Colour>>,
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
        let eval_row = |row: usize, out: &mut [f32], mut colour: Option<&mut [Colour]>| {
            let start = row_of(row);
            let mut stats = LatticeStats { points: nx, ..LatticeStats::default() };
            let mut previous: [Option<Uvw>; 2] = [None, None];
            for (x, d) in out.iter_mut().enumerate() {
                let p = start + IVec3::new(x as i32, 0, 0);
                let guess = match previous {
                    [Some(a), Some(b)] => Some(Uvw(std::array::from_fn(|i| 2.0 * b.0[i] - a.0[i]))),
                    [_, b] => b,
                };
                let m = self.map_index([p.x as f64, p.y as f64, p.z as f64], guess);
                previous = [previous[1], m.uvw];
                stats.searched += usize::from(m.iterations > 0);
                stats.newton_iterations += m.iterations as u64;
                if m.unmoved {
                    let own = self.source.index(p);
                    *d = own.map_or(0.0, |i| self.source.density[i]);
                    if let Some(c) = colour.as_deref_mut() {
                        c[x] = own.map_or(DEFAULT_COLOUR, |i| self.source.colour[i]);
                    }
                } else {
                    stats.moved += 1;
                    *d = self.source.density_at(m.read_at).clamp(0.0, 1.0);
                    if let Some(c) = colour.as_deref_mut() {
                        c[x] = self.source.colour_near(m.read_at);
                    }
                }
            }
            stats
        };
        match colours {
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
        }
    }

    /// Evaluates the deformed clay over `world` and writes it into `field`, growing the copy
    /// of the clay first where the control points now reach beyond it. The caller holds
    /// `field`'s stroke open (the lattice's whole session is one undo step).
    pub fn write(&mut self, field: &mut Field, world: Aabb) -> Result<LatticeStats, LatticeError> {
        let (slo, shi) = self.source_box(self.volume.hull())?;
        if !self.source.contains(slo, shi) {
            let lo = slo.min(self.source.lo);
            let hi = shi.max(self.source.lo + self.source.dims - IVec3::ONE);
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
