//! The clay: a sparse density + colour field.
//!
//! Owns bricks, sampling, the dirty set the mesher drains, and the undo/redo history. Knows nothing of tools,
//! meshes or Vulkan; depends only on `math`.
//!
//! Invariants:
//! - density is in [0, 1]; 1 is full clay, the surface is the iso-level (default 0.5); the
//!   stored values are samples of a band-limited characteristic function (Galyean–Hughes), so
//!   a surface sits between samples with sub-voxel precision;
//! - colour is linear RGBA per sample;
//! - the field has [`LEVELS`] resolution levels, voxel sizes doubling from the finest; a point
//!   of a level without a brick reads the coarser levels, and a point no level holds is empty
//!   (density 0) (see the `levels` module);
//! - a brick's colours are stored once while its matter has one colour, per sample otherwise;
//!   a brick of one value throughout (solid inside) is a constant tile shared by every key that
//!   holds it (see [`Brick`] and [`Field`]);
//! - after every edit, the dirty set holds every brick whose mesh reads a changed sample.

mod brick;
mod dense;
mod history;
mod levels;
mod plan;
mod sample;
mod tree;

pub use brick::{
    brick_key, dequantize, lattice_points, quantize, split_index, stores_differently, Brick, BrickColours,
    BrickKey, Colour, LevelKey, Quantum, BRICK_SIZE, BRICK_VOLUME, DEFAULT_COLOUR, DENSITY_ONE,
    DENSITY_TOLERANCE, LEVELS, MESHED_LEVELS,
};
pub use dense::{DenseCopy, Holds, Span, TiledCopy, TiledReader};
pub use history::{HistoryConfig, HistoryError, HistoryStats, BRICK_BYTES};
pub use levels::{COLOUR_DETAIL_TOLERANCE, DETAIL_TOLERANCE};
pub use plan::{bricks_over, BrickPlan, Fill, PlanStats};
pub use sample::FieldReader;

/// The finest voxel sizes a field may have, metres: from 0.1 mm (a 20 cm figure is then 2 000
/// voxels across) to 5 cm. Scenes and sculpt files outside it are refused, so that no file
/// sets the clay at a scale whose work never ends.
pub const VOXEL_SIZE_RANGE_M: std::ops::RangeInclusive<f32> = 1e-4..=0.05;
pub use tree::{bricks_reading, whole_rows, DirtySet, Field, HistoryStep, Ranges};
