//! `argile export`: a scene's final clay as a mesh file.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

use anyhow::{anyhow, bail, Context, Result};

use super::playback::Playback;
use super::sculpt::{is_sculpt, load_sculpt, with_lattice_applied};
use crate::field::Field;
use crate::io::write_atomically;
use crate::mesh::export::{write_mesh, write_parts, ExportFormat, PartMesh};
use crate::mesh::{mesh_all, weld, MeshDiff, SurfaceMeshes, WeldedMesh};
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

/// `scene`'s surface at the end of its timeline (after its last key and capture, its tools
/// let go: see [`Playback::let_go`]): its clay, or the composition of its parts.
pub fn final_field(scene: &Scene) -> Field {
    played_to_end(Playback::new(scene))
}

/// The clay of `playback` at the end of its scene's timeline.
fn played_to_end(mut playback: Playback<'_>) -> Field {
    playback.advance_to(playback.scene().end_s(), |_| {});
    playback.let_go();
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
    export_as(input, format, PartsExport::Composed, out, overwrite, progress)
}

/// How a sculpt of parts is exported.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum PartsExport {
    /// The composition, one mesh: what the station draws.
    #[default]
    Composed,
    /// One mesh per visible part, in its own frame, with its placement (a GLB node per part; an
    /// OBJ object per part, placed in the world).
    Separate,
}

/// [`export`], with the parts of a sculpt of parts composed or each its own mesh.
pub fn export_as(
    input: &Path,
    format: ExportFormat,
    parts: PartsExport,
    out: &Path,
    overwrite: bool,
    progress: bool,
) -> Result<ExportSummary> {
    // Checked here too (`write_atomically` checks again) so a refused export costs no meshing.
    if !overwrite && out.exists() {
        bail!("{} already exists; pass --force to replace it", out.display());
    }
    if parts == PartsExport::Separate {
        return export_parts(input, format, out, overwrite, progress);
    }
    let mesh = if is_sculpt(input) {
        let surface = super::assembly::sculpt_surface(with_lattice_applied(load_sculpt(input)?, input)?)
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
    write_welded(&mesh, format, out, overwrite, progress)
}

/// Exports the surface `field` as `format` to `out` (replacing it when `overwrite`): what the
/// station exports of the sculpt as it stands.
pub fn export_surface(
    field: &Field,
    format: ExportFormat,
    out: &Path,
    overwrite: bool,
) -> Result<ExportSummary> {
    if !overwrite && out.exists() {
        bail!("{} already exists", out.display());
    }
    let mesh = welded_surface(field);
    if mesh.indices.is_empty() {
        bail!("the clay has no surface: nothing to export to {}", out.display());
    }
    write_welded(&mesh, format, out, overwrite, false)
}

/// Writes `mesh` as `format` to `out`.
fn write_welded(
    mesh: &WeldedMesh,
    format: ExportFormat,
    out: &Path,
    overwrite: bool,
    progress: bool,
) -> Result<ExportSummary> {
    let bytes = write_with_progress(out, overwrite, progress, |w, p| write_mesh(format, mesh, w, p))?;
    Ok(ExportSummary {
        path: out.to_path_buf(),
        vertices: mesh.positions.len(),
        triangles: mesh.triangle_count(),
        bytes,
    })
}

/// Writes each visible part of `input`'s sculpt as its own mesh (see [`PartsExport::Separate`]).
fn export_parts(
    input: &Path,
    format: ExportFormat,
    out: &Path,
    overwrite: bool,
    progress: bool,
) -> Result<ExportSummary> {
    if matches!(format, ExportFormat::Ply | ExportFormat::Stl) {
        bail!("a {} file holds one mesh: export the parts separately as glb or obj", format.extension());
    }
    let (layouts, fields): (Vec<crate::scene::ScenePart>, Vec<Field>) = if is_sculpt(input) {
        let sculpt = with_lattice_applied(load_sculpt(input)?, input)?;
        let parts = super::assembly::parts_of(&sculpt)
            .with_context(|| format!("{}: a part's layout cannot be placed", input.display()))?;
        (parts, std::iter::once(sculpt.field).chain(sculpt.others).collect())
    } else {
        let scene = Scene::load(input)?;
        let mut playback = Playback::build(&scene)?;
        playback.advance_to(scene.end_s(), |_| {});
        playback.let_go();
        let parts = playback.assembly().parts().to_vec();
        let (first, _, others) = playback.into_parts();
        (parts, std::iter::once(first).chain(others).collect())
    };
    let meshes: Vec<(usize, WeldedMesh)> = layouts
        .iter()
        .zip(&fields)
        .enumerate()
        .filter(|(_, (layout, _))| layout.visible)
        .map(|(i, (_, field))| (i, welded_surface(field)))
        .filter(|(_, mesh)| !mesh.indices.is_empty())
        .collect();
    if meshes.is_empty() {
        bail!("{}: no visible part has a surface; there is nothing to export", input.display());
    }
    let parts: Vec<PartMesh<'_>> = meshes
        .iter()
        .map(|(i, mesh)| {
            let p = &layouts[*i].placement;
            PartMesh {
                name: &layouts[*i].name,
                mesh,
                scale: p.scale,
                rotation: p.rotation.to_array(),
                translation_m: p.translation_m.to_array(),
            }
        })
        .collect();
    let bytes = write_with_progress(out, overwrite, progress, |w, p| write_parts(format, &parts, w, p))?;
    Ok(ExportSummary {
        path: out.to_path_buf(),
        vertices: meshes.iter().map(|(_, m)| m.positions.len()).sum(),
        triangles: meshes.iter().map(|(_, m)| m.triangle_count()).sum(),
        bytes,
    })
}

/// Writes `out` atomically with `write`, with a progress bar on the terminal when `progress`;
/// returns the bytes written.
fn write_with_progress(
    out: &Path,
    overwrite: bool,
    progress: bool,
    write: impl FnOnce(&mut dyn std::io::Write, &mut dyn FnMut(f32)) -> std::io::Result<()>,
) -> Result<u64> {
    let bar = if progress { indicatif::ProgressBar::new(1000) } else { indicatif::ProgressBar::hidden() };
    bar.set_message(format!("writing {}", out.display()));
    let bytes = write_reporting(out, overwrite, &mut |f| bar.set_position((f * 1000.0) as u64), write)?;
    bar.finish_and_clear();
    Ok(bytes)
}

/// Writes `out` atomically with `write`, which tells `report` how far it is (0 to 1); returns
/// the bytes written.
fn write_reporting(
    out: &Path,
    overwrite: bool,
    report: &mut dyn FnMut(f32),
    write: impl FnOnce(&mut dyn std::io::Write, &mut dyn FnMut(f32)) -> std::io::Result<()>,
) -> Result<u64> {
    write_atomically(out, overwrite, |w| {
        write(w, report).with_context(|| format!("cannot write {}", out.display()))
    })?;
    Ok(std::fs::metadata(out).map(|m| m.len()).unwrap_or(0))
}

/// The share of an export's progress that welding takes; writing takes the rest.
const WELD_SHARE: f32 = 0.2;

/// An export of the surface as it stood when it started, welded and written on a thread of its
/// own so that the frames go on; its progress can be read while it runs. Dropped, it waits for
/// the file to be written.
#[derive(Debug)]
pub struct ExportJob {
    path: PathBuf,
    triangles: usize,
    /// Thousandths done.
    progress: Arc<AtomicU32>,
    thread: Option<std::thread::JoinHandle<Result<ExportSummary>>>,
}

impl ExportJob {
    /// Starts writing `surface` to `path` (replacing it), in the format its extension names.
    /// `Err` says why it cannot start: an extension the export does not know, or no surface.
    pub fn start(surface: SurfaceMeshes, path: &Path) -> Result<Self, String> {
        let Some(format) = ExportFormat::of_path(path) else {
            return Err(format!(
                "{}: not an extension the export knows (obj, ply, stl, glb)",
                path.display()
            ));
        };
        let triangles = surface.triangle_count();
        if triangles == 0 {
            return Err(format!("the clay has no surface: nothing to export to {}", path.display()));
        }
        let progress = Arc::new(AtomicU32::new(0));
        let (out, done) = (path.to_path_buf(), progress.clone());
        let thread = std::thread::Builder::new()
            .name("argile-export".into())
            .spawn(move || {
                let set = |f: f32| done.store((f.clamp(0.0, 1.0) * 1000.0) as u32, Ordering::Relaxed);
                let mesh = surface.weld();
                drop(surface);
                set(WELD_SHARE);
                let bytes = write_reporting(
                    &out,
                    true,
                    &mut |f| set(WELD_SHARE + (1.0 - WELD_SHARE) * f),
                    |w, p| write_mesh(format, &mesh, w, p),
                )?;
                set(1.0);
                Ok(ExportSummary {
                    path: out,
                    vertices: mesh.positions.len(),
                    triangles: mesh.triangle_count(),
                    bytes,
                })
            })
            .map_err(|e| format!("cannot start writing {}: {e}", path.display()))?;
        Ok(Self { path: path.to_path_buf(), triangles, progress, thread: Some(thread) })
    }

    /// The file it writes.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// How far it is, 0 to 1.
    pub fn progress(&self) -> f32 {
        self.progress.load(Ordering::Relaxed) as f32 / 1000.0
    }

    /// What it wrote (or why not) once it has finished; `None` while it runs.
    pub fn finished(&mut self) -> Option<Result<ExportSummary>> {
        if !self.thread.as_ref().is_some_and(|t| t.is_finished()) {
            return None;
        }
        self.thread.take().map(Self::joined)
    }

    fn joined(thread: std::thread::JoinHandle<Result<ExportSummary>>) -> Result<ExportSummary> {
        thread.join().unwrap_or_else(|_| Err(anyhow!("the export thread failed")))
    }
}

impl Drop for ExportJob {
    fn drop(&mut self) {
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// A station's exports: the surface as the renderer holds it, and the export under way.
#[derive(Debug, Default)]
pub struct Exports {
    surface: SurfaceMeshes,
    job: Option<ExportJob>,
}

impl Exports {
    /// Takes in what `diff` changes of the surface.
    pub fn apply(&mut self, diff: &MeshDiff) {
        self.surface.apply(diff);
    }

    /// The surface as the renderer holds it.
    #[cfg(test)]
    pub(crate) fn surface(&self) -> &SurfaceMeshes {
        &self.surface
    }

    /// Starts exporting the surface as it stands to `path`; says so, or why not (one export
    /// at a time).
    pub fn start(&mut self, path: &Path) -> String {
        if let Some(job) = &self.job {
            return format!(
                "an export to {} is under way ({:.0} %): one at a time",
                job.path().display(),
                100.0 * job.progress()
            );
        }
        match ExportJob::start(self.surface.clone(), path) {
            Ok(job) => {
                let said = format!("exporting {} triangles to {}", job.triangles, path.display());
                self.job = Some(job);
                said
            }
            Err(why) => why,
        }
    }

    /// What the export under way says now ("exporting NAME: 40 %"), if one is.
    pub fn status(&self) -> Option<String> {
        self.job.as_ref().map(|job| {
            let name = job
                .path()
                .file_name()
                .map_or_else(|| job.path().display().to_string(), |n| n.to_string_lossy().into());
            format!("exporting {name}: {:.0} %", 100.0 * job.progress())
        })
    }

    /// Once the export under way has finished, what it did.
    pub fn poll(&mut self) -> Option<String> {
        let done = self.job.as_mut()?.finished()?;
        self.job = None;
        Some(match done {
            Ok(done) => format!(
                "exported {} triangles ({} vertices) to {}",
                done.triangles,
                done.vertices,
                done.path.display()
            ),
            Err(e) => format!("{e:#}"),
        })
    }
}
