//! One brick: a dense `BRICK_SIZE`³ block of samples.
//!
//! ```text
//!  local index (x, y, z), each in 0..BRICK_SIZE        linear = x + S·(y + S·z)
//!
//!      z                       brick key K covers lattice points
//!     /                          K·S ..= K·S + (S − 1)   on each axis
//!    +------ x                 (keys are signed: the workspace is unbounded)
//!    |
//!    y
//! ```

use crate::math::IVec3;

/// Samples per brick edge. 8 keeps a brick at 1 KiB of densities (9 KiB with a colour per
/// sample), small enough that a stroke touches few samples it does not change, large enough
/// that the per-brick overhead (hash lookup, apron gather) stays a small part of meshing.
pub const BRICK_SIZE: i32 = 8;

/// `log2(BRICK_SIZE)`: a lattice point's brick is a shift of it.
const BRICK_SHIFT: i32 = BRICK_SIZE.trailing_zeros() as i32;
const _: () = assert!(1 << BRICK_SHIFT == BRICK_SIZE, "a brick's size is a power of two");

/// Samples in one brick.
pub const BRICK_VOLUME: usize = (BRICK_SIZE * BRICK_SIZE * BRICK_SIZE) as usize;

/// Key of a brick: lattice point `p` lies in brick `p.div_euclid(BRICK_SIZE)`.
pub type BrickKey = IVec3;

/// Resolution levels of a field: level `l` has voxels `2^l` times the finest's (1x to 16x).
pub const LEVELS: usize = 5;

/// The levels whose bricks' presence decides the lattice a brick's surface is meshed on: the
/// coarsest level, up to `log2 S` (cells as wide as the brick), under which no finer level
/// holds a brick. The dirty set follows the presence of bricks of these levels.
pub const MESHED_LEVELS: usize = BRICK_SIZE.trailing_zeros() as usize;
const _: () = assert!(1 << MESHED_LEVELS == BRICK_SIZE && MESHED_LEVELS < LEVELS);

/// A brick of one resolution level: level `l`'s lattice point `q` sits where the finest
/// level's point `q · 2^l` does, and its bricks are keyed on its own lattice like the finest's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LevelKey {
    /// The level (0: the finest).
    pub level: u8,
    /// The brick's key on that level's lattice.
    pub key: BrickKey,
}

impl LevelKey {
    /// Brick `key` of level `level`.
    pub fn new(level: usize, key: BrickKey) -> Self {
        debug_assert!(level < LEVELS);
        Self { level: level as u8, key }
    }

    /// The key's coordinates, level first, for sorting.
    pub fn sort_key(&self) -> (u8, [i32; 3]) {
        (self.level, self.key.to_array())
    }
}

impl From<BrickKey> for LevelKey {
    /// A brick of the finest level.
    fn from(key: BrickKey) -> Self {
        Self { level: 0, key }
    }
}

impl std::fmt::Display for LevelKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.level {
            0 => write!(f, "{}", self.key),
            l => write!(f, "{} of level {l}", self.key),
        }
    }
}

/// A linear RGBA colour.
pub type Colour = [f32; 4];

/// A stored density: `d · DENSITY_ONE`, rounded to the nearest integer.
///
/// Densities live in [0, 1], so a fixed-point fraction holds them in half the bytes of an
/// `f32`. The scale is a power of two so that decoding is exact (a multiplication by
/// 2⁻¹⁵), 0 and 1 are exact (empty and full samples, constant tiles), and so are the
/// dyadic fractions ½, ¼, … . A step of 2⁻¹⁵ ≈ 3·10⁻⁵ is far below what moves a surface
/// visibly (a tool's falloff changes a sample by about 0.25 per voxel it moves, so a step moves
/// the surface by about a ten-thousandth of a voxel).
pub type Quantum = u16;

/// The stored value of density 1.
pub const DENSITY_ONE: Quantum = 1 << 15;

/// The largest change of a density that storing it can make: half a step.
pub const DENSITY_TOLERANCE: f32 = 0.5 / DENSITY_ONE as f32;

/// Stores density `d`, clamped to [0, 1] (NaN stores as 0), rounded to the nearest step.
#[inline]
pub fn quantize(d: f32) -> Quantum {
    // In [0.5, DENSITY_ONE + 0.5] after the clamp, so truncating rounds to nearest, ties up.
    (d.clamp(0.0, 1.0) * f32::from(DENSITY_ONE) + 0.5) as Quantum
}

/// Whether storing density `new` where the stored density `old` (a value [`dequantize`]
/// gives) was changes the stored value: `quantize(new) != quantize(old)`, without rounding.
#[inline]
pub fn stores_differently(old: f32, new: f32) -> bool {
    let one = f32::from(DENSITY_ONE);
    // Both products are exact (a power-of-two scale) and so is their difference where it
    // matters (within a step of each other); `new` rounds to `old` within half a step below
    // and just under half a step above.
    let steps = new.clamp(0.0, 1.0) * one - old * one;
    !(-0.5..0.5).contains(&steps)
}

/// The density a stored value holds (exact).
#[inline]
pub fn dequantize(q: Quantum) -> f32 {
    f32::from(q) * (1.0 / DENSITY_ONE as f32)
}

/// The colour of samples nothing has painted: neutral clay grey.
pub const DEFAULT_COLOUR: Colour = [0.6, 0.6, 0.6, 1.0];

/// A dense block of densities, with colours stored once when the brick's matter has one colour.
///
/// Memory is what bounds a sculpt's size, so a brick stores what it must and no more:
///
/// - **Densities** are always per sample, as [`Quantum`]s (1 KiB a brick).
/// - **Colours** ([`BrickColours`]) are one colour for the whole brick while every sample that
///   holds matter has the same colour (unpainted clay: almost every brick), and per sample
///   (8 KiB more) only once paint or matter of another colour arrives. The colour of an empty
///   sample means nothing (the mesher weighs colours by density and new matter brings its own
///   colour, see [`Brick::compact`]), so it does not keep a brick from being uniform.
/// - **Uniform bricks** (every sample the same density and colour: the inside of solid clay)
///   are constant tiles: the field shares one brick per distinct value among every key that
///   holds it (see `Field`), so a solid interior costs a map entry per brick, not its samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Brick {
    /// Stored density per sample ([`quantize`]), linear index `x + S·(y + S·z)`; read and
    /// write them through [`Brick::density`] and [`Brick::set_density`].
    pub density: Box<[Quantum; BRICK_VOLUME]>,
    /// Colour per sample, same indexing.
    pub colour: BrickColours,
}

/// A brick's colours: one for all samples, or one per sample.
///
/// Indexing reads a sample's colour either way; writing through `IndexMut` stores one colour
/// per sample from then on. The field's edits avoid that when the colour does not change (see
/// [`BrickColours::set`]) and [`Brick::compact`] folds per-sample colours back to one.
/// Equality compares the samples' colours, whichever way they are stored.
#[derive(Clone, Debug)]
pub enum BrickColours {
    /// Every sample has this colour.
    Uniform(Colour),
    /// One colour per sample.
    PerSample(Box<[Colour; BRICK_VOLUME]>),
}

impl PartialEq for BrickColours {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (BrickColours::Uniform(a), BrickColours::Uniform(b)) => a == b,
            _ => self.iter().eq(other.iter()),
        }
    }
}

impl BrickColours {
    /// The colours of `BRICK_VOLUME` samples in linear order, stored once if they are all the
    /// same (exactly: empty samples are not treated apart, unlike [`Brick::compact`]).
    pub fn from_samples(mut colour: impl FnMut(usize) -> Colour) -> Self {
        let first = colour(0);
        let mut colours = BrickColours::Uniform(first);
        for i in 1..BRICK_VOLUME {
            colours.set(i, colour(i));
        }
        colours
    }

    /// Sets sample `i`'s colour, storing per-sample colours only if it differs.
    #[inline]
    pub fn set(&mut self, i: usize, colour: Colour) {
        match self {
            BrickColours::Uniform(c) if *c == colour => {}
            _ => self[i] = colour,
        }
    }

    /// The colours of every sample, in linear order.
    pub fn iter(&self) -> impl Iterator<Item = &Colour> + '_ {
        let (uniform, per_sample) = match self {
            BrickColours::Uniform(c) => (Some(std::iter::repeat_n(c, BRICK_VOLUME)), None),
            BrickColours::PerSample(v) => (None, Some(v.iter())),
        };
        uniform.into_iter().flatten().chain(per_sample.into_iter().flatten())
    }

    /// Whether one colour serves every sample.
    pub fn is_uniform(&self) -> bool {
        matches!(self, BrickColours::Uniform(_))
    }
}

impl std::ops::Index<usize> for BrickColours {
    type Output = Colour;

    #[inline]
    fn index(&self, i: usize) -> &Colour {
        match self {
            BrickColours::Uniform(c) => c,
            BrickColours::PerSample(v) => &v[i],
        }
    }
}

impl std::ops::IndexMut<usize> for BrickColours {
    /// The sample's own colour, storing one colour per sample from now on.
    #[inline]
    fn index_mut(&mut self, i: usize) -> &mut Colour {
        if let BrickColours::Uniform(c) = *self {
            *self = BrickColours::PerSample(Box::new([c; BRICK_VOLUME]));
        }
        match self {
            BrickColours::PerSample(v) => &mut v[i],
            BrickColours::Uniform(_) => unreachable!("made per-sample above"),
        }
    }
}

impl Default for Brick {
    fn default() -> Self {
        Self { density: Box::new([0; BRICK_VOLUME]), colour: BrickColours::Uniform(DEFAULT_COLOUR) }
    }
}

impl Brick {
    /// Linear index of a local coordinate (each component in `0..BRICK_SIZE`).
    #[inline]
    pub fn linear(local: IVec3) -> usize {
        debug_assert!(local.cmpge(IVec3::ZERO).all() && local.cmplt(IVec3::splat(BRICK_SIZE)).all());
        (local.x + BRICK_SIZE * (local.y + BRICK_SIZE * local.z)) as usize
    }

    /// Sample `i`'s density.
    #[inline]
    pub fn density(&self, i: usize) -> f32 {
        dequantize(self.density[i])
    }

    /// Stores `d` as sample `i`'s density (see [`quantize`]).
    #[inline]
    pub fn set_density(&mut self, i: usize, d: f32) {
        self.density[i] = quantize(d);
    }

    /// Every sample's density, in linear order.
    pub fn densities(&self) -> impl Iterator<Item = f32> + '_ {
        self.density.iter().map(|&q| dequantize(q))
    }

    /// The lowest and highest density of the samples of local points `lo ..= hi`, clamped to
    /// the brick (the whole brick's range is kept by the field).
    pub fn density_range_in(&self, lo: IVec3, hi: IVec3) -> (f32, f32) {
        let (lo, hi) = (lo.max(IVec3::ZERO), hi.min(IVec3::splat(BRICK_SIZE - 1)));
        let mut range = (Quantum::MAX, Quantum::MIN);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                let row = Self::linear(IVec3::new(lo.x, y, z))..=Self::linear(IVec3::new(hi.x, y, z));
                for &d in &self.density[row] {
                    range = (range.0.min(d), range.1.max(d));
                }
            }
        }
        if range.0 <= range.1 {
            (dequantize(range.0), dequantize(range.1))
        } else {
            (f32::INFINITY, f32::NEG_INFINITY)
        }
    }

    /// Whether every sample is empty (density 0): such a brick need not be stored.
    pub fn is_empty(&self) -> bool {
        self.density.iter().all(|&d| d == 0)
    }

    /// Total matter in the brick, in sample units.
    pub fn mass(&self) -> f64 {
        let sum: u64 = self.density.iter().map(|&d| u64::from(d)).sum();
        sum as f64 / f64::from(DENSITY_ONE)
    }

    /// Folds per-sample colours back to one when every sample holding matter has the same
    /// colour (empty samples take it too: their colour means nothing). Idempotent; a brick
    /// with no matter keeps its colours.
    pub fn compact(&mut self) {
        let BrickColours::PerSample(colours) = &self.colour else { return };
        let mut held = self.density.iter().zip(colours.iter()).filter(|(&d, _)| d > 0).map(|(_, c)| c);
        let Some(&first) = held.next() else { return };
        if held.all(|c| *c == first) {
            self.colour = BrickColours::Uniform(first);
        }
    }

    /// The value every sample holds, if they all hold the same density and colour: a constant
    /// tile.
    pub fn uniform_value(&self) -> Option<(f32, Colour)> {
        let BrickColours::Uniform(colour) = self.colour else { return None };
        let first = self.density[0];
        self.density.iter().all(|&d| d == first).then_some((dequantize(first), colour))
    }

    /// Heap bytes the brick's samples take.
    pub fn heap_bytes(&self) -> usize {
        std::mem::size_of::<[Quantum; BRICK_VOLUME]>()
            + match self.colour {
                BrickColours::Uniform(_) => 0,
                BrickColours::PerSample(_) => std::mem::size_of::<[Colour; BRICK_VOLUME]>(),
            }
    }
}

/// Number of lattice points of the box `lo ..= hi` (none where it is empty).
pub fn lattice_points(lo: IVec3, hi: IVec3) -> usize {
    let d = (hi - lo + IVec3::ONE).max(IVec3::ZERO);
    d.x as usize * d.y as usize * d.z as usize
}

/// The keys of the bricks holding a point of `lo ..= hi`, x fastest.
pub fn keys_over(lo: IVec3, hi: IVec3) -> impl Iterator<Item = BrickKey> {
    let s = IVec3::splat(BRICK_SIZE);
    let (a, b) = (lo.div_euclid(s), hi.div_euclid(s));
    (a.z..=b.z)
        .flat_map(move |z| (a.y..=b.y).flat_map(move |y| (a.x..=b.x).map(move |x| IVec3::new(x, y, z))))
}

/// The brick holding lattice point `p`, and `p`'s local coordinate in it.
#[inline]
pub fn split_index(p: IVec3) -> (BrickKey, IVec3) {
    let s = IVec3::splat(BRICK_SIZE);
    (p.div_euclid(s), p.rem_euclid(s))
}

/// The brick holding lattice point `p` (`split_index(p).0` as a shift, for loops that ask it
/// of every sample).
#[inline(always)]
pub fn brick_key(p: IVec3) -> BrickKey {
    p >> BRICK_SHIFT
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_index_handles_negative_points() {
        assert_eq!(split_index(IVec3::new(-1, 0, 8)), (IVec3::new(-1, 0, 1), IVec3::new(7, 0, 0)));
        assert_eq!(split_index(IVec3::new(-8, -9, 7)), (IVec3::new(-1, -2, 0), IVec3::new(0, 7, 7)));
        for p in [IVec3::new(-1, 0, 8), IVec3::new(-8, -9, 7), IVec3::new(-17, 16, 15)] {
            assert_eq!(brick_key(p), split_index(p).0);
        }
    }

    #[test]
    fn linear_index_is_x_fastest() {
        assert_eq!(Brick::linear(IVec3::new(1, 0, 0)), 1);
        assert_eq!(Brick::linear(IVec3::new(0, 1, 0)), 8);
        assert_eq!(Brick::linear(IVec3::new(0, 0, 1)), 64);
        assert_eq!(Brick::linear(IVec3::splat(7)), BRICK_VOLUME - 1);
    }

    #[test]
    fn colours_stay_one_until_a_sample_differs() {
        let mut b = Brick::default();
        b.colour.set(3, DEFAULT_COLOUR);
        assert!(b.colour.is_uniform());
        b.colour.set(3, [1.0, 0.0, 0.0, 1.0]);
        assert!(!b.colour.is_uniform());
        assert_eq!(b.colour[3], [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(b.colour[4], DEFAULT_COLOUR);
        assert_eq!(b.colour.iter().count(), BRICK_VOLUME);
        assert_eq!(b.heap_bytes(), BRICK_VOLUME * 18);
        // Stored either way, the same colours are equal.
        let expanded = BrickColours::PerSample(Box::new([DEFAULT_COLOUR; BRICK_VOLUME]));
        assert_eq!(expanded, BrickColours::Uniform(DEFAULT_COLOUR));
        assert_ne!(b.colour, BrickColours::Uniform(DEFAULT_COLOUR));
        assert_eq!(BrickColours::from_samples(|i| b.colour[i]), b.colour);
        assert!(BrickColours::from_samples(|_| [0.5; 4]).is_uniform());
    }

    #[test]
    fn compaction_ignores_the_colour_of_empty_samples() {
        let red = [1.0, 0.0, 0.0, 1.0];
        let mut b = Brick::default();
        b.set_density(3, 0.5);
        b.colour[3] = red;
        b.compact();
        assert_eq!(b.colour, BrickColours::Uniform(red));
        assert_eq!(b.heap_bytes(), BRICK_VOLUME * 2);
        // Two colours of matter stay per sample.
        b.set_density(4, 1.0);
        b.colour[4] = DEFAULT_COLOUR;
        b.compact();
        assert!(!b.colour.is_uniform());
        assert_eq!((b.colour[3], b.colour[4]), (red, DEFAULT_COLOUR));
    }

    #[test]
    fn a_brick_of_one_value_is_a_tile() {
        let mut b = Brick::default();
        assert_eq!(b.uniform_value(), Some((0.0, DEFAULT_COLOUR)));
        b.density.fill(DENSITY_ONE);
        assert_eq!(b.uniform_value(), Some((1.0, DEFAULT_COLOUR)));
        b.set_density(9, 0.99);
        assert_eq!(b.uniform_value(), None);
    }

    #[test]
    fn stored_densities_round_to_the_nearest_step() {
        // Every stored value reads back and stores again as itself.
        for q in 0..=DENSITY_ONE {
            assert_eq!(quantize(dequantize(q)), q);
        }
        // Empty, full and the dyadic fractions are exact.
        for d in [0.0, 1.0, 0.5, 0.25, 0.75, 0.125] {
            assert_eq!(dequantize(quantize(d)), d);
        }
        // Anything else moves by half a step at most, and out-of-range values clamp.
        for i in 0..=10_000 {
            let d = i as f32 / 10_000.0;
            assert!((dequantize(quantize(d)) - d).abs() <= DENSITY_TOLERANCE, "{d}");
        }
        assert_eq!(quantize(-0.3), 0);
        assert_eq!(quantize(1.7), DENSITY_ONE);
        assert_eq!(quantize(f32::NAN), 0);
        // Whether a new density stores differently, as quantizing both says.
        for q in [0, 1, 7, 16_384, DENSITY_ONE - 1, DENSITY_ONE] {
            let old = dequantize(q);
            for k in -40..=40 {
                let new = old + k as f32 * 0.25 * DENSITY_TOLERANCE;
                assert_eq!(stores_differently(old, new), quantize(new) != q, "{old} → {new}");
            }
        }
        // Storing keeps the order of densities (a removing edit never adds).
        let mut last = 0;
        for i in 0..=100_000 {
            let q = quantize(i as f32 / 100_000.0);
            assert!(q >= last);
            last = q;
        }
    }
}
