//! `[[region]]`: region tools on the timeline — a region of the clay moved, turned, copied,
//! bent, inflated or deflated, each one undo step (`scenes/README.md`).

use serde::Deserialize;
use toml::Spanned;

use super::{rotation, within_reach, At, SceneError, MAX_LENGTH_M, MAX_POSITION_M, MAX_TIME_S};
use crate::math::{Pose, Vec3};
use crate::parts::{Motion, Region, RegionOp, MAX_REGION_POINTS};

/// The most copies one `copy` entry makes.
pub const MAX_COPIES: u32 = 64;
/// The farthest an inflation or deflation moves the surface, metres.
pub const MAX_INFLATION_M: f32 = 0.1;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RegionFile {
    pub time_s: f32,
    pub op: String,
    pub centre_m: [f32; 3],
    pub half_m: Option<[f32; 3]>,
    pub radius_m: Option<f32>,
    #[serde(default)]
    pub rotation_deg: [f32; 3],
    #[serde(default)]
    pub move_m: [f32; 3],
    #[serde(default)]
    pub turn_deg: [f32; 3],
    pub count: Option<u32>,
    pub distance_m: Option<f32>,
    #[serde(default)]
    pub duration_s: f32,
    #[serde(default = "yes")]
    pub show: bool,
    pub part: Option<String>,
    pub name: Option<String>,
}

fn yes() -> bool {
    true
}

/// What a scene's region entry does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RegionAction {
    /// Carried, copied or bent along the entry's motion.
    Drag(RegionOp),
    /// The surface within moved out (> 0) or in (< 0) by this many metres.
    Inflate(f32),
    /// The clay within copied into a new part, after the others.
    CopyToPart,
}

/// A region tool on the scene's timeline.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneRegion {
    /// When it starts, seconds.
    pub time_s: f32,
    /// How long its motion takes (0: at once), seconds; the hand's motion ramps in over it.
    pub duration_s: f32,
    /// What it does.
    pub action: RegionAction,
    /// The region selected.
    pub region: Region,
    /// Where the hand carries it (about the region's centre).
    pub motion: Motion,
    /// Copies made, each carried once more along the motion (`copy` only; else 1).
    pub count: u32,
    /// Whether captures draw the region while it moves.
    pub show: bool,
    /// The part whose clay it acts on; the region and its motion are in that part's own frame.
    pub part: usize,
    /// `copy-to-part`: the new part's name (else its part's name and " copy").
    pub name: Option<String>,
}

impl SceneRegion {
    /// When it is done, seconds.
    pub fn end_s(&self) -> f32 {
        self.time_s + self.duration_s
    }
}

/// The scene's region tools, validated, in time order.
pub(super) fn resolve_regions(
    regions: &[Spanned<RegionFile>],
    parts: &[super::ScenePart],
    at: &At<'_>,
) -> Result<Vec<SceneRegion>, SceneError> {
    let mut out = Vec::with_capacity(regions.len());
    for spanned in regions {
        let span = Some(spanned.span());
        let r = spanned.get_ref();
        let fail = |message: String| Err(at(span.clone(), format!("[[region]] {message}")));
        let part = super::part::part_index(parts, r.part.as_deref(), spanned.span(), at)?;
        if parts[part].locked {
            return fail(format!("part \"{}\" is locked: no region tool acts on it", parts[part].name));
        }
        // The part's finest voxel, in its own frame.
        let voxel_size_m = parts[part].voxel_size_m;
        let action = match r.op.as_str() {
            "move" => RegionAction::Drag(RegionOp::Move),
            "copy" => RegionAction::Drag(RegionOp::Copy),
            "bend" => RegionAction::Drag(RegionOp::Bend),
            "copy-to-part" => RegionAction::CopyToPart,
            "inflate" | "deflate" => {
                let Some(d) = r.distance_m.filter(|d| d.is_finite() && *d > 0.0 && *d <= MAX_INFLATION_M)
                else {
                    return fail(format!(
                        "{} needs distance_m, how far the surface moves: above 0 and at most {MAX_INFLATION_M} m",
                        r.op
                    ));
                };
                RegionAction::Inflate(if r.op == "inflate" { d } else { -d })
            }
            other => {
                return fail(format!(
                    "op must be \"move\", \"copy\", \"bend\", \"inflate\", \"deflate\" or \"copy-to-part\", not \"{other}\""
                ))
            }
        };
        if !(r.time_s.is_finite() && (0.0..=MAX_TIME_S).contains(&r.time_s)) {
            return fail(format!("time_s must be 0 to {MAX_TIME_S} s, not {}", r.time_s));
        }
        if !(r.duration_s.is_finite() && (0.0..=MAX_TIME_S).contains(&r.duration_s)) {
            return fail(format!("duration_s must be 0 to {MAX_TIME_S} s, not {}", r.duration_s));
        }
        if !within_reach(r.centre_m) {
            return fail(format!("centre_m must lie within ±{MAX_POSITION_M} m on each axis"));
        }
        let length_ok = |v: f32| v.is_finite() && v > 0.0 && v <= MAX_LENGTH_M;
        let pose = Pose { position_m: Vec3::from(r.centre_m), rotation: rotation(r.rotation_deg) };
        let region = match (r.half_m, r.radius_m) {
            (Some(half), None) if half.iter().all(|&h| length_ok(h)) => Region::boxed(pose, Vec3::from(half)),
            (None, Some(radius)) if length_ok(radius) => Region::ball(pose.position_m, radius),
            (Some(_), Some(_)) | (None, None) => {
                return fail("selects with either half_m (a box) or radius_m (a ball), one of them".into())
            }
            _ => return fail(format!("half_m and radius_m must be positive lengths up to {MAX_LENGTH_M} m")),
        };
        if !r.rotation_deg.iter().chain(&r.turn_deg).all(|a| a.is_finite() && a.abs() <= 3600.0) {
            return fail("rotation_deg and turn_deg must be finite angles within ±3600°".into());
        }
        if !r.move_m.iter().all(|c| c.is_finite() && c.abs() <= MAX_LENGTH_M) {
            return fail(format!("move_m must be within ±{MAX_LENGTH_M} m on each axis"));
        }
        let still = r.move_m == [0.0; 3] && r.turn_deg == [0.0; 3];
        match action {
            RegionAction::Drag(op) if still => {
                return fail(format!(
                    "{} needs move_m or turn_deg: where the hand carries the region",
                    op.name()
                ))
            }
            RegionAction::Inflate(_) | RegionAction::CopyToPart if !still || r.duration_s > 0.0 => {
                return fail(format!("{} takes no move_m, turn_deg or duration_s", r.op))
            }
            _ => {}
        }
        if r.distance_m.is_some() && !matches!(action, RegionAction::Inflate(_)) {
            return fail("distance_m is for inflate and deflate".into());
        }
        let name = match (action, &r.name) {
            (_, None) => None,
            (RegionAction::CopyToPart, Some(n)) => {
                if n.is_empty() || n.chars().count() > 64 || parts.iter().any(|p| &p.name == n) {
                    return fail(format!("name must be 1 to 64 characters and no [[part]]'s, not \"{n}\""));
                }
                Some(n.clone())
            }
            (_, Some(_)) => return fail("name is for copy-to-part".into()),
        };
        let count = match (action, r.count) {
            (_, None) => 1,
            (RegionAction::Drag(RegionOp::Copy), Some(n)) if (1..=MAX_COPIES).contains(&n) => n,
            (RegionAction::Drag(RegionOp::Copy), Some(n)) => {
                return fail(format!("count must be 1 to {MAX_COPIES} copies, not {n}"))
            }
            (_, Some(_)) => return fail("count is for copy".into()),
        };
        if count > 1 && r.duration_s > 0.0 {
            return fail("a copy of several copies is made at once: no duration_s".into());
        }
        // The copy of the clay under the region: bounded before the scene plays.
        let size = region.bounds(0.0).size() / voxel_size_m + Vec3::splat(8.0);
        let points = f64::from(size.x) * f64::from(size.y) * f64::from(size.z);
        if points > MAX_REGION_POINTS as f64 {
            return fail(format!(
                "selects about {points:.0} lattice points of clay, over the {MAX_REGION_POINTS} a region tool may copy"
            ));
        }
        let motion = Motion {
            pivot_m: pose.position_m,
            translation_m: Vec3::from(r.move_m),
            rotation: rotation(r.turn_deg),
        };
        out.push(SceneRegion {
            time_s: r.time_s,
            duration_s: r.duration_s,
            action,
            region,
            motion,
            count,
            show: r.show,
            part,
            name,
        });
    }
    out.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    Ok(out)
}
