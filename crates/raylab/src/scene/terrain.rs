//! `terrain`: a fractal landscape, the built-in scene of procedural geometry.
//!
//! A square of `n × n` vertices, 16 units across, lifted by fBm noise (eight octaves of Perlin
//! noise, [`Perlin::fbm`]): `h(x, z) = 2.5 · fbm(x/4, z/4) + 0.4`, so hills rise up to about four
//! units. Where `h` would fall below 0 a lake fills it flat. Every vertex has the normal of the
//! heightfield's slope (central differences), so the hills shade smoothly; each grid cell is two
//! triangles, `2 (n − 1)²` in all. The land is a diffuse blend of grass and rock in `clouds`
//! noise, the lake a smooth blue `pbr` surface.
//!
//! `terrain` has 257 vertices a side (131,072 triangles); `terrain:N` has `N` (from 2 to 4097):
//! `terrain:708` has 999,698 triangles. The camera looks at the middle from above the near
//! edge, and the model's default light shines from above.

use glam::Vec3;
use rayon::prelude::*;

use super::{CameraSettings, FovAxis, Scene, SceneError};
use crate::material::MaterialTextures;
use crate::mesh::{CornerAttribute, Mesh, MeshMaterial, PbrParameters};
use crate::texture::{NoiseTexture, Pattern, Perlin, Texture};

/// Vertices a side of `terrain`.
pub const DEFAULT_SIDE: u32 = 257;

/// The most vertices a side `terrain:N` takes (33.5 million triangles).
pub const MAX_SIDE: u32 = 4097;

/// Half the width of the square.
const HALF_WIDTH: f32 = 8.0;

/// The built-in `terrain` or `terrain:N`, or `None` for another name.
pub(crate) fn parse_terrain(name: &str) -> Option<Result<Scene, SceneError>> {
    let rest = name.strip_prefix("terrain")?;
    let side = match rest.strip_prefix(':') {
        None if rest.is_empty() => DEFAULT_SIDE,
        None => return None,
        Some(n) => match n.parse::<u32>() {
            Ok(n) if (2..=MAX_SIDE).contains(&n) => n,
            _ => {
                return Some(Err(SceneError::InvalidBuiltIn {
                    name: name.to_string(),
                    problem: format!("terrain:N takes N vertices a side, from 2 to {MAX_SIDE}"),
                }));
            }
        },
    };
    Some(Ok(terrain(side, 0)))
}

/// The landscape with `side` vertices a side, its noise from `seed` (see the module
/// documentation).
///
/// # Panics
/// If `side` is below 2.
pub fn terrain(side: u32, seed: u64) -> Scene {
    assert!(side >= 2, "a terrain needs two vertices a side");
    let noise = Perlin::new(seed);
    let n = side as usize;
    let step = 2.0 * HALF_WIDTH / (side - 1) as f32;
    let coordinate = |i: usize| -HALF_WIDTH + i as f32 * step;
    let height = |x: f32, z: f32| 2.5 * noise.fbm(Vec3::new(x, 0.0, z) * 0.25, 8) + 0.4;
    // Heights on the grid, one row per task.
    let heights: Vec<f32> =
        (0..n * n).into_par_iter().map(|k| height(coordinate(k % n), coordinate(k / n))).collect();
    let at = |i: usize, j: usize| heights[j * n + i].max(0.0);
    let mut positions = Vec::with_capacity(n * n);
    let mut normals = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            positions.push(Vec3::new(coordinate(i), at(i, j), coordinate(j)));
            // The slope by central differences (one-sided at the edges); flat on the lake.
            let (i0, i1) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let (j0, j1) = (j.saturating_sub(1), (j + 1).min(n - 1));
            let dx = (at(i1, j) - at(i0, j)) / ((i1 - i0) as f32 * step);
            let dz = (at(i, j1) - at(i, j0)) / ((j1 - j0) as f32 * step);
            normals.push(Vec3::new(-dx, 1.0, -dz).normalize());
        }
    }
    let index = |i: usize, j: usize| (j * n + i) as u32;
    let cells = (n - 1) * (n - 1);
    let mut triangles = Vec::with_capacity(2 * cells);
    let mut material_ids = Vec::with_capacity(2 * cells);
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            // Counter-clockwise seen from above (+y).
            for t in [
                [index(i, j), index(i, j + 1), index(i + 1, j)],
                [index(i + 1, j), index(i, j + 1), index(i + 1, j + 1)],
            ] {
                let lake = t.iter().all(|&v| positions[v as usize].y == 0.0);
                triangles.push(t);
                material_ids.push(Some(u32::from(lake)));
            }
        }
    }
    let land = MeshMaterial {
        name: "land".into(),
        diffuse: Vec3::ONE,
        emission: Vec3::ZERO,
        textures: MaterialTextures {
            base_color: Some(Texture::Noise(NoiseTexture {
                pattern: Pattern::Clouds,
                noise: Perlin::new(seed.wrapping_add(1)),
                scale: 0.6,
                octaves: 6,
                turbulence: 1.0,
                colors: [Vec3::new(0.16, 0.3, 0.09), Vec3::new(0.45, 0.4, 0.33)],
            })),
            ..MaterialTextures::default()
        },
        pbr: None,
    };
    let lake = MeshMaterial {
        name: "lake".into(),
        diffuse: Vec3::new(0.05, 0.15, 0.3),
        emission: Vec3::ZERO,
        textures: MaterialTextures::default(),
        pbr: Some(PbrParameters { metallic: 0.0, roughness: 0.15, transmission: 0.0, ior: 1.33 }),
    };
    let normals = CornerAttribute::per_vertex(normals, &triangles);
    let mesh = Mesh {
        name: "terrain".into(),
        positions,
        triangles,
        normals: Some(normals),
        material_ids,
        materials: vec![land, lake],
        ..Mesh::default()
    };
    let mut scene = Scene::from_mesh(&mesh);
    // From above the near edge (the model's +z, the lab's −z), looking down at the middle.
    let position = super::model_to_lab(Vec3::new(0.0, 7.0, 1.6 * HALF_WIDTH));
    let pitch = -(position.y.abs() / position.z.abs()).atan();
    scene.camera = Some(CameraSettings {
        position,
        yaw: 0.0,
        pitch,
        roll: 0.0,
        fov_deg: 60.0,
        fov_axis: FovAxis::X,
        aperture_radius: 0.0,
        focus_distance: 1.0,
    });
    scene.name = "terrain".into();
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_has_its_triangles_and_its_heights_follow_the_noise() {
        let scene = terrain(33, 0);
        assert_eq!(scene.geometry.len(), 2 * 32 * 32);
        let noise = Perlin::new(0);
        // Every vertex (in the lab's frame, y down) is at the noise's height or on the lake.
        for &p in scene.geometry.positions() {
            let (x, z) = (p.x, -p.z);
            let h = (2.5 * noise.fbm(Vec3::new(x, 0.0, z) * 0.25, 8) + 0.4).max(0.0);
            assert!((-p.y - h).abs() < 1e-5, "{p}: height {h}");
        }
        let (lo, hi) = scene.bounds().unwrap();
        assert!((hi.x - lo.x - 16.0).abs() < 1e-5 && (hi.z - lo.z - 16.0).abs() < 1e-5);
        assert!(hi.y - lo.y > 1.0, "hills: {lo} to {hi}");
        // Front faces up: the geometric normals point to the lab's −y.
        assert!((0..scene.geometry.len()).all(|i| scene.geometry.normal(i).y < 0.0));
    }

    #[test]
    fn names_pick_the_size() {
        let scene = parse_terrain("terrain:10").unwrap().unwrap();
        assert_eq!(scene.geometry.len(), 2 * 81);
        assert_eq!(scene.name, "terrain");
        for bad in ["terrain:1", "terrain:5000", "terrain:x", "terrain:"] {
            let error = parse_terrain(bad).unwrap().unwrap_err().to_string();
            assert!(error.contains("from 2 to 4097"), "{bad}: {error}");
        }
        assert!(parse_terrain("terrains").is_none() && parse_terrain("cornell").is_none());
    }
}
