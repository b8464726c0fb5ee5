//! A dense copy of a box of the clay: one density and one colour per lattice point of the
//! finest level, read through every level, for operations that resample the clay through a
//! mapping and must read it as it was while they write: one box ([`DenseCopy`]), or the tiles
//! an operation has touched so far ([`TiledCopy`]).

use std::collections::HashMap;

use super::{Colour, Field, FieldReader, DEFAULT_COLOUR};
use crate::math::{div_floor, floor_i32, round_i32, IVec3, Vec3};

/// Densities and colours over the lattice points `lo ..= lo + dims − 1`, `x` fastest; points
/// outside read as empty.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DenseCopy {
    lo: IVec3,
    dims: IVec3,
    density: Vec<f32>,
    colour: Vec<Colour>,
    /// What each cell of [`CELL`]³ points holds, `x` fastest, for [`DenseCopy::span`].
    cells: Vec<Span>,
    /// Where asked for ([`DenseCopy::counted`]), a summed-volume table over `dims + 1`
    /// corners, `x` fastest: at corner `c`, how many points below it on every axis hold clay,
    /// and how many are not full, so that [`DenseCopy::holds`] knows from 8 entries whether a
    /// box is empty or full. Empty otherwise.
    counts: Vec<[u32; 2]>,
}

/// What every point of a box holds, where they all hold the same ([`DenseCopy::holds`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Holds {
    /// No clay.
    Empty,
    /// Full clay of one colour.
    Full(Colour),
    /// Anything else.
    Mixed,
}

/// Lattice points along each side of a [`DenseCopy`]'s summary cells.
const CELL: i32 = 4;

/// What some lattice points hold: their lowest and highest density, and their colour where
/// every one of them is full and of that one colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    /// The lowest density.
    pub min: f32,
    /// The highest density.
    pub max: f32,
    /// The colour of them all, where each is full and of one colour.
    pub full: Option<Colour>,
}

impl Span {
    /// Empty points.
    pub const EMPTY: Span = Span { min: 0.0, max: 0.0, full: None };

    fn of(density: f32, colour: Colour) -> Span {
        Span { min: density, max: density, full: (density == 1.0).then_some(colour) }
    }

    /// What the points of both hold.
    pub fn with(self, other: Span) -> Span {
        Span {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
            full: match (self.full, other.full) {
                (Some(a), Some(b)) if a == b => Some(a),
                _ => None,
            },
        }
    }
}

impl DenseCopy {
    /// A copy of `field` over `lo ..= hi` (empty when `hi < lo` on an axis).
    pub fn read(field: &Field, lo: IVec3, hi: IVec3) -> Self {
        Self::default().grown(field, lo, hi)
    }

    /// The copy over `lo ..= hi`: what this one holds is kept, the rest read from `field`.
    pub fn grown(&self, field: &Field, lo: IVec3, hi: IVec3) -> Self {
        let dims = (hi - lo + IVec3::ONE).max(IVec3::ZERO);
        let n = dims.x as usize * dims.y as usize * dims.z as usize;
        let (mut density, mut colour) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let mut reader = FieldReader::new(field);
        for z in lo.z..lo.z + dims.z {
            for y in lo.y..lo.y + dims.y {
                for x in lo.x..lo.x + dims.x {
                    let p = IVec3::new(x, y, z);
                    if let Some(i) = self.index(p) {
                        density.push(self.density[i]);
                        colour.push(self.colour[i]);
                        continue;
                    }
                    let d = reader.density(p);
                    let d = if d.is_finite() { d.clamp(0.0, 1.0) } else { 0.0 };
                    density.push(d);
                    colour.push(if d > 0.0 { reader.colour(p) } else { DEFAULT_COLOUR });
                }
            }
        }
        let cells = summarise(dims, &density, &colour);
        Self { lo, dims, density, colour, cells, counts: Vec::new() }
    }

    /// This copy with the summed-volume table that makes [`Self::holds`] exact (a copy asked
    /// about many boxes: 8 bytes more per point).
    pub fn counted(mut self) -> Self {
        self.counts = summed_counts(self.dims, &self.density);
        self
    }

    /// Whether every point of `lo ..= hi` is empty (points outside the copy are), or every
    /// one full and of one colour: exactly where the copy is [`Self::counted`], else from
    /// the summary cells. The colour is read from the cells, which may hold a few points
    /// around the box: a box of full points of one colour next to clay of another may be
    /// called mixed, never the other way.
    pub fn holds(&self, lo: IVec3, hi: IVec3) -> Holds {
        let (a, b) = (lo.max(self.lo), hi.min(self.hi()));
        if a.cmpgt(b).any() {
            return Holds::Empty;
        }
        if self.counts.is_empty() {
            return match self.span(lo, hi) {
                Span { max: 0.0, .. } => Holds::Empty,
                Span { min: 1.0, full: Some(colour), .. } => Holds::Full(colour),
                _ => Holds::Mixed,
            };
        }
        let [occupied, unfull] = self.count(a - self.lo, b - self.lo + IVec3::ONE);
        if occupied == 0 {
            return Holds::Empty;
        }
        if unfull > 0 || !(a == lo && b == hi) {
            return Holds::Mixed;
        }
        match self.span(lo, hi).full {
            Some(colour) => Holds::Full(colour),
            None => Holds::Mixed,
        }
    }

    /// The counts of [`Self::counts`] over the points from corner `a` up to (not including) corner `b`.
    #[inline]
    fn count(&self, a: IVec3, b: IVec3) -> [u32; 2] {
        let (sy, sz) = ((self.dims.x + 1) as usize, ((self.dims.x + 1) * (self.dims.y + 1)) as usize);
        let at = |x: i32, y: i32, z: i32| self.counts[x as usize + sy * y as usize + sz * z as usize];
        let mut out = [0u32; 2];
        for corner in 0..8 {
            let (x, y, z) = (
                if corner & 1 == 1 { b.x } else { a.x },
                if corner & 2 == 2 { b.y } else { a.y },
                if corner & 4 == 4 { b.z } else { a.z },
            );
            // Inclusion and exclusion: a corner counts positively where it takes an odd number
            // of its coordinates from `b` (`b` itself does, `a` does not).
            let c = at(x, y, z);
            let add = (corner as u32).count_ones() % 2 == 1;
            for k in 0..2 {
                // The sum is exact in `u32` whatever the order (wrapping arithmetic).
                out[k] = if add { out[k].wrapping_add(c[k]) } else { out[k].wrapping_sub(c[k]) };
            }
        }
        out
    }

    /// What the points of `lo ..= hi` hold, points outside the copy empty; the cells it reads
    /// may hold a few points around the box too (the span is then wider, never narrower).
    pub fn span(&self, lo: IVec3, hi: IVec3) -> Span {
        let (a, b) = (lo.max(self.lo), hi.min(self.hi()));
        if a.cmpgt(b).any() {
            return Span::EMPTY;
        }
        let outside = !(a == lo && b == hi);
        let (ca, cb) = ((a - self.lo) / CELL, (b - self.lo) / CELL);
        let cd = cell_dims(self.dims);
        let mut span = if outside { Some(Span::EMPTY) } else { None };
        for z in ca.z..=cb.z {
            for y in ca.y..=cb.y {
                for x in ca.x..=cb.x {
                    let cell = self.cells[(x + cd.x * (y + cd.y * z)) as usize];
                    span = Some(span.map_or(cell, |s| s.with(cell)));
                }
            }
        }
        span.unwrap_or(Span::EMPTY)
    }

    /// The lowest lattice point held.
    pub fn lo(&self) -> IVec3 {
        self.lo
    }

    /// The highest lattice point held (below `lo` on some axis when empty).
    pub fn hi(&self) -> IVec3 {
        self.lo + self.dims - IVec3::ONE
    }

    /// The lattice points it holds.
    pub fn len(&self) -> usize {
        self.density.len()
    }

    /// Whether it holds no point.
    pub fn is_empty(&self) -> bool {
        self.density.is_empty()
    }

    /// Whether it holds every point of `lo ..= hi`.
    pub fn contains(&self, lo: IVec3, hi: IVec3) -> bool {
        lo.cmpge(self.lo).all() && hi.cmple(self.hi()).all()
    }

    #[inline]
    fn index(&self, p: IVec3) -> Option<usize> {
        let c = p - self.lo;
        (c.cmpge(IVec3::ZERO).all() && c.cmplt(self.dims).all())
            .then(|| (c.x + self.dims.x * (c.y + self.dims.y * c.z)) as usize)
    }

    /// The density at a lattice point (0 outside).
    #[inline]
    pub fn density(&self, p: IVec3) -> f32 {
        self.index(p).map_or(0.0, |i| self.density[i])
    }

    /// The colour at a lattice point ([`DEFAULT_COLOUR`] outside).
    #[inline]
    pub fn colour(&self, p: IVec3) -> Colour {
        self.index(p).map_or(DEFAULT_COLOUR, |i| self.colour[i])
    }

    /// The density, where every point of `lo ..= hi` is held and has the same one.
    pub fn constant_density(&self, lo: IVec3, hi: IVec3) -> Option<f32> {
        if !self.contains(lo, hi) {
            return None;
        }
        let span = self.span(lo, hi);
        (span.min == span.max).then_some(span.min)
    }

    /// The trilinear density at a fractional lattice coordinate held in double precision
    /// (for mappings whose parameters need it).
    #[inline]
    pub fn density_f64(&self, p: [f64; 3]) -> f32 {
        let b = IVec3::new(floor_i32(p[0]), floor_i32(p[1]), floor_i32(p[2]));
        let f = [p[0] - b.x as f64, p[1] - b.y as f64, p[2] - b.z as f64];
        let c = b - self.lo;
        if c.cmpge(IVec3::ZERO).all() && (c + IVec3::ONE).cmplt(self.dims).all() {
            // The 2 × 2 × 2 block lies in the copy: direct indices.
            let (sy, sz) = (self.dims.x as usize, (self.dims.x * self.dims.y) as usize);
            let i = c.x as usize + sy * c.y as usize + sz * c.z as usize;
            let d = &self.density;
            let lerp = |a: f32, b: f32, t: f64| a as f64 + (b as f64 - a as f64) * t;
            let x00 = lerp(d[i], d[i + 1], f[0]);
            let x10 = lerp(d[i + sy], d[i + sy + 1], f[0]);
            let x01 = lerp(d[i + sz], d[i + sz + 1], f[0]);
            let x11 = lerp(d[i + sy + sz], d[i + sy + sz + 1], f[0]);
            let y0 = x00 + (x10 - x00) * f[1];
            let y1 = x01 + (x11 - x01) * f[1];
            return (y0 + (y1 - y0) * f[2]) as f32;
        }
        let mut acc = 0.0f64;
        for n in 0..8 {
            let o = IVec3::new(n & 1, (n >> 1) & 1, (n >> 2) & 1);
            let w = (if o.x == 1 { f[0] } else { 1.0 - f[0] })
                * (if o.y == 1 { f[1] } else { 1.0 - f[1] })
                * (if o.z == 1 { f[2] } else { 1.0 - f[2] });
            if w != 0.0 {
                acc += w * self.density(b + o) as f64;
            }
        }
        acc as f32
    }

    /// The colour of the nearest lattice point holding matter around `p`, else the default.
    pub fn colour_near(&self, p: [f64; 3]) -> Colour {
        let near = IVec3::new(round_i32(p[0]), round_i32(p[1]), round_i32(p[2]));
        if let Some(i) = self.index(near).filter(|&i| self.density[i] > 0.0) {
            return self.colour[i];
        }
        let base = IVec3::new(floor_i32(p[0]), floor_i32(p[1]), floor_i32(p[2]));
        (0..8)
            .map(|c| base + IVec3::new(c & 1, (c >> 1) & 1, (c >> 2) & 1))
            .filter_map(|q| self.index(q))
            .filter(|&i| self.density[i] > 0.0)
            .max_by(|&a, &b| self.density[a].total_cmp(&self.density[b]))
            .map_or(DEFAULT_COLOUR, |i| self.colour[i])
    }

    /// The heap bytes its densities and colours take.
    pub fn bytes(&self) -> usize {
        self.density.len() * (std::mem::size_of::<f32>() + std::mem::size_of::<Colour>())
            + self.cells.len() * std::mem::size_of::<Span>()
            + self.counts.len() * std::mem::size_of::<[u32; 2]>()
    }

    /// Trilinear density and density-weighted colour at a fractional lattice coordinate.
    #[inline]
    pub fn sample(&self, index: Vec3) -> (f32, Colour) {
        let base = index.floor();
        let f = index - base;
        let b = base.as_ivec3();
        // All eight corners held (the usual case): their indices by strides from the first.
        let first = b - self.lo;
        let inside = first.cmpge(IVec3::ZERO).all() && (first + IVec3::ONE).cmplt(self.dims).all();
        let (sy, sz) = (self.dims.x, self.dims.x * self.dims.y);
        let (mut d, mut c) = (0.0f32, [0.0f32; 4]);
        for corner in 0..8 {
            let o = IVec3::new(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = (if o.x == 1 { f.x } else { 1.0 - f.x })
                * (if o.y == 1 { f.y } else { 1.0 - f.y })
                * (if o.z == 1 { f.z } else { 1.0 - f.z });
            let i = if inside {
                let c = first + o;
                (c.x + sy * c.y + sz * c.z) as usize
            } else {
                let Some(i) = self.index(b + o) else { continue };
                i
            };
            let wd = w * self.density[i];
            d += wd;
            for (a, v) in c.iter_mut().zip(self.colour[i]) {
                *a += wd * v;
            }
        }
        if d > 0.0 {
            (d, c.map(|a| a / d))
        } else {
            (0.0, DEFAULT_COLOUR)
        }
    }
}

/// The summed-volume table of [`DenseCopy::counts`] for densities over `dims` points.
fn summed_counts(dims: IVec3, density: &[f32]) -> Vec<[u32; 2]> {
    let (nx, ny, nz) = ((dims.x + 1) as usize, (dims.y + 1) as usize, (dims.z + 1) as usize);
    let mut counts = vec![[0u32; 2]; nx * ny * nz];
    let (sy, sz) = (nx, nx * ny);
    let mut i = 0;
    for z in 1..nz {
        for y in 1..ny {
            let mut row = [0u32; 2];
            for x in 1..nx {
                let d = density[i];
                i += 1;
                row[0] += u32::from(d > 0.0);
                row[1] += u32::from(d < 1.0);
                let c = x + sy * y + sz * z;
                // This row so far, plus the box below it in y, plus the slab below in z, less
                // their overlap.
                let (below, under, both) = (counts[c - sy], counts[c - sz], counts[c - sy - sz]);
                counts[c] = std::array::from_fn(|k| row[k] + below[k] + under[k] - both[k]);
            }
        }
    }
    counts
}

fn cell_dims(dims: IVec3) -> IVec3 {
    (dims + IVec3::splat(CELL - 1)) / CELL
}

/// The [`Span`] of each cell of a copy of `dims` points.
fn summarise(dims: IVec3, density: &[f32], colour: &[Colour]) -> Vec<Span> {
    let cd = cell_dims(dims);
    let mut cells: Vec<Option<Span>> = vec![None; (cd.x * cd.y * cd.z).max(0) as usize];
    let mut i = 0;
    for z in 0..dims.z {
        for y in 0..dims.y {
            let row = ((y / CELL) + cd.y * (z / CELL)) * cd.x;
            for x in 0..dims.x {
                let cell = &mut cells[(row + x / CELL) as usize];
                let s = Span::of(density[i], colour[i]);
                *cell = Some(cell.map_or(s, |c| c.with(s)));
                i += 1;
            }
        }
    }
    cells.into_iter().map(|c| c.unwrap_or(Span::EMPTY)).collect()
}

/// Lattice points along each side of a [`TiledCopy`]'s tiles.
const TILE: i32 = 16;
/// Lattice points in a tile.
const TILE_VOLUME: usize = (TILE * TILE * TILE) as usize;

/// The clay as it was where an operation has needed it so far: tiles of 16³ lattice points of
/// the finest level, each read through every level the first time a box asks for it
/// ([`TiledCopy::take`]). Unlike a [`DenseCopy`] of one box, it grows with what is touched,
/// so an operation whose reach wanders (a region carried across the stage) holds only the
/// places it passed, never the box around them.
#[derive(Clone, Debug, Default)]
pub struct TiledCopy {
    /// Tile key (the lowest lattice point over [`TILE`]) to its index in `tiles`.
    index: HashMap<IVec3, usize>,
    tiles: Vec<DenseCopy>,
}

impl TiledCopy {
    /// An empty copy.
    pub fn new() -> Self {
        Self::default()
    }

    /// Reads from `field` every tile over `lo ..= hi` not held yet; returns how many it read.
    /// `field` must still hold the clay as it was wherever the copy holds nothing.
    pub fn take(&mut self, field: &Field, lo: IVec3, hi: IVec3) -> usize {
        let missing: Vec<IVec3> = tiles_over(lo, hi).filter(|k| !self.index.contains_key(k)).collect();
        for &key in &missing {
            let lo = key * TILE;
            self.index.insert(key, self.tiles.len());
            self.tiles.push(DenseCopy::read(field, lo, lo + IVec3::splat(TILE - 1)));
        }
        missing.len()
    }

    /// The tiles `take` would read for the boxes `(lo, hi)` that are not held yet, each once.
    pub fn missing(&self, boxes: &[(IVec3, IVec3)]) -> usize {
        let keys: std::collections::HashSet<IVec3> = boxes
            .iter()
            .flat_map(|&(lo, hi)| tiles_over(lo, hi))
            .filter(|k| !self.index.contains_key(k))
            .collect();
        keys.len()
    }

    /// The lattice points held.
    pub fn points(&self) -> usize {
        self.tiles.len() * TILE_VOLUME
    }

    /// The lattice points of one tile.
    pub const TILE_POINTS: usize = TILE_VOLUME;

    /// What the points of `lo ..= hi` held ([`DenseCopy::span`]), points it does not hold empty.
    pub fn span(&self, lo: IVec3, hi: IVec3) -> Span {
        tiles_over(lo, hi)
            .map(|key| {
                let (a, b) = (lo.max(key * TILE), hi.min(key * TILE + IVec3::splat(TILE - 1)));
                self.index.get(&key).map_or(Span::EMPTY, |&i| self.tiles[i].span(a, b))
            })
            .reduce(Span::with)
            .unwrap_or(Span::EMPTY)
    }

    /// A reader of the copy that remembers the last tile it read, so that runs of points in one
    /// tile cost one look-up.
    pub fn reader(&self) -> TiledReader<'_> {
        TiledReader { copy: self, last: None }
    }
}

/// Reads a [`TiledCopy`] point by point (see [`TiledCopy::reader`]).
#[derive(Debug)]
pub struct TiledReader<'c> {
    copy: &'c TiledCopy,
    last: Option<(IVec3, usize)>,
}

impl TiledReader<'_> {
    /// The density and colour at a lattice point: empty where the copy holds nothing.
    #[inline]
    pub fn get(&mut self, p: IVec3) -> (f32, Colour) {
        let key = tile_of(p);
        let tile = match self.last {
            Some((k, i)) if k == key => Some(i),
            _ => {
                let found = self.copy.index.get(&key).copied();
                if let Some(i) = found {
                    self.last = Some((key, i));
                }
                found
            }
        };
        tile.map_or((0.0, DEFAULT_COLOUR), |i| {
            let t = &self.copy.tiles[i];
            (t.density(p), t.colour(p))
        })
    }
}

/// The keys of the tiles over `lo ..= hi` (none when the box is empty).
fn tiles_over(lo: IVec3, hi: IVec3) -> impl Iterator<Item = IVec3> {
    let (a, b) = (tile_of(lo), tile_of(hi));
    let empty = hi.cmplt(lo).any();
    (a.z..=b.z)
        .flat_map(move |z| (a.y..=b.y).flat_map(move |y| (a.x..=b.x).map(move |x| IVec3::new(x, y, z))))
        .filter(move |_| !empty)
}

#[inline]
fn tile_of(p: IVec3) -> IVec3 {
    IVec3::new(div_floor(p.x, TILE), div_floor(p.y, TILE), div_floor(p.z, TILE))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_copy_reads_the_clay_and_interpolates_it() {
        let mut f = Field::new(0.001, 0.5);
        f.edit_box(IVec3::ZERO, IVec3::new(3, 3, 3), true, |p, d, c| {
            *d = p.x as f32 / 4.0;
            *c = [1.0, 0.0, 0.0, 1.0];
        });
        let copy = DenseCopy::read(&f, IVec3::splat(-1), IVec3::splat(4));
        assert_eq!(copy.density(IVec3::new(2, 1, 1)), f.density(IVec3::new(2, 1, 1)));
        let (d, c) = copy.sample(Vec3::new(2.5, 1.0, 1.0));
        assert!((d - 0.625).abs() < 1e-3, "{d}");
        assert_eq!(c, [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(copy.density(IVec3::splat(9)), 0.0);
        // Grown, it keeps what it held even where the field changed since.
        f.edit_box(IVec3::ZERO, IVec3::ZERO, true, |_, d, _| *d = 1.0);
        let grown = copy.grown(&f, IVec3::splat(-2), IVec3::splat(5));
        assert_eq!(grown.density(IVec3::ZERO), 0.0);
        assert!(
            grown.contains(IVec3::splat(-2), IVec3::splat(5))
                && !copy.contains(IVec3::splat(-2), IVec3::ZERO)
        );
    }

    #[test]
    fn a_tiled_copy_holds_what_was_taken_and_keeps_it() {
        let mut f = Field::new(0.001, 0.5);
        f.edit_box(IVec3::splat(-20), IVec3::splat(20), true, |p, d, _| *d = (p.x + 20) as f32 / 40.0);
        let mut copy = TiledCopy::new();
        assert_eq!(
            copy.missing(&[(IVec3::splat(-1), IVec3::splat(1)), (IVec3::ZERO, IVec3::ONE)]),
            8,
            "shared tiles once"
        );
        assert_eq!(copy.take(&f, IVec3::splat(-1), IVec3::splat(1)), 8);
        assert_eq!(copy.take(&f, IVec3::ZERO, IVec3::splat(15)), 0, "held already");
        let points = [IVec3::new(-16, 3, 0), IVec3::new(15, -16, 15), IVec3::new(7, 0, 0)];
        let was = points.map(|p| f.density(p));
        assert!(was[1] > 0.5);
        f.edit_box(IVec3::splat(-20), IVec3::splat(20), true, |_, d, _| *d = 0.0);
        let mut r = copy.reader();
        for (p, d) in points.into_iter().zip(was) {
            assert_eq!(r.get(p).0, d, "at {p}");
        }
        assert_eq!(r.get(IVec3::splat(40)).0, 0.0, "nothing held there");
        assert_eq!(copy.points(), 8 * TiledCopy::TILE_POINTS);
    }

    #[test]
    fn holds_says_exactly_where_a_box_is_empty_or_full() {
        // A full red block, a blue one beside it, a ramp of partial densities and empty clay.
        let mut f = Field::new(0.001, 0.5);
        let (red, blue) = ([0.9, 0.1, 0.1, 1.0], [0.1, 0.2, 0.9, 1.0]);
        f.edit_box(IVec3::ZERO, IVec3::new(12, 9, 9), true, |p, d, c| {
            *d = if p.x < 10 { 1.0 } else { 0.3 };
            *c = if p.y < 6 { red } else { blue };
        });
        let plain = DenseCopy::read(&f, IVec3::splat(-2), IVec3::new(17, 12, 12));
        let copy = plain.clone().counted();
        let brute = |lo: IVec3, hi: IVec3| {
            let mut points = (lo.z..=hi.z).flat_map(|z| {
                (lo.y..=hi.y).flat_map(move |y| (lo.x..=hi.x).map(move |x| IVec3::new(x, y, z)))
            });
            let first = IVec3::new(lo.x, lo.y, lo.z);
            if points.clone().all(|p| copy.density(p) == 0.0) {
                Holds::Empty
            } else if copy.contains(lo, hi)
                && points.all(|p| copy.density(p) == 1.0 && copy.colour(p) == copy.colour(first))
            {
                Holds::Full(copy.colour(first))
            } else {
                Holds::Mixed
            }
        };
        let mut seed = 7u64;
        let mut next = |n: i32| {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 33) % n as u64) as i32
        };
        let (mut empty, mut full) = (0, 0);
        for _ in 0..3000 {
            let lo = IVec3::new(next(22) - 4, next(18) - 4, next(18) - 4);
            let hi = lo + IVec3::new(next(6), next(6), next(6));
            let (exact, got) = (brute(lo, hi), copy.holds(lo, hi));
            // Without the table, from the cells: right or mixed.
            let rough = plain.holds(lo, hi);
            assert!(rough == exact || rough == Holds::Mixed, "{lo} {hi}: {rough:?} for {exact:?}");
            match exact {
                // Empty is exact; a full box of one colour may be called mixed where a cell
                // around it holds another (never the other way).
                Holds::Empty => assert_eq!(got, Holds::Empty, "{lo} {hi}"),
                Holds::Full(_) => assert!(got == exact || got == Holds::Mixed, "{lo} {hi}: {got:?}"),
                Holds::Mixed => assert_eq!(got, Holds::Mixed, "{lo} {hi}"),
            }
            empty += usize::from(got == Holds::Empty);
            full += usize::from(matches!(got, Holds::Full(_)));
        }
        assert!(empty > 300 && full > 10, "{empty} empty, {full} full");
        // Exact where the summary cells (4³ from -2) are not: an empty box whose cell holds
        // clay, a full box of cells that hold partial points.
        assert_eq!(copy.holds(IVec3::new(13, 0, 0), IVec3::new(15, 3, 3)), Holds::Empty);
        assert_eq!(plain.holds(IVec3::new(13, 0, 0), IVec3::new(15, 3, 3)), Holds::Mixed);
        assert!(copy.span(IVec3::new(13, 0, 0), IVec3::new(15, 3, 3)).max > 0.25);
        assert_eq!(copy.holds(IVec3::new(2, 2, 2), IVec3::new(9, 5, 9)), Holds::Full(red));
        assert_eq!(copy.holds(IVec3::new(2, 2, 2), IVec3::new(10, 5, 9)), Holds::Mixed);
    }

    #[test]
    fn a_span_holds_the_lowest_and_highest_density_and_the_one_colour_of_full_points() {
        let mut f = Field::new(0.001, 0.5);
        let blue = [0.1, 0.2, 0.9, 1.0];
        f.edit_box(IVec3::ZERO, IVec3::new(11, 11, 11), true, |p, d, c| {
            *d = if p.x < 8 { 1.0 } else { 0.25 };
            *c = blue;
        });
        let copy = DenseCopy::read(&f, IVec3::ZERO, IVec3::splat(15));
        let full = copy.span(IVec3::new(0, 0, 0), IVec3::new(7, 7, 7));
        assert_eq!((full.min, full.max, full.full), (1.0, 1.0, Some(blue)));
        let mixed = copy.span(IVec3::new(6, 0, 0), IVec3::new(9, 3, 3));
        assert_eq!((mixed.min, mixed.max, mixed.full), (0.25, 1.0, None));
        // Cells are read whole: a box within a cell spans the cell's points.
        let edge = copy.span(IVec3::new(9, 0, 0), IVec3::new(9, 1, 1));
        assert_eq!((edge.min, edge.max), (0.25, 0.25));
        let wide = copy.span(IVec3::new(11, 0, 0), IVec3::new(12, 1, 1));
        assert_eq!((wide.min, wide.max), (0.0, 0.25), "its cells hold 8 to 15");
        assert_eq!(copy.span(IVec3::splat(20), IVec3::splat(30)), Span::EMPTY, "outside the copy");
        let beyond = copy.span(IVec3::new(0, 0, 0), IVec3::new(7, 7, 30));
        assert_eq!((beyond.min, beyond.full), (0.0, None), "partly outside: empty points");
        // Every point is within its span, whatever the box.
        for (lo, hi) in [(IVec3::splat(-3), IVec3::splat(17)), (IVec3::new(5, 1, 2), IVec3::new(10, 4, 13))] {
            let s = copy.span(lo, hi);
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let d = copy.density(IVec3::new(x, y, z));
                        assert!(s.min <= d && d <= s.max);
                    }
                }
            }
        }
        let mut tiled = TiledCopy::new();
        tiled.take(&f, IVec3::ZERO, IVec3::splat(7));
        assert_eq!(tiled.span(IVec3::ZERO, IVec3::splat(7)).full, Some(blue));
        assert_eq!(tiled.span(IVec3::splat(40), IVec3::splat(41)), Span::EMPTY, "not held: empty");
    }
}
