//! Symmetry: a mirrored and a radial stroke leave exported meshes symmetric within one voxel,
//! and undoing them restores the clay bit for bit.

use std::path::Path;

use argile::app::{final_mesh, Playback};
use argile::math::{IVec3, Isometry, Vec3};
use argile::mesh::WeldedMesh;
use argile::scene::{Scene, Timeline};

fn scene(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/tests").join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn point_triangle_distance(p: Vec3, [a, b, c]: [Vec3; 3]) -> f32 {
    // Ericson, Real-Time Collision Detection, 5.1.5: the closest point by Voronoi regions.
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return p.distance(a);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return p.distance(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return p.distance(a + ab * (d1 / (d1 - d3)));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return p.distance(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return p.distance(a + ac * (d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return p.distance(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let denom = 1.0 / (va + vb + vc);
    p.distance(a + ab * (vb * denom) + ac * (vc * denom))
}

/// The largest distance from an image of a vertex to the mesh's surface, over every vertex
/// and image, found through a grid of cells `cell_m` wide (distances past a cell are
/// reported as at least one cell).
fn worst_asymmetry_m(mesh: &WeldedMesh, images: &[Isometry], cell_m: f32) -> f32 {
    let key = |p: Vec3| (p / cell_m).floor().as_ivec3();
    let corner = |i: u32| Vec3::from(mesh.positions[i as usize]);
    let triangles: Vec<[Vec3; 3]> =
        mesh.indices.chunks_exact(3).map(|t| [corner(t[0]), corner(t[1]), corner(t[2])]).collect();
    let mut grid: std::collections::HashMap<IVec3, Vec<usize>> = Default::default();
    for (i, t) in triangles.iter().enumerate() {
        grid.entry(key((t[0] + t[1] + t[2]) / 3.0)).or_default().push(i);
    }
    let nearest = |q: Vec3| {
        let c = key(q);
        let mut best = f32::INFINITY;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    for &t in grid.get(&(c + IVec3::new(dx, dy, dz))).into_iter().flatten() {
                        best = best.min(point_triangle_distance(q, triangles[t]));
                    }
                }
            }
        }
        best
    };
    let mut worst = 0.0f32;
    for &p in &mesh.positions {
        for image in images {
            worst = worst.max(nearest(image.point(Vec3::from(p))));
        }
    }
    worst
}

fn check_symmetric(name: &str, images_expected: usize) {
    let scene = scene(name);
    let images = scene.symmetry.images();
    assert_eq!(images.len(), images_expected);
    let mesh = final_mesh(&scene);
    assert!(mesh.triangle_count() > 1000);
    let voxel = scene.voxel_size_m;
    let worst = worst_asymmetry_m(&mesh, &images, 2.0 * voxel);
    assert!(worst <= voxel, "{name}: a vertex's image lies {:.3} voxels from the mesh", worst / voxel);
    // Without the symmetry the same strokes are far from symmetric: the test can fail.
    let mut lopsided = scene.clone();
    lopsided.symmetry = argile::parts::Symmetry::NONE;
    let plain = final_mesh(&lopsided);
    let off = worst_asymmetry_m(&plain, &images, 2.0 * voxel);
    assert!(off > 2.0 * voxel, "{name}: without symmetry the mesh is symmetric within {off} m");
    eprintln!("{name}: images within {:.3} voxels of the surface", worst / voxel);
}

#[test]
fn a_mirrored_stroke_is_symmetric_within_a_voxel_on_the_exported_mesh() {
    check_symmetric("mirror-stroke.toml", 2);
}

#[test]
fn a_radial_stroke_is_symmetric_within_a_voxel_on_the_exported_mesh() {
    check_symmetric("radial-stroke.toml", 5);
}

#[test]
fn undoing_a_symmetric_stroke_restores_the_clay_bit_for_bit() {
    for name in ["mirror-stroke.toml", "radial-stroke.toml"] {
        let scene = scene(name);
        let mut bare = scene.clone();
        bare.timeline = Timeline::new(Vec::new(), scene.timeline.step_s()).unwrap();
        let start = Playback::new(&bare).into_field();
        let mut playback = Playback::new(&scene);
        playback.advance_to(scene.timeline.duration_s(), |_| {});
        let mut field = playback.into_field();
        assert!(!field.same_samples(&start), "{name}: the stroke changed nothing");
        // One stroke with all its images: one undo step.
        assert!(field.undo().unwrap());
        assert!(field.same_samples(&start), "{name}: undo left a difference");
        assert!(!field.undo().unwrap(), "{name}: more than one undo step");
    }
}

#[test]
fn a_mirrored_push_conserves_the_clay_and_leaves_it_symmetric_within_a_voxel() {
    let scene = scene("mirror-push.toml");
    let mut bare = scene.clone();
    bare.timeline = Timeline::new(Vec::new(), scene.timeline.step_s()).unwrap();
    let before = Playback::new(&bare).into_field().mass();
    let mut playback = Playback::new(&scene);
    playback.advance_to(scene.timeline.duration_s() + 0.1, |_| {});
    let field = playback.into_field();
    let after = field.mass();
    assert!((after - before).abs() < 1e-3 * before, "mass {before} → {after}");
    let mesh = argile::app::welded_surface(&field);
    let images = scene.symmetry.images();
    let voxel = scene.voxel_size_m;
    let worst = worst_asymmetry_m(&mesh, &images, 2.0 * voxel);
    eprintln!("mirror-push: images within {:.3} voxels of the surface", worst / voxel);
    assert!(worst <= voxel, "a vertex's image lies {:.3} voxels from the surface", worst / voxel);
    // Both prints are there: the clay under each ball is pushed down.
    let t = *field.transform();
    let top = |x: f32| {
        (0..30)
            .rev()
            .find(|&j| {
                field.density(
                    t.world_to_index(Vec3::new(x, j as f32 * voxel - 0.02, 0.005)).round().as_ivec3(),
                ) > 0.5
            })
            .map_or(-1.0, |j| j as f32 * voxel - 0.02)
    };
    assert!(
        top(0.035) < top(0.0) - 0.004 && top(-0.035) < top(0.0) - 0.004,
        "{} {} {}",
        top(0.035),
        top(0.0),
        top(-0.035)
    );
}
