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
