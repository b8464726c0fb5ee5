//! Spaces, units and small geometric values shared by every stage.
//!
//! World space is in metres, right-handed, +Y up. Nothing outside this module converts between
//! world space and a field's index space: use [`VoxelTransform`].
//!
//! ```text
//!        +Y (WORLD_UP)
//!         |
//!         |
//!         +------ +X
//!        /
//!      +Z   (towards the default viewer)
//! ```
//!
//! This module depends on nothing else in the crate.

pub use glam::{IVec3, Mat3, Mat4, Quat, UVec3, Vec2, Vec3, Vec4};

/// The world's up direction.
pub const WORLD_UP: Vec3 = Vec3::Y;

/// The transform between a field's integer lattice and world space.
///
/// Lattice point `(i, j, k)` lies at `origin_m + (i, j, k) * voxel_size_m`. Samples live on
/// lattice points (the corners of marching-cubes cells), as in Galyean–Hughes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelTransform {
    /// Edge length of one voxel, in metres.
    pub voxel_size_m: f32,
    /// World position of lattice point (0, 0, 0), in metres.
    pub origin_m: Vec3,
}

impl VoxelTransform {
    /// A lattice of the given voxel size whose point (0, 0, 0) is the world origin.
    pub fn new(voxel_size_m: f32) -> Self {
        Self { voxel_size_m, origin_m: Vec3::ZERO }
    }

    /// World position of a (possibly fractional) lattice coordinate.
    pub fn index_to_world(&self, index: Vec3) -> Vec3 {
        self.origin_m + index * self.voxel_size_m
    }

    /// Fractional lattice coordinate of a world position.
    pub fn world_to_index(&self, world_m: Vec3) -> Vec3 {
        (world_m - self.origin_m) / self.voxel_size_m
    }

    /// A length in metres expressed in voxels.
    pub fn metres_to_voxels(&self, length_m: f32) -> f32 {
        length_m / self.voxel_size_m
    }
}

/// A rigid placement: rotation then translation, world space, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Position in metres.
    pub position_m: Vec3,
    /// Orientation.
    pub rotation: Quat,
}

impl Default for Pose {
    fn default() -> Self {
        Self { position_m: Vec3::ZERO, rotation: Quat::IDENTITY }
    }
}

impl Pose {
    /// Interpolates between two poses: linear in position, spherical in rotation.
    pub fn lerp(&self, other: &Pose, t: f32) -> Pose {
        Pose {
            position_m: self.position_m.lerp(other.position_m, t),
            rotation: self.rotation.slerp(other.rotation, t),
        }
    }

    /// The pose as a matrix taking local coordinates to world coordinates.
    pub fn to_matrix(&self) -> Mat4 {
        Mat4::from_rotation_translation(self.rotation, self.position_m)
    }

    /// Takes a world point into the pose's local frame.
    pub fn world_to_local(&self, world_m: Vec3) -> Vec3 {
        self.rotation.inverse() * (world_m - self.position_m)
    }
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box that contains nothing; growing it by a point gives that point's box.
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    /// A box from its centre and half extents.
    pub fn from_centre_half(centre: Vec3, half: Vec3) -> Self {
        Self { min: centre - half, max: centre + half }
    }

    /// Whether the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// The smallest box containing this box and `p`.
    pub fn grown_by_point(&self, p: Vec3) -> Self {
        Self { min: self.min.min(p), max: self.max.max(p) }
    }

    /// The smallest box containing both boxes.
    pub fn union(&self, other: &Aabb) -> Self {
        Self { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// The box grown by `margin` on every side.
    pub fn expanded(&self, margin: f32) -> Self {
        Self { min: self.min - Vec3::splat(margin), max: self.max + Vec3::splat(margin) }
    }

    /// The box's centre.
    pub fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// The box's size along each axis.
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    /// The box of a transformed box (the eight corners transformed).
    pub fn transformed(&self, m: &Mat4) -> Self {
        let mut out = Aabb::EMPTY;
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            );
            out = out.grown_by_point(m.transform_point3(c));
        }
        out
    }
}

/// Trilinear interpolation at a fractional lattice coordinate of a function given at lattice
/// points: the eight surrounding points, weighted by the products of their per-axis weights.
#[inline]
pub fn trilinear(index: Vec3, mut at: impl FnMut(IVec3) -> f32) -> f32 {
    let base = index.floor();
    let f = index - base;
    let b = base.as_ivec3();
    let mut acc = 0.0;
    for c in 0..8 {
        let o = IVec3::new(c & 1, (c >> 1) & 1, (c >> 2) & 1);
        let w = (if o.x == 1 { f.x } else { 1.0 - f.x })
            * (if o.y == 1 { f.y } else { 1.0 - f.y })
            * (if o.z == 1 { f.z } else { 1.0 - f.z });
        acc += w * at(b + o);
    }
    acc
}

/// Euclidean floor division of integers (rounds towards negative infinity).
pub fn div_floor(a: i32, b: i32) -> i32 {
    a.div_euclid(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn voxel_transform_round_trips() {
        let t = VoxelTransform { voxel_size_m: 0.002, origin_m: Vec3::new(0.1, -0.2, 0.3) };
        let p = Vec3::new(0.25, 0.5, -0.75);
        assert!((t.index_to_world(t.world_to_index(p)) - p).length() < 1e-6);
        assert_eq!(t.index_to_world(Vec3::ZERO), t.origin_m);
    }

    #[test]
    fn aabb_transformed_contains_rotated_corners() {
        let b = Aabb::from_centre_half(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        let m = Mat4::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let t = b.transformed(&m);
        assert!((t.size() - Vec3::new(6.0, 4.0, 2.0)).abs().max_element() < 1e-5);
    }

    #[test]
    fn div_floor_rounds_down() {
        assert_eq!(div_floor(-1, 8), -1);
        assert_eq!(div_floor(-8, 8), -1);
        assert_eq!(div_floor(-9, 8), -2);
        assert_eq!(div_floor(7, 8), 0);
    }
}
