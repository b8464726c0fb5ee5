//! Parts: fields of their own, placed in the world and composed by CSG.
//!
//! A part is a field in its own frame (its own finest voxel size and levels), placed in the
//! world by a [`Placement`] (rotation, translation, uniform scale), and composed with the parts
//! before it by a [`Csg`] operator (Hua–Qin §3.3.2). Densities compose as the fuzzy-set forms
//! of the Boolean operators, which keep them in [0, 1] and the surface where the iso-level
//! says:
//!
//! ```text
//!   union          a ∪ b = max(a, b)
//!   intersection   a ∩ b = min(a, b)
//!   difference     a − b = min(a, 1 − b)
//!   the first part composes with empty clay: a union is itself, the others are empty
//! ```
//!
//! The surface drawn, measured and exported is one field, the [`Composition`]: a world-aligned
//! field sampled from the visible parts. Its voxel is the finest of the parts' world voxels
//! (voxel size × scale); a coarser part is sampled on the composition's level whose voxel is the
//! largest not over its own, so each part keeps about its resolution and the mesher's seams
//! between levels make the surface crack-free where parts of different resolutions meet. Each
//! brick of a level holds the whole composition at its lattice points, so whichever level the
//! mesher reads, it reads the same surface.
//!
//! A part's edits re-compose only the bricks their changed samples reach ([`Composition::update`],
//! from the part's dirty set), and the composition's own dirty set then tells the mesher what to
//! re-mesh. A sculpt of one visible part at rest with the union operator needs no composition:
//! its field is the surface ([`Composition::needed`]).

use crate::field::{
    Brick, BrickKey, Colour, Field, FieldReader, LevelKey, BRICK_SIZE, BRICK_VOLUME, MESHED_LEVELS,
};
use crate::math::{Aabb, IVec3, Mat3, Mat4, Pose, Quat, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

/// How a part combines with the composition of the parts before it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Csg {
    /// Clay where either is.
    #[default]
    Union,
    /// The parts before, less this one.
    Difference,
    /// Clay where both are.
    Intersection,
}

impl Csg {
    /// Every operator, in the order the station steps through them.
    pub const ALL: [Csg; 3] = [Csg::Union, Csg::Difference, Csg::Intersection];

    /// The name scene files and messages use.
    pub fn name(self) -> &'static str {
        match self {
            Csg::Union => "union",
            Csg::Difference => "difference",
            Csg::Intersection => "intersection",
        }
    }

    /// The operator a scene file names.
    pub fn from_name(name: &str) -> Option<Csg> {
        Csg::ALL.into_iter().find(|c| c.name() == name)
    }

    /// The composed density of `before` (the parts before) and `part`, and whether the part's
    /// sample is the one that gives it (so its colour is the composition's).
    #[inline]
    pub fn compose(self, before: f32, part: f32) -> (f32, bool) {
        match self {
            Csg::Union => {
                if part > before {
                    (part, true)
                } else {
                    (before, false)
                }
            }
            Csg::Difference => ((1.0 - part).min(before), false),
            Csg::Intersection => {
                if part < before {
                    (part, true)
                } else {
                    (before, false)
                }
            }
        }
    }
}

/// Where a part sits in the world: its local point `l` is at `translation + rotation · (scale · l)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Orientation (unit).
    pub rotation: Quat,
    /// Position of the part's origin, metres.
    pub translation_m: Vec3,
    /// Uniform scale (positive).
    pub scale: f32,
}

impl Default for Placement {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// Why a placement cannot place a part.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlacementError {
    /// The scale is zero, negative or not finite.
    #[error("scale {0} is not a positive finite number")]
    Scale(f32),
    /// The scale is outside what a part may be scaled by.
    #[error("scale {0} is outside {min} to {max}", min = SCALE_RANGE.start(), max = SCALE_RANGE.end())]
    ScaleRange(f32),
    /// The rotation or translation holds a NaN or an infinity, or the rotation is not a turn.
    #[error("the pose is not a finite rotation and translation")]
    Degenerate,
}

/// The scales a part may have: a thousandth to a thousand times its own size.
pub const SCALE_RANGE: std::ops::RangeInclusive<f32> = 1e-3..=1e3;

impl Placement {
    /// The part where its own frame is the world's.
    pub const IDENTITY: Placement =
        Placement { rotation: Quat::IDENTITY, translation_m: Vec3::ZERO, scale: 1.0 };

    /// A placement, refused when its scale is not positive and finite, or its pose is not finite.
    pub fn new(rotation: Quat, translation_m: Vec3, scale: f32) -> Result<Self, PlacementError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(PlacementError::Scale(scale));
        }
        if !SCALE_RANGE.contains(&scale) {
            return Err(PlacementError::ScaleRange(scale));
        }
        let length = rotation.length();
        if !rotation.is_finite() || !translation_m.is_finite() || (length - 1.0).abs() > 1e-3 {
            return Err(PlacementError::Degenerate);
        }
        Ok(Self { rotation: rotation.normalize(), translation_m, scale })
    }

    /// Whether the part's frame is the world's.
    pub fn is_identity(&self) -> bool {
        self.scale == 1.0
            && self.translation_m == Vec3::ZERO
            && self.rotation.abs_diff_eq(Quat::IDENTITY, 0.0)
    }

    /// A local point in the world.
    #[inline]
    pub fn point(&self, local_m: Vec3) -> Vec3 {
        self.translation_m + self.rotation * (local_m * self.scale)
    }

    /// A world point in the part's frame.
    #[inline]
    pub fn local_point(&self, world_m: Vec3) -> Vec3 {
        self.rotation.inverse() * (world_m - self.translation_m) / self.scale
    }

    /// A tool's world pose in the part's frame (its size there is its world size over
    /// [`Placement::scale`]).
    pub fn local_pose(&self, pose: Pose) -> Pose {
        Pose {
            position_m: self.local_point(pose.position_m),
            rotation: (self.rotation.inverse() * pose.rotation).normalize(),
        }
    }

    /// The matrix taking local points to the world.
    pub fn to_matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(Vec3::splat(self.scale), self.rotation, self.translation_m)
    }

    /// The world box holding a local box.
    pub fn world_box(&self, local: Aabb) -> Aabb {
        if local.is_empty() {
            return Aabb::EMPTY;
        }
        local.transformed(&self.to_matrix())
    }

    /// This placement followed by `then` (`then` applied to the placed part).
    pub fn then(&self, then: &Placement) -> Placement {
        Placement {
            rotation: (then.rotation * self.rotation).normalize(),
            translation_m: then.point(self.translation_m),
            scale: self.scale * then.scale,
        }
    }
}

/// What the composition reads of a part.
#[derive(Clone, Copy, Debug)]
pub struct PartView<'a> {
    /// The part's clay, in its own frame.
    pub field: &'a Field,
    /// Where it sits.
    pub placement: Placement,
    /// How it combines with the parts before it.
    pub op: Csg,
    /// Hidden parts are left out of the composition.
    pub visible: bool,
}

/// What the composition was made for, per part: a change of any of it re-makes it whole.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Layout {
    placement: Placement,
    op: Csg,
    visible: bool,
    voxel_m: f32,
}

impl Layout {
    fn of(part: &PartView<'_>) -> Self {
        Self {
            placement: part.placement,
            op: part.op,
            visible: part.visible,
            voxel_m: part.field.transform().voxel_size_m,
        }
    }
}

/// The visible parts composed into one world-aligned field, kept up to date as they change.
#[derive(Debug)]
pub struct Composition {
    field: Field,
    layout: Vec<Layout>,
    /// Per part, the composition's level it is sampled on.
    levels: Vec<usize>,
    /// Per part, a world box holding its clay (never shrinks while the layout holds).
    bounds: Vec<Aabb>,
}

/// The affine map from one level's lattice of the composition to a part's lattice.
#[derive(Clone, Copy, Debug)]
struct LatticeMap {
    linear: Mat3,
    offset: Vec3,
    /// The map is a permutation with an integer offset: the part's own samples, no
    /// interpolation.
    exact: Option<(Mat3, IVec3)>,
}

impl LatticeMap {
    fn new(placement: &Placement, part_voxel_m: f32, level_voxel_m: f32) -> Self {
        // part index = R⁻¹ · (q · v_L − t) / (s · v_p)
        let inverse = Mat3::from_quat(placement.rotation.inverse());
        let to_part = 1.0 / (placement.scale * part_voxel_m);
        let linear = inverse * (level_voxel_m * to_part);
        let offset = inverse * (-placement.translation_m * to_part);
        let near_integer = |v: f32| (v - v.round()).abs() < 1e-4;
        let integral = linear.to_cols_array().iter().all(|&v| near_integer(v))
            && offset.to_array().iter().all(|&v| near_integer(v));
        let exact = integral.then(|| {
            let cols = linear.to_cols_array().map(f32::round);
            (Mat3::from_cols_array(&cols), offset.round().as_ivec3())
        });
        Self { linear, offset, exact }
    }

    /// The part's sample at the composition's lattice point `q` (density; `None` where it
    /// reads no clay at all).
    #[inline]
    fn index(&self, q: IVec3) -> Result<IVec3, Vec3> {
        match self.exact {
            Some((m, o)) => Ok((m * q.as_vec3()).round().as_ivec3() + o),
            None => Err(self.linear * q.as_vec3() + self.offset),
        }
    }
}

/// The parts one brick of the composition reads, with their maps, in order.
struct Reading<'a> {
    parts: Vec<(usize, &'a Field, Csg, LatticeMap)>,
}

impl Composition {
    /// Whether `parts` need a composition: not when they are one visible part at rest, unioned
    /// (its field is then the surface).
    pub fn needed(parts: &[PartView<'_>]) -> bool {
        !matches!(parts, [only] if only.visible && only.op == Csg::Union && only.placement.is_identity())
    }

    /// The composition of `parts`, made whole.
    pub fn build(parts: &[PartView<'_>]) -> Self {
        let layout: Vec<Layout> = parts.iter().map(Layout::of).collect();
        let world_voxel = |l: &Layout| l.voxel_m * l.placement.scale;
        let finest = layout
            .iter()
            .filter(|l| l.visible)
            .map(world_voxel)
            .reduce(f32::min)
            .or_else(|| layout.first().map(world_voxel))
            .unwrap_or(1e-3);
        let iso = parts.first().map_or(0.5, |p| p.field.iso());
        let levels = layout
            .iter()
            .map(|l| {
                let ratio = world_voxel(l) / finest;
                (ratio.log2() + 1e-3).floor().clamp(0.0, MESHED_LEVELS as f32) as usize
            })
            .collect();
        let bounds = parts.iter().map(part_bounds).collect();
        let mut composition = Self { field: Field::new(finest, iso), layout, levels, bounds };
        let everything: Vec<(usize, Aabb)> = parts
            .iter()
            .enumerate()
            .map(|(i, p)| (i, local_bounds(p.field)))
            .filter(|(_, b)| !b.is_empty())
            .collect();
        composition.recompose(parts, &everything);
        composition
    }

    /// Whether the composition was made for parts laid out as `parts` are (placements,
    /// operators, visibility, voxel sizes); when not, [`Composition::build`] makes it again.
    pub fn fits(&self, parts: &[PartView<'_>]) -> bool {
        self.layout.len() == parts.len() && self.layout.iter().zip(parts).all(|(l, p)| *l == Layout::of(p))
    }

    /// The composed surface's field (world-aligned).
    pub fn field(&self) -> &Field {
        &self.field
    }

    /// The composed field, ending the composition.
    pub fn into_field(self) -> Field {
        self.field
    }

    /// The composed field, for the mesher to drain its dirty set.
    pub fn field_mut(&mut self) -> &mut Field {
        &mut self.field
    }

    /// The level of the composition part `part` is sampled on.
    pub fn level_of(&self, part: usize) -> usize {
        self.levels[part]
    }

    /// Re-composes what changed: `changed` lists, per part, boxes of its own finest lattice
    /// (inclusive) whose samples may have changed. The bricks of the composition that read
    /// them are made again, and marked dirty when they change.
    pub fn update(&mut self, parts: &[PartView<'_>], changed: &[(usize, IVec3, IVec3)]) {
        debug_assert!(self.fits(parts));
        let mut local = Vec::with_capacity(changed.len());
        for &(part, lo, hi) in changed {
            let t = parts[part].field.transform();
            let points = Aabb { min: t.index_to_world(lo.as_vec3()), max: t.index_to_world(hi.as_vec3()) };
            let reach = points.expanded(t.voxel_size_m);
            self.bounds[part] = self.bounds[part].union(&parts[part].placement.world_box(reach));
            local.push((part, points));
        }
        if !local.is_empty() {
            self.recompose(parts, &local);
        }
    }

    /// Re-makes every brick of the composition, on every level it uses, whose lattice points
    /// read a part's samples in the boxes `changes` gives (per part, a box of its own frame,
    /// metres): the points within them where the part is read sample for sample, and within one
    /// of its voxels where it is interpolated.
    fn recompose(&mut self, parts: &[PartView<'_>], changes: &[(usize, Aabb)]) {
        let mut used: Vec<usize> =
            (0..parts.len()).filter(|&i| self.layout[i].visible).map(|i| self.levels[i]).collect();
        used.sort_unstable();
        used.dedup();
        // Coarse levels first: a finer brick left empty is kept only over coarser clay.
        for &level in used.iter().rev() {
            let voxel = self.field.transform().voxel_size_m * (1 << level) as f32;
            let brick_m = voxel * BRICK_SIZE as f32;
            let mut world = Aabb::EMPTY;
            for &(part, local) in changes {
                let (p, part_voxel) = (&parts[part], parts[part].field.transform().voxel_size_m);
                let exact = LatticeMap::new(&p.placement, part_voxel, voxel).exact.is_some();
                let grown = if exact { local } else { local.expanded(part_voxel) };
                world = world.union(&p.placement.world_box(grown));
            }
            if world.is_empty() {
                continue;
            }
            // The composition's points within the box, and the bricks holding them.
            let lo = ((world.min / voxel - Vec3::splat(1e-3)).ceil() / BRICK_SIZE as f32).floor().as_ivec3();
            let hi = ((world.max / voxel + Vec3::splat(1e-3)).floor() / BRICK_SIZE as f32).floor().as_ivec3();
            let covering: Vec<Aabb> = (0..parts.len())
                .filter(|&i| self.layout[i].visible && self.levels[i] == level)
                .map(|i| self.bounds[i])
                .collect();
            let mut keys = Vec::new();
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let key = IVec3::new(x, y, z);
                        let b = brick_box(key, brick_m, voxel);
                        keys.push((key, covering.iter().any(|c| overlaps(c, &b))));
                    }
                }
            }
            let reading = self.reading(parts, level);
            let bounds = &self.bounds;
            let readers = || reading.parts.iter().map(|(_, f, _, _)| FieldReader::new(f)).collect::<Vec<_>>();
            let make = |readers: &mut Vec<FieldReader<'_>>, &(key, covered): &(BrickKey, bool)| {
                let brick =
                    covered.then(|| compose_brick(&reading, readers, bounds, key, brick_m, voxel)).flatten();
                (key, brick)
            };
            // A stroke's few bricks are made on this thread; many, on all.
            let made: Vec<(BrickKey, Option<Made>)> = if keys.len() < PARALLEL_BRICKS {
                let mut r = readers();
                keys.iter().map(|k| make(&mut r, k)).collect()
            } else {
                keys.par_iter().map_init(readers, make).collect()
            };
            for (key, made) in made {
                let at = LevelKey::new(level, key);
                let old = self.field.shared_brick(at);
                match made {
                    Some(made) if !made.brick().is_empty() || self.coarser_holds(level, key) => {
                        if let (Made::Shared(new), Some(old)) = (&made, old) {
                            if Arc::ptr_eq(new, old) {
                                continue;
                            }
                        }
                        match (old.map(|old| changed_box(old, made.brick())), made) {
                            // Unchanged.
                            (Some(None), _) => {}
                            (Some(Some((lo, hi))), Made::Shared(b)) => {
                                self.field.share_brick_within(at, b, lo, hi)
                            }
                            (Some(Some((lo, hi))), Made::Owned(b)) => {
                                self.field.replace_brick_within(at, b, lo, hi)
                            }
                            (None, Made::Shared(b)) => self.field.share_brick_within(
                                at,
                                b,
                                IVec3::ZERO,
                                IVec3::splat(BRICK_SIZE - 1),
                            ),
                            (None, Made::Owned(b)) => self.field.insert_brick(at, b),
                        }
                    }
                    _ => {
                        if let Some(old) = old {
                            let (lo, hi) = changed_box(old, &Brick::default())
                                .unwrap_or((IVec3::ZERO, IVec3::splat(BRICK_SIZE - 1)));
                            self.field.remove_brick_within(at, lo, hi);
                        }
                    }
                }
            }
        }
    }

    /// Whether a level coarser than `level` stores a brick over level `level`'s brick `key`.
    fn coarser_holds(&self, level: usize, key: BrickKey) -> bool {
        (level + 1..crate::field::LEVELS).any(|l| {
            let shift = (l - level) as i32;
            self.field.level_brick(LevelKey::new(l, key >> shift)).is_some_and(|b| !b.is_empty())
        })
    }

    fn reading<'a>(&self, parts: &[PartView<'a>], level: usize) -> Reading<'a> {
        let voxel = self.field.transform().voxel_size_m * (1 << level) as f32;
        Reading {
            parts: parts
                .iter()
                .enumerate()
                .filter(|(i, _)| self.layout[*i].visible)
                .map(|(i, p)| {
                    (i, p.field, p.op, LatticeMap::new(&p.placement, p.field.transform().voxel_size_m, voxel))
                })
                .collect(),
        }
    }
}

/// The world box of a composition brick's points, grown by the voxel its mesh reads beyond
/// them.
fn brick_box(key: BrickKey, brick_m: f32, voxel_m: f32) -> Aabb {
    let min = key.as_vec3() * brick_m;
    Aabb { min: min - Vec3::splat(voxel_m), max: min + Vec3::splat(brick_m + voxel_m) }
}

fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    !a.is_empty() && !b.is_empty() && a.min.cmple(b.max).all() && b.min.cmple(a.max).all()
}

/// The box of samples (local, inclusive) where `new` differs from `old` for a mesh: a density,
/// or the colour of a sample holding clay; `None` where none does.
fn changed_box(old: &Brick, new: &Brick) -> Option<(IVec3, IVec3)> {
    let (mut lo, mut hi) = (IVec3::MAX, IVec3::MIN);
    for i in 0..BRICK_VOLUME {
        let (a, b) = (old.density[i], new.density[i]);
        if a != b || (b > 0 && old.colour[i] != new.colour[i]) {
            let p = local_point(i);
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    (lo.cmple(hi).all()).then_some((lo, hi))
}

/// A brick of the composition as it is made: one part's own brick, shared, or made here.
enum Made {
    Shared(Arc<Brick>),
    Owned(Brick),
}

impl Made {
    fn brick(&self) -> &Brick {
        match self {
            Made::Shared(b) => b,
            Made::Owned(b) => b,
        }
    }
}

/// One brick of the composition (`None`: no part reaches it).
fn compose_brick(
    reading: &Reading<'_>,
    readers: &mut [FieldReader<'_>],
    bounds: &[Aabb],
    key: BrickKey,
    brick_m: f32,
    voxel_m: f32,
) -> Option<Made> {
    let here = brick_box(key, brick_m, voxel_m);
    let reaches = |n: usize| overlaps(&bounds[reading.parts[n].0], &here);
    // The common case first, without allocating: one part reaches the brick, unioned, on the
    // composition's lattice brick for brick.
    let mut one = None;
    for n in 0..reading.parts.len() {
        if reaches(n) {
            one = match one {
                None => Some(n),
                Some(_) => {
                    one = None;
                    break;
                }
            };
        }
    }
    if let Some(made) = one.and_then(|n| shared_alone(reading, n, key)) {
        return Some(made);
    }
    let reaching: Vec<bool> = (0..reading.parts.len()).map(reaches).collect();
    if !reaching.iter().any(|&r| r) {
        return None;
    }
    if let Some(made) = compose_aligned(reading, &reaching, key) {
        return Some(made);
    }
    let mut brick = Brick::default();
    let mut winners = [u8::MAX; BRICK_VOLUME];
    let base = key * BRICK_SIZE;
    for (i, winner) in winners.iter_mut().enumerate() {
        let q = base + local_point(i);
        let mut density = 0.0f32;
        for (n, (_, _, op, map)) in reading.parts.iter().enumerate() {
            let d = if reaching[n] {
                match map.index(q) {
                    Ok(p) => readers[n].density(p),
                    Err(x) => readers[n].density_at(x),
                }
            } else {
                0.0
            };
            let (composed, wins) = op.compose(density, d);
            density = composed;
            if wins {
                *winner = n as u8;
            }
        }
        brick.set_density(i, density);
    }
    // The colour of the part that gives each sample its density, where there is clay (a brick
    // without any is kept empty: over coarser clay it says the composition is empty there).
    let mut held = winners.iter().enumerate().filter(|&(i, &n)| brick.density[i] > 0 && n != u8::MAX);
    let Some((first, _)) = held.next() else { return Some(Made::Owned(brick)) };
    let colour = |readers: &mut [FieldReader<'_>], i: usize| -> Colour {
        let n = winners[i] as usize;
        match reading.parts[n].3.index(base + local_point(i)) {
            Ok(p) => readers[n].colour(p),
            Err(x) => readers[n].colour_at(x),
        }
    };
    brick.colour = crate::field::BrickColours::Uniform(colour(readers, first));
    for (i, _) in held {
        let c = colour(readers, i);
        brick.colour.set(i, c);
    }
    brick.compact();
    Some(Made::Owned(brick))
}

/// One brick of the composition where every part reaching it lies on the composition's lattice
/// brick for brick (not turned, moved by whole bricks, at the level's voxel): composed from the
/// parts' bricks sample by sample on their stored values, which gives exactly what
/// [`compose_brick`]'s reads give (the operators commute with the quantisation). `None` where a
/// reaching part is not so placed.
/// The brick of the composition at `key` where part `n` alone reaches it, unioned, on the
/// composition's lattice brick for brick: that part's own brick (shared where it stores one).
fn shared_alone(reading: &Reading<'_>, n: usize, key: BrickKey) -> Option<Made> {
    let (_, field, op, map) = &reading.parts[n];
    let (m, o) = map.exact?;
    if *op != Csg::Union || m != Mat3::IDENTITY || o.rem_euclid(IVec3::splat(BRICK_SIZE)) != IVec3::ZERO {
        return None;
    }
    let key = key + o.div_euclid(IVec3::splat(BRICK_SIZE));
    if let Some(shared) = field.shared_brick(key) {
        return Some(Made::Shared(Arc::clone(shared)));
    }
    let mut scratch = Brick::default();
    Some(Made::Owned(field.read_brick(key, &mut scratch).cloned().unwrap_or_default()))
}

fn compose_aligned(reading: &Reading<'_>, reaching: &[bool], key: BrickKey) -> Option<Made> {
    let mut keys = Vec::with_capacity(reading.parts.len());
    for ((_, _, _, map), &reaches) in reading.parts.iter().zip(reaching) {
        if !reaches {
            keys.push(None);
            continue;
        }
        let (m, o) = map.exact?;
        if m != Mat3::IDENTITY || o.rem_euclid(IVec3::splat(BRICK_SIZE)) != IVec3::ZERO {
            return None;
        }
        keys.push(Some(key + o.div_euclid(IVec3::splat(BRICK_SIZE))));
    }
    let mut scratch = Brick::default();
    let mut out = Brick::default();
    let mut winners = [u8::MAX; BRICK_VOLUME];
    let mut owned: Vec<Option<Brick>> = Vec::with_capacity(keys.len());
    for (n, ((_, field, op, _), part_key)) in reading.parts.iter().zip(&keys).enumerate() {
        let brick = part_key.and_then(|k| field.read_brick(k, &mut scratch).cloned());
        let zero = [0 as crate::field::Quantum; BRICK_VOLUME];
        let densities = brick.as_ref().map_or(&zero, |b| &*b.density);
        for ((d, &q), winner) in out.density.iter_mut().zip(densities.iter()).zip(winners.iter_mut()) {
            match op {
                Csg::Union if q > *d => {
                    *d = q;
                    *winner = n as u8;
                }
                Csg::Intersection if q < *d => {
                    *d = q;
                    *winner = n as u8;
                }
                Csg::Difference => {
                    *d = (*d).min(crate::field::DENSITY_ONE - q.min(crate::field::DENSITY_ONE))
                }
                _ => {}
            }
        }
        owned.push(brick);
    }
    let mut held = winners.iter().enumerate().filter(|&(i, &n)| out.density[i] > 0 && n != u8::MAX);
    let Some((first, &n)) = held.next() else { return Some(Made::Owned(out)) };
    let colour =
        |i: usize, n: u8| owned[n as usize].as_ref().map_or(crate::field::DEFAULT_COLOUR, |b| b.colour[i]);
    out.colour = crate::field::BrickColours::Uniform(colour(first, n));
    for (i, &n) in held {
        out.colour.set(i, colour(i, n));
    }
    out.compact();
    Some(Made::Owned(out))
}

/// The local coordinates of a brick's sample of linear index `i`.
fn local_point(i: usize) -> IVec3 {
    let i = i as i32;
    IVec3::new(i % BRICK_SIZE, (i / BRICK_SIZE) % BRICK_SIZE, i / (BRICK_SIZE * BRICK_SIZE))
}

/// Bricks of the composition below which they are made on the calling thread.
const PARALLEL_BRICKS: usize = 32;

/// A world box holding a part's clay (its stored bricks on every level, and the apron its
/// mesh reads).
pub fn part_bounds(part: &PartView<'_>) -> Aabb {
    part.placement.world_box(local_bounds(part.field))
}

/// A box of a field's own frame holding its clay (its stored bricks on every level, and the
/// apron its mesh reads), metres.
pub fn local_bounds(field: &Field) -> Aabb {
    let mut lo = IVec3::MAX;
    let mut hi = IVec3::MIN;
    for l in 0..crate::field::LEVELS {
        let scale = 1 << l;
        for key in field.level_keys(l) {
            lo = lo.min(key * BRICK_SIZE * scale);
            hi = hi.max((key * BRICK_SIZE + IVec3::splat(BRICK_SIZE)) * scale);
        }
    }
    if lo.cmpgt(hi).any() {
        return Aabb::EMPTY;
    }
    let t = field.transform();
    Aabb { min: t.index_to_world(lo.as_vec3() - Vec3::ONE), max: t.index_to_world(hi.as_vec3() + Vec3::ONE) }
}

#[cfg(test)]
mod tests;
