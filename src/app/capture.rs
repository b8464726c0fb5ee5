//! Headless rendering of a scene: play its timeline and write each capture as a stereo PNG pair,
//! and as its display mode composes it when one is set.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::autosave::start_autosave;
use super::environment::load_environment;
use super::frame::build_frame;
use super::playback::Playback;
use crate::field::Field;
use crate::io::autosave::AutosaveConfig;
use crate::io::write_atomically;
use crate::mesh::{mesh_all, Mesher, SurfaceSketch};
use crate::render::{Renderer, RendererDesc, StereoImage, ViewPasses};
use crate::scene::Scene;
use crate::stereo::display::DisplayMode;
use crate::stereo::floating::FloatingWindow;

/// Options of a headless render.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Folder the images go to (created if missing).
    pub out_dir: PathBuf,
    /// Also write each capture as these display modes compose it (`NAME-MODE.png`; the two
    /// layers of quad-buffer as `NAME-quad-buffer-left.png` and `-right.png`); none keeps the
    /// scene's `[display] mode`.
    pub display_modes: Vec<DisplayMode>,
    /// Show a progress bar on the terminal.
    pub progress: bool,
    /// Turn the Vulkan validation layer on.
    pub validation: bool,
    /// Override the scene's per-eye image size.
    pub size_px: Option<(u32, u32)>,
    /// The screen the images are judged on for the parallax budget (the scene's `[head]`
    /// calibration, else the shipped `calibration/screen.toml`, when `None`).
    pub calibration: Option<crate::scene::ScreenCalibration>,
    /// Marks drawn over one eye's picture or both in every capture (a calibration pattern's).
    pub eye_marks: Vec<crate::render::EyeMark>,
}

/// One written capture.
#[derive(Clone, Debug)]
pub struct WrittenCapture {
    /// Capture name.
    pub name: String,
    /// Left-eye image.
    pub left: PathBuf,
    /// Right-eye image.
    pub right: PathBuf,
    /// The composed images, in the order of the display modes (two for quad-buffer).
    pub composed: Vec<PathBuf>,
}

/// Writes an image as PNG atomically (see [`write_atomically`]), replacing an older one.
pub fn save_png_atomically(image: &image::RgbaImage, path: &Path) -> Result<()> {
    write_atomically(path, true, |w| {
        image
            .write_to(w, image::ImageFormat::Png)
            .with_context(|| format!("cannot encode {}", path.display()))
    })
}

/// A renderer for a scene's output settings and environment (`view_passes`: `None` lets the
/// environment and the device choose).
pub fn renderer_for(
    scene: &Scene,
    size_px: Option<(u32, u32)>,
    validation: bool,
    view_passes: Option<ViewPasses>,
) -> Result<Renderer> {
    let environment = load_environment(&scene.environment.choice)?;
    let (width, height) = size_px.unwrap_or((scene.output.width_px, scene.output.height_px));
    super::budget::admit_render(&scene.source, width, height, scene.output.samples)?;
    let desc = RendererDesc { width, height, samples: scene.output.samples, validation, view_passes };
    Ok(Renderer::new(&desc, &environment, scene.environment.intensity)?)
}

/// Plays `scene` and renders every capture. Returns what was written, in capture order.
pub fn render_scene(scene: &Scene, options: &RenderOptions) -> Result<Vec<WrittenCapture>> {
    render_scene_autosaved(scene, options, None, None)
}

/// [`render_scene`], journaling the strokes with `autosave` (snapshots carry `scene_toml`);
/// the autosave session is closed when every capture is written.
pub fn render_scene_autosaved(
    scene: &Scene,
    options: &RenderOptions,
    autosave: Option<AutosaveConfig>,
    scene_toml: Option<&str>,
) -> Result<Vec<WrittenCapture>> {
    render_over(scene, None, options, autosave, scene_toml)
}

/// Renders every capture of `scene` over `field`, the clay of a sculpt opened from a file (see
/// [`super::open_sculpt`]), instead of the scene's initial clay.
pub fn render_sculpt(
    scene: &Scene,
    field: Field,
    others: Vec<Field>,
    options: &RenderOptions,
) -> Result<Vec<WrittenCapture>> {
    render_over(scene, Some((field, others)), options, None, None)
}

/// Renders the captures of `scene` over `field` when given, else over its initial clay.
fn render_over(
    scene: &Scene,
    field: Option<(Field, Vec<Field>)>,
    options: &RenderOptions,
    autosave: Option<AutosaveConfig>,
    scene_toml: Option<&str>,
) -> Result<Vec<WrittenCapture>> {
    std::fs::create_dir_all(&options.out_dir)
        .with_context(|| format!("cannot create the output folder {}", options.out_dir.display()))?;
    let mut scene = scene.clone();
    if let Some((w, h)) = options.size_px {
        scene.output.width_px = w;
        scene.output.height_px = h;
    }
    let display_modes = if options.display_modes.is_empty() {
        scene.display.mode.into_iter().collect()
    } else {
        options.display_modes.clone()
    };
    if let Some(head) = &scene.head {
        // The image shows the whole screen: a different aspect ratio would stretch the view.
        let (screen, image) =
            (head.calibration.screen.aspect(), scene.output.width_px as f32 / scene.output.height_px as f32);
        if (screen / image - 1.0).abs() > 0.01 {
            tracing::warn!(
                "{}: the images' aspect ratio {image:.3} differs from the calibrated screen's {screen:.3}; head-tracked views will look stretched",
                scene.source
            );
        }
    }
    let mut renderer = renderer_for(&scene, None, options.validation, None)?;
    tracing::info!("rendering {} on {}", scene.source, renderer.device_name());
    let start = |field: &mut Field, tools: crate::io::autosave::Besides<'_>| {
        autosave.and_then(|config| start_autosave(field, (scene_toml, tools), &scene.source, config))
    };
    let mut playback = match field {
        Some((field, others)) => Playback::on_sculpt(&scene, field, others, &[], start),
        None => Playback::new_autosaved(&scene, start)?,
    };
    let initial = mesh_all(playback.surface());
    playback.surface().take_dirty();
    let clay = initial.upserted_bounds();
    // What the floating window judges of the surface, when the scene asks for it.
    let mut sketch = SurfaceSketch::default();
    if scene.display.floating_window {
        sketch.apply(&initial);
    }
    // The views' copy of the scene, whose interaxial the parallax budget may lower.
    let mut viewed = scene.clone();
    let calibration = options.calibration.unwrap_or_else(|| super::comfort::scene_calibration(&scene));
    if let Some((_, warning)) = super::comfort::apply_parallax_budget(&mut viewed, calibration, clay) {
        tracing::warn!("{warning}");
    }
    renderer.apply(&initial)?;

    let end = scene.captures.last().map_or(0.0, |c| c.time_s);
    let bar = progress_bar(options.progress && end > 0.0, end);
    let mut mesher = Mesher::default();
    let mut written = Vec::with_capacity(scene.captures.len());
    for capture in &scene.captures {
        let progress = |t: f32| bar.set_position((t * 1000.0) as u64);
        // A stopping signal (handled where autosave runs) ends the run between two steps:
        // the captures written so far stay, the session is closed.
        if !playback.advance_until(capture.time_s, progress, || super::signals::received().is_some()) {
            println!(
                "{} received at {:.2} s of the timeline: stopping before the capture {}",
                super::signals::received().map_or("a signal", super::signals::name),
                playback.time_s(),
                capture.name
            );
            break;
        }
        playback.sync_lattices();
        let diff = mesher.remesh_dirty(playback.surface());
        if scene.display.floating_window {
            sketch.apply(diff);
        }
        renderer.apply(diff)?;
        let mut frame = build_frame(&viewed, &playback.hands(), capture.show_tools);
        frame.eye_marks.clone_from(&options.eye_marks);
        if capture.show_tools {
            frame.tools.extend(super::frame::lattice_glyphs(&playback));
            frame.tools.extend(super::frame::symmetry_glyphs(&playback));
            frame.tools.extend(super::frame::region_glyphs(&playback));
        }
        if let (Some(head), Some(rig)) = (&viewed.head, viewed.head_tracked_rig()) {
            frame.views = rig.views(&head.pose_at(capture.time_s));
        }
        if viewed.display.floating_window {
            frame.floating_window = FloatingWindow::measure(&frame.views, sketch.points());
        }
        if viewed.display.swap_eyes {
            frame.views.eyes.swap(0, 1);
            frame.floating_window = frame.floating_window.swapped();
        }
        renderer.draw(&frame)?;
        let StereoImage { left, right } = renderer.read_back()?;
        let left_path = options.out_dir.join(format!("{}-left.png", capture.name));
        let right_path = options.out_dir.join(format!("{}-right.png", capture.name));
        save_png_atomically(&left, &left_path)?;
        save_png_atomically(&right, &right_path)?;
        let mut composed = Vec::new();
        for &mode in &display_modes {
            renderer.compose(mode, scene.display.parity)?;
            let layers = renderer.read_back_composed()?;
            let suffixes: &[&str] = if layers.len() == 2 { &["-left", "-right"] } else { &[""] };
            for (layer, suffix) in layers.iter().zip(suffixes) {
                let path = options.out_dir.join(format!("{}-{mode}{suffix}.png", capture.name));
                save_png_atomically(layer, &path)?;
                composed.push(path);
            }
        }
        written.push(WrittenCapture {
            name: capture.name.clone(),
            left: left_path,
            right: right_path,
            composed,
        });
    }
    bar.finish_and_clear();
    if let Some(session) = playback.finish_autosave() {
        super::autosave::close_session(session);
    }
    // Dropping the renderer first lets the layer report destruction problems (leaks) too.
    let log = renderer.validation_log();
    drop(renderer);
    let messages = log.take();
    if !messages.is_empty() {
        anyhow::bail!(
            "the Vulkan validation layer reported {} problem(s):\n{}",
            messages.len(),
            messages.join("\n")
        );
    }
    Ok(written)
}

fn progress_bar(show: bool, end_s: f32) -> indicatif::ProgressBar {
    if !show {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new((end_s * 1000.0) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{prefix} [{bar:40}] {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_prefix("sculpting");
    bar.set_message(format!("timeline of {end_s:.2} s"));
    bar
}
