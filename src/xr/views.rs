//! From the runtime's views (a pose and four angles per eye, in the reference space) to the
//! renderer's eye cameras in the scene.

use super::grab::Placement;
use crate::math::{Mat4, Pose, Quat, Vec3};
use crate::render::{EyeView, StereoViews};
use crate::stereo::vulkan_frustum;

/// Near clipping plane of the headset's views, room metres.
pub const NEAR_M: f32 = 0.03;
/// Far clipping plane of the headset's views, room metres.
pub const FAR_M: f32 = 50.0;

/// One eye's field of view: the angles of its edges from straight ahead, radians (left and
/// down are negative on a usual headset), as `XrFovf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fov {
    /// Left edge.
    pub left: f32,
    /// Right edge.
    pub right: f32,
    /// Top edge.
    pub up: f32,
    /// Bottom edge.
    pub down: f32,
}

/// One view as the runtime locates it: the eye's pose in the reference space and its field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct XrView {
    /// The eye in the room (reference space), metres; it looks down its −Z, +Y up.
    pub pose: Pose,
    /// Its field of view.
    pub fov: Fov,
}

/// The renderer's camera for `view` with the scene placed in the room by `placement`: view
/// space is the eye's, in room metres, so the clipping planes are room distances.
pub fn eye_view(view: &XrView, placement: &Placement) -> EyeView {
    let eye = Mat4::from_rotation_translation(view.pose.rotation, view.pose.position_m);
    let f = view.fov;
    EyeView {
        view: eye.inverse() * placement.matrix(),
        projection: vulkan_frustum(
            NEAR_M * f.left.tan(),
            NEAR_M * f.right.tan(),
            NEAR_M * f.down.tan(),
            NEAR_M * f.up.tan(),
            NEAR_M,
            FAR_M,
        ),
        position_m: placement.to_world(view.pose.position_m),
    }
}

/// Both eyes' cameras (left, right).
pub fn stereo_views(views: &[XrView; 2], placement: &Placement) -> StereoViews {
    StereoViews { eyes: [eye_view(&views[0], placement), eye_view(&views[1], placement)] }
}

/// Where the scene first appears: its camera target this far in front of a standing
/// viewer's eyes at the stage origin, at a working height.
pub const WORK_POINT_M: Vec3 = Vec3::new(0.0, 1.3, -0.45);

/// The placement that shows `target_world` in front of the head `head` (room pose), at
/// scale 1: the recentre action. With no head pose, at [`WORK_POINT_M`].
pub fn recentred(target_world: Vec3, head: Option<Pose>) -> Placement {
    let Some(head) = head else { return Placement::centred(target_world, WORK_POINT_M) };
    // Only the head's heading counts: the sculpture stays upright.
    let forward = head.rotation * Vec3::NEG_Z;
    let flat = Vec3::new(forward.x, 0.0, forward.z).try_normalize().unwrap_or(Vec3::NEG_Z);
    let yaw = flat.x.atan2(-flat.z);
    let at = head.position_m + flat * (-WORK_POINT_M.z) + Vec3::Y * (WORK_POINT_M.y - 1.6);
    Placement {
        scale: 1.0,
        rotation: Quat::from_rotation_y(-yaw),
        translation_m: at - Quat::from_rotation_y(-yaw) * target_world,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn symmetric(half_angle: f32) -> Fov {
        Fov { left: -half_angle, right: half_angle, up: half_angle, down: -half_angle }
    }

    #[test]
    fn a_point_straight_ahead_lands_in_the_image_centre_and_up_is_up() {
        let view = XrView {
            pose: Pose { position_m: Vec3::new(0.0, 1.6, 0.0), rotation: Quat::IDENTITY },
            fov: symmetric(0.8),
        };
        let e = eye_view(&view, &Placement::default());
        let clip = e.projection * e.view * Vec3::new(0.0, 1.6, -1.0).extend(1.0);
        let ndc = clip.truncate() / clip.w;
        assert!(ndc.x.abs() < 1e-5 && ndc.y.abs() < 1e-5 && (0.0..1.0).contains(&ndc.z), "{ndc}");
        // Above the eye: clip y points down in Vulkan, so it is negative (top of the image).
        let clip = e.projection * e.view * Vec3::new(0.0, 1.9, -1.0).extend(1.0);
        assert!(clip.y / clip.w < -0.1);
        // A scaled placement: the eye's world position is scaled back.
        let p = Placement { scale: 2.0, ..Placement::default() };
        assert!((eye_view(&view, &p).position_m - Vec3::new(0.0, 0.8, 0.0)).length() < 1e-6);
    }

    #[test]
    fn an_asymmetric_field_shifts_the_centre() {
        // A wider left edge: straight ahead lies right of the image centre.
        let view = XrView { pose: Pose::default(), fov: Fov { left: -0.9, right: 0.5, up: 0.7, down: -0.7 } };
        let e = eye_view(&view, &Placement::default());
        let clip = e.projection * e.view * Vec3::new(0.0, 0.0, -1.0).extend(1.0);
        assert!(clip.x / clip.w > 0.1);
    }

    #[test]
    fn recentring_puts_the_target_in_front_of_the_head_upright() {
        let target = Vec3::new(0.0, 0.05, 0.0);
        let p = recentred(target, None);
        assert!((p.to_stage(target) - WORK_POINT_M).length() < 1e-6);
        // A head at (1, 1.6, 0) looking along +X: the target is 0.45 m further along +X.
        let head = Pose {
            position_m: Vec3::new(1.0, 1.6, 0.0),
            rotation: Quat::from_rotation_y(-std::f32::consts::FRAC_PI_2),
        };
        let p = recentred(target, Some(head));
        let at = p.to_stage(target);
        assert!((at - Vec3::new(1.45, 1.3, 0.0)).length() < 1e-5, "{at}");
        assert!((p.rotation * Vec3::Y - Vec3::Y).length() < 1e-6);
        // The scene's front (+Z, towards its default viewer) faces the head.
        let front = p.rotation * Vec3::Z;
        assert!((front - Vec3::NEG_X).length() < 1e-5, "{front}");
    }
}
