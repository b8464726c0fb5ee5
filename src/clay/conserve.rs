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

use super::grid::{Grid, QUEUED, WALL};

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
    /// in index order. Planes are searched in parallel and queued in order.
    pub fn seed(&mut self, grid: &mut Grid, threshold: f32) {
        let g: &Grid = grid;
        let plane = (g.dims.x * g.dims.y) as usize;
        let found: Vec<Vec<u32>> = g
            .density
            .par_chunks(plane)
            .zip(g.capacity.par_chunks(plane))
            .zip(g.flags.par_chunks(plane))
            .enumerate()
            .map(|(z, ((d, cap), flags))| {
                let mut out = Vec::new();
                for i in 0..d.len() {
                    if d[i] > cap[i] + threshold && flags[i] & (QUEUED | WALL) == 0 {
                        out.push((z * plane + i) as u32);
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

    /// Pops at most `max_iterations` cells, moving their excess. Returns the cells popped.
    pub fn run(&mut self, grid: &mut Grid, threshold: f32, max_iterations: usize) -> usize {
        let mut pops = 0;
        while pops < max_iterations {
            let Some(c) = self.queue.pop_front() else { break };
            pops += 1;
            let c = c as usize;
            grid.flags[c] &= !QUEUED;
            let (d, cap) = (grid.density[c], grid.capacity[c]);
            let excess = d - cap;
            if excess <= threshold {
                continue;
            }
            let dirs = grid.dirs[c];
            let mut targets = [0usize; 6];
            let mut n = 0;
            for dir in 0..6 {
                if dirs & (1 << dir) == 0 {
                    continue;
                }
                let j = grid.neighbour(c, dir);
                if grid.flags[j] & WALL != 0 || grid.capacity[j] < cap {
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
            grid.density[c] = if moved >= d { 0.0 } else { d - moved };
            for &j in &targets[..n] {
                grid.density[j] += share;
                if grid.density[j] > grid.capacity[j] + threshold && grid.flags[j] & QUEUED == 0 {
                    grid.flags[j] |= QUEUED;
                    self.queue.push_back(j as u32);
                }
            }
        }
        pops
    }
}
