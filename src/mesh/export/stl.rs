//! Binary STL: an 80-byte header, the triangle count, then per triangle its unit facet normal,
//! its three corners (millimetres, counter-clockwise seen from outside) and a zero attribute.

use std::io::Write;

use super::{report, MILLIMETRES_PER_METRE};
use crate::math::Vec3;
use crate::mesh::WeldedMesh;

pub(super) fn write(
    mesh: &WeldedMesh,
    out: &mut dyn Write,
    progress: &mut dyn FnMut(f32),
) -> std::io::Result<()> {
    let mut header = [b' '; 80];
    let text = b"Argile sculpt, binary STL, units: millimetres";
    header[..text.len()].copy_from_slice(text);
    out.write_all(&header)?;
    let count = u32::try_from(mesh.triangle_count()).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "more triangles than binary STL can count (2^32)",
        )
    })?;
    out.write_all(&count.to_le_bytes())?;
    let mut record = [0u8; 50];
    for (i, t) in mesh.indices.chunks_exact(3).enumerate() {
        let corners =
            [t[0], t[1], t[2]].map(|k| Vec3::from(mesh.positions[k as usize]) * MILLIMETRES_PER_METRE);
        let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalize_or_zero();
        for (slot, v) in std::iter::once(normal).chain(corners).enumerate() {
            for (axis, c) in v.to_array().iter().enumerate() {
                let at = 12 * slot + 4 * axis;
                record[at..at + 4].copy_from_slice(&c.to_le_bytes());
            }
        }
        out.write_all(&record)?;
        report(progress, i, mesh.triangle_count(), 0.0, 1.0);
    }
    Ok(())
}
