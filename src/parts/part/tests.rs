use super::*;
use crate::tool::{apply_tool, rasterize_solid, Action, CsgOp, PlacedSolid, Solid, Tool, ToolShape};

const RED: Colour = [0.8, 0.1, 0.1, 1.0];
const BLUE: Colour = [0.1, 0.2, 0.9, 1.0];

fn solid_field(voxel_m: f32, solid: Solid, at: Vec3, colour: Colour) -> Field {
    let mut field = Field::new(voxel_m, 0.5);
    let placed = PlacedSolid { solid, pose: Pose { position_m: at, rotation: Quat::IDENTITY }, scale: 1.0 };
    rasterize_solid(&mut field, &placed, CsgOp::Union, colour);
    field
}

fn ball(voxel_m: f32, radius_m: f32, at: Vec3, colour: Colour) -> Field {
    solid_field(voxel_m, Solid::Sphere { radius_m }, at, colour)
}

fn view(field: &Field, placement: Placement, op: Csg) -> PartView<'_> {
    PartView { field, placement, op, visible: true }
}

fn density(field: &Field, world_m: Vec3) -> f32 {
    FieldReader::new(field).density_world(world_m)
}

#[test]
fn one_part_at_rest_needs_no_composition_and_anything_else_does() {
    let f = ball(1e-3, 0.01, Vec3::ZERO, RED);
    assert!(!Composition::needed(&[view(&f, Placement::IDENTITY, Csg::Union)]));
    let moved = Placement::new(Quat::IDENTITY, Vec3::X * 0.01, 1.0).unwrap();
    assert!(Composition::needed(&[view(&f, moved, Csg::Union)]));
    assert!(Composition::needed(&[view(&f, Placement::IDENTITY, Csg::Difference)]));
    assert!(Composition::needed(&[view(&f, Placement::IDENTITY, Csg::Union), view(&f, moved, Csg::Union)]));
}

#[test]
fn placements_refuse_zero_negative_and_non_finite_scales_and_poses() {
    assert_eq!(Placement::new(Quat::IDENTITY, Vec3::ZERO, 0.0), Err(PlacementError::Scale(0.0)));
    assert!(Placement::new(Quat::IDENTITY, Vec3::ZERO, -1.0).is_err());
    assert!(Placement::new(Quat::IDENTITY, Vec3::ZERO, f32::NAN).is_err());
    assert!(Placement::new(Quat::IDENTITY, Vec3::ZERO, 1e6).is_err());
    assert_eq!(
        Placement::new(Quat::IDENTITY, Vec3::splat(f32::INFINITY), 1.0),
        Err(PlacementError::Degenerate)
    );
    assert_eq!(
        Placement::new(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0), Vec3::ZERO, 1.0),
        Err(PlacementError::Degenerate)
    );
    let p = Placement::new(Quat::from_rotation_y(0.7), Vec3::new(0.1, -0.2, 0.3), 2.5).unwrap();
    let x = Vec3::new(0.01, 0.02, -0.03);
    assert!((p.local_point(p.point(x)) - x).length() < 1e-6);
    assert!((p.to_matrix().transform_point3(x) - p.point(x)).length() < 1e-6);
    let q = Placement::new(Quat::from_rotation_x(-0.4), Vec3::new(0.0, 0.05, 0.0), 0.5).unwrap();
    assert!((p.then(&q).point(x) - q.point(p.point(x))).length() < 1e-6);
}

#[test]
fn a_part_moved_by_whole_voxels_is_its_own_samples_moved() {
    let f = ball(1e-3, 0.006, Vec3::ZERO, RED);
    let shift = Vec3::new(0.013, -0.004, 0.021);
    let moved = Placement::new(Quat::IDENTITY, shift, 1.0).unwrap();
    let c = Composition::build(&[view(&f, moved, Csg::Union)]);
    let mut a = FieldReader::new(&f);
    let mut b = FieldReader::new(c.field());
    for z in -8..=8 {
        for y in -8..=8 {
            for x in -8..=8 {
                let p = IVec3::new(x, y, z);
                assert_eq!(a.density(p), b.density(p + IVec3::new(13, -4, 21)), "at {p}");
            }
        }
    }
    assert_eq!(c.field().mass(), f.mass());
}

#[test]
fn a_quarter_turn_reads_the_parts_samples_without_interpolating() {
    let f = solid_field(
        1e-3,
        Solid::Box { half_m: Vec3::new(0.008, 0.003, 0.002) },
        Vec3::new(0.002, 0.0, 0.0),
        RED,
    );
    let turned = Placement::new(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2), Vec3::ZERO, 1.0).unwrap();
    let c = Composition::build(&[view(&f, turned, Csg::Union)]);
    assert_eq!(c.field().mass(), f.mass(), "a permutation of the lattice moves every sample whole");
    // The long axis now runs along y.
    assert!(density(c.field(), Vec3::new(0.0, 0.009, 0.0)) > 0.5);
    assert!(density(c.field(), Vec3::new(0.009, 0.0, 0.0)) < 0.5);
}

#[test]
fn union_difference_and_intersection_of_two_balls() {
    let a = ball(1e-3, 0.010, Vec3::ZERO, RED);
    let b = ball(1e-3, 0.010, Vec3::X * 0.012, BLUE);
    let inside_a_only = Vec3::X * -0.006;
    let both = Vec3::X * 0.006;
    let inside_b_only = Vec3::X * 0.018;
    for (op, expect) in [
        (Csg::Union, [true, true, true]),
        (Csg::Difference, [true, false, false]),
        (Csg::Intersection, [false, true, false]),
    ] {
        let c = Composition::build(&[
            view(&a, Placement::IDENTITY, Csg::Union),
            view(&b, Placement::IDENTITY, op),
        ]);
        let got = [inside_a_only, both, inside_b_only].map(|p| density(c.field(), p) > 0.5);
        assert_eq!(got, expect, "{}", op.name());
        for v in c.field().shared_bricks().flat_map(|(_, b)| b.densities().collect::<Vec<_>>()) {
            assert!(v.is_finite() && (0.0..=1.0).contains(&v));
        }
    }
    // Union: each ball keeps its colour.
    let c = Composition::build(&[
        view(&a, Placement::IDENTITY, Csg::Union),
        view(&b, Placement::IDENTITY, Csg::Union),
    ]);
    let at = |p: Vec3| {
        FieldReader::new(c.field()).colour(c.field().transform().world_to_index(p).round().as_ivec3())
    };
    assert_eq!(at(inside_a_only), RED);
    assert_eq!(at(inside_b_only), BLUE);
}

#[test]
fn the_first_part_composes_with_empty_clay() {
    let a = ball(1e-3, 0.010, Vec3::ZERO, RED);
    for op in [Csg::Difference, Csg::Intersection] {
        let c = Composition::build(&[view(&a, Placement::IDENTITY, op)]);
        assert_eq!(c.field().mass(), 0.0, "{} of nothing", op.name());
    }
}

#[test]
fn hidden_parts_are_left_out() {
    let a = ball(1e-3, 0.010, Vec3::ZERO, RED);
    let b = ball(1e-3, 0.006, Vec3::ZERO, BLUE);
    let mut cutter = view(&b, Placement::IDENTITY, Csg::Difference);
    cutter.visible = false;
    let c = Composition::build(&[view(&a, Placement::IDENTITY, Csg::Union), cutter]);
    assert!(density(c.field(), Vec3::ZERO) > 0.99);
}

#[test]
fn a_coarser_part_is_sampled_on_a_coarser_level_of_the_composition() {
    let fine = ball(1e-3, 0.008, Vec3::ZERO, RED);
    let coarse = ball(2e-3, 0.012, Vec3::X * 0.03, BLUE);
    let scaled = ball(1e-3, 0.004, Vec3::ZERO, BLUE);
    let grown = Placement::new(Quat::IDENTITY, Vec3::X * -0.03, 4.0).unwrap();
    let parts = [
        view(&fine, Placement::IDENTITY, Csg::Union),
        view(&coarse, Placement::IDENTITY, Csg::Union),
        view(&scaled, grown, Csg::Union),
    ];
    let c = Composition::build(&parts);
    assert_eq!(c.field().transform().voxel_size_m, 1e-3);
    assert_eq!([c.level_of(0), c.level_of(1), c.level_of(2)], [0, 1, 2]);
    assert!(c.field().level_brick_count(1) > 0 && c.field().level_brick_count(2) > 0);
    for (centre, r) in [(Vec3::ZERO, 0.008), (Vec3::X * 0.03, 0.012), (Vec3::X * -0.03, 0.016)] {
        assert!(density(c.field(), centre) > 0.99);
        assert!(density(c.field(), centre + Vec3::Y * (r - 0.003)) > 0.5, "inside the ball at {centre}");
        assert!(density(c.field(), centre + Vec3::Y * (r + 0.003)) < 0.5, "outside the ball at {centre}");
    }
}

#[test]
fn an_edit_re_composes_what_it_touched_as_a_whole_build_would() {
    let mut a = ball(1e-3, 0.010, Vec3::ZERO, RED);
    let b = ball(2e-3, 0.010, Vec3::ZERO, BLUE);
    let turned = Placement::new(Quat::from_rotation_y(0.5), Vec3::new(0.015, 0.0, 0.0), 1.3).unwrap();
    let mut c =
        Composition::build(&[view(&a, Placement::IDENTITY, Csg::Union), view(&b, turned, Csg::Difference)]);
    let _ = c.field_mut().take_dirty();
    // A stamp on the first part, where the second does not cut.
    let tool = Tool::new(ToolShape::sphere(0.004), Action::Add, BLUE);
    a.begin_stroke();
    apply_tool(
        &mut a,
        &tool,
        Pose { position_m: Vec3::new(-0.011, 0.0, 0.0), rotation: Quat::IDENTITY },
        0.0,
    );
    a.end_stroke();
    let changed: Vec<(usize, IVec3, IVec3)> = a
        .take_dirty()
        .iter()
        .map(|k| (0, k * BRICK_SIZE, k * BRICK_SIZE + IVec3::splat(BRICK_SIZE - 1)))
        .collect();
    let parts = [view(&a, Placement::IDENTITY, Csg::Union), view(&b, turned, Csg::Difference)];
    c.update(&parts, &changed);
    assert!(!c.field_mut().take_dirty().is_empty(), "the composition's change is dirty for the mesher");
    let whole = Composition::build(&parts);
    assert!(c.field().same_samples(whole.field()), "the update is the whole build's");
}

#[test]
fn a_composition_marks_dirty_about_what_its_parts_changes_mark() {
    let mut a = Field::new(1e-3, 0.5);
    crate::tool::stamp_sphere(
        &mut a,
        Vec3::new(0.00031, -0.00017, 0.00023),
        0.1,
        crate::tool::Action::Add,
        RED,
    );
    let far = ball(2e-3, 0.03, Vec3::ZERO, BLUE);
    let away = Placement::new(Quat::from_rotation_y(0.5), Vec3::X * 0.2, 1.2).unwrap();
    let mut c =
        Composition::build(&[view(&a, Placement::IDENTITY, Csg::Union), view(&far, away, Csg::Union)]);
    let _ = c.field_mut().take_dirty();
    let _ = a.take_dirty();
    for i in 0..6 {
        let angle = i as f32 * 0.32;
        let centre = Vec3::new(angle.cos(), 0.3 * (i as f32 * 0.37).sin(), angle.sin()).normalize() * 0.1;
        crate::tool::stamp_sphere(&mut a, centre, 0.016, crate::tool::Action::Remove, RED);
        let dirty = a.take_dirty();
        let changed: Vec<(usize, IVec3, IVec3)> = dirty
            .iter()
            .map(|k| (0, k * BRICK_SIZE, k * BRICK_SIZE + IVec3::splat(BRICK_SIZE - 1)))
            .collect();
        c.update(&[view(&a, Placement::IDENTITY, Csg::Union), view(&far, away, Csg::Union)], &changed);
        let composed = c.field_mut().take_dirty();
        let extra: Vec<_> = composed.iter().filter(|k| !dirty.contains(*k)).collect();
        // Bricks the stamp empties are removed from the composition with what read their old
        // clay marked: a little more than the part's own marks, never the whole neighbourhood
        // of every brick a coarse part's presence would mark.
        assert!(
            composed.len() * 4 <= dirty.len() * 5,
            "stamp {i}: {} dirty in the part, {} in the composition; extra {:?}",
            dirty.len(),
            composed.len(),
            &extra[..extra.len().min(8)]
        );
    }
}
