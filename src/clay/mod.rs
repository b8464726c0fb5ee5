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
//!
//! ## Where this departs from the paper, and why
//!
//! - Pseudo-distances are computed by a Dijkstra whose queue is a list of unit-wide buckets
//!   (every step costs at least 1, a full cell's 1/density): exact, in linear time, without a
//!   heap (`displace`; `bucketed_distances_equal_dijkstras` checks it against a heap). The
//!   static group's distance and each moving tool's run side by side.
//! - Several moving tools (both hands pushing): each tool's share is the paper's two-tool
//!   blend against the nearest other group (static or moving), and the shares add. With one
//!   moving tool this is exactly the paper's formula.
//! - The tool's motion counts from the contact, found by bisection within the step (the
//!   paper's "exact time of the collision").
//! - Matter never moves into a cell covered more deeply by a body than its own: with the
//!   60° rule alone, matter pushed out of a tool's rim could be pushed back into it by the
//!   next cell, and the two would trade it forever.
//! - The tolerated excess is settled when the push ends, so the field, whose densities stay
//!   in [0, 1], loses no matter to clamping.
//! - Crumbs are counted at the field's iso-level, the surface the user sees (the paper counts
//!   "above-threshold" cells; its threshold, 0.3, would let a visible speck hang on the body
//!   by a thread of invisible matter).
//! - Colour is not carried with the matter: cells that fill up take the window's mean colour.
//! - The displacement layer passes a tool's motion on once the tool has travelled a cell in
//!   contact since it last did ([`ClayParams::min_travel_voxels`]), not at every step: the
//!   paper's 32³ grid moved by about a cell per step, ours by a tenth of one, and the
//!   trilinear splat smears matter a little each time it moves it by a fraction of a cell, so
//!   a slow push roughened the clay it dragged (visible ripples on a bent bar). The other two
//!   layers run every step; the motion left when the push ends is passed on by
//!   [`Clay::finish`].
//! - The active window is one dense array per quantity, not a set of per-brick buffers.
//!   Every layer walks the six neighbours of a cell (each pop of the conservation queue,
//!   each step of a distance): in a dense window a neighbour is one index offset, with no
//!   brick lookup and, thanks to the wall, no bounds test. The window covers only the
//!   tools and the clay connected to them, with a margin (`window_around`), so it holds the
//!   cells the paper's grid would. The second buffer is the densities last written to the
//!   field: the write-back compares against it and edits only the bricks that differ. The
//!   price is memory for the whole window, empty cells included: 43 bytes a cell with one
//!   moving tool (densities, capacities, flags, owners, directions, the written copy, two
//!   distances, a step and two crumb labels), 90 MB for a 128³ window.

//!
//! ## Where the time goes, and what is skipped
//!
//! The work that is skipped changes no result (the same bits as doing it all):
//! - rows of cells along X that hold no matter (the grid's row marks, set by every layer that
//!   puts matter in a cell) are left out of the scans for excess, loose matter and crumbs;
//! - a body's footprint skips the cells a solid's distance clears along each row, outside it
//!   and deep inside it (those are fully covered); the outward directions of a covered cell
//!   are found the first time the conservation layer moves matter out of it;
//! - whether a moving tool touches the clay at either end of a step is read from its
//!   footprints there, not from another sweep of its box;
//! - the pseudo-distances ask whether a cell is a barrier only of covered or fixed cells; the
//!   displacement's per-cell steps are computed in parallel chunks gathered in order;
//! - the conservation queue is a ring whose push is conditional without a branch (whether a
//!   neighbour joins the queue was a coin toss for the branch predictor, and cost two
//!   mispredictions a pop), and a full cell's distance cost is `1 / min(ρ, 1)`, not a branch.

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
