//! Freeform tools (Ferley et al. 1999, §4.1.2): a region of a sculpt copied out of its field
//! and used as a tool's potential, reconstructed between samples by trilinear interpolation.
//!
//! The copy keeps the source's samples and spacing; the tool frame scales and orients it, and
//! the potential is read at each lattice point mapped into the copy, never resampled onto a
//! grid. The source's samples are band-limited, so the tool is too.

use crate::field::{Field, FieldReader};
use crate::math::{IVec3, UVec3, Vec3};

/// A copy of a box of a field's densities, centred on the box's centre.
#[derive(Clone, Debug, PartialEq)]
pub struct Freeform {
    samples: Vec<f32>,
    dims: UVec3,
    spacing_m: f32,
}

impl Freeform {
    /// Copies the densities of lattice points `lo ..= hi` of `field`. The tool's origin is the
    /// box's centre; its samples keep the field's spacing.
    ///
    /// # Panics
    /// If `lo` is above `hi` on an axis (an empty box is a caller bug).
    pub fn from_field(field: &Field, lo: IVec3, hi: IVec3) -> Self {
        assert!(lo.cmple(hi).all(), "freeform region {lo}..={hi} is empty");
        let dims = (hi - lo + IVec3::ONE).as_uvec3();
        let mut reader = FieldReader::new(field);
        let mut samples = Vec::with_capacity((dims.x * dims.y * dims.z) as usize);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    samples.push(reader.density(IVec3::new(x, y, z)));
                }
            }
        }
        Self { samples, dims, spacing_m: field.transform().voxel_size_m }
    }

    /// Copies the lattice points of `field` inside the world box `min_m ..= max_m`.
    pub fn from_world_box(field: &Field, min_m: Vec3, max_m: Vec3) -> Self {
        let t = field.transform();
        let lo = t.world_to_index(min_m.min(max_m)).ceil().as_ivec3();
        let hi = t.world_to_index(max_m.max(min_m)).floor().as_ivec3().max(lo);
        Self::from_field(field, lo, hi)
    }

    /// A copy made before (see [`Freeform::samples`]): `samples` holds `dims.x · dims.y ·
    /// dims.z` densities in [0, 1], x fastest, `spacing_m` apart; `None` when they do not.
    pub fn from_samples(samples: Vec<f32>, dims: UVec3, spacing_m: f32) -> Option<Self> {
        let fits = dims.cmpge(UVec3::ONE).all()
            && samples.len() as u64 == u64::from(dims.x) * u64::from(dims.y) * u64::from(dims.z)
            && spacing_m.is_finite()
            && spacing_m > 0.0
            && samples.iter().all(|d| (0.0..=1.0).contains(d));
        fits.then_some(Self { samples, dims, spacing_m })
    }

    /// The copied densities, x fastest, then y, then z.
    pub fn samples(&self) -> &[f32] {
        &self.samples
    }

    /// Distance between the copied samples, metres.
    pub fn spacing_m(&self) -> f32 {
        self.spacing_m
    }

    /// Half the size of the copied box, metres.
    pub fn half_extents_m(&self) -> Vec3 {
        (self.dims.as_vec3() - Vec3::ONE) * self.spacing_m * 0.5
    }

    /// Number of samples along each axis.
    pub fn dims(&self) -> UVec3 {
        self.dims
    }

    /// Sum of the copied densities (matter, in sample units of the source).
    pub fn mass(&self) -> f64 {
        self.samples.iter().map(|&d| f64::from(d)).sum()
    }

    #[inline]
    fn sample(&self, i: IVec3) -> f32 {
        if i.cmplt(IVec3::ZERO).any() || i.as_uvec3().cmpge(self.dims).any() {
            return 0.0;
        }
        let u = i.as_uvec3();
        self.samples[(u.x + self.dims.x * (u.y + self.dims.y * u.z)) as usize]
    }

    /// Trilinear density of the copy at a local point (0 outside it).
    #[inline]
    pub fn potential(&self, local_m: Vec3) -> f32 {
        let index = local_m / self.spacing_m + (self.dims.as_vec3() - Vec3::ONE) * 0.5;
        let base = index.floor();
        let f = index - base;
        let b = base.as_ivec3();
        if b.cmplt(IVec3::splat(-1)).any() || b.cmpge(self.dims.as_ivec3()).any() {
            return 0.0;
        }
        let mut acc = 0.0;
        for c in 0..8 {
            let o = IVec3::new(c & 1, (c >> 1) & 1, (c >> 2) & 1);
            let w = (if o.x == 1 { f.x } else { 1.0 - f.x })
                * (if o.y == 1 { f.y } else { 1.0 - f.y })
                * (if o.z == 1 { f.z } else { 1.0 - f.z });
            if w > 0.0 {
                acc += w * self.sample(b + o);
            }
        }
        acc.clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::{stamp_sphere, Action};

    #[test]
    fn a_copy_reproduces_the_samples_and_interpolates_between_them() {
        let mut f = Field::new(0.001, 0.5);
        stamp_sphere(&mut f, Vec3::new(0.0, 0.0, 0.0), 0.006, Action::Add, [1.0; 4]);
        let ff = Freeform::from_field(&f, IVec3::splat(-10), IVec3::splat(10));
        assert_eq!(ff.dims(), UVec3::splat(21));
        assert!((ff.mass() - f.mass()).abs() < 1e-3);
        assert_eq!(ff.potential(Vec3::ZERO), 1.0);
        // On the lattice: the source sample; between two: their mean.
        let p = IVec3::new(6, 0, 0);
        assert!((ff.potential(Vec3::new(0.006, 0.0, 0.0)) - f.density(p)).abs() < 1e-6);
        let mid = 0.5 * (f.density(p) + f.density(p + IVec3::X));
        assert!((ff.potential(Vec3::new(0.0065, 0.0, 0.0)) - mid).abs() < 1e-5);
        assert_eq!(ff.potential(Vec3::splat(0.02)), 0.0);
    }
}
