//! The body of the `load` fuzz target, shared with its stable-toolchain run
//! (`tests/fuzz_load.rs`): the sculpt loader on arbitrary bytes must refuse or load, never
//! panic, hang or allocate what the bytes claim; what it loads must store and load again
//! unchanged.

/// Runs the loader on `data`; panics (a finding) when the round trip of a loaded sculpt fails.
pub fn check(data: &[u8]) {
    let Ok(sculpt) = argile::io::decode(data, "fuzz.argile", &mut |_| {}) else { return };
    let again = argile::io::encode(&sculpt.field, sculpt.scene_toml.as_deref(), &mut |_| {});
    let back = argile::io::decode(&again, "again.argile", &mut |_| {})
        .expect("a loaded sculpt stores and loads again");
    assert!(back.field.same_samples(&sculpt.field));
    assert_eq!(back.scene_toml, sculpt.scene_toml);
}
