//! Iso-surface extraction: the clay's surface as per-brick triangle chunks.
//!
//! Owns marching cubes over the field's bricks, the chunk meshes and the diffs the renderer
//! applies. Knows nothing of Vulkan or devices; depends on `math` and `field`.
//!
//! ## Seam contract
//!
//! ```text
//!   lattice points of brick K on one axis:  K·S ... K·S+S−1
//!
//!        apron      brick K cells          apron
//!   K·S−1 |  K·S ─ K·S+1 ─ … ─ K·S+S−1 ─ K·S+S  | K·S+S+1
//!     ▲      └───── cells whose minimum ─────┘      ▲
//!     │            corner is in brick K             │
//!  gradient                                     gradient of the
//!  at K·S                                       far corners K·S+S
//! ```
//!
//! A brick meshes exactly the cells whose minimum corner lies in it, so every cell is meshed
//! by exactly one brick. It reads its samples plus an apron of one below and two above on each
//! axis (far cell corners and central-difference gradients). Vertices on cell edges are
//! interpolated from the lower-index end towards the higher one, in lattice coordinates, so
//! where two bricks' triangles meet they compute bit-identical positions, normals and colours:
//! the union of the chunks is a closed surface once coincident vertices are welded.
//!
//! Normals are the normalised negated field gradient (central differences), interpolated along
//! the edge like the position; colour is interpolated from the samples likewise.
//!
//! ## Incremental meshing
//!
//! [`Mesher`] re-meshes a set of bricks (a stroke's dirty set) into chunk diffs. Bricks whose
//! cells surely hold no triangle are told from the field's per-brick density ranges, without
//! reading a sample, classified on a small grid of the set's box (one range look-up per brick
//! instead of eight); the others are gathered and marched in parallel, each worker with
//! buffers of its own. A mesher kept from call to call reuses every buffer, the chunks of its
//! diff included: its steady state allocates nothing (`tests/mesh_alloc.rs`).
//!
//! ## Resolution levels
//!
//! Each brick is meshed on the coarsest level, up to cells as wide as the brick, under which
//! no finer level holds a brick over what its cells read (`coarse::mesh_level`): clay a tool
//! wrote on a coarse level is meshed on that level's lattice, with a quarter of the triangles
//! per level, while the finest bricks keep the kernel below. Where levels meet, the coarse
//! cells conform to the finer ones: a coarse cell's face toward a finer brick is cut into that
//! brick's squares, and its edges along a finer brick (across a face, or along an edge only)
//! into that brick's edges; the surface on such a cell is traced on those faces with the case
//! table's own rule, so both sides draw the same segments through the same vertices, and the
//! welded surface is closed (see the `coarse` module). No transition cell thicker than a face,
//! no restriction on the ratio of levels between neighbours.
//!
//! Where a finest brick is meshed next to coarse clay, the bricks its block reads from the
//! coarser levels are made by interpolation, once per mesher call, in parallel, for all the
//! finest bricks of the call that read them (each was otherwise made again for every
//! neighbour, up to 27 times); a brick is told empty or full, like a stored one, from the
//! range of the coarse samples its interpolation reads. Those bricks, and a coarse level's
//! samples where they are read through a coarser level, are allocated per call: the
//! no-allocation steady state holds for clay of one level, the finest or a coarse one
//! (`tests/mesh_alloc.rs`).
//!
//! The kernel classifies the brick's 9³ cell corners once, as one bit per corner in rows along
//! x, so that a cell's case is a few shifts and rows of cells the surface does not cross are
//! skipped whole.

mod cases;
mod coarse;
pub mod export;
mod march;
mod mesher;
mod types;
mod weld;

pub use cases::{case_table, CORNER_OFFSETS, EDGES};
pub use coarse::{levels_around, march_coarse, mesh_level, CoarseScratch, MAX_MESH_LEVEL};
pub use march::{march_brick, Block, MarchScratch, Neighbourhood, BLOCK, BLOCK_VOLUME, CROSSING_MARGIN};
pub use mesher::{gather_block, mesh_all, mesh_brick, meshable_bricks, remesh, remesh_dirty, Mesher};
pub use types::*;
pub use weld::{weld, SurfaceMeshes, WeldedMesh};
