//! A TOML scene file rendered with a progress report: the lab's Cornell box lit by an area
//! light (`scenes/cornell-lab.toml`), path-traced to a PNG, the percentage done printed as the
//! passes finish.
//!
//! ```sh
//! cargo run --release --example toml_scene                          # writes cornell-lab.png in the temporary folder
//! cargo run --release --example toml_scene -- scene.toml out.png    # any scene file, any output
//! ```

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

use raylab::Scene;
use raylab::scene::LoadOptions;
use raylab::session::{CameraOptions, Event, RenderJob, RenderOptions, ResolvedSettings};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene_file = args.next().unwrap_or_else(|| {
        concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/cornell-lab.toml").to_string()
    });
    let output = args
        .next()
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("cornell-lab.png"));

    // Any scene: built in, a scene file or a model file. Its [render] settings apply unless
    // the options say otherwise; here, fewer samples than the file asks for.
    let opened = Scene::open(&scene_file, &LoadOptions::default())?;
    let scene = &opened.scene;
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    let options = RenderOptions { spp: Some(16), ..RenderOptions::default() };
    let settings = ResolvedSettings::resolve(scene, &options);
    let mut job = RenderJob::new(scene, settings, 0)?;
    let cameras = CameraOptions { size: Some((200, 200)), ..CameraOptions::default() };
    let camera = cameras.camera(scene.camera, scene, opened.is_model, job.accel()?)?;

    // Progress: the job says how many rows all passes have, then each band of rows as it
    // finishes (from the render threads: the count is atomic).
    let total = AtomicU64::new(0);
    let done = AtomicU64::new(0);
    let last_shown = AtomicU64::new(0);
    let progress = |event: Event| match event {
        Event::Started { rows, .. } => total.store(rows.max(1), Ordering::Relaxed),
        Event::Rows(rows) => {
            let done = done.fetch_add(rows as u64, Ordering::Relaxed) + rows as u64;
            let percent = done * 100 / total.load(Ordering::Relaxed).max(1);
            // Every 10 %, once.
            if percent / 10 > last_shown.fetch_max(percent / 10, Ordering::Relaxed) {
                println!("{percent:>3} %");
            }
        }
        _ => {}
    };
    let outcome = job.render_frame(&camera, &output, None, &progress)?;
    println!(
        "{}: {} ({} triangles), {} integrator, {} samples per pixel, {:.2} s",
        output.display(),
        scene.name,
        scene.geometry.len(),
        settings.integrator,
        outcome.samples,
        outcome.elapsed.as_secs_f64()
    );
    if done.load(Ordering::Relaxed) != total.load(Ordering::Relaxed) {
        return Err("the progress did not add up to the rows rendered".into());
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
