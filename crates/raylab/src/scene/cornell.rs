//! The lab's Cornell box: the 30 triangles of `TestModel.h` (KTH DH2323 Lab 2; Bristol COMS30115).
//!
//! Built in Cornell units (the room is `L = 555` wide), then mapped to `[−1, 1]³` with
//! `x' = 1 − 2x/L`, `y' = 1 − 2y/L`, `z' = 2z/L − 1`, so that y points **down** as in the lab.
//! Walls face into the room and the blocks face out. There is no front wall, and the blocks have
//! no bottom faces.

use glam::Vec3;

use super::Scene;
use crate::geometry::Geometry;
use crate::light::PointLight;
use crate::material::Material;

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
    let colours = [
        ("red", RED),
        ("yellow", YELLOW),
        ("green", GREEN),
        ("cyan", CYAN),
        ("blue", BLUE),
        ("purple", PURPLE),
        ("white", WHITE),
    ];

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
    let material_of =
        |colour: Vec3| colours.iter().position(|&(_, c)| c == colour).expect("a lab colour") as u32;
    let mut geometry = Geometry::new();
    geometry.add_triangles(
        "cornell",
        faces.into_iter().map(|(corners, colour)| (corners.map(to_lab), material_of(colour))),
    );
    // The lab lights both sides of every surface.
    let materials = colours
        .iter()
        .map(|&(name, colour)| Material { two_sided: true, ..Material::diffuse(name, colour) })
        .collect();
    Scene::new("cornell", geometry, materials, PointLight::lab())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn centroid(t: &[Vec3; 3]) -> Vec3 {
        (t[0] + t[1] + t[2]) / 3.0
    }

    /// The lab's normal, `(v2 − v0) × (v1 − v0)`: the opposite of the counter-clockwise one.
    fn lab_normal(scene: &Scene, i: usize) -> Vec3 {
        -scene.geometry.normal(i)
    }

    fn colour(scene: &Scene, i: usize) -> Vec3 {
        scene.materials[scene.geometry.material_id(i) as usize].bsdf.albedo()
    }

    #[test]
    fn thirty_triangles_inside_the_unit_cube() {
        let scene = cornell_box();
        assert_eq!(scene.geometry.len(), 30);
        for i in 0..30 {
            for p in scene.geometry.triangle(i) {
                assert!(p.abs().max_element() <= 1.0, "{p}");
            }
            assert!((scene.geometry.normal(i).length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn y_points_down_floor_at_plus_one() {
        let scene = cornell_box();
        for i in 0..2 {
            assert!(scene.geometry.triangle(i).iter().all(|p| p.y == 1.0));
            // The floor faces up, which is −y.
            assert!((lab_normal(&scene, i) - Vec3::NEG_Y).length() < 1e-6);
            assert_eq!(colour(&scene, i), GREEN);
        }
    }

    #[test]
    fn walls_face_into_the_room_and_blocks_face_out() {
        let scene = cornell_box();
        for i in 0..10 {
            // Toward the room's centre, the origin.
            let t = scene.geometry.triangle(i);
            assert!(lab_normal(&scene, i).dot(-centroid(&t)) > 0.0, "wall {t:?}");
        }
        for block in [10..20, 20..30] {
            let centre = block.clone().map(|i| centroid(&scene.geometry.triangle(i))).sum::<Vec3>()
                / block.len() as f32;
            for i in block {
                let t = scene.geometry.triangle(i);
                assert!(lab_normal(&scene, i).dot(centroid(&t) - centre) > 0.0, "block {t:?}");
            }
        }
    }

    #[test]
    fn the_lab_colours_are_where_the_lab_puts_them() {
        let scene = cornell_box();
        let colours: Vec<Vec3> = (0..30).map(|i| colour(&scene, i)).collect();
        let expected =
            [GREEN, PURPLE, YELLOW, CYAN, WHITE].iter().flat_map(|c| [*c, *c]).collect::<Vec<_>>();
        assert_eq!(colours[..10], expected[..]);
        assert!(colours[10..20].iter().all(|c| *c == RED));
        assert!(colours[20..30].iter().all(|c| *c == BLUE));
    }
}
