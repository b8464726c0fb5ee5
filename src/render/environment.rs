//! Environment lighting on the CPU: from an [`Environment`] to the cube maps and spherical
//! harmonics the GPU reads.
//!
//! Nothing here touches Vulkan. The renderer uploads:
//!
//! - a **radiance cube** ([`build_radiance_cube`]) with a full box-filtered mip chain, sampled
//!   for the background and, at [`reflection_lod`], for glossy reflections on the clay;
//! - nine **irradiance coefficients** ([`irradiance_sh9`]) that the clay shader evaluates with
//!   exactly the formula of [`eval_sh9`] for diffuse ambient light.
//!
//! Directions are in world space: right-handed, +Y up, the default viewer on +Z looking towards
//! −Z. Colours are linear RGB radiance.

use std::f32::consts::{FRAC_PI_2, PI};

use rayon::prelude::*;

use super::Environment;
use crate::math::Vec3;

/// A cube map in linear RGB: six faces in Vulkan layer order (+X, −X, +Y, −Y, +Z, −Z), each
/// with a full mip chain.
///
/// `levels[0]` holds `size × size` texels per face; each next level halves the side (a 2 × 2
/// box filter) down to 1 × 1, so there are `log2(size) + 1` levels. Each face is row-major:
/// texel `(s, t)` (column `s`, row `t`, as in Vulkan's cube map texture coordinates) is at
/// index `t * side + s`. Alpha is always 1.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeMap {
    /// Side of level 0 in texels (a power of two).
    pub size: u32,
    /// The mip chain, level 0 first; each level holds the six faces in layer order.
    pub levels: Vec<[Vec<[f32; 4]>; 6]>,
}

impl CubeMap {
    /// Side in texels of mip level `level` (at least 1).
    pub fn level_size(&self, level: usize) -> u32 {
        (self.size >> level.min(31)).max(1)
    }
}

/// Hermite smoothstep: 0 below `e0`, 1 above `e1`, C¹-smooth in between.
fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A soft-edged rectangle: 1 inside `|p - centre| < half - soft` on both axes, 0 outside
/// `half + soft`, smooth in between.
fn soft_rect(p: (f32, f32), centre: (f32, f32), half: (f32, f32), soft: f32) -> f32 {
    let dx = (p.0 - centre.0).abs();
    let dy = (p.1 - centre.1).abs();
    (1.0 - smoothstep(half.0 - soft, half.0 + soft, dx))
        * (1.0 - smoothstep(half.1 - soft, half.1 + soft, dy))
}

/// The built-in procedural studio: the radiance arriving from direction `dir` (world space,
/// need not be normalised; a zero or non-finite `dir` gives black).
///
/// It is smooth everywhere (every edge is a smoothstep or a Gaussian), finite and
/// non-negative, so it mip-maps and projects onto spherical harmonics without ringing from
/// hard edges:
///
/// - **floor** (below the horizon): dark and slightly warm, a gentle gradient from about 0.05
///   straight down to 0.1 at the horizon;
/// - **horizon**: a soft warm band about ±5° wide;
/// - **sky**: cool grey, from about 0.3 at the horizon to 0.45 at the zenith;
/// - **key softbox**: a large rectangle on a virtual ceiling one unit up, centred slightly in
///   front of the subject (towards the viewer, +Z), radiance about 5, with soft edges;
/// - **strip light**: a tall, softer vertical strip on a virtual wall one unit to the left
///   (−X), radiance about 2.
///
/// ```text
///  top view (looking down -Y)             side view (from -X, looking towards +X)
///
///              -Z                                +Y    key softbox (ceiling y = 1)
///               |                                 |  ============
///   strip  #  +-|-+                         sky   |                  sky
///   light  #  | o |  o = clay               -Z ----o-------------------> +Z (viewer)
///  (x=-1)  #  |key|  key softbox            ~~~~~~~~~~~~~~~~~~~~~~~~~~~~  warm horizon band
///             +-|-+  overhead                    dark warm floor
///               |
///              +Z (viewer)
///
///  key softbox: plane y = 1, x in [-0.55, 0.55], z in [-0.05, 0.75], radiance ~5
///  strip light: plane x = -1, z in [0, 0.3], y in [-0.4, 0.9], radiance ~2
///  (extents measured to the middle of the soft edges)
/// ```
pub fn studio_radiance(dir: Vec3) -> Vec3 {
    let Some(d) = dir.try_normalize() else { return Vec3::ZERO };
    let y = d.y;

    // Floor: 0.05 looking straight down, 0.1 at the horizon; warm.
    let floor = Vec3::new(1.0, 0.88, 0.74) * (0.05 + 0.05 * (1.0 + y.min(0.0)));
    // Sky: cool grey, brighter towards the zenith.
    let sky = Vec3::new(0.88, 0.94, 1.04) * (0.3 + 0.15 * y.max(0.0));
    // Cross-fade floor → sky across the horizon, then add a warm band on it.
    let mut radiance = floor.lerp(sky, smoothstep(-0.04, 0.06, y));
    let band = (-(y / 0.09) * (y / 0.09)).exp();
    radiance += Vec3::new(1.0, 0.8, 0.6) * (0.22 * band);

    // Key softbox on the ceiling plane y = 1. Below y = 0.1 the ray meets the plane beyond
    // 9.9 units from the centre, far outside the box, so cutting it off there is continuous.
    if y > 0.1 {
        let p = (d.x / y, d.z / y);
        let w = soft_rect(p, (0.0, 0.35), (0.55, 0.4), 0.2);
        radiance += Vec3::new(1.0, 0.97, 0.92) * (5.0 * w);
    }

    // Strip light on the wall plane x = −1 (to the left). As above, the cut-off at −x = 0.1
    // lies far outside the strip.
    if -d.x > 0.1 {
        let q = (d.z / -d.x, d.y / -d.x);
        let w = soft_rect(q, (0.15, 0.25), (0.15, 0.65), 0.12);
        radiance += Vec3::new(0.92, 0.96, 1.0) * (2.0 * w);
    }

    radiance
}

/// The direction through texture coordinates `(s, t)` ∈ [0, 1]² of cube face `face` (Vulkan
/// layer order: 0 = +X, 1 = −X, 2 = +Y, 3 = −Y, 4 = +Z, 5 = −Z), normalised.
///
/// This inverts the Vulkan specification's "Cube Map Face Selection" table: with the major
/// axis component `ma` and `s = (sc / |ma| + 1) / 2`, `t = (tc / |ma| + 1) / 2`,
///
/// | face | ma  | sc  | tc  |
/// |------|-----|-----|-----|
/// | +X   | +rx | −rz | −ry |
/// | −X   | −rx | +rz | −ry |
/// | +Y   | +ry | +rx | +rz |
/// | −Y   | −ry | +rx | −rz |
/// | +Z   | +rz | +rx | −ry |
/// | −Z   | −rz | −rx | −ry |
///
/// # Panics
///
/// If `face > 5`.
pub fn cube_face_direction(face: usize, s: f32, t: f32) -> Vec3 {
    let sc = 2.0 * s - 1.0;
    let tc = 2.0 * t - 1.0;
    let d = match face {
        0 => Vec3::new(1.0, -tc, -sc),
        1 => Vec3::new(-1.0, -tc, sc),
        2 => Vec3::new(sc, 1.0, tc),
        3 => Vec3::new(sc, -1.0, -tc),
        4 => Vec3::new(sc, -tc, 1.0),
        5 => Vec3::new(-sc, -tc, -1.0),
        _ => panic!("cube face {face} out of range 0..6"),
    };
    d.normalize()
}

/// Bilinear sample of an equirectangular image in direction `d` (normalised): wraps
/// horizontally, clamps vertically, texel centres at half-integers.
fn sample_equirect(width: u32, height: u32, texels: &[[f32; 3]], d: Vec3) -> Vec3 {
    let (w, h) = (width as usize, height as usize);
    let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    let x = u * width as f32 - 0.5;
    let y = v * height as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let col = |i: f32| (i as i64).rem_euclid(w as i64) as usize;
    let row = |j: f32| (j.max(0.0) as usize).min(h - 1);
    let (c0, c1) = (col(x0), col(x0 + 1.0));
    let (r0, r1) = (row(y0), row(y0 + 1.0));
    let at = |r: usize, c: usize| Vec3::from_array(texels[r * w + c]);
    let top = at(r0, c0).lerp(at(r0, c1), fx);
    let bottom = at(r1, c0).lerp(at(r1, c1), fx);
    top.lerp(bottom, fy)
}

/// Builds the radiance cube of `env`, scaled by `intensity`, with a full mip chain.
///
/// `size` is rounded up to a power of two (at least 1). Level 0 is sampled at texel centres:
/// [`Environment::Studio`] through [`studio_radiance`]; [`Environment::Equirect`] bilinearly
/// (wrapping horizontally, clamped vertically) at `u = 0.5 + atan2(d.x, −d.z) / 2π`,
/// `v = acos(d.y) / π`. An equirect image whose `texels` do not hold `width × height` entries,
/// or with a zero side, is treated as black. Every component is multiplied by `intensity`;
/// non-finite and negative results become 0. Each further level is the 2 × 2 box filter of
/// the one before.
pub fn build_radiance_cube(env: &Environment, intensity: f32, size: u32) -> CubeMap {
    let size = size.max(1).checked_next_power_of_two().unwrap_or(1 << 31);
    let n = size as usize;
    let equirect_ok = |width: u32, height: u32, texels: &[[f32; 3]]| {
        width > 0 && height > 0 && (width as usize).checked_mul(height as usize) == Some(texels.len())
    };
    let sample = |d: Vec3| -> Vec3 {
        match env {
            Environment::Studio => studio_radiance(d),
            Environment::Equirect { width, height, texels } => {
                if equirect_ok(*width, *height, texels) {
                    sample_equirect(*width, *height, texels, d)
                } else {
                    Vec3::ZERO
                }
            }
        }
    };
    let clean = |c: f32| {
        let c = c * intensity;
        if c.is_finite() && c > 0.0 {
            c
        } else {
            0.0
        }
    };

    let inv = 1.0 / size as f32;
    let level0: [Vec<[f32; 4]>; 6] = std::array::from_fn(|face| {
        let mut texels = vec![[0.0f32; 4]; n * n];
        texels.par_chunks_mut(n).enumerate().for_each(|(t, row)| {
            let tc = (t as f32 + 0.5) * inv;
            for (s, texel) in row.iter_mut().enumerate() {
                let d = cube_face_direction(face, (s as f32 + 0.5) * inv, tc);
                let l = sample(d);
                *texel = [clean(l.x), clean(l.y), clean(l.z), 1.0];
            }
        });
        texels
    });

    let mut levels = vec![level0];
    let mut side = n;
    while side > 1 {
        let half = side / 2;
        let prev = levels.last().expect("level 0 exists");
        let next: [Vec<[f32; 4]>; 6] = std::array::from_fn(|face| downsample(&prev[face], side, half));
        levels.push(next);
        side = half;
    }
    CubeMap { size, levels }
}

/// One 2 × 2 box-filter step of a `side × side` face to `half × half` (`side = 2 · half`).
fn downsample(src: &[[f32; 4]], side: usize, half: usize) -> Vec<[f32; 4]> {
    let mut dst = vec![[0.0f32; 4]; half * half];
    for (t, row) in dst.chunks_mut(half).enumerate() {
        let (r0, r1) = (&src[2 * t * side..][..side], &src[(2 * t + 1) * side..][..side]);
        for (s, texel) in row.iter_mut().enumerate() {
            for (c, out) in texel.iter_mut().enumerate() {
                *out = 0.25 * (r0[2 * s][c] + r0[2 * s + 1][c] + r1[2 * s][c] + r1[2 * s + 1][c]);
            }
        }
    }
    dst
}

/// The solid angle subtended by the part of a cube face (at distance 1, coordinates in
/// [−1, 1]²) from the face centre's corner to `(x, y)`: `atan2(x·y, √(x² + y² + 1))`.
fn corner_solid_angle(x: f64, y: f64) -> f64 {
    (x * y).atan2((x * x + y * y + 1.0).sqrt())
}

/// The exact solid angle of each texel of one `size × size` cube face, row-major (the same for
/// all six faces). They sum to 4π / 6 per face.
fn texel_solid_angles(size: usize) -> Vec<f32> {
    let step = 2.0 / size as f64;
    let edges: Vec<f64> = (0..=size).map(|i| -1.0 + i as f64 * step).collect();
    let mut weights = Vec::with_capacity(size * size);
    for t in 0..size {
        let (y0, y1) = (edges[t], edges[t + 1]);
        for s in 0..size {
            let (x0, x1) = (edges[s], edges[s + 1]);
            let w = corner_solid_angle(x0, y0) - corner_solid_angle(x0, y1) - corner_solid_angle(x1, y0)
                + corner_solid_angle(x1, y1);
            weights.push(w as f32);
        }
    }
    weights
}

/// The nine real spherical harmonics of bands 0..=2 at the unit direction `d`, in the order
/// documented on [`eval_sh9`].
fn sh9_basis(d: Vec3) -> [f32; 9] {
    let (x, y, z) = (d.x, d.y, d.z);
    [
        0.282095,
        0.488603 * y,
        0.488603 * z,
        0.488603 * x,
        1.092548 * x * y,
        1.092548 * y * z,
        0.315392 * (3.0 * z * z - 1.0),
        1.092548 * x * z,
        0.546274 * (x * x - y * y),
    ]
}

/// The irradiance of a radiance cube as nine spherical-harmonic coefficients (RGB each), for
/// [`eval_sh9`].
///
/// Level 0 is projected onto the real spherical harmonics of bands 0..=2, each texel weighted
/// by its exact solid angle (so the weights sum to 4π), and the result is convolved with the
/// clamped cosine (Ramamoorthi & Hanrahan 2001: `A0 = π`, `A1 = 2π/3`, `A2 = π/4`). Evaluated
/// with [`eval_sh9`], it gives the irradiance `E(n)` of a surface with normal `n`; a Lambertian
/// surface of albedo ρ then reflects `ρ · E(n) / π`.
pub fn irradiance_sh9(cube: &CubeMap) -> [Vec3; 9] {
    let n = cube.size.max(1) as usize;
    let weights = texel_solid_angles(n);
    let inv = 1.0 / n as f32;
    let Some(level0) = cube.levels.first() else { return [Vec3::ZERO; 9] };

    // Accumulate in f64 per row, in parallel, then sum.
    let sum = (0..6 * n)
        .into_par_iter()
        .map(|face_row| {
            let (face, t) = (face_row / n, face_row % n);
            let mut acc = [[0.0f64; 3]; 9];
            let tc = (t as f32 + 0.5) * inv;
            for s in 0..n {
                let Some(texel) = level0[face].get(t * n + s) else { continue };
                let w = f64::from(weights[t * n + s]);
                let d = cube_face_direction(face, (s as f32 + 0.5) * inv, tc);
                for (a, y) in acc.iter_mut().zip(sh9_basis(d)) {
                    let wy = w * f64::from(y);
                    for c in 0..3 {
                        a[c] += wy * f64::from(texel[c]);
                    }
                }
            }
            acc
        })
        .reduce(
            || [[0.0f64; 3]; 9],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    for c in 0..3 {
                        x[c] += y[c];
                    }
                }
                a
            },
        );

    let band_scale = |i: usize| match i {
        0 => PI,
        1..=3 => 2.0 * PI / 3.0,
        _ => PI / 4.0,
    };
    std::array::from_fn(|i| {
        let k = f64::from(band_scale(i));
        Vec3::new((sum[i][0] * k) as f32, (sum[i][1] * k) as f32, (sum[i][2] * k) as f32)
    })
}

/// Evaluates nine spherical-harmonic coefficients (as produced by [`irradiance_sh9`]) in the
/// direction `n` (need not be normalised; a zero `n` is taken as +Y).
///
/// The basis, in coefficient order, with `(x, y, z)` the unit direction in world space:
///
/// | index | function | formula                    |
/// |-------|----------|----------------------------|
/// | 0     | Y₀₀      | 0.282095                   |
/// | 1     | Y₁₋₁     | 0.488603 · y               |
/// | 2     | Y₁₀      | 0.488603 · z               |
/// | 3     | Y₁₁      | 0.488603 · x               |
/// | 4     | Y₂₋₂     | 1.092548 · x · y           |
/// | 5     | Y₂₋₁     | 1.092548 · y · z           |
/// | 6     | Y₂₀      | 0.315392 · (3z² − 1)       |
/// | 7     | Y₂₁      | 1.092548 · x · z           |
/// | 8     | Y₂₂      | 0.546274 · (x² − y²)       |
///
/// The result is `Σ sh[i] · Yᵢ(n)`; the cosine convolution is already folded into the
/// coefficients. `irradiance()` in `shaders/include/frame.glsl` is the same formula; the
/// tests use this one to check the coefficients.
#[cfg_attr(not(test), allow(dead_code))]
pub fn eval_sh9(sh: &[Vec3; 9], n: Vec3) -> Vec3 {
    let d = n.try_normalize().unwrap_or(Vec3::Y);
    sh.iter().zip(sh9_basis(d)).fold(Vec3::ZERO, |acc, (c, y)| acc + *c * y)
}

/// The (fractional) mip level of a radiance cube of side `size` whose texels are about as wide
/// as the specular lobe of a Phong / Blinn–Phong exponent `shininess`.
///
/// The lobe is about `√(2 / (n + 2))` radians wide; a level-`k` texel spans about
/// `(π/2) / (size >> k)` radians, so `k = log2(width · size / (π/2))`, clamped to
/// `[0, log2(size)]` (the 1 × 1 level). Non-increasing in `shininess`; a negative or NaN
/// shininess counts as 0.
pub fn reflection_lod(shininess: f32, size: u32) -> f32 {
    let size = size.max(1);
    let max_level = size.ilog2() as f32;
    let n = shininess.max(0.0);
    let width = (2.0 / (n + 2.0)).sqrt();
    let lod = (width * size as f32 / FRAC_PI_2).log2();
    if lod.is_nan() {
        return 0.0;
    }
    lod.clamp(0.0, max_level)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vulkan's cube map face selection: the face and (s, t) that a direction `r` samples.
    fn select_face(r: Vec3) -> (usize, f32, f32) {
        let a = r.abs();
        let (face, ma, sc, tc) = if a.x >= a.y && a.x >= a.z {
            if r.x >= 0.0 {
                (0, a.x, -r.z, -r.y)
            } else {
                (1, a.x, r.z, -r.y)
            }
        } else if a.y >= a.z {
            if r.y >= 0.0 {
                (2, a.y, r.x, r.z)
            } else {
                (3, a.y, r.x, -r.z)
            }
        } else if r.z >= 0.0 {
            (4, a.z, r.x, -r.y)
        } else {
            (5, a.z, -r.x, -r.y)
        };
        (face, (sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0)
    }

    fn constant_equirect(colour: [f32; 3]) -> Environment {
        Environment::Equirect { width: 16, height: 8, texels: vec![colour; 16 * 8] }
    }

    fn level_mean(level: &[Vec<[f32; 4]>; 6]) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        let mut count = 0usize;
        for face in level {
            for texel in face {
                for c in 0..3 {
                    sum[c] += f64::from(texel[c]);
                }
                count += 1;
            }
        }
        sum.map(|s| s / count as f64)
    }

    fn sphere_directions(n_theta: usize, n_phi: usize) -> impl Iterator<Item = Vec3> {
        (0..=n_theta).flat_map(move |i| {
            let theta = PI * i as f32 / n_theta as f32;
            (0..n_phi).map(move |j| {
                let phi = 2.0 * PI * j as f32 / n_phi as f32;
                Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
            })
        })
    }

    #[test]
    fn cube_face_direction_round_trips_through_face_selection() {
        let k = 23;
        for face in 0..6 {
            for i in 0..k {
                for j in 0..k {
                    let s = (i as f32 + 0.5) / k as f32;
                    let t = (j as f32 + 0.5) / k as f32;
                    let d = cube_face_direction(face, s, t);
                    assert!((d.length() - 1.0).abs() < 1e-5, "direction not normalised");
                    let (f, s2, t2) = select_face(d);
                    assert_eq!(f, face, "face {face} at ({s}, {t}) selects face {f}");
                    assert!((s2 - s).abs() < 1e-5 && (t2 - t).abs() < 1e-5, "({s}, {t}) → ({s2}, {t2})");
                }
            }
        }
    }

    #[test]
    fn face_centres_are_the_axes() {
        let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for (face, axis) in axes.iter().enumerate() {
            assert!((cube_face_direction(face, 0.5, 0.5) - *axis).length() < 1e-6, "face {face}");
        }
        // Spot-check orientation: +Z face, s = 1 is +X, t = 1 is −Y (rows go down).
        assert!(cube_face_direction(4, 1.0, 0.5).x > 0.5);
        assert!(cube_face_direction(4, 0.5, 1.0).y < -0.5);
        // +Y face, t = 1 is +Z.
        assert!(cube_face_direction(2, 0.5, 1.0).z > 0.5);
    }

    #[test]
    fn solid_angles_sum_to_four_pi() {
        for size in [1usize, 2, 3, 8, 64, 256] {
            let total: f64 = texel_solid_angles(size).iter().map(|&w| f64::from(w)).sum::<f64>() * 6.0;
            let four_pi = 4.0 * std::f64::consts::PI;
            assert!((total - four_pi).abs() / four_pi < 1e-3, "size {size}: {total}");
        }
        // Corner texels subtend less than centre texels.
        let w = texel_solid_angles(8);
        assert!(w[0] < w[3 * 8 + 3]);
    }

    #[test]
    fn constant_environment_gives_pi_l_irradiance() {
        let l = [0.5f32, 0.25, 1.0];
        let cube = build_radiance_cube(&constant_equirect(l), 1.0, 32);
        let sh = irradiance_sh9(&cube);
        let expected = Vec3::from_array(l) * PI;
        let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z, Vec3::new(1.0, 2.0, -3.0)];
        for n in dirs {
            let e = eval_sh9(&sh, n);
            for c in 0..3 {
                assert!((e[c] - expected[c]).abs() < 0.01 * expected[c], "n = {n}: {e} vs {expected}");
            }
        }
        // Intensity scales linearly.
        let sh2 = irradiance_sh9(&build_radiance_cube(&constant_equirect(l), 2.0, 16));
        let e2 = eval_sh9(&sh2, Vec3::Y);
        assert!((e2 - expected * 2.0).abs().max_element() < 0.02 * expected.max_element() * 2.0);
    }

    #[test]
    fn upper_hemisphere_light_lights_upward_normals() {
        let (w, h) = (32u32, 16u32);
        let texels = (0..h)
            .flat_map(|row| (0..w).map(move |_| if row < h / 2 { [1.0f32; 3] } else { [0.0; 3] }))
            .collect();
        let cube = build_radiance_cube(&Environment::Equirect { width: w, height: h, texels }, 1.0, 32);
        let sh = irradiance_sh9(&cube);
        let up = eval_sh9(&sh, Vec3::Y).x;
        let down = eval_sh9(&sh, -Vec3::Y).x;
        let side = eval_sh9(&sh, Vec3::X).x;
        // Exact: π up, 0 down, π/2 sideways; order-2 SH is close.
        assert!(up > down + 2.0, "up {up} down {down}");
        assert!((up - PI).abs() < 0.15 * PI, "up {up}");
        assert!(down.abs() < 0.15 * PI, "down {down}");
        assert!((side - PI / 2.0).abs() < 0.05 * PI, "side {side}");
    }

    #[test]
    fn studio_is_finite_non_negative_and_lit_from_above() {
        for d in sphere_directions(180, 360) {
            let l = studio_radiance(d);
            assert!(l.is_finite() && l.min_element() >= 0.0, "{d}: {l}");
            assert!(l.max_element() < 10.0, "{d}: {l}");
        }
        assert!(studio_radiance(Vec3::ZERO) == Vec3::ZERO);
        let up = studio_radiance(Vec3::Y).length();
        let down = studio_radiance(-Vec3::Y).length();
        assert!(up > 4.0 * down, "up {up} down {down}");
        // The key softbox is bright, the floor dark, the sky grey, the strip to the left.
        let key = studio_radiance(Vec3::new(0.0, 1.0, 0.35));
        assert!(key.min_element() > 4.0 && key.max_element() < 6.5, "key {key}");
        let floor = studio_radiance(Vec3::new(0.0, -1.0, 0.2));
        assert!(floor.max_element() < 0.12 && floor.min_element() > 0.03, "floor {floor}");
        let sky = studio_radiance(Vec3::new(0.0, 0.6, -1.0));
        assert!(sky.min_element() > 0.25 && sky.max_element() < 0.55, "sky {sky}");
        let strip = studio_radiance(Vec3::new(-1.0, 0.25, 0.15));
        assert!(strip.min_element() > 1.8 && strip.max_element() < 2.8, "strip {strip}");
        let right = studio_radiance(Vec3::new(1.0, 0.25, 0.15));
        assert!(right.max_element() < 1.0, "right {right}");
        // Irradiance agrees: the top of the clay is lit far more than its underside.
        let sh = irradiance_sh9(&build_radiance_cube(&Environment::Studio, 1.0, 32));
        assert!(eval_sh9(&sh, Vec3::Y).x > 3.0 * eval_sh9(&sh, -Vec3::Y).x);
        assert!(eval_sh9(&sh, -Vec3::X).x > eval_sh9(&sh, Vec3::X).x);
    }

    #[test]
    fn studio_is_continuous() {
        let step = 0.01f32;
        let mut worst = 0.0f32;
        for d in sphere_directions(200, 400) {
            // Two perpendicular neighbours, each 0.01 rad away.
            let a = d.any_orthonormal_vector();
            let b = d.cross(a);
            let l = studio_radiance(d);
            for axis in [a, b] {
                let n = d * step.cos() + axis * step.sin();
                worst = worst.max((studio_radiance(n) - l).abs().max_element());
            }
        }
        // The brightest step inside the softbox's soft edge; a hard edge would jump by ~5.
        assert!(worst < 0.4, "largest change over 0.01 rad: {worst}");
    }

    #[test]
    fn equirect_centre_lands_on_minus_z_and_top_row_on_plus_y() {
        let (w, h) = (64u32, 32u32);
        let mut texels = vec![[0.0f32, 0.0, 0.0]; (w * h) as usize];
        // The 2×2 block around the image centre is red, the top row green, the column at
        // three quarters (u = 0.75) blue.
        for (r, c) in [(15, 31), (15, 32), (16, 31), (16, 32)] {
            texels[r * w as usize + c] = [1.0, 0.0, 0.0];
        }
        for texel in &mut texels[..w as usize] {
            *texel = [0.0, 1.0, 0.0];
        }
        for r in 2..(h as usize - 2) {
            texels[r * w as usize + 48] = [0.0, 0.0, 1.0];
            texels[r * w as usize + 47] = [0.0, 0.0, 1.0];
        }
        let env = Environment::Equirect { width: w, height: h, texels };
        let size = 32usize;
        let cube = build_radiance_cube(&env, 1.0, size as u32);
        let centre = |face: usize| {
            let f = &cube.levels[0][face];
            let c = size / 2;
            let sum: Vec3 = [(c - 1, c - 1), (c - 1, c), (c, c - 1), (c, c)]
                .iter()
                .map(|&(t, s)| Vec3::from_slice(&f[t * size + s][..3]))
                .sum();
            sum / 4.0
        };
        let minus_z = centre(5);
        assert!(minus_z.x > 0.5 && minus_z.y < 0.01 && minus_z.z < 0.01, "−Z centre {minus_z}");
        for face in [0, 1, 2, 3, 4] {
            assert!(centre(face).x < 0.01, "face {face} centre {}", centre(face));
        }
        let plus_y = centre(2);
        assert!(plus_y.y > 0.99 && plus_y.x < 0.01, "+Y centre {plus_y}");
        assert!(centre(3).y < 0.01);
        let plus_x = centre(0);
        assert!(plus_x.z > 0.9, "+X centre {plus_x}");
        assert!(centre(1).z < 0.01);
        // The brightest red texel of the whole cube is on the −Z face.
        let (best_face, _) = (0..6)
            .map(|f| (f, cube.levels[0][f].iter().map(|t| t[0]).fold(0.0f32, f32::max)))
            .fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        assert_eq!(best_face, 5);
    }

    #[test]
    fn mip_chain_halves_and_preserves_the_mean() {
        let cube = build_radiance_cube(&Environment::Studio, 1.5, 64);
        assert_eq!(cube.size, 64);
        assert_eq!(cube.levels.len(), 7);
        let mean0 = level_mean(&cube.levels[0]);
        for (k, level) in cube.levels.iter().enumerate() {
            let side = (64 >> k) as usize;
            assert_eq!(cube.level_size(k) as usize, side);
            for face in level {
                assert_eq!(face.len(), side * side);
                assert!(face
                    .iter()
                    .all(|t| t[3] == 1.0 && t[..3].iter().all(|c| c.is_finite() && *c >= 0.0)));
            }
            let mean = level_mean(level);
            for c in 0..3 {
                assert!(
                    (mean[c] - mean0[c]).abs() < 1e-5 * mean0[c].max(1e-3),
                    "level {k}: {mean:?} vs {mean0:?}"
                );
            }
        }
        assert_eq!(cube.levels.last().map(|l| l[0].len()), Some(1));
        // Non-power-of-two sizes round up; size 0 gives a single 1×1 level.
        assert_eq!(build_radiance_cube(&Environment::Studio, 1.0, 48).size, 64);
        let tiny = build_radiance_cube(&Environment::Studio, 1.0, 0);
        assert_eq!((tiny.size, tiny.levels.len()), (1, 1));
    }

    #[test]
    fn bad_values_become_black() {
        let env =
            Environment::Equirect { width: 4, height: 2, texels: vec![[f32::NAN, f32::INFINITY, -1.0]; 8] };
        let cube = build_radiance_cube(&env, 1.0, 4);
        assert!(cube.levels.iter().flatten().flatten().all(|t| t[..3] == [0.0, 0.0, 0.0]));
        let short = Environment::Equirect { width: 4, height: 2, texels: vec![[1.0; 3]; 3] };
        let cube = build_radiance_cube(&short, 1.0, 4);
        assert!(cube.levels[0].iter().flatten().all(|t| t[..3] == [0.0, 0.0, 0.0]));
        let cube = build_radiance_cube(&Environment::Studio, f32::INFINITY, 4);
        assert!(cube.levels[0].iter().flatten().all(|t| t[..3].iter().all(|c| c.is_finite())));
    }

    #[test]
    fn reflection_lod_is_monotone_and_clamped() {
        for size in [1u32, 16, 256, 1024] {
            let max = size.ilog2() as f32;
            let mut previous = f32::INFINITY;
            for i in 0..2000 {
                let shininess = i as f32 * 0.5;
                let lod = reflection_lod(shininess, size);
                assert!((0.0..=max).contains(&lod), "size {size} n {shininess}: {lod}");
                assert!(lod <= previous, "size {size}: not monotone at n = {shininess}");
                previous = lod;
            }
            for odd in [-5.0, f32::NAN, f32::INFINITY, 1e30] {
                assert!((0.0..=max).contains(&reflection_lod(odd, size)));
            }
        }
        // A rough lobe (n = 0: one radian) reaches the 1×1 level of a 256 cube only when
        // clamped; a mirror-like lobe sits at level 0.
        assert!(reflection_lod(0.0, 256) > 6.0);
        assert_eq!(reflection_lod(1e6, 256), 0.0);
        // n = 48 on a 256 cube: width 0.2 rad → log2(0.2 · 256 / (π/2)) ≈ 5.03.
        assert!((reflection_lod(48.0, 256) - 5.03).abs() < 0.02);
    }
}
