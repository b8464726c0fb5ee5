//! The rigid bodies that act on the clay: tools that push, supports that hold, a table.
//!
//! A body is a density `T` in [0, 1] over space (the tool's potential, band-limited across
//! hard edges as everywhere in the tool module): a cell covered by `T` has room for `1 − T`
//! of clay (Dewaele–Cani §3.2.2: "a tool of density 0.8 leaves room for 0.2"). Matter inside
//! a body may only leave it outwards: along the axis directions within 60° of the gradient
//! of a distance to the body's surface, i.e. where the normalised gradient's component
//! exceeds ½ (cos 60°). That distance is analytic for the solids and ellipsoids; for a
//! freeform tool, whose copied densities saturate at 1 inside, it is the depth below the
//! surface found by propagation from the tool's edges inwards, computed once per tool when
//! the push starts (§3.2.2).

use rayon::prelude::*;

use crate::math::{IVec3, Pose, UVec3, Vec3, VoxelTransform};
use crate::tool::{Falloff, Freeform, ToolFrame, ToolShape, SOLID_BAND_VOXELS};

use super::grid::{Grid, ALL_DIRS};

/// The shape of a body acting on the clay.
#[derive(Clone, Debug, PartialEq)]
pub enum ClayShape {
    /// A tool shape scaled along its local axes (the tool module's shapes).
    Tool {
        /// The shape in its local frame.
        shape: ToolShape,
        /// Scale along the local X, Y and Z axes.
        scale: Vec3,
    },
    /// A table: the half-space below the plane through the pose's position, whose normal is
    /// the pose's local +Y (the side the clay rests on).
    Plane,
}

/// A body acting on the clay: a moving tool or a static support.
#[derive(Clone, Debug, PartialEq)]
pub struct ClayTool {
    /// Its shape.
    pub shape: ClayShape,
    /// Where it starts.
    pub pose: Pose,
    /// A support: held still, whatever poses the simulation is given for it; its cells anchor
    /// the clay (displacement 0) until it is let go ([`super::Clay::release`]).
    pub support: bool,
    /// A mirror image of the tool (a symmetry's image): its poses read local X negated
    /// (see [`ToolFrame::mirrored`]).
    pub mirrored: bool,
}

impl ClayTool {
    /// A moving tool.
    pub fn pusher(shape: ToolShape, scale: Vec3, pose: Pose) -> Self {
        Self { shape: ClayShape::Tool { shape, scale }, pose, support: false, mirrored: false }
    }

    /// A static support of a tool's shape.
    pub fn support(shape: ToolShape, scale: Vec3, pose: Pose) -> Self {
        Self { shape: ClayShape::Tool { shape, scale }, pose, support: true, mirrored: false }
    }

    /// A table under the clay: the plane through `point_m` facing up (+Y), a support.
    pub fn table(point_m: Vec3) -> Self {
        Self {
            shape: ClayShape::Plane,
            pose: Pose { position_m: point_m, ..Pose::default() },
            support: true,
            mirrored: false,
        }
    }
}

/// Depth below a freeform tool's surface, per copied sample (the inward propagation of
/// §3.2.2: the pseudo-distance without its 1/density term).
#[derive(Debug)]
struct Depth {
    dims: IVec3,
    spacing_m: f32,
    depth: Vec<f32>,
}

impl Depth {
    fn of(tool: &Freeform) -> Self {
        let dims = tool.dims().max(UVec3::ONE).as_ivec3();
        let half = tool.half_extents_m();
        let spacing_m = if dims.x > 1 { 2.0 * half.x / (dims.x - 1) as f32 } else { 1.0 };
        let centre = (dims.as_vec3() - Vec3::ONE) * 0.5;
        let n = (dims.x * dims.y * dims.z) as usize;
        let index = |c: IVec3| (c.x + dims.x * (c.y + dims.y * c.z)) as usize;
        let mut depth = vec![f32::INFINITY; n];
        let mut frontier = Vec::new();
        for z in 0..dims.z {
            for y in 0..dims.y {
                for x in 0..dims.x {
                    let c = IVec3::new(x, y, z);
                    let v = tool.potential((c.as_vec3() - centre) * spacing_m);
                    if v < 0.5 {
                        depth[index(c)] = 0.0;
                        frontier.push(c);
                    } else if c.cmpeq(IVec3::ZERO).any() || c.cmpeq(dims - IVec3::ONE).any() {
                        // The copy's border counts as the tool's edge.
                        depth[index(c)] = 1.0;
                        frontier.push(c);
                    }
                }
            }
        }
        // Breadth-first: every step inwards costs one sample.
        let mut next = Vec::new();
        while !frontier.is_empty() {
            for &c in &frontier {
                let d = depth[index(c)] + 1.0;
                for o in super::grid::NEIGHBOURS {
                    let q = c + o;
                    if q.cmpge(IVec3::ZERO).all() && q.cmplt(dims).all() && depth[index(q)] > d {
                        depth[index(q)] = d;
                        next.push(q);
                    }
                }
            }
            std::mem::swap(&mut frontier, &mut next);
            next.clear();
        }
        Self { dims, spacing_m, depth }
    }

    /// Trilinear depth at a local point (0 outside the copy).
    fn at(&self, local_m: Vec3) -> f32 {
        let index = local_m / self.spacing_m + (self.dims.as_vec3() - Vec3::ONE) * 0.5;
        crate::math::trilinear(index, |q| {
            if q.cmplt(IVec3::ZERO).any() || q.cmpge(self.dims).any() {
                0.0
            } else {
                self.depth[(q.x + self.dims.x * (q.y + self.dims.y * q.z)) as usize]
            }
        })
    }
}

/// The cells a body covers in the grid at one pose, with the body's density there. The
/// directions matter may leave each cell by are found when the conservation layer first needs
/// them ([`Body::outward_dirs_at`]): most covered cells hold no matter.
#[derive(Clone, Debug, Default)]
pub(crate) struct Footprint {
    /// Linear cell indices, ascending.
    pub cells: Vec<u32>,
    /// The body's density at each cell, in (0, 1].
    pub density: Vec<f32>,
}

/// A body prepared for the simulation.
#[derive(Debug)]
pub(crate) struct Body {
    pub tool: ClayTool,
    /// Inward depth of a freeform tool, computed once.
    depth: Option<Depth>,
    /// The current pose and its footprint.
    pub pose: Pose,
    pub footprint: Footprint,
    /// The pose from which the tool's motion in contact with the clay has not yet been
    /// passed on to it (see [`super::ClayParams::min_travel_voxels`]).
    pub untransmitted_from: Option<Pose>,
}

impl Body {
    pub fn new(tool: ClayTool) -> Self {
        let depth = match &tool.shape {
            ClayShape::Tool { shape: ToolShape::Freeform(f), .. } => Some(Depth::of(f)),
            _ => None,
        };
        let pose = tool.pose;
        Self { tool, depth, pose, footprint: Footprint::default(), untransmitted_from: None }
    }

    /// The body's density at a world point and a signed distance-like value whose gradient
    /// points out of the body (world metres for the analytic shapes).
    #[inline]
    fn sample(&self, frame: &ToolFrame, band_local: f32, world_m: Vec3) -> (f32, f32) {
        match &self.tool.shape {
            ClayShape::Plane => {
                let n = frame.pose.rotation * Vec3::Y;
                let d = n.dot(world_m - frame.pose.position_m);
                (ramp(d, band_local), d)
            }
            ClayShape::Tool { shape: ToolShape::Solid(s), .. } => {
                let d = s.signed_distance(frame.world_to_local(world_m));
                (ramp(d, band_local), d)
            }
            ClayShape::Tool { shape, .. } => {
                let local = frame.world_to_local(world_m);
                let t = shape.potential(local, band_local);
                let outward = match shape {
                    ToolShape::Solid(s) => s.signed_distance(local),
                    ToolShape::Ellipsoid(e) => match e.falloff {
                        Falloff::Box => e.signed_distance(local),
                        Falloff::Wyvill => e.normalised_radius(local),
                    },
                    ToolShape::Freeform(_) => {
                        let depth = self.depth.as_ref().map_or(0.0, |d| d.at(local));
                        -(depth + t)
                    }
                };
                (t, outward)
            }
        }
    }

    /// How far (world metres) a point whose outward value is `outward` surely is from every
    /// point the body covers, for the shapes whose outward value bounds the distance to
    /// their surface from below (solids, planes); `None` for the others.
    #[inline]
    fn clearance_m(&self, frame: &ToolFrame, band_local: f32, outward: f32) -> Option<f32> {
        match &self.tool.shape {
            ClayShape::Plane => Some(outward - 0.5 * band_local),
            ClayShape::Tool { shape: ToolShape::Solid(_), .. } => {
                Some((outward - 0.5 * band_local) * frame.min_scale())
            }
            ClayShape::Tool { .. } => None,
        }
    }

    /// How far (world metres) inside the band a point whose outward value is `outward` surely
    /// is, for the same shapes: every point that near is covered fully (density 1).
    #[inline]
    fn depth_m(&self, frame: &ToolFrame, band_local: f32, outward: f32) -> Option<f32> {
        self.clearance_m(frame, band_local, -outward)
    }

    fn frame(&self, pose: Pose) -> ToolFrame {
        match &self.tool.shape {
            ClayShape::Tool { scale, .. } => ToolFrame::with_mirror(pose, *scale, self.tool.mirrored),
            ClayShape::Plane => ToolFrame::new(pose, Vec3::ONE),
        }
    }

    /// How far (world metres) a point of the body moves at most between poses `a` and `b`:
    /// the translation, plus the rotation's arc at the body's outermost point.
    pub fn travel_m(&self, a: Pose, b: Pose) -> f32 {
        let reach = match &self.tool.shape {
            ClayShape::Tool { shape, scale } => (shape.half_extents_m() * *scale).length(),
            ClayShape::Plane => 0.0,
        };
        let angle = 2.0 * a.rotation.dot(b.rotation).abs().min(1.0).acos();
        a.position_m.distance(b.position_m) + angle * reach
    }

    /// The width of the band across the body's surface, in its local frame.
    fn band_local(&self, frame: &ToolFrame, transform: &VoxelTransform) -> f32 {
        let band_m = SOLID_BAND_VOXELS * transform.voxel_size_m;
        match &self.tool.shape {
            ClayShape::Plane => band_m,
            ClayShape::Tool { .. } => band_m / frame.min_scale(),
        }
    }

    /// The lattice box (inclusive, clipped to the grid's interior) the body can cover at
    /// `pose`, and the band width in its local frame.
    fn reach(&self, grid: &Grid, transform: &VoxelTransform, pose: Pose) -> (IVec3, IVec3, f32) {
        let frame = self.frame(pose);
        let band_local = self.band_local(&frame, transform);
        let interior = (grid.lo + IVec3::ONE, grid.lo + grid.dims - IVec3::splat(2));
        match &self.tool.shape {
            ClayShape::Plane => (interior.0, interior.1, band_local),
            ClayShape::Tool { shape, .. } => {
                let mut half = shape.half_extents_m();
                if shape.is_hard_edged() {
                    half += Vec3::splat(0.5 * band_local);
                }
                let world = frame.world_bounds(half);
                let lo = transform.world_to_index(world.min).ceil().as_ivec3().max(interior.0);
                let hi = transform.world_to_index(world.max).floor().as_ivec3().min(interior.1);
                (lo, hi, band_local)
            }
        }
    }

    /// The cells the body covers at `pose`. Planes of the box are evaluated in parallel and
    /// gathered in order, so the result does not depend on the number of threads.
    pub fn footprint_at(&self, grid: &Grid, transform: &VoxelTransform, pose: Pose) -> Footprint {
        let (lo, hi, band_local) = self.reach(grid, transform, pose);
        let mut fp = Footprint::default();
        if lo.cmpgt(hi).any() {
            return fp;
        }
        let frame = self.frame(pose);
        let planes: Vec<Vec<(u32, f32)>> = (lo.z..=hi.z)
            .into_par_iter()
            .map(|z| {
                let mut out = Vec::new();
                for y in lo.y..=hi.y {
                    let mut x = lo.x;
                    while x <= hi.x {
                        let p = IVec3::new(x, y, z);
                        x += 1;
                        let w = transform.index_to_world(p.as_vec3());
                        let (t, outward) = self.sample(&frame, band_local, w);
                        if t <= 0.0 {
                            // Where the outward value bounds the distance, the cells it
                            // clears along the row cannot be covered either.
                            if let Some(clear_m) = self.clearance_m(&frame, band_local, outward) {
                                x += (clear_m / transform.voxel_size_m).floor().max(0.0) as i32;
                            }
                            continue;
                        }
                        let i = grid.index(p - grid.lo) as u32;
                        out.push((i, t.min(1.0)));
                        if t >= 1.0 {
                            // Likewise, the cells that deep inside along the row are covered
                            // fully (a hundredth of a cell is kept for rounding).
                            if let Some(deep_m) = self.depth_m(&frame, band_local, outward) {
                                let k = ((deep_m / transform.voxel_size_m) - 0.01).floor().max(0.0) as i32;
                                let k = k.min(hi.x - x + 1);
                                out.extend((1..=k as u32).map(|j| (i + j, 1.0)));
                                x += k;
                            }
                        }
                    }
                }
                out
            })
            .collect();
        for (c, t) in planes.into_iter().flatten() {
            fp.cells.push(c);
            fp.density.push(t);
        }
        fp
    }

    /// The directions matter may leave lattice point `p` by, under the body at its current
    /// pose: those within 60° of the gradient of its outward distance (§3.2.2).
    pub fn outward_dirs_at(&self, transform: &VoxelTransform, p: IVec3) -> u8 {
        let frame = self.frame(self.pose);
        let band_local = self.band_local(&frame, transform);
        let w = transform.index_to_world(p.as_vec3());
        let eps = 0.5 * transform.voxel_size_m;
        // Central differences of the outward distance, in world space: they are symmetric,
        // so a freeform tool's stepped depth gives no slant.
        let diff = |axis: Vec3| {
            self.sample(&frame, band_local, w + axis * eps).1
                - self.sample(&frame, band_local, w - axis * eps).1
        };
        outward_dirs(Vec3::new(diff(Vec3::X), diff(Vec3::Y), diff(Vec3::Z)))
    }

    /// Whether the body at `pose` covers a cell holding matter (more than `min_density`).
    pub fn touches(&self, grid: &Grid, transform: &VoxelTransform, pose: Pose, min_density: f32) -> bool {
        let (lo, hi, band_local) = self.reach(grid, transform, pose);
        if lo.cmpgt(hi).any() {
            return false;
        }
        let frame = self.frame(pose);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let p = IVec3::new(x, y, z);
                    if grid.density[grid.index(p - grid.lo)] > min_density
                        && self.sample(&frame, band_local, transform.index_to_world(p.as_vec3())).0 > 0.0
                    {
                        return true;
                    }
                }
            }
        }
        false
    }
}

#[inline]
fn ramp(distance_m: f32, band_m: f32) -> f32 {
    (0.5 - distance_m / band_m).clamp(0.0, 1.0)
}

/// The axis directions within 60° of `g` (all of them where `g` vanishes, at a body's centre).
pub(crate) fn outward_dirs(g: Vec3) -> u8 {
    let len = g.length();
    if len <= 1e-12 {
        return ALL_DIRS;
    }
    let n = g / len;
    let mut bits = 0u8;
    for (axis, c) in [n.x, n.y, n.z].into_iter().enumerate() {
        if c < -0.5 {
            bits |= 1 << (2 * axis);
        }
        if c > 0.5 {
            bits |= 1 << (2 * axis + 1);
        }
    }
    bits
}
