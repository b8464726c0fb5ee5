//! The marching-cubes kernel over one brick's gathered block of samples.

use super::cases::{case_table, CORNER_OFFSETS, EDGES};
use super::types::{ChunkMesh, Vertex};
use crate::field::{split_index, Brick, BrickKey, Colour, Field, BRICK_SIZE, DEFAULT_COLOUR};
use crate::math::{IVec3, Vec3, VoxelTransform};

/// Samples per axis of a gathered block: the brick plus one sample below (for gradients) and
/// two above (the cells' far corners, and their gradients).
pub const BLOCK: usize = BRICK_SIZE as usize + 3;
/// Samples in a gathered block.
pub const BLOCK_VOLUME: usize = BLOCK * BLOCK * BLOCK;
const CORNERS_PER_AXIS: usize = BRICK_SIZE as usize + 1;

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
    /// Lattice point of block point (0, 0, 0).
    pub origin: IVec3,
}

impl Default for Block {
    fn default() -> Self {
        Self { density: vec![0.0; BLOCK_VOLUME], origin: IVec3::ZERO }
    }
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
        let bricks = std::array::from_fn(|i| {
            let i = i as i32;
            field.brick(key + IVec3::new(i % 3 - 1, (i / 3) % 3 - 1, i / 9 - 1))
        });
        Self { key, bricks }
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
}

#[inline]
fn at(x: usize, y: usize, z: usize) -> usize {
    x + BLOCK * (y + BLOCK * z)
}

/// Reusable per-worker buffers: the edge → vertex map of the brick being meshed.
#[derive(Clone, Debug)]
pub struct MarchScratch {
    edge_vertex: Vec<u32>,
}

impl Default for MarchScratch {
    fn default() -> Self {
        Self { edge_vertex: vec![u32::MAX; CORNERS_PER_AXIS.pow(3) * 3] }
    }
}

impl Block {
    /// Whether the cells of the brick all lie on one side of `iso` (no triangle possible).
    pub fn is_uniform(&self, iso: f32) -> bool {
        let first = self.density[at(1, 1, 1)] >= iso;
        for z in 1..=CORNERS_PER_AXIS {
            for y in 1..=CORNERS_PER_AXIS {
                let row = at(1, y, z);
                if self.density[row..row + CORNERS_PER_AXIS].iter().any(|&d| (d >= iso) != first) {
                    return false;
                }
            }
        }
        true
    }

    /// Central-difference gradient at a block point (per lattice unit). Needs the point to be
    /// at least one sample inside the block.
    #[inline]
    fn gradient(&self, x: usize, y: usize, z: usize) -> Vec3 {
        let d = &self.density;
        Vec3::new(
            d[at(x + 1, y, z)] - d[at(x - 1, y, z)],
            d[at(x, y + 1, z)] - d[at(x, y - 1, z)],
            d[at(x, y, z + 1)] - d[at(x, y, z - 1)],
        ) * 0.5
    }
}

/// Meshes the brick's cells (those whose minimum corner is in the brick) into `out`.
///
/// Seam contract: a vertex on a cell edge is interpolated from the edge's lower-index endpoint
/// towards the higher one, in lattice coordinates, from samples both neighbouring bricks gather
/// identically; so a vertex on a shared face is bit-identical in both bricks' meshes.
pub fn march_brick(
    block: &Block,
    colours: &Neighbourhood<'_>,
    iso: f32,
    transform: &VoxelTransform,
    scratch: &mut MarchScratch,
    out: &mut ChunkMesh,
) {
    out.reset();
    if block.is_uniform(iso) {
        return;
    }
    scratch.edge_vertex.fill(u32::MAX);
    let table = case_table();
    let s = BRICK_SIZE as usize;
    for cz in 1..=s {
        for cy in 1..=s {
            for cx in 1..=s {
                let mut mask = 0usize;
                for (c, o) in CORNER_OFFSETS.iter().enumerate() {
                    let p = at(cx + o[0] as usize, cy + o[1] as usize, cz + o[2] as usize);
                    if block.density[p] >= iso {
                        mask |= 1 << c;
                    }
                }
                let triangles = &table[mask];
                if triangles.is_empty() {
                    continue;
                }
                for tri in triangles {
                    for &e in tri {
                        let index =
                            edge_vertex(block, colours, iso, transform, scratch, out, [cx, cy, cz], e);
                        out.indices.push(index);
                    }
                }
            }
        }
    }
}

/// The index of the vertex on edge `e` of the cell at block point `cell`, made on first use.
#[allow(clippy::too_many_arguments)]
fn edge_vertex(
    block: &Block,
    colours: &Neighbourhood<'_>,
    iso: f32,
    transform: &VoxelTransform,
    scratch: &mut MarchScratch,
    out: &mut ChunkMesh,
    cell: [usize; 3],
    e: u8,
) -> u32 {
    let (lower, axis) = EDGES[usize::from(e)];
    let o = CORNER_OFFSETS[usize::from(lower)];
    let (x, y, z) = (cell[0] + o[0] as usize, cell[1] + o[1] as usize, cell[2] + o[2] as usize);
    let axis = usize::from(axis);
    let key = (((x - 1) + CORNERS_PER_AXIS * ((y - 1) + CORNERS_PER_AXIS * (z - 1))) * 3) + axis;
    if scratch.edge_vertex[key] != u32::MAX {
        return scratch.edge_vertex[key];
    }
    let step = [usize::from(axis == 0), usize::from(axis == 1), usize::from(axis == 2)];
    let (x1, y1, z1) = (x + step[0], y + step[1], z + step[2]);
    let (a, b) = (at(x, y, z), at(x1, y1, z1));
    let (va, vb) = (block.density[a], block.density[b]);
    // Kept off the ends so that a sample lying exactly on the iso-level (tool values are
    // multiples of 1/64) does not put the vertices of several edges at one point: positions
    // then stay distinct and a mesh welded by position keeps its topology.
    let t = ((iso - va) / (vb - va)).clamp(1e-4, 1.0 - 1e-4);
    let mut lattice = (block.origin + IVec3::new(x as i32, y as i32, z as i32)).as_vec3();
    lattice[axis] += t;
    let position = transform.index_to_world(lattice);
    let gradient = block.gradient(x, y, z).lerp(block.gradient(x1, y1, z1), t);
    let normal = if gradient.length_squared() > 1e-20 {
        -gradient.normalize()
    } else {
        // A flat spot exactly on the surface: face away from the dense end of the edge.
        let mut n = Vec3::ZERO;
        n[axis] = if va >= iso { 1.0 } else { -1.0 };
        n
    };
    // Colour is weighted by matter as well as by position: the empty end of an edge holds no
    // clay, so its (meaningless) colour must not tint the surface.
    let corner = block.origin + IVec3::new(x as i32, y as i32, z as i32);
    let (ca, cb) = (colours.colour(corner), colours.colour(corner + IVec3::from(step.map(|c| c as i32))));
    let (wa, wb) = (va.max(0.0) * (1.0 - t), vb.max(0.0) * t);
    let total = wa + wb;
    let colour = if total > 0.0 {
        std::array::from_fn(|i| (ca[i] * wa + cb[i] * wb) / total)
    } else {
        std::array::from_fn(|i| ca[i] + (cb[i] - ca[i]) * t)
    };
    let index = out.vertices.len() as u32;
    out.vertices.push(Vertex { position: position.to_array(), normal: normal.to_array(), colour });
    scratch.edge_vertex[key] = index;
    index
}
