//! The sculpt's structure above one field: regions and the tools that act on them, and
//! symmetry.
//!
//! [`Symmetry`] is a group of rigid motions, some mirroring, in a frame of the sculpt: mirror
//! planes through the frame's origin normal to its axes, and radial copies about one of its
//! axes. Tools act at every image of the hand's pose ([`Symmetry::images`]); the tool module
//! applies a mirrored image with its local X negated, so asymmetric shapes appear reflected.
//!
//! [`RegionDrag`] carries, copies or bends a selected region of the clay, resampling it from
//! its state when the drag started; [`inflate`] grows or shrinks the surface within one.
//!
//! A sculpt is built of parts: fields of their own, each placed in the world ([`Placement`])
//! and composed with the parts before it by a [`Csg`] operator into the one surface drawn and
//! exported ([`Composition`]).
//!
//! Depends on `math`, `field` and `tool`.

mod part;
mod region;
mod symmetry;

pub use part::{
    local_bounds, part_bounds, Composition, Csg, PartView, Placement, PlacementError, SCALE_RANGE,
};
pub use region::{
    copy_into, copy_repeated, inflate, Motion, Region, RegionDrag, RegionError, RegionOp, RegionStats,
    MAX_REGION_POINTS,
};
pub use symmetry::{Axis, Symmetry, SymmetrySwitch, MAX_IMAGES, MAX_RADIAL};
