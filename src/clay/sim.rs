//! A push: the clay of a window of the field, the bodies acting on it, and the fixed-rate
//! simulation steps that run the three layers in order.

use std::time::Instant;

use crate::field::{Colour, Field, FieldReader, DEFAULT_COLOUR};
use crate::math::{IVec3, Pose, VoxelTransform};

use super::body::{Body, ClayTool};
use super::conserve::Conservation;
use super::displace::{Displacement, Groups, Mover};
use super::grid::{write_back, Grid, ALL_DIRS, COVERED, DIRS_UNKNOWN, FIXED, NO_OWNER, WALL};
use super::tension::Tension;

/// The clay's behaviour. The defaults are the paper's where it gives a value.
#[derive(Clone, Debug, PartialEq)]
pub struct ClayParams {
    /// α in [0, 1]: the fraction of a tool's motion the displacement layer transmits to the
    /// clay (§3.1.3). 1 is dry, plastic clay that follows the tool; near 0 the clay is fluid
    /// and the tool mostly sinks into it, leaving prints.
    pub fluidity: f32,
    /// Excess over a cell's capacity that the conservation layer tolerates (§3.2.3: 0.01,
    /// "1.01").
    pub excess_threshold: f32,
    /// Cells the conservation layer may pop per step; the rest carries to the next step.
    pub max_iterations: usize,
    /// Cells under this density are candidates for surface tension (§3.3: 0.3).
    pub tension_density: f32,
    /// The density gradient (per voxel) the surface should keep: a loose cell whose gradient
    /// is weaker gives its matter away. The field's solids have a gradient of
    /// `1 / SOLID_BAND_VOXELS` = 0.25 across their surface; the default 0.1 leaves them alone.
    pub tension_gradient: f32,
    /// Components of at most this many cells at or above the field's iso-level (pieces the
    /// user sees apart from the rest) are crumbs. The paper's "few neighbouring cells" were
    /// cells of a 32³ grid, each worth a few dozen of our finer ones: 64.
    pub crumb_cells: usize,
    /// Whether a removed crumb's matter goes back to the nearest dense cell (mass is then
    /// conserved) or is discarded.
    pub return_crumbs: bool,
    /// Cells under this density are outside the clay for the displacement layer's distances.
    pub min_density: f32,
    /// Simulation step, seconds: [`Clay::advance`] runs one step per `step_s` of time,
    /// whatever the caller's frame rate.
    pub step_s: f32,
    /// The displacement layer passes a tool's motion on to the clay once the tool has
    /// travelled this far (voxels) in contact since it last did. Splatting matter by a small
    /// fraction of a cell smears it a little each time: a tool dragging clay by a tenth of a
    /// cell per step would blur and roughen the surface it drags (the paper's coarse grid
    /// moved by about a cell per step). The conservation and tension layers still run every
    /// step. 0 passes the motion on at every step.
    pub min_travel_voxels: f32,
}

impl Default for ClayParams {
    fn default() -> Self {
        Self {
            fluidity: 1.0,
            excess_threshold: 0.01,
            max_iterations: 300_000,
            tension_density: 0.3,
            tension_gradient: 0.1,
            crumb_cells: 64,
            return_crumbs: true,
            min_density: 0.01,
            step_s: 1.0 / 60.0,
            min_travel_voxels: 1.0,
        }
    }
}

/// Time spent in each part of the steps so far, seconds, and work counts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LayerTimes {
    /// Placing the bodies: footprints, capacities, allowed directions.
    pub bodies_s: f64,
    /// Layer 1, large-scale displacement.
    pub displace_s: f64,
    /// Layer 2, mass conservation.
    pub conserve_s: f64,
    /// Layer 3, surface tension and crumbs.
    pub tension_s: f64,
    /// Steps run.
    pub steps: u64,
    /// Cells popped by the conservation layer.
    pub conserve_pops: u64,
    /// Steps in which the displacement layer moved matter (a tool had travelled far enough).
    pub displacements: u64,
}

/// The virtual clay of one push: a window of the field simulated while tools act on it.
///
/// Create it when a push starts, give it the tools' poses as they move ([`Clay::advance`] at
/// any frame rate, or [`Clay::step`] one step at a time), write it back into the field as
/// often as the mesher should see it ([`Clay::write_to`]), and [`Clay::finish`] it when the
/// push ends. The caller opens one undo stroke around the push, so undo takes it back whole.
#[derive(Debug)]
pub struct Clay {
    grid: Grid,
    transform: VoxelTransform,
    bodies: Vec<Body>,
    params: ClayParams,
    displacement: Displacement,
    conservation: Conservation,
    tension: Tension,
    /// Cells some body covered at the last placement, ascending per body.
    covered: Vec<u32>,
    /// The fixed cells, ascending.
    fixed: Vec<u32>,
    written: Vec<f32>,
    colour: Colour,
    /// The field's iso-level: crumbs are counted in what the user sees.
    iso: f32,
    times: LayerTimes,
    since_step_s: f64,
    /// The poses [`Clay::advance`] was last given (the start of its next interval).
    frame_poses: Vec<Pose>,
}

impl Clay {
    /// Takes lattice points `lo ..= hi` of `field` (see [`super::window_around`]) as the
    /// clay, with `tools` acting on it. Nothing moves until the first step.
    pub fn new(field: &Field, lo: IVec3, hi: IVec3, tools: Vec<ClayTool>, params: ClayParams) -> Self {
        let grid = Grid::load(field, lo, hi);
        let written = grid.density.clone();
        let colour = mean_colour(field, &grid);
        let n = grid.len();
        let mut clay = Self {
            grid,
            transform: *field.transform(),
            bodies: tools.into_iter().map(Body::new).collect(),
            params: sanitised(params),
            displacement: Displacement::new(n),
            conservation: Conservation::default(),
            tension: Tension::default(),
            covered: Vec::new(),
            fixed: Vec::new(),
            written,
            colour,
            iso: field.iso(),
            times: LayerTimes::default(),
            since_step_s: 0.0,
            frame_poses: Vec::new(),
        };
        clay.frame_poses = clay.poses();
        for i in 0..clay.bodies.len() {
            let pose = clay.bodies[i].pose;
            clay.bodies[i].footprint = clay.bodies[i].footprint_at(&clay.grid, &clay.transform, pose);
        }
        clay.place_bodies();
        clay
    }

    /// Holds every lattice point for which `fixed` is true (within the window): its matter
    /// is never displaced, and it anchors the clay like a support (§3.1).
    pub fn fix_where(&mut self, fixed: impl Fn(IVec3) -> bool) {
        for i in 0..self.grid.len() {
            if self.grid.flags[i] & (FIXED | WALL) == 0 && fixed(self.grid.lo + self.grid.coord(i)) {
                self.grid.flags[i] |= FIXED;
                self.fixed.push(i as u32);
            }
        }
    }

    /// Lets support `tool` (an index in the order given) go: from the next step it covers no
    /// cell and holds nothing, as when the hand holding it moves or opens. Tools that push
    /// are left alone. Returns whether the tool was a support still holding.
    pub fn release(&mut self, tool: usize) -> bool {
        let Some(body) = self.bodies.get_mut(tool) else { return false };
        if !body.tool.support || body.footprint.cells.is_empty() {
            return false;
        }
        body.footprint = Default::default();
        self.place_bodies();
        true
    }

    /// The window, lattice points `lo ..= hi`.
    pub fn window(&self) -> (IVec3, IVec3) {
        (self.grid.lo, self.grid.lo + self.grid.dims - IVec3::ONE)
    }

    /// The parameters.
    pub fn params(&self) -> &ClayParams {
        &self.params
    }

    /// Total matter in the window (sum of densities, f64).
    pub fn mass(&self) -> f64 {
        self.grid.mass()
    }

    /// The matter held beyond full cells (densities over 1), which the field, whose
    /// densities stay in [0, 1], does not show until [`Clay::finish`] settles it.
    pub fn excess_mass(&self) -> f64 {
        self.grid.density.iter().map(|&d| f64::from((d - 1.0).max(0.0))).sum()
    }

    /// Density at a lattice point of the window (0 outside it).
    pub fn density(&self, p: IVec3) -> f32 {
        let c = p - self.grid.lo;
        if c.cmplt(IVec3::ZERO).any() || c.cmpge(self.grid.dims).any() {
            return 0.0;
        }
        self.grid.density[self.grid.index(c)]
    }

    /// Every density of the window, x fastest, then y, then z.
    pub fn densities(&self) -> &[f32] {
        &self.grid.density
    }

    /// The current pose of each tool, in the order given.
    pub fn poses(&self) -> Vec<Pose> {
        self.bodies.iter().map(|b| b.pose).collect()
    }

    /// Time spent per layer so far.
    pub fn times(&self) -> LayerTimes {
        self.times
    }

    /// Cells the conservation layer has left for the next step.
    pub fn pending_excess(&self) -> usize {
        self.conservation.pending()
    }

    /// Moves the tools towards `poses` (one per tool, in order; supports ignore theirs) over
    /// `dt_s` seconds, running a step every [`ClayParams::step_s`] of that time at the poses
    /// interpolated then. Time left over carries to the next call. Returns the steps run.
    pub fn advance(&mut self, poses: &[Pose], dt_s: f32) -> usize {
        let from = std::mem::take(&mut self.frame_poses);
        let dt = f64::from(if dt_s.is_finite() { dt_s.max(0.0) } else { 0.0 });
        let step = f64::from(self.params.step_s);
        let mut t = step - self.since_step_s;
        let mut steps = 0;
        while t <= dt + 1e-9 {
            let u = if dt > 0.0 { (t / dt).min(1.0) as f32 } else { 1.0 };
            let at: Vec<Pose> =
                from.iter().enumerate().map(|(i, p)| poses.get(i).map_or(*p, |q| p.lerp(q, u))).collect();
            self.step(&at);
            steps += 1;
            t += step;
        }
        self.since_step_s = (dt - (t - step)).max(0.0);
        self.frame_poses =
            from.iter().enumerate().map(|(i, p)| poses.get(i).copied().unwrap_or(*p)).collect();
        steps
    }

    /// One simulation step: the tools move to `poses` (supports stay), then the three layers
    /// run in order.
    pub fn step(&mut self, poses: &[Pose]) {
        let t0 = Instant::now();
        let mut movers = Vec::new();
        for (i, body) in self.bodies.iter_mut().enumerate() {
            let Some(&to) = poses.get(i) else { continue };
            if body.tool.support || to == body.pose {
                continue;
            }
            let from = body.pose;
            let min = self.params.min_density;
            // The footprint at `to` (needed anyway), and the one kept from the last step at
            // `from`, tell whether the tool touches matter at either end of the step.
            let footprint = body.footprint_at(&self.grid, &self.transform, to);
            let g = &self.grid;
            let holds_matter = |cells: &[u32]| cells.iter().any(|&c| g.density[c as usize] > min);
            if !holds_matter(&footprint.cells) {
                body.untransmitted_from = None;
            } else {
                // The motion counts from the contact (§3.1): bisect for it when the tool
                // was clear of the clay at the start of the step. Motion not yet passed on
                // counts from where it began.
                let start = if let Some(since) = body.untransmitted_from {
                    since
                } else if holds_matter(&body.footprint.cells) {
                    from
                } else {
                    let (mut a, mut b) = (0.0f32, 1.0f32);
                    for _ in 0..8 {
                        let m = 0.5 * (a + b);
                        if body.touches(&self.grid, &self.transform, from.lerp(&to, m), min) {
                            b = m;
                        } else {
                            a = m;
                        }
                    }
                    from.lerp(&to, b)
                };
                let travel = body.travel_m(start, to) / self.transform.voxel_size_m;
                // A thousandth of a cell is allowed for the rounding of interpolated poses, so
                // that a tool travelling exactly a cell is seen to, at any frame rate.
                if travel >= self.params.min_travel_voxels - 1e-3 {
                    movers.push(Mover { body: i as u8, from: start, to });
                    body.untransmitted_from = None;
                } else {
                    body.untransmitted_from = Some(start);
                }
            }
            body.pose = to;
            body.footprint = footprint;
        }
        self.place_bodies();
        let t1 = Instant::now();
        self.displace(&movers);
        self.times.displacements += u64::from(!movers.is_empty());
        let t2 = Instant::now();
        let pops = self.conserve(self.params.excess_threshold, self.params.max_iterations);
        let t3 = Instant::now();
        let p = &self.params;
        self.tension.run(&mut self.grid, p.tension_density, p.tension_gradient);
        self.tension.remove_crumbs(&mut self.grid, self.iso, p.crumb_cells, p.return_crumbs);
        let t4 = Instant::now();
        self.times.bodies_s += (t1 - t0).as_secs_f64();
        self.times.displace_s += (t2 - t1).as_secs_f64();
        self.times.conserve_s += (t3 - t2).as_secs_f64();
        self.times.tension_s += (t4 - t3).as_secs_f64();
        self.times.steps += 1;
        self.times.conserve_pops += pops as u64;
    }

    /// The displacement layer, for `movers`.
    fn displace(&mut self, movers: &[Mover]) {
        let supports: Vec<bool> = self.bodies.iter().map(|b| b.tool.support).collect();
        let groups = Groups { covered: &self.covered, fixed: &self.fixed, supports: &supports };
        let p = &self.params;
        self.displacement.run(&mut self.grid, &self.transform, movers, &groups, p.fluidity, p.min_density);
    }

    /// The conservation layer: queues the cells over capacity by more than `threshold` and
    /// pops at most `max_iterations`. Returns the cells popped.
    fn conserve(&mut self, threshold: f32, max_iterations: usize) -> usize {
        self.conservation.seed(&mut self.grid, threshold);
        let (bodies, transform) = (&self.bodies, &self.transform);
        let outward = |owner: u8, p: IVec3| bodies[owner as usize].outward_dirs_at(transform, p);
        self.conservation.run(&mut self.grid, threshold, max_iterations, outward)
    }

    /// Rebuilds capacities, allowed directions and owners from the bodies' footprints.
    fn place_bodies(&mut self) {
        let g = &mut self.grid;
        for &c in &self.covered {
            let c = c as usize;
            g.capacity[c] = 1.0;
            g.dirs[c] = ALL_DIRS;
            g.owner[c] = NO_OWNER;
            g.flags[c] &= !COVERED;
        }
        self.covered.clear();
        for (b, body) in self.bodies.iter().enumerate() {
            let fp = &body.footprint;
            for (&c, &t) in fp.cells.iter().zip(&fp.density) {
                let c = c as usize;
                if g.owner[c] == NO_OWNER {
                    self.covered.push(c as u32);
                    g.flags[c] |= COVERED;
                }
                if g.owner[c] == NO_OWNER || 1.0 - t < g.capacity[c] {
                    g.capacity[c] = 1.0 - t;
                    g.dirs[c] = DIRS_UNKNOWN;
                    g.owner[c] = b as u8;
                }
            }
        }
    }

    /// Writes the densities that changed since the last write into `field` (clamped to
    /// [0, 1]), marking the bricks dirty. Matter new to a cell takes the clay's mean colour.
    pub fn write_to(&mut self, field: &mut Field) {
        write_back(&self.grid, &mut self.written, field, self.colour);
    }

    /// Ends the push: passes on the tools' motion not yet passed to the clay; lets the tools
    /// go and removes the crumbs they held; settles the excess the conservation layer
    /// tolerated (down to 1e-4 over capacity, the iteration cap lifted), so that clamping to
    /// [0, 1] loses no visible matter; and writes the clay back into `field`.
    pub fn finish(mut self, field: &mut Field) {
        // The tools' last motion not yet passed on to the clay.
        let movers: Vec<Mover> = self
            .bodies
            .iter()
            .enumerate()
            .filter_map(|(i, b)| b.untransmitted_from.map(|from| Mover { body: i as u8, from, to: b.pose }))
            .collect();
        if !movers.is_empty() {
            self.displace(&movers);
        }
        // The tools let go: crumbs they held while working them are loose now, and are eaten.
        for body in &mut self.bodies {
            body.footprint = Default::default();
        }
        self.place_bodies();
        let p = &self.params;
        self.tension.remove_crumbs(&mut self.grid, self.iso, p.crumb_cells, p.return_crumbs);
        let threshold = 1e-4;
        self.conserve(threshold, usize::MAX);
        self.write_to(field);
    }
}

fn sanitised(p: ClayParams) -> ClayParams {
    let finite_or = |v: f32, d: f32| if v.is_finite() { v } else { d };
    let d = ClayParams::default();
    ClayParams {
        fluidity: finite_or(p.fluidity, d.fluidity).clamp(0.0, 1.0),
        excess_threshold: finite_or(p.excess_threshold, d.excess_threshold).max(1e-5),
        tension_density: finite_or(p.tension_density, d.tension_density).clamp(0.0, 1.0),
        tension_gradient: finite_or(p.tension_gradient, d.tension_gradient).max(0.0),
        min_density: finite_or(p.min_density, d.min_density).clamp(1e-4, 1.0),
        step_s: if p.step_s.is_finite() && p.step_s > 0.0 { p.step_s } else { d.step_s },
        min_travel_voxels: finite_or(p.min_travel_voxels, d.min_travel_voxels).max(0.0),
        ..p
    }
}

/// Mass-weighted mean colour of the window's clay.
fn mean_colour(field: &Field, grid: &Grid) -> Colour {
    let mut reader = FieldReader::new(field);
    let mut acc = [0.0f64; 4];
    let mut w = 0.0f64;
    for (i, &d) in grid.density.iter().enumerate() {
        if d > 0.0 && grid.flags[i] & WALL == 0 {
            let c = reader.colour(grid.lo + grid.coord(i));
            for (a, c) in acc.iter_mut().zip(c) {
                *a += f64::from(d) * f64::from(c);
            }
            w += f64::from(d);
        }
    }
    if w > 0.0 {
        acc.map(|a| (a / w) as f32)
    } else {
        DEFAULT_COLOUR
    }
}
