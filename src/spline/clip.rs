//! Functional clipping (ESM §3.1): the spline's function intersected with the unit cube, so
//! that no "ghost" solid appears outside the lattice.
//!
//! Outside [0, 1]³ a spline's pieces continue as polynomials, with no control over their
//! values: a function that is below the iso-level at the lattice's faces can rise above it
//! again outside. ESM intersects the solid with the unit cube by the R-function
//!
//! ```text
//!   a & b = a + b − √(a² + b²)                          (ESM §3.1, R-function intersection)
//!   F_p(t) = t (1 − t)                                   the unit strip, ≥ 0 on [0, 1]
//!   F_c(u, v, w) = F_p(u) & F_p(v) & F_p(w)             the unit cube, ≥ 0 inside
//!   S_clip(u, v, w) = S(u, v, w) & F_c(u, v, w)
//! ```
//!
//! `a & b ≥ 0` exactly where both are, and `a & b ≤ min(a, b)` everywhere, so `S_clip` is
//! negative at every point outside the cube, whatever `S`, and its zero set inside the cube is
//! that of `S`. Where `S = 0` and `F_c > 0` the gradient of `S_clip` is that of `S`
//! (`∂(a & b)/∂a = 1 − a/√(a² + b²) = 1` at `a = 0`): the surface and its normals are kept.
//!
//! ## From density to the paper's signed functions and back
//!
//! ESM's defining functions are signed: positive inside the solid, zero on its surface. Our
//! function values are densities in [0, 1] with the surface at the iso-level `iso` (0.5).
//! So the clipped density of a function value `f` at parameters `uvw` is
//!
//! ```text
//!   g = f − iso                          signed, positive inside, 0 on the surface
//!   c = λ · F_c(uvw)                     the cube's function, scaled by λ = cube_scale
//!   density = clamp(iso + (g & c), 0, 1)
//! ```
//!
//! Consequences, each tested below: density < iso at every point outside the cube (no ghost);
//! density ≤ clamp(f, 0, 1) everywhere (clipping never adds matter); inside the cube
//! density ≥ iso exactly where f ≥ iso (the surface is unchanged); density is exactly 0
//! where some parameter lies farther than [`Clipping::band`] outside [0, 1]
//! ([`Clipping::is_empty_at`]), so callers need not evaluate the spline there.
//!
//! λ = 1 is the paper's form ([`Clipping::PAPER`]). It compresses the interior: full clay
//! (f = 1) at the cube's centre, where `F_c ≈ 0.107`, reads 0.595, and a band of faint
//! density (below iso) reaches 0.37 of the box outside it. A larger λ leaves the surface where
//! it is and brings the interior within `g² / (2 c)` of the unclipped density, while the
//! outside band narrows to about `iso / λ`: [`Clipping::with_band`] picks λ from the width of
//! that band (a few voxels is a good choice: the clip stays band-limited).

use super::volume::{SplineVolume, Uvw};
use super::SplineError;

/// The R-function intersection `a & b = a + b − √(a² + b²)` (ESM §3.1): non-negative exactly
/// where both arguments are, never above either.
#[inline]
pub fn r_intersection(a: f64, b: f64) -> f64 {
    a + b - (a * a + b * b).sqrt()
}

/// The unit strip's defining function `t (1 − t)`: positive on (0, 1).
#[inline]
pub fn unit_strip(t: f64) -> f64 {
    t * (1.0 - t)
}

/// The unit cube's defining function `F_p(u) & F_p(v) & F_p(w)`: positive inside [0, 1]³.
#[inline]
pub fn unit_cube_function(uvw: Uvw) -> f64 {
    let [u, v, w] = uvw.0;
    r_intersection(r_intersection(unit_strip(u), unit_strip(v)), unit_strip(w))
}

/// How a spline's function is clipped to the unit cube and turned into a density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clipping {
    iso: f64,
    cube_scale: f64,
}

impl Default for Clipping {
    /// The paper's clipping, [`Clipping::PAPER`].
    fn default() -> Self {
        Self::PAPER
    }
}

impl Clipping {
    /// ESM §3.1 as printed: iso-level 0.5, the cube's function unscaled (λ = 1).
    pub const PAPER: Clipping = Clipping { iso: 0.5, cube_scale: 1.0 };

    /// A clipping at iso-level `iso` (in (0, 1)) with the cube's function scaled by
    /// `cube_scale` (λ, finite and at least `iso / 2`, which keeps the band at most 1: the
    /// inverse mapping searches parameters in [−1, 2]³).
    pub fn new(iso: f64, cube_scale: f64) -> Result<Self, SplineError> {
        if !(iso.is_finite() && iso > 0.0 && iso < 1.0) {
            return Err(SplineError::Parameter {
                name: "the iso-level",
                what: "between 0 and 1",
                value: iso,
            });
        }
        if !(cube_scale.is_finite() && cube_scale >= iso / 2.0) {
            return Err(SplineError::Parameter {
                name: "the cube's scale",
                what: "finite and at least half the iso-level (a clipping band of at most 1)",
                value: cube_scale,
            });
        }
        Ok(Self { iso, cube_scale })
    }

    /// A clipping whose band of non-zero density outside the cube is at most `band` wide in
    /// parameter units (a fraction of the box, in (0, 1]): `λ = iso / (band · (1 + band))`.
    pub fn with_band(iso: f64, band: f64) -> Result<Self, SplineError> {
        if !(band.is_finite() && band > 0.0 && band <= 1.0) {
            return Err(SplineError::Parameter {
                name: "the clipping band",
                what: "a width in (0, 1]",
                value: band,
            });
        }
        Self::new(iso, iso / (band * (1.0 + band)))
    }

    /// The iso-level: the density of the surface.
    pub fn iso(&self) -> f64 {
        self.iso
    }

    /// λ, the scale of the cube's function.
    pub fn cube_scale(&self) -> f64 {
        self.cube_scale
    }

    /// How far outside [0, 1] (in parameter units) a parameter may lie and the density still
    /// be non-zero: the root of `λ · t (1 − t) = −iso`, `(√(1 + 4 iso / λ) − 1) / 2`.
    pub fn band(&self) -> f64 {
        ((1.0 + 4.0 * self.iso / self.cube_scale).sqrt() - 1.0) / 2.0
    }

    /// `(f − iso) & λ F_c(uvw)`: the clipped signed function, positive inside the solid.
    #[inline]
    pub fn signed(&self, value: f64, uvw: Uvw) -> f64 {
        r_intersection(value - self.iso, self.cube_scale * unit_cube_function(uvw))
    }

    /// The clipped density, `clamp(iso + signed, 0, 1)`.
    #[inline]
    pub fn density(&self, value: f64, uvw: Uvw) -> f32 {
        (self.iso + self.signed(value, uvw)).clamp(0.0, 1.0) as f32
    }

    /// Whether the clipped density at `uvw` is 0 whatever the function's value: some
    /// parameter lies so far outside [0, 1] that `λ F_p(t) ≤ −iso` (`a & b ≤ min(a, b)`).
    #[inline]
    pub fn is_empty_at(&self, uvw: Uvw) -> bool {
        let least = uvw.0.iter().map(|&t| unit_strip(t)).fold(f64::INFINITY, f64::min);
        self.cube_scale * least <= -self.iso
    }
}

impl SplineVolume {
    /// The clipped density at parameters `uvw` (function mapping, no space mapping): 0
    /// without evaluating the spline where [`Clipping::is_empty_at`].
    pub fn density_at_parameters(&self, uvw: Uvw, clip: &Clipping) -> f32 {
        if !uvw.is_finite() || clip.is_empty_at(uvw) {
            return 0.0;
        }
        clip.density(self.value(uvw), uvw)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spline::volume::tests::{unit_box, Rng};
    use crate::spline::KnotStyle;

    #[test]
    fn the_r_intersection_is_an_intersection() {
        let values = [-3.0, -1.0, -0.2, 0.0, 0.1, 0.5, 2.0, 10.0];
        for &a in &values {
            for &b in &values {
                let r = r_intersection(a, b);
                assert!(r <= a.min(b) + 1e-15, "{a} & {b} = {r}");
                if a > 0.0 && b > 0.0 {
                    assert!(r > 0.0);
                } else if a < 0.0 || b < 0.0 {
                    assert!(r < 0.0);
                } else {
                    assert_eq!(r, 0.0, "{a} & {b}: on the boundary of one, inside the other");
                }
                assert_eq!(r, r_intersection(b, a));
            }
        }
        assert!(unit_cube_function(Uvw::new(0.5, 0.5, 0.5)) > 0.1);
        assert_eq!(unit_cube_function(Uvw::new(0.0, 0.5, 0.5)), 0.0);
        assert!(unit_cube_function(Uvw::new(0.5, 1.01, 0.5)) < 0.0);
    }

    fn clippings() -> Vec<Clipping> {
        vec![Clipping::PAPER, Clipping::new(0.3, 4.0).unwrap(), Clipping::with_band(0.5, 0.02).unwrap()]
    }

    #[test]
    fn no_ghost_outside_the_cube_and_nothing_beyond_the_band() {
        let mut rng = Rng(23);
        for clip in clippings() {
            for _ in 0..20_000 {
                let uvw = rng.uvw(-1.5, 2.5);
                let value = -5.0 + 10.0 * rng.next_f64();
                let d = clip.density(value, uvw);
                assert!(d.is_finite());
                if !uvw.is_in_unit_cube() {
                    assert!(clip.signed(value, uvw) < 0.0, "positive outside at {uvw:?}");
                    assert!((d as f64) < clip.iso() + 1e-7);
                }
                if clip.is_empty_at(uvw) {
                    assert_eq!(d, 0.0);
                }
                let far = uvw.0.iter().any(|&t| t < -clip.band() - 1e-9 || t > 1.0 + clip.band() + 1e-9);
                if far {
                    assert_eq!(d, 0.0, "{uvw:?} lies beyond the band {}", clip.band());
                    assert!(clip.is_empty_at(uvw));
                }
            }
        }
        assert!((Clipping::with_band(0.5, 0.02).unwrap().band() - 0.02).abs() < 1e-12);
        assert!((Clipping::PAPER.band() - (3f64.sqrt() - 1.0) / 2.0).abs() < 1e-12);
    }

    #[test]
    fn clipping_never_adds_matter_and_keeps_the_surface() {
        let mut rng = Rng(29);
        for clip in clippings() {
            for _ in 0..20_000 {
                let uvw = rng.uvw(-0.2, 1.2);
                let value = -0.5 + 2.0 * rng.next_f64();
                let d = clip.density(value, uvw) as f64;
                assert!(d <= value.clamp(0.0, 1.0) + 1e-7, "clipping added matter at {uvw:?}");
                if unit_cube_function(uvw) > 0.0 && (value - clip.iso()).abs() > 1e-9 {
                    assert_eq!(clip.signed(value, uvw) > 0.0, value > clip.iso(), "the surface moved");
                }
            }
        }
    }

    #[test]
    fn the_surface_normal_is_kept() {
        // g(u) = 2 (u − 0.4) + iso crosses the iso-level at u = 0.4: the clipped function has
        // the same slope there.
        for clip in clippings() {
            let uvw = |u: f64| Uvw::new(u, 0.5, 0.5);
            let f = |u: f64| clip.iso() + 2.0 * (u - 0.4);
            let h = 1e-7;
            let slope =
                (clip.signed(f(0.4 + h), uvw(0.4 + h)) - clip.signed(f(0.4 - h), uvw(0.4 - h))) / (2.0 * h);
            assert!((slope - 2.0).abs() < 1e-5, "{clip:?}: slope {slope}");
        }
    }

    #[test]
    fn a_wider_scale_keeps_the_interior_density() {
        let centre = Uvw::new(0.5, 0.5, 0.5);
        let paper = Clipping::PAPER.density(1.0, centre);
        assert!((paper - 0.595).abs() < 0.01, "full clay at the centre reads {paper} with the paper's scale");
        let tight = Clipping::with_band(0.5, 0.01).unwrap();
        // λ ≈ 50: within g² / (2 λ F_c) = 0.025 of full at the centre, where F_c ≈ 0.107.
        assert!(tight.density(1.0, centre) > 0.97);
        assert!(tight.density(1.0, Uvw::new(0.1, 0.5, 0.5)) > 0.95);
        assert!(tight.density(0.8, Uvw::new(0.3, 0.4, 0.6)) > 0.78);
        let tighter = Clipping::with_band(0.5, 0.001).unwrap();
        assert!(tighter.density(1.0, centre) > 0.997);
        // Same zero set: a face of full clay sits at iso.
        for clip in clippings() {
            assert!((clip.density(1.0, Uvw::new(0.0, 0.5, 0.5)) as f64 - clip.iso()).abs() < 1e-7);
        }
    }

    #[test]
    fn a_volume_of_clay_has_ghosts_that_clipping_removes() {
        // The values rise towards the u = 1 face: the extended spline is above iso outside it.
        let mut vol = SplineVolume::bspline(unit_box(), [6, 4, 4], [4, 3, 3], KnotStyle::Uniform).unwrap();
        vol.update_values(|[i, _, _], _| i as f64 / 5.0).unwrap();
        let clip = Clipping::PAPER;
        let outside = Uvw::new(1.2, 0.5, 0.5);
        assert!(vol.value(outside) > clip.iso() + 0.3, "the ghost: unclipped value {}", vol.value(outside));
        assert!((vol.density_at_parameters(outside, &clip) as f64) < clip.iso());
        assert_eq!(vol.density_at_parameters(Uvw::new(5.0, 0.5, 0.5), &clip), 0.0);
        assert_eq!(vol.density_at_parameters(Uvw::new(f64::NAN, 0.5, 0.5), &clip), 0.0);
        assert!(vol.density_at_parameters(Uvw::new(0.9, 0.5, 0.5), &clip) > 0.5);
    }

    #[test]
    fn bad_clipping_parameters_are_refused() {
        assert!(Clipping::new(0.0, 1.0).is_err());
        assert!(Clipping::new(1.0, 1.0).is_err());
        assert!(Clipping::new(0.5, 0.0).is_err());
        assert!(Clipping::new(0.5, f64::NAN).is_err());
        assert!(Clipping::with_band(0.5, -0.1).is_err());
        assert!(Clipping::with_band(0.5, 1.5).is_err());
        assert!(Clipping::new(0.5, 0.2).is_err(), "a band wider than 1");
        assert!((Clipping::with_band(0.5, 1.0).unwrap().band() - 1.0).abs() < 1e-12);
        assert!((Clipping::new(0.9, 1.0).unwrap().band() - 0.5732).abs() < 1e-3);
        assert_eq!(Clipping::default(), Clipping::PAPER);
    }
}
