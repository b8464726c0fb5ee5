//! The memory budget: the most memory the clay a command builds or loads, its mesh and its
//! render targets may need, checked against an estimate before the work starts.
//!
//! A scene's initial clay is estimated from its solids' volumes and areas
//! ([`crate::tool::rasterize_cost`]), a sculpt file's from its bricks as they are read (see
//! [`crate::io::read_file_within`]), a render from its targets' sizes. A command whose work
//! would need more says so with the estimate, the budget and what to change, and does nothing;
//! this keeps a mistyped size from filling the machine's memory until the kernel kills the
//! station, with whatever was not saved.
//!
//! The budget is half of the machine's memory (or of the control group's limit, where that is
//! lower) unless `--memory-budget` sets it; it is process-wide, as a resource limit is.

use std::sync::OnceLock;

use anyhow::{bail, Result};

use crate::field::Field;
use crate::scene::Scene;
use crate::tool::{rasterize_cost, CsgOp, RasterCost};

/// The memory budget in force.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryBudget {
    /// Bytes.
    pub bytes: u64,
    /// Where it comes from, for messages ("half of this machine's 23.4 GiB").
    pub source: String,
}

static BUDGET: OnceLock<MemoryBudget> = OnceLock::new();

/// Sets the budget for the rest of the process (`--memory-budget`); only the first call counts.
pub fn set(bytes: u64) {
    let _ = BUDGET.set(MemoryBudget { bytes, source: "set by --memory-budget".into() });
}

/// The budget in force: the one [`set`] gave, else half of the machine's memory.
pub fn get() -> &'static MemoryBudget {
    BUDGET.get_or_init(|| match machine_memory_bytes() {
        Some(total) => MemoryBudget {
            bytes: total / 2,
            source: format!("half of this machine's {}", size_text(total as f64)),
        },
        // Nowhere to read it from: the budget of a small machine.
        None => MemoryBudget { bytes: 4 << 30, source: "4 GiB (this machine's memory is unknown)".into() },
    })
}

/// The memory this process may use: the machine's (`MemTotal` of `/proc/meminfo`), or its
/// control group's limit (`memory.max`, cgroup v2) where that is lower.
pub fn machine_memory_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let total = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))
        .and_then(|v| v.trim().strip_suffix("kB"))
        .and_then(|v| v.trim().parse::<u64>().ok())?
        * 1024;
    let group =
        std::fs::read_to_string("/sys/fs/cgroup/memory.max").ok().and_then(|v| v.trim().parse::<u64>().ok());
    Some(group.map_or(total, |g| g.min(total)))
}

/// Parses a memory size: bytes, or a number with K, M, G or T (powers of 1024; `KiB`, `MB`
/// and the like are read the same), e.g. `8G`, `512M`, `1.5GiB`.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let shift = match unit.to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        _ => return Err(format!("`{text}` is not a size: write bytes, or a number with K, M, G or T (8G)")),
    };
    match number.trim().parse::<f64>() {
        Ok(n) if n.is_finite() && n * (1u64 << shift) as f64 >= (1u64 << 20) as f64 => {
            Ok((n * (1u64 << shift) as f64).min(u64::MAX as f64) as u64)
        }
        _ => Err(format!("`{text}` is not a memory size of at least 1M (for example 8G or 512M)")),
    }
}

/// A size for people: `1.9 GiB`, `340 MiB`, `12 KiB`.
pub fn size_text(bytes: f64) -> String {
    const UNITS: [&str; 6] = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = bytes.max(0.0);
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    match unit {
        0 => format!("{v:.0} bytes"),
        _ if v >= 100.0 => format!("{v:.0} {}", UNITS[unit]),
        _ => format!("{v:.1} {}", UNITS[unit]),
    }
}

/// Refuses work whose estimate is over the budget: "`what` would need about …".
pub fn admit(what: &str, estimate_bytes: f64, advice: &str) -> Result<()> {
    let budget = get();
    if estimate_bytes > budget.bytes as f64 {
        bail!(
            "{what} would need about {} of memory, over the memory budget of {} ({}); {advice}, \
             or raise the budget with --memory-budget",
            size_text(estimate_bytes),
            size_text(budget.bytes as f64),
            budget.source
        );
    }
    Ok(())
}

/// The budget as the limit a sculpt file's clay is read within.
pub fn sculpt_limit() -> crate::io::MemoryLimit {
    let budget = get();
    crate::io::MemoryLimit {
        bytes: budget.bytes,
        what: format!(
            "the memory budget of {} ({}); raise it with --memory-budget",
            size_text(budget.bytes as f64),
            budget.source
        ),
    }
}

/// Triangles a mesh has for each voxel face of surface (area over the voxel's square), as
/// the stock solids mesh (`the_estimate_of_a_solids_clay_is_near_what_it_builds`).
const TRIANGLES_PER_SURFACE_VOXEL: f64 = 3.0;

/// Bytes a mesh takes for each voxel face of surface: its triangles, each three 4-byte
/// indices and half a 40-byte vertex (a closed triangle mesh has about twice as many
/// triangles as vertices), held by the mesher and again by the renderer's buffers (on
/// lavapipe, in the same memory).
pub const MESH_BYTES_PER_SURFACE_VOXEL: f64 = TRIANGLES_PER_SURFACE_VOXEL * (12.0 + 20.0) * 2.0;

/// The estimate of what a scene's initial clay takes, with its mesh: the cost of rasterising
/// each solid it adds (a solid carved away takes nothing more) at its part's voxel, summed;
/// where the parts are composed, each visible part's solids again, at the voxel of the
/// composition's level it is sampled on (see [`crate::parts::Composition`]).
pub fn scene_clay_cost(scene: &Scene) -> RasterCost {
    let mut cost = RasterCost::default();
    let adding = || scene.clay.iter().filter(|p| p.op == CsgOp::Union);
    for p in adding() {
        cost += rasterize_cost(&p.solid, scene.parts[p.part].voxel_size_m);
    }
    let composed = scene.parts.len() > 1 || scene.parts.iter().any(|p| !p.placement.is_identity());
    let world_voxel = |p: &crate::scene::ScenePart| p.voxel_size_m * p.placement.scale;
    let finest = scene.parts.iter().filter(|p| p.visible).map(world_voxel).reduce(f32::min);
    if let (true, Some(finest)) = (composed, finest) {
        for p in adding().filter(|p| scene.parts[p.part].visible) {
            let part = &scene.parts[p.part];
            let level =
                (world_voxel(part) / finest).log2().floor().clamp(0.0, crate::field::MESHED_LEVELS as f32);
            cost += rasterize_cost(&p.solid, finest * level.exp2() / part.placement.scale);
        }
    }
    cost
}

/// Bytes [`scene_clay_cost`] comes to: the field's, and its mesh's.
pub fn clay_bytes(cost: &RasterCost) -> f64 {
    Field::estimated_bytes(cost.keys, cost.surface_bricks)
        + cost.surface_voxels * MESH_BYTES_PER_SURFACE_VOXEL
}

/// Triangles a surface of that many voxel faces meshes into.
pub fn mesh_triangles(surface_voxels: f64) -> f64 {
    surface_voxels * TRIANGLES_PER_SURFACE_VOXEL
}

/// Refuses a scene whose initial clay, of `cost` ([`scene_clay_cost`]), would take more than
/// the budget, before it is built.
pub fn admit_scene(scene: &Scene, cost: &RasterCost) -> Result<()> {
    admit(
        &format!(
            "the initial clay of {} ({:.3e} bricks of {} mm voxels, {:.3e} of them on its surface)",
            scene.source,
            cost.keys,
            scene.voxel_size_m * 1000.0,
            cost.surface_bricks
        ),
        clay_bytes(cost),
        "make the clay smaller or its [field] voxel_size_m larger",
    )
}

/// Bytes the offscreen targets of a stereo render of `width` × `height` pixels per eye with
/// `samples` take: per eye and pixel, the multisampled colour and depth, the resolved colour,
/// its read-back copy and the 8-bit image written.
pub fn render_bytes(width: u32, height: u32, samples: u32) -> f64 {
    let pixels = 2.0 * f64::from(width) * f64::from(height);
    pixels * (f64::from(samples) * (8.0 + 4.0) + 4.0 + 4.0 + 4.0)
}

/// Refuses a render whose targets would take more than the budget.
pub fn admit_render(source: &str, width: u32, height: u32, samples: u32) -> Result<()> {
    admit(
        &format!("a stereo render of {width}x{height} pixels per eye with {samples} samples of {source}"),
        render_bytes(width, height, samples),
        "render smaller (--size) or with fewer [output] samples",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_and_print_as_people_write_them() {
        assert_eq!(parse_size("8G"), Ok(8 << 30));
        assert_eq!(parse_size("512m"), Ok(512 << 20));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("2097152"), Ok(2 << 20));
        for bad in ["", "G", "-1G", "nanG", "8Q", "1K", "0"] {
            assert!(parse_size(bad).is_err(), "{bad:?}");
        }
        assert_eq!(size_text(1536.0), "1.5 KiB");
        assert_eq!(size_text(7.6 * (1u64 << 30) as f64), "7.6 GiB");
        assert_eq!(size_text(12.0), "12 bytes");
    }

    #[test]
    fn the_estimate_of_a_solids_clay_is_near_what_it_builds() {
        use crate::math::{Pose, Quat, Vec3};
        use crate::tool::{rasterize_solid, PlacedSolid, Solid};
        let turned =
            Pose { position_m: Vec3::new(0.003, -0.002, 0.001), rotation: Quat::from_rotation_y(0.5) };
        let solids = [
            Solid::Sphere { radius_m: 0.05 },
            Solid::Box { half_m: Vec3::new(0.06, 0.02, 0.04) },
            Solid::Torus { major_m: 0.05, minor_m: 0.015 },
            Solid::Bar { half_length_m: 0.08, radius_m: 0.012 },
            Solid::Cylinder { radius_m: 0.03, half_height_m: 0.04 },
        ];
        for voxel in [0.001, 0.002] {
            for solid in solids {
                let placed = PlacedSolid { solid, pose: turned, scale: 1.0 };
                let cost = rasterize_cost(&placed, voxel);
                let mut field = Field::new(voxel, 0.5);
                rasterize_solid(&mut field, &placed, CsgOp::Union, [1.0; 4]);
                let keys = field.brick_count() as f64;
                let own = keys - field.tile_count() as f64;
                let triangles = crate::mesh::mesh_all(&field).upserted_triangles() as f64;
                let ratios = [
                    cost.keys / keys,
                    cost.surface_bricks / own,
                    mesh_triangles(cost.surface_voxels) / triangles,
                ];
                println!("{solid:?} at {voxel}: keys, own bricks, triangles estimated / built {ratios:.3?}");
                for r in ratios {
                    assert!((0.7..1.6).contains(&r), "{solid:?} at {voxel} m: {ratios:?}");
                }
                // The bytes of what was built, counted as the estimate counts them: at least
                // what the field counts of itself (its maps' spare room and the dirty set are
                // not in that count).
                let counted = field.memory_bytes() as f64;
                let estimated = Field::estimated_bytes(keys, own);
                assert!((1.0..2.5).contains(&(estimated / counted)), "{estimated} for {counted} bytes");
            }
        }
    }

    #[test]
    fn the_machine_memory_is_read() {
        let m = machine_memory_bytes().expect("/proc/meminfo");
        assert!(m > 64 << 20, "{m}");
    }
}
