//! `argile calibrate`: the frusta a screen calibration gives, and a test-pattern stereo pair
//! that shows whether it is right.
//!
//! The pattern is built in screen space (the world is the calibrated room, 1:1): a green grid
//! of thin bars lying on the screen plane, which must show zero parallax (the two images
//! agree on it) and whose lines are a stated number of millimetres apart (a ruler on the screen
//! checks its calibrated size, which zero parallax cannot show), a red ball 12 % of the viewing
//! distance in front of the screen (crossed disparity) and a blue ball 15 % of it behind the
//! screen (uncrossed), both wholly within the default 1° budget, each expected at
//! `IPD · (Z − D) / Z` on the screen. Seen on the calibrated display from the default eye, with
//! the right eye's image to the right eye, the grid sits on the glass and the balls float at
//! the printed distances. Over it, at zero parallax ([`eye_marks`]): a millimetre ruler along
//! the bottom edge, an L that only the left eye's picture holds and an R only the right's
//! (which eye sees which picture: swapped eyes, interlace parity, frame-sequential phase), and
//! a white square in each eye's picture alone with grey references beside it (crosstalk). The
//! pattern is also written as the display's own mode composes it, with its parity.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Result;

use super::capture::{render_scene, RenderOptions, WrittenCapture};
use crate::math::{Pose, Quat, Vec3};
use crate::render::{EyeMark, BOTH_VIEWS, LEFT_VIEW, RIGHT_VIEW};
use crate::scene::{ClayPrimitive, HeadPath, Scene, ScreenCalibration};
use crate::stereo::comfort::disparity_deg;
use crate::stereo::screen::Frustum;
use crate::stereo::screen_parallax_m;
use crate::tool::{CsgOp, PlacedSolid, Solid};

/// A marker of the test pattern and the disparity it must show.
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    /// "near" or "far".
    pub name: &'static str,
    /// Its colour (linear RGB), for finding it in the images.
    pub colour: Vec3,
    /// Its centre, screen space.
    pub position_m: Vec3,
    /// Distance in front of the screen plane (negative: behind).
    pub in_front_m: f32,
    /// Expected parallax on the screen (right-eye position minus left-eye), metres.
    pub parallax_m: f32,
    /// The same in pixels of the rendered images.
    pub parallax_px: f32,
    /// Its visual angle from the default eye, degrees.
    pub disparity_deg: f32,
}

/// The test pattern: a scene rendering it and what its markers must show.
#[derive(Clone, Debug)]
pub struct TestPattern {
    /// The scene (world = screen space, head at the default eye).
    pub scene: Scene,
    /// The near and far markers.
    pub markers: [Marker; 2],
    /// The grid's colour (linear RGB).
    pub grid_colour: Vec3,
    /// What each eye alone is shown, and the crosstalk references both are: see [`eye_marks`].
    pub eye_marks: Vec<EyeMark>,
}

/// The crosstalk references' levels: fractions of the squares' white, linear.
pub const CROSSTALK_LEVELS: [f32; 3] = [0.02, 0.05, 0.10];

/// Where the left eye's crosstalk square lies (device coordinates, y down): the bottom row of
/// the grid's cells, at the left; the right eye's mirrors it.
pub const CROSSTALK_SQUARE: ([f32; 2], [f32; 2]) = ([-0.95, 0.55], [-0.65, 0.95]);

/// Where the left eye's letter L starts (device coordinates, y down): the top left cell, below
/// the heads-up display's lines; the right eye's R ends as far from the right edge.
pub const LABEL_AT: [f32; 2] = [-0.93, -0.8];

/// Millimetres between the ruler's ticks; every fifth is longer, every tenth longer still.
pub const RULER_TICK_MM: f32 = 10.0;

/// The marks over the pattern, at zero parallax, for pictures `width_px` wide of a screen
/// `width_mm` wide and `aspect` (width over height):
///
/// - **A ruler** along the bottom edge, in both pictures: a tick every [`RULER_TICK_MM`] from
///   the left edge of the picture, longer each 50 mm and 100 mm. Shown full screen, a real
///   ruler held against the glass must match it; ticks closer or farther apart mean
///   `[screen] width_m` is wrong by that ratio.
/// - **L and R**: an L in the left eye's top left corner, an R in the right eye's top right.
///   Closing one eye shows which picture reaches the other: the right eye must see R only. An
///   L seen by the right eye means the eyes are swapped (`E`, `--swap-eyes`) or, on an
///   interlaced or frame-sequential display, the parity is (`P`, `[display] parity`).
/// - **Crosstalk**: a white square in the left eye's picture only, lower left, and one in the
///   right eye's only, lower right; beside each, grey patches at [`CROSSTALK_LEVELS`] of its
///   white, in both pictures. Seen with one eye, the other eye's square should be black: a
///   ghost of it as bright as a patch is that much crosstalk (the display leaks that fraction
///   of the other eye's picture).
pub fn eye_marks(aspect: f32, width_mm: f32, width_px: u32) -> Vec<EyeMark> {
    const WHITE: [f32; 3] = [1.0, 1.0, 1.0];
    let mut marks = Vec::new();
    // The ruler: ticks a pixel and a half wide, so that each shows at any position.
    let tick = 3.0 / width_px.max(1) as f32;
    let ticks = (width_mm / RULER_TICK_MM).floor() as u32;
    for k in 0..=ticks.min(2000) {
        let x = -1.0 + 2.0 * k as f32 * RULER_TICK_MM / width_mm;
        let length = match k {
            _ if k % 10 == 0 => 0.09,
            _ if k % 5 == 0 => 0.06,
            _ => 0.03,
        };
        let x0 = x.clamp(-1.0, 1.0 - tick);
        marks.push(EyeMark {
            views: BOTH_VIEWS,
            min: [x0, 1.0 - length],
            max: [x0 + tick, 1.0],
            colour: WHITE,
        });
    }
    // Font pixels a 57th of the height, square on the screen.
    let pixel = [0.035 / aspect.max(0.1), 0.035];
    marks.extend(EyeMark::text("L", LEFT_VIEW, LABEL_AT, pixel, WHITE));
    let r_at = [-LABEL_AT[0] - 8.0 * pixel[0], LABEL_AT[1]];
    marks.extend(EyeMark::text("R", RIGHT_VIEW, r_at, pixel, WHITE));
    let (min, max) = CROSSTALK_SQUARE;
    for (views, side) in [(LEFT_VIEW, 1.0f32), (RIGHT_VIEW, -1.0)] {
        let x = |v: f32| v * side;
        let (x0, x1) = (x(min[0]).min(x(max[0])), x(min[0]).max(x(max[0])));
        marks.push(EyeMark { views, min: [x0, min[1]], max: [x1, max[1]], colour: WHITE });
        // The references, inwards of the square, each a third of its height.
        for (i, level) in CROSSTALK_LEVELS.iter().enumerate() {
            let start = max[0] + 0.05 + i as f32 * 0.15;
            let (p0, p1) = (x(start).min(x(start + 0.1)), x(start).max(x(start + 0.1)));
            marks.push(EyeMark { views: BOTH_VIEWS, min: [p0, 0.68], max: [p1, 0.82], colour: [*level; 3] });
        }
    }
    marks
}

/// The grid's cells across the screen.
pub(crate) const GRID_COLUMNS: u32 = 8;
/// The grid's cells up the screen.
const GRID_ROWS: u32 = 4;

/// Grid colour: green, so that neither marker's colour is confused with it.
const GRID: Vec3 = Vec3::new(0.1, 0.9, 0.1);

/// The test pattern of `calibration` for images `width_px` wide (their height follows the
/// screen's aspect ratio).
pub fn test_pattern(calibration: &ScreenCalibration, width_px: u32) -> TestPattern {
    let c = calibration;
    let (vr, vu, vn) = c.screen.basis();
    let (w, h) = (c.screen.width_m(), c.screen.height_m());
    let d = c.viewing_distance_m();
    let height_px = ((width_px as f32 / c.screen.aspect()).round() as u32).max(16);
    let facing = c.default_head().rotation;
    let at = |x: f32, y: f32, z: f32| c.screen.centre_m() + vr * x + vu * y + vn * z;

    // Bars of about 2 pixels across; the field's voxels a third of that.
    let radius_m = w / width_px as f32;
    let voxel_m = (radius_m / 1.5).clamp(1e-4, 0.05);
    let mut scene = Scene::parse(
        &format!(
            "[field]\nvoxel_size_m = {voxel_m}\n[output]\nwidth_px = {width_px}\nheight_px = {height_px}\nsamples = 4\n\
             [environment]\nshow = false\nbackground = [0.0, 0.0, 0.0]\n[stage]\nshow = false\n\
             [[light]]\nkind = \"directional\"\ndirection = [0.3, -0.4, -1.0]\nattached_to = \"viewer\"\n\
             [[capture]]\nname = \"calibration\"\ntime_s = 0.0\nshow_tools = false\n"
        ),
        "<calibration test pattern>",
        None,
    )
    .expect("the generated test pattern scene is valid (tested)");
    // The camera at the default eye looking along the screen's normal, its convergence plane on
    // the screen: the world is screen space, 1:1.
    scene.rig.eye_m = c.default_eye_m;
    scene.rig.target_m = c.default_eye_m - vn * d;
    scene.rig.up = vu;
    scene.rig.convergence_m = d;
    scene.rig.interaxial_m = c.ipd_m;
    // The screen's own field of view from the default eye: the rig's views are the tracked ones.
    scene.rig.fov_y_deg = 2.0 * (0.5 * h / d).atan().to_degrees();
    scene.rig.near_m = c.near_m;
    scene.rig.far_m = c.far_m;
    scene.head = Some(HeadPath { calibration: *c, keys: Vec::new() });

    let bar = |centre: Vec3, half_length_m: f32, turn: Quat, colour: Vec3| ClayPrimitive {
        solid: PlacedSolid {
            solid: Solid::Bar { half_length_m, radius_m },
            pose: Pose { position_m: centre, rotation: facing * turn },
            scale: 1.0,
        },
        op: CsgOp::Union,
        part: 0,
        colour: colour.extend(1.0).to_array(),
    };
    for i in 1..GRID_COLUMNS {
        let x = (i as f32 / GRID_COLUMNS as f32 - 0.5) * w;
        scene.clay.push(bar(
            at(x, 0.0, 0.0),
            0.5 * h,
            Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
            GRID,
        ));
    }
    for j in 1..GRID_ROWS {
        let y = (j as f32 / GRID_ROWS as f32 - 0.5) * h;
        scene.clay.push(bar(at(0.0, y, 0.0), 0.5 * w, Quat::IDENTITY, GRID));
    }

    let mut marker = |name, colour: Vec3, (x, y): (f32, f32), in_front_m: f32, radius_m: f32| {
        let parallax_m = screen_parallax_m(c.ipd_m, d, d - in_front_m);
        Marker {
            name,
            colour,
            position_m: at(x, y, in_front_m),
            in_front_m,
            parallax_m,
            parallax_px: parallax_m / w * width_px as f32,
            disparity_deg: disparity_deg(parallax_m, d),
        }
        .with_ball(&mut scene.clay, radius_m)
    };
    let markers = [
        // Each ball in a cell of the grid, clear of its bars, so neither eye sees a bar cut it.
        marker("near", Vec3::new(1.0, 0.12, 0.08), (-0.3125 * w, -0.125 * h), 0.12 * d, 0.035 * h),
        marker("far", Vec3::new(0.08, 0.25, 1.0), (0.3125 * w, 0.125 * h), -0.15 * d, 0.07 * h),
    ];
    scene.display.parity = c.display.parity;
    TestPattern {
        scene,
        markers,
        grid_colour: GRID,
        eye_marks: eye_marks(c.screen.aspect(), w * 1000.0, width_px),
    }
}

impl Marker {
    fn with_ball(self, clay: &mut Vec<ClayPrimitive>, radius_m: f32) -> Self {
        clay.push(ClayPrimitive {
            solid: PlacedSolid {
                solid: Solid::Sphere { radius_m },
                pose: Pose { position_m: self.position_m, rotation: Quat::IDENTITY },
                scale: 1.0,
            },
            op: CsgOp::Union,
            part: 0,
            colour: self.colour.extend(1.0).to_array(),
        });
        self
    }
}

/// The calibration and its frusta in words and millimetres, for the terminal.
pub fn describe(calibration: &ScreenCalibration, source: &str, pattern: &TestPattern) -> String {
    let c = calibration;
    let d = c.viewing_distance_m();
    let mm = |v: Vec3| format!("({:.1}, {:.1}, {:.1}) mm", v.x * 1000.0, v.y * 1000.0, v.z * 1000.0);
    let mut s = String::new();
    let diagonal_in = c.screen.width_m().hypot(c.screen.height_m()) / 0.0254;
    let _ = writeln!(s, "Screen calibration: {source}");
    let _ = writeln!(
        s,
        "  screen: {:.1} × {:.1} mm ({diagonal_in:.1}\", aspect {:.3}), centre {}",
        c.screen.width_m() * 1000.0,
        c.screen.height_m() * 1000.0,
        c.screen.aspect(),
        mm(c.screen.centre_m())
    );
    let _ = writeln!(
        s,
        "  corners: lower left {}, lower right {}, upper left {}",
        mm(c.screen.lower_left_m),
        mm(c.screen.lower_right_m),
        mm(c.screen.upper_left_m)
    );
    let _ = writeln!(
        s,
        "  default eye {} ({:.1} mm from the screen), IPD {:.1} mm, clipping {:.0} mm to {:.1} m",
        mm(c.default_eye_m),
        d * 1000.0,
        c.ipd_m * 1000.0,
        c.near_m * 1000.0,
        c.far_m
    );
    let _ = writeln!(
        s,
        "  tracker at {}, opentrack UDP port {}",
        mm(c.tracker.to_screen.position_m),
        c.tracker.port
    );
    let head = c.default_head();
    let half = head.rotation * Vec3::X * (0.5 * c.ipd_m);
    for (name, eye) in [("left", head.position_m - half), ("right", head.position_m + half)] {
        // On the screen plane (near = distance to the screen), the edges are physical offsets.
        let f = Frustum::new(&c.screen, eye, d, c.far_m);
        let [l, r, b, t] = f.lrbt;
        let [al, ar, ab, at] = f.angles_deg();
        let _ = writeln!(
            s,
            "  {name} eye at {}: screen edges from the eye's foot left {:.1}, right {:.1}, bottom {:.1}, top {:.1} mm; \
             frustum angles left {al:.2}°, right {ar:.2}°, bottom {ab:.2}°, top {at:.2}° (field of view {:.2}° × {:.2}°)",
            mm(f.eye_m),
            l * 1000.0,
            r * 1000.0,
            b * 1000.0,
            t * 1000.0,
            ar - al,
            at - ab
        );
    }
    // The depth range within the budget, from p = IPD · (Z − D) / Z at p = ±the budget's parallax.
    let p = 2.0 * d * (0.5 * c.budget.max_disparity_deg.to_radians()).tan();
    let front = d - d * c.ipd_m / (c.ipd_m + p);
    let behind = if p >= c.ipd_m { None } else { Some(d * c.ipd_m / (c.ipd_m - p) - d) };
    let _ = writeln!(
        s,
        "  parallax budget ±{:.2}° ({:.1} mm on the screen): comfortable from {:.0} mm in front of the screen to {}",
        c.budget.max_disparity_deg,
        p * 1000.0,
        front * 1000.0,
        behind.map_or("infinity".to_owned(), |b| format!("{:.0} mm behind it", b * 1000.0))
    );
    let (w, h) = (pattern.scene.output.width_px, pattern.scene.output.height_px);
    let _ =
        writeln!(s, "Test pattern ({w} × {h} per eye): the green grid lies on the screen (zero parallax)");
    let _ = writeln!(
        s,
        "  its lines are {:.1} mm apart across and {:.1} mm apart up the screen, shown full screen: \
         measure them with a ruler; other spacings mean [screen] width_m and height_m are wrong",
        c.screen.width_m() / GRID_COLUMNS as f32 * 1000.0,
        c.screen.height_m() / GRID_ROWS as f32 * 1000.0
    );
    let _ = writeln!(
        s,
        "  the ruler along the bottom edge ticks every {RULER_TICK_MM:.0} mm (longer each 50 and 100 mm) from the \
         picture's left edge: a ruler held against the glass must match it"
    );
    let _ = writeln!(
        s,
        "  close your right eye: the left eye must see the L (top left) and not the R; close your left eye: \
         the right eye sees the R only. Seen the other way round, swap the eyes (E, --swap-eyes) or flip the \
         parity (P, [display] parity)"
    );
    let _ = writeln!(
        s,
        "  crosstalk: with one eye, the other eye's white square (lower left for the left eye, lower right for \
         the right) must look black; a ghost as bright as one of the grey patches beside it ({}) is that much \
         of the other eye's picture leaking through",
        CROSSTALK_LEVELS.map(|l| format!("{:.0} %", l * 100.0)).join(", ")
    );
    for m in &pattern.markers {
        let _ = writeln!(
            s,
            "  {} ball {:.0} mm {} the screen: parallax {:+.1} mm = {:+.2} px, {:+.2}° ({})",
            m.name,
            m.in_front_m.abs() * 1000.0,
            if m.in_front_m > 0.0 { "in front of" } else { "behind" },
            m.parallax_m * 1000.0,
            m.parallax_px,
            m.disparity_deg,
            if m.parallax_m < 0.0 { "crossed" } else { "uncrossed" }
        );
    }
    s
}

/// Options of `argile calibrate`.
#[derive(Clone, Debug)]
pub struct CalibrateOptions {
    /// The calibration file (the shipped one when `None`).
    pub calibration: Option<PathBuf>,
    /// Folder for the test pattern pair.
    pub out_dir: PathBuf,
    /// Width of each eye's image.
    pub width_px: u32,
    /// Turn the Vulkan validation layer on.
    pub validation: bool,
    /// Also write the pattern as these display modes compose it (the display's own mode).
    pub display_modes: Vec<crate::stereo::display::DisplayMode>,
}

/// What `argile calibrate` did.
#[derive(Clone, Debug)]
pub struct Calibrated {
    /// The description printed to the user.
    pub report: String,
    /// The test pattern.
    pub pattern: TestPattern,
    /// The rendered pair.
    pub written: WrittenCapture,
}

/// Loads the calibration, describes its frusta and renders the test pattern pair.
pub fn calibrate(options: &CalibrateOptions) -> Result<Calibrated> {
    let (calibration, source) = match &options.calibration {
        Some(path) => (ScreenCalibration::load(path)?, path.display().to_string()),
        None => (ScreenCalibration::shipped(), "calibration/screen.toml (built in)".to_owned()),
    };
    let pattern = test_pattern(&calibration, options.width_px);
    // The display's own mode, from its calibration, unless the command line names others.
    let display_modes = match options.display_modes.is_empty() {
        true => calibration.display.mode.into_iter().collect(),
        false => options.display_modes.clone(),
    };
    let report = describe(&calibration, &source, &pattern);
    let render = RenderOptions {
        out_dir: options.out_dir.clone(),
        display_modes,
        progress: false,
        validation: options.validation,
        size_px: None,
        calibration: Some(calibration),
        eye_marks: pattern.eye_marks.clone(),
    };
    let mut written = render_scene(&pattern.scene, &render)?;
    let written = written.pop().expect("the test pattern has one capture");
    Ok(Calibrated { report, pattern, written })
}

/// Options of `argile calibrate --adjust`.
#[derive(Clone, Debug, Default)]
pub struct AdjustOptions {
    /// The calibration file to adjust (created when missing, from the shipped calibration).
    pub calibration: PathBuf,
    /// Width of the pattern's eye images it is built for (its bars are about 2 pixels wide).
    pub width_px: u32,
    /// The station's window: the display, the monitor, key bindings, scripted frames. Its
    /// window fills the monitor unless it names a size.
    pub station: super::StationOptions,
}

/// Shows the test pattern of the calibration file in the station's window, where keys change
/// the screen's size, the viewing distance and the IPD, and write them back to the file.
pub fn adjust_calibration(options: &AdjustOptions) -> Result<super::StationReport> {
    if let Some(reason) = super::no_display_reason() {
        anyhow::bail!("cannot show the calibration's test pattern to adjust it: {reason}");
    }
    let path = &options.calibration;
    let calibration = match path.exists() {
        true => ScreenCalibration::load(path)?,
        false => ScreenCalibration::shipped(),
    };
    let pattern = test_pattern(&calibration, options.width_px);
    let mut station = options.station.clone();
    station.fullscreen |= station.window_px.is_none();
    station.adjust = Some(super::AdjustTarget::new(path.clone(), calibration, &pattern));
    let source = match path.exists() {
        true => path.display().to_string(),
        false => format!("{} (not there yet: the shipped calibration until written)", path.display()),
    };
    print!("{}", describe(&calibration, &source, &pattern));
    super::run_station(&pattern.scene, "calibration", &station)
}

/// A change `argile calibrate --adjust` makes to a calibration while its pattern shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Adjustment {
    /// The screen grows this much wider (metres), about its centre; its height follows, its
    /// aspect ratio (the pixels') kept.
    Width(f32),
    /// The default eye moves this much farther from the screen, along its normal (metres).
    Distance(f32),
    /// The interpupillary distance grows by this (metres).
    Ipd(f32),
}

/// The widths `--adjust` keeps a screen within, metres.
pub const ADJUST_WIDTH_M: std::ops::RangeInclusive<f32> = 0.05..=20.0;
/// The viewing distances it keeps the default eye within, metres.
pub const ADJUST_DISTANCE_M: std::ops::RangeInclusive<f32> = 0.1..=10.0;
/// The interpupillary distances it keeps within, metres (adults: 50 to 75 mm).
pub const ADJUST_IPD_M: std::ops::RangeInclusive<f32> = 0.045..=0.08;

/// `calibration` changed by `adjustment`, kept within the ranges above.
pub fn adjusted(calibration: &ScreenCalibration, adjustment: Adjustment) -> ScreenCalibration {
    let clamp = |v: f32, r: &std::ops::RangeInclusive<f32>| v.clamp(*r.start(), *r.end());
    let mut c = *calibration;
    match adjustment {
        Adjustment::Width(delta) => {
            let w = c.screen.width_m();
            let s = clamp(w + delta, &ADJUST_WIDTH_M) / w;
            let centre = c.screen.centre_m();
            let about = |p: Vec3| centre + (p - centre) * s;
            c.screen.lower_left_m = about(c.screen.lower_left_m);
            c.screen.lower_right_m = about(c.screen.lower_right_m);
            c.screen.upper_left_m = about(c.screen.upper_left_m);
        }
        Adjustment::Distance(delta) => {
            let d = c.viewing_distance_m();
            let to = clamp(d + delta, &ADJUST_DISTANCE_M).max(c.near_m + 0.01);
            c.default_eye_m += c.screen.basis().2 * (to - d);
        }
        Adjustment::Ipd(delta) => c.ipd_m = clamp(c.ipd_m + delta, &ADJUST_IPD_M),
    }
    c
}

/// Micrometres: what a written calibration rounds its lengths to.
fn rounded(v: f32) -> f64 {
    (f64::from(v) * 1e7).round() / 1e7
}

/// Writes the screen size, the default eye and the IPD of `calibration` that differ from
/// `before` into the calibration file `path` (created when missing), keeping its other keys,
/// comments and layout. A screen given by its corners there keeps its corners, else it is
/// given by `width_m` and `height_m` (the adjustment keeps its centre and turn). The file is
/// written atomically and read back: what it then says is returned, and must be `calibration`
/// within a micrometre, or nothing is left changed.
pub fn write_calibration(
    path: &std::path::Path,
    before: &ScreenCalibration,
    calibration: &ScreenCalibration,
) -> Result<ScreenCalibration> {
    use anyhow::Context as _;
    use toml_edit::{DocumentMut, Item, Table, Value};
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(e).with_context(|| format!("cannot read {}", path.display())),
    };
    let mut doc: DocumentMut =
        text.parse().with_context(|| format!("{} is not TOML: it is left as it was", path.display()))?;
    // A value replaced keeps the comment after it.
    let set = |table: &mut Table, key: &str, mut value: Value| {
        if let Some(old) = table.get(key).and_then(Item::as_value) {
            *value.decor_mut() = old.decor().clone();
        }
        table.insert(key, Item::Value(value));
    };
    let vector = |v: Vec3| Value::from_iter([rounded(v.x), rounded(v.y), rounded(v.z)]);
    fn table<'d>(doc: &'d mut DocumentMut, name: &str, path: &std::path::Path) -> Result<&'d mut Table> {
        let item = doc.entry(name).or_insert_with(toml_edit::table);
        item.as_table_mut().with_context(|| {
            format!("{}: `{name}` is not a table, so the adjustment cannot be written there", path.display())
        })
    }
    let (s0, s1) = (&before.screen, &calibration.screen);
    if s0 != s1 {
        let screen = table(&mut doc, "screen", path)?;
        let corners = ["lower_left_m", "lower_right_m", "upper_left_m"];
        if corners.iter().any(|k| screen.contains_key(k)) {
            for (key, p) in corners.into_iter().zip([s1.lower_left_m, s1.lower_right_m, s1.upper_left_m]) {
                set(screen, key, vector(p));
            }
        } else {
            set(screen, "width_m", Value::from(rounded(s1.width_m())));
            set(screen, "height_m", Value::from(rounded(s1.height_m())));
        }
    }
    if before.default_eye_m != calibration.default_eye_m {
        set(table(&mut doc, "viewer", path)?, "default_eye_m", vector(calibration.default_eye_m));
    }
    if before.ipd_m != calibration.ipd_m {
        set(table(&mut doc, "viewer", path)?, "ipd_m", Value::from(rounded(calibration.ipd_m)));
    }
    let written = doc.to_string();
    let name = path.display().to_string();
    let back = ScreenCalibration::parse(&written, &name).with_context(|| {
        format!("the adjusted calibration would not read back, so {name} is left as it was")
    })?;
    let off = [
        (back.screen.lower_left_m - s1.lower_left_m).abs().max_element(),
        (back.screen.lower_right_m - s1.lower_right_m).abs().max_element(),
        (back.screen.upper_left_m - s1.upper_left_m).abs().max_element(),
        (back.default_eye_m - calibration.default_eye_m).abs().max_element(),
        (back.ipd_m - calibration.ipd_m).abs(),
    ];
    let worst = off.into_iter().fold(0.0f32, f32::max);
    if worst > 1e-6 {
        anyhow::bail!(
            "the adjusted calibration would read back {:.1} µm off what is shown (is the screen in {name} \
             turned by corners that are not square?), so {name} is left as it was",
            worst * 1e6
        );
    }
    crate::io::write_atomically(path, true, |w| {
        use std::io::Write as _;
        w.write_all(written.as_bytes()).with_context(|| format!("cannot write {name}"))
    })?;
    Ok(back)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_marks_are_a_millimetre_ruler_an_l_and_an_r_for_one_eye_each_and_crosstalk_squares() {
        let c = ScreenCalibration::shipped();
        let p = test_pattern(&c, 1000);
        let width_mm = c.screen.width_m() * 1000.0;
        let both: Vec<&EyeMark> = p.eye_marks.iter().filter(|m| m.views == BOTH_VIEWS).collect();
        // 531.3 mm: ticks at 0, 10, …, 530 mm, each where its millimetres put it on the screen.
        let ticks: Vec<&&EyeMark> = both.iter().filter(|m| m.max[1] == 1.0).collect();
        assert_eq!(ticks.len(), 54);
        for (k, t) in ticks.iter().enumerate() {
            let mm = (t.min[0] + 1.0) / 2.0 * width_mm;
            assert!((mm - 10.0 * k as f32).abs() < 0.01, "tick {k} at {mm} mm");
            let long = 1.0 - t.min[1];
            let expected = [0.09, 0.03, 0.03, 0.03, 0.03, 0.06, 0.03, 0.03, 0.03, 0.03][k % 10];
            assert!((long - expected).abs() < 1e-5, "tick {k}: {long}");
        }
        // Three references for each eye's square, at the stated levels.
        let references: Vec<f32> = both.iter().filter(|m| m.max[1] < 1.0).map(|m| m.colour[0]).collect();
        assert_eq!(references, [CROSSTALK_LEVELS, CROSSTALK_LEVELS].concat());
        let only = |views| p.eye_marks.iter().filter(move |m: &&EyeMark| m.views == views);
        // The L lies in the left half, the R in the right; each eye's square on its side.
        assert!(only(LEFT_VIEW).all(|m| m.max[0] < 0.0) && only(LEFT_VIEW).count() > 4);
        assert!(only(RIGHT_VIEW).all(|m| m.min[0] > 0.0) && only(RIGHT_VIEW).count() > 4);
        let squares = |views| only(views).filter(|m| m.max[1] - m.min[1] > 0.3).count();
        assert_eq!((squares(LEFT_VIEW), squares(RIGHT_VIEW)), (1, 1));
        let text = describe(&c, "shipped", &p);
        assert!(text.contains("every 10 mm") && text.contains("2 %, 5 %, 10 %"), "{text}");
    }

    #[test]
    fn the_shipped_pattern_expects_opposite_disparities_within_the_budget() {
        let c = ScreenCalibration::shipped();
        let p = test_pattern(&c, 512);
        assert_eq!((p.scene.output.width_px, p.scene.output.height_px), (512, 288));
        let [near, far] = &p.markers;
        assert!(near.parallax_m < 0.0 && far.parallax_m > 0.0);
        // 72 mm in front of a screen 600 mm away: 63 mm · (528 − 600) / 528 = −8.59 mm; 90 mm
        // behind: 63 mm · 90 / 690 = 8.22 mm.
        assert!((near.parallax_m + 0.008_591).abs() < 1e-5, "{}", near.parallax_m);
        assert!((far.parallax_m - 0.008_217).abs() < 1e-5, "{}", far.parallax_m);
        assert!(near.disparity_deg.abs() < 1.0 && far.disparity_deg < 1.0, "within the shipped budget");
        let rig = p.scene.head_tracked_rig().unwrap();
        assert!((rig.placement.scale - 1.0).abs() < 1e-5, "the world is screen space, 1:1");
        assert!(rig.placement.translation_m.length() < 1e-5);
        let text = describe(&c, "shipped", &p);
        assert!(
            text.contains("left eye") && text.contains("crossed") && text.contains("uncrossed"),
            "{text}"
        );
        // The grid's spacing, for a ruler: a 531.3 mm screen in 8 columns.
        assert!(text.contains("66.4 mm apart across and 74.7 mm apart up"), "{text}");
        // The pattern's own balls, whole, are within the budget it is judged on: calibrate
        // warns of nothing.
        let clay = crate::mesh::mesh_all(super::super::Playback::new(&p.scene).field()).upserted_bounds();
        let mut scene = p.scene.clone();
        let verdict = super::super::comfort::apply_parallax_budget(&mut scene, c, clay);
        assert!(verdict.is_none(), "{:?}", verdict.map(|v| v.1));
    }

    #[test]
    fn adjustments_keep_the_screen_centred_and_square_and_stay_within_their_ranges() {
        let c = ScreenCalibration::shipped();
        let wider = adjusted(&c, Adjustment::Width(0.05));
        assert!((wider.screen.width_m() - c.screen.width_m() - 0.05).abs() < 1e-6);
        assert!((wider.screen.aspect() - c.screen.aspect()).abs() < 1e-5);
        assert!((wider.screen.centre_m() - c.screen.centre_m()).length() < 1e-6);
        assert!((wider.viewing_distance_m() - c.viewing_distance_m()).abs() < 1e-6, "the eye stays");
        assert_eq!(adjusted(&c, Adjustment::Width(-10.0)).screen.width_m(), *ADJUST_WIDTH_M.start());
        let far = adjusted(&c, Adjustment::Distance(100.0));
        assert!((far.viewing_distance_m() - ADJUST_DISTANCE_M.end()).abs() < 1e-4);
        assert!(
            (far.default_eye_m.truncate() - c.default_eye_m.truncate()).length() < 1e-6,
            "along the normal"
        );
        assert_eq!(adjusted(&c, Adjustment::Ipd(-1.0)).ipd_m, *ADJUST_IPD_M.start());
        assert_eq!(adjusted(&c, Adjustment::Ipd(1.0)).ipd_m, *ADJUST_IPD_M.end());
    }

    #[test]
    fn written_adjustments_keep_the_file_s_comments_and_corners_and_read_back_as_shown() {
        let dir = std::env::temp_dir().join(format!("argile-write-calibration-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // A screen by its size, with comments and a key the adjustment does not touch.
        let sized = dir.join("sized.toml");
        let text = "# my monitor\n[screen]\nwidth_m = 0.6   # measured\nheight_m = 0.3375\n\n[tracker]\nport = 5000\n";
        std::fs::write(&sized, text).unwrap();
        let before = ScreenCalibration::load(&sized).unwrap();
        let after = adjusted(&adjusted(&before, Adjustment::Width(0.004)), Adjustment::Ipd(0.002));
        let back = write_calibration(&sized, &before, &after).unwrap();
        let written = std::fs::read_to_string(&sized).unwrap();
        assert!(written.starts_with("# my monitor\n[screen]\nwidth_m = 0.604   # measured\n"), "{written}");
        assert!(written.contains("port = 5000") && written.contains("ipd_m = 0.065"), "{written}");
        assert!(!written.contains("default_eye_m"), "the eye did not move: {written}");
        assert_eq!(back, ScreenCalibration::load(&sized).unwrap());
        assert!((back.screen.width_m() - 0.604).abs() < 1e-6 && (back.ipd_m - 0.065).abs() < 1e-6);

        // A screen by its corners keeps its corners.
        let cornered = dir.join("corners.toml");
        std::fs::write(
            &cornered,
            "[screen]\nlower_left_m = [-0.3, -0.2, 0.0]\nlower_right_m = [0.3, -0.2, 0.0]\nupper_left_m = [-0.3, 0.2, 0.0]\n",
        )
        .unwrap();
        let before = ScreenCalibration::load(&cornered).unwrap();
        let after = adjusted(&adjusted(&before, Adjustment::Width(-0.06)), Adjustment::Distance(0.1));
        write_calibration(&cornered, &before, &after).unwrap();
        let written = std::fs::read_to_string(&cornered).unwrap();
        assert!(
            written.contains("lower_right_m = [0.27, -0.18, 0.0]") && !written.contains("width_m"),
            "{written}"
        );
        assert!(written.contains("default_eye_m = [0.0, 0.0, 0.7]"), "{written}");

        // A file that is not TOML is named and left as it was.
        let broken = dir.join("broken.toml");
        std::fs::write(&broken, "[screen\nwidth_m = ").unwrap();
        let e = write_calibration(&broken, &before, &after).unwrap_err();
        assert!(format!("{e:#}").contains("broken.toml is not TOML"), "{e:#}");
        assert_eq!(std::fs::read_to_string(&broken).unwrap(), "[screen\nwidth_m = ");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
