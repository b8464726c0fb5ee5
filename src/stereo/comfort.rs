//! Stereo comfort: screen parallax and its visual angle, the parallax budget, and
//! auto-convergence.
//!
//! Screen parallax of a point at distance `Z` from eyes `e` apart, with the zero-parallax plane
//! at distance `D`: `p = e · (Z − D) / Z` (negative, crossed, in front of the plane; positive,
//! uncrossed, behind it). Seen from the viewing distance `V` on the physical display, it spans
//! the visual angle `2·atan(p_display / 2V)`.
//!
//! The budget (after Lambooij et al. 2009) keeps that angle within about 1° either way, and never
//! lets the display's uncrossed parallax exceed the viewer's eye separation (the eyes would have
//! to diverge). Parallax is proportional to the interaxial distance, so the budget's remedy is
//! the largest interaxial that fits: [`BudgetCheck::allowed_interaxial_m`].
//!
//! Auto-convergence moves the zero-parallax plane to a point of interest (the active tool, or the
//! sculpture's centre) through a first-order low-pass filter on the logarithm of the distance:
//!
//! ```text
//!   ln c ← ln c + (ln z − ln c) · (1 − exp(−dt / τ))
//! ```
//!
//! It never overshoots, covers 63 % of a change in τ seconds (95 % in 3τ), treats a change from
//! 30 cm to 60 cm like one from 1 m to 2 m (the eyes feel ratios of distance), and its result does
//! not depend on the frame rate (two steps of `dt` equal one of `2·dt` exactly).

/// Screen parallax (metres on the zero-parallax plane) of a point at `point_distance_m` from
/// eyes `interaxial_m` apart whose zero-parallax plane is at `plane_distance_m`.
pub fn screen_parallax_m(interaxial_m: f32, plane_distance_m: f32, point_distance_m: f32) -> f32 {
    interaxial_m * (point_distance_m - plane_distance_m) / point_distance_m
}

/// The visual angle, degrees, of a parallax `parallax_m` on a display seen from
/// `viewing_distance_m` (signed like the parallax).
pub fn disparity_deg(parallax_m: f32, viewing_distance_m: f32) -> f32 {
    2.0 * (0.5 * parallax_m / viewing_distance_m).atan().to_degrees()
}

/// How a stereo camera's zero-parallax plane maps onto the physical display.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewing {
    /// Distance between the camera's eyes, world metres.
    pub interaxial_m: f32,
    /// Distance from the eyes to the zero-parallax plane, world metres.
    pub convergence_m: f32,
    /// Physical metres on the display per world metre on the zero-parallax plane.
    pub display_per_world: f32,
    /// Distance from the viewer to the display, physical metres.
    pub viewing_distance_m: f32,
    /// The viewer's own eye separation, physical metres.
    pub eye_separation_m: f32,
}

impl Viewing {
    /// Parallax on the display (physical metres) of a point at `distance_m` (world metres).
    pub fn display_parallax_m(&self, distance_m: f32) -> f32 {
        screen_parallax_m(self.interaxial_m, self.convergence_m, distance_m) * self.display_per_world
    }

    /// Visual angle of that parallax, degrees.
    pub fn disparity_deg(&self, distance_m: f32) -> f32 {
        disparity_deg(self.display_parallax_m(distance_m), self.viewing_distance_m)
    }
}

/// Whether the budget warns only or also limits the interaxial distance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BudgetMode {
    /// Report the excess; leave the interaxial alone.
    Warn,
    /// Lower the interaxial until the depth range fits.
    Limit,
}

/// The parallax budget.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParallaxBudget {
    /// Largest comfortable disparity either way, degrees of visual angle.
    pub max_disparity_deg: f32,
    /// Warn or limit.
    pub mode: BudgetMode,
}

impl Default for ParallaxBudget {
    /// 1° either way, warning only.
    fn default() -> Self {
        Self { max_disparity_deg: 1.0, mode: BudgetMode::Warn }
    }
}

/// The budget's verdict on a depth range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BudgetCheck {
    /// Disparity of the nearest point, degrees (negative: crossed).
    pub nearest_deg: f32,
    /// Disparity of the farthest point, degrees (positive: uncrossed).
    pub farthest_deg: f32,
    /// Whether either exceeds the budget, or the far parallax exceeds the eye separation.
    pub exceeded: bool,
    /// The largest interaxial (world metres) that keeps the range within the budget (the
    /// current one when it already fits).
    pub allowed_interaxial_m: f32,
}

impl BudgetCheck {
    /// A sentence for the user when the budget is exceeded.
    pub fn warning(&self, budget: &ParallaxBudget) -> Option<String> {
        self.exceeded.then(|| {
            format!(
                "stereo disparity spans {:.2}° to {:.2}°, beyond the comfortable ±{:.2}°: lower the interaxial to {:.1} mm or bring the convergence plane into the sculpture",
                self.nearest_deg,
                self.farthest_deg,
                budget.max_disparity_deg,
                self.allowed_interaxial_m * 1000.0
            )
        })
    }
}

impl ParallaxBudget {
    /// Checks the depth range `nearest_m..=farthest_m` (distances from the eyes, world metres).
    pub fn check(&self, viewing: &Viewing, nearest_m: f32, farthest_m: f32) -> BudgetCheck {
        let nearest_deg = viewing.disparity_deg(nearest_m);
        let farthest_deg = viewing.disparity_deg(farthest_m);
        let max_rad = self.max_disparity_deg.to_radians();
        // The parallax that subtends the budget's angle at the viewing distance.
        let max_parallax = 2.0 * viewing.viewing_distance_m * (0.5 * max_rad).tan();
        let far_limit = max_parallax.min(viewing.eye_separation_m);
        let near_p = viewing.display_parallax_m(nearest_m).abs();
        let far_p = viewing.display_parallax_m(farthest_m).max(0.0);
        let mut factor = 1.0f32;
        if near_p > max_parallax {
            factor = factor.min(max_parallax / near_p);
        }
        if far_p > far_limit {
            factor = factor.min(far_limit / far_p);
        }
        BudgetCheck {
            nearest_deg,
            farthest_deg,
            exceeded: factor < 1.0,
            allowed_interaxial_m: viewing.interaxial_m * factor,
        }
    }

    /// The interaxial to use: the current one when warning only, else the largest allowed.
    pub fn apply(&self, check: &BudgetCheck, interaxial_m: f32) -> f32 {
        match self.mode {
            BudgetMode::Warn => interaxial_m,
            BudgetMode::Limit => interaxial_m.min(check.allowed_interaxial_m),
        }
    }
}

/// Keeps a point of interest at zero parallax, smoothly (the filter is in the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoConvergence {
    /// Time constant τ of the filter, seconds (> 0).
    pub time_constant_s: f32,
    /// Closest and farthest convergence distance allowed, metres.
    pub range_m: (f32, f32),
    current_m: f32,
}

impl AutoConvergence {
    /// The default time constant: 0.3 s (95 % of a change within a second).
    pub const DEFAULT_TIME_CONSTANT_S: f32 = 0.3;

    /// A filter starting at `initial_m`, its output kept within `range_m`.
    pub fn new(initial_m: f32, time_constant_s: f32, range_m: (f32, f32)) -> Self {
        Self { time_constant_s, range_m, current_m: initial_m.clamp(range_m.0, range_m.1) }
    }

    /// The current convergence distance.
    pub fn current_m(&self) -> f32 {
        self.current_m
    }

    /// Moves towards `target_m` (the point of interest's distance along the view) over `dt_s`
    /// seconds and returns the new convergence distance. A non-finite or non-positive target,
    /// or step, leaves it unchanged.
    pub fn update(&mut self, target_m: f32, dt_s: f32) -> f32 {
        if !(target_m.is_finite() && target_m > 0.0 && dt_s.is_finite() && dt_s > 0.0) {
            return self.current_m;
        }
        let target = target_m.clamp(self.range_m.0, self.range_m.1);
        let alpha = 1.0 - (-dt_s / self.time_constant_s.max(1e-6)).exp();
        let ln = self.current_m.ln() + (target.ln() - self.current_m.ln()) * alpha;
        self.current_m = ln.exp().clamp(self.range_m.0, self.range_m.1);
        self.current_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn desk() -> Viewing {
        Viewing {
            interaxial_m: 0.063,
            convergence_m: 0.6,
            display_per_world: 1.0,
            viewing_distance_m: 0.6,
            eye_separation_m: 0.063,
        }
    }

    #[test]
    fn parallax_and_angle_have_the_expected_signs_and_sizes() {
        assert_eq!(screen_parallax_m(0.063, 0.6, 0.6), 0.0);
        assert!((screen_parallax_m(0.063, 0.6, 1.2) - 0.0315).abs() < 1e-6);
        assert!(screen_parallax_m(0.063, 0.6, 0.3) < 0.0);
        // 1 cm at 60 cm is about 0.955°.
        assert!((disparity_deg(0.01, 0.6) - 0.9549).abs() < 1e-3);
    }

    #[test]
    fn the_budget_warns_and_limits_to_the_largest_fitting_interaxial() {
        let v = desk();
        let budget = ParallaxBudget::default();
        let fits = budget.check(&v, 0.55, 0.7);
        assert!(!fits.exceeded && fits.allowed_interaxial_m == v.interaxial_m);
        assert!(fits.warning(&budget).is_none());
        let deep = budget.check(&v, 0.3, 3.0);
        assert!(deep.exceeded && deep.nearest_deg < -1.0 && deep.farthest_deg > 1.0);
        assert!(deep.warning(&budget).unwrap().contains("interaxial"));
        let limited = Viewing { interaxial_m: deep.allowed_interaxial_m, ..v };
        let after = budget.check(&limited, 0.3, 3.0);
        assert!(after.nearest_deg.abs() <= 1.0 + 1e-4 && after.farthest_deg <= 1.0 + 1e-4, "{after:?}");
        assert_eq!(budget.apply(&deep, v.interaxial_m), v.interaxial_m, "warn only");
        let limit = ParallaxBudget { mode: BudgetMode::Limit, ..budget };
        assert_eq!(limit.apply(&deep, v.interaxial_m), deep.allowed_interaxial_m);
    }

    #[test]
    fn far_parallax_never_exceeds_the_eye_separation() {
        // A generous angle budget on a large display: divergence is the binding limit.
        let v = Viewing { display_per_world: 4.0, viewing_distance_m: 3.0, ..desk() };
        let budget = ParallaxBudget { max_disparity_deg: 5.0, mode: BudgetMode::Limit };
        let c = budget.check(&v, 0.6, 1000.0);
        let limited = Viewing { interaxial_m: c.allowed_interaxial_m, ..v };
        assert!(c.exceeded);
        assert!(limited.display_parallax_m(1000.0) <= v.eye_separation_m * 1.0001);
    }

    #[test]
    fn auto_convergence_ignores_bad_input_and_stays_in_range() {
        let mut a = AutoConvergence::new(0.6, 0.3, (0.1, 10.0));
        assert_eq!(a.update(f32::NAN, 0.01), 0.6);
        assert_eq!(a.update(0.5, -1.0), 0.6);
        for _ in 0..1000 {
            a.update(100.0, 0.1);
        }
        assert!((a.current_m() - 10.0).abs() < 1e-3);
    }

    proptest! {
        /// The filter approaches the target monotonically, never overshoots, reaches 63 % (in
        /// log distance) after one time constant, and does not depend on the frame rate.
        #[test]
        fn auto_convergence_is_smooth_and_frame_rate_independent(
            start in 0.2f32..3.0, target in 0.2f32..3.0, tau in 0.05f32..2.0, dt in 0.001f32..0.05,
        ) {
            let range = (0.1, 10.0);
            let mut a = AutoConvergence::new(start, tau, range);
            let mut previous = start;
            let steps = (tau / dt).round().max(1.0) as usize;
            for _ in 0..steps {
                let c = a.update(target, dt);
                prop_assert!((c - target).abs() <= (previous - target).abs() + 1e-6, "monotone approach");
                prop_assert!((c - target) * (start - target) >= -1e-9, "no overshoot");
                previous = c;
            }
            let elapsed = steps as f32 * dt;
            let expected_fraction = 1.0 - (-elapsed / tau).exp();
            if (target.ln() - start.ln()).abs() > 1e-3 {
                let fraction = (a.current_m().ln() - start.ln()) / (target.ln() - start.ln());
                prop_assert!((fraction - expected_fraction).abs() < 1e-3, "{fraction} vs {expected_fraction}");
            }
            let mut one = AutoConvergence::new(start, tau, range);
            let mut two = AutoConvergence::new(start, tau, range);
            one.update(target, 2.0 * dt);
            two.update(target, dt);
            two.update(target, dt);
            prop_assert!((one.current_m() - two.current_m()).abs() < 1e-4 * one.current_m());
        }
    }
}
