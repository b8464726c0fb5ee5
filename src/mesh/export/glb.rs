//! glTF 2.0 binary (`.glb`): one mesh with one triangle primitive, or one node per part, each
//! with its own mesh and its placement.
//!
//! ```text
//!  GLB header (magic "glTF", version 2, total length)
//!  JSON chunk (padded with spaces to 4 bytes)
//!  BIN chunk  (padded with zeros to 4 bytes):
//!    [positions f32×3][normals f32×3][colours f32×4][indices u32]   each view 4-byte aligned
//! ```
//!
//! Accessors carry `min`/`max` for positions (the validator requires it), colours are linear
//! (`COLOR_0` is linear in glTF), buffer views name their targets, lengths are exact.

use std::io::Write;

use serde_json::json;

use super::PartMesh;
use crate::mesh::WeldedMesh;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

pub(super) fn write(
    mesh: &WeldedMesh,
    out: &mut dyn Write,
    progress: &mut dyn FnMut(f32),
) -> std::io::Result<()> {
    let whole = PartMesh {
        name: "sculpt",
        mesh,
        scale: 1.0,
        rotation: [0.0, 0.0, 0.0, 1.0],
        translation_m: [0.0; 3],
    };
    write_parts(&[whole], out, progress)
}

/// One node per part, each with its mesh (in the part's own frame) and its placement as the
/// node's translation, rotation and scale.
pub(super) fn write_parts(
    parts: &[PartMesh<'_>],
    out: &mut dyn Write,
    progress: &mut dyn FnMut(f32),
) -> std::io::Result<()> {
    if parts.is_empty() || parts.iter().any(|p| p.mesh.positions.is_empty() || p.mesh.indices.is_empty()) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "a glTF mesh needs at least one triangle",
        ));
    }
    let mut views = Vec::with_capacity(4 * parts.len());
    for p in parts {
        let mesh = p.mesh;
        views.push((bytemuck::cast_slice::<[f32; 3], u8>(&mesh.positions), ARRAY_BUFFER));
        views.push((bytemuck::cast_slice::<[f32; 3], u8>(&mesh.normals), ARRAY_BUFFER));
        views.push((bytemuck::cast_slice::<[f32; 4], u8>(&mesh.colours), ARRAY_BUFFER));
        views.push((bytemuck::cast_slice::<u32, u8>(&mesh.indices), ELEMENT_ARRAY_BUFFER));
    }
    let mut offsets = Vec::with_capacity(views.len());
    let mut length = 0usize;
    for (bytes, _) in &views {
        offsets.push(length);
        length += bytes.len().next_multiple_of(4);
    }
    let mut accessors = Vec::with_capacity(views.len());
    let mut meshes = Vec::with_capacity(parts.len());
    let mut nodes = Vec::with_capacity(parts.len());
    for (i, p) in parts.iter().enumerate() {
        let (mesh, first) = (p.mesh, 4 * i);
        let (n, bounds) = (mesh.positions.len(), mesh.bounds());
        accessors.push(json!({ "bufferView": first, "componentType": FLOAT, "count": n, "type": "VEC3",
            "min": bounds.min.to_array(), "max": bounds.max.to_array() }));
        accessors
            .push(json!({ "bufferView": first + 1, "componentType": FLOAT, "count": n, "type": "VEC3" }));
        accessors
            .push(json!({ "bufferView": first + 2, "componentType": FLOAT, "count": n, "type": "VEC4" }));
        accessors.push(json!({ "bufferView": first + 3, "componentType": UNSIGNED_INT,
            "count": mesh.indices.len(), "type": "SCALAR" }));
        meshes.push(json!({
            "name": p.name,
            "primitives": [{
                "attributes": { "POSITION": first, "NORMAL": first + 1, "COLOR_0": first + 2 },
                "indices": first + 3,
                "mode": 4
            }]
        }));
        let mut node = json!({ "mesh": i, "name": p.name });
        if p.translation_m != [0.0; 3] {
            node["translation"] = json!(p.translation_m);
        }
        if p.rotation != [0.0, 0.0, 0.0, 1.0] {
            node["rotation"] = json!(p.rotation);
        }
        if p.scale != 1.0 {
            node["scale"] = json!([p.scale, p.scale, p.scale]);
        }
        nodes.push(node);
    }
    let json = json!({
        "asset": { "version": "2.0", "generator": concat!("Argile ", env!("CARGO_PKG_VERSION")) },
        "scene": 0,
        "scenes": [{ "nodes": (0..parts.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
        "buffers": [{ "byteLength": length }],
        "bufferViews": views.iter().zip(&offsets).map(|((bytes, target), offset)| json!({
            "buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": target
        })).collect::<Vec<_>>(),
        "accessors": accessors
    });
    let mut json_bytes = serde_json::to_vec(&json).map_err(std::io::Error::other)?;
    json_bytes.resize(json_bytes.len().next_multiple_of(4), b' ');
    let total = 12 + 8 + json_bytes.len() + 8 + length;
    let total = u32::try_from(total).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the mesh is larger than a GLB file can hold (4 GiB)",
        )
    })?;
    out.write_all(b"glTF")?;
    out.write_all(&2u32.to_le_bytes())?;
    out.write_all(&total.to_le_bytes())?;
    out.write_all(&(json_bytes.len() as u32).to_le_bytes())?;
    out.write_all(b"JSON")?;
    out.write_all(&json_bytes)?;
    out.write_all(&(length as u32).to_le_bytes())?;
    out.write_all(b"BIN\0")?;
    for (i, (bytes, _)) in views.iter().enumerate() {
        out.write_all(bytes)?;
        out.write_all(&[0; 3][..bytes.len().next_multiple_of(4) - bytes.len()])?;
        progress((i + 1) as f32 / views.len() as f32);
    }
    Ok(())
}
