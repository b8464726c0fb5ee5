//! Virtual clay: the plastic, mass-conserving deformation of Dewaele and Cani (2003, §3).
//!
//! Owns the three layers that move matter when tools push the clay, and the supports that
//! hold it. Depends on `math`, `field` (its public API) and `tool` (shapes and frames); knows
//! nothing of meshes, devices or Vulkan.
//!
//! ```text
//!  Field ──load window──► ClayGrid (dense, one cell per lattice point, a wall layer around)
//!                           │  each fixed step, in this order:
//!                           │   1. displacement  pseudo-distances from the moving tool and the
//!                           │                    supports (+1/density per cell), blended by
//!                           │                    k = (d1 − d2)/d12, δ = (1−k)/2·αδ1 + (1+k)/2·δ2,
//!                           │                    matter splatted trilinearly at x + δ
//!                           │   2. conservation  excess over the capacity (1 − tool density)
//!                           │                    pushed to the six neighbours through a FIFO
//!                           │   3. tension       loose low-density cells give their matter to
//!                           │                    denser neighbours; crumbs are eaten back
//!  Field ◄──write back─────┘  (changed bricks only, marked dirty; one undo stroke per push)
//! ```
//!
//! Invariants: matter (the sum of densities) is conserved by every layer, except for crumbs
//! removed with [`ClayParams::return_crumbs`] off; no density is ever negative or NaN; the
//! result of a step depends only on the grid, the tools and the parameters, never on the
//! number of threads. While a push runs, cells may hold slightly more than 1 (the
//! conservation layer's threshold, and work carried to the next step); the field only ever
//! receives densities clamped to [0, 1], and [`Clay::finish`] settles the excess first.

mod body;
mod conserve;
mod displace;
mod grid;
mod sim;
mod tension;

pub use body::{ClayShape, ClayTool};
pub use grid::window_around;
pub use sim::{Clay, ClayParams, LayerTimes};

#[cfg(test)]
mod tests;
