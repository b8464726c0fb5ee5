//! Tool shapes: the potential field a tool contributes, evaluated in the tool's own frame.
//!
//! A tool's shape is a potential `T(p)` in [0, 1] over its local frame (Ferley et al. 1999,
//! §4): 1 deep inside, 0 outside its influence region, ½ on the surface the tool shows. Every
//! shape is evaluated directly at each lattice point mapped into the tool's frame, analytically
//! or, for freeform tools, by trilinear interpolation of the copied samples. No rotated or
//! scaled voxmap is ever resampled (the step Galyean–Hughes could not afford, §3), so an
//! oriented tool cuts the same clay as an axis-aligned one.
//!
//! ```text
//!   world point ──(pose⁻¹)──► rotated frame ──(÷ scale per axis)──► local frame ──► T(local)
//! ```
//!
//! Hard-edged shapes (sphere, box, cylinder, torus, the box-falloff ellipsoid) use the
//! band-limited ramp of their signed distance ([`crate::tool::solid_density`]), so moving a
//! tool by a fraction of a voxel moves the surface it leaves by that fraction.

mod ellipsoid;
mod freeform;

use std::sync::Arc;

pub use ellipsoid::{wyvill, Ellipsoid, Falloff};
pub use freeform::Freeform;

use super::shape::Solid;
use crate::math::{Aabb, Pose, Vec3};

/// The shape of a tool, in its local frame (lengths in metres, before the tool's scale).
#[derive(Clone, Debug, PartialEq)]
pub enum ToolShape {
    /// A hard-edged solid: the band-limited ramp of its signed distance.
    Solid(Solid),
    /// An ellipsoid with the Wyvill or the box falloff (Ferley et al. §4.1.1).
    Ellipsoid(Ellipsoid),
    /// A region of a sculpt copied as a tool (Ferley et al. §4.1.2).
    Freeform(Arc<Freeform>),
}

impl ToolShape {
    /// A ball of radius `radius_m`.
    pub fn sphere(radius_m: f32) -> Self {
        ToolShape::Solid(Solid::Sphere { radius_m })
    }

    /// Half the size of the box containing the influence region, in the local frame, before
    /// scaling; a hard-edged shape's ramp reaches half a band beyond it.
    pub fn half_extents_m(&self) -> Vec3 {
        match self {
            ToolShape::Solid(s) => s.local_bounds().max,
            ToolShape::Ellipsoid(e) => e.radii_m,
            ToolShape::Freeform(f) => f.half_extents_m(),
        }
    }

    /// Whether the potential is the band-limited ramp of a signed distance (and so reaches
    /// half a band beyond [`ToolShape::half_extents_m`]).
    pub fn is_hard_edged(&self) -> bool {
        match self {
            ToolShape::Solid(_) => true,
            ToolShape::Ellipsoid(e) => e.falloff == Falloff::Box,
            ToolShape::Freeform(_) => false,
        }
    }

    /// The potential at a local point: 1 inside, 0 outside, ½ on the surface.
    ///
    /// `band_local_m` is the width of the ramp across a hard edge, measured in the local frame
    /// (the field's band divided by the smallest scale factor); smooth falloffs ignore it.
    #[inline]
    pub fn potential(&self, local_m: Vec3, band_local_m: f32) -> f32 {
        match self {
            ToolShape::Solid(s) => ramp(s.signed_distance(local_m), band_local_m),
            ToolShape::Ellipsoid(e) => match e.falloff {
                Falloff::Wyvill => wyvill(e.normalised_radius(local_m)),
                Falloff::Box => ramp(e.signed_distance(local_m), band_local_m),
            },
            ToolShape::Freeform(f) => f.potential(local_m),
        }
    }
}

#[inline]
fn ramp(distance: f32, band: f32) -> f32 {
    (0.5 - distance / band).clamp(0.0, 1.0)
}

/// Where a tool is: a 6-DoF pose and a scale along each of the tool's local axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolFrame {
    /// Position and orientation.
    pub pose: Pose,
    /// Scale along the local X, Y and Z axes, applied before the pose.
    pub scale: Vec3,
    /// A mirror image of the tool: local coordinates are read with X negated (see
    /// [`crate::math::Isometry::pose`]), so that an asymmetric shape appears reflected.
    pub mirrored: bool,
}

impl ToolFrame {
    /// A frame at `pose` with scale `scale`.
    pub fn new(pose: Pose, scale: Vec3) -> Self {
        Self { pose, scale, mirrored: false }
    }

    /// A frame at `pose` with scale `scale`, mirrored or not.
    pub fn with_mirror(pose: Pose, scale: Vec3, mirrored: bool) -> Self {
        Self { pose, scale, mirrored }
    }

    /// Takes a world point into the tool's local (unscaled) frame.
    #[inline]
    pub fn world_to_local(&self, world_m: Vec3) -> Vec3 {
        self.flip(self.pose.world_to_local(world_m)) / self.scale
    }

    /// Takes a world direction (or difference of points) into the local frame.
    #[inline]
    pub fn world_vector_to_local(&self, world: Vec3) -> Vec3 {
        self.flip(self.pose.rotation.inverse() * world) / self.scale
    }

    #[inline]
    fn flip(&self, v: Vec3) -> Vec3 {
        if self.mirrored {
            Vec3::new(-v.x, v.y, v.z)
        } else {
            v
        }
    }

    /// The smallest scale factor: local distances times it bound world distances from below.
    pub fn min_scale(&self) -> f32 {
        self.scale.min_element()
    }

    /// A world box containing the local box of half size `half_m` around the origin.
    pub fn world_bounds(&self, half_m: Vec3) -> Aabb {
        let m = self.pose.to_matrix() * crate::math::Mat4::from_scale(self.scale);
        Aabb::from_centre_half(Vec3::ZERO, half_m).transformed(&m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Quat;

    #[test]
    fn the_frame_scales_after_undoing_the_pose() {
        let frame = ToolFrame::new(
            Pose {
                position_m: Vec3::new(1.0, 0.0, 0.0),
                rotation: Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
            },
            Vec3::new(2.0, 1.0, 1.0),
        );
        // Local +X (scaled by 2) points along world +Y after the rotation.
        let local = frame.world_to_local(Vec3::new(1.0, 2.0, 0.0));
        assert!((local - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-6, "{local}");
        let b = frame.world_bounds(Vec3::splat(1.0));
        assert!((b.max - Vec3::new(2.0, 2.0, 1.0)).length() < 1e-5, "{:?}", b);
    }

    #[test]
    fn every_shape_is_one_inside_zero_outside() {
        let shapes = [
            ToolShape::sphere(0.01),
            ToolShape::Solid(Solid::Box { half_m: Vec3::new(0.01, 0.02, 0.03) }),
            ToolShape::Solid(Solid::Cylinder { radius_m: 0.01, half_height_m: 0.02 }),
            ToolShape::Ellipsoid(Ellipsoid {
                radii_m: Vec3::new(0.01, 0.02, 0.015),
                falloff: Falloff::Wyvill,
            }),
            ToolShape::Ellipsoid(Ellipsoid { radii_m: Vec3::new(0.01, 0.02, 0.015), falloff: Falloff::Box }),
        ];
        for s in shapes {
            assert_eq!(s.potential(Vec3::ZERO, 0.002), 1.0, "{s:?}");
            let far = s.half_extents_m() * 1.5 + Vec3::splat(0.002);
            assert_eq!(s.potential(far, 0.002), 0.0, "{s:?}");
        }
        let torus = ToolShape::Solid(Solid::Torus { major_m: 0.02, minor_m: 0.005 });
        assert_eq!(torus.potential(Vec3::new(0.02, 0.0, 0.0), 0.002), 1.0);
        assert_eq!(torus.potential(Vec3::ZERO, 0.002), 0.0);
    }
}
