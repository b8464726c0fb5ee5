//! Layer 3, surface tension (Dewaele–Cani §3.3).
//!
//! Pushed clay spreads into thin, loose matter the user cannot see. A cell under the
//! threshold density (0.3) whose density gradient is weaker than the target gradient, the
//! one the surface should have, gives its matter to its denser neighbours (in proportion to
//! how much denser each is): the clay stays compact, and a stretched neck thins until it
//! parts. Every cell decides from the densities at the start of the layer, so the result does
//! not depend on the order cells are visited in.
//!
//! Crumbs, components of a few above-threshold cells cut off from the rest, are removed, their
//! matter (with the loose matter around them) handed to the nearest dense cell when
//! [`super::ClayParams::return_crumbs`] is on, "as if the crumb had been eaten up by the clay".

use std::collections::VecDeque;

use rayon::prelude::*;

use super::grid::{Grid, FIXED, NO_OWNER, WALL};

/// Density of a cell that takes back a crumb's matter.
const DENSE: f32 = 0.9;

/// Scratch of the tension layer.
#[derive(Debug, Default)]
pub(crate) struct Tension {
    moves: Vec<(u32, [f32; 6])>,
    label: Vec<u32>,
    component: Vec<u32>,
    halo: Vec<u32>,
    search: VecDeque<u32>,
    seen: Vec<u32>,
    epoch: u32,
    /// The last label given (labels are not reused between runs).
    next_label: u32,
}

impl Tension {
    /// Moves loose matter to denser neighbours. Returns the matter moved. Rows that hold no
    /// matter are skipped, and those found empty are unmarked.
    pub fn run(&mut self, grid: &mut Grid, threshold: f32, target_gradient: f32) -> f64 {
        let ny = grid.dims.y as usize;
        let nz = grid.dims.z as usize;
        let mut rows = std::mem::take(&mut grid.rows);
        let g = &*grid;
        let nx = g.dims.x as usize;
        let plane = nx * ny;
        let (sy, sz) = (g.offsets[3] as usize, g.offsets[5] as usize);
        let target2 = target_gradient * target_gradient;
        // One z-plane per task; planes collected in order, so the list is the same whatever
        // the number of threads.
        let planes: Vec<Vec<(u32, [f32; 6])>> = rows
            .par_chunks_mut(ny)
            .enumerate()
            .map(|(z, rows)| {
                let mut out = Vec::new();
                for (y, flag) in rows.iter_mut().enumerate().filter(|(_, f)| **f != 0) {
                    let row = z * plane + y * nx;
                    if g.density[row..row + nx].iter().all(|&d| d <= 0.0) {
                        *flag = 0;
                        continue;
                    }
                    if z == 0 || z == nz - 1 || y == 0 || y == ny - 1 {
                        continue;
                    }
                    for i in row + 1..row + nx - 1 {
                        let d = g.density[i];
                        if !(d > 0.0 && d < threshold) || g.capacity[i] < 1.0 || g.flags[i] & FIXED != 0 {
                            continue;
                        }
                        let gx = g.density[i + 1] - g.density[i - 1];
                        let gy = g.density[i + sy] - g.density[i - sy];
                        let gz = g.density[i + sz] - g.density[i - sz];
                        if 0.25 * (gx * gx + gy * gy + gz * gz) >= target2 {
                            continue;
                        }
                        let mut w = [0.0f32; 6];
                        let mut sum = 0.0;
                        for (dir, wd) in w.iter_mut().enumerate() {
                            let j = g.neighbour(i, dir);
                            let dj = g.density[j];
                            if dj > d && g.flags[j] & WALL == 0 {
                                *wd = dj - d;
                                sum += dj - d;
                            }
                        }
                        if sum > 0.0 {
                            out.push((i as u32, w.map(|x| x / sum * d)));
                        }
                    }
                }
                out
            })
            .collect();
        let g = grid;
        g.rows = rows;
        self.moves.clear();
        for p in planes {
            self.moves.extend(p);
        }
        let mut total = 0.0f64;
        for &(i, shares) in &self.moves {
            let i = i as usize;
            // The cell may already have received from a looser neighbour: it gives what it
            // held at the start of the layer and keeps what arrived since.
            let given: f32 = shares.iter().sum();
            total += f64::from(given);
            g.density[i] = (g.density[i] - given).max(0.0);
            g.mark_around(i);
            for (dir, s) in shares.into_iter().enumerate() {
                if s > 0.0 {
                    let j = g.neighbour(i, dir);
                    g.density[j] += s;
                }
            }
        }
        total
    }

    /// Removes components of at most `max_cells` cells at or above `threshold`, with the
    /// loose matter around them that touches no other dense cell; their matter goes to the
    /// nearest cell of density 0.9 or more when `give_back` is set. Returns the matter
    /// removed (given back or not).
    pub fn remove_crumbs(
        &mut self,
        grid: &mut Grid,
        threshold: f32,
        max_cells: usize,
        give_back: bool,
    ) -> f64 {
        let n = grid.len();
        // Labels grow from run to run; a cell is labelled in this run when its label is
        // above `base`, so the labels need no clearing but on wrapping round.
        if self.label.len() != n || self.next_label > u32::MAX - n as u32 {
            self.label = vec![0; n];
            self.seen = vec![0; n];
            self.next_label = 0;
        }
        let base = self.next_label;
        let mut next_label = base;
        let mut removed = 0.0f64;
        let nx = grid.dims.x as usize;
        let live: Vec<usize> = (0..grid.rows.len()).filter(|&r| grid.rows[r] != 0).collect();
        for start in live.into_iter().flat_map(|r| r * nx..(r + 1) * nx) {
            if self.label[start] > base || grid.density[start] < threshold || grid.flags[start] & WALL != 0 {
                continue;
            }
            next_label += 1;
            // Flood the component; stop counting past the crumb size but finish labelling.
            self.component.clear();
            self.component.push(start as u32);
            self.label[start] = next_label;
            let mut k = 0;
            while k < self.component.len() {
                let c = self.component[k] as usize;
                k += 1;
                for dir in 0..6 {
                    let j = grid.neighbour(c, dir);
                    if self.label[j] <= base && grid.density[j] >= threshold && grid.flags[j] & WALL == 0 {
                        self.label[j] = next_label;
                        self.component.push(j as u32);
                    }
                }
            }
            if self.component.len() > max_cells {
                continue;
            }
            // A crumb held by a tool or fixed stays: it is being worked.
            if self
                .component
                .iter()
                .any(|&c| grid.flags[c as usize] & FIXED != 0 || grid.owner[c as usize] != NO_OWNER)
            {
                continue;
            }
            removed += self.eat(grid, next_label, threshold, give_back);
        }
        self.next_label = next_label;
        removed
    }

    fn eat(&mut self, grid: &mut Grid, label: u32, threshold: f32, give_back: bool) -> f64 {
        // The loose halo: cells under the threshold next to the crumb, touching no other
        // dense cell.
        self.halo.clear();
        for &c in &self.component {
            for dir in 0..6 {
                let j = grid.neighbour(c as usize, dir);
                let d = grid.density[j];
                if d > 0.0 && d < threshold && grid.flags[j] & WALL == 0 && !self.halo.contains(&(j as u32)) {
                    let other_dense = (0..6).any(|e| {
                        let q = grid.neighbour(j, e);
                        grid.density[q] >= threshold && self.label[q] != label
                    });
                    if !other_dense {
                        self.halo.push(j as u32);
                    }
                }
            }
        }
        let mass: f32 = self.component.iter().chain(&self.halo).map(|&c| grid.density[c as usize]).sum();
        let target = if give_back {
            match self.nearest_dense(grid, label) {
                Some(t) => Some(t),
                // Nowhere to give it back to: leave the crumb rather than lose its matter.
                None => return 0.0,
            }
        } else {
            None
        };
        for &c in self.component.iter().chain(&self.halo) {
            grid.density[c as usize] = 0.0;
        }
        if let Some(t) = target {
            grid.density[t] += mass;
            grid.mark_around(t);
        }
        f64::from(mass)
    }

    /// Breadth-first search from the crumb for the nearest dense cell outside it.
    fn nearest_dense(&mut self, grid: &Grid, label: u32) -> Option<usize> {
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.seen.fill(0);
            self.epoch = 1;
        }
        self.search.clear();
        for &c in &self.component {
            self.seen[c as usize] = self.epoch;
            self.search.push_back(c);
        }
        while let Some(c) = self.search.pop_front() {
            for dir in 0..6 {
                let j = grid.neighbour(c as usize, dir);
                if self.seen[j] == self.epoch || grid.flags[j] & WALL != 0 {
                    continue;
                }
                self.seen[j] = self.epoch;
                if grid.density[j] >= DENSE && self.label[j] != label && grid.capacity[j] >= 1.0 {
                    return Some(j);
                }
                self.search.push_back(j as u32);
            }
        }
        None
    }
}
