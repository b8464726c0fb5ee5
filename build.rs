//! Compiles the GLSL sources in `shaders/` to SPIR-V in `OUT_DIR` with `glslc`.
//!
//! A shader error fails the build with glslc's own message, which names the file and line.
//! `glslc` comes from the Debian package of the same name (`scripts/setup` installs it).

use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    let manifest =
        PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let shader_dir = manifest.join("shaders");
    println!("cargo:rerun-if-changed={}", shader_dir.display());
    let include_dir = shader_dir.join("include");
    if include_dir.is_dir() {
        for entry in sorted_entries(&include_dir) {
            println!("cargo:rerun-if-changed={}", entry.display());
        }
    }
    let glslc = std::env::var("GLSLC").unwrap_or_else(|_| "glslc".to_owned());
    for path in sorted_entries(&shader_dir) {
        let Some(ext) = path.extension().and_then(|e| e.to_str()) else { continue };
        if !matches!(ext, "vert" | "frag" | "comp") {
            continue;
        }
        println!("cargo:rerun-if-changed={}", path.display());
        let name = path.file_name().and_then(|n| n.to_str()).expect("shader names are UTF-8");
        let target = out.join(format!("{name}.spv"));
        let result = Command::new(&glslc)
            .arg("--target-env=vulkan1.1")
            .arg("-O")
            .arg("-Werror")
            .arg("-I")
            .arg(&include_dir)
            .arg(&path)
            .arg("-o")
            .arg(&target)
            .output();
        match result {
            Err(e) => fail(&format!(
                "could not run `{glslc}` to compile {}: {e}. Install the Debian package `glslc` \
                 (scripts/setup does it) or set GLSLC to the compiler's path.",
                path.display()
            )),
            Ok(o) if !o.status.success() => fail(&format!(
                "shader {} does not compile:\n{}{}",
                path.display(),
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            )),
            Ok(_) => {}
        }
    }
}

fn sorted_entries(dir: &Path) -> Vec<PathBuf> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.is_file()).collect())
        .unwrap_or_default();
    entries.sort();
    entries
}

fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(1);
}
