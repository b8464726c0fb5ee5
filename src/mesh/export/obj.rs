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

/// One object (`o NAME`) per part, its vertices placed in the world.
pub(super) fn write_parts(
    parts: &[super::PartMesh<'_>],
    out: &mut dyn Write,
    progress: &mut dyn FnMut(f32),
) -> std::io::Result<()> {
    let vertices: usize = parts.iter().map(|p| p.mesh.positions.len()).sum();
    let triangles: usize = parts.iter().map(|p| p.mesh.triangle_count()).sum();
    writeln!(
        out,
        "# Argile sculpt of {} parts: {vertices} vertices, {triangles} triangles; units: millimetres",
        parts.len()
    )?;
    let mut base = 1;
    for (i, p) in parts.iter().enumerate() {
        let rotation = glam::Quat::from_array(p.rotation);
        let translation = glam::Vec3::from(p.translation_m);
        // The name on one line, whatever it holds.
        writeln!(out, "o {}", p.name.replace(['\n', '\r'], " "))?;
        for v in &p.mesh.positions {
            let w = (translation + rotation * (glam::Vec3::from(*v) * p.scale)) * MILLIMETRES_PER_METRE;
            writeln!(out, "v {} {} {}", w.x, w.y, w.z)?;
        }
        for n in &p.mesh.normals {
            let w = rotation * glam::Vec3::from(*n);
            writeln!(out, "vn {} {} {}", w.x, w.y, w.z)?;
        }
        for t in p.mesh.indices.chunks_exact(3) {
            let [a, b, c] = [t[0] + base, t[1] + base, t[2] + base];
            writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}")?;
        }
        base += p.mesh.positions.len() as u32;
        report(progress, i + 1, parts.len(), 0.0, 1.0);
    }
    Ok(())
}
