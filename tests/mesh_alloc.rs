//! The incremental mesher's steady state allocates nothing: once its buffers have grown,
//! marking and re-meshing dirty sets it has seen makes no heap allocation on any thread.
//!
//! A counting global allocator counts every allocation of the process; this binary holds one
//! test so that nothing else allocates while it counts.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use argile::field::Field;
use argile::math::{IVec3, Vec3};
use argile::mesh::{remesh_dirty, MeshDiff, Mesher};
use argile::tool::{stamp_sphere, Action};

/// The system allocator, counting allocations and reallocations.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every method forwards to the system allocator with the caller's arguments, so the
// caller's guarantees are the system allocator's; counting touches no memory it hands out.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: forwarded unchanged (see the impl).
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: forwarded unchanged (see the impl).
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: forwarded unchanged (see the impl).
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged (see the impl).
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn sphere(radius_m: f32) -> Field {
    let mut f = Field::new(0.001, 0.5);
    stamp_sphere(&mut f, Vec3::new(0.0003, 0.0001, -0.0002), radius_m, Action::Add, [0.7, 0.4, 0.2, 1.0]);
    f.take_dirty();
    f
}

fn same(a: &MeshDiff, b: &MeshDiff) -> bool {
    a.removed == b.removed && a.upserted == b.upserted
}

/// Re-meshes the lattice boxes `boxes` of `field`, in turns, on a pool of two threads: the
/// allocations in each of five windows of 20 steady-state marks and re-meshes, after a
/// warm-up, and how many re-meshes equalled the first ones.
fn steady_state(field: &mut Field, boxes: [(IVec3, IVec3); 2]) -> (Vec<usize>, usize, Vec<MeshDiff>) {
    let full: Vec<MeshDiff> = boxes
        .iter()
        .map(|&(lo, hi)| {
            field.mark_dirty(lo, hi);
            remesh_dirty(field)
        })
        .collect();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    // Counted inside the pool: handing work to rayon from outside it may allocate in rayon.
    // A pool thread also allocates once on its own, when it first looks at another's work
    // queue (it registers with the queues' garbage collector), at a time of its choosing; so
    // the steady state is counted over five windows of 20 re-meshes, of which one must make
    // no allocation at all (a mesher that allocates would make some in every window).
    let (windows, rounds) = pool.install(|| {
        let mut mesher = Mesher::default();
        // Warm-up: the buffers (the field's dirty set among them) grow to both boxes.
        for (lo, hi) in [boxes[0], boxes[1], boxes[0], boxes[1]] {
            field.mark_dirty(lo, hi);
            mesher.remesh_dirty(field);
        }
        let mut rounds = 0;
        let windows: Vec<usize> = (0..5)
            .map(|_| {
                let before = ALLOCATIONS.load(Ordering::SeqCst);
                for i in 0..20 {
                    let which = usize::from(i % 3 == 2);
                    let (lo, hi) = boxes[which];
                    field.mark_dirty(lo, hi);
                    let diff = mesher.remesh_dirty(field);
                    rounds += usize::from(same(diff, &full[which]));
                }
                ALLOCATIONS.load(Ordering::SeqCst) - before
            })
            .collect();
        (windows, rounds)
    });
    (windows, rounds, full)
}

#[test]
fn remeshing_known_dirty_sets_again_allocates_nothing() {
    let mut field = sphere(0.03);
    // Carved where the dirty boxes below re-mesh, so that they hold varied surface.
    stamp_sphere(&mut field, Vec3::new(0.03, 0.0, 0.0), 0.008, Action::Remove, [0.0; 4]);
    stamp_sphere(&mut field, Vec3::new(0.0, 0.03, 0.0), 0.004, Action::Remove, [0.0; 4]);
    field.take_dirty();
    // Two lattice boxes across the surface, as a stroke's stamps mark them.
    let boxes =
        [(IVec3::new(20, -9, -9), IVec3::new(40, 9, 9)), (IVec3::new(-5, 24, -5), IVec3::new(5, 36, 5))];
    let (windows, rounds, full) = steady_state(&mut field, boxes);
    assert!(full[0].upserted_triangles() > 1000 && full[1].upserted_triangles() > 100);
    assert!(!full[0].removed.is_empty(), "the box reaches bricks with no surface");
    assert_eq!(rounds, 100, "every re-mesh equals a fresh one");
    assert!(
        windows.contains(&0),
        "allocations in each window of 20 steady-state marks and re-meshes: {windows:?}"
    );

    // Clay of one coarse level (4 mm voxels), meshed on its own lattice, allocates nothing
    // either.
    let mut coarse = Field::new(0.001, 0.5);
    coarse.edit_level(
        2,
        IVec3::splat(-12),
        IVec3::splat(12),
        true,
        |_, _, _| true,
        |q, d, _| {
            *d = (0.5 + 8.3 - (q.as_vec3() - Vec3::new(0.3, -0.2, 0.1)).length()).clamp(0.0, 1.0);
        },
    );
    coarse.take_dirty();
    let boxes =
        [(IVec3::new(20, -20, -20), IVec3::new(40, 20, 20)), (IVec3::new(-8, 24, -8), IVec3::new(8, 40, 8))];
    let (windows, rounds, full) = steady_state(&mut coarse, boxes);
    assert!(full.iter().all(|d| d.upserted.iter().all(|(k, _)| argile::mesh::mesh_level(&coarse, *k) == 2)));
    assert!(
        full[0].upserted_triangles() > 100 && full[1].upserted_triangles() > 50,
        "{} {}",
        full[0].upserted_triangles(),
        full[1].upserted_triangles()
    );
    assert_eq!(rounds, 100, "every coarse re-mesh equals a fresh one");
    assert!(windows.contains(&0), "allocations re-meshing coarse clay: {windows:?}");
}
