//! The inverse space mapping (ESM §3: "moving control points in (x, y, z) space … requires
//! the inverse space mapping"): the parameters `(u, v, w)` with `P(u, v, w) = x`.
//!
//! `P` has no closed-form inverse once control points move, so it is solved for by Newton's
//! method on `r(u) = P(u) − x`:
//!
//! ```text
//!   start   u₀ = A⁻¹(x)           the rest lattice's inverse: the box's affine inverse, exact
//!                                 for an undeformed lattice (or a caller's warm start)
//!   step    J(uₙ) δ = −r(uₙ)       J = ∂P/∂(u, v, w); Levenberg–Marquardt
//!                                 (Jᵀ J + μ I) δ = −Jᵀ r where J is (nearly) singular
//!   damp    uₙ₊₁ = uₙ + t δ       t = 1, ½, ¼, … until |r| decreases (backtracking)
//!   stop    |r| ≤ 10⁻⁹ · the box's largest side
//! ```
//!
//! Iterates stay in [−1, 2]³: beyond that, every clipping keeps the density at 0 (its band is
//! at most 1, 0.37 for the paper's scale, [`super::Clipping::band`]), and the extended
//! polynomials only grow. If the first start fails, the search falls back to the parameters of
//! the nearest control point and to the nearest node of a coarse grid of `P`.
//!
//! A world point outside the control points' bounding box, grown by a margin, is refused
//! without iterating: the image of the unit cube lies inside that box (convex hull property,
//! weights being positive), so such a point has no preimage in the cube. If the lattice folds
//! over itself a point has several preimages; the search returns the first one it finds, one
//! inside the cube if it finds one.

use crate::math::Vec3;

use super::clip::Clipping;
use super::volume::{to_f64, Located, SplineVolume, Uvw};

/// The result of an inverse mapping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseMap {
    /// The parameters found (the best found when not converged), always finite.
    pub uvw: Uvw,
    /// Whether `|P(uvw) − x|` is within the tolerance.
    pub converged: bool,
    /// Whether it converged and `uvw` lies in the unit cube (within 10⁻⁹): `x` is inside the
    /// deformed lattice.
    pub inside: bool,
    /// Newton iterations spent, over all starts.
    pub iterations: u32,
    /// `|P(uvw) − x|` in metres.
    pub residual_m: f64,
}

/// Newton iterations per start.
const MAX_ITERATIONS: u32 = 40;
/// Halvings of a step before the direction is given up.
const MAX_HALVINGS: u32 = 24;
/// Convergence tolerance, relative to the box's largest side.
pub(crate) const TOLERANCE: f64 = 1e-9;
/// The parameter box the iterates stay in.
const SEARCH: (f64, f64) = (-1.0, 2.0);
/// Slack of the unit cube test.
const INSIDE_SLACK: f64 = 1e-9;
/// The margin, relative to the box's size, by which the control hull is grown before points
/// outside it are refused by [`SplineVolume::inverse_map`].
pub(crate) const HULL_MARGIN: f64 = 0.5;
/// Nodes per axis of the fallback's coarse grid.
const COARSE: usize = 4;

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn clamp_search(u: Uvw) -> Uvw {
    Uvw(u.0.map(|t| if t.is_finite() { t.clamp(SEARCH.0, SEARCH.1) } else { 0.5 }))
}

/// Solves `M δ = b` for a 3 × 3 matrix given by columns, regularised by `mu` (0: plain
/// Newton, refused when nearly singular). Returns `None` for a (numerically) singular system.
fn solve(cols: &[[f64; 3]; 3], rhs: [f64; 3], mu: f64) -> Option<[f64; 3]> {
    // Work on the normal equations when regularising: (MᵀM + μI) δ = Mᵀ b.
    let (m, b) = if mu > 0.0 {
        let mut n = [[0.0; 3]; 3];
        let mut nb = [0.0; 3];
        for a in 0..3 {
            for c in 0..3 {
                n[c][a] =
                    (0..3).map(|x| cols[a][x] * cols[c][x]).sum::<f64>() + if a == c { mu } else { 0.0 };
            }
            nb[a] = (0..3).map(|x| cols[a][x] * rhs[x]).sum();
        }
        (n, nb)
    } else {
        (*cols, rhs)
    };
    // m[c][r]: column c, row r. Cramer's rule via the columns' cross products.
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (c0, c1, c2) = (m[0], m[1], m[2]);
    let det = dot(c0, cross(c1, c2));
    let scale = norm(c0) * norm(c1) * norm(c2);
    if !(det.abs() > 1e-12 * scale && scale > 0.0) {
        return None;
    }
    let x = [dot(b, cross(c1, c2)) / det, dot(c0, cross(b, c2)) / det, dot(c0, cross(c1, b)) / det];
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// One run of damped Newton from `start`.
struct Run {
    uvw: Uvw,
    residual: f64,
    iterations: u32,
    /// Position and Jacobian at `uvw`.
    located: Located,
}

impl SplineVolume {
    /// The parameters of world point `x` in the deformed lattice, from the rest lattice's
    /// inverse (see the module documentation).
    pub fn inverse_map(&self, x: Vec3) -> InverseMap {
        self.inverse_map_from(x, None)
    }

    /// As [`Self::inverse_map`], trying `start` (e.g. a neighbouring point's parameters)
    /// before the rest lattice's inverse.
    pub fn inverse_map_from(&self, x: Vec3, start: Option<Uvw>) -> InverseMap {
        let margin = self.region().size() * HULL_MARGIN as f32;
        self.inverse_map_within(x, start, margin, true, TOLERANCE).0
    }

    /// The inverse map refusing points farther than `margin` outside the control hull, converged
    /// within `tolerance` (relative to the box's largest side; [`TOLERANCE`] unless a caller
    /// needs less); with `fallbacks`, failed starts inside the hull try the nearest control
    /// and a coarse grid.
    /// Also returns the position and Jacobian at the parameters found, when the search ran.
    pub(crate) fn inverse_map_within(
        &self,
        x: Vec3,
        start: Option<Uvw>,
        margin: Vec3,
        fallbacks: bool,
        tolerance: f64,
    ) -> (InverseMap, Option<Located>) {
        if !x.is_finite() {
            let map = InverseMap {
                uvw: Uvw::new(0.5, 0.5, 0.5),
                converged: false,
                inside: false,
                iterations: 0,
                residual_m: f64::INFINITY,
            };
            return (map, None);
        }
        let rest = self.rest_parameters(x);
        let target = to_f64(x);
        let tol = tolerance * self.region().size().max_element() as f64;
        let hull = self.hull();
        let grown = crate::math::Aabb { min: hull.min - margin, max: hull.max + margin };
        let in_grown = x.cmpge(grown.min).all() && x.cmple(grown.max).all();
        if !in_grown {
            let uvw = clamp_search(rest);
            let residual_m = norm(sub(self.position_f64(uvw), target));
            return (InverseMap { uvw, converged: false, inside: false, iterations: 0, residual_m }, None);
        }
        let mut best = self.newton(target, start.unwrap_or(rest), tol);
        let mut iterations = best.iterations;
        if best.residual > tol && start.is_some() {
            let run = self.newton(target, rest, tol);
            iterations += run.iterations;
            if run.residual < best.residual {
                best = run;
            }
        }
        let in_hull = x.cmpge(hull.min).all() && x.cmple(hull.max).all();
        let converged_inside = |b: &Run| b.residual <= tol && inside(b.uvw);
        if fallbacks && in_hull && !converged_inside(&best) {
            for seed in [self.nearest_control_parameters(target), self.nearest_coarse_node(target)] {
                let run = self.newton(target, seed, tol);
                iterations += run.iterations;
                // Prefer a preimage inside the cube; else the smallest residual.
                let closer = best.residual > tol && run.residual < best.residual;
                if converged_inside(&run) || closer {
                    best = run;
                }
                if converged_inside(&best) {
                    break;
                }
            }
        }
        let converged = best.residual <= tol;
        let map = InverseMap {
            uvw: best.uvw,
            converged,
            inside: converged && inside(best.uvw),
            iterations,
            residual_m: best.residual,
        };
        (map, Some(best.located))
    }

    /// Damped Newton (Levenberg–Marquardt where the Jacobian is singular) from `start`.
    fn newton(&self, target: [f64; 3], start: Uvw, tol: f64) -> Run {
        let mut u = clamp_search(start);
        let mut e = self.locate::<true>(u);
        let mut r = sub(e.position, target);
        let mut err = norm(r);
        let mut iterations = 0;
        while iterations < MAX_ITERATIONS && err > tol {
            iterations += 1;
            let rhs = r.map(|c| -c);
            let trace: f64 = e.jacobian.iter().map(|c| c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sum();
            // Newton first; if it fails to descend, ever more gradient-like LM steps.
            let mut accepted = false;
            for mu in [0.0, 1e-6, 1e-3, 1e-1, 1e1] {
                let Some(delta) = solve(&e.jacobian, rhs, mu * trace.max(f64::MIN_POSITIVE)) else {
                    continue;
                };
                let mut t = 1.0;
                for _ in 0..MAX_HALVINGS {
                    let cand = clamp_search(Uvw(std::array::from_fn(|a| u.0[a] + t * delta[a])));
                    let ec = self.locate::<true>(cand);
                    let rc = sub(ec.position, target);
                    let ec_err = norm(rc);
                    if ec_err < err * (1.0 - 1e-4 * t) || ec_err <= tol {
                        (u, e, r, err) = (cand, ec, rc, ec_err);
                        accepted = true;
                        break;
                    }
                    t *= 0.5;
                }
                if accepted {
                    break;
                }
            }
            if !accepted {
                break;
            }
        }
        Run { uvw: u, residual: err, iterations, located: e }
    }

    /// The Greville parameters (clamped to the cube) of the control point nearest `target`.
    fn nearest_control_parameters(&self, target: [f64; 3]) -> Uvw {
        let nearest = self
            .controls()
            .iter()
            .enumerate()
            .map(|(index, c)| (index, norm(sub(to_f64(c.position_m), target))))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(index, _)| index);
        let [i, j, k] = self.ijk(nearest);
        Uvw::new(self.knots(0).greville(i), self.knots(1).greville(j), self.knots(2).greville(k))
            .clamped_to_unit_cube()
    }

    /// The node of a coarse parameter grid over the cube whose image is nearest `target`.
    fn nearest_coarse_node(&self, target: [f64; 3]) -> Uvw {
        let node = |n: usize| n as f64 / (COARSE - 1) as f64;
        let mut best = (Uvw::new(0.5, 0.5, 0.5), f64::INFINITY);
        for c in 0..COARSE {
            for b in 0..COARSE {
                for a in 0..COARSE {
                    let uvw = Uvw::new(node(a), node(b), node(c));
                    let d = norm(sub(self.position_f64(uvw), target));
                    if d < best.1 {
                        best = (uvw, d);
                    }
                }
            }
        }
        best.0
    }

    /// The density of the deformed solid at world point `x`: the clipped function at the
    /// inverse-mapped parameters, `clip(F(P⁻¹(x)))` (ESM's space and function mapping with
    /// functional clipping). 0 where `x` has no preimage (the search failed or it lies beyond
    /// the clipping band outside the lattice).
    pub fn mapped_density(&self, x: Vec3, clip: &Clipping) -> f32 {
        self.mapped_density_from(x, None, clip).0
    }

    /// As [`Self::mapped_density`] with a warm start; also returns the inverse map.
    pub fn mapped_density_from(&self, x: Vec3, start: Option<Uvw>, clip: &Clipping) -> (f32, InverseMap) {
        let (density, map, _) = self.mapped_density_detailed(x, start, clip);
        (density, map)
    }

    /// As [`Self::mapped_density_from`], with the position and Jacobian at the parameters
    /// found.
    pub(crate) fn mapped_density_detailed(
        &self,
        x: Vec3,
        start: Option<Uvw>,
        clip: &Clipping,
    ) -> (f32, InverseMap, Option<Located>) {
        // Points whose preimage lies beyond the band read 0: refuse them at about the band's
        // width outside the hull (the rest lattice's parameters scale with the box).
        let margin = self.region().size() * clip.band() as f32;
        let (map, eval) = self.inverse_map_within(x, start, margin, true, TOLERANCE);
        let density = match eval {
            Some(_) if map.converged && !clip.is_empty_at(map.uvw) => {
                clip.density(self.value(map.uvw), map.uvw)
            }
            _ => 0.0,
        };
        (density, map, eval)
    }

    /// The first-order prediction of the parameters of `uvw`'s image moved by `step` (world):
    /// `uvw + J⁻¹ step`, or `uvw` where `J` is singular.
    pub(crate) fn predict(uvw: Uvw, jacobian: &[[f64; 3]; 3], step: [f64; 3]) -> Uvw {
        match solve(jacobian, step, 0.0) {
            Some(d) => Uvw(std::array::from_fn(|a| uvw.0[a] + d[a])),
            None => uvw,
        }
    }
}

fn inside(uvw: Uvw) -> bool {
    uvw.0.iter().all(|&t| (-INSIDE_SLACK..=1.0 + INSIDE_SLACK).contains(&t))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Quat;
    use crate::spline::volume::tests::{unit_box, volumes, Rng};
    use crate::spline::{KnotStyle, SplineKind};

    fn round_trip(vol: &SplineVolume, rng: &mut Rng, samples: usize, what: &str) {
        let size = vol.region().size().max_element() as f64;
        let mut worst = 0.0f64;
        let mut iterations = 0;
        for _ in 0..samples {
            let uvw = rng.uvw(0.0, 1.0);
            let x = vol.position_f64(uvw);
            let xv = Vec3::new(x[0] as f32, x[1] as f32, x[2] as f32);
            let map = vol.inverse_map(xv);
            assert!(map.converged, "{what}: {uvw:?} → {xv} did not converge: {map:?}");
            assert!(map.uvw.is_finite());
            let back = vol.position_f64(map.uvw);
            let target = to_f64(xv);
            let err = norm(sub(back, target)) / size;
            worst = worst.max(err);
            assert!(err < 1e-5, "{what}: round trip error {err} of the box");
            iterations += map.iterations;
        }
        eprintln!(
            "{what}: worst round trip {worst:.1e} of the box, {:.1} iterations a point",
            iterations as f64 / samples as f64
        );
    }

    #[test]
    fn an_untouched_lattice_maps_every_point_to_itself() {
        let mut rng = Rng(31);
        for vol in volumes() {
            for _ in 0..200 {
                let uvw = rng.uvw(0.0, 1.0);
                let x = vol.rest_point(uvw);
                let map = vol.inverse_map(x);
                assert!(map.converged && map.inside, "{map:?}");
                assert!(map.iterations <= 2, "the rest start is the answer: {map:?}");
                let rest = vol.rest_parameters(x);
                assert!((0..3).all(|a| (map.uvw.0[a] - rest.0[a]).abs() < 1e-6));
                assert!((vol.position(map.uvw) - x).abs().max_element() < 1e-6);
            }
        }
    }

    fn twisted(
        kind: SplineKind,
        counts: [usize; 3],
        orders: [usize; 3],
        style: KnotStyle,
        turn: f32,
    ) -> SplineVolume {
        let b = unit_box();
        let mut vol = match kind {
            SplineKind::Bezier => SplineVolume::bezier(b, counts).unwrap(),
            SplineKind::BSpline => SplineVolume::bspline(b, counts, orders, style).unwrap(),
            SplineKind::Nurbs => SplineVolume::nurbs(b, counts, orders, style).unwrap(),
        };
        let (c, size) = (b.centre(), b.size());
        vol.update_positions(|_, cp| {
            let t = (cp.rest_m.y - b.min.y) / size.y;
            let q = Quat::from_rotation_y(turn * t);
            c + q * (cp.rest_m - c)
        })
        .unwrap();
        vol
    }

    #[test]
    fn twisted_lattices_round_trip() {
        let mut rng = Rng(37);
        for (kind, counts, orders, style) in [
            (SplineKind::Bezier, [4, 5, 4], [4, 5, 4], KnotStyle::Clamped),
            (SplineKind::BSpline, [8, 8, 8], [4, 4, 4], KnotStyle::Uniform),
            (SplineKind::BSpline, [6, 9, 5], [3, 4, 2], KnotStyle::Clamped),
            (SplineKind::BSpline, [16, 16, 16], [4, 4, 4], KnotStyle::Clamped),
        ] {
            let vol = twisted(kind, counts, orders, style, 1.5);
            round_trip(&vol, &mut rng, 300, &format!("twisted {kind:?} {counts:?} {style:?}"));
        }
        let mut nurbs = twisted(SplineKind::Nurbs, [6, 6, 6], [3, 3, 3], KnotStyle::Clamped, 1.0);
        for (i, j, k, w) in [(1, 2, 3, 5.0), (3, 3, 3, 0.2), (0, 5, 5, 3.0)] {
            nurbs.set_weight(i, j, k, w).unwrap();
        }
        round_trip(&nurbs, &mut rng, 300, "twisted weighted NURBS");
    }

    #[test]
    fn bent_and_stretched_lattices_round_trip() {
        let mut rng = Rng(41);
        let b = unit_box();
        let size = b.size();
        for style in [KnotStyle::Uniform, KnotStyle::Clamped] {
            let mut bent = SplineVolume::bspline(b, [10, 6, 6], [4, 4, 3], style).unwrap();
            // Bend the bar along x into an arc of 90°.
            bent.update_positions(|_, cp| {
                let t = (cp.rest_m.x - b.min.x) / size.x - 0.5;
                let angle = t * std::f32::consts::FRAC_PI_2;
                let radius = size.x / std::f32::consts::FRAC_PI_2;
                let r = radius + (cp.rest_m.y - b.centre().y);
                Vec3::new(
                    b.centre().x + r * angle.sin(),
                    b.centre().y + r * angle.cos() - radius,
                    cp.rest_m.z,
                )
            })
            .unwrap();
            round_trip(&bent, &mut rng, 300, &format!("bent {style:?}"));

            let mut stretched = SplineVolume::bspline(b, [7, 7, 7], [4, 4, 4], style).unwrap();
            // Stretch non-uniformly: x² along x, 3 × along y, squeeze z near the top.
            stretched
                .update_positions(|_, cp| {
                    let t = (cp.rest_m - b.min) / size;
                    b.min + size * Vec3::new(t.x * t.x * 1.5 + 0.2 * t.x, 3.0 * t.y, t.z * (1.0 - 0.5 * t.y))
                })
                .unwrap();
            round_trip(&stretched, &mut rng, 300, &format!("stretched {style:?}"));
        }
        let mut dragged = SplineVolume::bezier(b, [5, 5, 5]).unwrap();
        dragged.set_position(2, 2, 4, b.max + Vec3::new(0.0, 0.1, 0.3)).unwrap();
        round_trip(&dragged, &mut rng, 300, "one dragged Bézier control");
    }

    #[test]
    fn degenerate_lattices_and_far_points_give_no_nan() {
        let b = unit_box();
        let mut collapsed = SplineVolume::bspline(b, [5, 5, 5], [3, 3, 3], KnotStyle::Clamped).unwrap();
        // A whole slab of control points on one point, and then everything on one point.
        collapsed.update_positions(|[i, _, _], cp| if i < 3 { b.centre() } else { cp.rest_m }).unwrap();
        let mut point = collapsed.clone();
        point.update_positions(|_, _| b.centre()).unwrap();
        let mut flat = collapsed.clone();
        flat.update_positions(|_, cp| Vec3::new(cp.rest_m.x, b.centre().y, cp.rest_m.z)).unwrap();
        let clip = Clipping::PAPER;
        let mut rng = Rng(43);
        for vol in [&collapsed, &point, &flat] {
            for x in [
                b.centre(),
                b.min,
                b.max,
                Vec3::new(1e30, -1e30, 0.0),
                Vec3::splat(f32::MAX),
                Vec3::new(f32::NAN, 0.0, 0.0),
                Vec3::new(0.0, f32::INFINITY, 0.0),
            ]
            .into_iter()
            .chain((0..200).map(|_| vol.rest_point(rng.uvw(-0.5, 1.5))))
            {
                let map = vol.inverse_map(x);
                assert!(map.uvw.is_finite(), "{x} → {map:?}");
                assert!(!map.residual_m.is_nan());
                let d = vol.mapped_density(x, &clip);
                assert!(d.is_finite() && (0.0..=1.0).contains(&d));
                let j = vol.jacobian(map.uvw);
                assert!(j.is_finite());
            }
        }
        // All on one point: that point maps (anywhere), others do not.
        assert!(point.inverse_map(b.centre()).converged);
        assert!(!point.inverse_map(b.max).converged);
    }

    #[test]
    fn points_outside_the_lattice_are_reported_outside() {
        let vol = twisted(SplineKind::BSpline, [6, 6, 6], [4, 4, 4], KnotStyle::Clamped, 1.0);
        let far = vol.inverse_map(Vec3::new(10.0, 10.0, 10.0));
        assert!(!far.converged && !far.inside && far.iterations == 0);
        // Just above the top face: maps, outside the cube.
        let top = vol.position(Uvw::new(0.5, 1.0, 0.5)) + Vec3::new(0.0, 0.01, 0.0);
        let map = vol.inverse_map(top);
        assert!(map.converged && !map.inside && map.uvw.0[1] > 1.0, "{map:?}");
        // A warm start from a neighbour converges at least as fast.
        let uvw = Uvw::new(0.3, 0.6, 0.2);
        let x = vol.position(uvw);
        let near = vol.inverse_map_from(x, Some(Uvw::new(0.31, 0.6, 0.2)));
        assert!(near.converged && near.inside);
        assert!(near.iterations <= vol.inverse_map(x).iterations.max(3));
    }

    #[test]
    fn a_translated_lattice_carries_its_solid_along() {
        let b = unit_box();
        let mut vol = SplineVolume::bspline(b, [8, 8, 8], [4, 4, 4], KnotStyle::Clamped).unwrap();
        let c = b.centre();
        vol.update_values(|_, cp| if (cp.rest_m - c).length() < 0.08 { 1.0 } else { 0.0 }).unwrap();
        let before: Vec<f32> = (0..50)
            .map(|s| vol.mapped_density(c + Vec3::new(0.003 * s as f32 - 0.07, 0.01, 0.0), &Clipping::PAPER))
            .collect();
        let offset = Vec3::new(0.05, -0.02, 0.03);
        vol.update_positions(|_, cp| cp.rest_m + offset).unwrap();
        for (s, &d) in before.iter().enumerate() {
            let x = c + offset + Vec3::new(0.003 * s as f32 - 0.07, 0.01, 0.0);
            assert!((vol.mapped_density(x, &Clipping::PAPER) - d).abs() < 1e-5);
        }
        assert!(before.iter().any(|&d| d > 0.5));
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig {
                cases: 48,
                rng_seed: proptest::test_runner::RngSeed::Fixed(73),
                ..ProptestConfig::default()
            })]
            #[test]
            fn any_moderate_deformation_round_trips(
                seed in 1u64..u64::MAX,
                order in 2usize..5,
                count in 5usize..9,
                clamped in any::<bool>(),
                amount in 0.0f32..0.35,
            ) {
                let style = if clamped { KnotStyle::Clamped } else { KnotStyle::Uniform };
                let b = unit_box();
                let mut vol = SplineVolume::bspline(b, [count; 3], [order; 3], style).unwrap();
                // Each control moves by up to `amount` of a lattice spacing on each axis.
                let spacing = b.size() / (count - 1) as f32;
                let mut rng = Rng(seed);
                vol.update_positions(|_, c| c.rest_m + rng.uvw(-1.0, 1.0).to_vec3() * spacing * amount).unwrap();
                let size = b.size().max_element() as f64;
                for _ in 0..20 {
                    let uvw = rng.uvw(0.0, 1.0);
                    let x = vol.position(uvw);
                    let map = vol.inverse_map(x);
                    prop_assert!(map.converged, "{:?} from {:?}", map, uvw);
                    let err = norm(sub(vol.position_f64(map.uvw), to_f64(x))) / size;
                    prop_assert!(err < 1e-5);
                }
            }
        }
    }
}
