//! A scene built in code and rendered to an OpenEXR file: a rough gold sphere on a grey floor
//! under a white sky, path-traced, with an albedo layer beside the picture.
//!
//! ```sh
//! cargo run --release --example scene_in_code               # writes scene_in_code.exr in the temporary folder
//! cargo run --release --example scene_in_code -- out.exr    # or where you say
//! ```

use std::path::PathBuf;

use glam::Vec3;
use raylab::material::{Bsdf, Conductor, Ggx, METALS, RoughConductor};
use raylab::scene::{CameraSettings, FovAxis};
use raylab::session::{CameraOptions, RenderJob, RenderOptions, ResolvedSettings};
use raylab::settings::{AovKind, IntegratorKind};
use raylab::{Geometry, Light, Material, Scene};

/// Triangles of a sphere of `radius` about `centre`, with counter-clockwise (outward) fronts.
fn sphere(centre: Vec3, radius: f32, material: u32) -> Vec<([Vec3; 3], u32)> {
    let (rings, segments) = (24, 48);
    let point = |ring: u32, segment: u32| {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = std::f32::consts::TAU * segment as f32 / segments as f32;
        centre + radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    let mut triangles = Vec::new();
    for ring in 0..rings {
        for segment in 0..segments {
            let [a, b, c, d] = [
                point(ring, segment),
                point(ring + 1, segment),
                point(ring + 1, segment + 1),
                point(ring, segment + 1),
            ];
            triangles.push(([a, d, b], material));
            triangles.push(([d, c, b], material));
        }
    }
    triangles
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let output = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("scene_in_code.exr"));

    // Geometry in the lab's frame: x right, y down, z forward. The floor is the plane y = 1.
    let mut geometry = Geometry::new();
    geometry.add_triangles("sphere", sphere(Vec3::new(0.0, 0.4, 3.0), 0.6, 0));
    let floor = |x: f32, z: f32| Vec3::new(x, 1.0, z);
    let (a, b, c, d) = (floor(-4.0, -1.0), floor(4.0, -1.0), floor(4.0, 8.0), floor(-4.0, 8.0));
    // Fronts face up (−y), toward the camera's side of the floor.
    geometry.add_triangles("floor", [([a, b, c], 1), ([a, c, d], 1)]);
    // Gold's complex index of refraction per channel, from the table of measured metals.
    let (_, eta, k) = METALS.iter().find(|(name, ..)| *name == "Au").ok_or("gold is listed")?;
    let conductor = Conductor {
        eta: Vec3::from_array(*eta),
        k: Vec3::from_array(*k),
        specular_reflectance: Vec3::ONE,
    };
    // Brushed a little (GGX roughness α = 0.2), so that the sphere's facets blur together.
    let rough = RoughConductor { conductor, distribution: Ggx::new(0.2, 0.2) };
    let gold =
        Material { bsdf: Bsdf::RoughConductor(rough), ..Material::diffuse("gold", Vec3::ONE) };
    let scene = Scene {
        name: "gold sphere".into(),
        geometry,
        materials: vec![gold, Material::diffuse("floor", Vec3::splat(0.5))],
        lights: vec![Light::Environment { radiance: Vec3::ONE }],
        // Above the floor, looking down at the sphere by atan(0.8 / 3) ≈ 15°.
        camera: Some(CameraSettings {
            position: Vec3::new(0.0, -0.3, 0.0),
            yaw: 0.0,
            pitch: -(0.8f32 / 3.0).atan(),
            roll: 0.0,
            fov_deg: 40.0,
            fov_axis: FovAxis::X,
            aperture_radius: 0.0,
            focus_distance: 1.0,
        }),
        ..Scene::default()
    };
    scene.validate()?;

    // Path tracing, 32 samples per pixel, on every core; an albedo layer from the same samples.
    let options = RenderOptions {
        integrator: Some(IntegratorKind::Path),
        spp: Some(32),
        ..RenderOptions::default()
    };
    let settings = ResolvedSettings::resolve(&scene, &options);
    let mut job = RenderJob::new(&scene, settings, 0)?;
    job.aovs = vec![AovKind::Albedo];
    let cameras = CameraOptions { size: Some((160, 120)), ..CameraOptions::default() };
    let camera = cameras.camera(scene.camera, &scene, false, job.accel()?)?;
    let outcome = job.render_frame(&camera, &output, None, &|_| {})?;
    println!(
        "{}: {}×{}, {} samples per pixel in {:.2} s, channels R, G, B and albedo.R, .G, .B",
        output.display(),
        camera.width,
        camera.height,
        outcome.samples,
        outcome.elapsed.as_secs_f64()
    );
    // The sky lights everything: no pixel is black, and gold reflects more red than blue.
    let film = outcome.film.ok_or("the picture")?;
    let centre = film.pixel(camera.width / 2, camera.height / 2);
    println!("the sphere's centre: ({:.3}, {:.3}, {:.3})", centre.x, centre.y, centre.z);
    if !(centre.x > centre.z && film.pixels().iter().all(|p| p.max_element() > 0.0)) {
        return Err("the gold sphere does not look gold".into());
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
