//! Writing a resampled copy of the clay brick by brick: what the region tools' drags and the
//! lattice write each time the hand or a control point moves.
//!
//! Such an edit recomputes the clay over a box from a copy of it as it was, many times over.
//! Most of its bricks come out whole: as they were, empty, or full of one colour. A
//! [`BrickPlan`] asks the edit what each brick becomes ([`Fill`]), evaluates point by point
//! only the bricks that come out mixed (on every thread), and writes only the bricks that
//! become other than what the last update left in them. It remembers what it left in each
//! brick, so an update may be asked of any bricks: those the edit may change now and, where
//! the edit's reach moves, those an earlier update changed.
//!
//! The plan holds for as long as nothing else writes the bricks it has written: the edits that
//! use it hold the field's stroke open for their whole session. An edit that shares its bricks
//! with another writer (lattices open side by side) names the points it may write: a brick is
//! decided and evaluated whole, but written only there.

use rustc_hash::FxHashMap as HashMap;

use rayon::prelude::*;

use super::{brick_key, Brick, Colour, Field, BRICK_SIZE, BRICK_VOLUME, DEFAULT_COLOUR};
use crate::math::IVec3;

/// What an update makes of a whole brick (or of a block of it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fill {
    /// The clay as it was.
    Original,
    /// No clay.
    Empty,
    /// Full clay of one colour.
    Full(Colour),
    /// Each point its own: evaluated one by one.
    Mixed,
}

impl Fill {
    /// The value of a point of a brick of this fill ([`Fill::Mixed`] has none), given the clay
    /// as it was there.
    #[inline]
    pub fn value(self, original: impl FnOnce() -> (f32, Colour)) -> Option<(f32, Colour)> {
        match self {
            Fill::Original => Some(original()),
            Fill::Empty => Some((0.0, DEFAULT_COLOUR)),
            Fill::Full(colour) => Some((1.0, colour)),
            Fill::Mixed => None,
        }
    }
}

/// How a brick is written: filled (never [`Fill::Mixed`]), or from its evaluated values.
#[derive(Clone, Copy, Debug)]
enum Planned {
    Fill(Fill),
    Values(usize),
}

/// What one update wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlanStats {
    /// Lattice points written (each brick that became other than what it held).
    pub written: u64,
    /// Of those, the points evaluated one by one (the rest are whole bricks or blocks filled or
    /// given back).
    pub evaluated: u64,
    /// Bricks written.
    pub bricks: usize,
}

/// What an edit left in each brick it changed, and the buffer its mixed bricks are evaluated
/// into, kept from one update to the next.
#[derive(Clone, Debug, Default)]
pub struct BrickPlan {
    /// What the last update left in each brick it holds other than as it was (by brick key).
    left: HashMap<IVec3, Fill>,
    /// The values of the bricks evaluated point by point.
    scratch: Vec<(f32, Colour)>,
}

impl BrickPlan {
    /// A plan that has written nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// The bricks the edit has left other than as they were.
    pub fn changed_bricks(&self) -> impl Iterator<Item = IVec3> + '_ {
        self.left.keys().copied()
    }

    /// Writes into `field` what the bricks `keys` become now (a caller whose reach moves asks
    /// of [`Self::changed_bricks`] too, which go back to the clay as it was when nothing
    /// reaches them): `fill(key)` decides a whole brick; a [`Fill::Mixed`] one is evaluated by
    /// `evaluate(key, reader, out)` into `out` in [`Brick::linear`] order (returning how many
    /// points it evaluated one by one), on every thread, each with a `reader()` of its own;
    /// `original(reader, p)` is the clay as it was at `p`. A brick that would come out as the
    /// last update left it is not written. Only the points `within` (`lo ..= hi`), where given,
    /// are written.
    #[allow(clippy::too_many_arguments)]
    pub fn write<R>(
        &mut self,
        field: &mut Field,
        within: Option<(IVec3, IVec3)>,
        keys: impl IntoIterator<Item = IVec3>,
        fill: impl Fn(IVec3) -> Fill + Sync,
        reader: impl Fn() -> R + Sync + Send,
        evaluate: impl Fn(IVec3, &mut R, &mut [(f32, Colour)]) -> usize + Sync + Send,
        original: impl Fn(&mut R, IVec3) -> (f32, Colour),
    ) -> PlanStats {
        let mut keys: Vec<IVec3> = keys.into_iter().collect();
        keys.sort_unstable_by_key(|k| k.to_array());
        keys.dedup();
        let fills: Vec<Fill> = keys.par_iter().map(|&key| fill(key)).collect();
        let was = |key: &IVec3| self.left.get(key).copied().unwrap_or(Fill::Original);
        // A brick left as it is now is not written again; a mixed one always is.
        let writes: Vec<(IVec3, Fill)> = keys
            .iter()
            .zip(&fills)
            .filter(|&(key, &fill)| fill == Fill::Mixed || fill != was(key))
            .map(|(&key, &fill)| (key, fill))
            .collect();
        // Each mixed brick's values at its place in the buffer.
        let mut mixed: Vec<IVec3> = Vec::new();
        let plan: HashMap<IVec3, Planned> = writes
            .iter()
            .map(|&(key, fill)| match fill {
                Fill::Mixed => {
                    mixed.push(key);
                    (key, Planned::Values(mixed.len() - 1))
                }
                fill => (key, Planned::Fill(fill)),
            })
            .collect();
        let mut values = std::mem::take(&mut self.scratch);
        values.resize(mixed.len() * BRICK_VOLUME, (0.0, DEFAULT_COLOUR));
        let evaluated: usize = values
            .par_chunks_mut(BRICK_VOLUME)
            .zip(&mixed)
            .map_init(&reader, |r, (out, &key)| evaluate(key, r, out))
            .sum();
        let size = IVec3::splat(BRICK_SIZE);
        let mut written = 0u64;
        if !writes.is_empty() {
            let lo = writes.iter().fold(IVec3::MAX, |a, w| a.min(w.0 * size));
            let hi = writes.iter().fold(IVec3::MIN, |a, w| a.max(w.0 * size + size - IVec3::ONE));
            let (lo, hi) = within.map_or((lo, hi), |(a, b)| (lo.max(a), hi.min(b)));
            let mut r = reader();
            let mut brick: Option<(IVec3, Planned)> = None;
            field.edit_region(
                lo,
                hi,
                true,
                |a, _| plan.contains_key(&brick_key(a)),
                |p, d, c| {
                    written += 1;
                    let key = brick_key(p);
                    let planned = match brick {
                        Some((k, planned)) if k == key => planned,
                        _ => {
                            let planned = plan[&key];
                            brick = Some((key, planned));
                            planned
                        }
                    };
                    (*d, *c) = match planned {
                        Planned::Fill(fill) => {
                            fill.value(|| original(&mut r, p)).expect("a planned fill is never mixed")
                        }
                        Planned::Values(i) => values[i * BRICK_VOLUME + Brick::linear(p - key * size)],
                    };
                },
            );
        }
        for (key, fill) in keys.into_iter().zip(fills) {
            if fill == Fill::Original {
                self.left.remove(&key);
            } else {
                self.left.insert(key, fill);
            }
        }
        self.scratch = values;
        PlanStats { written, evaluated: evaluated as u64, bricks: writes.len() }
    }
}

/// The keys of the bricks over the lattice box `lo ..= hi`.
pub fn bricks_over(lo: IVec3, hi: IVec3) -> impl Iterator<Item = IVec3> {
    let size = IVec3::splat(BRICK_SIZE);
    let (a, b) = (lo.div_euclid(size), hi.div_euclid(size));
    (a.z..=b.z)
        .flat_map(move |z| (a.y..=b.y).flat_map(move |y| (a.x..=b.x).map(move |x| IVec3::new(x, y, z))))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A brick written whole then given back: the field holds what the plan said, and a
    /// second update asking the same writes nothing.
    #[test]
    fn bricks_are_written_as_planned_and_not_again() {
        let mut field = Field::new(0.001, 0.5);
        let red = [1.0, 0.0, 0.0, 1.0];
        field.edit_box(IVec3::ZERO, IVec3::splat(15), true, |p, d, c| {
            *d = if p.x < 8 { 1.0 } else { 0.25 };
            *c = [0.0, 0.0, 1.0, 1.0];
        });
        let before = crate::field::DenseCopy::read(&field, IVec3::ZERO, IVec3::splat(23));
        let original = |_: &mut (), p: IVec3| (before.density(p), before.colour(p));
        let mut plan = BrickPlan::new();
        let fill = |key: IVec3| match key.x {
            0 => Fill::Full(red),
            1 => Fill::Mixed,
            _ => Fill::Original,
        };
        let evaluate = |key: IVec3, _: &mut (), out: &mut [(f32, Colour)]| {
            for (i, v) in out.iter_mut().enumerate() {
                *v = (i as f32 / BRICK_VOLUME as f32, red);
            }
            assert_eq!(key.x, 1);
            out.len()
        };
        let keys: Vec<IVec3> = bricks_over(IVec3::ZERO, IVec3::splat(23)).collect();
        assert_eq!(keys.len(), 27);
        let stats = plan.write(&mut field, None, keys.clone(), fill, || (), evaluate, original);
        // Bricks x = 0 and x = 1 of the 3 × 3 × 3 over the box.
        assert_eq!(stats.bricks, 18);
        assert_eq!(stats.evaluated, 9 * BRICK_VOLUME as u64);
        assert_eq!(field.density(IVec3::new(3, 3, 3)), 1.0);
        assert_eq!(field.colour(IVec3::new(3, 3, 3)), red);
        let local = IVec3::new(2, 5, 7);
        let expect = Brick::linear(local) as f32 / BRICK_VOLUME as f32;
        let got = field.density(IVec3::new(8, 0, 0) + local);
        assert!((got - expect).abs() <= crate::field::DENSITY_TOLERANCE, "{got} against {expect}");
        assert_eq!(field.density(IVec3::new(17, 3, 3)), 0.0);
        // The same again: the full bricks stay, the mixed ones are written again.
        let stats = plan.write(&mut field, None, keys.clone(), fill, || (), evaluate, original);
        assert_eq!(stats.bricks, 9);
        // Everything back as it was: only the bricks the plan changed are written, exactly.
        let stats = plan.write(&mut field, None, keys, |_| Fill::Original, || (), evaluate, original);
        assert_eq!((stats.bricks, stats.evaluated), (18, 0));
        for p in bricks_over(IVec3::ZERO, IVec3::splat(15)).flat_map(|k| {
            (0..BRICK_VOLUME as i32).map(move |i| k * BRICK_SIZE + IVec3::new(i % 8, (i / 8) % 8, i / 64))
        }) {
            assert_eq!((field.density(p), field.colour(p)), (before.density(p), before.colour(p)), "{p}");
        }
        assert_eq!(plan.changed_bricks().count(), 0);
    }
}
