//! Stereo image regression tests: scenes rendered offscreen (multiview, 4x MSAA) on the pinned
//! Vulkan device with the validation layer on, each eye compared with `tests/golden/`; and one
//! stereo pair composed in every display mode by the composition pass (`display-MODE.png`).
//!
//! Regenerate the goldens after a deliberate change: `BLESS=1 scripts/test` (or
//! `BLESS=1 cargo test --test golden_stereo`). Actual and diff images of every run are written
//! under `target/stereo-tests/`.
//!
//! These tests need a Vulkan device and fail (never skip) without one.

use std::path::Path;

use argile::app::{render_scene, RenderOptions};
use argile::scene::Scene;
use argile::stereo::display::DisplayMode;

mod common;
use common::{check_against_golden, out_dir, root};

fn render(
    case: &str,
    scene_path: &str,
    size: Option<(u32, u32)>,
) -> (image::RgbaImage, image::RgbaImage, Scene) {
    let (left, right, scene, _) = render_composed(case, scene_path, size, &[]);
    (left, right, scene)
}

/// Renders like [`render`] and also composes the capture in each of `modes` (through the
/// composition pass); returns the composed images too, in order (two for quad-buffer).
fn render_composed(
    case: &str,
    scene_path: &str,
    size: Option<(u32, u32)>,
    modes: &[DisplayMode],
) -> (image::RgbaImage, image::RgbaImage, Scene, Vec<image::RgbaImage>) {
    let scene = if scene_path == "default" {
        Scene::default_scene()
    } else {
        Scene::load(&root().join(scene_path)).expect("test scene loads")
    };
    let options = RenderOptions {
        out_dir: out_dir(case),
        display_modes: modes.to_vec(),
        progress: false,
        validation: true,
        size_px: size,
        calibration: None,
        eye_marks: Vec::new(),
    };
    // A missing Vulkan device or any validation message fails here, loudly.
    let written = render_scene(&scene, &options).unwrap_or_else(|e| panic!("rendering {case} failed: {e:#}"));
    assert_eq!(written.len(), 1, "{case} has one capture");
    let load = |p: &Path| image::open(p).expect("rendered image reads back").to_rgba8();
    let composed = written[0].composed.iter().map(|p| load(p)).collect();
    (load(&written[0].left), load(&written[0].right), scene, composed)
}

fn golden_case(case: &str, scene: &str, size: Option<(u32, u32)>) {
    let (left, right, _) = render(case, scene, size);
    assert_ne!(left, right, "{case}: the two eyes must differ");
    check_against_golden(case, "left", &left);
    check_against_golden(case, "right", &right);
}

#[test]
fn default_scene_matches_golden() {
    golden_case("default", "default", Some((256, 256)));
}

#[test]
fn carved_sphere_matches_golden() {
    golden_case("carved-sphere", "scenes/tests/carved-sphere.toml", None);
}

#[test]
fn toothpaste_stroke_matches_golden() {
    golden_case("toothpaste", "scenes/tests/toothpaste.toml", None);
}

/// A stroke mirrored across x = 0, with the mirror plane drawn faintly through the clay.
#[test]
fn mirror_stroke_matches_golden() {
    golden_case("mirror-stroke", "scenes/tests/mirror-stroke.toml", None);
}

/// A groove carved five times about the vertical axis, which is drawn as a line.
#[test]
fn radial_stroke_matches_golden() {
    golden_case("radial-stroke", "scenes/tests/radial-stroke.toml", None);
}

/// The same stroke with a tool editing the level its size chooses, on a lattice fine enough
/// that it edits level 2: coarse clay meshed on the finest lattice, closed and in the same
/// place as the fine stroke. Its highlights show the level's 2 mm cells as a faint grid: the
/// finest lattice interpolates the coarse one trilinearly, so the normal turns at each coarse
/// cell's faces (a smoother interpolation between levels would take that away).
#[test]
fn a_tool_editing_by_its_size_matches_golden() {
    golden_case("tool-by-size", "scenes/tests/tool-by-size.toml", None);
}

#[test]
fn levels_meeting_match_golden() {
    golden_case("levels-meet", "scenes/tests/levels-meet.toml", None);
}

#[test]
fn tool_eraser_matches_golden() {
    golden_tool_case("tool-eraser");
}

#[test]
fn tool_heat_gun_matches_golden() {
    golden_rate_tool_case("tool-heat-gun");
}

#[test]
fn tool_build_matches_golden() {
    golden_rate_tool_case("tool-build");
}

#[test]
fn tool_paint_matches_golden() {
    golden_tool_case("tool-paint");
}

#[test]
fn tool_soft_paint_matches_golden() {
    golden_tool_case("tool-soft-paint");
}

#[test]
fn tool_smooth_matches_golden() {
    golden_tool_case("tool-smooth");
}

#[test]
fn tool_stamp_matches_golden() {
    golden_tool_case("tool-stamp");
}

#[test]
fn tool_inflate_matches_golden() {
    golden_tool_case("tool-inflate");
}

#[test]
fn tool_deflate_matches_golden() {
    golden_tool_case("tool-deflate");
}

#[test]
fn tool_freeform_matches_golden() {
    golden_tool_case("tool-freeform");
}

/// A tool scene of `scenes/tests/` (one per action, shapes varied among them), rendered small
/// (160×120 per eye).
fn golden_tool_case(case: &str) {
    golden_case(case, &format!("scenes/tests/{case}.toml"), None);
}

/// The largest mean error of the held (rate) tools' pictures, levels: rendered on an Intel
/// Xeon host, the pictures blessed on an AMD EPYC one differ by one level over about half their
/// pixels (mean 0.46, 99th percentile 1), the same before and after the lattice work; every
/// other golden matches both hosts within the common bound. The 99th percentile's bound of 4
/// levels still catches any change of shape.
const RATE_TOOL_MAX_MEAN_ERROR: f64 = 0.6;

fn golden_rate_tool_case(case: &str) {
    let (left, right, _) = render(case, &format!("scenes/tests/{case}.toml"), None);
    assert_ne!(left, right, "{case}: the two eyes must differ");
    common::check_against_golden_within(case, "left", &left, RATE_TOOL_MAX_MEAN_ERROR);
    common::check_against_golden_within(case, "right", &right, RATE_TOOL_MAX_MEAN_ERROR);
}

/// The stage seen from inside fills both eyes: no pixel of the magenta background may show
/// (a driver that loses clipped triangles in one view leaves holes there).
#[test]
fn the_stage_seen_from_inside_has_no_holes_in_either_eye() {
    let (left, right, _) = render("inside-stage", "scenes/tests/inside-stage.toml", None);
    for (eye, image) in [("left", &left), ("right", &right)] {
        let holes = image.pixels().filter(|p| p[0] > 200 && p[1] < 60 && p[2] > 200).count();
        assert_eq!(holes, 0, "{eye} eye: {holes} background pixels show through the stage");
    }
    check_against_golden("inside-stage", "left", &left);
    check_against_golden("inside-stage", "right", &right);
}

/// Centroid (column, row) of the pixels `select` picks, and their count.
fn centroid(img: &image::RgbaImage, select: impl Fn(&image::Rgba<u8>) -> bool) -> (f32, f32, usize) {
    let (mut sx, mut sy, mut n) = (0.0f64, 0.0f64, 0usize);
    for (x, y, p) in img.enumerate_pixels() {
        if select(p) {
            sx += f64::from(x) + 0.5;
            sy += f64::from(y) + 0.5;
            n += 1;
        }
    }
    assert!(n > 0, "nothing selected");
    ((sx / n as f64) as f32, (sy / n as f64) as f32, n)
}

#[test]
fn near_objects_have_crossed_and_far_objects_uncrossed_parallax() {
    let (left, right, scene) = render("parallax", "scenes/tests/parallax.toml", None);
    check_against_golden("parallax", "left", &left);
    check_against_golden("parallax", "right", &right);
    let red = |p: &image::Rgba<u8>| {
        p[0] > 40 && u16::from(p[0]) > 2 * u16::from(p[2]) && u16::from(p[0]) > 2 * u16::from(p[1])
    };
    let blue = |p: &image::Rgba<u8>| p[2] > 40 && u16::from(p[2]) > 2 * u16::from(p[0]);
    let (w, h) = (scene.output.width_px, scene.output.height_px);
    let aspect = w as f32 / h as f32;
    for (name, select, distance_m) in
        [("near", &red as &dyn Fn(&image::Rgba<u8>) -> bool, 0.3f32), ("far", &blue, 1.0)]
    {
        let (xl, yl, nl) = centroid(&left, select);
        let (xr, yr, nr) = centroid(&right, select);
        assert!(nl > 20 && nr > 20, "{name} ball visible in both eyes ({nl}, {nr} pixels)");
        let expected = scene.rig.parallax_px(distance_m, w, aspect);
        let measured = xr - xl;
        assert!(
            (measured - expected).abs() <= 1.0,
            "{name} ball: parallax {measured:.2} px, expected {expected:.2} px"
        );
        assert!((yl - yr).abs() <= 0.5, "{name} ball: vertical parallax {:.2} px", yl - yr);
        if distance_m < scene.rig.convergence_m {
            assert!(
                measured < -1.0,
                "in front of the convergence plane: crossed (left eye sees it further right)"
            );
        } else {
            assert!(measured > 1.0, "behind the convergence plane: uncrossed");
        }
    }
}

#[test]
fn the_heads_up_display_has_zero_parallax() {
    let mut scene = Scene::load(&root().join("scenes/tests/carved-sphere.toml")).expect("test scene loads");
    scene.output.width_px = 256;
    scene.output.height_px = 128;
    let mut renderer =
        argile::app::renderer_for(&scene, None, true, None).unwrap_or_else(|e| panic!("no renderer: {e:#}"));
    let mut frame = argile::app::build_frame(&scene, &[], false);
    frame.hud = vec!["tool 1: 44 mm, remove".into(), "convergence 0.47 m".into()];
    renderer.draw(&frame).expect("drawn");
    let pair = renderer.read_back().expect("read back");
    let log = renderer.validation_log();
    drop(renderer);
    assert!(log.take().is_empty(), "the validation layer is silent");
    // The text is opaque: its pixels are the same in both eyes, at the same places.
    let text = |img: &image::RgbaImage| -> Vec<(u32, u32)> {
        img.enumerate_pixels()
            .filter(|(_, _, p)| p[0] > 240 && p[1] > 240 && p[2] > 225)
            .map(|(x, y, _)| (x, y))
            .collect()
    };
    let (left, right) = (text(&pair.left), text(&pair.right));
    assert!(left.len() > 200, "the HUD is drawn: {} text pixels", left.len());
    assert_eq!(left, right, "each letter lands on the same pixels in both eyes");
    assert!(left.iter().all(|&(x, y)| x < 200 && y < 40), "in the top-left corner");
    // And the clay behind it still differs between the eyes (the scene has parallax).
    assert_ne!(pair.left, pair.right);
}

/// Every display mode, composed by the composition pass from one stereo pair of the default
/// scene (128² per eye), against its golden `display-MODE.png` (quad-buffer: its two layers).
#[test]
fn every_display_mode_matches_its_golden() {
    let (left, right, _, composed) =
        render_composed("display", "default", Some((128, 128)), &DisplayMode::ALL);
    let mut images = composed.iter();
    for mode in DisplayMode::ALL {
        let (w, h) = mode.output_size((128, 128));
        for layer in 0..mode.layers() {
            let image = images.next().expect("one image per layer of every mode");
            assert_eq!(image.dimensions(), (w, h), "{mode}");
            let eye = match (mode.layers(), layer) {
                (1, _) => String::new(),
                (_, 0) => "-left".to_owned(),
                _ => "-right".to_owned(),
            };
            check_against_golden("display", &format!("{mode}{eye}"), image);
        }
    }
    assert!(images.next().is_none());
    // Quad-buffer output is the pair itself, mono the left eye, and so is a frame-sequential
    // display's first frame (phase left-even).
    assert_eq!(composed[0], left);
    assert_eq!(composed[1], right);
    assert_eq!(composed.last(), Some(&left));
    let first = |m: DisplayMode| -> usize {
        DisplayMode::ALL.iter().take_while(|&&x| x != m).map(|x| x.layers() as usize).sum()
    };
    assert_eq!(composed[first(DisplayMode::FrameSequential)], left);
}

/// In the anaglyph, the near red ball and the far blue ball of the parallax scene show red
/// fringes (the left eye's image) and cyan fringes (the right eye's) on the sides their
/// parallax puts them: crossed parallax in front of the screen puts the left eye's image of
/// the near ball to the right.
#[test]
fn anaglyph_fringes_sit_where_the_parallax_puts_them() {
    let (left, right, scene, composed) =
        render_composed("anaglyph-parallax", "scenes/tests/parallax.toml", None, &[DisplayMode::Anaglyph]);
    let anaglyph = &composed[0];
    check_against_golden("anaglyph-parallax", "anaglyph", anaglyph);
    let width = scene.output.width_px;
    let aspect = width as f32 / scene.output.height_px as f32;
    // Where only one eye sees the near ball the anaglyph is that eye's colour channel alone:
    // strongly red where only the left eye sees it, dark red with cyan elsewhere.
    let near = |p: &image::Rgba<u8>| {
        p[0] > 40 && u16::from(p[0]) > 2 * u16::from(p[2]) && u16::from(p[0]) > 2 * u16::from(p[1])
    };
    let (xl, _, _) = centroid(&left, near);
    let (xr, _, _) = centroid(&right, near);
    let parallax = scene.rig.parallax_px(0.3, width, aspect);
    assert!(parallax < -2.0 && (xr - xl - parallax).abs() <= 1.0, "near ball parallax {}", xr - xl);
    // On the row through the ball (the background is black, the other ball far below): the
    // red fringe, where only the left eye sees the ball, lies right of the ball's centre and
    // shows red alone; the cyan fringe, where only the right eye sees it, lies left of it and
    // shows no red.
    let (_, row, _) = centroid(&left, near);
    let row = row as u32;
    let lit = |p: &image::Rgba<u8>| p[0].max(p[1]).max(p[2]) > 30;
    let centre = 0.5 * (xl + xr);
    let mut red = 0;
    let mut cyan = 0;
    for x in 0..width {
        let (l, r, p) =
            (lit(left.get_pixel(x, row)), lit(right.get_pixel(x, row)), anaglyph.get_pixel(x, row));
        if l && !r {
            assert!((x as f32) > centre, "red fringe at column {x}, right of {centre}");
            assert!(p[0] > 30 && p[1] < 5 && p[2] < 5, "red fringe at {x}: {p:?}");
            red += 1;
        }
        if r && !l {
            assert!((x as f32) < centre, "cyan fringe at column {x}, left of {centre}");
            assert!(p[0] < 5 && p[1] > 30, "cyan fringe at {x}: {p:?}");
            cyan += 1;
        }
    }
    assert!(red >= 2 && cyan >= 2, "fringes {red} red and {cyan} cyan pixels wide on row {row}");
}

/// Head-tracked stereo (`[head]` with a calibrated 30 cm square screen): the head has moved up
/// and to the right, so the scene is seen from there through the fixed screen.
#[test]
fn head_tracked_scene_matches_golden() {
    golden_case("head-tracked", "scenes/tests/head-tracked.toml", None);
}

// `argile calibrate`'s test pattern, measured: the grid on the screen plane shows zero
// parallax, the near and far balls the disparities the calibration predicts.

type Pixel = image::Rgba<u8>;

fn is_marker_red(p: &Pixel) -> bool {
    p[0] > 40 && u16::from(p[0]) > 2 * u16::from(p[1]) && u16::from(p[0]) > 2 * u16::from(p[2])
}

fn is_marker_blue(p: &Pixel) -> bool {
    p[2] > 40 && u16::from(p[2]) > 2 * u16::from(p[0]) && u16::from(p[2]) > u16::from(p[1]) + 20
}

fn is_grid(p: &Pixel) -> bool {
    u16::from(p[1]) > 2 * u16::from(p[0]) && u16::from(p[1]) > u16::from(p[2]) + 10
}

/// Centroid of a ball's whole silhouette (its highlight included, which the colour test
/// misses and which sits differently in each eye): every lit, non-grid pixel near the pixels
/// of its colour.
fn silhouette_centroid(img: &image::RgbaImage, colour: impl Fn(&Pixel) -> bool) -> (f64, f64, usize) {
    let (cx, cy, n) = centroid(img, colour);
    let (cx, cy) = (f64::from(cx), f64::from(cy));
    // The radius of a disc of the coloured pixels' area, with a margin.
    let reach = (n as f64 / std::f64::consts::PI).sqrt() * 1.3 + 2.0;
    let (mut sx, mut sy, mut count) = (0.0, 0.0, 0usize);
    for (x, y, p) in img.enumerate_pixels() {
        let (fx, fy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
        if (fx - cx).hypot(fy - cy) <= reach && p.0[..3].iter().any(|&c| c > 20) && !is_grid(p) {
            sx += fx;
            sy += fy;
            count += 1;
        }
    }
    (sx / count as f64, sy / count as f64, count)
}

#[test]
fn the_calibration_test_pattern_shows_zero_parallax_on_the_screen_and_the_predicted_disparities() {
    let out_dir = out_dir("calibration");
    let options = argile::app::CalibrateOptions {
        calibration: None,
        out_dir,
        width_px: 256,
        validation: true,
        display_modes: Vec::new(),
    };
    // A missing Vulkan device or any validation message fails here, loudly.
    let done = argile::app::calibrate(&options).unwrap_or_else(|e| panic!("argile calibrate failed: {e:#}"));
    let load = |p: &std::path::Path| image::open(p).expect("rendered image reads back").to_rgba8();
    let (left, right) = (load(&done.written.left), load(&done.written.right));
    assert_eq!(left.dimensions(), (256, 144));

    // The balls: crossed in front, uncrossed behind, at the predicted size; no vertical parallax.
    let [near, far] = &done.pattern.markers;
    for (marker, select) in [(near, &is_marker_red as &dyn Fn(&Pixel) -> bool), (far, &is_marker_blue)] {
        let (xl, yl, nl) = silhouette_centroid(&left, select);
        let (xr, yr, nr) = silhouette_centroid(&right, select);
        assert!(nl > 15 && nr > 15, "{} ball visible in both eyes ({nl}, {nr} pixels)", marker.name);
        let measured = xr - xl;
        let expected = f64::from(marker.parallax_px);
        assert!(
            (measured - expected).abs() <= 0.5,
            "{} ball: parallax {measured:.2} px, expected {expected:.2} px",
            marker.name
        );
        assert!((yl - yr).abs() <= 0.3, "{} ball: vertical parallax {:.2} px", marker.name, yl - yr);
        assert_eq!(
            measured < 0.0,
            marker.in_front_m > 0.0,
            "{}: crossed in front, uncrossed behind",
            marker.name
        );
    }

    // The grid, on the rows no ball reaches in either eye: the two images agree on it, away
    // from the marks one eye alone is shown (the L, the R and the crosstalk squares, white;
    // with a margin wider than the shifts tried).
    let white = |p: &Pixel| p.0[..3].iter().all(|&c| c > 200);
    let marked = |x: i64, y: u32| {
        let (w, h) = (i64::from(left.width()), i64::from(left.height()));
        (x - 4..=x + 4).any(|x| {
            (i64::from(y) - 2..=i64::from(y) + 2).any(|y| {
                (0..w).contains(&x)
                    && (0..h).contains(&y)
                    && white(left.get_pixel(x as u32, y as u32)) != white(right.get_pixel(x as u32, y as u32))
            })
        })
    };
    let ball_rows: Vec<bool> = (0..left.height())
        .map(|y| {
            (0..left.width()).any(|x| {
                [&left, &right].iter().any(|img| {
                    let p = img.get_pixel(x, y);
                    is_marker_red(p) || is_marker_blue(p)
                })
            })
        })
        .collect();
    let rows: Vec<u32> = (0..left.height())
        .filter(|&y| {
            let lo = y.saturating_sub(3) as usize;
            let hi = ((y + 3) as usize).min(ball_rows.len() - 1);
            !ball_rows[lo..=hi].iter().any(|&b| b)
        })
        .collect();
    assert!(rows.len() > 80, "most rows are free of the balls ({} rows)", rows.len());
    let green = |img: &image::RgbaImage, x: i64, y: u32| -> f64 {
        if x < 0 || x >= i64::from(img.width()) {
            return 0.0;
        }
        f64::from(img.get_pixel(x as u32, y)[1])
    };
    let unmarked: Vec<(i64, u32)> = rows
        .iter()
        .flat_map(|&y| (0..i64::from(left.width())).map(move |x| (x, y)))
        .filter(|&(x, y)| !marked(x, y))
        .collect();
    assert!(unmarked.len() > rows.len() * left.width() as usize / 2, "the marks cover little of the grid");
    let mismatch = |shift: i64| -> f64 {
        let sum: f64 =
            unmarked.iter().map(|&(x, y)| (green(&left, x, y) - green(&right, x + shift, y)).abs()).sum();
        sum / unmarked.len() as f64
    };
    let at_zero = mismatch(0);
    for shift in [-3i64, -2, -1, 1, 2, 3] {
        let shifted = mismatch(shift);
        assert!(
            at_zero < shifted,
            "the grid matches best unshifted: {at_zero:.3} at 0, {shifted:.3} at {shift}"
        );
    }
    assert!(at_zero < 1.0, "the grid has zero parallax: mean green difference {at_zero:.3} levels");
    let grid = |p: &Pixel| p[1] > 60 && u16::from(p[1]) > 2 * u16::from(p[0]);
    let grid_pixels = rows.iter().flat_map(|&y| (0..left.width()).map(move |x| (x, y)));
    let lit = grid_pixels.filter(|&(x, y)| grid(left.get_pixel(x, y))).count();
    assert!(lit > 300, "the grid is drawn ({lit} pixels)");
}

/// A virtual-clay scene of `scenes/`, every capture of its timeline at 256² per eye: the goldens
/// are named after the captures.
fn golden_timeline_case(scene_path: &str) -> Vec<argile::app::WrittenCapture> {
    let case = Path::new(scene_path).file_stem().and_then(|s| s.to_str()).expect("scene file name");
    let scene = Scene::load(&root().join(scene_path)).expect("test scene loads");
    let options = RenderOptions {
        out_dir: out_dir(case),
        display_modes: Vec::new(),
        progress: false,
        validation: true,
        size_px: Some((256, 256)),
        calibration: None,
        eye_marks: Vec::new(),
    };
    let written = render_scene(&scene, &options).unwrap_or_else(|e| panic!("rendering {case} failed: {e:#}"));
    assert!(written.len() >= 2, "{case}: several times of the timeline");
    for capture in &written {
        let load = |p: &Path| image::open(p).expect("rendered image reads back").to_rgba8();
        let (left, right) = (load(&capture.left), load(&capture.right));
        assert_ne!(left, right, "{}: the two eyes must differ", capture.name);
        std::fs::create_dir_all(out_dir(&capture.name)).expect("output folder");
        check_against_golden(&capture.name, "left", &left);
        check_against_golden(&capture.name, "right", &right);
    }
    written
}

#[test]
fn bend_bar_matches_golden_through_its_timeline() {
    golden_timeline_case("scenes/bend-bar.toml");
}

#[test]
fn lattice_bars_match_golden_through_their_timeline() {
    golden_timeline_case("scenes/lattice-bars.toml");
}

/// A bar standing along Z under a lattice, seen from the side, with the slice through the
/// lattice's middle layer drawn: its zero contour, a red ring around the bar, shows as a red
/// line across the bar's middle in both eyes, at rest and swelled (a run of rows with red in the
/// middle third of the width, longer than any control's sphere).
#[test]
fn a_lattice_slice_shows_its_zero_contour_across_the_bar_and_matches_golden() {
    let written = golden_timeline_case("scenes/lattice-slice.toml");
    assert_eq!(written.len(), 2);
    for capture in &written {
        for path in [&capture.left, &capture.right] {
            let image = image::open(path).expect("rendered image reads back").to_rgba8();
            let (w, h) = image.dimensions();
            // The contour's red, lit: red well above green and blue.
            let red = |x: u32, y: u32| {
                let [r, g, b, _] = image.get_pixel(x, y).0.map(i32::from);
                r > 170 && r - g > 70 && r - b > 80
            };
            let (mut run, mut longest) = (0, 0);
            for y in 0..h {
                run = if (w / 3..2 * w / 3).any(|x| red(x, y)) { run + 1 } else { 0 };
                longest = longest.max(run);
            }
            assert!(
                longest >= 16,
                "{}: the contour across the bar: {longest} rows of red in a run",
                path.display()
            );
        }
    }
}

/// A figure's arm bent up (half way, its grab ball drawn), a block carried onto its head (half
/// way, its region drawn), then everything done: the arm bent, the head inflated, the other
/// arm deflated, the block on the head, turned.
#[test]
fn region_tools_match_golden_through_their_timeline() {
    golden_timeline_case("scenes/region-tools.toml");
}

/// Hua–Qin's copy and compose: one chair, a 3 × 3 grid of it.
#[test]
fn region_grid_matches_golden() {
    golden_case("region-grid", "scenes/region-grid.toml", Some((256, 256)));
}

/// A figure of three parts at three resolutions (a plinth at 2 mm, a body at 1 mm, a head at
/// 0.5 mm placed at 1.4 times its size and turned), a band of clay laid on the head part by a
/// world-space tool.
#[test]
fn parts_figure_matches_golden() {
    golden_case("parts-figure", "scenes/parts-figure.toml", Some((256, 256)));
}

/// A difference part drilling a hole through two others of different resolutions.
#[test]
fn parts_hole_matches_golden() {
    golden_case("parts-hole", "scenes/parts-hole.toml", Some((256, 256)));
}

/// The floating window: near clay cut by the left edge (a bar) and by the right edge (a ball)
/// masks the left eye's left strip and the right eye's right strip, each as wide as the clay's
/// crossed parallax at that edge; the other edges keep their pixels.
#[test]
fn the_floating_window_masks_the_edges_near_clay_touches_and_matches_golden() {
    let (left, right, scene) = render("floating-window", "scenes/floating-window.toml", None);
    let (w, h) = left.dimensions();
    let black_columns = |image: &image::RgbaImage, columns: &mut dyn Iterator<Item = u32>| {
        columns.take_while(|&x| (0..h).all(|y| image.get_pixel(x, y).0[..3] == [0, 0, 0])).count() as u32
    };
    // The bar's nearest point, 0.332 m from the eyes: p = e (C − Z) / Z over the plane's width.
    let (e, c, z) = (scene.rig.interaxial_m, scene.rig.convergence_m, 0.5 - 0.15 - 0.018);
    let plane_width = 2.0 * c * (scene.rig.fov_y_deg.to_radians() * 0.5).tan() * w as f32 / h as f32;
    let bar_px = e * (c - z) / z / plane_width * w as f32;
    let masked = black_columns(&left, &mut (0..w));
    assert!(
        (masked as f32 - bar_px).abs() <= 1.0,
        "the left eye's strip: {masked} px, the bar's parallax {bar_px:.2} px"
    );
    let right_masked = black_columns(&right, &mut (0..w).rev());
    assert!((3..=7).contains(&right_masked), "the right eye's strip: {right_masked} px");
    assert_eq!(black_columns(&right, &mut (0..w)), 0, "the right eye's left edge is whole");
    assert_eq!(black_columns(&left, &mut (0..w).rev()), 0, "the left eye's right edge is whole");
    check_against_golden("floating-window", "left", &left);
    check_against_golden("floating-window", "right", &right);
    // Without the window, the same views keep every pixel.
    let text = std::fs::read_to_string(common::root().join("scenes/floating-window.toml")).unwrap();
    let plain = common::out_dir("floating-window").join("whole.toml");
    std::fs::create_dir_all(plain.parent().unwrap()).unwrap();
    std::fs::write(&plain, text.replace("floating_window = true", "floating_window = false")).unwrap();
    let (whole, _, _) = render("floating-window-whole", plain.to_str().unwrap(), None);
    assert_eq!(black_columns(&whole, &mut (0..w)), 0);
}

/// `argile calibrate`'s pattern: the L in the left eye's picture only, the R in the right's,
/// each eye's crosstalk square in its own picture only, the row-interlaced image carrying the
/// left eye's L on its even rows (the shipped parity), and the pair matching its golden.
#[test]
fn the_calibration_pattern_shows_each_eye_its_letter_and_square_and_matches_golden() {
    let dir = out_dir("calibration-marks");
    let calibrated = argile::app::calibrate(&argile::app::CalibrateOptions {
        calibration: None,
        out_dir: dir.clone(),
        width_px: 384,
        validation: true,
        display_modes: vec![DisplayMode::RowInterlaced],
    })
    .expect("the test pattern renders");
    let load = |p: &Path| image::open(p).expect("the pattern reads back").to_rgba8();
    let (left, right) = (load(&calibrated.written.left), load(&calibrated.written.right));
    let (w, h) = left.dimensions();
    // White pixels in a region given in device coordinates (y down).
    let white_in = |image: &image::RgbaImage, (x0, y0): (f32, f32), (x1, y1): (f32, f32)| {
        let px = |v: f32, n: u32| (((v + 1.0) * 0.5 * n as f32) as u32).min(n - 1);
        let mut rows = Vec::new();
        for y in px(y0, h)..=px(y1, h) {
            for x in px(x0, w)..=px(x1, w) {
                if image.get_pixel(x, y).0[..3].iter().all(|&c| c > 240) {
                    rows.push(y);
                }
            }
        }
        rows
    };
    let l_region = ((-0.95, -0.92), (-0.6, -0.55));
    let r_region = ((0.6, -0.92), (0.95, -0.55));
    let (square_l, square_r) = (((-0.94, 0.6), (-0.66, 0.9)), ((0.66, 0.6), (0.94, 0.9)));
    for (what, eye, region, seen) in [
        ("L", "left", l_region, true),
        ("L", "right", l_region, false),
        ("R", "right", r_region, true),
        ("R", "left", r_region, false),
        ("the left eye's square", "left", square_l, true),
        ("the left eye's square", "right", square_l, false),
        ("the right eye's square", "right", square_r, true),
        ("the right eye's square", "left", square_r, false),
    ] {
        let image = if eye == "left" { &left } else { &right };
        let found = white_in(image, region.0, region.1).len();
        assert_eq!(found > 20, seen, "{what} in the {eye} eye's picture: {found} white pixels");
    }
    let interlaced = load(calibrated.written.composed.first().expect("the row-interlaced image"));
    let rows = white_in(&interlaced, l_region.0, l_region.1);
    assert!(rows.len() > 20 && rows.iter().all(|y| y % 2 == 0), "the L on even rows only: {rows:?}");
    check_against_golden("calibration-marks", "left", &left);
    check_against_golden("calibration-marks", "right", &right);
}

/// The judgement itself: a level of rounding everywhere passes (another CPU's shader code), a
/// picture moved by a pixel fails.
#[test]
fn the_golden_check_forgives_a_level_of_rounding_but_not_a_moved_edge() {
    let golden = image::open(common::root().join("tests/golden/parts-hole-left.png")).unwrap().to_rgba8();
    let rounded = image::RgbaImage::from_fn(golden.width(), golden.height(), |x, y| {
        let p = golden.get_pixel(x, y);
        image::Rgba([p[0].saturating_add(1), p[1].saturating_sub(1), p[2], p[3]])
    });
    assert_eq!(common::mean_error(&rounded, &golden), 0.0);
    let moved = image::RgbaImage::from_fn(golden.width(), golden.height(), |x, y| {
        *golden.get_pixel(x.saturating_sub(1), y)
    });
    let mean = common::mean_error(&moved, &golden);
    assert!(mean > 0.1, "a picture moved by a pixel passes: mean error {mean}");
}

#[test]
fn push_print_matches_golden_through_its_timeline() {
    golden_timeline_case("scenes/push-print.toml");
}

#[test]
fn poke_hole_matches_golden_through_its_timeline() {
    golden_timeline_case("scenes/poke-hole.toml");
}

/// The four glyph shapes side by side — sphere, box, cylinder, torus (a tube half the ring's
/// radius) — the first two as tools, the other two as controllers, over a black background:
/// each is drawn with its own shape, and the torus shows its hole.
#[test]
fn the_glyph_shapes_match_golden() {
    use argile::math::{Mat4, Quat, Vec3};
    use argile::render::{Environment, Frame, GlyphShape, Light, Renderer, RendererDesc, ToolGlyph};
    let (width, height) = (256u32, 128u32);
    let desc = RendererDesc { width, height, samples: 4, validation: true, view_passes: None };
    let mut renderer = Renderer::new(&desc, &Environment::Studio, 1.0).expect("a Vulkan device");
    let validation = renderer.validation_log();
    let rig = argile::stereo::StereoRig {
        eye_m: Vec3::new(0.0, 0.12, 0.5),
        target_m: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_deg: 30.0,
        interaxial_m: 0.02,
        convergence_m: 0.5,
        near_m: 0.05,
        far_m: 10.0,
    };
    let glyph = |shape, x: f32, turn: Quat, colour: [f32; 3]| ToolGlyph {
        shape,
        model: Mat4::from_scale_rotation_translation(Vec3::splat(0.04), turn, Vec3::new(x, 0.0, 0.0)),
        colour: Vec3::from(colour).extend(0.9),
    };
    let torus = glyph(GlyphShape::Torus { tube: 0.5 }, 0.165, Quat::from_rotation_x(1.2), [0.8, 0.2, 0.8]);
    let frame = Frame {
        views: rig.views(width as f32 / height as f32),
        lights: vec![Light::Directional {
            direction: Vec3::new(0.4, -0.8, -0.5),
            radiance: Vec3::splat(2.0),
        }],
        material: Default::default(),
        tools: vec![
            glyph(GlyphShape::Sphere, -0.165, Quat::IDENTITY, [0.9, 0.5, 0.2]),
            glyph(GlyphShape::Box, -0.055, Quat::from_rotation_y(0.6), [0.3, 0.8, 0.3]),
        ],
        controllers: vec![
            glyph(GlyphShape::Cylinder, 0.055, Quat::from_rotation_x(0.3), [0.3, 0.5, 1.0]),
            torus,
        ],
        stage: None,
        show_environment: false,
        background: Vec3::ZERO,
        hud: Vec::new(),
        panel: None,
        floating_window: argile::stereo::floating::FloatingWindow::NONE,
        eye_marks: Vec::new(),
    };
    renderer.draw(&frame).unwrap();
    let image = renderer.read_back().unwrap();
    drop(renderer);
    let messages = validation.take();
    assert!(messages.is_empty(), "the validation layer reported {messages:#?}");

    let eye = frame.views.eyes[0];
    let pixel = |p: Vec3| {
        let clip = eye.projection * eye.view * p.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        (((ndc.x + 1.0) * 0.5 * width as f32) as u32, ((ndc.y + 1.0) * 0.5 * height as f32) as u32)
    };
    let lit =
        |(x, y): (u32, u32)| image.left.get_pixel(x, y).0[..3].iter().map(|&c| u32::from(c)).sum::<u32>();
    for g in frame.tools.iter().chain(&frame.controllers).filter(|g| g.shape != torus.shape) {
        assert!(lit(pixel(g.model.w_axis.truncate())) > 100, "{:?} is drawn at its centre", g.shape);
    }
    assert_eq!(lit(pixel(torus.model.w_axis.truncate())), 0, "the torus's hole shows the background");
    let on_ring = torus.model.transform_point3(Vec3::X);
    assert!(lit(pixel(on_ring)) > 100, "the torus's ring is drawn");
    // The box covers its corners, beyond the sphere a box glyph used to be.
    let cube = frame.tools[1];
    for corner in [Vec3::new(0.9, 0.9, 0.9), Vec3::new(-0.9, -0.9, 0.9)] {
        assert!(lit(pixel(cube.model.transform_point3(corner))) > 100, "the box's corner {corner}");
    }
    check_against_golden("glyph-shapes", "left", &image.left);
    check_against_golden("glyph-shapes", "right", &image.right);
}

#[test]
fn swapped_eyes_write_each_eye_the_others_image() {
    // The same scene rendered as it is and with `[display] swap_eyes`: each image of the one is
    // the other eye's of the other, byte for byte.
    let text = std::fs::read_to_string(root().join("scenes/default.toml")).unwrap();
    let render = |swap: bool, case: &str| {
        let mut scene = Scene::parse(&text, "default.toml", None).unwrap();
        scene.display.swap_eyes = swap;
        let options = RenderOptions {
            out_dir: out_dir(case),
            display_modes: Vec::new(),
            progress: false,
            validation: true,
            size_px: Some((64, 64)),
            calibration: None,
            eye_marks: Vec::new(),
        };
        let written =
            render_scene(&scene, &options).unwrap_or_else(|e| panic!("rendering {case} failed: {e:#}"));
        let last = written.last().expect("a capture");
        (std::fs::read(&last.left).unwrap(), std::fs::read(&last.right).unwrap())
    };
    let (left, right) = render(false, "eyes-as-rendered");
    let (swapped_left, swapped_right) = render(true, "eyes-swapped");
    assert_ne!(left, right, "the eyes differ");
    assert!(swapped_left == right && swapped_right == left, "each eye has the other's image");
}
