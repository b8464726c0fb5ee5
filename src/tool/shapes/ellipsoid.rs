//! Ellipsoidal tools (Ferley et al. 1999, §4.1.1): an isotropic field around the centre, the
//! Wyvill function or a box-shaped one, made ellipsoidal by scaling along three axes.
//!
//! ```text
//!   T   Wyvill: smooth, ½ at half the radius         Box: 1 inside, 0 outside (band-limited)
//!   1 ──╮                                          1 ─────────╮
//!        ╲_                                                   ╲
//!   ½      ╲__                                    ½            ╳  ← radius
//!   0         ╲____ ρ = 1 (the radius)            0             ╲______
//! ```

use crate::math::Vec3;

/// The radial profile of an ellipsoidal tool.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Falloff {
    /// Wyvill's soft-object function of the normalised radius: 1 at the centre, 0 at the
    /// radii, ½ at half of them; smooth everywhere.
    Wyvill,
    /// The characteristic function of the ellipsoid, band-limited across its surface.
    Box,
}

/// An ellipsoid whose semi-axes along local X, Y, Z are `radii_m`: the limit of the tool's
/// influence region, which is also what the tool's glyph shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipsoid {
    /// Semi-axes in metres.
    pub radii_m: Vec3,
    /// Radial profile.
    pub falloff: Falloff,
}

/// Wyvill's soft-object function of a normalised radius `ρ`:
/// `1 − 4/9 ρ⁶ + 17/9 ρ⁴ − 22/9 ρ²` for `ρ < 1`, else 0.
#[inline]
pub fn wyvill(rho: f32) -> f32 {
    if rho >= 1.0 {
        return 0.0;
    }
    let r2 = rho * rho;
    let r4 = r2 * r2;
    (1.0 - (4.0 / 9.0) * r4 * r2 + (17.0 / 9.0) * r4 - (22.0 / 9.0) * r2).clamp(0.0, 1.0)
}

impl Ellipsoid {
    /// `|p / radii|`: 1 on the ellipsoid.
    #[inline]
    pub fn normalised_radius(&self, local_m: Vec3) -> f32 {
        (local_m / self.radii_m).length()
    }

    /// An estimate of the signed distance to the ellipsoid, exact on its surface and along its
    /// axes, to first order elsewhere: `k₀ (k₀ − 1) / k₁` with `k₀ = |p / r|`, `k₁ = |p / r²|`.
    #[inline]
    pub fn signed_distance(&self, local_m: Vec3) -> f32 {
        let k0 = (local_m / self.radii_m).length();
        let k1 = (local_m / (self.radii_m * self.radii_m)).length();
        if k1 > 0.0 {
            k0 * (k0 - 1.0) / k1
        } else {
            -self.radii_m.min_element()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wyvill_is_one_half_and_zero_where_it_should_be() {
        assert_eq!(wyvill(0.0), 1.0);
        assert!((wyvill(0.5) - 0.5).abs() < 1e-6);
        assert!(wyvill(1.0 - 1e-6).abs() < 1e-5);
        assert_eq!(wyvill(1.5), 0.0);
        let mut last = 1.0;
        for i in 1..=100 {
            let v = wyvill(i as f32 / 100.0);
            assert!(v <= last);
            last = v;
        }
    }

    #[test]
    fn the_distance_is_exact_along_the_axes() {
        let e = Ellipsoid { radii_m: Vec3::new(1.0, 2.0, 3.0), falloff: Falloff::Box };
        assert!((e.signed_distance(Vec3::new(1.5, 0.0, 0.0)) - 0.5).abs() < 1e-6);
        assert!((e.signed_distance(Vec3::new(0.0, 1.0, 0.0)) + 1.0).abs() < 1e-6);
        assert!((e.signed_distance(Vec3::new(0.0, 0.0, 3.0))).abs() < 1e-6);
        assert!(e.signed_distance(Vec3::ZERO) < 0.0);
    }
}
