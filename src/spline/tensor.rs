//! Axis-by-axis products of a 3D array with per-axis matrices: the separable evaluation of a
//! tensor-product spline on a grid, `s = (B ⊗ C ⊗ D) p` (HQ eq. 3), in `O(N³·k)` rather than
//! `O(N³·k³)`, and the separable least-squares solve `p = (B⁺ ⊗ C⁺ ⊗ D⁺) s`.
//!
//! Arrays are `[d0, d1, d2]` with index `i0 + d0·(i1 + d1·i2)` (axis 0 fastest). A matrix is
//! given as sparse rows: row `r` has `width` coefficients starting at column `first[r]` (a
//! basis table: the `k` non-zero basis functions at a sample), or dense (`first` all 0).

use super::knots::KnotVector;

/// The rows of a matrix, each a run of `width` coefficients from column `first[r]`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Rows {
    pub first: Vec<usize>,
    pub width: usize,
    pub coeffs: Vec<f64>,
}

impl Rows {
    /// The basis table of `knots` at `params`: row `r` holds the non-zero `N_i(params[r])`.
    pub fn basis(knots: &KnotVector, params: &[f64]) -> Self {
        let width = knots.order();
        let mut first = Vec::with_capacity(params.len());
        let mut coeffs = Vec::with_capacity(params.len() * width);
        for &u in params {
            let b = knots.basis(u);
            first.push(b.first);
            coeffs.extend_from_slice(b.values());
        }
        Self { first, width, coeffs }
    }

    /// A dense `rows × cols` matrix, row-major.
    pub fn dense(rows: usize, cols: usize, coeffs: Vec<f64>) -> Self {
        debug_assert_eq!(coeffs.len(), rows * cols);
        Self { first: vec![0; rows], width: cols, coeffs }
    }

    /// The number of rows.
    pub fn len(&self) -> usize {
        self.first.len()
    }

    fn row(&self, r: usize) -> (usize, &[f64]) {
        (self.first[r], &self.coeffs[r * self.width..(r + 1) * self.width])
    }
}

/// `out = M ×_axis data`: the array with axis `axis` replaced by `rows.len()` entries,
/// `out[.., r, ..] = Σ_t M[r, t] · data[.., t, ..]`. Returns the new array and dimensions.
pub(crate) fn transform_axis(
    data: &[f64],
    dims: [usize; 3],
    axis: usize,
    rows: &Rows,
) -> (Vec<f64>, [usize; 3]) {
    debug_assert_eq!(data.len(), dims.iter().product::<usize>());
    let [d0, d1, d2] = dims;
    let n = rows.len();
    let mut out_dims = dims;
    out_dims[axis] = n;
    let mut out = vec![0.0; out_dims.iter().product()];
    match axis {
        0 => {
            for (line, out_line) in data.chunks_exact(d0).zip(out.chunks_exact_mut(n)) {
                for (r, o) in out_line.iter_mut().enumerate() {
                    let (first, c) = rows.row(r);
                    *o = c.iter().zip(&line[first..first + c.len()]).map(|(a, b)| a * b).sum();
                }
            }
        }
        1 => {
            for i2 in 0..d2 {
                for r in 0..n {
                    let (first, c) = rows.row(r);
                    let o = d0 * (r + n * i2);
                    let out_line = &mut out[o..o + d0];
                    for (t, &ct) in c.iter().enumerate() {
                        let s = d0 * (first + t + d1 * i2);
                        for (a, &b) in out_line.iter_mut().zip(&data[s..s + d0]) {
                            *a += ct * b;
                        }
                    }
                }
            }
        }
        _ => {
            let plane = d0 * d1;
            for r in 0..n {
                let (first, c) = rows.row(r);
                let out_plane = &mut out[plane * r..plane * (r + 1)];
                for (t, &ct) in c.iter().enumerate() {
                    let s = plane * (first + t);
                    for (a, &b) in out_plane.iter_mut().zip(&data[s..s + plane]) {
                        *a += ct * b;
                    }
                }
            }
        }
    }
    (out, out_dims)
}

/// Applies one matrix per axis, axis 0 first.
pub(crate) fn transform_all(data: &[f64], dims: [usize; 3], rows: [&Rows; 3]) -> (Vec<f64>, [usize; 3]) {
    let (a, da) = transform_axis(data, dims, 0, rows[0]);
    let (b, db) = transform_axis(&a, da, 1, rows[1]);
    transform_axis(&b, db, 2, rows[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separable_products_equal_the_triple_sum() {
        let dims = [3, 4, 2];
        let data: Vec<f64> = (0..24).map(|i| (i as f64 * 0.37).sin()).collect();
        let m: [Rows; 3] = [
            Rows::dense(2, 3, vec![1.0, 2.0, 3.0, -1.0, 0.5, 0.25]),
            Rows { first: vec![0, 1, 2], width: 2, coeffs: vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0] },
            Rows::dense(3, 2, vec![1.0, 0.0, 0.0, 1.0, 0.5, 0.5]),
        ];
        let (out, od) = transform_all(&data, dims, [&m[0], &m[1], &m[2]]);
        assert_eq!(od, [2, 3, 3]);
        let entry = |rows: &Rows, r: usize, c: usize| {
            let (first, coeffs) = rows.row(r);
            if (first..first + coeffs.len()).contains(&c) {
                coeffs[c - first]
            } else {
                0.0
            }
        };
        for c in 0..3 {
            for b in 0..3 {
                for a in 0..2 {
                    let mut want = 0.0;
                    for k in 0..2 {
                        for j in 0..4 {
                            for i in 0..3 {
                                want += entry(&m[0], a, i)
                                    * entry(&m[1], b, j)
                                    * entry(&m[2], c, k)
                                    * data[i + 3 * (j + 4 * k)];
                            }
                        }
                    }
                    assert!((out[a + 2 * (b + 3 * c)] - want).abs() < 1e-12);
                }
            }
        }
    }
}
