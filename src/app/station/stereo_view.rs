//! The stereo view, one part of the station: how the pair is seen (the display's calibration,
//! the viewer's head, convergence and interaxial, the parallax budget) and shown (the display
//! mode, its parity and what masks its edges).

use super::super::comfort::{measure_parallax, over_budget, Seen};
use crate::input::opentrack::OpentrackHead;
use crate::math::{Aabb, Vec2, Vec3};
use crate::scene::{Scene, ScreenCalibration};
use crate::stereo::comfort::{AutoConvergence, BudgetCheck};
use crate::stereo::display::{DisplayMode, Parity};
use crate::stereo::floating::FloatingWindow;
use crate::stereo::{HeadTrackedRig, Placement, StereoRig};

/// What a parallax budget verdict depends on: the clay's bounds, the stereo rig (eye,
/// convergence, interaxial, the tracked eyes' interaxial) and how the window shows it.
type BudgetKey = ([f32; 6], [f32; 3], [f32; 3], ((u32, u32), DisplayMode, bool));

/// The parallax budget's last verdict (see [`StereoView::judge_parallax`]).
#[derive(Clone, Debug)]
pub(super) struct Budgeted {
    /// What it was judged on.
    key: BudgetKey,
    /// The check and the warning, when over the budget.
    pub(super) over: Option<(BudgetCheck, String)>,
    /// The interaxial it allows in limit mode (of the tracked eyes while tracked).
    allowed: Option<f32>,
    /// The check whether over or not, and the budget's bound, degrees (the panel's readout);
    /// `None` with nothing in view.
    pub(super) readout: Option<(BudgetCheck, f32)>,
}

/// The stereo view: the display's calibration, the viewer's head, the convergence and the
/// distance between the eyes, the parallax budget, the display mode and what it shows.
#[derive(Debug)]
pub(super) struct StereoView {
    /// The convergence plane's distance as a share of the mouse's viewing distance (the
    /// convergence keys and the panel's slider change it; the view zoom keeps it).
    pub(super) convergence_factor: f32,
    /// The lights turn with the viewer instead of staying with the scene.
    pub(super) lights_follow_viewer: bool,
    /// The display, its screen and the viewer.
    pub(super) calibration: ScreenCalibration,
    /// Where the viewer's head is, for head-tracked views: opentrack, else the scene's
    /// scripted head, else none (the scene's camera rig).
    pub(super) head: Option<OpentrackHead>,
    /// Keeps the desk tool at zero parallax while on.
    pub(super) auto_convergence: Option<AutoConvergence>,
    /// The parallax budget's verdict for what is shown now: what it was judged on, the check
    /// and warning when over budget, and the interaxial it allows in limit mode (of the
    /// head-tracked eyes when the views are head-tracked).
    pub(super) budget: Option<Budgeted>,
    /// The distance between the eyes of head-tracked views, physical metres: the calibrated
    /// viewer's, until the interaxial keys or the budget's limit change it.
    pub(super) tracked_interaxial_m: f32,
    /// Seconds since the views became head-tracked (they ease in from the untracked views).
    pub(super) tracked_for_s: Option<f32>,
    /// Each eye gets the other's image.
    pub(super) swap_eyes: bool,
    /// Whether the floating window masks the pictures' edges, and the strips it masks now
    /// (eased towards the measured ones).
    pub(super) floating_window: (bool, FloatingWindow),
    /// The interlace parity (a frame-sequential display's phase) is the calibration's flipped.
    pub(super) parity_flipped: bool,
    /// Frames the window has shown (a frame-sequential display alternates eyes by it).
    pub(super) frames_shown: u64,
    /// How the window shows the stereo pair.
    pub(super) display_mode: DisplayMode,
    /// Whether the window's surface can show quad-buffer stereo.
    pub(super) quad_buffer: bool,
    /// The window's top-left corner on the screen, pixels (interlace parity follows it).
    pub(super) window_origin: (i32, i32),
    /// The window's size, pixels (the display mode shares it between the eyes).
    pub(super) window_px: (u32, u32),
    /// The monitor's resolution as the window system gives it (when the calibration does not).
    pub(super) monitor_px: Option<(u32, u32)>,
    /// The views are head-tracked without a tracker: the scene scripts the head, or the
    /// calibration's pattern is seen from its adjusted eye.
    pub(super) tracked_without_tracker: bool,
}

impl StereoView {
    /// The view of `scene` in a window of `window_px`: its rig's convergence, its calibration
    /// (see [`super::super::comfort::scene_calibration`]) and display options; anaglyph until
    /// the window's surface is known.
    pub(super) fn new(scene: &Scene, window_px: (u32, u32)) -> Self {
        let rig = &scene.rig;
        let calibration = super::super::comfort::scene_calibration(scene);
        Self {
            convergence_factor: rig.convergence_m / (rig.eye_m - rig.target_m).length().max(1e-6),
            lights_follow_viewer: false,
            calibration,
            tracked_interaxial_m: calibration.ipd_m,
            tracked_for_s: None,
            swap_eyes: scene.display.swap_eyes,
            floating_window: (scene.display.floating_window, FloatingWindow::NONE),
            parity_flipped: false,
            frames_shown: 0,
            head: None,
            auto_convergence: None,
            budget: None,
            display_mode: DisplayMode::Anaglyph,
            quad_buffer: false,
            window_origin: (0, 0),
            window_px,
            monitor_px: None,
            tracked_without_tracker: scene.head.is_some(),
        }
    }

    /// The display mode and, for interlaced modes, the parity in window pixels (the
    /// calibration's parity is the screen's; a window on an odd row or column flips it).
    pub(super) fn display(&self) -> (DisplayMode, Parity) {
        let screen = self.display_phase();
        let parity = match self.display_mode {
            DisplayMode::ColumnInterlaced => screen.for_origin(self.window_origin.0),
            DisplayMode::FrameSequential => screen.for_frame(self.frames_shown),
            _ => screen.for_origin(self.window_origin.1),
        };
        (self.display_mode, parity)
    }

    /// Each eye's picture in the window, pixels (at least 1 × 1), and the picture the mouse
    /// reads the pointer in.
    pub(super) fn eye_pictures(&self) -> ((u32, u32), Vec2) {
        let (w, h) = self.display_mode.eye_size_for_output(self.window_px);
        let (_, picture) = self.display_mode.pointer_in_eye(Vec2::ZERO, self.window_px);
        ((w.max(1), h.max(1)), picture)
    }

    /// Where the window's pixel `p` lies in the picture of the eye it shows.
    pub(super) fn in_eye(&self, p: Vec2) -> Vec2 {
        self.display_mode.pointer_in_eye(p, self.window_px).0
    }

    /// Whether the views are head-tracked (opentrack, the scene's scripted head, or the
    /// adjusted calibration's eye).
    pub(super) fn tracked(&self) -> bool {
        self.head.is_some() || self.tracked_without_tracker
    }

    /// The distance between the eyes of the views shown: the head-tracked eyes' while
    /// tracked (physical metres), else `rig`'s.
    pub(super) fn interaxial_in_use_m(&self, rig: &StereoRig) -> f32 {
        match self.tracked() {
            true => self.tracked_interaxial_m,
            false => rig.interaxial_m,
        }
    }

    /// That distance, to change.
    pub(super) fn interaxial_in_use<'a>(&'a mut self, rig: &'a mut StereoRig) -> &'a mut f32 {
        match self.tracked() {
            true => &mut self.tracked_interaxial_m,
            false => &mut rig.interaxial_m,
        }
    }

    /// Puts the convergence plane `m` metres from the eye, within `rig`'s
    /// [`StereoRig::convergence_range`], as a share of the mouse's viewing distance
    /// `distance_m`; returns where it went.
    pub(super) fn set_convergence(&mut self, m: f32, rig: &StereoRig, distance_m: f32) -> f32 {
        let (lo, hi) = rig.convergence_range();
        let kept = m.clamp(lo, hi);
        self.convergence_factor = kept / distance_m.max(1e-6);
        kept
    }

    /// Moves the convergence plane by `factor` within [`StereoRig::convergence_range`]; says
    /// so at either end.
    pub(super) fn step_convergence(
        &mut self,
        factor: f32,
        rig: &StereoRig,
        distance_m: f32,
    ) -> Option<String> {
        let wanted = self.convergence_factor * factor * distance_m.max(1e-6);
        let kept = self.set_convergence(wanted, rig, distance_m);
        (kept != wanted).then(|| {
            let end = match kept == rig.convergence_range().0 {
                true => "nearest, twice the near plane",
                false => "farthest, half the far plane",
            };
            format!("convergence {kept:.2} m: at its {end}")
        })
    }

    /// Puts `rig`'s convergence plane for a frame `dt_s` long, seen from the mouse's viewing
    /// distance `distance_m`: the zoom moves it with the clay, within the keys' range; auto
    /// convergence follows the desk tool at `tool_m`.
    pub(super) fn converge(&mut self, rig: &mut StereoRig, distance_m: f32, tool_m: Vec3, dt_s: f32) {
        let (lo, hi) = rig.convergence_range();
        rig.convergence_m = (distance_m * self.convergence_factor).clamp(lo, hi);
        if let Some(auto) = &mut self.auto_convergence {
            // The desk tool's depth along the view, smoothly.
            let depth = (tool_m - rig.eye_m).dot(rig.forward());
            rig.convergence_m = auto.update(depth, dt_s);
            self.convergence_factor = rig.convergence_m / distance_m.max(1e-6);
        }
    }

    /// Scales the interaxial distance in use (the head-tracked eyes' while tracked) by
    /// `factor`, up to [`StereoRig::MAX_INTERAXIAL_M`]; says so at the end.
    pub(super) fn step_interaxial(&mut self, factor: f32, rig: &mut StereoRig) -> Option<String> {
        let interaxial = self.interaxial_in_use(rig);
        let wanted = *interaxial * factor;
        *interaxial = wanted.min(StereoRig::MAX_INTERAXIAL_M);
        (wanted > StereoRig::MAX_INTERAXIAL_M).then(|| {
            format!(
                "eyes {:.0} mm apart: at the most the station allows",
                StereoRig::MAX_INTERAXIAL_M * 1000.0
            )
        })
    }

    /// The rig of head-tracked views of `rig`, while tracked: its convergence plane on the
    /// calibrated screen (or `placement`, where given), the eyes
    /// [`StereoView::tracked_interaxial_m`] apart.
    pub(super) fn tracked_rig(
        &self,
        rig: &StereoRig,
        placement: Option<Placement>,
    ) -> Option<HeadTrackedRig> {
        let c = &self.calibration;
        self.tracked().then(|| HeadTrackedRig {
            screen: c.screen,
            placement: placement.unwrap_or_else(|| Placement::from_rig(&c.screen, c.default_eye_m, rig)),
            interaxial_m: self.tracked_interaxial_m,
            near_m: rig.near_m,
            far_m: rig.far_m,
        })
    }

    /// The window's eyes' pictures as seen on the calibrated screen, whose resolution the
    /// calibration gives, else the window system.
    pub(super) fn seen_window(&self) -> Seen {
        let screen_px = self.calibration.resolution_px.or(self.monitor_px);
        Seen::window(self.calibration, self.display_mode, self.window_px, screen_px)
    }

    /// How the parallax budget sees the window: each eye's picture on the calibrated screen.
    pub(super) fn describe_picture(&self) -> String {
        let seen = self.seen_window();
        let from = match (self.calibration.resolution_px, self.monitor_px) {
            (Some((w, h)), _) => format!("a {w}x{h} screen, as the calibration says"),
            (None, Some((w, h))) => format!("a {w}x{h} monitor, as the window system says"),
            (None, None) => "a screen of unknown resolution: fitted to it".to_owned(),
        };
        format!(
            "parallax budget: each eye's picture is {:.0} mm wide on the {:.0} mm screen ({} pixels of {from}), \
             seen from {:.2} m, within ±{:.2}°",
            seen.picture_width_m * 1000.0,
            self.calibration.screen.width_m() * 1000.0,
            self.display_mode.eye_size_for_output(self.window_px).0,
            self.calibration.viewing_distance_m(),
            self.calibration.budget.max_disparity_deg
        )
    }

    /// Why head-tracked views look different from a camera rig's of `scene_fov_deg`: the
    /// screen, seen from the default eye, spans its own field of view, which the scene's camera
    /// may not.
    pub(super) fn tracking_notice(&self, scene_fov_deg: f32) -> String {
        let c = &self.calibration;
        let screen_fov = 2.0 * (0.5 * c.screen.height_m() / c.viewing_distance_m()).atan().to_degrees();
        let grows = (0.5 * scene_fov_deg.to_radians()).tan() / (0.5 * screen_fov.to_radians()).tan();
        if (grows - 1.0).abs() < 0.02 {
            "head tracking: the views follow your head through the calibrated screen".to_owned()
        } else {
            format!(
                "head tracking: the views follow your head through the calibrated screen, which spans \
                 {screen_fov:.1}° from the default eye where the scene's camera shows {scene_fov_deg:.1}°: \
                 the clay looks {grows:.2} times as large (easing in over {:.1} s)",
                c.tracker.ease_s
            )
        }
    }

    /// Checks what `view` shows (the clay within `clay` and the stage) against the parallax
    /// budget of the screen calibration, as the window shows it on the screen and with the
    /// views' own eyes (the head-tracked ones while tracked, on `placement` where given), when
    /// any of that changed since the last check. Returns the warning to show when the view
    /// goes over the budget.
    pub(super) fn judge_parallax(
        &mut self,
        view: &Scene,
        clay: Aabb,
        placement: Option<Placement>,
    ) -> Option<String> {
        let rig = &view.rig;
        let key: BudgetKey = (
            [clay.min.x, clay.min.y, clay.min.z, clay.max.x, clay.max.y, clay.max.z],
            rig.eye_m.to_array(),
            [rig.convergence_m, rig.interaxial_m, self.tracked_interaxial_m],
            (self.window_px, self.display_mode, self.tracked()),
        );
        if self.budget.as_ref().is_some_and(|b| b.key == key) {
            return None;
        }
        let seen = Seen { tracked: self.tracked_rig(rig, placement), ..self.seen_window() };
        let measured = measure_parallax(view, &seen, clay);
        let readout = measured.as_ref().map(|m| (m.check, seen.calibration.budget.max_disparity_deg));
        let verdict = measured.and_then(|m| over_budget(view, &seen, m));
        // Limit mode narrows the eyes in use: the rig's, or the tracked eyes' (physical metres).
        let allowed = verdict.as_ref().filter(|v| v.limit).map(|v| v.check.allowed_interaxial_m / v.scale);
        let over = verdict.map(|v| (v.check, v.warning));
        let newly_over = self.budget.as_ref().is_none_or(|b| b.over.is_none());
        let warning = over.as_ref().filter(|_| newly_over).map(|(_, w)| w.clone());
        self.budget = Some(Budgeted { key, over, allowed, readout });
        warning
    }

    /// In the budget's limit mode, the eyes in use (`rig`'s, or the tracked ones) no farther
    /// apart than the last verdict allows.
    pub(super) fn limit_interaxial(&mut self, rig: &mut StereoRig) {
        if let Some(Budgeted { allowed: Some(allowed), .. }) = self.budget {
            let interaxial = self.interaxial_in_use(rig);
            *interaxial = interaxial.min(allowed);
        }
    }

    /// The display's parity in screen rows (columns), or a frame-sequential display's phase:
    /// the calibration's, flipped by P.
    pub(super) fn display_phase(&self) -> Parity {
        match self.parity_flipped {
            true => self.calibration.display.parity.flipped(),
            false => self.calibration.display.parity,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stereo::comfort::BudgetMode;

    /// A head-tracked scene (its scripted head) without a stage, whose budget warns or limits.
    fn tracked_scene(limit: bool) -> Scene {
        let text = "[head]\n[stage]\nshow = false\n";
        let mut s = Scene::parse(text, "tracked.toml", None).unwrap();
        if let Some(h) = &mut s.head {
            h.calibration.budget.mode = if limit { BudgetMode::Limit } else { BudgetMode::Warn };
        }
        s
    }

    #[test]
    fn convergence_keeps_to_its_range_and_says_which_end_it_reached() {
        let scene = Scene::parse("", "plain.toml", None).unwrap();
        let mut stereo = StereoView::new(&scene, (320, 240));
        let rig = scene.rig;
        let (lo, hi) = rig.convergence_range();
        assert!(lo == 2.0 * rig.near_m && hi > lo);
        let distance = 0.5;
        assert!(stereo.step_convergence(1.1, &rig, distance).is_none(), "a step within the range");
        let far = (0..200).find_map(|_| stereo.step_convergence(1.5, &rig, distance)).unwrap();
        assert!(
            far.contains("farthest") && (stereo.convergence_factor * distance - hi).abs() < 1e-5,
            "{far}"
        );
        let near = (0..200).find_map(|_| stereo.step_convergence(0.5, &rig, distance)).unwrap();
        assert!(
            near.contains("nearest") && (stereo.convergence_factor * distance - lo).abs() < 1e-6,
            "{near}"
        );
        // The zoom keeps the plane's share of the viewing distance, within the range.
        let mut moved = rig;
        assert_eq!(stereo.set_convergence(0.3, &rig, distance), 0.3);
        stereo.converge(&mut moved, 2.0 * distance, Vec3::ZERO, 1.0 / 60.0);
        assert!((moved.convergence_m - 0.6).abs() < 1e-5, "{}", moved.convergence_m);
        stereo.converge(&mut moved, 1e6, Vec3::ZERO, 1.0 / 60.0);
        assert_eq!(moved.convergence_m, hi);
    }

    #[test]
    fn the_interaxial_in_use_is_the_tracked_eyes_while_tracked_and_stops_at_its_most() {
        let untracked = Scene::parse("", "plain.toml", None).unwrap();
        let mut stereo = StereoView::new(&untracked, (320, 240));
        let mut rig = untracked.rig;
        assert!(!stereo.tracked());
        let (before, tracked_before) = (rig.interaxial_m, stereo.tracked_interaxial_m);
        assert!(stereo.step_interaxial(0.5, &mut rig).is_none());
        assert_eq!((rig.interaxial_m, stereo.tracked_interaxial_m), (before * 0.5, tracked_before));
        // A tracker (here the scene's head) moves the tracked eyes instead.
        let scene = tracked_scene(false);
        let mut stereo = StereoView::new(&scene, (320, 240));
        let mut rig = scene.rig;
        assert!(stereo.tracked());
        assert_eq!(stereo.tracked_interaxial_m, scene.head.as_ref().unwrap().calibration.ipd_m);
        let said = (0..100).find_map(|_| stereo.step_interaxial(1.5, &mut rig)).unwrap();
        assert!(said.contains("at the most"), "{said}");
        assert_eq!(stereo.tracked_interaxial_m, StereoRig::MAX_INTERAXIAL_M);
        assert_eq!(rig.interaxial_m, scene.rig.interaxial_m, "the rig's eyes stay");
        assert_eq!(stereo.interaxial_in_use_m(&rig), StereoRig::MAX_INTERAXIAL_M);
        let tracked = stereo.tracked_rig(&rig, None).unwrap();
        assert_eq!(tracked.interaxial_m, StereoRig::MAX_INTERAXIAL_M);
    }

    #[test]
    fn the_budget_warns_once_and_in_limit_mode_narrows_the_eyes_in_use() {
        // Clay from 30 cm in front of the screen to 2 m behind it.
        let deep = Aabb { min: Vec3::new(-0.1, -0.1, -2.0), max: Vec3::new(0.1, 0.1, 0.3) };
        for limit in [false, true] {
            let scene = tracked_scene(limit);
            let mut stereo = StereoView::new(&scene, (640, 360));
            let mut rig = scene.rig;
            let warning = stereo.judge_parallax(&scene, deep, None).expect("over the budget");
            assert!(warning.contains("beyond the comfortable"), "{warning}");
            let over = stereo.budget.as_ref().and_then(|b| b.over.as_ref()).map(|(c, _)| c.exceeded);
            assert_eq!(over, Some(true));
            assert!(stereo.judge_parallax(&scene, deep, None).is_none(), "said once");
            let ipd = stereo.tracked_interaxial_m;
            stereo.limit_interaxial(&mut rig);
            match limit {
                false => assert_eq!(stereo.tracked_interaxial_m, ipd, "warn mode leaves the eyes"),
                true => assert!(stereo.tracked_interaxial_m < ipd, "{}", stereo.tracked_interaxial_m),
            }
            assert_eq!(rig.interaxial_m, scene.rig.interaxial_m, "the rig's eyes are not the tracked ones");
        }
        // Shallow clay is within the budget, and the readout still reports it.
        let scene = tracked_scene(false);
        let mut stereo = StereoView::new(&scene, (640, 360));
        let shallow = Aabb { min: Vec3::new(-0.1, -0.1, -0.05), max: Vec3::new(0.1, 0.1, 0.03) };
        assert!(stereo.judge_parallax(&scene, shallow, None).is_none());
        let budget = stereo.budget.as_ref().unwrap();
        assert!(budget.over.is_none() && budget.readout.is_some_and(|(c, bound)| !c.exceeded && bound > 0.0));
    }
}
