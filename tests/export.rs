//! Mesh export: every format read back with an independent reader and compared with the mesh
//! Argile exported; the command line refuses to overwrite and writes atomically.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use argile::app::{export, final_mesh};
use argile::math::Vec3;
use argile::mesh::export::{ExportFormat, MILLIMETRES_PER_METRE};
use argile::mesh::WeldedMesh;
use argile::scene::Scene;

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tests/toothpaste.toml");

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("argile-export-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn mesh() -> WeldedMesh {
    final_mesh(&Scene::load(Path::new(SCENE)).unwrap())
}

fn exported(dir: &Path, format: ExportFormat) -> PathBuf {
    let path = dir.join(format!("sculpt.{}", format.extension()));
    let summary = export(Path::new(SCENE), format, &path, false, false).unwrap();
    assert_eq!(summary.path, path);
    path
}

fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).abs().max_element() <= tolerance
}

fn srgb(linear: f32) -> f32 {
    let c = linear.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[test]
fn the_exported_surface_is_closed_and_consistently_oriented() {
    let m = mesh();
    assert!(m.triangle_count() > 1000);
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in m.indices.chunks_exact(3) {
        for i in 0..3 {
            *directed.entry((t[i], t[(i + 1) % 3])).or_default() += 1;
        }
    }
    assert!(directed.iter().all(|(&(a, b), &n)| n == 1 && directed.get(&(b, a)) == Some(&1)));
    // One blob of clay: a sphere's topology.
    let edges = directed.len() / 2;
    let euler = m.positions.len() as i64 - edges as i64 + m.triangle_count() as i64;
    assert_eq!(euler, 2);
}

#[test]
fn glb_reads_back_with_the_gltf_crate() {
    let dir = temp_dir("glb");
    let m = mesh();
    let path = exported(&dir, ExportFormat::Glb);
    let (document, buffers, _) = gltf::import(&path).expect("a valid glTF 2.0 binary");
    let primitive = document.meshes().next().unwrap().primitives().next().unwrap();
    let reader = primitive.reader(|b| Some(&buffers[b.index()]));
    let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
    let normals: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
    let colours: Vec<[f32; 4]> = reader.read_colors(0).unwrap().into_rgba_f32().collect();
    let indices: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
    assert_eq!(
        (positions, normals, colours, indices),
        (m.positions.clone(), m.normals.clone(), m.colours.clone(), m.indices.clone())
    );
    let bounds = primitive.bounding_box();
    assert_eq!((Vec3::from(bounds.min), Vec3::from(bounds.max)), (m.bounds().min, m.bounds().max));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn stl_reads_back_watertight_in_millimetres() {
    let dir = temp_dir("stl");
    let m = mesh();
    let path = exported(&dir, ExportFormat::Stl);
    let stl = stl_io::read_stl(&mut std::fs::File::open(&path).unwrap()).unwrap();
    assert_eq!(stl.faces.len(), m.triangle_count());
    assert_eq!(stl.vertices.len(), m.positions.len(), "the reader's welding finds the same vertices");
    stl.validate().expect("every edge is shared by exactly two facets: watertight");
    let b = m.bounds();
    let (lo, hi) = stl.vertices.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
        let p = Vec3::new(v[0], v[1], v[2]);
        (lo.min(p), hi.max(p))
    });
    assert!(close(lo, b.min * MILLIMETRES_PER_METRE, 1e-3) && close(hi, b.max * MILLIMETRES_PER_METRE, 1e-3));
    // Facet normals point outward: away from the centre of the stroke's bounding box on
    // average, and agree with the vertex normals of the mesh.
    let agree = stl
        .faces
        .iter()
        .zip(m.indices.chunks_exact(3))
        .filter(|(f, t)| {
            let n = Vec3::new(f.normal[0], f.normal[1], f.normal[2]);
            let vertex_normal: Vec3 = t.iter().map(|&i| Vec3::from(m.normals[i as usize])).sum();
            n.dot(vertex_normal) > 0.0
        })
        .count();
    assert!(
        agree as f32 > 0.99 * stl.faces.len() as f32,
        "{agree} of {} facets face outward",
        stl.faces.len()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn obj_reads_back_with_normals_in_millimetres() {
    let dir = temp_dir("obj");
    let m = mesh();
    let path = exported(&dir, ExportFormat::Obj);
    let (models, _) = tobj::load_obj(
        &path,
        &tobj::LoadOptions { single_index: true, triangulate: false, ..Default::default() },
    )
    .expect("a valid OBJ");
    let obj = &models[0].mesh;
    assert_eq!(obj.positions.len(), 3 * m.positions.len());
    assert_eq!(obj.normals.len(), 3 * m.normals.len());
    // The reader numbers vertices in the order faces first use them: the same triangles,
    // corner by corner, at the same points.
    assert_eq!(obj.indices.len(), m.indices.len());
    let read = |i: u32| {
        let i = 3 * i as usize;
        Vec3::new(obj.positions[i], obj.positions[i + 1], obj.positions[i + 2])
    };
    for (corner, (&r, &w)) in obj.indices.iter().zip(&m.indices).enumerate() {
        let want = Vec3::from(m.positions[w as usize]) * MILLIMETRES_PER_METRE;
        assert!(close(read(r), want, 1e-3), "triangle {} corner {}", corner / 3, corner % 3);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn ply_reads_back_with_srgb_vertex_colours() {
    use ply_rs::ply::Property;
    let dir = temp_dir("ply");
    let m = mesh();
    let path = exported(&dir, ExportFormat::Ply);
    let parser = ply_rs::parser::Parser::<ply_rs::ply::DefaultElement>::new();
    let ply = parser
        .read_ply(&mut std::io::BufReader::new(std::fs::File::open(&path).unwrap()))
        .expect("a valid PLY");
    let vertices = &ply.payload["vertex"];
    let faces = &ply.payload["face"];
    assert_eq!((vertices.len(), faces.len()), (m.positions.len(), m.triangle_count()));
    let float = |e: &ply_rs::ply::DefaultElement, k: &str| match e[k] {
        Property::Float(v) => v,
        ref other => panic!("{k} is {other:?}"),
    };
    let byte = |e: &ply_rs::ply::DefaultElement, k: &str| match e[k] {
        Property::UChar(v) => v,
        ref other => panic!("{k} is {other:?}"),
    };
    for (i, v) in vertices.iter().enumerate().step_by(89) {
        let p = Vec3::new(float(v, "x"), float(v, "y"), float(v, "z"));
        assert_eq!(p, Vec3::from(m.positions[i]));
        let expected = (srgb(m.colours[i][0]) * 255.0).round();
        assert!((f32::from(byte(v, "red")) - expected).abs() <= 1.0, "vertex {i}: red");
    }
    match &faces[0]["vertex_indices"] {
        Property::ListUInt(list) => assert_eq!(list.as_slice(), &m.indices[..3]),
        other => panic!("faces hold {other:?}"),
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_command_refuses_to_overwrite_without_force_and_says_what_it_wrote() {
    let dir = temp_dir("cli");
    let out = dir.join("s.glb");
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_argile"))
            .args(["export", SCENE, "--format", "glb", "--out"])
            .arg(&out)
            .args(extra)
            .output()
            .unwrap()
    };
    let first = run(&[]);
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    assert!(String::from_utf8_lossy(&first.stdout).contains("triangles"));
    let written = std::fs::read(&out).unwrap();
    let second = run(&[]);
    assert!(!second.status.success());
    assert!(String::from_utf8_lossy(&second.stderr).contains("already exists; pass --force"));
    assert_eq!(std::fs::read(&out).unwrap(), written, "the file is untouched");
    assert!(run(&["--force"]).status.success());
    assert_eq!(std::fs::read(&out).unwrap(), written, "the same scene exports the same bytes");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "no temporary file is left");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_scene_without_clay_is_refused() {
    let dir = temp_dir("empty");
    let scene = dir.join("empty.toml");
    std::fs::write(&scene, "[camera]\nfov_y_deg = 30.0\n").unwrap();
    let e = export(&scene, ExportFormat::Stl, &dir.join("x.stl"), false, false).unwrap_err().to_string();
    assert!(e.contains("nothing to export"), "{e}");
    assert!(!dir.join("x.stl").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The shortest distance between two vertices of `mesh`, found through a grid of cells `cell`
/// wide (pairs farther apart than `cell` are not looked at: the answer is then at least `cell`).
fn closest_vertices(mesh: &WeldedMesh, cell: f32) -> f32 {
    let key = |p: [f32; 3]| p.map(|c| (c / cell).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in mesh.positions.iter().enumerate() {
        grid.entry(key(*p)).or_default().push(i);
    }
    let mut closest = f32::INFINITY;
    for (i, p) in mesh.positions.iter().enumerate() {
        let k = key(*p);
        for d in 0..27 {
            let at = [k[0] + d % 3 - 1, k[1] + d / 3 % 3 - 1, k[2] + d / 9 - 1];
            for &j in grid.get(&at).into_iter().flatten() {
                if j > i {
                    closest = closest.min(Vec3::from(*p).distance(Vec3::from(mesh.positions[j])));
                }
            }
        }
    }
    closest
}

/// A slicer or CAD tool welds vertices closer than its tolerance. Exports keep every two
/// vertices more than a thousandth of the finest voxel apart (1 µm at 1 mm voxels), so a weld
/// at up to that tolerance merges nothing and the mesh stays closed and manifold: the default
/// scene, coarse clay beside fine, a carved channel.
#[test]
fn exported_vertices_stay_a_thousandth_of_a_voxel_apart_so_a_weld_at_that_tolerance_changes_nothing() {
    for name in ["scenes/default.toml", "scenes/tests/levels-meet.toml", "scenes/tests/carved-sphere.toml"] {
        let scene = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(name)).unwrap();
        let field = argile::app::final_field(&scene);
        let voxel = field.transform().voxel_size_m;
        let mesh = argile::app::welded_surface(&field);
        let closest = closest_vertices(&mesh, 0.002 * voxel);
        assert!(closest > 0.001 * voxel, "{name}: two vertices {:.2e} voxel apart", closest / voxel);
    }
}
