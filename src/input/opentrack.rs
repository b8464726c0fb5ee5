//! Head tracking over opentrack's "UDP over network" protocol.
//!
//! Each datagram is six little-endian 64-bit floats: x, y, z in centimetres and yaw, pitch,
//! roll in degrees (default port 4242). [`parse_packet`] is the pure decoder; a
//! [`OpentrackReceiver`] thread only receives datagrams, decodes them and keeps the newest pose
//! with the time it arrived. A datagram of any other length, or holding a non-finite number, is
//! ignored and counted: it never stops the receiver.
//!
//! ```text
//!  UDP datagram ──► parse_packet ──► TrackerPose (tracker frame: metres, degrees)
//!      ──► TrackerPose::to_screen (calibrated signs, tracker → screen) ──► head Pose
//!      ──► head::HeadFilter (dropout: hold, then ease to the default eye) ──► stereo rig
//! ```
//!
//! [`OpentrackHead`] puts the three together for a frame loop: `pose()` each frame.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::head::{DropoutTimings, HeadFilter};
use crate::math::{Pose, Quat, Vec3};
use crate::scene::{ScreenCalibration, TrackerCalibration, TrackerZero};

/// opentrack's default UDP port.
pub const DEFAULT_PORT: u16 = 4242;

/// The size of one datagram: six `f64`.
pub const PACKET_BYTES: usize = 48;

/// A decoded datagram, in the tracker's own frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerPose {
    /// Position, metres (converted from the protocol's centimetres).
    pub position_m: Vec3,
    /// Yaw, pitch, roll, degrees.
    pub angles_deg: Vec3,
}

/// Why a datagram was ignored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PacketError {
    /// Fewer or more bytes than six doubles.
    #[error("an opentrack datagram is {PACKET_BYTES} bytes, not {0}")]
    WrongLength(usize),
    /// A value is NaN or infinite, or a position beyond 100 m.
    #[error("an opentrack datagram holds a non-finite or out-of-range value")]
    OutOfRange,
}

/// Decodes one datagram.
pub fn parse_packet(bytes: &[u8]) -> Result<TrackerPose, PacketError> {
    if bytes.len() != PACKET_BYTES {
        return Err(PacketError::WrongLength(bytes.len()));
    }
    let mut v = [0.0f64; 6];
    for (value, chunk) in v.iter_mut().zip(bytes.chunks_exact(8)) {
        let mut b = [0u8; 8];
        b.copy_from_slice(chunk);
        *value = f64::from_le_bytes(b);
    }
    let position_ok = v[..3].iter().all(|c| c.is_finite() && c.abs() <= 10_000.0);
    let angles_ok = v[3..].iter().all(|a| a.is_finite() && a.abs() <= 100_000.0);
    if !(position_ok && angles_ok) {
        return Err(PacketError::OutOfRange);
    }
    Ok(TrackerPose {
        position_m: Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32) * 0.01,
        angles_deg: Vec3::new(v[3] as f32, v[4] as f32, v[5] as f32),
    })
}

/// Encodes a pose as opentrack sends it (x, y, z in centimetres; yaw, pitch, roll in degrees).
pub fn encode_packet(position_cm: [f64; 3], angles_deg: [f64; 3]) -> [u8; PACKET_BYTES] {
    let mut out = [0u8; PACKET_BYTES];
    for (chunk, v) in out.chunks_exact_mut(8).zip(position_cm.iter().chain(&angles_deg)) {
        chunk.copy_from_slice(&v.to_le_bytes());
    }
    out
}

impl TrackerPose {
    /// The head's pose in screen space: the calibration's signs applied, then the tracker's
    /// frame placed in the screen's, its zero at the default eye `default_eye_m` (a tracker
    /// centred on the viewer's head, [`TrackerZero::Centred`]) or at the tracker's origin
    /// ([`TrackerZero::Origin`]). Yaw turns about the tracker's +Y, pitch about +X, roll about
    /// +Z, applied in that order (yaw outermost).
    pub fn to_screen(&self, calibration: &TrackerCalibration, default_eye_m: Vec3) -> Pose {
        let p = self.position_m * calibration.position_signs;
        let [yaw, pitch, roll] = (self.angles_deg * calibration.angle_signs).to_array().map(f32::to_radians);
        let local = Quat::from_euler(glam::EulerRot::YXZ, yaw, pitch, roll);
        let frame = calibration.to_screen;
        let zero = match calibration.zero {
            TrackerZero::Centred => default_eye_m,
            TrackerZero::Origin => frame.position_m,
        };
        Pose { position_m: zero + frame.rotation * p, rotation: (frame.rotation * local).normalize() }
    }

    /// This pose as seen from `zero`, the pose the viewer recentred on: positions and angles
    /// less `zero`'s.
    pub fn relative_to(&self, zero: &TrackerPose) -> TrackerPose {
        TrackerPose {
            position_m: self.position_m - zero.position_m,
            angles_deg: self.angles_deg - zero.angles_deg,
        }
    }
}

/// The newest decoded pose and when it arrived.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Received {
    /// The pose.
    pub pose: TrackerPose,
    /// When its datagram arrived.
    pub at: Instant,
    /// How many valid datagrams had arrived, this one included.
    pub sequence: u64,
}

/// Datagram counters since the receiver started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PacketCounts {
    /// Valid datagrams.
    pub accepted: u64,
    /// Datagrams ignored for their length.
    pub wrong_length: u64,
    /// Datagrams ignored for a non-finite or out-of-range value.
    pub out_of_range: u64,
}

impl PacketCounts {
    /// All ignored datagrams.
    pub fn malformed(&self) -> u64 {
        self.wrong_length + self.out_of_range
    }
}

#[derive(Debug, Default)]
struct Shared {
    latest: Mutex<Option<Received>>,
    accepted: AtomicU64,
    wrong_length: AtomicU64,
    out_of_range: AtomicU64,
    stop: AtomicBool,
}

/// A thread receiving opentrack datagrams on a UDP socket. Dropping it stops and joins the
/// thread (within [`OpentrackReceiver::POLL`]).
#[derive(Debug)]
pub struct OpentrackReceiver {
    shared: Arc<Shared>,
    local_addr: SocketAddr,
    thread: Option<JoinHandle<()>>,
}

impl OpentrackReceiver {
    /// How often the thread looks at its stop flag while no datagram arrives.
    pub const POLL: Duration = Duration::from_millis(50);

    /// Listens on `addr` (for example `0.0.0.0:4242`, or `127.0.0.1:0` for any free port).
    pub fn bind(addr: SocketAddr) -> std::io::Result<Self> {
        let socket = UdpSocket::bind(addr)?;
        socket.set_read_timeout(Some(Self::POLL))?;
        let local_addr = socket.local_addr()?;
        let shared = Arc::new(Shared::default());
        let thread_shared = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("opentrack".into())
            .spawn(move || receive(&socket, &thread_shared))?;
        Ok(Self { shared, local_addr, thread: Some(thread) })
    }

    /// Where it listens.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// The newest valid pose, if any arrived.
    pub fn latest(&self) -> Option<Received> {
        *self.shared.latest.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// The datagram counters.
    pub fn counts(&self) -> PacketCounts {
        PacketCounts {
            accepted: self.shared.accepted.load(Ordering::Relaxed),
            wrong_length: self.shared.wrong_length.load(Ordering::Relaxed),
            out_of_range: self.shared.out_of_range.load(Ordering::Relaxed),
        }
    }
}

impl Drop for OpentrackReceiver {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            // The thread only loops on a socket with a timeout; it cannot hold us up for long.
            let _ = t.join();
        }
    }
}

fn receive(socket: &UdpSocket, shared: &Shared) {
    // One byte more than a datagram, so an oversized datagram is seen as such, not cut.
    let mut buffer = [0u8; PACKET_BYTES + 1];
    while !shared.stop.load(Ordering::Relaxed) {
        let n = match socket.recv(&mut buffer) {
            Ok(n) => n,
            Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {
                continue
            }
            Err(e) => {
                // A transient error (an ICMP message on some systems): wait a poll and go on.
                tracing::debug!("opentrack socket: {e}");
                std::thread::sleep(OpentrackReceiver::POLL);
                continue;
            }
        };
        match parse_packet(&buffer[..n]) {
            Ok(pose) => {
                let sequence = shared.accepted.fetch_add(1, Ordering::Relaxed) + 1;
                let received = Received { pose, at: Instant::now(), sequence };
                *shared.latest.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = Some(received);
            }
            Err(PacketError::WrongLength(_)) => {
                shared.wrong_length.fetch_add(1, Ordering::Relaxed);
            }
            Err(PacketError::OutOfRange) => {
                shared.out_of_range.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
}

/// The head pose from opentrack, ready for the stereo rig each frame: the receiver, the
/// calibration's tracker → screen transform and the dropout filter together.
#[derive(Debug)]
pub struct OpentrackHead {
    receiver: OpentrackReceiver,
    filter: HeadFilter,
    tracker: TrackerCalibration,
    default_eye_m: Vec3,
    /// The tracker's pose the viewer recentred on ([`OpentrackHead::recentre`]).
    zero: Option<TrackerPose>,
    epoch: Instant,
}

impl OpentrackHead {
    /// Listens on `addr`, or on every interface at the calibration's port when `None`.
    pub fn start(calibration: &ScreenCalibration, addr: Option<SocketAddr>) -> std::io::Result<Self> {
        let tracker = calibration.tracker;
        let addr = addr.unwrap_or_else(|| SocketAddr::from(([0, 0, 0, 0], tracker.port)));
        let timings = DropoutTimings { hold_s: tracker.hold_s, ease_s: tracker.ease_s };
        Ok(Self {
            receiver: OpentrackReceiver::bind(addr)?,
            filter: HeadFilter::new(calibration.default_head(), timings),
            tracker,
            default_eye_m: calibration.default_eye_m,
            zero: None,
            epoch: Instant::now(),
        })
    }

    /// The head pose to render from now, screen space.
    pub fn pose(&mut self) -> Pose {
        let seconds = |t: Instant| t.saturating_duration_since(self.epoch).as_secs_f64();
        let (tracker, eye, zero) = (&self.tracker, self.default_eye_m, self.zero);
        let newest = self.receiver.latest().map(|r| {
            let pose = zero.map_or(r.pose, |z| r.pose.relative_to(&z));
            (pose.to_screen(tracker, eye), seconds(r.at), r.sequence)
        });
        self.filter.update(newest, seconds(Instant::now()))
    }

    /// Takes the tracker's newest pose as the viewer's centred head: from now on it maps to
    /// the default eye, looking at the screen. Returns `false` when no pose has arrived yet.
    pub fn recentre(&mut self) -> bool {
        let newest = self.receiver.latest().map(|r| r.pose);
        // The pose as the calibration reads it, less where its zero already sits.
        self.zero = newest.map(|p| match self.tracker.zero {
            TrackerZero::Centred => p,
            TrackerZero::Origin => {
                let frame = self.tracker.to_screen;
                let eye_in_tracker = frame.rotation.inverse() * (self.default_eye_m - frame.position_m);
                TrackerPose { position_m: p.position_m - eye_in_tracker * self.tracker.position_signs, ..p }
            }
        });
        self.zero.is_some()
    }

    /// Whether the tracker counts as lost (no datagram for longer than the hold time).
    pub fn lost(&self) -> bool {
        self.filter.lost(Instant::now().saturating_duration_since(self.epoch).as_secs_f64())
    }

    /// The receiver (its address and datagram counters).
    pub fn receiver(&self) -> &OpentrackReceiver {
        &self.receiver
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::ScreenCalibration;

    #[test]
    fn packets_decode_and_bad_ones_are_refused() {
        let p = parse_packet(&encode_packet([10.0, -5.0, 60.0], [15.0, -10.0, 2.5])).unwrap();
        assert!((p.position_m - Vec3::new(0.1, -0.05, 0.6)).length() < 1e-6);
        assert_eq!(p.angles_deg, Vec3::new(15.0, -10.0, 2.5));
        let good = encode_packet([0.0; 3], [0.0; 3]);
        assert_eq!(parse_packet(&good[..47]), Err(PacketError::WrongLength(47)));
        assert_eq!(parse_packet(&[]), Err(PacketError::WrongLength(0)));
        let mut long = good.to_vec();
        long.push(0);
        assert_eq!(parse_packet(&long), Err(PacketError::WrongLength(49)));
        assert_eq!(
            parse_packet(&encode_packet([f64::NAN, 0.0, 0.0], [0.0; 3])),
            Err(PacketError::OutOfRange)
        );
        assert_eq!(
            parse_packet(&encode_packet([0.0; 3], [0.0, f64::INFINITY, 0.0])),
            Err(PacketError::OutOfRange)
        );
    }

    #[test]
    fn a_tracker_pose_lands_in_screen_space_through_the_calibration() {
        let mut t = ScreenCalibration::shipped().tracker;
        let eye = ScreenCalibration::shipped().default_eye_m;
        t.zero = TrackerZero::Origin;
        t.to_screen.position_m = Vec3::new(0.0, 0.17, 0.0);
        let p = TrackerPose { position_m: Vec3::new(0.1, -0.17, 0.6), angles_deg: Vec3::new(90.0, 0.0, 0.0) };
        let pose = p.to_screen(&t, eye);
        assert!((pose.position_m - Vec3::new(0.1, 0.0, 0.6)).length() < 1e-6);
        // Yaw 90° (turned to the left) takes the head's right (+X) to the screen's −Z.
        assert!((pose.rotation * Vec3::X - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-5);
        t.position_signs = Vec3::new(-1.0, 1.0, 1.0);
        assert!((p.to_screen(&t, eye).position_m.x + 0.1).abs() < 1e-6, "a flipped axis");
        // Centred (the shipped zero): opentrack's all-zero pose is the default eye, looking
        // at the screen, wherever the tracker itself sits.
        let shipped = ScreenCalibration::shipped();
        assert_eq!(shipped.tracker.zero, TrackerZero::Centred);
        let centred =
            TrackerPose { position_m: Vec3::ZERO, angles_deg: Vec3::ZERO }.to_screen(&shipped.tracker, eye);
        assert!(
            (centred.position_m - eye).length() < 1e-6
                && centred.rotation.angle_between(Quat::IDENTITY) < 1e-6
        );
        let right = TrackerPose { position_m: Vec3::new(0.1, 0.0, 0.0), angles_deg: Vec3::ZERO };
        assert!(
            (right.to_screen(&shipped.tracker, eye).position_m - (eye + Vec3::new(0.1, 0.0, 0.0))).length()
                < 1e-6
        );
    }

    #[test]
    fn loopback_datagrams_move_the_head_tracked_views() {
        use crate::stereo::screen::to_pixel;
        use crate::stereo::{HeadTrackedRig, Placement};

        let mut calibration = ScreenCalibration::shipped();
        // A tracker at the screen's centre, axes along the screen's; a long hold, so that a slow
        // machine sees no dropout between two steps of this test.
        calibration.tracker.to_screen = Pose::default();
        calibration.tracker.zero = TrackerZero::Origin;
        calibration.tracker.hold_s = 59.0;
        let rig = HeadTrackedRig {
            screen: calibration.screen,
            placement: Placement::IDENTITY,
            interaxial_m: calibration.ipd_m,
            near_m: 0.05,
            far_m: 20.0,
        };
        let mut head = OpentrackHead::start(&calibration, Some("127.0.0.1:0".parse().unwrap())).unwrap();
        let to = head.receiver().local_addr();
        let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
        // A point 20 cm behind the screen, where the screen is 531 mm wide and 1920 px across.
        let p = Vec3::new(0.0, 0.0, -0.2);
        let column = |head: &Pose| {
            let v = rig.views(head);
            (to_pixel(&v.eyes[0], p, 1920.0, 1080.0).0 + to_pixel(&v.eyes[1], p, 1920.0, 1080.0).0) * 0.5
        };
        assert!(head.lost(), "nothing tracked yet");
        let centred = head.pose();
        assert_eq!(centred, calibration.default_head());
        assert!((column(&centred) - 960.0).abs() < 1e-3, "straight ahead of the default eye");
        // The head moves 10 cm to the right (x = 10 cm, z = 60 cm): the point, behind the
        // screen, is seen through the screen further right, by 10 cm · 20 / 80 = 25 mm.
        sender.send_to(&encode_packet([10.0, 0.0, 60.0], [0.0; 3]), to).unwrap();
        wait_for(head.receiver(), |r| r.counts().accepted == 1);
        let moved = head.pose();
        assert!(!head.lost());
        assert!((moved.position_m - Vec3::new(0.1, 0.0, 0.6)).length() < 1e-5);
        let expected = 960.0 + 0.025 / calibration.screen.width_m() * 1920.0;
        assert!((column(&moved) - expected).abs() < 0.05, "{} vs {expected}", column(&moved));
        // Garbage does not move it.
        sender.send_to(&[0xff; 48], to).unwrap();
        sender.send_to(&[1, 2, 3], to).unwrap();
        wait_for(head.receiver(), |r| r.counts().malformed() == 2);
        assert_eq!(head.pose(), moved);
        // Recentred there, the head is the default eye again; 5 cm further right, 5 cm right
        // of it.
        assert!(head.recentre());
        assert!((head.pose().position_m - calibration.default_eye_m).length() < 1e-5);
        sender.send_to(&encode_packet([15.0, 0.0, 60.0], [0.0; 3]), to).unwrap();
        wait_for(head.receiver(), |r| r.counts().accepted == 2);
        assert!(
            (head.pose().position_m - calibration.default_eye_m - Vec3::new(0.05, 0.0, 0.0)).length() < 1e-5
        );
    }

    #[test]
    fn a_centred_head_sees_the_scene_from_the_default_eye() {
        // opentrack's centred pose: an all-zero datagram. The shipped calibration's tracker
        // zero is the centred head, so the view is the default eye's, not the bezel's.
        let mut calibration = ScreenCalibration::shipped();
        calibration.tracker.hold_s = 59.0;
        let mut head = OpentrackHead::start(&calibration, Some("127.0.0.1:0".parse().unwrap())).unwrap();
        let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
        sender.send_to(&encode_packet([0.0; 3], [0.0; 3]), head.receiver().local_addr()).unwrap();
        wait_for(head.receiver(), |r| r.counts().accepted == 1);
        let pose = head.pose();
        assert!(!head.lost());
        assert!((pose.position_m - calibration.default_head().position_m).length() < 1e-6, "{pose:?}");
        assert!(pose.rotation.angle_between(calibration.default_head().rotation) < 1e-5);
    }

    fn wait_for(receiver: &OpentrackReceiver, done: impl Fn(&OpentrackReceiver) -> bool) {
        let start = Instant::now();
        while !done(receiver) {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "the receiver saw nothing: {:?}",
                receiver.counts()
            );
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    #[test]
    fn loopback_datagrams_are_received_and_bad_ones_counted() {
        let receiver = OpentrackReceiver::bind("127.0.0.1:0".parse().unwrap()).unwrap();
        let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
        let to = receiver.local_addr();
        sender.send_to(&encode_packet([1.0, 2.0, 3.0], [4.0, 5.0, 6.0])[..20], to).unwrap();
        sender.send_to(&[0u8; 60], to).unwrap();
        sender.send_to(&encode_packet([f64::NAN, 0.0, 0.0], [0.0; 3]), to).unwrap();
        sender.send_to(&[], to).unwrap();
        sender.send_to(&encode_packet([12.0, -3.0, 55.0], [10.0, 0.0, 0.0]), to).unwrap();
        wait_for(&receiver, |r| r.counts().accepted == 1 && r.counts().malformed() == 4);
        assert_eq!(receiver.counts(), PacketCounts { accepted: 1, wrong_length: 3, out_of_range: 1 });
        let latest = receiver.latest().unwrap();
        assert!((latest.pose.position_m - Vec3::new(0.12, -0.03, 0.55)).length() < 1e-6);
        assert_eq!(latest.sequence, 1);
        sender.send_to(&encode_packet([-12.0, 0.0, 70.0], [0.0; 3]), to).unwrap();
        wait_for(&receiver, |r| r.counts().accepted == 2);
        assert!((receiver.latest().unwrap().pose.position_m.x + 0.12).abs() < 1e-6, "the newest pose wins");
    }
}
