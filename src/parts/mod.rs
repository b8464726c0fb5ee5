//! The sculpt's structure above one field: its symmetry.
//!
//! [`Symmetry`] is a group of rigid motions, some mirroring, in a frame of the sculpt: mirror
//! planes through the frame's origin normal to its axes, and radial copies about one of its
//! axes. Tools act at every image of the hand's pose ([`Symmetry::images`]); the tool module
//! applies a mirrored image with its local X negated, so asymmetric shapes appear reflected.
//!
//! Depends on `math` only.

mod symmetry;

pub use symmetry::{Axis, Symmetry, SymmetrySwitch, MAX_IMAGES, MAX_RADIAL};
