//! The mouse: a virtual trackball to turn the scene (Ferley et al. §2), drag and wheel for
//! distance, and a 3D cursor mode that moves the tool.
//!
//! Trackball geometry (Shoemake's arcball, Graphics Gems IV; Bell's trackball, in Gavin
//! Bell's `trackball.c`): the viewport's inscribed circle is a ball seen from the front, in
//! *ball coordinates* (centre 0, radius 1, x right, y up, z towards the viewer):
//!
//! ```text
//!         y                 Shoemake: inside the circle, z = √(1 − x² − y²) (the sphere);
//!    .----|----.                      outside, the point moves to the rim (z = 0).
//!   /     |     \           Bell:     inside r² ≤ ½, the sphere; outside, the hyperbolic
//!  |      o------|-- x                sheet z = ½ / |p|, so the rim is no edge.
//!   \           /
//!    '---------'            Rotation of a drag step p0 → p1: about p0 × p1,
//!                           Shoemake by twice the arc angle, Bell by the arc angle.
//! ```
//!
//! A drag is applied as a sequence of steps between successive mouse positions; each step's
//! rotation is the inverse of the step taken backwards, so retracing a path restores the
//! orientation. Dragging right turns the front of the scene to the right (a positive turn about
//! +y). Distance changes are multiplicative (each wheel step or drag pixel scales it), clamped.
//!
//! The settings (trackball, its speed and direction, the wheel's zoom step and direction, the
//! 3D cursor's plane) are data: `calibration/mouse.toml`, layered like the other device files
//! (a user file names only what it changes; errors give file, line and column).

use std::path::Path;

use serde::Deserialize;
use toml::Spanned;

use super::calibration::{read_text, CalibrationError, Layer};
use crate::math::{Mat4, Quat, Vec2, Vec3, Vec4};

/// The shipped mouse settings, embedded in the binary; `calibration/mouse.toml` documents
/// every key.
pub const SHIPPED_MOUSE_TOML: &str = include_str!("../../calibration/mouse.toml");

/// Which trackball.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrackballKind {
    /// Shoemake's arcball: the rotation is twice the arc between the two ball points, so a
    /// drag from the centre to the rim turns half a turn and retracing always restores.
    Shoemake,
    /// Bell's trackball: a sphere blended into a hyperbolic sheet; the rotation is the arc.
    Bell,
}

/// Where a point in ball coordinates lies on the trackball surface (a unit vector for
/// Shoemake, a point on the sphere or sheet for Bell).
pub fn project_to_ball(p: Vec2, kind: TrackballKind) -> Vec3 {
    let p = if p.is_finite() { p } else { Vec2::ZERO };
    let r2 = p.length_squared();
    match kind {
        TrackballKind::Shoemake => {
            if r2 <= 1.0 {
                Vec3::new(p.x, p.y, (1.0 - r2).sqrt())
            } else {
                (p / r2.sqrt()).extend(0.0)
            }
        }
        TrackballKind::Bell => {
            if r2 <= 0.5 {
                Vec3::new(p.x, p.y, (1.0 - r2).sqrt())
            } else {
                Vec3::new(p.x, p.y, 0.5 / r2.sqrt())
            }
        }
    }
}

/// The rotation of one drag step from `from` to `to` (ball coordinates).
pub fn trackball_rotation(from: Vec2, to: Vec2, kind: TrackballKind) -> Quat {
    let a = project_to_ball(from, kind).normalize_or_zero();
    let b = project_to_ball(to, kind).normalize_or_zero();
    let axis = a.cross(b);
    let sin = axis.length();
    if sin < 1e-9 {
        // No step, or exactly opposite points (only reachable in one jump across the rim, with
        // no defined axis): no rotation rather than an arbitrary one.
        return Quat::IDENTITY;
    }
    let arc = sin.atan2(a.dot(b));
    let angle = match kind {
        TrackballKind::Shoemake => 2.0 * arc,
        TrackballKind::Bell => arc,
    };
    Quat::from_axis_angle(axis / sin, angle)
}

/// Converts a pixel position (origin top left, y down) to ball coordinates for a viewport of
/// `size_px`: the ball is the inscribed circle.
pub fn pixel_to_ball(pixel: Vec2, size_px: Vec2) -> Vec2 {
    let half = size_px * 0.5;
    let radius = half.min_element().max(1.0);
    Vec2::new(pixel.x - half.x, half.y - pixel.y) / radius
}

/// Converts a pixel position to Vulkan's normalised device coordinates (x right, y down, −1 to
/// 1), which the renderer's projections ([`crate::stereo::vulkan_frustum`]) map to.
pub fn pixel_to_ndc(pixel: Vec2, size_px: Vec2) -> Vec2 {
    let size = size_px.max(Vec2::ONE);
    Vec2::new(2.0 * pixel.x / size.x - 1.0, 2.0 * pixel.y / size.y - 1.0)
}

/// The world-space ray under a point in normalised device coordinates, given the inverse of
/// the view-projection matrix (Vulkan depth 0 to 1): its origin on the near plane and its unit
/// direction. `None` if the matrix is degenerate.
pub fn cursor_ray(ndc: Vec2, inverse_view_projection: &Mat4) -> Option<(Vec3, Vec3)> {
    let unproject = |z: f32| {
        let p = *inverse_view_projection * Vec4::new(ndc.x, ndc.y, z, 1.0);
        (p.w.abs() > 1e-12).then(|| p.truncate() / p.w)
    };
    let near = unproject(0.0)?;
    let far = unproject(1.0)?;
    let dir = (far - near).try_normalize()?;
    near.is_finite().then_some((near, dir))
}

/// Where the ray under `ndc` meets the plane through `plane_point` with normal `plane_normal`
/// (the 3D cursor). `None` if the ray runs parallel to the plane or meets it behind the viewer.
pub fn cursor_on_plane(
    ndc: Vec2,
    inverse_view_projection: &Mat4,
    plane_point: Vec3,
    plane_normal: Vec3,
) -> Option<Vec3> {
    let (origin, dir) = cursor_ray(ndc, inverse_view_projection)?;
    let denom = dir.dot(plane_normal);
    if denom.abs() < 1e-6 {
        return None;
    }
    let t = (plane_point - origin).dot(plane_normal) / denom;
    (t >= 0.0 && t.is_finite()).then(|| origin + dir * t)
}

/// A mouse button.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MouseButton {
    /// Left: turn (trackball), or carry the tool in cursor mode.
    Left,
    /// Right: drag up and down for distance.
    Right,
    /// Middle.
    Middle,
}

/// What the mouse did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MouseEvent {
    /// A button went down at a pixel.
    Press(MouseButton, Vec2),
    /// A button went up.
    Release(MouseButton),
    /// The pointer moved to a pixel.
    Move(Vec2),
    /// Wheel steps (positive: away from the user).
    Wheel(f32),
}

/// What the mouse drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MouseMode {
    /// Trackball, drag and wheel turn and bring the scene nearer or farther.
    Scene,
    /// The pointer is a 3D cursor carrying the tool in the plane facing the viewer through the
    /// tool; the wheel moves the tool in depth.
    Cursor,
}

/// The plane the 3D cursor carries the tool in (through the tool).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CursorPlane {
    /// Facing the viewer: the tool stays under the pointer at its depth.
    View,
    /// The ground plane (normal +Y): the tool slides at its height.
    Horizontal,
}

/// Mouse navigation settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MouseSettings {
    /// Which trackball.
    pub trackball: TrackballKind,
    /// Turn per drag as a multiple of the trackball's own.
    pub trackball_speed: f32,
    /// Reverse the trackball's turn (the viewer goes round the scene).
    pub invert_trackball: bool,
    /// Reverse the wheel.
    pub invert_wheel: bool,
    /// The 3D cursor's plane.
    pub cursor_plane: CursorPlane,
    /// Tool motion per pointer motion in the cursor's clutch (relative) mode.
    pub clutch_gain: f32,
    /// Distance factor per wheel step (distance × factor^steps; below 1: the wheel away brings
    /// the scene nearer).
    pub wheel_factor: f32,
    /// Distance factor per pixel of right-button drag (downwards is farther).
    pub drag_factor_per_px: f32,
    /// Closest viewing distance, metres.
    pub min_distance_m: f32,
    /// Farthest viewing distance, metres.
    pub max_distance_m: f32,
    /// Tool depth step per wheel step in cursor mode, metres.
    pub cursor_depth_step_m: f32,
}

impl Default for MouseSettings {
    /// The values of the shipped `calibration/mouse.toml` (a test holds them equal).
    fn default() -> Self {
        Self {
            trackball: TrackballKind::Shoemake,
            trackball_speed: 1.0,
            invert_trackball: false,
            invert_wheel: false,
            cursor_plane: CursorPlane::View,
            clutch_gain: 1.0,
            wheel_factor: 0.9,
            drag_factor_per_px: 1.005,
            min_distance_m: 0.05,
            max_distance_m: 20.0,
            cursor_depth_step_m: 0.005,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MouseFile {
    trackball: Option<TrackballKind>,
    trackball_speed: Option<Spanned<f32>>,
    invert_trackball: Option<bool>,
    wheel_zoom_step: Option<Spanned<f32>>,
    invert_wheel: Option<bool>,
    drag_zoom_per_px: Option<Spanned<f32>>,
    min_distance_m: Option<Spanned<f32>>,
    max_distance_m: Option<Spanned<f32>>,
    cursor_plane: Option<CursorPlane>,
    cursor_depth_step_m: Option<Spanned<f32>>,
    clutch_gain: Option<Spanned<f32>>,
}

impl MouseSettings {
    /// The shipped settings (`calibration/mouse.toml`, embedded).
    pub fn shipped() -> Self {
        Self::parse_layer(SHIPPED_MOUSE_TOML, "calibration/mouse.toml", None)
            .expect("the shipped mouse settings are valid (tested)")
    }

    /// Loads a settings file, layered over the shipped defaults.
    pub fn load(path: &Path) -> Result<Self, CalibrationError> {
        let text = read_text(path, "mouse settings")?;
        Self::parse_layer(&text, &path.display().to_string(), Some(&Self::shipped()))
    }

    /// Parses settings text over `base`; without a base every key must be present. `name` is
    /// used in messages.
    pub fn parse_layer(text: &str, name: &str, base: Option<&Self>) -> Result<Self, CalibrationError> {
        let layer = Layer { text, name, what: "mouse settings file" };
        let file: MouseFile =
            crate::scene::parse_toml(text).map_err(|(span, message)| layer.at(span, message))?;
        let trackball = layer.value(file.trackball, "trackball", base.map(|b| b.trackball))?;
        let cursor_plane = layer.value(file.cursor_plane, "cursor_plane", base.map(|b| b.cursor_plane))?;
        let trackball_speed = layer.number(
            file.trackball_speed,
            "trackball_speed",
            0.1..=10.0,
            base.map(|b| b.trackball_speed),
        )?;
        let wheel_zoom_step = layer.number(
            file.wheel_zoom_step,
            "wheel_zoom_step",
            0.01..=0.5,
            base.map(|b| 1.0 - b.wheel_factor),
        )?;
        let drag_zoom_per_px = layer.number(
            file.drag_zoom_per_px,
            "drag_zoom_per_px",
            0.0001..=0.05,
            base.map(|b| b.drag_factor_per_px - 1.0),
        )?;
        let min_distance_m = layer.number(
            file.min_distance_m,
            "min_distance_m",
            0.01..=1000.0,
            base.map(|b| b.min_distance_m),
        )?;
        let max_span = file.max_distance_m.as_ref().map(Spanned::span);
        let max_distance_m = layer.number(
            file.max_distance_m,
            "max_distance_m",
            0.01..=1000.0,
            base.map(|b| b.max_distance_m),
        )?;
        if min_distance_m >= max_distance_m {
            return Err(layer.at(
                max_span,
                format!(
                    "`max_distance_m` ({max_distance_m}) must be farther than `min_distance_m` ({min_distance_m})"
                ),
            ));
        }
        let cursor_depth_step_m = layer.number(
            file.cursor_depth_step_m,
            "cursor_depth_step_m",
            0.0001..=0.1,
            base.map(|b| b.cursor_depth_step_m),
        )?;
        Ok(Self {
            trackball,
            trackball_speed,
            invert_trackball: layer.value(
                file.invert_trackball,
                "invert_trackball",
                base.map(|b| b.invert_trackball),
            )?,
            invert_wheel: layer.value(file.invert_wheel, "invert_wheel", base.map(|b| b.invert_wheel))?,
            cursor_plane,
            clutch_gain: layer.number(
                file.clutch_gain,
                "clutch_gain",
                0.05..=4.0,
                base.map(|b| b.clutch_gain),
            )?,
            wheel_factor: 1.0 - wheel_zoom_step,
            drag_factor_per_px: 1.0 + drag_zoom_per_px,
            min_distance_m,
            max_distance_m,
            cursor_depth_step_m,
        })
    }
}

impl MouseSettings {
    /// A trackball step as these settings turn it: its angle times the speed, reversed when
    /// inverted (so retracing a path still restores the orientation).
    pub fn turn(&self, step: Quat) -> Quat {
        let gain = if self.invert_trackball { -self.trackball_speed } else { self.trackball_speed };
        if gain == 1.0 {
            return step;
        }
        Quat::from_scaled_axis(step.to_scaled_axis() * gain)
    }
}

/// The mouse as a scene navigator and 3D cursor: a small state machine fed [`MouseEvent`]s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MouseNavigator {
    /// Settings.
    pub settings: MouseSettings,
    /// What the mouse drives.
    pub mode: MouseMode,
    /// The scene's orientation as turned by the trackball.
    pub scene_rotation: Quat,
    /// Viewing distance, metres.
    pub distance_m: f32,
    /// The tool position the cursor mode moves.
    pub tool_position_m: Vec3,
    viewport_px: Vec2,
    last: Option<Vec2>,
    left: bool,
    right: bool,
}

impl MouseNavigator {
    /// A navigator for a viewport of `viewport_px` pixels, at `distance_m`.
    pub fn new(settings: MouseSettings, viewport_px: Vec2, distance_m: f32) -> Self {
        Self {
            settings,
            mode: MouseMode::Scene,
            scene_rotation: Quat::IDENTITY,
            distance_m: distance_m.clamp(settings.min_distance_m, settings.max_distance_m),
            tool_position_m: Vec3::ZERO,
            viewport_px,
            last: None,
            left: false,
            right: false,
        }
    }

    /// The window was resized.
    pub fn resize(&mut self, viewport_px: Vec2) {
        self.viewport_px = viewport_px;
    }

    /// Folds one event in. `inverse_view_projection` and `view_direction` (unit, world) place
    /// the 3D cursor; they are only read in cursor mode. Non-finite positions are ignored.
    pub fn handle(&mut self, event: MouseEvent, inverse_view_projection: &Mat4, view_direction: Vec3) {
        match event {
            MouseEvent::Press(button, at) => {
                if !at.is_finite() {
                    return;
                }
                match button {
                    MouseButton::Left => self.left = true,
                    MouseButton::Right => self.right = true,
                    MouseButton::Middle => {}
                }
                self.last = Some(at);
                if self.mode == MouseMode::Cursor && button == MouseButton::Left {
                    self.place_cursor(at, inverse_view_projection, view_direction);
                }
            }
            MouseEvent::Release(button) => match button {
                MouseButton::Left => self.left = false,
                MouseButton::Right => self.right = false,
                MouseButton::Middle => {}
            },
            MouseEvent::Move(at) => {
                if !at.is_finite() {
                    return;
                }
                let Some(previous) = self.last.replace(at) else { return };
                match self.mode {
                    MouseMode::Scene if self.left => {
                        let from = pixel_to_ball(previous, self.viewport_px);
                        let to = pixel_to_ball(at, self.viewport_px);
                        let step = self.settings.turn(trackball_rotation(from, to, self.settings.trackball));
                        self.scene_rotation = (step * self.scene_rotation).normalize();
                    }
                    MouseMode::Scene if self.right => {
                        let dy = at.y - previous.y;
                        self.scale_distance(self.settings.drag_factor_per_px.powf(dy));
                    }
                    MouseMode::Cursor if self.left => {
                        self.place_cursor(at, inverse_view_projection, view_direction)
                    }
                    _ => {}
                }
            }
            MouseEvent::Wheel(steps) => {
                if !steps.is_finite() {
                    return;
                }
                let steps = if self.settings.invert_wheel { -steps } else { steps };
                match self.mode {
                    MouseMode::Scene => self.scale_distance(self.settings.wheel_factor.powf(steps)),
                    MouseMode::Cursor => {
                        let d = view_direction.try_normalize().unwrap_or(Vec3::NEG_Z);
                        self.tool_position_m += d * (steps * self.settings.cursor_depth_step_m);
                    }
                }
            }
        }
    }

    /// Whether the left button is down (in cursor mode, the tool is being carried).
    pub fn left_held(&self) -> bool {
        self.left
    }

    /// Where the pointer was last seen, pixels (the viewport's centre before any).
    pub fn last_position(&self) -> Vec2 {
        self.last.unwrap_or(self.viewport_px * 0.5)
    }

    fn scale_distance(&mut self, factor: f32) {
        // A huge wheel turn underflows the factor to 0 or overflows it to infinity: both
        // clamp to the range, as the user meant.
        if factor >= 0.0 {
            let s = self.settings;
            self.distance_m = (self.distance_m * factor).clamp(s.min_distance_m, s.max_distance_m);
        }
    }

    fn place_cursor(&mut self, at: Vec2, inverse_view_projection: &Mat4, view_direction: Vec3) {
        let ndc = pixel_to_ndc(at, self.viewport_px);
        let normal = match self.settings.cursor_plane {
            CursorPlane::View => view_direction.try_normalize().unwrap_or(Vec3::NEG_Z),
            CursorPlane::Horizontal => Vec3::Y,
        };
        if let Some(p) = cursor_on_plane(ndc, inverse_view_projection, self.tool_position_m, normal) {
            self.tool_position_m = p;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::{FRAC_PI_2, PI};

    #[test]
    fn projection_is_on_the_surface() {
        for kind in [TrackballKind::Shoemake, TrackballKind::Bell] {
            assert_eq!(project_to_ball(Vec2::ZERO, kind), Vec3::Z);
            assert_eq!(project_to_ball(Vec2::new(f32::NAN, 0.0), kind), Vec3::Z);
        }
        assert!(
            (project_to_ball(Vec2::new(3.0, 4.0), TrackballKind::Shoemake) - Vec3::new(0.6, 0.8, 0.0))
                .length()
                < 1e-6
        );
        // Bell's sheet meets the sphere at r² = ½ (z = 1/√2 on both sides).
        let r = std::f32::consts::FRAC_1_SQRT_2;
        let inside = project_to_ball(Vec2::new(r - 1e-4, 0.0), TrackballKind::Bell).z;
        let outside = project_to_ball(Vec2::new(r + 1e-4, 0.0), TrackballKind::Bell).z;
        assert!((inside - outside).abs() < 1e-3);
        assert_eq!(trackball_rotation(Vec2::X, Vec2::NEG_X, TrackballKind::Shoemake), Quat::IDENTITY);
    }

    #[test]
    fn dragging_right_turns_the_front_to_the_right() {
        let q = trackball_rotation(Vec2::ZERO, Vec2::new(0.1, 0.0), TrackballKind::Bell);
        let front = q * Vec3::Z;
        assert!(front.x > 0.0 && front.y.abs() < 1e-6, "{front:?}");
        let q = trackball_rotation(Vec2::ZERO, Vec2::new(0.0, 0.1), TrackballKind::Bell);
        assert!((q * Vec3::Z).y > 0.0, "dragging up turns the front up");
        // And pixel rows grow downwards.
        assert!(pixel_to_ball(Vec2::new(50.0, 0.0), Vec2::new(100.0, 100.0)).y > 0.0);
    }

    #[test]
    fn cursor_lands_under_the_pointer() {
        let view = Mat4::look_at_rh(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, Vec3::Y);
        let proj = Mat4::perspective_rh(FRAC_PI_2, 1.0, 0.1, 10.0);
        let inv = (proj * view).inverse();
        let p = cursor_on_plane(Vec2::new(0.5, 0.0), &inv, Vec3::ZERO, Vec3::Z).unwrap();
        // 90° field of view at distance 1: ndc 0.5 is half a metre right.
        assert!((p - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-4, "{p:?}");
        let back = proj * view * p.extend(1.0);
        assert!(((back.truncate() / back.w).truncate() - Vec2::new(0.5, 0.0)).length() < 1e-4);
        assert_eq!(cursor_on_plane(Vec2::ZERO, &inv, Vec3::ZERO, Vec3::X), None, "parallel plane");
        assert_eq!(
            cursor_on_plane(Vec2::ZERO, &inv, Vec3::new(0.0, 0.0, 5.0), Vec3::Z),
            None,
            "behind the viewer"
        );
        assert_eq!(cursor_ray(Vec2::ZERO, &Mat4::ZERO), None);
        let _ = PI;
    }

    #[test]
    fn the_shipped_settings_are_the_defaults_and_user_files_layer_over_them() {
        assert_eq!(MouseSettings::shipped(), MouseSettings::default());
        let base = MouseSettings::shipped();
        let mine = MouseSettings::parse_layer(
            "trackball_speed = 2.0\ninvert_wheel = true\ncursor_plane = \"horizontal\"\nwheel_zoom_step = 0.2\n",
            "mine.toml",
            Some(&base),
        )
        .unwrap();
        assert_eq!(mine.trackball_speed, 2.0);
        assert!(mine.invert_wheel && !mine.invert_trackball);
        assert_eq!(mine.cursor_plane, CursorPlane::Horizontal);
        assert!((mine.wheel_factor - 0.8).abs() < 1e-6);
        assert_eq!(mine.trackball, base.trackball, "unnamed keys keep the shipped value");

        let err =
            |text: &str| MouseSettings::parse_layer(text, "mine.toml", Some(&base)).unwrap_err().to_string();
        let e = err("trackball_speed = 1.0\ntrackbal = \"bell\"\n");
        assert!(e.starts_with("mine.toml:2:1:") && e.contains("trackbal"), "{e}");
        let e = err("wheel_zoom_step = 0.9\n");
        assert!(e.starts_with("mine.toml:1:19:") && e.contains("between 0.01 and 0.5"), "{e}");
        let e = err("cursor_plane = \"diagonal\"\n");
        assert!(e.starts_with("mine.toml:1:16:") && e.contains("diagonal"), "{e}");
        let e = err("min_distance_m = 2.0\nmax_distance_m = 1.0\n");
        assert!(e.starts_with("mine.toml:2:18:") && e.contains("farther"), "{e}");
        let e =
            MouseSettings::parse_layer("trackball = \"bell\"\n", "alone.toml", None).unwrap_err().to_string();
        assert!(e.contains("missing"), "{e}");
    }

    #[test]
    fn speed_invert_and_cursor_plane_settings_change_what_the_mouse_does() {
        let identity = Mat4::IDENTITY;
        let drag = |settings: MouseSettings| {
            let mut m = MouseNavigator::new(settings, Vec2::new(100.0, 100.0), 1.0);
            m.handle(MouseEvent::Press(MouseButton::Left, Vec2::new(50.0, 50.0)), &identity, Vec3::NEG_Z);
            m.handle(MouseEvent::Move(Vec2::new(60.0, 50.0)), &identity, Vec3::NEG_Z);
            m.scene_rotation.to_axis_angle()
        };
        let (axis, angle) = drag(MouseSettings::default());
        let (fast_axis, fast) = drag(MouseSettings { trackball_speed: 2.0, ..MouseSettings::default() });
        assert!((fast - 2.0 * angle).abs() < 1e-5 && (fast_axis - axis).length() < 1e-5);
        let (back_axis, back) = drag(MouseSettings { invert_trackball: true, ..MouseSettings::default() });
        assert!((back - angle).abs() < 1e-5 && (back_axis + axis).length() < 1e-5, "reversed");

        let wheel = |settings: MouseSettings| {
            let mut m = MouseNavigator::new(settings, Vec2::new(100.0, 100.0), 1.0);
            m.handle(MouseEvent::Wheel(1.0), &identity, Vec3::NEG_Z);
            m.distance_m
        };
        assert!(wheel(MouseSettings::default()) < 1.0);
        assert!(wheel(MouseSettings { invert_wheel: true, ..MouseSettings::default() }) > 1.0);

        // The horizontal cursor plane keeps the tool at its height whatever the pointer does.
        let view = Mat4::look_at_rh(Vec3::new(0.0, 1.0, 1.0), Vec3::ZERO, Vec3::Y);
        let inv = (Mat4::perspective_rh(FRAC_PI_2, 1.0, 0.1, 10.0) * view).inverse();
        let forward = (Vec3::ZERO - Vec3::new(0.0, 1.0, 1.0)).normalize();
        let settings = MouseSettings { cursor_plane: CursorPlane::Horizontal, ..MouseSettings::default() };
        let mut m = MouseNavigator::new(settings, Vec2::new(100.0, 100.0), 1.0);
        m.mode = MouseMode::Cursor;
        m.handle(MouseEvent::Press(MouseButton::Left, Vec2::new(70.0, 40.0)), &inv, forward);
        assert!(m.tool_position_m.y.abs() < 1e-5 && m.tool_position_m.x > 0.01, "{}", m.tool_position_m);
        let mut v = MouseNavigator::new(MouseSettings::default(), Vec2::new(100.0, 100.0), 1.0);
        v.mode = MouseMode::Cursor;
        v.handle(MouseEvent::Press(MouseButton::Left, Vec2::new(70.0, 40.0)), &inv, forward);
        assert!(
            v.tool_position_m.y.abs() > 0.01,
            "the view plane tilts with the view: {}",
            v.tool_position_m
        );
    }
}
