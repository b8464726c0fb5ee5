//! Where the sculpture is in the room, and how hands move it: one grip drags and turns it
//! rigidly with the hand, two grips turn, move and scale it about the midpoint of the hands.
//!
//! ```text
//!   world (scene metres) ──Placement──► stage (room metres, the runtime's reference space)
//!   p_stage = translation + rotation · (scale · p_world)
//!
//!   two grips:  a0 ●━━━━━━● b0      →      a1 ●━━━━━━━━━━● b1
//!                    m0                          m1
//!   the world point under each hand stays under it: the placement is scaled by |b1−a1|/|b0−a0|,
//!   turned by the shortest arc from (b0−a0) to (b1−a1), and moved from m0 to m1.
//! ```
//!
//! The scale is clamped to [`SCALE_RANGE`] and always positive, and the turn is a rotation,
//! so the sculpture is never mirrored.

use crate::math::{Mat4, Pose, Quat, Vec3};

/// The scales a grab may give the sculpture (room metres per scene metre).
pub const SCALE_RANGE: (f32, f32) = (0.05, 20.0);

/// Hands closer than this give no scale or turn (only the midpoint's move).
const MIN_SPAN_M: f32 = 1e-3;

/// A similarity transform from scene (world) metres to the room (stage space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Room metres per scene metre (positive).
    pub scale: f32,
    /// Turn.
    pub rotation: Quat,
    /// Where the scene's origin is in the room, metres.
    pub translation_m: Vec3,
}

impl Default for Placement {
    fn default() -> Self {
        Self { scale: 1.0, rotation: Quat::IDENTITY, translation_m: Vec3::ZERO }
    }
}

impl Placement {
    /// The room position of a scene point.
    pub fn to_stage(&self, p_world: Vec3) -> Vec3 {
        self.translation_m + self.rotation * (self.scale * p_world)
    }

    /// The scene position of a room point.
    pub fn to_world(&self, p_stage: Vec3) -> Vec3 {
        self.rotation.inverse() * (p_stage - self.translation_m) / self.scale
    }

    /// A room pose (a hand) in the scene: position and orientation (the scale aside).
    pub fn pose_to_world(&self, pose: Pose) -> Pose {
        Pose { position_m: self.to_world(pose.position_m), rotation: self.rotation.inverse() * pose.rotation }
    }

    /// Scene → room, as a matrix.
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(Vec3::splat(self.scale), self.rotation, self.translation_m)
    }

    /// The placement that puts the scene point `target_world` at `at_stage`, upright, at
    /// scale 1 (the recentre action).
    pub fn centred(target_world: Vec3, at_stage: Vec3) -> Self {
        Self { scale: 1.0, rotation: Quat::IDENTITY, translation_m: at_stage - target_world }
    }
}

/// One hand gripping: the sculpture follows the hand rigidly from `hand_start` to `hand_now`
/// (room poses), starting from `start`.
pub fn one_hand_grab(start: &Placement, hand_start: Pose, hand_now: Pose) -> Placement {
    let turn = (hand_now.rotation * hand_start.rotation.inverse()).normalize();
    Placement {
        scale: start.scale,
        rotation: (turn * start.rotation).normalize(),
        translation_m: hand_now.position_m + turn * (start.translation_m - hand_start.position_m),
    }
}

/// Both hands gripping: from the hands at `start_hands` (room positions, dominant and other)
/// with the sculpture at `start`, to the hands at `now_hands`. The world points under the
/// hands stay under them (as far as the scale clamp allows); the midpoint of the hands is the
/// pivot of the turn and the scale.
pub fn two_hand_grab(start: &Placement, start_hands: (Vec3, Vec3), now_hands: (Vec3, Vec3)) -> Placement {
    let (a0, b0) = start_hands;
    let (a1, b1) = now_hands;
    let (m0, m1) = ((a0 + b0) * 0.5, (a1 + b1) * 0.5);
    let (d0, d1) = (b0 - a0, b1 - a1);
    let (span0, span1) = (d0.length(), d1.length());
    let (factor, turn) =
        if span0 < MIN_SPAN_M || span1 < MIN_SPAN_M || !span0.is_finite() || !span1.is_finite() {
            (1.0, Quat::IDENTITY)
        } else {
            (span1 / span0, Quat::from_rotation_arc(d0 / span0, d1 / span1))
        };
    let scale = (start.scale * factor).clamp(SCALE_RANGE.0, SCALE_RANGE.1);
    let factor = scale / start.scale;
    Placement {
        scale,
        rotation: (turn * start.rotation).normalize(),
        translation_m: m1 + turn * (factor * (start.translation_m - m0)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
        (a - b).length() <= tolerance
    }

    fn vec3() -> impl Strategy<Value = Vec3> {
        (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    fn placement() -> impl Strategy<Value = Placement> {
        (0.2f32..5.0, vec3(), -3.0f32..3.0, vec3()).prop_map(|(scale, axis, angle, t)| Placement {
            scale,
            rotation: Quat::from_axis_angle(axis.try_normalize().unwrap_or(Vec3::Y), angle),
            translation_m: t,
        })
    }

    #[test]
    fn placements_round_trip_and_match_their_matrix() {
        let p = Placement {
            scale: 2.0,
            rotation: Quat::from_rotation_y(0.7),
            translation_m: Vec3::new(0.1, 1.2, -0.4),
        };
        let x = Vec3::new(0.3, -0.2, 0.05);
        assert!(close(p.to_world(p.to_stage(x)), x, 1e-5));
        assert!(close(p.matrix().transform_point3(x), p.to_stage(x), 1e-5));
        let c = Placement::centred(Vec3::new(0.0, 0.1, 0.0), Vec3::new(0.0, 1.2, -0.5));
        assert!(close(c.to_stage(Vec3::new(0.0, 0.1, 0.0)), Vec3::new(0.0, 1.2, -0.5), 1e-6));
    }

    #[test]
    fn pulling_the_hands_apart_doubles_the_sculpture_about_their_midpoint() {
        let start = Placement::default();
        let p = two_hand_grab(
            &start,
            (Vec3::new(-0.1, 1.0, 0.0), Vec3::new(0.1, 1.0, 0.0)),
            (Vec3::new(-0.2, 1.0, 0.0), Vec3::new(0.2, 1.0, 0.0)),
        );
        assert!((p.scale - 2.0).abs() < 1e-5);
        assert!(close(p.to_stage(Vec3::new(0.0, 1.0, 0.0)), Vec3::new(0.0, 1.0, 0.0), 1e-5));
        assert!(close(p.to_stage(Vec3::new(0.1, 1.0, 0.0)), Vec3::new(0.2, 1.0, 0.0), 1e-5));
    }

    #[test]
    fn crossing_the_hands_turns_and_never_mirrors() {
        // The hands swap sides: a half turn about the vertical, not a mirror.
        let p = two_hand_grab(
            &Placement::default(),
            (Vec3::new(-0.1, 1.0, 0.0), Vec3::new(0.1, 1.0, 0.0)),
            (Vec3::new(0.1, 1.0, 0.0), Vec3::new(-0.1, 1.0, 0.0)),
        );
        assert!(p.scale > 0.0);
        assert!(p.matrix().determinant() > 0.0);
        assert!(close(p.to_stage(Vec3::new(-0.1, 1.0, 0.0)), Vec3::new(0.1, 1.0, 0.0), 1e-4));
        // Hands on top of each other: only the move, no scale or turn.
        let q = two_hand_grab(&Placement::default(), (Vec3::ZERO, Vec3::ZERO), (Vec3::X, Vec3::X));
        assert_eq!((q.scale, q.rotation), (1.0, Quat::IDENTITY));
        assert!(close(q.translation_m, Vec3::X, 1e-6));
    }

    #[test]
    fn one_hand_carries_the_sculpture_rigidly() {
        let start = Placement { scale: 1.5, ..Placement::default() };
        let h0 = Pose { position_m: Vec3::new(0.2, 1.0, 0.0), rotation: Quat::IDENTITY };
        let h1 = Pose { position_m: Vec3::new(0.0, 1.2, 0.3), rotation: Quat::from_rotation_x(0.5) };
        let p = one_hand_grab(&start, h0, h1);
        let under = start.to_world(h0.position_m);
        assert!(close(p.to_stage(under), h1.position_m, 1e-5));
        assert_eq!(p.scale, 1.5);
    }

    proptest! {
        #[test]
        fn the_points_under_the_hands_stay_under_them(
            start in placement(), a0 in vec3(), b0 in vec3(), a1 in vec3(), b1 in vec3(),
        ) {
            prop_assume!((b0 - a0).length() > 0.05 && (b1 - a1).length() > 0.05);
            let p = two_hand_grab(&start, (a0, b0), (a1, b1));
            prop_assert!(p.scale >= SCALE_RANGE.0 && p.scale <= SCALE_RANGE.1);
            prop_assert!(p.matrix().determinant() > 0.0, "mirrored: {p:?}");
            prop_assert!((p.rotation.length() - 1.0).abs() < 1e-4);
            // The midpoint is the pivot, whatever the clamp did.
            let m0 = start.to_world((a0 + b0) * 0.5);
            prop_assert!(close(p.to_stage(m0), (a1 + b1) * 0.5, 1e-3));
            let unclamped = start.scale * (b1 - a1).length() / (b0 - a0).length();
            if unclamped > SCALE_RANGE.0 && unclamped < SCALE_RANGE.1 {
                prop_assert!(close(p.to_stage(start.to_world(a0)), a1, 2e-3));
                prop_assert!(close(p.to_stage(start.to_world(b0)), b1, 2e-3));
            }
        }

        #[test]
        fn holding_still_changes_nothing(start in placement(), a in vec3(), b in vec3()) {
            let p = two_hand_grab(&start, (a, b), (a, b));
            prop_assert!((p.scale - start.scale).abs() <= 1e-5 * start.scale);
            let x = Vec3::new(0.1, 0.2, 0.3);
            prop_assert!(close(p.to_stage(x), start.to_stage(x), 1e-4));
        }
    }
}
