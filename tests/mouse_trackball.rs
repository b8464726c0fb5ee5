//! The mouse, scripted: trackball drags turn the scene by the expected angles and retracing a
//! path restores it; drag and wheel set the distance; the 3D cursor carries the tool.

use std::f32::consts::PI;

use argile::input::mouse::{
    MouseButton, MouseEvent, MouseMode, MouseNavigator, MouseSettings, TrackballKind,
};
use argile::math::{Mat4, Quat, Vec2, Vec3};

const VIEWPORT: Vec2 = Vec2::new(400.0, 200.0);

fn navigator(kind: TrackballKind) -> MouseNavigator {
    MouseNavigator::new(MouseSettings { trackball: kind, ..MouseSettings::default() }, VIEWPORT, 1.0)
}

/// Presses the left button at the first point, moves through the rest, releases.
fn drag(nav: &mut MouseNavigator, path: &[Vec2]) {
    let (inv, dir) = (Mat4::IDENTITY, Vec3::NEG_Z);
    nav.handle(MouseEvent::Press(MouseButton::Left, path[0]), &inv, dir);
    for &p in &path[1..] {
        nav.handle(MouseEvent::Move(p), &inv, dir);
    }
    nav.handle(MouseEvent::Release(MouseButton::Left), &inv, dir);
}

fn line(from: Vec2, to: Vec2, steps: usize) -> Vec<Vec2> {
    (0..=steps).map(|i| from.lerp(to, i as f32 / steps as f32)).collect()
}

fn angle(q: Quat) -> f32 {
    q.normalize().to_axis_angle().1
}

// The ball is the inscribed circle: centre (200, 100), radius 100 pixels.
const CENTRE: Vec2 = Vec2::new(200.0, 100.0);

#[test]
fn shoemake_centre_to_rim_is_half_a_turn_and_a_full_drag_a_whole_turn() {
    let mut nav = navigator(TrackballKind::Shoemake);
    drag(&mut nav, &line(CENTRE, CENTRE + Vec2::new(100.0, 0.0), 50));
    let front = nav.scene_rotation * Vec3::Z;
    assert!((front - Vec3::NEG_Z).length() < 1e-3, "the front faces away: {front:?}");
    let (axis, a) = nav.scene_rotation.to_axis_angle();
    assert!((a - PI).abs() < 1e-3 && (axis - Vec3::Y).length() < 1e-3, "{axis:?} {a}");

    // Rim to rim through the centre, in one drag: a whole turn about +y, back where it began.
    let mut nav = navigator(TrackballKind::Shoemake);
    let path = line(CENTRE - Vec2::new(100.0, 0.0), CENTRE + Vec2::new(100.0, 0.0), 200);
    let mut total = 0.0;
    let mut previous = nav.scene_rotation;
    nav.handle(MouseEvent::Press(MouseButton::Left, path[0]), &Mat4::IDENTITY, Vec3::NEG_Z);
    for &p in &path[1..] {
        nav.handle(MouseEvent::Move(p), &Mat4::IDENTITY, Vec3::NEG_Z);
        total += angle(nav.scene_rotation * previous.inverse());
        previous = nav.scene_rotation;
    }
    assert!((total - 2.0 * PI).abs() < 1e-2, "total {total}");
    assert!((nav.scene_rotation * Vec3::Z - Vec3::Z).length() < 1e-3);
}

#[test]
fn bell_centre_to_rim_turns_by_the_arc_to_the_sheet() {
    let mut nav = navigator(TrackballKind::Bell);
    drag(&mut nav, &line(CENTRE, CENTRE + Vec2::new(100.0, 0.0), 50));
    // The rim point (1, 0) lies on the sheet at z = ½: the arc from (0, 0, 1) is atan(1 / ½).
    let expected = (1.0f32).atan2(0.5);
    assert!((angle(nav.scene_rotation) - expected).abs() < 1e-3, "{}", angle(nav.scene_rotation));
    let front = nav.scene_rotation * Vec3::Z;
    assert!(front.x > 0.0 && front.y.abs() < 1e-4);
}

#[test]
fn retracing_a_path_restores_the_scene() {
    for kind in [TrackballKind::Shoemake, TrackballKind::Bell] {
        let mut nav = navigator(kind);
        // A wandering path that leaves the ball (outside the circle) and comes back.
        let path: Vec<Vec2> = (0..300)
            .map(|i| {
                let t = i as f32 / 40.0;
                CENTRE + Vec2::new(150.0 * (t * 1.3).sin(), 90.0 * (t * 0.7).cos() - 20.0)
            })
            .collect();
        drag(&mut nav, &path);
        assert!(angle(nav.scene_rotation) > 0.1, "{kind:?}: the path turns the scene");
        let back: Vec<Vec2> = path.iter().rev().copied().collect();
        drag(&mut nav, &back);
        assert!(angle(nav.scene_rotation) < 1e-3, "{kind:?}: left {}", angle(nav.scene_rotation));
    }
}

#[test]
fn wheel_and_right_drag_set_the_distance() {
    let mut nav = navigator(TrackballKind::Shoemake);
    let (inv, dir) = (Mat4::IDENTITY, Vec3::NEG_Z);
    nav.handle(MouseEvent::Wheel(3.0), &inv, dir);
    assert!((nav.distance_m - 0.9f32.powi(3)).abs() < 1e-5, "the wheel away brings the scene nearer");
    nav.handle(MouseEvent::Wheel(-3.0), &inv, dir);
    assert!((nav.distance_m - 1.0).abs() < 1e-5);
    nav.handle(MouseEvent::Wheel(1000.0), &inv, dir);
    assert_eq!(nav.distance_m, MouseSettings::default().min_distance_m);
    nav.handle(MouseEvent::Wheel(f32::NAN), &inv, dir);
    assert_eq!(nav.distance_m, MouseSettings::default().min_distance_m);

    let mut nav = navigator(TrackballKind::Shoemake);
    nav.handle(MouseEvent::Press(MouseButton::Right, CENTRE), &inv, dir);
    nav.handle(MouseEvent::Move(CENTRE + Vec2::new(0.0, 100.0)), &inv, dir);
    assert!(nav.distance_m > 1.5, "dragging down moves the scene away: {}", nav.distance_m);
    nav.handle(MouseEvent::Move(CENTRE), &inv, dir);
    assert!((nav.distance_m - 1.0).abs() < 1e-4);
    assert_eq!(nav.scene_rotation, Quat::IDENTITY, "the right button never turns");
}

#[test]
fn cursor_mode_carries_the_tool_under_the_pointer() {
    let eye = Vec3::new(0.0, 0.0, 1.0);
    let view = Mat4::look_at_rh(eye, Vec3::ZERO, Vec3::Y);
    // Vulkan's clip space, as the renderer's projections: y points down the image.
    let proj = Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0))
        * Mat4::perspective_rh(PI / 2.0, VIEWPORT.x / VIEWPORT.y, 0.1, 10.0);
    let inv = (proj * view).inverse();
    let dir = Vec3::NEG_Z;
    let mut nav = navigator(TrackballKind::Shoemake);
    nav.mode = MouseMode::Cursor;
    // The pointer at the top-right quarter: ndc (0.5, −0.5), half a metre right and up.
    nav.handle(MouseEvent::Press(MouseButton::Left, Vec2::new(300.0, 50.0)), &inv, dir);
    let p = nav.tool_position_m;
    assert!((p - Vec3::new(0.5 * VIEWPORT.x / VIEWPORT.y, 0.5, 0.0)).length() < 1e-4, "{p:?}");
    nav.handle(MouseEvent::Move(Vec2::new(200.0, 100.0)), &inv, dir);
    assert!(nav.tool_position_m.length() < 1e-4, "the centre of the screen");
    nav.handle(MouseEvent::Wheel(4.0), &inv, dir);
    assert!(
        (nav.tool_position_m - Vec3::new(0.0, 0.0, -0.02)).length() < 1e-6,
        "the wheel pushes the tool away"
    );
    nav.handle(MouseEvent::Release(MouseButton::Left), &inv, dir);
    nav.handle(MouseEvent::Move(Vec2::new(10.0, 10.0)), &inv, dir);
    assert!((nav.tool_position_m - Vec3::new(0.0, 0.0, -0.02)).length() < 1e-6, "released: the tool stays");
    assert_eq!(nav.scene_rotation, Quat::IDENTITY, "cursor mode never turns the scene");
}
