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
        let p = self.interaxial_m * (distance_m - self.convergence_m) / distance_m;
        p / self.window_width_m(aspect) * width_px as f32
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
    use crate::math::Vec4;

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

    fn to_pixel(view: &EyeView, p: Vec3, width: f32, height: f32) -> (f32, f32, f32) {
        let clip = view.projection * view.view * Vec4::from((p, 1.0));
        let ndc = clip.truncate() / clip.w;
        ((ndc.x * 0.5 + 0.5) * width, (ndc.y * 0.5 + 0.5) * height, ndc.z)
    }

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
    fn up_is_up_in_the_image() {
        let v = rig().views(1.0);
        let (_, y_high, _) = to_pixel(&v.eyes[0], Vec3::new(0.0, 0.1, 0.0), 100.0, 100.0);
        assert!(y_high < 50.0, "a point above the axis lands in the top half (row 0 is the top)");
    }
}
