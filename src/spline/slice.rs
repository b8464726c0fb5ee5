//! A slice of a spline volume (ESM §4.2): the surface `w = w_k` through the `l × m` patch of
//! controls `k`, and the zero contour of the function on it, where the solid's surface crosses
//! the slice.
//!
//! The contour is found by marching squares over a grid of `(u, v)` samples on the slice and
//! mapped into space by the volume's position, so that it lies on the deformed slice. It is
//! written here rather than taken from a contouring crate: those close their rings along the
//! grid's border (values beyond it count as outside), which would draw a contour on the
//! lattice's face wherever the solid reaches it.

use super::{SplineVolume, Uvw};
use crate::math::Vec3;

/// Samples per side of the grid a slice's contour is found on.
pub const SLICE_SAMPLES: usize = 48;

impl SplineVolume {
    /// The normalised parameter `w` of the slice through controls `k` (their Greville
    /// abscissa, within the unit interval).
    pub fn slice_w(&self, k: usize) -> f64 {
        self.knots(2).greville(k).clamp(0.0, 1.0)
    }

    /// The contour `F = iso` on the slice `w` as segments in space (each a pair of points),
    /// over a grid of `samples × samples` parameters (at least 2).
    pub fn slice_contour(&self, w: f64, iso: f64, samples: usize) -> Vec<[Vec3; 2]> {
        let n = samples.max(2);
        let at = |i: usize, j: usize| Uvw([i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64, w]);
        let values: Vec<f64> = (0..n * n).map(|c| self.value(at(c % n, c / n)) - iso).collect();
        let value = |i: usize, j: usize| values[i + n * j];
        let mut segments = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                // Corners anticlockwise from (i, j); an edge crossed where its ends' signs differ.
                let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
                let f = corners.map(|(a, b)| value(a, b));
                let mut crossings = Vec::with_capacity(4);
                for e in 0..4 {
                    let (a, b) = (f[e], f[(e + 1) % 4]);
                    if (a >= 0.0) != (b >= 0.0) {
                        let t = a / (a - b);
                        let (p, q) = (
                            at(corners[e].0, corners[e].1),
                            at(corners[(e + 1) % 4].0, corners[(e + 1) % 4].1),
                        );
                        crossings.push(Uvw(std::array::from_fn(|c| p.0[c] + t * (q.0[c] - p.0[c]))));
                    }
                }
                let mut pair = |a: Uvw, b: Uvw| segments.push([self.position(a), self.position(b)]);
                match crossings.as_slice() {
                    [a, b] => pair(*a, *b),
                    // A saddle: the centre's sign says which corners the contour keeps apart.
                    [a, b, c, d] => {
                        let centre = f.iter().sum::<f64>() / 4.0;
                        if (centre >= 0.0) == (f[0] >= 0.0) {
                            pair(*a, *d);
                            pair(*b, *c);
                        } else {
                            pair(*a, *b);
                            pair(*c, *d);
                        }
                    }
                    _ => {}
                }
            }
        }
        segments
    }
}

#[cfg(test)]
mod tests {
    use crate::math::{Aabb, Vec3};
    use crate::spline::{KnotStyle, SplineVolume, Uvw};

    /// A cubic B-spline volume over the unit box whose values are `1 − |x − c|²/r²` at its
    /// Greville points (`r` = 0.5): about a ball of radius `r / √2` about `c` for iso 0.5.
    fn ball() -> SplineVolume {
        let region = Aabb { min: Vec3::ZERO, max: Vec3::ONE };
        let mut v = SplineVolume::bspline(region, [8, 8, 8], [4, 4, 4], KnotStyle::Clamped).unwrap();
        for k in 0..8 {
            for j in 0..8 {
                for i in 0..8 {
                    let p = v.control(i, j, k).unwrap().rest_m;
                    let d = (p - Vec3::splat(0.5)).length_squared() / 0.25;
                    v.set_value(i, j, k, 1.0 - d as f64).unwrap();
                }
            }
        }
        v
    }

    #[test]
    fn the_zero_contour_lies_on_the_slice_where_the_function_crosses_the_iso_value() {
        let v = ball();
        let w = v.slice_w(4);
        assert!((w - 0.5).abs() < 0.2, "{w}");
        let segments = v.slice_contour(w, 0.5, 48);
        assert!(segments.len() > 40, "a closed loop of many segments: {}", segments.len());
        for [a, b] in &segments {
            for p in [a, b] {
                let uvw = v.rest_parameters(*p);
                assert!((uvw.0[2] - w).abs() < 1e-6, "on the slice: {uvw:?}");
                let f = v.value(Uvw(uvw.0));
                assert!((f - 0.5).abs() < 0.02, "on the contour: {f}");
            }
        }
        // A loop: every end is the end of another segment.
        let ends: Vec<Vec3> = segments.iter().flatten().copied().collect();
        for p in &ends {
            assert_eq!(ends.iter().filter(|q| q.distance(*p) < 1e-6).count(), 2, "at {p}");
        }
        // No crossing above or below the whole slice: no contour.
        assert!(v.slice_contour(w, 5.0, 48).is_empty());
        assert!(v.slice_contour(w, -5.0, 48).is_empty());
    }

    #[test]
    fn the_contour_follows_the_deformed_slice() {
        let mut v = ball();
        let w = v.slice_w(4);
        let rest = v.slice_contour(w, 0.5, 32);
        for j in 0..8 {
            for i in 0..8 {
                let p = v.control(i, j, 4).unwrap().position_m;
                v.set_position(i, j, 4, p + Vec3::new(0.0, 0.0, 0.1)).unwrap();
            }
        }
        let moved = v.slice_contour(w, 0.5, 32);
        assert_eq!(rest.len(), moved.len());
        let lift = moved.iter().zip(&rest).map(|(a, b)| a[0].z - b[0].z).fold(0.0f32, f32::max);
        assert!(lift > 0.02, "the contour moved with the controls: {lift}");
    }
}
