//! The marching-cubes kernel over one brick's gathered block of samples.

use super::cases::{flat_cases, CORNER_OFFSETS, EDGES};
use super::types::{ChunkMesh, Vertex};
use crate::field::{split_index, Brick, BrickKey, Colour, Field, Quantum, BRICK_SIZE, DEFAULT_COLOUR};
use crate::math::{IVec3, Vec3, Vec4, VoxelTransform};

/// Samples per axis of a gathered block: the brick plus one sample below (for gradients) and
/// two above (the cells' far corners, and their gradients).
pub const BLOCK: usize = BRICK_SIZE as usize + 3;
/// Samples in a gathered block.
pub const BLOCK_VOLUME: usize = BLOCK * BLOCK * BLOCK;
const CORNERS_PER_AXIS: usize = BRICK_SIZE as usize + 1;
// `Block::classify` compares a row of corners as 4 + 4 + 1.
const _: () = assert!(CORNERS_PER_AXIS == 9);

/// One brick's densities and their apron, gathered from the field so the kernel never looks
/// up a brick: block point `(x, y, z)` is lattice point `key·S − 1 + (x, y, z)`.
///
/// Colours are not gathered: only the two ends of each edge the surface crosses need one, so
/// the kernel reads them from the bricks themselves through a [`Neighbourhood`]. A block then
/// copies 4 bytes per sample instead of 20.
#[derive(Clone, Debug)]
pub struct Block {
    /// Densities, `x + BLOCK·(y + BLOCK·z)`.
    pub density: Vec<f32>,
    /// The same densities as stored, gathered before they are decoded all at once.
    pub stored: Vec<Quantum>,
    /// Lattice point of block point (0, 0, 0).
    pub origin: IVec3,
    /// Spare bricks for neighbours the coarser levels give (see `gather_block`); made on
    /// first need.
    pub refined: Vec<Brick>,
}

impl Default for Block {
    fn default() -> Self {
        Self {
            density: vec![0.0; BLOCK_VOLUME],
            stored: vec![0; BLOCK_VOLUME],
            origin: IVec3::ZERO,
            refined: Vec::new(),
        }
    }
}

/// The key of neighbour `i` of brick `key`, `i = (dx + 1) + 3·(dy + 1) + 9·(dz + 1)` (the
/// order of [`Neighbourhood::bricks`]).
#[inline]
pub(super) fn neighbour(key: BrickKey, i: usize) -> BrickKey {
    let i = i as i32;
    key + IVec3::new(i % 3 - 1, (i / 3) % 3 - 1, i / 9 - 1)
}

/// The bricks around one brick (itself and its 26 neighbours), looked up once.
#[derive(Clone, Copy, Debug)]
pub struct Neighbourhood<'f> {
    /// The brick at the centre.
    pub key: BrickKey,
    /// `bricks[(dx + 1) + 3·((dy + 1) + 3·(dz + 1))]` is brick `key + (dx, dy, dz)`, if stored.
    pub bricks: [Option<&'f Brick>; 27],
}

impl<'f> Neighbourhood<'f> {
    /// Looks up brick `key` and its neighbours in `field`.
    pub fn new(field: &'f Field, key: BrickKey) -> Self {
        Self { key, bricks: std::array::from_fn(|i| field.brick(neighbour(key, i))) }
    }

    /// The colour at lattice point `p`, which must lie in the neighbourhood.
    #[inline]
    pub fn colour(&self, p: IVec3) -> Colour {
        let (k, local) = split_index(p);
        let d = k - self.key + IVec3::ONE;
        debug_assert!(d.cmpge(IVec3::ZERO).all() && d.cmple(IVec3::splat(2)).all(), "{p} is outside");
        self.bricks[(d.x + 3 * (d.y + 3 * d.z)) as usize]
            .map_or(DEFAULT_COLOUR, |b| b.colour[Brick::linear(local)])
    }

    /// The colour at block point `(x, y, z)` (each in `0..BLOCK`): the same as [`Self::colour`]
    /// at the lattice point `key·S − 1 + (x, y, z)`, without dividing.
    #[inline]
    fn colour_in_block(&self, x: usize, y: usize, z: usize) -> Colour {
        // Block coordinate 0 is the last sample of the lower brick, 1 ..= S the centre brick,
        // S + 1 and S + 2 the first two of the upper one: brick (c + S − 1) / S, sample
        // (c + S − 1) % S.
        let s = BRICK_SIZE as usize;
        let (x, y, z) = (x + s - 1, y + s - 1, z + s - 1);
        let brick = x / s + 3 * (y / s + 3 * (z / s));
        self.bricks[brick].map_or(DEFAULT_COLOUR, |b| b.colour[x % s + s * (y % s + s * (z % s))])
    }
}

#[inline]
fn at(x: usize, y: usize, z: usize) -> usize {
    x + BLOCK * (y + BLOCK * z)
}

/// Rows of cell corners classified per brick: `CORNERS_PER_AXIS`² rows of one bit per corner.
const ROWS: usize = CORNERS_PER_AXIS * CORNERS_PER_AXIS;
/// A row whose corners are all dense.
const FULL_ROW: u16 = (1 << CORNERS_PER_AXIS) - 1;

/// Reusable per-worker buffers: the edge → vertex map of the brick being meshed and the
/// corners' classification.
#[derive(Clone, Debug)]
pub struct MarchScratch {
    /// Vertex of each crossing edge, slot `3·(x + C·(y + C·z)) + axis` for the edge from
    /// corner `(x, y, z)`; other slots hold whatever an earlier brick left.
    edge_vertex: Vec<u32>,
    /// Bit `x` of `dense[y + C·z]`: whether corner `(x, y, z)` (block point `(x, y, z) + 1`)
    /// is at least the iso-level.
    dense: [u16; ROWS],
}

impl Default for MarchScratch {
    fn default() -> Self {
        Self { edge_vertex: vec![u32::MAX; CORNERS_PER_AXIS.pow(3) * 3], dense: [0; ROWS] }
    }
}

/// For each cube edge: its lower corner's offset in the edge → vertex map (whose slot for
/// corner `(x, y, z)` and axis `a` is `3·(x + C·(y + C·z)) + a`), plus its axis.
const EDGE_SLOT: [usize; 12] = {
    let mut slots = [0; 12];
    let mut e = 0;
    while e < 12 {
        let (lower, axis) = EDGES[e];
        let o = CORNER_OFFSETS[lower as usize];
        let corner = o[0] as usize + CORNERS_PER_AXIS * (o[1] as usize + CORNERS_PER_AXIS * o[2] as usize);
        slots[e] = 3 * corner + axis as usize;
        e += 1;
    }
    slots
};

impl Block {
    /// Classifies the cell corners into `dense` (see [`MarchScratch`]); returns whether they
    /// are all on one side of `iso`.
    fn classify(&self, iso: f32, dense: &mut [u16; ROWS]) -> bool {
        let (mut any, mut all) = (0u16, FULL_ROW);
        for (i, bits) in dense.iter_mut().enumerate() {
            let row = at(1, 1 + i % CORNERS_PER_AXIS, 1 + i / CORNERS_PER_AXIS);
            let samples: &[f32; CORNERS_PER_AXIS] =
                self.density[row..row + CORNERS_PER_AXIS].try_into().expect("a row of corners");
            // Four samples to a comparison (the row is 9: 4 + 4 + 1).
            let four =
                |i: usize| Vec4::from_slice(&samples[i..i + 4]).cmpge(Vec4::splat(iso)).bitmask() as u16;
            *bits = four(0) | four(4) << 4 | u16::from(samples[8] >= iso) << 8;
            any |= *bits;
            all &= *bits;
        }
        any == 0 || all == FULL_ROW
    }

    /// Central-difference gradient at a block point (per lattice unit). Needs the point to be
    /// at least one sample inside the block.
    #[inline]
    fn gradient(&self, x: usize, y: usize, z: usize) -> Vec3 {
        let d = &self.density;
        let p = at(x, y, z);
        Vec3::new(
            d[p + 1] - d[p - 1],
            d[p + BLOCK] - d[p - BLOCK],
            d[p + BLOCK * BLOCK] - d[p - BLOCK * BLOCK],
        ) * 0.5
    }
}

/// Meshes the brick's cells (those whose minimum corner is in the brick) into `out`.
///
/// Seam contract: a vertex on a cell edge is interpolated from the edge's lower-index endpoint
/// towards the higher one, in lattice coordinates, from samples both neighbouring bricks gather
/// identically; so a vertex on a shared face is bit-identical in both bricks' meshes.
///
/// Vertices first: one on every edge of the cells' corner grid that the surface crosses
/// (each such edge is one that some cell's case uses, see the `cases` module), made in z, y, x
/// order of their lower corner and x, y, z order of axis. Then the cells, in z, y, x order (x
/// fastest), each with its triangles in case-table order, read their vertices from the
/// edge → vertex map, where every edge they use has one: no cell checks or clears a slot.
pub fn march_brick(
    block: &Block,
    colours: &Neighbourhood<'_>,
    iso: f32,
    transform: &VoxelTransform,
    scratch: &mut MarchScratch,
    out: &mut ChunkMesh,
) {
    out.reset();
    if block.classify(iso, &mut scratch.dense) {
        return;
    }
    let c = CORNERS_PER_AXIS;
    let s = BRICK_SIZE as usize;
    let MarchScratch { edge_vertex: map, dense } = scratch;
    let dense = &*dense;
    // Edges along x run from corners x = 0 ..= S − 1; along y and z from y or z ≤ S − 1.
    let along_x = FULL_ROW >> 1;
    for z in 0..c {
        for y in 0..c {
            let row = dense[y + c * z];
            let crossing = [
                (row ^ (row >> 1)) & along_x,
                if y < s { row ^ dense[y + 1 + c * z] } else { 0 },
                if z < s { row ^ dense[y + c * (z + 1)] } else { 0 },
            ];
            let mut any = crossing[0] | crossing[1] | crossing[2];
            while any != 0 {
                let x = any.trailing_zeros() as usize;
                any &= any - 1;
                let slot = 3 * (x + c * (y + c * z));
                let corner = [x + 1, y + 1, z + 1];
                let mut add = |axis: usize, vertex: Vertex| {
                    map[slot + axis] = out.vertices.len() as u32;
                    out.vertices.push(vertex);
                };
                if crossing[0] >> x & 1 == 1 {
                    add(0, edge_vertex::<0>(block, colours, iso, transform, corner));
                }
                if crossing[1] >> x & 1 == 1 {
                    add(1, edge_vertex::<1>(block, colours, iso, transform, corner));
                }
                if crossing[2] >> x & 1 == 1 {
                    add(2, edge_vertex::<2>(block, colours, iso, transform, corner));
                }
            }
        }
    }
    let cases = flat_cases();
    for cz in 0..s {
        for cy in 0..s {
            // The four rows of corners around this row of cells.
            let rows = [
                dense[cy + c * cz],
                dense[cy + 1 + c * cz],
                dense[cy + c * (cz + 1)],
                dense[cy + 1 + c * (cz + 1)],
            ];
            let (any, all) = (rows[0] | rows[1] | rows[2] | rows[3], rows[0] & rows[1] & rows[2] & rows[3]);
            if any == 0 || all == FULL_ROW {
                continue;
            }
            for cx in 0..s {
                // Corner c = x + 2y + 4z: bits (x, x + 1) of each row, rows in (y, z) order.
                let mask = usize::from(
                    ((rows[0] >> cx) & 3)
                        | (((rows[1] >> cx) & 3) << 2)
                        | (((rows[2] >> cx) & 3) << 4)
                        | (((rows[3] >> cx) & 3) << 6),
                );
                let cell_slot = 3 * (cx + c * (cy + c * cz));
                for &e in cases.edges(mask) {
                    out.indices.push(map[cell_slot + EDGE_SLOT[usize::from(e)]]);
                }
            }
        }
    }
}

/// The vertex on the edge from block point `corner` one step along axis `AXIS`.
#[inline]
fn edge_vertex<const AXIS: usize>(
    block: &Block,
    colours: &Neighbourhood<'_>,
    iso: f32,
    transform: &VoxelTransform,
    corner: [usize; 3],
) -> Vertex {
    let axis = AXIS;
    let [x, y, z] = corner;
    let step = [usize::from(axis == 0), usize::from(axis == 1), usize::from(axis == 2)];
    let (x1, y1, z1) = (x + step[0], y + step[1], z + step[2]);
    let (a, b) = (at(x, y, z), at(x1, y1, z1));
    let (va, vb) = (block.density[a], block.density[b]);
    let t = crossing(iso, va, vb);
    let position =
        crossing_position(transform, block.origin + IVec3::new(x as i32, y as i32, z as i32), axis, 1, t);
    let gradient = block.gradient(x, y, z).lerp(block.gradient(x1, y1, z1), t);
    let normal = if gradient.length_squared() > 1e-20 {
        -gradient.normalize()
    } else {
        // A flat spot exactly on the surface: face away from the dense end of the edge.
        let mut n = Vec3::ZERO;
        n[axis] = if va >= iso { 1.0 } else { -1.0 };
        n
    };
    let (ca, cb) = (colours.colour_in_block(x, y, z), colours.colour_in_block(x1, y1, z1));
    let colour = crossing_colour((va, ca), (vb, cb), t);
    Vertex { position: position.to_array(), normal: normal.to_array(), colour }
}

/// How far a crossing is kept from either end of its edge, as a fraction of the edge.
///
/// Two vertices nearest each other lie on two edges meeting at one sample, each this far from
/// it: `√2 ·` [`CROSSING_MARGIN`] of a voxel apart, 0.0014 voxel. A slicer or CAD tool that
/// welds the export at up to a thousandth of a voxel (1 µm at 1 mm voxels) then merges no
/// vertex, and the mesh stays closed and manifold; the surface moves by at most 1/1024 voxel
/// where a sample lies on it or nearly (under a micrometre at 1 mm voxels).
pub const CROSSING_MARGIN: f32 = 1.0 / 1024.0;

/// Where the surface crosses an edge whose ends hold `va` and `vb`, as a fraction of the edge
/// from the `va` end. Kept [`CROSSING_MARGIN`] off the ends, so that a sample lying on or
/// near the iso-level (tool values are multiples of 1/64) does not put the vertices of several
/// edges at one point or nearly so: positions stay distinct and a mesh welded by position, or
/// within a thousandth of a voxel, keeps its topology.
#[inline]
pub(super) fn crossing(iso: f32, va: f32, vb: f32) -> f32 {
    ((iso - va) / (vb - va)).clamp(CROSSING_MARGIN, 1.0 - CROSSING_MARGIN)
}

/// World position of the crossing at fraction `t` of the edge of `length` finest voxels from
/// finest lattice point `lower` along `axis`. Every mesh level computes an edge's vertex here,
/// from the same two samples: where meshes of two levels share an edge, they share its vertex
/// bit for bit.
#[inline]
pub(super) fn crossing_position(
    transform: &VoxelTransform,
    lower: IVec3,
    axis: usize,
    length: i32,
    t: f32,
) -> Vec3 {
    let mut lattice = lower.as_vec3();
    // (`t · 1` is `t` exactly: the finest level's kernel agrees.)
    lattice[axis] += t * length as f32;
    transform.index_to_world(lattice)
}

/// The colour at fraction `t` of an edge between samples `a` and `b` (density, colour),
/// weighted by matter as well as by position: the empty end of an edge holds no clay, so its
/// (meaningless) colour must not tint the surface.
#[inline]
pub(super) fn crossing_colour((va, ca): (f32, Colour), (vb, cb): (f32, Colour), t: f32) -> Colour {
    let (wa, wb) = (va.max(0.0) * (1.0 - t), vb.max(0.0) * t);
    let total = wa + wb;
    if ca == cb || wb == 0.0 {
        // One colour at both ends (most edges), or matter at one end only: it is the
        // vertex's, exactly (an empty sample's colour, whatever it is, changes nothing).
        ca
    } else if wa == 0.0 {
        cb
    } else if total > 0.0 {
        std::array::from_fn(|i| (ca[i] * wa + cb[i] * wb) / total)
    } else {
        std::array::from_fn(|i| ca[i] + (cb[i] - ca[i]) * t)
    }
}
