//! Region tools on scene timelines: each is one undo step that gives the clay back bit for
//! bit, Hua–Qin's copy grid holds nine chairs' worth of clay, and the exported figure meshes
//! closed.

use std::path::Path;

use argile::app::Playback;
use argile::scene::{Scene, Timeline};

fn scene(name: &str) -> Scene {
    Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name))
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn each_region_tool_is_one_undo_step_and_undoing_all_gives_the_clay_back() {
    for (name, steps) in [("region-tools.toml", 4), ("region-grid.toml", 2)] {
        let scene = scene(name);
        let mut bare = scene.clone();
        bare.timeline = Timeline::new(Vec::new(), scene.timeline.step_s()).unwrap();
        bare.regions.clear();
        let start = Playback::new(&bare).into_field();
        let mut playback = Playback::new(&scene);
        playback.advance_to(scene.regions.iter().map(|r| r.end_s()).fold(0.0, f32::max) + 0.1, |_| {});
        let mut field = playback.into_field();
        assert!(!field.same_samples(&start), "{name}: the regions changed nothing");
        for i in 0..steps {
            assert!(field.undo().unwrap(), "{name}: undo step {i}");
        }
        assert!(field.same_samples(&start), "{name}: undo left a difference");
        assert!(!field.undo().unwrap(), "{name}: more undo steps than region tools");
        for _ in 0..steps {
            assert!(field.redo());
        }
        assert!(!field.same_samples(&start), "{name}: redo brings them back");
    }
}

#[test]
fn the_copy_grid_holds_nine_chairs_of_clay_and_meshes_closed() {
    let scene = scene("region-grid.toml");
    let mut one = scene.clone();
    one.regions.clear();
    let chair = Playback::new(&one).into_field().mass();
    let mut playback = Playback::new(&scene);
    playback.advance_to(1.0, |_| {});
    let field = playback.into_field();
    let ratio = field.mass() / chair;
    assert!((ratio - 9.0).abs() < 0.01, "{ratio} chairs of clay");
    let mesh = argile::app::welded_surface(&field);
    assert!(mesh.triangle_count() > 10_000);
    // Closed and consistently oriented: every directed edge once, and its reverse once.
    let mut edges = std::collections::HashMap::<(u32, u32), u32>::new();
    for t in mesh.indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1, "edge {a}-{b} used {n} times");
        assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no reverse: a hole");
    }
}
