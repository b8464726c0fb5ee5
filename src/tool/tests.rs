//! Properties of the whole tool kit, with fixed seeds: density stays in [0, 1] and finite for
//! every action, removing never adds, painting never changes density, strokes do not depend on
//! the frame rate, and an oriented tool cuts the same amount of clay as an axis-aligned one.

use std::collections::HashSet;
use std::sync::Arc;

use proptest::prelude::*;

use super::*;
use crate::field::{Field, BRICK_SIZE};
use crate::math::{IVec3, Pose, Quat, Vec3};

const VOXEL_M: f32 = 0.001;

/// A field holding a sphere of clay of radius 12 voxels at the origin, painted grey-blue.
fn clay() -> Field {
    let mut f = Field::new(VOXEL_M, 0.5);
    stamp_sphere(&mut f, Vec3::ZERO, 0.012, Action::Add, [0.3, 0.4, 0.6, 1.0]);
    f
}

fn actions() -> Vec<Action> {
    vec![
        Action::Add,
        Action::Remove,
        Action::SoftRemove { rate_per_s: 3.0 },
        Action::Build { rate_per_s: 3.0 },
        Action::Paint,
        Action::SoftPaint { rate_per_s: 4.0 },
        Action::Smooth { centre_weight: 4.0, rate_per_s: 60.0 },
        Action::Stamp { deformation: Deformation::default(), falloff_m: 0.006 },
        Action::Inflate { speed_m_per_s: 0.05 },
        Action::Deflate { speed_m_per_s: 0.05 },
    ]
}

fn shapes(source: &Field) -> Vec<ToolShape> {
    vec![
        ToolShape::sphere(0.006),
        ToolShape::Solid(Solid::Box { half_m: Vec3::new(0.004, 0.007, 0.005) }),
        ToolShape::Solid(Solid::Cylinder { radius_m: 0.004, half_height_m: 0.006 }),
        ToolShape::Solid(Solid::Torus { major_m: 0.006, minor_m: 0.0025 }),
        ToolShape::Ellipsoid(Ellipsoid { radii_m: Vec3::new(0.008, 0.005, 0.006), falloff: Falloff::Wyvill }),
        ToolShape::Ellipsoid(Ellipsoid { radii_m: Vec3::new(0.006, 0.004, 0.005), falloff: Falloff::Box }),
        ToolShape::Freeform(Arc::new(Freeform::from_field(source, IVec3::splat(-6), IVec3::splat(6)))),
    ]
}

/// Every finest lattice point of every brick holding clay in either field, on any level.
fn points(a: &Field, b: &Field) -> Vec<IVec3> {
    let keys: HashSet<IVec3> = a.covered_keys().into_iter().chain(b.covered_keys()).collect();
    let mut out = Vec::new();
    for key in keys {
        for z in 0..BRICK_SIZE {
            for y in 0..BRICK_SIZE {
                for x in 0..BRICK_SIZE {
                    out.push(key * BRICK_SIZE + IVec3::new(x, y, z));
                }
            }
        }
    }
    out
}

fn pose(p: (f32, f32, f32), r: (f32, f32, f32)) -> Pose {
    Pose {
        position_m: Vec3::new(p.0, p.1, p.2),
        rotation: Quat::from_euler(glam::EulerRot::XYZ, r.0, r.1, r.2),
    }
}

fn small_sphere_source() -> Field {
    let mut f = Field::new(VOXEL_M, 0.5);
    stamp_sphere(&mut f, Vec3::ZERO, 0.004, Action::Add, [1.0; 4]);
    f
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 48,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x544f_4f4c),
        ..ProptestConfig::default()
    })]

    /// Whatever the action, shape, pose, scale and time step, density stays in [0, 1] and
    /// finite; removing never adds matter anywhere; painting never changes density.
    #[test]
    fn every_action_keeps_density_in_range_and_its_promises(
        action in 0usize..10,
        shape in 0usize..7,
        p in (-0.015f32..0.015, -0.015f32..0.015, -0.015f32..0.015),
        r in (-3.2f32..3.2, -3.2f32..3.2, -3.2f32..3.2),
        scale in (0.5f32..2.0, 0.5f32..2.0, 0.5f32..2.0),
        dt in prop_oneof![Just(0.0f32), 0.0f32..0.5, Just(f32::NAN), Just(1e6f32)],
        repeats in 1usize..4,
        by_size in any::<bool>(),
    ) {
        let source = small_sphere_source();
        let tool = Tool {
            scale: Vec3::new(scale.0, scale.1, scale.2),
            // Sizes of 2 to 16 voxels: by size, they edit levels 0 to 2 over the clay of level 0.
            level_samples: by_size.then_some(3.0),
            ..Tool::new(shapes(&source)[shape].clone(), actions()[action], [0.9, 0.1, 0.1, 1.0])
        };
        let before = clay();
        let mut after = before.clone();
        for _ in 0..repeats {
            let c = apply_tool(&mut after, &tool, pose(p, r), dt);
            prop_assert!(c.visited >= c.computed && c.computed >= c.dirtied);
            let sized = tool.level_samples.map_or(0, |n| edit_level_for(&after, tool.size_m(), n));
            prop_assert!(c.level as usize == sized || (tool.action.reads_neighbours() && (c.level as usize) < sized));
        }
        for q in points(&before, &after) {
            let (d0, d1) = (before.density(q), after.density(q));
            prop_assert!((0.0..=1.0).contains(&d1), "{:?}: density {} at {}", tool.action, d1, q);
            if tool.action.only_removes() {
                prop_assert!(d1 <= d0, "{:?} added matter at {}: {} → {}", tool.action, q, d0, d1);
            }
            if tool.action.only_paints() {
                prop_assert_eq!(d0, d1, "paint changed density at {}", q);
            }
            prop_assert!(after.colour(q).iter().all(|c| c.is_finite()));
        }
    }

    /// A stroke advanced in frames of one duration gives the same clay as the same stroke in
    /// frames of another, for every action.
    #[test]
    fn strokes_do_not_depend_on_the_frame_rate(
        action in 0usize..10,
        from in (-0.012f32..0.0, -0.004f32..0.004, -0.004f32..0.004),
        length_m in 0.004f32..0.02,
        duration_s in 0.1f32..0.6,
        frames in (2usize..12, 12usize..60),
        turn in -1.5f32..1.5,
    ) {
        let tool = Tool {
            scale: Vec3::new(1.0, 0.7, 1.3),
            ..Tool::new(ToolShape::Solid(Solid::Box { half_m: Vec3::splat(0.004) }), actions()[action], [0.9, 0.5, 0.1, 1.0])
        };
        let start = pose(from, (0.0, 0.0, 0.0));
        let end = pose((from.0 + length_m, from.1, from.2), (0.0, turn, 0.0));
        let run = |n: usize| {
            let mut f = clay();
            let mut s = Stroke::new(tool.clone());
            s.advance(&mut f, start, 0.0);
            for i in 1..=n {
                s.advance(&mut f, start.lerp(&end, i as f32 / n as f32), duration_s / n as f32);
            }
            (f, s.stamp_count())
        };
        let (a, na) = run(frames.0);
        let (b, nb) = run(frames.1);
        prop_assert_eq!(na, nb, "same number of stamps");
        let mut worst = 0.0f32;
        for q in points(&a, &b) {
            worst = worst.max((a.density(q) - b.density(q)).abs());
        }
        prop_assert!(worst < 2e-3, "{:?}: largest density difference {}", tool.action, worst);
    }

    /// A rotated box or ellipsoid deposits the same matter as the axis-aligned one (no
    /// resampling of a rotated voxmap).
    #[test]
    fn oriented_tools_deposit_the_same_mass_as_aligned_ones(
        shape in prop_oneof![Just(1usize), Just(4), Just(5)],
        r in (-3.2f32..3.2, -3.2f32..3.2, -3.2f32..3.2),
        offset in (0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0),
    ) {
        let source = small_sphere_source();
        let tool = Tool { scale: Vec3::new(1.5, 1.0, 0.8), ..Tool::new(shapes(&source)[shape].clone(), Action::Add, [1.0; 4]) };
        let at = (offset.0 * VOXEL_M, offset.1 * VOXEL_M, offset.2 * VOXEL_M);
        let mut aligned = Field::new(VOXEL_M, 0.5);
        apply_tool(&mut aligned, &tool, pose(at, (0.0, 0.0, 0.0)), 0.0);
        let mut rotated = Field::new(VOXEL_M, 0.5);
        apply_tool(&mut rotated, &tool, pose(at, r), 0.0);
        let rel = (rotated.mass() - aligned.mass()).abs() / aligned.mass();
        prop_assert!(rel < 0.01, "{:?}: mass {} rotated vs {} aligned", tool.shape, rotated.mass(), aligned.mass());
    }
}

#[test]
fn the_general_path_and_the_sphere_kernel_agree() {
    // A sphere scaled unevenly takes the general path; scaled (2, 2, 2.000001) it is a sphere.
    let mut a = Field::new(VOXEL_M, 0.5);
    let mut b = Field::new(VOXEL_M, 0.5);
    let at = Pose { position_m: Vec3::new(0.0003, -0.0002, 0.0001), ..Pose::default() };
    stamp_sphere(&mut a, at.position_m, 0.008, Action::Add, [1.0; 4]);
    let tool = Tool {
        scale: Vec3::new(2.0, 2.0, 2.000_001),
        ..Tool::new(ToolShape::sphere(0.004), Action::Add, [1.0; 4])
    };
    let c = apply_tool(&mut b, &tool, at, 0.0);
    assert!((a.mass() - b.mass()).abs() < 1e-3 * a.mass());
    assert!(c.dirtied > 0 && c.bricks >= 8);
    let mut fast = Field::new(VOXEL_M, 0.5);
    let c = apply_tool(&mut fast, &Tool { scale: Vec3::splat(2.0), ..tool }, at, 0.0);
    assert!(fast.same_samples(&a), "the sphere path is the stamp_sphere kernel");
    // It computes only the points within the ball's reach, of all those of its box.
    assert!(c.visited > c.computed && c.computed > c.dirtied && c.dirtied > 0, "{c:?}");
    // Carving the clay both left, off centre: the same samples again.
    let carve = Pose { position_m: at.position_m + Vec3::new(0.0061, 0.0013, -0.0007), ..at };
    stamp_sphere(&mut a, carve.position_m, 0.006, Action::Remove, [1.0; 4]);
    apply_tool(&mut fast, &Tool::new(ToolShape::sphere(0.006), Action::Remove, [1.0; 4]), carve, 0.0);
    assert!(fast.same_samples(&a) && fast.mass() < b.mass(), "removing");
}

#[test]
fn counters_tell_visited_computed_and_dirtied_apart() {
    // A thin box rotated 45° fills a small part of its world bounding box.
    let tool = Tool::new(
        ToolShape::Solid(Solid::Box { half_m: Vec3::new(0.02, 0.002, 0.002) }),
        Action::Add,
        [1.0; 4],
    );
    let mut f = Field::new(VOXEL_M, 0.5);
    let p = Pose { position_m: Vec3::ZERO, rotation: Quat::from_rotation_z(std::f32::consts::FRAC_PI_4) };
    let c = apply_tool(&mut f, &tool, p, 0.0);
    assert!(c.visited > 3 * c.computed, "{c:?}");
    assert!(c.computed > c.dirtied && c.dirtied > 0, "{c:?}");
    // Stamping again in the same place changes nothing.
    let again = apply_tool(&mut f, &tool, p, 0.0);
    assert_eq!(again.dirtied, 0);
    assert_eq!(again.computed, c.computed);
}

#[test]
fn heat_gun_melts_in_proportion_to_time_and_removes_everything_eventually() {
    let tool = Tool::new(ToolShape::sphere(0.02), Action::SoftRemove { rate_per_s: 1.0 }, [0.0; 4]);
    let mut f = clay();
    let m0 = f.mass();
    apply_tool(&mut f, &tool, Pose::default(), 0.25);
    assert!((f.density(IVec3::ZERO) - 0.75).abs() < 1e-6);
    assert!(f.mass() < m0);
    apply_tool(&mut f, &tool, Pose::default(), 1.0);
    assert_eq!(f.mass(), 0.0);
}

#[test]
fn smoothing_rounds_a_box_corner_and_keeps_the_bulk() {
    let mut f = Field::new(VOXEL_M, 0.5);
    let cube =
        PlacedSolid { solid: Solid::Box { half_m: Vec3::splat(0.01) }, pose: Pose::default(), scale: 1.0 };
    rasterize_solid(&mut f, &cube, CsgOp::Union, [1.0; 4]);
    let corner = IVec3::splat(9);
    let before = f.density(corner);
    let tool = Tool::new(
        ToolShape::sphere(0.006),
        Action::Smooth { centre_weight: 4.0, rate_per_s: 120.0 },
        [1.0; 4],
    );
    let m0 = f.mass();
    for _ in 0..30 {
        apply_tool(&mut f, &tool, Pose { position_m: Vec3::splat(0.01), ..Pose::default() }, TICK_S);
    }
    assert!(f.density(corner) < before - 0.05, "the corner wears away: {} → {}", before, f.density(corner));
    assert!((f.mass() - m0).abs() < 0.05 * m0, "sanding moves matter, it does not destroy it");
}

#[test]
fn a_gentler_centre_weight_smooths_less() {
    let corner = IVec3::splat(9);
    let sanded = |w: f32| {
        let mut f = Field::new(VOXEL_M, 0.5);
        let cube = PlacedSolid {
            solid: Solid::Box { half_m: Vec3::splat(0.01) },
            pose: Pose::default(),
            scale: 1.0,
        };
        rasterize_solid(&mut f, &cube, CsgOp::Union, [1.0; 4]);
        let tool = Tool::new(
            ToolShape::sphere(0.006),
            Action::Smooth { centre_weight: w, rate_per_s: 120.0 },
            [1.0; 4],
        );
        for _ in 0..10 {
            apply_tool(&mut f, &tool, Pose { position_m: Vec3::splat(0.01), ..Pose::default() }, TICK_S);
        }
        f.density(corner)
    };
    assert!(sanded(4.0) < sanded(24.0));
}

#[test]
fn inflating_moves_the_surface_out_and_deflating_in() {
    let crossing = |f: &Field| {
        (0..40)
            .find_map(|x| {
                let (a, b) = (f.density(IVec3::new(x, 0, 0)), f.density(IVec3::new(x + 1, 0, 0)));
                (a >= 0.5 && b < 0.5).then(|| x as f32 + (a - 0.5) / (a - b))
            })
            .expect("surface on the axis")
    };
    let base = clay();
    let r0 = crossing(&base);
    for (action, sign) in
        [(Action::Inflate { speed_m_per_s: 0.012 }, 1.0), (Action::Deflate { speed_m_per_s: 0.012 }, -1.0)]
    {
        let mut f = base.clone();
        let tool = Tool::new(ToolShape::sphere(0.03), action, [1.0; 4]);
        let mut s = Stroke::new(tool);
        s.advance(&mut f, Pose::default(), 0.0);
        s.advance(&mut f, Pose::default(), 0.25);
        // 0.012 m/s for 0.25 s: three voxels.
        let moved = crossing(&f) - r0;
        assert!((moved - 3.0 * sign).abs() < 0.6, "{action:?}: surface moved {moved} voxels");
        // Deep inside and far outside nothing changes: there is no surface there.
        assert_eq!(f.density(IVec3::ZERO), 1.0);
        assert_eq!(f.density(IVec3::new(25, 0, 0)), 0.0);
    }
}

#[test]
fn a_stamp_prints_a_hollow_and_raises_a_rim() {
    // A slab of clay with its top at y = 0; a ball pressed 4 mm into it.
    let mut f = Field::new(VOXEL_M, 0.5);
    let slab = PlacedSolid {
        solid: Solid::Box { half_m: Vec3::new(0.03, 0.01, 0.03) },
        pose: Pose { position_m: Vec3::new(0.0, -0.01, 0.0), ..Pose::default() },
        scale: 1.0,
    };
    rasterize_solid(&mut f, &slab, CsgOp::Union, [1.0; 4]);
    let top =
        |f: &Field, x: i32| (-20..10).rev().find(|&y| f.density(IVec3::new(x, y, 0)) >= 0.5).unwrap_or(-99);
    assert_eq!(top(&f, 0), 0);
    let deformation = Deformation::new(0.5, 0.25, 0.25, -2.0, 0.5).unwrap();
    let tool = Tool::new(
        ToolShape::sphere(0.008),
        Action::Stamp { deformation, falloff_m: 0.008 },
        [1.0, 0.0, 0.0, 1.0],
    );
    let c =
        apply_tool(&mut f, &tool, Pose { position_m: Vec3::new(0.0, 0.004, 0.0), ..Pose::default() }, 0.0);
    assert!(c.dirtied > 0);
    assert!(top(&f, 0) <= -3, "a hollow under the ball: top at {}", top(&f, 0));
    let rim = (8..16).map(|x| top(&f, x)).max().unwrap();
    assert!(rim >= 1, "a rim rises around the print: {rim}");
    assert_eq!(top(&f, 28), 0, "far away the slab is untouched");
}

#[test]
fn paint_colours_the_clay_under_the_tool_only() {
    let mut f = clay();
    let tool = Tool::new(ToolShape::sphere(0.004), Action::Paint, [1.0, 0.0, 0.0, 1.0]);
    apply_tool(&mut f, &tool, Pose { position_m: Vec3::new(0.012, 0.0, 0.0), ..Pose::default() }, 0.0);
    assert_eq!(f.colour(IVec3::new(12, 0, 0)), [1.0, 0.0, 0.0, 1.0]);
    assert_eq!(f.colour(IVec3::new(-12, 0, 0)), [0.3, 0.4, 0.6, 1.0]);
}

#[test]
fn a_freeform_copy_used_as_a_tool_reproduces_its_source() {
    let source = small_sphere_source();
    let tool = Tool::new(
        ToolShape::Freeform(Arc::new(Freeform::from_field(&source, IVec3::splat(-8), IVec3::splat(8)))),
        Action::Add,
        [1.0; 4],
    );
    let mut f = Field::new(VOXEL_M, 0.5);
    apply_tool(&mut f, &tool, Pose { position_m: Vec3::new(0.02, 0.0, 0.0), ..Pose::default() }, 0.0);
    assert!((f.mass() - source.mass()).abs() < 1e-3 * source.mass());
    assert_eq!(f.density(IVec3::new(20, 0, 0)), 1.0);
    // Scaled twice as large along X, it deposits about twice the matter.
    let mut g = Field::new(VOXEL_M, 0.5);
    apply_tool(&mut g, &Tool { scale: Vec3::new(2.0, 1.0, 1.0), ..tool }, Pose::default(), 0.0);
    let ratio = g.mass() / source.mass();
    assert!((ratio - 2.0).abs() < 0.05, "ratio {ratio}");
}

#[test]
fn a_mirrored_image_of_an_asymmetric_tool_is_its_reflection_not_a_turn() {
    // An L of clay: a bar along +X and one along +Y, copied as a freeform tool.
    let mut source = Field::new(VOXEL_M, 0.5);
    let bar = |half: Vec3, at: Vec3| PlacedSolid {
        solid: Solid::Box { half_m: half },
        pose: Pose { position_m: at, ..Pose::default() },
        scale: 1.0,
    };
    rasterize_solid(
        &mut source,
        &bar(Vec3::new(0.006, 0.002, 0.002), Vec3::new(0.004, 0.0, 0.0)),
        CsgOp::Union,
        [1.0; 4],
    );
    rasterize_solid(
        &mut source,
        &bar(Vec3::new(0.002, 0.004, 0.002), Vec3::new(0.0, 0.003, 0.0)),
        CsgOp::Union,
        [1.0; 4],
    );
    let tool = Tool::new(
        ToolShape::Freeform(Arc::new(Freeform::from_field(&source, IVec3::splat(-12), IVec3::splat(12)))),
        Action::Add,
        [1.0; 4],
    );
    let pose = Pose {
        position_m: Vec3::new(0.02, 0.003, -0.004),
        rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.9, 0.3),
    };
    let mirror = crate::math::Isometry::reflection(Vec3::ZERO, Vec3::X);
    let (image, mirrored) = mirror.pose(&pose);
    assert!(mirrored);
    let stamp = |at: Pose, mirrored: bool| {
        let mut f = Field::new(VOXEL_M, 0.5);
        apply_tool_mirrored(&mut f, &tool, at, mirrored, 0.0);
        f
    };
    let (original, reflected, turned) = (stamp(pose, false), stamp(image, true), stamp(image, false));
    let (mut same, mut differ) = (0, 0);
    for k in -16..=16 {
        for j in -16..=16 {
            for i in 4..=36 {
                let d = original.density(IVec3::new(i, j, k));
                // The reflection: the same clay at the mirrored lattice point, within rounding.
                assert!((reflected.density(IVec3::new(-i, j, k)) - d).abs() < 0.02, "at {i} {j} {k}");
                same += usize::from(d > 0.5);
                differ += usize::from((turned.density(IVec3::new(-i, j, k)) > 0.5) != (d > 0.5));
            }
        }
    }
    assert!(same > 100, "the tool deposits clay: {same}");
    // Turned instead of reflected, the L would lie the other way round.
    assert!(differ > same / 4, "{differ} of {same} samples differ when turned");
}
