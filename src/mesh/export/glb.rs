//! glTF 2.0 binary (`.glb`): one mesh with one triangle primitive.
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
    if mesh.positions.is_empty() || mesh.indices.is_empty() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "a glTF mesh needs at least one triangle",
        ));
    }
    let n = mesh.positions.len();
    let views = [
        (bytemuck::cast_slice::<[f32; 3], u8>(&mesh.positions), ARRAY_BUFFER),
        (bytemuck::cast_slice::<[f32; 3], u8>(&mesh.normals), ARRAY_BUFFER),
        (bytemuck::cast_slice::<[f32; 4], u8>(&mesh.colours), ARRAY_BUFFER),
        (bytemuck::cast_slice::<u32, u8>(&mesh.indices), ELEMENT_ARRAY_BUFFER),
    ];
    let mut offsets = Vec::with_capacity(views.len());
    let mut length = 0usize;
    for (bytes, _) in &views {
        offsets.push(length);
        length += bytes.len().next_multiple_of(4);
    }
    let bounds = mesh.bounds();
    let json = json!({
        "asset": { "version": "2.0", "generator": concat!("Argile ", env!("CARGO_PKG_VERSION")) },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "name": "sculpt" }],
        "meshes": [{
            "name": "sculpt",
            "primitives": [{
                "attributes": { "POSITION": 0, "NORMAL": 1, "COLOR_0": 2 },
                "indices": 3,
                "mode": 4
            }]
        }],
        "buffers": [{ "byteLength": length }],
        "bufferViews": views.iter().zip(&offsets).map(|((bytes, target), offset)| json!({
            "buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": target
        })).collect::<Vec<_>>(),
        "accessors": [
            { "bufferView": 0, "componentType": FLOAT, "count": n, "type": "VEC3",
              "min": bounds.min.to_array(), "max": bounds.max.to_array() },
            { "bufferView": 1, "componentType": FLOAT, "count": n, "type": "VEC3" },
            { "bufferView": 2, "componentType": FLOAT, "count": n, "type": "VEC4" },
            { "bufferView": 3, "componentType": UNSIGNED_INT, "count": mesh.indices.len(), "type": "SCALAR" }
        ]
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
