//! Parts: a figure of three parts at three resolutions, a difference part drilling through two
//! others, tools acting on one part through its placement, sculpt-wide undo across parts, any
//! composition meshing closed and consistently oriented, and bad parts refused at their line.

use std::collections::HashMap;
use std::path::Path;

use argile::app::{welded_surface, Playback};
use argile::field::{Field, FieldReader};
use argile::math::{Pose, Quat, Vec3};
use argile::parts::{Composition, Csg, PartView, Placement};
use argile::scene::{Scene, Timeline};
use argile::tool::{rasterize_solid, CsgOp, PlacedSolid, Solid};
use proptest::prelude::*;

fn scene(name: &str) -> Scene {
    Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name))
        .unwrap_or_else(|e| panic!("{e}"))
}

fn density(field: &Field, world_m: Vec3) -> f32 {
    FieldReader::new(field).density_world(world_m)
}

/// Every directed edge once and its reverse once: closed, edge-manifold, consistently oriented;
/// every position finite.
fn assert_closed_and_oriented(field: &Field, what: &str) -> usize {
    let mesh = welded_surface(field);
    assert!(mesh.positions.iter().flatten().all(|c| c.is_finite()), "{what}: a vertex is not finite");
    let mut edges = HashMap::<(u32, u32), u32>::new();
    for t in mesh.indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1, "{what}: edge {a}-{b} used {n} times");
        assert_eq!(edges.get(&(b, a)), Some(&1), "{what}: edge {a}-{b} has no reverse: a hole");
    }
    mesh.triangle_count()
}

#[test]
fn a_figure_of_three_parts_keeps_each_at_its_resolution_and_meshes_closed() {
    let scene = scene("parts-figure.toml");
    assert_eq!(scene.parts.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(), ["plinth", "body", "head"]);
    let mut playback = Playback::new(&scene);
    playback.advance_to(1.0, |_| {});
    let parts = playback.assembly();
    assert_eq!(parts.others()[1].transform().voxel_size_m, 0.0005, "the head keeps its own voxel");
    let surface = playback.into_surface();
    // The head's world voxel (0.5 mm × 1.4) is the finest: the composition's; the plinth's
    // 2 mm sits on a coarser level.
    assert!((surface.transform().voxel_size_m - 0.0007).abs() < 1e-7);
    assert!(surface.level_brick_count(1) > 0, "the plinth on a coarser level");
    for (what, at) in [
        ("plinth", Vec3::new(0.035, 0.007, 0.02)),
        ("body", Vec3::new(0.0, 0.04, 0.0)),
        ("head", Vec3::new(0.0, 0.078, 0.0)),
        (
            "head's nose, turned 30° and scaled 1.4",
            Quat::from_rotation_y(30f32.to_radians()) * Vec3::new(0.0, 0.0, 0.0126) + Vec3::Y * 0.078,
        ),
    ] {
        assert!(density(&surface, at) > 0.5, "{what} at {at}");
    }
    assert!(
        density(&surface, Vec3::new(0.0, 0.078, 0.0125)) < 0.5,
        "the head is not where its nose would be unturned"
    );
    let triangles = assert_closed_and_oriented(&surface, "figure");
    assert!(triangles > 10_000, "{triangles} triangles");
}

#[test]
fn a_tool_on_one_part_acts_in_its_frame_and_leaves_the_others() {
    let scene = scene("parts-figure.toml");
    let mut bare = scene.clone();
    bare.timeline = Timeline::new(Vec::new(), scene.timeline.step_s()).unwrap();
    let before = Playback::new(&bare);
    let mut after = Playback::new(&scene);
    after.advance_to(1.0, |_| {});
    assert!(after.field().same_samples(before.field()), "the plinth is untouched");
    assert!(
        after.assembly().others()[0].same_samples(&before.assembly().others()[0]),
        "the body is untouched"
    );
    let (head_before, head_after) = (&before.assembly().others()[1], &after.assembly().others()[1]);
    assert!(head_after.mass() > head_before.mass(), "the band is laid on the head");
    // At a key's world position, the band is clay of the head, in its frame.
    let placement = scene.parts[2].placement;
    let key = Vec3::new(0.0, 0.0815, 0.0118);
    let local = placement.local_point(key);
    let index = head_after.transform().world_to_index(local);
    assert!(FieldReader::new(head_after).density_at(index) > 0.5);
    assert!(FieldReader::new(head_before).density_at(index) < 0.5);
    // The tool's world size holds in the head's frame: a 2.5 mm ball is 2.5 / 1.4 mm there, so
    // the band's clay is about what a stroke of the same tool lays in the world.
    let added =
        (head_after.mass() - head_before.mass()) * f64::from(head_after.transform().voxel_size_m).powi(3);
    let world_added = added * f64::from(placement.scale).powi(3);
    assert!(world_added > 1e-7 && world_added < 1e-6, "{world_added} m³ of band");
}

#[test]
fn a_difference_part_drills_through_two_others_and_hidden_it_leaves_them_whole() {
    let scene = scene("parts-hole.toml");
    let surface = argile::app::final_field(&scene);
    let hole = Vec3::new(0.0, 0.045, 0.0);
    assert!(density(&surface, hole) < 0.5, "the hole through wall and pillar");
    assert!(density(&surface, hole + Vec3::Z * 0.017) < 0.5, "through the pillar's front");
    assert!(density(&surface, hole + Vec3::new(0.0, 0.012, 0.0)) > 0.5, "clay beside the hole");
    assert_closed_and_oriented(&surface, "drilled");
    let mut hidden = scene.clone();
    hidden.parts[2].visible = false;
    let whole = argile::app::final_field(&hidden);
    assert!(density(&whole, hole) > 0.5, "hidden, the drill cuts nothing");
}

#[test]
fn undo_takes_back_a_step_on_another_part_and_gives_the_sculpt_back_bit_for_bit() {
    let scene = scene("parts-figure.toml");
    let mut bare = scene.clone();
    bare.timeline = Timeline::new(Vec::new(), scene.timeline.step_s()).unwrap();
    let start = Playback::new(&bare).into_surface();
    let mut playback = Playback::new(&scene);
    playback.advance_to(1.0, |_| {});
    assert!(!playback.surface().same_samples(&start));
    assert!(playback.undo().unwrap(), "the band is one step");
    assert!(playback.surface().same_samples(&start), "undo gives the sculpt back");
    assert!(!playback.undo().unwrap(), "nothing more to undo");
    assert!(playback.redo());
    assert!(!playback.surface().same_samples(&start), "redo lays the band again");
}

fn ball_part(voxel_m: f32, radius_m: f32, at: Vec3) -> Field {
    let mut field = Field::new(voxel_m, 0.5);
    let solid = PlacedSolid {
        solid: Solid::Sphere { radius_m },
        pose: Pose { position_m: at, rotation: Quat::IDENTITY },
        scale: 1.0,
    };
    rasterize_solid(&mut field, &solid, CsgOp::Union, [0.7, 0.5, 0.3, 1.0]);
    field
}

fn box_part(voxel_m: f32, half_m: Vec3) -> Field {
    let mut field = Field::new(voxel_m, 0.5);
    let solid = PlacedSolid { solid: Solid::Box { half_m }, pose: Pose::default(), scale: 1.0 };
    rasterize_solid(&mut field, &solid, CsgOp::Union, [0.3, 0.5, 0.7, 1.0]);
    field
}

prop_compose! {
    fn a_part()(
        ball in any::<bool>(),
        size in 0.004f32..0.012,
        voxel in prop::sample::select(vec![0.001f32, 0.0015, 0.002]),
        at in prop::array::uniform3(-0.008f32..0.008),
        turn in prop::array::uniform3(-3.2f32..3.2),
        scale in 0.6f32..1.8,
        op in prop::sample::select(Csg::ALL.to_vec()),
    ) -> (Field, Placement, Csg) {
        let field = if ball { ball_part(voxel, size, Vec3::ZERO) } else { box_part(voxel, Vec3::new(size, 0.7 * size, 0.5 * size)) };
        let rotation = Quat::from_rotation_x(turn[0]) * Quat::from_rotation_y(turn[1]) * Quat::from_rotation_z(turn[2]);
        (field, Placement::new(rotation, Vec3::from(at), scale).unwrap(), op)
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]
    /// Any parts, placed anywhere, at any scale and resolution, composed by any operators:
    /// the surface is closed and consistently oriented, and every sample is a density.
    #[test]
    fn any_composition_meshes_closed_and_consistently_oriented(parts in prop::collection::vec(a_part(), 1..4)) {
        let views: Vec<PartView<'_>> = parts
            .iter()
            .enumerate()
            .map(|(i, (field, placement, op))| PartView {
                field,
                placement: *placement,
                op: if i == 0 { Csg::Union } else { *op },
                visible: true,
            })
            .collect();
        let composition = Composition::build(&views);
        for (_, brick) in composition.field().shared_bricks() {
            prop_assert!(brick.densities().all(|d| d.is_finite() && (0.0..=1.0).contains(&d)));
        }
        assert_closed_and_oriented(composition.field(), "composition");
    }
}

fn refused(toml: &str) -> String {
    match Scene::parse(toml, "bad.toml", None) {
        Ok(_) => panic!("accepted:\n{toml}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_parts_are_refused_at_their_line_with_what_is_wrong() {
    let part = |extra: &str| format!("[[part]]\nname = \"a\"\n\n[[part]]\nname = \"b\"\n{extra}\n");
    for (toml, says) in [
        (part("scale = 0.0"), "scale 0 is not a positive finite number"),
        (part("scale = -2.0"), "scale -2 is not a positive finite number"),
        (part("op = \"xor\""), "op must be \"union\", \"difference\" or \"intersection\""),
        (part("voxel_size_m = 0.5"), "voxel_size_m must be between"),
        (part("scale = 0.001"), "in the world, outside"),
        ("[[part]]\nname = \"a\"\n[[part]]\nname = \"a\"\n".to_owned(), "given to two parts"),
        ("[[part]]\nname = \"\"\n".to_owned(), "name must be 1 to"),
        (
            "[[part]]\nname = \"a\"\nscale = 2.0\n[[tool]]\nname = \"p\"\nshape = \"sphere\"\nradius_m = 0.01\naction = \"push\"\n".to_owned(),
            "a push or support tool acts on the first part (\"a\") in world coordinates",
        ),
        (
            format!("{}[[region]]\ntime_s = 0.0\nop = \"inflate\"\npart = \"c\"\ncentre_m = [0.0, 0.0, 0.0]\nradius_m = 0.01\ndistance_m = 0.001\n", part("")),
            "no part named \"c\" (parts: a, b)",
        ),
        (
            format!("{}[[region]]\ntime_s = 0.0\nop = \"inflate\"\npart = \"b\"\ncentre_m = [0.0, 0.0, 0.0]\nradius_m = 0.01\ndistance_m = 0.001\n", part("locked = true")),
            "[[region]] part \"b\" is locked: no region tool acts on it",
        ),
        (
            format!("{}[[clay]]\npart = \"c\"\nshape = \"sphere\"\nradius_m = 0.01\n", part("")),
            "no part named \"c\" (parts: a, b)",
        ),
        (
            format!("{}[[lattice]]\nname = \"l\"\npart = \"c\"\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [0.01, 0.01, 0.01]\n", part("")),
            "no part named \"c\" (parts: a, b)",
        ),
        (
            format!(
                "{}[[lattice]]\nname = \"l\"\npart = \"b\"\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [0.01, 0.01, 0.01]\n",
                part("locked = true")
            ),
            "lattice `l`: part \"b\" is locked: no lattice acts on it",
        ),
        (
            format!(
                "{}[[tool]]\nname = \"t\"\nshape = \"sphere\"\nradius_m = 0.01\naction = \"add\"\n\n[[key]]\ntime_s = 0.0\ntool = \"t\"\npart = \"b\"\nposition_m = [0.0, 0.0, 0.0]\nactive = true\n",
                part("locked = true")
            ),
            "part \"b\" is locked",
        ),
    ] {
        let message = refused(&toml);
        assert!(message.contains(says), "{message}\n  should say: {says}");
        assert!(message.contains("bad.toml:"), "names the file and line: {message}");
    }
}

#[test]
fn a_sculpt_file_keeps_every_part_and_exports_and_renders_their_composition() {
    let dir = std::env::temp_dir().join(format!("argile-parts-file-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/parts-figure.toml");
    let out = dir.join("figure.argile");
    argile::app::save_scene_sculpt(&scene_path, &out, false, None).unwrap();
    let scene = scene("parts-figure.toml");
    let mut played = Playback::new(&scene);
    played.advance_to(1.0, |_| {});
    played.close_steps();
    let sculpt = argile::app::load_sculpt(&out).unwrap();
    assert_eq!(sculpt.parts.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(), ["plinth", "body", "head"]);
    assert_eq!(sculpt.parts[2].scale, 1.4);
    assert_eq!(sculpt.parts[1].op, "union");
    assert!(sculpt.field.same_samples(played.field()), "the first part");
    assert_eq!(sculpt.others.len(), 2);
    for (read, made) in sculpt.others.iter().zip(played.assembly().others()) {
        assert!(read.same_samples(made), "every other part, bit for bit");
        assert_eq!(read.transform(), made.transform(), "at its own voxel size");
    }
    // Opened, it is the same sculpt: its parts placed as they were, composed the same.
    let (opened_scene, opened) = argile::app::open_sculpt(&out).unwrap();
    assert_eq!(opened_scene.parts, scene.parts);
    let reopened = Playback::on_sculpt(&opened_scene, opened.field, opened.others, &[], |_, _| None);
    assert!(reopened.into_surface().same_samples(&played.into_surface()));
    // Exported, it is the scene's composition.
    let (from_scene, from_file) = (dir.join("scene.obj"), dir.join("file.obj"));
    let format = argile::mesh::export::ExportFormat::Obj;
    argile::app::export(&scene_path, format, &from_scene, false, false).unwrap();
    argile::app::export(&out, format, &from_file, false, false).unwrap();
    assert_eq!(std::fs::read(&from_scene).unwrap(), std::fs::read(&from_file).unwrap());
    // A format version without parts refuses it rather than dropping all but one.
    let old = argile::io::EncodeOptions { version: 4, history: true };
    let e = argile::app::convert_sculpt(&out, &dir.join("v4.argile"), old, false).unwrap_err().to_string();
    assert!(e.contains("is a sculpt of 3 parts; format version 4 stores one"), "{e}");
    // The lazy reader reads the parts whole with its head.
    let lazy = argile::io::LazySculpt::open(&out).unwrap().finish(&mut |_| {}).unwrap();
    assert_eq!(lazy.others.len(), 2);
    assert!(lazy.others[1].same_samples(&sculpt.others[1]));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn export_parts_separate_writes_a_glb_node_per_part_with_its_placement() {
    let dir = std::env::temp_dir().join(format!("argile-parts-export-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/parts-figure.toml");
    let out = dir.join("figure.glb");
    let format = argile::mesh::export::ExportFormat::Glb;
    let written =
        argile::app::export_as(&scene_path, format, argile::app::PartsExport::Separate, &out, false, false)
            .unwrap();
    let (document, buffers, _) = gltf::import(&out).unwrap();
    let nodes: Vec<_> = document.nodes().collect();
    assert_eq!(nodes.iter().map(|n| n.name().unwrap()).collect::<Vec<_>>(), ["plinth", "body", "head"]);
    let (t, r, s) = nodes[2].transform().decomposed();
    assert!((Vec3::from(t) - Vec3::new(0.0, 0.078, 0.0)).length() < 1e-6);
    assert!((Quat::from_array(r).dot(Quat::from_rotation_y(30f32.to_radians())).abs() - 1.0).abs() < 1e-6);
    assert!((s[0] - 1.4).abs() < 1e-6);
    // The head's mesh is in its own frame: a ball of 8 mm about its origin (with its nose).
    let head = nodes[2].mesh().unwrap().primitives().next().unwrap();
    let reader = head.reader(|b| Some(&buffers[b.index()]));
    let radius = reader.read_positions().unwrap().map(|p| Vec3::from(p).length()).fold(0.0f32, f32::max);
    assert!(radius > 0.0095 && radius < 0.0125, "{radius}");
    let triangles: usize = nodes
        .iter()
        .map(|n| n.mesh().unwrap().primitives().map(|p| p.indices().unwrap().count() / 3).sum::<usize>())
        .sum();
    assert_eq!(triangles, written.triangles);
    // OBJ: an object per part, placed in the world; PLY holds one mesh and is refused.
    let obj = dir.join("figure.obj");
    argile::app::export_as(
        &scene_path,
        argile::mesh::export::ExportFormat::Obj,
        argile::app::PartsExport::Separate,
        &obj,
        false,
        false,
    )
    .unwrap();
    let text = std::fs::read_to_string(&obj).unwrap();
    assert_eq!(
        text.lines().filter(|l| l.starts_with("o ")).collect::<Vec<_>>(),
        ["o plinth", "o body", "o head"]
    );
    let ply = argile::app::export_as(
        &scene_path,
        argile::mesh::export::ExportFormat::Ply,
        argile::app::PartsExport::Separate,
        &dir.join("x.ply"),
        false,
        false,
    );
    assert!(ply.unwrap_err().to_string().contains("a ply file holds one mesh"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A scene's lattice deforms the clay of the part it names, in that part's own frame: its box
/// and its keys are where the part's clay is written, turned, moved and scaled with the part;
/// the other part is left bit for bit.
#[test]
fn a_scene_lattice_deforms_the_part_it_names_in_that_part_s_frame() {
    let text = "[field]\nvoxel_size_m = 0.002\n\
        [[part]]\nname = \"base\"\n\
        [[part]]\nname = \"arm\"\nposition_m = [0.3, 0.0, 0.0]\nrotation_deg = [0.0, 90.0, 0.0]\nscale = 2.0\nvoxel_size_m = 0.001\n\
        [[clay]]\nshape = \"sphere\"\nradius_m = 0.03\n\
        [[clay]]\npart = \"arm\"\nshape = \"sphere\"\nradius_m = 0.015\n\
        [[lattice]]\nname = \"swell\"\npart = \"arm\"\nmin_m = [-0.025, -0.025, -0.025]\nmax_m = [0.025, 0.025, 0.025]\n\
        controls = [4, 4, 4]\napply_s = 1.0\n\
        [[lattice_key]]\ntime_s = 1.0\nlattice = \"swell\"\ni = [2, 3]\nvalue_offset = 0.5\n";
    let scene = Scene::parse(text, "arm-lattice.toml", None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.lattices[0].part, 1);
    let mut playback = Playback::new(&scene);
    let (base, arm) = (playback.field().clone(), playback.assembly().others()[0].clone());
    let placement = scene.parts[1].placement;
    // The arm's own +X (the side the raised controls are on) is the world's -Z, twice as far.
    let (plus, minus) =
        (placement.point(Vec3::new(0.018, 0.0, 0.0)), placement.point(Vec3::new(-0.018, 0.0, 0.0)));
    assert!((plus - Vec3::new(0.3, 0.0, -0.036)).length() < 1e-5, "{plus}");
    let composed = |p: &mut Playback<'_>| p.surface().clone();
    let before = composed(&mut playback);
    assert!(density(&before, plus) < 0.1 && density(&before, minus) < 0.1);
    playback.advance_to(1.5, |_| {});
    let after = composed(&mut playback);
    assert!(density(&after, plus) > 0.5, "the arm swells on its own +X: {}", density(&after, plus));
    assert!(density(&after, minus) < 0.1, "and not on its -X: {}", density(&after, minus));
    assert!(playback.field().same_samples(&base), "the base part is left as it was");
    let arm_now = &playback.assembly().others()[0];
    assert!(arm_now.mass() > arm.mass() * 1.02, "{} against {}", arm_now.mass(), arm.mass());
    assert_closed_and_oriented(&after, "the swelled arm with the base");
    // One undo step gives the arm back.
    assert!(playback.undo().unwrap());
    assert!(playback.assembly().others()[0].same_samples(&arm));
    assert!(!playback.undo().unwrap(), "the lattice was the one step");
}

/// A scene's region tool acts on the clay of the part it names, in that part's own frame: its
/// region and its motion are where the part's clay is written, turned, moved and scaled with
/// the part; the other part is left bit for bit, and one undo step gives the part back.
#[test]
fn a_scene_region_tool_moves_the_clay_of_the_part_it_names_in_that_part_s_frame() {
    let text = "[field]\nvoxel_size_m = 0.002\n\
        [[part]]\nname = \"base\"\n\
        [[part]]\nname = \"arm\"\nposition_m = [0.3, 0.0, 0.0]\nrotation_deg = [0.0, 90.0, 0.0]\nscale = 2.0\nvoxel_size_m = 0.001\n\
        [[clay]]\nshape = \"sphere\"\nradius_m = 0.03\n\
        [[clay]]\npart = \"arm\"\nshape = \"sphere\"\nradius_m = 0.01\n\
        [[region]]\ntime_s = 0.5\nduration_s = 0.5\nop = \"move\"\npart = \"arm\"\ncentre_m = [0.0, 0.0, 0.0]\nradius_m = 0.014\nmove_m = [0.02, 0.0, 0.0]\n";
    let scene = Scene::parse(text, "arm-region.toml", None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.regions[0].part, 1);
    let mut playback = Playback::new(&scene);
    let (base, arm) = (playback.field().clone(), playback.assembly().others()[0].clone());
    let placement = scene.parts[1].placement;
    // The arm's own +X is the world's -Z, twice as far: the ball goes 4 cm along world -Z.
    let (from, to) = (placement.point(Vec3::ZERO), placement.point(Vec3::new(0.02, 0.0, 0.0)));
    assert!((to - Vec3::new(0.3, 0.0, -0.04)).length() < 1e-5, "{to}");
    let before = playback.surface().clone();
    assert!(density(&before, from) > 0.5 && density(&before, to) < 0.1);
    playback.advance_to(1.5, |_| {});
    let after = playback.surface().clone();
    assert!(density(&after, to) > 0.5, "the arm's ball lands 4 cm along -Z: {}", density(&after, to));
    assert!(density(&after, from) < 0.1, "and leaves empty space: {}", density(&after, from));
    assert!(playback.field().same_samples(&base), "the base part is left as it was");
    let moved = playback.assembly().others()[0].mass();
    assert!((moved - arm.mass()).abs() < 0.01 * arm.mass(), "{moved} against {}", arm.mass());
    assert_closed_and_oriented(&after, "the moved arm with the base");
    // One undo step gives the arm back.
    assert!(playback.undo().unwrap());
    assert!(playback.assembly().others()[0].same_samples(&arm));
    assert!(!playback.undo().unwrap(), "the region tool was the one step");
}

/// A region copied into a new part (Hua and Qin's copy and compose into another patch): the
/// new part holds the clay within the region and becomes the active one, the part it came from
/// is left bit for bit, one undo takes the part away and one redo brings it back, and an
/// autosave session recovers the sculpt as each step left it.
#[test]
fn a_region_copied_into_a_new_part_is_one_undo_step_and_autosave_recovers_it() {
    use argile::io::autosave::{recover, Autosave, AutosaveConfig, LocalDisk};
    use argile::tool::{Action, Tool, ToolShape};
    let root = std::env::temp_dir().join(format!("argile-copy-to-part-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let text = "[field]\nvoxel_size_m = 0.002\n[[clay]]\nshape = \"sphere\"\nradius_m = 0.03\n";
    let scene = Scene::parse(text, "copy-to-part.toml", None).unwrap_or_else(|e| panic!("{e}"));
    let config =
        AutosaveConfig { sync_interval: std::time::Duration::from_millis(5), ..AutosaveConfig::default() };
    let mut playback = Playback::new_autosaved(&scene, |field, besides| {
        Autosave::start_with_tools(
            &root,
            field,
            (Some(text), besides),
            "test",
            config,
            std::sync::Arc::new(LocalDisk),
        )
        .ok()
    })
    .unwrap();
    let ball = playback.field().clone();
    // A tool of 1 cm radius at the ball's top.
    let tool = Tool::new(ToolShape::sphere(0.01), Action::Add, [1.0; 4]);
    let top = Pose { position_m: Vec3::new(0.0, 0.03, 0.0), rotation: Quat::IDENTITY };
    let part = playback.copy_to_new_part(tool.clone(), top).unwrap();
    assert_eq!((part, playback.assembly().parts().len(), playback.assembly().active()), (1, 2, 1));
    assert_eq!(playback.assembly().parts()[1].name, "clay copy");
    assert!(playback.field().same_samples(&ball), "the ball is left as it was");
    let copy = playback.assembly().others()[0].clone();
    assert!(density(&copy, Vec3::new(0.0, 0.025, 0.0)) > 0.9, "the copy holds the clay within the tool");
    assert!(density(&copy, Vec3::new(0.0, -0.02, 0.0)) < 0.01, "and nothing of the rest");
    assert!(copy.mass() > 0.0 && copy.mass() < 0.3 * ball.mass(), "{} of {}", copy.mass(), ball.mass());
    assert_closed_and_oriented(&playback.surface().clone(), "the ball with its copied cap");
    // A second copy is named apart; away from the clay, nothing is copied and no part added.
    let away = Pose { position_m: Vec3::new(0.5, 0.0, 0.0), ..top };
    let e = playback.copy_to_new_part(tool.clone(), away).unwrap_err();
    assert!(e.contains("no clay within the region"), "{e}");
    assert_eq!(playback.assembly().parts().len(), 2);
    let recovered_now = |playback: &Playback<'_>| {
        let dir = playback.autosave().unwrap().dir().to_owned();
        let strokes = playback.autosave().unwrap().strokes();
        let start = std::time::Instant::now();
        while playback.autosave().unwrap().durable_strokes() < strokes {
            assert!(start.elapsed().as_secs() < 20, "the journal syncs");
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        recover(&dir).unwrap().sculpt
    };
    let r = recovered_now(&playback);
    assert_eq!(r.parts.len(), 2, "the snapshot lists the new part");
    assert!(r.field.same_samples(&ball) && r.others[0].same_samples(&copy), "recovered as it stands");
    // Undo takes the part away, redo brings it back.
    assert!(playback.undo().unwrap());
    assert_eq!(playback.assembly().parts().len(), 1);
    assert_eq!(playback.assembly().active(), 0);
    assert!(playback.field().same_samples(&ball));
    let r = recovered_now(&playback);
    assert!(r.parts.len() <= 1 && r.others.is_empty(), "recovered without it: {} parts", r.parts.len());
    assert!(r.field.same_samples(&ball));
    assert!(playback.redo());
    assert_eq!(playback.assembly().parts().len(), 2);
    assert!(playback.assembly().others()[0].same_samples(&copy), "brought back bit for bit");
    playback.journal();
    let r = recovered_now(&playback);
    assert_eq!(r.parts.len(), 2);
    assert!(r.others[0].same_samples(&copy), "and recovered with it");
    assert!(playback.undo().unwrap());
    assert!(!playback.undo().unwrap(), "the copy was the one step");
    drop(playback);
    std::fs::remove_dir_all(&root).unwrap();
}

/// A scene's `copy-to-part` region tool makes a part of the clay within its region at its
/// time, named as the entry says; bad entries are refused at their line.
#[test]
fn a_scene_copy_to_part_makes_a_named_part_of_the_region_and_bad_ones_are_refused() {
    let head = "[field]\nvoxel_size_m = 0.002\n[[clay]]\nshape = \"sphere\"\nradius_m = 0.03\n";
    let entry = |extra: &str| {
        format!("{head}[[region]]\ntime_s = 0.5\nop = \"copy-to-part\"\ncentre_m = [0.0, 0.03, 0.0]\nradius_m = 0.01\n{extra}")
    };
    let text = entry("name = \"cap\"\n");
    let scene = Scene::parse(&text, "cap.toml", None).unwrap_or_else(|e| panic!("{e}"));
    let mut playback = Playback::new(&scene);
    let ball = playback.field().clone();
    playback.advance_to(0.4, |_| {});
    assert_eq!(playback.assembly().parts().len(), 1, "not before its time");
    playback.advance_to(1.0, |_| {});
    let parts = playback.assembly().parts();
    assert_eq!((parts.len(), parts[1].name.as_str()), (2, "cap"));
    let cap = &playback.assembly().others()[0];
    assert!(density(cap, Vec3::new(0.0, 0.025, 0.0)) > 0.9 && density(cap, Vec3::ZERO) < 0.01);
    assert!(playback.field().same_samples(&ball));
    assert!(playback.undo().unwrap());
    assert_eq!(playback.assembly().parts().len(), 1, "one undo step takes it away");
    for (extra, says) in [
        ("name = \"clay\"\n", "name must be 1 to 64 characters and no [[part]]'s"),
        ("move_m = [0.01, 0.0, 0.0]\n", "copy-to-part takes no move_m"),
        ("distance_m = 0.001\n", "distance_m is for inflate and deflate"),
    ] {
        let e = Scene::parse(&entry(extra), "bad.toml", None).unwrap_err().to_string();
        assert!(e.contains(says) && e.contains("bad.toml:6:1"), "{extra}: {e}");
    }
    let moving = format!(
        "{head}[[region]]\ntime_s = 0.5\nop = \"move\"\nname = \"x\"\ncentre_m = [0.0, 0.0, 0.0]\nradius_m = 0.01\nmove_m = [0.01, 0.0, 0.0]\n"
    );
    let e = Scene::parse(&moving, "bad.toml", None).unwrap_err().to_string();
    assert!(e.contains("name is for copy-to-part"), "{e}");
}
