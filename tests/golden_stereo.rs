//! Stereo image regression tests: scenes rendered offscreen (multiview, 4x MSAA) on the pinned
//! Vulkan device with the validation layer on, each eye compared with `tests/golden/`.
//!
//! Regenerate the goldens after a deliberate change: `BLESS=1 scripts/test` (or
//! `BLESS=1 cargo test --test golden_stereo`). Actual and diff images of every run are written
//! under `target/stereo-tests/`.
//!
//! These tests need a Vulkan device and fail (never skip) without one.

use std::path::{Path, PathBuf};

use argile::app::{render_scene, RenderOptions};
use argile::scene::Scene;

/// Per-pixel error is the largest absolute channel difference (0..=255).
/// Thresholds set on llvmpipe (Mesa 22.3.6, LLVM 15), which renders bit-identically across
/// runs: a change that moves any edge by a pixel fails, a blessed image passes exactly.
const MAX_MEAN_ERROR: f64 = 0.1; // llvmpipe, Mesa 22.3.6
const MAX_P99_ERROR: u8 = 4; // llvmpipe, Mesa 22.3.6

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn out_dir(case: &str) -> PathBuf {
    root().join("target").join("stereo-tests").join(case)
}

fn render(
    case: &str,
    scene_path: &str,
    size: Option<(u32, u32)>,
) -> (image::RgbaImage, image::RgbaImage, Scene) {
    let scene = if scene_path == "default" {
        Scene::default_scene()
    } else {
        Scene::load(&root().join(scene_path)).expect("test scene loads")
    };
    let options = RenderOptions {
        out_dir: out_dir(case),
        preview: None,
        progress: false,
        validation: true,
        size_px: size,
    };
    // A missing Vulkan device or any validation message fails here, loudly.
    let written = render_scene(&scene, &options).unwrap_or_else(|e| panic!("rendering {case} failed: {e:#}"));
    assert_eq!(written.len(), 1, "{case} has one capture");
    let load = |p: &Path| image::open(p).expect("rendered image reads back").to_rgba8();
    (load(&written[0].left), load(&written[0].right), scene)
}

struct Comparison {
    mean: f64,
    p99: u8,
    diff: image::RgbaImage,
}

fn compare(actual: &image::RgbaImage, golden: &image::RgbaImage) -> Comparison {
    assert_eq!(actual.dimensions(), golden.dimensions(), "image size changed");
    let mut errors: Vec<u8> = Vec::with_capacity((actual.width() * actual.height()) as usize);
    let diff = image::RgbaImage::from_fn(actual.width(), actual.height(), |x, y| {
        let (a, g) = (actual.get_pixel(x, y), golden.get_pixel(x, y));
        let e = (0..4).map(|i| a[i].abs_diff(g[i])).max().unwrap_or(0);
        errors.push(e);
        // Errors in red on a dimmed copy of the golden, so where they are is visible.
        let base = g[1] / 4;
        image::Rgba([base.saturating_add(e.saturating_mul(8)), base, base, 255])
    });
    let mean = errors.iter().map(|&e| f64::from(e)).sum::<f64>() / errors.len() as f64;
    errors.sort_unstable();
    let p99 = errors[(errors.len() * 99 / 100).min(errors.len() - 1)];
    Comparison { mean, p99, diff }
}

fn check_against_golden(case: &str, eye: &str, actual: &image::RgbaImage) {
    let golden_path = root().join("tests/golden").join(format!("{case}-{eye}.png"));
    if std::env::var_os("BLESS").is_some() {
        actual.save(&golden_path).expect("golden written");
        eprintln!("blessed {}", golden_path.display());
        return;
    }
    let golden = match image::open(&golden_path) {
        Ok(g) => g.to_rgba8(),
        Err(e) => panic!(
            "no golden {} ({e}); render it with BLESS=1 and look at it before committing",
            golden_path.display()
        ),
    };
    let c = compare(actual, &golden);
    let dir = out_dir(case);
    let driver = "lavapipe";
    actual.save(dir.join(format!("{case}-{eye}-{driver}-actual.png"))).expect("actual written");
    c.diff.save(dir.join(format!("{case}-{eye}-{driver}-diff.png"))).expect("diff written");
    assert!(
        c.mean <= MAX_MEAN_ERROR && c.p99 <= MAX_P99_ERROR,
        "{case} {eye} eye differs from its golden: mean error {:.3} (max {MAX_MEAN_ERROR}), 99th percentile {} \
         (max {MAX_P99_ERROR}); see {}",
        c.mean,
        c.p99,
        dir.display()
    );
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

#[test]
fn tool_eraser_matches_golden() {
    golden_tool_case("tool-eraser");
}

#[test]
fn tool_heat_gun_matches_golden() {
    golden_tool_case("tool-heat-gun");
}

#[test]
fn tool_build_matches_golden() {
    golden_tool_case("tool-build");
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

/// A virtual-clay scene of `scenes/`, every capture of its timeline at 256² per eye: the goldens
/// are named after the captures.
fn golden_timeline_case(scene_path: &str) {
    let case = Path::new(scene_path).file_stem().and_then(|s| s.to_str()).expect("scene file name");
    let scene = Scene::load(&root().join(scene_path)).expect("test scene loads");
    let options = RenderOptions {
        out_dir: out_dir(case),
        preview: None,
        progress: false,
        validation: true,
        size_px: Some((256, 256)),
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
}

#[test]
fn bend_bar_matches_golden_through_its_timeline() {
    golden_timeline_case("scenes/bend-bar.toml");
}

#[test]
fn push_print_matches_golden_through_its_timeline() {
    golden_timeline_case("scenes/push-print.toml");
}

#[test]
fn poke_hole_matches_golden_through_its_timeline() {
    golden_timeline_case("scenes/poke-hole.toml");
}
