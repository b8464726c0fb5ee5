//! Regions of the clay and the tools that act on them (Hua–Qin §4.4): copy and compose, move
//! and turn, bend, inflate and deflate.
//!
//! A [`Region`] is a shape placed in the world: a box, or a tool's own shape. Its potential
//! `w` (1 inside, 0 outside, a ramp [`SOLID_BAND_VOXELS`] wide across a hard edge) weighs each
//! sample's share, so a region cut through the clay leaves band-limited faces, never a
//! staircase. Hua and Qin change a trivariate patch's coefficients; here the clay is
//! resampled through the motion `M` of the hand that carries the region:
//!
//! ```text
//!   move:  d'(x) = max(d(x)·(1 − w(x)),  w(q)·d(q)),  q = M⁻¹(x)   what it leaves is empty,
//!   copy:  d'(x) = max(d(x),             w(q)·d(q))                 what it lands on unites
//!   bend:  d'(x) = d(F⁻¹(x)),  F = F_n ∘ … ∘ F_1,
//!          F_k(p) = p + φ(|p − g_k| / R)·(ΔM_k(p) − p)              a sweep (see below)
//!   inflate / deflate: the level-set ticks of Action::Inflate / Deflate over the region
//! ```
//!
//! `d` is always the clay as it was when the drag started: a [`DenseCopy`] of each source,
//! read trilinearly, and a [`TiledCopy`] of every place the drag has written. A drag
//! re-evaluated with each new motion of the hand therefore costs the same whatever its
//! history, gives back the clay exactly when the hand returns, and ends as one edit.
//!
//! **Bend** is Medium's Move tool: the clay within `R` of the grab point `g` follows the hand
//! with the smooth Wyvill falloff `φ`. Applied in one step, a displacement larger than about
//! `R/2` folds the clay over itself. The motion is therefore swept in `n` steps, each moving no
//! point by more than `R/4` (Angelidis et al.'s sweepers): each step is then a bijection,
//! inverted by a fixed-point iteration that contracts by at least half per round. So the clay
//! is resampled through an invertible map, never torn or left with holes, however far the
//! hand goes.
//!
//! **Symmetry**: with a symmetry's images, each image of the region moves by the image of the
//! motion (`I·M·I⁻¹`), and all act at once on the clay as it was, so images that overlap
//! unite rather than overwrite each other.

use crate::field::{
    bricks_over, Brick, BrickPlan, Colour, DenseCopy, Field, Fill, Span, TiledCopy, TiledReader, BRICK_SIZE,
};
use crate::math::{Aabb, Affine3A, IVec3, Isometry, Mat3, Pose, Quat, Vec3, VoxelTransform};
use crate::tool::{
    apply_tool_mirrored, wyvill, Action, Solid, StampCounters, Tool, ToolFrame, ToolShape, SOLID_BAND_VOXELS,
};

/// The most lattice points a drag may copy (its sources and the places it writes): 2²⁴, about
/// 320 MiB with colours.
pub const MAX_REGION_POINTS: usize = 1 << 24;

/// The most steps a bend's sweep takes; past that, each step moves the clay further.
const MAX_SWEEP_STEPS: u32 = 256;

/// Rounds of the fixed-point inversion of one sweep step (each at least halves the error).
const SWEEP_ROUNDS: usize = 12;

/// Why a region tool cannot act.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RegionError {
    /// The copy the drag needs is over [`MAX_REGION_POINTS`].
    #[error(
        "the region tool would copy {points} lattice points of clay, over its bound of {max}: select a smaller region or move it less far"
    )]
    TooLarge {
        /// What it would hold.
        points: usize,
        /// [`MAX_REGION_POINTS`].
        max: usize,
    },
    /// The region has no size.
    #[error("the region is empty: its size is zero on some axis")]
    Empty,
}

/// A selected region: a tool's shape placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// The shape, in its local frame.
    pub shape: ToolShape,
    /// Where it is.
    pub frame: ToolFrame,
}

impl Region {
    /// A box of half size `half_m` at `pose`.
    pub fn boxed(pose: Pose, half_m: Vec3) -> Self {
        Self { shape: ToolShape::Solid(Solid::Box { half_m }), frame: ToolFrame::new(pose, Vec3::ONE) }
    }

    /// A ball of radius `radius_m` about `centre_m`.
    pub fn ball(centre_m: Vec3, radius_m: f32) -> Self {
        Self {
            shape: ToolShape::sphere(radius_m),
            frame: ToolFrame::new(Pose { position_m: centre_m, ..Pose::default() }, Vec3::ONE),
        }
    }

    /// A tool's shape at the tool's pose.
    pub fn of_tool(tool: &Tool, pose: Pose) -> Self {
        Self { shape: tool.shape.clone(), frame: ToolFrame::new(pose, tool.scale) }
    }

    /// The centre of the region (its frame's origin).
    pub fn centre_m(&self) -> Vec3 {
        self.frame.pose.position_m
    }

    /// Its largest half-size (a ball's radius; a bend's falloff radius).
    pub fn radius_m(&self) -> f32 {
        (self.shape.half_extents_m() * self.frame.scale).max_element()
    }

    /// The world box holding it and half the ramp across its edge, `band_m` wide.
    pub fn bounds(&self, band_m: f32) -> Aabb {
        let band_local = band_m / self.frame.min_scale();
        let reach = if self.shape.is_hard_edged() { 0.5 * band_local } else { 0.0 };
        self.frame.world_bounds(self.shape.half_extents_m() + Vec3::splat(reach))
    }

    /// The region's image under a symmetry's image (mirrored when the image mirrors).
    pub fn image(&self, image: &Isometry) -> Region {
        let (pose, mirrored) = image.pose(&self.frame.pose);
        let frame = ToolFrame::with_mirror(pose, self.frame.scale, mirrored != self.frame.mirrored);
        Region { shape: self.shape.clone(), frame }
    }

    fn has_size(&self) -> bool {
        let size = self.shape.half_extents_m() * self.frame.scale;
        size.min_element() > 0.0 && size.is_finite()
    }
}

/// A rigid motion about a pivot: `p ↦ pivot + translation + rotation·(p − pivot)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// The point the rotation turns about (a bend's grab point), metres.
    pub pivot_m: Vec3,
    /// How far the pivot goes, metres.
    pub translation_m: Vec3,
    /// The turn about the pivot.
    pub rotation: Quat,
}

impl Motion {
    /// No motion, about `pivot_m`.
    pub fn still(pivot_m: Vec3) -> Self {
        Self { pivot_m, translation_m: Vec3::ZERO, rotation: Quat::IDENTITY }
    }

    /// The motion that takes a hand from pose `from` to pose `to`, turning about where the hand
    /// was.
    pub fn between(from: Pose, to: Pose) -> Self {
        Self {
            pivot_m: from.position_m,
            translation_m: to.position_m - from.position_m,
            rotation: (to.rotation * from.rotation.inverse()).normalize(),
        }
    }

    /// Where it takes `p`.
    #[inline]
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.pivot_m + self.translation_m + self.rotation * (p - self.pivot_m)
    }

    /// [`Motion::inverse_apply`] as an affine map.
    fn inverse_affine(&self) -> Affine3A {
        Affine3A::from_translation(self.pivot_m)
            * Affine3A::from_quat(self.rotation.inverse())
            * Affine3A::from_translation(-self.pivot_m - self.translation_m)
    }

    /// Where `x` came from.
    #[inline]
    pub fn inverse_apply(&self, x: Vec3) -> Vec3 {
        self.pivot_m + self.rotation.inverse() * (x - self.pivot_m - self.translation_m)
    }

    /// The motion done `k` times over (copies repeated along it): `Mᵏ(p) = g + Σᵢ₍ᵢ<ₖ₎ Rⁱ·t +
    /// Rᵏ·(p − g)`.
    pub fn times(&self, k: u32) -> Motion {
        let (mut translation_m, mut rotation) = (Vec3::ZERO, Quat::IDENTITY);
        for _ in 0..k {
            translation_m += rotation * self.translation_m;
            rotation = (rotation * self.rotation).normalize();
        }
        Motion { pivot_m: self.pivot_m, translation_m, rotation }
    }

    /// The fraction `s` of the motion, from the identity (0) to itself (1).
    pub fn fraction(&self, s: f32) -> Motion {
        Motion {
            translation_m: self.translation_m * s,
            rotation: Quat::IDENTITY.slerp(self.rotation, s),
            ..*self
        }
    }

    /// The motion seen through a symmetry's image: `I·M·I⁻¹`.
    pub fn image(&self, image: &Isometry) -> Motion {
        let l = image.linear;
        let turned = l * Mat3::from_quat(self.rotation) * l.transpose();
        Motion {
            pivot_m: image.point(self.pivot_m),
            translation_m: image.vector(self.translation_m),
            rotation: Quat::from_mat3(&turned).normalize(),
        }
    }

    /// The motion's angle, radians.
    fn angle(&self) -> f32 {
        self.rotation.to_axis_angle().1.abs()
    }

    fn matrix(&self) -> crate::math::Mat4 {
        crate::math::Mat4::from_translation(self.pivot_m + self.translation_m)
            * crate::math::Mat4::from_quat(self.rotation)
            * crate::math::Mat4::from_translation(-self.pivot_m)
    }
}

/// What a region drag does to the clay.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RegionOp {
    /// The region is carried: it leaves empty space and unites with what it lands on.
    Move,
    /// A copy of the region is carried; the region stays (Hua–Qin's copy and compose).
    Copy,
    /// The clay within the region's radius of its centre (the grab point) follows the hand
    /// with a smooth falloff; the motion turns about the grab point.
    Bend,
}

impl RegionOp {
    /// Its name, as scene files and messages write it.
    pub fn name(self) -> &'static str {
        match self {
            RegionOp::Move => "move",
            RegionOp::Copy => "copy",
            RegionOp::Bend => "bend",
        }
    }
}

/// What one update of a drag did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RegionStats {
    /// Lattice points written (each brick that became other than what it held).
    pub written: u64,
    /// Of those, the points evaluated one by one (the rest are whole bricks filled or given
    /// back).
    pub evaluated: u64,
    /// Lattice points the drag's copies hold.
    pub copied: u64,
    /// Sweep steps a bend took (0 for other operations).
    pub sweep_steps: u32,
}

/// One image of the region a drag carries.
#[derive(Clone, Debug)]
struct Image {
    isometry: Isometry,
    region: Region,
    /// The clay under the region as it was, with a margin for trilinear reads.
    source: DenseCopy,
}

/// A region carried by a hand: [`RegionDrag::update`] with each new motion resamples the clay
/// from its state when the drag started.
#[derive(Clone, Debug)]
pub struct RegionDrag {
    op: RegionOp,
    images: Vec<Image>,
    /// The clay as it was wherever the drag has written.
    originals: TiledCopy,
    /// What the drag left in each brick, and the buffer its mixed bricks are evaluated into.
    plan: BrickPlan,
    /// The ramp across a region's edge, in the region's local units.
    band_local_m: f32,
    /// The motion last applied.
    motion: Option<Motion>,
}

impl RegionDrag {
    /// Starts a drag of `region` (and its images under `images`; the identity may be among them
    /// or not) on `field`, copying the clay under each.
    pub fn start(
        field: &Field,
        region: Region,
        op: RegionOp,
        images: &[Isometry],
    ) -> Result<Self, RegionError> {
        if !region.has_size() {
            return Err(RegionError::Empty);
        }
        let t = *field.transform();
        let band_m = SOLID_BAND_VOXELS * t.voxel_size_m;
        let mut isometries = vec![Isometry::IDENTITY];
        isometries.extend(images.iter().filter(|i| !i.is_identity()));
        let boxes: Vec<(IVec3, IVec3)> =
            isometries.iter().map(|i| lattice_box(field, region.image(i).bounds(band_m), 1)).collect();
        let points: usize = boxes.iter().map(|&(lo, hi)| box_points(lo, hi)).sum();
        if points > MAX_REGION_POINTS {
            return Err(RegionError::TooLarge { points, max: MAX_REGION_POINTS });
        }
        let images = isometries
            .into_iter()
            .zip(boxes)
            .map(|(isometry, (lo, hi))| Image {
                region: region.image(&isometry),
                isometry,
                source: DenseCopy::read(field, lo, hi),
            })
            .collect();
        Ok(Self {
            op,
            images,
            originals: TiledCopy::new(),
            plan: BrickPlan::new(),
            band_local_m: band_m / region.frame.min_scale(),
            motion: None,
        })
    }

    /// What it does to the clay.
    pub fn op(&self) -> RegionOp {
        self.op
    }

    /// The region carried (the first image).
    pub fn region(&self) -> &Region {
        &self.images[0].region
    }

    /// The region's images other than itself.
    pub fn image_regions(&self) -> impl Iterator<Item = &Region> + '_ {
        self.images.iter().skip(1).map(|i| &i.region)
    }

    /// The region and its images where the hand has carried them (a bend's: its grab ball),
    /// for drawing.
    pub fn carried_regions(&self) -> Vec<Region> {
        let motion = self.motion.unwrap_or(Motion::still(self.region().centre_m()));
        self.images
            .iter()
            .map(|image| {
                let m = motion.image(&image.isometry);
                let mut r = image.region.clone();
                r.frame.pose = Pose {
                    position_m: m.apply(r.centre_m()),
                    rotation: (m.rotation * r.frame.pose.rotation).normalize(),
                };
                r
            })
            .collect()
    }

    /// Applies `motion` to the region (its images, the images of the motion) on the clay as it
    /// was when the drag started; what earlier updates wrote and this one does not reach is
    /// given back as it was.
    pub fn update(&mut self, field: &mut Field, motion: Motion) -> Result<RegionStats, RegionError> {
        self.apply(field, motion, true)
    }

    /// What `motion` does to each image for an update (a still one, where `exact_still` says
    /// so, gives the clay back as it was, exactly: a resampling at the points themselves would
    /// round).
    fn moved(&self, motion: Motion, exact_still: bool) -> Moved {
        // A bend turns about its grab point, the region's centre.
        let motion = match self.op {
            RegionOp::Bend => Motion { pivot_m: self.region().centre_m(), ..motion },
            _ => motion,
        };
        let still = exact_still && motion.translation_m == Vec3::ZERO && motion.rotation == Quat::IDENTITY;
        let motions: Vec<Motion> = self.images.iter().map(|i| motion.image(&i.isometry)).collect();
        let sweeps: Vec<Sweep> = match self.op {
            RegionOp::Bend => motions.iter().map(|m| Sweep::new(m, self.region().radius_m())).collect(),
            _ => Vec::new(),
        };
        let steps = sweeps.first().map_or(1, |s| s.steps.len() as u32);
        Moved { motion, still, motions, sweeps, steps }
    }

    /// How an update moved as `moved` resamples the clay held in `originals`.
    fn resample<'a>(&'a self, moved: &'a Moved, t: VoxelTransform, originals: &'a TiledCopy) -> Resample<'a> {
        Resample {
            op: if moved.still { None } else { Some(self.op) },
            images: &self.images,
            sweeps: &moved.sweeps,
            carries: self.images.iter().zip(&moved.motions).map(|(i, m)| Carry::new(i, m, &t)).collect(),
            t,
            band: self.band_local_m,
            originals,
        }
    }

    /// [`RegionDrag::update`]; a still motion gives the clay back exactly where `exact_still`
    /// says so, else it is resampled as any other (to write the region into another field).
    fn apply(
        &mut self,
        field: &mut Field,
        motion: Motion,
        exact_still: bool,
    ) -> Result<RegionStats, RegionError> {
        let t = *field.transform();
        let moved = self.moved(motion, exact_still);
        let (motion, steps) = (moved.motion, moved.steps);
        // Where the clay may change now: each image's region and where it lands (for a bend,
        // every step of the sweep).
        let mut reach: Vec<(IVec3, IVec3)> = Vec::new();
        for (image, m) in self.images.iter().zip(&moved.motions) {
            let bounds = image.region.bounds(SOLID_BAND_VOXELS * t.voxel_size_m);
            let mut landed = bounds.transformed(&m.matrix());
            if self.op == RegionOp::Bend {
                for k in 1..steps {
                    landed = landed.union(&bounds.transformed(&m.fraction(k as f32 / steps as f32).matrix()));
                }
            }
            reach.push(lattice_box(field, bounds, 1));
            reach.push(lattice_box(field, landed, 1));
        }
        // The region's own place is in both every frame: each box once.
        reach.sort_by_key(|&(lo, hi)| (lo.to_array(), hi.to_array()));
        reach.dedup();
        let missing = self.originals.missing(&reach);
        let sources: usize = self.images.iter().map(|i| i.source.len()).sum();
        let points = self.originals.points() + missing * TiledCopy::TILE_POINTS + sources;
        if points > MAX_REGION_POINTS {
            return Err(RegionError::TooLarge { points, max: MAX_REGION_POINTS });
        }
        // Tiles are whole bricks: every brick a box reaches is held whole.
        for &(lo, hi) in &reach {
            self.originals.take(field, lo, hi);
        }
        // Every brick the clay may change in now, and every one an earlier update left other
        // than as it was: what each becomes, decided for the whole brick where it can be.
        let mut plan = std::mem::take(&mut self.plan);
        let keys: Vec<IVec3> =
            reach.iter().flat_map(|&(lo, hi)| bricks_over(lo, hi)).chain(plan.changed_bricks()).collect();
        let how = self.resample(&moved, t, &self.originals);
        let stats = plan.write(
            field,
            None,
            keys,
            |key| how.fill(key * BRICK_SIZE, BRICK_SIZE),
            || self.originals.reader(),
            |key, originals, out| how.evaluate(key, originals, out),
            |originals, p| originals.get(p),
        );
        self.plan = plan;
        self.motion = Some(motion);
        let copied = (self.originals.points() + sources) as u64;
        Ok(RegionStats {
            written: stats.written,
            evaluated: stats.evaluated,
            copied,
            sweep_steps: if self.op == RegionOp::Bend { steps } else { 0 },
        })
    }
}

/// The motion of each image of a drag for one update.
struct Moved {
    /// The hand's motion (a bend's about its grab point).
    motion: Motion,
    /// Whether the clay is given back exactly as it was.
    still: bool,
    /// Each image's motion.
    motions: Vec<Motion>,
    /// A bend's sweep of each image's motion.
    sweeps: Vec<Sweep>,
    /// The steps of a bend's sweep (1 for other operations).
    steps: u32,
}

/// What one update resamples the clay through (`op` none: the clay as it was, exactly).
struct Resample<'a> {
    op: Option<RegionOp>,
    images: &'a [Image],
    sweeps: &'a [Sweep],
    carries: Vec<Carry>,
    t: VoxelTransform,
    band: f32,
    originals: &'a TiledCopy,
}

/// Lattice points along a side of the blocks a mixed brick is decided in, block by block,
/// before its points are evaluated one by one.
const BLOCK: i32 = 4;

impl Resample<'_> {
    /// What the lattice points `lo ..= lo + n − 1` become, where they all become one thing;
    /// else [`Fill::Mixed`]. Decided from bounds of each region's weight over the box (and over
    /// its image under each inverse motion) and the spans of the copies there.
    fn fill(&self, lo: IVec3, n: i32) -> Fill {
        let Some(op) = self.op else { return Fill::Original };
        let hi = lo + IVec3::splat(n - 1);
        // The box's centre on the lattice, and the ball holding it (in metres, a little wider
        // for rounding).
        let centre = lo.as_vec3() + Vec3::splat(0.5 * (n - 1) as f32);
        let r = 0.5 * (n - 1) as f32 * 3f32.sqrt() * self.t.voxel_size_m * 1.001;
        if op == RegionOp::Bend {
            let centre = self.t.index_to_world(centre);
            let reached =
                self.sweeps.iter().flat_map(|s| &s.steps).any(|s| centre.distance(s.centre) <= s.reach + r);
            return if reached { Fill::Mixed } else { Fill::Original };
        }
        let corners: [Vec3; 8] = std::array::from_fn(|i| {
            let o = IVec3::new(i as i32 & 1, (i as i32 >> 1) & 1, (i as i32 >> 2) & 1);
            (lo + o * (n - 1)).as_vec3()
        });
        let original = self.originals.span(lo, hi);
        // Whether every image leaves the clay here as it is, or one takes it all away; and what
        // the images bring (`Original`: nothing).
        let (mut kept, mut gone) = (true, false);
        let mut brought = Fill::Original;
        for (image, c) in self.images.iter().zip(&self.carries) {
            let shape = &image.region.shape;
            let r_local = r / image.region.frame.min_scale();
            let bounds = |map: &Affine3A| {
                let local = corners.map(|p| map.transform_point3(p));
                shape.potential_bounds(&local, map.transform_point3(centre), r_local, self.band)
            };
            let (w_lo, w_hi) = bounds(&c.here_local);
            kept &= w_hi == 0.0;
            gone |= w_lo == 1.0;
            let (w_lo, w_hi) = bounds(&c.from_local);
            if w_hi == 0.0 {
                continue;
            }
            // The source points the trilinear reads there touch.
            let index = corners.map(|p| c.from_index.transform_point3(p));
            let a = index.iter().fold(Vec3::INFINITY, |a, &c| a.min(c)).floor().as_ivec3();
            let b = index.iter().fold(Vec3::NEG_INFINITY, |a, &c| a.max(c)).floor().as_ivec3() + IVec3::ONE;
            let source = image.source.span(a, b);
            brought = match (brought, source) {
                (_, Span { max: 0.0, .. }) => brought,
                (Fill::Original, Span { min, full: Some(colour), .. }) if w_lo == 1.0 && min == 1.0 => {
                    Fill::Full(colour)
                }
                _ => Fill::Mixed,
            };
        }
        let leaves = op == RegionOp::Move;
        match brought {
            Fill::Original if original.max == 0.0 || !leaves || kept => Fill::Original,
            Fill::Original if gone => Fill::Empty,
            Fill::Full(colour) if original.max == 0.0 || (leaves && gone) => Fill::Full(colour),
            _ => Fill::Mixed,
        }
    }

    /// Writes the brick `key`'s densities and colours into `out`, point by point
    /// ([`Brick::linear`] order); returns how many points were evaluated one by one (blocks of
    /// one fill are not).
    fn evaluate(&self, key: IVec3, originals: &mut TiledReader<'_>, out: &mut [(f32, Colour)]) -> usize {
        let base = key * IVec3::splat(BRICK_SIZE);
        let mut evaluated = 0;
        let blocks = BRICK_SIZE / BLOCK;
        for block in 0..blocks * blocks * blocks {
            let offset =
                IVec3::new(block % blocks, (block / blocks) % blocks, block / (blocks * blocks)) * BLOCK;
            let fill = self.fill(base + offset, BLOCK);
            for i in 0..BLOCK * BLOCK * BLOCK {
                let local = offset + IVec3::new(i % BLOCK, (i / BLOCK) % BLOCK, i / (BLOCK * BLOCK));
                let p = base + local;
                out[Brick::linear(local)] = fill.value(|| originals.get(p)).unwrap_or_else(|| {
                    evaluated += 1;
                    self.point(p, originals.get(p))
                });
            }
        }
        evaluated
    }

    /// The clay at the lattice point `p`, which held `original`.
    #[inline]
    fn point(&self, p: IVec3, original: (f32, Colour)) -> (f32, Colour) {
        match self.op {
            None => original,
            Some(RegionOp::Bend) => {
                bent(self.images, self.sweeps, self.t.index_to_world(p.as_vec3()), &self.t, original)
            }
            Some(op) => {
                carried(self.images, &self.carries, p.as_vec3(), self.band, op == RegionOp::Move, original)
            }
        }
    }
}

/// One image's maps from a lattice point, for [`carried`]: into its region's frame where it
/// is, and into the frame and the source's lattice where it came from.
#[derive(Clone, Copy, Debug)]
struct Carry {
    here_local: Affine3A,
    from_local: Affine3A,
    from_index: Affine3A,
}

impl Carry {
    fn new(image: &Image, motion: &Motion, t: &VoxelTransform) -> Self {
        let (to_world, to_local) = (t.index_to_world_affine(), image.region.frame.world_to_local_affine());
        let from_world = motion.inverse_affine() * to_world;
        Self {
            here_local: to_local * to_world,
            from_local: to_local * from_world,
            from_index: t.world_to_index_affine() * from_world,
        }
    }
}

/// Move and copy at a lattice point: what stays (times what each moving image leaves) plus
/// what each image carries there, at most full. Across a region's soft edge the part that
/// stays and the part carried add up to the clay that was, so a region cut out of the clay
/// and put back leaves no seam; where carried clay lands on clay, the two unite.
#[inline]
fn carried(
    images: &[Image],
    carries: &[Carry],
    p: Vec3,
    band: f32,
    leaves: bool,
    (od, oc): (f32, Colour),
) -> (f32, Colour) {
    let mut keep = 1.0;
    let (mut brought, mut colour) = (0.0f32, [0.0f32; 4]);
    for (image, c) in images.iter().zip(carries) {
        if leaves && od > 0.0 {
            keep *= 1.0 - image.region.shape.potential(c.here_local.transform_point3(p), band);
        }
        let w = image.region.shape.potential(c.from_local.transform_point3(p), band);
        if w > 0.0 {
            let (sd, sc) = image.source.sample(c.from_index.transform_point3(p));
            let a = w * sd;
            brought += a;
            for (c, v) in colour.iter_mut().zip(sc) {
                *c += a * v;
            }
        }
    }
    if brought == 0.0 {
        return (od * keep, oc);
    }
    let stays = od * keep;
    let total = stays + brought;
    for (c, v) in colour.iter_mut().zip(oc) {
        *c = (*c + stays * v) / total;
    }
    (total.min(1.0), colour)
}

/// A bend at a world point: the clay found by undoing each image's sweep, read from the image
/// whose source holds it.
#[inline]
fn bent(
    images: &[Image],
    sweeps: &[Sweep],
    x: Vec3,
    t: &VoxelTransform,
    original: (f32, Colour),
) -> (f32, Colour) {
    let mut q = x;
    let mut from = None;
    for (i, sweep) in sweeps.iter().enumerate() {
        let back = sweep.undo(q);
        if back != q {
            q = back;
            from = Some(i);
        }
    }
    match from {
        None => original,
        Some(i) => images[i].source.sample(t.world_to_index(q)),
    }
}

/// One step of a sweep: the clay within `radius` of `centre` moves by `φ(|p − centre|/R)·
/// (after(before⁻¹(p)) − p)`.
#[derive(Clone, Copy, Debug)]
struct SweepStep {
    before: Motion,
    after: Motion,
    centre: Vec3,
    /// Beyond this distance from `centre` nothing lands or leaves.
    reach: f32,
}

/// A bend's motion cut into steps that each move the clay by at most a quarter of the radius.
#[derive(Clone, Debug)]
struct Sweep {
    steps: Vec<SweepStep>,
    radius: f32,
}

impl Sweep {
    fn new(motion: &Motion, radius: f32) -> Self {
        let n = sweep_steps(motion, radius);
        let steps = (1..=n)
            .map(|k| {
                let before = motion.fraction((k - 1) as f32 / n as f32);
                let after = motion.fraction(k as f32 / n as f32);
                let centre = before.apply(motion.pivot_m);
                let moved =
                    (after.apply(motion.pivot_m) - centre).length() + radius * motion.angle() / n as f32;
                SweepStep { before, after, centre, reach: radius + moved + 1e-6 }
            })
            .collect();
        Self { steps, radius }
    }

    /// Where the clay now at `x` came from: each step inverted by a fixed-point iteration, the
    /// last first.
    #[inline]
    fn undo(&self, x: Vec3) -> Vec3 {
        let mut p = x;
        for s in self.steps.iter().rev() {
            if p.distance_squared(s.centre) > s.reach * s.reach {
                continue;
            }
            let target = p;
            let mut q = p;
            for _ in 0..SWEEP_ROUNDS {
                let moved = s.after.apply(s.before.inverse_apply(q)) - q;
                let next = target - wyvill(q.distance(s.centre) / self.radius) * moved;
                let done = next.distance_squared(q) < 1e-14 * self.radius * self.radius;
                q = next;
                if done {
                    break;
                }
            }
            p = q;
        }
        p
    }
}

/// Sweep steps for `motion` over a ball of `radius`: no point moves over a quarter radius a step.
fn sweep_steps(motion: &Motion, radius: f32) -> u32 {
    let far = motion.translation_m.length() + motion.angle() * radius;
    ((4.0 * far / radius.max(1e-9)).ceil() as u32).clamp(1, MAX_SWEEP_STEPS)
}

/// The lattice box of `field`'s finest level holding `world`, grown by `margin` points.
fn lattice_box(field: &Field, world: Aabb, margin: i32) -> (IVec3, IVec3) {
    let t = field.transform();
    let lo = t.world_to_index(world.min).floor().as_ivec3() - IVec3::splat(margin);
    let hi = t.world_to_index(world.max).ceil().as_ivec3() + IVec3::splat(margin);
    (lo, hi)
}

fn box_points(lo: IVec3, hi: IVec3) -> usize {
    let d = (hi - lo + IVec3::ONE).max(IVec3::ZERO);
    d.x as usize * d.y as usize * d.z as usize
}

/// Grows (`distance_m` > 0) or shrinks the clay's surface within `region` (and its images) by
/// about `distance_m`, in level-set ticks of at most a quarter voxel (Hua–Qin's inflation and
/// deflation, here a motion of the surface along its normal, as [`Action::Inflate`] makes).
pub fn inflate(field: &mut Field, region: &Region, distance_m: f32, images: &[Isometry]) -> StampCounters {
    let mut counters = StampCounters::default();
    if !distance_m.is_finite() || distance_m == 0.0 || !region.has_size() {
        return counters;
    }
    let voxel = field.transform().voxel_size_m;
    let ticks = (distance_m.abs() / (0.25 * voxel)).ceil().max(1.0) as u32;
    let speed_m_per_s = 1.0;
    let action =
        if distance_m > 0.0 { Action::Inflate { speed_m_per_s } } else { Action::Deflate { speed_m_per_s } };
    let tool = Tool { scale: region.frame.scale, ..Tool::new(region.shape.clone(), action, [1.0; 4]) };
    let dt = distance_m.abs() / ticks as f32;
    let mut placed = vec![(region.frame.pose, region.frame.mirrored)];
    for image in images.iter().filter(|i| !i.is_identity()) {
        let r = region.image(image);
        placed.push((r.frame.pose, r.frame.mirrored));
    }
    for _ in 0..ticks {
        for &(pose, mirrored) in &placed {
            counters += apply_tool_mirrored(field, &tool, pose, mirrored, dt);
        }
    }
    counters
}

/// Copies the clay of `source` within `region` (and its images under `images`) into `target`,
/// a field on the same lattice, where it lands united with what `target` holds: Hua and Qin's
/// copy and compose into another patch (a region pasted as a new part).
pub fn copy_into(
    source: &Field,
    region: &Region,
    images: &[Isometry],
    target: &mut Field,
) -> Result<RegionStats, RegionError> {
    debug_assert_eq!(source.transform(), target.transform(), "one lattice");
    let mut drag = RegionDrag::start(source, region.clone(), RegionOp::Copy, images)?;
    drag.apply(target, Motion::still(region.centre_m()), false)
}

/// Copies `region` `count` times, each along `motion` once more than the last (a row of
/// copies; a row copied again makes a grid), every copy united with what it lands on.
pub fn copy_repeated(
    field: &mut Field,
    region: &Region,
    motion: Motion,
    count: u32,
    images: &[Isometry],
) -> Result<RegionStats, RegionError> {
    let mut stats = RegionStats::default();
    for k in 1..=count {
        let mut drag = RegionDrag::start(field, region.clone(), RegionOp::Copy, images)?;
        let s = drag.update(field, motion.times(k))?;
        stats.written += s.written;
        stats.evaluated += s.evaluated;
        stats.copied = stats.copied.max(s.copied);
    }
    Ok(stats)
}

#[cfg(test)]
mod tests;
