//! The native sculpt file: bit-exact round trips of random sculpts, the command line saving a
//! scene's clay and exporting it again, damaged files refused by name.

use std::path::PathBuf;
use std::process::Command;

use argile::app::load_sculpt;
use argile::field::Field;
use argile::io::{decode, encode, encode_with, EncodeOptions, LazySculpt};
use argile::math::{IVec3, Vec3};
use argile::tool::{stamp_sphere, Action};
use proptest::prelude::*;

mod sculpt_bytes;

use sculpt_bytes::{join, split};

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tests/toothpaste.toml");
/// A scene with clay on the finest level beside clay on coarser ones.
const LEVELS_SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tests/levels-meet.toml");

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("argile-sculpt-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn argile(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_argile")).args(args).output().unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 24,
        rng_seed: proptest::test_runner::RngSeed::Fixed(5),
        ..ProptestConfig::default()
    })]

    /// Any sculpt of random stamps reads back bit for bit, colours included.
    #[test]
    fn random_sculpts_round_trip_bit_for_bit(
        stamps in proptest::collection::vec(
            (-0.03f32..0.03, -0.03f32..0.03, -0.03f32..0.03, 0.001f32..0.01, any::<bool>(), 0.0f32..1.0),
            1..12,
        )
    ) {
        let mut f = Field::new(0.001, 0.5);
        for (x, y, z, r, remove, hue) in stamps {
            let action = if remove { Action::Remove } else { Action::Add };
            stamp_sphere(&mut f, Vec3::new(x, y, z), r, action, [hue, 1.0 - hue, 0.5, 1.0]);
        }
        let back = decode(&encode(&f, None, &mut |_| {}), "p.argile", &mut |_| {}).unwrap();
        prop_assert!(back.field.same_samples(&f));
    }
}

#[test]
fn a_saved_scene_exports_the_same_mesh_as_the_scene() {
    let dir = temp_dir("cli");
    let sculpt = dir.join("paste.argile");
    let s = sculpt.to_str().unwrap();
    let out = argile(&["save", SCENE, "--out", s]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("bricks"));
    let again = argile(&["save", SCENE, "--out", s]);
    assert!(!again.status.success() && String::from_utf8_lossy(&again.stderr).contains("pass --force"));
    assert!(argile(&["save", SCENE, "--out", s, "--force"]).status.success());

    let loaded = load_sculpt(&sculpt).unwrap();
    assert_eq!(
        loaded.scene_toml.unwrap(),
        std::fs::read_to_string(SCENE).unwrap(),
        "the scene travels along"
    );

    let (from_scene, from_sculpt) = (dir.join("a.stl"), dir.join("b.stl"));
    assert!(argile(&["export", SCENE, "--format", "stl", "--out", from_scene.to_str().unwrap()])
        .status
        .success());
    let out = argile(&["export", s, "--format", "stl", "--out", from_sculpt.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read(&from_scene).unwrap(), std::fs::read(&from_sculpt).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_damaged_sculpt_is_refused_with_its_name() {
    let dir = temp_dir("damaged");
    let sculpt = dir.join("d.argile");
    assert!(argile(&["save", SCENE, "--out", sculpt.to_str().unwrap()]).status.success());
    let mut bytes = std::fs::read(&sculpt).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0xff;
    std::fs::write(&sculpt, &bytes).unwrap();
    let out = argile(&[
        "export",
        sculpt.to_str().unwrap(),
        "--format",
        "obj",
        "--out",
        dir.join("x.obj").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("sculpt file {}", sculpt.display())) && err.contains("checksum"), "{err}");
    assert!(!dir.join("x.obj").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The field of `tests/fixtures/sculpt-v1.argile`: exact in `f32` (small integer ratios), so
/// the comparison holds on any machine. The file also stores colours at empty samples, which
/// edits no longer keep: compare with [`same_matter`].
fn fixture_field() -> Field {
    let mut f = Field::new(0.002, 0.5);
    f.edit_box(
        argile::math::IVec3::new(-12, -5, -9),
        argile::math::IVec3::new(10, 13, 6),
        true,
        |p, d, c| {
            *d = ((p.x * 7 + p.y * 3 + p.z * 5).rem_euclid(17) as f32 / 16.0).min(1.0);
            *c = [p.x.rem_euclid(4) as f32 / 4.0, p.y.rem_euclid(8) as f32 / 8.0, 0.5, 1.0];
        },
    );
    f
}

/// Whether `a` and `b` hold the same bricks, bit-identical densities, and bit-identical colours
/// wherever there is matter (an empty sample's colour means nothing).
fn same_matter(a: &Field, b: &Field) -> bool {
    let keys = |f: &Field| f.brick_keys().collect::<std::collections::HashSet<_>>();
    keys(a) == keys(b)
        && a.brick_keys().all(|k| {
            let (x, y) = (a.brick(k).unwrap(), b.brick(k).unwrap());
            (0..argile::field::BRICK_VOLUME).all(|i| {
                x.density[i] == y.density[i]
                    && (x.density[i] == 0 || x.colour[i].map(f32::to_bits) == y.colour[i].map(f32::to_bits))
            })
        })
}

const FIXTURE_V1: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/sculpt-v1.argile");
/// The same sculpt as the version-1 fixture, written by format version 2.
const FIXTURE_V2: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/sculpt-v2.argile");

#[test]
fn a_version_1_file_still_loads() {
    let bytes = std::fs::read(FIXTURE_V1).unwrap();
    assert_eq!(&bytes[4..8], &1u32.to_le_bytes(), "the fixture is format version 1");
    let mut sculpt = load_sculpt(std::path::Path::new(FIXTURE_V1)).unwrap();
    assert!(same_matter(&sculpt.field, &fixture_field()));
    assert_eq!(sculpt.field.transform().voxel_size_m, 0.002);
    assert_eq!(sculpt.scene_toml.as_deref(), Some("# the analytic field of tests/sculpt_file.rs\n"));
    assert!(!sculpt.field.undo().unwrap(), "version 1 holds no history");
}

#[test]
fn a_version_2_file_still_loads() {
    let bytes = std::fs::read(FIXTURE_V2).unwrap();
    assert_eq!(&bytes[4..8], &2u32.to_le_bytes(), "the fixture is format version 2");
    let sculpt = load_sculpt(std::path::Path::new(FIXTURE_V2)).unwrap();
    assert!(same_matter(&sculpt.field, &fixture_field()));
    assert_eq!(sculpt.field.transform().voxel_size_m, 0.002);
}

#[test]
fn convert_moves_sculpts_between_versions() {
    let dir = temp_dir("convert");
    let (v4, v3) = (dir.join("v4.argile"), dir.join("v3.argile"));
    let (v2, v1) = (dir.join("v2.argile"), dir.join("back-to-v1.argile"));
    let out = argile(&["convert", FIXTURE_V1, v4.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let current = argile::io::VERSION;
    assert!(String::from_utf8_lossy(&out.stdout).contains(&format!("format version {current}")));
    assert_eq!(&std::fs::read(&v4).unwrap()[4..8], &current.to_le_bytes());
    assert!(same_matter(&load_sculpt(&v4).unwrap().field, &fixture_field()));
    let out = argile(&["convert", v4.to_str().unwrap(), v3.to_str().unwrap(), "--format-version", "3"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(
        std::fs::read(&v3).unwrap(),
        std::fs::read(FIXTURE_V3).unwrap(),
        "the same bytes as version 3 wrote"
    );
    let out = argile(&["convert", v3.to_str().unwrap(), v2.to_str().unwrap(), "--format-version", "2"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(
        std::fs::read(&v2).unwrap(),
        std::fs::read(FIXTURE_V2).unwrap(),
        "the same bytes as version 2 wrote"
    );
    let out = argile(&["convert", v2.to_str().unwrap(), v1.to_str().unwrap(), "--format-version", "1"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(
        std::fs::read(&v1).unwrap(),
        std::fs::read(FIXTURE_V1).unwrap(),
        "the same bytes as version 1 wrote"
    );

    let out =
        argile(&["convert", FIXTURE_V1, dir.join("v9.argile").to_str().unwrap(), "--format-version", "9"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("format version 9 cannot be written"));
    let out = argile(&["convert", FIXTURE_V1, v4.to_str().unwrap()]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("pass --force"));

    // Clay on coarser levels is refused by versions 1 and 2 (they store the finest level
    // alone; refined, its surface would move), with a sentence that names the file and says
    // what to write instead; version 3 stores it as it is.
    for version in ["1", "2"] {
        let old = dir.join(format!("levels-v{version}.argile"));
        let out = argile(&["convert", LEVELS_SCENE, old.to_str().unwrap(), "--format-version", version]);
        let said = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && !old.exists(), "{said}");
        assert!(
            said.contains("levels-meet.toml")
                && said.contains("coarser levels")
                && said.contains("version 3 or later"),
            "{said}"
        );
    }
    let v3 = dir.join("levels-v3.argile");
    assert!(argile(&["convert", LEVELS_SCENE, v3.to_str().unwrap(), "--format-version", "3"])
        .status
        .success());
    assert!(load_sculpt(&v3).unwrap().field.has_levels_above(0));

    // A scene converts to its clay at the end of its timeline, as `argile save` stores it.
    let (converted, saved) = (dir.join("scene.argile"), dir.join("saved.argile"));
    assert!(argile(&["convert", SCENE, converted.to_str().unwrap()]).status.success());
    assert!(argile(&["save", SCENE, "--out", saved.to_str().unwrap()]).status.success());
    assert!(load_sculpt(&converted).unwrap().field.same_samples(&load_sculpt(&saved).unwrap().field));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Undoes every step of both fields, then redoes them all, checking they agree bit for bit
/// at each step.
fn assert_same_history(a: &mut Field, b: &mut Field) -> Result<(), TestCaseError> {
    prop_assert_eq!(a.history_stats(), b.history_stats());
    loop {
        let (ua, ub) = (a.undo().unwrap(), b.undo().unwrap());
        prop_assert_eq!(ua, ub);
        prop_assert!(a.same_samples(b));
        if !ua {
            break;
        }
    }
    loop {
        let (ra, rb) = (a.redo(), b.redo());
        prop_assert_eq!(ra, rb);
        prop_assert!(a.same_samples(b));
        if !ra {
            break;
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 16,
        rng_seed: proptest::test_runner::RngSeed::Fixed(9),
        ..ProptestConfig::default()
    })]

    /// Random strokes, some undone: the sculpt, its history (undo and redo) and its settings
    /// read back bit for bit.
    #[test]
    fn sculpts_with_history_round_trip_bit_for_bit(
        strokes in proptest::collection::vec(
            proptest::collection::vec(
                (-0.03f32..0.03, -0.03f32..0.03, -0.03f32..0.03, 0.001f32..0.008, any::<bool>(), 0.0f32..1.0),
                1..4,
            ),
            1..7,
        ),
        undone in 0usize..4,
        voxel in 0.0005f32..0.004,
        iso in 0.2f32..0.8,
        scene in proptest::option::of("[a-z =\n\"0-9.\\[\\]]{0,40}"),
    ) {
        let mut f = Field::new(voxel, iso);
        for stroke in &strokes {
            f.begin_stroke();
            for &(x, y, z, r, remove, hue) in stroke {
                let action = if remove { Action::Remove } else { Action::Add };
                stamp_sphere(&mut f, Vec3::new(x, y, z), r, action, [hue, 1.0 - hue, 0.5, 1.0]);
            }
            f.end_stroke();
        }
        for _ in 0..undone {
            f.undo().unwrap();
        }
        let bytes = encode(&f, scene.as_deref(), &mut |_| {});
        let mut back = decode(&bytes, "p.argile", &mut |_| {}).unwrap();
        prop_assert!(back.field.same_samples(&f));
        prop_assert_eq!(back.field.transform(), f.transform());
        prop_assert_eq!(back.field.iso().to_bits(), f.iso().to_bits());
        prop_assert_eq!(back.scene_toml, scene);
        assert_same_history(&mut back.field, &mut f)?;
    }
}

/// Where each part of a sculpt file lies: (start, end, what) for the header fields and each
/// chunk's tag, lengths, checksum and stored bytes.
fn layout(bytes: &[u8]) -> Vec<(usize, usize, &'static str)> {
    let mut parts = vec![(0, 4, "magic"), (4, 8, "version"), (8, 12, "count")];
    let mut at = 12;
    while at < bytes.len() {
        let stored = u32::from_le_bytes(bytes[at + 8..at + 12].try_into().unwrap()) as usize;
        parts.extend([
            (at, at + 4, "tag"),
            (at + 4, at + 8, "raw length"),
            (at + 8, at + 12, "stored length"),
            (at + 12, at + 16, "checksum"),
            (at + 16, at + 16 + stored, "stored"),
        ]);
        at += 16 + stored;
    }
    parts
}

/// A sculpt with every kind of chunk: scene text, bricks, undo and redo steps.
fn full_sculpt() -> Vec<u8> {
    let mut f = fixture_field();
    for i in 0..3 {
        f.begin_stroke();
        stamp_sphere(
            &mut f,
            Vec3::new(0.004 * i as f32, 0.0, 0.0),
            0.006,
            Action::Remove,
            [1.0, 0.0, 0.0, 1.0],
        );
        f.end_stroke();
    }
    f.undo().unwrap();
    encode(&f, Some("[field]\nvoxel_size_m = 0.002\n"), &mut |_| {})
}

#[test]
fn every_truncation_is_refused_as_truncated() {
    let bytes = full_sculpt();
    let parts = layout(&bytes);
    assert!(parts.iter().filter(|p| p.2 == "tag").count() >= 4);
    for n in 0..bytes.len() {
        let e = decode(&bytes[..n], "cut.argile", &mut |_| {}).unwrap_err().to_string();
        assert!(e.starts_with("sculpt file cut.argile: "), "{e}");
        let count = u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize;
        let expected = if n < 12 {
            "no ARGL header"
        } else if count > (n - 12) / 16 {
            "more than its"
        } else {
            "(truncated)"
        };
        assert!(e.contains(expected), "cut at {n}: {e}");
    }
    // Read from a file chunk by chunk, the same cuts give the same sentences.
    let dir = temp_dir("cuts");
    let path = dir.join("cut.argile");
    for n in (0..bytes.len()).step_by(97) {
        std::fs::write(&path, &bytes[..n]).unwrap();
        let from_file = argile::io::read_file(&path, &mut |_| {}).unwrap_err().reason;
        let from_memory = decode(&bytes[..n], "m", &mut |_| {}).unwrap_err().reason;
        assert_eq!(from_file, from_memory, "cut at {n}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn random_byte_flips_are_refused_with_the_message_for_the_part_hit() {
    let bytes = full_sculpt();
    let parts = layout(&bytes);
    let mut x: u64 = 0x2545_F491_4F6C_DD1D;
    for _ in 0..3000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let at = (x % bytes.len() as u64) as usize;
        let mask = 1u8 << ((x >> 32) % 8);
        let mut bad = bytes.clone();
        bad[at] ^= mask;
        let e = decode(&bad, "flip.argile", &mut |_| {}).unwrap_err().to_string();
        let part = parts.iter().find(|p| p.0 <= at && at < p.1).unwrap().2;
        let expected: &[&str] = match part {
            "magic" => &["not an Argile sculpt"],
            "version" => &["format version"],
            "count" => &["chunks, more than", "follow its last chunk", "(truncated)", "holds no META"],
            "tag" => &["unknown or repeated tag", "first chunk is not META", "late META"],
            "raw length" => &["does not decompress to its stated size", "over the"],
            "stored length" => &["checksum", "(truncated)"],
            _ => &["checksum"],
        };
        assert!(expected.iter().any(|m| e.contains(m)), "{part} flipped at byte {at}: {e}");
    }
}

// ---- Reading lazily (format version 4) ----

/// A sculpt spread over many blocks: stamps along a bar 0.3 m long at 1 mm voxels, a coarse
/// build on level 2 around its middle, and the undo step of a last stroke.
fn spread_field() -> Field {
    let mut f = Field::new(0.001, 0.5);
    for i in 0..15 {
        let centre = Vec3::new(-0.15 + 0.02 * i as f32, 0.004 * (i % 3) as f32, 0.0);
        stamp_sphere(&mut f, centre, 0.006, Action::Add, [0.05 * i as f32, 0.4, 0.6, 1.0]);
    }
    coarse_ball(&mut f, 2, IVec3::new(0, 40, 0), 30.0);
    f.begin_stroke();
    stamp_sphere(&mut f, Vec3::new(0.05, 0.0, 0.0), 0.005, Action::Remove, [0.0; 4]);
    f.end_stroke();
    f
}

/// A ball of `radius` finest voxels about `centre` (finest lattice), built on `level`.
fn coarse_ball(f: &mut Field, level: usize, centre: IVec3, radius: f32) {
    let step = 1 << level;
    let (c, r) = (centre / step, (radius / step as f32).ceil() as i32 + 2);
    f.edit_level(
        level,
        c - IVec3::splat(r),
        c + IVec3::splat(r),
        true,
        |_, _, _| true,
        |q, d, col| {
            let dist = (q * step - centre).as_vec3().length();
            *d = d.max(((radius - dist) / step as f32 * 0.5 + 0.5).clamp(0.0, 1.0));
            *col = [0.7, 0.3, 0.2, 1.0];
        },
    );
}

/// Every point of `lo..=hi` reads the same in both fields, bit for bit: its density, and its
/// colour where it holds matter (an empty point's colour means nothing: there, the default
/// colour comes through an interpolation of the empty coarse levels when the field has any,
/// to within a rounding).
fn reads_the_same(part: &Field, whole: &Field, lo: IVec3, hi: IVec3) -> Result<(), TestCaseError> {
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                let p = IVec3::new(x, y, z);
                let (a, b) = (part.sample(p), whole.sample(p));
                prop_assert_eq!(a.0.to_bits(), b.0.to_bits(), "density at {}", p);
                if a.0 > 0.0 {
                    prop_assert_eq!(a.1.map(f32::to_bits), b.1.map(f32::to_bits), "colour at {}", p);
                }
            }
        }
    }
    Ok(())
}

/// Loads `lo..=hi` lazily from `bytes` and checks it: the chunks read are those reaching into
/// the box, the box reads as in the whole sculpt read at once (bit for bit), and finishing gives the whole sculpt, history and all.
fn check_box(bytes: &[u8], lo: IVec3, hi: IVec3) -> Result<usize, TestCaseError> {
    let mut lazy = LazySculpt::from_bytes(bytes.to_vec(), "lazy.argile").unwrap();
    prop_assert_eq!(lazy.field().level_brick_count(0), 0, "opening reads no brick");
    let read = lazy.load_box(lo, hi).unwrap();
    for (i, c) in lazy.chunks().iter().enumerate() {
        let (a, b) = c.reach();
        let reaches = a.cmple(hi).all() && b.cmpge(lo).all();
        prop_assert_eq!(lazy.is_loaded(i), reaches, "chunk {} ({:?})", i, c);
    }
    let mut whole = decode(bytes, "whole.argile", &mut |_| {}).unwrap().field;
    reads_the_same(lazy.field(), &whole, lo, hi)?;
    let mut back = lazy.finish(&mut |_| {}).unwrap().field;
    assert_same_history(&mut back, &mut whole)?;
    Ok(read)
}

#[test]
fn opening_a_sculpt_reads_its_index_and_a_box_reads_the_chunks_reaching_into_it() {
    let whole = spread_field();
    let bytes = encode(&whole, Some("# a scene\n"), &mut |_| {});
    assert_eq!(&bytes[4..8], &argile::io::VERSION.to_le_bytes());
    let lazy = LazySculpt::from_bytes(bytes.clone(), "lazy.argile").unwrap();
    assert_eq!(lazy.scene_toml(), Some("# a scene\n"));
    assert_eq!(lazy.brick_count() as usize, whole.brick_count() + whole.level_brick_count(2));
    let levels: Vec<usize> = lazy.chunks().iter().map(|c| c.level).collect();
    assert!(levels.contains(&0) && levels.contains(&2), "{levels:?}");
    // A level alone: its chunks, and every brick of it.
    let mut coarse = LazySculpt::from_bytes(bytes.clone(), "lazy.argile").unwrap();
    assert_eq!(coarse.load_level(2).unwrap(), levels.iter().filter(|&&l| l == 2).count());
    assert_eq!(coarse.field().level_brick_count(2), whole.level_brick_count(2));
    assert_eq!(coarse.field().level_brick_count(0), 0);
    assert_eq!(coarse.chunks_left(), levels.iter().filter(|&&l| l != 2).count());
    assert!(
        lazy.bytes_read() * 20 < lazy.file_len(),
        "opening read {} of {} bytes",
        lazy.bytes_read(),
        lazy.file_len()
    );
    // One stamp's box, at the bar's left end, and a box across the coarse build and the bar.
    let left = IVec3::new(-150, 0, 0);
    let read = check_box(&bytes, left - IVec3::splat(8), left + IVec3::splat(8)).unwrap();
    assert!(read >= 1 && read < lazy.chunks().len() / 2, "{read} of {} chunks", lazy.chunks().len());
    check_box(&bytes, IVec3::new(-20, -10, -6), IVec3::new(20, 70, 6)).unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 12,
        rng_seed: proptest::test_runner::RngSeed::Fixed(11),
        ..ProptestConfig::default()
    })]

    /// Random strokes on the finest level and coarse builds on levels 1 to 3, some undone: any
    /// box loaded lazily reads as in the whole sculpt, and finishing gives the whole sculpt.
    #[test]
    fn any_box_read_lazily_reads_as_the_whole_sculpt(
        stamps in proptest::collection::vec(
            (-0.1f32..0.1, -0.05f32..0.05, -0.05f32..0.05, 0.002f32..0.01, any::<bool>()),
            1..8,
        ),
        builds in proptest::collection::vec((1usize..4, -100i32..100, -60i32..60, 10.0f32..40.0), 0..3),
        undone in 0usize..3,
        lo in (-120i32..120, -70i32..70, -70i32..70),
        size in (0i32..40, 0i32..40, 0i32..40),
    ) {
        let mut f = Field::new(0.001, 0.5);
        for &(level, x, y, r) in &builds {
            f.begin_stroke();
            coarse_ball(&mut f, level, IVec3::new(x, y, 0), r);
            f.end_stroke();
        }
        for &(x, y, z, r, remove) in &stamps {
            f.begin_stroke();
            let action = if remove { Action::Remove } else { Action::Add };
            stamp_sphere(&mut f, Vec3::new(x, y, z), r, action, [x.abs() * 5.0, 0.5, 0.5, 1.0]);
            f.end_stroke();
        }
        for _ in 0..undone {
            f.undo().unwrap();
        }
        let bytes = encode(&f, None, &mut |_| {});
        let lo = IVec3::new(lo.0, lo.1, lo.2);
        check_box(&bytes, lo, lo + IVec3::new(size.0, size.1, size.2))?;
    }
}

/// Both readers refuse `bytes`, naming the file, with a reason containing `why`.
fn both_refuse(bytes: &[u8], why: &str) {
    let e = decode(bytes, "lie.argile", &mut |_| {}).unwrap_err().to_string();
    assert!(e.starts_with("sculpt file lie.argile: ") && e.contains(why), "whole: {e}");
    let lazy = LazySculpt::from_bytes(bytes.to_vec(), "lie.argile").and_then(|mut l| {
        for i in 0..l.chunks().len() {
            l.load_chunk(i)?;
        }
        l.finish(&mut |_| {})
    });
    let e = lazy.unwrap_err().to_string();
    assert!(e.starts_with("sculpt file lie.argile: ") && e.contains(why), "lazy: {e}");
}

#[test]
fn an_index_that_lies_is_refused_by_both_readers() {
    let bytes = encode(&spread_field(), None, &mut |_| {});
    let (header, chunks) = split(&bytes);
    assert_eq!(&chunks[1].0, b"INDX");
    let entry = |i: usize| 12 + 25 * i;
    let patched = |at: usize, value: &[u8]| {
        let mut c = chunks.clone();
        c[1].1[at..at + value.len()].copy_from_slice(value);
        join(header, &c)
    };
    // Entry 0's block moved to where no brick of it lies.
    both_refuse(&patched(entry(0) + 1, &77i32.to_le_bytes()), "outside its block");
    // Entry 1 claims a brick more, and the header's count with it: the chunk holds fewer.
    let mut c = chunks.clone();
    let bricks = u32::from_le_bytes(c[1].1[entry(1) + 13..entry(1) + 17].try_into().unwrap());
    c[1].1[entry(1) + 13..entry(1) + 17].copy_from_slice(&(bricks + 1).to_le_bytes());
    let meta = String::from_utf8(c[0].1.clone()).unwrap();
    let total: u64 = meta.split("\"bricks\":").nth(1).unwrap().trim_end_matches('}').parse().unwrap();
    c[0].1 = meta.replace(&format!("\"bricks\":{total}"), &format!("\"bricks\":{}", total + 1)).into_bytes();
    both_refuse(&join(header, &c), "its index entry says");
    // Entry 2 starts 16 bytes late: inside another chunk.
    let offset = u64::from_le_bytes(c[1].1[entry(2) + 17..entry(2) + 25].try_into().unwrap());
    both_refuse(&patched(entry(2) + 17, &(offset + 16).to_le_bytes()), "chunk 4");
    // Absurd values: an offset at the end of the 64-bit range, a block beyond the field, more
    // entries than the chunk holds.
    both_refuse(&patched(entry(2) + 17, &u64::MAX.to_le_bytes()), "where none can start");
    both_refuse(&patched(entry(0) + 5, &i32::MIN.to_le_bytes()), "beyond the field");
    both_refuse(&patched(0, &u32::MAX.to_le_bytes()), "not a whole index");
    // The history put a byte early.
    let history = u64::from_le_bytes(chunks[1].1[4..12].try_into().unwrap());
    both_refuse(&patched(4, &(history - 1).to_le_bytes()), "history");
    // A brick chunk before the index; the index left out.
    let mut c = chunks.clone();
    c.swap(1, 2);
    both_refuse(&join(header, &c), "before the index");
    let mut c = chunks.clone();
    c.remove(1);
    both_refuse(&join(header, &c), "before the index");
}

#[test]
fn every_truncation_of_an_indexed_sculpt_is_refused_by_both_readers() {
    let mut f = spread_field();
    f.undo().unwrap();
    let bytes = encode(&f, None, &mut |_| {});
    for n in (0..bytes.len()).step_by(97).chain([bytes.len() - 1]) {
        both_refuse(&bytes[..n], "");
    }
}

/// The same sculpt as the version-1 fixture, written by format version 3.
const FIXTURE_V3: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/sculpt-v3.argile");

#[test]
fn a_version_3_file_still_loads_whole_or_lazily() {
    let bytes = std::fs::read(FIXTURE_V3).unwrap();
    assert_eq!(&bytes[4..8], &3u32.to_le_bytes(), "the fixture is format version 3");
    let sculpt = load_sculpt(std::path::Path::new(FIXTURE_V3)).unwrap();
    assert!(same_matter(&sculpt.field, &fixture_field()));
    let lazy = LazySculpt::open(std::path::Path::new(FIXTURE_V3)).unwrap();
    assert!(lazy.chunks().is_empty() && lazy.bytes_read() == bytes.len() as u64, "no index: read whole");
    assert!(lazy.finish(&mut |_| {}).unwrap().field.same_samples(&sculpt.field));
    let v3 = encode_with(
        &sculpt.field,
        sculpt.scene_toml.as_deref(),
        EncodeOptions { version: 3, history: true },
        &mut |_| {},
    );
    assert_eq!(v3, bytes, "the same bytes as version 3 wrote");
}

#[test]
fn info_describes_a_sculpt_from_its_index() {
    let dir = temp_dir("info");
    let path = dir.join("spread.argile");
    let bytes = encode(&spread_field(), Some("# a scene\n"), &mut |_| {});
    std::fs::write(&path, &bytes).unwrap();
    let out = argile(&["info", path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    let lazy = LazySculpt::from_bytes(bytes.clone(), "spread.argile").unwrap();
    for line in [
        format!("format version {}, {} bytes", argile::io::VERSION, bytes.len()),
        "voxels 1 mm, iso-level 0.5".to_owned(),
        "level 0 (1 mm voxels): ".to_owned(),
        "level 2 (4 mm voxels): ".to_owned(),
        "undo history: 1 chunks".to_owned(),
        "stored (10 bytes of TOML)".to_owned(),
        format!("read {} of {} bytes: its header, settings, scene and index", lazy.bytes_read(), bytes.len()),
    ] {
        assert!(text.contains(&line), "`{line}` in:\n{text}");
    }
    // A damaged index is refused by name, as every reader refuses it.
    let mut bad = bytes;
    let tags: Vec<usize> = layout(&bad).into_iter().filter(|p| p.2 == "tag").map(|p| p.0).collect();
    let indx = tags.into_iter().find(|&at| &bad[at..at + 4] == b"INDX").unwrap();
    bad[indx + 16 + 2] ^= 0x10;
    std::fs::write(&path, &bad).unwrap();
    let out = argile(&["info", path.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("sculpt file {}", path.display()))
            && err.contains("chunk 2 (INDX) fails its checksum"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

const FREEFORM_SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tests/tool-freeform.toml");

/// The densities of the scene's first tool, a freeform one.
fn freeform_samples(playback: &argile::app::Playback<'_>) -> Vec<f32> {
    match &playback.tools()[0].shape {
        argile::tool::ToolShape::Freeform(f) => f.samples().to_vec(),
        other => panic!("the first tool is freeform, not {other:?}"),
    }
}

#[test]
fn a_sculpt_keeps_its_scenes_freeform_tools_as_they_were_made() {
    let dir = temp_dir("tools");
    let (path, carved) = (dir.join("copy.argile"), dir.join("carved.argile"));
    let out = argile(&["save", FREEFORM_SCENE, "--out", path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(FREEFORM_SCENE).unwrap();
    let scene = argile::scene::Scene::parse(&text, FREEFORM_SCENE, None).unwrap();
    let made = freeform_samples(&argile::app::Playback::new(&scene));
    assert!(made.iter().any(|&d| d > 0.5), "the copy holds the torus");

    let mut sculpt = load_sculpt(&path).unwrap();
    assert_eq!(sculpt.tools.len(), 1);
    assert_eq!((sculpt.tools[0].index, &sculpt.tools[0].samples), (0, &made));
    // The clay the tool was copied from carved away: the file still holds the tool.
    let t = *sculpt.field.transform();
    let (lo, hi) =
        (t.world_to_index(Vec3::new(-0.12, -0.02, -0.04)), t.world_to_index(Vec3::new(-0.04, 0.02, 0.04)));
    sculpt.field.edit_box(lo.floor().as_ivec3(), hi.ceil().as_ivec3(), false, |_, d, _| *d = 0.0);
    let bytes =
        argile::io::encode_sculpt(&sculpt.field, sculpt.scene_parts(), EncodeOptions::default(), &mut |_| {});
    std::fs::write(&carved, &bytes).unwrap();
    let (scene, opened) = argile::app::open_sculpt(&carved).unwrap();
    let copied = argile::app::Playback::on_field(&scene, opened.field.clone(), &[], |_, _| None);
    assert!(freeform_samples(&copied).iter().all(|&d| d == 0.0), "copied again, the tool would be empty");
    let playback = argile::app::Playback::on_field(&scene, opened.field, &opened.tools, |_, _| None);
    assert!(freeform_samples(&playback) == made, "the tool as it was made");

    // Versions before 4 hold no tools; a damaged tool chunk is refused by name.
    let v3 = encode_with(&sculpt.field, None, EncodeOptions { version: 3, history: true }, &mut |_| {});
    assert!(decode(&v3, "v3.argile", &mut |_| {}).unwrap().tools.is_empty());
    let (header, chunks) = split(&bytes);
    let at = chunks.iter().position(|c| &c.0 == b"TOOL").unwrap();
    for (offset, value, why) in [
        (4, 1000u32.to_le_bytes(), "samples in"),
        (16, f32::NAN.to_le_bytes(), "not a usable spacing"),
        (20, 1.5f32.to_le_bytes(), "outside [0, 1]"),
    ] {
        let mut c = chunks.clone();
        c[at].1[offset..offset + 4].copy_from_slice(&value);
        both_refuse(&join(header, &c), why);
    }
    let mut c = chunks.clone();
    c.insert(at, c[at].clone());
    both_refuse(&join(header, &c), "a second copy of tool 0");
    // More tools than a file may hold.
    let mut c = chunks.clone();
    for i in 1..=argile::io::MAX_TOOLS as u32 {
        let mut tool = c[at].clone();
        tool.1[..4].copy_from_slice(&i.to_le_bytes());
        c.insert(at, tool);
    }
    both_refuse(&join(header, &c), "more than 64 freeform tools");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_sculpt_keeps_the_view_it_was_saved_in_and_refuses_a_view_no_station_has() {
    let view = argile::io::StoredView {
        turn: argile::math::Quat::from_rotation_y(0.5).to_array(),
        distance_m: 0.4,
        scene_position_m: [0.01, 0.0, -0.02],
        scene_rotation: argile::math::Quat::from_rotation_x(0.1).to_array(),
        convergence_factor: 0.9,
        interaxial_m: 0.05,
        lights_follow_viewer: true,
        auto_convergence: false,
        display_mode: "side-by-side".into(),
    };
    let field = spread_field();
    let parts = argile::io::SceneParts {
        toml: Some("# a scene\n"),
        tools: &[],
        view: Some(&view),
        ..Default::default()
    };
    let bytes = argile::io::encode_sculpt(&field, parts, EncodeOptions::default(), &mut |_| {});
    let back = decode(&bytes, "view.argile", &mut |_| {}).unwrap();
    assert_eq!(back.view.as_ref(), Some(&view));
    let lazy = LazySculpt::from_bytes(bytes.clone(), "view.argile").unwrap().finish(&mut |_| {}).unwrap();
    assert_eq!(lazy.view.as_ref(), Some(&view));
    let v3 =
        argile::io::encode_sculpt(&field, parts, EncodeOptions { version: 3, history: true }, &mut |_| {});
    assert!(decode(&v3, "v3.argile", &mut |_| {}).unwrap().view.is_none(), "version 3 holds no view");

    let (header, chunks) = split(&bytes);
    let at = chunks.iter().position(|c| &c.0 == b"VIEW").unwrap();
    let json = String::from_utf8(chunks[at].1.clone()).unwrap();
    for (from, to, why) in [
        ("\"distance_m\":0.4", "\"distance_m\":1e9", "no station has"),
        ("\"turn\":[", "\"turn\":[3.0,", "not a view"),
        ("\"side-by-side\"", "\"hologram\"", "display mode `hologram`"),
        ("\"auto_convergence\":false", "\"auto_convergence\":false,\"zoom\":2", "unknown field"),
    ] {
        assert!(json.contains(from), "{json}");
        let mut c = chunks.clone();
        c[at].1 = json.replace(from, to).into_bytes();
        both_refuse(&join(header, &c), why);
    }
    let mut c = chunks.clone();
    c[at].1 = json.replace("\"turn\":[0.0,", "\"turn\":[0.5,").into_bytes();
    both_refuse(&join(header, &c), "no station has");
}
