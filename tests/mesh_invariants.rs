//! Invariants of the mesher on analytic shapes and random strokes: closed, consistently
//! oriented surfaces on the iso-level, seams that weld, incremental = full re-meshing.

use std::collections::HashMap;

use argile::field::{Field, FieldReader};
use argile::math::{IVec3, Pose, Quat, Vec3};
use argile::mesh::{mesh_all, remesh_dirty, ChunkKey, ChunkMesh};
use argile::tool::{
    apply_tool, rasterize_solid, stamp_sphere, Action, CsgOp, PlacedSolid, Solid, Tool, ToolShape,
};
use proptest::prelude::*;

/// All chunks welded by exact position (the seam contract makes shared vertices bit-identical).
struct Welded {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

fn weld<'a>(chunks: impl IntoIterator<Item = &'a ChunkMesh>) -> Welded {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let mut w = Welded { positions: Vec::new(), normals: Vec::new(), triangles: Vec::new() };
    for chunk in chunks {
        let map: Vec<u32> = chunk
            .vertices
            .iter()
            .map(|v| {
                let key = v.position.map(f32::to_bits);
                *ids.entry(key).or_insert_with(|| {
                    w.positions.push(Vec3::from(v.position));
                    w.normals.push(Vec3::from(v.normal));
                    (w.positions.len() - 1) as u32
                })
            })
            .collect();
        for t in chunk.indices.chunks_exact(3) {
            w.triangles.push([map[t[0] as usize], map[t[1] as usize], map[t[2] as usize]]);
        }
    }
    w
}

/// Every directed edge is used exactly once and its reverse exactly once: a closed, edge-manifold,
/// consistently oriented surface.
fn assert_closed_and_oriented(w: &Welded) {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &w.triangles {
        assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "degenerate triangle {t:?}");
        for i in 0..3 {
            *directed.entry((t[i], t[(i + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "edge {a}->{b} used {n} times");
        assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}->{b} has no opposite: the surface is open");
    }
}

/// V − E + F of a closed welded mesh (2 for a sphere's topology, 0 for a torus's).
fn euler_characteristic(w: &Welded) -> i64 {
    let edges = w.triangles.len() * 3 / 2;
    w.positions.len() as i64 - edges as i64 + w.triangles.len() as i64
}

fn area_and_volume(w: &Welded) -> (f32, f32) {
    let mut area = 0.0;
    let mut volume = 0.0;
    for t in &w.triangles {
        let [a, b, c] = t.map(|i| w.positions[i as usize]);
        area += 0.5 * (b - a).cross(c - a).length();
        volume += a.dot(b.cross(c)) / 6.0;
    }
    (area, volume)
}

fn solid_field(solid: Solid, voxel: f32, position: Vec3) -> Field {
    let mut f = Field::new(voxel, 0.5);
    let placed =
        PlacedSolid { solid, pose: Pose { position_m: position, rotation: Quat::IDENTITY }, scale: 1.0 };
    rasterize_solid(&mut f, &placed, CsgOp::Union, [0.8, 0.4, 0.2, 1.0]);
    f
}

fn full_mesh(field: &Field) -> Welded {
    let diff = mesh_all(field);
    weld(diff.upserted.iter().map(|(_, m)| m))
}

fn assert_on_iso_level(field: &Field, w: &Welded) {
    let mut reader = FieldReader::new(field);
    for p in &w.positions {
        let d = reader.density_world(*p);
        assert!((d - field.iso()).abs() < 2e-3, "vertex {p} has density {d}");
    }
}

#[test]
fn a_single_full_sample_is_an_octahedron() {
    let mut f = Field::new(1.0, 0.5);
    f.edit_box(IVec3::ZERO, IVec3::ZERO, true, |_, d, _| *d = 1.0);
    let w = full_mesh(&f);
    // Eight cells share the sample; each cuts its corner with one triangle.
    assert_eq!(w.triangles.len(), 8);
    assert_eq!(w.positions.len(), 6);
    assert_closed_and_oriented(&w);
    let (_, volume) = area_and_volume(&w);
    // Vertices halfway along each axis: an octahedron of "radius" 0.5, volume 4/3 · 0.5³.
    assert!((volume - 4.0 / 3.0 * 0.125).abs() < 1e-3, "volume {volume}");
}

#[test]
fn a_sphere_straddling_brick_seams_is_closed_with_the_right_area_and_volume() {
    let r = 0.0237;
    // Centred on a brick corner so that the surface crosses seams on every axis.
    let f = solid_field(Solid::Sphere { radius_m: r }, 0.001, Vec3::new(0.016, -0.008, 0.0));
    let w = full_mesh(&f);
    assert_closed_and_oriented(&w);
    assert_on_iso_level(&f, &w);
    assert_eq!(euler_characteristic(&w), 2, "a sphere's topology");
    let (area, volume) = area_and_volume(&w);
    let pi = std::f32::consts::PI;
    assert!((area / (4.0 * pi * r * r) - 1.0).abs() < 0.02, "area {area}");
    assert!((volume / (4.0 / 3.0 * pi * r * r * r) - 1.0).abs() < 0.02, "volume {volume}");
    // Normals point out of the sphere.
    for (p, n) in w.positions.iter().zip(&w.normals) {
        let out = (*p - Vec3::new(0.016, -0.008, 0.0)).normalize();
        assert!(n.dot(out) > 0.95, "normal {n} at {p}");
        assert!((n.length() - 1.0).abs() < 1e-4);
    }
}

#[test]
fn torus_and_box_are_closed_and_on_the_iso_level() {
    for (solid, euler) in [
        (Solid::Torus { major_m: 0.02, minor_m: 0.0065 }, 0),
        (Solid::Box { half_m: Vec3::new(0.0113, 0.0171, 0.0093) }, 2),
        (Solid::RoundedBox { half_m: Vec3::new(0.02, 0.01, 0.015), corner_m: 0.004 }, 2),
        (Solid::Cylinder { radius_m: 0.009, half_height_m: 0.013 }, 2),
        (Solid::Bar { half_length_m: 0.03, radius_m: 0.006 }, 2),
    ] {
        let f = solid_field(solid, 0.001, Vec3::new(0.0031, 0.0007, -0.0049));
        let w = full_mesh(&f);
        assert!(!w.triangles.is_empty(), "{solid:?}");
        assert_closed_and_oriented(&w);
        assert_eq!(euler_characteristic(&w), euler, "{solid:?}: V − E + F");
        assert_on_iso_level(&f, &w);
        let (_, volume) = area_and_volume(&w);
        assert!(volume > 0.0, "{solid:?}: outward orientation gives a positive volume");
    }
}

/// A box whose faces lie on the lattice has its whole outer layer of samples stored at the
/// iso-level: the surface must neither pass through those samples (where the cells around one
/// would meet in slivers) nor depend on which way a rounding broke each tie.
#[test]
fn a_box_with_its_faces_on_the_lattice_meshes_without_slivers() {
    let f = solid_field(Solid::Box { half_m: Vec3::new(0.010, 0.006, 0.008) }, 0.001, Vec3::ZERO);
    assert_eq!(f.density(IVec3::new(10, 0, 0)), f.iso(), "the face samples hold the iso-level");
    let w = full_mesh(&f);
    assert_closed_and_oriented(&w);
    assert_eq!(euler_characteristic(&w), 2);
    let smallest = w
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| w.positions[i as usize] / 0.001);
            0.5 * (b - a).cross(c - a).length()
        })
        .fold(f32::INFINITY, f32::min);
    assert!(smallest > 0.05, "a sliver of {smallest} square voxels");
    // The same box on either side of the origin: every face alike.
    let (_, volume) = area_and_volume(&w);
    let extent = w.positions.iter().fold(Vec3::ZERO, |m, p| m.max(p.abs()));
    assert!((extent - Vec3::new(0.010, 0.006, 0.008)).abs().max_element() < 1e-6, "{extent}");
    assert!(volume > 0.0);
}

#[test]
fn meshing_is_reproducible_bit_for_bit() {
    let f = solid_field(Solid::Torus { major_m: 0.02, minor_m: 0.006 }, 0.001, Vec3::ZERO);
    let a = mesh_all(&f);
    let b = mesh_all(&f);
    assert_eq!(a.upserted, b.upserted);
}

#[derive(Clone, Debug)]
struct Stamp {
    centre: Vec3,
    radius: f32,
    add: bool,
}

fn stamps() -> impl Strategy<Value = Vec<Stamp>> {
    prop::collection::vec(
        (-0.012f32..0.012, -0.012f32..0.012, -0.012f32..0.012, 0.0015f32..0.008, prop::bool::weighted(0.7))
            .prop_map(|(x, y, z, radius, add)| Stamp { centre: Vec3::new(x, y, z), radius, add }),
        1..12,
    )
}

/// The field after `stamps`, each made by `stamp` into an empty field, and the chunks kept
/// by applying the re-mesh of its dirty bricks after each.
fn remeshed_after_each(
    stamps: &[Stamp],
    mut stamp: impl FnMut(&mut Field, &Stamp, Action),
) -> (Field, HashMap<ChunkKey, ChunkMesh>) {
    let mut field = Field::new(0.001, 0.5);
    let mut chunks = HashMap::new();
    for s in stamps {
        stamp(&mut field, s, if s.add { Action::Add } else { Action::Remove });
        let diff = remesh_dirty(&mut field);
        for key in diff.removed {
            chunks.remove(&key);
        }
        chunks.extend(diff.upserted);
    }
    (field, chunks)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, rng_seed: proptest::test_runner::RngSeed::Fixed(0x4152_4749), ..ProptestConfig::default() })]

    /// After any sequence of strokes, incremental re-meshing of the dirty bricks gives exactly
    /// the chunks of a full re-mesh, and the surface is closed, oriented and free of NaN.
    #[test]
    fn incremental_meshing_equals_full_meshing_and_stays_closed(stamps in stamps()) {
        let (field, chunks) = remeshed_after_each(&stamps, |field, s, action| {
            stamp_sphere(field, s.centre, s.radius, action, [0.2, 0.5, 0.9, 1.0]);
        });
        let full: HashMap<ChunkKey, ChunkMesh> = mesh_all(&field).upserted.into_iter().collect();
        prop_assert_eq!(&chunks, &full);
        for key in field.brick_keys() {
            let brick = field.brick(key).unwrap();
            prop_assert!(brick.density.iter().all(|&d| d <= argile::field::DENSITY_ONE));
        }
        let w = weld(full.values());
        prop_assert!(w.positions.iter().chain(&w.normals).all(|v| v.is_finite()));
        assert_closed_and_oriented(&w);
        assert_on_iso_level(&field, &w);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, rng_seed: proptest::test_runner::RngSeed::Fixed(0x4c45_5645), ..ProptestConfig::default() })]

    /// Strokes of tools editing by their size (levels 0 to 2 here, over and beside each
    /// other): incremental re-meshing of the dirty bricks still gives exactly the chunks of a
    /// full re-mesh, and the surface stays closed across the levels.
    #[test]
    fn incremental_meshing_equals_full_meshing_across_levels(stamps in stamps()) {
        let (field, chunks) = remeshed_after_each(&stamps, |field, s, action| {
            // Radii of 1.5 to 8 mm, at most 2 voxels across: levels 0, 1 and 2.
            let tool = Tool {
                level_samples: Some(2.0),
                ..Tool::new(ToolShape::sphere(s.radius), action, [0.2, 0.5, 0.9, 1.0])
            };
            apply_tool(field, &tool, Pose { position_m: s.centre, ..Default::default() }, 0.0);
        });
        let full: HashMap<ChunkKey, ChunkMesh> = mesh_all(&field).upserted.into_iter().collect();
        prop_assert_eq!(&chunks, &full);
        let w = weld(full.values());
        assert_closed_and_oriented(&w);
    }
}

/// The paper's tool voxmap value (4× oversampling, two 2×2×2 box filters), for comparison.
fn galyean_hughes_sphere(offset: Vec3, radius: f32) -> f32 {
    const W: [f32; 3] = [0.25, 0.5, 0.25];
    let mut acc = 0.0;
    for (a, wa) in W.iter().enumerate() {
        for (b, wb) in W.iter().enumerate() {
            for (c, wc) in W.iter().enumerate() {
                let tap = offset + (Vec3::new(a as f32, b as f32, c as f32) - 1.0) * 0.25;
                if tap.length_squared() <= radius * radius {
                    acc += wa * wb * wc;
                }
            }
        }
    }
    acc
}

/// RMS and maximum angle (degrees) between mesh normals and the sphere's true normals.
fn normal_errors(f: &Field, centre: Vec3) -> (f64, f64) {
    let diff = mesh_all(f);
    let (mut sum, mut max, mut n) = (0.0f64, 0.0f64, 0usize);
    for (_, chunk) in &diff.upserted {
        for v in &chunk.vertices {
            let truth = (Vec3::from(v.position) - centre).normalize();
            let angle = f64::from(Vec3::from(v.normal).dot(truth).clamp(-1.0, 1.0).acos().to_degrees());
            sum += angle * angle;
            max = max.max(angle);
            n += 1;
        }
    }
    ((sum / n as f64).sqrt(), max)
}

#[test]
fn the_wide_band_gives_truer_normals_than_the_papers_filter() {
    let centre_index = Vec3::new(0.37, -0.21, 0.13);
    let radius = 9.3;
    let mut paper = Field::new(0.001, 0.5);
    let snapped = (centre_index * 4.0).round() / 4.0;
    let reach = IVec3::splat(radius as i32 + 2);
    paper.edit_box(-reach, reach, true, |p, d, _| {
        *d = d.max(galyean_hughes_sphere(p.as_vec3() - snapped, radius))
    });
    let mut ours = Field::new(0.001, 0.5);
    stamp_sphere(&mut ours, centre_index * 0.001, radius * 0.001, Action::Add, [1.0; 4]);
    let (paper_rms, paper_max) = normal_errors(&paper, snapped * 0.001);
    let (ours_rms, ours_max) = normal_errors(&ours, centre_index * 0.001);
    eprintln!("normal error: paper rms {paper_rms:.2}° max {paper_max:.2}°, ours rms {ours_rms:.2}° max {ours_max:.2}°");
    assert!(ours_rms * 4.0 < paper_rms, "rms {ours_rms:.2}° vs the paper's {paper_rms:.2}°");
    assert!(ours_max < 2.0, "max {ours_max:.2}°");
}

/// A sphere of radius 9 level-2 voxels (36 finest voxels) held on level 2 alone, meshed on the
/// finest lattice from the interpolation; then a fine carve refines part of it.
#[test]
fn coarse_clay_meshes_closed_and_continuous_with_fine_clay_beside_it() {
    let mut f = Field::new(0.001, 0.5);
    f.edit_level(
        2,
        IVec3::splat(-12),
        IVec3::splat(12),
        true,
        |_, _, _| true,
        |q, d, _| {
            *d = (9.5 - q.as_vec3().length()).clamp(0.0, 1.0);
        },
    );
    assert_eq!(f.brick_count(), 0, "no finest brick yet");
    let w = full_mesh(&f);
    assert_closed_and_oriented(&w);
    assert_eq!(euler_characteristic(&w), 2);
    assert_on_iso_level(&f, &w);
    let (_, volume) = area_and_volume(&w);
    let want = 4.0 / 3.0 * std::f32::consts::PI * (9.0f32 * 4.0 * 0.001).powi(3);
    assert!((volume / want - 1.0).abs() < 0.1, "volume {volume} against {want}");

    // A fine carve across the surface: the finest bricks it makes meet the coarse clay
    // without a crack, and re-meshing what it dirtied equals meshing everything again.
    let mut chunks: HashMap<_, _> = mesh_all(&f).upserted.into_iter().collect();
    f.take_dirty();
    f.begin_stroke();
    f.edit_box(IVec3::new(30, -6, -6), IVec3::new(40, 6, 6), false, |p, d, _| {
        let r = (p - IVec3::new(36, 0, 0)).as_vec3().length();
        *d = d.min(((r - 4.0) / 2.0).clamp(0.0, 1.0));
    });
    f.end_stroke();
    assert!(f.brick_count() > 0, "the carve refined finest bricks");
    let diff = remesh_dirty(&mut f);
    for key in diff.removed {
        chunks.remove(&key);
    }
    chunks.extend(diff.upserted);
    let all: HashMap<ChunkKey, ChunkMesh> = mesh_all(&f).upserted.into_iter().collect();
    assert_eq!(chunks, all);
    let full = weld(all.values());
    assert_closed_and_oriented(&full);
    assert_eq!(euler_characteristic(&full), 2);
    assert_on_iso_level(&f, &full);
}

/// A ball of radius `radius` level voxels written on level `level` alone, centred on world
/// position `centre`, adding or carving.
fn level_ball(field: &mut Field, level: usize, centre: Vec3, radius: f32, add: bool) {
    let voxel = 0.001 * (1 << level) as f32;
    let c = centre / voxel;
    let reach = IVec3::splat(radius.ceil() as i32 + 2);
    let mid = c.round().as_ivec3();
    field.edit_level(
        level,
        mid - reach,
        mid + reach,
        add,
        |_, _, _| true,
        |q, d, colour| {
            let v = (0.5 - (q.as_vec3() - c).length() + radius).clamp(0.0, 1.0);
            if add {
                if v > *d {
                    *colour = [0.3, 0.6, 0.2, 1.0];
                }
                *d = d.max(v);
            } else {
                *d = d.min(1.0 - v);
            }
        },
    );
}

/// The seam contract across chunks of any levels: a vertex two chunks share (by position) has
/// the same normal and colour, bit for bit, in both, so shading is one across the seams.
/// Returns how many vertices chunks share.
fn assert_shared_vertices_agree(chunks: &[(ChunkKey, ChunkMesh)]) -> usize {
    let mut seen: HashMap<[u32; 3], (ChunkKey, argile::mesh::Vertex)> = HashMap::new();
    let mut shared = 0;
    for (key, chunk) in chunks {
        for v in &chunk.vertices {
            match seen.entry(v.position.map(f32::to_bits)) {
                std::collections::hash_map::Entry::Occupied(e) => {
                    let (other, first) = e.get();
                    if other != key {
                        assert_eq!(first, v, "chunks {other} and {key}");
                        shared += 1;
                    }
                }
                std::collections::hash_map::Entry::Vacant(e) => {
                    e.insert((*key, *v));
                }
            }
        }
    }
    shared
}

/// No triangle of a welded mesh is flat: its height over its longest side is more than a
/// millionth of that side. (Marching cubes makes small triangles, where a sample lies near
/// the iso-level, and thin ones, but keeps its vertices 10⁻⁴ of an edge from the samples: a
/// thinner triangle has its corners in a line.)
fn assert_no_flat_triangle(w: &Welded) {
    for t in &w.triangles {
        let [a, b, c] = t.map(|i| w.positions[i as usize].as_dvec3());
        let twice_area = (b - a).cross(c - a).length();
        let longest = (b - a).length().max((c - b).length()).max((a - c).length());
        assert!(
            twice_area > 1e-6 * longest * longest,
            "triangle {t:?} at {a} is flat: height {} over a side of {longest}",
            twice_area / longest
        );
    }
}

/// Coarse clay (level 2, 4 mm voxels) meshed on its own lattice: a sixteenth of the finest
/// level's triangles for the same sphere, closed, on the iso-level, of the right volume.
#[test]
fn coarse_clay_is_meshed_on_its_own_level() {
    let mut coarse = Field::new(0.001, 0.5);
    level_ball(&mut coarse, 2, Vec3::new(0.0013, -0.0021, 0.0007), 7.6, true);
    let mut fine = Field::new(0.001, 0.5);
    level_ball(&mut fine, 0, Vec3::new(0.0013, -0.0021, 0.0007), 7.6 * 4.0, true);
    let (c, f) = (mesh_all(&coarse), mesh_all(&fine));
    assert!(c.upserted.iter().all(|(k, _)| argile::mesh::mesh_level(&coarse, *k) == 2));
    let ratio = f.upserted_triangles() as f32 / c.upserted_triangles() as f32;
    assert!(
        (12.0..20.0).contains(&ratio),
        "{} finest triangles against {} coarse",
        f.upserted_triangles(),
        c.upserted_triangles()
    );
    let w = weld(c.upserted.iter().map(|(_, m)| m));
    assert_closed_and_oriented(&w);
    assert_eq!(euler_characteristic(&w), 2);
    assert_on_iso_level(&coarse, &w);
    assert_no_flat_triangle(&w);
    let (_, volume) = area_and_volume(&w);
    let want = 4.0 / 3.0 * std::f32::consts::PI * (7.6f32 * 0.004).powi(3);
    assert!((volume / want - 1.0).abs() < 0.03, "volume {volume} against {want}");
}

/// Fine clay touching coarse clay of every coarser level across a face, along an edge only
/// and at a corner only: the coarse cells conform and the surface is closed, one piece.
#[test]
fn fine_clay_meets_coarse_clay_across_faces_edges_and_corners_without_a_crack() {
    for level in 1..=3 {
        let scale = (1 << level) as f32;
        // A coarse slab about 80 mm wide and 12 to 24 mm thick, then a fine ball on its top
        // face and a fine dent in its bottom one, each about a brick corner: the finest
        // bricks meet coarse ones across faces, along edges only and at corners only.
        let mut f = Field::new(0.001, 0.5);
        let half = (IVec3::new(40, 40, 6) / (1 << level)).max(IVec3::ONE);
        f.edit_level(
            level,
            -half,
            half,
            true,
            |_, _, _| true,
            |q, d, _| {
                let inside = (half.as_vec3() - q.as_vec3().abs()).min_element();
                *d = (0.5 + inside).clamp(0.0, 1.0);
            },
        );
        // The slab's faces lie at z = ±(half.z + 0.5) level voxels.
        let top = (half.z as f32 + 0.5) * scale * 0.001;
        level_ball(&mut f, 0, Vec3::new(0.0081, 0.0079, top + 0.0007), 5.3, true);
        f.begin_stroke();
        level_ball(&mut f, 0, Vec3::new(-0.0161, 0.0159, -top - 0.0003), 4.1, false);
        f.end_stroke();
        let diff = mesh_all(&f);
        let levels: Vec<usize> =
            diff.upserted.iter().map(|(k, _)| argile::mesh::mesh_level(&f, *k)).collect();
        let on = |l: usize| levels.iter().filter(|&&m| m == l).count();
        assert!(on(0) > 0 && on(level) > 2 * on(0), "level {level}: {levels:?}");
        assert!(levels.iter().all(|&m| m == 0 || m == level), "level {level}: {levels:?}");
        assert!(assert_shared_vertices_agree(&diff.upserted) > 100, "level {level}");
        let w = weld(diff.upserted.iter().map(|(_, m)| m));
        assert_closed_and_oriented(&w);
        assert_eq!(euler_characteristic(&w), 2, "level {level}: one closed piece");
        assert_on_iso_level(&f, &w);
        assert_no_flat_triangle(&w);
        assert!(area_and_volume(&w).1 > 0.0);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(0x4d4c_564c), ..ProptestConfig::default() })]

    /// Balls added and carved on levels 0 to 3 in any order, then some strokes undone: every
    /// brick meshed on the coarsest level its clay allows, the incremental chunks equal a full
    /// re-mesh after each step, and the welded surface is closed, oriented, on the iso-level
    /// and without a flat triangle.
    #[test]
    fn meshes_of_mixed_levels_are_closed_and_incremental(
        stamps in stamps(),
        levels in prop::collection::vec(0usize..=3, 12),
        undo in 0usize..4,
    ) {
        let mut field = Field::new(0.001, 0.5);
        let mut chunks: HashMap<ChunkKey, ChunkMesh> = HashMap::new();
        let apply = |field: &mut Field, chunks: &mut HashMap<ChunkKey, ChunkMesh>| {
            let diff = remesh_dirty(field);
            for key in diff.removed {
                chunks.remove(&key);
            }
            chunks.extend(diff.upserted);
        };
        for (s, &level) in stamps.iter().zip(&levels) {
            field.begin_stroke();
            let radius = s.radius / (0.001 * (1 << level) as f32);
            level_ball(&mut field, level, s.centre, radius.max(1.2), s.add);
            field.end_stroke();
            apply(&mut field, &mut chunks);
        }
        for _ in 0..undo {
            field.undo().unwrap();
            apply(&mut field, &mut chunks);
        }
        let all = mesh_all(&field).upserted;
        assert_shared_vertices_agree(&all);
        let full: HashMap<ChunkKey, ChunkMesh> = all.into_iter().collect();
        prop_assert_eq!(&chunks, &full);
        let w = weld(full.values());
        prop_assert!(w.positions.iter().chain(&w.normals).all(|v| v.is_finite()));
        assert_closed_and_oriented(&w);
        assert_on_iso_level(&field, &w);
        assert_no_flat_triangle(&w);
    }
}

/// One step of a session: a stroke of three stamps of a tool, or an undo, or a redo.
#[derive(Clone, Debug)]
enum Step {
    Stroke { shape: u8, action: u8, level_samples: Option<f32>, size: f32, at: Vec3, turn: Vec3, colour: u8 },
    Undo,
    Redo,
}

fn steps() -> impl Strategy<Value = Vec<Step>> {
    let stroke = (
        0u8..3,
        0u8..6,
        prop::option::of(prop::sample::select(vec![2.0f32, 4.0, 8.0])),
        0.002f32..0.02,
        (-0.03f32..0.03, -0.03f32..0.03, -0.03f32..0.03),
        (0.0f32..3.0, 0.0f32..3.0, 0.0f32..3.0),
        0u8..3,
    )
        .prop_map(|(shape, action, level_samples, size, (x, y, z), (a, b, c), colour)| Step::Stroke {
            shape,
            action,
            level_samples,
            size,
            at: Vec3::new(x, y, z),
            turn: Vec3::new(a, b, c),
            colour,
        });
    prop::collection::vec(prop_oneof![8 => stroke, 1 => Just(Step::Undo), 1 => Just(Step::Redo)], 1..24)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, rng_seed: proptest::test_runner::RngSeed::Fixed(0x5345_5353), ..ProptestConfig::default() })]

    /// A session of balls, boxes and rounded boxes adding, carving, painting and smoothing, on
    /// the finest level and by their size (levels 0 to 4), with undo and redo: the chunks kept
    /// by re-meshing each step's dirty bricks equal a full re-mesh, and the surface is closed
    /// with every shared vertex alike in its chunks.
    #[test]
    fn any_session_of_tools_and_levels_meshes_incrementally_and_closed(steps in steps()) {
        let mut field = Field::new(0.001, 0.5);
        let mut mesher = argile::mesh::Mesher::default();
        let mut chunks: HashMap<ChunkKey, ChunkMesh> = HashMap::new();
        let colours = [[0.8, 0.2, 0.2, 1.0], [0.2, 0.7, 0.3, 1.0], [0.2, 0.3, 0.9, 1.0]];
        for step in &steps {
            match *step {
                Step::Undo => {
                    field.undo().unwrap();
                }
                Step::Redo => {
                    field.redo();
                }
                Step::Stroke { shape, action, level_samples, size, at, turn, colour } => {
                    let shape = match shape {
                        0 => ToolShape::sphere(size),
                        1 => ToolShape::Solid(Solid::Box { half_m: Vec3::new(size, size * 0.6, size * 0.8) }),
                        _ => ToolShape::Solid(Solid::RoundedBox {
                            half_m: Vec3::new(size, size * 0.7, size * 0.5),
                            corner_m: size * 0.3,
                        }),
                    };
                    let action = match action {
                        0..=2 => Action::Add,
                        3 => Action::Remove,
                        4 => Action::Paint,
                        _ => Action::Smooth { centre_weight: 6.0, rate_per_s: 20.0 },
                    };
                    let tool = Tool { level_samples, ..Tool::new(shape, action, colours[usize::from(colour)]) };
                    let rotation = Quat::from_euler(glam::EulerRot::XYZ, turn.x, turn.y, turn.z);
                    field.begin_stroke();
                    for i in 0..3 {
                        let pose = Pose { position_m: at + Vec3::X * (i as f32 * size * 0.5), rotation };
                        apply_tool(&mut field, &tool, pose, 0.05);
                    }
                    field.end_stroke();
                }
            }
            let diff = mesher.remesh_dirty(&mut field);
            for key in &diff.removed {
                chunks.remove(key);
            }
            chunks.extend(diff.upserted.iter().cloned());
        }
        let all = mesh_all(&field).upserted;
        assert_shared_vertices_agree(&all);
        let full: HashMap<ChunkKey, ChunkMesh> = all.into_iter().collect();
        prop_assert_eq!(&chunks, &full);
        assert_closed_and_oriented(&weld(full.values()));
    }
}

/// A drag of a lattice's control point: which one, where to, and its value's change.
#[derive(Clone, Debug)]
struct Drag {
    ijk: [usize; 3],
    offset: Vec3,
    value: f64,
}

fn drags() -> impl Strategy<Value = Vec<Drag>> {
    let drag = ((0usize..6, 0usize..5, 0usize..5), (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), -0.4f64..0.4)
        .prop_map(|((i, j, k), (x, y, z), value)| Drag {
            ijk: [i, j, k],
            offset: Vec3::new(x, y, z) * 0.012,
            value,
        });
    prop::collection::vec(drag, 1..8)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, rng_seed: proptest::test_runner::RngSeed::Fixed(0x4C41_5454), ..ProptestConfig::default() })]

    /// Any drags of any control points of a lattice over a bar, the outer ones included, each
    /// moving it and changing its value, of every kind of lattice: the clay stays finite and
    /// in [0, 1], its incremental re-mesh equals a full one, the surface is closed and
    /// consistently oriented, and resetting the lattice gives back the clay bit for bit.
    #[test]
    fn any_drags_of_a_lattice_leave_a_closed_surface_and_reset_exactly(drags in drags(), kind in 0u8..3) {
        use argile::lattice::{Lattice, LatticeSpec};
        use argile::math::Aabb;
        use argile::spline::SplineKind;
        let bar = Solid::Bar { half_length_m: 0.05, radius_m: 0.01 };
        let original = solid_field(bar, 0.002, Vec3::ZERO);
        let mut field = original.clone();
        let region = Aabb { min: Vec3::new(-0.05, -0.025, -0.025), max: Vec3::new(0.05, 0.025, 0.025) };
        let kind = [SplineKind::Bezier, SplineKind::BSpline, SplineKind::Nurbs][usize::from(kind)];
        let mut lattice = Lattice::open(&field, &LatticeSpec { kind, ..LatticeSpec::cubic(region, [6, 5, 5]) }).unwrap();
        let mut mesher = argile::mesh::Mesher::default();
        let mut chunks: HashMap<ChunkKey, ChunkMesh> = mesher.remesh_dirty(&mut field).upserted.iter().cloned().collect();
        field.begin_stroke();
        for d in &drags {
            let [i, j, k] = d.ijk;
            let c = *lattice.volume().control(i, j, k).unwrap();
            let mut changed = lattice.move_control(d.ijk, c.position_m + d.offset).unwrap();
            changed = changed.union(&lattice.set_value(d.ijk, c.value + d.value).unwrap());
            lattice.write(&mut field, changed).unwrap();
            let diff = mesher.remesh_dirty(&mut field);
            for key in &diff.removed {
                chunks.remove(key);
            }
            chunks.extend(diff.upserted.iter().cloned());
        }
        field.end_stroke();
        let (lo, hi) = lattice.points_of(lattice.reach());
        let mut reader = FieldReader::new(&field);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let d = reader.density(IVec3::new(x, y, z));
                    prop_assert!(d.is_finite() && (0.0..=1.0).contains(&d));
                }
            }
        }
        let full: HashMap<ChunkKey, ChunkMesh> = mesh_all(&field).upserted.into_iter().collect();
        prop_assert_eq!(&chunks, &full);
        assert_closed_and_oriented(&weld(full.values()));
        lattice.reset(&mut field).unwrap();
        prop_assert!(field.same_samples(&original), "the reset lattice did not give back the clay");
    }
}
