//! What the desk's and the headset's panels share: the tool's rows and what their commands do
//! to a tool, the parts', the history's and the lattice's rows, and the lattice's steps.
//!
//! Each station builds its [`PanelView`] from these and applies the panel's commands through
//! them, so a slider or a button does the same thing at the desk and in the headset.

use super::document::Document;
use super::playback::Playback;
use crate::app::held_lattice::{PART_MARGIN, VALUE_STEP, WEIGHT_STEP};
use crate::math::{Aabb, Pose, Vec3};
use crate::tool::{Action, Ellipsoid, Falloff, Solid, Tool, ToolShape, HAND_SIZE_SAMPLES};
use crate::ui::{LatticeRow, PanelCommand, PanelView, PartRow};

/// The shapes the desk tool cycles through with `next-shape`, all of size `s` (their smallest
/// half extent), and their names.
pub(super) fn shape_cycle(s: f32) -> [(ToolShape, &'static str); 5] {
    [
        (ToolShape::sphere(s), "sphere"),
        (ToolShape::Solid(Solid::Box { half_m: Vec3::splat(s) }), "box"),
        (ToolShape::Solid(Solid::Cylinder { radius_m: s, half_height_m: s }), "cylinder"),
        (ToolShape::Solid(Solid::Torus { major_m: 2.0 * s, minor_m: s }), "torus"),
        (
            ToolShape::Ellipsoid(Ellipsoid { radii_m: Vec3::new(2.0 * s, s, s), falloff: Falloff::Wyvill }),
            "ellipsoid",
        ),
    ]
}

/// The name of a tool shape for the HUD.
pub(super) fn shape_name(shape: &ToolShape) -> &'static str {
    match shape {
        ToolShape::Solid(Solid::Sphere { .. }) => "sphere",
        ToolShape::Solid(Solid::Box { .. } | Solid::RoundedBox { .. }) => "box",
        ToolShape::Solid(Solid::Cylinder { .. }) => "cylinder",
        ToolShape::Solid(Solid::Torus { .. }) => "torus",
        ToolShape::Solid(Solid::Bar { .. }) => "bar",
        ToolShape::Ellipsoid(_) => "ellipsoid",
        ToolShape::Freeform(_) => "freeform",
    }
}

/// The actions the desk tool cycles through with `next-action`.
pub(super) fn action_cycle() -> [Action; 6] {
    [
        Action::Add,
        Action::Remove,
        Action::Build { rate_per_s: 2.0 },
        Action::SoftRemove { rate_per_s: 2.0 },
        Action::Paint,
        Action::Smooth { centre_weight: 6.0, rate_per_s: 20.0 },
    ]
}

/// The range of the panel's size slider, millimetres (wider when the tool already is).
const SIZE_RANGE_MM: (f32, f32) = (1.0, 200.0);

/// A lattice opened around the tool spans this many times the tool's largest half-extent on
/// each side of it.
const AROUND_TOOL: f32 = 2.0;

/// The rate per second of an action that has one.
fn rate_of(action: Action) -> Option<f32> {
    match action {
        Action::Build { rate_per_s }
        | Action::SoftRemove { rate_per_s }
        | Action::SoftPaint { rate_per_s }
        | Action::Smooth { rate_per_s, .. } => Some(rate_per_s),
        _ => None,
    }
}

/// `action` at `rate` per second, where it has a rate.
fn with_rate(action: Action, rate: f32) -> Action {
    match action {
        Action::Build { .. } => Action::Build { rate_per_s: rate },
        Action::SoftRemove { .. } => Action::SoftRemove { rate_per_s: rate },
        Action::SoftPaint { .. } => Action::SoftPaint { rate_per_s: rate },
        Action::Smooth { centre_weight, .. } => Action::Smooth { centre_weight, rate_per_s: rate },
        other => other,
    }
}

/// Fills the tool's rows of `view` from `tool`, whose action is `action_index` of the action
/// cycle where its name does not say.
pub(super) fn fill_tool(view: &mut PanelView, tool: &Tool, action_index: usize) {
    let cycle = shape_cycle(1.0);
    let size_mm = tool.size_m() * 1000.0;
    view.shapes = cycle.iter().map(|(_, n)| *n).collect();
    view.shape = cycle.iter().position(|(_, n)| *n == shape_name(&tool.shape));
    view.actions = action_cycle().iter().map(|a| a.name()).collect();
    view.action = action_cycle().iter().position(|a| a.name() == tool.action.name()).unwrap_or(action_index);
    view.size_mm = size_mm;
    view.size_range_mm = (SIZE_RANGE_MM.0.min(size_mm), SIZE_RANGE_MM.1.max(size_mm));
    view.rate_per_s = rate_of(tool.action);
    view.spacing = tool.spacing;
    view.colour = [tool.colour[0], tool.colour[1], tool.colour[2]];
}

/// Does a tool command of the panel (shape, action, size, rate, spacing, colour, level) to
/// `tool`, its action index and the voxels across it its level is chosen by; returns whether
/// `command` was one. Values that are not finite or out of range change nothing or are
/// brought within range.
pub(super) fn apply_tool(
    command: &PanelCommand,
    tool: &mut Tool,
    action_index: &mut usize,
    hand_samples: &mut Option<f32>,
) -> bool {
    match *command {
        PanelCommand::Shape(i) => {
            let size = tool.shape.half_extents_m().min_element();
            if let Some((shape, _)) = shape_cycle(size).get(i) {
                tool.shape = shape.clone();
            }
        }
        PanelCommand::Action(i) => {
            if let Some(action) = action_cycle().get(i) {
                *action_index = i;
                tool.action = *action;
            }
        }
        PanelCommand::SizeMm(mm) => {
            let now = tool.size_m();
            if mm.is_finite() && mm > 0.0 && now > 0.0 {
                tool.scale *= mm * 1e-3 / now;
            }
        }
        PanelCommand::Rate(rate) => {
            if rate.is_finite() && rate > 0.0 {
                tool.action = with_rate(tool.action, rate);
            }
        }
        PanelCommand::Spacing(spacing) => {
            if spacing.is_finite() {
                tool.spacing = spacing.clamp(0.05, 1.0);
            }
        }
        PanelCommand::Colour(rgb) => {
            if rgb.iter().all(|c| c.is_finite()) {
                let [r, g, b] = rgb.map(|c| c.clamp(0.0, 1.0));
                tool.colour = [r, g, b, tool.colour[3]];
            }
        }
        PanelCommand::LevelSamples(samples) => {
            *hand_samples = samples.filter(|n| n.is_finite() && *n >= 1.0);
            tool.level_samples = *hand_samples;
        }
        PanelCommand::LevelBySize => {
            *hand_samples = Some(HAND_SIZE_SAMPLES);
            tool.level_samples = *hand_samples;
        }
        _ => return false,
    }
    true
}

/// The level `acting` (the tool as it acts) edits (its size chooses it) and that level's voxel
/// size, millimetres.
pub(super) fn edit_level(playback: &Playback<'_>, acting: &Tool) -> (u32, f32) {
    let field = playback.field();
    let level = acting.level_samples.map_or(0, |n| crate::tool::edit_level_for(field, acting.size_m(), n));
    (level as u32, field.level_transform(level).voxel_size_m * 1000.0)
}

/// The sculpt's parts as the panel lists them.
pub(super) fn part_rows(playback: &Playback<'_>) -> Vec<PartRow> {
    playback
        .assembly()
        .parts()
        .iter()
        .map(|p| PartRow {
            name: p.name.clone(),
            op: p.op.name(),
            voxel_mm: p.voxel_size_m * 1000.0,
            visible: p.visible,
            locked: p.locked,
        })
        .collect()
}

/// The history as the panel lists it: `undo` steps that can be undone and `redo` that can be
/// redone, numbered, named by `undone_names` (the newest steps' names, oldest first) and
/// `redo_names` (the undone steps' names, the next to redo last); steps without a name (a
/// scene's, the headset's) are called "step".
pub(super) fn history_rows(
    (undo, redo): (usize, usize),
    undone_names: &[String],
    redo_names: &[String],
) -> (Vec<String>, Vec<String>) {
    let undo_list = (0..undo)
        .map(|i| {
            let k = (undone_names.len() + i).checked_sub(undo);
            format!("{}. {}", i + 1, k.map_or("step", |k| undone_names[k].as_str()))
        })
        .collect();
    let redo_list = (0..redo)
        .map(|i| {
            let k = redo_names.len().checked_sub(1 + i);
            format!("{}. {}", undo + i + 1, k.map_or("step", |k| redo_names[k].as_str()))
        })
        .collect();
    (undo_list, redo_list)
}

/// The lattice tool as the panel shows it: the form the next opens with, and the open one
/// with its picked control.
pub(super) fn lattice_row(playback: &Playback<'_>) -> LatticeRow {
    let held = playback.held_lattice();
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
    LatticeRow {
        form: playback.lattice_form(),
        weighted: held.is_some_and(|h| h.lattice().spec().kind == crate::spline::SplineKind::Nurbs),
        open,
    }
}

/// A step on the open lattice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum LatticeStep {
    /// Apply it (one undo step).
    Apply,
    /// Close it, the clay as it was.
    Cancel,
    /// Raise (`true`) or lower the picked control's value.
    Value(bool),
    /// Make the picked control's weight heavier (`true`) or lighter.
    Weight(bool),
    /// Show the next slice (or hide the slice after the last).
    NextSlice,
}

impl LatticeStep {
    /// The step a panel command asks for, if it is one.
    pub(super) fn of(command: &PanelCommand) -> Option<Self> {
        Some(match *command {
            PanelCommand::ApplyLattice => LatticeStep::Apply,
            PanelCommand::CancelLattice => LatticeStep::Cancel,
            PanelCommand::ControlValue(up) => LatticeStep::Value(up),
            PanelCommand::ControlWeight(heavier) => LatticeStep::Weight(heavier),
            PanelCommand::NextLatticeSlice => LatticeStep::NextSlice,
            _ => return None,
        })
    }
}

/// Takes `step` on the document's open lattice; says what it did (`how_to_open` completes
/// "no lattice is open" with the station's way of opening one).
pub(super) fn lattice_step(doc: &mut Document<'_>, step: LatticeStep, how_to_open: &str) -> String {
    let none = || format!("no lattice is open ({how_to_open})");
    match step {
        LatticeStep::Apply => match doc.playback.apply_lattice() {
            true => {
                doc.edited();
                "lattice applied (undo takes it back)".to_owned()
            }
            false => none(),
        },
        LatticeStep::Cancel => match doc.playback.cancel_lattice() {
            true => "lattice closed: the clay is as it was".to_owned(),
            false => none(),
        },
        LatticeStep::Value(up) => match doc.playback.held_lattice_mut() {
            None => none(),
            Some(held) => match held.add_value(if up { VALUE_STEP } else { -VALUE_STEP }) {
                Ok(v) => format!("control {:?}: value {v:.2}", held.picked()),
                Err(e) => format!("the control's value stays: {e}"),
            },
        },
        LatticeStep::Weight(heavier) => match doc.playback.held_lattice_mut() {
            None => none(),
            Some(held) => match held.scale_weight(if heavier { WEIGHT_STEP } else { 1.0 / WEIGHT_STEP }) {
                Ok(w) => format!("control {:?}: weight {w:.2}", held.picked()),
                Err(e) => format!("the control's weight stays: {e}"),
            },
        },
        LatticeStep::NextSlice => match doc.playback.held_lattice_mut() {
            None => none(),
            Some(held) => match held.next_slice() {
                Some(k) => format!(
                    "lattice slice {} of {}: its controls' values and zero contour",
                    k + 1,
                    held.lattice().volume().counts()[2]
                ),
                None => "lattice slice hidden".to_owned(),
            },
        },
    }
}

/// The region a new lattice opens over, in the active part's frame: around `tool` at `pose`
/// (the scene), or, without one, the active part's whole clay with a margin. `Err` says why
/// there is none.
pub(super) fn lattice_region(playback: &Playback<'_>, around: Option<(&Tool, Pose)>) -> Result<Aabb, String> {
    match around {
        Some((tool, pose)) => {
            let (tool, local, _) = playback.in_active_part(tool.clone(), pose, &[]);
            let half = AROUND_TOOL * tool.half_extents_m().max_element();
            Ok(Aabb::from_centre_half(local.position_m, Vec3::splat(half)))
        }
        None => {
            let part = playback.assembly().active();
            let clay = crate::parts::local_bounds(playback.assembly().field(playback.field(), part));
            if clay.is_empty() {
                return Err("the active part holds no clay to open a lattice over".to_owned());
            }
            Ok(clay.expanded(PART_MARGIN * clay.size().max_element()))
        }
    }
}

/// What opening the sculpt at `path` says, leaving `left` unsaved changes to `fate` (see
/// [`Document::unsaved_fate`]).
pub(super) fn opened_said(path: &std::path::Path, left: u64, fate: &str) -> String {
    match left {
        0 => format!("opened {}", path.display()),
        n => format!("opened {} ({n} unsaved change(s) left behind: {fate})", path.display()),
    }
}

/// What a save as says: where it saved, where saving writes from now on; or why not, and
/// where saving still writes (`save_to`, the document's after the attempt).
pub(super) fn saved_as_said(
    saved: &anyhow::Result<super::document::Saved>,
    save_to: &std::path::Path,
) -> String {
    match saved {
        Ok(saved) => format!("saved the sculpt to {}, where saving writes from now on", saved.path.display()),
        Err(e) => format!("{e:#}; saving still writes to {}", save_to.display()),
    }
}
