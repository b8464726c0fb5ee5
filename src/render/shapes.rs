//! The fixed meshes the renderer draws besides the clay: the glyphs' sphere, box, cylinder and
//! torus, the stage box and the background's full-screen quad.
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

/// The box `[-1, 1]³` (the glyph box: half extents 1, centred like every glyph shape).
pub(crate) fn centred_box() -> (Vec<Vertex>, Vec<u32>) {
    let (mut vertices, indices) = unit_box();
    for v in &mut vertices {
        v.position = v.position.map(|x| 2.0 * x - 1.0);
    }
    (vertices, indices)
}

/// The capped cylinder of radius 1 along Y, `y` in [-1, 1], with `segments` sides: smooth
/// normals on the side, flat ones on the caps; counter-clockwise seen from outside.
pub(crate) fn unit_cylinder(segments: u32) -> (Vec<Vertex>, Vec<u32>) {
    let vertex = |p: Vec3, n: Vec3| Vertex { position: p.to_array(), normal: n.to_array(), colour: [1.0; 4] };
    let ring = |k: u32| {
        let a = std::f32::consts::TAU * k as f32 / segments as f32;
        Vec3::new(a.cos(), 0.0, -a.sin())
    };
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    // The side: a bottom and a top vertex per segment boundary (the seam repeats, `segments + 1`).
    for k in 0..=segments {
        let r = ring(k);
        vertices.push(vertex(r - Vec3::Y, r));
        vertices.push(vertex(r + Vec3::Y, r));
    }
    for k in 0..segments {
        let (b0, t0, b1, t1) = (2 * k, 2 * k + 1, 2 * k + 2, 2 * k + 3);
        indices.extend([b0, b1, t1, b0, t1, t0]);
    }
    // The caps: a fan around a centre vertex each.
    for y in [1.0f32, -1.0] {
        let normal = Vec3::Y * y;
        let centre = vertices.len() as u32;
        vertices.push(vertex(normal, normal));
        for k in 0..segments {
            vertices.push(vertex(ring(k) + normal, normal));
        }
        for k in 0..segments {
            let (a, b) = (centre + 1 + k, centre + 1 + (k + 1) % segments);
            indices.extend(if y > 0.0 { [centre, a, b] } else { [centre, b, a] });
        }
    }
    (vertices, indices)
}

/// The spine of the torus around Y of ring radius 1: each vertex lies on the unit ring in the
/// XZ plane and its normal points from there across the tube, so that `position + t·normal`
/// is the torus of tube radius `t` (the glyph vertex shader adds it, so one mesh draws every
/// tube/ring ratio). `ring` segments around Y, `tube` around the tube; counter-clockwise seen
/// from outside.
///
/// ```text
///        Y                       ring point r(θ) = (cos θ, 0, −sin θ)
///        │   ╭──╮    ╭──╮        tube normal n(θ, φ) = cos φ · r(θ) + sin φ · Y
///     ───┼───○──┼────○──┼──►     vertex = r(θ) + t · n(θ, φ)
///        │   ╰──╯    ╰──╯
/// ```
pub(crate) fn torus_spine(ring: u32, tube: u32) -> (Vec<Vertex>, Vec<u32>) {
    let mut vertices = Vec::with_capacity((ring * tube) as usize);
    for i in 0..ring {
        let theta = std::f32::consts::TAU * i as f32 / ring as f32;
        let r = Vec3::new(theta.cos(), 0.0, -theta.sin());
        for j in 0..tube {
            let phi = std::f32::consts::TAU * j as f32 / tube as f32;
            let n = phi.cos() * r + phi.sin() * Vec3::Y;
            vertices.push(Vertex { position: r.to_array(), normal: n.to_array(), colour: [1.0; 4] });
        }
    }
    let at = |i: u32, j: u32| (i % ring) * tube + j % tube;
    let mut indices = Vec::with_capacity((6 * ring * tube) as usize);
    for i in 0..ring {
        for j in 0..tube {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            indices.extend([a, b, c, a, c, d]);
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

    /// Welds `vertices` by position (after `offset`, the torus's tube) and checks that every
    /// edge is used once each way (closed and consistently oriented); returns the signed
    /// volume, positive when the faces turn counter-clockwise seen from outside.
    fn closed_volume((v, i): &(Vec<Vertex>, Vec<u32>), offset: f32) -> f32 {
        let at = |k: u32| {
            let x = &v[k as usize];
            Vec3::from(x.position) + offset * Vec3::from(x.normal)
        };
        let key = |p: Vec3| (p * 1e4).round().as_ivec3().to_array();
        let mut edges: HashMap<([i32; 3], [i32; 3]), i32> = HashMap::new();
        let mut volume = 0.0;
        for t in i.chunks(3) {
            let p = [at(t[0]), at(t[1]), at(t[2])];
            volume += p[0].dot(p[1].cross(p[2])) / 6.0;
            for e in 0..3 {
                let (a, b) = (key(p[e]), key(p[(e + 1) % 3]));
                if a < b {
                    *edges.entry((a, b)).or_default() += 1;
                } else {
                    *edges.entry((b, a)).or_default() -= 1;
                }
            }
        }
        assert!(edges.values().all(|&c| c == 0), "every edge used once each way: closed and oriented");
        volume
    }

    #[test]
    fn the_glyph_shapes_are_closed_outward_meshes_of_their_unit_size() {
        let sphere = closed_volume(&icosphere(3), 0.0);
        assert!((sphere - 4.0 / 3.0 * std::f32::consts::PI).abs() < 0.05, "sphere volume {sphere}");
        let cube = centred_box();
        assert!((closed_volume(&cube, 0.0) - 8.0).abs() < 1e-5, "the box [-1, 1]³");
        assert!(cube.0.iter().all(|x| x.position.iter().all(|c| c.abs() == 1.0)));
        let cylinder = unit_cylinder(32);
        let expected = 2.0 * 16.0 * (std::f32::consts::TAU / 32.0).sin();
        assert!((closed_volume(&cylinder, 0.0) - expected).abs() < 1e-4, "the 32-gon prism, height 2");
        for x in &cylinder.0 {
            let [px, py, pz] = x.position;
            assert!(((px * px + pz * pz).sqrt() - 1.0).abs() < 1e-6 || py.abs() == 1.0);
            assert!(py.abs() <= 1.0);
        }
        let torus = torus_spine(48, 16);
        for tube in [0.25f32, 0.5] {
            let volume = closed_volume(&torus, tube);
            let exact = 2.0 * std::f32::consts::PI.powi(2) * tube * tube;
            assert!((volume / exact - 1.0).abs() < 0.05, "tube {tube}: volume {volume}, exact {exact}");
        }
        for x in &torus.0 {
            let p = Vec3::from(x.position);
            assert!((p.length() - 1.0).abs() < 1e-6 && p.y == 0.0, "the spine is the unit ring");
            assert!((Vec3::from(x.normal).length() - 1.0).abs() < 1e-6);
        }
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
