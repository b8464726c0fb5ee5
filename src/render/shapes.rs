//! The fixed meshes the renderer draws besides the clay: the tool glyph's sphere, the stage
//! box and the background's full-screen quad.
//!
//! Each is drawn whole from buffers of its own (see `ShapeMesh` in the renderer).

use std::collections::HashMap;

use crate::math::Vec3;
use crate::mesh::Vertex;

/// An icosahedron subdivided `levels` times, projected onto the unit sphere; counter-clockwise
/// seen from outside, normals equal to positions.
pub(crate) fn icosphere(levels: u32) -> (Vec<Vertex>, Vec<u32>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut points: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::from(*p).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, points: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                points.push((points[a as usize] + points[b as usize]).normalize());
                points.len() as u32 - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = midpoint(a, b, &mut points);
                let bc = midpoint(b, c, &mut points);
                let ca = midpoint(c, a, &mut points);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    let vertices = points
        .iter()
        .map(|p| Vertex { position: p.to_array(), normal: p.to_array(), colour: [1.0; 4] })
        .collect();
    (vertices, faces.into_iter().flatten().collect())
}

/// The unit box `[0, 1]³`: 24 vertices (4 per face, normals outward), 36 indices,
/// counter-clockwise seen from outside.
pub(crate) fn unit_box() -> (Vec<Vertex>, Vec<u32>) {
    let mut vertices = Vec::with_capacity(24);
    let mut indices = Vec::with_capacity(36);
    for axis in 0..3 {
        // Tangent axes in cyclic order: e_b × e_c = e_axis.
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        for positive in [true, false] {
            let mut normal = Vec3::ZERO;
            normal[axis] = if positive { 1.0 } else { -1.0 };
            // Counter-clockwise seen from the side the normal points to.
            let corners = if positive {
                [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            } else {
                [(0.0, 0.0), (0.0, 1.0), (1.0, 1.0), (1.0, 0.0)]
            };
            let base = vertices.len() as u32;
            for (u, v) in corners {
                let mut p = Vec3::ZERO;
                p[axis] = if positive { 1.0 } else { 0.0 };
                p[b] = u;
                p[c] = v;
                vertices.push(Vertex { position: p.to_array(), normal: normal.to_array(), colour: [1.0; 4] });
            }
            indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    (vertices, indices)
}

/// A quad exactly covering clip space, corners at (±1, ±1) in normalised device coordinates.
pub(crate) fn full_screen_quad() -> (Vec<Vertex>, Vec<u32>) {
    let vertices = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]].map(|[x, y]| Vertex {
        position: [x, y, 1.0],
        normal: [0.0, 0.0, 1.0],
        colour: [1.0; 4],
    });
    (vertices.to_vec(), vec![0, 1, 2, 0, 2, 3])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_icosphere_is_closed_outward_and_on_the_unit_sphere() {
        let (v, i) = icosphere(2);
        assert_eq!(i.len() / 3, 20 * 16);
        assert_eq!(v.len(), 10 * 16 + 2, "Euler: V = F/2 + 2");
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in i.chunks(3) {
            let p: Vec<Vec3> = t.iter().map(|&k| Vec3::from(v[k as usize].position)).collect();
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            assert!(n.dot(p[0] + p[1] + p[2]) > 0.0, "counter-clockwise seen from outside");
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { -1 };
            }
        }
        assert!(edges.values().all(|&c| c == 0), "every edge used once each way: closed and oriented");
        assert!(v.iter().all(|x| (Vec3::from(x.position).length() - 1.0).abs() < 1e-6));
    }

    #[test]
    fn the_box_is_the_closed_unit_cube_with_outward_counter_clockwise_faces() {
        let (v, i) = unit_box();
        assert_eq!((v.len(), i.len()), (24, 36));
        let centre = Vec3::splat(0.5);
        let mut area = 0.0;
        for t in i.chunks(3) {
            let p: Vec<Vec3> = t.iter().map(|&k| Vec3::from(v[k as usize].position)).collect();
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            area += 0.5 * n.length();
            let normal = Vec3::from(v[t[0] as usize].normal);
            assert!((n.normalize() - normal).length() < 1e-5, "winding matches the normal {normal}");
            assert!(p.iter().all(|q| ((*q - centre).dot(normal) - 0.5).abs() < 1e-6), "on the face {normal}");
        }
        assert!((area - 6.0).abs() < 1e-4, "six unit faces, no overlap: area {area}");
    }

    #[test]
    fn the_full_screen_quad_covers_clip_space_exactly() {
        let (v, i) = full_screen_quad();
        let xy: Vec<[f32; 2]> = v.iter().map(|x| [x.position[0], x.position[1]]).collect();
        assert!(xy.iter().all(|p| p[0].abs() == 1.0 && p[1].abs() == 1.0));
        let area: f32 = i
            .chunks(3)
            .map(|t| {
                let [a, b, c] = [xy[t[0] as usize], xy[t[1] as usize], xy[t[2] as usize]];
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs()
            })
            .sum();
        assert_eq!(area, 4.0);
    }
}
