//! The parallax budget applied to a scene before it is rendered: the clay's depth range, seen
//! on the calibrated display, checked against `[comfort]` of the screen calibration (the
//! scene's `[head] calibration`, else the shipped `calibration/screen.toml`).

use crate::math::{Aabb, Vec3};
use crate::scene::{Scene, ScreenCalibration};
use crate::stereo::comfort::BudgetCheck;
use crate::stereo::BudgetMode;

/// The budget's verdict on a scene's clay when it exceeds the budget.
#[derive(Clone, Debug)]
pub struct BudgetVerdict {
    /// The check of the clay's depth range.
    pub check: BudgetCheck,
    /// Whether the budget asks to lower the interaxial (rather than only warn).
    pub limit: bool,
    /// World metres per physical metre of the head-tracked placement (1 without a head).
    scale: f32,
    /// A sentence for the user.
    pub warning: String,
}

/// Checks the clay inside `clay` against the budget, seen from the default eye, without
/// changing the scene; `None` when it fits.
pub fn judge_parallax_budget(scene: &Scene, clay: Aabb) -> Option<BudgetVerdict> {
    if clay.is_empty() {
        return None;
    }
    let corners: Vec<Vec3> = (0..8)
        .map(|i| {
            let pick = |bit: u32, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
            Vec3::new(
                pick(1, clay.min.x, clay.max.x),
                pick(2, clay.min.y, clay.max.y),
                pick(4, clay.min.z, clay.max.z),
            )
        })
        .collect();
    let range = |depths: &mut dyn Iterator<Item = f32>, near_m: f32| {
        depths.fold((f32::INFINITY, 0.0f32), |(lo, hi), z| (lo.min(z.max(near_m)), hi.max(z.max(near_m))))
    };
    let (check, budget, scale) = match (&scene.head, scene.head_tracked_rig()) {
        (Some(head), Some(rig)) => {
            let eye = head.calibration.default_head();
            let (near, far) = range(&mut corners.iter().map(|&c| rig.depth_of(&eye, c)), rig.near_m);
            let budget = head.calibration.budget;
            (budget.check(&rig.viewing(&eye), near, far), budget, rig.placement.scale)
        }
        _ => {
            let display = ScreenCalibration::shipped();
            let aspect = scene.output.width_px as f32 / scene.output.height_px as f32;
            let viewing = scene.rig.viewing(
                display.screen.width_m(),
                display.viewing_distance_m(),
                display.ipd_m,
                aspect,
            );
            let (near, far) = range(&mut corners.iter().map(|&c| scene.rig.depth_of(c)), scene.rig.near_m);
            (display.budget.check(&viewing, near, far), display.budget, 1.0)
        }
    };
    let warning = format!("{}: {}", scene.source, check.warning(&budget)?);
    Some(BudgetVerdict { check, limit: budget.mode == BudgetMode::Limit, scale, warning })
}

/// [`judge_parallax_budget`], then in `limit` mode the scene's interaxial distance is lowered
/// until the clay fits. Returns the check and the sentence for the user when it was exceeded.
pub fn apply_parallax_budget(scene: &mut Scene, clay: Aabb) -> Option<(BudgetCheck, String)> {
    let verdict = judge_parallax_budget(scene, clay)?;
    if verdict.limit {
        let allowed = verdict.check.allowed_interaxial_m;
        match &mut scene.head {
            // The head-tracked interaxial is the calibrated eye separation, in physical metres.
            Some(head) => head.calibration.ipd_m = allowed / verdict.scale,
            None => scene.rig.set_interaxial_m(allowed),
        }
    }
    Some((verdict.check, verdict.warning))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deep_scene(limit: bool) -> Scene {
        let text = "[head]\n[[capture]]\nname = \"c\"\ntime_s = 0.0\n";
        let mut s = Scene::parse(text, "deep.toml", None).unwrap();
        if let Some(h) = &mut s.head {
            h.calibration.budget.mode = if limit { BudgetMode::Limit } else { BudgetMode::Warn };
        }
        s
    }

    #[test]
    fn a_deep_sculpture_is_warned_about_and_limited_on_request() {
        // Clay from 30 cm in front of the screen to 2 m behind it, seen from 60 cm.
        let deep = Aabb { min: Vec3::new(-0.1, -0.1, -2.0), max: Vec3::new(0.1, 0.1, 0.3) };
        let mut warned = deep_scene(false);
        let (check, message) = apply_parallax_budget(&mut warned, deep).expect("beyond the budget");
        assert!(message.starts_with("deep.toml: stereo disparity") && check.exceeded, "{message}");
        assert_eq!(warned.head_tracked_rig().unwrap().interaxial_m, 0.063, "warning only");
        let mut limited = deep_scene(true);
        apply_parallax_budget(&mut limited, deep).expect("beyond the budget");
        let rig = limited.head_tracked_rig().unwrap();
        assert!((rig.interaxial_m - check.allowed_interaxial_m).abs() < 1e-6 && rig.interaxial_m < 0.063);
        assert!(apply_parallax_budget(&mut limited, deep).is_none(), "now within the budget");
        let shallow = Aabb { min: Vec3::new(-0.1, -0.1, -0.05), max: Vec3::new(0.1, 0.1, 0.03) };
        assert!(apply_parallax_budget(&mut deep_scene(false), shallow).is_none());
        assert!(apply_parallax_budget(&mut deep_scene(false), Aabb::EMPTY).is_none());
    }

    #[test]
    fn a_scene_without_a_head_is_judged_on_the_shipped_display() {
        let mut s = Scene::parse(
            "[camera]\neye_m = [0.0, 0.0, 0.6]\ninteraxial_m = 0.2\n[[capture]]\nname = \"c\"\ntime_s = 0.0\n",
            "wide.toml",
            None,
        )
        .unwrap();
        let clay = Aabb { min: Vec3::new(-0.1, -0.1, -0.3), max: Vec3::new(0.1, 0.1, 0.2) };
        assert!(apply_parallax_budget(&mut s, clay).is_some(), "a 20 cm interaxial exceeds the budget");
        assert_eq!(s.rig.interaxial_m, 0.2, "warned only: the shipped budget warns");
    }
}
