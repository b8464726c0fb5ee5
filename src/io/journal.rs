//! The autosave journal's bytes: its header and one record per finished stroke (layout in the
//! module docs of `io`).

use std::collections::HashSet;

use super::{
    put_chunk, put_part_entries, read_chunk, read_part_entries, u32_at, PartBrick, BRICKS_PER_CHUNK,
};
use crate::field::{Brick, LevelKey};

const MAGIC: &[u8; 4] = b"ARGJ";
/// Version 2 journals entries of any part (version 1: of the first part alone); both are read.
const VERSION: u32 = 2;
/// Bytes of a journal's header.
pub(crate) const HEADER: usize = 20;
const RECORD_TAG: [u8; 4] = *b"STRK";

/// The header of a journal continuing from stroke `base`.
pub(crate) fn header(base: u64) -> [u8; HEADER] {
    let mut out = [0; HEADER];
    out[..4].copy_from_slice(MAGIC);
    out[4..8].copy_from_slice(&VERSION.to_le_bytes());
    out[8..16].copy_from_slice(&base.to_le_bytes());
    let crc = crc32fast::hash(&out[..16]);
    out[16..].copy_from_slice(&crc.to_le_bytes());
    out
}

/// The bytes of one record: stroke number `stroke`, the bricks it changed as they are now,
/// in parts of at most [`BRICKS_PER_CHUNK`] bricks (each part a chunk, the last one flagged).
pub(crate) fn record(stroke: u64, bricks: &[PartBrick]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut raw = Vec::new();
    let parts = bricks.len().div_ceil(BRICKS_PER_CHUNK).max(1);
    for (i, part) in bricks.chunks(BRICKS_PER_CHUNK).chain(bricks.is_empty().then_some(&[][..])).enumerate() {
        raw.clear();
        raw.extend_from_slice(&stroke.to_le_bytes());
        raw.push(u8::from(i + 1 == parts));
        raw.extend_from_slice(&(part.len() as u32).to_le_bytes());
        put_part_entries(&mut raw, part);
        put_chunk(&mut out, RECORD_TAG, &raw);
    }
    out
}

/// One stroke read back: its number and the bricks it left (`None`: emptied), each with its
/// part's index (0 the first).
#[derive(Debug)]
pub(crate) struct Record {
    pub(crate) stroke: u64,
    pub(crate) bricks: Vec<(u16, LevelKey, Option<Brick>)>,
}

/// Reads a journal's records in order. A journal whose header is not whole is refused; the
/// records are read while they are whole, checked and numbered `base + 1, base + 2, …`.
#[derive(Debug)]
pub(crate) struct Reader<'b> {
    bytes: &'b [u8],
    at: usize,
    index: u32,
    next: u64,
    raw: Vec<u8>,
    /// Why reading stopped before the end of the bytes, once it has.
    pub(crate) torn: Option<String>,
}

impl<'b> Reader<'b> {
    /// A reader over a journal's bytes; refuses a missing or damaged header.
    pub(crate) fn new(bytes: &'b [u8]) -> Result<Self, String> {
        if bytes.len() < HEADER || &bytes[..4] != MAGIC {
            return Err("it is not an autosave journal (no whole ARGJ header)".into());
        }
        if crc32fast::hash(&bytes[..16]) != u32_at(bytes, 16) {
            return Err("its header fails its checksum".into());
        }
        let version = u32_at(bytes, 4);
        if !(1..=VERSION).contains(&version) {
            return Err(format!(
                "it is journal version {version}; this Argile reads versions 1 to {VERSION}"
            ));
        }
        let base = u64::from_le_bytes(bytes[8..16].try_into().expect("8 bytes"));
        Ok(Self { bytes, at: HEADER, index: 0, next: base + 1, raw: Vec::new(), torn: None })
    }

    /// The stroke the journal continues from.
    pub(crate) fn base(&self) -> u64 {
        self.next - 1 - u64::from(self.index)
    }

    /// Reads the next record, all its parts.
    fn read(&mut self) -> Result<Record, String> {
        let mut bricks = Vec::new();
        let mut seen = HashSet::new();
        loop {
            let chunk = read_chunk(self.bytes, &mut self.at, self.index, &mut self.raw)?;
            if chunk.tag != RECORD_TAG {
                return Err(format!("record {} has the tag `{}`", self.index, chunk.name));
            }
            let raw = &self.raw;
            if raw.len() < 13 {
                return Err(format!("record {} is too short", self.index));
            }
            let stroke = u64::from_le_bytes(raw[..8].try_into().expect("8 bytes"));
            if stroke != self.next {
                return Err(format!(
                    "record {} is stroke {stroke}, stroke {} was expected",
                    self.index, self.next
                ));
            }
            let (last, count) = (raw[8], u32_at(raw, 9) as usize);
            let mut at = 13;
            let part = read_part_entries(raw, &mut at, count, &mut seen)
                .map_err(|e| format!("record {}: {e}", self.index))?;
            if at != raw.len() {
                return Err(format!(
                    "record {} has {} bytes after its last brick",
                    self.index,
                    raw.len() - at
                ));
            }
            bricks.extend(part);
            match last {
                0 => continue,
                1 => break,
                other => return Err(format!("record {} has a last-part flag {other}", self.index)),
            }
        }
        self.index += 1;
        self.next += 1;
        Ok(Record { stroke: self.next - 1, bricks })
    }
}

impl Iterator for Reader<'_> {
    type Item = Record;

    /// The next whole record; `None` at the end or at the first record that is torn, damaged
    /// or out of sequence (then `torn` says why, and nothing after it is read).
    fn next(&mut self) -> Option<Record> {
        if self.torn.is_some() || self.at == self.bytes.len() {
            return None;
        }
        let start = self.at;
        match self.read() {
            Ok(r) => Some(r),
            Err(e) => {
                // From the record's first part: a record is applied whole or not at all.
                self.at = start;
                self.torn = Some(format!(
                    "{e} ({} bytes from byte {} discarded)",
                    self.bytes.len() - self.at,
                    self.at
                ));
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::BRICK_VOLUME;
    use crate::math::IVec3;
    use std::sync::Arc;

    fn brick(seed: f32) -> Arc<Brick> {
        let mut b = Brick::default();
        for i in 0..BRICK_VOLUME {
            b.set_density(i, (i as f32 * 0.37 + seed).sin() * 0.5 + 0.5);
        }
        b.colour[5] = [seed, 0.5, 0.25, 1.0];
        Arc::new(b)
    }

    fn journal(strokes: u64) -> Vec<u8> {
        let mut out = header(7).to_vec();
        for s in 1..=strokes {
            let bricks = vec![
                (0, IVec3::new(s as i32, -1, 2).into(), Some(brick(s as f32))),
                (0, LevelKey::new(2, IVec3::new(0, 0, -(s as i32))), None),
                (3, LevelKey::new(1, IVec3::new(s as i32, 0, 0)), Some(brick(-(s as f32)))),
            ];
            out.extend_from_slice(&record(7 + s, &bricks));
        }
        out
    }

    #[test]
    fn records_read_back_in_order_bit_for_bit() {
        let bytes = journal(3);
        let mut reader = Reader::new(&bytes).unwrap();
        assert_eq!(reader.base(), 7);
        let records: Vec<Record> = reader.by_ref().collect();
        assert!(reader.torn.is_none());
        assert_eq!(records.iter().map(|r| r.stroke).collect::<Vec<_>>(), [8, 9, 10]);
        assert_eq!(records[1].bricks[0].2.as_ref(), Some(&*brick(2.0)));
        assert_eq!(records[2].bricks[1], (0, LevelKey::new(2, IVec3::new(0, 0, -3)), None));
        assert_eq!(
            records[2].bricks[2],
            (3, LevelKey::new(1, IVec3::new(3, 0, 0)), Some((*brick(-3.0)).clone()))
        );
    }

    #[test]
    fn a_torn_or_damaged_tail_ends_the_journal_at_the_last_whole_record() {
        let bytes = journal(3);
        let whole: Vec<usize> = {
            let mut ends = vec![HEADER];
            let mut at = HEADER;
            let mut raw = Vec::new();
            for i in 0..3 {
                read_chunk(&bytes, &mut at, i, &mut raw).unwrap();
                ends.push(at);
            }
            ends
        };
        for cut in HEADER..bytes.len() {
            let mut reader = Reader::new(&bytes[..cut]).unwrap();
            let n = reader.by_ref().count();
            let complete = whole.iter().filter(|&&e| e <= cut).count() - 1;
            assert_eq!(n, complete, "cut at {cut}");
            assert_eq!(reader.torn.is_some(), !whole.contains(&cut), "cut at {cut}");
        }
        for flip in (HEADER..bytes.len()).step_by(41) {
            let mut bad = bytes.clone();
            bad[flip] ^= 0x20;
            let mut reader = Reader::new(&bad).unwrap();
            let n = reader.by_ref().count();
            let damaged = whole.iter().filter(|&&e| e <= flip).count() - 1;
            assert_eq!(n, damaged, "flip at {flip}: the records before it stay, none after");
            assert!(reader.torn.is_some());
        }
    }

    #[test]
    fn a_record_of_many_parts_is_applied_whole_or_not_at_all() {
        let bricks: Vec<_> =
            (0..BRICKS_PER_CHUNK as i32 * 2 + 5).map(|i| (0, IVec3::new(i, 0, 0).into(), None)).collect();
        let mut bytes = header(0).to_vec();
        bytes.extend_from_slice(&record(1, &bricks[..3]));
        let first = bytes.len();
        bytes.extend_from_slice(&record(2, &bricks));
        let mut reader = Reader::new(&bytes).unwrap();
        let records: Vec<Record> = reader.by_ref().collect();
        assert_eq!(records.len(), 2);
        assert_eq!(records[1].bricks.len(), bricks.len());
        // Cut inside its last part: none of its parts is applied.
        let mut reader = Reader::new(&bytes[..bytes.len() - 10]).unwrap();
        assert_eq!(reader.by_ref().count(), 1);
        let torn = reader.torn.unwrap();
        assert!(torn.contains(&format!("from byte {first} discarded")), "{torn}");
    }

    #[test]
    fn a_damaged_header_or_a_gap_in_the_numbering_is_caught() {
        let mut bytes = journal(2);
        bytes[9] ^= 1;
        assert!(Reader::new(&bytes).unwrap_err().contains("checksum"));
        let mut gap = header(0).to_vec();
        gap.extend_from_slice(&record(1, &[]));
        gap.extend_from_slice(&record(3, &[]));
        let mut reader = Reader::new(&gap).unwrap();
        assert_eq!(reader.by_ref().count(), 1);
        assert!(reader.torn.as_deref().unwrap().contains("stroke 2 was expected"));
    }
}
