//! The dependency rules of DESIGN.md, checked on the source: a module may not name what it
//! must not know. Fails with the file, line and the offending path.

use std::path::{Path, PathBuf};

/// Crate modules and external crates a module must not name.
const RULES: &[(&str, &[&str])] = &[
    ("math", &["crate::", "super::super", "ash", "openxr", "hidapi", "gilrs", "image"]),
    (
        "field",
        &[
            "crate::tool",
            "crate::mesh",
            "crate::render",
            "crate::xr",
            "crate::input",
            "crate::app",
            "crate::scene",
            "crate::stereo",
            "crate::clay",
            "ash",
            "openxr",
            "hidapi",
            "gilrs",
        ],
    ),
    (
        "tool",
        &[
            "crate::mesh",
            "crate::render",
            "crate::xr",
            "crate::input",
            "crate::app",
            "crate::scene",
            "crate::stereo",
            "ash",
            "openxr",
            "hidapi",
            "gilrs",
        ],
    ),
    (
        "mesh",
        &[
            "crate::tool",
            "crate::render",
            "crate::xr",
            "crate::input",
            "crate::app",
            "crate::scene",
            "crate::stereo",
            "ash",
            "openxr",
            "hidapi",
            "gilrs",
        ],
    ),
    (
        "clay",
        &[
            "crate::render",
            "crate::xr",
            "crate::input",
            "crate::app",
            "crate::mesh",
            "ash",
            "openxr",
            "hidapi",
            "gilrs",
        ],
    ),
    (
        "spline",
        &["crate::render", "crate::xr", "crate::input", "crate::app", "ash", "openxr", "hidapi", "gilrs"],
    ),
    (
        "lattice",
        &[
            "crate::render",
            "crate::xr",
            "crate::input",
            "crate::app",
            "crate::mesh",
            "crate::scene",
            "crate::clay",
            "ash",
            "openxr",
            "hidapi",
            "gilrs",
        ],
    ),
    (
        "parts",
        &[
            "crate::render",
            "crate::xr",
            "crate::input",
            "crate::app",
            "crate::scene",
            "ash",
            "openxr",
            "hidapi",
            "gilrs",
        ],
    ),
    (
        "render",
        &[
            "crate::field",
            "crate::tool",
            "crate::clay",
            "crate::input",
            "crate::xr",
            "crate::app",
            "crate::scene",
            "openxr",
            "hidapi",
            "gilrs",
        ],
    ),
    (
        "stereo",
        &[
            "crate::field",
            "crate::mesh",
            "crate::tool",
            "crate::xr",
            "crate::input",
            "crate::app",
            "ash",
            "openxr",
        ],
    ),
    (
        "scene",
        &[
            "crate::render",
            "crate::mesh",
            "crate::xr",
            "crate::input",
            "crate::app",
            "ash",
            "openxr",
            "hidapi",
            "gilrs",
        ],
    ),
    (
        "input",
        &["crate::field", "crate::mesh", "crate::render", "crate::clay", "crate::app", "ash", "openxr"],
    ),
    ("xr", &["crate::field", "crate::mesh", "crate::clay", "crate::tool", "crate::app"]),
    (
        "ui",
        &[
            "crate::field",
            "crate::tool",
            "crate::mesh",
            "crate::input",
            "crate::xr",
            "crate::app",
            "crate::io",
            "ash",
            "openxr",
            "hidapi",
            "gilrs",
            "winit",
        ],
    ),
    (
        "io",
        &[
            "crate::render",
            "crate::xr",
            "crate::input",
            "crate::app",
            "crate::mesh",
            "ash",
            "openxr",
            "hidapi",
            "gilrs",
        ],
    ),
];

/// `bench` uses the other modules as a user would; none of them may name it (only `main.rs`).
#[test]
fn no_module_but_the_command_line_names_bench() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut found = Vec::new();
    let mut stack = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap().flatten() {
            let p = e.path();
            if p == src.join("bench") || p == src.join("main.rs") {
                continue;
            }
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let text = std::fs::read_to_string(&p).unwrap();
                for (n, line) in text.lines().enumerate() {
                    if names(line, "crate::bench") || names(line, "super::bench") {
                        found.push(format!("{}:{}: {}", p.display(), n + 1, line.trim()));
                    }
                }
            }
        }
    }
    assert!(found.is_empty(), "modules naming `bench` (DESIGN.md):\n{}", found.join("\n"));
}

/// Modules where `unsafe` may appear (DESIGN.md: "`unsafe` is confined to `render` and `xr`").
const UNSAFE_ALLOWED: &[&str] = &["render", "xr"];

fn module_files(src: &Path, module: &str) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let single = src.join(format!("{module}.rs"));
    if single.is_file() {
        files.push(single);
    }
    let mut stack = vec![src.join(module)];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    files.sort();
    files
}

/// Whether `line` names `path`: `crate::x` anywhere, or an external crate `c` as `c::` or
/// `use c` at a word boundary.
fn names(line: &str, path: &str) -> bool {
    let code = line.split("//").next().unwrap_or("");
    if path.contains("::") || path.starts_with("super") {
        return code.contains(path);
    }
    let bytes = code.as_bytes();
    code.match_indices(path).any(|(i, _)| {
        let before_ok =
            i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_' || bytes[i - 1] == b':');
        let after = &code[i + path.len()..];
        before_ok
            && (after.starts_with("::")
                || (code[..i].trim_end().ends_with("use")
                    && !after.starts_with(|c: char| c.is_alphanumeric() || c == '_')))
    })
}

fn violations(src: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for (module, forbidden) in RULES {
        for file in module_files(src, module) {
            let text = std::fs::read_to_string(&file).expect("source is readable");
            for (n, line) in text.lines().enumerate() {
                for f in *forbidden {
                    if names(line, f) {
                        found.push(format!(
                            "{}:{}: module `{module}` must not use `{f}`: {}",
                            file.display(),
                            n + 1,
                            line.trim()
                        ));
                    }
                }
                let code = line.split("//").next().unwrap_or("");
                if !UNSAFE_ALLOWED.contains(module) && names_unsafe(code) {
                    found.push(format!(
                        "{}:{}: `unsafe` outside render and xr: {}",
                        file.display(),
                        n + 1,
                        line.trim()
                    ));
                }
            }
        }
    }
    found
}

fn names_unsafe(code: &str) -> bool {
    code.split(|c: char| !(c.is_alphanumeric() || c == '_')).any(|w| w == "unsafe")
}

#[test]
fn modules_respect_the_dependency_rules() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let found = violations(&src);
    assert!(found.is_empty(), "dependency rules broken (DESIGN.md):\n{}", found.join("\n"));
}

#[test]
fn every_ruled_module_that_exists_is_scanned() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    for module in ["math", "field", "tool", "mesh", "render", "stereo", "scene", "input", "xr", "io"] {
        assert!(!module_files(&src, module).is_empty(), "module {module} has no source file to check");
    }
}

#[test]
fn the_checker_catches_violations() {
    let dir = std::env::temp_dir().join(format!("argile-arch-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("field")).unwrap();
    std::fs::write(dir.join("field/mod.rs"), "use crate::math::Vec3;\nuse ash::vk;\nfn f() { crate::render::draw(); }\nunsafe fn g() {}\n// use ash::vk in a comment is fine\nfn h(trash: u8) {}\n").unwrap();
    std::fs::write(dir.join("math.rs"), "use crate::field::Field;\n").unwrap();
    let found = violations(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(found.len(), 4, "{found:#?}");
    assert!(found.iter().any(|f| f.contains("field/mod.rs:2") && f.contains("`ash`")));
    assert!(found.iter().any(|f| f.contains("field/mod.rs:3") && f.contains("crate::render")));
    assert!(found.iter().any(|f| f.contains("field/mod.rs:4") && f.contains("unsafe")));
    assert!(found.iter().any(|f| f.contains("math.rs:1")));
}

/// The modules directly under `app` (a file `x.rs`, or a folder `x/` with `x.rs`) and the
/// others each names in its code (`super::x`, `crate::app::x`, or `super::super::x` from a
/// file of a folder), its tests left out.
fn app_imports(app: &Path) -> Vec<(String, Vec<String>)> {
    let mut modules: Vec<String> = std::fs::read_dir(app)
        .unwrap()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let stem = name.strip_suffix(".rs").unwrap_or(&name).to_owned();
            (stem != "mod" && (e.path().is_dir() || name.ends_with(".rs"))).then_some(stem)
        })
        .collect();
    modules.sort();
    modules.dedup();
    modules
        .iter()
        .map(|m| {
            let mut named = Vec::new();
            for file in module_files(app, m) {
                let depth = file.strip_prefix(app).unwrap().components().count() - 1;
                let up = "super::".repeat(depth + 1);
                let text = std::fs::read_to_string(&file).unwrap();
                let code = text.split("\n#[cfg(test)]").next().unwrap();
                for other in modules.iter().filter(|o| *o != m) {
                    let mentioned = code.lines().any(|line| {
                        [format!("{up}{other}::"), format!("crate::app::{other}::"), format!("{up}{other};")]
                            .iter()
                            .any(|path| names(line, path))
                    });
                    if mentioned && !named.contains(other) {
                        named.push(other.clone());
                    }
                }
            }
            (m.clone(), named)
        })
        .collect()
}

/// A circle of modules naming one another, if any: the first found, as a path back to its start.
fn circle(imports: &[(String, Vec<String>)]) -> Option<Vec<String>> {
    fn walk(
        at: &str,
        imports: &[(String, Vec<String>)],
        path: &mut Vec<String>,
        done: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        if let Some(i) = path.iter().position(|p| p == at) {
            let mut found = path[i..].to_vec();
            found.push(at.to_owned());
            return Some(found);
        }
        if done.iter().any(|d| d == at) {
            return None;
        }
        path.push(at.to_owned());
        let next = imports.iter().find(|(m, _)| m == at).map(|(_, n)| n.clone()).unwrap_or_default();
        for n in next {
            if let Some(found) = walk(&n, imports, path, done) {
                return Some(found);
            }
        }
        path.pop();
        done.push(at.to_owned());
        None
    }
    let mut done = Vec::new();
    imports.iter().find_map(|(m, _)| walk(m, imports, &mut Vec::new(), &mut done))
}

/// DESIGN.md: the modules of `app` depend on one another without circles (a station uses the
/// document, the panel's rows, the playback; none of those uses a station).
#[test]
fn the_modules_of_app_name_one_another_in_no_circle() {
    let app = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/app");
    let imports = app_imports(&app);
    let station = imports.iter().find(|(m, _)| m == "station").expect("app/station is scanned");
    assert!(station.1.iter().any(|n| n == "document"), "the station's imports are read: {station:?}");
    assert_eq!(circle(&imports), None, "app's modules in a circle:\n{imports:#?}");
}

#[test]
fn the_circle_finder_finds_a_circle_and_passes_a_chain() {
    let chain = |pairs: &[(&str, &[&str])]| -> Vec<(String, Vec<String>)> {
        pairs.iter().map(|(m, n)| (m.to_string(), n.iter().map(|s| s.to_string()).collect())).collect()
    };
    assert_eq!(circle(&chain(&[("a", &["b"]), ("b", &["c"]), ("c", &[])])), None);
    let found = circle(&chain(&[("a", &["b"]), ("b", &["c"]), ("c", &["b"])])).unwrap();
    assert_eq!(found, ["b", "c", "b"]);
}
