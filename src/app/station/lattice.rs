//! The lattice held open at the desk: its keys, and the picked control following the tool.

use super::Station;
use crate::app::held_lattice::{PART_MARGIN, VALUE_STEP, WEIGHT_STEP};
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
            StationAction::NextLatticeKind => {
                let form = self.doc.playback.lattice_form().next_kind();
                self.set_lattice_form(form)
            }
            StationAction::DragControl => return true,
            _ => return false,
        };
        self.messages.push(said);
        true
    }

    /// The lattice tool as the panel shows it.
    pub(super) fn lattice_row(&self) -> crate::ui::LatticeRow {
        let held = self.doc.playback.held_lattice();
        let open = held.map(|h| {
            let spec = h.lattice().spec();
            let form = crate::lattice::LatticeForm {
                kind: spec.kind,
                counts: spec.counts,
                order: spec.order,
                knots: spec.knots,
            };
            let [i, j, k] = h.picked();
            let control = h.lattice().volume().control(i, j, k).ok();
            format!(
                "open: {}; control ({i}, {j}, {k}){}",
                form.describe(),
                control.map_or(String::new(), |c| format!(", value {:.2}, weight {:.2}", c.value, c.weight))
            )
        });
        crate::ui::LatticeRow {
            form: self.doc.playback.lattice_form(),
            weighted: held.is_some_and(|h| h.lattice().spec().kind == crate::spline::SplineKind::Nurbs),
            open,
        }
    }

    /// The lattices opened from now on have `form`; says so.
    pub(super) fn set_lattice_form(&mut self, form: crate::lattice::LatticeForm) -> String {
        self.doc.playback.set_lattice_form(form);
        let form = self.doc.playback.lattice_form().describe();
        match self.doc.playback.held_lattice() {
            Some(_) => format!("the open lattice stays as it is; the next opens as: {form}"),
            None => format!("lattices open as: {form} (F, Shift+F)"),
        }
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
        let form = self.doc.playback.lattice_form();
        match self.doc.playback.open_lattice(&form.over(region)) {
            Ok(()) => {
                let size = region.size() * 1000.0;
                let weights = match form.kind {
                    crate::spline::SplineKind::Nurbs => ", W/Shift+W its weight",
                    _ => "",
                };
                format!(
                    "lattice open ({}) over {:.0} × {:.0} × {:.0} mm: D drags the control nearest the tool, R/Shift+R \
                     its value{weights}; Enter applies, Backspace puts the clay back",
                    form.describe(),
                    size.x,
                    size.y,
                    size.z
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
