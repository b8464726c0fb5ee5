//! Input devices: which ones the station can see (`argile info`), and the pure stages that
//! turn device data into tool poses.
//!
//! ```text
//!  HID report bytes ──► spacemouse::parse_report ──► SpaceMouseState (latest raw axes, buttons)
//!      ──► calibration::apply_calibration ──► SixDof (calibrated deflection)
//!  tracked hand positions ──► smoothing (Galyean–Hughes predictive, One Euro)
//!      ──► clutch (relative mode with gain) ──► tool pose
//!
//!  reader thread (hidapi, or the spacenavd socket) ──► Mailbox (bounded, newest state wins)
//!  gilrs events ──► gamepad::GamepadMapper ──► GamepadMotion + actions
//!  mouse events ──► mouse::MouseNavigator (trackball, distance, 3D cursor)
//!      ──► desk::DeskInput (per frame) ──► motion::integrate ──► the mapped Target's pose
//!  opentrack UDP datagrams ──► opentrack::OpentrackReceiver (thread) ──► screen-space head pose
//!      ──► head::HeadFilter (dropout: hold, then ease to the default eye) ──► stereo rig
//! ```
//!
//! Contract: every stage is a pure function or a small state machine fed plain values, tested
//! without hardware on recorded-style data; device threads only read and forward bytes. Bad
//! device data is an error value to count, never a panic. Calibration is TOML data
//! (`calibration/*.toml`). Device identification is a pure function of vendor, product and
//! usage ids; enumeration goes through `hidapi` (3Dconnexion SpaceMice) and `gilrs` (gamepads).
//! Knows nothing of the field, meshes, the renderer or Vulkan.

pub mod calibration;
pub mod clutch;
pub mod desk;
pub mod gamepad;
pub mod head;
pub mod motion;
pub mod mouse;
pub mod opentrack;
pub mod reader;
pub mod settings;
pub mod smoothing;
pub mod spacemouse;
pub mod spacenav;

use motion::DeviceClass;

/// 3Dconnexion's vendor ids: Logitech's (older devices) and 3Dconnexion's own.
pub const SPACEMOUSE_VENDORS: [u16; 2] = [0x046d, 0x256f];

/// HID usage page Generic Desktop, and its Multi-axis Controller usage.
const GENERIC_DESKTOP: u16 = 0x01;
const MULTI_AXIS_CONTROLLER: u16 = 0x08;

/// The name of a known 3Dconnexion product.
pub fn spacemouse_model(vendor: u16, product: u16) -> Option<&'static str> {
    Some(match (vendor, product) {
        (0x046d, 0xc603) => "SpaceMouse Plus XT",
        (0x046d, 0xc605) => "CadMan",
        (0x046d, 0xc606) => "SpaceMouse Classic",
        (0x046d, 0xc621) => "Spaceball 5000",
        (0x046d, 0xc623) => "SpaceTraveler",
        (0x046d, 0xc625) => "SpacePilot",
        (0x046d, 0xc626) => "SpaceNavigator",
        (0x046d, 0xc627) => "SpaceExplorer",
        (0x046d, 0xc628) => "SpaceNavigator for Notebooks",
        (0x046d, 0xc629) => "SpacePilot Pro",
        (0x046d, 0xc62b) => "SpaceMouse Pro",
        (0x256f, 0xc62e) => "SpaceMouse Wireless (cable)",
        (0x256f, 0xc62f) => "SpaceMouse Wireless (receiver)",
        (0x256f, 0xc631) => "SpaceMouse Pro Wireless (cable)",
        (0x256f, 0xc632) => "SpaceMouse Pro Wireless (receiver)",
        (0x256f, 0xc633) => "SpaceMouse Enterprise",
        (0x256f, 0xc635) => "SpaceMouse Compact",
        (0x256f, 0xc652) => "3Dconnexion Universal Receiver",
        _ => return None,
    })
}

/// Whether a HID interface is a 3Dconnexion six-axis controller: a known model, or any
/// interface of a 3Dconnexion vendor id whose usage is Multi-axis Controller.
pub fn is_spacemouse(vendor: u16, product: u16, usage_page: u16, usage: u16) -> bool {
    SPACEMOUSE_VENDORS.contains(&vendor)
        && (spacemouse_model(vendor, product).is_some()
            || (usage_page == GENERIC_DESKTOP && usage == MULTI_AXIS_CONTROLLER))
}

/// The name to show for a HID device: the known model, else what the device says, else its
/// vendor and product ids.
pub fn hid_device_name(d: &hidapi::DeviceInfo) -> String {
    spacemouse_model(d.vendor_id(), d.product_id())
        .map(str::to_owned)
        .or_else(|| d.product_string().map(str::to_owned))
        .unwrap_or_else(|| format!("{:04x}:{:04x}", d.vendor_id(), d.product_id()))
}

/// An input device the station can use.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SeenDevice {
    /// Its family, which decides the target it drives (see [`motion::MappingTable`]).
    pub class: DeviceClass,
    /// What kind: "SpaceMouse", "SpaceMouse (spacenavd)" or "gamepad".
    pub kind: &'static str,
    /// Its name.
    pub name: String,
    /// Where it is (HID path or gamepad id).
    pub location: String,
}

/// What was found, with the reasons a device family could not be looked at.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct InputReport {
    /// Devices found.
    pub devices: Vec<SeenDevice>,
    /// One sentence per family that could not be enumerated.
    pub problems: Vec<String>,
}

/// Enumerates SpaceMice (hidapi) and gamepads (gilrs). Never fails: problems are reported.
pub fn probe() -> InputReport {
    let mut report = InputReport::default();
    match hidapi::HidApi::new() {
        Ok(api) => {
            for d in api.device_list() {
                if is_spacemouse(d.vendor_id(), d.product_id(), d.usage_page(), d.usage()) {
                    let name = hid_device_name(d);
                    let location = d.path().to_string_lossy().into_owned();
                    if !report.devices.iter().any(|s| s.location == location) {
                        let class = DeviceClass::SpaceMouse;
                        report.devices.push(SeenDevice { class, kind: "SpaceMouse", name, location });
                    }
                }
            }
        }
        Err(e) => report.problems.push(format!("cannot enumerate HID devices (SpaceMouse): {e}")),
    }
    let socket = std::path::Path::new(spacenav::DEFAULT_SOCKET);
    if spacenav::SpacenavSource::socket_present(socket) {
        report.devices.push(SeenDevice {
            class: DeviceClass::SpaceMouse,
            kind: "SpaceMouse (spacenavd)",
            name: "spacenavd".into(),
            location: socket.display().to_string(),
        });
    }
    match gilrs::Gilrs::new() {
        Ok(gilrs) => {
            for (id, pad) in gilrs.gamepads() {
                report.devices.push(SeenDevice {
                    class: DeviceClass::Gamepad,
                    kind: "gamepad",
                    name: pad.name().to_owned(),
                    location: format!("gamepad {id}"),
                });
            }
        }
        Err(e) => report.problems.push(format!("cannot enumerate gamepads: {e}")),
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_models_and_multi_axis_interfaces_are_spacemice() {
        assert_eq!(spacemouse_model(0x046d, 0xc626), Some("SpaceNavigator"));
        assert!(is_spacemouse(0x256f, 0xc635, 0x01, 0x08));
        assert!(is_spacemouse(0x256f, 0xffff, 0x01, 0x08), "an unknown 3Dconnexion multi-axis device");
        assert!(!is_spacemouse(0x256f, 0xffff, 0x01, 0x06), "a 3Dconnexion keyboard interface");
        assert!(!is_spacemouse(0x046d, 0xc52b, 0x01, 0x02), "a Logitech mouse receiver");
        assert!(!is_spacemouse(0x1234, 0xc626, 0x01, 0x08));
    }

    #[test]
    fn probing_never_panics() {
        let r = probe();
        for d in &r.devices {
            assert!(!d.name.is_empty());
        }
    }
}
