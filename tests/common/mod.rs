//! What the image regression tests share: where goldens and outputs live, and the comparison
//! of an image with its golden (tolerance, diff image, `BLESS=1` to regenerate).

#![allow(dead_code)] // each test crate uses its own part

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};

pub mod xr;

/// Per-pixel error is the largest absolute channel difference (0..=255).
/// Thresholds set on llvmpipe (Mesa 22.3.6, LLVM 15), which renders bit-identically across
/// runs: a change that moves any edge by a pixel fails, a blessed image passes exactly.
/// llvmpipe compiles its shaders for the CPU it runs on, and a flat surface whose shade lies on
/// a level's boundary rounds to either level depending on whether that CPU fuses multiply-adds:
/// the mean counts only the error beyond one level, so such a surface does not fail a golden
/// made on another machine, while a moved edge (tens of levels) still does.
const MAX_MEAN_ERROR: f64 = 0.1; // llvmpipe, Mesa 22.3.6
const MAX_P99_ERROR: u8 = 4; // llvmpipe, Mesa 22.3.6

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn out_dir(case: &str) -> PathBuf {
    root().join("target").join("stereo-tests").join(case)
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
    let mean = errors.iter().map(|&e| f64::from(e.saturating_sub(1))).sum::<f64>() / errors.len() as f64;
    errors.sort_unstable();
    let p99 = errors[(errors.len() * 99 / 100).min(errors.len() - 1)];
    Comparison { mean, p99, diff }
}

/// The mean error of `actual` against `golden`, as the golden checks judge it.
pub fn mean_error(actual: &image::RgbaImage, golden: &image::RgbaImage) -> f64 {
    compare(actual, golden).mean
}

pub fn check_against_golden(case: &str, eye: &str, actual: &image::RgbaImage) {
    check_against_golden_within(case, eye, actual, MAX_MEAN_ERROR);
}

/// [`check_against_golden`] with a mean error of at most `max_mean` levels (the 99th
/// percentile's bound unchanged), for cases whose pictures differ by a level between CPUs.
pub fn check_against_golden_within(case: &str, eye: &str, actual: &image::RgbaImage, max_mean: f64) {
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
    std::fs::create_dir_all(&dir).expect("test output folder");
    let driver = "lavapipe";
    actual.save(dir.join(format!("{case}-{eye}-{driver}-actual.png"))).expect("actual written");
    c.diff.save(dir.join(format!("{case}-{eye}-{driver}-diff.png"))).expect("diff written");
    assert!(
        c.mean <= max_mean && c.p99 <= MAX_P99_ERROR,
        "{case} {eye} eye differs from its golden: mean error {:.3} (max {max_mean}), 99th percentile {} \
         (max {MAX_P99_ERROR}); see {}",
        c.mean,
        c.p99,
        dir.display()
    );
}

/// An X server on a display number it picks itself; killed on drop.
pub struct Xvfb {
    child: Child,
    /// Its display, for `DISPLAY`.
    pub display: String,
}

impl Xvfb {
    pub fn start() -> Self {
        let mut child = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "800x600x24", "-nolisten", "tcp"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap_or_else(|e| {
                panic!("cannot start Xvfb ({e}); install the Debian package xvfb (scripts/setup test does)")
            });
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("piped stdout"))
            .read_line(&mut line)
            .expect("Xvfb prints its display number");
        let number = line.trim();
        assert!(!number.is_empty() && number.chars().all(|c| c.is_ascii_digit()), "Xvfb said {line:?}");
        Self { child, display: format!(":{number}") }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
