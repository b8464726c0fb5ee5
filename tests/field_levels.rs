//! Resolution levels under random strokes of tools that edit by their size: undo and redo
//! exact across levels, values continuous everywhere, fine detail kept under coarse edits,
//! sub-voxel placement on a coarse level, and a large tool's level chosen by its size.

use argile::field::{Brick, Field, FieldReader, BRICK_SIZE};
use argile::math::{IVec3, Pose, Vec3};
use argile::tool::{apply_tool, edit_level_for, Action, Stroke, Tool, ToolShape, MAX_SIZE_SAMPLES};
use proptest::prelude::*;

const VOXEL_M: f32 = 0.001;

/// One stroke: a sphere tool of an action and radius dragged along a short path, editing the
/// level its size chooses.
#[derive(Clone, Debug)]
struct StrokeSpec {
    action: usize,
    start: [f32; 3],
    end: [f32; 3],
    radius_m: f32,
}

const ACTIONS: [Action; 4] = [Action::Add, Action::Remove, Action::Paint, Action::Build { rate_per_s: 4.0 }];

fn stroke_spec() -> impl Strategy<Value = StrokeSpec> {
    (
        0usize..ACTIONS.len(),
        [-0.03f32..0.03, -0.03f32..0.03, -0.03f32..0.03],
        [-0.03f32..0.03, -0.03f32..0.03, -0.03f32..0.03],
        // 2 to 40 finest voxels: levels 0 to 3.
        0.002f32..0.04,
    )
        .prop_map(|(action, start, end, radius_m)| StrokeSpec { action, start, end, radius_m })
}

fn play(field: &mut Field, s: &StrokeSpec) {
    let tool = Tool {
        level_samples: Some(MAX_SIZE_SAMPLES),
        ..Tool::new(ToolShape::sphere(s.radius_m), ACTIONS[s.action], [0.8, 0.3, 0.2, 1.0])
    };
    field.begin_stroke();
    let mut stroke = Stroke::new(tool);
    let (a, b) = (Vec3::from(s.start), Vec3::from(s.end));
    for i in 0..=4 {
        let pose = Pose { position_m: a.lerp(b, i as f32 / 4.0), ..Default::default() };
        stroke.advance(field, pose, 1.0 / 60.0);
    }
    field.end_stroke();
}

/// Fine clay laid down outside any stroke: a sphere of 12 finest voxels.
fn base_field() -> Field {
    let mut f = Field::new(VOXEL_M, 0.5);
    let tool = Tool::new(ToolShape::sphere(0.012), Action::Add, [0.3, 0.5, 0.7, 1.0]);
    apply_tool(&mut f, &tool, Pose::default(), 0.0);
    f
}

/// The largest difference between neighbouring finest points along each axis, over every
/// brick holding clay on any level (each brick and its three upper neighbours read once).
fn largest_step(f: &Field) -> f32 {
    let mut step = 0.0f32;
    let mut scratch: [Brick; 4] = Default::default();
    for key in f.covered_keys() {
        let [own, up_x, up_y, up_z] = &mut scratch;
        let empty = Brick::default();
        let own = f.read_brick(key, own).unwrap_or(&empty);
        let up = [
            f.read_brick(key + IVec3::X, up_x).unwrap_or(&empty),
            f.read_brick(key + IVec3::Y, up_y).unwrap_or(&empty),
            f.read_brick(key + IVec3::Z, up_z).unwrap_or(&empty),
        ];
        for z in 0..BRICK_SIZE {
            for y in 0..BRICK_SIZE {
                for x in 0..BRICK_SIZE {
                    let p = IVec3::new(x, y, z);
                    let d = own.density(Brick::linear(p));
                    for (axis, next) in [IVec3::X, IVec3::Y, IVec3::Z].into_iter().zip(up) {
                        let q = p + axis;
                        let n = if q.cmplt(IVec3::splat(BRICK_SIZE)).all() {
                            own.density(Brick::linear(q))
                        } else {
                            next.density(Brick::linear(q.rem_euclid(IVec3::splat(BRICK_SIZE))))
                        };
                        step = step.max((n - d).abs());
                    }
                }
            }
        }
    }
    step
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 16,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x4c45_5645),
        ..ProptestConfig::default()
    })]

    /// Strokes of every size over fine clay: undoing them all gives back the first field bit for
    /// bit, on every level, and redoing them all the last one; no density leaves [0, 1]; the
    /// field never steps between neighbouring points by more than a band-limited solid's ramp
    /// (a quarter per voxel) plus the steepest change a level-1 edit carries into it (as much
    /// again): no seam where levels meet.
    #[test]
    fn strokes_of_every_size_undo_exactly_and_stay_continuous(
        strokes in prop::collection::vec(stroke_spec(), 1..5),
    ) {
        let mut f = base_field();
        let first = f.clone();
        for s in &strokes {
            play(&mut f, s);
        }
        let last = f.clone();
        let step = largest_step(&f);
        prop_assert!(step <= 0.5 + 1e-4, "a step of {step} between neighbouring points");
        for k in f.covered_keys() {
            let mut r = FieldReader::new(&f);
            let d = r.density(k * BRICK_SIZE);
            prop_assert!((0.0..=1.0).contains(&d), "density {d}");
        }
        while f.undo().unwrap() {}
        prop_assert!(f.same_samples(&first), "undo restores every level");
        while f.redo() {}
        prop_assert!(f.same_samples(&last), "redo restores every level");
    }
}

#[test]
fn a_tool_ten_times_larger_edits_a_level_three_times_coarser() {
    let f = Field::new(VOXEL_M, 0.5);
    assert_eq!(edit_level_for(&f, 0.004, MAX_SIZE_SAMPLES), 0);
    assert_eq!(edit_level_for(&f, 0.008, MAX_SIZE_SAMPLES), 0);
    assert_eq!(edit_level_for(&f, 0.012, MAX_SIZE_SAMPLES), 1);
    assert_eq!(edit_level_for(&f, 0.040, MAX_SIZE_SAMPLES), 3);
    assert_eq!(edit_level_for(&f, 5.0, MAX_SIZE_SAMPLES), 4, "the coarsest level bounds it");

    // The 40 mm stamp into empty space writes level 3 alone and computes about as many samples
    // as the 4 mm one.
    let stamp = |radius_m: f32| {
        let mut f = Field::new(VOXEL_M, 0.5);
        let tool = Tool {
            level_samples: Some(MAX_SIZE_SAMPLES),
            ..Tool::new(ToolShape::sphere(radius_m), Action::Add, [1.0; 4])
        };
        let c = apply_tool(&mut f, &tool, Pose::default(), 0.0);
        (c, f)
    };
    let (small, _) = stamp(0.004);
    let (large, f) = stamp(0.040);
    assert_eq!((small.level, large.level), (0, 3));
    assert!(large.computed < 2 * small.computed, "{small:?} against {large:?}");
    assert_eq!(f.brick_count(), 0);
    assert!(f.level_brick_count(3) > 0);
    // Read on the finest lattice, it is a sphere of 40 mm.
    let crossing = (0..60)
        .find(|&x| f.density(IVec3::new(x, 0, 0)) >= 0.5 && f.density(IVec3::new(x + 1, 0, 0)) < 0.5)
        .expect("a surface on the axis");
    assert!((crossing as f32 - 40.0).abs() <= 2.0, "surface at {crossing} voxels");
}

#[test]
fn a_coarse_edit_keeps_the_fine_detail_it_passes_over() {
    // Fine clay with engraved detail: a groove one voxel deep along x.
    let mut f = Field::new(VOXEL_M, 0.5);
    f.edit_box(IVec3::new(-40, -40, -40), IVec3::new(40, 0, 40), true, |p, d, _| {
        // A slab whose top ramps gently from 1 to 0 over 16 voxels of y, grooved where
        // |z| ≤ 1: the clay under the tool is nowhere full or empty, so no change saturates.
        let top = if p.z.abs() <= 1 { -3.0 } else { -2.0 };
        *d = (0.5 - (p.y as f32 - top) / 16.0).clamp(0.0, 1.0);
    });
    let groove = |f: &Field, x: i32| {
        let (cut, flat) = (f.density(IVec3::new(x, -2, 0)), f.density(IVec3::new(x, -2, 8)));
        flat - cut
    };
    let before = groove(&f, 0);
    assert!((before - 1.0 / 16.0).abs() < 1e-6);
    // A soft build with a 32 mm tool (level 2) raises the whole surface a little.
    let tool = Tool {
        level_samples: Some(MAX_SIZE_SAMPLES),
        ..Tool::new(ToolShape::sphere(0.032), Action::Build { rate_per_s: 0.4 }, [1.0; 4])
    };
    let c = apply_tool(
        &mut f,
        &tool,
        Pose { position_m: Vec3::new(0.0, -0.002, 0.0), ..Default::default() },
        0.25,
    );
    assert_eq!(c.level, 2);
    let after = groove(&f, 0);
    assert!((after - before).abs() < 1e-5, "the groove keeps its depth: {before} then {after}");
    assert!(f.density(IVec3::new(0, -2, 8)) > 0.5 + 0.05, "the surface rose");
}

#[test]
fn a_coarse_tool_moved_by_a_tenth_of_a_voxel_moves_the_surface_by_a_little() {
    // A 32 mm tool edits level 2 (4 mm voxels); moving it by 0.1 mm moves the surface it leaves
    // by about as much, never by a jump.
    let surface = |offset_m: f32| {
        let mut f = Field::new(VOXEL_M, 0.5);
        let tool = Tool {
            level_samples: Some(MAX_SIZE_SAMPLES),
            ..Tool::new(ToolShape::sphere(0.032), Action::Add, [1.0; 4])
        };
        apply_tool(
            &mut f,
            &tool,
            Pose { position_m: Vec3::new(offset_m, 0.0, 0.0), ..Default::default() },
            0.0,
        );
        let x = (0..60)
            .find(|&x| f.density(IVec3::new(x, 0, 0)) >= 0.5 && f.density(IVec3::new(x + 1, 0, 0)) < 0.5)
            .expect("a surface on the axis");
        let (a, b) = (f.density(IVec3::new(x, 0, 0)), f.density(IVec3::new(x + 1, 0, 0)));
        x as f32 + (a - 0.5) / (a - b)
    };
    let base = surface(0.0);
    for k in 1..=10 {
        let moved = surface(k as f32 * 0.0001) - base;
        let want = k as f32 * 0.1;
        assert!((moved - want).abs() < 0.05, "moved by {k} tenths: {moved} voxels");
    }
}
