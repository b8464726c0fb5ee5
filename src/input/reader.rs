//! The SpaceMouse reader: a thread that opens every SpaceMouse it finds, reads their reports
//! with a timeout and hands the frame loop the newest state through a [`Mailbox`].
//!
//! ```text
//!  reader thread                                         frame loop
//!  ┌──────────────────────────────────────────┐         ┌──────────────────────────────┐
//!  │ every rescan_interval: source.enumerate() │         │ mailbox.drain(&mut drained)   │
//!  │   new path ─► source.open ─► Connected    │         │   (try_lock: never waits)     │
//!  │   path gone ─────────────► Lost           │ Mailbox │   events in order, then the   │
//!  │ each open device: read_report(timeout)    │ ──────► │   newest state of every       │
//!  │   bytes ─► SpaceMouseState::feed          │         │   device                      │
//!  │   error ─► Lost, forget the device        │         └──────────────────────────────┘
//!  └──────────────────────────────────────────┘
//! ```
//!
//! Contract:
//! - The thread body ([`ReaderCore::step`]) is driven by a [`ReportSource`]: [`HidSource`]
//!   for real devices (hidapi), [`crate::input::spacenav::SpacenavSource`] for the spacenavd
//!   daemon, and recorded streams in tests. Nothing device-specific happens past the source:
//!   every report goes through [`SpaceMouseState::feed`].
//! - The mailbox is bounded and the newest state wins: axes are a per-device snapshot that each
//!   report overwrites; discrete events (connect, buttons, loss) queue up to a capacity, beyond
//!   which the oldest is dropped and counted. The frame loop never blocks on the reader: a
//!   drain that finds the lock held returns nothing and the next frame gets the newer state.
//! - Hot-plug: a device that errors on read, or that a rescan no longer lists, is reported
//!   [`ReaderEvent::Lost`] (its buttons count as released, so a stroke in progress ends
//!   cleanly) and forgotten; the next rescan that lists it opens it again under a new id.
//! - Malformed reports are counted in the device's state and never stop the reader.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::spacemouse::{ButtonChange, SpaceMouseState};

/// Longest report a SpaceMouse sends, with its id, plus slack for unknown reports.
pub const MAX_REPORT_LEN: usize = 64;

/// A device the source can open.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceInfo {
    /// Where the device is (HID path, socket path); identifies it across rescans.
    pub path: String,
    /// Its name, for the user.
    pub name: String,
}

/// A source or device failure, in words for the user.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct SourceError(pub String);

/// One open device.
pub trait ReportDevice: Send {
    /// Reads one input report (report id first) into `buf`, waiting at most `timeout`.
    /// `Ok(0)` means nothing arrived in time; an error means the device is gone.
    fn read_report(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, SourceError>;
}

/// Where SpaceMouse devices come from.
pub trait ReportSource: Send {
    /// The devices present now.
    fn enumerate(&mut self) -> Result<Vec<DeviceInfo>, SourceError>;
    /// Opens one of them.
    fn open(&mut self, device: &DeviceInfo) -> Result<Box<dyn ReportDevice>, SourceError>;
}

/// A device's identity for one connection: a re-plugged device gets a new id.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DeviceId(pub u64);

/// A discrete event from the reader.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ReaderEvent {
    /// A device was opened.
    Connected {
        /// Its id for this connection.
        id: DeviceId,
        /// What and where it is.
        info: DeviceInfo,
    },
    /// Buttons went down or up.
    Buttons {
        /// The device.
        id: DeviceId,
        /// What changed.
        change: ButtonChange,
        /// The full bitmap after the change.
        buttons: u64,
    },
    /// A device went away (unplugged, or an error); its buttons count as released.
    Lost {
        /// The device.
        id: DeviceId,
        /// The buttons that were down, now released.
        released: u64,
        /// Why, in words.
        reason: String,
    },
    /// A listed device could not be opened (reported once until it opens or leaves the list;
    /// it is retried at every rescan).
    OpenFailed {
        /// The device.
        info: DeviceInfo,
        /// Why (often: permissions of the hidraw node).
        reason: String,
    },
}

/// What a drain hands the frame loop.
#[derive(Clone, Debug, Default)]
pub struct Drained {
    /// Discrete events since the last drain, oldest first.
    pub events: Vec<ReaderEvent>,
    /// The newest state of every connected device.
    pub states: Vec<(DeviceId, SpaceMouseState)>,
    /// Events dropped because the queue was full, since the reader started.
    pub dropped_events: u64,
}

#[derive(Debug, Default)]
struct Inbox {
    events: VecDeque<ReaderEvent>,
    states: Vec<(DeviceId, SpaceMouseState)>,
    dropped_events: u64,
}

/// The bounded hand-over between the reader thread and the frame loop; the newest state wins.
#[derive(Debug)]
pub struct Mailbox {
    inbox: Mutex<Inbox>,
    capacity: usize,
}

impl Mailbox {
    /// A mailbox queueing at most `capacity` discrete events (at least 1).
    pub fn new(capacity: usize) -> Self {
        Self { inbox: Mutex::new(Inbox::default()), capacity: capacity.max(1) }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inbox> {
        // A panic elsewhere while holding the lock leaves plain data behind; keep using it.
        self.inbox.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Queues an event; when full, drops the oldest. A loss removes the device's state.
    pub fn push_event(&self, event: ReaderEvent) {
        let mut inbox = self.lock();
        if let ReaderEvent::Lost { id, .. } = event {
            inbox.states.retain(|(d, _)| *d != id);
        }
        if inbox.events.len() == self.capacity {
            inbox.events.pop_front();
            inbox.dropped_events += 1;
        }
        inbox.events.push_back(event);
    }

    /// Replaces the state of device `id` with a newer one.
    pub fn publish_state(&self, id: DeviceId, state: SpaceMouseState) {
        let mut inbox = self.lock();
        match inbox.states.iter_mut().find(|(d, _)| *d == id) {
            Some(slot) => slot.1 = state,
            None => inbox.states.push((id, state)),
        }
    }

    /// Moves the queued events and copies the newest states into `out` (its buffers are
    /// reused). Never waits: returns `false`, leaving `out` empty, if the reader holds the lock.
    pub fn drain(&self, out: &mut Drained) -> bool {
        out.events.clear();
        out.states.clear();
        let mut inbox = match self.inbox.try_lock() {
            Ok(g) => g,
            Err(std::sync::TryLockError::Poisoned(p)) => p.into_inner(),
            Err(std::sync::TryLockError::WouldBlock) => return false,
        };
        out.events.extend(inbox.events.drain(..));
        out.states.extend_from_slice(&inbox.states);
        out.dropped_events = inbox.dropped_events;
        true
    }
}

/// Timing of the reader.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReaderConfig {
    /// Longest wait for one device's report (split among open devices).
    pub read_timeout: Duration,
    /// Time between two enumerations (hot-plug).
    pub rescan_interval: Duration,
    /// Discrete events the mailbox holds.
    pub event_capacity: usize,
}

impl Default for ReaderConfig {
    /// 10 ms reads (a device sends about 60 reports a second per axis group), a rescan every
    /// second, 256 queued events.
    fn default() -> Self {
        Self {
            read_timeout: Duration::from_millis(10),
            rescan_interval: Duration::from_secs(1),
            event_capacity: 256,
        }
    }
}

struct OpenDevice {
    id: DeviceId,
    info: DeviceInfo,
    device: Box<dyn ReportDevice>,
    state: SpaceMouseState,
}

/// The reader's body, one [`step`](Self::step) at a time; the thread only loops over it.
pub struct ReaderCore<S: ReportSource> {
    source: S,
    config: ReaderConfig,
    mailbox: Arc<Mailbox>,
    open: Vec<OpenDevice>,
    failed: Vec<String>,
    next_id: u64,
    last_scan: Option<Instant>,
    buf: [u8; MAX_REPORT_LEN],
}

impl<S: ReportSource> std::fmt::Debug for ReaderCore<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReaderCore")
            .field("open", &self.open.iter().map(|d| (d.id, &d.info.path)).collect::<Vec<_>>())
            .field("config", &self.config)
            .finish_non_exhaustive()
    }
}

impl<S: ReportSource> ReaderCore<S> {
    /// A reader over `source`, posting to `mailbox`.
    pub fn new(source: S, config: ReaderConfig, mailbox: Arc<Mailbox>) -> Self {
        Self {
            source,
            config,
            mailbox,
            open: Vec::new(),
            failed: Vec::new(),
            next_id: 1,
            last_scan: None,
            buf: [0; MAX_REPORT_LEN],
        }
    }

    /// The devices open now.
    pub fn open_devices(&self) -> impl Iterator<Item = (DeviceId, &DeviceInfo)> {
        self.open.iter().map(|d| (d.id, &d.info))
    }

    /// One round: rescan if due, then one read from each open device. Returns whether any
    /// device is open (when none is, the caller should wait before the next step).
    pub fn step(&mut self) -> bool {
        let due = self.last_scan.is_none_or(|t| t.elapsed() >= self.config.rescan_interval);
        if due {
            self.last_scan = Some(Instant::now());
            self.rescan();
        }
        let share = self.config.read_timeout / (self.open.len().max(1) as u32);
        let mut i = 0;
        while i < self.open.len() {
            let d = &mut self.open[i];
            match d.device.read_report(&mut self.buf, share) {
                Ok(0) => i += 1,
                Ok(n) => {
                    let n = n.min(self.buf.len());
                    if let Ok(change) = d.state.feed(&self.buf[..n]) {
                        if change != ButtonChange::default() {
                            let event = ReaderEvent::Buttons { id: d.id, change, buttons: d.state.buttons };
                            self.mailbox.push_event(event);
                        }
                    }
                    self.mailbox.publish_state(d.id, d.state);
                    i += 1;
                }
                Err(e) => self.lose(i, e.0),
            }
        }
        !self.open.is_empty()
    }

    fn lose(&mut self, index: usize, reason: String) {
        let d = self.open.swap_remove(index);
        self.mailbox.push_event(ReaderEvent::Lost { id: d.id, released: d.state.buttons, reason });
    }

    fn rescan(&mut self) {
        let found = match self.source.enumerate() {
            Ok(f) => f,
            // Enumeration failing says nothing about the open devices: keep reading them.
            Err(_) => return,
        };
        let mut i = 0;
        while i < self.open.len() {
            if found.iter().any(|f| f.path == self.open[i].info.path) {
                i += 1;
            } else {
                self.lose(i, format!("{} was unplugged", self.open[i].info.name));
            }
        }
        self.failed.retain(|p| found.iter().any(|f| &f.path == p));
        for info in found {
            if self.open.iter().any(|d| d.info.path == info.path) {
                continue;
            }
            // A failed open is retried at every rescan (udev often sets a new node's
            // permissions a moment after it appears) but reported only once.
            match self.source.open(&info) {
                Ok(device) => {
                    self.failed.retain(|p| *p != info.path);
                    let id = DeviceId(self.next_id);
                    self.next_id += 1;
                    self.mailbox.push_event(ReaderEvent::Connected { id, info: info.clone() });
                    self.open.push(OpenDevice { id, info, device, state: SpaceMouseState::default() });
                }
                Err(e) if !self.failed.contains(&info.path) => {
                    self.failed.push(info.path.clone());
                    self.mailbox.push_event(ReaderEvent::OpenFailed { info, reason: e.0 });
                }
                Err(_) => {}
            }
        }
    }
}

/// The running reader thread; dropping it stops and joins the thread.
#[derive(Debug)]
pub struct ReaderHandle {
    mailbox: Arc<Mailbox>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl ReaderHandle {
    /// Starts a reader thread over the source `make_source` builds on that thread (so a
    /// source need not be movable between threads once built, as hidapi's context is not).
    pub fn spawn<S, F>(make_source: F, config: ReaderConfig) -> std::io::Result<Self>
    where
        S: ReportSource + 'static,
        F: FnOnce() -> Result<S, SourceError> + Send + 'static,
    {
        let mailbox = Arc::new(Mailbox::new(config.event_capacity));
        let stop = Arc::new(AtomicBool::new(false));
        let (m, s) = (mailbox.clone(), stop.clone());
        let thread = std::thread::Builder::new().name("argile-spacemouse".into()).spawn(move || {
            let source = match make_source() {
                Ok(source) => source,
                Err(e) => {
                    tracing::warn!("SpaceMouse reader not started: {e}");
                    return;
                }
            };
            let mut core = ReaderCore::new(source, config, m);
            while !s.load(Ordering::Relaxed) {
                if !core.step() {
                    // Nothing open: wait a read's time rather than spin on enumeration.
                    std::thread::sleep(config.read_timeout);
                }
            }
        })?;
        Ok(Self { mailbox, stop, thread: Some(thread) })
    }

    /// The mailbox the frame loop drains.
    pub fn mailbox(&self) -> &Arc<Mailbox> {
        &self.mailbox
    }
}

impl Drop for ReaderHandle {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            // The thread wakes within one read timeout; a panic in it has been logged already.
            let _ = t.join();
        }
    }
}

/// SpaceMice over hidapi (Linux hidraw).
pub struct HidSource {
    api: hidapi::HidApi,
}

impl std::fmt::Debug for HidSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("HidSource")
    }
}

impl HidSource {
    /// Opens the HID library.
    pub fn new() -> Result<Self, SourceError> {
        hidapi::HidApi::new()
            .map(|api| Self { api })
            .map_err(|e| SourceError(format!("cannot open the HID library: {e}")))
    }
}

struct HidReportDevice(hidapi::HidDevice);

impl ReportDevice for HidReportDevice {
    fn read_report(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, SourceError> {
        let ms = i32::try_from(timeout.as_millis()).unwrap_or(i32::MAX);
        self.0.read_timeout(buf, ms).map_err(|e| SourceError(format!("read failed: {e}")))
    }
}

impl ReportSource for HidSource {
    fn enumerate(&mut self) -> Result<Vec<DeviceInfo>, SourceError> {
        self.api.refresh_devices().map_err(|e| SourceError(format!("cannot list HID devices: {e}")))?;
        let mut out: Vec<DeviceInfo> = Vec::new();
        for d in self.api.device_list() {
            if super::is_spacemouse(d.vendor_id(), d.product_id(), d.usage_page(), d.usage()) {
                let path = d.path().to_string_lossy().into_owned();
                if out.iter().all(|o| o.path != path) {
                    out.push(DeviceInfo { path, name: super::hid_device_name(d) });
                }
            }
        }
        Ok(out)
    }

    fn open(&mut self, device: &DeviceInfo) -> Result<Box<dyn ReportDevice>, SourceError> {
        let path = std::ffi::CString::new(device.path.as_bytes())
            .map_err(|_| SourceError(format!("{}: the device path holds a NUL byte", device.name)))?;
        let dev = self.api.open_path(&path).map_err(|e| {
            SourceError(format!(
                "cannot open {} at {}: {e} (check the permissions of the hidraw node, for example with a udev rule)",
                device.name, device.path
            ))
        })?;
        Ok(Box::new(HidReportDevice(dev)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(x: i16) -> SpaceMouseState {
        let mut s = SpaceMouseState::default();
        s.axes.0[0] = x;
        s
    }

    #[test]
    fn newest_state_wins_and_the_queue_keeps_the_newest_events() {
        let m = Mailbox::new(4);
        for x in 0..10 {
            m.publish_state(DeviceId(1), state(x));
        }
        m.publish_state(DeviceId(2), state(-5));
        for n in 0..10u64 {
            let change = ButtonChange { pressed: 1 << n, released: 0 };
            m.push_event(ReaderEvent::Buttons { id: DeviceId(1), change, buttons: 1 << n });
        }
        let mut d = Drained::default();
        assert!(m.drain(&mut d));
        assert_eq!(d.states, vec![(DeviceId(1), state(9)), (DeviceId(2), state(-5))]);
        assert_eq!(d.dropped_events, 6);
        let kept: Vec<u64> = d
            .events
            .iter()
            .map(|e| match e {
                ReaderEvent::Buttons { buttons, .. } => *buttons,
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(kept, [1 << 6, 1 << 7, 1 << 8, 1 << 9]);
        assert!(m.drain(&mut d) && d.events.is_empty(), "events are handed over once");
        assert_eq!(d.states.len(), 2, "states stay until the device is lost");
        m.push_event(ReaderEvent::Lost { id: DeviceId(1), released: 0, reason: "gone".into() });
        assert!(m.drain(&mut d));
        assert_eq!(d.states, vec![(DeviceId(2), state(-5))]);
    }

    #[test]
    fn a_drain_never_waits_for_the_reader() {
        let m = Mailbox::new(4);
        m.publish_state(DeviceId(1), state(3));
        let mut d = Drained::default();
        let held = m.inbox.lock().unwrap();
        assert!(!m.drain(&mut d), "the lock is held: the drain gives up at once");
        assert!(d.states.is_empty());
        drop(held);
        assert!(m.drain(&mut d));
        assert_eq!(d.states, vec![(DeviceId(1), state(3))]);
    }
}
