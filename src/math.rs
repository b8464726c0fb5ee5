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

pub use glam::{Affine3A, IVec3, Mat3, Mat4, Quat, UVec3, Vec2, Vec3, Vec4};

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

    /// [`VoxelTransform::index_to_world`] as an affine map.
    pub fn index_to_world_affine(&self) -> Affine3A {
        Affine3A::from_mat3_translation(Mat3::from_diagonal(Vec3::splat(self.voxel_size_m)), self.origin_m)
    }

    /// [`VoxelTransform::world_to_index`] as an affine map.
    pub fn world_to_index_affine(&self) -> Affine3A {
        let s = 1.0 / self.voxel_size_m;
        Affine3A::from_mat3_translation(Mat3::from_diagonal(Vec3::splat(s)), -self.origin_m * s)
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

/// A rigid motion that may mirror: `x ↦ linear·x + translation` with `linear` orthonormal
/// (determinant +1 for a rotation, −1 for a reflection). The images of a symmetry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Isometry {
    /// The orthonormal part.
    pub linear: Mat3,
    /// The translation, metres.
    pub translation: Vec3,
}

impl Default for Isometry {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Isometry {
    /// The identity.
    pub const IDENTITY: Self = Self { linear: Mat3::IDENTITY, translation: Vec3::ZERO };

    /// The reflection across the plane through `point_m` with unit normal `normal`.
    pub fn reflection(point_m: Vec3, normal: Vec3) -> Self {
        let n = normal.normalize();
        let linear = Mat3::IDENTITY - 2.0 * Mat3::from_cols(n * n.x, n * n.y, n * n.z);
        Self { linear, translation: point_m - linear * point_m }
    }

    /// The rotation by `angle` radians about the axis through `point_m` along `axis`.
    pub fn rotation_about(point_m: Vec3, axis: Vec3, angle: f32) -> Self {
        let linear = Mat3::from_axis_angle(axis.normalize(), angle);
        Self { linear, translation: point_m - linear * point_m }
    }

    /// The motion as a matrix taking points to their images.
    pub fn to_matrix(&self) -> Mat4 {
        Mat4::from_cols(
            self.linear.x_axis.extend(0.0),
            self.linear.y_axis.extend(0.0),
            self.linear.z_axis.extend(0.0),
            self.translation.extend(1.0),
        )
    }

    /// Whether it is the identity, within 1e-6 in every entry.
    pub fn is_identity(&self) -> bool {
        self.distance(&Isometry::IDENTITY) <= 1e-6
    }

    /// Whether it mirrors (reverses handedness).
    pub fn mirrors(&self) -> bool {
        self.linear.determinant() < 0.0
    }

    /// The image of a point.
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.linear * p + self.translation
    }

    /// The image of a direction.
    pub fn vector(&self, v: Vec3) -> Vec3 {
        self.linear * v
    }

    /// `self` after `first`.
    pub fn after(&self, first: &Isometry) -> Isometry {
        Isometry { linear: self.linear * first.linear, translation: self.point(first.translation) }
    }

    /// The inverse motion.
    pub fn inverse(&self) -> Isometry {
        let linear = self.linear.transpose();
        Isometry { linear, translation: -(linear * self.translation) }
    }

    /// The largest difference between the two maps' entries (rotation entries, and the
    /// translation in metres).
    pub fn distance(&self, other: &Isometry) -> f32 {
        let d = self.linear - other.linear;
        let linear = d.x_axis.abs().max(d.y_axis.abs()).max(d.z_axis.abs()).max_element();
        linear.max((self.translation - other.translation).abs().max_element())
    }

    /// The image of a pose, and whether the image is mirrored.
    ///
    /// A rotation carries the pose along. A reflection `M` takes the pose's frame `R` to the
    /// left-handed `M·R`; the pose returned is the proper rotation `M·R·D`, with `D` the flip
    /// of the local X axis, so that a local point `l` of the original lands on the returned
    /// frame's local point `D·l`: a mirrored image reads its local coordinates with X negated.
    pub fn pose(&self, pose: &Pose) -> (Pose, bool) {
        let frame = Mat3::from_quat(pose.rotation);
        let mirrored = self.mirrors();
        let flip = if mirrored { Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0)) } else { Mat3::IDENTITY };
        let rotation = Quat::from_mat3(&(self.linear * frame * flip)).normalize();
        (Pose { position_m: self.point(pose.position_m), rotation }, mirrored)
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

/// The median of `v` (the mean of the middle two for an even count; NaN when empty).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
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

/// `x.floor() as i32`, inlined: on the baseline x86-64 target `f64::floor` is a call into
/// the maths library, which the per-sample loops of the resampling tools cannot afford.
/// Exact for every `x` an `i32` holds; saturates as `as` does beyond.
#[inline(always)]
pub fn floor_i32(x: f64) -> i32 {
    let t = x as i32;
    t - i32::from((t as f64) > x)
}

/// `x.round() as i32` (halves away from zero), inlined as [`floor_i32`] is.
#[inline(always)]
pub fn round_i32(x: f64) -> i32 {
    let t = x as i32;
    let d = x - t as f64;
    t + i32::from(d >= 0.5) - i32::from(d <= -0.5)
}

/// Euclidean floor division of integers (rounds towards negative infinity).
pub fn div_floor(a: i32, b: i32) -> i32 {
    a.div_euclid(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inlined_floor_and_round_match_the_library() {
        let mut xs =
            vec![0.0, -0.0, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 1e-12, -1e-12, 7.0, -7.0, 123456.49999999999];
        xs.extend((0..2000).map(|i| (i as f64 - 1000.0) * 0.173 + 0.001 * (i % 7) as f64));
        for x in xs {
            assert_eq!(floor_i32(x), x.floor() as i32, "floor {x}");
            assert_eq!(round_i32(x), x.round() as i32, "round {x}");
        }
        assert_eq!(floor_i32(f64::NAN), 0);
    }

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
    fn a_mirrored_pose_reads_its_local_points_with_x_negated() {
        let m = Isometry::reflection(Vec3::new(0.1, 0.0, 0.0), Vec3::X);
        assert!(m.mirrors());
        let pose = Pose {
            position_m: Vec3::new(0.3, 0.2, -0.1),
            rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1),
        };
        let (image, mirrored) = m.pose(&pose);
        assert!(mirrored);
        for local in [Vec3::X, Vec3::Y, Vec3::new(0.2, -0.5, 0.7)] {
            let world = pose.to_matrix().transform_point3(local);
            let read = image.world_to_local(m.point(world)) * Vec3::new(-1.0, 1.0, 1.0);
            assert!((read - local).length() < 1e-5, "{read} {local}");
        }
        let r = Isometry::rotation_about(Vec3::Y, Vec3::Y, 1.0);
        assert!(!r.mirrors());
        assert!(r.after(&r.inverse()).distance(&Isometry::IDENTITY) < 1e-6);
        assert!(m.after(&m).distance(&Isometry::IDENTITY) < 1e-6);
    }

    #[test]
    fn div_floor_rounds_down() {
        assert_eq!(div_floor(-1, 8), -1);
        assert_eq!(div_floor(-8, 8), -1);
        assert_eq!(div_floor(-9, 8), -2);
        assert_eq!(div_floor(7, 8), 0);
    }
}
