//! The lab's Cornell box: the 30 triangles of `TestModel.h` (KTH DH2323 Lab 2; Bristol COMS30115).
//!
//! Built in Cornell units (the room is `L = 555` wide), then mapped to `[−1, 1]³` with
//! `x' = 1 − 2x/L`, `y' = 1 − 2y/L`, `z' = 2z/L − 1`, so that y points **down** as in the lab.
//! Walls face into the room and the blocks face out. There is no front wall, and the blocks have
//! no bottom faces.

use glam::Vec3;

use super::Scene;
use crate::light::PointLight;
use crate::triangle::Triangle;

/// The room's side `L` in Cornell units.
pub const CORNELL_BOX_SIZE: f32 = 555.0;

const RED: Vec3 = Vec3::new(0.75, 0.15, 0.15);
const YELLOW: Vec3 = Vec3::new(0.75, 0.75, 0.15);
const GREEN: Vec3 = Vec3::new(0.15, 0.75, 0.15);
const CYAN: Vec3 = Vec3::new(0.15, 0.75, 0.75);
const BLUE: Vec3 = Vec3::new(0.15, 0.15, 0.75);
const PURPLE: Vec3 = Vec3::new(0.75, 0.15, 0.75);
const WHITE: Vec3 = Vec3::new(0.75, 0.75, 0.75);

/// The lab's Cornell box with the lab's light, in the lab's y-down `[−1, 1]³` frame.
pub fn cornell_box() -> Scene {
    const L: f32 = CORNELL_BOX_SIZE;
    let v = Vec3::new;
    let mut faces: Vec<([Vec3; 3], Vec3)> = Vec::with_capacity(30);

    // The room.
    let (a, b, c, d) = (v(L, 0.0, 0.0), v(0.0, 0.0, 0.0), v(L, 0.0, L), v(0.0, 0.0, L));
    let (e, f, g, h) = (v(L, L, 0.0), v(0.0, L, 0.0), v(L, L, L), v(0.0, L, L));
    faces.extend([
        ([c, b, a], GREEN), // floor
        ([c, d, b], GREEN),
        ([a, e, c], PURPLE), // left wall
        ([c, e, g], PURPLE),
        ([f, b, d], YELLOW), // right wall
        ([h, f, d], YELLOW),
        ([e, f, g], CYAN), // ceiling
        ([f, h, g], CYAN),
        ([g, d, c], WHITE), // back wall
        ([g, h, d], WHITE),
    ]);

    // The short red block and the tall blue one.
    let short =
        [v(290.0, 0.0, 114.0), v(130.0, 0.0, 65.0), v(240.0, 0.0, 272.0), v(82.0, 0.0, 225.0)];
    let tall =
        [v(423.0, 0.0, 247.0), v(265.0, 0.0, 296.0), v(472.0, 0.0, 406.0), v(314.0, 0.0, 456.0)];
    for (base, height, colour) in [(short, 165.0, RED), (tall, 330.0, BLUE)] {
        let [a, b, c, d] = base;
        let lift = v(0.0, height, 0.0);
        let (e, f, g, h) = (a + lift, b + lift, c + lift, d + lift);
        faces.extend(
            [
                [e, b, a], // front
                [e, f, b],
                [f, d, b], // right
                [f, h, d],
                [h, c, d], // back
                [h, g, c],
                [g, e, c], // left
                [e, a, c],
                [g, f, e], // top
                [g, h, f],
            ]
            .map(|corners| (corners, colour)),
        );
    }

    let to_lab = |p: Vec3| v(1.0 - 2.0 * p.x / L, 1.0 - 2.0 * p.y / L, 2.0 * p.z / L - 1.0);
    let triangles = faces
        .into_iter()
        .map(|([p0, p1, p2], colour)| Triangle::new(to_lab(p0), to_lab(p1), to_lab(p2), colour))
        .collect();
    Scene { name: "cornell".into(), triangles, light: PointLight::lab() }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn centroid(t: &Triangle) -> Vec3 {
        (t.v0 + t.v1 + t.v2) / 3.0
    }

    #[test]
    fn thirty_triangles_inside_the_unit_cube() {
        let scene = cornell_box();
        assert_eq!(scene.triangles.len(), 30);
        for t in &scene.triangles {
            for p in [t.v0, t.v1, t.v2] {
                assert!(p.abs().max_element() <= 1.0, "{p}");
            }
            assert!((t.normal.length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn y_points_down_floor_at_plus_one() {
        let scene = cornell_box();
        let floor = &scene.triangles[0..2];
        assert!(floor.iter().all(|t| [t.v0, t.v1, t.v2].iter().all(|p| p.y == 1.0)));
        // The floor faces up, which is −y.
        assert!(floor.iter().all(|t| (t.normal - Vec3::NEG_Y).length() < 1e-6));
        assert!(floor.iter().all(|t| t.albedo == GREEN));
    }

    #[test]
    fn walls_face_into_the_room_and_blocks_face_out() {
        let scene = cornell_box();
        for t in &scene.triangles[..10] {
            // Toward the room's centre, the origin.
            assert!(t.normal.dot(-centroid(t)) > 0.0, "wall {t:?}");
        }
        for block in [&scene.triangles[10..20], &scene.triangles[20..30]] {
            let centre = block.iter().map(centroid).sum::<Vec3>() / block.len() as f32;
            for t in block {
                assert!(t.normal.dot(centroid(t) - centre) > 0.0, "block {t:?}");
            }
        }
    }

    #[test]
    fn the_lab_colours_are_where_the_lab_puts_them() {
        let scene = cornell_box();
        let colours: Vec<Vec3> = scene.triangles.iter().map(|t| t.albedo).collect();
        let expected =
            [GREEN, PURPLE, YELLOW, CYAN, WHITE].iter().flat_map(|c| [*c, *c]).collect::<Vec<_>>();
        assert_eq!(colours[..10], expected[..]);
        assert!(colours[10..20].iter().all(|c| *c == RED));
        assert!(colours[20..30].iter().all(|c| *c == BLUE));
    }
}
