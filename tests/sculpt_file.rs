//! The native sculpt file: bit-exact round trips of random sculpts, the command line saving a
//! scene's clay and exporting it again, damaged files refused by name.

use std::path::PathBuf;
use std::process::Command;

use argile::app::load_sculpt;
use argile::field::Field;
use argile::io::{decode, encode};
use argile::math::Vec3;
use argile::tool::{stamp_sphere, Action};
use proptest::prelude::*;

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tests/toothpaste.toml");

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
