//! `[[part]]`: the parts a sculpt is built of — each a field of its own voxel size, placed in
//! the world and composed with the parts before it (`scenes/README.md`).

use serde::Deserialize;
use toml::Spanned;

use super::{rotation, within_reach, At, SceneError, MAX_POSITION_M};
use crate::field::VOXEL_SIZE_RANGE_M;
use crate::math::Vec3;
use crate::parts::{Csg, Placement};

/// The most parts a scene may have.
pub const MAX_PARTS: usize = 256;
/// The longest name a part may have, characters.
pub const MAX_PART_NAME: usize = 64;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PartFile {
    pub name: String,
    pub voxel_size_m: Option<f32>,
    #[serde(default)]
    pub position_m: [f32; 3],
    #[serde(default)]
    pub rotation_deg: [f32; 3],
    #[serde(default = "one")]
    pub scale: f32,
    #[serde(default = "union")]
    pub op: String,
    #[serde(default = "yes")]
    pub visible: bool,
    #[serde(default)]
    pub locked: bool,
}

fn one() -> f32 {
    1.0
}

fn yes() -> bool {
    true
}

fn union() -> String {
    "union".into()
}

/// A part of the scene's sculpt.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenePart {
    /// Its name, unique in the scene.
    pub name: String,
    /// Its field's finest voxel, metres (in its own frame: the world's voxel is this times the
    /// placement's scale).
    pub voxel_size_m: f32,
    /// Where it sits in the world.
    pub placement: Placement,
    /// How it combines with the parts before it.
    pub op: Csg,
    /// Whether it is drawn, measured and exported.
    pub visible: bool,
    /// Whether tools leave it alone.
    pub locked: bool,
}

impl ScenePart {
    /// The one part of a scene without `[[part]]`: the whole sculpt, at rest.
    pub fn whole(voxel_size_m: f32) -> Self {
        Self {
            name: "clay".into(),
            voxel_size_m,
            placement: Placement::IDENTITY,
            op: Csg::Union,
            visible: true,
            locked: false,
        }
    }
}

/// The scene's parts, validated, in order (the one whole part without `[[part]]`).
pub(super) fn resolve_parts(
    parts: &[Spanned<PartFile>],
    field_voxel_m: f32,
    at: &At<'_>,
) -> Result<Vec<ScenePart>, SceneError> {
    if parts.is_empty() {
        return Ok(vec![ScenePart::whole(field_voxel_m)]);
    }
    if parts.len() > MAX_PARTS {
        return Err(at(Some(parts[MAX_PARTS].span()), format!("a scene holds at most {MAX_PARTS} parts")));
    }
    let mut out: Vec<ScenePart> = Vec::with_capacity(parts.len());
    for spanned in parts {
        let span = Some(spanned.span());
        let p = spanned.get_ref();
        let fail = |message: String| Err(at(span.clone(), format!("[[part]] {message}")));
        let name = p.name.trim();
        if name.is_empty() || name.chars().count() > MAX_PART_NAME || name.chars().any(char::is_control) {
            return fail(format!("name must be 1 to {MAX_PART_NAME} printable characters"));
        }
        if out.iter().any(|o| o.name == name) {
            return fail(format!("name \"{name}\" is given to two parts"));
        }
        let voxel = p.voxel_size_m.unwrap_or(field_voxel_m);
        if !VOXEL_SIZE_RANGE_M.contains(&voxel) {
            return fail(format!(
                "\"{name}\": voxel_size_m must be between {} and {} metres, not {voxel}",
                VOXEL_SIZE_RANGE_M.start(),
                VOXEL_SIZE_RANGE_M.end()
            ));
        }
        if !within_reach(p.position_m) {
            return fail(format!("\"{name}\": position_m must lie within ±{MAX_POSITION_M} m on each axis"));
        }
        if !p.rotation_deg.iter().all(|a| a.is_finite() && a.abs() <= 3600.0) {
            return fail(format!("\"{name}\": rotation_deg must be finite angles within ±3600°"));
        }
        let placement = match Placement::new(rotation(p.rotation_deg), Vec3::from(p.position_m), p.scale) {
            Ok(placement) => placement,
            Err(e) => return fail(format!("\"{name}\": {e}")),
        };
        // A world voxel outside the range would make the composition's work endless or its
        // surface too coarse to sculpt.
        let world_voxel = voxel * placement.scale;
        if !VOXEL_SIZE_RANGE_M.contains(&world_voxel) {
            return fail(format!(
                "\"{name}\": its voxel scaled ({voxel} m × {}) is {world_voxel} m in the world, outside {} to {} m",
                placement.scale,
                VOXEL_SIZE_RANGE_M.start(),
                VOXEL_SIZE_RANGE_M.end()
            ));
        }
        let Some(op) = Csg::from_name(&p.op) else {
            return fail(format!(
                "\"{name}\": op must be \"union\", \"difference\" or \"intersection\", not \"{}\"",
                p.op
            ));
        };
        out.push(ScenePart {
            name: name.to_owned(),
            voxel_size_m: voxel,
            placement,
            op,
            visible: p.visible,
            locked: p.locked,
        });
    }
    Ok(out)
}

/// The index of the part a `part = "…"` key names (the first part when none is named).
pub(super) fn part_index(
    parts: &[ScenePart],
    name: Option<&str>,
    span: std::ops::Range<usize>,
    at: &At<'_>,
) -> Result<usize, SceneError> {
    let Some(name) = name else { return Ok(0) };
    parts.iter().position(|p| p.name == name).ok_or_else(|| {
        let known: Vec<&str> = parts.iter().map(|p| p.name.as_str()).collect();
        at(Some(span), format!("no part named \"{name}\" (parts: {})", known.join(", ")))
    })
}
