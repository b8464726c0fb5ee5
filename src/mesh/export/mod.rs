//! Writing a welded mesh in the formats other tools read.
//!
//! | format | file | units | contents |
//! |---|---|---|---|
//! | [`ExportFormat::Obj`] | text | millimetres | positions, normals, triangles |
//! | [`ExportFormat::Ply`] | binary little-endian | metres | positions, normals, 8-bit sRGB colours, triangles |
//! | [`ExportFormat::Stl`] | binary | millimetres | facet normals and corners (watertight when the sculpt is closed) |
//! | [`ExportFormat::Glb`] | glTF 2.0 binary | metres | `POSITION` (with min/max), `NORMAL`, `COLOR_0` (linear), `u32` indices |
//!
//! STL and OBJ carry no unit of their own; millimetres are what slicers and CAD tools assume.
//! Writers take any `Write` (the caller buffers and makes the write atomic) and report progress
//! as a fraction in [0, 1].

mod glb;
mod obj;
mod ply;
mod stl;

use std::io::Write;

use super::weld::WeldedMesh;

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ExportFormat {
    /// Wavefront OBJ with normals, millimetres.
    Obj,
    /// Binary PLY with normals and vertex colours, metres.
    Ply,
    /// Binary STL, millimetres.
    Stl,
    /// glTF 2.0 binary, metres.
    Glb,
}

impl ExportFormat {
    /// Every format, in the order offered.
    pub const ALL: [ExportFormat; 4] =
        [ExportFormat::Obj, ExportFormat::Ply, ExportFormat::Stl, ExportFormat::Glb];

    /// The format whose extension `path` has (any case), if one has.
    pub fn of_path(path: &std::path::Path) -> Option<ExportFormat> {
        let ext = path.extension()?.to_str()?;
        Self::ALL.into_iter().find(|f| f.extension().eq_ignore_ascii_case(ext))
    }

    /// The usual file extension.
    pub fn extension(self) -> &'static str {
        match self {
            ExportFormat::Obj => "obj",
            ExportFormat::Ply => "ply",
            ExportFormat::Stl => "stl",
            ExportFormat::Glb => "glb",
        }
    }
}

/// A part's mesh in its own frame (metres) and where the part sits: its vertex `v` is at
/// `translation + rotation · (scale · v)` in the world.
#[derive(Clone, Copy, Debug)]
pub struct PartMesh<'a> {
    /// The part's name.
    pub name: &'a str,
    /// Its surface, welded.
    pub mesh: &'a WeldedMesh,
    /// Its uniform scale.
    pub scale: f32,
    /// Its turn (quaternion x, y, z, w).
    pub rotation: [f32; 4],
    /// Where its origin sits, metres.
    pub translation_m: [f32; 3],
}

/// Writes each of `parts` as its own mesh: a GLB node per part with its placement, an OBJ
/// object per part placed in the world. PLY and STL hold one mesh and are refused.
pub fn write_parts(
    format: ExportFormat,
    parts: &[PartMesh<'_>],
    out: &mut dyn Write,
    progress: &mut dyn FnMut(f32),
) -> std::io::Result<()> {
    match format {
        ExportFormat::Glb => glb::write_parts(parts, out, progress),
        ExportFormat::Obj => obj::write_parts(parts, out, progress),
        ExportFormat::Ply | ExportFormat::Stl => Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "a {} file holds one mesh: export the parts separately as glb or obj",
                format.extension()
            ),
        )),
    }
}

/// Metres to the millimetres of OBJ and STL files.
pub const MILLIMETRES_PER_METRE: f32 = 1000.0;

/// Writes `mesh` in `format`, calling `progress` with the fraction done now and then.
pub fn write_mesh(
    format: ExportFormat,
    mesh: &WeldedMesh,
    out: &mut dyn Write,
    progress: &mut dyn FnMut(f32),
) -> std::io::Result<()> {
    match format {
        ExportFormat::Obj => obj::write(mesh, out, progress),
        ExportFormat::Ply => ply::write(mesh, out, progress),
        ExportFormat::Stl => stl::write(mesh, out, progress),
        ExportFormat::Glb => glb::write(mesh, out, progress),
    }?;
    progress(1.0);
    Ok(())
}

/// Items between two progress reports.
const PROGRESS_EVERY: usize = 1 << 16;

/// Calls `progress` every [`PROGRESS_EVERY`] items of `total` (the first `share` of the work).
fn report(progress: &mut dyn FnMut(f32), done: usize, total: usize, start: f32, share: f32) {
    if done % PROGRESS_EVERY == 0 && total > 0 {
        progress(start + share * done as f32 / total as f32);
    }
}

/// Linear to 8-bit sRGB.
fn srgb8(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_encoding_hits_the_ends_and_the_middle_grey() {
        assert_eq!(srgb8(0.0), 0);
        assert_eq!(srgb8(1.0), 255);
        assert_eq!(srgb8(0.2159), 128, "sRGB 128 is linear 0.2159");
        assert_eq!(srgb8(-1.0), 0);
        assert_eq!(srgb8(f32::NAN), 0);
    }
}
