//! The simulation's dense window on the sparse field.
//!
//! ```text
//!   lattice point p  ↔  cell (p − lo), linear index x + nx·(y + ny·z)
//!
//!   +---------------------+   the outermost layer of cells is a wall: it never moves and
//!   |#####################|   never receives matter, so every interior cell has its six
//!   |#                   #|   neighbours in the grid and no kernel checks bounds. The
//!   |#     interior      #|   window is chosen with a margin wide enough that the clay
//!   |#                   #|   never reaches the wall.
//!   |#####################|
//!   +---------------------+
//! ```

use rustc_hash::FxHashSet;

use crate::field::{Colour, Field, FieldReader, BRICK_SIZE};
use crate::math::{Aabb, IVec3};

/// The cell is held: its matter is not displaced, and it anchors the supports' distance.
pub(crate) const FIXED: u8 = 1;
/// The cell belongs to the outermost layer.
pub(crate) const WALL: u8 = 2;
/// The cell is in the conservation layer's queue.
pub(crate) const QUEUED: u8 = 4;
/// A body covers the cell: its capacity may be under 1 and its owner is set.
pub(crate) const COVERED: u8 = 8;

/// No tool covers the cell.
pub(crate) const NO_OWNER: u8 = u8::MAX;

/// Densities of a window of the lattice, with per-cell state shared by the layers.
#[derive(Debug)]
pub(crate) struct Grid {
    /// Lattice point of cell (0, 0, 0).
    pub lo: IVec3,
    /// Cells along each axis.
    pub dims: IVec3,
    /// Matter per cell (1 is a full cell).
    pub density: Vec<f32>,
    /// Room for matter per cell: 1 − the densest tool covering it.
    pub capacity: Vec<f32>,
    /// Directions matter may leave the cell by (bit `d` for [`NEIGHBOURS`]`[d]`), or
    /// [`DIRS_UNKNOWN`].
    pub dirs: Vec<u8>,
    /// Index of the tool covering the cell most, or [`NO_OWNER`].
    pub owner: Vec<u8>,
    /// [`FIXED`], [`WALL`], [`QUEUED`], [`COVERED`].
    pub flags: Vec<u8>,
    /// Linear offsets of the six neighbours: −x, +x, −y, +y, −z, +z.
    pub offsets: [isize; 6],
    /// Per row of cells along X (index `y + ny·z`): 0 where every cell of the row is surely
    /// empty. Every layer that puts matter in a cell marks its row ([`Grid::mark_around`]);
    /// the scans for excess, loose matter and crumbs skip the rows left unmarked, and the
    /// tension layer's scan unmarks the rows it finds empty.
    pub rows: Vec<u8>,
}

/// The six axis directions, in the order of [`Grid::offsets`] and of the direction bits.
pub(crate) const NEIGHBOURS: [IVec3; 6] = [
    IVec3::new(-1, 0, 0),
    IVec3::new(1, 0, 0),
    IVec3::new(0, -1, 0),
    IVec3::new(0, 1, 0),
    IVec3::new(0, 0, -1),
    IVec3::new(0, 0, 1),
];

/// Every direction allowed.
pub(crate) const ALL_DIRS: u8 = 0b11_1111;

/// A body covers the cell and its directions are not known yet (found on first need).
pub(crate) const DIRS_UNKNOWN: u8 = u8::MAX;

impl Grid {
    /// Copies the field's densities over lattice points `lo ..= hi` (at least 3 on each axis).
    pub fn load(field: &Field, lo: IVec3, hi: IVec3) -> Self {
        let dims = (hi - lo + IVec3::ONE).max(IVec3::splat(3));
        let n = (dims.x * dims.y * dims.z) as usize;
        let mut density = vec![0.0f32; n];
        let mut flags = vec![0u8; n];
        let mut reader = FieldReader::new(field);
        let mut i = 0;
        for z in 0..dims.z {
            for y in 0..dims.y {
                for x in 0..dims.x {
                    let wall =
                        x == 0 || y == 0 || z == 0 || x == dims.x - 1 || y == dims.y - 1 || z == dims.z - 1;
                    if wall {
                        flags[i] = WALL;
                    }
                    let d = reader.density(lo + IVec3::new(x, y, z));
                    density[i] = if d.is_finite() { d.max(0.0) } else { 0.0 };
                    i += 1;
                }
            }
        }
        let sy = dims.x as isize;
        let sz = sy * dims.y as isize;
        let rows = density.chunks(dims.x as usize).map(|r| u8::from(r.iter().any(|&d| d > 0.0))).collect();
        Self {
            lo,
            dims,
            density,
            capacity: vec![1.0; n],
            dirs: vec![ALL_DIRS; n],
            owner: vec![NO_OWNER; n],
            flags,
            offsets: [-1, 1, -sy, sy, -sz, sz],
            rows,
        }
    }

    /// Marks the rows of interior cell `i` and of its six neighbours as holding matter.
    #[inline]
    pub fn mark_around(&mut self, i: usize) {
        mark_rows_around(&mut self.rows, self.dims, i);
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.density.len()
    }

    /// Linear index of a cell coordinate.
    #[inline]
    pub fn index(&self, c: IVec3) -> usize {
        (c.x + self.dims.x * (c.y + self.dims.y * c.z)) as usize
    }

    /// Cell coordinate of a linear index.
    #[inline]
    pub fn coord(&self, i: usize) -> IVec3 {
        cell_coord(self.dims, i)
    }

    /// Linear index of neighbour `d` of interior cell `i`.
    #[inline]
    pub fn neighbour(&self, i: usize, d: usize) -> usize {
        (i as isize + self.offsets[d]) as usize
    }

    /// Total matter, summed in f64.
    pub fn mass(&self) -> f64 {
        self.density.iter().map(|&d| f64::from(d)).sum()
    }
}

/// [`Grid::mark_around`] on the grid's row marks `rows`, for a grid of `dims` cells.
#[inline]
pub(crate) fn mark_rows_around(rows: &mut [u8], dims: IVec3, i: usize) {
    let r = i / dims.x as usize;
    let ny = dims.y as usize;
    rows[r - 1] = 1;
    rows[r] = 1;
    rows[r + 1] = 1;
    rows[r - ny] = 1;
    rows[r + ny] = 1;
}

/// [`Grid::coord`] for a grid of `dims` cells.
#[inline]
pub(crate) fn cell_coord(dims: IVec3, i: usize) -> IVec3 {
    let i = i as i32;
    let x = i % dims.x;
    let yz = i / dims.x;
    IVec3::new(x, yz % dims.y, yz / dims.y)
}

/// Writes what changed since the last write back into the field.
///
/// `written` holds the densities the field was last given (or loaded from); bricks of the
/// field where no cell differs from it are left alone. Densities go in clamped to [0, 1];
/// cells that receive matter where the field had none take `colour`.
pub(crate) fn write_back(grid: &Grid, written: &mut [f32], field: &mut Field, colour: Colour) {
    let s = IVec3::splat(BRICK_SIZE);
    // Interior only: the wall never changes.
    let (lo, hi) = (grid.lo + IVec3::ONE, grid.lo + grid.dims - IVec3::splat(2));
    let mut changed: FxHashSet<IVec3> = FxHashSet::default();
    for (i, (&d, &w)) in grid.density.iter().zip(written.iter()).enumerate() {
        if d.to_bits() != w.to_bits() {
            changed.insert((grid.lo + grid.coord(i)).div_euclid(s));
        }
    }
    if changed.is_empty() {
        return;
    }
    let reaches = |a: IVec3, _b: IVec3| changed.contains(&a.div_euclid(s));
    field.edit_region(lo, hi, true, reaches, |p, d, c| {
        let i = grid.index(p - grid.lo);
        let new = grid.density[i].clamp(0.0, 1.0);
        if *d <= 0.0 && new > 0.0 {
            *c = colour;
        }
        *d = new;
        written[i] = grid.density[i];
    });
}

/// A window around `tools` (world boxes) and the clay connected to them: the boxes, grown to
/// the field's bricks that touch them or touch, through other stored bricks, a brick that
/// does; then `margin` lattice points on every side, for the clay to move into and for the
/// wall. Returns lattice points `lo ..= hi`.
pub fn window_around(field: &Field, tools: &[Aabb], margin: i32) -> (IVec3, IVec3) {
    let t = field.transform();
    let s = IVec3::splat(BRICK_SIZE);
    let mut lo = IVec3::splat(i32::MAX);
    let mut hi = IVec3::splat(i32::MIN);
    let mut frontier = Vec::new();
    let mut seen: FxHashSet<IVec3> = FxHashSet::default();
    for b in tools.iter().filter(|b| !b.is_empty() && b.min.is_finite() && b.max.is_finite()) {
        let a = t.world_to_index(b.min).floor().as_ivec3();
        let z = t.world_to_index(b.max).ceil().as_ivec3();
        lo = lo.min(a);
        hi = hi.max(z);
        let (ka, kz) = (a.div_euclid(s) - IVec3::ONE, z.div_euclid(s) + IVec3::ONE);
        for kz_ in ka.z..=kz.z {
            for ky in ka.y..=kz.y {
                for kx in ka.x..=kz.x {
                    let k = IVec3::new(kx, ky, kz_);
                    if field.read_range(k).is_some_and(|r| r.1 > 0.0) && seen.insert(k) {
                        frontier.push(k);
                    }
                }
            }
        }
    }
    while let Some(k) = frontier.pop() {
        lo = lo.min(k * s);
        hi = hi.max(k * s + s - IVec3::ONE);
        for d in NEIGHBOURS {
            let n = k + d;
            if field.read_range(n).is_some_and(|r| r.1 > 0.0) && seen.insert(n) {
                frontier.push(n);
            }
        }
    }
    if lo.cmpgt(hi).any() {
        return (IVec3::ZERO, IVec3::splat(2));
    }
    (lo - IVec3::splat(margin), hi + IVec3::splat(margin))
}
