//! Least-squares fit of the control values to a density field (HQ §4.2.2, eq. 9–13).
//!
//! HQ finds the control coefficients `p` that minimise the mean square error between the
//! spline and densities `d` sampled on a grid of parameters,
//! `p = [(B ⊗ C ⊗ D)ᵀ (B ⊗ C ⊗ D)]⁻¹ (B ⊗ C ⊗ D)ᵀ d` (eq. 13), where `B`, `C`, `D` are the
//! per-axis matrices of basis values at the samples (eq. 3). On a full tensor grid that
//! pseudo-inverse factors, `(B ⊗ C ⊗ D)⁺ = B⁺ ⊗ C⁺ ⊗ D⁺` with `B⁺ = (BᵀB)⁻¹ Bᵀ`, so the
//! fit is three small solves, one per axis: a Cholesky factorisation of each `n × n` normal
//! matrix (n ≤ 16, plain `f64` loops) and three axis-by-axis products with the samples
//! (`super::tensor`). The result is the same least-squares solution, in `O(S³·n)` for `S`
//! samples per axis instead of a `n³ × n³` system.
//!
//! ## Samples
//!
//! Along each axis, every non-empty knot span receives `s` samples at the midpoints of `s`
//! equal parts (`s` = the samples per span asked for, [`DEFAULT_SAMPLES_PER_SPAN`] = 3 by
//! default, raised where needed so that the axis has at least as many samples as control
//! points: a Bézier axis of `n` controls, one span, gets `max(s, n)`). Midpoints of open spans
//! meet the Schoenberg–Whitney condition (every basis function is non-zero at a distinct
//! sample in order), so each normal matrix is positive definite. The field is sampled at the
//! lattice's *current* image of each parameter, `field(P(u, v, w))`: on an untouched lattice
//! that is the box's affine grid, and fitting a deformed lattice bakes the field into it.
//!
//! ## Accuracy
//!
//! A polynomial of degree below the order on each axis lies in the spline space and is
//! reproduced to rounding (10⁻⁹ in the tests). A smooth ball of clay (a logistic ramp whose
//! 10–90 % width is 1.1 to 1.4 knot spans of the coarsest axis) is fitted with a largest
//! error below 0.06 in density and an RMS error below 0.015 at the samples, and within 1.25
//! times that between them; a sharper ramp than the knot spacing can carry rings (0.2 for a
//! ramp of 0.6 spans). Choose the control count from the finest detail to keep.
//!
//! ## NURBS
//!
//! `F = Σ B w f / W` is not linear-separable in `f` when the weights differ. The fit solves
//! instead for the homogeneous values `h = w·f` with `Σ B h ≈ d·W` at the samples (separable,
//! `W` being the weights' own spline) and sets `f = h / w`. That minimises `Σ W² (F − d)²`,
//! the error weighted by the squared denominator: exactly the least-squares fit when the
//! weights are equal, and within a factor `(w_max / w_min)²` of it otherwise.

use rayon::prelude::*;

use crate::math::Vec3;

use super::knots::KnotVector;
use super::tensor::{transform_all, Rows};
use super::volume::{SplineVolume, Uvw};
use super::{SplineError, AXES};

/// Samples per knot span per axis when none is asked for.
pub const DEFAULT_SAMPLES_PER_SPAN: usize = 3;
/// The most samples per knot span per axis.
pub const MAX_SAMPLES_PER_SPAN: usize = 16;

/// The parameters a fit samples, per axis; the samples are their full tensor grid, index
/// `a + S_u·(b + S_v·c)`.
#[derive(Clone, Debug, PartialEq)]
pub struct FitSamples {
    params: [Vec<f64>; 3],
}

/// How well a fit matches its samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitReport {
    /// The largest `|F − d|` over the samples.
    pub max_error: f64,
    /// The root mean square of `F − d` over the samples.
    pub rms_error: f64,
    /// The number of samples.
    pub samples: usize,
}

impl FitSamples {
    /// The sample parameters along axis 0 (u), 1 (v) or 2 (w).
    pub fn params(&self, axis: usize) -> &[f64] {
        &self.params[axis.min(2)]
    }

    /// The number of samples per axis.
    pub fn counts(&self) -> [usize; 3] {
        [self.params[0].len(), self.params[1].len(), self.params[2].len()]
    }

    /// The number of samples.
    pub fn len(&self) -> usize {
        self.counts().iter().product()
    }

    /// Whether there are no samples (never, for samples made by a volume).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The parameters of sample `(a, b, c)`.
    pub fn uvw(&self, a: usize, b: usize, c: usize) -> Uvw {
        Uvw::new(self.params[0][a], self.params[1][b], self.params[2][c])
    }

    fn axis_params(knots: &KnotVector, per_span: usize) -> Vec<f64> {
        let breaks = knots.span_breaks();
        let spans = breaks.len() - 1;
        let s = per_span.max(knots.count().div_ceil(spans));
        breaks
            .windows(2)
            .flat_map(|w| (0..s).map(move |j| w[0] + (w[1] - w[0]) * (j as f64 + 0.5) / s as f64))
            .collect()
    }
}

/// Factors the symmetric positive definite `n × n` matrix `a` (row-major) in place into its
/// lower Cholesky factor; `Err(row)` where a pivot is not clearly positive.
fn cholesky(a: &mut [f64], n: usize) -> Result<(), usize> {
    let largest = (0..n).map(|i| a[i * n + i]).fold(0.0, f64::max);
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d.is_nan() || d <= 1e-13 * largest {
            return Err(j);
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    Ok(())
}

/// Solves `L Lᵀ x = b` in place.
fn cholesky_solve(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[k * n + i] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
}

/// `B⁺ = (BᵀB)⁻¹ Bᵀ` for the basis table `b` of an axis with `n` controls, as dense rows
/// (`n × S`).
fn pseudo_inverse(b: &Rows, n: usize, axis: usize) -> Result<Rows, SplineError> {
    let samples = b.len();
    // The transposed basis matrix, dense n × S.
    let mut bt = vec![0.0; n * samples];
    for r in 0..samples {
        let first = b.first[r];
        for t in 0..b.width {
            bt[(first + t) * samples + r] = b.coeffs[r * b.width + t];
        }
    }
    let mut normal = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..samples).map(|r| bt[i * samples + r] * bt[j * samples + r]).sum();
            normal[i * n + j] = s;
            normal[j * n + i] = s;
        }
    }
    cholesky(&mut normal, n).map_err(|row| SplineError::Singular { axis: AXES[axis], row })?;
    // Solve for each column of Bᵀ; write the result transposed into the row-major n × S.
    let mut out = vec![0.0; n * samples];
    let mut column = vec![0.0; n];
    for r in 0..samples {
        for i in 0..n {
            column[i] = bt[i * samples + r];
        }
        cholesky_solve(&normal, n, &mut column);
        for i in 0..n {
            out[i * samples + r] = column[i];
        }
    }
    Ok(Rows::dense(n, samples, out))
}

impl SplineVolume {
    /// The fit's sample parameters with `samples_per_span` (1..=16) samples per knot span
    /// per axis (see the module documentation).
    pub fn fit_samples(&self, samples_per_span: usize) -> Result<FitSamples, SplineError> {
        if !(1..=MAX_SAMPLES_PER_SPAN).contains(&samples_per_span) {
            return Err(SplineError::SamplesPerSpan { value: samples_per_span });
        }
        Ok(FitSamples { params: [0, 1, 2].map(|a| FitSamples::axis_params(self.knots(a), samples_per_span)) })
    }

    /// Fits the control values to `values`, the densities at `samples` (index
    /// `a + S_u·(b + S_v·c)`), in the least-squares sense (HQ eq. 13, separated per axis),
    /// and reports the error at the samples. On an error the values are unchanged.
    pub fn fit_values(&mut self, samples: &FitSamples, values: &[f64]) -> Result<FitReport, SplineError> {
        let sdims = samples.counts();
        if values.len() != samples.len() {
            return Err(SplineError::Length {
                what: "the fit's values",
                expected: samples.len(),
                given: values.len(),
            });
        }
        if let Some(&bad) = values.iter().find(|v| !v.is_finite()) {
            return Err(SplineError::NotFinite { what: "a fit sample", value: bad });
        }
        if samples.is_empty() {
            return Err(SplineError::Length { what: "the fit's samples", expected: 1, given: 0 });
        }
        let counts = self.counts();
        let tables: [Rows; 3] = std::array::from_fn(|a| Rows::basis(self.knots(a), samples.params(a)));
        let mut inverses = Vec::with_capacity(3);
        for a in 0..3 {
            inverses.push(pseudo_inverse(&tables[a], counts[a], a)?);
        }
        let weights: Vec<f64> = self.controls().iter().map(|c| c.weight).collect();
        let rational = !self.has_uniform_weights();
        let tables_ref = [&tables[0], &tables[1], &tables[2]];
        // Rational: fit h = w·f to d·W (see the module documentation).
        let denominators = rational.then(|| transform_all(&weights, counts, tables_ref).0);
        let target: Vec<f64> = match &denominators {
            Some(w) => values.iter().zip(w).map(|(d, w)| d * w).collect(),
            None => values.to_vec(),
        };
        let (coeffs, cdims) = transform_all(&target, sdims, [&inverses[0], &inverses[1], &inverses[2]]);
        debug_assert_eq!(cdims, counts);
        let fitted: Vec<f64> =
            if rational { coeffs.iter().zip(&weights).map(|(h, w)| h / w).collect() } else { coeffs };
        self.set_values(&fitted)?;

        // The error at the samples, from the same separable evaluation.
        let homogeneous: Vec<f64> = fitted.iter().zip(&weights).map(|(f, w)| f * w).collect();
        let numerators = transform_all(if rational { &homogeneous } else { &fitted }, counts, tables_ref).0;
        let (mut max_error, mut sum_sq) = (0.0f64, 0.0f64);
        for (i, (&d, &num)) in values.iter().zip(&numerators).enumerate() {
            let f = match &denominators {
                Some(w) => num / w[i],
                None => num,
            };
            let e = (f - d).abs();
            max_error = max_error.max(e);
            sum_sq += e * e;
        }
        Ok(FitReport { max_error, rms_error: (sum_sq / values.len() as f64).sqrt(), samples: values.len() })
    }

    /// Fits the control values to a density field (world point → density), sampled at the
    /// lattice's current image of [`Self::fit_samples`]`(samples_per_span)`; the field is
    /// called from several threads.
    pub fn fit_field<F>(&mut self, field: F, samples_per_span: usize) -> Result<FitReport, SplineError>
    where
        F: Fn(Vec3) -> f32 + Sync,
    {
        let samples = self.fit_samples(samples_per_span)?;
        let [su, sv, _] = samples.counts();
        let at_rest = self.is_at_rest();
        let this = &*self;
        let values: Vec<f64> = (0..samples.len())
            .into_par_iter()
            .map(|index| {
                let uvw = samples.uvw(index % su, (index / su) % sv, index / (su * sv));
                let x = if at_rest { this.rest_point(uvw) } else { this.position(uvw) };
                field(x) as f64
            })
            .collect();
        self.fit_values(&samples, &values)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::spline::volume::tests::{unit_box, Rng};
    use crate::spline::{Clipping, KnotStyle, SplineKind};

    /// A polynomial of degree `deg[a]` along each axis, in the parameters.
    fn polynomial(deg: [usize; 3]) -> impl Fn(Uvw) -> f64 {
        move |p: Uvw| {
            let [u, v, w] = p.0;
            let pu: f64 = (0..=deg[0]).map(|e| (0.3 + 0.1 * e as f64) * u.powi(e as i32)).sum();
            let pv: f64 = (0..=deg[1]).map(|e| (-0.7 + 0.4 * e as f64) * v.powi(e as i32)).sum();
            let pw: f64 = (0..=deg[2]).map(|e| (0.2 - 0.3 * e as f64) * w.powi(e as i32)).sum();
            pu * pv + pw * u - 0.5 * pw
        }
    }

    #[test]
    fn a_polynomial_of_degree_below_the_order_is_reproduced() {
        let b = unit_box();
        let knots = [
            KnotVector::new(6, 3, vec![0.0, 0.0, 0.0, 0.1, 0.5, 0.5, 2.0, 2.0, 2.0]).unwrap(),
            KnotVector::new(5, 4, vec![-1.0, -0.5, 0.0, 0.2, 0.3, 1.5, 1.6, 4.0, 4.0]).unwrap(),
            KnotVector::uniform(7, 2).unwrap(),
        ];
        let volumes = vec![
            SplineVolume::bezier(b, [5, 3, 6]).unwrap(),
            SplineVolume::bspline(b, [8, 6, 7], [4, 3, 2], KnotStyle::Uniform).unwrap(),
            SplineVolume::bspline(b, [16, 16, 16], [4, 4, 4], KnotStyle::Clamped).unwrap(),
            SplineVolume::nurbs(b, [6, 6, 6], [3, 3, 3], KnotStyle::Clamped).unwrap(),
            SplineVolume::over_box(b, SplineKind::BSpline, knots).unwrap(),
        ];
        let mut rng = Rng(47);
        for mut vol in volumes {
            let orders = vol.orders();
            let poly = polynomial([orders[0] - 1, orders[1] - 1, orders[2] - 1]);
            for per_span in [1, 2, 4] {
                let samples = vol.fit_samples(per_span).unwrap();
                let [su, sv, sw] = samples.counts();
                let mut values = Vec::with_capacity(samples.len());
                for c in 0..sw {
                    for b in 0..sv {
                        for a in 0..su {
                            values.push(poly(samples.uvw(a, b, c)));
                        }
                    }
                }
                let report = vol.fit_values(&samples, &values).unwrap();
                assert!(report.max_error < 1e-9, "{:?} {per_span}: {report:?}", vol.kind());
                for _ in 0..100 {
                    let uvw = rng.uvw(0.0, 1.0);
                    let err = (vol.value(uvw) - poly(uvw)).abs();
                    assert!(err < 1e-9, "{:?}: error {err} between samples", vol.kind());
                }
            }
        }
    }

    /// A smooth ball of clay: density 1 inside, 0 outside, a logistic ramp of width about
    /// 4·`ramp_m` across the surface at `radius_m`.
    pub(crate) fn ball(centre: Vec3, radius_m: f32, ramp_m: f32) -> impl Fn(Vec3) -> f32 + Sync {
        move |x: Vec3| 1.0 / (1.0 + (((x - centre).length() - radius_m) / ramp_m).exp())
    }

    #[test]
    fn a_smooth_ball_is_fitted_and_reproduced_through_the_mapping() {
        let b = unit_box();
        // The ball's ramp (10–90 %, 4.4 × `ramp`) spans about 1.1 knot spans of the coarsest
        // axis for 8³, 1.4 for 16³.
        for (counts, order, ramp, tolerance) in [(8, 4, 0.02, 0.06), (16, 4, 0.01, 0.05), (16, 3, 0.01, 0.05)]
        {
            let field = ball(b.centre(), 0.08, ramp);
            let mut vol = SplineVolume::bspline(b, [counts; 3], [order; 3], KnotStyle::Clamped).unwrap();
            let report = vol.fit_field(&field, DEFAULT_SAMPLES_PER_SPAN).unwrap();
            eprintln!("ball fit, ramp {ramp} m, {counts}³ controls of order {order}: {report:?}");
            assert!(report.max_error < tolerance, "{report:?}");
            assert!(report.rms_error < tolerance / 4.0, "{report:?}");
            // Between the samples, through the (identity) space mapping and the clipping's
            // surface: the untouched lattice reproduces the field within the tolerance.
            let clip = Clipping::with_band(0.5, 0.02).unwrap();
            let mut rng = Rng(53);
            let mut worst = 0.0f64;
            for _ in 0..500 {
                let x = vol.rest_point(rng.uvw(0.2, 0.8));
                let raw = vol.value(vol.inverse_map(x).uvw);
                let err = (raw - field(x) as f64).abs();
                worst = worst.max(err);
                assert!(err < tolerance * 1.25, "at {x}: {raw} vs {}", field(x));
                // Clipping keeps the fitted function's surface.
                let d = vol.mapped_density(x, &clip) as f64;
                if (raw - 0.5).abs() > 1e-6 {
                    assert_eq!(d > 0.5, raw > 0.5, "the surface moved at {x}: {d} vs {raw}");
                }
            }
            eprintln!("  worst error between samples {worst:.4}");
        }
    }

    #[test]
    fn a_fit_on_a_deformed_lattice_bakes_the_field_into_it() {
        // Fitting samples the field at the lattice's current image: afterwards the mapped
        // function reproduces the field in the world, through the deformation.
        let b = unit_box();
        let field = ball(b.centre() + Vec3::new(0.02, 0.0, 0.0), 0.07, 0.02);
        let mut vol = SplineVolume::bspline(b, [12; 3], [4; 3], KnotStyle::Clamped).unwrap();
        let (c, size) = (b.centre(), b.size());
        vol.update_positions(|_, cp| {
            let t = (cp.rest_m.y - b.min.y) / size.y;
            c + crate::math::Quat::from_rotation_y(0.8 * t) * (cp.rest_m - c)
        })
        .unwrap();
        let report = vol.fit_field(&field, 3).unwrap();
        assert!(report.max_error < 0.05, "{report:?}");
        let mut rng = Rng(67);
        for _ in 0..300 {
            let x = vol.position(rng.uvw(0.15, 0.85));
            let map = vol.inverse_map(x);
            assert!(map.inside);
            let err = (vol.value(map.uvw) - field(x) as f64).abs();
            assert!(err < 0.06, "at {x}: {err}");
        }
    }

    #[test]
    fn a_fit_of_sixteen_cubed_controls_is_quick() {
        let b = unit_box();
        let field = ball(b.centre(), 0.08, 0.01);
        for counts in [8, 16] {
            let mut vol = SplineVolume::bspline(b, [counts; 3], [4; 3], KnotStyle::Uniform).unwrap();
            let samples = vol.fit_samples(DEFAULT_SAMPLES_PER_SPAN).unwrap();
            let values: Vec<f64> = (0..samples.len())
                .map(|i| {
                    let [su, sv, _] = samples.counts();
                    field(vol.rest_point(samples.uvw(i % su, (i / su) % sv, i / (su * sv)))) as f64
                })
                .collect();
            let start = std::time::Instant::now();
            let report = vol.fit_values(&samples, &values).unwrap();
            let solve = start.elapsed();
            let start = std::time::Instant::now();
            vol.fit_field(&field, DEFAULT_SAMPLES_PER_SPAN).unwrap();
            let with_sampling = start.elapsed();
            eprintln!(
                "fit {counts}³ controls, {} samples: solve {:.2} ms, with field sampling {:.2} ms \
                 (max error {:.4})",
                samples.len(),
                solve.as_secs_f64() * 1e3,
                with_sampling.as_secs_f64() * 1e3,
                report.max_error
            );
        }
    }

    #[test]
    fn a_weighted_fit_is_exact_for_equal_weights_and_close_otherwise() {
        let b = unit_box();
        let field = ball(b.centre(), 0.08, 0.015);
        let mut spline = SplineVolume::bspline(b, [8; 3], [3; 3], KnotStyle::Clamped).unwrap();
        let mut nurbs = SplineVolume::nurbs(b, [8; 3], [3; 3], KnotStyle::Clamped).unwrap();
        let plain = spline.fit_field(&field, 3).unwrap();
        nurbs.update_values(|_, _| 0.0).unwrap();
        for k in 0..8 {
            for j in 0..8 {
                for i in 0..8 {
                    nurbs.set_weight(i, j, k, 2.0).unwrap();
                }
            }
        }
        let equal = nurbs.fit_field(&field, 3).unwrap();
        assert!((equal.max_error - plain.max_error).abs() < 1e-12);
        nurbs.set_weight(3, 4, 4, 6.0).unwrap();
        nurbs.set_weight(0, 0, 0, 0.5).unwrap();
        let weighted = nurbs.fit_field(&field, 3).unwrap();
        assert!(weighted.rms_error < plain.rms_error * 2.0, "{weighted:?} vs {plain:?}");
    }

    #[test]
    fn bad_fit_requests_are_refused() {
        let mut vol = SplineVolume::bspline(unit_box(), [5; 3], [3; 3], KnotStyle::Clamped).unwrap();
        assert!(matches!(vol.fit_samples(0), Err(SplineError::SamplesPerSpan { value: 0 })));
        assert!(matches!(vol.fit_samples(17), Err(SplineError::SamplesPerSpan { .. })));
        let samples = vol.fit_samples(2).unwrap();
        assert_eq!(samples.counts(), [6, 6, 6]);
        assert!(matches!(vol.fit_values(&samples, &[0.0; 5]), Err(SplineError::Length { .. })));
        let mut values = vec![0.5; samples.len()];
        values[3] = f64::NAN;
        assert!(matches!(vol.fit_values(&samples, &values), Err(SplineError::NotFinite { .. })));
        assert!(vol.controls().iter().all(|c| c.value == 0.0), "a refused fit changes nothing");
        assert!(vol.fit_field(|_| f32::NAN, 2).is_err());
        // A Bézier axis gets at least as many samples as controls.
        let bez = SplineVolume::bezier(unit_box(), [7, 2, 3]).unwrap();
        assert_eq!(bez.fit_samples(1).unwrap().counts(), [7, 2, 3]);
    }

    #[test]
    fn cholesky_solves_a_small_system() {
        let mut a = vec![4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0];
        let orig = a.clone();
        cholesky(&mut a, 3).unwrap();
        let mut x = vec![1.0, -2.0, 0.5];
        let rhs = x.clone();
        cholesky_solve(&a, 3, &mut x);
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| orig[i * 3 + j] * x[j]).sum();
            assert!((r - rhs[i]).abs() < 1e-12);
        }
        let mut singular = vec![1.0, 1.0, 1.0, 1.0];
        assert_eq!(cholesky(&mut singular, 2), Err(1));
    }
}
