use super::*;

fn err(text: &str) -> (usize, usize, String) {
    match Scene::parse(text, "t.toml", None) {
        Err(SceneError::Invalid { line, column, message, path }) => {
            assert_eq!(path, "t.toml");
            (line, column, message)
        }
        other => panic!("expected an error, got {other:?}"),
    }
}

/// Checks each case `(text, "file:line:column", words)`: `parse` refuses the text with an
/// error that starts with that place and contains the words.
pub(super) fn assert_refused<T: std::fmt::Debug>(
    cases: &[(&str, &str, &str)],
    parse: impl Fn(&str) -> Result<T, SceneError>,
) {
    for &(text, place, words) in cases {
        let e = parse(text).unwrap_err().to_string();
        assert!(e.starts_with(place) && e.contains(words), "{text:?}: {e}");
    }
}

#[test]
fn the_default_scene_is_valid() {
    let s = Scene::default_scene();
    assert_eq!(s.clay.len(), 4);
    assert_eq!(s.tools.len(), 2);
    assert_eq!(s.captures.len(), 1);
    assert_eq!(s.output.samples, 4);
    assert!(s.timeline.duration_s() > 2.0);
}

#[test]
fn an_empty_file_is_a_scene_with_defaults() {
    let s = Scene::parse("", "empty.toml", None).unwrap();
    assert!(s.clay.is_empty());
    assert_eq!(s.captures[0].name, "final");
    assert_eq!(s.environment.choice, EnvironmentChoice::Studio);
}

#[test]
fn unknown_keys_are_refused_with_line_and_column() {
    let (line, column, message) = err("[camera]\nfov_y_deg = 30.0\nfov = 3\n");
    assert_eq!((line, column), (3, 1));
    assert!(message.contains("unknown field `fov`"), "{message}");
}

#[test]
fn syntax_errors_name_the_line() {
    let (line, _, _) = err("[field]\nvoxel_size_m = 0.002\n[[clay]\n");
    assert_eq!(line, 3);
}

#[test]
fn shape_parameters_are_checked_against_the_shape() {
    let (line, _, message) = err("\n\n[[clay]]\nshape = \"sphere\"\nsize_m = [1.0, 1.0, 1.0]\n");
    assert_eq!(line, 3);
    assert!(message.contains("`size_m` does not apply"), "{message}");
    let (_, _, message) = err("[[clay]]\nshape = \"torus\"\nmajor_radius_m = 0.1\n");
    assert!(message.contains("needs `minor_radius_m`"), "{message}");
    let (_, _, message) = err("[[clay]]\nshape = \"sphere\"\nradius_m = -1.0\n");
    assert!(message.contains("positive"), "{message}");
    let (_, _, message) = err("[[clay]]\nshape = \"pyramid\"\n");
    assert!(message.contains("unknown variant `pyramid`"), "{message}");
}

#[test]
fn keys_must_name_a_defined_tool() {
    let text = "[[tool]]\nname = \"a\"\nradius_m = 0.01\naction = \"add\"\n\n[[key]]\ntime_s = 0.0\ntool = \"b\"\nposition_m = [0.0, 0.0, 0.0]\n";
    let (line, _, message) = err(text);
    assert_eq!(line, 6);
    assert!(message.contains("no tool named `b`") && message.contains("tools: a"), "{message}");
}

#[test]
fn colours_accept_hex_and_linear_triples_only() {
    let s =
        Scene::parse("[[clay]]\nshape = \"sphere\"\nradius_m = 0.1\ncolour = [0.5, 0.25, 1.0]\n", "c", None)
            .unwrap();
    assert_eq!(s.clay[0].colour, [0.5, 0.25, 1.0, 1.0]);
    let (_, _, message) = err("[[clay]]\nshape = \"sphere\"\nradius_m = 0.1\ncolour = \"red\"\n");
    assert!(message.contains("#rrggbb"), "{message}");
    let (_, _, message) = err("[[clay]]\nshape = \"sphere\"\nradius_m = 0.1\ncolour = [2.0, 0.0, 0.0]\n");
    assert!(message.contains("0..1"), "{message}");
}

#[test]
fn image_environments_resolve_against_the_scene_folder() {
    let s =
        Scene::parse("[environment]\nkind = \"image\"\npath = \"sky.hdr\"\n", "s", Some(Path::new("scenes")))
            .unwrap();
    assert_eq!(s.environment.choice, EnvironmentChoice::Image(PathBuf::from("scenes/sky.hdr")));
    let (_, _, message) = err("[environment]\nkind = \"image\"\n");
    assert!(message.contains("needs `path`"), "{message}");
}

#[test]
fn a_missing_file_is_named() {
    let e = Scene::load(Path::new("no/such/scene.toml")).unwrap_err();
    assert!(e.to_string().starts_with("cannot read scene file no/such/scene.toml"), "{e}");
}

#[test]
fn captures_are_sorted_and_names_checked() {
    let s = Scene::parse(
        "[[capture]]\nname = \"b\"\ntime_s = 2.0\n[[capture]]\nname = \"a\"\ntime_s = 1.0\n",
        "c",
        None,
    )
    .unwrap();
    assert_eq!(s.captures.iter().map(|c| c.name.as_str()).collect::<Vec<_>>(), ["a", "b"]);
    let (_, _, message) = err("[[capture]]\nname = \"../x\"\ntime_s = 1.0\n");
    assert!(message.contains("letters, digits"), "{message}");
}

const TOOL: &str = "[[tool]]\nname = \"t\"\n";

#[test]
fn every_tool_scene_of_the_tests_folder_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/tests");
    let mut actions = std::collections::HashSet::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        for t in &scene.tools {
            actions.insert(std::mem::discriminant(&t.action));
        }
    }
    assert_eq!(actions.len(), 12, "a scene for each of the twelve actions (push and support included)");
}

#[test]
fn tool_shapes_and_actions_take_their_parameters() {
    let s = Scene::parse(
        &format!("{TOOL}shape = \"ellipsoid\"\nradii_m = [0.01, 0.02, 0.03]\nfalloff = \"box\"\nscale = [1.0, 2.0, 1.0]\naction = \"heat_gun\"\nrate_per_s = 2.5\n"),
        "t",
        None,
    )
    .unwrap();
    let t = &s.tools[0];
    assert_eq!(t.action, Action::SoftRemove { rate_per_s: 2.5 });
    assert_eq!(t.half_extents_m(), Vec3::new(0.01, 0.04, 0.03));
    let s =
        Scene::parse(&format!("{TOOL}radius_m = 0.01\naction = \"stamp\"\nn = 0.4\n"), "t", None).unwrap();
    let Action::Stamp { deformation, falloff_m } = s.tools[0].action else { panic!("a stamp") };
    assert_eq!(deformation.parameters().4, 0.4);
    assert_eq!(falloff_m, 0.01);
    let s = Scene::parse(
        &format!("{TOOL}shape = \"freeform\"\nregion_min_m = [-0.1, -0.1, -0.1]\nregion_max_m = [0.1, 0.0, 0.1]\naction = \"add\"\n"),
        "t",
        None,
    )
    .unwrap();
    assert_eq!(
        s.tools[0].shape,
        SceneToolShape::Freeform { min_m: Vec3::splat(-0.1), max_m: Vec3::new(0.1, 0.0, 0.1) }
    );
}

#[test]
fn tool_errors_name_the_line_and_what_to_change() {
    let (line, column, message) =
        err(&format!("\n\n{TOOL}radius_m = 0.01\naction = \"stamp\"\ns = 0.5\nm = 0.4\nr = 0.3\n"));
    assert_eq!((line, column), (3, 1));
    assert!(message.contains("s + m + r = 1.2") && message.contains("value range"), "{message}");
    let (_, _, message) = err(&format!("{TOOL}radius_m = 0.01\naction = \"smooth\"\ncentre_weight = 30.0\n"));
    assert!(message.contains("between 4 and 24"), "{message}");
    let (_, _, message) = err(&format!("{TOOL}radius_m = 0.01\naction = \"paint\"\nrate_per_s = 1.0\n"));
    assert!(message.contains("`rate_per_s` does not apply to action paint"), "{message}");
    let (_, _, message) = err(&format!("{TOOL}shape = \"box\"\nradius_m = 0.01\naction = \"add\"\n"));
    assert!(message.contains("`radius_m` does not apply to a box tool; it takes size_m"), "{message}");
    let (_, _, message) = err(&format!("{TOOL}shape = \"torus\"\nmajor_radius_m = 0.01\naction = \"add\"\n"));
    assert!(message.contains("needs `minor_radius_m`"), "{message}");
    let (_, _, message) = err(&format!("{TOOL}radius_m = 0.01\nscale = [1.0, 0.0, 1.0]\naction = \"add\"\n"));
    assert!(message.contains("scale must be three factors more than 0"), "{message}");
    let (line, _, message) = err(&format!("{TOOL}radius_m = 0.01\naction = \"polish\"\n"));
    assert_eq!(line, 4);
    assert!(message.contains("unknown variant `polish`"), "{message}");
    let (_, _, message) = err(&format!("{TOOL}radius_m = 0.01\naction = \"add\"\nlevel_samples = 0.5\n"));
    assert!(
        message.contains("level_samples is the most voxels across the tool's size, 1 to 64"),
        "{message}"
    );
    let scene = Scene::parse(
        &format!("{TOOL}radius_m = 0.01\naction = \"add\"\nlevel_samples = 8\n"),
        "t.toml",
        None,
    )
    .unwrap();
    assert_eq!(scene.tools[0].level_samples, Some(8.0));
}

#[test]
fn the_display_table_names_a_mode_parity_and_fallback() {
    use crate::stereo::display::{DisplayMode, Parity};
    let s = Scene::parse("", "t.toml", None).unwrap();
    assert_eq!(s.display, DisplaySettings::default());
    assert_eq!(s.display.mode, None);
    assert_eq!(s.display.fallback, Some(DisplayMode::Anaglyph));
    let s = Scene::parse(
        "[display]\nmode = \"row-interlaced\"\nparity = \"left-odd\"\nfallback = \"side-by-side-half\"\n",
        "t.toml",
        None,
    )
    .unwrap();
    assert_eq!(s.display.mode, Some(DisplayMode::RowInterlaced));
    assert_eq!(s.display.parity, Parity::LeftOdd);
    assert_eq!(s.display.fallback, Some(DisplayMode::SideBySideHalf));
    assert_eq!(
        Scene::parse("[display]\nfallback = \"none\"\n", "t.toml", None).unwrap().display.fallback,
        None
    );

    let (line, _, message) = err("[display]\n\nmode = \"3d\"\n");
    assert_eq!(line, 3);
    assert!(
        message.contains("`3d` is not a display mode")
            && message.contains("anaglyph-amber-blue, frame-sequential, mono"),
        "{message}"
    );
    let s = Scene::parse("[display]\nfullscreen = true\nmonitor = \"DP-2\"\n", "t.toml", None).unwrap();
    assert!(s.display.fullscreen);
    assert_eq!(s.display.monitor.map(|m| m.to_string()), Some("DP-2".to_owned()));
    let (line, _, message) = err(&format!("[display]\nmonitor = \"{}\"\n", "x".repeat(49)));
    assert_eq!(line, 2);
    assert!(message.contains("1 to 48 bytes"), "{message}");
    let (line, _, message) = err("[display]\nparity = \"even\"\n");
    assert_eq!(line, 2);
    assert!(message.contains("left-even"), "{message}");
    let (line, _, message) = err("[display]\nmode = \"quad-buffer\"\nfallback = \"quad-buffer\"\n");
    assert_eq!(line, 3);
    assert!(message.contains("fallback cannot be quad-buffer"), "{message}");
    let (_, _, message) = err("[display]\nfallback = \"stereo\"\n");
    assert!(message.contains("`stereo` is not a display mode") && message.contains("or none"), "{message}");
}

#[test]
fn the_input_table_names_a_settings_file_beside_the_scene() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("calibration");
    let s = Scene::parse("[input]\nsettings = \"input.toml\"\n", "t.toml", Some(&dir)).unwrap();
    assert_eq!(s.input_settings, Some(dir.join("input.toml")));
    assert_eq!(Scene::parse("", "t.toml", None).unwrap().input_settings, None);
    let (line, column, message) = err("[input]\nsettings = \"no-such-input.toml\"\n");
    assert_eq!((line, column), (2, 12));
    assert!(message.contains("there is no file") && message.contains("no-such-input.toml"), "{message}");
    let (line, _, message) = err("[input]\nsetings = \"input.toml\"\n");
    assert_eq!(line, 2);
    assert!(message.contains("setings"), "{message}");
}

#[test]
fn nan_and_infinities_are_refused_where_they_are_written_in_every_table() {
    for (text, key, line) in [
        ("[camera]\nup = [0.0, nan, 0.0]\n", "camera.up[1]", 2),
        ("[environment]\nintensity = inf\n", "environment.intensity", 2),
        (
            "[[clay]]\nshape = \"sphere\"\nradius_m = 0.05\nrotation_deg = [0.0, -inf, 0.0]\n",
            "clay[1].rotation_deg[1]",
            4,
        ),
        (
            "[[tool]]\nname = \"t\"\nradius_m = 0.01\naction = \"add\"\nglyph_opacity = nan\n",
            "tool[1].glyph_opacity",
            5,
        ),
        ("[material]\nspecular = 1e39\n", "material.specular", 2),
    ] {
        let (l, _, message) = err(text);
        assert_eq!(l, line, "{message}");
        assert_eq!(message, format!("`{key}` must be a finite number"));
    }
}

#[test]
fn timelines_that_would_never_end_and_keys_out_of_reach_are_refused_at_their_line() {
    let tool = "[[tool]]\nname = \"t\"\nradius_m = 0.01\naction = \"add\"\n";
    // A step too short for any work to end, at the key's own line.
    let (line, _, message) = err(&format!("{tool}[timeline]\nstep_s = 1e-12\n"));
    assert_eq!(line, 6, "{message}");
    assert!(message.contains("step_s must be 0.0001 to 1 seconds"), "{message}");
    // A key far in time, or at a position or rotation that is no number.
    let key = |time: &str, position: &str, rotation: &str| {
        format!(
            "{tool}[[key]]\ntime_s = {time}\ntool = \"t\"\nposition_m = {position}\nrotation_deg = {rotation}\n"
        )
    };
    // Out of range: at the key's table; no number at all: at the value itself.
    for (text, expected, at) in [
        (key("1e12", "[0.0, 0.0, 0.0]", "[0.0, 0.0, 0.0]"), "time_s must be 0 to 86400 s", (5, 1)),
        (key("1.0", "[1e30, 0.0, 0.0]", "[0.0, 0.0, 0.0]"), "position_m must be within ±100 m", (5, 1)),
        (
            key("1.0", "[nan, 0.0, 0.0]", "[0.0, 0.0, 0.0]"),
            "`key[1].position_m[0]` must be a finite number",
            (8, 15),
        ),
        (
            key("1.0", "[0.0, 0.0, 0.0]", "[0.0, inf, 0.0]"),
            "`key[1].rotation_deg[1]` must be a finite number",
            (9, 22),
        ),
    ] {
        let (line, column, message) = err(&text);
        assert_eq!((line, column), at, "{message}");
        assert!(message.contains(expected), "{message}");
    }
    // A capture late enough that the f32 time would stop advancing (262,144 s at the default
    // step) is over the step count.
    let (_, _, message) = err(&format!("{tool}[[capture]]\nname = \"late\"\ntime_s = 80000.0\n"));
    assert!(
        message.contains("over 1048576 steps") && message.contains("lengthen [timeline] step_s"),
        "{message}"
    );
    // Within bounds, the same scene loads.
    Scene::parse(&format!("{tool}[[capture]]\nname = \"late\"\ntime_s = 10000.0\n"), "t.toml", None).unwrap();
}

#[test]
fn a_calibration_with_nan_is_refused_at_the_value() {
    let e = ScreenCalibration::parse("[screen]\nwidth_m = nan\n", "s.toml").unwrap_err().to_string();
    assert_eq!(e, "s.toml:2:11: `screen.width_m` must be a finite number");
}

#[test]
fn what_a_file_says_is_quoted_cut_and_escaped() {
    let long = "x".repeat(10_000);
    let (_, _, message) =
        err(&format!("[[key]]\ntime_s = 0.0\ntool = \"{long}\"\nposition_m = [0.0, 0.0, 0.0]\n"));
    assert!(message.chars().count() < MESSAGE_LIMIT + 40, "{} characters", message.len());
    assert!(message.contains("more characters)"), "{message}");
    let (_, _, message) = err("[[key]]\ntime_s = 0.0\ntool = \"\\u001b[2J\"\nposition_m = [0.0, 0.0, 0.0]\n");
    assert!(!message.contains('\u{1b}') && message.contains("\\u{1b}[2J"), "{message:?}");
}

#[test]
fn lengths_scales_and_freeform_regions_that_would_run_away_are_refused() {
    let clay = |extra: &str| format!("[[clay]]\nshape = \"sphere\"\nradius_m = 0.05\n{extra}");
    let (line, _, message) = err("[[clay]]\nshape = \"sphere\"\nradius_m = 1e6\n");
    assert_eq!(line, 1);
    assert!(
        message.contains("radius_m must be a positive number of metres up to 10, not 1000000"),
        "{message}"
    );
    let (_, _, message) = err(&clay("scale = 1e9\n"));
    assert!(message.contains("scale must be a factor more than 0 and at most 10"), "{message}");
    let tool = |extra: &str| format!("[[tool]]\nname = \"t\"\naction = \"add\"\n{extra}");
    let (_, _, message) = err(&tool("radius_m = 0.01\nscale = [1e9, 1.0, 1.0]\n"));
    assert!(message.contains("scale must be three factors"), "{message}");
    let (_, _, message) = err(&tool("shape = \"freeform\"\nregion_min_m = [-100.0, -100.0, -100.0]\nregion_max_m = [100.0, 100.0, 100.0]\n"));
    assert!(
        message.contains("the freeform region spans") && message.contains("choose a smaller region"),
        "{message}"
    );
    let (_, _, message) =
        err("[[tool]]\nname = \"s\"\naction = \"stamp\"\nradius_m = 0.01\nfalloff_m = 1e9\n");
    assert!(message.contains("falloff_m must be a positive number of metres up to 10"), "{message}");
    // A region of 10 cm at the default voxel copies 1e6 samples: fine.
    let text = tool(
        "shape = \"freeform\"\nregion_min_m = [-0.05, -0.05, -0.05]\nregion_max_m = [0.05, 0.05, 0.05]\n",
    );
    Scene::parse(&format!("{}{text}", clay("")), "t.toml", None).unwrap();
}

const LATTICE: &str = "[[lattice]]\nname = \"l\"\nmin_m = [-0.1, -0.05, -0.05]\nmax_m = [0.1, 0.05, 0.05]\n\
                       controls = [6, 4, 4]\n";

#[test]
fn lattices_and_their_keys_are_read_in_time_order_each_ramping_from_the_one_before() {
    let text = format!(
        "{LATTICE}open_s = 0.5\n\
         [[lattice_key]]\ntime_s = 2.0\nlattice = \"l\"\ni = [5, 5]\nrotation_deg = [90, 0, 0]\n\
         [[lattice_key]]\ntime_s = 1.0\nlattice = \"l\"\ni = [2, 3]\nj = [1, 2]\nvalue_offset = 0.2\n"
    );
    let s = Scene::parse(&text, "t.toml", None).unwrap();
    let l = &s.lattices[0];
    assert_eq!((l.open_s, l.apply_s, l.show), (0.5, 2.0, true));
    assert_eq!(l.spec.counts, [6, 4, 4]);
    assert_eq!(l.spec.kind, crate::spline::SplineKind::BSpline);
    let times: Vec<(f32, f32)> = l.edits.iter().map(|e| (e.from_s, e.time_s)).collect();
    assert_eq!(times, [(0.5, 1.0), (1.0, 2.0)]);
    assert_eq!(l.edits[0].edit.select.ranges, [(2, 3), (1, 2), (0, 3)]);
    // The default capture comes when the lattice is applied.
    assert_eq!(s.captures[0].time_s, 2.0);
}

#[test]
fn bad_lattices_and_keys_are_refused_where_they_are() {
    let key = |body: &str| format!("{LATTICE}[[lattice_key]]\ntime_s = 1.0\nlattice = \"l\"\n{body}");
    let cases = [
        (format!("{LATTICE}order = 1\n"), "t.toml:1:1", "order must be 2 to 16"),
        (LATTICE.replace("[6, 4, 4]", "[6, 1, 4]"), "t.toml:1:1", "2 to 16 control points"),
        (LATTICE.replace("max_m = [0.1,", "max_m = [-0.2,"), "t.toml:1:1", "must exceed min_m"),
        (
            format!("{}kind = \"bezier\"\n", LATTICE.replace("[6, 4, 4]", "[17, 4, 4]")),
            "t.toml:1:1",
            "2 to 16",
        ),
        (LATTICE.replace("[0.1, 0.05, 0.05]", "[3.0, 3.0, 3.0]"), "t.toml:1:1", "over the limit"),
        (key("i = [2, 6]\n"), "t.toml:6:1", "index ranges within"),
        (key("weight = 2.0\n"), "t.toml:6:1", "NURBS lattices"),
        (key("value_offset = 3.0\n"), "t.toml:6:1", "-1 to 1"),
        (key("offset_m = [4.0, 0.0, 0.0]\n"), "t.toml:1:1", "over the limit"),
        (
            format!("{LATTICE}apply_s = 0.5\n[[lattice_key]]\ntime_s = 1.0\nlattice = \"l\"\n"),
            "t.toml:1:1",
            "apply_s",
        ),
        (
            format!("{LATTICE}[[lattice_key]]\ntime_s = 1.0\nlattice = \"m\"\n"),
            "t.toml:6:1",
            "no lattice named `m`",
        ),
        (format!("{LATTICE}{LATTICE}"), "t.toml:6:1", "distinct"),
    ];
    for (text, place, words) in &cases {
        let e = Scene::parse(text, "t.toml", None).unwrap_err().to_string();
        assert!(e.starts_with(place) && e.contains(words), "{text:?}: {e}");
    }
}

#[test]
fn symmetry_is_read_with_its_frame_and_bad_symmetries_are_refused() {
    assert!(Scene::parse("", "t.toml", None).unwrap().symmetry.is_none());
    let text = "[symmetry]\nmirror = [\"x\", \"Z\"]\nradial = 3\naxis = \"y\"\ncentre_m = [0.1, 0.0, 0.0]\n";
    let s = Scene::parse(text, "t.toml", None).unwrap().symmetry;
    assert_eq!(s.mirror, [true, false, true]);
    assert_eq!((s.radial, s.axis), (3, crate::parts::Axis::Y));
    assert_eq!(s.frame.position_m, Vec3::new(0.1, 0.0, 0.0));
    assert_eq!(s.images().len(), 12);
    let cases = [
        ("[symmetry]\nmirror = [\"w\"]\n", "not \"w\""),
        ("[symmetry]\nmirror = [\"x\", \"x\"]\n", "twice"),
        ("[symmetry]\nradial = 0\n", "1 to 64"),
        ("[symmetry]\nradial = 65\n", "1 to 64"),
        ("[symmetry]\naxis = \"up\"\n", "axis must be"),
        ("[symmetry]\ncentre_m = [0.0, 200.0, 0.0]\n", "within ±100 m"),
        ("[symmetry]\nplanes = 2\n", "unknown field"),
    ];
    for (text, words) in cases {
        let e = Scene::parse(text, "t.toml", None).unwrap_err().to_string();
        assert!(e.starts_with("t.toml:") && e.contains(words), "{text:?}: {e}");
    }
}

#[test]
fn regions_are_read_in_time_order_and_bad_ones_are_refused_where_they_are() {
    let text = "[[region]]\ntime_s = 2.0\nop = \"inflate\"\ncentre_m = [0.0, 0.0, 0.0]\nradius_m = 0.02\ndistance_m = 0.002\n\
                [[region]]\ntime_s = 1.0\nop = \"copy\"\ncentre_m = [0.0, 0.0, 0.0]\nhalf_m = [0.01, 0.01, 0.01]\nmove_m = [0.03, 0.0, 0.0]\ncount = 3\n";
    let s = Scene::parse(text, "t.toml", None).unwrap();
    assert_eq!(s.regions.len(), 2);
    assert_eq!(s.regions[0].action, crate::scene::RegionAction::Drag(crate::parts::RegionOp::Copy));
    assert_eq!(s.regions[0].count, 3);
    assert_eq!(s.regions[1].action, crate::scene::RegionAction::Inflate(0.002));
    let head = "[[region]]\ntime_s = 1.0\ncentre_m = [0.0, 0.0, 0.0]\n";
    let cases = [
        ("op = \"twist\"\nhalf_m = [0.01, 0.01, 0.01]\n", "not \"twist\""),
        ("op = \"move\"\nhalf_m = [0.01, 0.01, 0.01]\n", "needs move_m or turn_deg"),
        ("op = \"move\"\nmove_m = [0.01, 0.0, 0.0]\n", "either half_m"),
        ("op = \"move\"\nhalf_m = [0.01, 0.0, 0.01]\nmove_m = [0.01, 0.0, 0.0]\n", "positive lengths"),
        ("op = \"inflate\"\nradius_m = 0.01\n", "needs distance_m"),
        ("op = \"deflate\"\nradius_m = 0.01\ndistance_m = 0.5\n", "at most 0.1"),
        (
            "op = \"inflate\"\nradius_m = 0.01\ndistance_m = 0.001\nmove_m = [0.01, 0.0, 0.0]\n",
            "takes no move_m",
        ),
        ("op = \"move\"\nradius_m = 0.01\nmove_m = [0.01, 0.0, 0.0]\ncount = 2\n", "count is for copy"),
        ("op = \"copy\"\nradius_m = 0.01\nmove_m = [0.01, 0.0, 0.0]\ncount = 0\n", "1 to 64"),
        ("op = \"move\"\nhalf_m = [1.0, 1.0, 1.0]\nmove_m = [0.01, 0.0, 0.0]\n", "may copy"),
        ("op = \"move\"\nradius_m = 0.01\nmove_m = [0.01, 0.0, 0.0]\nspin = 1\n", "unknown field"),
    ];
    for (body, words) in cases {
        let text = format!("{head}{body}");
        let e = Scene::parse(&text, "t.toml", None).unwrap_err().to_string();
        assert!(e.starts_with("t.toml:") && e.contains(words), "{body:?}: {e}");
    }
}
