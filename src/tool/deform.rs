//! The stamp's deformation function `def(v)` (Ferley et al. 1999, §4.3, Fig. 10–12).
//!
//! A stamp prints its shape into the clay: it removes matter where it penetrates and raises a
//! bulge around the print, imitating displaced material without simulating it. The tool's
//! potential `T(P)` (1 at its core, ½ on its surface, 0 outside its reach) is turned into the
//! variable `v = maxVal − T(P) = 1 − T(P)` (0 at the core, growing outwards), and the
//! stamp's contribution `def(v)` is added to the clay's density, which is then clamped to
//! [0, 1].
//!
//! The function of Fig. 11, as printed, with `v₀ = v − s − m` in the last piece:
//!
//! ```text
//!             ⎧ −(s·k + 2)/s³ · v³ + (s·k + 3)/s² · v² − 1             v < s
//!   def(v) =  ⎨ −(k·m + 2·n)/m³ · v₁³ + (2·k·m + 3·n)/m² · v₁² − k · v₁   v < s + m, v₁ = v − s
//!             ⎪  2·n/r³ · v₀³ − 3·n/r² · v₀² + n                        v < s + m + r
//!             ⎩  0                                                      otherwise
//! ```
//!
//! ```text
//!   def
//!    n ┤              ╭──╮            s: where the print's edge lies (the tool's surface),
//!      │             ╱    ╲              set to the iso-level ½ by default
//!    0 ┼───────────╳───────╲──────   m: width of the rising bulge, n: its height
//!      │         ╱  s     s+m  s+m+r  r: width of the bulge's decay to nothing
//!      │       ╱                     k: slope control where the pieces meet at s:
//!   −1 ┤──────╯                         def′(s) = −k (k < 0 rises through the edge)
//!      0                       v = 1 − T
//! ```
//!
//! Each piece is the cubic Hermite segment between its end values (−1 → 0, 0 → n, n → 0)
//! with zero slope at `v = 0`, `s + m` and `s + m + r`, and slope `−k` at `v = s`; the pieces
//! join with continuous value and slope. The first two pieces are exactly the printed ones.
//! The printed third piece reads `−2n/r³ · v₀³ − 3n/m² · v₀² + n`, which does not reach 0
//! at `v = s + m + r`; the only cubic with the stated end values and flat ends is the one
//! above (the signs and `r²` restored), which is what we evaluate.
//!
//! The paper requires `s + m + r ≤ maxVal − minVal` (here 1, density's range): otherwise the
//! function's domain exceeds the values the potential takes and the bulge would be truncated.
//! [`Deformation::new`] refuses such parameters.

use std::fmt;

/// The parameters of `def(v)`, validated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deformation {
    s: f32,
    m: f32,
    r: f32,
    k: f32,
    n: f32,
}

/// Why a set of deformation parameters is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DeformError {
    /// `s`, `m` or `r` is not a positive finite number, or `k`/`n` is not finite.
    #[error("stamp parameter `{name}` must be {what}, not {value}")]
    BadValue {
        /// Which parameter.
        name: &'static str,
        /// What it must be.
        what: &'static str,
        /// The value given.
        value: f32,
    },
    /// The function's domain exceeds the field's value range.
    #[error(
        "stamp parameters s + m + r = {sum} exceed the field's value range of {range} \
         (density runs from 0 to 1): the deformation would be truncated; make s, m or r smaller"
    )]
    Truncated {
        /// `s + m + r`.
        sum: f32,
        /// `maxVal − minVal`.
        range: f32,
    },
}

/// The range of values the field (and a tool's potential) takes: density in [0, 1].
pub const FIELD_VALUE_RANGE: f32 = 1.0;

impl Default for Deformation {
    /// `s = ½` (the iso-level), `m = 0.2`, `r = 0.2`, `k = −2`, `n = 0.3`: a print whose rim
    /// rises steadily into a bulge 0.3 high.
    fn default() -> Self {
        Self { s: 0.5, m: 0.2, r: 0.2, k: -2.0, n: 0.3 }
    }
}

impl Deformation {
    /// Validates the parameters: `s`, `m`, `r` positive, `k`, `n` finite, and
    /// `s + m + r ≤` [`FIELD_VALUE_RANGE`].
    pub fn new(s: f32, m: f32, r: f32, k: f32, n: f32) -> Result<Self, DeformError> {
        for (name, value) in [("s", s), ("m", m), ("r", r)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(DeformError::BadValue { name, what: "a positive number", value });
            }
        }
        for (name, value) in [("k", k), ("n", n)] {
            if !value.is_finite() {
                return Err(DeformError::BadValue { name, what: "a finite number", value });
            }
        }
        let sum = s + m + r;
        if sum > FIELD_VALUE_RANGE + 1e-6 {
            return Err(DeformError::Truncated { sum, range: FIELD_VALUE_RANGE });
        }
        Ok(Self { s, m, r, k, n })
    }

    /// The parameters `(s, m, r, k, n)`.
    pub fn parameters(&self) -> (f32, f32, f32, f32, f32) {
        (self.s, self.m, self.r, self.k, self.n)
    }

    /// `def(v)`, see the module documentation.
    #[inline]
    pub fn def(&self, v: f32) -> f32 {
        let Self { s, m, r, k, n } = *self;
        if v < s {
            -(s * k + 2.0) / (s * s * s) * v * v * v + (s * k + 3.0) / (s * s) * v * v - 1.0
        } else if v < s + m {
            let v1 = v - s;
            -(k * m + 2.0 * n) / (m * m * m) * v1 * v1 * v1 + (2.0 * k * m + 3.0 * n) / (m * m) * v1 * v1
                - k * v1
        } else if v < s + m + r {
            let v0 = v - s - m;
            2.0 * n / (r * r * r) * v0 * v0 * v0 - 3.0 * n / (r * r) * v0 * v0 + n
        } else {
            0.0
        }
    }

    /// The stamp's contribution for a tool potential `t` in [0, 1]: `def(1 − t)`.
    #[inline]
    pub fn contribution(&self, t: f32) -> f32 {
        self.def(FIELD_VALUE_RANGE - t)
    }
}

impl fmt::Display for Deformation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "def(s = {}, m = {}, r = {}, k = {}, n = {})", self.s, self.m, self.r, self.k, self.n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pieces_join_with_value_and_slope() {
        let d = Deformation::new(0.45, 0.25, 0.2, -1.5, 0.35).unwrap();
        let (s, m, r, k, n) = d.parameters();
        let h = 2e-4;
        let slope = |v: f32| (d.def(v + h) - d.def(v - h)) / (2.0 * h);
        assert!((d.def(0.0) + 1.0).abs() < 1e-6);
        for (v, value) in [(s, 0.0), (s + m, n), (s + m + r, 0.0)] {
            assert!((d.def(v - 1e-5) - value).abs() < 1e-3, "left of {v}");
            assert!((d.def(v + 1e-5) - value).abs() < 1e-3, "right of {v}");
        }
        assert!((slope(s) + k).abs() < 1e-2, "def'(s) = -k: {}", slope(s));
        assert!(slope(s + m).abs() < 1e-2);
        assert!(slope(s + m + r).abs() < 1e-2);
        assert!(slope(h).abs() < 1e-2);
        assert_eq!(d.def(0.95), 0.0);
    }

    #[test]
    fn parameters_beyond_the_value_range_are_refused() {
        let e = Deformation::new(0.5, 0.4, 0.3, 0.0, 0.2).unwrap_err();
        assert!(matches!(e, DeformError::Truncated { .. }));
        let msg = e.to_string();
        assert!(msg.contains("s + m + r = 1.2") && msg.contains("value range"), "{msg}");
        assert!(Deformation::new(0.5, 0.0, 0.3, 0.0, 0.2).is_err());
        assert!(Deformation::new(0.5, 0.2, 0.3, f32::NAN, 0.2).is_err());
        assert!(Deformation::new(0.5, 0.25, 0.25, 0.0, 0.2).is_ok());
    }

    #[test]
    fn the_default_removes_inside_and_bulges_outside() {
        let d = Deformation::default();
        assert_eq!(d.contribution(1.0), -1.0);
        assert!(d.contribution(0.6) < 0.0);
        assert!(d.contribution(0.3) > 0.0);
        assert!((d.contribution(0.3) - 0.3).abs() < 1e-5, "the bulge's top at v = s + m");
        assert_eq!(d.contribution(0.0), 0.0);
    }
}
