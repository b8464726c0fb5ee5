//! Resolving a scene's `[[tool]]` tables into tool shapes and actions, with the checks that
//! each key belongs to the shape and action it is given for.

use std::ops::Range;

use super::file::{ActionSpec, FalloffSpec, ToolShapeSpec, ToolSpec};
use super::{positive, At, SceneError};
use crate::math::Vec3;
use crate::tool::{Action, Deformation, Ellipsoid, Falloff, Solid, ToolShape};

/// A tool's shape as the scene gives it.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneToolShape {
    /// An analytic shape.
    Shape(ToolShape),
    /// A freeform tool copied from the clay inside a world box when the scene starts playing
    /// (after its initial clay is laid down).
    Freeform {
        /// Minimum corner of the copied region, metres.
        min_m: Vec3,
        /// Maximum corner of the copied region, metres.
        max_m: Vec3,
    },
}

impl SceneToolShape {
    /// Half the size of the tool's influence box in its local frame, before scaling.
    pub fn half_extents_m(&self) -> Vec3 {
        match self {
            SceneToolShape::Shape(s) => s.half_extents_m(),
            SceneToolShape::Freeform { min_m, max_m } => (*max_m - *min_m) * 0.5,
        }
    }
}

fn span_err(at: &At<'_>, span: &Range<usize>, message: String) -> SceneError {
    at(Some(span.clone()), message)
}

/// The shape, checking that only its own keys are present.
pub(super) fn shape_of(t: &ToolSpec, span: &Range<usize>, at: &At<'_>) -> Result<SceneToolShape, SceneError> {
    let name = format!("{:?}", t.shape).to_lowercase();
    let need = |v: Option<f32>, key: &str| -> Result<f32, SceneError> {
        let v = v.ok_or_else(|| span_err(at, span, format!("a {name} tool needs `{key}`")))?;
        positive(v, key, span, at)
    };
    let need3 = |v: Option<[f32; 3]>, key: &str| -> Result<Vec3, SceneError> {
        let v = v.ok_or_else(|| span_err(at, span, format!("a {name} tool needs `{key}`")))?;
        for c in v {
            positive(c, key, span, at)?;
        }
        Ok(Vec3::from(v))
    };
    let allowed: &[&str] = match t.shape {
        ToolShapeSpec::Sphere => &["radius_m"],
        ToolShapeSpec::Ellipsoid => &["radii_m", "falloff"],
        ToolShapeSpec::Box => &["size_m"],
        ToolShapeSpec::Cylinder => &["radius_m", "height_m"],
        ToolShapeSpec::Torus => &["major_radius_m", "minor_radius_m"],
        ToolShapeSpec::Freeform => &["region_min_m", "region_max_m"],
    };
    let present = [
        ("radius_m", t.radius_m.is_some()),
        ("radii_m", t.radii_m.is_some()),
        ("falloff", t.falloff.is_some()),
        ("size_m", t.size_m.is_some()),
        ("height_m", t.height_m.is_some()),
        ("major_radius_m", t.major_radius_m.is_some()),
        ("minor_radius_m", t.minor_radius_m.is_some()),
        ("region_min_m", t.region_min_m.is_some()),
        ("region_max_m", t.region_max_m.is_some()),
    ];
    if let Some((key, _)) = present.iter().find(|(k, p)| *p && !allowed.contains(k)) {
        return Err(span_err(
            at,
            span,
            format!("`{key}` does not apply to a {name} tool; it takes {}", allowed.join(", ")),
        ));
    }
    Ok(SceneToolShape::Shape(match t.shape {
        ToolShapeSpec::Sphere => ToolShape::sphere(need(t.radius_m, "radius_m")?),
        ToolShapeSpec::Ellipsoid => ToolShape::Ellipsoid(Ellipsoid {
            radii_m: need3(t.radii_m, "radii_m")?,
            falloff: match t.falloff.unwrap_or(FalloffSpec::Wyvill) {
                FalloffSpec::Wyvill => Falloff::Wyvill,
                FalloffSpec::Box => Falloff::Box,
            },
        }),
        ToolShapeSpec::Box => ToolShape::Solid(Solid::Box { half_m: need3(t.size_m, "size_m")? * 0.5 }),
        ToolShapeSpec::Cylinder => ToolShape::Solid(Solid::Cylinder {
            radius_m: need(t.radius_m, "radius_m")?,
            half_height_m: need(t.height_m, "height_m")? * 0.5,
        }),
        ToolShapeSpec::Torus => ToolShape::Solid(Solid::Torus {
            major_m: need(t.major_radius_m, "major_radius_m")?,
            minor_m: need(t.minor_radius_m, "minor_radius_m")?,
        }),
        ToolShapeSpec::Freeform => {
            let (min, max) = match (t.region_min_m, t.region_max_m) {
                (Some(a), Some(b)) => (Vec3::from(a), Vec3::from(b)),
                _ => {
                    return Err(span_err(
                        at,
                        span,
                        "a freeform tool needs `region_min_m` and `region_max_m`".into(),
                    ))
                }
            };
            if !(min.is_finite() && max.is_finite()) || min.cmpge(max).any() {
                return Err(span_err(
                    at,
                    span,
                    "`region_min_m` must be below `region_max_m` on every axis".into(),
                ));
            }
            return Ok(SceneToolShape::Freeform { min_m: min, max_m: max });
        }
    }))
}

/// The action, checking that only its own parameters are present.
pub(super) fn action_of(
    t: &ToolSpec,
    size_m: f32,
    span: &Range<usize>,
    at: &At<'_>,
) -> Result<Action, SceneError> {
    let name = format!("{:?}", t.action).to_lowercase();
    let allowed: &[&str] = match t.action {
        ActionSpec::Add | ActionSpec::Remove | ActionSpec::Paint | ActionSpec::Push | ActionSpec::Support => {
            &[]
        }
        ActionSpec::SoftRemove | ActionSpec::Build | ActionSpec::SoftPaint => &["rate_per_s"],
        ActionSpec::Smooth => &["rate_per_s", "centre_weight"],
        ActionSpec::Stamp => &["s", "m", "r", "k", "n", "falloff_m"],
        ActionSpec::Inflate | ActionSpec::Deflate => &["speed_m_per_s"],
    };
    let present = [
        ("rate_per_s", t.rate_per_s.is_some()),
        ("centre_weight", t.centre_weight.is_some()),
        ("speed_m_per_s", t.speed_m_per_s.is_some()),
        ("s", t.s.is_some()),
        ("m", t.m.is_some()),
        ("r", t.r.is_some()),
        ("k", t.k.is_some()),
        ("n", t.n.is_some()),
        ("falloff_m", t.falloff_m.is_some()),
    ];
    if let Some((key, _)) = present.iter().find(|(k, p)| *p && !allowed.contains(k)) {
        let takes = if allowed.is_empty() {
            "it takes no parameters".to_owned()
        } else {
            format!("it takes {}", allowed.join(", "))
        };
        return Err(span_err(at, span, format!("`{key}` does not apply to action {name}; {takes}")));
    }
    let rate = |default: f32| -> Result<f32, SceneError> {
        let v = t.rate_per_s.unwrap_or(default);
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(span_err(at, span, format!("rate_per_s must be a positive number per second, not {v}")))
        }
    };
    Ok(match t.action {
        ActionSpec::Add => Action::Add,
        ActionSpec::Push => Action::Push,
        ActionSpec::Support => Action::Support,
        ActionSpec::Remove => Action::Remove,
        ActionSpec::Paint => Action::Paint,
        ActionSpec::SoftRemove => Action::SoftRemove { rate_per_s: rate(1.0)? },
        ActionSpec::Build => Action::Build { rate_per_s: rate(1.0)? },
        ActionSpec::SoftPaint => Action::SoftPaint { rate_per_s: rate(2.0)? },
        ActionSpec::Smooth => {
            let centre_weight = t.centre_weight.unwrap_or(8.0);
            if !(4.0..=24.0).contains(&centre_weight) {
                return Err(span_err(
                    at,
                    span,
                    format!("centre_weight must be between 4 and 24 (the sample's weight against 1 per neighbour), not {centre_weight}"),
                ));
            }
            Action::Smooth { centre_weight, rate_per_s: rate(30.0)? }
        }
        ActionSpec::Stamp => {
            let d = Deformation::default();
            let (s, m, r, k, n) = d.parameters();
            let deformation = Deformation::new(
                t.s.unwrap_or(s),
                t.m.unwrap_or(m),
                t.r.unwrap_or(r),
                t.k.unwrap_or(k),
                t.n.unwrap_or(n),
            )
            .map_err(|e| span_err(at, span, e.to_string()))?;
            let falloff_m = match t.falloff_m {
                Some(v) => positive(v, "falloff_m", span, at)?,
                None => size_m,
            };
            Action::Stamp { deformation, falloff_m }
        }
        ActionSpec::Inflate | ActionSpec::Deflate => {
            let speed_m_per_s = positive(t.speed_m_per_s.unwrap_or(0.02), "speed_m_per_s", span, at)?;
            if t.action == ActionSpec::Inflate {
                Action::Inflate { speed_m_per_s }
            } else {
                Action::Deflate { speed_m_per_s }
            }
        }
    })
}
