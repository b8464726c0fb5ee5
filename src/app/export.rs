//! `argile export`: a scene's final clay as a mesh file.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::playback::Playback;
use super::sculpt::{is_sculpt, load_sculpt};
use crate::field::Field;
use crate::io::write_atomically;
use crate::mesh::export::{write_mesh, ExportFormat};
use crate::mesh::{mesh_all, weld, WeldedMesh};
use crate::scene::Scene;

/// What an export wrote.
#[derive(Clone, Debug)]
pub struct ExportSummary {
    /// The file.
    pub path: PathBuf,
    /// Welded vertices.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Bytes written.
    pub bytes: u64,
}

/// The end of `scene`'s timeline: its last key or capture, seconds.
pub(super) fn end_s(scene: &Scene) -> f32 {
    scene.captures.iter().map(|c| c.time_s).fold(scene.timeline.duration_s(), f32::max)
}

/// `scene`'s surface at the end of its timeline (after its last key and capture): its clay,
/// or the composition of its parts.
pub fn final_field(scene: &Scene) -> Field {
    played_to_end(Playback::new(scene))
}

/// The clay of `playback` at the end of its scene's timeline.
fn played_to_end(mut playback: Playback<'_>) -> Field {
    playback.advance_to(end_s(playback.scene()), |_| {});
    playback.into_surface()
}

/// The surface of `field`, welded into one indexed mesh; chunks in key order, so the same
/// clay gives the same file.
pub fn welded_surface(field: &Field) -> WeldedMesh {
    let mut diff = mesh_all(field);
    diff.upserted.sort_unstable_by_key(|(k, _)| k.to_array());
    weld(diff.upserted.iter().map(|(_, m)| m))
}

/// The surface of `scene`'s clay at the end of its timeline.
pub fn final_mesh(scene: &Scene) -> WeldedMesh {
    welded_surface(&final_field(scene))
}

/// Exports `input` as `format` to `out` (refusing to replace a file unless `overwrite`), with
/// a progress bar when `progress`. `input` is a scene file (its clay at the end of its
/// timeline) or a saved sculpt (`.argile`).
pub fn export(
    input: &Path,
    format: ExportFormat,
    out: &Path,
    overwrite: bool,
    progress: bool,
) -> Result<ExportSummary> {
    // Checked here too (`write_atomically` checks again) so a refused export costs no meshing.
    if !overwrite && out.exists() {
        bail!("{} already exists; pass --force to replace it", out.display());
    }
    let mesh = if is_sculpt(input) {
        let surface = super::assembly::sculpt_surface(load_sculpt(input)?)
            .with_context(|| format!("{}: a part's layout cannot be placed", input.display()))?;
        welded_surface(&surface)
    } else {
        let scene = Scene::load(input)?;
        welded_surface(&played_to_end(Playback::build(&scene)?))
    };
    if mesh.indices.is_empty() {
        bail!(
            "{}: the clay has no surface at the end of the timeline; there is nothing to export",
            input.display()
        );
    }
    let bar = if progress { indicatif::ProgressBar::new(1000) } else { indicatif::ProgressBar::hidden() };
    bar.set_message(format!("writing {}", out.display()));
    write_atomically(out, overwrite, |w| {
        write_mesh(format, &mesh, w, &mut |f| bar.set_position((f * 1000.0) as u64))
            .with_context(|| format!("cannot write {}", out.display()))
    })?;
    bar.finish_and_clear();
    let bytes = std::fs::metadata(out).map(|m| m.len()).unwrap_or(0);
    Ok(ExportSummary {
        path: out.to_path_buf(),
        vertices: mesh.positions.len(),
        triangles: mesh.triangle_count(),
        bytes,
    })
}
