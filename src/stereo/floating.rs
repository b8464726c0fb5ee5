//! The floating stereoscopic window: black strips on the pictures' side edges that bring the
//! frame forward to the clay it cuts.
//!
//! Clay in front of the zero-parallax plane (crossed parallax) that runs off a side edge of
//! the picture is cut by a frame that looks farther away than the clay itself: the eyes read
//! the frame as an occluder behind what it occludes (a frame violation), and the clay seems to
//! be pulled back into the screen. Stereo film and games answer with a floating window: the
//! left eye's picture loses a strip at its left edge and the right eye's a strip at its right
//! edge, each as wide as the crossed parallax of the nearest clay at that edge, so that the
//! edge of the picture itself shows that parallax and sits at (or in front of) the clay.
//!
//! ```text
//!      left eye's picture              right eye's picture
//!   ┌──┬────────────────────┐      ┌────────────────────┬──┐
//!   │▓▓│                    │      │                    │▓▓│   ▓ masked: the edge's parallax
//!   │▓▓│   clay ◀─ cut here │      │                    │▓▓│     is −(strip width), crossed
//!   └──┴────────────────────┘      └────────────────────┴──┘
//! ```
//!
//! A point of the clay at the left edge: its right-eye image `x_R` lies on the edge, its
//! left-eye image `x_L = x_R + |p|` (crossed parallax `p = x_R − x_L < 0`). Masking the left
//! eye's picture up to `|p|` puts the left eye's edge where the point is, so the edge has the
//! point's parallax. The right edge mirrors it. Clay counts as touching an edge where its
//! image lies within [`EDGE_BAND`] of it, on either side (the part just outside the picture is
//! what the edge cuts); clay above or below the picture does not count, nor does clay behind
//! the zero-parallax plane, which the frame cuts correctly.

use crate::math::Vec3;
use crate::render::StereoViews;

/// How far from a side edge (a fraction of the picture's width, either side of it) clay
/// counts as touching it.
pub const EDGE_BAND: f32 = 0.03;

/// The widest strip masked, a fraction of the picture's width: clay nearer the viewer than
/// this would cost more of the picture than the window is worth (and is far over any parallax
/// budget).
pub const MAX_STRIP: f32 = 0.1;

/// Seconds in which an eased window covers about two thirds of the way to the measured one.
pub const EASE_TIME_S: f32 = 0.15;

/// The strips masked on one picture: fractions of its width, from its left and right edges.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EdgeStrips {
    /// From the left edge, in [0, [`MAX_STRIP`]].
    pub left: f32,
    /// From the right edge, in [0, [`MAX_STRIP`]].
    pub right: f32,
}

/// The floating window of a stereo pair: the strips of each eye's picture, `[left, right]`
/// in the order of [`StereoViews::eyes`] (the left eye's picture masks its left edge, the
/// right eye's its right edge).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FloatingWindow {
    /// Per picture, as `StereoViews::eyes`.
    pub strips: [EdgeStrips; 2],
}

impl FloatingWindow {
    /// No strips: the pictures whole.
    pub const NONE: Self = Self { strips: [EdgeStrips { left: 0.0, right: 0.0 }; 2] };

    /// The window for `views` (left eye then right) and clay sampled at `points` (world
    /// metres): each edge's strip is the crossed parallax of the nearest clay touching it, as a
    /// fraction of the picture's width, at most [`MAX_STRIP`].
    pub fn measure(views: &StereoViews, points: impl IntoIterator<Item = Vec3>) -> Self {
        let [left_eye, right_eye] = views.eyes.map(|e| e.projection * e.view);
        let band = 2.0 * EDGE_BAND; // in normalised device coordinates, 2 across
        let (mut left_edge, mut right_edge) = (0.0f32, 0.0f32);
        for p in points {
            let (l, r) = (left_eye * p.extend(1.0), right_eye * p.extend(1.0));
            // Crossed parallax, a fraction of the width (2 across in device coordinates); a point
            // behind an eye, above or below the picture, or not finite, is skipped.
            let (x_l, x_r) = (l.x / l.w, r.x / r.w);
            let crossed = 0.5 * (x_l - x_r);
            let in_view = l.w > 0.0 && r.w > 0.0 && (l.y / l.w).abs() <= 1.0;
            if !in_view || crossed.is_nan() || crossed <= 0.0 {
                continue;
            }
            if (x_r + 1.0).abs() <= band {
                left_edge = left_edge.max(crossed);
            }
            if (x_l - 1.0).abs() <= band {
                right_edge = right_edge.max(crossed);
            }
        }
        Self {
            strips: [
                EdgeStrips { left: left_edge.min(MAX_STRIP), right: 0.0 },
                EdgeStrips { left: 0.0, right: right_edge.min(MAX_STRIP) },
            ],
        }
    }

    /// The window moved from `self` towards `target` over `dt_s` seconds, exponentially with
    /// [`EASE_TIME_S`]: the strips slide in and out rather than jump as the clay moves.
    pub fn eased(self, target: Self, dt_s: f32) -> Self {
        let k = if dt_s.is_finite() && dt_s > 0.0 { 1.0 - (-dt_s / EASE_TIME_S).exp() } else { 0.0 };
        let mix = |a: f32, b: f32| a + (b - a) * k;
        let strips = std::array::from_fn(|i| EdgeStrips {
            left: mix(self.strips[i].left, target.strips[i].left),
            right: mix(self.strips[i].right, target.strips[i].right),
        });
        Self { strips }
    }

    /// The window of the pictures swapped between the eyes (as `[display] swap_eyes` swaps
    /// the views): each strip goes with its picture.
    pub fn swapped(self) -> Self {
        Self { strips: [self.strips[1], self.strips[0]] }
    }

    /// The widest strip, a fraction of the picture's width.
    pub fn widest(&self) -> f32 {
        self.strips.iter().map(|s| s.left.max(s.right)).fold(0.0, f32::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stereo::StereoRig;

    fn rig() -> StereoRig {
        StereoRig {
            eye_m: Vec3::new(0.0, 0.0, 1.0),
            target_m: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 40.0,
            interaxial_m: 0.065,
            convergence_m: 1.0,
            near_m: 0.05,
            far_m: 10.0,
        }
    }

    /// The horizontal half-width of the view at distance `d` in front of the centre eye.
    fn half_width_at(rig: &StereoRig, aspect: f32, d: f32) -> f32 {
        d * (rig.fov_y_deg.to_radians() * 0.5).tan() * aspect
    }

    #[test]
    fn clay_in_front_cut_by_the_left_edge_masks_the_left_eye_by_its_parallax() {
        let (rig, aspect) = (rig(), 1.5);
        let views = rig.views(aspect);
        // A column of points 0.4 m in front of the zero-parallax plane (0.6 m from the eyes),
        // on the left edge of the right eye's picture.
        let d = 0.6;
        let w = half_width_at(&rig, aspect, d);
        // The right eye sits e/2 to the right; its frustum's left edge at depth d.
        let e = rig.interaxial_m;
        let x_edge = -w + e * 0.5 * (1.0 - d / rig.convergence_m);
        let column: Vec<Vec3> = (-5..=5).map(|i| Vec3::new(x_edge, i as f32 * 0.02, 1.0 - d)).collect();
        let window = FloatingWindow::measure(&views, column);
        // p = e (Z − C) / Z on the convergence plane, whose width is 2 C tan · aspect.
        let expected = e * (rig.convergence_m - d) / d / (2.0 * half_width_at(&rig, aspect, 1.0));
        assert!((window.strips[0].left - expected).abs() < 1e-4, "{window:?}, expected {expected}");
        assert_eq!(window.strips[0].right, 0.0);
        assert_eq!(window.strips[1], EdgeStrips::default(), "the right eye keeps its picture whole");
        // Swapped pictures carry their strips with them.
        assert_eq!(window.swapped().strips[1].left, window.strips[0].left);
    }

    #[test]
    fn the_right_edge_mirrors_the_left() {
        let (rig, aspect) = (rig(), 1.5);
        let views = rig.views(aspect);
        let d = 0.6;
        let w = half_width_at(&rig, aspect, d);
        let x_edge = w - rig.interaxial_m * 0.5 * (1.0 - d / rig.convergence_m);
        let window = FloatingWindow::measure(&views, [Vec3::new(x_edge, 0.0, 1.0 - d)]);
        let left_case = FloatingWindow::measure(&views, [Vec3::new(-x_edge, 0.0, 1.0 - d)]);
        assert!(window.strips[1].right > 0.0);
        assert!((window.strips[1].right - left_case.strips[0].left).abs() < 1e-5);
        assert_eq!(window.strips[0], EdgeStrips::default());
    }

    #[test]
    fn clay_behind_the_screen_inside_the_picture_or_above_it_masks_nothing() {
        let (rig, aspect) = (rig(), 1.5);
        let views = rig.views(aspect);
        let edge = |d: f32| -half_width_at(&rig, aspect, d);
        let points = [
            // Behind the zero-parallax plane, on the left edge: uncrossed.
            Vec3::new(edge(1.6), 0.0, 1.0 - 1.6),
            // In front, well inside the picture.
            Vec3::new(0.0, 0.0, 0.5),
            // In front and on the left edge, but above the picture.
            Vec3::new(edge(0.6), 0.6, 0.4),
            // Behind the eyes.
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(f32::NAN, 0.0, 0.5),
        ];
        assert_eq!(FloatingWindow::measure(&views, points), FloatingWindow::NONE);
    }

    #[test]
    fn the_strip_is_bounded_and_easing_approaches_without_overshoot() {
        let (rig, aspect) = (rig(), 1.5);
        let views = rig.views(aspect);
        // Clay a few centimetres from the eyes, at the left edge: a huge parallax.
        let d = 0.08;
        let x = -half_width_at(&rig, aspect, d) + rig.interaxial_m * 0.5 * (1.0 - d / rig.convergence_m);
        let p = Vec3::new(x, 0.0, 1.0 - d);
        let window = FloatingWindow::measure(&views, [p]);
        assert_eq!(window.strips[0].left, MAX_STRIP);
        let mut eased = FloatingWindow::NONE;
        let mut last = 0.0;
        for _ in 0..100 {
            eased = eased.eased(window, 1.0 / 60.0);
            assert!(eased.strips[0].left >= last && eased.strips[0].left <= MAX_STRIP);
            last = eased.strips[0].left;
        }
        assert!((last - MAX_STRIP).abs() < 1e-3, "{last}");
        assert_eq!(FloatingWindow::NONE.eased(window, f32::NAN), FloatingWindow::NONE);
        assert_eq!((window.widest(), FloatingWindow::NONE.widest()), (MAX_STRIP, 0.0));
    }
}
