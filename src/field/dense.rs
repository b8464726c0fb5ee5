//! A dense copy of a box of the clay: one density and one colour per lattice point of the
//! finest level, read through every level, for operations that resample the clay through a
//! mapping and must read it as it was while they write: one box ([`DenseCopy`]), or the tiles
//! an operation has touched so far ([`TiledCopy`]).

use std::collections::HashMap;

use super::{Colour, Field, FieldReader, DEFAULT_COLOUR};
use crate::math::{div_floor, IVec3, Vec3};

/// Densities and colours over the lattice points `lo ..= lo + dims − 1`, `x` fastest; points
/// outside read as empty.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DenseCopy {
    lo: IVec3,
    dims: IVec3,
    density: Vec<f32>,
    colour: Vec<Colour>,
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
        Self { lo, dims, density, colour }
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

    /// Trilinear density and density-weighted colour at a fractional lattice coordinate.
    #[inline]
    pub fn sample(&self, index: Vec3) -> (f32, Colour) {
        let base = index.floor();
        let f = index - base;
        let b = base.as_ivec3();
        let (mut d, mut c) = (0.0f32, [0.0f32; 4]);
        for corner in 0..8 {
            let o = IVec3::new(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = (if o.x == 1 { f.x } else { 1.0 - f.x })
                * (if o.y == 1 { f.y } else { 1.0 - f.y })
                * (if o.z == 1 { f.z } else { 1.0 - f.z });
            let Some(i) = self.index(b + o) else { continue };
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
}
