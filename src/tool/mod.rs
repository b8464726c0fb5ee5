//! Tools and the solids of the initial clay, and how they write into the field.
//!
//! Owns tool shapes, actions and band-limited stamping. Knows nothing of devices or Vulkan;
//! depends on `math` and `field`.

mod shape;
mod stamp;
mod stroke;

pub use shape::{PlacedSolid, Solid};
pub use stamp::{rasterize_solid, solid_density, stamp_sphere, Action, CsgOp, SOLID_BAND_VOXELS};
pub use stroke::{Stroke, Tool};
