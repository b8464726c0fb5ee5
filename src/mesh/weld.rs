//! Welding chunk meshes into one indexed mesh.
//!
//! The seam contract (module docs of `mesh`) makes a vertex shared by two bricks bit-identical
//! in both, so welding by exact position joins the chunks into one closed surface, with no
//! tolerance to choose and no vertex merged that should not be.

use std::collections::HashMap;
use std::sync::Arc;

use super::types::{ChunkKey, ChunkMesh, MeshDiff};
use crate::math::{Aabb, Vec3};

/// The surface's triangles chunk by chunk, kept up to date from the diffs the renderer
/// applies. Each chunk is shared, so a copy of the whole costs a pointer per chunk: an export
/// takes one and welds and writes it away from the frame, while the clay goes on changing.
#[derive(Clone, Debug, Default)]
pub struct SurfaceMeshes {
    chunks: HashMap<ChunkKey, Arc<ChunkMesh>>,
}

impl SurfaceMeshes {
    /// Takes in what `diff` changes.
    pub fn apply(&mut self, diff: &MeshDiff) {
        for key in &diff.removed {
            self.chunks.remove(key);
        }
        for (key, chunk) in &diff.upserted {
            self.chunks.insert(*key, Arc::new(chunk.clone()));
        }
    }

    /// Triangles in all chunks.
    pub fn triangle_count(&self) -> usize {
        self.chunks.values().map(|c| c.triangle_count()).sum()
    }

    /// The chunks welded into one mesh, in key order (as [`weld`] of a whole field's chunks
    /// sorted by key: the same clay gives the same mesh).
    pub fn weld(&self) -> WeldedMesh {
        let mut keys: Vec<&ChunkKey> = self.chunks.keys().collect();
        keys.sort_unstable_by_key(|k| k.to_array());
        weld(keys.into_iter().map(|k| self.chunks[k].as_ref()))
    }
}

/// An indexed triangle mesh: per-vertex position (metres), unit normal and linear RGBA colour;
/// three indices per triangle, counter-clockwise seen from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WeldedMesh {
    /// Positions, metres.
    pub positions: Vec<[f32; 3]>,
    /// Unit outward normals.
    pub normals: Vec<[f32; 3]>,
    /// Linear RGBA colours.
    pub colours: Vec<[f32; 4]>,
    /// Three vertex indices per triangle.
    pub indices: Vec<u32>,
}

impl WeldedMesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Bounding box of the vertices ([`Aabb::EMPTY`] for an empty mesh).
    pub fn bounds(&self) -> Aabb {
        self.positions.iter().fold(Aabb::EMPTY, |b, p| b.grown_by_point(Vec3::from(*p)))
    }
}

/// Welds chunks by exact vertex position, in the order given (pass chunks in a fixed order,
/// e.g. sorted by key, for reproducible files).
pub fn weld<'a>(chunks: impl IntoIterator<Item = &'a ChunkMesh>) -> WeldedMesh {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let mut mesh = WeldedMesh::default();
    let mut map = Vec::new();
    for chunk in chunks {
        map.clear();
        for v in &chunk.vertices {
            let id = *ids.entry(v.position.map(f32::to_bits)).or_insert_with(|| {
                mesh.positions.push(v.position);
                mesh.normals.push(v.normal);
                mesh.colours.push(v.colour);
                (mesh.positions.len() - 1) as u32
            });
            map.push(id);
        }
        mesh.indices.extend(chunk.indices.iter().map(|&i| map[i as usize]));
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Vertex;

    fn vertex(p: [f32; 3]) -> Vertex {
        Vertex { position: p, normal: [0.0, 0.0, 1.0], colour: [1.0; 4] }
    }

    #[test]
    fn shared_positions_become_one_vertex() {
        // Two chunks each holding one triangle of a quad; the diagonal is shared.
        let a = ChunkMesh {
            vertices: vec![vertex([0.0, 0.0, 0.0]), vertex([1.0, 0.0, 0.0]), vertex([1.0, 1.0, 0.0])],
            indices: vec![0, 1, 2],
        };
        let b = ChunkMesh {
            vertices: vec![vertex([1.0, 1.0, 0.0]), vertex([0.0, 1.0, 0.0]), vertex([0.0, 0.0, 0.0])],
            indices: vec![0, 1, 2],
        };
        let m = weld([&a, &b]);
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.indices, vec![0, 1, 2, 2, 3, 0]);
        assert_eq!(m.triangle_count(), 2);
        assert_eq!(m.bounds().max, Vec3::new(1.0, 1.0, 0.0));
    }
}
