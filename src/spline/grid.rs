//! Evaluation over regular grids of world points, and the region a control point affects.
//!
//! Two paths:
//!
//! - *Rest lattice* ([`SplineVolume::rest_density_grid`], ESM §4.3's "all the coefficients
//!   can be evaluated before"): the parameters of grid point `(x, y, z)` are
//!   `((x − min)/size)` per axis, independent of the other axes, so the spline separates. One
//!   basis table per axis (`N` samples × `k` values) and three axis-by-axis contractions of
//!   the `l × m × n` control values (along u, then v, then w) cost
//!   `O(N·m·n·k + N²·n·k + N³·k)`, i.e. `O(N³·k)` for `N ≥ m, n`, instead of `k³` products
//!   per point. This evaluates the function mapping alone (`F` at
//!   the rest parameters); it is the mapped density when the lattice is at rest
//!   ([`SplineVolume::is_at_rest`]).
//! - *Deformed lattice* ([`SplineVolume::mapped_density_grid`]): per point, the inverse
//!   mapping and `F`, rows of the grid in parallel; along a row each point's Newton search
//!   starts from its neighbour's parameters.
//!
//! [`SplineVolume::density_grid`] picks the first when it applies. Both clip
//! ([`super::Clipping`]) and write densities, `x` fastest. The rest path allocates its
//! intermediate arrays (8 bytes a grid point, twice that for NURBS); the deformed path
//! allocates nothing per point.
//!
//! ## Locality
//!
//! A control point's basis function is non-zero on its support only, `order` knot spans per
//! axis (the whole cube for Bézier, ESM §4.4); changing its value changes `F` there and
//! nowhere else ([`SplineVolume::control_support`], [`SplineVolume::rest_bounds`]). Moving
//! it changes `P` on the same support, so the mapped density can change only where that
//! support lies before or after the move: inside the bounding box of the control points
//! that share a span with it ([`SplineVolume::support_world_bounds`]). Callers re-evaluate
//! only there after a drag.

use rayon::prelude::*;

use crate::math::{Aabb, IVec3, UVec3, Vec3, VoxelTransform};

use super::clip::{r_intersection, unit_strip, Clipping};
use super::tensor::{transform_all, Rows};
use super::volume::{SplineVolume, Uvw};
use super::SplineError;

/// The most points a grid may have (2²⁷, 512³).
pub const MAX_GRID_SAMPLES: usize = 1 << 27;

/// A regular grid of world points: the lattice points `min … min + counts − 1` of a voxel
/// transform, index `x + nx·(y + ny·z)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleGrid {
    /// The voxel size and origin.
    pub transform: VoxelTransform,
    /// The first lattice point.
    pub min: IVec3,
    /// Points per axis.
    pub counts: UVec3,
}

/// What a grid evaluation did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GridStats {
    /// Grid points.
    pub points: usize,
    /// Points where the spline was evaluated (the others are 0 without it: beyond the
    /// clipping band, or with no preimage).
    pub evaluated: usize,
    /// Points whose inverse mapping converged (the deformed path; all evaluated points on the
    /// rest path).
    pub converged: usize,
    /// Points inside the lattice (parameters in the unit cube).
    pub inside: usize,
    /// Newton iterations, in all.
    pub newton_iterations: u64,
}

impl std::ops::Add for GridStats {
    type Output = GridStats;

    fn add(self, o: GridStats) -> GridStats {
        GridStats {
            points: self.points + o.points,
            evaluated: self.evaluated + o.evaluated,
            converged: self.converged + o.converged,
            inside: self.inside + o.inside,
            newton_iterations: self.newton_iterations + o.newton_iterations,
        }
    }
}

/// A box of parameters; bounds may be infinite (a support that reaches past the cube's face,
/// where the end spans' polynomials continue).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamBox {
    /// The smallest parameters.
    pub min: Uvw,
    /// The largest parameters.
    pub max: Uvw,
}

impl ParamBox {
    /// The unit cube.
    pub const UNIT: ParamBox = ParamBox { min: Uvw::new(0.0, 0.0, 0.0), max: Uvw::new(1.0, 1.0, 1.0) };

    /// Whether `uvw` lies in the box.
    pub fn contains(&self, uvw: Uvw) -> bool {
        (0..3).all(|a| uvw.0[a] >= self.min.0[a] && uvw.0[a] <= self.max.0[a])
    }

    /// The box clamped to `[lo, hi]` on every axis.
    pub fn clamped(&self, lo: f64, hi: f64) -> ParamBox {
        ParamBox {
            min: Uvw(self.min.0.map(|t| t.clamp(lo, hi))),
            max: Uvw(self.max.0.map(|t| t.clamp(lo, hi))),
        }
    }
}

impl SampleGrid {
    /// A grid of `counts` points from lattice point `min`; refused when empty, larger than
    /// [`MAX_GRID_SAMPLES`], or with a voxel size or origin that is not positive and finite.
    pub fn new(transform: VoxelTransform, min: IVec3, counts: UVec3) -> Result<Self, SplineError> {
        let grid = |reason: String| Err(SplineError::Grid { reason });
        if !(transform.voxel_size_m.is_finite()
            && transform.voxel_size_m > 0.0
            && transform.origin_m.is_finite())
        {
            return grid(format!(
                "voxel size {} m, origin {:?}",
                transform.voxel_size_m,
                transform.origin_m.to_array()
            ));
        }
        let len = counts.x as u128 * counts.y as u128 * counts.z as u128;
        if len == 0 || len > MAX_GRID_SAMPLES as u128 {
            return grid(format!("{} × {} × {} points", counts.x, counts.y, counts.z));
        }
        if (min.as_i64vec3() + counts.as_i64vec3()).max_element() > i32::MAX as i64 {
            return grid(format!("lattice points from {:?} overflow", min.to_array()));
        }
        Ok(Self { transform, min, counts })
    }

    /// The lattice points of `transform` inside `region` (at least one per axis: the nearest
    /// when the box is thinner than a voxel).
    pub fn covering(region: Aabb, transform: VoxelTransform) -> Result<Self, SplineError> {
        if !(region.min.is_finite() && region.max.is_finite()) || region.is_empty() {
            return Err(SplineError::Grid {
                reason: format!("the box {:?} – {:?} is empty or not finite", region.min, region.max),
            });
        }
        let lo = transform.world_to_index(region.min).ceil();
        let hi = transform.world_to_index(region.max).floor().max(lo);
        let limit = i32::MAX as f32 / 2.0;
        if !(lo.abs().max_element() < limit && hi.abs().max_element() < limit) {
            return Err(SplineError::Grid { reason: "the box lies too far from the origin".into() });
        }
        let (lo, hi) = (lo.as_ivec3(), hi.as_ivec3());
        Self::new(transform, lo, (hi - lo + IVec3::ONE).as_uvec3())
    }

    /// The number of points.
    pub fn len(&self) -> usize {
        self.counts.x as usize * self.counts.y as usize * self.counts.z as usize
    }

    /// Whether the grid has no points (never, for a grid made by [`Self::new`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The world position of grid point `(x, y, z)`, counted from `min`, each below its count.
    pub fn point(&self, x: u32, y: u32, z: u32) -> Vec3 {
        self.transform.index_to_world((self.min + UVec3::new(x, y, z).as_ivec3()).as_vec3())
    }

    /// The world coordinates of the grid's points along `axis`.
    fn axis_coordinates(&self, axis: usize) -> Vec<f64> {
        let (vs, origin) = (self.transform.voxel_size_m as f64, self.transform.origin_m[axis] as f64);
        (0..self.counts[axis]).map(|i| origin + (self.min[axis] as f64 + i as f64) * vs).collect()
    }

    fn check_output(&self, len: usize) -> Result<(), SplineError> {
        if len != self.len() {
            return Err(SplineError::Length { what: "the output", expected: self.len(), given: len });
        }
        Ok(())
    }
}

impl SplineVolume {
    /// The parameters where control `(i, j, k)`'s basis function can be non-zero: its knots'
    /// supports per axis, infinite past a face when it acts on the end span there.
    pub fn control_support(&self, i: usize, j: usize, k: usize) -> Result<ParamBox, SplineError> {
        self.control(i, j, k)?;
        let s = [self.knots(0).support(i), self.knots(1).support(j), self.knots(2).support(k)];
        Ok(ParamBox { min: Uvw(s.map(|s| s.0)), max: Uvw(s.map(|s| s.1)) })
    }

    /// The world box of the rest image of `params`, cut to where the clipped density can be
    /// non-zero (the unit cube grown by the clipping's band): where the rest-lattice density
    /// changes when a value in that support changes.
    pub fn rest_bounds(&self, params: &ParamBox, clip: &Clipping) -> Aabb {
        let band = clip.band();
        let p = params.clamped(-band, 1.0 + band);
        Aabb { min: self.rest_point(p.min), max: self.rest_point(p.max) }
    }

    /// The bounding box of the current positions of every control point that shares a knot
    /// span with `(i, j, k)`, grown by the clipping band (times the box's size) on the sides
    /// where its support reaches a face. It holds the image of the control's support inside
    /// the cube (convex hull property), and about that of the band outside it (the continued
    /// end spans, to first order). Moving `(i, j, k)` changes the mapped density only where
    /// its support maps before or after the move: re-evaluate the union of this box taken
    /// before and after.
    pub fn support_world_bounds(
        &self,
        i: usize,
        j: usize,
        k: usize,
        clip: &Clipping,
    ) -> Result<Aabb, SplineError> {
        let support = self.control_support(i, j, k)?;
        let ijk = [i, j, k];
        let orders = self.orders();
        let counts = self.counts();
        let lo: [usize; 3] = std::array::from_fn(|a| ijk[a].saturating_sub(orders[a] - 1));
        let hi: [usize; 3] = std::array::from_fn(|a| (ijk[a] + orders[a] - 1).min(counts[a] - 1));
        let mut bounds = Aabb::EMPTY;
        for c in lo[2]..=hi[2] {
            for b in lo[1]..=hi[1] {
                for a in lo[0]..=hi[0] {
                    bounds = bounds
                        .grown_by_point(self.controls()[a + counts[0] * (b + counts[1] * c)].position_m);
                }
            }
        }
        let grow = self.region().size() * clip.band() as f32;
        for a in 0..3 {
            if support.min.0[a] <= 0.0 {
                bounds.min[a] -= grow[a];
            }
            if support.max.0[a] >= 1.0 {
                bounds.max[a] += grow[a];
            }
        }
        Ok(bounds)
    }

    /// The clipped density at every grid point, taking the parameters from the rest
    /// lattice's affine inverse (function mapping; see the module documentation), by
    /// separable contraction.
    pub fn rest_density_grid(
        &self,
        grid: &SampleGrid,
        clip: &Clipping,
        out: &mut [f32],
    ) -> Result<GridStats, SplineError> {
        grid.check_output(out.len())?;
        let region = self.region();
        // Per axis: the parameters, and the run of grid points within the band (an interval:
        // the others are 0 whatever the function, `Clipping::is_empty_at`, and no point of
        // the runs' box is).
        let mut params: [Vec<f64>; 3] = Default::default();
        let mut active = [(0usize, 0usize); 3];
        for a in 0..3 {
            let (min, size) = (region.min[a] as f64, region.max[a] as f64 - region.min[a] as f64);
            let p: Vec<f64> = grid.axis_coordinates(a).iter().map(|x| (x - min) / size).collect();
            let live = |t: &f64| clip.cube_scale() * unit_strip(*t) > -clip.iso();
            let first = p.iter().position(live).unwrap_or(p.len());
            let last = p.iter().rposition(live).map_or(first, |l| l + 1);
            active[a] = (first, last.max(first));
            params[a] = p;
        }
        out.fill(0.0);
        let n: [usize; 3] = std::array::from_fn(|a| active[a].1 - active[a].0);
        if n.contains(&0) {
            return Ok(GridStats { points: grid.len(), ..GridStats::default() });
        }
        let live_params: [&[f64]; 3] = std::array::from_fn(|a| &params[a][active[a].0..active[a].1]);
        // The live parameters lie within the band: the continued polynomials are only
        // needed that far.
        let tables: [Rows; 3] = std::array::from_fn(|a| Rows::basis(self.knots(a), live_params[a]));
        let tables_ref = [&tables[0], &tables[1], &tables[2]];
        let counts = self.counts();
        let rational = !self.has_uniform_weights();
        let numerators: Vec<f64> = if rational {
            self.controls().iter().map(|c| c.weight * c.value).collect()
        } else {
            self.controls().iter().map(|c| c.value).collect()
        };
        let (num, _) = transform_all(&numerators, counts, tables_ref);
        let den = rational.then(|| {
            let w: Vec<f64> = self.controls().iter().map(|c| c.weight).collect();
            transform_all(&w, counts, tables_ref).0
        });
        // The cube's function, by parts: the strips per axis, `F_p(u) & F_p(v)` per (u, v).
        let strips: [Vec<f64>; 3] =
            std::array::from_fn(|a| live_params[a].iter().map(|&t| unit_strip(t)).collect());
        let uv: Vec<f64> = strips[1]
            .iter()
            .flat_map(|&sv| strips[0].iter().map(move |&su| r_intersection(su, sv)))
            .collect();
        let (nx, ny) = (grid.counts.x as usize, grid.counts.y as usize);
        for (c, &strip_w) in strips[2].iter().enumerate() {
            for b in 0..n[1] {
                let row = nx * (active[1].0 + b + ny * (active[2].0 + c)) + active[0].0;
                for a in 0..n[0] {
                    let index = a + n[0] * (b + n[1] * c);
                    let f = match &den {
                        Some(w) => num[index] / w[index].max(1e-3 * self.min_weight_value()),
                        None => num[index],
                    };
                    let cube = r_intersection(uv[a + n[0] * b], strip_w);
                    let g = r_intersection(f - clip.iso(), clip.cube_scale() * cube);
                    out[row + a] = (clip.iso() + g).clamp(0.0, 1.0) as f32;
                }
            }
        }
        let inside =
            (0..3).map(|a| live_params[a].iter().filter(|t| (0.0..=1.0).contains(*t)).count()).product();
        let evaluated = n.iter().product();
        Ok(GridStats { points: grid.len(), evaluated, converged: evaluated, inside, newton_iterations: 0 })
    }

    /// The clipped density of the deformed solid at every grid point: inverse mapping and
    /// function per point ([`Self::mapped_density`]), rows in parallel, each point's search
    /// starting from its neighbour's parameters.
    pub fn mapped_density_grid(
        &self,
        grid: &SampleGrid,
        clip: &Clipping,
        out: &mut [f32],
    ) -> Result<GridStats, SplineError> {
        grid.check_output(out.len())?;
        let nx = grid.counts.x as usize;
        let ny = grid.counts.y;
        let stats = out
            .par_chunks_mut(nx)
            .enumerate()
            .map(|(row, line)| {
                let (y, z) = (row as u32 % ny, row as u32 / ny);
                let mut stats = GridStats { points: nx, ..GridStats::default() };
                // Each search starts from the previous point's parameters moved by the
                // step along the row through the inverse Jacobian (first order).
                let step = [grid.transform.voxel_size_m as f64, 0.0, 0.0];
                let mut start: Option<Uvw> = None;
                for (x, d) in line.iter_mut().enumerate() {
                    let p = grid.point(x as u32, y, z);
                    let (density, map, eval) = self.mapped_density_detailed(p, start, clip);
                    *d = density;
                    stats.evaluated += usize::from(map.iterations > 0 || map.converged);
                    stats.converged += usize::from(map.converged);
                    stats.inside += usize::from(map.inside);
                    stats.newton_iterations += map.iterations as u64;
                    start = match (map.converged, eval) {
                        (true, Some(e)) => Some(SplineVolume::predict(map.uvw, &e.jacobian, step)),
                        _ => None,
                    };
                }
                stats
            })
            .reduce(GridStats::default, |a, b| a + b);
        Ok(stats)
    }

    /// The clipped density at every grid point: the separable rest path when the lattice is
    /// at rest, else the per-point mapped path.
    pub fn density_grid(
        &self,
        grid: &SampleGrid,
        clip: &Clipping,
        out: &mut [f32],
    ) -> Result<GridStats, SplineError> {
        if self.is_at_rest() {
            self.rest_density_grid(grid, clip, out)
        } else {
            self.mapped_density_grid(grid, clip, out)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spline::fit::tests::ball;
    use crate::spline::volume::tests::{unit_box, volumes, Rng};
    use crate::spline::{KnotStyle, SplineKind};

    fn grid_over(vol: &SplineVolume, voxel: f32, margin: f32) -> SampleGrid {
        SampleGrid::covering(vol.region().expanded(margin), VoxelTransform::new(voxel)).unwrap()
    }

    fn per_point(vol: &SplineVolume, grid: &SampleGrid, clip: &Clipping) -> Vec<f32> {
        let mut out = Vec::with_capacity(grid.len());
        for z in 0..grid.counts.z {
            for y in 0..grid.counts.y {
                for x in 0..grid.counts.x {
                    out.push(vol.density_at_parameters(vol.rest_parameters(grid.point(x, y, z)), clip));
                }
            }
        }
        out
    }

    #[test]
    fn the_separable_grid_equals_per_point_evaluation() {
        let mut rng = Rng(59);
        for mut vol in volumes() {
            vol.update_values(|_, _| 1.2 * rng.next_f64() - 0.1).unwrap();
            if vol.kind() == SplineKind::Nurbs {
                vol.set_weight(2, 2, 2, 5.0).unwrap();
                vol.set_weight(0, 4, 1, 0.2).unwrap();
            }
            for clip in [Clipping::PAPER, Clipping::with_band(0.5, 0.05).unwrap()] {
                let grid = grid_over(&vol, 0.011, 0.15);
                let mut out = vec![0.0; grid.len()];
                let stats = vol.rest_density_grid(&grid, &clip, &mut out).unwrap();
                let want = per_point(&vol, &grid, &clip);
                let worst = out.iter().zip(&want).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
                // The per-point path reads f32 world points; the grid's coordinates are f64.
                assert!(worst < 1e-5, "{:?}: {worst}", vol.kind());
                assert!(stats.evaluated < stats.points && stats.inside > 0, "{stats:?}");
            }
        }
    }

    #[test]
    fn the_mapped_grid_of_a_rest_lattice_equals_the_rest_grid() {
        let b = unit_box();
        let mut vol = SplineVolume::bspline(b, [8, 8, 8], [4, 4, 4], KnotStyle::Uniform).unwrap();
        vol.fit_field(ball(b.centre(), 0.08, 0.01), 3).unwrap();
        let clip = Clipping::with_band(0.5, 0.05).unwrap();
        let grid = grid_over(&vol, 0.01, 0.03);
        let (mut fast, mut slow) = (vec![0.0; grid.len()], vec![0.0; grid.len()]);
        vol.rest_density_grid(&grid, &clip, &mut fast).unwrap();
        let stats = vol.mapped_density_grid(&grid, &clip, &mut slow).unwrap();
        let worst = fast.iter().zip(&slow).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        assert!(worst < 1e-4, "{worst} ({stats:?})");
        assert!(fast.iter().any(|&d| d > 0.9));
    }

    #[test]
    fn a_grid_of_128_cubed_points_is_quick() {
        let b = Aabb { min: Vec3::ZERO, max: Vec3::splat(0.256) };
        let mut vol = SplineVolume::bspline(b, [16; 3], [4; 3], KnotStyle::Clamped).unwrap();
        vol.fit_field(ball(b.centre(), 0.08, 0.01), 3).unwrap();
        let grid = SampleGrid::new(VoxelTransform::new(0.002), IVec3::ZERO, UVec3::splat(128)).unwrap();
        let mut out = vec![0.0; grid.len()];
        let clip = Clipping::with_band(0.5, 0.02).unwrap();
        let start = std::time::Instant::now();
        let stats = vol.rest_density_grid(&grid, &clip, &mut out).unwrap();
        let rest = start.elapsed();
        let mut bent = vol.clone();
        bent.update_positions(|_, c| {
            c.rest_m + Vec3::new(0.0, 0.1 * (c.rest_m.x - 0.128).powi(2) * 10.0, 0.0)
        })
        .unwrap();
        let start = std::time::Instant::now();
        let mapped = bent.mapped_density_grid(&grid, &clip, &mut out).unwrap();
        let deformed = start.elapsed();
        eprintln!(
            "128³ grid, 16³ cubic controls: rest (separable) {:.1} ms {stats:?}; deformed (per point) {:.0} ms \
             ({:.2} Newton iterations a point) {mapped:?}",
            rest.as_secs_f64() * 1e3,
            deformed.as_secs_f64() * 1e3,
            mapped.newton_iterations as f64 / mapped.points as f64
        );
    }

    #[test]
    fn raising_a_value_acts_only_on_its_support_for_b_splines_and_everywhere_for_bezier() {
        let b = unit_box();
        let clip = Clipping::with_band(0.5, 0.05).unwrap();
        let mut rng = Rng(61);
        for vol in [
            SplineVolume::bspline(b, [9, 8, 7], [4, 3, 4], KnotStyle::Clamped).unwrap(),
            SplineVolume::bspline(b, [9, 8, 7], [3, 3, 2], KnotStyle::Uniform).unwrap(),
            SplineVolume::bezier(b, [5, 4, 6]).unwrap(),
        ] {
            let mut vol = vol;
            vol.update_values(|_, _| 0.3 + 0.4 * rng.next_f64()).unwrap();
            let (i, j, k) = (4, 3, 2);
            let support = vol.control_support(i, j, k).unwrap();
            let mut raised = vol.clone();
            raised.set_value(i, j, k, vol.control(i, j, k).unwrap().value + 0.5).unwrap();
            let mut higher = raised.clone();
            higher.set_value(i, j, k, vol.control(i, j, k).unwrap().value + 1.0).unwrap();
            let bezier = vol.kind() == SplineKind::Bezier;
            let (mut changed, mut unchanged) = (0, 0);
            for _ in 0..3000 {
                let uvw = rng.uvw(0.0, 1.0);
                let (f0, f1, f2) = (vol.value(uvw), raised.value(uvw), higher.value(uvw));
                assert!(f1 >= f0 && f2 >= f1, "raising a value lowered F");
                let inner = ParamBox {
                    min: Uvw(support.min.0.map(|t| t + 1e-9)),
                    max: Uvw(support.max.0.map(|t| t - 1e-9)),
                };
                if inner.contains(uvw) || bezier {
                    assert!(f1 > f0, "{:?}: no change inside the support at {uvw:?}", vol.kind());
                    changed += 1;
                } else if !support.contains(uvw) {
                    assert_eq!(f1, f0, "{:?}: change outside the support at {uvw:?}", vol.kind());
                    unchanged += 1;
                }
            }
            if bezier {
                assert_eq!(unchanged, 0);
                assert_eq!(
                    support,
                    ParamBox { min: Uvw([f64::NEG_INFINITY; 3]), max: Uvw([f64::INFINITY; 3]) }
                );
            } else {
                assert!(changed > 30 && unchanged > 1000, "{changed} changed, {unchanged} unchanged");
            }
            // On a grid: the changed densities lie within the rest bounds of the support.
            let grid = grid_over(&vol, 0.01, 0.05);
            let (mut d0, mut d1) = (vec![0.0; grid.len()], vec![0.0; grid.len()]);
            vol.rest_density_grid(&grid, &clip, &mut d0).unwrap();
            raised.rest_density_grid(&grid, &clip, &mut d1).unwrap();
            let bounds = vol.rest_bounds(&support, &clip);
            for z in 0..grid.counts.z {
                for y in 0..grid.counts.y {
                    for x in 0..grid.counts.x {
                        let index = (x + grid.counts.x * (y + grid.counts.y * z)) as usize;
                        if d0[index] != d1[index] {
                            let p = grid.point(x, y, z);
                            assert!(
                                p.cmpge(bounds.min - 1e-6).all() && p.cmple(bounds.max + 1e-6).all(),
                                "density changed at {p}, outside {bounds:?}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_drag_changes_the_density_only_inside_the_support_bounds() {
        let b = unit_box();
        let clip = Clipping::with_band(0.5, 0.03).unwrap();
        let mut vol = SplineVolume::bspline(b, [8, 8, 8], [3, 3, 3], KnotStyle::Clamped).unwrap();
        vol.fit_field(ball(b.centre(), 0.09, 0.01), 3).unwrap();
        let (i, j, k) = (5, 4, 4);
        let before_bounds = vol.support_world_bounds(i, j, k, &clip).unwrap();
        let mut dragged = vol.clone();
        let p = vol.control(i, j, k).unwrap().position_m;
        dragged.set_position(i, j, k, p + Vec3::new(0.04, 0.02, -0.01)).unwrap();
        let after_bounds = dragged.support_world_bounds(i, j, k, &clip).unwrap();
        let bounds = before_bounds.union(&after_bounds);
        let grid = grid_over(&vol, 0.008, 0.05);
        let (mut d0, mut d1) = (vec![0.0; grid.len()], vec![0.0; grid.len()]);
        vol.density_grid(&grid, &clip, &mut d0).unwrap();
        let stats = dragged.density_grid(&grid, &clip, &mut d1).unwrap();
        let mut changed = 0;
        for z in 0..grid.counts.z {
            for y in 0..grid.counts.y {
                for x in 0..grid.counts.x {
                    let index = (x + grid.counts.x * (y + grid.counts.y * z)) as usize;
                    if (d0[index] - d1[index]).abs() > 1e-4 {
                        changed += 1;
                        let p = grid.point(x, y, z);
                        assert!(
                            p.cmpge(bounds.min).all() && p.cmple(bounds.max).all(),
                            "density changed at {p}, outside {bounds:?}"
                        );
                    }
                }
            }
        }
        assert!(changed > 10, "the drag changed {changed} points ({stats:?})");
        assert!(bounds.size().max_element() < b.size().max_element(), "the bounds are local: {bounds:?}");
    }

    #[test]
    fn a_nurbs_weight_acts_as_the_paper_says() {
        // ESM §4.4: "if a control point is inside the solid, with a positive function value,
        // the effect of changing its weight can be considered as null. [...] if the control
        // point is close to the boundary of the solid, i.e. the last control point with a
        // positive value, the effect is locally important. If the control point has negative
        // value, the effect is locally important too, depending of course on the order."
        let b = unit_box();
        let clip = Clipping::PAPER;
        let mut reach = Vec::new();
        for order in [3, 4] {
            let mut vol = SplineVolume::nurbs(b, [10, 6, 6], [order, 3, 3], KnotStyle::Clamped).unwrap();
            // A slab of clay along u: signed values (f − iso) +0.5 for i ≤ 4, −0.5 beyond.
            vol.update_values(|[i, _, _], _| if i <= 4 { 1.0 } else { 0.0 }).unwrap();
            let surface = |v: &SplineVolume| {
                // Where F crosses iso along the u axis at v = w = 0.5 (bisection).
                let (mut lo, mut hi) = (0.0, 1.0);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if v.value(Uvw::new(mid, 0.5, 0.5)) > clip.iso() {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                lo
            };
            let base = surface(&vol);
            let effect = |i: usize, w: f64| {
                let mut weighted = vol.clone();
                for j in 0..6 {
                    for k in 0..6 {
                        weighted.set_weight(i, j, k, w).unwrap();
                    }
                }
                let shift = surface(&weighted) - base;
                // The largest change of F inside the control's support and outside it, and
                // the length of u over which F changes.
                let (mut near, mut far, mut changed) = (0.0f64, 0.0f64, 0);
                for s in 0..=200 {
                    let uvw = Uvw::new(s as f64 / 200.0, 0.5, 0.5);
                    let d = (weighted.value(uvw) - vol.value(uvw)).abs();
                    let support = vol.knots(0).support(i);
                    if uvw.0[0] > support.0 && uvw.0[0] < support.1 {
                        near = near.max(d);
                    } else {
                        far = far.max(d);
                    }
                    changed += usize::from(d > 1e-9);
                }
                // And in the world: where the mapped density crosses iso along x through
                // the box's centre (the weight moves space too).
                let crossing = |v: &SplineVolume| {
                    let (mut lo, mut hi) = (b.min.x, b.max.x);
                    for _ in 0..40 {
                        let mid = 0.5 * (lo + hi);
                        if v.mapped_density(Vec3::new(mid, b.centre().y, b.centre().z), &clip) > 0.5 {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    lo
                };
                let world_shift = crossing(&weighted) - crossing(&vol);
                (shift, near, far, changed as f64 / 200.0, world_shift)
            };
            // Deep inside: all its neighbours hold the same value, F is their weighted mean:
            // no effect at all.
            let (shift, near, far, _, world) = effect(1, 4.0);
            assert!(shift.abs() < 1e-12 && near < 1e-12 && far < 1e-12, "inside: {shift} {near}");
            assert!(world.abs() < 1e-6, "inside: the surface moved by {world} m");
            // The last positive control, at the boundary: the surface moves outwards.
            let (shift, near, far, _, world) = effect(4, 4.0);
            assert!(shift > 0.01, "order {order}: boundary weight moved the surface by {shift}");
            assert!(near > 0.1 && far < 1e-12, "order {order}: near {near}, far {far}");
            assert!(world > 0.0005, "order {order}: the surface moved by {world} m");
            // The first negative control: the surface moves inwards, locally.
            let (shift, near, far, extent, world) = effect(5, 4.0);
            assert!(shift < -0.01 && near > 0.1 && far < 1e-12, "order {order}: {shift} {near} {far}");
            assert!(world < -0.0005, "order {order}: the surface moved by {world} m");
            reach.push(extent);
            // And far on the negative side, where every neighbour is negative: no effect.
            let (shift, near, ..) = effect(9, 4.0);
            assert!(shift.abs() < 1e-12 && near < 1e-12);
            let boundary = effect(4, 4.0);
            eprintln!(
                "order {order}: surface at u = {base:.3}; weight 4 on the boundary control moves it by \
                 {:.3} in u, {:.1} mm in the world; weight 4 on the first negative control changes F over \
                 {extent:.2} of u",
                boundary.0,
                boundary.4 * 1e3
            );
        }
        // "Depending of course on the order": a higher order spreads the effect wider.
        assert!(reach[1] > reach[0], "{reach:?}");
    }

    #[test]
    fn bad_grids_are_refused() {
        let t = VoxelTransform::new(0.01);
        assert!(SampleGrid::new(t, IVec3::ZERO, UVec3::new(0, 4, 4)).is_err());
        assert!(SampleGrid::new(t, IVec3::ZERO, UVec3::splat(1024)).is_err());
        assert!(SampleGrid::new(VoxelTransform::new(0.0), IVec3::ZERO, UVec3::ONE).is_err());
        assert!(SampleGrid::new(VoxelTransform::new(f32::NAN), IVec3::ZERO, UVec3::ONE).is_err());
        assert!(SampleGrid::new(t, IVec3::splat(i32::MAX - 1), UVec3::splat(4)).is_err());
        assert!(SampleGrid::covering(Aabb::EMPTY, t).is_err());
        assert!(SampleGrid::covering(Aabb { min: Vec3::ZERO, max: Vec3::splat(1e30) }, t).is_err());
        let grid = SampleGrid::covering(unit_box(), t).unwrap();
        let vol = SplineVolume::bezier(unit_box(), [3, 3, 3]).unwrap();
        let mut short = vec![0.0; 3];
        assert!(vol.density_grid(&grid, &Clipping::PAPER, &mut short).is_err());
        // A grid far from the lattice is all empty, without evaluating anything.
        let far = SampleGrid::new(t, IVec3::splat(1000), UVec3::splat(8)).unwrap();
        let mut out = vec![1.0; far.len()];
        let stats = vol.rest_density_grid(&far, &Clipping::PAPER, &mut out).unwrap();
        assert!(out.iter().all(|&d| d == 0.0) && stats.evaluated == 0);
    }
}
