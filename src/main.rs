//! `argile`: the command-line shell over the station (`argile::app`).

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use argile::app::{self, RenderOptions};
use argile::bench;
use argile::io::autosave::AutosaveConfig;
use argile::mesh::export::ExportFormat;
use argile::scene::Scene;
use argile::stereo::display::DisplayMode;
use clap::{Parser, Subcommand};

/// Argile: sculpt virtual clay in stereo and VR.
///
/// With no command, starts the station on the default scene: in a headset when an OpenXR
/// runtime with a headset is ready, else in a window when there is a display, else headless
/// (it renders the default scene and says where the stereo pair is).
#[derive(Parser)]
#[command(version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// The most memory the clay a command builds or opens, its mesh and its images may need,
    /// e.g. 8G or 512M (default: half of this machine's memory). Work whose estimate is over it
    /// is refused before it starts, with the estimate.
    #[arg(long, global = true, value_parser = argile::app::budget::parse_size)]
    memory_budget: Option<u64>,
}

#[derive(Subcommand)]
enum Command {
    /// Opens the station window on a scene (the default scene when none is named) and sculpts
    /// at the display's rate; without a display, says so and renders the scene headless.
    Run {
        /// The scene file (TOML, see scenes/README.md), or a sculpt file (`.argile`) to go on
        /// sculpting (saving writes back to it).
        scene: Option<PathBuf>,
        /// Close after this many frames, with a fixed 1/60 s time step (scripted runs, tests).
        #[arg(long)]
        frames: Option<u64>,
        /// With --frames: write what the window shows in the last frame to this PNG.
        #[arg(long, requires = "frames")]
        screenshot: Option<PathBuf>,
        /// Input events to play at given frames (TOML, see `argile::app::InputScript`).
        #[arg(long)]
        input_script: Option<PathBuf>,
        /// Key bindings read over the shipped ones (see calibration/keys.toml).
        #[arg(long)]
        keys: Option<PathBuf>,
        /// Where the save key (and closing with unsaved strokes) writes the sculpt
        /// (default: SCENE-NAME.argile in the current folder).
        #[arg(long)]
        save_to: Option<PathBuf>,
        /// Window size, WIDTHxHEIGHT, instead of the scene's output size.
        #[arg(long, value_parser = parse_size)]
        size: Option<(u32, u32)>,
        /// How the window shows the stereo pair (default: the scene's `[display] mode`, else
        /// anaglyph); the M key cycles the modes.
        #[arg(long)]
        display_mode: Option<DisplayMode>,
        /// Track the head with opentrack ("UDP over network" output) on this address, e.g.
        /// 127.0.0.1:4242: head-tracked views through the calibrated screen.
        #[arg(long)]
        opentrack: Option<std::net::SocketAddr>,
        /// The screen calibration (TOML, see calibration/README.md), read over the shipped
        /// calibration/screen.toml: display mode and parity, screen, viewer, tracker.
        #[arg(long)]
        calibration: Option<PathBuf>,
        /// Turn the Vulkan validation layer on (fails on any validation message).
        #[arg(long)]
        validation: bool,
        /// Each eye gets the other's image (glasses worn backwards, emitters that invert); the
        /// E key swaps them back and forth.
        #[arg(long)]
        swap_eyes: bool,
        /// Mask the side edges where clay in front of the screen touches them (a floating
        /// stereoscopic window, as `[display] floating_window`); Shift+M switches it.
        #[arg(long)]
        floating_window: bool,
        /// The window fills its monitor (as `[display] fullscreen`); F11 switches at run time.
        #[arg(long)]
        fullscreen: bool,
        /// The monitor the window opens on: its index (from 0) or (a part of) its name, such as
        /// DP-1 (as `[display] monitor` in a scene or the calibration); a name that fits none is
        /// refused with the list.
        #[arg(long)]
        monitor: Option<argile::scene::MonitorName>,
        /// Sculpt in an OpenXR headset; without a loader, runtime or headset, says which is
        /// missing and opens the desktop stereo station instead.
        #[arg(long)]
        xr: bool,
        /// In the headset, the left hand holds the tool (the right one grabs).
        #[arg(long, requires = "xr")]
        left_handed: bool,
        /// When the OpenXR runtime goes away, how long to wait for it to come back (seconds)
        /// before going on at the desktop station with the saved sculpt.
        #[arg(long, requires = "xr", default_value_t = app::WAIT_FOR_RUNTIME_S, value_parser = parse_wait)]
        xr_wait_s: f64,
        /// Desk input settings (see calibration/input.toml): what each device drives and its
        /// calibration file; else ~/.config/argile/input.toml if there is one.
        #[arg(long)]
        input: Option<PathBuf>,
        /// The folder the open key (Ctrl+O) takes sculpts from, newest first (default: the
        /// folder of the save file).
        #[arg(long)]
        open_dir: Option<PathBuf>,
        /// The hand's tool edits the finest resolution level whatever its size. By default a
        /// tool spanning more than 32 voxels edits the coarser level its size chooses, unless
        /// its scene tool sets `level_samples`.
        #[arg(long)]
        edit_finest: bool,
    },
    /// Plays a scene's timeline offscreen and writes every capture as NAME-left.png and
    /// NAME-right.png.
    Render {
        /// The scene file (TOML, see scenes/README.md), or a sculpt file (`.argile`), shown in
        /// the scene stored in it.
        scene: PathBuf,
        /// Folder for the images (created if missing).
        #[arg(long, short)]
        out: PathBuf,
        /// Also write each capture as this display mode shows it, as NAME-MODE.png (repeat for
        /// several; replaces the scene's `[display] mode`). Quad-buffer writes its two layers
        /// as NAME-quad-buffer-left.png and -right.png.
        #[arg(long, value_enum)]
        display_mode: Vec<DisplayMode>,
        /// Per-eye image size, WIDTHxHEIGHT, instead of the scene's.
        #[arg(long, value_parser = parse_size)]
        size: Option<(u32, u32)>,
        /// The screen calibration (see calibration/README.md) the images are judged on for the
        /// parallax budget: its screen, viewing distance and [comfort] (default: the scene's
        /// [head] calibration, else the shipped calibration/screen.toml).
        #[arg(long)]
        calibration: Option<PathBuf>,
        /// Each eye's image written as the other's (glasses worn backwards, emitters that
        /// invert); as the scene's `[display] swap_eyes`.
        #[arg(long)]
        swap_eyes: bool,
        /// Mask the side edges where clay in front of the screen touches them (a floating
        /// stereoscopic window), as the scene's `[display] floating_window`.
        #[arg(long)]
        floating_window: bool,
        /// Turn the Vulkan validation layer on (fails on any validation message).
        #[arg(long)]
        validation: bool,
        #[command(flatten)]
        autosave: AutosaveArgs,
    },
    /// Plays a scene to the end of its timeline and saves its clay as a sculpt (`.argile`).
    Save {
        /// The scene file (TOML, see scenes/README.md), or a sculpt file (`.argile`) to copy.
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
        /// A sculpt of parts as one mesh, their composition (`composed`), or one mesh per
        /// visible part with its placement (`separate`: a GLB node or an OBJ object each).
        #[arg(long, value_enum, default_value = "composed")]
        parts: app::PartsExport,
    },
    /// Lists the Vulkan devices, the OpenXR state, the input devices Argile sees, what each
    /// drives and where its calibration comes from; with a sculpt file, describes it instead
    /// from its index, without reading its clay.
    Info {
        /// A sculpt file (`.argile`) to describe: version, size, settings, each level's bricks
        /// and where they lie, history and scene.
        sculpt: Option<PathBuf>,
        /// Desk input settings (see calibration/input.toml); else ~/.config/argile/input.toml
        /// if there is one.
        #[arg(long)]
        input: Option<PathBuf>,
    },
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
    /// Prints the stereo frusta a screen calibration gives and renders a test-pattern stereo
    /// pair: a grid on the screen plane (zero parallax) and a near and a far ball with their
    /// expected disparities.
    Calibrate {
        /// The screen calibration (TOML, see calibration/README.md); the shipped one when absent.
        #[arg(long)]
        calibration: Option<PathBuf>,
        /// Folder for calibration-left.png and calibration-right.png (created if missing).
        #[arg(long, short, default_value = "argile-calibration")]
        out: PathBuf,
        /// Width of each eye's image in pixels (the height follows the screen's aspect ratio).
        #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(64..=8192))]
        width: u32,
        /// Also write the pattern as this display mode shows it, as calibration-MODE.png: the
        /// mode of the display being checked (repeat for several; the calibration's
        /// `[display] mode` when none is given).
        #[arg(long, value_enum)]
        display_mode: Vec<DisplayMode>,
        /// Show the pattern in the station's window (full screen unless --size) and adjust the
        /// calibration while it shows: the arrows size the screen, PageUp/PageDown move the
        /// eye, = and - change the IPD, Enter or Ctrl+S writes them into the --calibration file
        /// (created when missing), Backspace goes back to what it says.
        #[arg(long, requires = "calibration")]
        adjust: bool,
        /// With --adjust: the window's size, WIDTHxHEIGHT, instead of the whole monitor.
        #[arg(long, requires = "adjust", value_parser = parse_size)]
        size: Option<(u32, u32)>,
        /// With --adjust: the monitor the window opens on (its index or a part of its name).
        #[arg(long, requires = "adjust")]
        monitor: Option<argile::scene::MonitorName>,
        /// With --adjust: key bindings read over the shipped ones (see calibration/keys.toml).
        #[arg(long, requires = "adjust")]
        keys: Option<PathBuf>,
        /// With --adjust: close after this many frames (scripted runs, tests).
        #[arg(long, requires = "adjust")]
        frames: Option<u64>,
        /// With --adjust and --frames: write what the window shows in the last frame to this PNG.
        #[arg(long, requires = "frames")]
        screenshot: Option<PathBuf>,
        /// With --adjust: input events to play at given frames (see `argile::app::InputScript`).
        #[arg(long, requires = "adjust")]
        input_script: Option<PathBuf>,
        /// Turn the Vulkan validation layer on (fails on any validation message).
        #[arg(long)]
        validation: bool,
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
    /// The autosave settings if autosave is on, after recovering unclosed sessions. With
    /// autosave, SIGINT, SIGTERM and SIGHUP end the run between two steps of the timeline, as
    /// a clean exit does (the session is closed once what was done is written).
    fn start(&self) -> Option<AutosaveConfig> {
        self.autosave.then(|| {
            if let Err(e) = app::signals::install() {
                tracing::warn!("{e:#}");
            }
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

fn parse_wait(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (0.0..=86_400.0).contains(&v) => Ok(v),
        _ => Err(format!("`{s}` is not a number of seconds from 0 to 86400")),
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
    if let Some(bytes) = cli.memory_budget {
        app::budget::set(bytes);
    }
    let result = match cli.command {
        // A headset when one is ready, else the desktop station.
        None => {
            let xr = (argile::xr::runtime_configured() && argile::xr::probe().ready())
                .then_some(XrChoice { left_handed: false, wait_for_runtime_s: app::WAIT_FOR_RUNTIME_S });
            station(None, xr, app::StationOptions::default())
        }
        Some(Command::Run {
            scene,
            frames,
            screenshot,
            input_script,
            keys,
            save_to,
            size,
            display_mode,
            opentrack,
            calibration,
            validation,
            swap_eyes,
            floating_window,
            fullscreen,
            monitor,
            xr,
            left_handed,
            xr_wait_s,
            input,
            open_dir,
            edit_finest,
        }) => station(
            scene,
            xr.then_some(XrChoice { left_handed, wait_for_runtime_s: xr_wait_s }),
            app::StationOptions {
                frames,
                screenshot,
                script: input_script,
                keys,
                save_to,
                window_px: size,
                validation,
                display_mode,
                opentrack,
                calibration,
                autosave: None,
                scene_toml: None,
                input,
                open: None,
                open_dir,
                edit_finest,
                swap_eyes,
                floating_window,
                fullscreen,
                monitor,
                recovered: Vec::new(),
                adjust: None,
            },
        ),
        Some(Command::Render {
            scene,
            out,
            display_mode,
            size,
            calibration,
            swap_eyes,
            floating_window,
            validation,
            autosave,
        }) => {
            let view = RenderView { size, calibration: calibration.as_deref(), swap_eyes, floating_window };
            render(&scene, out, display_mode, view, validation, &autosave)
        }
        Some(Command::Export { input, format, out, force, parts }) => {
            app::export_as(&input, format, parts, &out, force, true).map(|s| {
                println!(
                    "wrote {} ({} vertices, {} triangles, {} bytes)",
                    s.path.display(),
                    s.vertices,
                    s.triangles,
                    s.bytes
                )
            })
        }
        Some(Command::Save { scene, out, force, autosave }) => {
            let saved = if app::is_sculpt(&scene) {
                let options = argile::io::EncodeOptions { version: argile::io::VERSION, history: true };
                app::convert_sculpt(&scene, &out, options, force)
            } else {
                app::save_scene_sculpt(&scene, &out, force, autosave.start())
            };
            saved.map(|s| println!("wrote {} ({} bricks, {} bytes)", s.path.display(), s.bricks, s.bytes))
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
        Some(Command::Recover) => match app::recover_and_report() {
            app::RecoveryCount { recovered: 0, failed: 0, .. } => {
                println!("No session is left to recover: every earlier session closed cleanly.");
                Ok(())
            }
            app::RecoveryCount { failed: 0, .. } => Ok(()),
            app::RecoveryCount { recovered, failed, .. } => Err(anyhow::anyhow!(
                "{failed} session(s) could not be recovered (each is named above and left in place); \
                 {recovered} recovered"
            )),
        },
        Some(Command::Info { sculpt: Some(path), .. }) => app::describe_sculpt(&path).map(|d| print!("{d}")),
        Some(Command::Info { input, sculpt: None }) => info(input.as_deref()),
        Some(Command::Bench { json, quick, workloads }) => run_bench(json, quick, &workloads),
        Some(Command::Calibrate {
            calibration: Some(file),
            width,
            display_mode,
            adjust: true,
            size,
            monitor,
            keys,
            frames,
            screenshot,
            input_script,
            validation,
            ..
        }) => app::signals::install().and_then(|()| {
            let options = app::AdjustOptions {
                calibration: file,
                width_px: width,
                station: app::StationOptions {
                    frames,
                    screenshot,
                    script: input_script,
                    keys,
                    window_px: size,
                    validation,
                    display_mode: display_mode.first().copied(),
                    monitor,
                    ..Default::default()
                },
            };
            app::adjust_calibration(&options).map(|_| ())
        }),
        Some(Command::Calibrate { calibration, out, width, display_mode, validation, .. }) => {
            let options = app::CalibrateOptions {
                calibration,
                out_dir: out,
                width_px: width,
                validation,
                display_modes: display_mode,
            };
            app::calibrate(&options).map(|c| {
                print!("{}", c.report);
                print_written(std::slice::from_ref(&c.written));
            })
        }
    };
    let stopped = app::signals::received();
    if let Err(e) = &result {
        eprintln!("error: {e:#}");
    }
    match (stopped, result) {
        (Some(signal), _) => {
            println!("stopped by {}", app::signals::name(signal));
            ExitCode::from(app::signals::exit_status(signal) as u8)
        }
        (None, Ok(())) => ExitCode::SUCCESS,
        (None, Err(_)) => ExitCode::FAILURE,
    }
}

fn print_written(written: &[app::WrittenCapture]) {
    for w in written {
        println!("wrote {} and {}", w.left.display(), w.right.display());
        for p in &w.composed {
            println!("wrote {}", p.display());
        }
    }
}

/// How the headset is used.
#[derive(Clone, Copy, Debug)]
struct XrChoice {
    left_handed: bool,
    wait_for_runtime_s: f64,
}

/// Runs the station: in the headset when `xr` is set and one is there, else in a window,
/// else headless.
fn station(
    mut scene_path: Option<PathBuf>,
    xr: Option<XrChoice>,
    options: app::StationOptions,
) -> Result<()> {
    // SIGINT, SIGTERM and SIGHUP stop the desk or the headset as a clean exit does.
    app::signals::install()?;
    // Every file named is checked before anything runs: headless, none of them is read, and a
    // mistyped name would go unnoticed.
    let named = [
        ("input script", &options.script),
        ("key bindings", &options.keys),
        ("screen calibration", &options.calibration),
        ("desk input settings", &options.input),
    ];
    for (kind, path) in named.iter().filter_map(|(k, p)| p.as_ref().map(|p| (k, p))) {
        argile::io::text::regular_file(path)
            .with_context(|| format!("cannot read {kind} file {}", path.display()))?;
    }
    let mut sculpt = None;
    let (scene, scene_text) = match &scene_path {
        Some(p) if app::is_sculpt(p) => {
            let (scene, opened) = app::open_sculpt(p)?;
            let text = opened.scene_toml.clone();
            sculpt = Some(opened);
            (scene, text)
        }
        Some(p) => {
            let text = argile::io::text::read_text(p, argile::io::text::SCENE_LIMIT)
                .with_context(|| format!("cannot read scene file {}", p.display()))?;
            (Scene::parse(&text, &p.display().to_string(), p.parent())?, Some(text))
        }
        None => (Scene::default_scene(), Some(argile::scene::DEFAULT_SCENE_TOML.to_owned())),
    };
    let mut scene = scene;
    scene.display.swap_eyes |= options.swap_eyes;
    scene.display.floating_window |= options.floating_window;
    let name = scene_path
        .as_deref()
        .and_then(|p| p.file_stem())
        .map_or("default".to_owned(), |s| s.to_string_lossy().into_owned());
    let recovered = app::recover_and_report().sculpts;
    if let Some(XrChoice { left_handed, wait_for_runtime_s }) = xr {
        let xr_options = app::XrRunOptions {
            wait_for_runtime_s,
            session: argile::xr::XrOptions { validation: options.validation, ..Default::default() },
            frames: options.frames,
            save_to: options.save_to.clone(),
            autosave: Some(AutosaveConfig::default()),
            scene_toml: scene_text.clone(),
            left_handed,
            edit_finest: options.edit_finest,
        };
        // The headset sculpts an opened file's clay; it is saved to the file it came from
        // unless --save-to says otherwise.
        // A copy (bricks are shared, not copied): without a headset, the desktop station
        // below opens the same sculpt.
        let opened = sculpt.clone();
        let xr_options = app::XrRunOptions {
            save_to: xr_options.save_to.or_else(|| opened.is_some().then(|| scene_path.clone()).flatten()),
            ..xr_options
        };
        match app::run_xr(&scene, opened, &name, &xr_options) {
            Ok(report) => {
                println!(
                    "headset session on {} closed after {} frames{}{}",
                    report.runtime,
                    report.frames,
                    if report.depth { " (with depth)" } else { "" },
                    match report.recreated {
                        0 => String::new(),
                        n => format!("; the session was lost and made again {n} time(s)"),
                    }
                );
                if let Some(p) = &report.saved {
                    println!("saved the sculpt to {}", p.display());
                }
                match (&report.saved, report.runtime_gone && app::signals::received().is_none()) {
                    // The runtime went away for good: the desktop station goes on with the
                    // saved sculpt, saving back to it.
                    (Some(saved), true) => {
                        println!("Going on at the desktop stereo station with {}.", saved.display());
                        sculpt = Some(app::open_sculpt(saved)?.1);
                        scene_path = Some(saved.clone());
                    }
                    _ => return Ok(()),
                }
            }
            Err(e) => match app::xr_absent(&e) {
                Some(absent) => println!("No headset session: {absent}. Using the desktop stereo station."),
                None => return Err(e),
            },
        }
    }
    if let Some(reason) = app::no_display_reason() {
        println!("No window can open here: {reason}. Rendering the {name} scene headless.");
        let unused: Vec<&str> = [
            ("--frames", options.frames.is_some()),
            ("--input-script", options.script.is_some()),
            ("--keys", options.keys.is_some()),
            ("--calibration", options.calibration.is_some()),
            ("--input", options.input.is_some()),
            ("--opentrack", options.opentrack.is_some()),
        ]
        .into_iter()
        .filter_map(|(flag, given)| given.then_some(flag))
        .collect();
        if !unused.is_empty() {
            println!("Headless, these drive only the window and are not used: {}.", unused.join(", "));
        }
        let options = RenderOptions {
            out_dir: PathBuf::from("argile-out"),
            display_modes: vec![options.display_mode.unwrap_or(DisplayMode::Anaglyph)],
            progress: true,
            validation: options.validation,
            size_px: options.window_px,
            calibration: options
                .calibration
                .as_deref()
                .map(argile::scene::ScreenCalibration::load)
                .transpose()?,
            eye_marks: Vec::new(),
        };
        let written = match sculpt {
            Some(s) => {
                let path = scene_path.as_deref().unwrap_or(std::path::Path::new("the sculpt"));
                let s = app::with_lattice_applied(s, path)?;
                app::render_sculpt(&scene, s.field, s.others, &options)?
            }
            None => app::render_scene_autosaved(
                &scene,
                &options,
                Some(AutosaveConfig::default()),
                scene_text.as_deref(),
            )?,
        };
        print_written(&written);
        return Ok(());
    }
    // A sculpt file is opened by the station itself, so that saving writes back to it.
    let open = sculpt.is_some().then(|| scene_path.clone()).flatten();
    let options = app::StationOptions {
        autosave: Some(AutosaveConfig::default()),
        scene_toml: scene_text,
        open,
        recovered: recovered.iter().map(|r| (r.path.clone(), r.described())).collect(),
        ..options
    };
    let report = app::run_station(&scene, &name, &options)?;
    println!("station closed after {} frames", report.frames);
    if let Some(p) = &report.screenshot {
        println!("wrote {}", p.display());
    }
    if let Some(p) = &report.saved {
        println!("saved the sculpt to {}", p.display());
    }
    Ok(())
}

/// How `argile render` shows the scene: the eyes' size, the screen judged on, swapped eyes,
/// the floating window.
struct RenderView<'a> {
    size: Option<(u32, u32)>,
    calibration: Option<&'a std::path::Path>,
    swap_eyes: bool,
    floating_window: bool,
}

fn render(
    scene: &std::path::Path,
    out: PathBuf,
    display_modes: Vec<DisplayMode>,
    view: RenderView<'_>,
    validation: bool,
    autosave: &AutosaveArgs,
) -> Result<()> {
    let RenderView { size, calibration, swap_eyes, floating_window } = view;
    let calibration = calibration.map(argile::scene::ScreenCalibration::load).transpose()?;
    let options = RenderOptions {
        out_dir: out,
        display_modes,
        progress: true,
        validation,
        size_px: size,
        calibration,
        eye_marks: Vec::new(),
    };
    if app::is_sculpt(scene) {
        // Nothing is sculpted while rendering a sculpt: there is nothing to autosave.
        let path = scene;
        let (mut scene, sculpt) = app::open_sculpt(path)?;
        let sculpt = app::with_lattice_applied(sculpt, path)?;
        scene.display.swap_eyes |= swap_eyes;
        scene.display.floating_window |= floating_window;
        print_written(&app::render_sculpt(&scene, sculpt.field, sculpt.others, &options)?);
        return Ok(());
    }
    let text = argile::io::text::read_text(scene, argile::io::text::SCENE_LIMIT)
        .with_context(|| format!("cannot read scene file {}", scene.display()))?;
    let mut scene = Scene::parse(&text, &scene.display().to_string(), scene.parent())?;
    scene.display.swap_eyes |= swap_eyes;
    scene.display.floating_window |= floating_window;
    let written = app::render_scene_autosaved(&scene, &options, autosave.start(), Some(&text))?;
    print_written(&written);
    Ok(())
}

fn info(input_settings: Option<&std::path::Path>) -> Result<()> {
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
    use argile::input::settings::InputSettings;
    let layers: Vec<&std::path::Path> = input_settings.into_iter().collect();
    let settings = InputSettings::load(&layers, InputSettings::user_config_dir().as_deref())?;
    let mapping = settings.mapping;
    for d in &input.devices {
        println!(
            "  {}: {} ({}), drives the {} (calibration: {})",
            d.kind,
            d.name,
            d.location,
            mapping.target(d.class).name(),
            settings.source(d.class)
        );
    }
    let mouse = argile::input::motion::DeviceClass::Mouse;
    println!(
        "  mouse: the window's pointer, drives the {} (settings: {})",
        mapping.target(mouse).name(),
        settings.source(mouse)
    );
    for p in &input.problems {
        println!("  {p}");
    }
    let files: Vec<String> = settings.files.iter().map(|p| p.display().to_string()).collect();
    let files =
        if files.is_empty() { "shipped".to_owned() } else { format!("shipped < {}", files.join(" < ")) };
    println!("\nDesk input settings ({files}):");
    for line in settings.describe(&mapping) {
        println!("  {line}");
    }
    println!(
        "  SpaceMice are read {}",
        match settings.spacemouse_via {
            argile::input::settings::SpaceMouseVia::Auto => "through spacenavd when it runs, else over HID",
            argile::input::settings::SpaceMouseVia::Hid => "over HID",
            argile::input::settings::SpaceMouseVia::Spacenavd => "through spacenavd",
        }
    );
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
