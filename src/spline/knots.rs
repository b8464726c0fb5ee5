//! Knot vectors and the Cox–de Boor B-spline basis (HQ §3.1, eq. 2; ESM §4.4 for Bézier as
//! the full-order case).
//!
//! A knot vector `t_0 ≤ t_1 ≤ … ≤ t_{n+k−1}` for `n` control points of order `k` (degree
//! `k − 1`) defines `n` basis functions `N_i`, each a piecewise polynomial non-zero on
//! `[t_i, t_{i+k})` only. The spline's domain is `[t_{k−1}, t_n]`, where the `N_i` sum to 1;
//! every public parameter here is normalised so that the domain is `[0, 1]`.
//!
//! ```text
//!   uniform, n = 6, k = 3          t: 0   1   2   3   4   5   6   7   8
//!                                          │←─── domain ───→│
//!                                          t_2            t_6
//!   clamped, n = 6, k = 3          t: 0 0 0  ¼  ½  ¾  1 1 1      (domain [0, 1], ends
//!                                                                 interpolate end controls)
//!   Bézier, n = k = 4              t: 0 0 0 0  1 1 1 1            (one span: Bernstein)
//! ```
//!
//! At a parameter only the `k` functions `N_{s−k+1} … N_s` of its span `s` are non-zero;
//! [`KnotVector::basis`] returns exactly those, with the index of the first, in a fixed-size
//! array: no allocation. Values are computed by the triangular Cox–de Boor recurrence
//!
//! ```text
//!   N_{i,1}(t) = 1 on [t_i, t_{i+1}), else 0
//!   N_{i,k}(t) = (t − t_i) / (t_{i+k−1} − t_i) · N_{i,k−1}(t)
//!              + (t_{i+k} − t) / (t_{i+k} − t_{i+1}) · N_{i+1,k−1}(t)
//! ```
//!
//! and derivatives from the order `k − 1` values,
//! `N′_{i,k} = (k−1) · (N_{i,k−1} / (t_{i+k−1} − t_i) − N_{i+1,k−1} / (t_{i+k} − t_{i+1}))`.
//! Outside the domain the first and last spans' polynomials are extended (the spline's
//! natural continuation, whose "ghosts" ESM §3.1 clips away); partition of unity holds there
//! too.

use super::{SplineError, AXES};

/// The smallest order (2: piecewise linear). Order 1 has no linear precision, so it could not
/// map the rest lattice onto its box.
pub const MIN_ORDER: usize = 2;
/// The largest order (16: a Bézier volume of 16 control points per axis).
pub const MAX_ORDER: usize = 16;
/// The fewest control points per axis.
pub const MIN_CONTROLS: usize = 2;
/// The most control points per axis.
pub const MAX_CONTROLS: usize = 16;

/// How a knot vector is spaced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum KnotStyle {
    /// Equally spaced knots `0, 1, …, n + k − 1` (the "periodic" style): every span alike, the
    /// volume does not reach its end control points.
    Uniform,
    /// `k` equal knots at each end and equally spaced interior knots (open, clamped): the volume
    /// interpolates its corner control points. With `k = n` this is the Bézier case.
    Clamped,
}

/// A validated knot vector with its order and control count.
#[derive(Clone, Debug, PartialEq)]
pub struct KnotVector {
    knots: Vec<f64>,
    order: usize,
    count: usize,
    /// The domain, `[t_{k−1}, t_n]`.
    lo: f64,
    hi: f64,
    /// The first and last non-empty spans of the domain.
    first_span: usize,
    last_span: usize,
}

/// The non-zero basis functions at one parameter: `values[r]` is `N_{first + r}`, for
/// `r < order`; entries past the order are 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Basis {
    /// Index of the first non-zero basis function (span − order + 1).
    pub first: usize,
    /// The order, the number of meaningful entries.
    pub order: usize,
    /// The values.
    pub values: [f64; MAX_ORDER],
}

/// The non-zero basis functions at one parameter and their first derivatives with respect to
/// the normalised parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BasisDerivatives {
    /// Index of the first non-zero basis function.
    pub first: usize,
    /// The order, the number of meaningful entries.
    pub order: usize,
    /// `N_{first + r}(u)`.
    pub values: [f64; MAX_ORDER],
    /// `dN_{first + r}/du`, `u` normalised to the domain [0, 1].
    pub derivatives: [f64; MAX_ORDER],
}

impl Basis {
    /// The meaningful values, `N_first … N_{first+order−1}`.
    pub fn values(&self) -> &[f64] {
        &self.values[..self.order]
    }

    /// The knot span `s` (`t_s ≤ t < t_{s+1}`): `first + order − 1`.
    pub fn span(&self) -> usize {
        self.first + self.order - 1
    }
}

impl BasisDerivatives {
    /// The knot span `s`: `first + order − 1`.
    pub fn span(&self) -> usize {
        self.first + self.order - 1
    }

    /// The meaningful values.
    pub fn values(&self) -> &[f64] {
        &self.values[..self.order]
    }

    /// The meaningful derivatives.
    pub fn derivatives(&self) -> &[f64] {
        &self.derivatives[..self.order]
    }
}

/// Checks a control count and an order for one axis.
pub(crate) fn check_count_and_order(axis: usize, count: usize, order: usize) -> Result<(), SplineError> {
    if !(MIN_CONTROLS..=MAX_CONTROLS).contains(&count) {
        return Err(SplineError::ControlCount { axis: AXES[axis], count });
    }
    if !(MIN_ORDER..=MAX_ORDER.min(count)).contains(&order) {
        return Err(SplineError::Order { axis: AXES[axis], order, count });
    }
    Ok(())
}

impl KnotVector {
    /// Uniform knots `0, 1, …, count + order − 1` for `count` control points of `order`.
    pub fn uniform(count: usize, order: usize) -> Result<Self, SplineError> {
        Self::styled(KnotStyle::Uniform, count, order, 0)
    }

    /// Clamped (open) uniform knots on [0, 1]: `order` zeros, `count − order` equally spaced
    /// interior knots, `order` ones.
    pub fn clamped(count: usize, order: usize) -> Result<Self, SplineError> {
        Self::styled(KnotStyle::Clamped, count, order, 0)
    }

    /// The Bézier basis of `count` control points: clamped knots of order `count`, whose
    /// basis functions are the Bernstein polynomials of degree `count − 1`.
    pub fn bezier(count: usize) -> Result<Self, SplineError> {
        let order = count.clamp(MIN_ORDER, MAX_ORDER);
        check_count_and_order(0, count, order)?;
        Self::clamped(count, order)
    }

    /// Knots of the given style.
    pub fn with_style(style: KnotStyle, count: usize, order: usize) -> Result<Self, SplineError> {
        Self::styled(style, count, order, 0)
    }

    /// As [`Self::with_style`], naming `axis` (0, 1, 2 for u, v, w) in errors.
    pub(crate) fn styled(
        style: KnotStyle,
        count: usize,
        order: usize,
        axis: usize,
    ) -> Result<Self, SplineError> {
        check_count_and_order(axis, count, order)?;
        let knots = match style {
            KnotStyle::Uniform => (0..count + order).map(|i| i as f64).collect(),
            KnotStyle::Clamped => {
                let spans = (count - order + 1) as f64;
                (0..count + order)
                    .map(|i| {
                        if i < order {
                            0.0
                        } else if i >= count {
                            1.0
                        } else {
                            (i + 1 - order) as f64 / spans
                        }
                    })
                    .collect()
            }
        };
        Self::validated(knots, count, order, axis)
    }

    /// A user-given (possibly non-uniform) knot vector for `count` control points of `order`.
    ///
    /// Refused unless: the count is 2..=16 and the order 2..=min(count, 16); there are
    /// `count + order` finite, non-decreasing knots; the domain `[t_{k−1}, t_n]` is not empty;
    /// no knot strictly inside the domain repeats `order` times or more (the spline would be
    /// discontinuous there) and none repeats more than `order` times (a basis function would
    /// vanish).
    pub fn new(count: usize, order: usize, knots: Vec<f64>) -> Result<Self, SplineError> {
        Self::for_axis(count, order, knots, 0)
    }

    /// As [`Self::new`], naming `axis` in errors.
    pub(crate) fn for_axis(
        count: usize,
        order: usize,
        knots: Vec<f64>,
        axis: usize,
    ) -> Result<Self, SplineError> {
        check_count_and_order(axis, count, order)?;
        Self::validated(knots, count, order, axis)
    }

    fn validated(knots: Vec<f64>, count: usize, order: usize, axis: usize) -> Result<Self, SplineError> {
        let name = AXES[axis];
        if knots.len() != count + order {
            return Err(SplineError::KnotCount {
                axis: name,
                count,
                order,
                expected: count + order,
                given: knots.len(),
            });
        }
        for (index, &value) in knots.iter().enumerate() {
            if !value.is_finite() || (index > 0 && value < knots[index - 1]) {
                return Err(SplineError::KnotOrder { axis: name, index, value });
            }
        }
        let (lo, hi) = (knots[order - 1], knots[count]);
        if lo >= hi {
            return Err(SplineError::EmptyDomain { axis: name, first: order - 1, last: count, lo, hi });
        }
        let mut start = 0;
        while start < knots.len() {
            let value = knots[start];
            let end = knots[start..].iter().position(|&t| t != value).map_or(knots.len(), |p| start + p);
            let multiplicity = end - start;
            let allowed = if value > lo && value < hi { order - 1 } else { order };
            if multiplicity > allowed {
                return Err(SplineError::KnotMultiplicity { axis: name, value, multiplicity, allowed });
            }
            start = end;
        }
        let first_span = (order - 1..count).find(|&s| knots[s] < knots[s + 1]).unwrap_or(order - 1);
        let last_span = (order - 1..count).rev().find(|&s| knots[s] < knots[s + 1]).unwrap_or(count - 1);
        Ok(Self { knots, order, count, lo, hi, first_span, last_span })
    }

    /// The knots, unnormalised, as given or generated.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The order `k` (degree + 1).
    pub fn order(&self) -> usize {
        self.order
    }

    /// The number of control points `n`.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The domain `[t_{k−1}, t_n]` in the knots' own units; the normalised parameter 0 is its
    /// start and 1 its end.
    pub fn domain(&self) -> (f64, f64) {
        (self.lo, self.hi)
    }

    /// Whether this is the Bézier basis: order equal to the count, clamped.
    pub fn is_bezier(&self) -> bool {
        self.order == self.count && self.is_clamped()
    }

    /// Whether the first and last `order` knots lie on the domain's ends: the end controls
    /// alone shape the ends (the curve starts and ends at them).
    pub fn is_clamped(&self) -> bool {
        self.knots[..self.order].iter().all(|&t| t == self.lo)
            && self.knots[self.count..].iter().all(|&t| t == self.hi)
    }

    /// The normalised parameters of the non-empty knot spans' ends inside the domain, in
    /// order: `[0, …, 1]`, one more than the number of spans.
    pub fn span_breaks(&self) -> Vec<f64> {
        let mut out = vec![0.0];
        for s in self.first_span..=self.last_span {
            if self.knots[s] < self.knots[s + 1] {
                out.push(self.normalise(self.knots[s + 1]));
            }
        }
        out
    }

    /// A knot-space value as a normalised parameter.
    fn normalise(&self, t: f64) -> f64 {
        (t - self.lo) / (self.hi - self.lo)
    }

    /// The Greville abscissa of control `i`, normalised: the mean of knots `t_{i+1} …
    /// t_{i+k−1}`. Control values placed at `a + b·g_i` give the spline `a + b·u` exactly
    /// (linear precision); for uniform knots the first and last abscissae lie outside [0, 1].
    pub fn greville(&self, i: usize) -> f64 {
        let i = i.min(self.count - 1);
        let sum: f64 = self.knots[i + 1..i + self.order].iter().sum();
        self.normalise(sum / (self.order - 1) as f64)
    }

    /// The normalised parameter interval on which basis function `i` can be non-zero:
    /// `[t_i, t_{i+k}]`, extended to −∞ (+∞) when `N_i` is non-zero on the first (last) span,
    /// whose polynomial continues outside the domain.
    pub fn support(&self, i: usize) -> (f64, f64) {
        let i = i.min(self.count - 1);
        let p = self.order - 1;
        let lo = if i <= self.first_span { f64::NEG_INFINITY } else { self.normalise(self.knots[i]) };
        let hi =
            if i + p >= self.last_span { f64::INFINITY } else { self.normalise(self.knots[i + self.order]) };
        (lo, hi)
    }

    /// The span `s` holding knot-space parameter `t`: `t_s ≤ t < t_{s+1}` with a non-empty
    /// span, the first span below the domain and the last one at and above its end.
    #[inline]
    fn span(&self, t: f64) -> usize {
        let (mut lo, mut hi) = (self.first_span, self.last_span);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if self.knots[mid] <= t {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        lo
    }

    /// Cox–de Boor on span `span` at knot-space `t` (Piegl and Tiller's algorithm A2.2): the
    /// `order` values into `n`; when `lower` is given, the `order − 1` values of the order
    /// below into it first.
    /// Arrays of `N` entries, at least the order.
    #[inline]
    fn cox_de_boor<const N: usize>(
        &self,
        span: usize,
        t: f64,
        n: &mut [f64; N],
        mut lower: Option<&mut [f64; N]>,
    ) {
        debug_assert!(self.order <= N);
        let p = self.order - 1;
        let u = &self.knots;
        let mut left = [0.0; N];
        let mut right = [0.0; N];
        n[0] = 1.0;
        for j in 1..=p {
            if j == p {
                if let Some(lower) = lower.as_deref_mut() {
                    lower[..p].copy_from_slice(&n[..p]);
                }
            }
            left[j] = t - u[span + 1 - j];
            right[j] = u[span + j] - t;
            let mut saved = 0.0;
            for r in 0..j {
                // The denominator is the knot interval t_{span+r+1} − t_{span+1−j+r}, which
                // contains the non-empty span: never zero.
                let temp = n[r] / (right[r + 1] + left[j - r]);
                n[r] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            n[j] = saved;
        }
    }

    /// The `order` non-zero basis functions at normalised parameter `u` (extended outside
    /// [0, 1]). `u` must be finite.
    #[inline]
    pub fn basis(&self, u: f64) -> Basis {
        let t = self.lo + u * (self.hi - self.lo);
        let span = self.span(t);
        let mut values = [0.0; MAX_ORDER];
        self.cox_de_boor(span, t, &mut values, None);
        Basis { first: span + 1 - self.order, order: self.order, values }
    }

    /// The non-zero basis functions at `u` and their derivatives with respect to `u`.
    #[inline]
    pub fn basis_with_derivatives(&self, u: f64) -> BasisDerivatives {
        let (first, values, derivatives) = self.basis_sized::<MAX_ORDER, true>(u);
        BasisDerivatives { first, order: self.order, values, derivatives }
    }

    /// The index of the first non-zero basis function at `u`, the functions, and with `D` their
    /// derivatives with respect to `u` (else zeros), in arrays of `N` entries, at least the
    /// order: no wider than a caller of low orders needs.
    #[inline]
    pub(crate) fn basis_sized<const N: usize, const D: bool>(&self, u: f64) -> (usize, [f64; N], [f64; N]) {
        let scale = self.hi - self.lo;
        let t = self.lo + u * scale;
        let span = self.span(t);
        let p = self.order - 1;
        let mut values = [0.0; N];
        let mut derivatives = [0.0; N];
        if !D {
            self.cox_de_boor(span, t, &mut values, None);
            return (span + 1 - self.order, values, derivatives);
        }
        let mut lower = [0.0; N];
        self.cox_de_boor(span, t, &mut values, Some(&mut lower));
        let k = &self.knots;
        let degree = p as f64 * scale;
        for (r, d) in derivatives.iter_mut().enumerate().take(self.order) {
            // N_{span−p+r} at order k draws on N_{span−p+r} (lower[r − 1]) and
            // N_{span−p+r+1} (lower[r]) at order k − 1.
            let mut acc = 0.0;
            if r >= 1 {
                acc += lower[r - 1] / (k[span + r] - k[span + r - p]);
            }
            if r < p {
                acc -= lower[r] / (k[span + r + 1] - k[span + r + 1 - p]);
            }
            *d = degree * acc;
        }
        (span + 1 - self.order, values, derivatives)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The textbook recursion over all `n` functions, as the reference.
    fn reference(knots: &[f64], order: usize, i: usize, t: f64, last_span: usize) -> f64 {
        if order == 1 {
            let (a, b) = (knots[i], knots[i + 1]);
            // The half-open rule, closed at the domain's end so that t = end is covered.
            // (Only where no span follows: with uniform knots the next span's right value is the
            // continuous one.)
            let closed = i == last_span && t == b && knots[i + 1..].iter().all(|&c| c == b);
            return if (a <= t && t < b) || closed { 1.0 } else { 0.0 };
        }
        let mut v = 0.0;
        let d1 = knots[i + order - 1] - knots[i];
        if d1 > 0.0 {
            v += (t - knots[i]) / d1 * reference(knots, order - 1, i, t, last_span);
        }
        let d2 = knots[i + order] - knots[i + 1];
        if d2 > 0.0 {
            v += (knots[i + order] - t) / d2 * reference(knots, order - 1, i + 1, t, last_span);
        }
        v
    }

    fn binomial(n: usize, k: usize) -> f64 {
        (0..k).fold(1.0, |acc, j| acc * (n - j) as f64 / (j + 1) as f64)
    }

    fn all_vectors() -> Vec<KnotVector> {
        let mut out = Vec::new();
        for count in [2, 3, 4, 5, 7, 16] {
            for order in 2..=count.min(6) {
                out.push(KnotVector::uniform(count, order).unwrap());
                out.push(KnotVector::clamped(count, order).unwrap());
            }
            out.push(KnotVector::bezier(count).unwrap());
        }
        out.push(KnotVector::new(6, 3, vec![0.0, 0.0, 0.0, 0.1, 0.5, 0.5, 2.0, 2.0, 2.0]).unwrap());
        out.push(KnotVector::new(5, 4, vec![-1.0, -0.5, 0.0, 0.2, 0.3, 1.5, 1.6, 4.0, 4.0]).unwrap());
        out
    }

    #[test]
    fn partition_of_unity_inside_and_outside_the_domain() {
        for kv in all_vectors() {
            for s in 0..=200 {
                let u = -0.5 + 2.0 * s as f64 / 200.0;
                let b = kv.basis(u);
                let sum: f64 = b.values().iter().sum();
                // Far outside, the continued polynomials grow and cancel: relative rounding.
                let magnitude: f64 = b.values().iter().map(|v| v.abs()).sum();
                assert!((sum - 1.0).abs() < 1e-13 * magnitude.max(1.0) * 100.0, "{kv:?} u={u} sum={sum}");
                if (0.0..=1.0).contains(&u) {
                    assert!(b.values().iter().all(|&v| v >= -1e-15), "negative basis in domain");
                }
                let d: f64 = kv.basis_with_derivatives(u).derivatives().iter().sum();
                assert!(d.abs() < 1e-9, "derivatives must sum to 0, got {d}");
            }
        }
    }

    #[test]
    fn basis_matches_the_full_recursion_with_the_right_span_index() {
        for kv in all_vectors() {
            for s in 0..=97 {
                let u = s as f64 / 97.0;
                let t = kv.lo + u * (kv.hi - kv.lo);
                let b = kv.basis(u);
                let s = b.span();
                assert!(
                    kv.knots[s] <= t && (t < kv.knots[s + 1] || s == kv.last_span),
                    "{kv:?} u={u} span {s}"
                );
                assert!(kv.knots[s] < kv.knots[s + 1], "an empty span");
                for i in 0..kv.count() {
                    let want = reference(&kv.knots, kv.order, i, t, kv.last_span);
                    let got =
                        if (b.first..b.first + b.order).contains(&i) { b.values[i - b.first] } else { 0.0 };
                    assert!((want - got).abs() < 1e-12, "{kv:?} u={u} i={i}: {got} vs {want}");
                }
                assert!(b.values[b.order..].iter().all(|&v| v == 0.0));
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for kv in all_vectors() {
            for s in 0..40 {
                // Stay off knots, where the derivative of a low order may jump.
                let u = -0.2 + 1.4 * (s as f64 + 0.37) / 40.0;
                let h = 1e-6;
                let d = kv.basis_with_derivatives(u);
                let (bp, bm) = (kv.basis(u + h), kv.basis(u - h));
                if bp.first != d.first || bm.first != d.first {
                    continue;
                }
                for r in 0..d.order {
                    let fd = (bp.values[r] - bm.values[r]) / (2.0 * h);
                    let scale = 1.0 + d.derivatives[r].abs();
                    assert!((fd - d.derivatives[r]).abs() < 1e-5 * scale, "{kv:?} u={u} r={r}");
                    assert_eq!(d.values[r], kv.basis(u).values[r]);
                }
            }
        }
    }

    #[test]
    fn bezier_basis_is_bernstein() {
        for count in 2..=MAX_CONTROLS {
            let kv = KnotVector::bezier(count).unwrap();
            assert!(kv.is_bezier());
            let deg = count - 1;
            for s in 0..=50 {
                let u = s as f64 / 50.0;
                let b = kv.basis(u);
                assert_eq!(b.first, 0);
                for i in 0..count {
                    let bern = binomial(deg, i) * u.powi(i as i32) * (1.0 - u).powi((deg - i) as i32);
                    assert!((b.values[i] - bern).abs() < 1e-12, "n={count} i={i} u={u}");
                }
            }
        }
        assert!(!KnotVector::uniform(4, 4).unwrap().is_bezier());
        assert!(!KnotVector::clamped(5, 4).unwrap().is_bezier());
    }

    #[test]
    fn greville_abscissae_give_linear_precision() {
        for kv in all_vectors() {
            for s in 0..=30 {
                let u = -0.3 + 1.6 * s as f64 / 30.0;
                let b = kv.basis(u);
                let x: f64 = (0..b.order).map(|r| b.values[r] * kv.greville(b.first + r)).sum();
                assert!((x - u).abs() < 1e-12, "{kv:?} u={u} x={x}");
            }
        }
    }

    #[test]
    fn a_basis_function_vanishes_outside_its_support() {
        for kv in all_vectors() {
            for i in 0..kv.count() {
                let (a, b) = kv.support(i);
                for s in 0..=200 {
                    let u = -0.5 + 2.0 * s as f64 / 200.0;
                    let basis = kv.basis(u);
                    let inside = (basis.first..basis.first + basis.order).contains(&i);
                    if inside && basis.values[i - basis.first].abs() > 1e-14 {
                        assert!(u >= a - 1e-12 && u <= b + 1e-12, "{kv:?} i={i} u={u} support {a}..{b}");
                    }
                }
            }
        }
    }

    #[test]
    fn bad_knot_vectors_are_refused_with_a_message() {
        let e = KnotVector::uniform(17, 4).unwrap_err();
        assert_eq!(e.to_string(), "a lattice needs 2 to 16 control points per axis, not 17 (axis u)");
        assert!(matches!(KnotVector::uniform(1, 2), Err(SplineError::ControlCount { .. })));
        assert!(matches!(KnotVector::uniform(5, 1), Err(SplineError::Order { .. })));
        assert!(matches!(KnotVector::uniform(5, 6), Err(SplineError::Order { .. })));
        assert!(matches!(KnotVector::bezier(17), Err(SplineError::ControlCount { .. })));
        assert!(matches!(
            KnotVector::new(4, 2, vec![0.0, 1.0, 2.0]),
            Err(SplineError::KnotCount { expected: 6, given: 3, .. })
        ));
        let e = KnotVector::new(4, 2, vec![0.0, 1.0, 0.5, 2.0, 3.0, 4.0]).unwrap_err();
        assert!(matches!(e, SplineError::KnotOrder { index: 2, .. }), "{e}");
        assert!(matches!(
            KnotVector::new(4, 2, vec![0.0, 1.0, f64::NAN, 2.0, 3.0, 4.0]),
            Err(SplineError::KnotOrder { index: 2, .. })
        ));
        // An interior knot repeated `order` times breaks the spline apart.
        assert!(matches!(
            KnotVector::new(6, 3, vec![0.0, 0.0, 0.0, 0.5, 0.5, 0.5, 1.0, 1.0, 1.0]),
            Err(SplineError::KnotMultiplicity { multiplicity: 3, allowed: 2, .. })
        ));
        assert!(matches!(
            KnotVector::new(3, 2, vec![0.0, 0.0, 0.0, 1.0, 1.0]),
            Err(SplineError::KnotMultiplicity { .. }) | Err(SplineError::EmptyDomain { .. })
        ));
        assert!(matches!(
            KnotVector::new(2, 2, vec![0.0, 1.0, 1.0, 2.0]),
            Err(SplineError::EmptyDomain { .. })
        ));
    }

    #[test]
    fn span_breaks_list_the_non_empty_spans() {
        let kv = KnotVector::new(6, 3, vec![0.0, 0.0, 0.0, 0.1, 0.5, 0.5, 2.0, 2.0, 2.0]).unwrap();
        assert_eq!(kv.span_breaks(), vec![0.0, 0.05, 0.25, 1.0]);
        assert_eq!(KnotVector::uniform(6, 3).unwrap().span_breaks(), vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        assert_eq!(KnotVector::bezier(5).unwrap().span_breaks(), vec![0.0, 1.0]);
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig {
                cases: 200,
                rng_seed: proptest::test_runner::RngSeed::Fixed(71),
                ..ProptestConfig::default()
            })]
            #[test]
            fn any_knot_vector_is_refused_or_a_partition_of_unity(
                count in 0usize..18,
                order in 0usize..8,
                steps in proptest::collection::vec(prop_oneof![12 => 0.01f64..2.0, 3 => Just(0.0f64), 1 => -0.1f64..0.0], 26),
                short in any::<bool>(),
            ) {
                // Non-decreasing mostly (a decrease now and then), the right length mostly.
                let len = (count + order).saturating_sub(usize::from(short)).min(steps.len());
                let knots: Vec<f64> = steps[..len].iter().scan(0.0, |t, s| { *t += s; Some(*t) }).collect();
                if let Ok(kv) = KnotVector::new(count, order, knots) {
                    prop_assert_eq!(kv.knots().len(), count + order);
                    for s in 0..=40 {
                        let u = -0.25 + 1.5 * s as f64 / 40.0;
                        let b = kv.basis(u);
                        prop_assert!(b.first + b.order <= count);
                        let sum: f64 = b.values().iter().sum();
                        let magnitude: f64 = b.values().iter().map(|v| v.abs()).sum();
                        prop_assert!((sum - 1.0).abs() < 1e-10 * magnitude.max(1.0), "{:?} u={} sum={}", kv, u, sum);
                        if (0.0..=1.0).contains(&u) {
                            let t = kv.lo + u * (kv.hi - kv.lo);
                            for i in 0..count {
                                let want = reference(&kv.knots, order, i, t, kv.last_span);
                                let got = if (b.first..b.first + b.order).contains(&i) { b.values[i - b.first] } else { 0.0 };
                                prop_assert!((want - got).abs() < 1e-9, "{:?} u={} i={}", kv, u, i);
                            }
                        }
                    }
                }
            }
        }
    }
}
