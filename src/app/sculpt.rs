//! Saving a scene's sculpt in the native format and loading sculpts (see [`crate::io`]).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::autosave::start_autosave;
use super::playback::Playback;
use crate::field::{BRICK_SIZE, LEVELS};
use crate::io::autosave::AutosaveConfig;
use crate::io::write_atomically;
use crate::io::{
    encode_sculpt, read_file_within, EncodeOptions, LazySculpt, SceneParts, Sculpt, StoredView, VERSION,
};
use crate::math::{IVec3, Vec3};
use crate::scene::Scene;

/// The extension of sculpt files.
pub const SCULPT_EXTENSION: &str = "argile";

/// Whether `path` names a sculpt file (by its extension).
pub fn is_sculpt(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case(SCULPT_EXTENSION))
}

/// What a save wrote.
#[derive(Clone, Debug)]
pub struct SavedSculpt {
    /// The file.
    pub path: PathBuf,
    /// Bricks stored, on every level.
    pub bricks: usize,
    /// Bytes written.
    pub bytes: usize,
}

/// Plays the scene file `scene_path` to the end of its timeline and saves its clay, with the
/// scene's text, to `out` (atomically; an existing file only when `overwrite`). With
/// `autosave`, the strokes are journaled as they are played, and the session is closed once
/// `out` is written.
pub fn save_scene_sculpt(
    scene_path: &Path,
    out: &Path,
    overwrite: bool,
    autosave: Option<AutosaveConfig>,
) -> Result<SavedSculpt> {
    // Checked here too (`write_atomically` checks again) so a refused save costs no playback.
    if !overwrite && out.exists() {
        bail!("{} already exists; pass --force to replace it", out.display());
    }
    // Read once: the same text is parsed and stored.
    let text = crate::io::text::read_text(scene_path, crate::io::text::SCENE_LIMIT)
        .with_context(|| format!("cannot read scene file {}", scene_path.display()))?;
    let scene = Scene::parse(&text, &scene_path.display().to_string(), scene_path.parent())?;
    let source = scene_path.display().to_string();
    let mut playback = Playback::new_autosaved(&scene, |field, tools| {
        autosave.and_then(|config| start_autosave(field, (Some(&text), tools), &source, config))
    })?;
    let end = scene.end_s();
    // A stopping signal (handled where autosave runs) ends the timeline early: the sculpt as
    // far as it got is saved, and the session closed.
    if !playback.advance_until(end, |_| {}, || super::signals::received().is_some()) {
        println!(
            "{} received at {:.2} s of the timeline's {end:.2} s: saving the sculpt as far as it got",
            super::signals::received().map_or("a signal", super::signals::name),
            playback.time_s()
        );
    }
    playback.let_go();
    let session = playback.finish_autosave();
    let tools = playback.stored_tools();
    let (field, layouts, others) = playback.into_parts();
    let scene = SceneParts {
        toml: Some(&text),
        tools: &tools,
        view: None,
        layouts: &layouts,
        others: &others,
        lattice: None,
        symmetry: Some(&scene.symmetry),
    };
    let bytes = encode_sculpt(&field, scene, EncodeOptions::default(), &mut |_| {});
    write_atomically(out, overwrite, |w| {
        w.write_all(&bytes).with_context(|| format!("cannot write {}", out.display()))
    })?;
    if let Some(session) = session {
        super::autosave::close_session(session);
    }
    let bricks = all_bricks(&field) + others.iter().map(all_bricks).sum::<usize>();
    Ok(SavedSculpt { path: out.to_path_buf(), bricks, bytes: bytes.len() })
}

/// The bricks `field` stores, on every level.
fn all_bricks(field: &crate::field::Field) -> usize {
    (0..LEVELS).map(|l| field.level_brick_count(l)).sum()
}

/// Loads a sculpt file, refusing damaged, truncated, future-version or hostile files with a
/// sentence that names the file.
pub fn load_sculpt(path: &Path) -> Result<Sculpt> {
    load_sculpt_with_progress(path, false)
}

/// [`load_sculpt`], with a progress bar on the terminal when `progress`.
pub fn load_sculpt_with_progress(path: &Path, progress: bool) -> Result<Sculpt> {
    let bar = if progress { indicatif::ProgressBar::new(1000) } else { indicatif::ProgressBar::hidden() };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {percent}%")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(format!("loading {}", path.display()));
    // Read chunk by chunk: a large sculpt is never in memory twice.
    let limit = super::budget::sculpt_limit();
    let sculpt = read_file_within(path, &limit, &mut |f| bar.set_position((f * 1000.0) as u64));
    bar.finish_and_clear();
    Ok(sculpt?)
}

/// `sculpt` (read from `path`) with the lattice it holds open applied to its part's clay, as
/// the station shows it: for what only wants its shape (an export, a render).
pub fn with_lattice_applied(mut sculpt: Sculpt, path: &Path) -> Result<Sculpt> {
    let Some(stored) = sculpt.lattice.take() else { return Ok(sculpt) };
    let field = match stored.part {
        0 => &mut sculpt.field,
        p => sculpt.others.get_mut(p - 1).with_context(|| {
            format!("{}: its lattice lies over part {p}, which it has not", path.display())
        })?,
    };
    let mut held = super::held_lattice::HeldLattice::reopen(field, &stored)
        .with_context(|| format!("{}: its open lattice cannot be applied", path.display()))?;
    held.sync(field).with_context(|| format!("{}: its open lattice cannot be applied", path.display()))?;
    field.take_dirty();
    Ok(sculpt)
}

/// Opens a sculpt file for viewing or sculpting: its clay, and the scene to show it in — the
/// scene it was made in (its text is stored in the file), else the default scene — with that
/// scene's initial clay and timeline left out (the file's clay is their result); its camera,
/// lights, environment, tools and captures stay.
pub fn open_sculpt(path: &Path) -> Result<(Scene, Sculpt)> {
    let sculpt = load_sculpt_with_progress(path, true)?;
    let mut scene = match &sculpt.scene_toml {
        Some(text) => {
            let name = format!("{} (the scene stored in it)", path.display());
            Scene::parse(text, &name, path.parent())?
        }
        None => Scene::default_scene(),
    };
    scene.source = path.display().to_string();
    scene.parts = super::assembly::parts_of(&sculpt)
        .with_context(|| format!("{}: a part's layout cannot be placed", path.display()))?;
    scene.clay.clear();
    scene.timeline = crate::scene::Timeline::new(Vec::new(), scene.timeline.step_s())
        .expect("an empty timeline has no two keys at one time");
    Ok((scene, sculpt))
}

/// The coarsest level of `field` that holds clay, if a level coarser than the finest does.
fn coarsest_level(field: &crate::field::Field) -> Option<usize> {
    (1..crate::field::LEVELS).rev().find(|&level| field.level_keys(level).next().is_some())
}

/// Rewrites the sculpt file `input` (any version this build reads) as `options` say, to `out`
/// (atomically; an existing file only when `overwrite`). `input` may also be a scene file,
/// whose clay at the end of its timeline is stored, with the scene's text. Versions 1 and 2
/// are refused for clay on coarser levels than the finest (they would move its surface).
pub fn convert_sculpt(
    input: &Path,
    out: &Path,
    options: EncodeOptions,
    overwrite: bool,
) -> Result<SavedSculpt> {
    if !(1..=VERSION).contains(&options.version) {
        bail!(
            "format version {} cannot be written; this Argile writes versions 1 to {VERSION}",
            options.version
        );
    }
    if !overwrite && out.exists() {
        bail!("{} already exists; pass --force to replace it", out.display());
    }
    let sculpt = if is_sculpt(input) {
        load_sculpt_with_progress(input, true)?
    } else {
        let text = crate::io::text::read_text(input, crate::io::text::SCENE_LIMIT)
            .with_context(|| format!("cannot read scene file {}", input.display()))?;
        let scene = Scene::parse(&text, &input.display().to_string(), input.parent())?;
        let mut playback = Playback::build(&scene)?;
        playback.advance_to(scene.end_s(), |_| {});
        playback.let_go();
        let tools = playback.stored_tools();
        let (field, parts, others) = playback.into_parts();
        let symmetry = Some(scene.symmetry);
        Sculpt { field, scene_toml: Some(text), tools, view: None, parts, others, lattice: None, symmetry }
    };
    if options.version < 6 && sculpt.lattice.is_some() {
        bail!(
            "{} holds a lattice left open; format version {} cannot store one (versions from 6 do): \
             open it in the station and apply the lattice (Enter) or put the clay back (Backspace) first",
            input.display(),
            options.version
        );
    }
    if let Some(level) = (options.version < 3).then(|| coarsest_level(&sculpt.field)).flatten() {
        // Versions 1 and 2 store the finest level alone: the coarse clay would go in refined,
        // read between its samples, and its surface would move by up to a coarse voxel.
        let voxel_mm = sculpt.field.level_transform(level).voxel_size_m * 1000.0;
        bail!(
            "{} holds clay on coarser levels than the finest (down to level {level}, {voxel_mm:.1} mm voxels);              format version {} stores the finest level alone, and refining the coarse clay into it would move              its surface by up to {voxel_mm:.1} mm: write format version 3 or later",
            input.display(),
            options.version
        );
    }
    if options.version < 5 && !sculpt.parts.is_empty() {
        bail!(
            "{} is a sculpt of {} parts; format version {} stores one (versions from 5 store parts)",
            input.display(),
            sculpt.parts.len(),
            options.version
        );
    }
    let bytes = encode_sculpt(&sculpt.field, sculpt.scene_parts(), options, &mut |_| {});
    write_atomically(out, overwrite, |w| {
        w.write_all(&bytes).with_context(|| format!("cannot write {}", out.display()))
    })?;
    let bricks = all_bricks(&sculpt.field) + sculpt.others.iter().map(all_bricks).sum::<usize>();
    Ok(SavedSculpt { path: out.to_path_buf(), bricks, bytes: bytes.len() })
}

/// Encodes the clay of `playback` (with its undo history, and the lattice it holds open over
/// the clay as it was when the lattice opened), the scene text it plays, the scene's freeform
/// tools and the station's `view` as a sculpt file's bytes.
pub(crate) fn encode_playback(
    playback: &mut Playback<'_>,
    scene_toml: Option<&str>,
    view: Option<&StoredView>,
) -> Vec<u8> {
    playback.as_stored(|playback, lattice| {
        let tools = playback.stored_tools();
        let layouts = playback.assembly().layouts();
        let others = if layouts.is_empty() { &[][..] } else { playback.assembly().others() };
        let symmetry = Some(playback.symmetry());
        let scene = SceneParts {
            toml: scene_toml,
            tools: &tools,
            view,
            layouts: &layouts,
            others,
            lattice,
            symmetry,
        };
        encode_sculpt(playback.field(), scene, EncodeOptions::default(), &mut |_| {})
    })
}

/// Writes a sculpt file's `bytes` to `path`, atomically.
pub(crate) fn write_sculpt(bytes: &[u8], path: &Path) -> Result<()> {
    write_atomically(path, true, |w| {
        w.write_all(bytes).with_context(|| format!("cannot write {}", path.display()))
    })
}

/// Describes the sculpt file at `path` from its index, without reading its clay (a file of
/// version 1 to 3 has no index: it is read whole): its version and size, settings, each
/// level's bricks and where they lie, its history and scene, and how much of it was read.
pub fn describe_sculpt(path: &Path) -> Result<String> {
    use std::fmt::Write;
    let lazy = LazySculpt::open(path)?;
    let field = lazy.field();
    let voxel_mm = field.transform().voxel_size_m * 1000.0;
    let mut out =
        format!("{}: format version {}, {} bytes\n", path.display(), lazy.version(), lazy.file_len());
    let _ = writeln!(out, "  voxels {voxel_mm} mm, iso-level {}", field.iso());
    // Per level: bricks, chunks, and the box of the finest lattice that holds them.
    let mut levels = [(0u64, 0usize, IVec3::MAX, IVec3::MIN); LEVELS];
    if lazy.chunks().is_empty() {
        for (level, stats) in levels.iter_mut().enumerate() {
            for key in field.level_keys(level) {
                let lo = key * BRICK_SIZE * (1 << level);
                let hi = lo + IVec3::splat((BRICK_SIZE - 1) << level);
                *stats = (stats.0 + 1, 0, stats.2.min(lo), stats.3.max(hi));
            }
        }
    } else {
        for c in lazy.chunks() {
            let (lo, hi) = c.samples();
            let stats = &mut levels[c.level];
            *stats = (stats.0 + u64::from(c.bricks), stats.1 + 1, stats.2.min(lo), stats.3.max(hi));
        }
    }
    let metres = |p: IVec3| field.transform().index_to_world(p.as_vec3());
    for (level, &(bricks, chunks, lo, hi)) in levels.iter().enumerate().filter(|(_, l)| l.0 > 0) {
        let (a, b): (Vec3, Vec3) = (metres(lo), metres(hi));
        let _ =
            write!(out, "  level {level} ({} mm voxels): {bricks} bricks", voxel_mm * (1 << level) as f32);
        if chunks > 0 {
            let _ = write!(out, " in {chunks} chunks");
        }
        let _ = writeln!(
            out,
            ", in {} spanning x {:.3}..{:.3} m, y {:.3}..{:.3} m, z {:.3}..{:.3} m",
            if chunks > 0 { "blocks of 64 samples a side" } else { "bricks" },
            a.x,
            b.x,
            a.y,
            b.y,
            a.z,
            b.z
        );
    }
    if lazy.brick_count() == 0 {
        let _ = writeln!(out, "  no clay");
    }
    let (layouts, others) = lazy.parts();
    if !layouts.is_empty() {
        let _ = writeln!(out, "  {} parts, composed in order:", layouts.len());
        for (i, p) in layouts.iter().enumerate() {
            let bricks = if i == 0 { lazy.brick_count() as usize } else { all_bricks(&others[i - 1]) };
            let _ = writeln!(
                out,
                "    {:?}: {}, {} mm voxels, at ({:.3}, {:.3}, {:.3}) m, scale {}, {bricks} bricks{}{}",
                p.name,
                p.op,
                p.voxel_size_m * 1000.0,
                p.translation_m[0],
                p.translation_m[1],
                p.translation_m[2],
                p.scale,
                if p.visible { "" } else { ", hidden" },
                if p.locked { ", locked" } else { "" }
            );
        }
    }
    if let Some(l) = lazy.lattice() {
        let [x, y, z] = l.counts;
        let _ = writeln!(
            out,
            "  a lattice left open over part {}: {x} × {y} × {z} {} controls of order {}, {} knots, from \
             ({:.3}, {:.3}, {:.3}) to ({:.3}, {:.3}, {:.3}) m (the clay stored is the clay it opened on)",
            l.part,
            l.kind,
            l.order,
            l.knots,
            l.min_m[0],
            l.min_m[1],
            l.min_m[2],
            l.max_m[0],
            l.max_m[1],
            l.max_m[2]
        );
    }
    if let Some(s) = lazy.symmetry() {
        let _ = writeln!(out, "  symmetry {} (the strokes act through it when it opens)", s.describe());
    }
    match lazy.history_size() {
        Some((0, _)) => {
            let _ = writeln!(out, "  no undo history");
        }
        Some((chunks, bytes)) => {
            let _ = writeln!(out, "  undo history: {chunks} chunks, {bytes} bytes");
        }
        None => {
            let stats = field.history_stats();
            let _ =
                writeln!(out, "  undo history: {} undo and {} redo steps", stats.undo_in_memory, stats.redo);
        }
    }
    match lazy.scene_toml() {
        Some(text) => {
            let _ = writeln!(out, "  the scene it was made in: stored ({} bytes of TOML)", text.len());
        }
        None => {
            let _ = writeln!(out, "  no scene stored");
        }
    }
    let what = if lazy.chunks().is_empty() && lazy.brick_count() > 0 {
        "the whole file (no index before version 4)"
    } else {
        "its header, settings, scene and index"
    };
    let _ = writeln!(out, "  read {} of {} bytes: {what}", lazy.bytes_read(), lazy.file_len());
    Ok(out)
}
