//! The mesher's output: plain values that the renderer uploads and the exporters write.

use crate::math::{Aabb, IVec3, Vec3};

/// One mesh vertex as the renderer consumes it (`#[repr(C)]`, 40 bytes).
///
/// `normal` is the normalised negated field gradient: it points out of the clay, towards
/// lower density. `colour` is linear RGBA.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    /// World position in metres.
    pub position: [f32; 3],
    /// Unit outward normal.
    pub normal: [f32; 3],
    /// Linear RGBA colour.
    pub colour: [f32; 4],
}

/// Key of a mesh chunk: the key of the field brick it was extracted from.
pub type ChunkKey = IVec3;

/// The triangles extracted from one brick: indexed, counter-clockwise seen from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ChunkMesh {
    /// Vertices, shared by the triangles of this chunk.
    pub vertices: Vec<Vertex>,
    /// Three indices per triangle into `vertices`.
    pub indices: Vec<u32>,
}

impl ChunkMesh {
    /// Empties the mesh, keeping its allocations for reuse.
    pub fn reset(&mut self) {
        self.vertices.clear();
        self.indices.clear();
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Whether the chunk holds no triangle.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Bounding box of the vertices ([`Aabb::EMPTY`] for an empty chunk).
    pub fn bounds(&self) -> Aabb {
        self.vertices.iter().fold(Aabb::EMPTY, |b, v| b.grown_by_point(Vec3::from(v.position)))
    }
}

impl MeshDiff {
    /// The bounds of the upserted chunks (of the whole surface, for a full extraction).
    pub fn upserted_bounds(&self) -> Aabb {
        self.upserted.iter().fold(Aabb::EMPTY, |b, (_, c)| b.union(&c.bounds()))
    }
}

/// What changed in the surface since the last diff: the renderer applies it to its chunk
/// buffers. A key appears at most once, in one of the two lists.
#[derive(Clone, Debug, Default)]
pub struct MeshDiff {
    /// Chunks that are new or whose triangles changed, with their whole new mesh.
    pub upserted: Vec<(ChunkKey, ChunkMesh)>,
    /// Chunks that no longer hold any triangle.
    pub removed: Vec<ChunkKey>,
}

impl MeshDiff {
    /// Whether the diff changes nothing.
    pub fn is_empty(&self) -> bool {
        self.upserted.is_empty() && self.removed.is_empty()
    }

    /// Triangles in the upserted chunks.
    pub fn upserted_triangles(&self) -> usize {
        self.upserted.iter().map(|(_, m)| m.triangle_count()).sum()
    }
}

/// What the views judge of the surface without its triangles — how far it reaches and where it
/// is near the pictures' edges: each chunk's bounds and a few of its vertices, kept up to date
/// from the diffs the renderer applies.
#[derive(Clone, Debug, Default)]
pub struct SurfaceSketch {
    chunks: std::collections::HashMap<ChunkKey, (Aabb, Vec<Vec3>)>,
}

impl SurfaceSketch {
    /// Vertices kept of each chunk, evenly spread through its vertex list (which the mesher
    /// writes cell by cell, so they spread over the chunk's surface).
    pub const POINTS_PER_CHUNK: usize = 32;

    /// Takes in what `diff` changes.
    pub fn apply(&mut self, diff: &MeshDiff) {
        for key in &diff.removed {
            self.chunks.remove(key);
        }
        for (key, chunk) in &diff.upserted {
            let step = chunk.vertices.len().div_ceil(Self::POINTS_PER_CHUNK).max(1);
            let points = chunk.vertices.iter().step_by(step).map(|v| Vec3::from(v.position)).collect();
            self.chunks.insert(*key, (chunk.bounds(), points));
        }
    }

    /// Forgets the surface (a new one follows in whole).
    pub fn clear(&mut self) {
        self.chunks.clear();
    }

    /// The surface's bounds ([`Aabb::EMPTY`] for none).
    pub fn bounds(&self) -> Aabb {
        self.chunks.values().fold(Aabb::EMPTY, |b, (c, _)| b.union(c))
    }

    /// The kept vertices, every chunk's.
    pub fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.chunks.values().flat_map(|(_, p)| p.iter().copied())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chunk(vertices: usize, at: f32) -> ChunkMesh {
        ChunkMesh {
            vertices: (0..vertices)
                .map(|i| Vertex { position: [at, i as f32, 0.0], ..Default::default() })
                .collect(),
            indices: vec![0, 1, 2],
        }
    }

    #[test]
    fn the_sketch_follows_the_diffs_and_keeps_a_bounded_spread_of_vertices() {
        let mut sketch = SurfaceSketch::default();
        let (a, b) = (IVec3::ZERO, IVec3::X);
        sketch.apply(&MeshDiff { upserted: vec![(a, chunk(100, 0.0)), (b, chunk(5, 1.0))], removed: vec![] });
        assert_eq!(sketch.points().filter(|p| p.x == 0.0).count(), 25, "every 4th of 100");
        assert_eq!(sketch.points().filter(|p| p.x == 1.0).count(), 5);
        let ys: Vec<f32> = sketch.points().filter(|p| p.x == 0.0).map(|p| p.y).collect();
        assert!(ys.contains(&0.0) && ys.iter().any(|&y| y >= 96.0), "spread over the list");
        assert_eq!(sketch.bounds(), Aabb { min: Vec3::ZERO, max: Vec3::new(1.0, 99.0, 0.0) });
        sketch.apply(&MeshDiff { upserted: vec![(b, chunk(3, 2.0))], removed: vec![a] });
        assert_eq!(sketch.points().count(), 3);
        assert_eq!(sketch.bounds(), Aabb { min: Vec3::new(2.0, 0.0, 0.0), max: Vec3::new(2.0, 2.0, 0.0) });
        sketch.clear();
        assert!(sketch.bounds().is_empty() && sketch.points().next().is_none());
    }
}
