//! The native sculpt format (`.argile`): the clay, the scene it was made in and that scene's
//! freeform tools.
//!
//! Knows the field (it stores bricks) and nothing of Vulkan or devices.
//!
//! ## Layout, version 7
//!
//! ```text
//!  header  "ARGL" · version u32 · chunk count u32                      (little-endian)
//!  chunk   tag [u8; 4] · raw length u32 · stored length u32 · CRC-32 u32 · stored bytes
//!          …one after the other, `chunk count` of them
//!
//!  chunks  META  (first, once)  JSON: format, voxel size, iso-level, brick size, brick count
//!          SCNE  (at most once) the scene file's TOML text the sculpt was made in
//!          VIEW  (at most once, before INDX) JSON: the station's view when it was saved (turn
//!                               and distance of the camera, the scene's pose, stereo
//!                               settings, display mode; see [`StoredView`])
//!          TOOL  (any number, before INDX) a freeform tool of that scene as it was saved (a
//!                               copy of clay the scene's clay no longer holds): the scene
//!                               tool's index u32 · sample counts (3 × u32) · spacing f32
//!                               (metres) · densities (f32, x fastest, then y, then z)
//!          PRTS  (at most once, before INDX) JSON: the parts' layouts, the first part's
//!                               (whose clay is the file's own bricks) first: name, voxel
//!                               size, rotation (quaternion), translation, scale, operator,
//!                               visibility, lock (see [`PartLayout`]); absent for one part at
//!                               rest
//!          PART  (any number, after PRTS, before INDX) bricks of a part after the first: the
//!                               part's index u32 (1 and up) · level u8 · up to 512 bricks of
//!                               that level as in BRKS, keyed on the part's own lattice
//!          LATT  (at most once, after PRTS and PART, before INDX) JSON: the lattice held open
//!                               when the sculpt was saved (see [`StoredLattice`]): its part,
//!                               box, counts, kind, order, knots, every control's position,
//!                               value and weight, the control picked. The clay stored for its
//!                               part is the clay as it was when the lattice opened (and the
//!                               history the closed steps before it): a reader reopens the
//!                               lattice over it and puts its controls in place to have the
//!                               sculpt as it was left, or applies it for the shape alone
//!          SYMM  (at most once, after LATT, before INDX) JSON: the symmetry the strokes acted
//!                               through when the sculpt was saved: its frame's origin and
//!                               rotation, the mirror planes, the radial copies and their axis
//!                               (written whenever the symmetry is known, off included)
//!          INDX  (once, before any brick) the directory of the brick chunks that follow it:
//!                               chunk count u32 · history offset u64 · per brick chunk, in
//!                               file order: level u8 · block (3 × i32) · brick count u32 ·
//!                               offset u64. Offsets count from the first byte after INDX.
//!          BRKS  (any number)   the bricks of one block of the finest level: per brick its
//!                               key (3 × i32), then 512 densities (f32) and 512 linear RGBA
//!                               colours (4 × f32)
//!          BRKL  (any number)   the bricks of one block of a coarser level: the level u8
//!                               (1 to 4), then the bricks as in BRKS, keyed on that level's
//!                               lattice
//!          HIST  (any number, from the history offset on) the undo history held in memory
//!                               (optional): kind u8 (0 undo, 1 redo) · step index u32 · entry
//!                               count u32 (≤ 512) · entries: per brick, flags u8 (bit 0:
//!                               present; bits 1–3: the level, 0 the finest) · key (3 × i32) ·
//!                               if present its densities and colours as in BRKS. Undo steps
//!                               oldest first, then redo steps (the next redo last), each index
//!                               from 0; a step of more than 512 bricks continues in chunks of
//!                               the same index.
//!
//!  block   the bricks of a level whose keys shifted right by 3 agree: a cube of 8 × 8 × 8
//!          bricks, 64 samples of its level a side (64 finest voxels on level 0, 1024 on
//!          level 4); it holds at most 512 bricks, so it fits one chunk
//! ```
//!
//! The index lets a sculpt be read lazily ([`LazySculpt`]): opening one reads the header,
//! META, SCNE and INDX, and any brick chunk can then be read on its own, by where its block
//! lies (loading a box reads the chunks whose samples reach into it, and nothing else).
//!
//! Version 6 is version 7 without SYMM: a sculpt opened from it keeps the symmetry in force, and
//! one converted to it leaves its symmetry out (a setting, not clay). Version 5 is version 6 without LATT: a lattice held open is refused there rather than lost
//! (`argile convert`). Version 4 is version 5 without PRTS and PART: a sculpt of one part. The undo history (HIST)
//! is the first part's; the other parts' histories are not stored.
//! Version 3 is version 4 without INDX, TOOL and VIEW, its brick chunks holding up to 512 bricks of one level
//! in key order (not by block). Version 2 is version 3 without BRKL chunks and with the finest
//! level alone in entries; version 1 is version 2 without HIST chunks. This build reads all
//! four and writes any (`argile convert`): a sculpt with coarse levels written as version 1
//! or 2 stores the finest lattice as its readers see it (the coarse clay refined into finest
//! bricks, the same field to the eye and to the mesher), without its undo history. A sculpt of
//! several parts (or of one placed, hidden, locked or composed other than by union) is refused
//! in versions 1 to 4 rather than cut down to its first part. Versions 1
//! to 3 have no index: [`LazySculpt`] reads them whole when it opens them. They hold no
//! freeform tools either: a scene's freeform tool is copied again from the clay.
//!
//! - Every chunk's bytes are LZ4-compressed (`lz4_flex` block format) and carry the CRC-32 of
//!   the stored bytes; a reader checks the CRC before decompressing and the decompressed
//!   length against the header.
//! - Chunks bound the memory a reader commits before it has checked anything: a chunk is at
//!   most [`MAX_CHUNK_BYTES`] raw, so a large sculpt loads chunk by chunk, with progress.
//! - A reader refuses, with a sentence naming the file and the problem: a truncated file, a
//!   bad checksum, a future version, an unknown or repeated chunk, sizes or counts past the
//!   limits, a brick key twice or beyond ±2²⁴ bricks, densities outside [0, 1] or non-finite
//!   samples, history steps out of order, an index that does not say where the chunks are and
//!   what they hold. It never allocates what a header claims before checking the claim
//!   against the file's size.
//! - Files are written atomically ([`write_atomically`]).
//!
//! Later versions add chunk tags; a reader keeps reading every version it has shipped
//! (`tests/fixtures/sculpt-v1.argile`, `sculpt-v2.argile` and `sculpt-v3.argile` are checked).
//!
//! ## Fuzzing the loader
//!
//! `fuzz/fuzz_targets/load.rs` (cargo-fuzz, nightly: `cargo +nightly fuzz run load --
//! -max_total_time=120`) and `tests/fuzz_load.rs` (stable: `ARGILE_FUZZ_SECONDS=120 cargo test
//! --test fuzz_load -- --nocapture`) run the same body, `fuzz/fuzz_targets/load_body.rs`: any
//! bytes are refused or loaded without a panic, and what loads stores and loads again
//! unchanged. The stable run mutates valid files byte by byte and chunk by chunk, rewriting
//! lengths, compression and CRCs so that its changes reach the checks behind the checksum.
//!
//! Runs recorded (2-core AMD EPYC VM, shared with other builds; debug profile, opt-level 1):
//!
//! | run | inputs | loaded | result |
//! |---|---:|---:|---|
//! | stable, seed 1, 120 s, before the fix | 150 147 | — | a brick key of 2³¹−1 overflowed `key × 8` in `Field::insert_brick`: keys beyond ±2²⁴ bricks are now refused ([`MAX_BRICK_COORD`]) |
//! | stable, seed 1, 120 s | 481 352 | 23 582 | no panic, no input over 1 s |
//! | stable, seed 2, 120 s | 635 177 | 30 622 | no panic, no input over 1 s |
//!
//! ## Autosave: journal and snapshots
//!
//! While a session sculpts, [`autosave`] keeps, in a session folder of the user's state
//! directory (`autosave/<session>/`):
//!
//! ```text
//!  session.json        who owns the session: process id and start token, start time, source
//!  snapshot-N.argile   the sculpt after its first N strokes, in the format above
//!  journal-B.argj      the strokes after stroke B, appended as they finish:
//!     header  "ARGJ" · version u32 (2; version 1 is read too) · base stroke B u64 · CRC-32 of
//!             these 16 bytes u32
//!     records chunks as above, tag STRK, one record per finished stroke (or undo, redo),
//!             in one or more chunks: stroke number u64 (B + 1, B + 2, …) · last part u8
//!             (1 on the record's last chunk) · entry count u32 (≤ 512) · entries as in
//!             HIST, each brick as the stroke left it (absent: the brick is now empty); an
//!             entry of a part after the first has bit 7 of its flags set and the part's
//!             index (u16) after them
//!  closed              written (atomically) when the session ends cleanly
//! ```
//!
//! - A record holds every brick its stroke changed, as it is after the stroke: replaying the
//!   records in order on a snapshot gives the sculpt after each stroke, bit for bit.
//! - Records are written by a background thread and synced to disk in batches (at most one
//!   second after they are written): the sculpting thread only hands over shared bricks.
//! - A checkpoint writes `snapshot-N` atomically (temporary file, sync, rename, sync folder),
//!   then starts a new journal; only then are older snapshots and the journals they cover
//!   removed. Nothing already on disk is ever overwritten in place.
//! - Recovery loads the newest snapshot that reads whole, then applies the records numbered
//!   after it, from the journals in order of their base, while they follow one another
//!   (N + 1, N + 2, …). The first record that is cut short (a part missing included), fails
//!   its checksum or breaks the numbering ends its journal: a torn tail is discarded, never
//!   applied. The next journal continues only if its base shows no stroke is missing.

use std::collections::HashSet;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::field::{
    Brick, BrickColours, BrickKey, Colour, Field, HistoryStep, LevelKey, BRICK_SIZE, BRICK_VOLUME, LEVELS,
};
use crate::math::IVec3;

mod atomic;
pub mod autosave;
mod journal;
mod lattice;
mod lazy;
mod parts;
mod process;
mod symmetry;
pub mod text;

pub use atomic::write_atomically;
pub use lattice::{StoredControl, StoredLattice, KNOT_STYLES, LATTICE_KINDS};
pub use lazy::{ChunkInfo, LazySculpt};
pub use parts::{PartLayout, MAX_PARTS, PART_OPS};
pub use process::process_alive;

/// The format version this build writes.
pub const VERSION: u32 = 7;
/// The largest raw chunk a reader accepts.
pub const MAX_CHUNK_BYTES: usize = 64 << 20;
/// The most chunks a file may declare.
pub const MAX_CHUNKS: u32 = 1 << 20;
/// The most freeform tools a file may hold, and the most samples of them all (far beyond a
/// scene's few tools, each a box of clay of a hundred samples a side).
pub const MAX_TOOLS: usize = 64;
/// See [`MAX_TOOLS`].
pub const MAX_TOOL_SAMPLES: usize = 1 << 25;
/// The largest view (a few hundred bytes of JSON) a file may hold.
const MAX_VIEW_BYTES: usize = 1 << 16;
/// Bricks per `BRKS` chunk written, and per `HIST` or journal chunk.
pub const BRICKS_PER_CHUNK: usize = 512;

const MAGIC: &[u8; 4] = b"ARGL";
/// Bytes of one stored brick: its key, densities and colours.
const BRICK_RECORD: usize = 12 + BRICK_VOLUME * 4 + BRICK_VOLUME * 16;
const CHUNK_HEADER: usize = 16;
/// The fewest bytes an entry (see [`put_entries`]) takes: an absent brick.
const MIN_ENTRY: usize = 13;

/// A sculpt as stored: the clay, the scene text it was made in and that scene's freeform
/// tools.
#[derive(Clone, Debug)]
pub struct Sculpt {
    /// The clay.
    pub field: Field,
    /// The scene file's text, if the sculpt was made from one.
    pub scene_toml: Option<String>,
    /// The scene's freeform tools as they were saved.
    pub tools: Vec<StoredTool>,
    /// The station's view when it was saved.
    pub view: Option<StoredView>,
    /// Its parts' layouts, the first part's (whose clay is `field`) first; empty for a sculpt
    /// of one part at rest.
    pub parts: Vec<PartLayout>,
    /// The clay of the parts after the first, one field each.
    pub others: Vec<Field>,
    /// The lattice held open when it was saved, over the clay as it was when it opened.
    pub lattice: Option<StoredLattice>,
    /// The symmetry the strokes acted through when it was saved (version 7; none stored
    /// before).
    pub symmetry: Option<crate::parts::Symmetry>,
}

impl Sculpt {
    /// A sculpt of one part: `field`, with nothing else.
    pub fn of_field(field: Field) -> Self {
        Self {
            field,
            scene_toml: None,
            tools: Vec::new(),
            view: None,
            parts: Vec::new(),
            others: Vec::new(),
            lattice: None,
            symmetry: None,
        }
    }

    /// What it stores besides its clay, to encode it again.
    pub fn scene_parts(&self) -> SceneParts<'_> {
        SceneParts {
            toml: self.scene_toml.as_deref(),
            tools: &self.tools,
            view: self.view.as_ref(),
            layouts: &self.parts,
            others: &self.others,
            lattice: self.lattice.as_ref(),
            symmetry: self.symmetry.as_ref(),
        }
    }
}

/// What a sculpt stores besides its clay: the scene it was made in, that scene's freeform
/// tools as they were copied, and the view it was last seen in.
#[derive(Clone, Copy, Debug, Default)]
pub struct SceneParts<'a> {
    /// The scene file's text.
    pub toml: Option<&'a str>,
    /// The scene's freeform tools.
    pub tools: &'a [StoredTool],
    /// The station's view.
    pub view: Option<&'a StoredView>,
    /// The parts' layouts (none: one part at rest).
    pub layouts: &'a [PartLayout],
    /// The clay of the parts after the first.
    pub others: &'a [Field],
    /// The lattice held open (version 6), over the clay as it was when it opened.
    pub lattice: Option<&'a StoredLattice>,
    /// The symmetry the strokes act through (version 7).
    pub symmetry: Option<&'a crate::parts::Symmetry>,
}

/// The station's view when a sculpt was saved: where the camera looks from, the stereo
/// settings and the display, so that the sculpt opens as it was left.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoredView {
    /// The trackball's turn of the scene about the camera's target (quaternion x, y, z, w).
    pub turn: [f32; 4],
    /// The camera's distance from its target, metres.
    pub distance_m: f32,
    /// The scene's pose as the 6-DoF devices left it: position (metres) and rotation
    /// (quaternion x, y, z, w).
    pub scene_position_m: [f32; 3],
    /// See `scene_position_m`.
    pub scene_rotation: [f32; 4],
    /// The convergence distance over the camera's distance.
    pub convergence_factor: f32,
    /// The distance between the eyes, metres.
    pub interaxial_m: f32,
    /// Whether the lights attached to the viewer follow it.
    pub lights_follow_viewer: bool,
    /// Whether automatic convergence was on.
    pub auto_convergence: bool,
    /// The display mode's name (see `stereo::DisplayMode`).
    pub display_mode: String,
}

impl StoredView {
    /// Reads a VIEW chunk's bytes, refusing what a saved view cannot be: numbers that are not
    /// finite, a rotation that is not one, distances out of range, an unknown display mode.
    fn read(raw: &[u8], chunk: u32) -> Result<Self, String> {
        let v: Self =
            serde_json::from_slice(raw).map_err(|e| format!("chunk {chunk} (VIEW) is not a view: {e}"))?;
        let unit = |q: [f32; 4]| (crate::math::Quat::from_array(q).length() - 1.0).abs() < 1e-3;
        let numbers = v.turn.iter().chain(&v.scene_position_m).chain(&v.scene_rotation);
        let fine =
            numbers.chain([&v.distance_m, &v.convergence_factor, &v.interaxial_m]).all(|x| x.is_finite())
                && unit(v.turn)
                && unit(v.scene_rotation)
                && v.scene_position_m.iter().all(|x| x.abs() < 1e3)
                && (1e-4..1e3).contains(&v.distance_m)
                && (1e-4..1e3).contains(&v.convergence_factor)
                && (0.0..1.0).contains(&v.interaxial_m);
        if !fine {
            return Err(format!("chunk {chunk} (VIEW) holds a view no station has: {v:?}"));
        }
        if v.display_mode.parse::<crate::stereo::display::DisplayMode>().is_err() {
            return Err(format!(
                "chunk {chunk} (VIEW) names display mode `{}`, which this Argile has not",
                v.display_mode
            ));
        }
        Ok(v)
    }
}

/// A freeform tool as a sculpt stores it: a box of densities copied from clay (see
/// `tool::Freeform`), and which of the scene's tools it is.
#[derive(Clone, Debug, PartialEq)]
pub struct StoredTool {
    /// The tool's index in the scene's `[[tool]]` list.
    pub index: u32,
    /// Samples along x, y and z (each at least 1).
    pub dims: [u32; 3],
    /// Distance between samples, metres.
    pub spacing_m: f32,
    /// Densities in [0, 1], x fastest, then y, then z.
    pub samples: Vec<f32>,
}

impl StoredTool {
    fn put(&self) -> Vec<u8> {
        let mut raw = Vec::with_capacity(20 + 4 * self.samples.len());
        for v in [self.index, self.dims[0], self.dims[1], self.dims[2]] {
            raw.extend_from_slice(&v.to_le_bytes());
        }
        raw.extend_from_slice(&self.spacing_m.to_le_bytes());
        for d in &self.samples {
            raw.extend_from_slice(&d.to_le_bytes());
        }
        raw
    }

    /// Reads a TOOL chunk's bytes, refusing sizes that do not match the bytes, a spacing that
    /// is not a usable size and densities outside [0, 1].
    fn read(raw: &[u8], chunk: u32) -> Result<Self, String> {
        if raw.len() < 20 {
            return Err(format!("chunk {chunk} (TOOL) is too short"));
        }
        let dims = [u32_at(raw, 4), u32_at(raw, 8), u32_at(raw, 12)];
        let count = dims.iter().try_fold(1u64, |n, &d| n.checked_mul(u64::from(d)));
        if dims.contains(&0) || raw.len() % 4 != 0 || count != Some(((raw.len() - 20) / 4) as u64) {
            return Err(format!(
                "chunk {chunk} (TOOL) claims {} × {} × {} samples in {} bytes",
                dims[0],
                dims[1],
                dims[2],
                raw.len()
            ));
        }
        let f = |at: usize| f32::from_le_bytes(raw[at..at + 4].try_into().expect("4 bytes"));
        let spacing_m = f(16);
        if !(spacing_m.is_finite() && spacing_m > 0.0 && spacing_m < 1.0) {
            return Err(format!(
                "chunk {chunk} (TOOL) has samples {spacing_m} m apart, not a usable spacing"
            ));
        }
        let samples: Vec<f32> = (20..raw.len()).step_by(4).map(f).collect();
        if let Some(d) = samples.iter().find(|d| !(0.0..=1.0).contains(*d)) {
            return Err(format!("chunk {chunk} (TOOL) holds density {d}, outside [0, 1]"));
        }
        Ok(Self { index: u32_at(raw, 0), dims, spacing_m, samples })
    }
}

/// Why a sculpt file cannot be read.
#[derive(Debug, thiserror::Error)]
#[error("sculpt file {file}: {reason}")]
pub struct SculptError {
    /// The file (as given by the caller).
    pub file: String,
    /// What is wrong with it.
    pub reason: String,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Meta {
    format: String,
    voxel_size_m: f32,
    iso: f32,
    brick_size: i32,
    bricks: u64,
}

/// What [`encode_with`] writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncodeOptions {
    /// The format version to write (1 to 7; version 1 holds no history, versions 1 and 2 no
    /// coarse levels, versions 1 to 3 no index, versions 1 to 4 no parts: the first part
    /// alone; versions 1 to 5 no lattice, 1 to 6 no symmetry).
    pub version: u32,
    /// Whether to store the undo history held in memory.
    pub history: bool,
}

impl Default for EncodeOptions {
    /// The current version, with the history.
    fn default() -> Self {
        Self { version: VERSION, history: true }
    }
}

/// Encodes a sculpt in the current version, with its undo history; `progress` gets the
/// fraction of bricks written.
pub fn encode(field: &Field, scene_toml: Option<&str>, progress: &mut dyn FnMut(f32)) -> Vec<u8> {
    encode_with(field, scene_toml, EncodeOptions::default(), progress)
}

/// Encodes a sculpt as `options` say (`options.version` must be one this build writes: 1 to
/// [`VERSION`]).
pub fn encode_with(
    field: &Field,
    scene_toml: Option<&str>,
    options: EncodeOptions,
    progress: &mut dyn FnMut(f32),
) -> Vec<u8> {
    encode_sculpt(field, SceneParts { toml: scene_toml, ..SceneParts::default() }, options, progress)
}

/// Encodes a sculpt with what it stores besides its clay (`scene`) as `options` say
/// (versions before 4 leave the scene's freeform tools and the view out).
pub fn encode_sculpt(
    field: &Field,
    scene: SceneParts<'_>,
    options: EncodeOptions,
    progress: &mut dyn FnMut(f32),
) -> Vec<u8> {
    assert!((1..=VERSION).contains(&options.version), "format version {} is not written", options.version);
    let levels = options.version >= 3 || !field.has_levels_above(0);
    let mut refined = Vec::new();
    let bricks: Vec<(LevelKey, &Brick)> = if levels {
        field.shared_bricks().map(|(k, b)| (k, &**b)).collect()
    } else {
        // The finest lattice as readers see it: the coarse clay refined into finest bricks.
        let mut scratch = Brick::default();
        for key in field.covered_keys() {
            if field.brick(key).is_none() {
                if let Some(b) = field.read_brick(key, &mut scratch) {
                    refined.push((key, b.clone()));
                }
            }
        }
        let stored = field.brick_keys().filter_map(|k| field.brick(k).map(|b| (LevelKey::from(k), b)));
        stored.chain(refined.iter().map(|(k, b)| (LevelKey::from(*k), b))).collect()
    };
    // Undo steps speak of the bricks as stored, levels and all: with the levels folded into
    // the finest, they would undo into holes.
    let history = (options.history && options.version >= 2 && levels).then(|| field.history_in_memory());
    let settings = (field.transform().voxel_size_m, field.iso());
    let scene =
        if options.version >= 4 { scene } else { SceneParts { toml: scene.toml, ..SceneParts::default() } };
    let others = scene
        .others
        .iter()
        .enumerate()
        .flat_map(|(i, f)| f.shared_bricks().map(move |(k, b)| (i as u32 + 1, k, &**b)))
        .collect();
    encode_parts(options.version, settings, bricks, scene, others, history.as_ref(), progress)
}

/// Encodes a sculpt given as its settings, bricks (in any order), scene text and freeform
/// tools, without history.
pub(crate) fn encode_bricks(
    voxel_size_m: f32,
    iso: f32,
    bricks: Vec<(LevelKey, &Brick)>,
    scene: SceneParts<'_>,
    others: Vec<(u32, LevelKey, &Brick)>,
    progress: &mut dyn FnMut(f32),
) -> Vec<u8> {
    encode_parts(VERSION, (voxel_size_m, iso), bricks, scene, others, None, progress)
}

type History = (Vec<HistoryStep>, Vec<HistoryStep>);

fn encode_parts(
    version: u32,
    (voxel_size_m, iso): (f32, f32),
    mut bricks: Vec<(LevelKey, &Brick)>,
    SceneParts { toml: scene_toml, tools, view, layouts, lattice, symmetry, .. }: SceneParts<'_>,
    mut others: Vec<(u32, LevelKey, &Brick)>,
    history: Option<&History>,
    progress: &mut dyn FnMut(f32),
) -> Vec<u8> {
    let meta = Meta {
        format: "argile sculpt".into(),
        voxel_size_m,
        iso,
        brick_size: BRICK_SIZE,
        bricks: bricks.len() as u64,
    };
    // Chunks of the bricks of one block (version 4), or of up to 512 bricks of one level.
    let indexed = version >= 4;
    let groups: Vec<&[(LevelKey, &Brick)]> = if indexed {
        bricks.sort_unstable_by_key(|(k, _)| (k.level, block_of(k.key).to_array(), k.key.to_array()));
        bricks.chunk_by(|a, b| (a.0.level, block_of(a.0.key)) == (b.0.level, block_of(b.0.key))).collect()
    } else {
        bricks.sort_unstable_by_key(|(k, _)| k.sort_key());
        bricks.chunk_by(|a, b| a.0.level == b.0.level).flat_map(|l| l.chunks(BRICKS_PER_CHUNK)).collect()
    };
    let steps: Vec<(u8, u32, &HistoryStep)> = history.map_or_else(Vec::new, |(undo, redo)| {
        let undo = undo.iter().enumerate().map(|(i, s)| (0, i as u32, s));
        undo.chain(redo.iter().enumerate().map(|(i, s)| (1, i as u32, s))).collect()
    });
    let step_chunks: usize = steps.iter().map(|(_, _, s)| s.len().div_ceil(BRICKS_PER_CHUNK).max(1)).sum();
    // The brick chunks, compressed first: the index gives where each one lies.
    let group_count = groups.len().max(1);
    let mut raw = Vec::new();
    let mut stored = Vec::with_capacity(groups.len());
    let mut entries = Vec::with_capacity(groups.len());
    let mut offset = 0u64;
    for (i, group) in groups.into_iter().enumerate() {
        raw.clear();
        raw.reserve(1 + group.len() * BRICK_RECORD);
        let level = group[0].0.level;
        if level > 0 {
            raw.push(level);
        }
        for (key, brick) in group {
            put_brick(&mut raw, key.key, brick);
        }
        let mut chunk = Vec::new();
        put_chunk(&mut chunk, if level > 0 { *b"BRKL" } else { *b"BRKS" }, &raw);
        entries.push(IndexEntry {
            level,
            block: block_of(group[0].0.key),
            bricks: group.len() as u32,
            offset,
        });
        offset += chunk.len() as u64;
        stored.push(chunk);
        progress((i + 1) as f32 / group_count as f32);
    }
    // Version 5: the parts' layouts and the other parts' bricks, before the index.
    let mut parts = Vec::new();
    let part_chunks = if version >= 5 && !layouts.is_empty() {
        put_chunk(&mut parts, *b"PRTS", &parts::put_layouts(layouts));
        1 + parts::put_part_chunks(&mut parts, &mut others)
    } else {
        0
    };
    let lattice = lattice.filter(|_| version >= 6);
    let symmetry = symmetry.filter(|_| version >= 7);
    let chunk_count = 1
        + part_chunks
        + u32::from(lattice.is_some())
        + u32::from(symmetry.is_some())
        + u32::from(scene_toml.is_some())
        + u32::from(view.is_some())
        + tools.len() as u32
        + u32::from(indexed)
        + stored.len() as u32
        + step_chunks as u32;
    let mut out = Vec::with_capacity(offset as usize + 1024);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&version.to_le_bytes());
    out.extend_from_slice(&chunk_count.to_le_bytes());
    put_chunk(&mut out, *b"META", &serde_json::to_vec(&meta).expect("plain values serialise"));
    if let Some(text) = scene_toml {
        put_chunk(&mut out, *b"SCNE", text.as_bytes());
    }
    if let Some(view) = view {
        put_chunk(&mut out, *b"VIEW", &serde_json::to_vec(view).expect("plain values serialise"));
    }
    for tool in tools {
        put_chunk(&mut out, *b"TOOL", &tool.put());
    }
    out.extend_from_slice(&parts);
    if let Some(lattice) = lattice {
        put_chunk(&mut out, *b"LATT", &lattice.put());
    }
    if let Some(symmetry) = symmetry {
        put_chunk(&mut out, *b"SYMM", &symmetry::put(symmetry));
    }
    if indexed {
        put_chunk(&mut out, *b"INDX", &put_index(&entries, offset));
    }
    for chunk in stored {
        out.extend_from_slice(&chunk);
    }
    for (kind, index, step) in steps {
        for part in step.chunks(BRICKS_PER_CHUNK).chain(step.is_empty().then_some(&[][..])) {
            raw.clear();
            raw.push(kind);
            raw.extend_from_slice(&index.to_le_bytes());
            raw.extend_from_slice(&(part.len() as u32).to_le_bytes());
            put_entries(&mut raw, part);
            put_chunk(&mut out, *b"HIST", &raw);
        }
    }
    out
}

/// The block (see the module docs) holding brick `key` of its level.
fn block_of(key: BrickKey) -> IVec3 {
    key >> BLOCK_SHIFT
}

/// Bricks of a block a side, as a shift of brick keys.
const BLOCK_SHIFT: i32 = 3;
/// Bytes of one index entry: level, block, brick count, offset.
const INDEX_ENTRY: usize = 1 + 12 + 4 + 8;

/// One brick chunk as the index tells of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct IndexEntry {
    pub(crate) level: u8,
    pub(crate) block: IVec3,
    pub(crate) bricks: u32,
    /// From the first byte after the index chunk.
    pub(crate) offset: u64,
}

/// The index chunk's bytes: the entries and where the history starts (both from the first
/// byte after the index chunk).
fn put_index(entries: &[IndexEntry], history_offset: u64) -> Vec<u8> {
    let mut raw = Vec::with_capacity(12 + entries.len() * INDEX_ENTRY);
    raw.extend_from_slice(&(entries.len() as u32).to_le_bytes());
    raw.extend_from_slice(&history_offset.to_le_bytes());
    for e in entries {
        raw.push(e.level);
        for c in e.block.to_array() {
            raw.extend_from_slice(&c.to_le_bytes());
        }
        raw.extend_from_slice(&e.bricks.to_le_bytes());
        raw.extend_from_slice(&e.offset.to_le_bytes());
    }
    raw
}

/// Reads an index chunk's bytes, refusing entries that are not in file order, repeat a block,
/// name a level or block beyond the field, claim more bricks than a block holds or than the
/// file's META says, or lie past `room` bytes (what follows the index in the file).
fn read_index(raw: &[u8], bricks: u64, room: u64) -> Result<(Vec<IndexEntry>, u64), String> {
    if raw.len() < 12
        || (raw.len() - 12) % INDEX_ENTRY != 0
        || u32_at(raw, 0) as usize != (raw.len() - 12) / INDEX_ENTRY
    {
        return Err("its INDX chunk is not a whole index".into());
    }
    let u64_at = |at: usize| u64::from_le_bytes(raw[at..at + 8].try_into().expect("8 bytes"));
    let history = u64_at(4);
    if history > room {
        return Err(format!(
            "its index puts the history at byte {history} after it, past the file's end (truncated)"
        ));
    }
    let mut entries = Vec::with_capacity((raw.len() - 12) / INDEX_ENTRY);
    let mut blocks = HashSet::new();
    let (mut next, mut total) = (0u64, 0u64);
    let limit = MAX_BRICK_COORD >> BLOCK_SHIFT;
    for e in raw[12..].chunks_exact(INDEX_ENTRY) {
        let block = IVec3::new(u32_at(e, 1) as i32, u32_at(e, 5) as i32, u32_at(e, 9) as i32);
        let entry = IndexEntry {
            level: e[0],
            block,
            bricks: u32_at(e, 13),
            offset: u64::from_le_bytes(e[17..25].try_into().expect("8 bytes")),
        };
        let i = entries.len();
        if usize::from(entry.level) >= LEVELS
            || block.to_array().iter().any(|c| !(-limit..=limit).contains(c))
        {
            return Err(format!(
                "its index entry {i} names block {block} of level {}, beyond the field",
                entry.level
            ));
        }
        if !(1..=BRICKS_PER_CHUNK as u32).contains(&entry.bricks) {
            return Err(format!("its index entry {i} claims {} bricks in one block", entry.bricks));
        }
        // The first chunk starts right after the index; each takes at least its header and a
        // byte; all of them lie before the history.
        if (i == 0 && entry.offset != 0)
            || entry.offset < next
            || entry.offset.saturating_add(CHUNK_HEADER as u64) > history
        {
            return Err(format!(
                "its index entry {i} puts a chunk at byte {} after the index, where none can start",
                entry.offset
            ));
        }
        if !blocks.insert((entry.level, block)) {
            return Err(format!("its index names block {block} of level {} twice", entry.level));
        }
        next = entry.offset + CHUNK_HEADER as u64 + 1;
        total += u64::from(entry.bricks);
        entries.push(entry);
    }
    if total != bricks {
        return Err(format!("its index counts {total} bricks, its META chunk says {bricks}"));
    }
    Ok((entries, history))
}

/// Appends brick entries of the first part: per brick, flags u8 (bit 0: present; bits 1–3:
/// the level) · key (3 × i32) · if present, its densities and colours (as [`put_brick`]).
pub(crate) fn put_entries(raw: &mut Vec<u8>, bricks: &[(LevelKey, Option<Arc<Brick>>)]) {
    for (key, brick) in bricks {
        put_entry(raw, 0, *key, brick.as_deref());
    }
}

/// A brick of one part of a sculpt: the part's index (0 the first), its key, the brick
/// (`None`: absent).
pub(crate) type PartBrick = (u16, LevelKey, Option<Arc<Brick>>);

/// Flag of an entry of a part after the first: its index follows the flags (u16).
const PART_FLAG: u8 = 0x80;

/// Appends brick entries of any parts: as [`put_entries`], with the flags' bit 7 set and the
/// part's index (u16) after them for a part after the first.
pub(crate) fn put_part_entries(raw: &mut Vec<u8>, bricks: &[PartBrick]) {
    for (part, key, brick) in bricks {
        put_entry(raw, *part, *key, brick.as_deref());
    }
}

fn put_entry(raw: &mut Vec<u8>, part: u16, key: LevelKey, brick: Option<&Brick>) {
    let flags = u8::from(brick.is_some()) | key.level << 1;
    if part == 0 {
        raw.push(flags);
    } else {
        raw.push(flags | PART_FLAG);
        raw.extend_from_slice(&part.to_le_bytes());
    }
    match brick {
        Some(b) => put_brick(raw, key.key, b),
        None => {
            for c in key.key.to_array() {
                raw.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
}

/// Reads `count` entries written by [`put_entries`] from `raw` at `*at`, refusing a key twice
/// and an entry of another part.
pub(crate) fn read_entries(
    raw: &[u8],
    at: &mut usize,
    count: usize,
    seen: &mut HashSet<LevelKey>,
) -> Result<Vec<(LevelKey, Option<Brick>)>, String> {
    let first_part = |part: u16, key: LevelKey| match part {
        0 if seen.insert(key) => Ok(()),
        0 => Err(format!("brick {key} appears twice")),
        _ => Err(format!("brick {key} is of part {part}; these entries are of the first part alone")),
    };
    let entries = read_entries_with(raw, at, count, first_part)?;
    Ok(entries.into_iter().map(|(_, key, brick)| (key, brick)).collect())
}

/// Reads `count` entries written by [`put_part_entries`] from `raw` at `*at`, refusing a key of
/// one part twice.
pub(crate) fn read_part_entries(
    raw: &[u8],
    at: &mut usize,
    count: usize,
    seen: &mut HashSet<(u16, LevelKey)>,
) -> Result<Vec<(u16, LevelKey, Option<Brick>)>, String> {
    read_entries_with(raw, at, count, |part, key| match seen.insert((part, key)) {
        true => Ok(()),
        false => Err(format!("brick {key} of part {part} appears twice")),
    })
}

/// Reads `count` entries of any parts, each key checked by `accept` (which refuses a repeat).
fn read_entries_with(
    raw: &[u8],
    at: &mut usize,
    count: usize,
    mut accept: impl FnMut(u16, LevelKey) -> Result<(), String>,
) -> Result<Vec<(u16, LevelKey, Option<Brick>)>, String> {
    // Refuse counts the bytes cannot hold before allocating for them.
    if count > (raw.len() - *at) / MIN_ENTRY {
        return Err(format!("it claims {count} bricks, more than its {} bytes hold", raw.len() - *at));
    }
    let mut entries = Vec::with_capacity(count);
    for _ in 0..count {
        let Some(flags) = raw.get(*at).copied() else { return Err("it ends inside a brick".into()) };
        *at += 1;
        let part = if flags & PART_FLAG != 0 {
            let Some(bytes) = raw.get(*at..*at + 2) else { return Err("it ends inside a brick".into()) };
            *at += 2;
            let part = u16::from_le_bytes([bytes[0], bytes[1]]);
            if part == 0 {
                return Err("an entry flagged as of a later part names the first".into());
            }
            part
        } else {
            0
        };
        let level = usize::from((flags & !PART_FLAG) >> 1);
        if level >= LEVELS {
            return Err(format!(
                "a brick has the flags {flags}: level {level} is beyond the field's {LEVELS}"
            ));
        }
        let entry = match flags & 1 {
            0 if raw.len() >= *at + 12 => {
                let key = read_key(&raw[*at..])?;
                *at += 12;
                (LevelKey::new(level, key), None)
            }
            1 if raw.len() >= *at + BRICK_RECORD => {
                let (key, brick) = read_brick(&raw[*at..])?;
                *at += BRICK_RECORD;
                (LevelKey::new(level, key), Some(brick))
            }
            _ => return Err("it ends inside a brick".into()),
        };
        accept(part, entry.0)?;
        entries.push((part, entry.0, entry.1));
    }
    Ok(entries)
}

/// Appends a chunk: tag, raw and stored lengths, CRC-32 of the stored bytes, stored bytes.
pub(crate) fn put_chunk(out: &mut Vec<u8>, tag: [u8; 4], raw: &[u8]) {
    let stored = lz4_flex::block::compress(raw);
    out.extend_from_slice(&tag);
    out.extend_from_slice(&(raw.len() as u32).to_le_bytes());
    out.extend_from_slice(&(stored.len() as u32).to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(&stored).to_le_bytes());
    out.extend_from_slice(&stored);
}

/// Appends a brick's key, densities and colours.
pub(crate) fn put_brick(out: &mut Vec<u8>, key: BrickKey, brick: &Brick) {
    for c in key.to_array() {
        out.extend_from_slice(&c.to_le_bytes());
    }
    for d in brick.densities() {
        out.extend_from_slice(&d.to_le_bytes());
    }
    for c in brick.colour.iter().flatten() {
        out.extend_from_slice(&c.to_le_bytes());
    }
}

pub(crate) fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
}

/// The largest brick coordinate a file may hold, either way: far beyond any sculpt (±134 km at
/// 1 mm voxels), and small enough that lattice arithmetic on it (brick × 8, aprons) never
/// overflows.
pub const MAX_BRICK_COORD: i32 = 1 << 24;

/// Reads the brick key (3 × i32) at the start of `bytes` (at least 12), refusing coordinates
/// beyond [`MAX_BRICK_COORD`].
fn read_key(bytes: &[u8]) -> Result<BrickKey, String> {
    let key = IVec3::new(u32_at(bytes, 0) as i32, u32_at(bytes, 4) as i32, u32_at(bytes, 8) as i32);
    if key.to_array().iter().any(|c| !(-MAX_BRICK_COORD..=MAX_BRICK_COORD).contains(c)) {
        return Err(format!("brick {key} lies beyond the field's range (±{MAX_BRICK_COORD} bricks)"));
    }
    Ok(key)
}

/// Reads the brick record at the start of `record` (at least [`BRICK_RECORD`] bytes),
/// refusing densities outside [0, 1] and colours that are not numbers.
pub(crate) fn read_brick(record: &[u8]) -> Result<(BrickKey, Brick), String> {
    let key = read_key(record)?;
    let mut brick = Brick::default();
    let f = |i: usize| f32::from_le_bytes(record[i..i + 4].try_into().expect("4 bytes"));
    for i in 0..BRICK_VOLUME {
        let d = f(12 + 4 * i);
        if !(0.0..=1.0).contains(&d) {
            return Err(format!("brick {key} holds density {d}, outside [0, 1]"));
        }
        brick.set_density(i, d);
    }
    let colour = |i: usize| -> Colour { std::array::from_fn(|j| f(12 + 4 * BRICK_VOLUME + 16 * i + 4 * j)) };
    if (0..BRICK_VOLUME).any(|i| colour(i).iter().any(|v| !v.is_finite())) {
        return Err(format!("brick {key} holds a colour that is not a number"));
    }
    brick.colour = BrickColours::from_samples(colour);
    Ok((key, brick))
}

/// One chunk read whole and checked.
pub(crate) struct Chunk {
    pub(crate) tag: [u8; 4],
    /// The tag as text, for messages.
    pub(crate) name: String,
}

/// Where a reader takes a sculpt's bytes from: memory, or a file read chunk by chunk, so that
/// a large sculpt is never in memory twice.
trait Source: Send {
    /// Bytes in all.
    fn len(&self) -> u64;
    /// Bytes taken so far.
    fn position(&self) -> u64;
    /// The next `n` bytes (the caller checked that they exist), read into `buf` where they must
    /// be copied.
    fn take<'a>(&'a mut self, n: usize, buf: &'a mut Vec<u8>) -> Result<&'a [u8], String>;
    /// Goes to byte `to` (at most [`Source::len`]).
    fn seek(&mut self, to: u64) -> Result<(), String>;
}

struct Slice<B> {
    bytes: B,
    at: usize,
}

impl<B: AsRef<[u8]> + Send> Source for Slice<B> {
    fn len(&self) -> u64 {
        self.bytes.as_ref().len() as u64
    }

    fn position(&self) -> u64 {
        self.at as u64
    }

    fn take<'a>(&'a mut self, n: usize, _: &'a mut Vec<u8>) -> Result<&'a [u8], String> {
        let taken = &self.bytes.as_ref()[self.at..self.at + n];
        self.at += n;
        Ok(taken)
    }

    fn seek(&mut self, to: u64) -> Result<(), String> {
        self.at = to as usize;
        Ok(())
    }
}

struct FileSource {
    reader: std::io::BufReader<std::fs::File>,
    len: u64,
    at: u64,
}

impl FileSource {
    /// The file at `path`, read through a buffer of `buffer` bytes (0: each read goes to the
    /// file, for reading a few chunks here and there).
    fn open(path: &std::path::Path, buffer: usize) -> Result<Self, String> {
        // A FIFO or a device would block or never end: only regular files are opened.
        text::regular_file(path).map_err(|e| format!("cannot read it: {e}"))?;
        let file = std::fs::File::open(path).map_err(|e| format!("cannot open it: {e}"))?;
        let len = file.metadata().map_err(|e| format!("cannot read it: {e}"))?.len();
        Ok(Self { reader: std::io::BufReader::with_capacity(buffer, file), len, at: 0 })
    }
}

impl Source for FileSource {
    fn len(&self) -> u64 {
        self.len
    }

    fn position(&self) -> u64 {
        self.at
    }

    fn take<'a>(&'a mut self, n: usize, buf: &'a mut Vec<u8>) -> Result<&'a [u8], String> {
        buf.clear();
        buf.resize(n, 0);
        std::io::Read::read_exact(&mut self.reader, buf).map_err(|e| format!("cannot read it: {e}"))?;
        self.at += n as u64;
        Ok(buf)
    }

    fn seek(&mut self, to: u64) -> Result<(), String> {
        use std::io::Seek;
        self.reader.seek(std::io::SeekFrom::Start(to)).map_err(|e| format!("cannot read it: {e}"))?;
        self.at = to;
        Ok(())
    }
}

/// Reads chunk number `index` at `*at` of `bytes` into `raw` (see [`read_chunk_from`]); on
/// success `*at` moves past it, on failure it stays.
pub(crate) fn read_chunk(
    bytes: &[u8],
    at: &mut usize,
    index: u32,
    raw: &mut Vec<u8>,
) -> Result<Chunk, String> {
    let mut source = Slice { bytes, at: *at };
    let chunk = read_chunk_from(&mut source, index, raw, &mut Vec::new())?;
    *at = source.at;
    Ok(chunk)
}

/// Reads chunk number `index` into `raw`, checking its size limit, checksum and decompressed
/// length; `buf` holds its stored bytes where they must be copied.
fn read_chunk_from(
    source: &mut dyn Source,
    index: u32,
    raw: &mut Vec<u8>,
    buf: &mut Vec<u8>,
) -> Result<Chunk, String> {
    if source.len() - source.position() < CHUNK_HEADER as u64 {
        return Err(format!("it ends inside the header of chunk {index} (truncated)"));
    }
    let header = source.take(CHUNK_HEADER, buf)?;
    let tag: [u8; 4] = header[..4].try_into().expect("4 bytes");
    let raw_len = u32_at(header, 4) as usize;
    let stored_len = u32_at(header, 8) as usize;
    let crc = u32_at(header, 12);
    // Quoted as the file has it, escaped: a tag is never sent raw to the terminal.
    let name = tag.escape_ascii().to_string();
    if raw_len > MAX_CHUNK_BYTES {
        return Err(format!(
            "chunk {index} ({name}) claims {raw_len} bytes, over the {MAX_CHUNK_BYTES} limit"
        ));
    }
    if stored_len as u64 > source.len() - source.position() {
        return Err(format!("it ends inside chunk {index} ({name}) (truncated)"));
    }
    let stored = source.take(stored_len, buf)?;
    if crc32fast::hash(stored) != crc {
        return Err(format!("chunk {index} ({name}) fails its checksum: the file is damaged"));
    }
    raw.clear();
    raw.resize(raw_len, 0);
    match lz4_flex::block::decompress_into(stored, raw) {
        Ok(n) if n == raw_len => {}
        _ => return Err(format!("chunk {index} ({name}) does not decompress to its stated size")),
    }
    Ok(Chunk { tag, name })
}

/// Decodes a sculpt, refusing anything not written whole by [`encode`] (see the module docs);
/// `file` names the file in errors, `progress` gets the fraction of the bytes read.
pub fn decode(bytes: &[u8], file: &str, progress: &mut dyn FnMut(f32)) -> Result<Sculpt, SculptError> {
    decode_from(&mut Slice { bytes, at: 0 }, &MemoryLimit::NONE, progress)
        .map_err(|reason| SculptError { file: file.to_owned(), reason })
}

/// Reads the sculpt file `path` chunk by chunk (a chunk at a time in memory besides the
/// sculpt), as [`decode`] checks it; `progress` gets the fraction of the file read.
pub fn read_file(path: &std::path::Path, progress: &mut dyn FnMut(f32)) -> Result<Sculpt, SculptError> {
    read_file_within(path, &MemoryLimit::NONE, progress)
}

/// The most memory a sculpt's clay may take as it is read.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryLimit {
    /// Bytes, as [`Field::estimated_bytes`] counts them.
    pub bytes: u64,
    /// What the limit is, for the refusal ("the memory budget of 4 GiB (…)").
    pub what: String,
}

impl MemoryLimit {
    /// No limit.
    pub const NONE: MemoryLimit = MemoryLimit { bytes: u64::MAX, what: String::new() };
}

/// [`read_file`] within `limit`: a file whose bricks alone (each key's bookkeeping, before any
/// sample) would take more is refused before a brick is read, and one whose clay grows past it
/// as it is read (bricks of samples of their own, which a file cannot announce) is refused
/// there, with what was read so far given back to the allocator.
pub fn read_file_within(
    path: &std::path::Path,
    limit: &MemoryLimit,
    progress: &mut dyn FnMut(f32),
) -> Result<Sculpt, SculptError> {
    let fail = |reason: String| SculptError { file: path.display().to_string(), reason };
    let mut source = FileSource::open(path, 1 << 20).map_err(fail)?;
    decode_from(&mut source, limit, progress).map_err(fail)
}

/// The refusal of a sculpt whose clay needs `bytes` (at least) of memory, over `limit`.
fn over_limit(limit: &MemoryLimit, bytes: f64, read: u64, bricks: u64) -> String {
    format!(
        "its clay would need more than {:.0} MB of memory ({read} of its {bricks} bricks read), over {}",
        bytes / 1e6,
        limit.what
    )
}

/// Reads and checks the 12-byte header: the version and the chunk count.
fn read_header(source: &mut dyn Source, buf: &mut Vec<u8>) -> Result<(u32, u32), String> {
    if source.len() < 12 {
        return Err("it is not an Argile sculpt (no ARGL header)".into());
    }
    let header: [u8; 12] = source.take(12, buf)?.try_into().expect("12 bytes");
    if &header[..4] != MAGIC {
        return Err("it is not an Argile sculpt (no ARGL header)".into());
    }
    let version = u32_at(&header, 4);
    if version == 0 || version > VERSION {
        return Err(format!(
            "it is format version {version}; this Argile reads versions 1 to {VERSION} (a newer Argile wrote it)"
        ));
    }
    let chunk_count = u32_at(&header, 8);
    // Every chunk takes at least its header: a count the file cannot hold is refused before
    // anything is allocated for it.
    if chunk_count > MAX_CHUNKS || u64::from(chunk_count) > (source.len() - 12) / CHUNK_HEADER as u64 {
        return Err(format!(
            "it declares {chunk_count} chunks, more than its {} bytes can hold",
            source.len()
        ));
    }
    Ok((version, chunk_count))
}

/// Reads the META chunk's bytes into an empty field of its settings.
fn read_meta(raw: &[u8]) -> Result<(Meta, Field), String> {
    let m: Meta = serde_json::from_slice(raw).map_err(|e| format!("its META chunk is not valid: {e}"))?;
    if m.format != "argile sculpt" || m.brick_size != BRICK_SIZE {
        return Err(format!("its META chunk describes `{}` with bricks of {}", m.format, m.brick_size));
    }
    if !(m.voxel_size_m.is_finite() && crate::field::VOXEL_SIZE_RANGE_M.contains(&m.voxel_size_m)) {
        let (lo, hi) = (crate::field::VOXEL_SIZE_RANGE_M.start(), crate::field::VOXEL_SIZE_RANGE_M.end());
        return Err(format!(
            "its voxel size {} m is not a usable size (Argile works from {lo} to {hi} m)",
            m.voxel_size_m
        ));
    }
    if !(m.iso > 0.0 && m.iso < 1.0) {
        return Err(format!("its iso-level {} is outside (0, 1)", m.iso));
    }
    let field = Field::new(m.voxel_size_m, m.iso);
    Ok((m, field))
}

/// Reads the bricks of a BRKS or BRKL chunk (chunk number `index`) into `field`, refusing a
/// brick `keys` already holds; with `block`, refusing a chunk that is not the bricks of that
/// block (level, block, count) as its index entry says. Returns how many of the bricks read
/// hold samples of their own (not one density throughout).
fn read_brick_chunk(
    tag: &[u8; 4],
    raw: &[u8],
    index: u32,
    block: Option<&IndexEntry>,
    keys: &mut HashSet<LevelKey>,
    field: &mut Field,
) -> Result<usize, String> {
    let (level, records) = if tag == b"BRKS" {
        (0, raw)
    } else {
        let level = raw.first().map_or(0, |&l| usize::from(l));
        if !(1..LEVELS).contains(&level) {
            return Err(format!("chunk {index} (BRKL) is of level {level}, not one of 1 to {}", LEVELS - 1));
        }
        (level, &raw[1..])
    };
    let name = tag.escape_ascii().to_string();
    if records.len() % BRICK_RECORD != 0 {
        return Err(format!("chunk {index} ({name}) holds a partial brick"));
    }
    let count = records.len() / BRICK_RECORD;
    if let Some(e) = block {
        if usize::from(e.level) != level || e.bricks as usize != count {
            return Err(format!(
                "chunk {index} ({name}) holds {count} bricks of level {level}; its index entry says {} of level {}",
                e.bricks, e.level
            ));
        }
    }
    let mut own = 0;
    for record in records.chunks_exact(BRICK_RECORD) {
        let (key, brick) = read_brick(record)?;
        if let Some(e) = block.filter(|e| block_of(key) != e.block) {
            return Err(format!("chunk {index} ({name}) holds brick {key}, outside its block {}", e.block));
        }
        let key = LevelKey::new(level, key);
        if !keys.insert(key) {
            return Err(format!("brick {key} is stored twice"));
        }
        field.insert_brick(key, brick);
        own += usize::from(field.level_density_range(key).is_some_and(|(lo, hi)| lo != hi));
    }
    Ok(own)
}

/// The undo history as HIST chunks give it, step by step.
#[derive(Default)]
struct HistoryReader {
    undo: Vec<HistoryStep>,
    redo: Vec<HistoryStep>,
    /// The (kind, index) of the step the last HIST chunk added to, and its keys.
    step_at: Option<(u8, u32)>,
    step_keys: HashSet<LevelKey>,
}

impl HistoryReader {
    /// Whether no HIST chunk was read yet.
    fn is_empty(&self) -> bool {
        self.step_at.is_none()
    }

    /// Adds HIST chunk number `index`.
    fn read(&mut self, raw: &[u8], index: u32) -> Result<(), String> {
        if raw.len() < 9 {
            return Err(format!("chunk {index} (HIST) is too short"));
        }
        let (kind, step) = (raw[0], u32_at(raw, 1));
        let follows = match self.step_at {
            _ if kind > 1 => false,
            None => step == 0,
            Some((k, s)) if k == kind => step == s || step == s + 1,
            Some((k, _)) => k < kind && step == 0,
        };
        if !follows {
            return Err(format!("chunk {index} (HIST) is history step {kind}/{step}, out of order"));
        }
        let stack = if kind == 0 { &mut self.undo } else { &mut self.redo };
        if self.step_at != Some((kind, step)) {
            stack.push(Vec::new());
            self.step_keys.clear();
        }
        self.step_at = Some((kind, step));
        let mut at = 9;
        let entries = read_entries(raw, &mut at, u32_at(raw, 5) as usize, &mut self.step_keys)
            .map_err(|e| format!("chunk {index} (HIST): {e}"))?;
        if at != raw.len() {
            return Err(format!("chunk {index} (HIST) has {} bytes after its last brick", raw.len() - at));
        }
        let step = stack.last_mut().expect("pushed above");
        step.extend(entries.into_iter().map(|(k, b)| (k, b.map(Arc::new))));
        Ok(())
    }
}

/// What the chunks before the bricks say: the settings, the scene, and (version 4) the index.
struct Head {
    version: u32,
    chunk_count: u32,
    meta: Meta,
    field: Field,
    scene_toml: Option<String>,
    tools: Vec<StoredTool>,
    view: Option<StoredView>,
    /// Version 5: the parts' layouts and the clay of those after the first.
    layouts: Vec<PartLayout>,
    others: Option<parts::PartsReader>,
    /// Version 6: the lattice held open.
    lattice: Option<StoredLattice>,
    /// Version 7: the symmetry.
    symmetry: Option<crate::parts::Symmetry>,
    /// Version 4: the brick chunks, and where the history starts, both from `base`.
    index: Option<(Vec<IndexEntry>, u64)>,
    /// The first byte after the index (version 4; before, it means nothing).
    base: u64,
    /// Chunks read.
    chunks_read: u32,
}

/// Reads the header, META, SCNE (if any) and, from version 4, INDX. Before version 4 it stops
/// after META or SCNE; the chunk it peeked at that is neither is left in `pending`.
fn read_head(
    source: &mut dyn Source,
    raw: &mut Vec<u8>,
    buf: &mut Vec<u8>,
    pending: &mut Option<Chunk>,
) -> Result<Head, String> {
    let (version, chunk_count) = read_header(source, buf)?;
    if chunk_count == 0 {
        return Err("it holds no META chunk".into());
    }
    let Chunk { tag, .. } = read_chunk_from(source, 0, raw, buf)?;
    if &tag != b"META" {
        return Err("its first chunk is not META".into());
    }
    let (meta, field) = read_meta(raw)?;
    let mut head = Head {
        version,
        chunk_count,
        meta,
        field,
        scene_toml: None,
        tools: Vec::new(),
        view: None,
        layouts: Vec::new(),
        others: None,
        lattice: None,
        symmetry: None,
        index: None,
        base: source.position(),
        chunks_read: 1,
    };
    while head.chunks_read < chunk_count {
        let index = head.chunks_read;
        let chunk = read_chunk_from(source, index, raw, buf)?;
        head.chunks_read += 1;
        match &chunk.tag {
            b"SCNE" if head.scene_toml.is_none() && index == 1 => {
                let text =
                    String::from_utf8(raw.clone()).map_err(|_| "its scene text is not UTF-8".to_owned())?;
                head.scene_toml = Some(text);
            }
            b"VIEW" if version >= 4 && head.view.is_none() => {
                if raw.len() > MAX_VIEW_BYTES {
                    return Err(format!(
                        "chunk {index} (VIEW) holds {} bytes, more than a view takes",
                        raw.len()
                    ));
                }
                head.view = Some(StoredView::read(raw, index)?);
            }
            b"TOOL" if version >= 4 => {
                let tool = StoredTool::read(raw, index)?;
                if head.tools.iter().any(|t| t.index == tool.index) {
                    return Err(format!("chunk {index} (TOOL) is a second copy of tool {}", tool.index));
                }
                let samples = head.tools.iter().map(|t| t.samples.len()).sum::<usize>() + tool.samples.len();
                if head.tools.len() == MAX_TOOLS || samples > MAX_TOOL_SAMPLES {
                    return Err(format!(
                        "chunk {index} (TOOL) makes more than {MAX_TOOLS} freeform tools or {MAX_TOOL_SAMPLES} samples of them"
                    ));
                }
                head.tools.push(tool);
            }
            b"PRTS" if version >= 5 && head.others.is_none() => {
                head.layouts = parts::read_layouts(raw, index)?;
                head.others = Some(parts::PartsReader::new(&head.layouts, head.meta.iso));
                if (head.layouts[0].voxel_size_m - head.meta.voxel_size_m).abs() > 1e-9 {
                    return Err(format!(
                        "chunk {index} (PRTS) gives the first part voxels of {} m; its META chunk says {} m",
                        head.layouts[0].voxel_size_m, head.meta.voxel_size_m
                    ));
                }
            }
            b"PART" if version >= 5 => {
                let Some(reader) = head.others.as_mut() else {
                    return Err(format!("chunk {index} (PART) comes before the parts are listed (PRTS)"));
                };
                reader.read(raw, index)?;
            }
            b"LATT" if version >= 6 && head.lattice.is_none() => {
                head.lattice = Some(StoredLattice::read(raw, index)?);
            }
            b"SYMM" if version >= 7 && head.symmetry.is_none() => {
                head.symmetry = Some(symmetry::read(raw, index)?);
            }
            b"INDX" if version >= 4 => {
                if let Some(lattice) = &head.lattice {
                    lattice.check_part(head.layouts.len().max(1))?;
                }
                let room = source.len() - source.position();
                let (entries, history_at) = read_index(raw, head.meta.bricks, room)?;
                if entries.len() as u64 > u64::from(chunk_count - head.chunks_read) {
                    return Err(format!(
                        "its index names {} brick chunks; its header counts {} chunks after the index",
                        entries.len(),
                        chunk_count - head.chunks_read
                    ));
                }
                head.index = Some((entries, history_at));
                head.base = source.position();
                return Ok(head);
            }
            _ if version >= 4 => {
                return Err(format!(
                    "chunk {index} (`{}`) is unknown, repeated or out of place before the index (INDX)",
                    chunk.name
                ));
            }
            _ => {
                *pending = Some(chunk);
                return Ok(head);
            }
        }
    }
    if version >= 4 {
        return Err("it holds no index (INDX chunk)".into());
    }
    Ok(head)
}

fn decode_from(
    source: &mut dyn Source,
    limit: &MemoryLimit,
    progress: &mut dyn FnMut(f32),
) -> Result<Sculpt, String> {
    let (mut buf, mut raw) = (Vec::new(), Vec::new());
    let mut pending = None;
    let Head {
        version,
        chunk_count,
        meta,
        mut field,
        scene_toml,
        tools,
        view,
        layouts,
        others,
        lattice,
        symmetry,
        index: directory,
        base,
        chunks_read,
    } = read_head(source, &mut raw, &mut buf, &mut pending)?;
    let mut keys: HashSet<LevelKey> = HashSet::new();
    let other_bricks = others.as_ref().map_or(0, parts::PartsReader::bricks) as f64;
    let lowest = Field::estimated_bytes(meta.bricks as f64 + other_bricks, other_bricks);
    if lowest > limit.bytes as f64 {
        return Err(over_limit(limit, lowest, 0, meta.bricks));
    }
    // Bricks read that hold samples of their own (not one density throughout).
    let mut own = 0u64;
    let mut history = HistoryReader::default();
    // Version 4: the index entry the next brick chunk must match.
    let mut next_entry = 0;
    let first = chunks_read - u32::from(pending.is_some());
    for index in first..chunk_count {
        let at = source.position() - base;
        let Chunk { tag, name } = match pending.take() {
            Some(chunk) => chunk,
            None => read_chunk_from(source, index, &mut raw, &mut buf)?,
        };
        match &tag {
            b"BRKS" | b"BRKL" if version >= 3 || &tag == b"BRKS" => {
                let entry = match &directory {
                    Some((entries, _)) => {
                        let e = entries.get(next_entry).filter(|e| e.offset == at);
                        let e =
                            e.ok_or_else(|| format!("chunk {index} ({name}) is not where the index says"))?;
                        next_entry += 1;
                        Some(*e)
                    }
                    None => None,
                };
                if !history.is_empty() {
                    return Err(format!("chunk {index} ({name}) follows the history"));
                }
                let read = read_brick_chunk(&tag, &raw, index, entry.as_ref(), &mut keys, &mut field)?;
                own += read as u64;
                let bytes = Field::estimated_bytes(meta.bricks as f64, own as f64);
                if bytes > limit.bytes as f64 {
                    return Err(over_limit(limit, bytes, keys.len() as u64, meta.bricks));
                }
            }
            b"HIST" if version >= 2 => {
                if let Some((entries, history_at)) = &directory {
                    if history.is_empty() && (next_entry != entries.len() || at != *history_at) {
                        return Err(format!("chunk {index} (HIST) is not where the index puts the history"));
                    }
                }
                history.read(&raw, index)?;
            }
            _ => return Err(format!("chunk {index} has an unknown or repeated tag `{name}`")),
        }
        progress(source.position() as f32 / source.len() as f32);
    }
    if source.position() != source.len() {
        return Err(format!("{} bytes follow its last chunk", source.len() - source.position()));
    }
    if let Some((entries, history_at)) = &directory {
        if next_entry != entries.len() {
            return Err(format!("its index names {} brick chunks; it holds {next_entry}", entries.len()));
        }
        if history.is_empty() && source.len() - base != *history_at {
            return Err("its index puts the history where the file does not end".into());
        }
    }
    if keys.len() as u64 != meta.bricks {
        return Err(format!("it holds {} bricks, its META chunk says {}", keys.len(), meta.bricks));
    }
    field.take_dirty();
    field.set_history(history.undo, history.redo);
    let others = others.map_or_else(Vec::new, parts::PartsReader::finish);
    Ok(Sculpt { field, scene_toml, tools, view, parts: layouts, others, lattice, symmetry })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_field() -> Field {
        let mut f = Field::new(0.0015, 0.5);
        f.edit_box(IVec3::new(-9, -3, 2), IVec3::new(12, 5, 17), true, |p, d, c| {
            *d = ((p.x + 2 * p.y - p.z) as f32 * 0.05).sin().abs();
            *c = [0.1 * (p.x & 7) as f32, 0.5, 0.25, 1.0];
        });
        f
    }

    #[test]
    fn a_sculpt_reads_back_bit_for_bit() {
        let f = sample_field();
        let bytes = encode(&f, Some("[camera]\nfov_y_deg = 30.0\n"), &mut |_| {});
        let back = decode(&bytes, "s.argile", &mut |_| {}).unwrap();
        assert!(back.field.same_samples(&f));
        assert_eq!(back.field.transform(), f.transform());
        assert_eq!(back.scene_toml.as_deref(), Some("[camera]\nfov_y_deg = 30.0\n"));
        assert!(bytes.len() < f.brick_count() * BRICK_RECORD, "compressed: {} bytes", bytes.len());
    }

    #[test]
    fn voxel_sizes_no_scene_allows_are_refused_in_files_too() {
        for voxel in [1e-30, 5e-5, 0.2] {
            let bytes = encode(&Field::new(voxel, 0.5), None, &mut |_| {});
            let e = decode(&bytes, "tiny.argile", &mut |_| {}).unwrap_err().to_string();
            assert!(e.contains("is not a usable size (Argile works from 0.0001 to 0.05 m)"), "{e}");
        }
        let bytes = encode(&Field::new(1e-4, 0.5), None, &mut |_| {});
        assert!(decode(&bytes, "fine.argile", &mut |_| {}).is_ok());
    }

    #[test]
    fn a_chunks_tag_is_quoted_escaped_never_raw() {
        // A sculpt whose only chunk is tagged with a terminal escape sequence and claims more
        // than the limit.
        let mut bytes = Vec::new();
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&VERSION.to_le_bytes());
        bytes.extend_from_slice(&1u32.to_le_bytes());
        bytes.extend_from_slice(b"\x1b[2J");
        bytes.extend_from_slice(&0xFFFF_FFF0u32.to_le_bytes());
        bytes.extend_from_slice(&0u32.to_le_bytes());
        bytes.extend_from_slice(&crc32fast::hash(&[]).to_le_bytes());
        let e = decode(&bytes, "hostile.argile", &mut |_| {}).unwrap_err().to_string();
        assert!(!e.contains('\x1b'), "{e:?}");
        assert!(e.contains("\\x1b[2J") && e.contains("hostile.argile"), "{e}");
        assert!(e.contains("over the"), "a claimed size is refused before any allocation: {e}");
    }

    #[test]
    fn brick_keys_beyond_the_range_are_refused_not_overflowed() {
        // Found by the fuzz run: a key of i32::MAX overflowed the lattice arithmetic.
        for far in [MAX_BRICK_COORD + 1, i32::MAX, i32::MIN] {
            let mut f = Field::new(0.001, 0.5);
            let mut brick = Brick::default();
            brick.set_density(0, 1.0);
            f.insert_brick(IVec3::new(1, 0, 0), brick.clone());
            // Version 3 (no index): the key's range is checked before its block is.
            let mut bytes = encode_with(&f, None, EncodeOptions { version: 3, history: false }, &mut |_| {});
            // Rewrite the stored key's y through the chunk layer: decompress, patch, recompress.
            let (meta_len, at) = (u32_at(&bytes, 20) as usize, 12);
            let brks = at + 16 + meta_len;
            let raw_len = u32_at(&bytes, brks + 4) as usize;
            let stored_len = u32_at(&bytes, brks + 8) as usize;
            let mut raw =
                lz4_flex::block::decompress(&bytes[brks + 16..brks + 16 + stored_len], raw_len).unwrap();
            raw[4..8].copy_from_slice(&far.to_le_bytes());
            bytes.truncate(brks);
            put_chunk(&mut bytes, *b"BRKS", &raw);
            let e = decode(&bytes, "far.argile", &mut |_| {}).unwrap_err().to_string();
            assert!(e.contains("beyond the field's range"), "{e}");
        }
        let mut f = Field::new(0.001, 0.5);
        let mut brick = Brick::default();
        brick.set_density(0, 1.0);
        f.insert_brick(IVec3::new(-MAX_BRICK_COORD, MAX_BRICK_COORD, 0), brick);
        let back = decode(&encode(&f, None, &mut |_| {}), "edge.argile", &mut |_| {}).unwrap();
        assert!(back.field.same_samples(&f), "the range's edge loads");
    }

    #[test]
    fn every_truncation_is_refused() {
        let bytes = encode(&sample_field(), None, &mut |_| {});
        for n in (0..bytes.len()).step_by(7).chain([bytes.len() - 1]) {
            let e = decode(&bytes[..n], "cut.argile", &mut |_| {}).unwrap_err().to_string();
            assert!(e.starts_with("sculpt file cut.argile: "), "{e}");
        }
    }

    #[test]
    fn flipped_bytes_are_refused() {
        let bytes = encode(&sample_field(), None, &mut |_| {});
        for i in (0..bytes.len()).step_by(53) {
            let mut bad = bytes.clone();
            bad[i] ^= 0x41;
            assert!(decode(&bad, "bad.argile", &mut |_| {}).is_err(), "a flip at byte {i} is caught");
        }
    }

    #[test]
    fn future_versions_and_absurd_claims_are_refused_by_name() {
        let bytes = encode(&sample_field(), None, &mut |_| {});
        let mut future = bytes.clone();
        future[4..8].copy_from_slice(&(VERSION + 1).to_le_bytes());
        let e = decode(&future, "f.argile", &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains(&format!("format version {}", VERSION + 1)) && e.contains("newer Argile"), "{e}");
        let mut many = bytes.clone();
        many[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = decode(&many, "m.argile", &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("more than its"), "{e}");
        let mut huge = bytes;
        huge[16..20].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = decode(&huge, "h.argile", &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("over the"), "{e}");
        let e = decode(b"PK\x03\x04 not a sculpt", "z.argile", &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("not an Argile sculpt"), "{e}");
    }

    #[test]
    fn version_1_and_no_history_leave_the_history_out() {
        let mut f = sample_field();
        f.begin_stroke();
        f.edit_box(IVec3::ZERO, IVec3::splat(3), true, |_, d, _| *d = 1.0);
        f.end_stroke();
        let with = encode(&f, None, &mut |_| {});
        assert!(decode(&with, "h.argile", &mut |_| {}).unwrap().field.undo().unwrap());
        for options in
            [EncodeOptions { version: 1, history: true }, EncodeOptions { version: 2, history: false }]
        {
            let bytes = encode_with(&f, None, options, &mut |_| {});
            assert_eq!(u32_at(&bytes, 4), options.version);
            assert!(bytes.len() < with.len(), "{options:?}");
            let mut back = decode(&bytes, "n.argile", &mut |_| {}).unwrap();
            assert!(back.field.same_samples(&f));
            assert!(!back.field.undo().unwrap(), "{options:?} stores no history");
        }
    }

    /// A field with a coarse sphere on level 2, a fine edit refining part of it, and the fine
    /// edit's undo step.
    fn levelled_field() -> Field {
        let mut f = Field::new(0.001, 0.5);
        f.edit_level(
            2,
            IVec3::splat(-12),
            IVec3::splat(12),
            true,
            |_, _, _| true,
            |q, d, c| {
                *d = (8.0 - q.as_vec3().length()).clamp(0.0, 1.0);
                *c = [0.2, 0.4, 0.6, 1.0];
            },
        );
        f.begin_stroke();
        f.edit_box(IVec3::new(20, -4, -4), IVec3::new(40, 4, 4), false, |p, d, c| {
            *d = (*d - 0.05 * (p.y & 3) as f32).max(0.0);
            *c = [0.9, 0.1, 0.1, 1.0];
        });
        f.end_stroke();
        f
    }

    #[test]
    fn every_level_and_its_history_read_back_bit_for_bit() {
        let f = levelled_field();
        assert!(f.level_brick_count(2) > 0 && f.brick_count() > 0);
        let bytes = encode(&f, None, &mut |_| {});
        let mut back = decode(&bytes, "l.argile", &mut |_| {}).unwrap().field;
        assert!(back.same_samples(&f));
        assert!(back.undo().unwrap());
        let mut undone = levelled_field();
        undone.undo().unwrap();
        assert!(back.same_samples(&undone));
    }

    #[test]
    fn older_versions_store_what_readers_of_the_finest_lattice_see() {
        let f = levelled_field();
        let bytes = encode_with(&f, None, EncodeOptions { version: 2, history: true }, &mut |_| {});
        let mut back = decode(&bytes, "v2.argile", &mut |_| {}).unwrap().field;
        assert_eq!(back.level_brick_count(2), 0, "version 2 holds the finest level alone");
        for p in [IVec3::ZERO, IVec3::new(21, 1, 0), IVec3::new(-29, 3, 2), IVec3::new(33, -2, 1)] {
            assert_eq!(back.sample(p), f.sample(p), "{p}");
        }
        assert!(!back.undo().unwrap(), "undo steps of the levelled bricks are left out");
    }

    #[test]
    fn a_coarse_level_beyond_the_field_is_refused() {
        let f = levelled_field();
        let bytes = encode(&f, None, &mut |_| {});
        // Rewrite the level byte of the first BRKL chunk to 9 through the chunk layer.
        let mut at = 12;
        loop {
            let (raw_len, stored_len) = (u32_at(&bytes, at + 4) as usize, u32_at(&bytes, at + 8) as usize);
            if &bytes[at..at + 4] == b"BRKL" {
                let mut raw =
                    lz4_flex::block::decompress(&bytes[at + 16..at + 16 + stored_len], raw_len).unwrap();
                raw[0] = 9;
                let mut bad = bytes[..at].to_vec();
                put_chunk(&mut bad, *b"BRKL", &raw);
                bad.extend_from_slice(&bytes[at + 16 + stored_len..]);
                let e = decode(&bad, "l.argile", &mut |_| {}).unwrap_err().to_string();
                assert!(e.contains("l.argile") && e.contains("level 9"), "{e}");
                return;
            }
            at += 16 + stored_len;
        }
    }

    #[test]
    fn a_version_1_file_with_history_chunks_is_refused() {
        let mut f = sample_field();
        f.begin_stroke();
        f.edit_box(IVec3::ZERO, IVec3::splat(3), true, |_, d, _| *d = 1.0);
        f.end_stroke();
        let mut bytes = encode_with(&f, None, EncodeOptions { version: 2, history: true }, &mut |_| {});
        bytes[4..8].copy_from_slice(&1u32.to_le_bytes());
        let e = decode(&bytes, "v1.argile", &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("unknown or repeated tag `HIST`"), "{e}");
    }

    #[test]
    fn an_empty_field_round_trips() {
        let f = Field::new(0.001, 0.5);
        let back = decode(&encode(&f, None, &mut |_| {}), "e.argile", &mut |_| {}).unwrap();
        assert_eq!(back.field.brick_count(), 0);
        assert!(back.scene_toml.is_none());
    }
}
