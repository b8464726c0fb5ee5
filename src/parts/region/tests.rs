use super::*;
use crate::tool::{rasterize_solid, CsgOp, PlacedSolid};

const VOXEL_M: f32 = 0.001;

fn solid(field: &mut Field, solid: Solid, at: Vec3, colour: Colour) {
    let placed = PlacedSolid { solid, pose: Pose { position_m: at, ..Pose::default() }, scale: 1.0 };
    rasterize_solid(field, &placed, CsgOp::Union, colour);
}

fn ball_at(at: Vec3, radius_m: f32) -> Field {
    let mut f = Field::new(VOXEL_M, 0.5);
    solid(&mut f, Solid::Sphere { radius_m }, at, [0.8, 0.5, 0.3, 1.0]);
    f
}

fn density_at(field: &Field, world: Vec3) -> f32 {
    field.density(field.transform().world_to_index(world).round().as_ivec3())
}

fn boxed(centre: Vec3, half: f32) -> Region {
    Region::boxed(Pose { position_m: centre, ..Pose::default() }, Vec3::splat(half))
}

fn finite_and_bounded(field: &Field, lo: IVec3, hi: IVec3) {
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                let d = field.density(IVec3::new(x, y, z));
                assert!((0.0..=1.0).contains(&d), "density {d} at {x} {y} {z}");
            }
        }
    }
}

#[test]
fn a_moved_region_lands_whole_and_leaves_nothing_behind() {
    let mut f = ball_at(Vec3::ZERO, 0.01);
    let before = f.mass();
    let mut drag = RegionDrag::start(&f, boxed(Vec3::ZERO, 0.015), RegionOp::Move, &[]).unwrap();
    // Twenty-three voxels along X: the clay lands on the lattice, exactly as it was.
    let stats = drag
        .update(&mut f, Motion { translation_m: Vec3::new(0.023, 0.0, 0.0), ..Motion::still(Vec3::ZERO) })
        .unwrap();
    assert!(stats.written > 0 && stats.copied > 0);
    assert!((f.mass() - before).abs() < 1e-6 * before, "mass {before} → {}", f.mass());
    assert_eq!(density_at(&f, Vec3::ZERO), 0.0, "nothing left where it was");
    let moved = ball_at(Vec3::new(0.023, 0.0, 0.0), 0.01);
    for p in [IVec3::new(23, 0, 0), IVec3::new(30, 5, -3), IVec3::new(14, 0, 0), IVec3::new(33, 2, 1)] {
        assert!(
            (f.density(p) - moved.density(p)).abs() < 2e-3,
            "at {p}: {} {}",
            f.density(p),
            moved.density(p)
        );
        let (a, b) = (f.colour(p), moved.colour(p));
        assert!(a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-4), "{a:?} {b:?}");
    }
}

#[test]
fn moving_back_gives_the_clay_back_bit_for_bit_and_one_undo_takes_the_drag_back() {
    let mut f = ball_at(Vec3::new(0.002, 0.0, 0.0), 0.008);
    let start = f.clone();
    f.begin_stroke();
    let mut drag = RegionDrag::start(&f, boxed(Vec3::ZERO, 0.01), RegionOp::Move, &[]).unwrap();
    let turn = Quat::from_euler(glam::EulerRot::XYZ, 0.3, 0.5, -0.2);
    for (i, t) in [0.004f32, 0.011, 0.03].into_iter().enumerate() {
        let m =
            Motion { translation_m: Vec3::new(t, 0.3 * t, 0.0), rotation: turn, ..Motion::still(Vec3::ZERO) };
        drag.update(&mut f, m).unwrap();
        assert!(!f.same_samples(&start), "update {i} changed nothing");
    }
    drag.update(&mut f, Motion::still(Vec3::ZERO)).unwrap();
    assert!(f.same_samples(&start), "the hand came back: the clay is as it was");
    drag.update(&mut f, Motion { translation_m: Vec3::new(0.0, 0.02, 0.0), ..Motion::still(Vec3::ZERO) })
        .unwrap();
    f.end_stroke();
    assert!(f.undo().unwrap());
    assert!(f.same_samples(&start), "one undo step");
}

#[test]
fn a_turned_region_keeps_its_clay_within_a_percent_and_stays_finite() {
    let mut f = Field::new(VOXEL_M, 0.5);
    solid(&mut f, Solid::Box { half_m: Vec3::new(0.012, 0.004, 0.004) }, Vec3::ZERO, [1.0; 4]);
    let before = f.mass();
    let mut drag = RegionDrag::start(&f, boxed(Vec3::ZERO, 0.016), RegionOp::Move, &[]).unwrap();
    let m = Motion {
        translation_m: Vec3::new(0.0, 0.03, 0.0),
        rotation: Quat::from_rotation_z(std::f32::consts::FRAC_PI_2 * 0.7),
        ..Motion::still(Vec3::ZERO)
    };
    drag.update(&mut f, m).unwrap();
    let after = f.mass();
    assert!((after - before).abs() < 0.01 * before, "mass {before} → {after}");
    finite_and_bounded(&f, IVec3::splat(-20), IVec3::new(20, 50, 20));
    // The bar's end turned with it.
    let end = m.apply(Vec3::new(0.01, 0.0, 0.0));
    assert!(density_at(&f, end) > 0.9, "{end}");
    assert_eq!(density_at(&f, Vec3::new(0.01, 0.0, 0.0)), 0.0);
}

#[test]
fn three_copies_in_a_row_then_the_row_copied_twice_make_a_grid_of_nine() {
    let mut f = Field::new(VOXEL_M, 0.5);
    solid(&mut f, Solid::Box { half_m: Vec3::new(0.004, 0.006, 0.004) }, Vec3::ZERO, [0.2, 0.4, 0.9, 1.0]);
    let one = f.mass();
    let cell = boxed(Vec3::ZERO, 0.009);
    let step = Motion { translation_m: Vec3::new(0.02, 0.0, 0.0), ..Motion::still(Vec3::ZERO) };
    copy_repeated(&mut f, &cell, step, 2, &[]).unwrap();
    let row = Region::boxed(
        Pose { position_m: Vec3::new(0.02, 0.0, 0.0), ..Pose::default() },
        Vec3::new(0.029, 0.009, 0.009),
    );
    let down = Motion { translation_m: Vec3::new(0.0, 0.0, 0.02), ..Motion::still(Vec3::ZERO) };
    copy_repeated(&mut f, &row, down, 2, &[]).unwrap();
    assert!((f.mass() / one - 9.0).abs() < 1e-3, "{} copies' worth", f.mass() / one);
    for i in 0..3 {
        for k in 0..3 {
            let at = Vec3::new(0.02 * i as f32, 0.0, 0.02 * k as f32);
            assert!(density_at(&f, at) > 0.99, "copy {i} {k}");
            let c = f.colour(f.transform().world_to_index(at).round().as_ivec3());
            assert!((c[2] - 0.9).abs() < 1e-4, "{c:?}");
        }
    }
}

#[test]
fn a_motion_repeated_composes_exactly() {
    let m = Motion {
        pivot_m: Vec3::new(0.1, 0.0, 0.0),
        translation_m: Vec3::new(0.0, 0.02, 0.01),
        rotation: Quat::from_rotation_y(0.4),
    };
    let p = Vec3::new(0.3, -0.1, 0.2);
    assert!(m.times(3).apply(p).distance(m.apply(m.apply(m.apply(p)))) < 1e-6);
    assert!(m.inverse_apply(m.apply(p)).distance(p) < 1e-6);
    assert_eq!(m.times(0).apply(p), p);
}

/// Whether the clay's samples over 0.5 connect `from` to `to` within the box `lo ..= hi`.
fn connected(field: &Field, from: IVec3, to: IVec3, lo: IVec3, hi: IVec3) -> bool {
    let mut seen = std::collections::HashSet::new();
    let mut queue = vec![from];
    while let Some(p) = queue.pop() {
        if p == to {
            return true;
        }
        if !seen.insert(p) || field.density(p) <= 0.5 {
            continue;
        }
        for d in [IVec3::X, IVec3::NEG_X, IVec3::Y, IVec3::NEG_Y, IVec3::Z, IVec3::NEG_Z] {
            let q = p + d;
            if q.cmpge(lo).all() && q.cmple(hi).all() && !seen.contains(&q) {
                queue.push(q);
            }
        }
    }
    false
}

#[test]
fn a_bend_carries_the_end_of_a_bar_far_without_tearing_or_folding_it() {
    let mut f = Field::new(VOXEL_M, 0.5);
    solid(&mut f, Solid::Box { half_m: Vec3::new(0.04, 0.005, 0.005) }, Vec3::ZERO, [1.0; 4]);
    let start = f.clone();
    let grab = Vec3::new(0.035, 0.0, 0.0);
    let mut drag = RegionDrag::start(&f, Region::ball(grab, 0.03), RegionOp::Bend, &[]).unwrap();
    // Up by one and a half times the falloff's radius: in one step this would fold the clay.
    let lift = Vec3::new(0.0, 0.045, 0.0);
    let stats = drag.update(&mut f, Motion { translation_m: lift, ..Motion::still(grab) }).unwrap();
    assert!(stats.sweep_steps >= 6, "{} steps", stats.sweep_steps);
    assert!(density_at(&f, grab + lift) > 0.9, "the grabbed end went with the hand");
    assert!(density_at(&f, grab) < 0.1, "and left its place");
    assert_eq!(density_at(&f, Vec3::new(-0.035, 0.0, 0.0)), density_at(&start, Vec3::new(-0.035, 0.0, 0.0)));
    let t = *f.transform();
    let index = |w: Vec3| t.world_to_index(w).round().as_ivec3();
    assert!(
        connected(
            &f,
            index(Vec3::new(-0.035, 0.0, 0.0)),
            index(grab + lift),
            IVec3::new(-45, -10, -10),
            IVec3::new(45, 60, 10)
        ),
        "the bar is still one piece"
    );
    finite_and_bounded(&f, IVec3::new(-45, -10, -10), IVec3::new(45, 60, 10));
    // The bar's cross-section stays about as thick: neither torn thin nor folded double.
    let thick =
        |x: f32| (-10..60).filter(|&j| density_at(&f, Vec3::new(x, j as f32 * VOXEL_M, 0.0)) > 0.5).count();
    for x in [0.015f32, 0.025, 0.035] {
        let n = thick(x);
        assert!((8..=24).contains(&n), "{n} voxels of clay across the bar at x = {x}");
    }
    // Back where it started: exact.
    drag.update(&mut f, Motion::still(grab)).unwrap();
    assert!(f.same_samples(&start));
}

#[test]
fn inflating_grows_the_clay_within_the_region_only_and_deflating_shrinks_it() {
    let mut f = ball_at(Vec3::ZERO, 0.01);
    let before = f.mass();
    let region = boxed(Vec3::new(0.01, 0.0, 0.0), 0.006);
    inflate(&mut f, &region, 0.002, &[]);
    let grown = f.mass();
    assert!(grown > before * 1.01, "{before} → {grown}");
    assert!(density_at(&f, Vec3::new(0.0115, 0.0, 0.0)) > 0.5, "the surface moved out by about 2 mm");
    assert_eq!(
        density_at(&f, Vec3::new(-0.0105, 0.0, 0.0)),
        density_at(&ball_at(Vec3::ZERO, 0.01), Vec3::new(-0.0105, 0.0, 0.0))
    );
    inflate(&mut f, &region, -0.004, &[]);
    assert!(f.mass() < before, "{} after deflating", f.mass());
    assert!(density_at(&f, Vec3::new(0.0085, 0.0, 0.0)) < 0.5);
}

#[test]
fn a_mirrored_move_moves_the_mirror_image_the_mirrored_way() {
    let mut f = ball_at(Vec3::new(0.02, 0.0, 0.0), 0.006);
    solid(&mut f, Solid::Sphere { radius_m: 0.006 }, Vec3::new(-0.02, 0.0, 0.0), [1.0; 4]);
    let mirror = crate::parts::Symmetry::mirror(crate::parts::Axis::X).images();
    let mut drag =
        RegionDrag::start(&f, boxed(Vec3::new(0.02, 0.0, 0.0), 0.008), RegionOp::Move, &mirror).unwrap();
    assert_eq!(drag.image_regions().count(), 1);
    drag.update(&mut f, Motion { translation_m: Vec3::new(0.01, 0.005, 0.0), ..Motion::still(Vec3::ZERO) })
        .unwrap();
    for p in [IVec3::new(30, 5, 0), IVec3::new(25, 9, 2), IVec3::new(20, 0, 0), IVec3::new(36, 5, -1)] {
        let q = IVec3::new(-p.x, p.y, p.z);
        assert_eq!(f.density(p), f.density(q), "at {p}");
    }
    assert!(density_at(&f, Vec3::new(-0.03, 0.005, 0.0)) > 0.9);
}

#[test]
fn a_region_too_large_to_copy_is_refused_and_an_empty_one_too() {
    let f = Field::new(VOXEL_M, 0.5);
    let huge = boxed(Vec3::ZERO, 0.2);
    assert!(matches!(RegionDrag::start(&f, huge, RegionOp::Move, &[]), Err(RegionError::TooLarge { .. })));
    let flat = Region::boxed(Pose::default(), Vec3::new(0.01, 0.0, 0.01));
    assert_eq!(RegionDrag::start(&f, flat, RegionOp::Copy, &[]).unwrap_err(), RegionError::Empty);
    let mut f = ball_at(Vec3::ZERO, 0.005);
    let mut drag = RegionDrag::start(&f, boxed(Vec3::ZERO, 0.006), RegionOp::Move, &[]).unwrap();
    let far = Motion { translation_m: Vec3::new(5.0, 0.0, 0.0), ..Motion::still(Vec3::ZERO) };
    let mut flung = f.clone();
    assert!(drag.update(&mut flung, far).is_ok(), "a small region carried far holds only where it went");
    let mut wide = RegionDrag::start(&f, boxed(Vec3::ZERO, 0.12), RegionOp::Move, &[]).unwrap();
    let before = f.clone();
    assert!(matches!(wide.update(&mut f, far), Err(RegionError::TooLarge { .. })));
    assert!(f.same_samples(&before), "a refused update leaves the clay as it was");
}

/// What a drag moved by `motion` should leave at each lattice point of `lo ..= hi`: every
/// point evaluated one by one on the clay as it was (`start`), none decided a brick or a block
/// at a time.
fn each_point(
    drag: &RegionDrag,
    start: &Field,
    motion: Motion,
    lo: IVec3,
    hi: IVec3,
) -> Vec<(IVec3, f32, Colour)> {
    let mut originals = TiledCopy::new();
    originals.take(start, lo, hi);
    let moved = drag.moved(motion, true);
    let how = drag.resample(&moved, *start.transform(), &originals);
    let mut reader = originals.reader();
    let mut out = Vec::new();
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                let p = IVec3::new(x, y, z);
                let (d, c) = how.point(p, reader.get(p));
                out.push((p, d, c));
            }
        }
    }
    out
}

#[test]
fn bricks_filled_whole_hold_what_each_point_evaluated_would_through_every_update() {
    // Two colours of clay: a ball and a bar through it.
    let mut start = ball_at(Vec3::new(0.001, 0.0, 0.0), 0.006);
    solid(
        &mut start,
        Solid::Box { half_m: Vec3::new(0.011, 0.002, 0.003) },
        Vec3::ZERO,
        [0.2, 0.4, 0.9, 1.0],
    );
    let turned = Pose { position_m: Vec3::new(0.0, 0.001, 0.0), rotation: Quat::from_rotation_z(0.4) };
    let mirror = crate::parts::Symmetry::mirror(crate::parts::Axis::X).images();
    let regions = [
        (Region::boxed(turned, Vec3::new(0.008, 0.006, 0.007)), RegionOp::Move, vec![]),
        (Region::ball(Vec3::new(0.002, 0.0, 0.0), 0.007), RegionOp::Copy, vec![]),
        (
            Region {
                shape: ToolShape::Solid(Solid::Torus { major_m: 0.006, minor_m: 0.003 }),
                frame: ToolFrame::new(turned, Vec3::new(1.0, 1.5, 0.8)),
            },
            RegionOp::Move,
            mirror.clone(),
        ),
        (
            Region {
                shape: ToolShape::Ellipsoid(crate::tool::Ellipsoid {
                    radii_m: Vec3::new(0.008, 0.005, 0.006),
                    falloff: crate::tool::Falloff::Wyvill,
                }),
                frame: ToolFrame::new(turned, Vec3::ONE),
            },
            RegionOp::Move,
            vec![],
        ),
        (Region::ball(Vec3::new(0.008, 0.0, 0.0), 0.006), RegionOp::Bend, mirror),
    ];
    let frames = [
        (Vec3::new(0.003, 0.0, 0.0), 0.0),
        (Vec3::new(0.007, 0.002, -0.001), 0.2),
        (Vec3::new(0.012, 0.004, 0.0), 0.5),
        (Vec3::new(0.004, -0.003, 0.002), -0.3),
    ];
    let (lo, hi) = (IVec3::new(-30, -24, -20), IVec3::new(30, 24, 20));
    for (k, (region, op, images)) in regions.into_iter().enumerate() {
        let mut f = start.clone();
        let mut drag = RegionDrag::start(&f, region, op, &images).unwrap();
        let mut filled = 0;
        for (i, &(translation_m, angle)) in frames.iter().enumerate() {
            let motion =
                Motion { translation_m, rotation: Quat::from_rotation_y(angle), ..Motion::still(Vec3::ZERO) };
            let stats = drag.update(&mut f, motion).unwrap();
            filled += stats.written - stats.evaluated;
            for (p, d, c) in each_point(&drag, &start, motion, lo, hi) {
                let got = f.density(p);
                assert!((got - d).abs() < 1e-4, "region {k}, update {i}, at {p}: {got} against {d}");
                if d > 0.01 {
                    let got = f.colour(p);
                    assert!(
                        got.iter().zip(c).all(|(a, b)| (a - b).abs() < 2e-3),
                        "region {k}, update {i}, colour at {p}: {got:?} against {c:?}"
                    );
                }
            }
        }
        assert!(filled > 0, "region {k}: some bricks or blocks were filled whole");
        drag.update(&mut f, Motion::still(Vec3::ZERO)).unwrap();
        // Every density and every colour of clay as it was (an empty sample's colour is none).
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let p = IVec3::new(x, y, z);
                    let (d, was) = (f.density(p), start.density(p));
                    assert!(
                        d == was && (d == 0.0 || f.colour(p) == start.colour(p)),
                        "region {k}: back, at {p}"
                    );
                }
            }
        }
        assert_eq!(f.brick_count(), start.brick_count());
    }
}

#[test]
fn an_update_leaves_alone_the_bricks_that_stay_as_the_last_one_left_them() {
    let mut f = ball_at(Vec3::ZERO, 0.01);
    let mut drag = RegionDrag::start(&f, boxed(Vec3::ZERO, 0.014), RegionOp::Move, &[]).unwrap();
    let step = |x: f32| Motion { translation_m: Vec3::new(x, 0.0, 0.0), ..Motion::still(Vec3::ZERO) };
    drag.update(&mut f, step(0.006)).unwrap();
    let moved = drag.update(&mut f, step(0.04)).unwrap();
    // Held again where it is: the bricks filled whole (the ball's inside, the place it left)
    // are as the last update left them, and only those of the ball's surface are written.
    let again = drag.update(&mut f, step(0.04)).unwrap();
    assert_eq!(again.evaluated, moved.evaluated);
    assert!(again.written < moved.written, "{} then {}", moved.written, again.written);
    assert!(again.written < again.evaluated + moved.written / 2, "{again:?} after {moved:?}");
}
