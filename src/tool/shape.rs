//! Analytic solids: the primitives a scene's initial clay is made of.
//!
//! Each solid is described in its own local frame (centred at the origin, +Y up) by a signed
//! distance in metres: negative inside, positive outside, zero on the surface. Distances are
//! exact or a lower bound near the surface, which is all band-limited rasterisation needs.

use crate::math::{Aabb, Pose, Vec2, Vec3};

/// A solid in its local frame. All lengths in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Solid {
    /// A ball.
    Sphere {
        /// Radius.
        radius_m: f32,
    },
    /// A box with sharp edges.
    Box {
        /// Half the size along each local axis.
        half_m: Vec3,
    },
    /// A box whose edges and corners are rounded.
    RoundedBox {
        /// Half the size along each local axis, rounding included.
        half_m: Vec3,
        /// Radius of the rounded edges (at most the smallest half size).
        corner_m: f32,
    },
    /// A capped cylinder along local Y.
    Cylinder {
        /// Radius.
        radius_m: f32,
        /// Half the height.
        half_height_m: f32,
    },
    /// A ring around local Y, lying in the XZ plane.
    Torus {
        /// Distance from the centre to the tube's axis.
        major_m: f32,
        /// Radius of the tube.
        minor_m: f32,
    },
    /// A bar along local X with round section and hemispherical ends (a capsule): the piece
    /// of clay that Dewaele–Cani bend.
    Bar {
        /// Half the length, end caps included.
        half_length_m: f32,
        /// Radius of the section.
        radius_m: f32,
    },
}

impl Solid {
    /// Signed distance from a local point to the surface (negative inside).
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        match *self {
            Solid::Sphere { radius_m } => p.length() - radius_m,
            Solid::Box { half_m } => box_distance(p, half_m),
            Solid::RoundedBox { half_m, corner_m } => {
                let r = corner_m.min(half_m.min_element()).max(0.0);
                box_distance(p, half_m - Vec3::splat(r)) - r
            }
            Solid::Cylinder { radius_m, half_height_m } => {
                let d = Vec2::new(Vec2::new(p.x, p.z).length() - radius_m, p.y.abs() - half_height_m);
                d.max_element().min(0.0) + d.max(Vec2::ZERO).length()
            }
            Solid::Torus { major_m, minor_m } => {
                Vec2::new(Vec2::new(p.x, p.z).length() - major_m, p.y).length() - minor_m
            }
            Solid::Bar { half_length_m, radius_m } => {
                let h = (half_length_m - radius_m).max(0.0);
                Vec3::new(p.x - p.x.clamp(-h, h), p.y, p.z).length() - radius_m
            }
        }
    }

    /// Whether it is convex (its signed distance then a convex function).
    pub fn is_convex(&self) -> bool {
        !matches!(self, Solid::Torus { .. })
    }

    /// The solid's volume and surface area, m³ and m² (a rounded box's are its sharp box's, a
    /// little more). For estimates of what rasterising it costs.
    pub fn volume_and_area(&self) -> (f64, f64) {
        use std::f64::consts::PI;
        match *self {
            Solid::Sphere { radius_m } => {
                let r = f64::from(radius_m);
                (4.0 / 3.0 * PI * r.powi(3), 4.0 * PI * r * r)
            }
            Solid::Box { half_m } | Solid::RoundedBox { half_m, .. } => {
                let [a, b, c] = half_m.to_array().map(f64::from);
                (8.0 * a * b * c, 8.0 * (a * b + b * c + c * a))
            }
            Solid::Cylinder { radius_m, half_height_m } => {
                let (r, h) = (f64::from(radius_m), 2.0 * f64::from(half_height_m));
                (PI * r * r * h, 2.0 * PI * r * (r + h))
            }
            Solid::Torus { major_m, minor_m } => {
                let (big, r) = (f64::from(major_m), f64::from(minor_m));
                (2.0 * PI * PI * big * r * r, 4.0 * PI * PI * big * r)
            }
            Solid::Bar { half_length_m, radius_m } => {
                let r = f64::from(radius_m);
                let l = 2.0 * (f64::from(half_length_m) - r).max(0.0);
                (PI * r * r * (l + 4.0 / 3.0 * r), 2.0 * PI * r * (l + 2.0 * r))
            }
        }
    }

    /// A box containing the solid, in its local frame.
    pub fn local_bounds(&self) -> Aabb {
        let half = match *self {
            Solid::Sphere { radius_m } => Vec3::splat(radius_m),
            Solid::Box { half_m } | Solid::RoundedBox { half_m, .. } => half_m,
            Solid::Cylinder { radius_m, half_height_m } => Vec3::new(radius_m, half_height_m, radius_m),
            Solid::Torus { major_m, minor_m } => Vec3::new(major_m + minor_m, minor_m, major_m + minor_m),
            Solid::Bar { half_length_m, radius_m } => Vec3::new(half_length_m, radius_m, radius_m),
        };
        Aabb::from_centre_half(Vec3::ZERO, half)
    }
}

fn box_distance(p: Vec3, half: Vec3) -> f32 {
    let q = p.abs() - half;
    q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
}

/// A solid placed in the world: scaled uniformly, rotated, then translated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedSolid {
    /// The solid in its local frame.
    pub solid: Solid,
    /// Its placement.
    pub pose: Pose,
    /// Uniform scale applied before the pose.
    pub scale: f32,
}

impl PlacedSolid {
    /// Signed distance from a world point, in metres.
    pub fn signed_distance(&self, world_m: Vec3) -> f32 {
        let local = self.pose.world_to_local(world_m) / self.scale;
        self.solid.signed_distance(local) * self.scale
    }

    /// A world box containing the placed solid.
    pub fn bounds(&self) -> Aabb {
        let m = self.pose.to_matrix() * crate::math::Mat4::from_scale(Vec3::splat(self.scale));
        self.solid.local_bounds().transformed(&m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Quat;

    #[test]
    fn surfaces_are_where_the_sizes_say() {
        let cases = [
            (Solid::Sphere { radius_m: 0.1 }, Vec3::new(0.1, 0.0, 0.0)),
            (Solid::Box { half_m: Vec3::new(0.1, 0.2, 0.3) }, Vec3::new(0.0, 0.2, 0.0)),
            (Solid::RoundedBox { half_m: Vec3::splat(0.1), corner_m: 0.02 }, Vec3::new(0.0, 0.0, 0.1)),
            (Solid::Cylinder { radius_m: 0.05, half_height_m: 0.1 }, Vec3::new(0.0, 0.1, 0.0)),
            (Solid::Cylinder { radius_m: 0.05, half_height_m: 0.1 }, Vec3::new(0.05, 0.0, 0.0)),
            (Solid::Torus { major_m: 0.1, minor_m: 0.02 }, Vec3::new(0.12, 0.0, 0.0)),
            (Solid::Bar { half_length_m: 0.2, radius_m: 0.03 }, Vec3::new(0.2, 0.0, 0.0)),
            (Solid::Bar { half_length_m: 0.2, radius_m: 0.03 }, Vec3::new(0.0, 0.03, 0.0)),
        ];
        for (solid, surface_point) in cases {
            assert!(solid.signed_distance(surface_point).abs() < 1e-6, "{solid:?} at {surface_point}");
            assert!(
                solid.signed_distance(Vec3::ZERO.lerp(surface_point, 0.5)) < 0.0
                    || matches!(solid, Solid::Torus { .. })
            );
            assert!(solid.signed_distance(surface_point * 1.5) > 0.0, "{solid:?}");
            let b = solid.local_bounds();
            assert!(surface_point.cmple(b.max + 1e-6).all() && surface_point.cmpge(b.min - 1e-6).all());
        }
    }

    #[test]
    fn placement_scales_and_moves_the_distance() {
        let placed = PlacedSolid {
            solid: Solid::Sphere { radius_m: 1.0 },
            pose: Pose { position_m: Vec3::new(1.0, 0.0, 0.0), rotation: Quat::from_rotation_z(0.3) },
            scale: 0.1,
        };
        assert!(placed.signed_distance(Vec3::new(1.1, 0.0, 0.0)).abs() < 1e-6);
        assert!((placed.signed_distance(Vec3::new(1.3, 0.0, 0.0)) - 0.2).abs() < 1e-6);
        let b = placed.bounds();
        assert!((b.centre() - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-6);
    }
}
