//! The SpaceMouse reader driven by recorded report streams (`tests/fixtures/spacemouse/`)
//! through a scripted `ReportSource`: the same `ReaderCore` a hidapi device runs, hot-plug
//! included (an unplug in the middle of a stroke, then a re-plug), and the frame side
//! (`DeskInput`) ending the stroke cleanly.

use std::collections::VecDeque;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use argile::input::calibration::SpaceMouseCalibration;
use argile::input::desk::{DeskInput, FrameInput};
use argile::input::motion::{ActionEvent, DeviceClass, InputAction, MappingTable, Rates, Target};
use argile::input::reader::{
    DeviceId, DeviceInfo, Drained, Mailbox, ReaderConfig, ReaderCore, ReaderEvent, ReaderHandle,
    ReportDevice, ReportSource, SourceError,
};
use argile::input::spacemouse::{ButtonChange, RawAxes};
use argile::math::Quat;

/// One line of a fixture.
#[derive(Clone, Debug)]
enum Item {
    Report(Vec<u8>),
    /// A read that timed out.
    Quiet,
    /// The cable is pulled: the read fails and the next enumerations do not list the device.
    Unplug,
    /// The device leaves the enumeration while its reads just time out (a backend that does
    /// not report the removal on read).
    Vanish,
}

fn load(name: &str) -> Vec<Item> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/spacemouse").join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let code = line.split_once('#').map_or(line, |(c, _)| c);
        if code.trim().is_empty() {
            continue;
        }
        let (_, rest) =
            code.split_once(':').unwrap_or_else(|| panic!("{}:{}: no time", path.display(), n + 1));
        let rest = rest.trim();
        out.push(if rest == "unplug" {
            Item::Unplug
        } else if rest.is_empty() {
            Item::Quiet
        } else {
            Item::Report(
                rest.split_whitespace()
                    .map(|b| {
                        u8::from_str_radix(b, 16)
                            .unwrap_or_else(|e| panic!("{}:{}: {e}", path.display(), n + 1))
                    })
                    .collect(),
            )
        });
    }
    out
}

/// How many enumerations an unplugged device misses before it is back.
const ABSENT_SCANS: usize = 2;

struct ScriptedDevice {
    info: DeviceInfo,
    items: VecDeque<Item>,
    listed: bool,
    absent_scans: usize,
    /// Bumped on every unplug, so a handle from before the unplug stays dead.
    generation: u32,
}

#[derive(Clone)]
struct ScriptedSource(Arc<Mutex<Vec<ScriptedDevice>>>);

impl ScriptedSource {
    fn new(scripts: Vec<(&str, Vec<Item>)>) -> Self {
        let devices = scripts
            .into_iter()
            .map(|(path, items)| ScriptedDevice {
                info: DeviceInfo { path: path.into(), name: format!("scripted {path}") },
                items: items.into(),
                listed: true,
                absent_scans: 0,
                generation: 0,
            })
            .collect();
        Self(Arc::new(Mutex::new(devices)))
    }

    fn finished(&self) -> bool {
        self.0
            .lock()
            .unwrap()
            .iter()
            .all(|d| d.items.is_empty() && (d.listed || d.absent_scans == 0 || d.absent_scans == usize::MAX))
    }
}

struct ScriptedHandle {
    source: ScriptedSource,
    index: usize,
    generation: u32,
}

impl ReportDevice for ScriptedHandle {
    fn read_report(&mut self, buf: &mut [u8], _timeout: Duration) -> Result<usize, SourceError> {
        let mut devices = self.source.0.lock().unwrap();
        let d = &mut devices[self.index];
        if d.generation != self.generation {
            return Err(SourceError("No such device".into()));
        }
        match d.items.pop_front() {
            None | Some(Item::Quiet) => Ok(0),
            Some(Item::Report(bytes)) => {
                buf[..bytes.len()].copy_from_slice(&bytes);
                Ok(bytes.len())
            }
            Some(Item::Unplug) => {
                d.listed = false;
                d.absent_scans = ABSENT_SCANS;
                d.generation += 1;
                Err(SourceError("No such device".into()))
            }
            Some(Item::Vanish) => {
                d.listed = false;
                d.absent_scans = usize::MAX;
                Ok(0)
            }
        }
    }
}

impl ReportSource for ScriptedSource {
    fn enumerate(&mut self) -> Result<Vec<DeviceInfo>, SourceError> {
        let mut devices = self.0.lock().unwrap();
        let mut out = Vec::new();
        for d in devices.iter_mut() {
            if d.listed {
                out.push(d.info.clone());
            } else if d.absent_scans != usize::MAX {
                d.absent_scans -= 1;
                d.listed = d.absent_scans == 0;
            }
        }
        Ok(out)
    }

    fn open(&mut self, device: &DeviceInfo) -> Result<Box<dyn ReportDevice>, SourceError> {
        let devices = self.0.lock().unwrap();
        let index = devices.iter().position(|d| d.info.path == device.path).unwrap();
        Ok(Box::new(ScriptedHandle { source: self.clone(), index, generation: devices[index].generation }))
    }
}

fn config() -> ReaderConfig {
    ReaderConfig {
        read_timeout: Duration::from_millis(1),
        rescan_interval: Duration::ZERO,
        event_capacity: 4096,
    }
}

/// Steps the core until the scripts are played out (plus a few idle rounds); returns every
/// drain along the way.
fn run_to_end(source: &ScriptedSource, mailbox: &Arc<Mailbox>) -> Vec<Drained> {
    let mut core = ReaderCore::new(source.clone(), config(), mailbox.clone());
    let mut drains = Vec::new();
    let mut idle = 0;
    for _ in 0..10_000 {
        core.step();
        let mut d = Drained::default();
        assert!(mailbox.drain(&mut d));
        drains.push(d);
        idle = if source.finished() { idle + 1 } else { 0 };
        if idle > 3 {
            return drains;
        }
    }
    panic!("the scripts did not play out");
}

#[test]
fn unplug_mid_stroke_is_a_loss_then_a_new_connection() {
    let source = ScriptedSource::new(vec![("hid-a", load("unplug-during-stroke.hex"))]);
    let mailbox = Arc::new(Mailbox::new(4096));
    let drains = run_to_end(&source, &mailbox);
    let events: Vec<ReaderEvent> = drains.iter().flat_map(|d| d.events.clone()).collect();
    let shape: Vec<String> = events
        .iter()
        .map(|e| match e {
            ReaderEvent::Connected { id, .. } => format!("connected {}", id.0),
            ReaderEvent::Buttons { id, change, .. } => {
                format!("buttons {} +{:b} -{:b}", id.0, change.pressed, change.released)
            }
            ReaderEvent::Lost { id, released, .. } => format!("lost {} released {released:b}", id.0),
            ReaderEvent::OpenFailed { .. } => "open failed".into(),
        })
        .collect();
    assert_eq!(
        shape,
        ["connected 1", "buttons 1 +1 -0", "lost 1 released 1", "connected 2"],
        "no button event on the new connection: its buttons start up"
    );
    let last = drains.last().unwrap();
    assert_eq!(last.dropped_events, 0);
    assert_eq!(last.states.len(), 1, "only the new connection has a state");
    let (id, state) = last.states[0];
    assert_eq!(id, DeviceId(2));
    assert_eq!(state.axes, RawAxes([-200, 0, 0, 0, 0, 0]));
    assert_eq!(state.buttons, 0);
    assert_eq!(state.rejected_reports, 1);
    // The first connection's last state, seen before the loss, had the push and the twist.
    let before_loss = drains
        .iter()
        .rev()
        .find_map(|d| d.states.iter().find(|(i, _)| *i == DeviceId(1)).map(|(_, s)| *s))
        .unwrap();
    assert_eq!(before_loss.axes, RawAxes([200, 0, 0, 10, 0, 0]));
}

#[test]
fn several_devices_and_a_silent_disappearance() {
    let mut silent = load("wireless-six-axis.hex");
    let cut = silent.len() / 2;
    silent.insert(cut, Item::Vanish);
    silent.truncate(cut + 1);
    let source = ScriptedSource::new(vec![
        ("hid-nav", load("navigator-push-and-twist.hex")),
        ("hid-wireless", silent),
        ("hid-corrupt", load("corrupt-stream.hex")),
    ]);
    let mailbox = Arc::new(Mailbox::new(4096));
    let drains = run_to_end(&source, &mailbox);
    let events: Vec<ReaderEvent> = drains.iter().flat_map(|d| d.events.clone()).collect();
    let connected: Vec<u64> =
        events.iter().filter_map(|e| matches!(e, ReaderEvent::Connected { .. }).then_some(1)).collect();
    assert_eq!(connected.len(), 3);
    let lost: Vec<&String> = events
        .iter()
        .filter_map(|e| match e {
            ReaderEvent::Lost { reason, .. } => Some(reason),
            _ => None,
        })
        .collect();
    assert_eq!(lost.len(), 1, "{events:?}");
    assert!(lost[0].contains("scripted hid-wireless") && lost[0].contains("unplugged"), "{}", lost[0]);

    let last = drains.last().unwrap();
    assert_eq!(last.states.len(), 2);
    // The corrupt stream ends as its header says; its empty read is a timeout, not a report.
    let corrupt = last.states.iter().map(|(_, s)| *s).find(|s| s.battery_percent == Some(50)).unwrap();
    assert_eq!(corrupt.axes, RawAxes([120, -40, 0, 0, 15, 0]));
    assert_eq!(corrupt.buttons, 1);
    let bad_lines = 10;
    assert_eq!(corrupt.rejected_reports, bad_lines - 1);
}

/// Feeds the scripted stream through the reader and the desk, frame by frame.
#[test]
fn the_desk_ends_the_stroke_when_the_device_is_lost() {
    let source = ScriptedSource::new(vec![("hid-a", load("unplug-during-stroke.hex"))]);
    let mailbox = Arc::new(Mailbox::new(64));
    let mut core = ReaderCore::new(source.clone(), config(), mailbox.clone());
    let mut desk =
        DeskInput::new(SpaceMouseCalibration::shipped(), MappingTable::default(), Rates::default());
    let mut actions: Vec<ActionEvent> = Vec::new();
    let mut tool_x_at_loss = None;
    let mut frame = 0;
    let mut idle = 0;
    while idle < 4 {
        core.step();
        let before = actions.len();
        let input = FrameInput {
            t_s: f64::from(frame) / 90.0,
            dt_s: 1.0 / 90.0,
            view_rotation: Quat::IDENTITY,
            gamepads: &[],
            mouse_turn: Quat::IDENTITY,
        };
        desk.update(Some(&mailbox), &input, &mut actions);
        if actions[before..].iter().any(|a| a.action == InputAction::Stroke && !a.pressed) {
            tool_x_at_loss = Some(desk.poses.get(Target::Tool).position_m.x);
            assert_eq!(desk.spacemice().count(), 0, "the lost device is forgotten in the same frame");
        }
        frame += 1;
        idle = if source.finished() { idle + 1 } else { 0 };
        assert!(frame < 10_000);
    }
    let strokes: Vec<bool> =
        actions.iter().filter(|a| a.action == InputAction::Stroke).map(|a| a.pressed).collect();
    assert_eq!(strokes, [true, false], "one stroke, begun by button 1, ended by the loss");
    assert!(actions.iter().all(|a| a.device == DeviceClass::SpaceMouse));
    let x = tool_x_at_loss.expect("the loss released the stroke");
    // The push right moved the tool right; after the re-plug a push left moves it back.
    assert!(x > 0.05, "tool x {x}");
    assert!(desk.poses.get(Target::Tool).position_m.x < x);
}

#[test]
fn the_reader_thread_forwards_a_replug_without_the_frame_loop_waiting() {
    let source = ScriptedSource::new(vec![("hid-a", load("unplug-during-stroke.hex"))]);
    let probe = source.clone();
    let reader = ReaderHandle::spawn(move || Ok(source), config()).unwrap();
    let mut seen = Vec::new();
    let mut last_state = None;
    let mut d = Drained::default();
    // A guard against a hung reader, not a timing requirement.
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        if reader.mailbox().drain(&mut d) {
            seen.extend(d.events.iter().cloned());
            if let Some(&(id, s)) = d.states.first() {
                last_state = Some((id, s));
            }
        }
        let replugged = seen.iter().any(|e| matches!(e, ReaderEvent::Connected { id: DeviceId(2), .. }));
        let settled = matches!(last_state, Some((DeviceId(2), s)) if s.axes.0[0] == -200 && probe.finished());
        if replugged && settled {
            break;
        }
        assert!(Instant::now() < deadline, "reader stalled; events so far: {seen:?}");
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(seen.contains(&ReaderEvent::Buttons {
        id: DeviceId(1),
        change: ButtonChange { pressed: 1, released: 0 },
        buttons: 1
    }));
    assert!(seen.iter().any(|e| matches!(e, ReaderEvent::Lost { id: DeviceId(1), released: 1, .. })));
    drop(reader);
}

/// A device whose node refuses the first `refusals` opens (permissions not yet set).
struct LateOpen {
    refusals: usize,
    attempts: usize,
}

impl ReportSource for LateOpen {
    fn enumerate(&mut self) -> Result<Vec<DeviceInfo>, SourceError> {
        Ok(vec![DeviceInfo { path: "hid-locked".into(), name: "locked".into() }])
    }
    fn open(&mut self, _: &DeviceInfo) -> Result<Box<dyn ReportDevice>, SourceError> {
        self.attempts += 1;
        if self.attempts <= self.refusals {
            return Err(SourceError("permission denied".into()));
        }
        let source = ScriptedSource::new(vec![("hid-locked", vec![Item::Report(vec![0x03, 0x01])])]);
        Ok(Box::new(ScriptedHandle { source, index: 0, generation: 0 }))
    }
}

#[test]
fn a_device_that_cannot_be_opened_is_reported_once_and_retried() {
    let mailbox = Arc::new(Mailbox::new(16));
    let mut core = ReaderCore::new(LateOpen { refusals: 4, attempts: 0 }, config(), mailbox.clone());
    for _ in 0..4 {
        assert!(!core.step());
    }
    let mut d = Drained::default();
    assert!(mailbox.drain(&mut d));
    assert_eq!(d.events.len(), 1);
    assert!(matches!(&d.events[0], ReaderEvent::OpenFailed { reason, .. } if reason == "permission denied"));
    assert!(core.step(), "the fifth attempt opens it");
    assert!(mailbox.drain(&mut d));
    assert!(
        matches!(d.events[..], [ReaderEvent::Connected { .. }, ReaderEvent::Buttons { buttons: 1, .. }]),
        "{:?}",
        d.events
    );
}
