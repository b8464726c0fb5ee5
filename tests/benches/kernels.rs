//! Criterion benchmarks of the CPU kernels: marching one brick, stamping the band-limited
//! sphere, re-meshing what a stroke dirtied, the head-tracked stereo views of a frame and one
//! virtual-clay step. `argile bench` holds the end-to-end workloads.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

use argile::field::Field;
use argile::math::{Pose, Quat, Vec3};
use argile::mesh::{gather_block, march_brick, remesh_dirty, Block, ChunkMesh, MarchScratch};
use argile::tool::{rasterize_solid, stamp_sphere, Action, CsgOp, PlacedSolid, Solid};

fn sphere_field(radius_m: f32) -> Field {
    let mut f = Field::new(0.001, 0.5);
    let solid = PlacedSolid {
        solid: Solid::Sphere { radius_m },
        pose: Pose { position_m: Vec3::new(0.0003, 0.0001, -0.0002), rotation: Quat::IDENTITY },
        scale: 1.0,
    };
    rasterize_solid(&mut f, &solid, CsgOp::Union, [0.7, 0.4, 0.2, 1.0]);
    f
}

fn march(c: &mut Criterion) {
    let field = sphere_field(0.02);
    // A brick the surface crosses diagonally.
    let key = (Vec3::splat(0.02 / 3f32.sqrt() / 0.001 / 8.0)).as_ivec3();
    let mut block = Block::default();
    let (around, block) = gather_block(&field, key, &mut block);
    let mut scratch = MarchScratch::default();
    let mut mesh = ChunkMesh::default();
    march_brick(block, &around, 0.5, field.transform(), &mut scratch, &mut mesh);
    let tris = mesh.triangle_count();
    assert!(tris > 0, "the benchmarked brick holds surface");
    let mut group = c.benchmark_group("march_brick");
    group.throughput(Throughput::Elements(tris as u64));
    group.bench_function(BenchmarkId::from_parameter(format!("tris={tris}")), |b| {
        b.iter(|| march_brick(block, &around, 0.5, field.transform(), &mut scratch, &mut mesh))
    });
    let mut other = Block::default();
    group.bench_function("gather", |b| b.iter(|| gather_block(&field, key, &mut other).0.key));
    group.finish();
}

fn stamp(c: &mut Criterion) {
    let mut group = c.benchmark_group("apply_brush");
    for r in [4.0f32, 8.0, 16.0] {
        let mut field = sphere_field(0.03);
        let mut x = 0.0f32;
        group.bench_function(BenchmarkId::new("sphere_add", format!("radius_voxels={r}")), |b| {
            b.iter(|| {
                x = (x + 0.0005) % 0.01;
                stamp_sphere(
                    &mut field,
                    Vec3::new(0.03 + x, 0.0, 0.0),
                    r * 0.001,
                    Action::Add,
                    [0.2, 0.4, 0.9, 1.0],
                )
            })
        });
    }
    group.finish();
}

fn remesh(c: &mut Criterion) {
    let mut group = c.benchmark_group("remesh_dirty");
    for r in [4.0f32, 16.0] {
        let mut field = sphere_field(0.03);
        remesh_dirty(&mut field);
        let mut i = 0;
        group.bench_function(BenchmarkId::from_parameter(format!("stamp_radius_voxels={r}")), |b| {
            b.iter(|| {
                i += 1;
                let y = (i % 40) as f32 * 0.0005;
                stamp_sphere(&mut field, Vec3::new(0.03, y, 0.0), r * 0.001, Action::Remove, [0.0; 4]);
                remesh_dirty(&mut field)
            })
        });
    }
    group.finish();
}

/// Both eyes' head-tracked views (Kooima's projection through the shipped 24" screen) for a
/// moving head: the per-frame cost of fish-tank stereo.
fn head_tracked_views(c: &mut Criterion) {
    let calibration = argile::scene::ScreenCalibration::shipped();
    let rig = argile::stereo::HeadTrackedRig {
        screen: calibration.screen,
        placement: argile::stereo::Placement::IDENTITY,
        interaxial_m: calibration.ipd_m,
        near_m: calibration.near_m,
        far_m: calibration.far_m,
    };
    let mut i = 0u32;
    c.bench_function("head_tracked_views/eyes=2", |b| {
        b.iter(|| {
            i = i.wrapping_add(1);
            let x = (i % 100) as f32 * 0.002 - 0.1;
            let head = Pose { position_m: Vec3::new(x, 0.02, 0.6), rotation: Quat::from_rotation_y(x) };
            rig.views(&head)
        })
    });
}

/// One virtual-clay step (all three layers) of a ball bending a bar of radius 5 voxels that
/// rests on a support, in a 64×32×32 window; the ball goes down and up by a quarter voxel per
/// step, so it stays in contact.
fn clay_step(c: &mut Criterion) {
    use argile::clay::{Clay, ClayParams, ClayTool};
    use argile::math::IVec3;
    use argile::tool::ToolShape;
    let h = 0.001;
    let field = {
        let mut f = Field::new(h, 0.5);
        let bar = PlacedSolid {
            solid: Solid::Bar { half_length_m: 24.0 * h, radius_m: 5.0 * h },
            pose: Pose::default(),
            scale: 1.0,
        };
        rasterize_solid(&mut f, &bar, CsgOp::Union, [0.7, 0.4, 0.2, 1.0]);
        f
    };
    let at = |x: f32, y: f32| Pose { position_m: Vec3::new(x, y, 0.0) * h, rotation: Quat::IDENTITY };
    let support = ClayTool::support(
        ToolShape::Solid(Solid::Box { half_m: Vec3::new(10.0, 5.0, 8.0) * h }),
        Vec3::ONE,
        at(-14.0, -10.0),
    );
    let ball = ClayTool::pusher(ToolShape::sphere(5.0 * h), Vec3::ONE, at(19.0, 11.0));
    let (lo, hi) = (IVec3::new(-32, -20, -16), IVec3::new(31, 11, 15));
    let mut clay = Clay::new(&field, lo, hi, vec![support, ball], ClayParams::default());
    let mut i = 0u32;
    let y = |i: u32| 11.0 - 0.25 * (i % 32).min(32 - i % 32) as f32;
    for _ in 0..16 {
        i += 1;
        clay.step(&[Pose::default(), at(19.0, y(i))]);
    }
    let mut group = c.benchmark_group("clay_step");
    group.bench_function("bend_bar/window=64x32x32", |b| {
        b.iter(|| {
            i += 1;
            clay.step(&[Pose::default(), at(19.0, y(i))]);
        })
    });
    group.finish();
}

criterion_group!(benches, march, stamp, remesh, head_tracked_views, clay_step);
criterion_main!(benches);
