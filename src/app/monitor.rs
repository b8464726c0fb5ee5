//! Which monitor the station's window opens on, and whether it fills it.
//!
//! Half modes, interlaced parity and head-tracked views depend on where the window lies on
//! which screen, so a stereo display is named (`--monitor`, `[display] monitor` in a scene or
//! a calibration) and filled (`--fullscreen`, `[display] fullscreen`, F11 at run time). The
//! window system's monitors are read as [`Monitor`]s; the choice is made here, apart from
//! winit, so that it is tested without a display.

use std::fmt;

/// A monitor as the window system describes it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Monitor {
    /// Its name (an X11 RandR output such as `DP-1`, or what the window system calls it).
    pub name: String,
    /// Its top-left corner on the desktop, pixels.
    pub position_px: (i32, i32),
    /// Its resolution, pixels.
    pub size_px: (u32, u32),
    /// Its refresh rate, millihertz, when the window system says.
    pub refresh_mhz: Option<u32>,
}

impl fmt::Display for Monitor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "`{}` {}x{} at ({}, {})",
            self.name, self.size_px.0, self.size_px.1, self.position_px.0, self.position_px.1
        )?;
        if let Some(mhz) = self.refresh_mhz {
            write!(f, ", {:.0} Hz", f64::from(mhz) / 1000.0)?;
        }
        Ok(())
    }
}

/// The monitor `choice` names among `monitors`: its index in the list (from 0), its name (any
/// case), or a part of the name that only one monitor's holds. A choice that names none, or
/// more than one, is refused with the list.
pub fn pick_monitor(choice: &str, monitors: &[Monitor]) -> Result<usize, String> {
    let choice = choice.trim();
    let listed = || {
        if monitors.is_empty() {
            "the window system lists no monitor".to_owned()
        } else {
            let each: Vec<String> = monitors.iter().enumerate().map(|(i, m)| format!("{i}: {m}")).collect();
            format!("the monitors are {}", each.join("; "))
        }
    };
    if let Ok(i) = choice.parse::<usize>() {
        return if i < monitors.len() {
            Ok(i)
        } else {
            Err(format!("there is no monitor {i}; {}", listed()))
        };
    }
    if let Some(i) = monitors.iter().position(|m| m.name.eq_ignore_ascii_case(choice)) {
        return Ok(i);
    }
    let lower = choice.to_lowercase();
    let holding: Vec<usize> = (0..monitors.len())
        .filter(|&i| !lower.is_empty() && monitors[i].name.to_lowercase().contains(&lower))
        .collect();
    match holding[..] {
        [i] => Ok(i),
        [] => Err(format!("no monitor is called `{choice}`; {}", listed())),
        _ => Err(format!("`{choice}` names {} monitors; {}", holding.len(), listed())),
    }
}

/// What a frame-sequential display does at `refresh_mhz`: each eye gets half the frames, so
/// below 100 Hz the glasses flicker (DLP-Link and 3D-ready DLP displays run at 120 Hz).
pub fn frame_sequential_notice(refresh_mhz: Option<u32>) -> String {
    match refresh_mhz {
        Some(mhz) => {
            let hz = f64::from(mhz) / 1000.0;
            let flicker = if hz < 99.5 {
                "; under 100 Hz the glasses flicker: set the display to 120 Hz (DLP-Link needs it)"
            } else {
                ""
            };
            format!("frame-sequential at {hz:.0} Hz: each eye sees {:.0} frames a second{flicker}", hz / 2.0)
        }
        None => {
            "frame-sequential: the window system does not say the refresh rate; each eye sees half of it \
                 (DLP-Link needs 120 Hz)"
                .to_owned()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn monitors() -> Vec<Monitor> {
        let m = |name: &str, x: i32, hz: Option<u32>| Monitor {
            name: name.to_owned(),
            position_px: (x, 0),
            size_px: (1920, 1080),
            refresh_mhz: hz,
        };
        vec![m("DP-1", 0, Some(59_940)), m("DP-2", 1920, Some(120_000)), m("HDMI-A-1", 3840, None)]
    }

    #[test]
    fn a_monitor_is_picked_by_index_name_or_a_part_of_its_name_only_it_holds() {
        let list = monitors();
        assert_eq!(pick_monitor("1", &list), Ok(1));
        assert_eq!(pick_monitor(" dp-2 ", &list), Ok(1));
        assert_eq!(pick_monitor("hdmi", &list), Ok(2));
        let e = pick_monitor("DP", &list).unwrap_err();
        assert!(
            e.contains("`DP` names 2 monitors") && e.contains("1: `DP-2` 1920x1080 at (1920, 0), 120 Hz"),
            "{e}"
        );
        let e = pick_monitor("3", &list).unwrap_err();
        assert!(e.starts_with("there is no monitor 3; the monitors are 0: `DP-1`"), "{e}");
        assert!(pick_monitor("VGA", &list).unwrap_err().starts_with("no monitor is called `VGA`"));
        assert!(pick_monitor("", &list).is_err(), "an empty name names none");
        assert!(pick_monitor("0", &[]).unwrap_err().contains("lists no monitor"));
    }

    #[test]
    fn frame_sequential_says_what_each_eye_gets_and_warns_of_flicker() {
        let at120 = frame_sequential_notice(Some(120_000));
        assert_eq!(at120, "frame-sequential at 120 Hz: each eye sees 60 frames a second");
        assert!(frame_sequential_notice(Some(59_940)).contains("flicker"));
        assert!(frame_sequential_notice(None).contains("does not say"));
    }
}
