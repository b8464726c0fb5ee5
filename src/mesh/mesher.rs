//! Meshing the whole field or just its dirty bricks, in parallel.

use rayon::prelude::*;

use std::sync::Mutex;

use rustc_hash::{FxHashMap, FxHashSet};

use super::cases::flat_cases;
use super::coarse::{levels_around, march_coarse, mesh_level, CoarseScratch};
use super::march::{march_brick, neighbour, Block, MarchScratch, Neighbourhood, BLOCK, BLOCK_VOLUME};
use super::types::{ChunkMesh, MeshDiff};
use crate::field::{dequantize, Brick, BrickKey, Field, Quantum, BRICK_SIZE, BRICK_VOLUME};
use crate::math::IVec3;

/// Copies brick `key`'s densities and apron into `block`, row by row (within a brick and
/// within the block, the samples of one (y, z) row are contiguous, so each row is one slice
/// copy). Returns the bricks it read, for the kernel's colour look-ups, and the block.
///
/// Where the finest level holds no brick but coarser levels hold clay, the brick the coarser
/// levels give is made in the block's spare bricks and read like a stored one: a brick meshed
/// on the finest level reads coarse clay beside it as the finest lattice sees it.
pub fn gather_block<'f>(
    field: &'f Field,
    key: BrickKey,
    block: &'f mut Block,
) -> (Neighbourhood<'f>, &'f Block) {
    gather(field, key, block, None)
}

/// [`gather_block`], reading the bricks the coarser levels give from `made` (made once for a
/// whole mesh call) when given, else making them into the block's spare bricks.
fn gather<'f>(
    field: &'f Field,
    key: BrickKey,
    block: &'f mut Block,
    made: Option<&'f CoarseBricks>,
) -> (Neighbourhood<'f>, &'f Block) {
    let mut around = Neighbourhood::new(field, key);
    let mut spare = [false; 27];
    if field.has_levels_above(0) {
        match made {
            Some(made) => {
                for (i, brick) in around.bricks.iter_mut().enumerate() {
                    if brick.is_none() {
                        *brick = made.bricks.get(&neighbour(key, i));
                    }
                }
            }
            None => {
                if block.refined.is_empty() {
                    block.refined.resize_with(27, Brick::default);
                }
                for (i, (brick, refined)) in around.bricks.iter().zip(block.refined.iter_mut()).enumerate() {
                    if brick.is_none() {
                        spare[i] = field.read_brick(neighbour(key, i), refined).is_some();
                    }
                }
            }
        }
    }
    let refined = &block.refined;
    let found = around.bricks;
    let reading: [Option<&Brick>; 27] =
        std::array::from_fn(|i| if spare[i] { Some(&refined[i]) } else { found[i] });
    copy_block(&reading, &mut block.stored, &mut block.density);
    block.origin = key * BRICK_SIZE - IVec3::ONE;
    let block: &'f Block = block;
    around.bricks = std::array::from_fn(|i| if spare[i] { Some(&block.refined[i]) } else { found[i] });
    (around, block)
}

/// The finest-level bricks that the coarser levels give around a set of bricks to mesh, each
/// made once. Without it each is made again for every neighbour that reads it: up to 27
/// times, and making one interpolates 512 samples through every coarser level.
#[derive(Debug, Default)]
struct CoarseBricks {
    /// The bricks holding matter; a key absent here (and not stored) is empty.
    bricks: FxHashMap<BrickKey, Brick>,
    /// Scratch: the keys to make, gathered without duplicates (a sort of the 27 neighbours
    /// of every key cost more than making a tenth of the bricks), then listed.
    wanted: FxHashSet<BrickKey>,
    listed: Vec<BrickKey>,
}

impl CoarseBricks {
    /// Makes the bricks that the neighbourhoods of `keys` read from the coarser levels (in
    /// parallel), dropping those of the last call.
    fn make(&mut self, field: &Field, keys: &[BrickKey]) {
        self.bricks.clear();
        if keys.is_empty() || !field.has_levels_above(0) {
            return;
        }
        for &key in keys {
            self.wanted.extend((0..27).map(|i| neighbour(key, i)));
        }
        self.listed.clear();
        self.listed.extend(self.wanted.drain().filter(|&k| field.brick(k).is_none()));
        // One scratch brick per task, given away only when it was made: most neighbours
        // around the surface are empty.
        let made: Vec<(BrickKey, Brick)> = self
            .listed
            .par_iter()
            .map_init(Brick::default, |scratch, &k| {
                field.read_brick(k, scratch).is_some().then(|| (k, std::mem::take(scratch)))
            })
            .flatten()
            .collect();
        self.bricks.extend(made);
    }
}

/// Copies the densities of a brick's block from the bricks around it (ordered as
/// [`Neighbourhood::bricks`]; absent ones are empty). On each axis, block coordinate 0 is the
/// lower neighbour's last sample, `1 ..= S` the centre brick's and `S + 1`, `S + 2` the upper
/// neighbour's first two; so each block row (one `y`, `z`) is three pieces of fixed length,
/// copied without a call, from three bricks looked up once for all the rows they serve, into
/// `stored`; then the whole block is decoded into `density` in one loop.
fn copy_block(around: &[Option<&Brick>; 27], stored: &mut [Quantum], density: &mut [f32]) {
    const S: usize = BRICK_SIZE as usize;
    /// Per piece of an axis: the neighbour along it, its block coordinates, the local
    /// coordinate of the first of them.
    const PIECES: [(usize, (usize, usize), usize); 3] =
        [(0, (0, 1), S - 1), (1, (1, S + 1), 0), (2, (S + 1, BLOCK), 0)];
    static EMPTY: [Quantum; BRICK_VOLUME] = [0; BRICK_VOLUME];
    let block: &mut [Quantum; BLOCK_VOLUME] = stored.try_into().expect("a block holds BLOCK_VOLUME samples");
    for (bz, (z0, z1), lz0) in PIECES {
        for (by, (y0, y1), ly0) in PIECES {
            let brick = |bx: usize| around[bx + 3 * (by + 3 * bz)].map_or(&EMPTY, |b| &*b.density);
            let (lower, centre, upper) = (brick(0), brick(1), brick(2));
            for (z, lz) in (z0..z1).zip(lz0..) {
                for (y, ly) in (y0..y1).zip(ly0..) {
                    let from = S * (ly + S * lz);
                    let dst: &mut [Quantum; BLOCK] =
                        (&mut block[BLOCK * (y + BLOCK * z)..][..BLOCK]).try_into().expect("a block row");
                    dst[0] = lower[from + S - 1];
                    dst[1..=S].copy_from_slice(&centre[from..from + S]);
                    dst[S + 1..].copy_from_slice(&upper[from..from + 2]);
                }
            }
        }
    }
    for (d, &q) in density.iter_mut().zip(block.iter()) {
        *d = dequantize(q);
    }
}

/// Meshes one brick into `out`, on its mesh level ([`mesh_level`]), reusing the caller's
/// buffers (those of the finest level's kernel).
pub fn mesh_brick(
    field: &Field,
    key: BrickKey,
    block: &mut Block,
    scratch: &mut MarchScratch,
    out: &mut ChunkMesh,
) {
    let level = mesh_level(field, key);
    let around = if level > 0 { levels_around(field, key) } else { [0; 27] };
    mesh_brick_with(field, key, level, &around, block, None, scratch, &mut CoarseScratch::default(), out);
}

/// [`mesh_brick`] on mesh level `level` ([`mesh_level`]; `around`: the levels of the brick
/// and its neighbours, read where it is coarse), reading the finest bricks the coarser levels
/// give from `made` when given.
#[allow(clippy::too_many_arguments)]
fn mesh_brick_with(
    field: &Field,
    key: BrickKey,
    level: usize,
    around: &[u8; 27],
    block: &mut Block,
    made: Option<&CoarseBricks>,
    scratch: &mut MarchScratch,
    coarse: &mut CoarseScratch,
    out: &mut ChunkMesh,
) {
    if level > 0 {
        march_coarse(field, key, level, around, coarse, out);
        return;
    }
    let (around, block) = gather(field, key, block, made);
    march_brick(block, &around, field.surface_level(), field.transform(), scratch, out);
}

/// How a density range lies against the iso-level (where there is no clay: outside).
const OUTSIDE: u8 = 0;
const INSIDE: u8 = 1;
const CROSSING: u8 = 2;

fn range_class((lo, hi): (f32, f32), iso: f32) -> u8 {
    if hi < iso {
        OUTSIDE
    } else if lo >= iso {
        INSIDE
    } else {
        CROSSING
    }
}

/// A brick's classes as the mesh cells around it read it, two bits each: bits 0–1 for all
/// its samples (what its own cells read), bits 2–3, 4–5, 6–7 for its lower x, y and z faces
/// (see [`Field::read_ranges`]), of which the cells of the bricks below it read one or the
/// samples two or three of them share.
fn class(field: &Field, key: BrickKey) -> u8 {
    let iso = field.surface_level();
    let Some(ranges) = field.read_ranges(key) else { return OUTSIDE };
    let all = range_class(ranges.all, iso);
    // A brick on one side of the iso-level has its faces there too.
    let faces = if all == CROSSING { ranges.low_faces.map(|r| range_class(r, iso)) } else { [all; 3] };
    all | faces[0] << 2 | faces[1] << 4 | faces[2] << 6
}

/// The class of what the cells of brick `key` read of brick `key + GROUP[c]`, from its
/// [`class`]: all of it for `c = 0`; else the samples its lower faces across the axes of
/// `c` share, whose range lies in each face's range (so one face on one side settles it).
#[inline]
fn read_class(c: usize, class: u8) -> u8 {
    if c == 0 {
        return class & 3;
    }
    let faces = (0..3).filter(|a| c >> a & 1 == 1).map(|a| class >> (2 + 2 * a) & 3);
    faces.fold(CROSSING, |read, face| if read == CROSSING { face } else { read })
}

/// Whether the cells of a brick, reading the eight bricks of [`GROUP`] of these classes (see
/// [`class`]; the first is the brick itself), surely hold no triangle.
#[inline]
fn group_is_empty(classes: impl IntoIterator<Item = u8>) -> bool {
    let read = classes.into_iter().enumerate().map(|(c, class)| read_class(c, class));
    let (any, all) = read.fold((OUTSIDE, INSIDE), |(any, all), c| (any | c, all & c));
    any == OUTSIDE || (any == INSIDE && all == INSIDE)
}

/// Offsets of the eight bricks `key ..= key + 1` the cells of brick `key` read.
const GROUP: [IVec3; 8] = {
    let mut g = [IVec3::ZERO; 8];
    let mut c = 0;
    while c < 8 {
        g[c] = IVec3::new((c & 1) as i32, ((c >> 1) & 1) as i32, ((c >> 2) & 1) as i32);
        c += 1;
    }
    g
};

/// Whether brick `key` surely holds no triangle: the cells it meshes read brick `key` and
/// the lower faces of bricks `key + 1` on each axis, and what they read is all inside the clay
/// or all outside it. Decided from the field's density ranges of each brick and each lower
/// face, without reading a sample.
pub fn surely_empty(field: &Field, key: BrickKey) -> bool {
    group_is_empty(GROUP.iter().map(|&o| class(field, key + o)))
}

/// The classes of the bricks of a box of keys, x-major (`z` fastest, the order of sorted
/// keys), so that many keys are classified with one look-up per brick instead of eight.
#[derive(Clone, Debug, Default)]
struct ClassGrid {
    lo: IVec3,
    dims: IVec3,
    classes: Vec<u8>,
}

impl ClassGrid {
    /// Sizes the grid to `lo ..= hi`, all [`OUTSIDE`].
    fn reset(&mut self, lo: IVec3, hi: IVec3) {
        self.lo = lo;
        self.dims = hi - lo + IVec3::ONE;
        self.classes.clear();
        self.classes.resize(volume(lo, hi), OUTSIDE);
    }

    #[inline]
    fn index(&self, key: BrickKey) -> usize {
        let q = (key - self.lo).as_uvec3();
        (q.z + self.dims.z as u32 * (q.y + self.dims.y as u32 * q.x)) as usize
    }

    /// Whether brick `key` surely holds no triangle; `key + 1` must lie in the grid.
    #[inline]
    fn surely_empty(&self, key: BrickKey) -> bool {
        group_is_empty(GROUP.iter().map(|&o| self.classes[self.index(key + o)]))
    }
}

/// Number of keys in `lo ..= hi` (0 for an empty box), saturating.
fn volume(lo: IVec3, hi: IVec3) -> usize {
    let d = (hi.as_i64vec3() - lo.as_i64vec3() + glam::I64Vec3::ONE).max(glam::I64Vec3::ZERO);
    usize::try_from(d.x.saturating_mul(d.y).saturating_mul(d.z)).unwrap_or(usize::MAX)
}

/// The buffers one worker thread marches with.
#[derive(Debug)]
struct Worker {
    block: Block,
    scratch: MarchScratch,
    coarse: CoarseScratch,
    /// Sized for the largest chunk a brick can make, so it never grows.
    mesh: ChunkMesh,
}

impl Default for Worker {
    fn default() -> Self {
        let cases = flat_cases();
        let max_indices = (0..256).map(|m| cases.edges(m).len()).max().unwrap_or(0) * BRICK_VOLUME;
        // Each vertex sits on a distinct edge from a corner of the brick's 9³ cell corners.
        let max_vertices = 3 * (BRICK_SIZE as usize + 1).pow(3);
        let mesh = ChunkMesh {
            vertices: Vec::with_capacity(max_vertices),
            indices: Vec::with_capacity(max_indices),
        };
        Self {
            block: Block::default(),
            scratch: MarchScratch::default(),
            coarse: CoarseScratch::default(),
            mesh,
        }
    }
}

/// The incremental mesher: re-meshes sets of bricks into a [`MeshDiff`] it keeps, reusing
/// every buffer from one call to the next.
///
/// Each worker thread marches with buffers of its own (kept by the mesher); each key of a call
/// has a slot whose vectors the next call reuses: the chunks of the returned diff are those
/// vectors, lent until the next call, which takes them back. Re-meshing a set of bricks no
/// larger than before therefore allocates nothing once the buffers have grown (a thread
/// outside the rayon pool handing it the work may still allocate inside rayon). Memory held:
/// the chunks of the largest call so far.
#[derive(Debug, Default)]
pub struct Mesher {
    /// One per thread of the pool, by thread index (locked by that thread only).
    workers: Vec<Mutex<Worker>>,
    keys: Vec<BrickKey>,
    /// The mesh level of each key ([`mesh_level`]).
    levels: Vec<u8>,
    /// The mesh levels of the keys and of the coarse ones' neighbours, each found once.
    mesh_levels: FxHashMap<BrickKey, u8>,
    /// The keys meshed on the finest level, whose neighbours the coarser levels may give.
    finest: Vec<BrickKey>,
    slots: Vec<ChunkMesh>,
    /// The slot each chunk of `diff.upserted` came from.
    upserted_slots: Vec<usize>,
    grid: ClassGrid,
    coarse: CoarseBricks,
    diff: MeshDiff,
}

impl Mesher {
    /// Re-meshes the given bricks in parallel: bricks with triangles are upserted, the others
    /// removed (removing a chunk the renderer does not hold is harmless), both in key order.
    pub fn remesh<I: IntoIterator<Item = BrickKey>>(&mut self, field: &Field, keys: I) -> &MeshDiff {
        self.begin();
        self.keys.extend(keys);
        self.remesh_keys(field)
    }

    /// [`Self::remesh`] of the keys gathered in `keys`.
    fn remesh_keys(&mut self, field: &Field) -> &MeshDiff {
        // A fixed order makes diffs (and so draw order and images) reproducible.
        self.keys.sort_unstable_by_key(|k| k.to_array());
        self.keys.dedup();
        let (Some(&first), Some(&last)) = (self.keys.first(), self.keys.last()) else { return &self.diff };
        let (lo, hi) = self.keys.iter().fold((first, last), |(lo, hi), &k| (lo.min(k), hi.max(k)));
        let (diff, grid) = (&mut self.diff, &mut self.grid);
        // Classify by a grid of the keys' box when that takes fewer look-ups than eight a key.
        let use_grid = volume(lo, hi + IVec3::ONE) <= 8 * self.keys.len();
        if use_grid {
            grid.reset(lo, hi + IVec3::ONE);
            for x in lo.x..=hi.x + 1 {
                for y in lo.y..=hi.y + 1 {
                    for z in lo.z..=hi.z + 1 {
                        let key = IVec3::new(x, y, z);
                        let i = grid.index(key);
                        grid.classes[i] = class(field, key);
                    }
                }
            }
        }
        self.keys.retain(|&k| {
            let empty = if use_grid { grid.surely_empty(k) } else { surely_empty(field, k) };
            if empty {
                diff.removed.push(k);
            }
            !empty
        });
        self.march(field);
        &self.diff
    }

    /// Meshes the whole field: upserts only.
    pub fn mesh_all(&mut self, field: &Field) -> &MeshDiff {
        self.begin();
        let mut bounds: Option<(IVec3, IVec3)> = None;
        for k in field.brick_keys() {
            bounds = Some(bounds.map_or((k, k), |(lo, hi)| (lo.min(k), hi.max(k))));
        }
        let Some((lo, hi)) =
            bounds.or_else(|| field.has_levels_above(0).then_some((IVec3::ZERO, IVec3::ZERO)))
        else {
            return &self.diff;
        };
        // Bricks `lo − 1 ..= hi` may hold triangles (a cell in brick K reads K ..= K + 1).
        // A dense grid of the stored bricks' classes finds them with one look-up per stored
        // brick, unless the field is too sparse for its box.
        if !field.has_levels_above(0) && volume(lo - IVec3::ONE, hi + IVec3::ONE) <= 64 * field.brick_count()
        {
            let grid = &mut self.grid;
            grid.reset(lo - IVec3::ONE, hi + IVec3::ONE);
            for k in field.brick_keys() {
                let i = grid.index(k);
                grid.classes[i] = class(field, k);
            }
            for x in lo.x - 1..=hi.x {
                for y in lo.y - 1..=hi.y {
                    for z in lo.z - 1..=hi.z {
                        let key = IVec3::new(x, y, z);
                        if !grid.surely_empty(key) {
                            self.keys.push(key);
                        }
                    }
                }
            }
        } else {
            self.keys.extend(meshable_bricks(field).into_iter().filter(|&k| !surely_empty(field, k)));
        }
        self.march(field);
        self.diff.removed.clear();
        &self.diff
    }

    /// Meshes the bricks the field marked dirty since the last call, draining its dirty set
    /// (which keeps its memory: marking and re-meshing allocate nothing once both have grown).
    pub fn remesh_dirty(&mut self, field: &mut Field) -> &MeshDiff {
        self.begin();
        self.keys.extend(field.drain_dirty());
        self.remesh_keys(field)
    }

    /// The diff of the last call, left empty here (its vectors are then not reused).
    pub fn take_diff(&mut self) -> MeshDiff {
        self.upserted_slots.clear();
        std::mem::take(&mut self.diff)
    }

    /// Takes back the chunks lent in the last diff and empties it.
    fn begin(&mut self) {
        for ((_, mesh), &slot) in self.diff.upserted.drain(..).zip(&self.upserted_slots) {
            self.slots[slot] = mesh;
        }
        self.upserted_slots.clear();
        self.diff.removed.clear();
        self.keys.clear();
    }

    /// Marches `keys` in parallel into their slots and lists the results in the diff.
    fn march(&mut self, field: &Field) {
        let n = self.keys.len();
        if self.slots.len() < n {
            self.slots.resize_with(n, ChunkMesh::default);
        }
        let threads = rayon::current_num_threads();
        if self.workers.len() < threads {
            self.workers.resize_with(threads, Mutex::default);
        }
        self.levels.clear();
        self.finest.clear();
        self.mesh_levels.clear();
        if field.has_levels_above(0) {
            let known = &mut self.mesh_levels;
            let mut level_of = |k: BrickKey| *known.entry(k).or_insert_with(|| mesh_level(field, k) as u8);
            for &key in &self.keys {
                let level = level_of(key);
                self.levels.push(level);
                if level == 0 {
                    self.finest.push(key);
                } else {
                    // A coarse brick's cells conform to its neighbours' levels.
                    for i in 0..27 {
                        level_of(neighbour(key, i));
                    }
                }
            }
        } else {
            self.levels.resize(n, 0);
        }
        self.coarse.make(field, &self.finest);
        let (workers, coarse, known) = (&self.workers, &self.coarse, &self.mesh_levels);
        let keys = self.keys.par_iter().zip(self.levels.par_iter());
        keys.zip(self.slots[..n].par_iter_mut()).for_each(|((&key, &level), slot)| {
            let index = rayon::current_thread_index().unwrap_or(0) % workers.len();
            let mut worker = workers[index].lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            let Worker { block, scratch, coarse: coarse_scratch, mesh } = &mut *worker;
            let level = usize::from(level);
            let around = if level > 0 { std::array::from_fn(|i| known[&neighbour(key, i)]) } else { [0; 27] };
            let mut mesh_into = |out: &mut ChunkMesh| {
                mesh_brick_with(
                    field,
                    key,
                    level,
                    &around,
                    block,
                    Some(coarse),
                    scratch,
                    coarse_scratch,
                    out,
                );
            };
            if slot.vertices.capacity() == 0 {
                // A new slot: marched into the worker's chunk, which never grows, and given
                // just what it needs, rather than grown by doublings.
                mesh_into(mesh);
                slot.vertices.extend_from_slice(&mesh.vertices);
                slot.indices.extend_from_slice(&mesh.indices);
            } else {
                // A slot that held a chunk before keeps its vectors and takes this one in place.
                mesh_into(slot);
            }
        });
        for (i, (&key, slot)) in self.keys.iter().zip(&mut self.slots).enumerate() {
            if slot.is_empty() {
                self.diff.removed.push(key);
            } else {
                self.diff.upserted.push((key, std::mem::take(slot)));
                self.upserted_slots.push(i);
            }
        }
    }
}

/// Re-meshes the given bricks in parallel (see [`Mesher::remesh`]; a mesher kept between
/// calls reuses its buffers).
pub fn remesh<I: IntoIterator<Item = BrickKey>>(field: &Field, keys: I) -> MeshDiff {
    let mut mesher = Mesher::default();
    mesher.remesh(field, keys);
    mesher.take_diff()
}

/// Every brick that can hold triangles: a cell in brick `K` reads bricks `K ..= K + 1`, so
/// each brick `B` holding clay (stored, or given by the coarser levels) may put triangles in
/// bricks `B − 1 ..= B` on each axis.
pub fn meshable_bricks(field: &Field) -> Vec<BrickKey> {
    let holding = if field.has_levels_above(0) { field.covered_keys() } else { field.brick_keys().collect() };
    let mut keys: Vec<BrickKey> =
        holding.into_iter().flat_map(|b| GROUP.iter().map(move |&o| b - o)).collect();
    keys.sort_unstable_by_key(|k| k.to_array());
    keys.dedup();
    keys
}

/// Meshes the whole field; only upserts.
pub fn mesh_all(field: &Field) -> MeshDiff {
    let mut mesher = Mesher::default();
    mesher.mesh_all(field);
    mesher.take_diff()
}

/// Meshes the bricks the field marked dirty since the last call, draining its dirty set.
pub fn remesh_dirty(field: &mut Field) -> MeshDiff {
    let dirty = field.take_dirty();
    remesh(field, dirty)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Colour;

    fn ball(radius: i32) -> Field {
        let mut f = Field::new(0.001, 0.5);
        add_ball(&mut f, IVec3::ZERO, radius);
        f
    }

    fn add_ball(f: &mut Field, centre: IVec3, radius: i32) {
        let r = IVec3::splat(radius + 2);
        let grey: Colour = [0.5; 4];
        f.edit_box(centre - r, centre + r, true, |p, d, c| {
            *d = (0.5 - ((p - centre).as_vec3().length() - radius as f32) / 4.0).clamp(0.0, 1.0);
            *c = grey;
        });
    }

    #[test]
    fn dense_and_sparse_classification_find_the_same_chunks() {
        let dense = ball(30);
        // A second ball far away: the field's box is too sparse for a grid of it.
        let mut sparse = ball(30);
        add_ball(&mut sparse, IVec3::new(900, -40, 300), 12);
        for field in [&dense, &sparse] {
            // The definition: every brick that can hold triangles, each classified alone.
            let keys = meshable_bricks(field);
            let mut reference = MeshDiff::default();
            for &key in &keys {
                let mut mesh = ChunkMesh::default();
                mesh_brick(field, key, &mut Block::default(), &mut MarchScratch::default(), &mut mesh);
                if !mesh.is_empty() {
                    reference.upserted.push((key, mesh));
                }
            }
            assert!(reference.upserted_triangles() > 1000);
            assert_eq!(mesh_all(field).upserted, reference.upserted, "whole field");
            // A compact set is classified on a grid, a scattered one key by key.
            let far = IVec3::splat(10_000);
            for extra in [None, Some(far)] {
                let diff = remesh(field, keys.iter().copied().chain(extra));
                assert_eq!(diff.upserted, reference.upserted, "extra key {extra:?}");
                assert_eq!(
                    diff.removed.len() + diff.upserted.len(),
                    keys.len() + usize::from(extra.is_some())
                );
            }
        }
    }

    /// A ball of level `level` (voxels `2^level` times the finest), centred on level point
    /// `centre`.
    fn add_coarse_ball(f: &mut Field, level: usize, centre: IVec3, radius: i32) {
        let r = IVec3::splat(radius + 2);
        let grey: Colour = [0.4, 0.5, 0.6, 1.0];
        f.edit_level(
            level,
            centre - r,
            centre + r,
            true,
            |_, _, _| true,
            |p, d, c| {
                *d = (0.5 - ((p - centre).as_vec3().length() - radius as f32) / 2.0).clamp(0.0, 1.0);
                *c = grey;
            },
        );
    }

    #[test]
    fn coarse_bricks_made_once_per_call_mesh_as_made_for_each_brick() {
        // Coarse clay of two levels, and fine clay overlapping one of them: the mesher makes
        // the finest bricks the coarse levels give once for the call; meshing each brick alone
        // makes them again for every neighbour. Both must give the same chunks, bit for bit.
        let mut f = Field::new(0.001, 0.5);
        add_coarse_ball(&mut f, 2, IVec3::ZERO, 7);
        add_coarse_ball(&mut f, 1, IVec3::new(20, 3, -2), 6);
        add_ball(&mut f, IVec3::new(36, 6, -4), 9);
        assert!(f.has_levels_above(0));
        let keys = meshable_bricks(&f);
        let mut reference = MeshDiff::default();
        for &key in &keys {
            let mut mesh = ChunkMesh::default();
            mesh_brick(&f, key, &mut Block::default(), &mut MarchScratch::default(), &mut mesh);
            if !mesh.is_empty() {
                reference.upserted.push((key, mesh));
            }
        }
        assert!(reference.upserted.len() > 30, "{} chunks", reference.upserted.len());
        let mut mesher = Mesher::default();
        assert_eq!(mesher.mesh_all(&f).upserted, reference.upserted, "whole field");
        // And a part of it after the whole, with the bricks of the last call dropped.
        let some: Vec<BrickKey> = keys.iter().copied().step_by(3).collect();
        let want: Vec<_> = reference.upserted.iter().filter(|(k, _)| some.contains(k)).cloned().collect();
        assert_eq!(mesher.remesh(&f, some.iter().copied()).upserted, want, "a third of the keys");
    }

    #[test]
    fn a_mesher_lends_its_chunks_and_takes_them_back() {
        let mut f = ball(20);
        f.take_dirty();
        let keys = meshable_bricks(&f);
        let mut mesher = Mesher::default();
        let first = mesher.remesh(&f, keys.iter().copied()).clone();
        assert_eq!(mesher.mesh_all(&f).upserted, first.upserted);
        // A smaller set after a larger one: only its chunks, each as a fresh mesher makes it.
        f.edit_box(IVec3::new(18, -3, -3), IVec3::new(24, 3, 3), false, |_, d, _| *d = 0.0);
        let dirty: Vec<BrickKey> = f.take_dirty().into_iter().collect();
        let again = mesher.remesh(&f, dirty.iter().copied());
        assert_eq!(again.upserted, remesh(&f, dirty.iter().copied()).upserted);
        assert!(again.upserted.len() < first.upserted.len() && !again.is_empty());
        assert!(mesher.remesh(&f, []).is_empty());
    }

    #[test]
    fn a_brick_whose_upper_neighbour_crosses_away_from_their_shared_face_is_surely_empty() {
        // A small ball inside brick (1, 0, 0): its clay (out to 4 voxels from x = 12) stops
        // short of the brick's lower x face, the only part of it brick 0's cells read.
        let mut f = Field::new(0.001, 0.5);
        add_ball(&mut f, IVec3::new(12, 4, 4), 2);
        assert!(!surely_empty(&f, IVec3::new(1, 0, 0)));
        assert!(surely_empty(&f, IVec3::ZERO));
        // Moved across the face, it puts triangles in brick 0, which is no longer ruled out.
        let mut g = Field::new(0.001, 0.5);
        add_ball(&mut g, IVec3::new(9, 4, 4), 2);
        let mut mesh = ChunkMesh::default();
        mesh_brick(&g, IVec3::ZERO, &mut Block::default(), &mut MarchScratch::default(), &mut mesh);
        assert!(!mesh.is_empty() && !surely_empty(&g, IVec3::ZERO));
        // Both classifications (key by key and on a grid) agree with the definition.
        for field in [&f, &g] {
            let keys = meshable_bricks(field);
            let want: Vec<BrickKey> = keys
                .iter()
                .copied()
                .filter(|&k| {
                    mesh_brick(field, k, &mut Block::default(), &mut MarchScratch::default(), &mut mesh);
                    !mesh.is_empty()
                })
                .collect();
            let got: Vec<BrickKey> = remesh(field, keys).upserted.iter().map(|(k, _)| *k).collect();
            assert_eq!(got, want);
        }
    }

    #[test]
    fn only_bricks_away_from_the_surface_are_surely_empty() {
        let f = ball(30);
        assert!(surely_empty(&f, IVec3::ZERO), "deep inside");
        assert!(surely_empty(&f, IVec3::new(10, 0, 0)), "far outside");
        // The surface crosses x = 30 on the axis: bricks 3 (24..31) and its lower neighbour.
        assert!(!surely_empty(&f, IVec3::new(3, 0, 0)));
        // Every brick with triangles is one the shortcut keeps.
        for key in meshable_bricks(&f) {
            let mut mesh = ChunkMesh::default();
            mesh_brick(&f, key, &mut Block::default(), &mut MarchScratch::default(), &mut mesh);
            assert!(mesh.is_empty() || !surely_empty(&f, key), "brick {key} has triangles");
        }
    }
}
