//! The parallax budget applied to a scene before it is rendered: the clay's depth range, seen
//! on the calibrated display, checked against `[comfort]` of the screen calibration (the
//! scene's `[head] calibration`, else the shipped `calibration/screen.toml`).

use crate::math::{Aabb, Vec3};
use crate::scene::{Scene, ScreenCalibration};
use crate::stereo::comfort::BudgetCheck;
use crate::stereo::display::DisplayMode;
use crate::stereo::{BudgetMode, HeadTrackedRig};

/// The budget's verdict on a scene's clay when it exceeds the budget.
#[derive(Clone, Debug)]
pub struct BudgetVerdict {
    /// The check of the clay's depth range.
    pub check: BudgetCheck,
    /// Whether the budget asks to lower the interaxial (rather than only warn).
    pub limit: bool,
    /// World metres per physical metre of the head-tracked placement (1 without a head).
    pub scale: f32,
    /// A sentence for the user (empty where it fits, from [`measure_parallax`]).
    pub warning: String,
}

/// Where the eyes' pictures are seen: the calibrated screen, how wide each eye's picture is on
/// it, and the head-tracked rig the views come from when they are head-tracked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seen {
    /// The screen, the viewer and the budget.
    pub calibration: ScreenCalibration,
    /// Width of each eye's picture on the screen, metres.
    pub picture_width_m: f32,
    /// The head-tracked rig, when the views are seen through the screen from a tracked head.
    pub tracked: Option<HeadTrackedRig>,
}

impl Seen {
    /// Pictures of `eye_px` pixels shown on their own on the calibrated screen (a render, a
    /// test pattern): as large as the screen holds them, the screen's width or, for a picture
    /// narrower than the screen's aspect, its height times the picture's aspect.
    pub fn fitted(calibration: ScreenCalibration, eye_px: (u32, u32)) -> Self {
        let aspect = eye_px.0.max(1) as f32 / eye_px.1.max(1) as f32;
        let (w, h) = (calibration.screen.width_m(), calibration.screen.height_m());
        Self { calibration, picture_width_m: w.min(h * aspect), tracked: None }
    }

    /// A window of `window_px` showing `mode` on a screen of `screen_px` pixels: each eye's
    /// picture is the window's share of the screen's width (half the window in full
    /// side-by-side; the whole window in the squeezed modes, which the display stretches back);
    /// without the screen's resolution, as [`Seen::fitted`].
    pub fn window(
        calibration: ScreenCalibration,
        mode: DisplayMode,
        window_px: (u32, u32),
        screen_px: Option<(u32, u32)>,
    ) -> Self {
        let eye = mode.eye_size_for_output(window_px);
        match screen_px {
            Some((screen_w, _)) if screen_w > 0 => Self {
                calibration,
                picture_width_m: calibration.screen.width_m() * eye.0 as f32 / screen_w as f32,
                tracked: None,
            },
            _ => Self::fitted(calibration, eye),
        }
    }
}

/// Lattice points a side of each stage wall is sampled at, to find the part of it in view.
const WALL_SAMPLES: usize = 17;

/// Depths (by `depth_of`) of the points of the stage's walls that `views` show: the walls
/// seen from inside (the eye on a wall's inner side, as the renderer draws them: back faces
/// only), sampled on a grid, each point kept where either eye's frustum holds it.
fn stage_depths(
    stage: &crate::scene::StageSettings,
    views: &crate::render::StereoViews,
    depth_of: &dyn Fn(Vec3) -> f32,
) -> Vec<f32> {
    let eye = views.eyes.iter().map(|e| e.view.inverse().w_axis.truncate()).sum::<Vec3>() * 0.5;
    let clips: Vec<_> = views.eyes.iter().map(|e| e.projection * e.view).collect();
    let seen = |p: Vec3| {
        clips.iter().any(|m| {
            let c = *m * p.extend(1.0);
            c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w && (0.0..=c.w).contains(&c.z)
        })
    };
    let (lo, hi) = (stage.min_m, stage.max_m);
    let mut depths = Vec::new();
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for (plane, inside) in [(lo[axis], eye[axis] > lo[axis]), (hi[axis], eye[axis] < hi[axis])] {
            if !inside {
                continue;
            }
            for i in 0..WALL_SAMPLES {
                for j in 0..WALL_SAMPLES {
                    let t = |k: usize| k as f32 / (WALL_SAMPLES - 1) as f32;
                    let mut p = Vec3::ZERO;
                    p[axis] = plane;
                    p[u] = lo[u] + (hi[u] - lo[u]) * t(i);
                    p[v] = lo[v] + (hi[v] - lo[v]) * t(j);
                    if seen(p) {
                        depths.push(depth_of(p));
                    }
                }
            }
        }
    }
    depths
}

/// Checks what is shown — the clay inside `clay`, and the part of the stage's walls in view
/// when the stage is shown — against the budget of `seen`'s calibration, seen from the default
/// eye, without changing the scene; `None` when it fits.
pub fn judge_parallax_budget(scene: &Scene, seen: &Seen, clay: Aabb) -> Option<BudgetVerdict> {
    over_budget(scene, seen, measure_parallax(scene, seen, clay)?)
}

/// `verdict` of [`measure_parallax`] with its warning, when it is over `seen`'s budget.
pub fn over_budget(scene: &Scene, seen: &Seen, verdict: BudgetVerdict) -> Option<BudgetVerdict> {
    let warning = format!("{}: {}", scene.source, verdict.check.warning(&seen.calibration.budget)?);
    Some(BudgetVerdict { warning, ..verdict })
}

/// What [`judge_parallax_budget`] measures, whether or not it fits (the nearest and farthest
/// disparity, the interaxial allowed), its warning empty; `None` when nothing is shown.
pub fn measure_parallax(scene: &Scene, seen: &Seen, clay: Aabb) -> Option<BudgetVerdict> {
    let corners: Vec<Vec3> = if clay.is_empty() {
        Vec::new()
    } else {
        (0..8)
            .map(|i| {
                let pick = |bit: u32, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
                Vec3::new(
                    pick(1, clay.min.x, clay.max.x),
                    pick(2, clay.min.y, clay.max.y),
                    pick(4, clay.min.z, clay.max.z),
                )
            })
            .collect()
    };
    let c = &seen.calibration;
    let budget = c.budget;
    let aspect = scene.output.width_px as f32 / scene.output.height_px as f32;
    let eye = c.default_head();
    type DepthOf = Box<dyn Fn(Vec3) -> f32>;
    let (views, depth_of, viewing, near_m, scale): (_, DepthOf, _, _, _) = match seen.tracked {
        Some(rig) => (
            rig.views(&eye),
            Box::new(move |p| rig.depth_of(&eye, p)),
            rig.viewing(&eye),
            rig.near_m,
            rig.placement.scale,
        ),
        None => {
            let rig = scene.rig;
            let viewing = rig.viewing(seen.picture_width_m, c.viewing_distance_m(), c.ipd_m, aspect);
            (rig.views(aspect), Box::new(move |p| rig.depth_of(p)), viewing, rig.near_m, 1.0)
        }
    };
    let mut depths: Vec<f32> = corners.iter().map(|&p| depth_of(p)).collect();
    if let Some(stage) = &scene.stage {
        depths.extend(stage_depths(stage, &views, &*depth_of));
    }
    if depths.is_empty() {
        return None;
    }
    let (near, far) = depths
        .iter()
        .fold((f32::INFINITY, 0.0f32), |(lo, hi), &z| (lo.min(z.max(near_m)), hi.max(z.max(near_m))));
    let check = budget.check(&viewing, near, far);
    Some(BudgetVerdict { check, limit: budget.mode == BudgetMode::Limit, scale, warning: String::new() })
}

/// The calibration a scene is seen through when nothing else names one: its `[head]`
/// calibration, else the shipped `calibration/screen.toml`.
pub fn scene_calibration(scene: &Scene) -> ScreenCalibration {
    scene.head.as_ref().map_or_else(ScreenCalibration::shipped, |h| h.calibration)
}

/// [`judge_parallax_budget`] of a render of `scene` (its clay `clay` and its stage) through
/// `calibration`, then in `limit` mode the scene's interaxial distance (its `[head]`'s
/// calibrated eye separation when head-tracked) is lowered until it fits. Returns the check
/// and the sentence for the user when it was exceeded.
pub fn apply_parallax_budget(
    scene: &mut Scene,
    calibration: ScreenCalibration,
    clay: Aabb,
) -> Option<(BudgetCheck, String)> {
    let seen = Seen {
        tracked: scene.head_tracked_rig(),
        ..Seen::fitted(calibration, (scene.output.width_px, scene.output.height_px))
    };
    let verdict = judge_parallax_budget(scene, &seen, clay)?;
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
        let text = "[head]\n[stage]\nshow = false\n[[capture]]\nname = \"c\"\ntime_s = 0.0\n";
        let mut s = Scene::parse(text, "deep.toml", None).unwrap();
        if let Some(h) = &mut s.head {
            h.calibration.budget.mode = if limit { BudgetMode::Limit } else { BudgetMode::Warn };
        }
        s
    }

    fn apply(scene: &mut Scene, clay: Aabb) -> Option<(BudgetCheck, String)> {
        let calibration = scene_calibration(scene);
        apply_parallax_budget(scene, calibration, clay)
    }

    #[test]
    fn a_deep_sculpture_is_warned_about_and_limited_on_request() {
        // Clay from 30 cm in front of the screen to 2 m behind it, seen from 60 cm.
        let deep = Aabb { min: Vec3::new(-0.1, -0.1, -2.0), max: Vec3::new(0.1, 0.1, 0.3) };
        let mut warned = deep_scene(false);
        let (check, message) = apply(&mut warned, deep).expect("beyond the budget");
        assert!(message.starts_with("deep.toml: stereo disparity") && check.exceeded, "{message}");
        assert_eq!(warned.head_tracked_rig().unwrap().interaxial_m, 0.063, "warning only");
        let mut limited = deep_scene(true);
        apply(&mut limited, deep).expect("beyond the budget");
        let rig = limited.head_tracked_rig().unwrap();
        assert!((rig.interaxial_m - check.allowed_interaxial_m).abs() < 1e-6 && rig.interaxial_m < 0.063);
        assert!(apply(&mut limited, deep).is_none(), "now within the budget");
        let shallow = Aabb { min: Vec3::new(-0.1, -0.1, -0.05), max: Vec3::new(0.1, 0.1, 0.03) };
        assert!(apply(&mut deep_scene(false), shallow).is_none());
        assert!(apply(&mut deep_scene(false), Aabb::EMPTY).is_none());
    }

    fn wide_scene(extra: &str) -> Scene {
        let text = format!(
            "[camera]\neye_m = [0.0, 0.0, 0.6]\ninteraxial_m = 0.2\n[output]\nwidth_px = 1600\nheight_px = 900\n{extra}\n"
        );
        Scene::parse(&text, "wide.toml", None).unwrap()
    }

    #[test]
    fn a_scene_without_a_head_is_judged_on_the_calibration_given() {
        let clay = Aabb { min: Vec3::new(-0.1, -0.1, -0.3), max: Vec3::new(0.1, 0.1, 0.2) };
        let mut s = wide_scene("[stage]\nshow = false");
        let (check, _) = apply(&mut s, clay).expect("a 20 cm interaxial exceeds the shipped budget");
        assert_eq!(s.rig.interaxial_m, 0.2, "warned only: the shipped budget warns");
        // The same clay on a 65-inch screen seen from 2.5 m: the same parallax on the screen
        // (the picture is 2.7 times as wide) subtends less from 4.2 times as far.
        let tv = ScreenCalibration::parse(
            "[screen]\nwidth_m = 1.439\nheight_m = 0.809\n[viewer]\ndefault_eye_m = [0, 0, 2.5]\n",
            "tv.toml",
        )
        .unwrap();
        let seen = Seen::fitted(tv, (1600, 900));
        let on_tv = judge_parallax_budget(&s, &seen, clay).map(|v| v.check);
        let on_tv = on_tv.expect("still over ±1°");
        let ratio = on_tv.farthest_deg / check.farthest_deg;
        assert!((ratio - 1.439 / 0.53131 * 0.6 / 2.5).abs() < 0.02, "{ratio}");
        // A budget of 9° takes it all (its nearest point is 7.5°).
        let lenient = ScreenCalibration::parse("[comfort]\nmax_disparity_deg = 9\n", "lenient.toml").unwrap();
        assert!(judge_parallax_budget(&s, &Seen::fitted(lenient, (1600, 900)), clay).is_none());
    }

    #[test]
    fn a_picture_is_as_wide_as_it_shows_on_the_screen() {
        let shipped = ScreenCalibration::shipped();
        let (w, h) = (shipped.screen.width_m(), shipped.screen.height_m());
        // A 16:9 picture fills the 16:9 screen; a square one is as wide as the screen is high.
        assert!((Seen::fitted(shipped, (1920, 1080)).picture_width_m - w).abs() < 1e-4);
        assert!((Seen::fitted(shipped, (1024, 1024)).picture_width_m - h).abs() < 1e-6);
        // A 1024-pixel window on a 1920-pixel monitor covers 1024/1920 of its width; each eye
        // of full side-by-side half of that; a squeezed half, stretched by the display, all.
        let screen = Some((1920, 1080));
        let window = |mode| Seen::window(shipped, mode, (1024, 600), screen).picture_width_m;
        assert!((window(DisplayMode::Anaglyph) - w * 1024.0 / 1920.0).abs() < 1e-6);
        assert!((window(DisplayMode::SideBySide) - w * 512.0 / 1920.0).abs() < 1e-6);
        assert!((window(DisplayMode::SideBySideHalf) - w * 1024.0 / 1920.0).abs() < 1e-6);
        // The screen's resolution unknown: the eye's picture fitted to the screen.
        let unknown = Seen::window(shipped, DisplayMode::Anaglyph, (1024, 600), None);
        assert_eq!(unknown, Seen::fitted(shipped, (1024, 600)));
    }

    #[test]
    fn the_stage_is_judged_with_the_clay() {
        // Clay at the convergence plane fits; a stage whose back wall is 2 m behind it does not.
        let clay = Aabb { min: Vec3::splat(-0.01), max: Vec3::splat(0.01) };
        let deep = wide_scene("[stage]\nmin_m = [-0.3, -0.2, -2.0]\nmax_m = [0.3, 0.3, 0.3]");
        let seen = Seen::fitted(ScreenCalibration::shipped(), (1600, 900));
        let verdict = judge_parallax_budget(&deep, &seen, clay).expect("the back wall is over the budget");
        assert!(verdict.check.farthest_deg > 1.0, "{}", verdict.warning);
        let bare = wide_scene("[stage]\nshow = false");
        assert!(judge_parallax_budget(&bare, &seen, clay).is_none());
        // The walls' parts out of view are not judged: the stage's near corners lie beside
        // the eye, far outside the picture.
        let near = wide_scene("[stage]\nmin_m = [-0.3, -0.2, -0.2]\nmax_m = [0.3, 0.3, 0.55]");
        let judged = judge_parallax_budget(&near, &seen, clay).map(|v| v.check.nearest_deg);
        assert!(judged.is_none_or(|d| d > -3.0), "{judged:?}");
    }
}
