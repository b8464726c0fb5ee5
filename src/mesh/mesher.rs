//! Meshing the whole field or just its dirty bricks, in parallel.

use rayon::prelude::*;

use super::march::{march_brick, Block, MarchScratch, Neighbourhood, BLOCK};
use super::types::{ChunkMesh, MeshDiff};
use crate::field::{Brick, BrickKey, Field, BRICK_SIZE};
use crate::math::IVec3;

/// Copies brick `key`'s densities and apron into `block`, row by row (within a brick and
/// within the block, the samples of one (y, z) row are contiguous, so each row is one slice
/// copy). Returns the bricks it read, for the kernel's colour look-ups.
pub fn gather_block<'f>(field: &'f Field, key: BrickKey, block: &mut Block) -> Neighbourhood<'f> {
    let around = Neighbourhood::new(field, key);
    let s = BRICK_SIZE;
    block.origin = key * s - IVec3::ONE;
    let lo = block.origin;
    let hi = lo + IVec3::splat(BLOCK as i32 - 1);
    for (i, brick) in around.bricks.iter().enumerate() {
        let i = i as i32;
        let base = (key + IVec3::new(i % 3 - 1, (i / 3) % 3 - 1, i / 9 - 1)) * s;
        let a = lo.max(base);
        let b = hi.min(base + IVec3::splat(s - 1));
        if a.cmpgt(b).any() {
            continue;
        }
        let len = (b.x - a.x + 1) as usize;
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                let q = (IVec3::new(a.x, y, z) - lo).as_uvec3();
                let dst = q.x as usize + BLOCK * (q.y as usize + BLOCK * q.z as usize);
                let row = &mut block.density[dst..dst + len];
                match brick {
                    Some(brick) => {
                        let src = Brick::linear(IVec3::new(a.x, y, z) - base);
                        row.copy_from_slice(&brick.density[src..src + len]);
                    }
                    None => row.fill(0.0),
                }
            }
        }
    }
    around
}

/// Meshes one brick into `out`, reusing the caller's buffers.
pub fn mesh_brick(
    field: &Field,
    key: BrickKey,
    block: &mut Block,
    scratch: &mut MarchScratch,
    out: &mut ChunkMesh,
) {
    let around = gather_block(field, key, block);
    march_brick(block, &around, field.iso(), field.transform(), scratch, out);
}

/// Whether brick `key` surely holds no triangle: the cells it meshes read bricks
/// `key ..= key + 1` on each axis, and those are all inside the clay or all outside it.
/// Decided from the field's per-brick density ranges, without reading a sample.
pub fn surely_empty(field: &Field, key: BrickKey) -> bool {
    let iso = field.iso();
    let mut inside = 0;
    for c in 0..8 {
        let k = key + IVec3::new(c & 1, (c >> 1) & 1, (c >> 2) & 1);
        match field.density_range(k) {
            None => {}
            Some((_, hi)) if hi < iso => {}
            Some((lo, _)) if lo >= iso => inside += 1,
            Some(_) => return false,
        }
        if inside != 0 && inside != c + 1 {
            return false;
        }
    }
    true
}

/// Re-meshes the given bricks in parallel: bricks with triangles are upserted, the others
/// removed (removing a chunk the renderer does not hold is harmless).
pub fn remesh<I: IntoIterator<Item = BrickKey>>(field: &Field, keys: I) -> MeshDiff {
    let mut keys: Vec<BrickKey> = keys.into_iter().collect();
    // A fixed order makes diffs (and so draw order and images) reproducible.
    keys.sort_unstable_by_key(|k| k.to_array());
    keys.dedup();
    let mut diff = MeshDiff::default();
    keys.retain(|&k| {
        let empty = surely_empty(field, k);
        if empty {
            diff.removed.push(k);
        }
        !empty
    });
    // Each worker marches into buffers it keeps across bricks (they grow once to the largest
    // chunk), and a chunk leaves with vectors of exactly its size: one allocation each.
    let meshes: Vec<(BrickKey, ChunkMesh)> = keys
        .par_iter()
        .map_init(
            || (Block::default(), MarchScratch::default(), ChunkMesh::default()),
            |(block, scratch, work), &key| {
                mesh_brick(field, key, block, scratch, work);
                (key, ChunkMesh { vertices: work.vertices.clone(), indices: work.indices.clone() })
            },
        )
        .collect();
    for (key, mesh) in meshes {
        if mesh.is_empty() {
            diff.removed.push(key);
        } else {
            diff.upserted.push((key, mesh));
        }
    }
    diff
}

/// Every brick that can hold triangles: a cell in brick `K` reads bricks `K ..= K + 1`, so
/// each stored brick `B` may put triangles in bricks `B − 1 ..= B` on each axis.
pub fn meshable_bricks(field: &Field) -> Vec<BrickKey> {
    let mut keys: Vec<BrickKey> = field
        .brick_keys()
        .flat_map(|b| (0..8).map(move |c| b - IVec3::new(c & 1, (c >> 1) & 1, (c >> 2) & 1)))
        .collect();
    keys.sort_unstable_by_key(|k| k.to_array());
    keys.dedup();
    keys
}

/// Meshes the whole field; only upserts.
pub fn mesh_all(field: &Field) -> MeshDiff {
    let mut diff = remesh(field, meshable_bricks(field));
    diff.removed.clear();
    diff
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
        let r = IVec3::splat(radius + 2);
        let grey: Colour = [0.5; 4];
        f.edit_box(-r, r, true, |p, d, c| {
            *d = (0.5 - (p.as_vec3().length() - radius as f32) / 4.0).clamp(0.0, 1.0);
            *c = grey;
        });
        f
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
