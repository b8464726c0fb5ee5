//! `[symmetry]`: the mirror planes and radial copies every tool acts through
//! (`scenes/README.md`).

use serde::Deserialize;
use toml::Spanned;

use super::{rotation, within_reach, At, SceneError, MAX_POSITION_M};
use crate::math::{Pose, Vec3};
use crate::parts::{Axis, Symmetry, MAX_RADIAL};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SymmetryFile {
    #[serde(default)]
    pub mirror: Vec<String>,
    #[serde(default = "one")]
    pub radial: u32,
    #[serde(default = "y")]
    pub axis: String,
    #[serde(default)]
    pub centre_m: [f32; 3],
    #[serde(default)]
    pub rotation_deg: [f32; 3],
}

fn one() -> u32 {
    1
}

fn y() -> String {
    "y".into()
}

/// The scene's symmetry ([`Symmetry::NONE`] without `[symmetry]`).
pub(super) fn resolve_symmetry(
    spec: Option<&Spanned<SymmetryFile>>,
    at: &At<'_>,
) -> Result<Symmetry, SceneError> {
    let Some(spanned) = spec else { return Ok(Symmetry::NONE) };
    let span = Some(spanned.span());
    let s = spanned.get_ref();
    let fail = |message: String| Err(at(span.clone(), format!("[symmetry] {message}")));
    let axis_named = |name: &str| Axis::from_name(name);
    let mut mirror = [false; 3];
    for name in &s.mirror {
        let Some(a) = axis_named(name) else {
            return fail(format!(
                "mirror names the axes whose planes mirror: \"x\", \"y\" or \"z\", not \"{name}\""
            ));
        };
        if std::mem::replace(&mut mirror[a as usize], true) {
            return fail(format!("mirror names the axis \"{name}\" twice"));
        }
    }
    if !(1..=MAX_RADIAL).contains(&s.radial) {
        return fail(format!(
            "radial is the number of copies about the axis, 1 to {MAX_RADIAL}, not {}",
            s.radial
        ));
    }
    let Some(axis) = axis_named(&s.axis) else {
        return fail(format!("axis must be \"x\", \"y\" or \"z\", not \"{}\"", s.axis));
    };
    if !within_reach(s.centre_m) {
        return fail(format!("centre_m must lie within ±{MAX_POSITION_M} m on each axis"));
    }
    if !s.rotation_deg.iter().all(|d| d.is_finite()) {
        return fail("rotation_deg must be finite".into());
    }
    let frame = Pose { position_m: Vec3::from(s.centre_m), rotation: rotation(s.rotation_deg) };
    Ok(Symmetry { frame, mirror, radial: s.radial, axis })
}
