//! Tools and the solids of the initial clay, and how they write into the field.
//!
//! Owns tool shapes ([`ToolShape`]: sphere, box, cylinder, torus, ellipsoids with the Wyvill
//! or box falloff, freeform copies of a sculpt) placed by a 6-DoF pose and a per-axis scale,
//! the actions ([`Action`]: add, remove, heat gun, build, paint, smooth, stamp with
//! Ferley et al.'s `def(v)`, inflate/deflate), band-limited stamping and strokes. Knows nothing
//! of devices or Vulkan; depends on `math` and `field`, through the field's public API only.
//!
//! Invariants: every action keeps density in [0, 1] and finite; actions that remove never
//! add matter; paint never changes density; a stroke's result does not depend on how often it
//! is advanced.

mod action;
mod apply;
mod deform;
mod shape;
mod shapes;
mod stamp;
mod stroke;

pub use action::Action;
pub use apply::{
    apply_tool, apply_tool_mirrored, edit_level_for, StampCounters, HAND_SIZE_SAMPLES, MAX_SIZE_SAMPLES,
};
pub use deform::{DeformError, Deformation, FIELD_VALUE_RANGE};
pub use shape::{PlacedSolid, Solid};
pub use shapes::{wyvill, Ellipsoid, Falloff, Freeform, ToolFrame, ToolShape};
pub use stamp::{
    rasterize_cost, rasterize_solid, rasterize_solid_in_slabs, solid_density, stamp_sphere, CsgOp,
    RasterCost, SOLID_BAND_VOXELS,
};
pub use stroke::{Stroke, Tool, TICK_S};

#[cfg(test)]
mod tests;
