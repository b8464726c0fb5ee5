//! Recorded-style SpaceMouse report streams (`tests/fixtures/spacemouse/`, format in its
//! README) driven through the code a device reader uses: `SpaceMouseState::feed`, then the
//! shipped calibration.

use std::path::Path;

use anyhow::{bail, Context, Result};
use argile::input::calibration::{apply_calibration, DominantAxis, SixDof, SpaceMouseCalibration};
use argile::input::spacemouse::{RawAxes, SpaceMouseState};

/// One line of a fixture: time, bytes, and whether it is marked `# bad:`.
struct Recorded {
    time_ms: f64,
    bytes: Vec<u8>,
    marked_bad: bool,
}

fn load(name: &str) -> Result<Vec<Recorded>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/spacemouse").join(name);
    let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let (code, comment) = line.split_once('#').unwrap_or((line, ""));
        if code.trim().is_empty() {
            continue;
        }
        let Some((time, hex)) = code.split_once(':') else {
            bail!("{}:{}: expected `<time ms>: <hex bytes>`", path.display(), n + 1);
        };
        let time_ms: f64 =
            time.trim().parse().with_context(|| format!("{}:{}: time", path.display(), n + 1))?;
        let bytes = hex
            .split_whitespace()
            .map(|b| {
                u8::from_str_radix(b, 16).with_context(|| format!("{}:{}: byte `{b}`", path.display(), n + 1))
            })
            .collect::<Result<Vec<u8>>>()?;
        out.push(Recorded { time_ms, bytes, marked_bad: comment.trim_start().starts_with("bad:") });
    }
    Ok(out)
}

/// Feeds a stream; returns the state and the calibrated motion after every report.
fn replay(stream: &[Recorded], calib: &SpaceMouseCalibration) -> (SpaceMouseState, Vec<SixDof>) {
    let mut state = SpaceMouseState::default();
    let mut motion = Vec::with_capacity(stream.len());
    for r in stream {
        let result = state.feed(&r.bytes);
        assert_eq!(result.is_err(), r.marked_bad, "at {} ms, {:02x?}: {result:?}", r.time_ms, r.bytes);
        motion.push(apply_calibration(state.axes, calib));
    }
    (state, motion)
}

#[test]
fn fixtures_are_in_time_order() -> Result<()> {
    for name in ["navigator-push-and-twist.hex", "wireless-six-axis.hex", "corrupt-stream.hex"] {
        let stream = load(name)?;
        assert!(stream.len() > 10, "{name}");
        assert!(stream.windows(2).all(|w| w[0].time_ms < w[1].time_ms), "{name}");
    }
    Ok(())
}

#[test]
fn navigator_push_and_twist() -> Result<()> {
    let stream = load("navigator-push-and-twist.hex")?;
    let calib = SpaceMouseCalibration::shipped();
    let (state, motion) = replay(&stream, &calib);
    assert_eq!(state.rejected_reports, 0);
    assert_eq!(state.accepted_reports, stream.len() as u64);
    assert_eq!(state.axes, RawAxes([0, 0, 0, 0, 0, 200]));
    assert_eq!(state.buttons, 0b10);
    assert_eq!(state.battery_percent, None);

    // The push reaches full deflection: the tool goes down at full rate, and the cap's
    // cross-talk stays inside the dead zone, so nothing else moves meanwhile.
    let push: Vec<&SixDof> = motion.iter().filter(|m| m.translation.y != 0.0).collect();
    assert!(push.len() > 30, "{}", push.len());
    let lowest = push.iter().map(|m| m.translation.y).fold(0.0, f32::min);
    assert!((lowest + 1.0).abs() < 1e-6, "full push gives −1, got {lowest}");
    assert!(push.iter().all(|m| m.translation.y <= 0.0 && m.translation.x == 0.0 && m.translation.z == 0.0));
    assert!(push.iter().all(|m| m.rotation == argile::math::Vec3::ZERO));

    // The held twist turns the tool clockwise seen from above (negative about world +y),
    // at (200/350 − dz)/(1 − dz) to the curve's power.
    let last = motion.last().unwrap();
    let d = (200.0 / 350.0 - calib.dead_zone) / (1.0 - calib.dead_zone);
    assert!((last.rotation.y + d.powf(calib.curve_exponent)).abs() < 1e-5, "{last:?}");
    assert_eq!(last.translation, argile::math::Vec3::ZERO);
    Ok(())
}

#[test]
fn navigator_button_edges() -> Result<()> {
    let stream = load("navigator-push-and-twist.hex")?;
    let mut state = SpaceMouseState::default();
    let mut edges = Vec::new();
    for r in &stream {
        let change = state.feed(&r.bytes).expect("a clean stream");
        if change.pressed != 0 || change.released != 0 {
            edges.push((change.pressed, change.released));
        }
    }
    assert_eq!(edges, [(0b1, 0), (0, 0b1), (0b10, 0)]);
    Ok(())
}

#[test]
fn wireless_six_axis_stream() -> Result<()> {
    let stream = load("wireless-six-axis.hex")?;
    let calib = SpaceMouseCalibration::shipped();
    let (state, motion) = replay(&stream, &calib);
    assert_eq!((state.accepted_reports, state.rejected_reports), (stream.len() as u64, 0));
    assert_eq!(state.axes, RawAxes::default());
    assert_eq!(state.battery_percent, Some(87));
    assert_eq!(state.buttons, 0b1);

    // Right and away from the user: +x and −z in the world; rotation cross-talk stays in
    // the dead zone.
    let peak = motion.iter().max_by(|a, b| a.translation.x.total_cmp(&b.translation.x)).unwrap();
    assert!(peak.translation.x > 0.7 && peak.translation.z < -0.2, "{peak:?}");
    assert_eq!(peak.translation.y, 0.0);
    assert!(motion.iter().all(|m| m.rotation == argile::math::Vec3::ZERO));

    // One axis at a time: the smaller y deflection is dropped whenever x leads.
    let single = SpaceMouseCalibration { dominant_axis: DominantAxis::Single, ..calib };
    let (_, motion) = replay(&stream, &single);
    assert!(motion.iter().all(|m| m.to_array().iter().filter(|v| **v != 0.0).count() <= 1));
    assert!(motion.iter().any(|m| m.translation.x > 0.7));
    assert!(motion.iter().all(|m| m.translation.z == 0.0));
    Ok(())
}

#[test]
fn corrupt_reports_are_counted_and_change_nothing() -> Result<()> {
    let stream = load("corrupt-stream.hex")?;
    let calib = SpaceMouseCalibration::shipped();
    let (state, _) = replay(&stream, &calib);
    let bad = stream.iter().filter(|r| r.marked_bad).count() as u64;
    assert_eq!(bad, 10);
    assert_eq!(state.rejected_reports, bad);
    assert_eq!(state.accepted_reports, stream.len() as u64 - bad);

    let good: Vec<Recorded> = stream.into_iter().filter(|r| !r.marked_bad).collect();
    let (clean, _) = replay(&good, &calib);
    assert_eq!(SpaceMouseState { rejected_reports: bad, ..clean }, state);
    assert_eq!(state.axes, RawAxes([120, -40, 0, 0, 15, 0]));
    assert_eq!((state.buttons, state.battery_percent), (0b1, Some(50)));
    Ok(())
}
