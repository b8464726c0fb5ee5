//! Where the clay's mesh chunks live on the GPU: one vertex arena and one index arena shared by
//! every chunk, so the whole clay draws with a single indexed draw.
//!
//! ```text
//!  index arena:  [ chunk A tris | 0 0 0 0 0 0 (freed) | chunk C tris | chunk B tris ]  ← draw count
//!  vertex arena: [ A verts | free | C verts | B verts | free …                       ]
//! ```
//!
//! - Indices are stored rebased (each index plus its chunk's first vertex), so the draw needs
//!   no per-chunk vertex offset.
//! - A freed index range is overwritten with zeros: degenerate triangles that rasterise to
//!   nothing, so holes need no separate draw list.
//! - The draw covers indices up to the end of the last allocated range (the high-water mark).
//! - Ranges come from `range-alloc` (first fit with coalescing). When a chunk does not fit,
//!   the arena doubles; the old contents are copied at the same offsets, so rebased indices
//!   stay valid.
//!
//! Re-meshing a brick frees its chunk's ranges and allocates new ones: an edit costs uploads
//! proportional to what changed, never to the whole clay. The bookkeeping here is pure; the
//! bytes go to an [`ArenaStorage`] (GPU buffers in the renderer, plain vectors in tests).

use std::collections::HashMap;
use std::ops::Range;

use range_alloc::RangeAllocator;

use crate::mesh::{ChunkKey, MeshDiff, Vertex};

/// Where the arena's bytes are stored.
pub(crate) trait ArenaStorage {
    /// The error growing storage can cause.
    type Error;
    /// Makes room for `vertices` vertices and `indices` indices, keeping what is stored at
    /// the same positions.
    fn reserve(&mut self, vertices: u32, indices: u32) -> Result<(), Self::Error>;
    /// Writes vertices from position `at`.
    fn write_vertices(&mut self, at: u32, vertices: &[Vertex]);
    /// Writes indices from position `at`.
    fn write_indices(&mut self, at: u32, indices: &[u32]);
}

#[derive(Clone, Debug)]
struct Slot {
    vertices: Range<u32>,
    indices: Range<u32>,
}

/// The arena's bookkeeping: which ranges each chunk holds.
#[derive(Debug)]
pub(crate) struct ChunkArena {
    vertices: RangeAllocator<u32>,
    indices: RangeAllocator<u32>,
    slots: HashMap<ChunkKey, Slot>,
    triangles: usize,
    draw_count: u32,
    scratch: Vec<u32>,
}

impl ChunkArena {
    /// An arena with room for `vertices` and `indices` to begin with.
    pub(crate) fn new(vertices: u32, indices: u32) -> Self {
        Self {
            vertices: RangeAllocator::new(0..vertices.max(1)),
            indices: RangeAllocator::new(0..indices.max(3)),
            slots: HashMap::new(),
            triangles: 0,
            draw_count: 0,
            scratch: Vec::new(),
        }
    }

    /// Current capacity: (vertices, indices).
    pub(crate) fn capacity(&self) -> (u32, u32) {
        (self.vertices.initial_range().end, self.indices.initial_range().end)
    }

    /// Live triangles.
    pub(crate) fn triangles(&self) -> usize {
        self.triangles
    }

    /// Indices the single draw covers (live triangles plus zeroed holes).
    pub(crate) fn draw_count(&self) -> u32 {
        self.draw_count
    }

    /// Live chunks.
    pub(crate) fn chunk_count(&self) -> usize {
        self.slots.len()
    }

    fn free(&mut self, key: ChunkKey, storage: &mut impl ArenaStorage) {
        if let Some(slot) = self.slots.remove(&key) {
            self.scratch.clear();
            self.scratch.resize(slot.indices.len(), 0);
            storage.write_indices(slot.indices.start, &self.scratch);
            self.triangles -= slot.indices.len() / 3;
            self.vertices.free_range(slot.vertices);
            self.indices.free_range(slot.indices);
        }
    }

    fn allocate<S: ArenaStorage>(
        &mut self,
        vertices: u32,
        indices: u32,
        storage: &mut S,
    ) -> Result<Slot, S::Error> {
        loop {
            let v = self.vertices.allocate_range(vertices);
            let i = self.indices.allocate_range(indices);
            match (v, i) {
                (Ok(vertices), Ok(indices)) => return Ok(Slot { vertices, indices }),
                (v, i) => {
                    if let Ok(r) = v {
                        self.vertices.free_range(r);
                    }
                    if let Ok(r) = i {
                        self.indices.free_range(r);
                    }
                    let (vc, ic) = self.capacity();
                    let new_v = vc.saturating_mul(2).max(vc.saturating_add(vertices));
                    let new_i = ic.saturating_mul(2).max(ic.saturating_add(indices));
                    storage.reserve(new_v, new_i)?;
                    self.vertices.grow_to(new_v);
                    self.indices.grow_to(new_i);
                }
            }
        }
    }

    /// Applies a mesh diff: frees removed and replaced chunks, writes the new ones.
    pub(crate) fn apply<S: ArenaStorage>(
        &mut self,
        diff: &MeshDiff,
        storage: &mut S,
    ) -> Result<(), S::Error> {
        for key in &diff.removed {
            self.free(*key, storage);
        }
        for (key, _) in &diff.upserted {
            self.free(*key, storage);
        }
        for (key, chunk) in &diff.upserted {
            if chunk.is_empty() {
                continue;
            }
            let slot = self.allocate(chunk.vertices.len() as u32, chunk.indices.len() as u32, storage)?;
            storage.write_vertices(slot.vertices.start, &chunk.vertices);
            self.scratch.clear();
            self.scratch.extend(chunk.indices.iter().map(|i| i + slot.vertices.start));
            storage.write_indices(slot.indices.start, &self.scratch);
            self.triangles += chunk.triangle_count();
            self.slots.insert(*key, slot);
        }
        self.draw_count = self.indices.allocated_ranges().map(|r| r.end).max().unwrap_or(0);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::IVec3;
    use crate::mesh::ChunkMesh;
    use proptest::prelude::*;

    #[derive(Default)]
    struct Vecs {
        vertices: Vec<Vertex>,
        indices: Vec<u32>,
        grown: usize,
    }

    impl ArenaStorage for Vecs {
        type Error = std::convert::Infallible;
        fn reserve(&mut self, vertices: u32, indices: u32) -> Result<(), Self::Error> {
            self.vertices.resize(vertices as usize, Vertex::default());
            self.indices.resize(indices as usize, 0);
            self.grown += 1;
            Ok(())
        }
        fn write_vertices(&mut self, at: u32, vertices: &[Vertex]) {
            self.vertices[at as usize..at as usize + vertices.len()].copy_from_slice(vertices);
        }
        fn write_indices(&mut self, at: u32, indices: &[u32]) {
            self.indices[at as usize..at as usize + indices.len()].copy_from_slice(indices);
        }
    }

    /// A chunk whose triangles carry the key and a generation in their vertex positions.
    fn chunk(key: i32, generation: u32, triangles: usize) -> ChunkMesh {
        let mut m = ChunkMesh::default();
        for t in 0..triangles {
            for c in 0..3 {
                m.indices.push(m.vertices.len() as u32);
                m.vertices.push(Vertex {
                    position: [key as f32, generation as f32, (3 * t + c) as f32],
                    ..Vertex::default()
                });
            }
        }
        m
    }

    /// The non-degenerate triangles the single draw produces, as sorted position triples.
    fn drawn(arena: &ChunkArena, s: &Vecs) -> Vec<[[u32; 3]; 3]> {
        let mut tris: Vec<[[u32; 3]; 3]> = s.indices[..arena.draw_count() as usize]
            .chunks(3)
            .filter(|t| !(t[0] == t[1] && t[1] == t[2]))
            .map(|t| t.iter().map(|&i| s.vertices[i as usize].position.map(|p| p as u32)).collect::<Vec<_>>())
            .map(|v| [v[0], v[1], v[2]])
            .collect();
        tris.sort_unstable();
        tris
    }

    fn expected(live: &HashMap<i32, (u32, usize)>) -> Vec<[[u32; 3]; 3]> {
        let mut tris = Vec::new();
        for (&key, &(generation, n)) in live {
            let m = chunk(key, generation, n);
            for t in m.indices.chunks(3) {
                let v: Vec<[u32; 3]> =
                    t.iter().map(|&i| m.vertices[i as usize].position.map(|p| p as u32)).collect();
                tris.push([v[0], v[1], v[2]]);
            }
        }
        tris.sort_unstable();
        tris
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(7), ..ProptestConfig::default() })]
        /// Whatever sequence of upserts and removals, the single draw shows exactly the live
        /// chunks' triangles, and the arena grows only when it must.
        #[test]
        fn the_single_draw_shows_exactly_the_live_chunks(
            ops in proptest::collection::vec((0i32..12, 0usize..20, any::<bool>()), 1..60)
        ) {
            let mut arena = ChunkArena::new(16, 16);
            let mut storage = Vecs::default();
            storage.reserve(16, 16).unwrap();
            let mut live: HashMap<i32, (u32, usize)> = HashMap::new();
            for (generation, (key, triangles, remove)) in ops.into_iter().enumerate() {
                let k = IVec3::new(key, 0, 0);
                let diff = if remove {
                    live.remove(&key);
                    MeshDiff { removed: vec![k], ..MeshDiff::default() }
                } else {
                    if triangles > 0 { live.insert(key, (generation as u32, triangles)); } else { live.remove(&key); }
                    MeshDiff { upserted: vec![(k, chunk(key, generation as u32, triangles))], ..MeshDiff::default() }
                };
                arena.apply(&diff, &mut storage).unwrap();
                prop_assert_eq!(drawn(&arena, &storage), expected(&live));
                prop_assert_eq!(arena.triangles(), live.values().map(|v| v.1).sum::<usize>());
                prop_assert_eq!(arena.chunk_count(), live.len());
            }
        }
    }

    #[test]
    fn freed_space_is_reused_before_growing() {
        let mut arena = ChunkArena::new(300, 300);
        let mut s = Vecs::default();
        s.reserve(300, 300).unwrap();
        let grown = s.grown;
        for generation in 0..50 {
            let diff =
                MeshDiff { upserted: vec![(IVec3::ZERO, chunk(0, generation, 30))], ..MeshDiff::default() };
            arena.apply(&diff, &mut s).unwrap();
        }
        assert_eq!(s.grown, grown, "re-meshing one chunk in place never grows the arena");
        assert_eq!(arena.draw_count(), 90);
        let diff = MeshDiff { removed: vec![IVec3::ZERO], ..MeshDiff::default() };
        arena.apply(&diff, &mut s).unwrap();
        assert_eq!((arena.draw_count(), arena.triangles()), (0, 0));
    }
}
