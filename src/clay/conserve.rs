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

use std::collections::VecDeque;

use rayon::prelude::*;

use crate::math::IVec3;

use super::grid::{Grid, ALL_DIRS, COVERED, DIRS_UNKNOWN, QUEUED, WALL};

/// The factor by which a cell overshoots its excess (§3.2.3): what it gives its six
/// neighbours, a sixth comes back.
pub(crate) const OVERSHOOT: f32 = 6.0 / 5.0;

/// The queue of cells that may hold an excess, kept between steps.
#[derive(Debug, Default)]
pub(crate) struct Conservation {
    queue: VecDeque<u32>,
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
        for i in found.into_iter().flatten() {
            grid.flags[i as usize] |= QUEUED;
            self.queue.push_back(i);
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
        let g = grid;
        // Capacities are read only where a body covers the cell; elsewhere they are 1.
        let capacity = |g: &Grid, i: usize| if g.flags[i] & COVERED != 0 { g.capacity[i] } else { 1.0 };
        let mut pops = 0;
        while pops < max_iterations {
            let Some(c) = self.queue.pop_front() else { break };
            pops += 1;
            let c = c as usize;
            g.flags[c] &= !QUEUED;
            let (d, cap) = (g.density[c], capacity(g, c));
            let excess = d - cap;
            if excess <= threshold {
                continue;
            }
            let dirs = if g.flags[c] & COVERED == 0 {
                ALL_DIRS
            } else if g.dirs[c] == DIRS_UNKNOWN {
                let dirs = outward(g.owner[c], g.lo + g.coord(c));
                g.dirs[c] = dirs;
                dirs
            } else {
                g.dirs[c]
            };
            let mut targets = [0usize; 6];
            let mut n = 0;
            for dir in 0..6 {
                if dirs & (1 << dir) == 0 {
                    continue;
                }
                let j = g.neighbour(c, dir);
                let fj = g.flags[j];
                if fj & WALL != 0 || (fj & COVERED != 0 && g.capacity[j] < cap) {
                    continue;
                }
                targets[n] = j;
                n += 1;
            }
            if n == 0 {
                continue;
            }
            let over = if n >= 2 { OVERSHOOT } else { 1.0 };
            let moved = (excess * over).min(d);
            let share = moved / n as f32;
            g.density[c] = if moved >= d { 0.0 } else { d - moved };
            g.mark_around(c);
            for &j in &targets[..n] {
                g.density[j] += share;
                if g.flags[j] & QUEUED == 0 && g.density[j] > capacity(g, j) + threshold {
                    g.flags[j] |= QUEUED;
                    self.queue.push_back(j as u32);
                }
            }
        }
        pops
    }
}
