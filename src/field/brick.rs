//! One brick: a dense `BRICK_SIZE`³ block of samples.
//!
//! ```text
//!  local index (x, y, z), each in 0..BRICK_SIZE        linear = x + S·(y + S·z)
//!
//!      z                       brick key K covers lattice points
//!     /                          K·S ..= K·S + (S − 1)   on each axis
//!    +------ x                 (keys are signed: the workspace is unbounded)
//!    |
//!    y
//! ```

use crate::math::IVec3;

/// Samples per brick edge. 8 keeps a brick (density + colour) at 10 KiB, small enough that a
/// stroke touches few samples it does not change, large enough that the per-brick overhead
/// (hash lookup, apron gather) stays a small part of meshing.
pub const BRICK_SIZE: i32 = 8;

/// Samples in one brick.
pub const BRICK_VOLUME: usize = (BRICK_SIZE * BRICK_SIZE * BRICK_SIZE) as usize;

/// Key of a brick: lattice point `p` lies in brick `p.div_euclid(BRICK_SIZE)`.
pub type BrickKey = IVec3;

/// A linear RGBA colour.
pub type Colour = [f32; 4];

/// The colour of samples nothing has painted: neutral clay grey.
pub const DEFAULT_COLOUR: Colour = [0.6, 0.6, 0.6, 1.0];

/// A dense block of samples: density in [0, 1] and linear RGBA colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Brick {
    /// Density per sample, linear index `x + S·(y + S·z)`.
    pub density: Box<[f32; BRICK_VOLUME]>,
    /// Colour per sample, same indexing.
    pub colour: Box<[Colour; BRICK_VOLUME]>,
}

impl Default for Brick {
    fn default() -> Self {
        Self { density: Box::new([0.0; BRICK_VOLUME]), colour: Box::new([DEFAULT_COLOUR; BRICK_VOLUME]) }
    }
}

impl Brick {
    /// Linear index of a local coordinate (each component in `0..BRICK_SIZE`).
    #[inline]
    pub fn linear(local: IVec3) -> usize {
        debug_assert!(local.cmpge(IVec3::ZERO).all() && local.cmplt(IVec3::splat(BRICK_SIZE)).all());
        (local.x + BRICK_SIZE * (local.y + BRICK_SIZE * local.z)) as usize
    }

    /// Whether every sample is empty (density 0): such a brick need not be stored.
    pub fn is_empty(&self) -> bool {
        self.density.iter().all(|&d| d == 0.0)
    }

    /// Total density (matter) in the brick, in sample units.
    pub fn mass(&self) -> f64 {
        self.density.iter().map(|&d| f64::from(d)).sum()
    }
}

/// The brick holding lattice point `p`, and `p`'s local coordinate in it.
#[inline]
pub fn split_index(p: IVec3) -> (BrickKey, IVec3) {
    let s = IVec3::splat(BRICK_SIZE);
    (p.div_euclid(s), p.rem_euclid(s))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_index_handles_negative_points() {
        assert_eq!(split_index(IVec3::new(-1, 0, 8)), (IVec3::new(-1, 0, 1), IVec3::new(7, 0, 0)));
        assert_eq!(split_index(IVec3::new(-8, -9, 7)), (IVec3::new(-1, -2, 0), IVec3::new(0, 7, 7)));
    }

    #[test]
    fn linear_index_is_x_fastest() {
        assert_eq!(Brick::linear(IVec3::new(1, 0, 0)), 1);
        assert_eq!(Brick::linear(IVec3::new(0, 1, 0)), 8);
        assert_eq!(Brick::linear(IVec3::new(0, 0, 1)), 64);
        assert_eq!(Brick::linear(IVec3::splat(7)), BRICK_VOLUME - 1);
    }
}
