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

impl ToolShape {
    /// The lowest and the highest potential over the local box (or parallelepiped) of
    /// `corners`, held in the ball of radius `radius_local_m` about `centre_local_m`. A solid's
    /// signed distance moves by at most the distance moved, so the ball bounds it both ways;
    /// a convex solid's is a convex function, so over the box it is at most its largest at
    /// the corners. Other shapes: 0 and 1 where the ball reaches the box of their influence,
    /// 0 and 0 where it does not.
    pub fn potential_bounds(
        &self,
        corners_local_m: &[Vec3; 8],
        centre_local_m: Vec3,
        radius_local_m: f32,
        band_local_m: f32,
    ) -> (f32, f32) {
        if let ToolShape::Solid(s) = self {
            let d = s.signed_distance(centre_local_m);
            // The farthest out any point of the box can be.
            let mut farthest = d + radius_local_m;
            if s.is_convex() {
                let corner =
                    corners_local_m.iter().fold(f32::NEG_INFINITY, |a, &c| a.max(s.signed_distance(c)));
                farthest = farthest.min(corner);
            }
            return (ramp(farthest, band_local_m), ramp(d - radius_local_m, band_local_m));
        }
        // A freeform's trilinear reads reach one spacing past its outer samples.
        let reach = match self {
            ToolShape::Freeform(f) => f.spacing_m(),
            _ if self.is_hard_edged() => 0.5 * band_local_m,
            _ => 0.0,
        };
        let outside = centre_local_m.abs() - Vec3::splat(radius_local_m);
        if outside.cmpgt(self.half_extents_m() + Vec3::splat(reach)).any() {
            (0.0, 0.0)
        } else {
            (0.0, 1.0)
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

    /// [`ToolFrame::world_to_local`] as an affine map, for many points.
    pub fn world_to_local_affine(&self) -> crate::math::Affine3A {
        let flip = if self.mirrored { Vec3::new(-1.0, 1.0, 1.0) } else { Vec3::ONE };
        let linear = crate::math::Mat3::from_diagonal(flip / self.scale)
            * crate::math::Mat3::from_quat(self.pose.rotation.inverse());
        crate::math::Affine3A::from_mat3(linear)
            * crate::math::Affine3A::from_translation(-self.pose.position_m)
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

    #[test]
    fn the_affine_map_into_a_frame_is_the_frame_s_own() {
        let pose = Pose {
            position_m: Vec3::new(0.1, -0.2, 0.3),
            rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1),
        };
        for mirrored in [false, true] {
            let frame = ToolFrame::with_mirror(pose, Vec3::new(1.5, 0.5, 2.0), mirrored);
            let affine = frame.world_to_local_affine();
            for p in [Vec3::ZERO, Vec3::new(0.3, 0.1, -0.2), Vec3::new(-1.0, 2.0, 0.5)] {
                let (a, b) = (affine.transform_point3(p), frame.world_to_local(p));
                assert!((a - b).length() < 1e-5, "{a} against {b}");
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 200,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0xb0b5),
            ..proptest::prelude::ProptestConfig::default()
        })]
        /// The bounds over a turned, scaled box hold every potential sampled in it.
        #[test]
        fn potential_bounds_hold_every_point_of_the_box(
            shape in 0usize..7,
            centre in proptest::array::uniform3(-0.03f32..0.03),
            size in proptest::array::uniform3(0.0005f32..0.02),
            turn in proptest::array::uniform3(-3.0f32..3.0),
        ) {
            let shapes = [
                ToolShape::sphere(0.01),
                ToolShape::Solid(Solid::Box { half_m: Vec3::new(0.01, 0.02, 0.015) }),
                ToolShape::Solid(Solid::RoundedBox { half_m: Vec3::new(0.01, 0.02, 0.015), corner_m: 0.004 }),
                ToolShape::Solid(Solid::Cylinder { radius_m: 0.01, half_height_m: 0.02 }),
                ToolShape::Solid(Solid::Torus { major_m: 0.015, minor_m: 0.005 }),
                ToolShape::Ellipsoid(Ellipsoid { radii_m: Vec3::new(0.01, 0.02, 0.015), falloff: Falloff::Wyvill }),
                ToolShape::Ellipsoid(Ellipsoid { radii_m: Vec3::new(0.01, 0.02, 0.015), falloff: Falloff::Box }),
            ];
            let s = &shapes[shape];
            let rotation = Quat::from_euler(glam::EulerRot::XYZ, turn[0], turn[1], turn[2]);
            let (centre, half) = (Vec3::from(centre), Vec3::from(size));
            let corner = |i: usize| {
                let o = Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32) * 2.0 - Vec3::ONE;
                centre + rotation * (o * half)
            };
            let corners: [Vec3; 8] = std::array::from_fn(corner);
            let band = 0.004;
            let (lo, hi) = s.potential_bounds(&corners, centre, half.length(), band);
            for i in 0..343 {
                let f = Vec3::new((i % 7) as f32, ((i / 7) % 7) as f32, (i / 49) as f32) / 3.0 - Vec3::ONE;
                let w = s.potential(centre + rotation * (f * half), band);
                proptest::prop_assert!(lo <= w && w <= hi, "{lo} ≤ {w} ≤ {hi} at {f}");
            }
        }
    }
}
