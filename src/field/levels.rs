//! Resolution levels: how the coarser lattices are read, refined, edited and coarsened.
//!
//! ```text
//!  level 2  ●───────────────●───────────────●      voxel 4h     point q sits at finest 4q
//!  level 1  ●───────●───────●───────●───────●      voxel 2h     point q sits at finest 2q
//!  level 0  ●───●───●───●───●───●───●───●───●      voxel h      (the finest, default 1 mm)
//!                   └─ stored ──┘                   elsewhere: interpolated from level 1,
//!                                                   where level 1 has no brick, from level 2, …
//! ```
//!
//! - **The value at a point** of level `l` is its own brick's sample where level `l` holds a
//!   brick, else the trilinear interpolation of level `l + 1`'s values (recursively); where
//!   no level holds a brick it is empty. The finest level present wins, and the field seen on
//!   the finest lattice is the trilinear interpolation of these values: continuous
//!   everywhere, level boundaries included.
//! - **Refinement on demand**: an edit of level `l` where that level holds no brick but a
//!   coarser one does first stores the brick as the coarser levels give it (the field does
//!   not change), then edits it. Edits of the finest level (tools, clay, scenes) thereby work
//!   on coarse clay as on fine.
//! - **Editing a coarse level over fine detail** ([`Field::edit_level`]): the edit sees, at
//!   each of its points, the value of the finest level present there, writes the coarse
//!   level, and adds the change, interpolated, to every finer brick under it: the fine detail
//!   rides along instead of being erased. Where a change saturates (clay filled to 1,
//!   emptied to 0), the detail goes with it.
//! - **Tools on a coarse level** (`tool::apply_tool` with `Tool::level_samples`) edit it with
//!   [`Field::edit_level_alone`], then apply themselves again to the finer bricks under them,
//!   each on its own lattice ([`Field::edit_stored`]): a tool's `max`, `min` or paint keeps the
//!   fine clay's edges where it does not reach, and cuts its own edge as sharply as each
//!   lattice holds it. Carrying the interpolated coarse change down instead (what
//!   [`Field::edit_level`] does for any edit) left a carve over fine clay with a wavy edge: the
//!   change followed the coarse samples of the fine clay's ramp, which the coarse level does
//!   not resolve.
//! - **Coarsening**: after an edit, a brick of a level under a coarser one that equals the
//!   coarser levels' interpolation within [`DETAIL_TOLERANCE`] holds no detail and is dropped.
//! - Colours follow densities: matter that was there keeps its colour plus the interpolated
//!   change; new matter takes the interpolated colour of the coarse matter that brought it.

use super::brick::{
    dequantize, keys_over, lattice_points, quantize, Brick, BrickColours, BrickKey, Colour, LevelKey,
    Quantum, BRICK_SIZE, BRICK_VOLUME, DEFAULT_COLOUR, LEVELS,
};
use super::tree::{whole_rows, Field, Ranges, Reach, Walk};
use crate::math::IVec3;

/// A sample: density and colour.
type Sample = (f32, Colour);

/// What an edit of a coarse level did at one of its points: the change of density and of
/// colour (zero where there was no matter), and the new density and colour.
type Change = (f32, Colour, f32, Colour);

/// Marks a point no stored brick of the level holds, while a block is gathered.
const MISSING: Sample = (-1.0, DEFAULT_COLOUR);

/// Largest difference in density between a brick and the coarser levels' interpolation for
/// the brick to count as holding no detail. Zero: dropping a brick never changes a density
/// readers see, so the promises of the actions (painting keeps density, removing never adds)
/// hold to the bit; the bricks a coarse edit fills, empties or leaves as refined are dropped
/// all the same.
pub const DETAIL_TOLERANCE: f32 = 0.0;

/// Largest difference in each colour channel for a brick to count as holding no detail: far
/// below a display's step (1/255), above the rounding of colours interpolated in another order.
pub const COLOUR_DETAIL_TOLERANCE: f32 = 1e-5;

/// Index of `p` in a block `lo ..= lo + dims − 1`, x fastest.
#[inline]
fn at(p: IVec3, lo: IVec3, dims: IVec3) -> usize {
    let q = p - lo;
    (q.x + dims.x * (q.y + dims.y * q.z)) as usize
}

/// Fills the points of `out` (a finer level's points `lo ..= hi`, x fastest) that are
/// [`MISSING`] with the trilinear interpolation of `coarse` (the next coarser level's points
/// `c_lo ..= c_hi`, which cover them): density linearly, colour weighed by density (an empty
/// sample's colour means nothing) and plainly averaged where no tap holds matter. A point on
/// a coarse point takes its value exactly.
///
/// The interpolation is separable: each axis is halved in turn (a midpoint is the mean of its
/// two neighbours, an even point their copy), a few additions per point instead of eight taps.
/// Where every coarse sample holding matter has the same colour (clay of one colour), only
/// densities are interpolated and the points between coarse points take that colour exactly,
/// empty or not: a refined brick of one-coloured clay stays one colour, rounding included.
/// Otherwise the colour is carried premultiplied by density alongside the plain one.
fn upsample(coarse: &[Sample], c_lo: IVec3, c_hi: IVec3, lo: IVec3, hi: IVec3, out: &mut [Sample]) {
    if out.is_empty() {
        return;
    }
    let c_dims = (c_hi - c_lo + IVec3::ONE).to_array().map(|d| d as usize);
    // Per axis, each fine coordinate's lower coarse point (from `c_lo`) and whether it lies
    // between two coarse points.
    let maps: [Vec<(usize, bool)>; 3] = std::array::from_fn(|a| {
        (lo[a]..=hi[a]).map(|c| ((c.div_euclid(2) - c_lo[a]) as usize, c & 1 == 1)).collect()
    });
    // The colour of the coarse matter, if it has one (an empty sample's colour means nothing).
    let mut matter = coarse.iter().filter(|s| s.0 > 0.0).map(|s| s.1);
    let first = matter.next().unwrap_or(coarse[0].1);
    let uniform = matter.all(|c| c == first);
    if uniform {
        let density: Vec<f32> = coarse.iter().map(|s| s.0).collect();
        let fine = separable(density, c_dims, &maps, |a, b| 0.5 * (a + b));
        fill_missing(coarse, c_dims, &maps, out, |i| (fine[i], first));
        return;
    }
    // Density, colour premultiplied by density, plain colour, and 1 where the plain colour is
    // that of all the matter the point reads (0 elsewhere).
    let carried: Vec<[f32; 10]> = coarse
        .iter()
        .map(|&(d, c)| {
            [d, d * c[0], d * c[1], d * c[2], d * c[3], c[0], c[1], c[2], c[3], f32::from(d > 0.0)]
        })
        .collect();
    let fine = separable(carried, c_dims, &maps, |a, b| {
        let mut m: [f32; 10] = std::array::from_fn(|k| 0.5 * (a[k] + b[k]));
        // Matter of one colour keeps it exactly, as where all the coarse matter has one
        // colour: a point's colour then depends on the samples it reads alone.
        let one = match (a[0] > 0.0, b[0] > 0.0) {
            (true, true) => (a[9] == 1.0 && b[9] == 1.0 && a[5..9] == b[5..9]).then_some(a),
            (true, false) => (a[9] == 1.0).then_some(a),
            (false, true) => (b[9] == 1.0).then_some(b),
            (false, false) => None,
        };
        m[9] = 0.0;
        if let Some(c) = one {
            m[5..10].copy_from_slice(&c[5..10]);
        }
        m
    });
    fill_missing(coarse, c_dims, &maps, out, |i| {
        let f = &fine[i];
        let d = f[0];
        let colour = if d > 0.0 && f[9] == 0.0 {
            [f[1] / d, f[2] / d, f[3] / d, f[4] / d]
        } else {
            [f[5], f[6], f[7], f[8]]
        };
        (d, colour)
    });
}

/// Sets each [`MISSING`] point of `out` to its coarse sample where it lies on one, else to
/// `between(i)` (`i`: its index in `out`).
fn fill_missing(
    coarse: &[Sample],
    c_dims: [usize; 3],
    maps: &[Vec<(usize, bool)>; 3],
    out: &mut [Sample],
    between: impl Fn(usize) -> Sample,
) {
    let mut i = 0;
    for &(z0, z_odd) in &maps[2] {
        for &(y0, y_odd) in &maps[1] {
            for &(x0, x_odd) in &maps[0] {
                if out[i].0 < 0.0 {
                    out[i] = if x_odd || y_odd || z_odd {
                        // Stored as the finer level would store it, so that a brick the
                        // coarser levels give reads the same stored or not.
                        let (d, c) = between(i);
                        (dequantize(quantize(d)), c)
                    } else {
                        coarse[x0 + c_dims[0] * (y0 + c_dims[1] * z0)]
                    };
                }
                i += 1;
            }
        }
    }
}

/// Refines `coarse` (dims `c_dims`, x fastest) along x, then y, then z, each fine coordinate
/// of an axis given by `maps` as its lower coarse point and whether it lies midway. Along y
/// and z whole rows (planes) are copied or averaged at once.
fn separable<T: Copy>(
    coarse: Vec<T>,
    c_dims: [usize; 3],
    maps: &[Vec<(usize, bool)>; 3],
    mid: impl Fn(T, T) -> T,
) -> Vec<T> {
    let [cx, cy, cz] = c_dims;
    let [fx, fy, fz] = [maps[0].len(), maps[1].len(), maps[2].len()];
    let mut along_x = Vec::with_capacity(fx * cy * cz);
    for row in coarse.chunks_exact(cx) {
        along_x.extend(maps[0].iter().map(|&(c, odd)| if odd { mid(row[c], row[c + 1]) } else { row[c] }));
    }
    // Rows (y) or planes (z) of `src`, `len` values each, refined into `dst` by `map`.
    let refine = |src: &[T], len: usize, map: &[(usize, bool)], dst: &mut Vec<T>| {
        for &(c, odd) in map {
            let a = &src[c * len..(c + 1) * len];
            if odd {
                let b = &src[(c + 1) * len..(c + 2) * len];
                dst.extend(a.iter().zip(b).map(|(&a, &b)| mid(a, b)));
            } else {
                dst.extend_from_slice(a);
            }
        }
    };
    let mut along_y = Vec::with_capacity(fx * fy * cz);
    for plane in along_x.chunks_exact(fx * cy) {
        refine(plane, fx, &maps[1], &mut along_y);
    }
    let mut fine = Vec::with_capacity(fx * fy * fz);
    refine(&along_y, fx * fy, &maps[2], &mut fine);
    fine
}

/// Coarse points per axis under a brick: a brick's `S` points lie on or between `S/2 + 1`
/// points of the next coarser level (its lowest point is even).
const COARSE_AXIS: usize = BRICK_SIZE as usize / 2 + 1;
const COARSE_VOLUME: usize = COARSE_AXIS * COARSE_AXIS * COARSE_AXIS;

/// Refines the stored densities of the next coarser level's points under a brick (x fastest)
/// into the brick's stored densities, as [`upsample`] and the quantizing of
/// [`fill_missing`] do in floats: a point on a coarse point takes its value; one between
/// takes the mean of the `2^k` coarse points around it (`k`: the axes on which it lies
/// midway), rounded half up to a stored value. The means of stored values are exact in
/// floats, so the integers here give the same values bit for bit.
fn refine_brick_quanta(coarse: &[Quantum; COARSE_VOLUME], fine: &mut [Quantum; BRICK_VOLUME]) {
    const S: usize = BRICK_SIZE as usize;
    const C: usize = COARSE_AXIS;
    // Each axis in turn, keeping sums: twice the values along x, four times along y, eight
    // times along z.
    let mut along_x = [0u32; S * C * C];
    for (row, dst) in coarse.chunks_exact(C).zip(along_x.chunks_exact_mut(S)) {
        for (x, d) in dst.iter_mut().enumerate() {
            let c = x / 2;
            *d = u32::from(row[c]) + u32::from(row[c + (x & 1)]);
        }
    }
    let mut along_y = [0u32; S * S * C];
    for (plane, dst) in along_x.chunks_exact(S * C).zip(along_y.chunks_exact_mut(S * S)) {
        for (y, dst) in dst.chunks_exact_mut(S).enumerate() {
            let (a, b) = (&plane[(y / 2) * S..][..S], &plane[(y / 2 + (y & 1)) * S..][..S]);
            for ((d, &a), &b) in dst.iter_mut().zip(a).zip(b) {
                *d = a + b;
            }
        }
    }
    for (z, dst) in fine.chunks_exact_mut(S * S).enumerate() {
        let (a, b) = (&along_y[(z / 2) * S * S..][..S * S], &along_y[(z / 2 + (z & 1)) * S * S..][..S * S]);
        for ((d, &a), &b) in dst.iter_mut().zip(a).zip(b) {
            // Eight times the mean: round half up.
            *d = ((a + b + 4) >> 3) as Quantum;
        }
    }
}

impl Field {
    /// The values of level `level`'s points `lo ..= hi` into `out` (x fastest): the level's
    /// own samples where it holds a brick (unless `own` is false) and the coarser levels'
    /// interpolation elsewhere (see the module docs).
    pub(super) fn level_block(&self, level: usize, lo: IVec3, hi: IVec3, own: bool, out: &mut Vec<Sample>) {
        let dims = hi - lo + IVec3::ONE;
        out.clear();
        out.resize(lattice_points(lo, hi), MISSING);
        let mut missing = true;
        if own && !self.levels[level].bricks.is_empty() {
            for key in keys_over(lo, hi) {
                let Some(brick) = self.levels[level].bricks.get(&key) else { continue };
                let base = key * BRICK_SIZE;
                let (a, b) = (lo.max(base), hi.min(base + IVec3::splat(BRICK_SIZE - 1)));
                let len = (b.x - a.x + 1) as usize;
                for z in a.z..=b.z {
                    for y in a.y..=b.y {
                        // A row at a time: a run of samples in the brick and in the block.
                        let p = IVec3::new(a.x, y, z);
                        let (from, to) = (Brick::linear(p - base), at(p, lo, dims));
                        let (src, dst) = (&brick.density[from..from + len], &mut out[to..to + len]);
                        match &brick.colour {
                            BrickColours::Uniform(c) => {
                                for (o, &q) in dst.iter_mut().zip(src) {
                                    *o = (dequantize(q), *c);
                                }
                            }
                            BrickColours::PerSample(colours) => {
                                for ((o, &q), c) in dst.iter_mut().zip(src).zip(&colours[from..from + len]) {
                                    *o = (dequantize(q), *c);
                                }
                            }
                        }
                    }
                }
            }
            missing = out.iter().any(|s| s.0 < 0.0);
        }
        if !missing {
            return;
        }
        if !self.has_levels_above(level) {
            for s in out.iter_mut().filter(|s| s.0 < 0.0) {
                *s = (0.0, DEFAULT_COLOUR);
            }
            return;
        }
        let (c_lo, c_hi) = (lo.div_euclid(IVec3::splat(2)), (hi + IVec3::ONE).div_euclid(IVec3::splat(2)));
        let mut coarse = Vec::new();
        self.level_block(level + 1, c_lo, c_hi, true, &mut coarse);
        upsample(&coarse, c_lo, c_hi, lo, hi, out);
    }

    /// The values of level `level`'s points `lo ..= hi` as that level reads them, into `out`
    /// (x fastest): its own samples where it holds a brick, the coarser levels' interpolation
    /// elsewhere; finer levels are not read. Where no finer level holds a brick, these are the
    /// values readers see (the mesher meshes such clay on its own level).
    pub fn level_values(&self, level: usize, lo: IVec3, hi: IVec3, out: &mut Vec<(f32, Colour)>) {
        self.level_block(level, lo, hi, true, out);
    }

    /// Whether level `level` holds a brick over any of its points `lo ..= hi`.
    pub fn level_holds_over(&self, level: usize, lo: IVec3, hi: IVec3) -> bool {
        let bricks = &self.levels[level].bricks;
        !bricks.is_empty() && keys_over(lo, hi).any(|k| bricks.contains_key(&k))
    }

    /// The lattice of level `level`: the finest's origin, voxels `2^level` times as large.
    pub fn level_transform(&self, level: usize) -> crate::math::VoxelTransform {
        let mut t = self.transform;
        t.voxel_size_m *= (1u32 << level) as f32;
        t
    }

    /// The values of level `level`'s points `lo ..= hi` as an edit of that level sees them
    /// (see [`Field::edit_level`]): at each point, the finest level present there. x fastest.
    pub fn level_samples(&self, level: usize, lo: IVec3, hi: IVec3, out: &mut Vec<(f32, Colour)>) {
        self.level_block(level, lo, hi, true, out);
        self.overlay_finer(level, lo, hi, out);
    }

    /// Replaces each of `out`'s values of level `level`'s points `lo ..= hi` with the sample
    /// of the finest level finer than `level` holding the point, where one does.
    fn overlay_finer(&self, level: usize, lo: IVec3, hi: IVec3, out: &mut [Sample]) {
        if (0..level).all(|l| self.levels[l].bricks.is_empty()) {
            return;
        }
        let mut i = 0;
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    if let Some(s) = self.finer_sample(level, IVec3::new(x, y, z)) {
                        out[i] = s;
                    }
                    i += 1;
                }
            }
        }
    }

    /// The finest level, `level` or finer, holding a brick under level `level`'s points
    /// `lo ..= hi` (`level` itself where no finer one does).
    pub fn finest_level_under(&self, level: usize, lo: IVec3, hi: IVec3) -> usize {
        (0..level)
            .find(|&l| {
                let scale = 1 << (level - l);
                let bricks = &self.levels[l].bricks;
                !bricks.is_empty()
                    && keys_over(lo * scale, (hi + IVec3::ONE) * scale - IVec3::ONE)
                        .any(|k| bricks.contains_key(&k))
            })
            .unwrap_or(level)
    }

    /// Brick `key` of `level` as the coarser levels give it, if it holds matter.
    ///
    /// Where the coarse samples it reads hold matter of one colour (clay of one colour: most
    /// coarse clay), the densities are refined in integers from the coarse level's stored
    /// values ([`refine_brick_quanta`]), the same values as [`Field::level_block`]'s
    /// interpolation gives, without its samples of five floats each.
    pub(super) fn interpolated_brick(&self, level: usize, key: BrickKey) -> Option<Brick> {
        if !self.has_levels_above(level) {
            return None;
        }
        let base = key * BRICK_SIZE;
        let top = base + IVec3::splat(BRICK_SIZE - 1);
        // The next coarser level's points the brick's points lie on or between.
        let (c_lo, c_hi) = (base.div_euclid(IVec3::splat(2)), (top + IVec3::ONE).div_euclid(IVec3::splat(2)));
        let mut coarse = Vec::new();
        self.level_block(level + 1, c_lo, c_hi, true, &mut coarse);
        let mut matter = coarse.iter().filter(|s| s.0 > 0.0).map(|s| s.1);
        let first = matter.next()?;
        let mut brick = Brick::default();
        if matter.all(|c| c == first) {
            let quanta: [Quantum; COARSE_VOLUME] = std::array::from_fn(|i| quantize(coarse[i].0));
            refine_brick_quanta(&quanta, &mut brick.density);
            brick.colour = BrickColours::Uniform(first);
        } else {
            let mut samples = Vec::with_capacity(BRICK_VOLUME);
            samples.resize(BRICK_VOLUME, MISSING);
            upsample(&coarse, c_lo, c_hi, base, top, &mut samples);
            for (d, s) in brick.density.iter_mut().zip(&samples) {
                *d = quantize(s.0);
            }
            brick.colour = BrickColours::from_samples(|i| samples[i].1);
            brick.compact();
        }
        brick.density.iter().any(|&q| q > 0).then_some(brick)
    }

    /// Whether a coarser level holds a brick that level `level`'s brick `key` reads.
    pub(super) fn reads_above(&self, level: usize, key: BrickKey) -> bool {
        let base = key * BRICK_SIZE;
        (level + 1..LEVELS).any(|m| {
            let bricks = &self.levels[m].bricks;
            if bricks.is_empty() {
                return false;
            }
            let shift = (m - level) as i32;
            let lo = IVec3::new(base.x >> shift, base.y >> shift, base.z >> shift);
            let top = base + IVec3::splat(BRICK_SIZE - 1);
            let hi = IVec3::new(top.x >> shift, top.y >> shift, top.z >> shift) + IVec3::ONE;
            keys_over(lo, hi).any(|k| bricks.contains_key(&k))
        })
    }

    /// The sample of the finest level finer than `level` holding level `level`'s point `q`
    /// (`None`: no finer level holds it).
    fn finer_sample(&self, level: usize, q: IVec3) -> Option<Sample> {
        (0..level).find_map(|l| {
            let bricks = &self.levels[l].bricks;
            if bricks.is_empty() {
                return None;
            }
            let p = q * (1 << (level - l));
            let (key, local) = super::brick::split_index(p);
            bricks.get(&key).map(|b| {
                let i = Brick::linear(local);
                (b.density(i), b.colour[i])
            })
        })
    }

    /// Density at a lattice point of the finest level: its sample, or the coarser levels'
    /// interpolation where the finest level holds no brick.
    pub fn density(&self, p: IVec3) -> f32 {
        self.sample(p).0
    }

    /// Colour at a lattice point of the finest level (see [`Field::density`]).
    pub fn colour(&self, p: IVec3) -> Colour {
        self.sample(p).1
    }

    /// Density and colour at a lattice point of the finest level.
    pub fn sample(&self, p: IVec3) -> Sample {
        let (key, local) = super::brick::split_index(p);
        match self.levels[0].bricks.get(&key) {
            Some(b) => {
                let i = Brick::linear(local);
                (b.density(i), b.colour[i])
            }
            None if self.has_levels_above(0) => {
                let mut out = Vec::with_capacity(1);
                self.level_block(0, p, p, false, &mut out);
                out[0]
            }
            None => (0.0, DEFAULT_COLOUR),
        }
    }

    /// Brick `key` of the finest level as readers see it: the stored brick, or (written into
    /// `scratch`) the coarser levels' interpolation where the finest level holds none; `None`
    /// where the field is empty.
    pub fn read_brick<'a>(&'a self, key: BrickKey, scratch: &'a mut Brick) -> Option<&'a Brick> {
        if let Some(b) = self.levels[0].bricks.get(&key) {
            return Some(b);
        }
        if !self.has_levels_above(0) || !self.reads_above(0, key) {
            return None;
        }
        *scratch = self.interpolated_brick(0, key)?;
        Some(scratch)
    }

    /// The lowest and highest density of finest-level brick `key` as readers see it (see
    /// [`Field::read_brick`]): its own range where it is stored, else the range of the coarser
    /// levels' samples its interpolation reads, which holds it; `None` where the field is
    /// surely empty.
    pub fn read_range(&self, key: BrickKey) -> Option<(f32, f32)> {
        if let Some(r) = self.levels[0].ranges.get(&key) {
            return Some(r.all);
        }
        let base = key * BRICK_SIZE;
        let top = base + IVec3::splat(BRICK_SIZE - 1);
        let mut range: Option<(f32, f32)> = None;
        for m in 1..LEVELS {
            if self.levels[m].bricks.is_empty() {
                continue;
            }
            // The level-m points the interpolation reads, and the bricks that hold them.
            let shift = m as i32;
            let lo = IVec3::new(base.x >> shift, base.y >> shift, base.z >> shift);
            let hi = IVec3::new(top.x >> shift, top.y >> shift, top.z >> shift) + IVec3::ONE;
            let mut all = true;
            for k in keys_over(lo, hi) {
                let (Some(&Ranges { all: (a, b), .. }), Some(brick)) =
                    (self.levels[m].ranges.get(&k), self.levels[m].bricks.get(&k))
                else {
                    all = false;
                    continue;
                };
                // The interpolation is a weighted mean of the samples it reads: their range
                // holds it, and is far tighter than the coarse brick's (a coarse brick
                // crossing the surface lies over hundreds of finest bricks that do not).
                let (a, b) = if a == b {
                    (a, b)
                } else {
                    brick.density_range_in(lo - k * BRICK_SIZE, hi - k * BRICK_SIZE)
                };
                range = Some(range.map_or((a, b), |(lo, hi)| (lo.min(a), hi.max(b))));
            }
            if all {
                return range;
            }
        }
        // Some points read no level: they are empty.
        range.map(|(_, hi)| (0.0, hi))
    }

    /// Every finest-level brick that holds matter as readers see it: the stored ones and
    /// those the coarser levels cover, sorted.
    pub fn covered_keys(&self) -> Vec<BrickKey> {
        let mut keys: Vec<BrickKey> = self.brick_keys().collect();
        for m in 1..LEVELS {
            let scale = 1 << m;
            for key in self.level_keys(m) {
                // Level-m points key·S ..= key·S + S − 1 reach finest points strictly within
                // one level-m voxel of them.
                let lo = (key * BRICK_SIZE - IVec3::ONE) * scale + IVec3::ONE;
                let hi = (key * BRICK_SIZE + IVec3::splat(BRICK_SIZE)) * scale - IVec3::ONE;
                keys.extend(keys_over(lo, hi));
            }
        }
        keys.sort_unstable_by_key(|k| k.to_array());
        keys.dedup();
        keys
    }

    /// Total matter as readers see it on the finest lattice, in finest-sample units (sum of
    /// densities).
    pub fn mass(&self) -> f64 {
        let stored: f64 = self.levels[0].bricks.values().map(|b| b.mass()).sum();
        if !self.has_levels_above(0) {
            return stored;
        }
        let covered: f64 = self
            .covered_keys()
            .into_iter()
            .filter(|k| !self.levels[0].bricks.contains_key(k))
            .filter_map(|k| self.interpolated_brick(0, k))
            .map(|b| b.mass())
            .sum();
        stored + covered
    }

    /// Edits level `level`'s points `lo ..= hi` as [`Field::edit_where`] edits the finest
    /// level's, with that level's lattice (voxels `2^level` times the finest's, point `q` at
    /// finest point `q · 2^level`): `edit` sees at each point the value of the finest level
    /// present there, and the change it makes is carried, interpolated, into every finer brick
    /// under it (the fine detail rides along; see the module docs). One undo step with the
    /// rest of the stroke.
    pub fn edit_level(
        &mut self,
        level: usize,
        lo: IVec3,
        hi: IVec3,
        create: bool,
        changes: impl Fn(IVec3, IVec3, Option<(f32, f32)>) -> bool,
        edit: impl FnMut(IVec3, &mut f32, &mut Colour),
    ) {
        self.edit_level_then(level, lo, hi, create, changes, whole_rows, edit, true);
    }

    /// [`Field::edit_level`] for edits that reach the finer bricks themselves: the level is
    /// edited as there, and its change is not carried into the finer bricks under it; the
    /// caller edits those at their own resolution with [`Field::edit_stored`] (a tool
    /// evaluated on each finer lattice keeps its edge as sharp as that lattice holds it).
    ///
    /// `rows(y, z)` gives the span of each row the edit can change, as for
    /// [`Field::edit_where`]; it is honoured where no finer level holds a brick (over finer
    /// clay the level takes the finer values at every point of the box first, so every point
    /// is walked).
    #[allow(clippy::too_many_arguments)]
    pub fn edit_level_alone(
        &mut self,
        level: usize,
        lo: IVec3,
        hi: IVec3,
        create: bool,
        changes: impl Fn(IVec3, IVec3, Option<(f32, f32)>) -> bool,
        rows: impl Fn(i32, i32) -> (i32, i32),
        edit: impl FnMut(IVec3, &mut f32, &mut Colour),
    ) {
        self.edit_level_then(level, lo, hi, create, changes, rows, edit, false);
    }

    /// Edits the bricks `level` stores over its points `lo ..= hi`, creating and refining none
    /// (see [`Field::edit_where`] for `edit`); for the finer bricks under an
    /// [`Field::edit_level_alone`].
    pub fn edit_stored(
        &mut self,
        level: usize,
        lo: IVec3,
        hi: IVec3,
        edit: impl FnMut(IVec3, &mut f32, &mut Colour),
    ) {
        self.edit_existing(level, lo, hi, edit);
    }

    #[allow(clippy::too_many_arguments)]
    fn edit_level_then(
        &mut self,
        level: usize,
        lo: IVec3,
        hi: IVec3,
        create: bool,
        changes: impl Fn(IVec3, IVec3, Option<(f32, f32)>) -> bool,
        rows: impl Fn(i32, i32) -> (i32, i32),
        mut edit: impl FnMut(IVec3, &mut f32, &mut Colour),
        carry: bool,
    ) {
        assert!(level < LEVELS, "level {level} is beyond the field's {LEVELS}");
        if lo.cmpgt(hi).any() {
            return;
        }
        let finer = (0..level).any(|l| !self.levels[l].bricks.is_empty());
        let dims = hi - lo + IVec3::ONE;
        // Per point of the box: the change of density and colour, and the new matter.
        // (`None`: the edit did not reach the point.)
        let mut change: Vec<Option<Change>> =
            if finer { vec![None; lattice_points(lo, hi)] } else { Vec::new() };
        // The finest value present at each point, read before the walk writes.
        let mut truth = Vec::new();
        if finer {
            let mut shown = Vec::new();
            self.level_block(level, lo, hi, true, &mut shown);
            truth.clone_from(&shown);
            self.overlay_finer(level, lo, hi, &mut truth);
            self.hold_finest_around(level, lo, hi, &shown, &truth);
        }
        // Where finer clay lies under the level, the level takes its values (they may change
        // nothing: bricks that hold no detail are dropped again).
        let walk = Walk { create: create || finer, refine: true };
        let rows = |y, z| if finer { whole_rows(y, z) } else { rows(y, z) };
        self.edit_samples(level, lo, hi, walk, Reach { bricks: changes, rows }, |p, d, c| {
            if finer {
                (*d, *c) = truth[at(p, lo, dims)];
            }
            let (d0, c0) = (*d, *c);
            edit(p, d, c);
            if finer {
                let dc = if d0 > 0.0 { std::array::from_fn(|k| c[k] - c0[k]) } else { [0.0; 4] };
                change[at(p, lo, dims)] = Some((*d - d0, dc, *d, *c));
            }
        });
        if finer && carry {
            self.carry_down(level, lo, hi, &change);
        }
    }

    /// Before an edit of level `level` over `lo ..= hi` writes `truth` (the finest values
    /// present) into that level, which showed `shown`: where a point's value changes, the
    /// finest points that read it through the levels (no finest brick holds them) would change
    /// too; the finest bricks around such points are stored as they read now, so that only the
    /// edit's change reaches them.
    fn hold_finest_around(&mut self, level: usize, lo: IVec3, hi: IVec3, shown: &[Sample], truth: &[Sample]) {
        let scale = 1 << level;
        let mut keys = Vec::new();
        let mut i = 0;
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let ((td, tc), (sd, sc)) = (truth[i], shown[i]);
                    i += 1;
                    if td.to_bits() == sd.to_bits() && (td == 0.0 || tc == sc) {
                        continue;
                    }
                    // Finest points strictly within one voxel of the level around q.
                    let q = IVec3::new(x, y, z);
                    let (f_lo, f_hi) =
                        ((q - IVec3::ONE) * scale + IVec3::ONE, (q + IVec3::ONE) * scale - IVec3::ONE);
                    keys.extend(keys_over(f_lo, f_hi).filter(|k| !self.levels[0].bricks.contains_key(k)));
                }
            }
        }
        keys.sort_unstable_by_key(|k| k.to_array());
        keys.dedup();
        for key in keys {
            let brick = self.interpolated_brick(0, key).unwrap_or_default();
            let key = LevelKey::new(0, key);
            self.history.touch(key, None);
            self.store(key, std::sync::Arc::new(brick));
        }
    }

    /// Adds level `level`'s changes over `lo ..= hi`, interpolated, to every finer brick.
    fn carry_down(&mut self, level: usize, lo: IVec3, hi: IVec3, change: &[Option<Change>]) {
        let dims = hi - lo + IVec3::ONE;
        let get = |q: IVec3| -> Option<Change> {
            if q.cmpge(lo).all() && q.cmple(hi).all() {
                change[at(q, lo, dims)]
            } else {
                None
            }
        };
        for l in (0..level).rev() {
            if self.levels[l].bricks.is_empty() {
                continue;
            }
            let scale = 1 << (level - l);
            let inv = 1.0 / scale as f32;
            // Finer points strictly within one coarse voxel of the changed ones.
            let f_lo = (lo - IVec3::ONE) * scale + IVec3::ONE;
            let f_hi = (hi + IVec3::ONE) * scale - IVec3::ONE;
            self.edit_existing(l, f_lo, f_hi, |p, d, c| {
                let q0 = p.div_euclid(IVec3::splat(scale));
                let f = (p - q0 * scale).as_vec3() * inv;
                let (mut dd, mut dc, mut nd, mut nc) = (0.0f32, [0.0f32; 4], 0.0f32, [0.0f32; 4]);
                // Whether every coarse point around holds, after the edit, full or no clay.
                let (mut full, mut empty) = (true, true);
                for corner in 0..8 {
                    let o = IVec3::new(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
                    let w = (if o.x == 1 { f.x } else { 1.0 - f.x })
                        * (if o.y == 1 { f.y } else { 1.0 - f.y })
                        * (if o.z == 1 { f.z } else { 1.0 - f.z });
                    if w == 0.0 {
                        continue;
                    }
                    let Some((cd, cdc, cn, cnc)) = get(q0 + o) else {
                        (full, empty) = (false, false);
                        continue;
                    };
                    full &= cn >= 1.0;
                    empty &= cn <= 0.0;
                    dd += w * cd;
                    nd += w * cn;
                    for k in 0..4 {
                        dc[k] += w * cdc[k];
                        nc[k] += w * cn * cnc[k];
                    }
                }
                if dd == 0.0 && dc == [0.0; 4] {
                    return;
                }
                let old = *d;
                // Clay filled or emptied all around takes the detail with it.
                *d = if full {
                    1.0
                } else if empty {
                    0.0
                } else {
                    (old + dd).clamp(0.0, 1.0)
                };
                if old > 0.0 {
                    *c = std::array::from_fn(|k| (c[k] + dc[k]).clamp(0.0, 1.0));
                } else if nd > 0.0 {
                    *c = nc.map(|v| v / nd);
                }
            });
        }
    }

    /// Drops level `level`'s bricks among `keys` that hold no detail: equal to the coarser
    /// levels' interpolation within [`DETAIL_TOLERANCE`].
    pub(super) fn coarsen(&mut self, level: usize, keys: &[BrickKey]) {
        if !self.has_levels_above(level) {
            return;
        }
        let mut samples = Vec::new();
        for &key in keys {
            let Some(brick) = self.levels[level].bricks.get(&key) else { continue };
            let base = key * BRICK_SIZE;
            self.level_block(level, base, base + IVec3::splat(BRICK_SIZE - 1), false, &mut samples);
            let plain = samples.iter().enumerate().all(|(i, &(d, c))| {
                let (bd, bc) = (brick.density(i), brick.colour[i]);
                (bd - d).abs() <= DETAIL_TOLERANCE
                    && (bd == 0.0 && d == 0.0
                        || (0..4).all(|k| (bc[k] - c[k]).abs() <= COLOUR_DETAIL_TOLERANCE))
            });
            if plain {
                let key = LevelKey::new(level, key);
                let current = self.levels[level].bricks.get(&key.key).cloned();
                self.history.touch(key, current.as_ref());
                self.remove(key);
                self.mark_level_dirty(level, base, base + IVec3::splat(BRICK_SIZE - 1));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::brick::{DENSITY_ONE, DENSITY_TOLERANCE};
    use super::*;

    #[test]
    fn an_interpolated_colour_depends_on_the_samples_read_alone() {
        // Level-1 clay of one colour, with a spot of another a few points away: a finest
        // point reading only the first colour's matter takes it exactly, whether its brick is
        // refined whole (its coarse samples of two colours) or the point alone.
        let mut f = Field::new(0.001, 0.5);
        let (red, blue) = ([0.8, 0.1, 0.1, 1.0], [0.1, 0.2, 0.9, 1.0]);
        f.edit_level(
            1,
            IVec3::splat(-6),
            IVec3::splat(6),
            true,
            |_, _, _| true,
            |q, d, c| {
                *d = (0.3 + 0.05 * q.x as f32 + 0.03 * q.y as f32).clamp(0.0, 1.0);
                *c = if q == IVec3::new(3, 2, 1) { blue } else { red };
            },
        );
        let mut scratch = Brick::default();
        let brick = f.read_brick(IVec3::ZERO, &mut scratch).expect("coarse clay there").clone();
        let mut exact = 0;
        for i in 0..BRICK_VOLUME {
            let p = IVec3::new(i as i32 % 8, i as i32 / 8 % 8, i as i32 / 64);
            let (d, c) = f.sample(p);
            assert_eq!(brick.density(i), d, "{p}");
            if d > 0.0 {
                assert_eq!(brick.colour[i], c, "{p}");
                // Points whose coarse samples around hold red matter only are red, exactly.
                let reads_blue = (p - IVec3::new(6, 4, 2)).abs().max_element() < 2;
                exact += usize::from(!reads_blue && c == red);
            }
        }
        assert!(exact > 400, "{exact} points exactly red");
    }

    #[test]
    fn refining_in_integers_gives_the_float_interpolations_stored_values() {
        // Coarse values of every kind: empty, full, odd quanta (whose means round), and
        // neighbours far apart; bricks at negative and positive keys.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let colour = [0.3, 0.6, 0.9, 1.0];
        for key in [IVec3::ZERO, IVec3::new(-1, 2, -3), IVec3::new(5, -4, 1)] {
            for _ in 0..50 {
                let quanta: [Quantum; COARSE_VOLUME] = std::array::from_fn(|_| match next() % 4 {
                    0 => 0,
                    1 => DENSITY_ONE,
                    _ => (next() % (u64::from(DENSITY_ONE) + 1)) as Quantum,
                });
                let base = key * BRICK_SIZE;
                let top = base + IVec3::splat(BRICK_SIZE - 1);
                let (c_lo, c_hi) =
                    (base.div_euclid(IVec3::splat(2)), (top + IVec3::ONE).div_euclid(IVec3::splat(2)));
                let coarse: Vec<Sample> = quanta.iter().map(|&q| (dequantize(q), colour)).collect();
                let mut floats = vec![MISSING; BRICK_VOLUME];
                upsample(&coarse, c_lo, c_hi, base, top, &mut floats);
                let mut integers = [0; BRICK_VOLUME];
                refine_brick_quanta(&quanta, &mut integers);
                for (i, (q, s)) in integers.iter().zip(&floats).enumerate() {
                    assert_eq!(*q, quantize(s.0), "sample {i} of brick {key}");
                }
            }
        }
    }

    /// A field holding only level `level`'s points `lo ..= hi` on each axis, set by `edit`.
    fn level_clay(level: usize, lo: i32, hi: i32, edit: impl FnMut(IVec3, &mut f32, &mut Colour)) -> Field {
        let mut f = Field::new(0.001, 0.5);
        f.edit_level(level, IVec3::splat(lo), IVec3::splat(hi), true, |_, _, _| true, edit);
        f
    }

    /// A field whose level 2 holds a ramp along x over a slab, and nothing finer.
    fn coarse_ramp() -> Field {
        level_clay(2, -8, 8, |q, d, _| *d = ((q.x + 8) as f32 / 16.0).clamp(0.0, 1.0))
    }

    #[test]
    fn the_finest_lattice_reads_coarse_levels_by_interpolation() {
        let f = coarse_ramp();
        assert_eq!(f.brick_count(), 0);
        assert!(f.level_brick_count(2) > 0);
        // Level-2 point q sits at finest 4q: the ramp (q.x + 8) / 16 is (p.x / 4 + 8) / 16.
        for x in -28..=28 {
            let p = IVec3::new(x, 3, -5);
            let want = (x as f32 / 4.0 + 8.0) / 16.0;
            assert!((f.density(p) - want).abs() < 1e-6, "{p}: {} vs {want}", f.density(p));
        }
        // Beyond the coarse bricks the field is empty.
        assert_eq!(f.density(IVec3::new(0, 0, 4 * 30)), 0.0);
    }

    #[test]
    fn a_fine_edit_refines_on_demand_without_changing_the_rest() {
        let mut f = coarse_ramp();
        let before: Vec<f32> = (-20..20).map(|x| f.density(IVec3::new(x, 1, 1))).collect();
        f.begin_stroke();
        f.edit_box(IVec3::new(2, 1, 1), IVec3::new(2, 1, 1), false, |_, d, _| *d = 1.0);
        f.end_stroke();
        assert_eq!(f.brick_count(), 1, "one finest brick holds the edit");
        for (i, x) in (-20..20).enumerate() {
            let p = IVec3::new(x, 1, 1);
            let want = if x == 2 { 1.0 } else { before[i] };
            assert_eq!(f.density(p), want, "{p}");
        }
        // Undo restores the coarse-only field.
        f.undo().unwrap();
        assert_eq!(f.brick_count(), 0);
        assert!(f.same_samples(&coarse_ramp()));
    }

    #[test]
    fn fine_detail_rides_along_a_coarse_edit() {
        let mut f = coarse_ramp();
        // A fine dent, then a coarse edit that raises the whole ramp by 0.1.
        f.edit_box(IVec3::new(0, 0, 0), IVec3::new(0, 0, 0), false, |_, d, _| *d -= 0.2);
        let dent = f.density(IVec3::ZERO) - f.density(IVec3::new(1, 0, 0));
        f.begin_stroke();
        f.edit_level(2, IVec3::splat(-3), IVec3::splat(3), false, |_, _, _| true, |_, d, _| *d += 0.1);
        f.end_stroke();
        let after = f.density(IVec3::ZERO) - f.density(IVec3::new(1, 0, 0));
        assert!((after - dent).abs() < 1e-5, "the dent keeps its depth: {dent} then {after}");
        assert!((f.density(IVec3::new(1, 0, 0)) - (0.5 + 0.25 / 16.0 + 0.1)).abs() < 1e-5);
        // Undo brings back both levels.
        let mut g = coarse_ramp();
        g.edit_box(IVec3::new(0, 0, 0), IVec3::new(0, 0, 0), false, |_, d, _| *d -= 0.2);
        f.undo().unwrap();
        assert!(f.same_samples(&g));
    }

    #[test]
    fn a_coarse_edit_that_fills_the_detail_drops_the_fine_bricks() {
        let mut f = coarse_ramp();
        f.edit_box(IVec3::new(0, 0, 0), IVec3::new(3, 3, 3), false, |_, d, _| *d *= 0.5);
        assert!(f.brick_count() > 0);
        f.edit_level(2, IVec3::splat(-4), IVec3::splat(4), false, |_, _, _| true, |_, d, _| *d = 1.0);
        assert_eq!(f.brick_count(), 0, "no detail is left under solid clay");
        assert_eq!(f.density(IVec3::new(1, 2, 3)), 1.0);
    }

    #[test]
    fn values_are_continuous_across_a_level_boundary() {
        let mut f = coarse_ramp();
        f.edit_box(IVec3::new(-3, -3, -3), IVec3::new(3, 3, 3), false, |p, d, _| {
            *d = (*d + 0.01 * (p.y as f32)).clamp(0.0, 1.0);
        });
        assert_eq!(f.brick_count(), 8, "the edit refined the eight bricks around the origin");
        // Across the fine bricks' faces (between x = −9 and −8, and x = 7 and 8) neighbouring
        // points differ by the ramp's slope, as they do everywhere the edit did not reach: the
        // level boundary shows no step.
        for x in [-11, -10, -9, -8, 6, 7, 8, 9] {
            for y in [-9, -8, -1, 0, 7, 8] {
                let (a, b) = (f.density(IVec3::new(x, y, 2)), f.density(IVec3::new(x + 1, y, 2)));
                assert!((b - a - 1.0 / 64.0).abs() <= 1e-6, "x {x}, y {y}: {a} then {b}");
            }
        }
    }

    /// A sample of level `level` as stored (empty where no brick holds it).
    fn stored(f: &Field, level: usize, q: IVec3) -> Sample {
        let (key, local) = super::super::brick::split_index(q);
        f.level_brick(LevelKey::new(level, key)).map_or((0.0, DEFAULT_COLOUR), |b| {
            (b.density(Brick::linear(local)), b.colour[Brick::linear(local)])
        })
    }

    /// A field whose level 2 holds scattered densities in two colours: no two neighbours alike.
    fn coarse_noise() -> Field {
        level_clay(2, -6, 9, |q, d, c| {
            let h = ((q.x * 73_856_093) ^ (q.y * 19_349_663) ^ (q.z * 83_492_791)) as u32;
            *d = if h % 5 == 0 { 0.0 } else { (h % 1000) as f32 / 999.0 };
            *c = if h & 1 == 0 { [0.9, 0.1, 0.2, 1.0] } else { [0.1, 0.3, 0.8, 0.5] };
        })
    }

    #[test]
    fn the_finest_lattice_is_the_trilinear_interpolation_of_the_coarse_samples() {
        let f = coarse_noise();
        let mut scratch = Brick::default();
        let mut checked = 0;
        for key in keys_over(IVec3::splat(-12), IVec3::splat(20)) {
            let Some(brick) = f.read_brick(key, &mut scratch) else { continue };
            for i in 0..BRICK_VOLUME {
                let p = key * BRICK_SIZE + IVec3::new(i as i32 % 8, i as i32 / 8 % 8, i as i32 / 64);
                // Level-2 point q sits at finest 4q: eight taps with weights in quarters.
                let (q, r) = (p.div_euclid(IVec3::splat(4)), p.rem_euclid(IVec3::splat(4)).as_vec3() / 4.0);
                let (mut d, mut weighted, mut plain) = (0.0f32, [0.0f32; 4], [0.0f32; 4]);
                for corner in 0..8 {
                    let o = IVec3::new(corner & 1, corner >> 1 & 1, corner >> 2);
                    let w = (0..3).map(|a| if o[a] == 1 { r[a] } else { 1.0 - r[a] }).product::<f32>();
                    let (cd, cc) = stored(&f, 2, q + o);
                    d += w * cd;
                    for k in 0..4 {
                        weighted[k] += w * cd * cc[k];
                        plain[k] += w * cc[k];
                    }
                }
                let colour = if d > 0.0 { weighted.map(|c| c / d) } else { plain };
                let (got_d, got_c) = (brick.density(i), brick.colour[i]);
                // Stored to the nearest step of a density on level 1, then on the finest.
                let tolerance = 2.0 * DENSITY_TOLERANCE + 1e-6;
                assert!((got_d - d).abs() <= tolerance, "{p}: density {got_d}, trilinear {d}");
                if d > 1e-3 {
                    // Colours are weighed by level 1's densities, each off by a step at most.
                    let tolerance = 1e-5 + 2.0 * DENSITY_TOLERANCE / d;
                    for k in 0..4 {
                        assert!(
                            (got_c[k] - colour[k]).abs() <= tolerance,
                            "{p}: colour {got_c:?}, trilinear {colour:?}"
                        );
                    }
                }
                if p.rem_euclid(IVec3::splat(4)) == IVec3::ZERO {
                    assert_eq!((got_d, got_c), stored(&f, 2, q), "{p} sits on a coarse point");
                }
                checked += 1;
            }
        }
        assert!(checked > 20_000, "{checked} samples checked");
        // An empty box reads nothing.
        let mut out = vec![(1.0, DEFAULT_COLOUR)];
        f.level_block(0, IVec3::splat(3), IVec3::splat(2), false, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn one_coloured_clay_refines_to_its_colour_exactly() {
        let teal: Colour = [0.1, 0.7, 0.63, 0.9];
        let f = level_clay(3, -4, 4, |q, d, c| {
            *d = (1.3 - q.as_vec3().length() / 3.0).clamp(0.0, 1.0);
            *c = teal;
        });
        let mut scratch = Brick::default();
        let mut bricks = 0;
        for key in f.covered_keys() {
            let Some(brick) = f.read_brick(key, &mut scratch) else { continue };
            // Exactly that colour, stored once: rounding would store one colour per sample.
            assert!(matches!(brick.colour, BrickColours::Uniform(c) if c == teal), "{key}: not one colour");
            bricks += 1;
        }
        assert!(bricks > 100, "{bricks} bricks");
    }

    #[test]
    fn ranges_of_coarse_clay_are_those_of_the_samples_read() {
        let f =
            level_clay(3, -6, 6, |q, d, _| *d = (0.5 + (4.5 - q.as_vec3().length()) / 2.0).clamp(0.0, 1.0));
        // The finest bricks at the centre read only full coarse samples, those far out only
        // empty ones, though every level-3 brick around them crosses the surface.
        assert_eq!(f.read_range(IVec3::ZERO), Some((1.0, 1.0)));
        assert_eq!(f.read_range(IVec3::new(-7, 0, 0)), Some((0.0, 0.0)));
        let keys = f.covered_keys();
        let crossing =
            keys.iter().filter(|&&k| f.read_range(k).is_some_and(|(lo, hi)| lo < 0.5 && hi >= 0.5));
        let crossing = crossing.count();
        assert!(crossing * 3 < keys.len(), "{crossing} of {} covered bricks may cross", keys.len());
    }

    #[test]
    fn covered_keys_and_ranges_describe_the_coarse_clay() {
        let f = coarse_ramp();
        let keys = f.covered_keys();
        // The level-2 bricks cover finest points −35 ..= 35 and more on each axis.
        assert!(keys.contains(&IVec3::new(-4, 0, 3)) && keys.contains(&IVec3::new(3, -4, 0)));
        let mut scratch = Brick::default();
        for &k in &keys {
            let (lo, hi) = f.read_range(k).expect("covered");
            let brick = f.read_brick(k, &mut scratch);
            if let Some(b) = brick {
                for d in b.densities() {
                    assert!(d >= lo && d <= hi, "{k}: {d} outside {lo}..{hi}");
                }
            }
        }
        assert_eq!(f.read_range(IVec3::new(100, 0, 0)), None);
        // The mass seen on the finest lattice is the interpolated ramp's.
        assert!(f.mass() > 0.0);
    }
}
