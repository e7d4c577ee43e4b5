//! The shapes scene files build in: Mitsuba's `rectangle` and `cube`, and a sphere.

use glam::Vec3;

use crate::mesh::Mesh;

/// Mitsuba's `rectangle`: `[−1, 1]²` in the plane z = 0, facing +z.
pub(super) fn rectangle() -> Mesh {
    Mesh {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        ..Mesh::default()
    }
}

/// Mitsuba's `cube`: `[−1, 1]³`, facing out.
pub(super) fn cube() -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array(std::array::from_fn(|i| if i == axis { sign } else { 0.0 }));
            let u =
                Vec3::from_array(std::array::from_fn(
                    |i| if i == (axis + 1) % 3 { 1.0 } else { 0.0 },
                ));
            let v = n.cross(u);
            let base = positions.len() as u32;
            positions.extend([n - u - v, n + u - v, n + u + v, n - u + v]);
            triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
        }
    }
    Mesh { positions, triangles, ..Mesh::default() }
}

/// A UV sphere facing out, with per-vertex normals (smooth shading).
pub(super) fn sphere(centre: Vec3, radius: f32) -> Mesh {
    let (rings, segments) = (48u32, 96u32);
    let mut positions = Vec::new();
    for ring in 0..=rings {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        for segment in 0..segments {
            let phi = 2.0 * std::f32::consts::PI * segment as f32 / segments as f32;
            positions.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            ));
        }
    }
    let index = |ring: u32, segment: u32| ring * segments + segment % segments;
    let mut triangles = Vec::new();
    for ring in 0..rings {
        for segment in 0..segments {
            let (a, b) = (index(ring, segment), index(ring, segment + 1));
            let (c, d) = (index(ring + 1, segment), index(ring + 1, segment + 1));
            if ring > 0 {
                triangles.push([a, c, b]);
            }
            if ring + 1 < rings {
                triangles.push([b, c, d]);
            }
        }
    }
    let normals = crate::mesh::CornerAttribute::per_vertex(positions.clone(), &triangles);
    Mesh {
        positions: positions.iter().map(|&p| centre + radius * p).collect(),
        triangles,
        normals: Some(normals),
        ..Mesh::default()
    }
}
