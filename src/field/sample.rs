//! Reading the field between lattice points: trilinear density, colour and gradient.
//!
//! Galyean–Hughes reconstruct the band-limited characteristic function between samples by
//! linear interpolation (a triangle filter); so do we.

use super::brick::{split_index, Brick, BrickKey, Colour, DEFAULT_COLOUR};
use super::tree::Field;
use crate::math::{IVec3, Vec3};

/// A read accessor that remembers the last brick it visited, so that coherent reads (a
/// kernel walking neighbouring points) skip the hash lookup (OpenVDB's `ValueAccessor`).
/// One per thread; it borrows the field immutably.
///
/// It reads the finest level; where that holds no brick, the coarser levels' interpolation,
/// made once per brick visited.
#[derive(Debug)]
pub struct FieldReader<'f> {
    field: &'f Field,
    /// The last brick read: stored (borrowed), interpolated (in `refined`), or empty.
    cached: Option<(BrickKey, Cached<'f>)>,
    refined: Brick,
    coarse: bool,
}

#[derive(Clone, Copy, Debug)]
enum Cached<'f> {
    Stored(&'f Brick),
    Refined,
    Empty,
}

impl<'f> FieldReader<'f> {
    /// A reader over `field`.
    pub fn new(field: &'f Field) -> Self {
        Self { field, cached: None, refined: Brick::default(), coarse: field.has_levels_above(0) }
    }

    #[inline]
    fn brick(&mut self, key: BrickKey) -> Option<&Brick> {
        let cached = match self.cached {
            Some((k, c)) if k == key => c,
            _ => {
                let c = match self.field.brick(key) {
                    Some(b) => Cached::Stored(b),
                    None if self.coarse => match self.field.read_brick(key, &mut self.refined) {
                        Some(_) => Cached::Refined,
                        None => Cached::Empty,
                    },
                    None => Cached::Empty,
                };
                self.cached = Some((key, c));
                c
            }
        };
        match cached {
            Cached::Stored(b) => Some(b),
            Cached::Refined => Some(&self.refined),
            Cached::Empty => None,
        }
    }

    /// Density at a lattice point.
    #[inline]
    pub fn density(&mut self, p: IVec3) -> f32 {
        let (key, local) = split_index(p);
        self.brick(key).map_or(0.0, |b| b.density(Brick::linear(local)))
    }

    /// Colour at a lattice point.
    #[inline]
    pub fn colour(&mut self, p: IVec3) -> Colour {
        let (key, local) = split_index(p);
        self.brick(key).map_or(DEFAULT_COLOUR, |b| b.colour[Brick::linear(local)])
    }

    /// Trilinear density at a fractional lattice coordinate.
    pub fn density_at(&mut self, index: Vec3) -> f32 {
        crate::math::trilinear(index, |p| self.density(p))
    }

    /// Trilinear colour at a fractional lattice coordinate.
    pub fn colour_at(&mut self, index: Vec3) -> Colour {
        let base = index.floor();
        let f = index - base;
        let b = base.as_ivec3();
        let mut acc = [0.0f32; 4];
        for c in 0..8 {
            let o = IVec3::new(c & 1, (c >> 1) & 1, (c >> 2) & 1);
            let w = (if o.x == 1 { f.x } else { 1.0 - f.x })
                * (if o.y == 1 { f.y } else { 1.0 - f.y })
                * (if o.z == 1 { f.z } else { 1.0 - f.z });
            let col = self.colour(b + o);
            for (a, c) in acc.iter_mut().zip(col) {
                *a += w * c;
            }
        }
        acc
    }

    /// Gradient of the trilinear density by central differences, per lattice unit.
    pub fn gradient_at(&mut self, index: Vec3) -> Vec3 {
        let h = 0.5;
        Vec3::new(
            self.density_at(index + Vec3::X * h) - self.density_at(index - Vec3::X * h),
            self.density_at(index + Vec3::Y * h) - self.density_at(index - Vec3::Y * h),
            self.density_at(index + Vec3::Z * h) - self.density_at(index - Vec3::Z * h),
        ) / (2.0 * h)
    }

    /// Trilinear density at a world position (metres).
    pub fn density_world(&mut self, p_m: Vec3) -> f32 {
        let index = self.field.transform().world_to_index(p_m);
        self.density_at(index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trilinear_reproduces_a_linear_ramp() {
        let mut f = Field::new(1.0, 0.5);
        f.edit_box(IVec3::splat(-4), IVec3::splat(12), true, |p, d, _| *d = (p.x as f32 + 4.0) / 16.0);
        let mut r = FieldReader::new(&f);
        let v = r.density_at(Vec3::new(2.25, 3.5, -1.75));
        assert!((v - 6.25 / 16.0).abs() < 1e-6);
        let g = r.gradient_at(Vec3::new(2.25, 3.5, 1.0));
        assert!((g - Vec3::new(1.0 / 16.0, 0.0, 0.0)).length() < 1e-6);
    }
}
