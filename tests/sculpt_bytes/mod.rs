//! Sculpt files taken apart into their chunks and put back together, for the tests that
//! change a file behind its checksums (see the layout in `src/io/mod.rs`).

/// A sculpt file as its header and its chunks (tag, decompressed bytes).
pub type Chunks = ([u8; 12], Vec<([u8; 4], Vec<u8>)>);

fn u32_at(b: &[u8], at: usize) -> usize {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize
}

/// Splits a valid sculpt file into its chunks.
pub fn split(file: &[u8]) -> Chunks {
    let header: [u8; 12] = file[..12].try_into().unwrap();
    let mut chunks = Vec::new();
    let mut at = 12;
    for _ in 0..u32_at(file, 8) {
        let tag: [u8; 4] = file[at..at + 4].try_into().unwrap();
        let (raw_len, stored_len) = (u32_at(file, at + 4), u32_at(file, at + 8));
        let stored = &file[at + 16..at + 16 + stored_len];
        chunks.push((tag, lz4_flex::block::decompress(stored, raw_len).unwrap()));
        at += 16 + stored_len;
    }
    (header, chunks)
}

/// Writes chunks back as a file whose chunk count, lengths, compression and checksums are
/// all valid.
pub fn join(header: [u8; 12], chunks: &[([u8; 4], Vec<u8>)]) -> Vec<u8> {
    let mut out = header.to_vec();
    out[8..12].copy_from_slice(&(chunks.len() as u32).to_le_bytes());
    for (tag, raw) in chunks {
        let stored = lz4_flex::block::compress(raw);
        out.extend_from_slice(tag);
        out.extend_from_slice(&(raw.len() as u32).to_le_bytes());
        out.extend_from_slice(&(stored.len() as u32).to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&stored).to_le_bytes());
        out.extend_from_slice(&stored);
    }
    out
}
