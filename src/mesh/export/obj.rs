//! Wavefront OBJ: `v` positions in millimetres, `vn` normals, `f a//a b//b c//c` triangles.

use std::io::Write;

use super::{report, MILLIMETRES_PER_METRE};
use crate::mesh::WeldedMesh;

pub(super) fn write(
    mesh: &WeldedMesh,
    out: &mut dyn Write,
    progress: &mut dyn FnMut(f32),
) -> std::io::Result<()> {
    writeln!(
        out,
        "# Argile sculpt: {} vertices, {} triangles; units: millimetres",
        mesh.positions.len(),
        mesh.triangle_count()
    )?;
    let total = mesh.positions.len() + mesh.triangle_count();
    for (i, p) in mesh.positions.iter().enumerate() {
        let [x, y, z] = p.map(|c| c * MILLIMETRES_PER_METRE);
        writeln!(out, "v {x} {y} {z}")?;
        report(progress, i, total, 0.0, 1.0);
    }
    for [x, y, z] in &mesh.normals {
        writeln!(out, "vn {x} {y} {z}")?;
    }
    for (i, t) in mesh.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [t[0] + 1, t[1] + 1, t[2] + 1];
        writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}")?;
        report(progress, mesh.positions.len() + i, total, 0.0, 1.0);
    }
    Ok(())
}
