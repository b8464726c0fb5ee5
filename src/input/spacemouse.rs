//! SpaceMouse HID input reports: a pure parser and the state it accumulates into.
//!
//! The reader thread only reads bytes from the device and forwards them; everything it hands
//! over goes through [`parse_report`] (or [`SpaceMouseState::feed`]), which the tests drive with
//! recorded-style report streams (`tests/fixtures/spacemouse/`).
//!
//! Report layouts (hidraw hands over the report id as the first byte):
//!
//! ```text
//!  id 0x01, 7 bytes:   01 | tx lo tx hi | ty lo ty hi | tz lo tz hi          translation
//!  id 0x01, 13 bytes:  01 | tx ty tz (3 × i16 LE)     | rx ry rz (3 × i16 LE)  newer devices
//!  id 0x02, 7 bytes:   02 | rx lo rx hi | ry lo ry hi | rz lo rz hi          rotation
//!  id 0x03, 2–9 bytes: 03 | button bitmap, little-endian (bit 0 = button 1)
//!  id 0x17, 2+ bytes:  17 | battery charge in percent (wireless devices)
//! ```
//!
//! Axis values are signed 16-bit little-endian and span about ±350 counts. In the device's own
//! frame x points right, y towards the user and z down (the calibration maps them to world
//! axes). Nothing here panics on any byte string: short, over-long and unknown reports are a
//! [`ReportError`], which the caller counts and otherwise ignores.

/// Report id of translation (or, 13 bytes long, of all six axes).
pub const REPORT_TRANSLATION: u8 = 0x01;
/// Report id of rotation.
pub const REPORT_ROTATION: u8 = 0x02;
/// Report id of the button bitmap.
pub const REPORT_BUTTONS: u8 = 0x03;
/// Report id of the battery level of wireless devices.
pub const REPORT_BATTERY: u8 = 0x17;

/// Length, id included, of a three-axis report.
const THREE_AXIS_LEN: usize = 1 + 3 * 2;
/// Length, id included, of the combined six-axis report of newer devices.
const SIX_AXIS_LEN: usize = 1 + 6 * 2;
/// Most bitmap bytes a button report may carry (64 buttons).
const MAX_BUTTON_BYTES: usize = 8;

/// The six raw axes in device order: `[x, y, z, rx, ry, rz]`, in device counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct RawAxes(pub [i16; 6]);

impl RawAxes {
    /// The translation axes `[x, y, z]`.
    pub fn translation(&self) -> [i16; 3] {
        [self.0[0], self.0[1], self.0[2]]
    }

    /// The rotation axes `[rx, ry, rz]`.
    pub fn rotation(&self) -> [i16; 3] {
        [self.0[3], self.0[4], self.0[5]]
    }
}

/// What one input report says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpaceMouseEvent {
    /// Translation `[x, y, z]` (report 1, older devices).
    Translation([i16; 3]),
    /// Rotation `[rx, ry, rz]` (report 2).
    Rotation([i16; 3]),
    /// All six axes at once (report 1 of newer devices).
    Motion(RawAxes),
    /// The full button bitmap: bit `n` set while button `n + 1` is down.
    Buttons(u64),
    /// Battery charge of a wireless device, percent.
    Battery {
        /// 0 to 100.
        percent: u8,
    },
}

/// Why a report was not understood. The caller counts these and drops the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReportError {
    /// A read returned no bytes.
    #[error("empty SpaceMouse report")]
    Empty,
    /// A known report with a length its layout does not have.
    #[error("SpaceMouse report {id:#04x} is {len} bytes long; its layout has {expected}")]
    BadLength {
        /// Report id.
        id: u8,
        /// Bytes received, id included.
        len: usize,
        /// The lengths the layout allows.
        expected: &'static str,
    },
    /// A known report whose content is out of range.
    #[error("SpaceMouse report {id:#04x} holds an impossible value {value}")]
    BadValue {
        /// Report id.
        id: u8,
        /// The value.
        value: u64,
    },
    /// A report id this parser does not know.
    #[error("unknown SpaceMouse report {id:#04x} ({len} bytes)")]
    Unknown {
        /// Report id.
        id: u8,
        /// Bytes received, id included.
        len: usize,
    },
}

fn three_axes(data: &[u8]) -> [i16; 3] {
    let v = |i: usize| i16::from_le_bytes([data[2 * i], data[2 * i + 1]]);
    [v(0), v(1), v(2)]
}

/// Parses one input report (report id first, as hidraw delivers it). Pure; never panics.
pub fn parse_report(report: &[u8]) -> Result<SpaceMouseEvent, ReportError> {
    let Some((&id, data)) = report.split_first() else { return Err(ReportError::Empty) };
    let len = report.len();
    match id {
        REPORT_TRANSLATION => match len {
            THREE_AXIS_LEN => Ok(SpaceMouseEvent::Translation(three_axes(data))),
            SIX_AXIS_LEN => {
                let [x, y, z] = three_axes(&data[..6]);
                let [rx, ry, rz] = three_axes(&data[6..]);
                Ok(SpaceMouseEvent::Motion(RawAxes([x, y, z, rx, ry, rz])))
            }
            _ => Err(ReportError::BadLength { id, len, expected: "7 or 13" }),
        },
        REPORT_ROTATION => match len {
            THREE_AXIS_LEN => Ok(SpaceMouseEvent::Rotation(three_axes(data))),
            _ => Err(ReportError::BadLength { id, len, expected: "7" }),
        },
        REPORT_BUTTONS => {
            if data.is_empty() || data.len() > MAX_BUTTON_BYTES {
                return Err(ReportError::BadLength { id, len, expected: "2 to 9" });
            }
            let mut bytes = [0u8; MAX_BUTTON_BYTES];
            bytes[..data.len()].copy_from_slice(data);
            Ok(SpaceMouseEvent::Buttons(u64::from_le_bytes(bytes)))
        }
        REPORT_BATTERY => match data.first() {
            None => Err(ReportError::BadLength { id, len, expected: "at least 2" }),
            Some(&percent) if percent > 100 => Err(ReportError::BadValue { id, value: percent.into() }),
            Some(&percent) => Ok(SpaceMouseEvent::Battery { percent }),
        },
        _ => Err(ReportError::Unknown { id, len }),
    }
}

/// Buttons that went down or up with one event.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ButtonChange {
    /// Bits of buttons newly down.
    pub pressed: u64,
    /// Bits of buttons newly up.
    pub released: u64,
}

/// The latest six axes and buttons of one device, accumulated from its reports.
///
/// Older devices send translation and rotation in separate reports, so each report updates its
/// half and leaves the other as last seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpaceMouseState {
    /// The latest raw axes.
    pub axes: RawAxes,
    /// The latest button bitmap.
    pub buttons: u64,
    /// The latest battery charge, once a wireless device has reported it.
    pub battery_percent: Option<u8>,
    /// Reports understood.
    pub accepted_reports: u64,
    /// Reports dropped as malformed or unknown.
    pub rejected_reports: u64,
}

impl SpaceMouseState {
    /// Folds one parsed event into the state; says which buttons changed.
    pub fn apply(&mut self, event: &SpaceMouseEvent) -> ButtonChange {
        match *event {
            SpaceMouseEvent::Translation(t) => self.axes.0[..3].copy_from_slice(&t),
            SpaceMouseEvent::Rotation(r) => self.axes.0[3..].copy_from_slice(&r),
            SpaceMouseEvent::Motion(axes) => self.axes = axes,
            SpaceMouseEvent::Buttons(bits) => {
                let change = ButtonChange { pressed: bits & !self.buttons, released: self.buttons & !bits };
                self.buttons = bits;
                return change;
            }
            SpaceMouseEvent::Battery { percent } => self.battery_percent = Some(percent),
        }
        ButtonChange::default()
    }

    /// Parses one report as read from the device and folds it in; a bad report is counted in
    /// `rejected_reports` and leaves the state as it was.
    pub fn feed(&mut self, report: &[u8]) -> Result<ButtonChange, ReportError> {
        match parse_report(report) {
            Ok(event) => {
                self.accepted_reports += 1;
                Ok(self.apply(&event))
            }
            Err(e) => {
                self.rejected_reports += 1;
                Err(e)
            }
        }
    }

    /// Whether button `index` (0-based) is down.
    pub fn is_down(&self, index: u32) -> bool {
        index < 64 && self.buttons & (1 << index) != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn separate_translation_and_rotation_reports() {
        // 300 = 0x012c, -100 = 0xff9c, -350 = 0xfea2.
        assert_eq!(
            parse_report(&[0x01, 0x2c, 0x01, 0x9c, 0xff, 0x00, 0x00]),
            Ok(SpaceMouseEvent::Translation([300, -100, 0]))
        );
        assert_eq!(
            parse_report(&[0x02, 0x00, 0x00, 0xe2, 0xff, 0xa2, 0xfe]),
            Ok(SpaceMouseEvent::Rotation([0, -30, -350]))
        );
    }

    #[test]
    fn combined_six_axis_report_is_translation_then_rotation() {
        let mut r = vec![0x01];
        for v in [1i16, -2, 3, -4, 5, -32768] {
            r.extend_from_slice(&v.to_le_bytes());
        }
        assert_eq!(parse_report(&r), Ok(SpaceMouseEvent::Motion(RawAxes([1, -2, 3, -4, 5, -32768]))));
    }

    #[test]
    fn buttons_and_battery() {
        assert_eq!(parse_report(&[0x03, 0x01, 0x00]), Ok(SpaceMouseEvent::Buttons(1)));
        assert_eq!(parse_report(&[0x03, 0x03]), Ok(SpaceMouseEvent::Buttons(3)));
        assert_eq!(parse_report(&[0x03, 0x00, 0x00, 0x00, 0x80]), Ok(SpaceMouseEvent::Buttons(1 << 31)));
        assert_eq!(parse_report(&[0x17, 0x64]), Ok(SpaceMouseEvent::Battery { percent: 100 }));
        assert_eq!(parse_report(&[0x17, 0x65]), Err(ReportError::BadValue { id: 0x17, value: 101 }));
    }

    #[test]
    fn short_long_and_unknown_reports_are_errors() {
        assert_eq!(parse_report(&[]), Err(ReportError::Empty));
        assert!(matches!(parse_report(&[0x01, 0x00]), Err(ReportError::BadLength { id: 1, len: 2, .. })));
        assert!(matches!(parse_report(&[0x01; 8]), Err(ReportError::BadLength { id: 1, len: 8, .. })));
        assert!(matches!(parse_report(&[0x02; 13]), Err(ReportError::BadLength { id: 2, len: 13, .. })));
        assert!(matches!(parse_report(&[0x03]), Err(ReportError::BadLength { id: 3, len: 1, .. })));
        assert!(matches!(parse_report(&[0x03; 10]), Err(ReportError::BadLength { id: 3, len: 10, .. })));
        assert!(matches!(parse_report(&[0x17]), Err(ReportError::BadLength { id: 0x17, .. })));
        assert_eq!(parse_report(&[0x04, 0x01]), Err(ReportError::Unknown { id: 4, len: 2 }));
        assert_eq!(parse_report(&[0x00]), Err(ReportError::Unknown { id: 0, len: 1 }));
    }

    #[test]
    fn state_keeps_the_other_half_and_reports_button_edges() {
        let mut s = SpaceMouseState::default();
        s.feed(&[0x01, 0x0a, 0x00, 0x14, 0x00, 0x1e, 0x00]).unwrap();
        s.feed(&[0x02, 0x01, 0x00, 0x02, 0x00, 0x03, 0x00]).unwrap();
        assert_eq!(s.axes, RawAxes([10, 20, 30, 1, 2, 3]));
        s.feed(&[0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00]).unwrap();
        assert_eq!(s.axes, RawAxes([0, 0, 0, 1, 2, 3]));
        assert_eq!(s.feed(&[0x03, 0x01, 0x00]), Ok(ButtonChange { pressed: 1, released: 0 }));
        assert_eq!(s.feed(&[0x03, 0x02, 0x00]), Ok(ButtonChange { pressed: 2, released: 1 }));
        assert!(s.is_down(1) && !s.is_down(0) && !s.is_down(64));
        let before = s;
        assert!(s.feed(&[0x01, 0xff]).is_err());
        assert_eq!(s.rejected_reports, 1);
        assert_eq!(SpaceMouseState { rejected_reports: 0, ..s }, before, "a bad report changes nothing else");
        assert_eq!(s.accepted_reports, 5);
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 512,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x5350_4d53),
            ..ProptestConfig::default()
        })]

        /// Any byte string parses or is refused; accepted axis reports round-trip their values.
        #[test]
        fn any_bytes_parse_or_are_refused(bytes in proptest::collection::vec(any::<u8>(), 0..20)) {
            match parse_report(&bytes) {
                Ok(SpaceMouseEvent::Translation(t)) => {
                    prop_assert_eq!(bytes.len(), 7);
                    prop_assert_eq!(t[2].to_le_bytes(), [bytes[5], bytes[6]]);
                }
                Ok(SpaceMouseEvent::Motion(a)) => {
                    prop_assert_eq!(bytes.len(), 13);
                    prop_assert_eq!(a.0[5].to_le_bytes(), [bytes[11], bytes[12]]);
                }
                Ok(SpaceMouseEvent::Rotation(_)) => prop_assert_eq!(bytes[0], 2),
                Ok(SpaceMouseEvent::Buttons(b)) => {
                    prop_assert_eq!(bytes[0], 3);
                    prop_assert_eq!(b.to_le_bytes()[0], bytes[1]);
                }
                Ok(SpaceMouseEvent::Battery { percent }) => prop_assert!(percent <= 100),
                Err(_) => {}
            }
        }

        /// Encoding six axes in the combined layout and parsing gives them back.
        #[test]
        fn six_axes_round_trip(axes in any::<[i16; 6]>()) {
            let mut r = vec![REPORT_TRANSLATION];
            for v in axes {
                r.extend_from_slice(&v.to_le_bytes());
            }
            prop_assert_eq!(parse_report(&r), Ok(SpaceMouseEvent::Motion(RawAxes(axes))));
        }
    }
}
