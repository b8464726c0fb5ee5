//! The native sculpt format (`.argile`): the clay, and the scene it was made in.
//!
//! Knows the field (it stores bricks) and nothing of Vulkan or devices.
//!
//! ## Layout, version 1
//!
//! ```text
//!  header  "ARGL" · version u32 · chunk count u32                      (little-endian)
//!  chunk   tag [u8; 4] · raw length u32 · stored length u32 · CRC-32 u32 · stored bytes
//!          …one after the other, `chunk count` of them
//!
//!  chunks  META  (first, once)  JSON: format, voxel size, iso-level, brick size, brick count
//!          SCNE  (at most once) the scene file's TOML text the sculpt was made in
//!          BRKS  (any number)   up to 512 bricks: per brick its key (3 × i32), then
//!                               512 densities (f32) and 512 linear RGBA colours (4 × f32)
//! ```
//!
//! - Every chunk's bytes are LZ4-compressed (`lz4_flex` block format) and carry the CRC-32 of
//!   the stored bytes; a reader checks the CRC before decompressing and the decompressed
//!   length against the header.
//! - Chunks bound the memory a reader commits before it has checked anything: a chunk is at
//!   most [`MAX_CHUNK_BYTES`] raw, so a large sculpt loads chunk by chunk, with progress.
//! - A reader refuses, with a sentence naming the file and the problem: a truncated file, a
//!   bad checksum, a future version, an unknown or repeated chunk, sizes or counts past the
//!   limits, a brick key twice, densities outside [0, 1] or non-finite samples. It never
//!   allocates what a header claims before checking the claim against the file's size.
//! - Files are written atomically by the caller (`app::write_atomically`).
//!
//! Later versions (resolution levels, undo history, freeform tools) add chunk tags; a reader
//! keeps reading every version it has shipped.

use std::collections::HashSet;

use serde::{Deserialize, Serialize};

use crate::field::{Brick, BrickKey, Field, BRICK_SIZE, BRICK_VOLUME};
use crate::math::IVec3;

/// The format version this build writes.
pub const VERSION: u32 = 1;
/// The largest raw chunk a reader accepts.
pub const MAX_CHUNK_BYTES: usize = 64 << 20;
/// The most chunks a file may declare.
pub const MAX_CHUNKS: u32 = 1 << 20;
/// Bricks per `BRKS` chunk written.
pub const BRICKS_PER_CHUNK: usize = 512;

const MAGIC: &[u8; 4] = b"ARGL";
const BRICK_RECORD: usize = 12 + BRICK_VOLUME * 4 + BRICK_VOLUME * 16;
const CHUNK_HEADER: usize = 16;

/// A sculpt as stored: the clay and the scene text it was made in.
#[derive(Debug)]
pub struct Sculpt {
    /// The clay.
    pub field: Field,
    /// The scene file's text, if the sculpt was made from one.
    pub scene_toml: Option<String>,
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

/// Encodes a sculpt; `progress` gets the fraction of bricks written.
pub fn encode(field: &Field, scene_toml: Option<&str>, progress: &mut dyn FnMut(f32)) -> Vec<u8> {
    let mut keys: Vec<BrickKey> = field.brick_keys().collect();
    keys.sort_unstable_by_key(|k| k.to_array());
    let meta = Meta {
        format: "argile sculpt".into(),
        voxel_size_m: field.transform().voxel_size_m,
        iso: field.iso(),
        brick_size: BRICK_SIZE,
        bricks: keys.len() as u64,
    };
    let mut chunks: Vec<([u8; 4], Vec<u8>)> =
        vec![(*b"META", serde_json::to_vec(&meta).expect("plain values serialise"))];
    if let Some(text) = scene_toml {
        chunks.push((*b"SCNE", text.as_bytes().to_vec()));
    }
    let groups = keys.chunks(BRICKS_PER_CHUNK);
    let group_count = groups.len().max(1);
    for (i, group) in groups.enumerate() {
        let mut raw = Vec::with_capacity(group.len() * BRICK_RECORD);
        for key in group {
            let brick = field.brick(*key).expect("listed keys are stored");
            for c in key.to_array() {
                raw.extend_from_slice(&c.to_le_bytes());
            }
            for d in brick.density.iter() {
                raw.extend_from_slice(&d.to_le_bytes());
            }
            for c in brick.colour.iter().flatten() {
                raw.extend_from_slice(&c.to_le_bytes());
            }
        }
        chunks.push((*b"BRKS", raw));
        progress((i + 1) as f32 / group_count as f32);
    }
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(chunks.len() as u32).to_le_bytes());
    for (tag, raw) in chunks {
        let stored = lz4_flex::block::compress(&raw);
        out.extend_from_slice(&tag);
        out.extend_from_slice(&(raw.len() as u32).to_le_bytes());
        out.extend_from_slice(&(stored.len() as u32).to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&stored).to_le_bytes());
        out.extend_from_slice(&stored);
    }
    out
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
}

/// Decodes a sculpt, refusing anything not written whole by [`encode`] (see the module docs);
/// `file` names the file in errors, `progress` gets the fraction of the file read.
pub fn decode(bytes: &[u8], file: &str, progress: &mut dyn FnMut(f32)) -> Result<Sculpt, SculptError> {
    let fail = |reason: String| SculptError { file: file.to_owned(), reason };
    if bytes.len() < 12 || &bytes[..4] != MAGIC {
        return Err(fail("it is not an Argile sculpt (no ARGL header)".into()));
    }
    let version = u32_at(bytes, 4);
    if version == 0 || version > VERSION {
        return Err(fail(format!(
            "it is format version {version}; this Argile reads versions 1 to {VERSION} (a newer Argile wrote it)"
        )));
    }
    let chunk_count = u32_at(bytes, 8);
    // Every chunk takes at least its header: a count the file cannot hold is refused before
    // anything is allocated for it.
    if chunk_count > MAX_CHUNKS || chunk_count as usize > (bytes.len() - 12) / CHUNK_HEADER {
        return Err(fail(format!(
            "it declares {chunk_count} chunks, more than its {} bytes can hold",
            bytes.len()
        )));
    }
    let mut at = 12;
    let mut meta: Option<Meta> = None;
    let mut field: Option<Field> = None;
    let mut scene_toml = None;
    let mut keys: HashSet<BrickKey> = HashSet::new();
    let mut raw = Vec::new();
    for index in 0..chunk_count {
        if bytes.len() - at < CHUNK_HEADER {
            return Err(fail(format!("it ends inside the header of chunk {index} (truncated)")));
        }
        let tag: [u8; 4] = bytes[at..at + 4].try_into().expect("4 bytes");
        let raw_len = u32_at(bytes, at + 4) as usize;
        let stored_len = u32_at(bytes, at + 8) as usize;
        let crc = u32_at(bytes, at + 12);
        let name = String::from_utf8_lossy(&tag).into_owned();
        at += CHUNK_HEADER;
        if raw_len > MAX_CHUNK_BYTES {
            return Err(fail(format!(
                "chunk {index} ({name}) claims {raw_len} bytes, over the {MAX_CHUNK_BYTES} limit"
            )));
        }
        if stored_len > bytes.len() - at {
            return Err(fail(format!("it ends inside chunk {index} ({name}) (truncated)")));
        }
        let stored = &bytes[at..at + stored_len];
        at += stored_len;
        if crc32fast::hash(stored) != crc {
            return Err(fail(format!("chunk {index} ({name}) fails its checksum: the file is damaged")));
        }
        raw.clear();
        raw.resize(raw_len, 0);
        match lz4_flex::block::decompress_into(stored, &mut raw) {
            Ok(n) if n == raw_len => {}
            _ => return Err(fail(format!("chunk {index} ({name}) does not decompress to its stated size"))),
        }
        match (&tag, &meta) {
            (b"META", None) if index == 0 => {
                let m: Meta = serde_json::from_slice(&raw)
                    .map_err(|e| fail(format!("its META chunk is not valid: {e}")))?;
                if m.format != "argile sculpt" || m.brick_size != BRICK_SIZE {
                    return Err(fail(format!(
                        "its META chunk describes `{}` with bricks of {}",
                        m.format, m.brick_size
                    )));
                }
                if !(m.voxel_size_m.is_finite() && m.voxel_size_m > 0.0 && m.voxel_size_m < 1.0) {
                    return Err(fail(format!("its voxel size {} m is not a usable size", m.voxel_size_m)));
                }
                if !(m.iso > 0.0 && m.iso < 1.0) {
                    return Err(fail(format!("its iso-level {} is outside (0, 1)", m.iso)));
                }
                field = Some(Field::new(m.voxel_size_m, m.iso));
                meta = Some(m);
            }
            (b"META", _) => return Err(fail(format!("chunk {index} is a second or late META chunk"))),
            (_, None) => return Err(fail("its first chunk is not META".into())),
            (b"SCNE", Some(_)) if scene_toml.is_none() => {
                let text =
                    String::from_utf8(raw.clone()).map_err(|_| fail("its scene text is not UTF-8".into()))?;
                scene_toml = Some(text);
            }
            (b"BRKS", Some(_)) => {
                if raw.len() % BRICK_RECORD != 0 {
                    return Err(fail(format!("chunk {index} (BRKS) holds a partial brick")));
                }
                let field = field.as_mut().expect("META came first");
                for record in raw.chunks_exact(BRICK_RECORD) {
                    let key = IVec3::new(
                        u32_at(record, 0) as i32,
                        u32_at(record, 4) as i32,
                        u32_at(record, 8) as i32,
                    );
                    if !keys.insert(key) {
                        return Err(fail(format!("brick {key} is stored twice")));
                    }
                    let mut brick = Brick::default();
                    let f = |i: usize| f32::from_le_bytes(record[i..i + 4].try_into().expect("4 bytes"));
                    for i in 0..BRICK_VOLUME {
                        let d = f(12 + 4 * i);
                        if !(0.0..=1.0).contains(&d) {
                            return Err(fail(format!("brick {key} holds density {d}, outside [0, 1]")));
                        }
                        brick.density[i] = d;
                        let c = std::array::from_fn(|j| f(12 + 4 * BRICK_VOLUME + 16 * i + 4 * j));
                        if c.iter().any(|v: &f32| !v.is_finite()) {
                            return Err(fail(format!("brick {key} holds a colour that is not a number")));
                        }
                        brick.colour[i] = c;
                    }
                    field.insert_brick(key, brick);
                }
            }
            _ => return Err(fail(format!("chunk {index} has an unknown or repeated tag `{name}`"))),
        }
        progress(at as f32 / bytes.len() as f32);
    }
    if at != bytes.len() {
        return Err(fail(format!("{} bytes follow its last chunk", bytes.len() - at)));
    }
    let (Some(meta), Some(mut field)) = (meta, field) else {
        return Err(fail("it holds no META chunk".into()));
    };
    if keys.len() as u64 != meta.bricks {
        return Err(fail(format!("it holds {} bricks, its META chunk says {}", keys.len(), meta.bricks)));
    }
    field.take_dirty();
    Ok(Sculpt { field, scene_toml })
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
        future[4..8].copy_from_slice(&7u32.to_le_bytes());
        let e = decode(&future, "f.argile", &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("format version 7") && e.contains("newer Argile"), "{e}");
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
    fn an_empty_field_round_trips() {
        let f = Field::new(0.001, 0.5);
        let back = decode(&encode(&f, None, &mut |_| {}), "e.argile", &mut |_| {}).unwrap();
        assert_eq!(back.field.brick_count(), 0);
        assert!(back.scene_toml.is_none());
    }
}
