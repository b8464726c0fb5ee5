//! The `load` fuzz target's body (`fuzz/fuzz_targets/load_body.rs`) on the stable toolchain:
//! mutations of valid sculpt files for a bounded time. Half are byte-level (bit flips, byte
//! stores, truncations, insertions, deletions, extreme 32- and 64-bit values, splices of two
//! files); the other half change a chunk's decompressed contents, or drop, repeat or reorder
//! chunks, and write the file again with valid lengths, compression and checksums, so that
//! they reach the checks behind the CRC (which byte-level changes almost never pass).
//!
//! In the test suite it runs two seconds. For a longer run (the figure in `src/io/mod.rs`):
//!
//! ```sh
//! ARGILE_FUZZ_SECONDS=120 cargo test --test fuzz_load -- --nocapture
//! ```
//!
//! `ARGILE_FUZZ_SEED` picks the mutation stream (default 1). An input that panics is written
//! to `target/fuzz-findings/` and named in the failure; an input the loader takes more than a
//! second over fails too (a hang).

#[path = "../fuzz/fuzz_targets/load_body.rs"]
mod load_body;
mod sculpt_bytes;

use sculpt_bytes::{join, split, Chunks};

use std::time::{Duration, Instant};

use argile::field::Field;
use argile::io::{encode_with, EncodeOptions};
use argile::math::IVec3;

/// xorshift64*: a small, reproducible stream of mutation choices.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Valid sculpts to mutate: the committed version-1 file, and version 2 files with and without
/// history and scene text.
fn seeds() -> Vec<Vec<u8>> {
    let fixture = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/sculpt-v1.argile");
    let mut out = vec![std::fs::read(&fixture).expect("the committed version-1 sculpt")];
    let mut field = Field::new(0.002, 0.5);
    for (i, centre) in [IVec3::ZERO, IVec3::new(9, 3, -4)].into_iter().enumerate() {
        field.begin_stroke();
        field.edit_box(centre - IVec3::splat(5), centre + IVec3::splat(5), true, |p, d, c| {
            let r = (p - centre).as_vec3().length();
            *d = (0.5 - (r - 4.0) / 3.0).clamp(0.0, 1.0).max(*d);
            *c = [0.2 * i as f32, 0.5, 0.7, 1.0];
        });
        field.end_stroke();
    }
    let scene = Some("[[clay]]\nshape = \"sphere\"\nradius_m = 0.01\n");
    for (toml, history) in [(scene, true), (None, false)] {
        out.push(encode_with(&field, toml, EncodeOptions { version: 2, history }, &mut |_| {}));
    }
    // Version 4 (indexed), with a coarse level over several blocks, a fine stroke, a freeform
    // tool and a view.
    field.begin_stroke();
    field.edit_level(
        2,
        IVec3::new(-20, -4, -4),
        IVec3::new(20, 4, 4),
        true,
        |_, _, _| true,
        |q, d, c| {
            *d = (0.5 + 0.2 * (q.y as f32)).clamp(0.0, 1.0);
            *c = [0.3, 0.3, 0.8, 1.0];
        },
    );
    field.end_stroke();
    let tool = argile::io::StoredTool { index: 0, dims: [3, 2, 2], spacing_m: 0.002, samples: vec![0.5; 12] };
    let view = argile::io::StoredView {
        turn: [0.0, 0.0, 0.0, 1.0],
        distance_m: 0.3,
        scene_position_m: [0.0; 3],
        scene_rotation: [0.0, 0.0, 0.0, 1.0],
        convergence_factor: 1.0,
        interaxial_m: 0.065,
        lights_follow_viewer: false,
        auto_convergence: true,
        display_mode: "anaglyph".into(),
    };
    let parts =
        argile::io::SceneParts { toml: scene, tools: &[tool], view: Some(&view), ..Default::default() };
    out.push(argile::io::encode_sculpt(&field, parts, EncodeOptions::default(), &mut |_| {}));
    out
}

/// Points an index (INDX) at where its file's brick chunks and history now lie, so that
/// changes to the chunks reach the checks behind the index's.
fn reindex(chunks: &mut [([u8; 4], Vec<u8>)]) {
    let Some(at) = chunks.iter().position(|(tag, raw)| tag == b"INDX" && raw.len() >= 12) else { return };
    let mut offset = 0u64;
    let (mut entry, mut history) = (0, None);
    let sizes: Vec<([u8; 4], u64)> = chunks[at + 1..]
        .iter()
        .map(|(tag, raw)| (*tag, 16 + lz4_flex::block::compress(raw).len() as u64))
        .collect();
    let index = &mut chunks[at].1;
    for (tag, size) in sizes {
        match &tag {
            b"BRKS" | b"BRKL" if 12 + 25 * (entry + 1) <= index.len() => {
                index[12 + 25 * entry + 17..12 + 25 * (entry + 1)].copy_from_slice(&offset.to_le_bytes());
                entry += 1;
            }
            b"HIST" if history.is_none() => history = Some(offset),
            _ => {}
        }
        offset += size;
    }
    index[4..12].copy_from_slice(&history.unwrap_or(offset).to_le_bytes());
}

/// A structure-aware mutation: a seed's chunks changed inside, or dropped, repeated or
/// reordered, written back with valid checksums (and, half the time, a valid index).
fn mutate_chunks(rng: &mut Rng, seeds: &[Chunks]) -> Vec<u8> {
    let (header, mut chunks) = seeds[rng.below(seeds.len())].clone();
    for _ in 0..1 + rng.below(3) {
        let n = chunks.len();
        match rng.below(6) {
            0 if n > 1 => {
                chunks.remove(rng.below(n));
            }
            1 if n > 0 => {
                let c = chunks[rng.below(n)].clone();
                chunks.insert(rng.below(n + 1), c);
            }
            2 if n > 1 => chunks.swap(rng.below(n), rng.below(n)),
            _ if n > 0 => {
                let (_, raw) = &mut chunks[rng.below(n)];
                *raw = mutate(rng, &[std::mem::take(raw)]);
            }
            _ => {}
        }
    }
    if rng.below(2) == 0 {
        reindex(&mut chunks);
    }
    join(header, &chunks)
}

fn mutate(rng: &mut Rng, seeds: &[Vec<u8>]) -> Vec<u8> {
    let mut data = seeds[rng.below(seeds.len())].clone();
    for _ in 0..1 + rng.below(4) {
        let len = data.len();
        match rng.below(8) {
            0 if len > 0 => {
                let i = rng.below(len);
                data[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let i = rng.below(len);
                data[i] = rng.next() as u8;
            }
            2 => data.truncate(rng.below(len + 1)),
            3 => {
                let at = rng.below(len + 1);
                let n = 1 + rng.below(16);
                let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
                data.splice(at..at, bytes);
            }
            4 if len > 0 => {
                let at = rng.below(len);
                let end = (at + 1 + rng.below(64)).min(len);
                data.drain(at..end);
            }
            5 if len >= 4 => {
                // Counts, sizes and lengths are little-endian integers: make one absurd.
                let extremes = [0u32, 1, 0x7fff_ffff, 0x8000_0000, u32::MAX, 0xffff];
                let v = extremes[rng.below(extremes.len())].to_le_bytes();
                let at = rng.below(len - 3);
                data[at..at + 4].copy_from_slice(&v);
            }
            6 if len >= 8 => {
                let v = [0u64, u64::MAX, 1 << 40, i64::MAX as u64][rng.below(4)].to_le_bytes();
                let at = rng.below(len - 7);
                data[at..at + 8].copy_from_slice(&v);
            }
            _ => {
                // Splice: the head of this file, the tail of another.
                let other = &seeds[rng.below(seeds.len())];
                let cut = rng.below(len + 1);
                let from = rng.below(other.len() + 1);
                data.truncate(cut);
                data.extend_from_slice(&other[from..]);
            }
        }
    }
    data
}

fn keep_finding(data: &[u8], n: u64) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-findings");
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(format!("load-{n}.argile"));
    let _ = std::fs::write(&path, data);
    path
}

#[test]
fn the_loader_survives_mutated_sculpt_files() {
    let seconds: f64 = std::env::var("ARGILE_FUZZ_SECONDS").ok().and_then(|s| s.parse().ok()).unwrap_or(2.0);
    let seed: u64 = std::env::var("ARGILE_FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    let seeds = seeds();
    for s in &seeds {
        assert!(argile::io::decode(s, "seed.argile", &mut |_| {}).is_ok(), "every seed loads");
    }
    let structured: Vec<Chunks> = seeds.iter().map(|s| split(s)).collect();
    for (s, c) in seeds.iter().zip(&structured) {
        assert_eq!(&join(c.0, &c.1), s, "the seeds split and join back");
    }
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let deadline = Instant::now() + Duration::from_secs_f64(seconds);
    let (mut runs, mut loaded) = (0u64, 0u64);
    while Instant::now() < deadline {
        let data =
            if runs % 2 == 0 { mutate(&mut rng, &seeds) } else { mutate_chunks(&mut rng, &structured) };
        let started = Instant::now();
        let outcome = std::panic::catch_unwind(|| load_body::check(&data));
        if outcome.is_err() {
            panic!("the loader panicked on {}", keep_finding(&data, runs).display());
        }
        if started.elapsed() > Duration::from_secs(1) {
            panic!("the loader took {:?} over {}", started.elapsed(), keep_finding(&data, runs).display());
        }
        loaded += u64::from(argile::io::decode(&data, "m.argile", &mut |_| {}).is_ok());
        runs += 1;
    }
    println!("{runs} mutated sculpt files in {seconds} s (seed {seed}): {loaded} loaded, none panicked");
    assert!(runs > 0);
}
