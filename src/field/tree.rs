//! The field's storage: bricks keyed by signed brick coordinates, plus the dirty set.

use std::sync::Arc;

use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};

use super::brick::{
    dequantize, keys_over, quantize, Brick, BrickColours, BrickKey, Colour, LevelKey, Quantum, BRICK_SIZE,
    BRICK_VOLUME, DENSITY_ONE, LEVELS, MESHED_LEVELS,
};
use super::history::{History, HistoryConfig, HistoryError, HistoryStats, Step};
use crate::math::{IVec3, VoxelTransform};

/// Bricks whose mesh may have changed since the mesher last drained the set.
///
/// Brick maps and sets hash with FxHash: keys are small integer triples chosen by the field,
/// not by an adversary, and the default SipHash cost several percent of meshing.
pub type DirtySet = HashSet<BrickKey>;

/// Every brick whose mesh reads lattice point `p`.
///
/// The mesher meshes, for brick `K`, the cells whose minimum corner lies in `K` and takes
/// normals from central differences, so it reads lattice points `K·S − 1 ..= K·S + S + 1` on
/// each axis (the apron). A change at `p` therefore dirties bricks
/// `ceil((p − S − 1) / S) ..= floor((p + 1) / S)`.
pub fn bricks_reading(lo: IVec3, hi: IVec3) -> (BrickKey, BrickKey) {
    let s = IVec3::splat(BRICK_SIZE);
    let first = (lo - IVec3::splat(BRICK_SIZE + 1) + s - IVec3::ONE).div_euclid(s);
    let last = (hi + IVec3::ONE).div_euclid(s);
    (first, last)
}

/// One step of the undo history: the bricks it puts back, each key once (`None`: absent).
pub type HistoryStep = Vec<(LevelKey, Option<Arc<Brick>>)>;

/// One resolution level's bricks, with the lowest and highest density of each.
#[derive(Clone, Debug, Default)]
pub(super) struct Level {
    pub(super) bricks: HashMap<BrickKey, Arc<Brick>>,
    /// Density ranges of each stored brick, kept with every edit, so that whole bricks can be
    /// classified (inside, outside, crossing the surface) without reading them.
    pub(super) ranges: HashMap<BrickKey, Ranges>,
}

/// A brick's lowest and highest density over all its samples, and over those of each of its
/// three lower faces (local x, y or z 0): the only ones of its samples that the mesh cells of
/// the bricks below it read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ranges {
    /// Lowest and highest density of all the brick's samples.
    pub all: (f32, f32),
    /// The same for its samples of local x = 0, y = 0 and z = 0.
    pub low_faces: [(f32, f32); 3],
}

/// A sparse density + colour field on a regular lattice.
///
/// Invariants: densities are in [0, 1] (1 is full clay; the surface is the iso-level, default
/// 0.5); a lattice point of a level without a brick reads the coarser levels, and one no level
/// holds has density 0 and [`super::DEFAULT_COLOUR`]; every edit marks the bricks whose mesh
/// reads what it changed (see [`bricks_reading`]) in the dirty set.
///
/// Edits made between [`Field::begin_stroke`] and [`Field::end_stroke`] form one undo step
/// (see the `history` module).
///
/// Bricks are shared copy-on-write (`Arc`): the undo history and the autosave journal keep
/// the bricks a stroke replaced or made by taking a reference, and the first edit of a shared
/// brick copies it, so each stroke copies each brick it touches once, as before.
///
/// Constant tiles: a brick whose samples all hold one density and colour (the inside of solid
/// clay) is shared, one `Arc` per distinct value, among every key that holds it; the first
/// edit of such a key copies the tile into a brick of its own (copy-on-write), and an edit
/// that leaves a brick uniform shares the tile again. Readers see bricks either way.
///
/// Resolution levels: the field holds [`LEVELS`] lattices, level `l`'s voxels `2^l` times
/// the finest's (see the `levels` module). The methods without a level in their name speak of
/// the finest level, whose lattice is the one the mesher, the clay and sampling read; its
/// points read the coarser levels where it holds no brick ([`Field::density`]).
#[derive(Debug)]
pub struct Field {
    pub(super) transform: VoxelTransform,
    pub(super) iso: f32,
    /// The levels, finest first.
    pub(super) levels: Vec<Level>,
    /// The shared constant tiles, by the bits of their density and colour.
    tiles: HashMap<TileValue, Arc<Brick>>,
    dirty: DirtySet,
    /// Bricks of the coarser levels whose points changed since the dirty set was last read,
    /// with the box of their points that did (level lattice): the finest bricks these points
    /// reach are marked when it is read, so that a coarse stamp costs one mark per coarse
    /// brick, not one per finest brick under it, and no finest brick its change does not
    /// reach is re-meshed.
    coarse_dirty: HashMap<LevelKey, (IVec3, IVec3)>,
    pub(super) history: History,
}

impl Clone for Field {
    /// A copy of the samples and the dirty set, with an empty history of the same settings.
    fn clone(&self) -> Self {
        Self {
            transform: self.transform,
            iso: self.iso,
            levels: self.levels.clone(),
            tiles: self.tiles.clone(),
            dirty: self.dirty.clone(),
            coarse_dirty: self.coarse_dirty.clone(),
            history: History::new(self.history.config().clone()),
        }
    }
}

impl Field {
    /// An empty field with the given voxel size (metres) and iso-level.
    pub fn new(voxel_size_m: f32, iso: f32) -> Self {
        assert!(voxel_size_m > 0.0 && voxel_size_m.is_finite(), "voxel size must be positive");
        Self {
            transform: VoxelTransform::new(voxel_size_m),
            iso,
            levels: vec![Level::default(); LEVELS],
            tiles: HashMap::default(),
            dirty: DirtySet::default(),
            coarse_dirty: HashMap::default(),
            history: History::new(HistoryConfig::default()),
        }
    }

    /// Sets the undo history's limits and spill folder (steps already recorded are kept).
    pub fn set_history_config(&mut self, config: HistoryConfig) {
        let old = std::mem::replace(&mut self.history, History::new(config));
        drop(old);
    }

    /// Opens a stroke: its edits become one undo step. A stroke still open is closed first,
    /// and the redo steps are cleared.
    pub fn begin_stroke(&mut self) {
        self.history.begin();
    }

    /// Closes the open stroke, if any.
    pub fn end_stroke(&mut self) {
        self.history.end();
    }

    /// Whether a stroke is open.
    pub fn in_stroke(&self) -> bool {
        self.history.recording()
    }

    /// Takes back the open stroke's edits and forgets it: the field is bit for bit as it was
    /// when the stroke began, no undo step is left and the redo steps it cleared stay gone.
    /// The restored bricks are marked dirty. Returns whether a stroke was open.
    pub fn abandon_stroke(&mut self) -> bool {
        let Some((step, _)) = self.history.take_open() else { return false };
        self.swap_in(step);
        true
    }

    /// Exchanges the open stroke's saved bricks with the field's own: called once, the field is
    /// as it was when the stroke began (what a save stores beside the closed history) and the
    /// stroke holds its edits; called again, both are back, bit for bit. Nothing may edit the
    /// field in between. Returns whether a stroke was open.
    pub fn swap_open_stroke(&mut self) -> bool {
        let Some((mut step, seen)) = self.history.take_open() else { return false };
        for (key, brick) in &mut step.bricks {
            *brick = match brick.take() {
                Some(b) => self.store(*key, b),
                None => self.remove(*key),
            };
        }
        self.history.put_open((step, seen));
        true
    }

    /// Undoes the newest stroke (closing an open one first). Returns whether there was one.
    /// The restored bricks are marked dirty.
    pub fn undo(&mut self) -> Result<bool, HistoryError> {
        let Some(step) = self.history.pop_undo()? else { return Ok(false) };
        let redo = self.swap_in(step);
        self.history.push_redo(redo);
        Ok(true)
    }

    /// Redoes the newest undone stroke. Returns whether there was one.
    pub fn redo(&mut self) -> bool {
        let Some(step) = self.history.pop_redo() else { return false };
        let undo = self.swap_in(step);
        self.history.push_undo(undo);
        true
    }

    /// The undo history's counts.
    pub fn history_stats(&self) -> HistoryStats {
        self.history.stats()
    }

    /// The undo steps held in memory (oldest first; steps spilled to disk are left out) and
    /// the redo steps (the next redo last). Each step lists the bricks it puts back (`None`:
    /// absent), shared, not copied.
    pub fn history_in_memory(&self) -> (Vec<HistoryStep>, Vec<HistoryStep>) {
        let (undo, redo) = self.history.in_memory();
        let plain = |steps: Vec<&Step>| steps.into_iter().map(|s| s.bricks.clone()).collect();
        (plain(undo), plain(redo))
    }

    /// Replaces the undo history with `undo` (oldest first) and `redo` (the next redo last),
    /// as [`Field::history_in_memory`] gives them, within the history's memory budget.
    pub fn set_history(&mut self, undo: Vec<HistoryStep>, redo: Vec<HistoryStep>) {
        let steps = |v: Vec<HistoryStep>| v.into_iter().map(|bricks| Step { bricks }).collect();
        self.history.restore(steps(undo), steps(redo));
    }

    /// Puts the step's bricks in place and returns the ones they replaced.
    fn swap_in(&mut self, step: Step) -> Step {
        let mut replaced = Step { bricks: Vec::with_capacity(step.bricks.len()) };
        for (key, brick) in step.bricks {
            let old = match brick {
                Some(b) => self.store(key, b),
                None => self.remove(key),
            };
            replaced.bricks.push((key, old));
            self.history.note_changed(key);
            let base = key.key * BRICK_SIZE;
            self.mark_level_dirty(key.level.into(), base, base + IVec3::splat(BRICK_SIZE - 1));
        }
        replaced
    }

    /// Whether both fields hold the same samples, bit for bit (same bricks on every level,
    /// same values).
    pub fn same_samples(&self, other: &Field) -> bool {
        self.levels.iter().zip(&other.levels).all(|(mine, theirs)| same_level(mine, theirs))
    }

    /// Lattice ↔ world transform.
    pub fn transform(&self) -> &VoxelTransform {
        &self.transform
    }

    /// The density of the surface.
    pub fn iso(&self) -> f32 {
        self.iso
    }

    /// The density the mesher extracts the surface at: the iso-level moved up to halfway
    /// between two stored densities (within 2⁻¹⁶ of it). No sample holds it, so which side of
    /// the surface a sample lies on never rests on a tie: a sample stored at the iso-level
    /// itself is outside. Such samples are common (a box whose faces lie on the lattice has
    /// its whole outer layer at the iso-level), and a tie broken either way by rounding would
    /// let the smallest change of one sample move the surface by a voxel.
    pub fn surface_level(&self) -> f32 {
        (f32::from(quantize(self.iso).min(DENSITY_ONE - 1)) + 0.5) / f32::from(DENSITY_ONE)
    }

    /// Number of stored bricks of the finest level.
    pub fn brick_count(&self) -> usize {
        self.levels[0].bricks.len()
    }

    /// Number of stored bricks of `level`.
    pub fn level_brick_count(&self, level: usize) -> usize {
        self.levels[level].bricks.len()
    }

    /// The finest level's brick with this key, if stored.
    #[inline]
    pub fn brick(&self, key: BrickKey) -> Option<&Brick> {
        self.levels[0].bricks.get(&key).map(Arc::as_ref)
    }

    /// The brick with this level and key, if stored.
    #[inline]
    pub fn level_brick(&self, key: LevelKey) -> Option<&Brick> {
        self.levels[usize::from(key.level)].bricks.get(&key.key).map(Arc::as_ref)
    }

    /// Keys of `level`'s stored bricks, in no particular order.
    pub fn level_keys(&self, level: usize) -> impl Iterator<Item = BrickKey> + '_ {
        self.levels[level].bricks.keys().copied()
    }

    /// Whether a level coarser than `level` holds a brick.
    #[inline]
    pub fn has_levels_above(&self, level: usize) -> bool {
        self.levels.iter().skip(level + 1).any(|l| !l.bricks.is_empty())
    }

    /// The bricks that closed strokes, undo and redo changed since the last call, as they are
    /// now, in no particular order: shared, not copied (`None`: the brick is gone, its samples
    /// are empty). Edits outside strokes are not included. For the autosave journal; cost: one map lookup per
    /// changed brick.
    pub fn take_changed_bricks(&mut self) -> Vec<(LevelKey, Option<Arc<Brick>>)> {
        let keys = self.history.take_changed();
        keys.into_iter().map(|k| (k, self.stored(k).cloned())).collect()
    }

    /// Every stored brick of every level, shared (not copied), in no particular order.
    pub fn shared_bricks(&self) -> impl Iterator<Item = (LevelKey, &Arc<Brick>)> + '_ {
        self.levels
            .iter()
            .enumerate()
            .flat_map(|(l, level)| level.bricks.iter().map(move |(k, b)| (LevelKey::new(l, *k), b)))
    }

    /// The stored brick at `key`, shared.
    fn stored(&self, key: LevelKey) -> Option<&Arc<Brick>> {
        self.levels[usize::from(key.level)].bricks.get(&key.key)
    }

    /// Puts `brick` at `key` (a finest-level [`BrickKey`] or a [`LevelKey`]) as it is,
    /// replacing what was there, and marks what it changes dirty. An empty brick is stored too:
    /// under coarser clay it says the clay is empty there. For loading stored sculpts; not
    /// journaled.
    pub fn insert_brick(&mut self, key: impl Into<LevelKey>, mut brick: Brick) {
        let key = key.into();
        brick.compact();
        self.store(key, Arc::new(brick));
        let base = key.key * BRICK_SIZE;
        self.mark_level_dirty(key.level.into(), base, base + IVec3::splat(BRICK_SIZE - 1));
    }

    /// The brick stored at `key` (a finest-level [`BrickKey`] or a [`LevelKey`]), shared.
    pub fn shared_brick(&self, key: impl Into<LevelKey>) -> Option<&Arc<Brick>> {
        self.stored(key.into())
    }

    /// [`Field::replace_brick_within`] for a brick shared with another field (stored as it
    /// is, not copied).
    pub fn share_brick_within(&mut self, key: impl Into<LevelKey>, brick: Arc<Brick>, lo: IVec3, hi: IVec3) {
        let key = key.into();
        self.store(key, brick);
        let base = key.key * BRICK_SIZE;
        self.mark_level_dirty(key.level.into(), base + lo, base + hi);
    }

    /// [`Field::remove_brick`] for a caller that knows which of the brick's samples held
    /// anything: only what reads the samples `lo ..= hi` (local) is marked dirty.
    pub fn remove_brick_within(&mut self, key: impl Into<LevelKey>, lo: IVec3, hi: IVec3) {
        let key = key.into();
        self.remove(key);
        let base = key.key * BRICK_SIZE;
        self.mark_level_dirty(key.level.into(), base + lo, base + hi);
    }

    /// [`Field::insert_brick`] for a caller that knows which samples differ from the brick it
    /// replaces: only what reads the samples `lo ..= hi` (local to the brick, each in
    /// `0..BRICK_SIZE`) is marked dirty.
    pub fn replace_brick_within(&mut self, key: impl Into<LevelKey>, mut brick: Brick, lo: IVec3, hi: IVec3) {
        let key = key.into();
        brick.compact();
        self.store(key, Arc::new(brick));
        let base = key.key * BRICK_SIZE;
        self.mark_level_dirty(key.level.into(), base + lo, base + hi);
    }

    /// Removes the brick at `key` (its points read the coarser levels, or are empty), and marks
    /// what it changes dirty. For loading stored sculpts; not journaled.
    pub fn remove_brick(&mut self, key: impl Into<LevelKey>) {
        let key = key.into();
        self.remove(key);
        let base = key.key * BRICK_SIZE;
        self.mark_level_dirty(key.level.into(), base, base + IVec3::splat(BRICK_SIZE - 1));
    }

    /// The lowest and highest density of a stored brick of the finest level (`None`: no
    /// brick; its samples read the coarser levels, see [`Field::read_range`]).
    #[inline]
    pub fn density_range(&self, key: BrickKey) -> Option<(f32, f32)> {
        self.levels[0].ranges.get(&key).map(|r| r.all)
    }

    /// [`Field::read_range`] of finest-level brick `key`, with the lowest and highest density
    /// as readers see them on each of its lower faces (its samples of local x, y, z 0), the
    /// only ones the mesh cells of the bricks below it read: exact for a stored brick, else
    /// the whole brick's range. One look-up for both.
    pub fn read_ranges(&self, key: BrickKey) -> Option<Ranges> {
        match self.levels[0].ranges.get(&key) {
            Some(&r) => Some(r),
            None => self.read_range(key).map(|r| Ranges { all: r, low_faces: [r; 3] }),
        }
    }

    /// The lowest and highest density of a stored brick of any level.
    #[inline]
    pub fn level_density_range(&self, key: LevelKey) -> Option<(f32, f32)> {
        self.levels[usize::from(key.level)].ranges.get(&key.key).map(|r| r.all)
    }

    /// Keys of every stored brick of the finest level, in no particular order.
    pub fn brick_keys(&self) -> impl Iterator<Item = BrickKey> + '_ {
        self.levels[0].bricks.keys().copied()
    }

    /// Bytes the samples take in memory: each distinct brick's samples once (a constant tile
    /// shared by many keys counts once) plus the per-key bookkeeping (map entries and density
    /// ranges), not counting the undo history.
    pub fn memory_bytes(&self) -> usize {
        let per_key =
            std::mem::size_of::<(BrickKey, Arc<Brick>)>() + std::mem::size_of::<(BrickKey, Ranges)>();
        let per_brick = std::mem::size_of::<Brick>() + 2 * std::mem::size_of::<usize>();
        let mut seen = HashSet::<*const Brick>::default();
        let keys: usize = self.levels.iter().map(|l| l.bricks.len()).sum();
        let samples: usize = self
            .levels
            .iter()
            .flat_map(|l| l.bricks.values())
            .chain(self.tiles.values())
            .filter(|b| seen.insert(Arc::as_ptr(b)))
            .map(|b| per_brick + b.heap_bytes())
            .sum();
        keys * per_key + self.tiles.len() * (per_key + 4) + samples
    }

    /// Bytes a field of `keys` stored bricks, `own` of which hold samples of their own (of one
    /// colour; the others share constant tiles), takes in memory: what
    /// [`Field::memory_bytes`] counts for them, plus the spare room of its maps and of the
    /// dirty set, which holds each key until the mesher drains it. For estimates of a build
    /// before it starts.
    pub fn estimated_bytes(keys: f64, own: f64) -> f64 {
        use std::mem::size_of;
        let per_key =
            size_of::<(BrickKey, Arc<Brick>)>() + size_of::<(BrickKey, Ranges)>() + size_of::<BrickKey>() + 3; // a control byte in each of the three tables
                                                                                                               // The tables are at most 7/8 full and double as they grow: about 1.6 slots a key.
        let per_brick = size_of::<Brick>() + 2 * size_of::<usize>() + BRICK_VOLUME * size_of::<Quantum>();
        keys * per_key as f64 * 1.6 + own * per_brick as f64
    }

    /// Number of stored keys, on every level, that share a constant tile.
    pub fn tile_count(&self) -> usize {
        self.levels
            .iter()
            .flat_map(|l| l.bricks.values())
            .filter(|b| self.tiles.values().any(|t| Arc::ptr_eq(b, t)))
            .count()
    }

    /// Puts `brick` at `key` (sharing the constant tile of its value, if it is uniform) and
    /// records its density range; returns what was there.
    pub(super) fn store(&mut self, key: LevelKey, brick: Arc<Brick>) -> Option<Arc<Brick>> {
        let level = &mut self.levels[usize::from(key.level)];
        level.ranges.insert(key.key, brick_ranges(&brick));
        let brick = match brick.uniform_value() {
            Some(value) => self.tile(value, brick),
            None => brick,
        };
        let old = self.levels[usize::from(key.level)].bricks.insert(key.key, brick);
        if old.is_none() {
            self.note_presence(key);
        }
        old
    }

    /// Removes the brick at `key`; returns what was there.
    pub(super) fn remove(&mut self, key: LevelKey) -> Option<Arc<Brick>> {
        let level = &mut self.levels[usize::from(key.level)];
        level.ranges.remove(&key.key);
        let old = level.bricks.remove(&key.key);
        if old.is_some() {
            self.note_presence(key);
        }
        old
    }

    /// [`Self::note_presence_in_levels`] where the field has more than one level (kept out of
    /// line: the edit walks call it for every brick they make).
    #[inline]
    fn note_presence(&mut self, key: LevelKey) {
        if key.level != 0 || self.has_levels_above(0) {
            self.note_presence_in_levels(key);
        }
    }

    /// After brick `key` came or went: where the field has more than one level, which level
    /// holds the clay there changed, though no density may have. The mesher meshes each brick
    /// on the coarsest level free of bricks of the finer [`MESHED_LEVELS`], with cells that
    /// conform to finer neighbours: it meshes the bricks reading the brick's points, and their
    /// neighbours, differently, and those are marked dirty.
    #[inline(never)]
    fn note_presence_in_levels(&mut self, key: LevelKey) {
        let level = usize::from(key.level);
        if level >= MESHED_LEVELS {
            return;
        }
        let scale = 1 << level;
        let base = key.key * BRICK_SIZE * scale;
        let top = (key.key * BRICK_SIZE + IVec3::splat(BRICK_SIZE - 1)) * scale;
        // Where no other level holds a brick within a brick of this one, the bricks around are
        // meshed on this level or hold no clay: none conforms to another's level, and only
        // those reading the brick's points change.
        let (near_lo, near_hi) =
            (base - IVec3::splat(BRICK_SIZE * scale), top + IVec3::splat(BRICK_SIZE * scale));
        let near = |l: usize, other: &Level| {
            let side = IVec3::splat(BRICK_SIZE << l);
            let (a, b) = (near_lo.div_euclid(side), near_hi.div_euclid(side));
            let span = b - a + IVec3::ONE;
            // A finer level's many keys there are not looked up one by one.
            if span.x * span.y * span.z > 64 {
                return !other.bricks.is_empty();
            }
            (a.z..=b.z).any(|z| {
                (a.y..=b.y).any(|y| (a.x..=b.x).any(|x| other.bricks.contains_key(&IVec3::new(x, y, z))))
            })
        };
        let alone = self
            .levels
            .iter()
            .enumerate()
            .all(|(l, other)| l == level || other.bricks.is_empty() || !near(l, other));
        let beyond = if alone { IVec3::ZERO } else { IVec3::splat(BRICK_SIZE) };
        self.mark_dirty(base - beyond, top + beyond);
    }

    /// The shared tile of `value`, made from `brick` (which holds it) if there is none yet.
    fn tile(&mut self, value: (f32, Colour), brick: Arc<Brick>) -> Arc<Brick> {
        if self.tiles.len() >= MAX_UNUSED_TILES {
            // Tiles no key shares any more (values that no longer occur).
            self.tiles.retain(|_, t| Arc::strong_count(t) > 1);
        }
        let (density, colour) = value;
        let bits = [
            density.to_bits(),
            colour[0].to_bits(),
            colour[1].to_bits(),
            colour[2].to_bits(),
            colour[3].to_bits(),
        ];
        self.tiles.entry(bits).or_insert(brick).clone()
    }

    /// Samples strictly between empty and full: the band around the surface (what a narrow-band
    /// level set such as OpenVDB's stores as active voxels).
    /// Stored samples of every level count.
    pub fn band_samples(&self) -> usize {
        self.levels
            .iter()
            .flat_map(|l| l.bricks.values())
            .map(|b| b.density.iter().filter(|&&d| d > 0 && d < DENSITY_ONE).count())
            .sum()
    }

    /// Calls `edit` on every lattice point of the box `lo ..= hi`, brick by brick.
    ///
    /// `edit(point, density, colour)` may change the sample. Where no brick exists, `create`
    /// decides: `true` makes one (for edits that add matter), `false` skips those points (for
    /// edits that only remove or recolour matter). Bricks left empty are dropped. The colour
    /// given to a sample left empty is not kept (an empty sample's colour means nothing; see
    /// [`Brick::compact`]). The bricks whose mesh reads a sample the edit changed (its density,
    /// or the colour of a sample holding matter) are marked dirty.
    pub fn edit_box(
        &mut self,
        lo: IVec3,
        hi: IVec3,
        create: bool,
        edit: impl FnMut(IVec3, &mut f32, &mut Colour),
    ) {
        self.edit_region(lo, hi, create, |_, _| true, edit);
    }

    /// [`Field::edit_box`] for edits that may leave whole parts of the box unchanged:
    /// `reaches(a, b)` says whether the edit can change a point of the box `a ..= b` (one
    /// brick's share of `lo ..= hi`); where it cannot, the brick is neither created nor walked.
    pub fn edit_region(
        &mut self,
        lo: IVec3,
        hi: IVec3,
        create: bool,
        reaches: impl Fn(IVec3, IVec3) -> bool,
        edit: impl FnMut(IVec3, &mut f32, &mut Colour),
    ) {
        self.edit_where(lo, hi, create, |a, b, _| reaches(a, b), whole_rows, edit);
    }

    /// [`Field::edit_region`] for edits that also know which bricks they cannot change from
    /// the brick's lowest and highest density: `changes(a, b, range)` gets the brick's
    /// [`Field::density_range`] too (`None`: no brick), so that, say, adding matter skips a
    /// brick that is already full without copying it; and `rows(y, z)` gives the span
    /// `(first, last)` of `x`, inclusive, on each row of the box that the edit can change
    /// (none where `first > last`; every sample with [`whole_rows`]), so that, say, a ball's
    /// edit visits only the samples within its reach. `edit` is called on the samples both
    /// allow, and only on those.
    #[inline(never)]
    pub fn edit_where(
        &mut self,
        lo: IVec3,
        hi: IVec3,
        create: bool,
        changes: impl Fn(IVec3, IVec3, Option<(f32, f32)>) -> bool,
        rows: impl Fn(i32, i32) -> (i32, i32),
        edit: impl FnMut(IVec3, &mut f32, &mut Colour),
    ) {
        self.edit_samples(0, lo, hi, Walk { create, refine: true }, Reach { bricks: changes, rows }, edit);
    }

    /// The brick walk of [`Field::edit_where`] on `level`'s lattice, doing as `walk` says
    /// where the level holds no brick.
    pub(super) fn edit_samples(
        &mut self,
        level: usize,
        lo: IVec3,
        hi: IVec3,
        walk: Walk,
        reach: Reach<impl Fn(IVec3, IVec3, Option<(f32, f32)>) -> bool, impl Fn(i32, i32) -> (i32, i32)>,
        mut edit: impl FnMut(IVec3, &mut f32, &mut Colour),
    ) {
        let mut rows = RowSpans::new(reach.rows);
        self.edit_bricks(level, lo, hi, walk, reach.bricks, |brick, base, a, b, mut fresh| {
            rows.enter(base);
            let mut changed = Changed::NONE;
            for z in a.z..=b.z {
                for y in a.y..=b.y {
                    let mut row = Row::NONE;
                    for x in rows.local(base, a, b, y, z) {
                        let local = IVec3::new(x, y, z);
                        let i = Brick::linear(local);
                        let (stored, old) = (brick.density[i], brick.colour[i]);
                        let (mut density, mut colour) = (dequantize(stored), old);
                        edit(base + local, &mut density, &mut colour);
                        let d = quantize(density);
                        brick.density[i] = d;
                        let mut change = d != stored;
                        // An empty sample's colour means nothing: it is not stored.
                        if d > 0 {
                            let recoloured = colours_differ(colour, old);
                            if fresh {
                                brick.colour = BrickColours::Uniform(colour);
                                fresh = false;
                            } else if recoloured {
                                brick.colour.set(i, colour);
                            }
                            change |= recoloured;
                        }
                        if change {
                            row.add(x);
                        }
                    }
                    changed.add_row(row, y, z);
                }
            }
            changed
        });
    }

    /// [`Field::edit_region`] for edits that only lower or reshape the matter where it is and
    /// leave its colour alone (carving): `edit(point, density)` sees no colour, so the walk
    /// neither reads nor writes one, and no brick is created. `rows` as for
    /// [`Field::edit_where`].
    pub fn edit_density(
        &mut self,
        lo: IVec3,
        hi: IVec3,
        reaches: impl Fn(IVec3, IVec3) -> bool,
        rows: impl Fn(i32, i32) -> (i32, i32),
        mut edit: impl FnMut(IVec3, &mut f32),
    ) {
        let mut rows = RowSpans::new(rows);
        self.edit_bricks(
            0,
            lo,
            hi,
            Walk { create: false, refine: true },
            |a, b, _| reaches(a, b),
            |brick, base, a, b, _| {
                rows.enter(base);
                let mut changed = Changed::NONE;
                for z in a.z..=b.z {
                    for y in a.y..=b.y {
                        let start = Brick::linear(IVec3::new(0, y, z));
                        let mut row = Row::NONE;
                        for x in rows.local(base, a, b, y, z) {
                            let stored = &mut brick.density[start + x as usize];
                            let mut density = dequantize(*stored);
                            edit(base + IVec3::new(x, y, z), &mut density);
                            let d = quantize(density);
                            if d != *stored {
                                *stored = d;
                                row.add(x);
                            }
                        }
                        changed.add_row(row, y, z);
                    }
                }
                changed
            },
        );
    }

    /// Edits the stored bricks of `level` over `lo ..= hi`, neither creating nor refining any
    /// (see [`Field::edit_where`] for `edit`).
    pub(super) fn edit_existing(
        &mut self,
        level: usize,
        lo: IVec3,
        hi: IVec3,
        edit: impl FnMut(IVec3, &mut f32, &mut Colour),
    ) {
        self.edit_samples(
            level,
            lo,
            hi,
            Walk { create: false, refine: false },
            Reach { bricks: |_, _, _| true, rows: whole_rows },
            edit,
        );
    }

    /// The brick walk under every edit: for each brick of `level` over `lo ..= hi` that
    /// `changes`, records it for undo, copies it if shared, lets `samples(brick, base, a, b,
    /// fresh)` edit its points `base + (a ..= b)` (`fresh`: the brick was made empty for this
    /// edit) and say which it changed, marks the bricks reading those dirty, then drops the
    /// brick if empty, shares it as a tile if uniform, and keeps its density ranges. Where
    /// the level holds no brick, `walk` says whether to refine one from the coarser levels
    /// (where they hold clay) and whether to create an empty one.
    ///
    /// Afterwards, the walked bricks that hold no detail over the coarser levels are dropped
    /// (see the `levels` module).
    pub(super) fn edit_bricks(
        &mut self,
        level: usize,
        lo: IVec3,
        hi: IVec3,
        walk: Walk,
        changes: impl Fn(IVec3, IVec3, Option<(f32, f32)>) -> bool,
        mut samples: impl FnMut(&mut Brick, IVec3, IVec3, IVec3, bool) -> Changed,
    ) {
        if lo.cmpgt(hi).any() {
            return;
        }
        let above = self.has_levels_above(level);
        let mut walked = Vec::new();
        let s = IVec3::splat(BRICK_SIZE);
        for key in keys_over(lo, hi) {
            let level_key = LevelKey::new(level, key);
            let base = key * s;
            let a = lo.max(base) - base;
            let b = hi.min(base + s - IVec3::ONE) - base;
            let mut stored = self.levels[level].bricks.contains_key(&key);
            if !stored && walk.refine && above && self.reads_above(level, key) {
                // The coarser levels hold clay here: the level's brick is theirs first.
                if let Some(refined) = self.interpolated_brick(level, key) {
                    if !changes(base + a, base + b, Some(brick_ranges(&refined).all)) {
                        continue;
                    }
                    self.history.touch(level_key, None);
                    self.store(level_key, Arc::new(refined));
                    stored = true;
                }
            }
            // The brick's range as it stands (refined above, if it was).
            let prior = self.levels[level].ranges.get(&key).map(|r| r.all);
            if !changes(base + a, base + b, prior) {
                continue;
            }
            if !stored && !walk.create {
                continue;
            }
            self.history.touch(level_key, self.levels[level].bricks.get(&key));
            if above {
                walked.push(key);
            }
            // A brick made by this edit holds no matter yet: its colour is that of the
            // first matter the edit puts in it.
            let fresh = !stored;
            if fresh {
                self.note_presence(level_key);
            }
            // An empty brick says nothing unless coarser clay would show through it (then the
            // coarsening below drops it if that clay is empty there too).
            let keep_empty = above && self.reads_above(level, key);
            // Copies the brick if the history, the journal or a tile shares it.
            let brick = Arc::make_mut(self.levels[level].bricks.entry(key).or_default());
            let changed = samples(brick, base, a, b, fresh);
            // A stored brick the edit left as it was keeps its compaction and its ranges; one
            // of one density may be a tile's copy, and is shared again below.
            if !fresh && changed.bounds().is_none() && prior.is_some_and(|(lo, hi)| lo != hi) {
                continue;
            }
            brick.compact();
            let ranges = brick_ranges(brick);
            let range = ranges.all;
            // One density everywhere (the range says so without another pass) and one
            // colour: a constant tile.
            let uniform = match (range.0.to_bits() == range.1.to_bits(), &brick.colour) {
                (true, &BrickColours::Uniform(colour)) => Some(colour),
                _ => None,
            };
            // Only the samples the edit changed: the bricks it skipped (out of its reach, or
            // unchanged by it) and the parts of walked bricks it left alone keep their meshes.
            if let Some((a, b)) = changed.bounds() {
                self.mark_level_dirty(level, base + a, base + b);
            }
            if range.1 == 0.0 && !keep_empty {
                self.remove(level_key);
                continue;
            }
            if let Some(colour) = uniform {
                let edited = self.levels[level].bricks[&key].clone();
                let tile = self.tile((range.0, colour), edited);
                self.levels[level].bricks.insert(key, tile);
            }
            self.levels[level].ranges.insert(key, ranges);
        }
        if above {
            self.coarsen(level, &walked);
        }
    }

    /// Marks dirty every finest-level brick whose mesh reads a point that level `level`'s
    /// points `lo ..= hi` reach (finest points strictly within one of its voxels).
    pub(super) fn mark_level_dirty(&mut self, level: usize, lo: IVec3, hi: IVec3) {
        if level == 0 {
            self.mark_dirty(lo, hi);
        } else {
            for key in keys_over(lo, hi) {
                let base = key * BRICK_SIZE;
                let (a, b) = (lo.max(base), hi.min(base + IVec3::splat(BRICK_SIZE - 1)));
                self.coarse_dirty
                    .entry(LevelKey::new(level, key))
                    .and_modify(|(lo, hi)| (*lo, *hi) = (lo.min(a), hi.max(b)))
                    .or_insert((a, b));
            }
        }
    }

    /// Marks the finest bricks that the coarse points changed since the last read reach.
    fn settle_dirty(&mut self) {
        let mut coarse = std::mem::take(&mut self.coarse_dirty);
        for (key, (lo, hi)) in coarse.drain() {
            let scale = 1 << key.level;
            self.mark_dirty((lo - IVec3::ONE) * scale + IVec3::ONE, (hi + IVec3::ONE) * scale - IVec3::ONE);
        }
        // The map keeps its memory for the next marks.
        self.coarse_dirty = coarse;
    }

    /// Marks dirty every brick whose mesh reads a lattice point of `lo ..= hi`.
    pub fn mark_dirty(&mut self, lo: IVec3, hi: IVec3) {
        let (first, last) = bricks_reading(lo, hi);
        for z in first.z..=last.z {
            for y in first.y..=last.y {
                for x in first.x..=last.x {
                    self.dirty.insert(IVec3::new(x, y, z));
                }
            }
        }
    }

    /// The bricks marked dirty since the last call, leaving the set empty.
    pub fn take_dirty(&mut self) -> DirtySet {
        self.settle_dirty();
        std::mem::take(&mut self.dirty)
    }

    /// The bricks marked dirty since the last call, leaving the set empty but keeping its
    /// memory for the next marks.
    pub fn drain_dirty(&mut self) -> impl Iterator<Item = BrickKey> + '_ {
        self.settle_dirty();
        self.dirty.drain()
    }

    /// The dirty set, without draining it.
    pub fn dirty(&mut self) -> &DirtySet {
        self.settle_dirty();
        &self.dirty
    }
}

/// Where an edit can change the field (see [`Field::edit_where`]): which bricks, from their
/// share of the edit's box and their density range, and which samples of each row.
pub(super) struct Reach<B, R> {
    pub(super) bricks: B,
    pub(super) rows: R,
}

/// The span of `x` of every row: for edits that may change any sample of their box (see
/// [`Field::edit_where`]).
pub fn whole_rows(_y: i32, _z: i32) -> (i32, i32) {
    (i32::MIN, i32::MAX)
}

/// An edit's span of `x` on each row `(y, z)`, asked of its `rows` once for the bricks of one
/// row of bricks (the walk takes them in turn, `x` fastest) and only for the rows it walks.
struct RowSpans<R> {
    rows: R,
    /// The `y`, `z` of the lowest sample of the row of bricks whose spans are kept.
    column: Option<(i32, i32)>,
    /// Per row of those bricks (local `y` fastest); `None` until asked.
    spans: [Option<(i32, i32)>; (BRICK_SIZE * BRICK_SIZE) as usize],
}

impl<R: Fn(i32, i32) -> (i32, i32)> RowSpans<R> {
    fn new(rows: R) -> Self {
        Self { rows, column: None, spans: [None; (BRICK_SIZE * BRICK_SIZE) as usize] }
    }

    /// Readies the spans of the brick at `base` (those of its row of bricks are kept).
    #[inline]
    fn enter(&mut self, base: IVec3) {
        if self.column != Some((base.y, base.z)) {
            self.column = Some((base.y, base.z));
            self.spans = [None; (BRICK_SIZE * BRICK_SIZE) as usize];
        }
    }

    /// The local `x` to visit on row `(y, z)` (local) of the brick at `base` (entered last),
    /// whose share of the box is `a ..= b`. (Half open: an inclusive range costs a flag and
    /// its test per step, and the walks step it once per sample.)
    #[inline]
    fn local(&mut self, base: IVec3, a: IVec3, b: IVec3, y: i32, z: i32) -> std::ops::Range<i32> {
        let row = (y + BRICK_SIZE * z) as usize;
        let (first, last) = *self.spans[row].get_or_insert_with(|| (self.rows)(base.y + y, base.z + z));
        a.x.max(first.saturating_sub(base.x))..b.x.min(last.saturating_sub(base.x)) + 1
    }
}

/// What the brick walk does where a level holds no brick.
#[derive(Clone, Copy, Debug)]
pub(super) struct Walk {
    /// Make an empty brick (for edits that add matter).
    pub(super) create: bool,
    /// Store the brick the coarser levels give, where they hold clay (for every edit of the
    /// clay; not for carrying a coarse edit down into the finer bricks that exist).
    pub(super) refine: bool,
}

/// Whether two levels hold the same bricks, bit for bit.
fn same_level(mine: &Level, theirs: &Level) -> bool {
    mine.bricks.len() == theirs.bricks.len()
        && mine.bricks.iter().all(|(k, b)| {
            theirs.bricks.get(k).is_some_and(|o| {
                b.density == o.density
                    && b.colour
                        .iter()
                        .flatten()
                        .zip(o.colour.iter().flatten())
                        .all(|(x, y)| x.to_bits() == y.to_bits())
            })
        })
}

/// The bits of a constant tile's density and RGBA colour.
type TileValue = [u32; 5];

/// Distinct tile values kept before those no key shares are forgotten.
const MAX_UNUSED_TILES: usize = 64;

/// The box of the samples an edit changed in one brick (local coordinates), grown row by
/// row; empty until the first.
#[derive(Clone, Copy, Debug)]
pub(super) struct Changed {
    lo: IVec3,
    hi: IVec3,
}

impl Changed {
    pub(super) const NONE: Changed = Changed { lo: IVec3::MAX, hi: IVec3::MIN };

    /// Grows the box by the changed samples of row `(y, z)`, if any.
    #[inline]
    pub(super) fn add_row(&mut self, row: Row, y: i32, z: i32) {
        if row.first <= row.last {
            self.lo = self.lo.min(IVec3::new(row.first, y, z));
            self.hi = self.hi.max(IVec3::new(row.last, y, z));
        }
    }

    /// The box, or `None` where nothing changed.
    pub(super) fn bounds(self) -> Option<(IVec3, IVec3)> {
        self.lo.cmple(self.hi).all().then_some((self.lo, self.hi))
    }
}

/// Whether two colours differ in any bit (so a sign of zero counts, unlike `!=`).
#[inline]
fn colours_differ(a: Colour, b: Colour) -> bool {
    // Without a branch per channel: the loops call this for every sample they edit.
    a.iter().zip(&b).fold(0, |bits, (x, y)| bits | (x.to_bits() ^ y.to_bits())) != 0
}

/// The first and last changed sample of a row, walked in increasing `x`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Row {
    first: i32,
    last: i32,
}

impl Row {
    pub(super) const NONE: Row = Row { first: i32::MAX, last: i32::MIN };

    #[inline]
    pub(super) fn add(&mut self, x: i32) {
        self.first = self.first.min(x);
        self.last = x;
    }
}

/// Lowest and highest density of a brick's samples, and of those on each lower face.
///
/// The samples are folded lane by lane, four rows (one `y`, `z` each, all `x`) at a time:
/// lane `x + S·j` of a fold holds the range of the folded rows' samples at that `x` in their
/// `j`-th row of four. Chunk `k` holds rows `(y, z) = (4·(k % 2) + j, k / 2)`, so the lanes
/// with `x = 0` of the fold over all chunks give the lower x face, the lanes of `j = 0` of the
/// fold over the even chunks the lower y face (rows `y = 0`), and the fold over the first two
/// chunks the lower z face. Element-wise folds of fixed-size chunks vectorise (a few vector
/// instructions per chunk); a fold along each row was a compare per sample, and the walk
/// takes the ranges of every brick it edits.
fn brick_ranges(brick: &Brick) -> Ranges {
    const S: usize = BRICK_SIZE as usize;
    const W: usize = 4 * S;
    /// Lanes as `i16` offset by `i16::MIN`, which keeps the order of the stored values: the
    /// baseline x86-64 instruction set compares 16-bit lanes signed only.
    type Lanes = [i16; W];
    #[inline(always)]
    fn fold<'a>(chunks: impl Iterator<Item = &'a [Quantum; W]>) -> (Lanes, Lanes) {
        let (mut lo, mut hi) = ([i16::MAX; W], [i16::MIN; W]);
        for chunk in chunks {
            for i in 0..W {
                let v = chunk[i] as i16 ^ i16::MIN;
                lo[i] = lo[i].min(v);
                hi[i] = hi[i].max(v);
            }
        }
        (lo, hi)
    }
    /// The range over some lanes of a fold.
    #[inline(always)]
    fn across((lo, hi): &(Lanes, Lanes), lanes: impl Iterator<Item = usize>) -> (f32, f32) {
        let (lo, hi) = lanes.fold((i16::MAX, i16::MIN), |(l, h), i| (l.min(lo[i]), h.max(hi[i])));
        (dequantize((lo ^ i16::MIN) as Quantum), dequantize((hi ^ i16::MIN) as Quantum))
    }
    let chunks: &[[Quantum; W]; BRICK_VOLUME / W] = bytemuck::cast_ref(&*brick.density);
    let all = fold(chunks.iter());
    let even = fold(chunks.iter().step_by(2));
    let first = fold(chunks[..2].iter());
    Ranges {
        all: across(&all, 0..W),
        low_faces: [across(&all, (0..W).step_by(S)), across(&even, 0..S), across(&first, 0..W)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::DEFAULT_COLOUR;

    #[test]
    fn absent_points_are_empty() {
        let f = Field::new(0.001, 0.5);
        assert_eq!(f.density(IVec3::new(-100, 5, 3)), 0.0);
        assert_eq!(f.colour(IVec3::ZERO), DEFAULT_COLOUR);
    }

    #[test]
    fn edit_box_writes_across_negative_bricks_and_drops_empty_ones() {
        let mut f = Field::new(0.001, 0.5);
        f.edit_box(IVec3::splat(-3), IVec3::splat(2), true, |_, d, _| *d = 1.0);
        assert_eq!(f.brick_count(), 8);
        assert_eq!(f.density(IVec3::splat(-3)), 1.0);
        assert_eq!(f.density(IVec3::splat(-4)), 0.0);
        assert!((f.mass() - 216.0).abs() < 1e-9);
        assert_eq!(f.density_range(IVec3::splat(-1)), Some((0.0, 1.0)));
        f.edit_box(IVec3::splat(-3), IVec3::splat(2), false, |_, d, _| *d = 0.0);
        assert_eq!(f.brick_count(), 0);
        assert_eq!(f.density_range(IVec3::splat(-1)), None);
    }

    #[test]
    fn solid_interiors_share_constant_tiles() {
        let mut f = Field::new(0.001, 0.5);
        f.edit_box(IVec3::splat(0), IVec3::splat(31), true, |_, d, _| *d = 1.0);
        assert_eq!((f.brick_count(), f.tile_count()), (64, 64));
        // 64 keys, one shared brick of samples: far less than 64 bricks' samples.
        assert!(f.memory_bytes() < 64 * 256 + 2 * BRICK_VOLUME * 4, "{}", f.memory_bytes());
        let solid = f.clone();

        // Editing one key copies the tile for it alone.
        f.begin_stroke();
        f.edit_box(IVec3::splat(3), IVec3::splat(3), false, |_, d, _| *d = 0.25);
        f.end_stroke();
        assert_eq!(f.tile_count(), 63);
        assert_eq!(f.density(IVec3::splat(3)), 0.25);
        assert_eq!(f.density(IVec3::splat(11)), 1.0);
        assert_eq!(f.density(IVec3::new(3, 3, 2)), 1.0);

        // Filling it again shares the tile again; undo restores exactly.
        f.begin_stroke();
        f.edit_box(IVec3::splat(3), IVec3::splat(3), false, |_, d, _| *d = 1.0);
        f.end_stroke();
        assert_eq!(f.tile_count(), 64);
        assert!(f.undo().unwrap() && f.undo().unwrap());
        assert!(f.same_samples(&solid));
        assert_eq!(f.tile_count(), 64);
    }

    #[test]
    fn an_abandoned_stroke_leaves_the_field_and_its_history_as_they_were() {
        let mut f = Field::new(0.001, 0.5);
        f.begin_stroke();
        f.edit_box(IVec3::ZERO, IVec3::splat(20), true, |_, d, _| *d = 1.0);
        f.end_stroke();
        let before = f.clone();
        let stats = f.history_stats();
        f.begin_stroke();
        // Changes a brick, removes one's matter, and makes new ones.
        f.edit_box(IVec3::splat(4), IVec3::splat(40), true, |p, d, _| *d = if p.x < 10 { 0.0 } else { 0.75 });
        assert!(!f.same_samples(&before));
        // The field as it was when the stroke began, for the call alone.
        let after = f.clone();
        assert!(f.swap_open_stroke());
        assert!(f.same_samples(&before) && f.in_stroke(), "as the stroke found it");
        assert!(f.swap_open_stroke());
        assert!(f.same_samples(&after) && f.in_stroke(), "the stroke's edits are back, and it is still open");
        assert!(f.abandon_stroke());
        assert!(f.same_samples(&before), "bit for bit as the stroke found it");
        assert!(!f.in_stroke() && !f.abandon_stroke());
        let now = f.history_stats();
        assert_eq!((now.undo_in_memory, now.memory_bytes), (stats.undo_in_memory, stats.memory_bytes));
        // The step before it is still the newest.
        assert!(f.undo().unwrap());
        assert_eq!(f.brick_count(), 0);
    }

    #[test]
    fn a_painted_tile_keeps_its_neighbours_colour() {
        let red = [1.0, 0.0, 0.0, 1.0];
        let mut f = Field::new(0.001, 0.5);
        f.edit_box(IVec3::ZERO, IVec3::splat(15), true, |_, d, _| *d = 1.0);
        f.edit_box(IVec3::ZERO, IVec3::splat(7), false, |_, _, c| *c = red);
        // The painted brick is a tile of its own value; the others keep sharing the grey one.
        assert_eq!(f.tile_count(), 8);
        assert_eq!(f.colour(IVec3::splat(7)), red);
        assert_eq!(f.colour(IVec3::splat(8)), DEFAULT_COLOUR);
        f.edit_box(IVec3::ZERO, IVec3::ZERO, false, |_, _, c| *c = DEFAULT_COLOUR);
        assert_eq!((f.colour(IVec3::ZERO), f.colour(IVec3::ONE)), (DEFAULT_COLOUR, red));
        assert_eq!(f.tile_count(), 7);
        let painted = f.brick(IVec3::ZERO).unwrap();
        assert_eq!(painted.heap_bytes(), BRICK_VOLUME * 18, "two colours of matter: per-sample colours");
    }

    #[test]
    fn carving_density_alone_equals_carving_through_the_colour_walk() {
        let (red, blue) = ([1.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0]);
        let mut f = Field::new(0.001, 0.5);
        f.edit_box(IVec3::splat(-8), IVec3::splat(23), true, |p, d, c| {
            *d = 1.0;
            *c = if p.x < 4 { red } else { blue };
        });
        let carve = |p: IVec3| ((p.x - 6).pow(2) + (p.y - 2).pow(2) + p.z.pow(2)) as f32 / 100.0;
        let reaches = |a: IVec3, _: IVec3| a.x < 8;
        let mut walked = f.clone();
        walked.begin_stroke();
        walked
            .edit_region(IVec3::splat(-8), IVec3::splat(23), false, reaches, |p, d, _| *d = d.min(carve(p)));
        walked.end_stroke();
        f.begin_stroke();
        f.edit_density(IVec3::splat(-8), IVec3::splat(23), reaches, whole_rows, |p, d| *d = d.min(carve(p)));
        f.end_stroke();
        assert!(f.same_samples(&walked));
        assert_eq!((f.brick_count(), f.tile_count()), (walked.brick_count(), walked.tile_count()));
        assert_eq!(f.density(IVec3::new(6, 2, 0)), 0.0);
        assert_eq!((f.colour(IVec3::new(3, 9, 9)), f.colour(IVec3::new(5, 9, 9))), (red, blue));
        assert_eq!(f.density(IVec3::new(9, 2, 0)), 1.0, "bricks beyond the reach are not walked");
        f.undo().unwrap();
        walked.undo().unwrap();
        assert!(f.same_samples(&walked));
    }

    #[test]
    fn new_matter_of_one_colour_keeps_its_colour_once() {
        let red = [1.0, 0.0, 0.0, 1.0];
        let mut f = Field::new(0.001, 0.5);
        // Matter in a corner of a new brick: the brick's colour is the matter's.
        f.edit_box(IVec3::splat(5), IVec3::splat(7), true, |_, d, c| {
            *d = 0.5;
            *c = red;
        });
        let brick = f.brick(IVec3::ZERO).unwrap();
        assert_eq!((brick.colour.is_uniform(), brick.colour[0]), (true, red));
        // Painting empty samples blue keeps nothing: they hold no matter to colour.
        f.edit_box(IVec3::ZERO, IVec3::splat(4), false, |_, _, c| *c = [0.0, 0.0, 1.0, 1.0]);
        assert!(f.brick(IVec3::ZERO).unwrap().colour.is_uniform());
        assert_eq!(f.brick(IVec3::ZERO).unwrap().heap_bytes(), BRICK_VOLUME * 2);
        assert_eq!(f.colour(IVec3::splat(6)), red);
    }

    #[test]
    fn dirty_set_covers_every_mesh_reading_the_change() {
        let mut f = Field::new(0.001, 0.5);
        // Point 0 of brick 0 is read by brick −1 (its cells reach +1 and gradients +2)...
        f.mark_dirty(IVec3::ZERO, IVec3::ZERO);
        let d = f.take_dirty();
        assert!(d.contains(&IVec3::splat(-1)) && d.contains(&IVec3::ZERO));
        assert_eq!(d.len(), 8);
        // ...and point 7 by brick 1 (its gradient at point 8 reads point 7).
        f.mark_dirty(IVec3::splat(7), IVec3::splat(7));
        let d = f.take_dirty();
        assert!(d.contains(&IVec3::ONE) && d.contains(&IVec3::ZERO) && !d.contains(&IVec3::splat(-1)));
        // Points 2..=6 are read by brick 0 alone.
        let (first, last) = bricks_reading(IVec3::splat(2), IVec3::splat(6));
        assert_eq!((first, last), (IVec3::ZERO, IVec3::ZERO));
    }

    #[test]
    fn an_edit_marks_only_the_bricks_reading_what_it_changed() {
        let mut f = Field::new(0.001, 0.5);
        // Matter in brick 0 alone; a carve over the box of bricks −2 ..= 2 walks brick 0 only
        // (no other brick exists to carve), so only the bricks reading brick 0 are dirty.
        f.edit_box(IVec3::ZERO, IVec3::splat(7), true, |_, d, _| *d = 1.0);
        f.take_dirty();
        f.edit_box(IVec3::splat(-16), IVec3::splat(23), false, |_, d, _| *d *= 0.5);
        let dirty = f.take_dirty();
        let (first, last) = bricks_reading(IVec3::ZERO, IVec3::splat(7));
        assert_eq!((first, last), (IVec3::splat(-1), IVec3::ONE));
        assert_eq!(dirty.len(), 27);
        assert!(dirty.iter().all(|k| k.cmpge(first).all() && k.cmple(last).all()), "{dirty:?}");
        // Within a walked brick, only what changed: one sample in the brick's middle is read
        // by brick 0 alone, and an edit that leaves every value as it was marks nothing.
        f.edit_density(
            IVec3::splat(-16),
            IVec3::splat(23),
            |_, _| true,
            whole_rows,
            |p, d| {
                if p == IVec3::splat(4) {
                    *d = 0.75;
                }
            },
        );
        assert_eq!(f.take_dirty().into_iter().collect::<Vec<_>>(), [IVec3::ZERO]);
        f.edit_box(IVec3::splat(-16), IVec3::splat(23), true, |_, _, _| {});
        assert!(f.take_dirty().is_empty());
        // A new colour is a change (the mesh's vertex colours read it).
        f.edit_box(IVec3::splat(-16), IVec3::splat(23), false, |p, _, c| {
            if p == IVec3::splat(4) {
                *c = [1.0, 0.0, 0.0, 1.0];
            }
        });
        assert_eq!(f.take_dirty().into_iter().collect::<Vec<_>>(), [IVec3::ZERO]);
        // A region edit marks the bricks it walks, not the ones it rules out.
        f.edit_region(IVec3::splat(-16), IVec3::splat(23), true, |a, _| a.x >= 16, |_, d, _| *d = 1.0);
        let dirty = f.take_dirty();
        assert!(dirty.contains(&IVec3::new(2, 0, 0)) && dirty.contains(&IVec3::new(1, -2, 2)));
        assert!(dirty.iter().all(|k| k.x >= 1), "{dirty:?}");
    }

    #[test]
    fn the_surface_level_lies_between_two_stored_densities_next_to_the_iso_level() {
        for iso in [0.5, 0.3, 0.01, 0.99999] {
            let level = Field::new(0.001, iso).surface_level();
            assert!((level - iso).abs() <= 2.0 * crate::field::DENSITY_TOLERANCE, "{iso}: {level}");
            assert!((0..=DENSITY_ONE).all(|q| dequantize(q) != level), "{iso}: a stored value");
        }
        // A sample stored at the iso-level is outside.
        assert!(dequantize(quantize(0.5)) < Field::new(0.001, 0.5).surface_level());
    }

    #[test]
    fn brick_ranges_hold_the_whole_brick_and_each_lower_face() {
        let mut brick = Brick::default();
        for i in 0..BRICK_VOLUME {
            brick.set_density(i, ((i * 7919) % 1000) as f32 / 1000.0);
        }
        let mut want = [(f32::INFINITY, f32::NEG_INFINITY); 4];
        for (i, d) in brick.densities().enumerate() {
            let local = IVec3::new(i as i32 % 8, i as i32 / 8 % 8, i as i32 / 64);
            for (r, on) in want.iter_mut().zip([true, local.x == 0, local.y == 0, local.z == 0]) {
                if on {
                    *r = (r.0.min(d), r.1.max(d));
                }
            }
        }
        let got = brick_ranges(&brick);
        assert_eq!(got.all, want[0]);
        assert_eq!(got.low_faces, [want[1], want[2], want[3]]);
        // A ramp along x: its lower x face is one value, the others span the ramp.
        for i in 0..BRICK_VOLUME {
            brick.set_density(i, (i % 8) as f32 / 7.0);
        }
        let ramp = brick_ranges(&brick);
        assert_eq!((ramp.all, ramp.low_faces), ((0.0, 1.0), [(0.0, 0.0), (0.0, 1.0), (0.0, 1.0)]));
    }
}
