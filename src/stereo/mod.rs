//! The desktop stereo camera rig, and the display modes that show its stereo pairs
//! ([`display`]).
//!
//! Off-axis (asymmetric) frusta, never toe-in: both eyes look along the same axis; each eye's
//! frustum passes through the same window on the convergence plane, so points on that plane
//! have zero parallax, nearer points crossed (negative) parallax and farther points uncrossed
//! (positive) parallax, and no point has vertical parallax.
//!
//! ```text
//!            window on the convergence plane (width W = 2·C·tan(fov_x / 2))
//!      ┌───────────────────────────────┐        ▲
//!       \   ╲                    ╱    /         │ C (convergence distance)
//!        \    ╲                ╱     /          │
//!         \     ╲            ╱      /           │
//!          L ───── e/2 ── · ── e/2 ── R         ▼   (e = interaxial, · = centre eye)
//! ```
//!
//! Screen parallax of a point at distance `Z` along the view axis, on the convergence plane:
//! `p = e · (Z − C) / Z` (metres on that plane), which is `p / W · width` pixels.
//! Knows nothing of Vulkan handles; it hands the renderer plain [`StereoViews`].
//!
//! Head-tracked projection from a calibrated physical screen is in [`screen`] (this rig is its
//! special case for an eye centred in front of the screen); interaxial, convergence, the
//! parallax budget and auto-convergence are in [`comfort`].

pub mod comfort;
pub mod floating;
pub mod screen;

pub use comfort::{screen_parallax_m, AutoConvergence, BudgetMode, ParallaxBudget, Viewing};
pub use screen::{generalized_perspective, HeadTrackedRig, Placement, Screen};

pub mod display;

use crate::math::{Mat4, Vec3};
use crate::render::{EyeView, StereoViews};

/// A stereo camera: a centre eye looking at a target, two eyes either side of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StereoRig {
    /// Centre eye position, metres.
    pub eye_m: Vec3,
    /// Point the centre eye looks at, metres.
    pub target_m: Vec3,
    /// Approximate up direction.
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
    /// Distance between the eyes, metres.
    pub interaxial_m: f32,
    /// Distance from the eyes to the zero-parallax plane, metres.
    pub convergence_m: f32,
    /// Near clipping distance, metres.
    pub near_m: f32,
    /// Far clipping distance, metres.
    pub far_m: f32,
}

impl StereoRig {
    /// Unit vector along which both eyes look.
    pub fn forward(&self) -> Vec3 {
        (self.target_m - self.eye_m).normalize()
    }

    /// Unit vector from the left eye to the right eye.
    pub fn right(&self) -> Vec3 {
        self.forward().cross(self.up).normalize()
    }

    /// The centre eye's world → view transform.
    pub fn centre_view(&self) -> Mat4 {
        Mat4::look_to_rh(self.eye_m, self.forward(), self.up)
    }

    /// The convergence plane's range, metres: from twice the near plane to half the far one,
    /// so that the zero-parallax plane never lies where nothing is drawn.
    pub fn convergence_range(&self) -> (f32, f32) {
        (self.near_m * 2.0, (self.far_m * 0.5).max(self.near_m * 2.0))
    }

    /// Width of the zero-parallax window on the convergence plane, metres.
    pub fn window_width_m(&self, aspect: f32) -> f32 {
        2.0 * self.convergence_m * (self.fov_y_deg.to_radians() * 0.5).tan() * aspect
    }

    /// Both eyes' views for images of the given aspect ratio (width / height).
    pub fn views(&self, aspect: f32) -> StereoViews {
        let forward = self.forward();
        let right = self.right();
        let up = right.cross(forward);
        let half_h = self.convergence_m * (self.fov_y_deg.to_radians() * 0.5).tan();
        let half_w = half_h * aspect;
        let n = self.near_m;
        let scale = n / self.convergence_m;
        let eye = |sign: f32| {
            let offset = sign * 0.5 * self.interaxial_m;
            let position = self.eye_m + right * offset;
            // The window is fixed in the world; seen from an eye shifted by `offset`, its edges
            // shift by −offset.
            let (l, r) = ((-half_w - offset) * scale, (half_w - offset) * scale);
            let (b, t) = (-half_h * scale, half_h * scale);
            EyeView {
                view: Mat4::look_to_rh(position, forward, up),
                projection: vulkan_frustum(l, r, b, t, n, self.far_m),
                position_m: position,
            }
        };
        StereoViews { eyes: [eye(-1.0), eye(1.0)] }
    }

    /// Expected horizontal parallax (right-eye column minus left-eye column) in pixels of a
    /// point at `distance_m` along the view axis, for images `width_px` wide.
    pub fn parallax_px(&self, distance_m: f32, width_px: u32, aspect: f32) -> f32 {
        let p = screen_parallax_m(self.interaxial_m, self.convergence_m, distance_m);
        p / self.window_width_m(aspect) * width_px as f32
    }

    /// Largest interaxial distance [`Self::set_interaxial_m`] accepts, metres.
    pub const MAX_INTERAXIAL_M: f32 = 0.25;

    /// Sets the distance between the eyes at runtime, clamped to
    /// `0..=`[`Self::MAX_INTERAXIAL_M`] (0 gives mono); a non-finite value is ignored.
    pub fn set_interaxial_m(&mut self, interaxial_m: f32) {
        if interaxial_m.is_finite() {
            self.interaxial_m = interaxial_m.clamp(0.0, Self::MAX_INTERAXIAL_M);
        }
    }

    /// Sets the distance of the zero-parallax plane at runtime, clamped between the near and
    /// far clipping distances; a non-finite value is ignored.
    pub fn set_convergence_m(&mut self, convergence_m: f32) {
        if convergence_m.is_finite() {
            self.convergence_m = convergence_m.clamp(self.near_m, self.far_m);
        }
    }

    /// Distance of `point_m` along the view axis (what convergence on it means).
    pub fn depth_of(&self, point_m: Vec3) -> f32 {
        (point_m - self.eye_m).dot(self.forward())
    }

    /// One step of auto-convergence on `point_m` (the active tool or the sculpture's centre):
    /// the filter moves the convergence towards the point's depth, see [`comfort`].
    pub fn converge_on(&mut self, filter: &mut AutoConvergence, point_m: Vec3, dt_s: f32) {
        let c = filter.update(self.depth_of(point_m), dt_s);
        self.set_convergence_m(c);
    }

    /// How this rig's zero-parallax window maps onto a physical display `display_width_m`
    /// wide, seen from `viewing_distance_m` by eyes `eye_separation_m` apart, for images of
    /// the given aspect ratio (the window fills the display's width).
    pub fn viewing(
        &self,
        display_width_m: f32,
        viewing_distance_m: f32,
        eye_separation_m: f32,
        aspect: f32,
    ) -> Viewing {
        Viewing {
            interaxial_m: self.interaxial_m,
            convergence_m: self.convergence_m,
            display_per_world: display_width_m / self.window_width_m(aspect),
            viewing_distance_m,
            eye_separation_m,
        }
    }
}

/// An off-axis perspective projection into Vulkan clip space: right-handed view space looking
/// down −Z, clip y pointing down (so row 0 of the image is the top), depth 0 at `near` and 1 at
/// `far`. `l, r, b, t` are the window edges on the near plane.
pub fn vulkan_frustum(l: f32, r: f32, b: f32, t: f32, near: f32, far: f32) -> Mat4 {
    use crate::math::Vec4;
    Mat4::from_cols(
        Vec4::new(2.0 * near / (r - l), 0.0, 0.0, 0.0),
        Vec4::new(0.0, -2.0 * near / (t - b), 0.0, 0.0),
        Vec4::new((r + l) / (r - l), -(t + b) / (t - b), far / (near - far), -1.0),
        Vec4::new(0.0, 0.0, near * far / (near - far), 0.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rig() -> StereoRig {
        StereoRig {
            eye_m: Vec3::new(0.0, 0.0, 0.6),
            target_m: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 40.0,
            interaxial_m: 0.064,
            convergence_m: 0.6,
            near_m: 0.05,
            far_m: 10.0,
        }
    }

    use screen::to_pixel;

    #[test]
    fn convergence_plane_has_zero_parallax_and_depth_maps_to_unit_range() {
        let r = rig();
        let v = r.views(1.0);
        for p in [Vec3::ZERO, Vec3::new(0.1, -0.05, 0.0)] {
            let (xl, yl, _) = to_pixel(&v.eyes[0], p, 512.0, 512.0);
            let (xr, yr, _) = to_pixel(&v.eyes[1], p, 512.0, 512.0);
            assert!((xl - xr).abs() < 1e-3 && (yl - yr).abs() < 1e-3);
        }
        let near = to_pixel(&v.eyes[0], Vec3::new(0.0, 0.0, 0.6 - 0.05), 1.0, 1.0).2;
        let far = to_pixel(&v.eyes[0], Vec3::new(0.0, 0.0, 0.6 - 10.0), 1.0, 1.0).2;
        assert!(near.abs() < 1e-5 && (far - 1.0).abs() < 1e-5);
    }

    #[test]
    fn parallax_matches_the_formula_and_has_no_vertical_component() {
        let r = rig();
        let v = r.views(1.5);
        for z in [0.3f32, 0.45, 0.9, 2.0] {
            let p = Vec3::new(0.02, 0.07, 0.6 - z);
            let (xl, yl, _) = to_pixel(&v.eyes[0], p, 768.0, 512.0);
            let (xr, yr, _) = to_pixel(&v.eyes[1], p, 768.0, 512.0);
            assert!((yl - yr).abs() < 1e-3, "vertical parallax at {z}");
            let expected = r.parallax_px(z, 768, 1.5);
            assert!(((xr - xl) - expected).abs() < 1e-2, "z {z}: {} vs {expected}", xr - xl);
            assert_eq!(xr - xl < 0.0, z < r.convergence_m, "crossed in front, uncrossed behind");
        }
    }

    #[test]
    fn interaxial_and_convergence_change_at_runtime_within_bounds() {
        let mut r = rig();
        r.set_interaxial_m(0.03);
        assert_eq!(r.interaxial_m, 0.03);
        r.set_interaxial_m(-1.0);
        assert_eq!(r.interaxial_m, 0.0);
        r.set_interaxial_m(f32::NAN);
        assert_eq!(r.interaxial_m, 0.0);
        r.set_interaxial_m(0.064);
        r.set_convergence_m(0.4);
        let v = r.views(1.0);
        let p = Vec3::new(0.05, 0.02, 0.2);
        let (xl, _, _) = to_pixel(&v.eyes[0], p, 512.0, 512.0);
        let (xr, _, _) = to_pixel(&v.eyes[1], p, 512.0, 512.0);
        assert!((xl - xr).abs() < 1e-3, "the new convergence plane has zero parallax");
        r.set_convergence_m(1e6);
        assert_eq!(r.convergence_m, r.far_m);
    }

    #[test]
    fn auto_convergence_brings_the_tool_to_zero_parallax() {
        let mut r = rig();
        let tool = Vec3::new(0.03, -0.02, 0.25);
        let mut filter = AutoConvergence::new(r.convergence_m, 0.3, (r.near_m, r.far_m));
        let mut last = r.convergence_m;
        for _ in 0..300 {
            r.converge_on(&mut filter, tool, 1.0 / 90.0);
            assert!(r.convergence_m <= last + 1e-6, "moves steadily towards the tool");
            last = r.convergence_m;
        }
        assert!((r.convergence_m - 0.35).abs() < 1e-3, "{}", r.convergence_m);
        let v = r.views(1.0);
        let (xl, _, _) = to_pixel(&v.eyes[0], tool, 512.0, 512.0);
        let (xr, _, _) = to_pixel(&v.eyes[1], tool, 512.0, 512.0);
        assert!((xl - xr).abs() < 0.05, "{}", xr - xl);
    }

    #[test]
    fn the_rig_viewing_matches_its_pixel_parallax() {
        let r = rig();
        // A window as wide as the display: display parallax is parallax on the plane scaled.
        let aspect = 16.0 / 9.0;
        let v = r.viewing(0.531, 0.6, 0.063, aspect);
        let px = r.parallax_px(1.2, 1920, aspect);
        assert!((v.display_parallax_m(1.2) - px / 1920.0 * 0.531).abs() < 1e-6);
    }

    #[test]
    fn up_is_up_in_the_image() {
        let v = rig().views(1.0);
        let (_, y_high, _) = to_pixel(&v.eyes[0], Vec3::new(0.0, 0.1, 0.0), 100.0, 100.0);
        assert!(y_high < 50.0, "a point above the axis lands in the top half (row 0 is the top)");
    }
}
