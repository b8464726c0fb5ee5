//! A region of a part's clay held by a hand, at the desk or in the headset: the region of the
//! tool's shape (or a box the hand dragged out, [`box_between`]) is taken when the hand closes, carried (or a copy of it
//! carried, or the clay bent after it) as the hand moves, and left as one undo step when the
//! hand opens. The scene's scripted region tools are [`super::playback`]'s; this is the
//! hand-held one, one at a time, shared by the desk and the headset through
//! [`super::playback::Playback`].

use crate::field::Field;
use crate::math::{Pose, Vec3};
use crate::parts::{Motion, Region, RegionDrag, RegionOp, RegionStats};

/// How far one press of inflate or deflate moves the surface within the region, metres.
pub const SWELL_STEP_M: f32 = 0.001;

/// A region tool a hand holds: one of the drags, or a swell of the surface within the region.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RegionTool {
    /// Carried with the hand while it is closed: move, copy or bend.
    Drag(RegionOp),
    /// Each press moves the surface within the region out (inflate) or in (deflate) by
    /// [`SWELL_STEP_M`].
    Swell {
        /// Outwards.
        out: bool,
    },
    /// Each pull copies the region into a new part, which becomes the active one (the support
    /// grip then carries it).
    CopyToPart,
    /// The hand drags out a box from where the trigger goes down to where it comes up: the
    /// region the others act on from then on, instead of the tool's shape (a box too thin
    /// clears it).
    SelectBox,
}

impl RegionTool {
    /// Every region tool, in the order the headset's palette steps through them.
    pub const ALL: [RegionTool; 7] = [
        RegionTool::Drag(RegionOp::Move),
        RegionTool::Drag(RegionOp::Copy),
        RegionTool::Drag(RegionOp::Bend),
        RegionTool::Swell { out: true },
        RegionTool::Swell { out: false },
        RegionTool::CopyToPart,
        RegionTool::SelectBox,
    ];

    /// Its name, as messages say it.
    pub fn name(self) -> &'static str {
        match self {
            RegionTool::Drag(op) => op.name(),
            RegionTool::Swell { out: true } => "inflate",
            RegionTool::Swell { out: false } => "deflate",
            RegionTool::CopyToPart => "copy to part",
            RegionTool::SelectBox => "select box",
        }
    }

    /// The one after `now` in [`RegionTool::ALL`], none (the hand sculpts again) after the last.
    pub fn after(now: Option<RegionTool>) -> Option<RegionTool> {
        match now {
            None => Some(RegionTool::ALL[0]),
            Some(t) => {
                let at = RegionTool::ALL.iter().position(|a| *a == t).unwrap_or(RegionTool::ALL.len());
                RegionTool::ALL.get(at + 1).copied()
            }
        }
    }

    /// What the hand does with it, as the message that selects it says.
    pub fn describe(self) -> String {
        match self {
            RegionTool::Drag(RegionOp::Move) => {
                "region tool move: the trigger carries the clay within the tool (or the box selected), leaving empty space".into()
            }
            RegionTool::Drag(RegionOp::Copy) => {
                "region tool copy: the trigger carries a copy of the clay within the tool (or the box selected)".into()
            }
            RegionTool::Drag(RegionOp::Bend) => {
                "region tool bend: the trigger bends the clay within the tool (or the box selected) after the hand".into()
            }
            RegionTool::Swell { out } => format!(
                "region tool {}: each pull of the trigger moves the surface within the tool (or the box selected) {} by {} mm",
                self.name(),
                if out { "out" } else { "in" },
                SWELL_STEP_M * 1e3
            ),
            RegionTool::CopyToPart => {
                "region tool copy to part: each pull of the trigger copies the clay within the tool (or the box selected) into a new part, which the support grip then carries".into()
            }
            RegionTool::SelectBox => {
                "region tool select box: hold the trigger and drag out a box for the region tools; a pull without a drag clears it".into()
            }
        }
    }
}

/// The fewest voxels of its part a selected box spans on each axis; a thinner one clears the
/// selection.
pub const MIN_BOX_VOXELS: f32 = 2.0;

/// The box from corner `a` to corner `b`, axis-aligned in their frame; none where it spans
/// less than `min_m` on some axis.
pub fn box_between(a: Vec3, b: Vec3, min_m: f32) -> Option<Region> {
    let size = (b - a).abs();
    let centre = 0.5 * (a + b);
    (size.min_element() >= min_m && size.is_finite())
        .then(|| Region::boxed(Pose { position_m: centre, ..Pose::default() }, 0.5 * size))
}

/// What the user is told when a box is selected (its size, metres) or the selection is
/// cleared; `clear` says how to clear it.
pub fn selection_said(size_m: Option<Vec3>, clear: &str) -> String {
    match size_m {
        Some(s) => format!(
            "box of {:.0} × {:.0} × {:.0} mm selected: the region tools act on it ({clear} clears it)",
            s.x * 1e3,
            s.y * 1e3,
            s.z * 1e3
        ),
        None => "selection cleared: the region tools act on the tool's shape".into(),
    }
}

/// A region of part `part`'s clay carried by a hand: the drag, and the hand's pose in the
/// part's frame when it took the region. The part's stroke stays open while it is held, so
/// that the whole drag is one undo step.
#[derive(Clone, Debug)]
pub struct HeldRegion {
    part: usize,
    drag: RegionDrag,
    grab: Pose,
}

impl HeldRegion {
    /// Takes `region` from `field` (part `part`'s clay, its images under `images` with it; the
    /// hand at `pose`; both in the part's frame) for `op`, and opens the part's stroke. Refused,
    /// with a sentence, while the field's stroke is open or when the region cannot be taken.
    pub fn grab(
        field: &mut Field,
        part: usize,
        op: RegionOp,
        region: Region,
        pose: Pose,
        images: &[crate::math::Isometry],
    ) -> Result<Self, String> {
        if field.in_stroke() {
            return Err(format!("cannot {} the region while a stroke is drawn", op.name()));
        }
        let drag = RegionDrag::start(field, region, op, images)
            .map_err(|e| format!("cannot {} the region: {e}", op.name()))?;
        field.begin_stroke();
        Ok(Self { part, drag, grab: pose })
    }

    /// The part whose clay it carries.
    pub fn part(&self) -> usize {
        self.part
    }

    /// The drag, for drawing where the region is (its regions lie in the part's frame).
    pub fn drag(&self) -> &RegionDrag {
        &self.drag
    }

    /// Carries the region to where the hand is now, at `pose` in the part's frame, on `field`
    /// (the part's clay).
    pub fn carry(&mut self, field: &mut Field, pose: Pose) -> Result<RegionStats, String> {
        self.drag
            .update(field, Motion::between(self.grab, pose))
            .map_err(|e| format!("the region stops: {e}"))
    }

    /// Lets the region go where it was last carried: the part's stroke ends (the caller
    /// journals it). Returns the region where the hand left it when it carried the clay (a
    /// move or a copy), for a selection to follow.
    pub fn let_go(self, field: &mut Field) -> Option<Region> {
        field.end_stroke();
        match self.drag.op() {
            RegionOp::Bend => None,
            _ => self.drag.carried_regions().into_iter().next(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_palettes_region_tools_step_through_every_one_then_back_to_sculpting() {
        let mut seen = Vec::new();
        let mut now = RegionTool::after(None);
        while let Some(t) = now {
            assert!(!seen.contains(&t), "{} comes twice", t.name());
            seen.push(t);
            now = RegionTool::after(now);
        }
        assert_eq!(seen, RegionTool::ALL);
        let names: std::collections::HashSet<_> = seen.iter().map(|t| t.name()).collect();
        assert_eq!(names.len(), RegionTool::ALL.len());
        for t in RegionTool::ALL {
            assert!(t.describe().contains(t.name()));
        }
    }
}
