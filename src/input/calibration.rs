//! SpaceMouse calibration: data (`calibration/spacemouse.toml`) and the pure function that
//! turns raw device counts into calibrated six-axis deflection.
//!
//! [`apply_calibration`] works in this order, per output axis:
//!
//! ```text
//!  raw counts ──► pick source axis (axis map) ──► ÷ full_scale, clamp to [-1, 1]
//!    ──► dead zone: |v| ≤ dz → 0, else (|v| − dz) / (1 − dz)   (continuous at the edge)
//!    ──► dominant-axis filter (keeps only the largest deflection, see DominantAxis)
//!    ──► response curve |v|^curve_exponent ──► × axis sensitivity × global sensitivity
//!    ──► sign (invert)
//! ```
//!
//! Invariants (tested with proptest): the output is finite and bounded by the sensitivities for
//! every raw input and every calibration that loads; each output is monotone in its source
//! axis; deflections inside the dead zone give exactly zero.
//!
//! A calibration file is layered over the shipped defaults: a user file names only the keys it
//! changes. Unknown keys are refused and every error names the file, line and column.

use std::path::Path;

use serde::Deserialize;
use toml::Spanned;

use super::spacemouse::RawAxes;
use crate::math::Vec3;
use crate::scene::line_column;

/// The shipped calibration, embedded in the binary; `calibration/spacemouse.toml` documents
/// every key.
pub const SHIPPED_SPACEMOUSE_TOML: &str = include_str!("../../calibration/spacemouse.toml");

/// A problem with a calibration or mapping file; the message names the file and, where it
/// can, the line and column.
pub type CalibrationError = crate::scene::FileError;

/// A calibration or mapping file being read over a base layer: errors name the file, line and
/// column; values are range-checked; absent keys fall back to the base.
pub(crate) struct Layer<'t> {
    /// The file's text.
    pub(crate) text: &'t str,
    /// The file's name, for messages.
    pub(crate) name: &'t str,
    /// What the file is ("calibration", "mapping"), for messages.
    pub(crate) what: &'t str,
}

impl Layer<'_> {
    /// An error at `span` of the text (the file's start when unknown).
    pub(crate) fn at(&self, span: Option<std::ops::Range<usize>>, message: String) -> CalibrationError {
        let (line, column) = span.map_or((1, 1), |s| line_column(self.text, s.start));
        CalibrationError::Invalid { path: self.name.to_owned(), line, column, message }
    }

    /// The error for a key that neither the file nor a base gives.
    pub(crate) fn missing(&self, key: &str) -> CalibrationError {
        self.at(None, format!("`{key}` is missing (a complete {} needs it)", self.what))
    }

    /// A value given in the file, else `fallback` when absent.
    pub(crate) fn value<T>(
        &self,
        value: Option<T>,
        key: &str,
        fallback: Option<T>,
    ) -> Result<T, CalibrationError> {
        value.or(fallback).ok_or_else(|| self.missing(key))
    }

    /// A number within `range`, else `fallback` when absent.
    pub(crate) fn number(
        &self,
        value: Option<Spanned<f32>>,
        key: &str,
        range: std::ops::RangeInclusive<f32>,
        fallback: Option<f32>,
    ) -> Result<f32, CalibrationError> {
        match value {
            Some(v) if range.contains(v.get_ref()) => Ok(*v.get_ref()),
            Some(v) => Err(self.at(
                Some(v.span()),
                format!("`{key}` must be between {} and {}, not {}", range.start(), range.end(), v.get_ref()),
            )),
            None => fallback.ok_or_else(|| self.missing(key)),
        }
    }
}

/// Reads a device file's text; the error names the file and says what it is (`kind`).
pub(crate) fn read_text(path: &Path, kind: &'static str) -> Result<String, CalibrationError> {
    crate::io::text::read_text(path, crate::io::text::SETTINGS_LIMIT)
        .map_err(|reason| CalibrationError::Read { kind, path: path.to_owned(), reason })
}

/// One of the device's raw axes, in report order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RawAxis {
    /// Translation x (device right).
    X,
    /// Translation y (device towards the user).
    Y,
    /// Translation z (device down).
    Z,
    /// Rotation about x.
    Rx,
    /// Rotation about y.
    Ry,
    /// Rotation about z.
    Rz,
}

impl RawAxis {
    /// Index into [`RawAxes`].
    pub fn index(self) -> usize {
        self as usize
    }

    fn name(self) -> &'static str {
        ["x", "y", "z", "rx", "ry", "rz"][self.index()]
    }
}

/// Names of the calibrated output axes, in [`SixDof`] order.
pub const OUTPUT_AXES: [&str; 6] = ["tx", "ty", "tz", "rx", "ry", "rz"];

/// Which deflections survive the dominant-axis filter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DominantAxis {
    /// All six axes pass.
    #[default]
    Off,
    /// Only the single largest of the six (ties: the first in tx..rz order).
    Single,
    /// The largest translation and the largest rotation.
    PerGroup,
}

/// How one output axis is driven.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisCalibration {
    /// The raw axis feeding it.
    pub from: RawAxis,
    /// Whether its sign is flipped.
    pub invert: bool,
    /// Its own gain, ≥ 0.
    pub sensitivity: f32,
}

/// A validated SpaceMouse calibration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpaceMouseCalibration {
    /// Raw counts of a full deflection (> 0).
    pub full_scale: f32,
    /// Fraction of full deflection read as zero, in [0, 0.95].
    pub dead_zone: f32,
    /// Exponent of the response curve, in [0.2, 5]; 1 is linear, above 1 gives fine control
    /// near the centre.
    pub curve_exponent: f32,
    /// Gain applied to every axis, ≥ 0.
    pub sensitivity: f32,
    /// The dominant-axis filter.
    pub dominant_axis: DominantAxis,
    /// Output axes tx, ty, tz, rx, ry, rz.
    pub axes: [AxisCalibration; 6],
}

/// Calibrated six-axis deflection: each component is a signed fraction of full deflection
/// times the sensitivities. Consumers scale it into metres and radians per second.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SixDof {
    /// World-frame translation deflection (x right, y up, z towards the viewer).
    pub translation: Vec3,
    /// World-frame rotation deflection, about x, y, z.
    pub rotation: Vec3,
}

impl SixDof {
    /// The six components in tx..rz order.
    pub fn to_array(&self) -> [f32; 6] {
        let (t, r) = (self.translation, self.rotation);
        [t.x, t.y, t.z, r.x, r.y, r.z]
    }

    /// From six components in tx..rz order.
    pub fn from_array(v: [f32; 6]) -> Self {
        Self { translation: Vec3::new(v[0], v[1], v[2]), rotation: Vec3::new(v[3], v[4], v[5]) }
    }
}

/// Raw counts to calibrated deflection. Pure; finite for every input (see the module docs).
pub fn apply_calibration(raw: RawAxes, calib: &SpaceMouseCalibration) -> SixDof {
    let dz = calib.dead_zone;
    let mut deflection = [0.0f32; 6];
    for (out, axis) in deflection.iter_mut().zip(&calib.axes) {
        let v = (f32::from(raw.0[axis.from.index()]) / calib.full_scale).clamp(-1.0, 1.0);
        let past = ((v.abs() - dz) / (1.0 - dz)).max(0.0);
        *out = if v < 0.0 { -past } else { past };
    }
    match calib.dominant_axis {
        DominantAxis::Off => {}
        DominantAxis::Single => keep_largest(&mut deflection),
        DominantAxis::PerGroup => {
            let (t, r) = deflection.split_at_mut(3);
            keep_largest(t);
            keep_largest(r);
        }
    }
    let mut out = [0.0f32; 6];
    for ((o, v), axis) in out.iter_mut().zip(deflection).zip(&calib.axes) {
        let magnitude = v.abs().powf(calib.curve_exponent) * axis.sensitivity * calib.sensitivity;
        let negative = (v < 0.0) != axis.invert;
        *o = if v == 0.0 {
            0.0
        } else if negative {
            -magnitude
        } else {
            magnitude
        };
    }
    SixDof::from_array(out)
}

/// Zeroes all but the first largest-magnitude entry.
fn keep_largest(values: &mut [f32]) {
    let mut best = 0;
    for (i, v) in values.iter().enumerate() {
        if v.abs() > values[best].abs() {
            best = i;
        }
    }
    for (i, v) in values.iter_mut().enumerate() {
        if i != best {
            *v = 0.0;
        }
    }
}

impl SpaceMouseCalibration {
    /// The shipped calibration (`calibration/spacemouse.toml`, embedded).
    pub fn shipped() -> Self {
        Self::parse_layer(SHIPPED_SPACEMOUSE_TOML, "calibration/spacemouse.toml", None)
            .expect("the shipped SpaceMouse calibration is valid (tested)")
    }

    /// Loads a calibration file, layered over the shipped defaults.
    pub fn load(path: &Path) -> Result<Self, CalibrationError> {
        Self::parse(&read_text(path, "calibration")?, &path.display().to_string())
    }

    /// Parses calibration text layered over the shipped defaults; `name` is used in messages.
    pub fn parse(text: &str, name: &str) -> Result<Self, CalibrationError> {
        Self::parse_layer(text, name, Some(&Self::shipped()))
    }

    /// Parses calibration text over `base`; without a base every key must be present.
    pub fn parse_layer(text: &str, name: &str, base: Option<&Self>) -> Result<Self, CalibrationError> {
        let layer = Layer { text, name, what: "calibration" };
        let file: CalibrationFile =
            crate::scene::parse_toml(text).map_err(|(span, message)| layer.at(span, message))?;
        let full_scale =
            layer.number(file.full_scale, "full_scale", 1.0..=32767.0, base.map(|b| b.full_scale))?;
        let dead_zone = layer.number(file.dead_zone, "dead_zone", 0.0..=0.95, base.map(|b| b.dead_zone))?;
        let curve_exponent =
            layer.number(file.curve_exponent, "curve_exponent", 0.2..=5.0, base.map(|b| b.curve_exponent))?;
        let sensitivity =
            layer.number(file.sensitivity, "sensitivity", 0.0..=100.0, base.map(|b| b.sensitivity))?;
        let dominant_axis = match (file.dominant_axis, base) {
            (Some(d), _) => d,
            (None, Some(b)) => b.dominant_axis,
            (None, None) => return Err(layer.missing("dominant_axis")),
        };

        let given = file.axes.unwrap_or_default();
        let entries = [given.tx, given.ty, given.tz, given.rx, given.ry, given.rz];
        let mut axes = [AxisCalibration { from: RawAxis::X, invert: false, sensitivity: 1.0 }; 6];
        let mut spans: [Option<std::ops::Range<usize>>; 6] = Default::default();
        for (i, entry) in entries.into_iter().enumerate() {
            let out = OUTPUT_AXES[i];
            axes[i] = match entry {
                Some(e) => {
                    spans[i] = Some(e.span());
                    let e = e.into_inner();
                    let sensitivity = layer.number(
                        e.sensitivity,
                        &format!("axes.{out}.sensitivity"),
                        0.0..=100.0,
                        Some(1.0),
                    )?;
                    AxisCalibration { from: e.from, invert: e.invert, sensitivity }
                }
                None => base.map(|b| b.axes[i]).ok_or_else(|| layer.missing(&format!("axes.{out}")))?,
            };
        }
        // Two outputs fed by one raw axis is almost always a typo; the unfed axis would be dead.
        for i in 0..6 {
            if let Some(j) = (0..i).find(|&j| axes[j].from == axes[i].from) {
                let span = spans[i].clone().or_else(|| spans[j].clone());
                return Err(layer.at(
                    span,
                    format!(
                        "raw axis `{}` drives both `{}` and `{}`; each output needs its own raw axis",
                        axes[i].from.name(),
                        OUTPUT_AXES[j],
                        OUTPUT_AXES[i]
                    ),
                ));
            }
        }
        Ok(Self { full_scale, dead_zone, curve_exponent, sensitivity, dominant_axis, axes })
    }
}

/// The TOML layout; every table refuses unknown keys.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CalibrationFile {
    full_scale: Option<Spanned<f32>>,
    dead_zone: Option<Spanned<f32>>,
    curve_exponent: Option<Spanned<f32>>,
    sensitivity: Option<Spanned<f32>>,
    dominant_axis: Option<DominantAxis>,
    axes: Option<AxesFile>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct AxesFile {
    tx: Option<Spanned<AxisFile>>,
    ty: Option<Spanned<AxisFile>>,
    tz: Option<Spanned<AxisFile>>,
    rx: Option<Spanned<AxisFile>>,
    ry: Option<Spanned<AxisFile>>,
    rz: Option<Spanned<AxisFile>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AxisFile {
    from: RawAxis,
    #[serde(default)]
    invert: bool,
    sensitivity: Option<Spanned<f32>>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn linear() -> SpaceMouseCalibration {
        let axis = |from| AxisCalibration { from, invert: false, sensitivity: 1.0 };
        SpaceMouseCalibration {
            full_scale: 100.0,
            dead_zone: 0.0,
            curve_exponent: 1.0,
            sensitivity: 1.0,
            dominant_axis: DominantAxis::Off,
            axes: [RawAxis::X, RawAxis::Y, RawAxis::Z, RawAxis::Rx, RawAxis::Ry, RawAxis::Rz].map(axis),
        }
    }

    fn invalid(e: CalibrationError) -> (String, usize, usize, String) {
        match e {
            CalibrationError::Invalid { path, line, column, message } => (path, line, column, message),
            other => panic!("expected an Invalid error, got {other}"),
        }
    }

    #[test]
    fn shipped_file_is_complete_and_maps_device_axes_to_world() {
        let c = SpaceMouseCalibration::shipped();
        assert_eq!(c.full_scale, 350.0);
        assert!(c.dead_zone > 0.0 && c.curve_exponent >= 1.0);
        // Pushing the cap down (device +z) moves the tool down (world −y); pulling it towards
        // the user (device +y) moves the tool towards the viewer (world +z).
        let down = apply_calibration(RawAxes([0, 0, 350, 0, 0, 0]), &c);
        assert!(down.translation.y < -0.9 && down.translation.x == 0.0 && down.translation.z == 0.0);
        let pull = apply_calibration(RawAxes([0, 350, 0, 0, 0, 0]), &c);
        assert!(pull.translation.z > 0.9);
        // Twisting clockwise seen from above (device +rz about the downward z) turns the tool
        // clockwise seen from above: negative about world +y.
        let twist = apply_calibration(RawAxes([0, 0, 0, 0, 0, 350]), &c);
        assert!(twist.rotation.y < -0.9);
        assert_eq!(apply_calibration(RawAxes::default(), &c), SixDof::default());
    }

    #[test]
    fn dead_zone_sign_and_continuity() {
        let mut c = linear();
        c.dead_zone = 0.1;
        c.axes[0].invert = true;
        let tx = |raw: i16| apply_calibration(RawAxes([raw, 0, 0, 0, 0, 0]), &c).translation.x;
        assert_eq!(tx(10), 0.0);
        assert_eq!(tx(-10), 0.0);
        assert!((tx(55) + 0.5).abs() < 1e-6, "inverted, rescaled past the dead zone: {}", tx(55));
        assert!((tx(-100) - 1.0).abs() < 1e-6);
        assert!(tx(11).abs() < 0.02, "continuous at the dead-zone edge");
        assert!((tx(i16::MAX) - -1.0).abs() < 1e-6, "clamped to full deflection");
    }

    #[test]
    fn curve_and_sensitivity() {
        let mut c = linear();
        c.curve_exponent = 2.0;
        c.sensitivity = 2.0;
        c.axes[4].sensitivity = 0.5;
        let out = apply_calibration(RawAxes([50, 0, 0, 0, -50, 0]), &c);
        assert!((out.translation.x - 0.5).abs() < 1e-6, "0.5² × 2 = {}", out.translation.x);
        assert!((out.rotation.y + 0.25).abs() < 1e-6, "−0.5² × 2 × 0.5 = {}", out.rotation.y);
    }

    #[test]
    fn dominant_axis_modes() {
        let mut c = linear();
        let raw = RawAxes([30, -60, 10, 20, 0, -70]);
        assert_eq!(apply_calibration(raw, &c).to_array().iter().filter(|v| **v != 0.0).count(), 5);
        c.dominant_axis = DominantAxis::Single;
        let single = apply_calibration(raw, &c).to_array();
        assert_eq!(single, [0.0, 0.0, 0.0, 0.0, 0.0, -0.7]);
        c.dominant_axis = DominantAxis::PerGroup;
        let per_group = apply_calibration(raw, &c).to_array();
        assert_eq!(per_group, [0.0, -0.6, 0.0, 0.0, 0.0, -0.7]);
    }

    #[test]
    fn a_partial_file_layers_over_the_shipped_defaults() {
        let text =
            "dead_zone = 0.2\ndominant_axis = \"single\"\n[axes]\ntx = { from = \"x\", invert = true }\n";
        let c = SpaceMouseCalibration::parse(text, "mine.toml").unwrap();
        let shipped = SpaceMouseCalibration::shipped();
        assert_eq!(c.dead_zone, 0.2);
        assert_eq!(c.dominant_axis, DominantAxis::Single);
        assert!(c.axes[0].invert);
        assert_eq!(c.axes[1..], shipped.axes[1..]);
        assert_eq!((c.full_scale, c.curve_exponent), (shipped.full_scale, shipped.curve_exponent));
    }

    #[test]
    fn unknown_keys_are_refused_with_line_and_column() {
        let (path, line, column, message) = invalid(
            SpaceMouseCalibration::parse("dead_zone = 0.1\ndeadzone = 0.2\n", "mine.toml").unwrap_err(),
        );
        assert_eq!((path.as_str(), line, column), ("mine.toml", 2, 1));
        assert!(message.contains("deadzone"), "{message}");

        let text = "[axes]\ntx = { from = \"x\", inverted = true }\n";
        let (_, line, _, message) = invalid(SpaceMouseCalibration::parse(text, "mine.toml").unwrap_err());
        assert_eq!(line, 2);
        assert!(message.contains("inverted"), "{message}");

        let (_, line, column, message) =
            invalid(SpaceMouseCalibration::parse("[axes]\nty = { from = \"w\" }\n", "m.toml").unwrap_err());
        assert_eq!(line, 2, "{message}");
        assert!(column > 1 && message.contains('w'), "{column} {message}");
    }

    #[test]
    fn out_of_range_values_name_the_place() {
        let text = "full_scale = 350\n\ncurve_exponent = 9.0\n";
        let e = SpaceMouseCalibration::parse(text, "calib.toml").unwrap_err();
        assert_eq!(e.to_string(), "calib.toml:3:18: `curve_exponent` must be between 0.2 and 5, not 9");
        let text = "[axes]\nrz = { from = \"rz\", sensitivity = -1.0 }\n";
        let (_, line, _, message) = invalid(SpaceMouseCalibration::parse(text, "c.toml").unwrap_err());
        assert_eq!(line, 2);
        assert!(message.contains("axes.rz.sensitivity"), "{message}");
    }

    #[test]
    fn one_raw_axis_may_not_feed_two_outputs() {
        let text = "[axes]\ntx = { from = \"x\" }\nty = { from = \"x\" }\n";
        let (_, line, _, message) = invalid(SpaceMouseCalibration::parse(text, "c.toml").unwrap_err());
        assert_eq!(line, 3);
        assert!(message.contains("`x` drives both `tx` and `ty`"), "{message}");
    }

    #[test]
    fn a_base_less_layer_must_be_complete() {
        let e = SpaceMouseCalibration::parse_layer("dead_zone = 0.1\n", "c.toml", None).unwrap_err();
        assert!(e.to_string().contains("`full_scale` is missing"), "{e}");
    }

    #[test]
    fn loading_a_missing_file_names_it() {
        let e = SpaceMouseCalibration::load(Path::new("no/such/spacemouse.toml")).unwrap_err();
        assert!(e.to_string().contains("no/such/spacemouse.toml"), "{e}");
    }

    fn calibration() -> impl Strategy<Value = SpaceMouseCalibration> {
        let axis = (any::<bool>(), 0.0f32..=100.0).prop_map(|(invert, sensitivity)| (invert, sensitivity));
        (
            1.0f32..=32767.0,
            0.0f32..=0.95,
            0.2f32..=5.0,
            0.0f32..=100.0,
            prop_oneof![Just(DominantAxis::Off), Just(DominantAxis::Single), Just(DominantAxis::PerGroup)],
            Just([RawAxis::X, RawAxis::Y, RawAxis::Z, RawAxis::Rx, RawAxis::Ry, RawAxis::Rz]).prop_shuffle(),
            proptest::array::uniform6(axis),
        )
            .prop_map(
                |(full_scale, dead_zone, curve_exponent, sensitivity, dominant_axis, from, axes)| {
                    SpaceMouseCalibration {
                        full_scale,
                        dead_zone,
                        curve_exponent,
                        sensitivity,
                        dominant_axis,
                        axes: std::array::from_fn(|i| AxisCalibration {
                            from: from[i],
                            invert: axes[i].0,
                            sensitivity: axes[i].1,
                        }),
                    }
                },
            )
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 1024,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x4341_4c49),
            ..ProptestConfig::default()
        })]

        #[test]
        fn output_is_finite_and_bounded(raw in any::<[i16; 6]>(), c in calibration()) {
            let out = apply_calibration(RawAxes(raw), &c).to_array();
            for (v, axis) in out.iter().zip(&c.axes) {
                prop_assert!(v.is_finite());
                prop_assert!(v.abs() <= axis.sensitivity * c.sensitivity * (1.0 + 1e-5), "{} {:?}", v, c);
            }
        }

        #[test]
        fn each_output_is_monotone_in_its_source(
            raw in any::<[i16; 6]>(), a in any::<i16>(), b in any::<i16>(), out in 0usize..6, c in calibration(),
        ) {
            let c = SpaceMouseCalibration { dominant_axis: DominantAxis::Off, ..c };
            let (lo, hi) = (a.min(b), a.max(b));
            let source = c.axes[out].from.index();
            let mut r = raw;
            r[source] = lo;
            let v_lo = apply_calibration(RawAxes(r), &c).to_array()[out];
            r[source] = hi;
            let v_hi = apply_calibration(RawAxes(r), &c).to_array()[out];
            if c.axes[out].invert {
                prop_assert!(v_hi <= v_lo, "{} > {}", v_hi, v_lo);
            } else {
                prop_assert!(v_hi >= v_lo, "{} < {}", v_hi, v_lo);
            }
        }

        #[test]
        fn the_dead_zone_reads_zero(raw in any::<[i16; 6]>(), c in calibration()) {
            let out = apply_calibration(RawAxes(raw), &c).to_array();
            for (v, axis) in out.iter().zip(&c.axes) {
                let deflection = f32::from(raw[axis.from.index()]).abs() / c.full_scale;
                if deflection <= c.dead_zone {
                    prop_assert_eq!(*v, 0.0);
                }
            }
        }

        #[test]
        fn single_dominant_keeps_only_the_largest(raw in any::<[i16; 6]>(), c in calibration()) {
            let c = SpaceMouseCalibration { dominant_axis: DominantAxis::Single, ..c };
            let out = apply_calibration(RawAxes(raw), &c).to_array();
            let nonzero: Vec<usize> = (0..6).filter(|&i| out[i] != 0.0).collect();
            prop_assert!(nonzero.len() <= 1);
            if let Some(&kept) = nonzero.first() {
                let mag = |i: usize| f32::from(raw[c.axes[i].from.index()]).abs().min(c.full_scale);
                prop_assert!((0..6).all(|i| mag(i) <= mag(kept)), "{:?} kept {}", raw, kept);
            }
        }
    }
}
