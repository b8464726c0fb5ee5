//! Reading a sculpt lazily: its directory first, then the bricks where they are wanted.
//!
//! Opening a version-4 sculpt reads its header, META, SCNE and INDX chunks: the settings, the
//! scene, and where each block's bricks lie. A caller then loads the chunks it needs (a box
//! of the finest lattice, a level, a chunk), and [`LazySculpt::finish`] reads the rest and
//! the history and checks the whole file as [`super::read_file`] does.
//!
//! Every chunk read is checked as a whole-file read checks it (checksum, sizes, samples), and
//! against its index entry (level, block, brick count): a chunk that is not what the index
//! says is refused with a sentence naming the file. After a refusal the sculpt stays refused.

use std::collections::HashSet;

use super::{
    decode_from, read_brick_chunk, read_chunk_from, read_head, Chunk, FileSource, Head, HistoryReader,
    IndexEntry, Sculpt, SculptError, Slice, Source, StoredTool, StoredView, BLOCK_SHIFT,
};
use crate::field::{Field, BRICK_SIZE};
use crate::math::IVec3;

/// One brick chunk of a sculpt file, as its index tells of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChunkInfo {
    /// The level of its bricks (0: the finest).
    pub level: usize,
    /// Its block: the bricks of the level whose keys shifted right by 3 are this.
    pub block: IVec3,
    /// Bricks it holds (1 to 512).
    pub bricks: u32,
}

impl ChunkInfo {
    /// Where its block's samples lie on the finest lattice: the lowest and highest
    /// (inclusive), its level's voxel apart.
    pub fn samples(&self) -> (IVec3, IVec3) {
        let step = 1 << self.level;
        let side = BRICK_SIZE << BLOCK_SHIFT;
        let lo = self.block * side * step;
        (lo, lo + IVec3::splat((side - 1) * step))
    }

    /// The points of the finest lattice whose values its samples take part in (lowest and
    /// highest, inclusive): its block's samples, and as far on each side as interpolation
    /// between them and the next sample of its level reaches.
    pub fn reach(&self) -> (IVec3, IVec3) {
        let ((lo, hi), apron) = (self.samples(), IVec3::splat((1 << self.level) - 1));
        (lo - apron, hi + apron)
    }

    fn from_entry(e: &IndexEntry) -> Self {
        Self { level: usize::from(e.level), block: e.block, bricks: e.bricks }
    }
}

/// A sculpt file opened for reading part by part (see the module docs).
pub struct LazySculpt {
    file: String,
    source: Box<dyn Source>,
    version: u32,
    chunk_count: u32,
    bricks: u64,
    field: Field,
    scene_toml: Option<String>,
    tools: Vec<StoredTool>,
    view: Option<StoredView>,
    parts: Vec<super::PartLayout>,
    others: Vec<Field>,
    lattice: Option<super::StoredLattice>,
    symmetry: Option<crate::parts::Symmetry>,
    entries: Vec<IndexEntry>,
    chunks: Vec<ChunkInfo>,
    /// Per chunk, its bytes in the file once it has been read.
    read: Vec<Option<u64>>,
    /// Where the history starts, from `base`.
    history_at: u64,
    /// The first byte after the index.
    base: u64,
    /// The file number of the first brick chunk.
    first_chunk: u32,
    bytes_read: u64,
    /// Whether the file has no index and was read whole at opening.
    whole: bool,
    refused: Option<String>,
    raw: Vec<u8>,
    buf: Vec<u8>,
}

impl std::fmt::Debug for LazySculpt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LazySculpt")
            .field("file", &self.file)
            .field("version", &self.version)
            .field("chunks", &self.chunks.len())
            .field("chunks_left", &self.chunks_left())
            .field("bytes_read", &self.bytes_read)
            .finish_non_exhaustive()
    }
}

impl LazySculpt {
    /// Opens the sculpt file at `path`, reading its settings, scene and index (a file of
    /// version 1 to 3 has no index: it is read whole, as [`super::read_file`] reads it).
    pub fn open(path: &std::path::Path) -> Result<Self, SculptError> {
        let file = path.display().to_string();
        match FileSource::open(path, 0) {
            Ok(source) => Self::from_source(Box::new(source), file),
            Err(reason) => Err(SculptError { file, reason }),
        }
    }

    /// [`LazySculpt::open`] on the bytes of a file; `file` names it in errors.
    pub fn from_bytes(bytes: Vec<u8>, file: &str) -> Result<Self, SculptError> {
        Self::from_source(Box::new(Slice { bytes, at: 0 }), file.to_owned())
    }

    fn from_source(mut source: Box<dyn Source>, file: String) -> Result<Self, SculptError> {
        let fail = |reason: String| SculptError { file: file.clone(), reason };
        let (mut raw, mut buf) = (Vec::new(), Vec::new());
        let head = read_head(&mut *source, &mut raw, &mut buf, &mut None).map_err(fail)?;
        let Head {
            version,
            chunk_count,
            meta,
            field,
            scene_toml,
            tools,
            view,
            layouts,
            others,
            lattice,
            symmetry,
            index,
            base,
            chunks_read,
        } = head;
        let mut sculpt = Self {
            file: file.clone(),
            source,
            version,
            chunk_count,
            bricks: meta.bricks,
            field,
            scene_toml,
            tools,
            view,
            parts: layouts,
            others: others.map_or_else(Vec::new, super::parts::PartsReader::finish),
            lattice,
            symmetry,
            entries: Vec::new(),
            chunks: Vec::new(),
            read: Vec::new(),
            history_at: 0,
            base,
            first_chunk: chunks_read,
            bytes_read: 0,
            whole: false,
            refused: None,
            raw,
            buf,
        };
        match index {
            Some((entries, history_at)) => {
                sculpt.bytes_read = sculpt.source.position();
                sculpt.chunks = entries.iter().map(ChunkInfo::from_entry).collect();
                sculpt.read = vec![None; entries.len()];
                sculpt.entries = entries;
                sculpt.history_at = history_at;
            }
            None => {
                sculpt.source.seek(0).map_err(fail)?;
                let whole =
                    decode_from(&mut *sculpt.source, &super::MemoryLimit::NONE, &mut |_| {}).map_err(fail)?;
                sculpt.bytes_read = sculpt.source.len();
                sculpt.field = whole.field;
                sculpt.tools = whole.tools;
                sculpt.view = whole.view;
                sculpt.parts = whole.parts;
                sculpt.others = whole.others;
                sculpt.lattice = whole.lattice;
                sculpt.symmetry = whole.symmetry;
                sculpt.whole = true;
            }
        }
        Ok(sculpt)
    }

    /// The format version of the file.
    pub fn version(&self) -> u32 {
        self.version
    }

    /// The file's size in bytes.
    pub fn file_len(&self) -> u64 {
        self.source.len()
    }

    /// Bytes of the file read so far (headers and stored chunk bytes).
    pub fn bytes_read(&self) -> u64 {
        self.bytes_read
    }

    /// The bricks the whole sculpt holds, on every level.
    pub fn brick_count(&self) -> u64 {
        self.bricks
    }

    /// The parts' layouts (none: one part at rest) and the clay of those after the first, read
    /// whole with the file's head.
    pub fn parts(&self) -> (&[super::PartLayout], &[Field]) {
        (&self.parts, &self.others)
    }

    /// The lattice held open when it was saved.
    pub fn lattice(&self) -> Option<&super::StoredLattice> {
        self.lattice.as_ref()
    }

    /// The symmetry the strokes acted through when it was saved (version 7).
    pub fn symmetry(&self) -> Option<&crate::parts::Symmetry> {
        self.symmetry.as_ref()
    }

    /// The scene file's text, if the sculpt was made from one.
    pub fn scene_toml(&self) -> Option<&str> {
        self.scene_toml.as_deref()
    }

    /// The scene's freeform tools as the file stores them.
    pub fn tools(&self) -> &[StoredTool] {
        &self.tools
    }

    /// The clay loaded so far, with the sculpt's settings (its points beyond the loaded chunks
    /// read the coarser levels loaded, or are empty). Its dirty set holds what was loaded. A
    /// file without an index is loaded whole, its history with it.
    pub fn field(&self) -> &Field {
        &self.field
    }

    /// The brick chunks, in file order (none for a file without an index: it is loaded).
    pub fn chunks(&self) -> &[ChunkInfo] {
        &self.chunks
    }

    /// The undo history's chunks and bytes in the file (read by [`LazySculpt::finish`]; a
    /// file without an index has its history read with it: `None`).
    pub fn history_size(&self) -> Option<(u32, u64)> {
        let chunks = self.chunk_count - self.first_chunk - self.chunks.len() as u32;
        (!self.whole).then(|| (chunks, self.source.len() - self.base - self.history_at))
    }

    /// Whether chunk `i` has been loaded.
    ///
    /// # Panics
    /// If `i` is not below `chunks().len()` (a caller bug).
    pub fn is_loaded(&self, i: usize) -> bool {
        self.read[i].is_some()
    }

    /// The chunks not loaded yet.
    pub fn chunks_left(&self) -> usize {
        self.read.iter().filter(|r| r.is_none()).count()
    }

    /// Loads chunk `i` (nothing if it is loaded), checking it against its index entry.
    ///
    /// # Panics
    /// If `i` is not below `chunks().len()` (a caller bug).
    pub fn load_chunk(&mut self, i: usize) -> Result<(), SculptError> {
        if let Some(reason) = &self.refused {
            return Err(SculptError { file: self.file.clone(), reason: reason.clone() });
        }
        if self.read[i].is_some() {
            return Ok(());
        }
        let number = self.first_chunk + i as u32;
        let entry = self.entries[i];
        let result = self.source.seek(self.base + entry.offset).and_then(|()| {
            let Chunk { tag, name } =
                read_chunk_from(&mut *self.source, number, &mut self.raw, &mut self.buf)?;
            if &tag != b"BRKS" && &tag != b"BRKL" {
                return Err(format!("chunk {number} ({name}) is not the brick chunk its index says"));
            }
            let mut keys = HashSet::new();
            read_brick_chunk(&tag, &self.raw, number, Some(&entry), &mut keys, &mut self.field)
        });
        match result {
            Ok(_) => {
                let len = self.source.position() - (self.base + entry.offset);
                self.bytes_read += len;
                self.read[i] = Some(len);
                Ok(())
            }
            Err(reason) => {
                self.refused = Some(reason.clone());
                Err(SculptError { file: self.file.clone(), reason })
            }
        }
    }

    /// Loads every chunk whose samples reach a point of the finest lattice in `lo..=hi`, so
    /// that the loaded clay reads at each such point as the whole sculpt does. Returns the
    /// chunks it read.
    pub fn load_box(&mut self, lo: IVec3, hi: IVec3) -> Result<usize, SculptError> {
        let wanted: Vec<usize> = (0..self.chunks.len())
            .filter(|&i| {
                let (a, b) = self.chunks[i].reach();
                self.read[i].is_none() && a.cmple(hi).all() && b.cmpge(lo).all()
            })
            .collect();
        for &i in &wanted {
            self.load_chunk(i)?;
        }
        Ok(wanted.len())
    }

    /// Loads the chunks of `level`. Returns the chunks it read.
    pub fn load_level(&mut self, level: usize) -> Result<usize, SculptError> {
        let wanted: Vec<usize> = (0..self.chunks.len())
            .filter(|&i| self.chunks[i].level == level && self.read[i].is_none())
            .collect();
        for &i in &wanted {
            self.load_chunk(i)?;
        }
        Ok(wanted.len())
    }

    /// Loads what is left (the bricks, then the undo history), checks the file whole (its
    /// chunks follow one another as the index says, nothing follows the last) and gives the
    /// sculpt, as [`super::read_file`] would have; `progress` gets the fraction of the chunks
    /// loaded.
    pub fn finish(mut self, progress: &mut dyn FnMut(f32)) -> Result<Sculpt, SculptError> {
        if self.whole {
            progress(1.0);
            return Ok(Sculpt {
                field: self.field,
                scene_toml: self.scene_toml,
                tools: self.tools,
                view: self.view,
                parts: self.parts,
                others: self.others,
                lattice: self.lattice,
                symmetry: self.symmetry,
            });
        }
        let total = self.chunks.len().max(1) as f32;
        for i in 0..self.chunks.len() {
            self.load_chunk(i)?;
            progress((i + 1) as f32 / total);
        }
        let fail = |reason: String| SculptError { file: self.file.clone(), reason };
        for (i, (e, len)) in self.entries.iter().zip(&self.read).enumerate() {
            let end = e.offset + len.expect("every chunk is loaded");
            let (next, what) = match self.entries.get(i + 1) {
                Some(n) => (n.offset, "the next chunk"),
                None => (self.history_at, "the history"),
            };
            if end != next {
                return Err(fail(format!(
                    "chunk {} ends at byte {end} after the index, where the index puts {what} at {next}",
                    self.first_chunk + i as u32
                )));
            }
        }
        let mut history = HistoryReader::default();
        let start = self.base + self.history_at;
        self.source.seek(start).map_err(fail)?;
        for number in self.first_chunk + self.chunks.len() as u32..self.chunk_count {
            let Chunk { tag, name } =
                read_chunk_from(&mut *self.source, number, &mut self.raw, &mut self.buf).map_err(fail)?;
            if &tag != b"HIST" {
                return Err(fail(format!("chunk {number} ({name}) is not where the index puts it")));
            }
            history.read(&self.raw, number).map_err(fail)?;
        }
        let end = self.source.position();
        self.bytes_read += end - start;
        if end != self.source.len() {
            return Err(fail(format!("{} bytes follow its last chunk", self.source.len() - end)));
        }
        let mut field = self.field;
        field.take_dirty();
        field.set_history(history.undo, history.redo);
        Ok(Sculpt {
            field,
            scene_toml: self.scene_toml,
            tools: self.tools,
            view: self.view,
            parts: self.parts,
            others: self.others,
            lattice: self.lattice,
            symmetry: self.symmetry,
        })
    }
}
