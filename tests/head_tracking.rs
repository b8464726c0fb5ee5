//! The calibration test pattern, rendered offscreen on the pinned Vulkan device with the
//! validation layer on and measured: the grid on the screen plane shows zero parallax, the near
//! and far balls the disparities the calibration predicts.
//!
//! Needs a Vulkan device and fails (never skips) without one.

use std::path::PathBuf;

use argile::app::{calibrate, CalibrateOptions};

type Pixel = image::Rgba<u8>;

fn is_red(p: &Pixel) -> bool {
    p[0] > 40 && u16::from(p[0]) > 2 * u16::from(p[1]) && u16::from(p[0]) > 2 * u16::from(p[2])
}

fn is_blue(p: &Pixel) -> bool {
    p[2] > 40 && u16::from(p[2]) > 2 * u16::from(p[0]) && u16::from(p[2]) > u16::from(p[1]) + 20
}

/// Centroid (column, row) of the selected pixels and their count.
fn centroid(img: &image::RgbaImage, select: impl Fn(&Pixel) -> bool) -> (f64, f64, usize) {
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0usize);
    for (x, y, p) in img.enumerate_pixels() {
        if select(p) {
            sx += f64::from(x) + 0.5;
            sy += f64::from(y) + 0.5;
            n += 1;
        }
    }
    assert!(n > 0, "nothing selected");
    (sx / n as f64, sy / n as f64, n)
}

fn is_grid(p: &Pixel) -> bool {
    u16::from(p[1]) > 2 * u16::from(p[0]) && u16::from(p[1]) > u16::from(p[2]) + 10
}

/// Centroid of a ball's whole silhouette (its highlight included, which the colour test
/// misses and which sits differently in each eye): every lit, non-grid pixel near the pixels
/// of its colour.
fn silhouette_centroid(img: &image::RgbaImage, colour: impl Fn(&Pixel) -> bool) -> (f64, f64, usize) {
    let (cx, cy, n) = centroid(img, colour);
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
fn the_test_pattern_shows_zero_parallax_on_the_screen_and_the_predicted_disparities() {
    let out_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/stereo-tests/calibration");
    let options = CalibrateOptions { calibration: None, out_dir, width_px: 256, validation: true };
    // A missing Vulkan device or any validation message fails here, loudly.
    let done = calibrate(&options).unwrap_or_else(|e| panic!("argile calibrate failed: {e:#}"));
    let load = |p: &std::path::Path| image::open(p).expect("rendered image reads back").to_rgba8();
    let (left, right) = (load(&done.written.left), load(&done.written.right));
    assert_eq!(left.dimensions(), (256, 144));

    // The balls: crossed in front, uncrossed behind, at the predicted size; no vertical parallax.
    let [near, far] = &done.pattern.markers;
    for (marker, select) in [(near, &is_red as &dyn Fn(&Pixel) -> bool), (far, &is_blue)] {
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

    // The grid, on the rows no ball reaches in either eye: the two images agree on it.
    let ball_rows: Vec<bool> = (0..left.height())
        .map(|y| {
            (0..left.width()).any(|x| {
                [&left, &right].iter().any(|img| {
                    let p = img.get_pixel(x, y);
                    is_red(p) || is_blue(p)
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
    let mismatch = |shift: i64| -> f64 {
        let mut sum = 0.0;
        for &y in &rows {
            for x in 0..i64::from(left.width()) {
                sum += (green(&left, x, y) - green(&right, x + shift, y)).abs();
            }
        }
        sum / (rows.len() as f64 * f64::from(left.width()))
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
