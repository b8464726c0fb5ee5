//! Head-tracked ("fish-tank") stereo: Kooima's generalized perspective projection from the
//! physical screen's corners and the tracked eyes, so the sculpture stays fixed in the room as
//! the head moves.
//!
//! Screen space is the calibrated room frame, in metres: by convention the origin is the
//! screen's centre, +X along its bottom edge to the right, +Y up its left edge, +Z out of the
//! screen towards the viewer (any rigid placement of the corners works; the basis is taken from
//! them).
//!
//! ```text
//!   pc (upper left) ┌──────────────────────┐
//!                   │ vu ▲                 │
//!                   │    │                 │        · pe (eye), at distance d along vn
//!                   │    └──► vr           │
//!   pa (lower left) └──────────────────────┘ pb (lower right)       vn = vr × vu (towards the eye)
//! ```
//!
//! For an eye `pe`: `va = pa − pe`, `vb = pb − pe`, `vc = pc − pe`, `d = −vn·va`; on the near
//! plane at distance `n` the window edges are `l = vr·va·n/d`, `r = vr·vb·n/d`,
//! `b = vu·va·n/d`, `t = vu·vc·n/d`. The view turns world space into the screen's basis centred
//! on the eye; the projection is [`vulkan_frustum`]`(l, r, b, t, n, f)`. Every point on the
//! screen plane lands on the same pixel for both eyes (zero parallax), whatever the head does.
//!
//! An eye on or behind the screen plane has no valid frustum: the eye is moved back in front of
//! the screen to [`MIN_EYE_DISTANCE_FRACTION`] of the screen's width (about 1 cm for a desktop
//! monitor) before projecting, so frusta stay finite for every head pose (tested).
//!
//! The screen sits in the scene's world through a [`Placement`] (a similarity: rotation,
//! translation and uniform scale), which is how "convergence" reads with a physical screen: the
//! scene's convergence plane is mapped onto the screen.

use super::{vulkan_frustum, StereoRig, Viewing};
use crate::math::{Mat3, Mat4, Pose, Quat, Vec3, Vec4};
use crate::render::{EyeView, StereoViews};

/// The closest an eye may come to the screen plane, as a fraction of the screen's width.
pub const MIN_EYE_DISTANCE_FRACTION: f32 = 0.02;

/// A physical screen by three of its corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Screen {
    /// Lower-left corner (Kooima's `pa`).
    pub lower_left_m: Vec3,
    /// Lower-right corner (`pb`).
    pub lower_right_m: Vec3,
    /// Upper-left corner (`pc`).
    pub upper_left_m: Vec3,
}

impl Screen {
    /// A `width_m` × `height_m` screen centred at `centre`'s position, its plane spanned by
    /// `centre`'s X (right) and Y (up) axes, facing `centre`'s +Z.
    pub fn from_size(width_m: f32, height_m: f32, centre: Pose) -> Screen {
        let corner = |x: f32, y: f32| {
            centre.position_m + centre.rotation * Vec3::new(x * width_m * 0.5, y * height_m * 0.5, 0.0)
        };
        Screen {
            lower_left_m: corner(-1.0, -1.0),
            lower_right_m: corner(1.0, -1.0),
            upper_left_m: corner(-1.0, 1.0),
        }
    }

    /// The orthonormal basis `(vr, vu, vn)`: right, up, and the normal towards the viewer.
    /// `vu` is made exactly perpendicular to `vr` (calibration checks the corners make a right
    /// angle within a degree).
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let vr = (self.lower_right_m - self.lower_left_m).normalize();
        let up = (self.upper_left_m - self.lower_left_m).normalize();
        let vn = vr.cross(up).normalize();
        (vr, vn.cross(vr), vn)
    }

    /// Width (bottom edge), metres.
    pub fn width_m(&self) -> f32 {
        (self.lower_right_m - self.lower_left_m).length()
    }

    /// Height (left edge), metres.
    pub fn height_m(&self) -> f32 {
        (self.upper_left_m - self.lower_left_m).length()
    }

    /// Width over height.
    pub fn aspect(&self) -> f32 {
        self.width_m() / self.height_m()
    }

    /// The centre of the screen.
    pub fn centre_m(&self) -> Vec3 {
        (self.lower_right_m + self.upper_left_m) * 0.5
    }

    /// Distance of `p` in front of the screen plane (negative behind it).
    pub fn signed_distance_m(&self, p: Vec3) -> f32 {
        self.basis().2.dot(p - self.lower_left_m)
    }

    /// The screen with its corners moved by `m` (a similarity: rotation, translation, uniform
    /// scale).
    pub fn transformed(&self, m: &Mat4) -> Screen {
        Screen {
            lower_left_m: m.transform_point3(self.lower_left_m),
            lower_right_m: m.transform_point3(self.lower_right_m),
            upper_left_m: m.transform_point3(self.upper_left_m),
        }
    }

    /// Why these corners cannot be a screen, if they cannot: not finite, an edge shorter than
    /// 1 cm or longer than 100 m, or edges more than 1° from a right angle.
    pub fn problem(&self) -> Option<String> {
        let corners = [self.lower_left_m, self.lower_right_m, self.upper_left_m];
        if !corners.iter().all(|c| c.is_finite()) {
            return Some("the screen's corners must be finite numbers".to_owned());
        }
        let (w, h) = (self.width_m(), self.height_m());
        if !(0.01..=100.0).contains(&w) || !(0.01..=100.0).contains(&h) {
            return Some(format!(
                "the screen must be between 1 cm and 100 m on each side, not {w:.4} m × {h:.4} m"
            ));
        }
        let cos = (self.lower_right_m - self.lower_left_m)
            .normalize()
            .dot((self.upper_left_m - self.lower_left_m).normalize());
        let angle_deg = cos.clamp(-1.0, 1.0).acos().to_degrees();
        if (angle_deg - 90.0).abs() > 1.0 {
            return Some(format!(
                "the screen's bottom and left edges meet at {angle_deg:.2}°, not 90° (check the corners' order: lower left, lower right, upper left)"
            ));
        }
        None
    }

    /// Where an eye at `eye_m` is taken to be: itself when it is at least
    /// [`MIN_EYE_DISTANCE_FRACTION`] of the width in front of the screen, else moved along the
    /// normal to that distance.
    pub fn clamp_eye(&self, eye_m: Vec3) -> Vec3 {
        let (_, _, vn) = self.basis();
        let min_d = MIN_EYE_DISTANCE_FRACTION * self.width_m();
        let d = self.signed_distance_m(eye_m);
        if d >= min_d {
            eye_m
        } else {
            eye_m + vn * (min_d - d)
        }
    }
}

/// The edges of an eye's frustum on its near plane and the eye actually used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// Eye position, after clamping in front of the screen.
    pub eye_m: Vec3,
    /// Distance from the eye to the screen plane.
    pub screen_distance_m: f32,
    /// Left, right, bottom and top edges on the near plane, in the screen's basis.
    pub lrbt: [f32; 4],
    /// Near and far distances.
    pub near_m: f32,
    /// Far distance.
    pub far_m: f32,
}

impl Frustum {
    /// Kooima's frustum of the eye at `eye_m` through `screen` (see the module docs).
    pub fn new(screen: &Screen, eye_m: Vec3, near_m: f32, far_m: f32) -> Frustum {
        let (vr, vu, vn) = screen.basis();
        let pe = screen.clamp_eye(eye_m);
        let va = screen.lower_left_m - pe;
        let vb = screen.lower_right_m - pe;
        let vc = screen.upper_left_m - pe;
        let d = -vn.dot(va);
        let k = near_m / d;
        Frustum {
            eye_m: pe,
            screen_distance_m: d,
            lrbt: [vr.dot(va) * k, vr.dot(vb) * k, vu.dot(va) * k, vu.dot(vc) * k],
            near_m,
            far_m,
        }
    }

    /// The angles of the frustum's left, right, bottom and top planes from the screen normal
    /// through the eye, degrees (left and bottom negative when the eye is inside the window).
    pub fn angles_deg(&self) -> [f32; 4] {
        self.lrbt.map(|e| (e / self.near_m).atan().to_degrees())
    }
}

/// The eye's view and Vulkan projection for `screen` (Kooima's generalized perspective
/// projection, depth 0 at `near_m`, 1 at `far_m`).
pub fn generalized_perspective(screen: &Screen, eye_m: Vec3, near_m: f32, far_m: f32) -> EyeView {
    let f = Frustum::new(screen, eye_m, near_m, far_m);
    let (vr, vu, vn) = screen.basis();
    // Rows vr, vu, vn: world directions into the screen's basis; then the eye to the origin.
    let rotation = Mat4::from_mat3(Mat3::from_cols(vr, vu, vn).transpose());
    let [l, r, b, t] = f.lrbt;
    EyeView {
        view: rotation * Mat4::from_translation(-f.eye_m),
        projection: vulkan_frustum(l, r, b, t, near_m, far_m),
        position_m: f.eye_m,
    }
}

/// Where screen space sits in the scene's world: `world = translation + rotation · (scale ·
/// screen)`. `scale` is world metres per physical metre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Rotation of screen axes into world axes.
    pub rotation: Quat,
    /// World position of the screen-space origin.
    pub translation_m: Vec3,
    /// World metres per physical metre (> 0).
    pub scale: f32,
}

impl Placement {
    /// Screen space is the world.
    pub const IDENTITY: Placement =
        Placement { rotation: Quat::IDENTITY, translation_m: Vec3::ZERO, scale: 1.0 };

    /// The screen → world matrix.
    pub fn to_matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(Vec3::splat(self.scale), self.rotation, self.translation_m)
    }

    /// A screen-space point in the world.
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.translation_m + self.rotation * (p * self.scale)
    }

    /// The placement that puts an eye at `default_eye_m` (screen space) where the scene's
    /// camera `rig` is, looking the same way, with the scene's convergence plane on the screen:
    /// from the default eye, the head-tracked views then show what the rig shows (proved by the
    /// tests for a centred eye).
    pub fn from_rig(screen: &Screen, default_eye_m: Vec3, rig: &StereoRig) -> Placement {
        let (vr, vu, vn) = screen.basis();
        let forward = rig.forward();
        let right = rig.right();
        let up = right.cross(forward);
        let world_basis = Mat3::from_cols(right, up, -forward);
        let rotation = Quat::from_mat3(&(world_basis * Mat3::from_cols(vr, vu, vn).transpose())).normalize();
        let d = screen.signed_distance_m(screen.clamp_eye(default_eye_m));
        let scale = rig.convergence_m / d;
        let translation_m = rig.eye_m - rotation * (default_eye_m * scale);
        Placement { rotation, translation_m, scale }
    }
}

/// A head-tracked stereo camera: a calibrated screen placed in the world, an eye separation,
/// and clipping distances (world metres).
///
/// At runtime, `interaxial_m` may be lowered (flatter depth) and the convergence changed by
/// placing the screen again with [`Placement::from_rig`] from a [`StereoRig`] whose convergence
/// was set ([`StereoRig::set_convergence_m`], or auto-convergence with
/// [`StereoRig::converge_on`]): the world then scales about the default eye, and the point at
/// the new convergence distance lies on the screen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadTrackedRig {
    /// The physical screen, screen space.
    pub screen: Screen,
    /// Where screen space sits in the world.
    pub placement: Placement,
    /// Distance between the eyes, physical metres (the calibrated IPD by default; smaller
    /// values flatten the depth).
    pub interaxial_m: f32,
    /// Near clipping distance, world metres.
    pub near_m: f32,
    /// Far clipping distance, world metres.
    pub far_m: f32,
}

impl HeadTrackedRig {
    /// The eyes `[left, right]` of a head at `head` (screen space: position, and orientation
    /// whose +X runs from the left eye to the right eye).
    pub fn eye_positions_m(&self, head: &Pose) -> [Vec3; 2] {
        let half = head.rotation * Vec3::X * (0.5 * self.interaxial_m);
        [head.position_m - half, head.position_m + half]
    }

    /// Both eyes' views for a head at `head` (screen space).
    pub fn views(&self, head: &Pose) -> StereoViews {
        let m = self.placement.to_matrix();
        let screen = self.screen.transformed(&m);
        let eyes = self.eye_positions_m(head).map(|e| self.placement.point(e));
        StereoViews { eyes: eyes.map(|e| generalized_perspective(&screen, e, self.near_m, self.far_m)) }
    }

    /// How the views of a head at `head` map onto the physical screen, for the parallax
    /// budget: distances in world metres, the screen 1 / scale physical metres per world metre.
    pub fn viewing(&self, head: &Pose) -> Viewing {
        let d = self.screen.signed_distance_m(self.screen.clamp_eye(head.position_m));
        let s = self.placement.scale;
        Viewing {
            interaxial_m: self.interaxial_m * s,
            convergence_m: d * s,
            display_per_world: 1.0 / s,
            viewing_distance_m: d,
            eye_separation_m: self.interaxial_m,
        }
    }

    /// Distance of a world point from the head's eyes along the screen normal (world metres).
    pub fn depth_of(&self, head: &Pose, point_m: Vec3) -> f32 {
        let screen = self.screen.transformed(&self.placement.to_matrix());
        let eye = self.placement.point(self.screen.clamp_eye(head.position_m));
        screen.signed_distance_m(eye) - screen.signed_distance_m(point_m)
    }

    /// Both eyes' frusta in screen space (physical metres) for a head at `head`, with the near
    /// plane at `near_m` physical metres.
    pub fn frusta(&self, head: &Pose, near_m: f32) -> [Frustum; 2] {
        let far_m = self.far_m / self.placement.scale;
        self.eye_positions_m(head).map(|e| Frustum::new(&self.screen, e, near_m, far_m))
    }
}

/// Projects a world point through an eye to pixel coordinates (column, row from the top) of a
/// `width` × `height` image, and its depth.
pub fn to_pixel(view: &EyeView, p: Vec3, width: f32, height: f32) -> (f32, f32, f32) {
    let clip = view.projection * view.view * Vec4::from((p, 1.0));
    let ndc = clip.truncate() / clip.w;
    ((ndc.x * 0.5 + 0.5) * width, (ndc.y * 0.5 + 0.5) * height, ndc.z)
}

#[cfg(test)]
mod tests {
    use super::super::comfort::screen_parallax_m;
    use super::*;
    use proptest::prelude::*;

    /// A 24" 16:9 monitor centred at the origin.
    fn monitor() -> Screen {
        Screen::from_size(0.531, 0.299, Pose::default())
    }

    fn rig(screen: Screen, ipd: f32) -> HeadTrackedRig {
        HeadTrackedRig {
            screen,
            placement: Placement::IDENTITY,
            interaxial_m: ipd,
            near_m: 0.01,
            far_m: 50.0,
        }
    }

    fn head(x: f32, y: f32, z: f32, pitch_deg: f32) -> Pose {
        Pose { position_m: Vec3::new(x, y, z), rotation: Quat::from_rotation_x(pitch_deg.to_radians()) }
    }

    fn mat_close(a: &Mat4, b: &Mat4, tol: f32) -> bool {
        a.to_cols_array().iter().zip(b.to_cols_array()).all(|(x, y)| (x - y).abs() <= tol * (1.0 + y.abs()))
    }

    #[test]
    fn screen_from_size_has_the_expected_corners_and_basis() {
        let s = monitor();
        assert!((s.width_m() - 0.531).abs() < 1e-6 && (s.height_m() - 0.299).abs() < 1e-6);
        let (vr, vu, vn) = s.basis();
        assert!(
            (vr - Vec3::X).length() < 1e-6
                && (vu - Vec3::Y).length() < 1e-6
                && (vn - Vec3::Z).length() < 1e-6
        );
        assert!(s.problem().is_none());
        let skewed = Screen { upper_left_m: s.upper_left_m + Vec3::new(0.02, 0.0, 0.0), ..s };
        assert!(skewed.problem().unwrap().contains("90°"));
    }

    #[test]
    fn the_sculpture_stays_fixed_in_the_room_as_the_head_moves() {
        // A point behind the screen seen from two head positions: its rays from each eye pass
        // through the screen where the straight line from the eye to the point crosses it.
        let r = rig(monitor(), 0.063);
        let p = Vec3::new(0.05, -0.03, -0.2);
        for h in [head(0.0, 0.0, 0.6, 0.0), head(0.2, 0.1, 0.5, 0.0)] {
            let v = r.views(&h);
            for (eye, e) in v.eyes.iter().zip(r.eye_positions_m(&h)) {
                let t = e.z / (e.z - p.z);
                let hit = e + (p - e) * t;
                let (x, y, _) = to_pixel(eye, p, 531.0, 299.0);
                let expect_x = (hit.x + 0.2655) / 0.531 * 531.0;
                let expect_y = (0.1495 - hit.y) / 0.299 * 299.0;
                assert!(
                    (x - expect_x).abs() < 0.01 && (y - expect_y).abs() < 0.01,
                    "{x},{y} vs {expect_x},{expect_y}"
                );
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// A level head (eyes along the screen's horizontal) sees no vertical parallax anywhere.
        #[test]
        fn a_level_head_sees_no_vertical_parallax(
            hx in -0.4f32..0.4, hy in -0.3f32..0.3, hz in 0.2f32..1.5, pitch in -40f32..40.0,
            ipd in 0.05f32..0.075,
            px in -0.5f32..0.5, py in -0.4f32..0.4, pz in -2.0f32..0.15,
        ) {
            let r = rig(monitor(), ipd);
            let p = Vec3::new(px, py, pz);
            prop_assume!(hz - pz > 0.05);
            let v = r.views(&head(hx, hy, hz, pitch));
            let (_, yl, _) = to_pixel(&v.eyes[0], p, 1920.0, 1080.0);
            let (_, yr, _) = to_pixel(&v.eyes[1], p, 1920.0, 1080.0);
            prop_assert!((yl - yr).abs() < 2e-3 * (1.0 + yl.abs()), "{yl} vs {yr}");
        }

        /// Points on the screen plane land on the same pixel for both eyes, whatever the head.
        #[test]
        fn the_screen_plane_has_zero_disparity_for_any_head(
            hx in -0.5f32..0.5, hy in -0.4f32..0.4, hz in 0.1f32..2.0,
            yaw in -60f32..60.0, pitch in -45f32..45.0, roll in -45f32..45.0,
            u in 0f32..1.0, w in 0f32..1.0,
        ) {
            let s = monitor();
            let r = rig(s, 0.063);
            let rot = Quat::from_euler(glam::EulerRot::YXZ, yaw.to_radians(), pitch.to_radians(), roll.to_radians());
            let v = r.views(&Pose { position_m: Vec3::new(hx, hy, hz), rotation: rot });
            let p = s.lower_left_m + (s.lower_right_m - s.lower_left_m) * u + (s.upper_left_m - s.lower_left_m) * w;
            let (xl, yl, _) = to_pixel(&v.eyes[0], p, 1920.0, 1080.0);
            let (xr, yr, _) = to_pixel(&v.eyes[1], p, 1920.0, 1080.0);
            prop_assert!((xl - xr).abs() < 0.02 && (yl - yr).abs() < 0.02, "({xl},{yl}) vs ({xr},{yr})");
            // And on the pixel the screen position names.
            prop_assert!((xl - u * 1920.0).abs() < 0.05 && (yl - (1.0 - w) * 1080.0).abs() < 0.05);
        }

        /// In front of the screen the disparity is crossed, behind it uncrossed, with the
        /// magnitude IPD · (Z − D) / Z on the screen.
        #[test]
        fn disparity_is_crossed_in_front_uncrossed_behind_with_the_analytic_magnitude(
            hx in -0.2f32..0.2, hy in -0.15f32..0.15, d in 0.3f32..1.2, ipd in 0.05f32..0.075,
            px in -0.3f32..0.3, py in -0.2f32..0.2, depth in -1.5f32..0.25,
        ) {
            let s = monitor();
            let r = rig(s, ipd);
            prop_assume!(d - depth > 0.05 && depth.abs() > 1e-3);
            let v = r.views(&head(hx, hy, d, 0.0));
            let p = Vec3::new(px, py, depth);
            let (xl, _, _) = to_pixel(&v.eyes[0], p, 1920.0, 1080.0);
            let (xr, _, _) = to_pixel(&v.eyes[1], p, 1920.0, 1080.0);
            let measured_m = (xr - xl) / 1920.0 * s.width_m();
            let expected_m = screen_parallax_m(ipd, d, d - depth);
            prop_assert!((measured_m - expected_m).abs() < 1e-5 + 1e-3 * expected_m.abs(), "{measured_m} vs {expected_m}");
            prop_assert_eq!(measured_m < 0.0, depth > 0.0, "crossed in front, uncrossed behind");
        }

        /// With the eye centred in front of the screen, the generalized projection is the
        /// standard off-axis rig whose window is the screen, placed anywhere in the world.
        #[test]
        fn a_centred_eye_gives_the_standard_off_axis_rig(
            w in 0.2f32..1.5, aspect in 1.0f32..2.4, d in 0.3f32..1.5, ipd in 0.0f32..0.075,
            ex in -2.0f32..2.0, ey in -2.0f32..2.0, ez in -2.0f32..2.0,
            tx in -1.0f32..1.0, ty in -1.0f32..1.0, convergence in 0.2f32..3.0,
        ) {
            let s = Screen::from_size(w, w / aspect, Pose::default());
            let eye = Vec3::new(ex, ey, ez);
            let target = eye + Vec3::new(tx, ty, -1.0);
            let standard = StereoRig {
                eye_m: eye,
                target_m: target,
                up: Vec3::Y,
                fov_y_deg: (2.0 * (0.5 * w / aspect / d).atan()).to_degrees(),
                interaxial_m: ipd * convergence / d,
                convergence_m: convergence,
                near_m: 0.05,
                far_m: 20.0,
            };
            let default_eye = Vec3::new(0.0, 0.0, d);
            let tracked = HeadTrackedRig {
                screen: s,
                placement: Placement::from_rig(&s, default_eye, &standard),
                interaxial_m: ipd,
                near_m: 0.05,
                far_m: 20.0,
            };
            let a = tracked.views(&Pose { position_m: default_eye, rotation: Quat::IDENTITY });
            let b = standard.views(aspect);
            for (x, y) in a.eyes.iter().zip(&b.eyes) {
                prop_assert!(mat_close(&x.view, &y.view, 2e-4), "view\n{}\n{}", x.view, y.view);
                prop_assert!(mat_close(&x.projection, &y.projection, 2e-4), "projection\n{}\n{}", x.projection, y.projection);
                prop_assert!((x.position_m - y.position_m).length() < 1e-4);
            }
        }

        /// Frusta stay finite for any head pose, the eye on or behind the screen included; such
        /// an eye is moved in front of the screen.
        #[test]
        fn frusta_are_finite_for_extreme_head_poses(
            hx in -100f32..100.0, hy in -100f32..100.0, hz in -100f32..100.0,
            yaw in -180f32..180.0, pitch in -90f32..90.0, roll in -180f32..180.0,
        ) {
            let s = monitor();
            let r = rig(s, 0.063);
            let rot = Quat::from_euler(glam::EulerRot::YXZ, yaw.to_radians(), pitch.to_radians(), roll.to_radians());
            let h = Pose { position_m: Vec3::new(hx, hy, hz), rotation: rot };
            for eye in r.views(&h).eyes {
                prop_assert!(eye.view.is_finite() && eye.projection.is_finite() && eye.position_m.is_finite());
                prop_assert!(s.signed_distance_m(eye.position_m) >= MIN_EYE_DISTANCE_FRACTION * s.width_m() * 0.999);
            }
            for f in r.frusta(&h, 0.01) {
                prop_assert!(f.lrbt.iter().all(|e| e.is_finite()) && f.screen_distance_m > 0.0);
            }
        }
    }

    #[test]
    fn the_viewing_of_a_placed_screen_predicts_its_disparities() {
        // The screen scaled 2× into the world: world distances double, display parallax does not.
        let s = monitor();
        let standard = StereoRig {
            eye_m: Vec3::new(0.0, 0.0, 1.2),
            target_m: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 30.0,
            interaxial_m: 0.1,
            convergence_m: 1.2,
            near_m: 0.05,
            far_m: 20.0,
        };
        let default_eye = Vec3::new(0.0, 0.0, 0.6);
        let r =
            HeadTrackedRig { placement: Placement::from_rig(&s, default_eye, &standard), ..rig(s, 0.063) };
        let head = Pose { position_m: default_eye, rotation: Quat::IDENTITY };
        let v = r.viewing(&head);
        let p = Vec3::new(0.1, 0.05, -0.4);
        let z = r.depth_of(&head, p);
        assert!((z - 1.6).abs() < 1e-5, "{z}");
        let views = r.views(&head);
        let (xl, _, _) = to_pixel(&views.eyes[0], p, 1920.0, 1080.0);
        let (xr, _, _) = to_pixel(&views.eyes[1], p, 1920.0, 1080.0);
        let measured_m = (xr - xl) / 1920.0 * s.width_m();
        assert!(
            (measured_m - v.display_parallax_m(z)).abs() < 1e-5,
            "{measured_m} vs {}",
            v.display_parallax_m(z)
        );
    }

    #[test]
    fn changing_the_rigs_convergence_moves_the_screen_to_it() {
        let s = monitor();
        let mut standard = StereoRig {
            eye_m: Vec3::new(0.1, 0.2, 0.9),
            target_m: Vec3::new(0.0, 0.0, 0.0),
            up: Vec3::Y,
            fov_y_deg: 30.0,
            interaxial_m: 0.063,
            convergence_m: 0.9,
            near_m: 0.05,
            far_m: 20.0,
        };
        let default_eye = Vec3::new(0.0, 0.0, 0.6);
        let head = Pose { position_m: Vec3::new(0.05, -0.03, 0.55), rotation: Quat::IDENTITY };
        for convergence in [0.3f32, 0.9, 1.7] {
            standard.set_convergence_m(convergence);
            let r = HeadTrackedRig {
                placement: Placement::from_rig(&s, default_eye, &standard),
                ..rig(s, 0.063)
            };
            let up = standard.right().cross(standard.forward());
            let p = standard.eye_m + standard.forward() * convergence + standard.right() * 0.03 + up * 0.02;
            let v = r.views(&head);
            let (xl, yl, _) = to_pixel(&v.eyes[0], p, 1920.0, 1080.0);
            let (xr, yr, _) = to_pixel(&v.eyes[1], p, 1920.0, 1080.0);
            assert!(
                (xl - xr).abs() < 0.02 && (yl - yr).abs() < 0.02,
                "convergence {convergence}: {xl},{yl} vs {xr},{yr}"
            );
        }
    }

    #[test]
    fn an_eye_exactly_on_the_screen_plane_is_moved_in_front() {
        let s = monitor();
        let v = generalized_perspective(&s, Vec3::new(0.1, 0.0, 0.0), 0.01, 10.0);
        assert!(v.projection.is_finite());
        assert!((v.position_m.z - MIN_EYE_DISTANCE_FRACTION * s.width_m()).abs() < 1e-6);
    }
}
