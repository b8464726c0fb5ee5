//! Binary little-endian PLY: positions (metres) and normals as `float`, colours as 8-bit sRGB
//! `uchar` RGBA, faces as `list uchar uint`.

use std::io::Write;

use super::{report, srgb8};
use crate::mesh::WeldedMesh;

pub(super) fn write(
    mesh: &WeldedMesh,
    out: &mut dyn Write,
    progress: &mut dyn FnMut(f32),
) -> std::io::Result<()> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment Argile sculpt; units: metres; colours: sRGB\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n\
         element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangle_count()
    );
    out.write_all(header.as_bytes())?;
    let total = mesh.positions.len() + mesh.triangle_count();
    let mut record = Vec::with_capacity(28);
    for (i, ((p, n), c)) in mesh.positions.iter().zip(&mesh.normals).zip(&mesh.colours).enumerate() {
        record.clear();
        for v in p.iter().chain(n) {
            record.extend_from_slice(&v.to_le_bytes());
        }
        record.extend([srgb8(c[0]), srgb8(c[1]), srgb8(c[2]), (c[3].clamp(0.0, 1.0) * 255.0 + 0.5) as u8]);
        out.write_all(&record)?;
        report(progress, i, total, 0.0, 1.0);
    }
    for (i, t) in mesh.indices.chunks_exact(3).enumerate() {
        record.clear();
        record.push(3);
        for v in t {
            record.extend_from_slice(&v.to_le_bytes());
        }
        out.write_all(&record)?;
        report(progress, mesh.positions.len() + i, total, 0.0, 1.0);
    }
    Ok(())
}
