use super::*;
use crate::field::{Field, FieldReader};
use crate::math::{Pose, Quat};
use crate::tool::{rasterize_solid, CsgOp, PlacedSolid, Solid};

const VOXEL: f32 = 0.002;

fn field_with(solid: Solid, at: Vec3) -> Field {
    let mut f = Field::new(VOXEL, 0.5);
    let placed = PlacedSolid { solid, pose: Pose { position_m: at, rotation: Quat::IDENTITY }, scale: 1.0 };
    rasterize_solid(&mut f, &placed, CsgOp::Union, [0.8, 0.4, 0.2, 1.0]);
    f
}

/// A bar of radius 12 mm and length 200 mm along X (ends included).
fn bar() -> Field {
    field_with(Solid::Bar { half_length_m: 0.088, radius_m: 0.012 }, Vec3::ZERO)
}

/// A box around the bar's middle, 120 × 60 × 60 mm.
fn bar_box() -> Aabb {
    Aabb { min: Vec3::new(-0.06, -0.03, -0.03), max: Vec3::new(0.06, 0.03, 0.03) }
}

fn open(field: &Field, spec: LatticeSpec) -> Lattice {
    Lattice::open(field, &spec).expect("the lattice opens")
}

/// The densities of `field` at the lattice points `lo ..= hi`.
fn samples(field: &Field, lo: IVec3, hi: IVec3) -> Vec<f32> {
    let mut r = FieldReader::new(field);
    let mut out = Vec::new();
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                out.push(r.density(IVec3::new(x, y, z)));
            }
        }
    }
    out
}

/// A small deterministic generator (xorshift).
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn everywhere(l: &Lattice) -> Aabb {
    l.reach().expanded(0.02)
}

#[test]
fn an_untouched_lattice_leaves_the_clay_bit_for_bit() {
    for spec in [
        LatticeSpec::cubic(bar_box(), [8, 5, 5]),
        LatticeSpec { kind: SplineKind::Bezier, ..LatticeSpec::cubic(bar_box(), [4, 4, 4]) },
        LatticeSpec {
            kind: SplineKind::Nurbs,
            knots: KnotStyle::Uniform,
            ..LatticeSpec::cubic(bar_box(), [6, 4, 4])
        },
    ] {
        let original = bar();
        let mut field = original.clone();
        let mut lattice = open(&field, spec);
        let stats = lattice.write(&mut field, everywhere(&lattice)).unwrap();
        // At rest: every brick is the clay as it was, none written.
        assert!(stats.written == 0 && stats.points == 0, "{stats:?}");
        assert!(field.same_samples(&original), "{:?}: the clay changed", spec.kind);
        // Moved and put back: exact again.
        let c = lattice.volume().control(2, 2, 2).unwrap().position_m;
        let b = lattice.move_control([2, 2, 2], c + Vec3::new(0.0, 0.01, 0.0)).unwrap();
        lattice.write(&mut field, b).unwrap();
        assert!(!field.same_samples(&original));
        let b = lattice.move_control([2, 2, 2], c).unwrap();
        lattice.write(&mut field, b).unwrap();
        assert!(field.same_samples(&original), "{:?}: not back after the move back", spec.kind);
    }
}

#[test]
fn raising_one_value_grows_the_clay_monotonically() {
    let mut field = bar();
    let mut lattice = open(&field, LatticeSpec::cubic(bar_box(), [8, 5, 5]));
    let ijk = [3, 2, 2];
    let f0 = lattice.volume().control(3, 2, 2).unwrap().value;
    let mut masses = vec![field.mass()];
    for step in 1..=6 {
        let b = lattice.set_value(ijk, f0 + 0.1 * step as f64).unwrap();
        lattice.write(&mut field, b).unwrap();
        masses.push(field.mass());
    }
    for w in masses.windows(2) {
        assert!(w[1] >= w[0], "the mass fell as the value rose: {masses:?}");
    }
    assert!(masses[6] > masses[0] * 1.02, "the clay barely grew: {masses:?}");
    // And lowering it below the fit shrinks the clay.
    let b = lattice.set_value(ijk, f0 - 0.3).unwrap();
    lattice.write(&mut field, b).unwrap();
    assert!(field.mass() < masses[0], "{} !< {}", field.mass(), masses[0]);
}

#[test]
fn nothing_changes_outside_the_lattice_and_its_faces_join_without_a_seam() {
    let original = bar();
    let mut field = original.clone();
    let mut lattice = open(&field, LatticeSpec::cubic(bar_box(), [6, 5, 5]));
    // Every interior control moved and re-valued: a strong, irregular deformation.
    let mut rng = Rng(7);
    let mut changed = Aabb::EMPTY;
    for k in 1..4 {
        for j in 1..4 {
            for i in 1..5 {
                let p = lattice.volume().control(i, j, k).unwrap().position_m;
                let d = Vec3::new(rng.next_f64() as f32 - 0.5, rng.next_f64() as f32 - 0.5, 0.0) * 0.015;
                changed = changed.union(&lattice.move_control([i, j, k], p + d).unwrap());
                let v = lattice.volume().control(i, j, k).unwrap().value;
                changed =
                    changed.union(&lattice.set_value([i, j, k], v + 0.2 * rng.next_f64() - 0.1).unwrap());
            }
        }
    }
    lattice.write(&mut field, changed).unwrap();
    assert!(!field.same_samples(&original));
    let (lo, hi) = lattice.points_of(bar_box().expanded(0.02));
    let (a, b) = (samples(&original, lo, hi), samples(&field, lo, hi));
    let dims = hi - lo + IVec3::ONE;
    let t = *field.transform();
    let region = bar_box();
    let mut worst_at_face = 0.0f32;
    for (n, (x, y)) in a.iter().zip(&b).enumerate() {
        let p =
            IVec3::new(n as i32 % dims.x, (n as i32 / dims.x) % dims.y, n as i32 / (dims.x * dims.y)) + lo;
        let w = t.index_to_world(p.as_vec3());
        let inside = w.cmpge(region.min - 0.25 * VOXEL).all() && w.cmple(region.max + 0.25 * VOXEL).all();
        if !inside {
            assert_eq!(x, y, "the clay changed outside the lattice at {w}");
        }
        // On a face the result is the clay as it was: it meets the clay outside, and its
        // change grows from nothing into the box (the mapping is continuous there).
        let to_face = (w - region.min).min(region.max - w).min_element();
        if to_face.abs() < 0.25 * VOXEL {
            worst_at_face = worst_at_face.max((x - y).abs());
        }
    }
    assert!(worst_at_face < 2e-3, "a seam on the lattice's faces: {worst_at_face}");
}

#[test]
fn a_b_spline_drag_acts_on_its_support_and_a_bezier_drag_on_the_whole_box() {
    for (spec, local) in [
        (LatticeSpec::cubic(bar_box(), [8, 6, 6]), true),
        (LatticeSpec { kind: SplineKind::Bezier, ..LatticeSpec::cubic(bar_box(), [8, 6, 6]) }, false),
    ] {
        let original = bar();
        let mut field = original.clone();
        let mut lattice = open(&field, spec);
        let ijk = [2, 3, 3];
        let support = lattice.changed_box(ijk).unwrap();
        let p = lattice.volume().control(2, 3, 3).unwrap().position_m;
        lattice.move_control(ijk, p + Vec3::new(0.0, 0.012, 0.0)).unwrap();
        lattice.write(&mut field, everywhere(&lattice)).unwrap();
        let (lo, hi) = lattice.points_of(bar_box());
        let (a, b) = (samples(&original, lo, hi), samples(&field, lo, hi));
        let dims = hi - lo + IVec3::ONE;
        let t = *field.transform();
        let mut changed_outside = 0;
        let mut changed = 0;
        for (n, (x, y)) in a.iter().zip(&b).enumerate() {
            let p = IVec3::new(n as i32 % dims.x, (n as i32 / dims.x) % dims.y, n as i32 / (dims.x * dims.y))
                + lo;
            let w = t.index_to_world(p.as_vec3());
            if x != y {
                changed += 1;
                if !(w.cmpge(support.min).all() && w.cmple(support.max).all()) {
                    changed_outside += 1;
                }
            }
        }
        assert!(changed > 0);
        if local {
            assert_eq!(changed_outside, 0, "a B-spline drag changed the clay outside its support");
            assert!(support.size().x < 0.9 * bar_box().size().x, "{support:?}");
        } else {
            // A Bézier control's support is the whole box: the clay changes along all of it.
            assert!(changed_outside == 0 && support.size().x >= bar_box().size().x);
            let xs: Vec<i32> = a
                .iter()
                .zip(&b)
                .enumerate()
                .filter(|(_, (x, y))| x != y)
                .map(|(n, _)| n as i32 % dims.x)
                .collect();
            let (min, max) = (xs.iter().min().unwrap(), xs.iter().max().unwrap());
            assert!((max - min) as f32 > 0.8 * dims.x as f32, "a Bézier drag acted locally: {min}..{max}");
        }
    }
}

#[test]
fn a_nurbs_weight_acts_only_near_the_clays_boundary() {
    // A ball filling the middle of the lattice.
    let original = field_with(Solid::Sphere { radius_m: 0.04 }, Vec3::ZERO);
    let region = Aabb { min: Vec3::splat(-0.06), max: Vec3::splat(0.06) };
    let spec = LatticeSpec { kind: SplineKind::Nurbs, ..LatticeSpec::cubic(region, [7, 7, 7]) };
    let mut field = original.clone();
    let mut lattice = open(&field, spec);
    let b = lattice.set_weight([3, 3, 3], 4.0).unwrap();
    lattice.write(&mut field, b).unwrap();
    let (lo, hi) = lattice.points_of(region);
    let (a, c) = (samples(&original, lo, hi), samples(&field, lo, hi));
    let dims = hi - lo + IVec3::ONE;
    let t = *field.transform();
    let mut changed = 0;
    for (n, (x, y)) in a.iter().zip(&c).enumerate() {
        if x != y {
            changed += 1;
            let p = IVec3::new(n as i32 % dims.x, (n as i32 / dims.x) % dims.y, n as i32 / (dims.x * dims.y))
                + lo;
            let r = t.index_to_world(p.as_vec3()).length();
            // Only within the ball's surface band: deep inside, every value is full clay.
            assert!((r - 0.04).abs() < 0.02, "a sample {r} m from the centre changed");
        }
    }
    assert!(changed > 0, "the weight did nothing");
}

#[test]
fn the_fit_reproduces_smooth_clay_and_reports_its_error_on_sharp_clay() {
    // A ramp of density along X, within [0.1, 0.9]: a polynomial the cubic fit reproduces.
    let mut smooth = Field::new(VOXEL, 0.5);
    let (lo, hi) = (IVec3::new(-40, -20, -20), IVec3::new(40, 20, 20));
    smooth.edit_box(lo, hi, true, |p, d, _| *d = 0.5 + 0.005 * p.x as f32);
    let region = Aabb { min: Vec3::new(-0.06, -0.03, -0.03), max: Vec3::new(0.06, 0.03, 0.03) };
    let lattice = open(&smooth, LatticeSpec::cubic(region, [6, 4, 4]));
    let fit = lattice.fit_report();
    // The density quantum is 1/65535: the ramp is reproduced to it.
    assert!(fit.max_error < 1e-4, "{fit:?}");
    let sharp = open(&bar(), LatticeSpec::cubic(bar_box(), [8, 5, 5])).fit_report();
    assert!(sharp.rms_error > 1e-3 && sharp.rms_error < 0.2, "{sharp:?}");
}

#[test]
fn a_raised_value_moves_the_surface_as_the_fitted_function_does() {
    // The bar's top surface at its middle: where the fitted function's iso-surface moves when
    // the values of the middle controls rise, and where the lattice moves the clay's.
    let mut field = bar();
    let mut lattice = open(&field, LatticeSpec::cubic(bar_box(), [7, 7, 7]));
    let raise = 0.15;
    let mut changed = Aabb::EMPTY;
    for k in 1..6 {
        for j in 1..6 {
            let v = lattice.volume().control(3, j, k).unwrap().value;
            changed = changed.union(&lattice.set_value([3, j, k], v + raise).unwrap());
        }
    }
    lattice.write(&mut field, changed).unwrap();
    let surface_y = |density: &mut dyn FnMut(f32) -> f32| {
        // Upwards from the axis: the first height where the density falls below 0.5.
        let mut y = 0.0f32;
        while y < 0.03 && density(y) >= 0.5 {
            y += 1e-5;
        }
        y
    };
    let mut reader = FieldReader::new(&field);
    let clay_y = surface_y(&mut |y| reader.density_world(Vec3::new(0.0, y, 0.0)));
    let at = |v: &SplineVolume, y: f32| v.value(v.rest_parameters(Vec3::new(0.0, y, 0.0))) as f32;
    let fitted_before = surface_y(&mut |y| at(lattice.fitted(), y));
    let fitted_after = surface_y(&mut |y| at(lattice.volume(), y));
    let moved_fit = fitted_after - fitted_before;
    let moved_clay = clay_y - 0.012;
    assert!(moved_fit > 0.0008, "the fitted surface barely moved: {moved_fit}");
    assert!(
        (moved_clay - moved_fit).abs() < 0.25 * moved_fit,
        "the clay moved {moved_clay} m, the fitted function's surface {moved_fit} m"
    );
}

#[test]
fn refusals_leave_the_lattice_as_it_was() {
    let field = bar();
    let mut lattice = open(&field, LatticeSpec::cubic(bar_box(), [5, 4, 4]));
    let before = lattice.volume().clone();
    assert!(matches!(lattice.move_control([1, 1, 1], Vec3::splat(50.0)), Err(LatticeError::TooLarge { .. })));
    assert!(lattice.move_control([9, 1, 1], Vec3::ZERO).is_err());
    assert!(lattice.set_value([1, 1, 1], f64::NAN).is_err());
    assert!(lattice.set_weight([1, 1, 1], 2.0).is_err(), "weights belong to NURBS");
    assert_eq!(lattice.volume(), &before);
    let huge = Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
    let e = Lattice::open(&field, &LatticeSpec::cubic(huge, [4, 4, 4])).unwrap_err();
    assert!(e.to_string().contains("over the limit"), "{e}");
}

/// Writes each change of `lattice` into `field` and checks the field against the lattice's
/// point-by-point evaluation of all it reaches: the same densities within the density
/// quantum and the mapping's tolerance, the same colours wherever there is clay. Returns the
/// writes' statistics.
fn written_as_evaluated(
    field: &mut Field,
    lattice: &mut Lattice,
    changes: &mut dyn FnMut(&mut Lattice, usize) -> Option<Aabb>,
    what: &str,
) -> Vec<LatticeStats> {
    let mut stats = Vec::new();
    field.begin_stroke();
    for step in 0.. {
        let Some(changed) = changes(lattice, step) else { break };
        stats.push(lattice.write(field, changed).unwrap());
        holds_the_evaluation(field, lattice, &format!("{what}, step {step}"));
    }
    field.end_stroke();
    stats
}

/// Checks `field` against `lattice`'s point-by-point evaluation of all it reaches: the same
/// densities within the density quantum and the mapping's tolerance, the same colours
/// wherever there is clay.
fn holds_the_evaluation(field: &Field, lattice: &Lattice, what: &str) {
    // Beyond the reach the lattice holds no copy of the clay (and changes none).
    let (lo, hi) = lattice.points_of(lattice.reach());
    let (mut d, mut c) = (Vec::new(), Vec::new());
    lattice.evaluate(lo, hi, &mut d, Some(&mut c));
    let dims = hi - lo + IVec3::ONE;
    let mut r = FieldReader::new(field);
    let tolerance = 2.0 * crate::field::DENSITY_TOLERANCE + 1e-4;
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let p = lo + IVec3::new(x, y, z);
                let i = (x + dims.x * (y + dims.y * z)) as usize;
                let got = r.density(p);
                assert!((got - d[i]).abs() <= tolerance, "{what}: {got} at {p}, evaluated {}", d[i]);
                if d[i] > 0.01 {
                    let colour = field.colour(p);
                    let off = (0..4).map(|k| (colour[k] - c[i][k]).abs()).fold(0.0f32, f32::max);
                    assert!(off < 1e-3, "{what}: colour {colour:?} at {p}, evaluated {:?}", c[i]);
                }
            }
        }
    }
}

#[test]
fn lattices_open_side_by_side_write_only_their_own_reach() {
    // Two lattices along the bar, their reaches 3 voxels apart and the bricks between them
    // shared: each writes whole bricks, yet leaves the other's clay as the other made it.
    let mut field = bar();
    let left = Aabb { min: Vec3::new(-0.06, -0.03, -0.03), max: Vec3::new(0.003, 0.03, 0.03) };
    let right = Aabb { min: Vec3::new(0.011, -0.03, -0.03), max: Vec3::new(0.06, 0.03, 0.03) };
    let mut a = open(&field, LatticeSpec::cubic(left, [6, 5, 5]));
    let mut b = open(&field, LatticeSpec::cubic(right, [6, 5, 5]));
    let (ra, rb) = (a.points_of(a.reach()), b.points_of(b.reach()));
    assert!(
        ra.1.x < rb.0.x && ra.1.x.div_euclid(BRICK_SIZE) == rb.0.x.div_euclid(BRICK_SIZE),
        "{ra:?} {rb:?}"
    );
    field.begin_stroke();
    // The right lattice's face toward the left one pulled up, then the left one dragged.
    let p = b.volume().control(0, 2, 2).unwrap().position_m;
    let changed = b.move_control([0, 2, 2], p + Vec3::new(0.004, 0.008, 0.0)).unwrap();
    b.write(&mut field, changed).unwrap();
    let p = a.volume().control(3, 2, 2).unwrap().position_m;
    let changed = a.move_control([3, 2, 2], p + Vec3::new(0.0, -0.008, 0.0)).unwrap();
    a.write(&mut field, changed).unwrap();
    field.end_stroke();
    holds_the_evaluation(&field, &a, "the left lattice");
    holds_the_evaluation(&field, &b, "the right lattice");
}

#[test]
fn a_write_brick_by_brick_gives_the_clay_of_the_point_by_point_evaluation() {
    let box_ = bar_box();
    let lift = |l: &mut Lattice, ijk: [usize; 3], by: Vec3| {
        let p = l.volume().control(ijk[0], ijk[1], ijk[2]).unwrap().position_m;
        l.move_control(ijk, p + by).unwrap()
    };
    // An interior control dragged up, down and back (the displacements' bound and the nodes
    // decide whole bricks), a value raised and lowered (the shift), a NURBS weight, a face
    // control (whose face then moves: no brick is full by the bound alone), uniform knots.
    type Changes = Box<dyn FnMut(&mut Lattice, usize) -> Option<Aabb>>;
    // With each: whether whole bricks are filled (a shift of the values or weights reaches a
    // control's spacing, here every brick of the box).
    let cases: Vec<(&str, LatticeSpec, Changes, bool)> = vec![
        (
            "an interior drag",
            LatticeSpec::cubic(box_, [8, 5, 5]),
            Box::new(move |l, step| {
                let by = [0.012, -0.024, 0.006, 0.006];
                (step < by.len()).then(|| lift(l, [3, 2, 2], Vec3::new(0.0, by[step], 0.002)))
            }),
            true,
        ),
        (
            "a value",
            LatticeSpec::cubic(box_, [8, 5, 5]),
            Box::new(|l, step| {
                let v = l.volume().control(3, 2, 2).unwrap().value;
                let by = [0.3, -0.5, 0.2];
                (step < by.len()).then(|| l.set_value([3, 2, 2], v + by[step]).unwrap())
            }),
            false,
        ),
        (
            "a weight and a drag",
            LatticeSpec { kind: SplineKind::Nurbs, ..LatticeSpec::cubic(box_, [6, 5, 5]) },
            Box::new(move |l, step| match step {
                0 => Some(l.set_weight([2, 2, 2], 3.0).unwrap()),
                1 => Some(lift(l, [3, 2, 2], Vec3::new(0.0, 0.01, 0.0))),
                _ => None,
            }),
            false,
        ),
        (
            "a face control",
            LatticeSpec::cubic(box_, [6, 5, 5]),
            Box::new(move |l, step| (step < 2).then(|| lift(l, [5, 2, 2], Vec3::new(-0.012, 0.006, 0.0)))),
            true,
        ),
        (
            "a twist, layer by layer",
            LatticeSpec::cubic(box_, [8, 4, 4]),
            Box::new(move |l, step| {
                // Layer `step + 1` turned about the bar's axis, the far face a quarter turn.
                let i = step + 1;
                (i < 8).then(|| {
                    let turn = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2 * i as f32 / 7.0);
                    let mut changed: Option<Aabb> = None;
                    for k in 0..4 {
                        for j in 0..4 {
                            let p = l.volume().control(i, j, k).unwrap().position_m;
                            let moved = Vec3::new(p.x, 0.0, 0.0) + turn * Vec3::new(0.0, p.y, p.z);
                            let b = l.move_control([i, j, k], moved).unwrap();
                            changed = Some(changed.map_or(b, |c| c.union(&b)));
                        }
                    }
                    changed.unwrap()
                })
            }),
            false,
        ),
        (
            "uniform knots",
            LatticeSpec { knots: KnotStyle::Uniform, ..LatticeSpec::cubic(box_, [7, 5, 5]) },
            Box::new(move |l, step| (step < 2).then(|| lift(l, [3, 2, 2], Vec3::new(0.0, 0.01, 0.0)))),
            true,
        ),
    ];
    for (what, spec, mut changes, fills_whole) in cases {
        let mut field = bar();
        let mut lattice = open(&field, spec);
        let stats = written_as_evaluated(&mut field, &mut lattice, &mut *changes, what);
        // Whole bricks and blocks were filled, not every point evaluated.
        assert!(stats.iter().all(|s| s.written > 0), "{what}: {stats:?}");
        if fills_whole {
            let whole = |s: &LatticeStats| (s.bricks * crate::field::BRICK_VOLUME) as u64;
            assert!(stats.iter().all(|s| (s.points as u64) < whole(s)), "{what}: {stats:?}");
        }
    }
}

#[test]
fn the_interpolated_mapping_matches_the_exact_one() {
    // A strong twist (a quarter turn over 20 mm) and swell of the bar: the mapping
    // interpolated between coarse nodes reads the clay about where the exact one does.
    let field = bar();
    let mut lattice = open(&field, LatticeSpec::cubic(bar_box(), [8, 5, 5]));
    for i in 1..7 {
        for k in 0..5 {
            for j in 0..5 {
                let c = lattice.volume().control(i, j, k).unwrap();
                let p = c.position_m;
                let turn = Quat::from_rotation_x(0.2 * i as f32);
                let moved = Vec3::new(p.x, 0.0, 0.0) + turn * Vec3::new(0.0, p.y, p.z);
                let v = c.value;
                // Whole layers turned (a twist that folds nothing), the inner values raised.
                lattice.move_control([i, j, k], moved).unwrap();
                if j > 0 && j < 4 && k > 0 && k < 4 {
                    lattice.set_value([i, j, k], v + 0.1).unwrap();
                }
            }
        }
    }
    let (lo, hi) = lattice.points_of(bar_box());
    let (mut exact, mut fast) = (Vec::new(), Vec::new());
    let slow = lattice.evaluate_with(lo, hi, &mut exact, None, false);
    let quick = lattice.evaluate_with(lo, hi, &mut fast, None, true);
    assert!(quick.newton_iterations < slow.newton_iterations, "{quick:?} {slow:?}");
    let worst = exact.iter().zip(&fast).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    let mean = exact.iter().zip(&fast).map(|(a, b)| (a - b).abs() as f64).sum::<f64>() / exact.len() as f64;
    // The worst where the deformed faces cut a cell (its points are found on a straight line
    // between its corners); on the whole, well under a thousandth.
    assert!(worst < 0.15 && mean < 1e-3, "worst {worst}, mean {mean}");
    assert!(fast.iter().all(|d| d.is_finite() && (0.0..=1.0).contains(d)));
}

#[test]
fn a_lattice_form_steps_through_the_kinds_stays_within_its_limits_and_says_what_it_is() {
    let form = LatticeForm::default();
    assert_eq!(form.describe(), "cubic NURBS, 4 × 4 × 4 controls, clamped knots");
    let kinds: Vec<SplineKind> =
        std::iter::successors(Some(form), |f| Some(f.next_kind())).skip(1).take(3).map(|f| f.kind).collect();
    assert_eq!(kinds, [SplineKind::Bezier, SplineKind::BSpline, SplineKind::Nurbs]);
    let odd = LatticeForm { counts: [0, 3, 99], order: 1, ..form.next_kind() };
    assert_eq!(odd.within_limits().counts, [2, 3, 16]);
    let region = Aabb { min: Vec3::ZERO, max: Vec3::ONE };
    let spec = odd.over(region);
    assert_eq!(
        (spec.counts, spec.order, spec.kind, spec.region),
        ([2, 3, 16], 2, SplineKind::Bezier, region)
    );
    assert_eq!(odd.within_limits().describe(), "Bézier, 2 × 3 × 16 controls");
    let quadratic = LatticeForm { kind: SplineKind::BSpline, order: 3, knots: KnotStyle::Uniform, ..form };
    assert_eq!(quadratic.describe(), "quadratic B-spline, 4 × 4 × 4 controls, uniform knots");
    // Every form within its limits makes a volume.
    for kind in LatticeForm::KINDS {
        for order in [2, 4, 16] {
            let f = LatticeForm { kind, order, counts: [2, 5, 16], knots: KnotStyle::Clamped };
            assert!(f.over(region).volume().is_ok(), "{f:?}");
        }
    }
}
