//! The sculpt loader on arbitrary bytes: it must refuse or load, never panic, hang or
//! allocate what the bytes claim; what it loads must store and load again unchanged.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(sculpt) = argile::io::decode(data, "fuzz.argile", &mut |_| {}) else { return };
    let again = argile::io::encode(&sculpt.field, sculpt.scene_toml.as_deref(), &mut |_| {});
    let back = argile::io::decode(&again, "again.argile", &mut |_| {}).expect("a loaded sculpt stores and loads again");
    assert!(back.field.same_samples(&sculpt.field));
    assert_eq!(back.scene_toml, sculpt.scene_toml);
});
