//! Clutch (relative) mode, after Galyean–Hughes §2.2.2: the hand moves the tool the way a
//! mouse moves a cursor, and holding the clutch is lifting the mouse off the pad.
//!
//! ```text
//!  hand:    A ──────► B   (held) B ──back──► A   A ──────► B
//!  clutch:  engaged        held                  engaged
//!  tool:    T ──────► T+g(B−A)   stays put       T+g(B−A) ──────► T+2g(B−A)
//! ```
//!
//! Contract: while the clutch is held the tool does not move, whatever the hand does; on
//! release nothing jumps (the hand's pose at release becomes the new reference). While
//! engaged, each motion of the hand between two engaged samples is applied to the tool
//! relative, scaled by a gain (below 1 for fine work: the whole reach of the arm then maps to
//! a small part of the sculpting space). Translation is taken in world space; rotation is the
//! hand's world-frame rotation increment, scaled in angle, and turns the tool about its own
//! position.

use crate::math::{Pose, Quat};

/// How hand motion scales into tool motion while engaged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClutchGains {
    /// Tool metres per hand metre.
    pub translation: f32,
    /// Tool angle per hand angle.
    pub rotation: f32,
}

impl Default for ClutchGains {
    /// One to one.
    fn default() -> Self {
        Self { translation: 1.0, rotation: 1.0 }
    }
}

/// The relative-mode state of one hand's tool.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clutch {
    tool: Pose,
    gains: ClutchGains,
    /// The hand at the last engaged sample; `None` after a hold, a bad sample, or at start.
    reference: Option<Pose>,
}

impl Clutch {
    /// A clutch whose tool starts at `tool`.
    pub fn new(tool: Pose, gains: ClutchGains) -> Self {
        Self { tool, gains, reference: None }
    }

    /// Feeds one hand sample and whether the clutch is held; returns the tool pose.
    ///
    /// A hand pose that is not finite is ignored and makes the next good sample the new
    /// reference, so a tracking glitch never throws the tool.
    pub fn update(&mut self, hand: Pose, clutch_held: bool) -> Pose {
        if clutch_held || !(hand.position_m.is_finite() && hand.rotation.is_finite()) {
            self.reference = None;
            return self.tool;
        }
        if let Some(previous) = self.reference {
            let step = hand.position_m - previous.position_m;
            let mut turn = hand.rotation * previous.rotation.inverse();
            // The short way round: q and −q are the same rotation, and scaling the angle of the
            // long one would turn the tool the wrong way.
            if turn.w < 0.0 {
                turn = -turn;
            }
            let scaled = Quat::from_scaled_axis(turn.normalize().to_scaled_axis() * self.gains.rotation);
            self.tool.position_m += step * self.gains.translation;
            // Renormalise so thousands of small increments do not drift off unit length.
            self.tool.rotation = (scaled * self.tool.rotation).normalize();
        }
        self.reference = Some(hand);
        self.tool
    }

    /// The tool pose.
    pub fn tool(&self) -> Pose {
        self.tool
    }

    /// Places the tool (a reset or a snap); the hand's next sample becomes the reference.
    pub fn set_tool(&mut self, tool: Pose) {
        self.tool = tool;
        self.reference = None;
    }

    /// The gains.
    pub fn gains(&self) -> ClutchGains {
        self.gains
    }

    /// Changes the gains; motion already applied stays.
    pub fn set_gains(&mut self, gains: ClutchGains) {
        self.gains = gains;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use proptest::prelude::*;
    use std::f32::consts::FRAC_PI_2;

    fn at(x: f32, y: f32, z: f32) -> Pose {
        Pose { position_m: Vec3::new(x, y, z), rotation: Quat::IDENTITY }
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    fn same_rotation(a: Quat, b: Quat) -> bool {
        a.dot(b).abs() > 1.0 - 1e-5
    }

    #[test]
    fn ratcheting_moves_the_tool_further_than_the_reach() {
        let mut c = Clutch::new(Pose::default(), ClutchGains::default());
        c.update(at(0.0, 0.0, 0.0), false);
        assert!(close(c.update(at(0.1, 0.0, 0.0), false).position_m, Vec3::X * 0.1));
        // Held: the hand goes back, the tool stays.
        c.update(at(0.1, 0.0, 0.0), true);
        assert!(close(c.update(at(0.0, 0.05, 0.0), true).position_m, Vec3::X * 0.1));
        c.update(at(0.0, 0.0, 0.0), true);
        // Released where the hand is: no jump; then the same stroke again.
        assert!(close(c.update(at(0.0, 0.0, 0.0), false).position_m, Vec3::X * 0.1));
        assert!(close(c.update(at(0.1, 0.0, 0.0), false).position_m, Vec3::X * 0.2));
    }

    #[test]
    fn a_small_gain_gives_fine_control() {
        let mut c = Clutch::new(at(1.0, 2.0, 3.0), ClutchGains { translation: 0.25, rotation: 1.0 });
        c.update(at(0.5, 0.5, 0.5), false);
        let tool = c.update(at(0.7, 0.5, 0.1), false);
        assert!(close(tool.position_m, Vec3::new(1.05, 2.0, 2.9)), "{}", tool.position_m);
    }

    #[test]
    fn rotation_turns_the_tool_about_itself_scaled_by_the_rotation_gain() {
        for (gain, angle) in [(1.0, FRAC_PI_2), (0.5, FRAC_PI_2 / 2.0), (0.0, 0.0)] {
            let start = Pose { position_m: Vec3::new(0.0, 0.1, 0.0), rotation: Quat::from_rotation_x(0.3) };
            let mut c = Clutch::new(start, ClutchGains { translation: 1.0, rotation: gain });
            // The hand is away from the tool and turns about its own centre.
            let hand = at(0.3, 0.0, 0.0);
            c.update(hand, false);
            let turned = Pose { rotation: Quat::from_rotation_y(FRAC_PI_2), ..hand };
            let tool = c.update(turned, false);
            assert!(close(tool.position_m, start.position_m), "gain {gain}: the tool turns in place");
            let expected = Quat::from_rotation_y(angle) * start.rotation;
            assert!(
                same_rotation(tool.rotation, expected),
                "gain {gain}: {:?} vs {expected:?}",
                tool.rotation
            );
        }
    }

    #[test]
    fn turning_the_long_way_is_scaled_the_short_way() {
        let mut c = Clutch::new(Pose::default(), ClutchGains { translation: 1.0, rotation: 0.5 });
        c.update(Pose::default(), false);
        // −q for a 20° turn: the same rotation with a negative w.
        let q = -Quat::from_rotation_z(20f32.to_radians());
        let tool = c.update(Pose { rotation: q, ..Pose::default() }, false);
        assert!(
            same_rotation(tool.rotation, Quat::from_rotation_z(10f32.to_radians())),
            "{:?}",
            tool.rotation
        );
    }

    #[test]
    fn held_rotation_is_ignored_and_release_does_not_jump() {
        let mut c = Clutch::new(Pose::default(), ClutchGains::default());
        c.update(Pose::default(), false);
        let far = Pose { position_m: Vec3::splat(0.4), rotation: Quat::from_rotation_z(1.0) };
        c.update(far, true);
        assert_eq!(c.update(far, false), Pose::default(), "the release sample is the new reference");
        let tool = c.update(Pose { position_m: far.position_m + Vec3::Y * 0.01, ..far }, false);
        assert!(close(tool.position_m, Vec3::Y * 0.01));
        assert!(same_rotation(tool.rotation, Quat::IDENTITY));
    }

    #[test]
    fn a_bad_hand_sample_is_ignored_without_a_jump() {
        let mut c = Clutch::new(Pose::default(), ClutchGains::default());
        c.update(at(0.0, 0.0, 0.0), false);
        let nan = Pose { position_m: Vec3::NAN, rotation: Quat::IDENTITY };
        assert_eq!(c.update(nan, false), Pose::default());
        // The tracker comes back elsewhere: that is the new reference, not a jump.
        assert_eq!(c.update(at(0.5, 0.0, 0.0), false), Pose::default());
        assert!(close(c.update(at(0.6, 0.0, 0.0), false).position_m, Vec3::X * 0.1));
    }

    #[test]
    fn set_tool_and_set_gains() {
        let mut c = Clutch::new(Pose::default(), ClutchGains::default());
        c.update(at(0.0, 0.0, 0.0), false);
        c.set_tool(at(1.0, 0.0, 0.0));
        assert_eq!(c.update(at(0.3, 0.0, 0.0), false), at(1.0, 0.0, 0.0), "no jump after set_tool");
        c.set_gains(ClutchGains { translation: 0.1, rotation: 1.0 });
        assert_eq!(c.gains().translation, 0.1);
        assert!(close(c.update(at(0.4, 0.0, 0.0), false).position_m, Vec3::new(1.01, 0.0, 0.0)));
        assert!(close(c.tool().position_m, Vec3::new(1.01, 0.0, 0.0)));
    }

    fn pose() -> impl Strategy<Value = Pose> {
        (
            (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
            (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
            -std::f32::consts::PI..std::f32::consts::PI,
        )
            .prop_map(|((x, y, z), (ax, ay, az), angle)| {
                let axis = Vec3::new(ax, ay, az).try_normalize().unwrap_or(Vec3::Y);
                Pose { position_m: Vec3::new(x, y, z), rotation: Quat::from_axis_angle(axis, angle) }
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 256,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x434c_5554),
            ..ProptestConfig::default()
        })]

        /// With unit gains and the clutch never held, the tool follows the hand rigidly:
        /// it moves by the hand's displacement and turns by the hand's rotation.
        #[test]
        fn unit_gain_follows_the_hand(start in pose(), hands in proptest::collection::vec(pose(), 1..40)) {
            let mut c = Clutch::new(start, ClutchGains::default());
            for h in &hands {
                c.update(*h, false);
            }
            let (first, last) = (hands[0], hands[hands.len() - 1]);
            let tool = c.tool();
            prop_assert!((tool.position_m - (start.position_m + last.position_m - first.position_m)).length() < 1e-4);
            let expected = last.rotation * first.rotation.inverse() * start.rotation;
            prop_assert!(tool.rotation.dot(expected).abs() > 1.0 - 1e-4, "{:?} vs {:?}", tool.rotation, expected);
            prop_assert!((tool.rotation.length() - 1.0).abs() < 1e-5);
        }

        /// The tool moves by the gain times the hand motion between consecutive engaged
        /// samples, and not at all for motion that touches a held sample.
        #[test]
        fn only_engaged_motion_counts(
            gain in 0.0f32..2.0,
            steps in proptest::collection::vec(((-0.1f32..0.1, -0.1f32..0.1, -0.1f32..0.1), any::<bool>()), 1..60),
        ) {
            let mut c = Clutch::new(Pose::default(), ClutchGains { translation: gain, rotation: 1.0 });
            let mut hand = Vec3::ZERO;
            let mut expected = Vec3::ZERO;
            let mut previous_engaged = false;
            for ((x, y, z), held) in steps {
                let step = Vec3::new(x, y, z);
                hand += step;
                if previous_engaged && !held {
                    expected += step * gain;
                }
                let tool = c.update(Pose { position_m: hand, rotation: Quat::IDENTITY }, held);
                prop_assert!((tool.position_m - expected).length() < 1e-4, "{} vs {}", tool.position_m, expected);
                previous_engaged = !held;
            }
        }
    }
}
