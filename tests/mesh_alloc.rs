//! The incremental mesher's steady state allocates nothing: once its buffers have grown,
//! re-meshing dirty sets it has seen makes no heap allocation on any thread.
//!
//! A counting global allocator counts every allocation of the process; this binary holds one
//! test so that nothing else allocates while it counts.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use argile::field::{BrickKey, Field};
use argile::math::Vec3;
use argile::mesh::{remesh, MeshDiff, Mesher};
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

/// The bricks a carving stamp of radius `r_m` at `centre` dirties.
fn stamp_dirt(field: &mut Field, centre: Vec3, r_m: f32) -> Vec<BrickKey> {
    stamp_sphere(field, centre, r_m, Action::Remove, [0.0; 4]);
    field.take_dirty().into_iter().collect()
}

fn same(a: &MeshDiff, b: &MeshDiff) -> bool {
    a.removed == b.removed && a.upserted == b.upserted
}

#[test]
fn remeshing_known_dirty_sets_again_allocates_nothing() {
    let mut field = sphere(0.03);
    let a = stamp_dirt(&mut field, Vec3::new(0.03, 0.0, 0.0), 0.008);
    let b = stamp_dirt(&mut field, Vec3::new(0.0, 0.03, 0.0), 0.004);
    let (full_a, full_b) = (remesh(&field, a.iter().copied()), remesh(&field, b.iter().copied()));
    assert!(full_a.upserted_triangles() > 1000 && full_b.upserted_triangles() > 100);
    assert!(!full_a.removed.is_empty(), "the stamp's box reaches bricks with no surface");

    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    // Counted inside the pool: handing work to rayon from outside it may allocate in rayon.
    let (allocations, rounds) = pool.install(|| {
        let mut mesher = Mesher::default();
        // Warm-up: the buffers grow to both sets.
        for keys in [&a, &b, &a, &b] {
            mesher.remesh(&field, keys.iter().copied());
        }
        // Each pool thread registers with rayon's work-stealing deque once, on its first
        // steal (one allocation, whenever that comes); a broadcast makes every thread steal.
        rayon::broadcast(|_| ());
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        let mut rounds = 0;
        for i in 0..20 {
            let (keys, full) = if i % 3 == 2 { (&b, &full_b) } else { (&a, &full_a) };
            let diff = mesher.remesh(&field, keys.iter().copied());
            rounds += usize::from(same(diff, full));
        }
        (ALLOCATIONS.load(Ordering::SeqCst) - before, rounds)
    });
    assert_eq!(rounds, 20, "every re-mesh equals a fresh one");
    assert_eq!(allocations, 0, "allocations in 20 steady-state re-meshes");
}
