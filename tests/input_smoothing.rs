//! The tracker filters on a recorded-style noisy hand path: a smooth 3D Lissajous curve
//! (speeds up to about 0.44 m/s) sampled at 90 Hz, with Gaussian noise of σ = 1 mm per axis
//! from a fixed-seed generator. Each filter must cut jitter (RMS of second differences) by a
//! stated factor while its lag (the time shift that best aligns its output with the clean
//! curve) stays under a stated bound. The figures are those quoted in `src/input/smoothing.rs`.

use std::f64::consts::TAU;

use argile::input::smoothing::{OneEuroFilter, PositionFilter, PredictionClamp, PredictiveFilter};
use argile::math::Vec3;

const RATE_HZ: f64 = 90.0;
const DURATION_S: f64 = 12.0;
const NOISE_M: f64 = 0.001;
/// Samples skipped before measuring, so start-up transients do not count.
const WARM_UP: usize = 90;

/// The clean hand path, metres.
fn clean(t_s: f64) -> Vec3 {
    Vec3::new(
        (0.12 * (TAU * 0.4 * t_s).sin()) as f32,
        (0.08 * (TAU * 0.6 * t_s + 0.5).sin()) as f32,
        (0.05 * (TAU * 0.3 * t_s).sin()) as f32,
    )
}

/// SplitMix64: a small, fixed, portable generator, so the path is the same everywhere.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    fn unit(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal (Box–Muller).
    fn normal(&mut self) -> f64 {
        (-2.0 * self.unit().ln()).sqrt() * (TAU * self.unit()).cos()
    }
}

/// `(time, noisy sample)` pairs.
fn noisy_path(seed: u64) -> Vec<(f64, Vec3)> {
    let mut rng = SplitMix64(seed);
    let n = (DURATION_S * RATE_HZ) as usize;
    (0..n)
        .map(|i| {
            let t = i as f64 / RATE_HZ;
            let noise = Vec3::new(
                (rng.normal() * NOISE_M) as f32,
                (rng.normal() * NOISE_M) as f32,
                (rng.normal() * NOISE_M) as f32,
            );
            (t, clean(t) + noise)
        })
        .collect()
}

/// RMS length of the second differences of a series, after the warm-up.
fn jitter(series: &[Vec3]) -> f64 {
    let d: Vec<f64> =
        series[WARM_UP..].windows(3).map(|w| f64::from((w[2] - 2.0 * w[1] + w[0]).length())).collect();
    (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt()
}

/// The shift (seconds, 0..150 ms in 0.5 ms steps) that best aligns `series` with the clean
/// path delayed by it, and the RMS distance left at that shift.
fn lag(times: &[f64], series: &[Vec3]) -> (f64, f64) {
    let rms_at = |shift_s: f64| {
        let sum: f64 = times[WARM_UP..]
            .iter()
            .zip(&series[WARM_UP..])
            .map(|(&t, &p)| f64::from((p - clean(t - shift_s)).length_squared()))
            .sum();
        (sum / (times.len() - WARM_UP) as f64).sqrt()
    };
    (0..=300).map(|k| k as f64 * 0.0005).map(|s| (s, rms_at(s))).min_by(|a, b| a.1.total_cmp(&b.1)).unwrap()
}

struct Measured {
    jitter_reduction: f64,
    lag_s: f64,
    residual_m: f64,
}

fn measure(filter: &mut dyn PositionFilter, seed: u64) -> Measured {
    let path = noisy_path(seed);
    let times: Vec<f64> = path.iter().map(|p| p.0).collect();
    let raw: Vec<Vec3> = path.iter().map(|p| p.1).collect();
    let out: Vec<Vec3> = path.iter().map(|&(t, p)| filter.filter(t, p)).collect();
    let (lag_s, residual_m) = lag(&times, &out);
    Measured { jitter_reduction: jitter(&raw) / jitter(&out), lag_s, residual_m }
}

#[test]
fn the_noisy_path_is_what_the_figures_assume() {
    let path = noisy_path(0x4741_4c59);
    let times: Vec<f64> = path.iter().map(|p| p.0).collect();
    let raw: Vec<Vec3> = path.iter().map(|p| p.1).collect();
    let (lag_s, residual_m) = lag(&times, &raw);
    assert_eq!(lag_s, 0.0, "raw samples have no lag");
    // σ = 1 mm per axis is √3 mm in 3D.
    assert!((residual_m - NOISE_M * 3f64.sqrt()).abs() < 1e-4, "{residual_m}");
    // Second differences of white noise: √6 σ per axis; the curve itself adds almost nothing.
    let j = jitter(&raw);
    assert!((j - NOISE_M * 18f64.sqrt()).abs() < 3e-4, "{j}");
    assert_eq!(noisy_path(0x4741_4c59)[500].1, path[500].1, "the generator is deterministic");
}

#[test]
fn galyean_hughes_filter_reduces_jitter_with_little_lag() {
    for seed in [0x4741_4c59, 1, 2] {
        let mut f = PredictiveFilter::new(0.005, PredictionClamp::PreviousPosition);
        let m = measure(&mut f, seed);
        eprintln!(
            "predictive, seed {seed}: jitter ÷{:.2}, lag {:.1} ms, residual {:.2} mm",
            m.jitter_reduction,
            m.lag_s * 1e3,
            m.residual_m * 1e3
        );
        assert!(m.jitter_reduction >= 1.25, "seed {seed}: jitter reduced only ÷{:.2}", m.jitter_reduction);
        assert!(m.lag_s < 0.002, "seed {seed}: lag {:.1} ms", m.lag_s * 1e3);
    }
}

#[test]
fn one_euro_filter_reduces_jitter_with_bounded_lag() {
    for seed in [0x4741_4c59, 1, 2] {
        let mut f = OneEuroFilter::hand_tracking();
        let m = measure(&mut f, seed);
        eprintln!(
            "one euro, seed {seed}: jitter ÷{:.2}, lag {:.1} ms, residual {:.2} mm",
            m.jitter_reduction,
            m.lag_s * 1e3,
            m.residual_m * 1e3
        );
        assert!(m.jitter_reduction >= 3.8, "seed {seed}: jitter reduced only ÷{:.2}", m.jitter_reduction);
        assert!(m.lag_s < 0.026, "seed {seed}: lag {:.1} ms", m.lag_s * 1e3);
    }
}
