//! The lattice held open at the desk: its keys, and the picked control following the tool.

use super::Station;
use crate::app::held_lattice::{held_spec, PART_MARGIN, VALUE_STEP, WEIGHT_STEP};
use crate::config::StationAction;
use crate::input::motion::Target;
use crate::math::{Aabb, Vec3};

/// A lattice opened around the tool spans this many times the tool's largest half-extent on
/// each side of it.
const AROUND_TOOL: f32 = 2.0;

impl Station<'_> {
    /// The lattice keys (see `calibration/keys.toml`); returns whether `action` was one.
    pub(super) fn act_lattice(&mut self, action: StationAction) -> bool {
        let said = match action {
            StationAction::OpenLattice | StationAction::OpenPartLattice => {
                self.end_desk_strokes();
                self.open_lattice(action == StationAction::OpenPartLattice)
            }
            StationAction::ApplyLattice => match self.doc.playback.apply_lattice() {
                true => {
                    self.doc.edited();
                    "lattice applied (undo takes it back)".to_owned()
                }
                false => "no lattice is open (F opens one)".to_owned(),
            },
            StationAction::CancelLattice => match self.doc.playback.cancel_lattice() {
                true => "lattice closed: the clay is as it was".to_owned(),
                false => "no lattice is open (F opens one)".to_owned(),
            },
            StationAction::RaiseValue | StationAction::LowerValue => {
                let delta = if action == StationAction::RaiseValue { VALUE_STEP } else { -VALUE_STEP };
                match self.doc.playback.held_lattice_mut() {
                    None => "no lattice is open (F opens one)".to_owned(),
                    Some(held) => match held.add_value(delta) {
                        Ok(v) => format!("control {:?}: value {v:.2}", held.picked()),
                        Err(e) => format!("the control's value stays: {e}"),
                    },
                }
            }
            StationAction::HeavierWeight | StationAction::LighterWeight => {
                let factor =
                    if action == StationAction::HeavierWeight { WEIGHT_STEP } else { 1.0 / WEIGHT_STEP };
                match self.doc.playback.held_lattice_mut() {
                    None => "no lattice is open (F opens one)".to_owned(),
                    Some(held) => match held.scale_weight(factor) {
                        Ok(w) => format!("control {:?}: weight {w:.2}", held.picked()),
                        Err(e) => format!("the control's weight stays: {e}"),
                    },
                }
            }
            StationAction::NextLatticeSlice => match self.doc.playback.held_lattice_mut() {
                None => "no lattice is open (F opens one)".to_owned(),
                Some(held) => match held.next_slice() {
                    Some(k) => format!(
                        "lattice slice {} of {}: its controls' values and zero contour",
                        k + 1,
                        held.lattice().volume().counts()[2]
                    ),
                    None => "lattice slice hidden".to_owned(),
                },
            },
            StationAction::DragControl => return true,
            _ => return false,
        };
        self.messages.push(said);
        true
    }

    /// Opens a lattice over the clay around the desk tool, or over the active part's whole
    /// clay; says what it did.
    fn open_lattice(&mut self, whole_part: bool) -> String {
        let region = if whole_part {
            let part = self.doc.playback.assembly().active();
            let clay = crate::parts::local_bounds(
                self.doc.playback.assembly().field(self.doc.playback.field(), part),
            );
            if clay.is_empty() {
                return "the active part holds no clay to open a lattice over".to_owned();
            }
            clay.expanded(PART_MARGIN * clay.size().max_element())
        } else {
            let pose = self.desk.poses.get(Target::Tool);
            let (tool, local, _) = self.doc.playback.in_active_part(self.desk_tool.clone(), pose, &[]);
            let half = AROUND_TOOL * tool.half_extents_m().max_element();
            Aabb::from_centre_half(local.position_m, Vec3::splat(half))
        };
        match self.doc.playback.open_lattice(&held_spec(region)) {
            Ok(()) => {
                let size = region.size() * 1000.0;
                format!(
                    "lattice open over {:.0} × {:.0} × {:.0} mm: D drags the control nearest the tool, R/Shift+R \
                     its value, W/Shift+W its weight; Enter applies, Backspace puts the clay back",
                    size.x, size.y, size.z
                )
            }
            Err(e) => e,
        }
    }

    /// Each frame while a lattice is open: the control nearest the tool (`point`, the active
    /// part's frame) is picked, and dragged while the drag key is held.
    pub(super) fn drive_lattice(&mut self, point: Vec3) {
        let dragging = self.holding(StationAction::DragControl);
        let Some(held) = self.doc.playback.held_lattice_mut() else { return };
        held.pick_nearest(point);
        if let Err(e) = held.drag(point, dragging) {
            let message = format!("the control stays: {e}");
            if self.messages.last() != Some(&message) {
                self.messages.push(message);
            }
        }
    }
}
