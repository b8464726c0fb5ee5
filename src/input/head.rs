//! The head pose the stereo rig uses, from a tracker that may drop out.
//!
//! While samples arrive the head is where the tracker says. When they stop, the last pose is
//! held for `hold_s` (a blink of the camera, a hand across the face), then the view eases back
//! to the default eye position over `ease_s` with a smoothstep (zero speed at both ends), and
//! stays there. The shipped timings are 0.5 s and 1 s (`calibration/screen.toml`, `[tracker]`).
//! When samples come back the head follows them at once: a correct view matters more than a
//! smooth one.
//!
//! ```text
//!  pose   tracked ─────────┐ hold ┌─╮ ease (smoothstep)
//!                          │      │  ╰──╮
//!  default ················│······│·····╰──────────
//!                     last sample  +hold_s  +hold_s+ease_s
//! ```

use crate::math::Pose;

/// Dropout timings, seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DropoutTimings {
    /// How long the last pose is held.
    pub hold_s: f32,
    /// How long the return to the default pose takes.
    pub ease_s: f32,
}

/// Turns a tracker's newest sample (if any) into the head pose to render from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadFilter {
    default: Pose,
    timings: DropoutTimings,
    last: Option<(Pose, f64, u64)>,
}

impl HeadFilter {
    /// A filter resting at `default` (screen space) until a sample arrives.
    pub fn new(default: Pose, timings: DropoutTimings) -> Self {
        Self { default, timings, last: None }
    }

    /// The head pose at `now_s`, given the tracker's newest sample `(pose, arrival time,
    /// sequence number)`. A sample with a sequence number already seen is not new: its age
    /// counts towards the dropout.
    pub fn update(&mut self, newest: Option<(Pose, f64, u64)>, now_s: f64) -> Pose {
        if let Some(sample) = newest {
            // The same datagram again keeps its arrival time; its pose may have changed (the
            // viewer recentred the tracker).
            self.last = Some(sample);
        }
        let Some((pose, at_s, _)) = self.last else { return self.default };
        let age = (now_s - at_s).max(0.0) as f32;
        if age <= self.timings.hold_s {
            return pose;
        }
        let u = if self.timings.ease_s > 0.0 {
            ((age - self.timings.hold_s) / self.timings.ease_s).min(1.0)
        } else {
            1.0
        };
        pose.lerp(&self.default, u * u * (3.0 - 2.0 * u))
    }

    /// Whether the tracker counts as lost at `now_s` (the hold has run out).
    pub fn lost(&self, now_s: f64) -> bool {
        self.last.is_none_or(|(_, at_s, _)| (now_s - at_s) as f32 > self.timings.hold_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Quat, Vec3};

    fn pose(x: f32) -> Pose {
        Pose { position_m: Vec3::new(x, 0.0, 0.6), rotation: Quat::from_rotation_y(x) }
    }

    #[test]
    fn dropout_holds_then_eases_back_to_the_default() {
        let default = pose(0.0);
        let mut f = HeadFilter::new(default, DropoutTimings { hold_s: 0.5, ease_s: 1.0 });
        assert_eq!(f.update(None, 0.0), default, "nothing tracked yet");
        let tracked = pose(0.2);
        assert_eq!(f.update(Some((tracked, 1.0, 1)), 1.0), tracked);
        // The same sample again is not news: it ages.
        assert_eq!(f.update(Some((tracked, 1.0, 1)), 1.5), tracked, "held");
        assert!(!f.lost(1.5) && f.lost(1.51));
        let mut previous = tracked.position_m.x;
        for i in 1..=20 {
            let x = f.update(Some((tracked, 1.0, 1)), 1.5 + f64::from(i) * 0.05).position_m.x;
            assert!(x <= previous && x >= 0.0, "eases monotonically towards the default");
            previous = x;
        }
        let halfway = f.update(None, 2.0).position_m.x;
        assert!((halfway - 0.1).abs() < 1e-6, "smoothstep is half way at half the ease: {halfway}");
        assert_eq!(f.update(None, 2.5), default);
        assert_eq!(f.update(None, 100.0), default);
        let back = pose(-0.1);
        assert_eq!(f.update(Some((back, 100.0, 2)), 100.0), back, "a new sample is followed at once");
    }

    #[test]
    fn zero_ease_returns_at_once() {
        let mut f = HeadFilter::new(pose(0.0), DropoutTimings { hold_s: 0.0, ease_s: 0.0 });
        f.update(Some((pose(0.3), 0.0, 1)), 0.0);
        assert_eq!(f.update(None, 0.001), pose(0.0));
    }
}
