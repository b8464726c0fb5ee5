//! Layer 1, large-scale displacement (Dewaele–Cani §3.1).
//!
//! From the cells a body covers, a pseudo-distance spreads through the clay: entering a cell
//! costs `1 / density` (a full cell costs 1), so influence falls fastest through thin, weak
//! clay, where tears should start. It stops at the clay's border (cells under
//! [`super::ClayParams::min_density`]), at fixed cells and at cells covered by other bodies,
//! which it reaches but does not cross. The static group (every support and the fixed cells)
//! gets one such distance `d2`, each moving tool its own `d1`. With `d12` the least `d1` of a
//! cell attached to another group, a cell moves by
//!
//! ```text
//!   k = (d1 − d2) / d12  (clamped to [−1, 1]),   δ = (1 − k)/2 · α δ1 + (1 + k)/2 · δ2,
//! ```
//!
//! with `δ2 = 0` for the static group and `δ1` the tool's rigid motion since it touched the
//! clay (§3.1.1, §3.1.3). Its matter is then put at `x + δ`, split trilinearly over the eight
//! surrounding cells (§3.1.2).
//!
//! Every step costs at least 1, so the distances are computed by a bucketed Dijkstra whose
//! buckets are unit intervals of distance: a cell popped from bucket `b` can only improve
//! cells into bucket `b + 1` or later, so each bucket's cells are final when it is reached
//! and may be expanded in any order. The result equals Dijkstra's, in linear time, without
//! a heap; the bucket order is fixed, so it is deterministic.

use rayon::prelude::*;

use crate::math::{IVec3, Pose, Vec3, VoxelTransform};

use super::grid::{Grid, COVERED, FIXED, NO_OWNER, WALL};

/// One pseudo-distance over the grid, with the cells it reached (to reset them cheaply).
#[derive(Debug, Default)]
pub(crate) struct Distance {
    pub dist: Vec<f32>,
    pub reached: Vec<u32>,
    buckets: Vec<Vec<u32>>,
    /// The least distance at which a cell attached to another group was reached.
    pub to_others: f32,
}

impl Distance {
    pub fn new(cells: usize) -> Self {
        Self {
            dist: vec![f32::INFINITY; cells],
            reached: Vec::new(),
            buckets: Vec::new(),
            to_others: f32::INFINITY,
        }
    }

    fn reset(&mut self) {
        for &i in &self.reached {
            self.dist[i as usize] = f32::INFINITY;
        }
        self.reached.clear();
        self.to_others = f32::INFINITY;
    }

    /// Spreads the distance from `seeds` (distance 0). `is_barrier(i)`: the cell is reached
    /// (at cost 1) but not crossed, and counts towards [`Distance::to_others`]; it is asked
    /// only of cells a body covers or that are fixed (no other cell is a barrier).
    pub fn propagate(
        &mut self,
        grid: &Grid,
        seeds: impl Iterator<Item = usize>,
        min_density: f32,
        is_barrier: impl Fn(usize) -> bool,
    ) {
        self.reset();
        for b in &mut self.buckets {
            b.clear();
        }
        if self.buckets.is_empty() {
            self.buckets.push(Vec::new());
        }
        for s in seeds {
            if self.dist[s] > 0.0 {
                self.dist[s] = 0.0;
                self.reached.push(s as u32);
                self.buckets[0].push(s as u32);
            }
        }
        // Local slices: the compiler keeps their addresses in registers instead of reloading
        // them after every store of a distance.
        let Self { dist, reached, buckets, to_others } = self;
        let dist = &mut dist[..];
        let (density, flags, offsets) = (&grid.density[..], &grid.flags[..], &grid.offsets);
        let mut b = 0;
        while b < buckets.len() {
            let mut bucket = std::mem::take(&mut buckets[b]);
            for &c in &bucket {
                let c = c as usize;
                let dc = dist[c];
                if dc as usize != b {
                    continue; // improved since it was queued
                }
                if dc > 0.0 && flags[c] & (COVERED | FIXED) != 0 && is_barrier(c) {
                    *to_others = to_others.min(dc);
                    continue;
                }
                for &offset in offsets {
                    let n = c.wrapping_add_signed(offset);
                    let f = flags[n];
                    if f & WALL != 0 {
                        continue;
                    }
                    let cost = if f & (COVERED | FIXED) != 0 && is_barrier(n) {
                        1.0
                    } else {
                        let rho = density[n];
                        if rho < min_density {
                            continue;
                        }
                        // A full cell costs exactly 1 (1 / 1 is 1: the same sums), without a
                        // branch on whether the cell is full.
                        1.0 / rho.min(1.0)
                    };
                    let nd = dc + cost;
                    let old = dist[n];
                    if nd < old {
                        if old == f32::INFINITY {
                            reached.push(n as u32);
                        }
                        dist[n] = nd;
                        let nb = nd as usize;
                        if nb >= buckets.len() {
                            buckets.resize_with(nb + 1, Vec::new);
                        }
                        buckets[nb].push(n as u32);
                    }
                }
            }
            bucket.clear();
            // Give the (empty) allocation back for the next propagation.
            buckets[b] = bucket;
            b += 1;
        }
    }
}

/// A moving tool's part in this step: its group, and the rigid motion of the step.
pub(crate) struct Mover {
    /// Index of the body (its cells carry this owner).
    pub body: u8,
    /// Pose when the motion counted from (the contact, if it happened during the step).
    pub from: Pose,
    /// Pose at the end of the step.
    pub to: Pose,
}

/// Where the groups' seeds are: the cells the bodies cover (each once), the fixed cells, and
/// which bodies are supports.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Groups<'a> {
    pub covered: &'a [u32],
    pub fixed: &'a [u32],
    pub supports: &'a [bool],
}

/// Scratch of the displacement layer, kept between steps.
#[derive(Debug, Default)]
pub(crate) struct Displacement {
    movers: Vec<Distance>,
    fixed: Distance,
    delta: Vec<Vec3>,
    moved: Vec<u32>,
    amount: Vec<f32>,
}

impl Displacement {
    pub fn new(cells: usize) -> Self {
        Self { fixed: Distance::new(cells), delta: vec![Vec3::ZERO; cells], ..Default::default() }
    }

    /// Runs the layer: moves the matter of every cell connected to a moving tool.
    /// `support(owner)` says whether a body index is a support. Returns the matter moved.
    pub fn run(
        &mut self,
        grid: &mut Grid,
        transform: &VoxelTransform,
        movers: &[Mover],
        groups: &Groups<'_>,
        fluidity: f32,
        min_density: f32,
    ) -> f64 {
        let Groups { covered, fixed, supports } = *groups;
        let support = |o: u8| supports.get(o as usize).copied().unwrap_or(false);
        if movers.is_empty() {
            return 0.0;
        }
        while self.movers.len() < movers.len() {
            self.movers.push(Distance::new(grid.len()));
        }
        let g: &Grid = grid;
        let is_fixed = |i: usize| g.flags[i] & FIXED != 0;
        // The static group: supports and fixed cells; moving tools' cells stop it. Seeds
        // come from the bodies' footprints and the fixed list, never from a scan of the grid.
        let static_seeds = covered
            .iter()
            .map(|&c| c as usize)
            .filter(|&i| g.owner[i] != NO_OWNER && support(g.owner[i]))
            .chain(fixed.iter().map(|&c| c as usize));
        // The distances are independent of each other: each group's runs on its own thread
        // (each propagation is sequential, so the result does not depend on the threads).
        let (fixed_dist, mover_dists) = (&mut self.fixed, &mut self.movers[..movers.len()]);
        rayon::join(
            || {
                fixed_dist.propagate(g, static_seeds, min_density, |i| {
                    g.flags[i] & (COVERED | FIXED) == COVERED && !support(g.owner[i])
                })
            },
            || {
                mover_dists.par_iter_mut().zip(movers).for_each(|(dist, m)| {
                    let seeds =
                        covered.iter().map(|&c| c as usize).filter(|&i| g.owner[i] == m.body && !is_fixed(i));
                    dist.propagate(g, seeds, min_density, |i| {
                        let f = g.flags[i];
                        f & FIXED != 0 || (f & COVERED != 0 && g.owner[i] != m.body)
                    });
                })
            },
        );
        // δ per reached cell, summed over the moving tools.
        self.moved.clear();
        let h = transform.voxel_size_m;
        for (mi, m) in movers.iter().enumerate() {
            let (d1, held, all) = (&self.movers[mi], &self.fixed, &self.movers[..movers.len()]);
            let d12 = d1.to_others;
            // A tool that only translates moves every cell by the same vector.
            let translation =
                (m.from.rotation == m.to.rotation).then(|| (m.to.position_m - m.from.position_m) / h);
            // Each cell's step depends on the distances only: chunks of cells run in parallel
            // and are gathered in order, so the sums below do not depend on the threads.
            let step_of = |c: usize| -> Option<Vec3> {
                if g.flags[c] & (FIXED | WALL) != 0 || g.density[c] <= 0.0 {
                    return None;
                }
                if g.owner[c] != NO_OWNER && g.owner[c] != m.body {
                    return None;
                }
                // The nearest other group: the static one or another moving tool.
                let mut d2 = held.dist[c];
                for (mj, other) in all.iter().enumerate() {
                    if mj != mi {
                        d2 = d2.min(other.dist[c]);
                    }
                }
                let k = if d12.is_finite() && d2.is_finite() {
                    ((d1.dist[c] - d2) / d12).clamp(-1.0, 1.0)
                } else {
                    -1.0
                };
                let weight = 0.5 * (1.0 - k) * fluidity;
                if weight <= 0.0 {
                    return None;
                }
                let motion = match translation {
                    Some(t) => t,
                    None => {
                        let p = transform.index_to_world((g.lo + g.coord(c)).as_vec3());
                        let rigid = m.to.position_m
                            + m.to.rotation * (m.from.rotation.inverse() * (p - m.from.position_m));
                        (rigid - p) / h
                    }
                };
                Some(motion * weight)
            };
            let steps: Vec<(u32, Vec3)> = d1
                .reached
                .par_chunks(1 << 12)
                .flat_map_iter(|chunk| chunk.iter().filter_map(|&c| step_of(c as usize).map(|s| (c, s))))
                .collect();
            for (c, step) in steps {
                let c = c as usize;
                if self.delta[c] == Vec3::ZERO {
                    self.moved.push(c as u32);
                }
                self.delta[c] += step;
            }
        }
        // Take the matter out of every moving cell before any lands, so each cell moves what
        // it held at the start of the layer.
        self.amount.clear();
        let mut total = 0.0f64;
        for &c in &self.moved {
            let c = c as usize;
            self.amount.push(grid.density[c]);
            total += f64::from(grid.density[c]);
            grid.density[c] = 0.0;
        }
        let hi = (grid.dims - IVec3::splat(2)).as_vec3();
        for (&c, &q) in self.moved.iter().zip(&self.amount) {
            let c = c as usize;
            let dest = (grid.coord(c).as_vec3() + self.delta[c]).clamp(Vec3::ONE, hi - Vec3::splat(1e-3));
            self.delta[c] = Vec3::ZERO;
            let base = dest.floor();
            let f = dest - base;
            let bc = base.as_ivec3();
            let b = grid.index(bc);
            let (r, ny) = ((bc.y + grid.dims.y * bc.z) as usize, grid.dims.y as usize);
            for row in [r, r + 1, r + ny, r + ny + 1] {
                grid.rows[row] = 1;
            }
            let (sy, sz) = (grid.offsets[3] as usize, grid.offsets[5] as usize);
            let w = [1.0 - f.x, f.x];
            let wy = [1.0 - f.y, f.y];
            let wz = [1.0 - f.z, f.z];
            for (dz, wz) in wz.iter().enumerate() {
                for (dy, wy) in wy.iter().enumerate() {
                    let row = b + dz * sz + dy * sy;
                    let qzy = q * wz * wy;
                    grid.density[row] += qzy * w[0];
                    grid.density[row + 1] += qzy * w[1];
                }
            }
        }
        total
    }
}
