//! `argile calibrate --adjust`: the station shows the calibration's test pattern, and keys
//! change the screen's size, the viewing distance and the IPD while it shows; the changes are
//! written back to the calibration file.
//!
//! The pattern is built once, in the screen space of the calibration it started from. A
//! change of size scales that world about the screen's centre with the screen (the grid keeps
//! spanning it, and its lines stay a known fraction of its width apart); the eye is placed by
//! the calibration as it stands. The ruler, the letters and the crosstalk squares are drawn
//! for the picture as it is now seen.

use std::path::PathBuf;

use super::Station;
use crate::app::calibrate::{adjusted, eye_marks, write_calibration, Adjustment, TestPattern};
use crate::config::StationAction;
use crate::math::Vec3;
use crate::render::EyeMark;
use crate::scene::ScreenCalibration;
use crate::stereo::screen::Placement;
use crate::stereo::screen_parallax_m;

/// Width change of one press, metres (ten times that with Shift).
pub const WIDTH_STEP_M: f32 = 0.001;
/// Distance change of one press, metres (ten times that with Shift).
pub const DISTANCE_STEP_M: f32 = 0.005;
/// IPD change of one press, metres.
pub const IPD_STEP_M: f32 = 0.0005;

/// What `argile calibrate --adjust` adjusts: a calibration file and the pattern shown.
#[derive(Clone, Debug)]
pub struct AdjustTarget {
    /// The calibration file the adjustments are written to (created when missing).
    pub file: PathBuf,
    /// The calibration the pattern is built on, which the keys then change.
    pub calibration: ScreenCalibration,
    /// What `file` says now (the shipped calibration when it does not exist yet).
    pub written: ScreenCalibration,
    /// The pattern's near and far balls' distances in front of the screen, metres.
    pub balls_in_front_m: [f32; 2],
}

impl AdjustTarget {
    /// Adjusting `calibration`, read from `file` (or the shipped one for a file to create),
    /// on `pattern`.
    pub fn new(file: PathBuf, calibration: ScreenCalibration, pattern: &TestPattern) -> Self {
        Self {
            file,
            calibration,
            written: calibration,
            balls_in_front_m: pattern.markers.each_ref().map(|m| m.in_front_m),
        }
    }
}

/// The calibration being adjusted on its test pattern.
#[derive(Debug)]
pub(crate) struct Adjusting {
    /// The calibration file the adjustments are written to.
    file: PathBuf,
    /// The calibration the pattern was built on: the world is its screen space.
    pattern: ScreenCalibration,
    /// The balls' centres' distances in front of that screen (negative: behind), metres.
    balls_in_front_m: [f32; 2],
    /// The grid's cells across the screen.
    columns: u32,
    /// What the file says now (the shipped calibration under a file not yet written).
    written: ScreenCalibration,
    /// Quit was asked once with changes not written: the next quit quits.
    quit_warned: bool,
}

impl Adjusting {
    /// Where the pattern's world sits in the screen space of `now`: scaled about the screen's
    /// centre as far as the screen has grown since the pattern was built.
    fn placement(&self, now: &ScreenCalibration) -> Placement {
        let s = now.screen.width_m() / self.pattern.screen.width_m();
        let c = self.pattern.screen.centre_m();
        Placement {
            rotation: crate::math::Quat::IDENTITY,
            translation_m: c * (1.0 - 1.0 / s),
            scale: 1.0 / s,
        }
    }
}

impl Station<'_> {
    /// Shows the station's scene, the test pattern of `target`, to adjust its calibration:
    /// the keys change it and write it to its file (see [`Station::act_adjusting`]).
    pub fn start_adjusting(&mut self, target: AdjustTarget) {
        self.adjusting = Some(Adjusting {
            file: target.file,
            pattern: target.calibration,
            balls_in_front_m: target.balls_in_front_m,
            columns: crate::app::calibrate::GRID_COLUMNS,
            written: target.written,
            quit_warned: false,
        });
        // The pattern is seen from the calibrated eye: the views are head-tracked views.
        self.stereo.tracked_without_tracker = true;
        self.set_calibration(target.calibration);
        self.messages.push(self.adjusting_keys());
    }

    /// Whether the calibration shown differs from what its file says.
    pub fn adjustments_unwritten(&self) -> bool {
        self.adjusting.as_ref().is_some_and(|a| !same_adjustables(&a.written, &self.stereo.calibration))
    }

    /// What a user leaving with changes not written needs to know: where they would have
    /// gone and the values, to write by hand.
    pub fn unwritten_adjustments(&self) -> Option<String> {
        let a = self.adjusting.as_ref().filter(|_| self.adjustments_unwritten())?;
        let c = &self.stereo.calibration;
        let e = c.default_eye_m;
        Some(format!(
            "the adjustments were not written to {}: [screen] width_m = {:.5}, height_m = {:.5}; \
             [viewer] default_eye_m = [{:.4}, {:.4}, {:.4}], ipd_m = {:.4}",
            a.file.display(),
            c.screen.width_m(),
            c.screen.height_m(),
            e.x,
            e.y,
            e.z,
            c.ipd_m
        ))
    }

    /// The keys while adjusting, as they are bound.
    fn adjusting_keys(&self) -> String {
        let keys = |a: StationAction| {
            let chords = self.controls.bindings.chords(a);
            chords.first().map_or_else(|| format!("({} unbound)", a.name()), ToString::to_string)
        };
        format!(
            "calibrating: {}/{} narrower/wider screen, {}/{} nearer/farther eye (Shift: ten times), \
             {}/{} IPD, {} or {} writes, {} back to the file's",
            keys(StationAction::PointerLeft),
            keys(StationAction::PointerRight),
            keys(StationAction::PointerToward),
            keys(StationAction::PointerAway),
            keys(StationAction::InteraxialNarrower),
            keys(StationAction::InteraxialWider),
            keys(StationAction::ApplyLattice),
            keys(StationAction::Save),
            keys(StationAction::CancelLattice),
        )
    }

    /// The keys of calibrating (their actions are the tool's and the lattice's at the desk);
    /// returns whether `action` was taken (every action but the view's is, while adjusting).
    pub(super) fn act_adjusting(&mut self, action: StationAction) -> bool {
        let Some(a) = &self.adjusting else { return false };
        let (file, written, quit_warned) = (a.file.clone(), a.written, a.quit_warned);
        let ten = if self.controls.modifiers.shift { 10.0 } else { 1.0 };
        let adjustment = match action {
            StationAction::PointerLeft => Adjustment::Width(-WIDTH_STEP_M * ten),
            StationAction::PointerRight => Adjustment::Width(WIDTH_STEP_M * ten),
            StationAction::PointerToward => Adjustment::Distance(-DISTANCE_STEP_M * ten),
            StationAction::PointerAway => Adjustment::Distance(DISTANCE_STEP_M * ten),
            StationAction::InteraxialNarrower => Adjustment::Ipd(-IPD_STEP_M),
            StationAction::InteraxialWider => Adjustment::Ipd(IPD_STEP_M),
            StationAction::Save | StationAction::ApplyLattice => {
                let said = match write_calibration(&file, &written, &self.stereo.calibration) {
                    Ok(back) => {
                        let file = file.display().to_string();
                        self.show_calibration(back);
                        if let Some(a) = &mut self.adjusting {
                            a.written = back;
                        }
                        format!("wrote the screen's size, the viewing distance and the IPD to {file}")
                    }
                    Err(e) => format!("{e:#}"),
                };
                self.messages.push(said);
                return true;
            }
            StationAction::CancelLattice => {
                self.show_calibration(written);
                self.messages.push(format!("back to what {} says", file.display()));
                return true;
            }
            StationAction::Quit => {
                if self.adjustments_unwritten() && !quit_warned {
                    let save =
                        self.controls.bindings.chords(StationAction::Save).first().map(ToString::to_string);
                    self.messages.push(format!(
                        "the adjustments are not written to {}: {} writes them; quit again to leave without",
                        file.display(),
                        save.unwrap_or_else(|| "save".to_owned())
                    ));
                    if let Some(a) = &mut self.adjusting {
                        a.quit_warned = true;
                    }
                } else {
                    self.quit = true;
                }
                return true;
            }
            // The view's keys work as at the desk: they are what the pattern checks.
            StationAction::NextDisplayMode
            | StationAction::SwapEyes
            | StationAction::FlipParity
            | StationAction::ToggleFullscreen
            | StationAction::ToggleFloatingWindow
            | StationAction::TogglePanel
            | StationAction::ToggleLights => return false,
            _ => {
                self.messages.push(self.adjusting_keys());
                return true;
            }
        };
        let now = adjusted(&self.stereo.calibration, adjustment);
        self.show_calibration(now);
        if let Some(a) = &mut self.adjusting {
            a.quit_warned = false;
        }
        true
    }

    /// While adjusting, the pointer keys with Shift (or any modifiers) held: they take ten
    /// times the step.
    pub(super) fn adjusting_step_key(&self, key: winit::keyboard::KeyCode) -> Option<StationAction> {
        self.adjusting.as_ref()?;
        self.controls.bindings.held_action(key).filter(|a| {
            matches!(
                a,
                StationAction::PointerLeft
                    | StationAction::PointerRight
                    | StationAction::PointerAway
                    | StationAction::PointerToward
            )
        })
    }

    /// Shows the pattern through `calibration` (its display settings as they are).
    fn show_calibration(&mut self, calibration: ScreenCalibration) {
        self.stereo.calibration = calibration;
        self.stereo.tracked_interaxial_m = calibration.ipd_m;
    }

    /// Where the pattern's world sits in screen space while adjusting.
    pub(super) fn adjusting_placement(&self) -> Option<Placement> {
        self.adjusting.as_ref().map(|a| a.placement(&self.stereo.calibration))
    }

    /// The marks over the pattern for the pictures as they are seen now.
    pub(super) fn adjusting_marks(&self) -> Vec<EyeMark> {
        if self.adjusting.is_none() {
            return Vec::new();
        }
        let (w, h) = (self.view.output.width_px, self.view.output.height_px);
        let seen = self.stereo.seen_window();
        eye_marks(w as f32 / h.max(1) as f32, seen.picture_width_m * 1000.0, w)
    }

    /// The heads-up display while adjusting: the calibration as it stands, what the pattern
    /// must show with it, and the keys.
    pub(super) fn adjusting_hud(&self) -> Option<Vec<String>> {
        let a = self.adjusting.as_ref()?;
        let c = &self.stereo.calibration;
        let (w, h) = (c.screen.width_m(), c.screen.height_m());
        let d = c.viewing_distance_m();
        let s = w / a.pattern.screen.width_m();
        let picture_m = self.stereo.seen_window().picture_width_m;
        let px = |m: f32| m / picture_m * self.view.output.width_px as f32;
        let balls = a.balls_in_front_m.map(|in_front| {
            let in_front = in_front * s;
            px(screen_parallax_m(c.ipd_m, d, d - in_front))
        });
        Some(vec![
            format!(
                "{}{}",
                a.file
                    .file_name()
                    .map_or_else(|| a.file.display().to_string(), |n| n.to_string_lossy().into_owned()),
                if self.adjustments_unwritten() { " (changes not written)" } else { "" }
            ),
            format!(
                "screen {:.1} x {:.1} mm ({:.1} in), eye {:.0} mm from it, IPD {:.1} mm",
                w * 1000.0,
                h * 1000.0,
                w.hypot(h) / 0.0254,
                d * 1000.0,
                c.ipd_m * 1000.0
            ),
            format!(
                "grid {:.1} mm, ruler 10 mm; red ball {:+.1} px, blue {:+.1} px",
                w / a.columns as f32 * 1000.0,
                balls[0],
                balls[1]
            ),
            format!(
                "{}{}: the L for the left eye only, the R for the right only",
                self.stereo.display_mode,
                if self.stereo.swap_eyes { ", eyes swapped" } else { "" }
            ),
        ])
    }
}

/// Whether two calibrations agree on what `--adjust` changes.
fn same_adjustables(a: &ScreenCalibration, b: &ScreenCalibration) -> bool {
    let near = |p: Vec3, q: Vec3| (p - q).abs().max_element() <= 1e-6;
    near(a.screen.lower_left_m, b.screen.lower_left_m)
        && near(a.screen.lower_right_m, b.screen.lower_right_m)
        && near(a.screen.upper_left_m, b.screen.upper_left_m)
        && near(a.default_eye_m, b.default_eye_m)
        && (a.ipd_m - b.ipd_m).abs() <= 1e-6
}

#[cfg(test)]
mod tests {
    use winit::keyboard::KeyCode;

    use super::*;
    use crate::app::calibrate::test_pattern;
    use crate::config::{KeyBindings, Modifiers};
    use crate::render::BOTH_VIEWS;

    fn press(station: &mut Station<'_>, key: KeyCode) {
        station.key(key, true);
        station.key(key, false);
    }

    /// The ruler's ticks' x, left to right (device coordinates).
    fn ticks(marks: &[EyeMark]) -> Vec<f32> {
        let mut x: Vec<f32> =
            marks.iter().filter(|m| m.views == BOTH_VIEWS && m.max[1] == 1.0).map(|m| m.min[0]).collect();
        x.sort_by(f32::total_cmp);
        x
    }

    #[test]
    fn keys_size_the_screen_move_the_eye_and_change_the_ipd_and_enter_writes_them_to_the_file() {
        let dir = std::env::temp_dir().join(format!("argile-adjust-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("mine.toml");
        let shipped = ScreenCalibration::shipped();
        let pattern = test_pattern(&shipped, 256);
        let size = (pattern.scene.output.width_px, pattern.scene.output.height_px);
        let mut station = Station::new(&pattern.scene, KeyBindings::shipped(), size, dir.join("p.argile"));
        station.start_adjusting(AdjustTarget::new(file.clone(), shipped, &pattern));
        let w0 = shipped.screen.width_m();
        let frame = station.step(1.0 / 60.0, |_| {});
        let t = ticks(&frame.eye_marks);
        assert!((t[1] - t[0] - 2.0 * 10.0 / (w0 * 1000.0)).abs() < 1e-4, "{t:?}");

        // One press of → is a millimetre wider, with Shift ten; PageUp 5 mm farther; = half a
        // millimetre more IPD.
        press(&mut station, KeyCode::ArrowRight);
        station.set_modifiers(Modifiers { shift: true, ..Modifiers::default() });
        press(&mut station, KeyCode::ArrowRight);
        station.set_modifiers(Modifiers::default());
        press(&mut station, KeyCode::PageUp);
        press(&mut station, KeyCode::Equal);
        let c = station.stereo.calibration;
        assert!((c.screen.width_m() - (w0 + 0.011)).abs() < 1e-6, "{}", c.screen.width_m());
        assert!((c.screen.aspect() - shipped.screen.aspect()).abs() < 1e-5);
        assert!((c.screen.centre_m() - shipped.screen.centre_m()).length() < 1e-6);
        assert!((c.viewing_distance_m() - 0.605).abs() < 1e-6);
        assert!((c.ipd_m - 0.0635).abs() < 1e-6);

        // The tools wait: holding Space makes no stroke.
        station.key(KeyCode::Space, true);
        let frame = station.step(1.0 / 60.0, |_| {});
        station.key(KeyCode::Space, false);
        station.step(1.0 / 60.0, |_| {});
        assert_eq!(station.field().history_stats().undo_in_memory, 0);
        // The ruler follows the new width; the pattern's world grows with the screen, so its
        // screen's corners stay on the picture's corners, seen from the moved eye.
        let t = ticks(&frame.eye_marks);
        assert!((t[1] - t[0] - 2.0 * 10.0 / ((w0 + 0.011) * 1000.0)).abs() < 1e-4, "{t:?}");
        for eye in &frame.views.eyes {
            for (corner, expected) in
                [(shipped.screen.lower_left_m, [-1.0, 1.0]), (shipped.screen.upper_left_m, [-1.0, -1.0])]
            {
                let clip = eye.projection * eye.view * corner.extend(1.0);
                let ndc = clip.truncate() / clip.w;
                assert!((ndc.x - expected[0]).abs() < 1e-3 && (ndc.y - expected[1]).abs() < 1e-3, "{ndc}");
            }
        }
        let s = (w0 + 0.011) / w0;
        let seen_eyes = (frame.views.eyes[1].position_m - frame.views.eyes[0].position_m).length();
        assert!((seen_eyes - 0.0635 / s).abs() < 1e-5, "{seen_eyes}");
        let hud = station.hud_lines().join("\n");
        assert!(
            hud.contains("screen 542.3 x 305.0 mm") && hud.contains("eye 605 mm") && hud.contains("IPD 63.5"),
            "{hud}"
        );
        assert!(hud.contains("(changes not written)"), "{hud}");

        // Leaving with changes not written asks once, and says the values.
        press(&mut station, KeyCode::Escape);
        assert!(!station.wants_quit());
        assert!(station.messages.last().unwrap().contains("quit again"), "{:?}", station.messages);
        let said = station.unwritten_adjustments().unwrap();
        assert!(said.contains("width_m = 0.54231") && said.contains("ipd_m = 0.0635"), "{said}");

        // Enter writes them: only what changed, read back as shown.
        press(&mut station, KeyCode::Enter);
        assert!(station.messages.last().unwrap().starts_with("wrote"), "{:?}", station.messages);
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(!text.contains("tracker") && !text.contains("centre_m"), "{text}");
        let back = ScreenCalibration::load(&file).unwrap();
        assert!(same_adjustables(&back, &station.stereo.calibration), "{text}");
        assert!(station.unwritten_adjustments().is_none());
        assert!(!station.hud_lines().join("\n").contains("not written"));

        // Backspace goes back to what the file says.
        press(&mut station, KeyCode::ArrowLeft);
        press(&mut station, KeyCode::Minus);
        assert!(station.adjustments_unwritten());
        press(&mut station, KeyCode::Backspace);
        assert!(same_adjustables(&station.stereo.calibration, &back));
        press(&mut station, KeyCode::Escape);
        assert!(station.wants_quit(), "nothing unwritten: quit quits");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn other_keys_say_what_the_keys_do_and_the_view_keys_still_work() {
        let shipped = ScreenCalibration::shipped();
        let pattern = test_pattern(&shipped, 128);
        let size = (pattern.scene.output.width_px, pattern.scene.output.height_px);
        let dir = std::env::temp_dir();
        let mut station = Station::new(&pattern.scene, KeyBindings::shipped(), size, dir.join("p.argile"));
        station.start_adjusting(AdjustTarget::new(dir.join("argile-never-written.toml"), shipped, &pattern));
        press(&mut station, KeyCode::KeyF);
        assert!(station.doc.playback.held_lattice().is_none(), "no lattice opens on the pattern");
        assert!(station.messages.last().unwrap().starts_with("calibrating: ArrowLeft/ArrowRight"));
        press(&mut station, KeyCode::KeyE);
        assert!(station.stereo.swap_eyes, "E swaps the eyes");
        assert!(station.hud_lines().iter().any(|l| l.contains("eyes swapped")));
    }
}
