//! Undo and redo of strokes: bit-exact restoration, redo cleared by a new stroke, the memory
//! budget spilling to disk or dropping the oldest steps, damaged spill files refused.

use argile::field::{Field, HistoryConfig, BRICK_VOLUME};
use argile::math::Vec3;
use argile::tool::{stamp_sphere, Action};
use proptest::prelude::*;

/// One stroke: stamps of one action along a short path.
#[derive(Clone, Debug)]
struct StrokeSpec {
    remove: bool,
    start: [f32; 3],
    end: [f32; 3],
    radius: f32,
    colour: [f32; 4],
}

fn stroke_spec() -> impl Strategy<Value = StrokeSpec> {
    (
        any::<bool>(),
        [-0.02f32..0.02, -0.02f32..0.02, -0.02f32..0.02],
        [-0.02f32..0.02, -0.02f32..0.02, -0.02f32..0.02],
        0.002f32..0.008,
        [0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0],
    )
        .prop_map(|(remove, start, end, radius, c)| StrokeSpec {
            remove,
            start,
            end,
            radius,
            colour: [c[0], c[1], c[2], 1.0],
        })
}

fn play(field: &mut Field, s: &StrokeSpec) {
    field.begin_stroke();
    let (a, b) = (Vec3::from(s.start), Vec3::from(s.end));
    let action = if s.remove { Action::Remove } else { Action::Add };
    for i in 0..=6 {
        stamp_sphere(field, a.lerp(b, i as f32 / 6.0), s.radius, action, s.colour);
    }
    field.end_stroke();
}

/// A field with some clay laid down outside any stroke (not undoable).
fn base_field() -> Field {
    let mut f = Field::new(0.001, 0.5);
    stamp_sphere(&mut f, Vec3::ZERO, 0.012, Action::Add, [0.7, 0.4, 0.2, 1.0]);
    f
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("argile-history-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 24,
        rng_seed: proptest::test_runner::RngSeed::Fixed(11),
        ..ProptestConfig::default()
    })]

    /// Undoing every stroke restores the initial field bit for bit; redoing every one restores
    /// the final field bit for bit.
    #[test]
    fn undo_all_restores_the_start_and_redo_all_the_end(strokes in proptest::collection::vec(stroke_spec(), 1..6)) {
        let initial = base_field();
        let mut f = base_field();
        for s in &strokes {
            play(&mut f, s);
        }
        let last = f.clone();
        for _ in &strokes {
            prop_assert!(f.undo().unwrap());
        }
        prop_assert!(!f.undo().unwrap(), "nothing left to undo");
        prop_assert!(f.same_samples(&initial));
        for _ in &strokes {
            prop_assert!(f.redo());
        }
        prop_assert!(!f.redo());
        prop_assert!(f.same_samples(&last));
    }

    /// The same holds when the memory budget forces all but the newest step onto disk.
    #[test]
    fn spilled_steps_undo_exactly(strokes in proptest::collection::vec(stroke_spec(), 2..5)) {
        let dir = temp_dir("prop-spill");
        let initial = base_field();
        let mut f = base_field();
        f.set_history_config(HistoryConfig { memory_budget_bytes: 1, spill_dir: Some(dir.clone()), ..HistoryConfig::default() });
        for s in &strokes {
            play(&mut f, s);
        }
        let stats = f.history_stats();
        prop_assert_eq!(stats.undo_in_memory, 1);
        prop_assert_eq!(stats.undo_on_disk, strokes.len() - 1);
        while f.undo().unwrap() {}
        prop_assert!(f.same_samples(&initial));
        drop(f);
        prop_assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "the session's spill folder is removed");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn add_then_undo_restores_the_field_and_marks_it_dirty() {
    let mut f = Field::new(0.001, 0.5);
    let empty = f.clone();
    f.begin_stroke();
    stamp_sphere(&mut f, Vec3::new(0.003, 0.0, -0.001), 0.005, Action::Add, [1.0, 0.0, 0.0, 1.0]);
    f.end_stroke();
    assert!(f.mass() > 0.0);
    f.take_dirty();
    assert!(f.undo().unwrap());
    assert!(f.same_samples(&empty));
    assert_eq!(f.brick_count(), 0);
    assert!(!f.take_dirty().is_empty(), "the mesher learns what undo changed");
}

#[test]
fn a_new_stroke_clears_redo() {
    let mut f = base_field();
    let spec =
        StrokeSpec { remove: true, start: [0.0; 3], end: [0.01, 0.0, 0.0], radius: 0.004, colour: [0.0; 4] };
    play(&mut f, &spec);
    assert!(f.undo().unwrap());
    assert_eq!(f.history_stats().redo, 1);
    play(&mut f, &StrokeSpec { remove: false, ..spec });
    assert_eq!(f.history_stats().redo, 0);
    assert!(!f.redo(), "the undone stroke cannot come back after a new one");
}

#[test]
fn edits_outside_strokes_are_not_journaled_and_empty_strokes_leave_no_step() {
    let mut f = base_field();
    f.begin_stroke();
    f.end_stroke();
    assert_eq!(f.history_stats().undo_in_memory, 0);
    assert!(!f.undo().unwrap());
    assert!(f.mass() > 0.0, "the base clay is not undoable");
}

/// A carving stroke through the base clay at `x`: it saves the bricks it changes.
fn carve(x: f32) -> StrokeSpec {
    StrokeSpec {
        remove: true,
        start: [x, 0.006, 0.008],
        end: [x, 0.0, 0.008],
        radius: 0.003,
        colour: [0.0; 4],
    }
}

/// Bytes one carving stroke saves.
fn carve_bytes() -> usize {
    let mut f = base_field();
    play(&mut f, &carve(0.0));
    f.history_stats().memory_bytes
}

#[test]
fn without_a_spill_folder_the_oldest_steps_are_dropped() {
    let one = carve_bytes();
    // Each saved brick holds at least its densities (2 bytes a sample).
    assert!(one > 4 * 2 * BRICK_VOLUME, "a carving stroke saves several bricks: {one} bytes");
    let mut f = base_field();
    f.set_history_config(HistoryConfig {
        memory_budget_bytes: 2 * one + one / 2,
        ..HistoryConfig::default()
    });
    let mut states = vec![f.clone()];
    for i in 0..5 {
        play(&mut f, &carve(-0.006 + 0.003 * i as f32));
        states.push(f.clone());
    }
    let stats = f.history_stats();
    assert!(stats.dropped >= 1 && stats.memory_bytes <= 2 * one + one / 2, "{stats:?}");
    assert_eq!(stats.undo_in_memory + stats.dropped, 5);
    let kept = stats.undo_in_memory;
    for _ in 0..kept {
        assert!(f.undo().unwrap());
    }
    assert!(!f.undo().unwrap(), "undo stops at the oldest kept step");
    assert!(f.same_samples(&states[5 - kept]), "the state before the oldest kept stroke");
}

#[test]
fn over_the_disk_budget_the_oldest_spilled_steps_are_dropped() {
    let dir = temp_dir("disk-budget");
    let one = carve_bytes() as u64;
    let mut f = base_field();
    f.set_history_config(HistoryConfig {
        memory_budget_bytes: 1,
        spill_dir: Some(dir.clone()),
        disk_budget_bytes: 3 * one,
    });
    for i in 0..8 {
        play(&mut f, &carve(-0.007 + 0.002 * i as f32));
    }
    let stats = f.history_stats();
    assert!(stats.dropped > 0 && stats.disk_bytes <= 3 * one, "{stats:?}");
    assert_eq!(stats.undo_on_disk + stats.undo_in_memory + stats.dropped, 8);
    drop(f);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_damaged_spill_file_is_refused_with_its_path() {
    let dir = temp_dir("damaged");
    let mut f = base_field();
    f.set_history_config(HistoryConfig {
        memory_budget_bytes: 1,
        spill_dir: Some(dir.clone()),
        ..HistoryConfig::default()
    });
    for x in [0.0f32, 0.02] {
        play(
            &mut f,
            &StrokeSpec {
                remove: false,
                start: [x, 0.03, 0.0],
                end: [x, 0.035, 0.0],
                radius: 0.003,
                colour: [1.0; 4],
            },
        );
    }
    let session = std::fs::read_dir(&dir).unwrap().next().unwrap().unwrap().path();
    let spilled = std::fs::read_dir(&session).unwrap().next().unwrap().unwrap().path();
    let mut bytes = std::fs::read(&spilled).unwrap();
    bytes[100] ^= 0xff;
    std::fs::write(&spilled, bytes).unwrap();
    assert!(f.undo().unwrap(), "the newest step is in memory");
    let e = f.undo().unwrap_err().to_string();
    assert!(e.contains(&spilled.display().to_string()) && e.contains("checksum"), "{e}");
    drop(f);
    std::fs::remove_dir_all(&dir).unwrap();
}
