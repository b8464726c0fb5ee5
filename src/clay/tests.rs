//! The virtual clay's behaviours (Dewaele–Cani §5) and invariants.

use super::*;
use crate::field::Field;
use crate::math::{Aabb, IVec3, Pose, Vec3};
use crate::tool::{rasterize_solid, CsgOp, PlacedSolid, Solid, ToolShape};

const H: f32 = 0.001;

fn at(x: f32, y: f32, z: f32) -> Pose {
    Pose { position_m: Vec3::new(x, y, z) * H, ..Pose::default() }
}

fn solid_field(solid: Solid, centre: Pose) -> Field {
    let mut f = Field::new(H, 0.5);
    rasterize_solid(
        &mut f,
        &PlacedSolid { solid, pose: centre, scale: 1.0 },
        CsgOp::Union,
        [0.6, 0.6, 0.6, 1.0],
    );
    f
}

/// A bar along X, 96 voxels long, radius 6, centred at the origin.
fn bar() -> Field {
    solid_field(Solid::Bar { half_length_m: 48.0 * H, radius_m: 6.0 * H }, Pose::default())
}

/// Mean Y (voxels) of the matter of lattice points with x in `x0..=x1`.
fn mean_y(clay: &Clay, x0: i32, x1: i32) -> f64 {
    let (lo, hi) = clay.window();
    let (mut m, mut my) = (0.0f64, 0.0f64);
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            for x in x0.max(lo.x)..=x1.min(hi.x) {
                let d = f64::from(clay.density(IVec3::new(x, y, z)));
                m += d;
                my += d * f64::from(y);
            }
        }
    }
    my / m
}

/// Components (6-connected) of the lattice points at or above the iso-level.
fn components(clay: &Clay, iso: f32) -> usize {
    let (lo, hi) = clay.window();
    let dims = hi - lo + IVec3::ONE;
    let idx = |c: IVec3| (c.x + dims.x * (c.y + dims.y * c.z)) as usize;
    let d = clay.densities();
    let mut seen = vec![false; d.len()];
    let mut count = 0;
    for start in 0..d.len() {
        if seen[start] || d[start] < iso {
            continue;
        }
        count += 1;
        seen[start] = true;
        let mut stack = vec![start];
        while let Some(i) = stack.pop() {
            let c = IVec3::new(i as i32 % dims.x, (i as i32 / dims.x) % dims.y, i as i32 / (dims.x * dims.y));
            for o in [IVec3::X, IVec3::NEG_X, IVec3::Y, IVec3::NEG_Y, IVec3::Z, IVec3::NEG_Z] {
                let q = c + o;
                if q.cmpge(IVec3::ZERO).all() && q.cmplt(dims).all() {
                    let j = idx(q);
                    if !seen[j] && d[j] >= iso {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
    }
    count
}

struct Bend {
    clay: Clay,
    mass0: f64,
    /// Pusher travel after first contact, voxels.
    travel: f64,
    free0: f64,
    held0: f64,
    max_mass_error: f64,
}

/// The paper's bending (§5.1, Fig. 1): the bar rests on a support block under its left
/// half; a ball pushes its right end down by 24 voxels.
fn bend(fluidity: f32) -> Bend {
    bend_with(ClayParams { fluidity, ..ClayParams::default() })
}

fn bend_with(params: ClayParams) -> Bend {
    let field = bar();
    let support = ClayTool::support(
        ToolShape::Solid(Solid::Box { half_m: Vec3::new(20.0, 6.0, 10.0) * H }),
        Vec3::ONE,
        at(-28.0, -12.0, 0.0),
    );
    let start = at(40.0, 14.0, 0.0);
    let pusher = ClayTool::pusher(ToolShape::sphere(6.0 * H), Vec3::ONE, start);
    let tools = vec![support, pusher];
    let (lo, hi) = (IVec3::new(-60, -48, -16), IVec3::new(60, 24, 16));
    let mut clay = Clay::new(&field, lo, hi, tools, params);
    let mass0 = clay.mass();
    let free0 = mean_y(&clay, 30, 60);
    let held0 = mean_y(&clay, -44, -12);
    let mut max_mass_error = 0.0f64;
    // Contact: the ball's ramp meets the bar's at y = 6 + 2 + 6 + 2 = 16 − 2 … start at 14
    // is already touching the band; travel counts the whole push.
    let steps = 96;
    let depth = 24.0;
    for s in 1..=steps {
        let y = 14.0 - depth * s as f32 / steps as f32;
        clay.step(&[Pose::default(), at(40.0, y, 0.0)]);
        max_mass_error = max_mass_error.max((clay.mass() - mass0).abs() / mass0);
    }
    Bend { clay, mass0, travel: f64::from(depth), free0, held0, max_mass_error }
}

#[test]
fn bending_follows_the_pusher_and_holds_the_support() {
    let b = bend(1.0);
    let free = b.free0 - mean_y(&b.clay, 30, 60);
    let held = (mean_y(&b.clay, -44, -12) - b.held0).abs();
    assert!(free >= 0.7 * b.travel, "free end moved {free:.2} of the pusher's {:.1} voxels", b.travel);
    assert!(held < 1.0, "the part on the support moved {held:.3} voxels");
    assert_eq!(components(&b.clay, 0.5), 1, "the bar stays one piece");
    assert!(b.max_mass_error < 0.01, "mass drifted by {:.4}%", b.max_mass_error * 100.0);
    assert!((b.clay.mass() - b.mass0).abs() / b.mass0 < 0.01);
}

#[test]
fn a_slow_push_keeps_the_surface_it_drags_smooth() {
    // The ball pushes by a quarter of a cell per step. Splatting the dragged clay at every
    // step smears its surface and roughens it; passing the motion on once the tool has
    // travelled a cell keeps it smoother. The surface's band: cells part full, from 0.1 to
    // 0.9; its roughness: the pairs of neighbouring cells on either side of the iso-level (a
    // rough surface has more of them than a smooth one of the same shape).
    let band = |d: &[f32]| d.iter().filter(|&&d| d > 0.1 && d < 0.9).count();
    let crossings = |d: &[f32]| {
        let (lo, hi) = (IVec3::new(-60, -48, -16), IVec3::new(60, 24, 16));
        let dims = hi - lo + IVec3::ONE;
        let (sy, sz) = (dims.x as usize, (dims.x * dims.y) as usize);
        (0..d.len() - sz)
            .map(|i| [1, sy, sz].iter().filter(|&&o| (d[i] >= 0.5) != (d[i + o] >= 0.5)).count())
            .sum::<usize>()
    };
    let bar = Clay::new(
        &bar(),
        IVec3::new(-60, -48, -16),
        IVec3::new(60, 24, 16),
        Vec::new(),
        ClayParams::default(),
    );
    let (band0, crossings0) = (band(bar.densities()), crossings(bar.densities()));
    let every_step = bend_with(ClayParams { min_travel_voxels: 0.0, ..ClayParams::default() });
    let every_cell = bend(1.0);
    let (a, b) = (every_step.clay.densities(), every_cell.clay.densities());
    assert!(
        band(b) < band(a) && crossings(b) < crossings(a),
        "band cells: {} passing the motion on every cell travelled, {} at every step, {band0} before; \
         crossings: {}, {}, {crossings0} before",
        band(b),
        band(a),
        crossings(b),
        crossings(a)
    );
}

#[test]
fn more_fluid_clay_moves_its_far_end_less() {
    let dry = bend(1.0);
    let fluid = bend(0.3);
    let far = |b: &Bend| b.free0 - mean_y(&b.clay, 44, 60);
    assert!(far(&fluid) < 0.8 * far(&dry), "α 0.3: {:.2} voxels, α 1: {:.2}", far(&fluid), far(&dry));
}

#[test]
fn a_print_sinks_under_the_tool_and_raises_a_rim() {
    // A block on a table, a ball pressed 6 voxels into its top; fluid clay (§5.3).
    let field = solid_field(Solid::Box { half_m: Vec3::new(20.0, 8.0, 20.0) * H }, Pose::default());
    let table = ClayTool::table(Vec3::new(0.0, -8.0 * H, 0.0));
    let ball = ClayTool::pusher(ToolShape::sphere(7.0 * H), Vec3::ONE, at(0.0, 17.0, 0.0));
    let params = ClayParams { fluidity: 0.2, ..ClayParams::default() };
    let mut clay =
        Clay::new(&field, IVec3::new(-32, -14, -32), IVec3::new(32, 28, 32), vec![table, ball], params);
    let mass0 = clay.mass();
    // The height of the clay over the table: the matter of a column (the block is full).
    let height =
        |clay: &Clay, x: i32, z: i32| (-14..=28).map(|y| clay.density(IVec3::new(x, y, z))).sum::<f32>();
    // The highest column of the ring 8 to 16 voxels from the axis, towards each of 8 sides.
    let rims = |clay: &Clay| {
        (0..8)
            .map(|k| {
                let a = k as f32 * std::f32::consts::FRAC_PI_4;
                (8..=16)
                    .map(|r| {
                        height(clay, (r as f32 * a.cos()).round() as i32, (r as f32 * a.sin()).round() as i32)
                    })
                    .fold(0.0f32, f32::max)
            })
            .collect::<Vec<f32>>()
    };
    let (centre0, rims0) = (height(&clay, 0, 0), rims(&clay));
    for s in 1..=40 {
        clay.step(&[Pose::default(), at(0.0, 17.0 - 12.0 * s as f32 / 40.0, 0.0)]);
        let drift = (clay.mass() - mass0).abs() / mass0;
        assert!(drift < 0.01, "step {s}: mass drifted by {:.3} %", drift * 100.0);
    }
    let (centre, rims) = (height(&clay, 0, 0), rims(&clay));
    assert!(centre < centre0 - 4.0, "under the tool: {centre} from {centre0}");
    // The rim rises on every side of the print, by half a voxel on average.
    for (k, (r, r0)) in rims.iter().zip(&rims0).enumerate() {
        assert!(*r > r0 + 0.2, "around the tool, towards side {k}: {r} from {r0}");
    }
    let rise = rims.iter().zip(&rims0).map(|(r, r0)| r - r0).sum::<f32>() / 8.0;
    assert!(rise > 0.5, "the rim rose by {rise} on average: {rims:?} from {rims0:?}");
    // The block does not sink into the table.
    assert!(clay.density(IVec3::new(0, -11, 0)) < 0.1);
    assert!((clay.mass() - mass0).abs() / mass0 < 0.01);
}

#[test]
fn clay_left_alone_does_not_change() {
    let field = bar();
    let tools = vec![ClayTool::pusher(ToolShape::sphere(4.0 * H), Vec3::ONE, at(0.0, 30.0, 0.0))];
    let mut clay =
        Clay::new(&field, IVec3::new(-60, -16, -16), IVec3::new(60, 40, 16), tools, ClayParams::default());
    let before = clay.densities().to_vec();
    for _ in 0..5 {
        clay.step(&[at(0.0, 30.0, 0.0)]);
    }
    assert!(before.iter().zip(clay.densities()).all(|(a, b)| a.to_bits() == b.to_bits()));
}

#[test]
fn mass_inside_a_tool_leaves_outwards_only() {
    // A slab pressed by a flat box from above: no matter may cross to the tool's top side.
    let field = solid_field(Solid::Box { half_m: Vec3::new(16.0, 3.0, 16.0) * H }, Pose::default());
    let press = ClayTool::pusher(
        ToolShape::Solid(Solid::Box { half_m: Vec3::new(6.0, 3.0, 6.0) * H }),
        Vec3::ONE,
        at(0.0, 8.0, 0.0),
    );
    let params = ClayParams { fluidity: 0.0, ..ClayParams::default() };
    let mut clay = Clay::new(&field, IVec3::new(-28, -16, -28), IVec3::new(28, 20, 28), vec![press], params);
    for s in 1..=20 {
        clay.step(&[at(0.0, 8.0 - 4.0 * s as f32 / 20.0, 0.0)]);
    }
    // Above the press's top face (y = 4 + 3 + 2 of band), straight over its centre.
    for y in 10..20 {
        assert!(clay.density(IVec3::new(0, y, 0)) < 1e-3, "matter went through the tool at y = {y}");
    }
}

#[test]
fn advancing_at_any_frame_rate_runs_the_same_steps() {
    let run = |frames: usize| {
        let field = bar();
        let tools = vec![ClayTool::pusher(ToolShape::sphere(6.0 * H), Vec3::ONE, at(40.0, 14.0, 0.0))];
        let params = ClayParams { step_s: 0.01, ..ClayParams::default() };
        let mut clay = Clay::new(&field, IVec3::new(-60, -30, -16), IVec3::new(60, 24, 16), tools, params);
        for f in 1..=frames {
            let u = f as f32 / frames as f32;
            clay.advance(&[at(40.0, 14.0 - 10.0 * u, 0.0)], 0.2 / frames as f32);
        }
        (clay.times().steps, clay.densities().to_vec())
    };
    let (a_steps, a) = run(7);
    let (b_steps, b) = run(20);
    assert_eq!(a_steps, 20);
    assert_eq!(b_steps, 20);
    let diff = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
    assert!(diff < 1e-4, "frame rates disagree by {diff}");
}

#[test]
fn runs_are_bit_identical_across_thread_counts() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| bend(0.8).clay.densities().to_vec())
    };
    let one = run(1);
    let three = run(3);
    assert!(one.iter().zip(&three).all(|(a, b)| a.to_bits() == b.to_bits()));
    assert!(one.iter().all(|d| d.is_finite() && *d >= 0.0));
}

#[test]
fn a_push_writes_back_as_one_undo_step_and_keeps_the_field_in_range() {
    let mut field = bar();
    let initial = field.clone();
    let mass0 = field.mass();
    let tools = vec![ClayTool::pusher(ToolShape::sphere(6.0 * H), Vec3::ONE, at(40.0, 14.0, 0.0))];
    let bounds = [Aabb::from_centre_half(Vec3::new(40.0, 8.0, 0.0) * H, Vec3::splat(10.0 * H))];
    let (lo, hi) = window_around(&field, &bounds, 12);
    assert!(lo.x <= -48 && hi.x >= 48, "the window holds the whole bar: {lo}..{hi}");
    let mut clay = Clay::new(&field, lo, hi, tools, ClayParams::default());
    field.begin_stroke();
    let _ = field.take_dirty();
    for s in 1..=30 {
        clay.step(&[at(40.0, 14.0 - 0.4 * s as f32, 0.0)]);
        if s % 10 == 0 {
            clay.write_to(&mut field);
        }
    }
    assert!(!field.dirty().is_empty(), "written bricks are dirty for the mesher");
    clay.finish(&mut field);
    field.end_stroke();
    assert!((field.mass() - mass0).abs() / mass0 < 0.01, "field mass {} from {mass0}", field.mass());
    for key in field.brick_keys().collect::<Vec<_>>() {
        let (a, b) = field.density_range(key).unwrap();
        assert!(a >= 0.0 && b <= 1.0);
    }
    assert!(!field.same_samples(&initial));
    assert!(field.undo().unwrap());
    assert!(field.same_samples(&initial), "one undo takes the whole push back");
}

mod invariants {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 12, rng_seed: proptest::test_runner::RngSeed::Fixed(5), ..ProptestConfig::default() })]
        #[test]
        fn any_push_conserves_matter_and_stays_finite_and_non_negative(
            from in (-20.0f32..20.0, 10.0f32..16.0, -6.0f32..6.0),
            to in (-20.0f32..20.0, -8.0f32..4.0, -6.0f32..6.0),
            radius in 3.0f32..8.0,
            fluidity in 0.0f32..1.0,
            supported in any::<bool>(),
        ) {
            let field = solid_field(Solid::Bar { half_length_m: 24.0 * H, radius_m: 6.0 * H }, Pose::default());
            let mut tools = vec![ClayTool::pusher(ToolShape::sphere(radius * H), Vec3::ONE, at(from.0, from.1, from.2))];
            if supported {
                tools.push(ClayTool::table(Vec3::new(0.0, -6.0 * H, 0.0)));
            }
            let params = ClayParams { fluidity, max_iterations: 20_000, ..ClayParams::default() };
            let mut clay = Clay::new(&field, IVec3::new(-40, -24, -24), IVec3::new(40, 24, 24), tools, params);
            let mass0 = clay.mass();
            let end = at(to.0, to.1, to.2);
            let steps = 16;
            for s in 1..=steps {
                let u = s as f32 / steps as f32;
                clay.step(&[at(from.0, from.1, from.2).lerp(&end, u), Pose::default()]);
            }
            prop_assert!(clay.densities().iter().all(|d| d.is_finite() && *d >= 0.0));
            prop_assert!((clay.mass() - mass0).abs() / mass0 < 1e-3, "{} from {}", clay.mass(), mass0);
        }
    }
}

#[test]
fn two_supports_hold_both_ends_while_the_middle_sinks() {
    let field = bar();
    let block = |x: f32| {
        ClayTool::support(
            ToolShape::Solid(Solid::Box { half_m: Vec3::new(10.0, 6.0, 10.0) * H }),
            Vec3::ONE,
            at(x, -12.0, 0.0),
        )
    };
    let ball = ClayTool::pusher(ToolShape::sphere(6.0 * H), Vec3::ONE, at(0.0, 14.0, 0.0));
    let tools = vec![block(-36.0), block(36.0), ball];
    let mut clay =
        Clay::new(&field, IVec3::new(-60, -40, -16), IVec3::new(60, 24, 16), tools, ClayParams::default());
    let (left0, right0, middle0) = (mean_y(&clay, -46, -30), mean_y(&clay, 30, 46), mean_y(&clay, -6, 6));
    for s in 1..=60 {
        clay.step(&[Pose::default(), Pose::default(), at(0.0, 14.0 - 20.0 * s as f32 / 60.0, 0.0)]);
    }
    let sunk = middle0 - mean_y(&clay, -6, 6);
    assert!(sunk > 6.0, "the middle sank {sunk:.2} voxels");
    for (name, before, x0, x1) in [("left", left0, -46, -30), ("right", right0, 30, 46)] {
        let moved = (mean_y(&clay, x0, x1) - before).abs();
        assert!(moved < 1.0, "the {name} end moved {moved:.3} voxels");
    }
}

#[test]
fn a_freeform_tool_lets_matter_out_of_its_inside_only_outwards() {
    use super::body::Body;
    use super::grid::Grid;
    use crate::tool::Freeform;
    // A freeform ball copied from a sculpt: its copied densities saturate at 1 inside, so the
    // outward directions come from the depth propagated in from its edges.
    let sculpt = solid_field(Solid::Sphere { radius_m: 8.0 * H }, Pose::default());
    let shape = ToolShape::Freeform(std::sync::Arc::new(Freeform::from_field(
        &sculpt,
        IVec3::splat(-12),
        IVec3::splat(12),
    )));
    let body = Body::new(ClayTool::pusher(shape, Vec3::ONE, Pose::default()));
    let empty = Field::new(H, 0.5);
    let grid = Grid::load(&empty, IVec3::splat(-16), IVec3::splat(16));
    let fp = body.footprint_at(&grid, empty.transform(), Pose::default());
    let dirs_at = |p: IVec3| {
        let i = grid.index(p - grid.lo) as u32;
        assert!(fp.cells.contains(&i), "{p} is covered");
        body.outward_dirs_at(empty.transform(), p)
    };
    // Bits: −x, +x, −y, +y, −z, +z.
    assert_eq!(dirs_at(IVec3::new(5, 0, 0)), 0b00_0010, "+x side: out along +x");
    assert_eq!(dirs_at(IVec3::new(0, -5, 0)), 0b00_0100, "−y side: out along −y");
    assert_eq!(dirs_at(IVec3::new(0, 0, 6)), 0b10_0000);
}

#[test]
fn bucketed_distances_equal_dijkstras() {
    use super::displace::Distance;
    use super::grid::{Grid, WALL};
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let empty = Field::new(H, 0.5);
    let mut grid = Grid::load(&empty, IVec3::ZERO, IVec3::splat(13));
    // Deterministic pseudo-random densities, some under the border threshold.
    let mut x = 0x2545_f491_u32;
    for d in grid.density.iter_mut() {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        *d = (x % 1000) as f32 / 900.0;
    }
    let min_density = 0.05;
    let seeds = [grid.index(IVec3::new(3, 4, 5)), grid.index(IVec3::new(10, 9, 2))];
    let barrier = grid.index(IVec3::new(6, 6, 6));
    // Barriers are cells a body covers.
    grid.flags[barrier] |= super::grid::COVERED;
    let mut bucketed = Distance::new(grid.len());
    bucketed.propagate(&grid, seeds.iter().copied(), min_density, |i| i == barrier);
    // Reference: a binary-heap Dijkstra with the same costs.
    let mut dist = vec![f32::INFINITY; grid.len()];
    let mut heap = BinaryHeap::new();
    for &s in &seeds {
        dist[s] = 0.0;
        heap.push(Reverse((0u32, s)));
    }
    while let Some(Reverse((bits, c))) = heap.pop() {
        let dc = f32::from_bits(bits);
        if dc > dist[c] || (c == barrier && dc > 0.0) {
            continue;
        }
        for d in 0..6 {
            let n = grid.neighbour(c, d);
            if grid.flags[n] & WALL != 0 {
                continue;
            }
            let cost = if n == barrier {
                1.0
            } else if grid.density[n] < min_density {
                continue;
            } else {
                1.0 / grid.density[n].min(1.0)
            };
            if dc + cost < dist[n] {
                dist[n] = dc + cost;
                heap.push(Reverse(((dc + cost).to_bits(), n)));
            }
        }
    }
    let reached = dist.iter().filter(|d| d.is_finite()).count();
    assert!(reached > 100, "the test grid is connected enough: {reached}");
    for (i, (&a, &b)) in bucketed.dist.iter().zip(&dist).enumerate() {
        assert!(a == b || (a - b).abs() <= 1e-4 * b, "cell {i}: {a} against {b}");
    }
    assert_eq!(bucketed.to_others, dist[barrier]);
}

/// FNV-1a over the bits of every density: equal only for bit-identical fields.
fn checksum(densities: &[f32]) -> u64 {
    densities
        .iter()
        .fold(0xcbf2_9ce4_8422_2325, |h, d| (h ^ u64::from(d.to_bits())).wrapping_mul(0x100_0000_01b3))
}

/// Two balls squeeze the bar from above and below while a support holds its left end; the
/// lower ball turns as it rises (a rigid motion that is not a translation).
fn squeeze() -> Clay {
    let field = bar();
    let support = ClayTool::support(
        ToolShape::Solid(Solid::Box { half_m: Vec3::new(20.0, 6.0, 10.0) * H }),
        Vec3::ONE,
        at(-28.0, -12.0, 0.0),
    );
    let top = ClayTool::pusher(ToolShape::sphere(6.0 * H), Vec3::ONE, at(30.0, 13.0, 0.0));
    let bottom = ClayTool::pusher(ToolShape::sphere(5.0 * H), Vec3::new(1.0, 1.4, 1.0), at(34.0, -13.0, 0.0));
    let (lo, hi) = (IVec3::new(-60, -32, -20), IVec3::new(60, 32, 20));
    // A low iteration cap, so that work carries from step to step.
    let params = ClayParams { max_iterations: 3_000, ..ClayParams::default() };
    let mut clay = Clay::new(&field, lo, hi, vec![support, top, bottom], params);
    for s in 1..=40 {
        let t = s as f32 / 40.0;
        let mut turned = at(34.0, -13.0 + 6.0 * t, 0.0);
        turned.rotation = crate::math::Quat::from_rotation_z(0.6 * t);
        clay.step(&[Pose::default(), at(30.0, 13.0 - 6.0 * t, 0.0), turned]);
    }
    clay
}

/// The clay's results are pinned bit for bit: work skipped or reordered for speed must leave
/// every density as it was. A deliberate change of the model updates these checksums (and
/// says why). Last change: the field stores densities in steps of 2⁻¹⁵, so the clay starts
/// from the solid's stored densities.
#[test]
fn the_bend_and_the_squeeze_give_the_pinned_densities() {
    let b = bend(1.0);
    let s = squeeze();
    assert!(s.densities().iter().all(|d| d.is_finite() && *d >= 0.0));
    assert_eq!(
        (checksum(b.clay.densities()), checksum(s.densities())),
        (17_834_580_063_966_760_671, 16_961_204_197_381_132_656),
        "bend, squeeze"
    );
}
