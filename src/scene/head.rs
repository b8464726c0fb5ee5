//! The scripted head of a scene (`[head]`): a screen calibration and keyframes of the viewer's
//! head in screen space, for head-tracked renders (fish-tank stereo) without a tracker.

use std::path::Path;

use serde::Deserialize;
use toml::Spanned;

use super::timeline::{locate, Span};
use super::{At, SceneError, ScreenCalibration};
use crate::math::{Pose, Quat, Vec3};

/// One keyframe of the head.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadKey {
    /// Time, seconds.
    pub time_s: f32,
    /// The head in screen space (the point between the eyes; +X from the left eye to the
    /// right).
    pub pose: Pose,
}

/// A scripted head path and the screen it looks at.
#[derive(Clone, Debug, PartialEq)]
pub struct HeadPath {
    /// The screen, viewer and tracker calibration.
    pub calibration: ScreenCalibration,
    /// Keys sorted by time.
    pub keys: Vec<HeadKey>,
}

impl HeadPath {
    /// The head at `t`: interpolated between keys (straight line, spherical rotation), resting
    /// at the first key before it and the last after it; at the calibration's default eye
    /// without keys.
    pub fn pose_at(&self, t: f32) -> Pose {
        match locate(&self.keys, t, |k| k.time_s) {
            None => self.calibration.default_head(),
            Some(Span::Rest(k)) => k.pose,
            Some(Span::Between(a, b, u)) => a.pose.lerp(&b.pose, u),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct HeadSpec {
    calibration: Option<Spanned<String>>,
    #[serde(default)]
    key: Vec<Spanned<HeadKeySpec>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HeadKeySpec {
    time_s: f32,
    position_m: [f32; 3],
    #[serde(default)]
    yaw_deg: f32,
    #[serde(default)]
    pitch_deg: f32,
    #[serde(default)]
    roll_deg: f32,
}

/// Validates `[head]`; a relative calibration path is resolved against `base_dir`.
pub(super) fn resolve_head(
    spec: &HeadSpec,
    base_dir: Option<&Path>,
    at: &At<'_>,
) -> Result<HeadPath, SceneError> {
    let calibration = match &spec.calibration {
        None => ScreenCalibration::shipped(),
        Some(p) => {
            let path = Path::new(p.get_ref());
            let path = match base_dir {
                Some(dir) if path.is_relative() => dir.join(path),
                _ => path.to_owned(),
            };
            ScreenCalibration::load(&path).map_err(|e| match e {
                SceneError::Read { .. } => at(
                    Some(p.span()),
                    format!("[head] cannot read the screen calibration {}: {e}", path.display()),
                ),
                invalid => invalid,
            })?
        }
    };
    let facing = calibration.default_head().rotation;
    let mut keys: Vec<(usize, HeadKey)> = Vec::with_capacity(spec.key.len());
    for (i, spanned) in spec.key.iter().enumerate() {
        let k = spanned.get_ref();
        let span = Some(spanned.span());
        if !(k.time_s.is_finite() && k.time_s >= 0.0) {
            return Err(at(span, format!("[[head.key]] time_s must be zero or positive, not {}", k.time_s)));
        }
        let numbers = k.position_m.iter().chain([&k.yaw_deg, &k.pitch_deg, &k.roll_deg]);
        if !numbers.clone().all(|v| v.is_finite() && v.abs() <= 1000.0) {
            return Err(at(span, "[[head.key]] position_m and angles must be finite numbers".to_owned()));
        }
        let position_m = Vec3::from(k.position_m);
        let d = calibration.screen.signed_distance_m(position_m);
        if d <= 0.0 {
            return Err(at(
                span,
                format!("[[head.key]] the head must be in front of the screen (+Z in screen space), not {d:.3} m from it"),
            ));
        }
        let [yaw, pitch, roll] = [k.yaw_deg, k.pitch_deg, k.roll_deg].map(f32::to_radians);
        let rotation = facing * Quat::from_euler(glam::EulerRot::YXZ, yaw, pitch, roll);
        keys.push((i, HeadKey { time_s: k.time_s, pose: Pose { position_m, rotation } }));
    }
    keys.sort_by(|a, b| a.1.time_s.total_cmp(&b.1.time_s).then(a.0.cmp(&b.0)));
    if let Some(w) = keys.windows(2).find(|w| w[0].1.time_s == w[1].1.time_s) {
        return Err(at(Some(spec.key[w[1].0].span()), format!("two head keys at {} s", w[1].1.time_s)));
    }
    Ok(HeadPath { calibration, keys: keys.into_iter().map(|(_, k)| k).collect() })
}

#[cfg(test)]
mod tests {
    use super::super::Scene;
    use super::*;

    #[test]
    fn head_keys_interpolate_in_screen_space() {
        let s = Scene::parse(
            "[head]\n[[head.key]]\ntime_s = 0.0\nposition_m = [-0.1, 0.0, 0.6]\n\
             [[head.key]]\ntime_s = 2.0\nposition_m = [0.1, 0.05, 0.5]\nyaw_deg = 20.0\n",
            "h.toml",
            None,
        )
        .unwrap();
        let head = s.head.as_ref().unwrap();
        assert_eq!(head.calibration, ScreenCalibration::shipped());
        let mid = head.pose_at(1.0);
        assert!((mid.position_m - Vec3::new(0.0, 0.025, 0.55)).length() < 1e-6);
        assert!((mid.rotation.angle_between(Quat::IDENTITY).to_degrees() - 10.0).abs() < 1e-3);
        assert_eq!(head.pose_at(-1.0), head.keys[0].pose);
        assert_eq!(head.pose_at(9.0), head.keys[1].pose);
        let rig = s.head_tracked_rig().unwrap();
        assert_eq!(rig.interaxial_m, head.calibration.ipd_m);
        assert!(Scene::default_scene().head.is_none());
        let still = Scene::parse("[head]\n", "h.toml", None).unwrap();
        assert_eq!(still.head.unwrap().pose_at(3.0).position_m, Vec3::new(0.0, 0.0, 0.6), "the default eye");
    }

    #[test]
    fn bad_head_keys_and_calibrations_are_named() {
        let cases = [
            ("[head]\n[[head.key]]\ntime_s = 0.0\nposition_m = [0.0, 0.0, -0.2]\n", "h.toml:2:1", "in front of the screen"),
            (
                "[head]\n[[head.key]]\ntime_s = 1.0\nposition_m = [0.0, 0.0, 0.5]\n[[head.key]]\ntime_s = 1.0\nposition_m = [0.0, 0.0, 0.6]\n",
                "h.toml:5:1",
                "two head keys",
            ),
            ("[head]\ncalibration = \"no-such-screen.toml\"\n", "h.toml:2:15", "cannot read the screen calibration"),
            ("[head]\nkeys = []\n", "h.toml:2:1", "unknown field"),
        ];
        super::super::tests::assert_refused(&cases, |t| Scene::parse(t, "h.toml", None));
    }
}
