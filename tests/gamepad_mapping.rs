//! The gamepad path: gilrs events inserted into gilrs' own queue and drained by `Gamepads`,
//! and the pure mapping driven with `gilrs::EventType` values, against the shipped
//! `calibration/gamepad.toml`.
//!
//! gilrs offers no constructor for a pad id or an event code outside a device; with its
//! `serde-serialize` feature both deserialize (the code's layout is the Linux one: an evdev
//! kind and code), which is how these tests name them.

use argile::input::gamepad::{ContactFeedback, GamepadCalibration, GamepadMapper, Gamepads, Rumble, Source};
use argile::input::motion::{ActionEvent, DeviceClass, InputAction};
use gilrs::ev::Code;
use gilrs::{Axis, Button, Event, EventType, GamepadId};
use serde_json::json;

fn pad(n: usize) -> GamepadId {
    serde_json::from_value(json!(n)).expect("gilrs ids deserialize with serde-serialize")
}

fn code() -> Code {
    serde_json::from_value(json!({ "kind": 3, "code": 0 })).expect("Linux event code layout")
}

fn gamepads() -> Gamepads {
    // Default filters look pads up by id and would refuse events of pads gilrs never saw.
    let gilrs = match gilrs::GilrsBuilder::new().with_default_filters(false).build() {
        Ok(g) => g,
        Err(gilrs::Error::NotImplemented(g)) => g,
        Err(e) => panic!("gilrs: {e}"),
    };
    Gamepads::with_gilrs(gilrs, GamepadCalibration::shipped())
}

fn stroke(pressed: bool) -> ActionEvent {
    ActionEvent { action: InputAction::Stroke, pressed, device: DeviceClass::Gamepad }
}

#[test]
fn events_in_gilrs_queue_drive_motion_and_actions() {
    let mut pads = gamepads();
    let (a, b) = (pad(0), pad(1));
    let insert = |pads: &mut Gamepads, id, event| pads.gilrs_mut().insert_event(Event::new(id, event));
    insert(&mut pads, a, EventType::Connected);
    insert(&mut pads, a, EventType::AxisChanged(Axis::LeftStickX, 1.0, code()));
    insert(&mut pads, a, EventType::AxisChanged(Axis::LeftStickY, 0.5, code()));
    insert(&mut pads, a, EventType::ButtonChanged(Button::RightTrigger2, 1.0, code()));
    insert(&mut pads, a, EventType::ButtonPressed(Button::South, code()));
    insert(&mut pads, b, EventType::AxisChanged(Axis::RightStickX, -1.0, code()));
    insert(&mut pads, b, EventType::ButtonPressed(Button::Select, code()));
    let mut actions = Vec::new();
    pads.poll(&mut actions);
    assert_eq!(
        actions,
        [
            stroke(true),
            ActionEvent { action: InputAction::CycleTarget, pressed: true, device: DeviceClass::Gamepad }
        ]
    );
    let motions: Vec<_> = pads.motions().collect();
    assert_eq!(motions.len(), 2);
    let m = motions.iter().find(|(id, _)| *id == a).unwrap().1;
    assert!((m.six.translation.x - 1.0).abs() < 1e-6, "full right stick is full speed right");
    assert!((m.six.translation.y - 1.0).abs() < 1e-6, "right trigger pulled: up");
    assert!(
        m.six.translation.z < -0.2 && m.six.translation.z > -0.5,
        "half forward: away, curved: {}",
        m.six.translation.z
    );
    let m = motions.iter().find(|(id, _)| *id == b).unwrap().1;
    assert!((m.six.rotation.y + 1.0).abs() < 1e-6);

    // Pad a goes away during its stroke: the stroke ends, its controls centre, it is forgotten.
    insert(&mut pads, a, EventType::Disconnected);
    actions.clear();
    pads.poll(&mut actions);
    assert_eq!(actions, [stroke(false)]);
    assert!(pads.mapper(a).is_none());
    assert_eq!(pads.motions().count(), 1);
}

#[test]
fn pure_mapping_dead_zone_curve_dpad_and_edges() {
    let c = GamepadCalibration::shipped();
    let mut m = GamepadMapper::default();
    let mut actions = Vec::new();
    m.handle(&EventType::AxisChanged(Axis::LeftStickX, c.dead_zone * 0.9, code()), &c, &mut actions);
    assert_eq!(m.motion(&c).six.translation.x, 0.0, "inside the dead zone");
    m.handle(&EventType::AxisChanged(Axis::LeftStickX, -2.0, code()), &c, &mut actions);
    assert_eq!(m.motion(&c).six.translation.x, -1.0, "clamped to full travel");
    m.handle(&EventType::AxisChanged(Axis::LeftStickX, f32::NAN, code()), &c, &mut actions);
    assert_eq!(m.value(Source::LeftStickX), -1.0, "a NaN is ignored");
    assert_eq!(m.ignored_events, 1);

    m.handle(&EventType::ButtonPressed(Button::DPadUp, code()), &c, &mut actions);
    assert!((m.motion(&c).size_rate - 0.5).abs() < 1e-6, "d-pad up grows the tool at half speed");
    m.handle(&EventType::ButtonPressed(Button::DPadDown, code()), &c, &mut actions);
    assert_eq!(m.motion(&c).size_rate, 0.0, "up and down cancel");
    m.handle(&EventType::ButtonReleased(Button::DPadUp, code()), &c, &mut actions);
    assert!((m.motion(&c).size_rate + 0.5).abs() < 1e-6);

    m.handle(&EventType::ButtonPressed(Button::East, code()), &c, &mut actions);
    m.handle(&EventType::ButtonPressed(Button::East, code()), &c, &mut actions);
    m.handle(&EventType::ButtonReleased(Button::East, code()), &c, &mut actions);
    m.handle(&EventType::ButtonReleased(Button::West, code()), &c, &mut actions);
    let clutch = |pressed| ActionEvent { action: InputAction::Clutch, pressed, device: DeviceClass::Gamepad };
    assert_eq!(actions, [clutch(true), clutch(false)], "edges only; a release without a press is nothing");

    // Triggers: either as analog buttons or as Z axes; `triggers` is right minus left.
    m.handle(&EventType::ButtonChanged(Button::LeftTrigger2, 0.75, code()), &c, &mut actions);
    m.handle(&EventType::AxisChanged(Axis::RightZ, 0.25, code()), &c, &mut actions);
    assert!((m.value(Source::Triggers) + 0.5).abs() < 1e-6);
    assert!(m.motion(&c).six.translation.y < 0.0);
}

#[test]
fn rumble_is_a_no_op_without_a_force_feedback_pad() {
    let mut pads = gamepads();
    // A pad known only from inserted events is not connected to gilrs: nothing plays.
    pads.gilrs_mut().insert_event(Event::new(pad(0), EventType::Connected));
    let mut actions = Vec::new();
    pads.poll(&mut actions);
    assert_eq!(pads.pad_ids().collect::<Vec<_>>(), [pad(0)]);
    assert!(!pads.play(pad(0), ContactFeedback::TAP));
    assert!(!pads.play(pad(7), Rumble { strong: 1.0, weak: 1.0, duration_ms: 80 }));
    assert!(!pads.play(pad(0), Rumble::STOP), "a stop starts nothing");
    assert!(!pads.play(pad(0), Rumble { strong: f32::NAN, weak: 0.5, duration_ms: 80 }));
}

#[test]
fn the_shipped_file_and_a_user_file() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("calibration/gamepad.toml");
    assert_eq!(GamepadCalibration::load(&path).unwrap(), GamepadCalibration::shipped());
    let dir = std::env::temp_dir().join(format!("argile-gamepad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mine = dir.join("gamepad.toml");
    std::fs::write(
        &mine,
        "[axes]\nsize = { from = \"triggers\", invert = true }\n[buttons]\nmode = \"undo\"\n",
    )
    .unwrap();
    let c = GamepadCalibration::load(&mine).unwrap();
    assert_eq!(c.action(Button::Mode), Some(InputAction::Undo));
    assert_eq!(c.axes[6].from, Source::Triggers);
    std::fs::write(&mine, "[axes]\nsize = { from = \"triggers\", invert = \"yes\" }\n").unwrap();
    let e = GamepadCalibration::load(&mine).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}:2:", mine.display())), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
