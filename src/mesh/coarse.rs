//! Coarse clay meshed on its own level, its cells conforming to finer neighbours.
//!
//! ```text
//!   level 2 brick, meshed on level 2        level 0 brick (the finest)
//!   ┌───────────┬───────────┐┬──┬──┬──┬──┬──┬──┬──┬──┐
//!   │           │           ││  │  │  │  │  │  │  │  │   the coarse cell's face toward
//!   │  regular  │ conforming●●──┼──┼──┼──┼──┼──┼──┼──┤   the finer brick is cut into that
//!   │   cell    │   cell    ││  │  │  │  │  │  │  │  │   brick's squares, and its edges on
//!   ├───────────┼───────────●┼──┼──┼──┼──┼──┼──┼──┼──┤   the brick's face into its edges:
//!   │           │           ││  │  │  │  │  │  │  │  │   the cell is a polyhedron whose
//!   │           │           ●●──┼──┼──┼──┼──┼──┼──┼──┤   faces are the squares the finer
//!   │           │           ││  │  │  │  │  │  │  │  │   cells show it
//!   └───────────┴───────────┘┴──┴──┴──┴──┴──┴──┴──┴──┘
//! ```
//!
//! - **Which level.** A brick is meshed on the coarsest level, up to [`MAX_MESH_LEVEL`]
//!   (cells as wide as the brick), under which no finer level holds a brick over the points
//!   its cells read ([`mesh_level`]). There the finer levels' values are the coarse level's
//!   interpolation: the coarse cells hold all the clay says, with a fraction of the finest
//!   level's triangles (a quarter per level).
//! - **Where levels meet.** Every face and edge of a cell has a resolution: the finest mesh
//!   level of the bricks whose cells it bounds. A cell whose faces and edges are all of its own
//!   level is marched with the case table; a cell with a finer face or edge is a polyhedron
//!   whose faces are that face's squares (each edge on the face's rim cut into that edge's
//!   pieces) and whose other faces are polygons with their edges cut likewise. Its surface is
//!   traced with the case table's own rule (on each face, walked counter-clockwise from
//!   outside, a segment from each empty→dense crossing to the next dense→empty one), which
//!   reads nothing but the face's samples: the finer cells draw the same segments on the
//!   squares they share with it, in reverse. The segments close into loops, each triangulated
//!   so that no triangle or chord lies in one face and none turns over, and of those ways the
//!   one whose thinnest triangle is the least thin.
//! - **Same vertices.** A vertex is made on an edge piece from its two samples with the
//!   kernel's formula ([`super::march`]'s `crossing_position`): finer and coarser meshes sharing
//!   an edge piece share the vertex bit for bit, and welding by position closes the surface.
//!   On a finer piece its normal is the one the finer level's mesh gives it (central
//!   differences on that level at the piece's ends, weighed as that mesh weighs them), and so
//!   is its colour: the shading runs on across the seam (tested, vertex for vertex).
//! - **No transition cells needed thicker than a face**, and no limit on the ratio of levels
//!   across a face: a level-3 cell next to the finest level has a face of 8 × 8 squares.
//!   Cells meeting finer bricks along an edge only (the case Transvoxel's face cells leave
//!   open) have that edge cut, and so do the cells around it.
//! - **Incremental.** A brick's mesh depends on its neighbours' levels; the field marks a
//!   brick's surroundings dirty when a brick of any level comes or goes (see `Field`).

use rustc_hash::FxHashMap;

use super::cases::{case_table, link_crossings, CORNER_OFFSETS, EDGES};
use super::march::{crossing, crossing_colour, crossing_position, neighbour};
use super::types::{ChunkMesh, Vertex};
use crate::field::{BrickKey, Colour, Field, BRICK_SIZE, MESHED_LEVELS};
use crate::math::{IVec3, Vec3, VoxelTransform};

/// The coarsest level a brick is meshed on: there one cell spans the brick. The field's dirty
/// set follows the presence of the finer levels' bricks ([`MESHED_LEVELS`]).
pub const MAX_MESH_LEVEL: usize = MESHED_LEVELS;

/// Cell corners of a brick meshed on level 1 or coarser: at most `(S/2 + 1)³`.
const MAX_CORNERS: usize = (BRICK_SIZE as usize / 2 + 1).pow(3);

/// The level brick `key`'s cells are meshed on: the coarsest, up to [`MAX_MESH_LEVEL`], under
/// which no level holds a brick over the points the cells read (`key·S ..= key·S + S` on the
/// finest lattice); 0 in a field holding the finest level alone.
pub fn mesh_level(field: &Field, key: BrickKey) -> usize {
    if !field.has_levels_above(0) {
        return 0;
    }
    let lo = key * BRICK_SIZE;
    let hi = lo + IVec3::splat(BRICK_SIZE);
    (0..MAX_MESH_LEVEL)
        .find(|&l| field.level_holds_over(l, lo >> l as i32, hi >> l as i32))
        .unwrap_or(MAX_MESH_LEVEL)
}

/// The mesh levels of brick `key` and its 26 neighbours, `(dx + 1) + 3·(dy + 1) + 9·(dz + 1)`.
pub fn levels_around(field: &Field, key: BrickKey) -> [u8; 27] {
    std::array::from_fn(|i| mesh_level(field, neighbour(key, i)) as u8)
}

/// Central-difference gradient at point `q` of a lattice whose values `value` gives (per
/// voxel of that lattice), as every mesh level takes it.
#[inline]
fn central_gradient(value: impl Fn(IVec3) -> f32, q: IVec3) -> Vec3 {
    let d = |o: IVec3| value(q + o) - value(q - o);
    Vec3::new(d(IVec3::X), d(IVec3::Y), d(IVec3::Z)) * 0.5
}

/// Reusable buffers of the coarse marcher.
#[derive(Debug, Default)]
pub struct CoarseScratch {
    /// The level's values over the brick's cells and an apron of one (gradients).
    samples: Vec<(f32, Colour)>,
    /// The finest values a conforming cell reads, over the cell.
    fine: Vec<(f32, Colour)>,
    /// The chunk's vertex on each edge piece.
    vertex_of: VertexMap,
    /// The level's gradient at each cell corner of the brick, x fastest.
    gradients: Vec<Vec3>,
    /// A conforming cell's polygons: each vertex's two faces.
    faces_of: FxHashMap<u32, [u32; 2]>,
    /// A conforming cell's segments: start → end.
    next: FxHashMap<u32, u32>,
    /// Segment starts in the order found.
    starts: Vec<u32>,
    ring: Vec<IVec3>,
    crossings: Vec<(u32, bool)>,
    loop_: Vec<u32>,
    /// The segment starts already in a loop.
    seen: Vec<u32>,
    triangulations: Triangulations,
    /// The runs of a loop still to cut into triangles.
    runs: Vec<(usize, usize)>,
}

/// The chunk's vertex on each edge piece: on a cell edge, by its lower corner and axis, in
/// `dense` (`u32::MAX`: none yet); on a finer piece, by its lower point and axis.
#[derive(Debug, Default)]
struct VertexMap {
    dense: Vec<u32>,
    sparse: FxHashMap<(IVec3, u8), u32>,
    /// The samples around a finer piece, for its ends' gradients.
    around: Vec<(f32, Colour)>,
}

impl VertexMap {
    fn clear(&mut self, corners: usize) {
        self.dense.clear();
        self.dense.resize(3 * corners, u32::MAX);
        self.sparse.clear();
    }

    /// The slot of the piece from finest point `lower` along `axis`, `length` long.
    #[inline]
    fn slot(&mut self, cells: &Cells<'_>, lower: IVec3, axis: usize, length: i32) -> &mut u32 {
        if length == cells.width {
            let q = (lower >> cells.level as i32) - cells.base;
            let c = cells.dims - 2;
            &mut self.dense[3 * (q.x + c * (q.y + c * q.z)) as usize + axis]
        } else {
            self.sparse.entry((lower, axis as u8)).or_insert(u32::MAX)
        }
    }
}

/// What one brick's cells read: the level's values and the lattice.
struct Cells<'a> {
    field: &'a Field,
    transform: &'a VoxelTransform,
    iso: f32,
    level: usize,
    /// Cell width in finest voxels.
    width: i32,
    /// Level point of the brick's base, of `samples[0]`, and the samples' extent per axis
    /// (the cells' corners per axis are `dims − 2`).
    base: IVec3,
    lo: IVec3,
    dims: i32,
}

impl Cells<'_> {
    #[inline]
    fn index(&self, q: IVec3) -> usize {
        let d = q - self.lo;
        (d.x + self.dims * (d.y + self.dims * d.z)) as usize
    }

    /// Central-difference gradient at level point `q` (per level voxel).
    fn gradient(&self, samples: &[(f32, Colour)], q: IVec3) -> Vec3 {
        central_gradient(|p| samples[self.index(p)].0, q)
    }
}

/// One cell being meshed: its lowest finest point and its corners' gradients.
struct Cell {
    lo: IVec3,
    gradients: [Vec3; 8],
}

impl Cell {
    /// The gradient at finest lattice position `p` in the cell: the corners' trilinearly
    /// interpolated (on an edge, the two ends' lerp, as the finest kernel's).
    fn gradient_at(&self, p: Vec3, width: i32) -> Vec3 {
        let f = ((p - self.lo.as_vec3()) / width as f32).clamp(Vec3::ZERO, Vec3::ONE);
        let mut g = Vec3::ZERO;
        for (o, &grad) in CORNER_OFFSETS.iter().zip(&self.gradients) {
            let w = |a: usize| if o[a] == 1 { f[a] } else { 1.0 - f[a] };
            g += grad * (w(0) * w(1) * w(2));
        }
        g
    }
}

/// The vertex on the edge piece from finest point `lower` along `axis`, `length` long, whose
/// ends hold `a` and `b`: made once per chunk.
#[allow(clippy::too_many_arguments)]
fn piece_vertex(
    cells: &Cells<'_>,
    cell: &Cell,
    vertex_of: &mut VertexMap,
    out: &mut ChunkMesh,
    lower: IVec3,
    axis: usize,
    length: i32,
    a: (f32, Colour),
    b: (f32, Colour),
) -> u32 {
    let known = *vertex_of.slot(cells, lower, axis, length);
    if known != u32::MAX {
        return known;
    }
    let made = {
        let t = crossing(cells.iso, a.0, b.0);
        let position = crossing_position(cells.transform, lower, axis, length, t);
        let gradient = if length < cells.width {
            finer_piece_gradient(cells.field, &mut vertex_of.around, lower, axis, length, t)
        } else {
            let mut lattice = lower.as_vec3();
            lattice[axis] += t * length as f32;
            cell.gradient_at(lattice, cells.width)
        };
        let normal = if gradient.length_squared() > 1e-20 {
            -gradient.normalize()
        } else {
            let mut n = Vec3::ZERO;
            n[axis] = if a.0 >= cells.iso { 1.0 } else { -1.0 };
            n
        };
        out.vertices.push(Vertex {
            position: position.to_array(),
            normal: normal.to_array(),
            colour: crossing_colour(a, b, t),
        });
        (out.vertices.len() - 1) as u32
    };
    *vertex_of.slot(cells, lower, axis, length) = made;
    made
}

/// The gradient at fraction `t` of a finer level's edge piece, from finest point `lower` along
/// `axis`, `length` long, as that level's mesh gives it: its ends' central differences on that
/// level, weighed as that mesh weighs them; so that the shading is one across the levels'
/// seam. `around`: scratch for the samples read.
fn finer_piece_gradient(
    field: &Field,
    around: &mut Vec<(f32, Colour)>,
    lower: IVec3,
    axis: usize,
    length: i32,
    t: f32,
) -> Vec3 {
    let level = length.trailing_zeros() as i32;
    let (qa, mut qb) = (lower >> level, lower >> level);
    qb[axis] += 1;
    let (lo, hi) = (qa - IVec3::ONE, qb + IVec3::ONE);
    field.level_values(level as usize, lo, hi, around);
    let dims = hi - lo + IVec3::ONE;
    let value = |q: IVec3| {
        let d = q - lo;
        around[(d.x + dims.x * (d.y + dims.y * d.z)) as usize].0
    };
    let (ga, gb) = (central_gradient(value, qa), central_gradient(value, qb));
    if level == 0 {
        // As the finest kernel weighs its ends.
        ga.lerp(gb, t)
    } else {
        // As a coarse cell's trilinear weights come out on its edge (`Cell::gradient_at`).
        let along = lower.as_vec3()[axis] + t * length as f32;
        let f = ((along - lower[axis] as f32) / length as f32).clamp(0.0, 1.0);
        ga * (1.0 - f) + gb * f
    }
}

/// Meshes brick `key` on level `level` (≥ 1, see [`mesh_level`]) into `out`; `around` holds
/// the mesh levels of the brick and its neighbours ([`levels_around`]).
pub fn march_coarse(
    field: &Field,
    key: BrickKey,
    level: usize,
    around: &[u8; 27],
    scratch: &mut CoarseScratch,
    out: &mut ChunkMesh,
) {
    debug_assert!((1..=MAX_MESH_LEVEL).contains(&level));
    out.reset();
    let width = 1i32 << level;
    let n = BRICK_SIZE >> level;
    let corners = (n + 1) as usize;
    scratch.vertex_of.clear(corners.pow(3));
    // The level point at the brick's base, and the samples: the cells' corners and an apron.
    let q0 = (key * BRICK_SIZE) >> level as i32;
    let cells = Cells {
        field,
        transform: field.transform(),
        iso: field.surface_level(),
        level,
        width,
        base: q0,
        lo: q0 - IVec3::ONE,
        dims: n + 3,
    };
    field.level_values(level, cells.lo, q0 + IVec3::splat(n + 1), &mut scratch.samples);
    let finer_around = around.iter().any(|&l| usize::from(l) < level);
    let samples = std::mem::take(&mut scratch.samples);
    // Which cell corners are dense; none or all: no cell crosses (see below).
    let corner_index = |c: IVec3| (c.x + (n + 1) * (c.y + (n + 1) * c.z)) as usize;
    let mut dense = [false; MAX_CORNERS];
    let mut count = 0;
    for z in 0..=n {
        for y in 0..=n {
            for x in 0..=n {
                let c = IVec3::new(x, y, z);
                dense[corner_index(c)] = samples[cells.index(q0 + c)].0 >= cells.iso;
                count += usize::from(dense[corner_index(c)]);
            }
        }
    }
    if count == 0 || count == corners.pow(3) {
        scratch.samples = samples;
        return;
    }
    // Gradients at the corners, each made when a cell first needs it.
    let mut gradients = std::mem::take(&mut scratch.gradients);
    gradients.clear();
    gradients.resize(corners.pow(3), Vec3::NAN);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let c = IVec3::new(x, y, z);
                let corner = q0 + c;
                let mut mask = 0usize;
                for (i, o) in CORNER_OFFSETS.iter().enumerate() {
                    mask |= usize::from(dense[corner_index(c + IVec3::from(*o))]) << i;
                }
                // All corners on one side: so is every finer point between them (each is a
                // mean of the corners, rounded to a stored value), so no face crosses.
                if mask == 0 || mask == 255 {
                    continue;
                }
                let cell = Cell {
                    lo: corner * width,
                    gradients: CORNER_OFFSETS.map(|o| {
                        let g = &mut gradients[corner_index(c + IVec3::from(o))];
                        if g.x.is_nan() {
                            *g = cells.gradient(&samples, corner + IVec3::from(o));
                        }
                        *g
                    }),
                };
                let res = |spans: [i8; 3]| resolution(c, n, around, spans);
                if finer_around && conforms(&res, level) {
                    conforming_cell(&cells, &cell, &res, scratch, out);
                } else {
                    for triangle in &case_table()[mask] {
                        for &e in triangle {
                            let (lower, axis) = EDGES[usize::from(e)];
                            let (lower, axis) =
                                (corner + IVec3::from(CORNER_OFFSETS[usize::from(lower)]), usize::from(axis));
                            let mut upper = lower;
                            upper[axis] += 1;
                            let (a, b) = (samples[cells.index(lower)], samples[cells.index(upper)]);
                            let v = piece_vertex(
                                &cells,
                                &cell,
                                &mut scratch.vertex_of,
                                out,
                                lower * width,
                                axis,
                                width,
                                a,
                                b,
                            );
                            out.indices.push(v);
                        }
                    }
                }
            }
        }
    }
    scratch.samples = samples;
    scratch.gradients = gradients;
}

/// The resolution (mesh level) of a face or edge of cell `c` (of `n` per axis in its brick):
/// the finest mesh level among the bricks whose cells it bounds. `spans[a]` is −1 where the
/// element spans axis `a`, else its side (0 or 1) of the cell on that axis.
fn resolution(c: IVec3, n: i32, around: &[u8; 27], spans: [i8; 3]) -> u8 {
    let range = |a: usize| match spans[a] {
        0 if c[a] == 0 => -1..=0,
        1 if c[a] == n - 1 => 0..=1,
        _ => 0..=0,
    };
    let mut finest = around[13];
    for dz in range(2) {
        for dy in range(1) {
            for dx in range(0) {
                finest = finest.min(around[((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)) as usize]);
            }
        }
    }
    finest
}

/// The spans of face `f` (`2·axis + side`).
fn face_spans(f: usize) -> [i8; 3] {
    let mut spans = [-1; 3];
    spans[f / 2] = (f % 2) as i8;
    spans
}

/// The spans of a cell's 6 faces and 12 edges (see [`resolution`]).
fn faces_and_edges() -> impl Iterator<Item = [i8; 3]> {
    let edges = (0..12).map(|e| {
        // Along axis `e / 4`, at sides `e & 1` and `e >> 1 & 1` of the two others.
        let (along, sides) = (e / 4, [(e & 1) as i8, (e >> 1 & 1) as i8]);
        let mut spans = [-1; 3];
        spans[(along + 1) % 3] = sides[0];
        spans[(along + 2) % 3] = sides[1];
        spans
    });
    (0..6).map(face_spans).chain(edges)
}

/// The finest resolution of a cell's faces and edges.
fn finest_around(res: &impl Fn([i8; 3]) -> u8) -> u8 {
    faces_and_edges().map(res).min().unwrap_or(u8::MAX)
}

/// Whether a cell of `level` has a face or an edge of a finer resolution.
fn conforms(res: &impl Fn([i8; 3]) -> u8, level: usize) -> bool {
    usize::from(finest_around(res)) < level
}

/// Meshes a cell with finer faces or edges as the polyhedron they make (see the module docs).
fn conforming_cell(
    cells: &Cells<'_>,
    cell: &Cell,
    res: &impl Fn([i8; 3]) -> u8,
    scratch: &mut CoarseScratch,
    out: &mut ChunkMesh,
) {
    let width = cells.width;
    // Every point the polygons use lies on the finest level of the cell's faces and edges.
    let finest = finest_around(res);
    let r = i32::from(finest);
    let f_lo = cell.lo >> r;
    let f_dims = (width >> r) + 1;
    cells.field.level_values(usize::from(finest), f_lo, f_lo + IVec3::splat(f_dims - 1), &mut scratch.fine);
    let CoarseScratch {
        fine,
        vertex_of,
        faces_of,
        next,
        starts,
        ring,
        crossings,
        loop_,
        seen,
        triangulations,
        runs,
        ..
    } = scratch;
    let sample = |p: IVec3| -> (f32, Colour) {
        let d = (p >> r) - f_lo;
        fine[(d.x + f_dims * (d.y + f_dims * d.z)) as usize]
    };
    faces_of.clear();
    next.clear();
    starts.clear();
    let mut polygon = 0u32;
    for f in 0..6 {
        let (axis, side) = (f / 2, (f % 2) as i32);
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let spans = face_spans(f);
        let square = 1i32 << res(spans);
        let k = width / square;
        // The piece length of the rim's edge at side `s` across axis `across`.
        let rim = |across: usize, s: i8| {
            let mut e = spans;
            e[across] = s;
            1i32 << res(e)
        };
        // Along u at v-sides 0 and 1, along v at u-sides 0 and 1.
        let (u0, u1, v0, v1) = (rim(v, 0), rim(v, 1), rim(u, 0), rim(u, 1));
        let (eu, ev) = (unit(u), unit(v));
        for j in 0..k {
            for i in 0..k {
                ring.clear();
                let origin = cell.lo + unit(axis) * side * width + eu * (i * square) + ev * (j * square);
                // Counter-clockwise seen from +axis: (0,0) → (1,0) → (1,1) → (0,1).
                let sides = [
                    (origin, eu, if j == 0 { u0 } else { square }),
                    (origin + eu * square, ev, if i == k - 1 { v1 } else { square }),
                    (origin + (eu + ev) * square, -eu, if j == k - 1 { u1 } else { square }),
                    (origin + ev * square, -ev, if i == 0 { v0 } else { square }),
                ];
                for (start, dir, step) in sides {
                    ring.extend((0..square / step).map(|s| start + dir * (s * step)));
                }
                if side == 0 {
                    ring.reverse();
                }
                // Crossings in ring order: (vertex, starts a segment).
                crossings.clear();
                for (idx, &a) in ring.iter().enumerate() {
                    let b = ring[(idx + 1) % ring.len()];
                    let (sa, sb) = (sample(a), sample(b));
                    let (da, db) = (sa.0 >= cells.iso, sb.0 >= cells.iso);
                    if da == db {
                        continue;
                    }
                    let step = b - a;
                    let along = (0..3).find(|&x| step[x] != 0).expect("a ring steps along an axis");
                    let (lower, (sl, su)) = if step[along] > 0 { (a, (sa, sb)) } else { (b, (sb, sa)) };
                    let id =
                        piece_vertex(cells, cell, vertex_of, out, lower, along, step[along].abs(), sl, su);
                    faces_of.entry(id).and_modify(|fs| fs[1] = polygon).or_insert([polygon, polygon]);
                    crossings.push((id, db));
                }
                link_crossings(crossings, |start, end| {
                    next.insert(start, end);
                    starts.push(start);
                });
                polygon += 1;
            }
        }
    }
    // Follow the segments into loops and triangulate each.
    seen.clear();
    for &first in starts.iter() {
        if seen.contains(&first) {
            continue;
        }
        loop_.clear();
        let mut e = first;
        loop {
            seen.push(e);
            loop_.push(e);
            e = next[&e];
            if e == first {
                break;
            }
            debug_assert!(!loop_.contains(&e), "segments close into loops");
        }
        triangulate(loop_, faces_of, (triangulations, runs), out);
    }
}

/// A unit step along `axis`.
fn unit(axis: usize) -> IVec3 {
    let mut u = IVec3::ZERO;
    u[axis] = 1;
    u
}

/// The best triangulation of each run `i ..= j` of a loop: its faults, its thinnest
/// triangle's height over longest side, and the vertex its triangle on `(i, j)` takes.
type Triangulations = Vec<(u32, f32, u16)>;

/// Triangulates loop `ring` (counter-clockwise seen from outside the clay) into `out`: of all
/// its triangulations, one with the fewest faults (a chord or a triangle in one face of the
/// cell, a triangle turned against the loop), and of those the one whose thinnest triangle is
/// the least thin (height over longest side), found by dynamic programming over the loop's
/// runs. A loop along finer faces has runs of vertices in a line, which a fan from one vertex,
/// or ears cut greedily, would lay into flat triangles.
fn triangulate(
    ring: &[u32],
    faces_of: &FxHashMap<u32, [u32; 2]>,
    (best, runs): (&mut Triangulations, &mut Vec<(usize, usize)>),
    out: &mut ChunkMesh,
) {
    let n = ring.len();
    if n < 3 {
        return;
    }
    let faces = |i: usize| faces_of[&ring[i]];
    let share = |i: usize, j: usize| faces(i).iter().any(|f| faces(j).contains(f));
    let position = |i: usize| Vec3::from(out.vertices[ring[i] as usize].position);
    // The loop's normal (Newell's), against which a turned-over triangle is told.
    let centre = (0..n).map(position).sum::<Vec3>() / n as f32;
    let normal: Vec3 = (0..n).map(|i| (position(i) - centre).cross(position((i + 1) % n) - centre)).sum();
    let triangle = |i: usize, k: usize, j: usize| {
        let in_face = faces(i).iter().any(|f| faces(k).contains(f) && faces(j).contains(f));
        let (a, b, c) = (position(i), position(k), position(j));
        let cross = (b - a).cross(c - a);
        let longest = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
        (
            u32::from(in_face) + u32::from(cross.dot(normal) <= 0.0),
            cross.length() / longest.max(f32::MIN_POSITIVE),
        )
    };
    best.clear();
    best.resize(n * n, (0, f32::INFINITY, 0));
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            // The run's own side (i, j) is a chord unless it is the loop's closing side.
            let chord = u32::from(len < n - 1 && share(i, j));
            let mut pick = (u32::MAX, f32::NEG_INFINITY, 0u16);
            for k in i + 1..j {
                let (l, r) = (best[i * n + k], best[k * n + j]);
                let (faults, quality) = triangle(i, k, j);
                let candidate = (l.0 + r.0 + faults + chord, l.1.min(r.1).min(quality), k as u16);
                if candidate.0 < pick.0 || (candidate.0 == pick.0 && candidate.1 > pick.1) {
                    pick = candidate;
                }
            }
            best[i * n + j] = pick;
        }
    }
    // The triangles, from the whole loop's run down.
    runs.clear();
    runs.push((0, n - 1));
    while let Some((i, j)) = runs.pop() {
        if j - i < 2 {
            continue;
        }
        let k = usize::from(best[i * n + j].2);
        out.indices.extend([ring[i], ring[k], ring[j]]);
        runs.extend([(i, k), (k, j)]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_brick_is_meshed_on_the_coarsest_level_free_of_finer_bricks_over_its_cells() {
        let mut f = Field::new(0.001, 0.5);
        assert_eq!(mesh_level(&f, IVec3::ZERO), 0, "one level: the finest");
        // Clay on level 2 alone (4 mm voxels): its bricks are meshed on level 2.
        f.edit_level(2, IVec3::splat(-20), IVec3::splat(20), true, |_, _, _| true, |_, d, _| *d = 0.7);
        assert_eq!(mesh_level(&f, IVec3::new(3, -2, 1)), 2);
        // A finest brick at key 4: the brick's cells read it, and so do the cells of the bricks
        // below it on each axis (their upper faces are its lower ones); those beyond do not.
        f.edit_box(IVec3::splat(32), IVec3::splat(33), false, |_, d, _| *d = 0.2);
        assert!(f.brick(IVec3::splat(4)).is_some());
        assert_eq!(mesh_level(&f, IVec3::splat(4)), 0);
        assert_eq!(mesh_level(&f, IVec3::new(3, 4, 4)), 0);
        assert_eq!(mesh_level(&f, IVec3::splat(3)), 0);
        assert_eq!(mesh_level(&f, IVec3::new(5, 4, 4)), 2);
        assert_eq!(mesh_level(&f, IVec3::new(4, 2, 4)), 2);
        let around = levels_around(&f, IVec3::new(5, 4, 4));
        assert_eq!((around[13], around[12], around[14]), (2, 0, 2));
    }

    /// Whether cell `c` of a level-2 brick (2 cells per axis) among neighbours of `around`'s
    /// mesh levels conforms to a finer one.
    fn conforming(around: &[u8; 27], c: IVec3) -> bool {
        conforms(&|spans| resolution(c, 2, around, spans), 2)
    }

    #[test]
    fn a_cell_conforms_where_a_face_or_an_edge_borders_a_finer_brick() {
        // The brick of level 2 at the centre, a finest brick beside it (dx = −1) only: the
        // cells on the brick's lower x face conform, the others do not.
        let mut around = [2u8; 27];
        around[12] = 0;
        let at = |x, y, z| conforming(&around, IVec3::new(x, y, z));
        assert!(at(0, 0, 0) && at(0, 1, 1));
        assert!(!at(1, 0, 0) && !at(1, 1, 1));
        // A finest brick along an edge only (dx = −1, dy = −1): the cells along that edge.
        let mut around = [2u8; 27];
        around[9] = 0;
        let at = |x, y, z| conforming(&around, IVec3::new(x, y, z));
        assert!(at(0, 0, 0) && at(0, 0, 1));
        assert!(!at(0, 1, 0) && !at(1, 0, 0));
        // At a corner only (dx = dy = dz = −1): no cell has a finer face or edge.
        let mut around = [2u8; 27];
        around[0] = 0;
        assert!(!conforming(&around, IVec3::ZERO));
    }
}
