//! The standard workloads of `argile bench`: each yields one JSON object per measurement.
//! The workloads use the other modules as a user of the library would; no other module
//! names this one.

mod io;
mod xr;

use std::time::Instant;

use anyhow::Result;
use serde_json::{json, Value};

use crate::app::{build_frame, renderer_for, Assembly, Playback};
use crate::field::Field;
use crate::math::{IVec3, Vec3};
use crate::mesh::{mesh_all, ChunkMesh, MeshDiff, Mesher};
use crate::render::ViewPasses;
use crate::scene::Scene;
use crate::stereo::display::{DisplayMode, Parity};
use crate::tool::{stamp_sphere, Action, MAX_SIZE_SAMPLES};

/// A standard workload.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Workload {
    /// A straight stroke of sphere stamps of radius 4, 8, 16 and 32 voxels into empty space.
    Stamp,
    /// A stroke of removing sphere stamps of radius 4, 8, 16 and 32 voxels across the surface
    /// of a solid sphere of radius 100 voxels.
    StampCarve,
    /// The same straight stroke into empty space with a 4 mm and a 40 mm sphere tool on a
    /// 1 mm finest level, each editing the level its size chooses (at most
    /// [`crate::tool::MAX_SIZE_SAMPLES`] voxels across its radius), field alone and with the
    /// incremental re-mesh after each stamp, and the 40 mm one on the finest level for
    /// comparison.
    StampAdaptive,
    /// Strokes of 10, 20, 40 and 80 mm sphere tools on a 1 mm finest level, each on the
    /// finest level and editing by its size with at most 8, 16 and 32 voxels across it (the
    /// hand tools' bound, [`crate::tool::HAND_SIZE_SAMPLES`], is chosen from these): the stamp
    /// alone, with the re-mesh after it, and the field's bytes.
    HandTools,
    /// Full extraction of the surface of a solid sphere of radius 100 voxels, of the field a
    /// stroke of radius-16 stamps leaves, and of the coarse clay a short stroke of a 40 mm
    /// tool editing by its size leaves, on one thread and on all.
    MeshFull,
    /// The incremental re-mesh after one stamp of radius 4, 8, 16 and 32 voxels carving the
    /// surface of a sphere; and the same with the sphere the first part of a sculpt of two
    /// (`remesh-stamp-parts`), the composition re-made where the stamp changed it first.
    RemeshStamp,
    /// Stereo frames of the default scene and of a mesh of over a million triangles, with
    /// both eyes in one multiview pass and with one pass per eye.
    RenderStereo,
    /// The per-frame cost of desk input (mailbox drain, calibration, smoothing, integration,
    /// gamepad mapping, trackball) with 1, 2 and 4 SpaceMice and as many gamepads.
    InputFrame,
    /// The display-mode composition pass after a stereo frame of the default scene, in every
    /// display mode: the pass alone and its read-back.
    Compose,
    /// The station's frame on the default scene while the desk tool sculpts, split into input,
    /// tools, mesh, render and composition, in every display mode (offscreen: no present).
    FrameDesktop,
    /// The autosave journal's cost on the sculpting thread per finished stroke (strokes of
    /// radius 8 and 16 voxels carving a sphere), and the strokes' own cost with and without it.
    JournalStroke,
    /// Saving a sculpt of over 10 million samples: MB/s, size on disk against memory.
    SaveLarge,
    /// Loading that sculpt back: MB/s.
    LoadLarge,
    /// Virtual-clay steps per second bending a bar held by a support (Dewaele–Cani §5.1) in
    /// active windows of 32³, 128×32×32 and 128³ cells, with each layer's share of the time.
    ClayBend,
    /// An 8×8×8 cubic B-spline lattice over a 128³ box of 1 mm clay around a bar: opening it
    /// (the copy of the clay and the least-squares fit of its values), and after each drag of
    /// an interior control point the re-evaluation of the clay over the box that drag
    /// changed, then its write into the field.
    LatticeDrag,
    /// A box region of 64³ lattice points of 1 mm clay (a ball filling it) carried and turned
    /// by a hand over frames: each frame's update of the drag, which resamples the region's
    /// source and every place it passes from the clay as it was (the bound: one VR
    /// frame, 11.1 ms).
    RegionMove,
    /// The headset frame against the OpenXR test runtime (built with
    /// `cargo build -p argile-xr-test-runtime`): from `xrWaitFrame` returning to `xrEndFrame`
    /// returning while the right controller carves the default scene, split into the frame's
    /// start (begin, images, input), simulation, meshing and render submission.
    FrameXr,
}

impl Workload {
    /// Every workload, in the order `argile bench` runs them.
    pub const ALL: [Workload; 17] = [
        Workload::Stamp,
        Workload::StampCarve,
        Workload::StampAdaptive,
        Workload::HandTools,
        Workload::MeshFull,
        Workload::RemeshStamp,
        Workload::RenderStereo,
        Workload::InputFrame,
        Workload::Compose,
        Workload::FrameDesktop,
        Workload::JournalStroke,
        Workload::SaveLarge,
        Workload::LoadLarge,
        Workload::ClayBend,
        Workload::LatticeDrag,
        Workload::RegionMove,
        Workload::FrameXr,
    ];
}

/// Sizes of the workloads.
#[derive(Clone, Copy, Debug)]
pub struct BenchSize {
    /// Stamps per stroke.
    pub stamps: usize,
    /// Strokes per radius (the median is reported).
    pub repetitions: usize,
    /// Per-eye image side.
    pub image_px: u32,
    /// Timed frames.
    pub frames: usize,
    /// Triangles the big render mesh reaches at least.
    pub big_mesh_triangles: usize,
    /// Radius of the solid sphere the meshing workloads extract, voxels.
    pub sphere_radius_voxels: f32,
    /// Timed input frames per device set.
    pub input_frames: usize,
    /// Radius of the solid sphere the save and load workloads store, voxels.
    pub large_sphere_radius_voxels: f32,
    /// Timed virtual-clay steps per window.
    pub clay_steps: usize,
    /// Side of the lattice workload's box, voxels.
    pub lattice_side_voxels: i32,
    /// Timed drags of the lattice workload.
    pub lattice_drags: usize,
    /// Side of the region workload's box, lattice points.
    pub region_side: i32,
    /// Timed frames of the region workload.
    pub region_frames: usize,
}

impl BenchSize {
    /// The standard sizes.
    pub const STANDARD: BenchSize = BenchSize {
        stamps: 200,
        repetitions: 5,
        image_px: 1024,
        frames: 20,
        big_mesh_triangles: 1_000_000,
        sphere_radius_voxels: 100.0,
        input_frames: 20_000,
        large_sphere_radius_voxels: 130.0,
        clay_steps: 60,
        lattice_side_voxels: 128,
        lattice_drags: 11,
        region_side: 64,
        region_frames: 45,
    };
    /// A small run that checks the workloads work (not for figures).
    pub const QUICK: BenchSize = BenchSize {
        stamps: 20,
        repetitions: 1,
        image_px: 128,
        frames: 2,
        big_mesh_triangles: 100_000,
        sphere_radius_voxels: 24.0,
        input_frames: 200,
        large_sphere_radius_voxels: 24.0,
        clay_steps: 4,
        lattice_side_voxels: 24,
        lattice_drags: 2,
        region_side: 16,
        region_frames: 3,
    };
}

use crate::math::median;

/// Runs the workloads, handing each result to `emit`.
pub fn run(workloads: &[Workload], size: BenchSize, mut emit: impl FnMut(Value)) -> Result<()> {
    for w in workloads {
        match w {
            Workload::Stamp => bench_stamp(size, &mut emit),
            Workload::StampCarve => bench_stamp_carve(size, &mut emit),
            Workload::StampAdaptive => bench_stamp_adaptive(size, &mut emit),
            Workload::HandTools => bench_hand_tools(size, &mut emit),
            Workload::MeshFull => bench_mesh_full(size, &mut emit)?,
            Workload::RemeshStamp => bench_remesh_stamp(size, &mut emit),
            Workload::RenderStereo => bench_render(size, &mut emit)?,
            Workload::InputFrame => bench_input(size, &mut emit),
            Workload::Compose => bench_compose(size, &mut emit)?,
            Workload::FrameDesktop => bench_frame_desktop(size, &mut emit)?,
            Workload::JournalStroke => io::journal_stroke(size, &mut emit)?,
            Workload::SaveLarge => io::save_large(size, &mut emit)?,
            Workload::LoadLarge => io::load_large(size, &mut emit)?,
            Workload::ClayBend => bench_clay_bend(size, &mut emit),
            Workload::LatticeDrag => bench_lattice_drag(size, &mut emit)?,
            Workload::RegionMove => bench_region_move(size, &mut emit)?,
            Workload::FrameXr => xr::frame_xr(size.image_px, size.frames, &mut emit)?,
        }
    }
    Ok(())
}

/// One stroke of `n` stamps of radius `r` voxels along +X, spacing r/2, into `field` (from
/// `start`, lattice units), re-meshing after each stamp when `remesh`; returns (µs per stamp,
/// triangles re-meshed).
fn stroke_into(
    field: &mut Field,
    start: Vec3,
    n: usize,
    r: f32,
    action: Action,
    remesh: bool,
) -> (f64, usize) {
    let voxel = field.transform().voxel_size_m;
    let mut triangles = 0;
    // One mesher for the stroke, as the station keeps: its buffers are reused.
    let mut mesher = Mesher::default();
    let begin = Instant::now();
    for i in 0..n {
        let centre = (start + Vec3::new(i as f32 * 0.5 * r, 0.0, 0.0)) * voxel;
        stamp_sphere(field, centre, r * voxel, action, [0.7, 0.4, 0.2, 1.0]);
        if remesh {
            triangles += mesher.remesh_dirty(field).upserted_triangles();
        }
    }
    (begin.elapsed().as_secs_f64() * 1e6 / n as f64, triangles)
}

/// A stroke into an empty field; returns (µs per stamp, triangles re-meshed, the field).
fn stroke(n: usize, r: f32, remesh: bool) -> (f64, usize, Field) {
    let mut field = Field::new(0.001, 0.5);
    let (us, triangles) = stroke_into(&mut field, Vec3::ZERO, n, r, Action::Add, remesh);
    (us, triangles, field)
}

/// OpenVDB's narrow-band half width, in voxels (its `LEVEL_SET_HALF_WIDTH`).
const OPENVDB_HALF_WIDTH: f32 = 3.0;

/// Bytes OpenVDB takes per active voxel of a narrow-band level set, as measured for the field
/// issue's peer figures (its `memUsage` of the same strokes).
const OPENVDB_BYTES_PER_ACTIVE_VOXEL: f64 = 13.0;

/// Lattice points within `half_width` voxels of the surface of the union of `n` balls of
/// radius `r` voxels centred at `(k · r/2, 0, 0)`, `k < n`: the active voxels of the stroke
/// of [`stroke`] held as an OpenVDB narrow-band level set.
fn narrow_band_voxels(n: usize, r: f32, half_width: f32) -> usize {
    let (step, last) = (0.5 * r, n.saturating_sub(1) as f32);
    let reach = r + half_width;
    let (x0, x1) = ((-reach).floor() as i32, (last * step + reach).ceil() as i32);
    let across = reach.ceil() as i32;
    let mut count = 0;
    for x in x0..=x1 {
        // The balls are alike, so a point's nearest surface is its nearest centre's, and on a
        // line of centres that is the nearest along x.
        let dx = x as f32 - (x as f32 / step).round().clamp(0.0, last) * step;
        for y in -across..=across {
            for z in -across..=across {
                let distance = (dx * dx + (y * y + z * z) as f32).sqrt() - r;
                count += usize::from(distance.abs() < half_width);
            }
        }
    }
    count
}

fn bench_stamp(size: BenchSize, emit: &mut impl FnMut(Value)) {
    for r in [4.0f32, 8.0, 16.0, 32.0] {
        let field_only: Vec<f64> = (0..size.repetitions).map(|_| stroke(size.stamps, r, false).0).collect();
        let mut remeshed_tris = 0;
        let mut memory = (0, 0);
        let openvdb_voxels = narrow_band_voxels(size.stamps, r, OPENVDB_HALF_WIDTH);
        let with_mesh: Vec<f64> = (0..size.repetitions)
            .map(|_| {
                let (t, tris, field) = stroke(size.stamps, r, true);
                remeshed_tris = tris;
                memory = (field.memory_bytes(), field.band_samples());
                t
            })
            .collect();
        emit(json!({
            "workload": "stamp",
            "radius_voxels": r,
            "stamps": size.stamps,
            "spacing_voxels": r / 2.0,
            "repetitions": size.repetitions,
            "threads": rayon::current_num_threads(),
            "field_us_per_stamp_median": median(field_only),
            "field_and_mesh_us_per_stamp_median": median(with_mesh),
            "remeshed_triangles_per_stroke": remeshed_tris,
            "field_bytes": memory.0,
            "band_samples": memory.1,
            "bytes_per_band_sample": memory.0 as f64 / memory.1.max(1) as f64,
            "openvdb_active_voxels": openvdb_voxels,
            "bytes_per_openvdb_active_voxel": memory.0 as f64 / openvdb_voxels.max(1) as f64,
            "memory_to_openvdb": memory.0 as f64 / (OPENVDB_BYTES_PER_ACTIVE_VOXEL * openvdb_voxels.max(1) as f64),
        }));
    }
}

/// Removing strokes across the surface of a solid sphere of `sphere_radius_voxels`: the line
/// runs along +X through the centre with its midpoint on the surface, so half the stamps cut
/// into the clay and half leave it.
fn bench_stamp_carve(size: BenchSize, emit: &mut impl FnMut(Value)) {
    let sphere = sphere_field(size.sphere_radius_voxels);
    for r in [4.0f32, 8.0, 16.0, 32.0] {
        let length = size.stamps as f32 * 0.5 * r;
        let start = Vec3::new(size.sphere_radius_voxels - 0.5 * length, 0.0, 0.0);
        let mut carved = 0.0;
        let times: Vec<f64> = (0..size.repetitions)
            .map(|_| {
                let mut field = sphere.clone();
                let before = field.mass();
                let (us, _) = stroke_into(&mut field, start, size.stamps, r, Action::Remove, false);
                carved = before - field.mass();
                us
            })
            .collect();
        emit(json!({
            "workload": "stamp-carve",
            "radius_voxels": r,
            "sphere_radius_voxels": size.sphere_radius_voxels,
            "stamps": size.stamps,
            "spacing_voxels": r / 2.0,
            "repetitions": size.repetitions,
            "field_us_per_stamp_median": median(times),
            "carved_samples": carved,
        }));
    }
}

/// Strokes of `size.stamps` sphere stamps along +X, spacing half the radius, into an empty
/// field of 1 mm voxels, with tools of radius 4 mm and 40 mm editing by their size, and the
/// 40 mm one on the finest level: µs per stamp (median, min, max of the repetitions), samples
/// visited and computed, bricks walked, the level written, field memory; the ratio of the
/// 40 mm stroke's time to the 4 mm one's; and for the tools editing by their size, the median
/// µs per stamp with the incremental re-mesh after each stamp and the triangles it upserted.
fn bench_stamp_adaptive(size: BenchSize, emit: &mut impl FnMut(Value)) {
    let run = |radius_m, by_size: bool, remesh| {
        tool_stroke(size.stamps, radius_m, by_size.then_some(MAX_SIZE_SAMPLES), remesh)
    };
    let mut medians = Vec::new();
    for (radius_m, by_size) in [(0.004f32, true), (0.04, true), (0.04, false)] {
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..size.repetitions {
            let (us, counters, _, field) = run(radius_m, by_size, false);
            times.push(us);
            last = Some((counters, field.memory_bytes()));
        }
        let (c, bytes) = last.expect("at least one repetition");
        // With the incremental re-mesh after each stamp, as the station does (not for the
        // 40 mm tool on the finest level: seconds per stroke).
        let mut remeshed = 0;
        let with_mesh: Vec<f64> = if by_size {
            (0..size.repetitions)
                .map(|_| {
                    let (us, _, triangles, _) = run(radius_m, by_size, true);
                    remeshed = triangles;
                    us
                })
                .collect()
        } else {
            Vec::new()
        };
        let (lo, hi) = times.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &t| (lo.min(t), hi.max(t)));
        let med = median(times);
        medians.push(med);
        let n = size.stamps as f64;
        emit(json!({
            "workload": "stamp-adaptive",
            "radius_mm": radius_m * 1000.0,
            "by_size": by_size,
            "level": c.level,
            "stamps": size.stamps,
            "repetitions": size.repetitions,
            "us_per_stamp_median": med,
            "us_per_stamp_min": lo,
            "us_per_stamp_max": hi,
            "visited_per_stamp": c.visited as f64 / n,
            "computed_per_stamp": c.computed as f64 / n,
            "bricks_per_stamp": c.bricks as f64 / n,
            "field_bytes": bytes,
            "ratio_to_4mm": med / medians[0],
            "with_remesh_us_per_stamp_median": (!with_mesh.is_empty()).then(|| median(with_mesh)),
            "remeshed_triangles_per_stroke": remeshed,
        }));
    }
}

/// The hand tools' strokes (see [`Workload::HandTools`]): per radius and bound, µs per stamp
/// (medians of the repetitions) without and with the re-mesh after each stamp, the level
/// written and the field's bytes.
fn bench_hand_tools(size: BenchSize, emit: &mut impl FnMut(Value)) {
    // 80 mm stamps on the finest level take milliseconds each: fewer stamps than the others.
    let stamps = size.stamps.min(30);
    for radius_mm in [10.0f32, 20.0, 40.0, 80.0] {
        for bound in [None, Some(8.0), Some(16.0), Some(32.0)] {
            let timed = |remesh| {
                median(
                    (0..size.repetitions)
                        .map(|_| tool_stroke(stamps, radius_mm * 0.001, bound, remesh).0)
                        .collect(),
                )
            };
            let (field_us, with_remesh_us) = (timed(false), timed(true));
            let (_, counters, _, field) = tool_stroke(stamps, radius_mm * 0.001, bound, false);
            emit(json!({
                "workload": "hand-tools",
                "radius_mm": radius_mm,
                "level_samples": bound,
                "level": counters.level,
                "stamps": stamps,
                "repetitions": size.repetitions,
                "us_per_stamp_median": field_us,
                "with_remesh_us_per_stamp_median": with_remesh_us,
                "field_bytes": field.memory_bytes(),
            }));
        }
    }
}

/// A stroke of `stamps` adding sphere-tool stamps of radius `radius_m` along +X, spacing half
/// the radius, into an empty field of 1 mm voxels, the tool editing the finest level or by its
/// size with at most `level_samples` voxels across it, with or without the incremental re-mesh
/// after each stamp: (µs per stamp, the stamps' counters, triangles re-meshed, the field left).
fn tool_stroke(
    stamps: usize,
    radius_m: f32,
    level_samples: Option<f32>,
    remesh: bool,
) -> (f64, crate::tool::StampCounters, usize, Field) {
    use crate::math::Pose;
    use crate::tool::{apply_tool, StampCounters, Tool, ToolShape};
    let mut field = Field::new(0.001, 0.5);
    let tool =
        Tool { level_samples, ..Tool::new(ToolShape::sphere(radius_m), Action::Add, [0.7, 0.4, 0.2, 1.0]) };
    let mut total = StampCounters::default();
    let mut mesher = Mesher::default();
    let mut triangles = 0;
    let begin = Instant::now();
    for i in 0..stamps {
        let pose = Pose { position_m: Vec3::new(i as f32 * 0.5 * radius_m, 0.0, 0.0), ..Default::default() };
        total += apply_tool(&mut field, &tool, pose, 0.0);
        if remesh {
            triangles += mesher.remesh_dirty(&mut field).upserted_triangles();
        }
    }
    (begin.elapsed().as_secs_f64() * 1e6 / stamps as f64, total, triangles, field)
}

/// A field holding a solid sphere of `radius` voxels (1 mm voxels), centred off the lattice.
pub(super) fn sphere_field(radius: f32) -> Field {
    let mut field = Field::new(0.001, 0.5);
    stamp_sphere(
        &mut field,
        Vec3::new(0.00031, -0.00017, 0.00023),
        radius * 0.001,
        Action::Add,
        [0.7, 0.4, 0.2, 1.0],
    );
    field
}

/// Runs `work` on a pool of `threads` threads.
fn on_threads<T: Send>(threads: usize, work: impl FnOnce() -> T + Send) -> Result<T> {
    Ok(rayon::ThreadPoolBuilder::new().num_threads(threads).build()?.install(work))
}

fn bench_mesh_full(size: BenchSize, emit: &mut impl FnMut(Value)) -> Result<()> {
    let mut stroke_field = Field::new(0.001, 0.5);
    for i in 0..size.stamps {
        let centre = Vec3::new(i as f32 * 0.008, 0.0, 0.0);
        stamp_sphere(&mut stroke_field, centre, 0.016, Action::Add, [0.7, 0.4, 0.2, 1.0]);
    }
    // Coarse clay: a short stroke of a 40 mm tool editing by its size (level 3, 8 mm voxels),
    // meshed on its own level.
    let (_, _, _, coarse_field) = tool_stroke(size.stamps.min(10), 0.04, Some(MAX_SIZE_SAMPLES), false);
    let sphere = sphere_field(size.sphere_radius_voxels);
    for (name, field) in
        [("sphere", &sphere), ("stamp-add-16", &stroke_field), ("stroke-40mm-by-size", &coarse_field)]
    {
        // Stored samples of every level (the coarse stroke stores none on the finest).
        let bricks: usize = (0..crate::field::LEVELS).map(|l| field.level_brick_count(l)).sum();
        let samples = bricks * crate::field::BRICK_VOLUME;
        for threads in [1, rayon::current_num_threads()] {
            let (ms, triangles) = on_threads(threads, || {
                let _ = mesh_all(field);
                let mut triangles = 0;
                let times: Vec<f64> = (0..size.repetitions)
                    .map(|_| {
                        let t = Instant::now();
                        let diff = mesh_all(field);
                        let ms = t.elapsed().as_secs_f64() * 1e3;
                        triangles = diff.upserted_triangles();
                        ms
                    })
                    .collect();
                (median(times), triangles)
            })?;
            emit(json!({
                "workload": "mesh-full",
                "field": name,
                "sphere_radius_voxels": size.sphere_radius_voxels,
                "threads": threads,
                "repetitions": size.repetitions,
                "median_ms": ms,
                "triangles": triangles,
                "stored_samples": samples,
                "stored_samples_per_second": samples as f64 / (ms * 1e-3),
            }));
        }
    }
    Ok(())
}

/// The sphere field `first` (of `radius` voxels at the origin) as the first part of a sculpt of
/// two: the second a ball of 2 mm voxels beside it, turned and scaled, which no stamp reaches.
fn two_part_assembly(first: &Field, radius: f32) -> Assembly {
    use crate::math::Quat;
    use crate::parts::Placement;
    use crate::scene::ScenePart;
    let mut ball = Field::new(0.002, 0.5);
    stamp_sphere(&mut ball, Vec3::ZERO, 0.3 * radius * 0.001, Action::Add, [0.3, 0.5, 0.7, 1.0]);
    ball.take_dirty();
    let placement =
        Placement::new(Quat::from_rotation_y(0.5), Vec3::new(2.0 * radius * 0.001, 0.0, 0.0), 1.2)
            .expect("a finite placement");
    let parts = vec![
        ScenePart::whole(first.transform().voxel_size_m),
        ScenePart { name: "ball".into(), voxel_size_m: 0.002, placement, ..ScenePart::whole(0.002) },
    ];
    Assembly::new(parts, vec![ball], first)
}

fn bench_remesh_stamp(size: BenchSize, emit: &mut impl FnMut(Value)) {
    let radius = size.sphere_radius_voxels;
    for r in [4.0f32, 8.0, 16.0, 32.0] {
        // The sphere alone, then as the first part of a sculpt of two: its surface is then the
        // composition's, re-made where each stamp changed it before the re-mesh.
        for parted in [false, true] {
            let mut field = sphere_field(radius);
            let mut assembly = parted.then(|| two_part_assembly(&field, radius));
            // One mesher for the stroke, as the station keeps: its buffers are reused.
            let mut mesher = Mesher::default();
            match &mut assembly {
                Some(a) => {
                    let surface = a.surface(&mut field);
                    let _ = mesher.mesh_all(surface);
                    surface.take_dirty();
                }
                None => {
                    let _ = mesher.mesh_all(&field);
                    field.take_dirty();
                }
            }
            let stamps = size.stamps.min(100);
            let (mut times, mut composing) = (Vec::with_capacity(stamps), Vec::with_capacity(stamps));
            let (mut bricks, mut surface_dirty) = (0, 0);
            for i in 0..stamps {
                // Carving stamps walking over the sphere's surface, each on fresh clay.
                let angle = i as f32 * 2.0 * r / radius;
                let centre = Vec3::new(angle.cos(), 0.3 * (i as f32 * 0.37).sin(), angle.sin()).normalize()
                    * radius
                    * 0.001;
                stamp_sphere(&mut field, centre, r * 0.001, Action::Remove, [0.0; 4]);
                bricks += field.dirty().len();
                let t = Instant::now();
                let diff = match &mut assembly {
                    Some(a) => {
                        let surface = a.surface(&mut field);
                        composing.push(t.elapsed().as_secs_f64() * 1e6);
                        surface_dirty += surface.dirty().len();
                        mesher.remesh_dirty(surface)
                    }
                    None => mesher.remesh_dirty(&mut field),
                };
                times.push(t.elapsed().as_secs_f64() * 1e6);
                std::hint::black_box(diff);
            }
            emit(json!({
                "workload": if parted { "remesh-stamp-parts" } else { "remesh-stamp" },
                "radius_voxels": r,
                "stamps": stamps,
                "threads": rayon::current_num_threads(),
                "median_us": median(times),
                "dirty_bricks_per_stamp": bricks as f64 / stamps as f64,
                "compose_median_us": if parted { median(composing) } else { 0.0 },
                "surface_dirty_bricks_per_stamp": if parted { surface_dirty } else { bricks } as f64 / stamps as f64,
            }));
        }
    }
}

/// Desk input at 90 frames per second with `spacemice` SpaceMice and `gamepads` pads: before
/// each frame (untimed) the reader's share is simulated by publishing three reports' worth of
/// state per SpaceMouse and, every 45th frame, a button edge; the frame itself (timed) is what
/// the frame loop pays: `DeskInput::update` (drain, calibration, One Euro, integration), the
/// gamepads' mapping and a trackball step.
fn bench_input(size: BenchSize, emit: &mut impl FnMut(Value)) {
    use crate::input::calibration::SpaceMouseCalibration;
    use crate::input::desk::{DeskInput, FrameInput};
    use crate::input::gamepad::{GamepadCalibration, GamepadMapper, GamepadMotion, Source};
    use crate::input::motion::{MappingTable, Rates};
    use crate::input::mouse::{trackball_rotation, TrackballKind};
    use crate::input::reader::{DeviceId, DeviceInfo, Mailbox, ReaderEvent};
    use crate::input::spacemouse::{ButtonChange, SpaceMouseState};
    use crate::math::{Quat, Vec2};

    for (spacemice, gamepads) in [(1usize, 0usize), (2, 2), (4, 4)] {
        let mailbox = Mailbox::new(256);
        let mut desk =
            DeskInput::new(SpaceMouseCalibration::shipped(), MappingTable::default(), Rates::default());
        let pad_calibration = GamepadCalibration::shipped();
        let mut pads = vec![GamepadMapper::default(); gamepads];
        let mut motions = vec![GamepadMotion::default(); gamepads];
        let mut states = vec![SpaceMouseState::default(); spacemice];
        for d in 0..spacemice {
            let info = DeviceInfo { path: format!("bench-{d}"), name: "bench".into() };
            mailbox.push_event(ReaderEvent::Connected { id: DeviceId(d as u64), info });
        }
        let mut actions = Vec::with_capacity(64);
        let dt = 1.0 / 90.0;
        let mut times = Vec::with_capacity(size.input_frames);
        for frame in 0..size.input_frames {
            let phase = frame as f32 * 0.05;
            for (d, state) in states.iter_mut().enumerate() {
                for k in 0..3 {
                    let v = ((phase + (d + k) as f32 * 0.3).sin() * 300.0) as i16;
                    state.axes.0 = [v, -v / 2, v / 3, v / 4, -v, v / 5];
                    mailbox.publish_state(DeviceId(d as u64), *state);
                }
                if frame % 45 == 0 {
                    let buttons = state.buttons ^ 1;
                    let change = ButtonChange {
                        pressed: buttons & !state.buttons,
                        released: state.buttons & !buttons,
                    };
                    state.buttons = buttons;
                    mailbox.push_event(ReaderEvent::Buttons { id: DeviceId(d as u64), change, buttons });
                }
            }
            actions.clear();
            let start = Instant::now();
            for (p, (pad, motion)) in pads.iter_mut().zip(motions.iter_mut()).enumerate() {
                pad.set_value(Source::LeftStickX, (phase + p as f32).sin());
                pad.set_value(Source::RightStickY, (phase * 0.7).cos());
                *motion = pad.motion(&pad_calibration);
            }
            let from = Vec2::new(phase.sin() * 0.5, 0.1);
            let turn = trackball_rotation(from, from + Vec2::new(0.01, 0.0), TrackballKind::Shoemake);
            let input = FrameInput {
                t_s: f64::from(frame as u32) * f64::from(dt),
                dt_s: dt,
                view_rotation: Quat::IDENTITY,
                gamepads: &motions,
                mouse_turn: turn,
            };
            desk.update(Some(&mailbox), &input, &mut actions);
            times.push(start.elapsed().as_secs_f64() * 1e6);
        }
        let sorted = {
            let mut t = times.clone();
            t.sort_by(f64::total_cmp);
            t
        };
        let p99 = sorted.get(sorted.len() * 99 / 100).copied().unwrap_or(f64::NAN);
        emit(json!({
            "workload": "input-frame",
            "spacemice": spacemice,
            "gamepads": gamepads,
            "mouse": true,
            "frames": size.input_frames,
            "us_per_frame_median": median(times),
            "us_per_frame_p99": p99,
            "tool_moved_m": desk.poses.get(crate::input::motion::Target::Tool).position_m.length(),
        }));
    }
}

/// The bend of Dewaele–Cani §5.1 in a window of `dims` cells (1 mm voxels): a bar along X,
/// 3/4 of the window long, of radius a sixth of its smaller cross extent, rests on a support
/// block under its left third; a ball of the bar's radius pushes its right end down by a
/// voxel every two steps. Reports steps per second once the ball touches the bar, and how
/// many of the steps passed the ball's motion on to the clay (once per voxel travelled).
fn bench_clay_bend(size: BenchSize, emit: &mut impl FnMut(Value)) {
    use crate::clay::{Clay, ClayParams, ClayTool};
    use crate::math::Pose;
    use crate::tool::{rasterize_solid, CsgOp, PlacedSolid, Solid, ToolShape};

    let h = 0.001;
    for (name, dims) in
        [("32", IVec3::splat(32)), ("128x32x32", IVec3::new(128, 32, 32)), ("128", IVec3::splat(128))]
    {
        let d = dims.as_vec3();
        let radius = (d.y.min(d.z) / 6.0).floor();
        let half_length = 0.375 * d.x;
        let mut field = Field::new(h, 0.5);
        let bar = Solid::Bar { half_length_m: half_length * h, radius_m: radius * h };
        rasterize_solid(
            &mut field,
            &PlacedSolid { solid: bar, pose: Pose::default(), scale: 1.0 },
            CsgOp::Union,
            [0.7, 0.4, 0.2, 1.0],
        );
        let at = |x: f32, y: f32| Pose { position_m: Vec3::new(x, y, 0.0) * h, ..Pose::default() };
        // The bar's axis sits a third of the way down the window, so that its end has room.
        let lo = IVec3::new(-dims.x / 2, -2 * dims.y / 3, -dims.z / 2);
        let hi = lo + dims - IVec3::ONE;
        let support_half = Vec3::new(half_length / 3.0, radius, radius * 1.5);
        let support = ClayTool::support(
            ToolShape::Solid(Solid::Box { half_m: support_half * h }),
            Vec3::ONE,
            at(-half_length + support_half.x, -2.0 * radius),
        );
        let x_push = half_length - radius;
        let y0 = 2.0 * radius + 1.0;
        let pusher = ClayTool::pusher(ToolShape::sphere(radius * h), Vec3::ONE, at(x_push, y0));
        let mut clay = Clay::new(&field, lo, hi, vec![support, pusher], ClayParams::default());
        let mass0 = clay.mass();
        // Into contact, untimed.
        let mut y = y0;
        for _ in 0..4 {
            y -= 0.5;
            clay.step(&[Pose::default(), at(x_push, y)]);
        }
        let before = clay.times();
        let start = Instant::now();
        for _ in 0..size.clay_steps {
            y -= 0.5;
            clay.step(&[Pose::default(), at(x_push, y)]);
        }
        let seconds = start.elapsed().as_secs_f64();
        let t = clay.times();
        let layers = [
            t.bodies_s - before.bodies_s,
            t.displace_s - before.displace_s,
            t.conserve_s - before.conserve_s,
            t.tension_s - before.tension_s,
        ];
        let total: f64 = layers.iter().sum::<f64>().max(1e-12);
        emit(json!({
            "workload": "clay-bend",
            "window": name,
            "cells": dims.x * dims.y * dims.z,
            "bar_radius_voxels": radius,
            "steps": size.clay_steps,
            "threads": rayon::current_num_threads(),
            "steps_per_second": size.clay_steps as f64 / seconds,
            "share_bodies": layers[0] / total,
            "share_displacement": layers[1] / total,
            "share_conservation": layers[2] / total,
            "share_tension": layers[3] / total,
            "conservation_pops_per_step": (t.conserve_pops - before.conserve_pops) as f64 / size.clay_steps as f64,
            "displacement_steps": t.displacements - before.displacements,
            "mass_drift": (clay.mass() - mass0) / mass0,
        }));
    }
}

fn bench_lattice_drag(size: BenchSize, emit: &mut impl FnMut(Value)) -> Result<()> {
    use crate::lattice::{Lattice, LatticeSpec};
    use crate::math::{Aabb, Pose};
    use crate::tool::{rasterize_solid, CsgOp, PlacedSolid, Solid};

    let h = 0.001;
    let side = size.lattice_side_voxels;
    let half = 0.5 * side as f32 * h;
    let mut field = Field::new(h, 0.5);
    let bar = Solid::Bar { half_length_m: 0.8 * half, radius_m: 0.2 * half };
    rasterize_solid(
        &mut field,
        &PlacedSolid { solid: bar, pose: Pose::default(), scale: 1.0 },
        CsgOp::Union,
        [0.7, 0.4, 0.2, 1.0],
    );
    let region = Aabb { min: Vec3::splat(-half), max: Vec3::splat(half - h) };
    let spec = LatticeSpec::cubic(region, [8, 8, 8]);
    let start = Instant::now();
    let mut lattice = Lattice::open(&field, &spec)?;
    let open_s = start.elapsed().as_secs_f64();
    let opened = lattice.open_times();
    let ijk = [3, 4, 4];
    let rest = lattice.volume().control(3, 4, 4)?.position_m;
    let (mut update_ms, mut dense_ms, mut updates, mut dense) = (Vec::new(), Vec::new(), Vec::new(), None);
    let mut densities = Vec::new();
    field.begin_stroke();
    for drag in 0..size.lattice_drags {
        // Up and down by a sixth of the box's side and back: a drag of the point through the bar.
        let lift = [1.0, -1.0, 0.5][drag % 3] * side as f32 * h / 6.0;
        let changed = lattice.move_control(ijk, rest + Vec3::new(0.0, lift, 0.0))?;
        // The update the station makes each frame: the changed box re-evaluated and written.
        let t = Instant::now();
        updates.push(lattice.write(&mut field, changed)?);
        update_ms.push(t.elapsed().as_secs_f64() * 1e3);
        // For comparison: every sample of the changed box evaluated one by one.
        let (lo, hi) = lattice.points_of(changed);
        let t = Instant::now();
        dense = Some(lattice.evaluate(lo, hi, &mut densities, None));
        dense_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    field.end_stroke();
    let fit = lattice.fit_report();
    let dense = dense.unwrap_or_default();
    let per_update = |f: fn(&crate::lattice::LatticeStats) -> f64| median(updates.iter().map(f).collect());
    emit(json!({
        "workload": "lattice-drag",
        "box_voxels": side,
        "controls": [8, 8, 8],
        "order": 4,
        "threads": rayon::current_num_threads(),
        "open_ms": open_s * 1e3,
        "copy_ms": opened.copy_s * 1e3,
        "fit_ms": opened.fit_s * 1e3,
        "fit_samples": fit.samples,
        "fit_rms_error": fit.rms_error,
        "drags": size.lattice_drags,
        "update_ms_median": median(update_ms),
        "update_written_median": per_update(|s| s.written as f64),
        "update_bricks_median": per_update(|s| s.bricks as f64),
        "update_evaluated_median": per_update(|s| s.points as f64),
        "update_searched_median": per_update(|s| s.searched as f64),
        "points_per_drag": dense.points,
        "dense_evaluate_ms_median": median(dense_ms),
        "dense_searched_per_drag": dense.searched,
        "newton_iterations_per_point": dense.newton_iterations as f64 / dense.points.max(1) as f64,
    }));
    Ok(())
}

fn bench_region_move(size: BenchSize, emit: &mut impl FnMut(Value)) -> Result<()> {
    use crate::math::{Pose, Quat};
    use crate::parts::{Motion, Region, RegionDrag, RegionOp};
    use crate::tool::{rasterize_solid, CsgOp, PlacedSolid, Solid, SOLID_BAND_VOXELS};

    let h = 0.001;
    // The box's lattice points: side + 1 across, with the band's half inside it.
    let half = 0.5 * (size.region_side as f32 - 1.0 - SOLID_BAND_VOXELS) * h;
    let mut field = Field::new(h, 0.5);
    let ball = Solid::Sphere { radius_m: 0.9 * half };
    rasterize_solid(
        &mut field,
        &PlacedSolid { solid: ball, pose: Pose::default(), scale: 1.0 },
        CsgOp::Union,
        [0.7, 0.4, 0.2, 1.0],
    );
    let region = Region::boxed(Pose::default(), Vec3::splat(half));
    let start = Instant::now();
    field.begin_stroke();
    let mut drag = RegionDrag::start(&field, region, RegionOp::Move, &[])?;
    let start_ms = start.elapsed().as_secs_f64() * 1e3;
    let (mut update_ms, mut written, mut evaluated) = (Vec::new(), 0u64, 0u64);
    let mut copied = 0u64;
    for frame in 0..size.region_frames {
        // A hand carrying the region 2 mm a frame along a gentle arc, turning it as it goes.
        let s = (frame + 1) as f32;
        let motion = Motion {
            translation_m: Vec3::new(0.002 * s, 0.0005 * s, 0.0),
            rotation: Quat::from_rotation_y(0.01 * s),
            ..Motion::still(Vec3::ZERO)
        };
        let t = Instant::now();
        let stats = drag.update(&mut field, motion)?;
        update_ms.push(t.elapsed().as_secs_f64() * 1e3);
        written = stats.written;
        evaluated = stats.evaluated;
        copied = stats.copied;
    }
    field.end_stroke();
    emit(json!({
        "workload": "region-move",
        "region_points": size.region_side.pow(3),
        "frames": size.region_frames,
        "threads": rayon::current_num_threads(),
        "start_ms": start_ms,
        "written_per_frame": written,
        "evaluated_per_frame": evaluated,
        "copied_points": copied,
        "update_ms_median": median(update_ms.clone()),
        "update_ms_max": update_ms.iter().copied().fold(0.0, f64::max),
    }));
    Ok(())
}

/// Copies of `mesh` on a square grid on the XZ plane until the total reaches `triangles`.
fn replicate(mesh: &MeshDiff, triangles: usize, spacing_m: f32) -> (MeshDiff, f32) {
    let per_copy = mesh.upserted_triangles().max(1);
    let copies = triangles.div_ceil(per_copy);
    let side = (copies as f64).sqrt().ceil() as i32;
    let mut out = MeshDiff::default();
    let mut made = 0;
    'grid: for gz in 0..side {
        for gx in 0..side {
            if made == copies {
                break 'grid;
            }
            let offset = Vec3::new(gx as f32 - (side - 1) as f32 * 0.5, 0.0, -(gz as f32)) * spacing_m;
            // Keys far apart so that copies never share a chunk key.
            let key_offset = IVec3::new(gx * 4096, 0, gz * 4096);
            for (key, chunk) in &mesh.upserted {
                let mut c: ChunkMesh = chunk.clone();
                for v in &mut c.vertices {
                    v.position = (Vec3::from(v.position) + offset).to_array();
                }
                out.upserted.push((*key + key_offset, c));
            }
            made += 1;
        }
    }
    (out, side as f32 * spacing_m)
}

fn bench_render(size: BenchSize, emit: &mut impl FnMut(Value)) -> Result<()> {
    let mut scene = Scene::default_scene();
    scene.output.width_px = size.image_px;
    scene.output.height_px = size.image_px;
    let mut playback = Playback::new(&scene);
    let end = scene.captures.last().map_or(0.0, |c| c.time_s);
    playback.advance_to(end, |_| {});
    let sculpt = mesh_all(playback.field());
    let hands = playback.hands();
    let (big, extent) = replicate(&sculpt, size.big_mesh_triangles, 0.3);

    // Both ways of drawing the eyes, each in a renderer of its own, so that their ratio is
    // measured in one run.
    for view_passes in [ViewPasses::Joint, ViewPasses::Split] {
        let mut renderer = renderer_for(&scene, None, false, Some(view_passes))?;
        for (name, diff, frame_scene) in [
            ("default", &sculpt, scene.clone()),
            ("million-triangles", &big, {
                let mut s = scene.clone();
                s.rig.eye_m = Vec3::new(0.0, extent * 0.6, extent * 0.55);
                s.rig.target_m = Vec3::new(0.0, 0.0, -extent * 0.45);
                s.rig.convergence_m = (s.rig.target_m - s.rig.eye_m).length();
                s.rig.far_m = extent * 4.0;
                s.stage = None;
                s
            }),
        ] {
            // Replace whatever the previous mesh left.
            let clear = MeshDiff {
                removed: sculpt.upserted.iter().chain(&big.upserted).map(|(k, _)| *k).collect(),
                ..MeshDiff::default()
            };
            renderer.apply(&clear)?;
            renderer.apply(diff)?;
            let frame = build_frame(&frame_scene, &hands, true);
            for _ in 0..3 {
                renderer.draw(&frame)?;
            }
            let mut frame_ms = Vec::with_capacity(size.frames);
            for _ in 0..size.frames {
                let t = Instant::now();
                renderer.draw(&frame)?;
                frame_ms.push(t.elapsed().as_secs_f64() * 1e3);
            }
            let mut readback_ms = Vec::new();
            for _ in 0..size.frames.min(5) {
                let t = Instant::now();
                renderer.read_back()?;
                readback_ms.push(t.elapsed().as_secs_f64() * 1e3);
            }
            let min_frame = frame_ms.iter().copied().fold(f64::INFINITY, f64::min);
            emit(json!({
                "workload": "render-stereo",
                "scene": name,
                "device": renderer.device_name(),
                "view_passes": match view_passes {
                    ViewPasses::Joint => "joint",
                    ViewPasses::Split => "split",
                },
                "width_px": size.image_px,
                "height_px": size.image_px,
                "eyes": 2,
                "samples": scene.output.samples,
                "triangles": renderer.triangle_count(),
                "frames": size.frames,
                "median_frame_ms": median(frame_ms),
                "min_frame_ms": min_frame,
                "median_readback_ms": median(readback_ms),
            }));
        }
    }
    Ok(())
}

/// The composition pass in every display mode, after one stereo frame of the default scene at
/// `image_px` per eye. Each timed composition is recorded, submitted and waited for on its own
/// (as the offscreen renderer runs it), so the figure includes one submission's overhead.
fn bench_compose(size: BenchSize, emit: &mut impl FnMut(Value)) -> Result<()> {
    let mut scene = Scene::default_scene();
    scene.output.width_px = size.image_px;
    scene.output.height_px = size.image_px;
    let mut playback = Playback::new(&scene);
    let end = scene.captures.last().map_or(0.0, |c| c.time_s);
    playback.advance_to(end, |_| {});
    let mut renderer = renderer_for(&scene, None, false, None)?;
    renderer.apply(&mesh_all(playback.field()))?;
    let frame = build_frame(&scene, &playback.hands(), true);
    renderer.draw(&frame)?;
    let timed = |run: &mut dyn FnMut() -> Result<()>| -> Result<f64> {
        let mut ms = Vec::with_capacity(size.frames);
        for _ in 0..size.frames {
            let t = Instant::now();
            run()?;
            ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
        Ok(median(ms))
    };
    let draw_ms = timed(&mut || Ok(renderer.draw(&frame)?))?;
    for mode in DisplayMode::ALL {
        // The first composition makes the mode's output image.
        renderer.compose(mode, Parity::LeftEven)?;
        let compose_ms = timed(&mut || Ok(renderer.compose(mode, Parity::LeftEven)?))?;
        let readback_ms = timed(&mut || Ok(renderer.read_back_composed().map(drop)?))?;
        let (width, height) = mode.output_size((size.image_px, size.image_px));
        emit(json!({
            "workload": "compose",
            "mode": mode.name(),
            "device": renderer.device_name(),
            "eye_width_px": size.image_px,
            "eye_height_px": size.image_px,
            "output_width_px": width,
            "output_height_px": height,
            "output_layers": mode.layers(),
            "frames": size.frames,
            "median_compose_ms": compose_ms,
            "median_readback_ms": readback_ms,
            "median_stereo_frame_ms": draw_ms,
        }));
    }
    Ok(())
}

/// The station's frame, offscreen, for a window of `image_px` × `image_px` in every display
/// mode but quad-buffer: the desk tool (the default scene's first tool) carves while it moves
/// right, so every frame stamps, re-meshes and uploads. Medians of each stage; the swapchain's
/// present is not part of an offscreen frame.
fn bench_frame_desktop(size: BenchSize, emit: &mut impl FnMut(Value)) -> Result<()> {
    use crate::app::{Station, SCRIPTED_STEP_S};
    use crate::config::KeyBindings;
    use winit::keyboard::KeyCode;
    let scene = Scene::default_scene();
    let window = (size.image_px, size.image_px);
    for mode in DisplayMode::ALL.into_iter().filter(|m| m.layers() == 1) {
        let mut station = Station::new(&scene, KeyBindings::shipped(), window, "unused.argile".into());
        station.set_surface(mode, "offscreen", 1)?;
        station.set_panel_shown(true);
        let eye = mode.eye_size_for_output(window);
        let mut renderer = renderer_for(&scene, Some(eye), false, None)?;
        renderer.apply(&mesh_all(station.field()))?;
        station.key(KeyCode::Space, true);
        station.key(KeyCode::ArrowRight, true);
        let mut stages: [Vec<f64>; 8] = Default::default();
        for frame_index in 0..size.frames + 2 {
            let started = Instant::now();
            let mut failed = None;
            let mut upload_ms = 0.0;
            let frame = station.step(SCRIPTED_STEP_S, |diff| {
                let t = Instant::now();
                if let Err(e) = renderer.apply(diff) {
                    failed = Some(e);
                }
                upload_ms = t.elapsed().as_secs_f64() * 1e3;
            });
            if let Some(e) = failed {
                return Err(e.into());
            }
            let t = Instant::now();
            renderer.draw(&frame)?;
            let render_ms = t.elapsed().as_secs_f64() * 1e3;
            let t = Instant::now();
            renderer.compose(mode, Parity::LeftEven)?;
            let compose_ms = t.elapsed().as_secs_f64() * 1e3;
            let total_ms = started.elapsed().as_secs_f64() * 1e3;
            // The first frames make the mode's pipeline and output image.
            if frame_index >= 2 {
                let times = station.times();
                for (v, x) in stages.iter_mut().zip([
                    times.panel_ms,
                    times.input_ms,
                    times.tools_ms,
                    times.mesh_ms - upload_ms,
                    upload_ms,
                    render_ms,
                    compose_ms,
                    total_ms,
                ]) {
                    v.push(x);
                }
            }
        }
        let [panel, input, tools, mesh, upload, render, compose, total] = stages.map(median);
        emit(json!({
            "workload": "frame-desktop",
            "mode": mode.name(),
            "device": renderer.device_name(),
            "window_px": [window.0, window.1],
            "eye_px": [eye.0, eye.1],
            "frames": size.frames,
            "median_panel_ms": panel,
            "median_input_ms": input,
            "median_tools_ms": tools,
            "median_mesh_ms": mesh,
            "median_upload_ms": upload,
            "median_render_ms": render,
            "median_compose_ms": compose,
            "median_frame_ms": total,
            "present": "not measured offscreen",
        }));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_workload_runs_by_default() {
        for w in <Workload as clap::ValueEnum>::value_variants() {
            assert!(Workload::ALL.contains(w), "{w:?} is missing from Workload::ALL");
        }
    }

    /// Needs the OpenXR test runtime (built with the tests) and a Vulkan device.
    #[test]
    fn the_headset_frame_is_split_into_its_parts_against_the_test_runtime() {
        let mut lines = Vec::new();
        run(&[Workload::FrameXr], BenchSize::QUICK, |v| lines.push(v)).unwrap();
        assert_eq!(lines.len(), 1);
        let l = &lines[0];
        let part = |k: &str| l[k].as_f64().unwrap_or_else(|| panic!("{k} in {l}"));
        let parts = [
            "median_frame_start_ms",
            "median_simulation_ms",
            "median_meshing_ms",
            "median_render_submission_ms",
        ];
        assert!(parts.iter().all(|k| part(k) >= 0.0), "{l}");
        assert!(part("median_render_submission_ms") > 0.0 && part("median_frame_ms") > 0.0, "{l}");
        assert_eq!(l["frames"], BenchSize::QUICK.frames as u64, "{l}");
    }

    #[test]
    fn the_desktop_frame_is_split_into_its_stages_in_every_flat_display_mode() {
        let mut lines = Vec::new();
        run(&[Workload::FrameDesktop], BenchSize::QUICK, |v| lines.push(v)).unwrap();
        assert_eq!(lines.len(), DisplayMode::ALL.len() - 1, "every mode but quad-buffer");
        for l in &lines {
            let stage = |k: &str| l[k].as_f64().unwrap_or_else(|| panic!("{k} in {l}"));
            let parts: f64 = [
                "median_input_ms",
                "median_tools_ms",
                "median_mesh_ms",
                "median_upload_ms",
                "median_render_ms",
                "median_compose_ms",
            ]
            .iter()
            .map(|k| stage(k))
            .sum();
            assert!(stage("median_tools_ms") > 0.0, "the desk tool carves every frame: {l}");
            assert!(stage("median_render_ms") > 0.0 && stage("median_compose_ms") > 0.0, "{l}");
            // Medians of parts need not add up exactly to the median total, but come close.
            assert!(parts <= 1.5 * stage("median_frame_ms") + 1.0, "{l}");
        }
    }

    #[test]
    fn replication_reaches_the_triangle_count_with_distinct_keys() {
        let scene = Scene::default_scene();
        let sculpt = mesh_all(Playback::new(&scene).field());
        let (big, _) = replicate(&sculpt, 3 * sculpt.upserted_triangles() + 1, 0.3);
        assert_eq!(big.upserted_triangles(), 4 * sculpt.upserted_triangles());
        let mut keys: Vec<[i32; 3]> = big.upserted.iter().map(|(k, _)| k.to_array()).collect();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), big.upserted.len());
    }

    #[test]
    fn meshing_workloads_report_triangles_and_times() {
        let mut lines = Vec::new();
        run(&[Workload::MeshFull, Workload::RemeshStamp], BenchSize::QUICK, |v| lines.push(v)).unwrap();
        let full: Vec<_> = lines.iter().filter(|l| l["workload"] == "mesh-full").collect();
        assert_eq!(full.len(), 6, "three fields, one thread and all");
        assert!(full
            .iter()
            .all(|l| l["triangles"].as_u64().unwrap() > 1000 && l["median_ms"].as_f64().unwrap() > 0.0));
        for name in ["remesh-stamp", "remesh-stamp-parts"] {
            let remesh: Vec<_> = lines.iter().filter(|l| l["workload"] == name).collect();
            assert_eq!(remesh.len(), 4, "{name}");
            assert!(remesh.iter().all(|l| l["dirty_bricks_per_stamp"].as_f64().unwrap() >= 1.0), "{name}");
            assert!(remesh.iter().all(|l| l["median_us"].as_f64().unwrap() > 0.0), "{name}");
        }
    }

    #[test]
    fn input_workload_reports_every_device_set_and_moves_the_tool() {
        let mut lines = Vec::new();
        run(&[Workload::InputFrame], BenchSize::QUICK, |v| lines.push(v)).unwrap();
        assert_eq!(lines.len(), 3);
        for l in &lines {
            assert_eq!(l["workload"], "input-frame");
            assert!(l["us_per_frame_median"].as_f64().unwrap() > 0.0);
            assert!(l["tool_moved_m"].as_f64().unwrap() > 0.0, "the SpaceMice moved the tool: {l}");
        }
    }

    #[test]
    fn the_region_workload_reports_its_updates() {
        let mut lines = Vec::new();
        run(&[Workload::RegionMove], BenchSize::QUICK, |v| lines.push(v)).unwrap();
        let l = &lines[0];
        assert_eq!(l["workload"], "region-move");
        assert!(l["written_per_frame"].as_u64().unwrap() > 4096, "{l}");
        assert!(l["update_ms_median"].as_f64().unwrap() > 0.0, "{l}");
    }

    #[test]
    fn the_lattice_workload_reports_its_fit_and_drags() {
        let mut lines = Vec::new();
        run(&[Workload::LatticeDrag], BenchSize::QUICK, |v| lines.push(v)).unwrap();
        let l = &lines[0];
        assert_eq!(l["workload"], "lattice-drag");
        assert!(l["points_per_drag"].as_u64().unwrap() > 0, "{l}");
        assert!(l["update_ms_median"].as_f64().unwrap() > 0.0 && l["fit_ms"].as_f64().unwrap() > 0.0, "{l}");
        assert!(l["newton_iterations_per_point"].as_f64().unwrap() > 0.0, "{l}");
        // The update writes the drag and evaluates fewer points than the changed box holds.
        assert!(l["update_written_median"].as_f64().unwrap() > 0.0, "{l}");
        assert!(
            l["update_evaluated_median"].as_f64().unwrap() < l["points_per_drag"].as_f64().unwrap(),
            "{l}"
        );
    }

    #[test]
    fn clay_workload_reports_every_window_and_keeps_the_mass() {
        let mut lines = Vec::new();
        run(&[Workload::ClayBend], BenchSize::QUICK, |v| lines.push(v)).unwrap();
        assert_eq!(lines.len(), 3);
        for l in &lines {
            assert_eq!(l["workload"], "clay-bend");
            assert!(l["steps_per_second"].as_f64().unwrap() > 0.0);
            assert!(l["share_displacement"].as_f64().unwrap() > 0.0, "the ball moves the bar: {l}");
            assert!(l["mass_drift"].as_f64().unwrap().abs() < 1e-3, "{l}");
        }
    }

    #[test]
    fn the_hand_tools_report_each_size_and_bound_with_the_level_it_chooses() {
        let mut lines = Vec::new();
        run(&[Workload::HandTools], BenchSize::QUICK, |v| lines.push(v)).unwrap();
        assert_eq!(lines.len(), 16);
        let level = |mm: f64, bound: Option<f64>| {
            let l = lines
                .iter()
                .find(|l| l["radius_mm"].as_f64() == Some(mm) && l["level_samples"].as_f64() == bound)
                .unwrap_or_else(|| panic!("{mm} mm, {bound:?}"));
            assert!(l["us_per_stamp_median"].as_f64().unwrap() > 0.0, "{l}");
            assert!(l["with_remesh_us_per_stamp_median"].as_f64().unwrap() > 0.0, "{l}");
            (l["level"].as_u64().unwrap(), l["field_bytes"].as_u64().unwrap())
        };
        // 1 mm voxels: a 40 mm ball spans 40 of them.
        assert_eq!([None, Some(8.0), Some(16.0), Some(32.0)].map(|b| level(40.0, b).0), [0, 3, 2, 1]);
        assert_eq!([None, Some(8.0), Some(16.0), Some(32.0)].map(|b| level(10.0, b).0), [0, 1, 0, 0]);
        // A coarser level stores less of the large tool's stroke.
        assert!(level(80.0, Some(32.0)).1 < level(80.0, None).1 / 4);
    }

    #[test]
    fn the_adaptive_stroke_reports_both_tools_and_their_levels() {
        let mut lines = Vec::new();
        run(&[Workload::StampAdaptive], BenchSize::QUICK, |v| lines.push(v)).unwrap();
        let levels: Vec<u64> = lines.iter().map(|l| l["level"].as_u64().unwrap()).collect();
        assert_eq!(levels, [0, 3, 0]);
        for l in &lines {
            assert_eq!(l["workload"], "stamp-adaptive");
            assert!(
                l["us_per_stamp_median"].as_f64().unwrap() > 0.0 && l["field_bytes"].as_u64().unwrap() > 0
            );
        }
        // The tools editing by their size are also timed with the re-mesh after each stamp.
        for l in &lines[..2] {
            assert!(l["with_remesh_us_per_stamp_median"].as_f64().unwrap() > 0.0, "{l}");
            assert!(l["remeshed_triangles_per_stroke"].as_u64().unwrap() > 0, "{l}");
        }
        assert!(lines[2]["with_remesh_us_per_stamp_median"].is_null());
        // The finest-level 40 mm stroke computes far more samples than the one its size levels
        // (it computes only those within the ball's reach, that one its whole box).
        let computed = |i: usize| lines[i]["computed_per_stamp"].as_f64().unwrap();
        assert!(computed(2) > 50.0 * computed(1), "{} against {}", computed(2), computed(1));
    }

    #[test]
    fn the_narrow_band_of_a_ball_is_its_shell() {
        // The lattice points within 3 voxels of a sphere of radius r: about its shell's volume.
        let shell = |r: f64| 4.0 / 3.0 * std::f64::consts::PI * ((r + 3.0).powi(3) - (r - 3.0).powi(3));
        let got = narrow_band_voxels(1, 20.0, 3.0) as f64;
        assert!((got / shell(20.0) - 1.0).abs() < 0.01, "{got} against {}", shell(20.0));
        // A line of balls: about a capsule's, its side 2π r L times the band's width and its
        // two half-ball ends one ball's shell.
        let (n, r) = (100, 8.0);
        let length = (n - 1) as f64 * r / 2.0;
        let capsule = 2.0 * std::f64::consts::PI * r * length * 6.0 + shell(r);
        let got = narrow_band_voxels(n, r as f32, 3.0) as f64;
        assert!((got / capsule - 1.0).abs() < 0.03, "{got} against {capsule}");
    }

    #[test]
    fn stamp_workload_reports_every_radius() {
        let mut lines = Vec::new();
        run(&[Workload::Stamp, Workload::StampCarve], BenchSize::QUICK, |v| lines.push(v)).unwrap();
        assert_eq!(lines.len(), 8);
        for l in &lines[..4] {
            assert!(l["field_us_per_stamp_median"].as_f64().unwrap() > 0.0);
            assert!(l["remeshed_triangles_per_stroke"].as_u64().unwrap() > 0);
            let per_sample = l["bytes_per_band_sample"].as_f64().unwrap();
            // A band sample is a stored sample, and every stored sample's density takes 2 bytes.
            assert!(per_sample > 2.0, "every stored sample costs 2 bytes: {per_sample}");
            let to_openvdb = l["memory_to_openvdb"].as_f64().unwrap();
            assert!(to_openvdb > 0.0 && to_openvdb.is_finite(), "{l}");
        }
        for l in &lines[4..] {
            assert_eq!(l["workload"], "stamp-carve");
            assert!(l["carved_samples"].as_f64().unwrap() > 0.0, "the stroke crosses the clay: {l}");
        }
    }
}
