//! Ray queries against a mesh: load an OBJ file, build a BVH over its triangles, and ask the two
//! questions of every ray tracer for a grid of rays: what does each ray hit first, and is
//! anything between a point and a light?
//!
//! ```sh
//! cargo run --release --example ray_queries            # the Stanford bunny in the repository
//! cargo run --release --example ray_queries -- my.obj  # any OBJ, PLY or glTF file
//! ```

use std::path::PathBuf;
use std::time::Instant;

use glam::Vec3;
use raylab::{Accelerator, Bvh, Ray};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let file = std::env::args_os().nth(1).map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/bunny_lowres.obj")
    });
    // Every triangle in world space (a glTF file's instances copied into place).
    let mesh = raylab::scene::load_mesh(&file)?.flattened();
    let triangles: Vec<[Vec3; 3]> = mesh.triangle_vertices().collect();
    let start = Instant::now();
    let bvh = Bvh::new(&triangles);
    println!(
        "{}: {} triangles, BVH built in {:.1} ms",
        file.display(),
        triangles.len(),
        start.elapsed().as_secs_f64() * 1e3
    );

    // A 256×256 grid of parallel rays from in front of the mesh (−z) toward it.
    let (lo, hi) = mesh.bounds().ok_or("the mesh has no triangles")?;
    let size = hi - lo;
    let n = 256;
    let rays: Vec<Ray> = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
            let origin = Vec3::new(
                lo.x + size.x * x / n as f32,
                lo.y + size.y * y / n as f32,
                lo.z - size.z,
            );
            Ray::new(origin, Vec3::Z)
        })
        .collect();

    // Closest hits, for the whole batch at once (coherent rays are traced as packets).
    let start = Instant::now();
    let mut hits = vec![None; rays.len()];
    bvh.closest_hits(&rays, &mut hits);
    let elapsed = start.elapsed().as_secs_f64();
    let hit_count = hits.iter().flatten().count();
    println!(
        "closest hits: {hit_count} of {} rays hit, {:.2} M rays/s",
        rays.len(),
        rays.len() as f64 / elapsed / 1e6
    );
    let nearest = hits.iter().flatten().min_by(|a, b| a.t.total_cmp(&b.t)).ok_or("no ray hit")?;
    println!("nearest hit: triangle {} at t = {:.4}", nearest.triangle, nearest.t);

    // Shadow rays: from each hit point toward a light above the mesh, as segments that stop
    // just short of the light. A point is lit where nothing is in the way.
    let light = (lo + hi) / 2.0 + Vec3::new(0.0, -2.0 * size.y, -size.z);
    let mut lit = 0;
    for (ray, hit) in rays.iter().zip(&hits) {
        let Some(hit) = hit else { continue };
        let point = ray.at(hit.t);
        // Start a little off the surface, toward the light, so that the ray does not find the
        // triangle it starts on.
        let from = point + (light - point).normalize() * 1e-4 * size.length();
        if !bvh.occluded(&Ray::segment(from, light - from, 1.0)) {
            lit += 1;
        }
    }
    println!("shadow rays: {lit} of {hit_count} hit points see the light");
    // Every answer is exactly what testing every triangle gives (brute force), ray by ray.
    let brute = raylab::BruteForce::new(&triangles);
    let checked = rays.iter().step_by(97).all(|ray| brute.closest_hit(ray) == bvh.closest_hit(ray));
    println!(
        "a sample of answers checked against brute force: {}",
        if checked { "equal" } else { "DIFFERENT" }
    );
    if !checked {
        return Err("the BVH and brute force disagree".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs_with_no_arguments() {
        super::main().unwrap();
    }
}
