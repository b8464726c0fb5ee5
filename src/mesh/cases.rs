//! The marching-cubes case table, derived at first use from one rule instead of typed in.
//!
//! ```text
//!  corners: c = x + 2y + 4z           edges: e = 4·axis + j, the j-th edge of that axis,
//!                                     j counting the lower corners with that axis bit 0
//!       6 +--------+ 7                  in increasing order:
//!        /|       /|                      axis x: lower corners 0 2 4 6 → edges 0 1 2 3
//!     4 +--------+5|                      axis y: lower corners 0 1 4 5 → edges 4 5 6 7
//!       | |      | |     y                axis z: lower corners 0 1 2 3 → edges 8 9 10 11
//!       |2+------|-+ 3   |  z
//!       |/       |/      | /
//!     0 +--------+ 1     +---- x
//! ```
//!
//! A corner is *dense* when its density is at least the iso-level. On each face, walked
//! counter-clockwise as seen from outside the cube, the surface crosses every edge whose ends
//! differ; a segment runs from each empty→dense crossing to the next dense→empty crossing.
//! That leaves the dense region on the right of every segment seen from outside, and on a face
//! with two diagonal dense corners it cuts each dense corner off on its own (the ambiguous face
//! is resolved by separating dense corners). The rule reads only the face's own corners, so the
//! two cubes sharing a face draw the same segments in opposite directions: the surface is closed
//! and consistently oriented. Segments chain into loops (each crossed edge ends one segment and
//! starts another), and each loop is a polygon, counter-clockwise seen from the empty side, fanned
//! into triangles from a vertex that lays no triangle flat in a face of the cube (a loop can
//! cross an ambiguous face twice, and the cube beyond, crossing it twice too, would lay the same
//! triangle the other way round: two triangles on one welded edge).

use std::sync::OnceLock;

/// Offset of corner `c` from the cell's minimum corner.
pub const CORNER_OFFSETS: [[i32; 3]; 8] =
    [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]];

/// For edge `e`: its lower corner and its axis (0 = x, 1 = y, 2 = z).
pub const EDGES: [(u8, u8); 12] =
    [(0, 0), (2, 0), (4, 0), (6, 0), (0, 1), (1, 1), (4, 1), (5, 1), (0, 2), (1, 2), (2, 2), (3, 2)];

fn edge_between(a: usize, b: usize) -> usize {
    let lower = a.min(b);
    let axis = (a ^ b).trailing_zeros() as usize;
    debug_assert_eq!((a ^ b).count_ones(), 1);
    EDGES.iter().position(|&(c, ax)| usize::from(c) == lower && usize::from(ax) == axis).expect("cube edge")
}

fn corner(bits: [usize; 3]) -> usize {
    bits[0] | (bits[1] << 1) | (bits[2] << 2)
}

/// The six faces, each as its four corners counter-clockwise seen from outside the cube.
fn faces() -> [[usize; 4]; 6] {
    let mut out = [[0; 4]; 6];
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in 0..2 {
            let mut ring = [0usize; 4];
            for (i, (a, b)) in [(0, 0), (1, 0), (1, 1), (0, 1)].into_iter().enumerate() {
                let mut bits = [0; 3];
                bits[axis] = side;
                bits[u] = a;
                bits[v] = b;
                ring[i] = corner(bits);
            }
            // (u, v, axis) is right-handed, so this ring is counter-clockwise seen from +axis.
            if side == 0 {
                ring.reverse();
            }
            out[axis * 2 + side] = ring;
        }
    }
    out
}

/// The rule on one face: of its crossings, listed counter-clockwise seen from outside the
/// cell as (vertex, whether the ring goes from an empty sample to a dense one there), links
/// each empty→dense crossing to the next dense→empty one, calling `link(start, end)`.
pub(super) fn link_crossings<T: Copy>(crossings: &[(T, bool)], mut link: impl FnMut(T, T)) {
    for (i, &(start, is_start)) in crossings.iter().enumerate() {
        if !is_start {
            continue;
        }
        let end = (1..crossings.len())
            .map(|k| crossings[(i + k) % crossings.len()])
            .find(|&(_, s)| !s)
            .expect("crossings alternate");
        link(start, end.0);
    }
}

/// Triangles of one case, as triples of edge indices.
pub type CaseTriangles = Vec<[u8; 3]>;

fn build_case(mask: usize) -> CaseTriangles {
    let dense = |c: usize| mask & (1 << c) != 0;
    let mut next = [u8::MAX; 12];
    for ring in faces() {
        // Crossings in counter-clockwise order: (edge, starts_segment).
        let mut crossings = Vec::with_capacity(4);
        for i in 0..4 {
            let (a, b) = (ring[i], ring[(i + 1) % 4]);
            if dense(a) != dense(b) {
                crossings.push((edge_between(a, b), dense(b)));
            }
        }
        link_crossings(&crossings, |start, end| next[start] = end as u8);
    }
    let mut triangles = Vec::new();
    let mut seen = [false; 12];
    for first in 0..12 {
        if next[first] == u8::MAX || seen[first] {
            continue;
        }
        let mut ring = Vec::new();
        let mut e = first;
        while !seen[e] {
            seen[e] = true;
            ring.push(e as u8);
            e = usize::from(next[e]);
        }
        debug_assert_eq!(e, first, "segments close into loops");
        // Fanned from a vertex that lays no triangle in a face (see the module docs).
        let n = ring.len();
        let ring = &ring;
        let fan = |apex: usize| {
            (1..n - 1).map(move |i| [ring[apex], ring[(apex + i) % n], ring[(apex + i + 1) % n]])
        };
        let apex = (0..n).find(|&a| fan(a).all(|t| !in_one_face(t))).unwrap_or(0);
        triangles.extend(fan(apex));
    }
    triangles
}

/// The faces of the cube holding edge `e`, as `2·axis + side` (its lower corner's bit on the
/// two axes across it).
fn faces_of_edge(e: u8) -> [usize; 2] {
    let (lower, axis) = EDGES[usize::from(e)];
    let across = [(axis + 1) % 3, (axis + 2) % 3].map(usize::from);
    across.map(|b| 2 * b + (usize::from(lower) >> b & 1))
}

/// Whether the three edges of a triangle lie on one face of the cube (the triangle in it).
fn in_one_face(t: [u8; 3]) -> bool {
    let [a, b, c] = t.map(faces_of_edge);
    a.iter().any(|f| b.contains(f) && c.contains(f))
}

/// The case table: triangles for each of the 256 corner masks (bit `c` set = corner `c` dense).
pub fn case_table() -> &'static [CaseTriangles; 256] {
    static TABLE: OnceLock<[CaseTriangles; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(build_case))
}

/// The case table flattened for the kernel: the edges of case `m`'s triangles, three per
/// triangle, are `edges[start[m]..start[m + 1]]`, in [`case_table`]'s order.
pub struct FlatCases {
    start: [u16; 257],
    edges: Vec<u8>,
}

impl FlatCases {
    /// The triangles' edges of case `mask`, three per triangle.
    #[inline]
    pub fn edges(&self, mask: usize) -> &[u8] {
        &self.edges[usize::from(self.start[mask])..usize::from(self.start[mask + 1])]
    }
}

/// [`case_table`] as one flat array (no pointer chase per cell).
pub fn flat_cases() -> &'static FlatCases {
    static FLAT: OnceLock<FlatCases> = OnceLock::new();
    FLAT.get_or_init(|| {
        let mut flat = FlatCases { start: [0; 257], edges: Vec::new() };
        for (mask, triangles) in case_table().iter().enumerate() {
            flat.edges.extend(triangles.iter().flatten());
            flat.start[mask + 1] = u16::try_from(flat.edges.len()).expect("small table");
        }
        flat
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flat_table_lists_every_case_in_order() {
        for (mask, triangles) in case_table().iter().enumerate() {
            let edges: Vec<u8> = triangles.iter().flatten().copied().collect();
            assert_eq!(flat_cases().edges(mask), &edges[..], "mask {mask}");
        }
    }

    #[test]
    fn trivial_cases_have_no_triangles() {
        assert!(case_table()[0].is_empty());
        assert!(case_table()[255].is_empty());
    }

    #[test]
    fn single_corner_is_one_triangle_facing_away_from_it() {
        for (c, offset) in CORNER_OFFSETS.iter().enumerate() {
            let tris = &case_table()[1 << c];
            assert_eq!(tris.len(), 1, "corner {c}");
            // Points at the edge midpoints; the normal must point away from the dense corner.
            let mid = |e: u8| {
                let (lo, axis) = EDGES[usize::from(e)];
                let mut p = CORNER_OFFSETS[usize::from(lo)].map(|v| v as f32);
                p[usize::from(axis)] += 0.5;
                glam::Vec3::from(p)
            };
            let [a, b, d] = tris[0].map(mid);
            let n = (b - a).cross(d - a);
            let corner = glam::Vec3::from(offset.map(|v| v as f32));
            assert!(n.dot(a - corner) > 0.0, "corner {c}: normal {n} points into the clay");
        }
    }

    #[test]
    fn every_case_uses_exactly_the_edges_it_crosses() {
        // The kernel makes a vertex on every crossed edge before it reads the cells' cases.
        for mask in 0..256usize {
            let mut used: Vec<u8> = flat_cases().edges(mask).to_vec();
            used.sort_unstable();
            used.dedup();
            let crossed: Vec<u8> = (0..12u8)
                .filter(|&e| {
                    let (lower, axis) = EDGES[usize::from(e)];
                    let upper = usize::from(lower) | 1 << axis;
                    (mask >> lower & 1) != (mask >> upper & 1)
                })
                .collect();
            assert_eq!(used, crossed, "mask {mask}");
        }
    }

    #[test]
    fn complement_cases_have_as_many_crossings() {
        for mask in 0..256usize {
            let edges = |m: usize| {
                let mut used: Vec<u8> = case_table()[m].iter().flatten().copied().collect();
                used.sort_unstable();
                used.dedup();
                used
            };
            assert_eq!(edges(mask), edges(255 - mask), "mask {mask}");
        }
    }

    #[test]
    fn no_triangle_lies_in_a_face_of_the_cube() {
        // The cube across that face would draw the same triangle the other way round.
        for mask in 0..256usize {
            for &t in &case_table()[mask] {
                assert!(!in_one_face(t), "mask {mask}: triangle {t:?} lies in a face");
            }
        }
        // The test sees such a triangle: edges 0, 4 and 1 (x at y = 0, y at x = 0, x at y = 1)
        // all lie in the face z = 0.
        assert!(in_one_face([0, 4, 1]) && !in_one_face([0, 4, 8]));
    }

    #[test]
    fn every_case_is_a_closed_surface_inside_the_cube() {
        // Within one cube, every directed edge between two crossing points that lies inside
        // the cube (not on a face) is matched by its reverse; face edges appear once.
        for mask in 1..255usize {
            let mut directed = std::collections::HashMap::new();
            for t in &case_table()[mask] {
                for i in 0..3 {
                    *directed.entry((t[i], t[(i + 1) % 3])).or_insert(0i32) += 1;
                }
            }
            for (&(a, b), &n) in &directed {
                let back = directed.get(&(b, a)).copied().unwrap_or(0);
                assert!(n == 1 && back <= 1, "mask {mask}: edge {a}->{b} used {n} times");
            }
        }
    }
}
