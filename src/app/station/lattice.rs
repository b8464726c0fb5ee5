//! The lattice held open at the desk: its keys, and the picked control following the tool.

use super::Station;
use crate::app::panel_rows::{lattice_region, lattice_step, LatticeStep};
use crate::config::StationAction;
use crate::input::motion::Target;
use crate::math::Vec3;

/// How a lattice is opened at the desk, as the messages say it.
pub(super) const LATTICE_OPENS: &str = "F opens one";

impl Station<'_> {
    /// The lattice keys (see `calibration/keys.toml`); returns whether `action` was one.
    pub(super) fn act_lattice(&mut self, action: StationAction) -> bool {
        let step = match action {
            StationAction::ApplyLattice => Some(LatticeStep::Apply),
            StationAction::CancelLattice => Some(LatticeStep::Cancel),
            StationAction::RaiseValue => Some(LatticeStep::Value(true)),
            StationAction::LowerValue => Some(LatticeStep::Value(false)),
            StationAction::HeavierWeight => Some(LatticeStep::Weight(true)),
            StationAction::LighterWeight => Some(LatticeStep::Weight(false)),
            StationAction::NextLatticeSlice => Some(LatticeStep::NextSlice),
            _ => None,
        };
        let said = match (action, step) {
            (_, Some(step)) => lattice_step(&mut self.doc, step, LATTICE_OPENS),
            (StationAction::OpenLattice | StationAction::OpenPartLattice, _) => {
                self.end_desk_strokes();
                self.open_lattice(action == StationAction::OpenPartLattice)
            }
            (StationAction::NextLatticeKind, _) => {
                let form = self.doc.playback.lattice_form().next_kind();
                self.set_lattice_form(form)
            }
            (StationAction::DragControl, _) => return true,
            _ => return false,
        };
        self.messages.push(said);
        true
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
        let around = (!whole_part).then(|| (&self.desk_tool, self.controls.desk.poses.get(Target::Tool)));
        let region = match lattice_region(&self.doc.playback, around) {
            Ok(region) => region,
            Err(why) => return why,
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
