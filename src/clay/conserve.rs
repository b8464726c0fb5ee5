//! Layer 2, mass conservation (Dewaele–Cani §3.2).
//!
//! A cell holding more than its capacity (1, or `1 − T` under a body of density `T`) plus a
//! threshold (0.01: "1.01") hands the excess to its neighbours, which pass on what they cannot
//! hold, until the matter reaches room at the clay's border: prints sink, rims rise. The cells
//! that may hold an excess wait in a first-in-first-out queue, each at most once (a flag per
//! cell). The layer stops when the queue is empty or after an iteration cap; what is left stays
//! in the cells and the queue, and is finished at the next step: no matter is ever lost.
//!
//! Matter leaves a cell only along its allowed directions (outwards from a body, within 60° of
//! its distance gradient: see `body`), never into a cell that a body covers more deeply, so a
//! tool pushes matter ahead of it and none goes through it (§3.2.2). A cell moves `6/5` of its
//! excess, because a sixth of what it gives to full neighbours comes back (§3.2.3).

use rayon::prelude::*;

use crate::math::IVec3;

use super::grid::{cell_coord, mark_rows_around, Grid, ALL_DIRS, COVERED, DIRS_UNKNOWN, QUEUED, WALL};

/// The factor by which a cell overshoots its excess (§3.2.3): what it gives its six
/// neighbours, a sixth comes back.
pub(crate) const OVERSHOOT: f32 = 6.0 / 5.0;

/// The queue of cells that may hold an excess, kept between steps.
#[derive(Debug, Default)]
pub(crate) struct Conservation {
    queue: Fifo,
}

/// A first-in-first-out ring of cell indices whose push can be conditional without a branch:
/// whether a neighbour joins the queue depends on its density and is a coin toss for the
/// branch predictor, so the index is always written at the tail and the length grows by the
/// condition.
#[derive(Debug, Default)]
struct Fifo {
    /// A power-of-two number of slots (or none).
    ring: Vec<u32>,
    head: usize,
    len: usize,
}

impl Fifo {
    fn len(&self) -> usize {
        self.len
    }

    /// Makes room for `extra` more cells, keeping their order.
    #[inline(always)]
    fn reserve(&mut self, extra: usize) {
        if self.len + extra > self.ring.len() {
            self.grow(extra);
        }
    }

    #[cold]
    #[inline(never)]
    fn grow(&mut self, extra: usize) {
        let slots = (self.len + extra).next_power_of_two().max(1024);
        let mut ring = Vec::with_capacity(slots);
        ring.extend((0..self.len).map(|k| self.ring[(self.head + k) & (self.ring.len() - 1)]));
        ring.resize(slots, 0);
        (self.ring, self.head) = (ring, 0);
    }

    #[inline]
    fn pop(&mut self) -> Option<u32> {
        if self.len == 0 {
            return None;
        }
        let c = self.ring[self.head];
        self.head = (self.head + 1) & (self.ring.len() - 1);
        self.len -= 1;
        Some(c)
    }

    /// Appends `c` if `keep`; needs a free slot (see [`Fifo::reserve`]).
    #[inline]
    fn push_if(&mut self, c: u32, keep: bool) {
        let mask = self.ring.len() - 1;
        self.ring[(self.head + self.len) & mask] = c;
        self.len += usize::from(keep);
    }
}

impl Conservation {
    /// Queues every cell over its capacity by more than `threshold` that is not queued yet,
    /// in index order. Planes are searched in parallel and queued in order; rows that hold no
    /// matter are skipped.
    pub fn seed(&mut self, grid: &mut Grid, threshold: f32) {
        let g: &Grid = grid;
        let nx = g.dims.x as usize;
        let plane = nx * g.dims.y as usize;
        let found: Vec<Vec<u32>> = (0..g.dims.z as usize)
            .into_par_iter()
            .map(|z| {
                let mut out = Vec::new();
                for (y, _) in g.rows[z * g.dims.y as usize..][..g.dims.y as usize]
                    .iter()
                    .enumerate()
                    .filter(|(_, &r)| r != 0)
                {
                    let row = z * plane + y * nx;
                    for i in row..row + nx {
                        if g.density[i] > g.capacity[i] + threshold && g.flags[i] & (QUEUED | WALL) == 0 {
                            out.push(i as u32);
                        }
                    }
                }
                out
            })
            .collect();
        self.queue.reserve(found.iter().map(Vec::len).sum());
        for i in found.into_iter().flatten() {
            grid.flags[i as usize] |= QUEUED;
            self.queue.push_if(i, true);
        }
    }

    /// Cells still waiting.
    pub fn pending(&self) -> usize {
        self.queue.len()
    }

    /// Pops at most `max_iterations` cells, moving their excess. `outward(owner, p)` gives the
    /// directions matter may leave lattice point `p` by under body `owner`, for the covered
    /// cells whose directions are not known yet. Returns the cells popped.
    pub fn run(
        &mut self,
        grid: &mut Grid,
        threshold: f32,
        max_iterations: usize,
        outward: impl Fn(u8, IVec3) -> u8,
    ) -> usize {
        // The grid's arrays as local slices: the compiler then keeps their addresses in
        // registers instead of reloading them after every store of a density.
        let (lo, dims, offsets) = (grid.lo, grid.dims, grid.offsets);
        let Grid { density, capacity, dirs: allowed, owner, flags, rows, .. } = grid;
        let (density, flags, allowed, rows) =
            (&mut density[..], &mut flags[..], &mut allowed[..], &mut rows[..]);
        let (capacity, owner) = (&capacity[..], &owner[..]);
        // Capacities are read only where a body covers the cell; elsewhere they are 1.
        let capacity_of = |f: u8, i: usize| if f & COVERED != 0 { capacity[i] } else { 1.0 };
        let mut pops = 0;
        while pops < max_iterations {
            let Some(c) = self.queue.pop() else { break };
            pops += 1;
            let c = c as usize;
            let fc = flags[c] & !QUEUED;
            flags[c] = fc;
            let (d, cap) = (density[c], capacity_of(fc, c));
            let excess = d - cap;
            if excess <= threshold {
                continue;
            }
            let dirs = if fc & COVERED == 0 {
                ALL_DIRS
            } else if allowed[c] == DIRS_UNKNOWN {
                let dirs = outward(owner[c], lo + cell_coord(dims, c));
                allowed[c] = dirs;
                dirs
            } else {
                allowed[c]
            };
            // The neighbours that may take matter, gathered without a branch per direction.
            let mut targets = [0usize; 6];
            let mut n = 0;
            for (dir, &offset) in offsets.iter().enumerate() {
                let j = c.wrapping_add_signed(offset);
                let fj = flags[j];
                let blocked = fj & WALL != 0 || (fj & COVERED != 0 && capacity[j] < cap);
                targets[n] = j;
                n += usize::from(dirs & (1 << dir) != 0 && !blocked);
            }
            if n == 0 {
                continue;
            }
            let over = if n >= 2 { OVERSHOOT } else { 1.0 };
            let moved = (excess * over).min(d);
            let share = moved / n as f32;
            density[c] = if moved >= d { 0.0 } else { d - moved };
            mark_rows_around(rows, dims, c);
            self.queue.reserve(n);
            for &j in &targets[..n] {
                let dj = density[j] + share;
                density[j] = dj;
                let fj = flags[j];
                let join = (fj & QUEUED == 0) & (dj > capacity_of(fj, j) + threshold);
                flags[j] = fj | (QUEUED * u8::from(join));
                self.queue.push_if(j as u32, join);
            }
        }
        pops
    }
}

#[cfg(test)]
mod tests {
    use super::Fifo;
    use std::collections::VecDeque;

    /// The ring keeps first-in-first-out order through wrap-arounds and growth while wrapped,
    /// and a push whose condition is false leaves it as it was.
    #[test]
    fn the_ring_is_a_fifo_through_wraps_and_growth() {
        let (mut ring, mut model) = (Fifo::default(), VecDeque::new());
        let mut state = 0x2545_f491_u32;
        for round in 0..20_000u32 {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            // Bursts of pushes then of pops, so the front moves round the ring and the ring
            // grows while its cells wrap past its end.
            let pushing = (round / 700) % 3 != 2;
            if pushing || state % 4 == 0 {
                ring.reserve(1);
                let keep = state % 3 != 0;
                ring.push_if(round, keep);
                if keep {
                    model.push_back(round);
                }
            } else {
                assert_eq!(ring.pop(), model.pop_front());
            }
            assert_eq!(ring.len(), model.len());
        }
        while let Some(c) = model.pop_front() {
            assert_eq!(ring.pop(), Some(c));
        }
        assert_eq!(ring.pop(), None);
    }
}
