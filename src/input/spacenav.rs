//! The spacenavd alternative: a client of the daemon's UNIX-socket protocol, as a
//! [`ReportSource`] for the same reader thread as HID devices.
//!
//! Choice: on Linux, a user who already runs `spacenavd` has handed the device to the daemon
//! (it grabs the evdev node, and the hidraw node may not be readable by the user). Reading the
//! daemon's socket then serves that user without udev rules, and keeps the daemon's own axis
//! settings (`spnavrc`). Where no daemon runs, the HID path ([`super::reader::HidSource`]) reads
//! the device itself. Both feed [`super::spacemouse::SpaceMouseState`] through the same reader,
//! so calibration, mapping and hot-plug are identical: a daemon that stops is a lost device, a
//! daemon that comes back is a device plugged in again.
//!
//! Protocol (spacenavd `src/proto.h`, `src/proto_unix.c`): the daemon writes events of eight
//! 32-bit integers in the host's byte order:
//!
//! ```text
//!  [type, d0, d1, d2, d3, d4, d5, d6]
//!  type 0 motion:   d0..d5 = x, y, z, rx, ry, rz   d6 = period in ms since the last motion
//!  type 1 press:    d0 = button number (0-based)
//!  type 2 release:  d0 = button number
//!  type 3 device change, type 4 configuration change (protocol 1 only)
//!  type with the request tag 0x7faa0000 in its high bits: a reply to a request (protocol 1)
//! ```
//!
//! A client may ask for protocol 1 by writing the integer `0x7faa5500 | 1`; the daemon
//! answers with the version it accepts. Protocol 0 needs no handshake and is the default here.
//!
//! Each event becomes the HID report a device would have sent (a 13-byte six-axis report 1,
//! or a 9-byte button report 3 with the full bitmap), so nothing downstream knows where it came
//! from. Axes are passed in the daemon's order; the daemon has already applied its own axis
//! inversions and sensitivity, and the SpaceMouse calibration maps them as for a HID device.
//! Events that make no sense (unknown type, button number out of range) are counted and skipped.

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::time::Duration;

use super::reader::{DeviceInfo, ReportDevice, ReportSource, SourceError};
use super::spacemouse::{REPORT_BUTTONS, REPORT_TRANSLATION};

/// Where spacenavd listens by default.
pub const DEFAULT_SOCKET: &str = "/var/run/spnav.sock";

/// Bytes of one event or reply: eight 32-bit integers.
pub const EVENT_LEN: usize = 32;

/// The tag in the high bits of requests and replies.
pub const REQ_TAG: i32 = 0x7faa_0000;
const REQ_TAG_MASK: i32 = 0x7fff_0000;
/// The protocol-change request, before the version is or-ed in.
pub const REQ_CHANGE_PROTO: i32 = 0x7faa_5500;

/// One event from the daemon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpnavEvent {
    /// Six axes and the time since the previous motion event.
    Motion {
        /// x, y, z, rx, ry, rz as the daemon sends them.
        axes: [i32; 6],
        /// Milliseconds since the previous motion event.
        period_ms: i32,
    },
    /// A button went down.
    Press(u8),
    /// A button went up.
    Release(u8),
    /// The device behind the daemon changed (protocol 1).
    DeviceChange,
    /// The daemon's configuration changed (protocol 1).
    ConfigChange,
    /// A reply to a request (protocol 1): not an input event.
    Reply,
}

/// Why an event was not understood.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SpnavError {
    /// An event type this client does not know.
    #[error("unknown spacenavd event type {0}")]
    UnknownType(i32),
    /// A button number outside 0 to 63.
    #[error("spacenavd button number {0} is out of range")]
    BadButton(i32),
}

/// Decodes one event (host byte order). Pure; never panics.
pub fn parse_event(bytes: &[u8; EVENT_LEN]) -> Result<SpnavEvent, SpnavError> {
    let mut v = [0i32; 8];
    for (i, chunk) in bytes.chunks_exact(4).enumerate() {
        v[i] = i32::from_ne_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]);
    }
    let button = |n: i32| u8::try_from(n).ok().filter(|&b| b < 64).ok_or(SpnavError::BadButton(n));
    match v[0] {
        0 => Ok(SpnavEvent::Motion { axes: [v[1], v[2], v[3], v[4], v[5], v[6]], period_ms: v[7] }),
        1 => button(v[1]).map(SpnavEvent::Press),
        2 => button(v[1]).map(SpnavEvent::Release),
        3 => Ok(SpnavEvent::DeviceChange),
        4 => Ok(SpnavEvent::ConfigChange),
        t if t & REQ_TAG_MASK == REQ_TAG => Ok(SpnavEvent::Reply),
        t => Err(SpnavError::UnknownType(t)),
    }
}

/// Encodes an event as the daemon writes it (used by tests and tools that replay streams).
pub fn encode_event(event: &SpnavEvent) -> [u8; EVENT_LEN] {
    let v: [i32; 8] = match *event {
        SpnavEvent::Motion { axes, period_ms } => {
            [0, axes[0], axes[1], axes[2], axes[3], axes[4], axes[5], period_ms]
        }
        SpnavEvent::Press(b) => [1, b.into(), 0, 0, 0, 0, 0, 0],
        SpnavEvent::Release(b) => [2, b.into(), 0, 0, 0, 0, 0, 0],
        SpnavEvent::DeviceChange => [3, 0, 0, 0, 0, 0, 0, 0],
        SpnavEvent::ConfigChange => [4, 0, 0, 0, 0, 0, 0, 0],
        SpnavEvent::Reply => [REQ_TAG | 0x1000, 0, 0, 0, 0, 0, 0, 0],
    };
    let mut out = [0u8; EVENT_LEN];
    for (i, x) in v.iter().enumerate() {
        out[4 * i..4 * i + 4].copy_from_slice(&x.to_ne_bytes());
    }
    out
}

/// The HID report equivalent to `event`, given the button bitmap (updated for presses and
/// releases); `None` for events that carry no input. Returns the report length written.
pub fn event_to_report(event: &SpnavEvent, buttons: &mut u64, out: &mut [u8; 13]) -> Option<usize> {
    match *event {
        SpnavEvent::Motion { axes, .. } => {
            out[0] = REPORT_TRANSLATION;
            for (i, a) in axes.iter().enumerate() {
                let v = (*a).clamp(i16::MIN.into(), i16::MAX.into()) as i16;
                out[1 + 2 * i..3 + 2 * i].copy_from_slice(&v.to_le_bytes());
            }
            Some(13)
        }
        SpnavEvent::Press(b) | SpnavEvent::Release(b) => {
            let bit = 1u64 << b;
            if matches!(event, SpnavEvent::Press(_)) {
                *buttons |= bit;
            } else {
                *buttons &= !bit;
            }
            out[0] = REPORT_BUTTONS;
            out[1..9].copy_from_slice(&buttons.to_le_bytes());
            Some(9)
        }
        SpnavEvent::DeviceChange | SpnavEvent::ConfigChange | SpnavEvent::Reply => None,
    }
}

/// Which protocol to speak.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Protocol {
    /// Events only, no handshake (every daemon version).
    V0,
    /// Ask for protocol 1 (device and configuration change events); falls back to 0 if the
    /// daemon does not answer within the read timeout.
    V1,
}

/// The daemon as a source of SpaceMouse reports: present while its socket accepts
/// connections.
#[derive(Debug)]
pub struct SpacenavSource {
    socket: PathBuf,
    protocol: Protocol,
}

impl SpacenavSource {
    /// A source reading the daemon listening at `socket` (usually [`DEFAULT_SOCKET`]).
    pub fn new(socket: impl Into<PathBuf>, protocol: Protocol) -> Self {
        Self { socket: socket.into(), protocol }
    }

    /// Whether a socket file exists at `path` (a daemon may be listening).
    pub fn socket_present(path: &Path) -> bool {
        use std::os::unix::fs::FileTypeExt;
        std::fs::metadata(path).is_ok_and(|m| m.file_type().is_socket())
    }
}

/// An open connection to the daemon.
#[derive(Debug)]
pub struct SpacenavDevice {
    stream: UnixStream,
    pending: [u8; EVENT_LEN],
    filled: usize,
    buttons: u64,
    /// The protocol the daemon accepted.
    pub protocol: i32,
    /// Events skipped as not understood.
    pub rejected_events: u64,
}

impl SpacenavDevice {
    /// Connects to the daemon at `socket`, asking for `protocol`.
    pub fn connect(socket: &Path, protocol: Protocol) -> Result<Self, SourceError> {
        let at = |e: std::io::Error| SourceError(format!("spacenavd at {}: {e}", socket.display()));
        let mut stream = UnixStream::connect(socket).map_err(at)?;
        let mut device = Self {
            stream: stream.try_clone().map_err(at)?,
            pending: [0; EVENT_LEN],
            filled: 0,
            buttons: 0,
            protocol: 0,
            rejected_events: 0,
        };
        if protocol == Protocol::V1 {
            stream.write_all(&(REQ_CHANGE_PROTO | 1).to_ne_bytes()).map_err(at)?;
            stream.set_read_timeout(Some(Duration::from_millis(200))).map_err(at)?;
            let mut answer = [0u8; 4];
            match stream.read_exact(&mut answer) {
                Ok(()) => device.protocol = i32::from_ne_bytes(answer) & 0xff,
                // An old daemon does not answer: it speaks protocol 0.
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                Err(e) => return Err(at(e)),
            }
        }
        Ok(device)
    }

    /// Reads until one whole event is in, or the timeout passes (`Ok(None)`).
    fn next_event(&mut self, timeout: Duration) -> Result<Option<[u8; EVENT_LEN]>, SourceError> {
        // A zero timeout would mean "block forever" to the socket.
        let timeout = timeout.max(Duration::from_millis(1));
        self.stream.set_read_timeout(Some(timeout)).map_err(|e| SourceError(format!("spacenavd: {e}")))?;
        while self.filled < EVENT_LEN {
            match self.stream.read(&mut self.pending[self.filled..]) {
                Ok(0) => return Err(SourceError("spacenavd closed the connection".into())),
                Ok(n) => self.filled += n,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => return Ok(None),
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(SourceError(format!("spacenavd: {e}"))),
            }
        }
        self.filled = 0;
        Ok(Some(self.pending))
    }
}

impl ReportDevice for SpacenavDevice {
    fn read_report(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, SourceError> {
        let Some(bytes) = self.next_event(timeout)? else { return Ok(0) };
        let event = match parse_event(&bytes) {
            Ok(e) => e,
            Err(e) => {
                self.rejected_events += 1;
                tracing::debug!("{e}");
                return Ok(0);
            }
        };
        let mut report = [0u8; 13];
        match event_to_report(&event, &mut self.buttons, &mut report) {
            Some(n) if n <= buf.len() => {
                buf[..n].copy_from_slice(&report[..n]);
                Ok(n)
            }
            _ => Ok(0),
        }
    }
}

impl ReportSource for SpacenavSource {
    fn enumerate(&mut self) -> Result<Vec<DeviceInfo>, SourceError> {
        Ok(if Self::socket_present(&self.socket) {
            vec![DeviceInfo {
                path: self.socket.display().to_string(),
                name: "SpaceMouse (spacenavd)".into(),
            }]
        } else {
            Vec::new()
        })
    }

    fn open(&mut self, _device: &DeviceInfo) -> Result<Box<dyn ReportDevice>, SourceError> {
        Ok(Box::new(SpacenavDevice::connect(&self.socket, self.protocol)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::spacemouse::{parse_report, RawAxes, SpaceMouseEvent};
    use proptest::prelude::*;

    #[test]
    fn events_round_trip_and_become_hid_reports() {
        let motion = SpnavEvent::Motion { axes: [10, -20, 30, -40, 50, 40000], period_ms: 16 };
        assert_eq!(parse_event(&encode_event(&motion)), Ok(motion));
        let mut buttons = 0;
        let mut r = [0u8; 13];
        let n = event_to_report(&motion, &mut buttons, &mut r).unwrap();
        assert_eq!(
            parse_report(&r[..n]),
            Ok(SpaceMouseEvent::Motion(RawAxes([10, -20, 30, -40, 50, i16::MAX])))
        );
        let n = event_to_report(&SpnavEvent::Press(1), &mut buttons, &mut r).unwrap();
        assert_eq!(parse_report(&r[..n]), Ok(SpaceMouseEvent::Buttons(0b10)));
        let n = event_to_report(&SpnavEvent::Press(40), &mut buttons, &mut r).unwrap();
        assert_eq!(parse_report(&r[..n]), Ok(SpaceMouseEvent::Buttons(0b10 | 1 << 40)));
        let n = event_to_report(&SpnavEvent::Release(1), &mut buttons, &mut r).unwrap();
        assert_eq!(parse_report(&r[..n]), Ok(SpaceMouseEvent::Buttons(1 << 40)));
        assert_eq!(event_to_report(&SpnavEvent::ConfigChange, &mut buttons, &mut r), None);
    }

    #[test]
    fn nonsense_is_an_error() {
        let mut b = encode_event(&SpnavEvent::Press(0));
        b[4..8].copy_from_slice(&64i32.to_ne_bytes());
        assert_eq!(parse_event(&b), Err(SpnavError::BadButton(64)));
        b[4..8].copy_from_slice(&(-1i32).to_ne_bytes());
        assert_eq!(parse_event(&b), Err(SpnavError::BadButton(-1)));
        b[0..4].copy_from_slice(&9i32.to_ne_bytes());
        assert_eq!(parse_event(&b), Err(SpnavError::UnknownType(9)));
        assert_eq!(parse_event(&encode_event(&SpnavEvent::Reply)), Ok(SpnavEvent::Reply));
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 256,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x7370_6e76),
            ..ProptestConfig::default()
        })]

        /// Any 32 bytes decode or are refused, and what decodes gives a valid report or none.
        #[test]
        fn any_bytes_decode_or_are_refused(bytes in any::<[u8; 32]>(), buttons in any::<u64>()) {
            if let Ok(event) = parse_event(&bytes) {
                let mut b = buttons;
                let mut r = [0u8; 13];
                if let Some(n) = event_to_report(&event, &mut b, &mut r) {
                    prop_assert!(parse_report(&r[..n]).is_ok());
                }
            }
        }
    }
}
