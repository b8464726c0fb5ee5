//! `argile bench` workloads of the sculpt file and the autosave journal.

use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use serde_json::{json, Value};

use super::{median, sphere_field, BenchSize};
use crate::app::load_sculpt_with_progress;
use crate::field::Field;
use crate::io::autosave::{Autosave, AutosaveConfig, LocalDisk};
use crate::io::{encode, write_atomically};
use crate::math::Vec3;
use crate::tool::{stamp_sphere, Action};

/// A scratch folder for one workload, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Result<Self> {
        let dir = std::env::temp_dir().join(format!("argile-bench-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
        Ok(Self(dir))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Stroke `k` of `stamps` removing stamps of radius `r` voxels, tangent to the sphere of
/// radius `sphere_r` voxels at an angle that turns with `k`, so strokes touch fresh bricks.
fn carve_stroke(field: &mut Field, k: usize, stamps: usize, r: f32, sphere_r: f32) {
    let voxel = field.transform().voxel_size_m;
    let a = k as f32 * 0.7;
    let (on, along) = (Vec3::new(a.cos(), 0.0, a.sin()) * sphere_r, Vec3::new(-a.sin(), 0.0, a.cos()));
    let start = on - along * (stamps as f32 * 0.25 * r);
    field.begin_stroke();
    for i in 0..stamps {
        let centre = (start + along * (i as f32 * 0.5 * r)) * voxel;
        stamp_sphere(field, centre, r * voxel, Action::Remove, [0.7, 0.4, 0.2, 1.0]);
    }
    field.end_stroke();
}

pub(super) fn journal_stroke(size: BenchSize, emit: &mut impl FnMut(Value)) -> Result<()> {
    let scratch = Scratch::new("journal")?;
    let sphere = sphere_field(size.sphere_radius_voxels);
    let strokes = 10 * size.repetitions;
    let stamps = (size.stamps / 10).max(2);
    for r in [8.0f32, 16.0] {
        let mut field = sphere.clone();
        let mut bricks = Vec::new();
        let plain: Vec<f64> = (0..strokes)
            .map(|k| {
                let begin = Instant::now();
                carve_stroke(&mut field, k, stamps, r, size.sphere_radius_voxels);
                let us = begin.elapsed().as_secs_f64() * 1e6;
                bricks.push(field.take_changed_bricks().len() as f64);
                us
            })
            .collect();

        let mut field = sphere.clone();
        let config =
            AutosaveConfig { checkpoint_interval: Duration::from_secs(3600), ..AutosaveConfig::default() };
        let mut autosave =
            Autosave::start(&scratch.0, &mut field, None, "bench", config, Arc::new(LocalDisk))?;
        let mut journaled = Vec::new();
        let mut record = Vec::new();
        for k in 0..strokes {
            let begin = Instant::now();
            carve_stroke(&mut field, k, stamps, r, size.sphere_radius_voxels);
            let stroked = Instant::now();
            autosave.record(&mut field);
            journaled.push((stroked - begin).as_secs_f64() * 1e6);
            record.push(stroked.elapsed().as_secs_f64() * 1e6);
        }
        let waited = Instant::now();
        while autosave.durable_strokes() < strokes as u64 && waited.elapsed() < Duration::from_secs(60) {
            std::thread::sleep(Duration::from_millis(5));
        }
        let journal_bytes: u64 = std::fs::read_dir(autosave.dir())
            .into_iter()
            .flatten()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().starts_with("journal-"))
            .filter_map(|e| e.metadata().ok())
            .map(|m| m.len())
            .sum();
        autosave.close()?;
        let record_max = record.iter().copied().fold(0.0, f64::max);
        let record_p90 = percentile(&mut record.clone(), 0.9);
        emit(json!({
            "workload": "journal-stroke",
            "radius_voxels": r,
            "strokes": strokes,
            "stamps_per_stroke": stamps,
            "bricks_per_stroke_median": median(bricks),
            "record_us_median": median(record),
            "record_us_p90": record_p90,
            "record_us_max": record_max,
            "stroke_us_median_without_autosave": median(plain),
            "stroke_us_median_with_autosave": median(journaled),
            "journal_bytes_per_stroke": journal_bytes as f64 / strokes as f64,
        }));
    }
    Ok(())
}

/// The `q` quantile of `v` (nearest rank).
fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(((v.len() as f64 * q).ceil() as usize).saturating_sub(1)).copied().unwrap_or(f64::NAN)
}

/// A solid sphere of `radius` voxels painted in bands, as a large sculpt.
fn large_field(radius: f32) -> Field {
    let mut field = sphere_field(radius);
    let r = radius.ceil() as i32 + 2;
    let lo = crate::math::IVec3::splat(-r);
    field.edit_box(lo, -lo, false, |p, _, c| {
        let band = ((p.x + 2 * p.y).div_euclid(16) & 3) as f32;
        *c = [0.2 + 0.2 * band, 0.5, 0.8 - 0.15 * band, 1.0];
    });
    field.take_dirty();
    field
}

fn megabytes_per_s(bytes: usize, seconds: f64) -> f64 {
    bytes as f64 / 1e6 / seconds.max(1e-9)
}

pub(super) fn save_large(size: BenchSize, emit: &mut impl FnMut(Value)) -> Result<()> {
    let scratch = Scratch::new("save")?;
    let field = large_field(size.large_sphere_radius_voxels);
    let path = scratch.0.join("large.argile");
    let mut encode_s = Vec::new();
    let mut total_s = Vec::new();
    let mut file_bytes = 0;
    for _ in 0..size.repetitions {
        let begin = Instant::now();
        let bytes = encode(&field, None, &mut |_| {});
        encode_s.push(begin.elapsed().as_secs_f64());
        write_atomically(&path, true, |w| {
            w.write_all(&bytes).with_context(|| format!("cannot write {}", path.display()))
        })?;
        total_s.push(begin.elapsed().as_secs_f64());
        file_bytes = bytes.len();
    }
    let samples = field.brick_count() * crate::field::BRICK_VOLUME;
    let sample_bytes = field.brick_count() * crate::field::BRICK_BYTES;
    let (encode_s, total_s) = (median(encode_s), median(total_s));
    emit(json!({
        "workload": "save-large",
        "samples": samples,
        "bricks": field.brick_count(),
        "memory_bytes": field.memory_bytes(),
        "file_bytes": file_bytes,
        "file_to_memory": file_bytes as f64 / field.memory_bytes() as f64,
        "encode_ms_median": encode_s * 1e3,
        "save_ms_median": total_s * 1e3,
        "save_mb_per_s_of_samples": megabytes_per_s(sample_bytes, total_s),
        "save_mb_per_s_of_file": megabytes_per_s(file_bytes, total_s),
        "repetitions": size.repetitions,
    }));
    Ok(())
}

pub(super) fn load_large(size: BenchSize, emit: &mut impl FnMut(Value)) -> Result<()> {
    let scratch = Scratch::new("load")?;
    let field = large_field(size.large_sphere_radius_voxels);
    let path = scratch.0.join("large.argile");
    let bytes = encode(&field, None, &mut |_| {});
    write_atomically(&path, true, |w| {
        w.write_all(&bytes).with_context(|| format!("cannot write {}", path.display()))
    })?;
    let mut times = Vec::new();
    for _ in 0..size.repetitions {
        let begin = Instant::now();
        let loaded = load_sculpt_with_progress(&path, false)?;
        times.push(begin.elapsed().as_secs_f64());
        anyhow::ensure!(loaded.field.same_samples(&field), "the loaded sculpt differs from the saved one");
    }
    // Lazily: the index alone; then a box of 32 voxels a side on the sphere's surface, as a
    // viewer or a tool would want first; then the rest, which checks the whole file.
    let r = size.large_sphere_radius_voxels as i32;
    let (box_lo, box_hi) =
        (crate::math::IVec3::new(r - 16, -16, -16), crate::math::IVec3::new(r + 15, 15, 15));
    let (mut open_s, mut box_s, mut finish_s) = (Vec::new(), Vec::new(), Vec::new());
    let (mut open_bytes, mut box_bytes, mut box_chunks, mut chunks) = (0, 0, 0, 0);
    for _ in 0..size.repetitions {
        let begin = Instant::now();
        let mut lazy = crate::io::LazySculpt::open(&path)?;
        open_s.push(begin.elapsed().as_secs_f64());
        open_bytes = lazy.bytes_read();
        let begin = Instant::now();
        box_chunks = lazy.load_box(box_lo, box_hi)?;
        box_s.push(begin.elapsed().as_secs_f64());
        box_bytes = lazy.bytes_read() - open_bytes;
        chunks = lazy.chunks().len();
        let begin = Instant::now();
        let loaded = lazy.finish(&mut |_| {})?;
        finish_s.push(begin.elapsed().as_secs_f64());
        anyhow::ensure!(
            loaded.field.same_samples(&field),
            "the lazily loaded sculpt differs from the saved one"
        );
    }
    let sample_bytes = field.brick_count() * crate::field::BRICK_BYTES;
    let t = median(times);
    let (open_s, box_s, finish_s) = (median(open_s), median(box_s), median(finish_s));
    emit(json!({
        "workload": "load-large",
        "samples": field.brick_count() * crate::field::BRICK_VOLUME,
        "file_bytes": bytes.len(),
        "chunks": chunks,
        "lazy_open_ms_median": open_s * 1e3,
        "lazy_open_bytes": open_bytes,
        "lazy_box_ms_median": box_s * 1e3,
        "lazy_box_chunks": box_chunks,
        "lazy_box_bytes": box_bytes,
        "lazy_rest_ms_median": finish_s * 1e3,
        "load_to_lazy_open": t / open_s.max(1e-9),
        "load_ms_median": t * 1e3,
        "load_mb_per_s_of_samples": megabytes_per_s(sample_bytes, t),
        "load_mb_per_s_of_file": megabytes_per_s(bytes.len(), t),
        "threads": rayon::current_num_threads(),
        "repetitions": size.repetitions,
    }));
    Ok(())
}
