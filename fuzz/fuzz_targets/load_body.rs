//! The body of the `load` fuzz target, shared with its stable-toolchain run
//! (`tests/fuzz_load.rs`): the sculpt loader on arbitrary bytes must refuse or load, never
//! panic, hang or allocate what the bytes claim; what it loads must store and load again
//! unchanged; and the lazy reader (`LazySculpt`) must take and refuse the same files as the
//! whole-file reader, and give the same sculpt.

/// Runs the loaders on `data`; panics (a finding) when they disagree or when the round trip
/// of a loaded sculpt fails.
pub fn check(data: &[u8]) {
    let whole = argile::io::decode(data, "fuzz.argile", &mut |_| {});
    let lazy = argile::io::LazySculpt::from_bytes(data.to_vec(), "fuzz.argile").and_then(|mut l| {
        // A box first, as a viewer would, then the rest.
        if let Some(c) = l.chunks().last().copied() {
            let (lo, _) = c.reach();
            l.load_box(lo, lo + argile::math::IVec3::splat(8))?;
        }
        l.finish(&mut |_| {})
    });
    let sculpt = match (whole, lazy) {
        (Ok(whole), Ok(lazy)) => {
            assert!(lazy.field.same_samples(&whole.field), "the lazy reader gives the same clay");
            assert_eq!(lazy.scene_toml, whole.scene_toml);
            assert_eq!(lazy.tools, whole.tools);
            assert_eq!(lazy.view, whole.view);
            assert_eq!(lazy.field.history_stats(), whole.field.history_stats());
            whole
        }
        (Err(_), Err(_)) => return,
        (whole, lazy) => panic!(
            "the readers disagree: whole {:?}, lazy {:?}",
            whole.err().map(|e| e.reason),
            lazy.err().map(|e| e.reason)
        ),
    };
    let options = argile::io::EncodeOptions::default();
    let again = argile::io::encode_sculpt(&sculpt.field, sculpt.scene_parts(), options, &mut |_| {});
    let back = argile::io::decode(&again, "again.argile", &mut |_| {})
        .expect("a loaded sculpt stores and loads again");
    assert!(back.field.same_samples(&sculpt.field));
    assert_eq!(back.scene_toml, sculpt.scene_toml);
    assert_eq!(back.tools, sculpt.tools);
    assert_eq!(back.view, sculpt.view);
}
