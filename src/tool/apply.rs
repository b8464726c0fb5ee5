//! Applying a tool once (one stamp) at a pose: the per-sample pipeline and its counters.
//!
//! The walk follows Ferley et al. (1999, §3.2, Fig. 6–7): every lattice point of the tool's
//! world bounding box is **visited**; those inside the tool's oriented local box are
//! **computed** (the potential is evaluated there, in the tool's frame); those whose density
//! or colour changed are **dirtied**. Lattice points map to the local frame by one affine map
//! stepped along the rows, so a rotated or scaled tool costs no resampling.

use std::ops::AddAssign;

use super::action::Action;
use super::shape::Solid;
use super::shapes::ToolFrame;
use super::shapes::ToolShape;
use super::stamp::{mix_in, Ball, SOLID_BAND_VOXELS};
use super::stroke::Tool;
use crate::field::{brick_key, lattice_points, stores_differently, whole_rows, Colour, Field, LEVELS};
use crate::math::{IVec3, Pose, Vec3};

/// Work done by one stamp (or a sum of stamps), as in Ferley et al.'s performance table.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StampCounters {
    /// Lattice points of the tool's world bounding box.
    pub visited: u64,
    /// Points inside the tool's oriented box, where the potential was evaluated.
    pub computed: u64,
    /// Points whose density or colour changed.
    pub dirtied: u64,
    /// Bricks whose samples the stamp walked.
    pub bricks: u64,
    /// Resolution level the stamp wrote (0: the finest; see [`edit_level_for`]).
    pub level: u32,
}

impl AddAssign for StampCounters {
    fn add_assign(&mut self, o: Self) {
        self.visited += o.visited;
        self.computed += o.computed;
        self.dirtied += o.dirtied;
        self.bricks += o.bricks;
        self.level = self.level.max(o.level);
    }
}

/// A bound on the samples of its level across a tool's size (a sphere's radius, see
/// [`Tool::size_m`]) for tools that edit by their size ([`Tool::level_samples`]): the cost of
/// a stamp then stays about that of a tool this many samples across, whatever its size.
pub const MAX_SIZE_SAMPLES: f32 = 8.0;

/// The bound on a hand tool's samples across its size (see [`Tool::level_samples`]) where its
/// scene tool sets none: in the station and the headset, a tool spanning up to 32 voxels of
/// the finest level edits it, a larger one the level its size chooses.
///
/// On the finest level a stamp's field work grows with the cube of the tool's size, and so do
/// the bricks it stores and the undo history it fills: the field of a stroke of 30 stamps of
/// a 40 mm ball on 1 mm voxels takes 5.8 MB there and 1.2 MB on level 1; of an 80 mm one,
/// 24 MB there and 1.2 MB on level 2. The re-mesh takes back what a coarse level saves in
/// time, for the mesher makes the finest bricks of coarse clay by interpolation and meshes
/// them on the finest lattice: of the bounds 8, 16 and 32, this one keeps stamp and re-mesh
/// within about a tenth of the finest level's time (above it for a 40 mm tool, below for an
/// 80 mm one: `argile bench hand-tools`, BENCHMARKS.md), and the finest level for the tools
/// that shape detail.
pub const HAND_SIZE_SAMPLES: f32 = 32.0;

/// The level a tool of size `size_m` (metres) edits when it may span at most `samples`
/// voxels of it: the finest such level, or the coarsest.
pub fn edit_level_for(field: &Field, size_m: f32, samples: f32) -> usize {
    let across = field.transform().metres_to_voxels(size_m);
    (0..LEVELS).find(|&l| across <= samples * (1u32 << l) as f32).unwrap_or(LEVELS - 1)
}

/// The lattice box a tool at `frame` may change, and the geometry to evaluate it.
struct Footprint {
    lo: IVec3,
    hi: IVec3,
    /// Local position of lattice point `lo`, and the local step per lattice unit on each axis.
    origin: Vec3,
    step: [Vec3; 3],
    /// Half size of the local box where the potential can be non-zero.
    local_half: Vec3,
    /// Ramp width across hard edges, in the local frame.
    band_local: f32,
}

fn footprint(field: &Field, level: usize, tool: &Tool, frame: &ToolFrame) -> Footprint {
    footprint_banded(field, level, level, tool, frame)
}

/// [`footprint`] on `level`'s lattice for the tool band-limited on `band_level`'s.
fn footprint_banded(
    field: &Field,
    level: usize,
    band_level: usize,
    tool: &Tool,
    frame: &ToolFrame,
) -> Footprint {
    let t = field.level_transform(level);
    let h = t.voxel_size_m;
    let band_h = field.level_transform(band_level).voxel_size_m;
    let band_m = match tool.action {
        Action::Stamp { falloff_m, .. } => falloff_m.max(SOLID_BAND_VOXELS * band_h),
        _ => SOLID_BAND_VOXELS * band_h,
    };
    let band_local = band_m / frame.min_scale();
    let mut local_half = tool.shape.half_extents_m();
    if tool.shape.is_hard_edged() {
        local_half += Vec3::splat(0.5 * band_local);
    }
    let world = frame.world_bounds(local_half);
    let lo = t.world_to_index(world.min).ceil().as_ivec3();
    let hi = t.world_to_index(world.max).floor().as_ivec3();
    let origin = frame.world_to_local(t.index_to_world(lo.as_vec3()));
    let step = [Vec3::X, Vec3::Y, Vec3::Z].map(|axis| frame.world_vector_to_local(axis * h));
    Footprint { lo, hi, origin, step, local_half, band_local }
}

/// A dense copy of density and colour over `lo − 1 ..= hi + 1` of the level edited, for
/// actions that read neighbours: they read the values before the stamp, whatever order the
/// walk writes in.
struct Snapshot {
    lo: IVec3,
    dims: IVec3,
    density: Vec<f32>,
    colour: Vec<Colour>,
}

impl Snapshot {
    fn take(field: &Field, level: usize, lo: IVec3, hi: IVec3) -> Self {
        let (lo, hi) = (lo - IVec3::ONE, hi + IVec3::ONE);
        let dims = hi - lo + IVec3::ONE;
        let mut samples = Vec::new();
        field.level_samples(level, lo, hi, &mut samples);
        let (density, colour) = samples.into_iter().unzip();
        Self { lo, dims, density, colour }
    }

    #[inline]
    fn index(&self, p: IVec3) -> usize {
        let q = p - self.lo;
        (q.x + self.dims.x * (q.y + self.dims.y * q.z)) as usize
    }

    /// Density at `p` and at its six neighbours (−x, +x, −y, +y, −z, +z).
    #[inline]
    fn neighbourhood(&self, p: IVec3) -> (f32, [f32; 6]) {
        let i = self.index(p);
        let (sx, sy) = (1, self.dims.x as usize);
        let sz = sy * self.dims.y as usize;
        let d = &self.density;
        (d[i], [d[i - sx], d[i + sx], d[i - sy], d[i + sy], d[i - sz], d[i + sz]])
    }

    /// Density-weighted mean colour of the six neighbours (the sample's own when they are
    /// empty).
    fn neighbour_colour(&self, p: IVec3) -> Colour {
        let i = self.index(p);
        let (sy, sz) = (self.dims.x as usize, (self.dims.x * self.dims.y) as usize);
        let mut acc = [0.0f32; 4];
        let mut w = 0.0;
        for j in [i - 1, i + 1, i - sy, i + sy, i - sz, i + sz] {
            let dj = self.density[j];
            for (a, c) in acc.iter_mut().zip(self.colour[j]) {
                *a += dj * c;
            }
            w += dj;
        }
        if w > 0.0 {
            acc.map(|a| a / w)
        } else {
            self.colour[i]
        }
    }
}

#[inline]
fn lerp_colour(c: &mut Colour, to: Colour, t: f32) {
    for (a, b) in c.iter_mut().zip(to) {
        *a += (b - *a) * t;
    }
}

/// Applies `tool` once at `pose`; rate-based actions act for `dt_s` seconds (per-stamp
/// actions ignore it). Returns the stamp's counters.
///
/// A uniformly scaled sphere adding or removing matter takes a sphere-only path that gives the
/// same clay as [`super::stamp_sphere`] with fewer operations per sample.
///
/// The stamp edits the finest level, or with [`Tool::level_samples`] the level its size
/// chooses ([`edit_level_for`]), band-limited on that
/// level's lattice; finer detail under it rides along (see [`Field::edit_level`]). Actions
/// that read the neighbours (smoothing, inflation) edit no coarser than the finest clay under
/// the tool.
pub fn apply_tool(field: &mut Field, tool: &Tool, pose: Pose, dt_s: f32) -> StampCounters {
    apply_tool_mirrored(field, tool, pose, false, dt_s)
}

/// [`apply_tool`] of the tool's mirror image when `mirrored` (the pose as
/// [`crate::math::Isometry::pose`] gives it): an asymmetric shape acts reflected.
pub fn apply_tool_mirrored(
    field: &mut Field,
    tool: &Tool,
    pose: Pose,
    mirrored: bool,
    dt_s: f32,
) -> StampCounters {
    let frame = ToolFrame::with_mirror(pose, tool.scale, mirrored);
    let level = tool.level_samples.map_or(0, |n| edit_level_for(field, tool.size_m(), n));
    if let (ToolShape::Solid(Solid::Sphere { radius_m }), Action::Add | Action::Remove) =
        (&tool.shape, tool.action)
    {
        if tool.scale.x == tool.scale.y && tool.scale.y == tool.scale.z {
            return sphere_fast_path(field, level, *radius_m * tool.scale.x, tool, pose);
        }
    }
    let mut fp = footprint(field, level, tool, &frame);
    // Smoothing and inflation move the surface by what its ramp looks like on the level they
    // edit: they edit no coarser than the finest clay under them, whose ramp that level holds.
    let finest =
        if tool.action.reads_neighbours() { field.finest_level_under(level, fp.lo, fp.hi) } else { level };
    let level = if finest < level {
        fp = footprint(field, finest, tool, &frame);
        finest
    } else {
        level
    };
    let mut counters = StampCounters { level: level as u32, ..Default::default() };
    if fp.lo.cmpgt(fp.hi).any() {
        return counters;
    }
    let snapshot = tool.action.reads_neighbours().then(|| Snapshot::take(field, level, fp.lo, fp.hi));
    let dt_s = if dt_s.is_finite() { dt_s.max(0.0) } else { 0.0 };
    let inv_h = 1.0 / field.level_transform(level).voxel_size_m;
    let kernel = Kernel {
        action: tool.action,
        shape: &tool.shape,
        colour: tool.colour,
        dt_s,
        inv_h,
        snapshot: snapshot.as_ref(),
    };
    let mut walk = Walked { counters: &mut counters, last_brick: None };
    if level == 0 || tool.action.reads_neighbours() {
        let create = tool.action.may_create();
        field.edit_level(
            level,
            fp.lo,
            fp.hi,
            create,
            |_, _, _| true,
            |p, d, c| kernel.apply(&fp, p, d, c, &mut walk),
        );
        return counters;
    }
    // A coarse level, then the finer bricks under it, each on its own lattice: the tool keeps
    // the coarse level's band (the same tool in metres everywhere), and the fine clay keeps
    // its own edges where the tool does not reach.
    field.edit_level_alone(
        level,
        fp.lo,
        fp.hi,
        tool.action.may_create(),
        |_, _, _| true,
        whole_rows,
        |p, d, c| kernel.apply(&fp, p, d, c, &mut walk),
    );
    for finer in (0..level).rev() {
        if field.level_brick_count(finer) == 0 {
            continue;
        }
        let fine = footprint_banded(field, finer, level, tool, &frame);
        walk.last_brick = None;
        field.edit_stored(finer, fine.lo, fine.hi, |p, d, c| kernel.apply(&fine, p, d, c, &mut walk));
    }
    counters
}

/// What one stamp does at a sample, on any level's lattice.
struct Kernel<'a> {
    action: Action,
    shape: &'a ToolShape,
    colour: Colour,
    dt_s: f32,
    /// Lattice units per metre of the level edited (for speeds).
    inv_h: f32,
    snapshot: Option<&'a Snapshot>,
}

/// The counters of a walk, and the brick it last counted.
struct Walked<'a> {
    counters: &'a mut StampCounters,
    last_brick: Option<IVec3>,
}

impl Kernel<'_> {
    /// Applies the stamp at lattice point `p` of the footprint's lattice.
    #[inline]
    fn apply(&self, fp: &Footprint, p: IVec3, d: &mut f32, c: &mut Colour, walk: &mut Walked<'_>) {
        walk.counters.visited += 1;
        let brick = brick_key(p);
        if walk.last_brick != Some(brick) {
            walk.last_brick = Some(brick);
            walk.counters.bricks += 1;
        }
        let q = (p - fp.lo).as_vec3();
        let local = fp.origin + fp.step[0] * q.x + fp.step[1] * q.y + fp.step[2] * q.z;
        if local.abs().cmpgt(fp.local_half).any() {
            return;
        }
        walk.counters.computed += 1;
        let t = self.shape.potential(local, fp.band_local);
        if t <= 0.0 {
            return;
        }
        let (old_d, old_c) = (*d, *c);
        match self.action {
            Action::Push | Action::Support => {}
            Action::Add => {
                let new = d.max(t);
                mix_in(c, *d, new, self.colour);
                *d = new;
            }
            Action::Remove => *d = d.min(1.0 - t),
            Action::SoftRemove { rate_per_s } => *d = (*d - rate_per_s * self.dt_s * t).clamp(0.0, 1.0),
            Action::Build { rate_per_s } => {
                let new = (*d + rate_per_s * self.dt_s * t).clamp(0.0, 1.0);
                mix_in(c, *d, new, self.colour);
                *d = new;
            }
            Action::Paint => lerp_colour(c, self.colour, t),
            Action::SoftPaint { rate_per_s } => {
                lerp_colour(c, self.colour, (rate_per_s * self.dt_s * t).clamp(0.0, 1.0))
            }
            Action::Smooth { centre_weight, rate_per_s } => {
                let s = self.snapshot.expect("smoothing takes a snapshot");
                let (own, n) = s.neighbourhood(p);
                let w = centre_weight.clamp(4.0, 24.0);
                let avg = (w * own + n.iter().sum::<f32>()) / (w + 6.0);
                let alpha = (rate_per_s * self.dt_s).clamp(0.0, 1.0) * t;
                let new = (own + alpha * (avg - own)).clamp(0.0, 1.0);
                if new > *d {
                    mix_in(c, *d, new, s.neighbour_colour(p));
                }
                *d = new;
            }
            Action::Stamp { deformation, .. } => {
                let new = (*d + deformation.contribution(t)).clamp(0.0, 1.0);
                mix_in(c, *d, new, self.colour);
                *d = new;
            }
            Action::Inflate { speed_m_per_s } | Action::Deflate { speed_m_per_s } => {
                let s = self.snapshot.expect("inflation takes a snapshot");
                let (own, n) = s.neighbourhood(p);
                let outwards = matches!(self.action, Action::Inflate { .. });
                let grad = upwind_gradient(own, n, outwards);
                let step = speed_m_per_s.max(0.0) * self.inv_h * self.dt_s * t * grad;
                let mut new = if outwards { own + step } else { own - step }.clamp(0.0, 1.0);
                // The ramp's ends creep a voxel per tick at vanishing amounts; an empty sample
                // stays empty, and a full one full, until the change is meaningful.
                if (own == 0.0 && new < MIN_LEVEL_CHANGE) || (own == 1.0 && new > 1.0 - MIN_LEVEL_CHANGE) {
                    new = own;
                }
                if new > *d {
                    mix_in(c, *d, new, s.neighbour_colour(p));
                }
                *d = new;
            }
        }
        if !d.is_finite() {
            *d = old_d;
        }
        if stores_differently(old_d, *d) || *c != old_c {
            walk.counters.dirtied += 1;
        }
    }
}

/// The least change inflation or deflation makes to an empty or a full sample (1/1024).
const MIN_LEVEL_CHANGE: f32 = 1.0 / 1024.0;

/// `|∇d|` per lattice unit by Godunov's upwind differences (Osher–Sethian): a surface moving
/// outwards takes each axis's difference from the denser side, one moving inwards from the
/// emptier side, so the update neither oscillates nor smears the ramp.
#[inline]
fn upwind_gradient(own: f32, n: [f32; 6], outwards: bool) -> f32 {
    let mut g2 = 0.0;
    for axis in 0..3 {
        let (lo, hi) = (n[2 * axis], n[2 * axis + 1]);
        let g = if outwards { (lo - own).max(hi - own) } else { (own - lo).max(own - hi) }.max(0.0);
        g2 += g * g;
    }
    g2.sqrt()
}

/// The sphere's add/remove kernel: the arithmetic of [`stamp_sphere`] (distances in lattice
/// units from the centre, no frame to map through), so both give bit-identical clay, plus the
/// counters. On the finest level it walks what [`stamp_sphere`] walks: the bricks and the
/// parts of rows within the ball's reach (the rest of its box it leaves as it is).
fn sphere_fast_path(
    field: &mut Field,
    level: usize,
    radius_m: f32,
    tool: &Tool,
    pose: Pose,
) -> StampCounters {
    let mut counters = StampCounters { level: level as u32, ..Default::default() };
    let add = tool.action == Action::Add;
    // The sphere in `level`'s voxels (its band's), applied on the lattice of level `on`, whose
    // point p sits at p / scale of them.
    let stamp = |field: &mut Field, on: usize, counters: &mut StampCounters| {
        let transform = field.level_transform(level);
        let ball = Ball::new(transform.world_to_index(pose.position_m), transform.metres_to_voxels(radius_m));
        let scale = (1u32 << (level - on)) as f32;
        let (lo, hi) = ball.bounds(scale);
        counters.visited += lattice_points(lo, hi) as u64;
        let mut kernel = SphereKernel {
            ball,
            inv_scale: 1.0 / scale,
            add,
            colour: tool.colour,
            counters,
            last_brick: None,
        };
        // Within the ball's reach; a full brick stays full when adding. Each walk below gets
        // a closure of its own around the kernel, which it inlines.
        let within = move |a, b, range: Option<(f32, f32)>| {
            ball.reaches(a, b) && !(add && range.is_some_and(|r: (f32, f32)| r.0 >= 1.0))
        };
        let rows = move |y, z| ball.row(y, z);
        if level == 0 {
            // What `edit_level` does on the finest level.
            field.edit_where(lo, hi, add, within, rows, |p, d, c| kernel.apply(p, d, c));
        } else if on == level {
            // Over finer clay the level takes its values at every point of the box first.
            let alone = (0..level).all(|l| field.level_brick_count(l) == 0);
            let changes = move |a, b, range| !alone || within(a, b, range);
            field.edit_level_alone(level, lo, hi, add, changes, rows, |p, d, c| kernel.apply(p, d, c));
        } else {
            field.edit_stored(on, lo, hi, |p, d, c| kernel.apply(p, d, c));
        }
    };
    stamp(field, level, &mut counters);
    // The finer bricks under a coarse stamp, each on its own lattice (see `apply_tool`).
    for on in (0..level).rev() {
        if field.level_brick_count(on) > 0 {
            stamp(field, on, &mut counters);
        }
    }
    counters
}

/// The sphere's kernel at one point of a lattice `1 / inv_scale` times finer than its ball's,
/// and its counters.
struct SphereKernel<'c> {
    ball: Ball,
    inv_scale: f32,
    add: bool,
    colour: Colour,
    counters: &'c mut StampCounters,
    last_brick: Option<IVec3>,
}

impl SphereKernel<'_> {
    #[inline(always)]
    fn apply(&mut self, p: IVec3, d: &mut f32, c: &mut Colour) {
        self.counters.computed += 1;
        let brick = brick_key(p);
        if self.last_brick != Some(brick) {
            self.last_brick = Some(brick);
            self.counters.bricks += 1;
        }
        let tool = self.ball.density_at(p.as_vec3() * self.inv_scale);
        let old = *d;
        if self.add {
            let new = d.max(tool);
            mix_in(c, *d, new, self.colour);
            *d = new;
        } else {
            *d = d.min(1.0 - tool);
        }
        if stores_differently(old, *d) {
            self.counters.dirtied += 1;
        }
    }
}
