//! `argile`: the command-line shell over the station (`argile::app`).

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use argile::app::{self, bench, RenderOptions};
use argile::io::autosave::AutosaveConfig;
use argile::mesh::export::ExportFormat;
use argile::scene::Scene;
use argile::stereo::Preview;
use clap::{Parser, Subcommand};

/// Argile: sculpt virtual clay in stereo and VR.
///
/// With no command, starts the station on the default scene. Until the desktop window exists,
/// the station renders the default scene headless and says where the stereo pair is.
#[derive(Parser)]
#[command(version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Plays a scene's timeline offscreen and writes every capture as NAME-left.png and
    /// NAME-right.png.
    Render {
        /// The scene file (TOML, see scenes/README.md).
        scene: PathBuf,
        /// Folder for the images (created if missing).
        #[arg(long, short)]
        out: PathBuf,
        /// Also write a combined preview image per capture.
        #[arg(long, value_enum)]
        preview: Option<Preview>,
        /// Per-eye image size, WIDTHxHEIGHT, instead of the scene's.
        #[arg(long, value_parser = parse_size)]
        size: Option<(u32, u32)>,
        /// Turn the Vulkan validation layer on (fails on any validation message).
        #[arg(long)]
        validation: bool,
        #[command(flatten)]
        autosave: AutosaveArgs,
    },
    /// Plays a scene to the end of its timeline and saves its clay as a sculpt (`.argile`).
    Save {
        /// The scene file (TOML, see scenes/README.md).
        scene: PathBuf,
        /// The sculpt file to write (`.argile`).
        #[arg(long, short)]
        out: PathBuf,
        /// Replace the file if it exists.
        #[arg(long)]
        force: bool,
        #[command(flatten)]
        autosave: AutosaveArgs,
    },
    /// Rewrites a sculpt file (`.argile`, any version this Argile reads) in another format
    /// version, or stores a scene's clay (at the end of its timeline) as a sculpt.
    Convert {
        /// The sculpt file (`.argile`) or scene file (TOML) to read.
        input: PathBuf,
        /// The sculpt file to write (`.argile`).
        out: PathBuf,
        /// The format version to write (1 holds no undo history).
        #[arg(long, default_value_t = argile::io::VERSION)]
        format_version: u32,
        /// Leave the undo history out.
        #[arg(long)]
        no_history: bool,
        /// Replace the file if it exists.
        #[arg(long)]
        force: bool,
    },
    /// Recovers the sculpts of sessions that did not close cleanly (a crash, a power cut) and
    /// says where each is saved. The station does this at every start.
    Recover,
    /// Writes the clay of a scene (as it is at the end of its timeline) or of a saved sculpt
    /// (`.argile`) as a mesh file.
    ///
    /// OBJ and STL are written in millimetres, PLY and glTF (GLB) in metres. The mesh is
    /// welded and indexed; PLY and GLB carry vertex colours.
    Export {
        /// The scene file (TOML, see scenes/README.md) or sculpt file (`.argile`).
        input: PathBuf,
        /// The mesh format.
        #[arg(long, short, value_enum)]
        format: ExportFormat,
        /// The file to write.
        #[arg(long, short)]
        out: PathBuf,
        /// Replace the file if it exists.
        #[arg(long)]
        force: bool,
    },
    /// Lists the Vulkan devices, the OpenXR state and the input devices Argile sees.
    Info,
    /// Runs the standard benchmark workloads.
    Bench {
        /// One JSON object per line.
        #[arg(long)]
        json: bool,
        /// Small sizes: checks the workloads run, figures are not comparable.
        #[arg(long)]
        quick: bool,
        /// Workloads to run (all when none is named).
        #[arg(value_enum)]
        workloads: Vec<bench::Workload>,
    },
}

/// Autosave of a scripted session.
#[derive(clap::Args)]
struct AutosaveArgs {
    /// Journal every finished stroke in the state folder, so that a crash loses at most the
    /// stroke in progress; sessions that did not close are recovered first.
    #[arg(long)]
    autosave: bool,
    /// Seconds of work between two autosave checkpoints.
    #[arg(long, default_value_t = 60.0, value_parser = parse_seconds)]
    checkpoint_s: f64,
    /// Seconds a journaled stroke may wait for its sync to disk (at most 1).
    #[arg(long, default_value_t = 1.0, value_parser = parse_seconds)]
    sync_s: f64,
}

impl AutosaveArgs {
    /// The autosave settings if autosave is on, after recovering unclosed sessions.
    fn start(&self) -> Option<AutosaveConfig> {
        self.autosave.then(|| {
            app::recover_and_report();
            AutosaveConfig {
                checkpoint_interval: std::time::Duration::from_secs_f64(self.checkpoint_s),
                sync_interval: std::time::Duration::from_secs_f64(self.sync_s.min(1.0)),
                ..AutosaveConfig::default()
            }
        })
    }
}

fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (0.01..=86_400.0).contains(&v) => Ok(v),
        _ => Err(format!("`{s}` is not a number of seconds from 0.01 to 86400")),
    }
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) =
        s.split_once('x').ok_or_else(|| format!("`{s}` is not WIDTHxHEIGHT (for example 512x512)"))?;
    let parse = |v: &str| v.parse::<u32>().ok().filter(|v| (16..=8192).contains(v));
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("`{s}`: width and height must be whole numbers from 16 to 8192")),
    }
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn,argile=info")),
        )
        .with_writer(std::io::stderr)
        .with_target(false)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    let cli = Cli::parse();
    let result = match cli.command {
        None => station(),
        Some(Command::Render { scene, out, preview, size, validation, autosave }) => {
            render(&scene, out, preview, size, validation, &autosave)
        }
        Some(Command::Export { input, format, out, force }) => app::export(&input, format, &out, force, true)
            .map(|s| {
                println!(
                    "wrote {} ({} vertices, {} triangles, {} bytes)",
                    s.path.display(),
                    s.vertices,
                    s.triangles,
                    s.bytes
                )
            }),
        Some(Command::Save { scene, out, force, autosave }) => {
            app::save_scene_sculpt(&scene, &out, force, autosave.start())
                .map(|s| println!("wrote {} ({} bricks, {} bytes)", s.path.display(), s.bricks, s.bytes))
        }
        Some(Command::Convert { input, out, format_version, no_history, force }) => {
            let options = argile::io::EncodeOptions { version: format_version, history: !no_history };
            app::convert_sculpt(&input, &out, options, force).map(|s| {
                println!(
                    "wrote {} (format version {format_version}, {} bricks, {} bytes)",
                    s.path.display(),
                    s.bricks,
                    s.bytes
                )
            })
        }
        Some(Command::Recover) => {
            if app::recover_and_report() == 0 {
                println!("No session is left to recover: every earlier session closed cleanly.");
            }
            Ok(())
        }
        Some(Command::Info) => info(),
        Some(Command::Bench { json, quick, workloads }) => run_bench(json, quick, &workloads),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn print_written(written: &[app::WrittenCapture]) {
    for w in written {
        println!("wrote {} and {}", w.left.display(), w.right.display());
        if let Some(p) = &w.preview {
            println!("wrote {}", p.display());
        }
    }
}

fn station() -> Result<()> {
    let has_display = std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some();
    if has_display {
        println!("The interactive desktop window is not part of this version; rendering the default scene headless.");
    } else {
        println!("No display found: rendering the default scene headless.");
    }
    app::recover_and_report();
    let scene = Scene::default_scene();
    let options = RenderOptions {
        out_dir: PathBuf::from("argile-out"),
        preview: Some(Preview::Anaglyph),
        progress: true,
        validation: false,
        size_px: None,
    };
    let toml = argile::scene::DEFAULT_SCENE_TOML;
    let written = app::render_scene_autosaved(&scene, &options, Some(AutosaveConfig::default()), Some(toml))?;
    print_written(&written);
    Ok(())
}

fn render(
    scene: &std::path::Path,
    out: PathBuf,
    preview: Option<Preview>,
    size: Option<(u32, u32)>,
    validation: bool,
    autosave: &AutosaveArgs,
) -> Result<()> {
    let text = std::fs::read_to_string(scene)
        .with_context(|| format!("cannot read scene file {}", scene.display()))?;
    let scene = Scene::parse(&text, &scene.display().to_string(), scene.parent())?;
    let options = RenderOptions { out_dir: out, preview, progress: true, validation, size_px: size };
    let written = app::render_scene_autosaved(&scene, &options, autosave.start(), Some(&text))?;
    print_written(&written);
    Ok(())
}

fn info() -> Result<()> {
    println!("Argile {}", env!("CARGO_PKG_VERSION"));
    println!("\nVulkan:");
    match argile::render::probe_devices() {
        Ok(probe) => print!("{probe}"),
        Err(e) => println!("  {e}"),
    }
    println!("\nOpenXR:\n  {}", argile::xr::probe());
    println!("\nInput devices:");
    let input = argile::input::probe();
    if input.devices.is_empty() {
        println!("  none found (no SpaceMouse, no gamepad)");
    }
    let mapping = argile::input::motion::MappingTable::default();
    for d in &input.devices {
        println!("  {}: {} ({}), drives the {}", d.kind, d.name, d.location, mapping.target(d.class).name());
    }
    let mouse = argile::input::motion::DeviceClass::Mouse;
    println!("  mouse: the window's pointer, drives the {}", mapping.target(mouse).name());
    for p in &input.problems {
        println!("  {p}");
    }
    Ok(())
}

fn run_bench(json: bool, quick: bool, workloads: &[bench::Workload]) -> Result<()> {
    let workloads = if workloads.is_empty() { &bench::Workload::ALL[..] } else { workloads };
    let size = if quick { bench::BenchSize::QUICK } else { bench::BenchSize::STANDARD };
    let stdout = std::io::stdout();
    bench::run(workloads, size, |value| {
        let mut out = stdout.lock();
        let line = if json {
            value.to_string()
        } else {
            let obj = value
                .as_object()
                .map(|o| o.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join("  "));
            obj.unwrap_or_default()
        };
        // A closed pipe (`| head`) is not an error worth a panic.
        let _ = writeln!(out, "{line}");
    })
    .context("benchmark failed")
}
