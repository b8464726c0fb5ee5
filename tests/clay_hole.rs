//! Poking a hole through a slab of virtual clay held at its four corners (Dewaele–Cani §5.2):
//! the slab's surface changes topology, and the slab stays one piece around the hole.

use std::collections::HashMap;

use argile::clay::{Clay, ClayParams, ClayTool};
use argile::field::Field;
use argile::math::{IVec3, Pose, Vec3};
use argile::mesh::{mesh_all, weld, WeldedMesh};
use argile::tool::{rasterize_solid, CsgOp, PlacedSolid, Solid, ToolShape};

const H: f32 = 0.001;

fn at(y: f32) -> Pose {
    Pose { position_m: Vec3::new(0.0, y, 0.0) * H, ..Pose::default() }
}

fn surface(field: &Field) -> WeldedMesh {
    let mut diff = mesh_all(field);
    diff.upserted.sort_by_key(|(k, _)| (k.x, k.y, k.z));
    weld(diff.upserted.iter().map(|(_, m)| m))
}

/// V − E + F of a closed welded mesh.
fn euler_characteristic(m: &WeldedMesh) -> i64 {
    let faces = m.triangle_count() as i64;
    m.positions.len() as i64 - faces * 3 / 2 + faces
}

/// The pieces of a mesh (triangles joined by shared vertices), largest first: per piece its
/// Euler characteristic, its vertex count and its lowest and highest Y (metres).
fn pieces(m: &WeldedMesh) -> Vec<(i64, usize, f32, f32)> {
    let mut parent: Vec<u32> = (0..m.positions.len() as u32).collect();
    fn root(p: &mut [u32], mut i: u32) -> u32 {
        while p[i as usize] != i {
            p[i as usize] = p[p[i as usize] as usize];
            i = p[i as usize];
        }
        i
    }
    for t in m.indices.chunks_exact(3) {
        for k in 1..3 {
            let (a, b) = (root(&mut parent, t[0]), root(&mut parent, t[k]));
            parent[a as usize] = b;
        }
    }
    // Per root: vertices, faces, min y, max y.
    let mut stats: HashMap<u32, (i64, i64, f32, f32)> = HashMap::new();
    for v in 0..m.positions.len() as u32 {
        let r = root(&mut parent, v);
        let y = m.positions[v as usize][1];
        let e = stats.entry(r).or_insert((0, 0, f32::INFINITY, f32::NEG_INFINITY));
        e.0 += 1;
        e.2 = e.2.min(y);
        e.3 = e.3.max(y);
    }
    for t in m.indices.chunks_exact(3) {
        stats.get_mut(&root(&mut parent, t[0])).unwrap().1 += 1;
    }
    let mut out: Vec<(i64, usize, f32, f32)> =
        stats.values().map(|&(v, f, lo, hi)| (v - f * 3 / 2 + f, v as usize, lo, hi)).collect();
    out.sort_by_key(|p| std::cmp::Reverse(p.1));
    out
}

#[test]
fn a_tool_pushed_through_a_held_slab_opens_a_hole() {
    let mut field = Field::new(H, 0.5);
    let slab = PlacedSolid {
        solid: Solid::Box { half_m: Vec3::new(20.0, 3.0, 20.0) * H },
        pose: Pose::default(),
        scale: 1.0,
    };
    rasterize_solid(&mut field, &slab, CsgOp::Union, [0.7, 0.5, 0.4, 1.0]);
    let before = surface(&field);
    assert_eq!(euler_characteristic(&before), 2);
    let mass0 = field.mass();

    let tool = ClayTool::pusher(ToolShape::sphere(5.0 * H), Vec3::ONE, at(12.0));
    // Fairly fluid clay lets the tool through rather than dragging the slab along (§5.2).
    let params = ClayParams { fluidity: 0.3, ..ClayParams::default() };
    let mut clay = Clay::new(&field, IVec3::new(-28, -32, -28), IVec3::new(28, 20, 28), vec![tool], params);
    // The four corners are held (§5.2).
    clay.fix_where(|p| p.x.abs() >= 15 && p.z.abs() >= 15);
    field.begin_stroke();
    let steps = 60;
    let clay_mass0 = clay.mass();
    for s in 1..=steps {
        clay.step(&[at(12.0 - 32.0 * s as f32 / steps as f32)]);
        let drift = (clay.mass() - clay_mass0).abs() / clay_mass0;
        assert!(drift < 0.01, "step {s}: the clay's matter drifted by {:.3} %", drift * 100.0);
    }
    clay.finish(&mut field);
    field.end_stroke();

    let after = surface(&field);
    let parts = pieces(&after);
    // The tool went through and the slab stays one piece: no plug was punched out, the
    // matter the tool pushed stays in the slab (the bump behind it, §5.2). One hole through a
    // closed surface: V − E + F of the whole surface drops by 2, from 2 (a ball) to 0 (a
    // torus).
    assert_eq!(parts.len(), 1, "the slab stays one piece: {parts:?}");
    assert_eq!(
        euler_characteristic(&after),
        euler_characteristic(&before) - 2,
        "a hole through the slab: {parts:?}"
    );
    // The hole is where the tool went: no clay in the column on its axis; and the slab
    // closes round it: clay in every column of a ring between the hole and the held corners.
    let column =
        |x: i32, z: i32| (-32..=20).map(|y| field.density(IVec3::new(x, y, z))).fold(0.0f32, f32::max);
    assert!(column(0, 0) < field.iso(), "the axis of the push is open: {}", column(0, 0));
    for k in 0..32 {
        let a = k as f32 / 32.0 * std::f32::consts::TAU;
        let (x, z) = ((11.0 * a.cos()).round() as i32, (11.0 * a.sin()).round() as i32);
        assert!(column(x, z) >= field.iso(), "no clay round the hole at ({x}, {z}): {}", column(x, z));
    }
    assert!((field.mass() - mass0).abs() / mass0 < 0.01);
}

/// `scenes/poke-hole.toml` ends with the ball pushed through the slab, the punched plug under
/// it. The paper (§3.3) eats crumbs ("a few neighbouring cells", 64 here) back into the nearest
/// dense cell once no tool works them; so does the end of a timeline, where the tools let go:
/// the exported clay is one slab with a hole, and the plug's matter is back in it.
#[test]
fn the_plug_punched_out_of_the_poke_hole_scene_is_eaten_back_when_the_ball_lets_go() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/poke-hole.toml");
    let scene = argile::scene::Scene::load(std::path::Path::new(path)).unwrap();
    let mass0 = argile::app::Playback::new(&scene).field().mass();
    let field = argile::app::final_field(&scene);
    let parts = pieces(&surface(&field));
    assert_eq!(parts.len(), 1, "one slab, no plug beside it: {parts:?}");
    assert_eq!(parts[0].0, 0, "with a hole through it: {parts:?}");
    let drift = (field.mass() - mass0).abs() / mass0;
    assert!(drift < 1e-3, "the plug's matter went back to the slab: drift {:.4} %", drift * 100.0);
}
